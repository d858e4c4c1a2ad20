//! At which temperature the strengths were measured and what the lifetime is for.
//!
//! A strength measured at 20 °C is not a strength at 800 °C: ceramic particles soften above
//! ≈ 900 °C as an amorphous phase rises (the deliverable §2), and their JH-2 constants change
//! between room temperature and 800 °C (§4). Every crush and strength row therefore carries a
//! test temperature ([`crate::intake::observed::test_temperatures`]), and every study that
//! turns strengths into a lifetime or a comparison says, on its first page and in
//! `summary.md`:
//!
//! * at which temperature each material was tested;
//! * what temperature the lifetime is for: the tests' own (the chain carries no temperature
//!   law), or an operating temperature other than the tests' (`[operating]` of the main study,
//!   or a named temperature effect with the study's `predict.temperature_c`);
//! * a **warning** when the two materials of a comparison were tested at different temperatures
//!   (the comparison then sets a strength at one temperature against one at another), and when
//!   one material's tests span several temperatures that its strength model pools without a
//!   temperature term.
//!
//! The sentences are built from the temperatures themselves ([`paragraph`], [`warnings`]).

use crate::intake::observed::describe_temperatures;

/// One material's tests: its label and each specimen's test temperature (°C).
#[derive(Debug, Clone, Copy)]
pub struct Tested<'a> {
    /// The material's label.
    pub label: &'a str,
    /// Each specimen's test temperature (°C).
    pub temperatures_c: &'a [f64],
    /// Whether its strength model carries a temperature term (several temperatures are then
    /// modelled, not pooled).
    pub temperature_term: bool,
}

impl Tested<'_> {
    /// The distinct test temperatures, ascending.
    pub fn distinct(&self) -> Vec<f64> {
        let mut t: Vec<f64> = self.temperatures_c.to_vec();
        t.sort_by(f64::total_cmp);
        t.dedup();
        t
    }
}

/// What the lifetime is for.
#[derive(Debug, Clone, PartialEq)]
pub enum LifetimeAt {
    /// The tests' own temperature (no law carries the strength elsewhere).
    Tests,
    /// Operating temperatures, per material (words such as `800 °C` or `700–800 °C`), reached
    /// by the named means (`the temperature laws of temperature.toml`).
    Operating {
        /// The temperature each material's lifetime is for, in words, in the materials' order.
        per_material: Vec<String>,
        /// What carries the strength there, in words.
        by: String,
    },
}

/// The warning for a recorded factor whose levels coincide with the test temperatures (every
/// particle of a level tested at one temperature, each level at another): the data cannot tell
/// the factor's effect from the temperature's. `levels`: the factor's level per particle.
pub fn confounded(label: &str, factor: &str, levels: &[String], temperatures_c: &[f64]) -> Option<String> {
    let mut pairs: Vec<(&str, f64)> = Vec::new();
    for (l, t) in levels.iter().zip(temperatures_c) {
        match pairs.iter().find(|(pl, _)| *pl == l.as_str()) {
            Some((_, pt)) if *pt != *t => return None,
            Some(_) => {}
            None => pairs.push((l, *t)),
        }
    }
    let mut temps: Vec<f64> = pairs.iter().map(|p| p.1).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    (temps.len() > 1).then(|| {
        let map = pairs.iter().map(|(l, t)| format!("{l} at {} °C", crate::intake::columns::shown(*t))).collect::<Vec<_>>().join(", ");
        format!("{label}: `{factor}` coincides with the test temperature ({map}): the data cannot tell its effect from the temperature's, and whichever the naming loop names stands for both")
    })
}

/// What the lifetimes hold at where no temperature law carries the strength: for each material
/// whose strength model carries a temperature term, the temperature its study predicts at
/// (`predicted`, in words; None: none named), else its tests'.
pub fn named_or_tests(materials: &[Tested], predicted: &[Option<String>]) -> LifetimeAt {
    let at: Vec<Option<&String>> = materials.iter().zip(predicted).map(|(m, p)| p.as_ref().filter(|_| m.temperature_term)).collect();
    if at.iter().all(Option::is_none) {
        return LifetimeAt::Tests;
    }
    LifetimeAt::Operating {
        per_material: at.iter().map(|p| p.cloned().unwrap_or_else(|| "its tests' temperature".into())).collect(),
        by: "the strength model's temperature-softening term and the study's predict.temperature_c".into(),
    }
}

/// The warning for a study's `predict.temperature_c` that changes nothing: the material's
/// strength model carries no temperature term, so every particle is alike at any temperature.
pub fn unused_prediction(m: &Tested, predicted: Option<&str>) -> Option<String> {
    predicted.filter(|_| !m.temperature_term).map(|p| format!("{}: predict.temperature_c ({p}) changes nothing: its strength model carries no temperature term, so its lifetime is at its tests' temperature ({})", m.label, describe_temperatures(m.temperatures_c)))
}

/// The first-page paragraph: where each material was tested and what the lifetime is for.
pub fn paragraph(materials: &[Tested], at: &LifetimeAt) -> String {
    let same = materials.windows(2).all(|w| w[0].distinct() == w[1].distinct());
    let tests: Vec<String> = materials.iter().map(|m| format!("{} was tested at {}", m.label, describe_temperatures(m.temperatures_c))).collect();
    let tested = match materials.len() {
        2 if same => format!("both materials were tested at {}", describe_temperatures(materials[0].temperatures_c)),
        n if n > 2 && same => format!("every material was tested at {}", describe_temperatures(materials[0].temperatures_c)),
        _ => tests.join("; "),
    };
    match at {
        LifetimeAt::Tests => {
            let one = materials.iter().all(|m| m.distinct().len() == 1);
            let held = if one && same {
                format!("The lifetimes hold at {}, the tests' temperature, not at a plant's operating temperature", describe_temperatures(materials[0].temperatures_c))
            } else if one {
                "Each lifetime holds at its own material's test temperature, not at a plant's operating temperature".to_string()
            } else {
                // A material whose tests span several temperatures, fitted as one population:
                // its lifetime holds at none of them.
                let each: Vec<String> = materials
                    .iter()
                    .map(|m| match m.distinct().len() {
                        1 => format!("{}'s at {}", m.label, describe_temperatures(m.temperatures_c)),
                        _ => format!("{}'s pools its tests at {} into one population and holds at none of these temperatures alone", m.label, describe_temperatures(m.temperatures_c)),
                    })
                    .collect();
                format!("No lifetime is at a plant's operating temperature: {}", each.join("; "))
            };
            format!("**Test temperature**: {tested}. {held}. Nothing in this study carries the strength to another temperature.")
        }
        LifetimeAt::Operating { per_material, by } => {
            let ops: Vec<String> = materials.iter().zip(per_material).map(|(m, t)| format!("{} at {t}", m.label)).collect();
            format!("**At a temperature other than the tests'**: the lifetimes are for the operating temperature ({}), while {tested}; {by} carry the strength from the one to the other.", ops.join("; "))
        }
    }
}

/// The warnings the tests' temperatures call for (module docs).
pub fn warnings(materials: &[Tested]) -> Vec<String> {
    let mut out = Vec::new();
    if materials.len() == 2 && materials[0].distinct() != materials[1].distinct() {
        out.push(format!(
            "the two materials were tested at different temperatures ({} at {}, {} at {}): the comparison sets a strength measured at one temperature against one measured at another",
            materials[0].label,
            describe_temperatures(materials[0].temperatures_c),
            materials[1].label,
            describe_temperatures(materials[1].temperatures_c)
        ));
    }
    for m in materials.iter().filter(|m| m.distinct().len() > 1 && !m.temperature_term) {
        out.push(format!("{}'s tests span {}, fitted as one population without a temperature term: name the `temperature` effect to model it", m.label, describe_temperatures(m.temperatures_c)));
    }
    out
}

/// `md` with each of `warnings` stated at the head of the section the report's first page
/// opens with (after the line `## Answer`, else `## Headline`), so that a comparison or lifetime
/// is not read without them (they also go to stderr and the report's Warnings page); where
/// there is no such section, before the first section (`## `), else at the end.
pub fn with_warnings(md: &str, warnings: &[String]) -> String {
    if warnings.is_empty() {
        return md.to_string();
    }
    let block: String = warnings.iter().map(|w| format!("**Warning**: {w}.\n\n")).collect();
    let head = if md.contains("## Answer\n") { "## Answer\n" } else { "## Headline\n" };
    match md.find(head) {
        Some(i) => {
            let j = i + head.len();
            format!("{}\n{block}{}", &md[..j], md[j..].trim_start_matches('\n'))
        }
        None => match md.find("\n## ") {
            Some(i) => format!("{}{block}{}", &md[..=i], &md[i + 1..]),
            None => format!("{md}\n{block}"),
        },
    }
}

/// The summary's section on what each material's file said beyond its values
/// ([`crate::intake::Provenance::summary_notes`]), one line per material with any; empty when
/// none has any.
pub fn read_section(materials: &[(&str, Vec<String>)]) -> String {
    let lines: Vec<String> = materials.iter().filter(|(_, n)| !n.is_empty()).map(|(label, n)| format!("* **{label}**: {}.\n", n.join("; "))).collect();
    if lines.is_empty() { String::new() } else { format!("\n## Read from the files\n\n{}", lines.concat()) }
}

/// The warning for materials side by side (a discrepancy study's lifetimes) tested at
/// different temperatures: each lifetime holds at its own tests' temperature, so the table
/// does not compare the materials at one temperature. None where every material was tested at
/// the same temperatures, or there is one.
pub fn side_by_side(materials: &[Tested]) -> Option<String> {
    (materials.len() > 1 && materials.windows(2).any(|w| w[0].distinct() != w[1].distinct())).then(|| {
        let each = materials.iter().map(|m| format!("{} at {}", m.label, describe_temperatures(m.temperatures_c))).collect::<Vec<_>>().join(", ");
        format!("the materials were tested at different temperatures ({each}): each one's lifetime holds at its own tests' temperature, so side by side they set a strength measured at one temperature against one measured at another, not one material against the other")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warnings_head_the_headline_section() {
        let md = "# T\n\nlead\n\n## Headline\n\n* A is better\n";
        let w = vec!["the two materials were tested at different temperatures (A at 800 °C, B at 20 °C)".to_string()];
        assert_eq!(with_warnings(md, &w), "# T\n\nlead\n\n## Headline\n\n**Warning**: the two materials were tested at different temperatures (A at 800 °C, B at 20 °C).\n\n* A is better\n");
        assert_eq!(with_warnings(md, &[]), md);
        assert!(with_warnings("# T\n", &w).ends_with("**Warning**: the two materials were tested at different temperatures (A at 800 °C, B at 20 °C).\n\n"));
        // An answer section comes first on the report's first page: the warnings head it.
        let md = "# T\n\nlead\n\n## Answer\n\nA breaks less.\n\n## Headline\n\n* A is better\n";
        assert_eq!(with_warnings(md, &w), "# T\n\nlead\n\n## Answer\n\n**Warning**: the two materials were tested at different temperatures (A at 800 °C, B at 20 °C).\n\nA breaks less.\n\n## Headline\n\n* A is better\n");
        // Without a headline, before the first section.
        assert_eq!(with_warnings("# T\n\nlead\n\n## A\n\nx\n", &w), "# T\n\nlead\n\n**Warning**: the two materials were tested at different temperatures (A at 800 °C, B at 20 °C).\n\n## A\n\nx\n");
    }

    #[test]
    fn the_read_section_lists_only_materials_with_notes() {
        assert_eq!(read_section(&[("A", vec![]), ("B", vec![])]), "");
        assert_eq!(read_section(&[("A", vec!["column not used: `x`".into()]), ("B", vec![])]), "\n## Read from the files\n\n* **A**: column not used: `x`.\n");
    }

    #[test]
    fn the_sentences_follow_the_temperatures() {
        let (rt, hot) = (vec![20.0; 3], vec![800.0; 2]);
        let a = Tested { label: "Gen 4", temperatures_c: &hot, temperature_term: false };
        let b = Tested { label: "BL 16/30", temperatures_c: &rt, temperature_term: false };
        let p = paragraph(&[a, b], &LifetimeAt::Tests);
        assert!(p.contains("Gen 4 was tested at 800 °C; BL 16/30 was tested at 20 °C") && p.contains("its own material's test temperature"), "{p}");
        let w = warnings(&[a, b]);
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("different temperatures (Gen 4 at 800 °C, BL 16/30 at 20 °C)"), "{w:?}");
        let b_rt = Tested { label: "BL 16/30", temperatures_c: &rt, ..b };
        let a_rt = Tested { label: "Gen 4", temperatures_c: &rt, ..a };
        let p = paragraph(&[a_rt, b_rt], &LifetimeAt::Tests);
        assert!(p.contains("both materials were tested at 20 °C") && p.contains("hold at 20 °C, the tests' temperature"), "{p}");
        assert!(warnings(&[a_rt, b_rt]).is_empty());
        // Side by side (a discrepancy study's lifetimes): warned where the temperatures differ.
        assert!(side_by_side(&[a, b]).is_some_and(|w| w.contains("(Gen 4 at 800 °C, BL 16/30 at 20 °C): each one's lifetime holds at its own tests' temperature")));
        assert!(side_by_side(&[a_rt, b_rt]).is_none() && side_by_side(&[a]).is_none());
        let p = paragraph(&[a_rt, b_rt], &LifetimeAt::Operating { per_material: vec!["800 °C".into(), "700–800 °C".into()], by: "the temperature laws of `temperature.toml`".into() });
        assert!(p.contains("Gen 4 at 800 °C; BL 16/30 at 700–800 °C") && p.contains("while both materials were tested at 20 °C"), "{p}");
        // One material's tests at two temperatures, pooled: warned; with a term: not.
        let mixed = vec![20.0, 20.0, 800.0];
        let m = Tested { label: "Gen 4", temperatures_c: &mixed, temperature_term: false };
        assert!(warnings(&[m])[0].contains("span 20 °C (2) and 800 °C (1), fitted as one population"), "{:?}", warnings(&[m]));
        assert!(warnings(&[Tested { temperature_term: true, ..m }]).is_empty());
        // Its lifetime holds at neither temperature (it used to read "holds at its own test
        // temperature").
        let p = paragraph(&[m, b], &LifetimeAt::Tests);
        assert!(p.contains("No lifetime is at a plant's operating temperature: Gen 4's pools its tests at 20 °C (2) and 800 °C (1) into one population and holds at none of these temperatures alone; BL 16/30's at 20 °C."), "{p}");
        assert!(!p.contains("its own material's test temperature"), "{p}");
        // A batch tested at one temperature each: confounded; a batch at both: not.
        let l = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(confounded("Gen 4", "Charge", &l(&["K1", "K2", "K1"]), &mixed).is_none());
        let w = confounded("Gen 4", "Charge", &l(&["K1", "K1", "K2"]), &mixed).unwrap();
        assert!(w.contains("`Charge` coincides with the test temperature (K1 at 20 °C, K2 at 800 °C)"), "{w}");
        assert!(confounded("Gen 4", "Charge", &l(&["K1", "K2", "K1"]), &[20.0; 3]).is_none());
        // A named temperature counts only where the model carries the term.
        let named = [Some("800 °C".to_string())];
        assert_eq!(named_or_tests(&[m], &named), LifetimeAt::Tests);
        assert!(unused_prediction(&m, Some("800 °C")).is_some_and(|w| w.contains("changes nothing")));
        let with_term = Tested { temperature_term: true, ..m };
        assert!(matches!(named_or_tests(&[with_term], &named), LifetimeAt::Operating { per_material, .. } if per_material == ["800 °C"]));
        assert!(unused_prediction(&with_term, Some("800 °C")).is_none());
    }
}

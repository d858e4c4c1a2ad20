//! `summary.md` of the main study: every sentence generated from the numbers it describes
//! (headline, whether accounting for the effects changes which particle is better, the
//! deliverable's shape hypothesis, what drives the answer, damage models side by side).

use super::sobol::SobolIndices;
use super::study::UqStudy;
use crate::lifetime::damage::DamageModel;
use crate::strength::{StrengthSpec, summarise};
use super::forms::Form;
use super::headline::{AVERAGED, AveragingRow, Headline, Row, pm};

/// "the deliverable's model (no effects)" or "the `x` model"; where a material carries its
/// failure origins' laws under it, said ("…; Gen 4: each failure origin's law").
pub(super) fn model_phrase(f: &Form) -> String {
    let name = f.setup.spec.name();
    let origins: Vec<String> = f.setup.materials.iter().filter_map(|m| origin_list(m).map(|l| format!("{}: each failure origin's law ({l})", m.model.label))).collect();
    match (name == "deliverable", origins.is_empty()) {
        (true, true) => "the deliverable's model (no effects)".into(),
        (true, false) => format!("the deliverable's model (no effects; {})", origins.join("; ")),
        (false, _) => format!("the `{name}` model"),
    }
}

/// The better particle for P(candidate worse) = p, and how sure.
pub(super) fn verdict(p: f64, names: [&str; 2]) -> String {
    let (better, q) = if p > 0.5 { (names[1], p) } else { (names[0], 1.0 - p) };
    if p == 0.5 {
        return "neither particle is better".into();
    }
    let sure = if q >= 0.99 {
        "with near certainty"
    } else if q >= 0.9 {
        "with high probability"
    } else if q >= 0.7 {
        "more likely than not"
    } else {
        "but the answer is close to a coin toss"
    };
    format!("{better} is the better particle, {sure} ({q:.3})")
}

/// The effects each material carries under a model, in words.
pub(super) fn effects_phrase(f: &Form) -> String {
    f.setup
        .materials
        .iter()
        .map(|m| match origin_list(m) {
            Some(list) => format!("{}: each failure origin's law ({list})", m.model.label),
            None => format!("{}: {}", m.model.label, crate::strength::fit::names(m.model.fit.effects()).replace('+', ", ")),
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The failure origins a material's model carries ("\"Oberfläche\", \"Volumen\""), or None
/// where it carries one law.
fn origin_list(m: &super::setup::Material) -> Option<String> {
    (!m.origins.is_empty()).then(|| m.origins.iter().map(|o| format!("\"{}\"", o.fit.origin)).collect::<Vec<_>>().join(", "))
}

/// What the main study did with each material's failure-origin column, per strength model,
/// from the models themselves: which carry every origin's law and which fit one law to the
/// breaks of every origin (empty where no material names its origins).
pub(super) fn origins_paragraph(forms: &[Form]) -> String {
    let mut md = String::new();
    for j in 0..2 {
        let m = &forms[0].setup.materials[j];
        let Some(column) = &m.origin_column else { continue };
        let (known, pooled): (Vec<&Form>, Vec<&Form>) = forms.iter().partition(|f| !f.setup.materials[j].origins.is_empty());
        let quote = |v: &[&Form]| v.iter().map(|f| format!("`{}`", f.setup.spec.name())).collect::<Vec<_>>().join(", ");
        md.push_str(&format!("\n**Known failure origins of {}** (column `{column}`): ", m.model.label));
        let few = known.first().map_or_else(String::new, |f| crate::strength::origins::few_breaks(f.setup.materials[j].origins.iter().map(|o| &o.fit)));
        if let Some(f) = known.first() {
            let list = origin_list(&f.setup.materials[j]).unwrap_or_default();
            md.push_str(&format!(
                "in {} each origin ({list}) has its own two-parameter Weibull law, fitted to its breaks with the other origins' breaks censored (ASTM C1239), and a particle breaks at the first origin to fail: P = 1 − Π (1 − P_origin), exact under independent trials; under the damage models each origin's flaws accumulate damage on their own. ",
                if known.len() == 1 { format!("the strength model {}", quote(&known)) } else { format!("the strength models {}", quote(&known)) }
            ));
        }
        if !pooled.is_empty() {
            md.push_str(&format!(
                "{} {} effects on {}, and fit{} one law to the breaks of every origin (the origins' laws carry no effects).",
                if pooled.len() == 1 { format!("The strength model {}", quote(&pooled)) } else { format!("The strength models {}", quote(&pooled)) },
                if pooled.len() == 1 { "carries" } else { "carry" },
                m.model.label,
                if pooled.len() == 1 { "s" } else { "" }
            ));
        }
        md.push('\n');
        if !few.is_empty() {
            md.push_str(&format!("\n{few}\n"));
        }
    }
    md
}

/// The plain-language summary; every sentence with a number is built from the numbers it
/// states.
pub(super) fn summary(s: &UqStudy, forms: &[Form], ind: &[SobolIndices], varying: &[usize], outputs: &[String], headline: &Headline, averaging: &[AveragingRow]) -> String {
    let st = &forms[0].setup;
    let [a, b] = [&st.materials[0].model.label, &st.materials[1].model.label];
    let names = [a.as_str(), b.as_str()];
    let primary_damage = st.models[0];
    let first_h = st.years[0];
    let row = |strength: &str, damage: DamageModel, years: f64| headline.rows.iter().find(|r| r.strength == strength && r.damage == damage && r.years == years);
    let mut md = format!("# {a} against {b}: breakage over {} years, with its uncertainty\n\n", st.years.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" and "));
    md.push_str(&format!(
        "{} Monte Carlo samples per strength model ({:?}, {} independent blocks for the standard errors) of every uncertain input; {} strength model{} compared; damage model of the headline: {}.{}\n\n",
        forms[0].prop.count(),
        s.propagation.method,
        forms[0].prop.blocks.len(),
        forms.len(),
        if forms.len() == 1 { "" } else { "s" },
        primary_damage.label(),
        crate::intake::synthetic_sentence("crush data", &st.materials.iter().map(|m| (m.model.label.as_str(), m.path.as_path())).collect::<Vec<_>>())
    ));
    // What the crush files' rows say beyond a break (specimens not broken by the rig, classes).
    for m in &st.materials {
        let t = m.sample.strength.view().tally();
        if !t.complete() {
            let bands = match s.strength.uncertainty {
                crate::strength::Uncertainty::Bootstrap => "bands from the bootstrap that censors each redraw as the campaign did",
                crate::strength::Uncertainty::Bayesian => "bands from the posterior of the censored likelihood",
            };
            md.push_str(&format!("**{}**: {}. Fitted as what the rows say, with {bands}.\n\n", m.model.label, t.describe("particles")));
        }
    }
    // At which temperature each material was tested, and what the comparison holds at.
    {
        use crate::lifetime::tested::{LifetimeAt, paragraph};
        let temps: Vec<Vec<f64>> = st.materials.iter().map(|m| m.temperatures_c()).collect();
        let tested: Vec<_> = st.materials.iter().zip(&temps).map(|(m, t)| m.tested(t)).collect();
        let at = if let (Some(th), Some(op)) = (&st.thermal, &s.operating) {
            let range = |i: usize| {
                let m = &st.inputs[i].marginal;
                let (lo, hi) = (m.quantile(0.0), m.quantile(1.0));
                if lo == hi { format!("{lo} °C") } else { format!("{lo}–{hi} °C") }
            };
            LifetimeAt::Operating {
                per_material: vec![range(th.temperature_inputs[0]), range(th.temperature_inputs[1])],
                by: format!("the temperature laws of `{}` ({} joint draws, input `temperature_law`; they move the Weibull scale and the particle's Young's modulus)", op.law.display(), th.laws.len()),
            }
        } else {
            let named: Vec<Option<String>> = st.materials.iter().map(|m| m.model.population.predicted_temperature()).collect();
            crate::lifetime::tested::named_or_tests(&tested, &named)
        };
        md.push_str(&paragraph(&tested, &at));
        md.push_str("\n\n");
    }
    md.push_str("## Headline\n\n");
    for l in &headline.lines {
        md.push_str(&format!("* {}\n", l.trim()));
    }
    md.push_str(&format!("\n| strength model | effects | weight (stacking) | {} |\n|---|---|---|{}\n", st.years.iter().map(|y| format!("P({a} worse), {y} yr")).collect::<Vec<_>>().join(" | "), "---|".repeat(st.years.len())));
    let n = forms[0].prop.count();
    for f in forms {
        let cells: Vec<String> = st.years.iter().map(|&y| row(&f.setup.spec.name(), primary_damage, y).map_or("–".into(), |r| pm(r.worse, r.se, n))).collect();
        md.push_str(&format!("| {} | {} | {:.3} | {} |\n", f.setup.spec.name(), effects_phrase(f), f.weight, cells.join(" | ")));
    }
    if forms.len() > 1 {
        let cells: Vec<String> = st.years.iter().map(|&y| row(AVERAGED, primary_damage, y).map_or("–".into(), |r| pm(r.worse, r.se, n))).collect();
        md.push_str(&format!("| {AVERAGED} | | 1 | {} |\n", cells.join(" | ")));
    }

    // The question in plain words.
    if forms.len() > 1 {
        md.push_str(&format!("\n## Does accounting for the effects change which particle is better? ({first_h} yr, {})\n\n", primary_damage.label()));
        let base = forms.iter().find(|f| f.setup.spec == StrengthSpec::default());
        if let Some(r0) = base.and_then(|f| row(&f.setup.spec.name(), primary_damage, first_h)) {
            md.push_str(&format!("Under {} {a} breaks more than {b} with probability {}: {}.\n", base.map(model_phrase).unwrap_or_default(), pm(r0.worse, r0.se, n), verdict(r0.worse, names)));
            for f in forms.iter().filter(|f| f.setup.spec != StrengthSpec::default()) {
                let Some(r) = row(&f.setup.spec.name(), primary_damage, first_h) else { continue };
                // The naming loop may name nothing: then the model is the deliverable's.
                if f.setup.spec == StrengthSpec::Diagnosed && f.setup.materials.iter().all(|m| m.model.fit.effects().is_empty()) {
                    md.push_str(&format!("Under {}, the naming loop named no effect in either material's data: it is the deliverable's model, with probability {}.\n", model_phrase(f), pm(r.worse, r.se, n)));
                    continue;
                }
                let same = (r.worse > 0.5) == (r0.worse > 0.5);
                md.push_str(&format!(
                    "Under {} ({}), with probability {}: {}; accounting for these effects {} which particle is better.\n",
                    model_phrase(f),
                    effects_phrase(f),
                    pm(r.worse, r.se, n),
                    verdict(r.worse, names),
                    if same { "does not change" } else { "changes" }
                ));
            }
            if let Some(r) = row(AVERAGED, primary_damage, first_h) {
                let best = forms.iter().max_by(|x, y| x.weight.total_cmp(&y.weight)).map(|f| (model_phrase(f), f.weight)).unwrap_or_default();
                md.push_str(&format!(
                    "\nThe stacking weights (from the cross-validated log density of the {} crush tests) put {:.3} on {}. Averaged over the strength models, P({a} breaks more) = {}: {}.\n",
                    forms[0].lpd[0].len() + forms[0].lpd[1].len(),
                    best.1,
                    best.0,
                    pm(r.worse, r.se, n),
                    verdict(r.worse, names)
                ));
            }
            // The deliverable's hypothesis, where the study states it: shape effects would
            // favour the candidate. Tested with the models whose shape effects were fitted to
            // both materials' data (which needs their roundness or sphericity columns).
            let shape: Vec<&Form> = forms.iter().filter(|f| f.setup.materials.iter().all(|m| m.model.fit.effects().iter().any(|e| e.is_contact_geometry()))).collect();
            if s.model_form.shape_hypothesis && !shape.is_empty() {
                md.push_str(&format!("\nThe deliverable expected that accounting for the particles' shape (roundness, non-sphericity) would make the lifetime model favour {a}. "));
                let parts: Vec<String> = shape
                    .iter()
                    .filter_map(|f| row(&f.setup.spec.name(), primary_damage, first_h).map(|r| (f, r)))
                    .map(|(f, r)| format!("under {} P({a} breaks less than {b}) = {:.3}", model_phrase(f), 1.0 - r.worse))
                    .collect();
                let favoured = shape.iter().filter_map(|f| row(&f.setup.spec.name(), primary_damage, first_h)).any(|r| r.worse < 0.5);
                md.push_str(&format!(
                    "With shape effects fitted to these data, {}, against {:.3} under the deliverable's model: the hypothesis is {}.\n",
                    parts.join(", "),
                    1.0 - r0.worse,
                    if favoured { format!("supported ({a} is favoured)") } else if shape.iter().filter_map(|f| row(&f.setup.spec.name(), primary_damage, first_h)).all(|r| r.worse > r0.worse) { format!("not supported: the shape effects make {b} look even better") } else { format!("not supported: {b} stays the better particle") }
                ));
            }
        }
    }

    md.push_str("\n## Breaking probability per strength model (median and 90 % band)\n\n| strength model | material | horizon | median P | 90 % band |\n|---|---|---|---|---|\n");
    let strengths: Vec<String> = forms.iter().map(|f| f.setup.spec.name()).chain((forms.len() > 1).then(|| AVERAGED.to_string())).collect();
    for name in &strengths {
        for &y in &st.years {
            if let Some(r) = row(name, primary_damage, y) {
                for j in 0..2 {
                    md.push_str(&format!("| {name} | {} | {y} yr | {:.2e} | {:.1e} – {:.1e} |\n", names[j], r.median[j], r.band[j].0, r.band[j].1));
                }
            }
        }
    }

    md.push_str("\n## The strength models (per material: effects, modulus and 90 % range of the draws)\n\n| strength model | material | effects | m | other parameters |\n|---|---|---|---|---|\n");
    for f in forms {
        for m in &f.setup.materials {
            for o in &m.origins {
                let sums = summarise(&o.model.fit, &o.fit.draws);
                let scale = &sums[1];
                md.push_str(&format!(
                    "| {} | {} | failure origin \"{}\" ({} breaks) | {:.2} [{:.2}, {:.2}] | scale σθ = {:.1} [{:.1}, {:.1}] MPa |\n",
                    f.setup.spec.name(),
                    m.model.label,
                    o.fit.origin,
                    o.fit.breaks,
                    sums[0].estimate,
                    sums[0].q05,
                    sums[0].q95,
                    scale.estimate / 1e6,
                    scale.q05 / 1e6,
                    scale.q95 / 1e6
                ));
            }
            if !m.origins.is_empty() {
                continue;
            }
            let sums = summarise(&m.model.fit, &m.draws);
            let other: Vec<String> = sums.iter().skip(2).map(|p| format!("{} = {:.3} [{:.3}, {:.3}]", p.name, p.estimate, p.q05, p.q95)).collect();
            md.push_str(&format!("| {} | {} | {} | {:.2} [{:.2}, {:.2}] | {} |\n", f.setup.spec.name(), m.model.label, crate::strength::fit::names(m.model.fit.effects()), sums[0].estimate, sums[0].q05, sums[0].q95, other.join("; ")));
        }
    }

    md.push_str(&origins_paragraph(forms));

    // What the recorded factors of a model are predicted for.
    for (j, m) in st.materials.iter().enumerate() {
        let mut factors: Vec<String> = Vec::new();
        for f in forms {
            for e in f.setup.materials[j].model.fit.effects() {
                if let crate::strength::Effect::Factor(x) = e
                    && !factors.contains(&x.column)
                {
                    factors.push(x.column.clone());
                }
            }
        }
        if !factors.is_empty() {
            md.push_str(&format!("\n{} is predicted for {} — in the models that carry these factors; the others do not depend on them.\n", m.model.label, m.model.population.describe_factors(&factors)));
        }
    }

    md.push_str(&format!("\n## What drives it (Sobol' total indices, last horizon, strength model `{}`)\n\n", st.spec.name()));
    for (o, si) in ind.iter().enumerate() {
        let mut order: Vec<usize> = (0..varying.len()).collect();
        order.sort_by(|&p, &q| si.total[q].total_cmp(&si.total[p]));
        let top: Vec<String> = order.iter().take(3).map(|&k| format!("{} (S_T = {:.2}, S = {:.2})", st.inputs[varying[k]].name, si.total[k], si.first[k])).collect();
        md.push_str(&format!("* `{}`: {}\n", outputs[o], top.join("; ")));
        let neg: Vec<String> = si.negative().iter().map(|&k| st.inputs[varying[k]].name.clone()).collect();
        if !neg.is_empty() {
            md.push_str(&format!("  (negative estimates, i.e. zero within Monte Carlo error: {})\n", neg.join(", ")));
        }
    }

    md.push_str(&format!("\n## Damage models side by side (strength model `{}`)\n\n| model | horizon | P({a} worse) | both equal | median P {a} | median P {b} |\n|---|---|---|---|---|---|\n", st.spec.name()));
    let primary_rows: Vec<&Row> = headline.rows.iter().filter(|r| r.strength == st.spec.name()).collect();
    for r in &primary_rows {
        md.push_str(&format!("| {} | {} yr | {:.3} | {:.3} | {:.2e} | {:.2e} |\n", r.damage.label(), r.years, r.worse, r.ties, r.median[0], r.median[1]));
    }
    md.push('\n');
    md.push_str(&damage_sentences(*st.years.last().unwrap_or(&1.0), &primary_rows, names));
    md.push_str("The spread between the damage models is model-form uncertainty that more crush data cannot remove: it needs repeated-impact tests.\n");

    if averaging.len() > st.years.len() {
        md.push_str("\n## Averaging domain of σ̄ (deliverable's strength model, independent trials)\n\n| domain | horizon | P(candidate worse) | median P candidate | median P reference |\n|---|---|---|---|---|\n");
        for (d, years, worse, se, pa, pb) in averaging {
            md.push_str(&format!("| {d} | {years} yr | {worse:.4} ± {se:.4} | {pa:.2e} | {pb:.2e} |\n"));
        }
        md.push_str("\nEvery domain whose outer limit is a multiple of the contact radius gives σ̄ = r·p0 in the crush test and in the impact alike, so r cancels between the Weibull scale and the impact stress: those domains give identical answers up to Monte Carlo error. Only a domain reaching the particle radius (σ̄ depends on a/R, which differs between the crush at break and a 5 m/s impact) changes them.\n");
    }
    md
}

/// How each damage model's medians compare with independent trials', generated from the rows
/// at horizon `last` (years).
pub(super) fn damage_sentences(last: f64, rows: &[&Row], names: [&str; 2]) -> String {
    let Some(indep) = rows.iter().find(|r| r.damage == DamageModel::Independent && r.years == last) else { return String::new() };
    let mut out = String::new();
    for r in rows.iter().filter(|r| r.damage != DamageModel::Independent && r.years == last) {
        let parts: Vec<String> = (0..2)
            .map(|j| {
                let (x, y) = (r.median[j], indep.median[j]);
                let times = |r: f64| if r >= 1000.0 { format!("{r:.1e}") } else if r >= 10.0 { format!("{r:.0}") } else { format!("{r:.2}") };
                let cmp = if x == 0.0 && y > 0.0 {
                    "no breakage in most samples (below its energy threshold)".to_string()
                } else if x > y {
                    format!("larger median probabilities ({x:.2e} against {y:.2e}, × {})", times(x / y))
                } else if x < y {
                    format!("smaller median probabilities ({x:.2e} against {y:.2e}, × {})", times(x / y))
                } else {
                    format!("the same median probability ({x:.2e})")
                };
                format!("for {} {cmp}", names[j])
            })
            .collect();
        out.push_str(&format!("Over {last} years {} gives, compared with independent trials, {}; under it P({} breaks more) = {:.3}.\n", r.damage.label(), parts.join(", and "), names[0], r.worse));
    }
    out
}

#[cfg(test)]
mod tests {
    //! The summary's sentences and the averaged headline against hand-made rows: a wrong
    //! comparison, ratio or weight would show here.
    use super::super::headline::{Row, pm};
    use super::*;

    fn row(damage: DamageModel, years: f64, worse: f64, se: f64, ties: f64, median: [f64; 2]) -> Row {
        Row { strength: "m".into(), damage, years, worse, se, ties, median, band: [(0.0, 1.0); 2] }
    }

    #[test]
    fn verdict_names_the_better_particle_and_how_sure() {
        let n = ["Gen 4", "BL 16/30"];
        assert_eq!(verdict(0.9999, n), "BL 16/30 is the better particle, with near certainty (1.000)");
        assert_eq!(verdict(0.05, n), "Gen 4 is the better particle, with high probability (0.950)");
        assert_eq!(verdict(0.75, n), "BL 16/30 is the better particle, more likely than not (0.750)");
        assert_eq!(verdict(0.4, n), "Gen 4 is the better particle, but the answer is close to a coin toss (0.600)");
        assert_eq!(verdict(0.5, n), "neither particle is better");
    }

    #[test]
    fn pm_never_prints_a_zero_error() {
        assert_eq!(pm(1.0, 0.0, 1000), "1.0000 (in all 1000 samples)");
        assert_eq!(pm(0.9999, 2.9e-6, 10), "0.9999 ± 2.9e-6");
        assert_eq!(pm(0.25, 0.0123, 10), "0.2500 ± 0.0123");
    }

    #[test]
    fn damage_sentences_compare_each_model_with_independent_trials() {
        let names = ["A", "B"];
        let rows = [
            row(DamageModel::Independent, 10.0, 0.9, 0.0, 0.0, [1e-3, 2e-4]),
            row(DamageModel::VogelPeukert, 10.0, 0.8, 0.0, 0.0, [0.0, 2e-3]),
            row(DamageModel::TavaresKing, 10.0, 0.7, 0.0, 0.0, [5e-2, 2e-4]),
            // Another horizon: ignored.
            row(DamageModel::TavaresKing, 1.0, 0.1, 0.0, 0.0, [1.0, 1.0]),
        ];
        let refs: Vec<&Row> = rows.iter().collect();
        let text = damage_sentences(10.0, &refs, names);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 2, "{text}");
        assert_eq!(
            lines[0],
            "Over 10 years Vogel–Peukert gives, compared with independent trials, for A no breakage in most samples (below its energy threshold), and for B larger median probabilities (2.00e-3 against 2.00e-4, × 10); under it P(A breaks more) = 0.800."
                .replace("Vogel–Peukert", DamageModel::VogelPeukert.label())
        );
        assert_eq!(
            lines[1],
            "Over 10 years Tavares–King gives, compared with independent trials, for A larger median probabilities (5.00e-2 against 1.00e-3, × 50), and for B the same median probability (2.00e-4); under it P(A breaks more) = 0.700."
                .replace("Tavares–King", DamageModel::TavaresKing.label())
        );
        // Without an independent-trials row there is nothing to compare with.
        assert_eq!(damage_sentences(10.0, &refs[1..], names), "");
    }
}

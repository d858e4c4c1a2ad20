//! Captions of a temperature report's figures (`kind = "temperature"`), each read from the table
//! its figure is drawn from: the phase fractions, the parameters' laws, the held-out curves and
//! the breaking probability against temperature.

use std::path::Path;

use super::super::document::Block;
use super::super::temperature::axis;
use super::super::{Table, distinct, prob_text};
use super::{FigureNote, p, percent};
use crate::error::Result;

/// "20 °C" with no trailing ".0".
fn celsius(t: f64) -> String {
    format!("{} °C", super::sig2(t))
}

/// The note of figure `stem` of a temperature report (None: not one of its figures).
pub(super) fn figure(dir: &Path, stem: &str) -> Result<Option<FigureNote>> {
    Ok(Some(match stem {
        "phase_fractions" => phases(dir)?,
        "parameters_vs_temperature" => parameters(dir)?,
        "held_out" => held_out(dir)?,
        "breakage_vs_temperature" => breakage(dir)?,
        _ => return Ok(None),
    }))
}

fn phases(dir: &Path) -> Result<FigureNote> {
    let t = Table::load(dir, "phases")?;
    let names: Vec<String> = t.df.get_column_names().iter().map(|n| n.to_string()).collect();
    let (column, basis) = [("volume_fraction", "volume"), ("mass_fraction", "mass"), ("mole_fraction", "mole")].into_iter().find(|(c, _)| names.iter().any(|n| n == c)).unwrap_or(("volume_fraction", "volume"));
    let (temp, phase, frac, amorphous) = (t.f("temperature_c")?, t.s("phase")?, t.f(column)?, t.s("amorphous")?);
    let temps = distinct(&temp);
    let (t0, t1) = (temps.iter().cloned().fold(f64::INFINITY, f64::min), temps.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
    let at = |tt: f64| -> String {
        let parts: Vec<String> = (0..temp.len()).filter(|&i| temp[i] == tt && frac[i] > 0.0).map(|i| format!("{} {:.3}", phase[i], frac[i])).collect();
        if parts.is_empty() { "no phase".into() } else { parts.join(", ") }
    };
    let glassy: Vec<String> = distinct(&(0..phase.len()).filter(|&i| amorphous[i] == "true").map(|i| phase[i].clone()).collect::<Vec<_>>());
    let amorph = if glassy.is_empty() {
        "No phase is amorphous.".to_string()
    } else {
        // The amorphous fraction per temperature: the sum over the amorphous phases.
        let sum = |tt: f64| (0..temp.len()).filter(|&i| temp[i] == tt && amorphous[i] == "true").map(|i| frac[i]).sum::<f64>();
        let mut sorted = temps.clone();
        sorted.sort_by(f64::total_cmp);
        match sorted.iter().find(|&&tt| sum(tt) > 0.01) {
            Some(&first) => format!("The amorphous fraction ({}, dashed) first exceeds 0.01 at {} and is {:.3} at {}.", glassy.join(", "), celsius(first), sum(t1), celsius(t1)),
            None => format!("The amorphous fraction ({}, dashed) stays at or below 0.01 up to {}.", glassy.join(", "), celsius(t1)),
        }
    };
    Ok(FigureNote {
        title: Some("Phases against temperature".into()),
        caption: p(&format!(
            "The {basis} fraction of each of the {} phases at {} temperatures from {} to {}, joined by straight lines (nothing is drawn beyond the table). At {}: {}; at {}: {}. {amorph}",
            distinct(&phase).len(),
            temps.len(),
            celsius(t0),
            celsius(t1),
            celsius(t0),
            at(t0),
            celsius(t1),
            at(t1)
        )),
        blocks: vec![],
    })
}

fn parameters(dir: &Path) -> Result<FigureNote> {
    let t = Table::load(dir, "parameters_vs_temperature")?;
    let (name, unit, temp, q50, lo, hi) = (t.s("parameter")?, t.s("unit")?, t.f("temperature_c")?, t.f("q50")?, t.f("lo")?, t.f("hi")?);
    let c = Table::load(dir, "calibrated_states")?;
    let calibrated: Vec<String> = distinct(&c.f("temperature_c")?).into_iter().map(celsius).collect();
    let mut rows = Vec::new();
    let mut said = Vec::new();
    let (mut t0, mut t1) = (f64::NAN, f64::NAN);
    for n in distinct(&name) {
        let idx: Vec<usize> = (0..name.len()).filter(|&i| name[i] == n).collect();
        let (Some(&a), Some(&b)) = (idx.iter().min_by(|&&x, &&y| temp[x].total_cmp(&temp[y])), idx.iter().max_by(|&&x, &&y| temp[x].total_cmp(&temp[y]))) else { continue };
        (t0, t1) = (temp[a], temp[b]);
        let (label, f) = axis(&n, &unit[a]);
        let v = |i: usize| format!("{:.3} [{:.3}, {:.3}]", q50[i] * f, lo[i] * f, hi[i] * f);
        let widen = (hi[b] - lo[b]) / (hi[a] - lo[a]);
        rows.push(vec![label.clone(), v(a), v(b), format!("{widen:.2}")]);
        if n == "youngs_modulus" {
            let u = if unit[a] == "Pa" { " GPa" } else { "" };
            said.push(format!("Young's modulus E falls from {:.1}{u} at {} to {:.1}{u} at {} (medians)", q50[a] * f, celsius(temp[a]), q50[b] * f, celsius(temp[b])));
        }
    }
    let e = if said.is_empty() { String::new() } else { format!(" {}.", said.join("; ")) };
    Ok(FigureNote {
        title: Some("The calibrated parameters against temperature".into()),
        caption: p(&format!(
            "Median and 90 % band of each parameter's law θ(T) from {} to {}, with the calibration posteriors at {} (points with bars).{e} The table gives each law at both ends of the grid and how much its band widens between them.",
            celsius(t0),
            celsius(t1),
            calibrated.join(" and ")
        )),
        blocks: vec![Block::Table { header: vec!["parameter".into(), format!("median [90 %] at {}", celsius(t0)), format!("at {}", celsius(t1)), "band width ratio".into()], rows }],
    })
}

fn held_out(dir: &Path) -> Result<FigureNote> {
    let t = Table::load(dir, "validation")?;
    let (label, source, n, inside, level) = (t.s("label")?, t.s("source")?, t.f("observations")?, t.f("inside")?, t.f("level")?);
    let pct = level.first().map_or(90.0, |l| (100.0 * l).round());
    let mut rows = Vec::new();
    let mut said = Vec::new();
    for l in distinct(&label) {
        let mut parts = Vec::new();
        for s in distinct(&(0..label.len()).filter(|&i| label[i] == l).map(|i| source[i].clone()).collect::<Vec<_>>()) {
            let idx: Vec<usize> = (0..label.len()).filter(|&i| label[i] == l && source[i] == s).collect();
            let (k, m): (f64, f64) = (idx.iter().map(|&i| inside[i]).sum(), idx.iter().map(|&i| n[i]).sum());
            let share = format!("{k:.0} of {m:.0} ({})", percent(k / m.max(1.0)));
            parts.push(format!("{s}: {share}"));
            rows.push(vec![l.clone(), s.clone(), share]);
        }
        said.push(format!("{l} — {}", parts.join("; ")));
    }
    Ok(FigureNote {
        title: Some("Held-out crush curves against the predictions".into()),
        caption: p(&format!(
            "Each held-out data set (no law was fitted to it): the force at the grid displacements and the peak force, observed (grey markers) against each source's {pct:.0} % predictive interval. Observations inside their interval: {}.",
            said.join(". ")
        )),
        blocks: vec![Block::Table { header: vec!["data set".into(), "source".into(), format!("inside its {pct:.0} % interval")], rows }],
    })
}

fn breakage(dir: &Path) -> Result<FigureNote> {
    let t = Table::load(dir, "lifetime_vs_temperature")?;
    let (label, yrs, temp, q50, lo, hi) = (t.s("material")?, t.f("years")?, t.f("temperature_c")?, t.f("p_q50")?, t.f("p_lo")?, t.f("p_hi")?);
    let m = Table::load(dir, "softening_marks")?;
    let (mlabel, mtemp) = (m.s("material")?, m.f("softening_temperature_c")?);
    let (t0, t1) = (temp.iter().cloned().fold(f64::INFINITY, f64::min), temp.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
    let mut rows = Vec::new();
    let mut said = Vec::new();
    for y in distinct(&yrs) {
        for l in distinct(&label) {
            let find = |tt: f64| (0..label.len()).find(|&i| label[i] == l && yrs[i] == y && temp[i] == tt);
            let (Some(a), Some(b)) = (find(t0), find(t1)) else { continue };
            let band = |i: usize| format!("{} [{}, {}]", prob_text(q50[i]), prob_text(lo[i]), prob_text(hi[i]));
            rows.push(vec![l.clone(), format!("{y}"), band(a), band(b)]);
            if said.len() < distinct(&label).len() {
                said.push(format!("{l} {} at {} and {} at {}", prob_text(q50[a]), celsius(t0), prob_text(q50[b]), celsius(t1)));
            }
        }
    }
    let first = distinct(&yrs).first().copied().unwrap_or(f64::NAN);
    let marks: Vec<String> = (0..mlabel.len()).map(|i| format!("{} {}", mlabel[i], celsius(mtemp[i]))).collect();
    let marks = if marks.is_empty() { String::new() } else { format!(" Dashed lines: Table 1's softening temperatures ({}).", marks.join(", ")) };
    Ok(FigureNote {
        title: Some("Breaking probability against operating temperature".into()),
        caption: p(&format!(
            "Median breaking probability and its 90 % band against the operating temperature, one panel per horizon. After {} year{}, median: {}.{marks}",
            first,
            if first == 1.0 { "" } else { "s" },
            said.join("; ")
        )),
        blocks: vec![Block::Table { header: vec!["material".into(), "years".into(), format!("median P [90 %] at {}", celsius(t0)), format!("at {}", celsius(t1))], rows }],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::TempDir;

    /// The phase caption names the temperature where the amorphous phases together first exceed
    /// 0.01, and the phases present at both ends.
    #[test]
    fn phase_caption_reads_the_table() {
        let dir = TempDir::new("captions-temperature").unwrap();
        std::fs::write(
            dir.path().join("phases.csv"),
            "temperature_c,phase,volume_fraction,amorphous\n\
             20,A,1.0,false\n20,G1,0.0,true\n20,G2,0.0,true\n\
             500,A,0.992,false\n500,G1,0.004,true\n500,G2,0.004,true\n\
             900,A,0.8,false\n900,G1,0.1,true\n900,G2,0.1,true\n",
        )
        .unwrap();
        let n = figure(dir.path(), "phase_fractions").unwrap().unwrap();
        let c: String = n.caption.iter().map(|s| s.text.as_str()).collect();
        assert!(c.contains("3 phases at 3 temperatures from 20 °C to 900 °C"), "{c}");
        assert!(c.contains("At 20 °C: A 1.000;"), "{c}");
        assert!(c.contains("(G1, G2, dashed) first exceeds 0.01 at 900 °C and is 0.200 at 900 °C"), "{c}");
    }
}

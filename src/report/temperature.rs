//! Figures of a temperature report (`kind = "temperature"`), drawn from its tables only.
//!
//! | file stem | content | table |
//! |---|---|---|
//! | `phase_fractions` | every phase's fraction against temperature, amorphous phases dashed (the deliverable's Fig. 2 in °C) | `phases.csv` |
//! | `parameters_vs_temperature` | one panel per parameter (and Young's modulus): the law's median and band, the calibrated states with their bands | `parameters_vs_temperature.csv`, `calibrated_states.csv` |
//! | `breakage_vs_temperature` | one panel per horizon: each material's median breaking probability and band against temperature, Table 1's softening temperatures marked | `lifetime_vs_temperature.csv`, `softening_marks.csv` |

use std::path::Path;

use plotters::prelude::SeriesLabelPosition;

use super::canvas::{Encoded, colour};
use super::panel::{Kind, Marker, Panel, Series, figure, figure_grid, padded};
use super::{Rendered, Table, distinct, lg};
use crate::error::Result;

/// Draws every figure of a temperature report in `dir` (those whose tables it has).
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let mut figures = vec![("phase_fractions", phase_fractions(dir, width_cm)?)];
    if dir.join("parameters_vs_temperature.csv").is_file() {
        figures.push(("parameters_vs_temperature", parameters(dir, width_cm)?));
    }
    if dir.join("lifetime_vs_temperature.csv").is_file() {
        figures.push(("breakage_vs_temperature", breakage(dir, width_cm)?));
    }
    super::write_figures(dir, figures)
}

/// A parameter's name and unit as an axis label, with the value scale (Pa shown in GPa).
fn axis(name: &str, unit: &str) -> (String, f64) {
    let what = match name {
        "g" => "Shear modulus G".to_string(),
        "k1" => "Bulk modulus K₁".to_string(),
        "a" => "Intact strength A".to_string(),
        "t" => "Tensile strength T".to_string(),
        "youngs_modulus" => "Young's modulus E".to_string(),
        other => other.to_string(),
    };
    match unit {
        "Pa" => (format!("{what} (GPa)"), 1e-9),
        "" | "-" => (format!("{what} (–)"), 1.0),
        u => (format!("{what} ({u})"), 1.0),
    }
}

fn parameters(dir: &Path, width_cm: f64) -> Result<(Encoded, usize)> {
    let t = Table::load(dir, "parameters_vs_temperature")?;
    let (name, unit, temp, q50, lo, hi) = (t.s("parameter")?, t.s("unit")?, t.f("temperature_c")?, t.f("q50")?, t.f("lo")?, t.f("hi")?);
    let c = Table::load(dir, "calibrated_states")?;
    let (cname, ctemp, c50, clo, chi) = (c.s("parameter")?, c.f("temperature_c")?, c.f("calibration_q50")?, c.f("calibration_lo")?, c.f("calibration_hi")?);
    let names = distinct(&name);
    let mut panels = Vec::new();
    for (k, n) in names.iter().enumerate() {
        let rows: Vec<usize> = (0..name.len()).filter(|&i| &name[i] == n).collect();
        let (y_desc, f) = axis(n, &unit[rows[0]]);
        let first = k == 0;
        let mut series = vec![
            Series { label: first.then(|| "law: band".to_string()), points: rows.iter().map(|&i| (temp[i], f * lo[i])).collect(), colour: colour(0), kind: Kind::Band(rows.iter().map(|&i| f * hi[i]).collect(), 0.25) },
            Series::line(first.then(|| "law: median".to_string()), rows.iter().map(|&i| (temp[i], f * q50[i])).collect(), colour(0), 1.2),
        ];
        let crow: Vec<usize> = (0..cname.len()).filter(|&i| &cname[i] == n).collect();
        for (m, &i) in crow.iter().enumerate() {
            series.push(Series { label: None, points: vec![(ctemp[i], f * clo[i]), (ctemp[i], f * chi[i])], colour: colour(1), kind: Kind::Line(1.0) });
            series.push(Series { label: (first && m == 0).then(|| "calibration: median, band".to_string()), points: vec![(ctemp[i], f * c50[i])], colour: colour(1), kind: Kind::Markers(Marker::Circle, 2.5) });
        }
        let ys = rows.iter().flat_map(|&i| [f * lo[i], f * hi[i]]).chain(crow.iter().flat_map(|&i| [f * clo[i], f * chi[i]]));
        let (_, ymax) = padded(ys, 0.05, 0.05);
        panels.push(Some(Panel {
            x_categories: vec![],
            x_desc: "Temperature (°C)".into(),
            y_desc,
            x_range: padded(temp.iter().cloned(), 0.0, 0.0),
            y_range: (0.0, ymax),
            y_log: false,
            series,
            legend: first.then_some(SeriesLabelPosition::LowerLeft),
        }));
    }
    let cols = 2;
    let rows = names.len().div_ceil(cols);
    figure_grid("parameters_vs_temperature", 2.0 * width_cm, 0.42 * rows as f64, cols, &panels)
}

fn years_label(y: f64) -> String {
    if y == 1.0 { "1 year".into() } else { format!("{y} years") }
}

fn breakage(dir: &Path, width_cm: f64) -> Result<(Encoded, usize)> {
    let t = Table::load(dir, "lifetime_vs_temperature")?;
    let (key, label, yrs, temp, q50, lo, hi) = (t.s("material_key")?, t.s("material")?, t.f("years")?, t.f("temperature_c")?, t.f("p_q50")?, t.f("p_lo")?, t.f("p_hi")?);
    let m = Table::load(dir, "softening_marks")?;
    let (mkey, mlabel, mtemp) = (m.s("material_key")?, m.s("material")?, m.f("softening_temperature_c")?);
    let keys = distinct(&key);
    let horizons = distinct(&yrs);
    let mut panels = Vec::new();
    for (h, &y) in horizons.iter().enumerate() {
        let rows_of = |k: &String| (0..key.len()).filter(|&i| &key[i] == k && yrs[i] == y).collect::<Vec<usize>>();
        // Probabilities are drawn down to the figures' floor (below it, on it); decades
        // under the lowest drawn value (six in the last panel) leave the legend its own room.
        let floor = keys.iter().flat_map(|k| rows_of(k)).map(|i| lg(lo[i])).fold(0.0, f64::min).floor();
        let last = h + 1 == horizons.len();
        let low = if last { floor - 6.0 } else { floor - 0.5 };
        let mut series = Vec::new();
        for (j, k) in keys.iter().enumerate() {
            let rows = rows_of(k);
            let name = &label[rows[0]];
            series.push(Series { label: last.then(|| format!("{name}: median, band")), points: rows.iter().map(|&i| (temp[i], lg(lo[i]))).collect(), colour: colour(j), kind: Kind::Band(rows.iter().map(|&i| lg(hi[i])).collect(), 0.22) });
            series.push(Series::line(None, rows.iter().map(|&i| (temp[i], lg(q50[i]))).collect(), colour(j), 1.2));
        }
        for (i, mk) in mkey.iter().enumerate() {
            let j = keys.iter().position(|k| k == mk).unwrap_or(0);
            series.push(Series { label: last.then(|| format!("{} softening, {} °C (Table 1)", mlabel[i], mtemp[i])), points: vec![(mtemp[i], low), (mtemp[i], 0.0)], colour: colour(j), kind: Kind::Dashed(1.0, 3.0, 2.0) });
        }
        panels.push((
            Panel {
                x_categories: vec![],
                x_desc: if h + 1 == horizons.len() { "Operating temperature (°C)".into() } else { String::new() },
                y_desc: format!("P break, {}", years_label(y)),
                x_range: padded(temp.iter().cloned(), 0.0, 0.0),
                y_range: (low, 0.3),
                y_log: true,
                series,
                legend: last.then_some(SeriesLabelPosition::LowerLeft),
            },
            1.0 / horizons.len() as f64,
        ));
    }
    figure("breakage_vs_temperature", width_cm, 0.65 * horizons.len() as f64, &panels)
}

fn phase_fractions(dir: &Path, width_cm: f64) -> Result<(Encoded, usize)> {
    let t = Table::load(dir, "phases")?;
    let names: Vec<String> = t.df.get_column_names().iter().map(|n| n.to_string()).collect();
    let (column, basis) = if names.iter().any(|n| n == "mass_fraction") { ("mass_fraction", "Mass") } else { ("mole_fraction", "Mole") };
    let (temp, phase, frac, amorphous) = (t.f("temperature_c")?, t.s("phase")?, t.f(column)?, t.s("amorphous")?);
    let mut series = Vec::new();
    for (k, p) in distinct(&phase).iter().enumerate() {
        let rows: Vec<usize> = (0..phase.len()).filter(|&i| &phase[i] == p).collect();
        let points: Vec<(f64, f64)> = rows.iter().map(|&i| (temp[i], frac[i])).collect();
        let glassy = rows.first().is_some_and(|&i| amorphous[i] == "true");
        let label = if glassy { format!("{p} (amorphous)") } else { p.clone() };
        let kind = if glassy { Kind::Dashed(1.6, 4.0, 2.5) } else { Kind::Line(1.2) };
        series.push(Series { label: Some(label), points, colour: colour(k), kind });
    }
    let panel = Panel {
        x_categories: vec![],
        x_desc: "Temperature (°C)".into(),
        y_desc: format!("{basis} fraction of phase (–)"),
        x_range: padded(temp.iter().cloned(), 0.0, 0.0),
        y_range: (0.0, 1.0),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    figure("phase_fractions", width_cm, 0.8, &[(panel, 1.0)])
}

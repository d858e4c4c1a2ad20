//! Figures of a temperature report (`kind = "temperature"`), drawn from its tables only.
//!
//! | file stem | content | table |
//! |---|---|---|
//! | `phase_fractions` | every phase's fraction against temperature, amorphous phases dashed (the deliverable's Fig. 2 in °C) | `phases.csv` |
//! | `parameters_vs_temperature` | one panel per parameter (and Young's modulus): the law's median and band, the calibrated states with their bands | `parameters_vs_temperature.csv`, `calibrated_states.csv` |
//! | `held_out` | per held-out data set: the force at the grid displacements (observations as dots; each source's predictive interval as a band) and the peak force (each source's interval and centre, observed peaks as dots) | `validation.csv`, `validation_observations.csv` |
//! | `breakage_vs_temperature` | one panel per horizon: each material's median breaking probability and band against temperature, Table 1's softening temperatures marked | `lifetime_vs_temperature.csv`, `softening_marks.csv` |

use std::path::Path;

use plotters::prelude::SeriesLabelPosition;

use super::canvas::{Encoded, colour};
use super::panel::{Kind, Marker, Panel, Series, figure, figure_grid, padded};
use super::{Rendered, Table, distinct, lg};
use crate::error::{Error, Result};

/// Draws every figure of a temperature report in `dir` (those whose tables it has).
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let mut figures: Vec<super::Figure<_>> = vec![("phase_fractions", Box::new(|| phase_fractions(dir, width_cm)))];
    if dir.join("parameters_vs_temperature.csv").is_file() {
        figures.push(("parameters_vs_temperature", Box::new(|| parameters(dir, width_cm))));
    }
    if dir.join("validation.csv").is_file() {
        figures.push(("held_out", Box::new(|| held_out(dir, width_cm))));
    }
    if dir.join("lifetime_vs_temperature.csv").is_file() {
        figures.push(("breakage_vs_temperature", Box::new(|| breakage(dir, width_cm))));
    }
    super::write_figures(dir, super::draw_all(figures)?)
}

/// A parameter's name and unit as an axis label, with the value scale (Pa shown in GPa).
pub(crate) fn axis(name: &str, unit: &str) -> (String, f64) {
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

/// A source's short name under the peak-force axis.
fn source_short(kind: &str, t: f64) -> String {
    if kind == "laws" { format!("laws, {t} °C") } else { format!("{t} °C as is") }
}

fn held_out(dir: &Path, width_cm: f64) -> Result<(Encoded, usize)> {
    let t = Table::load(dir, "validation")?;
    let label = t.s("label")?;
    let (study, temp, source, kind, ts, output, grid, lo, hi, pred) =
        (t.s("study")?, t.f("temperature_c")?, t.s("source")?, t.s("source_kind")?, t.f("source_temperature_c")?, t.s("output")?, t.f("grid_displacement_m")?, t.f("lo")?, t.f("hi")?, t.f("predicted")?);
    let pct = t.f("level")?.first().map_or(90.0, |l| (100.0 * l).round());
    let o = Table::load(dir, "validation_observations")?;
    let (ostudy, ooutput, ovalue) = (o.s("study")?, o.s("output")?, o.f("value")?);
    let studies = distinct(&study);
    let grey = plotters::style::RGBColor(110, 110, 110);
    let mut panels = Vec::new();
    for st in &studies {
        let rows: Vec<usize> = (0..study.len()).filter(|&i| &study[i] == st).collect();
        let t_c = temp[rows[0]];
        let sources = distinct(&rows.iter().map(|&i| source[i].clone()).collect::<Vec<_>>());
        // Grid forces against the (normalised) displacement.
        let grid_x: Vec<f64> = distinct(&rows.iter().filter(|&&i| grid[i].is_finite()).map(|&i| grid[i]).collect::<Vec<_>>());
        let mut series = Vec::new();
        for (k, sname) in sources.iter().enumerate() {
            let r: Vec<usize> = rows.iter().copied().filter(|&i| &source[i] == sname && grid[i].is_finite()).collect();
            series.push(Series { label: Some(format!("{}: {pct} % interval", source_short(&kind[r[0]], ts[r[0]]))), points: r.iter().map(|&i| (grid[i] * 1e6, lo[i])).collect(), colour: colour(k), kind: Kind::Band(r.iter().map(|&i| hi[i]).collect(), 0.2) });
            series.push(Series::line(None, r.iter().map(|&i| (grid[i] * 1e6, pred[i])).collect(), colour(k), 1.0));
        }
        let force_names: Vec<String> = distinct(&rows.iter().filter(|&&i| grid[i].is_finite()).map(|&i| output[i].clone()).collect::<Vec<_>>());
        let obs_pts: Vec<(f64, f64)> = (0..ostudy.len())
            .filter(|&i| &ostudy[i] == st)
            .filter_map(|i| force_names.iter().position(|n| *n == ooutput[i]).map(|g| (grid_x[g] * 1e6, ovalue[i])))
            .collect();
        let what = if label[rows[0]].contains("°C") { label[rows[0]].clone() } else { format!("{}, {t_c} °C", label[rows[0]]) };
        series.push(Series { label: Some(format!("held out: {what}")), points: obs_pts.clone(), colour: grey, kind: Kind::Markers(Marker::Circle, 1.3) });
        let ys = rows.iter().filter(|&&i| grid[i].is_finite()).flat_map(|&i| [lo[i], hi[i]]).chain(obs_pts.iter().map(|p| p.1));
        panels.push((
            Panel {
                x_categories: vec![],
                x_desc: "Displacement, normalised to D₀ (µm)".into(),
                y_desc: "Force, normalised (N)".into(),
                x_range: (0.0, grid_x.iter().cloned().fold(0.0, f64::max) * 1e6 * 1.05),
                y_range: (0.0, padded(ys, 0.0, 0.05).1),
                y_log: false,
                series,
                legend: Some(SeriesLabelPosition::UpperLeft),
            },
            0.6 / studies.len() as f64,
        ));
        // Peak force: one interval per source, the observed peaks beside them.
        let mut series = Vec::new();
        let mut cats = Vec::new();
        let mut ys = Vec::new();
        for (k, sname) in sources.iter().enumerate() {
            let Some(&i) = rows.iter().find(|&&i| &source[i] == sname && output[i] == "peak_force") else { continue };
            let x = (k + 1) as f64;
            cats.push(source_short(&kind[i], ts[i]));
            series.push(Series { label: None, points: vec![(x - 0.25, lo[i]), (x + 0.25, lo[i])], colour: colour(k), kind: Kind::Band(vec![hi[i]; 2], 0.3) });
            series.push(Series { label: (k == 0).then(|| format!("predicted centre, {pct} % interval")), points: vec![(x, pred[i])], colour: colour(k), kind: Kind::Markers(Marker::Cross, 2.5) });
            let peaks: Vec<(f64, f64)> = (0..ostudy.len()).filter(|&j| &ostudy[j] == st && ooutput[j] == "peak_force").map(|j| (x, ovalue[j])).collect();
            ys.extend([lo[i], hi[i]]);
            ys.extend(peaks.iter().map(|p| p.1));
            series.push(Series { label: (k == 0).then(|| "observed peaks".to_string()), points: peaks, colour: grey, kind: Kind::Markers(Marker::Circle, 1.3) });
        }
        panels.push((
            Panel {
                x_categories: cats.clone(),
                x_desc: "Source of the prediction".into(),
                y_desc: "Peak force, normalised (N)".into(),
                x_range: (0.5, cats.len() as f64 + 0.5),
                y_range: (0.0, padded(ys.into_iter(), 0.0, 0.1).1),
                y_log: false,
                series,
                legend: Some(SeriesLabelPosition::UpperRight),
            },
            0.4 / studies.len() as f64,
        ));
    }
    figure("held_out", width_cm, 1.25 * studies.len() as f64, &panels)
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
        // under the lowest drawn value (seven in the last panel) leave the legend its own room.
        let floor = keys.iter().flat_map(|k| rows_of(k)).map(|i| lg(lo[i])).fold(0.0, f64::min).floor();
        let last = h + 1 == horizons.len();
        let low = if last { floor - 7.0 } else { floor - 0.5 };
        let mut series = Vec::new();
        for (j, k) in keys.iter().enumerate() {
            let rows = rows_of(k);
            let name = &label[rows[0]];
            series.push(Series { label: last.then(|| format!("{name}: median, band")), points: rows.iter().map(|&i| (temp[i], lg(lo[i]))).collect(), colour: colour(j), kind: Kind::Band(rows.iter().map(|&i| lg(hi[i])).collect(), 0.22) });
            series.push(Series::line(None, rows.iter().map(|&i| (temp[i], lg(q50[i]))).collect(), colour(j), 1.2));
        }
        for (i, mk) in mkey.iter().enumerate() {
            let j = keys.iter().position(|k| k == mk).unwrap_or(0);
            // From the drawn floor up: the legend's room below stays free.
            series.push(Series { label: last.then(|| format!("{} softening, {} °C (Table 1)", mlabel[i], mtemp[i])), points: vec![(mtemp[i], floor), (mtemp[i], 0.0)], colour: colour(j), kind: Kind::Dashed(1.0, 3.0, 2.0) });
        }
        panels.push((
            Panel {
                x_categories: vec![],
                x_desc: if h + 1 == horizons.len() { "Operating temperature (°C)".into() } else { String::new() },
                y_desc: format!("P break, {}", years_label(y)),
                // A little room on the right for the last tick label.
                x_range: padded(temp.iter().cloned(), 0.0, 0.03),
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
    // The study writes volume fractions; reports written before it did hold the file's basis.
    let Some((column, basis)) = [("volume_fraction", "Volume"), ("mass_fraction", "Mass"), ("mole_fraction", "Mole")].into_iter().find(|(c, _)| names.iter().any(|n| n == c)) else {
        return Err(Error::data_file(&dir.join("phases.csv"), "header", "no column `volume_fraction`, `mass_fraction` or `mole_fraction`"));
    };
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

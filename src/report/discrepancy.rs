//! Figures of a discrepancy report (`kind = "discrepancy"`), drawn from its tables only.
//!
//! | file stem | content | table |
//! |---|---|---|
//! | `discrepancy_residuals_<key>` | quantile residuals vs every covariate diagnosed, base model (left) and final model (right), with the binned mean | `residuals.csv` |
//! | `discrepancy_probability_<key>` | Weibull probability plot before (σ̄ as reduced) and after (σ̄ adjusted to the average covariates), with the fitted lines | `residuals.csv`, `fits.csv` |
//! | `discrepancy_origins_<key>` | each failure origin's breaks (Kaplan–Meier positions, the other origins censored) and its fitted line | `residuals.csv`, `origins.csv` |
//! | `discrepancy_gap` | gap measure G per round and material, with its expectation when nothing is missing | `stages.csv` |
//! | `discrepancy_evidence` | likelihood ratio of every candidate per round against the round's critical value | `evidence.csv` |
//! | `discrepancy_lifetime` | breaking probability of the population, base vs final model, 90 % bands | `lifetime.csv` |
//! | `discrepancy_power` | detection power and false-positive rate vs number of crush tests | `power.csv` |
//! | `discrepancy_curves` (kind `discrepancy_curves`) | measured mean crush curves with the calibrated FE before/after the named terms; δ(x) with 90 % bands before/after | `curve_points.csv`, `curve_evidence.csv` |

use std::path::Path;

use plotters::prelude::{BLACK, RGBColor, SeriesLabelPosition};

use super::canvas::{Encoded, colour};
use super::panel::{Kind, Marker, Panel, Series, figure, figure_grid, figure_legend_below, padded};
use super::{Rendered, Table, distinct, lg};
use crate::error::Result;

type Drawn = (Encoded, usize);

const GREY: RGBColor = RGBColor(150, 150, 150);

/// Draws every discrepancy figure in `dir`.
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let m = Table::load(dir, "materials")?;
    let (keys, labels) = (m.s("key")?, m.s("label")?);
    let mut names: Vec<String> = Vec::new();
    let mut drawn: Vec<Drawn> = Vec::new();
    let cov = Table::load(dir, "covariates")?;
    let cov_materials = cov.s("material")?;
    for (k, key) in keys.iter().enumerate() {
        // A file that records no covariate has no residual trend to plot.
        if cov_materials.contains(key) {
            names.push(format!("discrepancy_residuals_{key}"));
            drawn.push(residuals(dir, width_cm, key)?);
        }
        names.push(format!("discrepancy_probability_{key}"));
        drawn.push(probability(dir, width_cm, key, &labels[k], colour(k))?);
        // Known failure origins: each origin's breaks and law (older reports lack the table).
        if let Ok(o) = Table::load(dir, "origins")
            && o.s("material")?.contains(key)
        {
            names.push(format!("discrepancy_origins_{key}"));
            drawn.push(by_origin(dir, width_cm, key, &o)?);
        }
    }
    names.push("discrepancy_gap".into());
    drawn.push(gap(dir, width_cm, &keys, &labels)?);
    let ev = Table::load(dir, "evidence")?;
    if ev.s("skipped")?.iter().any(|s| s.is_empty()) {
        names.push("discrepancy_evidence".into());
        drawn.push(evidence(dir, width_cm, &keys, &labels)?);
    }
    let life = Table::load(dir, "lifetime")?;
    if !life.s("material")?.is_empty() {
        names.push("discrepancy_lifetime".into());
        drawn.push(lifetime(dir, width_cm, &keys, &labels)?);
    }
    let power_rows = Table::load(dir, "power")?;
    if !power_rows.s("material")?.is_empty() {
        names.push("discrepancy_power".into());
        drawn.push(power(dir, width_cm, &keys, &labels)?);
    }
    super::write_figures(dir, names.iter().map(|n| n.as_str()).zip(drawn).collect())
}

/// Axis label and display factor of a covariate column: a crush file's five with their units,
/// a strength file's factor by its column name (as the file holds it).
fn covariate_axis(name: &str) -> (String, f64) {
    match name {
        "diameter_m" => ("Diameter d (mm)".into(), 1e3),
        "roundness" => ("Roundness (–)".into(), 1.0),
        "sphericity" => ("Sphericity (–)".into(), 1.0),
        "temperature_c" => ("Temperature (°C)".into(), 1.0),
        "impacts" => ("Prior impacts (–)".into(), 1.0),
        other => (format!("{} (as in the file)", other.replace('_', " ")), 1.0),
    }
}

/// Means of y over `bins` equal-count bins of x, at the bins' mean x; where x takes at most
/// `bins` distinct values (a size series, a few test temperatures), one bin per value, so no
/// bin straddles two of them.
fn binned(x: &[f64], y: &[f64], bins: usize) -> Vec<(f64, f64)> {
    let mut idx: Vec<usize> = (0..x.len()).collect();
    idx.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let mut distinct: Vec<f64> = idx.iter().map(|&i| x[i]).collect();
    distinct.dedup();
    if distinct.len() <= bins {
        return distinct
            .iter()
            .map(|&v| {
                let g: Vec<f64> = idx.iter().filter(|&&i| x[i] == v).map(|&i| y[i]).collect();
                (v, g.iter().sum::<f64>() / g.len() as f64)
            })
            .collect();
    }
    idx.chunks(idx.len().div_ceil(bins).max(1))
        .map(|g| (g.iter().map(|&i| x[i]).sum::<f64>() / g.len() as f64, g.iter().map(|&i| y[i]).sum::<f64>() / g.len() as f64))
        .collect()
}

fn residuals(dir: &Path, width_cm: f64, key: &str) -> Result<Drawn> {
    let t = Table::load(dir, "residuals")?;
    let (mat, stage, r) = (t.s("material")?, t.s("stage")?, t.f("residual")?);
    let rows: Vec<usize> = (0..mat.len()).filter(|&i| mat[i] == key).collect();
    let fits = Table::load(dir, "fits")?;
    let (fm, fs, fe) = (fits.s("material")?, fits.s("stage")?, fits.s("effects")?);
    let effects_after = (0..fm.len()).find(|&i| fm[i] == key && fs[i] == "after").map(|i| fe[i].clone()).unwrap_or_default();
    let y_range = padded(rows.iter().map(|&i| r[i]), 0.05, 0.05);
    // The final model's effects where they fit beside the axis; else "final model" (the
    // effects are in the probability plot's legend and the summary).
    let after = format!("Residual, + {}", effects_after.replace(" then ", " + "));
    let after_label = if after.chars().count() <= 26 { after } else { "Residual, final model".to_string() };
    let mut panels = Vec::new();
    let cov = Table::load(dir, "covariates")?;
    let (cm, cc, ct) = (cov.s("material")?, cov.s("column")?, cov.s("type")?);
    let listed: Vec<(String, bool)> = (0..cm.len()).filter(|&i| cm[i] == key).map(|i| (cc[i].clone(), ct[i] == "categorical")).collect();
    for (name, categorical) in &listed {
        let name = name.as_str();
        if !t.has(name) {
            continue;
        }
        if *categorical {
            let v = t.s(name)?;
            let mut levels: Vec<String> = rows.iter().map(|&i| v[i].clone()).collect();
            levels.sort();
            levels.dedup();
            if levels.len() < 2 {
                continue;
            }
            for (si, st) in ["before", "after"].iter().enumerate() {
                let idx: Vec<usize> = rows.iter().copied().filter(|&i| stage[i] == *st).collect();
                let c = if si == 0 { GREY } else { colour(0) };
                let mut series = vec![Series { label: None, points: vec![(0.5, 0.0), (levels.len() as f64 + 0.5, 0.0)], colour: BLACK, kind: Kind::Dashed(0.6, 3.0, 2.0) }];
                let mut medians = Vec::new();
                for (k, l) in levels.iter().enumerate() {
                    let x = (k + 1) as f64;
                    let mut y: Vec<f64> = idx.iter().filter(|&&i| v[i] == *l).map(|&i| r[i]).collect();
                    y.sort_by(f64::total_cmp);
                    let q = crate::stats::interpolated_quantiles(y.clone(), &[0.1, 0.5, 0.9]);
                    series.push(Series { label: None, points: vec![(x - 0.25, q[0]), (x + 0.25, q[0])], colour: c, kind: Kind::Band(vec![q[2]; 2], 0.25) });
                    // Specimens spread across the level's width, in the order of their residual.
                    let m = y.len().max(1) as f64;
                    series.push(Series { label: None, points: y.iter().enumerate().map(|(j, yy)| (x - 0.2 + 0.4 * (j as f64 + 0.5) / m, *yy)).collect(), colour: c, kind: Kind::Markers(Marker::Circle, 1.2) });
                    medians.push((x, q[1]));
                }
                series.push(Series { label: None, points: medians, colour: if si == 0 { BLACK } else { colour(1) }, kind: Kind::Markers(Marker::Triangle, 2.6) });
                panels.push(Some(Panel {
                    x_categories: levels.clone(),
                    x_desc: level_axis(&name.replace('_', " ")),
                    y_desc: if si == 0 { "Residual, base model".into() } else { after_label.clone() },
                    x_range: (0.5, levels.len() as f64 + 0.5),
                    y_range,
                    y_log: false,
                    series,
                    legend: None,
                }));
            }
            continue;
        }
        let v = t.f(name)?;
        let vals: Vec<f64> = rows.iter().map(|&i| v[i]).collect();
        if vals.iter().any(|x| !x.is_finite()) || vals.iter().all(|x| *x == vals[0]) {
            continue;
        }
        let (label, factor) = covariate_axis(name);
        for (si, st) in ["before", "after"].iter().enumerate() {
            let idx: Vec<usize> = rows.iter().copied().filter(|&i| stage[i] == *st).collect();
            let x: Vec<f64> = idx.iter().map(|&i| v[i] * factor).collect();
            let y: Vec<f64> = idx.iter().map(|&i| r[i]).collect();
            let xr = padded(x.iter().copied(), 0.04, 0.04);
            let c = if si == 0 { GREY } else { colour(0) };
            panels.push(Some(Panel {
                x_categories: vec![],
                x_desc: label.clone(),
                y_desc: if si == 0 { "Residual, base model".into() } else { after_label.clone() },
                x_range: xr,
                y_range,
                y_log: false,
                series: vec![
                    Series { label: None, points: vec![(xr.0, 0.0), (xr.1, 0.0)], colour: BLACK, kind: Kind::Dashed(0.6, 3.0, 2.0) },
                    Series { label: None, points: x.iter().copied().zip(y.iter().copied()).collect(), colour: c, kind: Kind::Markers(Marker::Circle, 1.4) },
                    Series::line(None, binned(&x, &y, 5), if si == 0 { BLACK } else { colour(1) }, 1.3),
                ],
                legend: None,
            }));
        }
    }
    let rows_n = (panels.len() / 2).max(1);
    figure_grid(&format!("discrepancy_residuals_{key}"), 2.0 * width_cm, 0.3 * rows_n as f64, 2, &panels)
}

/// The x label of a categorical factor's residual panel: what the band and the triangle are,
/// shortened for a long column name so that the label fits the panel at 8.5 cm (the full form
/// cut off "down feed rate (level; band 10–90 %, triangle median)").
fn level_axis(name: &str) -> String {
    if name.chars().count() <= 9 { format!("{name} (level; band 10–90 %, triangle median)") } else { format!("{name} (10–90 % band, median)") }
}

/// Whether material `key` is crush data: unless materials.csv says it is a strength file (older
/// reports have no `data` column: crush).
fn is_crush(dir: &Path, key: &str) -> Result<bool> {
    Ok(match Table::load(dir, "materials") {
        Ok(m) if m.has("data") => {
            let (k, d) = (m.s("key")?, m.s("data")?);
            !(0..k.len()).any(|i| k[i] == key && d[i] == "strength")
        }
        _ => true,
    })
}

fn probability(dir: &Path, width_cm: f64, key: &str, label: &str, c: RGBColor) -> Result<Drawn> {
    let p = probability_panel(dir, key, label, c)?;
    figure(&format!("discrepancy_probability_{key}"), width_cm, 0.8, &[(p, 1.0)])
}

/// The Weibull probability plot of material `key`: each stage's strengths at their plotting
/// positions and its fitted line ln(−ln(1 − F)) = m (ln σ − ln σ_θ) — for a two-population law
/// its curve. The line spans exactly the x axis and the y axis holds both its ends, so nothing
/// of it is clipped and its drawn slope is the fitted m.
fn probability_panel(dir: &Path, key: &str, label: &str, c: RGBColor) -> Result<Panel> {
    let crush = is_crush(dir, key)?;
    let t = Table::load(dir, "residuals")?;
    let (mat, stage, raw, adj) = (t.s("material")?, t.s("stage")?, t.f("strength_pa")?, t.f("adjusted_pa")?);
    // What each row says and an interval's upper end (reports without censoring lack them).
    let observed = t.s("observed").ok();
    let (raw_up, adj_up) = (t.f("upper_pa").ok(), t.f("adjusted_upper_pa").ok());
    let kind_of = |i: usize| observed.as_ref().and_then(|o| crate::obs::Censor::parse(&o[i])).unwrap_or(crate::obs::Censor::Exact);
    let fits = Table::load(dir, "fits")?;
    let (fm, fs, fe, shape, scale) = (fits.s("material")?, fits.s("stage")?, fits.s("effects")?, fits.f("weibull_modulus")?, fits.f("scale_pa")?);
    // The final stage's modulus range (a modulus per level).
    let moduli = Table::load(dir, "stages").ok().filter(|t| t.has("weibull_modulus_min")).and_then(|t| {
        let (sm, lo, hi) = (t.s("material").ok()?, t.f("weibull_modulus_min").ok()?, t.f("weibull_modulus_max").ok()?);
        let last = (0..sm.len()).filter(|&i| sm[i] == key).last()?;
        Some((lo[last], hi[last]))
    });
    // A stage whose law is two flaw populations or a threshold (fits.csv `law`; older reports
    // lack it): (kind, mixture?, p, first, second, threshold γ or NaN).
    type Law = (String, bool, f64, (f64, f64), (f64, f64), f64);
    let law = |j: usize| -> Option<Law> {
        let kind = fits.s("law").ok()?.get(j)?.clone();
        let g = |c: &str| fits.f(c).ok().and_then(|v| v.get(j).copied());
        let mixture = match kind.as_str() {
            "mixture" => true,
            "competing_risks" => false,
            "threshold" => return Some((kind, false, 1.0, (g("law_scale1_pa")?, g("law_modulus1")?), (g("law_scale1_pa")?, g("law_modulus1")?), g("law_threshold_pa")?)),
            _ => return None,
        };
        Some((kind.replace('_', " "), mixture, g("law_weight")?, (g("law_scale1_pa")?, g("law_modulus1")?), (g("law_scale2_pa")?, g("law_modulus2")?), f64::NAN))
    };
    let mut series = Vec::new();
    let mut xs = Vec::new();
    let mut lines = Vec::new();
    let mut curves = Vec::new();
    // Censored points of each stage, drawn after both stages' breaks (the legend lists those first).
    let mut rings = Vec::new();
    // Each stage's breaks' marker series: (its index in `series`, its points).
    let mut markers: Vec<(usize, Vec<(f64, f64)>)> = Vec::new();
    for (si, st) in ["before", "after"].iter().enumerate() {
        // Plotting positions: C1239's (i − 0.5)/N, or Kaplan–Meier/Turnbull where rows are
        // censored (drawn as open circles).
        let rows: Vec<usize> = (0..mat.len()).filter(|&i| mat[i] == key && stage[i] == *st).collect();
        let v: Vec<f64> = rows.iter().map(|&i| if si == 0 { raw[i] } else { adj[i] } / 1e6).collect();
        let up: Vec<f64> = rows.iter().map(|&i| if si == 0 { raw_up.as_ref() } else { adj_up.as_ref() }.map_or(f64::NAN, |u| u[i] / 1e6)).collect();
        let kinds: Vec<crate::obs::Censor> = rows.iter().map(|&i| kind_of(i)).collect();
        let censoring = kinds.iter().any(|k| *k != crate::obs::Censor::Exact).then(|| crate::obs::Censoring { kind: kinds.clone(), upper: up, scheme: Default::default() });
        let positions = crate::weibull::probability_plot_observed(crate::obs::Obs { x: &v, censoring: censoring.as_ref() });
        let at = |p: &crate::weibull::PlotPoint| (p.x.ln(), (-(-p.f).ln_1p()).ln());
        let pts: Vec<(f64, f64)> = positions.iter().filter(|p| p.kind == crate::obs::Censor::Exact && p.f < 1.0).map(at).collect();
        let open: Vec<(f64, f64)> = positions.iter().filter(|p| p.kind != crate::obs::Censor::Exact && p.f > 0.0 && p.f < 1.0).map(at).collect();
        let open_kinds: Vec<crate::obs::Censor> = positions.iter().filter(|p| p.kind != crate::obs::Censor::Exact).map(|p| p.kind).collect();
        xs.extend(pts.iter().chain(&open).map(|p| p.0));
        if !open.is_empty() {
            let colour_st = if si == 0 { GREY } else { c };
            rings.push(Series { label: Some(format!("{}: {}", if si == 0 { "base" } else { "final" }, super::censored_words(open_kinds.into_iter()))), points: open, colour: colour_st, kind: Kind::Markers(Marker::Ring, 2.8) });
        }
        let Some(j) = (0..fm.len()).find(|&i| fm[i] == key && fs[i] == *st) else { continue };
        let (m, s) = (shape[j], (scale[j] / 1e6).ln());
        if pts.is_empty() {
            xs.extend([s - 0.3, s + 0.3]);
        }
        let colour_st = if si == 0 { GREY } else { c };
        let name = if si == 0 { "base model".to_string() } else { format!("+ {}", fe[j].replace(" then ", " + ")) };
        // With a modulus per level the line is the reference level's (the adjusted points are
        // carried onto it): say so, with the range by level (stages.csv; older reports lack it).
        // A two-population law is drawn as its curve ln(−ln(1 − F(x))), not a line.
        // The stage's legend entry goes on its breaks' markers, or, where it has none (every row
        // censored or a class), on its line: no entry for a marker that is not drawn.
        let on_line = pts.is_empty();
        markers.push((series.len(), pts.clone()));
        let marker = |label: String, pts: Vec<(f64, f64)>| Series { label: (!on_line).then_some(label), points: pts, colour: colour_st, kind: Kind::Markers(if si == 0 { Marker::Cross } else { Marker::Circle }, 1.6) };
        if let Some(l) = law(j) {
            let label = if l.5.is_nan() { format!("final: {}, m = {:.1} and {:.1}", l.0, l.3.1.min(l.4.1), l.3.1.max(l.4.1)) } else { format!("final: threshold {:.1} MPa, m = {:.1}", l.5 / 1e6, l.3.1) };
            series.push(marker(label.clone(), pts));
            curves.push((l, colour_st, label, on_line));
            continue;
        }
        let label = match moduli.filter(|(lo, hi)| si == 1 && hi > lo) {
            Some((lo, hi)) => format!("final model: m = {lo:.1}–{hi:.1}, line at {m:.1}"),
            None => format!("{name}: m = {m:.1}"),
        };
        series.push(marker(label.clone(), pts));
        lines.push((m, s, colour_st, label, on_line));
    }
    // Where no effect moves the breaks (the same positions before and after), one set of
    // markers, said to be both — the base's would hide under the final's — and each stage's
    // legend entry on its line.
    let merged = markers.len() == 2 && !markers[0].1.is_empty() && markers[0].1 == markers[1].1;
    if merged {
        series[markers[1].0].label = Some("strengths: base and final alike".into());
        series.remove(markers[0].0);
    }
    // Where no effect moves the censored points (the same positions before and after), one set
    // of rings, said to be both: the base's would hide under the final's.
    if rings.len() == 2 && rings[0].points == rings[1].points {
        let base = rings.remove(0);
        let words = base.label.as_deref().and_then(|l| l.strip_prefix("base: ")).unwrap_or("censored").to_string();
        rings[0].label = Some(format!("base and final alike: {words}"));
    }
    series.extend(rings);
    let xr = padded(xs.iter().copied(), 0.05, 0.05);
    for (m, s, colour_st, label, on_line) in lines {
        series.push(Series::line((on_line || merged).then_some(label), vec![(xr.0, m * (xr.0 - s)), (xr.1, m * (xr.1 - s))], colour_st, 1.0));
    }
    for (l, colour_st, label, on_line) in curves {
        let pts: Vec<(f64, f64)> = (0..=200)
            .map(|k| xr.0 + (xr.1 - xr.0) * k as f64 / 200.0)
            .map(|lx| (lx, if l.5.is_nan() { crate::weibull::two_population_cdf(l.1, l.2, l.3, l.4, lx.exp() * 1e6) } else { crate::weibull::threshold_cdf(l.5, l.3, lx.exp() * 1e6) }))
            .map(|(lx, f)| (lx, (-(-f).ln_1p()).ln()))
            .filter(|p| p.1.is_finite())
            .collect();
        series.push(Series::line((on_line || merged).then_some(label), pts, colour_st, 1.0));
    }
    Ok(Panel {
        x_categories: vec![],
        // A strength file's values are specimen strengths, not the Hertz σ̄ of a crush test.
        x_desc: if crush { format!("ln(σ̄ at break / 1 MPa), {label}") } else { "ln(specimen strength / 1 MPa)".into() },
        y_desc: "ln(−ln(1 − F))".into(),
        x_range: xr,
        y_range: padded(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)), 0.05, 0.05),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperLeft),
    })
}

/// The probability plot by failure origin (ASTM C1239's figure for concurrent flaw
/// populations): each origin's breaks at their Kaplan–Meier positions with the other origins'
/// breaks censored, as its law is fitted, and its fitted line; a class or a break at or below a
/// value of its own origin is not drawn (it has no single strength), only counted in its fit.
fn by_origin(dir: &Path, width_cm: f64, key: &str, o: &Table) -> Result<Drawn> {
    let t = Table::load(dir, "residuals")?;
    let (mat, stage, raw, observed, origin) = (t.s("material")?, t.s("stage")?, t.f("strength_pa")?, t.s("observed")?, t.s("failure_origin")?);
    let up = t.f("upper_pa")?;
    let rows: Vec<usize> = (0..mat.len()).filter(|&i| mat[i] == key && stage[i] == "before").collect();
    let x: Vec<f64> = rows.iter().map(|&i| raw[i] / 1e6).collect();
    let kind: Vec<crate::obs::Censor> = rows.iter().map(|&i| crate::obs::Censor::parse(&observed[i]).unwrap_or(crate::obs::Censor::Exact)).collect();
    let censoring = crate::obs::Censoring { kind, upper: rows.iter().map(|&i| up[i] / 1e6).collect(), scheme: Default::default() };
    let obs = crate::obs::Obs { x: &x, censoring: Some(&censoring) };
    let labels: Vec<String> = rows.iter().map(|&i| origin[i].clone()).collect();
    let (om, oo, breaks, shape, scale) = (o.s("material")?, o.s("origin")?, o.f("breaks")?, o.f("weibull_modulus")?, o.f("scale_pa")?);
    let mut series = Vec::new();
    let mut lines = Vec::new();
    let mut xs: Vec<f64> = Vec::new();
    for (j, i) in (0..om.len()).filter(|&i| om[i] == key).enumerate() {
        let (mine, _) = obs.of_origin(&labels, &oo[i]);
        let pts: Vec<(f64, f64)> = crate::weibull::probability_plot_observed(mine.view())
            .into_iter()
            .filter(|p| p.kind == crate::obs::Censor::Exact && p.f > 0.0 && p.f < 1.0)
            .map(|p| (p.x.ln(), (-(-p.f).ln_1p()).ln()))
            .collect();
        xs.extend(pts.iter().map(|p| p.0));
        let c = colour(j);
        let marker = [Marker::Circle, Marker::Triangle, Marker::Cross][j % 3];
        if shape[i].is_finite() {
            let label = format!("{}: {} breaks, m = {:.1}, σθ = {:.0} MPa", oo[i], breaks[i], shape[i], scale[i] / 1e6);
            series.push(Series { label: Some(label), points: pts, colour: c, kind: Kind::Markers(marker, 2.0) });
            lines.push((shape[i], (scale[i] / 1e6).ln(), c));
        } else {
            series.push(Series { label: Some(format!("{}: {} break{}, no law", oo[i], breaks[i], if breaks[i] == 1.0 { "" } else { "s" })), points: pts, colour: c, kind: Kind::Markers(marker, 2.0) });
        }
    }
    let xr = padded(xs.iter().copied(), 0.05, 0.05);
    for (m, s, c) in lines {
        series.push(Series::line(None, vec![(xr.0, m * (xr.0 - s)), (xr.1, m * (xr.1 - s))], c, 1.0));
    }
    let crush = is_crush(dir, key)?;
    let p = Panel {
        x_categories: vec![],
        x_desc: if crush { "ln(σ̄ at break / 1 MPa)".into() } else { "ln(specimen strength / 1 MPa)".into() },
        y_desc: "ln(−ln(1 − F)), other origins censored".into(),
        x_range: xr,
        y_range: padded(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)), 0.05, 0.05),
        y_log: false,
        series: series.iter().map(|s| Series { label: None, ..s.clone() }).collect(),
        legend: None,
    };
    // The legend below the plot, one origin a line: with three or more origins a legend inside
    // covered points wherever it went.
    let entries: Vec<Series> = series.into_iter().filter(|s| s.label.is_some()).collect();
    figure_legend_below(&format!("discrepancy_origins_{key}"), width_cm, 0.8 + 0.045 * entries.len() as f64, &[(p, 1.0)], &entries, 1)
}

fn gap(dir: &Path, width_cm: f64, keys: &[String], labels: &[String]) -> Result<Drawn> {
    let t = Table::load(dir, "stages")?;
    // The expectation with nothing missing per round (the bootstrap's mean G; reports written
    // before it was a column: the number of findings, Σ df when every covariate is numeric).
    let (mat, round, g, ncov) = (t.s("material")?, t.f("round")?, t.f("gap")?, t.f("gap_expected").or_else(|_| t.f("covariates_diagnosed"))?);
    let mut series = Vec::new();
    let mut max_round: f64 = 0.0;
    for (k, key) in keys.iter().enumerate() {
        let rows: Vec<usize> = (0..mat.len()).filter(|&i| &mat[i] == key).collect();
        let pts: Vec<(f64, f64)> = rows.iter().map(|&i| (round[i] + 1.0, g[i])).collect();
        max_round = max_round.max(rows.iter().map(|&i| round[i]).fold(0.0, f64::max));
        series.push(Series::line(Some(labels[k].clone()), pts.clone(), colour(k), 1.2));
        series.push(Series { label: None, points: pts, colour: colour(k), kind: Kind::Markers([Marker::Circle, Marker::Triangle, Marker::Cross][k % 3], 2.0) });
        // Each round's expectation when nothing is missing (the bootstrap's mean G: it falls as
        // fitted effects take their terms), joined across the rounds.
        let expected: Vec<(f64, f64)> = rows.iter().filter(|&&i| ncov[i].is_finite()).map(|&i| (round[i] + 1.0, ncov[i])).collect();
        match expected.as_slice() {
            [] => {}
            [(_, e)] => series.push(Series { label: Some(format!("{}: nothing missing (≈ {e:.1})", labels[k])), points: vec![(0.7, *e), (max_round + 1.3, *e)], colour: colour(k), kind: Kind::Dashed(0.8, 3.0, 2.0) }),
            _ => series.push(Series { label: Some(format!("{}: nothing missing", labels[k])), points: expected, colour: colour(k), kind: Kind::Dashed(0.8, 3.0, 2.0) }),
        }
    }
    let cats: Vec<String> = (0..=max_round as usize).map(|r| if r == 0 { "base".into() } else { format!("+{r} effect{}", if r > 1 { "s" } else { "" }) }).collect();
    let p = Panel {
        x_categories: cats,
        x_desc: "Model (effects added by the workflow)".into(),
        y_desc: "Gap G = n Σρ² + Σ H (–)".into(),
        x_range: (0.6, max_round + 1.4),
        y_range: (0.0, g.iter().copied().fold(0.0, f64::max) * 1.45 + 1.0),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    figure("discrepancy_gap", width_cm, 0.75, &[(p, 1.0)])
}

/// The evidence figure's candidates on one material's axis (those fitted, in evidence.csv
/// order) and whether they are numbered 1, 2, … because their names would overlap under the
/// axis (the caption then gives the numbers' names).
pub fn evidence_axis(fitted: &[String]) -> (Vec<String>, bool) {
    let cats = distinct(fitted);
    let numbered = cats.iter().map(|c| c.chars().count() + 2).sum::<usize>() > 48;
    (cats, numbered)
}

fn evidence(dir: &Path, width_cm: f64, keys: &[String], labels: &[String]) -> Result<Drawn> {
    let t = Table::load(dir, "evidence")?;
    let (mat, round, cand, skipped, lr, crit) = (t.s("material")?, t.f("round")?, t.s("candidate")?, t.s("skipped")?, t.f("likelihood_ratio")?, t.f("likelihood_ratio_critical")?);
    let mut panels = Vec::new();
    for (k, key) in keys.iter().enumerate() {
        let rows: Vec<usize> = (0..mat.len()).filter(|&i| &mat[i] == key && skipped[i].is_empty()).collect();
        let (cats, numbered) = evidence_axis(&rows.iter().map(|&i| cand[i].clone()).collect::<Vec<_>>());
        let rounds = rows.iter().map(|&i| round[i] as usize).max().map_or(0, |r| r + 1);
        let mut series = Vec::new();
        for r in 0..rounds {
            let idx: Vec<usize> = rows.iter().copied().filter(|&i| round[i] as usize == r).collect();
            let off = 0.12 * (r as f64 - 0.5 * (rounds as f64 - 1.0));
            let pts: Vec<(f64, f64)> = idx.iter().map(|&i| (cats.iter().position(|c| *c == cand[i]).unwrap_or(0) as f64 + 1.0 + off, lr[i])).collect();
            let c = colour(r);
            // Rounds numbered from 0 as in evidence.csv, the summary and the caption.
            series.push(Series { label: Some(format!("round {r} Λ")), points: pts, colour: c, kind: Kind::Markers([Marker::Circle, Marker::Triangle, Marker::Cross][r % 3], 2.2) });
            // Each candidate's critical Λ (its own degrees of freedom) as a dash across its slot.
            for (j, &i) in idx.iter().enumerate() {
                let x = cats.iter().position(|c| *c == cand[i]).unwrap_or(0) as f64 + 1.0;
                let label = (j == 0).then(|| format!("round {r} critical"));
                series.push(Series { label, points: vec![(x - 0.4, crit[i]), (x + 0.4, crit[i])], colour: c, kind: Kind::Dashed(0.8, 3.0, 2.0) });
            }
        }
        // The axis holds every Λ and every critical value (a small Λ under a larger critical
        // value would put the critical dash on the frame, where it reads as the axis' top).
        let top = rows.iter().flat_map(|&i| [lr[i], crit[i]]).filter(|v| v.is_finite()).fold(1.0, f64::max);
        panels.push((
            Panel {
                x_categories: if numbered { (1..=cats.len()).map(|j| j.to_string()).collect() } else { cats.clone() },
                x_desc: match (k + 1 == keys.len(), numbered) {
                    (false, _) => String::new(),
                    (true, false) => "Candidate effect".into(),
                    (true, true) => "Candidate (numbered: see the caption)".into(),
                },
                // A long label does not fit beside the axis: the key then (the legend of the
                // other figures and materials.csv give the label).
                y_desc: format!("Λ, {}", if labels[k].chars().count() <= 18 { labels[k].as_str() } else { key.as_str() }),
                x_range: (0.5, cats.len() as f64 + 0.5),
                y_range: (0.0, top * 1.6),
                y_log: false,
                series,
                legend: Some(SeriesLabelPosition::UpperRight),
            },
            1.0 / keys.len() as f64,
        ));
    }
    figure("discrepancy_evidence", width_cm, 0.6 * keys.len() as f64, &panels)
}

fn lifetime(dir: &Path, width_cm: f64, keys: &[String], labels: &[String]) -> Result<Drawn> {
    let t = Table::load(dir, "lifetime")?;
    let (mat, stage, years, p, q05, q95) = (t.s("material")?, t.s("stage")?, t.f("years")?, t.f("p_break")?, t.f("q05")?, t.f("q95")?);
    let horizons = distinct(&years);
    let mut panels = Vec::new();
    for (hi, h) in horizons.iter().enumerate() {
        let mut series = Vec::new();
        let mut ys = Vec::new();
        // With known failure origins (a third stage) the three bands sit side by side.
        let known = stage.iter().any(|st| st == "origins");
        for (si, st) in ["before", "after", "origins"].iter().enumerate().take(if known { 3 } else { 2 }) {
            let c = [GREY, colour(0), colour(1)][si];
            let off = if known { [-0.18, 0.0, 0.18][si] } else { [-0.12, 0.12][si] };
            let mut pts = Vec::new();
            for (k, key) in keys.iter().enumerate() {
                if let Some(i) = (0..mat.len()).find(|&i| &mat[i] == key && stage[i] == *st && years[i] == *h) {
                    let x = k as f64 + 1.0 + off;
                    pts.push((x, lg(p[i])));
                    series.push(Series::line(None, vec![(x, lg(q05[i])), (x, lg(q95[i]))], c, 1.2));
                    ys.extend([lg(q05[i]), lg(q95[i]), lg(p[i])]);
                }
            }
            let label = ["base model, 90 % band", "with the named effects", "known origins, each its own law"][si];
            series.push(Series { label: Some(label.into()), points: pts, colour: c, kind: Kind::Markers([Marker::Cross, Marker::Circle, Marker::Triangle][si], 2.2) });
        }
        let (lo, top) = padded(ys.iter().copied(), 0.1, 0.6);
        panels.push((
            Panel {
                x_categories: labels.to_vec(),
                x_desc: if hi + 1 == horizons.len() { "Material".into() } else { String::new() },
                y_desc: format!("P break, {h} yr"),
                x_range: (0.5, keys.len() as f64 + 0.5),
                y_range: (lo.floor(), top.min(0.3).max(lo.floor() + 1.0)),
                y_log: true,
                series,
                legend: if hi == 0 { Some(SeriesLabelPosition::LowerRight) } else { None },
            },
            1.0 / horizons.len() as f64,
        ));
    }
    figure("discrepancy_lifetime", width_cm, 0.55 * horizons.len() as f64, &panels)
}

fn power(dir: &Path, width_cm: f64, keys: &[String], labels: &[String]) -> Result<Drawn> {
    let t = Table::load(dir, "power")?;
    let (mat, scen, eff, n, all, lo, hi) = (t.s("material")?, t.s("scenario")?, t.s("effects")?, t.f("particles")?, t.f("rate_all")?, t.f("rate_all_lo90")?, t.f("rate_all_hi90")?);
    let mut series = Vec::new();
    for (k, key) in keys.iter().enumerate() {
        for sc in ["effects", "none"] {
            let rows: Vec<usize> = (0..mat.len()).filter(|&i| &mat[i] == key && scen[i] == sc).collect();
            if rows.is_empty() {
                continue;
            }
            let pts: Vec<(f64, f64)> = rows.iter().map(|&i| (n[i], all[i])).collect();
            if sc == "effects" {
                series.push(Series { label: None, points: rows.iter().map(|&i| (n[i], lo[i])).collect(), colour: colour(k), kind: Kind::Band(rows.iter().map(|&i| hi[i]).collect(), 0.18) });
                series.push(Series::line(Some(format!("{}: {} found", labels[k], eff[rows[0]].replace(" then ", " + "))), pts.clone(), colour(k), 1.3));
                series.push(Series { label: None, points: pts, colour: colour(k), kind: Kind::Markers(Marker::Circle, 2.0) });
            } else {
                series.push(Series { label: Some(format!("{}: false positives", labels[k])), points: pts.clone(), colour: colour(k), kind: Kind::Dashed(1.0, 3.0, 2.0) });
                series.push(Series { label: None, points: pts, colour: colour(k), kind: Kind::Markers(Marker::Cross, 2.0) });
            }
        }
    }
    let xr = padded(n.iter().copied(), 0.04, 0.04);
    series.push(Series { label: Some("5 % guard level".into()), points: vec![(xr.0, 0.05), (xr.1, 0.05)], colour: BLACK, kind: Kind::Dashed(0.6, 1.0, 1.5) });
    let p = Panel {
        x_categories: vec![],
        x_desc: "Crush tests per material (particles)".into(),
        y_desc: "Rate over synthetic datasets (–)".into(),
        x_range: xr,
        y_range: (0.0, 1.05),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::MiddleRight),
    };
    figure("discrepancy_power", width_cm, 0.85, &[(p, 1.0)])
}

/// Draws the figure of a curve-level discrepancy report (`kind = "discrepancy_curves"`):
/// `discrepancy_curves` — top, the measured mean curves (markers, ±σ) with the calibrated model
/// before (grey, dashed) and after the named terms (colour); bottom, the posterior mean of δ
/// with its 90 % band, before (grey) and after (colour). From `curve_points.csv` only.
pub fn render_curves(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let t = Table::load(dir, "curve_points")?;
    let (file, x, y, sig) = (t.s("file")?, t.f("displacement_m")?, t.f("force_mean_n")?, t.f("sigma_n")?);
    let (mb, ma) = (t.f("model_before_n")?, t.f("model_after_n")?);
    let (db, dbs, da, das) = (t.f("delta_before_n")?, t.f("delta_sd_before_n")?, t.f("delta_after_n")?, t.f("delta_sd_after_n")?);
    let ev = Table::load(dir, "curve_evidence")?;
    let named: Vec<String> = {
        let (c, n) = (ev.s("candidate")?, ev.s("named")?);
        (0..c.len()).filter(|&i| n[i] == "yes").map(|i| c[i].clone()).collect()
    };
    let after = if named.is_empty() { "no term named".to_string() } else { format!("+ {}", named.join(" + ")) };
    let files = distinct(&file);
    let um = |v: f64| v * 1e6;
    let (mut top, mut bottom) = (Vec::new(), Vec::new());
    for (g, name) in files.iter().enumerate() {
        let rows: Vec<usize> = (0..file.len()).filter(|&i| &file[i] == name).collect();
        let c = colour(g);
        let first = g == 0;
        for &i in &rows {
            top.push(Series::line(None, vec![(um(x[i]), y[i] - sig[i]), (um(x[i]), y[i] + sig[i])], c, 0.8));
        }
        top.push(Series { label: Some(format!("{name}: measured")), points: rows.iter().map(|&i| (um(x[i]), y[i])).collect(), colour: c, kind: Kind::Markers([Marker::Circle, Marker::Triangle, Marker::Cross][g % 3], 2.0) });
        top.push(Series { label: first.then(|| "calibrated FE (no term)".to_string()), points: rows.iter().map(|&i| (um(x[i]), mb[i])).collect(), colour: GREY, kind: Kind::Dashed(1.0, 3.0, 2.0) });
        top.push(Series::line(Some(format!("{name}: FE {after}")), rows.iter().map(|&i| (um(x[i]), ma[i])).collect(), c, 1.2));
        bottom.push(Series { label: None, points: rows.iter().map(|&i| (um(x[i]), db[i] - 1.645 * dbs[i])).collect(), colour: GREY, kind: Kind::Band(rows.iter().map(|&i| db[i] + 1.645 * dbs[i]).collect(), 0.25) });
        bottom.push(Series { label: first.then(|| "δ, calibrated FE (90 %)".to_string()), points: rows.iter().map(|&i| (um(x[i]), db[i])).collect(), colour: GREY, kind: Kind::Dashed(1.0, 3.0, 2.0) });
        bottom.push(Series { label: None, points: rows.iter().map(|&i| (um(x[i]), da[i] - 1.645 * das[i])).collect(), colour: c, kind: Kind::Band(rows.iter().map(|&i| da[i] + 1.645 * das[i]).collect(), 0.25) });
        bottom.push(Series::line(Some(format!("δ, {name} {after}")), rows.iter().map(|&i| (um(x[i]), da[i])).collect(), c, 1.2));
    }
    let xr = (0.0, x.iter().copied().fold(0.0, f64::max) * 1e6 * 1.05);
    let ytop = y.iter().zip(&sig).map(|(a, s)| a + s).chain(mb.iter().copied()).chain(ma.iter().copied()).fold(0.0, f64::max);
    let dvals: Vec<f64> = (0..x.len()).flat_map(|i| [db[i] - 1.645 * dbs[i], db[i] + 1.645 * dbs[i], da[i] - 1.645 * das[i], da[i] + 1.645 * das[i], 0.0]).collect();
    let panels = vec![
        (
            Panel {
                x_categories: vec![],
                x_desc: String::new(),
                y_desc: "Force at D₀ (N)".into(),
                x_range: xr,
                // Headroom for the legend: the curves rise to the upper right, under it.
                y_range: (0.0, ytop * 1.75),
                y_log: false,
                series: top,
                legend: Some(SeriesLabelPosition::UpperLeft),
            },
            0.55,
        ),
        (
            Panel {
                x_categories: vec![],
                x_desc: "Total displacement at D₀ (µm)".into(),
                y_desc: "Discrepancy δ (N)".into(),
                x_range: xr,
                y_range: padded(dvals, 0.08, 0.8),
                y_log: false,
                series: bottom,
                legend: Some(SeriesLabelPosition::UpperLeft),
            },
            0.45,
        ),
    ];
    let drawn = figure("discrepancy_curves", width_cm, 1.25, &panels)?;
    super::write_figures(dir, vec![("discrepancy_curves", drawn)])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fitted line of the Weibull probability plot is drawn with the fitted modulus as its
    /// slope: both ends inside the axes (nothing clipped), for moduli from 3 to 40. Before, the
    /// line ran 0.05 in ln σ past the data, beyond a narrow x axis, and a clipped x with an
    /// unclipped y drew m = 26 with a slope of about 38.
    #[test]
    fn the_probability_line_has_the_fitted_slope_for_any_modulus() {
        for m in [3.0, 5.0, 8.0, 12.0, 20.0, 26.3, 40.0] {
            let dir = crate::io::TempDir::new("probability").unwrap();
            let n = 30;
            let mut residuals = String::from("material,stage,strength_pa,adjusted_pa\n");
            for stage in ["before", "after"] {
                for i in 0..n {
                    let f = (i as f64 + 0.5) / n as f64;
                    let x = 1.2e9 * (-(1.0 - f).ln()).powf(1.0 / m);
                    residuals.push_str(&format!("bl,{stage},{x},{}\n", 0.97 * x));
                }
            }
            std::fs::write(dir.path().join("residuals.csv"), residuals).unwrap();
            std::fs::write(dir.path().join("fits.csv"), format!("material,stage,effects,weibull_modulus,scale_pa\nbl,before,none,{m},1.2e9\nbl,after,size,{},1.16e9\n", m * 1.1)).unwrap();
            let p = probability_panel(dir.path(), "bl", "BL", BLACK).unwrap();
            let lines: Vec<&Series> = p.series.iter().filter(|s| matches!(s.kind, Kind::Line(_))).collect();
            assert_eq!(lines.len(), 2, "m = {m}");
            for (line, fitted) in lines.iter().zip([m, m * 1.1]) {
                let [(x0, y0), (x1, y1)] = line.points[..] else { panic!("a line of two points") };
                for (x, y) in [(x0, y0), (x1, y1)] {
                    assert!(x >= p.x_range.0 && x <= p.x_range.1 && y >= p.y_range.0 && y <= p.y_range.1, "m = {m}: ({x}, {y}) outside {:?} × {:?}", p.x_range, p.y_range);
                }
                assert!(((y1 - y0) / (x1 - x0) / fitted - 1.0).abs() < 1e-12, "m = {m}: slope {}", (y1 - y0) / (x1 - x0));
            }
            // Every point lies inside the axes too.
            assert!(p.series.iter().flat_map(|s| &s.points).all(|&(x, y)| x >= p.x_range.0 && x <= p.x_range.1 && y >= p.y_range.0 && y <= p.y_range.1));
        }
    }
}

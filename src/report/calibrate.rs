//! Figures of a calibration report (`kind = "calibrate"`), drawn from the report's tables only.
//!
//! | file stem | content | table(s) |
//! |---|---|---|
//! | `calibration_fit` | crush: measured curves (normalised to D₀), FE curves at posterior draws and at the estimate, the 90 % posterior-predictive band of the grid forces and of the peak (Fig. 6b style); other models: observations against their 90 % predictive intervals | `curves.csv`, `grid.csv`, `observations.csv` |
//! | `calibration_residuals` | standardised residuals (d − median)/σ with the 90 % predictive band | `observations.csv` |
//! | `calibration_corner` | posterior pair plot: histograms, pairwise draws | `chains.csv`, `parameters.csv` |
//! | `calibration_trace` | traces of four walkers per parameter | `chains.csv` |
//! | `calibration_comparison` | (with `[compare]`) parameter table, reference vs this calibration, the change coloured by size (Fig. 7 style) | `comparison.csv` |
//!
//! Parameters in Pa are drawn in GPa.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{Encoded, canvas_size, colour, encode, fig_err, register_fonts, text};
use super::panel::{Kind, Marker, Panel, Series, figure, figure_grid, figure_legend_below, padded};
use super::{Rendered, Table};
use crate::error::Result;

type Drawn = (Encoded, usize);

/// Draws every calibration figure in `dir`.
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let mut figures: Vec<super::Figure<Drawn>> = vec![
        ("calibration_fit", Box::new(|| fit(dir, width_cm))),
        ("calibration_residuals", Box::new(|| residuals(dir, width_cm))),
        ("calibration_corner", Box::new(|| corner(dir, 2.0 * width_cm))),
        ("calibration_trace", Box::new(|| trace(dir, width_cm))),
    ];
    if dir.join("comparison.csv").is_file() {
        figures.push(("calibration_comparison", Box::new(|| comparison(dir, 2.0 * width_cm))));
    }
    super::write_figures(dir, super::draw_all(figures)?)
}

/// Display scale and unit of a parameter (Pa → GPa).
fn display(unit: &str) -> (f64, String) {
    if unit == "Pa" { (1e-9, "GPa".into()) } else { (1.0, unit.to_string()) }
}

fn axis_label(name: &str, unit: &str) -> String {
    let (_, u) = display(unit);
    if u == "-" || u.is_empty() { name.to_string() } else { format!("{name} ({u})") }
}

fn fit(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let obs = Table::load(dir, "observations")?;
    if !dir.join("curves.csv").is_file() {
        return observations_fit(&obs, width_cm);
    }
    let c = Table::load(dir, "curves")?;
    let (kind, x, f) = (c.s("kind")?, c.f("displacement_m")?, c.f("force_n")?);
    let gt = Table::load(dir, "grid")?;
    let (grid, d0) = (gt.f("grid_displacement_m")?, gt.f("reference_diameter_m")?[0]);
    let k = grid.len();
    let (oi, q05, q50, q95, val, grp) = (obs.f("output_index")?, obs.f("predictive_q05")?, obs.f("predictive_q50")?, obs.f("predictive_q95")?, obs.f("value")?, obs.f("group")?);
    let first = |o: usize| oi.iter().position(|&v| v as usize == o);
    let mut series = Vec::new();
    // Band over the grid forces (first observation of each grid output).
    let mut lower = vec![(0.0, 0.0)];
    let mut upper = vec![0.0];
    for (o, &g) in grid.iter().enumerate() {
        if let Some(i) = first(o) {
            lower.push((1e6 * g, q05[i]));
            upper.push(q95[i]);
        }
    }
    series.push(Series { label: Some("90 % posterior predictive".into()), points: lower, colour: colour(0), kind: Kind::Band(upper, 0.25) });
    let mut first_data = true;
    let mut first_draw = true;
    for (_, idx) in c.groups_by("id")? {
        let pts: Vec<(f64, f64)> = idx.iter().map(|&i| (1e6 * x[i], f[i])).collect();
        match kind[idx[0]].as_str() {
            "data" => {
                series.push(Series::line(first_data.then(|| format!("measured, D₀ = {:.0} µm", d0 * 1e6)), pts, RGBColor(150, 150, 150), 0.6));
                first_data = false;
            }
            "posterior_draw" => {
                series.push(Series::line(first_draw.then(|| "FE at posterior draws".to_string()), pts, colour(0), 0.5));
                first_draw = false;
            }
            _ => {
                series.push(Series { label: Some("FE at least-squares estimate".into()), points: pts, colour: BLACK, kind: Kind::Dashed(0.9, 3.0, 2.0) });
            }
        }
    }
    // Peak: measured (fracture displacement, peak force) pairs; predictive 90 % cross.
    let mut peaks = Vec::new();
    for (i, &o) in oi.iter().enumerate() {
        if o as usize == k
            && let Some(j) = (0..oi.len()).find(|&j| oi[j] as usize == k + 1 && grp[j] == grp[i])
        {
            peaks.push((1e6 * val[j], val[i]));
        }
    }
    series.push(Series { label: Some("measured fracture point".into()), points: peaks, colour: colour(1), kind: Kind::Markers(Marker::Circle, 1.8) });
    if let (Some(ip), Some(ix)) = (first(k), first(k + 1)) {
        let (xm, ym) = (1e6 * q50[ix], q50[ip]);
        series.push(Series::line(Some("90 % predictive peak".into()), vec![(xm, q05[ip]), (xm, q95[ip])], colour(1), 1.2));
        series.push(Series::line(None, vec![(1e6 * q05[ix], ym), (1e6 * q95[ix], ym)], colour(1), 1.2));
    }
    let xmax = x.iter().cloned().fold(0.0, f64::max) * 1e6;
    // Everything drawn fits: curves, points, the cross and the band's upper edge.
    let band_top = series.iter().flat_map(|s| match &s.kind {
        Kind::Band(upper, _) => upper.clone(),
        _ => vec![],
    });
    let ymax = series.iter().flat_map(|s| s.points.iter().map(|p| p.1)).chain(band_top).fold(0.0, f64::max);
    // Up to six entries: the legend below the axes (an inner one hid curves and points whatever the
    // corner), in two columns.
    let entries: Vec<Series> = series.iter().filter(|s| s.label.is_some()).map(|s| Series { points: vec![], ..s.clone() }).collect();
    let panel = Panel {
        x_categories: vec![],
        x_desc: "Total crush displacement δ·D₀/D (µm)".into(),
        y_desc: "Platen force F·(D₀/D)² (N)".into(),
        x_range: (0.0, xmax * 1.02),
        y_range: (0.0, ymax * 1.05),
        y_log: false,
        series,
        legend: None,
    };
    figure_legend_below("calibration_fit", width_cm, 0.8 + 0.035 * entries.len().div_ceil(2) as f64, &[(panel, 1.0)], &entries, 2)
}

/// Any model: each observation against its 90 % predictive interval. Velocity-profile outputs
/// `vz_at_<h>mm` are drawn against height (a box per sampled height: the profile between the
/// heights is not known), the other outputs below as ratios to their predictive median.
fn observations_fit(obs: &Table, width_cm: f64) -> Result<Drawn> {
    let (val, q05, q50, q95) = (obs.f("value")?, obs.f("predictive_q05")?, obs.f("predictive_q50")?, obs.f("predictive_q95")?);
    let names = obs.s("output")?;
    let mut prof = Vec::new();
    let mut rest = Vec::new();
    for (i, n) in names.iter().enumerate() {
        match n.strip_prefix("vz_at_").and_then(|r| r.strip_suffix("mm")).and_then(|h| h.parse::<f64>().ok()) {
            Some(h) => prof.push((h, i)),
            None => rest.push(i),
        }
    }
    if prof.len() < 2 {
        return figure("calibration_fit", width_cm, 0.75, &[(ratio_panel(&names, &rest.iter().chain(prof.iter().map(|p| &p.1)).copied().collect::<Vec<_>>(), &val, &q05, &q50, &q95, Some(SeriesLabelPosition::UpperRight)), 1.0)]);
    }
    prof.sort_by(|a, b| a.0.total_cmp(&b.0));
    let span = prof.last().map(|p| p.0).unwrap_or(1.0) - prof[0].0;
    let half = (0.015 * span).max(0.5);
    let mut series = Vec::new();
    for (k, &(h, i)) in prof.iter().enumerate() {
        let label = |s: &str| if k == 0 { Some(s.to_string()) } else { None };
        series.push(Series { label: label("90 % posterior predictive"), points: vec![(h - half, q05[i]), (h + half, q05[i])], colour: colour(0), kind: Kind::Band(vec![q95[i]; 2], 0.3) });
        series.push(Series::line(label("predictive median"), vec![(h - half, q50[i]), (h + half, q50[i])], colour(0), 1.0));
    }
    series.push(Series { label: Some("measured".into()), points: prof.iter().map(|&(h, i)| (h, val[i])).collect(), colour: colour(1), kind: Kind::Markers(Marker::Circle, 1.8) });
    let ys: Vec<f64> = prof.iter().flat_map(|&(_, i)| [q05[i], q95[i], val[i]]).collect();
    let profile = Panel {
        x_categories: vec![],
        x_desc: "Height above the outlet (mm)".into(),
        y_desc: "Mean vertical velocity (m/s)".into(),
        x_range: padded(prof.iter().map(|p| p.0), 0.05, 0.05),
        y_range: padded(ys, 0.1, 0.45),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    if rest.is_empty() {
        return figure("calibration_fit", width_cm, 0.75, &[(profile, 1.0)]);
    }
    figure("calibration_fit", width_cm, 1.2, &[(profile, 0.62), (ratio_panel(&names, &rest, &val, &q05, &q50, &q95, None), 0.38)])
}

/// Observations `idx` as ratios to their predictive median, with the 90 % interval as a box;
/// x = the output's position in `idx` (named in the x label when there are few).
fn ratio_panel(names: &[String], idx: &[usize], val: &[f64], q05: &[f64], q50: &[f64], q95: &[f64], legend: Option<SeriesLabelPosition>) -> Panel {
    let mut series = Vec::new();
    for (k, &i) in idx.iter().enumerate() {
        let x = (k + 1) as f64;
        let label = if k == 0 { Some("90 % posterior predictive".to_string()) } else { None };
        series.push(Series { label, points: vec![(x - 0.2, q05[i] / q50[i]), (x + 0.2, q05[i] / q50[i])], colour: colour(0), kind: Kind::Band(vec![q95[i] / q50[i]; 2], 0.3) });
    }
    series.push(Series { label: Some("measured".into()), points: idx.iter().enumerate().map(|(k, &i)| ((k + 1) as f64, val[i] / q50[i])).collect(), colour: colour(1), kind: Kind::Markers(Marker::Circle, 1.8) });
    Panel {
        // Names fit under the axis for a few outputs; more are numbered in table order.
        x_categories: idx.iter().enumerate().map(|(k, &i)| if idx.len() <= 3 { names[i].replace('_', " ") } else { (k + 1).to_string() }).collect(),
        x_desc: if idx.len() <= 3 { "Output".into() } else { "Observation (order of observations.csv)".into() },
        y_desc: "Value / pred. median (-)".into(),
        x_range: (0.5, idx.len() as f64 + 0.5),
        y_range: padded(idx.iter().flat_map(|&i| [q05[i] / q50[i], q95[i] / q50[i], val[i] / q50[i]]), 0.15, 0.15),
        y_log: false,
        series,
        legend,
    }
}

fn residuals(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let obs = Table::load(dir, "observations")?;
    let (val, sig, q05, q50, q95) = (obs.f("value")?, obs.f("sigma")?, obs.f("predictive_q05")?, obs.f("predictive_q50")?, obs.f("predictive_q95")?);
    let n = val.len();
    let upper: Vec<f64> = (0..n).map(|i| (q95[i] - q50[i]) / sig[i]).collect();
    let z: Vec<(f64, f64)> = (0..n).map(|i| ((i + 1) as f64, (val[i] - q50[i]) / sig[i])).collect();
    // One box per observation: the interval belongs to that observation, not to the space
    // between neighbours.
    let mut series: Vec<Series> = (0..n)
        .map(|i| {
            let (x, lo) = ((i + 1) as f64, (q05[i] - q50[i]) / sig[i]);
            let label = if i == 0 { Some("90 % posterior predictive".to_string()) } else { None };
            Series { label, points: vec![(x - 0.4, lo), (x + 0.4, lo)], colour: colour(0), kind: Kind::Band(vec![upper[i]; 2], 0.3) }
        })
        .collect();
    series.push(Series::line(None, vec![(0.5, 0.0), (n as f64 + 0.5, 0.0)], RGBColor(120, 120, 120), 0.5));
    series.push(Series { label: Some("observation".into()), points: z.clone(), colour: colour(1), kind: Kind::Markers(Marker::Circle, 1.4) });
    let lim = z.iter().map(|p| p.1.abs()).chain(upper.iter().map(|u| u.abs())).fold(2.0, f64::max) * 1.5;
    let panel = Panel {
        x_categories: vec![],
        x_desc: "Observation (in data-file order, grouped by output)".into(),
        y_desc: "(d − predictive median)/σ (-)".into(),
        x_range: (0.5, n as f64 + 0.5),
        y_range: (-lim, lim),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    figure("calibration_residuals", width_cm, 0.6, &[(panel, 1.0)])
}

/// Parameter names, units and their chain columns (display units).
fn chain_columns(dir: &Path) -> Result<(Vec<String>, Vec<String>, Vec<Vec<f64>>, Table)> {
    let pt = Table::load(dir, "parameters")?;
    let (names, units) = (pt.s("name")?, pt.s("unit")?);
    let ch = Table::load(dir, "chains")?;
    let cols = names
        .iter()
        .zip(&units)
        .map(|(n, u)| {
            let s = display(u).0;
            ch.f(n).map(|v| v.into_iter().map(|x| x * s).collect())
        })
        .collect::<Result<Vec<Vec<f64>>>>()?;
    Ok((names, units, cols, ch))
}

fn corner(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let (names, units, cols, _) = chain_columns(dir)?;
    let p = names.len();
    let n = cols[0].len();
    let stride = (n / 1500).max(1);
    let ranges: Vec<(f64, f64)> = cols.iter().map(|c| padded(c.iter().cloned(), 0.05, 0.05)).collect();
    let mut panels = Vec::new();
    for r in 0..p {
        for c in 0..p {
            if c > r {
                panels.push(None);
                continue;
            }
            let x_desc = if r + 1 == p { axis_label(&names[c], &units[c]) } else { String::new() };
            if r == c {
                // Histogram as a step line, normalised to its maximum.
                let bins = 30;
                let (lo, hi) = ranges[c];
                let mut h = vec![0.0; bins];
                for v in &cols[c] {
                    let b = (((v - lo) / (hi - lo)) * bins as f64).floor().clamp(0.0, bins as f64 - 1.0) as usize;
                    h[b] += 1.0;
                }
                let mx = h.iter().cloned().fold(1.0, f64::max);
                let mut pts = Vec::new();
                for (b, v) in h.iter().enumerate() {
                    let x0 = lo + (hi - lo) * b as f64 / bins as f64;
                    let x1 = lo + (hi - lo) * (b + 1) as f64 / bins as f64;
                    pts.push((x0, v / mx));
                    pts.push((x1, v / mx));
                }
                panels.push(Some(Panel { x_categories: vec![], x_desc, y_desc: if c == 0 { "density (rel.)".into() } else { String::new() }, x_range: ranges[c], y_range: (0.0, 1.1), y_log: false, series: vec![Series::line(None, pts, colour(0), 0.8)], legend: None }));
            } else {
                let pts: Vec<(f64, f64)> = (0..n).step_by(stride).map(|i| (cols[c][i], cols[r][i])).collect();
                let y_desc = if c == 0 { axis_label(&names[r], &units[r]) } else { String::new() };
                panels.push(Some(Panel { x_categories: vec![], x_desc, y_desc, x_range: ranges[c], y_range: ranges[r], y_log: false, series: vec![Series { label: None, points: pts, colour: colour(0), kind: Kind::Markers(Marker::Circle, 0.35) }], legend: None }));
            }
        }
    }
    figure_grid("calibration_corner", width_cm, 1.0, p, &panels)
}

fn trace(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let (names, units, cols, ch) = chain_columns(dir)?;
    let (step, walker) = (ch.f("step")?, ch.f("walker")?);
    let p = names.len();
    let panels: Vec<(Panel, f64)> = (0..p)
        .map(|k| {
            let series = (0..4)
                .map(|w| Series::line(None, (0..step.len()).filter(|&i| walker[i] as usize == w).map(|i| (step[i], cols[k][i])).collect(), colour(w), 0.4))
                .collect();
            let panel = Panel {
                x_categories: vec![],
                x_desc: if k + 1 == p { "Step after burn-in".into() } else { String::new() },
                y_desc: axis_label(&names[k], &units[k]),
                x_range: padded(step.iter().cloned(), 0.0, 0.0),
                y_range: padded(cols[k].iter().cloned(), 0.05, 0.05),
                y_log: false,
                series,
                legend: None,
            };
            (panel, 1.0 / p as f64)
        })
        .collect();
    figure("calibration_trace", width_cm, 0.35 * p as f64, &panels)
}

/// Fig. 7 style table: parameter, reference [90 %], this [90 %], change coloured by size.
fn comparison(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let name = "calibration_comparison";
    let t = Table::load(dir, "comparison")?;
    let pt = Table::load(dir, "parameters")?;
    let (pn, pu) = (pt.s("name")?, pt.s("unit")?);
    let (names, rl, tl) = (t.s("name")?, t.s("reference_label")?, t.s("this_label")?);
    let (a, a5, a95, b, b5, b95, ch) = (t.f("reference_mean")?, t.f("reference_q05")?, t.f("reference_q95")?, t.f("this_mean")?, t.f("this_q05")?, t.f("this_q95")?, t.f("change_percent")?);
    register_fonts()?;
    let rows = names.len() + 1;
    let aspect = 0.09 * rows as f64 + 0.08;
    let size = canvas_size(width_cm, aspect);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(fig_err(name))?;
        let (w, h) = (size.0 as i32, size.1 as i32);
        let row_h = h / (rows as i32 + 1);
        let colx = [w * 2 / 100, w * 22 / 100, w * 52 / 100, w * 82 / 100];
        let head = [
            "parameter".to_string(),
            format!("{} mean [90 %]", rl.first().cloned().unwrap_or_default()),
            format!("{} mean [90 %]", tl.first().cloned().unwrap_or_default()),
            "change".to_string(),
        ];
        for (x, s) in colx.iter().zip(&head) {
            super::canvas::check_glyphs(name, s)?;
            root.draw_text(s, &text(8.0), (*x, row_h / 2)).map_err(fig_err(name))?;
        }
        for (i, n) in names.iter().enumerate() {
            let y = row_h * (i as i32 + 1) + row_h / 2;
            let unit = pn.iter().position(|x| x == n).map(|k| pu[k].clone()).unwrap_or_default();
            let (s, u) = display(&unit);
            let cell = |m: f64, lo: f64, hi: f64| format!("{:.3} [{:.3}, {:.3}] {}", m * s, lo * s, hi * s, if u == "-" { "" } else { &u });
            // Change colour: < 10 % pale, 10–30 % amber, > 30 % red.
            let c = ch[i].abs();
            let fill = if c < 10.0 { RGBColor(235, 240, 245) } else if c < 30.0 { RGBColor(253, 208, 140) } else { RGBColor(240, 120, 100) };
            root.draw(&Rectangle::new([(colx[3] - w / 100, y - row_h / 2 + 2), (w - w / 100, y + row_h / 2 - 2)], fill.filled())).map_err(fig_err(name))?;
            for (x, s) in colx.iter().zip([n.clone(), cell(a[i], a5[i], a95[i]), cell(b[i], b5[i], b95[i]), format!("{:+.1} %", ch[i])]) {
                super::canvas::check_glyphs(name, &s)?;
                root.draw_text(&s, &text(7.5), (*x, y - row_h / 4)).map_err(fig_err(name))?;
            }
        }
        let legend = "change colour: < 10 %, 10–30 %, > 30 %";
        root.draw_text(legend, &text(6.5), (colx[0], row_h * rows as i32 + row_h / 4)).map_err(fig_err(name))?;
        root.present().map_err(fig_err(name))?;
    }
    Ok((encode(name, &svg, size, width_cm)?, 0))
}

//! Figures of a UQ report (`kind = "uq"`), drawn from the report's tables only.
//!
//! Candidate and reference (keys and labels, in that order) come from `materials.csv`.
//!
//! | file stem | content | table |
//! |---|---|---|
//! | `uq_breakage_vs_velocity` | P_break vs impact velocity, median and 90 % band per material, one panel per horizon (Fig. 16 with bands) | `breakage_vs_velocity.csv` |
//! | `uq_distributions` | density of log₁₀ P_break per material, one panel per horizon | `distributions.csv` |
//! | `uq_convergence` | P(candidate breaks more) vs sample count with ±2 MC standard errors | `convergence.csv` |
//! | `uq_sobol` | first-order and total Sobol' indices with intervals, one panel per output | `sobol.csv` |
//! | `uq_sobol_convergence` | total indices vs base sample size, candidate's log₁₀ P | `sobol.csv` |
//! | `uq_model_form` | the damage models side by side (primary strength model): median and 90 % band per material and horizon | `breakage.csv` |
//! | `uq_strength_models` | the strength models side by side and model-averaged (stacking weights in the labels): P(candidate breaks more) with ±2 MC standard errors per horizon, and P_break at the last horizon, median and 90 % band per material | `comparison.csv`, `breakage.csv`, `weights.csv` |
//!
//! Tables and figures other than `uq_strength_models` describe the primary strength model
//! (`primary_strength_model` of `materials.csv`) and, where one damage model is shown, the
//! primary damage model (`primary_damage_model`); the bottom x axis of `uq_breakage_vs_velocity`,
//! `uq_distributions` (briefly: "diagnosed strength, indep. trials") and `uq_sobol` names both. Sobol' panels name their output in words
//! (`output_label` of `sobol.csv`). In `uq_model_form` a P = 0 (below Vogel–Peukert's
//! threshold) is drawn on the axis floor, which the y-axis label then names ("floor: P = 0").

use std::path::Path;

use plotters::prelude::SeriesLabelPosition;

use super::canvas::{Encoded, colour};
use super::panel::{Kind, Marker, Panel, Series, figure, padded};
use super::{LG_FLOOR, Rendered, Table, distinct, lg};
use crate::error::Result;

type Drawn = (Encoded, usize);

/// Draws every UQ figure in `dir` (candidate and reference from `materials.csv`).
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let m = Table::load(dir, "materials")?;
    let (k, l) = (m.s("key")?, m.s("label")?);
    if k.len() != 2 || l.len() != 2 {
        return Err(crate::error::Error::data_file(&dir.join("materials.csv"), "rows", "needs the candidate and the reference"));
    }
    let (keys, labels) = ([k[0].clone(), k[1].clone()], [l[0].clone(), l[1].clone()]);
    let (keys, labels) = (&keys, &labels);
    let primary = m.s("primary_strength_model")?[0].clone();
    // Which models a figure of the primary models shows (reports written before the damage
    // model was recorded name the strength model only).
    // model, and in a short form for the single-width figures.
    let damage = m.s("primary_damage_model").ok().and_then(|d| d.first().cloned());
    let shown = match &damage {
        Some(d) => format!("strength model: {}; damage: {d}", short_model(&primary)),
        None => format!("strength model: {}", short_model(&primary)),
    };
    let brief = match &damage {
        Some(d) => format!("{} strength, {}", short_model(&primary), d.replace("independent", "indep.")),
        None => format!("{} strength model", short_model(&primary)),
    };
    let (brief, shown, primary) = (&brief, &shown, &primary);
    let figures: Vec<super::Figure<Drawn>> = vec![
        ("uq_breakage_vs_velocity", Box::new(move || breakage_vs_velocity(dir, width_cm, labels, keys, brief))),
        ("uq_distributions", Box::new(move || distributions(dir, width_cm, labels, keys, brief))),
        ("uq_convergence", Box::new(move || convergence(dir, width_cm, labels))),
        ("uq_sobol", Box::new(move || sobol(dir, 2.0 * width_cm, shown))),
        ("uq_sobol_convergence", Box::new(move || sobol_convergence(dir, width_cm))),
        ("uq_model_form", Box::new(move || model_form(dir, width_cm, labels, keys, primary))),
        ("uq_strength_models", Box::new(move || strength_models(dir, 2.0 * width_cm, labels, keys))),
    ];
    super::write_figures(dir, super::draw_all(figures)?)
}

fn years_label(y: f64) -> String {
    if y == 1.0 { "1 year".into() } else { format!("{y} years") }
}

fn breakage_vs_velocity(dir: &Path, width_cm: f64, labels: &[String; 2], keys: &[String; 2], shown: &str) -> Result<Drawn> {
    let t = Table::load(dir, "breakage_vs_velocity")?;
    let (mat, yrs, v, q05, q50, q95) = (t.s("material")?, t.f("years")?, t.f("velocity_m_s")?, t.f("q05")?, t.f("median")?, t.f("q95")?);
    let horizons = distinct(&yrs);
    let mut panels = Vec::new();
    for (hi, &h) in horizons.iter().enumerate() {
        let mut series = Vec::new();
        let rows_of = |key: &String| (0..mat.len()).filter(|&i| &mat[i] == key && yrs[i] == h).collect::<Vec<usize>>();
        // The data reach down to the figures' floor; four more decades below it leave the lower
        // right corner free for the legend (the bands rise with velocity), and anything under
        // the axis is drawn on it.
        let data_lo = keys.iter().flat_map(|k| rows_of(k)).map(|i| lg(q05[i])).fold(0.0, f64::min).floor();
        let lo = data_lo - 4.0;
        let at = |p: f64| p.max(1e-300).log10().max(lo);
        for (j, key) in keys.iter().enumerate() {
            let rows = rows_of(key);
            series.push(Series { label: Some(format!("{} 90 % band", labels[j])), points: rows.iter().map(|&i| (v[i], at(q05[i]))).collect(), colour: colour(j), kind: Kind::Band(rows.iter().map(|&i| at(q95[i])).collect(), 0.25) });
            series.push(Series::line(Some(format!("{} median", labels[j])), rows.iter().map(|&i| (v[i], at(q50[i]))).collect(), colour(j), 1.2));
        }
        panels.push((
            Panel {
                x_categories: vec![],
                x_desc: if hi + 1 == horizons.len() { format!("Velocity (m/s); {shown}") } else { String::new() },
                y_desc: format!("P break, {}", years_label(h)),
                x_range: padded(v.iter().cloned(), 0.0, 0.0),
                y_range: (lo, 0.3),
                y_log: true,
                series,
                legend: if hi == 0 { Some(SeriesLabelPosition::LowerRight) } else { None },
            },
            1.0 / horizons.len() as f64,
        ));
    }
    figure("uq_breakage_vs_velocity", width_cm, 0.6 * horizons.len() as f64, &panels)
}

fn distributions(dir: &Path, width_cm: f64, labels: &[String; 2], keys: &[String; 2], shown: &str) -> Result<Drawn> {
    let t = Table::load(dir, "distributions")?;
    let (mat, yrs, x, d) = (t.s("material")?, t.f("years")?, t.f("log10_p")?, t.f("density")?);
    let horizons = distinct(&yrs);
    let mut panels = Vec::new();
    for (hi, &h) in horizons.iter().enumerate() {
        let mut series = Vec::new();
        let rows_h: Vec<usize> = (0..mat.len()).filter(|&i| yrs[i] == h).collect();
        for (j, key) in keys.iter().enumerate() {
            let rows: Vec<usize> = rows_h.iter().copied().filter(|&i| &mat[i] == key).collect();
            series.push(Series::line(Some(labels[j].clone()), rows.iter().map(|&i| (x[i], d[i])).collect(), colour(j), 1.2));
        }
        panels.push((
            Panel {
                x_categories: vec![],
                x_desc: if hi + 1 == horizons.len() { format!("log₁₀ P, {}; {shown}", years_label(h)) } else { format!("log₁₀ P, {}", years_label(h)) },
                y_desc: "Density (per decade)".into(),
                x_range: padded(rows_h.iter().map(|&i| x[i]), 0.02, 0.02),
                y_range: (0.0, rows_h.iter().map(|&i| d[i]).fold(0.0, f64::max) * 1.3),
                y_log: false,
                series,
                legend: if hi == 0 { Some(SeriesLabelPosition::UpperLeft) } else { None },
            },
            1.0 / horizons.len() as f64,
        ));
    }
    figure("uq_distributions", width_cm, 0.55 * horizons.len() as f64, &panels)
}

fn convergence(dir: &Path, width_cm: f64, labels: &[String; 2]) -> Result<Drawn> {
    let t = Table::load(dir, "convergence")?;
    let (yrs, n, p, se) = (t.f("years")?, t.f("samples")?, t.f("p_candidate_worse")?, t.f("mc_se")?);
    let mut series = Vec::new();
    for (k, &h) in distinct(&yrs).iter().enumerate() {
        let rows: Vec<usize> = (0..yrs.len()).filter(|&i| yrs[i] == h).collect();
        series.push(Series { label: Some(format!("± 2 se, {}", years_label(h))), points: rows.iter().map(|&i| (n[i].log10(), p[i] - 2.0 * se[i])).collect(), colour: colour(k), kind: Kind::Band(rows.iter().map(|&i| p[i] + 2.0 * se[i]).collect(), 0.25) });
        let kind = if k == 0 { Kind::Dashed(1.2, 3.0, 2.0) } else { Kind::Line(1.2) };
        series.push(Series { label: Some(years_label(h)), points: rows.iter().map(|&i| (n[i].log10(), p[i])).collect(), colour: colour(k), kind });
    }
    let panel = Panel {
        x_categories: vec![],
        x_desc: "Monte Carlo samples (log₁₀)".into(),
        y_desc: format!("P({} breaks more)", labels[0]),
        x_range: padded(n.iter().map(|v| v.log10()), 0.0, 0.02),
        // A probability axis ends at 1 (the legend sits in the padding above the data).
        y_range: {
            let (lo, hi) = padded((0..p.len()).flat_map(|i| [p[i] - 2.0 * se[i], p[i] + 2.0 * se[i]]).map(|v| v.clamp(0.0, 1.0)), 0.1, 0.6);
            (lo.max(0.0), hi.min(1.0))
        },
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::LowerRight),
    };
    figure("uq_convergence", width_cm, 0.7, &[(panel, 1.0)])
}

/// Short input names for a category axis.
fn short(name: &str) -> String {
    name.replace("strength_", "Weib. ")
        .replace("size_alpha_", "α ")
        .replace("roundness_q_", "q ")
        .replace("sphericity_p_", "p ")
        .replace("temperature_strength_ratio_per_100c_", "T ratio ")
        .replace("energy_fraction", "η")
        .replace("velocity", "V")
        .replace("impacts_per_year", "N/yr")
        .replace("tk_gamma", "γ (TK)")
}

fn sobol(dir: &Path, width_cm: f64, shown: &str) -> Result<Drawn> {
    let t = Table::load(dir, "sobol")?;
    let (out, n, input) = (t.s("output")?, t.f("n")?, t.s("input")?);
    // The output in words (older reports: its column name, spaced), and its horizon.
    let words = t.s("output_label").unwrap_or_else(|_| out.iter().map(|o| o.replace('_', " ")).collect());
    let horizon = t.f("years").ok().and_then(|y| y.first().copied()).map_or(String::new(), |y| format!(", P after {}", years_label(y)));
    let (s1, s1l, s1h, st, stl, sth) = (t.f("s1")?, t.f("s1_lo")?, t.f("s1_hi")?, t.f("st")?, t.f("st_lo")?, t.f("st_hi")?);
    let nmax = n.iter().cloned().fold(0.0, f64::max);
    let outputs = distinct(&out);
    // The intervals' level as the table states it (reports before it was written: 95 %, the
    // default then as now).
    let level = t.f("level").ok().and_then(|l| l.first().copied()).unwrap_or(0.95);
    let interval = format!("{} interval", crate::report::captions::percent(level));
    let mut panels = Vec::new();
    for (oi, o) in outputs.iter().enumerate() {
        let rows: Vec<usize> = (0..out.len()).filter(|&i| &out[i] == o && n[i] == nmax).collect();
        let mut series = Vec::new();
        for (k, &i) in rows.iter().enumerate() {
            let x = (k + 1) as f64;
            let lab = |s: &str| if k == 0 { Some(s.to_string()) } else { None };
            series.push(Series { label: lab("first order S"), points: vec![(x - 0.3, 0.0), (x - 0.02, 0.0)], colour: colour(0), kind: Kind::Band(vec![s1[i]; 2], 0.8) });
            series.push(Series { label: lab("total S_T"), points: vec![(x + 0.02, 0.0), (x + 0.3, 0.0)], colour: colour(1), kind: Kind::Band(vec![st[i]; 2], 0.8) });
            series.push(Series::line(lab(&interval), vec![(x - 0.16, s1l[i]), (x - 0.16, s1h[i])], plotters::style::BLACK, 0.8));
            series.push(Series::line(None, vec![(x + 0.16, stl[i]), (x + 0.16, sth[i])], plotters::style::BLACK, 0.8));
        }
        let hi = rows.iter().map(|&i| sth[i].max(st[i]).max(s1h[i])).fold(0.0, f64::max).max(0.05);
        let lo = rows.iter().map(|&i| s1l[i].min(stl[i]).min(s1[i])).fold(0.0, f64::min);
        panels.push((
            Panel {
                x_categories: rows.iter().map(|&i| short(&input[i])).collect(),
                x_desc: if oi + 1 == outputs.len() { format!("Input — {shown}{horizon}") } else { String::new() },
                y_desc: format!("Index of {}", rows.first().map_or_else(|| o.replace('_', " "), |&i| words[i].clone())),
                x_range: (0.5, rows.len() as f64 + 0.5),
                y_range: (lo - 0.02, hi * 1.25),
                y_log: false,
                series,
                legend: if oi == 0 { Some(SeriesLabelPosition::UpperRight) } else { None },
            },
            1.0 / outputs.len() as f64,
        ));
    }
    figure("uq_sobol", width_cm, 0.35 * outputs.len() as f64, &panels)
}

fn sobol_convergence(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let t = Table::load(dir, "sobol")?;
    let (out, n, input, st) = (t.s("output")?, t.f("n")?, t.s("input")?, t.f("st")?);
    let first = out.first().cloned().unwrap_or_default();
    let first_words = t.s("output_label").ok().and_then(|w| w.first().cloned()).unwrap_or_else(|| first.replace('_', " "));
    let nmax = n.iter().cloned().fold(0.0, f64::max);
    // The four inputs with the largest final total index.
    let mut fin: Vec<(String, f64)> = (0..out.len()).filter(|&i| out[i] == first && n[i] == nmax).map(|i| (input[i].clone(), st[i])).collect();
    fin.sort_by(|a, b| b.1.total_cmp(&a.1));
    let mut series = Vec::new();
    for (k, (name, _)) in fin.iter().take(4).enumerate() {
        let rows: Vec<usize> = (0..out.len()).filter(|&i| out[i] == first && &input[i] == name).collect();
        series.push(Series::line(Some(short(name)), rows.iter().map(|&i| (n[i].log2(), st[i])).collect(), colour(k), 1.2));
        series.push(Series { label: None, points: rows.iter().map(|&i| (n[i].log2(), st[i])).collect(), colour: colour(k), kind: Kind::Markers(Marker::Circle, 1.5) });
    }
    let ys: Vec<f64> = series.iter().flat_map(|s| s.points.iter().map(|p| p.1)).collect();
    let panel = Panel {
        x_categories: vec![],
        x_desc: "Saltelli base sample size (log₂ n)".into(),
        y_desc: format!("S_T of {first_words}"),
        x_range: padded(n.iter().map(|v| v.log2()), 0.05, 0.05),
        // Indices lie in [0, 1]: the upper part of the axis is left to the legend.
        y_range: (ys.iter().cloned().fold(0.0, f64::min) - 0.02, ys.iter().cloned().fold(1.0, f64::max) + 0.05),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    figure("uq_sobol_convergence", width_cm, 0.7, &[(panel, 1.0)])
}

fn model_form(dir: &Path, width_cm: f64, labels: &[String; 2], keys: &[String; 2], primary: &str) -> Result<Drawn> {
    let t = Table::load(dir, "breakage")?.filter("strength_model", primary)?;
    let (model, mat, yrs, q05, q50, q95) = (t.s("model")?, t.s("material")?, t.f("years")?, t.f("q05")?, t.f("median")?, t.f("q95")?);
    let models = distinct(&model);
    let horizons = distinct(&yrs);
    let mut panels = Vec::new();
    for (hi, &h) in horizons.iter().enumerate() {
        let mut series = Vec::new();
        let mut ys = Vec::new();
        for (j, key) in keys.iter().enumerate() {
            let off = if j == 0 { -0.15 } else { 0.15 };
            for (k, m) in models.iter().enumerate() {
                let Some(i) = (0..model.len()).find(|&i| &model[i] == m && &mat[i] == key && yrs[i] == h) else { continue };
                let x = (k + 1) as f64 + off;
                let lab = if k == 0 { Some(labels[j].clone()) } else { None };
                series.push(Series { label: lab, points: vec![(x - 0.1, lg(q05[i])), (x + 0.1, lg(q05[i]))], colour: colour(j), kind: Kind::Band(vec![lg(q95[i]); 2], 0.35) });
                series.push(Series { label: None, points: vec![(x, lg(q50[i]))], colour: colour(j), kind: Kind::Markers(Marker::Circle, 2.0) });
                ys.extend([lg(q05[i]), lg(q95[i])].into_iter().filter(|&v| v > LG_FLOOR));
            }
        }
        // P = 0 (below the Vogel–Peukert threshold) sits on the axis floor, two decades below
        // the smallest non-zero value.
        let lo = (ys.iter().cloned().fold(0.0, f64::min) - 2.0).floor().max(LG_FLOOR);
        let mut floored = false;
        for s in series.iter_mut() {
            for p in s.points.iter_mut() {
                floored |= p.1 <= lo;
                p.1 = p.1.max(lo);
            }
            if let Kind::Band(up, _) = &mut s.kind {
                up.iter_mut().for_each(|v| {
                    floored |= *v <= lo;
                    *v = v.max(lo)
                });
            }
        }

        panels.push((
            Panel {
                // P = 0 (below the Vogel–Peukert threshold) is drawn on the axis floor.
                x_categories: models.iter().map(|m| match m.as_str() { "independent" => "indep.".to_string(), "vogel_peukert" => "VP".into(), "tavares_king" => "TK".into(), o => o.into() }).collect(),
                x_desc: if hi + 1 == horizons.len() { "Damage model (dot: median, bar: 90 %)".into() } else { String::new() },
                // Named, so that a bar or dot on the floor does not read as a small probability.
                y_desc: if floored { format!("P break, {} (floor: P = 0)", years_label(h)) } else { format!("P break, {}", years_label(h)) },
                // One empty column on the right keeps the legend off the data.
                x_range: (0.5, models.len() as f64 + 1.7),
                y_range: (lo, 0.8),
                y_log: true,
                series,
                legend: if hi + 1 == horizons.len() { Some(SeriesLabelPosition::LowerRight) } else { None },
            },
            1.0 / horizons.len() as f64,
        ));
    }
    figure("uq_model_form", width_cm, 0.6 * horizons.len() as f64, &panels)
}

/// Short name of a strength model on a category axis.
fn short_model(name: &str) -> String {
    match name {
        "deliverable" => "deliverable".into(),
        "model-averaged" => "averaged".into(),
        o => o.replace("roundness", "rnd").replace("sphericity", "sph").replace("temperature", "T").replace("damage", "dmg"),
    }
}

fn strength_models(dir: &Path, width_cm: f64, labels: &[String; 2], keys: &[String; 2]) -> Result<Drawn> {
    let w = Table::load(dir, "weights")?;
    let (wm, ws) = (w.s("strength_model")?, w.f("weight_stacking")?);
    let c = Table::load(dir, "comparison")?;
    let (cs, cm, cy, cp, cse) = (c.s("strength_model")?, c.s("model")?, c.f("years")?, c.f("p_candidate_worse")?, c.f("mc_se")?);
    let damage = cm.first().cloned().unwrap_or_default();
    let models = distinct(&cs);
    let horizons = distinct(&cy);
    let categories: Vec<String> = models
        .iter()
        .map(|m| match wm.iter().position(|x| x == m) {
            Some(i) if wm.len() > 1 => format!("{} (w = {:.2})", short_model(m), ws[i]),
            _ => short_model(m),
        })
        .collect();
    // Top: P(candidate breaks more) per model and horizon, ±2 se.
    let mut top = Vec::new();
    for (hi, &h) in horizons.iter().enumerate() {
        let off = (hi as f64 - 0.5 * (horizons.len() as f64 - 1.0)) * 0.15;
        let mut pts = Vec::new();
        for (k, m) in models.iter().enumerate() {
            let Some(i) = (0..cs.len()).find(|&i| &cs[i] == m && cm[i] == damage && cy[i] == h) else { continue };
            let x = (k + 1) as f64 + off;
            pts.push((x, cp[i]));
            top.push(Series::line(None, vec![(x, (cp[i] - 2.0 * cse[i]).max(0.0)), (x, (cp[i] + 2.0 * cse[i]).min(1.0))], colour(hi), 1.0));
        }
        let marker = if hi == 0 { Marker::Circle } else { Marker::Triangle };
        top.push(Series { label: Some(years_label(h)), points: pts, colour: colour(hi), kind: Kind::Markers(marker, 2.2) });
    }
    // A probability axis ends at 1; its lower end follows the data (the legend sits in the
    // free column on the right).
    let lows: Vec<f64> = (0..cs.len()).filter(|&i| cm[i] == damage).map(|i| (cp[i] - 2.0 * cse[i]).max(0.0)).collect();
    let (lo, _) = padded(lows.iter().copied().chain([1.0]), 0.15, 0.0);
    let top_panel = Panel {
        x_categories: categories.clone(),
        x_desc: String::new(),
        // Short enough for the low panel's height (before: "P(Gen 4 breaks more)" ran past its
        // top edge): the candidate by name while it is short, else "candidate".
        y_desc: format!("P({} worse)", if labels[0].chars().count() <= 8 { labels[0].as_str() } else { "candidate" }),
        x_range: (0.5, models.len() as f64 + 1.5),
        y_range: (lo.max(0.0), 1.0),
        y_log: false,
        series: top,
        legend: Some(SeriesLabelPosition::LowerRight),
    };
    // Bottom: P break at the last horizon, median and 90 % band per material.
    let t = Table::load(dir, "breakage")?.filter("model", &damage)?;
    let (ts, mat, yrs, q05, q50, q95) = (t.s("strength_model")?, t.s("material")?, t.f("years")?, t.f("q05")?, t.f("median")?, t.f("q95")?);
    let last = horizons.last().copied().unwrap_or(1.0);
    let mut series = Vec::new();
    let mut ys = Vec::new();
    for (j, key) in keys.iter().enumerate() {
        let off = if j == 0 { -0.15 } else { 0.15 };
        for (k, m) in models.iter().enumerate() {
            let Some(i) = (0..ts.len()).find(|&i| &ts[i] == m && &mat[i] == key && yrs[i] == last) else { continue };
            let x = (k + 1) as f64 + off;
            let lab = if k == 0 { Some(labels[j].clone()) } else { None };
            series.push(Series { label: lab, points: vec![(x - 0.1, lg(q05[i])), (x + 0.1, lg(q05[i]))], colour: colour(j), kind: Kind::Band(vec![lg(q95[i]); 2], 0.35) });
            series.push(Series { label: None, points: vec![(x, lg(q50[i]))], colour: colour(j), kind: Kind::Markers(Marker::Circle, 2.0) });
            ys.extend([lg(q05[i]), lg(q95[i])]);
        }
    }
    let lo = (ys.iter().cloned().fold(0.0, f64::min) - 0.5).floor().max(LG_FLOOR);
    let bottom = Panel {
        x_categories: categories,
        x_desc: "Strength model (stacking weight w; rnd: roundness, sph: sphericity); dot: median, bar: 90 % band".into(),
        y_desc: format!("P break, {}", years_label(last)),
        x_range: (0.5, models.len() as f64 + 1.5),
        y_range: (lo, 0.8),
        y_log: true,
        series,
        legend: Some(SeriesLabelPosition::LowerRight),
    };
    figure("uq_strength_models", width_cm, 0.6, &[(top_panel, 0.4), (bottom, 0.6)])
}

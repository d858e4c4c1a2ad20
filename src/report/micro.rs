//! Figures of a microstructure report (`kind = "microstructure"`), drawn from its tables only.
//!
//! | file stem | deliverable | table(s) |
//! |---|---|---|
//! | `phases_<structure>` | Figs. 10c, 11b (segmented phases) | `map_<structure>.csv`, `phases.csv` |
//! | `sigma1_tension_<structure>`, `sigma1_compression_<structure>` | Fig. 12 (stress peaks, also in compression) | `map_<structure>.csv` |
//! | `shear_strain_<structure>` | Fig. 11a (deformation bands) | `map_<structure>.csv` |
//! | `exceedance` | — (the hot-spot tail per phase, σ₁ over the phase's own strength; at 1 the share above strength) | `distributions.csv`, `phases.csv` |
//! | `comparison` | §6.1 with numbers | `structure_summary.csv`, `structures.csv` |
//! | `failure_curves` | — (with `[failure]`: the applied stress at each crack against the cracks so far, first realisation, both tests) | `failure_events.csv`, `structure_summary.csv` |
//! | `cracks_<test>_<structure>` | Fig. 11a (where the microstructure gives way) | `failure_events.csv`, `map_<structure>.csv`, `phases.csv` |
//!
//! Maps show the first realisation (in blocks when it is larger than 256 pixels a side, each
//! block with its largest value), with the phase boundaries drawn over the fields. σ₁ maps are
//! white at 0, red up to the 99.5 % quantile and blue down to the 0.5 % quantile (each side
//! scaled to its own end, beyond it the end colours); γ_max maps a sequential scale up to its
//! 99.5 % quantile. Cells of equal colour along a row are drawn as one rectangle
//! (colours quantised to 64 levels), which keeps the vector files small.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{Encoded, colour, fig_err};
use super::crush::diverging;
use super::dem::viridis;
use super::map::{MapSpec, map_figure};
use super::panel::{Kind, Marker, Panel, Series, figure, figure_legend_below, padded};
use super::{Rendered, Table, distinct};
use crate::error::Result;

type Drawn = (Encoded, usize);

/// Draws every figure of the microstructure report in `dir`.
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let phases = Table::load(dir, "phases")?.s("phase")?;
    let structures = distinct(&Table::load(dir, "structures")?.s("structure")?);
    let mut figures: Vec<(String, Drawn)> = Vec::new();
    let s_mpa = Table::load(dir, "hot_spots")?.f("applied_stress_pa")?.first().copied().unwrap_or(f64::NAN) / 1e6;
    for st in &structures {
        let t = Table::load(dir, &format!("map_{st}"))?;
        figures.push((format!("phases_{st}"), phase_map(&format!("phases_{st}"), &t, &phases, width_cm)?));
        for (col, test, sign) in [("sigma1_tension_pa", "tension", ""), ("sigma1_compression_pa", "compression", "−")] {
            let name = format!("sigma1_{test}_{st}");
            figures.push((name.clone(), value_map(&name, &t, col, &format!("σ₁ (MPa) at Σxx = {sign}{s_mpa:.0} MPa"), 1e-6, true, width_cm)?));
        }
        let name = format!("shear_strain_{st}");
        figures.push((name.clone(), value_map(&name, &t, "shear_strain_tension", &format!("γ_max (‰) at Σxx = {s_mpa:.0} MPa"), 1e3, false, width_cm)?));
    }
    figures.push(("exceedance".into(), exceedance(dir, &phases, width_cm)?));
    figures.push(("comparison".into(), comparison(dir, width_cm)?));
    if dir.join("failure_events.csv").is_file() {
        let ev = Table::load(dir, "failure_events")?;
        figures.push(("failure_curves".into(), failure_curves(&ev, dir, width_cm)?));
        let (st, te) = (ev.s("structure")?, ev.s("test")?);
        for name in distinct(&st) {
            for test in ["tension", "compression"] {
                if (0..st.len()).any(|k| st[k] == name && te[k] == test) {
                    let fig = format!("cracks_{test}_{name}");
                    let map = Table::load(dir, &format!("map_{name}"))?;
                    figures.push((fig.clone(), crack_map(&fig, &map, &ev, &name, test, &phases, width_cm)?));
                }
            }
        }
    }
    super::write_figures(dir, figures.iter().map(|(n, d)| (n.as_str(), d.clone())).collect())
}

/// Each structure's label (from `structure_summary.csv`), or its key.
pub(crate) fn structure_labels(dir: &Path) -> Result<impl Fn(&str) -> String> {
    let t = Table::load(dir, "structure_summary")?;
    let (n, l) = (t.s("structure")?, t.s("label")?);
    Ok(move |k: &str| n.iter().position(|x| x == k).map_or(k.to_string(), |i| l[i].clone()))
}

/// A map table's geometry: extent and block side (µm), each row's block column and row.
struct MapCells {
    w: f64,
    h: f64,
    block: f64,
    i: Vec<u64>,
    j: Vec<u64>,
}

fn cells(t: &Table) -> Result<MapCells> {
    let index = |c: &str| -> Result<Vec<u64>> { Ok(t.f(c)?.iter().map(|v| *v as u64).collect()) };
    Ok(MapCells { w: t.f("width_m")?[0] * 1e6, h: t.f("height_m")?[0] * 1e6, block: t.f("block_m")?[0] * 1e6, i: index("i")?, j: index("j")? })
}

/// Draws the cells row by row, merging neighbours of one colour into one rectangle.
fn draw_runs(chart: &mut super::map::MapChart, name: &str, (w, h): (f64, f64), i: &[u64], j: &[u64], block: f64, colours: &[RGBColor]) -> Result<()> {
    let mut rects = Vec::new();
    let mut k = 0;
    while k < colours.len() {
        let mut end = k + 1;
        while end < colours.len() && j[end] == j[k] && i[end] == i[end - 1] + 1 && colours[end] == colours[k] {
            end += 1;
        }
        let (x0, x1) = (i[k] as f64 * block, ((i[end - 1] + 1) as f64 * block).min(w));
        let (y0, y1) = (j[k] as f64 * block, ((j[k] + 1) as f64 * block).min(h));
        // Neighbours overlap by about two canvas pixels (the plot is some 1500 pixels wide), so
        // that anti-aliasing leaves no seams between rows.
        let o = (w / 700.0).max(0.03 * block);
        let (ox, oy) = (o, o);
        rects.push(Rectangle::new([((x0 - ox).max(0.0), (y0 - oy).max(0.0)), ((x1 + ox).min(w), (y1 + oy).min(h))], colours[k].filled()));
        k = end;
    }
    chart.draw_series(rects).map_err(fig_err(name))?;
    Ok(())
}

/// The boundaries between cells of different phases as line segments (runs merged).
fn boundaries(i: &[u64], j: &[u64], phase: &[String], block: f64, (w, h): (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let (mx, my) = ((i.iter().max().copied().unwrap_or(0) + 1) as usize, (j.iter().max().copied().unwrap_or(0) + 1) as usize);
    let at = |a: usize, b: usize| &phase[b * mx + a];
    let mut out = Vec::new();
    // Vertical edges between columns a − 1 and a, horizontal ones between rows b − 1 and b.
    for a in 1..mx {
        let mut b = 0;
        while b < my {
            if at(a - 1, b) != at(a, b) {
                let start = b;
                while b < my && at(a - 1, b) != at(a, b) {
                    b += 1;
                }
                let x = a as f64 * block;
                out.push(vec![(x, start as f64 * block), (x, (b as f64 * block).min(h))]);
            } else {
                b += 1;
            }
        }
    }
    for b in 1..my {
        let mut a = 0;
        while a < mx {
            if at(a, b - 1) != at(a, b) {
                let start = a;
                while a < mx && at(a, b - 1) != at(a, b) {
                    a += 1;
                }
                let y = b as f64 * block;
                out.push(vec![(start as f64 * block, y), ((a as f64 * block).min(w), y)]);
            } else {
                a += 1;
            }
        }
    }
    out
}

fn phase_map(name: &str, t: &Table, phases: &[String], width_cm: f64) -> Result<Drawn> {
    let MapCells { w, h, block, i, j } = cells(t)?;
    let ph = t.s("phase")?;
    let index = |p: &str| phases.iter().position(|q| q == p).unwrap_or(0);
    let colours: Vec<RGBColor> = ph.iter().map(|p| colour(index(p))).collect();
    let present: Vec<(String, RGBColor)> = distinct(&ph).iter().map(|p| (index(p), p.clone())).collect::<std::collections::BTreeSet<_>>().into_iter().map(|(k, p)| (p.replace('_', " "), colour(k))).collect();
    let none = |_: f64| BLACK;
    let spec = MapSpec { name, width_cm, x: (0.0, w, "x (µm)"), y: (0.0, h, "y (µm)"), labels: (5, 5), bar: (0.0, 1.0, ""), colour: &none, categories: Some(&present) };
    map_figure(&spec, |chart| draw_runs(chart, name, (w, h), &i, &j, block, &colours))
}

/// A map of one column with the phase boundaries drawn over it. Signed values: white at 0, red
/// up to the 99.5 % quantile, blue down to the 0.5 % quantile (each side to its own end).
fn value_map(name: &str, t: &Table, col: &str, desc: &str, scale: f64, signed: bool, width_cm: f64) -> Result<Drawn> {
    let MapCells { w, h, block, i, j } = cells(t)?;
    let v: Vec<f64> = t.f(col)?.iter().map(|x| x * scale).collect();
    let q = crate::stats::interpolated_quantiles(v.clone(), &[0.005, 0.995]);
    let levels = 64.0;
    let (lo, hi, colour): (f64, f64, Box<dyn Fn(f64) -> RGBColor>) = if signed {
        let (lo, hi) = (q[0].min(0.0), q[1].max(0.0));
        let (lo, hi) = (if lo < 0.0 { lo } else { -1e-12 }, if hi > 0.0 { hi } else { 1e-12 });
        (lo, hi, Box::new(move |x: f64| diverging((if x >= 0.0 { x / hi } else { -x / lo } * levels / 2.0).round() / (levels / 2.0))))
    } else {
        let m = q[1].max(1e-12);
        (0.0, m, Box::new(move |x: f64| viridis(((x / m) * levels).round() / levels)))
    };
    let colours: Vec<RGBColor> = v.iter().map(|&x| colour(x)).collect();
    let edges = boundaries(&i, &j, &t.s("phase")?, block, (w, h));
    let spec = MapSpec { name, width_cm, x: (0.0, w, "x (µm)"), y: (0.0, h, "y (µm)"), labels: (5, 5), bar: (lo, hi, desc), colour: &*colour, categories: None };
    map_figure(&spec, |chart| {
        draw_runs(chart, name, (w, h), &i, &j, block, &colours)?;
        let style = RGBColor(40, 40, 40).stroke_width(super::panel::pt(0.3));
        chart.draw_series(edges.into_iter().map(|e| PathElement::new(e, style))).map_err(fig_err(name))?;
        Ok(())
    })
}

/// Exceedance: the share of a phase's area whose σ₁ exceeds a multiple of the phase's own
/// tensile strength, at the applied stress, one panel per test — read at 1, the share of the
/// phase above its strength. One legend strip below both panels.
fn exceedance(dir: &Path, phases: &[String], width_cm: f64) -> Result<Drawn> {
    let d = Table::load(dir, "distributions")?.filter("measure", "sigma1_pa")?;
    let (st, te, ph, p, v, s) = (d.s("structure")?, d.s("test")?, d.s("phase")?, d.f("p")?, d.f("value")?, d.f("applied_stress_pa")?);
    let strength = Table::load(dir, "phases")?.f("tensile_strength_pa")?;
    let strength_of = |phase: &str| phases.iter().position(|q| q == phase).map_or(f64::NAN, |k| strength[k]);
    let labels_of = structure_labels(dir)?;
    let structures = distinct(&st);
    let sv = s.first().copied().unwrap_or(f64::NAN);
    let (y_lo, y_hi) = (-4.2, 0.1);
    let mut panels = Vec::new();
    let mut entries = Vec::new();
    for (ti, (test, sign)) in [("tension", ""), ("compression", "−")].iter().enumerate() {
        let mut series = Vec::new();
        let mut xs = vec![1.0];
        for (si, name) in structures.iter().enumerate() {
            let here: Vec<usize> = (0..st.len()).filter(|&k| &st[k] == name && te[k] == *test).collect();
            for (pi, phase) in distinct(&here.iter().map(|&k| ph[k].clone()).collect::<Vec<_>>()).iter().enumerate() {
                let st_p = strength_of(phase);
                let pts: Vec<(f64, f64)> = here.iter().filter(|&&k| &ph[k] == phase).map(|&k| (v[k] / st_p, (1.0 - p[k]).log10())).collect();
                xs.extend(pts.iter().map(|q| q.0));
                let kind = if pi == 0 { Kind::Line(1.0) } else { Kind::Dashed(1.0, 3.0, 2.0) };
                let s = Series { label: Some(format!("{}: {}", labels_of(name), phase.replace('_', " "))), points: pts, colour: colour(si), kind };
                if ti == 0 {
                    entries.push(Series { points: vec![], ..s.clone() });
                }
                series.push(Series { label: None, ..s });
            }
        }
        let line = Series { label: None, points: vec![(1.0, y_lo), (1.0, y_hi)], colour: RGBColor(110, 110, 110), kind: Kind::Dashed(0.6, 1.0, 1.5) };
        if ti == 0 {
            entries.push(Series { label: Some("σ₁ = σ_t of the phase".into()), points: vec![], ..line.clone() });
        }
        series.push(line);
        panels.push(Panel {
            x_categories: vec![],
            x_desc: format!("σ₁ / σ_t at Σxx = {sign}{:.0} MPa ({test})", sv / 1e6),
            y_desc: "share of phase area above".into(),
            x_range: padded(xs.iter().cloned(), 0.03, 0.03),
            y_range: (y_lo, y_hi),
            y_log: true,
            series,
            legend: None,
        });
    }
    let n_rows = entries.len().div_ceil(2) as f64;
    let panels: Vec<(Panel, f64)> = panels.into_iter().map(|p| (p, 0.5)).collect();
    figure_legend_below("exceedance", width_cm, 1.35 + 0.045 * n_rows, &panels, &entries, 2)
}

/// E with its HS bounds, the area above strength and the first-failure stress per structure
/// (mean ± one standard deviation over the realisations).
fn comparison(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let t = Table::load(dir, "structure_summary")?;
    let (st, lab, q, mean, sd) = (t.s("structure")?, t.s("label")?, t.s("quantity")?, t.f("mean")?, t.f("sd")?);
    let structures = distinct(&st);
    let labels: Vec<String> = structures.iter().map(|s| lab[st.iter().position(|x| x == s).unwrap_or(0)].clone()).collect();
    let get = |s: &str, quantity: &str| -> (f64, f64) { (0..st.len()).find(|&k| st[k] == s && q[k] == quantity).map_or((f64::NAN, f64::NAN), |k| (mean[k], sd[k])) };
    let sr = Table::load(dir, "structures")?;
    let (sst, lo, hi) = (sr.s("structure")?, sr.f("youngs_hs_lower_pa")?, sr.f("youngs_hs_upper_pa")?);
    let n = structures.len() as f64;
    let x_range = (0.5, n + 0.5);
    let bar = |x: f64, (m, s): (f64, f64), scale: f64, c: RGBColor, label: Option<String>, marker: Marker| -> Vec<Series> {
        vec![
            Series { label: None, points: vec![(x, (m - s) * scale), (x, (m + s) * scale)], colour: c, kind: Kind::Line(0.8) },
            Series { label, points: vec![(x, m * scale)], colour: c, kind: Kind::Markers(marker, 2.2) },
        ]
    };
    // E and its HS bounds.
    let mut series = Vec::new();
    let mut ys = Vec::new();
    for (k, s) in structures.iter().enumerate() {
        let x = k as f64 + 1.0;
        let idx: Vec<usize> = (0..sst.len()).filter(|&i| &sst[i] == s).collect();
        let (l, h) = (idx.iter().map(|&i| lo[i]).fold(f64::INFINITY, f64::min) / 1e9, idx.iter().map(|&i| hi[i]).fold(f64::NEG_INFINITY, f64::max) / 1e9);
        ys.extend([l, h]);
        series.push(Series { label: (k == 0).then(|| "Hashin–Shtrikman bounds".to_string()), points: vec![(x - 0.18, l), (x + 0.18, l)], colour: RGBColor(120, 120, 120), kind: Kind::Line(0.8) });
        series.push(Series { label: None, points: vec![(x - 0.18, h), (x + 0.18, h)], colour: RGBColor(120, 120, 120), kind: Kind::Line(0.8) });
        series.extend(bar(x, get(s, "youngs_modulus"), 1e-9, colour(0), (k == 0).then(|| "E, mean ± sd".to_string()), Marker::Circle));
    }
    let e_panel = Panel { x_categories: labels.clone(), x_desc: String::new(), y_desc: "effective E (GPa)".into(), x_range, y_range: padded(ys, 0.08, 0.7), y_log: false, series, legend: Some(SeriesLabelPosition::UpperRight) };
    let two = |quantity: &str, scale: f64, y_desc: &str, log: bool| -> Panel {
        let tr = |v: f64| if log { v.max(1e-300).log10() } else { v };
        let mut series = Vec::new();
        let mut ys = if log { vec![] } else { vec![0.0] };
        for (k, s) in structures.iter().enumerate() {
            for (t, (test, marker)) in [("tension", Marker::Circle), ("compression", Marker::Triangle)].iter().enumerate() {
                let (mut m, mut d) = get(s, &format!("{quantity}_{test}"));
                // A strength whose runs ended at max_events is a lower bound: a cross.
                let mut marker = *marker;
                let mut label = test.to_string();
                if !m.is_finite() {
                    (m, d) = get(s, &format!("{quantity}_{test}_lower_bound"));
                    marker = Marker::Cross;
                    label = format!("{test}, lower bound");
                }
                if !m.is_finite() {
                    continue;
                }
                let x = k as f64 + 1.0 + (t as f64 - 0.5) * 0.2;
                let (lo, hi) = (tr(((m - d) * scale).max(m * scale * 1e-3)), tr((m + d) * scale));
                ys.extend([lo, hi]);
                series.push(Series { label: None, points: vec![(x, lo), (x, hi)], colour: colour(t + 1), kind: Kind::Line(0.8) });
                let shown = series.iter().any(|x: &Series| x.label.as_deref() == Some(label.as_str()));
                series.push(Series { label: (!shown).then_some(label), points: vec![(x, tr(m * scale))], colour: colour(t + 1), kind: Kind::Markers(marker, 2.2) });
            }
        }
        let y_range = if log { let (a, b) = padded(ys, 0.1, 0.6); (a.floor(), b.ceil()) } else { padded(ys, 0.0, 0.35) };
        Panel { x_categories: labels.clone(), x_desc: String::new(), y_desc: y_desc.into(), x_range, y_range, y_log: log, series, legend: Some(SeriesLabelPosition::UpperRight) }
    };
    let a_panel = two("above_strength", 100.0, "area above strength (%)", false);
    let f_panel = two("first_failure", 1e-6, "first-failure stress (MPa)", true);
    if q.iter().any(|x| x.starts_with("strength_")) {
        let s_panel = two("strength", 1e-6, "strength, progressive (MPa)", true);
        return figure("comparison", width_cm, 1.9, &[(e_panel, 0.25), (a_panel, 0.25), (f_panel, 0.25), (s_panel, 0.25)]);
    }
    figure("comparison", width_cm, 1.5, &[(e_panel, 0.34), (a_panel, 0.33), (f_panel, 0.33)])
}

/// The applied stress at which each pixel cracks, against the number of pixels cracked so far,
/// for the first realisation of each structure, one panel per test: rising where the cell
/// carries more load after a crack, falling where a crack runs on by itself; the highest point is
/// the cell's strength.
fn failure_curves(ev: &Table, dir: &Path, width_cm: f64) -> Result<Drawn> {
    let (st, re, te, s, n) = (ev.s("structure")?, ev.f("realisation")?, ev.s("test")?, ev.f("applied_stress_pa")?, ev.f("event")?);
    let labels_of = structure_labels(dir)?;
    let structures = distinct(&st);
    let mut panels = Vec::new();
    for (ti, test) in ["tension", "compression"].iter().enumerate() {
        let mut series = Vec::new();
        let (mut xs, mut ys) = (vec![0.0], vec![0.0]);
        for (si, name) in structures.iter().enumerate() {
            let pts: Vec<(f64, f64)> = (0..st.len()).filter(|&k| &st[k] == name && te[k] == *test && re[k] == 0.0).map(|k| (n[k] + 1.0, 1e-6 * s[k])).collect();
            if pts.is_empty() {
                continue;
            }
            xs.extend(pts.iter().map(|p| p.0));
            ys.extend(pts.iter().map(|p| p.1));
            series.push(Series::line((ti == 0).then(|| labels_of(name)), pts, colour(si), 0.8));
        }
        panels.push(Panel {
            x_categories: vec![],
            x_desc: format!("cracked pixels, {test}"),
            y_desc: "|Σxx| at the crack (MPa)".into(),
            x_range: padded(xs, 0.0, 0.03),
            y_range: padded(ys, 0.0, 0.25),
            y_log: false,
            series,
            legend: (ti == 0).then_some(SeriesLabelPosition::UpperRight),
        });
    }
    let panels: Vec<(Panel, f64)> = panels.into_iter().map(|p| (p, 0.5)).collect();
    figure("failure_curves", width_cm, 1.3, &panels)
}

/// The cracked pixels of the first realisation in one test, coloured by the order they cracked
/// in, over the phases in pale tones with their boundaries.
fn crack_map(name: &str, map: &Table, ev: &Table, structure: &str, test: &str, phases: &[String], width_cm: f64) -> Result<Drawn> {
    let MapCells { w, h, block, i, j } = cells(map)?;
    let ph = map.s("phase")?;
    let index = |p: &str| phases.iter().position(|q| q == p).unwrap_or(0);
    let pale = |c: RGBColor| RGBColor(((c.0 as u16 + 3 * 255) / 4) as u8, ((c.1 as u16 + 3 * 255) / 4) as u8, ((c.2 as u16 + 3 * 255) / 4) as u8);
    let background: Vec<RGBColor> = ph.iter().map(|p| pale(colour(index(p)))).collect();
    let edges = boundaries(&i, &j, &ph, block, (w, h));
    let (st, re, te, ci, cj, px, order) = (ev.s("structure")?, ev.f("realisation")?, ev.s("test")?, ev.f("i")?, ev.f("j")?, ev.f("pixel_m")?, ev.f("event")?);
    let cracks: Vec<(f64, f64, f64, f64)> = (0..st.len()).filter(|&k| st[k] == structure && te[k] == test && re[k] == 0.0).map(|k| (ci[k] * px[k] * 1e6, cj[k] * px[k] * 1e6, px[k] * 1e6, order[k])).collect();
    let last = cracks.iter().map(|c| c.3).fold(1.0, f64::max);
    let colour_of = |v: f64| viridis(v / last);
    let spec = MapSpec { name, width_cm, x: (0.0, w, "x (µm)"), y: (0.0, h, "y (µm)"), labels: (5, 5), bar: (0.0, last, &format!("crack order in {test}")), colour: &colour_of, categories: None };
    map_figure(&spec, |chart| {
        draw_runs(chart, name, (w, h), &i, &j, block, &background)?;
        let style = RGBColor(90, 90, 90).stroke_width(super::panel::pt(0.3));
        chart.draw_series(edges.into_iter().map(|e| PathElement::new(e, style))).map_err(fig_err(name))?;
        // Each cracked pixel, at least a block wide so that it shows on a coarsened map.
        let side = |p: f64| p.max(block);
        chart
            .draw_series(cracks.iter().map(|&(x, y, p, k)| Rectangle::new([(x, y), ((x + side(p)).min(w), (y + side(p)).min(h))], colour_of(k).filled())))
            .map_err(fig_err(name))?;
        Ok(())
    })
}

//! Figures of a crush report (`kind = "crush"`), drawn from the report's tables only.
//!
//! | file stem | deliverable | table(s) |
//! |---|---|---|
//! | `crush_force_displacement` | Figs. 6b, 9c (F–δ per case, fracture marked) | `curves.csv`, `crush_summary.csv` |
//! | `crush_strain_map` | Fig. 6c (max principal log strain, whole section) | `fields.csv` |
//! | `crush_strain_map_contact` | Fig. 8 bottom (the same, contact region) | `fields.csv` |
//! | `crush_depth_profile` | Fig. 8 top (principal strains below the contact vs depth) | `depth_profile.csv` |
//!
//! The strain maps show the first case's last snapshot; their colour range is ± the 98th
//! percentile of |ε₁| in the window (larger values take the end colours).

use std::path::Path;

use plotters::prelude::*;

use super::{Rendered, Table};
use super::canvas::{colour, fig_err};
use super::map::{MapSpec, map_figure};
use super::panel::{Kind, Marker, Panel, Series, figure, padded};
use crate::error::Result;

type Drawn = (super::canvas::Encoded, usize);

/// Draws every crush figure in `dir`.
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let fields = Table::load(dir, "fields")?;
    let fields = &fields;
    let mut figures: Vec<super::Figure<Drawn>> = vec![("crush_force_displacement", Box::new(|| force_displacement(dir, width_cm)))];
    if fields.df.height() > 0 {
        figures.push(("crush_strain_map", Box::new(|| strain_map("crush_strain_map", fields, width_cm, 1.0))));
        figures.push(("crush_strain_map_contact", Box::new(|| strain_map("crush_strain_map_contact", fields, width_cm, 0.35))));
        figures.push(("crush_depth_profile", Box::new(|| depth_profile(dir, width_cm))));
    }
    super::write_figures(dir, super::draw_all(figures)?)
}

fn force_displacement(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let t = Table::load(dir, "curves")?;
    // Plane-strain reports carry forces per unit thickness (N/m), drawn in N/mm.
    let plane = t.has("force_n_per_m");
    let (fcol, pcol, scale, y_desc) =
        if plane { ("force_n_per_m", "peak_force_n_per_m", 1e-3, "Force per thickness F/L (N/mm)") } else { ("force_n", "peak_force_n", 1.0, "Platen force F (N)") };
    let (labels, d) = (t.s("label")?, t.f("displacement_m")?);
    let f: Vec<f64> = t.f(fcol)?.iter().map(|v| v * scale).collect();
    let s = Table::load(dir, "crush_summary")?;
    let (skeys, at, frac) = (s.s("case")?, s.f("peak_displacement_m")?, s.f("fracture_displacement_m")?);
    let peak: Vec<f64> = s.f(pcol)?.iter().map(|v| v * scale).collect();
    let mut series = Vec::new();
    let mut marks = Vec::new();
    for (ci, (key, idx)) in t.groups_by("case")?.iter().enumerate() {
        let pts: Vec<(f64, f64)> = idx.iter().map(|&i| (1e6 * d[i], f[i])).collect();
        series.push(Series::line(Some(labels[idx[0]].clone()), pts, colour(ci), 1.0));
        if let Some(k) = skeys.iter().position(|s| s == key)
            && frac[k].is_finite()
        {
            marks.push((1e6 * at[k], peak[k], colour(ci)));
        }
    }
    if !marks.is_empty() {
        for (i, (x, y, c)) in marks.iter().enumerate() {
            let label = if i == 0 { Some("fracture (first sustained drop)".to_string()) } else { None };
            series.push(Series { label, points: vec![(*x, *y)], colour: *c, kind: Kind::Markers(Marker::Circle, 2.0) });
        }
    }
    let panel = Panel {
        x_categories: vec![],
        x_desc: "Total crush displacement δ (µm)".into(),
        y_desc: y_desc.into(),
        x_range: padded(d.iter().map(|x| 1e6 * x), 0.0, 0.02),
        y_range: (0.0, padded(f.iter().cloned(), 0.0, 0.3).1),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperLeft),
    };
    figure("crush_force_displacement", width_cm, 0.75, &[(panel, 1.0)])
}

/// Diverging blue–white–red map for t ∈ [−1, 1] (compression blue, tension red).
pub(crate) fn diverging(t: f64) -> RGBColor {
    let t = if t.is_finite() { t.clamp(-1.0, 1.0) } else { 0.0 };
    let (a, b) = if t < 0.0 { ((59.0, 76.0, 192.0), (247.0, 247.0, 247.0)) } else { ((247.0, 247.0, 247.0), (180.0, 4.0, 38.0)) };
    let f = if t < 0.0 { t + 1.0 } else { t };
    let m = |x: f64, y: f64| (x + f * (y - x)).round() as u8;
    RGBColor(m(a.0, b.0), m(a.1, b.1), m(a.2, b.2))
}

/// Max principal log strain of the first case's last snapshot, mirrored about the axis; the
/// window is `zoom` × the particle (1 = whole section; < 1 = the contact region, 1.4 times as
/// deep as wide).
fn strain_map(name: &str, t: &Table, width_cm: f64, zoom: f64) -> Result<Drawn> {
    let keys = t.s("case")?;
    let disp = t.f("displacement_m")?;
    let key = keys[0].clone();
    let d0 = (0..keys.len()).filter(|&i| keys[i] == key).map(|i| disp[i]).fold(0.0, f64::max);
    let idx: Vec<usize> = (0..keys.len()).filter(|&i| keys[i] == key && disp[i] == d0).collect();
    let cols: Vec<Vec<f64>> = ["r1_m", "z1_m", "r2_m", "z2_m", "r3_m", "z3_m", "r4_m", "z4_m"].iter().map(|c| t.f(c)).collect::<Result<_>>()?;
    let val: Vec<f64> = t.f("max_principal_log_strain")?.iter().map(|v| 1e3 * v).collect();
    let r_max = idx.iter().flat_map(|&i| [cols[0][i], cols[2][i], cols[4][i], cols[6][i]]).fold(0.0, f64::max);
    let r_min = idx.iter().flat_map(|&i| [cols[0][i], cols[2][i], cols[4][i], cols[6][i]]).fold(0.0, f64::min);
    let z_max = idx.iter().flat_map(|&i| [cols[1][i], cols[3][i], cols[5][i], cols[7][i]]).fold(0.0, f64::max);
    // An axisymmetric quarter (r ≥ 0) is mirrored about the axis; a plane-strain section is whole.
    let mirror = r_min >= 0.0;
    let r_max = r_max.max(-r_min);
    // Centred on the top contact: the axis of a quarter, the highest vertex of a section.
    let x_c = if mirror {
        0.0
    } else {
        let cols = &cols;
        idx.iter().flat_map(|&i| (0..4).map(move |k| (cols[2 * k][i], cols[2 * k + 1][i]))).fold((0.0, f64::MIN), |m, p| if p.1 > m.1 { p } else { m }).0
    };
    let (x_lo, x_hi) = (1e3 * (x_c - zoom * r_max), 1e3 * (x_c + zoom * r_max));
    let depth = if zoom < 1.0 { 1.4 * zoom } else { 1.0 };
    let z_min = idx.iter().flat_map(|&i| [cols[1][i], cols[3][i], cols[5][i], cols[7][i]]).fold(0.0, f64::min);
    let y_lo = if !mirror && zoom >= 1.0 { z_min * 1e3 * 1.02 } else { z_max * (1.0 - depth) * 1e3 };
    let y_hi = z_max * 1e3 * (1.0 + 0.02 * depth);
    // Colour range: ±the 98th percentile of |ε₁| in the window, so that a few crushed elements
    // under the platen do not wash out the rest; larger values take the end colours.
    let in_window = |i: usize| {
        let (x, z) = ((0..4).map(|k| cols[2 * k][i]).sum::<f64>() * 250.0, (0..4).map(|k| cols[2 * k + 1][i]).sum::<f64>() * 250.0);
        (mirror || (x_lo..=x_hi).contains(&x)) && (y_lo..=y_hi).contains(&z)
    };
    let mut mags: Vec<f64> = idx.iter().filter(|&&i| in_window(i)).map(|&i| val[i].abs()).filter(|v| v.is_finite()).collect();
    mags.sort_by(f64::total_cmp);
    let vmax = mags.get(((mags.len() as f64 * 0.98) as usize).min(mags.len().saturating_sub(1))).copied().unwrap_or(1e-12).max(1e-12);
    let x_desc = if mirror { "radius r (mm)" } else { "x (mm)" };
    let bar_desc = format!("ε₁ (‰) at δ = {:.0} µm", d0 * 1e6);
    let colour = |v: f64| diverging(v / vmax);
    let spec = MapSpec {
        name,
        width_cm,
        x: (x_lo, x_hi, x_desc),
        y: (y_lo, y_hi, "height z (mm)"),
        labels: (5, 5),
        bar: (-vmax, vmax, &bar_desc),
        colour: &colour,
        categories: None,
    };
    map_figure(&spec, |chart| {
        for sign in if mirror { vec![1.0, -1.0] } else { vec![1.0] } {
            chart
                .draw_series(idx.iter().map(|&i| {
                    let poly: Vec<(f64, f64)> = (0..4).map(|k| (sign * 1e3 * cols[2 * k][i], 1e3 * cols[2 * k + 1][i])).collect();
                    Polygon::new(poly, colour(val[i]).filled())
                }))
                .map_err(fig_err(name))?;
        }
        Ok(())
    })
}

fn depth_profile(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let t = Table::load(dir, "depth_profile")?;
    let (keys, disp, depth) = (t.s("case")?, t.f("displacement_m")?, t.f("depth_m")?);
    let (emax, emin) = (t.f("max_principal_log_strain")?, t.f("min_principal_log_strain")?);
    let key = keys[0].clone();
    let mut snaps: Vec<f64> = (0..keys.len()).filter(|&i| keys[i] == key).map(|i| disp[i]).collect();
    snaps.dedup();
    let mut series = Vec::new();
    let mut xs = Vec::new();
    for (si, &d) in snaps.iter().enumerate() {
        let idx: Vec<usize> = (0..keys.len()).filter(|&i| keys[i] == key && disp[i] == d).collect();
        let tens: Vec<(f64, f64)> = idx.iter().map(|&i| (1e6 * depth[i], 1e3 * emax[i])).collect();
        let comp: Vec<(f64, f64)> = idx.iter().map(|&i| (1e6 * depth[i], 1e3 * emin[i])).collect();
        xs.extend(tens.iter().chain(&comp).map(|p| p.1));
        series.push(Series::line(Some(format!("δ = {:.0} µm", d * 1e6)), tens, colour(si), 1.0));
        series.push(Series { label: None, points: comp, colour: colour(si), kind: Kind::Dashed(1.0, 3.0, 2.0) });
    }
    let r_max = depth.iter().cloned().fold(0.0, f64::max);
    let panel = Panel {
        x_categories: vec![],
        x_desc: "Depth below the platen (µm)".into(),
        y_desc: "ε₁ (solid), ε₃ (dashed) under the contact (‰)".into(),
        x_range: (0.0, 1e6 * (0.5 * r_max)),
        y_range: padded(xs, 0.05, 0.35),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::LowerRight),
    };
    figure("crush_depth_profile", width_cm, 0.8, &[(panel, 1.0)])
}

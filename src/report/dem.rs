//! Figures of a DEM report (`kind = "dem"`), drawn from the report's tables only.
//!
//! | file stem | deliverable | table(s) |
//! |---|---|---|
//! | `dem_velocity_profile` | Fig. 4 right (oscillating mean velocity) | `velocity_profile.csv`, `tubes.csv` |
//! | `dem_speed_map` | Fig. 4 left (mean speed between the tubes) | `speed_map.csv`, `tubes.csv` |
//! | `dem_impact_spectra` | impact velocities per row (§3) | `impacts.parquet` |
//! | `dem_force_time` | Fig. 5 (force and cumulative force of one impact) | `force_trace.csv` |

use std::path::Path;

use plotters::prelude::*;

use super::{Rendered, Table};
use super::canvas::{colour, fig_err};
use super::map::{MapSpec, map_figure};
use super::panel::{Kind, Panel, Series, figure, padded, pt};
use crate::error::{Error, Result};
use crate::io::{col_f64, col_str};

fn tubes(dir: &Path) -> Result<Vec<(f64, f64, f64, u32)>> {
    let t = Table::load(dir, "tubes")?;
    let x = t.f("x_m")?;
    let z = t.f("z_m")?;
    let r = t.f("radius_m")?;
    let row = t.f("row")?;
    Ok((0..x.len()).map(|k| (x[k], z[k], r[k], row[k] as u32)).collect())
}

/// Draws every DEM figure in `dir`.
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let mut figures = vec![
        ("dem_velocity_profile", velocity_profile(dir, width_cm)?),
        ("dem_speed_map", speed_map(dir, width_cm)?),
        ("dem_impact_spectra", impact_spectra(dir, width_cm)?),
    ];
    // A run too short to trace a tube impact has no Fig. 5 (the summary says so).
    if let Some(f) = force_time(dir, width_cm)? {
        figures.push(("dem_force_time", f));
    }
    super::write_figures(dir, figures)
}

type Drawn = (super::canvas::Encoded, usize);

fn velocity_profile(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let t = Table::load(dir, "velocity_profile")?;
    let z = t.f("z_m")?;
    let vz = t.f("mean_vz_m_s")?;
    let pts: Vec<(f64, f64)> = z.iter().zip(&vz).filter(|(_, v)| v.is_finite()).map(|(&z, &v)| (-v, 1e3 * z)).collect();
    let tubes = tubes(dir)?;
    let (x0, x1) = padded(pts.iter().map(|q| q.0).chain([0.0]), 0.02, 0.08);
    let (y0, y1) = padded(pts.iter().map(|q| q.1).chain([0.0]), 0.0, 0.02);
    let mut series = Vec::new();
    let mut rows: Vec<(u32, f64, f64)> = Vec::new();
    for &(_, z, r, row) in &tubes {
        if !rows.iter().any(|x| x.0 == row) {
            rows.push((row, z, r));
        }
    }
    for (k, &(_, z, r)) in rows.iter().enumerate() {
        series.push(Series {
            label: (k == 0).then(|| "tube rows".to_string()),
            points: vec![(x0, 1e3 * (z - r)), (x1, 1e3 * (z - r))],
            colour: RGBColor(150, 150, 150),
            kind: Kind::Band(vec![1e3 * (z + r), 1e3 * (z + r)], 0.35),
        });
    }
    series.push(Series::line(Some("mean −v_z".into()), pts, colour(0), 1.2));
    let panel = Panel {
        x_categories: vec![],
        x_desc: "mean downward velocity −v_z (m/s)".into(),
        y_desc: "height z (mm)".into(),
        x_range: (x0, x1),
        y_range: (y0, y1),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    figure("dem_velocity_profile", width_cm, 1.25, &[(panel, 1.0)])
}

/// Perceptually uniform colour map (viridis anchors, linear interpolation).
pub(crate) fn viridis(t: f64) -> RGBColor {
    const AT: [f64; 6] = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0];
    const RGB: [[f64; 6]; 3] = [[68.0, 65.0, 42.0, 34.0, 122.0, 253.0], [1.0, 68.0, 120.0, 168.0, 209.0, 231.0], [84.0, 135.0, 142.0, 132.0, 81.0, 37.0]];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let at = crate::stats::locate(&AT, t);
    let m = |c: &[f64; 6]| crate::stats::lerp(c, at).round() as u8;
    RGBColor(m(&RGB[0]), m(&RGB[1]), m(&RGB[2]))
}

fn speed_map(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let name = "dem_speed_map";
    let t = Table::load(dir, "speed_map")?;
    let x = t.f("x_m")?;
    let z = t.f("z_m")?;
    let dx = t.f("cell_dx_m")?;
    let dz = t.f("cell_dz_m")?;
    let s = t.f("mean_speed_m_s")?;
    let tubes = tubes(dir)?;
    let tt = Table::load(dir, "tubes")?;
    let width = tt.f("width_m")?.first().copied().unwrap_or(0.125);
    let top = tt.f("domain_top_m")?.first().copied().unwrap_or(0.3);
    let vmax = s.iter().cloned().filter(|v| v.is_finite()).fold(0.0, f64::max).max(1e-9);
    let colour = |v: f64| viridis(v / vmax);
    let spec = MapSpec {
        name,
        width_cm,
        x: (0.0, 1e3 * width, "x (mm)"),
        y: (0.0, 1e3 * top, "height z (mm)"),
        labels: (4, 8),
        bar: (0.0, vmax, "mean speed (m/s)"),
        colour: &colour,
        categories: None,
    };
    map_figure(&spec, |chart| {
        let err = fig_err(name);
        chart
            .draw_series((0..x.len()).filter(|&k| s[k].is_finite()).map(|k| {
                // Cells overlap by 3 % so that anti-aliasing leaves no seams between them.
                let (hx, hz) = (0.53 * dx[k], 0.53 * dz[k]);
                Rectangle::new([(1e3 * (x[k] - hx).max(0.0), 1e3 * (z[k] - hz).max(0.0)), (1e3 * (x[k] + hx).min(width), 1e3 * (z[k] + hz).min(top))], colour(s[k]).filled())
            }))
            .map_err(&err)?;
        for &(tx, tz, r, _) in &tubes {
            let poly: Vec<(f64, f64)> = (0..=72)
                .map(|k| {
                    let a = k as f64 / 72.0 * std::f64::consts::TAU;
                    ((1e3 * (tx + r * a.cos())).clamp(0.0, 1e3 * width), 1e3 * (tz + r * a.sin()))
                })
                .collect();
            chart.draw_series(std::iter::once(Polygon::new(poly.clone(), RGBColor(200, 200, 200).filled()))).map_err(&err)?;
            chart.draw_series(std::iter::once(PathElement::new(poly, BLACK.stroke_width(pt(0.4))))).map_err(&err)?;
        }
        Ok(())
    })
}

fn cdf(mut v: Vec<f64>) -> Vec<(f64, f64)> {
    v.sort_by(f64::total_cmp);
    let n = v.len() as f64;
    // At most ~400 points per curve: every k-th order statistic.
    let step = (v.len() / 400).max(1);
    let mut out: Vec<(f64, f64)> = v.iter().enumerate().step_by(step).map(|(i, &x)| (x, (i + 1) as f64 / n)).collect();
    if let Some(&last) = v.last()
        && out.last().map(|q| q.0) != Some(last)
    {
        out.push((last, 1.0));
    }
    out
}

fn impact_spectra(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let path = dir.join("impacts.parquet");
    let file = std::fs::File::open(&path).map_err(|e| Error::read(&path, e))?;
    use polars::prelude::SerReader;
    let df = polars::prelude::ParquetReader::new(file)
        .finish()
        .map_err(|e| Error::data_file(&path, "file", format!("not a readable Parquet file: {e}")))?;
    let target = col_str(&df, &path, "target")?;
    let row = col_f64(&df, &path, "row")?;
    let v = col_f64(&df, &path, "v_normal_m_s")?;
    let rows = tubes(dir)?.iter().map(|t| t.3).max().unwrap_or(0);
    let vmax = padded(v.iter().cloned().chain([0.0]), 0.0, 0.03).1;
    let mut panels = Vec::new();
    for (tname, desc) in [("tube", "tube impacts"), ("particle", "particle impacts")] {
        let mut series = Vec::new();
        for r in 1..=rows {
            let sel: Vec<f64> = (0..v.len()).filter(|&i| target[i] == tname && row[i] as u32 == r).map(|i| v[i]).collect();
            if sel.len() < 5 {
                continue;
            }
            series.push(Series::line(Some(format!("row {r} (n = {})", sel.len())), cdf(sel), colour(r as usize - 1), 1.0));
        }
        panels.push((
            Panel {
                x_categories: vec![],
                x_desc: "normal impact velocity at first contact (m/s)".into(),
                y_desc: format!("CDF, {desc}"),
                x_range: (0.0, vmax),
                y_range: (0.0, 1.02),
                y_log: false,
                series,
                legend: Some(SeriesLabelPosition::LowerRight),
            },
            0.5,
        ));
    }
    figure("dem_impact_spectra", width_cm, 1.35, &panels)
}

fn force_time(dir: &Path, width_cm: f64) -> Result<Option<Drawn>> {
    let trace = Table::load(dir, "force_trace")?;
    let t = trace.f("time_s")?;
    let f = trace.f("normal_force_n")?;
    let c = trace.f("cumulative_impulse_n_s")?;
    let modulus = trace.f("youngs_modulus_pa")?.first().copied().unwrap_or(f64::NAN);
    let v0 = trace.f("v_normal_m_s")?.first().copied().unwrap_or(f64::NAN);
    if t.len() < 3 {
        return Ok(None);
    }
    let tf: Vec<(f64, f64)> = t.iter().zip(&f).map(|(&t, &f)| (1e6 * t, f)).collect();
    let tc: Vec<(f64, f64)> = t.iter().zip(&c).map(|(&t, &c)| (1e6 * t, 1e6 * c)).collect();
    let xr = padded(tf.iter().map(|q| q.0), 0.0, 0.02);
    let p1 = Panel {
        x_categories: vec![],
        x_desc: "time since first contact (µs)".into(),
        y_desc: "normal force (N)".into(),
        x_range: xr,
        y_range: padded(tf.iter().map(|q| q.1).chain([0.0]), 0.02, 0.08),
        y_log: false,
        series: vec![Series::line(Some(format!("DEM, E = {:.2} GPa, v_n = {:.2} m/s", modulus / 1e9, v0)), tf, colour(0), 1.2)],
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    let p2 = Panel {
        x_categories: vec![],
        x_desc: "time since first contact (µs)".into(),
        y_desc: "∫F dt (µN·s)".into(),
        x_range: xr,
        y_range: padded(tc.iter().map(|q| q.1).chain([0.0]), 0.02, 0.08),
        y_log: false,
        series: vec![Series::line(Some("cumulative force".into()), tc, colour(1), 1.2)],
        legend: Some(SeriesLabelPosition::LowerRight),
    };
    figure("dem_force_time", width_cm, 1.2, &[(p1, 0.5), (p2, 0.5)]).map(Some)
}

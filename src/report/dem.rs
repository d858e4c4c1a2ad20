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

use super::Rendered;
use super::canvas::{FONT, canvas_size, check_glyphs, colour, encode, fig_err, register_fonts, text, tick_format};
use super::panel::{Kind, Panel, Series, figure, padded, pt};
use crate::error::{Error, Result};
use crate::io::{col_f64, col_str, read_table};

fn load(dir: &Path, name: &str) -> Result<(std::path::PathBuf, polars::prelude::DataFrame)> {
    let path = dir.join(name);
    Ok((path.clone(), read_table(&path)?))
}

fn tubes(dir: &Path) -> Result<Vec<(f64, f64, f64, u32)>> {
    let (p, df) = load(dir, "tubes.csv")?;
    let x = col_f64(&df, &p, "x_m")?;
    let z = col_f64(&df, &p, "z_m")?;
    let r = col_f64(&df, &p, "radius_m")?;
    let row = col_f64(&df, &p, "row")?;
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
    let (p, df) = load(dir, "velocity_profile.csv")?;
    let z = col_f64(&df, &p, "z_m")?;
    let vz = col_f64(&df, &p, "mean_vz_m_s")?;
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
    const A: [(f64, (u8, u8, u8)); 6] =
        [(0.0, (68, 1, 84)), (0.2, (65, 68, 135)), (0.4, (42, 120, 142)), (0.6, (34, 168, 132)), (0.8, (122, 209, 81)), (1.0, (253, 231, 37))];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    for w in A.windows(2) {
        if t <= w[1].0 {
            let f = (t - w[0].0) / (w[1].0 - w[0].0);
            let m = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
            return RGBColor(m(w[0].1.0, w[1].1.0), m(w[0].1.1, w[1].1.1), m(w[0].1.2, w[1].1.2));
        }
    }
    RGBColor(253, 231, 37)
}

fn speed_map(dir: &Path, width_cm: f64) -> Result<Drawn> {
    let name = "dem_speed_map";
    let (p, df) = load(dir, "speed_map.csv")?;
    let x = col_f64(&df, &p, "x_m")?;
    let z = col_f64(&df, &p, "z_m")?;
    let dx = col_f64(&df, &p, "cell_dx_m")?;
    let dz = col_f64(&df, &p, "cell_dz_m")?;
    let s = col_f64(&df, &p, "mean_speed_m_s")?;
    let tubes = tubes(dir)?;
    let (tp, tdf) = load(dir, "tubes.csv")?;
    let width = col_f64(&tdf, &tp, "width_m")?.first().copied().unwrap_or(0.125);
    let top = col_f64(&tdf, &tp, "domain_top_m")?.first().copied().unwrap_or(0.3);
    let vmax = s.iter().cloned().filter(|v| v.is_finite()).fold(0.0, f64::max).max(1e-9);
    // Equal data aspect: the plotting area (left 80 % of the canvas less margins and label
    // areas, as laid out below) gets the domain's height/width ratio.
    register_fonts()?;
    let w_px = canvas_size(width_cm, 1.0).0 as f64;
    let plot_w = 0.8 * w_px - pt(33.0) as f64;
    let h_px = plot_w * top / width + pt(27.0) as f64;
    let size = canvas_size(width_cm, h_px / w_px);
    let mut svg = String::new();
    let x_desc = "x (mm)";
    let y_desc = "height z (mm)";
    let bar_desc = "mean speed (m/s)";
    for t in [x_desc, y_desc, bar_desc] {
        check_glyphs(name, t)?;
    }
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(fig_err(name))?;
        let (left, right) = root.split_horizontally((size.0 as f64 * 0.80) as u32);
        let err = fig_err(name);
        let mut chart = ChartBuilder::on(&left)
            .margin_top(pt(6.0))
            .margin_right(pt(4.0))
            .margin_left(pt(2.0))
            .margin_bottom(pt(2.0))
            .x_label_area_size(pt(19.0))
            .y_label_area_size(pt(27.0))
            .build_cartesian_2d(0.0..1e3 * width, 0.0..1e3 * top)
            .map_err(&err)?;
        let xf = tick_format(0.0, 1e3 * width);
        let yf = tick_format(0.0, 1e3 * top);
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .label_style(text(7.0))
            .axis_desc_style(text(8.0))
            .x_labels(4)
            .y_labels(8)
            .x_label_formatter(&xf)
            .y_label_formatter(&yf)
            .disable_mesh()
            .axis_style(BLACK.stroke_width(pt(0.5)))
            .draw()
            .map_err(&err)?;
        chart
            .draw_series((0..x.len()).filter(|&k| s[k].is_finite()).map(|k| {
                let c = viridis(s[k] / vmax);
                // Cells overlap by 3 % so that anti-aliasing leaves no seams between them.
                let (hx, hz) = (0.53 * dx[k], 0.53 * dz[k]);
                Rectangle::new([(1e3 * (x[k] - hx).max(0.0), 1e3 * (z[k] - hz).max(0.0)), (1e3 * (x[k] + hx).min(width), 1e3 * (z[k] + hz).min(top))], c.filled())
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
        // Colour bar.
        let mut bar = ChartBuilder::on(&right)
            .margin_top(pt(6.0))
            .margin_right(pt(2.0))
            .margin_left(pt(4.0))
            .margin_bottom(pt(2.0))
            .x_label_area_size(pt(19.0))
            .y_label_area_size(pt(0.0))
            .right_y_label_area_size(pt(22.0))
            .build_cartesian_2d(0.0..1.0, 0.0..vmax)
            .map_err(&err)?
            .set_secondary_coord(0.0..1.0, 0.0..vmax);
        bar.draw_series((0..100).map(|k| {
            let a = vmax * k as f64 / 100.0;
            let b = vmax * (k + 1) as f64 / 100.0;
            Rectangle::new([(0.0, a), (1.0, b)], viridis((k as f64 + 0.5) / 100.0).filled())
        }))
        .map_err(&err)?;
        let bf = tick_format(0.0, vmax);
        bar.configure_secondary_axes()
            .y_desc(bar_desc)
            .label_style(text(7.0))
            .axis_desc_style(text(8.0))
            .y_labels(6)
            .y_label_formatter(&bf)
            .x_labels(0)
            .axis_style(BLACK.stroke_width(pt(0.5)))
            .draw()
            .map_err(&err)?;
        root.present().map_err(fig_err(name))?;
    }
    let _ = FONT;
    Ok((encode(name, &svg, size, width_cm)?, 0))
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
    let (p, df) = load(dir, "force_trace.csv")?;
    let t = col_f64(&df, &p, "time_s")?;
    let f = col_f64(&df, &p, "normal_force_n")?;
    let c = col_f64(&df, &p, "cumulative_impulse_n_s")?;
    let modulus = col_f64(&df, &p, "youngs_modulus_pa")?.first().copied().unwrap_or(f64::NAN);
    let v0 = col_f64(&df, &p, "v_normal_m_s")?.first().copied().unwrap_or(f64::NAN);
    if t.len() < 3 {
        return Ok(None);
    }
    let tf: Vec<(f64, f64)> = t.iter().zip(&f).map(|(&t, &f)| (1e6 * t, f)).collect();
    let tc: Vec<(f64, f64)> = t.iter().zip(&c).map(|(&t, &c)| (1e6 * t, 1e6 * c)).collect();
    let xr = padded(tf.iter().map(|q| q.0), 0.0, 0.02);
    let p1 = Panel {
        x_desc: "time since first contact (µs)".into(),
        y_desc: "normal force (N)".into(),
        x_range: xr,
        y_range: padded(tf.iter().map(|q| q.1).chain([0.0]), 0.02, 0.08),
        y_log: false,
        series: vec![Series::line(Some(format!("DEM, E = {:.2} GPa, v_n = {:.2} m/s", modulus / 1e9, v0)), tf, colour(0), 1.2)],
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    let p2 = Panel {
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

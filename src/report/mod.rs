//! Figures of a lifetime report, drawn from the report's tables only, so
//! `partlife report <name>` redraws without re-simulating.
//!
//! | file stem | deliverable | table(s) |
//! |---|---|---|
//! | `fig05_force_time` | Fig. 5 | `force_time.csv` |
//! | `fig13_stress_profile` | Fig. 13 right | `stress_profile.csv`, `stress_profile_summary.csv` |
//! | `fig14_sigma_vs_diameter` | Fig. 14 left | `particles.csv`, `size_trend.csv` |
//! | `fig14_weibull_cdf` | Fig. 14 right | `weibull_points.csv`, `weibull_cdf.csv`, `weibull_fits.csv` |
//! | `fig15_impact` | Fig. 15 | `impact_curves.csv` |
//! | `fig16_breakage` | Fig. 16 | `breakage_curves.csv`, `lifetime_summary.csv` |
//!
//! Each figure is written as SVG (with its physical size), PNG (300 dpi) and vector PDF with the
//! embedded DejaVu Sans font ([`canvas`]).

pub mod canvas;
pub mod build;
pub mod captions;
pub mod document;
pub mod html;
pub mod layout;
pub mod pdf;
pub mod calibrate;
pub mod crush;
pub mod dem;
pub mod map;
pub mod micro;
pub mod panel;
pub mod uq;
pub mod discrepancy;
pub mod experiments;
pub mod temperature;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use plotters::prelude::SeriesLabelPosition;
use plotters::style::{BLACK, RGBColor};

use crate::error::{Error, Result};
use crate::obs::Censor;
use crate::io::{col_f64, col_str, read_table, write_atomic};
use canvas::{Encoded, colour};
use panel::{Kind, Marker, Panel, Series, figure, padded};

/// A loaded report table with its path (for messages).
/// A report table (`<name>.csv`) with typed column access; shared by every figure module.
pub(crate) struct Table {
    path: PathBuf,
    pub(crate) df: polars::prelude::DataFrame,
}

impl Table {
    pub(crate) fn load(dir: &Path, name: &str) -> Result<Self> {
        Self::load_file(&dir.join(format!("{name}.csv")))
    }
    pub(crate) fn load_file(path: &Path) -> Result<Self> {
        Ok(Table { df: read_table(path)?, path: path.to_path_buf() })
    }
    pub(crate) fn f(&self, col: &str) -> Result<Vec<f64>> {
        col_f64(&self.df, &self.path, col)
    }
    pub(crate) fn s(&self, col: &str) -> Result<Vec<String>> {
        col_str(&self.df, &self.path, col)
    }
    /// The rows whose text column `col` equals `value`.
    pub(crate) fn filter(self, col: &str, value: &str) -> Result<Self> {
        let keys = self.s(col)?;
        let mask: polars::prelude::BooleanChunked = keys.iter().map(|k| Some(k == value)).collect();
        let df = self.df.filter(&mask).map_err(|e| Error::data_file(&self.path, col, e.to_string()))?;
        Ok(Table { df, path: self.path })
    }
    /// Whether the table has a column.
    pub(crate) fn has(&self, col: &str) -> bool {
        self.df.get_column_names().iter().any(|c| c.as_str() == col)
    }
    /// Row indices per material key, in first-appearance order.
    fn groups(&self) -> Result<Vec<(String, Vec<usize>)>> {
        self.groups_by("material_key")
    }
    /// Row indices per value of a text column, in first-appearance order.
    pub(crate) fn groups_by(&self, col: &str) -> Result<Vec<(String, Vec<usize>)>> {
        let keys = self.s(col)?;
        let mut out: Vec<(String, Vec<usize>)> = Vec::new();
        for (i, k) in keys.into_iter().enumerate() {
            match out.iter_mut().find(|(kk, _)| *kk == k) {
                Some((_, v)) => v.push(i),
                None => out.push((k, vec![i])),
            }
        }
        Ok(out)
    }
}

/// Material keys and labels in study order (from `weibull_fits.csv`), with colour/marker index.
struct Materials {
    keys: Vec<String>,
    labels: Vec<String>,
}

impl Materials {
    fn load(dir: &Path) -> Result<Self> {
        let t = Table::load(dir, "weibull_fits")?;
        Ok(Materials { keys: t.s("material_key")?, labels: t.s("material")? })
    }
    fn index(&self, key: &str) -> usize {
        self.keys.iter().position(|k| k == key).unwrap_or(self.keys.len())
    }
    fn label(&self, key: &str) -> String {
        self.labels.get(self.index(key)).cloned().unwrap_or_else(|| key.to_string())
    }
    fn colour(&self, key: &str) -> RGBColor {
        colour(self.index(key))
    }
    fn marker(&self, key: &str) -> Marker {
        [Marker::Circle, Marker::Triangle, Marker::Cross][self.index(key) % 3]
    }
}

fn pick(v: &[f64], idx: &[usize]) -> Vec<f64> {
    idx.iter().map(|&i| v[i]).collect()
}

fn zip(x: Vec<f64>, y: Vec<f64>) -> Vec<(f64, f64)> {
    x.into_iter().zip(y).collect()
}

/// Distinct values of a column in order of appearance.
pub(crate) fn distinct<T: PartialEq + Clone>(v: &[T]) -> Vec<T> {
    let mut out: Vec<T> = Vec::new();
    for x in v {
        if !out.contains(x) {
            out.push(x.clone());
        }
    }
    out
}

/// Lowest log₁₀ probability the figures show.
pub(crate) const LG_FLOOR: f64 = -12.0;

/// log₁₀ of a probability for a logarithmic axis, floored at [`LG_FLOOR`].
pub(crate) fn lg(p: f64) -> f64 {
    p.max(1e-300).log10().max(LG_FLOOR)
}

/// What [`render`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    /// Files written, relative to the report directory.
    pub files: Vec<String>,
    /// Per figure: data samples hidden by a legend (0 unless no corner was free).
    pub legend_hidden: Vec<(String, usize)>,
}

/// A probability: three decimals from 0.1 up ("0.871", "1.000"), three significant figures
/// below ("0.0412", "1.23e-5"), "0" for exactly 0.
pub fn prob_text(p: f64) -> String {
    if p == 0.0 {
        "0".into()
    } else if p.abs() < 1e-3 {
        format!("{p:.2e}")
    } else if p.abs() < 0.1 {
        format!("{:.*}", (2.0 - p.abs().log10().floor()) as usize, p)
    } else {
        format!("{p:.3}")
    }
}

/// A bootstrap p-value of `replicates` replicates: at its floor 1/(B + 1) — no replicate reached
/// the observed statistic — "≤ floor", since B replicates resolve nothing smaller; else to three
/// decimals.
pub fn bootstrap_p_text(p: f64, replicates: usize) -> String {
    if replicates > 0 && p <= 1.0 / (replicates as f64 + 1.0) * (1.0 + 1e-9) { format!("≤ {p:.3}") } else { format!("{p:.3}") }
}

/// Value ± error, to the error's precision (at most 4 decimals: "1.0000 ± 0.0000" is a
/// probability within 0.00005 of 1); the value alone, to 4 decimals, without an error.
pub fn pm_text(v: f64, se: f64) -> String {
    if se > 0.0 && se.is_finite() {
        let d = (-(se.log10().floor()) + 1.0).clamp(0.0, 4.0) as usize;
        format!("{v:.d$} ± {se:.d$}")
    } else {
        format!("{v:.4}")
    }
}

/// Draws every figure of the lifetime report in `dir` from its tables.
pub fn render(dir: &Path, width_cm: f64) -> Result<Rendered> {
    let mats = Materials::load(dir)?;
    let mats = &mats;
    let figures: Vec<Figure<Drawn>> = vec![
        ("fig05_force_time", Box::new(|| fig05_force_time(dir, mats, width_cm))),
        ("fig13_stress_profile", Box::new(|| fig13_stress_profile(dir, mats, width_cm))),
        ("fig14_sigma_vs_diameter", Box::new(|| fig14_sigma_vs_diameter(dir, mats, width_cm))),
        ("fig14_weibull_cdf", Box::new(|| fig14_weibull_cdf(dir, mats, width_cm))),
        ("fig15_impact", Box::new(|| fig15_impact(dir, mats, width_cm))),
        ("fig16_breakage", Box::new(|| fig16_breakage(dir, mats, width_cm))),
    ];
    write_figures(dir, draw_all(figures)?)
}

/// A figure to draw: its file stem and the drawing.
pub(crate) type Figure<'a, D> = (&'static str, Box<dyn Fn() -> Result<D> + Send + Sync + 'a>);

/// Draws figures side by side (each reads its own tables and encodes its own files), returning
/// them in the order given; the first error in that order.
pub(crate) fn draw_all<D: Send>(figures: Vec<Figure<'_, D>>) -> Result<Vec<(&'static str, D)>> {
    use rayon::prelude::*;
    let drawn: Vec<Result<D>> = figures.par_iter().map(|(_, draw)| draw()).collect();
    figures.iter().zip(drawn).map(|((name, _), d)| Ok((*name, d?))).collect()
}

/// Writes each drawn figure as `<name>.svg`, `.png` and `.pdf` into `dir`.
pub(crate) fn write_figures(dir: &Path, figures: Vec<(&str, Drawn)>) -> Result<Rendered> {
    let mut files = Vec::new();
    let mut legend_hidden = Vec::new();
    for (name, (enc, hidden)) in figures {
        legend_hidden.push((name.to_string(), hidden));
        for (ext, bytes) in [("svg", enc.svg.as_bytes()), ("png", enc.png.as_slice()), ("pdf", enc.pdf.as_slice())] {
            let file = format!("{name}.{ext}");
            write_atomic(&dir.join(&file), bytes)?;
            files.push(file);
        }
    }
    Ok(Rendered { files, legend_hidden })
}

/// Redraws the figures of an existing report (`partlife report <name>`), with the figure width
/// recorded in its manifest.
pub fn redraw(report_dir: &Path) -> Result<Rendered> {
    let manifest_path = report_dir.join("manifest.json");
    let text = std::fs::read_to_string(&manifest_path).map_err(|e| Error::read(&manifest_path, e))?;
    let json: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| Error::data_file(&manifest_path, "file", format!("not valid JSON: {e}")))?;
    let width = json
        .pointer("/study_resolved/figures/width_cm")
        .and_then(|v| v.as_f64())
        .unwrap_or(8.5);
    match json.pointer("/study_resolved/kind").and_then(|v| v.as_str()) {
        Some("dem") => return dem::render(report_dir, width),
        Some("crush") => return crush::render(report_dir, width),
        Some("calibrate") => return calibrate::render(report_dir, width),
        Some("uq") => return uq::render(report_dir, width),
        Some("discrepancy") => return discrepancy::render(report_dir, width),
        Some("discrepancy_curves") => return discrepancy::render_curves(report_dir, width),
        Some("experiments") => return experiments::render(report_dir, width),
        Some("temperature") => return temperature::render(report_dir, width),
        Some("microstructure") => return micro::render(report_dir, width),
        _ => {}
    }
    render(report_dir, width)
}

/// A drawn figure and the data samples its legends hide.
type Drawn = (Encoded, usize);

fn fig05_force_time(dir: &Path, mats: &Materials, w: f64) -> Result<Drawn> {
    let t = Table::load(dir, "force_time")?;
    let (time, force, imp, vel, eta) = (t.f("time_s")?, t.f("force_n")?, t.f("impulse_n_s")?, t.f("velocity_m_s")?, t.f("energy_fraction")?);
    let mut top = Vec::new();
    let mut bottom = Vec::new();
    for (key, idx) in t.groups()? {
        let c = mats.colour(&key);
        let tt: Vec<f64> = pick(&time, &idx).iter().map(|x| x * 1e6).collect();
        let label = format!("{}, V = {} m/s, η = {}", mats.label(&key), vel[idx[0]], eta[idx[0]]);
        top.push(Series::line(Some(label), zip(tt.clone(), pick(&force, &idx)), c, 1.0));
        bottom.push(Series::line(Some(mats.label(&key)), zip(tt, pick(&imp, &idx).iter().map(|j| j * 1e6).collect()), c, 1.0));
    }
    let xr = padded(time.iter().map(|x| x * 1e6), 0.0, 0.02);
    let p1 = Panel {
        x_categories: vec![],
        x_desc: "Time since first contact t (µs)".into(),
        y_desc: "Contact force F (N)".into(),
        x_range: xr,
        y_range: (0.0, padded(force.iter().cloned(), 0.0, 0.35).1),
        y_log: false,
        series: top,
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    let p2 = Panel {
        x_categories: vec![],
        x_desc: "Time since first contact t (µs)".into(),
        y_desc: "Impulse ∫F dt (µN·s)".into(),
        x_range: xr,
        y_range: (0.0, padded(imp.iter().map(|j| j * 1e6), 0.0, 0.08).1),
        y_log: false,
        series: bottom,
        legend: Some(SeriesLabelPosition::LowerRight),
    };
    figure("fig05_force_time", w, 1.25, &[(p1, 0.5), (p2, 0.5)])
}

fn fig13_stress_profile(dir: &Path, mats: &Materials, w: f64) -> Result<Drawn> {
    let t = Table::load(dir, "stress_profile")?;
    let sum = Table::load(dir, "stress_profile_summary")?;
    let (r, sr) = (t.f("r_m")?, t.f("sigma_r_pa")?);
    let skeys = sum.s("material_key")?;
    let (sd, sf, sb, s0, s1) = (sum.f("diameter_m")?, sum.f("crush_force_n")?, sum.f("sigma_bar_pa")?, sum.f("domain_start_m")?, sum.f("domain_end_m")?);
    let mut series = Vec::new();
    for (key, idx) in t.groups()? {
        let c = mats.colour(&key);
        let j = skeys.iter().position(|k| *k == key).ok_or_else(|| {
            Error::data_file(&sum.path, "material_key", format!("no summary row for material {key}"))
        })?;
        let label = format!("{}: d = {:.2} mm, F = {:.0} N", mats.label(&key), sd[j] * 1e3, sf[j]);
        let pts = zip(pick(&r, &idx).iter().map(|x| x * 1e6).collect(), pick(&sr, &idx).iter().map(|s| s / 1e9).collect());
        series.push(Series::line(Some(label), pts, c, 1.0));
        series.push(Series {
            label: None,
            points: vec![(s0[j] * 1e6, sb[j] / 1e9), (s1[j] * 1e6, sb[j] / 1e9)],
            colour: c,
            kind: Kind::Dashed(1.0, 3.0, 1.5),
        });
        series.push(Series {
            label: None,
            points: vec![(0.5 * (s0[j] + s1[j]) * 1e6, sb[j] / 1e9)],
            colour: c,
            kind: Kind::Markers(Marker::Circle, 2.2),
        });
    }
    series.push(Series {
        label: Some("σ̄: mean tensile σᵣ over its domain".into()),
        points: vec![],
        colour: BLACK,
        kind: Kind::Dashed(1.0, 3.0, 1.5),
    });
    let yr = padded(sr.iter().map(|s| s / 1e9), 0.05, 0.15);
    let p = Panel {
        x_categories: vec![],
        x_desc: "Distance from contact centre r (µm)".into(),
        y_desc: "Radial surface stress σᵣ (GPa)".into(),
        x_range: (0.0, r.iter().cloned().fold(0.0, f64::max) * 1e6),
        y_range: yr,
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::LowerRight),
    };
    figure("fig13_stress_profile", w, 0.8, &[(p, 1.0)])
}

fn fig14_sigma_vs_diameter(dir: &Path, mats: &Materials, w: f64) -> Result<Drawn> {
    let t = Table::load(dir, "particles")?;
    let trend = Table::load(dir, "size_trend")?;
    let (d, sb) = (t.f("diameter_m")?, t.f("sigma_bar_pa")?);
    // What each particle's row says (reports without censoring have no column: every one broke).
    let observed = t.s("observed").ok();
    let broke = |i: usize| observed.as_ref().is_none_or(|o| Censor::parse(&o[i]) == Some(Censor::Exact));
    let tkeys = trend.s("material_key")?;
    let (b, se, c0, rr, lo, hi) = (trend.f("exponent")?, trend.f("exponent_se")?, trend.f("ln_prefactor")?, trend.f("pearson_r_log")?, trend.f("diameter_min_m")?, trend.f("diameter_max_m")?);
    let mut series = Vec::new();
    for (key, idx) in t.groups()? {
        let c = mats.colour(&key);
        let (yes, no): (Vec<usize>, Vec<usize>) = idx.iter().partition(|&&i| broke(i));
        series.push(Series {
            label: Some(format!("{} (n = {})", mats.label(&key), yes.len())),
            points: zip(pick(&d, &yes).iter().map(|x| x * 1e3).collect(), pick(&sb, &yes).iter().map(|s| s / 1e6).collect()),
            colour: c,
            kind: Kind::Markers(mats.marker(&key), 2.0),
        });
        if !no.is_empty() {
            series.push(Series {
                label: Some(format!("{}: σ̄ at the limit, not broken (n = {})", mats.label(&key), no.len())),
                points: zip(pick(&d, &no).iter().map(|x| x * 1e3).collect(), pick(&sb, &no).iter().map(|s| s / 1e6).collect()),
                colour: c,
                kind: Kind::Markers(Marker::Ring, 2.0),
            });
        }
        if let Some(j) = tkeys.iter().position(|k| *k == key) {
            let line: Vec<(f64, f64)> = (0..=40)
                .map(|i| {
                    let x = lo[j] + (hi[j] - lo[j]) * i as f64 / 40.0;
                    (x * 1e3, (c0[j] + b[j] * x.ln()).exp() / 1e6)
                })
                .collect();
            // A censored sample's line is the Weibull regression's median (no r).
            let how = if rr[j].is_finite() { format!(", r = {:.2}", rr[j]) } else { ", censored regression".to_string() };
            series.push(Series::line(
                Some(format!("fit σ̄ ∝ d^({:.2} ± {:.2}){how}", b[j], se[j]).replace('-', "−")),
                line,
                c,
                1.0,
            ));
        }
    }
    let p = Panel {
        x_categories: vec![],
        x_desc: "Particle diameter d (mm)".into(),
        y_desc: "σ̄ at break (MPa)".into(),
        x_range: padded(d.iter().map(|x| x * 1e3), 0.05, 0.05),
        y_range: padded(sb.iter().map(|s| s / 1e6), 0.08, 0.75),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperRight),
    };
    figure("fig14_sigma_vs_diameter", w, 0.8, &[(p, 1.0)])
}

fn fig14_weibull_cdf(dir: &Path, mats: &Materials, w: f64) -> Result<Drawn> {
    let pts = Table::load(dir, "weibull_points")?;
    let cdf = Table::load(dir, "weibull_cdf")?;
    let fits = Table::load(dir, "weibull_fits")?;
    let (px, pf) = (pts.f("sigma_bar_pa")?, pts.f("cdf_rank")?);
    // Each point's kind (reports without censoring have no column: every one broke).
    let observed = pts.s("observed").ok();
    let kind_of = |i: usize| observed.as_ref().and_then(|o| Censor::parse(&o[i])).unwrap_or(Censor::Exact);
    let censored = (0..px.len()).any(|i| kind_of(i) != Censor::Exact);
    let bootstrap = fits.s("bound_method").is_ok_and(|m| m.iter().any(|v| v.contains("bootstrap")));
    let (cx, cy, cl, cu) = (cdf.f("sigma_pa")?, cdf.f("cdf")?, cdf.f("cdf_lower")?, cdf.f("cdf_upper")?);
    let fkeys = fits.s("material_key")?;
    let (shape, scale, conf) = (fits.f("shape_used")?, fits.f("scale_pa")?, fits.f("confidence")?);
    // Room on the left for the legend (the CDFs are near zero there).
    let xr = padded(px.iter().map(|x| x / 1e6), 0.75, 0.06);
    let mut series = Vec::new();
    for (n, (key, idx)) in cdf.groups()?.into_iter().enumerate() {
        let c = mats.colour(&key);
        let keep: Vec<usize> = idx.into_iter().filter(|&i| cx[i] / 1e6 >= xr.0 && cx[i] / 1e6 <= xr.1).collect();
        let x: Vec<f64> = pick(&cx, &keep).iter().map(|v| v / 1e6).collect();
        let j = fkeys.iter().position(|k| *k == key).unwrap_or(0);
        if n == 0 {
            series.push(Series {
                label: Some(format!("{:.0} % {} confidence band", 100.0 * conf[j], if bootstrap { "bootstrap" } else { "pivotal" })),
                points: vec![],
                colour: RGBColor(120, 120, 120),
                kind: Kind::Band(vec![], 0.35),
            });
        }
        series.push(Series {
            label: None,
            points: zip(x.clone(), pick(&cl, &keep)),
            colour: c,
            kind: Kind::Band(pick(&cu, &keep), 0.18),
        });
        series.push(Series::line(
            Some(format!("{}: m = {:.1}, σθ = {:.0} MPa", mats.label(&key), shape[j], scale[j] / 1e6)),
            zip(x, pick(&cy, &keep)),
            c,
            1.0,
        ));
    }
    for (key, idx) in pts.groups()? {
        let (yes, no): (Vec<usize>, Vec<usize>) = idx.iter().partition(|&&i| kind_of(i) == Censor::Exact);
        series.push(Series {
            label: Some(format!("{} data", mats.label(&key))),
            points: zip(pick(&px, &yes).iter().map(|v| v / 1e6).collect(), pick(&pf, &yes)),
            colour: mats.colour(&key),
            kind: Kind::Markers(mats.marker(&key), 1.8),
        });
        if !no.is_empty() {
            series.push(Series {
                label: Some(format!("{}: {}", mats.label(&key), censored_words(no.iter().map(|&i| kind_of(i))))),
                points: zip(pick(&px, &no).iter().map(|v| v / 1e6).collect(), pick(&pf, &no)),
                colour: mats.colour(&key),
                // Larger than a break's marker, so a ring beside a break stays visible.
                kind: Kind::Markers(Marker::Ring, 3.0),
            });
        }
    }
    let p = Panel {
        x_categories: vec![],
        x_desc: "σ̄ at break (MPa)".into(),
        y_desc: if censored { "Breaking probability (Kaplan–Meier)".into() } else { "Breaking probability, data at (i − 0.5)/N".into() },
        x_range: xr,
        y_range: (0.0, 1.0),
        y_log: false,
        series,
        legend: Some(SeriesLabelPosition::UpperLeft),
    };
    figure("fig14_weibull_cdf", w, 0.8, &[(p, 1.0)])
}

/// What a series of censored probability-plot points is, from the kinds it holds, in the
/// order first seen (`not broken, class ends`).
pub(crate) fn censored_words(kinds: impl Iterator<Item = Censor>) -> String {
    let mut seen: Vec<Censor> = Vec::new();
    for k in kinds {
        if !seen.contains(&k) {
            seen.push(k);
        }
    }
    seen.iter().map(|k| k.plotted()).collect::<Vec<_>>().join(", ")
}

fn fig15_impact(dir: &Path, mats: &Materials, w: f64) -> Result<Drawn> {
    let t = Table::load(dir, "impact_curves")?;
    let (v, f, sb) = (t.f("velocity_m_s")?, t.f("f_max_n")?, t.f("sigma_bar_pa")?);
    let (mut top, mut bottom) = (Vec::new(), Vec::new());
    for (key, idx) in t.groups()? {
        let c = mats.colour(&key);
        top.push(Series::line(Some(mats.label(&key)), zip(pick(&v, &idx), pick(&f, &idx)), c, 1.0));
        bottom.push(Series::line(Some(mats.label(&key)), zip(pick(&v, &idx), pick(&sb, &idx).iter().map(|s| s / 1e6).collect()), c, 1.0));
    }
    let xr = (0.0, v.iter().cloned().fold(0.0, f64::max));
    let p1 = Panel {
        x_categories: vec![],
        x_desc: "Impact velocity V (m/s)".into(),
        y_desc: "Max. contact force Fₘₐₓ (N)".into(),
        x_range: xr,
        y_range: (0.0, padded(f.iter().cloned(), 0.0, 0.08).1),
        y_log: false,
        series: top,
        legend: Some(SeriesLabelPosition::UpperLeft),
    };
    let p2 = Panel {
        x_categories: vec![],
        x_desc: "Impact velocity V (m/s)".into(),
        y_desc: "σ̄ at Fₘₐₓ (MPa)".into(),
        x_range: xr,
        y_range: (0.0, padded(sb.iter().map(|s| s / 1e6), 0.0, 0.08).1),
        y_log: false,
        series: bottom,
        legend: Some(SeriesLabelPosition::LowerRight),
    };
    figure("fig15_impact", w, 1.25, &[(p1, 0.5), (p2, 0.5)])
}

fn fig16_breakage(dir: &Path, mats: &Materials, w: f64) -> Result<Drawn> {
    let t = Table::load(dir, "breakage_curves")?;
    let summary = Table::load(dir, "lifetime_summary")?;
    let (v, n, p) = (t.f("velocity_m_s")?, t.f("impacts")?, t.f("p_break")?);
    let per_year = {
        let (y, i) = (summary.f("years")?, summary.f("impacts")?);
        y.first().zip(i.first()).map(|(y, i)| i / y)
    };
    let mut counts: Vec<f64> = Vec::new();
    for &c in &n {
        if !counts.contains(&c) {
            counts.push(c);
        }
    }
    counts.sort_by(f64::total_cmp);
    if counts.is_empty() {
        return Err(Error::data_file(&t.path, "file", "no rows: nothing to draw"));
    }
    let vmax = v.iter().cloned().fold(0.0, f64::max);
    // Floor of the log axis: the smallest probability of one impact at 5 % of the velocity range.
    let low = v
        .iter()
        .zip(&n)
        .zip(&p)
        .filter(|((vv, nn), pp)| **vv >= 0.05 * vmax && **nn == counts[0] && **pp > 0.0)
        .map(|(_, pp)| *pp)
        .fold(1.0, f64::min);
    let floor = low.log10().floor().clamp(-16.0, -1.0);
    let styles: [Kind; 4] = [Kind::Line(1.0), Kind::Dashed(1.0, 4.0, 2.0), Kind::Dashed(1.0, 1.0, 1.5), Kind::Dashed(1.0, 8.0, 2.0)];
    let mut series = Vec::new();
    let mut by_key: BTreeMap<usize, (String, Vec<usize>)> = BTreeMap::new();
    for (key, idx) in t.groups()? {
        by_key.insert(mats.index(&key), (key, idx));
    }
    for (key, idx) in by_key.values() {
        let c = mats.colour(key);
        for (ci, &cnt) in counts.iter().enumerate() {
            let pts: Vec<(f64, f64)> = idx
                .iter()
                .filter(|&&i| n[i] == cnt && p[i] > 10f64.powf(floor))
                .map(|&i| (v[i], p[i].log10()))
                .collect();
            series.push(Series { label: None, points: pts, colour: c, kind: styles[ci % 4].clone() });
        }
        series.push(Series::line(Some(mats.label(key)), vec![], c, 1.0));
    }
    // The lifetimes the caption and the answer quote: each horizon's breaking probability at
    // the reference velocity with its confidence band (a bar), so the figure shows the numbers
    // the text gives. The caption names them; the legend, which the curves leave little room
    // for, does not.
    let (sv, sp, slo, shi) = (summary.f("velocity_m_s")?, summary.f("p_break")?, summary.f("p_break_lower")?, summary.f("p_break_upper")?);
    let shown = |x: f64| x.max(10f64.powf(floor)).log10();
    let groups = summary.groups()?;
    let slots = groups.iter().map(|(_, idx)| idx.len()).sum::<usize>().max(1);
    let mut slot = 0;
    for (key, idx) in groups {
        let c = mats.colour(&key);
        for &i in &idx {
            // Each material and horizon side by side at the one velocity, so that no bar hides
            // another (materials in their order, horizons ascending within each).
            let dx = (slot as f64 - 0.5 * (slots - 1) as f64) * 0.012 * vmax;
            slot += 1;
            series.push(Series { label: None, points: vec![(sv[i] + dx, shown(slo[i])), (sv[i] + dx, shown(shi[i]))], colour: c, kind: Kind::Line(0.8) });
            series.push(Series { label: None, points: vec![(sv[i] + dx, shown(sp[i]))], colour: c, kind: Kind::Markers(Marker::Circle, 1.6) });
        }
    }
    for (ci, &cnt) in counts.iter().enumerate() {
        let years = per_year.map(|py| cnt / py).filter(|y| *y >= 0.999 && (y - y.round()).abs() < 1e-9);
        let label = match years {
            Some(y) => format!("N = {cnt} ({y:.0} yr)"),
            None => format!("N = {cnt}"),
        };
        series.push(Series { label: Some(label), points: vec![], colour: BLACK, kind: styles[ci % 4].clone() });
    }
    let p = Panel {
        x_categories: vec![],
        x_desc: "Impact velocity V (m/s)".into(),
        y_desc: "Breaking probability after N impacts".into(),
        x_range: (0.0, vmax),
        y_range: (floor, 0.0),
        y_log: true,
        series,
        legend: Some(SeriesLabelPosition::LowerRight),
    };
    figure("fig16_breakage", w, 0.85, &[(p, 1.0)])
}

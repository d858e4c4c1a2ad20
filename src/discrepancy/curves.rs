//! The force–displacement level of the discrepancy workflow (issue 7, item 4): where does the
//! **calibrated crush FE** disagree with measured crush curves, which physical term is missing,
//! and does adding it make the disagreement go away?
//!
//! ```toml
//! kind = "discrepancy_curves"
//! seed = 20261122
//! calibration = "calibrate_gen3_rt.toml"   # a crush calibration; its report must exist
//! candidates = ["compliance", "temperature", "curvature"]
//! [[data]]                                 # one or more curve files (the first at the
//! file = "../datasets/crush_curves_gen3_rt.csv"   # calibration's temperature)
//! temperature_c = 20
//! [koh]        # walkers, steps, burn_in (Kennedy–O'Hagan sampler)
//! [curvature]  # roundness = [...], width: the FE table of the curvature candidate
//! ```
//!
//! # The model and its emulator
//!
//! η_k(θ) is the force of the calibration's crush FE at its grid displacements x_k (normalised
//! to its reference diameter D₀, see [`crate::calibrate::data`]), θ its fitted JH-2 constants.
//! The emulator is the calibration's own: the GP fitted to the FE runs in
//! `reports/<calibration>/runs.csv` (training rows) — no FE run is repeated. The measured
//! curves are normalised to D₀ the same way and averaged per file at the grid points below
//! every particle's fracture: y = mean force, σ = particle scatter/√n (floored at
//! `sigma_floor`·mean) with the emulator's predictive variance at the calibrated θ added.
//!
//! # Diagnosis
//!
//! * **curve residuals**: every particle's standardised residual (F − η(θ̂))/σ_particle at every
//!   grid point, θ̂ the least-squares fit without discrepancy; the trend of the mean residual
//!   along the curve (Spearman ρ against displacement, permutation p-value) — the
//!   "displacement along a curve" covariate;
//! * **δ(x)**: the Kennedy–O'Hagan discrepancy ([`super::koh`]), a GP over displacement (and
//!   temperature when the files differ in it) fitted jointly with θ; where |δ̂| exceeds twice
//!   the uncertainty σ of the mean curve is where the model disagrees, and the gap measure is
//!   **RMS(δ̂_i/σ_i)**, δ's posterior mean in units of the measurement uncertainty (≲ 1 when
//!   nothing is missing).
//!
//! # What is known about θ
//!
//! By default (`theta = "calibration"`) θ's prior is the calibration's posterior (a Gaussian
//! fitted to its draws in `chains.csv`): the curves are compared with the **calibrated** model,
//! and a term the constants could mimic on these curves alone (a compliant machine looks like a
//! softer, weaker particle) still shows against what the calibration established. With
//! `theta = "bounds"` θ is uniform in the calibration's bounds (recalibrated on these data), and
//! only what no θ can mimic shows. The prior enters the BIC as data.
//!
//! # Candidate terms (post-processing of η, or an FE table; no new emulator)
//!
//! | name | equation | parameter |
//! |---|---|---|
//! | `compliance` | the recorded displacement includes the load train: x = δ(F) + c·F, so F(x) solves F = η(x − c·F) (η between grid points by linear interpolation of F^(2/3), exact for Hertz) | c (µm/N at D₀) |
//! | `temperature` | stiffness and strength soften together: F(x, T) = r^((T − T₀)/100 °C) η(x), T₀ the first file's temperature | force ratio r per 100 °C |
//! | `curvature` | the contact tip has pole curvature ratio ρ (an asperity, [`crate::fem::mesh::Shape::Asperity`]): F = η(x)·Φ_k(ρ), Φ the ratio of asperity to sphere FE forces at the calibrated θ, tabulated at `curvature.roundness` and interpolated linearly | ρ (–) |
//!
//! A candidate is skipped with a reason when the data cannot show it (temperature with one
//! temperature). Each round fits the current model and every remaining candidate with
//! [`super::koh::fit`] and names the one with the lowest BIC if it beats the current model by
//! more than 6 ([`super::koh::BIC_STRONG`]); the named term is added and the loop repeats, at
//! most `max_effects` times. The compliance term acts on the whole curve after the
//! multiplicative terms (it is the machine, not the particle).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::koh::{self, BIC_STRONG, KohFit, KohOptions, Problem};
use crate::calibrate::data::{Curve, load_curves};
use crate::calibrate::emulator::Emulator;
use crate::calibrate::run::Built;
use crate::error::{Error, Result};
use crate::fem::mesh::Shape;
use crate::fem::model::CrushModel;
use crate::fracture::FractureParams;
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
use crate::model::Simulator;
use crate::report::Table;
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::schema::{FigureOptions, StudyFile, check};

/// The FE-level candidate terms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CurveCandidate {
    /// Platen (machine) compliance.
    Compliance,
    /// Temperature softening of stiffness and strength.
    Temperature,
    /// Contact-tip curvature (roundness of the pole).
    Curvature,
}

impl CurveCandidate {
    /// Every candidate.
    pub const ALL: [CurveCandidate; 3] = [CurveCandidate::Compliance, CurveCandidate::Temperature, CurveCandidate::Curvature];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            CurveCandidate::Compliance => "compliance",
            CurveCandidate::Temperature => "temperature",
            CurveCandidate::Curvature => "curvature",
        }
    }

    /// The parameter the term adds: (name with unit).
    pub fn parameter(self) -> &'static str {
        match self {
            CurveCandidate::Compliance => "platen compliance c (µm/N)",
            CurveCandidate::Temperature => "force ratio per 100 °C (–)",
            CurveCandidate::Curvature => "pole curvature ratio ρ (–)",
        }
    }

    /// The equation, for reports.
    pub fn equation(self) -> &'static str {
        match self {
            CurveCandidate::Compliance => "F solves F = η(x − c·F)",
            CurveCandidate::Temperature => "F = r^((T − T₀)/100 °C) · η(x)",
            CurveCandidate::Curvature => "F = Φ(x; ρ) · η(x), Φ from asperity/sphere FE runs",
        }
    }
}

/// What the discrepancy fits know about the calibrated constants θ.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThetaPrior {
    /// The calibration's posterior (Gaussian approximation of its draws): the data are compared
    /// with the *calibrated* model, so a term the constants could mimic still shows.
    #[default]
    Calibration,
    /// Uniform within the calibration's bounds: θ is recalibrated on these data, and only what
    /// no θ can mimic shows.
    Bounds,
}

fn all_candidates() -> Vec<CurveCandidate> {
    CurveCandidate::ALL.to_vec()
}

/// One measured curve file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveFile {
    /// Crush-curve CSV (`particle, diameter_m, displacement_m, force_n`), relative to the study.
    pub file: String,
    /// Test temperature (°C).
    pub temperature_c: f64,
    /// Label in tables and figures (default: the file stem).
    #[serde(default)]
    pub label: Option<String>,
}

/// The FE table of the curvature candidate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CurvatureTable {
    /// Pole curvature ratios run (each in (0, 1)); the sphere (1) is added.
    pub roundness: Vec<f64>,
    /// Angular half-width of the asperity (rad), as [`Shape::Asperity`].
    pub width: f64,
}

impl Default for CurvatureTable {
    fn default() -> Self {
        CurvatureTable { roundness: vec![0.4, 0.55, 0.7, 0.85], width: 0.35 }
    }
}

/// A study of kind `discrepancy_curves`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveStudy {
    /// `discrepancy_curves`.
    pub kind: String,
    /// Seed of the samplers.
    pub seed: u64,
    /// The crush calibration study (relative to this file) whose report holds the emulator's
    /// training runs and the posterior.
    pub calibration: String,
    /// Measured curve files (the first at the calibration's temperature).
    pub data: Vec<CurveFile>,
    /// Prior of the calibrated constants in the discrepancy fits (default: the calibration's
    /// posterior).
    #[serde(default)]
    pub theta: ThetaPrior,
    /// Candidates tried (default: all).
    #[serde(default = "all_candidates")]
    pub candidates: Vec<CurveCandidate>,
    /// Most terms named.
    #[serde(default = "three")]
    pub max_effects: usize,
    /// Floor of the particle scatter, relative to the mean force.
    #[serde(default = "floor")]
    pub sigma_floor: f64,
    /// Sampler of the Kennedy–O'Hagan fits (its seed is the study's).
    #[serde(default)]
    pub koh: KohOptions,
    /// Curvature table.
    #[serde(default)]
    pub curvature: CurvatureTable,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
}

fn three() -> usize {
    3
}

fn floor() -> f64 {
    0.02
}

impl CurveStudy {
    /// Checks every setting that does not need a file.
    pub fn validate(&self, file: &str) -> Result<()> {
        check(file, "data", !self.data.is_empty(), "at least one [[data]] curve file is required".into())?;
        for (i, d) in self.data.iter().enumerate() {
            check(file, &format!("data[{i}].temperature_c"), d.temperature_c.is_finite() && d.temperature_c > -273.15 && d.temperature_c < 2000.0, format!("must be a temperature in °C, got {}", d.temperature_c))?;
        }
        check(file, "candidates", !self.candidates.is_empty(), "at least one candidate is required".into())?;
        check(file, "max_effects", (1..=3).contains(&self.max_effects), format!("must lie in [1, 3], got {}", self.max_effects))?;
        check(file, "sigma_floor", self.sigma_floor >= 0.0 && self.sigma_floor < 0.5, format!("must lie in [0, 0.5), got {}", self.sigma_floor))?;
        check(file, "koh.steps", self.koh.steps >= 200 && self.koh.burn_in >= 100 && self.koh.walkers >= 8 && self.koh.delta_draws >= 1, "needs steps ≥ 200, burn_in ≥ 100, walkers ≥ 8, delta_draws ≥ 1".into())?;
        check(file, "curvature.roundness", !self.curvature.roundness.is_empty() && self.curvature.roundness.iter().all(|r| *r > 0.05 && *r < 1.0), "needs values in (0.05, 1)".into())?;
        check(file, "curvature.width", self.curvature.width > 0.05 && self.curvature.width < 1.0, format!("must lie in (0.05, 1) rad, got {}", self.curvature.width))?;
        check(file, "figures.width_cm", self.figures.width_cm >= 4.0 && self.figures.width_cm <= 40.0, format!("must lie in [4, 40], got {}", self.figures.width_cm))
    }
}

/// One data point: the mean normalised force of one file at one grid displacement.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Index of the file.
    pub group: usize,
    /// Grid index.
    pub k: usize,
    /// Grid displacement at D₀ (m).
    pub x: f64,
    /// Temperature (°C).
    pub temperature: f64,
    /// Mean force (N).
    pub mean: f64,
    /// Particle scatter (sd over particles, floored) (N).
    pub scatter: f64,
    /// Particles averaged.
    pub particles: usize,
    /// σ of the mean: scatter/√n with the emulator's variance added (N).
    pub sigma: f64,
}

/// One file's curves, normalised to D₀.
#[derive(Debug, Clone)]
pub struct Group {
    /// Label.
    pub label: String,
    /// Temperature (°C).
    pub temperature: f64,
    /// Curves at D₀.
    pub curves: Vec<Curve>,
}

/// Averages each group at the grid points below every particle's fracture (or curve end).
pub fn reduce(paths: &[PathBuf], groups: &[Group], grid: &[f64], fracture: FractureParams, sigma_floor: f64) -> Result<Vec<Point>> {
    let mut out = Vec::new();
    for (g, grp) in groups.iter().enumerate() {
        let limit = grp
            .curves
            .iter()
            .map(|c| c.fracture(fracture).map(|f| 0.9 * f.1).unwrap_or_else(|| c.displacement.last().copied().unwrap_or(0.0)))
            .fold(f64::INFINITY, f64::min);
        let mut used = 0;
        for (k, &x) in grid.iter().enumerate().filter(|(_, x)| **x <= limit) {
            let f: Vec<f64> = grp.curves.iter().filter_map(|c| c.force_at(x)).collect();
            if f.len() < grp.curves.len() {
                continue;
            }
            let n = f.len() as f64;
            let mean = f.iter().sum::<f64>() / n;
            let sd = (f.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let scatter = sd.max(sigma_floor * mean.abs()).max(1e-9);
            out.push(Point { group: g, k, x, temperature: grp.temperature, mean, scatter, particles: f.len(), sigma: scatter / n.sqrt() });
            used += 1;
        }
        if used < 3 {
            return Err(Error::data_file(
                &paths[g],
                "file",
                format!("only {used} of the calibration's grid displacements lie before every particle's fracture (at {:.2} µm when normalised): at least 3 are needed", limit * 1e6),
            ));
        }
    }
    Ok(out)
}

/// Force between grid points by linear interpolation of F^(2/3) through the origin (exact for
/// a Hertzian curve); linear extrapolation of the last segment beyond the grid.
fn interp(grid: &[f64], f: &[f64], x: f64) -> f64 {
    let g = |v: f64| v.max(0.0).powf(2.0 / 3.0);
    let j = grid.partition_point(|&v| v < x).min(grid.len() - 1);
    let (x0, g0) = if j == 0 { (0.0, 0.0) } else { (grid[j - 1], g(f[j - 1])) };
    let (x1, g1) = (grid[j], g(f[j]));
    let v = g0 + (x - x0) / (x1 - x0).max(f64::MIN_POSITIVE) * (g1 - g0);
    v.max(0.0).powf(1.5)
}

/// The force recorded at displacement x with compliance c (m/N): F = η(x − cF), by bisection.
fn with_compliance(grid: &[f64], f: &[f64], x: f64, c: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, interp(grid, f, x));
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if mid - interp(grid, f, x - c * mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Ratio of asperity to sphere FE force at the grid, per tabulated pole curvature ratio.
#[derive(Debug, Clone, PartialEq)]
pub struct RatioTable {
    /// Pole curvature ratios, ascending, the last 1 (sphere).
    pub roundness: Vec<f64>,
    /// Φ[r][k].
    pub ratio: Vec<Vec<f64>>,
}

impl RatioTable {
    fn at(&self, rho: f64, k: usize) -> f64 {
        let r = &self.roundness;
        let j = r.partition_point(|&v| v < rho).clamp(1, r.len() - 1);
        let t = ((rho - r[j - 1]) / (r[j] - r[j - 1])).clamp(0.0, 1.0);
        self.ratio[j - 1][k] + t * (self.ratio[j][k] - self.ratio[j - 1][k])
    }
}

/// The base model's force on the grid at θ (the calibration's emulator means).
pub type BaseCurve<'a> = dyn Fn(&[f64]) -> Vec<f64> + Sync + 'a;

/// The calibrated model with terms, evaluated at the data points.
pub struct CurveModel<'a> {
    /// Force on the grid at the base θ.
    pub base: &'a BaseCurve<'a>,
    /// Grid displacements at D₀ (m).
    pub grid: &'a [f64],
    /// Data points.
    pub points: &'a [Point],
    /// Temperature of each group (°C).
    pub temperatures: Vec<f64>,
    /// Reference temperature of the softening term (°C).
    pub t_ref: f64,
    /// FE ratio table of the curvature term.
    pub table: Option<&'a RatioTable>,
    /// Number of base parameters.
    pub base_dim: usize,
}

impl CurveModel<'_> {
    /// Forces at every point for θ = (base constants, one parameter per term in `terms` order).
    pub fn eval(&self, terms: &[CurveCandidate], theta: &[f64]) -> Vec<f64> {
        let base = (self.base)(&theta[..self.base_dim]);
        let mut factor = vec![vec![1.0; self.grid.len()]; self.temperatures.len()];
        let mut compliance = None;
        for (j, t) in terms.iter().enumerate() {
            let v = theta[self.base_dim + j];
            match t {
                CurveCandidate::Compliance => compliance = Some(v * 1e-6),
                CurveCandidate::Temperature => {
                    for (row, temp) in factor.iter_mut().zip(&self.temperatures) {
                        let s = v.powf((temp - self.t_ref) / 100.0);
                        row.iter_mut().for_each(|f| *f *= s);
                    }
                }
                CurveCandidate::Curvature => {
                    if let Some(tab) = self.table {
                        for row in factor.iter_mut() {
                            for (k, f) in row.iter_mut().enumerate() {
                                *f *= tab.at(v, k);
                            }
                        }
                    }
                }
            }
        }
        let curves: Vec<Vec<f64>> = factor.iter().map(|row| base.iter().zip(row).map(|(b, f)| b * f).collect()).collect();
        self.points
            .iter()
            .map(|p| match compliance {
                Some(c) => with_compliance(self.grid, &curves[p.group], p.x, c),
                None => curves[p.group][p.k],
            })
            .collect()
    }
}

/// Evidence of one candidate in one round.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveEvidence {
    /// Round (0-based).
    pub round: usize,
    /// Candidate.
    pub candidate: CurveCandidate,
    /// Why it was not tried.
    pub skipped: Option<String>,
    /// The fit with the term (None when skipped).
    pub fit: Option<KohFit>,
    /// BIC(candidate) − BIC(current).
    pub delta_bic: f64,
    /// Gap RMS(δ̂/σ) with the term (NaN when skipped).
    pub gap: f64,
    /// Named in this round.
    pub named: bool,
}

/// The model of one round: its terms and fit.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveStage {
    /// Terms of the model.
    pub terms: Vec<CurveCandidate>,
    /// Its Kennedy–O'Hagan fit.
    pub fit: KohFit,
    /// Model forces at the points at the posterior median θ.
    pub model: Vec<f64>,
    /// Gap RMS(δ̂/σ).
    pub gap: f64,
}

/// What the loop found.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveOutcome {
    /// Terms named, in order.
    pub named: Vec<CurveCandidate>,
    /// Per round and candidate.
    pub evidence: Vec<CurveEvidence>,
    /// Base model first, then one stage per named term.
    pub stages: Vec<CurveStage>,
    /// Least-squares θ of the base model (no δ).
    pub theta_ls: Vec<f64>,
}

/// The gap measure, as written into `verdict.json`.
pub const CURVE_GAP_MEASURE: &str = "RMS over the curve points of δ̂/σ: the posterior-mean Kennedy–O'Hagan discrepancy in units of the measurement uncertainty of the mean curve (≲ 1 when nothing is missing)";

/// Everything the loop needs.
pub struct CurveInputs<'a> {
    /// Model.
    pub model: CurveModel<'a>,
    /// θ names and bounds of the base model.
    pub names: Vec<String>,
    /// Bounds.
    pub bounds: Vec<(f64, f64)>,
    /// Candidates allowed.
    pub candidates: Vec<CurveCandidate>,
    /// Most terms named.
    pub max_effects: usize,
    /// Sampler.
    pub koh: KohOptions,
    /// Gaussian prior of the base θ (mean, inverse covariance): the calibration's posterior;
    /// None: uniform within the bounds (θ recalibrated freely).
    pub prior: Option<(Vec<f64>, nalgebra::DMatrix<f64>)>,
}

fn bounds_of(c: CurveCandidate, points: &[Point], grid: &[f64], table: Option<&RatioTable>) -> (f64, f64) {
    match c {
        CurveCandidate::Compliance => {
            let fmax = points.iter().map(|p| p.mean).fold(0.0, f64::max).max(1e-9);
            let xmax = grid.iter().copied().fold(0.0, f64::max);
            (0.0, 0.5 * xmax / fmax * 1e6)
        }
        CurveCandidate::Temperature => (0.5, 1.5),
        CurveCandidate::Curvature => (table.and_then(|t| t.roundness.first().copied()).unwrap_or(0.5), 1.0),
    }
}

fn skip_reason(c: CurveCandidate, points: &[Point], table: Option<&RatioTable>) -> Option<String> {
    match c {
        CurveCandidate::Temperature => {
            let t0 = points.first().map_or(0.0, |p| p.temperature);
            points.iter().all(|p| p.temperature == t0).then(|| format!("every curve file is at {t0} °C: one temperature cannot show softening"))
        }
        CurveCandidate::Curvature => table.is_none().then(|| "no curvature table (the FE runs were not made)".to_string()),
        CurveCandidate::Compliance => None,
    }
}

impl CurveInputs<'_> {
    fn log_prior(&self, theta: &[f64]) -> f64 {
        match &self.prior {
            Some((mean, inv)) => {
                let d = nalgebra::DVector::from_fn(mean.len(), |i, _| theta[i] - mean[i]);
                -0.5 * d.dot(&(inv * &d))
            }
            None => 0.0,
        }
    }

    fn problem<'m>(&'m self, terms: &[CurveCandidate], f: &'m koh::ModelFn<'m>, prior: &'m (dyn Fn(&[f64]) -> f64 + Sync)) -> Problem<'m> {
        let pts = self.model.points;
        let two_d = pts.iter().any(|p| p.temperature != pts[0].temperature);
        let mut names = self.names.clone();
        let mut bounds = self.bounds.clone();
        for t in terms {
            names.push(t.name().to_string());
            bounds.push(bounds_of(*t, pts, self.model.grid, self.model.table));
        }
        Problem {
            name: if terms.is_empty() { "calibrated FE".into() } else { format!("calibrated FE + {}", terms.iter().map(|t| t.name()).collect::<Vec<_>>().join(" + ")) },
            x: pts.iter().map(|p| if two_d { vec![p.x * 1e6, p.temperature / 100.0] } else { vec![p.x * 1e6] }).collect(),
            y: pts.iter().map(|p| p.mean).collect(),
            noise_sd: pts.iter().map(|p| p.sigma).collect(),
            model: f,
            names,
            bounds,
            constrain_origin: false,
            prior: self.prior.as_ref().map(|_| prior),
        }
    }

    fn stage(&self, terms: Vec<CurveCandidate>, seed: u64) -> Result<CurveStage> {
        let f = |t: &[f64]| self.model.eval(&terms, t);
        let prior = |t: &[f64]| self.log_prior(t);
        let p = self.problem(&terms, &f, &prior);
        let fit = koh::fit(&p, &KohOptions { seed, ..self.koh.clone() })?;
        let model = self.model.eval(&terms, &fit.theta_median);
        let gap = gap_of(&fit, self.model.points);
        Ok(CurveStage { terms, fit, model, gap })
    }

    /// Runs the name → add → shrink loop.
    pub fn analyse(&self, progress: &(dyn Fn(&str) + Sync)) -> Result<CurveOutcome> {
        let f = |t: &[f64]| self.model.eval(&[], t);
        let prior = |t: &[f64]| self.log_prior(t);
        let theta_ls = koh::least_squares(&self.problem(&[], &f, &prior))?;
        progress("base model");
        let mut stages = vec![self.stage(Vec::new(), self.koh.seed)?];
        let mut evidence = Vec::new();
        let mut named = Vec::new();
        for round in 0..self.max_effects {
            let current = stages.last().cloned().ok_or_else(|| Error::numerical("curve discrepancy", "no stage"))?;
            let remaining: Vec<CurveCandidate> = self.candidates.iter().copied().filter(|c| !named.contains(c)).collect();
            if remaining.is_empty() {
                break;
            }
            progress(&format!("round {}: {} candidates", round + 1, remaining.len()));
            let tried: Vec<(CurveCandidate, Option<String>, Option<CurveStage>)> = remaining
                .par_iter()
                .enumerate()
                .map(|(j, &c)| {
                    if let Some(why) = skip_reason(c, self.model.points, self.model.table) {
                        return Ok((c, Some(why), None));
                    }
                    let mut terms = current.terms.clone();
                    terms.push(c);
                    let seed = self.koh.seed.wrapping_add(1000 * (round as u64 + 1) + j as u64);
                    Ok((c, None, Some(self.stage(terms, seed)?)))
                })
                .collect::<Result<_>>()?;
            let best = tried
                .iter()
                .enumerate()
                .filter_map(|(i, (_, _, s))| s.as_ref().map(|s| (i, s.fit.bic - current.fit.bic)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .filter(|(_, d)| *d < BIC_STRONG)
                .map(|(i, _)| i);
            let mut next = None;
            for (i, (c, why, s)) in tried.into_iter().enumerate() {
                let delta_bic = s.as_ref().map_or(f64::NAN, |s| s.fit.bic - current.fit.bic);
                evidence.push(CurveEvidence { round, candidate: c, skipped: why, fit: s.as_ref().map(|s| s.fit.clone()), delta_bic, gap: s.as_ref().map_or(f64::NAN, |s| s.gap), named: Some(i) == best });
                if Some(i) == best {
                    named.push(c);
                    next = s;
                }
            }
            match next {
                Some(s) => stages.push(s),
                None => break,
            }
        }
        Ok(CurveOutcome { named, evidence, stages, theta_ls })
    }
}

fn gap_of(fit: &KohFit, points: &[Point]) -> f64 {
    (fit.delta.iter().zip(points).map(|(d, p)| (d / p.sigma).powi(2)).sum::<f64>() / points.len() as f64).sqrt()
}

/// (from, to) displacement (m) and the largest |δ̂|/F of one file; None: nowhere.
pub type Disagreement = Option<(f64, f64, f64)>;

/// Where the discrepancy exceeds twice the uncertainty of the mean curve (|δ̂| > 2σ): per
/// group, (from, to) displacement (m) and the largest |δ̂|/F there.
pub fn disagreement(fit: &KohFit, points: &[Point], groups: usize) -> Vec<Disagreement> {
    (0..groups)
        .map(|g| {
            let hits: Vec<usize> = (0..points.len()).filter(|&i| points[i].group == g && fit.delta[i].abs() > 2.0 * points[i].sigma).collect();
            let (lo, hi) = hits.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &i| (a.min(points[i].x), b.max(points[i].x)));
            let rel = hits.iter().map(|&i| fit.delta[i].abs() / points[i].mean.abs().max(1e-12)).fold(0.0, f64::max);
            (!hits.is_empty()).then_some((lo, hi, rel))
        })
        .collect()
}

/// Trend of each file's mean curve residual (y − η(θ̂_LS))/σ along the curve: Spearman ρ against
/// displacement with its permutation p-value (999 permutations); NaN with fewer than 4 points.
pub fn trend_along_curve(points: &[Point], least_squares: &[f64], groups: usize, seed: u64) -> Result<Vec<(f64, f64)>> {
    (0..groups)
        .map(|g| {
            let idx: Vec<usize> = (0..points.len()).filter(|&i| points[i].group == g).collect();
            if idx.len() < 4 {
                return Ok((f64::NAN, f64::NAN));
            }
            let r: Vec<f64> = idx.iter().map(|&i| (points[i].mean - least_squares[i]) / points[i].sigma).collect();
            let x: Vec<f64> = idx.iter().map(|&i| points[i].x).collect();
            super::gof::covariate_trend(&r, &x, 999, seed.wrapping_add(g as u64))
        })
        .collect()
}

/// The calibration the loop starts from, read from its study and report.
pub struct Calibrated {
    /// The crush model (grid, bounds, FE set-up).
    pub model: CrushModel,
    /// Reference diameter D₀ (m).
    pub reference_diameter: f64,
    /// Grid displacements (m).
    pub grid: Vec<f64>,
    /// Fracture detection of the calibration.
    pub fracture: FractureParams,
    /// Emulator fitted to the report's training runs.
    pub emulator: Emulator,
    /// Posterior median θ.
    pub theta: Vec<f64>,
    /// Gaussian approximation of the posterior: mean and inverse covariance (from the chains).
    pub posterior: (Vec<f64>, nalgebra::DMatrix<f64>),
    /// Files read (study, data, runs, parameters).
    pub inputs: Vec<PathBuf>,
}

/// Loads a crush calibration and its report; a missing or stale report is an error naming it.
pub fn load_calibration(study_file: &str, key: &str, path: &Path, reports_root: &Path) -> Result<Calibrated> {
    if !path.is_file() {
        return Err(Error::config(study_file, key, format!("{} does not exist", path.display())));
    }
    let loaded = StudyFile::read(path)?;
    if loaded.kind(&["calibrate"])? != "calibrate" {
        return Err(Error::config(study_file, key, format!("{} is not a kind = \"calibrate\" study", path.display())));
    }
    let cs: crate::calibrate::run::CalibrateStudy = loaded.parse()?;
    let prep = cs.prepare(&loaded.path, &|p: &str| loaded.resolve(Path::new(p)))?;
    let Built::Crush(model, red) = prep.built else {
        return Err(Error::config(study_file, key, format!("{} calibrates the DEM: the curve workflow needs a crush calibration", path.display())));
    };
    let fracture = match &cs.model {
        crate::calibrate::run::ModelSpec::Crush { crush } => crush.fracture,
        _ => FractureParams::default(),
    };
    let dir = reports_root.join(&loaded.name);
    let runs_path = dir.join("runs.csv");
    let params_path = dir.join("parameters.csv");
    let grid_path = dir.join("grid.csv");
    for p in [&runs_path, &params_path, &grid_path] {
        if !p.is_file() {
            return Err(Error::config(study_file, key, format!("{} does not exist: run `partlife run {}` first", p.display(), path.display())));
        }
    }
    let grid_report = Table::load_file(&grid_path)?.f("grid_displacement_m")?;
    let same = grid_report.len() == red.grid.len() && grid_report.iter().zip(&red.grid).all(|(a, b)| (a - b).abs() <= 1e-9 * b.abs());
    if !same {
        return Err(Error::data_file(&grid_path, "grid_displacement_m", format!("differs from the grid {} makes of its data now: the report is stale, rerun it", path.display())));
    }
    let runs = Table::load_file(&runs_path)?;
    let source = runs.s("source")?;
    let rows: Vec<usize> = (0..source.len()).filter(|&i| source[i] == "training").collect();
    let names: Vec<String> = model.space().params().iter().map(|p| p.name.clone()).collect();
    let cols: Vec<Vec<f64>> = names.iter().map(|n| runs.f(n)).collect::<Result<_>>()?;
    let outs: Vec<Vec<f64>> = model.outputs().iter().map(|o| runs.f(&o.name)).collect::<Result<_>>()?;
    let thetas: Vec<Vec<f64>> = rows.iter().map(|&i| cols.iter().map(|c| c[i]).collect()).collect();
    let ys: Vec<Vec<f64>> = rows.iter().map(|&i| outs.iter().map(|c| c[i]).collect()).collect();
    if thetas.len() < 2 * names.len() + 2 {
        return Err(Error::data_file(&runs_path, "source", format!("{} training runs: too few for an emulator of {} constants", thetas.len(), names.len())));
    }
    let emulator = Emulator::fit(model.space(), model.outputs(), thetas, ys)?;
    let pt = Table::load_file(&params_path)?;
    let (pn, q50) = (pt.s("name")?, pt.f("q50")?);
    let theta: Vec<f64> = names
        .iter()
        .map(|n| pn.iter().position(|v| v == n).map(|i| q50[i]).ok_or_else(|| Error::data_file(&params_path, "name", format!("no row for parameter {n}"))))
        .collect::<Result<_>>()?;
    let chains_path = dir.join("chains.csv");
    let posterior = gaussian_posterior(&chains_path, &names)?;
    let mut inputs = vec![loaded.path.clone()];
    inputs.extend(prep.inputs);
    inputs.extend([runs_path, params_path, chains_path]);
    Ok(Calibrated { model, reference_diameter: red.reference_diameter, grid: red.grid, fracture, emulator, theta, posterior, inputs })
}

/// Mean and inverse covariance of the calibration's posterior draws (`chains.csv`).
fn gaussian_posterior(path: &Path, names: &[String]) -> Result<(Vec<f64>, nalgebra::DMatrix<f64>)> {
    if !path.is_file() {
        return Err(Error::data_file(path, "file", "missing: rerun the calibration"));
    }
    let t = Table::load_file(path)?;
    let cols: Vec<Vec<f64>> = names.iter().map(|n| t.f(n)).collect::<Result<_>>()?;
    let n = cols.first().map_or(0, |c| c.len());
    if n < 10 * names.len() {
        return Err(Error::data_file(path, "file", format!("{n} draws: too few for the posterior's covariance")));
    }
    let mean: Vec<f64> = cols.iter().map(|c| c.iter().sum::<f64>() / n as f64).collect();
    let d = names.len();
    let cov = nalgebra::DMatrix::from_fn(d, d, |i, j| cols[i].iter().zip(&cols[j]).map(|(a, b)| (a - mean[i]) * (b - mean[j])).sum::<f64>() / (n as f64 - 1.0));
    let inv = cov.try_inverse().ok_or_else(|| Error::data_file(path, "file", "the posterior draws have a singular covariance"))?;
    Ok((mean, inv))
}

/// FE runs of the curvature table at θ: Φ[r][k] = F_asperity(x_k)/F_sphere(x_k).
pub fn curvature_table(cal: &Calibrated, spec: &CurvatureTable, progress: &(dyn Fn() + Sync)) -> Result<RatioTable> {
    let mut roundness: Vec<f64> = spec.roundness.clone();
    roundness.sort_by(f64::total_cmp);
    roundness.dedup();
    roundness.push(1.0);
    let shapes: Vec<Shape> = roundness.iter().map(|&rho| if rho >= 1.0 { Shape::Sphere } else { Shape::Asperity { roundness: rho, width: spec.width } }).collect();
    let runs = cal.model.forces_with_shapes(&cal.theta, cal.reference_diameter, &shapes, &cal.grid, progress)?;
    let sphere = runs.last().cloned().unwrap_or_default();
    let ratio = runs.iter().map(|f| f.iter().zip(&sphere).map(|(a, b)| if *b > 0.0 { a / b } else { 1.0 }).collect()).collect();
    Ok(RatioTable { roundness, ratio })
}

/// Runs a `discrepancy_curves` study.
pub fn run_curves(loaded: &StudyFile, s: &CurveStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let file = loaded.path.display().to_string();
    // The curve files first (cheap), then the calibration and its emulator.
    let mut paths = Vec::new();
    let mut raw = Vec::new();
    for (i, d) in s.data.iter().enumerate() {
        let path = loaded.resolve(Path::new(&d.file));
        if !path.is_file() {
            return Err(Error::config(&file, format!("data[{i}].file"), format!("{} does not exist", path.display())));
        }
        raw.push(load_curves(&path)?);
        paths.push(path);
    }
    let cal = load_calibration(&file, "calibration", &loaded.resolve(Path::new(&s.calibration)), &opts.reports_root)?;
    let groups: Vec<Group> = s
        .data
        .iter()
        .zip(&paths)
        .zip(&raw)
        .map(|((d, path), curves)| Group {
            label: d.label.clone().unwrap_or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()),
            temperature: d.temperature_c,
            curves: curves.iter().map(|c| c.normalised(cal.reference_diameter)).collect(),
        })
        .collect();
    let mut points = reduce(&paths, &groups, &cal.grid, cal.fracture, s.sigma_floor)?;
    // The emulator's own uncertainty at the calibrated θ joins the measurement's.
    let emu_var: Vec<f64> = cal.emulator.predict(&cal.theta).iter().map(|p| p.1).collect();
    for p in &mut points {
        p.sigma = (p.sigma.powi(2) + emu_var[p.k]).sqrt();
    }
    let want_table = s.candidates.contains(&CurveCandidate::Curvature);
    let steps = 2 + s.candidates.len() * s.max_effects + if want_table { s.curvature.roundness.len() + 1 } else { 0 };
    let pb = progress_bar(steps as u64, opts.progress, crate::runkit::PROGRESS_COUNT);
    let table = if want_table {
        pb.set_message("curvature table: FE runs at the calibrated constants");
        Some(curvature_table(&cal, &s.curvature, &|| pb.inc(1))?)
    } else {
        None
    };
    let names: Vec<String> = cal.model.space().params().iter().map(|p| p.name.clone()).collect();
    let bounds: Vec<(f64, f64)> = cal.model.space().params().iter().map(|p| (p.lower, p.upper)).collect();
    let base = |t: &[f64]| cal.emulator.means(t, cal.grid.len());
    let inputs_loop = CurveInputs {
        model: CurveModel { base: &base, grid: &cal.grid, points: &points, temperatures: groups.iter().map(|g| g.temperature).collect(), t_ref: s.data[0].temperature_c, table: table.as_ref(), base_dim: names.len() },
        names,
        bounds,
        candidates: s.candidates.clone(),
        max_effects: s.max_effects,
        koh: KohOptions { seed: s.seed, ..s.koh.clone() },
        prior: match s.theta {
            ThetaPrior::Calibration => Some(cal.posterior.clone()),
            ThetaPrior::Bounds => None,
        },
    };
    let outcome = inputs_loop.analyse(&|m: &str| {
        pb.set_message(m.to_string());
        pb.inc(1);
    })?;
    let base_ls = inputs_loop.model.eval(&[], &outcome.theta_ls);
    let trend = trend_along_curve(&points, &base_ls, groups.len(), s.seed)?;

    let mut dir = ReportDir::create(&opts.reports_root, &loaded.name)?;
    write_curve_tables(&mut dir, &groups, &points, &cal, &outcome, &base_ls, table.as_ref())?;
    let where_ = disagreement(&outcome.stages[0].fit, &points, groups.len());
    let verdict = curve_verdict(loaded, s, &groups, &outcome, &where_, &trend);
    let json = serde_json::to_string_pretty(&verdict).map_err(|e| Error::numerical("verdict.json", e.to_string()))?;
    dir.write_bytes("verdict.json", json.as_bytes())?;
    dir.write_bytes("summary.md", curve_summary(s, &groups, &outcome, &where_, &trend).as_bytes())?;
    pb.set_message("figures");
    let mut failures = Vec::new();
    let rendered = crate::report::discrepancy::render_curves(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    let mut inputs = vec![InputFile::hash(&loaded.path)?];
    for p in cal.inputs.iter().chain(&paths) {
        inputs.push(InputFile::hash(p)?);
    }
    let mut evaluations = BTreeMap::new();
    evaluations.insert("koh_fits".to_string(), (outcome.evidence.iter().filter(|e| e.fit.is_some()).count() + 1) as u64);
    evaluations.insert("fe_runs".to_string(), table.as_ref().map_or(0, |t| t.roundness.len() as u64));
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let headline = curve_headline(&outcome);
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines: vec![headline] })
}

fn term_names(t: &[CurveCandidate]) -> String {
    if t.is_empty() { "none".into() } else { t.iter().map(|c| c.name()).collect::<Vec<_>>().join(" then ") }
}

fn curve_headline(o: &CurveOutcome) -> String {
    let (b, a) = (&o.stages[0], o.stages.last().unwrap_or(&o.stages[0]));
    format!("crush curves: terms named: {}; gap RMS(δ/σ) {:.2} → {:.2}; RMS δ {:.3} N → {:.3} N", term_names(&o.named), b.gap, a.gap, b.fit.delta_rms, a.fit.delta_rms)
}

/// The parameter of the term a candidate fit added (its last θ): (median, 5 %, 95 %).
fn added_parameter(fit: &KohFit) -> (f64, f64, f64) {
    let i = fit.theta_median.len() - 1;
    (fit.theta_median[i], fit.theta_90[i].0, fit.theta_90[i].1)
}

fn curve_verdict(loaded: &StudyFile, s: &CurveStudy, groups: &[Group], o: &CurveOutcome, where_: &[Disagreement], trend: &[(f64, f64)]) -> serde_json::Value {
    use serde_json::json;
    let (b, a) = (&o.stages[0], o.stages.last().unwrap_or(&o.stages[0]));
    let evidence: Vec<serde_json::Value> = o
        .evidence
        .iter()
        .map(|e| {
            let par = e.fit.as_ref().map(|f| {
                let (m, lo, hi) = added_parameter(f);
                json!({ "name": e.candidate.parameter(), "median": m, "q05": lo, "q95": hi })
            });
            json!({
                "round": e.round + 1,
                "candidate": e.candidate.name(),
                "skipped": e.skipped,
                "bic": e.fit.as_ref().map(|f| f.bic),
                "delta_bic": if e.delta_bic.is_finite() { json!(e.delta_bic) } else { json!(null) },
                "gap": e.fit.as_ref().map(|_| e.gap),
                "delta_rms_n": e.fit.as_ref().map(|f| f.delta_rms),
                "parameter": par,
                "named": e.named,
            })
        })
        .collect();
    json!({
        "study": loaded.name,
        "calibration": s.calibration,
        "effects_named": o.named.iter().map(|c| c.name()).collect::<Vec<_>>(),
        "gap_before": b.gap,
        "gap_after": a.gap,
        "gap_measure": CURVE_GAP_MEASURE,
        "delta_rms_before_n": b.fit.delta_rms,
        "delta_rms_after_n": a.fit.delta_rms,
        "bic_before": b.fit.bic,
        "bic_after": a.fit.bic,
        "guard": format!("a term is named when it lowers BIC by more than {} against the current model", -BIC_STRONG),
        "evidence": evidence,
        "disagreement_before": groups.iter().zip(where_).map(|(g, w)| json!({
            "file": g.label,
            "temperature_c": g.temperature,
            "from_um": w.map(|w| w.0 * 1e6),
            "to_um": w.map(|w| w.1 * 1e6),
            "largest_relative_delta": w.map(|w| w.2),
        })).collect::<Vec<_>>(),
        "trend_along_curve": groups.iter().zip(trend).map(|(g, t)| json!({
            "file": g.label,
            "spearman_rho": if t.0.is_finite() { json!(t.0) } else { json!(null) },
            "p_permutation": if t.1.is_finite() { json!(t.1) } else { json!(null) },
        })).collect::<Vec<_>>(),
        "parameters_after": a.fit.names.iter().zip(&a.fit.theta_median).zip(&a.fit.theta_90).map(|((n, m), q)| json!({ "name": n, "median": m, "q05": q.0, "q95": q.1 })).collect::<Vec<_>>(),
    })
}

#[allow(clippy::too_many_arguments)]
fn write_curve_tables(dir: &mut ReportDir, groups: &[Group], points: &[Point], cal: &Calibrated, o: &CurveOutcome, base_ls: &[f64], ratios: Option<&RatioTable>) -> Result<()> {
    // points.csv: data, model and δ before and after.
    let (b, a) = (&o.stages[0], o.stages.last().unwrap_or(&o.stages[0]));
    let mut t = table(vec![
        scol("file", points.iter().map(|p| groups[p.group].label.clone()).collect()),
        fcol("temperature_c", points.iter().map(|p| p.temperature).collect()),
        fcol("displacement_m", points.iter().map(|p| p.x).collect()),
        fcol("force_mean_n", points.iter().map(|p| p.mean).collect()),
        fcol("sigma_n", points.iter().map(|p| p.sigma).collect()),
        ucol("particles", points.iter().map(|p| p.particles as u64).collect()),
        fcol("model_least_squares_n", base_ls.to_vec()),
        fcol("model_before_n", b.model.clone()),
        fcol("delta_before_n", b.fit.delta.clone()),
        fcol("delta_sd_before_n", b.fit.delta_sd.clone()),
        fcol("model_after_n", a.model.clone()),
        fcol("delta_after_n", a.fit.delta.clone()),
        fcol("delta_sd_after_n", a.fit.delta_sd.clone()),
    ])?;
    dir.write_table("curve_points", &mut t)?;

    // curve_residuals.csv: every particle at every point, standardised by the particle scatter.
    let (mut f, mut part, mut x, mut r) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, p) in points.iter().enumerate() {
        for c in &groups[p.group].curves {
            if let Some(v) = c.force_at(p.x) {
                f.push(groups[p.group].label.clone());
                part.push(c.particle.clone());
                x.push(p.x);
                r.push((v - base_ls[i]) / p.scatter);
            }
        }
    }
    let mut t = table(vec![scol("file", f), scol("particle", part), fcol("displacement_m", x), fcol("residual", r)])?;
    dir.write_table("curve_residuals", &mut t)?;

    // curve_evidence.csv
    let ev = &o.evidence;
    let par = |k: usize| {
        ev.iter()
            .map(|e| {
                e.fit.as_ref().map_or(f64::NAN, |f| {
                    let p = added_parameter(f);
                    [p.0, p.1, p.2][k]
                })
            })
            .collect::<Vec<f64>>()
    };
    let mut t = table(vec![
        ucol("round", ev.iter().map(|e| e.round as u64 + 1).collect()),
        scol("candidate", ev.iter().map(|e| e.candidate.name().to_string()).collect()),
        scol("equation", ev.iter().map(|e| e.candidate.equation().to_string()).collect()),
        scol("skipped", ev.iter().map(|e| e.skipped.clone().unwrap_or_default()).collect()),
        fcol("bic", ev.iter().map(|e| e.fit.as_ref().map_or(f64::NAN, |f| f.bic)).collect()),
        fcol("delta_bic", ev.iter().map(|e| e.delta_bic).collect()),
        fcol("gap", ev.iter().map(|e| e.gap).collect()),
        scol("parameter", ev.iter().map(|e| e.candidate.parameter().to_string()).collect()),
        fcol("median", par(0)),
        fcol("q05", par(1)),
        fcol("q95", par(2)),
        scol("named", ev.iter().map(|e| if e.named { "yes" } else { "no" }.to_string()).collect()),
    ])?;
    dir.write_table("curve_evidence", &mut t)?;

    // curve_stages.csv: one row per model and parameter.
    let (mut st, mut terms, mut pn, mut med, mut lo, mut hi, mut gap, mut bic, mut ls) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    for (k, s) in o.stages.iter().enumerate() {
        for (j, n) in s.fit.names.iter().enumerate() {
            st.push(k as u64);
            terms.push(term_names(&s.terms));
            pn.push(n.clone());
            med.push(s.fit.theta_median[j]);
            lo.push(s.fit.theta_90[j].0);
            hi.push(s.fit.theta_90[j].1);
            gap.push(s.gap);
            bic.push(s.fit.bic);
            ls.push(if k == 0 { o.theta_ls[j] } else { f64::NAN });
        }
    }
    let mut t = table(vec![
        ucol("stage", st),
        scol("terms", terms),
        scol("parameter", pn),
        fcol("median", med),
        fcol("q05", lo),
        fcol("q95", hi),
        fcol("least_squares_without_delta", ls),
        fcol("gap", gap),
        fcol("bic", bic),
    ])?;
    dir.write_table("curve_stages", &mut t)?;

    // curvature_table.csv and the calibration's θ.
    if let Some(tab) = ratios {
        let (mut rho, mut xs, mut ph) = (vec![], vec![], vec![]);
        for (r, row) in tab.roundness.iter().zip(&tab.ratio) {
            for (xk, v) in cal.grid.iter().zip(row) {
                rho.push(*r);
                xs.push(*xk);
                ph.push(*v);
            }
        }
        let mut t = table(vec![fcol("roundness", rho), fcol("displacement_m", xs), fcol("force_ratio", ph)])?;
        dir.write_table("curvature_table", &mut t)?;
    }
    Ok(())
}

fn curve_summary(s: &CurveStudy, groups: &[Group], o: &CurveOutcome, where_: &[Disagreement], trend: &[(f64, f64)]) -> String {
    let (b, a) = (&o.stages[0], o.stages.last().unwrap_or(&o.stages[0]));
    let mut md = String::from("# Discrepancy of the calibrated crush FE against measured curves\n\n");
    md.push_str(&format!("Calibration: `{}` (its emulator and posterior). Data: ", s.calibration));
    md.push_str(&groups.iter().map(|g| format!("{} ({} curves, {} °C)", g.label, g.curves.len(), g.temperature)).collect::<Vec<_>>().join(", "));
    md.push_str(&format!(".\n\n**Terms named: {}.** Gap RMS(δ̂/σ) {:.2} → {:.2}; RMS δ̂ {:.3} N → {:.3} N; BIC {:.1} → {:.1}.\n\n", term_names(&o.named), b.gap, a.gap, b.fit.delta_rms, a.fit.delta_rms, b.fit.bic, a.fit.bic));
    md.push_str("## Where the calibrated model disagrees (base model, |δ̂| > 2σ of the mean curve)\n\n");
    for ((g, w), t) in groups.iter().zip(where_).zip(trend) {
        match w {
            Some((lo, hi, rel)) => md.push_str(&format!("* {}: from {:.1} to {:.1} µm (normalised), largest |δ̂|/F {:.1} %", g.label, lo * 1e6, hi * 1e6, 100.0 * rel)),
            None => md.push_str(&format!("* {}: nowhere", g.label)),
        }
        md.push_str(&format!("; least-squares residual trend along the curve: Spearman ρ {:.2} (permutation p {:.3})\n", t.0, t.1));
    }
    md.push_str("\n## Evidence (ΔBIC against the round's current model; named below −6)\n\n| round | candidate | ΔBIC | gap | parameter | median [90 %] | verdict |\n|---|---|---|---|---|---|---|\n");
    for e in &o.evidence {
        match &e.fit {
            Some(f) => {
                let (m, lo, hi) = added_parameter(f);
                md.push_str(&format!(
                    "| {} | {} | {:.1} | {:.2} | {} | {:.4} [{:.4}, {:.4}] | {} |\n",
                    e.round + 1,
                    e.candidate.name(),
                    e.delta_bic,
                    e.gap,
                    e.candidate.parameter(),
                    m,
                    lo,
                    hi,
                    if e.named {
                        "**named**"
                    } else if e.delta_bic < BIC_STRONG {
                        "passed, weaker"
                    } else {
                        "not supported"
                    }
                ));
            }
            None => md.push_str(&format!("| {} | {} | – | – | – | – | skipped: {} |\n", e.round + 1, e.candidate.name(), e.skipped.clone().unwrap_or_default())),
        }
    }
    md.push_str("\n## Constants before and after (posterior median [90 %])\n\n| parameter | base model | final model |\n|---|---|---|\n");
    for (j, n) in a.fit.names.iter().enumerate() {
        let before = b.fit.names.iter().position(|m| m == n).map_or("–".to_string(), |i| format!("{:.4e} [{:.4e}, {:.4e}]", b.fit.theta_median[i], b.fit.theta_90[i].0, b.fit.theta_90[i].1));
        md.push_str(&format!("| {} | {} | {:.4e} [{:.4e}, {:.4e}] |\n", n, before, a.fit.theta_median[j], a.fit.theta_90[j].0, a.fit.theta_90[j].1));
    }
    md.push_str("\nEquations of the terms, the gap measure and the guard: `partlife::discrepancy::curves` (module documentation). Figure `discrepancy_curves`: measured mean curves with the base and final model (top) and δ̂ with its 90 % band before and after (bottom).\n");
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_is_exact_on_hertzian_curves_and_compliance_solves_its_equation() {
        // F = k x^1.5 is linear in F^(2/3): exact between grid points and beyond the last.
        let k = 3e9;
        let grid: Vec<f64> = (1..=8).map(|i| i as f64 * 2e-6).collect();
        let f: Vec<f64> = grid.iter().map(|x| k * x.powf(1.5)).collect();
        for x in [0.5e-6, 3e-6, 7.7e-6, 15.9e-6, 18e-6] {
            assert!((interp(&grid, &f, x) / (k * x.powf(1.5)) - 1.0).abs() < 1e-12, "x = {x}");
        }
        // With compliance c the recorded force solves F = k (x − cF)^1.5.
        let c = 0.05e-6;
        for x in [3e-6, 9e-6, 15e-6] {
            let got = with_compliance(&grid, &f, x, c);
            assert!((got - k * (x - c * got).powf(1.5)).abs() < 1e-9 * got, "x = {x}: {got}");
            assert!(got < k * x.powf(1.5));
        }
    }

    #[test]
    fn ratio_table_interpolates_linearly_in_roundness() {
        let t = RatioTable { roundness: vec![0.5, 0.75, 1.0], ratio: vec![vec![0.5, 0.7], vec![0.8, 0.9], vec![1.0, 1.0]] };
        assert_eq!(t.at(0.5, 0), 0.5);
        assert!((t.at(0.625, 0) - 0.65).abs() < 1e-12);
        assert!((t.at(0.875, 1) - 0.95).abs() < 1e-12);
        assert_eq!(t.at(1.0, 1), 1.0);
        // Clamped outside the table.
        assert_eq!(t.at(0.2, 0), 0.5);
    }

    /// The fast sibling of the slow `curve_loop_names_curvature` test (tests/discrepancy_curves.rs,
    /// which runs the fine-mesh FE): the same loop on a Hertzian base model F = θ·10⁹·x^1.5 with a
    /// known ratio table Φ(ρ, x_k) = 1 − (1 − ρ)e^(−k/4) (an asperity softens the start of the
    /// curve), data made with ρ = 0.6. The loop must name curvature first, put ρ = 0.6 in its
    /// 90 % range, skip temperature (one temperature) and shrink the gap.
    #[test]
    fn the_loop_names_a_hidden_curvature_and_recovers_it() {
        let grid: Vec<f64> = (1..=14).map(|i| i as f64 * 1.5e-6).collect();
        let phi = |rho: f64| -> Vec<f64> { (0..grid.len()).map(|k| 1.0 - (1.0 - rho) * (-(k as f64) / 4.0).exp()).collect() };
        let table = RatioTable { roundness: vec![0.4, 0.55, 0.7, 0.85, 1.0], ratio: [0.4, 0.55, 0.7, 0.85, 1.0].iter().map(|&r| phi(r)).collect() };
        let base = |t: &[f64]| -> Vec<f64> { grid.iter().map(|x| t[0] * 1e9 * x.powf(1.5)).collect() };
        let truth: Vec<f64> = base(&[1.0]).iter().zip(phi(0.6)).map(|(f, p)| f * p).collect();
        let points: Vec<Point> = (0..grid.len())
            .map(|k| Point { group: 0, k, x: grid[k], temperature: 20.0, mean: truth[k], scatter: 0.02 + 0.005 * truth[k], particles: 1, sigma: 0.02 + 0.005 * truth[k] })
            .collect();
        let inputs = CurveInputs {
            model: CurveModel { base: &base, grid: &grid, points: &points, temperatures: vec![20.0], t_ref: 20.0, table: Some(&table), base_dim: 1 },
            names: vec!["stiffness".into()],
            bounds: vec![(0.5, 2.0)],
            candidates: vec![CurveCandidate::Compliance, CurveCandidate::Temperature, CurveCandidate::Curvature],
            max_effects: 2,
            koh: KohOptions { walkers: 16, steps: 1500, burn_in: 1000, delta_draws: 100, seed: 7 },
            prior: None,
        };
        let o = inputs.analyse(&|_| {}).unwrap();
        assert_eq!(o.named.first(), Some(&CurveCandidate::Curvature), "named {:?}", o.named);
        let stage = &o.stages[1];
        let (lo, hi) = stage.fit.theta_90[1];
        assert!(lo <= 0.6 && 0.6 <= hi && hi - lo < 0.2, "ρ range [{lo}, {hi}]");
        let skipped = o.evidence.iter().find(|e| e.candidate == CurveCandidate::Temperature).and_then(|e| e.skipped.clone()).unwrap_or_default();
        assert!(skipped.contains("one temperature"), "{skipped}");
        assert!(stage.gap < 0.5 * o.stages[0].gap, "gap {} → {}", o.stages[0].gap, stage.gap);
    }
}

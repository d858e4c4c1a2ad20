//! The curve-level model and its loop: the measured curves reduced to mean forces on the
//! calibration's grid, the calibrated model with candidate terms ([`CurveModel`]), and the
//! name → add → shrink loop ([`CurveInputs::analyse`]) with its Kennedy–O'Hagan fits.

use std::path::PathBuf;
use rayon::prelude::*;
use crate::discrepancy::koh::{self, BIC_STRONG, KohFit, KohOptions, Problem};
use crate::calibrate::data::Curve;
use crate::error::{Error, Result};
use crate::stats;
use crate::fracture::FractureParams;
use super::CurveCandidate;

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
    let v = if x <= grid[0] || grid.len() == 1 {
        // The segment from the origin to the first grid point.
        stats::lerp(&[0.0, g(f[0])], stats::locate(&[0.0, grid[0]], x))
    } else {
        let (j, t) = stats::locate(grid, x);
        stats::lerp(&[g(f[j - 1]), g(f[j])], (1, t))
    };
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
    /// `Φ[r][k]`.
    pub ratio: Vec<Vec<f64>>,
}

impl RatioTable {
    fn at(&self, rho: f64, k: usize) -> f64 {
        let (j, t) = stats::locate(&self.roundness, rho);
        stats::lerp(&[self.ratio[j - 1][k], self.ratio[j][k]], (1, t.clamp(0.0, 1.0)))
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
            crate::discrepancy::gof::covariate_trend(&r, &x, 999, seed.wrapping_add(g as u64))
        })
        .collect()
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
}

//! Kennedy–O'Hagan calibration with a Gaussian-process model discrepancy, and the
//! name → add → shrink comparison of candidate model terms (issue 7, item 4).
//!
//! ```text
//! y_i = η(x_i, θ) + δ(x_i) + ε_i,   δ ~ GP(0, σ_δ² k_ℓ),   ε_i ~ N(0, σ_ε,i²) (σ_ε,i known)
//! ```
//!
//! k_ℓ is the squared-exponential kernel with one length per input dimension. With
//! `constrain_origin` (one input), δ is conditioned on δ(0) = 0 and δ′(0) = 0, the constrained
//! prior Brynjarsdóttir & O'Hagan (2014) show is needed for the "simple machine":
//!
//! ```text
//! k_c(x, x′) = σ_δ² [e^(−(x − x′)²/2ℓ²) − e^(−(x² + x′²)/2ℓ²) (1 + x x′/ℓ²)]
//! ```
//!
//! Inference is fully Bayesian over (θ, ln σ_δ, ln ℓ): θ uniform in its bounds, ln σ_δ uniform
//! on [ln(10⁻⁴ s_y), ln(10 s_y)] (s_y the sd of y, so δ may collapse to nothing), ln ℓ uniform on
//! [ln(0.1 r), ln(10 r)] (r the input's range); the GP is integrated out, so the likelihood is
//! N(y − η(θ); 0, K + σ_ε² I). Sampled with the ensemble sampler ([`crate::calibrate::mcmc`]).
//! The posterior mean of δ at the data is averaged over thinned draws of K(K + σ_ε² I)⁻¹(y − η).
//!
//! **Comparing model terms.** Each candidate is the simulator with one more physical term (and
//! its parameter). A candidate is named when it lowers BIC = −2 max ℓ + p ln n by more than 6
//! ("strong" evidence, Kass & Raftery 1995) against the current model; its discrepancy should
//! then collapse (posterior σ_δ and RMS δ down to the noise level) and θ be recovered.
//!
//! Verified in `tests/verification/koh.rs` on the simple machine (least squares without δ gives
//! the biased θ̂ = 0.5624; the constrained-δ posterior covers θ = 0.65; adding the saturation
//! term collapses δ and recovers θ and a) and on the ball drop (linear drag leaves a structured
//! δ(h, R); adding quadratic drag is named, δ collapses and C is recovered).

use nalgebra::{DMatrix, DVector};

use crate::calibrate::Noise;
use crate::calibrate::lsq::{self, LsqOptions};
use crate::calibrate::mcmc::{EnsembleOptions, ensemble};
use crate::error::{Error, Result};
use crate::model::{OutputSpec, Simulator};
use crate::params::{Param, ParamSpace};
use crate::stats::interpolated_quantiles;

/// The simulator at every data point as a function of θ.
pub type ModelFn<'a> = dyn Fn(&[f64]) -> Vec<f64> + Sync + 'a;

/// A log prior density of θ.
pub type PriorFn<'a> = dyn Fn(&[f64]) -> f64 + Sync + 'a;

/// A calibration problem with discrepancy.
pub struct Problem<'a> {
    /// Name of the model (for reports).
    pub name: String,
    /// Inputs of δ at the data points (n × d).
    pub x: Vec<Vec<f64>>,
    /// Observations.
    pub y: Vec<f64>,
    /// Known noise sd σ_ε,i, one per observation.
    pub noise_sd: Vec<f64>,
    /// The simulator η(θ) at every data point.
    pub model: &'a ModelFn<'a>,
    /// Names of θ.
    pub names: Vec<String>,
    /// Bounds of θ (uniform prior).
    pub bounds: Vec<(f64, f64)>,
    /// Condition δ on δ(0) = 0 and δ′(0) = 0 (one input only).
    pub constrain_origin: bool,
    /// Log prior density of θ (up to a constant) beyond the uniform bounds, for example the
    /// posterior of an earlier calibration; it then counts as data in the BIC.
    pub prior: Option<&'a PriorFn<'a>>,
}

/// Sampler settings (also a study's `[koh]` section; the seed comes from the study).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct KohOptions {
    /// Walkers.
    pub walkers: usize,
    /// Steps after burn-in.
    pub steps: usize,
    /// Burn-in steps.
    pub burn_in: usize,
    /// Draws used for the posterior mean of δ.
    pub delta_draws: usize,
    /// Seed.
    #[serde(skip)]
    pub seed: u64,
}

impl Default for KohOptions {
    fn default() -> Self {
        KohOptions { walkers: 32, steps: 3000, burn_in: 2000, delta_draws: 400, seed: 20261122 }
    }
}

/// A fitted model with discrepancy.
#[derive(Debug, Clone, PartialEq)]
pub struct KohFit {
    /// Model name.
    pub name: String,
    /// θ names.
    pub names: Vec<String>,
    /// θ at the highest posterior density found.
    pub theta_map: Vec<f64>,
    /// Posterior median of θ.
    pub theta_median: Vec<f64>,
    /// 5 % and 95 % posterior quantiles of θ.
    pub theta_90: Vec<(f64, f64)>,
    /// Posterior median of σ_δ.
    pub sigma_delta: f64,
    /// Posterior median of the lengths.
    pub lengths: Vec<f64>,
    /// Largest log-likelihood found (GP integrated out; plus the log prior of θ when the
    /// problem has one).
    pub max_loglik: f64,
    /// BIC = −2 max ℓ + (dim θ + 1 + d) ln n.
    pub bic: f64,
    /// Posterior mean of δ at the data points.
    pub delta: Vec<f64>,
    /// Posterior sd of δ at the data points (over θ, σ_δ, ℓ and the GP).
    pub delta_sd: Vec<f64>,
    /// RMS of that mean.
    pub delta_rms: f64,
}

fn sq(v: f64) -> f64 {
    v * v
}

/// Squared-exponential covariance of the discrepancy between two inputs.
fn kernel(a: &[f64], b: &[f64], s2: f64, ell: &[f64], constrain: bool) -> f64 {
    let r2: f64 = a.iter().zip(b).zip(ell).map(|((x, y), l)| sq((x - y) / l)).sum();
    let mut k = (-0.5 * r2).exp();
    if constrain {
        let (x, y, l) = (a[0], b[0], ell[0]);
        k -= (-(x * x + y * y) / (2.0 * l * l)).exp() * (1.0 + x * y / (l * l));
    }
    s2 * k
}

impl Problem<'_> {
    fn dim_x(&self) -> usize {
        self.x.first().map_or(0, |v| v.len())
    }

    fn check(&self) -> Result<()> {
        let n = self.y.len();
        if n < 3 || self.x.len() != n || self.x.iter().any(|v| v.len() != self.dim_x()) {
            return Err(Error::numerical("discrepancy GP", format!("{} inputs for {n} observations (need ≥ 3)", self.x.len())));
        }
        if self.constrain_origin && self.dim_x() != 1 {
            return Err(Error::numerical("discrepancy GP", "the δ(0) = 0, δ′(0) = 0 constraint needs one input"));
        }
        if self.bounds.len() != self.names.len() || self.bounds.iter().any(|(a, b)| a.partial_cmp(b) != Some(std::cmp::Ordering::Less)) || self.noise_sd.len() != n || self.noise_sd.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(Error::numerical("discrepancy GP", "θ bounds must be ordered and every observation needs a noise sd > 0"));
        }
        Ok(())
    }

    fn hyper_bounds(&self) -> Vec<(f64, f64)> {
        let n = self.y.len() as f64;
        let mean = self.y.iter().sum::<f64>() / n;
        let noise = self.noise_sd.iter().fold(0.0_f64, |a, &b| a.max(b));
        let sy = (self.y.iter().map(|v| sq(v - mean)).sum::<f64>() / n).sqrt().max(noise);
        let mut b = vec![((1e-4 * sy).ln(), (10.0 * sy).ln())];
        for k in 0..self.dim_x() {
            let (lo, hi) = self.x.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v[k]), b.max(v[k])));
            let r = (hi - lo).max(1e-12);
            b.push(((0.1 * r).ln(), (10.0 * r).ln()));
        }
        b
    }

    /// Covariance K of δ at the data and the residual, for a parameter point p = (θ, ln σ_δ, ln ℓ).
    fn parts(&self, p: &[f64]) -> (DMatrix<f64>, DVector<f64>) {
        let nt = self.names.len();
        let n = self.y.len();
        let s2 = (2.0 * p[nt]).exp();
        let ell: Vec<f64> = p[nt + 1..].iter().map(|v| v.exp()).collect();
        let k = DMatrix::from_fn(n, n, |i, j| kernel(&self.x[i], &self.x[j], s2, &ell, self.constrain_origin));
        let eta = (self.model)(&p[..nt]);
        let r = DVector::from_fn(n, |i, _| self.y[i] - eta.get(i).copied().unwrap_or(f64::NAN));
        (k, r)
    }

    /// Log-likelihood with δ integrated out (−∞ where undefined).
    pub fn loglik(&self, p: &[f64]) -> f64 {
        let n = self.y.len();
        let (k, r) = self.parts(p);
        if r.iter().any(|v| !v.is_finite()) {
            return f64::NEG_INFINITY;
        }
        let mut s = k;
        for i in 0..n {
            s[(i, i)] += sq(self.noise_sd[i]) * (1.0 + 1e-10);
        }
        let Some(ch) = s.cholesky() else { return f64::NEG_INFINITY };
        let alpha = ch.solve(&r);
        let logdet: f64 = ch.l().diagonal().iter().map(|d| 2.0 * d.ln()).sum();
        -0.5 * (r.dot(&alpha) + logdet + n as f64 * (2.0 * std::f64::consts::PI).ln())
    }

    /// Conditional mean and variance of δ at the data given (θ, σ_δ, ℓ).
    fn delta_moments(&self, p: &[f64]) -> Option<(DVector<f64>, DVector<f64>)> {
        let (k, r) = self.parts(p);
        let mut s = k.clone();
        for i in 0..self.y.len() {
            s[(i, i)] += sq(self.noise_sd[i]) * (1.0 + 1e-10);
        }
        let ch = s.cholesky()?;
        let mean = &k * ch.solve(&r);
        let reduced = &k * ch.solve(&k);
        let var = DVector::from_fn(self.y.len(), |i, _| (k[(i, i)] - reduced[(i, i)]).max(0.0));
        Some((mean, var))
    }
}

/// The simulator of a problem at its data points, as the calibration engine's [`Simulator`].
struct AtData<'p, 'a> {
    problem: &'p Problem<'a>,
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
}

impl Simulator for AtData<'_, '_> {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        Ok((self.problem.model)(theta))
    }
}

/// Least squares of y − η(θ) without discrepancy (the calibration engine's multi-start
/// Levenberg–Marquardt within the bounds): the estimate a calibration that ignores δ reports.
pub fn least_squares(problem: &Problem) -> Result<Vec<f64>> {
    problem.check()?;
    let params = problem
        .names
        .iter()
        .zip(&problem.bounds)
        .map(|(n, (a, b))| Param::uniform(n, "-", *a, *b, 0.5 * (a + b)))
        .collect();
    let sim = AtData {
        problem,
        space: ParamSpace::new(params)?,
        outputs: (0..problem.y.len()).map(|i| OutputSpec::new(format!("y{i}"), "-")).collect(),
    };
    let noise = Noise::Known { sigma: problem.noise_sd.clone() };
    Ok(lsq::fit(&sim, &problem.y, &noise, &LsqOptions::default())?.theta)
}

/// Samples the posterior of (θ, σ_δ, ℓ) and summarises it.
pub fn fit(problem: &Problem, opts: &KohOptions) -> Result<KohFit> {
    problem.check()?;
    let nt = problem.names.len();
    let mut bounds = problem.bounds.clone();
    bounds.extend(problem.hyper_bounds());
    let dim = bounds.len();
    let log_post = |p: &[f64]| -> f64 {
        if p.iter().zip(&bounds).any(|(v, (a, b))| !(v >= a && v <= b)) {
            return f64::NEG_INFINITY;
        }
        problem.loglik(p) + problem.prior.map_or(0.0, |f| f(&p[..nt]))
    };
    // Walkers start near the least-squares θ with mid-range hyperparameters.
    let theta0 = least_squares(problem)?;
    let walkers = opts.walkers.max(2 * dim + 2) & !1;
    let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(opts.seed);
    let mut init = Vec::new();
    while init.len() < walkers {
        let p: Vec<f64> = (0..dim)
            .map(|k| {
                let (a, b) = bounds[k];
                let centre = if k < nt { theta0[k] } else { a + 0.6 * (b - a) };
                (centre + 0.02 * (b - a) * (rand::Rng::random::<f64>(&mut rng) - 0.5)).clamp(a, b)
            })
            .collect();
        if log_post(&p).is_finite() {
            init.push(p);
        }
        if init.is_empty() && rand::Rng::random::<f64>(&mut rng) < 1e-4 {
            return Err(Error::numerical("discrepancy GP", "no finite starting point"));
        }
    }
    let chains = ensemble(
        log_post,
        init,
        &EnsembleOptions { walkers, steps: opts.steps, burn_in: opts.burn_in, stretch: 2.0, seed: opts.seed },
    )?;
    let (mut best, mut best_lp) = (Vec::new(), f64::NEG_INFINITY);
    for (s, lp) in chains.draws.iter().zip(&chains.log_prob) {
        for (p, l) in s.iter().zip(lp) {
            if *l > best_lp {
                best_lp = *l;
                best = p.clone();
            }
        }
    }
    let q = |k: usize| interpolated_quantiles(chains.flat(k), &[0.05, 0.5, 0.95]);
    let med = |k: usize| q(k)[1];
    let theta_median: Vec<f64> = (0..nt).map(med).collect();
    let theta_90: Vec<(f64, f64)> = (0..nt).map(q).map(|v| (v[0], v[2])).collect();
    let sigma_delta = med(nt).exp();
    let lengths: Vec<f64> = (nt + 1..dim).map(|k| med(k).exp()).collect();
    // Posterior mean of δ over thinned draws.
    let all: Vec<&Vec<f64>> = chains.draws.iter().flat_map(|s| s.iter()).collect();
    let stride = (all.len() / opts.delta_draws.max(1)).max(1);
    let n = problem.y.len();
    let (mut delta, mut second) = (DVector::<f64>::zeros(n), DVector::<f64>::zeros(n));
    let mut used = 0;
    for p in all.iter().step_by(stride) {
        if let Some((m, v)) = problem.delta_moments(p) {
            second += v + m.component_mul(&m);
            delta += m;
            used += 1;
        }
    }
    if used == 0 {
        return Err(Error::numerical("discrepancy GP", "no posterior draw gave a positive-definite covariance"));
    }
    delta /= used as f64;
    second /= used as f64;
    let delta_sd: Vec<f64> = (0..n).map(|i| (second[i] - sq(delta[i])).max(0.0).sqrt()).collect();
    let delta: Vec<f64> = delta.iter().copied().collect();
    let delta_rms = (delta.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    let max_loglik = best_lp;
    let bic = -2.0 * max_loglik + dim as f64 * (n as f64).ln();
    Ok(KohFit {
        name: problem.name.clone(),
        names: problem.names.clone(),
        theta_map: best[..nt].to_vec(),
        theta_median,
        theta_90,
        sigma_delta,
        lengths,
        max_loglik,
        bic,
        delta,
        delta_sd,
        delta_rms,
    })
}

/// Evidence threshold of the comparison: ΔBIC below −6 is "strong" (Kass & Raftery 1995).
pub const BIC_STRONG: f64 = -6.0;

/// One round of name → add → shrink: fits the current model and every candidate (each the
/// current model with one more term) and names the candidate with the lowest BIC if it beats
/// the current model by more than [`BIC_STRONG`]. Returns the fits (current first) and the
/// index into `candidates` of the one named.
pub fn compare(current: &Problem, candidates: &[Problem], opts: &KohOptions) -> Result<(Vec<KohFit>, Option<usize>)> {
    let mut fits = vec![fit(current, opts)?];
    for (k, c) in candidates.iter().enumerate() {
        fits.push(fit(c, &KohOptions { seed: opts.seed.wrapping_add(k as u64 + 1), ..opts.clone() })?);
    }
    let base = fits[0].bic;
    let best = (1..fits.len()).min_by(|&a, &b| fits[a].bic.total_cmp(&fits[b].bic));
    let named = best.filter(|&i| fits[i].bic - base < BIC_STRONG).map(|i| i - 1);
    Ok((fits, named))
}

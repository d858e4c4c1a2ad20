//! The joint uncertainty of a fitted strength model: draws of (m, μ, β).
//!
//! The Weibull regression is a log-location-scale model, y = ln σ̄ = μ + β·z + b·w with w
//! standard minimum-Gumbel and b = 1/m ([`super::regress`]). For such a model the maximum-
//! likelihood estimates give pivotal quantities whose distribution does not depend on the
//! unknown parameters (Lawless 2003, §6.3):
//!
//! ```text
//! b̂/b,   (μ̂ − μ)/b̂,   (β̂ − β)/b̂
//! ```
//!
//! so simulating unit samples (μ = 0, β = 0, b = 1) at the observed covariates and refitting
//! gives exact draws (μ*, β*, b*) of those pivots, and the draws
//!
//! ```text
//! b = b̂/b*,   μ = μ̂ − b̂ μ*/b*,   β = β̂ − b̂ β*/b*
//! ```
//!
//! are the parametric bootstrap in pivotal form ([`Uncertainty::Bootstrap`]). Without effects
//! this is exactly ASTM C1239's pivotal simulation (m_j = m̂/q_j with q = m̂* of a unit sample,
//! ln σ_j = ln σ̂ − t_j/m̂ with t = m̂* ln σ̂*; [`crate::weibull::Pivotal::draws`]). A model that
//! profiles a Tavares–King damage ratio is not location-scale in it; its draws are a plain
//! parametric bootstrap (refits of samples drawn from the fitted model).
//!
//! **Censored samples.** The pivots are exact for complete samples (and type II censoring); a
//! sample with specimens that did not break by a recorded limit, or broke within a class, is
//! type I censored, and (b̂/b, …) then depend on where the limits sit relative to the unknown
//! law. Such a sample's pivots are simulated at the fitted law instead: samples drawn from it,
//! each redraw censored as the campaign censored its row ([`crate::obs::Obs::censor`]), refitted,
//! and the refits (b*, μ*, β*) taken as draws of the pivots — b = b̂²/b*,
//! μ = μ̂ − b̂(μ* − μ̂)/b*, β = β̂ − b̂(β* − β̂)/b* (the parametric bootstrap in pivotal form,
//! exact again where the censoring is type II). Its modulus is corrected for bias by those
//! refits (m̂²/E[m̂*]), not by C1239's unbiasing factor, which is for complete samples.
//!
//! [`Uncertainty::Bayesian`] samples the posterior with the prior flat in (μ, β, ln b) — the
//! right-invariant prior of a location-scale model, ∝ 1/(m σ_θ) without effects — by the
//! ensemble sampler ([`crate::calibrate::mcmc`]); the damage ratio, if any, gets a prior flat in
//! ln x on [10⁻⁴, 0.99]. For location-scale models this prior reproduces the conditional
//! confidence intervals of the pivots, so the two agree on large samples
//! (`tests/verification/strength.rs`).
//!
//! Every draw has its own ChaCha8 stream: the draws do not depend on the thread count.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::Distribution;
use rayon::prelude::*;

use super::effects::Effect;
use super::fit::{ModelFit, StrengthFit};
use super::options::Uncertainty;
use super::regress::{Design, fit};
use crate::error::{Error, Result};

/// Most regression columns (β) a model carries: one per linear effect, L − 1 (or L, partially
/// pooled) per categorical factor's levels.
pub const MAX_LINEAR: usize = 16;

/// Most scale columns (γ) a model carries: L − 1 per categorical factor with a modulus per level.
pub const MAX_SCALE: usize = 8;

/// One set of strength-model parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    /// Weibull modulus m.
    pub shape: f64,
    /// μ = ln σ_θ at z = 0 (ln Pa): the scale of a perfectly round particle of the reference
    /// diameter at the reference temperature.
    pub mu: f64,
    /// β of the regression columns (in the order of [`StrengthFit::beta_columns`]), zero-padded.
    pub beta: [f64; MAX_LINEAR],
    /// γ of the scale columns (a modulus per level: 1/m_i = (1/m) e^(Σ γ_j v_ij)), zero-padded.
    pub gamma: [f64; MAX_SCALE],
}

impl Params {
    /// Modulus `shape` and μ = ln σ_θ, without effects.
    pub fn base(shape: f64, mu: f64) -> Params {
        Params { shape, mu, beta: [0.0; MAX_LINEAR], gamma: [0.0; MAX_SCALE] }
    }

    /// The parameters of a fitted model.
    pub fn of(model: &ModelFit) -> Params {
        let mut p = Params::base(model.shape(), model.reg.mu);
        for (b, v) in p.beta.iter_mut().zip(&model.reg.beta) {
            *b = *v;
        }
        for (g, v) in p.gamma.iter_mut().zip(&model.reg.gamma) {
            *g = *v;
        }
        p
    }
}

impl ModelFit {
    /// Whether its bootstrap draws are pivotal ([`StrengthFit::pivotal`]).
    pub fn pivotal(&self) -> bool {
        self.complete && self.location_scale()
    }

    /// Whether the model is location-scale in all its parameters (one modulus, no penalty, no
    /// profiled damage ratio, the Weibull law): its bootstrap draws are in pivotal form, exact
    /// for a complete sample, simulated at the fit under censoring (module docs).
    pub fn location_scale(&self) -> bool {
        self.damage_ratio.is_none() && self.scale_columns.is_empty() && self.penalty.iter().all(|l| *l == 0.0) && self.law.is_none()
    }

    /// `k` pivotal draws of the parameters (module docs): unit samples at the fitted covariates,
    /// refitted; draw r from its own ChaCha8 stream of `seed`.
    pub fn pivotal_params(&self, k: usize, seed: u64) -> Result<Vec<Params>> {
        let m = self;
        let (b_hat, mu_hat) = (m.reg.b, m.reg.mu);
        let design = Design { columns: &m.columns, offset: None, scale_columns: &m.scale_columns, penalty: &m.penalty };
        let out: Vec<Option<Params>> = (0..k)
            .into_par_iter()
            .map(|r| {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                rng.set_stream(r as u64 + 1);
                // A unit sample is standard exponential (Weibull with m = 1, σ = 1); a refit
                // that fails (vanishingly rare) is replaced by the next sample of its stream.
                for _ in 0..20 {
                    let x: Vec<f64> = (0..m.n).map(|_| rand_distr::Exp1.sample(&mut rng)).collect();
                    if let Ok(u) = fit(crate::obs::Obs::exact(&x), &design) {
                        let mut p = Params::base(u.b / b_hat, mu_hat - b_hat * u.mu / u.b);
                        for (j, b) in p.beta.iter_mut().enumerate().take(m.reg.beta.len()) {
                            *b = m.reg.beta[j] - b_hat * u.beta[j] / u.b;
                        }
                        return Some(p);
                    }
                }
                None
            })
            .collect();
        collect(out, "pivotal simulation")
    }

    /// The exact two-sided `level` confidence band of a single-column effect's β from `k`
    /// pivotal draws: (β̂ − β)/b̂ is pivotal in a location-scale model, so the draws' quantiles
    /// cover β with probability `level` whatever the true parameters (up to Monte Carlo error),
    /// where the Wald and profile bands rely on large samples. None where the pivots do not hold
    /// ([`ModelFit::pivotal`]) or the effect has several columns.
    pub fn pivotal_band(&self, c: &Effect, level: f64, k: usize, seed: u64) -> Option<(f64, f64)> {
        let r = self.beta_range(c)?;
        if !self.pivotal() || r.len() != 1 || r.start >= MAX_LINEAR {
            return None;
        }
        let draws = self.pivotal_params(k, seed).ok()?;
        let a = 0.5 * (1.0 - level);
        let q = crate::stats::interpolated_quantiles(draws.iter().map(|d| d.beta[r.start]).collect(), &[a, 1.0 - a]);
        Some((q[0], q[1]))
    }
}

impl StrengthFit {
    /// The maximum-likelihood estimate.
    pub fn estimate(&self) -> Params {
        Params::of(&self.model)
    }

    /// Whether the bootstrap draws are pivotal (m = m̂/q) rather than plain refits (m = m̂*): the
    /// pivots are exact for a location-scale model — one modulus, no penalty, no profiled damage
    /// ratio — fitted to a complete sample. A modulus per level or partially pooled levels are
    /// not location-scale in all their parameters, and type I censoring breaks the pivots; their
    /// draws are the plain parametric bootstrap (module docs).
    pub fn pivotal(&self) -> bool {
        self.model.pivotal()
    }

    /// The modulus corrected for the bias of its maximum-likelihood estimate, from `draws` of
    /// [`StrengthFit::draws`] with the bootstrap: m̂ / E[m̂/m] over pivotal draws (C1239's
    /// unbiasing factor, generalised), m̂² / E[m̂*] over plain bootstrap refits (the refits' mean
    /// over m̂ is the bias factor).
    pub fn unbiased_shape(&self, draws: &[Params]) -> f64 {
        let m = self.model.shape();
        let k = draws.len() as f64;
        if self.model.location_scale() { m * k / draws.iter().map(|d| m / d.shape).sum::<f64>() } else { m * m * k / draws.iter().map(|d| d.shape).sum::<f64>() }
    }

    /// `k` joint draws of the parameters (seeded; independent of the thread count).
    pub fn draws(&self, how: Uncertainty, k: usize, seed: u64) -> Result<Vec<Params>> {
        if self.model.columns.len() > MAX_LINEAR || self.model.scale_columns.len() > MAX_SCALE {
            return Err(Error::numerical("strength draws", format!("at most {MAX_LINEAR} regression columns and {MAX_SCALE} scale columns (levels of a factor count one each)")));
        }
        match how {
            Uncertainty::Bootstrap if self.pivotal() => self.pivotal_draws(k, seed),
            Uncertainty::Bootstrap if self.model.location_scale() => Ok(self.bootstrap_draws(k, seed)?.iter().map(|d| self.pivotal_form(d)).collect()),
            Uncertainty::Bootstrap => self.bootstrap_draws(k, seed),
            Uncertainty::Bayesian => self.posterior_draws(k, seed),
        }
    }

    /// Pivotal draws: unit samples at the observed covariates, refitted.
    fn pivotal_draws(&self, k: usize, seed: u64) -> Result<Vec<Params>> {
        self.model.pivotal_params(k, seed)
    }

    /// A refit (b*, μ*, β*) of a sample drawn from the fit, taken as a draw of the pivots
    /// (module docs): b = b̂²/b*, μ = μ̂ − b̂(μ* − μ̂)/b*, β = β̂ − b̂(β* − β̂)/b*.
    fn pivotal_form(&self, refit: &Params) -> Params {
        let (b_hat, mu_hat) = (self.model.reg.b, self.model.reg.mu);
        let b_star = 1.0 / refit.shape;
        let mut p = Params::base(1.0 / (b_hat * b_hat / b_star), mu_hat - b_hat * (refit.mu - mu_hat) / b_star);
        for (j, b) in p.beta.iter_mut().enumerate().take(self.model.reg.beta.len()) {
            *b = self.model.reg.beta[j] - b_hat * (refit.beta[j] - self.model.reg.beta[j]) / b_star;
        }
        p
    }

    /// Plain parametric bootstrap (models with a profiled damage ratio, a modulus per level or
    /// partially pooled levels; censored samples, each redraw censored as its row was).
    fn bootstrap_draws(&self, k: usize, seed: u64) -> Result<Vec<Params>> {
        let out: Vec<Option<Params>> = (0..k)
            .into_par_iter()
            .map(|r| (0..20).find_map(|attempt| self.model.bootstrap_refit(self.data.view(), &self.terms, seed ^ ((attempt as u64) << 40), r).map(|(_, f)| Params::of(&f))))
            .collect();
        collect(out, "parametric bootstrap")
    }

    /// Posterior draws by the ensemble sampler: θ = (μ, ln b, β…, γ…, [ln x]), flat in each
    /// but a partially pooled factor's β, whose prior is N(0, τ²) at the fitted τ (empirical
    /// Bayes: the spread is not redrawn).
    fn posterior_draws(&self, k: usize, seed: u64) -> Result<Vec<Params>> {
        use crate::calibrate::mcmc::{EnsembleOptions, ensemble};
        let m = &self.model;
        let nl = m.columns.len();
        let ns = m.scale_columns.len();
        let damage = m.damage_ratio.is_some();
        let dim = 2 + nl + ns + usize::from(damage);
        let obs = self.data.view();
        let complete = obs.complete();
        let y: Vec<f64> = obs.x.iter().map(|x| x.ln()).collect();
        let damage_terms = self.terms.iter().find_map(|(_, t)| match t {
            super::effects::Term::Damage { impacts, gamma } => Some((impacts.clone(), *gamma)),
            _ => None,
        });
        let (lx_lo, lx_hi) = ((1e-4f64).ln(), (0.99f64).ln());
        let log_post = |t: &[f64]| -> f64 {
            let (mu, s) = (t[0], t[1]);
            let offset = if let Some((impacts, gamma)) = &damage_terms {
                let lx = t[2 + nl + ns];
                if !(lx_lo..=lx_hi).contains(&lx) {
                    return f64::NEG_INFINITY;
                }
                let n_max = impacts.iter().copied().max().unwrap_or(0);
                let Some(path) = crate::lifetime::damage::tk_ratio_path(lx.exp(), *gamma, n_max) else { return f64::NEG_INFINITY };
                Some(impacts.iter().map(|&n| (lx - path[n as usize]) / 5.0).collect::<Vec<f64>>())
            } else {
                None
            };
            let mut l = 0.0;
            for j in 0..nl {
                l -= 0.5 * m.penalty.get(j).copied().unwrap_or(0.0) * t[2 + j] * t[2 + j];
            }
            for (i, yi) in y.iter().enumerate() {
                let mut ls = mu;
                for j in 0..nl {
                    ls += t[2 + j] * m.columns[j][i];
                }
                if let Some(o) = &offset {
                    ls += o[i];
                }
                let mut lb = s;
                for j in 0..ns {
                    lb += t[2 + nl + j] * m.scale_columns[j][i];
                }
                if complete {
                    let w = (yi - ls) / lb.exp();
                    l += -lb + w - w.exp();
                } else {
                    // What the row says (a censored row's ln S, …), plus the exact row's y.
                    l += super::regress::ln_prob(obs, i, ls, lb.exp()) + if obs.kind(i) == crate::obs::Censor::Exact { *yi } else { 0.0 };
                }
            }
            if l.is_finite() { l } else { f64::NEG_INFINITY }
        };
        // Start the walkers in a small ball around the MLE (scaled by asymptotic sds).
        let n = m.n as f64;
        let mut centre = vec![m.reg.mu, m.reg.b.ln()];
        let mut sd = vec![1.05 * m.reg.b / n.sqrt(), 0.78 / n.sqrt()];
        let se = |v: f64| if v.is_finite() && v > 0.0 { v } else { 0.1 };
        for j in 0..nl {
            centre.push(m.reg.beta[j]);
            sd.push(se(m.reg.beta_se[j]));
        }
        for j in 0..ns {
            centre.push(m.reg.gamma[j]);
            sd.push(se(m.reg.gamma_se[j]));
        }
        if let Some(x) = m.damage_ratio {
            centre.push(x.ln().clamp(lx_lo + 0.01, lx_hi - 0.01));
            sd.push(0.05);
        }
        let walkers = (4 * dim).max(16);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xBA7E5);
        let normal = rand_distr::StandardNormal;
        let init: Vec<Vec<f64>> = (0..walkers)
            .map(|_| {
                centre.iter().zip(&sd).map(|(c, s)| {
                    let z: f64 = normal.sample(&mut rng);
                    c + 0.1 * s * z
                }).collect()
            })
            .collect();
        let thin = 10;
        let steps = (k * thin).div_ceil(walkers);
        let opts = EnsembleOptions { walkers, steps, burn_in: 1000, stretch: 2.0, seed };
        let chains = ensemble(log_post, init, &opts)?;
        for p in 0..dim {
            let d = chains.diagnostics(p);
            if !(d.r_hat < 1.1) {
                return Err(Error::numerical("strength posterior", format!("the ensemble sampler did not converge (parameter {p}: R̂ = {:.3})", d.r_hat)));
            }
        }
        let mut out = Vec::with_capacity(k);
        'steps: for step in chains.draws.iter().skip(thin - 1).step_by(thin) {
            for t in step {
                let mut p = Params::base((-t[1]).exp(), t[0]);
                p.beta[..nl].copy_from_slice(&t[2..2 + nl]);
                p.gamma[..ns].copy_from_slice(&t[2 + nl..2 + nl + ns]);
                out.push(p);
                if out.len() == k {
                    break 'steps;
                }
            }
        }
        if out.len() < k {
            return Err(Error::numerical("strength posterior", format!("{} of {k} draws", out.len())));
        }
        Ok(out)
    }
}

fn collect(out: Vec<Option<Params>>, what: &str) -> Result<Vec<Params>> {
    let k = out.len();
    let got: Vec<Params> = out.into_iter().flatten().collect();
    if got.len() < k {
        return Err(Error::numerical("strength draws", format!("{what}: {} of {k} refits failed", k - got.len())));
    }
    Ok(got)
}

/// One parameter of a fitted strength model: its estimate and the 5/95 % quantiles of its draws.
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterSummary {
    /// `weibull_modulus`, `scale_pa` (e^μ), or an effect's reported symbol (`size_alpha`, `roundness_q`, …).
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Maximum-likelihood estimate.
    pub estimate: f64,
    /// 5 % quantile of the draws.
    pub q05: f64,
    /// 95 % quantile of the draws.
    pub q95: f64,
}

/// The modulus, the scale e^μ, every single-column effect's reported parameter and, for a
/// categorical factor, each level's scale ratio to the reference (`levels(g)_<level>_scale_ratio`)
/// or its modulus (`moduli(g)_<level>_modulus`), with the 90 % range of `draws`.
pub fn summarise(fit: &StrengthFit, draws: &[Params]) -> Vec<ParameterSummary> {
    let est = fit.estimate();
    let row = |name: String, unit: &str, f: &dyn Fn(&Params) -> f64| {
        let q = crate::stats::interpolated_quantiles(draws.iter().map(f).collect(), &[0.05, 0.95]);
        ParameterSummary { name, unit: unit.into(), estimate: f(&est), q05: q[0], q95: q[1] }
    };
    let mut out = vec![row("weibull_modulus".into(), "-", &|p| p.shape), row("scale_pa".into(), "Pa", &|p| p.mu.exp())];
    for (j, c) in fit.beta_columns().into_iter().enumerate() {
        match &c.level {
            None => {
                let (sym, _, _) = c.effect.parameter(0.0, 1.0);
                out.push(row(format!("{}_{sym}", c.effect.name()), "-", &|p| c.effect.natural(p.beta[j])));
            }
            Some(l) => out.push(row(format!("{}_{l}_scale_ratio", c.effect.name()), "-", &|p| p.beta[j].exp())),
        }
    }
    for (j, c) in fit.scale_columns().into_iter().enumerate() {
        out.push(row(format!("{}_{}_modulus", c.effect.name(), c.level.unwrap_or_default()), "-", &|p| p.shape * (-p.gamma[j]).exp()));
    }
    out
}

//! Partial pooling of a categorical factor's level scales: the spread τ of the levels'
//! ln-scale offsets (δ ~ N(0, τ²)), chosen by the Laplace approximation of the marginal
//! likelihood,
//!
//! ```text
//! ln L(τ) ≈ ℓ(θ̂_τ) − Σ_l δ̂_l²/(2τ²) − L ln τ − ½ ln det(−∂²ℓ/∂δ² + I/τ²),
//! ```
//!
//! maximised over ln τ ∈ [ln 10⁻³, ln 3] (a grid, then golden section), with θ̂_τ the penalised
//! fit at that τ ([`super::regress`]); the model's ℓ is the unpenalised log-likelihood there.
//! Each trial τ is a penalised fit of the whole model ([`super::mle`]); unit test below:
//! τ → ∞ and τ → 0 give the fixed-effects and the base fits, and the Laplace marginal equals a
//! quadrature over the offsets.

use super::effects::{Effect, Term};
use super::mle::{ModelFit, fit_at};
use super::regress::RegFit;
use crate::error::{Error, Result};
use crate::obs::Obs;
use crate::stats::golden_max;

/// The model with `pooled` partially pooled factors among `terms`, each τ at its marginal-
/// likelihood maximum; `ratio` the damage-ratio hint, `hint` a fit to similar data (its τ start
/// the search and its optimum the Newton iteration).
pub(super) fn fit_pooled(x: Obs, terms: &[(Effect, Term)], ratio: Option<f64>, hint: Option<&ModelFit>, pooled: usize) -> Result<ModelFit> {
    // τ of each pooled factor by the Laplace marginal likelihood; several pooled factors are
    // tuned one at a time, twice round.
    // Each trial τ's Newton iteration starts from the previous trial's optimum (the first from
    // the hint's, when it has the same columns).
    let last: std::cell::RefCell<Option<RegFit>> = std::cell::RefCell::new(hint.map(|h| h.reg.clone()));
    let marginal = |ln_tau: &[f64]| -> f64 {
        let m = fit_at(x, terms, ratio, ln_tau, last.borrow().as_ref());
        m.map_or(f64::NEG_INFINITY, |m| {
            let v = laplace_marginal(&m);
            *last.borrow_mut() = Some(m.reg);
            v
        })
    };
    let (lo, hi) = ((1e-3f64).ln(), 3f64.ln());
    let hinted = hint.map(|h| h.pooled_ln_tau()).filter(|v| v.len() == pooled);
    let mut ln_tau = hinted.clone().unwrap_or_else(|| vec![(0.1f64).ln(); pooled]);
    for _ in 0..if pooled == 1 { 1 } else { 2 } {
        for t in 0..pooled {
            let base = ln_tau.clone();
            let at = |v: f64| -> f64 {
                let mut lt = base.clone();
                lt[t] = v;
                marginal(&lt)
            };
            // Near a hint: golden section on ln τ ± 0.7, kept unless it ends on an inner edge.
            if let Some(h) = &hinted {
                let (a, b) = ((h[t] - 0.7).max(lo), (h[t] + 0.7).min(hi));
                let v = golden_max(&at, a, b, 0.05);
                if (v - a > 0.05 || a == lo) && (b - v > 0.05 || b == hi) && at(v).is_finite() {
                    ln_tau[t] = v;
                    continue;
                }
            }
            let grid: Vec<f64> = (0..=8).map(|j| lo + (hi - lo) * j as f64 / 8.0).collect();
            let vals: Vec<f64> = grid.iter().map(|&g| at(g)).collect();
            let best = (0..grid.len()).max_by(|&a, &b| vals[a].total_cmp(&vals[b])).unwrap_or(0);
            if !vals[best].is_finite() {
                return Err(Error::numerical("partially pooled levels", "no spread of the level scales gives a fit"));
            }
            let v = golden_max(&at, grid[best.saturating_sub(1)], grid[(best + 1).min(grid.len() - 1)], 0.02);
            ln_tau[t] = if at(v) >= vals[best] { v } else { grid[best] };
        }
    }
    let start = last.borrow().clone();
    fit_at(x, terms, ratio, &ln_tau, start.as_ref())
}

/// The Laplace approximation of the marginal log-likelihood of a partially pooled fit (module
/// docs): ℓ − Σ λ δ²/2 + Σ ½ ln λ − ½ ln det, λ = 1/τ² per pooled column.
fn laplace_marginal(m: &ModelFit) -> f64 {
    marginal_of(&m.reg, &m.penalty)
}

/// [`laplace_marginal`] of a regression fit under the penalties `penalty`.
fn marginal_of(reg: &RegFit, penalty: &[f64]) -> f64 {
    let mut v = reg.loglik - 0.5 * reg.ln_det_penalised;
    for (j, &l) in penalty.iter().enumerate() {
        if l > 0.0 {
            v += 0.5 * l.ln() - 0.5 * l * reg.beta[j] * reg.beta[j];
        }
    }
    v
}

impl ModelFit {
    /// The profile interval at `level` of a partially pooled factor's spread τ from the Laplace
    /// marginal likelihood: {τ : 2[ln L(τ̂) − ln L(τ)] ≤ χ²₁(level)}, the other parameters (and
    /// any other pooled factor's τ) held at the fit's, τ searched in [10⁻³, 3] as in the fit; an
    /// end reaching that range is its bound. None if `c` is not partially pooled in this fit or
    /// the model has a profiled damage ratio.
    pub fn tau_band(&self, x: Obs, c: &Effect, level: f64) -> Option<(f64, f64)> {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        let r = self.beta_range(c).filter(|r| !r.is_empty())?;
        if self.damage_ratio.is_some() || self.law.is_some() || !self.penalty.get(r.start).is_some_and(|l| *l > 0.0) {
            return None;
        }
        let at = |ln_tau: f64| -> f64 {
            let mut penalty = self.penalty.clone();
            for j in r.clone() {
                penalty[j] = (-2.0 * ln_tau).exp();
            }
            let design = super::regress::Design { columns: &self.columns, offset: self.offset.as_deref(), scale_columns: &self.scale_columns, penalty: &penalty };
            super::regress::fit_from(x, &design, Some(&self.reg)).map_or(f64::NEG_INFINITY, |reg| marginal_of(&reg, &penalty))
        };
        let hat = -0.5 * self.penalty[r.start].ln();
        let target = at(hat) - 0.5 * ChiSquared::new(1.0).ok()?.inverse_cdf(level);
        let (lo, hi) = ((1e-3f64).ln(), 3f64.ln());
        let end = |dir: f64, bound: f64| crate::stats::region_end(|v| Some(at(v) >= target), hat, dir, 0.05, bound, 1e-3);
        Some((end(-1.0, lo)?.exp(), end(1.0, hi)?.exp()))
    }
}


#[cfg(test)]
mod tests {
    use super::*;
    use crate::strength::fit::{Sample, fit_model};
    use crate::strength::regress::{Design, fit};
    use crate::weibull::Weibull;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Three batches of 15, 10 and 2 specimens with ln-scale offsets 0, −0.1 and +0.15, m = 8.
    fn three_batches() -> (Vec<f64>, Vec<String>) {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let mut x = Vec::new();
        let mut g = Vec::new();
        for (name, k, d) in [("A", 15, 0.0), ("B", 10, -0.1), ("C", 2, 0.15)] {
            for _ in 0..k {
                x.push(Weibull::new(8.0, 3e8 * f64::exp(d)).unwrap().sample(&mut rng));
                g.push(name.to_string());
            }
        }
        (x, g)
    }

    #[test]
    fn pooled_levels_span_complete_to_no_pooling_and_the_laplace_marginal_matches_quadrature() {
        use crate::strength::factors::{Factor, Form};
        let (x, g) = three_batches();
        let e = Effect::Factor(Factor { column: "g".into(), form: Form::Levels });
        let s = Sample { strength: crate::obs::Observations::exact(x.clone()), levels: vec![("g".into(), g.clone())], ..Sample::default() };
        let t = s.term(&e, 5.0).unwrap();
        assert!(matches!(t, Term::Pooled { .. }), "a level of 2 specimens is pooled");
        let terms = vec![(e.clone(), t)];
        // τ → ∞: the fixed-effects fit (one scale per level); τ → 0: the base model.
        let wide = fit_at(Obs::exact(&x), &terms, None, &[(50.0f64).ln()], None).unwrap();
        let fixed: Vec<Vec<f64>> = ["B", "C"].iter().map(|l| g.iter().map(|v| f64::from(u8::from(v == l))).collect()).collect();
        let fixed = fit(Obs::exact(&x), &Design { columns: &fixed, ..Design::default() }).unwrap();
        assert!((wide.reg.loglik - fixed.loglik).abs() < 1e-3, "{} vs {}", wide.reg.loglik, fixed.loglik);
        assert!((wide.reg.edf_penalised - 2.0).abs() < 1e-3, "edf {}", wide.reg.edf_penalised);
        let narrow = fit_at(Obs::exact(&x), &terms, None, &[(1e-4f64).ln()], None).unwrap();
        let base = fit(Obs::exact(&x), &Design::default()).unwrap();
        assert!((narrow.reg.loglik - base.loglik).abs() < 1e-3 && narrow.reg.edf_penalised < 0.01);
        // The fitted τ's model lies between the two, counted at its effective df.
        let m = fit_model(Obs::exact(&x), &terms).unwrap();
        assert!(m.reg.loglik >= base.loglik - 1e-9 && m.reg.loglik <= fixed.loglik + 1e-9);
        assert_eq!(m.parameters(), 4);
        assert!(m.effective_parameters() > 2.0 && m.effective_parameters() < 4.0, "{}", m.effective_parameters());
        // The Laplace marginal at τ = 0.1 against a 3-D quadrature over the level offsets with μ
        // and b at the penalised mode: ln ∫ exp ℓ(δ) Π N(δ_l; 0, τ²) dδ.
        let tau = 0.1f64;
        let at = fit_at(Obs::exact(&x), &terms, None, &[tau.ln()], None).unwrap();
        let (mu, b) = (at.reg.mu, at.reg.b);
        let level: Vec<usize> = g.iter().map(|v| ["A", "B", "C"].iter().position(|l| l == v).unwrap()).collect();
        let loglik = |d: [f64; 3]| -> f64 { x.iter().zip(&level).map(|(xi, &l)| crate::strength::regress::ln_density_of_log(xi.ln(), mu + d[l], b) - xi.ln()).sum() };
        let h = 0.01;
        let grid: Vec<f64> = (-60..=60).map(|k| k as f64 * h).collect();
        let ln_prior = |d: f64| -0.5 * (d / tau).powi(2) - (tau * (2.0 * std::f64::consts::PI).sqrt()).ln();
        let mut terms_ln = Vec::with_capacity(grid.len().pow(3));
        let centre = [at.reg.beta[0], at.reg.beta[1], at.reg.beta[2]];
        for &a in &grid {
            for &bb in &grid {
                for &c in &grid {
                    let d = [centre[0] + a, centre[1] + bb, centre[2] + c];
                    terms_ln.push(loglik(d) + ln_prior(d[0]) + ln_prior(d[1]) + ln_prior(d[2]));
                }
            }
        }
        let top = terms_ln.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let quad = top + (terms_ln.iter().map(|v| (v - top).exp()).sum::<f64>() * h.powi(3)).ln();
        // (The prior's (2π)^(−L/2) cancels the Gaussian integral's (2π)^(L/2).)
        let laplace = laplace_marginal(&at);
        assert!((laplace - quad).abs() < 0.05, "Laplace {laplace} vs quadrature {quad}");
    }
}

//! Weibull regression: the strength model with covariates, fitted by maximum likelihood.
//!
//! Every candidate effect of the discrepancy workflow changes the Weibull scale of a particle
//! and leaves the modulus alone:
//!
//! ```text
//! x_i ~ Weibull(m, σ_i),   ln σ_i = μ + Σ_k β_k z_ik + o_i
//! ```
//!
//! with z the effect's covariate column(s) and o a known offset (the Tavares–King damage term at
//! a trial damage ratio). In logs this is a log-location-scale model, y = ln x = ln σ + b·w with
//! w standard minimum-Gumbel and b = 1/m, whose log-likelihood in the units of x is
//!
//! ```text
//! ℓ = Σ_i [ −ln b + w_i − e^(w_i) − y_i ],   w_i = (y_i − ln σ_i)/b.
//! ```
//!
//! It is maximised by Newton's method in (μ, β, s = ln b) with the analytic gradient and Hessian
//! (step halving until ℓ rises; a Levenberg shift when −H is not positive definite), starting
//! from least squares on y. Covariates are centred and scaled inside the fit for conditioning.
//! With no covariates the fit is the ordinary Weibull MLE (`tests` below: equal to
//! [`crate::weibull::fit_mle`] to 1e-9).

use nalgebra::{DMatrix, DVector};
use rand::Rng;

use crate::error::{Error, Result};

/// Euler–Mascheroni constant: E[w] = −γ for the standard minimum-Gumbel w.
const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;

/// Covariate columns and an optional offset for n particles.
#[derive(Debug, Clone, Copy, Default)]
pub struct Design<'a> {
    /// Columns z_k (each of length n).
    pub columns: &'a [Vec<f64>],
    /// Known offset o_i in ln σ_i (none: 0).
    pub offset: Option<&'a [f64]>,
}

/// Log density of y = ln x for Weibull strength x with scale e^ln_scale and modulus 1/b: y is
/// minimum-Gumbel with location ln_scale and scale b, ln f = −ln b + w − e^w with
/// w = (y − ln_scale)/b (the crate's one copy; the density of x subtracts y).
pub fn ln_density_of_log(y: f64, ln_scale: f64, b: f64) -> f64 {
    let w = (y - ln_scale) / b;
    -b.ln() + w - w.exp()
}

/// New crushed particles drawn from a population of rows: each particle's row uniformly with
/// replacement, then its strength Weibull with modulus `m` and the row's scale e^(ln σ_row),
/// by inversion, ln s = ln σ_row + ln(−ln U)/m. Returns (row, ln s) per particle, the row and U
/// drawn in that order from `rng`. The crate's one generator of synthetic crush data (the
/// discrepancy workflow's detection power and experiment design's crush tests).
pub fn draw_particles<R: Rng + ?Sized>(ln_scale: &[f64], m: f64, n: usize, rng: &mut R) -> Vec<(usize, f64)> {
    (0..n)
        .map(|_| {
            let i = rng.random_range(0..ln_scale.len());
            let u: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
            (i, ln_scale[i] + (-u.ln()).ln() / m)
        })
        .collect()
}

/// A fitted Weibull regression.
#[derive(Debug, Clone, PartialEq)]
pub struct RegFit {
    /// Intercept μ (ln Pa for strengths in Pa).
    pub mu: f64,
    /// Coefficients β_k of the columns, in the columns' own units.
    pub beta: Vec<f64>,
    /// Standard errors of β from the observed information (NaN if singular).
    pub beta_se: Vec<f64>,
    /// b = 1/m.
    pub b: f64,
    /// Maximised log-likelihood in the units of x.
    pub loglik: f64,
}

impl RegFit {
    /// Weibull modulus m = 1/b.
    pub fn shape(&self) -> f64 {
        1.0 / self.b
    }

    /// ln σ_i of particle i under `design`.
    pub fn ln_scale(&self, design: &Design, i: usize) -> f64 {
        self.mu
            + design.columns.iter().zip(&self.beta).map(|(z, b)| b * z[i]).sum::<f64>()
            + design.offset.map_or(0.0, |o| o[i])
    }

    /// Log density of the value x for particle i.
    pub fn ln_density(&self, design: &Design, i: usize, x: f64) -> f64 {
        self.ln_density_at(self.ln_scale(design, i), x)
    }

    /// Log density of x under Weibull(1/b, e^ln_scale).
    pub fn ln_density_at(&self, ln_scale: f64, x: f64) -> f64 {
        let y = x.ln();
        ln_density_of_log(y, ln_scale, self.b) - y
    }

    /// The value of Weibull(1/b, e^ln_scale) at probability u (inversion).
    pub fn quantile_at(&self, ln_scale: f64, u: f64) -> f64 {
        (ln_scale + self.b * (-(1.0 - u).ln()).ln()).exp()
    }

    /// Fitted CDF at x for particle i.
    pub fn cdf(&self, design: &Design, i: usize, x: f64) -> f64 {
        let w = (x.ln() - self.ln_scale(design, i)) / self.b;
        -(-w.exp()).exp_m1()
    }

    /// One draw for every particle of `design` (n of them), by inversion.
    pub fn sample<R: Rng + ?Sized>(&self, design: &Design, n: usize, rng: &mut R) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let u: f64 = rng.random();
                self.quantile_at(self.ln_scale(design, i), u)
            })
            .collect()
    }
}

fn bad(rule: String) -> Error {
    Error::numerical("Weibull regression", rule)
}

/// Maximum-likelihood fit of `x` (all > 0 and finite) with `design`.
pub fn fit(x: &[f64], design: &Design) -> Result<RegFit> {
    fit_with(x, design, None)
}

/// The fit with a column tied to the modulus: ln σ_i = μ + Σ β z_i + o_i − k t_i/m, the
/// weakest-link size law with its exponent k/m (`tie` = (t, k)). In the standardised residual
/// w_i = (y_i − η_i)/b + k t_i the log-likelihood keeps its form ℓ = Σ[−ln b + w_i − e^(w_i) − y_i];
/// the derivatives in s = ln b use u_i = (y_i − η_i)/b (∂w/∂s = −u). The returned `RegFit`'s
/// μ, β and b are the tied model's; its `ln_scale` omits the tied term.
pub fn fit_tied(x: &[f64], design: &Design, tie: (&[f64], f64)) -> Result<RegFit> {
    if tie.0.len() != x.len() {
        return Err(bad("the tied column does not match the data length".into()));
    }
    fit_with(x, design, Some(tie))
}

fn fit_with(x: &[f64], design: &Design, tie: Option<(&[f64], f64)>) -> Result<RegFit> {
    let n = x.len();
    let k = design.columns.len();
    if n < k + 3 {
        return Err(bad(format!("{n} values are too few for {} parameters", k + 2)));
    }
    if let Some(v) = x.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        return Err(bad(format!("values must be finite and > 0 (got {v})")));
    }
    if design.columns.iter().any(|c| c.len() != n) || design.offset.is_some_and(|o| o.len() != n) {
        return Err(bad("a covariate column or the offset does not match the data length".into()));
    }
    // Centred, scaled columns.
    let mut centre = vec![0.0; k];
    let mut spread = vec![1.0; k];
    let mut z = DMatrix::<f64>::zeros(n, k + 1);
    for i in 0..n {
        z[(i, 0)] = 1.0;
    }
    for (j, col) in design.columns.iter().enumerate() {
        let m = col.iter().sum::<f64>() / n as f64;
        let sd = (col.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n as f64).sqrt();
        if !(sd > 0.0 && sd.is_finite()) {
            return Err(bad(format!("covariate column {j} is constant or not finite")));
        }
        centre[j] = m;
        spread[j] = sd;
        for i in 0..n {
            z[(i, j + 1)] = (col[i] - m) / sd;
        }
    }
    let y: Vec<f64> = (0..n).map(|i| x[i].ln() - design.offset.map_or(0.0, |o| o[i])).collect();
    let sum_y: f64 = x.iter().map(|v| v.ln()).sum();
    // Start: least squares on y, b from the residual sd (Gumbel sd = π b/√6).
    let zt = z.transpose();
    let yv = DVector::from_vec(y.clone());
    let theta0 = (&zt * &z)
        .lu()
        .solve(&(&zt * &yv))
        .ok_or_else(|| bad("the covariate columns are collinear".into()))?;
    let res = &yv - &z * &theta0;
    let b0 = ((res.norm_squared() / n as f64).sqrt() * 6f64.sqrt() / std::f64::consts::PI).max(1e-6);
    let mut p = DVector::<f64>::zeros(k + 2);
    for j in 0..=k {
        p[j] = theta0[j];
    }
    p[0] += EULER_GAMMA * b0;
    p[k + 1] = b0.ln();

    // ℓ without the constant −Σy, and its derivatives.
    let eval = |p: &DVector<f64>| -> (f64, DVector<f64>, DMatrix<f64>) {
        let s = p[k + 1];
        let b = s.exp();
        let eta = &z * p.rows(0, k + 1);
        let mut l = 0.0;
        let mut g = DVector::<f64>::zeros(k + 2);
        let mut h = DMatrix::<f64>::zeros(k + 2, k + 2);
        for i in 0..n {
            // u: the residual in units of b; w = u (+ k t_i when a column is tied to 1/b).
            let u = (y[i] - eta[i]) / b;
            let w = u + tie.map_or(0.0, |(t, kk)| kk * t[i]);
            let ew = w.exp();
            l += -s + w - ew;
            let zi = z.row(i);
            for a in 0..=k {
                g[a] += (ew - 1.0) * zi[a] / b;
                for c in 0..=k {
                    h[(a, c)] -= ew * zi[a] * zi[c] / (b * b);
                }
                h[(a, k + 1)] -= zi[a] * (u * ew + ew - 1.0) / b;
            }
            g[k + 1] += -1.0 - u + u * ew;
            h[(k + 1, k + 1)] += u - u * ew - u * u * ew;
        }
        for a in 0..=k {
            h[(k + 1, a)] = h[(a, k + 1)];
        }
        (l, g, h)
    };

    let (mut l, mut g, mut h) = eval(&p);
    let mut converged = false;
    for _ in 0..200 {
        let neg_h = -&h;
        let step = match neg_h.clone().cholesky() {
            Some(c) => c.solve(&g),
            None => {
                let shift = neg_h.diagonal().iter().fold(0.0f64, |a, v| a.max(v.abs())) * 1e-3 + 1e-8;
                let mut damped = neg_h.clone();
                let mut solved = None;
                for t in 0..30 {
                    for d in 0..k + 2 {
                        damped[(d, d)] = neg_h[(d, d)] + shift * 10f64.powi(t);
                    }
                    if let Some(c) = damped.clone().cholesky() {
                        solved = Some(c.solve(&g));
                        break;
                    }
                }
                solved.ok_or_else(|| bad("the information matrix could not be regularised".into()))?
            }
        };
        let mut t = 1.0;
        let mut improved = false;
        for _ in 0..40 {
            let trial = &p + &step * t;
            let (lt, gt, ht) = eval(&trial);
            if lt.is_finite() && lt >= l - 1e-12 * l.abs().max(1.0) {
                let gain = lt - l;
                p = trial;
                l = lt;
                g = gt;
                h = ht;
                improved = true;
                if gain.abs() < 1e-11 * l.abs().max(1.0) && (step.norm() * t) < 1e-9 {
                    converged = true;
                }
                break;
            }
            t *= 0.5;
        }
        if !improved || g.norm() < 1e-9 * (n as f64) {
            converged = converged || g.norm() < 1e-6 * (n as f64);
            break;
        }
        if converged {
            break;
        }
    }
    if !converged || !l.is_finite() {
        return Err(bad(format!("Newton iteration did not converge (gradient norm {:.3e})", g.norm())));
    }
    let cov = (-&h).try_inverse();
    let beta: Vec<f64> = (0..k).map(|j| p[j + 1] / spread[j]).collect();
    let beta_se: Vec<f64> = (0..k)
        .map(|j| cov.as_ref().map_or(f64::NAN, |c| c[(j + 1, j + 1)].max(0.0).sqrt() / spread[j]))
        .collect();
    let mu = p[0] - (0..k).map(|j| beta[j] * centre[j]).sum::<f64>();
    Ok(RegFit { mu, beta, beta_se, b: p[k + 1].exp(), loglik: l - sum_y })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::weibull::{Weibull, fit_mle};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn without_covariates_it_is_the_weibull_mle() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let w = Weibull::new(9.0, 2.0e9).unwrap();
        let x: Vec<f64> = (0..60).map(|_| w.sample(&mut rng)).collect();
        let r = fit(&x, &Design::default()).unwrap();
        let m = fit_mle(&x).unwrap().mle;
        assert!((r.shape() / m.shape - 1.0).abs() < 1e-9, "{} vs {}", r.shape(), m.shape);
        assert!((r.mu.exp() / m.scale - 1.0).abs() < 1e-9);
        assert!((r.loglik - m.log_likelihood(&x)).abs() < 1e-6 * r.loglik.abs());
    }

    #[test]
    fn recovers_a_covariate_coefficient() {
        // ln σ = ln 2e9 + 0.5 ln z, m = 12, n = 4000: β within 3 standard errors.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let n = 4000;
        let z: Vec<f64> = (0..n).map(|_| rng.random_range(-0.4..0.0)).collect();
        let x: Vec<f64> = z
            .iter()
            .map(|&zi| Weibull::new(12.0, 2.0e9 * (0.5 * zi).exp()).unwrap().sample(&mut rng))
            .collect();
        let cols = vec![z];
        let r = fit(&x, &Design { columns: &cols, offset: None }).unwrap();
        assert!((r.beta[0] - 0.5).abs() < 3.0 * r.beta_se[0], "β = {} ± {}", r.beta[0], r.beta_se[0]);
        assert!((r.shape() - 12.0).abs() < 0.5, "m = {}", r.shape());
        assert!(r.beta_se[0] > 0.0 && r.beta_se[0] < 0.05);
    }
}

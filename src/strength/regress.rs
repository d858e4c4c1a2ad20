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
//! **Censored and grouped rows** ([`crate::obs`]) add the log-probability of what they say
//! instead of the log density; each row's ℓ and its derivatives in (η_i, s) are
//! [`super::loglik::row_terms`].
//!
//! It is maximised by Newton's method in (μ, β, s = ln b) with the analytic gradient and Hessian
//! (step halving until ℓ rises; a Levenberg shift when −H is not positive definite), starting
//! from least squares on y. Covariates are centred and scaled inside the fit for conditioning.
//! With no covariates the fit is the ordinary Weibull MLE (`tests` below: equal to
//! [`crate::weibull::fit_mle`] to 1e-9).
//!
//! **A modulus per group.** The design may also carry *scale columns* v (0/1 indicators of the
//! levels of a categorical factor): then b varies by specimen,
//!
//! ```text
//! ln b_i = s + Σ_j γ_j v_ij,   m_i = 1/b_i,
//! ```
//!
//! a Weibull modulus per level (Lawless 2003, §6.3.3, scale depending on covariates). With
//! w_i = (y_i − ln σ_i)/b_i the log-likelihood keeps its form, ℓ = Σ[−ln b_i + w_i − e^(w_i) − y_i];
//! ∂w_i/∂s = −w_i and ∂w_i/∂γ_j = −w_i v_ij, so the Newton iteration runs in (μ, β, s, γ) with the
//! same derivatives multiplied by the scale row (1, v_i). Test below: one modulus per group
//! equals separate two-parameter fits of the groups (scale columns and level columns together).
//!
//! **Partial pooling.** A column may carry a ridge precision λ_k = 1/τ² (`penalty`): its
//! coefficient then has the prior β_k ~ N(0, τ²) and the fit maximises the penalised
//! log-likelihood ℓ − Σ λ_k β_k²/2 (the mode of the random-effects posterior given τ). Penalised
//! columns are neither centred nor scaled, so a level's δ shrinks towards the intercept — the
//! scale of the population of levels — and a level absent from the data gets δ = 0. The fit
//! reports the unpenalised ℓ at that mode (for likelihood ratios) and
//! `ln_det_penalised` = ln det(−∂²(ℓ − penalty)/∂β_P²) over the penalised block, the term a
//! Laplace approximation of the marginal likelihood of τ needs
//! (see [`crate::strength::fit`]).

use nalgebra::{DMatrix, DVector};
use rand::Rng;

pub use super::loglik::{ln_density_of_log, ln_prob};
use super::loglik::row_terms;
use crate::error::{Error, Result};
use crate::obs::{Censor, Obs};

/// Euler–Mascheroni constant: E[w] = −γ for the standard minimum-Gumbel w.
const EULER_GAMMA: f64 = 0.577_215_664_901_532_9;

/// Covariate columns and an optional offset for n particles.
#[derive(Debug, Clone, Copy, Default)]
pub struct Design<'a> {
    /// Columns z_k (each of length n).
    pub columns: &'a [Vec<f64>],
    /// Known offset o_i in ln σ_i (none: 0).
    pub offset: Option<&'a [f64]>,
    /// Scale columns v_j (each of length n): ln b_i = s + Σ γ_j v_ij (none: one modulus).
    pub scale_columns: &'a [Vec<f64>],
    /// Ridge precision of each column (empty or one per column; 0: unpenalised).
    pub penalty: &'a [f64],
}

/// New crushed particles drawn from a population of rows: each particle's row uniformly with
/// replacement, then its strength Weibull with modulus `m` and the row's scale e^(ln σ_row),
/// by inversion, ln s = ln σ_row + ln(−ln U)/m. Returns (row, ln s) per particle, the row and U
/// drawn in that order from `rng`. The crate's one generator of synthetic crush data (the
/// discrepancy workflow's detection power and experiment design's crush tests).
pub fn draw_particles<R: Rng + ?Sized>(ln_scale: &[f64], m: f64, n: usize, rng: &mut R) -> Vec<(usize, f64)> {
    draw_rows(ln_scale, |_| m, n, rng)
}

/// [`draw_particles`] with the modulus of each row, `m(i)` (a modulus per level); the same
/// draws as `draw_particles` when every row has the same modulus.
pub fn draw_rows<R: Rng + ?Sized>(ln_scale: &[f64], m: impl Fn(usize) -> f64, n: usize, rng: &mut R) -> Vec<(usize, f64)> {
    (0..n)
        .map(|_| {
            let i = rng.random_range(0..ln_scale.len());
            let u: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
            (i, ln_scale[i] + (-u.ln()).ln() / m(i))
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
    /// b = 1/m (of the reference group when the design has scale columns).
    pub b: f64,
    /// Coefficients γ_j of the scale columns: ln b_i = ln b + Σ γ_j v_ij.
    pub gamma: Vec<f64>,
    /// Their standard errors (NaN if singular).
    pub gamma_se: Vec<f64>,
    /// Maximised log-likelihood in the units of x (with a penalty: the unpenalised ℓ at the
    /// penalised optimum).
    pub loglik: f64,
    /// ln det of the negative penalised Hessian over the penalised columns (0 without).
    pub ln_det_penalised: f64,
    /// Effective degrees of freedom of the penalised columns, Σ_j (1 − λ_j C_jj) with C the
    /// inverse of the negative penalised Hessian (Hastie & Tibshirani 1990 §3.5): from L − 1
    /// (no pooling; the intercept takes one direction) down to 0 (complete pooling). 0 without.
    pub edf_penalised: f64,
    /// [Var μ̂, Var ln b̂, Cov(μ̂, ln b̂)] from the observed information (NaN if singular), μ at
    /// the columns' zero: Fisher-matrix bounds of σ_θ = e^μ and m = 1/b without effects,
    /// censored rows included.
    pub location_scale_cov: [f64; 3],
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

    /// b_i = 1/m_i of particle i under `design` (b without scale columns).
    pub fn b_at(&self, design: &Design, i: usize) -> f64 {
        self.b * design.scale_columns.iter().zip(&self.gamma).map(|(v, g)| g * v[i]).sum::<f64>().exp()
    }

    /// Log density of the value x for particle i.
    pub fn ln_density(&self, design: &Design, i: usize, x: f64) -> f64 {
        self.ln_density_with(self.ln_scale(design, i), self.b_at(design, i), x)
    }

    /// Log density of x under Weibull(1/b, e^ln_scale) with the reference b.
    pub fn ln_density_at(&self, ln_scale: f64, x: f64) -> f64 {
        self.ln_density_with(ln_scale, self.b, x)
    }

    /// Log density of x under Weibull(1/b, e^ln_scale).
    pub fn ln_density_with(&self, ln_scale: f64, b: f64, x: f64) -> f64 {
        let y = x.ln();
        ln_density_of_log(y, ln_scale, b) - y
    }

    /// The value of Weibull(1/b, e^ln_scale) at probability u (inversion), reference b.
    pub fn quantile_at(&self, ln_scale: f64, u: f64) -> f64 {
        (ln_scale + self.b * (-(1.0 - u).ln()).ln()).exp()
    }

    /// Fitted CDF at x for particle i.
    pub fn cdf(&self, design: &Design, i: usize, x: f64) -> f64 {
        let w = (x.ln() - self.ln_scale(design, i)) / self.b_at(design, i);
        -(-w.exp()).exp_m1()
    }

    /// One draw for every particle of `design` (n of them), by inversion.
    pub fn sample<R: Rng + ?Sized>(&self, design: &Design, n: usize, rng: &mut R) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let u: f64 = rng.random();
                (self.ln_scale(design, i) + self.b_at(design, i) * (-(1.0 - u).ln()).ln()).exp()
            })
            .collect()
    }
}

fn bad(rule: String) -> Error {
    Error::numerical("Weibull regression", rule)
}

/// Maximum-likelihood fit of `x` (all > 0 and finite) with `design`.
pub fn fit(x: Obs, design: &Design) -> Result<RegFit> {
    fit_with(x, design, None, None)
}

/// [`fit`] started from a fit of the same design to similar data or at a nearby penalty (the
/// partially pooled factor's τ search): the same optimum in fewer Newton steps. A start of
/// another shape, or one where ℓ is not finite, is ignored.
pub fn fit_from(x: Obs, design: &Design, start: Option<&RegFit>) -> Result<RegFit> {
    fit_with(x, design, None, start)
}

/// The profile-likelihood interval of the coefficient β_j of column `j` (Venzon & Moolgavkar
/// 1988; Lawless 2003 §6.3.2): the β with 2[ℓ̂ − ℓ_p(β)] ≤ χ²₁(`level`), ℓ_p(β) the likelihood
/// maximised over every other parameter with β_j held at β — column j moves into the offset.
/// Unlike the Wald band β̂ ± z·se it follows the likelihood's asymmetry (a power law's exponent
/// near a bound, few distinct covariate values). Each end is bracketed by steps of the standard
/// error from the Wald end and found by bisection to 10⁻⁶ se. None where the column is
/// penalised or a profile fit fails.
pub fn profile_interval(x: Obs, design: &Design, fitted: &RegFit, j: usize, level: f64) -> Option<(f64, f64)> {
    if j >= design.columns.len() || design.penalty.get(j).is_some_and(|l| *l > 0.0) {
        return None;
    }
    use statrs::distribution::{ContinuousCDF, Normal};
    // χ²₁(level) = z², z the two-sided normal quantile.
    let z = Normal::standard().inverse_cdf(0.5 + 0.5 * level);
    let crit = 0.5 * z * z;
    let se = fitted.beta_se[j];
    if !(se.is_finite() && se > 0.0) {
        return None;
    }
    let others: Vec<Vec<f64>> = design.columns.iter().enumerate().filter(|(k, _)| *k != j).map(|(_, c)| c.clone()).collect();
    let penalty: Vec<f64> = if design.penalty.is_empty() { Vec::new() } else { design.penalty.iter().enumerate().filter(|(k, _)| *k != j).map(|(_, l)| *l).collect() };
    let deficit = |b: f64| -> Option<f64> {
        let offset: Vec<f64> = (0..x.len()).map(|i| design.offset.map_or(0.0, |o| o[i]) + b * design.columns[j][i]).collect();
        let d = Design { columns: &others, offset: Some(&offset), scale_columns: design.scale_columns, penalty: &penalty };
        fit(x, &d).ok().map(|f| fitted.loglik - f.loglik - crit)
    };
    let end = |dir: f64| crate::stats::region_end(|b| deficit(b).map(|d| d < 0.0), fitted.beta[j], dir, z * se, dir * f64::INFINITY, 1e-6 * se);
    Some((end(-1.0)?, end(1.0)?))
}

/// The fit with a column tied to the modulus: ln σ_i = μ + Σ β z_i + o_i − k t_i/m, the
/// weakest-link size law with its exponent k/m (`tie` = (t, k)). In the standardised residual
/// w_i = (y_i − η_i)/b + k t_i the log-likelihood keeps its form ℓ = Σ[−ln b + w_i − e^(w_i) − y_i];
/// the derivatives in s = ln b use u_i = (y_i − η_i)/b (∂w/∂s = −u). The returned `RegFit`'s
/// μ, β and b are the tied model's; its `ln_scale` omits the tied term.
pub fn fit_tied(x: Obs, design: &Design, tie: (&[f64], f64)) -> Result<RegFit> {
    if tie.0.len() != x.len() {
        return Err(bad("the tied column does not match the data length".into()));
    }
    fit_with(x, design, Some(tie), None)
}

fn fit_with(x: Obs, design: &Design, tie: Option<(&[f64], f64)>, start: Option<&RegFit>) -> Result<RegFit> {
    let n = x.len();
    let k = design.columns.len();
    let r = design.scale_columns.len();
    if n < k + r + 3 {
        return Err(bad(format!("{n} values are too few for {} parameters", k + r + 2)));
    }
    if let Some(v) = x.x.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        return Err(bad(format!("values must be finite and > 0 (got {v})")));
    }
    if let Some(i) = (0..n).find(|&i| x.kind(i) == Censor::Interval && !(x.upper(i).is_finite() && x.upper(i) > x.x[i])) {
        return Err(bad(format!("an interval's upper end must be finite and above its lower end (row {}: {} to {})", i + 1, x.x[i], x.upper(i))));
    }
    if (0..n).all(|i| x.kind(i) == Censor::Right) {
        return Err(bad(format!("none of the {n} specimens broke (every row is right-censored): the strength law is not identified")));
    }
    if design.columns.iter().chain(design.scale_columns).any(|c| c.len() != n) || design.offset.is_some_and(|o| o.len() != n) || !(design.penalty.is_empty() || design.penalty.len() == k) {
        return Err(bad("a covariate column, a scale column or the offset does not match the data length".into()));
    }
    if let Some(j) = design.scale_columns.iter().position(|v| v.iter().all(|x| *x == v[0]) || v.iter().any(|x| !x.is_finite())) {
        return Err(bad(format!("scale column {j} is constant or not finite")));
    }
    // Centred, scaled columns.
    let mut centre = vec![0.0; k];
    let mut spread = vec![1.0; k];
    let mut z = DMatrix::<f64>::zeros(n, k + 1);
    for i in 0..n {
        z[(i, 0)] = 1.0;
    }
    let pen: Vec<f64> = if design.penalty.is_empty() { vec![0.0; k] } else { design.penalty.to_vec() };
    if pen.iter().any(|l| !(l.is_finite() && *l >= 0.0)) {
        return Err(bad("a ridge precision is negative or not finite".into()));
    }
    for (j, col) in design.columns.iter().enumerate() {
        if pen[j] > 0.0 {
            // Penalised: taken as is (δ shrinks towards the intercept; may be constant).
            for i in 0..n {
                z[(i, j + 1)] = col[i];
            }
            continue;
        }
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
    // Each row's log value(s) less the offset: an interval's lower and upper end; a least-squares
    // start takes one point per row (Obs::point).
    let off = |i: usize| design.offset.map_or(0.0, |o| o[i]);
    let kinds: Vec<Censor> = (0..n).map(|i| x.kind(i)).collect();
    let y: Vec<f64> = (0..n).map(|i| x.x[i].ln() - off(i)).collect();
    let y_upper: Vec<f64> = (0..n).map(|i| if kinds[i] == Censor::Interval { x.upper(i).ln() - off(i) } else { f64::NAN }).collect();
    let y_start: Vec<f64> = (0..n).map(|i| x.point(i).ln() - off(i)).collect();
    let sum_y: f64 = (0..n).filter(|&i| kinds[i] == Censor::Exact).map(|i| x.x[i].ln()).sum();
    // Start: least squares on y, b from the residual sd (Gumbel sd = π b/√6).
    let zt = z.transpose();
    let yv = DVector::from_vec(y_start);
    let mut ztz = &zt * &z;
    for j in 0..k {
        ztz[(j + 1, j + 1)] += pen[j];
    }
    let theta0 = ztz
        .lu()
        .solve(&(&zt * &yv))
        .ok_or_else(|| bad("the covariate columns are collinear".into()))?;
    let res = &yv - &z * &theta0;
    let b0 = ((res.norm_squared() / n as f64).sqrt() * 6f64.sqrt() / std::f64::consts::PI).max(1e-6);
    // Parameters: location (μ, β) in 0..=k, then s = ln b at k + 1 and γ after it.
    let np = k + 2 + r;
    let mut p = DVector::<f64>::zeros(np);
    for j in 0..=k {
        p[j] = theta0[j];
    }
    p[0] += EULER_GAMMA * b0;
    p[k + 1] = b0.ln();
    // The scale row of specimen i: (1, v_i1, …, v_ir).
    let v = |i: usize, c: usize| if c == 0 { 1.0 } else { design.scale_columns[c - 1][i] };

    // ℓ without the constant −Σy, and its derivatives.
    let eval = |p: &DVector<f64>| -> (f64, DVector<f64>, DMatrix<f64>) {
        let eta = &z * p.rows(0, k + 1);
        let mut l = 0.0;
        let mut g = DVector::<f64>::zeros(np);
        let mut h = DMatrix::<f64>::zeros(np, np);
        // Without scale columns ln b is p[k + 1] for every specimen: one exp, not n.
        let b_common = (r == 0).then(|| p[k + 1].exp());
        for i in 0..n {
            let s: f64 = (0..=r).map(|c| p[k + 1 + c] * v(i, c)).sum();
            let b = b_common.unwrap_or_else(|| s.exp());
            // The row's ℓ and its derivatives in (η_i, s_i); w = u (+ k t_i when a column is
            // tied to 1/b).
            let shift = tie.map_or(0.0, |(t, kk)| kk * t[i]);
            let [li, ge, gs, hee, hes, hs] = row_terms(kinds[i], y[i], y_upper[i], eta[i], s, b, shift);
            l += li;
            let zi = z.row(i);
            for a in 0..=k {
                // Zero entries (level indicators of other levels) add nothing: skipped.
                if zi[a] == 0.0 {
                    continue;
                }
                g[a] += ge * zi[a];
                for c in 0..=k {
                    if zi[c] != 0.0 {
                        h[(a, c)] += hee * zi[a] * zi[c];
                    }
                }
                let d = zi[a] * hes;
                for c in 0..=r {
                    h[(a, k + 1 + c)] += d * v(i, c);
                }
            }
            for c in 0..=r {
                let vc = v(i, c);
                if vc == 0.0 {
                    continue;
                }
                g[k + 1 + c] += gs * vc;
                for e in 0..=r {
                    h[(k + 1 + c, k + 1 + e)] += hs * vc * v(i, e);
                }
            }
        }
        for a in 0..=k {
            for c in 0..=r {
                h[(k + 1 + c, a)] = h[(a, k + 1 + c)];
            }
        }
        // The ridge penalty −Σ λ β²/2 (penalised columns are unscaled: β = p).
        for j in 0..k {
            if pen[j] > 0.0 {
                l -= 0.5 * pen[j] * p[j + 1] * p[j + 1];
                g[j + 1] -= pen[j] * p[j + 1];
                h[(j + 1, j + 1)] -= pen[j];
            }
        }
        (l, g, h)
    };

    if let Some(st) = start.filter(|st| st.beta.len() == k && st.gamma.len() == r && st.b > 0.0) {
        let mut q = DVector::<f64>::zeros(np);
        q[0] = st.mu + (0..k).map(|j| st.beta[j] * centre[j]).sum::<f64>();
        for j in 0..k {
            q[j + 1] = st.beta[j] * spread[j];
        }
        q[k + 1] = st.b.ln();
        for j in 0..r {
            q[k + 2 + j] = st.gamma[j];
        }
        if eval(&q).0.is_finite() {
            p = q;
        }
    }
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
                    for d in 0..np {
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
    let penalised: Vec<usize> = (0..k).filter(|&j| pen[j] > 0.0).collect();
    let ln_det_penalised = if penalised.is_empty() {
        0.0
    } else {
        let block = DMatrix::from_fn(penalised.len(), penalised.len(), |a, c| -h[(penalised[a] + 1, penalised[c] + 1)]);
        block.cholesky().map_or(f64::NAN, |c| 2.0 * c.l().diagonal().iter().map(|d| d.ln()).sum::<f64>())
    };
    let penalty_value: f64 = (0..k).map(|j| 0.5 * pen[j] * p[j + 1] * p[j + 1]).sum();
    let edf_penalised = penalised.iter().map(|&j| 1.0 - pen[j] * cov.as_ref().map_or(f64::NAN, |c| c[(j + 1, j + 1)])).sum();
    let beta: Vec<f64> = (0..k).map(|j| p[j + 1] / spread[j]).collect();
    let beta_se: Vec<f64> = (0..k)
        .map(|j| cov.as_ref().map_or(f64::NAN, |c| c[(j + 1, j + 1)].max(0.0).sqrt() / spread[j]))
        .collect();
    let mu = p[0] - (0..k).map(|j| beta[j] * centre[j]).sum::<f64>();
    let gamma: Vec<f64> = (0..r).map(|j| p[k + 2 + j]).collect();
    let gamma_se: Vec<f64> = (0..r).map(|j| cov.as_ref().map_or(f64::NAN, |c| c[(k + 2 + j, k + 2 + j)].max(0.0).sqrt())).collect();
    // μ = p₀ − Σ β_j c_j: its variance and covariance with s through the gradient of that map.
    let location_scale_cov = cov.as_ref().map_or([f64::NAN; 3], |c| {
        let grad: Vec<f64> = (0..=k).map(|j| if j == 0 { 1.0 } else { -centre[j - 1] / spread[j - 1] }).collect();
        let var_mu: f64 = (0..=k).map(|a| (0..=k).map(|b| grad[a] * c[(a, b)] * grad[b]).sum::<f64>()).sum();
        let cov_mu_s: f64 = (0..=k).map(|a| grad[a] * c[(a, k + 1)]).sum();
        [var_mu, c[(k + 1, k + 1)], cov_mu_s]
    });
    Ok(RegFit { mu, beta, beta_se, b: p[k + 1].exp(), gamma, gamma_se, loglik: l + penalty_value - sum_y, ln_det_penalised, edf_penalised, location_scale_cov })
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
        let r = fit(Obs::exact(&x), &Design::default()).unwrap();
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
        let r = fit(Obs::exact(&x), &Design { columns: &cols, ..Design::default() }).unwrap();
        assert!((r.beta[0] - 0.5).abs() < 3.0 * r.beta_se[0], "β = {} ± {}", r.beta[0], r.beta_se[0]);
        assert!((r.shape() - 12.0).abs() < 0.5, "m = {}", r.shape());
        assert!(r.beta_se[0] > 0.0 && r.beta_se[0] < 0.05);
    }

    #[test]
    fn a_modulus_per_group_is_the_groups_fitted_apart() {
        // Two groups with their own scale and modulus: the regression with one level column and
        // one scale column reaches the sum of the groups' separate two-parameter maxima, and
        // its scales and moduli are theirs.
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let (a, b) = (Weibull::new(5.0, 1.0e8).unwrap(), Weibull::new(12.0, 1.3e8).unwrap());
        let xa: Vec<f64> = (0..40).map(|_| a.sample(&mut rng)).collect();
        let xb: Vec<f64> = (0..25).map(|_| b.sample(&mut rng)).collect();
        let x: Vec<f64> = xa.iter().chain(&xb).copied().collect();
        let g: Vec<f64> = (0..65).map(|i| f64::from(u8::from(i >= 40))).collect();
        let cols = vec![g.clone()];
        let r = fit(Obs::exact(&x), &Design { columns: &cols, offset: None, scale_columns: &cols, penalty: &[] }).unwrap();
        let (fa, fb) = (fit_mle(&xa).unwrap().mle, fit_mle(&xb).unwrap().mle);
        let apart = fa.log_likelihood(&xa) + fb.log_likelihood(&xb);
        assert!((r.loglik - apart).abs() < 1e-6 * apart.abs(), "{} vs {apart}", r.loglik);
        assert!((r.shape() / fa.shape - 1.0).abs() < 1e-6);
        let design = Design { columns: &cols, offset: None, scale_columns: &cols, penalty: &[] };
        assert!((1.0 / r.b_at(&design, 50) / fb.shape - 1.0).abs() < 1e-6);
        assert!(((r.mu + r.beta[0]).exp() / fb.scale - 1.0).abs() < 1e-6);
        assert!(r.gamma_se[0] > 0.0 && r.gamma_se[0].is_finite());
        // The CDF uses each specimen's own modulus.
        let x0 = 1.2e8;
        assert!((r.cdf(&design, 50, x0) - b_cdf(fb.shape, fb.scale, x0)).abs() < 1e-6);
    }

    fn b_cdf(m: f64, s: f64, x: f64) -> f64 {
        1.0 - (-(x / s).powf(m)).exp()
    }

    #[test]
    fn the_profile_interval_ends_where_the_likelihood_has_fallen_by_the_chi_square_quantile() {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for n in [30usize, 2000] {
            let z: Vec<f64> = (0..n).map(|i| ((i % 7) as f64 - 3.0) / 3.0).collect();
            let x: Vec<f64> = z.iter().map(|&zi| draw_particles(&[(4e8f64).ln() + 0.05 * zi], 8.0, 1, &mut rng)[0].1.exp()).collect();
            let cols = vec![z.clone()];
            let d = Design { columns: &cols, ..Design::default() };
            let f = fit(Obs::exact(&x), &d).unwrap();
            let (lo, hi) = profile_interval(Obs::exact(&x), &d, &f, 0, 0.90).unwrap();
            assert!(lo < f.beta[0] && f.beta[0] < hi, "{lo} {} {hi}", f.beta[0]);
            // At each end the profile likelihood has fallen by χ²₁(0.90)/2 = 1.3528.
            for b in [lo, hi] {
                let off: Vec<f64> = z.iter().map(|zi| b * zi).collect();
                let p = fit(Obs::exact(&x), &Design { offset: Some(&off), ..Design::default() }).unwrap();
                assert!((2.0 * (f.loglik - p.loglik) - 2.705_543).abs() < 1e-4, "n = {n}: {}", 2.0 * (f.loglik - p.loglik));
            }
            // On a large sample the likelihood is quadratic: the Wald band.
            if n == 2000 {
                let w = 1.644_854 * f.beta_se[0];
                assert!(((hi - lo) / (2.0 * w) - 1.0).abs() < 0.03, "{lo} {hi} vs ±{w}");
            }
        }
    }

    fn censored(x: &[f64], limit: f64) -> crate::obs::Observations {
        let kind: Vec<Censor> = x.iter().map(|v| if *v > limit { Censor::Right } else { Censor::Exact }).collect();
        let n = x.len();
        crate::obs::Observations {
            x: x.iter().map(|v| v.min(limit)).collect(),
            censoring: Some(crate::obs::Censoring { kind, upper: vec![f64::NAN; n], scheme: std::sync::Arc::new(crate::obs::Scheme { right: vec![limit; n], left: vec![0.0; n], edges: vec![Vec::new(); n], right_draws: vec![Vec::new(); n] }) }),
        }
    }

    #[test]
    fn a_right_censored_fit_solves_the_censored_shape_equation() {
        // Without covariates the censored MLE solves Σ_all x^m ln x / Σ_all x^m − 1/m
        // − (1/r) Σ_broken ln x = 0 (r broken rows; Lawless 2003 eq. 5.2.8), and
        // σ^m = Σ_all x^m / r.
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let w = Weibull::new(11.5, 300e6).unwrap();
        let x: Vec<f64> = (0..60).map(|_| w.sample(&mut rng)).collect();
        let o = censored(&x, 320e6);
        let r = fit(o.view(), &Design::default()).unwrap();
        let (m, sigma) = (r.shape(), r.mu.exp());
        let broken: Vec<f64> = (0..60).filter(|&i| o.view().kind(i) == Censor::Exact).map(|i| o.x[i]).collect();
        assert!(broken.len() < 60 && broken.len() > 30, "{} broken", broken.len());
        let rr = broken.len() as f64;
        let s0: f64 = o.x.iter().map(|v| (v / 3e8).powf(m)).sum();
        let s1: f64 = o.x.iter().map(|v| (v / 3e8).powf(m) * (v / 3e8).ln()).sum();
        let g = s1 / s0 - 1.0 / m - broken.iter().map(|v| (v / 3e8).ln()).sum::<f64>() / rr;
        assert!(g.abs() < 1e-9, "shape equation {g}");
        assert!((sigma / (3e8 * (s0 / rr).powf(1.0 / m)) - 1.0).abs() < 1e-9);
        // Its log-likelihood is Σ_broken ln f + Σ_unbroken ln S.
        let law = Weibull::new(m, sigma).unwrap();
        let l: f64 = broken.iter().map(|v| law.ln_pdf(*v)).sum::<f64>() - (60 - broken.len()) as f64 * (320e6f64 / sigma).powf(m);
        assert!((r.loglik - l).abs() < 1e-8 * l.abs(), "{} vs {l}", r.loglik);
    }

    #[test]
    fn narrow_classes_give_the_exact_fit_and_a_left_censored_row_adds_ln_f() {
        // Every value in a class ±0.01 % wide: the interval fit equals the exact fit.
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let w = Weibull::new(8.0, 2.0).unwrap();
        let x: Vec<f64> = (0..80).map(|_| w.sample(&mut rng)).collect();
        let n = x.len();
        let o = crate::obs::Observations {
            x: x.iter().map(|v| v * (1.0 - 1e-4)).collect(),
            censoring: Some(crate::obs::Censoring { kind: vec![Censor::Interval; n], upper: x.iter().map(|v| v * (1.0 + 1e-4)).collect(), scheme: Default::default() }),
        };
        let (a, b) = (fit(Obs::exact(&x), &Design::default()).unwrap(), fit(o.view(), &Design::default()).unwrap());
        assert!((a.shape() / b.shape() - 1.0).abs() < 1e-4 && (a.mu - b.mu).abs() < 1e-5, "{} {} vs {} {}", a.shape(), a.mu, b.shape(), b.mu);
        // Five rows broke at or below 2.5: each adds ln F(2.5) at the fitted law.
        let c = crate::obs::Censoring { kind: (0..n).map(|i| if i < 5 { Censor::Left } else { Censor::Exact }).collect(), upper: vec![f64::NAN; n], scheme: Default::default() };
        let xl: Vec<f64> = x.iter().enumerate().map(|(i, v)| if i < 5 { 2.5 } else { *v }).collect();
        let f = fit(Obs { x: &xl, censoring: Some(&c) }, &Design::default()).unwrap();
        let law = Weibull::new(f.shape(), f.mu.exp()).unwrap();
        let l: f64 = xl[5..].iter().map(|v| law.ln_pdf(*v)).sum::<f64>() + 5.0 * law.cdf(2.5).ln();
        assert!((f.loglik - l).abs() < 1e-9 * l.abs());
    }

    #[test]
    fn a_sample_that_never_broke_is_refused() {
        let x = [1.0, 2.0, 3.0, 4.0];
        let o = censored(&x, 0.5);
        let e = fit(o.view(), &Design::default()).unwrap_err().to_string();
        assert!(e.contains("none of the 4 specimens broke"), "{e}");
    }
}

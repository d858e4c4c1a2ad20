//! Two-parameter Weibull strength statistics per ASTM C1239 (complete samples, one flaw
//! population), with C1239's unbiasing factor and pivotal confidence bounds simulated here
//! rather than copied from the standard's tables.
//!
//! # Equations
//!
//! ```text
//! P_f(σ) = 1 − exp[−(σ/σ_θ)^m]
//! shape:  g(m) = Σ x_i^m ln x_i / Σ x_i^m − (1/N) Σ ln x_i − 1/m = 0   (x_i = σ_i / max σ)
//! scale:  σ̂_θ = max σ · [(1/N) Σ x_i^m̂]^(1/m̂)
//! ```
//!
//! g is strictly increasing (g' = Var_w(ln x) + 1/m² > 0), so the root is bracketed and found by
//! safeguarded Newton on the scaled data (no overflow for any m).
//!
//! **Unbiasing** (C1239 §8.3): m̂ is biased high; m_unbiased = UF(N)·m̂ with UF = 1/E[m̂/m].
//! **Pivotal bounds** (Thoman, Bain & Antle 1969): q = m̂/m and t = m̂ ln(σ̂_θ/σ_θ) have
//! parameter-free distributions; both are simulated on standard Weibull samples (m = σ_θ = 1),
//! seeded, in parallel blocks with one ChaCha8 stream per block, so the result does not depend on
//! the thread count. Bounds at two-sided confidence 1 − α:
//!
//! ```text
//! m   ∈ [m̂/q_{1−α/2}, m̂/q_{α/2}]        σ_θ ∈ [σ̂_θ exp(−t_{1−α/2}/m̂), σ̂_θ exp(−t_{α/2}/m̂)]
//! ```
//!
//! The same simulated pairs give joint draws of (m, σ_θ) consistent with the data
//! (m_j = m̂/q_j, σ_j = σ̂ exp(−t_j/m̂)): the parametric-bootstrap band of the CDF and of any
//! downstream quantity such as the breaking probability.
//!
//! Also: observed-information (Fisher matrix) standard errors and log-Wald bounds (the
//! convention of `reliability`'s `Fit_Weibull_2P`), probability-plot points
//! F_i = (i − 0.5)/N (C1239 §8.5), and size scaling σ_θ2 = σ_θ1 (V_eff1/V_eff2)^(1/m) (C1683).
//!
//! Verified by `tests/verification/weibull.rs`: Lieblein–Zelen data (shape 2.10206, scale
//! 81.8783, log-likelihood −113.6913, Fisher SEs and log-Wald bounds) and the C1239 unbiasing
//! factors within 0.01.

use rand::{Rng, SeedableRng};
use rand_distr::Distribution;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

use crate::error::{Error, Result};

/// A two-parameter Weibull distribution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Weibull {
    /// Shape (Weibull modulus) m, > 0.
    pub shape: f64,
    /// Scale (characteristic strength) σ_θ, > 0, in the data's unit.
    pub scale: f64,
}

impl Weibull {
    /// Validated constructor.
    pub fn new(shape: f64, scale: f64) -> Result<Self> {
        if !(shape > 0.0 && shape.is_finite() && scale > 0.0 && scale.is_finite()) {
            return Err(Error::Param {
                name: "weibull".into(),
                rule: format!("shape and scale must be finite and > 0 (got {shape}, {scale})"),
            });
        }
        Ok(Weibull { shape, scale })
    }

    /// Cumulative hazard H = (x/σ_θ)^m = −ln(1 − P_f).
    pub fn cumulative_hazard(&self, x: f64) -> f64 {
        if x <= 0.0 { 0.0 } else { (x / self.scale).powf(self.shape) }
    }

    /// P_f(x) = 1 − exp(−H), accurate for tiny probabilities.
    pub fn cdf(&self, x: f64) -> f64 {
        -(-self.cumulative_hazard(x)).exp_m1()
    }

    /// Quantile: x with P_f(x) = p.
    pub fn quantile(&self, p: f64) -> f64 {
        self.scale * (-(-p).ln_1p()).powf(1.0 / self.shape)
    }

    /// Log density.
    pub fn ln_pdf(&self, x: f64) -> f64 {
        if x <= 0.0 {
            return f64::NEG_INFINITY;
        }
        let z = x / self.scale;
        self.shape.ln() - self.scale.ln() + (self.shape - 1.0) * z.ln() - z.powf(self.shape)
    }

    /// Log-likelihood of a sample.
    pub fn log_likelihood(&self, data: &[f64]) -> f64 {
        data.iter().map(|&x| self.ln_pdf(x)).sum()
    }

    /// One draw by inversion.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let u: f64 = rng.random();
        self.scale * (-(1.0 - u).ln()).powf(1.0 / self.shape)
    }
}

/// Maximum-likelihood fit of a complete sample.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WeibullFit {
    /// Sample size N.
    pub n: usize,
    /// MLE (m̂, σ̂_θ).
    pub mle: Weibull,
    /// Log-likelihood at the MLE.
    pub log_likelihood: f64,
}

fn invalid_sample(rule: String) -> Error {
    Error::numerical("Weibull maximum-likelihood fit", rule)
}

/// Shape equation on log-data `lx` (shifted so max = 0) at m: g, g′, g″ and Σ x^m.
///
/// With weights w_i = x_i^m / Σ x^m and moments E_w of ln x:
/// g = E_w[l] − mean(l) − 1/m, g′ = Var_w(l) + 1/m², g″ = κ₃,w(l) − 2/m³.
fn shape_equation(lx: &[f64], mean_lx: f64, m: f64) -> (f64, f64, f64, f64) {
    let (mut s0, mut s1, mut s2, mut s3) = (0.0, 0.0, 0.0, 0.0);
    for &l in lx {
        let w = (m * l).exp();
        let wl = w * l;
        s0 += w;
        s1 += wl;
        s2 += wl * l;
        s3 += wl * l * l;
    }
    let (e1, e2, e3) = (s1 / s0, s2 / s0, s3 / s0);
    let var = e2 - e1 * e1;
    let k3 = e3 - 3.0 * e2 * e1 + 2.0 * e1 * e1 * e1;
    (e1 - mean_lx - 1.0 / m, var + 1.0 / (m * m), k3 - 2.0 / (m * m * m), s0)
}

/// Solves the MLE shape equation on log-data shifted so that max = 0; returns (m̂, Σ x^m̂).
///
/// Halley's method (cubic convergence, no extra exponentials over Newton) from the moment
/// estimate m₀ = 1.2825/sd(ln x). g is increasing, so each evaluation also tightens a bracket;
/// a step that leaves the bracket is replaced by bisection, or by doubling/halving while one
/// side is still open. Typically 4 passes over the data.
fn solve_shape(lx: &[f64]) -> Result<(f64, f64)> {
    let n = lx.len() as f64;
    let mean = lx.iter().sum::<f64>() / n;
    let var = lx.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / (n - 1.0);
    let mut m = 1.2825 / var.sqrt();
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for _ in 0..300 {
        let (g, dg, d2g, sum) = shape_equation(lx, mean, m);
        if g < 0.0 { lo = m } else { hi = m }
        let halley = m - 2.0 * g * dg / (2.0 * dg * dg - g * d2g);
        let next = if halley > lo && halley < hi {
            halley
        } else if hi.is_infinite() {
            2.0 * m
        } else if lo == 0.0 {
            0.5 * m
        } else {
            0.5 * (lo + hi)
        };
        if (next - m).abs() <= 1e-13 * m || (hi - lo) <= 1e-13 * m {
            // Σ x^m at m differs from Σ x^next by a relative 1e-13·m·|ln x|: negligible.
            return Ok((next, sum));
        }
        if !(1e-8..=1e8).contains(&next) {
            return Err(invalid_sample(format!("shape root outside [1e-8, 1e8] (iterate {next})")));
        }
        m = next;
    }
    Err(invalid_sample("shape iteration did not converge in 300 steps".into()))
}

/// Maximum-likelihood fit (C1239 §8.2) of a complete sample of positive values.
///
/// ```
/// # use partlife::weibull::fit_mle;
/// let fit = fit_mle(&[1.0, 1.3, 0.8, 1.1, 0.95]).unwrap();
/// assert!(fit.mle.shape > 1.0);
/// ```
pub fn fit_mle(data: &[f64]) -> Result<WeibullFit> {
    if data.len() < 2 {
        return Err(invalid_sample(format!("needs at least 2 values (got {})", data.len())));
    }
    if let Some(x) = data.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
        return Err(invalid_sample(format!("values must be finite and > 0 (got {x})")));
    }
    let max = data.iter().cloned().fold(f64::MIN, f64::max);
    let lx: Vec<f64> = data.iter().map(|x| (x / max).ln()).collect();
    if lx.iter().all(|&l| l == lx[0]) {
        return Err(invalid_sample("all values are equal: the shape is unbounded".into()));
    }
    let (m, _) = solve_shape(&lx)?;
    // The scale from an exact final pass: the data fit is reported to full precision.
    let mean_w = lx.iter().map(|l| (m * l).exp()).sum::<f64>() / data.len() as f64;
    let mle = Weibull { shape: m, scale: max * mean_w.powf(1.0 / m) };
    Ok(WeibullFit { n: data.len(), mle, log_likelihood: mle.log_likelihood(data) })
}

/// Fisher-matrix (observed information) standard errors and log-Wald bounds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FisherBounds {
    /// Standard error of m̂.
    pub shape_se: f64,
    /// Standard error of σ̂_θ.
    pub scale_se: f64,
    /// Correlation of (m̂, σ̂_θ).
    pub correlation: f64,
    /// Two-sided confidence level.
    pub confidence: f64,
    /// Bounds on m: m̂ exp(∓z se/m̂).
    pub shape: (f64, f64),
    /// Bounds on σ_θ.
    pub scale: (f64, f64),
}

/// Observed-information standard errors at the MLE and log-Wald bounds at `confidence`.
pub fn fisher_bounds(fit: &WeibullFit, data: &[f64], confidence: f64) -> Result<FisherBounds> {
    check_confidence(confidence)?;
    let (m, eta) = (fit.mle.shape, fit.mle.scale);
    let n = data.len() as f64;
    let (mut sz, mut szl, mut szl2) = (0.0, 0.0, 0.0);
    for &x in data {
        let l = (x / eta).ln();
        let z = (m * l).exp();
        sz += z;
        szl += z * l;
        szl2 += z * l * l;
    }
    // Observed information = negative Hessian of ℓ(m, η); its inverse is the covariance.
    let imm = n / (m * m) + szl2;
    let iee = -(m / (eta * eta)) * (n - (m + 1.0) * sz);
    let ime = n / eta - sz / eta - m * szl / eta;
    let info = nalgebra::Matrix2::new(imm, ime, ime, iee);
    let cov = info
        .cholesky()
        .map(|c| c.inverse())
        .ok_or_else(|| Error::numerical("Weibull Fisher matrix", format!("not positive definite: {info:?}")))?;
    let (vmm, vee, vme) = (cov[(0, 0)], cov[(1, 1)], cov[(0, 1)]);
    let z = std_normal_quantile(0.5 + 0.5 * confidence);
    let (sm, se) = (vmm.sqrt(), vee.sqrt());
    Ok(FisherBounds {
        shape_se: sm,
        scale_se: se,
        correlation: vme / (sm * se),
        confidence,
        shape: (m * (-z * sm / m).exp(), m * (z * sm / m).exp()),
        scale: (eta * (-z * se / eta).exp(), eta * (z * se / eta).exp()),
    })
}

impl FisherBounds {
    /// The same bounds from the covariance of (ln σ̂_θ, ln b̂), b = 1/m — what the Weibull
    /// regression's observed information gives, censored rows included: se(σ̂) = σ̂ sd(ln σ̂),
    /// se(m̂) = m̂ sd(ln b̂), corr(m̂, σ̂) = −corr(ln b̂, ln σ̂). At the MLE this is the same
    /// matrix as [`fisher_bounds`] transformed (the gradient vanishes there).
    pub fn from_log_cov(law: Weibull, [var_ln_scale, var_ln_b, cov]: [f64; 3], confidence: f64) -> Result<FisherBounds> {
        check_confidence(confidence)?;
        if !(var_ln_scale > 0.0 && var_ln_b > 0.0) {
            return Err(Error::numerical("Weibull Fisher matrix", format!("not positive definite: variances {var_ln_scale}, {var_ln_b}")));
        }
        let (m, eta) = (law.shape, law.scale);
        let z = std_normal_quantile(0.5 + 0.5 * confidence);
        let (sm, se) = (m * var_ln_b.sqrt(), eta * var_ln_scale.sqrt());
        Ok(FisherBounds {
            shape_se: sm,
            scale_se: se,
            correlation: -cov / (var_ln_scale * var_ln_b).sqrt(),
            confidence,
            shape: (m * (-z * sm / m).exp(), m * (z * sm / m).exp()),
            scale: (eta * (-z * se / eta).exp(), eta * (z * se / eta).exp()),
        })
    }
}

fn std_normal_quantile(p: f64) -> f64 {
    Normal::new(0.0, 1.0).map(|n| n.inverse_cdf(p)).unwrap_or(f64::NAN)
}

fn check_confidence(c: f64) -> Result<()> {
    if !(c > 0.0 && c < 1.0) {
        return Err(Error::Param { name: "confidence".into(), rule: format!("must lie in (0, 1) (got {c})") });
    }
    Ok(())
}

/// Simulated pivotal quantities for sample size N (Thoman, Bain & Antle 1969).
#[derive(Debug, Clone, PartialEq)]
pub struct Pivotal {
    /// Sample size N the pivots were simulated for.
    pub n: usize,
    /// Pairs (q_j, t_j) = (m̂*, m̂* ln σ̂*) from standard Weibull samples, in simulation order.
    pub pairs: Vec<(f64, f64)>,
    q_sorted: Vec<f64>,
    t_sorted: Vec<f64>,
}

/// Replicates per parallel block: each block has its own ChaCha8 stream.
const BLOCK: usize = 256;

/// Simulates `replicates` standard-Weibull samples of size `n` and fits each (seeded;
/// deterministic whatever the thread count).
pub fn simulate_pivotal(n: usize, replicates: usize, seed: u64) -> Result<Pivotal> {
    if n < 2 || replicates < 100 {
        return Err(Error::Param {
            name: "pivotal simulation".into(),
            rule: format!("needs n ≥ 2 and ≥ 100 replicates (got n = {n}, {replicates})"),
        });
    }
    let blocks = replicates.div_ceil(BLOCK);
    let per_block: Vec<Result<Vec<(f64, f64)>>> = (0..blocks)
        .into_par_iter()
        .map(|b| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(b as u64);
            let count = BLOCK.min(replicates - b * BLOCK);
            let mut out = Vec::with_capacity(count);
            let mut lx = vec![0.0; n];
            for _ in 0..count {
                // Standard Weibull (m = 1) = standard exponential (ziggurat sampler).
                for l in lx.iter_mut() {
                    let x: f64 = rand_distr::Exp1.sample(&mut rng);
                    *l = x.ln();
                }
                let max = lx.iter().cloned().fold(f64::MIN, f64::max);
                for l in lx.iter_mut() {
                    *l -= max;
                }
                let (m, sum) = solve_shape(&lx)?;
                let ln_scale = max + (sum / n as f64).ln() / m;
                out.push((m, m * ln_scale));
            }
            Ok(out)
        })
        .collect();
    let mut pairs = Vec::with_capacity(replicates);
    for b in per_block {
        pairs.extend(b?);
    }
    let mut q_sorted: Vec<f64> = pairs.iter().map(|p| p.0).collect();
    let mut t_sorted: Vec<f64> = pairs.iter().map(|p| p.1).collect();
    q_sorted.sort_by(f64::total_cmp);
    t_sorted.sort_by(f64::total_cmp);
    Ok(Pivotal { n, pairs, q_sorted, t_sorted })
}

pub use crate::stats::sorted_quantile;

/// Pivotal confidence bounds and the unbiased modulus of one fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PivotalBounds {
    /// Unbiasing factor UF(N) = 1/E[m̂/m] (simulated).
    pub unbiasing_factor: f64,
    /// Unbiased modulus UF·m̂.
    pub shape_unbiased: f64,
    /// Two-sided confidence level.
    pub confidence: f64,
    /// Bounds on m.
    pub shape: (f64, f64),
    /// Bounds on σ_θ.
    pub scale: (f64, f64),
}

impl Pivotal {
    /// Unbiasing factor UF(N) = 1/mean(m̂/m).
    pub fn unbiasing_factor(&self) -> f64 {
        self.pairs.len() as f64 / self.pairs.iter().map(|p| p.0).sum::<f64>()
    }

    /// Quantile of q = m̂/m.
    pub fn q_quantile(&self, p: f64) -> f64 {
        sorted_quantile(&self.q_sorted, p)
    }

    /// Quantile of t = m̂ ln(σ̂_θ/σ_θ).
    pub fn t_quantile(&self, p: f64) -> f64 {
        sorted_quantile(&self.t_sorted, p)
    }

    /// Pivotal bounds for a fit of the same sample size.
    pub fn bounds(&self, fit: &WeibullFit, confidence: f64) -> Result<PivotalBounds> {
        check_confidence(confidence)?;
        if fit.n != self.n {
            return Err(Error::numerical(
                "pivotal bounds",
                format!("pivots simulated for N = {}, fit has N = {}", self.n, fit.n),
            ));
        }
        let a = 0.5 * (1.0 - confidence);
        let (m, s) = (fit.mle.shape, fit.mle.scale);
        let uf = self.unbiasing_factor();
        Ok(PivotalBounds {
            unbiasing_factor: uf,
            shape_unbiased: uf * m,
            confidence,
            shape: (m / self.q_quantile(1.0 - a), m / self.q_quantile(a)),
            scale: (s * (-self.t_quantile(1.0 - a) / m).exp(), s * (-self.t_quantile(a) / m).exp()),
        })
    }

    /// Joint draws of (m, σ_θ) consistent with the fit: m_j = m̂/q_j, σ_j = σ̂ exp(−t_j/m̂).
    pub fn draws(&self, fit: &WeibullFit) -> Vec<Weibull> {
        let (m, s) = (fit.mle.shape, fit.mle.scale);
        self.pairs.iter().map(|&(q, t)| Weibull { shape: m / q, scale: s * (-t / m).exp() }).collect()
    }
}

/// Probability-plot points (x_(i), F_i = (i − 0.5)/N), sorted ascending (C1239 §8.5).
pub fn probability_plot(data: &[f64]) -> Vec<(f64, f64)> {
    let mut x = data.to_vec();
    x.sort_by(f64::total_cmp);
    let n = x.len() as f64;
    x.into_iter().enumerate().map(|(i, v)| (v, (i as f64 + 0.5) / n)).collect()
}

/// A probability-plot point of one row of a censored sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlotPoint {
    /// Where it is drawn: an exact row's value, a censored row's limit, an interval's upper end.
    pub x: f64,
    /// Its plotting position F.
    pub f: f64,
    /// What the row says.
    pub kind: crate::obs::Censor,
}

/// Plotting positions of observations of any kind: C1239 §8.5's F_i = (i − 0.5)/N for a
/// complete sample; otherwise from the nonparametric maximum-likelihood estimate F̂ of the
/// CDF (Turnbull 1976, self-consistency iterations on the rows' values and limits; with right
/// censoring only it is the Kaplan–Meier estimate): an exact row at F̂(x−) + (r − ½)/k·ΔF̂(x)
/// (the r-th of k rows tied at x; (i − 0.5)/N again without censoring), a censored row at its
/// limit with F̂ there, an interval row at its upper end with F̂ there. Sorted by x.
pub fn probability_plot_observed(obs: crate::obs::Obs) -> Vec<PlotPoint> {
    use crate::obs::Censor;
    if obs.complete() {
        return probability_plot(obs.x).into_iter().map(|(x, f)| PlotPoint { x, f, kind: Censor::Exact }).collect();
    }
    let n = obs.len();
    // Support: every exact value, interval end and limit; the mass beyond them sits at +∞.
    let mut support: Vec<f64> = (0..n).flat_map(|i| [obs.x[i], obs.upper(i)]).filter(|v| v.is_finite()).collect();
    support.sort_by(f64::total_cmp);
    support.dedup();
    let m = support.len();
    let at = |v: f64| support.partition_point(|s| *s < v);
    // Each row's admissible support points, a range [lo, hi) of 0..=m (m: +∞).
    let range: Vec<(usize, usize)> = (0..n)
        .map(|i| {
            let x = obs.x[i];
            match obs.kind(i) {
                Censor::Exact => (at(x), at(x) + 1),
                Censor::Right => (support.partition_point(|s| *s <= x), m + 1),
                Censor::Left => (0, at(x) + 1),
                Censor::Interval => (support.partition_point(|s| *s <= x), at(obs.upper(i)) + 1),
            }
        })
        .collect();
    let mut p = vec![1.0 / (m + 1) as f64; m + 1];
    let mut next = vec![0.0; m + 2];
    let mut prefix = vec![0.0; m + 2];
    for _ in 0..20_000 {
        for j in 0..=m {
            prefix[j + 1] = prefix[j] + p[j];
        }
        next.iter_mut().for_each(|v| *v = 0.0);
        for &(lo, hi) in &range {
            let den = prefix[hi] - prefix[lo];
            if den > 0.0 {
                next[lo] += 1.0 / den;
                next[hi] -= 1.0 / den;
            }
        }
        let mut change = 0.0f64;
        let mut w = 0.0;
        for j in 0..=m {
            w += next[j];
            let q = p[j] * w / n as f64;
            change = change.max((q - p[j]).abs());
            p[j] = q;
        }
        if change < 1e-13 {
            break;
        }
    }
    let mut cdf = vec![0.0; m + 1];
    let mut acc = 0.0;
    for j in 0..m {
        acc += p[j];
        cdf[j] = acc;
    }
    let below = |j: usize| if j == 0 { 0.0 } else { cdf[j - 1] };
    let mut out = Vec::with_capacity(n);
    // Exact rows, tied ones spread over their step of F̂.
    let mut exact: Vec<f64> = (0..n).filter(|&i| obs.kind(i) == Censor::Exact).map(|i| obs.x[i]).collect();
    exact.sort_by(f64::total_cmp);
    let mut g = 0;
    while g < exact.len() {
        let v = exact[g];
        let c = exact[g..].iter().take_while(|w| **w == v).count();
        let j = at(v);
        let (f0, f1) = (below(j), cdf[j]);
        out.extend((0..c).map(|r| PlotPoint { x: v, f: f0 + (r as f64 + 0.5) / c as f64 * (f1 - f0), kind: Censor::Exact }));
        g += c;
    }
    for i in (0..n).filter(|&i| obs.kind(i) != Censor::Exact) {
        let x = if obs.kind(i) == Censor::Interval { obs.upper(i) } else { obs.x[i] };
        out.push(PlotPoint { x, f: cdf[at(x)], kind: obs.kind(i) });
    }
    out.sort_by(|a, b| a.x.total_cmp(&b.x));
    out
}

/// Weibull scale for another effective size: σ_θ2 = σ_θ1 (size1/size2)^(1/m), where size is an
/// effective volume or area (ASTM C1683).
pub fn scale_for_size(scale: f64, shape: f64, size_from: f64, size_to: f64) -> f64 {
    scale * (size_from / size_to).powf(1.0 / shape)
}

/// CDF at x of two Weibull flaw populations, each (σ_j, m_j): the mixture
/// p F₁(x) + (1 − p) F₂(x) (`mixture`, a specimen holds one kind of flaw) or the competing risks
/// 1 − exp[−(x/σ₁)^m₁ − (x/σ₂)^m₂] (every specimen holds both; `p` unused). The laws are fitted
/// in `strength::flaws`; the probability plot draws them from their parameters.
pub fn two_population_cdf(mixture: bool, p: f64, first: (f64, f64), second: (f64, f64), x: f64) -> f64 {
    let h = |(s, m): (f64, f64)| (x / s).powf(m);
    if mixture { p * -(-h(first)).exp_m1() + (1.0 - p) * -(-h(second)).exp_m1() } else { -(-h(first) - h(second)).exp_m1() }
}

/// CDF at x of the three-parameter (threshold) Weibull law 1 − exp[−((x − γ)/σ)^m] for x > γ,
/// 0 below; fitted in `strength::flaws`.
pub fn threshold_cdf(threshold: f64, (s, m): (f64, f64), x: f64) -> f64 {
    -(-((x - threshold).max(0.0) / s).powf(m)).exp_m1()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_parameters_of_a_large_sample() {
        let w = Weibull::new(8.0, 300e6).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let data: Vec<f64> = (0..20_000).map(|_| w.sample(&mut rng)).collect();
        let fit = fit_mle(&data).unwrap();
        // Asymptotic SE of m̂ ≈ 0.78 m/√N = 0.044; of σ̂ ≈ 1.05 σ/(m√N) ≈ 0.28 MPa.
        assert!((fit.mle.shape - 8.0).abs() < 0.2, "{:?}", fit.mle);
        assert!((fit.mle.scale / 300e6 - 1.0).abs() < 0.005, "{:?}", fit.mle);
    }

    #[test]
    fn scale_invariance_of_the_fit() {
        let data = [3.1, 2.2, 4.5, 3.9, 2.8, 3.3, 5.0, 2.9];
        let a = fit_mle(&data).unwrap();
        let scaled: Vec<f64> = data.iter().map(|x| x * 1e9).collect();
        let b = fit_mle(&scaled).unwrap();
        assert!((a.mle.shape - b.mle.shape).abs() < 1e-10);
        assert!((b.mle.scale / a.mle.scale / 1e9 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_samples_are_errors() {
        assert!(fit_mle(&[1.0]).is_err());
        assert!(fit_mle(&[1.0, 1.0, 1.0]).is_err());
        assert!(fit_mle(&[1.0, -2.0, 3.0]).is_err());
        assert!(fit_mle(&[1.0, f64::NAN, 3.0]).is_err());
    }

    #[test]
    fn cdf_quantile_round_trip_and_tail_accuracy() {
        let w = Weibull::new(10.0, 1.0).unwrap();
        for &p in &[1e-15, 1e-6, 0.3, 0.99] {
            assert!((w.cdf(w.quantile(p)) / p - 1.0).abs() < 1e-10);
        }
        // 1 − exp(−1e-20) must be 1e-20, not 0.
        assert!((w.cdf(1e-2) / 1e-20 - 1.0).abs() < 1e-12);
    }

    #[test]
    fn pivotal_simulation_is_thread_count_independent() {
        let a = simulate_pivotal(10, 1000, 42).unwrap();
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let b = pool.install(|| simulate_pivotal(10, 1000, 42).unwrap());
        assert_eq!(a.pairs, b.pairs);
        let c = simulate_pivotal(10, 1000, 43).unwrap();
        assert_ne!(a.pairs, c.pairs);
    }

    #[test]
    fn pivotal_bounds_cover_the_truth_at_the_nominal_rate() {
        // Coverage of the 90 % shape and scale intervals over 400 simulated data sets.
        let n = 15;
        let piv = simulate_pivotal(n, 20_000, 1).unwrap();
        let truth = Weibull::new(6.0, 2.0).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(99);
        let (mut cm, mut cs) = (0, 0);
        let trials = 400;
        for _ in 0..trials {
            let data: Vec<f64> = (0..n).map(|_| truth.sample(&mut rng)).collect();
            let b = piv.bounds(&fit_mle(&data).unwrap(), 0.9).unwrap();
            cm += (b.shape.0 <= 6.0 && 6.0 <= b.shape.1) as usize;
            cs += (b.scale.0 <= 2.0 && 2.0 <= b.scale.1) as usize;
        }
        // Binomial(400, 0.9): sd = 6; accept ±4 sd.
        for c in [cm, cs] {
            assert!((c as f64 - 360.0).abs() < 24.0, "coverage {c}/400");
        }
    }

    #[test]
    fn censored_plotting_positions_follow_kaplan_meier() {
        use crate::obs::{Censor, Censoring, Obs};
        // 1, 2+ (did not break by 2), 3, 4: Kaplan–Meier F̂ = 1/4 from 1, 5/8 from 3, 1 from 4.
        let x = [3.0, 2.0, 1.0, 4.0];
        let c = Censoring::of_rows(vec![Censor::Exact, Censor::Right, Censor::Exact, Censor::Exact], &x, vec![f64::NAN; 4]).unwrap();
        let p = probability_plot_observed(Obs { x: &x, censoring: Some(&c) });
        let got: Vec<(f64, f64, Censor)> = p.iter().map(|q| (q.x, q.f, q.kind)).collect();
        let want = [(1.0, 0.125, Censor::Exact), (2.0, 0.25, Censor::Right), (3.0, 0.4375, Censor::Exact), (4.0, 0.8125, Censor::Exact)];
        for (g, w) in got.iter().zip(&want) {
            assert!(g.0 == w.0 && (g.1 - w.1).abs() < 1e-9 && g.2 == w.2, "{got:?}");
        }
        // A complete sample keeps C1239's (i − 0.5)/N.
        let q = probability_plot_observed(Obs::exact(&x));
        assert_eq!(q.iter().map(|p| p.f).collect::<Vec<_>>(), [0.125, 0.375, 0.625, 0.875]);
    }

    #[test]
    fn size_scaling() {
        // Doubling the effective volume lowers the scale by 2^(−1/m).
        let s = scale_for_size(100.0, 10.0, 1.0, 2.0);
        assert!((s - 100.0 * 2f64.powf(-0.1)).abs() < 1e-12);
    }
}

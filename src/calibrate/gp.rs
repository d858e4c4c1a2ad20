//! Gaussian-process emulator of a scalar simulator output on the unit cube.
//!
//! Kernel: anisotropic Matérn-5/2, `k(x, x') = σ² (1 + √5 r + 5r²/3) e^(−√5 r)`,
//! `r² = Σ_j (x_j − x'_j)²/ℓ_j²`, plus a nugget τ² on the diagonal (simulator noise such as the
//! crush FE's fracture scatter, and conditioning). Outputs are standardised (mean 0, sd 1)
//! before fitting. Hyperparameters (log ℓ_j, log σ², log τ²) maximise the log marginal
//! likelihood `−½ yᵀK⁻¹y − ½ log|K| − (n/2) log 2π` with argmin's Nelder–Mead from several
//! starts (Rasmussen & Williams 2006, ch. 5). Prediction: mean `k*ᵀK⁻¹y`, variance
//! `σ² − k*ᵀK⁻¹k*` (the latent function; add τ² for a new noisy run). Leave-one-out in closed
//! form (R&W eq. 5.12): `μ₋ᵢ = yᵢ − [K⁻¹y]ᵢ/[K⁻¹]ᵢᵢ`, `σ²₋ᵢ = 1/[K⁻¹]ᵢᵢ`.
//!
//! Verified by `tests/verification/gp.rs` (a known function reproduced within its predicted
//! variance; standardised leave-one-out errors of unit scale).

use argmin::core::{CostFunction, Executor};
use argmin::solver::neldermead::NelderMead;
use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};

/// A fitted emulator.
#[derive(Debug, Clone)]
pub struct Gp {
    x: Vec<Vec<f64>>,
    /// Length scales ℓ_j (unit-cube units).
    pub length_scales: Vec<f64>,
    inv_l: Vec<f64>,
    /// Signal variance σ² (standardised units).
    pub signal_variance: f64,
    /// Nugget τ² (standardised units).
    pub nugget: f64,
    y_mean: f64,
    y_sd: f64,
    chol: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    alpha: DVector<f64>,
    ys: DVector<f64>,
    /// Log marginal likelihood at the fitted hyperparameters (standardised data).
    pub log_likelihood: f64,
}

fn matern52(a: &[f64], b: &[f64], inv_l: &[f64], s2: f64) -> f64 {
    let r2: f64 = a.iter().zip(b).zip(inv_l).map(|((x, y), il)| ((x - y) * il).powi(2)).sum();
    let r = (5.0 * r2).sqrt();
    s2 * (1.0 + r + r * r / 3.0) * (-r).exp()
}

/// The kernel matrix plus the nugget on the diagonal. The kernel is evaluated on the lower
/// triangle and mirrored: `matern52(a, b)` and `matern52(b, a)` are the same bits (each
/// difference is the other's exact negation), so this is the matrix evaluated entry by entry,
/// for half the exponentials of the hyperparameter search.
fn kernel_matrix(x: &[Vec<f64>], inv_l: &[f64], s2: f64, nugget: f64) -> DMatrix<f64> {
    let n = x.len();
    let mut k = DMatrix::zeros(n, n);
    for j in 0..n {
        k[(j, j)] = matern52(&x[j], &x[j], inv_l, s2) + nugget;
        for i in j + 1..n {
            let v = matern52(&x[i], &x[j], inv_l, s2);
            k[(i, j)] = v;
            k[(j, i)] = v;
        }
    }
    k
}

/// Negative log marginal likelihood of standardised `y` at log-hyperparameters `h`.
struct Nll<'a> {
    x: &'a [Vec<f64>],
    y: &'a DVector<f64>,
}

impl Nll<'_> {
    fn value(&self, h: &DVector<f64>) -> f64 {
        let d = self.x[0].len();
        // Keep the search in a sane box: ℓ ∈ [1e-3, 1e3], σ² ∈ [1e-4, 1e4], τ² ∈ [1e-10, 1].
        let clamp = |v: f64, lo: f64, hi: f64| v.clamp(lo.ln(), hi.ln());
        let inv_l: Vec<f64> = (0..d).map(|j| (-clamp(h[j], 1e-3, 1e3)).exp()).collect();
        let s2 = clamp(h[d], 1e-4, 1e4).exp();
        let t2 = clamp(h[d + 1], 1e-10, 1.0).exp();
        let k = kernel_matrix(self.x, &inv_l, s2, t2);
        let Some(ch) = k.cholesky() else { return f64::INFINITY };
        let alpha = ch.solve(self.y);
        let logdet: f64 = 2.0 * ch.l_dirty().diagonal().iter().map(|v| v.ln()).sum::<f64>();
        let n = self.y.len() as f64;
        0.5 * self.y.dot(&alpha) + 0.5 * logdet + 0.5 * n * (2.0 * std::f64::consts::PI).ln()
    }
}

impl CostFunction for Nll<'_> {
    type Param = DVector<f64>;
    type Output = f64;
    fn cost(&self, h: &Self::Param) -> std::result::Result<f64, argmin::core::Error> {
        Ok(self.value(h))
    }
}

impl Gp {
    /// Fits an emulator to points `x` (unit cube) and outputs `y`.
    pub fn fit(x: Vec<Vec<f64>>, y: &[f64]) -> Result<Gp> {
        let n = x.len();
        if n < 3 || y.len() != n {
            return Err(Error::config("<emulator>", "design", format!("need ≥ 3 points with one output each, got {n} points and {} outputs", y.len())));
        }
        let d = x[0].len();
        if d == 0 || x.iter().any(|p| p.len() != d || p.iter().any(|v| !v.is_finite())) || y.iter().any(|v| !v.is_finite()) {
            return Err(Error::config("<emulator>", "design", "points must share one dimension ≥ 1 and be finite, outputs finite"));
        }
        let y_mean = y.iter().sum::<f64>() / n as f64;
        let y_sd = (y.iter().map(|v| (v - y_mean).powi(2)).sum::<f64>() / (n as f64 - 1.0)).sqrt().max(1e-300);
        let ys = DVector::from_iterator(n, y.iter().map(|v| (v - y_mean) / y_sd));
        let problem = Nll { x: &x, y: &ys };
        let mut best: Option<(DVector<f64>, f64)> = None;
        for &(l0, t0) in &[(0.3f64, 1e-6f64), (1.0, 1e-4), (0.1, 1e-2)] {
            let start = DVector::from_iterator(d + 2, (0..d).map(|_| l0.ln()).chain([0.0, t0.ln()]));
            let mut simplex = vec![start.clone()];
            for k in 0..d + 2 {
                let mut p = start.clone();
                p[k] += 0.7;
                simplex.push(p);
            }
            let solver = NelderMead::new(simplex).with_sd_tolerance(1e-6).map_err(|e| Error::numerical("emulator", e.to_string()))?;
            let res = Executor::new(Nll { x: &x, y: &ys }, solver)
                .configure(|s| s.max_iters(2000))
                .run()
                .map_err(|e| Error::numerical("emulator", e.to_string()))?;
            let state = res.state();
            if let Some(p) = state.best_param.clone() {
                let c = problem.value(&p);
                if c.is_finite() && best.as_ref().is_none_or(|b| c < b.1) {
                    best = Some((p, c));
                }
            }
        }
        let Some((h, nll)) = best else {
            return Err(Error::numerical("emulator", "no hyperparameters with a positive-definite kernel matrix"));
        };
        let length_scales: Vec<f64> = (0..d).map(|j| h[j].clamp(1e-3f64.ln(), 1e3f64.ln()).exp()).collect();
        let signal_variance = h[d].clamp(1e-4f64.ln(), 1e4f64.ln()).exp();
        let nugget = h[d + 1].clamp(1e-10f64.ln(), 0.0).exp();
        let inv_l: Vec<f64> = length_scales.iter().map(|l| 1.0 / l).collect();
        let chol = kernel_matrix(&x, &inv_l, signal_variance, nugget)
            .cholesky()
            .ok_or_else(|| Error::numerical("emulator", "kernel matrix not positive definite"))?;
        let alpha = chol.solve(&ys);
        Ok(Gp { x, length_scales, inv_l, signal_variance, nugget, y_mean, y_sd, chol, alpha, ys, log_likelihood: -nll })
    }

    /// Predictive mean and variance of the latent function at `p` (output units).
    pub fn predict(&self, p: &[f64]) -> (f64, f64) {
        let mut ks = DVector::from_iterator(self.x.len(), self.x.iter().map(|xi| matern52(xi, p, &self.inv_l, self.signal_variance)));
        let mean = ks.dot(&self.alpha);
        // k*ᵀ K⁻¹ k* = |L⁻¹ k*|² with K = L Lᵀ: one triangular solve, in place (the full
        // `solve` does two and allocates).
        self.chol.l_dirty().solve_lower_triangular_unchecked_mut(&mut ks);
        let var = (self.signal_variance - ks.norm_squared()).max(0.0);
        (self.y_mean + self.y_sd * mean, self.y_sd * self.y_sd * var)
    }

    /// Predictive mean only (no variance solve).
    pub fn mean(&self, p: &[f64]) -> f64 {
        let m: f64 = self.x.iter().zip(self.alpha.iter()).map(|(xi, a)| a * matern52(xi, p, &self.inv_l, self.signal_variance)).sum();
        self.y_mean + self.y_sd * m
    }

    /// Nugget variance in output units (the emulator's estimate of simulator noise).
    pub fn noise_variance(&self) -> f64 {
        self.y_sd * self.y_sd * self.nugget
    }

    /// Leave-one-out predictions (mean, variance of a new run incl. the nugget) at every design
    /// point, output units.
    pub fn leave_one_out(&self) -> Vec<(f64, f64)> {
        let kinv = self.chol.inverse();
        (0..self.x.len())
            .map(|i| {
                let kii = kinv[(i, i)];
                let mu = self.ys[i] - self.alpha[i] / kii;
                (self.y_mean + self.y_sd * mu, self.y_sd * self.y_sd / kii)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mirrored kernel matrix is the kernel evaluated at every entry, bit for bit.
    #[test]
    fn the_mirrored_kernel_matrix_is_the_entrywise_kernel() {
        let x: Vec<Vec<f64>> = (0..23).map(|i| vec![(i as f64 * 0.37).sin().abs(), (i as f64 * 1.9).cos() * 0.5 + 0.5, (i * i % 7) as f64 / 7.0]).collect();
        let inv_l = [3.1, 0.7, 12.0];
        let k = kernel_matrix(&x, &inv_l, 1.7, 1e-4);
        for i in 0..x.len() {
            for j in 0..x.len() {
                let want = matern52(&x[i], &x[j], &inv_l, 1.7) + if i == j { 1e-4 } else { 0.0 };
                assert_eq!(k[(i, j)].to_bits(), want.to_bits(), "({i}, {j})");
            }
        }
    }
}

//! Variance-based sensitivity: first-order and total Sobol' indices by the Saltelli (2010) and
//! Jansen (1999) estimators, with bootstrap confidence intervals.
//!
//! Design (Saltelli 2002/2010): two n × d matrices A and B from one 2d-dimensional Sobol'
//! sequence (the origin skipped), optionally rotated by a seeded random shift modulo 1
//! (Cranley–Patterson) so repeated seeds give independent replicates, and d matrices A_B^(i)
//! = A with column i from B: n(d + 2) model runs.
//!
//! Estimators, with V = Var(f) over the 2n runs of A and B:
//!
//! ```text
//! S_i  = (1/n) Σ_j f(B)_j (f(A_B^(i))_j − f(A)_j) / V          (Saltelli 2010)
//! ST_i = (1/2n) Σ_j (f(A)_j − f(A_B^(i))_j)² / V                (Jansen 1999)
//! ```
//!
//! Confidence intervals: percentile bootstrap over the n rows (the same resampled rows for
//! every index of one replicate), seeded. Negative estimates are reported as they are — a
//! negative S_i says the index is zero within the Monte Carlo error — and flagged by
//! [`SobolIndices::negative`], never clipped.
//!
//! Verified on the Ishigami function and the Sobol' g-function against their closed forms
//! (`tests/verification/sobol.rs`, numbers in docs/reference.md, verification §1).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::design::Sobol;
use crate::error::{Error, Result};

/// The Saltelli design in the unit cube.
#[derive(Debug, Clone)]
pub struct SaltelliDesign {
    /// Base sample size n.
    pub n: usize,
    /// Dimension d.
    pub d: usize,
    /// A (n rows).
    pub a: Vec<Vec<f64>>,
    /// B (n rows).
    pub b: Vec<Vec<f64>>,
}

impl SaltelliDesign {
    /// A design of base size `n` in `d` dimensions; `shift` seeds a random rotation modulo 1
    /// (None: the plain Sobol' points).
    pub fn new(d: usize, n: usize, shift: Option<u64>) -> Result<Self> {
        if n < 2 || d == 0 {
            return Err(Error::config("<sobol>", "n", format!("need n ≥ 2 and d ≥ 1, got n = {n}, d = {d}")));
        }
        let pts = Sobol::points(2 * d, n, 1)?;
        let rot: Vec<f64> = match shift {
            Some(seed) => {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                (0..2 * d).map(|_| rng.random::<f64>()).collect()
            }
            None => vec![0.0; 2 * d],
        };
        let wrap = |x: f64, s: f64| {
            let v = x + s;
            if v >= 1.0 { v - 1.0 } else { v }
        };
        let a = pts.iter().map(|p| (0..d).map(|k| wrap(p[k], rot[k])).collect()).collect();
        let b = pts.iter().map(|p| (0..d).map(|k| wrap(p[d + k], rot[d + k])).collect()).collect();
        Ok(SaltelliDesign { n, d, a, b })
    }

    /// Every point to evaluate, in the order [`estimate`] expects: A, B, then A_B^(1) … A_B^(d).
    pub fn points(&self) -> Vec<Vec<f64>> {
        let mut out = Vec::with_capacity(self.n * (self.d + 2));
        out.extend(self.a.iter().cloned());
        out.extend(self.b.iter().cloned());
        for i in 0..self.d {
            for (ra, rb) in self.a.iter().zip(&self.b) {
                let mut p = ra.clone();
                p[i] = rb[i];
                out.push(p);
            }
        }
        out
    }
}

/// First and total indices of one output.
#[derive(Debug, Clone, PartialEq)]
pub struct SobolIndices {
    /// Base sample size.
    pub n: usize,
    /// Output variance V.
    pub variance: f64,
    /// First-order S_i.
    pub first: Vec<f64>,
    /// Total ST_i.
    pub total: Vec<f64>,
    /// Bootstrap intervals of S_i (level [`estimate`]'s `level`).
    pub first_ci: Vec<(f64, f64)>,
    /// Bootstrap intervals of ST_i.
    pub total_ci: Vec<(f64, f64)>,
}

impl SobolIndices {
    /// Inputs whose first-order or total estimate is negative (zero within Monte Carlo error).
    pub fn negative(&self) -> Vec<usize> {
        (0..self.first.len()).filter(|&i| self.first[i] < 0.0 || self.total[i] < 0.0).collect()
    }
}

/// Point estimates from the rows `rows` (indices into the n base rows).
fn point(fa: &[f64], fb: &[f64], fab: &[&[f64]], rows: &[usize]) -> (f64, Vec<f64>, Vec<f64>) {
    let m = rows.len() as f64;
    let mean = rows.iter().map(|&j| fa[j] + fb[j]).sum::<f64>() / (2.0 * m);
    let var = rows.iter().map(|&j| (fa[j] - mean).powi(2) + (fb[j] - mean).powi(2)).sum::<f64>() / (2.0 * m - 1.0);
    let mut first = Vec::with_capacity(fab.len());
    let mut total = Vec::with_capacity(fab.len());
    for f in fab {
        let (mut s, mut t) = (0.0, 0.0);
        for &j in rows {
            s += fb[j] * (f[j] - fa[j]);
            t += (fa[j] - f[j]).powi(2);
        }
        first.push(s / m / var);
        total.push(t / (2.0 * m) / var);
    }
    (var, first, total)
}

/// Indices from the outputs at [`SaltelliDesign::points`] (`f.len() = n (d + 2)`), with
/// `bootstrap` percentile resamples at confidence `level` (seeded by `seed`).
pub fn estimate(f: &[f64], n: usize, bootstrap: usize, level: f64, seed: u64) -> Result<SobolIndices> {
    if n < 2 || f.len() % n != 0 || f.len() / n < 3 {
        return Err(Error::config("<sobol>", "outputs", format!("{} outputs do not form n (d + 2) runs with n = {n}", f.len())));
    }
    if let Some(v) = f.iter().find(|v| !v.is_finite()) {
        return Err(Error::numerical("Sobol' indices", format!("a model output is {v}")));
    }
    if !(level > 0.0 && level < 1.0) {
        return Err(Error::config("<sobol>", "level", format!("must lie in (0, 1), got {level}")));
    }
    let d = f.len() / n - 2;
    let (fa, fb) = (&f[..n], &f[n..2 * n]);
    let fab: Vec<&[f64]> = (0..d).map(|i| &f[(2 + i) * n..(3 + i) * n]).collect();
    let all: Vec<usize> = (0..n).collect();
    let (variance, first, total) = point(fa, fb, &fab, &all);
    if !(variance > 0.0) {
        return Err(Error::numerical("Sobol' indices", "the output does not vary over the design"));
    }
    let reps: Vec<(Vec<f64>, Vec<f64>)> = (0..bootstrap)
        .into_par_iter()
        .map(|r| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(r as u64 + 1);
            let rows: Vec<usize> = (0..n).map(|_| rng.random_range(0..n)).collect();
            let (_, s, t) = point(fa, fb, &fab, &rows);
            (s, t)
        })
        .collect();
    let ci = |get: &dyn Fn(&(Vec<f64>, Vec<f64>)) -> f64| -> (f64, f64) {
        let mut v: Vec<f64> = reps.iter().map(get).filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return (f64::NAN, f64::NAN);
        }
        v.sort_by(f64::total_cmp);
        let q = |p: f64| crate::weibull::sorted_quantile(&v, p);
        (q(0.5 * (1.0 - level)), q(0.5 * (1.0 + level)))
    };
    let first_ci = (0..d).map(|i| ci(&|r| r.0[i])).collect();
    let total_ci = (0..d).map(|i| ci(&|r| r.1[i])).collect();
    Ok(SobolIndices { n, variance, first, total, first_ci, total_ci })
}

/// Evaluates `f` (unit-cube inputs → outputs) on a Saltelli design in parallel and estimates
/// the indices of every output. Deterministic for the seed whatever the thread count.
pub fn sobol_indices<F>(f: F, d: usize, n: usize, seed: u64, bootstrap: usize, level: f64) -> Result<Vec<SobolIndices>>
where
    F: Fn(&[f64]) -> Result<Vec<f64>> + Sync,
{
    let design = SaltelliDesign::new(d, n, Some(seed))?;
    let ys: Vec<Vec<f64>> = design.points().par_iter().map(|p| f(p)).collect::<Result<_>>()?;
    let outputs = ys.first().map_or(0, |y| y.len());
    (0..outputs)
        .map(|o| {
            let col: Vec<f64> = ys.iter().map(|y| y[o]).collect();
            estimate(&col, n, bootstrap, level, seed ^ 0x5EED_0000 ^ o as u64)
        })
        .collect()
}

//! Weights of competing strength models from their predictive performance.
//!
//! Each model M is scored by the cross-validated log density of every crush test,
//! lpd_iM = ln p_M(x_i | x_−fold(i)) ([`super::fit::cv_pointwise`]); both materials' tests are
//! pooled, since one model specification is applied to both.
//!
//! * **Stacking** (Yao, Vehtari, Simpson & Gelman 2018, *Bayesian Analysis* 13, 917): the weights
//!   maximise the cross-validated log score of the mixture,
//!   `max_w Σ_i ln Σ_M w_M exp(lpd_iM)` over the simplex. A concave problem, solved by the
//!   fixed-point (EM) iteration `w_M ← mean_i [w_M p_iM / Σ_M' w_M' p_iM']`, which increases the
//!   objective at every step.
//! * **Pseudo-BMA**: w_M ∝ exp(elpd_M), elpd_M = Σ_i lpd_iM (Geisser & Eddy 1979; Yao et al.).
//!
//! partlife's headline uses **stacking**. Real particles follow none of the candidate models
//! exactly (the M-open case), and there pseudo-BMA, like BMA, piles the weight onto one model as
//! the data grow even when another carries part of the predictive truth; stacking keeps the
//! combination that predicts best and still concentrates on a model that is right
//! (`tests/strength.rs`: the weights go to the generator's model as n grows). Pseudo-BMA is
//! reported next to it for comparison.

use crate::error::{Error, Result};

/// Fewest crush tests (over all materials) from which weights are computed.
pub const MIN_POINTS: usize = 10;

fn check(lpd: &[Vec<f64>]) -> Result<usize> {
    let n = lpd.first().map_or(0, |v| v.len());
    if lpd.is_empty() || lpd.iter().any(|v| v.len() != n) {
        return Err(Error::numerical("model weights", "every model needs one score per crush test"));
    }
    if n < MIN_POINTS {
        return Err(Error::numerical("model weights", format!("{n} crush tests are too few to weigh strength models by cross-validation (at least {MIN_POINTS})")));
    }
    if let Some(v) = lpd.iter().flatten().find(|v| !v.is_finite()) {
        return Err(Error::numerical("model weights", format!("a cross-validated log density is not finite ({v})")));
    }
    Ok(n)
}

/// Stacking weights of the models whose pointwise scores are `lpd[model][point]`.
pub fn stacking(lpd: &[Vec<f64>]) -> Result<Vec<f64>> {
    let n = check(lpd)?;
    let k = lpd.len();
    // p_iM relative to the best model at each point (the common factor cancels).
    let p: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            let top = (0..k).map(|m| lpd[m][i]).fold(f64::NEG_INFINITY, f64::max);
            (0..k).map(|m| (lpd[m][i] - top).exp()).collect()
        })
        .collect();
    let objective = |w: &[f64]| p.iter().map(|pi| pi.iter().zip(w).map(|(a, b)| a * b).sum::<f64>().ln()).sum::<f64>();
    let mut w = vec![1.0 / k as f64; k];
    let mut last = objective(&w);
    for _ in 0..100_000 {
        let mut next = vec![0.0; k];
        for pi in &p {
            let mix: f64 = pi.iter().zip(&w).map(|(a, b)| a * b).sum();
            for m in 0..k {
                next[m] += w[m] * pi[m] / mix;
            }
        }
        next.iter_mut().for_each(|v| *v /= n as f64);
        let now = objective(&next);
        let change = next.iter().zip(&w).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        w = next;
        if change < 1e-10 && (now - last).abs() < 1e-12 * now.abs().max(1.0) {
            break;
        }
        last = now;
    }
    Ok(w)
}

/// Pseudo-BMA weights w_M ∝ exp(Σ_i lpd_iM).
pub fn pseudo_bma(lpd: &[Vec<f64>]) -> Result<Vec<f64>> {
    check(lpd)?;
    let elpd: Vec<f64> = lpd.iter().map(|v| v.iter().sum()).collect();
    let top = elpd.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let e: Vec<f64> = elpd.iter().map(|v| (v - top).exp()).collect();
    let total: f64 = e.iter().sum();
    Ok(e.into_iter().map(|v| v / total).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stacking_finds_the_mixture_optimum() {
        // Two models, each right on half the points: the best mixture is 50/50.
        let a: Vec<f64> = (0..20).map(|i| if i % 2 == 0 { 0.0 } else { -3.0 }).collect();
        let b: Vec<f64> = (0..20).map(|i| if i % 2 == 0 { -3.0 } else { 0.0 }).collect();
        let w = stacking(&[a.clone(), b]).unwrap();
        assert!((w[0] - 0.5).abs() < 1e-6, "{w:?}");
        // A model better everywhere takes all the weight; pseudo-BMA agrees.
        let c: Vec<f64> = a.iter().map(|v| v - 1.0).collect();
        let w = stacking(&[a.clone(), c.clone()]).unwrap();
        assert!(w[0] > 0.999, "{w:?}");
        assert!(pseudo_bma(&[a, c]).unwrap()[0] > 0.999);
        // Too few points is an error with the reason.
        let e = stacking(&[vec![0.0; 5], vec![0.0; 5]]).unwrap_err().to_string();
        assert!(e.contains("too few"), "{e}");
    }
}

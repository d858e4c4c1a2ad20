//! The main study's headline numbers: the comparison rows per strength model, damage model and
//! horizon, their model average, and the one way a probability with its Monte Carlo error is
//! written. Shared by the run (which computes them) and the summary (which states them).

use crate::lifetime::damage::DamageModel;

/// P ± its Monte Carlo standard error, the error written so that it never reads as zero: to four
/// decimals, in scientific notation below 5·10⁻⁵, and as "in all n samples" when every sample
/// agreed (se = 0, p = 0 or 1).
pub fn pm(p: f64, se: f64, n: usize) -> String {
    if se == 0.0 && (p == 0.0 || p == 1.0) {
        format!("{p:.4} (in all {n} samples)")
    } else if se < 5e-5 {
        format!("{p:.4} ± {se:.1e}")
    } else {
        format!("{p:.4} ± {se:.4}")
    }
}

/// One row of the comparison: P(candidate worse) of a strength model (or the average) under a
/// damage model at a horizon, with the medians of both materials.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Strength model name, or `model-averaged`.
    pub strength: String,
    /// Damage model.
    pub damage: DamageModel,
    /// Horizon (years).
    pub years: f64,
    /// P(candidate breaks more).
    pub worse: f64,
    /// Its Monte Carlo standard error.
    pub se: f64,
    /// Fraction of samples with equal P.
    pub ties: f64,
    /// Median P of candidate and reference.
    pub median: [f64; 2],
    /// 5 % and 95 % quantiles of P, candidate and reference.
    pub band: [(f64, f64); 2],
}

/// The headline lines and every comparison row.
pub struct Headline {
    /// Printed lines.
    pub lines: Vec<String>,
    /// Per strength model (then `model-averaged`), damage model and horizon.
    pub rows: Vec<Row>,
}

/// The name of the averaged rows.
pub const AVERAGED: &str = "model-averaged";

/// The model-averaged (P(candidate worse), its standard error, tie fraction) from the strength
/// models' rows and their stacking weights: P̄ = Σ w P, se = (Σ w² se²)^½ (independent runs),
/// ties = Σ w ties.
pub fn averaged(weights: &[f64], rows: &[Row]) -> (f64, f64, f64) {
    let worse = weights.iter().zip(rows).map(|(w, r)| w * r.worse).sum();
    let se = weights.iter().zip(rows).map(|(w, r)| (w * r.se).powi(2)).sum::<f64>().sqrt();
    let ties = weights.iter().zip(rows).map(|(w, r)| w * r.ties).sum();
    (worse, se, ties)
}

/// One row of `averaging.csv`: domain, horizon, P(candidate worse), se, medians.
pub type AveragingRow = (String, f64, f64, f64, f64, f64);

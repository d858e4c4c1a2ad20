//! The main study's headline numbers: the comparison rows per strength model, damage model and
//! horizon, their model average, and the one way a probability with its Monte Carlo error is
//! written. Shared by the run (which computes them) and the summary (which states them).

use crate::error::{Error, Result};
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

/// The model-averaged (P(candidate worse), its standard error, tie fraction) from each strength
/// model's per-block fractions `blocks[M][b]` (equal-sized blocks), tie fractions and stacking
/// weights.
///
/// Every strength model is propagated with the same seed and the same sample points, block for
/// block, so the models' estimates are correlated and (Σ w² se²)^½ would understate the error
/// when they move together. The average is formed block by block, ȳ_b = Σ_M w_M y_Mb — the
/// blocks are independent replicates — and P̄ = mean ȳ_b with se = sd(ȳ_b)/√B, which carries
/// whatever correlation the models share. ties = Σ w ties. Models with different block counts
/// are refused (they cannot be paired).
pub fn averaged(weights: &[f64], blocks: &[Vec<f64>], ties: &[f64]) -> Result<(f64, f64, f64)> {
    let b = blocks.first().map_or(0, Vec::len);
    if blocks.iter().any(|v| v.len() != b) || b == 0 || weights.len() != blocks.len() || ties.len() != blocks.len() {
        return Err(Error::numerical("model averaging", format!("the strength models' propagations cannot be paired block by block (blocks per model: {:?})", blocks.iter().map(Vec::len).collect::<Vec<_>>())));
    }
    let per_block: Vec<f64> = (0..b).map(|i| weights.iter().zip(blocks).map(|(w, v)| w * v[i]).sum()).collect();
    let (worse, se) = super::propagate::mean_se(&per_block);
    Ok((worse, se, weights.iter().zip(ties).map(|(w, t)| w * t).sum()))
}

/// One row of `averaging.csv`: domain, horizon, P(candidate worse), se, medians.
pub type AveragingRow = (String, f64, f64, f64, f64, f64);

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    #[test]
    fn the_average_is_the_weighted_mean_of_the_blocks() {
        let (p, se, ties) = averaged(&[0.25, 0.75], &[vec![0.1, 0.3], vec![0.5, 0.7]], &[0.1, 0.3]).unwrap();
        assert!((p - 0.5).abs() < 1e-15 && (ties - 0.25).abs() < 1e-15, "{p} {ties}");
        // Block averages 0.4 and 0.6: sd 0.1414, se = sd/√2 = 0.1.
        assert!((se - 0.1).abs() < 1e-15, "{se}");
        assert!(averaged(&[0.5, 0.5], &[vec![0.1, 0.3], vec![0.5]], &[0.0, 0.0]).unwrap_err().to_string().contains("cannot be paired"));
    }

    /// The standard error against the spread of repeated runs: two models whose block estimates
    /// are correlated (ρ = 0.9, as the shared sample points make them), 4000 repetitions of
    /// 8 blocks each. The root mean square of the reported se must match the standard deviation
    /// of P̄ over the repetitions; (Σ w² se²)^½, which assumed independent runs, gave
    /// (0.5/0.95)^½ = 0.73 of it.
    #[test]
    fn the_standard_error_matches_the_spread_of_repeated_runs() {
        let (reps, blocks, rho, sd) = (4000, 8, 0.9, 0.02);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut z = || -> f64 { StandardNormal.sample(&mut rng) };
        let (mut means, mut se2) = (Vec::new(), 0.0);
        for _ in 0..reps {
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for _ in 0..blocks {
                let (z1, z2) = (z(), z());
                a.push(0.3 + sd * z1);
                b.push(0.6 + sd * (rho * z1 + (1.0 - rho * rho).sqrt() * z2));
            }
            let (p, se, _) = averaged(&[0.5, 0.5], &[a, b], &[0.0, 0.0]).unwrap();
            means.push(p);
            se2 += se * se / reps as f64;
        }
        let (_, spread) = crate::stats::mean_and_sd(&means);
        let ratio = se2.sqrt() / spread;
        // The ratio's own sampling error over 4000 repetitions is about 1.5 %.
        assert!((ratio - 1.0).abs() < 0.05, "rms se / spread of P̄ = {ratio:.3}");
    }
}

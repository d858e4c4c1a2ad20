//! The false-discovery guard's arithmetic (the loop in [`super::workflow`] computes the
//! likelihood ratios and their bootstrap; this module turns them into decisions): candidates
//! compared on the one-parameter scale, the family-wise maxima of the bootstrap replicates with
//! failed refits counted as exceeding, the critical value the decision uses, the share of
//! failed refits above which a candidate gets no verdict, and when a round's bootstrap may stop.
//!
//! **Sequential bootstrap** (Davidson & MacKinnon 2000, "Bootstrap tests: how many
//! bootstraps?", Econometric Reviews 19: 55–68, their pretest procedure). A round draws its
//! replicates in stages — 99, 199, 499, 999, 1999, 4999, 9999, up to the study's `bootstrap` —
//! and stops at the first stage where every decision the round makes is settled: each count c of
//! B replicates whose decision compares c/B with a level π₀ (a p-value with α, a failure share
//! with [`MAX_FAILED_SHARE`]) is settled when the exact binomial test of π = π₀ rejects at
//! β = [`PRETEST_LEVEL`] in either direction, P(C ≤ c) < β/2 or P(C ≥ c) < β/2 with
//! C ~ Bin(B, π₀). A candidate with no replicate reaching its Λ is settled at 199 (0.95¹⁹⁹ =
//! 3.7·10⁻⁵), one far from α — most candidates of a round that names nothing — at 99; a decision
//! near α draws them all. Every replicate keeps its own random stream, so the first B replicates
//! are the same whether the round stops there or draws more, and the decisions equal those of
//! drawing every replicate except where a count sits within the pretest's error of α.

use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};

/// The likelihood ratio Λ of a candidate with `df` extra parameters on the one-parameter scale:
/// the χ²₁ value with the same upper-tail probability under Wilks' approximation (Λ itself
/// for df = 1). The family-wise guard compares candidates on this scale, so a categorical
/// factor with many levels does not dominate the maximum by its degrees of freedom alone; the
/// calibration stays the bootstrap's.
pub fn one_df_scale(lr: f64, df: usize) -> f64 {
    if df <= 1 || !lr.is_finite() {
        return lr;
    }
    let p = crate::stats::chi2_upper_tail(lr, df as f64);
    if !(p > 1e-300) {
        return lr;
    }
    let z = Normal::standard().inverse_cdf(0.5 * p);
    z * z
}

/// The inverse of [`one_df_scale`]: the Λ of a df-parameter candidate at a one-parameter value.
pub fn from_one_df_scale(l1: f64, df: usize) -> f64 {
    if df <= 1 || !l1.is_finite() {
        return l1;
    }
    let p = crate::stats::chi2_upper_tail(l1, 1.0);
    ChiSquared::new(df as f64).map_or(f64::NAN, |c| c.inverse_cdf(1.0 - p))
}

/// Largest share of a round's bootstrap replicates whose refits may fail for a candidate to
/// get a verdict: above it the candidate is neither named nor rejected (its failures, counted
/// as exceeding, would make any p-value an upper bound too loose to read).
pub const MAX_FAILED_SHARE: f64 = 0.10;

/// Whether a candidate with `failures` failed refits among `replicates` gets a verdict
/// ([`MAX_FAILED_SHARE`]).
pub fn decided(failures: usize, replicates: usize) -> bool {
    failures as f64 <= MAX_FAILED_SHARE * replicates as f64
}

/// The pretest's level β ([module docs](self)): a count is settled when the binomial test of its
/// level rejects at β.
pub const PRETEST_LEVEL: f64 = 0.001;

/// The stages at which a round's bootstrap looks whether its decisions are settled, ending at
/// `most` (every replicate); `[most]` alone when the bootstrap is not `sequential`.
pub fn stages(most: usize, sequential: bool) -> Vec<usize> {
    let mut v: Vec<usize> = if sequential { [99, 199, 499, 999, 1999, 4999, 9999].into_iter().filter(|&b| b < most).collect() } else { Vec::new() };
    v.push(most);
    v
}

/// Whether `count` of `replicates`, judged against the level `level` (α for a p-value, the
/// failure share for a verdict), is settled: the exact binomial test of π = level rejects at
/// [`PRETEST_LEVEL`] in either direction.
pub fn settled(count: usize, replicates: usize, level: f64) -> bool {
    use statrs::distribution::{Binomial, DiscreteCDF};
    let Ok(bin) = Binomial::new(level, replicates as u64) else { return false };
    let c = count as u64;
    let below = bin.cdf(c);
    let above = if c == 0 { 1.0 } else { bin.sf(c - 1) };
    below < PRETEST_LEVEL / 2.0 || above < PRETEST_LEVEL / 2.0
}

/// Per bootstrap replicate, max_c Λ*_c on the one-parameter scale (candidate c with `df[c]`
/// extra parameters): a failed refit (+∞) dominates, so it counts as exceeding every observed
/// Λ; a candidate not fitted on the data (NaN throughout) is left out.
pub fn family_maxima(lstar: &[&[f64]], df: &[usize]) -> Vec<f64> {
    lstar.iter().map(|r| r.iter().zip(df).map(|(v, d)| one_df_scale(*v, *d)).filter(|v| !v.is_nan()).fold(0.0, f64::max)).collect()
}

/// The critical value of the guard: the order statistic of the bootstrap maxima `max_star`
/// that the decision p = (1 + #{max* ≥ Λ})/(B + 1) < α uses, so that p < α exactly when
/// Λ > critical. With m the largest count for which (1 + m)/(B + 1) < α, it is the
/// (m + 1)-th largest maximum; +∞ when no count passes (B too small for α), −∞ when every
/// count does.
pub fn critical_value(max_star: &[f64], alpha: f64) -> f64 {
    let b = max_star.len();
    let passes = |count: usize| ((1 + count) as f64) / (b as f64 + 1.0) < alpha;
    let Some(m) = (0..=b).take_while(|&c| passes(c)).last() else { return f64::INFINITY };
    if m >= b {
        return f64::NEG_INFINITY;
    }
    let mut sorted = max_star.to_vec();
    sorted.sort_by(|a, b| b.total_cmp(a));
    sorted[m]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The family-wise p-value as the loop computes it.
    fn p_family(max_star: &[f64], l1: f64) -> f64 {
        (1 + max_star.iter().filter(|&&s| s >= l1).count()) as f64 / (max_star.len() as f64 + 1.0)
    }

    #[test]
    fn the_critical_value_is_the_order_statistic_the_decision_uses() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for (b, alpha) in [(199, 0.05), (99, 0.05), (499, 0.05), (200, 0.05), (999, 0.01), (57, 0.1)] {
            let max_star: Vec<f64> = (0..b).map(|_| (rng.random::<f64>() * 10.0).round() / 2.0).collect();
            let c = critical_value(&max_star, alpha);
            // Every candidate Λ, ties with the maxima included.
            for l in (0..=24).map(|k| k as f64 * 0.25) {
                assert_eq!(p_family(&max_star, l) < alpha, l > c, "B {b}, α {alpha}: Λ {l}, critical {c}, p {}", p_family(&max_star, l));
            }
        }
        // B = 199, α = 0.05: the 9th largest maximum ((1 + 8)/200 < 0.05 ≤ (1 + 9)/200).
        let max_star: Vec<f64> = (1..=199).map(f64::from).collect();
        assert_eq!(critical_value(&max_star, 0.05), 191.0);
        // Too few replicates for α: nothing passes.
        assert_eq!(critical_value(&[1.0; 19], 0.05), f64::INFINITY);
    }

    #[test]
    fn a_count_is_settled_only_far_from_its_level() {
        // No replicate above Λ: P(C = 0) = 0.95^B is 6.2e-3 at 99, 3.7e-5 at 199 (β/2 = 5e-4).
        assert!(!settled(0, 99, 0.05) && settled(0, 199, 0.05));
        // A p far above α settles at once: P(C ≥ 30 | 99, 0.05) = 4.6e-15; one at α never does.
        assert!(settled(30, 99, 0.05) && !settled(5, 99, 0.05) && !settled(25, 499, 0.05));
        // The edges: at B = 199, P(C ≤ 1) = 4.2e-4 < 5e-4 ≤ P(C ≤ 2) = 2.4e-3; P(C ≥ 22) =
        // 4.5e-4 < 5e-4 ≤ P(C ≥ 21) = 1.1e-3 (exact sums of the binomial terms, by hand).
        assert!(settled(1, 199, 0.05) && !settled(2, 199, 0.05));
        assert!(settled(22, 199, 0.05) && !settled(21, 199, 0.05));
        // Failure shares: none of 99 is settled against 10 % (0.9^99 = 3e-5).
        assert!(settled(0, 99, MAX_FAILED_SHARE));
        assert_eq!(stages(499, true), vec![99, 199, 499]);
        assert_eq!(stages(200, true), vec![99, 199, 200]);
        assert_eq!(stages(99, true), vec![99]);
        assert_eq!(stages(499, false), vec![499]);
    }

    /// A replicate whose candidate refit failed counts as exceeding: with 15 of 199 failed and
    /// the observed Λ above every computed Λ*, p = 16/200 — above α, not the 1/200 of leaving
    /// them out; 15 of 199 still allow a verdict (under 10 %), 20 do not.
    #[test]
    fn failed_refits_count_as_exceeding_and_too_many_leave_no_verdict() {
        let lstar: Vec<Vec<f64>> = (0..199).map(|r| vec![if r % 13 == 0 && r < 195 { f64::INFINITY } else { 1.0 + (r % 7) as f64 }, 0.5]).collect();
        let failed = lstar.iter().filter(|r| r[0].is_infinite()).count();
        assert_eq!(failed, 15);
        let rows: Vec<&[f64]> = lstar.iter().map(|r| r.as_slice()).collect();
        let max_star = family_maxima(&rows, &[1, 1]);
        assert_eq!(p_family(&max_star, 50.0), 16.0 / 200.0);
        assert!(critical_value(&max_star, 0.05) > 50.0);
        assert!(decided(failed, 199) && decided(19, 199) && !decided(20, 199));
        // A candidate never fitted on the data (NaN) does not enter the maxima.
        let nan: Vec<Vec<f64>> = (0..199).map(|_| vec![f64::NAN, 2.0]).collect();
        assert!(family_maxima(&nan.iter().map(|r| r.as_slice()).collect::<Vec<_>>(), &[1, 1]).iter().all(|&m| m == 2.0));
    }
}

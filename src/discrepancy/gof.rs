//! Diagnosis of a fitted Weibull strength model (issue 7, step 1 "Diagnose"): quantile
//! residuals, Anderson–Darling and Kolmogorov–Smirnov statistics with p-values calibrated by a
//! parametric bootstrap (the parameters were fitted, so the textbook tables for a fully
//! specified law would be far too lenient), and tests of residual structure against a covariate.
//!
//! * Quantile residuals: r_i = Φ⁻¹(F̂(x_i)) with F̂ the fitted Weibull CDF. For a continuous law
//!   the randomised quantile residuals of Dunn & Smyth (1996) reduce to these; under the model
//!   they are i.i.d. N(0, 1) (up to the fitting).
//! * AD = −n − (1/n) Σ (2i − 1)[ln u_(i) + ln(1 − u_(n+1−i))], KS = max_i max(i/n − u_(i),
//!   u_(i) − (i − 1)/n), with u = F̂(x) sorted.
//! * Bootstrap: B samples of size n from the fitted law, each refitted by MLE and its statistics
//!   recomputed; p = (1 + #{T* ≥ T})/(B + 1). Seeded; one stream per replicate, so the result
//!   does not depend on the thread count.
//! * Covariate structure: Spearman's rank correlation of the residuals with a covariate, its
//!   p-value by a seeded permutation test (exact for ties and small n).
//!
//! Verified in `tests/verification/discrepancy.rs`: the bootstrap p-value is uniform under the
//! model (false-positive rate at 5 % within binomial error over 200 data sets), the 5 % AD
//! critical value matches Stephens' table for the Weibull with estimated parameters, and a
//! hidden diameter effect is found by the covariate test.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal};

use crate::error::{Error, Result};
use crate::weibull::{Weibull, fit_mle};

/// Quantile residuals Φ⁻¹(F(x_i)) of `data` under `law` (clamped to ±8.3 at the extremes).
pub fn quantile_residuals(data: &[f64], law: &Weibull) -> Vec<f64> {
    normal_scores(data.iter().map(|&x| law.cdf(x)))
}

/// Anderson–Darling and Kolmogorov–Smirnov statistics of `data` under `law`.
pub fn ad_ks(data: &[f64], law: &Weibull) -> (f64, f64) {
    ad_ks_of_u(data.iter().map(|&x| law.cdf(x)).collect())
}

/// Anderson–Darling and Kolmogorov–Smirnov statistics of probability-integral transforms
/// u_i = F_i(x_i) (each particle may have its own fitted law).
pub fn ad_ks_of_u(mut u: Vec<f64>) -> (f64, f64) {
    for v in &mut u {
        *v = v.clamp(1e-300, 1.0 - 1e-16);
    }
    u.sort_by(f64::total_cmp);
    let n = u.len() as f64;
    let mut s = 0.0;
    let mut ks = 0.0f64;
    for (i, &ui) in u.iter().enumerate() {
        let k = i as f64 + 1.0;
        s += (2.0 * k - 1.0) * (ui.ln() + (1.0 - u[u.len() - 1 - i]).ln());
        ks = ks.max(k / n - ui).max(ui - (k - 1.0) / n);
    }
    (-n - s / n, ks)
}

/// Standard-normal quantiles of probabilities (clamped to ±8.3 at the extremes).
pub fn normal_scores(u: impl Iterator<Item = f64>) -> Vec<f64> {
    let n = Normal::new(0.0, 1.0).unwrap_or_else(|_| unreachable!("N(0,1) is valid"));
    u.map(|p| n.inverse_cdf(p.clamp(1e-16, 1.0 - 1e-16))).collect()
}

/// Goodness of fit of a Weibull MLE with bootstrap-calibrated p-values.
#[derive(Debug, Clone, PartialEq)]
pub struct GoodnessOfFit {
    /// The fitted law.
    pub fit: Weibull,
    /// Anderson–Darling statistic.
    pub ad: f64,
    /// Kolmogorov–Smirnov statistic.
    pub ks: f64,
    /// Bootstrap p-value of AD.
    pub p_ad: f64,
    /// Bootstrap p-value of KS.
    pub p_ks: f64,
    /// Bootstrap replicates used.
    pub replicates: usize,
}

/// Fits `data` by MLE and calibrates AD and KS by `b` parametric-bootstrap refits (seeded).
pub fn weibull_gof(data: &[f64], b: usize, seed: u64) -> Result<GoodnessOfFit> {
    if data.len() < 3 || b < 19 {
        return Err(Error::config("<discrepancy>", "bootstrap", format!("needs ≥ 3 values and ≥ 19 replicates, got {} and {b}", data.len())));
    }
    let fit = fit_mle(data)?.mle;
    let (ad, ks) = ad_ks(data, &fit);
    let n = data.len();
    let stats: Vec<Option<(f64, f64)>> = (0..b)
        .into_par_iter()
        .map(|r| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(r as u64 + 1);
            let sample: Vec<f64> = (0..n).map(|_| fit.sample(&mut rng)).collect();
            fit_mle(&sample).ok().map(|f| ad_ks(&sample, &f.mle))
        })
        .collect();
    let ok: Vec<(f64, f64)> = stats.into_iter().flatten().collect();
    if ok.len() < b / 2 {
        return Err(Error::numerical("goodness of fit", format!("only {} of {b} bootstrap refits converged", ok.len())));
    }
    let p = |t: f64, f: fn(&(f64, f64)) -> f64| (1 + ok.iter().filter(|s| f(s) >= t).count()) as f64 / (ok.len() + 1) as f64;
    Ok(GoodnessOfFit { fit, ad, ks, p_ad: p(ad, |s| s.0), p_ks: p(ks, |s| s.1), replicates: ok.len() })
}

/// Spearman's rank correlation of `x` and `y`.
pub fn spearman(x: &[f64], y: &[f64]) -> f64 {
    crate::stats::pearson(&crate::stats::ranks(x), &crate::stats::ranks(y)).0
}

/// Spearman's ρ of residuals against a covariate and its two-sided permutation p-value
/// (`permutations` shuffles, seeded).
pub fn covariate_trend(residuals: &[f64], covariate: &[f64], permutations: usize, seed: u64) -> Result<(f64, f64)> {
    if residuals.len() != covariate.len() || residuals.len() < 4 {
        return Err(Error::config("<discrepancy>", "covariate", format!("needs ≥ 4 paired values, got {} and {}", residuals.len(), covariate.len())));
    }
    if let Some(v) = covariate.iter().find(|v| !v.is_finite()) {
        return Err(Error::numerical("covariate trend", format!("a covariate value is {v}")));
    }
    let (rr, rc) = (crate::stats::ranks(residuals), crate::stats::ranks(covariate));
    let rho = crate::stats::pearson(&rr, &rc).0;
    let hits = permutation_hits(&rc, permutations, seed, |p| crate::stats::pearson(&rr, p).0.abs() >= rho.abs() - 1e-12);
    Ok((rho, (1 + hits) as f64 / (permutations + 1) as f64))
}

/// One covariate's residual trend and where the residuals depart most.
#[derive(Debug, Clone, PartialEq)]
pub struct CovariateFinding {
    /// Covariate name (`diameter_m`, `roundness`, `sphericity`, `temperature_c`, or a
    /// strength file's factor).
    pub covariate: String,
    /// Spearman ρ of the quantile residuals against it (NaN for a categorical factor).
    pub rho: f64,
    /// Permutation p-value.
    pub p: f64,
    /// Covariate range of the tertile whose mean residual is farthest from 0, and that mean
    /// (categorical: NaN, NaN and the mean residual of `worst_level`).
    pub worst_range: (f64, f64, f64),
    /// The statistic's contribution to the gap: n ρ² (numeric, ≈ χ²₁ when nothing is missing)
    /// or the Kruskal–Wallis H of the residuals by level (categorical, ≈ χ²_(L−1)).
    pub statistic: f64,
    /// Its degrees of freedom under no trend: 1, or L − 1.
    pub df: usize,
    /// Categorical: the level whose mean residual is farthest from 0 (for a scatter finding:
    /// whose mean absolute deviation from its median is farthest from the overall one).
    pub worst_level: Option<String>,
    /// A categorical factor's scatter finding: the statistic is the Kruskal–Wallis H of the
    /// absolute deviations from the level medians ([`scatter_kruskal_wallis`]), `worst_range`
    /// (NaN, mean absolute deviation over the levels compared, that of `worst_level`).
    pub scatter: bool,
}

/// Kruskal–Wallis H of `r` grouped by `levels`: H = 12/(n(n+1)) Σ_g n_g (R̄_g − (n+1)/2)² on the
/// ranks R of r (continuous residuals: no tie correction). ≈ χ²_(L−1) when the groups do not
/// differ (Kruskal & Wallis 1952).
pub fn kruskal_wallis(r: &[f64], levels: &[usize], groups: usize) -> f64 {
    let n = r.len() as f64;
    let ranks = crate::stats::ranks(r);
    let mut sum = vec![0.0; groups];
    let mut count = vec![0usize; groups];
    for (i, &g) in levels.iter().enumerate() {
        sum[g] += ranks[i];
        count[g] += 1;
    }
    let centre = 0.5 * (n + 1.0);
    12.0 / (n * (n + 1.0)) * (0..groups).filter(|&g| count[g] > 0).map(|g| count[g] as f64 * (sum[g] / count[g] as f64 - centre).powi(2)).sum::<f64>()
}

/// Each specimen's level as an index into the distinct levels (in order of appearance), and
/// those levels.
pub fn level_indices(values: &[String]) -> (Vec<usize>, Vec<&String>) {
    let mut names: Vec<&String> = Vec::new();
    let idx = values
        .iter()
        .map(|v| match names.iter().position(|n| *n == v) {
            Some(j) => j,
            None => {
                names.push(v);
                names.len() - 1
            }
        })
        .collect();
    (idx, names)
}

/// Kruskal–Wallis H of `r` grouped by the levels named in `values`.
pub fn kruskal_wallis_by(r: &[f64], values: &[String]) -> f64 {
    let (idx, names) = level_indices(values);
    kruskal_wallis(r, &idx, names.len())
}

/// |r_i − median of r over i's level|: each specimen's distance from its level's centre, so that
/// levels are compared by scatter alone.
pub fn deviations_from_level_medians(r: &[f64], levels: &[usize], groups: usize) -> Vec<f64> {
    let medians: Vec<f64> = (0..groups)
        .map(|g| {
            let v: Vec<f64> = levels.iter().zip(r).filter(|(l, _)| **l == g).map(|(_, x)| *x).collect();
            if v.is_empty() { 0.0 } else { crate::stats::median(&v) }
        })
        .collect();
    r.iter().zip(levels).map(|(x, &l)| (x - medians[l]).abs()).collect()
}

/// Kruskal–Wallis H of the absolute deviations from the level medians: a rank test of equal
/// scatter across levels (Conover, Johnson & Johnson 1981, the median-centred rank tests of the
/// Fligner–Killeen family), ≈ χ²_(L−1) when the levels scatter alike. A level with its own
/// Weibull modulus shows here, not in the location statistic.
pub fn scatter_kruskal_wallis(r: &[f64], levels: &[usize], groups: usize) -> f64 {
    kruskal_wallis(&deviations_from_level_medians(r, levels, groups), levels, groups)
}

/// Fewest specimens a level needs to enter the scatter statistic (one or two specimens have no
/// scatter of their own: one sits on its median, two at equal distances from it).
pub const MIN_FOR_SCATTER: usize = 3;

/// The specimens of the levels with at least [`MIN_FOR_SCATTER`]: their residuals, their level
/// renumbered 0…, and each kept level's original index.
fn scatter_levels(r: &[f64], idx: &[usize], groups: usize) -> (Vec<f64>, Vec<usize>, Vec<usize>) {
    let kept: Vec<usize> = (0..groups).filter(|&g| idx.iter().filter(|&&l| l == g).count() >= MIN_FOR_SCATTER).collect();
    let (rs, ls) = r.iter().zip(idx).filter_map(|(x, l)| kept.iter().position(|k| k == l).map(|p| (*x, p))).unzip();
    (rs, ls, kept)
}

/// [`scatter_kruskal_wallis`] of `r` grouped by the labels `values`, over the levels with at
/// least [`MIN_FOR_SCATTER`] specimens (0 when fewer than two such levels).
pub fn scatter_by(r: &[f64], values: &[String]) -> f64 {
    let (idx, names) = level_indices(values);
    let (rs, ls, kept) = scatter_levels(r, &idx, names.len());
    if kept.len() < 2 { 0.0 } else { scatter_kruskal_wallis(&rs, &ls, kept.len()) }
}

/// How many of `permutations` seeded shuffles of `idx` (covariate ranks or level labels;
/// Fisher–Yates, shuffle j on its own ChaCha8 stream of `seed`) give a statistic at least the
/// observed (`at_least`).
fn permutation_hits<T: Clone + Send + Sync>(idx: &[T], permutations: usize, seed: u64, at_least: impl Fn(&[T]) -> bool + Sync) -> usize {
    (0..permutations)
        .into_par_iter()
        .map(|j| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(j as u64 + 1);
            let mut p = idx.to_vec();
            for i in (1..p.len()).rev() {
                p.swap(i, rng.random_range(0..=i));
            }
            usize::from(at_least(&p))
        })
        .sum()
}

/// Residual differences between the levels of every categorical column given (name, each
/// specimen's level), two findings per column: the location — Kruskal–Wallis H with its
/// permutation p-value (`permutations` shuffles of the levels, seeded) and the level whose mean
/// residual is farthest from 0 — and the scatter ([`scatter_kruskal_wallis`] over the levels of
/// [`MIN_FOR_SCATTER`] or more specimens, its own permutations, the level whose mean absolute
/// deviation is farthest from the overall one). A column with one level is skipped with its
/// reason, a scatter with fewer than two such levels likewise.
pub fn level_findings(r: &[f64], columns: &[(String, Vec<String>)], permutations: usize, seed: u64) -> (Vec<CovariateFinding>, Vec<String>) {
    let mut found = Vec::new();
    let mut skipped = Vec::new();
    for (k, (name, values)) in columns.iter().enumerate() {
        let (idx, names) = level_indices(values);
        if names.len() < 2 || values.len() != r.len() {
            skipped.push(format!("{name}: one level only"));
            continue;
        }
        let g = names.len();
        let h = kruskal_wallis(r, &idx, g);
        let hits = permutation_hits(&idx, permutations, seed ^ (k as u64 + 101), |p| kruskal_wallis(r, p, g) >= h - 1e-12);
        let means: Vec<(f64, usize)> = (0..g).map(|l| {
            let v: Vec<f64> = idx.iter().zip(r).filter(|(i, _)| **i == l).map(|(_, x)| *x).collect();
            (v.iter().sum::<f64>() / v.len() as f64, l)
        }).collect();
        let worst = means.iter().fold((0.0f64, 0usize), |b, c| if c.0.abs() > b.0.abs() { *c } else { b });
        found.push(CovariateFinding {
            covariate: name.clone(),
            rho: f64::NAN,
            p: (1 + hits) as f64 / (permutations + 1) as f64,
            worst_range: (f64::NAN, f64::NAN, worst.0),
            statistic: h,
            df: g - 1,
            worst_level: Some(names[worst.1].clone()),
            scatter: false,
        });
        // The scatter: the same test on the absolute deviations from the level medians, over the
        // levels with enough specimens, its own permutation stream.
        let (rs, ls, kept) = scatter_levels(r, &idx, g);
        if kept.len() < 2 {
            skipped.push(format!("{name}: scatter not compared (fewer than two levels of {MIN_FOR_SCATTER} or more specimens)"));
            continue;
        }
        let (r, idx, g) = (&rs[..], ls, kept.len());
        let hs = scatter_kruskal_wallis(r, &idx, g);
        let hits = permutation_hits(&idx, permutations, seed ^ (k as u64 + 0x5CA7), |p| scatter_kruskal_wallis(r, p, g) >= hs - 1e-12);
        let dev = deviations_from_level_medians(r, &idx, g);
        let overall = dev.iter().sum::<f64>() / dev.len() as f64;
        let spread: Vec<(f64, usize)> = (0..g)
            .map(|l| {
                let v: Vec<f64> = idx.iter().zip(&dev).filter(|(i, _)| **i == l).map(|(_, x)| *x).collect();
                (v.iter().sum::<f64>() / v.len() as f64, l)
            })
            .collect();
        let worst = spread.iter().fold((overall, 0usize), |b, c| if (c.0 - overall).abs() > (b.0 - overall).abs() { *c } else { b });
        found.push(CovariateFinding {
            covariate: name.clone(),
            rho: f64::NAN,
            p: (1 + hits) as f64 / (permutations + 1) as f64,
            worst_range: (f64::NAN, overall, worst.0),
            statistic: hs,
            df: g - 1,
            worst_level: Some(names[kept[worst.1]].clone()),
            scatter: true,
        });
    }
    (found, skipped)
}

/// Step 1 on a strength sample with covariates: the goodness of fit of the Weibull MLE and the
/// residual trend against every covariate given (name, values; a covariate constant over the
/// sample or shorter than the data is skipped with its reason). Findings are sorted by p.
pub fn diagnose(strength: &[f64], covariates: &[(&str, Vec<f64>)], bootstrap: usize, permutations: usize, seed: u64) -> Result<(GoodnessOfFit, Vec<CovariateFinding>, Vec<String>)> {
    let gof = weibull_gof(strength, bootstrap, seed)?;
    let r = quantile_residuals(strength, &gof.fit);
    let (found, skipped) = covariate_findings(&r, covariates, permutations, seed)?;
    Ok((gof, found, skipped))
}

/// Residual trend against every covariate given (name, values; a covariate constant over the
/// sample or of the wrong length is skipped with its reason), sorted by p.
pub fn covariate_findings(r: &[f64], covariates: &[(&str, Vec<f64>)], permutations: usize, seed: u64) -> Result<(Vec<CovariateFinding>, Vec<String>)> {
    let mut found = Vec::new();
    let mut skipped = Vec::new();
    for (k, (name, x)) in covariates.iter().enumerate() {
        if x.len() != r.len() {
            skipped.push(format!("{name}: {} values for {} particles", x.len(), r.len()));
            continue;
        }
        if x.iter().all(|v| *v == x[0]) {
            skipped.push(format!("{name}: constant over the sample"));
            continue;
        }
        let (rho, p) = covariate_trend(r, x, permutations, seed ^ (k as u64 + 1))?;
        let mut idx: Vec<usize> = (0..x.len()).collect();
        idx.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
        // Tertiles of the covariate — or, where it takes at most six values (test temperatures,
        // gauge lengths), one group per value, so no group straddles two of them and its range
        // is not the whole data's; the group whose mean residual is farthest from 0.
        let mut distinct: Vec<f64> = idx.iter().map(|&i| x[i]).collect();
        distinct.dedup();
        let groups: Vec<&[usize]> = if distinct.len() <= 6 { idx.chunk_by(|&a, &b| x[a] == x[b]).collect() } else { idx.chunks(idx.len().div_ceil(3)).collect() };
        let worst = groups
            .into_iter()
            .map(|g| (x[g[0]], x[g[g.len() - 1]], g.iter().map(|&i| r[i]).sum::<f64>() / g.len() as f64))
            .fold((f64::NAN, f64::NAN, 0.0f64), |b, c| if c.2.abs() > b.2.abs() { c } else { b });
        found.push(CovariateFinding { covariate: name.to_string(), rho, p, worst_range: worst, statistic: x.len() as f64 * rho * rho, df: 1, worst_level: None, scatter: false });
    }
    found.sort_by(|a, b| a.p.total_cmp(&b.p));
    Ok((found, skipped))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A covariate with two values (tests at 20 and 800 °C, 35 and 10 particles): the group
    /// that departs is one temperature, not a tertile spanning both (it used to read "the
    /// residuals depart most for 20–800").
    #[test]
    fn a_covariate_with_few_values_departs_at_one_of_them() {
        let t: Vec<f64> = (0..45).map(|i| if i < 35 { 20.0 } else { 800.0 }).collect();
        let r: Vec<f64> = (0..45).map(|i| if i < 35 { 0.3 + 0.01 * (i % 5) as f64 } else { -0.9 + 0.01 * (i % 3) as f64 }).collect();
        let (f, _) = covariate_findings(&r, &[("temperature_c", t)], 99, 1).unwrap();
        assert_eq!((f[0].worst_range.0, f[0].worst_range.1), (800.0, 800.0), "{:?}", f[0].worst_range);
        // Many values: tertiles still.
        let d: Vec<f64> = (0..45).map(f64::from).collect();
        let (f, _) = covariate_findings(&r, &[("diameter_m", d)], 99, 1).unwrap();
        assert_eq!((f[0].worst_range.0, f[0].worst_range.1), (30.0, 44.0), "{:?}", f[0].worst_range);
        assert!(f[0].worst_range.2 < -0.4, "{:?}", f[0].worst_range);
    }

    #[test]
    fn the_scatter_statistic_sees_spread_and_not_location() {
        // Three levels of 40 evenly spread residuals: equal spread with shifted centres, then one
        // level twice as wide with equal centres.
        let base: Vec<f64> = (0..40).map(|i| (i as f64 - 19.5) / 10.0).collect();
        let levels: Vec<usize> = (0..120).map(|i| i / 40).collect();
        let shifted: Vec<f64> = (0..120).map(|i| base[i % 40] + [0.0, 2.0, -2.0][i / 40]).collect();
        let wide: Vec<f64> = (0..120).map(|i| base[i % 40] * if i / 40 == 2 { 2.0 } else { 1.0 }).collect();
        assert!(scatter_kruskal_wallis(&shifted, &levels, 3) < 0.5, "equal spread (to rounding): no scatter difference");
        assert!(kruskal_wallis(&shifted, &levels, 3) > 30.0, "{}", kruskal_wallis(&shifted, &levels, 3));
        assert!(scatter_kruskal_wallis(&wide, &levels, 3) > 15.0, "{}", scatter_kruskal_wallis(&wide, &levels, 3));
        assert!(kruskal_wallis(&wide, &levels, 3) < 0.5);
        let labels: Vec<String> = levels.iter().map(|l| ["a", "b", "c"][*l].to_string()).collect();
        let (f, _) = level_findings(&wide, &[("g".into(), labels)], 199, 3);
        let s = f.iter().find(|f| f.scatter).unwrap();
        assert_eq!(s.worst_level.as_deref(), Some("c"));
        assert!(s.p < 0.01 && s.df == 2 && s.worst_range.2 > s.worst_range.1);
    }
}

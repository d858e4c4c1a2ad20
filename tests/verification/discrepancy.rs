//! Diagnosis of Weibull fits (`discrepancy::gof`): the Anderson–Darling 5 % critical value for a
//! Weibull with estimated parameters against Stephens' table (AD·(1 + 0.2/√n) = 0.757,
//! D'Agostino & Stephens 1986, Table 4.17), bootstrap p-values that are uniform under the model
//! (false positives at 5 % within binomial error), power against a log-normal, and the residual
//! trend test finding a hidden size effect and none where there is none.

use partlife::discrepancy::gof::{ad_ks, covariate_trend, quantile_residuals, weibull_gof};
use partlife::weibull::{Weibull, fit_mle, sorted_quantile};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, LogNormal};

#[test]
fn anderson_darling_critical_value_with_estimated_parameters() {
    let law = Weibull::new(8.0, 300e6).unwrap();
    let n = 50;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut stats: Vec<f64> = (0..4000)
        .map(|_| {
            let x: Vec<f64> = (0..n).map(|_| law.sample(&mut rng)).collect();
            let f = fit_mle(&x).unwrap().mle;
            ad_ks(&x, &f).0 * (1.0 + 0.2 / (n as f64).sqrt())
        })
        .collect();
    stats.sort_by(f64::total_cmp);
    let q95 = sorted_quantile(&stats, 0.95);
    assert!((q95 - 0.757).abs() < 0.04, "95 % point of AD* = {q95} (Stephens: 0.757)");
}

#[test]
fn bootstrap_p_values_are_calibrated_under_the_model() {
    let law = Weibull::new(7.0, 800e6).unwrap();
    let (mut rej_ad, mut rej_ks) = (0, 0);
    let sets = 200;
    for s in 0..sets {
        let mut rng = ChaCha8Rng::seed_from_u64(1000 + s);
        let x: Vec<f64> = (0..40).map(|_| law.sample(&mut rng)).collect();
        let g = weibull_gof(&x, 199, s).unwrap();
        rej_ad += usize::from(g.p_ad <= 0.05);
        rej_ks += usize::from(g.p_ks <= 0.05);
    }
    // 200 Bernoulli(0.05): sd 0.015; accept 0.01–0.10.
    for (name, r) in [("AD", rej_ad), ("KS", rej_ks)] {
        let rate = r as f64 / sets as f64;
        assert!((0.01..=0.10).contains(&rate), "{name}: false-positive rate {rate}");
    }
}

#[test]
fn a_log_normal_is_detected_and_residuals_are_normal_under_the_model() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let ln = LogNormal::new(0.0, 0.35).unwrap();
    let x: Vec<f64> = (0..300).map(|_| 800e6 * ln.sample(&mut rng)).collect();
    let g = weibull_gof(&x, 199, 1).unwrap();
    assert!(g.p_ad < 0.05, "log-normal data fitted as Weibull: p_AD = {}", g.p_ad);
    let law = Weibull::new(9.0, 850e6).unwrap();
    let y: Vec<f64> = (0..2000).map(|_| law.sample(&mut rng)).collect();
    let r = quantile_residuals(&y, &fit_mle(&y).unwrap().mle);
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let var = r.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (r.len() as f64 - 1.0);
    assert!(mean.abs() < 0.06 && (var - 1.0).abs() < 0.08, "residual mean {mean}, variance {var}");
}

/// Strength scale ∝ d^(−3/m) (volume flaws) over d = 0.6–1.2 mm, m = 8, 80 particles: the
/// residuals of a size-blind fit fall with d. Over 100 data sets each, the permutation test at
/// 5 % finds the effect in ≥ 80 % and a trend where there is none in 1–10 % (binomial sd 2 %).
#[test]
fn residual_trend_finds_a_hidden_size_effect() {
    let m = 8.0;
    let fit = |x: &[f64]| fit_mle(x).unwrap().mle;
    let (mut found, mut false_pos, mut negative) = (0, 0, 0);
    let sets = 100;
    for s in 0..sets {
        let mut rng = ChaCha8Rng::seed_from_u64(500 + s);
        let d: Vec<f64> = (0..80).map(|_| 0.6e-3 + 0.6e-3 * rng.random::<f64>()).collect();
        let with: Vec<f64> = d.iter().map(|&di| Weibull::new(m, 800e6 * (di / 0.9e-3).powf(-3.0 / m)).unwrap().sample(&mut rng)).collect();
        let without: Vec<f64> = d.iter().map(|_| Weibull::new(m, 800e6).unwrap().sample(&mut rng)).collect();
        let (rho, p) = covariate_trend(&quantile_residuals(&with, &fit(&with)), &d, 400, s).unwrap();
        found += usize::from(p <= 0.05);
        negative += usize::from(rho < 0.0);
        let (_, p0) = covariate_trend(&quantile_residuals(&without, &fit(&without)), &d, 400, s).unwrap();
        false_pos += usize::from(p0 <= 0.05);
    }
    eprintln!("size effect found in {found}/{sets} (ρ < 0 in {negative}); false positives {false_pos}/{sets}");
    assert!(found >= 80 && negative >= 95, "power {found}/{sets}, ρ < 0 in {negative}");
    assert!((1..=10).contains(&false_pos), "false positives {false_pos}/{sets}");
    assert!(covariate_trend(&[1.0, 2.0, 3.0, 4.0], &[1.0, f64::NAN, 2.0, 3.0], 10, 1).is_err());
}

/// `diagnose` ranks the covariate that carries a hidden roundness effect first, locates the
/// disagreement at an end of its range (not the middle tertile), and skips a constant covariate
/// with its reason.
#[test]
fn diagnose_names_the_covariate_and_the_range() {
    use partlife::discrepancy::gof::diagnose;
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let n = 120;
    let d: Vec<f64> = (0..n).map(|_| 0.6e-3 + 0.6e-3 * rng.random::<f64>()).collect();
    let round: Vec<f64> = (0..n).map(|_| 0.6 + 0.35 * rng.random::<f64>()).collect();
    // A crush reduced as a sphere of radius R when the contact curvature is ρR: the force at
    // break scales as ρ², so the apparent σ̄ ∝ (F/R²)^(1/3) scales as ρ^(2/3).
    let s: Vec<f64> = round.iter().map(|&r| Weibull::new(9.0, 800e6 * (r / 0.8f64).powf(2.0 / 3.0)).unwrap().sample(&mut rng)).collect();
    let (gof, found, skipped) = diagnose(&s, &[("diameter_m", d), ("roundness", round), ("temperature_c", vec![20.0; n])], 99, 500, 1).unwrap();
    assert!(gof.replicates >= 90);
    assert_eq!(found[0].covariate, "roundness", "{found:?}");
    assert!(found[0].p < 0.01 && found[0].rho > 0.0, "{found:?}");
    let (lo, hi, mean) = found[0].worst_range;
    assert!(mean.abs() > 0.3 && (hi < 0.75 || lo > 0.8), "worst tertile [{lo}, {hi}], mean residual {mean}");
    assert!(skipped.iter().any(|s| s.starts_with("temperature_c: constant")), "{skipped:?}");
}

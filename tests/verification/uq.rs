//! The propagation machinery of the main study against closed forms: the geometric law of
//! independent trials and a linear limit state P_f = Φ(−β) by Monte Carlo with the block
//! standard error of the study. Vogel–Peukert and Tavares–King against hand-computed cases are
//! the unit tests of `lifetime::damage`; the chain itself is verified in `strength.rs`.

use partlife::lifetime::damage::{DamageModel, breakage};
use partlife::uq::propagate::block_points;
use partlife::uq::study::Method;
use statrs::distribution::{ContinuousCDF, Normal};

/// Independent trials: P(survive n) = (1 − p)^n for a per-impact p (geometric lifetime), and the
/// damage models coincide for one impact.
#[test]
fn geometric_lifetime_and_one_impact() {
    for p in [1e-9f64, 1e-4, 0.05] {
        let h = -(-p).ln_1p();
        for n in [1.0, 730.0, 7300.0] {
            let got = breakage(DamageModel::Independent, h, 10.0, n, 1.0);
            let survive = (1.0 - p).powf(n);
            assert!((got - (1.0 - survive)).abs() < 1e-12, "p = {p}, n = {n}");
            if survive > 1e-6 {
                assert!(((1.0 - got) / survive - 1.0).abs() < 1e-6, "survival, p = {p}, n = {n}");
            }
        }
        assert!((breakage(DamageModel::TavaresKing, h, 10.0, 1.0, 1.0) / p - 1.0).abs() < 1e-9);
    }
}

/// g = R − S, R ~ N(5, 1), S ~ N(2, 1.5): P_f = Φ(−β), β = 3/√3.25. Plain Monte Carlo in 8
/// blocks of 2¹⁵: the estimate lies within 4 block standard errors and the block standard error
/// agrees with √(P(1 − P)/N) within 35 %; LHS and Sobol' points are at least as accurate.
#[test]
fn linear_limit_state_by_monte_carlo() {
    let nd = Normal::new(0.0, 1.0).unwrap();
    let beta = 3.0 / 3.25f64.sqrt();
    let exact = nd.cdf(-beta);
    for method in [Method::Plain, Method::Lhs, Method::Sobol] {
        let (blocks, n) = (8, 1 << 15);
        let est: Vec<f64> = (0..blocks)
            .map(|r| {
                let pts = block_points(method, 2, n, 7, r).unwrap();
                pts.iter().filter(|u| 5.0 + nd.inverse_cdf(u[0].clamp(1e-16, 1.0 - 1e-16)) - (2.0 + 1.5 * nd.inverse_cdf(u[1].clamp(1e-16, 1.0 - 1e-16))) < 0.0).count() as f64 / n as f64
            })
            .collect();
        let mean = est.iter().sum::<f64>() / blocks as f64;
        let se = (est.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (blocks as f64 - 1.0) / blocks as f64).sqrt();
        let binom = (exact * (1.0 - exact) / (blocks * n) as f64).sqrt();
        if method == Method::Plain {
            assert!((mean - exact).abs() < 4.0 * se, "{mean} vs Φ(−β) = {exact} (block se {se})");
            assert!((se / binom - 1.0).abs() < 0.35, "block se {se} vs binomial {binom}");
        } else {
            // At least as accurate as plain Monte Carlo of the same size.
            assert!((mean - exact).abs() < 4.0 * binom, "{method:?}: {mean} vs Φ(−β) = {exact}");
        }
    }
}

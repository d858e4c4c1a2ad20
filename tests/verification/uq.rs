//! The UQ chain (`uq::run`, `uq::inputs`) against closed forms (verification.md §5):
//! the chain at fixed inputs equals the verified lifetime chain, the geometric law of
//! independent trials, a linear limit state P_f = Φ(−β) by Monte Carlo with the block standard
//! error of the study, and the Bayesian Weibull posterior against the parametric bootstrap of
//! the MLE on a large sample. Vogel–Peukert and Tavares–King against hand-computed cases are the
//! unit tests of `uq::damage`.

use partlife::contact::{AveragingDomain, Elastic, OuterLimit, Sphere};
use partlife::lifetime::{ImpactLoad, Lifetime};
use partlife::uq::damage::{DamageModel, VogelPeukert, breakage};
use partlife::uq::inputs::bayesian_weibull_draws;
use partlife::uq::run::{Method, block_points};
use partlife::weibull::{Weibull, fit_mle, simulate_pivotal, sorted_quantile};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use statrs::distribution::{ContinuousCDF, Normal};

/// The study's chain at fixed inputs (c = 1) against `Lifetime::p_after`, on the fast path
/// (σ̄ ∝ p0) and the general one (average to the particle radius).
#[test]
fn chain_at_fixed_inputs_is_the_lifetime_chain() {
    let base = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/studies/gen4_vs_bl.toml")).unwrap();
    let line_2a = "averaging = { measure = \"line\", outer = \"contact_multiple\", kappa = 2.0 }";
    for (toml_domain, domain) in [
        (line_2a, AveragingDomain::default()),
        ("averaging = { measure = \"line\", outer = \"particle_radius\" }", AveragingDomain { outer: OuterLimit::ParticleRadius, ..AveragingDomain::default() }),
    ] {
        check_fixed_chain(&base.replace(line_2a, toml_domain), domain);
    }
}

fn check_fixed_chain(study: &str, domain: AveragingDomain) {
    // Fix every shared input and both shapes at 1 (a sphere).
    let fixed = study
        .replace("roundness = { distribution = \"normal\", mean = 0.72, sd = 0.05, min = 0.5, max = 1.0 }", "roundness = { distribution = \"fixed\", value = 1.0 }")
        .replace("roundness = { distribution = \"normal\", mean = 0.82, sd = 0.05, min = 0.5, max = 1.0 }", "roundness = { distribution = \"fixed\", value = 1.0 }")
        .replace("sphericity = { distribution = \"normal\", mean = 0.87, sd = 0.05, min = 0.6, max = 1.0 }", "sphericity = { distribution = \"fixed\", value = 1.0 }")
        .replace("sphericity = { distribution = \"normal\", mean = 0.89, sd = 0.05, min = 0.6, max = 1.0 }", "sphericity = { distribution = \"fixed\", value = 1.0 }")
        .replace("energy_fraction = { distribution = \"log_normal\", median = 0.1, sd_log = 0.5, min = 0.01, max = 1.0 }", "energy_fraction = { distribution = \"fixed\", value = 0.1 }")
        .replace("velocity = { distribution = \"log_normal\", median = 5.0, sd_log = 0.2, min = 1.0, max = 15.0 }", "velocity = { distribution = \"fixed\", value = 5.0 }");
    let dir = tempfile::tempdir().unwrap();
    let studies = dir.path().join("studies");
    std::fs::create_dir_all(&studies).unwrap();
    std::fs::create_dir_all(dir.path().join("datasets")).unwrap();
    for f in ["crush_bl1630.csv", "crush_gen4.csv"] {
        std::fs::copy(concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/").to_string() + f, dir.path().join("datasets").join(f)).unwrap();
    }
    let path = studies.join("fixed.toml");
    std::fs::write(&path, fixed).unwrap();
    let loaded = partlife::study::load(&path).unwrap();
    let partlife::study::Study::Uq(s) = &loaded.study else { panic!("not a uq study") };
    let chain = s.prepare(&path).unwrap();
    // Varying: the two Weibull inputs and γ only.
    let names: Vec<&str> = chain.varying().iter().map(|&i| chain.inputs[i].name.as_str()).collect();
    assert_eq!(names, ["weibull_gen4", "weibull_bl1630", "tk_gamma"]);
    let steel = Elastic { youngs_modulus_pa: 210e9, poisson_ratio: 0.3 };
    for u in [[0.1, 0.7, 0.5], [0.93, 0.02, 0.5]] {
        let e = chain.evaluate(&u);
        for j in 0..2 {
            let w: Weibull = chain.inputs[j].marginal.weibull(u[j]).unwrap();
            let sphere: Sphere = chain.materials[j].sphere;
            let life = Lifetime { load: ImpactLoad::on_wall(&sphere, &steel, 0.1, domain), strength: w };
            for (h, n) in [(0, 730.0), (1, 7300.0)] {
                let want = life.p_after(5.0, n).unwrap();
                let got = e.p[(j * 2 + h) * 3];
                assert!((got / want - 1.0).abs() < 1e-9, "material {j}, N = {n}: {got} vs {want}");
            }
        }
    }
}

/// Independent trials: P(survive n) = (1 − p)^n for a per-impact p (geometric lifetime), and the
/// damage models coincide for one impact.
#[test]
fn geometric_lifetime_and_one_impact() {
    let vp = VogelPeukert::matched(2.0);
    for p in [1e-9f64, 1e-4, 0.05] {
        let h = -(-p).ln_1p();
        for n in [1.0, 730.0, 7300.0] {
            let got = breakage(DamageModel::Independent, h, 10.0, n, &vp, 1.0);
            let survive = (1.0 - p).powf(n);
            assert!((got - (1.0 - survive)).abs() < 1e-12, "p = {p}, n = {n}");
            if survive > 1e-6 {
                assert!(((1.0 - got) / survive - 1.0).abs() < 1e-6, "survival, p = {p}, n = {n}");
            }
        }
        assert!((breakage(DamageModel::TavaresKing, h, 10.0, 1.0, &vp, 1.0) / p - 1.0).abs() < 1e-9);
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

/// On N = 400 draws of a known law the Bayesian posterior (prior ∝ 1/(m σ)) and the parametric
/// bootstrap of the MLE give the same 5/50/95 % quantiles of m and σ_θ within 4 %, and the
/// bootstrap's 90 % interval of m is the C1239 pivotal interval.
#[test]
fn bayesian_and_bootstrap_weibull_agree_on_a_large_sample() {
    let truth = Weibull::new(8.0, 300e6).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let data: Vec<f64> = (0..400).map(|_| truth.sample(&mut rng)).collect();
    let fit = fit_mle(&data).unwrap();
    let boot = simulate_pivotal(fit.n, 20000, 5).unwrap().draws(&fit);
    let bayes = bayesian_weibull_draws(&data, &fit, 20000, 5).unwrap();
    let q = |v: &[Weibull], f: fn(&Weibull) -> f64, p: f64| {
        let mut x: Vec<f64> = v.iter().map(f).collect();
        x.sort_by(f64::total_cmp);
        sorted_quantile(&x, p)
    };
    for p in [0.05, 0.5, 0.95] {
        let (mb, mp) = (q(&boot, |w| w.shape, p), q(&bayes, |w| w.shape, p));
        assert!((mb / mp - 1.0).abs() < 0.04, "m at {p}: bootstrap {mb}, Bayes {mp}");
        let (sb, sp) = (q(&boot, |w| w.scale, p), q(&bayes, |w| w.scale, p));
        assert!((sb / sp - 1.0).abs() < 0.01, "σ_θ at {p}: bootstrap {sb}, Bayes {sp}");
    }
    let piv = simulate_pivotal(fit.n, 20000, 5).unwrap().bounds(&fit, 0.9).unwrap();
    let (lo, hi) = (q(&boot, |w| w.shape, 0.05), q(&boot, |w| w.shape, 0.95));
    assert!((lo / piv.shape.0 - 1.0).abs() < 0.01 && (hi / piv.shape.1 - 1.0).abs() < 0.01, "bootstrap [{lo}, {hi}] vs pivotal {:?}", piv.shape);
}

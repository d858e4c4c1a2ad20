//! Levenberg–Marquardt least squares (`calibrate::lsq`) on analytic models: exact recovery
//! without noise, coverage of the reported 90 % intervals over 200 noisy data sets (binomial
//! tolerance ±3 sd), a non-identifiable product named as such, and simulator failures recorded
//! without aborting the fit.

use partlife::calibrate::Noise;
use partlife::calibrate::lsq::{LsqMethod, LsqOptions, fit};
use partlife::model::{OutputSpec, Simulator};
use partlife::params::{Param, ParamSpace};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// y(t) = a e^(−b t) + c at t = 0, 1, …, 20; fails (an Err) when a > `fail_above`.
struct Decay {
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
    fail_above: f64,
}

impl Decay {
    fn new(fail_above: f64) -> Self {
        let space = ParamSpace::new(vec![
            Param::uniform("a", "-", 0.1, 10.0, 1.0),
            Param::uniform("b", "1/s", 0.01, 2.0, 1.0),
            Param::uniform("c", "-", -1.0, 1.0, 0.0),
        ])
        .unwrap();
        let outputs = (0..21).map(|i| OutputSpec::new(format!("y{i}"), "-")).collect();
        Decay { space, outputs, fail_above }
    }
}

impl Simulator for Decay {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, th: &[f64]) -> partlife::Result<Vec<f64>> {
        if th[0] > self.fail_above {
            return Err(partlife::Error::numerical("decay", "a too large"));
        }
        Ok((0..21).map(|i| th[0] * (-th[1] * i as f64).exp() + th[2]).collect())
    }
}

const TRUTH: [f64; 3] = [3.0, 0.4, 0.2];

#[test]
fn recovers_exact_parameters_without_noise() {
    let m = Decay::new(f64::INFINITY);
    let data = m.simulate(&TRUTH).unwrap();
    let r = fit(&m, &data, &Noise::Known { sigma: vec![0.01; 21] }, &LsqOptions::default()).unwrap();
    for (k, (&est, &tru)) in r.theta.iter().zip(&TRUTH).enumerate() {
        assert!((est - tru).abs() < 1e-6 * tru.abs().max(1.0), "θ{k}: {est} vs {tru}");
    }
    assert!(r.cost < 1e-12 && r.unidentified.is_empty(), "{r:?}");
    assert!(r.starts.iter().all(|s| s.iterations < LsqOptions::default().max_iterations), "a start ran out of iterations: {:?}", r.starts);
}

/// argmin's Nelder–Mead and L-BFGS reach the same optimum as Levenberg–Marquardt (to their
/// own tolerances: NM stops on the simplex spread, L-BFGS on the forward-difference gradient),
/// and a failing region is skipped, not fatal.
#[test]
fn nelder_mead_and_lbfgs_reach_the_same_optimum() {
    let m = Decay::new(f64::INFINITY);
    let data = m.simulate(&TRUTH).unwrap();
    let noise = Noise::Known { sigma: vec![0.01; 21] };
    for (method, tol) in [(LsqMethod::NelderMead, 1e-4), (LsqMethod::Lbfgs, 1e-4)] {
        let r = fit(&m, &data, &noise, &LsqOptions { method, starts: 3, max_iterations: 400, ftol: 1e-16, fd_step: 1e-7, ..LsqOptions::default() }).unwrap();
        for (k, (&est, &tru)) in r.theta.iter().zip(&TRUTH).enumerate() {
            assert!((est - tru).abs() < tol * tru.abs().max(1.0), "{method:?} θ{k}: {est} vs {tru}");
        }
        // The covariance comes from the Jacobian at the end point, as for LM.
        assert!(r.std_error.iter().all(|s| s.is_finite() && *s > 0.0), "{method:?}: {:?}", r.std_error);
        let failing = Decay::new(5.0);
        let rf = fit(&failing, &data, &noise, &LsqOptions { method, starts: 8, max_iterations: 400, ftol: 1e-16, fd_step: 1e-7, ..LsqOptions::default() }).unwrap();
        assert!((rf.theta[0] - TRUTH[0]).abs() < 1e-3, "{method:?} with failures: {:?}", rf.theta);
        assert!(!rf.failures.is_empty(), "{method:?}: the Sobol' starts above a = 5 fail");
    }
}

#[test]
fn reported_intervals_cover_the_truth() {
    let m = Decay::new(f64::INFINITY);
    let clean = m.simulate(&TRUTH).unwrap();
    let sigma = 0.05;
    let opts = LsqOptions { starts: 2, ..LsqOptions::default() };
    let (mut hits, mut total) = (0usize, 0usize);
    let mut scale_mean = 0.0;
    let n = 200;
    for seed in 0..n {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, sigma).unwrap();
        let data: Vec<f64> = clean.iter().map(|y| y + noise.sample(&mut rng)).collect();
        let r = fit(&m, &data, &Noise::Known { sigma: vec![sigma; 21] }, &opts).unwrap();
        for ((est, tru), se) in r.theta.iter().zip(TRUTH).zip(&r.std_error) {
            total += 1;
            if (est - tru).abs() <= 1.645 * se {
                hits += 1;
            }
        }
        let ri = fit(&m, &data, &Noise::Inferred, &opts).unwrap();
        scale_mean += ri.scale / n as f64;
    }
    let coverage = hits as f64 / total as f64;
    eprintln!("coverage {:.1} %, mean s²/σ² = {:.3}", 100.0 * coverage, scale_mean / (sigma * sigma));
    // 600 Bernoulli(0.9) trials (not independent within a data set): sd ≈ 0.012 → ±0.05.
    assert!((coverage - 0.9).abs() < 0.05, "90 % intervals cover {:.1} %", 100.0 * coverage);
    // Inferred σ²: E[s²] = σ² for a model linear near the optimum.
    assert!((scale_mean / (sigma * sigma) - 1.0).abs() < 0.1, "mean s² = {scale_mean:e}");
}

/// y = (a b) t: only the product is determined; the fit says so.
struct Product {
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
}

impl Simulator for Product {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, th: &[f64]) -> partlife::Result<Vec<f64>> {
        Ok((0..10).map(|i| th[0] * th[1] * i as f64).collect())
    }
}

#[test]
fn a_non_identifiable_product_is_named() {
    let m = Product {
        space: ParamSpace::new(vec![Param::uniform("gain_a", "-", 0.5, 2.0, 1.0), Param::uniform("gain_b", "-", 0.5, 2.0, 1.5)]).unwrap(),
        outputs: (0..10).map(|i| OutputSpec::new(format!("y{i}"), "-")).collect(),
    };
    let data: Vec<f64> = (0..10).map(|i| 1.2 * i as f64).collect();
    let r = fit(&m, &data, &Noise::Known { sigma: vec![0.01; 10] }, &LsqOptions::default()).unwrap();
    assert!((r.theta[0] * r.theta[1] - 1.2).abs() < 1e-6, "the product is fitted: {:?}", r.theta);
    // Both parameters are named, as a pair whose correlation is near ±1 or each on its own.
    let text = r.unidentified.join("; ");
    let named = |p: &str| r.unidentified.iter().any(|u| u.starts_with(&format!("{p}:")) || u.starts_with(&format!("{p} and ")) || u.contains(&format!(" and {p}:")));
    assert!(named("gain_a") && named("gain_b"), "not named: {text}");
}

#[test]
fn simulator_failures_are_recorded_not_fatal() {
    // The model fails for a > 8; one Sobol' start lands there, the others fit.
    let m = Decay::new(8.0);
    let data = m.simulate(&TRUTH).unwrap();
    let r = fit(&m, &data, &Noise::Relative { relative: 0.01, floor: 1e-3 }, &LsqOptions { starts: 8, ..LsqOptions::default() }).unwrap();
    assert!(!r.failures.is_empty(), "no start hit the failing region");
    assert!(r.starts.iter().any(|s| s.end.is_none()), "a failed start is recorded");
    assert!((r.theta[0] - TRUTH[0]).abs() < 1e-5, "{:?}", r.theta);
    // Data of the wrong length is refused.
    assert!(fit(&m, &data[..20], &Noise::Inferred, &LsqOptions::default()).is_err());
}

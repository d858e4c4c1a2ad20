//! MCMC (`calibrate::mcmc`) against exact posteriors (docs/reference.md, verification §2): the conjugate normal
//! mean, the Rosenbrock banana (E x₁ = 1, Var x₁ = 10, E x₂ = 11), a 10-D Gaussian with
//! condition number 10⁴; the diagnostics against an AR(1) process of known autocorrelation time
//! and chains stuck apart; the sampler's independence of the thread count. Means are checked
//! within 4 Monte Carlo standard errors (sd/√ESS), variances within the stated tolerance.

use partlife::calibrate::mcmc::{Chains, EnsembleOptions, diagnostics, ensemble};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, StandardNormal};

fn init(walkers: usize, dim: usize, centre: &[f64], spread: f64, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..walkers).map(|_| (0..dim).map(|k| centre[k] + spread * Distribution::<f64>::sample(&StandardNormal, &mut rng)).collect()).collect()
}

fn moments(c: &Chains, k: usize) -> (f64, f64, f64) {
    let x = c.flat(k);
    let m = x.iter().sum::<f64>() / x.len() as f64;
    let v = x.iter().map(|a| (a - m).powi(2)).sum::<f64>() / (x.len() as f64 - 1.0);
    let d = c.diagnostics(k);
    (m, v, (v / d.ess_bulk).sqrt())
}

#[test]
fn conjugate_normal_mean() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let y: Vec<f64> = (0..20).map(|_| Normal::new(1.3, 1.0).unwrap().sample(&mut rng)).collect();
    let (mu0, tau0, sigma) = (0.0, 2.0, 1.0);
    let n = y.len() as f64;
    let ybar = y.iter().sum::<f64>() / n;
    let tn2 = 1.0 / (1.0 / (tau0 * tau0) + n / (sigma * sigma));
    let mun = tn2 * (mu0 / (tau0 * tau0) + n * ybar / (sigma * sigma));
    let lp = |x: &[f64]| -0.5 * ((x[0] - mu0) / tau0).powi(2) - y.iter().map(|yi| 0.5 * ((yi - x[0]) / sigma).powi(2)).sum::<f64>();
    let opts = EnsembleOptions { walkers: 16, steps: 4000, burn_in: 500, stretch: 2.0, seed: 3 };
    let c = ensemble(lp, init(16, 1, &[0.0], 0.5, 4), &opts).unwrap();
    let (m, v, mcse) = moments(&c, 0);
    assert!((m - mun).abs() < 4.0 * mcse, "mean {m} vs {mun} (MCSE {mcse})");
    assert!((v / tn2 - 1.0).abs() < 0.05, "variance {v} vs {tn2}");
    let d = c.diagnostics(0);
    assert!(d.r_hat < 1.01 && d.ess_bulk > 400.0 && d.warning("μ").is_none(), "{d:?}");
}

#[test]
fn rosenbrock_banana() {
    let lp = |x: &[f64]| -(100.0 * (x[1] - x[0] * x[0]).powi(2) + (1.0 - x[0]).powi(2)) / 20.0;
    let opts = EnsembleOptions { walkers: 32, steps: 40_000, burn_in: 2000, stretch: 2.0, seed: 5 };
    let c = ensemble(lp, init(32, 2, &[1.0, 1.0], 0.1, 6), &opts).unwrap();
    let (m1, v1, e1) = moments(&c, 0);
    let (m2, _, e2) = moments(&c, 1);
    eprintln!("banana: E x1 = {m1:.3} ± {e1:.3}, Var x1 = {v1:.2}, E x2 = {m2:.2} ± {e2:.2}, τ = {:.0}", c.diagnostics(0).tau);
    assert!((m1 - 1.0).abs() < 4.0 * e1, "E x1 = {m1} (MCSE {e1})");
    assert!((v1 / 10.0 - 1.0).abs() < 0.1, "Var x1 = {v1}");
    assert!((m2 - 11.0).abs() < 4.0 * e2, "E x2 = {m2} (MCSE {e2})");
}

/// N(0, Σ) in 10-D, Σ = Q diag(λ) Qᵀ with λ from 10⁻² to 10² (condition number 10⁴) and Q a
/// seeded random rotation: (dimension, Σ, log-density).
fn gaussian_10d() -> (usize, nalgebra::DMatrix<f64>, impl Fn(&[f64]) -> f64 + Sync) {
    let d = 10;
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let a = nalgebra::DMatrix::<f64>::from_fn(d, d, |_, _| StandardNormal.sample(&mut rng));
    let q = a.qr().q();
    let lambda: Vec<f64> = (0..d).map(|i| 10f64.powf(-2.0 + 4.0 * i as f64 / (d - 1) as f64)).collect();
    let sigma = &q * nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_vec(lambda)) * q.transpose();
    let prec = sigma.clone().try_inverse().unwrap();
    let lp = move |x: &[f64]| {
        let v = nalgebra::DVector::from_column_slice(x);
        -0.5 * (v.transpose() * &prec * &v)[(0, 0)]
    };
    (d, sigma, lp)
}

#[test]
fn correlated_gaussian_10d() {
    let (d, sigma, lp) = gaussian_10d();
    let opts = EnsembleOptions { walkers: 40, steps: 20_000, burn_in: 4000, stretch: 2.0, seed: 12 };
    let c = ensemble(lp, init(40, d, &[0.0; 10], 0.01, 13), &opts).unwrap();
    for k in 0..d {
        let (m, v, e) = moments(&c, k);
        assert!(m.abs() < 4.0 * e, "dimension {k}: mean {m} (MCSE {e})");
        assert!((v / sigma[(k, k)] - 1.0).abs() < 0.15, "dimension {k}: variance {v} vs {}", sigma[(k, k)]);
    }
}

#[test]
fn ess_of_an_ar1_process() {
    // x_t = φ x_{t−1} + √(1−φ²) ε: τ = (1 + φ)/(1 − φ) = 19 for φ = 0.9.
    let phi: f64 = 0.9;
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let chains: Vec<Vec<f64>> = (0..8)
        .map(|_| {
            let mut x: f64 = StandardNormal.sample(&mut rng);
            (0..20_000)
                .map(|_| {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    x = phi * x + (1.0 - phi * phi).sqrt() * e;
                    x
                })
                .collect()
        })
        .collect();
    let d = diagnostics(&chains);
    let expected = 8.0 * 20_000.0 / 19.0;
    assert!((d.ess_bulk / expected - 1.0).abs() < 0.15, "ESS {} vs {expected}", d.ess_bulk);
    assert!((d.tau / 19.0 - 1.0).abs() < 0.15, "τ {}", d.tau);
    assert!(d.r_hat < 1.01, "{d:?}");
}

#[test]
fn r_hat_flags_chains_stuck_apart() {
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let chains: Vec<Vec<f64>> = (0..4).map(|c| (0..2000).map(|_| if c < 2 { 0.0 } else { 0.5 } + Distribution::<f64>::sample(&StandardNormal, &mut rng)).collect()).collect();
    let d = diagnostics(&chains);
    assert!(d.r_hat > 1.01 && d.warning("x").is_some(), "{d:?}");
}

#[test]
fn same_chain_on_one_and_two_threads() {
    let lp = |x: &[f64]| -0.5 * (x[0] * x[0] + 4.0 * x[1] * x[1]);
    let opts = EnsembleOptions { walkers: 8, steps: 500, burn_in: 0, stretch: 2.0, seed: 9 };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| ensemble(lp, init(8, 2, &[0.0, 0.0], 1.0, 1), &opts).unwrap())
    };
    assert_eq!(run(1).draws, run(2).draws);
}

#[test]
fn adaptive_metropolis_on_the_10d_gaussian() {
    use partlife::calibrate::mcmc::{AdaptiveOptions, adaptive_metropolis};
    let (d, sigma, lp) = gaussian_10d();
    let opts = AdaptiveOptions { chains: 4, steps: 100_000, burn_in: 20_000, adapt_after: 1000, initial_scale: vec![0.05; d], seed: 14 };
    let c = adaptive_metropolis(lp, init(4, d, &[0.0; 10], 0.01, 15), &opts).unwrap();
    let acc = c.acceptance.iter().sum::<f64>() / 4.0;
    // The optimal Gaussian random-walk acceptance in 10-D is ≈ 0.23–0.26.
    assert!((0.15..0.35).contains(&acc), "acceptance {acc}");
    for k in 0..d {
        let (m, v, e) = moments(&c, k);
        assert!(m.abs() < 4.0 * e, "dimension {k}: mean {m} (MCSE {e})");
        assert!((v / sigma[(k, k)] - 1.0).abs() < 0.15, "dimension {k}: variance {v} vs {}", sigma[(k, k)]);
        assert!(c.diagnostics(k).r_hat < 1.01);
    }
}

/// A run killed part-way (here by a log-density that turns NaN after a number of calls) and
/// rerun with the same checkpoint file ends with exactly the chain of an uninterrupted run.
#[test]
fn a_killed_run_resumes_from_its_checkpoint() {
    use partlife::calibrate::mcmc::{Checkpoint, ensemble_with_checkpoint};
    use std::sync::atomic::{AtomicUsize, Ordering};
    let lp = |x: &[f64]| -0.5 * (x[0] * x[0] + 4.0 * x[1] * x[1]) - 0.1 * x[0] * x[1];
    let opts = EnsembleOptions { walkers: 8, steps: 600, burn_in: 100, stretch: 2.0, seed: 19 };
    let start = init(8, 2, &[0.0, 0.0], 1.0, 2);
    let full = ensemble(lp, start.clone(), &opts).unwrap();
    let dir = partlife::io::TempDir::new("test").unwrap();
    let ck = Checkpoint { path: dir.path().join("chain.json"), every: 50 };
    let calls = AtomicUsize::new(0);
    let dying = |x: &[f64]| if calls.fetch_add(1, Ordering::SeqCst) > 3000 { f64::NAN } else { lp(x) };
    assert!(ensemble_with_checkpoint(dying, start.clone(), &opts, &ck).is_err(), "the run dies");
    assert!(ck.path.is_file(), "a checkpoint was written before it died");
    let resumed = ensemble_with_checkpoint(lp, start.clone(), &opts, &ck).unwrap();
    let first_diff = resumed.draws.iter().zip(&full.draws).position(|(a, b)| a != b);
    assert!(first_diff.is_none() && resumed.draws.len() == full.draws.len(), "the resumed chain differs from the uninterrupted one from step {first_diff:?}");
    assert_eq!(resumed.evaluations, full.evaluations);
    // A checkpoint of other options is refused, not overwritten.
    let other = EnsembleOptions { seed: 20, ..opts.clone() };
    assert!(ensemble_with_checkpoint(lp, start, &other, &ck).is_err());
}

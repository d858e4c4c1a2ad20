//! The Gaussian-process emulator (`calibrate::gp`) reproduces a known function within its
//! predicted variance, and its leave-one-out errors have unit scale once standardised; with
//! noisy data the nugget estimates the noise variance.

use partlife::calibrate::gp::Gp;
use partlife::design::{Sobol, latin_hypercube};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

fn f(x: &[f64]) -> f64 {
    (6.0 * x[0]).sin() + x[1] * x[1] + 0.5 * x[0] * x[1]
}

#[test]
fn reproduces_a_known_function_within_its_variance() {
    let x = latin_hypercube(40, 2, 3);
    let y: Vec<f64> = x.iter().map(|p| f(p)).collect();
    let gp = Gp::fit(x, &y).unwrap();
    let test = Sobol::points(2, 256, 1).unwrap();
    let (mut inside, mut sq) = (0usize, 0.0);
    for p in &test {
        let (m, v) = gp.predict(p);
        let e = m - f(p);
        sq += e * e;
        if e.abs() <= 3.0 * v.sqrt() + 1e-9 {
            inside += 1;
        }
    }
    let rmse = (sq / test.len() as f64).sqrt();
    let frac = inside as f64 / test.len() as f64;
    eprintln!("GP: RMSE {rmse:.2e} (output sd ≈ 0.8), {:.1} % within 3σ, ℓ = {:?}", 100.0 * frac, gp.length_scales);
    assert!(rmse < 0.02, "RMSE {rmse}");
    assert!(frac > 0.95, "only {:.1} % within 3σ", 100.0 * frac);
    // Standardised leave-one-out errors: not over-confident (mean z² well below 3). For a
    // smooth deterministic function the maximum-likelihood Matérn fit is conservative (z² ≈ 0.13
    // here), which is the safe side for a calibration that adds the emulator variance.
    let loo = gp.leave_one_out();
    let z2 = loo.iter().zip(&y).map(|((m, v), yi)| (m - yi).powi(2) / v).sum::<f64>() / y.len() as f64;
    eprintln!("mean squared standardised LOO error {z2:.3}");
    assert!((0.02..3.0).contains(&z2), "mean squared standardised LOO error {z2}");
}

#[test]
fn the_nugget_estimates_the_noise() {
    let x = latin_hypercube(80, 2, 5);
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let noise = Normal::new(0.0, 0.05).unwrap();
    let y: Vec<f64> = x.iter().map(|p| f(p) + noise.sample(&mut rng)).collect();
    let gp = Gp::fit(x, &y).unwrap();
    let sd = gp.noise_variance().sqrt();
    assert!((sd / 0.05 - 1.0).abs() < 0.4, "noise sd estimate {sd}");
    let (m, _) = gp.predict(&[0.5, 0.5]);
    assert!((m - f(&[0.5, 0.5])).abs() < 0.05, "{m}");
}

//! Kennedy–O'Hagan discrepancy: the simple machine of Brynjarsdóttir & O'Hagan (2014) and the
//! ball drop of SEPIA/GPMSA (docs/reference.md, verification §3.1–3.2).

use partlife::discrepancy::koh::{KohOptions, Problem, compare, least_squares};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const THETA: f64 = 0.65;
const A: f64 = 20.0;

fn machine_x() -> Vec<f64> {
    (0..11).map(|i| 0.4 * i as f64).collect()
}

fn reality(x: f64) -> f64 {
    THETA * x / (1.0 + x / A)
}

fn noisy(values: Vec<f64>, sd: f64, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = Normal::new(0.0, sd).unwrap();
    values.into_iter().map(|v| v + n.sample(&mut rng)).collect()
}

fn opts() -> KohOptions {
    KohOptions { walkers: 32, steps: 1500, burn_in: 1500, delta_draws: 300, seed: 7 }
}

#[test]
fn simple_machine_least_squares_is_biased_as_published() {
    // Noise-free, 11 points: θ̂ = 0.5624 (B&O'H 2014); max |δ| at the true θ = 0.433.
    let x = machine_x();
    let y: Vec<f64> = x.iter().map(|&v| reality(v)).collect();
    let model = |t: &[f64]| (0..x.len()).map(|i| t[0] * x[i]).collect::<Vec<f64>>();
    let p = Problem {
        name: "η = θx".into(),
        x: x.iter().map(|v| vec![*v]).collect(),
        y: y.clone(),
        noise_sd: vec![0.01; y.len()],
        model: &model,
        names: vec!["theta".into()],
        bounds: vec![(0.0, 2.0)],
        constrain_origin: true,
        prior: None,
    };
    let t = least_squares(&p).unwrap()[0];
    assert!((t - 0.5624).abs() < 5e-5, "θ̂ = {t}");
    let max_delta = x.iter().map(|&v| (reality(v) - THETA * v).abs()).fold(0.0, f64::max);
    assert!((max_delta - 0.433).abs() < 5e-4, "{max_delta}");
}

#[test]
fn simple_machine_constrained_discrepancy_and_the_missing_saturation_term() {
    let x = machine_x();
    let y = noisy(x.iter().map(|&v| reality(v)).collect(), 0.01, 3);
    let xs: Vec<Vec<f64>> = x.iter().map(|v| vec![*v]).collect();
    let linear = |t: &[f64]| (0..x.len()).map(|i| t[0] * x[i]).collect::<Vec<f64>>();
    let saturating = |t: &[f64]| (0..x.len()).map(|i| t[0] * x[i] / (1.0 + x[i] / t[1])).collect::<Vec<f64>>();
    let quadratic = |t: &[f64]| (0..x.len()).map(|i| t[0] * x[i] + t[1] * x[i] * x[i]).collect::<Vec<f64>>();
    let base = Problem { name: "θx".into(), x: xs.clone(), y: y.clone(), noise_sd: vec![0.01; y.len()], model: &linear, names: vec!["theta".into()], bounds: vec![(0.0, 2.0)], constrain_origin: true, prior: None };
    let cands = vec![
        Problem { name: "saturation θx/(1 + x/a)".into(), x: xs.clone(), y: y.clone(), noise_sd: vec![0.01; y.len()], model: &saturating, names: vec!["theta".into(), "a".into()], bounds: vec![(0.0, 2.0), (1.0, 200.0)], constrain_origin: true, prior: None },
        Problem { name: "quadratic θx + c x²".into(), x: xs.clone(), y: y.clone(), noise_sd: vec![0.01; y.len()], model: &quadratic, names: vec!["theta".into(), "c".into()], bounds: vec![(0.0, 2.0), (-1.0, 1.0)], constrain_origin: true, prior: None },
    ];
    let (fits, named) = compare(&base, &cands, &opts()).unwrap();
    for f in &fits {
        eprintln!("{}: θ median {:?} 90 % {:?}, σ_δ {:.2e}, RMS δ {:.2e}, BIC {:.2}", f.name, f.theta_median, f.theta_90, f.sigma_delta, f.delta_rms, f.bic);
    }
    // With the constrained δ the base model's posterior for θ covers the truth (B&O'H's point),
    // and its discrepancy is large and structured.
    let (lo, hi) = fits[0].theta_90[0];
    assert!(lo < THETA && THETA < hi, "base θ 90 % [{lo}, {hi}]");
    assert!(fits[0].delta_rms > 0.05, "base RMS δ {}", fits[0].delta_rms);
    // The saturation term is named, δ collapses to the noise level, θ and a are recovered.
    assert_eq!(named, Some(0), "BIC {:?}", fits.iter().map(|f| f.bic).collect::<Vec<_>>());
    let s = &fits[1];
    assert!(s.delta_rms < 0.01, "RMS δ after {}", s.delta_rms);
    let (lo, hi) = s.theta_90[0];
    assert!(lo < THETA && THETA < hi, "θ 90 % [{lo}, {hi}]");
    let (lo, hi) = s.theta_90[1];
    assert!(lo < A && A < hi, "a 90 % [{lo}, {hi}]");
    // And the unconstrained, no-discrepancy estimate was biased: the discrepancy mattered.
    assert!((least_squares(&base).unwrap()[0] - THETA).abs() > 0.05);
}

const G: f64 = 9.8;
const C_TRUE: f64 = 0.1 / (4.0 * std::f64::consts::PI / 3.0);

/// Fall distance after time t from rest with dv/dt = g − a v − b v² (a, b ≥ 0, not both tiny).
fn fall(t: f64, a: f64, b: f64) -> f64 {
    if b <= 1e-12 {
        // Linear drag: h = (g/a)(t − (1 − e^(−at))/a).
        return G / a * (t + (-a * t).exp_m1() / a);
    }
    let disc = (a * a + 4.0 * b * G).sqrt();
    let vt = (-a + disc) / (2.0 * b);
    let vm = (-a - disc) / (2.0 * b);
    let q = -vt / vm;
    let e = (-disc * t).exp();
    vt * (t + (1.0 + q) / (disc * q) * ((q * e).ln_1p() - q.ln_1p()))
}

/// Time to fall h (bisection).
fn time_to_fall(h: f64, a: f64, b: f64) -> f64 {
    let mut hi = (2.0 * h / G).sqrt();
    while fall(hi, a, b) < h {
        hi *= 2.0;
        if hi > 1e4 {
            return f64::NAN;
        }
    }
    let mut lo = 0.0;
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if fall(mid, a, b) < h { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

#[test]
fn ball_drop_closed_forms_agree_with_integration() {
    // RK4 of dv/dt = g − a v − b v² against the closed form, mixed and linear drag.
    for (a, b) in [(0.3, 0.0), (0.0, 0.2), (0.1, 0.05)] {
        let (mut h, mut v, dt) = (0.0f64, 0.0f64, 1e-4);
        let f = |v: f64| G - a * v - b * v * v;
        for _ in 0..20_000 {
            let k1 = f(v);
            let k2 = f(v + 0.5 * dt * k1);
            let k3 = f(v + 0.5 * dt * k2);
            let k4 = f(v + dt * k3);
            let l1 = v;
            let l2 = v + 0.5 * dt * k1;
            let l3 = v + 0.5 * dt * k2;
            let l4 = v + dt * k3;
            h += dt / 6.0 * (l1 + 2.0 * l2 + 2.0 * l3 + l4);
            v += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        let exact = fall(2.0, a, b);
        assert!((h - exact).abs() < 1e-8 * exact, "a = {a}, b = {b}: {h} vs {exact}");
    }
}

#[test]
fn ball_drop_names_quadratic_drag_and_recovers_c() {
    let radii = [0.1, 0.2, 0.4];
    let heights = [5.0, 10.0, 15.0, 20.0];
    let pts: Vec<(f64, f64)> = radii.iter().flat_map(|&r| heights.iter().map(move |&h| (h, r))).collect();
    let sd = 0.01;
    let y = noisy(pts.iter().map(|&(h, r)| time_to_fall(h, 0.0, C_TRUE / r)).collect(), sd, 11);
    let xs: Vec<Vec<f64>> = pts.iter().map(|&(h, r)| vec![h, r]).collect();
    let linear = |t: &[f64]| (0..pts.len()).map(|i| time_to_fall(pts[i].0, t[0] / pts[i].1, 0.0)).collect::<Vec<f64>>();
    let quadratic = |t: &[f64]| (0..pts.len()).map(|i| time_to_fall(pts[i].0, 0.0, t[0] / pts[i].1)).collect::<Vec<f64>>();
    let mixed = |t: &[f64]| (0..pts.len()).map(|i| time_to_fall(pts[i].0, t[0] / pts[i].1, t[1] / pts[i].1)).collect::<Vec<f64>>();
    let delayed = |t: &[f64]| (0..pts.len()).map(|i| time_to_fall(pts[i].0, t[0] / pts[i].1, 0.0) + t[1]).collect::<Vec<f64>>();
    let base = Problem { name: "linear drag".into(), x: xs.clone(), y: y.clone(), noise_sd: vec![sd; y.len()], model: &linear, names: vec!["c_linear".into()], bounds: vec![(1e-4, 2.0)], constrain_origin: false, prior: None };
    // The drag-law alternatives: quadratic instead of linear, both, or linear with a release delay.
    let cands = vec![
        Problem { name: "quadratic drag".into(), x: xs.clone(), y: y.clone(), noise_sd: vec![sd; y.len()], model: &quadratic, names: vec!["c_quadratic".into()], bounds: vec![(1e-4, 1.0)], constrain_origin: false, prior: None },
        Problem { name: "linear + quadratic drag".into(), x: xs.clone(), y: y.clone(), noise_sd: vec![sd; y.len()], model: &mixed, names: vec!["c_linear".into(), "c_quadratic".into()], bounds: vec![(0.0, 2.0), (0.0, 1.0)], constrain_origin: false, prior: None },
        Problem { name: "linear drag + release delay".into(), x: xs.clone(), y: y.clone(), noise_sd: vec![sd; y.len()], model: &delayed, names: vec!["c_linear".into(), "t0".into()], bounds: vec![(1e-4, 2.0), (-0.5, 0.5)], constrain_origin: false, prior: None },
    ];
    let (fits, named) = compare(&base, &cands, &opts()).unwrap();
    for f in &fits {
        eprintln!("{}: θ median {:?} 90 % {:?}, σ_δ {:.2e}, RMS δ {:.2e}, BIC {:.2}", f.name, f.theta_median, f.theta_90, f.sigma_delta, f.delta_rms, f.bic);
    }
    assert!(fits[0].delta_rms > 3.0 * sd, "linear drag leaves a structured δ: RMS {}", fits[0].delta_rms);
    // Quadratic drag is named (the mixed law fits as well but pays for its extra parameter),
    // δ collapses to below the noise and C is recovered.
    assert_eq!(named, Some(0), "BIC {:?}", fits.iter().map(|f| f.bic).collect::<Vec<_>>());
    let q = &fits[1];
    assert!(q.delta_rms < sd, "δ collapses: RMS {}", q.delta_rms);
    let (lo, hi) = q.theta_90[0];
    assert!(lo < C_TRUE && C_TRUE < hi, "C 90 % [{lo}, {hi}], truth {C_TRUE}");
    assert!(fits[2].delta_rms < sd && fits[3].delta_rms > 3.0 * sd, "mixed RMS δ {}, delay RMS δ {}", fits[2].delta_rms, fits[3].delta_rms);
}

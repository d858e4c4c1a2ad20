//! The strength model on generator data with hidden effects (the crush generator's BL-16/30-like
//! material, m = 22, with a size effect α = 0.5 and roundness as contact curvature q = 1
//! switched on; datasets of n = 80 crush tests):
//!
//! * coverage: the diagnosed model's 90 % band of the population's breaking probability after one
//!   year (730 impacts) at 5 m/s and η = 0.1 covers the generator's true population breakage —
//!   computed from the generator's own law over 200 000 of its particles — in at least 80 % of 100
//!   datasets; the deliverable's model's coverage is printed beside it;
//! * the stacking weights of four candidate models go to the generator's (size + roundness) as
//!   the number of crush tests grows (n = 40, 160, 640).
//!
//! The truth is read from the generator's settings here, in the test; fitting code never reads it.

mod common;

use common::bl_generator;
use partlife::contact::{ContactOptions, Elastic, Sphere};
use partlife::data::CrushData;
use partlife::discrepancy::workflow::{cv_scores, resolve};
use partlife::strength::{Effect, LifetimeModel, NamingSettings, Population, StrengthFit, StrengthSpec, Uncertainty, sample_of, weights};
use partlife::synth::{SynthSettings, generate};

const ETA: f64 = 0.1;
const V: f64 = 5.0;
const N: f64 = 730.0;
const DENSITY: f64 = 3060.0;

fn generator(count: usize, seed: u64) -> SynthSettings {
    let mut g: SynthSettings = toml::from_str(&bl_generator(1.0, 0.5, count, 0, "20.0", "")).unwrap();
    g.seed = seed;
    g
}

fn steel() -> Elastic {
    Elastic { youngs_modulus_pa: 210e9, poisson_ratio: 0.3 }
}

/// The generator's true population breakage: the mean over 200 000 of its particles (true
/// diameter and roundness) of 1 − exp(−N H), H from its own law.
fn truth() -> f64 {
    let mut g = generator(200_000, 987_654);
    g.material[0].measurement.force_rel_sd = 0.0;
    let m = g.material[0].clone();
    let particles = generate(&g, 0).unwrap();
    particles.iter().map(|p| -(-N * m.impact_hazard(p.diameter_true, p.roundness_true, DENSITY, &steel(), ETA, V)).exp_m1()).sum::<f64>() / particles.len() as f64
}

/// (diagnosed effects, its band, the deliverable's band) of one generated dataset.
fn bands(count: usize, seed: u64) -> (Vec<Effect>, (f64, f64, f64), (f64, f64, f64)) {
    let g = generator(count, seed);
    let records = generate(&g, 0).unwrap().into_iter().map(|p| p.record).collect();
    let data = CrushData::new(format!("generated-{seed}.csv"), records);
    let elastic = g.material[0].elastic;
    let sample = sample_of(&data, &elastic, &ContactOptions::default()).unwrap();
    let naming = NamingSettings { bootstrap: 199, seed, ..NamingSettings::default() };
    let diagnosed = resolve(&StrengthSpec::Diagnosed, &sample, &naming).unwrap();
    let band = |effects: &[Effect]| {
        let fit = StrengthFit::new(&sample, effects, naming.gamma, "bl").unwrap();
        let sphere = Sphere { diameter: 0.9e-3, density: DENSITY, elastic };
        let model = LifetimeModel::new("bl", "BL 16/30", sphere, steel(), Default::default(), fit, Population::of_data(&data)).unwrap();
        model.bands(&model.fit.estimate(), ETA, V, &[N], Uncertainty::Bootstrap, 1000, seed ^ 0xC0, 0.9).unwrap()[0]
    };
    (diagnosed.clone(), band(&diagnosed), band(&[]))
}

fn coverage(seeds: std::ops::Range<u64>) -> (usize, usize, usize) {
    let p = truth();
    let (mut diag, mut deliv, mut n) = (0, 0, 0);
    for seed in seeds {
        let (effects, d, b) = bands(80, 40_000 + seed);
        let inside = |x: (f64, f64, f64)| x.1 <= p && p <= x.2;
        eprintln!("seed {seed}: truth {p:.3e}; diagnosed {effects:?} {:.3e} [{:.2e}, {:.2e}] {}; deliverable {:.3e} [{:.2e}, {:.2e}] {}", d.0, d.1, d.2, inside(d), b.0, b.1, b.2, inside(b));
        diag += usize::from(inside(d));
        deliv += usize::from(inside(b));
        n += 1;
    }
    eprintln!("coverage of the true population breakage {p:.3e}: diagnosed model {diag}/{n}, deliverable's model {deliv}/{n}");
    (diag, deliv, n)
}

#[test]
fn the_diagnosed_model_covers_the_true_population_breakage() {
    // 100 datasets take about 4 s in release on 2 cores: no need for a shorter sibling.
    let (diag, _, n) = coverage(0..100);
    assert!(diag as f64 >= 0.8 * n as f64, "diagnosed model covered the truth in {diag} of {n} datasets");
}

/// Mean stacking weight of the generator's model (size + roundness) among four candidates over
/// `seeds` datasets of `count` crush tests, and the mean pseudo-BMA weight.
fn true_model_weight(count: usize, seeds: std::ops::Range<u64>) -> (f64, f64) {
    let specs = [vec![], vec![Effect::Size], vec![Effect::Roundness], vec![Effect::Size, Effect::Roundness]].map(StrengthSpec::Effects);
    let (mut w, mut wp, mut k) = (0.0, 0.0, 0.0);
    for seed in seeds {
        let g = generator(count, 70_000 + seed);
        let records = generate(&g, 0).unwrap().into_iter().map(|p| p.record).collect();
        let data = CrushData::new("generated.csv", records);
        let sample = sample_of(&data, &g.material[0].elastic, &ContactOptions::default()).unwrap();
        let naming = NamingSettings { seed, ..NamingSettings::default() };
        let lpd: Vec<Vec<f64>> = specs.iter().map(|s| cv_scores(s, &sample, &naming, "bl").unwrap()).collect();
        w += weights::stacking(&lpd).unwrap()[3];
        wp += weights::pseudo_bma(&lpd).unwrap()[3];
        k += 1.0;
    }
    (w / k, wp / k)
}

#[test]
fn stacking_weights_go_to_the_generators_model_as_the_data_grow() {
    let w: Vec<(f64, f64)> = [40, 160, 640].iter().map(|&n| true_model_weight(n, 0..6)).collect();
    eprintln!("mean weight of size + roundness (stacking, pseudo-BMA) at n = 40, 160, 640: {w:?}");
    assert!(w[0].0 < w[1].0 && w[1].0 < w[2].0, "stacking weights do not grow with n: {w:?}");
    assert!(w[2].0 > 0.9, "at n = 640 the generator's model gets {:.3}", w[2].0);
}

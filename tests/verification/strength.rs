//! The strength model (`partlife::strength`): one chain for every study.
//!
//! * The lifetime study, the main study and the discrepancy workflow give the same population
//!   breakage at fixed inputs (1e-9 relative), for the deliverable's model and for a model with
//!   size + roundness.
//! * A population's breakage with size and roundness equals the sum, by hand, of each particle's
//!   Hertz impact computed with its own contact curvature R_c = roundness^q R and its own scale.
//! * Without effects the pivotal draws are ASTM C1239's pivotal simulation; with a size effect on
//!   a large sample the parametric bootstrap (pivotal form) and the Bayesian posterior agree.

use std::path::Path;

use partlife::contact::{AveragingDomain, ContactOptions, Elastic, Impact, Sphere};
use partlife::io::{col_f64, col_str, read_table};
use partlife::runner::{RunOptions, run_file};
use partlife::strength::{Effect, LifetimeModel, Params, Particle, Population, Sample, StrengthFit, StrengthSpec, Uncertainty};
use partlife::uq::setup::{Setup, Shared};
use partlife::weibull::{Weibull, fit_mle, simulate_pivotal, sorted_quantile};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A scratch project with the shipped studies and crush files.
fn scratch() -> partlife::io::TempDir {
    let dir = partlife::io::TempDir::new("test").unwrap();
    for sub in ["studies", "datasets"] {
        std::fs::create_dir_all(dir.path().join(sub)).unwrap();
    }
    for f in ["lifetime.toml", "gen4_vs_bl.toml", "discrepancy_crush.toml"] {
        std::fs::copy(root().join("studies").join(f), dir.path().join("studies").join(f)).unwrap();
    }
    for f in ["crush_bl1630.csv", "crush_gen4.csv"] {
        std::fs::copy(root().join("datasets").join(f), dir.path().join("datasets").join(f)).unwrap();
    }
    dir
}

fn edit(path: &Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(text.contains(from), "{} has no \"{from}\"", path.display());
    std::fs::write(path, text.replacen(from, to, 1)).unwrap();
}

/// (material key, stage or "", years) → P from a report table.
fn table(path: &Path, key_col: &str, stage_col: Option<&str>) -> Vec<(String, String, f64, f64)> {
    let df = read_table(path).unwrap();
    let k = col_str(&df, path, key_col).unwrap();
    let st = stage_col.map(|c| col_str(&df, path, c).unwrap());
    let y = col_f64(&df, path, "years").unwrap();
    let p = col_f64(&df, path, "p_break").unwrap();
    (0..k.len()).map(|i| (k[i].clone(), st.as_ref().map_or(String::new(), |s| s[i].clone()), y[i], p[i])).collect()
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a / b - 1.0).abs() < 1e-9, "{what}: {a} vs {b}");
}

#[test]
fn three_studies_give_the_same_breakage_at_fixed_inputs() {
    let dir = scratch();
    let studies = dir.path().join("studies");
    let opts = RunOptions::new(dir.path().join("reports"), false);
    // The discrepancy workflow names size then roundness for BL 16/30 in the shipped file; its
    // "before" model is the deliverable's.
    let disc = studies.join("discrepancy_crush.toml");
    edit(&disc, "replicates = 40", "replicates = 0");
    run_file(&disc, &opts).unwrap();
    let verdict: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("reports/discrepancy_crush/verdict.json")).unwrap()).unwrap();
    assert_eq!(verdict["effects_named"]["bl1630"], serde_json::json!(["size", "roundness"]));
    let disc_p = table(&dir.path().join("reports/discrepancy_crush/lifetime.csv"), "material", Some("stage"));

    for (effects, list) in [(vec![], "[]"), (vec![Effect::Size, Effect::Roundness], "[\"size\", \"roundness\"]")] {
        // Lifetime study with the MLE modulus (its default is C1239's unbiased one).
        let life = studies.join(format!("lifetime_{}.toml", effects.len()));
        std::fs::copy(studies.join("lifetime.toml"), &life).unwrap();
        edit(&life, "shape_estimate = \"unbiased\"", "shape_estimate = \"mle\"");
        edit(&life, "effects = []", &format!("effects = {list}"));
        let summary = run_file(&life, &opts).unwrap();
        let life_p = table(&summary.report_dir.join("lifetime_summary.csv"), "material_key", None);

        // The main study's chain at the maximum-likelihood parameters, η = 0.1, V = 5 m/s.
        let loaded = partlife::study::load(&studies.join("gen4_vs_bl.toml")).unwrap();
        let partlife::study::Study::Uq(s) = &loaded.study else { panic!("not a uq study") };
        let spec = StrengthSpec::Effects(effects.clone());
        let shared = Shared::new(s, &loaded.file.path, std::path::Path::new("reports")).unwrap();
        let setup = Setup::new(s, &loaded.file.path, &spec, &AveragingDomain::default(), &shared).unwrap();
        let mut out = vec![0.0; setup.outputs()];
        setup.evaluate_at_estimates([1.0, 1.0], [0.1, 5.0, 730.0, 5.0], &mut out).unwrap();

        for (j, m) in setup.materials.iter().enumerate() {
            let key = &m.model.key;
            for (h, years) in [1.0, 10.0].into_iter().enumerate() {
                let uq = out[setup.slot(j, h, 0)];
                let lt = life_p.iter().find(|r| &r.0 == key && r.2 == years).unwrap().3;
                close(lt, uq, &format!("lifetime vs main study, {key}, {years} yr, effects {effects:?}"));
                let stage = if effects.is_empty() { Some("before") } else if key == "bl1630" { Some("after") } else { None };
                if let Some(stage) = stage {
                    let d = disc_p.iter().find(|r| &r.0 == key && r.1 == stage && r.2 == years).unwrap().3;
                    close(d, uq, &format!("discrepancy vs main study, {key}, {years} yr, effects {effects:?}"));
                }
            }
        }
    }
}

#[test]
fn population_breakage_with_size_and_roundness_is_the_sum_by_hand() {
    // Particles of three diameters and roundnesses; fit on a synthetic sample with both effects.
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let n = 200;
    let d: Vec<f64> = (0..n).map(|_| rng.random_range(0.6e-3..1.2e-3)).collect();
    let r: Vec<f64> = (0..n).map(|_| rng.random_range(0.6..0.9)).collect();
    let x: Vec<f64> = (0..n).map(|i| Weibull::new(15.0, 9e8 * (d[i] / 0.9e-3f64).powf(-0.5) * r[i].powf(2.0 / 3.0)).unwrap().sample(&mut rng)).collect();
    let sample = Sample {
        source: "t".into(),
        strength: partlife::obs::Observations::exact(x),
        covariates: vec![("diameter_m".into(), d.iter().map(|v| Some(*v)).collect()), ("roundness".into(), r.iter().map(|v| Some(*v)).collect())],
        particles: true,
        ..Sample::default()
    };
    let fit = StrengthFit::new(&sample, &[Effect::Size, Effect::Roundness], 5.0, "t").unwrap();
    let pop = vec![(0.7e-3, 0.65), (0.9e-3, 0.8), (1.1e-3, 0.95)];
    let population = Population { source: "declared".into(), particles: pop.iter().map(|&(dd, rr)| Particle { diameter_m: dd, roundness: Some(rr), sphericity: None, temperature_c: None }).collect(), sampled: false, ..Population::default() };
    let e = Elastic::new(112e9, 0.25).unwrap();
    let steel = Elastic::new(210e9, 0.3).unwrap();
    let model = LifetimeModel::new("t", "T", Sphere { diameter: 0.9e-3, density: 3060.0, elastic: e }, steel, AveragingDomain::default(), fit.clone(), population).unwrap();
    let p = fit.estimate();
    let (eta, v, n_imp) = (0.1, 5.0, 730.0);
    let got = model.breakage(&p, None, eta, v, &[n_imp]).unwrap()[0];
    // By hand: particle i's own Hertz impact with R_c = roundness^q d/2 and its own scale.
    let (alpha, q) = (-p.beta[0], 1.5 * p.beta[1]);
    let d_ref = fit.references[0];
    let want: f64 = pop
        .iter()
        .map(|&(dd, rr)| {
            let sphere = Sphere { diameter: dd, density: 3060.0, elastic: e };
            let rc = rr.powf(q) * dd / 2.0;
            let impact = Impact::sphere_on_wall(&sphere, &steel, rc, eta);
            let stress = partlife::contact::ContactStress::new(impact.hertz, AveragingDomain::default(), dd / 2.0).at_force(impact.max_force(v)).unwrap().mean_tensile;
            // μ is the scale of a perfectly round particle of the reference diameter.
            let scale = (p.mu - alpha * (dd / d_ref).ln()).exp();
            let h = (stress / scale).powf(p.shape);
            -(-n_imp * h).exp_m1()
        })
        .sum::<f64>()
        / 3.0;
    assert!((got / want - 1.0).abs() < 1e-10, "{got} vs {want}");
    // The crush reduction with R = d/2 and the roundness term is the reduction with R_c.
    let f = 150.0;
    let rc_stress = |rc: f64| partlife::contact::ContactStress::new(partlife::contact::Hertz::sphere_on_flat(&e, &ContactOptions::default().platen, rc), AveragingDomain::default(), rc).at_force(f).unwrap().mean_tensile;
    let (dd, rr) = (0.9e-3, 0.7f64);
    assert!((rc_stress(dd / 2.0) / rc_stress(rr.powf(q) * dd / 2.0) - rr.powf(2.0 * q / 3.0)).abs() < 1e-12);
}

#[test]
fn without_effects_the_pivotal_draws_are_c1239() {
    let truth = Weibull::new(9.0, 700e6).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let data: Vec<f64> = (0..50).map(|_| truth.sample(&mut rng)).collect();
    let sample = Sample { source: "t".into(), strength: partlife::obs::Observations::exact(data.clone()), covariates: vec![], particles: true, ..Sample::default() };
    let fit = StrengthFit::new(&sample, &[], 5.0, "t").unwrap();
    let ours = fit.draws(Uncertainty::Bootstrap, 20000, 11).unwrap();
    let c1239 = simulate_pivotal(50, 20000, 12).unwrap().draws(&fit_mle(&data).unwrap());
    let q = |v: Vec<f64>, p: f64| {
        let mut v = v;
        v.sort_by(f64::total_cmp);
        sorted_quantile(&v, p)
    };
    for p in [0.05, 0.5, 0.95] {
        let (a, b) = (q(ours.iter().map(|d| d.shape).collect(), p), q(c1239.iter().map(|w| w.shape).collect(), p));
        assert!((a / b - 1.0).abs() < 0.015, "m at {p}: {a} vs {b}");
        let (a, b) = (q(ours.iter().map(|d| d.mu.exp()).collect(), p), q(c1239.iter().map(|w| w.scale).collect(), p));
        assert!((a / b - 1.0).abs() < 0.003, "σ_θ at {p}: {a} vs {b}");
    }
}

#[test]
fn bootstrap_and_bayesian_draws_agree_on_a_large_sample_with_a_size_effect() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let n = 400;
    let d: Vec<f64> = (0..n).map(|_| rng.random_range(0.6e-3..1.2e-3)).collect();
    let x: Vec<f64> = d.iter().map(|&di| Weibull::new(12.0, 8e8 * (di / 0.9e-3f64).powf(-0.5)).unwrap().sample(&mut rng)).collect();
    let sample = Sample { source: "t".into(), strength: partlife::obs::Observations::exact(x), covariates: vec![("diameter_m".into(), d.iter().map(|v| Some(*v)).collect())], particles: true, ..Sample::default() };
    let fit = StrengthFit::new(&sample, &[Effect::Size], 5.0, "t").unwrap();
    let boot = fit.draws(Uncertainty::Bootstrap, 4000, 1).unwrap();
    let bayes = fit.draws(Uncertainty::Bayesian, 4000, 2).unwrap();
    let centre = fit.centre[0];
    let stats = |draws: &[Params], f: &dyn Fn(&Params) -> f64| -> ([f64; 3], f64) {
        let v: Vec<f64> = draws.iter().map(f).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let sd = (v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
        let q = partlife::stats::interpolated_quantiles(v, &[0.05, 0.5, 0.95]);
        ([q[0], q[1], q[2]], sd)
    };
    let params: [(&str, &dyn Fn(&Params) -> f64); 3] = [("m", &|p| p.shape), ("α", &|p| -p.beta[0]), ("μ_c", &|p| p.mu + p.beta[0] * centre)];
    for (name, f) in params {
        let (qb, sd) = stats(&boot, f);
        let (qp, _) = stats(&bayes, f);
        for k in 0..3 {
            assert!((qb[k] - qp[k]).abs() < 0.2 * sd, "{name}, quantile {k}: bootstrap {} vs Bayes {} (sd {sd})", qb[k], qp[k]);
        }
    }
    // Both cover the truth α = 0.5 and m = 12 within their 90 % ranges.
    let (qa, _) = stats(&boot, &|p| -p.beta[0]);
    assert!(qa[0] < 0.5 && 0.5 < qa[2], "α range {qa:?}");
}

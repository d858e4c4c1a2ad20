//! The DEM at study level: the cold-test study end to end (a shortened copy), determinism across
//! thread counts, the reduced-modulus claim (impact statistics within 5 % for a tenfold modulus),
//! the `TubeBankModel` simulator, and bad input (exit 2, one message naming file, key and rule,
//! nothing written).

mod common;
use common::Scratch;

use partlife::dem::model::TubeBankModel;
use partlife::dem::run::{DemStudy, spectrum};
use partlife::dem::{Dem, DemSetup};
use partlife::model::Simulator;
use partlife::study::{Study, load};

/// The repository's cold-test study, shrunk: two rows, 50 mm wide, short run.
fn small_study() -> DemStudy {
    let loaded = load(&common::root().join("studies/dem_cold_test.toml")).unwrap();
    let Study::Dem(s) = loaded.study else { panic!("not a DEM study") };
    let mut s = *s;
    s.geometry.rows = 2;
    s.geometry.width = 0.05;
    s.geometry.height_above = 0.02;
    s.geometry.height_below = 0.01;
    s.run.duration = 0.12;
    s.run.warmup = 0.06;
    s.run.snapshots = vec![];
    s.probes.trace_min_velocity = 0.3;
    s.inlet.mass_flux = 100.0;
    s
}

fn small_setup() -> DemSetup {
    small_study().setup("small").unwrap()
}

/// Edits the scratch copy of the cold-test study into the fast variant of `small_study`.
fn shrink(s: &Scratch) {
    let mut t = s.read("studies/dem_cold_test.toml");
    for (a, b) in [
        ("rows = 5", "rows = 2"),
        ("width = 0.125", "width = 0.05"),
        ("height_above = 0.04", "height_above = 0.02"),
        ("height_below = 0.03", "height_below = 0.01"),
        ("duration = 1.0", "duration = 0.12"),
        ("warmup = 0.6", "warmup = 0.06"),
        ("snapshots = [0.6]", "snapshots = [0.1]"),
        ("trace_min_velocity = 1.0", "trace_min_velocity = 0.3"),
    ] {
        assert!(t.contains(a), "the study has no \"{a}\"");
        t = t.replacen(a, b, 1);
    }
    s.write("studies/dem_cold_test.toml", &t);
}

#[test]
fn cold_test_study_fast_variant_writes_every_output() {
    let s = Scratch::new();
    shrink(&s);
    let out = s.run(&["run", "studies/dem_cold_test.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let dir = s.path("reports/dem_cold_test");
    for f in [
        "impacts.parquet",
        "passes.parquet",
        "impact_spectrum.csv",
        "velocity_profile.csv",
        "speed_map.csv",
        "flow.csv",
        "force_trace.csv",
        "tubes.csv",
        "dem_summary.csv",
        "manifest.json",
    ] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    for stem in ["dem_velocity_profile", "dem_speed_map", "dem_impact_spectra", "dem_force_time"] {
        for ext in ["svg", "png", "pdf"] {
            let p = dir.join(format!("{stem}.{ext}"));
            assert!(std::fs::metadata(&p).map(|m| m.len() > 1000).unwrap_or(false), "missing or empty {}", p.display());
        }
    }
    // Snapshots: the requested one and the end state, complete and consistent.
    let vtps: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().filter(|e| e.path().extension().is_some_and(|x| x == "vtp")).collect();
    assert_eq!(vtps.len(), 2, "{vtps:?}");
    for v in vtps {
        let text = std::fs::read_to_string(v.path()).unwrap();
        let (pts, n) = partlife::dem::vtk::read_points(&text).expect("a complete .vtp");
        assert!(n > 100, "{n} particles");
        assert!(pts.iter().all(|p| p[0] >= -1e-3 && p[0] <= 0.051 && p[1] >= 0.0 && p[1] < 0.005));
    }
    // Impact table read back through polars: columns, targets, positive normal velocities.
    let file = std::fs::File::open(dir.join("impacts.parquet")).unwrap();
    use polars::prelude::SerReader;
    let df = polars::prelude::ParquetReader::new(file).finish().unwrap();
    assert!(df.height() > 500, "{} impacts", df.height());
    let v = df.column("v_normal_m_s").unwrap().f64().unwrap();
    assert!(v.into_no_null_iter().all(|x| (0.05..10.0).contains(&x)));
    let spectrum = std::fs::read_to_string(dir.join("impact_spectrum.csv")).unwrap();
    assert!(spectrum.starts_with("target,row,impacts,mean_v_normal_m_s,q5_v_normal_m_s"), "{spectrum}");
    assert!(spectrum.lines().any(|l| l.starts_with("tube,1,")) && spectrum.lines().any(|l| l.starts_with("particle,1,")));
}

/// Positions and velocities after `steps` on a pool of `threads`.
fn trajectory(threads: usize, steps: u64) -> Vec<u64> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        let mut dem = Dem::new(small_setup(), "t").unwrap();
        dem.advance(steps).unwrap();
        let mut bits: Vec<(u64, [f64; 3], [f64; 3])> = (0..dem.p.len()).map(|i| (dem.p.id[i], dem.p.pos[i], dem.p.vel[i])).collect();
        bits.sort_by_key(|b| b.0);
        bits.iter().flat_map(|b| [b.0].into_iter().chain(b.1.iter().chain(b.2.iter()).map(|x| x.to_bits()))).collect()
    })
}

#[test]
fn trajectories_are_bit_identical_for_any_thread_count() {
    // 40 000 steps of 2 µs: the bank is filling and particles hit tubes and each other.
    let one = trajectory(1, 40_000);
    let two = trajectory(2, 40_000);
    let three = trajectory(3, 40_000);
    assert!(one.len() > 7 * 1000, "{} particles", one.len() / 7);
    assert!(one == two && one == three, "trajectories depend on the thread count");
}

#[test]
fn advancing_in_one_call_or_step_by_step_gives_the_same_bits() {
    // `advance` leaves each step's reactions and closing half kick to the next step's opening
    // pass; `step` completes every step. The trajectories and impacts must be the same bits.
    let run = |by_step: bool| {
        let mut setup = small_setup();
        // Impacts and field samples (which settle the pending kick) from the start.
        setup.probes.warmup = 0.0;
        let mut dem = Dem::new(setup, "t").unwrap();
        if by_step {
            for _ in 0..20_000 {
                dem.step().unwrap();
            }
        } else {
            dem.advance(20_000).unwrap();
        }
        let p = &dem.p;
        let bits: Vec<u64> = (0..p.len()).flat_map(|i| p.pos[i].into_iter().chain(p.vel[i]).chain(p.omega[i]).chain(p.force[i]).map(f64::to_bits)).collect();
        (p.len(), bits, dem.impacts.iter().map(|m| m.v_normal.to_bits()).collect::<Vec<_>>())
    };
    let (a, b) = (run(true), run(false));
    assert!(a.0 > 100 && a.2.len() > 100, "{} particles, {} impacts", a.0, a.2.len());
    assert!(a == b, "advance and step by step differ");
}

/// (mean, q50, q90) of the normal impact velocity of tube and particle impacts.
fn impact_stats(setup: DemSetup, duration: f64) -> [f64; 6] {
    let mut dem = Dem::new(setup, "t").unwrap();
    let steps = (duration / dem.setup.time_step).ceil() as u64;
    dem.advance(steps).unwrap();
    let sp = spectrum(&dem, &[0.5, 0.9]);
    let tube = sp.iter().find(|r| r.target == "tube" && r.row == 0).unwrap();
    let part = sp.iter().find(|r| r.target == "particle" && r.row == 0).unwrap();
    assert!(tube.count > 2000 && part.count > 2000, "too few impacts: {} tube, {} particle", tube.count, part.count);
    [tube.mean, tube.quantiles[0], tube.quantiles[1], part.mean, part.quantiles[0], part.quantiles[1]]
}

fn stiffer(mut s: DemSetup, factor: f64) -> DemSetup {
    s.particle.youngs_modulus *= factor;
    s.wall.youngs_modulus *= factor;
    // Same safety on the new limit: Δt ∝ E^(−2/5).
    s.time_step *= factor.powf(-0.4);
    s
}

/// Measured (2 rows, 0.2 s, impacts ≥ 0.1 m/s): −1.9 to −3.7 %. With the impact threshold at
/// 0.05 m/s the slow re-contacts in the dense caps on the tubes (whose number depends on the
/// contact stiffness) pull the medians down by up to 5.3 %, hence the 0.1 m/s default.
#[test]
fn impact_statistics_change_under_5_percent_for_a_tenfold_modulus() {
    let base = small_setup();
    let a = impact_stats(base.clone(), 0.2);
    let b = impact_stats(stiffer(base, 10.0), 0.2);
    let names = ["tube mean", "tube q50", "tube q90", "particle mean", "particle q50", "particle q90"];
    for k in 0..6 {
        let rel = (b[k] / a[k] - 1.0).abs();
        assert!(rel < 0.05, "{}: {} (E) vs {} (10 E): {:.1} %", names[k], a[k], b[k], 100.0 * rel);
    }
}

#[test]
#[ignore = "slow: full cold-test geometry, 0.6 s at E and 10 E (≈ 20 min on 2 cores)"]
fn impact_statistics_full_bank_tenfold_modulus() {
    let loaded = load(&common::root().join("studies/dem_cold_test.toml")).unwrap();
    let Study::Dem(s) = loaded.study else { panic!() };
    let base = s.setup("cold").unwrap();
    let a = impact_stats(base.clone(), s.run.duration);
    let b = impact_stats(stiffer(base, 10.0), s.run.duration);
    for k in 0..6 {
        assert!((b[k] / a[k] - 1.0).abs() < 0.05, "statistic {k}: {} vs {}", a[k], b[k]);
    }
}

#[test]
fn tube_bank_model_is_a_deterministic_simulator() {
    let setup = small_setup();
    let model = TubeBankModel::new(setup, 0.15, vec![0.02, 0.05], 0.005).unwrap();
    assert_eq!(model.space().len(), 4);
    let theta = model.space().nominal();
    let y1 = model.simulate(&theta).unwrap();
    let y2 = model.simulate(&theta).unwrap();
    assert_eq!(y1, y2);
    assert_eq!(y1.len(), model.outputs().len());
    // Falling particles: downward mean velocity at both heights; some mass leaves; tube
    // impacts happen.
    assert!(y1[0] < 0.0 && y1[1] < 0.0, "{y1:?}");
    assert!(y1[2] > 0.0, "mass flow {y1:?}");
    // More elastic tubes → faster rebounds → higher impact-velocity quantiles downstream.
    let mut soft = theta.clone();
    soft[partlife::dem::model::theta::RESTITUTION_PW] = 0.3;
    soft[partlife::dem::model::theta::RESTITUTION_PP] = 0.3;
    let y3 = model.simulate(&soft).unwrap();
    let q90 = model.outputs().iter().position(|o| o.name == "particle_v_normal_q90").unwrap();
    assert!(y3[q90] < y1[q90], "e = 0.3 gives particle q90 {} ≥ e = 0.7's {}", y3[q90], y1[q90]);
    // Out of bounds θ is refused before simulating.
    assert!(model.simulate(&[1.5, 0.7, 0.3, 0.3]).is_err());
}

/// Spoils the scratch DEM study and checks the bad-input contract (exit 2, one line naming the
/// file and key, nothing under reports/).
fn bad(from: &str, to: &str, expect: &[&str]) {
    Scratch::new().expect_bad_study("studies/dem_cold_test.toml", from, to, expect);
}

#[test]
fn bad_input_overlapping_tubes() {
    bad("horizontal_pitch = 0.05", "horizontal_pitch = 0.02", &["geometry", "overlap"]);
}

#[test]
fn bad_input_slab_thinner_than_largest_particle() {
    bad("slab = 0.005", "slab = 0.001", &["geometry.slab", "thinner than the largest particle"]);
}

#[test]
fn bad_input_time_step_above_stable_limit() {
    bad("time_step = 2.0e-6", "time_step = 2.0e-5", &["run.time_step", "stable limit"]);
}

#[test]
fn bad_input_restitution_outside_unit_interval() {
    bad("restitution = 0.7", "restitution = 1.2", &["contact.particle_particle.restitution", "(0, 1]"]);
    bad("restitution = 0.7", "restitution = 0.0", &["contact.particle_particle.restitution", "(0, 1]"]);
}

#[test]
fn bad_input_negative_friction() {
    bad("[contact.particle_wall]\nrestitution = 0.7\nfriction = 0.3", "[contact.particle_wall]\nrestitution = 0.7\nfriction = -0.1", &[
        "contact.particle_wall.friction",
        "≥ 0",
    ]);
}

#[test]
fn bad_input_insertion_region_outside_domain() {
    bad("height = 0.015", "height = 0.5", &["inlet.region"]);
}

#[test]
fn bad_input_unknown_key_and_bad_distribution() {
    bad("[inlet]", "[inlet]\nmass_flow = 3", &["mass_flow"]);
    bad("distribution = \"normal\"", "distribution = \"gamma\"", &["gamma"]);
}

#[test]
fn blow_up_stops_with_numerical_error_naming_step_and_particle() {
    // A stiff-enough step for the validation but a far too soft contact for the impact speed:
    // particles sink through each other and the overlap guard fires.
    let mut s = small_setup();
    s.particle.youngs_modulus = 1e4;
    s.wall.youngs_modulus = 1e4;
    s.max_speed = 0.01;
    s.time_step = 0.5 * s.time_step_limit();
    s.inlet.as_mut().unwrap().velocity = 3.0;
    let mut dem = Dem::new(s, "t").unwrap();
    let err = dem.advance(200_000).unwrap_err();
    let msg = err.to_string();
    assert!(!err.is_bad_input(), "{msg}");
    assert!(msg.contains("blow-up at step") && msg.contains("particle"), "{msg}");
}

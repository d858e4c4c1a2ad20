//! The calibration loop end to end: the crush calibration recovers the synthetic truth inside
//! its 90 % credible intervals (fast settings), a rerun reuses every cached run and gives the
//! same posterior, the generator's truth is never an input, the loop on an analytic model, and
//! bad input at load.

mod common;
use common::{Scratch, root};
use partlife::calibrate::data::{Observations, load_curves, reduce_curves};
use partlife::calibrate::data::Aggregated;
use partlife::calibrate::pipeline::{PipelineOptions, calibrate};
use partlife::error::Result;
use partlife::model::{OutputSpec, Simulator};
use partlife::params::{Param, ParamSpace};

/// The generator's truth of a case, read here by the test (never by fitting code).
fn truth(case_file: &str, name: &str) -> f64 {
    let text = std::fs::read_to_string(root().join("datasets/synth_curves.toml")).unwrap();
    let t: toml::Table = toml::from_str(&text).unwrap();
    let case = t["case"].as_array().unwrap().iter().find(|c| c["file"].as_str() == Some(case_file)).unwrap();
    case["truth"][name].as_float().unwrap()
}

fn column(csv: &str, name: &str) -> Vec<String> {
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = head.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
    lines.map(|l| l.split(',').nth(k).unwrap().to_string()).collect()
}

/// Fast settings: 20 design runs, one refinement round, short chains.
fn fast(study: &str) -> String {
    common::edited(study, &[("design = 32", "design = 20"), ("rounds = 6", "rounds = 1"), ("points = 8\n", "points = 6\n"), ("steps = 20000", "steps = 2000"), ("burn_in = 5000", "burn_in = 800"), ("check = 32", "check = 4")])
}

#[test]
fn crush_calibration_recovers_the_truth_and_a_rerun_reuses_every_run() {
    let s = Scratch::new();
    let study = "studies/calibrate_gen3_rt.toml";
    s.write(study, &fast(&s.read(study)));
    let out = s.run(&["run", study, "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let dir = "reports/calibrate_gen3_rt";
    for f in ["parameters.csv", "correlation.csv", "chains.csv", "observations.csv", "runs.csv", "rounds.csv", "failures.csv", "curves.csv", "summary.md", "manifest.json"] {
        assert!(s.path(&format!("{dir}/{f}")).is_file(), "{f} missing");
    }
    for fig in ["calibration_fit", "calibration_residuals", "calibration_corner", "calibration_trace"] {
        for ext in ["svg", "png", "pdf"] {
            assert!(s.path(&format!("{dir}/{fig}.{ext}")).is_file(), "{fig}.{ext} missing");
        }
    }
    let params = s.read(&format!("{dir}/parameters.csv"));
    let (names, q05, q95, ratio) = (column(&params, "name"), column(&params, "q05"), column(&params, "q95"), column(&params, "width_ratio"));
    let mut checked = 0;
    for k in 0..names.len() {
        let (lo, hi, w): (f64, f64, f64) = (q05[k].parse().unwrap(), q95[k].parse().unwrap(), ratio[k].parse().unwrap());
        let t = truth("crush_curves_gen3_rt.csv", &names[k]);
        if w < 0.9 {
            assert!(t >= lo && t <= hi, "{}: truth {t:e} outside the 90 % interval [{lo:e}, {hi:e}]", names[k]);
            checked += 1;
        }
    }
    assert!(checked >= 2, "at least G and A are identified ({checked} checked)");
    // The generator's settings are not an input of the run.
    let manifest: serde_json::Value = serde_json::from_str(&s.read(&format!("{dir}/manifest.json"))).unwrap();
    let inputs = manifest["inputs"].to_string();
    assert!(inputs.contains("crush_curves_gen3_rt.csv") && !inputs.contains("synth_curves"), "{inputs}");
    // The curves' test temperature, where it came from, and how the file was read: in the
    // manifest's record of the curve file, grid.csv and the summary.
    let read = manifest["inputs"].as_array().unwrap().iter().find(|i| i["path"].as_str().unwrap().ends_with("crush_curves_gen3_rt.csv")).unwrap()["read"].to_string();
    assert!(read.contains("test temperature: 20 °C (the study's data.temperature_c)"), "{read}");
    assert!(column(&s.read(&format!("{dir}/grid.csv")), "test_temperature_c").iter().all(|t| t.parse::<f64>().unwrap() == 20.0));
    let summary = s.read(&format!("{dir}/summary.md"));
    assert!(summary.contains("Data: 8 force–displacement curves (`crush_curves_gen3_rt.csv`) measured at 20 °C") && summary.contains("test temperature: 20 °C (the study's data.temperature_c)"), "{summary}");
    let ev = &manifest["evaluations"];
    let requested = ev["simulator_requested"].as_u64().unwrap();
    assert!(requested >= 20 && ev["simulator_runs"].as_u64().unwrap() + ev["simulator_cache_hits"].as_u64().unwrap() == requested, "{ev}");

    // Rerun: every simulator run comes from the cache, the posterior is the same.
    let out = s.run(&["run", study, "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let manifest: serde_json::Value = serde_json::from_str(&s.read(&format!("{dir}/manifest.json"))).unwrap();
    assert_eq!(manifest["evaluations"]["simulator_runs"].as_u64(), Some(0), "{}", manifest["evaluations"]);
    assert_eq!(s.read(&format!("{dir}/parameters.csv")), params);
}

/// y_j = θ₀ exp(−θ₁ x_j): cheap, smooth, two identified parameters.
struct Decay {
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
    x: Vec<f64>,
}

impl Simulator for Decay {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, t: &[f64]) -> Result<Vec<f64>> {
        Ok(self.x.iter().map(|x| t[0] * (-t[1] * x).exp()).collect())
    }
}

/// Observations of every output of `clean` plus `noise`, in replicates of all outputs (group
/// i / outputs), each with sd `sigma`.
fn replicates(clean: &[f64], noise: &[f64], sigma: f64) -> Observations {
    let m = clean.len();
    Observations { values: noise.iter().enumerate().map(|(i, n)| clean[i % m] + n).collect(), sigma: vec![sigma; noise.len()], output: (0..noise.len()).map(|i| i % m).collect(), group: (0..noise.len()).map(|i| i / m).collect() }
}

#[test]
fn loop_on_an_analytic_model_recovers_the_truth_and_refines_until_the_emulator_is_good() {
    let x: Vec<f64> = (0..6).map(|i| 0.4 * i as f64).collect();
    let model = Decay {
        space: ParamSpace::new(vec![Param::uniform("amplitude", "-", 0.5, 2.0, 1.0), Param::uniform("rate", "-", 0.1, 1.5, 0.5)]).unwrap(),
        outputs: (0..6).map(|i| OutputSpec::new(format!("y{i}"), "-")).collect(),
        x,
    };
    let truth = [1.3, 0.7];
    let clean = model.simulate(&truth).unwrap();
    // Three replicates per output with fixed noise (±0.02).
    let obs = replicates(&clean, &[0.02, -0.015, 0.01, -0.02, 0.005, 0.0, 0.012, -0.008, 0.018, -0.01, 0.0, 0.007, -0.004, 0.016, -0.019, 0.003, 0.011, -0.013], 0.02);
    let opts = PipelineOptions { design: 10, rounds: 4, points: 4, tolerance: 0.3, steps: 2000, burn_in: 500, check: 6, walkers: 16, ..PipelineOptions::default() };
    let cal = calibrate(&model, &obs, &opts, 7, None, &|_| {}).unwrap();
    for (k, t) in truth.iter().enumerate() {
        let mut v = cal.chains.flat(k);
        v.sort_by(f64::total_cmp);
        let (lo, hi) = (v[v.len() / 20], v[v.len() * 19 / 20]);
        assert!(*t >= lo && *t <= hi, "θ{k}: truth {t} outside [{lo}, {hi}]");
        assert!(hi - lo < 0.2, "θ{k}: interval [{lo}, {hi}] too wide for σ = 0.02");
        assert!(cal.diagnostics[k].r_hat < 1.02 && cal.diagnostics[k].ess_bulk > 400.0, "{:?}", cal.diagnostics[k]);
    }
    // Refinement drove the emulator error down to the tolerance and the check agrees.
    let last = cal.rounds.last().unwrap();
    assert!(last.epsilon.1 <= 0.3, "ε90 = {}", last.epsilon.1);
    assert!(cal.rounds.len() >= 2 && cal.rounds[0].epsilon.1 > last.epsilon.1, "{:?}", cal.rounds.iter().map(|r| r.epsilon).collect::<Vec<_>>());
    assert!(cal.check.emulator_error.iter().all(|e| *e < 0.5), "{:?}", cal.check.emulator_error);
    assert!(cal.failures.is_empty());
    // The combined data: 6 outputs, σ/√3 each.
    let agg = Aggregated::new(&obs, 0.0);
    assert_eq!(agg.output, (0..6).collect::<Vec<_>>());
    assert!(agg.sd.iter().all(|s| (s - 0.02 / 3f64.sqrt()).abs() < 1e-12));
}

/// [`Decay`] plus a deterministic run-to-run scatter of sd `tau` that changes completely with
/// the last digits of θ — the crush FE's fracture, which starts in whichever element fails
/// first, behaves so: no emulator can learn it, and it is noise to the likelihood.
struct Jittery(Decay, f64);

impl Simulator for Jittery {
    fn space(&self) -> &ParamSpace {
        self.0.space()
    }
    fn outputs(&self) -> &[OutputSpec] {
        self.0.outputs()
    }
    fn simulate(&self, t: &[f64]) -> Result<Vec<f64>> {
        let y = self.0.simulate(t)?;
        Ok(y.iter().enumerate().map(|(j, v)| v + self.1 * std::f64::consts::SQRT_2 * (1.0e6 * (t[0] + 1.7 * t[1]) + 2.3 * j as f64).sin()).collect())
    }
}

/// With a simulator that scatters by more than the data resolve (τ ≈ 4 × the sd of the combined
/// observations), the loop converges and its checks pass — the scatter is noise in the
/// likelihood, not an emulator failure (issue 32, item 9: the old check measured the emulator
/// against the data's resolution alone and warned here) — and the posterior is the one of the
/// smooth model with the scatter as noise, computed independently on a grid.
#[test]
fn a_simulator_scattering_more_than_the_data_resolve_is_calibrated_without_false_warnings() {
    let x: Vec<f64> = (0..4).map(|i| 0.6 * i as f64).collect();
    let decay = Decay {
        space: ParamSpace::new(vec![Param::uniform("amplitude", "-", 0.5, 2.0, 1.0), Param::uniform("rate", "-", 0.1, 1.5, 0.5)]).unwrap(),
        outputs: (0..4).map(|i| OutputSpec::new(format!("y{i}"), "-")).collect(),
        x: x.clone(),
    };
    let tau = 0.05;
    let clean = decay.simulate(&[1.3, 0.7]).unwrap();
    // Three replicates per output, sd 0.02: the combined sd is 0.0115, a quarter of τ.
    let obs = replicates(&clean, &[0.02, -0.015, 0.01, -0.02, 0.005, 0.0, 0.012, -0.008, 0.018, -0.01, 0.0, 0.007], 0.02);
    let model = Jittery(decay, tau);
    let opts = PipelineOptions { design: 24, rounds: 6, points: 6, tolerance: 0.5, steps: 8000, burn_in: 2000, check: 32, walkers: 32, ..PipelineOptions::default() };
    let cal = calibrate(&model, &obs, &opts, 11, None, &|_| {}).unwrap();
    assert!(cal.warnings.is_empty(), "{:?}\nrounds {:?}\nz {:?} (limit {}), shift {:?} (ESS {})", cal.warnings, cal.rounds.iter().map(|r| r.epsilon).collect::<Vec<_>>(), cal.check.z_rms, cal.check.z_limit, cal.check.shift, cal.check.shift_ess);
    // The scatter is found on every output: τ over the combined sd is 0.05 / 0.0115 = 4.3; the
    // nugget's maximum-likelihood estimate from ~40 runs comes out between 2.2 and 4.5 here (the
    // GP takes part of the scatter as short-scale variation), and each output is reported as
    // scattering by more than the data resolve.
    let agg = Aggregated::new(&obs, 0.0);
    for o in 0..4 {
        let want = tau / agg.sd[o];
        eprintln!("output {o}: scatter {:.2} (true {want:.2})", cal.check.scatter[o]);
        assert!(cal.check.scatter[o] > 1.0 && cal.check.scatter[o] < 1.2 * want, "output {o}: scatter {} vs {want}", cal.check.scatter[o]);
    }
    // The grid posterior of the smooth model with variance sd² + τ² per combined observation.
    let (n, (a0, a1), (r0, r1)) = (400, (0.5, 2.0), (0.1, 1.5));
    let (mut w, mut ma, mut mr, mut ma2, mut mr2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut lps = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let (a, r) = (a0 + (a1 - a0) * (i as f64 + 0.5) / n as f64, r0 + (r1 - r0) * (j as f64 + 0.5) / n as f64);
            let lp: f64 = (0..4).map(|o| -0.5 * (agg.mean[o] - a * (-r * x[o]).exp()).powi(2) / (agg.sd[o].powi(2) + tau * tau)).sum();
            lps.push((a, r, lp));
        }
    }
    let top = lps.iter().map(|l| l.2).fold(f64::NEG_INFINITY, f64::max);
    for (a, r, lp) in lps {
        let p = (lp - top).exp();
        w += p;
        ma += p * a;
        mr += p * r;
        ma2 += p * a * a;
        mr2 += p * r * r;
    }
    let grid = [(ma / w, (ma2 / w - (ma / w).powi(2)).sqrt()), (mr / w, (mr2 / w - (mr / w).powi(2)).sqrt())];
    for (k, (mean, sd)) in grid.iter().enumerate() {
        let v = cal.chains.flat(k);
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let s = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
        eprintln!("θ{k}: chains {m:.4} ± {s:.4}, grid {mean:.4} ± {sd:.4}");
        // Measured: means within 0.3 grid sd, sds 0.74–0.82 of the grid's — narrower where the
        // nugget is underestimated (output 3 above). Bounds: half a grid sd, and a third.
        assert!((m - mean).abs() < 0.5 * sd, "θ{k}: posterior mean {m} vs grid {mean} (sd {sd})");
        assert!((s / sd - 1.0).abs() < 1.0 / 3.0, "θ{k}: posterior sd {s} vs grid {sd}");
    }
}

/// A simulator that fails in part of its space: failures are recorded, never abort.
struct Holey(Decay);

impl Simulator for Holey {
    fn space(&self) -> &ParamSpace {
        self.0.space()
    }
    fn outputs(&self) -> &[OutputSpec] {
        self.0.outputs()
    }
    fn simulate(&self, t: &[f64]) -> Result<Vec<f64>> {
        if t[1] > 1.3 {
            return Err(partlife::error::Error::numerical("holey", "unstable"));
        }
        self.0.simulate(t)
    }
}

#[test]
fn simulator_failures_are_recorded_not_fatal() {
    let model = Holey(Decay {
        space: ParamSpace::new(vec![Param::uniform("amplitude", "-", 0.5, 2.0, 1.0), Param::uniform("rate", "-", 0.1, 1.5, 0.5)]).unwrap(),
        outputs: (0..3).map(|i| OutputSpec::new(format!("y{i}"), "-")).collect(),
        x: vec![0.0, 0.5, 1.0],
    });
    let clean = model.0.simulate(&[1.0, 0.5]).unwrap();
    let obs = Observations { values: clean.clone(), sigma: vec![0.02; 3], output: vec![0, 1, 2], group: vec![0; 3] };
    let opts = PipelineOptions { design: 16, rounds: 0, steps: 400, burn_in: 100, check: 2, walkers: 8, ..PipelineOptions::default() };
    let cal = calibrate(&model, &obs, &opts, 1, None, &|_| {}).unwrap();
    assert!(!cal.failures.is_empty(), "the design crosses the failing region");
    assert!(cal.failures.iter().all(|(t, e)| t[1] > 1.3 && e.contains("unstable")));
}

#[test]
fn curve_reduction_scales_to_the_reference_diameter() {
    let curves = load_curves(&root().join("datasets/crush_curves_gen3_rt.csv"), Some(20.0)).unwrap();
    assert_eq!(curves.len(), 8);
    let d0 = 0.9e-3;
    let red = reduce_curves(std::path::Path::new("x.csv"), &curves, d0, 8, 0.7, 0.02, Default::default()).unwrap();
    // Scaling: F(δ; D) → F·(D₀/D)² at δ·D₀/D.
    let c = &curves[0];
    let n = &red.curves[0];
    let s = d0 / c.diameter;
    assert!((n.displacement[40] - c.displacement[40] * s).abs() < 1e-15 && (n.force[40] - c.force[40] * s * s).abs() < 1e-9);
    // Grid strictly below every particle's fracture.
    let fmin = red.fractures.iter().flatten().map(|f| f.1).fold(f64::INFINITY, f64::min);
    assert!(red.grid.iter().all(|g| *g < fmin) && red.grid.len() == 8);
    // 8 grid forces + peak + fracture per broken particle.
    let broken = red.fractures.iter().flatten().count();
    assert_eq!(red.observations.len(), 8 * 8 + 2 * broken);
    assert!(red.observations.sigma.iter().all(|s| *s > 0.0));
}

/// Every curve states its test temperature: a temperature column (one value per particle) or the
/// study's `temperature_c` for curves without one; a calibration fits one temperature, so curves
/// at several are refused, and the reduction keeps the temperature its report states.
#[test]
fn curves_state_their_test_temperature_and_a_calibration_fits_one() {
    use partlife::fracture::FractureParams;
    let s = Scratch::new();
    let rt = std::fs::read_to_string(root().join("datasets/crush_curves_gen3_rt.csv")).unwrap();
    // A column: particles 1–4 at 20 °C, the others at 800 °C.
    let with = |t: &dyn Fn(&str) -> &'static str| -> String {
        rt.lines().enumerate().map(|(i, l)| if i == 0 { format!("{l},temperature_c\n") } else { format!("{l},{}\n", t(l.split(',').next().unwrap())) }).collect()
    };
    s.write("datasets/two.csv", &with(&|p| if p.parse::<u32>().unwrap() <= 4 { "20" } else { "800" }));
    let curves = load_curves(&s.path("datasets/two.csv"), None).unwrap();
    assert_eq!(curves.iter().map(|c| c.temperature_c).collect::<Vec<_>>(), [20.0, 20.0, 20.0, 20.0, 800.0, 800.0, 800.0, 800.0]);
    let e = reduce_curves(&s.path("datasets/two.csv"), &curves, 1e-3, 8, 0.8, 0.02, FractureParams::default()).unwrap_err().to_string();
    assert!(e.contains("two.csv") && e.contains("20 °C (4) and 800 °C (4) (20 °C: particles 1, 2, 3, 4; 800 °C: particles 5, 6, 7, 8)") && e.contains("one temperature"), "{e}");
    // A curve file without its displacement column: the example names a displacement header,
    // not a diameter's.
    let header = rt.lines().next().unwrap();
    let drop = header.split(',').position(|h| h == "displacement_m").unwrap();
    let cut: String = rt.lines().map(|l| l.split(',').enumerate().filter(|(i, _)| *i != drop).map(|(_, c)| c).collect::<Vec<_>>().join(",") + "\n").collect();
    s.write("datasets/no_s.csv", &cut);
    let e = load_curves(&s.path("datasets/no_s.csv"), Some(20.0)).unwrap_err().to_string();
    assert!(e.contains("missing column displacement (a length, e.g. `displacement_m`, `s [mm]`)"), "{e}");
    // One temperature: kept by the reduction.
    s.write("datasets/hot.csv", &with(&|_| "800"));
    let hot = load_curves(&s.path("datasets/hot.csv"), Some(800.0)).unwrap();
    assert_eq!(reduce_curves(&s.path("datasets/hot.csv"), &hot, 1e-3, 8, 0.8, 0.02, FractureParams::default()).unwrap().temperature_c, 800.0);
    // One particle's curve at two temperatures names the row.
    let mixed: String = with(&|_| "800").lines().enumerate().map(|(i, l)| if i == 3 { format!("{},20\n", l.rsplit_once(',').unwrap().0) } else { format!("{l}\n") }).collect();
    s.write("datasets/mixed.csv", &mixed);
    let e = load_curves(&s.path("datasets/mixed.csv"), None).unwrap_err().to_string();
    assert!(e.contains("row 3 (line 4)") && e.contains("particle 1's curve spans 20–800 °C"), "{e}");
    // A furnace's log that wanders by a kelvin or two along a curve is one temperature, its
    // mean; so are curves a few kelvin apart.
    let wander: String = rt.lines().enumerate().map(|(i, l)| if i == 0 { format!("{l},T [°C]\n") } else { format!("{l},{}\n", 799.0 + (i % 3) as f64) }).collect();
    s.write("datasets/wander.csv", &wander);
    let curves = load_curves(&s.path("datasets/wander.csv"), None).unwrap();
    assert!(curves.iter().all(|c| (c.temperature_c - 800.0).abs() < 1.0), "{:?}", curves.iter().map(|c| c.temperature_c).collect::<Vec<_>>());
    let t = reduce_curves(&s.path("datasets/wander.csv"), &curves, 1e-3, 8, 0.8, 0.02, FractureParams::default()).unwrap().temperature_c;
    assert!((t - 800.0).abs() < 1.0, "{t}");
    // A study's value that contradicts a column that gives every particle's is refused.
    let e = load_curves(&s.path("datasets/hot.csv"), Some(20.0)).unwrap_err().to_string();
    assert!(e.contains("column `temperature_c`") && e.contains("800 °C") && e.contains("says 20 °C: which is right?"), "{e}");
    // Neither a column nor a value: refused.
    let e = load_curves(&root().join("datasets/crush_curves_gen3_rt.csv"), None).unwrap_err().to_string();
    assert!(e.contains("states no test temperature"), "{e}");
}

#[test]
fn bad_calibration_studies_fail_at_load_naming_file_and_key() {
    let s = Scratch::new();
    let study = "studies/calibrate_gen3_rt.toml";
    let original = s.read(study);
    let cases: [(&str, &str, &[&str]); 8] = [
        ("name = \"t\"", "name = \"tt\"", &["param[3].name", "tt"]),
        ("lower = 0.6\nupper = 1.2", "lower = 1.2\nupper = 0.6", &["param[2]", "lower < upper"]),
        ("name = \"a\"\nlower = 0.6\nupper = 1.2", "name = \"a\"\nlower = 0.6\nupper = 1.2\nprior = { kind = \"normal\", mean = 0.9, sd = 0.0 }", &["param[2]", "sd > 0"]),
        ("name = \"g\"", "name = \"k1\"", &["param[1].name", "twice"]),
        ("design = 32", "design = 4", &["calibration.design"]),
        ("file = \"../datasets/crush_curves_gen3_rt.csv\"", "file = \"../datasets/missing.csv\"", &["missing.csv"]),
        // The curves' test temperature: neither a column nor the key is refused, as is an
        // implausible one.
        ("temperature_c = 20   #", "# temperature_c = 20", &["crush_curves_gen3_rt.csv", "states no test temperature", "data.temperature_c = 20"]),
        ("temperature_c = 20   #", "temperature_c = 3000   #", &["data.temperature_c", "[-273.15, 2100] °C"]),
    ];
    for (from, to, expect) in cases {
        s.write(study, &original);
        s.expect_bad_study(study, from, to, expect);
    }
    // A non-finite force names the row.
    s.write(study, &original);
    let data = s.read("datasets/crush_curves_gen3_rt.csv");
    let mut lines: Vec<String> = data.lines().map(String::from).collect();
    lines[5] = lines[5].rsplitn(2, ',').nth(1).unwrap().to_string() + ",nan";
    s.write("datasets/crush_curves_gen3_rt.csv", &(lines.join("\n") + "\n"));
    let out = s.run(&["run", study, "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    for e in ["crush_curves_gen3_rt.csv", "row 5 (line 6)", "force_n", "finite"] {
        assert!(out.stderr.contains(e), "message lacks \"{e}\": {}", out.stderr);
    }
    assert!(s.report_files().is_empty(), "a failed run wrote {:?}", s.report_files());
}

#[test]
fn observations_must_match_the_model_outputs_in_name_and_unit() {
    let s = Scratch::new();
    let study = "studies/calibrate_dem_bad.toml";
    let text = r#"kind = "calibrate"
label = "DEM"
[data]
kind = "observations"
file = "../datasets/profile.csv"
[model]
kind = "dem"
study = "dem_cold_test.toml"
duration = 0.8
heights = [0.1, 0.2]
window = 0.01
[[param]]
name = "restitution_pw"
lower = 0.3
upper = 0.95
[calibration]
design = 2
walkers = 8
"#;
    s.write(study, text);
    s.write("datasets/profile.csv", "output,unit,value,sd\nvz_at_100mm,m/s,-0.8,0.05\nmass_flow,g/s,37.5,1.0\n");
    let out = s.run(&["run", study, "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("profile.csv") && out.stderr.contains("row 2") && out.stderr.contains("kg/s"), "{}", out.stderr);
    s.write("datasets/profile.csv", "output,unit,value,sd\nvz_at_150mm,m/s,-0.8,0.05\n");
    let out = s.run(&["run", study, "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("vz_at_150mm") && out.stderr.contains("not an output"), "{}", out.stderr);
    s.write("datasets/profile.csv", "output,unit,value,sd\nvz_at_100mm,m/s,-0.8,0.05\n");
    let out = s.run(&["run", study, "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("calibration.design"), "{}", out.stderr);
    s.write(study, &common::edited(&text, &[("restitution_pw", "stiffness")]));
    let out = s.run(&["run", study, "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("param[0].name") && out.stderr.contains("stiffness"), "{}", out.stderr);
}

/// The DEM calibration end to end on a narrower rig (half the particles) with a short design:
/// the generator writes the "measured" profile from another particle stream, and the fit puts
/// the true particle–wall restitution inside its 90 % interval. The full study
/// (`studies/calibrate_dem.toml`, ≈ 1 min) is `dem_calibration_full_study` below.
#[test]
fn dem_calibration_recovers_the_wall_restitution() {
    let s = Scratch::new();
    let rig = std::fs::read_to_string(root().join("studies/dem_rig.toml")).unwrap();
    s.write("studies/dem_rig.toml", &common::edited(&rig, &[("width = 0.1\n", "width = 0.05\n")]));
    let synth = std::fs::read_to_string(root().join("datasets/synth_dem.toml")).unwrap();
    s.write("datasets/synth_dem.toml", &common::edited(&synth, &[("duration = 0.7 ", "duration = 0.55 ")]));
    let out = s.run(&["datasets", "synth-dem", "--settings", "datasets/synth_dem.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let data = s.read("datasets/dem_rig_profile.csv");
    assert_eq!(data.lines().count(), 8, "{data}");
    assert!(data.starts_with("output,unit,value,sd\nvz_at_15mm,m/s,") && data.contains("\nmass_flow,kg/s,"), "{data}");

    let study = std::fs::read_to_string(root().join("studies/calibrate_dem.toml")).unwrap();
    let fast = common::edited(&study, &[("design = 16", "design = 10"), ("rounds = 2", "rounds = 0"), ("steps = 10000", "steps = 3000"), ("burn_in = 2500", "burn_in = 1000"), ("check = 4", "check = 2")]);
    s.write("studies/calibrate_dem.toml", &fast);
    let out = s.run(&["run", "studies/calibrate_dem.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let dir = "reports/calibrate_dem";
    for fig in ["calibration_fit", "calibration_residuals", "calibration_corner", "calibration_trace"] {
        assert!(s.path(&format!("{dir}/{fig}.pdf")).is_file(), "{fig}.pdf missing");
    }
    let truth: toml::Table = toml::from_str(&synth).unwrap();
    let e_true = truth["truth"]["restitution_pw"].as_float().unwrap();
    let params = s.read(&format!("{dir}/parameters.csv"));
    let names = column(&params, "name");
    let k = names.iter().position(|n| n == "restitution_pw").unwrap();
    let (lo, hi, w): (f64, f64, f64) = (column(&params, "q05")[k].parse().unwrap(), column(&params, "q95")[k].parse().unwrap(), column(&params, "width_ratio")[k].parse().unwrap());
    assert!(lo <= e_true && e_true <= hi, "true e_pw {e_true} outside [{lo}, {hi}]");
    assert!(w < 0.5, "the profile determines e_pw: posterior/prior sd {w}");
    let manifest = s.read(&format!("{dir}/manifest.json"));
    assert!(manifest.contains("dem_rig_profile.csv") && manifest.contains("dem_rig.toml") && !manifest.contains("synth_dem"), "{manifest}");
    // The document opens with the answer, counted from parameters.csv's identifiability column,
    // each identified parameter with its posterior mean and interval and each other with its note,
    // and the fit figure on its first page.
    let summary = s.read(&format!("{dir}/summary.md"));
    let answer = summary.split("## Answer\n\n").nth(1).and_then(|t| t.split("\n\n").next()).unwrap_or_else(|| panic!("no answer in\n{summary}"));
    let notes = column(&params, "identifiability");
    let identified = notes.iter().filter(|n| n.is_empty() || *n == "\"\"").count();
    let head = match identified {
        i if i == names.len() => format!("**Every one of the {} parameters is identified by these data**", names.len()),
        0 => format!("**None of the {} parameters is identified by these data**", names.len()),
        i => format!("**{i} of the {} parameters {} identified by these data**", names.len(), if i == 1 { "is" } else { "are" }),
    };
    assert!(answer.starts_with(&head), "{answer}");
    let mean: f64 = column(&params, "posterior_mean")[k].parse().unwrap();
    assert_eq!(answer.contains(&format!("`restitution_pw` = {mean:.3e} [{lo:.3e}, {hi:.3e}]")), notes[k].is_empty() || notes[k] == "\"\"", "{answer}");
    assert!(answer.ends_with("observations lie inside their 90 % posterior-predictive interval."), "{answer}");
    let (_, figures) = common::first_page(&s.path(dir));
    assert_eq!(figures, ["calibration_fit"]);
}

#[test]
#[ignore = "slow: the full DEM calibration study, about 1–2 min"]
fn dem_calibration_full_study() {
    let s = Scratch::new();
    for f in ["studies/dem_rig.toml", "studies/calibrate_dem.toml", "datasets/dem_rig_profile.csv"] {
        s.write(f, &std::fs::read_to_string(root().join(f)).unwrap());
    }
    let out = s.run(&["run", "studies/calibrate_dem.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let synth: toml::Table = toml::from_str(&std::fs::read_to_string(root().join("datasets/synth_dem.toml")).unwrap()).unwrap();
    let params = s.read("reports/calibrate_dem/parameters.csv");
    let names = column(&params, "name");
    for (k, n) in names.iter().enumerate() {
        let t = synth["truth"][n.as_str()].as_float().unwrap();
        let (lo, hi): (f64, f64) = (column(&params, "q05")[k].parse().unwrap(), column(&params, "q95")[k].parse().unwrap());
        assert!(lo <= t && t <= hi, "{n}: truth {t} outside [{lo}, {hi}]");
    }
}

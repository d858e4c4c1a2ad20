//! The study graph: a study that reads other studies' reports finds them under its own reports
//! root, uses them when they are current, and with `--no-deps` refuses naming every missing or
//! stale one at once (the runs themselves: `tests/temperature.rs`, slow, and the planner's unit
//! tests in `src/runner.rs`). The reports here are made by hand with their manifests, so no
//! calibration runs.

mod common;

use common::{Scratch, edited, root};

/// Posterior draws in the calibration's `chains.csv` format around `medians` (g, k1, a, t).
fn chains(medians: [f64; 4]) -> String {
    let mut out = String::from("step,walker,g,k1,a,t,log_posterior\n");
    for i in 0..4800 {
        let v: Vec<String> = medians.iter().enumerate().map(|(k, m)| format!("{}", m * (1.0 + 0.05 * ((i * (k + 3)) as f64).sin()))).collect();
        out.push_str(&format!("{},{},{},-1.0\n", i / 32, i % 32, v.join(",")));
    }
    out
}

/// A report of `study` written by hand: its manifest (the study's text, its inputs with their
/// hashes, as a run records them) and `files`.
fn report(s: &Scratch, root: &str, study: &str, inputs: &[&str], files: &[(&str, String)]) {
    let stem = study.trim_end_matches(".toml");
    let dir = s.path(&format!("{root}/{stem}"));
    std::fs::create_dir_all(&dir).unwrap();
    let hashed: Vec<serde_json::Value> = std::iter::once(format!("studies/{study}"))
        .chain(inputs.iter().map(|i| i.to_string()))
        .map(|p| serde_json::json!({ "path": p, "sha256": partlife::io::sha256_hex(&std::fs::read(s.path(&p)).unwrap()) }))
        .collect();
    let manifest = serde_json::json!({ "study_toml": s.read(&format!("studies/{study}")), "inputs": hashed });
    std::fs::write(dir.join("manifest.json"), serde_json::to_string_pretty(&manifest).unwrap()).unwrap();
    for (name, body) in files {
        std::fs::write(dir.join(name), body).unwrap();
    }
}

/// The shipped temperature study without its slow parts (held-out FE runs, breakage against
/// temperature), the studies it reads, and their reports under `reports/`, current.
fn scratch() -> Scratch {
    scratch_in("reports")
}

/// [`scratch`] with the reports under `root`.
fn scratch_in(reports: &str) -> Scratch {
    let s = Scratch::new();
    let study = std::fs::read_to_string(root().join("studies/temperature.toml")).unwrap();
    let head = &study[..study.find("\n# Held out:").expect("the shipped study's held-out block")];
    s.write("studies/temperature.toml", &format!("{head}\n"));
    for f in ["studies/calibrate_gen3_800c.toml", "studies/discrepancy_curves.toml", "datasets/crush_curves_gen3_800c.csv"] {
        std::fs::copy(root().join(f), s.path(f)).unwrap();
    }
    let f = partlife::phases::ILLUSTRATIVE_FILE;
    std::fs::copy(root().join("datasets").join(f), s.path("datasets").join(f)).unwrap();
    let params = "name,unit\ng,Pa\nk1,Pa\na,-\nt,Pa\n".to_string();
    let grid = |t: f64| format!("grid_displacement_m,reference_diameter_m,test_temperature_c\n1e-6,1e-3,{t}\n2e-6,1e-3,{t}\n");
    report(&s, reports, "calibrate_gen3_rt.toml", &["datasets/crush_curves_gen3_rt.csv"], &[("chains.csv", chains([42e9, 72e9, 0.90, 0.42e9])), ("parameters.csv", params.clone()), ("grid.csv", grid(20.0))]);
    let rt_parameters = format!("{reports}/calibrate_gen3_rt/parameters.csv");
    report(&s, reports, "calibrate_gen3_800c.toml", &["datasets/crush_curves_gen3_800c.csv", &rt_parameters], &[("chains.csv", chains([29e9, 48e9, 0.82, 0.31e9])), ("parameters.csv", params), ("grid.csv", grid(800.0))]);
    report(&s, reports, "discrepancy_curves.toml", &["datasets/crush_curves_gen3_rt.csv", "datasets/crush_curves_gen3_800c.csv"], &[("curve_evidence.csv", "round,candidate,median,q05,q95,named\n1,temperature,0.9489,0.9450,0.9510,yes\n".into())]);
    s
}

fn run(s: &Scratch, args: &[&str]) -> common::Out {
    let mut all = vec!["run", "studies/temperature.toml", "--quiet"];
    all.extend_from_slice(args);
    s.run(&all)
}

#[test]
fn current_reports_are_used_as_they_are() {
    let s = scratch();
    let out = run(&s, &["--no-deps"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(!out.stderr.contains("running"), "nothing runs first: {}", out.stderr);
    let manifest = s.read("reports/temperature/manifest.json");
    assert!(manifest.contains("reports/calibrate_gen3_800c/chains.csv") && manifest.contains("reports/discrepancy_curves/curve_evidence.csv"), "the reports read are inputs: {manifest}");
}

/// A calibrated state is at its data's temperature: declared at another than the one its
/// calibration's report states (`grid.csv`), the temperature study is refused, naming the key,
/// both temperatures and the report.
#[test]
fn a_calibration_declared_at_another_temperature_than_its_curves_is_refused() {
    let s = scratch();
    s.write("reports/calibrate_gen3_800c/grid.csv", "grid_displacement_m,reference_diameter_m,test_temperature_c\n1e-6,1e-3,750\n");
    let out = run(&s, &["--no-deps"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    for e in ["law.calibrations[1].temperature_c", "800 °C", "measured at 750 °C", "calibrate_gen3_800c/grid.csv"] {
        assert!(out.stderr.contains(e), "message lacks \"{e}\": {}", out.stderr);
    }
    assert!(!s.path("reports/temperature").exists());
}

#[test]
fn no_deps_names_every_missing_or_stale_prerequisite_at_once() {
    let s = scratch();
    // The 800 °C calibration's study file changes; the room-temperature calibration's data too,
    // which makes every study reading it stale.
    s.write("studies/calibrate_gen3_800c.toml", &format!("{}\n# edited\n", s.read("studies/calibrate_gen3_800c.toml")));
    s.write("datasets/crush_curves_gen3_rt.csv", &s.read("datasets/crush_curves_gen3_rt.csv").replacen("\n", "\n\n", 2));
    let out = run(&s, &["--no-deps"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert_eq!(out.stderr.trim().lines().count(), 1, "one message: {}", out.stderr);
    for e in [
        "studies/temperature.toml: prerequisites: 3 studies' reports are missing or stale (--no-deps)",
        "studies/calibrate_gen3_rt.toml (its input datasets/crush_curves_gen3_rt.csv changed since its report was written; read by law.calibrations[0].study of studies/temperature.toml)",
        "studies/calibrate_gen3_800c.toml (studies/calibrate_gen3_800c.toml changed since its report was written; read by law.calibrations[1].study",
        "studies/discrepancy_curves.toml (its input datasets/crush_curves_gen3_rt.csv changed since its report was written; read by softening.study",
    ] {
        assert!(out.stderr.contains(e), "lacks {e}: {}", out.stderr);
    }
    assert!(!s.path("reports/temperature").exists(), "nothing written");
}

#[test]
fn prerequisites_are_looked_for_under_the_same_reports_dir() {
    let s = scratch();
    let out = run(&s, &["--no-deps", "--reports-dir", "elsewhere"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("3 studies' reports are missing") && out.stderr.contains("its report elsewhere/calibrate_gen3_rt is missing"), "{}", out.stderr);
    // Reports there are found there, and the study's own report goes there.
    let s = scratch_in("elsewhere");
    let out = run(&s, &["--no-deps", "--reports-dir", "elsewhere"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(s.path("elsewhere/temperature/manifest.json").is_file());
}

#[test]
fn a_study_file_names_what_it_reads_or_a_file_not_both() {
    let s = scratch();
    let study = s.read("studies/temperature.toml");
    s.write("studies/temperature.toml", &edited(&study, &[("study = \"calibrate_gen3_rt.toml\"", "study = \"calibrate_gen3_rt.toml\", chains = \"x.csv\"")]));
    let out = run(&s, &[]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("law.calibrations[0]: give `study`") && out.stderr.contains("not both"), "{}", out.stderr);
    // A cycle: the room-temperature calibration compares itself with the 800 °C one, which
    // compares with it.
    s.write("studies/temperature.toml", &study);
    let rt = s.read("studies/calibrate_gen3_rt.toml");
    s.write("studies/calibrate_gen3_rt.toml", &format!("{rt}\n[compare]\nstudy = \"calibrate_gen3_800c.toml\"\nlabel = \"800\"\n"));
    let out = run(&s, &[]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("cycle: studies/calibrate_gen3_rt.toml → studies/calibrate_gen3_800c.toml → studies/calibrate_gen3_rt.toml"), "{}", out.stderr);
}

//! Bad input: each malformed input gets one clear message naming the file, the row/key and the
//! rule, exit code 2, no panic, and nothing written under reports/ (an earlier report stays
//! byte-for-byte intact).

mod common;
use common::Scratch;

/// Runs the study in a scratch copy after `spoil` and checks the failure contract. Each
/// `expect` string must appear in the message.
fn check(spoil: impl Fn(&Scratch), expect: &[&str]) {
    let s = Scratch::new();
    // A good run first: its report must survive the bad one untouched.
    let ok = s.run(&["run", "studies/lifetime.toml", "--quiet"]);
    assert_eq!(ok.code, 0, "{}", ok.stderr);
    let before: Vec<(String, Vec<u8>)> =
        s.report_files().into_iter().map(|f| (f.clone(), std::fs::read(s.path("reports").join(&f)).unwrap())).collect();
    spoil(&s);
    let out = s.run(&["run", "studies/lifetime.toml", "--quiet"]);
    assert_eq!(out.code, 2, "exit code; stderr: {}", out.stderr);
    assert!(!out.stderr.contains("panicked"), "{}", out.stderr);
    assert_eq!(out.stderr.trim().lines().count(), 1, "one message: {}", out.stderr);
    for e in expect {
        assert!(out.stderr.contains(e), "message lacks \"{e}\": {}", out.stderr);
    }
    let after: Vec<(String, Vec<u8>)> =
        s.report_files().into_iter().map(|f| (f.clone(), std::fs::read(s.path("reports").join(&f)).unwrap())).collect();
    assert_eq!(before.len(), after.len(), "files under reports/ changed");
    assert!(before == after, "the earlier report was modified");
}

fn edit_csv(s: &Scratch, file: &str, f: impl Fn(&str) -> String) {
    let rel = format!("datasets/{file}");
    let text = s.read(&rel);
    s.write(&rel, &f(&text));
}

/// Replaces `from` by `to` (first occurrence) in the scratch study file.
fn edit_study(s: &Scratch, from: &str, to: &str) {
    let text = s.read("studies/lifetime.toml");
    assert!(text.contains(from), "the study has no \"{from}\"");
    s.write("studies/lifetime.toml", &text.replacen(from, to, 1));
}

/// Replaces field `col` of data row `row` (1-based) of a CSV text.
fn set_cell(text: &str, row: usize, col: usize, value: &str) -> String {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<String> = lines[row].split(',').map(String::from).collect();
    cells[col] = value.into();
    lines[row] = cells.join(",");
    lines.join("\n") + "\n"
}

#[test]
fn missing_data_file() {
    check(|s| std::fs::remove_file(s.path("datasets/crush_gen4.csv")).unwrap(), &["crush_gen4.csv", "cannot read"]);
}

#[test]
fn missing_study_file() {
    let s = Scratch::new();
    let out = s.run(&["run", "studies/nope.toml"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("nope.toml") && out.stderr.contains("cannot read"), "{}", out.stderr);
    assert!(!s.path("reports").exists(), "reports/ created by a failed run");
}

#[test]
fn missing_column() {
    check(
        |s| edit_csv(s, "crush_bl1630.csv", |t| t.replacen("crush_force_n", "pressure_n", 1)),
        &["crush_bl1630.csv", "header", "missing column crush_force (a force, e.g. `crush_force_n`, `Fmax [N]`)", "the file's columns are"],
    );
}

#[test]
fn non_numeric_cell() {
    check(
        |s| edit_csv(s, "crush_bl1630.csv", |t| set_cell(t, 3, 2, "0.9mm")),
        &["crush_bl1630.csv", "row 3 (line 4), column diameter_m", "\"0.9mm\" is not a number"],
    );
}

#[test]
fn zero_diameter() {
    check(
        |s| edit_csv(s, "crush_gen4.csv", |t| set_cell(t, 5, 2, "0")),
        &["crush_gen4.csv", "row 5 (line 6), column diameter_m", "diameter must be in [1e-6, 0.1] m"],
    );
}

#[test]
fn negative_force() {
    check(
        |s| edit_csv(s, "crush_gen4.csv", |t| set_cell(t, 2, 3, "-12.5")),
        &["crush_gen4.csv", "row 2 (line 3), column crush_force_n", "crush force must be in [1e-6, 1e5] N"],
    );
}

#[test]
fn zero_force() {
    check(
        |s| edit_csv(s, "crush_gen4.csv", |t| set_cell(t, 7, 3, "0")),
        &["row 7 (line 8), column crush_force_n", "must be in [1e-6, 1e5] N"],
    );
}

#[test]
fn nan_diameter() {
    check(
        |s| edit_csv(s, "crush_bl1630.csv", |t| set_cell(t, 10, 2, "NaN")),
        &["row 10 (line 11), column diameter_m", "not a finite number"],
    );
}

#[test]
fn nan_force() {
    check(
        |s| edit_csv(s, "crush_bl1630.csv", |t| set_cell(t, 1, 3, "nan")),
        &["row 1 (line 2), column crush_force_n", "not a finite number"],
    );
}

#[test]
fn empty_required_cell() {
    check(
        |s| edit_csv(s, "crush_bl1630.csv", |t| set_cell(t, 4, 3, "")),
        &["row 4 (line 5), column crush_force_n", "empty"],
    );
}

#[test]
fn roundness_above_one() {
    check(
        |s| edit_csv(s, "crush_bl1630.csv", |t| set_cell(t, 8, 4, "1.2")),
        &["row 8 (line 9), column roundness", "[0.01, 1]"],
    );
}

#[test]
fn roundness_zero() {
    check(|s| edit_csv(s, "crush_gen4.csv", |t| set_cell(t, 3, 4, "0")), &["column roundness", "[0.01, 1]"]);
}

#[test]
fn sphericity_negative() {
    check(|s| edit_csv(s, "crush_gen4.csv", |t| set_cell(t, 3, 5, "-0.5")), &["column sphericity", "[0.01, 1]"]);
}

#[test]
fn ragged_row() {
    check(
        |s| edit_csv(s, "crush_gen4.csv", |t| t.replacen("G4-002,Gen 4,", "G4-002,Gen 4,0.001,", 1)),
        &["datasets/crush_gen4.csv: row 2 (line 3)", "has 8 fields, the header has 7"],
    );
}

#[test]
fn short_row() {
    check(
        |s| edit_csv(s, "crush_gen4.csv", |t| {
            let mut lines: Vec<String> = t.lines().map(String::from).collect();
            let cut = lines[4].rfind(',').unwrap();
            lines[4].truncate(cut);
            lines.join("\n") + "\n"
        }),
        &["datasets/crush_gen4.csv: row 4 (line 5)", "has 6 fields, the header has 7"],
    );
}

#[test]
fn duplicated_column_name() {
    check(
        |s| edit_csv(s, "crush_bl1630.csv", |t| t.replacen("sphericity", "roundness", 1)),
        &["crush_bl1630.csv: header", "column `roundness` appears twice (columns 5 and 6)"],
    );
}

#[test]
fn directory_as_data_file() {
    check(
        |s| {
            std::fs::remove_file(s.path("datasets/crush_gen4.csv")).unwrap();
            std::fs::create_dir(s.path("datasets/crush_gen4.csv")).unwrap();
        },
        &["crush_gen4.csv", "is a directory, not a file"],
    );
}

/// Values that parse as numbers but no particle has: they used to travel on as an infinite
/// contact radius (exit 1) or an underflowed strength.
#[test]
fn implausible_force_and_diameter() {
    check(|s| edit_csv(s, "crush_gen4.csv", |t| set_cell(t, 3, 3, "1e308")), &["row 3 (line 4), column crush_force_n", "[1e-6, 1e5] N", "got 1e308"]);
    check(|s| edit_csv(s, "crush_gen4.csv", |t| set_cell(t, 6, 2, "1e-300")), &["row 6 (line 7), column diameter_m", "[1e-6, 0.1] m"]);
    check(|s| edit_csv(s, "crush_gen4.csv", |t| set_cell(t, 6, 2, "900")), &["row 6 (line 7), column diameter_m", "µm or mm"]);
}

#[test]
fn unknown_toml_key() {
    check(
        |s| edit_study(s, "energy_fraction = 0.1", "energy_fraction = 0.1\nenergy_fracton = 0.2"),
        &["lifetime.toml", "line", "energy_fracton", "unknown field"],
    );
}

#[test]
fn toml_syntax_error() {
    check(
        |s| edit_study(s, "seed = 20261121", "seed = "),
        &["lifetime.toml", "line"],
    );
}

#[test]
fn energy_fraction_zero() {
    check(
        |s| edit_study(s, "energy_fraction = 0.1", "energy_fraction = 0.0"),
        &["lifetime.toml", "impact.energy_fraction", "(0, 1]", "got 0"],
    );
}

#[test]
fn energy_fraction_negative() {
    check(
        |s| edit_study(s, "energy_fraction = 0.1", "energy_fraction = -0.1"),
        &["impact.energy_fraction", "(0, 1]"],
    );
}

#[test]
fn energy_fraction_above_one() {
    check(
        |s| edit_study(s, "energy_fraction = 0.1", "energy_fraction = 1.5"),
        &["impact.energy_fraction"],
    );
}

#[test]
fn impossible_poisson_ratio() {
    check(
        |s| edit_study(s, "poisson_ratio = 0.25", "poisson_ratio = 0.5"),
        &["material[0].elastic.poisson_ratio", "(-1, 0.5)"],
    );
}

#[test]
fn averaging_domain_inside_contact() {
    check(
        |s| edit_study(s, "kappa = 2.0", "kappa = 0.8"),
        &["contact.averaging.kappa", "kappa > 1"],
    );
}

#[test]
fn unknown_study_kind() {
    check(
        |s| edit_study(s, "kind = \"lifetime\"", "kind = \"lifetme\""),
        &["kind", "lifetme", "known: lifetime"],
    );
}

#[test]
fn datasets_check_reports_bad_cells() {
    let s = Scratch::new();
    edit_csv(&s, "crush_bl1630.csv", |t| set_cell(t, 2, 4, "7"));
    let out = s.run(&["datasets", "check", "datasets/crush_gen4.csv", "datasets/crush_bl1630.csv"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("crush_bl1630.csv: row 2 (line 3), column roundness"), "{}", out.stderr);
}

#[test]
fn report_of_a_missing_run() {
    let s = Scratch::new();
    let out = s.run(&["report", "lifetime"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("reports/lifetime") && out.stderr.contains("no report named lifetime"), "{}", out.stderr);
    // A directory without its manifest.
    std::fs::create_dir_all(s.path("reports/lifetime")).unwrap();
    let out = s.run(&["report", "lifetime"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("manifest.json"), "{}", out.stderr);
}

#[test]
fn bad_generator_settings() {
    let s = Scratch::new();
    let text = std::fs::read_to_string(common::root().join("datasets/synth_crush.toml")).unwrap().replacen("count = 50", "count = 1", 1);
    s.write("datasets/synth_crush.toml", &text);
    let before = s.read("datasets/crush_bl1630.csv");
    let out = s.run(&["datasets", "synth", "--settings", "datasets/synth_crush.toml"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("material[0].count"), "{}", out.stderr);
    assert_eq!(before, s.read("datasets/crush_bl1630.csv"), "a dataset was rewritten by a failed synth");
}

/// The UQ study: impossible distributions, bad spectra and horizons fail at load with exit
/// code 2, naming the file, the key or row, and the rule; nothing is written.
#[test]
fn uq_study_bad_input() {
    let s = Scratch::new();
    let study = "studies/gen4_vs_bl.toml";
    let text = std::fs::read_to_string(common::root().join(study)).unwrap();
    let reset = |s: &Scratch| s.write(study, &text);
    reset(&s);
    s.expect_bad_study(study, "median = 0.1, sd_log = 0.5", "median = 0.1, sd_log = -0.5", &["impact.energy_fraction", "sd_log"]);
    reset(&s);
    let population = "density_kg_m3 = 3060\npopulation = { particles = 64, diameter_m = { distribution = \"uniform\", min = 0.0006, max = 0.0012 }, roundness = { distribution = \"normal\", mean = 0.72, sd = 0.05, min = 0.5, max = 1.5 } }\n";
    s.expect_bad_study(study, "density_kg_m3 = 3060\n", population, &["material[0].population.roundness", "[0.01, 1]"]);
    reset(&s);
    s.expect_bad_study(study, "years = [1, 10]", "years = [0, 10]", &["impact.years", "> 0"]);
    reset(&s);
    s.expect_bad_study(study, "candidate = \"gen4\"", "candidate = \"gen5\"", &["compare.candidate", "gen5"]);
    // A velocity spectrum with a negative speed, a non-finite one, and an empty row.
    let spectrum = "velocity = { distribution = \"spectrum\", file = \"../datasets/spectrum.csv\", target = \"tube\", row = 0 }";
    let head = "target,row,impacts,mean_v_normal_m_s,q5_v_normal_m_s,q50_v_normal_m_s,q95_v_normal_m_s\n";
    for (row, expect) in [
        ("tube,0,100,0.2,0.1,-0.2,0.5\n", vec!["spectrum.csv", "q50_v_normal_m_s", "[0, 100] m/s", "got -0.2"]),
        ("tube,0,100,0.2,0.1,NaN,0.5\n", vec!["spectrum.csv", "q50_v_normal_m_s", "finite"]),
        ("tube,0,0,0,0,0,0\n", vec!["spectrum.csv", "impacts", "empty"]),
        ("particle,0,100,0.2,0.1,0.2,0.5\n", vec!["spectrum.csv", "no row with target `tube`"]),
    ] {
        // A data error names the data file, its row and column (not the study).
        s.write(study, &common::edited(&text, &[("velocity = { distribution = \"log_normal\", median = 5.0, sd_log = 0.2, min = 1.0, max = 15.0 }", spectrum)]));
        s.write("datasets/spectrum.csv", &format!("{head}{row}"));
        let out = s.run(&["run", study, "--quiet"]);
        assert_eq!(out.code, 2, "{}", out.stderr);
        for e in expect {
            assert!(out.stderr.contains(e), "message lacks \"{e}\": {}", out.stderr);
        }
        assert!(s.report_files().is_empty());
    }
    // A good spectrum runs.
    reset(&s);
    s.write("datasets/spectrum.csv", &format!("{head}tube,0,100,0.2,0.1,0.2,0.5\n"));
    let scaled = common::edited(spectrum, &[("row = 0 }", "row = 0, scale = 10.0 }")]);
    let t = common::edited(&text, &[("velocity = { distribution = \"log_normal\", median = 5.0, sd_log = 0.2, min = 1.0, max = 15.0 }", &scaled), ("samples = 262144", "samples = 8192"), ("n = 8192", "n = 256")]);
    s.write(study, &t);
    let out = s.run(&["run", study, "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let inputs = s.read("reports/gen4_vs_bl/inputs.csv");
    let v = inputs.lines().find(|l| l.starts_with("velocity,")).unwrap();
    let median: f64 = v.split(',').nth(3).unwrap().parse().unwrap();
    assert!((median - 2.0).abs() < 1e-9, "median of 10 × the spectrum = 2 m/s: {v}");
}

#[test]
fn uq_study_rejects_unknown_material_keys() {
    let s = Scratch::new();
    let study = "studies/gen4_vs_bl.toml";
    s.write(study, &std::fs::read_to_string(common::root().join(study)).unwrap());
    s.expect_bad_study(study, "density_kg_m3 = 3600\n", "density_kg_m3 = 3600\ncolour = \"red\"\n", &["line", "colour", "unknown field"]);
}

/// The main study's strength models (issue: one strength model for every study): an effect
/// whose covariate the data lack, an unknown effect, a model listed twice, and too few crush
/// tests to weigh the models are each refused with the reason, exit 2, nothing written.
#[test]
fn uq_strength_model_bad_input() {
    let s = Scratch::new();
    let study = "studies/gen4_vs_bl.toml";
    let text = std::fs::read_to_string(common::root().join(study)).unwrap();
    let gen4 = std::fs::read_to_string(common::root().join("datasets/crush_gen4.csv")).unwrap();
    let reset = |s: &Scratch| {
        s.write(study, &text);
        s.write("datasets/crush_gen4.csv", &gen4);
    };
    // The roundness column emptied: the explicit roundness + sphericity model needs it.
    reset(&s);
    let emptied: String = gen4
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let mut f: Vec<&str> = l.split(',').collect();
            if i > 0 {
                f[4] = "";
            }
            f.join(",") + "\n"
        })
        .collect();
    s.write("datasets/crush_gen4.csv", &emptied);
    bad_data(&s, study, &["crush_gen4.csv", "column roundness", "`gen4`", "`roundness` effect"]);
    // An unknown effect.
    reset(&s);
    s.expect_bad_study(study, "[\"roundness\", \"sphericity\"]", "[\"rondness\", \"sphericity\"]", &["rondness", "roundness"]);
    // A strength model listed twice.
    reset(&s);
    s.expect_bad_study(study, "strength = [[], [\"roundness\", \"sphericity\"], \"diagnosed\"]", "strength = [[], [], \"diagnosed\"]", &["model_form.strength[1]", "listed twice"]);
    // Nine crush tests: the weights cannot be computed.
    reset(&s);
    s.write("datasets/crush_gen4.csv", &gen4.lines().take(10).map(|l| format!("{l}\n")).collect::<String>());
    let two = common::edited(&text, &[("effects = \"diagnosed\"", "effects = []"), ("strength = [[], [\"roundness\", \"sphericity\"], \"diagnosed\"]", "strength = [[], [\"size\"]]")]);
    s.write(study, &two);
    bad_data(&s, study, &["crush_gen4.csv", "too few to weigh strength models", "at least 10"]);
}

/// Runs `study` and checks the contract for a data error: exit 2, one message naming what
/// `expect` lists (the data file rather than the study), nothing written.
fn bad_data(s: &Scratch, study: &str, expect: &[&str]) {
    let out = s.run(&["run", study, "--quiet"]);
    assert_eq!(out.code, 2, "exit code; stderr: {}", out.stderr);
    assert!(!out.stderr.contains("panicked"), "{}", out.stderr);
    assert_eq!(out.stderr.trim().lines().count(), 1, "one message: {}", out.stderr);
    for e in expect {
        assert!(out.stderr.contains(e), "message lacks \"{e}\": {}", out.stderr);
    }
    assert!(s.report_files().is_empty(), "a failed run wrote {:?}", s.report_files());
}

#[test]
fn discrepancy_study_bad_input() {
    let s = Scratch::new();
    let study = "studies/discrepancy_crush.toml";
    let text = std::fs::read_to_string(common::root().join(study)).unwrap();
    let reset = |s: &Scratch| s.write(study, &text);
    reset(&s);
    s.expect_bad_study(study, "alpha = 0.05", "alpha = 2.0", &["discrepancy.alpha", "(0, 0.5]"]);
    reset(&s);
    s.expect_bad_study(study, "\"damage\"]", "\"colour\"]", &["colour"]);
    reset(&s);
    s.expect_bad_study(study, "bootstrap = 499", "bootstrap = 10", &["discrepancy.bootstrap", "≥ 99"]);
    reset(&s);
    s.expect_bad_study(study, "particles = [20, 40, 80, 160]", "particles = [5, 40]", &["power.particles", "[10, 100000]"]);
    reset(&s);
    s.expect_bad_study(study, "cv_folds = 10", "cv_folds = 10\nfolds = 3", &["folds"]);
}

/// Every bad command-line argument is bad input: exit 2, a message naming the argument, no
/// panic, nothing written.
#[test]
fn bad_command_line_arguments() {
    let s = Scratch::new();
    let cases: [(&[&str], &[&str]); 9] = [
        (&["--threads", "0", "run", "studies/lifetime.toml"], &["--threads", "0"]),
        (&["run"], &["<STUDY>"]),
        (&["frobnicate"], &["frobnicate"]),
        (&["bench", "--uq", "--dem"], &["--uq", "--dem", "cannot be used with"]),
        (&["bench", "--chain", "chain.csv:1.5"], &["--chain", "--mcmc"]),
        (&["bench", "--mcmc", "--chain", "chain.csv"], &["--chain", "FILE:SECONDS"]),
        (&["bench", "--mcmc", "--chain", "chain.csv:soon"], &["--chain", "SECONDS"]),
        (&["discrepancy", "--out", "x", "studies/lifetime.toml"], &["--out"]),
        (&["datasets", "check", "datasets"], &["datasets", "is a directory, not a file"]),
    ];
    for (args, expect) in cases {
        let out = s.run(args);
        assert_eq!(out.code, 2, "partlife {args:?}: exit code; stderr: {}", out.stderr);
        assert!(!out.stderr.contains("panicked"), "partlife {args:?}: {}", out.stderr);
        for e in expect {
            assert!(out.stderr.contains(e), "partlife {args:?}: message lacks \"{e}\": {}", out.stderr);
        }
        assert!(s.report_files().is_empty(), "partlife {args:?} wrote {:?}", s.report_files());
    }
}

/// A strength file's study: a missing factor column, integer codes of unknown type, a strength
/// in the wrong unit and a reserved column name each get one message naming file, key or row
/// and the rule; exit 2; nothing written.
#[test]
fn bad_strength_files_and_factor_declarations() {
    let s = Scratch::new();
    std::fs::create_dir_all(s.path("datasets/real")).unwrap();
    let bars = "id;batch;lab;V [mm³];strength [MPa]\nB1;x;1;2,0;310\nB2;y;2;8,0;290\nB3;x;1;2,0;305\nB4;y;2;8,0;295\nB5;x;1;2,0;300\nB6;y;2;8,0;285\nB7;x;1;2,0;312\nB8;y;2;8,0;280\nB9;x;1;2,0;308\nB10;y;2;8,0;288\nB11;x;1;2,0;301\nB12;y;2;8,0;292\n";
    // With a test-temperature column (`T [°C]`), and without one (the study must then say it).
    let with_t: String = bars.lines().enumerate().map(|(i, l)| format!("{l};{}\n", if i == 0 { "T [°C]" } else { "20" })).collect();
    s.write("datasets/real/bars.csv", &with_t);
    s.write("datasets/real/bars_no_t.csv", bars);
    let study = "studies/bars.toml";
    let base = "kind = \"discrepancy\"\nseed = 1\n[discrepancy]\nbootstrap = 99\npermutations = 99\n[power]\nreplicates = 0\n[[strength]]\nkey = \"bars\"\nlabel = \"Bars\"\ndata = \"../datasets/real/bars.csv\"\nsize = { column = \"V\", measure = \"effective_volume\" }\nfactors = [\"batch\"]\n";
    s.write(study, base);
    let ok = s.run(&["run", study, "--reports-dir", "ok", "--quiet"]);
    assert_eq!(ok.code, 0, "{}", ok.stderr);
    std::fs::remove_dir_all(s.path("ok")).unwrap();
    s.expect_bad_study(study, "factors = [\"batch\"]", "factors = [\"batch\", \"furnace\"]", &["strength[0].factors.furnace", "no column `furnace`", "bars.csv"]);
    s.write(study, base);
    s.expect_bad_study(study, "factors = [\"batch\"]", "factors = [\"lab\"]", &["strength[0].factors", "`lab` holds 2 distinct whole numbers", "lab = \"categorical\""]);
    s.write(study, base);
    s.expect_bad_study(study, "data = \"../datasets/real/bars.csv\"", "data = { file = \"../datasets/real/bars.csv\", columns = { strength = \"strength [MPa]\" }, units = { strength = \"Pa\" } }", &["units.strength", "contradicts"]);
    s.write(study, base);
    s.expect_bad_study(study, "factors = [\"batch\"]", "factors = [\"residual\"]", &["strength[0].factors", "`residual` is a name the report's tables use"]);
    // A strength file that states no test temperature, in a study that gives none.
    s.write(study, base);
    s.expect_bad_study(study, "data = \"../datasets/real/bars.csv\"", "data = \"../datasets/real/bars_no_t.csv\"", &["bars_no_t.csv", "states no test temperature", "strength[0].data.temperature_c = 20"]);
    s.write(study, base);
    s.expect_bad_study(study, "data = \"../datasets/real/bars.csv\"", "data = { file = \"../datasets/real/bars_no_t.csv\", temperature_c = 5000 }", &["strength[0].data.temperature_c", "[-273.15, 2100] °C"]);
}

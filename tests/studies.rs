//! Every study file parses and validates; the lifetime study runs end to end into a temporary
//! directory with all figures, tables and the manifest, deterministically and independent of
//! the thread count, and reproduces the deliverable's qualitative findings on the synthetic data.

mod common;
use common::{Scratch, root};
use partlife::io::{col_f64, col_str, read_table};

const TABLES: [&str; 13] = [
    "particles",
    "weibull_fits",
    "weibull_points",
    "weibull_cdf",
    "size_trend",
    "stress_profile",
    "stress_profile_summary",
    "impact_curves",
    "breakage_curves",
    "force_time",
    "lifetime_summary",
    "strength_fits",
    "attrition",
];
const FIGURES: [&str; 6] =
    ["fig05_force_time", "fig13_stress_profile", "fig14_sigma_vs_diameter", "fig14_weibull_cdf", "fig15_impact", "fig16_breakage"];

#[test]
fn every_study_file_parses_and_validates() {
    let mut n = 0;
    for e in std::fs::read_dir(root().join("studies")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let s = partlife::study::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            let lines: Vec<&str> = s.file.text.lines().take(2).collect();
            assert!(lines.len() == 2 && lines.iter().all(|l| l.starts_with('#')), "{}: two comment lines first", p.display());
            n += 1;
        }
    }
    assert!(n >= 1);
}

fn run_ok(s: &Scratch, extra: &[&str]) {
    let mut args = vec!["run", "studies/lifetime.toml", "--quiet"];
    args.extend_from_slice(extra);
    let out = s.run(&args);
    assert_eq!(out.code, 0, "stderr: {}", out.stderr);
}

#[test]
fn lifetime_study_writes_every_output() {
    let s = Scratch::new();
    run_ok(&s, &[]);
    let dir = s.path("reports/lifetime");
    for t in TABLES {
        assert!(dir.join(format!("{t}.csv")).is_file(), "missing {t}.csv");
    }
    assert!(dir.join("manifest.json").is_file(), "missing manifest.json");
    for f in FIGURES {
        // SVG with its physical size, single-column width.
        let svg = std::fs::read_to_string(dir.join(format!("{f}.svg"))).unwrap();
        assert!(svg.contains("width=\"8.500cm\""), "{f}.svg size");
        assert!(svg.contains("font-family=\"DejaVu Sans\""), "{f}.svg font");
        // PNG at 300 dpi: 8.5 cm = 1004 px.
        let png = std::fs::read(dir.join(format!("{f}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        let width = u32::from_be_bytes(png[16..20].try_into().unwrap());
        assert_eq!(width, 1004, "{f}.png width");
        // Vector PDF with the font embedded (a FontFile2 stream of DejaVu Sans), 8.5 cm wide.
        let pdf = std::fs::read(dir.join(format!("{f}.pdf"))).unwrap();
        let text = String::from_utf8_lossy(&pdf);
        assert!(text.starts_with("%PDF-"), "{f}.pdf header");
        assert!(text.contains("/FontFile2") && text.contains("DejaVuSans"), "{f}.pdf embeds no font");
        assert!(text.contains("/MediaBox [0 0 240.94"), "{f}.pdf page width");
    }
    // Manifest: inputs hashed, generator truth not among them, no failures.
    let m: serde_json::Value = serde_json::from_str(&s.read("reports/lifetime/manifest.json")).unwrap();
    let inputs: Vec<String> = m["inputs"].as_array().unwrap().iter().map(|i| i["path"].as_str().unwrap().to_string()).collect();
    assert_eq!(inputs, ["studies/lifetime.toml", "datasets/crush_bl1630.csv", "datasets/crush_gen4.csv"]);
    let hash = partlife::io::sha256_hex(&std::fs::read(s.path("datasets/crush_gen4.csv")).unwrap());
    assert_eq!(m["inputs"][2]["sha256"], hash);
    assert_eq!(m["seed"], 20261121);
    assert_eq!(m["failures"].as_array().unwrap().len(), 0, "{}", m["failures"]);
    assert_eq!(m["study_toml"].as_str().unwrap(), s.read("studies/lifetime.toml"));
    assert_eq!(m["study_resolved"]["impact"]["energy_fraction"], 0.1);
    assert!(m["evaluations"]["lifetime_chain"].as_u64().unwrap() == 2 * 201);
    // The tool's revision is embedded at build time: named although the scratch study lies
    // outside any git tree (this test builds from a clone), and the study's own is unknown.
    let rev = m["partlife_revision"].as_str().unwrap_or_default();
    assert!(rev.len() == 40 && rev.chars().all(|c| c.is_ascii_hexdigit()), "{}", m["partlife_revision"]);
    assert!(m["git_revision"].is_null(), "{}", m["git_revision"]);
    // Tables, figures in three formats, manifest.json, summary.md, report.pdf and report.html.
    assert_eq!(m["outputs"].as_array().unwrap().len(), TABLES.len() + 3 * FIGURES.len() + 4);
    // No temporary directory left behind.
    let names: Vec<String> = std::fs::read_dir(s.path("reports")).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(names, ["lifetime"]);
}

#[test]
fn legends_hide_no_data() {
    let s = Scratch::new();
    run_ok(&s, &[]);
    let r = partlife::report::render(&s.path("reports/lifetime"), 8.5).unwrap();
    assert_eq!(r.legend_hidden.len(), 6);
    for (fig, n) in &r.legend_hidden {
        assert_eq!(*n, 0, "{fig}: the legend hides {n} data samples");
    }
    // Also at double-column width.
    let r = partlife::report::render(&s.path("reports/lifetime"), 17.0).unwrap();
    assert!(r.legend_hidden.iter().all(|(_, n)| *n == 0), "{:?}", r.legend_hidden);
}

fn tables(s: &Scratch) -> Vec<(String, Vec<u8>)> {
    TABLES
        .iter()
        .map(|t| (t.to_string(), std::fs::read(s.path(&format!("reports/lifetime/{t}.csv"))).unwrap()))
        .collect()
}

#[test]
fn runs_are_deterministic_and_thread_count_independent() {
    let a = Scratch::new();
    let b = Scratch::new();
    run_ok(&a, &[]);
    run_ok(&b, &["--threads", "1"]);
    for ((name, x), (_, y)) in tables(&a).iter().zip(tables(&b)) {
        assert!(*x == y, "{name}.csv differs between runs (threads all vs 1)");
    }
    // Every figure file the same bytes, the PDFs too (their resource dictionaries are sorted).
    for f in FIGURES {
        for ext in ["svg", "png", "pdf"] {
            let p = format!("reports/lifetime/{f}.{ext}");
            assert!(std::fs::read(a.path(&p)).unwrap() == std::fs::read(b.path(&p)).unwrap(), "{f}.{ext} differs");
        }
    }
}

#[test]
fn report_redraws_from_tables_only() {
    let s = Scratch::new();
    run_ok(&s, &[]);
    let svg = s.read("reports/lifetime/fig16_breakage.svg");
    for f in FIGURES {
        for ext in ["svg", "png", "pdf"] {
            std::fs::remove_file(s.path(&format!("reports/lifetime/{f}.{ext}"))).unwrap();
        }
    }
    // The datasets are gone too: redrawing must not need them.
    std::fs::remove_dir_all(s.path("datasets")).unwrap();
    let out = s.run(&["report", "lifetime"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("redrew 18 files"), "{}", out.stdout);
    assert_eq!(s.read("reports/lifetime/fig16_breakage.svg"), svg);
}

#[test]
fn synthetic_data_reproduce_the_deliverables_findings() {
    // Deliverable §6: BL 16/30 has the higher tensile stress at break and a Weibull modulus near
    // 10; Gen 4 has a lower modulus; the average tensile stress falls slightly with diameter.
    let s = Scratch::new();
    run_ok(&s, &[]);
    let p = s.path("reports/lifetime/weibull_fits.csv");
    let fits = read_table(&p).unwrap();
    let keys = col_str(&fits, &p, "material_key").unwrap();
    assert_eq!(keys, ["bl1630", "gen4"]);
    let m = col_f64(&fits, &p, "shape_mle").unwrap();
    let scale = col_f64(&fits, &p, "scale_pa").unwrap();
    assert!((9.0..=11.0).contains(&m[0]), "BL modulus {}", m[0]);
    assert!(m[1] < m[0] - 1.0, "Gen 4 modulus {} not below BL {}", m[1], m[0]);
    assert!(scale[0] > scale[1], "BL scale {} not above Gen 4 {}", scale[0], scale[1]);
    let p = s.path("reports/lifetime/size_trend.csv");
    let trend = read_table(&p).unwrap();
    for b in col_f64(&trend, &p, "exponent").unwrap() {
        assert!(b < 0.0 && b > -1.0, "size exponent {b}");
    }
    // Breaking probability rises with N and V; Gen 4 breaks more (the deliverable's conclusion).
    let p = s.path("reports/lifetime/lifetime_summary.csv");
    let sum = read_table(&p).unwrap();
    let pb = col_f64(&sum, &p, "p_break").unwrap();
    let lo = col_f64(&sum, &p, "p_break_lower").unwrap();
    let hi = col_f64(&sum, &p, "p_break_upper").unwrap();
    assert!(pb[0] < pb[1] && pb[2] < pb[3], "{pb:?}");
    assert!(pb[2] > pb[0] && pb[3] > pb[1], "{pb:?}");
    for i in 0..4 {
        assert!(lo[i] < pb[i] && pb[i] < hi[i], "band {i}: {} {} {}", lo[i], pb[i], hi[i]);
    }
}

/// Regression: `partlife run … | head -1` panicked ("failed printing to stdout") once the
/// reader closed the pipe. The report is on disk by then; the run must exit 0 without a panic.
#[test]
fn closed_stdout_pipe_is_not_a_panic() {
    let s = Scratch::new();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_partlife"))
        .args(["run", "studies/lifetime.toml", "--quiet"])
        .current_dir(s.dir.path())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take()); // the reader goes away before the first line
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(s.path("reports/lifetime/manifest.json").is_file());
}

/// The main study (README's first command) writes every table and figure with the headline per
/// strength model and model-averaged with the weights, is deterministic and independent of the
/// thread count, reproduces the committed golden values within their Monte Carlo tolerance, and
/// the README shows its headline as it is.
#[test]
fn main_uq_study_writes_the_headline_deterministically() {
    let run = |threads: &str| {
        let s = Scratch::new();
        s.write("studies/gen4_vs_bl.toml", &std::fs::read_to_string(root().join("studies/gen4_vs_bl.toml")).unwrap());
        let out = s.run(&["run", "studies/gen4_vs_bl.toml", "--quiet", "--threads", threads]);
        assert_eq!(out.code, 0, "{}", out.stderr);
        assert!(out.stdout.contains("P(Gen 4 breaks more than BL 16/30 in 10 yr) = ") && out.stdout.contains("(Monte Carlo se; averaged over the strength models with stacking weights"), "{}", out.stdout);
        (s, out.stdout)
    };
    // Both at once: the one-thread run would otherwise leave a core idle for most of the test.
    let ((a, stdout), (b, _)) = std::thread::scope(|scope| {
        let one = scope.spawn(|| run("1"));
        (run("2"), one.join().expect("the one-thread run"))
    });
    let dir = "reports/gen4_vs_bl";
    for t in ["materials", "comparison", "breakage", "strength_models", "weights", "convergence", "distributions", "breakage_vs_velocity", "sobol", "inputs", "averaging"] {
        assert_eq!(a.read(&format!("{dir}/{t}.csv")), b.read(&format!("{dir}/{t}.csv")), "{t}.csv differs between 2 threads and 1");
    }
    assert_eq!(a.read(&format!("{dir}/summary.md")), b.read(&format!("{dir}/summary.md")));
    for f in ["uq_breakage_vs_velocity", "uq_distributions", "uq_convergence", "uq_sobol", "uq_sobol_convergence", "uq_model_form", "uq_strength_models"] {
        for ext in ["svg", "png", "pdf"] {
            assert!(a.path(&format!("{dir}/{f}.{ext}")).is_file(), "{f}.{ext}");
        }
    }
    let manifest: serde_json::Value = serde_json::from_str(&a.read(&format!("{dir}/manifest.json"))).unwrap();
    assert_eq!(manifest["failures"].as_array().map(|v| v.len()), Some(0), "{}", manifest["failures"]);
    // The decision document: the run's headline numbers in the PDF's text (poppler), the answer
    // in a plant engineer's units and Vogel–Peukert's "no breakage" in words on its first page.
    assert!(a.path(&format!("{dir}/report.html")).is_file());
    if let Some(t) = common::program("tests/studies.rs main study document", "pdftotext", "poppler-utils", "PARTLIFE_EXPECT_POPPLER") {
        let pdf = a.path(&format!("{dir}/report.pdf"));
        let all = common::pdf_text(&t, &pdf, None);
        for line in stdout.lines().filter(|l| !l.starts_with("wrote ")) {
            assert!(all.contains(&common::one_space(line)), "report.pdf lacks the headline \"{line}\"");
        }
        let first = common::pdf_text(&t, &pdf, Some((1, 1)));
        assert!(first.contains("BL 16/30 breaks less than Gen 4") && first.contains("broken in year 1") && first.contains("Distribution of the breaking probability"), "page 1: {first}");
        assert!(!first.contains("Vogel–Peukert breaks nothing"), "the full attrition table has its own section: {first}");
    }
    // The document opens with the answer in one sentence generated from the numbers: which
    // particle breaks less, by how much in the plant's units (attrition.csv's model-averaged
    // row under independent trials) and how sure, then the headline model's attrition.
    let summary = a.read(&format!("{dir}/summary.md"));
    let (att, sm, model, mat, first_med) = {
        let p = a.path(&format!("{dir}/attrition.csv"));
        (p.clone(), common::table_text(&p, "strength_model"), common::table_text(&p, "model"), common::table_text(&p, "material"), common::table_f64(&p, "first_year_median"))
    };
    let share = |label: &str| partlife::report::captions::percent(first_med[(0..sm.len()).find(|&i| sm[i] == "model-averaged" && model[i] == "independent" && mat[i] == label).unwrap_or_else(|| panic!("{}: no row for {label}", att.display()))]);
    let answer = format!("## Answer\n\n**BL 16/30 breaks less than Gen 4**: in the first year of operation (730 impacts per particle) a median {} of its inventory breaks against {} of Gen 4's", share("BL 16/30"), share("Gen 4"));
    assert!(summary.contains(&answer), "{answer}\n{summary}");
    assert!(summary.find("## Answer").unwrap() < summary.find("## Headline").unwrap(), "{summary}");
    let attrition = a.read(&format!("{dir}/summary.md"));
    assert!(attrition.contains("| diagnosed | independent trials | Gen 4 |"), "summary.md lacks the attrition table");
    // Every damage model of the study is in the table, Tavares–King included, and each row's
    // first year agrees with the study's own 1-year horizon in breakage.csv (the table's median
    // is over its 4096-sample subset, the horizon's over every sample: within 10 %).
    let (att, brk) = (a.path(&format!("{dir}/attrition.csv")), a.path(&format!("{dir}/breakage.csv")));
    let (asm, amod, amat, afirst) = (common::table_text(&att, "strength_model"), common::table_text(&att, "model"), common::table_text(&att, "material"), common::table_f64(&att, "first_year_median"));
    let (bsm, bmod, bmat, byears, bmed) = (common::table_text(&brk, "strength_model"), common::table_text(&brk, "model"), common::table_text(&brk, "material"), common::table_f64(&brk, "years"), common::table_f64(&brk, "median"));
    let labels = [("gen4", "Gen 4"), ("bl1630", "BL 16/30")];
    for model in ["independent", "tavares_king"] {
        for (key, label) in labels {
            let i = (0..asm.len()).find(|&i| asm[i] == "diagnosed" && amod[i] == model && amat[i] == label).unwrap_or_else(|| panic!("attrition.csv has no row for {model}, {label}"));
            let k = (0..bsm.len()).find(|&k| bsm[k] == "diagnosed" && bmod[k] == model && bmat[k] == key && byears[k] == 1.0).unwrap();
            assert!((afirst[i] / bmed[k] - 1.0).abs() < 0.1, "{model}, {label}: first year {} against the 1-year median {}", afirst[i], bmed[k]);
        }
    }
    // Figures of one strength and damage model say which; Sobol' panels name their output in
    // words, not by column name (before: "Index of log10 p gen4").
    for (f, said) in [("uq_breakage_vs_velocity", "diagnosed strength, indep. trials"), ("uq_distributions", "diagnosed strength, indep. trials"), ("uq_sobol", "strength model: diagnosed; damage: independent trials")] {
        assert!(a.read(&format!("{dir}/{f}.svg")).contains(said), "{f}.svg does not name its models");
    }
    let sobol_svg = a.read(&format!("{dir}/uq_sobol.svg"));
    assert!(sobol_svg.contains("Index of log₁₀ P Gen 4") && sobol_svg.contains("P after 10 years") && !sobol_svg.contains("log10 p gen4"), "uq_sobol.svg output names");
    // The Sobol' intervals' level is the study's, alike in the table, the legend and the caption
    // (before: a legend of 95 % beside a caption of 90 %).
    let level = common::table_f64(&a.path(&format!("{dir}/sobol.csv")), "level");
    assert!(level.iter().all(|l| *l == 0.95), "{level:?}");
    let captions = common::figure_captions(&a.path(dir));
    let (_, caption) = captions.iter().find(|(stem, _)| stem == "uq_sobol").expect("a Sobol' caption");
    // Fig. 1 quotes 5 m/s itself (before: the grid's 4.87 m/s).
    let (_, velocity) = captions.iter().find(|(stem, _)| stem == "uq_breakage_vs_velocity").expect("a velocity caption");
    assert!(velocity.contains("At 5 m/s over 10 yr:"), "{velocity}");
    assert!(sobol_svg.contains("95 % interval") && caption.contains("with their 95 % bootstrap intervals") && !caption.contains("90 %"), "{caption}");
    // No table prints a negative zero (an empty sum is −0.0 in Rust).
    for t in ["attrition", "breakage", "comparison", "sobol"] {
        let text = a.read(&format!("{dir}/{t}.csv"));
        assert!(!text.lines().any(|l| l.split(',').any(|f| f == "-0.0" || f == "-0")), "{t}.csv prints -0");
    }

    // Golden values (tests/reference/gen4_vs_bl_headline.csv; the rule for regenerating them is
    // written in that file): P(candidate worse) within four Monte Carlo standard errors (floor
    // 1e-4), the weights to 1e-6.
    let cmp_path = a.path(&format!("{dir}/comparison.csv"));
    let cmp = read_table(&cmp_path).unwrap();
    let (cs, cm, cy, cp, cse) = (col_str(&cmp, &cmp_path, "strength_model").unwrap(), col_str(&cmp, &cmp_path, "model").unwrap(), col_f64(&cmp, &cmp_path, "years").unwrap(), col_f64(&cmp, &cmp_path, "p_candidate_worse").unwrap(), col_f64(&cmp, &cmp_path, "mc_se").unwrap());
    let w_path = a.path(&format!("{dir}/weights.csv"));
    let wt = read_table(&w_path).unwrap();
    let (wm, ws) = (col_str(&wt, &w_path, "strength_model").unwrap(), col_f64(&wt, &w_path, "weight_stacking").unwrap());
    let golden = std::fs::read_to_string(root().join("tests/reference/gen4_vs_bl_headline.csv")).unwrap();
    let mut checked = 0;
    for line in golden.lines().filter(|l| !l.starts_with('#') && !l.starts_with("strength_model,")) {
        let f: Vec<&str> = line.split(',').collect();
        let (model, years, p, se, w): (&str, f64, f64, f64, f64) = (f[0], f[1].parse().unwrap(), f[2].parse().unwrap(), f[3].parse().unwrap(), f[4].parse().unwrap());
        let i = (0..cs.len()).find(|&i| cs[i] == model && cm[i] == "independent" && cy[i] == years).unwrap_or_else(|| panic!("no row {model}, {years} yr"));
        let tol = 4.0 * se.max(cse[i]) + 1e-4;
        assert!((cp[i] - p).abs() <= tol, "{model}, {years} yr: P(Gen 4 worse) = {} against the golden {p} (tolerance {tol})", cp[i]);
        if let Some(k) = wm.iter().position(|m| m == model) {
            assert!((ws[k] - w).abs() < 1e-6, "{model}: stacking weight {} against the golden {w}", ws[k]);
        }
        checked += 1;
    }
    assert_eq!(checked, 8, "four strength rows (three models and the average) for each of two horizons");

    // The README shows this run's headline lines and the summary's strength-model table.
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    for line in stdout.lines().filter(|l| l.contains("P(Gen 4") || l.contains("per strength model")) {
        assert!(readme.contains(line), "README lacks the run's headline line (regenerate it from the run):\n{line}");
    }
    let summary = a.read(&format!("{dir}/summary.md"));
    let table: Vec<&str> = summary.lines().skip_while(|l| !l.starts_with("| strength model | effects | weight")).take_while(|l| l.starts_with('|')).collect();
    assert!(table.len() >= 5);
    for line in table {
        assert!(readme.contains(line), "README lacks the summary's strength-model table row (regenerate it from reports/gen4_vs_bl/summary.md):\n{line}");
    }

    // The Sobol' first-order indices of each output sum to at most 1 (+ their error); the dummy γ
    // has no effect on the independent-trials model; every effect parameter is an input.
    let sob_path = a.path(&format!("{dir}/sobol.csv"));
    let sob = read_table(&sob_path).unwrap();
    let f = |c: &str| col_f64(&sob, &sob_path, c).unwrap();
    let t = |c: &str| col_str(&sob, &sob_path, c).unwrap();
    let (n, out, input, s1, st) = (f("n"), t("output"), t("input"), f("s1"), f("st"));
    let nmax = n.iter().cloned().fold(0.0, f64::max);
    for name in ["strength_gen4", "size_alpha_gen4", "strength_bl1630", "size_alpha_bl1630", "roundness_q_bl1630"] {
        assert!(input.iter().any(|i| i == name), "no Sobol' input {name}");
    }
    for o in ["log10_p_gen4", "log10_p_bl1630", "p_gen4_minus_p_bl1630"] {
        let rows: Vec<usize> = (0..n.len()).filter(|&i| n[i] == nmax && out[i] == o).collect();
        let sum: f64 = rows.iter().map(|&i| s1[i]).sum();
        assert!(sum <= 1.05 && sum > 0.3, "{o}: ΣS = {sum}");
        let g = rows.iter().find(|&&i| input[i] == "tk_gamma").unwrap();
        assert!(st[*g].abs() < 1e-12, "{o}: γ does not enter independent trials, S_T = {}", st[*g]);
    }
    // A redraw from the tables alone gives the same figures.
    let before = a.read(&format!("{dir}/uq_sobol.svg"));
    std::fs::remove_file(a.path(&format!("{dir}/uq_sobol.svg"))).unwrap();
    partlife::report::redraw(&a.path(dir)).unwrap();
    assert_eq!(a.read(&format!("{dir}/uq_sobol.svg")), before);
}

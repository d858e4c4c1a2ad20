//! Shared helpers of the CLI-level tests: a scratch copy of the repository's study and
//! datasets, and a runner of the built binary.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `text` with each `(from, to)` replaced (every occurrence); panics if a `from` is absent, so a
/// test that speeds a study up notices when the study changes under it.
pub fn edited(text: &str, edits: &[(&str, &str)]) -> String {
    let mut out = text.to_string();
    for (from, to) in edits {
        assert!(out.contains(from), "the text has no \"{from}\" to replace");
        out = out.replace(from, to);
    }
    out
}

/// A temporary project: `studies/{lifetime,dem_cold_test,crush_gen3_rt,calibrate_gen3_rt}.toml` and
/// `datasets/*.csv` copied from the repo.
pub struct Scratch {
    pub dir: partlife::io::TempDir,
}

impl Scratch {
    pub fn new() -> Self {
        let dir = partlife::io::TempDir::new("test").unwrap();
        for sub in ["studies", "datasets"] {
            std::fs::create_dir_all(dir.path().join(sub)).unwrap();
        }
        for f in ["lifetime.toml", "dem_cold_test.toml", "crush_gen3_rt.toml", "calibrate_gen3_rt.toml"] {
            std::fs::copy(root().join("studies").join(f), dir.path().join("studies").join(f)).unwrap();
        }
        for f in ["crush_bl1630.csv", "crush_gen4.csv", "crush_curves_gen3_rt.csv"] {
            std::fs::copy(root().join("datasets").join(f), dir.path().join("datasets").join(f)).unwrap();
        }
        Scratch { dir }
    }
    pub fn path(&self, rel: &str) -> PathBuf {
        self.dir.path().join(rel)
    }
    pub fn read(&self, rel: &str) -> String {
        std::fs::read_to_string(self.path(rel)).unwrap()
    }
    pub fn write(&self, rel: &str, text: &str) {
        std::fs::write(self.path(rel), text).unwrap();
    }
    /// Runs `partlife <args>` in the scratch directory.
    pub fn run(&self, args: &[&str]) -> Out {
        run_in(self.dir.path(), args)
    }
    /// Runs `partlife <args>` in the scratch directory with extra environment variables.
    pub fn run_env(&self, args: &[&str], env: &[(&str, &str)]) -> Out {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_partlife"));
        cmd.args(args).current_dir(self.dir.path());
        for (k, v) in env {
            cmd.env(k, v);
        }
        let o = cmd.output().unwrap();
        Out { code: o.status.code().unwrap_or(-1), stdout: String::from_utf8_lossy(&o.stdout).into_owned(), stderr: String::from_utf8_lossy(&o.stderr).into_owned() }
    }
    /// Edits `study` (a path under studies/) by replacing `from` with `to`, runs it, and checks
    /// the bad-input contract: exit code 2, no panic, one message naming the study file and
    /// every `expect` string, and nothing written under reports/.
    pub fn expect_bad_study(&self, study: &str, from: &str, to: &str, expect: &[&str]) {
        let text = self.read(study);
        assert!(text.contains(from), "the study has no \"{from}\"");
        self.write(study, &text.replacen(from, to, 1));
        let out = self.run(&["run", study, "--quiet"]);
        assert_eq!(out.code, 2, "exit code; stderr: {}", out.stderr);
        assert!(!out.stderr.contains("panicked"), "{}", out.stderr);
        assert_eq!(out.stderr.trim().lines().count(), 1, "one message: {}", out.stderr);
        let file = study.rsplit('/').next().unwrap_or(study);
        for e in expect.iter().chain(&[file]) {
            assert!(out.stderr.contains(e), "message lacks \"{e}\": {}", out.stderr);
        }
        assert!(self.report_files().is_empty(), "a failed run wrote {:?}", self.report_files());
    }
    /// Every file under reports/, relative, sorted.
    pub fn report_files(&self) -> Vec<String> {
        let mut out = Vec::new();
        walk(&self.path("reports"), &self.path("reports"), &mut out);
        out.sort();
        out
    }
}

fn walk(base: &Path, dir: &Path, out: &mut Vec<String>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            walk(base, &p, out);
        } else {
            out.push(p.strip_prefix(base).unwrap().display().to_string());
        }
    }
}

/// A numeric column of a report table (integers converted).
pub fn table_f64(path: &Path, name: &str) -> Vec<f64> {
    partlife::io::col_f64(&partlife::io::read_table(path).unwrap(), path, name).unwrap()
}

/// A column of a report table as text.
pub fn table_text(path: &Path, name: &str) -> Vec<String> {
    partlife::io::col_str(&partlife::io::read_table(path).unwrap(), path, name).unwrap()
}

/// Output of one CLI call.
pub struct Out {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

pub fn run_in(dir: &Path, args: &[&str]) -> Out {
    let o = Command::new(env!("CARGO_BIN_EXE_partlife")).args(args).current_dir(dir).output().unwrap();
    Out {
        code: o.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
    }
}

/// A crush calibration small enough to run twice in a test (12 design runs on a coarse mesh,
/// no refinement, 3 check runs; a few seconds), written to `studies/cal.toml` of `s` with its
/// curves, and an `[executor]` table with `executor` lines.
pub fn tiny_calibration(s: &Scratch, executor: &str) {
    let study = std::fs::read_to_string(root().join("studies/calibrate_gen3_rt.toml")).unwrap();
    let tiny = edited(&study, &[("design = 32", "design = 12"), ("rounds = 6", "rounds = 0"), ("points = 8\n", "points = 6\n"), ("steps = 20000", "steps = 2000"), ("burn_in = 5000", "burn_in = 800"), ("check = 32", "check = 3"), ("refinement = 8.0", "refinement = 4.0")]);
    s.write("studies/cal.toml", &format!("{tiny}\n[executor]\n{executor}\n"));
    std::fs::copy(root().join("datasets/crush_curves_gen3_rt.csv"), s.path("datasets/crush_curves_gen3_rt.csv")).unwrap();
}

/// Generator settings of one BL-16/30-like material with the chosen hidden physics
/// (`q` roundness curvature exponent, `alpha` size exponent, `temperatures`/`softening` TOML
/// fragments), `count` particles, `seed`.
pub fn bl_generator(q: f64, alpha: f64, count: usize, seed: u64, temperature: &str, softening: &str) -> String {
    format!(
        r#"seed = {seed}
platen = {{ youngs_modulus_pa = 210e9, poisson_ratio = 0.3 }}
[[material]]
file = "hidden.csv"
label = "BL 16/30"
id_prefix = "BL"
count = {count}
temperature_c = {temperature}
elastic = {{ youngs_modulus_pa = 112e9, poisson_ratio = 0.25 }}
diameter = {{ mean = 0.00089, sd = 0.00014, min = 0.00059, max = 0.00119 }}
roundness = {{ mean = 0.72, sd = 0.05 }}
sphericity = {{ mean = 0.87, sd = 0.04 }}
[material.nature]
strength_shape = 22.0
strength_scale_pa = 1.99e9
reference_diameter_m = 0.0009
size_exponent = {alpha}
curvature_exponent = {q}
{softening}
[material.measurement]
force_rel_sd = 0.01
force_resolution_n = 0.1
diameter_sd_m = 5e-6
diameter_resolution_m = 1e-6
shape_sd = 0.01
shape_resolution = 0.001
"#
    )
}

/// Whether an external reader a test needs is here: `Some(path)`, or None after printing
/// "SKIPPED <test>: <why>" — unless `expect_env` is set to 1 (`.ci/run` sets it where it
/// installed the package), which makes a missing program a failure.
pub fn program(test: &str, name: &str, package: &str, expect_env: &str) -> Option<PathBuf> {
    let found = std::env::var_os("PATH").and_then(|paths| std::env::split_paths(&paths).map(|d| d.join(name)).find(|p| p.is_file()));
    if found.is_none() {
        let why = format!("{name} not found (Debian package {package}; .ci/run installs it)");
        assert!(std::env::var(expect_env).as_deref() != Ok("1"), "{test}: {why}, but {expect_env}=1");
        let _ = std::io::Write::write_all(&mut std::io::stderr(), format!("\nSKIPPED {test}: {why}\n").as_bytes());
    }
    found
}

/// Text of a PDF by poppler's pdftotext (pages `first..=last`, all when None), with every run
/// of whitespace made one space, so a sentence wrapped over lines still matches.
pub fn pdf_text(pdftotext: &Path, pdf: &Path, pages: Option<(usize, usize)>) -> String {
    let mut cmd = Command::new(pdftotext);
    if let Some((a, b)) = pages {
        cmd.args(["-f", &a.to_string(), "-l", &b.to_string()]);
    }
    let o = cmd.arg(pdf).arg("-").output().unwrap();
    assert!(o.status.success(), "pdftotext {}: {}", pdf.display(), String::from_utf8_lossy(&o.stderr));
    one_space(&String::from_utf8_lossy(&o.stdout))
}

/// Every run of whitespace as one space.
pub fn one_space(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The first page of `report.html` in report directory `dir` as text (tags dropped, the
/// entities of [`figure_captions`] read back): everything before the contents list, the same
/// blocks the PDF's first page holds; and the file stems of the figures on it.
#[allow(dead_code)]
pub fn first_page(dir: &Path) -> (String, Vec<String>) {
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let head = html.split("<nav id=\"contents\">").next().unwrap();
    let figures = head.split("id=\"fig-").skip(1).filter_map(|r| r.split('"').next()).map(String::from).collect();
    (html_text(head), figures)
}

#[allow(dead_code)]
/// HTML as text: the tags dropped, `&amp;`, `&lt;`, `&gt;`, `&quot;` and `&#39;` read back.
fn html_text(html: &str) -> String {
    let mut text = String::new();
    let mut tag = false;
    for c in html.chars() {
        match c {
            '<' => tag = true,
            '>' => tag = false,
            c if !tag => text.push(c),
            _ => {}
        }
    }
    text.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", "\"").replace("&#39;", "'").replace("&amp;", "&")
}

/// The caption of each figure of `report.html` in report directory `dir`, by file stem (text
/// with the tags dropped, `&amp;`, `&lt;`, `&gt;`, `&quot;` and `&#39;` read back); asserts that
/// every figure has one and that none is the generic caption of a figure whose numbers the
/// document does not read ("Drawn from this report's tables").
#[allow(dead_code)]
pub fn figure_captions(dir: &Path) -> Vec<(String, String)> {
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let mut out = Vec::new();
    for part in html.split("<figure ").skip(1) {
        let stem = part.split("id=\"fig-").nth(1).and_then(|r| r.split('"').next()).unwrap_or("").to_string();
        let cap = part.split("<figcaption>").nth(1).and_then(|r| r.split("</figcaption>").next()).unwrap_or_else(|| panic!("{}: figure {stem} has no caption", dir.display()));
        let text = html_text(cap);
        assert!(!text.contains("Drawn from this report's tables"), "{}: figure {stem} has the generic caption", dir.display());
        out.push((stem, text));
    }
    assert!(!out.is_empty(), "{}: no figure in report.html", dir.display());
    out
}

/// Every row of an `evidence.csv` whose guard was computed: the printed critical Λ is the one the
/// decision uses, (p_family < α) exactly when (Λ > critical); and the failure counts are
/// present (at most the replicates). Returns the rows checked.
#[allow(dead_code)]
pub fn guard_agrees_with_critical(evidence: &Path, alpha: f64) -> usize {
    let (lr, crit, p) = (table_f64(evidence, "likelihood_ratio"), table_f64(evidence, "likelihood_ratio_critical"), table_f64(evidence, "p_family"));
    let (failed, reps) = (table_f64(evidence, "bootstrap_failures"), table_f64(evidence, "bootstrap_replicates"));
    let mut checked = 0;
    for i in 0..lr.len() {
        assert!(failed[i] <= reps[i], "{}: row {i}: {} failures of {} replicates", evidence.display(), failed[i], reps[i]);
        if p[i].is_nan() {
            continue;
        }
        assert_eq!(p[i] < alpha, lr[i] > crit[i], "{}: row {i}: Λ {} against critical {} but p_family {} (α {alpha})", evidence.display(), lr[i], crit[i], p[i]);
        checked += 1;
    }
    checked
}

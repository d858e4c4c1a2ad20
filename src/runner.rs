//! Runs a study into its report directory: the dispatch from a loaded study's kind to its
//! runner, at the top of the module graph (only the CLI and the benchmarks import it). Each
//! runner writes tables, figures (drawn from the tables only) and `manifest.json` to a
//! temporary directory renamed into place at the end ([`crate::runkit`]).
//!
//! # The study graph
//!
//! A study may read other studies' reports (a temperature study the chains of two
//! calibrations, a calibration another calibration's parameters, the curve-level discrepancy
//! study its calibration's runs); each kind declares them
//! ([`crate::study::LoadedStudy::prerequisites`]). Before a study runs, [`plan`] walks that graph
//! depth first and lists, in the order they must run, the prerequisites whose report under the
//! same reports root is
//!
//! * **missing** — no `manifest.json`, or a report file the reader needs is absent;
//! * **stale** — the study file's text differs from the one the manifest holds, an input's
//!   SHA-256 differs from the manifest's (or the input cannot be found), or a study it reads is
//!   itself run first.
//!
//! [`run_file`] runs them first, saying on stderr what runs and why, the same way for local and
//! Slurm executors; with [`Deps::Refuse`] (`--no-deps`) it refuses instead and names every one
//! at once. A cycle is refused naming it.
//!
//! Verified by the unit tests below (fake graphs) and `tests/prerequisites.rs`.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
pub use crate::runkit::{Deps, RunOptions, RunSummary};
use crate::schema::Prerequisite;
use crate::study::{LoadedStudy, Study};

/// Runs a loaded study.
pub fn run(study: &LoadedStudy, opts: &RunOptions) -> Result<RunSummary> {
    let ensembles = match &study.study {
        Study::Calibrate(_) => true,
        Study::Temperature(t) => !t.validation.is_empty(),
        _ => false,
    };
    if opts.executor == Some(crate::runkit::ExecutorKind::Slurm) && !ensembles {
        return Err(crate::error::Error::config(
            study.file.path.display().to_string(),
            "--executor slurm",
            "only calibration studies (kind = \"calibrate\") and temperature studies with [[validation]] send simulator ensembles to an executor; run this study without --executor",
        ));
    }
    match &study.study {
        Study::Lifetime(s) => crate::lifetime_study::run_lifetime(&study.file, s, opts),
        Study::Dem(s) => crate::dem::run::run_dem(&study.file, s, opts),
        Study::Crush(s) => crate::fem::run::run_crush(&study.file, s, opts),
        Study::Calibrate(s) => crate::calibrate::run::run_calibrate(&study.file, s, opts),
        Study::Uq(s) => crate::uq::run::run_uq(&study.file, s, opts),
        Study::Discrepancy(s) => crate::discrepancy::run::run_discrepancy(&study.file, s, opts),
        Study::DiscrepancyCurves(s) => crate::discrepancy::curves::run_curves(&study.file, s, opts),
        Study::Experiments(s) => crate::experiments::run_experiments(&study.file, s, opts),
        Study::Temperature(s) => crate::temperature::run_temperature(&study.file, s, opts),
        Study::Microstructure(s) => crate::micro::run_microstructure(&study.file, s, opts),
    }
}

/// Loads a study, runs the prerequisites its reports need ([`plan`], per `opts.deps`), then
/// runs it.
pub fn run_file(path: &Path, opts: &RunOptions) -> Result<RunSummary> {
    let loaded = crate::study::load(path)?;
    run_with_prerequisites(&loaded, opts)
}

/// Runs a loaded study after its missing or stale prerequisites (module docs).
pub fn run_with_prerequisites(loaded: &LoadedStudy, opts: &RunOptions) -> Result<RunSummary> {
    let steps = plan(loaded, &opts.reports_root)?;
    if !steps.is_empty() {
        // The study's own inputs before minutes of prerequisites.
        loaded.check_inputs()?;
        if opts.deps == Deps::Refuse {
            let listed: Vec<String> = steps.iter().map(|s| format!("{} ({}; read by {} of {})", s.study.display(), s.why, s.key, s.by.display())).collect();
            return Err(Error::config(
                loaded.file.path.display().to_string(),
                "prerequisites",
                format!("{} (--no-deps): {}; run {} first, or run without --no-deps", if steps.len() == 1 { "1 study's report is missing or stale".to_string() } else { format!("{} studies' reports are missing or stale", steps.len()) }, listed.join("; "), if steps.len() == 1 { "it" } else { "them" }),
            ));
        }
        for s in &steps {
            eprintln!("running {} first: {} (read by {} of {})", s.study.display(), s.why, s.key, s.by.display());
            let summary = run(&crate::study::load(&s.study)?, opts)?;
            eprintln!("wrote {} in {:.2} s", summary.report_dir.display(), summary.wall_time_s);
        }
    }
    run(loaded, opts)
}

/// A prerequisite to run before the study.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// Its study file.
    pub study: PathBuf,
    /// Why it runs (missing or stale, and what changed).
    pub why: String,
    /// The key of the study that reads it.
    pub key: String,
    /// The study that reads it.
    pub by: PathBuf,
}

/// The prerequisites of `loaded` to run first, in order (module docs).
pub fn plan(loaded: &LoadedStudy, reports_root: &Path) -> Result<Vec<Step>> {
    let mut steps = Vec::new();
    let mut seen = Vec::new();
    walk(&loaded.file.path, loaded.prerequisites()?, &mut vec![loaded.file.path.clone()], &mut seen, &mut steps, &|p| crate::study::load(p)?.prerequisites(), &|p, files| stale(p, files, reports_root))?;
    Ok(steps)
}

type Prereqs<'a> = &'a dyn Fn(&Path) -> Result<Vec<Prerequisite>>;
type Staleness<'a> = &'a dyn Fn(&Path, &[&str]) -> Result<Option<String>>;

/// Depth first through the graph: each prerequisite's own prerequisites before it; `stack` the
/// path from the study (for cycles), `seen` the studies already judged.
fn walk(by: &Path, prereqs: Vec<Prerequisite>, stack: &mut Vec<PathBuf>, seen: &mut Vec<PathBuf>, steps: &mut Vec<Step>, of: Prereqs, stale_of: Staleness) -> Result<()> {
    for p in prereqs {
        if let Some(k) = stack.iter().position(|s| *s == p.study) {
            let cycle: Vec<String> = stack[k..].iter().chain(std::iter::once(&p.study)).map(|s| s.display().to_string()).collect();
            return Err(Error::config(by.display().to_string(), &p.key, format!("the studies read each other's reports in a cycle: {}", cycle.join(" → "))));
        }
        if seen.contains(&p.study) {
            continue;
        }
        if !p.study.is_file() {
            return Err(Error::config(by.display().to_string(), &p.key, format!("{} does not exist", p.study.display())));
        }
        let own = of(&p.study)?;
        stack.push(p.study.clone());
        walk(&p.study, own.clone(), stack, seen, steps, of, stale_of)?;
        stack.pop();
        // Its own report's state first; else whether a study it reads is run first.
        let why = match stale_of(&p.study, &p.files)? {
            Some(why) => Some(why),
            None => own.iter().find(|q| steps.iter().any(|s| s.study == q.study)).map(|q| format!("{} is run first", q.study.display())),
        };
        if let Some(why) = why {
            steps.push(Step { study: p.study.clone(), why, key: p.key.clone(), by: by.to_path_buf() });
        }
        seen.push(p.study);
    }
    Ok(())
}

/// Why the report of `study` under `reports_root` cannot be used as it is (missing or stale, in
/// words), or None when it is current; `files` are the report files the reader needs.
pub fn stale(study: &Path, files: &[&str], reports_root: &Path) -> Result<Option<String>> {
    let dir = crate::schema::report_dir(reports_root, study);
    let manifest = dir.join("manifest.json");
    if !manifest.is_file() {
        return Ok(Some(format!("its report {} is missing", dir.display())));
    }
    if let Some(f) = files.iter().find(|f| !dir.join(f).is_file()) {
        return Ok(Some(format!("its report {} has no {f}", dir.display())));
    }
    let text = crate::io::read_input_text(&manifest)?;
    let Ok(m) = serde_json::from_str::<serde_json::Value>(&text) else {
        return Ok(Some(format!("its report's {} is not a readable manifest", manifest.display())));
    };
    let study_text = crate::io::read_input_text(study)?;
    if m["study_toml"].as_str() != Some(study_text.as_str()) {
        return Ok(Some(format!("{} changed since its report was written", study.display())));
    }
    for input in m["inputs"].as_array().map(Vec::as_slice).unwrap_or(&[]) {
        let (Some(p), Some(sha)) = (input["path"].as_str(), input["sha256"].as_str()) else { continue };
        match std::fs::read(p) {
            Ok(bytes) if crate::io::sha256_hex(&bytes) == sha => {}
            Ok(_) => return Ok(Some(format!("its input {p} changed since its report was written"))),
            Err(_) => return Ok(Some(format!("its input {p} cannot be found from this directory"))),
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Plans over a fake graph: `edges` study → studies it reads; `stale` the studies whose
    /// reports are missing or stale.
    fn planned(root: &str, edges: &[(&str, &[&str])], stale: &[&str]) -> Result<Vec<String>> {
        let dir = crate::io::TempDir::new("plan").unwrap();
        let path = |s: &str| dir.path().join(s);
        let graph: HashMap<PathBuf, Vec<Prerequisite>> = edges.iter().map(|(a, bs)| (path(a), bs.iter().map(|b| Prerequisite { key: format!("reads.{b}"), study: path(b), files: vec![] }).collect())).collect();
        for (a, bs) in edges {
            for s in std::iter::once(a).chain(bs.iter()) {
                std::fs::write(path(s), "").unwrap();
            }
        }
        let of = |p: &Path| Ok(graph.get(p).cloned().unwrap_or_default());
        let stale_of = |p: &Path, _: &[&str]| Ok(stale.iter().any(|s| path(s) == p).then(|| "missing".to_string()));
        let mut steps = Vec::new();
        walk(&path(root), of(&path(root))?, &mut vec![path(root)], &mut Vec::new(), &mut steps, &of, &stale_of)?;
        Ok(steps.iter().map(|s| format!("{}:{}", s.study.file_name().unwrap().to_string_lossy(), s.why.replace(&dir.path().display().to_string(), ""))).collect())
    }

    #[test]
    fn prerequisites_run_in_order_and_once() {
        // temperature reads rt, c800 and curves; c800 and curves read rt.
        let edges: &[(&str, &[&str])] = &[("temperature", &["rt", "c800", "curves"]), ("c800", &["rt"]), ("curves", &["rt"])];
        assert_eq!(planned("temperature", edges, &["rt", "c800", "curves"]).unwrap(), vec!["rt:missing", "c800:missing", "curves:missing"]);
        // Current reports run nothing; a stale one reruns what reads it.
        assert!(planned("temperature", edges, &[]).unwrap().is_empty());
        assert_eq!(planned("temperature", edges, &["c800"]).unwrap(), vec!["c800:missing"]);
        assert_eq!(planned("temperature", edges, &["rt"]).unwrap(), vec!["rt:missing", "c800:/rt is run first", "curves:/rt is run first"]);
    }

    #[test]
    fn a_cycle_is_refused_naming_it() {
        let edges: &[(&str, &[&str])] = &[("a", &["b"]), ("b", &["c"]), ("c", &["a"])];
        let e = planned("a", edges, &[]).unwrap_err().to_string();
        assert!(e.contains("cycle") && e.contains("a → ") && e.ends_with("/a"), "{e}");
    }
}

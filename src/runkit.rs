//! What every study's run shares: the run options and summary, the clock,
//! progress bars, recording figures, and committing a report directory with its
//! `manifest.json`. Below every study module: study runners import it; it imports none of them
//! (only `io`, `report` and `schema`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::error::{Error, Result};
use crate::io::{InputFile, Manifest, ReportDir, git_state};
use crate::schema::StudyFile;

/// What a run produced, for the CLI to print.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// The committed report directory.
    pub report_dir: PathBuf,
    /// Wall time (s).
    pub wall_time_s: f64,
    /// One line per material with its headline numbers.
    pub headlines: Vec<String>,
}

/// Options of a run that are not part of the study.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Root of the report directories (`reports`).
    pub reports_root: PathBuf,
    /// Show a progress bar on stderr when it is a terminal.
    pub progress: bool,
    /// Where simulator ensembles run (`partlife run --executor`), overriding the study's
    /// `[executor] kind`; None: the study's choice, local by default.
    pub executor: Option<ExecutorKind>,
    /// What to do with a study this one reads whose report is missing or stale.
    pub deps: Deps,
    /// Write `report.pdf` and `report.html` with the report (`--no-document`: false).
    pub documents: bool,
}

/// What a run does with a prerequisite study (one whose report it reads) when that report is
/// missing or stale (`crate::runner`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Deps {
    /// Run it first, saying what runs and why (default).
    #[default]
    Run,
    /// Refuse, listing every missing or stale prerequisite at once (`--no-deps`).
    Refuse,
}

impl RunOptions {
    /// Reports under `reports_root`, the study's executor, prerequisites run when needed.
    pub fn new(reports_root: impl Into<PathBuf>, progress: bool) -> Self {
        RunOptions { reports_root: reports_root.into(), progress, executor: None, deps: Deps::Run, documents: true }
    }
}

/// Where a batch of simulator evaluations runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExecutorKind {
    /// In this process, in parallel over the rayon threads.
    #[default]
    Local,
    /// As Slurm array jobs whose tasks run `partlife eval` (`crate::calibrate::executor`).
    Slurm,
}

impl ExecutorKind {
    /// "local" or "slurm".
    pub fn name(self) -> &'static str {
        match self {
            ExecutorKind::Local => "local",
            ExecutorKind::Slurm => "slurm",
        }
    }
}

/// Default progress template: elapsed time, bar, count and message.
pub const PROGRESS_COUNT: &str = "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} {msg} (eta {eta})";

/// A progress bar on stderr (hidden when `show` is false) with an indicatif `template`.
pub fn progress_bar(len: u64, show: bool, template: &str) -> ProgressBar {
    let target = if show { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
    let pb = ProgressBar::with_draw_target(Some(len), target);
    if let Ok(style) = ProgressStyle::with_template(template) {
        pb.set_style(style);
    }
    pb
}

/// Starts the report directory of study `name` under the run's reports root, with the run's
/// choice of documents.
pub fn report_dir(opts: &RunOptions, name: &str) -> Result<ReportDir> {
    let mut dir = ReportDir::create(&opts.reports_root, name)?;
    dir.set_documents(opts.documents);
    Ok(dir)
}

/// `summary.md` of a study kind whose run states its results as headline lines (lifetime, DEM,
/// crush FE): the title and one bullet per line, each generated from the run's numbers.
pub fn headline_summary(title: &str, lines: &[String]) -> String {
    let mut md = format!("# {title}\n\n## Headline\n\n");
    for l in lines {
        md.push_str(&format!("* {}\n", l.trim()));
    }
    md
}

/// Records rendered figures in the report and any legend that had to hide data as a failure.
pub fn record_figures(dir: &mut ReportDir, rendered: crate::report::Rendered, failures: &mut Vec<String>) {
    dir.record(rendered.files);
    for (fig, n) in rendered.legend_hidden.iter().filter(|(_, n)| *n > 0) {
        failures.push(format!("figure {fig}: its legend hides {n} data samples (no free corner)"));
    }
}

/// When a run started: wall clock for the manifest, monotonic clock for its duration.
#[derive(Debug, Clone, Copy)]
pub struct RunClock {
    start: Instant,
    started_unix_s: u64,
}

impl RunClock {
    /// Now.
    pub fn start() -> Self {
        let started_unix_s = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
        RunClock { start: Instant::now(), started_unix_s }
    }
    /// Seconds since the start.
    pub fn seconds(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}

/// What a run records in its manifest besides the study.
pub struct RunRecord {
    /// Every input file with its hash.
    pub inputs: Vec<InputFile>,
    /// The study's seed.
    pub seed: u64,
    /// When the run started.
    pub clock: RunClock,
    /// Model evaluations by kind.
    pub evaluations: BTreeMap<String, u64>,
    /// What failed without stopping the run (figures, evaluations).
    pub failures: Vec<String>,
    /// What the run found in its inputs that a reader must know (materials tested at
    /// different temperatures); each also printed on stderr.
    pub warnings: Vec<String>,
}

/// Writes `manifest.json` (listing every file of the report), then — unless the run turned them
/// off — `report.pdf` and `report.html` from the report's files (`crate::report::build`), and
/// renames the report into place. Documents that cannot be written do not lose the run: the
/// manifest then records why among its failures and lists no document.
pub fn commit_with_manifest(mut dir: ReportDir, loaded: &StudyFile, study_resolved: serde_json::Value, run: RunRecord) -> Result<PathBuf> {
    let (git_revision, git_dirty) = git_state(loaded.path.parent().unwrap_or(Path::new(".")));
    let mut outputs = dir.files().to_vec();
    outputs.push("manifest.json".into());
    let documents = ["report.pdf".to_string(), "report.html".to_string()];
    if dir.documents() {
        outputs.extend(documents.iter().cloned());
    }
    let mut manifest = Manifest {
        partlife_version: env!("CARGO_PKG_VERSION").into(),
        partlife_revision: option_env!("PARTLIFE_REVISION").map(String::from),
        study: loaded.name.clone(),
        study_file: loaded.path.display().to_string(),
        study_toml: loaded.text.clone(),
        study_resolved,
        inputs: run.inputs,
        seed: run.seed,
        threads: rayon::current_num_threads(),
        git_revision,
        git_dirty,
        started_unix_s: run.clock.started_unix_s,
        wall_time_s: run.clock.seconds(),
        evaluations: run.evaluations,
        failures: run.failures,
        warnings: run.warnings,
        outputs,
    };
    let json = |m: &Manifest| serde_json::to_vec_pretty(m).map_err(|e| Error::numerical("manifest", e.to_string()));
    dir.write_bytes("manifest.json", &json(&manifest)?)?;
    if dir.documents() {
        match crate::report::build::write(dir.path()) {
            Ok(files) => dir.record(files),
            Err(e) => {
                manifest.failures.push(format!("report.pdf and report.html not written: {e}"));
                manifest.outputs.retain(|o| !documents.contains(o));
                let p = dir.path().join("manifest.json");
                crate::io::write_atomic(&p, &json(&manifest)?)?;
            }
        }
    }
    dir.commit()
}

//! Where batches of simulator evaluations run: in this process (`local`, the rayon path of
//! [`Simulator::simulate_batch`]) or on a Slurm cluster as array jobs (`slurm`).
//!
//! ```toml
//! [executor]                    # in a calibration study; `partlife run --executor` overrides kind
//! kind = "slurm"                # "local" (default) or "slurm"
//! partition = "compute"         # sbatch --partition (default: the cluster's default)
//! time_limit = "01:00:00"       # sbatch --time of one array task
//! evaluations_per_task = 1      # θ's one array task evaluates
//! max_array_size = 1000         # tasks per array job; a larger batch is split into several
//! cpus_per_task = 1             # sbatch --cpus-per-task, and the task's worker threads
//! retries = 2                   # resubmissions of the tasks that left evaluations missing
//! poll_seconds = 2.0            # how often squeue is asked
//! # program = "/shared/bin/partlife"   # the binary tasks run (default: this one)
//! # work_dir = "/shared/partlife-work"  # batches and task logs (default: <cache>/slurm)
//! ```
//!
//! # The Slurm protocol
//!
//! The calibration's evaluations are cached on disk ([`super::cache::Cached`]: one JSON file per
//! θ, keyed by the model's configuration and θ's bits, written atomically). The driver
//! ([`Slurm::run`]) hands the θ's without an entry to Slurm:
//!
//! 1. it writes a batch file (`<work>/<tag>/batch.json`: the study file, the cache directory, the
//!    SHA-256 of the model's configuration, `evaluations_per_task`, the θ's with their exact bits)
//!    and submits one `sbatch --array=0-(n−1)` job per at most `max_array_size` tasks, each task
//!    running `partlife eval <batch.json>` ([`super::eval::eval_task`]) on its slice of θ's;
//! 2. a task rebuilds the model from the study file (refusing a study whose model configuration
//!    changed since submission), evaluates those of its θ's not yet in the cache, stores each
//!    result in the shared cache as soon as it is computed, by temporary file and rename — a
//!    task killed mid-write leaves a whole entry or none, and keeps what it finished — and
//!    writes a small timing record;
//! 3. the driver polls `squeue` until the array has left the queue, reads every task's final
//!    state from `scontrol show job` (`COMPLETED`, `FAILED`, `TIMEOUT`, `CANCELLED`, …) — from
//!    the accounting (`sacct`, when installed) where scontrol fails or has forgotten the job —
//!    and looks the θ's up in the cache;
//! 4. θ's still missing are resubmitted, up to `retries` times; a cancelled task's θ's are not
//!    (someone cancelled them) and are reported; nor are those of a task whose state neither
//!    scontrol nor sacct can tell (it may still run, or have been cancelled): "state unknown" is
//!    reported as its own outcome with both commands' errors. What is still missing then is returned as a
//!    failed evaluation with its θ, the task's state and the tail of its log — never an abort:
//!    the calibration records failed evaluations as it does the model's own failures.
//!
//! A driver that is killed and restarted finds every finished entry in the cache and submits only
//! the rest. The outputs come from the same model code as a local run and travel as JSON with
//! exact round-trip, so a Slurm run's results are bit-identical to a local run's
//! (`tests/executor.rs`, `tests/slurm.rs`).
//!
//! Requirements: `sbatch`, `squeue` and `scontrol` on the driver's PATH (checked first:
//! `--executor slurm` without them is bad input, exit 2); the study, its data, the cache and work
//! directories and the binary on a filesystem every node shares, at the same paths.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use super::cache::Cached;
use crate::error::{Error, Result};
use crate::io::{sha256_hex, write_atomic};
use crate::model::{OutputSpec, Simulator};
use crate::params::ParamSpace;
use crate::runkit::ExecutorKind;

/// `[executor]` of a study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExecutorOptions {
    /// Local or Slurm.
    #[serde(default)]
    pub kind: ExecutorKind,
    /// Slurm partition (default: the cluster's default partition).
    #[serde(default)]
    pub partition: Option<String>,
    /// Time limit of one array task (`sbatch --time`: `[D-]HH:MM:SS`, `MM:SS` or minutes).
    #[serde(default = "time_limit")]
    pub time_limit: String,
    /// θ's one array task evaluates.
    #[serde(default = "one")]
    pub evaluations_per_task: usize,
    /// Most tasks in one array job.
    #[serde(default = "max_array")]
    pub max_array_size: usize,
    /// CPUs of a task (and its worker threads).
    #[serde(default = "one")]
    pub cpus_per_task: usize,
    /// Resubmissions of tasks whose evaluations are missing.
    #[serde(default = "retries")]
    pub retries: usize,
    /// Seconds between `squeue` polls.
    #[serde(default = "poll")]
    pub poll_seconds: f64,
    /// The binary the tasks run (default: the driver's own; relative to the study file).
    #[serde(default)]
    pub program: Option<PathBuf>,
    /// Batches and task logs (default: `<cache directory>/slurm`; relative to the study file).
    #[serde(default)]
    pub work_dir: Option<PathBuf>,
}

fn time_limit() -> String {
    "01:00:00".into()
}
fn one() -> usize {
    1
}
fn max_array() -> usize {
    1000
}
fn retries() -> usize {
    2
}
fn poll() -> f64 {
    2.0
}

impl Default for ExecutorOptions {
    fn default() -> Self {
        ExecutorOptions { kind: ExecutorKind::Local, partition: None, time_limit: time_limit(), evaluations_per_task: 1, max_array_size: max_array(), cpus_per_task: 1, retries: retries(), poll_seconds: poll(), program: None, work_dir: None }
    }
}

impl ExecutorOptions {
    /// Checks every option (`file` names the study in messages).
    pub fn validate(&self, file: &str) -> Result<()> {
        let key = |k: &str| format!("executor.{k}");
        if let Some(p) = &self.partition
            && (p.is_empty() || p.chars().any(|c| c.is_whitespace() || c == ','))
        {
            return Err(Error::config(file, key("partition"), format!("a partition name without spaces or commas, got \"{p}\"")));
        }
        let t = &self.time_limit;
        if t.is_empty() || !t.chars().all(|c| c.is_ascii_digit() || c == ':' || c == '-') || t.matches(':').count() > 2 {
            return Err(Error::config(file, key("time_limit"), format!("a Slurm time limit ([D-]HH:MM:SS, MM:SS or minutes), got \"{t}\"")));
        }
        for (name, v, hi) in [("evaluations_per_task", self.evaluations_per_task, 100_000), ("max_array_size", self.max_array_size, 1_000_000), ("cpus_per_task", self.cpus_per_task, 4096)] {
            if !(1..=hi).contains(&v) {
                return Err(Error::config(file, key(name), format!("must lie in 1…{hi}, got {v}")));
            }
        }
        if self.retries > 20 {
            return Err(Error::config(file, key("retries"), format!("must lie in 0…20, got {}", self.retries)));
        }
        if !(self.poll_seconds.is_finite() && (0.05..=600.0).contains(&self.poll_seconds)) {
            return Err(Error::config(file, key("poll_seconds"), format!("must lie in 0.05…600 s, got {}", self.poll_seconds)));
        }
        Ok(())
    }
}

/// A batch file: what the tasks of one submission evaluate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Batch {
    /// The calibration study the model is built from (absolute).
    pub study: PathBuf,
    /// The evaluation cache (absolute).
    pub cache_dir: PathBuf,
    /// SHA-256 of the model's configuration at submission.
    pub config_sha256: String,
    /// θ's per task.
    pub evaluations_per_task: usize,
    /// The θ's, in task order.
    pub thetas: Vec<Vec<f64>>,
}

impl Batch {
    /// The number of array tasks.
    pub fn tasks(&self) -> usize {
        self.thetas.len().div_ceil(self.evaluations_per_task.max(1))
    }

    /// The θ indices of task `t`.
    pub fn slice(&self, t: usize) -> std::ops::Range<usize> {
        let k = self.evaluations_per_task.max(1);
        (t * k).min(self.thetas.len())..((t + 1) * k).min(self.thetas.len())
    }
}

/// What one task did (`task-<i>.json` next to the batch file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TaskRecord {
    /// Array task index.
    pub task: usize,
    /// θ's evaluated.
    pub evaluations: usize,
    /// θ's of the task already in the cache (a rerun of a killed task), not evaluated again.
    pub already_cached: usize,
    /// Of the evaluated, those the model failed at (stored as failed entries).
    pub model_failures: usize,
    /// Reading the study and building the model (s).
    pub setup_s: f64,
    /// The evaluations, summed over them (s of worker time).
    pub compute_s: f64,
    /// Writing the cache entries, summed over them (s).
    pub write_s: f64,
    /// Start (Unix time, s).
    pub started_unix_s: f64,
    /// End (Unix time, s).
    pub finished_unix_s: f64,
}

/// Now, as Unix time (s).
pub fn unix_now() -> f64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs_f64()).unwrap_or(0.0)
}

/// SHA-256 of a model configuration (what a batch records and a task checks).
pub fn config_digest(config: &str) -> String {
    sha256_hex(config.as_bytes())
}

/// The record file of task `task` of a batch.
pub fn task_record_path(batch_path: &Path, task: usize) -> PathBuf {
    batch_path.with_file_name(format!("task-{task}.json"))
}

/// One submitted array job, for `executor.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayRecord {
    /// Slurm job id.
    pub job_id: String,
    /// 0 for the first submission, 1… for retries.
    pub attempt: usize,
    /// Array tasks.
    pub tasks: usize,
    /// θ's submitted.
    pub evaluations: usize,
    /// Tasks by final state (`COMPLETED 15, FAILED 1`).
    pub states: String,
    /// The `sbatch` call (s).
    pub submit_s: f64,
    /// From the end of `sbatch` to the first task's start (s; NaN without task records).
    pub queue_s: f64,
    /// From the submission to the array leaving the queue (s).
    pub wall_s: f64,
    /// Mean per task: reading the study and building the model (s).
    pub setup_s: f64,
    /// Sum over tasks of the evaluations' time (s).
    pub compute_s: f64,
    /// Mean per task: writing its cache entries (s).
    pub write_s: f64,
    /// Reading the batch's results from the cache (s).
    pub collect_s: f64,
}

/// What the Slurm executor did in a run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SlurmLog {
    /// Every array job.
    pub arrays: Vec<ArrayRecord>,
    /// What went wrong without stopping the run (failed and cancelled tasks).
    pub events: Vec<String>,
    /// θ's submitted, over all attempts.
    pub submitted: u64,
    /// θ's returned as failed after every retry (or cancelled).
    pub failed: u64,
}

/// The Slurm driver of one run.
pub struct Slurm {
    opts: ExecutorOptions,
    program: PathBuf,
    study: PathBuf,
    cache_dir: PathBuf,
    config_sha256: String,
    work: PathBuf,
    log: Mutex<SlurmLog>,
    serial: Mutex<u64>,
}

/// The Slurm commands the driver needs.
pub const SLURM_COMMANDS: [&str; 3] = ["sbatch", "squeue", "scontrol"];

/// The first of `commands` not found on PATH.
pub fn missing_command(commands: &[&str]) -> Option<String> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    commands
        .iter()
        .find(|c| {
            !std::env::split_paths(&path).any(|d| {
                let f = d.join(c);
                f.is_file() && std::fs::metadata(&f).map(|m| std::os::unix::fs::PermissionsExt::mode(&m.permissions()) & 0o111 != 0).unwrap_or(false)
            })
        })
        .map(|c| c.to_string())
}

fn absolute(p: &Path) -> Result<PathBuf> {
    std::path::absolute(p).map_err(|e| Error::read(p, e))
}

/// Quotes a word for the shell (`--wrap`).
fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

fn run_command(cmd: &mut Command, what: &str) -> Result<String> {
    let out = cmd.output().map_err(|e| Error::numerical("slurm executor", format!("{what} could not be started: {e}")))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        return Err(Error::numerical("slurm executor", format!("{what} failed ({}): {}", out.status, err.trim())));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Task index → state from `scontrol show job -o` lines (`ArrayTaskId=… JobState=…`).
fn parse_scontrol(text: &str) -> HashMap<usize, String> {
    let mut out = HashMap::new();
    for line in text.lines() {
        let field = |k: &str| line.split_whitespace().find_map(|w| w.strip_prefix(k)).map(str::to_string);
        if let (Some(ids), Some(state)) = (field("ArrayTaskId="), field("JobState=")) {
            for t in task_ids(&ids) {
                out.insert(t, state.clone());
            }
        }
    }
    out
}

/// Task index → state from `sacct -n -P -X -o JobID,State -j <id>` lines (`123_4|COMPLETED`,
/// `123_[5-7]|PENDING`, `123_2|CANCELLED by 0`): the state's first word, the lines of job `id`.
fn parse_sacct(text: &str, id: &str) -> HashMap<usize, String> {
    let mut out = HashMap::new();
    for line in text.lines() {
        let Some((job, state)) = line.trim().split_once('|') else { continue };
        let Some(tasks) = job.strip_prefix(id).and_then(|t| t.strip_prefix('_')) else { continue };
        let state = state.split_whitespace().next().unwrap_or("").to_string();
        for t in task_ids(tasks.trim_start_matches('[').trim_end_matches(']')) {
            out.insert(t, state.clone());
        }
    }
    out
}

/// The task indices of a `scontrol` ArrayTaskId value (`3`, `0-7`, `1,4-6`, `0-15%4`).
fn task_ids(v: &str) -> Vec<usize> {
    let v = v.split('%').next().unwrap_or("");
    let mut out = Vec::new();
    for part in v.split(',') {
        match part.split_once('-') {
            Some((a, b)) => {
                if let (Ok(a), Ok(b)) = (a.parse::<usize>(), b.parse::<usize>()) {
                    out.extend(a..=b);
                }
            }
            None => out.extend(part.parse::<usize>().ok()),
        }
    }
    out
}

impl Slurm {
    /// A driver for the calibration `study` whose evaluations are cached in `cache_dir` under the
    /// model configuration `config`. Refused (bad input) when a Slurm command is missing.
    pub fn new(opts: &ExecutorOptions, study: &Path, cache_dir: &Path, config: &str) -> Result<Self> {
        if let Some(c) = missing_command(&SLURM_COMMANDS) {
            return Err(Error::config("--executor slurm", c.clone(), format!("the Slurm executor needs {} on PATH; `{c}` is not there (install Slurm's client commands, or run with --executor local)", SLURM_COMMANDS.join(", "))));
        }
        // Relative paths of the study are relative to the study file.
        let of_study = |p: &Path| absolute(&study.parent().map_or(p.to_path_buf(), |d| d.join(p)));
        let program = match &opts.program {
            Some(p) => of_study(p)?,
            None => std::env::current_exe().map_err(|e| Error::numerical("slurm executor", format!("the running binary's path: {e}")))?,
        };
        let cache_dir = absolute(cache_dir)?;
        let work = match &opts.work_dir {
            Some(w) => of_study(w)?,
            None => cache_dir.join("slurm"),
        };
        std::fs::create_dir_all(&work).map_err(|e| Error::write(&work, e))?;
        Ok(Slurm { opts: opts.clone(), program, study: absolute(study)?, cache_dir, config_sha256: config_digest(config), work, log: Mutex::new(SlurmLog::default()), serial: Mutex::new(0) })
    }

    /// What the driver did so far.
    pub fn log(&self) -> SlurmLog {
        self.log.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    fn new_tag(&self) -> String {
        let mut s = self.serial.lock().unwrap_or_else(|e| e.into_inner());
        *s += 1;
        format!("batch-{}-{}-{}", std::process::id(), (unix_now() * 1e3) as u64, *s)
    }

    /// Submits `thetas` as one array job; returns (job id, batch file, tasks, sbatch seconds).
    fn submit(&self, thetas: &[Vec<f64>]) -> Result<(String, PathBuf, usize, f64)> {
        let dir = self.work.join(self.new_tag());
        let batch = Batch { study: self.study.clone(), cache_dir: self.cache_dir.clone(), config_sha256: self.config_sha256.clone(), evaluations_per_task: self.opts.evaluations_per_task, thetas: thetas.to_vec() };
        let path = dir.join("batch.json");
        let json = serde_json::to_vec(&batch).map_err(|e| Error::numerical("batch file", e.to_string()))?;
        write_atomic(&path, &json)?;
        let tasks = batch.tasks();
        let wrap = format!("{} --threads {} eval {}", shell_quote(&self.program.display().to_string()), self.opts.cpus_per_task, shell_quote(&path.display().to_string()));
        let mut cmd = Command::new("sbatch");
        cmd.arg("--parsable")
            .arg("--job-name=partlife-eval")
            .arg(format!("--array=0-{}", tasks - 1))
            .arg(format!("--time={}", self.opts.time_limit))
            .arg(format!("--cpus-per-task={}", self.opts.cpus_per_task))
            .arg(format!("--output={}", dir.join("task-%a.out").display()))
            .arg(format!("--wrap={wrap}"));
        if let Some(p) = &self.opts.partition {
            cmd.arg(format!("--partition={p}"));
        }
        let t = Instant::now();
        let out = run_command(&mut cmd, "sbatch")?;
        let secs = t.elapsed().as_secs_f64();
        let id = out.trim().split(';').next().unwrap_or("").to_string();
        if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
            return Err(Error::numerical("slurm executor", format!("sbatch printed no job id: \"{}\"", out.trim())));
        }
        Ok((id, path, tasks, secs))
    }

    /// Whether any of `ids` is still in the queue (an id squeue no longer knows has left it).
    fn queued(&self, ids: &[String]) -> Result<bool> {
        let out = Command::new("squeue").arg("-h").arg("-o").arg("%i").arg("-j").arg(ids.join(",")).output().map_err(|e| Error::numerical("slurm executor", format!("squeue could not be started: {e}")))?;
        if !out.status.success() {
            let err = String::from_utf8_lossy(&out.stderr);
            if err.contains("Invalid job id") {
                return Ok(false);
            }
            return Err(Error::numerical("slurm executor", format!("squeue failed: {}", err.trim())));
        }
        Ok(!String::from_utf8_lossy(&out.stdout).trim().is_empty())
    }

    /// The final state of every task of job `id`, by task index: from `scontrol show job -o`,
    /// else (scontrol failed, or no longer knows the job) from the accounting, `sacct`; Err
    /// with both failures when neither answers (the states are then unknown).
    fn states(&self, id: &str) -> std::result::Result<HashMap<usize, String>, String> {
        let scontrol = run_command(Command::new("scontrol").arg("show").arg("job").arg("-o").arg(id), "scontrol").map(|t| parse_scontrol(&t));
        match scontrol {
            Ok(s) if !s.is_empty() => Ok(s),
            first => {
                let why = first.err().map_or_else(|| "scontrol no longer knows the job".to_string(), |e| e.to_string());
                match run_command(Command::new("sacct").arg("-n").arg("-P").arg("-X").arg("-o").arg("JobID,State").arg("-j").arg(id), "sacct") {
                    Ok(t) if !parse_sacct(&t, id).is_empty() => Ok(parse_sacct(&t, id)),
                    Ok(_) => Err(format!("{why}; sacct has no record of job {id}")),
                    Err(e) => Err(format!("{why}; {e}")),
                }
            }
        }
    }

    /// Evaluates through Slurm every θ of `thetas` that `done` says has no cache entry yet, and
    /// returns per θ None (its entry is there now) or the reason it is not.
    pub fn run(&self, thetas: &[Vec<f64>], done: &(dyn Fn(&[f64]) -> bool + Sync), progress: &dyn Fn(&str)) -> Vec<Option<String>> {
        let key = |t: &[f64]| t.iter().map(|v| v.to_bits()).collect::<Vec<u64>>();
        let mut unique: Vec<Vec<f64>> = Vec::new();
        let mut seen = std::collections::HashSet::new();
        for t in thetas {
            if !done(t) && seen.insert(key(t)) {
                unique.push(t.clone());
            }
        }
        let mut reasons: HashMap<Vec<u64>, String> = HashMap::new();
        let mut missing = unique;
        let mut attempt = 0;
        while !missing.is_empty() && attempt <= self.opts.retries {
            let chunk = self.opts.max_array_size * self.opts.evaluations_per_task;
            let mut jobs = Vec::new();
            let mut next = Vec::new();
            for part in missing.chunks(chunk) {
                match self.submit(part) {
                    Ok((id, path, tasks, secs)) => jobs.push((id, path, tasks, secs, Instant::now(), part.to_vec())),
                    Err(e) => {
                        // sbatch refused (a controller down, a full queue): tried again next attempt.
                        self.log.lock().unwrap_or_else(|p| p.into_inner()).events.push(format!("attempt {attempt}: {e}"));
                        for t in part {
                            reasons.insert(key(t), format!("attempt {attempt}: {e}"));
                            next.push(t.clone());
                        }
                    }
                }
            }
            {
                let mut log = self.log.lock().unwrap_or_else(|e| e.into_inner());
                log.submitted += jobs.iter().map(|j| j.5.len() as u64).sum::<u64>();
            }
            let ids: Vec<String> = jobs.iter().map(|j| j.0.clone()).collect();
            let total: usize = jobs.iter().map(|j| j.5.len()).sum();
            let mut gone_at: HashMap<String, f64> = HashMap::new();
            let start = Instant::now();
            while !ids.is_empty() {
                let mut any = false;
                for (id, _, _, _, t0, _) in &jobs {
                    if gone_at.contains_key(id) {
                        continue;
                    }
                    match self.queued(std::slice::from_ref(id)) {
                        Ok(true) => any = true,
                        Ok(false) => {
                            gone_at.insert(id.clone(), t0.elapsed().as_secs_f64());
                        }
                        Err(e) => {
                            // A transient squeue failure: ask again at the next poll.
                            any = true;
                            if start.elapsed() > Duration::from_secs(3600) {
                                self.log.lock().unwrap_or_else(|p| p.into_inner()).events.push(format!("squeue kept failing for job {id}: {e}"));
                                gone_at.insert(id.clone(), f64::NAN);
                            }
                        }
                    }
                }
                let finished = jobs.iter().flat_map(|j| j.5.iter()).filter(|t| done(t)).count();
                progress(&format!("slurm: {} array job(s) {}, attempt {attempt}: {finished}/{total} evaluations in the cache", ids.len(), ids.join(", ")));
                if !any {
                    break;
                }
                std::thread::sleep(Duration::from_secs_f64(self.opts.poll_seconds));
            }
            for (id, path, tasks, submit_s, t0, part) in jobs {
                let (states, unknown) = match self.states(&id) {
                    Ok(s) => (s, None),
                    Err(why) => (HashMap::new(), Some(why)),
                };
                let batch_tasks: Vec<usize> = (0..tasks).collect();
                let k = self.opts.evaluations_per_task;
                let records: Vec<TaskRecord> = batch_tasks.iter().filter_map(|&t| std::fs::read_to_string(task_record_path(&path, t)).ok().and_then(|s| serde_json::from_str(&s).ok())).collect();
                let c0 = Instant::now();
                let present: Vec<bool> = part.iter().map(|t| done(t)).collect();
                let collect_s = c0.elapsed().as_secs_f64();
                let mut counts: std::collections::BTreeMap<String, usize> = std::collections::BTreeMap::new();
                for t in &batch_tasks {
                    *counts.entry(states.get(t).cloned().unwrap_or_else(|| "UNKNOWN".into())).or_default() += 1;
                }
                let submitted_unix = unix_now() - t0.elapsed().as_secs_f64();
                let first_start = records.iter().map(|r| r.started_unix_s).fold(f64::INFINITY, f64::min);
                let n = records.len().max(1) as f64;
                let rec = ArrayRecord {
                    job_id: id.clone(),
                    attempt,
                    tasks,
                    evaluations: part.len(),
                    states: counts.iter().map(|(s, n)| format!("{s} {n}")).collect::<Vec<_>>().join(", "),
                    submit_s,
                    queue_s: if first_start.is_finite() { first_start - submitted_unix } else { f64::NAN },
                    wall_s: gone_at.get(&id).copied().unwrap_or(f64::NAN),
                    setup_s: records.iter().map(|r| r.setup_s).sum::<f64>() / n,
                    compute_s: records.iter().map(|r| r.compute_s).sum(),
                    write_s: records.iter().map(|r| r.write_s).sum::<f64>() / n,
                    collect_s,
                };
                let mut log = self.log.lock().unwrap_or_else(|e| e.into_inner());
                log.arrays.push(rec);
                for (i, t) in part.iter().enumerate() {
                    if present[i] {
                        continue;
                    }
                    let task = i / k;
                    let Some(state) = states.get(&task).cloned() else {
                        // Its own outcome: a task whose state nobody can tell may still run or
                        // have been cancelled, so it is reported and not resubmitted blindly.
                        let why = unknown.clone().unwrap_or_else(|| format!("job {id} lists no state for the task"));
                        if i % k == 0 {
                            log.events.push(format!("array job {id} task {task}: state unknown ({why}); its {} evaluation(s) are recorded as failed, not resubmitted", part[i..].len().min(k)));
                        }
                        reasons.insert(key(t), format!("array job {id} task {task}: state unknown ({why}), result not in the cache"));
                        continue;
                    };
                    let tail = std::fs::read_to_string(path.with_file_name(format!("task-{task}.out"))).map(|s| s.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("").trim().to_string()).unwrap_or_default();
                    let why = format!("array job {id} task {task} ended {state} without its result (attempt {attempt}){}", if tail.is_empty() { String::new() } else { format!(": {tail}") });
                    if state == "CANCELLED" {
                        if i % k == 0 {
                            log.events.push(format!("array job {id} task {task} was cancelled: its {} evaluation(s) are recorded as failed, not resubmitted", part[i..].len().min(k)));
                        }
                        reasons.insert(key(t), format!("array job {id} task {task} was cancelled"));
                    } else {
                        if i % k == 0 {
                            log.events.push(why.clone());
                        }
                        reasons.insert(key(t), why);
                        next.push(t.clone());
                    }
                }
            }
            missing = next;
            attempt += 1;
        }
        let out: Vec<Option<String>> = thetas
            .iter()
            .map(|t| {
                if done(t) {
                    None
                } else {
                    Some(reasons.get(&key(t)).cloned().unwrap_or_else(|| "no result in the cache".into()))
                }
            })
            .collect();
        let mut log = self.log.lock().unwrap_or_else(|e| e.into_inner());
        let mut failed = std::collections::HashSet::new();
        for (t, r) in thetas.iter().zip(&out) {
            if r.is_some() {
                failed.insert(key(t));
            }
        }
        log.failed += failed.len() as u64;
        out
    }
}

/// A cached simulator whose batches run on Slurm: a batch's θ's without a cache entry are
/// evaluated by array tasks ([`Slurm::run`]); every result is then read from the cache; a θ that
/// no task delivered fails with the executor's reason.
pub struct Dispatched<'a, S: Simulator> {
    cached: &'a Cached<S>,
    slurm: &'a Slurm,
    progress: &'a (dyn Fn(&str) + Sync),
}

impl<'a, S: Simulator> Dispatched<'a, S> {
    /// `cached` evaluated through `slurm`, reporting its progress.
    pub fn new(cached: &'a Cached<S>, slurm: &'a Slurm, progress: &'a (dyn Fn(&str) + Sync)) -> Self {
        Dispatched { cached, slurm, progress }
    }
}

impl<S: Simulator> Simulator for Dispatched<'_, S> {
    fn space(&self) -> &ParamSpace {
        self.cached.space()
    }
    fn outputs(&self) -> &[OutputSpec] {
        self.cached.outputs()
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.simulate_batch(&[theta.to_vec()]).pop().unwrap_or_else(|| Err(Error::numerical("slurm executor", "no result")))
    }
    fn simulate_batch(&self, thetas: &[Vec<f64>]) -> Vec<Result<Vec<f64>>> {
        // A bad θ is refused here, as the model would, without a job.
        let checked: Vec<Result<()>> = thetas.iter().map(|t| self.space().check(t)).collect();
        let valid: Vec<Vec<f64>> = thetas.iter().zip(&checked).filter(|(_, c)| c.is_ok()).map(|(t, _)| t.clone()).collect();
        let done = |t: &[f64]| self.cached.lookup(t).is_some();
        let reasons = self.slurm.run(&valid, &done, self.progress);
        let mut reason = valid.iter().zip(reasons);
        thetas
            .iter()
            .zip(checked)
            .map(|(t, c)| {
                c?;
                match reason.next() {
                    Some((_, Some(why))) => Err(Error::numerical("slurm executor", why)),
                    _ => self.cached.lookup(t).unwrap_or_else(|| Err(Error::numerical("slurm executor", "the cache entry vanished after the job"))),
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_task_ids_and_batch_slices() {
        assert_eq!(task_ids("3"), vec![3]);
        assert_eq!(task_ids("0-3"), vec![0, 1, 2, 3]);
        assert_eq!(task_ids("1,4-5%2"), vec![1, 4, 5]);
        let b = Batch { study: "s".into(), cache_dir: "c".into(), config_sha256: String::new(), evaluations_per_task: 3, thetas: vec![vec![0.0]; 7] };
        assert_eq!(b.tasks(), 3);
        assert_eq!((b.slice(0), b.slice(2)), (0..3, 6..7));
        assert_eq!(shell_quote("a b'c"), "'a b'\\''c'");
    }

    #[test]
    fn options_are_checked() {
        let mut o = ExecutorOptions::default();
        o.validate("s.toml").unwrap();
        o.time_limit = "1 hour".into();
        assert!(o.validate("s.toml").unwrap_err().to_string().contains("executor.time_limit"));
        let o = ExecutorOptions { evaluations_per_task: 0, ..ExecutorOptions::default() };
        assert!(o.validate("s.toml").unwrap_err().to_string().contains("executor.evaluations_per_task"));
    }
}

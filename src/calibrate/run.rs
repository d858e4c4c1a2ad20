//! The `kind = "calibrate"` study: fit a simulator's parameters to measured data with the
//! loop of [`super::pipeline`] (design, emulator, least squares, MCMC, refinement, check).
//!
//! ```toml
//! kind = "calibrate"
//! seed = 5
//! label = "Gen 3, RT"
//! [data]            # kind = "crush_curves": file, temperature_c (unless a column gives it),
//!                   # reference_diameter?, points, fraction, sigma_floor
//!                   # kind = "observations": file (output, unit, value, sd)
//! [model]           # kind = "crush": [model.crush] = a CrushSetup (the calibration mesh)
//!                   # kind = "dem": study = "<dem study file>", duration, heights, window
//! [[param]]         # name, lower, upper, prior = { kind = "uniform" | "normal" | "log_normal", … }
//! [calibration]     # PipelineOptions: design, rounds, points, tolerance, sampler, walkers, steps, …
//! [compare]         # optional: study = "<another calibration study>" (its report's parameters.csv; run first
//!                   # when missing or stale) or reference = "<a parameters.csv>", label
//! [figures]         # width_cm
//! [executor]        # optional: kind = "local" | "slurm", partition, time_limit, … (super::executor)
//! ```
//!
//! Everything is checked at load: the data file is read and reduced, the model built, the
//! parameter names resolved (unknown → error), priors checked (lower ≥ upper, zero variance),
//! and every observation matched to a model output of the same unit.
//!
//! Simulator runs are cached in `<reports root>/.cache/<study>/` (keyed by the model's
//! configuration and θ) together with the MCMC checkpoints, so a killed or repeated study
//! reuses its finished runs. With `[executor] kind = "slurm"` (or `partlife run --executor
//! slurm`) the runs not in the cache are made by Slurm array tasks writing that cache
//! ([`super::executor`]); the report then also has `executor.csv` (one row per array job).
//!
//! Report files (`reports/<study>/`): `parameters.csv`, `correlation.csv`, `chains.csv`,
//! `observations.csv`, `runs.csv`, `rounds.csv`, `failures.csv`, (crush) `curves.csv` and
//! `grid.csv` (the grid displacements, the reference diameter and the curves' test temperature),
//! (with `[compare]`) `comparison.csv`, `summary.md`, figures (see
//! [`crate::report::calibrate`]), `manifest.json`.

use std::collections::{BTreeMap, HashMap};
use std::sync::Mutex;
use std::path::PathBuf;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

use super::cache::Cached;
use super::executor::{Dispatched, Slurm, SlurmLog};
use super::pipeline::{Calibration, calibrate, thinned};
use crate::error::{Error, Result};
use crate::fem::model::CrushModel;
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
use crate::model::Simulator;
use crate::params::{Param, Prior};
use crate::stats::interpolated_quantiles;
use crate::runkit::{ExecutorKind, RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, record_figures};
use crate::schema::StudyFile;
pub use super::study::*;

/// Runs a calibration study.
pub fn run_calibrate(loaded: &StudyFile, s: &CalibrateStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let resolve = |p: &str| loaded.resolve(std::path::Path::new(p));
    let prep = s.prepare(&loaded.path, &resolve)?;
    let mut inputs = vec![InputFile::hash(&loaded.path)?];
    for (k, p) in prep.inputs.iter().enumerate() {
        // The curve file (the first input) with the record of how it was read.
        match (&prep.read, k) {
            (Some(read), 0) => inputs.extend(InputFile::read(p, read)?),
            _ => inputs.push(InputFile::hash(p)?),
        }
    }
    // The calibration compared with: its parameters.csv, hashed when it is there.
    let compare_file = match &s.compare {
        Some(c) => Some(c.parameters_file(&loaded.path.display().to_string(), &resolve, &opts.reports_root)?),
        None => None,
    };
    if let Some(p) = compare_file.as_ref().filter(|p| p.is_file()) {
        inputs.push(InputFile::hash(p)?);
    }
    let cache_dir = opts.reports_root.join(".cache").join(&loaded.name);
    let pb = crate::runkit::progress_bar(1, opts.progress, "{spinner} [{elapsed_precise}] {msg}");
    pb.enable_steady_tick(std::time::Duration::from_millis(200));
    let progress = |m: &str| pb.set_message(m.to_string());
    let obs = &prep.observations;
    // Slurm (`--executor slurm` or `[executor] kind = "slurm"`): batches of uncached θ's become
    // array jobs whose tasks fill the same cache.
    let slurm = match opts.executor.unwrap_or(s.executor.kind) {
        ExecutorKind::Local => None,
        ExecutorKind::Slurm => Some(Slurm::new(&s.executor, &loaded.path, &cache_dir, &prep.config)?),
    };
    let (cal, counts, curves) = match &prep.built {
        Built::Crush(model, _) => {
            let recording = Recording { model, curves: Mutex::new(HashMap::new()) };
            let cached = Cached::new(&recording, &cache_dir, prep.config.clone())?;
            let cal = calibrate_on(&cached, slurm.as_ref(), s, obs, &cache_dir, &progress)?;
            progress("curves at posterior draws");
            let curves = recording.curves_at(&cal);
            (cal, cached.counts(), Some(curves))
        }
        Built::Dem(model) => {
            let cached = Cached::new(model.as_ref(), &cache_dir, prep.config.clone())?;
            let cal = calibrate_on(&cached, slurm.as_ref(), s, obs, &cache_dir, &progress)?;
            (cal, cached.counts(), None)
        }
    };
    progress("tables");
    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;
    let space = cal.emulator.space().clone();
    let headlines = write_tables(&mut dir, s, &prep, &cal, curves, compare_file.as_deref())?;
    progress("figures");
    let mut failures: Vec<String> = cal.warnings.clone();
    failures.extend(cal.failures.iter().map(|(t, e)| format!("simulator failed at θ = {t:?}: {e}")));
    let slurm_log = slurm.as_ref().map(Slurm::log);
    if let Some(log) = &slurm_log {
        failures.extend(log.events.iter().map(|e| format!("slurm: {e}")));
        write_executor(&mut dir, log)?;
    }
    let rendered = crate::report::calibrate::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    let mut evaluations = BTreeMap::new();
    evaluations.insert("simulator_requested".to_string(), cal.evaluations);
    evaluations.insert("simulator_cache_hits".to_string(), counts.0);
    evaluations.insert("simulator_runs".to_string(), counts.1);
    evaluations.insert("simulator_failures".to_string(), cal.failures.len() as u64);
    evaluations.insert("emulator_posterior_evaluations".to_string(), cal.emulator_evaluations);
    evaluations.insert("least_squares_emulator_evaluations".to_string(), cal.lsq.evaluations);
    evaluations.insert("emulator_training_runs".to_string(), cal.emulator.len() as u64);
    evaluations.insert("parameters".to_string(), space.len() as u64);
    if let Some(log) = &slurm_log {
        evaluations.insert("slurm_array_jobs".to_string(), log.arrays.len() as u64);
        evaluations.insert("slurm_tasks".to_string(), log.arrays.iter().map(|a| a.tasks as u64).sum());
        evaluations.insert("slurm_evaluations_submitted".to_string(), log.submitted);
        evaluations.insert("slurm_evaluations_failed".to_string(), log.failed);
    }
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let run = RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings: Vec::new() };
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, run)?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines })
}

/// The calibration loop on the cached simulator, its batches run here or by `slurm`.
fn calibrate_on<S: Simulator>(cached: &Cached<S>, slurm: Option<&Slurm>, s: &CalibrateStudy, obs: &super::data::Observations, cache_dir: &PathBuf, progress: &(dyn Fn(&str) + Sync)) -> Result<Calibration> {
    match slurm {
        None => calibrate(cached, obs, &s.calibration, s.seed, Some(cache_dir), progress),
        Some(sl) => calibrate(&Dispatched::new(cached, sl, progress), obs, &s.calibration, s.seed, Some(cache_dir), progress),
    }
}

/// `executor.csv`: every array job of a Slurm run — tasks, evaluations, final task states and
/// the time spent submitting, queueing, setting up, computing, writing and collecting.
fn write_executor(dir: &mut ReportDir, log: &SlurmLog) -> Result<()> {
    let a = &log.arrays;
    let mut t = table(vec![
        scol("job_id", a.iter().map(|r| r.job_id.clone()).collect()),
        ucol("attempt", a.iter().map(|r| r.attempt as u64).collect()),
        ucol("tasks", a.iter().map(|r| r.tasks as u64).collect()),
        ucol("evaluations", a.iter().map(|r| r.evaluations as u64).collect()),
        scol("task_states", a.iter().map(|r| r.states.clone()).collect()),
        fcol("submit_s", a.iter().map(|r| r.submit_s).collect()),
        fcol("queue_s", a.iter().map(|r| r.queue_s).collect()),
        fcol("wall_s", a.iter().map(|r| r.wall_s).collect()),
        fcol("task_setup_mean_s", a.iter().map(|r| r.setup_s).collect()),
        fcol("task_compute_sum_s", a.iter().map(|r| r.compute_s).collect()),
        fcol("task_write_mean_s", a.iter().map(|r| r.write_s).collect()),
        fcol("collect_s", a.iter().map(|r| r.collect_s).collect()),
    ])?;
    dir.write_table("executor", &mut t)
}

/// Full FE curves (normalised to D₀), by label.
type CurveSet = Vec<(String, Vec<(f64, f64)>)>;

/// The crush model keeping the curve of every run it makes, so the figure's curves at the
/// check draws and the estimate need no second FE run (runs served by the cache are redone).
struct Recording<'a> {
    model: &'a CrushModel,
    curves: Mutex<HashMap<Vec<u64>, Vec<(f64, f64)>>>,
}

fn bits(theta: &[f64]) -> Vec<u64> {
    theta.iter().map(|v| v.to_bits()).collect()
}

impl Recording<'_> {
    fn run(&self, theta: &[f64]) -> Result<Vec<f64>> {
        let (y, r) = self.model.evaluate(theta)?;
        let curve = r.curve.iter().map(|s| (s.displacement, s.force)).collect();
        self.curves.lock().unwrap_or_else(|e| e.into_inner()).insert(bits(theta), curve);
        Ok(y)
    }

    /// Curves at the check draws (`posterior_<i>`) and at the least-squares estimate; a θ the
    /// FE fails at is left out.
    fn curves_at(&self, cal: &Calibration) -> CurveSet {
        let mut thetas: Vec<(String, &Vec<f64>)> = cal.check.thetas.iter().enumerate().map(|(i, t)| (format!("posterior_{i}"), t)).collect();
        thetas.push(("estimate".into(), &cal.lsq.theta));
        let missing: Vec<&Vec<f64>> = {
            let have = self.curves.lock().unwrap_or_else(|e| e.into_inner());
            thetas.iter().map(|t| t.1).filter(|t| !have.contains_key(&bits(t))).collect()
        };
        crate::model::par_runs(&missing, |t| {
            let _ = self.run(t);
        });
        let have = self.curves.lock().unwrap_or_else(|e| e.into_inner());
        thetas.into_iter().filter_map(|(k, t)| have.get(&bits(t)).map(|c| (k, c.clone()))).collect()
    }
}

impl Simulator for Recording<'_> {
    fn space(&self) -> &crate::params::ParamSpace {
        self.model.space()
    }
    fn outputs(&self) -> &[crate::model::OutputSpec] {
        self.model.outputs()
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.run(theta)
    }
}

fn pr_mean(preds: &[Vec<(f64, f64)>], o: usize) -> f64 {
    preds.iter().map(|p| p[o].0).sum::<f64>() / preds.len().max(1) as f64
}


#[allow(clippy::too_many_lines)]
fn write_tables(dir: &mut ReportDir, s: &CalibrateStudy, prep: &Prepared, cal: &Calibration, curves: Option<CurveSet>, compare_file: Option<&std::path::Path>) -> Result<Vec<String>> {
    let space = cal.emulator.space();
    let params = space.params();
    let p = params.len();
    let names: Vec<String> = params.iter().map(|q| q.name.clone()).collect();
    let obs = &prep.observations;
    let outputs = cal.emulator.outputs();

    // Parameters.
    let flats: Vec<Vec<f64>> = (0..p).map(|k| cal.chains.flat(k)).collect();
    let mut stats = Vec::new();
    for k in 0..p {
        let v = &flats[k];
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let q = interpolated_quantiles(v.clone(), &[0.05, 0.5, 0.95]);
        stats.push((mean, sd, q));
    }
    let prior_sd: Vec<f64> = params.iter().map(|q| q.prior_sd()).collect();
    // Posterior correlation.
    let mut corr = vec![vec![0.0; p]; p];
    for a in 0..p {
        for b in 0..p {
            let (xa, xb) = (&flats[a], &flats[b]);
            let c: f64 = xa.iter().zip(xb).map(|(x, y)| (x - stats[a].0) * (y - stats[b].0)).sum::<f64>() / (xa.len() as f64 - 1.0);
            corr[a][b] = c / (stats[a].1 * stats[b].1);
        }
    }
    let mut ident = Vec::new();
    let mut notes = vec![String::new(); p];
    for k in 0..p {
        let ratio = stats[k].1 / prior_sd[k];
        if ratio > 0.9 {
            notes[k] = format!("not identified: posterior sd is {:.0} % of the prior's", 100.0 * ratio);
            ident.push(format!("{}: posterior sd {:.0} % of the prior's — the data do not determine it", names[k], 100.0 * ratio));
        } else if ratio > 0.5 {
            notes[k] = format!("weakly identified: posterior sd is {:.0} % of the prior's", 100.0 * ratio);
            ident.push(format!("{}: posterior sd {:.0} % of the prior's — the data narrow it only weakly", names[k], 100.0 * ratio));
        }
        for m in k + 1..p {
            if corr[k][m].abs() > 0.95 {
                ident.push(format!("{} and {}: posterior correlation {:+.3} — only a combination is determined", names[k], names[m], corr[k][m]));
                for j in [k, m] {
                    if notes[j].is_empty() {
                        notes[j] = "strongly correlated (see summary)".into();
                    }
                }
            }
        }
    }
    let col = |f: &dyn Fn(usize) -> f64| (0..p).map(f).collect::<Vec<f64>>();
    let prior_text = |q: &Param| match &q.prior {
        Prior::Uniform => "uniform".to_string(),
        Prior::Normal { mean, sd } => format!("normal({mean:e}, {sd:e})"),
        Prior::LogNormal { mu, sigma } => format!("log_normal({mu}, {sigma})"),
    };
    let mut df = table(vec![
        scol("name", names.clone()),
        scol("unit", params.iter().map(|q| q.unit.clone()).collect()),
        scol("prior", params.iter().map(prior_text).collect()),
        fcol("lower", col(&|k| params[k].lower)),
        fcol("upper", col(&|k| params[k].upper)),
        fcol("lsq_estimate", cal.lsq.theta.clone()),
        fcol("lsq_std_error", cal.lsq.std_error.clone()),
        fcol("posterior_mean", col(&|k| stats[k].0)),
        fcol("posterior_sd", col(&|k| stats[k].1)),
        fcol("q05", col(&|k| stats[k].2[0])),
        fcol("q50", col(&|k| stats[k].2[1])),
        fcol("q95", col(&|k| stats[k].2[2])),
        fcol("width_ratio", col(&|k| stats[k].1 / prior_sd[k])),
        fcol("r_hat", col(&|k| cal.diagnostics[k].r_hat)),
        fcol("ess_bulk", col(&|k| cal.diagnostics[k].ess_bulk)),
        fcol("ess_tail", col(&|k| cal.diagnostics[k].ess_tail)),
        fcol("tau_steps", col(&|k| cal.diagnostics[k].tau)),
        fcol("acceptance", vec![cal.chains.acceptance.iter().sum::<f64>() / cal.chains.acceptance.len() as f64; p]),
        scol("identifiability", notes.clone()),
    ])?;
    dir.write_table("parameters", &mut df)?;
    let mut cc = vec![scol("name", names.clone())];
    for (k, n) in names.iter().enumerate() {
        cc.push(fcol(n, (0..p).map(|a| corr[a][k]).collect()));
    }
    dir.write_table("correlation", &mut table(cc)?)?;

    // Chains, thinned to at most 2000 steps per walker.
    let thin = cal.chains.draws.len().div_ceil(2000).max(1);
    let (mut st, mut wk, mut lp) = (Vec::new(), Vec::new(), Vec::new());
    let mut vals: Vec<Vec<f64>> = vec![Vec::new(); p];
    for (i, step) in cal.chains.draws.iter().enumerate().step_by(thin) {
        for (w, x) in step.iter().enumerate() {
            st.push(i as u64);
            wk.push(w as u64);
            lp.push(cal.chains.log_prob[i][w]);
            for k in 0..p {
                vals[k].push(x[k]);
            }
        }
    }
    let mut cols = vec![ucol("step", st), ucol("walker", wk)];
    cols.extend(names.iter().zip(vals).map(|(n, v)| fcol(n, v)));
    cols.push(fcol("log_posterior", lp));
    dir.write_table("chains", &mut table(cols)?)?;

    // Posterior predictive of every observation: emulator mean at a posterior draw plus noise
    // N(0, σ² + v).
    let draws = thinned(&cal.chains, 400);
    let preds: Vec<Vec<(f64, f64)>> = draws.par_iter().map(|t| cal.emulator.predict(t)).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(s.seed ^ 0xB0B);
    let n01 = Normal::new(0.0, 1.0).map_err(|e| Error::numerical("predictive", e.to_string()))?;
    let est = cal.emulator.predict(&cal.lsq.theta);
    let (mut q05, mut q50, mut q95, mut mean_fit) = (vec![], vec![], vec![], vec![]);
    for i in 0..obs.len() {
        let o = obs.output[i];
        let me2 = (s.calibration.model_error * pr_mean(&preds, o)).powi(2);
        let v: Vec<f64> = preds.iter().map(|pr| pr[o].0 + (obs.sigma[i].powi(2) + pr[o].1 + me2).sqrt() * n01.sample(&mut rng)).collect();
        let q = interpolated_quantiles(v, &[0.05, 0.5, 0.95]);
        q05.push(q[0]);
        q50.push(q[1]);
        q95.push(q[2]);
        mean_fit.push(est[o].0);
    }
    let inside = (0..obs.len()).filter(|&i| obs.values[i] >= q05[i] && obs.values[i] <= q95[i]).count();
    let mut df = table(vec![
        scol("output", obs.output.iter().map(|&o| outputs[o].name.clone()).collect()),
        scol("unit", obs.output.iter().map(|&o| outputs[o].unit.clone()).collect()),
        ucol("output_index", obs.output.iter().map(|&o| o as u64).collect()),
        ucol("group", obs.group.iter().map(|&g| g as u64).collect()),
        fcol("value", obs.values.clone()),
        fcol("sigma", obs.sigma.clone()),
        fcol("lsq_fit", mean_fit),
        fcol("predictive_q05", q05),
        fcol("predictive_q50", q50),
        fcol("predictive_q95", q95),
    ])?;
    dir.write_table("observations", &mut df)?;

    // Simulator runs: design and refinement (emulator training), check draws, estimate.
    let m = outputs.len();
    let mut src = Vec::new();
    let mut th: Vec<Vec<f64>> = vec![Vec::new(); p];
    let mut ys: Vec<Vec<f64>> = vec![Vec::new(); m];
    let mut push = |label: String, t: &[f64], y: Option<&Vec<f64>>| {
        src.push(label);
        for k in 0..p {
            th[k].push(t[k]);
        }
        for o in 0..m {
            ys[o].push(y.map(|y| y[o]).unwrap_or(f64::NAN));
        }
    };
    for (t, y) in cal.emulator.thetas.iter().zip(&cal.emulator.runs) {
        push("training".into(), t, Some(y));
    }
    for (t, y) in cal.check.thetas.iter().zip(&cal.check.runs) {
        push("check".into(), t, y.as_ref());
    }
    push("estimate".into(), &cal.lsq.theta, cal.lsq_run.as_ref());
    let mut cols = vec![scol("source", src)];
    cols.extend(names.iter().zip(th).map(|(n, v)| fcol(n, v)));
    cols.extend(outputs.iter().zip(ys).map(|(o, v)| fcol(&o.name, v)));
    dir.write_table("runs", &mut table(cols)?)?;

    // Rounds.
    let mut cols = vec![
        ucol("round", (0..cal.rounds.len() as u64).collect()),
        ucol("runs", cal.rounds.iter().map(|r| r.runs as u64).collect()),
        fcol("epsilon_q50", cal.rounds.iter().map(|r| r.epsilon.0).collect()),
        fcol("epsilon_q90", cal.rounds.iter().map(|r| r.epsilon.1).collect()),
    ];
    for (o, spec) in outputs.iter().enumerate() {
        cols.push(fcol(&format!("loo_rmse_{}", spec.name), cal.rounds.iter().map(|r| r.loo[o].rmse).collect()));
        cols.push(fcol(&format!("loo_z2_{}", spec.name), cal.rounds.iter().map(|r| r.loo[o].mean_z2).collect()));
    }
    dir.write_table("rounds", &mut table(cols)?)?;
    let mut df = table(vec![
        scol("theta", cal.failures.iter().map(|f| format!("{:?}", f.0)).collect()),
        scol("error", cal.failures.iter().map(|f| f.1.clone()).collect()),
    ])?;
    dir.write_table("failures", &mut df)?;

    // Crush: data curves (normalised), FE curves at posterior draws and the estimate.
    if let (Built::Crush(_, red), Some(curves)) = (&prep.built, curves) {
        let (mut kind, mut id, mut x, mut f) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for c in &red.curves {
            for (d, v) in c.displacement.iter().zip(&c.force) {
                kind.push("data".to_string());
                id.push(c.particle.clone());
                x.push(*d);
                f.push(*v);
            }
        }
        for (k, pts) in curves {
            for (d, v) in pts {
                kind.push(if k == "estimate" { "estimate".into() } else { "posterior_draw".into() });
                id.push(k.clone());
                x.push(d);
                f.push(v);
            }
        }
        let mut df = table(vec![scol("kind", kind), scol("id", id), fcol("displacement_m", x), fcol("force_n", f)])?;
        dir.write_table("curves", &mut df)?;
        let mut df = table(vec![fcol("grid_displacement_m", red.grid.clone()), fcol("reference_diameter_m", vec![red.reference_diameter; red.grid.len()]), fcol("test_temperature_c", vec![red.temperature_c; red.grid.len()])])?;
        dir.write_table("grid", &mut df)?;
    }

    // Comparison with a reference calibration.
    let mut compare_line = None;
    if let (Some(c), Some(path)) = (&s.compare, compare_file) {
        match crate::report::Table::load_file(path) {
            Ok(t) => {
                let (rn, rm, r5, r95) = (t.s("name")?, t.f("posterior_mean")?, t.f("q05")?, t.f("q95")?);
                let (mut nn, mut a, mut a5, mut a95, mut b, mut b5, mut b95, mut ch) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
                for (k, n) in names.iter().enumerate() {
                    if let Some(j) = rn.iter().position(|x| x == n) {
                        nn.push(n.clone());
                        a.push(rm[j]);
                        a5.push(r5[j]);
                        a95.push(r95[j]);
                        b.push(stats[k].0);
                        b5.push(stats[k].2[0]);
                        b95.push(stats[k].2[2]);
                        ch.push(100.0 * (stats[k].0 - rm[j]) / rm[j]);
                    }
                }
                let mut df = table(vec![
                    scol("name", nn),
                    scol("reference_label", vec![c.label.clone(); a.len()]),
                    fcol("reference_mean", a),
                    fcol("reference_q05", a5),
                    fcol("reference_q95", a95),
                    scol("this_label", vec![s.label.clone(); b.len()]),
                    fcol("this_mean", b),
                    fcol("this_q05", b5),
                    fcol("this_q95", b95),
                    fcol("change_percent", ch),
                ])?;
                dir.write_table("comparison", &mut df)?;
            }
            Err(e) => compare_line = Some(format!("comparison with {} skipped: {e} (run that calibration first)", c.label)),
        }
    }

    // Summary.
    let mut md = format!("# Calibration: {}\n\n", s.label);
    if let (Built::Crush(_, red), Some(read)) = (&prep.built, &prep.read) {
        let file = std::path::Path::new(&read.file).file_name().map_or(read.file.clone(), |f| f.to_string_lossy().into_owned());
        md.push_str(&format!("Data: {} force–displacement curves (`{file}`) measured at {} °C (`grid.csv`). Read as: {}.\n\n", red.curves.len(), crate::intake::columns::shown((10.0 * red.temperature_c).round() / 10.0), read.describe()));
    }
    md.push_str(&format!(
        "Simulator runs: {} requested ({} in the emulator), {} failed; emulator posterior evaluations: {}.\n\n",
        cal.evaluations,
        cal.emulator.len(),
        cal.failures.len(),
        cal.emulator_evaluations
    ));
    md.push_str(&answer(&names, &params.iter().map(|q| q.unit.as_str()).collect::<Vec<_>>(), &stats.iter().map(|s| (s.0, s.2[0], s.2[2])).collect::<Vec<_>>(), &notes, inside, obs.len()));
    md.push_str("| parameter | unit | least squares ± se | posterior mean | 90 % interval | R̂ | ESS bulk | identifiability |\n|---|---|---|---|---|---|---|---|\n");
    for k in 0..p {
        md.push_str(&format!(
            "| {} | {} | {:.4e} ± {:.2e} | {:.4e} | [{:.4e}, {:.4e}] | {:.3} | {:.0} | {} |\n",
            names[k], params[k].unit, cal.lsq.theta[k], cal.lsq.std_error[k], stats[k].0, stats[k].2[0], stats[k].2[2], cal.diagnostics[k].r_hat, cal.diagnostics[k].ess_bulk, if notes[k].is_empty() { "identified" } else { &notes[k] }
        ));
    }
    md.push_str("\n## Identifiability\n\n");
    if ident.is_empty() && cal.lsq.unidentified.is_empty() {
        md.push_str("Every parameter is determined by the data (posterior sd < 90 % of the prior's, no correlation above 0.95).\n");
    }
    for l in &ident {
        md.push_str(&format!("* posterior: {l}\n"));
    }
    for l in &cal.lsq.unidentified {
        md.push_str(&format!("* least squares: {l}\n"));
    }
    md.push_str(&format!(
        "\n## Checks\n\n* {inside} of {} observations ({:.0} %) lie inside their 90 % posterior-predictive interval.\n* Check runs of the simulator at {} posterior draws: {:.0} % of the observations inside the 90 % interval of the runs plus noise; emulator error (RMS, in sd of each output's mean d̄) per output: {}.\n* The emulator's stated uncertainty at those runs (RMS of (run − emulator mean)/predictive sd, ≈ 1 when honest; limit {:.2}): {}.\n* The posterior under the simulator's own likelihood (the check draws reweighted from the emulator's likelihood to the simulator's, ESS {:.1} of {}; an honest emulator gives ESS above {:.1} and shifts below {:.2} in 99 % of replicates): mean shifts in posterior sd {}.\n* Emulator refinement (ε: the emulator's sd against what the likelihood resolves, √(sd of d̄² + τ²); tolerance {}): {}.\n{}",
        obs.len(),
        100.0 * inside as f64 / obs.len() as f64,
        cal.check.thetas.len(),
        100.0 * cal.check.coverage90,
        outputs.iter().zip(&cal.check.emulator_error).filter(|(_, e)| e.is_finite()).map(|(o, e)| format!("{} {e:.2}", o.name)).collect::<Vec<_>>().join(", "),
        cal.check.z_limit,
        outputs.iter().zip(&cal.check.z_rms).zip(&cal.check.emulator_error).filter(|(_, e)| e.is_finite()).map(|((o, z), _)| format!("{} {z:.2}", o.name)).collect::<Vec<_>>().join(", "),
        cal.check.shift_ess,
        cal.check.runs.iter().filter(|r| r.is_some()).count(),
        cal.check.null.0,
        cal.check.null.1,
        names.iter().zip(&cal.check.shift).map(|(n, s)| format!("{n} {s:+.2}")).collect::<Vec<_>>().join(", "),
        s.calibration.tolerance,
        cal.rounds.iter().map(|r| format!("{} runs → ε90 = {:.2}", r.runs, r.epsilon.1)).collect::<Vec<_>>().join("; "),
        {
            // Outputs on which the simulator itself scatters by more than the data resolve.
            let noisy: Vec<String> = outputs.iter().zip(&cal.check.scatter).filter(|(_, r)| r.is_finite() && **r > 1.0).map(|(o, r)| format!("{} (τ = {r:.1} × the sd of d̄)", o.name)).collect();
            let mut lines = if noisy.is_empty() {
                String::new()
            } else {
                format!("* The simulator's own run-to-run scatter τ (the emulator's nugget) exceeds what the data resolve on {}: nearby parameters give outputs that differ by about τ (the crush FE's fracture starts in whichever element fails first), so the likelihood counts τ as noise and these outputs constrain the parameters only to within it.\n", noisy.join(", "))
            };
            // Understated emulator uncertainty where the error is too small to matter: a note.
            let slight: Vec<String> = cal.check.understated().into_iter().filter(|(_, material)| !material).map(|(o, _)| format!("{} (z {:.2}; error {:.2})", outputs[o].name, cal.check.z_rms[o], cal.check.resolved_error[o])).collect();
            if !slight.is_empty() {
                lines.push_str(&format!(
                    "* The emulator states less uncertainty than the check runs show on {} — above the limit {:.2}, but its error there is below {} of what the likelihood resolves (√(sd of d̄² + τ²)), so it moves no posterior mean by more than about that many posterior sd: a note, not a warning.\n",
                    slight.join(", "),
                    cal.check.z_limit,
                    crate::calibrate::check::MATERIAL_ERROR
                ));
            }
            lines
        }
    ));
    if !cal.warnings.is_empty() {
        md.push_str("\n## Warnings\n\n");
        for w in &cal.warnings {
            md.push_str(&format!("* {w}\n"));
        }
    }
    if let Some(l) = &compare_line {
        md.push_str(&format!("\n{l}\n"));
    }
    dir.write_bytes("summary.md", md.as_bytes())?;

    let mut headlines: Vec<String> = (0..p)
        .map(|k| format!("{} = {:.4e} {} (90 % [{:.4e}, {:.4e}]){}", names[k], stats[k].0, params[k].unit, stats[k].2[0], stats[k].2[2], if notes[k].is_empty() { String::new() } else { format!(" — {}", notes[k]) }))
        .collect();
    headlines.push(format!("{inside}/{} observations inside the 90 % predictive interval; {} simulator runs", obs.len(), cal.evaluations));
    headlines.extend(cal.warnings.iter().map(|w| format!("warning: {w}")));
    if let Some(l) = compare_line {
        headlines.push(l);
    }
    Ok(headlines)
}

/// The `## Answer` section: how many parameters the data identify, each identified one's
/// posterior mean and 90 % interval, why the others are not (their identifiability notes), and
/// how many observations lie inside their 90 % posterior-predictive interval — one sentence
/// from the posterior table's numbers (`post`: mean, 5 % and 95 % quantiles).
fn answer(names: &[String], units: &[&str], post: &[(f64, f64, f64)], notes: &[String], inside: usize, observations: usize) -> String {
    let unit = |k: usize| if units[k].is_empty() || units[k] == "-" { String::new() } else { format!(" {}", units[k]) };
    let identified: Vec<String> = (0..names.len()).filter(|&k| notes[k].is_empty()).map(|k| format!("`{}` = {:.3e}{} [{:.3e}, {:.3e}]", names[k], post[k].0, unit(k), post[k].1, post[k].2)).collect();
    let others: Vec<String> = (0..names.len()).filter(|&k| !notes[k].is_empty()).map(|k| format!("`{}` is {}", names[k], notes[k])).collect();
    let head = match (identified.len(), names.len()) {
        (i, n) if i == n => format!("**Every one of the {n} parameters is identified by these data**"),
        (0, n) => format!("**None of the {n} parameters is identified by these data**"),
        (i, n) => format!("**{i} of the {n} parameters {} identified by these data**", if i == 1 { "is" } else { "are" }),
    };
    let listed = if identified.is_empty() { String::new() } else { format!(" (posterior mean and 90 % interval: {})", identified.join(", ")) };
    let rest = if others.is_empty() { String::new() } else { format!("; {}", others.join("; ")) };
    format!("## Answer\n\n{head}{listed}{rest}. {inside} of {observations} observations lie inside their 90 % posterior-predictive interval.\n\n")
}

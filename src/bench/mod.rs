//! Speed figures (`partlife bench`), measured in a benchmark rather than a timed test:
//!
//! * σ̄(V) + P_N evaluations per second on one core (goal ≥ 2·10⁷/s);
//! * Weibull MLE + 10⁴-sample pivotal bounds for N = 50 (goal < 50 ms), on all threads and on one;
//! * the lifetime study end to end (goal < 5 s), when a study file is given;
//! * the scaling table ([`dem_scaling`], [`fem_scaling`], [`main_study_scaling`] over
//!   [`thread_counts`]): the DEM bank, the crush FE and the main study on 1, 2, 4, … threads.
//!
//! Benchmarks find the repository's studies and datasets from the repository ([`repo_path`]),
//! whatever the working directory, and write only into scratch directories ([`TempDir`]): a
//! benchmark never touches `reports/`.

use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::contact::{AveragingDomain, Elastic, Sphere};
use crate::error::{Error, Result};
use crate::io::TempDir;
use crate::model::Simulator;
use crate::strength::{LifetimeChain, LifetimeModel, Population, Sample, StrengthFit};
use crate::weibull::{Weibull, fit_mle, simulate_pivotal};

mod scaling;
pub use scaling::*;

/// A file of the repository this binary was built from (`studies/…`, `datasets/…`), or the path
/// as given relative to the working directory when that checkout is gone.
pub fn repo_path(rel: &str) -> std::path::PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    if p.exists() { p } else { Path::new(rel).to_path_buf() }
}

/// Copies a directory tree (a report) into `to`.
fn copy_tree(from: &Path, to: &Path) -> Result<()> {
    std::fs::create_dir_all(to).map_err(|e| Error::write(to, e))?;
    for entry in std::fs::read_dir(from).map_err(|e| Error::read(from, e))? {
        let entry = entry.map_err(|e| Error::read(from, e))?;
        let (src, dst) = (entry.path(), to.join(entry.file_name()));
        if src.is_dir() {
            copy_tree(&src, &dst)?;
        } else {
            std::fs::copy(&src, &dst).map_err(|e| Error::write(&dst, e))?;
        }
    }
    Ok(())
}

/// Times `studies/discrepancy_curves.toml` end to end: (study, headlines, wall seconds), or None
/// when the repository has no report of its calibration (`reports/calibrate_gen3_rt`). The
/// calibration report is copied into a scratch reports root, so the run writes nothing under
/// the repository's `reports/`.
pub fn curve_discrepancy_speed() -> Result<Option<(std::path::PathBuf, Vec<String>, f64)>> {
    let study = repo_path("studies/discrepancy_curves.toml");
    let calibration = repo_path("reports/calibrate_gen3_rt");
    if !calibration.join("runs.csv").is_file() {
        return Ok(None);
    }
    let root = TempDir::new("bench-curves")?;
    copy_tree(&calibration, &root.path().join("calibrate_gen3_rt"))?;
    let loaded = crate::study::load(&study)?;
    let summary = crate::runner::run(&loaded, &crate::runner::RunOptions::new(root.path().to_path_buf(), false))?;
    Ok(Some((study, summary.headlines, summary.wall_time_s)))
}

/// Speed of the shipped experiment-design study.
#[derive(Debug, Clone)]
pub struct ExperimentsSpeed {
    /// Its headline.
    pub headline: String,
    /// Wall time on every thread (s).
    pub seconds: f64,
    /// Wall time on one thread (s).
    pub seconds_one_thread: f64,
    /// Whether every table is byte-identical between the two runs.
    pub identical: bool,
}

/// Times `studies/experiments.toml` end to end on every thread and on one, each into its own
/// scratch reports root (nothing under the repository's `reports/`), and compares the tables.
pub fn experiments_speed() -> Result<ExperimentsSpeed> {
    let loaded = crate::study::load(&repo_path("studies/experiments.toml"))?;
    let run = |threads: Option<usize>| -> Result<(TempDir, crate::runner::RunSummary)> {
        let root = TempDir::new("bench-experiments")?;
        let opts = crate::runner::RunOptions::new(root.path().to_path_buf(), false);
        let s = match threads {
            None => crate::runner::run(&loaded, &opts)?,
            Some(n) => rayon::ThreadPoolBuilder::new().num_threads(n).build().map_err(|e| Error::numerical("thread pool", e.to_string()))?.install(|| crate::runner::run(&loaded, &opts))?,
        };
        Ok((root, s))
    };
    let (all, a) = run(None)?;
    let (one, b) = run(Some(1))?;
    let tables = ["plans.csv", "allocation.csv", "prior.csv", "summary.md"];
    let identical = tables.iter().all(|t| std::fs::read(all.path().join("experiments").join(t)).ok() == std::fs::read(one.path().join("experiments").join(t)).ok());
    Ok(ExperimentsSpeed { headline: a.headlines.join(" "), seconds: a.wall_time_s, seconds_one_thread: b.wall_time_s, identical })
}

/// One measured figure.
#[derive(Debug, Clone)]
pub struct Figure {
    /// What was measured.
    pub what: String,
    /// The value.
    pub value: f64,
    /// Its unit.
    pub unit: String,
    /// The goal, in words.
    pub goal: String,
}

/// The deliverable's lifetime chain of a 0.9 mm particle (50 synthetic σ̄ at break, m ≈ 7),
/// with P_N for N = 7300.
fn bench_chain() -> Result<LifetimeChain> {
    let e = Elastic::new(112e9, 0.25)?;
    let sphere = Sphere { diameter: 0.9e-3, density: 3600.0, elastic: e };
    let w = Weibull::new(7.0, 800e6)?;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let sample = Sample { source: "bench".into(), strength: crate::obs::Observations::exact((0..50).map(|_| w.sample(&mut rng)).collect()), particles: true, ..Sample::default() };
    let fit = StrengthFit::new(&sample, &[], 5.0, "bench")?;
    let population = Population { source: "declared".into(), particles: vec![crate::strength::Particle { diameter_m: 0.9e-3, roundness: None, sphericity: None, temperature_c: None }], sampled: false, ..Population::default() };
    let model = LifetimeModel::new("bench", "bench", sphere, Elastic::new(210e9, 0.3)?, AveragingDomain::default(), fit, population)?;
    let p = model.fit.estimate();
    LifetimeChain::new(model, &[7300.0], (p, 0.1, 5.0))
}

/// σ̄(V) + P_N evaluations per second on the calling thread, through the lifetime model's fast
/// methods (`fast = true`: impact stress and one precomputed damage law, as the Monte Carlo
/// uses them) or the Simulator (`simulate`, with its bounds checks and allocations).
pub fn lifetime_evaluations_per_second(min_time: Duration, fast: bool) -> Result<f64> {
    let chain = bench_chain()?;
    let model = chain.model();
    let p = model.fit.estimate();
    let law = [crate::strength::model::Horizon::independent(7300.0)];
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let velocities: Vec<f64> = (0..4096).map(|_| rng.random_range(0.5..20.0)).collect();
    let thetas: Vec<Vec<f64>> = velocities.iter().map(|&v| chain.theta(&p, 0.1, v)).collect();
    let mut evals = 0u64;
    let mut acc = 0.0;
    let start = Instant::now();
    while start.elapsed() < min_time {
        if fast {
            for &v in &velocities {
                let ln_sigma = model.ln_impact_stress(black_box(0.1), black_box(v))?;
                let mut out = [0.0];
                model.breakage_into(&p, None, ln_sigma, &law, &mut out);
                acc += ln_sigma + out[0];
            }
        } else {
            for t in &thetas {
                acc += chain.simulate(black_box(t))?[2];
            }
        }
        evals += velocities.len() as u64;
    }
    black_box(acc);
    Ok(evals as f64 / start.elapsed().as_secs_f64())
}

/// Median wall time (ms) of a Weibull fit + pivotal bounds for N = 50 with 10⁴ replicates.
pub fn weibull_fit_with_bounds_ms(repeats: usize) -> Result<f64> {
    let w = Weibull::new(9.0, 700e6)?;
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let data: Vec<f64> = (0..50).map(|_| w.sample(&mut rng)).collect();
    let mut times = Vec::with_capacity(repeats);
    for r in 0..repeats {
        let start = Instant::now();
        let fit = fit_mle(&data)?;
        let piv = simulate_pivotal(fit.n, 10_000, r as u64)?;
        black_box(piv.bounds(&fit, 0.9)?);
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok(crate::stats::median(&times))
}

/// Runs every benchmark and returns the figures.
pub fn run_all(study: Option<&Path>) -> Result<Vec<Figure>> {
    // Seven trials of 0.3 s: the best is the code's speed, the median shows the machine's noise.
    let trials = |fast: bool| -> Result<(f64, f64)> {
        let mut v = (0..7).map(|_| lifetime_evaluations_per_second(Duration::from_millis(300), fast)).collect::<Result<Vec<f64>>>()?;
        v.sort_by(f64::total_cmp);
        Ok((v[6], v[3]))
    };
    let (fast_best, fast_median) = trials(true)?;
    let (slow_best, slow_median) = trials(false)?;
    let mut out = vec![
        Figure {
            what: "σ̄(V) + P_N evaluations, one core, the lifetime model's fast methods, best of 7".into(),
            value: fast_best,
            unit: format!("evaluations/s (median {fast_median:.3e})"),
            goal: "≥ 2e7/s".into(),
        },
        Figure {
            what: "σ̄(V) + P_N evaluations, one core, through Simulator::simulate, best of 7".into(),
            value: slow_best,
            unit: format!("evaluations/s (median {slow_median:.3e})"),
            goal: "(reference)".into(),
        },
    ];
    out.push(Figure {
        what: format!("Weibull MLE + 10^4 pivotal bounds, N = 50, {} threads", rayon::current_num_threads()),
        value: weibull_fit_with_bounds_ms(11)?,
        unit: "ms (median of 11)".into(),
        goal: "< 50 ms".into(),
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| crate::Error::numerical("thread pool", e.to_string()))?;
    out.push(Figure {
        what: "Weibull MLE + 10^4 pivotal bounds, N = 50, 1 thread".into(),
        value: pool.install(|| weibull_fit_with_bounds_ms(11))?,
        unit: "ms (median of 11)".into(),
        goal: "< 50 ms".into(),
    });
    if let Some(path) = study {
        // A calibration study is timed from an empty cache (a fresh reports root): design,
        // emulator, least squares, MCMC and the check runs, all of it.
        let goal = match crate::study::load(path)?.study {
            crate::study::Study::Calibrate(_) => "< 600 s (complete Bayesian calibration, empty cache)",
            _ => "< 5 s",
        };
        let root = TempDir::new("bench")?;
        let start = Instant::now();
        crate::runner::run_file(path, &crate::runner::RunOptions::new(root.path().to_path_buf(), false))?;
        let secs = start.elapsed().as_secs_f64();
        out.push(Figure {
            what: format!("study {} end to end (in process)", path.display()),
            value: secs,
            unit: "s".into(),
            goal: goal.into(),
        });
    }
    Ok(out)
}

/// The Rosenbrock banana of the MCMC verification (docs/reference.md, verification §2):
/// `log p = −[100(x₂ − x₁²)² + (1 − x₁)²]/20`.
pub fn banana_log_prob(x: &[f64]) -> f64 {
    -(100.0 * (x[1] - x[0] * x[0]).powi(2) + (1.0 - x[0]).powi(2)) / 20.0
}

/// One sampler speed measurement on the banana.
#[derive(Debug, Clone)]
pub struct McmcSpeed {
    /// Wall time of the sampling (s).
    pub seconds: f64,
    /// Log-density evaluations per second.
    pub evaluations_per_second: f64,
    /// Smaller bulk ESS of x₁ and x₂.
    pub ess: f64,
    /// ESS per second.
    pub ess_per_second: f64,
}

/// The ensemble sampler on the banana (32 walkers, `steps` after 2000 burn-in, seed 5), timed.
pub fn mcmc_banana(steps: usize) -> Result<McmcSpeed> {
    use crate::calibrate::mcmc::{EnsembleOptions, ensemble};
    let opts = EnsembleOptions { walkers: 32, steps, burn_in: 2000, stretch: 2.0, seed: 5 };
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let init: Vec<Vec<f64>> = (0..32).map(|_| vec![1.0 + 0.1 * (rng.random::<f64>() - 0.5), 1.0 + 0.1 * (rng.random::<f64>() - 0.5)]).collect();
    let start = Instant::now();
    let c = ensemble(banana_log_prob, init, &opts)?;
    let seconds = start.elapsed().as_secs_f64();
    let ess = c.diagnostics(0).ess_bulk.min(c.diagnostics(1).ess_bulk);
    Ok(McmcSpeed { seconds, evaluations_per_second: c.evaluations as f64 / seconds, ess, ess_per_second: ess / seconds })
}

/// Bulk ESS (smaller over the columns) of a chain file written by another sampler: CSV with
/// columns `step, walker, x1, x2` (`tests/bench/emcee/banana.py`), the same estimator as ours.
pub fn external_chain_ess(path: &Path) -> Result<f64> {
    let df = crate::io::read_table(path)?;
    let w = crate::io::col_f64(&df, path, "walker")?;
    let walkers = w.iter().fold(0.0f64, |a, &b| a.max(b)) as usize + 1;
    let mut ess = f64::INFINITY;
    for col in ["x1", "x2"] {
        let x = crate::io::col_f64(&df, path, col)?;
        let mut chains = vec![Vec::new(); walkers];
        for (wi, xi) in w.iter().zip(&x) {
            chains[*wi as usize].push(*xi);
        }
        ess = ess.min(crate::calibrate::mcmc::diagnostics(&chains).ess_bulk);
    }
    Ok(ess)
}

/// UQ speed figures.
#[derive(Debug, Clone)]
pub struct UqSpeed {
    /// The primary strength model of the study and the particles each material's population
    /// averages over (1 without effects).
    pub strength_model: String,
    /// Population rows evaluated per sample, per material.
    pub particles: [usize; 2],
    /// Wall time of 2²⁰ Monte Carlo samples of the full chain, both materials, every horizon and
    /// damage model of the main study (s).
    pub propagation_s: f64,
    /// Samples propagated.
    pub samples: usize,
    /// Wall time of the Ishigami Sobol' indices at N = 2¹⁴ (81 920 runs) with 1000 bootstrap
    /// resamples (s), and the largest |Ŝ − S| over first and total indices.
    pub ishigami_s: f64,
    /// Largest absolute error of the Ishigami indices.
    pub ishigami_error: f64,
}

/// Times the propagation of the main study's primary strength model (`study`, normally
/// `studies/gen4_vs_bl.toml`) with 2²⁰ samples (the fitting and draws before it are not timed),
/// and the Ishigami indices at N = 2¹⁴.
pub fn uq_speed(study: &Path) -> Result<UqSpeed> {
    let loaded = crate::study::load(study)?;
    let crate::study::Study::Uq(s) = &loaded.study else {
        return Err(crate::Error::config(study.display().to_string(), "kind", "the UQ benchmark needs a kind = \"uq\" study"));
    };
    let shared = crate::uq::setup::Shared::new(s, &loaded.file.path, Path::new("reports"))?;
    let setup = crate::uq::setup::Setup::new(s, &loaded.file.path, &s.strength.effects, &s.contact.averaging, &shared)?;
    let samples = 1 << 20;
    let prop = crate::uq::study::Propagation { method: crate::uq::study::Method::Sobol, samples, replicates: 8 };
    let start = Instant::now();
    let out = crate::uq::propagate::propagate(&setup, &prop, s.seed, &|| {})?;
    let propagation_s = start.elapsed().as_secs_f64();
    std::hint::black_box(&out.blocks);
    let particles = [0, 1].map(|j| if setup.materials[j].model.uniform() { 1 } else { setup.materials[j].model.population.len() });
    let ishigami = crate::testfns::Ishigami::standard();
    let f = |u: &[f64]| -> Result<Vec<f64>> {
        let x: Vec<f64> = u.iter().map(|v| std::f64::consts::PI * (2.0 * v - 1.0)).collect();
        ishigami.simulate(&x)
    };
    let start = Instant::now();
    let ind = crate::uq::sobol::sobol_indices(f, 3, 1 << 14, 1, 1000, 0.95)?;
    let ishigami_s = start.elapsed().as_secs_f64();
    let (s1, st) = ([0.313905, 0.442411, 0.0], [0.557589, 0.442411, 0.243684]);
    let ishigami_error = (0..3).map(|i| (ind[0].first[i] - s1[i]).abs().max((ind[0].total[i] - st[i]).abs())).fold(0.0, f64::max);
    Ok(UqSpeed { strength_model: setup.spec.name(), particles, propagation_s, samples, ishigami_s, ishigami_error })
}

/// Times the naming loop on a strength file of `n` specimens with six recorded factors — a
/// size measure (effective volume, two values), two numeric (a loading rate, log-uniform over
/// two decades; an irrelevant number) and three categorical (batch of three with batch B 15 %
/// weaker, furnace of two, operator of four) — and the two flaw-population laws, at the
/// shipped settings (at most 499 bootstrap replicates per round, 999 permutations per residual
/// test, ten folds), with the sequential bootstrap and again drawing every replicate. With `censored` > 0 that share of the specimens, the strongest, did not
/// break by the rig's limit (right-censored there, type I).
pub fn strength_factors_speed(n: usize, censored: f64) -> Result<NamingSpeed> {
    use crate::strength::factors::{Factor, FactorType, Form, SizeMeasure, candidates_of};
    let mut rng = ChaCha8Rng::seed_from_u64(33);
    let mut s = Sample { source: "bench".into(), ..Sample::default() };
    let volume: Vec<f64> = (0..n).map(|i| [2.0, 8.0][i % 2]).collect();
    let rate: Vec<f64> = (0..n).map(|_| 10f64.powf(rng.random_range(-1.0..1.0))).collect();
    let other: Vec<f64> = (0..n).map(|_| rng.random_range(1.0..5.0)).collect();
    let batch: Vec<String> = (0..n).map(|i| ["A", "B", "C"][(i / 2) % 3].to_string()).collect();
    let furnace: Vec<String> = (0..n).map(|_| ["F1", "F2"][rng.random_range(0..2)].to_string()).collect();
    let operator: Vec<String> = (0..n).map(|_| format!("O{}", rng.random_range(0..4))).collect();
    s.strength = crate::obs::Observations::exact(
        (0..n)
            .map(|i| {
                let scale = 380e6 * (volume[i] / 4.0).powf(-0.1) * if batch[i] == "B" { 0.85 } else { 1.0 };
                Weibull::new(10.0, scale).map(|w| w.sample(&mut rng))
            })
            .collect::<Result<_>>()?,
    );
    for (name, v) in [("volume", volume), ("rate", rate), ("other", other)] {
        s.covariates.push((name.into(), v.into_iter().map(Some).collect()));
    }
    for (name, v) in [("batch", batch), ("furnace", furnace), ("operator", operator)] {
        s.levels.push((name.into(), v));
    }
    s.factors = vec![Factor { column: "volume".into(), form: Form::Size(SizeMeasure::EffectiveVolume) }];
    // The candidates a study declaring these columns gets: linear and power for the numeric
    // ones, a scale and a modulus per level for the categorical ones.
    for c in ["rate", "other"] {
        s.factors.extend(candidates_of(c, FactorType::Numeric, true));
    }
    for c in ["batch", "furnace", "operator"] {
        s.factors.extend(candidates_of(c, FactorType::Categorical, false));
    }
    // And the two flaw-population laws, on by default for strength files.
    s.populations = vec![crate::strength::flaws::Populations::Mixture, crate::strength::flaws::Populations::Competing];
    if censored > 0.0 {
        s.strength = censored_at_quantile(&s.strength.x, censored);
    }
    let time = |sequential: bool| -> Result<(f64, Vec<String>, Vec<usize>)> {
        let start = Instant::now();
        let outcome = crate::discrepancy::workflow::analyse(&s, &crate::strength::NamingSettings { sequential, ..Default::default() }, true)?;
        Ok((start.elapsed().as_secs_f64(), outcome.named.iter().map(|e| e.name()).collect(), outcome.stages.iter().map(|st| st.replicates).collect()))
    };
    let (seconds, named, replicates) = time(true)?;
    let (seconds_every, named_every, _) = time(false)?;
    Ok(NamingSpeed { seconds, same_names: named == named_every, named, replicates, seconds_every, candidates: s.factors.len() + s.populations.len() })
}

/// The naming loop's speed on one strength file, with the sequential bootstrap (the default)
/// and drawing every replicate.
#[derive(Debug, Clone)]
pub struct NamingSpeed {
    /// Wall time with the sequential bootstrap (s).
    pub seconds: f64,
    /// Effects named.
    pub named: Vec<String>,
    /// Replicates each round drew (sequential).
    pub replicates: Vec<usize>,
    /// Wall time drawing every replicate of every round (s).
    pub seconds_every: f64,
    /// Whether both named the same effects.
    pub same_names: bool,
    /// Candidates offered.
    pub candidates: usize,
}

/// `x` right-censored at its (1 − `share`) sample quantile, the rig's limit: the values above it
/// did not break by it.
fn censored_at_quantile(x: &[f64], share: f64) -> crate::obs::Observations {
    let mut sorted = x.to_vec();
    sorted.sort_by(f64::total_cmp);
    let limit = crate::stats::sorted_quantile(&sorted, 1.0 - share);
    let kind: Vec<crate::obs::Censor> = x.iter().map(|v| if *v > limit { crate::obs::Censor::Right } else { crate::obs::Censor::Exact }).collect();
    let values: Vec<f64> = x.iter().map(|v| v.min(limit)).collect();
    let censoring = crate::obs::Censoring::of_rows(kind, &values, vec![f64::NAN; x.len()]);
    crate::obs::Observations { x: values, censoring }
}

/// Seconds per two-parameter Weibull fit of 500 strengths (Newton on the regression without
/// effects), complete and with the strongest 20 % right-censored at the rig's limit: the cost of
/// censoring (goal: at most twice).
pub fn censored_fit_speed() -> Result<(f64, f64)> {
    let mut rng = ChaCha8Rng::seed_from_u64(52);
    let w = Weibull::new(11.5, 300e6)?;
    let x: Vec<f64> = (0..500).map(|_| w.sample(&mut rng)).collect();
    let c = censored_at_quantile(&x, 0.2);
    let time = |o: crate::obs::Obs| -> Result<f64> {
        let reps = 2000;
        let start = Instant::now();
        for _ in 0..reps {
            std::hint::black_box(crate::strength::regress::fit(std::hint::black_box(o), &Default::default())?);
        }
        Ok(start.elapsed().as_secs_f64() / reps as f64)
    };
    Ok((time(crate::obs::Obs::exact(&x))?, time(c.view())?))
}

/// Speed of the discrepancy workflow on 100 particles.
#[derive(Debug, Clone)]
pub struct DiscrepancySpeed {
    /// Particles.
    pub particles: usize,
    /// Effects the loop named.
    pub named: Vec<String>,
    /// Wall time of the naming loop alone: every candidate, at most 499 bootstrap replicates per round,
    /// 999 permutations per residual trend (s).
    pub loop_s: f64,
    /// Wall time of the whole `partlife discrepancy --data` run: loop, lifetime bands, the
    /// detection-power study (320 synthetic datasets), tables and figures (s).
    pub report_s: f64,
}

/// Times the discrepancy workflow on 100 synthetic BL 16/30 particles (the shipped generator
/// settings with `count = 100`: size effect and roundness hidden).
pub fn discrepancy_speed(settings: &Path) -> Result<DiscrepancySpeed> {
    let mut gen_settings = crate::synth::SynthSettings::load(settings)?;
    gen_settings.material.truncate(1);
    gen_settings.material[0].count = 100;
    gen_settings.material[0].file = "bench_crush_100.csv".into();
    let scratch = TempDir::new("bench-discrepancy")?;
    let dir = scratch.path();
    crate::synth::synthesize(&gen_settings, dir)?;
    let data = dir.join("bench_crush_100.csv");
    // The generator's elastic constants; the density of the lifetime study's particles.
    let (file, s) = crate::discrepancy::run::quick_study(&data, gen_settings.material[0].elastic, 3600.0, None, None, None)?;
    let crush = crate::data::read_crush(&data)?;
    let sample = crate::strength::sample_of(&crush, &s.material[0].elastic, &s.contact)?;
    let settings = crate::strength::NamingSettings { seed: s.seed, ..Default::default() };
    let start = Instant::now();
    let outcome = crate::discrepancy::workflow::analyse(&sample, &settings, true)?;
    let loop_s = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let opts = crate::runner::RunOptions::new(dir.join("reports"), false);
    crate::discrepancy::run::run_discrepancy(&file, &s, &opts)?;
    let report_s = start.elapsed().as_secs_f64();
    Ok(DiscrepancySpeed { particles: sample.strength.len(), named: outcome.named.iter().map(|c| c.name()).collect(), loop_s, report_s })
}

/// One measurement of the microstructure homogenisation.
#[derive(Debug, Clone, PartialEq)]
pub struct MicroSpeed {
    /// Pixels a side.
    pub pixels: usize,
    /// Unknowns of the periodic problem (2·pixels² − 2).
    pub unknowns: usize,
    /// Reading the segmented PNG (s), fastest of the repeats.
    pub read_s: f64,
    /// Pattern and symbolic factorisation (s), fastest.
    pub symbolic_s: f64,
    /// Assembly, numeric factorisation, the three load cases and the fields (s), fastest.
    pub numeric_s: f64,
    /// The three together (s), fastest.
    pub total_s: f64,
    /// Effective C₁₁ (Pa): the same on every repeat and thread count.
    pub c11: f64,
}

/// Times the homogenisation of a `pixels × pixels` segmented image end to end — the PNG read,
/// the symbolic and numeric sparse Cholesky, the three load cases and every element's fields —
/// `repeats` times, keeping the fastest. The image is a synthetic soft-matrix microstructure of
/// α-alumina with 30 % fused silica (200 grains, seed 1) written to a scratch directory.
pub fn micro_speed(pixels: usize, repeats: usize) -> Result<MicroSpeed> {
    use crate::micro::{homogenise, image, material, structure};
    let m = structure::voronoi_two_phase(pixels, pixels, 1e-7, 200, 0.3, structure::Topology::SoftMatrix, 1)?;
    let dir = TempDir::new("bench-micro")?;
    let path = dir.path().join("micro.png");
    std::fs::write(&path, image::write_png(&m, &[[44, 160, 44], [214, 39, 40]])?).map_err(|e| Error::write(&path, e))?;
    let map: std::collections::BTreeMap<String, String> = [("#2ca02c".to_string(), "alumina".to_string()), ("#d62728".to_string(), "fused_silica".to_string())].into();
    let phases: Vec<Elastic> = ["alumina", "fused_silica"].iter().map(|n| material::built_in(n).map(|p| p.elastic).ok_or_else(|| Error::numerical("bench", "no built-in phase"))).collect::<Result<_>>()?;
    let mut best: Option<MicroSpeed> = None;
    for _ in 0..repeats.max(1) {
        let t0 = Instant::now();
        let (read, _) = image::read_segmented(&path, 1e-7, &map)?;
        let t1 = Instant::now();
        let p = homogenise::Periodic::new(read.nx, read.ny)?;
        let t2 = Instant::now();
        let eff = p.solve(&homogenise::element_lame(&read, &phases, homogenise::Plane::Strain)?)?;
        let t3 = Instant::now();
        black_box(&eff);
        let s = MicroSpeed {
            pixels,
            unknowns: 2 * pixels * pixels - 2,
            read_s: (t1 - t0).as_secs_f64(),
            symbolic_s: (t2 - t1).as_secs_f64(),
            numeric_s: (t3 - t2).as_secs_f64(),
            total_s: (t3 - t0).as_secs_f64(),
            c11: eff.c[0][0],
        };
        if best.as_ref().is_none_or(|b| s.total_s < b.total_s) {
            best = Some(s);
        }
    }
    best.ok_or_else(|| Error::numerical("bench", "no repeat ran"))
}

/// The intake's speed on one large lab export.
#[derive(Debug, Clone)]
pub struct IntakeSpeed {
    /// Data rows.
    pub rows: usize,
    /// Seconds to read the semicolon CSV (decimal comma, mm and N): fastest of the repeats.
    pub csv_s: f64,
    /// Seconds to read the .xlsx sheet (mm and kgf, study-mapped headers): fastest of the repeats.
    pub xlsx_s: f64,
    /// File sizes (bytes): CSV, .xlsx.
    pub bytes: (u64, u64),
}

/// Reads a `rows`-row crush export through the whole intake (decode, sniff or unzip, resolve,
/// exact unit conversion, plausibility, records), as a semicolon CSV and as an .xlsx sheet,
/// `repeats` times each; the files are made in a scratch directory from seeded random particles.
pub fn intake_speed(rows: usize, repeats: usize) -> Result<IntakeSpeed> {
    use crate::intake::write::{Sheet, Value};
    let dir = TempDir::new("bench-intake")?;
    let mut rng = ChaCha8Rng::seed_from_u64(31);
    let mut csv = String::from("Probe;Material;D [mm];Fmax [N];roundness;sphericity;T [°C]\n");
    let mut sheet = vec![vec![Value::Text("Nr.".into()), Value::Text("Dp".into()), Value::Text("Last".into()), Value::Text("T [°C]".into())]];
    for k in 0..rows {
        let d: f64 = (rng.random_range(0.6..1.1f64) * 1e3).round() / 1e3;
        let f: f64 = (rng.random_range(50.0..250.0f64) * 10.0).round() / 10.0;
        let (r, s): (f64, f64) = (rng.random_range(0.6..0.95), rng.random_range(0.7..0.98));
        csv.push_str(&format!("P{k};BL 16/30;{};{};{:.3};{:.3};20\n", format!("{d}").replace('.', ","), format!("{f}").replace('.', ","), r, s).replace("0.", "0,"));
        sheet.push(vec![Value::Text(format!("P{k}")), Value::Number(d), Value::Number(f / 9.80665), Value::Number(20.0)]);
    }
    let csv_path = dir.path().join("bench.csv");
    std::fs::write(&csv_path, &csv).map_err(|e| Error::write(&csv_path, e))?;
    let xlsx_path = dir.path().join("bench.xlsx");
    std::fs::write(&xlsx_path, crate::intake::write::xlsx(&[Sheet { name: "BL".into(), rows: sheet, merged: vec![] }])?).map_err(|e| Error::write(&xlsx_path, e))?;
    let csv_src = crate::intake::Source::file(&csv_path);
    let mut xlsx_src = crate::intake::Source::file(&xlsx_path);
    xlsx_src.columns = [("diameter", "Dp"), ("crush_force", "Last")].iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
    xlsx_src.units = [("diameter", "mm"), ("crush_force", "kgf")].iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
    let time = |src: &crate::intake::Source| -> Result<f64> {
        let mut best = f64::INFINITY;
        for _ in 0..repeats.max(1) {
            let t = Instant::now();
            let d = crate::data::read_crush_source(src, &crate::intake::MapOrigin::default())?;
            best = best.min(t.elapsed().as_secs_f64());
            if d.records.len() != rows {
                return Err(Error::numerical("intake benchmark", format!("read {} of {rows} rows", d.records.len())));
            }
            black_box(d);
        }
        Ok(best)
    };
    let size = |p: &Path| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0);
    Ok(IntakeSpeed { rows, csv_s: time(&csv_src)?, xlsx_s: time(&xlsx_src)?, bytes: (size(&csv_path), size(&xlsx_path)) })
}

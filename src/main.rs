//! `partlife` command line: a thin layer over the library.
//!
//! Exit codes: 0 success, 1 run failure, 2 bad input (file, row/key and rule in the message).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand};

/// partlife: lifetime of ceramic particles in CSP plants, from crush tests to breaking
/// probabilities under repeated impacts, with uncertainty.
#[derive(Debug, Parser)]
#[command(name = "partlife", version, about, long_about = None)]
struct Cli {
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, global = true, value_parser = clap::value_parser!(u16).range(1..))]
    threads: Option<u16>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a study file; writes reports/<study name>/ (tables, figures, manifest.json).
    Run {
        /// Study file, e.g. studies/lifetime.toml.
        study: PathBuf,
        /// Root directory of the reports.
        #[arg(long, default_value = "reports")]
        reports_dir: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Where a calibration's simulator runs go: this process (local) or Slurm array jobs
        /// (slurm; options in the study's [executor] table). Default: the study's choice, local.
        #[arg(long, value_enum)]
        executor: Option<Executor>,
        /// Do not run the studies whose reports this one reads when they are missing or stale:
        /// refuse, listing them all.
        #[arg(long)]
        no_deps: bool,
        /// Do not write report.pdf and report.html.
        #[arg(long)]
        no_document: bool,
    },
    /// Evaluate one Slurm array task of a batch file written by `run --executor slurm`
    /// (the task index from --task or SLURM_ARRAY_TASK_ID); results go to the batch's cache.
    Eval {
        /// The batch file (batch.json).
        batch: PathBuf,
        /// Array task index (default: $SLURM_ARRAY_TASK_ID).
        #[arg(long)]
        task: Option<usize>,
    },
    /// Redraw the figures of a report and write its report.pdf and report.html from its tables
    /// (no simulation).
    Report {
        /// Report name (the study file's stem), e.g. lifetime.
        name: String,
        /// Root directory of the reports.
        #[arg(long, default_value = "reports")]
        reports_dir: PathBuf,
        /// Redraw the figures only.
        #[arg(long)]
        no_document: bool,
    },
    /// Find where the strength model and crush data disagree, name the missing effect, add it
    /// and show the gap shrink. Either a study file (kind = "discrepancy") or `--data`.
    Discrepancy {
        /// Study file, e.g. studies/discrepancy_crush.toml.
        #[arg(required_unless_present = "data", conflicts_with = "data")]
        study: Option<PathBuf>,
        /// A crush CSV with the dataset columns (quick run with the default study settings).
        #[arg(long)]
        data: Option<PathBuf>,
        /// Model to diagnose (the deliverable's Weibull law of the Hertz σ̄ at break).
        #[arg(long, value_enum, default_value = "weibull-hertz", requires = "data")]
        model: DiscrepancyModel,
        /// With --data (required): the particles' Young's modulus (Pa), e.g. 112e9 for the
        /// deliverable's Gen 4. It sets the Hertz stresses, hence the lifetime (not the verdict).
        #[arg(long, requires = "data", value_name = "PA")]
        youngs_modulus_pa: Option<f64>,
        /// With --data (required): the particles' Poisson's ratio, e.g. 0.25.
        #[arg(long, requires = "data")]
        poisson_ratio: Option<f64>,
        /// With --data (required): the particles' apparent density (kg/m³), e.g. 3600.
        #[arg(long, requires = "data", value_name = "KG_M3")]
        density_kg_m3: Option<f64>,
        /// With --data: the test temperature (°C) of rows whose file gives none (no temperature
        /// column, or an empty cell); a file that states none is otherwise refused.
        #[arg(long, requires = "data", value_name = "CELSIUS")]
        temperature_c: Option<f64>,
        /// With --data: the temperature (°C) the lifetime is for where the loop names temperature
        /// softening (required when the file's tests span several temperatures).
        #[arg(long, requires = "data", value_name = "CELSIUS")]
        operating_temperature_c: Option<f64>,
        /// With --data: the material's name in the report (default: the file's material
        /// column, else its file name without extension).
        #[arg(long, requires = "data")]
        label: Option<String>,
        /// Root directory of the reports (as for `run`): the report goes to
        /// <root>/<study name>/ (<root>/discrepancy-<file stem>/ with --data), and a curve-level
        /// study finds its calibration's report under the same root.
        #[arg(long, default_value = "reports")]
        reports_dir: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Do not run the calibration a curve-level study reads when its report is missing or
        /// stale: refuse instead.
        #[arg(long)]
        no_deps: bool,
        /// Do not write report.pdf and report.html.
        #[arg(long)]
        no_document: bool,
    },
    /// Dataset tools.
    Datasets {
        #[command(subcommand)]
        command: DatasetsCommand,
    },
    /// Measure the speed figures (evaluations per second, fit time, study wall time).
    #[command(group(clap::ArgGroup::new("benchmark").args(["study", "dem", "fem", "mcmc", "uq", "discrepancy", "experiments", "micro", "intake", "scaling"]).multiple(false)))]
    Bench {
        /// Time the core figures and this study end to end.
        #[arg(long)]
        study: Option<PathBuf>,
        /// Run the DEM benchmark instead (the LIGGGHTS comparison case; about a minute).
        #[arg(long)]
        dem: bool,
        /// Run the crush FE benchmark instead (JH-2 crush to fracture on 1 and all threads).
        #[arg(long)]
        fem: bool,
        /// Run the MCMC benchmark instead (ensemble sampler on the Rosenbrock banana); with
        /// `--chain` also the ESS of another sampler's chain (tests/bench/emcee/banana.py).
        #[arg(long)]
        mcmc: bool,
        /// A chain CSV (step, walker, x1, x2) and its sampling time in seconds, `FILE:SECONDS`.
        #[arg(long, requires = "mcmc")]
        chain: Option<String>,
        /// Run the UQ benchmark instead: 2²⁰ Monte Carlo samples of the main study's chain and
        /// Sobol' indices of Ishigami at N = 2¹⁴ (compare tests/bench/salib/ishigami.py).
        #[arg(long)]
        uq: bool,
        /// Run the discrepancy benchmark instead: the naming loop and the full report on 100
        /// synthetic particles, then studies/discrepancy_curves.toml (the curve level; needs
        /// the report of studies/calibrate_gen3_rt.toml).
        #[arg(long)]
        discrepancy: bool,
        /// Run the experiment-design benchmark instead: studies/experiments.toml end to end
        /// into a scratch reports directory, on all threads and on one (same results).
        #[arg(long)]
        experiments: bool,
        /// Run the microstructure benchmark instead: homogenisation of a segmented
        /// `--pixels`² image (PNG read, sparse Cholesky, three load cases, fields; goal < 10 s
        /// at 512²), fastest of three.
        #[arg(long)]
        micro: bool,
        /// Pixels a side of the microstructure benchmark.
        #[arg(long, default_value_t = 512, requires = "micro")]
        pixels: usize,
        /// Run the data-intake benchmark instead: a `--rows`-row crush export read through the
        /// whole intake as a semicolon CSV (decimal comma, mm) and as an .xlsx sheet (mm, kgf),
        /// fastest of three (goal < 1 s each at 100 000 rows).
        #[arg(long)]
        intake: bool,
        /// Rows of the intake benchmark.
        #[arg(long, default_value_t = 100_000, requires = "intake")]
        rows: usize,
        /// Run the scaling benchmark instead: the DEM cold-test bank (particle-steps/s), the
        /// crush FE (element-steps/s) and the main study (wall s) on 1, 2, 4, … up to the
        /// available threads (`--threads` caps them), as one table with the speed-up on the
        /// most threads, and the DEM's time per step by phase (a few minutes on 2 cores).
        #[arg(long)]
        scaling: bool,
    },
}

/// Executors of `partlife run --executor`.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Executor {
    /// In this process, on all its threads.
    Local,
    /// As Slurm array jobs running `partlife eval`.
    Slurm,
}

/// Models `partlife discrepancy --data` can diagnose.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum DiscrepancyModel {
    /// Weibull law of the average Hertzian tensile stress at break (R = d/2).
    WeibullHertz,
}

#[derive(Debug, Subcommand)]
enum DatasetsCommand {
    /// Regenerate the synthetic crush datasets from the committed generator settings.
    Synth {
        /// Generator settings.
        #[arg(long, default_value = "datasets/synth_crush.toml")]
        settings: PathBuf,
        /// Output directory (default: the settings file's directory).
        #[arg(long)]
        out_dir: Option<PathBuf>,
    },
    /// Regenerate the synthetic crush force–displacement curves (fine-mesh FE; a few minutes).
    SynthCurves {
        /// Generator settings (the generator's truth).
        #[arg(long, default_value = "datasets/synth_curves.toml")]
        settings: PathBuf,
        /// Output directory (default: the settings file's directory).
        #[arg(long)]
        out_dir: Option<PathBuf>,
    },
    /// Regenerate the synthetic tube-bank measurements (one DEM run at the true coefficients).
    SynthDem {
        /// Generator settings (the generator's truth).
        #[arg(long, default_value = "datasets/synth_dem.toml")]
        settings: PathBuf,
        /// Output directory (default: the settings file's directory).
        #[arg(long)]
        out_dir: Option<PathBuf>,
    },
    /// Write the illustrative phase-fraction table (not computed: the rule is in
    /// `partlife::phases::illustrative`).
    SynthPhases {
        /// Output directory.
        #[arg(long, default_value = "datasets")]
        out_dir: PathBuf,
    },
    /// Regenerate the synthetic segmented micrograph (PNG) from its generator settings.
    SynthMicro {
        /// Generator settings.
        #[arg(long, default_value = "datasets/synth_micro.toml")]
        settings: PathBuf,
        /// Output directory (default: the settings file's directory).
        #[arg(long)]
        out_dir: Option<PathBuf>,
    },
    /// Write the example lab exports of datasets/examples/ (a semicolon CSV and a workbook) from
    /// the shipped SI crush files.
    LabExamples {
        /// Directory of the SI crush files.
        #[arg(long, default_value = "datasets")]
        datasets: PathBuf,
        /// Output directory.
        #[arg(long, default_value = "datasets/examples")]
        out_dir: PathBuf,
    },
    /// Validate input files (crush data, curves, observations, spectra, phase tables, Table 1;
    /// text or spreadsheets) and say what was read: format, columns, units, conversions.
    Check {
        /// Files to check (every sheet of a workbook unless --sheet names one).
        #[arg(required_unless_present = "study")]
        files: Vec<PathBuf>,
        /// The data files of this study, read as the study describes them (sheets, column
        /// maps, units, material filters, shape files).
        #[arg(long, conflicts_with_all = ["sheet", "header_row", "material"])]
        study: Option<PathBuf>,
        /// The sheet of a workbook: its name or its position from 1.
        #[arg(long)]
        sheet: Option<String>,
        /// The header's line (text) or sheet row (spreadsheet), from 1.
        #[arg(long)]
        header_row: Option<usize>,
        /// Only the rows of this material (a campaign file holding several).
        #[arg(long)]
        material: Option<String>,
        /// The test temperature (°C) of rows whose file gives none (crush, strength and crush-curve files).
        #[arg(long, conflicts_with = "study", value_name = "CELSIUS")]
        temperature_c: Option<f64>,
    },
}

/// Prints a line to stdout. A closed pipe (`partlife run … | head -1`) is not a failure: the
/// report is already on disk, so write errors on stdout are ignored instead of panicking.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($t)*);
    }};
}

/// Steps of the fine-mesh crush FE benchmark.
const FINE_STEPS: u64 = 1000;

/// The DEM phases `bench --dem` and `--scaling` time, in [`partlife::dem::Dem::phase_seconds`]'s
/// order.
const DEM_PHASES: &str = "kick–drift (+ reactions and closing kick), check, rebuild, forces, bookkeeping, settle + sample";

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            let bad_input = e.chain().any(|c| c.downcast_ref::<partlife::Error>().is_some_and(|pe| pe.is_bad_input()));
            ExitCode::from(if bad_input { 2 } else { 1 })
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new().num_threads(n.into()).build_global().context("setting the thread count")?;
    }
    match cli.command {
        Command::Run { study, reports_dir, quiet, executor, no_deps, no_document } => {
            let mut opts = partlife::runner::RunOptions::new(reports_dir, !quiet);
            opts.documents = !no_document;
            if no_deps {
                opts.deps = partlife::runner::Deps::Refuse;
            }
            opts.executor = executor.map(|e| match e {
                Executor::Local => partlife::runkit::ExecutorKind::Local,
                Executor::Slurm => partlife::runkit::ExecutorKind::Slurm,
            });
            let summary = partlife::runner::run_file(&study, &opts)?;
            for line in &summary.headlines {
                out!("{line}");
            }
            out!("wrote {} in {:.2} s", summary.report_dir.display(), summary.wall_time_s);
        }
        Command::Discrepancy { study, data, model: DiscrepancyModel::WeibullHertz, youngs_modulus_pa, poisson_ratio, density_kg_m3, temperature_c, operating_temperature_c, label, reports_dir, quiet, no_deps, no_document } => {
            let loaded = match (&study, &data) {
                (_, Some(d)) => {
                    let (Some(e), Some(nu), Some(rho)) = (youngs_modulus_pa, poisson_ratio, density_kg_m3) else {
                        let missing: Vec<&str> = [("--youngs-modulus-pa", youngs_modulus_pa), ("--poisson-ratio", poisson_ratio), ("--density-kg-m3", density_kg_m3)].iter().filter(|(_, v)| v.is_none()).map(|(k, _)| *k).collect();
                        return Err(partlife::Error::config("--data", missing.join(", "), "the lifetime needs the particles' elastic constants and density, which set the impact stress (no material is assumed): give --youngs-modulus-pa, --poisson-ratio and --density-kg-m3 (the deliverable's Gen 4: 112e9, 0.25, 3600)").into());
                    };
                    let (file, s) = partlife::discrepancy::run::quick_study(d, partlife::contact::Elastic { youngs_modulus_pa: e, poisson_ratio: nu }, rho, temperature_c, operating_temperature_c, label.as_deref())?;
                    partlife::study::LoadedStudy { file, study: partlife::study::Study::Discrepancy(Box::new(s)) }
                }
                (Some(s), None) => partlife::study::load(s)?,
                (None, None) => anyhow::bail!("give a study file or --data <crush.csv>"),
            };
            if study.is_some() && !matches!(loaded.study, partlife::study::Study::Discrepancy(_) | partlife::study::Study::DiscrepancyCurves(_)) {
                return Err(partlife::Error::config(loaded.file.path.display().to_string(), "kind", "`partlife discrepancy` runs studies of kind \"discrepancy\" or \"discrepancy_curves\"").into());
            }
            let mut opts = partlife::runner::RunOptions::new(reports_dir, !quiet);
            opts.documents = !no_document;
            if no_deps {
                opts.deps = partlife::runner::Deps::Refuse;
            }
            let summary = partlife::runner::run_with_prerequisites(&loaded, &opts)?;
            for line in &summary.headlines {
                out!("{line}");
            }
            out!("wrote {} in {:.2} s", summary.report_dir.display(), summary.wall_time_s);
        }
        Command::Eval { batch, task } => {
            let task = match task {
                Some(t) => t,
                None => std::env::var("SLURM_ARRAY_TASK_ID")
                    .ok()
                    .and_then(|v| v.trim().parse().ok())
                    .ok_or_else(|| partlife::Error::config("partlife eval", "--task", "give --task N or run as a Slurm array task (SLURM_ARRAY_TASK_ID)"))?,
            };
            let r = partlife::calibrate::eval::eval_task(&batch, task)?;
            out!(
                "task {}: {} evaluations ({} failed in the model; {} already in the cache): set-up {:.3} s, compute {:.3} s, cache writes {:.4} s",
                r.task, r.evaluations, r.model_failures, r.already_cached, r.setup_s, r.compute_s, r.write_s
            );
        }
        Command::Report { name, reports_dir, no_document } => {
            let dir = reports_dir.join(&name);
            if !dir.is_dir() {
                return Err(partlife::Error::data_file(&dir, "directory", format!("no report named {name} under {} (run its study first: partlife run studies/{name}.toml)", reports_dir.display())).into());
            }
            let rendered = partlife::report::redraw(&dir)?;
            out!("redrew {} files in {}", rendered.files.len(), dir.display());
            for (fig, n) in rendered.legend_hidden.iter().filter(|(_, n)| *n > 0) {
                eprintln!("warning: figure {fig}: its legend hides {n} data samples (no free corner)");
            }
            if !no_document {
                let docs = partlife::report::build::write(&dir)?;
                out!("wrote {} in {}", docs.join(" and "), dir.display());
            }
        }
        Command::Datasets { command: DatasetsCommand::Synth { settings, out_dir } } => {
            let s = partlife::synth::SynthSettings::load(&settings)?;
            let out = out_dir.unwrap_or_else(|| settings.parent().map(|p| p.to_path_buf()).unwrap_or_default());
            for sum in partlife::synth::synthesize(&s, &out)? {
                out!(
                    "{}: {} particles, d = {:.0}–{:.0} µm, median F(0.8–1.0 mm) = {:.1} N, r(F, d) = {:.3} (p = {:.3})",
                    sum.path.display(),
                    sum.count,
                    sum.diameter_range.0 * 1e6,
                    sum.diameter_range.1 * 1e6,
                    sum.median_force_08_10mm,
                    sum.force_diameter_r,
                    sum.force_diameter_p
                );
            }
        }
        Command::Datasets { command: DatasetsCommand::SynthCurves { settings, out_dir } } => {
            let s = partlife::calibrate::synth::CurveSynthSettings::load(&settings)?;
            let out = out_dir.unwrap_or_else(|| settings.parent().map(|p| p.to_path_buf()).unwrap_or_default());
            let total: usize = s.case.iter().map(|c| c.particles).sum();
            let bar = partlife::runkit::progress_bar(total as u64, true, partlife::runkit::PROGRESS_COUNT);
            for sum in partlife::calibrate::synth::synthesize(&s, &out, &|| bar.inc(1))? {
                out!("{}: {} particles", sum.path.display(), sum.particles);
                for (d, rho, f, x) in sum.rows {
                    out!("  d = {:.0} µm, roundness {:.3}: peak {:.1} N, fracture at {}", d * 1e6, rho, f, x.map(|x| format!("{:.1} µm", x * 1e6)).unwrap_or("—".into()));
                }
            }
            bar.finish_and_clear();
        }
        Command::Datasets { command: DatasetsCommand::SynthDem { settings, out_dir } } => {
            let (s, model) = partlife::calibrate::synth_dem::DemSynthSettings::load(&settings)?;
            let out = out_dir.unwrap_or_else(|| settings.parent().map(|p| p.to_path_buf()).unwrap_or_default());
            let bar = partlife::runkit::progress_bar(1, true, "{spinner} [{elapsed_precise}] {msg}");
            bar.enable_steady_tick(std::time::Duration::from_millis(200));
            bar.set_message(format!("DEM run of {} s at the true coefficients", s.duration));
            let (path, obs) = partlife::calibrate::synth_dem::synthesize(&s, &model, &out)?;
            bar.finish_and_clear();
            out!("{}: {} observations", path.display(), obs.len());
            for o in obs {
                out!("  {} = {:.4e} {} (noise-free {:.4e}, sd {:.2e})", o.output, o.value, o.unit, o.exact, o.sd);
            }
        }
        Command::Datasets { command: DatasetsCommand::SynthPhases { out_dir } } => {
            let path = out_dir.join(partlife::phases::ILLUSTRATIVE_FILE);
            let t = partlife::phases::illustrative();
            partlife::io::write_atomic(&path, t.to_csv().as_bytes())?;
            out!("{}: {} phases at {} temperatures ({}–{} °C), amorphous from {} °C", path.display(), t.phases.len(), t.temperatures_c.len(), t.range().0, t.range().1, t.amorphous_onset(0.0).map_or("—".into(), |v| v.to_string()));
        }
        Command::Datasets { command: DatasetsCommand::SynthMicro { settings, out_dir } } => {
            let text = partlife::io::read_input_text(&settings)?;
            let s: partlife::micro::synth::MicroSettings = partlife::schema::parse_toml(&settings, &text)?;
            let (m, png) = partlife::micro::synth::generate(&settings.display().to_string(), &s)?;
            let dir = out_dir.unwrap_or_else(|| settings.parent().map(PathBuf::from).unwrap_or_default());
            let path = dir.join(&s.file);
            partlife::io::write_atomic(&path, &png)?;
            out!("{}: {} × {} pixels, soft fraction {:.4}", path.display(), m.nx, m.ny, m.fraction(1));
        }
        Command::Datasets { command: DatasetsCommand::LabExamples { datasets, out_dir } } => {
            for p in partlife::lab::write_examples(&datasets, &out_dir)? {
                out!("{}", p.display());
            }
        }
        Command::Datasets { command: DatasetsCommand::Check { files, study, sheet, header_row, material, temperature_c } } => {
            let bare = study.is_none();
            let sources: Vec<(partlife::intake::Source, Option<&'static str>, partlife::intake::MapOrigin, Option<partlife::strength::specimens::SetColumns>)> = match study {
                Some(path) => partlife::study::load(&path)?.data_sources(),
                None => files
                    .into_iter()
                    .map(|f| {
                        let src = partlife::intake::Source {
                            sheet: sheet.as_ref().map(|s| s.parse::<usize>().map(partlife::intake::SheetRef::Index).unwrap_or_else(|_| partlife::intake::SheetRef::Name(s.clone()))),
                            header_row,
                            material: material.clone(),
                            temperature_c,
                            ..partlife::intake::Source::file(f)
                        };
                        (src, None, partlife::intake::MapOrigin::default(), None)
                    })
                    .collect(),
            };
            for (src, kind, origin, set) in sources {
                // A bare file has no study to hold a declaration the message asks for.
                let checked = partlife::inspect::check(&src, kind, &origin, set.as_ref()).map_err(|e| if bare { e.noted_where_declared(" — `datasets check <file>` declares nothing: write the declaration in a study's `data` table and check the file as the study reads it with `datasets check --study <study.toml>`") } else { e })?;
                for checked in checked {
                    for line in checked.lines() {
                        out!("{line}");
                    }
                }
            }
        }
        Command::Bench { dem: true, .. } => {
            out!("machine: {} threads available to rayon", rayon::current_num_threads());
            let d = partlife::bench::dem_particle_steps_per_second(0.15, 25_000)?;
            out!("DEM cold-test bank, {} particles after 0.15 s of filling, 25 000 steps per measurement from that state:", d.particles);
            for f in &d.speeds {
                let ph: Vec<String> = f.phase_us.iter().map(|v| format!("{v:.0}")).collect();
                out!(
                    "  {} thread(s): {:.4e} particle-steps/s; µs/step [{DEM_PHASES}] = [{}]; {} rebuilds",
                    f.threads,
                    f.particle_steps_per_second,
                    ph.join(", "),
                    f.rebuilds
                );
            }
            out!("  same trajectories on every count: {}", if d.identical { "yes" } else { "NO" });
        }
        Command::Bench { scaling: true, .. } => {
            let max = rayon::current_num_threads();
            let counts = partlife::bench::thread_counts(max);
            out!("machine: {} threads available to rayon ({} logical CPUs); thread counts {counts:?}", max, std::thread::available_parallelism().map_or(0, |n| n.get()));
            let dem = partlife::bench::dem_scaling(partlife::bench::dem_benchmark_setup()?, 0.15, 10_000, &counts)?;
            let deep = partlife::bench::dem_scaling(partlife::bench::dem_deep_bank_setup()?, 0.15, 1_000, &counts)?;
            let fem = partlife::bench::fem_scaling(2, &counts)?;
            let fine = partlife::bench::fem_steps_scaling(&partlife::bench::fem_fine_setup()?, FINE_STEPS, 2, &counts)?;
            let study = partlife::bench::main_study_scaling(&counts)?;
            let head: Vec<String> = counts.iter().map(|c| if *c == 1 { "1 thread".to_string() } else { c.to_string() }).collect();
            out!("| work | {} | speed-up on {max} |", head.join(" | "));
            out!("|---|{}---|", "---|".repeat(counts.len()));
            let row = |what: String, v: Vec<f64>, higher_better: bool, fmt: &dyn Fn(f64) -> String| {
                let speed_up = if higher_better { v[v.len() - 1] / v[0] } else { v[0] / v[v.len() - 1] };
                format!("| {what} | {} | {speed_up:.2}× |", v.iter().map(|x| fmt(*x)).collect::<Vec<_>>().join(" | "))
            };
            let e = |x: f64| format!("{x:.3e}");
            for (what, d) in [("DEM cold-test bank", &dem), ("DEM bank, 10× deeper slab", &deep)] {
                out!("{}", row(format!("{what}, {} particles (particle-steps/s)", d.particles), d.speeds.iter().map(|d| d.particle_steps_per_second).collect(), true, &e));
            }
            let elements = fem.first().map_or(0, |f| f.elements);
            out!("{}", row(format!("crush FE, {elements} elements (element-steps/s)"), fem.iter().map(|f| f.element_steps_per_second).collect(), true, &e));
            let fine_elements = fine.first().map_or(0, |f| f.elements);
            out!("{}", row(format!("crush FE, fine mesh, {fine_elements} elements (element-steps/s)"), fine.iter().map(|f| f.element_steps_per_second).collect(), true, &e));
            out!("{}", row("main study `gen4_vs_bl` (wall s)".into(), study.seconds.iter().map(|s| s.1).collect(), false, &|x| format!("{x:.2}")));
            out!("main study tables ({}) byte-identical on every thread count: {}", study.tables.join(", "), if study.identical { "yes" } else { "NO" });
            for (what, d) in [("cold-test bank", &dem), ("10× deeper slab", &deep)] {
                out!("DEM {what}, same trajectories on every thread count: {}; time per step by phase (µs): threads | {} | rebuilds", if d.identical { "yes" } else { "NO" }, DEM_PHASES.replace(", ", " | "));
                for s in &d.speeds {
                    let ph: Vec<String> = s.phase_us.iter().map(|v| format!("{v:.0}")).collect();
                    out!("  {} | {} | {}", s.threads, ph.join(" | "), s.rebuilds);
                }
            }
            let fe: Vec<String> = fem.iter().map(|f| format!("{} thread(s) {:.2} s", f.threads, f.run_seconds)).collect();
            out!("crush FE run to fracture ({} steps): {}; peak force the same on every count: {}", fem.first().map_or(0, |f| f.steps), fe.join(", "), if fem.windows(2).all(|w| w[0].peak_force == w[1].peak_force) { "yes" } else { "NO" });
            out!("crush FE fine mesh, {FINE_STEPS} steps: platen impulse the same bits on every count: {}", if fine.windows(2).all(|w| w[0].impulse.to_bits() == w[1].impulse.to_bits()) { "yes" } else { "NO" });
        }
        Command::Bench { mcmc: true, chain, .. } => {
            // Checked before the benchmark runs: a bad argument costs nothing.
            let chain = match chain {
                Some(spec) => {
                    let bad = |rule: String| partlife::Error::config("command line", "--chain", rule);
                    let (file, secs) = spec.rsplit_once(':').ok_or_else(|| bad(format!("takes FILE:SECONDS (got \"{spec}\")")))?;
                    let secs: f64 = secs.parse().ok().filter(|s: &f64| s.is_finite() && *s > 0.0).ok_or_else(|| bad(format!("SECONDS must be a number > 0 (got \"{secs}\")")))?;
                    Some((file.to_string(), secs))
                }
                None => None,
            };
            out!("machine: {} threads available to rayon", rayon::current_num_threads());
            let m = partlife::bench::mcmc_banana(40_000)?;
            out!(
                "ensemble sampler, Rosenbrock banana, 32 walkers × 40 000 steps: {:.2} s, {:.3e} evaluations/s, bulk ESS {:.0}, ESS/s {:.1}",
                m.seconds, m.evaluations_per_second, m.ess, m.ess_per_second
            );
            if let Some((file, secs)) = chain {
                let ess = partlife::bench::external_chain_ess(std::path::Path::new(&file))?;
                out!("external chain {file}: bulk ESS {ess:.0} in {secs:.2} s → ESS/s {:.1}; ratio ours/theirs {:.1}×", ess / secs, m.ess_per_second / (ess / secs));
            }
        }
        Command::Bench { discrepancy: true, .. } => {
            out!("machine: {} threads available to rayon", rayon::current_num_threads());
            let d = partlife::bench::discrepancy_speed(&partlife::bench::repo_path("datasets/synth_crush.toml"))?;
            out!(
                "discrepancy workflow, {} particles (named: {}): naming loop with every candidate, at most 499 bootstrap replicates per round and 999 permutations per trend {:.3} s; whole report with lifetime bands, 320-dataset power study and figures {:.2} s (goal < 30 s)",
                d.particles,
                d.named.join(", "),
                d.loop_s,
                d.report_s
            );
            // Named effects, the replicates each round drew, and both timings against the goal.
            let speed = |x: &partlife::bench::NamingSpeed, goal: &str| {
                format!(
                    "named: {}; the rounds drew {}: {:.2} s (goal < {goal}); drawing every replicate {:.2} s ({:.1}×), same names: {}",
                    x.named.join(", "),
                    x.replicates.iter().map(|b| b.to_string()).collect::<Vec<_>>().join(", "),
                    x.seconds,
                    x.seconds_every,
                    x.seconds_every / x.seconds,
                    if x.same_names { "yes" } else { "NO" }
                )
            };
            let a = partlife::bench::strength_factors_speed(500, 0.0)?;
            out!(
                "naming loop on a strength file of 500 specimens with 6 recorded factors (size, 2 numeric, 3 categorical) and both two-population laws ({} candidates), at most 499 bootstrap replicates per round, sequential, and 999 permutations per residual test — {}",
                a.candidates,
                speed(&a, "10 s")
            );
            let c = partlife::bench::strength_factors_speed(500, 0.2)?;
            out!("the same with the strongest 20 % not broken by the rig's limit (right-censored) — {}", speed(&c, "15 s"));
            let (complete, censored) = partlife::bench::censored_fit_speed()?;
            out!("one two-parameter fit of 500 strengths: complete {:.1} µs, 20 % censored {:.1} µs ({:.2}×; goal ≤ 2×)", complete * 1e6, censored * 1e6, censored / complete);
            // The curve level needs the calibration's report (its emulator runs).
            match partlife::bench::curve_discrepancy_speed()? {
                Some((study, headlines, secs)) => out!("curve-level discrepancy loop ({}): {} — {secs:.1} s including the 5 FE runs of the curvature table (goal < 15 min)", study.display(), headlines.join("; ")),
                None => out!("curve-level discrepancy loop: not timed — run `partlife run studies/calibrate_gen3_rt.toml` in the repository first (its report holds the emulator's runs)"),
            }
        }
        Command::Bench { experiments: true, .. } => {
            out!("machine: {} threads available to rayon", rayon::current_num_threads());
            let e = partlife::bench::experiments_speed()?;
            out!("studies/experiments.toml end to end ({}): {:.1} s on {} threads (goal < 60 s), {:.1} s on 1 thread; tables identical on both: {}", e.headline, e.seconds, rayon::current_num_threads(), e.seconds_one_thread, e.identical);
        }
        Command::Bench { uq: true, .. } => {
            out!("machine: {} threads available to rayon", rayon::current_num_threads());
            let u = partlife::bench::uq_speed(&partlife::bench::repo_path("studies/gen4_vs_bl.toml"))?;
            out!(
                "main-study chain (strength model `{}`, populations of {} and {} particles), {} Sobol' samples × 2 materials × 2 horizons × 3 damage models: {:.3} s ({:.2e} samples/s; goal 2²⁰ in < 2 s)",
                u.strength_model,
                u.particles[0],
                u.particles[1],
                u.samples,
                u.propagation_s,
                u.samples as f64 / u.propagation_s
            );
            out!("Sobol' indices of Ishigami, N = 2¹⁴ (81 920 runs) + 1000 bootstrap resamples: {:.3} s, largest |Ŝ − S| = {:.4}", u.ishigami_s, u.ishigami_error);
        }
        Command::Bench { intake: true, rows, .. } => {
            if !(10..=10_000_000).contains(&rows) {
                return Err(partlife::Error::config("partlife bench", "--rows", format!("must lie in 10…10000000, got {rows}")).into());
            }
            let i = partlife::bench::intake_speed(rows, 3)?;
            out!(
                "data intake, {} rows of crush data (decode, sniff or unzip, columns, exact unit conversion, plausibility, records), fastest of 3: semicolon CSV with decimal commas in mm and N ({:.1} MB) {:.3} s; .xlsx sheet in mm and kgf with study-mapped headers ({:.1} MB) {:.3} s (goal < 1 s each)",
                i.rows,
                i.bytes.0 as f64 / 1e6,
                i.csv_s,
                i.bytes.1 as f64 / 1e6,
                i.xlsx_s
            );
        }
        Command::Bench { micro: true, pixels, .. } => {
            if !(8..=4096).contains(&pixels) {
                return Err(partlife::Error::config("partlife bench", "--pixels", format!("must lie in 8…4096, got {pixels}")).into());
            }
            out!("machine: {} threads available to rayon (the factorisation is sequential)", rayon::current_num_threads());
            let m = partlife::bench::micro_speed(pixels, 3)?;
            out!(
                "microstructure homogenisation, {0} × {0} pixels ({1} unknowns), fastest of 3: total {2:.3} s (goal < 10 s at 512²) = PNG read {3:.3} s + symbolic factorisation {4:.3} s + assembly, numeric factorisation, 3 load cases and fields {5:.3} s; C11 = {6:.6e} Pa",
                m.pixels, m.unknowns, m.total_s, m.read_s, m.symbolic_s, m.numeric_s, m.c11
            );
        }
        Command::Bench { fem: true, .. } => {
            out!("machine: {} threads available to rayon", rayon::current_num_threads());
            for f in partlife::bench::fem_speed(3)? {
                out!(
                    "crush FE (studies/crush_gen3_rt.toml, {} elements, {} steps to fracture), {} thread(s): {:.4e} element-steps/s, run {:.2} s (goals: ≥ 2e7 element-steps/s on one core, ≥ 1.7× on two, run < 2 s); peak force {:.6} N",
                    f.elements, f.steps, f.threads, f.element_steps_per_second, f.run_seconds, f.peak_force
                );
            }
            let all = rayon::current_num_threads();
            let fine = partlife::bench::fem_steps_scaling(&partlife::bench::fem_fine_setup()?, FINE_STEPS, 2, &if all > 1 { vec![1, all] } else { vec![1] })?;
            for f in &fine {
                out!("crush FE, fine mesh ({} elements, {FINE_STEPS} steps from the start), {} thread(s): {:.4e} element-steps/s, {:.2} s", f.elements, f.threads, f.element_steps_per_second, f.seconds);
            }
            out!("  same platen impulse on every count: {}", if fine.windows(2).all(|w| w[0].impulse.to_bits() == w[1].impulse.to_bits()) { "yes" } else { "NO" });
        }
        Command::Bench { study, .. } => {
            out!("machine: {} threads available to rayon", rayon::current_num_threads());
            for fig in partlife::bench::run_all(study.as_deref())? {
                out!("{}: {:.4e} {} (goal {})", fig.what, fig.value, fig.unit, fig.goal);
            }
        }
    }
    Ok(())
}

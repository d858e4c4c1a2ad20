//! Runs a study into its report directory: the dispatch from a loaded study's kind to its
//! runner, at the top of the module graph (only the CLI and the benchmarks import it). Each
//! runner writes tables, figures (drawn from the tables only) and `manifest.json` to a
//! temporary directory renamed into place at the end ([`crate::runkit`]).

use std::path::Path;

use crate::error::Result;
pub use crate::runkit::{RunOptions, RunSummary};
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

/// Convenience for callers that only have a path.
pub fn run_file(path: &Path, opts: &RunOptions) -> Result<RunSummary> {
    let loaded = crate::study::load(path)?;
    run(&loaded, opts)
}

//! Study files: the dispatch from a study's `kind` to its schema.
//!
//! A study file `studies/<name>.toml` maps one-to-one to `reports/<name>/`:
//!
//! ```toml
//! kind = "lifetime"
//! seed = 20261121
//! [contact]            # platen and averaging domain of the tensile stress
//! [impact]             # wall, η, velocities, impact counts, impacts per year
//! [weibull]            # confidence level, pivotal samples, shape estimate
//! [figures]            # width
//! [[material]]         # one per particle type: data file, elastic constants, density
//! ```
//!
//! [`load`] reads the file ([`crate::schema::StudyFile`]), parses it as the schema of its kind
//! (kept with each kind's runner) and validates it. Only the top of the crate ([`crate::runner`],
//! the CLI, benchmarks) uses this module; study modules read other studies through
//! [`crate::schema`].

use std::path::Path;

use crate::error::{Error, Result};
pub use crate::schema::{ContactOptions, FigureOptions, ImpactOptions, MaterialSpec, StudyFile, parse_toml, resolve_relative};
pub use crate::lifetime_study::{LifetimeStudy, ShapeEstimate, WeibullOptions, validate_lifetime};

/// The kinds of study this version can run.
pub const KINDS: [&str; 10] = ["lifetime", "dem", "crush", "calibrate", "uq", "discrepancy", "discrepancy_curves", "experiments", "temperature", "microstructure"];

/// A parsed, validated study.
#[derive(Debug, Clone, PartialEq)]
#[allow(clippy::large_enum_variant)] // one per run: the size difference does not matter
pub enum Study {
    /// kind = "lifetime".
    Lifetime(LifetimeStudy),
    /// kind = "dem": particle flow through the tube bank.
    Dem(Box<crate::dem::run::DemStudy>),
    /// kind = "crush": single-particle crush tests with the FE.
    Crush(Box<crate::fem::run::CrushStudy>),
    /// kind = "calibrate": fit a simulator's parameters to data.
    Calibrate(Box<crate::calibrate::run::CalibrateStudy>),
    /// kind = "uq": Monte Carlo propagation and Sobol' indices of the lifetime chain.
    Uq(Box<crate::uq::study::UqStudy>),
    /// kind = "discrepancy": find, name and add what the strength model misses.
    Discrepancy(Box<crate::discrepancy::run::DiscrepancyStudy>),
    /// kind = "discrepancy_curves": the same at the force–displacement level, against a crush
    /// calibration.
    DiscrepancyCurves(Box<crate::discrepancy::curves::CurveStudy>),
    /// kind = "experiments": which crush or impact tests next, decided by their value.
    Experiments(Box<crate::experiments::ExperimentsStudy>),
    /// kind = "temperature": phases against temperature (the temperature model of the
    /// parameters and the lifetime at temperature to come).
    Temperature(Box<crate::temperature::TemperatureStudy>),
    /// kind = "microstructure": effective moduli and stress hot spots of two-phase
    /// microstructures (synthetic or segmented images).
    Microstructure(Box<crate::micro::MicroStudy>),
}

/// A study file loaded from disk and validated.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedStudy {
    /// The file: name, path, text.
    pub file: StudyFile,
    /// The validated content.
    pub study: Study,
}

impl LoadedStudy {
    /// The studies whose reports this one reads, each with the key that names it and the
    /// report files it needs (none for most kinds).
    pub fn prerequisites(&self) -> Result<Vec<crate::schema::Prerequisite>> {
        let f = &self.file;
        Ok(match &self.study {
            Study::Calibrate(s) => s.prerequisites(&|p: &str| f.resolve(Path::new(p))),
            Study::DiscrepancyCurves(s) => s.prerequisites(f),
            Study::Temperature(s) => s.prerequisites(f)?,
            Study::Uq(s) => s.prerequisites(&f.path)?,
            Study::Experiments(s) => s.prerequisites(f)?,
            _ => Vec::new(),
        })
    }

    /// Checks the study's own input files where a run reads them only after the reports of
    /// other studies (the curve files of a curve-level study, the phase table of a temperature
    /// study), so that a bad file is refused before any prerequisite runs.
    pub fn check_inputs(&self) -> Result<()> {
        let f = &self.file;
        match &self.study {
            Study::DiscrepancyCurves(s) => s.read_data(f).map(|_| ()),
            Study::Temperature(s) => s.phases.read(&f.path.display().to_string(), &f.resolve(&s.phases.file)).map(|_| ()),
            _ => Ok(()),
        }
    }

    /// The data files it reads, each as the study describes it (files resolved relative to the
    /// study file) with the kind of input the study reads it as ([`crate::inspect::check`];
    /// None: crush data, or whatever its header shows): what `partlife datasets check --study`
    /// reads. The crush data of its materials; a calibration's curve or observation file and a
    /// curve-level discrepancy study's curve files, with their column and unit maps and where
    /// the study holds each map (its key, for messages about the map). Other kinds read none.
    /// A strength file comes with its table's other column keys (size, factors, origin).
    pub fn data_sources(&self) -> Vec<(crate::intake::Source, Option<&'static str>, crate::intake::MapOrigin, Option<crate::strength::specimens::SetColumns>)> {
        use crate::intake::{MapOrigin, Source};
        let study = &self.file.path;
        let origin = |key: String| MapOrigin { file: study.display().to_string(), key };
        let materials: &[MaterialSpec] = match &self.study {
            Study::Lifetime(s) => &s.material,
            Study::Uq(s) => &s.material,
            Study::Discrepancy(s) => &s.material,
            Study::Calibrate(s) => {
                return vec![match &s.data {
                    crate::calibrate::study::DataSpec::CrushCurves { file, columns, units, temperature_c, sheet, header_row, .. } => {
                        let src = Source { sheet: sheet.clone(), header_row: *header_row, columns: columns.clone(), units: units.clone(), temperature_c: *temperature_c, ..Source::file(resolve_relative(study, Path::new(file))) };
                        (src, Some("curves"), origin("data".into()), None)
                    }
                    crate::calibrate::study::DataSpec::Observations { file } => (Source::file(resolve_relative(study, Path::new(file))), Some("observations"), origin("data".into()), None),
                }];
            }
            Study::DiscrepancyCurves(s) => return s.data.iter().enumerate().map(|(i, d)| (d.source(&resolve_relative(study, Path::new(&d.file))), Some("curves"), origin(format!("data[{i}]")), None)).collect(),
            _ => &[],
        };
        // A crush file is read with its material's factor and origin columns, as the run reads it.
        let mut out: Vec<_> = materials
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let keys = crate::strength::specimens::SetColumns { size: None, factors: m.factors.clone(), origin: m.origin.clone() };
                (m.data.resolved(study), None, origin(format!("material[{k}].data")), Some(keys))
            })
            .collect();
        if let Study::Discrepancy(s) = &self.study {
            out.extend(s.strength.iter().enumerate().map(|(k, set)| {
                let keys = crate::strength::specimens::SetColumns { size: set.size.clone(), factors: set.factors.clone(), origin: set.origin.clone() };
                (set.data.resolved(study), Some("strength"), origin(format!("strength[{k}].data")), Some(keys))
            }));
        }
        out
    }
}

/// Reads, parses and validates a study file.
pub fn load(path: &Path) -> Result<LoadedStudy> {
    let file = StudyFile::read(path)?;
    let name = path.display().to_string();
    let study = match file.kind(&KINDS)?.as_str() {
        "lifetime" => {
            let s: LifetimeStudy = file.parse()?;
            validate_lifetime(&s, &name)?;
            Study::Lifetime(s)
        }
        "dem" => {
            let s: crate::dem::run::DemStudy = file.parse()?;
            s.setup(&name)?;
            Study::Dem(Box::new(s))
        }
        "crush" => {
            let s: crate::fem::run::CrushStudy = file.parse()?;
            s.setups(&name)?;
            Study::Crush(Box::new(s))
        }
        "calibrate" => {
            let s: crate::calibrate::run::CalibrateStudy = file.parse()?;
            s.prepare(path, &|p: &str| resolve_relative(path, Path::new(p)))?;
            Study::Calibrate(Box::new(s))
        }
        "uq" => {
            let s: crate::uq::study::UqStudy = file.parse()?;
            s.validate(&name)?;
            Study::Uq(Box::new(s))
        }
        "discrepancy" => {
            let s: crate::discrepancy::run::DiscrepancyStudy = file.parse()?;
            s.validate(&name)?;
            Study::Discrepancy(Box::new(s))
        }
        "discrepancy_curves" => {
            let s: crate::discrepancy::curves::CurveStudy = file.parse()?;
            s.validate(&name)?;
            Study::DiscrepancyCurves(Box::new(s))
        }
        "experiments" => {
            let s: crate::experiments::ExperimentsStudy = file.parse()?;
            s.validate(&name, None)?;
            Study::Experiments(Box::new(s))
        }
        "temperature" => {
            let s: crate::temperature::TemperatureStudy = file.parse()?;
            s.validate(&name)?;
            Study::Temperature(Box::new(s))
        }
        "microstructure" => {
            let s: crate::micro::MicroStudy = file.parse()?;
            s.validate(&name)?;
            Study::Microstructure(Box::new(s))
        }
        other => {
            return Err(Error::config(&name, "kind", format!("unknown kind \"{other}\"; known: {}", KINDS.join(", "))));
        }
    };
    Ok(LoadedStudy { file, study })
}

//! The schema of a calibration study (`kind = "calibrate"`): data, model, parameters,
//! comparison and figures, and [`CalibrateStudy::prepare`], which validates it and builds the
//! model and observations a run calibrates.

use std::path::PathBuf;
use serde::{Deserialize, Serialize};
use super::data::{CrushReduction, Observations, load_observations, read_curves, reduce_curves};
use super::pipeline::PipelineOptions;
use crate::error::{Error, Result};
use crate::fem::model::CrushModel;
use crate::fem::CrushSetup;
use crate::model::{Restricted, Simulator};
use crate::params::{Param, Prior};

/// `[data]`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum DataSpec {
    /// Crush force–displacement curves (`particle, diameter_m, displacement_m, force_n`).
    CrushCurves {
        /// Curve file, relative to the study file.
        file: String,
        /// Reference diameter D₀ (m); default: the mean diameter of the particles.
        #[serde(default)]
        reference_diameter: Option<f64>,
        /// Grid displacements K (default 8).
        #[serde(default = "default_points")]
        points: usize,
        /// Grid end as a fraction of the smallest fracture displacement (default 0.8).
        #[serde(default = "default_fraction")]
        fraction: f64,
        /// σ floor as a fraction of each output's mean (default 0.02).
        #[serde(default = "default_floor")]
        sigma_floor: f64,
        /// The file's header for a field its header does not name (`particle`, `diameter`,
        /// `displacement`, `force`), e.g. `{ displacement = "Weg [µm]", force = "Kraft [N]" }`.
        #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
        columns: std::collections::BTreeMap<String, String>,
        /// A field's unit where its header states none, e.g. `{ displacement = "mm" }`.
        #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
        units: std::collections::BTreeMap<String, String>,
        /// The curves' test temperature (°C) where the file has no temperature column (or an
        /// empty cell); a curve with neither is refused.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        temperature_c: Option<f64>,
        /// The sheet of a workbook: its name, or its position from 1 (default: the first).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sheet: Option<crate::intake::SheetRef>,
        /// The line (text) or sheet row (workbook) of the header, from 1 (default: the first).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        header_row: Option<usize>,
    },
    /// Named observations (`output, unit, value, sd`).
    Observations {
        /// Observation file, relative to the study file.
        file: String,
    },
}

fn default_points() -> usize {
    8
}
fn default_fraction() -> f64 {
    0.8
}
fn default_floor() -> f64 {
    0.02
}

/// `[model]`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ModelSpec {
    /// The crush FE ([`CrushModel`]); θ names are JH-2 card names.
    Crush {
        /// Base set-up (its diameter is replaced by the data's reference diameter).
        crush: Box<CrushSetup>,
    },
    /// The tube-bank DEM ([`crate::dem::model::TubeBankModel`]); θ names are
    /// `restitution_pp`, `restitution_pw`, `friction_pp`, `friction_pw`.
    Dem {
        /// A `kind = "dem"` study file (relative to this study) whose set-up is the base.
        study: String,
        /// Simulated time per evaluation (s), warm-up included.
        duration: f64,
        /// Heights of the velocity-profile outputs (m).
        heights: Vec<f64>,
        /// Half-width of the height bands (m).
        window: f64,
    },
}

/// `[[param]]`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamDecl {
    /// Model parameter name.
    pub name: String,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
    /// Prior (default uniform), truncated to the bounds.
    #[serde(default = "uniform")]
    pub prior: Prior,
}

fn uniform() -> Prior {
    Prior::Uniform
}

/// `[compare]`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Compare {
    /// The calibration study (relative to the study file) whose report's `parameters.csv` is
    /// compared with (run first when its report is missing or stale).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub study: Option<std::path::PathBuf>,
    /// Or a `parameters.csv` of another calibration given directly (relative to the study file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<std::path::PathBuf>,
    /// Its label (`Gen 3, RT`).
    pub label: String,
}

impl Compare {
    /// The `parameters.csv` compared with (`resolve`: paths relative to the study file).
    pub fn parameters_file(&self, file: &str, resolve: &dyn Fn(&str) -> PathBuf, reports_root: &std::path::Path) -> Result<PathBuf> {
        crate::schema::one_of(file, "compare", &self.study, &self.reference, "study", "reference")?;
        Ok(match (&self.study, &self.reference) {
            (Some(st), _) => crate::schema::report_file(reports_root, &resolve(&st.to_string_lossy()), "parameters.csv"),
            (_, Some(r)) => resolve(&r.to_string_lossy()),
            _ => unreachable!("one_of checked"),
        })
    }
}

/// `[figures]`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CalibrateFigures {
    /// Single-column width (cm), default 8.5; the corner plot is twice as wide.
    pub width_cm: f64,
}

impl Default for CalibrateFigures {
    fn default() -> Self {
        CalibrateFigures { width_cm: 8.5 }
    }
}

/// A calibration study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrateStudy {
    /// `calibrate`.
    pub kind: String,
    /// Seed (MCMC, predictive draws).
    #[serde(default)]
    pub seed: u64,
    /// What is calibrated, for figures (`Gen 3, RT`).
    pub label: String,
    /// Data.
    pub data: DataSpec,
    /// Model.
    pub model: ModelSpec,
    /// Parameters to fit (at least one).
    pub param: Vec<ParamDecl>,
    /// The loop's settings.
    #[serde(default)]
    pub calibration: PipelineOptions,
    /// Comparison with another calibration.
    #[serde(default)]
    pub compare: Option<Compare>,
    /// Figures.
    #[serde(default)]
    pub figures: CalibrateFigures,
    /// Where the simulator's evaluations run (local by default; [`super::executor`]).
    #[serde(default)]
    pub executor: super::executor::ExecutorOptions,
}

/// The model of a study, built.
pub enum Built {
    /// Crush FE and the curve reduction.
    Crush(CrushModel, CrushReduction),
    /// Tube-bank DEM.
    Dem(Box<Restricted<crate::dem::model::TubeBankModel>>),
}

/// A study ready to run: the model, the observations, the input files.
pub struct Prepared {
    /// The model.
    pub built: Built,
    /// Observations.
    pub observations: Observations,
    /// Input files (data, referenced studies).
    pub inputs: Vec<PathBuf>,
    /// Configuration text of the model (the cache key's prefix).
    pub config: String,
    /// How the curve file was read (crush curves; its columns, units and test temperature).
    pub read: Option<crate::intake::Provenance>,
}

impl CalibrateStudy {
    /// The studies whose reports it reads: the calibration of `[compare] study`.
    pub fn prerequisites(&self, resolve: &dyn Fn(&str) -> PathBuf) -> Vec<crate::schema::Prerequisite> {
        self.compare.as_ref().and_then(|c| c.study.as_ref()).map(|st| crate::schema::Prerequisite { key: "compare.study".into(), study: resolve(&st.to_string_lossy()), files: vec!["parameters.csv"] }).into_iter().collect()
    }

    /// Loads the data and builds the model; every mismatch is an error naming the file and key.
    pub fn prepare(&self, loaded_path: &std::path::Path, resolve: &dyn Fn(&str) -> PathBuf) -> Result<Prepared> {
        let file = loaded_path.display().to_string();
        self.executor.validate(&file)?;
        if let Some(c) = &self.compare {
            crate::schema::one_of(&file, "compare", &c.study, &c.reference, "study", "reference")?;
        }
        if self.param.is_empty() {
            return Err(Error::config(&file, "param", "at least one [[param]] is required"));
        }
        let mut seen = std::collections::HashSet::new();
        let params: Vec<Param> = self
            .param
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if !seen.insert(p.name.clone()) {
                    return Err(Error::config(&file, format!("param[{i}].name"), format!("`{}` appears twice", p.name)));
                }
                let q = Param { name: p.name.clone(), unit: String::new(), lower: p.lower, upper: p.upper, prior: p.prior.clone(), nominal: 0.5 * (p.lower + p.upper) };
                crate::params::ParamSpace::new(vec![q.clone()]).map_err(|e| Error::config(&file, format!("param[{i}] ({})", p.name), e.to_string()))?;
                Ok(q)
            })
            .collect::<Result<_>>()?;
        let relabel = |e: Error| match e {
            Error::Param { name, rule } => {
                let i = self.param.iter().position(|p| p.name == name).unwrap_or(0);
                Error::config(&file, format!("param[{i}].name"), format!("`{name}`: {rule}"))
            }
            Error::Config { key, rule, .. } => Error::config(&file, format!("model: {key}"), rule),
            other => other,
        };
        let (built, observations, inputs, config, read) = match (&self.model, &self.data) {
            (ModelSpec::Crush { crush }, DataSpec::CrushCurves { file: data, reference_diameter, points, fraction, sigma_floor, columns, units, temperature_c, sheet, header_row }) => {
                if !(*points >= 2 && *points <= 40) {
                    return Err(Error::config(&file, "data.points", format!("must lie in [2, 40], got {points}")));
                }
                if !(*fraction > 0.0 && *fraction <= 1.0) {
                    return Err(Error::config(&file, "data.fraction", format!("must lie in (0, 1], got {fraction}")));
                }
                if !(*sigma_floor >= 0.0 && *sigma_floor < 1.0) {
                    return Err(Error::config(&file, "data.sigma_floor", format!("must lie in [0, 1), got {sigma_floor}")));
                }
                // Replaced by the data's reference diameter, but still checked: a study that
                // says `diameter = nan` is wrong even where the value is not used.
                if !crate::data::DIAMETER.contains(crush.diameter) {
                    return Err(Error::config(&file, "model.crush.diameter", format!("must lie in {}, got {}", crate::data::DIAMETER.shown, crush.diameter)));
                }
                let path = existing(&file, "data.file", resolve(data))?;
                if let Some(t) = temperature_c
                    && let Some(rule) = crate::intake::observed::TEMPERATURE.broken(*t)
                {
                    return Err(Error::config(&file, "data.temperature_c", rule));
                }
                let src = crate::intake::Source { sheet: sheet.clone(), header_row: *header_row, columns: columns.clone(), units: units.clone(), temperature_c: *temperature_c, ..crate::intake::Source::file(&path) };
                let (curves, read) = read_curves(&src, &crate::intake::MapOrigin { file: file.clone(), key: "data".into() })?;
                let d0 = match reference_diameter {
                    Some(d) if *d > 0.0 && d.is_finite() => *d,
                    Some(d) => return Err(Error::config(&file, "data.reference_diameter", format!("must be > 0, got {d}"))),
                    None => curves.iter().map(|c| c.diameter).sum::<f64>() / curves.len() as f64,
                };
                let red = reduce_curves(&path, &curves, d0, *points, *fraction, *sigma_floor, crush.fracture)?;
                let mut base = (**crush).clone();
                base.diameter = d0;
                base.fields_at.clear();
                let model = CrushModel::new(base.clone(), params, red.grid.clone()).map_err(relabel)?;
                let config = serde_json::to_string(&(&base, &self.param, &red.grid)).map_err(|e| Error::numerical("cache key", e.to_string()))?;
                let obs = red.observations.clone();
                (Built::Crush(model, red), obs, vec![path], config, Some(read))
            }
            (ModelSpec::Dem { study, duration, heights, window }, DataSpec::Observations { file: data }) => {
                let spath = existing(&file, "model.study", resolve(study))?;
                let loaded = crate::schema::StudyFile::read(&spath)?;
                if loaded.kind(&["dem"])? != "dem" {
                    return Err(Error::config(&file, "model.study", format!("{} is not a kind = \"dem\" study", spath.display())));
                }
                let ds: crate::dem::run::DemStudy = loaded.parse()?;
                let setup = ds.setup(&spath.display().to_string())?;
                if heights.is_empty() || heights.iter().any(|h| !h.is_finite()) || !(*window > 0.0) {
                    return Err(Error::config(&file, "model.heights", "at least one finite height and a window > 0 are required"));
                }
                let tb = crate::dem::model::TubeBankModel::new(setup, *duration, heights.clone(), *window).map_err(relabel)?;
                let model = Restricted::new(tb, params).map_err(relabel)?;
                let path = existing(&file, "data.file", resolve(data))?;
                let obs = load_observations(&path, model.outputs())?;
                let config = format!("{}\n{}", loaded.text, serde_json::to_string(&(&self.model, &self.param)).map_err(|e| Error::numerical("cache key", e.to_string()))?);
                (Built::Dem(Box::new(model)), obs, vec![path, spath], config, None)
            }
            _ => return Err(Error::config(&file, "data.kind", "a crush model takes data kind \"crush_curves\", a dem model \"observations\"")),
        };
        let dim = self.param.len();
        if observations.len() < dim {
            return Err(Error::config(&file, "data", format!("{} observations cannot determine {dim} parameters", observations.len())));
        }
        self.calibration.validate(&file, "calibration", dim)?;
        crate::schema::FigureOptions { width_cm: self.figures.width_cm }.validate(&file)?;
        // [compare]'s reference report may not exist yet at load: it is read when the tables are
        // written, and a missing one is reported in summary.md.
        Ok(Prepared { built, observations, inputs, config, read })
    }
}

/// `path` if it is a file, else an error naming the study key that refers to it.
fn existing(file: &str, key: &str, path: PathBuf) -> Result<PathBuf> {
    if path.is_file() { Ok(path) } else { Err(Error::config(file, key, format!("{} does not exist", path.display()))) }
}

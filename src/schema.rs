//! The study-file layer shared by every kind of study: reading a study file ([`StudyFile`]),
//! TOML parsing with precise errors ([`parse_toml`]), paths relative to the study, the checks
//! every validator uses, and the option types several kinds share (contact, impact, figures,
//! materials).
//!
//! A study file `studies/<name>.toml` maps one-to-one to `reports/<name>/`. It starts with two
//! comment lines (purpose; what a good result looks like) and names its `kind`. Each kind's
//! schema lives with its runner (`lifetime_study`, `dem::run`, `fem::run`, `calibrate::run`,
//! `uq::study`, `discrepancy::run`, `discrepancy::curves`); a runner that needs another study
//! (a calibration's model study, a curve study's calibration) reads it here with
//! [`StudyFile::read`] and [`StudyFile::parse`], so no study module depends on the dispatch in
//! `crate::study`. Every option has a documented default (the `Default` impls); validation
//! failures name the file, the dotted key and the rule.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

pub use crate::contact::ContactOptions;
use crate::contact::Elastic;
use crate::error::{Error, Result};

/// A study file as read from disk: its name (the file stem, which names the report), path and
/// text.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyFile {
    /// Name = file stem; the report goes to `reports/<name>/`.
    pub name: String,
    /// The file.
    pub path: PathBuf,
    /// Its text, verbatim.
    pub text: String,
}

impl StudyFile {
    /// Reads a study file (a missing path, a directory or non-UTF-8 bytes are named as such).
    pub fn read(path: &Path) -> Result<StudyFile> {
        let text = crate::io::read_input_text(path)?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .filter(|s| !s.is_empty() && !s.starts_with('.'))
            .ok_or_else(|| Error::config(path.display().to_string(), "file name", "a study file needs a name (its stem names the report)"))?;
        Ok(StudyFile { name, path: path.to_path_buf(), text })
    }

    /// The `kind` key (an error naming the file when it is missing).
    pub fn kind(&self, known: &[&str]) -> Result<String> {
        let head: toml::Table = parse_toml(&self.path, &self.text)?;
        head.get("kind")
            .and_then(|k| k.as_str())
            .map(str::to_string)
            .ok_or_else(|| Error::config(self.path.display().to_string(), "kind", format!("required: one of {}", known.join(", "))))
    }

    /// The study parsed as `T` (syntax, types and unknown keys checked; not validated).
    pub fn parse<T: DeserializeOwned>(&self) -> Result<T> {
        parse_toml(&self.path, &self.text)
    }

    /// Resolves a path of the study relative to the study file's directory (lexically:
    /// `studies/../datasets/x.csv` becomes `datasets/x.csv`).
    pub fn resolve(&self, p: &Path) -> PathBuf {
        resolve_relative(&self.path, p)
    }
}

/// Parses TOML into `T`; a syntax error, a wrong type or an unknown key becomes one
/// [`Error::Config`] naming the file, the line and the key.
pub fn parse_toml<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
        let snippet = e
            .span()
            .and_then(|s| text.get(s.clone()))
            .map(|s| s.lines().next().unwrap_or("").trim().to_string())
            .filter(|s| !s.is_empty());
        let key = match (line, snippet) {
            (Some(l), Some(s)) => format!("line {l} (`{s}`)"),
            (Some(l), None) => format!("line {l}"),
            _ => "document".into(),
        };
        Error::config(path.display().to_string(), key, e.message().trim().to_string())
    })
}

fn steel() -> Elastic {
    Elastic { youngs_modulus_pa: 210e9, poisson_ratio: 0.3 }
}


/// Impact options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImpactOptions {
    /// Wall (tube) material hit by the particles (default: steel).
    pub target: Elastic,
    /// Elastic energy fraction η ∈ (0, 1] (default 0.1, the deliverable's "trial and error").
    pub energy_fraction: f64,
    /// Largest velocity of the curves (m/s, default 20).
    pub velocity_max_m_s: f64,
    /// Number of velocities on the curves (default 201).
    pub velocity_points: usize,
    /// Impact counts N of the breakage curves (default 1, 100, 2100, 7300).
    pub impact_counts: Vec<f64>,
    /// High-velocity impacts per particle and year (default 730).
    pub impacts_per_year: f64,
    /// Operating horizons (years) of the summary table (default 1 and 10).
    pub years: Vec<f64>,
    /// Velocity of the force–time figure and the summary table (m/s, default 5, "maximum
    /// velocities on the order of 5 m/s" after the receiver).
    pub reference_velocity_m_s: f64,
}

impl Default for ImpactOptions {
    fn default() -> Self {
        ImpactOptions {
            target: steel(),
            energy_fraction: 0.1,
            velocity_max_m_s: 20.0,
            velocity_points: 201,
            impact_counts: vec![1.0, 100.0, 2100.0, 7300.0],
            impacts_per_year: crate::lifetime::IMPACTS_PER_YEAR,
            years: vec![1.0, 10.0],
            reference_velocity_m_s: 5.0,
        }
    }
}


/// Figure options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FigureOptions {
    /// Figure width (cm): 8.5 single column (default), 17 double column.
    pub width_cm: f64,
}

impl Default for FigureOptions {
    fn default() -> Self {
        FigureOptions { width_cm: 8.5 }
    }
}

impl FigureOptions {
    /// The width must lie in [4, 40] cm (`figures.width_cm` of study file `file`).
    pub fn validate(&self, file: &str) -> crate::error::Result<()> {
        if (4.0..=40.0).contains(&self.width_cm) {
            Ok(())
        } else {
            Err(crate::error::Error::config(file, "figures.width_cm", format!("must lie in [4, 40] cm, got {}", self.width_cm)))
        }
    }
}


/// One particle type.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Short key used in tables (`bl1630`): lowercase letters, digits, underscore.
    pub key: String,
    /// Label for figures (`BL 16/30`).
    pub label: String,
    /// Crush data: a file relative to the study file (`data = "crush.csv"`), or a table saying
    /// how to read it (`data = { file = "campaign.xlsx", sheet = "BL", material = "BL 16/30",
    /// columns = { … }, units = { … }, shape = { … } }`; [`crate::intake::Source`]).
    pub data: crate::intake::DataRef,
    /// Particle elastic constants.
    pub elastic: Elastic,
    /// Particle (apparent) density (kg/m³).
    pub density_kg_m3: f64,
    /// Diameter of the reference particle of the impact outputs (F_max, force history; m);
    /// default: median diameter of the crush data. The breakage does not depend on it.
    #[serde(default)]
    pub impact_diameter_m: Option<f64>,
    /// The particles predicted for (default: the crush data's particles, fresh).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub population: Option<crate::dist::PopulationSpec>,
    /// Recorded factors of the crush file (`factors = { batch = "categorical" }` or a list;
    /// [`crate::intake::factors`]): candidates of the naming loop and effects the strength model
    /// may carry (`levels(batch)`, `linear(rate)` …).
    #[serde(default, skip_serializing_if = "crate::intake::factors::Factors::is_empty")]
    pub factors: crate::intake::factors::Factors,
    /// What the prediction is for, per recorded factor the strength model carries
    /// ([`crate::strength::population::Prediction`]): `predict = { batch = "B2" }` (one level),
    /// `{ batch = { B1 = 0.6, B2 = 0.4 } }` (levels in proportion), `{ rate = 2.5 }` (a value) or
    /// `{ rate = { distribution = "uniform", min = 1, max = 4 } }`. Default: the crush data's
    /// particles with their own recorded values (a declared population needs every factor here).
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub predict: std::collections::BTreeMap<String, toml::Value>,
    /// The column naming each particle's failure origin (fractography: volume, surface, pore
    /// …; `none` for a particle that did not break). Read by the discrepancy study (each
    /// origin's law with the other origins' breaks censored (ASTM C1239), the test of one shared
    /// modulus, and the lifetime with every origin's law acting: [`crate::strength::origins`]) and
    /// by the main study (every origin's law acting in its strength models without effects on
    /// the material: [`crate::uq::setup`]). The lifetime study fits one law per material and
    /// refuses it ([`MaterialSpec::one_law`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<String>,
}

impl MaterialSpec {
    /// Reads the material's crush data as its `data` describes it (files relative to the study
    /// file `study`); `index` is its place among the study's `[[material]]`s (for messages).
    pub fn read_data(&self, study: &Path, index: usize) -> Result<crate::data::CrushData> {
        let file = study.display().to_string();
        let key = format!("material[{index}].data");
        self.data.validate(&file, &key)?;
        crate::data::read_crush_with_factors(&self.data.resolved(study), &self.factors, self.origin.as_deref(), &crate::intake::MapOrigin { file, key })
    }

    /// Refuses a declared failure-origin column in a study that fits one Weibull law per
    /// material (`kind`: the lifetime study), naming the key and where the origins are used:
    /// never read and passed over.
    pub fn one_law(&self, file: &str, index: usize, kind: &str) -> Result<()> {
        match &self.origin {
            Some(col) => Err(Error::config(
                file,
                format!("material[{index}].origin"),
                format!("the {kind} fits one Weibull law per material and does not read failure origins (`{col}`): each origin's law, the test of one shared modulus and the lifetime with every origin acting are the discrepancy study's (`kind = \"discrepancy\"` with this `[[material]]` and its `origin`), and the main study (`kind = \"uq\"`) carries every origin's law to the comparison; here remove `origin` and list the column in `material[{index}].data.ignore = [\"{col}\"]` (looked at and left out on purpose: the one law pools every origin)"),
            )),
            None => Ok(()),
        }
    }

    /// The reference particle of the impact outputs: `impact_diameter_m` or the median
    /// diameter of `data`.
    pub fn sphere(&self, data: &crate::data::CrushData) -> crate::contact::Sphere {
        let diameter = self.impact_diameter_m.unwrap_or_else(|| crate::stats::median(&data.diameters()));
        crate::contact::Sphere { diameter, density: self.density_kg_m3, elastic: self.elastic }
    }
}


pub use crate::intake::resolve_relative;

/// A study whose report another study reads: found by the study file's name under the same
/// reports root as the reading study's own report (`--reports-dir`), run first when its report
/// is missing or stale (`crate::runner`).
#[derive(Debug, Clone, PartialEq)]
pub struct Prerequisite {
    /// The reading study's key that names it (`law.calibrations[0].study`).
    pub key: String,
    /// The prerequisite study file (resolved).
    pub study: PathBuf,
    /// The files of its report that are read.
    pub files: Vec<&'static str>,
}

/// The report directory of study file `study` under `reports_root` (`<root>/<study stem>`).
pub fn report_dir(reports_root: &Path, study: &Path) -> PathBuf {
    reports_root.join(study.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default())
}

/// The file `name` of the report of study file `study` under `reports_root`
/// (`<root>/<study stem>/<name>`).
pub fn report_file(reports_root: &Path, study: &Path, name: &str) -> PathBuf {
    report_dir(reports_root, study).join(name)
}

/// A file read from another study's report or given directly: exactly one of `study` (a study
/// file, relative to the reading study) and `file` (relative to the reading study).
pub fn one_of(file: &str, key: &str, study: &Option<PathBuf>, given: &Option<PathBuf>, study_key: &str, file_key: &str) -> Result<()> {
    match (study, given) {
        (Some(_), None) | (None, Some(_)) => Ok(()),
        (Some(_), Some(_)) => Err(Error::config(file, key, format!("give `{study_key}` (a study whose report is read) or `{file_key}` (a file), not both"))),
        (None, None) => Err(Error::config(file, key, format!("needs `{study_key}` (a study whose report is read, run first when its report is missing or stale) or `{file_key}` (a file)"))),
    }
}


/// `Ok` if `ok`, else a configuration error naming `file`, `key` and `rule`.
pub(crate) fn check(file: &str, key: &str, ok: bool, rule: String) -> Result<()> {
    if ok { Ok(()) } else { Err(Error::config(file, key, rule)) }
}


/// Checks elastic constants, naming the study file and key.
pub fn elastic_checked(file: &str, key: &str, e: &Elastic) -> Result<()> {
    elastic(file, key, e)
}

pub(crate) fn elastic(file: &str, key: &str, e: &Elastic) -> Result<()> {
    e.validate(key).map_err(|err| match err {
        Error::Config { key, rule, .. } => Error::config(file, key, rule),
        other => other,
    })
}


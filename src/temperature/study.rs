//! The `kind = "temperature"` study file.
//!
//! ```toml
//! kind = "temperature"
//! seed = 20261125
//!
//! [phases]
//! file = "../datasets/phases_granulated_illustrative.csv"   # phase fractions against temperature
//! composition = "granulated (illustrative)"                 # what the table is of, for the report
//! onset_level = 0.01                 # amorphous fraction above which it counts as risen
//!
//! temperatures_c = [20, 1000, 20]    # from, to, step of the tables and figures against temperature
//! level = 0.9                        # probability of the central bands
//!
//! [law]                              # crate::thermal: calibrated states, glassy-ratio priors
//! calibrations = [{ temperature_c = 20, study = "calibrate_gen3_rt.toml" }, { temperature_c = 800, study = "…" }]
//! [law.glassy_ratio]
//! g = { distribution = "uniform", min = 0.01, max = 0.2 }
//!
//! [softening]                        # optional: the discrepancy workflow's temperature term
//! study = "discrepancy_curves.toml" # its report's curve_evidence.csv (or evidence = "<file>")
//!
//! [[validation]]                     # optional: held-out crush curves predicted from the laws
//! temperature_c = 950
//! study = "calibrate_gen3_950c.toml" # a crush calibration study of them (read, not run)
//! draws = 24                         # joint draws through the crush FE per source
//!
//! [lifetime]                         # optional: breakage against temperature (needs [law])
//! main = "gen4_vs_bl.toml"           # the main study (kind = "uq"): its primary strength model
//! samples = 4096
//! table1 = "../datasets/table1_particle_properties.csv"
//! softening = { bl1630 = "BauxLite BL 16/30", gen4 = "Granulated Gen 4" }   # Table 1 rows
//!
//! [figures]
//! width_cm = 8.5
//! ```


use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::schema::FigureOptions;
use crate::thermal::{LawOptions, PhasesOptions};

/// `[softening]`: the discrepancy workflow's estimate of the softening between the calibrated
/// temperatures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SofteningOptions {
    /// The `discrepancy_curves` study (relative to the study file) whose report's
    /// `curve_evidence.csv` is read (run first when missing or stale).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub study: Option<PathBuf>,
    /// Or a `curve_evidence.csv` given directly, relative to the study file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub evidence: Option<PathBuf>,
}

/// `[lifetime]`: the main study's breakage against temperature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LifetimeOptions {
    /// The main study (`kind = "uq"`), relative to this file: materials, impacts and its primary
    /// strength model.
    pub main: PathBuf,
    /// Monte Carlo samples per temperature (the same samples at every temperature).
    #[serde(default = "samples")]
    pub samples: usize,
    /// Temperatures (°C) whose breakage the summary tabulates (`lifetime_at.csv`).
    #[serde(default)]
    pub at: Vec<f64>,
    /// Table 1 (`datasets/table1_particle_properties.csv`), for the softening temperatures.
    pub table1: Option<PathBuf>,
    /// The Table 1 row of each material key whose softening temperature is marked.
    #[serde(default)]
    pub softening: BTreeMap<String, String>,
}

/// `[[validation]]`: crush data at a temperature the laws were not fitted to
/// ([`super::validate`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ValidationOptions {
    /// The temperature of the held-out data (°C).
    pub temperature_c: f64,
    /// A crush calibration study (`kind = "calibrate"`) of the held-out curves, relative to this
    /// file: its data reduction, crush model and model error (read, not run).
    pub study: PathBuf,
    /// Joint parameter draws run through the crush FE per source.
    #[serde(default = "validation_draws")]
    pub draws: usize,
}

fn validation_draws() -> usize {
    24
}

fn samples() -> usize {
    4096
}

fn level() -> f64 {
    0.9
}

/// A `kind = "temperature"` study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TemperatureStudy {
    /// `temperature`.
    pub kind: String,
    /// Seed (for the parts of the study that sample).
    pub seed: u64,
    /// The phase table.
    pub phases: PhasesOptions,
    /// From, to and step (°C) of the tables against temperature (default: the phase table's
    /// range up to 1000 °C in steps of 20 °C).
    pub temperatures_c: Option<[f64; 3]>,
    /// Probability of the central bands.
    #[serde(default = "level")]
    pub level: f64,
    /// The temperature laws of the calibrated parameters.
    pub law: Option<LawOptions>,
    /// The discrepancy workflow's softening estimate, reported next to the laws.
    pub softening: Option<SofteningOptions>,
    /// Breakage against temperature.
    pub lifetime: Option<LifetimeOptions>,
    /// Held-out crush data predicted from the laws.
    #[serde(default)]
    pub validation: Vec<ValidationOptions>,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
}

impl TemperatureStudy {
    /// Checks every option that needs no file.
    pub fn validate(&self, file: &str) -> Result<()> {
        let l = self.phases.onset_level;
        if !(l.is_finite() && l > 0.0 && l < 1.0) {
            return Err(Error::config(file, "phases.onset_level", format!("must lie in (0, 1), got {l}")));
        }
        if self.phases.composition.trim().is_empty() {
            return Err(Error::config(file, "phases.composition", "say what the table is of (a composition or particle)"));
        }
        if let Some([a, b, step]) = self.temperatures_c
            && !(a.is_finite() && b.is_finite() && a > -273.15 && a < b && step > 0.0 && (b - a) / step <= 500.0)
        {
            return Err(Error::config(file, "temperatures_c", format!("needs [from, to, step] with −273.15 < from < to and at most 500 steps, got [{a}, {b}, {step}]")));
        }
        if !(self.level > 0.0 && self.level < 1.0) {
            return Err(Error::config(file, "level", format!("must lie in (0, 1), got {}", self.level)));
        }
        if let Some(l) = &self.law {
            l.validate(file)?;
        }
        if let Some(so) = &self.softening {
            crate::schema::one_of(file, "softening", &so.study, &so.evidence, "study", "evidence")?;
        }
        if self.law.is_none() {
            for (present, key) in [(self.softening.is_some(), "softening"), (self.lifetime.is_some(), "lifetime"), (!self.validation.is_empty(), "validation")] {
                if present {
                    return Err(Error::config(file, key, "needs [law]: the temperature laws it is compared with or runs on"));
                }
            }
        }
        for (i, v) in self.validation.iter().enumerate() {
            if !(v.temperature_c.is_finite() && v.temperature_c > -273.15) {
                return Err(Error::config(file, format!("validation[{i}].temperature_c"), format!("must be a temperature above absolute zero (°C), got {}", v.temperature_c)));
            }
            if !(8..=1000).contains(&v.draws) {
                return Err(Error::config(file, format!("validation[{i}].draws"), format!("must lie in 8…1000, got {}", v.draws)));
            }
        }
        if let Some(l) = &self.lifetime {
            if !(256..=1 << 20).contains(&l.samples) {
                return Err(Error::config(file, "lifetime.samples", format!("must lie in 256…1048576, got {}", l.samples)));
            }
            if l.table1.is_none() && !l.softening.is_empty() {
                return Err(Error::config(file, "lifetime.softening", "names Table 1 rows: give lifetime.table1 too"));
            }
        }
        self.figures.validate(file)
    }

    /// The studies whose reports it reads (study file `file`): the calibrations of `[law]`, the
    /// curve-level discrepancy study of `[softening]`, and those of the main study of
    /// `[lifetime]` (which is read, not run). `[[validation]]` studies are read, not run.
    pub fn prerequisites(&self, file: &crate::schema::StudyFile) -> Result<Vec<crate::schema::Prerequisite>> {
        let resolve = |p: &std::path::Path| file.resolve(p);
        let mut out = self.law.as_ref().map(|l| crate::thermal::law_prerequisites(l, &resolve)).unwrap_or_default();
        if let Some(so) = &self.softening
            && let Some(st) = &so.study
        {
            out.push(crate::schema::Prerequisite { key: "softening.study".into(), study: resolve(st), files: vec!["curve_evidence.csv"] });
        }
        if let Some(l) = &self.lifetime {
            out.extend(crate::uq::study::UqStudy::prerequisites_of_file(&resolve(&l.main))?);
        }
        Ok(out)
    }

    /// The temperatures of the tables against temperature, within the phase table's range `lo`–`hi`.
    pub fn grid(&self, (lo, hi): (f64, f64)) -> Vec<f64> {
        let [a, b, step] = self.temperatures_c.unwrap_or([lo, hi.min(1000.0), 20.0]);
        let n = ((b - a) / step + 1e-9).floor() as usize;
        let mut t: Vec<f64> = (0..=n).map(|k| a + step * k as f64).collect();
        if t.last().is_some_and(|&x| x < b - 1e-9) {
            t.push(b);
        }
        t
    }
}

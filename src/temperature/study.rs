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
//! [figures]
//! width_cm = 8.5
//! ```

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::schema::FigureOptions;

/// `[phases]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhasesOptions {
    /// The phase-fraction table ([`crate::phases`]), relative to the study file.
    pub file: PathBuf,
    /// What the table is of, in words (for the report).
    pub composition: String,
    /// Amorphous fraction above which the amorphous phase counts as risen.
    #[serde(default = "onset_level")]
    pub onset_level: f64,
}

fn onset_level() -> f64 {
    0.01
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
        self.figures.validate(file)
    }
}

//! Generator of the synthetic "measured" tube-bank flow (`partlife datasets synth-dem`,
//! settings `datasets/synth_dem.toml`): a mean-velocity profile and the outlet mass flow, as a
//! cold-test rig with particle image velocimetry and a weighing cell would record them.
//!
//! The measured cold-test data of the deliverable's project are not public. The stand-in comes
//! from the DEM itself at the **true** contact coefficients (in the settings), but deliberately
//! not from the run the calibration repeats (no "inverse crime"):
//!
//! * a **different particle stream** (`particle_seed` instead of the rig study's seed: other
//!   diameters, other inlet positions), so the statistical noise of the DEM averages differs;
//! * a **longer measurement** (`duration`, after the same warm-up), as a rig averages longer
//!   than a calibration can afford;
//! * **measurement noise**: Gaussian with sd `velocity_sd` on every profile value and a relative
//!   sd `mass_flow_rel_sd` on the mass flow; the file's `sd` column states these sds.
//!
//! Randomness: one ChaCha8 stream seeded with `seed`, draws in output order; the DEM is
//! deterministic for its seed, so the file is reproducible for the same settings.

use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::dem::model::TubeBankModel;
use crate::error::{Error, Result};
use crate::io::write_atomic;
use crate::model::Simulator;

/// Generator settings (the file `datasets/synth_dem.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DemSynthSettings {
    /// Seed of the measurement noise.
    pub seed: u64,
    /// The rig: a `kind = "dem"` study (relative to the settings file).
    pub study: String,
    /// Seed of the rig's particle stream in the generating run.
    pub particle_seed: u64,
    /// Simulated time of the generating run (s), warm-up included.
    pub duration: f64,
    /// Heights of the profile samples (m).
    pub heights: Vec<f64>,
    /// Half-width of the band around each height (m).
    pub window: f64,
    /// Measurement noise sd of a profile value (m/s).
    pub velocity_sd: f64,
    /// Relative measurement noise sd of the mass flow (-).
    pub mass_flow_rel_sd: f64,
    /// Output file, relative to the output directory.
    pub file: String,
    /// The true contact coefficients (the generator's truth).
    pub truth: DemTruth,
}

/// True contact coefficients.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DemTruth {
    /// Particle–particle restitution (-).
    pub restitution_pp: f64,
    /// Particle–wall restitution (-).
    pub restitution_pw: f64,
    /// Particle–particle friction (-).
    pub friction_pp: f64,
    /// Particle–wall friction (-).
    pub friction_pw: f64,
}

/// One written observation.
#[derive(Debug, Clone, PartialEq)]
pub struct DemObservation {
    /// Output name (a [`TubeBankModel`] output).
    pub output: String,
    /// Unit.
    pub unit: String,
    /// Noise-free DEM value.
    pub exact: f64,
    /// Recorded (noisy) value.
    pub value: f64,
    /// Noise sd.
    pub sd: f64,
}

impl DemSynthSettings {
    /// Reads and validates the settings file; returns them with the rig model.
    pub fn load(path: &Path) -> Result<(Self, TubeBankModel)> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        let s: DemSynthSettings = crate::schema::parse_toml(path, &text)?;
        let model = s.model(path)?;
        Ok((s, model))
    }

    /// Validates the settings and builds the generating model.
    fn model(&self, path: &Path) -> Result<TubeBankModel> {
        let file = path.display().to_string();
        let bad = |k: &str, rule: String| Err(Error::config(&file, k, rule));
        if !(self.velocity_sd > 0.0 && self.velocity_sd.is_finite()) {
            return bad("velocity_sd", format!("must be a finite number > 0, got {}", self.velocity_sd));
        }
        if !(self.mass_flow_rel_sd > 0.0 && self.mass_flow_rel_sd < 1.0) {
            return bad("mass_flow_rel_sd", format!("must lie in (0, 1), got {}", self.mass_flow_rel_sd));
        }
        if self.heights.is_empty() || self.heights.iter().any(|h| !h.is_finite()) || !(self.window > 0.0) {
            return bad("heights", "at least one finite height and a window > 0 are required".into());
        }
        let t = self.truth;
        for (k, v) in [("truth.restitution_pp", t.restitution_pp), ("truth.restitution_pw", t.restitution_pw), ("truth.friction_pp", t.friction_pp), ("truth.friction_pw", t.friction_pw)] {
            if !(0.0..=1.0).contains(&v) {
                return bad(k, format!("must lie in [0, 1], got {v}"));
            }
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        let spath = dir.join(&self.study);
        if !spath.is_file() {
            return bad("study", format!("{} does not exist", spath.display()));
        }
        let sf = crate::schema::StudyFile::read(&spath)?;
        if sf.kind(&["dem"])? != "dem" {
            return bad("study", format!("{} is not a kind = \"dem\" study", spath.display()));
        }
        let ds: crate::dem::run::DemStudy = sf.parse()?;
        let mut setup = ds.setup(&spath.display().to_string())?;
        setup.seed = self.particle_seed;
        TubeBankModel::new(setup, self.duration, self.heights.clone(), self.window).map_err(|e| match e {
            Error::Config { key, rule, .. } => Error::config(&file, key, rule),
            other => other,
        })
    }
}

/// Runs the rig at the truth and draws the measurement noise: the profile values and the mass
/// flow, in that order.
pub fn generate(settings: &DemSynthSettings, model: &TubeBankModel) -> Result<Vec<DemObservation>> {
    let t = settings.truth;
    let y = model.simulate(&[t.restitution_pp, t.restitution_pw, t.friction_pp, t.friction_pw])?;
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let normal = Normal::new(0.0, 1.0).map_err(|e| Error::numerical("normal", e.to_string()))?;
    let n = settings.heights.len();
    let mut out = Vec::with_capacity(n + 1);
    for (k, spec) in model.outputs().iter().enumerate().take(n + 1) {
        let sd = if k < n { settings.velocity_sd } else { settings.mass_flow_rel_sd * y[k].abs() };
        out.push(DemObservation { output: spec.name.clone(), unit: spec.unit.clone(), exact: y[k], value: y[k] + sd * normal.sample(&mut rng), sd });
    }
    Ok(out)
}

/// Generates the file into `out_dir`; returns its path and the observations.
pub fn synthesize(settings: &DemSynthSettings, model: &TubeBankModel, out_dir: &Path) -> Result<(PathBuf, Vec<DemObservation>)> {
    let obs = generate(settings, model)?;
    let mut s = String::from("output,unit,value,sd\n");
    for o in &obs {
        s.push_str(&format!("{},{},{:.6e},{:.4e}\n", o.output, o.unit, o.value, o.sd));
    }
    let path = out_dir.join(&settings.file);
    write_atomic(&path, s.as_bytes())?;
    Ok((path, obs))
}

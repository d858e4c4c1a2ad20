//! Generator of the synthetic crush force–displacement curves
//! (`partlife datasets synth-curves`, settings `datasets/synth_curves.toml`).
//!
//! The measured curves of the deliverable's project (Figs. 6b, 6d, 7) are not public. This
//! generator makes stand-ins with the crush FE itself, but deliberately **not** the model the
//! calibration fits (no "inverse crime"):
//!
//! * a **finer mesh** (`refinement`, default 16 elements per contact radius; calibration
//!   studies run 8);
//! * **particle-to-particle scatter**: each particle has its own diameter (truncated normal) and
//!   its own tip roundness (uniform in `roundness`, an [`Shape::Asperity`] of that pole
//!   curvature), which the calibration model does not know (it crushes a sphere);
//! * optionally a **platen compliance** c (`compliance`, m/N): the recorded displacement is
//!   δ + c·F, the load train's deflection included (a hidden effect for the discrepancy
//!   workflow; 0 in the shipped files);
//! * **measurement noise** on the force: Gaussian with sd `force_sd_n + force_rel_sd·F`,
//!   sampled every `spacing` of total displacement, as a testing machine records.
//!
//! The true JH-2 set of every case is in the settings file. It is the generator's truth,
//! documented in `datasets/README.md`, and never read by fitting code: a calibration study
//! reads only the curve CSV.
//!
//! Randomness: one ChaCha8 stream per case (stream = case index), draws in a fixed order per
//! particle (diameter, roundness, then the force noise of each sample), so the files are
//! reproducible for the same settings; the FE runs are deterministic.

use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, Uniform};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::fem::material::MaterialParams;
use crate::fem::mesh::{MeshParams, Shape};
use crate::fem::{CrushSetup, CrushTest, FractureParams, PlatenParams, SolverParams};
use crate::io::write_atomic;
use crate::synth::TruncatedNormal;

/// Generator settings (the file `datasets/synth_curves.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveSynthSettings {
    /// Seed of all random draws.
    pub seed: u64,
    /// Mesh of the generator (finer than any calibration's).
    #[serde(default = "fine_mesh")]
    pub mesh: MeshParams,
    /// Platen loading (speed, friction, largest displacement).
    #[serde(default)]
    pub platen: PlatenParams,
    /// Sampling interval of the recorded curve in total displacement (m).
    pub spacing: f64,
    /// Absolute force noise sd (N).
    pub force_sd_n: f64,
    /// Relative force noise sd (-).
    pub force_rel_sd: f64,
    /// Cases, one file each.
    pub case: Vec<CurveCase>,
}

fn fine_mesh() -> MeshParams {
    MeshParams { refinement: 16.0, ..MeshParams::default() }
}

/// One synthetic case (material and temperature).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveCase {
    /// Output file name, relative to the output directory.
    pub file: String,
    /// Particles crushed.
    pub particles: usize,
    /// Diameter distribution (m).
    pub diameter: TruncatedNormal,
    /// Tip roundness range [low, high] ⊂ (0, 1] (uniform).
    pub roundness: [f64; 2],
    /// The true material (the generator's truth).
    pub truth: MaterialParams,
    /// Hidden platen (machine) compliance c (m/N, default 0): the recorded displacement is
    /// the particle's δ + c·F, as a testing machine whose load train yields records it.
    #[serde(default)]
    pub compliance: f64,
}

/// Columns of a curve file.
pub const CURVE_COLUMNS: [&str; 4] = ["particle", "diameter_m", "displacement_m", "force_n"];

/// One generated particle: its hidden draws and its recorded curve.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthCurve {
    /// Particle number (1-based).
    pub particle: usize,
    /// Diameter (m).
    pub diameter: f64,
    /// Tip roundness (hidden: not written).
    pub roundness: f64,
    /// Recorded (displacement m, force N).
    pub samples: Vec<(f64, f64)>,
    /// Noise-free FE peak force (N) and fracture displacement (m), for the summary only.
    pub peak: (f64, Option<f64>),
}

impl CurveSynthSettings {
    /// Reads and validates the settings file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        let s: CurveSynthSettings = crate::schema::parse_toml(path, &text)?;
        s.validate(&path.display().to_string())?;
        Ok(s)
    }

    /// Checks every setting.
    pub fn validate(&self, file: &str) -> Result<()> {
        let bad = |k: String, rule: String| Err(Error::config(file, k, rule));
        if !(self.spacing > 0.0 && self.spacing < self.platen.max_displacement) {
            return bad("spacing".into(), format!("must lie in (0, platen.max_displacement), got {}", self.spacing));
        }
        if !(self.force_sd_n >= 0.0 && self.force_rel_sd >= 0.0 && self.force_sd_n.is_finite() && self.force_rel_sd.is_finite()) {
            return bad("force_sd_n".into(), "noise sds must be finite and ≥ 0".into());
        }
        if self.case.is_empty() {
            return bad("case".into(), "at least one [[case]] is required".into());
        }
        for (i, c) in self.case.iter().enumerate() {
            let k = |s: &str| format!("case[{i}].{s}");
            if c.particles < 3 {
                return bad(k("particles"), format!("must be ≥ 3, got {}", c.particles));
            }
            let d = c.diameter;
            if !(d.min > 0.0 && d.min < d.max && d.sd > 0.0 && d.mean.is_finite()) {
                return bad(k("diameter"), format!("needs 0 < min < max and sd > 0 (got {d:?})"));
            }
            if !(c.compliance >= 0.0 && c.compliance < 1e-5) {
                return bad(k("compliance"), format!("must lie in [0, 1e-5) m/N, got {}", c.compliance));
            }
            let [lo, hi] = c.roundness;
            if !(lo > 0.0 && lo <= hi && hi <= 1.0) {
                return bad(k("roundness"), format!("needs 0 < low ≤ high ≤ 1, got [{lo}, {hi}]"));
            }
            self.setup(c, d.mean, hi).validate(file).map_err(|e| match e {
                Error::Config { key, rule, .. } => Error::config(file, format!("case[{i}]: {key}"), rule),
                other => other,
            })?;
        }
        Ok(())
    }

    fn setup(&self, c: &CurveCase, diameter: f64, roundness: f64) -> CrushSetup {
        let shape = if roundness >= 1.0 { Shape::Sphere } else { Shape::Asperity { roundness, width: 0.35 } };
        CrushSetup {
            diameter,
            shape,
            material: c.truth.clone(),
            mesh: self.mesh,
            platen: self.platen,
            solver: SolverParams::default(),
            fracture: FractureParams::default(),
            fields_at: vec![],
            kinematics: Default::default(),
            outline: None,
        }
    }
}

/// Draws the particles of case `index` and crushes each with the fine-mesh FE (in parallel).
pub fn generate(settings: &CurveSynthSettings, index: usize, progress: &(dyn Fn() + Sync)) -> Result<Vec<SynthCurve>> {
    generate_first(settings, index, settings.case[index].particles, progress)
}

/// The first `first` particles of case `index`, exactly as [`generate`] makes them: every
/// particle's diameter and roundness are drawn first, then the force noise particle by
/// particle, so the first particles' curves do not depend on the FE runs of the later ones.
pub fn generate_first(settings: &CurveSynthSettings, index: usize, first: usize, progress: &(dyn Fn() + Sync)) -> Result<Vec<SynthCurve>> {
    let c = &settings.case[index];
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    rng.set_stream(index as u64);
    let normal = Normal::new(0.0, 1.0).map_err(|e| Error::numerical("normal", e.to_string()))?;
    let uniform = Uniform::new_inclusive(c.roundness[0], c.roundness[1]).map_err(|e| Error::numerical("uniform", e.to_string()))?;
    let mut draws = Vec::with_capacity(c.particles);
    for _ in 0..c.particles {
        let d = loop {
            let v = c.diameter.mean + c.diameter.sd * normal.sample(&mut rng);
            if v >= c.diameter.min && v <= c.diameter.max {
                break v;
            }
        };
        // Recorded diameters are read to 1 µm.
        let d = (d * 1e6).round() * 1e-6;
        draws.push((d, uniform.sample(&mut rng)));
    }
    draws.truncate(first);
    let runs: Vec<Result<crate::fem::CrushResult>> = draws
        .par_iter()
        .map(|&(d, rho)| {
            let mut t = CrushTest::new(settings.setup(c, d, rho), "<synth-curves>")?;
            let r = t.run(None);
            progress();
            r
        })
        .collect();
    let mut out = Vec::with_capacity(draws.len());
    for (k, ((d, rho), run)) in draws.into_iter().zip(runs).enumerate() {
        let mut r = run?;
        // Machine compliance: the recorded displacement is δ + c·F, kept non-decreasing (after
        // fracture the load train springs back while the crosshead goes on).
        if c.compliance > 0.0 {
            let mut reach = 0.0_f64;
            for s in &mut r.curve {
                reach = reach.max(s.displacement + c.compliance * s.force);
                s.displacement = reach;
            }
        }
        let end = r.curve.last().map(|s| s.displacement).unwrap_or(0.0);
        let n = (end / settings.spacing).floor() as usize;
        let samples = (0..=n)
            .map(|i| {
                let x = i as f64 * settings.spacing;
                let f = crate::fem::model::force_at(&r.curve, x);
                let sd = settings.force_sd_n + settings.force_rel_sd * f.abs();
                let noisy = if i == 0 { 0.0 } else { f + sd * normal.sample(&mut rng) };
                (x, noisy)
            })
            .collect();
        out.push(SynthCurve { particle: k + 1, diameter: d, roundness: rho, samples, peak: (r.peak_force, r.fracture_displacement) });
    }
    Ok(out)
}

/// Writes a curve file (`particle, diameter_m, displacement_m, force_n`).
pub fn write_curves(path: &Path, curves: &[SynthCurve]) -> Result<()> {
    let mut s = CURVE_COLUMNS.join(",");
    s.push('\n');
    for c in curves {
        for &(x, f) in &c.samples {
            s.push_str(&format!("{},{:.6e},{:.4e},{:.4}\n", c.particle, c.diameter, x, f));
        }
    }
    write_atomic(path, s.as_bytes())
}

/// What one generated file holds.
#[derive(Debug, Clone, PartialEq)]
pub struct CurveSummary {
    /// File written.
    pub path: PathBuf,
    /// Particles.
    pub particles: usize,
    /// Per particle: diameter (m), hidden roundness, FE peak force (N), fracture displacement (m).
    pub rows: Vec<(f64, f64, f64, Option<f64>)>,
}

/// Generates every case into `out_dir`.
pub fn synthesize(settings: &CurveSynthSettings, out_dir: &Path, progress: &(dyn Fn() + Sync)) -> Result<Vec<CurveSummary>> {
    let mut out = Vec::new();
    for (i, c) in settings.case.iter().enumerate() {
        let curves = generate(settings, i, progress)?;
        let path = out_dir.join(&c.file);
        write_curves(&path, &curves)?;
        out.push(CurveSummary {
            path,
            particles: curves.len(),
            rows: curves.iter().map(|c| (c.diameter, c.roundness, c.peak.0, c.peak.1)).collect(),
        });
    }
    Ok(out)
}

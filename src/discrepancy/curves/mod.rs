//! The force–displacement level of the discrepancy workflow (issue 7, item 4): where does the
//! **calibrated crush FE** disagree with measured crush curves, which physical term is missing,
//! and does adding it make the disagreement go away?
//!
//! ```toml
//! kind = "discrepancy_curves"
//! seed = 20261122
//! calibration = "calibrate_gen3_rt.toml"   # a crush calibration; its report must exist
//! candidates = ["compliance", "temperature", "curvature"]
//! [[data]]                                 # one or more curve files (the first at the
//! file = "../datasets/crush_curves_gen3_rt.csv"   # calibration's temperature)
//! temperature_c = 20
//! [koh]        # walkers, steps, burn_in (Kennedy–O'Hagan sampler)
//! [curvature]  # roundness = [...], width: the FE table of the curvature candidate
//! ```
//!
//! # The model and its emulator
//!
//! η_k(θ) is the force of the calibration's crush FE at its grid displacements x_k (normalised
//! to its reference diameter D₀, see [`crate::calibrate::data`]), θ its fitted JH-2 constants.
//! The emulator is the calibration's own: the GP fitted to the FE runs in
//! `reports/<calibration>/runs.csv` (training rows) — no FE run is repeated. The measured
//! curves are normalised to D₀ the same way and averaged per file at the grid points below
//! every particle's fracture: y = mean force, σ = particle scatter/√n (floored at
//! `sigma_floor`·mean) with the emulator's predictive variance at the calibrated θ added.
//!
//! # Diagnosis
//!
//! * **curve residuals**: every particle's standardised residual (F − η(θ̂))/σ_particle at every
//!   grid point, θ̂ the least-squares fit without discrepancy; the trend of the mean residual
//!   along the curve (Spearman ρ against displacement, permutation p-value) — the
//!   "displacement along a curve" covariate;
//! * **δ(x)**: the Kennedy–O'Hagan discrepancy ([`super::koh`]), a GP over displacement (and
//!   temperature when the files differ in it) fitted jointly with θ; where |δ̂| exceeds twice
//!   the uncertainty σ of the mean curve is where the model disagrees, and the gap measure is
//!   **RMS(δ̂_i/σ_i)**, δ's posterior mean in units of the measurement uncertainty (≲ 1 when
//!   nothing is missing).
//!
//! # What is known about θ
//!
//! By default (`theta = "calibration"`) θ's prior is the calibration's posterior (a Gaussian
//! fitted to its draws in `chains.csv`): the curves are compared with the **calibrated** model,
//! and a term the constants could mimic on these curves alone (a compliant machine looks like a
//! softer, weaker particle) still shows against what the calibration established. With
//! `theta = "bounds"` θ is uniform in the calibration's bounds (recalibrated on these data), and
//! only what no θ can mimic shows. The prior enters the BIC as data.
//!
//! # Candidate terms (post-processing of η, or an FE table; no new emulator)
//!
//! | name | equation | parameter |
//! |---|---|---|
//! | `compliance` | the recorded displacement includes the load train: x = δ(F) + c·F, so F(x) solves F = η(x − c·F) (η between grid points by linear interpolation of F^(2/3), exact for Hertz) | c (µm/N at D₀) |
//! | `temperature` | stiffness and strength soften together: F(x, T) = r^((T − T₀)/100 °C) η(x), T₀ the first file's temperature | force ratio r per 100 °C |
//! | `curvature` | the contact tip has pole curvature ratio ρ (an asperity, [`crate::fem::mesh::Shape::Asperity`]): F = η(x)·Φ_k(ρ), Φ the ratio of asperity to sphere FE forces at the calibrated θ, tabulated at `curvature.roundness` and interpolated linearly | ρ (–) |
//!
//! A candidate is skipped with a reason when the data cannot show it (temperature with one
//! temperature). Each round fits the current model and every remaining candidate with
//! [`super::koh::fit`] and names the one with the lowest BIC if it beats the current model by
//! more than 6 ([`super::koh::BIC_STRONG`]); the named term is added and the loop repeats, at
//! most `max_effects` times. The compliance term acts on the whole curve after the
//! multiplicative terms (it is the machine, not the particle).

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::koh::KohOptions;
use crate::calibrate::data::read_curves;
use crate::error::{Error, Result};
use crate::io::InputFile;
use crate::model::Simulator;
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::schema::{FigureOptions, StudyFile, check};

mod calibration;
mod model;
mod report;
pub use calibration::*;
pub use model::*;
use report::*;

/// The FE-level candidate terms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CurveCandidate {
    /// Platen (machine) compliance.
    Compliance,
    /// Temperature softening of stiffness and strength.
    Temperature,
    /// Contact-tip curvature (roundness of the pole).
    Curvature,
}

impl CurveCandidate {
    /// Every candidate.
    pub const ALL: [CurveCandidate; 3] = [CurveCandidate::Compliance, CurveCandidate::Temperature, CurveCandidate::Curvature];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            CurveCandidate::Compliance => "compliance",
            CurveCandidate::Temperature => "temperature",
            CurveCandidate::Curvature => "curvature",
        }
    }

    /// The parameter the term adds: (name with unit).
    pub fn parameter(self) -> &'static str {
        match self {
            CurveCandidate::Compliance => "platen compliance c (µm/N)",
            CurveCandidate::Temperature => "force ratio per 100 °C (–)",
            CurveCandidate::Curvature => "pole curvature ratio ρ (–)",
        }
    }

    /// The equation, for reports.
    pub fn equation(self) -> &'static str {
        match self {
            CurveCandidate::Compliance => "F solves F = η(x − c·F)",
            CurveCandidate::Temperature => "F = r^((T − T₀)/100 °C) · η(x)",
            CurveCandidate::Curvature => "F = Φ(x; ρ) · η(x), Φ from asperity/sphere FE runs",
        }
    }
}

/// What the discrepancy fits know about the calibrated constants θ.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThetaPrior {
    /// The calibration's posterior (Gaussian approximation of its draws): the data are compared
    /// with the *calibrated* model, so a term the constants could mimic still shows.
    #[default]
    Calibration,
    /// Uniform within the calibration's bounds: θ is recalibrated on these data, and only what
    /// no θ can mimic shows.
    Bounds,
}

fn all_candidates() -> Vec<CurveCandidate> {
    CurveCandidate::ALL.to_vec()
}

/// One measured curve file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveFile {
    /// Crush-curve CSV (`particle, diameter_m, displacement_m, force_n`), relative to the study.
    pub file: String,
    /// Test temperature (°C).
    pub temperature_c: f64,
    /// Label in tables and figures (default: the file stem).
    #[serde(default)]
    pub label: Option<String>,
    /// The file's header for a field its header does not name, as a calibration's `[data]`
    /// takes it ([`crate::calibrate::data::read_curves`]).
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub columns: std::collections::BTreeMap<String, String>,
    /// A field's unit where its header states none.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub units: std::collections::BTreeMap<String, String>,
    /// The sheet of a workbook: its name, or its position from 1 (default: the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sheet: Option<crate::intake::SheetRef>,
    /// The line (text) or sheet row (workbook) of the header, from 1 (default: the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub header_row: Option<usize>,
}

impl CurveFile {
    /// How to read the file, found at `path` (resolved against the study), as every curve
    /// reader takes it.
    pub fn source(&self, path: &Path) -> crate::intake::Source {
        crate::intake::Source { sheet: self.sheet.clone(), header_row: self.header_row, columns: self.columns.clone(), units: self.units.clone(), temperature_c: Some(self.temperature_c), ..crate::intake::Source::file(path) }
    }
}

/// The FE table of the curvature candidate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CurvatureTable {
    /// Pole curvature ratios run (each in (0, 1)); the sphere (1) is added.
    pub roundness: Vec<f64>,
    /// Angular half-width of the asperity (rad), as `fem::Shape::Asperity`.
    pub width: f64,
}

impl Default for CurvatureTable {
    fn default() -> Self {
        CurvatureTable { roundness: vec![0.4, 0.55, 0.7, 0.85], width: 0.35 }
    }
}

/// A study of kind `discrepancy_curves`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveStudy {
    /// `discrepancy_curves`.
    pub kind: String,
    /// Seed of the samplers.
    pub seed: u64,
    /// The crush calibration study (relative to this file) whose report holds the emulator's
    /// training runs and the posterior.
    pub calibration: String,
    /// Measured curve files (the first at the calibration's temperature).
    pub data: Vec<CurveFile>,
    /// Prior of the calibrated constants in the discrepancy fits (default: the calibration's
    /// posterior).
    #[serde(default)]
    pub theta: ThetaPrior,
    /// Candidates tried (default: all).
    #[serde(default = "all_candidates")]
    pub candidates: Vec<CurveCandidate>,
    /// Most terms named.
    #[serde(default = "three")]
    pub max_effects: usize,
    /// Floor of the particle scatter, relative to the mean force.
    #[serde(default = "floor")]
    pub sigma_floor: f64,
    /// Sampler of the Kennedy–O'Hagan fits (its seed is the study's).
    #[serde(default)]
    pub koh: KohOptions,
    /// Curvature table.
    #[serde(default)]
    pub curvature: CurvatureTable,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
}

fn three() -> usize {
    3
}

fn floor() -> f64 {
    0.02
}

impl CurveStudy {
    /// Reads its curve files (each must exist and parse), in order: what a run checks first,
    /// before its calibration's report is read or run.
    pub fn read_data(&self, loaded: &StudyFile) -> Result<(Vec<std::path::PathBuf>, Vec<Vec<crate::calibrate::data::Curve>>)> {
        let file = loaded.path.display().to_string();
        let (mut paths, mut raw) = (Vec::new(), Vec::new());
        for (i, d) in self.data.iter().enumerate() {
            let path = loaded.resolve(Path::new(&d.file));
            if !path.is_file() {
                return Err(Error::config(&file, format!("data[{i}].file"), format!("{} does not exist", path.display())));
            }
            let curves = read_curves(&d.source(&path), &crate::intake::MapOrigin { file: file.clone(), key: format!("data[{i}]") })?.0;
            // A temperature column that says otherwise than the study: each file is one
            // temperature of the model.
            if let Some(c) = curves.iter().find(|c| (c.temperature_c - d.temperature_c).abs() > crate::intake::observed::TEMPERATURE_TOLERANCE_C) {
                return Err(Error::data_file(&path, format!("particle {}", c.particle), format!("its temperature column says {} °C, the study's data[{i}].temperature_c {} °C: each curve file is one test temperature; correct the one that is wrong, or split the file", c.temperature_c, d.temperature_c)));
            }
            raw.push(curves);
            paths.push(path);
        }
        Ok((paths, raw))
    }

    /// The studies whose reports it reads: its crush calibration (emulator runs, posterior,
    /// grid).
    pub fn prerequisites(&self, file: &StudyFile) -> Vec<crate::schema::Prerequisite> {
        vec![crate::schema::Prerequisite { key: "calibration".into(), study: file.resolve(Path::new(&self.calibration)), files: vec!["runs.csv", "parameters.csv", "grid.csv"] }]
    }

    /// Checks every setting that does not need a file.
    pub fn validate(&self, file: &str) -> Result<()> {
        check(file, "data", !self.data.is_empty(), "at least one [[data]] curve file is required".into())?;
        for (i, d) in self.data.iter().enumerate() {
            check(file, &format!("data[{i}].temperature_c"), d.temperature_c.is_finite() && d.temperature_c > -273.15 && d.temperature_c < 2000.0, format!("must be a temperature in °C, got {}", d.temperature_c))?;
        }
        check(file, "candidates", !self.candidates.is_empty(), "at least one candidate is required".into())?;
        check(file, "max_effects", (1..=3).contains(&self.max_effects), format!("must lie in [1, 3], got {}", self.max_effects))?;
        check(file, "sigma_floor", self.sigma_floor >= 0.0 && self.sigma_floor < 0.5, format!("must lie in [0, 0.5), got {}", self.sigma_floor))?;
        check(file, "koh.steps", self.koh.steps >= 200 && self.koh.burn_in >= 100 && self.koh.walkers >= 8 && self.koh.delta_draws >= 1, "needs steps ≥ 200, burn_in ≥ 100, walkers ≥ 8, delta_draws ≥ 1".into())?;
        check(file, "curvature.roundness", !self.curvature.roundness.is_empty() && self.curvature.roundness.iter().all(|r| *r > 0.05 && *r < 1.0), "needs values in (0.05, 1)".into())?;
        check(file, "curvature.width", self.curvature.width > 0.05 && self.curvature.width < 1.0, format!("must lie in (0.05, 1) rad, got {}", self.curvature.width))?;
        check(file, "figures.width_cm", self.figures.width_cm >= 4.0 && self.figures.width_cm <= 40.0, format!("must lie in [4, 40], got {}", self.figures.width_cm))
    }
}

/// Runs a `discrepancy_curves` study.
pub fn run_curves(loaded: &StudyFile, s: &CurveStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let file = loaded.path.display().to_string();
    // The curve files first (cheap), then the calibration and its emulator.
    let (paths, raw) = s.read_data(loaded)?;
    let cal = load_calibration(&file, "calibration", &loaded.resolve(Path::new(&s.calibration)), &opts.reports_root)?;
    // The calibrated model is the first file's temperature's: the temperature term's reference.
    if (cal.temperature_c - s.data[0].temperature_c).abs() > crate::intake::observed::TEMPERATURE_TOLERANCE_C {
        return Err(Error::config(
            &file,
            "data[0].temperature_c",
            format!("the temperature term is referred to the first curve file's {} °C, but the calibration {} fitted curves measured at {} °C: list first the curve file at the calibration's temperature", s.data[0].temperature_c, s.calibration, cal.temperature_c),
        ));
    }
    let groups: Vec<Group> = s
        .data
        .iter()
        .zip(&paths)
        .zip(&raw)
        .map(|((d, path), curves)| Group {
            label: d.label.clone().unwrap_or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()),
            temperature: d.temperature_c,
            curves: curves.iter().map(|c| c.normalised(cal.reference_diameter)).collect(),
        })
        .collect();
    let mut points = reduce(&paths, &groups, &cal.grid, cal.fracture, s.sigma_floor)?;
    // The emulator's own uncertainty at the calibrated θ joins the measurement's.
    let emu_var: Vec<f64> = cal.emulator.predict(&cal.theta).iter().map(|p| p.1).collect();
    for p in &mut points {
        p.sigma = (p.sigma.powi(2) + emu_var[p.k]).sqrt();
    }
    let want_table = s.candidates.contains(&CurveCandidate::Curvature);
    let steps = 2 + s.candidates.len() * s.max_effects + if want_table { s.curvature.roundness.len() + 1 } else { 0 };
    let pb = progress_bar(steps as u64, opts.progress, crate::runkit::PROGRESS_COUNT);
    let table = if want_table {
        pb.set_message("curvature table: FE runs at the calibrated constants");
        Some(curvature_table(&cal, &s.curvature, &|| pb.inc(1))?)
    } else {
        None
    };
    let names: Vec<String> = cal.model.space().params().iter().map(|p| p.name.clone()).collect();
    let bounds: Vec<(f64, f64)> = cal.model.space().params().iter().map(|p| (p.lower, p.upper)).collect();
    let base = |t: &[f64]| cal.emulator.means(t, cal.grid.len());
    let inputs_loop = CurveInputs {
        model: CurveModel { base: &base, grid: &cal.grid, points: &points, temperatures: groups.iter().map(|g| g.temperature).collect(), t_ref: s.data[0].temperature_c, table: table.as_ref(), base_dim: names.len() },
        names,
        bounds,
        candidates: s.candidates.clone(),
        max_effects: s.max_effects,
        koh: KohOptions { seed: s.seed, ..s.koh.clone() },
        prior: match s.theta {
            ThetaPrior::Calibration => Some(cal.posterior.clone()),
            ThetaPrior::Bounds => None,
        },
    };
    let outcome = inputs_loop.analyse(&|m: &str| {
        pb.set_message(m.to_string());
        pb.inc(1);
    })?;
    let base_ls = inputs_loop.model.eval(&[], &outcome.theta_ls);
    let trend = trend_along_curve(&points, &base_ls, groups.len(), s.seed)?;

    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;
    write_curve_tables(&mut dir, &groups, &points, &cal, &outcome, &base_ls, table.as_ref())?;
    let where_ = disagreement(&outcome.stages[0].fit, &points, groups.len());
    let verdict = curve_verdict(loaded, s, &groups, &outcome, &where_, &trend);
    let json = serde_json::to_string_pretty(&verdict).map_err(|e| Error::numerical("verdict.json", e.to_string()))?;
    dir.write_bytes("verdict.json", json.as_bytes())?;
    dir.write_bytes("summary.md", curve_summary(&s.calibration, &groups, &outcome, &where_, &trend).as_bytes())?;
    pb.set_message("figures");
    let mut failures = Vec::new();
    let rendered = crate::report::discrepancy::render_curves(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    let mut inputs = vec![InputFile::hash(&loaded.path)?];
    for p in cal.inputs.iter().chain(&paths) {
        inputs.push(InputFile::hash(p)?);
    }
    let mut evaluations = BTreeMap::new();
    evaluations.insert("koh_fits".to_string(), (outcome.evidence.iter().filter(|e| e.fit.is_some()).count() + 1) as u64);
    evaluations.insert("fe_runs".to_string(), table.as_ref().map_or(0, |t| t.roundness.len() as u64));
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let headline = curve_headline(&outcome);
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings: Vec::new() })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines: vec![headline] })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast sibling of the slow `curve_loop_names_curvature` test (tests/discrepancy_curves.rs,
    /// which runs the fine-mesh FE): the same loop on a Hertzian base model F = θ·10⁹·x^1.5 with a
    /// known ratio table Φ(ρ, x_k) = 1 − (1 − ρ)e^(−k/4) (an asperity softens the start of the
    /// curve), data made with ρ = 0.6. The loop must name curvature first, put ρ = 0.6 in its
    /// 90 % range, skip temperature (one temperature) and shrink the gap.
    #[test]
    fn the_loop_names_a_hidden_curvature_and_recovers_it() {
        let grid: Vec<f64> = (1..=14).map(|i| i as f64 * 1.5e-6).collect();
        let phi = |rho: f64| -> Vec<f64> { (0..grid.len()).map(|k| 1.0 - (1.0 - rho) * (-(k as f64) / 4.0).exp()).collect() };
        let table = RatioTable { roundness: vec![0.4, 0.55, 0.7, 0.85, 1.0], ratio: [0.4, 0.55, 0.7, 0.85, 1.0].iter().map(|&r| phi(r)).collect() };
        let base = |t: &[f64]| -> Vec<f64> { grid.iter().map(|x| t[0] * 1e9 * x.powf(1.5)).collect() };
        let truth: Vec<f64> = base(&[1.0]).iter().zip(phi(0.6)).map(|(f, p)| f * p).collect();
        let points: Vec<Point> = (0..grid.len())
            .map(|k| Point { group: 0, k, x: grid[k], temperature: 20.0, mean: truth[k], scatter: 0.02 + 0.005 * truth[k], particles: 1, sigma: 0.02 + 0.005 * truth[k] })
            .collect();
        let inputs = CurveInputs {
            model: CurveModel { base: &base, grid: &grid, points: &points, temperatures: vec![20.0], t_ref: 20.0, table: Some(&table), base_dim: 1 },
            names: vec!["stiffness".into()],
            bounds: vec![(0.5, 2.0)],
            candidates: vec![CurveCandidate::Compliance, CurveCandidate::Temperature, CurveCandidate::Curvature],
            max_effects: 2,
            koh: KohOptions { walkers: 16, steps: 1500, burn_in: 1000, delta_draws: 100, seed: 7 },
            prior: None,
        };
        let o = inputs.analyse(&|_| {}).unwrap();
        assert_eq!(o.named.first(), Some(&CurveCandidate::Curvature), "named {:?}", o.named);
        let stage = &o.stages[1];
        let (lo, hi) = stage.fit.theta_90[1];
        assert!(lo <= 0.6 && 0.6 <= hi && hi - lo < 0.2, "ρ range [{lo}, {hi}]");
        let skipped = o.evidence.iter().find(|e| e.candidate == CurveCandidate::Temperature).and_then(|e| e.skipped.clone()).unwrap_or_default();
        assert!(skipped.contains("one temperature"), "{skipped}");
        assert!(stage.gap < 0.5 * o.stages[0].gap, "gap {} → {}", o.stages[0].gap, stage.gap);
    }
}

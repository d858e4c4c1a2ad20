//! The link to the crush calibration: its study, report, emulator and posterior
//! ([`load_calibration`]), and the FE table of the curvature term ([`curvature_table`], run
//! through `fem::model::CrushModel`).

use std::path::{Path, PathBuf};
use crate::calibrate::emulator::Emulator;
use crate::calibrate::run::Built;
use crate::error::{Error, Result};
use crate::fem::mesh::Shape;
use crate::fem::model::CrushModel;
use crate::fracture::FractureParams;
use crate::model::Simulator;
use crate::report::Table;
use crate::schema::StudyFile;
use super::CurvatureTable;
use super::model::RatioTable;

/// The calibration the loop starts from, read from its study and report.
pub struct Calibrated {
    /// The crush model (grid, bounds, FE set-up).
    pub model: CrushModel,
    /// Reference diameter D₀ (m).
    pub reference_diameter: f64,
    /// Grid displacements (m).
    pub grid: Vec<f64>,
    /// Fracture detection of the calibration.
    pub fracture: FractureParams,
    /// Emulator fitted to the report's training runs.
    pub emulator: Emulator,
    /// Posterior median θ.
    pub theta: Vec<f64>,
    /// Gaussian approximation of the posterior: mean and inverse covariance (from the chains).
    pub posterior: (Vec<f64>, nalgebra::DMatrix<f64>),
    /// Files read (study, data, runs, parameters).
    pub inputs: Vec<PathBuf>,
    /// The test temperature of the calibration's curves (°C).
    pub temperature_c: f64,
}

/// Loads a crush calibration and its report; a missing or stale report is an error naming it.
pub fn load_calibration(study_file: &str, key: &str, path: &Path, reports_root: &Path) -> Result<Calibrated> {
    if !path.is_file() {
        return Err(Error::config(study_file, key, format!("{} does not exist", path.display())));
    }
    let loaded = StudyFile::read(path)?;
    if loaded.kind(&["calibrate"])? != "calibrate" {
        return Err(Error::config(study_file, key, format!("{} is not a kind = \"calibrate\" study", path.display())));
    }
    let cs: crate::calibrate::run::CalibrateStudy = loaded.parse()?;
    let prep = cs.prepare(&loaded.path, &|p: &str| loaded.resolve(Path::new(p)))?;
    let Built::Crush(model, red) = prep.built else {
        return Err(Error::config(study_file, key, format!("{} calibrates the DEM: the curve workflow needs a crush calibration", path.display())));
    };
    let fracture = match &cs.model {
        crate::calibrate::run::ModelSpec::Crush { crush } => crush.fracture,
        _ => FractureParams::default(),
    };
    let dir = reports_root.join(&loaded.name);
    let runs_path = dir.join("runs.csv");
    let params_path = dir.join("parameters.csv");
    let grid_path = dir.join("grid.csv");
    for p in [&runs_path, &params_path, &grid_path] {
        if !p.is_file() {
            return Err(Error::config(study_file, key, format!("{} does not exist: run `partlife run {}` first", p.display(), path.display())));
        }
    }
    let grid_report = Table::load_file(&grid_path)?.f("grid_displacement_m")?;
    let same = grid_report.len() == red.grid.len() && grid_report.iter().zip(&red.grid).all(|(a, b)| (a - b).abs() <= 1e-9 * b.abs());
    if !same {
        return Err(Error::data_file(&grid_path, "grid_displacement_m", format!("differs from the grid {} makes of its data now: the report is stale, rerun it", path.display())));
    }
    let runs = Table::load_file(&runs_path)?;
    let source = runs.s("source")?;
    let rows: Vec<usize> = (0..source.len()).filter(|&i| source[i] == "training").collect();
    let names: Vec<String> = model.space().params().iter().map(|p| p.name.clone()).collect();
    let cols: Vec<Vec<f64>> = names.iter().map(|n| runs.f(n)).collect::<Result<_>>()?;
    let outs: Vec<Vec<f64>> = model.outputs().iter().map(|o| runs.f(&o.name)).collect::<Result<_>>()?;
    let thetas: Vec<Vec<f64>> = rows.iter().map(|&i| cols.iter().map(|c| c[i]).collect()).collect();
    let ys: Vec<Vec<f64>> = rows.iter().map(|&i| outs.iter().map(|c| c[i]).collect()).collect();
    if thetas.len() < 2 * names.len() + 2 {
        return Err(Error::data_file(&runs_path, "source", format!("{} training runs: too few for an emulator of {} constants", thetas.len(), names.len())));
    }
    let emulator = Emulator::fit(model.space(), model.outputs(), thetas, ys)?;
    let pt = Table::load_file(&params_path)?;
    let (pn, q50) = (pt.s("name")?, pt.f("q50")?);
    let theta: Vec<f64> = names
        .iter()
        .map(|n| pn.iter().position(|v| v == n).map(|i| q50[i]).ok_or_else(|| Error::data_file(&params_path, "name", format!("no row for parameter {n}"))))
        .collect::<Result<_>>()?;
    let chains_path = dir.join("chains.csv");
    let posterior = gaussian_posterior(&chains_path, &names)?;
    let mut inputs = vec![loaded.path.clone()];
    inputs.extend(prep.inputs);
    inputs.extend([runs_path, params_path, chains_path]);
    Ok(Calibrated { model, reference_diameter: red.reference_diameter, grid: red.grid, fracture, emulator, theta, posterior, inputs, temperature_c: red.temperature_c })
}

/// Mean and inverse covariance of the calibration's posterior draws (`chains.csv`).
fn gaussian_posterior(path: &Path, names: &[String]) -> Result<(Vec<f64>, nalgebra::DMatrix<f64>)> {
    if !path.is_file() {
        return Err(Error::data_file(path, "file", "missing: rerun the calibration"));
    }
    let t = Table::load_file(path)?;
    let cols: Vec<Vec<f64>> = names.iter().map(|n| t.f(n)).collect::<Result<_>>()?;
    let n = cols.first().map_or(0, |c| c.len());
    if n < 10 * names.len() {
        return Err(Error::data_file(path, "file", format!("{n} draws: too few for the posterior's covariance")));
    }
    let mean: Vec<f64> = cols.iter().map(|c| c.iter().sum::<f64>() / n as f64).collect();
    let d = names.len();
    let cov = nalgebra::DMatrix::from_fn(d, d, |i, j| cols[i].iter().zip(&cols[j]).map(|(a, b)| (a - mean[i]) * (b - mean[j])).sum::<f64>() / (n as f64 - 1.0));
    let inv = cov.try_inverse().ok_or_else(|| Error::data_file(path, "file", "the posterior draws have a singular covariance"))?;
    Ok((mean, inv))
}

/// FE runs of the curvature table at θ: `Φ[r][k] = F_asperity(x_k)/F_sphere(x_k)`.
pub fn curvature_table(cal: &Calibrated, spec: &CurvatureTable, progress: &(dyn Fn() + Sync)) -> Result<RatioTable> {
    let mut roundness: Vec<f64> = spec.roundness.clone();
    roundness.sort_by(f64::total_cmp);
    roundness.dedup();
    roundness.push(1.0);
    let shapes: Vec<Shape> = roundness.iter().map(|&rho| if rho >= 1.0 { Shape::Sphere } else { Shape::Asperity { roundness: rho, width: spec.width } }).collect();
    let runs = cal.model.forces_with_shapes(&cal.theta, cal.reference_diameter, &shapes, &cal.grid, progress)?;
    let sphere = runs.last().cloned().unwrap_or_default();
    let ratio = runs.iter().map(|f| f.iter().zip(&sphere).map(|(a, b)| if *b > 0.0 { a / b } else { 1.0 }).collect()).collect();
    Ok(RatioTable { roundness, ratio })
}

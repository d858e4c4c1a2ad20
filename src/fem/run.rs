//! The `kind = "crush"` study: single-particle crush tests between rigid platens (deliverable
//! §4, Figs. 6–9), one FE run per case.
//!
//! ```toml
//! kind = "crush"
//! [crush]            # the base CrushSetup: diameter, material, mesh, platen, solver, fracture, fields_at
//! [[case]]           # key, label, optional shape / diameter / outline overriding the base
//! [figures]          # width_cm
//! ```
//!
//! Report files (`reports/<study>/`):
//!
//! | file | content |
//! |---|---|
//! | `curves.csv` | per case and sample: displacement, top and bottom force, energies |
//! | `crush_summary.csv` | per case: peak force, fracture displacement, quasi-static check, steps, elements |
//! | `fields.csv` | per case, snapshot and element: the element polygon (deformed) and its fields |
//! | `depth_profile.csv` | per case and snapshot: fields of the axis column vs depth below the platen |
//! | `<case>_d<µm>um.vtu` | VTK unstructured grid per snapshot (ParaView) |
//!
//! A plane-strain study (`kinematics = "plane_strain"`, every case alike) reports forces and
//! energies per unit thickness: those columns end in `_per_m` (`force_n_per_m`, …).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::mesh::Shape;
use super::output::{FIELD_NAMES, axis_column, vtu};
use super::{CrushResult, CrushSetup, CrushTest};
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, record_figures};
use crate::schema::StudyFile;

/// One crush case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrushCase {
    /// Short key (`sphere`): lowercase letters, digits, underscore.
    pub key: String,
    /// Label for figures.
    pub label: String,
    /// Shape overriding the base.
    #[serde(default)]
    pub shape: Option<Shape>,
    /// Diameter overriding the base (m).
    #[serde(default)]
    pub diameter: Option<f64>,
    /// Irregular outline overriding the base (plane strain).
    #[serde(default)]
    pub outline: Option<super::outline::Outline>,
}

/// `[figures]`
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CrushFigures {
    /// Figure width (cm), default 8.5.
    pub width_cm: f64,
}

impl Default for CrushFigures {
    fn default() -> Self {
        CrushFigures { width_cm: 8.5 }
    }
}

/// A crush study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrushStudy {
    /// `crush`.
    pub kind: String,
    /// Recorded in the manifest (the FE is deterministic and draws nothing).
    #[serde(default)]
    pub seed: u64,
    /// The base set-up.
    pub crush: CrushSetup,
    /// Cases, at least one.
    pub case: Vec<CrushCase>,
    /// Figures.
    #[serde(default)]
    pub figures: CrushFigures,
}

impl CrushStudy {
    /// The set-up and mesh of every case; validates everything before any step runs.
    pub fn setups(&self, file: &str) -> Result<Vec<(CrushSetup, super::mesh::Mesh)>> {
        if self.case.is_empty() {
            return Err(Error::config(file, "case", "at least one [[case]] is required"));
        }
        if !(self.figures.width_cm >= 4.0 && self.figures.width_cm <= 40.0) {
            return Err(Error::config(file, "figures.width_cm", format!("must lie in [4, 40], got {}", self.figures.width_cm)));
        }
        let mut seen = std::collections::HashSet::new();
        self.case
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let ok = !c.key.is_empty() && c.key.chars().all(|ch| ch.is_ascii_lowercase() || ch.is_ascii_digit() || ch == '_');
                if !ok {
                    return Err(Error::config(file, format!("case[{i}].key"), format!("\"{}\" must be lowercase letters, digits or _", c.key)));
                }
                if !seen.insert(c.key.clone()) {
                    return Err(Error::config(file, format!("case[{i}].key"), format!("\"{}\" appears twice", c.key)));
                }
                let mut s = self.crush.clone();
                if let Some(shape) = c.shape {
                    s.shape = shape;
                }
                if let Some(d) = c.diameter {
                    s.diameter = d;
                }
                if let Some(o) = &c.outline {
                    s.outline = Some(o.clone());
                }
                s.validate(file).map_err(|e| match e {
                    Error::Config { key, rule, .. } => Error::config(file, format!("case[{i}] ({}): {key}", c.key), rule),
                    other => other,
                })?;
                if s.kinematics != self.crush.kinematics {
                    return Err(Error::config(file, format!("case[{i}]"), "every case shares the study's kinematics (forces per radian and per thickness do not compare)"));
                }
                let mesh = s.mesh(file).map_err(|e| match e {
                    Error::Config { key, rule, .. } => Error::config(file, format!("case[{i}] ({}): {key}", c.key), rule),
                    other => other,
                })?;
                Ok((s, mesh))
            })
            .collect()
    }
}

/// Runs a crush study.
pub fn run_crush(loaded: &StudyFile, s: &CrushStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let file = loaded.path.display().to_string();
    let setups = s.setups(&file)?;
    let inputs = vec![InputFile::hash(&loaded.path)?];
    let pb = crate::runkit::progress_bar(1000, opts.progress, "{spinner} [{elapsed_precise}] {bar:30} {msg} (eta {eta})");
    let mut runs = Vec::new();
    let mut failures = Vec::new();
    let mut steps_total = 0u64;
    for (case, (setup, mesh)) in s.case.iter().zip(setups) {
        pb.set_message(format!("case {} ({})", case.key, case.label));
        pb.set_position(0);
        // Validated and meshed by `setups` above.
        let axisymmetric = setup.kinematics == super::Kinematics::Axisymmetric;
        let mut t = CrushTest::with_mesh(setup, mesh, axisymmetric)?;
        let r = t.run(Some(&pb))?;
        if let Some(w) = &r.quasi_static.warning {
            failures.push(format!("case {}: {w}", case.key));
        }
        for &d in &t.setup.fields_at {
            if !r.fields.iter().any(|f| f.displacement == d) {
                let end = r.curve.last().map(|s| s.displacement).unwrap_or(0.0);
                failures.push(format!("case {}: no fields at δ = {:.1} µm, the run ended at {:.1} µm (after fracture)", case.key, d * 1e6, end * 1e6));
            }
        }
        steps_total += r.steps * r.elements as u64;
        runs.push((case.clone(), t, r));
    }
    pb.set_message("tables");
    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;
    let headlines = write_tables(&mut dir, &runs)?;
    dir.write_bytes("summary.md", crate::runkit::headline_summary("Crush test of single particles (FE)", &headlines).as_bytes())?;
    pb.set_message("figures");
    let rendered = crate::report::crush::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    let mut evaluations = BTreeMap::new();
    evaluations.insert("crush_runs".to_string(), runs.len() as u64);
    evaluations.insert("element_steps".to_string(), steps_total);
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let run = RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings: Vec::new() };
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, run)?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines })
}

fn write_tables(dir: &mut ReportDir, runs: &[(CrushCase, CrushTest, CrushResult)]) -> Result<Vec<String>> {
    // Curves.
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); 8];
    let (mut keys, mut labels) = (Vec::new(), Vec::new());
    for (c, _, r) in runs {
        for s in &r.curve {
            keys.push(c.key.clone());
            labels.push(c.label.clone());
            for (k, v) in [s.time, s.displacement, s.force, s.force_bottom, s.kinetic, s.internal, s.hourglass, s.external].into_iter().enumerate() {
                cols[k].push(v);
            }
        }
    }
    // Plane strain: forces and energies per unit thickness (column names say so).
    let per = if runs.first().is_some_and(|r| r.1.setup.kinematics == super::Kinematics::PlaneStrain) { "_per_m" } else { "" };
    let names = ["time_s".to_string(), "displacement_m".into(), format!("force_n{per}"), format!("force_bottom_n{per}"), format!("kinetic_j{per}"), format!("internal_j{per}"), format!("hourglass_j{per}"), format!("external_work_j{per}")];
    let mut columns = vec![scol("case", keys), scol("label", labels)];
    columns.extend(names.iter().zip(cols).map(|(n, v)| fcol(n, v)));
    dir.write_table("curves", &mut table(columns)?)?;

    // Summary.
    let mut headlines = Vec::new();
    let get = |f: &dyn Fn(&CrushResult) -> f64| runs.iter().map(|(_, _, r)| f(r)).collect::<Vec<f64>>();
    let mut df = table(vec![
        scol("case", runs.iter().map(|r| r.0.key.clone()).collect()),
        scol("label", runs.iter().map(|r| r.0.label.clone()).collect()),
        fcol("diameter_m", runs.iter().map(|r| r.1.setup.diameter).collect()),
        fcol("pole_curvature_ratio", runs.iter().map(|r| r.1.setup.shape.pole_curvature_ratio()).collect()),
        fcol(&format!("peak_force_n{per}"), get(&|r| r.peak_force)),
        fcol("peak_displacement_m", get(&|r| r.peak_displacement)),
        fcol("fracture_displacement_m", get(&|r| r.fracture_displacement.unwrap_or(f64::NAN))),
        fcol("max_kinetic_ratio", get(&|r| r.quasi_static.max_kinetic_ratio)),
        fcol("max_force_imbalance", get(&|r| r.quasi_static.max_force_imbalance)),
        fcol("max_hourglass_ratio", get(&|r| r.quasi_static.max_hourglass_ratio)),
        scol("quasi_static_warning", runs.iter().map(|r| r.2.quasi_static.warning.clone().unwrap_or_default()).collect()),
        ucol("elements", runs.iter().map(|r| r.2.elements as u64).collect()),
        ucol("steps", runs.iter().map(|r| r.2.steps).collect()),
        fcol("time_step_min_s", get(&|r| r.time_step.0)),
        fcol("time_step_max_s", get(&|r| r.time_step.1)),
    ])?;
    dir.write_table("crush_summary", &mut df)?;
    for (c, _, r) in runs {
        let frac = r.fracture_displacement.map(|d| format!("fracture at δ = {:.1} µm", d * 1e6)).unwrap_or_else(|| "no fracture".into());
        let force = if per.is_empty() { format!("{:.1} N", r.peak_force) } else { format!("{:.3e} N/m", r.peak_force) };
        headlines.push(format!("{}: peak force {force} at δ = {:.1} µm, {frac}; {} elements, {} steps", c.label, r.peak_displacement * 1e6, r.elements, r.steps));
    }

    // Fields: polygons and values; depth profiles; VTU files.
    let mut f_case = Vec::new();
    let mut f_disp = Vec::new();
    let mut f_elem = Vec::new();
    let mut poly: Vec<Vec<f64>> = vec![Vec::new(); 8];
    let mut vals: Vec<Vec<f64>> = vec![Vec::new(); FIELD_NAMES.len()];
    let (mut d_case, mut d_disp, mut d_depth) = (Vec::new(), Vec::new(), Vec::new());
    let mut dvals: Vec<Vec<f64>> = vec![Vec::new(); FIELD_NAMES.len()];
    for (c, t, r) in runs {
        for snap in &r.fields {
            let name = format!("{}_d{:.1}um.vtu", c.key, snap.displacement * 1e6);
            dir.write_bytes(&name, vtu(&t.mesh, &snap.nodes, &snap.values).as_bytes())?;
            let columns = snap.values.columns();
            for (e, conn) in t.mesh.elements.iter().enumerate() {
                f_case.push(c.key.clone());
                f_disp.push(snap.displacement);
                f_elem.push(e as u64);
                for k in 0..4 {
                    poly[2 * k].push(snap.nodes[conn[k] as usize][0]);
                    poly[2 * k + 1].push(snap.nodes[conn[k] as usize][1]);
                }
                for (v, col) in vals.iter_mut().zip(columns) {
                    v.push(col[e]);
                }
            }
            let platen_z = t.mesh.surface.iter().map(|&i| t.mesh.nodes[i as usize][1]).fold(f64::MIN, f64::max) - 0.5 * snap.displacement;
            for p in axis_column(&t.mesh, &snap.nodes, &snap.values, platen_z) {
                d_case.push(c.key.clone());
                d_disp.push(snap.displacement);
                d_depth.push(p.depth);
                for (v, col) in dvals.iter_mut().zip(columns) {
                    v.push(col[p.element]);
                }
            }
        }
    }
    let mut columns = vec![scol("case", f_case), fcol("displacement_m", f_disp), ucol("element", f_elem)];
    let pnames = ["r1_m", "z1_m", "r2_m", "z2_m", "r3_m", "z3_m", "r4_m", "z4_m"];
    columns.extend(pnames.iter().zip(poly).map(|(n, v)| fcol(n, v)));
    columns.extend(FIELD_NAMES.iter().zip(vals).map(|((n, _), v)| fcol(n, v)));
    dir.write_table("fields", &mut table(columns)?)?;
    let mut columns = vec![scol("case", d_case), fcol("displacement_m", d_disp), fcol("depth_m", d_depth)];
    columns.extend(FIELD_NAMES.iter().zip(dvals).map(|((n, _), v)| fcol(n, v)));
    dir.write_table("depth_profile", &mut table(columns)?)?;
    Ok(headlines)
}

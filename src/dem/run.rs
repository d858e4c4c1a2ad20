//! The `kind = "dem"` study: particle flow through the tube bank, with the tables, snapshots
//! and figures of the deliverable's §3 (Figs. 3–5).
//!
//! Report files (`reports/<study>/`):
//!
//! | file | content |
//! |---|---|
//! | `impacts.parquet` | every impact after the warm-up: time, target (tube/particle/wall), ids, row, diameter, normal and tangential velocity at first contact, contact point |
//! | `impact_spectrum.csv` | per target and row: count, mean and quantiles of the normal impact velocity — the file the lifetime study reads |
//! | `velocity_profile.csv` | mean vertical velocity vs height |
//! | `speed_map.csv` | mean speed and vertical velocity on an (x, z) grid |
//! | `passes.parquet` | per particle that left through the outlet after the warm-up: residence time and impact counts since insertion |
//! | `flow.csv` | hold-up and cumulative in/outflow vs time |
//! | `force_trace.csv` | the traced tube impact: overlap, normal force and its cumulative integral, the impact's normal velocity and the (reduced) modulus |
//! | `tubes.csv` | the tube layout |
//! | `dem_summary.csv` | mass flow, hold-up, impacts per pass, counters, speed |
//! | `particles_t*.vtp` | particle snapshots for ParaView |

use std::time::Instant;

use polars::prelude::*;
use serde::{Deserialize, Serialize};

use super::contact::{Interaction, Material};
use super::geometry::{BankSpec, Geometry};
use super::probe::{Target, quantile};
use super::vtk;
use super::{Dem, DemSetup, Diameters, Inlet, ProbeSetup};
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, record_figures};
use crate::schema::StudyFile;

/// `[particles]`
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleOptions {
    /// Density (kg/m³).
    pub density: f64,
    /// Young's modulus used in the DEM (Pa), usually reduced (see [`crate::dem`]).
    pub youngs_modulus: f64,
    /// Poisson's ratio.
    pub poisson_ratio: f64,
    /// Diameter distribution.
    pub diameter: Diameters,
}

/// `[walls]`: tubes and side walls.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WallOptions {
    /// Young's modulus (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio.
    pub poisson_ratio: f64,
}

/// One interaction table.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InteractionOptions {
    /// Coefficient of restitution, (0, 1].
    pub restitution: f64,
    /// Coulomb friction, ≥ 0.
    pub friction: f64,
    /// Rolling friction, ≥ 0 (default 0).
    #[serde(default)]
    pub rolling_friction: f64,
}

impl InteractionOptions {
    fn to_interaction(&self) -> Interaction {
        Interaction { restitution: self.restitution, friction: self.friction, rolling_friction: self.rolling_friction }
    }
}

/// `[contact]`
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ContactTables {
    /// Particle–particle.
    pub particle_particle: InteractionOptions,
    /// Particle–tube and particle–wall.
    pub particle_wall: InteractionOptions,
}

/// `[inlet]`
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InletOptions {
    /// Mass flux through the inlet cross-section (width × slab) (kg/(m² s)).
    pub mass_flux: f64,
    /// Downward speed at insertion (m/s).
    pub velocity: f64,
    /// Height of the insertion region at the top of the domain (m).
    pub height: f64,
}

fn default_skin() -> f64 {
    0.25
}
fn default_rebuild() -> u64 {
    200
}
fn default_overlap() -> f64 {
    0.3
}
fn default_safety() -> f64 {
    0.5
}

/// `[run]`
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RunTable {
    /// Simulated time (s).
    pub duration: f64,
    /// Measurements start here (s).
    pub warmup: f64,
    /// Time step (s); default `time_step_safety` × the stable limit.
    #[serde(default)]
    pub time_step: Option<f64>,
    /// Safety factor on the stable limit when no step is given (default 0.5).
    #[serde(default = "default_safety")]
    pub time_step_safety: f64,
    /// Largest expected impact speed (m/s); default √(v_in² + 2 g H) + 1 m/s for the domain
    /// height H.
    #[serde(default)]
    pub max_speed: Option<f64>,
    /// Neighbour skin, fraction of the largest diameter (default 0.25).
    #[serde(default = "default_skin")]
    pub skin: f64,
    /// Neighbour lists are rebuilt (and particles inserted) at least every this many steps
    /// (default 200).
    #[serde(default = "default_rebuild")]
    pub max_rebuild_steps: u64,
    /// Overlap beyond this fraction of the radius stops the run (default 0.3).
    #[serde(default = "default_overlap")]
    pub max_overlap_fraction: f64,
    /// Snapshot times (s) for `.vtp` files; the end time is always written.
    #[serde(default)]
    pub snapshots: Vec<f64>,
}

// `[probes]` defaults are the solver's (`ProbeSetup::default`), in one place.
fn default_sample_every() -> u64 {
    ProbeSetup::default().sample_every
}
fn default_profile_bins() -> usize {
    ProbeSetup::default().profile_bins
}
fn default_map_nx() -> usize {
    ProbeSetup::default().map_nx
}
fn default_map_nz() -> usize {
    ProbeSetup::default().map_nz
}
fn default_min_v() -> f64 {
    ProbeSetup::default().min_impact_velocity
}
fn default_trace_v() -> f64 {
    ProbeSetup::default().trace_min_velocity
}
fn default_quantiles() -> Vec<f64> {
    vec![0.05, 0.25, 0.5, 0.75, 0.9, 0.95, 0.99]
}

/// `[probes]`
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeOptions {
    /// Field sampling interval (steps, default 100).
    #[serde(default = "default_sample_every")]
    pub sample_every: u64,
    /// Bins of the velocity profile (default 150).
    #[serde(default = "default_profile_bins")]
    pub profile_bins: usize,
    /// x bins of the speed map (default 50).
    #[serde(default = "default_map_nx")]
    pub map_nx: usize,
    /// z bins of the speed map (default 130).
    #[serde(default = "default_map_nz")]
    pub map_nz: usize,
    /// Contacts starting slower than this are touches, not impacts (m/s, default 0.1): the
    /// count of such slow re-contacts in dense regions depends on the (reduced) contact
    /// stiffness, the statistics of faster impacts do not (see `tests/dem.rs`).
    #[serde(default = "default_min_v")]
    pub min_impact_velocity: f64,
    /// Speed of the traced tube impact, at least (m/s, default 1.0).
    #[serde(default = "default_trace_v")]
    pub trace_min_velocity: f64,
    /// Quantiles of the impact spectrum (default 5, 25, 50, 75, 90, 95, 99 %).
    #[serde(default = "default_quantiles")]
    pub quantiles: Vec<f64>,
}

impl Default for ProbeOptions {
    fn default() -> Self {
        ProbeOptions {
            sample_every: default_sample_every(),
            profile_bins: default_profile_bins(),
            map_nx: default_map_nx(),
            map_nz: default_map_nz(),
            min_impact_velocity: default_min_v(),
            trace_min_velocity: default_trace_v(),
            quantiles: default_quantiles(),
        }
    }
}

fn default_width_cm() -> f64 {
    8.5
}

/// `[figures]`
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DemFigures {
    /// Figure width (cm), default 8.5 (single column).
    #[serde(default = "default_width_cm")]
    pub width_cm: f64,
}

impl Default for DemFigures {
    fn default() -> Self {
        DemFigures { width_cm: default_width_cm() }
    }
}

/// A DEM study file.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DemStudy {
    /// `dem`.
    pub kind: String,
    /// Seed of insertion positions and diameters.
    pub seed: u64,
    /// Particles.
    pub particles: ParticleOptions,
    /// Tubes and walls.
    pub walls: WallOptions,
    /// Interactions.
    pub contact: ContactTables,
    /// The tube bank.
    pub geometry: BankSpec,
    /// Insertion.
    pub inlet: InletOptions,
    /// Time stepping.
    pub run: RunTable,
    /// Measurements.
    #[serde(default)]
    pub probes: ProbeOptions,
    /// Figures.
    #[serde(default)]
    pub figures: DemFigures,
}

/// Gravity (m/s²).
pub const GRAVITY: f64 = 9.81;

impl DemStudy {
    /// The solver set-up; validates everything (errors name `file` and the key).
    pub fn setup(&self, file: &str) -> Result<DemSetup> {
        self.geometry.validate(file)?;
        let geometry = Geometry::tube_bank(&self.geometry);
        let pos = |key: &str, v: f64| -> Result<()> {
            if v > 0.0 && v.is_finite() { Ok(()) } else { Err(Error::config(file, key, format!("must be > 0, got {v}"))) }
        };
        pos("run.duration", self.run.duration)?;
        pos("inlet.height", self.inlet.height)?;
        pos("figures.width_cm", self.figures.width_cm)?;
        if !(self.run.warmup >= 0.0 && self.run.warmup < self.run.duration) {
            return Err(Error::config(file, "run.warmup", format!("must lie in [0, duration = {}) s, got {}", self.run.duration, self.run.warmup)));
        }
        if !(self.run.time_step_safety > 0.0 && self.run.time_step_safety <= 1.0) {
            return Err(Error::config(file, "run.time_step_safety", format!("must lie in (0, 1], got {}", self.run.time_step_safety)));
        }
        if self.run.max_rebuild_steps == 0 {
            return Err(Error::config(file, "run.max_rebuild_steps", "must be ≥ 1"));
        }
        for (k, &t) in self.run.snapshots.iter().enumerate() {
            if !(t >= 0.0 && t <= self.run.duration) {
                return Err(Error::config(file, format!("run.snapshots[{k}]"), format!("{t} s is outside [0, duration = {}] s", self.run.duration)));
            }
        }
        for (key, v) in [("probes.min_impact_velocity", self.probes.min_impact_velocity), ("probes.trace_min_velocity", self.probes.trace_min_velocity)] {
            if !crate::data::VELOCITY.contains(v) {
                return Err(Error::config(file, key, format!("must lie in {} (a speed), got {v}", crate::data::VELOCITY.shown)));
            }
        }
        for (k, &q) in self.probes.quantiles.iter().enumerate() {
            if !(q > 0.0 && q < 1.0) {
                return Err(Error::config(file, format!("probes.quantiles[{k}]"), format!("must lie in (0, 1), got {q}")));
            }
        }
        let height = geometry.z_hi - geometry.z_lo;
        let max_speed = self.run.max_speed.unwrap_or((self.inlet.velocity.powi(2) + 2.0 * GRAVITY * height).sqrt() + 1.0);
        pos("run.max_speed", max_speed)?;
        let inlet = Inlet {
            mass_flux: self.inlet.mass_flux,
            velocity: self.inlet.velocity,
            z_lo: geometry.z_hi - self.inlet.height,
            z_hi: geometry.z_hi,
        };
        let mut setup = DemSetup {
            particle: Material {
                density: self.particles.density,
                youngs_modulus: self.particles.youngs_modulus,
                poisson_ratio: self.particles.poisson_ratio,
            },
            wall: Material { density: 7800.0, youngs_modulus: self.walls.youngs_modulus, poisson_ratio: self.walls.poisson_ratio },
            particle_particle: self.contact.particle_particle.to_interaction(),
            particle_wall: self.contact.particle_wall.to_interaction(),
            diameters: self.particles.diameter,
            geometry,
            gravity: [0.0, 0.0, -GRAVITY],
            inlet: Some(inlet),
            time_step: 1.0,
            max_speed,
            skin_fraction: self.run.skin,
            max_rebuild_steps: self.run.max_rebuild_steps,
            rotation: true,
            max_overlap_fraction: self.run.max_overlap_fraction,
            probes: ProbeSetup {
                warmup: self.run.warmup,
                sample_every: self.probes.sample_every,
                profile_bins: self.probes.profile_bins,
                map_nx: self.probes.map_nx,
                map_nz: self.probes.map_nz,
                min_impact_velocity: self.probes.min_impact_velocity,
                trace_min_velocity: self.probes.trace_min_velocity,
            },
            seed: self.seed,
        };
        // The limit needs valid materials and diameters: validate with a provisional step first.
        setup.time_step = f64::MIN_POSITIVE;
        setup.validate(file)?;
        let limit = setup.time_step_limit();
        setup.time_step = self.run.time_step.unwrap_or(self.run.time_step_safety * limit);
        setup.validate(file)?;
        Ok(setup)
    }
}

/// Runs a DEM study into `reports/<name>/`.
pub fn run_dem(loaded: &StudyFile, s: &DemStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let file = loaded.path.display().to_string();
    let setup = s.setup(&file)?;
    let inputs = vec![InputFile::hash(&loaded.path)?];
    let dt = setup.time_step;
    let total_steps = (s.run.duration / dt).ceil() as u64;
    let mut dem = Dem::new(setup, &file)?;
    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;

    let pb = crate::runkit::progress_bar(total_steps, opts.progress, "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} steps {msg} (eta {eta})");
    let mut snaps: Vec<f64> = s.run.snapshots.clone();
    snaps.sort_by(f64::total_cmp);
    let mut next_snap = 0;
    let chunk = 500u64;
    let t_loop = Instant::now();
    while dem.step < total_steps {
        // Up to the chunk's end or the step that reaches the next snapshot, whichever is first
        // (time accumulated as the solver does, so the same step is found).
        let mut n = chunk.min(total_steps - dem.step);
        if let Some(&t_snap) = snaps.get(next_snap) {
            let (mut t, mut k) = (dem.time, 0);
            while k < n {
                t += dt;
                k += 1;
                if t >= t_snap - 0.5 * dt {
                    break;
                }
            }
            n = k;
        }
        dem.advance(n)?;
        while next_snap < snaps.len() && dem.time >= snaps[next_snap] - 0.5 * dt {
            write_snapshot(&mut dir, &dem)?;
            next_snap += 1;
        }
        pb.set_position(dem.step);
        pb.set_message(format!("t = {:.3} s, {} particles, {} impacts", dem.time, dem.p.len(), dem.impacts.len()));
    }
    let loop_s = t_loop.elapsed().as_secs_f64();
    if snaps.last().is_none_or(|&t| (t - dem.time).abs() > 0.5 * dt) {
        write_snapshot(&mut dir, &dem)?;
    }
    pb.set_message("tables");
    let headlines = write_tables(&mut dir, &dem, s, loop_s)?;
    dir.write_bytes("summary.md", crate::runkit::headline_summary("Particle flow through the tube bank (DEM)", &headlines).as_bytes())?;
    pb.set_message("figures");
    let rendered = crate::report::dem::render(dir.path(), s.figures.width_cm)?;
    let mut failures = Vec::new();
    record_figures(&mut dir, rendered, &mut failures);
    let mut evaluations = std::collections::BTreeMap::new();
    evaluations.insert("dem_particle_steps".to_string(), dem.counters.particle_steps);
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let run = RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings: Vec::new() };
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, run)?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines })
}

fn write_snapshot(dir: &mut ReportDir, dem: &Dem) -> Result<()> {
    let text = vtk::polydata(&dem.p, dem.time);
    dir.write_bytes(&format!("particles_t{:.3}s.vtp", dem.time), text.as_bytes())
}

fn parquet_bytes(df: &mut DataFrame, what: &str) -> Result<Vec<u8>> {
    let mut buf = Vec::new();
    ParquetWriter::new(&mut buf).finish(df).map_err(|e| Error::numerical(format!("writing {what}"), e.to_string()))?;
    Ok(buf)
}

/// Statistics of a run that tests and the Simulator read without files.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrumRow {
    /// Target name.
    pub target: &'static str,
    /// Row (0 = all rows).
    pub row: u32,
    /// Impacts.
    pub count: usize,
    /// Mean normal velocity (m/s).
    pub mean: f64,
    /// Quantiles, in the order asked.
    pub quantiles: Vec<f64>,
}

/// Impact spectrum per target and row (row 0 = all impacts of that target).
pub fn spectrum(dem: &Dem, quantiles: &[f64]) -> Vec<SpectrumRow> {
    let rows = dem.setup.geometry.row_z.len() as u32;
    let mut out = Vec::new();
    for target in [Target::Tube, Target::Particle] {
        for row in 0..=rows + 1 {
            let mut v: Vec<f64> = dem.impacts.iter().filter(|i| i.target == target && (row == 0 || i.row == row)).map(|i| i.v_normal).collect();
            if v.is_empty() && row != 0 {
                continue;
            }
            let mean = if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 };
            let q = quantiles.iter().map(|&q| quantile(&mut v, q)).collect();
            out.push(SpectrumRow { target: target.name(), row, count: v.len(), mean, quantiles: q });
        }
    }
    out
}

fn write_tables(dir: &mut ReportDir, dem: &Dem, s: &DemStudy, loop_s: f64) -> Result<Vec<String>> {
    let imp = &dem.impacts;
    let mut df = table(vec![
        fcol("time_s", imp.iter().map(|i| i.time).collect()),
        scol("target", imp.iter().map(|i| i.target.name().to_string()).collect()),
        ucol("particle", imp.iter().map(|i| i.particle).collect()),
        ucol("partner", imp.iter().map(|i| i.partner).collect()),
        ucol("row", imp.iter().map(|i| i.row as u64).collect()),
        fcol("diameter_m", imp.iter().map(|i| i.diameter).collect()),
        fcol("v_normal_m_s", imp.iter().map(|i| i.v_normal).collect()),
        fcol("v_tangential_m_s", imp.iter().map(|i| i.v_tangential).collect()),
        fcol("x_m", imp.iter().map(|i| i.point[0]).collect()),
        fcol("y_m", imp.iter().map(|i| i.point[1]).collect()),
        fcol("z_m", imp.iter().map(|i| i.point[2]).collect()),
    ])?;
    let bytes = parquet_bytes(&mut df, "impacts.parquet")?;
    dir.write_bytes("impacts.parquet", &bytes)?;

    // Spectrum.
    let qs = &s.probes.quantiles;
    let spec = spectrum(dem, qs);
    let mut cols = vec![
        scol("target", spec.iter().map(|r| r.target.to_string()).collect()),
        ucol("row", spec.iter().map(|r| r.row as u64).collect()),
        ucol("impacts", spec.iter().map(|r| r.count as u64).collect()),
        fcol("mean_v_normal_m_s", spec.iter().map(|r| r.mean).collect()),
    ];
    for (k, q) in qs.iter().enumerate() {
        cols.push(fcol(&format!("q{:.0}_v_normal_m_s", 100.0 * q), spec.iter().map(|r| r.quantiles[k]).collect()));
    }
    let mut df = table(cols)?;
    dir.write_table("impact_spectrum", &mut df)?;

    // Profile and map.
    let f = &dem.fields;
    let prof = f.profile();
    let mut df = table(vec![
        fcol("z_m", prof.iter().map(|p| p.0).collect()),
        fcol("mean_vz_m_s", prof.iter().map(|p| p.1).collect()),
        ucol("samples", prof.iter().map(|p| p.2).collect()),
    ])?;
    dir.write_table("velocity_profile", &mut df)?;
    let nx = f.map_x_edges.len() - 1;
    let nz = f.map_z_edges.len() - 1;
    let (mut xs, mut zs, mut sp, mut vz, mut cnt) = (vec![], vec![], vec![], vec![], vec![]);
    for iz in 0..nz {
        for ix in 0..nx {
            let c = iz * nx + ix;
            xs.push(0.5 * (f.map_x_edges[ix] + f.map_x_edges[ix + 1]));
            zs.push(0.5 * (f.map_z_edges[iz] + f.map_z_edges[iz + 1]));
            let n = f.count_map[c];
            sp.push(if n > 0 { f.sum_speed[c] / n as f64 } else { f64::NAN });
            vz.push(if n > 0 { f.sum_map_vz[c] / n as f64 } else { f64::NAN });
            cnt.push(n);
        }
    }
    let mut df = table(vec![
        fcol("x_m", xs),
        fcol("z_m", zs),
        fcol("cell_dx_m", vec![f.map_x_edges[1] - f.map_x_edges[0]; nx * nz]),
        fcol("cell_dz_m", vec![f.map_z_edges[1] - f.map_z_edges[0]; nx * nz]),
        fcol("mean_speed_m_s", sp),
        fcol("mean_vz_m_s", vz),
        ucol("samples", cnt),
    ])?;
    dir.write_table("speed_map", &mut df)?;

    // Passes.
    let ps = &dem.passes;
    let mut df = table(vec![
        ucol("particle", ps.iter().map(|p| p.particle).collect()),
        fcol("diameter_m", ps.iter().map(|p| p.diameter).collect()),
        fcol("residence_s", ps.iter().map(|p| p.residence).collect()),
        ucol("tube_impacts", ps.iter().map(|p| p.tube_impacts as u64).collect()),
        ucol("particle_impacts", ps.iter().map(|p| p.particle_impacts as u64).collect()),
    ])?;
    let bytes = parquet_bytes(&mut df, "passes.parquet")?;
    dir.write_bytes("passes.parquet", &bytes)?;

    // Flow.
    let fl = &dem.flow;
    let mut df = table(vec![
        fcol("time_s", fl.iter().map(|x| x.time).collect()),
        ucol("particles", fl.iter().map(|x| x.particles as u64).collect()),
        fcol("holdup_kg", fl.iter().map(|x| x.mass).collect()),
        fcol("inflow_kg", fl.iter().map(|x| x.inflow_mass).collect()),
        fcol("outflow_kg", fl.iter().map(|x| x.outflow_mass).collect()),
    ])?;
    dir.write_table("flow", &mut df)?;

    // Trace with its cumulative integral (trapezoid).
    let tr = &dem.trace;
    let mut cum = Vec::with_capacity(tr.len());
    let mut acc = 0.0;
    for (k, t) in tr.iter().enumerate() {
        if k > 0 {
            acc += 0.5 * (t.normal_force + tr[k - 1].normal_force) * (t.time - tr[k - 1].time);
        }
        cum.push(acc);
    }
    let mut df = table(vec![
        fcol("time_s", tr.iter().map(|t| t.time).collect()),
        fcol("overlap_m", tr.iter().map(|t| t.overlap).collect()),
        fcol("normal_force_n", tr.iter().map(|t| t.normal_force).collect()),
        fcol("cumulative_impulse_n_s", cum),
        fcol("youngs_modulus_pa", vec![dem.setup.particle.youngs_modulus; tr.len()]),
        fcol("v_normal_m_s", vec![dem.trace_velocity().unwrap_or(f64::NAN); tr.len()]),
    ])?;
    dir.write_table("force_trace", &mut df)?;

    let g = &dem.setup.geometry;
    let mut df = table(vec![
        ucol("tube", (0..g.tubes.len() as u64).collect()),
        ucol("row", g.tubes.iter().map(|t| t.row as u64).collect()),
        fcol("x_m", g.tubes.iter().map(|t| t.x).collect()),
        fcol("z_m", g.tubes.iter().map(|t| t.z).collect()),
        fcol("radius_m", g.tubes.iter().map(|t| t.radius).collect()),
        fcol("width_m", vec![g.x_hi - g.x_lo; g.tubes.len()]),
        fcol("domain_top_m", vec![g.z_hi; g.tubes.len()]),
    ])?;
    dir.write_table("tubes", &mut df)?;

    // Summary.
    let measured = (dem.time - s.run.warmup).max(0.0);
    let mass_flow = if measured > 0.0 { dem.outflow_mass_measured / measured } else { f64::NAN };
    let after: Vec<_> = fl.iter().filter(|x| x.time >= s.run.warmup).collect();
    let mean_n = after.iter().map(|x| x.particles as f64).sum::<f64>() / after.len().max(1) as f64;
    let mean_holdup = after.iter().map(|x| x.mass).sum::<f64>() / after.len().max(1) as f64;
    let per_pass = |f: &dyn Fn(&super::probe::Pass) -> f64| ps.iter().map(f).sum::<f64>() / ps.len().max(1) as f64;
    let tube_pp = per_pass(&|p| p.tube_impacts as f64);
    let part_pp = per_pass(&|p| p.particle_impacts as f64);
    let res = per_pass(&|p| p.residence);
    let inlet_area = (g.x_hi - g.x_lo) * g.slab;
    let c = dem.counters;
    let tube_all = spec.iter().find(|r| r.target == "tube" && r.row == 0);
    let q50 = qs.iter().position(|&q| (q - 0.5).abs() < 1e-9);
    let items: Vec<(&str, f64, &str)> = vec![
        ("time_step", dem.setup.time_step, "s"),
        ("time_step_limit", dem.setup.time_step_limit(), "s"),
        ("simulated_time", dem.time, "s"),
        ("warmup", s.run.warmup, "s"),
        ("steps", dem.step as f64, "-"),
        ("inlet_mass_flow", s.inlet.mass_flux * inlet_area, "kg/s"),
        ("outlet_mass_flow", mass_flow, "kg/s"),
        ("mean_particles_in_domain", mean_n, "-"),
        ("mean_holdup", mean_holdup, "kg"),
        ("passes", ps.len() as f64, "-"),
        ("tube_impacts_per_pass", tube_pp, "-"),
        ("particle_impacts_per_pass", part_pp, "-"),
        ("mean_residence_time", res, "s"),
        ("impacts_recorded", imp.len() as f64, "-"),
        ("particles_inserted", c.inserted as f64, "-"),
        ("insertions_deferred", c.deferred_insertions as f64, "-"),
        ("neighbour_builds", c.builds as f64, "-"),
        ("particle_steps", c.particle_steps as f64, "-"),
        ("loop_wall_time", loop_s, "s"),
        ("particle_steps_per_second", c.particle_steps as f64 / loop_s.max(1e-9), "1/s"),
        ("threads", rayon::current_num_threads() as f64, "-"),
        ("traced_impact_samples", dem.trace.len() as f64, "-"),
    ];
    let mut df = table(vec![
        scol("quantity", items.iter().map(|x| x.0.to_string()).collect()),
        fcol("value", items.iter().map(|x| x.1).collect()),
        scol("unit", items.iter().map(|x| x.2.to_string()).collect()),
    ])?;
    dir.write_table("dem_summary", &mut df)?;

    let mut headlines = vec![
        format!("{:.0} particles in the domain on average; outlet mass flow {:.4} kg/s (inlet {:.4} kg/s)", mean_n, mass_flow, s.inlet.mass_flux * inlet_area),
        if ps.is_empty() {
            "no particle left through the outlet after the warm-up: run longer for impacts per pass".to_string()
        } else {
            format!("{:.2} tube and {:.2} particle impacts per pass ({} passes, mean residence {:.3} s)", tube_pp, part_pp, ps.len(), res)
        },
    ];
    if let (Some(t), Some(k)) = (tube_all, q50) {
        headlines.push(format!("tube impacts: {} recorded, median normal velocity {:.2} m/s, mean {:.2} m/s", t.count, t.quantiles[k], t.mean));
    }
    if dem.trace.len() < 3 {
        headlines.push(format!(
            "warning: no tube impact at ≥ {} m/s after the warm-up was traced, so there is no force–time figure; run longer or lower probes.trace_min_velocity",
            s.probes.trace_min_velocity
        ));
    }
    headlines.push(format!("{:.3e} particle-steps/s on {} threads", c.particle_steps as f64 / loop_s.max(1e-9), rayon::current_num_threads()));
    Ok(headlines)
}

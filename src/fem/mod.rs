//! Native crush FE: a particle compressed between rigid flat platens, axisymmetric explicit
//! dynamics with the Johnson–Holmquist-2 ceramic model (deliverable §4, Figs. 6–9).
//!
//! ## Model
//! * Mesh ([`mesh`]): the (r, z) quarter of a body of revolution, graded towards the contact
//!   pole; symmetry conditions `v_r = 0` on the axis and `v_z = 0` on the equatorial plane, so
//!   the platen displacement u is half the total crush displacement δ_tot = 2u (both contacts).
//!   Plane strain ([`Kinematics::PlaneStrain`]): the whole (x, z) section, graded at both
//!   contacts, between a top and a bottom platen each moving by u, for irregular outlines
//!   ([`outline`]) that an axisymmetric model cannot represent; forces per unit thickness.
//! * Element ([`element`]): 4-node axisymmetric quad, one-point integration, stiffness
//!   hourglass control, bulk viscosity.
//! * Kinematics: updated Lagrangian **rate form** — the rate of deformation D and spin W are
//!   evaluated on the current configuration, stresses are advanced hypo-elastically with the
//!   Jaumann rate, and the JH-2 compression μ = V₀/V − 1 comes from the current volume. JH-2 is
//!   defined incrementally (plastic-strain increments, damage), and the near-contact strains
//!   (p₀/E ≈ 7 %) and rotations are moderate, so a rate form with an objective rate is the
//!   natural and standard (LS-DYNA, Autodyn) choice; a total small-strain form would not handle
//!   the rotation of damaged material beside the contact.
//! * Time integration: central differences with lumped (row-sum, per-radian) masses, variable
//!   step recomputed every `solver.step_interval` steps as `safety ×` the smallest element step
//!   ([`element::Kernel::critical_step`]); optional uniform mass scaling.
//! * Platen ([`contact`]): rigid and flat, moved at constant speed after a smooth cubic ramp;
//!   kinematic (velocity-constraint) contact, frictionless or Coulomb.
//!
//! ## Results
//! [`CrushResult`]: the force–displacement curve (top platen and equatorial reaction, each
//! averaged over its sample interval), energies, peak force and fracture displacement (first
//! sustained drop, see [`FractureParams`]), field snapshots at requested displacements, the
//! quasi-static check, step counts.
//!
//! Verified by `tests/verification/crush_fe.rs`.

pub mod contact;
pub mod element;
pub mod material;
pub mod mesh;
pub mod model;
pub mod outline;
pub mod output;
pub mod run;
mod setup;

pub use setup::*;

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use element::{ElementState, Kernel};
use material::MaterialParams;
use mesh::Mesh;

/// One sample of the force–displacement curve.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct CurveSample {
    /// Time (s).
    pub time: f64,
    /// Total crush displacement δ_tot = 2u (m), mid-interval.
    pub displacement: f64,
    /// Top platen force, averaged over the interval (N).
    pub force: f64,
    /// Equatorial-plane reaction (the bottom platen by symmetry), averaged (N).
    pub force_bottom: f64,
    /// Kinetic energy of the whole particle (J).
    pub kinetic: f64,
    /// Internal (strain + plastic + viscous) energy (J).
    pub internal: f64,
    /// Hourglass energy (J).
    pub hourglass: f64,
    /// Work done by the platens (J).
    pub external: f64,
}

/// Quasi-static check of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QuasiStatic {
    /// Largest E_kin / E_int after the ramp and up to 95 % of the peak-force displacement, where
    /// E_int exceeds 1 % of its value there.
    pub max_kinetic_ratio: f64,
    /// Largest |F_top − F_bottom| / F_peak over the same samples, both forces averaged over two
    /// wave transits (see [`output::quasi_static`]).
    pub max_force_imbalance: f64,
    /// Largest hourglass / internal energy over the same samples.
    pub max_hourglass_ratio: f64,
    /// A warning when the run was not quasi-static (ratio > 5 % or imbalance > 5 %) or the
    /// hourglass energy exceeded 10 % of the internal energy.
    pub warning: Option<String>,
}

/// Element fields at one displacement.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldSnapshot {
    /// Requested total displacement (m).
    pub displacement: f64,
    /// Deformed node positions (m).
    pub nodes: Vec<[f64; 2]>,
    /// Per element, in mesh order.
    pub values: output::ElementFields,
}

/// Outcome of a crush run.
#[derive(Debug, Clone)]
pub struct CrushResult {
    /// Force–displacement samples, starting at (0, 0).
    pub curve: Vec<CurveSample>,
    /// Largest force before fracture (N), the largest of the run when no fracture.
    pub peak_force: f64,
    /// Total displacement at the peak force (m).
    pub peak_displacement: f64,
    /// Fracture displacement (m) when a sustained drop occurred.
    pub fracture_displacement: Option<f64>,
    /// Field snapshots at the requested displacements, in order.
    pub fields: Vec<FieldSnapshot>,
    /// Quasi-static check.
    pub quasi_static: QuasiStatic,
    /// Time steps taken.
    pub steps: u64,
    /// Element count.
    pub elements: usize,
    /// Smallest and largest time step (s).
    pub time_step: (f64, f64),
}

/// The crush test: mesh, state and solver.
pub struct CrushTest {
    /// The set-up.
    pub setup: CrushSetup,
    /// The undeformed mesh.
    pub mesh: Mesh,
    kernel: Kernel,
    /// Current node positions (m).
    pub x: Vec<[f64; 2]>,
    v: Vec<[f64; 2]>,
    inv_mass: Vec<f64>,
    mass: Vec<f64>,
    /// Element states.
    pub states: Vec<ElementState>,
    forces: Vec<[f64; 8]>,
    /// Node → element-force slots (`8e + 2k`, the r component; z follows), CSR, in element
    /// order so the gather sums in a fixed order.
    adj_start: Vec<u32>,
    adj: Vec<u32>,
    f_node: Vec<[f64; 2]>,
    fix_r: Vec<bool>,
    fix_z: Vec<bool>,
    /// The nodes with `fix_z`, ascending (the bottom reaction is summed over them in this order).
    fixed_z: Vec<u32>,
    /// Whether a node lies on the surface (the platens may change its velocity after the
    /// nodal pass), and those nodes once each, ascending: every other node moves in the nodal
    /// pass itself, these after the contact.
    on_surface: Vec<bool>,
    surface_nodes: Vec<u32>,
    platen: contact::Platen,
    /// The bottom platen (plane strain; axisymmetric runs use the equatorial symmetry plane).
    bottom: Option<contact::Platen>,
    /// Time (s).
    pub time: f64,
    dt: f64,
    steps: u64,
    /// 2π for axisymmetric totals.
    scale: f64,
    e_int: f64,
    e_hg: f64,
    e_ext: f64,
}

const CHUNK: usize = 128;
/// Elements whose update halves run back to back (a divisor of CHUNK).
const BLOCK: usize = 4;

/// The element updates of chunk `c` (elements `c·CHUNK…`, states `st`): each block of BLOCK
/// elements runs the first half of the update, then the second ([`element::Kernel::begin`]: the
/// same bits, overlapped); `forces(e, f)` takes element e's internal forces. Returns the chunk's
/// (internal, hourglass) energy increments, or the first inverted element.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn element_chunk(kernel: &element::Kernel, elements: &[[u32; 4]], x: &[[f64; 2]], v: &[[f64; 2]], dt: f64, c: usize, st: &mut [ElementState], mut forces: impl FnMut(usize, [f64; 8])) -> std::result::Result<(f64, f64), usize> {
    let (mut ei, mut eh) = (0.0, 0.0);
    let mut halves = [element::Half::default(); BLOCK];
    for (b, st) in st.chunks_mut(BLOCK).enumerate() {
        let first = c * CHUNK + b * BLOCK;
        for (k, (st, h)) in st.iter_mut().zip(halves.iter_mut()).enumerate() {
            let conn = elements[first + k];
            let xe = conn.map(|i| x[i as usize]);
            let ve = conn.map(|i| v[i as usize]);
            *h = kernel.begin(&xe, &ve, st, dt).ok_or(first + k)?;
        }
        for (k, (st, h)) in st.iter_mut().zip(&halves).enumerate() {
            let (f, a, b) = kernel.finish(h, st);
            forces(first + k, f);
            ei += a;
            eh += b;
        }
    }
    Ok((ei, eh))
}

impl CrushTest {
    /// Builds the mesh and the initial state; errors before any step runs.
    pub fn new(setup: CrushSetup, file: &str) -> Result<Self> {
        setup.validate(file)?;
        let mesh = setup.mesh(file)?;
        let axisymmetric = setup.kinematics == Kinematics::Axisymmetric;
        Self::with_mesh(setup, mesh, axisymmetric)
    }

    /// A test on a given mesh (axisymmetric when `axisymmetric`).
    pub fn with_mesh(setup: CrushSetup, mesh: Mesh, axisymmetric: bool) -> Result<Self> {
        let material = setup.material.build();
        let density = material.density();
        let kernel = Kernel {
            material,
            axisymmetric,
            hourglass: setup.solver.hourglass,
            q_linear: setup.solver.bulk_viscosity_linear,
            q_quadratic: setup.solver.bulk_viscosity_quadratic,
            needs_rate: matches!(setup.material, MaterialParams::Jh2(j) if j.c > 0.0),
            density,
            wave_speed: (material.wave_modulus(0.0) / density).sqrt(),
            small_strain: setup.solver.small_strain,
        };
        let nn = mesh.nodes.len();
        let ne = mesh.elements.len();
        let mut mass = vec![0.0; nn];
        let mut states = vec![ElementState::default(); ne];
        for (e, conn) in mesh.elements.iter().enumerate() {
            let x = conn.map(|i| mesh.nodes[i as usize]);
            let g = element::geometry(&x, axisymmetric)
                .ok_or_else(|| Error::config("<mesh>", "mesh", format!("element {e} has a non-positive area")))?;
            states[e].v0 = g.area * g.rc;
            for &i in conn {
                mass[i as usize] += 0.25 * density * setup.solver.mass_scaling * g.area * g.rc;
            }
        }
        let inv_mass = mass.iter().map(|m| 1.0 / m).collect();
        // Node adjacency in element order (deterministic gather).
        let mut count = vec![0u32; nn + 1];
        for conn in &mesh.elements {
            for &i in conn {
                count[i as usize + 1] += 1;
            }
        }
        for i in 0..nn {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut adj = vec![0u32; 4 * ne];
        for (e, conn) in mesh.elements.iter().enumerate() {
            for (k, &i) in conn.iter().enumerate() {
                adj[fill[i as usize] as usize] = (8 * e + 2 * k) as u32;
                fill[i as usize] += 1;
            }
        }
        let mut fix_r = vec![false; nn];
        let mut fix_z = vec![false; nn];
        // Axisymmetric: v_r = 0 on the axis. Plane strain: the centre node is held in x against
        // rigid sliding between frictionless platens.
        for &i in &mesh.axis {
            fix_r[i as usize] = true;
        }
        for &i in &mesh.equator {
            fix_z[i as usize] = true;
        }
        let top = mesh.surface.iter().map(|&i| mesh.nodes[i as usize][1]).fold(f64::MIN, f64::max);
        let low = mesh.surface.iter().map(|&i| mesh.nodes[i as usize][1]).fold(f64::MAX, f64::min);
        let transit = setup.diameter / kernel.wave_speed;
        let (speed, ramp, mu) = (setup.platen.speed, setup.platen.ramp_transits * transit, setup.platen.friction);
        let platen = contact::Platen::new(top, speed, ramp, mu);
        let bottom = (!axisymmetric).then(|| contact::Platen::bottom(low, speed, ramp, mu));
        let x = mesh.nodes.clone();
        let mut on_surface = vec![false; nn];
        for &i in &mesh.surface {
            on_surface[i as usize] = true;
        }
        let surface_nodes = (0..nn as u32).filter(|&i| on_surface[i as usize]).collect();
        let mut t = CrushTest {
            kernel,
            x,
            v: vec![[0.0; 2]; nn],
            inv_mass,
            mass,
            states,
            forces: vec![[0.0; 8]; ne],
            adj_start: count,
            adj,
            f_node: vec![[0.0; 2]; nn],
            fixed_z: (0..nn as u32).filter(|&i| fix_z[i as usize]).collect(),
            on_surface,
            surface_nodes,
            fix_r,
            fix_z,
            platen,
            bottom,
            time: 0.0,
            dt: 0.0,
            steps: 0,
            scale: if axisymmetric { 2.0 * std::f64::consts::PI } else { 1.0 },
            e_int: 0.0,
            e_hg: 0.0,
            e_ext: 0.0,
            setup,
            mesh,
        };
        t.dt = t.stable_step();
        if !(t.dt > 0.0 && t.dt.is_finite()) {
            return Err(Error::numerical("crush FE", format!("no stable time step (got {:e} s)", t.dt)));
        }
        Ok(t)
    }

    /// `safety ×` the smallest element step (s).
    pub fn stable_step(&self) -> f64 {
        let ms = self.setup.solver.mass_scaling;
        let min = self
            .mesh
            .elements
            .par_iter()
            .zip(self.states.par_iter())
            .with_min_len(CHUNK)
            .map(|(conn, st)| self.kernel.critical_step(&conn.map(|i| self.x[i as usize]), st, ms))
            .reduce(|| f64::MAX, f64::min);
        self.setup.solver.safety * min
    }

    /// Current time step (s).
    pub fn time_step(&self) -> f64 {
        self.dt
    }

    /// Current total crush displacement δ_tot = 2u (m).
    pub fn displacement(&self) -> f64 {
        2.0 * self.platen.displacement(self.time)
    }

    /// Kinetic energy of the whole body (J).
    pub fn kinetic_energy(&self) -> f64 {
        self.scale * 0.5 * self.v.iter().zip(&self.mass).map(|(v, m)| m * (v[0] * v[0] + v[1] * v[1])).sum::<f64>()
    }

    /// (internal, hourglass, external work) energies so far (J).
    pub fn energies(&self) -> (f64, f64, f64) {
        (self.scale * self.e_int, self.scale * self.e_hg, self.scale * self.e_ext)
    }

    /// Sets the node velocities (verification runs: rigid-body motion, free vibration).
    pub fn set_velocities(&mut self, f: impl Fn([f64; 2]) -> [f64; 2]) {
        for (v, x) in self.v.iter_mut().zip(&self.x) {
            *v = f(*x);
        }
    }

    /// Overrides the time-step safety factor without validation: only for tests of the failure
    /// path (a factor above 1 makes the run unstable).
    pub fn override_safety(&mut self, safety: f64) {
        self.setup.solver.safety = safety;
        self.dt = self.stable_step();
    }

    /// Disables the platen (free-body verification runs) and, when `free`, the symmetry
    /// conditions too.
    pub fn detach_platen(&mut self, free: bool) {
        self.platen.active = false;
        if let Some(b) = self.bottom.as_mut() {
            b.active = false;
        }
        if free {
            self.fix_r.iter_mut().for_each(|f| *f = false);
            self.fix_z.iter_mut().for_each(|f| *f = false);
            self.fixed_z.clear();
        }
    }

    /// One explicit step; returns the (top platen impulse, bottom impulse) of the step per
    /// radian (N s) or per unit thickness (N s/m); the bottom is the equatorial reaction of an
    /// axisymmetric run and the bottom platen of a plane-strain run.
    pub fn step(&mut self) -> Result<(f64, f64)> {
        if self.steps > 0 && self.steps.is_multiple_of(self.setup.solver.step_interval as u64) {
            self.dt = self.stable_step();
        }
        let dt = self.dt;
        // 1. Element pass: stresses at t from the velocities of the last half step, in chunks
        //    of CHUNK elements (energies summed per chunk, then over the chunks in order).
        // 2. Nodal forces, summed over each node's elements in element order, velocities, and
        //    the positions of the nodes off the surface (no contact can change their velocity).
        // A run that has its thread to itself (one thread, or one run of a full batch of runs)
        // adds each element's forces into its nodes as it goes; otherwise the elements' forces
        // are stored and each node gathers its own, in parallel. Both sum in element order: the
        // same bits.
        let kernel = self.kernel;
        let x = if kernel.small_strain { &self.mesh.nodes } else { &self.x };
        let v = &self.v;
        let elements = &self.mesh.elements;
        let (inv_mass, fix_r, fix_z) = (&self.inv_mass, &self.fix_r, &self.fix_z);
        let velocity = |i: usize, s: [f64; 2], vi: &mut [f64; 2]| {
            let w = inv_mass[i];
            vi[0] = if fix_r[i] { 0.0 } else { vi[0] + dt * s[0] * w };
            vi[1] = if fix_z[i] { 0.0 } else { vi[1] + dt * s[1] * w };
        };
        let on_surface = &self.on_surface;
        let mv = |i: usize, vi: &[f64; 2], xi: &mut [f64; 2]| {
            if !on_surface[i] {
                xi[0] += dt * vi[0];
                xi[1] += dt * vi[1];
            }
        };
        let inverted = |e: usize, steps: u64, time: f64| Error::numerical("crush FE", format!("step {steps}: element {e} inverted (non-positive Jacobian) at t = {time:.4e} s"));
        if crate::model::alone_on_thread() {
            let f_node = &mut self.f_node;
            f_node.fill([0.0; 2]);
            for (c, st) in self.states.chunks_mut(CHUNK).enumerate() {
                let (ei, eh) = element_chunk(&kernel, elements, x, v, dt, c, st, |e, f| {
                    for (k, &i) in elements[e].iter().enumerate() {
                        let n = &mut f_node[i as usize];
                        n[0] -= f[2 * k];
                        n[1] -= f[2 * k + 1];
                    }
                })
                .map_err(|e| inverted(e, self.steps, self.time))?;
                self.e_int += ei;
                self.e_hg += eh;
            }
            for (i, ((s, vi), xi)) in self.f_node.iter().zip(self.v.iter_mut()).zip(self.x.iter_mut()).enumerate() {
                velocity(i, *s, vi);
                mv(i, vi, xi);
            }
        } else {
            let partial: Vec<std::result::Result<(f64, f64), usize>> = self
                .states
                .par_chunks_mut(CHUNK)
                .zip(self.forces.par_chunks_mut(CHUNK))
                .enumerate()
                .map(|(c, (st, fo))| element_chunk(&kernel, elements, x, v, dt, c, st, |e, f| fo[e - c * CHUNK] = f))
                .collect();
            for p in partial {
                let (a, b) = p.map_err(|e| inverted(e, self.steps, self.time))?;
                self.e_int += a;
                self.e_hg += b;
            }
            let (adj, start) = (&self.adj, &self.adj_start);
            let flat: &[f64] = self.forces.as_flattened();
            self.f_node.par_iter_mut().zip(self.v.par_iter_mut()).zip(self.x.par_iter_mut()).enumerate().with_min_len(4 * CHUNK).for_each(|(i, ((f, vi), xi))| {
                let mut s = [0.0; 2];
                for &slot in &adj[start[i] as usize..start[i + 1] as usize] {
                    let pair = &flat[slot as usize..slot as usize + 2];
                    s[0] -= pair[0];
                    s[1] -= pair[1];
                }
                *f = s;
                velocity(i, s, vi);
                mv(i, vi, xi);
            });
        }
        // 3. Constraints, contact, the surface nodes' positions. The held nodes' reaction in
        //    node order.
        let mut bottom = 0.0;
        for &i in &self.fixed_z {
            bottom -= self.f_node[i as usize][1] * dt;
        }
        let t_new = self.time + dt;
        let top = if self.platen.active { self.platen.constrain(t_new, dt, &self.mesh.surface, &self.x, &mut self.v, &self.mass, &self.fix_r) } else { 0.0 };
        if let Some(b) = self.bottom.filter(|b| b.active) {
            bottom = b.constrain(t_new, dt, &self.mesh.surface, &self.x, &mut self.v, &self.mass, &self.fix_r);
        }
        // External work: each platen's impulse times its speed over the step.
        let speed = self.platen.velocity(self.time + 0.5 * dt);
        self.e_ext += top * speed + if self.bottom.is_some() { bottom * speed } else { 0.0 };
        for &i in &self.surface_nodes {
            let (xi, vi) = (&mut self.x[i as usize], self.v[i as usize]);
            xi[0] += dt * vi[0];
            xi[1] += dt * vi[1];
        }
        self.time = t_new;
        self.steps += 1;
        Ok((top, bottom))
    }

    /// Runs the crush to the maximum displacement or past fracture.
    pub fn run(&mut self, progress: Option<&indicatif::ProgressBar>) -> Result<CrushResult> {
        crate::model::on_pool(|| self.run_on_this_thread(progress))
    }

    fn run_on_this_thread(&mut self, progress: Option<&indicatif::ProgressBar>) -> Result<CrushResult> {
        let p = self.setup.platen;
        let dmax = p.max_displacement;
        let interval = dmax / self.setup.solver.samples as f64;
        let mut curve = vec![CurveSample::default()];
        let mut fields = Vec::new();
        let mut pending: Vec<f64> = self.setup.fields_at.clone();
        pending.sort_by(f64::total_cmp);
        pending.dedup();
        let mut detector = output::FractureDetector::new(self.setup.fracture);
        let (mut imp_top, mut imp_bot, mut t0, mut d0) = (0.0, 0.0, self.time, self.displacement());
        let (mut dt_min, mut dt_max) = (f64::MAX, 0.0f64);
        let mut stop_at = dmax;
        loop {
            let (a, b) = self.step()?;
            dt_min = dt_min.min(self.dt);
            dt_max = dt_max.max(self.dt);
            imp_top += a;
            imp_bot += b;
            let d = self.displacement();
            while let Some(&target) = pending.first() {
                if d >= target {
                    fields.push(self.snapshot(target));
                    pending.remove(0);
                } else {
                    break;
                }
            }
            if d - d0 >= interval || d >= stop_at {
                let span = self.time - t0;
                let (ei, eh, ee) = self.energies();
                let s = CurveSample {
                    time: self.time,
                    displacement: 0.5 * (d + d0),
                    force: self.scale * imp_top / span,
                    force_bottom: self.scale * imp_bot / span,
                    kinetic: self.kinetic_energy(),
                    internal: ei,
                    hourglass: eh,
                    external: ee,
                };
                self.check_sample(&s)?;
                curve.push(s);
                if let Some(pb) = progress {
                    pb.set_position((1000.0 * d / dmax).min(1000.0) as u64);
                }
                if let Some(df) = detector.push(s.displacement, s.force)
                    && stop_at == dmax
                {
                    stop_at = (df * (1.0 + self.setup.fracture.run_on)).max(s.displacement + interval).min(dmax);
                }
                imp_top = 0.0;
                imp_bot = 0.0;
                t0 = self.time;
                d0 = d;
                if d >= stop_at {
                    break;
                }
            }
        }
        let (peak_force, peak_displacement, fracture_displacement) = detector.result();
        let transit = self.setup.diameter / self.kernel.wave_speed;
        let quasi_static = output::quasi_static(&curve, peak_force, peak_displacement, p.ramp_transits * transit, 2.0 * transit);
        Ok(CrushResult {
            curve,
            peak_force,
            peak_displacement,
            fracture_displacement,
            fields,
            quasi_static,
            steps: self.steps,
            elements: self.mesh.elements.len(),
            time_step: (dt_min, dt_max),
        })
    }

    fn check_sample(&self, s: &CurveSample) -> Result<()> {
        let finite = [s.force, s.force_bottom, s.kinetic, s.internal, s.hourglass, s.external].iter().all(|v| v.is_finite());
        if !finite {
            let node = self.v.iter().position(|v| !(v[0].is_finite() && v[1].is_finite()));
            let elem = self.states.iter().position(|st| !st.point.stress().iter().all(|v| v.is_finite()));
            return Err(Error::numerical(
                "crush FE",
                format!("step {}: non-finite state (first bad node {node:?}, element {elem:?}) at δ = {:.3e} m", self.steps, s.displacement),
            ));
        }
        // Energy blow-up: kinetic energy far above the work put in.
        if s.kinetic > 10.0 * s.external.abs() + 1e-9 {
            return Err(Error::numerical(
                "crush FE",
                format!("step {}: energy blow-up, kinetic energy {:.3e} J against platen work {:.3e} J (unstable time step?)", self.steps, s.kinetic, s.external),
            ));
        }
        Ok(())
    }

    /// Element fields now.
    pub fn snapshot(&self, displacement: f64) -> FieldSnapshot {
        FieldSnapshot {
            displacement,
            nodes: self.x.clone(),
            values: output::ElementFields::compute(&self.mesh, &self.x, &self.states, self.kernel.axisymmetric),
        }
    }
}

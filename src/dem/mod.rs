//! Native DEM: spheres with Hertz–Mindlin contacts flowing through a tube bank.
//!
//! * [`contact`]: the Hertz–Mindlin law with history, restitution-based damping, rolling resistance;
//! * [`geometry`]: slab periodic along the tubes, side walls, exact cylindrical tubes;
//! * [`grid`]: cell grid with sorted cells and a Verlet half neighbour list rebuilt by a skin
//!   criterion;
//! * [`particles`]: structure-of-arrays storage;
//! * [`probe`]: impacts at first contact, profiles, maps, passes, the traced force history;
//! * [`vtk`]: particle snapshots as VTK PolyData (`.vtp`);
//! * [`model`]: [`model::TubeBankModel`], the tube bank as a [`crate::model::Simulator`];
//! * [`run`]: the `kind = "dem"` study.
//!
//! # Time integration
//!
//! Velocity Verlet (kick–drift–kick), second order and exact for constant forces:
//! v ← v + ½Δt F/m, x ← x + Δt v, F ← F(x, v), v ← v + ½Δt F/m, and likewise for ω with the
//! torque and the sphere's moment of inertia 0.4 m r². The velocity-dependent parts of the
//! contact force (damping, tangential spring increment, rolling torque) see the predicted
//! end-of-step velocity v(t) + Δt a(t) rather than the half-step velocity LIGGGHTS uses: this
//! makes the dissipated energy second-order accurate, so the measured restitution stays within
//! 1 % of the set value at the default step (with the half-step velocity it drifts to −1.3 % at
//! e = 0.5 and 20 steps per contact). Conservative forces depend on positions only, so the
//! scheme stays symplectic for e = 1, μ = 0.
//!
//! # Stable time step
//!
//! Δt must not exceed `Δt_limit = min(0.2 T_R, t_c / 10)`: 20 % of the Rayleigh time
//! `T_R = π r_min √(ρ/G) / (0.1631 ν + 0.8766)` of the smallest particle (the usual DEM
//! practice), and a tenth of the shortest Hertz contact duration at the largest expected impact
//! speed (`max_speed`), so that every collision spans at least ten steps. When no step is given
//! the solver takes `0.5 Δt_limit` (safety factor 0.5).
//!
//! # Reduced stiffness
//!
//! The step scales as E^(−2/5): running with E = 10⁸ Pa instead of 112 GPa is 17× faster. The
//! contact duration and overlap grow (t_c ∝ E^(−2/5), δ ∝ E^(−2/5)) but, with the restitution
//! set independently, the rebound velocities — and so the impact-velocity statistics of a
//! collisional flow — barely change: the test suite checks that the impact-velocity quantiles
//! move by less than 5 % when E is raised tenfold. Peak forces do change (F ∝ E^(2/5)); partlife
//! therefore takes impact *velocities* from the DEM and computes forces with the true modulus
//! (Hertz, [`crate::contact::Impact`]).
//!
//! # Determinism
//!
//! Forces are computed in parallel over fixed blocks of particles; each block owns its
//! particles' forces and pair histories and returns the reactions on its neighbours, bucketed by
//! the neighbour's block. Each block then adds the reactions on its particles from every earlier
//! block and itself, in block order, so every particle's force is summed in the same order on
//! any thread count: trajectories are bit-identical for any thread count.
//!
//! That addition and the step's closing half kick are deferred to the next step's opening pass
//! (the same arithmetic in the same order, one pass over the arrays fewer); [`Dem::settle`]
//! applies them wherever velocities or forces are read: before a field sample, at the end of
//! [`Dem::step`] and of [`Dem::advance`].

pub mod contact;
pub mod geometry;
pub mod grid;
pub mod model;
pub mod particles;
pub mod probe;
pub mod run;
pub mod vec3;
pub mod vtk;
mod forces;
mod lifecycle;
mod setup;

use forces::*;
pub use setup::*;


use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{Error, Result};
use contact::{PairLaw, hertz_energy};
use grid::{BLOCK, Grid, History, NeighbourList, PARALLEL_BLOCKS, blocks_per_task, sort_by_cell};
use particles::{Particles, WallSlot};
use probe::{FlowSample, Fields, Impact, Pass, Target, TraceSample};
use vec3::{V3, dot, norm, sub};

/// What a force block returns. Aligned to two cache lines so that blocks on different threads
/// never write the same line (their vectors' lengths and the worst overlap live here).
#[derive(Debug, Clone, Default)]
#[repr(align(128))]
struct BlockOut {
    /// Reactions (particle, force, torque) on later particles, bucketed by the target's block
    /// minus this block.
    reactions: Vec<Vec<(u32, V3, V3)>>,
    impacts: Vec<(Impact, u32, u32, f64, f64)>,
    trace: Vec<TraceSample>,
    trace_ended: bool,
    worst_overlap: Option<(f64, u32)>,
}

/// Counters of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Counters {
    /// Neighbour-list builds.
    pub builds: u64,
    /// Particles inserted.
    pub inserted: u64,
    /// Particles that could not be placed when due (deferred to the next build).
    pub deferred_insertions: u64,
    /// Particles that left through the outlet.
    pub exited: u64,
    /// Sum over steps of the particle count (particle-steps).
    pub particle_steps: u64,
}

/// A DEM simulation.
#[derive(Clone)]
pub struct Dem {
    /// Its set-up.
    pub setup: DemSetup,
    pp: PairLaw,
    pw: PairLaw,
    grid: Grid,
    /// Particles.
    pub p: Particles,
    /// The arrays a rebuild gathers into (then swapped with `p`), kept for their capacity.
    spare: Particles,
    /// The cell sort's counts and starts, kept for its capacity.
    cell_buf: Vec<u32>,
    nl: NeighbourList,
    /// Simulated time (s).
    pub time: f64,
    /// Steps taken.
    pub step: u64,
    rng: ChaCha8Rng,
    next_id: u64,
    next_diameter: f64,
    steps_since_build: u64,
    primed: bool,
    /// Mass inserted (kg).
    pub inflow_mass: f64,
    /// Mass that left through the outlet (kg).
    pub outflow_mass: f64,
    /// Outlet mass after the warm-up (kg).
    pub outflow_mass_measured: f64,
    /// Impacts after the warm-up.
    pub impacts: Vec<Impact>,
    /// Passes completed (particle left through the outlet) after the warm-up, with the impacts
    /// counted since the particle's insertion.
    pub passes: Vec<Pass>,
    /// Field accumulators.
    pub fields: Fields,
    /// Hold-up and flow, at every field sample.
    pub flow: Vec<FlowSample>,
    /// The traced impact: (particle id, wall id, time of first contact, normal velocity).
    trace_target: Option<(u64, u32, f64, f64)>,
    /// The traced impact's force history (empty until one happened).
    pub trace: Vec<TraceSample>,
    trace_done: bool,
    reduce_seconds: f64,
    block_out: Vec<BlockOut>,
    /// Largest block offset of a reaction in `block_out`.
    reach: usize,
    /// The last force evaluation's reactions are not yet added to `p.force`/`p.torque`.
    pending_reactions: bool,
    /// The last step's closing half kick is not yet applied to `p.vel`/`p.omega`.
    pending_kick: bool,
    /// Force evaluations so far (pair-contact epoch, see [`grid::PairState`]).
    epoch: u32,
    /// Counters.
    pub counters: Counters,
    /// Wall time per phase (s): kick–drift (with the previous evaluation's reactions and closing
    /// kick), position check, neighbour rebuild, force blocks, serial bookkeeping of impacts,
    /// settling (reactions and closing kick, where a sample or the end of a run needs them) and
    /// sampling.
    pub phase_seconds: [f64; 6],
}

impl Dem {
    /// A simulation of a validated set-up (validation is repeated here; `file` names the study).
    pub fn new(setup: DemSetup, file: &str) -> Result<Self> {
        setup.validate(file)?;
        let pp = PairLaw::new(&setup.particle, &setup.particle, &setup.particle_particle);
        let pw = PairLaw::new(&setup.particle, &setup.wall, &setup.particle_wall);
        let d_max = setup.diameters.max();
        let skin = setup.skin();
        let grid = Grid::new(&setup.geometry, d_max + skin, d_max / 2.0 + skin);
        let mut rng = ChaCha8Rng::seed_from_u64(setup.seed);
        let next_diameter = setup.diameters.sample(&mut rng);
        let g = &setup.geometry;
        let pr = setup.probes;
        let z_top = setup.inlet.map(|i| i.z_hi).unwrap_or(g.z_hi);
        let fields = Fields::new((g.x_lo, g.x_hi), (g.outlet_z.unwrap_or(g.z_lo), z_top), pr.profile_bins, pr.map_nx, pr.map_nz);
        Ok(Dem {
            setup,
            pp,
            pw,
            grid,
            p: Particles::default(),
            spare: Particles::default(),
            cell_buf: Vec::new(),
            nl: NeighbourList::default(),
            time: 0.0,
            step: 0,
            rng,
            next_id: 0,
            next_diameter,
            steps_since_build: 0,
            primed: false,
            inflow_mass: 0.0,
            outflow_mass: 0.0,
            outflow_mass_measured: 0.0,
            impacts: Vec::new(),
            passes: Vec::new(),
            fields,
            flow: Vec::new(),
            trace_target: None,
            trace: Vec::new(),
            trace_done: false,
            reduce_seconds: 0.0,
            block_out: Vec::new(),
            reach: 0,
            pending_reactions: false,
            pending_kick: false,
            epoch: 0,
            counters: Counters::default(),
            phase_seconds: [0.0; 6],
        })
    }

    /// Normal velocity of the traced tube impact, once one happened (m/s).
    pub fn trace_velocity(&self) -> Option<f64> {
        self.trace_target.map(|t| t.3)
    }

    /// Places a particle by hand (verification set-ups); returns its id.
    pub fn add_particle(&mut self, pos: V3, vel: V3, diameter: f64) -> u64 {
        let id = self.next_id;
        self.next_id += 1;
        self.p.push(id, pos, vel, diameter / 2.0, self.setup.particle.density, self.setup.rotation, self.time);
        self.primed = false;
        id
    }

    /// Storage index of a particle id (indices change at every neighbour-list build).
    pub fn index_of(&self, id: u64) -> Option<usize> {
        self.p.id.iter().position(|&x| x == id)
    }

    /// The pair laws (particle–particle, particle–wall).
    pub fn laws(&self) -> (PairLaw, PairLaw) {
        (self.pp, self.pw)
    }

    /// Total mechanical energy: kinetic + Hertz elastic (pairs and walls) − gravity work (J).
    /// Exact only for e = 1 and μ = 0.
    pub fn energy(&self) -> f64 {
        debug_assert!(!self.pending_reactions && !self.pending_kick, "read between settled steps");
        let p = &self.p;
        let mut e = p.kinetic_energy();
        let gvec = self.setup.gravity;
        let slab = self.setup.geometry.slab;
        for i in 0..p.len() {
            e -= p.mass[i] * dot(gvec, p.pos[i]);
            for &j in self.nl.row(i).0 {
                let j = j as usize;
                let mut d = sub(p.pos[i], p.pos[j]);
                d[1] = min_image(d[1], slab);
                let delta = p.radius[i] + p.radius[j] - norm(d);
                if delta > 0.0 {
                    let rs = p.radius[i] * p.radius[j] / (p.radius[i] + p.radius[j]);
                    e += hertz_energy(&self.pp, rs, delta);
                }
            }
            for w in 0..self.setup.geometry.wall_count() {
                if let Some((delta, _, rs, _, _)) = wall_contact(&self.setup.geometry, w as u32, p.pos[i], p.radius[i]) {
                    e += hertz_energy(&self.pw, rs, delta);
                }
            }
        }
        e
    }


    /// Advances `n` steps; velocities and forces are complete when it returns.
    pub fn advance(&mut self, n: u64) -> Result<()> {
        crate::model::on_pool(|| {
            for _ in 0..n {
                self.step_deferred()?;
            }
            self.settle_timed();
            Ok(())
        })
    }

    /// One velocity-Verlet step; velocities and forces are complete when it returns.
    pub fn step(&mut self) -> Result<()> {
        self.advance(1)
    }

    /// Adds the pending reactions and applies the pending closing half kick, in parallel over
    /// the force blocks (the same arithmetic the next step's opening pass would do).
    pub fn settle(&mut self) {
        if !self.pending_reactions && !self.pending_kick {
            return;
        }
        let pending = Pending { outs: &self.block_out, reach: self.reach, reactions: self.pending_reactions, close: self.pending_kick, half: 0.5 * self.setup.time_step };
        let per_task = blocks_per_task(self.p.len().div_ceil(BLOCK));
        let p = &mut self.p;
        p.vel
            .par_chunks_mut(BLOCK)
            .zip(p.omega.par_chunks_mut(BLOCK))
            .zip(p.force.par_chunks_mut(BLOCK))
            .zip(p.torque.par_chunks_mut(BLOCK))
            .zip(p.mass.par_chunks(BLOCK))
            .zip(p.inv_inertia.par_chunks(BLOCK))
            .enumerate()
            .with_min_len(per_task)
            .for_each(|(b, (((((vs, ws), fs), ts), ms), iis))| pending.apply(b, vs, ws, fs, ts, ms, iis));
        self.pending_reactions = false;
        self.pending_kick = false;
    }

    /// [`Self::settle`], its time counted with the closing kick and sampling.
    fn settle_timed(&mut self) {
        let t0 = std::time::Instant::now();
        self.settle();
        self.phase_seconds[5] += t0.elapsed().as_secs_f64();
    }

    /// One step leaving the reactions and the closing half kick pending.
    fn step_deferred(&mut self) -> Result<()> {
        if !self.primed {
            debug_assert!(!self.pending_reactions && !self.pending_kick);
            self.p.vel_pred.clone_from(&self.p.vel);
            self.p.omega_pred.clone_from(&self.p.omega);
            self.rebuild()?;
            self.compute_forces()?;
            self.primed = true;
        }
        let dt = self.setup.time_step;
        let half = 0.5 * dt;
        let slab = self.setup.geometry.slab;
        let skin2 = (0.5 * self.setup.skin()).powi(2);
        // (Reactions and closing kick of the last step,) kick + drift, and the largest
        // displacement since the last build.
        let t0 = std::time::Instant::now();
        let bounds = self.escape_bounds();
        let pending = Pending { outs: &self.block_out, reach: self.reach, reactions: self.pending_reactions, close: self.pending_kick, half: 0.5 * self.setup.time_step };
        let per_task = blocks_per_task(self.p.len().div_ceil(BLOCK));
        let p = &mut self.p;
        // Fixed blocks of plain loops over slices (the compiler keeps them tight; rayon only
        // distributes blocks).
        let max_disp2 = p
            .pos
            .par_chunks_mut(BLOCK)
            .zip(p.vel.par_chunks_mut(BLOCK))
            .zip(p.omega.par_chunks_mut(BLOCK))
            .zip(p.vel_pred.par_chunks_mut(BLOCK))
            .zip(p.omega_pred.par_chunks_mut(BLOCK))
            .zip(p.force.par_chunks_mut(BLOCK))
            .zip(p.torque.par_chunks_mut(BLOCK))
            .zip(p.mass.par_chunks(BLOCK))
            .zip(p.inv_inertia.par_chunks(BLOCK))
            .zip(p.pos_at_build.par_chunks(BLOCK))
            .enumerate()
            .with_min_len(per_task)
            .map(|(blk, (((((((((xs, vs), ws), vps), wps), fs), ts), ms), iis), x0s))| {
                // The last step's reactions, then per particle its closing kick and this step's
                // opening kick (the same factors).
                pending.add_reactions(blk, fs, ts);
                let mut worst = 0.0f64;
                for k in 0..xs.len() {
                    let (x, v, w, f, t) = (&mut xs[k], &mut vs[k], &mut ws[k], fs[k], ts[k]);
                    let (a, b) = (half / ms[k], half * iis[k]);
                    if pending.close {
                        kick(v, w, f, t, a, b);
                    }
                    kick(v, w, f, t, a, b);
                    // End-of-step prediction v(t) + Δt a(t) for the velocity-dependent forces.
                    vps[k] = [v[0] + a * f[0], v[1] + a * f[1], v[2] + a * f[2]];
                    wps[k] = [w[0] + b * t[0], w[1] + b * t[1], w[2] + b * t[2]];
                    x[0] += dt * v[0];
                    x[1] += dt * v[1];
                    x[2] += dt * v[2];
                    if x[1] >= slab {
                        x[1] -= slab;
                    } else if x[1] < 0.0 {
                        x[1] += slab;
                    }
                    let x0 = x0s[k];
                    let mut dy = x[1] - x0[1];
                    if dy > 0.5 * slab {
                        dy -= slab;
                    } else if dy < -0.5 * slab {
                        dy += slab;
                    }
                    let d2 = (x[0] - x0[0]).powi(2) + dy * dy + (x[2] - x0[2]).powi(2);
                    // A particle that may have left the domain (or a NaN) flags the step for
                    // the exact serial check below.
                    let inside = x[0] >= bounds.0 && x[0] <= bounds.1 && x[2] >= bounds.2 && x[2] <= bounds.3;
                    worst = if inside && d2 <= f64::MAX { worst.max(d2) } else { f64::INFINITY };
                }
                worst
            })
            .reduce(|| 0.0, f64::max);
        self.pending_reactions = false;
        self.pending_kick = false;
        self.time += dt;
        self.step += 1;
        self.steps_since_build += 1;
        let t1 = std::time::Instant::now();
        if max_disp2 == f64::INFINITY {
            self.check_positions()?;
        }
        let t2 = std::time::Instant::now();
        if max_disp2 > skin2 || self.steps_since_build >= self.setup.max_rebuild_steps {
            self.rebuild()?;
        }
        let t3 = std::time::Instant::now();
        self.compute_forces()?;
        self.pending_kick = true;
        let t5 = std::time::Instant::now();
        self.counters.particle_steps += self.p.len() as u64;
        if self.time >= self.setup.probes.warmup && self.step.is_multiple_of(self.setup.probes.sample_every) {
            self.settle();
            self.sample();
        }
        let t6 = std::time::Instant::now();
        let ph = &mut self.phase_seconds;
        ph[0] += (t1 - t0).as_secs_f64();
        ph[1] += (t2 - t1).as_secs_f64();
        ph[2] += (t3 - t2).as_secs_f64();
        ph[3] += (t5 - t3).as_secs_f64() - self.reduce_seconds;
        ph[4] += self.reduce_seconds;
        ph[5] += (t6 - t5).as_secs_f64();
        Ok(())
    }

    fn compute_forces(&mut self) -> Result<()> {
        let nblocks = self.p.len().div_ceil(BLOCK);
        self.epoch += 1;
        let ctx = Ctx {
            epoch: self.epoch,
            pos: &self.p.pos,
            vel: &self.p.vel_pred,
            omega: &self.p.omega_pred,
            radius: &self.p.radius,
            mass: &self.p.mass,
            id: &self.p.id,
            start: &self.nl.start,
            cell_of: &self.nl.cell_of,
            grid: &self.grid,
            geom: &self.setup.geometry,
            pp: &self.pp,
            pw: &self.pw,
            dt: self.setup.time_step,
            time: self.time,
            gravity: self.setup.gravity,
            min_v: self.setup.probes.min_impact_velocity,
            max_overlap: self.setup.max_overlap_fraction,
            trace: if self.trace_done { None } else { self.trace_target.map(|(id, w, _, _)| (id, w)) },
        };
        // Per-block output buffers are kept between steps: reallocating them every step costs
        // page faults that serialise the threads.
        let mut outs = std::mem::take(&mut self.block_out);
        outs.resize_with(nblocks, BlockOut::default);
        self.p
            .force
            .par_chunks_mut(BLOCK)
            .zip(self.p.torque.par_chunks_mut(BLOCK))
            .zip(self.p.walls.par_chunks_mut(BLOCK))
            .zip(self.nl.blocks.par_iter_mut())
            .zip(outs.par_iter_mut())
            .enumerate()
            // One block per task (or all in one on a small system): rayon's default leaves of
            // many blocks balance badly when the contact density varies with height.
            .with_min_len(blocks_per_task(nblocks))
            .with_max_len(blocks_per_task(nblocks))
            .for_each(|(b, ((((f, t), w), s), out))| ctx.block(b * BLOCK, f, t, w, s, out));
        // Serial bookkeeping in block order (the reactions wait for the next parallel pass).
        let tr = std::time::Instant::now();
        let mut worst: Option<(f64, u32)> = None;
        self.reach = 0;
        for out in &outs {
            self.reach = self.reach.max(out.reactions.len().saturating_sub(1));
            for &(imp, i, j, delta, fnorm) in &out.impacts {
                match imp.target {
                    Target::Particle => {
                        self.p.n_particle[i as usize] += 1;
                        self.p.n_particle[j as usize] += 1;
                    }
                    Target::Tube => self.p.n_tube[i as usize] += 1,
                    Target::Wall => {}
                }
                if self.time >= self.setup.probes.warmup {
                    if imp.target == Target::Tube && self.trace_target.is_none() && imp.v_normal >= self.setup.probes.trace_min_velocity {
                        self.trace_target = Some((imp.particle, imp.partner as u32, imp.time, imp.v_normal));
                        self.trace.push(TraceSample { time: 0.0, overlap: delta, normal_force: fnorm });
                    }
                    self.impacts.push(imp);
                }
            }
            if let Some((_, _, t0, _)) = self.trace_target {
                for &s in &out.trace {
                    self.trace.push(TraceSample { time: s.time - t0, ..s });
                }
            }
            if out.trace_ended {
                self.trace_done = true;
            }
            if let Some(w) = out.worst_overlap
                && worst.is_none_or(|x| w.0 > x.0)
            {
                worst = Some(w);
            }
        }
        self.block_out = outs;
        self.pending_reactions = true;
        self.reduce_seconds = tr.elapsed().as_secs_f64();
        if let Some((frac, i)) = worst {
            let i = i as usize;
            return Err(Error::numerical(
                "DEM",
                format!(
                    "blow-up at step {} (t = {:.6e} s): particle {} overlaps a neighbour or wall by {:.1} % of its radius (limit {:.0} %); lower the time step, raise the modulus or reduce the inlet velocity",
                    self.step,
                    self.time,
                    self.p.id[i],
                    100.0 * frac,
                    100.0 * self.setup.max_overlap_fraction
                ),
            ));
        }
        Ok(())
    }

    fn sample(&mut self) {
        debug_assert!(!self.pending_kick, "sampled before the closing kick");
        let mut mass = 0.0;
        for i in 0..self.p.len() {
            self.fields.add(self.p.pos[i], self.p.vel[i]);
            mass += self.p.mass[i];
        }
        self.fields.samples += 1;
        self.flow.push(FlowSample {
            time: self.time,
            particles: self.p.len(),
            mass,
            outflow_mass: self.outflow_mass,
            inflow_mass: self.inflow_mass,
        });
    }

    /// Mean coordination number of particles whose centre lies in `region` (x, z bounds),
    /// counting particle–particle contacts only.
    pub fn coordination(&self, x: (f64, f64), z: (f64, f64)) -> (f64, usize) {
        let p = &self.p;
        let slab = self.setup.geometry.slab;
        let mut z_count = vec![0u32; p.len()];
        for i in 0..p.len() {
            for &j in self.nl.row(i).0 {
                let j = j as usize;
                let mut d = sub(p.pos[i], p.pos[j]);
                d[1] = min_image(d[1], slab);
                if norm(d) < p.radius[i] + p.radius[j] {
                    z_count[i] += 1;
                    z_count[j] += 1;
                }
            }
        }
        let inside: Vec<usize> = (0..p.len()).filter(|&i| (x.0..x.1).contains(&p.pos[i][0]) && (z.0..z.1).contains(&p.pos[i][2])).collect();
        let total: u32 = inside.iter().map(|&i| z_count[i]).sum();
        (total as f64 / inside.len().max(1) as f64, inside.len())
    }
}
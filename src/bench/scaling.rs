//! The solvers' speed cases and their scaling over threads (`partlife bench --dem`, `--fem`,
//! `--scaling`): the DEM cold-test bank shared with the LIGGGHTS comparison, the crush FE run to
//! fracture, and the main study end to end, each on the thread counts it is given; one pool per
//! count, so the figures do not depend on rayon's global pool.

use std::path::Path;
use std::time::Instant;

use super::repo_path;
use crate::error::Result;
use crate::io::TempDir;

/// The DEM speed case shared with the LIGGGHTS input in `tests/bench/liggghts/`: the cold-test
/// bank (Ø 25 mm tubes, 5 staggered rows, 125 mm × 5 mm slab), 1 mm particles, ρ = 3600 kg/m³,
/// E = 10⁸ Pa, ν = 0.25, e = 0.7, μ = 0.3, Δt = 2 µs, 200 kg/(m² s) inserted at 0.5 m/s.
pub fn dem_benchmark_setup() -> Result<crate::dem::DemSetup> {
    dem_bank_setup(1.0)
}

/// The large DEM case: the cold-test bank with a slab ten times deeper along the tubes (50 mm)
/// and the same flux per area, so ten times the particles of [`dem_benchmark_setup`] (about
/// 100 000 after 0.15 s).
pub fn dem_deep_bank_setup() -> Result<crate::dem::DemSetup> {
    dem_bank_setup(10.0)
}

/// The benchmark bank with its slab `depth` times the cold test's 5 mm.
fn dem_bank_setup(depth: f64) -> Result<crate::dem::DemSetup> {
    use crate::dem::contact::{Interaction, Material};
    use crate::dem::geometry::{BankSpec, Geometry};
    use crate::dem::{DemSetup, Diameters, Inlet, ProbeSetup};
    let mut bank = BankSpec::cold_test();
    bank.slab *= depth;
    let geometry = Geometry::tube_bank(&bank);
    let m = Material { density: 3600.0, youngs_modulus: 1e8, poisson_ratio: 0.25 };
    let i = Interaction { restitution: 0.7, friction: 0.3, rolling_friction: 0.0 };
    let inlet = Inlet { mass_flux: 200.0, velocity: 0.5, z_lo: geometry.z_hi - 0.015, z_hi: geometry.z_hi };
    let s = DemSetup {
        particle: m,
        wall: m,
        particle_particle: i,
        particle_wall: i,
        diameters: Diameters::Fixed { value: 1e-3 },
        geometry,
        gravity: [0.0, 0.0, -9.81],
        inlet: Some(inlet),
        time_step: 2e-6,
        max_speed: 3.5,
        skin_fraction: 0.25,
        max_rebuild_steps: 200,
        rotation: true,
        max_overlap_fraction: 0.3,
        probes: ProbeSetup { warmup: 1e9, ..ProbeSetup::default() },
        seed: 1,
    };
    s.validate("<dem benchmark>")?;
    Ok(s)
}

/// One DEM speed measurement.
#[derive(Debug, Clone)]
pub struct DemSpeed {
    /// Worker threads.
    pub threads: usize,
    /// Particle-steps per second.
    pub particle_steps_per_second: f64,
    /// Wall time per step and phase (µs): kick–drift (with the previous evaluation's reactions
    /// and closing kick), position check, neighbour rebuild, force blocks, serial bookkeeping of
    /// impacts, settling and sampling.
    pub phase_us: [f64; 6],
    /// Neighbour-list builds during the measurement.
    pub rebuilds: u64,
}

/// A DEM case timed on several thread counts.
#[derive(Debug, Clone)]
pub struct DemScaling {
    /// Particles at the start of timing.
    pub particles: usize,
    /// One measurement per thread count.
    pub speeds: Vec<DemSpeed>,
    /// Whether every count ended in the same state, bit for bit (positions, velocities, angular
    /// velocities, impacts).
    pub identical: bool,
}

/// DEM particle-steps per second of the cold-test bank: fills it for `fill_s` simulated seconds,
/// then times `steps` steps from that state on 1 thread and on all threads.
pub fn dem_particle_steps_per_second(fill_s: f64, steps: u64) -> Result<DemScaling> {
    dem_scaling(dem_benchmark_setup()?, fill_s, steps, &one_and_all())
}

/// 1 and all of rayon's threads (1 alone on one thread).
fn one_and_all() -> Vec<usize> {
    let all = rayon::current_num_threads();
    if all > 1 { vec![1, all] } else { vec![1] }
}

/// The thread counts of a scaling table: 1, 2, 4, … below `max`, and `max`.
pub fn thread_counts(max: usize) -> Vec<usize> {
    let mut c: Vec<usize> = std::iter::successors(Some(1usize), |&k| Some(2 * k)).take_while(|&k| k < max.max(1)).collect();
    c.push(max.max(1));
    c
}

/// A pool of `threads` workers.
fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| crate::Error::numerical("thread pool", e.to_string()))
}

/// `setup` filled for `fill_s` simulated seconds on the most threads of `counts`, then `steps`
/// steps timed from that same state on each count (so every count does the same work), and
/// whether they all end in the same state.
pub fn dem_scaling(setup: crate::dem::DemSetup, fill_s: f64, steps: u64, counts: &[usize]) -> Result<DemScaling> {
    let mut filled = crate::dem::Dem::new(setup, "<dem benchmark>")?;
    let fill_steps = (fill_s / filled.setup.time_step).round() as u64;
    pool(counts.iter().copied().max().unwrap_or(1))?.install(|| filled.advance(fill_steps))?;
    let particles = filled.p.len();
    let mut speeds = Vec::new();
    let mut first: Option<crate::dem::Dem> = None;
    let mut identical = true;
    for &threads in counts {
        let pool = pool(threads)?;
        let mut dem = filled.clone();
        let before = dem.counters.particle_steps;
        let ph0 = dem.phase_seconds;
        let b0 = dem.counters.builds;
        let start = Instant::now();
        pool.install(|| dem.advance(steps))?;
        let secs = start.elapsed().as_secs_f64();
        let mut phase_us = [0.0; 6];
        for (k, v) in phase_us.iter_mut().enumerate() {
            *v = 1e6 * (dem.phase_seconds[k] - ph0[k]) / steps as f64;
        }
        speeds.push(DemSpeed {
            threads,
            particle_steps_per_second: (dem.counters.particle_steps - before) as f64 / secs,
            phase_us,
            rebuilds: dem.counters.builds - b0,
        });
        match &first {
            None => first = Some(dem),
            Some(f) => identical &= same_state(f, &dem),
        }
    }
    Ok(DemScaling { particles, speeds, identical })
}

/// Same particles, positions, velocities, angular velocities and impacts, bit for bit.
fn same_state(a: &crate::dem::Dem, b: &crate::dem::Dem) -> bool {
    let bits = |v: &[[f64; 3]]| v.iter().flat_map(|x| x.map(f64::to_bits)).collect::<Vec<u64>>();
    let (p, q) = (&a.p, &b.p);
    p.id == q.id
        && bits(&p.pos) == bits(&q.pos)
        && bits(&p.vel) == bits(&q.vel)
        && bits(&p.omega) == bits(&q.omega)
        && a.impacts.len() == b.impacts.len()
        && a.impacts.iter().zip(&b.impacts).all(|(x, y)| x.particle == y.particle && x.v_normal.to_bits() == y.v_normal.to_bits())
}

/// The crush FE speed case: the `studies/crush_gen3_rt.toml` set-up (1 mm sphere, JH-2, default
/// calibration mesh), without field snapshots.
pub fn fem_benchmark_setup() -> Result<crate::fem::CrushSetup> {
    let text = include_str!("../../studies/crush_gen3_rt.toml");
    let study: crate::fem::run::CrushStudy = crate::study::parse_toml(Path::new("studies/crush_gen3_rt.toml"), text)?;
    let mut s = study.crush;
    s.fields_at.clear();
    s.validate("studies/crush_gen3_rt.toml")?;
    Ok(s)
}

/// One crush FE speed measurement: a run to fracture.
#[derive(Debug, Clone)]
pub struct FemSpeed {
    /// Worker threads.
    pub threads: usize,
    /// Element updates per second.
    pub element_steps_per_second: f64,
    /// Wall time of the run (s), mesh generation included.
    pub run_seconds: f64,
    /// Elements and steps.
    pub elements: usize,
    /// Time steps.
    pub steps: u64,
    /// Peak force (N): the same on every thread count.
    pub peak_force: f64,
}

/// Times one crush run to fracture on 1 thread and on all threads, `repeats` times each, and
/// keeps the fastest of each.
pub fn fem_speed(repeats: usize) -> Result<Vec<FemSpeed>> {
    fem_scaling(repeats, &one_and_all())
}

/// [`fem_speed`] on each thread count of `counts`.
pub fn fem_scaling(repeats: usize, counts: &[usize]) -> Result<Vec<FemSpeed>> {
    let setup = fem_benchmark_setup()?;
    let mut out = Vec::new();
    for &threads in counts {
        let pool = pool(threads)?;
        let mut best: Option<FemSpeed> = None;
        for _ in 0..repeats.max(1) {
            let start = Instant::now();
            let r = pool.install(|| -> Result<crate::fem::CrushResult> {
                let mut t = crate::fem::CrushTest::new(setup.clone(), "<fem benchmark>")?;
                t.run(None)
            })?;
            let secs = start.elapsed().as_secs_f64();
            let s = FemSpeed {
                threads,
                element_steps_per_second: (r.steps * r.elements as u64) as f64 / secs,
                run_seconds: secs,
                elements: r.elements,
                steps: r.steps,
                peak_force: r.peak_force,
            };
            if best.as_ref().is_none_or(|b| s.run_seconds < b.run_seconds) {
                best = Some(s);
            }
        }
        out.extend(best);
    }
    Ok(out)
}

/// The fine-mesh crush FE case: the [`fem_benchmark_setup`] sphere with four times the elements
/// per contact radius and per radius of the bulk (about 20 000 elements).
pub fn fem_fine_setup() -> Result<crate::fem::CrushSetup> {
    let mut s = fem_benchmark_setup()?;
    s.mesh.refinement *= 4.0;
    s.mesh.bulk_elements *= 4.0;
    s.validate("<fine-mesh fem benchmark>")?;
    Ok(s)
}

/// One fixed-length crush FE measurement.
#[derive(Debug, Clone)]
pub struct FemSteps {
    /// Worker threads.
    pub threads: usize,
    /// Element updates per second.
    pub element_steps_per_second: f64,
    /// Wall time of the steps (s), mesh generation excluded.
    pub seconds: f64,
    /// Elements.
    pub elements: usize,
    /// The top platen's impulse summed over the steps (N s per radian): the same bits on every
    /// thread count.
    pub impulse: f64,
}

/// `steps` explicit steps of `setup` from the start on each thread count of `counts`, fastest of
/// `repeats`.
pub fn fem_steps_scaling(setup: &crate::fem::CrushSetup, steps: u64, repeats: usize, counts: &[usize]) -> Result<Vec<FemSteps>> {
    let mut out = Vec::new();
    for &threads in counts {
        let pool = pool(threads)?;
        let mut best: Option<FemSteps> = None;
        for _ in 0..repeats.max(1) {
            let mut t = crate::fem::CrushTest::new(setup.clone(), "<fem benchmark>")?;
            let elements = t.mesh.elements.len();
            let start = Instant::now();
            let impulse = pool.install(|| -> Result<f64> {
                let mut sum = 0.0;
                for _ in 0..steps {
                    sum += t.step()?.0;
                }
                Ok(sum)
            })?;
            let seconds = start.elapsed().as_secs_f64();
            let s = FemSteps { threads, element_steps_per_second: (steps * elements as u64) as f64 / seconds, seconds, elements, impulse };
            if best.as_ref().is_none_or(|b| s.seconds < b.seconds) {
                best = Some(s);
            }
        }
        out.extend(best);
    }
    Ok(out)
}

/// The main study's wall time per thread count.
#[derive(Debug, Clone)]
pub struct StudyScaling {
    /// (threads, wall seconds of the run: fits, propagation, tables, figures, documents).
    pub seconds: Vec<(usize, f64)>,
    /// Whether its tables are byte-identical on every thread count.
    pub identical: bool,
    /// The tables compared.
    pub tables: Vec<&'static str>,
}

/// `studies/gen4_vs_bl.toml` end to end into a scratch reports directory on each thread count of
/// `counts` (the run's own wall time, as its manifest records it), and whether its tables are the
/// same bytes on every count.
pub fn main_study_scaling(counts: &[usize]) -> Result<StudyScaling> {
    let loaded = crate::study::load(&repo_path("studies/gen4_vs_bl.toml"))?;
    let tables = vec!["breakage.csv", "comparison.csv", "sobol.csv", "attrition.csv", "strength_models.csv"];
    let mut seconds = Vec::new();
    let mut first: Option<Vec<Option<Vec<u8>>>> = None;
    let mut identical = true;
    for &threads in counts {
        let root = TempDir::new("bench-scaling")?;
        let opts = crate::runner::RunOptions::new(root.path().to_path_buf(), false);
        let s = pool(threads)?.install(|| crate::runner::run(&loaded, &opts))?;
        seconds.push((threads, s.wall_time_s));
        let bytes: Vec<Option<Vec<u8>>> = tables.iter().map(|t| std::fs::read(root.path().join("gen4_vs_bl").join(t)).ok()).collect();
        match &first {
            None => first = Some(bytes),
            Some(f) => identical &= *f == bytes,
        }
    }
    Ok(StudyScaling { seconds, identical, tables })
}

#[cfg(test)]
mod tests {
    #[test]
    fn scaling_counts_double_up_to_the_available_threads() {
        assert_eq!(super::thread_counts(1), vec![1]);
        assert_eq!(super::thread_counts(2), vec![1, 2]);
        assert_eq!(super::thread_counts(6), vec![1, 2, 4, 6]);
        assert_eq!(super::thread_counts(16), vec![1, 2, 4, 8, 16]);
        assert_eq!(super::thread_counts(0), vec![1]);
    }
}

//! The set-up of a DEM run: particle diameters, inlet, probes and the whole [`DemSetup`] with
//! its validation.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};
use crate::error::{Error, Result};
use super::contact::{Interaction, Material, PairLaw, rayleigh_time};
use super::geometry::Geometry;
use super::vec3::V3;

/// Particle diameters.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(tag = "distribution", rename_all = "lowercase", deny_unknown_fields)]
pub enum Diameters {
    /// All equal.
    Fixed {
        /// Diameter (m).
        value: f64,
    },
    /// Uniform on [min, max].
    Uniform {
        /// Smallest (m).
        min: f64,
        /// Largest (m).
        max: f64,
    },
    /// Normal truncated to [min, max] (rejection).
    Normal {
        /// Mean (m).
        mean: f64,
        /// Standard deviation (m).
        sd: f64,
        /// Smallest (m).
        min: f64,
        /// Largest (m).
        max: f64,
    },
}

impl Diameters {
    /// Largest possible diameter.
    pub fn max(&self) -> f64 {
        match *self {
            Diameters::Fixed { value } => value,
            Diameters::Uniform { max, .. } | Diameters::Normal { max, .. } => max,
        }
    }
    /// Smallest possible diameter.
    pub fn min(&self) -> f64 {
        match *self {
            Diameters::Fixed { value } => value,
            Diameters::Uniform { min, .. } | Diameters::Normal { min, .. } => min,
        }
    }
    /// A draw.
    pub fn sample(&self, rng: &mut ChaCha8Rng) -> f64 {
        match *self {
            Diameters::Fixed { value } => value,
            Diameters::Uniform { min, max } => {
                if max > min {
                    rng.random_range(min..max)
                } else {
                    min
                }
            }
            Diameters::Normal { mean, sd, min, max } => {
                let n = Normal::new(mean, sd.max(0.0)).unwrap_or_else(|_| Normal::new(mean, 0.0).expect("sd 0"));
                for _ in 0..1000 {
                    let d = n.sample(rng);
                    if (min..=max).contains(&d) {
                        return d;
                    }
                }
                mean.clamp(min, max)
            }
        }
    }
    /// Checks the numbers.
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        let (lo, hi) = (self.min(), self.max());
        if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
            return Err(Error::config(file, key, format!("diameters must satisfy 0 < min ≤ max, got min {lo}, max {hi} m")));
        }
        if let Diameters::Normal { mean, sd, .. } = *self
            && !(sd >= 0.0 && mean >= lo && mean <= hi)
        {
            return Err(Error::config(file, key, format!("normal diameters need sd ≥ 0 and min ≤ mean ≤ max, got mean {mean}, sd {sd}")));
        }
        Ok(())
    }
}

/// Particle insertion at the top of the domain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inlet {
    /// Mass flux through the inlet cross-section (width × slab) (kg/(m² s)).
    pub mass_flux: f64,
    /// Downward speed at insertion (m/s).
    pub velocity: f64,
    /// Insertion region, lower z (m).
    pub z_lo: f64,
    /// Insertion region, upper z (m).
    pub z_hi: f64,
}

/// What to measure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeSetup {
    /// Measurements (impacts, passes, fields) start at this time (s).
    pub warmup: f64,
    /// Field sampling interval (steps).
    pub sample_every: u64,
    /// z bins of the velocity profile.
    pub profile_bins: usize,
    /// x bins of the speed map.
    pub map_nx: usize,
    /// z bins of the speed map.
    pub map_nz: usize,
    /// Contacts that start slower than this (normal approach speed, m/s) are resting touches,
    /// not impacts: neither recorded nor counted.
    pub min_impact_velocity: f64,
    /// The first tube impact after the warm-up at least this fast is traced (m/s).
    pub trace_min_velocity: f64,
}

impl Default for ProbeSetup {
    fn default() -> Self {
        ProbeSetup { warmup: 0.0, sample_every: 100, profile_bins: 150, map_nx: 50, map_nz: 130, min_impact_velocity: 0.1, trace_min_velocity: 1.0 }
    }
}

/// A complete DEM set-up.
#[derive(Debug, Clone, PartialEq)]
pub struct DemSetup {
    /// Particle material.
    pub particle: Material,
    /// Wall and tube material.
    pub wall: Material,
    /// Particle–particle interaction.
    pub particle_particle: Interaction,
    /// Particle–wall (and tube) interaction.
    pub particle_wall: Interaction,
    /// Diameters of inserted particles.
    pub diameters: Diameters,
    /// The domain.
    pub geometry: Geometry,
    /// Gravity (m/s²).
    pub gravity: V3,
    /// Inlet (none: particles are placed by hand).
    pub inlet: Option<Inlet>,
    /// Time step (s).
    pub time_step: f64,
    /// Largest expected relative impact speed (m/s), for the contact-time limit of the step.
    pub max_speed: f64,
    /// Neighbour skin as a fraction of the largest diameter.
    pub skin_fraction: f64,
    /// Neighbour lists are rebuilt at least every this many steps (insertion happens then).
    pub max_rebuild_steps: u64,
    /// Particles rotate (false: frozen rotation, sliding blocks, for tests).
    pub rotation: bool,
    /// Overlap beyond this fraction of the smaller radius stops the run (blow-up).
    pub max_overlap_fraction: f64,
    /// Probes.
    pub probes: ProbeSetup,
    /// Seed of insertion positions and diameters.
    pub seed: u64,
}

impl DemSetup {
    /// Skin distance (m).
    pub fn skin(&self) -> f64 {
        self.skin_fraction * self.diameters.max()
    }

    /// The stable-step limit `min(0.2 T_R, t_c/10)` (see the module docs).
    pub fn time_step_limit(&self) -> f64 {
        let r_min = self.diameters.min() / 2.0;
        let t_r = rayleigh_time(&self.particle, r_min);
        let m_min = self.particle.density * 4.0 / 3.0 * std::f64::consts::PI * r_min.powi(3);
        let pp = PairLaw::new(&self.particle, &self.particle, &self.particle_particle);
        let pw = PairLaw::new(&self.particle, &self.wall, &self.particle_wall);
        let v = self.max_speed.max(1e-3);
        let tc_pp = pp.contact_time(m_min / 2.0, r_min / 2.0, v);
        let tc_pw = pw.contact_time(m_min, r_min, v);
        (0.2 * t_r).min(tc_pp.min(tc_pw) / 10.0)
    }

    /// Checks every option against the rules in the module docs; `file` names the study file.
    pub fn validate(&self, file: &str) -> Result<()> {
        for (key, m) in [("particles", &self.particle), ("walls", &self.wall)] {
            if !(m.youngs_modulus > 0.0 && m.youngs_modulus.is_finite()) {
                return Err(Error::config(file, format!("{key}.youngs_modulus"), format!("must be > 0 Pa, got {}", m.youngs_modulus)));
            }
            if !(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
                return Err(Error::config(file, format!("{key}.poisson_ratio"), format!("must lie in (−1, 0.5), got {}", m.poisson_ratio)));
            }
        }
        if !(self.particle.density > 0.0 && self.particle.density.is_finite()) {
            return Err(Error::config(file, "particles.density", format!("must be > 0 kg/m³, got {}", self.particle.density)));
        }
        self.particle_particle.validate(file, "contact.particle_particle")?;
        self.particle_wall.validate(file, "contact.particle_wall")?;
        self.diameters.validate(file, "particles.diameter")?;
        if !(self.skin_fraction > 0.0 && self.skin_fraction <= 1.0) {
            return Err(Error::config(file, "run.skin", format!("must lie in (0, 1] (fraction of the largest diameter), got {}", self.skin_fraction)));
        }
        if !(self.max_overlap_fraction > 0.0 && self.max_overlap_fraction < 1.0) {
            return Err(Error::config(file, "run.max_overlap_fraction", format!("must lie in (0, 1), got {}", self.max_overlap_fraction)));
        }
        self.geometry.validate(file, self.diameters.max(), self.skin())?;
        let g = &self.geometry;
        let cut = self.diameters.max() + self.skin();
        let cells = ((g.x_hi - g.x_lo) / cut).ceil() * (g.slab / cut).ceil() * ((g.z_hi - g.z_lo) / cut + 4.0).ceil();
        if cells > 5e7 {
            return Err(Error::config(
                file,
                "geometry",
                format!("the domain needs {cells:.2e} neighbour cells of {cut:.2e} m (limit 5e7): reduce the width, slab or height, or the resolution is wrong"),
            ));
        }
        let limit = self.time_step_limit();
        if self.time_step.is_nan() || self.time_step <= 0.0 || self.time_step > limit {
            return Err(Error::config(
                file,
                "run.time_step",
                format!(
                    "{:.3e} s is above the stable limit {:.3e} s = min(0.2 × Rayleigh time, Hertz contact time at {} m/s / 10) for the smallest particle; lower it or omit it (default 0.5 × limit)",
                    self.time_step, limit, self.max_speed
                ),
            ));
        }
        if let Some(inlet) = &self.inlet {
            let g = &self.geometry;
            let r = self.diameters.max() / 2.0;
            if !(inlet.mass_flux >= 0.0 && inlet.mass_flux.is_finite()) {
                return Err(Error::config(file, "inlet.mass_flux", format!("must be ≥ 0 kg/(m² s), got {}", inlet.mass_flux)));
            }
            if !(inlet.velocity.is_finite()) {
                return Err(Error::config(file, "inlet.velocity", "must be finite"));
            }
            if !(inlet.z_lo >= g.z_lo && inlet.z_hi <= g.z_hi && inlet.z_hi - inlet.z_lo > 2.0 * r) {
                return Err(Error::config(
                    file,
                    "inlet.region",
                    format!(
                        "insertion region z [{}, {}] m must lie inside the domain z [{}, {}] m and be higher than the largest particle diameter",
                        inlet.z_lo, inlet.z_hi, g.z_lo, g.z_hi
                    ),
                ));
            }
            if g.x_hi - g.x_lo <= 2.0 * r {
                return Err(Error::config(file, "inlet.region", "the domain is narrower than one particle"));
            }
            for (t, tube) in g.tubes.iter().enumerate() {
                if tube.z + tube.radius + r > inlet.z_lo {
                    return Err(Error::config(
                        file,
                        "inlet.region",
                        format!("insertion region (z ≥ {} m) overlaps tube {t} (row {}, top at {:.4} m)", inlet.z_lo, tube.row, tube.z + tube.radius),
                    ));
                }
            }
        }
        if self.probes.sample_every == 0 || self.probes.profile_bins == 0 || self.probes.map_nx == 0 || self.probes.map_nz == 0 {
            return Err(Error::config(file, "probes", "sampling interval and bin counts must be ≥ 1"));
        }
        Ok(())
    }
}

//! The tube bank as a [`Simulator`]: θ = contact coefficients, y = what the flow measures.
//!
//! θ (names resolved once, at construction):
//! `restitution_pp`, `restitution_pw`, `friction_pp`, `friction_pw` (all dimensionless).
//!
//! y: the mean vertical velocity (m/s) in ±`window` bands around the requested heights (the
//! profile samples), the outlet mass flow (kg/s), the mean number of particles in the domain,
//! tube impacts per pass, and the 50 % and 90 % quantiles of the normal impact velocity of tube
//! and of particle–particle impacts (m/s).

use super::{Dem, DemSetup};
use crate::error::{Error, Result};
use crate::model::{OutputSpec, Simulator, check_outputs};
use crate::params::{Param, ParamSpace};

use super::probe::Target;

/// θ indices.
pub mod theta {
    /// Particle–particle restitution.
    pub const RESTITUTION_PP: usize = 0;
    /// Particle–wall restitution.
    pub const RESTITUTION_PW: usize = 1;
    /// Particle–particle friction.
    pub const FRICTION_PP: usize = 2;
    /// Particle–wall friction.
    pub const FRICTION_PW: usize = 3;
}

/// The tube-bank flow as θ ↦ y.
#[derive(Debug, Clone)]
pub struct TubeBankModel {
    base: DemSetup,
    duration: f64,
    heights: Vec<f64>,
    window: f64,
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
}

impl TubeBankModel {
    /// A model running `base` (its warm-up included) for `duration` seconds per evaluation and
    /// sampling the profile at `heights` (m) with a ±`window` (m) band.
    pub fn new(base: DemSetup, duration: f64, heights: Vec<f64>, window: f64) -> Result<Self> {
        base.validate("<TubeBankModel>")?;
        if duration.is_nan() || duration <= base.probes.warmup {
            return Err(Error::config("<TubeBankModel>", "duration", format!("must exceed the warm-up {} s, got {duration}", base.probes.warmup)));
        }
        let space = ParamSpace::new(vec![
            Param::uniform("restitution_pp", "-", 0.05, 1.0, base.particle_particle.restitution),
            Param::uniform("restitution_pw", "-", 0.05, 1.0, base.particle_wall.restitution),
            Param::uniform("friction_pp", "-", 0.0, 1.0, base.particle_particle.friction),
            Param::uniform("friction_pw", "-", 0.0, 1.0, base.particle_wall.friction),
        ])?;
        let mut outputs: Vec<OutputSpec> = heights.iter().map(|h| OutputSpec::new(format!("vz_at_{:.0}mm", 1e3 * h), "m/s")).collect();
        outputs.push(OutputSpec::new("mass_flow", "kg/s"));
        outputs.push(OutputSpec::new("particles_in_domain", "-"));
        outputs.push(OutputSpec::new("tube_impacts_per_pass", "-"));
        outputs.push(OutputSpec::new("tube_v_normal_q50", "m/s"));
        outputs.push(OutputSpec::new("tube_v_normal_q90", "m/s"));
        outputs.push(OutputSpec::new("particle_v_normal_q50", "m/s"));
        outputs.push(OutputSpec::new("particle_v_normal_q90", "m/s"));
        Ok(TubeBankModel { base, duration, heights, window, space, outputs })
    }

    /// The set-up an evaluation runs.
    pub fn setup_at(&self, theta: &[f64]) -> Result<DemSetup> {
        self.space.check(theta)?;
        let mut s = self.base.clone();
        s.particle_particle.restitution = theta[theta::RESTITUTION_PP];
        s.particle_wall.restitution = theta[theta::RESTITUTION_PW];
        s.particle_particle.friction = theta[theta::FRICTION_PP];
        s.particle_wall.friction = theta[theta::FRICTION_PW];
        Ok(s)
    }
}

impl Simulator for TubeBankModel {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        let setup = self.setup_at(theta)?;
        let dt = setup.time_step;
        let warmup = setup.probes.warmup;
        let mut dem = Dem::new(setup, "<TubeBankModel>")?;
        let steps = (self.duration / dt).ceil() as u64;
        dem.advance(steps)?;
        let f = &dem.fields;
        let mut y = Vec::with_capacity(self.outputs.len());
        for &h in &self.heights {
            let (mut s, mut n) = (0.0, 0u64);
            for k in 0..f.sum_vz.len() {
                let zc = 0.5 * (f.z_edges[k] + f.z_edges[k + 1]);
                if (zc - h).abs() <= self.window {
                    s += f.sum_vz[k];
                    n += f.count_z[k];
                }
            }
            y.push(if n > 0 { s / n as f64 } else { 0.0 });
        }
        let measured = dem.time - warmup;
        y.push(dem.outflow_mass_measured / measured);
        let after: Vec<_> = dem.flow.iter().filter(|x| x.time >= warmup).collect();
        y.push(after.iter().map(|x| x.particles as f64).sum::<f64>() / after.len().max(1) as f64);
        y.push(dem.passes.iter().map(|p| p.tube_impacts as f64).sum::<f64>() / dem.passes.len().max(1) as f64);
        let spectrum = super::run::spectrum(&dem, &[0.5, 0.9]);
        for target in [Target::Tube, Target::Particle] {
            // Row 0 = all rows; no impacts → 0 (a finite output).
            let all = spectrum.iter().find(|r| r.target == target.name() && r.row == 0);
            for k in 0..2 {
                y.push(all.map(|r| r.quantiles[k]).filter(|x| x.is_finite()).unwrap_or(0.0));
            }
        }
        check_outputs("tube bank DEM", &self.outputs, theta, &y)?;
        Ok(y)
    }
}

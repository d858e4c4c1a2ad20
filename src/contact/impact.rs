//! Particles and their loading: the [`Sphere`], its crush between platens ([`Crush`]) and its
//! impact on a wall with elastic energy fraction η ([`Impact`]), on the Hertz relations of
//! the parent module.


use super::*;
use crate::error::{Error, Result};

/// A sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// Diameter d (m).
    pub diameter: f64,
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Elastic constants.
    pub elastic: Elastic,
}

impl Sphere {
    /// Radius R = d/2 (m).
    pub fn radius(&self) -> f64 {
        0.5 * self.diameter
    }
    /// Mass m = ρ π d³/6 (kg).
    pub fn mass(&self) -> f64 {
        self.density * std::f64::consts::PI * self.diameter.powi(3) / 6.0
    }
}

/// Crushing of a sphere between two identical flat platens: two Hertz contacts in series.
/// The platen displacement is δ_tot = 2δ, so F = (√2/3) E* √R δ_tot^(3/2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crush {
    /// Each sphere–platen contact.
    pub contact: Hertz,
}

impl Crush {
    /// Sphere of curvature radius `radius` between platens of the given material.
    pub fn new(particle: &Elastic, platen: &Elastic, radius: f64) -> Self {
        Crush { contact: Hertz::sphere_on_flat(particle, platen, radius) }
    }
    /// Total platen displacement δ_tot = 2δ (m) at force F (N).
    pub fn total_displacement(&self, force: f64) -> f64 {
        2.0 * self.contact.approach(force)
    }
    /// Force (N) at total platen displacement δ_tot (m).
    pub fn force_at_displacement(&self, total: f64) -> f64 {
        self.contact.force_at_approach(0.5 * total)
    }
}

/// Dimensionless contact duration τ_c = (4/5) B(2/5, 1/2) = 2.943275… (Hertz impact).
pub fn dimensionless_contact_time() -> f64 {
    use statrs::function::gamma::gamma;
    0.8 * gamma(0.4) * gamma(0.5) / gamma(0.9)
}

/// One sample of an impact force history.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactSample {
    /// Time since first contact (s).
    pub time: f64,
    /// Contact force (N).
    pub force: f64,
    /// Running time integral of the force (N·s).
    pub impulse: f64,
}

/// Normal impact with elastic energy fraction η.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// The contact.
    pub hertz: Hertz,
    /// Effective mass m* (kg).
    pub effective_mass: f64,
    /// Elastic energy fraction η ∈ (0, 1].
    pub energy_fraction: f64,
}

impl Impact {
    /// Sphere on a massive flat wall: m* = m, R* = curvature radius.
    pub fn sphere_on_wall(sphere: &Sphere, wall: &Elastic, curvature_radius: f64, eta: f64) -> Self {
        Impact {
            hertz: Hertz::sphere_on_flat(&sphere.elastic, wall, curvature_radius),
            effective_mass: sphere.mass(),
            energy_fraction: eta,
        }
    }

    /// Two equal spheres: m* = m/2, R* = R_c/2; velocities are relative velocities.
    pub fn sphere_on_sphere(sphere: &Sphere, curvature_radius: f64, eta: f64) -> Self {
        Impact {
            hertz: Hertz::sphere_on_sphere(&sphere.elastic, curvature_radius),
            effective_mass: 0.5 * sphere.mass(),
            energy_fraction: eta,
        }
    }

    /// V_eff = √η V (m/s).
    pub fn effective_velocity(&self, v: f64) -> f64 {
        self.energy_fraction.sqrt() * v
    }

    /// Maximum approach δ_m (m) at impact velocity V (m/s).
    pub fn max_approach(&self, v: f64) -> f64 {
        let ve = self.effective_velocity(v);
        (15.0 * self.effective_mass * ve * ve / (16.0 * self.hertz.e_star * self.hertz.r_star.sqrt()))
            .powf(0.4)
    }

    /// Maximum force F_max (N).
    pub fn max_force(&self, v: f64) -> f64 {
        self.hertz.force_at_approach(self.max_approach(v))
    }

    /// Contact duration t_c (s); infinite at V = 0.
    pub fn contact_time(&self, v: f64) -> f64 {
        dimensionless_contact_time() * self.max_approach(v) / self.effective_velocity(v)
    }

    /// Force history over the whole contact, `n ≥ 2` samples uniformly spaced in time.
    pub fn force_history(&self, v: f64, n: usize) -> Result<Vec<ImpactSample>> {
        if n < 2 || !(v > 0.0 && v.is_finite()) {
            return Err(Error::numerical(
                "impact force history",
                format!("needs n ≥ 2 samples and V > 0 (got n = {n}, V = {v})"),
            ));
        }
        let ve = self.effective_velocity(v);
        let dm = self.max_approach(v);
        let fmax = self.hertz.force_at_approach(dm);
        let tau_c = dimensionless_contact_time();
        // RK4 on x'' = −(5/4) x^(3/2) with sub-steps between output samples.
        let sub = 200;
        let h = tau_c / ((n - 1) * sub) as f64;
        let acc = |x: f64| -1.25 * x.max(0.0).powf(1.5);
        let (mut x, mut u) = (0.0f64, 1.0f64);
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            let tau = i as f64 * tau_c / (n - 1) as f64;
            // The last sample is the end of contact: x = 0, u = −1 exactly.
            let (xs, us) = if i == n - 1 { (0.0, -1.0) } else { (x, u) };
            out.push(ImpactSample {
                time: tau * dm / ve,
                force: fmax * xs.max(0.0).powf(1.5),
                impulse: self.effective_mass * ve * (1.0 - us),
            });
            for _ in 0..sub {
                let (k1x, k1u) = (u, acc(x));
                let (k2x, k2u) = (u + 0.5 * h * k1u, acc(x + 0.5 * h * k1x));
                let (k3x, k3u) = (u + 0.5 * h * k2u, acc(x + 0.5 * h * k2x));
                let (k4x, k4u) = (u + h * k3u, acc(x + h * k3x));
                x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
                u += h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u);
            }
        }
        Ok(out)
    }
}

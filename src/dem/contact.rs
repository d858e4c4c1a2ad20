//! Hertz–Mindlin contact with history, as in LIGGGHTS (`normal_model_hertz.h`,
//! `tangential_model_history.h`), with the normal, damping and tangential parts kept separate
//! and the effective pair properties precomputed.
//!
//! For an overlap δ > 0 between bodies of effective radius R*, mass m*, modulus E* and shear
//! modulus G*:
//!
//! ```text
//! normal:      F_n  = k_n δ − γ_n v_n ,        k_n = (4/3) E* √(R* δ)
//! damping:     γ_n  = −2 √(5/6) β √(S_n m*) ,  S_n = 2 E* √(R* δ)
//!              β    = ln e / √(ln² e + π²)      (e: coefficient of normal restitution)
//! tangential:  ξ   += v_t Δt (ξ rotated into the current tangent plane, magnitude kept)
//!              F_t  = −k_t ξ − γ_t v_t ,        k_t = S_t = 8 G* √(R* δ)
//!              γ_t  = −2 √(5/6) β √(S_t m*)
//! Coulomb:     if k_t |ξ| > μ |F_n|:  ξ ← ξ μ|F_n| / (k_t|ξ|),  F_t = −k_t ξ   (sliding)
//! rolling:     T_r  = −μ_r R* k_n δ ω_rel/|ω_rel|   (constant directional torque, optional)
//! ```
//!
//! With this damping law the normal restitution does not depend on the impact velocity, and it
//! equals `e` when the normal force is not clipped at zero during unloading (LIGGGHTS' default,
//! kept here): the verification suite measures it within 1 % for e ∈ {0.5, 0.7, 0.9, 1.0}.
//! Clipping the small attractive force at the end of the contact would raise the restitution
//! (e = 0.5 → 0.55), so it is not done.
//!
//! Effective properties:
//! `1/E* = (1−ν₁²)/E₁ + (1−ν₂²)/E₂`, `1/G* = 2(2−ν₁)(1+ν₁)/E₁ + 2(2−ν₂)(1+ν₂)/E₂`,
//! `1/R* = 1/R₁ + 1/R₂`, `1/m* = 1/m₁ + 1/m₂`. A flat wall has R₂ = ∞ and m₂ = ∞. A tube (a
//! cylinder of radius R_t, axis along y) touching a sphere of radius r gives an elliptical
//! contact with principal radii r and r R_t/(r + R_t); its Hertz equivalent radius is their
//! geometric mean (Johnson 1985, §4.2), `R* = r √(R_t/(r + R_t))`.

use super::vec3::{V3, cross, dot, norm, scale, sub};
use crate::error::{Error, Result};

/// Elastic material of particles or walls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Density (kg/m³); unused for walls.
    pub density: f64,
    /// Young's modulus (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio.
    pub poisson_ratio: f64,
}

impl Material {
    /// Shear modulus G = E / (2(1 + ν)).
    pub fn shear_modulus(&self) -> f64 {
        self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))
    }
}

/// Interaction coefficients of one pair of materials.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interaction {
    /// Coefficient of normal restitution e ∈ (0, 1].
    pub restitution: f64,
    /// Coulomb friction coefficient μ ≥ 0.
    pub friction: f64,
    /// Rolling friction coefficient μ_r ≥ 0 (0: no rolling resistance).
    pub rolling_friction: f64,
}

impl Interaction {
    /// Checks the ranges; `key` names the study key in errors.
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        if !(self.restitution > 0.0 && self.restitution <= 1.0) {
            return Err(Error::config(file, format!("{key}.restitution"), format!("must lie in (0, 1], got {}", self.restitution)));
        }
        if !(self.friction >= 0.0 && self.friction.is_finite()) {
            return Err(Error::config(file, format!("{key}.friction"), format!("must be ≥ 0, got {}", self.friction)));
        }
        if !(self.rolling_friction >= 0.0 && self.rolling_friction.is_finite()) {
            return Err(Error::config(
                file,
                format!("{key}.rolling_friction"),
                format!("must be ≥ 0, got {}", self.rolling_friction),
            ));
        }
        Ok(())
    }
}

/// Damping ratio β = ln e / √(ln² e + π²) (≤ 0; 0 for e = 1).
pub fn damping_beta(restitution: f64) -> f64 {
    if restitution >= 1.0 {
        0.0
    } else {
        let l = restitution.ln();
        l / (l * l + std::f64::consts::PI.powi(2)).sqrt()
    }
}

/// Precomputed effective properties of one material pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairLaw {
    /// E* (Pa).
    pub e_star: f64,
    /// G* (Pa).
    pub g_star: f64,
    /// −2 √(5/6) β (≥ 0), the damping prefactor.
    pub damp: f64,
    /// μ.
    pub friction: f64,
    /// μ_r.
    pub rolling_friction: f64,
}

impl PairLaw {
    /// The law between two materials with the given interaction.
    pub fn new(a: &Material, b: &Material, i: &Interaction) -> Self {
        let e_star = 1.0 / ((1.0 - a.poisson_ratio.powi(2)) / a.youngs_modulus + (1.0 - b.poisson_ratio.powi(2)) / b.youngs_modulus);
        let g_inv = |m: &Material| 2.0 * (2.0 - m.poisson_ratio) * (1.0 + m.poisson_ratio) / m.youngs_modulus;
        let g_star = 1.0 / (g_inv(a) + g_inv(b));
        PairLaw {
            e_star,
            g_star,
            damp: -2.0 * (5.0f64 / 6.0).sqrt() * damping_beta(i.restitution),
            friction: i.friction,
            rolling_friction: i.rolling_friction,
        }
    }

    /// Hertz contact duration of an elastic (e = 1) head-on impact at relative normal speed v:
    /// t_c = 2.868 (m*² / (R* E*² v))^(1/5).
    pub fn contact_time(&self, m_star: f64, r_star: f64, v: f64) -> f64 {
        2.868 * (m_star * m_star / (r_star * self.e_star * self.e_star * v)).powf(0.2)
    }
}

/// Rayleigh time of a sphere of radius r: π r √(ρ/G) / (0.1631 ν + 0.8766).
pub fn rayleigh_time(m: &Material, radius: f64) -> f64 {
    std::f64::consts::PI * radius * (m.density / m.shear_modulus()).sqrt() / (0.1631 * m.poisson_ratio + 0.8766)
}

/// Geometry and kinematics of one contact, from the point of view of body i.
#[derive(Debug, Clone, Copy)]
pub struct ContactGeom {
    /// Unit normal pointing from the partner to body i.
    pub n: V3,
    /// Overlap δ > 0 (m).
    pub delta: f64,
    /// Relative velocity of body i's contact point with respect to the partner's.
    pub v_rel: V3,
    /// ω_i − ω_j (rad/s) for rolling resistance.
    pub w_rel: V3,
    /// R* (m).
    pub r_star: f64,
    /// m* (kg).
    pub m_star: f64,
}

/// The force on body i, its normal part and the rolling torque on body i.
#[derive(Debug, Clone, Copy)]
pub struct ContactForce {
    /// Total force on i (N).
    pub force: V3,
    /// Signed normal force (N, positive = repulsive).
    pub normal: f64,
    /// Rolling-resistance torque on i (N·m); the partner receives its negative.
    pub rolling_torque: V3,
}

/// Evaluates the contact force and updates the tangential history `xi`.
#[inline(always)]
pub fn hertz_mindlin(law: &PairLaw, c: &ContactGeom, xi: &mut V3, dt: f64) -> ContactForce {
    let n = c.n;
    let sqrt_rd = (c.r_star * c.delta).sqrt();
    let kn = (4.0 / 3.0) * law.e_star * sqrt_rd;
    let sn = 2.0 * law.e_star * sqrt_rd;
    let vn = dot(c.v_rel, n);
    let gamma_n = law.damp * (sn * c.m_star).sqrt();
    let fn_el = kn * c.delta;
    let f_n = fn_el - gamma_n * vn;
    let vt = sub(c.v_rel, scale(n, vn));

    // Tangential history: rotate into the current tangent plane keeping its magnitude, then add.
    let xi_mag = norm(*xi);
    let mut h = *xi;
    if xi_mag > 0.0 {
        let hn = dot(h, n);
        h = sub(h, scale(n, hn));
        let m = norm(h);
        if m > 0.0 {
            h = scale(h, xi_mag / m);
        }
    }
    h = [h[0] + vt[0] * dt, h[1] + vt[1] * dt, h[2] + vt[2] * dt];
    let kt = 8.0 * law.g_star * sqrt_rd;
    let shear = kt * norm(h);
    let limit = law.friction * f_n.abs();
    let ft = if shear > limit {
        if shear > 0.0 {
            h = scale(h, limit / shear);
        }
        scale(h, -kt)
    } else {
        let gamma_t = law.damp * (kt * c.m_star).sqrt();
        [-kt * h[0] - gamma_t * vt[0], -kt * h[1] - gamma_t * vt[1], -kt * h[2] - gamma_t * vt[2]]
    };
    *xi = h;

    let mut rolling_torque = [0.0; 3];
    if law.rolling_friction > 0.0 {
        let w = norm(c.w_rel);
        if w > 0.0 {
            rolling_torque = scale(c.w_rel, -law.rolling_friction * c.r_star * fn_el / w);
        }
    }
    ContactForce {
        force: [f_n * n[0] + ft[0], f_n * n[1] + ft[1], f_n * n[2] + ft[2]],
        normal: f_n,
        rolling_torque,
    }
}

/// Velocity of body i's contact point relative to the partner's, for a contact normal n
/// (partner → i), arms r_i (centre of i to contact: −r_i n) and r_j (+r_j n).
#[inline(always)]
pub fn contact_velocity(v_i: V3, v_j: V3, w_i: V3, w_j: V3, r_i: f64, r_j: f64, n: V3) -> V3 {
    let w = [r_i * w_i[0] + r_j * w_j[0], r_i * w_i[1] + r_j * w_j[1], r_i * w_i[2] + r_j * w_j[2]];
    let wxn = cross(w, n);
    [v_i[0] - v_j[0] - wxn[0], v_i[1] - v_j[1] - wxn[1], v_i[2] - v_j[2] - wxn[2]]
}

/// Hertz elastic energy stored in a contact: (8/15) E* √R* δ^(5/2).
pub fn hertz_energy(law: &PairLaw, r_star: f64, delta: f64) -> f64 {
    if delta <= 0.0 { 0.0 } else { (8.0 / 15.0) * law.e_star * r_star.sqrt() * delta.powf(2.5) }
}

/// Equivalent radius of a sphere of radius r on a tube of radius R_t (see the module docs).
pub fn tube_radius_star(r: f64, tube_radius: f64) -> f64 {
    r * (tube_radius / (r + tube_radius)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beta_limits() {
        assert_eq!(damping_beta(1.0), 0.0);
        assert!(damping_beta(0.5) < 0.0);
        // Linear spring-dashpot: e = exp(−π ζ / √(1 − ζ²)) with ζ = −β.
        let z = -damping_beta(0.7);
        assert!(((-std::f64::consts::PI * z / (1.0 - z * z).sqrt()).exp() - 0.7).abs() < 1e-12);
    }

    #[test]
    fn effective_moduli_of_identical_materials() {
        let m = Material { density: 3600.0, youngs_modulus: 1e8, poisson_ratio: 0.25 };
        let l = PairLaw::new(&m, &m, &Interaction { restitution: 0.7, friction: 0.3, rolling_friction: 0.0 });
        assert!((l.e_star - 1e8 / (2.0 * (1.0 - 0.0625))).abs() < 1e-3);
        let g = m.shear_modulus();
        assert!((l.g_star - g / (2.0 * (2.0 - 0.25))).abs() < 1e-3);
    }
}

//! Hertz contact of an elastic sphere (Johnson 1985, *Contact Mechanics*, ch. 3–4 and 11):
//! contact size and pressure, the surface stress field, the "average radial tensile stress"
//! used by the deliverable's lifetime model, crushing between platens, and impact with an
//! elastic energy fraction η.
//!
//! # Equations (SI units; compression negative in stresses)
//!
//! ```text
//! 1/E* = (1−ν1²)/E1 + (1−ν2²)/E2          1/R* = 1/R1 + 1/R2
//! a = (3 F R*/(4 E*))^(1/3)    δ = a²/R*    p0 = 3F/(2π a²)    F = (4/3) E* √R* δ^(3/2)
//! surface, s = r/a ≤ 1:  σ_r/p0 = (1−2ν)/(3s²)[1 − (1−s²)^(3/2)] − √(1−s²)
//!                        σ_θ/p0 = −(1−2ν)/(3s²)[1 − (1−s²)^(3/2)] − 2ν√(1−s²)
//!                        σ_z/p0 = −√(1−s²)
//! surface, s ≥ 1:        σ_r = −σ_θ = (1−2ν) p0/(3s²),  σ_z = 0
//! ```
//!
//! σ_r changes sign at s0(ν) just inside the contact edge; the **tensile zone** is s > s0.
//!
//! # Average radial tensile stress: the averaging domain is an explicit option
//!
//! Outside the contact σ_r ∝ 1/r², so on a half-space the tensile zone is unbounded and any
//! average needs an outer limit L ([`AveragingDomain`]):
//!
//! ```text
//! line:  σ̄ = [p0 a I_in + (1−2ν) p0 a (1 − a/L)/3] / (L − s0 a)
//! area:  σ̄ = [p0 a² J_in + (2π/3)(1−2ν) p0 a² ln(L/a)] / (π (L² − s0² a²))
//! I_in = ∫_{s0}^1 σ_r/p0 ds,   J_in = ∫_{s0}^1 σ_r/p0 2πs ds
//! ```
//!
//! **Default: line average with L = κ·a, κ = 2.** Reasons: (1) with L tied to the contact
//! radius σ̄ is exactly proportional to p0, so the stress measured in a crush test (a/R ≈ 0.18)
//! and the stress of an impact (a/R ≈ 0.04–0.1) are the same functional of the contact and the
//! crush → impact transfer carries no a/R bias (with L = R it does, see docs/reference.md, mechanics §3.3);
//! (2) ring cracks in brittle spheres start within about 1–1.5 a, so the band [s0 a, 2a] holds
//! the stresses that matter; (3) the half-space solution stays valid there (2a ≈ 0.36 R at
//! break). With L = κa the lifetime prediction does not depend on κ at all: κ rescales σ̄ and
//! the fitted Weibull scale by the same constant. `outer = "particle_radius"` (L = R) is
//! available to reproduce the alternative reading of the deliverable.
//!
//! # Impact with elastic energy fraction η
//!
//! A fraction η of the kinetic energy ½ m* V² is stored elastically (the deliverable's "about
//! 10 %"); equivalently the contact is a Hertz impact at V_eff = √η V:
//!
//! ```text
//! δ_m = [15 m* V_eff² / (16 E* √R*)]^(2/5)   F_max = (4/3) E* √R* δ_m^(3/2)
//! t_c = τ_c δ_m / V_eff,  τ_c = (4/5) B(2/5, 1/2) = 2.943275
//! ```
//!
//! The force history solves m* δ̈ = −(4/3) E* √R* δ^(3/2) (δ(0) = 0, δ̇(0) = V_eff), whose
//! scaled form x'' = −(5/4) x^(3/2) is integrated once with RK4; the running impulse is exact
//! from momentum, J(t) = m* (V_eff − δ̇(t)), and totals 2 m* V_eff. For a sphere on a massive
//! wall m* = m; for two equal spheres m* = m/2, R* = R/2 and V is the relative velocity.
//!
//! Verified by `tests/verification/hertz.rs` (docs/reference.md, mechanics tables §2.1, §2.4, §3.2–3.4) and
//! the unit tests below (finite-difference stiffness, continuity, limits, impulse).

use serde::{Deserialize, Serialize};

mod impact;
pub use impact::*;

use crate::error::{Error, Result};

/// Isotropic linear-elastic constants of a body.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Elastic {
    /// Young's modulus E (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio ν (-), in (−1, 0.5).
    pub poisson_ratio: f64,
}

impl Elastic {
    /// Validated constructor: E > 0 and −1 < ν < 0.5.
    pub fn new(youngs_modulus_pa: f64, poisson_ratio: f64) -> Result<Self> {
        let e = Elastic { youngs_modulus_pa, poisson_ratio };
        e.validate("elastic")?;
        Ok(e)
    }

    /// Checks E > 0 and −1 < ν < 0.5; `key` names the configuration entry in the message.
    pub fn validate(&self, key: &str) -> Result<()> {
        if !(self.youngs_modulus_pa.is_finite() && self.youngs_modulus_pa > 0.0) {
            return Err(Error::config(
                "<elastic>",
                format!("{key}.youngs_modulus_pa"),
                format!("must be a finite number > 0 (got {})", self.youngs_modulus_pa),
            ));
        }
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return Err(Error::config(
                "<elastic>",
                format!("{key}.poisson_ratio"),
                format!("must lie in (-1, 0.5) (got {})", self.poisson_ratio),
            ));
        }
        Ok(())
    }

    /// The constants of shear modulus `g` and bulk modulus `k` (Pa): E = 9KG/(3K + G),
    /// ν = (3K − 2G)/(2(3K + G)); not validated.
    pub fn from_shear_and_bulk(g: f64, k: f64) -> Self {
        Elastic { youngs_modulus_pa: 9.0 * k * g / (3.0 * k + g), poisson_ratio: (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g)) }
    }

    /// The Lamé constants (λ, μ) (Pa): μ = E/(2(1 + ν)), λ = Eν/((1 + ν)(1 − 2ν)).
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.youngs_modulus_pa, self.poisson_ratio);
        (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)))
    }

    /// Compliance term (1 − ν²)/E (1/Pa).
    pub fn compliance(&self) -> f64 {
        (1.0 - self.poisson_ratio * self.poisson_ratio) / self.youngs_modulus_pa
    }
}

/// Effective contact modulus E* of two bodies (Pa).
pub fn effective_modulus(a: &Elastic, b: &Elastic) -> f64 {
    1.0 / (a.compliance() + b.compliance())
}

/// Effective modulus of a body against a rigid counterpart, E/(1 − ν²) (Pa).
pub fn effective_modulus_rigid(a: &Elastic) -> f64 {
    1.0 / a.compliance()
}

/// A Hertz contact: effective modulus, effective radius, and the Poisson ratio of the body
/// whose surface stresses are evaluated (the particle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hertz {
    /// Effective modulus E* (Pa).
    pub e_star: f64,
    /// Effective radius of curvature R* (m).
    pub r_star: f64,
    /// Poisson's ratio ν of the body whose stresses are evaluated (-).
    pub nu: f64,
}

impl Hertz {
    /// Contact of a sphere (radius of curvature `radius`) with a flat counterpart.
    pub fn sphere_on_flat(particle: &Elastic, flat: &Elastic, radius: f64) -> Self {
        Hertz { e_star: effective_modulus(particle, flat), r_star: radius, nu: particle.poisson_ratio }
    }

    /// Contact of two equal spheres of the same material (radius of curvature `radius`).
    pub fn sphere_on_sphere(particle: &Elastic, radius: f64) -> Self {
        Hertz {
            e_star: effective_modulus(particle, particle),
            r_star: radius / 2.0,
            nu: particle.poisson_ratio,
        }
    }

    /// Stiffness constant K = (4/3) E* √R* in F = K δ^(3/2) (N/m^(3/2)).
    pub fn stiffness_constant(&self) -> f64 {
        4.0 / 3.0 * self.e_star * self.r_star.sqrt()
    }

    /// Contact radius a (m) at normal force F (N).
    pub fn contact_radius(&self, force: f64) -> f64 {
        (3.0 * force * self.r_star / (4.0 * self.e_star)).cbrt()
    }

    /// Approach δ (m) at force F (N): δ = a²/R*.
    pub fn approach(&self, force: f64) -> f64 {
        let a = self.contact_radius(force);
        a * a / self.r_star
    }

    /// Force F (N) at approach δ (m).
    pub fn force_at_approach(&self, approach: f64) -> f64 {
        self.stiffness_constant() * approach.max(0.0).powf(1.5)
    }

    /// Peak pressure p0 = 3F/(2πa²) (Pa).
    pub fn peak_pressure(&self, force: f64) -> f64 {
        let a = self.contact_radius(force);
        3.0 * force / (2.0 * std::f64::consts::PI * a * a)
    }
}

/// Surface stresses in units of p0 (compression negative).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceStress {
    /// Radial stress σ_r/p0.
    pub radial: f64,
    /// Hoop stress σ_θ/p0.
    pub hoop: f64,
    /// Normal stress σ_z/p0.
    pub normal: f64,
}

/// Hertz surface stresses at s = r/a (Johnson 1985, eq. 3.41), in units of p0.
///
/// ```
/// # use partlife::contact::surface_stress;
/// let nu = 0.25;
/// // Centre: σ_r = σ_θ = −(1+2ν)/2; edge: σ_r = (1−2ν)/3.
/// assert!((surface_stress(0.0, nu).radial + 0.75).abs() < 1e-12);
/// assert!((surface_stress(1.0, nu).radial - 0.5 / 3.0).abs() < 1e-12);
/// ```
pub fn surface_stress(s: f64, nu: f64) -> SurfaceStress {
    let s = s.abs();
    let k = (1.0 - 2.0 * nu) / 3.0;
    if s >= 1.0 {
        let t = k / (s * s);
        return SurfaceStress { radial: t, hoop: -t, normal: 0.0 };
    }
    let x = s * s;
    // [1 − (1−x)^(3/2)]/x, computed without cancellation; → 3/2 as x → 0.
    let g = if x == 0.0 { 1.5 } else { -(1.5 * (-x).ln_1p()).exp_m1() / x };
    let root = (1.0 - x).sqrt();
    SurfaceStress { radial: k * g - root, hoop: -k * g - 2.0 * nu * root, normal: -root }
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton iteration on P_n).
fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    let nf = n as f64;
    for i in 0..n.div_ceil(2) {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, 0.0);
            for j in 0..n {
                let p2 = p1;
                p1 = p0;
                p0 = ((2.0 * j as f64 + 1.0) * z * p1 - j as f64 * p2) / (j as f64 + 1.0);
            }
            dp = nf * (z * p0 - p1) / (z * z - 1.0);
            let dz = p0 / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
        w[n - 1 - i] = w[i];
    }
    (x, w)
}

/// The tensile zone of the Hertz surface field for one Poisson ratio: onset s0 and the small
/// contributions from inside the contact (docs/reference.md, mechanics §3.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TensileZone {
    /// Poisson's ratio ν.
    pub nu: f64,
    /// s0: σ_r(s0) = 0, 0 < s0 < 1; σ_r > 0 for s > s0.
    pub s0: f64,
    /// I_in = ∫_{s0}^1 σ_r/p0 ds.
    pub i_in: f64,
    /// J_in = ∫_{s0}^1 σ_r/p0 2πs ds.
    pub j_in: f64,
}

impl TensileZone {
    /// Computes s0 by bisection and the integrals by 32-point Gauss–Legendre in u, s = 1 − u²
    /// (which removes the √(1−s) edge singularity). The zone of the last ν asked for on this
    /// thread is kept: the main study builds one contact per sample and particle, nearly always
    /// at one ν, and the zone was a fifth of its time (the same bits either way).
    pub fn new(nu: f64) -> Self {
        thread_local! {
            static LAST: std::cell::Cell<Option<TensileZone>> = const { std::cell::Cell::new(None) };
        }
        if let Some(z) = LAST.get().filter(|z| z.nu.to_bits() == nu.to_bits()) {
            return z;
        }
        let z = Self::compute(nu);
        LAST.set(Some(z));
        z
    }

    fn compute(nu: f64) -> Self {
        static GAUSS: std::sync::OnceLock<(Vec<f64>, Vec<f64>)> = std::sync::OnceLock::new();
        let f = |s: f64| surface_stress(s, nu).radial;
        let (mut lo, mut hi) = (1e-9, 1.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            // Adjacent numbers: nothing changes any more.
            if mid == lo || mid == hi {
                break;
            }
            if f(mid) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let s0 = 0.5 * (lo + hi);
        let (nodes, weights) = GAUSS.get_or_init(|| gauss_legendre(32));
        let umax = (1.0 - s0).sqrt();
        let (mut i_in, mut j_in) = (0.0, 0.0);
        for (xi, wi) in nodes.iter().zip(weights) {
            let u = 0.5 * umax * (xi + 1.0);
            let s = 1.0 - u * u;
            let jac = 2.0 * u * 0.5 * umax;
            let sr = f(s);
            i_in += wi * sr * jac;
            j_in += wi * sr * 2.0 * std::f64::consts::PI * s * jac;
        }
        TensileZone { nu, s0, i_in, j_in }
    }

    /// Maximum surface tension σ_r(a)/p0 = (1 − 2ν)/3.
    pub fn edge_factor(&self) -> f64 {
        (1.0 - 2.0 * self.nu) / 3.0
    }
}

/// How the tensile radial stress is averaged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AveragingMeasure {
    /// Average along a radius: ∫σ_r dr / (L − s0 a).
    Line,
    /// Area-weighted average over the annulus: ∫σ_r 2πr dr / π(L² − s0² a²).
    Area,
}

/// Outer limit L of the averaging domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OuterLimit {
    /// L = κ·a: σ̄ ∝ p0 exactly (default, κ = 2).
    ContactMultiple,
    /// L = R, the particle radius: σ̄ depends on a/R.
    ParticleRadius,
}

/// Averaging domain [s0·a, L] of the radial tensile stress.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AveragingDomain {
    /// Line or area average.
    pub measure: AveragingMeasure,
    /// Outer limit.
    pub outer: OuterLimit,
    /// κ in L = κ·a (used with `outer = "contact_multiple"`), > 1.
    #[serde(default = "default_kappa")]
    pub kappa: f64,
}

fn default_kappa() -> f64 {
    2.0
}

impl Default for AveragingDomain {
    fn default() -> Self {
        AveragingDomain {
            measure: AveragingMeasure::Line,
            outer: OuterLimit::ContactMultiple,
            kappa: default_kappa(),
        }
    }
}

impl AveragingDomain {
    /// Checks κ > 1 (finite); `file`/`key` locate the option in messages.
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        if !(self.kappa.is_finite() && self.kappa > 1.0) {
            return Err(Error::config(
                file,
                format!("{key}.kappa"),
                format!("the averaging domain must reach beyond the contact edge: kappa > 1 (got {})", self.kappa),
            ));
        }
        Ok(())
    }

    /// Outer limit L (m) for contact radius a and particle radius R.
    pub fn outer_limit(&self, a: f64, particle_radius: f64) -> f64 {
        match self.outer {
            OuterLimit::ContactMultiple => self.kappa * a,
            OuterLimit::ParticleRadius => particle_radius,
        }
    }

    /// Short description for tables and legends.
    pub fn describe(&self) -> String {
        let m = match self.measure {
            AveragingMeasure::Line => "line",
            AveragingMeasure::Area => "area",
        };
        match self.outer {
            OuterLimit::ContactMultiple => format!("{m} average over [s0·a, {}·a]", self.kappa),
            OuterLimit::ParticleRadius => format!("{m} average over [s0·a, R]"),
        }
    }

    /// Mean tensile radial stress σ̄ (Pa) for peak pressure p0, contact radius a and particle
    /// radius R. Fails when the outer limit does not lie outside the contact (L ≤ a).
    pub fn mean_tensile_stress(
        &self,
        zone: &TensileZone,
        p0: f64,
        a: f64,
        particle_radius: f64,
    ) -> Result<f64> {
        let l = self.outer_limit(a, particle_radius);
        if l.is_nan() || l <= a {
            return Err(Error::numerical(
                "average tensile stress",
                format!(
                    "outer limit L = {l:.4e} m does not lie outside the contact radius a = {a:.4e} m \
                     (contact larger than the averaging domain)"
                ),
            ));
        }
        let k = zone.edge_factor();
        Ok(match self.measure {
            AveragingMeasure::Line => p0 * a * (zone.i_in + k * (1.0 - a / l)) / (l - zone.s0 * a),
            AveragingMeasure::Area => {
                let pi = std::f64::consts::PI;
                p0 * a * a * (zone.j_in + 2.0 * pi * k * (l / a).ln())
                    / (pi * (l * l - zone.s0 * zone.s0 * a * a))
            }
        })
    }

    /// σ̄/p0 when it is a constant (L = κa); `None` when it depends on a/R.
    pub fn ratio_to_peak_pressure(&self, zone: &TensileZone) -> Option<f64> {
        match self.outer {
            OuterLimit::ContactMultiple => self.mean_tensile_stress(zone, 1.0, 1.0, 0.0).ok(),
            OuterLimit::ParticleRadius => None,
        }
    }
}

/// Contact options of the crush test: the platen and the averaging domain of σ̄ (the `[contact]`
/// section of a study).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactOptions {
    /// Platen material (default: steel, E = 210 GPa, ν = 0.3).
    pub platen: Elastic,
    /// Averaging domain of the radial tensile stress (default: line, L = 2a; see the module
    /// docs for why).
    pub averaging: AveragingDomain,
}

impl Default for ContactOptions {
    fn default() -> Self {
        ContactOptions { platen: Elastic { youngs_modulus_pa: 210e9, poisson_ratio: 0.3 }, averaging: AveragingDomain::default() }
    }
}

/// Contact state at one force: what the lifetime chain needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactState {
    /// Normal force F (N).
    pub force: f64,
    /// Contact radius a (m).
    pub radius: f64,
    /// Approach δ at this contact (m).
    pub approach: f64,
    /// Peak pressure p0 (Pa).
    pub peak_pressure: f64,
    /// Maximum surface tension σ_r(a) = (1 − 2ν) p0/3 (Pa).
    pub max_tensile: f64,
    /// Average radial tensile stress σ̄ over the averaging domain (Pa).
    pub mean_tensile: f64,
}

/// Evaluates contact states of one contact geometry with one averaging domain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactStress {
    /// The contact.
    pub hertz: Hertz,
    /// Tensile zone for the particle's ν.
    pub zone: TensileZone,
    /// Averaging domain.
    pub domain: AveragingDomain,
    /// Particle radius R (m), used by `outer = "particle_radius"`.
    pub particle_radius: f64,
}

impl ContactStress {
    /// Builds the evaluator (computes the tensile zone once).
    pub fn new(hertz: Hertz, domain: AveragingDomain, particle_radius: f64) -> Self {
        ContactStress { hertz, zone: TensileZone::new(hertz.nu), domain, particle_radius }
    }

    /// Full contact state at force F (N).
    pub fn at_force(&self, force: f64) -> Result<ContactState> {
        let a = self.hertz.contact_radius(force);
        let p0 = 3.0 * force / (2.0 * std::f64::consts::PI * a * a);
        Ok(ContactState {
            force,
            radius: a,
            approach: a * a / self.hertz.r_star,
            peak_pressure: p0,
            max_tensile: self.zone.edge_factor() * p0,
            mean_tensile: self.domain.mean_tensile_stress(&self.zone, p0, a, self.particle_radius)?,
        })
    }

    /// Radial surface stress σ_r (Pa) at distance r (m) from the contact centre, at force F.
    pub fn radial_stress_at(&self, force: f64, r: f64) -> f64 {
        let a = self.hertz.contact_radius(force);
        let p0 = 3.0 * force / (2.0 * std::f64::consts::PI * a * a);
        p0 * surface_stress(r / a, self.hertz.nu).radial
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bauxite() -> Elastic {
        Elastic::new(112e9, 0.25).unwrap()
    }
    fn steel() -> Elastic {
        Elastic::new(210e9, 0.3).unwrap()
    }

    #[test]
    fn stiffness_matches_finite_difference() {
        // dF/dδ = 2 E* a (Johnson 1985 eq. 4.25) against a central difference.
        let h = Hertz::sphere_on_flat(&bauxite(), &steel(), 0.5e-3);
        for &f in &[1.0, 50.0, 150.0] {
            let d = h.approach(f);
            let e = 1e-6 * d;
            let fd = (h.force_at_approach(d + e) - h.force_at_approach(d - e)) / (2.0 * e);
            let exact = 2.0 * h.e_star * h.contact_radius(f);
            assert!((fd / exact - 1.0).abs() < 1e-8, "F={f}: {fd} vs {exact}");
            assert!((h.force_at_approach(d) / f - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn surface_stress_is_continuous_and_balanced() {
        for &nu in &[0.2, 0.25, 0.3] {
            let inside = surface_stress(1.0 - 1e-12, nu);
            let outside = surface_stress(1.0 + 1e-12, nu);
            assert!((inside.radial - outside.radial).abs() < 1e-5);
            assert!((inside.hoop - outside.hoop).abs() < 1e-5);
            // Series limit at the centre.
            let c = surface_stress(1e-8, nu);
            assert!((c.radial + (1.0 + 2.0 * nu) / 2.0).abs() < 1e-10);
            assert!((c.hoop - c.radial).abs() < 1e-10);
        }
    }

    #[test]
    fn pressure_integrates_to_force() {
        // ∫ p(r) 2πr dr = F with p = p0 √(1 − r²/a²).
        let h = Hertz::sphere_on_flat(&bauxite(), &steel(), 0.45e-3);
        let f = 120.0;
        let (a, p0) = (h.contact_radius(f), h.peak_pressure(f));
        let n = 100_000;
        let mut sum = 0.0;
        for i in 0..n {
            let r = (i as f64 + 0.5) / n as f64 * a;
            sum += p0 * (1.0 - (r / a).powi(2)).sqrt() * 2.0 * std::f64::consts::PI * r * a / n as f64;
        }
        assert!((sum / f - 1.0).abs() < 1e-6);
    }

    #[test]
    fn gauss_legendre_is_exact_for_polynomials() {
        let (x, w) = gauss_legendre(8);
        let int: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(14)).sum();
        assert!((int - 2.0 / 15.0).abs() < 1e-14);
    }

    #[test]
    fn contact_multiple_average_is_proportional_to_p0() {
        let d = AveragingDomain::default();
        let z = TensileZone::new(0.25);
        let c = d.ratio_to_peak_pressure(&z).unwrap();
        let s = d.mean_tensile_stress(&z, 3.7e9, 42e-6, 0.5e-3).unwrap();
        assert!((s / 3.7e9 - c).abs() < 1e-14);
        // Numerical line average over [s0 a, 2a] agrees with the closed form.
        let n = 200_000;
        let (lo, hi) = (z.s0, 2.0);
        let mut sum = 0.0;
        for i in 0..n {
            let s = lo + (i as f64 + 0.5) / n as f64 * (hi - lo);
            sum += surface_stress(s, 0.25).radial;
        }
        assert!((sum / n as f64 - c).abs() < 1e-6);
    }

    #[test]
    fn too_small_domain_is_an_error() {
        let d = AveragingDomain { outer: OuterLimit::ParticleRadius, ..Default::default() };
        let z = TensileZone::new(0.25);
        assert!(d.mean_tensile_stress(&z, 1e9, 1e-3, 0.5e-3).is_err());
        let bad = AveragingDomain { kappa: 1.0, ..Default::default() };
        assert!(bad.validate("s.toml", "contact.averaging").is_err());
    }

    #[test]
    fn impact_history_conserves_momentum_and_peaks_at_f_max() {
        let sphere = Sphere { diameter: 1e-3, density: 3600.0, elastic: bauxite() };
        let imp = Impact::sphere_on_wall(&sphere, &steel(), 0.5e-3, 0.1);
        let v = 5.0;
        let hist = imp.force_history(v, 401).unwrap();
        let fmax = hist.iter().map(|s| s.force).fold(0.0, f64::max);
        assert!((fmax / imp.max_force(v) - 1.0).abs() < 1e-4, "{fmax}");
        let last = hist.last().unwrap();
        assert!((last.time / imp.contact_time(v) - 1.0).abs() < 1e-12);
        // Trapezoid integral of F equals the momentum-based running impulse.
        let mut j = 0.0;
        for w in hist.windows(2) {
            j += 0.5 * (w[0].force + w[1].force) * (w[1].time - w[0].time);
        }
        let total = 2.0 * imp.effective_mass * imp.effective_velocity(v);
        assert!((j / total - 1.0).abs() < 1e-4, "{j} vs {total}");
        assert!((last.impulse / total - 1.0).abs() < 1e-12);
        // The RK4 trajectory returns to zero approach at τ_c with unit speed: one sample before
        // the end, x ≈ Δτ, so F/F_max ≈ Δτ^(3/2) (independent of the exact last sample).
        let dtau = dimensionless_contact_time() / 400.0;
        let ratio = hist[hist.len() - 2].force / fmax;
        assert!((ratio / dtau.powf(1.5) - 1.0).abs() < 0.01, "{ratio} vs {}", dtau.powf(1.5));
    }

    #[test]
    fn contact_time_constant() {
        // Independent check: τ_c = 2 ∫0^1 dx/√(1 − x^(5/2)); with x = 1 − u² the edge
        // singularity disappears. Midpoint rule, 10^6 panels.
        let n = 1_000_000;
        let mut sum = 0.0;
        for i in 0..n {
            let u = (i as f64 + 0.5) / n as f64;
            let x: f64 = 1.0 - u * u;
            sum += 2.0 * u / (1.0 - x.powf(2.5)).sqrt() / n as f64;
        }
        assert!((dimensionless_contact_time() - 2.0 * sum).abs() < 1e-6, "{}", 2.0 * sum);
        // docs/reference.md, mechanics §3.4 prints 2.9432.
        assert!((dimensionless_contact_time() - 2.9432).abs() < 1e-4);
    }
}

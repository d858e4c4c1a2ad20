//! The 4-node quad with one-point integration and Flanagan–Belytschko stiffness hourglass
//! control, axisymmetric (r, z) with hoop strain or plane strain.
//!
//! At the centroid (Flanagan & Belytschko 1981, Int. J. Numer. Meth. Eng. 17, 679):
//! `b_r = [z₂−z₄, z₃−z₁, z₄−z₂, z₁−z₃]/2A`, `b_z = [r₄−r₂, r₁−r₃, r₂−r₄, r₃−r₁]/2A`,
//! `D_rr = b_r·v_r`, `D_zz = b_z·v_z`, `D_rz = ½(b_z·v_r + b_r·v_z)`, `w = ½(b_z·v_r − b_r·v_z)`,
//! hoop `D_θθ = v̄_r / r̄` (axisymmetric; 0 in plane strain).
//!
//! Internal nodal forces per radian (axisymmetric, volume-weighted like LS-DYNA's type 15
//! element; V = A r̄):
//! `f_ri = (σ_rr b_ri + σ_rz b_zi) V + σ_θθ A/4`, `f_zi = (σ_rz b_ri + σ_zz b_zi) V`.
//!
//! Why one-point integration: the material update (JH-2, with `powf` in the strength and damage
//! laws) is the cost of a step, and one point per element is a quarter of that of 2×2 Gauss; it
//! also avoids volumetric locking near ν = 0.5 without a B-bar projection. Its zero-energy
//! (hourglass) modes `γ = ¼[h − (h·r) b_r − (h·z) b_z]`, `h = (1, −1, 1, −1)`, are resisted by a
//! stiffness (not viscous) generalised force, because a quasi-static crush moves too slowly for
//! viscous control to act: `Q̇ = κ γ·v`, `κ = q_hg M (b·b) V`, with M = K + 4G/3 and q_hg ≈ 0.05.
//! The hourglass energy is tracked and reported next to the internal energy.
//!
//! Bulk viscosity (compression only, as LS-DYNA): `q = ρ ℓ (Q₂ ℓ ε̇_v² − Q₁ c ε̇_v)`, ℓ = √A.
//!
//! Verified by `tests/verification/crush_fe.rs` (patch test, rigid-body motion, energy, Hertz).

// Index loops over the four nodes read like the formulas above.
#![allow(clippy::needless_range_loop)]

use super::material::{Material, PointState};

/// Element-level constants shared by all elements of a run.
#[derive(Debug, Clone, Copy)]
pub struct Kernel {
    /// The material.
    pub material: Material,
    /// Axisymmetric (true) or plane strain.
    pub axisymmetric: bool,
    /// Hourglass stiffness coefficient q_hg (-).
    pub hourglass: f64,
    /// Linear bulk viscosity Q₁ (-).
    pub q_linear: f64,
    /// Quadratic bulk viscosity Q₂ (-).
    pub q_quadratic: f64,
    /// Whether the material needs the equivalent strain rate (JH-2 with C > 0).
    pub needs_rate: bool,
    /// Density ρ₀ (kg/m³), physical (mass scaling is applied to nodal masses only).
    pub density: f64,
    /// Dilatational wave speed at zero strain (m/s).
    pub wave_speed: f64,
    /// Geometrically linear kinematics: gradients on the initial configuration, no spin, μ from
    /// the integrated volumetric strain (for comparison with small-strain theory such as Hertz).
    pub small_strain: bool,
}

/// Per-element state.
#[derive(Debug, Clone, Copy, Default)]
pub struct ElementState {
    /// Material point.
    pub point: PointState,
    /// Hourglass generalised forces (r, z) (N per radian, or N/m in plane strain).
    pub hg: [f64; 2],
    /// Initial volume per radian (m³) or area (m², plane strain).
    pub v0: f64,
    /// Bulk viscosity pressure at the last update (Pa).
    pub q: f64,
    /// Volumetric strain rate at the last update (1/s).
    pub rate_v: f64,
    /// Integrated volumetric strain Σ tr(D) Δt (-), used by small-strain kinematics.
    pub ev: f64,
}

/// Centroid geometry.
#[derive(Debug, Clone, Copy, Default)]
pub struct Geometry {
    /// Area (m²).
    pub area: f64,
    /// `∂N/∂r` at the centroid.
    pub br: [f64; 4],
    /// `∂N/∂z` at the centroid.
    pub bz: [f64; 4],
    /// Mean radius r̄ (m); 1 in plane strain.
    pub rc: f64,
}

/// What [`Kernel::begin`] leaves for [`Kernel::finish`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Half {
    g: Geometry,
    vol: f64,
    /// tr D (1/s).
    ev: f64,
    de: [f64; 4],
    w_dt: f64,
    mu: f64,
    rate_eq: f64,
    /// The stress and bulk-viscosity pressure before the step.
    old: [f64; 4],
    old_q: f64,
    /// Hourglass shape vector and energy increment.
    gamma: [f64; 4],
    e_hg: f64,
}

/// Centroid geometry of a quad; `None` when the area is not positive.
#[inline]
pub fn geometry(x: &[[f64; 2]; 4], axisymmetric: bool) -> Option<Geometry> {
    let (r, z) = ([x[0][0], x[1][0], x[2][0], x[3][0]], [x[0][1], x[1][1], x[2][1], x[3][1]]);
    let area = 0.5 * ((r[2] - r[0]) * (z[3] - z[1]) + (r[1] - r[3]) * (z[2] - z[0]));
    if area.is_nan() || area <= 0.0 {
        return None;
    }
    let inv = 0.5 / area;
    let br = [(z[1] - z[3]) * inv, (z[2] - z[0]) * inv, (z[3] - z[1]) * inv, (z[0] - z[2]) * inv];
    let bz = [(r[3] - r[1]) * inv, (r[0] - r[2]) * inv, (r[1] - r[3]) * inv, (r[2] - r[0]) * inv];
    let rc = if axisymmetric { 0.25 * (r[0] + r[1] + r[2] + r[3]) } else { 1.0 };
    Some(Geometry { area, br, bz, rc })
}

impl Kernel {
    /// Updates one element over `dt` from the node positions `x` (current, or initial with
    /// small-strain kinematics) and velocities `v`; returns its internal forces and the
    /// (internal, hourglass) energy increments per radian, or `None` if the element is inverted.
    /// The forces are `[r₁, z₁, …, r₄, z₄]`, to be subtracted.
    #[inline]
    pub fn update(&self, x: &[[f64; 2]; 4], v: &[[f64; 2]; 4], st: &mut ElementState, dt: f64) -> Option<([f64; 8], f64, f64)> {
        let h = self.begin(x, v, st, dt)?;
        Some(self.finish(&h, st))
    }

    /// The first half of [`Kernel::update`]: geometry, kinematics and the hourglass forces. A
    /// block of elements runs this half for each, then [`Kernel::finish`] for each: each half
    /// is a long chain of dependent operations (here three divisions; there the material's
    /// division and square roots), and running one half back to back for neighbouring
    /// elements lets the processor overlap their chains (about 7 % more element-steps per
    /// second on one core than one pass per element; splitting the material off into a third
    /// half was slower). Each element sees the same operations in the same order as in one
    /// pass, so the result is the same to the bit.
    #[inline(always)]
    pub fn begin(&self, x: &[[f64; 2]; 4], v: &[[f64; 2]; 4], st: &mut ElementState, dt: f64) -> Option<Half> {
        let g = geometry(x, self.axisymmetric)?;
        let vol = g.area * g.rc;
        let (mut dvr_dr, mut dvr_dz, mut dvz_dr, mut dvz_dz, mut vr) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for i in 0..4 {
            dvr_dr += g.br[i] * v[i][0];
            dvr_dz += g.bz[i] * v[i][0];
            dvz_dr += g.br[i] * v[i][1];
            dvz_dz += g.bz[i] * v[i][1];
            vr += v[i][0];
        }
        let d_tt = if self.axisymmetric { 0.25 * vr / g.rc } else { 0.0 };
        let d = [dvr_dr, dvz_dz, d_tt, 0.5 * (dvr_dz + dvz_dr)];
        let de = [d[0] * dt, d[1] * dt, d[2] * dt, d[3] * dt];
        st.ev += de[0] + de[1] + de[2];
        let (w, mu) = if self.small_strain { (0.0, (-st.ev).exp() - 1.0) } else { (0.5 * (dvr_dz - dvz_dr), st.v0 / vol - 1.0) };
        let rate_eq = if self.needs_rate {
            let tr = (d[0] + d[1] + d[2]) / 3.0;
            let (a, b, c) = (d[0] - tr, d[1] - tr, d[2] - tr);
            (2.0 / 3.0 * (a * a + b * b + c * c + 2.0 * d[3] * d[3])).sqrt()
        } else {
            0.0
        };
        let old = st.point.stress();
        let old_q = st.q;
        // Hourglass control.
        let mut gamma = [0.0; 4];
        let mut e_hg = 0.0;
        if self.hourglass > 0.0 {
            const H: [f64; 4] = [1.0, -1.0, 1.0, -1.0];
            let hr: f64 = (0..4).map(|i| H[i] * x[i][0]).sum();
            let hz: f64 = (0..4).map(|i| H[i] * x[i][1]).sum();
            let (mut qr, mut qz) = (0.0, 0.0);
            for i in 0..4 {
                gamma[i] = 0.25 * (H[i] - hr * g.br[i] - hz * g.bz[i]);
                qr += gamma[i] * v[i][0];
                qz += gamma[i] * v[i][1];
            }
            let bb: f64 = (0..4).map(|i| g.br[i] * g.br[i] + g.bz[i] * g.bz[i]).sum();
            let kappa = self.hourglass * self.density * self.wave_speed * self.wave_speed * bb * vol;
            let (hr0, hz0) = (st.hg[0], st.hg[1]);
            st.hg[0] += kappa * qr * dt;
            st.hg[1] += kappa * qz * dt;
            e_hg = 0.5 * ((hr0 + st.hg[0]) * qr + (hz0 + st.hg[1]) * qz) * dt;
        }
        Some(Half { g, vol, ev: d[0] + d[1] + d[2], de, w_dt: w * dt, mu, rate_eq, old, old_q, gamma, e_hg })
    }

    /// The second half of [`Kernel::update`] after [`Kernel::begin`] on the same state: the
    /// material update, bulk viscosity, internal energy and nodal forces.
    #[inline(always)]
    pub fn finish(&self, h: &Half, st: &mut ElementState) -> ([f64; 8], f64, f64) {
        let (g, vol, de, old, old_q) = (&h.g, h.vol, &h.de, &h.old, h.old_q);
        self.material.trial(&mut st.point, de, h.w_dt);
        self.material.settle(&mut st.point, h.mu, h.rate_eq);
        // Bulk viscosity.
        let ev = h.ev;
        st.rate_v = ev;
        st.q = if ev < 0.0 && (self.q_linear > 0.0 || self.q_quadratic > 0.0) {
            let l = g.area.sqrt();
            self.density * l * (self.q_quadratic * l * ev * ev - self.q_linear * self.wave_speed * ev)
        } else {
            0.0
        };
        let s = st.point.stress();
        let q = st.q;
        let sig = [s[0] - q, s[1] - q, s[2] - q, s[3]];
        // Internal energy increment, midpoint stress.
        let e_int = vol
            * (0.5 * (sig[0] + old[0] - old_q) * de[0]
                + 0.5 * (sig[1] + old[1] - old_q) * de[1]
                + 0.5 * (sig[2] + old[2] - old_q) * de[2]
                + (sig[3] + old[3]) * de[3]);
        let mut out = [0.0; 8];
        let hoop = if self.axisymmetric { 0.25 * sig[2] * g.area } else { 0.0 };
        for i in 0..4 {
            out[2 * i] = (sig[0] * g.br[i] + sig[3] * g.bz[i]) * vol + hoop;
            out[2 * i + 1] = (sig[3] * g.br[i] + sig[1] * g.bz[i]) * vol;
        }
        if self.hourglass > 0.0 {
            for i in 0..4 {
                out[2 * i] += st.hg[0] * h.gamma[i];
                out[2 * i + 1] += st.hg[1] * h.gamma[i];
            }
        }
        (out, e_int, h.e_hg)
    }

    /// Stable time step of one element (s): `ℓ/(Q + √(Q² + c²))`, ℓ = A / longest diagonal,
    /// c from the material's current wave modulus, Q the bulk-viscosity speed; `mass_scaling`
    /// multiplies the density.
    pub fn critical_step(&self, x: &[[f64; 2]; 4], st: &ElementState, mass_scaling: f64) -> f64 {
        let Some(g) = geometry(x, self.axisymmetric) else { return 0.0 };
        let d13 = ((x[2][0] - x[0][0]).powi(2) + (x[2][1] - x[0][1]).powi(2)).sqrt();
        let d24 = ((x[3][0] - x[1][0]).powi(2) + (x[3][1] - x[1][1]).powi(2)).sqrt();
        let l = g.area / d13.max(d24);
        let mu = st.v0 / (g.area * g.rc) - 1.0;
        let rho = self.density * mass_scaling;
        let c = (self.material.wave_modulus(mu) / rho).sqrt();
        let qv = if st.rate_v < 0.0 { self.q_linear * c + self.q_quadratic * l * st.rate_v.abs() } else { 0.0 };
        l / (qv + (qv * qv + c * c).sqrt())
    }
}

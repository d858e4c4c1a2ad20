//! Constitutive models of the crush FE: [`LinearElastic`] (verification) and the
//! Johnson–Holmquist-2 ceramic model ([`Jh2Params`], `kind = "jh2"`), both in rate (hypo-elastic) form.
//!
//! Stress is stored as four tensor components `[rr, zz, θθ, rz]` (plane strain: `θθ` is the
//! out-of-plane `yy`), compression negative, with the deviator `s` and the pressure
//! `P = −tr σ / 3` (compression positive) kept apart: `σ = s − P I`.
//!
//! ## Update per point and step (docs/reference.md, mechanics §1.6)
//! 1. Jaumann rotation of `s` by the in-plane spin `w·Δt` (objective rate):
//!    `Δs_rr = 2w s_rz`, `Δs_zz = −2w s_rz`, `Δs_rz = w (s_zz − s_rr)`.
//! 2. Trial deviator `s_tr = s + 2G dev(Δε)`, Δε = D Δt the rate-of-deformation increment.
//! 3. Pressure from the current volume ratio, `μ = V₀/V − 1` (exact, not integrated):
//!    * linear elastic: `P = K ln(1 + μ)` (logarithmic volumetric strain);
//!    * JH-2: `P = K1 μ + K2 μ² + K3 μ³ + ΔP` for μ > 0, `P = K1 μ` for μ ≤ 0, then the tensile
//!      cut-off `P ≥ −T (1 − D)` (docs/reference.md, mechanics §1.4).
//! 4. JH-2 strength, normalised by HEL quantities (§1.1–1.2):
//!    `σ_i* = A (P* + T*)^N`, `σ_f* = min(B P*^M, SFMAX)`, `σ_y = σ_HEL [(1 − D) σ_i* + D σ_f*]`,
//!    times `1 + C ln ε̇*` when `ε̇* = ε̇_eq/EPSI ≥ 1`.
//! 5. Radial return when `σ_eq,tr > σ_y`: `s = s_tr σ_y/σ_eq,tr`,
//!    `Δε_p = (σ_eq,tr − σ_y)/(3G)`, `ΔD = Δε_p / ε_p^f` with `ε_p^f = D1 (P* + T*)^D2`
//!    (`P* + T* ≤ 0` or `ε_p^f ≤ 0` → D = 1 at once, as D1 = 0 must), `D ≤ 1` (§1.3).
//! 6. Bulking when D grew and μ > 0 (§1.5):
//!    `ΔP ← −K1 μ + √((K1 μ + ΔP)² + 2 β K1 ΔU)`, `ΔU = [σ_y(D_old)² − σ_y(D_new)²]/(6G)`.
//!
//! No erosion (LS-DYNA FS = 0): a fully damaged element keeps its fractured strength.
//! The model has no temperature: room temperature and 800 °C are separate parameter sets.
//!
//! Verified by `tests/verification/jh2.rs` (the Johnson–Holmquist 1994 single-element paths,
//! hydrostatic EOS, tensile cut-off) and the finite-difference test at the foot of this file.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Linear elastic constants (for verification runs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearElastic {
    /// Density (kg/m³).
    pub density: f64,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio ν, in (−1, 0.5).
    pub poisson_ratio: f64,
}

/// Johnson–Holmquist-2 constants, named and ordered as the LS-DYNA `*MAT_JOHNSON_HOLMQUIST_CERAMICS`
/// (MAT_110) cards `MID RO G A B C M N / EPSI T SFMAX HEL PHEL BETA / D1 D2 K1 K2 K3 FS`, in SI
/// units (the card itself is unit-free; Johnson & Holmquist 1994 quote GPa). FS (erosion) is not
/// supported: erosion is off.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Jh2Params {
    /// RO: density ρ₀ (kg/m³).
    pub density: f64,
    /// G: shear modulus (Pa).
    pub g: f64,
    /// A: intact strength coefficient (-).
    pub a: f64,
    /// B: fractured strength coefficient (-).
    pub b: f64,
    /// C: strain-rate coefficient (-).
    pub c: f64,
    /// M: fractured strength exponent (-).
    pub m: f64,
    /// N: intact strength exponent (-).
    pub n: f64,
    /// EPSI: reference strain rate ε̇₀ (1/s).
    #[serde(default = "one")]
    pub epsi: f64,
    /// T: maximum hydrostatic tensile strength (Pa, positive).
    pub t: f64,
    /// SFMAX: cap of the normalised fractured strength (-).
    pub sfmax: f64,
    /// HEL: Hugoniot elastic limit (Pa).
    pub hel: f64,
    /// PHEL: pressure at the HEL (Pa).
    pub phel: f64,
    /// BETA: fraction of the lost deviatoric elastic energy converted to bulking pressure, [0, 1].
    pub beta: f64,
    /// D1: damage constant (-).
    pub d1: f64,
    /// D2: damage exponent (-).
    pub d2: f64,
    /// K1: bulk modulus (Pa).
    pub k1: f64,
    /// K2: second pressure coefficient (Pa).
    pub k2: f64,
    /// K3: third pressure coefficient (Pa).
    pub k3: f64,
}

fn one() -> f64 {
    1.0
}

impl Jh2Params {
    /// The Johnson & Holmquist (1994) illustrative ceramic (docs/reference.md, mechanics §1.7, ρ = 3700 kg/m³,
    /// SFMAX uncapped).
    pub fn jh1994() -> Self {
        Jh2Params {
            density: 3700.0,
            g: 90.16e9,
            a: 0.93,
            b: 0.31,
            c: 0.0,
            m: 0.6,
            n: 0.6,
            epsi: 1.0,
            t: 0.2e9,
            sfmax: 1e3,
            hel: 2.79e9,
            phel: 1.46e9,
            beta: 1.0,
            d1: 0.005,
            d2: 1.0,
            k1: 130.95e9,
            k2: 0.0,
            k3: 0.0,
        }
    }

    /// σ_HEL = 1.5 (HEL − PHEL) (Pa).
    pub fn sigma_hel(&self) -> f64 {
        1.5 * (self.hel - self.phel)
    }

    /// Checks every constant against its meaning; `key` prefixes the dotted key in errors.
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        let bad = |k: &str, rule: String| Err(Error::config(file, format!("{key}.{k}"), rule));
        let positive = [
            ("density", self.density),
            ("g", self.g),
            ("a", self.a),
            ("n", self.n),
            ("epsi", self.epsi),
            ("t", self.t),
            ("sfmax", self.sfmax),
            ("hel", self.hel),
            ("phel", self.phel),
            ("k1", self.k1),
        ];
        for (k, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return bad(k, format!("must be a positive finite number, got {v}"));
            }
        }
        for (k, v) in [("b", self.b), ("c", self.c), ("d1", self.d1), ("d2", self.d2), ("m", self.m)] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(k, format!("must be ≥ 0, got {v}"));
            }
        }
        if self.b > 0.0 && self.m <= 0.0 {
            return bad("m", "must be > 0 when B > 0".into());
        }
        if !(self.k2.is_finite() && self.k3.is_finite()) {
            return bad("k2", "K2 and K3 must be finite".into());
        }
        if !(0.0..=1.0).contains(&self.beta) {
            return bad("beta", format!("must lie in [0, 1] (a fraction of the lost elastic energy), got {}", self.beta));
        }
        if self.hel <= self.phel {
            return bad("hel", format!("HEL {} Pa must exceed PHEL {} Pa (σ_HEL = 1.5 (HEL − PHEL) > 0)", self.hel, self.phel));
        }
        // The EOS must stay monotone over the compressions a crush reaches.
        for i in 0..=100 {
            let mu = 0.3 * i as f64 / 100.0;
            let slope = self.k1 + 2.0 * self.k2 * mu + 3.0 * self.k3 * mu * mu;
            if slope <= 0.0 {
                return bad("k2", format!("dP/dμ = K1 + 2 K2 μ + 3 K3 μ² ≤ 0 at μ = {mu:.3}: the EOS must increase for 0 ≤ μ ≤ 0.3"));
            }
        }
        Ok(())
    }
}

impl LinearElastic {
    /// Checks the constants; `key` prefixes the dotted key in errors.
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        let bad = |k: &str, rule: String| Err(Error::config(file, format!("{key}.{k}"), rule));
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad("density", format!("must be positive, got {}", self.density));
        }
        if !(self.youngs_modulus.is_finite() && self.youngs_modulus > 0.0) {
            return bad("youngs_modulus", format!("must be positive, got {}", self.youngs_modulus));
        }
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return bad("poisson_ratio", format!("must lie in (−1, 0.5), got {}", self.poisson_ratio));
        }
        Ok(())
    }
}

/// A material as written in a study: `kind = "linear_elastic"` or `kind = "jh2"`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum MaterialParams {
    /// Linear elastic.
    LinearElastic(LinearElastic),
    /// Johnson–Holmquist-2.
    Jh2(Jh2Params),
}

impl MaterialParams {
    /// Density (kg/m³).
    pub fn density(&self) -> f64 {
        match self {
            MaterialParams::LinearElastic(e) => e.density,
            MaterialParams::Jh2(j) => j.density,
        }
    }

    /// Checks the constants.
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        match self {
            MaterialParams::LinearElastic(e) => e.validate(file, key),
            MaterialParams::Jh2(j) => j.validate(file, key),
        }
    }

    /// Small-strain Young's modulus and Poisson's ratio (JH-2: from G and K1).
    pub fn elastic_constants(&self) -> (f64, f64) {
        match self {
            MaterialParams::LinearElastic(e) => (e.youngs_modulus, e.poisson_ratio),
            MaterialParams::Jh2(j) => {
                let e = crate::contact::Elastic::from_shear_and_bulk(j.g, j.k1);
                (e.youngs_modulus_pa, e.poisson_ratio)
            }
        }
    }

    /// The update-ready material.
    pub fn build(&self) -> Material {
        Material::new(*self)
    }
}

/// Per-point state: deviator, pressure, damage, plastic strain, bulking pressure.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PointState {
    /// Deviatoric stress `[rr, zz, θθ, rz]` (Pa).
    pub s: [f64; 4],
    /// Pressure P (Pa, compression positive), without bulk viscosity.
    pub p: f64,
    /// Damage D ∈ [0, 1].
    pub damage: f64,
    /// Equivalent plastic strain (-).
    pub plastic_strain: f64,
    /// Bulking pressure ΔP (Pa).
    pub bulking: f64,
}

impl PointState {
    /// Cauchy stress `[rr, zz, θθ, rz]` (Pa).
    pub fn stress(&self) -> [f64; 4] {
        [self.s[0] - self.p, self.s[1] - self.p, self.s[2] - self.p, self.s[3]]
    }

    /// Von Mises equivalent stress √(3 J2) (Pa).
    pub fn von_mises(&self) -> f64 {
        von_mises(&self.s)
    }
}

/// √(3/2 s:s) of a deviator `[rr, zz, θθ, rz]`.
#[inline]
pub fn von_mises(s: &[f64; 4]) -> f64 {
    (1.5 * (s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + 2.0 * s[3] * s[3])).sqrt()
}

/// A material ready for updates: parameters plus derived constants.
#[derive(Debug, Clone, Copy)]
pub struct Material {
    /// The parameters it was built from.
    pub params: MaterialParams,
    g: f64,
    k: f64,
    // JH-2 derived constants (zero for linear elastic).
    sigma_hel: f64,
    inv_phel: f64,
    t_star: f64,
    /// Both exponents ≤ 1: the cheap lower bound of the strength surfaces is valid.
    concave: bool,
}

impl Material {
    /// Derived constants of `params` (validate first).
    pub fn new(params: MaterialParams) -> Self {
        match params {
            MaterialParams::LinearElastic(e) => {
                let g = e.youngs_modulus / (2.0 * (1.0 + e.poisson_ratio));
                let k = e.youngs_modulus / (3.0 * (1.0 - 2.0 * e.poisson_ratio));
                Material { params, g, k, sigma_hel: 0.0, inv_phel: 0.0, t_star: 0.0, concave: true }
            }
            MaterialParams::Jh2(j) => Material {
                params,
                g: j.g,
                k: j.k1,
                sigma_hel: j.sigma_hel(),
                inv_phel: 1.0 / j.phel,
                t_star: j.t / j.phel,
                concave: j.n <= 1.0 && (j.b == 0.0 || j.m <= 1.0),
            },
        }
    }

    /// Shear modulus (Pa).
    pub fn shear_modulus(&self) -> f64 {
        self.g
    }

    /// Small-strain bulk modulus (Pa).
    pub fn bulk_modulus(&self) -> f64 {
        self.k
    }

    /// Density (kg/m³).
    pub fn density(&self) -> f64 {
        self.params.density()
    }

    /// Constrained (P-wave) modulus K_t + 4G/3 at compression μ (Pa), for the stable time step:
    /// the EOS tangent dP/dμ = K1 + 2K2μ + 3K3μ², never below K1.
    pub fn wave_modulus(&self, mu: f64) -> f64 {
        let kt = match self.params {
            MaterialParams::LinearElastic(_) => self.k,
            MaterialParams::Jh2(j) => {
                let m = mu.max(0.0);
                (j.k1 + 2.0 * j.k2 * m + 3.0 * j.k3 * m * m).max(j.k1)
            }
        };
        kt + 4.0 / 3.0 * self.g
    }

    /// Yield strength σ_y (Pa) of JH-2 at pressure `p`, damage `d` and rate factor `rate`.
    #[inline]
    pub fn jh2_strength(&self, j: &Jh2Params, p: f64, d: f64, rate: f64) -> f64 {
        let ps = p * self.inv_phel;
        let x = ps + self.t_star;
        let intact = if x > 0.0 { j.a * x.powf(j.n) } else { 0.0 };
        let fractured = if ps > 0.0 && j.b > 0.0 { (j.b * ps.powf(j.m) * rate).min(j.sfmax) / rate } else { 0.0 };
        self.sigma_hel * rate * ((1.0 - d) * intact + d * fractured)
    }

    /// A lower bound of [`Self::jh2_strength`] without `powf`: `x^N ≥ min(x, 1)` for N ≤ 1.
    #[inline]
    fn jh2_strength_lower_bound(&self, j: &Jh2Params, p: f64, d: f64) -> f64 {
        let ps = p * self.inv_phel;
        let x = ps + self.t_star;
        let intact = if x > 0.0 { j.a * x.min(1.0) } else { 0.0 };
        let fractured = if ps > 0.0 && j.b > 0.0 { (j.b * ps.min(1.0)).min(j.sfmax) } else { 0.0 };
        self.sigma_hel * ((1.0 - d) * intact + d * fractured)
    }

    /// Advances one point by the rate-of-deformation increment `de = D Δt` (`[rr, zz, θθ, rz]`,
    /// tensor shear), the spin increment `w_dt = ½(∂v_r/∂z − ∂v_z/∂r) Δt`, the current
    /// compression `mu = V₀/V − 1` and the equivalent strain rate `rate_eq` (1/s, JH-2 rate term).
    #[inline]
    pub fn update(&self, st: &mut PointState, de: &[f64; 4], w_dt: f64, mu: f64, rate_eq: f64) {
        self.trial(st, de, w_dt);
        self.settle(st, mu, rate_eq);
    }

    /// The first half of [`Material::update`]: the deviator rotated by `w_dt` and advanced
    /// elastically by `de` (steps 1–2).
    #[inline]
    pub fn trial(&self, st: &mut PointState, de: &[f64; 4], w_dt: f64) {
        // 1. Jaumann rotation of the deviator.
        let s = &mut st.s;
        if w_dt != 0.0 {
            let (srr, szz, srz) = (s[0], s[1], s[3]);
            s[0] = srr + 2.0 * w_dt * srz;
            s[1] = szz - 2.0 * w_dt * srz;
            s[3] = srz + w_dt * (szz - srr);
        }
        // 2. Trial deviator.
        let tr = (de[0] + de[1] + de[2]) / 3.0;
        let g2 = 2.0 * self.g;
        s[0] += g2 * (de[0] - tr);
        s[1] += g2 * (de[1] - tr);
        s[2] += g2 * (de[2] - tr);
        s[3] += g2 * de[3];
    }

    /// The second half of [`Material::update`] after [`Material::trial`]: pressure, strength,
    /// return and damage at compression `mu` and equivalent strain rate `rate_eq`.
    #[inline]
    pub fn settle(&self, st: &mut PointState, mu: f64, rate_eq: f64) {
        match self.params {
            MaterialParams::LinearElastic(_) => {
                st.p = self.k * mu.ln_1p();
            }
            MaterialParams::Jh2(ref j) => self.jh2_update(j, st, mu, rate_eq),
        }
    }

    #[inline]
    fn jh2_update(&self, j: &Jh2Params, st: &mut PointState, mu: f64, rate_eq: f64) {
        // 3. EOS and tensile cut-off.
        let d = st.damage;
        let mut p = if mu > 0.0 { mu * (j.k1 + mu * (j.k2 + mu * j.k3)) + st.bulking } else { j.k1 * mu };
        let p_min = -j.t * (1.0 - d);
        if p < p_min {
            p = p_min;
        }
        st.p = p;
        // 4. Strength; the powf-free bound decides most elastic points.
        let q_tr = von_mises(&st.s);
        let rate = if j.c > 0.0 && rate_eq > j.epsi { 1.0 + j.c * (rate_eq / j.epsi).ln() } else { 1.0 };
        if self.concave && rate == 1.0 && q_tr <= self.jh2_strength_lower_bound(j, p, d) {
            return;
        }
        let sy = self.jh2_strength(j, p, d, rate);
        if q_tr <= sy {
            return;
        }
        // 5. Radial return and damage.
        let scale = if q_tr > 0.0 { sy / q_tr } else { 0.0 };
        for v in st.s.iter_mut() {
            *v *= scale;
        }
        let dep = (q_tr - sy) / (3.0 * self.g);
        st.plastic_strain += dep;
        if d >= 1.0 {
            return;
        }
        let x = p * self.inv_phel + self.t_star;
        let ef = if x > 0.0 { j.d1 * x.powf(j.d2) } else { 0.0 };
        let d_new = if ef > 0.0 { (d + dep / ef).min(1.0) } else { 1.0 };
        st.damage = d_new;
        // 6. Bulking.
        if j.beta > 0.0 && mu > 0.0 && d_new > d {
            let sy_new = self.jh2_strength(j, p, d_new, rate);
            let du = (sy * sy - sy_new * sy_new) / (6.0 * self.g);
            if du > 0.0 {
                let k1mu = j.k1 * mu;
                let dp = -k1mu + ((k1mu + st.bulking).powi(2) + 2.0 * j.beta * j.k1 * du).sqrt();
                st.p += dp - st.bulking;
                st.bulking = dp;
            }
        }
        // After a strength drop the deviator must stay on the current surface.
        if d_new > d {
            let sy_new = self.jh2_strength(j, st.p, d_new, rate);
            let q = von_mises(&st.s);
            if q > sy_new && q > 0.0 {
                let f = sy_new / q;
                for v in st.s.iter_mut() {
                    *v *= f;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn elastic_step(m: &Material, de: [f64; 4], mu: f64) -> [f64; 4] {
        let mut st = PointState::default();
        m.update(&mut st, &de, 0.0, mu, 0.0);
        st.stress()
    }

    /// Finite-difference check of the elastic branch: dσ/dε equals the isotropic tangent
    /// 2G dev + K I⊗I at the origin, for both materials.
    #[test]
    fn elastic_tangent_matches_finite_differences() {
        let mats = [
            MaterialParams::LinearElastic(LinearElastic { density: 3600.0, youngs_modulus: 112e9, poisson_ratio: 0.25 }).build(),
            MaterialParams::Jh2(Jh2Params::jh1994()).build(),
        ];
        for m in mats {
            let (g, k) = (m.shear_modulus(), m.bulk_modulus());
            let h = 1e-7;
            for col in 0..4 {
                let mut de = [0.0f64; 4];
                de[col] = h;
                // μ = V₀/V − 1 with V/V₀ = exp(tr Δε).
                let mu = (-(de[0] + de[1] + de[2])).exp() - 1.0;
                let sig = elastic_step(&m, de, mu);
                for (row, s) in sig.iter().enumerate() {
                    let fd = s / h;
                    let exact = if row == 3 {
                        if col == 3 { 2.0 * g } else { 0.0 }
                    } else if col == 3 {
                        0.0
                    } else {
                        let dev = if row == col { 2.0 * g * (1.0 - 1.0 / 3.0) } else { -2.0 * g / 3.0 };
                        dev + k
                    };
                    let scale = 2.0 * g + k;
                    assert!((fd - exact).abs() < 1e-5 * scale, "row {row} col {col}: fd {fd:e} vs {exact:e}");
                }
            }
        }
    }

    #[test]
    fn validation_names_the_constant() {
        let mut j = Jh2Params::jh1994();
        j.d1 = -0.1;
        let e = j.validate("s.toml", "material").unwrap_err().to_string();
        assert!(e.contains("material.d1"), "{e}");
        let mut j = Jh2Params::jh1994();
        j.beta = 1.5;
        assert!(j.validate("s.toml", "material").unwrap_err().to_string().contains("material.beta"));
        let mut j = Jh2Params::jh1994();
        j.k2 = -2e12;
        assert!(j.validate("s.toml", "material").unwrap_err().to_string().contains("dP/dμ"));
        let e = LinearElastic { density: 1.0, youngs_modulus: 1.0, poisson_ratio: 0.5 };
        assert!(e.validate("s.toml", "material").unwrap_err().to_string().contains("poisson_ratio"));
    }

    #[test]
    fn strength_bound_is_below_the_surface() {
        let j = Jh2Params::jh1994();
        let m = MaterialParams::Jh2(j).build();
        for i in 0..200 {
            let p = -0.3e9 + 0.05e9 * i as f64;
            for d in [0.0, 0.3, 1.0] {
                assert!(m.jh2_strength_lower_bound(&j, p, d) <= m.jh2_strength(&j, p, d, 1.0) + 1.0);
            }
        }
    }
}

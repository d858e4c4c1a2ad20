//! Local fields of a homogenised microstructure under a macroscopic stress, and their hot spots.
//!
//! # Virtual uniaxial tests
//!
//! The unit load cases of [`super::homogenise`] superpose: under the macroscopic stress Σ the
//! macroscopic strain is Ē = C⁻¹Σ and every element's stress and strain are Σₖ Ēₖ (field of case
//! k). A virtual uniaxial tension test along x is Σ = (s, 0, 0), a compression test
//! Σ = (−s, 0, 0): the periodic cell is loaded by a uniform traction s on its x faces and none
//! on its y faces, on average. Linear elasticity makes compression the negative of tension, but
//! a brittle phase's criterion is not symmetric: the maximum principal stress of a compressed
//! microstructure is the negative of the minimum one in tension, and its tensile peaks (the
//! deliverable's "stress peaks even in a compressive state", §5) are other elements.
//!
//! # Measures per element
//!
//! In plane strain σzz = λ(εxx + εyy) (λ of the element's phase), in plane stress σzz = 0.
//!
//! * σ₁, the maximum principal stress of (σxx, σyy, σxy, σzz);
//! * σ_vM = √(σxx² + σyy² + σzz² − σxxσyy − σyyσzz − σzzσxx + 3σxy²), the von Mises stress;
//! * ε₁ = (εxx + εyy)/2 + √(((εxx − εyy)/2)² + (γxy/2)²), the in-plane maximum principal strain;
//! * γ_max = 2√(((εxx − εyy)/2)² + (γxy/2)²), the in-plane maximum (engineering) shear strain —
//!   the measure of the deliverable's deformation bands (Fig. 11a).
//!
//! # Hot spots
//!
//! Per phase: the quantiles of each measure over the phase's pixels (type 7), the stress
//! concentration factors q₉₉.₉(σ₁)/s and max σ₁/s, the area fraction (of the whole cell and of
//! the phase) whose σ₁ exceeds the phase's tensile strength σ_t at the applied stress s, and the
//! first-failure stress s_f = min over the phase's pixels of σ_t/(σ₁ per unit s): the applied
//! stress at which the first pixel of the phase reaches its strength. A pixel-level maximum
//! depends on the pixel size near re-entrant corners of a pixelated interface, so s_f and
//! max σ₁ are reported with the resolution they were computed at; the quantiles and area
//! fractions converge with refinement (`tests/verification/micro.rs`).

use nalgebra::{Matrix3, Vector3};

use super::homogenise::{Effective, Plane};
use crate::error::{Error, Result};
use crate::stats::sorted_quantile;

/// The quantile probabilities of every per-phase measure.
pub const QUANTILES: [f64; 4] = [0.5, 0.9, 0.99, 0.999];

/// A virtual uniaxial test along x.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Test {
    /// Σ = (s, 0, 0).
    Tension,
    /// Σ = (−s, 0, 0).
    Compression,
}

impl Test {
    /// Both tests, tension first.
    pub const BOTH: [Test; 2] = [Test::Tension, Test::Compression];

    /// "tension" or "compression".
    pub fn name(self) -> &'static str {
        match self {
            Test::Tension => "tension",
            Test::Compression => "compression",
        }
    }

    /// The macroscopic stress of the test at magnitude `s` (Pa).
    pub fn stress(self, s: f64) -> [f64; 3] {
        match self {
            Test::Tension => [s, 0.0, 0.0],
            Test::Compression => [-s, 0.0, 0.0],
        }
    }
}

/// The scalar measures of every element under one macroscopic stress.
#[derive(Debug, Clone, PartialEq)]
pub struct Local {
    /// Macroscopic strain Ē = C⁻¹Σ (εxx, εyy, γxy).
    pub macro_strain: [f64; 3],
    /// σ₁ per element (Pa).
    pub sigma1: Vec<f64>,
    /// σ_vM per element (Pa).
    pub von_mises: Vec<f64>,
    /// ε₁ per element.
    pub strain1: Vec<f64>,
    /// γ_max per element.
    pub shear_strain: Vec<f64>,
}

/// The measures under the macroscopic stress `sigma`; `lame[e]` the element's in-plane constants.
pub fn under_stress(eff: &Effective, lame: &[(f64, f64)], plane: Plane, sigma: [f64; 3]) -> Result<Local> {
    let c = Matrix3::from_fn(|i, j| eff.c[i][j]);
    let e = c.lu().solve(&Vector3::from(sigma)).ok_or_else(|| Error::numerical("virtual test", "the effective stiffness is singular"))?;
    let ne = lame.len();
    let (mut sigma1, mut von_mises, mut strain1, mut shear_strain) = (Vec::with_capacity(ne), Vec::with_capacity(ne), Vec::with_capacity(ne), Vec::with_capacity(ne));
    for (el, &(l, _)) in lame.iter().enumerate() {
        let s: [f64; 3] = std::array::from_fn(|i| (0..3).map(|k| e[k] * eff.stress[k][el][i]).sum());
        let g: [f64; 3] = std::array::from_fn(|i| (0..3).map(|k| e[k] * eff.strain[k][el][i]).sum());
        let szz = match plane {
            Plane::Strain => l * (g[0] + g[1]),
            Plane::Stress => 0.0,
        };
        let (centre, radius) = (0.5 * (s[0] + s[1]), (0.25 * (s[0] - s[1]).powi(2) + s[2] * s[2]).sqrt());
        sigma1.push((centre + radius).max(szz));
        von_mises.push((s[0] * s[0] + s[1] * s[1] + szz * szz - s[0] * s[1] - s[1] * szz - szz * s[0] + 3.0 * s[2] * s[2]).max(0.0).sqrt());
        let r = (0.25 * (g[0] - g[1]).powi(2) + 0.25 * g[2] * g[2]).sqrt();
        strain1.push(0.5 * (g[0] + g[1]) + r);
        shear_strain.push(2.0 * r);
    }
    if sigma1.iter().chain(&strain1).any(|v| !v.is_finite()) {
        return Err(Error::numerical("virtual test", "a non-finite local stress or strain"));
    }
    Ok(Local { macro_strain: [e[0], e[1], e[2]], sigma1, von_mises, strain1, shear_strain })
}

/// One phase's hot-spot statistics under one test.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseHotSpots {
    /// Area fraction of the phase in the cell.
    pub area_fraction: f64,
    /// Mean σ₁ over the phase (Pa).
    pub sigma1_mean: f64,
    /// σ₁ at [`QUANTILES`] (Pa).
    pub sigma1_q: [f64; 4],
    /// Largest σ₁ (Pa).
    pub sigma1_max: f64,
    /// σ_vM at [`QUANTILES`] (Pa).
    pub von_mises_q: [f64; 4],
    /// ε₁ at [`QUANTILES`].
    pub strain1_q: [f64; 4],
    /// γ_max at [`QUANTILES`].
    pub shear_strain_q: [f64; 4],
    /// Area fraction of the whole cell in this phase with σ₁ > σ_t.
    pub above_strength: f64,
    /// The same as a fraction of the phase's area.
    pub above_strength_in_phase: f64,
    /// First-failure stress s_f (Pa): the applied stress at which the first pixel of the phase
    /// reaches σ_t (infinite when no pixel is in tension beyond round-off, σ₁ ≤ 10⁻⁹ s).
    pub first_failure_pa: f64,
}

/// The hot spots of each phase (label l = index) at applied stress `s` (Pa) with tensile
/// strengths `strength[l]` (Pa). A phase without pixels gets NaN statistics and no failure.
pub fn hot_spots(local: &Local, labels: &[u8], strength: &[f64], s: f64) -> Vec<PhaseHotSpots> {
    let ne = labels.len() as f64;
    (0..strength.len())
        .map(|p| {
            let idx: Vec<usize> = (0..labels.len()).filter(|&e| labels[e] as usize == p).collect();
            let sorted = |v: &[f64]| {
                let mut x: Vec<f64> = idx.iter().map(|&e| v[e]).collect();
                x.sort_by(f64::total_cmp);
                x
            };
            let q = |x: &[f64]| QUANTILES.map(|pr| sorted_quantile(x, pr));
            let s1 = sorted(&local.sigma1);
            let above = s1.iter().filter(|&&v| v > strength[p]).count() as f64;
            let worst = s1.last().copied().unwrap_or(f64::NAN);
            PhaseHotSpots {
                area_fraction: idx.len() as f64 / ne,
                sigma1_mean: if idx.is_empty() { f64::NAN } else { s1.iter().sum::<f64>() / s1.len() as f64 },
                sigma1_q: q(&s1),
                sigma1_max: worst,
                von_mises_q: q(&sorted(&local.von_mises)),
                strain1_q: q(&sorted(&local.strain1)),
                shear_strain_q: q(&sorted(&local.shear_strain)),
                above_strength: above / ne,
                above_strength_in_phase: if idx.is_empty() { f64::NAN } else { above / idx.len() as f64 },
                first_failure_pa: if worst > 1e-9 * s { s * strength[p] / worst } else { f64::INFINITY },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::Elastic;
    use crate::micro::homogenise::{element_lame, homogenise};
    use crate::micro::structure::Microstructure;

    #[test]
    fn a_single_phase_under_uniaxial_stress_has_the_textbook_measures() {
        let m = Microstructure::new(4, 4, 1e-6, vec![0; 16]).unwrap();
        let glass = Elastic { youngs_modulus_pa: 70e9, poisson_ratio: 0.2 };
        for plane in [Plane::Strain, Plane::Stress] {
            let eff = homogenise(&m, &[glass], plane).unwrap();
            let lame = element_lame(&m, &[glass], plane).unwrap();
            let s = 50e6;
            let t = under_stress(&eff, &lame, plane, Test::Tension.stress(s)).unwrap();
            // Plane stress: ε = s/E; plane strain: ε = s(1 − ν²)/E, σzz = νs.
            let (exx, szz) = match plane {
                Plane::Stress => (s / 70e9, 0.0),
                Plane::Strain => (s * (1.0 - 0.04) / 70e9, 0.2 * s),
            };
            assert!((t.macro_strain[0] / exx - 1.0).abs() < 1e-9, "{plane:?} {:?}", t.macro_strain);
            let vm = (s * s + szz * szz - s * szz).sqrt();
            for e in 0..16 {
                assert!((t.sigma1[e] / s - 1.0).abs() < 1e-9 && (t.von_mises[e] / vm - 1.0).abs() < 1e-9);
                assert!((t.strain1[e] / exx - 1.0).abs() < 1e-9);
            }
            // In compression the largest principal stress is the in-plane σyy = 0 (σzz = −νs in
            // plane strain is lower): no pixel is in tension.
            let c = under_stress(&eff, &lame, plane, Test::Compression.stress(s)).unwrap();
            assert!(c.sigma1.iter().all(|v| v.abs() < 1e-6 * s), "{:?}", &c.sigma1[..2]);
            let h = hot_spots(&t, &m.labels, &[40e6], s);
            assert_eq!((h[0].above_strength, h[0].area_fraction), (1.0, 1.0));
            assert!((h[0].first_failure_pa - 40e6).abs() < 1e-3);
            assert!(hot_spots(&c, &m.labels, &[40e6], s)[0].first_failure_pa.is_infinite());
        }
    }
}

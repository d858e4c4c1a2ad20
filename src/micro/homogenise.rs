//! Effective elastic moduli of a pixel microstructure by periodic homogenisation, the local
//! fields of each unit load case, and the bounds the moduli must respect.
//!
//! # The finite-element problem
//!
//! Every pixel is a bilinear four-node square element of its phase (isotropic, Lamé constants
//! λ, μ; in plane stress λ is replaced by λ₂ = 2λμ/(λ + 2μ)); the mesh conforms to the pixels. A
//! macroscopic strain Ē = (ε̄xx, ε̄yy, γ̄xy) is applied with periodic boundary conditions:
//! u(x) = Ē·x + ũ(x), ũ periodic on the box (opposite edges share their nodes), one node pinned
//! against rigid translation. The fluctuation solves K ũ = −Σₑ Kₑ (Ē·x)ₑ, K assembled from the
//! element matrices Kₑ = λ K_λ + μ K_μ of the unit square (2 × 2 Gauss points, exact for the
//! bilinear element; a square element's matrix does not depend on its size, so lengths are in
//! pixels and strains dimensionless). K is sparse, symmetric and positive definite once a node is
//! pinned; it is assembled straight into compressed columns (each node couples to its eight
//! periodic neighbours) and factorised once by faer's sparse Cholesky (approximate minimum degree
//! ordering, supernodal), sequential, so the result does not depend on the thread count. The
//! symbolic factorisation depends on the grid only and is reused when the stiffness changes
//! ([`Periodic::solve`] with other constants, as in progressive failure).
//!
//! The effective stiffness C (Voigt notation, engineering shear strain) has as column k the area
//! average of the stress for Ē = e_k; an element's average strain is its strain at the centre
//! (exact for the bilinear element). C is symmetric up to round-off and is symmetrised.
//!
//! # Isotropic projections and bounds (two dimensions)
//!
//! With κ the two-dimensional (area) bulk modulus — λ₂ + μ for an isotropic phase — and μ the
//! in-plane shear modulus, the isotropic projections of C are κ̄ = (C₁₁ + C₂₂ + 2C₁₂)/4 and
//! μ̄ = [(C₁₁ + C₂₂ − 2C₁₂)/4 + C₃₃]/2. For an isotropic composite of phases with area fractions
//! fᵢ they lie between the Hashin–Shtrikman (Walpole) bounds of a two-dimensional composite
//! (Torquato, *Random Heterogeneous Materials*, Springer 2002, §21.2 with d = 2)
//!
//! ```text
//! κ_HS(r) = [Σ fᵢ/(κᵢ + μ_r)]⁻¹ − μ_r,     μ_HS(r) = [Σ fᵢ/(μᵢ + H_r)]⁻¹ − H_r,   H = μκ/(κ + 2μ)
//! ```
//!
//! the upper bound with μ_r = max μᵢ and H_r = H(max κᵢ, max μᵢ), the lower with the minima;
//! and all between the Reuss ([Σ fᵢ/κᵢ]⁻¹) and Voigt (Σ fᵢκᵢ) averages. The same HS forms with
//! the matrix as reference give the dilute strain concentration of a circular inclusion
//! (Eshelby's result in two dimensions), the verification in `tests/verification/micro.rs`. A
//! laminate is not isotropic: its exact moduli (Backus averages) verify the solver instead.
//!
//! Young's modulus and Poisson's ratio follow from (κ, μ): in plane strain, of the
//! three-dimensional material, E = μ(3κ − μ)/κ and ν = (κ − μ)/(2κ); in plane stress, in-plane,
//! E = 4κμ/(κ + μ) and ν = (κ − μ)/(κ + μ). E increases with κ and with μ, so bounds on (κ, μ)
//! bound E.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Mat, Side};

use super::structure::Microstructure;
use crate::contact::Elastic;
use crate::error::{Error, Result};

/// The two-dimensional idealisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Plane {
    /// Plane strain (ε_zz = 0): a section of a long body.
    Strain,
    /// Plane stress (σ_zz = 0): a thin sheet.
    Stress,
}

impl Plane {
    /// "plane strain" or "plane stress".
    pub fn label(self) -> &'static str {
        match self {
            Plane::Strain => "plane strain",
            Plane::Stress => "plane stress",
        }
    }

    /// Young's modulus and Poisson's ratio from the two-dimensional (κ, μ) (module docs).
    pub fn youngs_and_poisson(self, kappa: f64, mu: f64) -> (f64, f64) {
        match self {
            Plane::Strain => (mu * (3.0 * kappa - mu) / kappa, (kappa - mu) / (2.0 * kappa)),
            Plane::Stress => (4.0 * kappa * mu / (kappa + mu), (kappa - mu) / (kappa + mu)),
        }
    }
}

/// A phase's in-plane Lamé constants (λ₂, μ).
pub fn plane_lame(e: &Elastic, plane: Plane) -> (f64, f64) {
    let (l, m) = e.lame();
    match plane {
        Plane::Strain => (l, m),
        Plane::Stress => (2.0 * l * m / (l + 2.0 * m), m),
    }
}

/// The fields of the three unit load cases Ē = e_k, per element (pixel), and the effective
/// stiffness.
#[derive(Debug, Clone, PartialEq)]
pub struct Effective {
    /// Effective stiffness (Pa), Voigt notation (xx, yy, xy with engineering shear strain).
    pub c: [[f64; 3]; 3],
    /// Isotropic projection of the two-dimensional bulk modulus κ̄ (Pa).
    pub bulk: f64,
    /// Isotropic projection of the in-plane shear modulus μ̄ (Pa).
    pub shear: f64,
    /// Per load case k and element, the average stress (σxx, σyy, σxy) (Pa per unit Ē_k).
    pub stress: [Vec<[f64; 3]>; 3],
    /// Per load case k and element, the average strain (εxx, εyy, γxy) (per unit Ē_k).
    pub strain: [Vec<[f64; 3]>; 3],
}

/// Voigt, Reuss and Hashin–Shtrikman bounds of the two-dimensional bulk and shear moduli.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// (κ, μ) Voigt (arithmetic) averages.
    pub voigt: (f64, f64),
    /// (κ, μ) Reuss (harmonic) averages.
    pub reuss: (f64, f64),
    /// (κ, μ) Hashin–Shtrikman upper bounds.
    pub hs_upper: (f64, f64),
    /// (κ, μ) Hashin–Shtrikman lower bounds.
    pub hs_lower: (f64, f64),
}

/// The bounds of phases with area fractions `f` and in-plane constants `(λ₂, μ)`.
pub fn bounds(f: &[f64], lame: &[(f64, f64)]) -> Bounds {
    let k: Vec<f64> = lame.iter().map(|(l, m)| l + m).collect();
    let m: Vec<f64> = lame.iter().map(|p| p.1).collect();
    let mean = |v: &[f64]| f.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
    let harmonic = |v: &[f64]| 1.0 / f.iter().zip(v).map(|(a, b)| a / b).sum::<f64>();
    let h = |k: f64, m: f64| m * k / (k + 2.0 * m);
    let hs = |kr: f64, mr: f64| {
        let hr = h(kr, mr);
        (1.0 / f.iter().zip(&k).map(|(a, b)| a / (b + mr)).sum::<f64>() - mr, 1.0 / f.iter().zip(&m).map(|(a, b)| a / (b + hr)).sum::<f64>() - hr)
    };
    let max = |v: &[f64]| v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let min = |v: &[f64]| v.iter().cloned().fold(f64::INFINITY, f64::min);
    Bounds { voigt: (mean(&k), mean(&m)), reuss: (harmonic(&k), harmonic(&m)), hs_upper: hs(max(&k), max(&m)), hs_lower: hs(min(&k), min(&m)) }
}

/// Gauss-point derivatives of the bilinear shape functions of the unit square, nodes
/// (0,0), (1,0), (1,1), (0,1): the strain–displacement matrix B (3 × 8, dofs u₁ v₁ … u₄ v₄).
fn b_matrix(x: f64, y: f64) -> [[f64; 8]; 3] {
    let dx = [-(1.0 - y), 1.0 - y, y, -y];
    let dy = [-(1.0 - x), -x, x, 1.0 - x];
    let mut b = [[0.0; 8]; 3];
    for n in 0..4 {
        b[0][2 * n] = dx[n];
        b[1][2 * n + 1] = dy[n];
        b[2][2 * n] = dy[n];
        b[2][2 * n + 1] = dx[n];
    }
    b
}

/// K_λ and K_μ of the unit square: Kₑ = λ K_λ + μ K_μ.
fn element_matrices() -> ([[f64; 8]; 8], [[f64; 8]; 8]) {
    let d_lambda = [[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 0.0]];
    let d_mu = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]];
    let g = [0.5 - 0.5 / 3f64.sqrt(), 0.5 + 0.5 / 3f64.sqrt()];
    let (mut kl, mut km) = ([[0.0; 8]; 8], [[0.0; 8]; 8]);
    for &x in &g {
        for &y in &g {
            let b = b_matrix(x, y);
            for a in 0..8 {
                for c in 0..8 {
                    for i in 0..3 {
                        for j in 0..3 {
                            kl[a][c] += 0.25 * b[i][a] * d_lambda[i][j] * b[j][c];
                            km[a][c] += 0.25 * b[i][a] * d_mu[i][j] * b[j][c];
                        }
                    }
                }
            }
        }
    }
    (kl, km)
}

/// The affine displacement of unit load case k at an element's local nodes.
fn affine(k: usize) -> [f64; 8] {
    let (exx, eyy, gxy) = [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)][k];
    let mut u = [0.0; 8];
    for (a, &(x, y)) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].iter().enumerate() {
        u[2 * a] = exx * x + 0.5 * gxy * y;
        u[2 * a + 1] = 0.5 * gxy * x + eyy * y;
    }
    u
}

/// A periodic pixel grid's stiffness pattern and symbolic Cholesky factorisation: build once per
/// grid size, solve for any constants.
pub struct Periodic {
    nx: usize,
    ny: usize,
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicLlt<usize>,
    kl: [[f64; 8]; 8],
    km: [[f64; 8]; 8],
}

impl Periodic {
    /// The pattern of an `nx × ny` periodic grid (node 0 pinned; free dof d − 2 for global dof
    /// d ≥ 2) and its symbolic factorisation.
    pub fn new(nx: usize, ny: usize) -> Result<Self> {
        if nx < 2 || ny < 2 {
            return Err(Error::numerical("homogenisation", format!("needs at least 2 × 2 pixels, got {nx} × {ny}")));
        }
        let n = 2 * nx * ny - 2;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(n * 10);
        col_ptr.push(0);
        for node in 1..nx * ny {
            let (i, j) = (node % nx, node / nx);
            let mut nbrs: Vec<usize> = Vec::with_capacity(9);
            for dj in [ny - 1, 0, 1] {
                for di in [nx - 1, 0, 1] {
                    nbrs.push(((j + dj) % ny) * nx + (i + di) % nx);
                }
            }
            nbrs.sort_unstable();
            nbrs.dedup();
            for a in 0..2 {
                let col = 2 * node + a;
                for &m in &nbrs {
                    for b in 0..2 {
                        let row = 2 * m + b;
                        if m != 0 && row >= col {
                            row_idx.push(row - 2);
                        }
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let symbolic = SymbolicLlt::try_new(pattern.as_ref(), Side::Lower).map_err(|e| Error::numerical("homogenisation", format!("symbolic factorisation: {e:?}")))?;
        let (kl, km) = element_matrices();
        Ok(Periodic { nx, ny, pattern, symbolic, kl, km })
    }

    /// Grid size (nx, ny).
    pub fn size(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    fn element_dofs(&self, e: usize) -> [usize; 8] {
        let (nx, ny) = (self.nx, self.ny);
        let (i, j) = (e % nx, e / nx);
        let node = |i: usize, j: usize| (j % ny) * nx + (i % nx);
        let n = [node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)];
        [2 * n[0], 2 * n[0] + 1, 2 * n[1], 2 * n[1] + 1, 2 * n[2], 2 * n[2] + 1, 2 * n[3], 2 * n[3] + 1]
    }

    /// Solves the three unit load cases with the in-plane constants `lame[e] = (λ₂, μ)` of each
    /// element (row by row from the bottom, as [`Microstructure::labels`]).
    pub fn solve(&self, lame: &[(f64, f64)]) -> Result<Effective> {
        let (nx, ny) = (self.nx, self.ny);
        let ne = nx * ny;
        if lame.len() != ne {
            return Err(Error::numerical("homogenisation", format!("{} element constants for {ne} pixels", lame.len())));
        }
        if let Some(e) = lame.iter().position(|&(l, m)| !(l.is_finite() && m.is_finite() && m > 0.0 && l + m > 0.0)) {
            return Err(Error::numerical("homogenisation", format!("element {e} has constants (λ₂, μ) = {:?}: every element needs μ > 0 and κ = λ₂ + μ > 0", lame[e])));
        }
        let (col_ptr, row_idx) = (self.pattern.col_ptr(), self.pattern.row_idx());
        let free = |d: usize| d.checked_sub(2);
        let mut values = vec![0.0; row_idx.len()];
        let (kl, km) = (&self.kl, &self.km);
        for (e, &(l, mu)) in lame.iter().enumerate() {
            let dofs = self.element_dofs(e);
            for c in 0..8 {
                let Some(s) = free(dofs[c]) else { continue };
                let rows = &row_idx[col_ptr[s]..col_ptr[s + 1]];
                for a in 0..8 {
                    if let Some(r) = free(dofs[a])
                        && r >= s
                    {
                        let pos = col_ptr[s] + rows.binary_search(&r).map_err(|_| Error::numerical("homogenisation", format!("entry ({r}, {s}) outside the pattern")))?;
                        values[pos] += l * kl[a][c] + mu * km[a][c];
                    }
                }
            }
        }
        let n = self.pattern.nrows();
        let mut rhs = Mat::<f64>::zeros(n, 3);
        let ua: [[f64; 8]; 3] = [affine(0), affine(1), affine(2)];
        for (e, &(l, mu)) in lame.iter().enumerate() {
            let dofs = self.element_dofs(e);
            for a in 0..8 {
                if let Some(r) = free(dofs[a]) {
                    for (k, u) in ua.iter().enumerate() {
                        let f: f64 = (0..8).map(|c| (l * kl[a][c] + mu * km[a][c]) * u[c]).sum();
                        rhs[(r, k)] -= f;
                    }
                }
            }
        }
        let k = SparseColMatRef::new(self.pattern.as_ref(), &values);
        let llt = Llt::try_new_with_symbolic(self.symbolic.clone(), k, Side::Lower).map_err(|e| Error::numerical("homogenisation", format!("the stiffness matrix is not positive definite ({e:?})")))?;
        llt.solve_in_place(rhs.as_mut());
        let b0 = b_matrix(0.5, 0.5);
        let mut c = [[0.0; 3]; 3];
        let mut stress: [Vec<[f64; 3]>; 3] = std::array::from_fn(|_| Vec::with_capacity(ne));
        let mut strain: [Vec<[f64; 3]>; 3] = std::array::from_fn(|_| Vec::with_capacity(ne));
        for k in 0..3 {
            let mut sum = [0.0; 3];
            for (e, &(l, mu)) in lame.iter().enumerate() {
                let dofs = self.element_dofs(e);
                let u: [f64; 8] = std::array::from_fn(|a| ua[k][a] + free(dofs[a]).map_or(0.0, |r| rhs[(r, k)]));
                let eps: [f64; 3] = std::array::from_fn(|i| (0..8).map(|a| b0[i][a] * u[a]).sum());
                let s = [(l + 2.0 * mu) * eps[0] + l * eps[1], l * eps[0] + (l + 2.0 * mu) * eps[1], mu * eps[2]];
                for i in 0..3 {
                    sum[i] += s[i];
                }
                stress[k].push(s);
                strain[k].push(eps);
            }
            for i in 0..3 {
                c[i][k] = sum[i] / ne as f64;
            }
        }
        for i in 0..3 {
            for j in 0..i {
                let v = 0.5 * (c[i][j] + c[j][i]);
                c[i][j] = v;
                c[j][i] = v;
            }
        }
        let bulk = (c[0][0] + c[1][1] + 2.0 * c[0][1]) / 4.0;
        let shear = ((c[0][0] + c[1][1] - 2.0 * c[0][1]) / 4.0 + c[2][2]) / 2.0;
        Ok(Effective { c, bulk, shear, stress, strain })
    }
}

/// The in-plane constants of every element of `m`, phase label l having the constants
/// `phases[l]`.
pub fn element_lame(m: &Microstructure, phases: &[Elastic], plane: Plane) -> Result<Vec<(f64, f64)>> {
    let per_label: Vec<(f64, f64)> = phases.iter().map(|e| plane_lame(e, plane)).collect();
    m.labels
        .iter()
        .map(|&l| per_label.get(l as usize).copied().ok_or_else(|| Error::numerical("homogenisation", format!("no constants for phase label {l} ({} phases)", phases.len()))))
        .collect()
}

/// Homogenises `m`, phase label l having the constants `phases[l]`, in the idealisation `plane`.
pub fn homogenise(m: &Microstructure, phases: &[Elastic], plane: Plane) -> Result<Effective> {
    Periodic::new(m.nx, m.ny)?.solve(&element_lame(m, phases, plane)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::micro::structure::{HARD, SOFT, Topology, voronoi_two_phase};

    fn alumina() -> Elastic {
        Elastic { youngs_modulus_pa: 400e9, poisson_ratio: 0.23 }
    }
    fn silica() -> Elastic {
        Elastic { youngs_modulus_pa: 72e9, poisson_ratio: 0.17 }
    }

    #[test]
    fn a_single_phase_gives_its_own_stiffness_and_a_uniform_field() {
        let m = Microstructure::new(7, 5, 1e-6, vec![0; 35]).unwrap();
        for plane in [Plane::Strain, Plane::Stress] {
            let eff = homogenise(&m, &[alumina()], plane).unwrap();
            let (l, mu) = plane_lame(&alumina(), plane);
            let d = [[l + 2.0 * mu, l, 0.0], [l, l + 2.0 * mu, 0.0], [0.0, 0.0, mu]];
            for i in 0..3 {
                for j in 0..3 {
                    assert!((eff.c[i][j] - d[i][j]).abs() < 1e-9 * d[0][0], "C[{i}][{j}] = {} vs {}", eff.c[i][j], d[i][j]);
                }
                for (s, e) in eff.stress[i].iter().zip(&eff.strain[i]) {
                    for q in 0..3 {
                        assert!((s[q] - d[q][i]).abs() < 1e-9 * d[0][0], "non-uniform stress {s:?}");
                        assert!((e[q] - f64::from(u8::from(q == i))).abs() < 1e-12, "non-uniform strain {e:?}");
                    }
                }
            }
            // The isotropic projections give back E and ν.
            let (e, nu) = plane.youngs_and_poisson(eff.bulk, eff.shear);
            assert!((e / 400e9 - 1.0).abs() < 1e-9 && (nu - 0.23).abs() < 1e-9, "{plane:?}: E {e}, ν {nu}");
        }
    }

    /// Layers normal to x (columns of alternating phases): the exact effective stiffness is the
    /// Backus average — with M = λ + 2μ, C₁₁ = ⟨1/M⟩⁻¹ (Reuss across the layers),
    /// C₁₂ = ⟨λ/M⟩C₁₁, C₂₂ = ⟨M − λ²/M⟩ + ⟨λ/M⟩²C₁₁ (Voigt-like along them) and C₃₃ = ⟨1/μ⟩⁻¹.
    #[test]
    fn a_laminate_gives_the_backus_moduli_exactly() {
        let (nx, ny) = (10, 4);
        let labels: Vec<u8> = (0..nx * ny).map(|p| if p % nx < 3 { SOFT } else { HARD }).collect();
        let m = Microstructure::new(nx, ny, 1e-6, labels).unwrap();
        let eff = homogenise(&m, &[alumina(), silica()], Plane::Strain).unwrap();
        let f = [0.7, 0.3];
        let p = [plane_lame(&alumina(), Plane::Strain), plane_lame(&silica(), Plane::Strain)];
        let avg = |g: &dyn Fn(f64, f64) -> f64| f[0] * g(p[0].0, p[0].1) + f[1] * g(p[1].0, p[1].1);
        let c11 = 1.0 / avg(&|l, m| 1.0 / (l + 2.0 * m));
        let r = avg(&|l, m| l / (l + 2.0 * m));
        let exact = [[c11, r * c11, 0.0], [r * c11, avg(&|l, m| l + 2.0 * m - l * l / (l + 2.0 * m)) + r * r * c11, 0.0], [0.0, 0.0, 1.0 / avg(&|_, m| 1.0 / m)]];
        for i in 0..3 {
            for j in 0..3 {
                assert!((eff.c[i][j] - exact[i][j]).abs() < 1e-9 * exact[0][0], "C[{i}][{j}] = {} vs {}", eff.c[i][j], exact[i][j]);
            }
        }
    }

    #[test]
    fn random_two_phase_moduli_lie_within_the_hashin_shtrikman_bounds() {
        let lame = [plane_lame(&alumina(), Plane::Strain), plane_lame(&silica(), Plane::Strain)];
        let mut by_topology = Vec::new();
        for topology in [Topology::SoftMatrix, Topology::SoftPockets] {
            let m = voronoi_two_phase(64, 64, 1e-6, 24, 0.3, topology, 3).unwrap();
            let b = bounds(&[m.fraction(HARD), m.fraction(SOFT)], &lame);
            let eff = homogenise(&m, &[alumina(), silica()], Plane::Strain).unwrap();
            assert!(b.reuss.0 <= b.hs_lower.0 && b.hs_lower.0 < eff.bulk && eff.bulk < b.hs_upper.0 && b.hs_upper.0 <= b.voigt.0, "{topology:?} κ {} in {b:?}", eff.bulk);
            assert!(b.reuss.1 <= b.hs_lower.1 && b.hs_lower.1 < eff.shear && eff.shear < b.hs_upper.1 && b.hs_upper.1 <= b.voigt.1, "{topology:?} μ {} in {b:?}", eff.shear);
            by_topology.push(eff);
        }
        // A hard skeleton is stiffer than hard islands in a soft matrix at the same fractions.
        assert!(by_topology[1].bulk > by_topology[0].bulk && by_topology[1].shear > by_topology[0].shear);
    }

    #[test]
    fn a_lost_shear_stiffness_is_refused() {
        let p = Periodic::new(4, 4).unwrap();
        let mut lame = vec![plane_lame(&alumina(), Plane::Strain); 16];
        lame[5].1 = 0.0;
        assert!(p.solve(&lame).unwrap_err().to_string().contains("element 5"));
    }
}

//! Results of the crush FE: element fields, fracture detection, the quasi-static check, the
//! strain profile under the contact and the VTK (.vtu) writer.
//!
//! Logarithmic strain: from the deformation gradient at the element centroid,
//! `F = ∂x/∂X` (in-plane, with the initial-configuration shape-function gradients) and the hoop
//! stretch `r̄/R̄`; principal log strains are `½ ln λ` of the eigenvalues λ of `b = F Fᵀ`.

// Index loops over the four nodes read like the formulas above.
#![allow(clippy::needless_range_loop)]

use std::fmt::Write as _;

use super::element::{ElementState, geometry};
use super::mesh::Mesh;
use crate::io::vtk_data_array;
use super::{CurveSample, QuasiStatic};

/// Per-element fields (one entry per element, mesh order).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ElementFields {
    /// Maximum principal logarithmic strain (-).
    pub max_principal_log_strain: Vec<f64>,
    /// Minimum principal logarithmic strain (-).
    pub min_principal_log_strain: Vec<f64>,
    /// Von Mises stress (Pa).
    pub von_mises: Vec<f64>,
    /// Pressure, compression positive (Pa).
    pub pressure: Vec<f64>,
    /// Radial stress σ_rr (Pa).
    pub radial_stress: Vec<f64>,
    /// Axial stress σ_zz (Pa).
    pub axial_stress: Vec<f64>,
    /// Hoop stress σ_θθ (Pa).
    pub hoop_stress: Vec<f64>,
    /// Damage D (-).
    pub damage: Vec<f64>,
    /// Equivalent plastic strain (-).
    pub plastic_strain: Vec<f64>,
    /// Centroid (r, z) in the current configuration (m).
    pub centroid: Vec<[f64; 2]>,
}

/// Names and units of the fields, in the order of [`ElementFields::columns`].
pub const FIELD_NAMES: [(&str, &str); 9] = [
    ("max_principal_log_strain", "-"),
    ("min_principal_log_strain", "-"),
    ("von_mises_pa", "Pa"),
    ("pressure_pa", "Pa"),
    ("radial_stress_pa", "Pa"),
    ("axial_stress_pa", "Pa"),
    ("hoop_stress_pa", "Pa"),
    ("damage", "-"),
    ("plastic_strain", "-"),
];

/// Principal logarithmic strains (max, min) of an element.
pub fn log_strains(x0: &[[f64; 2]; 4], x: &[[f64; 2]; 4], axisymmetric: bool) -> (f64, f64) {
    let (Some(g0), Some(g)) = (geometry(x0, axisymmetric), geometry(x, axisymmetric)) else {
        return (f64::NAN, f64::NAN);
    };
    let (mut frr, mut frz, mut fzr, mut fzz) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..4 {
        frr += g0.br[i] * x[i][0];
        frz += g0.bz[i] * x[i][0];
        fzr += g0.br[i] * x[i][1];
        fzz += g0.bz[i] * x[i][1];
    }
    // b = F Fᵀ (in-plane) and its eigenvalues.
    let b11 = frr * frr + frz * frz;
    let b22 = fzr * fzr + fzz * fzz;
    let b12 = frr * fzr + frz * fzz;
    let mean = 0.5 * (b11 + b22);
    let rad = (0.25 * (b11 - b22).powi(2) + b12 * b12).sqrt();
    let (l1, l2) = (mean + rad, mean - rad);
    let lt = if axisymmetric { (g.rc / g0.rc).powi(2) } else { 1.0 };
    let e = [0.5 * l1.ln(), 0.5 * l2.ln(), 0.5 * lt.ln()];
    (e.iter().cloned().fold(f64::MIN, f64::max), e.iter().cloned().fold(f64::MAX, f64::min))
}

impl ElementFields {
    /// Fields of every element from the current positions and states.
    pub fn compute(mesh: &Mesh, x: &[[f64; 2]], states: &[ElementState], axisymmetric: bool) -> Self {
        let mut f = ElementFields::default();
        for (conn, st) in mesh.elements.iter().zip(states) {
            let x0 = conn.map(|i| mesh.nodes[i as usize]);
            let xe = conn.map(|i| x[i as usize]);
            let (emax, emin) = log_strains(&x0, &xe, axisymmetric);
            let s = st.point.stress();
            f.max_principal_log_strain.push(emax);
            f.min_principal_log_strain.push(emin);
            f.von_mises.push(st.point.von_mises());
            f.pressure.push(st.point.p);
            f.radial_stress.push(s[0]);
            f.axial_stress.push(s[1]);
            f.hoop_stress.push(s[2]);
            f.damage.push(st.point.damage);
            f.plastic_strain.push(st.point.plastic_strain);
            f.centroid.push([xe.iter().map(|p| p[0]).sum::<f64>() / 4.0, xe.iter().map(|p| p[1]).sum::<f64>() / 4.0]);
        }
        f
    }

    /// The fields in the order of [`FIELD_NAMES`].
    pub fn columns(&self) -> [&[f64]; 9] {
        [
            &self.max_principal_log_strain,
            &self.min_principal_log_strain,
            &self.von_mises,
            &self.pressure,
            &self.radial_stress,
            &self.axial_stress,
            &self.hoop_stress,
            &self.damage,
            &self.plastic_strain,
        ]
    }
}

/// One point of the profile under the contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthSample {
    /// Depth below the platen (m).
    pub depth: f64,
    /// Element index.
    pub element: usize,
}

/// Elements of the column under the top contact, ordered by depth below the platen at height
/// `platen_z` (m): axisymmetric, those with an edge on the axis; plane strain, those crossed by
/// the vertical through the top contact node (`nodes`: current positions), upper half only.
pub fn axis_column(mesh: &Mesh, nodes: &[[f64; 2]], fields: &ElementFields, platen_z: f64) -> Vec<DepthSample> {
    let on_axis: std::collections::HashSet<u32> = mesh.axis.iter().cloned().collect();
    let top = mesh.surface.iter().cloned().max_by(|&a, &b| mesh.nodes[a as usize][1].total_cmp(&mesh.nodes[b as usize][1]));
    let xc = top.map(|i| nodes[i as usize][0]).unwrap_or(0.0);
    let keep = |e: usize, c: &[u32; 4]| {
        if mesh.axis.len() >= 2 {
            c.iter().filter(|i| on_axis.contains(i)).count() >= 2
        } else {
            let (lo, hi) = c.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &i| (lo.min(nodes[i as usize][0]), hi.max(nodes[i as usize][0])));
            lo <= xc && xc < hi && fields.centroid[e][1] > 0.0
        }
    };
    let mut v: Vec<DepthSample> = mesh
        .elements
        .iter()
        .enumerate()
        .filter(|(e, c)| keep(*e, c))
        .map(|(e, _)| DepthSample { depth: platen_z - fields.centroid[e][1], element: e })
        .collect();
    v.sort_by(|a, b| a.depth.total_cmp(&b.depth));
    v
}

pub use crate::fracture::FractureDetector;

/// The quasi-static check of a curve (see [`QuasiStatic`]) over the samples after the ramp and
/// up to 95 % of the displacement `peak_at` (m) of the peak force: fracture is dynamic by
/// nature, and in an irregular particle a splitting crack already runs in the last samples before
/// the force peaks (the loading that leads there is what must be quasi-static). The
/// force balance compares the two forces averaged over `window` (s, two wave transits 2R/c):
/// the stress waves that every damage event releases ring on the scale of one transit and are
/// not a departure from quasi-static loading unless they persist.
pub fn quasi_static(curve: &[CurveSample], peak: f64, peak_at: f64, ramp_time: f64, window: f64) -> QuasiStatic {
    let peak_at = 0.95 * peak_at;
    let mean_over = |i: usize| {
        let t = curve[i].time;
        let (mut a, mut b, mut n) = (0.0, 0.0, 0);
        for s in curve.iter().filter(|s| (s.time - t).abs() <= 0.5 * window && s.displacement <= peak_at) {
            a += s.force;
            b += s.force_bottom;
            n += 1;
        }
        (a / n as f64, b / n as f64)
    };
    let final_int = curve.iter().filter(|s| s.displacement <= peak_at).map(|s| s.internal).fold(0.0, f64::max);
    let (mut kr, mut fi, mut hr) = (0.0f64, 0.0f64, 0.0f64);
    for (i, s) in curve.iter().enumerate().filter(|(_, s)| s.time > ramp_time && s.displacement <= peak_at) {
        if s.internal > 0.01 * final_int && s.internal > 0.0 {
            kr = kr.max(s.kinetic / s.internal);
            hr = hr.max(s.hourglass / s.internal);
        }
        if peak > 0.0 {
            let (a, b) = mean_over(i);
            fi = fi.max((a - b).abs() / peak);
        }
    }
    let mut warn = Vec::new();
    if kr > 0.05 {
        warn.push(format!("kinetic/internal energy reached {:.1} % (> 5 %)", 100.0 * kr));
    }
    if fi > 0.05 {
        warn.push(format!("top/bottom force imbalance reached {:.1} % (> 5 %)", 100.0 * fi));
    }
    if hr > 0.1 {
        warn.push(format!("hourglass energy reached {:.1} % of the internal energy (> 10 %)", 100.0 * hr));
    }
    let warning = if warn.is_empty() { None } else { Some(format!("run not quasi-static: {}; lower crush.platen.speed or refine", warn.join("; "))) };
    QuasiStatic { max_kinetic_ratio: kr, max_force_imbalance: fi, max_hourglass_ratio: hr, warning }
}

/// ASCII VTK unstructured grid (.vtu) of quads in the (r, z) plane (z as VTK's y), with the
/// element fields as cell data.
pub fn vtu(mesh: &Mesh, nodes: &[[f64; 2]], fields: &ElementFields) -> String {
    let mut s = String::new();
    let (np, ne) = (nodes.len(), mesh.elements.len());
    s.push_str("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n");
    let _ = writeln!(s, "<Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{ne}\">");
    s.push_str("<Points>\n");
    vtk_data_array(&mut s, "Float64", "Points", 3, nodes.iter().flat_map(|p| [p[0], p[1], 0.0]), false);
    s.push_str("</Points>\n<Cells>\n");
    vtk_data_array(&mut s, "Int64", "connectivity", 1, mesh.elements.iter().flat_map(|c| c.iter().map(|&k| k as f64)), true);
    vtk_data_array(&mut s, "Int64", "offsets", 1, (1..=ne).map(|e| (4 * e) as f64), true);
    vtk_data_array(&mut s, "UInt8", "types", 1, (0..ne).map(|_| 9.0), true);
    s.push_str("</Cells>\n<CellData>\n");
    for ((name, _), col) in FIELD_NAMES.iter().zip(fields.columns()) {
        vtk_data_array(&mut s, "Float64", name, 1, col.iter().copied(), false);
    }
    s.push_str("</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fracture::FractureParams;

    #[test]
    fn fracture_needs_a_sustained_drop() {
        let p = FractureParams { drop: 0.2, sustain: 2.0, run_on: 0.0 };
        let mut d = FractureDetector::new(p);
        // A rise, a transient dip that recovers, a new peak, then a sustained drop.
        let pts = [(0.0, 0.0), (1.0, 10.0), (2.0, 7.0), (3.0, 12.0), (4.0, 20.0), (5.0, 10.0), (6.0, 9.0), (7.0, 8.0)];
        let mut hit = None;
        for (x, f) in pts {
            if let Some(v) = d.push(x, f) {
                hit = Some((x, v));
            }
        }
        assert_eq!(hit, Some((7.0, 4.0)));
        assert_eq!(d.result(), (20.0, 4.0, Some(4.0)));
    }

    #[test]
    fn quasi_static_check_flags_kinetic_energy_during_loading_only() {
        // A linear loading to the peak at 10 µm; kinetic energy spikes at `spike` µm.
        let curve = |spike: f64| -> Vec<CurveSample> {
            (0..=100)
                .map(|i| {
                    let d = 0.1e-6 * i as f64;
                    let e = 1e-3 * (d / 1e-5).powi(2);
                    let ke = if (d - spike * 1e-6).abs() < 0.05e-6 { 0.5 * e } else { 1e-4 * e };
                    CurveSample { time: d, displacement: d, force: 1e7 * d, force_bottom: 1e7 * d, kinetic: ke, internal: e, hourglass: 0.0, external: e }
                })
                .collect()
        };
        let q = quasi_static(&curve(9.9), 100.0, 1e-5, 0.0, 1e-9);
        assert!(q.warning.is_none(), "the onset of fracture at the peak is not loading: {q:?}");
        let q = quasi_static(&curve(5.0), 100.0, 1e-5, 0.0, 1e-9);
        assert!(q.max_kinetic_ratio > 0.4 && q.warning.as_deref().is_some_and(|w| w.contains("kinetic")), "{q:?}");
    }

    #[test]
    fn log_strain_of_a_uniform_stretch() {
        let x0 = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]];
        // z stretched by 1.1, no radial motion: principal log strains ln 1.1 and 0.
        let x = x0.map(|p| [p[0], 1.1 * p[1]]);
        let (emax, emin) = log_strains(&x0, &x, true);
        assert!((emax - 1.1f64.ln()).abs() < 1e-12 && emin.abs() < 1e-12);
    }
}

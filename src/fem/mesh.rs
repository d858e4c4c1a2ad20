//! Structured, graded meshes of 4-node quads for the crush FE.
//!
//! ## Axisymmetric quarter particle
//! The (r, z) quarter r ≥ 0, z ≥ 0 of a body of revolution whose loading axis is z; the platen
//! touches the pole (0, R). The unit quarter disc is split into three mapped blocks meeting at
//! an interior point C = (0.4, 0.4) R (the standard three-quad split of a triangle-like region):
//!
//! ```text
//!   pole (0,R) ── arc ── P45 (R/√2, R/√2)
//!      │   polar block    │
//!   M1 (0,R/2) ────── C ───── equatorial block ── arc ── (R, 0)
//!      │   core block    │
//!   (0,0) ─────────── M2 (R/2, 0) ──────────────────────
//! ```
//!
//! Each block is a transfinite (Coons) interpolation of its four edge node lists. The two edges
//! that meet at the pole are graded: a uniform zone of element size `h₀ = a/refinement` out to
//! `fine_zone·a` (a = expected contact radius, `expected_contact_ratio·R`), then geometric growth
//! by `growth` up to the bulk size R/`bulk_elements`. All other edges are uniform. Shared edges
//! use the same node list, so the mesh is conforming.
//!
//! Shapes (outline radius ρ_out(θ) = R f(θ), θ measured from the loading axis) are made by
//! mapping the unit-sphere mesh radially, node (ρ, θ) → (ρ f(θ), θ):
//! * [`Shape::Sphere`]: f = 1;
//! * [`Shape::Asperity`]: f(θ) = f_b + (1 − f_b) exp(−θ²/2w²) with f_b = 1 − w²(1/ρ_c − 1): a
//!   smooth tip whose radius of curvature at the pole is ρ_c R (roundness factor ρ_c ∈ (0, 1]) on a
//!   body of the same height R, width w (rad);
//! * [`Shape::Spheroid`]: polar semi-axis R, equatorial semi-axis αR; the pole's radius of
//!   curvature is α² R.
//!
//! The radius of curvature at the pole of a polar curve with f'(0) = 0 is
//! R f(0)² / (f(0) − f''(0)), which the unit test `pole_curvature_matches_roundness` checks.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Particle outline.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// A sphere.
    Sphere,
    /// A sphere whose contact region has radius of curvature `roundness·R`.
    Asperity {
        /// Roundness factor ρ_c ∈ (0, 1]: tip radius of curvature / R.
        roundness: f64,
        /// Angular half-width w of the tip region (rad), default 0.35.
        #[serde(default = "default_width")]
        width: f64,
    },
    /// A spheroid with the loading axis as its symmetry axis.
    Spheroid {
        /// Equatorial / polar semi-axis ratio α (> 0; < 1 prolate along the load).
        aspect: f64,
    },
}

fn default_width() -> f64 {
    0.35
}

impl Shape {
    /// Outline radius factor f(θ), θ from the loading axis (rad).
    pub fn radius_factor(&self, theta: f64) -> f64 {
        match *self {
            Shape::Sphere => 1.0,
            Shape::Asperity { roundness, width } => {
                let fb = 1.0 - width * width * (1.0 / roundness - 1.0);
                fb + (1.0 - fb) * (-theta * theta / (2.0 * width * width)).exp()
            }
            Shape::Spheroid { aspect } => {
                let (s, c) = theta.sin_cos();
                1.0 / (s * s / (aspect * aspect) + c * c).sqrt()
            }
        }
    }

    /// Radius of curvature at the pole divided by R.
    pub fn pole_curvature_ratio(&self) -> f64 {
        match *self {
            Shape::Sphere => 1.0,
            Shape::Asperity { roundness, .. } => roundness,
            Shape::Spheroid { aspect } => aspect * aspect,
        }
    }

    /// Checks the shape constants.
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        match *self {
            Shape::Sphere => Ok(()),
            Shape::Asperity { roundness, width } => {
                if !(roundness > 0.0 && roundness <= 1.0) {
                    return Err(Error::config(file, format!("{key}.roundness"), format!("must lie in (0, 1], got {roundness}")));
                }
                if !(width > 0.05 && width <= 1.0) {
                    return Err(Error::config(file, format!("{key}.width"), format!("must lie in (0.05, 1] rad, got {width}")));
                }
                let fb = 1.0 - width * width * (1.0 / roundness - 1.0);
                if fb < 0.5 {
                    return Err(Error::config(
                        file,
                        format!("{key}.roundness"),
                        format!("roundness {roundness} with width {width} rad shrinks the body below half its height (f_b = {fb:.2}); use a larger roundness or a smaller width"),
                    ));
                }
                Ok(())
            }
            Shape::Spheroid { aspect } => {
                if !(0.3..=3.0).contains(&aspect) {
                    return Err(Error::config(file, format!("{key}.aspect"), format!("must lie in [0.3, 3], got {aspect}")));
                }
                Ok(())
            }
        }
    }
}

/// Mesh density.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MeshParams {
    /// Elements per expected contact radius at the pole (the one refinement parameter; default 12).
    pub refinement: f64,
    /// Expected contact radius at the end of the run / R (default 0.15).
    pub expected_contact_ratio: f64,
    /// Extent of the uniform fine zone in expected contact radii (default 1.5).
    pub fine_zone: f64,
    /// Geometric growth factor of element size away from the fine zone (default 1.15).
    pub growth: f64,
    /// Bulk element size = R / bulk_elements (default 12).
    pub bulk_elements: f64,
}

impl Default for MeshParams {
    fn default() -> Self {
        MeshParams { refinement: 12.0, expected_contact_ratio: 0.15, fine_zone: 1.5, growth: 1.15, bulk_elements: 12.0 }
    }
}

impl MeshParams {
    /// Checks the parameters; a mesh that would come out degenerate is refused here or by
    /// [`Mesh::check_quality`].
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        let bad = |k: &str, rule: String| Err(Error::config(file, format!("{key}.{k}"), rule));
        if !(self.refinement >= 1.0 && self.refinement <= 200.0) {
            return bad("refinement", format!("must lie in [1, 200] elements per contact radius, got {}", self.refinement));
        }
        if !(self.expected_contact_ratio > 0.005 && self.expected_contact_ratio <= 0.5) {
            return bad("expected_contact_ratio", format!("must lie in (0.005, 0.5], got {}", self.expected_contact_ratio));
        }
        if !(self.fine_zone >= 0.5 && self.fine_zone <= 5.0) {
            return bad("fine_zone", format!("must lie in [0.5, 5] contact radii, got {}", self.fine_zone));
        }
        if !(self.growth >= 1.0 && self.growth <= 1.5) {
            return bad("growth", format!("must lie in [1, 1.5] (larger jumps in element size degrade the solution), got {}", self.growth));
        }
        if !(self.bulk_elements >= 4.0 && self.bulk_elements <= 200.0) {
            return bad("bulk_elements", format!("must lie in [4, 200], got {}", self.bulk_elements));
        }
        let h0 = self.expected_contact_ratio / self.refinement;
        let hb = 1.0 / self.bulk_elements;
        if h0 > hb {
            return bad(
                "refinement",
                format!("the contact element size a/refinement = {h0:.4} R is coarser than the bulk size R/bulk_elements = {hb:.4} R"),
            );
        }
        if h0 < 1e-4 {
            return bad("refinement", format!("contact element size {h0:.1e} R is below 1e-4 R: the mesh would have millions of elements"));
        }
        Ok(())
    }
}

/// A mesh of 4-node quads (counter-clockwise in (r, z)).
#[derive(Debug, Clone)]
pub struct Mesh {
    /// Node coordinates (r, z) (m).
    pub nodes: Vec<[f64; 2]>,
    /// Element connectivity, counter-clockwise.
    pub elements: Vec<[u32; 4]>,
    /// Nodes on the symmetry axis r = 0 (plane-strain section: the centre node, held in x).
    pub axis: Vec<u32>,
    /// Nodes on the equatorial plane z = 0.
    pub equator: Vec<u32>,
    /// Nodes on the outer surface (contact candidates).
    pub surface: Vec<u32>,
}

/// Node positions along an edge of length `len`, graded from `t = 0`: uniform `h0` up to
/// `fine`, then growing by `growth` up to `h_max`; the graded part is scaled to end exactly at
/// `len`. Returns the normalised positions in [0, 1].
fn graded(len: f64, h0: f64, fine: f64, growth: f64, h_max: f64) -> Vec<f64> {
    let mut t = vec![0.0];
    let mut h = h0;
    let mut x = 0.0;
    while x + h < len - 0.5 * h {
        x += h;
        t.push(x);
        if x >= fine {
            h = (h * growth).min(h_max);
        }
    }
    t.push(len);
    t.into_iter().map(|v| v / len).collect()
}

fn uniform(n: usize) -> Vec<f64> {
    (0..=n).map(|i| i as f64 / n as f64).collect()
}

fn lerp(a: [f64; 2], b: [f64; 2], t: f64) -> [f64; 2] {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
}

/// A mapped block: `bottom`/`top` have n+1 points (i direction), `left`/`right` m+1 points
/// (j direction); corners shared. Returns points indexed `[j][i]`.
fn coons(bottom: &[[f64; 2]], top: &[[f64; 2]], left: &[[f64; 2]], right: &[[f64; 2]]) -> Vec<Vec<[f64; 2]>> {
    let n = bottom.len() - 1;
    let m = left.len() - 1;
    let (p00, p10, p01, p11) = (bottom[0], bottom[n], top[0], top[n]);
    (0..=m)
        .map(|j| {
            let v = j as f64 / m as f64;
            (0..=n)
                .map(|i| {
                    let u = i as f64 / n as f64;
                    let mut p = [0.0; 2];
                    for k in 0..2 {
                        p[k] = (1.0 - v) * bottom[i][k] + v * top[i][k] + (1.0 - u) * left[j][k] + u * right[j][k]
                            - ((1.0 - u) * (1.0 - v) * p00[k] + u * (1.0 - v) * p10[k] + (1.0 - u) * v * p01[k] + u * v * p11[k]);
                    }
                    p
                })
                .collect()
        })
        .collect()
}

/// Builds meshes from blocks with node merging by exact block-edge identity.
struct Builder {
    nodes: Vec<[f64; 2]>,
    elements: Vec<[u32; 4]>,
}

impl Builder {
    /// Adds a block's nodes; `reuse(i, j)` returns an existing node id for shared edges.
    fn block(&mut self, pts: &[Vec<[f64; 2]>], reuse: &dyn Fn(usize, usize) -> Option<u32>) -> Vec<Vec<u32>> {
        let ids: Vec<Vec<u32>> = pts
            .iter()
            .enumerate()
            .map(|(j, row)| {
                row.iter()
                    .enumerate()
                    .map(|(i, p)| {
                        reuse(i, j).unwrap_or_else(|| {
                            self.nodes.push(*p);
                            (self.nodes.len() - 1) as u32
                        })
                    })
                    .collect()
            })
            .collect();
        for j in 0..ids.len() - 1 {
            for i in 0..ids[0].len() - 1 {
                self.elements.push([ids[j][i], ids[j][i + 1], ids[j + 1][i + 1], ids[j + 1][i]]);
            }
        }
        ids
    }
}

impl Mesh {
    /// The axisymmetric quarter mesh of a particle of diameter `diameter` (m).
    pub fn quarter(shape: &Shape, diameter: f64, p: &MeshParams) -> Result<Mesh> {
        let mut mesh = Self::unit_quarter(p);
        let radius = 0.5 * diameter;
        for n in mesh.nodes.iter_mut() {
            let rho = (n[0] * n[0] + n[1] * n[1]).sqrt();
            let theta = n[0].atan2(n[1]);
            let f = shape.radius_factor(theta);
            let (s, co) = theta.sin_cos();
            *n = if rho > 0.0 { [radius * rho * f * s, radius * rho * f * co] } else { [0.0, 0.0] };
        }
        for &i in &mesh.axis {
            mesh.nodes[i as usize][0] = 0.0;
        }
        for &i in &mesh.equator {
            mesh.nodes[i as usize][1] = 0.0;
        }
        mesh.check_quality()?;
        Ok(mesh)
    }

    /// The whole (x, z) section for plane strain: the unit quarter reflected into four quadrants
    /// (fine at both poles), its angles warped piecewise linearly so that the poles land on the
    /// directions `theta_top` and `theta_bottom` of the contact points (rad from +z towards +x),
    /// and mapped radially onto the outline radius `radius(θ)` (m).
    pub fn section(radius: &dyn Fn(f64) -> f64, theta_top: f64, theta_bottom: f64, p: &MeshParams) -> Result<Mesh> {
        let q = Self::unit_quarter(p);
        let nq = q.nodes.len();
        let on_axis: Vec<bool> = (0..nq).map(|i| q.axis.binary_search(&(i as u32)).is_ok()).collect();
        let on_eq: Vec<bool> = (0..nq).map(|i| q.equator.binary_search(&(i as u32)).is_ok()).collect();
        let mut nodes: Vec<[f64; 2]> = Vec::new();
        let mut elements = Vec::new();
        let mut surface = Vec::new();
        // Node ids per quadrant (sx, sz); shared nodes on the mirror lines are reused.
        let mut ids: Vec<Vec<u32>> = Vec::new();
        for (qi, (sx, sz)) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)].into_iter().enumerate() {
            let mut map = vec![0u32; nq];
            for i in 0..nq {
                let reuse = if sx < 0.0 && on_axis[i] {
                    Some(ids[qi - 1][i])
                } else if sz < 0.0 && on_eq[i] {
                    Some(ids[qi - 2][i])
                } else {
                    None
                };
                map[i] = reuse.unwrap_or_else(|| {
                    nodes.push([sx * q.nodes[i][0], sz * q.nodes[i][1]]);
                    (nodes.len() - 1) as u32
                });
            }
            for e in &q.elements {
                let c = e.map(|i| map[i as usize]);
                // One reflection reverses the orientation.
                elements.push(if sx * sz < 0.0 { [c[3], c[2], c[1], c[0]] } else { c });
            }
            surface.extend(q.surface.iter().map(|&i| map[i as usize]));
            ids.push(map);
        }
        surface.sort_unstable();
        surface.dedup();
        let two_pi = std::f64::consts::TAU;
        let pi = std::f64::consts::PI;
        // Clockwise (towards +x) from the top pole to the bottom pole, and the rest.
        let span_right = (theta_bottom - theta_top).rem_euclid(two_pi);
        let span_left = two_pi - span_right;
        for n in nodes.iter_mut() {
            let rho = (n[0] * n[0] + n[1] * n[1]).sqrt();
            if rho == 0.0 {
                continue;
            }
            let t = n[0].atan2(n[1]);
            let theta = if t >= 0.0 { theta_top + span_right * t / pi } else { theta_top + span_left * t / pi };
            let (s, c) = theta.sin_cos();
            let r = radius(theta);
            *n = [rho * r * s, rho * r * c];
        }
        let origin = nodes.iter().position(|n| n[0] == 0.0 && n[1] == 0.0).map(|i| i as u32);
        let mesh = Mesh { nodes, elements, axis: origin.into_iter().collect(), equator: Vec::new(), surface };
        mesh.check_quality()?;
        Ok(mesh)
    }

    /// The unit quarter disc (R = 1), graded towards the pole (0, 1).
    fn unit_quarter(p: &MeshParams) -> Mesh {
        let r = 1.0; // unit sphere; scaled and shaped at the end
        let h0 = p.expected_contact_ratio / p.refinement;
        let fine = p.fine_zone * p.expected_contact_ratio;
        let hb = 1.0 / p.bulk_elements;
        let c = [0.4 * r, 0.4 * r];
        let m1 = [0.0, 0.5 * r];
        let m2 = [0.5 * r, 0.0];
        let pole = [0.0, r];
        let q = std::f64::consts::FRAC_PI_4;
        let p45 = [r * q.sin(), r * q.cos()];
        // Graded edges from the pole.
        let t_arc = graded(q * r, h0, fine, p.growth, hb);
        let t_axis = graded(0.5 * r, h0, fine, p.growth, hb);
        let n1 = t_arc.len() - 1; // along the arc / M1–C
        let n2 = t_axis.len() - 1; // along the axis / P45–C
        let k = ((q * r / hb).round() as usize).max(2); // core / equatorial block width
        let arc = |theta: f64| [r * theta.sin(), r * theta.cos()];
        // Polar block: i along the arc (pole → P45), j along the axis (pole → M1).
        let e_arc: Vec<[f64; 2]> = t_arc.iter().map(|&t| arc(t * q)).collect();
        let e_inner: Vec<[f64; 2]> = uniform(n1).iter().map(|&t| lerp(m1, c, t)).collect();
        let e_axis: Vec<[f64; 2]> = t_axis.iter().map(|&t| lerp(pole, m1, t)).collect();
        let e_diag: Vec<[f64; 2]> = uniform(n2).iter().map(|&t| lerp(p45, c, t)).collect();
        let polar = coons(&e_arc, &e_inner, &e_axis, &e_diag);
        // Core block: i along M1 → C (shared), j from the axis bottom (0,0)→M1... built with
        // bottom = O → M2, top = M1 → C, left = O → M1, right = M2 → C.
        let o = [0.0, 0.0];
        let e_core_bottom: Vec<[f64; 2]> = uniform(n1).iter().map(|&t| lerp(o, m2, t)).collect();
        let e_core_left: Vec<[f64; 2]> = uniform(k).iter().map(|&t| lerp(o, m1, t)).collect();
        let e_core_right: Vec<[f64; 2]> = uniform(k).iter().map(|&t| lerp(m2, c, t)).collect();
        let core = coons(&e_core_bottom, &e_inner, &e_core_left, &e_core_right);
        // Equatorial block: bottom = M2 → (R,0) (n2), top = C → P45 (n2), left = M2 → C (k),
        // right = (R,0) → P45 along the arc (k).
        let e_eq_bottom: Vec<[f64; 2]> = uniform(n2).iter().map(|&t| lerp(m2, [r, 0.0], t)).collect();
        let e_eq_top: Vec<[f64; 2]> = e_diag.iter().rev().cloned().collect();
        let e_eq_right: Vec<[f64; 2]> = uniform(k).iter().map(|&t| arc(std::f64::consts::FRAC_PI_2 - t * q)).collect();
        let equatorial = coons(&e_eq_bottom, &e_eq_top, &e_core_right, &e_eq_right);

        let mut b = Builder { nodes: Vec::new(), elements: Vec::new() };
        // Polar block rows j run pole→M1; flip j so the element order is counter-clockwise:
        // with i along the arc (towards +r) and j downward, (i, j) → (i+1, j) → (i+1, j+1) is
        // clockwise, so build the block with rows reversed (j from M1 up to the pole).
        let polar_rev: Vec<Vec<[f64; 2]>> = polar.iter().rev().cloned().collect();
        let polar_ids = b.block(&polar_rev, &|_, _| None);
        // polar_rev[0] is the inner edge M1 → C.
        let inner_ids = polar_ids[0].clone();
        let core_ids = b.block(&core, &|i, j| if j == k { Some(inner_ids[i]) } else { None });
        // Diagonal P45 → C is the last column of the polar block (i = n1), rows reversed: row
        // index j' = n2 − j. Equatorial top runs C → P45 with index i: C is j = n2 in polar
        // (row 0 of polar_rev), P45 is j = 0 (row n2 of polar_rev).
        let diag_ids: Vec<u32> = (0..=n2).map(|i| polar_ids[i][n1]).collect(); // C → P45
        let core_right_ids: Vec<u32> = (0..=k).map(|j| core_ids[j][n1]).collect(); // M2 → C
        let eq_ids = b.block(&equatorial, &|i, j| {
            if j == k {
                Some(diag_ids[i])
            } else if i == 0 {
                Some(core_right_ids[j])
            } else {
                None
            }
        });

        // Node sets.
        let mut axis: Vec<u32> = (0..=n2).map(|j| polar_ids[j][0]).chain((0..=k).map(|j| core_ids[j][0])).collect();
        let mut equator: Vec<u32> = (0..=n1).map(|i| core_ids[0][i]).chain((0..=n2).map(|i| eq_ids[0][i])).collect();
        let mut surface: Vec<u32> = (0..=n1).map(|i| polar_ids[n2][i]).chain((0..=k).map(|j| eq_ids[j][n2])).collect();
        for v in [&mut axis, &mut equator, &mut surface] {
            v.sort_unstable();
            v.dedup();
        }
        Mesh { nodes: b.nodes, elements: b.elements, axis, equator, surface }
    }

    /// Signed area of element `e` (m²), positive counter-clockwise.
    pub fn area(&self, e: usize) -> f64 {
        let [a, b, c, d] = self.elements[e].map(|i| self.nodes[i as usize]);
        0.5 * ((c[0] - a[0]) * (d[1] - b[1]) + (b[0] - d[0]) * (c[1] - a[1]))
    }

    /// Refuses inverted or degenerate elements (interior angle outside [10°, 170°]).
    pub fn check_quality(&self) -> Result<()> {
        for (e, conn) in self.elements.iter().enumerate() {
            let p = conn.map(|i| self.nodes[i as usize]);
            if self.area(e) <= 0.0 {
                return Err(Error::config("<mesh>", "mesh", format!("element {e} is inverted (area {:.3e} m²)", self.area(e))));
            }
            for k in 0..4 {
                let (a, b, c) = (p[(k + 3) % 4], p[k], p[(k + 1) % 4]);
                let u = [a[0] - b[0], a[1] - b[1]];
                let v = [c[0] - b[0], c[1] - b[1]];
                let cross = u[0] * v[1] - u[1] * v[0];
                let dot = u[0] * v[0] + u[1] * v[1];
                let ang = cross.atan2(dot).abs().to_degrees();
                if !(10.0..=170.0).contains(&ang) {
                    return Err(Error::config(
                        "<mesh>",
                        "mesh",
                        format!("element {e} is degenerate: interior angle {ang:.1}° at node {} (allowed 10°–170°); change the mesh parameters", conn[k]),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Smallest element edge (m).
    pub fn min_edge(&self) -> f64 {
        let mut h = f64::MAX;
        for conn in &self.elements {
            for k in 0..4 {
                let a = self.nodes[conn[k] as usize];
                let b = self.nodes[conn[(k + 1) % 4] as usize];
                h = h.min(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt());
            }
        }
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_sphere_area_and_sets() {
        let m = Mesh::quarter(&Shape::Sphere, 1e-3, &MeshParams::default()).unwrap();
        let area: f64 = (0..m.elements.len()).map(|e| m.area(e)).sum();
        let exact = std::f64::consts::PI * 0.25e-6 / 4.0;
        // Straight chords under-fill the arc by O(h²).
        assert!((area - exact).abs() / exact < 2e-3, "area {area:e} vs {exact:e}");
        assert!(m.axis.iter().all(|&i| m.nodes[i as usize][0] == 0.0));
        assert!(m.equator.iter().all(|&i| m.nodes[i as usize][1] == 0.0));
        for &i in &m.surface {
            let [x, z] = m.nodes[i as usize];
            assert!(((x * x + z * z).sqrt() - 0.5e-3).abs() < 1e-12);
        }
        // Every node is used and the finest element sits at the pole.
        let h0 = 0.5e-3 * 0.15 / 8.0;
        assert!((m.min_edge() - h0).abs() / h0 < 0.35, "min edge {} vs {h0}", m.min_edge());
    }

    #[test]
    fn pole_curvature_matches_roundness() {
        for shape in [Shape::Asperity { roundness: 0.5, width: 0.35 }, Shape::Spheroid { aspect: 0.8 }] {
            let h = 1e-4;
            let f0 = shape.radius_factor(0.0);
            let f2 = (shape.radius_factor(h) - 2.0 * f0 + shape.radius_factor(-h)) / (h * h);
            let rc = f0 * f0 / (f0 - f2);
            assert!((rc - shape.pole_curvature_ratio()).abs() < 1e-5, "{shape:?}: {rc}");
            let m = Mesh::quarter(&shape, 1e-3, &MeshParams::default()).unwrap();
            assert!(m.elements.len() > 100);
        }
    }

    #[test]
    fn conforming_no_duplicate_nodes() {
        let m = Mesh::quarter(&Shape::Sphere, 1e-3, &MeshParams::default()).unwrap();
        let mut used = vec![0u32; m.nodes.len()];
        for e in &m.elements {
            for &i in e {
                used[i as usize] += 1;
            }
        }
        assert!(used.iter().all(|&u| u > 0));
        let mut pts: Vec<(i64, i64)> = m.nodes.iter().map(|p| ((p[0] * 1e12) as i64, (p[1] * 1e12) as i64)).collect();
        pts.sort_unstable();
        let n = pts.len();
        pts.dedup();
        assert_eq!(pts.len(), n, "coincident nodes: the blocks do not share their edges");
    }
}

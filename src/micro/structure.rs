//! Two-phase pixel microstructures and the connectivity of each phase.
//!
//! A [`Microstructure`] is a grid of `nx × ny` square pixels of side `pixel_m`, each labelled
//! with its phase (0 … 255), stored row by row from the bottom (`labels[j·nx + i]` is the pixel
//! in column i, row j).
//!
//! # Synthetic two-phase microstructures ([`voronoi_two_phase`])
//!
//! The deliverable's §6.1 argument is about topology at equal phase fractions: in BL 16/30 the soft
//! silica phase sits in pockets between alumina grains that touch one another (a hard skeleton),
//! in Gen 4 it forms a continuous matrix around the grains. Both are made here from the same
//! periodic Voronoi tessellation of `grains` seeds (uniform in the periodic box), and the soft
//! phase takes exactly `round(f·nx·ny)` pixels, those with the smallest value of a distance:
//!
//! * [`Topology::SoftMatrix`] (Gen 4-like): the distance of the pixel centre to the nearest cell
//!   boundary, min over the second and third nearest seeds s of (|p − s|² − |p − s₁|²)/(2|s − s₁|)
//!   (the distance to the bisector of s₁ and s): the soft phase is a layer along every grain
//!   boundary, continuous, and the hard grains are islands in it;
//! * [`Topology::SoftPockets`] (BL 16/30-like): |p − s₃| − |p − s₁|, the third-nearest seed
//!   distance minus the nearest, zero at triple junctions: the soft phase fills pockets at the
//!   triple junctions and the hard grains stay in contact along the rest of their boundaries.
//!
//! Distances use the periodic minimum image; ties go to the lower pixel index, so a
//! microstructure is a function of its settings and seed alone. Whether a phase percolates is
//! measured, not assumed ([`Microstructure::connectivity`]): at large soft fractions pockets merge.
//!
//! # Connectivity
//!
//! Clusters of a phase are its 4-connected pixel sets (edge neighbours, the box not wrapped). A
//! phase percolates in x (y) when one cluster touches both the left and right (bottom and top)
//! edges.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{Error, Result};

/// A labelled pixel grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Microstructure {
    /// Pixels along x.
    pub nx: usize,
    /// Pixels along y.
    pub ny: usize,
    /// Pixel side (m).
    pub pixel_m: f64,
    /// Phase label of each pixel, `labels[j·nx + i]`.
    pub labels: Vec<u8>,
}

/// How the soft phase of a synthetic two-phase microstructure is arranged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Topology {
    /// A continuous soft layer along every grain boundary, hard grains as islands (Gen 4-like).
    SoftMatrix,
    /// Soft pockets at the triple junctions of a hard skeleton (BL 16/30-like).
    SoftPockets,
}

/// The connectivity of one phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Connectivity {
    /// Area fraction of the phase.
    pub fraction: f64,
    /// Number of 4-connected clusters.
    pub clusters: usize,
    /// Pixels of the largest cluster over the phase's pixels (0 without pixels).
    pub largest_fraction: f64,
    /// One cluster touches the left and the right edge.
    pub percolates_x: bool,
    /// One cluster touches the bottom and the top edge.
    pub percolates_y: bool,
}

impl Connectivity {
    /// Percolates in x or y.
    pub fn percolates(&self) -> bool {
        self.percolates_x || self.percolates_y
    }
}

/// The label of the hard phase of a synthetic microstructure.
pub const HARD: u8 = 0;
/// The label of the soft phase of a synthetic microstructure.
pub const SOFT: u8 = 1;

impl Microstructure {
    /// A grid from its labels; refused when the sizes disagree or the pixel size is not positive.
    pub fn new(nx: usize, ny: usize, pixel_m: f64, labels: Vec<u8>) -> Result<Self> {
        if nx < 2 || ny < 2 || labels.len() != nx * ny {
            return Err(Error::numerical("microstructure", format!("needs at least 2 × 2 pixels and nx·ny labels, got {nx} × {ny} and {} labels", labels.len())));
        }
        if !(pixel_m.is_finite() && pixel_m > 0.0) {
            return Err(Error::numerical("microstructure", format!("the pixel size must be > 0, got {pixel_m}")));
        }
        Ok(Microstructure { nx, ny, pixel_m, labels })
    }

    /// Area fraction of phase `label`.
    pub fn fraction(&self, label: u8) -> f64 {
        self.labels.iter().filter(|&&l| l == label).count() as f64 / self.labels.len() as f64
    }

    /// The connectivity of phase `label` (see the module documentation).
    pub fn connectivity(&self, label: u8) -> Connectivity {
        let (nx, ny) = (self.nx, self.ny);
        let mut cluster = vec![usize::MAX; nx * ny];
        let (mut sizes, mut spans) = (Vec::new(), Vec::new());
        let mut stack = Vec::new();
        for start in 0..nx * ny {
            if self.labels[start] != label || cluster[start] != usize::MAX {
                continue;
            }
            let id = sizes.len();
            let (mut size, mut edges) = (0usize, [false; 4]);
            cluster[start] = id;
            stack.push(start);
            while let Some(p) = stack.pop() {
                size += 1;
                let (i, j) = (p % nx, p / nx);
                edges[0] |= i == 0;
                edges[1] |= i + 1 == nx;
                edges[2] |= j == 0;
                edges[3] |= j + 1 == ny;
                let neighbours = [(i > 0).then(|| p - 1), (i + 1 < nx).then(|| p + 1), (j > 0).then(|| p - nx), (j + 1 < ny).then(|| p + nx)];
                for q in neighbours.into_iter().flatten() {
                    if self.labels[q] == label && cluster[q] == usize::MAX {
                        cluster[q] = id;
                        stack.push(q);
                    }
                }
            }
            sizes.push(size);
            spans.push(edges);
        }
        let total: usize = sizes.iter().sum();
        Connectivity {
            fraction: total as f64 / (nx * ny) as f64,
            clusters: sizes.len(),
            largest_fraction: if total > 0 { *sizes.iter().max().unwrap_or(&0) as f64 / total as f64 } else { 0.0 },
            percolates_x: spans.iter().any(|e| e[0] && e[1]),
            percolates_y: spans.iter().any(|e| e[2] && e[3]),
        }
    }
}

/// A synthetic two-phase microstructure (see the module documentation): `grains` Voronoi grains
/// of the hard phase ([`HARD`]) and the soft phase ([`SOFT`]) on exactly `round(soft_fraction·nx·ny)`
/// pixels, arranged by `topology`.
pub fn voronoi_two_phase(nx: usize, ny: usize, pixel_m: f64, grains: usize, soft_fraction: f64, topology: Topology, seed: u64) -> Result<Microstructure> {
    if grains < 3 {
        return Err(Error::numerical("microstructure", format!("needs at least 3 grains, got {grains}")));
    }
    if !(soft_fraction > 0.0 && soft_fraction < 1.0) {
        return Err(Error::numerical("microstructure", format!("the soft fraction must lie in (0, 1), got {soft_fraction}")));
    }
    let (lx, ly) = (nx as f64, ny as f64);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let seeds: Vec<(f64, f64)> = (0..grains).map(|_| (rng.random::<f64>() * lx, rng.random::<f64>() * ly)).collect();
    let wrap = |d: f64, l: f64| d - l * (d / l).round();
    let measure: Vec<f64> = (0..nx * ny)
        .into_par_iter()
        .map(|p| {
            let (x, y) = ((p % nx) as f64 + 0.5, (p / nx) as f64 + 0.5);
            // The three nearest seeds: their minimum-image offsets from the pixel centre.
            let mut near = [(f64::INFINITY, 0.0, 0.0); 3];
            for &(sx, sy) in &seeds {
                let (dx, dy) = (wrap(sx - x, lx), wrap(sy - y, ly));
                let d2 = dx * dx + dy * dy;
                if d2 < near[2].0 {
                    near[2] = (d2, dx, dy);
                    near.sort_by(|a, b| a.0.total_cmp(&b.0));
                }
            }
            match topology {
                Topology::SoftMatrix => near[1..]
                    .iter()
                    .map(|&(d2, dx, dy)| {
                        let sep = ((dx - near[0].1).powi(2) + (dy - near[0].2).powi(2)).sqrt();
                        (d2 - near[0].0) / (2.0 * sep.max(1e-12))
                    })
                    .fold(f64::INFINITY, f64::min),
                Topology::SoftPockets => near[2].0.sqrt() - near[0].0.sqrt(),
            }
        })
        .collect();
    let mut order: Vec<usize> = (0..nx * ny).collect();
    order.sort_by(|&a, &b| measure[a].total_cmp(&measure[b]).then(a.cmp(&b)));
    let soft = ((soft_fraction * (nx * ny) as f64).round() as usize).clamp(1, nx * ny - 1);
    let mut labels = vec![HARD; nx * ny];
    for &p in &order[..soft] {
        labels[p] = SOFT;
    }
    Microstructure::new(nx, ny, pixel_m, labels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn connectivity_of_stripes_and_a_checkerboard() {
        // Vertical stripes two pixels wide: each phase has 4 clusters spanning y, none spanning x.
        let (nx, ny) = (16, 8);
        let labels: Vec<u8> = (0..nx * ny).map(|p| ((p % nx) / 2 % 2) as u8).collect();
        let m = Microstructure::new(nx, ny, 1e-6, labels).unwrap();
        let c = m.connectivity(1);
        assert_eq!((c.clusters, c.percolates_x, c.percolates_y), (4, false, true));
        assert!((c.fraction - 0.5).abs() < 1e-15 && (c.largest_fraction - 0.25).abs() < 1e-15);
        // A checkerboard of single pixels: no two same-phase pixels share an edge.
        let labels: Vec<u8> = (0..nx * ny).map(|p| ((p % nx + p / nx) % 2) as u8).collect();
        let c = Microstructure::new(nx, ny, 1e-6, labels).unwrap().connectivity(0);
        assert_eq!((c.clusters, c.percolates()), (nx * ny / 2, false));
    }

    #[test]
    fn synthetic_topologies_have_the_fraction_and_the_connectivity_they_are_made_for() {
        for seed in 0..3 {
            let a = voronoi_two_phase(128, 128, 1e-6, 40, 0.3, Topology::SoftMatrix, seed).unwrap();
            let b = voronoi_two_phase(128, 128, 1e-6, 40, 0.3, Topology::SoftPockets, seed).unwrap();
            for m in [&a, &b] {
                assert!((m.fraction(SOFT) - 0.3).abs() < 1.0 / (128.0 * 128.0));
            }
            let (sa, ha, sb, hb) = (a.connectivity(SOFT), a.connectivity(HARD), b.connectivity(SOFT), b.connectivity(HARD));
            // The box is not wrapped: a corner of the matrix may be cut off by the box edges.
            assert!(sa.percolates_x && sa.percolates_y && sa.largest_fraction > 0.95, "soft matrix: {sa:?}");
            assert!(!ha.percolates() && ha.clusters >= 30, "hard grains in a soft matrix: {ha:?}");
            // The skeleton spans the box both ways (some grains may be cut off by pockets or by
            // the box edges: its largest cluster holds 81–94 % of the hard phase over these seeds).
            assert!(hb.percolates_x && hb.percolates_y, "hard skeleton: {hb:?}");
            // At 30 % the pockets of neighbouring junctions merge (20 clusters of 40 grains with
            // seed 0) but none spans the box.
            assert!(!sb.percolates() && sb.clusters >= 10, "soft pockets: {sb:?}");
        }
        // Reproducible from the seed.
        assert_eq!(voronoi_two_phase(64, 48, 1e-6, 12, 0.25, Topology::SoftPockets, 7).unwrap(), voronoi_two_phase(64, 48, 1e-6, 12, 0.25, Topology::SoftPockets, 7).unwrap());
    }
}

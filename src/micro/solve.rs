//! One structure's realisations, built and solved: the microstructures of a `[[structure]]`
//! (synthetic realisations or an image), and for each the homogenisation, both virtual tests,
//! the hot spots, the bounds and the connectivity — what the tables, the maps and the summary are
//! made from.

use std::path::PathBuf;

use rayon::prelude::*;

use super::fields::{Local, PhaseHotSpots, Test, hot_spots, under_stress};
use super::homogenise::{Bounds, Periodic, Plane, bounds, element_lame, plane_lame};
use super::material::Phase;
use super::structure::{Connectivity, HARD, Microstructure, SOFT, voronoi_two_phase};
use super::study::StructureSpec;
use crate::error::{Error, Result};

/// A progressive-failure run of one realisation of a structure.
pub struct Cracked {
    /// Structure index.
    pub structure: usize,
    /// Realisation index.
    pub realisation: usize,
    /// The run.
    pub run: super::failure::Progressive,
}

/// Realisations needed for a Weibull fit of the first-failure stress.
pub const WEIBULL_MIN: usize = 5;

/// One structure ready to solve: its realisations' microstructures and phases.
pub struct Built {
    /// Phase table index of each label.
    pub phase_of_label: Vec<usize>,
    /// Realisations with their seeds (none for an image).
    pub realisations: Vec<(Microstructure, Option<u64>)>,
    /// The image read, if any.
    pub input: Option<PathBuf>,
}

/// Builds the microstructures of a structure. Realisation r of every synthetic structure uses
/// seed `seed + r`, so structures that differ only in topology share their grain seeds (a paired
/// comparison).
pub fn build(file: &str, key: &str, s: &StructureSpec, phases: &[Phase], seed: u64, resolve: &dyn Fn(&std::path::Path) -> PathBuf) -> Result<Built> {
    let index = |name: &str| phases.iter().position(|p| p.name == name).ok_or_else(|| Error::config(file, format!("{key}.phases"), format!("\"{name}\" is not in the phase table")));
    if let Some(g) = &s.synthetic {
        let mut phase_of_label = vec![0; 2];
        phase_of_label[HARD as usize] = index(&s.phases["hard"])?;
        phase_of_label[SOFT as usize] = index(&s.phases["soft"])?;
        let realisations = (0..s.realisations as u64)
            .into_par_iter()
            .map(|r| Ok((voronoi_two_phase(g.pixels[0], g.pixels[1], g.pixel_m, g.grains, g.soft_fraction, g.topology, seed.wrapping_add(r))?, Some(seed.wrapping_add(r)))))
            .collect::<Result<_>>()?;
        return Ok(Built { phase_of_label, realisations, input: None });
    }
    let Some(im) = &s.image else { return Err(Error::config(file, key, "give exactly one of `synthetic` and `image`")) };
    let path = resolve(&im.file);
    if !path.is_file() {
        return Err(Error::config(file, format!("{key}.image.file"), format!("{} does not exist", path.display())));
    }
    // A fault of the image names the image, and the study key and file that read it.
    let (m, names) = super::image::read_segmented(&path, im.pixel_m, &s.phases).map_err(|e| match e {
        Error::Data { file: f, location, rule } => Error::Data { file: f, location, rule: format!("{rule} (read as {key}.image of {file})") },
        other => other,
    })?;
    if m.nx > super::study::MAX_PIXELS || m.ny > super::study::MAX_PIXELS {
        return Err(Error::data_file(&path, "file", format!("the image is {} × {} pixels: at most {} a side (coarsen it)", m.nx, m.ny, super::study::MAX_PIXELS)));
    }
    let phase_of_label = names.iter().map(|n| index(n)).collect::<Result<_>>()?;
    Ok(Built { phase_of_label, realisations: vec![(m, None)], input: Some(path) })
}

/// One solved realisation.
pub struct Solved {
    /// The microstructure.
    pub micro: Microstructure,
    /// Its seed (synthetic).
    pub seed: Option<u64>,
    /// Effective stiffness (Pa).
    pub c: [[f64; 3]; 3],
    /// κ̄, μ̄ (Pa).
    pub bulk_shear: (f64, f64),
    /// E, ν from (κ̄, μ̄).
    pub youngs_poisson: (f64, f64),
    /// Area fraction of each label.
    pub fractions: Vec<f64>,
    /// Bounds at these fractions.
    pub bounds: Bounds,
    /// Connectivity of each label.
    pub connectivity: Vec<Connectivity>,
    /// The measures of each test ([`Test::BOTH`] order).
    pub locals: [Local; 2],
    /// The hot spots of each test and label.
    pub hot: [Vec<PhaseHotSpots>; 2],
}

impl Solved {
    /// Whether κ̄ and μ̄ lie within the HS bounds (relative round-off 10⁻⁹ allowed).
    pub fn within_hs(&self) -> bool {
        let (k, m) = self.bulk_shear;
        let (lo, hi) = (self.bounds.hs_lower, self.bounds.hs_upper);
        let tol = 1e-9;
        k >= lo.0 * (1.0 - tol) && k <= hi.0 * (1.0 + tol) && m >= lo.1 * (1.0 - tol) && m <= hi.1 * (1.0 + tol)
    }

    /// The smallest first-failure stress over the labels under test `t` (Pa).
    pub fn first_failure(&self, t: usize) -> f64 {
        self.hot[t].iter().map(|h| h.first_failure_pa).fold(f64::INFINITY, f64::min)
    }

    /// The cell's area fraction above strength under test `t`.
    pub fn above_strength(&self, t: usize) -> f64 {
        self.hot[t].iter().map(|h| h.above_strength).sum()
    }
}

/// Solves one realisation: homogenisation, both tests, hot spots, connectivity.
pub fn solve(periodic: &Periodic, m: Microstructure, seed: Option<u64>, phase_of_label: &[usize], phases: &[Phase], plane: Plane, s: f64) -> Result<Solved> {
    let elastic: Vec<_> = phase_of_label.iter().map(|&p| phases[p].elastic).collect();
    let strength: Vec<f64> = phase_of_label.iter().map(|&p| phases[p].tensile_strength_pa).collect();
    let lame = element_lame(&m, &elastic, plane)?;
    let eff = periodic.solve(&lame)?;
    let locals = [under_stress(&eff, &lame, plane, Test::Tension.stress(s))?, under_stress(&eff, &lame, plane, Test::Compression.stress(s))?];
    let hot = [hot_spots(&locals[0], &m.labels, &strength, s), hot_spots(&locals[1], &m.labels, &strength, s)];
    let fractions: Vec<f64> = (0..phase_of_label.len()).map(|l| m.fraction(l as u8)).collect();
    let per_label: Vec<(f64, f64)> = elastic.iter().map(|e| plane_lame(e, plane)).collect();
    let b = bounds(&fractions, &per_label);
    let connectivity = (0..phase_of_label.len()).map(|l| m.connectivity(l as u8)).collect();
    Ok(Solved { c: eff.c, bulk_shear: (eff.bulk, eff.shear), youngs_poisson: plane.youngs_and_poisson(eff.bulk, eff.shear), fractions, bounds: b, connectivity, locals, hot, micro: m, seed })
}

/// A per-structure quantity: name, unit, its value in a realisation.
pub type Quantity = (&'static str, &'static str, fn(&Solved) -> f64);

/// The per-structure quantities of `structure_summary.csv`.
pub fn quantities() -> Vec<Quantity> {
    vec![
        ("youngs_modulus", "Pa", |r| r.youngs_poisson.0),
        ("poisson_ratio", "-", |r| r.youngs_poisson.1),
        ("bulk_modulus_2d", "Pa", |r| r.bulk_shear.0),
        ("shear_modulus", "Pa", |r| r.bulk_shear.1),
        ("above_strength_tension", "-", |r| r.above_strength(0)),
        ("above_strength_compression", "-", |r| r.above_strength(1)),
        ("first_failure_tension", "Pa", |r| r.first_failure(0)),
        ("first_failure_compression", "Pa", |r| r.first_failure(1)),
    ]
}

/// A structure's Weibull fit of the first-failure stress under one test.
#[derive(Debug, Clone, PartialEq)]
pub struct FirstFailureWeibull {
    /// Structure index.
    pub structure: usize,
    /// Test index.
    pub test: usize,
    /// Realisations fitted.
    pub n: usize,
    /// MLE modulus m̂.
    pub shape: f64,
    /// Unbiased modulus.
    pub shape_unbiased: f64,
    /// 90 % pivotal bounds on m.
    pub shape_bounds: (f64, f64),
    /// MLE scale (Pa).
    pub scale: f64,
}


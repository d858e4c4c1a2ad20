//! The `kind = "microstructure"` study file.
//!
//! ```toml
//! kind = "microstructure"
//! seed = 20261125
//! plane = "strain"                   # "strain" or "stress" (micro::homogenise)
//! applied_stress_pa = 100e6          # s of the virtual tension and compression tests (Pa)
//!
//! [[phase]]                          # the phase table (micro::material): a built-in name …
//! name = "alumina"
//! [[phase]]                          # … with constants overridden (a source is then required)
//! name = "fused_silica"
//! tensile_strength_pa = 50e6
//! source = "…"
//!
//! [[structure]]                      # a synthetic microstructure, several realisations
//! name = "soft_matrix"               # key: file stems and tables
//! label = "Soft matrix (Gen 4-like)" # figures and summary
//! synthetic = { topology = "soft_matrix", pixels = [256, 256], pixel_m = 0.25e-6, grains = 64, soft_fraction = 0.3 }
//! phases = { hard = "alumina", soft = "fused_silica" }
//! realisations = 8
//!
//! [[structure]]                      # a segmented image (micro::image)
//! name = "bl1630_image"
//! label = "BL 16/30 (segmented image)"
//! image = { file = "../datasets/micro_bl1630_segmented.png", pixel_m = 0.1e-6 }
//! phases = { "#2ca02c" = "alumina", "#d62728" = "fused_silica" }
//!
//! [comparison]                       # optional: the deliverable's §6.1 question
//! continuous = "soft_matrix"         # the structure whose soft phase forms a continuous matrix
//! discontinuous = "soft_pockets"     # the one whose soft phase sits in isolated pockets
//!
//! [failure]                          # optional: progressive failure (micro::failure)
//! structures = ["soft_matrix", "soft_pockets"]   # default: all
//! realisations = 4                   # the first realisations of each
//! max_events = 300                   # cracked pixels at most
//! stop_fraction = 0.3                # stop when the load falls below this share of the peak
//! stiffness_fraction = 0.5           # … or the stiffness along the load below this share
//! residual = 1e-3                    # stiffness left in a cracked pixel
//!
//! [figures]
//! width_cm = 8.5
//! ```
//!
//! A structure names either `synthetic` (the Voronoi construction of
//! [`super::structure::voronoi_two_phase`], realisation r with its own seed) or `image`. Its
//! `phases` map names phases of the table: `hard` and `soft` for a synthetic structure, image
//! values for an image.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::homogenise::Plane;
use super::material::PhaseSpec;
use super::structure::Topology;
use crate::error::{Error, Result};
use crate::schema::FigureOptions;

/// Largest side of a pixel grid (memory: a 2048² grid needs about 4 GB for the factorisation).
pub const MAX_PIXELS: usize = 2048;

/// `synthetic = { … }` of a structure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SyntheticSpec {
    /// How the soft phase is arranged.
    pub topology: Topology,
    /// Pixels along x and y.
    pub pixels: [usize; 2],
    /// Pixel side (m).
    pub pixel_m: f64,
    /// Voronoi grains in the cell.
    pub grains: usize,
    /// Area fraction of the soft phase.
    pub soft_fraction: f64,
}

/// `image = { … }` of a structure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageSpec {
    /// The segmented PNG, relative to the study file.
    pub file: PathBuf,
    /// Pixel side (m).
    pub pixel_m: f64,
}

/// `[[structure]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureSpec {
    /// Key (letters, digits, `_`, `-`): file stems and table rows.
    pub name: String,
    /// Label in figures and the summary.
    pub label: String,
    /// A synthetic two-phase microstructure.
    pub synthetic: Option<SyntheticSpec>,
    /// A segmented image.
    pub image: Option<ImageSpec>,
    /// Structure value → phase name.
    pub phases: BTreeMap<String, String>,
    /// Realisations of a synthetic structure (an image has one).
    #[serde(default = "one")]
    pub realisations: usize,
}

fn one() -> usize {
    1
}

/// `[comparison]`: the deliverable's §6.1 question.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComparisonSpec {
    /// The structure whose soft phase forms a continuous matrix.
    pub continuous: String,
    /// The structure whose soft phase sits in isolated pockets.
    pub discontinuous: String,
}

fn plane() -> Plane {
    Plane::Strain
}

/// A `kind = "microstructure"` study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MicroStudy {
    /// `microstructure`.
    pub kind: String,
    /// Seed of the synthetic microstructures.
    pub seed: u64,
    /// Plane strain or plane stress.
    #[serde(default = "plane")]
    pub plane: Plane,
    /// Magnitude s of the virtual uniaxial tests (Pa).
    pub applied_stress_pa: f64,
    /// The phase table.
    pub phase: Vec<PhaseSpec>,
    /// The microstructures.
    pub structure: Vec<StructureSpec>,
    /// The §6.1 comparison.
    pub comparison: Option<ComparisonSpec>,
    /// Progressive failure.
    pub failure: Option<super::failure::FailureOptions>,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
}

fn is_key(s: &str) -> bool {
    !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

impl MicroStudy {
    /// Whether structure `name` gets a progressive-failure run.
    pub fn cracked(&self, name: &str) -> bool {
        self.failure.as_ref().is_some_and(|f| f.structures.is_empty() || f.structures.iter().any(|s| s == name))
    }

    /// Checks every option that needs no file; returns the resolved phase table.
    pub fn validate(&self, file: &str) -> Result<Vec<super::material::Phase>> {
        if !(self.applied_stress_pa.is_finite() && self.applied_stress_pa > 0.0 && self.applied_stress_pa <= 1e10) {
            return Err(Error::config(file, "applied_stress_pa", format!("must lie in (0, 1e10] Pa, got {}", self.applied_stress_pa)));
        }
        if self.phase.is_empty() {
            return Err(Error::config(file, "phase", "give at least two [[phase]] entries"));
        }
        let phases: Vec<super::material::Phase> = self.phase.iter().enumerate().map(|(i, p)| p.resolve(file, &format!("phase[{i}]"))).collect::<Result<_>>()?;
        for (i, p) in phases.iter().enumerate() {
            if phases[..i].iter().any(|q| q.name == p.name) {
                return Err(Error::config(file, format!("phase[{i}].name"), format!("\"{}\" is given twice", p.name)));
            }
        }
        if self.structure.is_empty() {
            return Err(Error::config(file, "structure", "give at least one [[structure]]"));
        }
        for (i, s) in self.structure.iter().enumerate() {
            let key = format!("structure[{i}]");
            if !is_key(&s.name) {
                return Err(Error::config(file, format!("{key}.name"), format!("must be letters, digits, _ or - (it names files), got \"{}\"", s.name)));
            }
            if self.structure[..i].iter().any(|o| o.name == s.name) {
                return Err(Error::config(file, format!("{key}.name"), format!("\"{}\" is given twice", s.name)));
            }
            if s.label.trim().is_empty() {
                return Err(Error::config(file, format!("{key}.label"), "must not be empty"));
            }
            for (k, v) in &s.phases {
                if !phases.iter().any(|p| &p.name == v) {
                    return Err(Error::config(file, format!("{key}.phases.\"{k}\""), format!("\"{v}\" is not in the phase table ({})", phases.iter().map(|p| p.name.as_str()).collect::<Vec<_>>().join(", "))));
                }
            }
            match (&s.synthetic, &s.image) {
                (Some(g), None) => {
                    let [nx, ny] = g.pixels;
                    if !((8..=MAX_PIXELS).contains(&nx) && (8..=MAX_PIXELS).contains(&ny)) {
                        return Err(Error::config(file, format!("{key}.synthetic.pixels"), format!("each side must lie in 8…{MAX_PIXELS}, got [{nx}, {ny}]")));
                    }
                    if !(g.pixel_m.is_finite() && g.pixel_m > 0.0) {
                        return Err(Error::config(file, format!("{key}.synthetic.pixel_m"), format!("the pixel size must be > 0 m, got {}", g.pixel_m)));
                    }
                    if !(g.soft_fraction > 0.0 && g.soft_fraction < 1.0) {
                        return Err(Error::config(file, format!("{key}.synthetic.soft_fraction"), format!("must lie in (0, 1), got {}", g.soft_fraction)));
                    }
                    if g.grains < 3 || g.grains * 16 > nx * ny {
                        return Err(Error::config(file, format!("{key}.synthetic.grains"), format!("must lie in 3…{} (at least 16 pixels a grain), got {}", nx * ny / 16, g.grains)));
                    }
                    let keys: Vec<&str> = s.phases.keys().map(String::as_str).collect();
                    if keys != ["hard", "soft"] {
                        return Err(Error::config(file, format!("{key}.phases"), format!("a synthetic structure maps exactly `hard` and `soft` to phases, got {}", if keys.is_empty() { "none".to_string() } else { keys.join(", ") })));
                    }
                    if s.phases["hard"] == s.phases["soft"] {
                        return Err(Error::config(file, format!("{key}.phases"), "`hard` and `soft` must be different phases"));
                    }
                    if !(1..=256).contains(&s.realisations) {
                        return Err(Error::config(file, format!("{key}.realisations"), format!("must lie in 1…256, got {}", s.realisations)));
                    }
                }
                (None, Some(im)) => {
                    if !(im.pixel_m.is_finite() && im.pixel_m > 0.0) {
                        return Err(Error::config(file, format!("{key}.image.pixel_m"), format!("the pixel size must be > 0 m, got {}", im.pixel_m)));
                    }
                    super::image::check_keys(file, &format!("{key}.phases"), &s.phases)?;
                    if s.phases.values().collect::<std::collections::BTreeSet<_>>().len() < 2 {
                        return Err(Error::config(file, format!("{key}.phases"), "map the image's values to at least two phases"));
                    }
                    if s.realisations != 1 {
                        return Err(Error::config(file, format!("{key}.realisations"), "an image is one realisation: leave realisations out"));
                    }
                }
                _ => return Err(Error::config(file, key, "give exactly one of `synthetic` and `image`")),
            }
        }
        if let Some(c) = &self.comparison {
            for (k, v) in [("continuous", &c.continuous), ("discontinuous", &c.discontinuous)] {
                if !self.structure.iter().any(|s| &s.name == v) {
                    return Err(Error::config(file, format!("comparison.{k}"), format!("\"{v}\" is not a structure of the study")));
                }
            }
            if c.continuous == c.discontinuous {
                return Err(Error::config(file, "comparison", "compares two different structures"));
            }
        }
        if let Some(f) = &self.failure {
            f.validate(file)?;
            for (i, name) in f.structures.iter().enumerate() {
                if !self.structure.iter().any(|s| &s.name == name) {
                    return Err(Error::config(file, format!("failure.structures[{i}]"), format!("\"{name}\" is not a structure of the study")));
                }
            }
            for st in self.structure.iter().filter(|s| self.cracked(&s.name)) {
                let name = &st.name;
                if f.realisations > st.realisations {
                    return Err(Error::config(file, "failure.realisations", format!("{} realisations asked, but `{name}` has {}", f.realisations, st.realisations)));
                }
            }
        }
        self.figures.validate(file)?;
        Ok(phases)
    }
}

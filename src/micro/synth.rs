//! The generator of the shipped segmented micrograph stand-in (`partlife datasets synth-micro`).
//!
//! The project's SEM images are not public, so `datasets/micro_bl1630_segmented.png` is
//! **synthetic**: a two-colour image in the style of the deliverable's Fig. 10c (green α-alumina,
//! red fused silica) made by this rule from `datasets/synth_micro.toml`:
//!
//! 1. the Voronoi construction of [`super::structure::voronoi_two_phase`] with the settings'
//!    topology, size, grains, soft fraction and seed;
//! 2. segmentation noise: each pixel's label flipped with probability `noise` (a ChaCha8 stream
//!    seeded with `seed + 1`), then one pass of a 3 × 3 majority filter (the label of at least
//!    five of the nine pixels around and including each, periodic), which leaves ragged boundaries and small islands as a trained
//!    classifier does;
//! 3. written as an 8-bit RGB PNG ([`super::image::write_png`]), top row = highest row.
//!
//! The soft fraction of the result differs from the setting by the noise; the study measures it.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::structure::{Microstructure, Topology, voronoi_two_phase};
use crate::error::{Error, Result};

/// `datasets/synth_micro.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MicroSettings {
    /// Output file name, in the settings' directory.
    pub file: String,
    /// Seed of the Voronoi seeds; the noise uses seed + 1.
    pub seed: u64,
    /// Pixels along x and y.
    pub pixels: [usize; 2],
    /// Voronoi grains.
    pub grains: usize,
    /// Soft (fused silica) area fraction before the noise.
    pub soft_fraction: f64,
    /// Arrangement of the soft phase.
    pub topology: Topology,
    /// Probability that a pixel's label is flipped before the majority filter.
    pub noise: f64,
    /// Colours of the hard and the soft phase, `#rrggbb`.
    pub colours: [String; 2],
}

fn rgb(file: &str, key: &str, c: &str) -> Result<[u8; 3]> {
    let hex = c.strip_prefix('#').filter(|h| h.len() == 6 && h.chars().all(|x| x.is_ascii_hexdigit())).ok_or_else(|| Error::config(file, key, format!("\"{c}\" is not a colour #rrggbb")))?;
    let b = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).unwrap_or(0);
    Ok([b(0), b(2), b(4)])
}

/// One majority-filter pass over periodic 3 × 3 neighbourhoods of a two-label grid (labels 0, 1).
fn majority(m: &Microstructure) -> Vec<u8> {
    let (nx, ny) = (m.nx, m.ny);
    (0..nx * ny)
        .map(|p| {
            let (i, j) = (p % nx, p / nx);
            let mut ones = 0;
            for dj in [ny - 1, 0, 1] {
                for di in [nx - 1, 0, 1] {
                    ones += usize::from(m.labels[((j + dj) % ny) * nx + (i + di) % nx] == 1);
                }
            }
            u8::from(ones >= 5)
        })
        .collect()
}

/// The microstructure and PNG bytes of the settings (`file` names the settings in messages).
pub fn generate(file: &str, s: &MicroSettings) -> Result<(Microstructure, Vec<u8>)> {
    if !(0.0..0.5).contains(&s.noise) {
        return Err(Error::config(file, "noise", format!("must lie in [0, 0.5), got {}", s.noise)));
    }
    let colours = [rgb(file, "colours[0]", &s.colours[0])?, rgb(file, "colours[1]", &s.colours[1])?];
    let mut m = voronoi_two_phase(s.pixels[0], s.pixels[1], 1.0, s.grains, s.soft_fraction, s.topology, s.seed)?;
    let mut rng = ChaCha8Rng::seed_from_u64(s.seed.wrapping_add(1));
    for l in m.labels.iter_mut() {
        if rng.random::<f64>() < s.noise {
            *l = 1 - *l;
        }
    }
    m.labels = majority(&m);
    let png = super::image::write_png(&m, &colours)?;
    Ok((m, png))
}

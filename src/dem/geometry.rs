//! Geometry of the DEM domain: a slab periodic along the tube axis (y), bounded in x by planes
//! (side walls) and open or closed in z, with horizontal tubes as exact cylinders along y.
//!
//! Coordinates: x across the bank (0 … width), y along the tubes (periodic, 0 … slab), z up.
//! Tube rows are numbered 1, 2, … from the top (particles meet row 1 first).

use super::vec3::{V3, dot};
use crate::error::{Error, Result};

/// An infinite plane wall; particles live on the side its normal points to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// A point on the plane.
    pub point: V3,
    /// Unit normal pointing into the domain.
    pub normal: V3,
}

impl Plane {
    /// Signed distance of x from the plane (positive inside).
    #[inline(always)]
    pub fn distance(&self, x: V3) -> f64 {
        dot([x[0] - self.point[0], x[1] - self.point[1], x[2] - self.point[2]], self.normal)
    }
}

/// A horizontal tube along y: an exact cylinder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tube {
    /// Axis position x (m).
    pub x: f64,
    /// Axis position z (m).
    pub z: f64,
    /// Radius (m).
    pub radius: f64,
    /// Row, 1 = top.
    pub row: u32,
}

/// Tube arrangement of a bank.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Arrangement {
    /// Every other row shifted by half the horizontal pitch.
    Staggered,
    /// Rows aligned.
    Inline,
}

/// Parameters of a tube bank (the cold-test rig by default).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct BankSpec {
    /// Width between the side walls (m).
    pub width: f64,
    /// Slab thickness along the tube axis (periodic) (m).
    pub slab: f64,
    /// Tube outer diameter (m).
    pub tube_diameter: f64,
    /// Number of rows.
    pub rows: u32,
    /// Horizontal pitch between tube axes in a row (m).
    pub horizontal_pitch: f64,
    /// Vertical pitch between rows (m).
    pub vertical_pitch: f64,
    /// Staggered or inline.
    pub arrangement: Arrangement,
    /// Horizontal offset of the first tube axis of row 1 from the left wall (m).
    pub first_tube_x: f64,
    /// Free height between the top of row 1 and the top of the domain (m); the inlet region
    /// sits at the top of it.
    pub height_above: f64,
    /// Free height between the bottom of the last row and the outlet (m).
    pub height_below: f64,
}

impl BankSpec {
    /// The cold-test default: Ø 25 mm tubes, 5 staggered rows of two and a half tubes in a
    /// 125 mm wide, 5 mm thick slab (pitch 50 mm both ways).
    pub fn cold_test() -> Self {
        BankSpec {
            width: 0.125,
            slab: 0.005,
            tube_diameter: 0.025,
            rows: 5,
            horizontal_pitch: 0.05,
            vertical_pitch: 0.05,
            arrangement: Arrangement::Staggered,
            first_tube_x: 0.025,
            height_above: 0.04,
            height_below: 0.03,
        }
    }
}

/// The domain.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    /// Lower x bound of the domain (m).
    pub x_lo: f64,
    /// Upper x bound (m).
    pub x_hi: f64,
    /// Lower z bound of the neighbour grid (m).
    pub z_lo: f64,
    /// Upper z bound (m).
    pub z_hi: f64,
    /// Period along y (m).
    pub slab: f64,
    /// Plane walls.
    pub planes: Vec<Plane>,
    /// Tubes.
    pub tubes: Vec<Tube>,
    /// Particles whose centre falls below this height leave through the outlet.
    pub outlet_z: Option<f64>,
    /// Row centres z (m), row 1 first; empty without a bank.
    pub row_z: Vec<f64>,
}

impl Geometry {
    /// A box of side walls at x_lo, x_hi and a floor at z_lo (closed), periodic in y.
    pub fn closed_box(x_lo: f64, x_hi: f64, z_lo: f64, z_hi: f64, slab: f64) -> Self {
        Geometry {
            x_lo,
            x_hi,
            z_lo,
            z_hi,
            slab,
            planes: vec![
                Plane { point: [x_lo, 0.0, 0.0], normal: [1.0, 0.0, 0.0] },
                Plane { point: [x_hi, 0.0, 0.0], normal: [-1.0, 0.0, 0.0] },
                Plane { point: [0.0, 0.0, z_lo], normal: [0.0, 0.0, 1.0] },
            ],
            tubes: Vec::new(),
            outlet_z: None,
            row_z: Vec::new(),
        }
    }

    /// A tube bank between side walls with an open outlet at z = 0.
    pub fn tube_bank(b: &BankSpec) -> Self {
        let r = b.tube_diameter / 2.0;
        let mut tubes = Vec::new();
        let mut row_z = Vec::new();
        let bottom = b.height_below + r;
        for k in 0..b.rows {
            let z = bottom + (b.rows - 1 - k) as f64 * b.vertical_pitch;
            row_z.push(z);
            let shift = match b.arrangement {
                Arrangement::Staggered if k % 2 == 1 => b.horizontal_pitch / 2.0,
                _ => 0.0,
            };
            // Axes from the first position, wrapped back to the left wall so that tubes cut by a
            // wall (half tubes) are kept.
            let mut x = b.first_tube_x + shift;
            while x - b.horizontal_pitch >= -1e-12 {
                x -= b.horizontal_pitch;
            }
            while x <= b.width + 1e-12 {
                tubes.push(Tube { x, z, radius: r, row: k + 1 });
                x += b.horizontal_pitch;
            }
        }
        let z_top = row_z.first().copied().unwrap_or(bottom) + r + b.height_above;
        Geometry {
            x_lo: 0.0,
            x_hi: b.width,
            z_lo: 0.0,
            z_hi: z_top,
            slab: b.slab,
            planes: vec![
                Plane { point: [0.0, 0.0, 0.0], normal: [1.0, 0.0, 0.0] },
                Plane { point: [b.width, 0.0, 0.0], normal: [-1.0, 0.0, 0.0] },
            ],
            tubes,
            outlet_z: Some(0.0),
            row_z,
        }
    }

    /// Row band of a height: 0 above the bank, 1…rows within (±half the row spacing around the
    /// row axis), rows + 1 below; 0 when there is no bank.
    pub fn row_of(&self, z: f64) -> u32 {
        let n = self.row_z.len();
        if n == 0 {
            return 0;
        }
        let half = if n > 1 { (self.row_z[0] - self.row_z[1]).abs() / 2.0 } else { self.tubes[0].radius * 2.0 };
        if z > self.row_z[0] + half {
            return 0;
        }
        for (k, &zc) in self.row_z.iter().enumerate() {
            if z >= zc - half {
                return k as u32 + 1;
            }
        }
        n as u32 + 1
    }

    /// Wall count: planes then tubes share one id space (`planes.len() + tube index`).
    pub fn wall_count(&self) -> usize {
        self.planes.len() + self.tubes.len()
    }

    /// Checks the geometry against the largest particle diameter and the neighbour skin.
    pub fn validate(&self, file: &str, d_max: f64, skin: f64) -> Result<()> {
        let cfg = |key: &str, rule: String| Err(Error::config(file, key, rule));
        if !(self.x_hi > self.x_lo && self.z_hi > self.z_lo) {
            return cfg("geometry", format!("empty domain x [{}, {}], z [{}, {}] m", self.x_lo, self.x_hi, self.z_lo, self.z_hi));
        }
        if self.slab.is_nan() || self.slab <= d_max {
            return cfg(
                "geometry.slab",
                format!("slab thickness {} m is thinner than the largest particle ({} m)", self.slab, d_max),
            );
        }
        if self.slab < 2.0 * (d_max + skin) {
            return cfg(
                "geometry.slab",
                format!(
                    "slab thickness {} m must be at least 2 × (largest diameter + skin) = {:.4e} m so that a particle meets each periodic neighbour once",
                    self.slab,
                    2.0 * (d_max + skin)
                ),
            );
        }
        for (i, a) in self.tubes.iter().enumerate() {
            if a.radius.is_nan() || a.radius <= 0.0 {
                return cfg("geometry.tube_diameter", format!("tube {i} has radius {} m; must be > 0", a.radius));
            }
            for (j, b) in self.tubes.iter().enumerate().skip(i + 1) {
                let d = ((a.x - b.x).powi(2) + (a.z - b.z).powi(2)).sqrt();
                if d < a.radius + b.radius {
                    return cfg(
                        "geometry",
                        format!(
                            "tubes {i} (row {}, x = {:.4} m) and {j} (row {}, x = {:.4} m) overlap: axes {:.4} m apart, diameters need {:.4} m; increase the pitches or reduce the tube diameter",
                            a.row,
                            a.x,
                            b.row,
                            b.x,
                            d,
                            a.radius + b.radius
                        ),
                    );
                }
            }
        }
        Ok(())
    }
}

impl BankSpec {
    /// Checks the numbers of the bank.
    pub fn validate(&self, file: &str) -> Result<()> {
        // Lengths of a particle heat exchanger: a few mm to metres; 100 m bounds any plant.
        let pos = |key: &str, v: f64| -> Result<()> {
            if v > 0.0 && v <= 100.0 { Ok(()) } else { Err(Error::config(file, format!("geometry.{key}"), format!("must lie in (0, 100] m, got {v}"))) }
        };
        pos("width", self.width)?;
        pos("slab", self.slab)?;
        pos("tube_diameter", self.tube_diameter)?;
        pos("horizontal_pitch", self.horizontal_pitch)?;
        pos("vertical_pitch", self.vertical_pitch)?;
        pos("height_above", self.height_above)?;
        pos("height_below", self.height_below)?;
        // The tubes of a row are laid out one by one: bound their number before the layout.
        if self.width / self.horizontal_pitch > 10_000.0 {
            return Err(Error::config(file, "geometry.horizontal_pitch", format!("{} m across a width of {} m makes more than 10 000 tubes per row", self.horizontal_pitch, self.width)));
        }
        if self.rows == 0 || self.rows > 100 {
            return Err(Error::config(file, "geometry.rows", format!("must be 1–100, got {}", self.rows)));
        }
        if !(self.first_tube_x >= 0.0 && self.first_tube_x <= self.width) {
            return Err(Error::config(
                file,
                "geometry.first_tube_x",
                format!("must lie within the width [0, {}] m, got {}", self.width, self.first_tube_x),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cold_test_has_two_and_a_half_tubes_per_row() {
        let g = Geometry::tube_bank(&BankSpec::cold_test());
        assert_eq!(g.row_z.len(), 5);
        for row in 1..=5 {
            let xs: Vec<f64> = g.tubes.iter().filter(|t| t.row == row).map(|t| t.x).collect();
            // Full tubes inside, half tubes on a wall: 2 full + 1 half in every row.
            let full = xs.iter().filter(|&&x| x > 1e-9 && x < 0.125 - 1e-9).count();
            let half = xs.len() - full;
            assert_eq!((full, half), (2, 1), "row {row}: {xs:?}");
        }
        assert!(g.validate("t", 1.2e-3, 0.3e-3).is_ok());
        assert_eq!(g.row_of(g.row_z[2]), 3);
        assert_eq!(g.row_of(g.z_hi), 0);
        assert_eq!(g.row_of(0.001), 6);
    }
}

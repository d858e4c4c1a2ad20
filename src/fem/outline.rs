//! Irregular particle outlines for plane-strain crush runs (deliverable Fig. 9a): a closed
//! star-shaped polygon given by the user, or a random one of given roughness.
//!
//! Random outline: `ρ(θ) = 1 + Σ_{k=2..K} (a_k cos kθ + b_k sin kθ)` with `a_k, b_k ~ N(0, s²/k)`,
//! s chosen so that the RMS of `ρ − 1` over θ equals `roughness` exactly (Parseval:
//! RMS² = ½ Σ (a_k² + b_k²)); sampled at 360 vertices, seeded (ChaCha8). Modes from k = 2 leave
//! the centroid in place to first order. Every outline is centred on its area centroid and
//! scaled to the height `diameter` along the load.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// An outline of a plane-strain particle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Outline {
    /// A closed polygon (m), vertices in order, star-shaped about its centroid.
    Polygon {
        /// Vertices (x, z).
        points: Vec<[f64; 2]>,
    },
    /// A random star-shaped outline.
    Random {
        /// RMS relative radius deviation, in (0, 0.2].
        roughness: f64,
        /// Highest Fourier mode K (default 12).
        #[serde(default = "default_modes")]
        modes: u32,
        /// Seed of the draw.
        seed: u64,
    },
}

fn default_modes() -> u32 {
    12
}

/// A star-shaped polygon centred on its centroid, with its radius function.
#[derive(Debug, Clone, PartialEq)]
pub struct StarPolygon {
    /// Vertices (m), centroid at the origin.
    pub points: Vec<[f64; 2]>,
}

fn centroid(p: &[[f64; 2]]) -> ([f64; 2], f64) {
    let (mut a, mut cx, mut cz) = (0.0, 0.0, 0.0);
    for i in 0..p.len() {
        let (x0, z0) = (p[i][0], p[i][1]);
        let (x1, z1) = (p[(i + 1) % p.len()][0], p[(i + 1) % p.len()][1]);
        let c = x0 * z1 - x1 * z0;
        a += c;
        cx += (x0 + x1) * c;
        cz += (z0 + z1) * c;
    }
    let a = 0.5 * a;
    ([cx / (6.0 * a), cz / (6.0 * a)], a)
}

impl Outline {
    /// The polygon of height `diameter`, centred and checked; `key` names it in errors.
    pub fn polygon(&self, diameter: f64, file: &str, key: &str) -> Result<StarPolygon> {
        let raw: Vec<[f64; 2]> = match self {
            Outline::Polygon { points } => {
                if points.len() < 3 || points.iter().any(|p| !(p[0].is_finite() && p[1].is_finite())) {
                    return Err(Error::config(file, format!("{key}.points"), "needs at least 3 finite (x, z) vertices"));
                }
                points.clone()
            }
            Outline::Random { roughness, modes, seed } => {
                if !(*roughness > 0.0 && *roughness <= 0.2) {
                    return Err(Error::config(file, format!("{key}.roughness"), format!("must lie in (0, 0.2], got {roughness}")));
                }
                if !(2..=60).contains(modes) {
                    return Err(Error::config(file, format!("{key}.modes"), format!("must lie in [2, 60], got {modes}")));
                }
                let mut rng = ChaCha8Rng::seed_from_u64(*seed);
                let coef: Vec<(f64, f64)> = (2..=*modes)
                    .map(|k| {
                        let s = 1.0 / (k as f64).sqrt();
                        let a: f64 = StandardNormal.sample(&mut rng);
                        let b: f64 = StandardNormal.sample(&mut rng);
                        (s * a, s * b)
                    })
                    .collect();
                let rms = (0.5 * coef.iter().map(|(a, b)| a * a + b * b).sum::<f64>()).sqrt();
                let scale = roughness / rms;
                (0..360)
                    .map(|i| {
                        let t = std::f64::consts::TAU * i as f64 / 360.0;
                        let d: f64 = coef.iter().enumerate().map(|(j, (a, b))| {
                            let k = (j + 2) as f64;
                            a * (k * t).cos() + b * (k * t).sin()
                        }).sum();
                        let r = 1.0 + scale * d;
                        [r * t.sin(), r * t.cos()]
                    })
                    .collect()
            }
        };
        let (c, area) = centroid(&raw);
        let mut pts: Vec<[f64; 2]> = raw.iter().map(|p| [p[0] - c[0], p[1] - c[1]]).collect();
        if area < 0.0 {
            pts.reverse();
        }
        // Star-shaped about the centroid: the polar angle turns monotonically once around.
        let ang: Vec<f64> = pts.iter().map(|p| p[0].atan2(p[1])).collect();
        let mut turn = 0.0;
        for i in 0..ang.len() {
            let mut d = ang[(i + 1) % ang.len()] - ang[i];
            d = (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
            if d >= 0.0 {
                // Counter-clockwise in (x, z) runs towards −θ (θ from +z towards +x).
                return Err(Error::config(file, key, format!("the outline is not star-shaped about its centroid (vertex {i} turns back)")));
            }
            turn += d;
        }
        if (turn + std::f64::consts::TAU).abs() > 1e-6 {
            return Err(Error::config(file, key, "the outline does not wind once around its centroid"));
        }
        let (lo, hi) = pts.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(p[1]), hi.max(p[1])));
        let s = diameter / (hi - lo);
        Ok(StarPolygon { points: pts.iter().map(|p| [s * p[0], s * p[1]]).collect() })
    }
}

impl StarPolygon {
    /// Distance from the centroid to the outline along θ (rad from +z towards +x) (m).
    pub fn radius(&self, theta: f64) -> f64 {
        let (ux, uz) = theta.sin_cos();
        let n = self.points.len();
        let mut best = f64::MAX;
        for i in 0..n {
            let (a, b) = (self.points[i], self.points[(i + 1) % n]);
            // Solve t u = a + s (b − a), t > 0, s ∈ [0, 1].
            let (ex, ez) = (b[0] - a[0], b[1] - a[1]);
            let det = ux * (-ez) - uz * (-ex);
            if det.abs() < 1e-300 {
                continue;
            }
            let t = (a[0] * (-ez) - a[1] * (-ex)) / det;
            let s = (ux * a[1] - uz * a[0]) / det;
            if t > 0.0 && (-1e-12..=1.0 + 1e-12).contains(&s) {
                best = best.min(t);
            }
        }
        best
    }

    /// Directions (rad from +z) of the highest and the lowest vertex: the contact points.
    pub fn poles(&self) -> (f64, f64) {
        let top = self.points.iter().cloned().fold([0.0, f64::MIN], |m, p| if p[1] > m[1] { p } else { m });
        let bot = self.points.iter().cloned().fold([0.0, f64::MAX], |m, p| if p[1] < m[1] { p } else { m });
        (top[0].atan2(top[1]), bot[0].atan2(bot[1]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_outline_has_the_requested_roughness_and_height() {
        let o = Outline::Random { roughness: 0.08, modes: 12, seed: 7 };
        let p = o.polygon(1e-3, "t", "outline").unwrap();
        let (lo, hi) = p.points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), q| (lo.min(q[1]), hi.max(q[1])));
        assert!((hi - lo - 1e-3).abs() < 1e-15);
        let r: Vec<f64> = p.points.iter().map(|q| (q[0] * q[0] + q[1] * q[1]).sqrt()).collect();
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        let rms = (r.iter().map(|x| (x / mean - 1.0).powi(2)).sum::<f64>() / r.len() as f64).sqrt();
        assert!((rms - 0.08).abs() < 0.01, "rms {rms}");
        // The radius function meets the vertices.
        for q in p.points.iter().step_by(37) {
            let th = q[0].atan2(q[1]);
            assert!((p.radius(th) - (q[0] * q[0] + q[1] * q[1]).sqrt()).abs() < 1e-12);
        }
        // Same seed, same outline.
        assert_eq!(p, o.polygon(1e-3, "t", "outline").unwrap());
    }

    #[test]
    fn a_non_star_polygon_is_refused() {
        // A "C" shape: not star-shaped about its centroid.
        let pts = vec![[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [1.0, 1.0], [1.0, 2.0], [3.0, 2.0], [3.0, 3.0], [0.0, 3.0]];
        let e = Outline::Polygon { points: pts }.polygon(1e-3, "s.toml", "case[0].outline").unwrap_err().to_string();
        assert!(e.contains("star-shaped") || e.contains("wind"), "{e}");
    }
}

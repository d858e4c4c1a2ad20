//! Space-filling designs on the unit cube: Sobol' sequences and Latin hypercubes.
//!
//! * [`Sobol`]: the unscrambled Sobol' low-discrepancy sequence in Gray-code order (Antonov &
//!   Saleev 1979), with the Joe & Kuo (2008) direction numbers (`new-joe-kuo-6.21201`, first 64
//!   dimensions), 32-bit resolution. Direction numbers `V_k = m_k 2^(32−k)` for k ≤ s, then
//!   `V_k = V_{k−s} ⊕ (V_{k−s} ≫ s) ⊕ ⊕_{i=1}^{s−1} a_i V_{k−i}`; point n is point n−1 with
//!   `V_c` xored in, c the position of the lowest zero bit of n−1. The first point is the origin.
//! * [`latin_hypercube`]: n points, each coordinate's n strata used once, uniform inside the
//!   stratum, seeded (ChaCha8).
//!
//! Verified by the unit tests below and `tests/design.rs` (the first 32 points in 64 dimensions
//! against `tests/reference/sobol_joe_kuo_64d_32.csv`, generated with SciPy's unscrambled Sobol'
//! engine, which uses the same Joe–Kuo numbers).

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};

/// Joe & Kuo (2008) `new-joe-kuo-6.21201` primitive polynomials (bit pattern, leading and
/// trailing 1 included) and initial direction numbers m₁…m_s, for the first 64 dimensions.
/// Dimension 1 (polynomial 1) is the van der Corput sequence.
const JOE_KUO: [(u32, &[u32]); 64] = [
    (1, &[1]),
    (3, &[1]),
    (7, &[1, 3]),
    (11, &[1, 3, 1]),
    (13, &[1, 1, 1]),
    (19, &[1, 1, 3, 3]),
    (25, &[1, 3, 5, 13]),
    (37, &[1, 1, 5, 5, 17]),
    (41, &[1, 1, 5, 5, 5]),
    (47, &[1, 1, 7, 11, 19]),
    (55, &[1, 1, 5, 1, 1]),
    (59, &[1, 1, 1, 3, 11]),
    (61, &[1, 3, 5, 5, 31]),
    (67, &[1, 3, 3, 9, 7, 49]),
    (91, &[1, 1, 1, 15, 21, 21]),
    (97, &[1, 3, 1, 13, 27, 49]),
    (103, &[1, 1, 1, 15, 7, 5]),
    (109, &[1, 3, 1, 15, 13, 25]),
    (115, &[1, 1, 5, 5, 19, 61]),
    (131, &[1, 3, 7, 11, 23, 15, 103]),
    (137, &[1, 3, 7, 13, 13, 15, 69]),
    (143, &[1, 1, 3, 13, 7, 35, 63]),
    (145, &[1, 3, 5, 9, 1, 25, 53]),
    (157, &[1, 3, 1, 13, 9, 35, 107]),
    (167, &[1, 3, 1, 5, 27, 61, 31]),
    (171, &[1, 1, 5, 11, 19, 41, 61]),
    (185, &[1, 3, 5, 3, 3, 13, 69]),
    (191, &[1, 1, 7, 13, 1, 19, 1]),
    (193, &[1, 3, 7, 5, 13, 19, 59]),
    (203, &[1, 1, 3, 9, 25, 29, 41]),
    (211, &[1, 3, 5, 13, 23, 1, 55]),
    (213, &[1, 3, 7, 3, 13, 59, 17]),
    (229, &[1, 3, 1, 3, 5, 53, 69]),
    (239, &[1, 1, 5, 5, 23, 33, 13]),
    (241, &[1, 1, 7, 7, 1, 61, 123]),
    (247, &[1, 1, 7, 9, 13, 61, 49]),
    (253, &[1, 3, 3, 5, 3, 55, 33]),
    (285, &[1, 3, 1, 15, 31, 13, 49, 245]),
    (299, &[1, 3, 5, 15, 31, 59, 63, 97]),
    (301, &[1, 3, 1, 11, 11, 11, 77, 249]),
    (333, &[1, 3, 1, 11, 27, 43, 71, 9]),
    (351, &[1, 1, 7, 15, 21, 11, 81, 45]),
    (355, &[1, 3, 7, 3, 25, 31, 65, 79]),
    (357, &[1, 3, 1, 1, 19, 11, 3, 205]),
    (361, &[1, 1, 5, 9, 19, 21, 29, 157]),
    (369, &[1, 3, 7, 11, 1, 33, 89, 185]),
    (391, &[1, 3, 3, 3, 15, 9, 79, 71]),
    (397, &[1, 3, 7, 11, 15, 39, 119, 27]),
    (425, &[1, 1, 3, 1, 11, 31, 97, 225]),
    (451, &[1, 1, 1, 3, 23, 43, 57, 177]),
    (463, &[1, 3, 7, 7, 17, 17, 37, 71]),
    (487, &[1, 3, 1, 5, 27, 63, 123, 213]),
    (501, &[1, 1, 3, 5, 11, 43, 53, 133]),
    (529, &[1, 3, 5, 5, 29, 17, 47, 173, 479]),
    (539, &[1, 3, 3, 11, 3, 1, 109, 9, 69]),
    (545, &[1, 1, 1, 5, 17, 39, 23, 5, 343]),
    (557, &[1, 3, 1, 5, 25, 15, 31, 103, 499]),
    (563, &[1, 1, 1, 11, 11, 17, 63, 105, 183]),
    (601, &[1, 1, 5, 11, 9, 29, 97, 231, 363]),
    (607, &[1, 1, 5, 15, 19, 45, 41, 7, 383]),
    (617, &[1, 3, 7, 7, 31, 19, 83, 137, 221]),
    (623, &[1, 1, 1, 3, 23, 15, 111, 223, 83]),
    (631, &[1, 1, 5, 13, 31, 15, 55, 25, 161]),
    (637, &[1, 1, 3, 13, 25, 47, 39, 87, 257]),
];

/// Largest dimension of [`Sobol`].
pub const SOBOL_MAX_DIM: usize = JOE_KUO.len();

/// Bits of resolution (points up to 2³² − 1).
const BITS: usize = 32;

/// The Sobol' sequence generator.
#[derive(Debug, Clone)]
pub struct Sobol {
    v: Vec<[u32; BITS]>,
    x: Vec<u32>,
    n: u64,
}

impl Sobol {
    /// A generator in `dim` dimensions (1 ≤ dim ≤ 64).
    pub fn new(dim: usize) -> Result<Self> {
        if dim == 0 || dim > SOBOL_MAX_DIM {
            return Err(Error::config("<design>", "dimensions", format!("Sobol' needs 1 to {SOBOL_MAX_DIM} dimensions, got {dim}")));
        }
        let v = JOE_KUO[..dim]
            .iter()
            .map(|&(poly, m)| {
                let mut v = [0u32; BITS];
                let s = (32 - poly.leading_zeros() - 1) as usize;
                if s == 0 {
                    for (k, vk) in v.iter_mut().enumerate() {
                        *vk = 1u32 << (BITS - 1 - k);
                    }
                    return v;
                }
                let a = (poly >> 1) & ((1u32 << (s - 1)) - 1);
                for k in 0..s.min(BITS) {
                    v[k] = m[k] << (BITS - 1 - k);
                }
                for k in s..BITS {
                    let mut x = v[k - s] ^ (v[k - s] >> s);
                    for i in 1..s {
                        if (a >> (s - 1 - i)) & 1 == 1 {
                            x ^= v[k - i];
                        }
                    }
                    v[k] = x;
                }
                v
            })
            .collect();
        Ok(Sobol { v, x: vec![0; dim], n: 0 })
    }

    /// The next point (the first is the origin).
    pub fn next_point(&mut self) -> Vec<f64> {
        if self.n > 0 {
            let c = (!(self.n - 1)).trailing_zeros() as usize;
            for (x, v) in self.x.iter_mut().zip(&self.v) {
                *x ^= v[c.min(BITS - 1)];
            }
        }
        self.n += 1;
        self.x.iter().map(|&x| x as f64 / 4_294_967_296.0).collect()
    }

    /// `n` points after skipping the first `skip`.
    pub fn points(dim: usize, n: usize, skip: usize) -> Result<Vec<Vec<f64>>> {
        let mut s = Sobol::new(dim)?;
        for _ in 0..skip {
            s.next_point();
        }
        Ok((0..n).map(|_| s.next_point()).collect())
    }
}

/// `n` Sobol' points in `dim` dimensions shifted modulo 1 by one uniform random vector drawn
/// from stream `stream` of ChaCha8(`seed`) (a randomised quasi-Monte Carlo set: unbiased, and
/// independent between streams).
pub fn shifted_sobol(dim: usize, n: usize, seed: u64, stream: u64) -> Result<Vec<Vec<f64>>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    let shift: Vec<f64> = (0..dim).map(|_| rng.random::<f64>()).collect();
    Ok(Sobol::points(dim, n, 1)?.into_iter().map(|p| p.iter().zip(&shift).map(|(x, s)| (x + s).fract()).collect()).collect())
}

/// A Latin hypercube of `n` points in `dim` dimensions, seeded.
pub fn latin_hypercube(n: usize, dim: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut columns = Vec::with_capacity(dim);
    let mut perm: Vec<usize> = (0..n).collect();
    for _ in 0..dim {
        perm.shuffle(&mut rng);
        columns.push(perm.iter().map(|&p| (p as f64 + rng.random::<f64>()) / n as f64).collect::<Vec<f64>>());
    }
    (0..n).map(|i| columns.iter().map(|c| c[i]).collect()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sobol_first_points_and_strata() {
        let p = Sobol::points(3, 8, 0).unwrap();
        assert_eq!(p[0], vec![0.0; 3]);
        assert_eq!(p[1], vec![0.5; 3]);
        assert_eq!(p[2], vec![0.75, 0.25, 0.25]);
        // A (0, m, 2) net: every 2^m block of a dyadic interval holds one point per dimension.
        let p = Sobol::points(10, 1024, 0).unwrap();
        for j in 0..10 {
            let mut seen = vec![false; 1024];
            for q in &p {
                seen[(q[j] * 1024.0) as usize] = true;
            }
            assert!(seen.iter().all(|&s| s), "dimension {j} misses a stratum");
        }
        assert!(Sobol::new(0).is_err() && Sobol::new(65).is_err());
    }

    #[test]
    fn latin_hypercube_uses_every_stratum_once() {
        let p = latin_hypercube(50, 4, 7);
        for j in 0..4 {
            let mut strata: Vec<usize> = p.iter().map(|q| (q[j] * 50.0) as usize).collect();
            strata.sort_unstable();
            assert_eq!(strata, (0..50).collect::<Vec<_>>());
        }
        assert_eq!(p, latin_hypercube(50, 4, 7));
        assert_ne!(p, latin_hypercube(50, 4, 8));
    }
}

//! Small statistics shared by the data tools and the runner: median, Pearson correlation with
//! its two-sided p-value (t = r √((n − 2)/(1 − r²)), Student t with n − 2 degrees of freedom),
//! straight-line least squares with the slope's standard error (nalgebra SVD), and the crate's one
//! sample quantile, one linear interpolation ([`locate`] + [`lerp`]) and its cubic Hermite sibling ([`hermite`]), one ranking ([`ranks`]) and one
//! categorical draw ([`Categorical`]).
//!
//! Verified by the unit tests below (exact line; the tabulated two-sided 5 % critical value
//! r = 0.279 at n = 50; a regression with known coefficients and standard error).

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, StudentsT};

use crate::error::{Error, Result};

/// Least-squares line y = intercept + slope·x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineFit {
    /// Intercept.
    pub intercept: f64,
    /// Slope.
    pub slope: f64,
    /// Standard error of the slope, s √[(XᵀX)⁻¹]₁₁ with s² = RSS/(n − 2).
    pub slope_se: f64,
    /// Pearson correlation of x and y.
    pub r: f64,
    /// Two-sided p-value of the slope (equal to that of r).
    pub p_value: f64,
}

/// Fits a straight line by least squares (SVD of the design matrix [1, x]).
pub fn fit_line(x: &[f64], y: &[f64]) -> Result<LineFit> {
    let n = x.len();
    if n < 3 || y.len() != n {
        return Err(Error::numerical("line fit", format!("needs ≥ 3 pairs of equal length (got {n}, {})", y.len())));
    }
    let design = DMatrix::from_fn(n, 2, |i, j| if j == 0 { 1.0 } else { x[i] });
    let obs = DVector::from_column_slice(y);
    let beta = design
        .clone()
        .svd(true, true)
        .solve(&obs, 1e-12)
        .map_err(|e| Error::numerical("line fit", e.to_string()))?;
    let resid = &obs - &design * &beta;
    let s2 = resid.norm_squared() / (n - 2) as f64;
    let xtx_inv = (design.transpose() * &design)
        .try_inverse()
        .ok_or_else(|| Error::numerical("line fit", "singular normal matrix"))?;
    let (r, p_value) = pearson(x, y);
    Ok(LineFit { intercept: beta[0], slope: beta[1], slope_se: (s2 * xtx_inv[(1, 1)]).sqrt(), r, p_value })
}

/// Upper tail P(X > x) of χ² with `df` degrees of freedom (NaN for df ≤ 0); statrs' survival
/// function, accurate where 1 − CDF would round to 0.
pub fn chi2_upper_tail(x: f64, df: f64) -> f64 {
    use statrs::distribution::{ChiSquared, ContinuousCDF};
    ChiSquared::new(df).map_or(f64::NAN, |c| c.sf(x.max(0.0)))
}

/// Two-sided p-value of a Pearson correlation r from n pairs (NaN for n < 3).
pub fn correlation_p_value(r: f64, n: usize) -> f64 {
    if n < 3 {
        return f64::NAN;
    }
    let dof = (n - 2) as f64;
    if r.abs() >= 1.0 {
        return 0.0;
    }
    let t = r * (dof / (1.0 - r * r)).sqrt();
    StudentsT::new(0.0, 1.0, dof).map(|d| 2.0 * d.sf(t.abs())).unwrap_or(f64::NAN)
}

/// Pearson correlation of two equally long samples and its two-sided p-value.
pub fn pearson(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx).powi(2);
        syy += (b - my).powi(2);
    }
    let r = sxy / (sxx * syy).sqrt();
    (r, correlation_p_value(r, x.len()))
}

/// Median of a slice (NaN when empty): [`sorted_quantile`] at p = 0.5, the mean of the two
/// middle values for even n.
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    sorted_quantile(&s, 0.5)
}

/// Mean and sample standard deviation (divisor n − 1; 0 for a single value) of `v`.
pub fn mean_and_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}

/// The quantile p ∈ [0, 1] of a sorted sample: partlife's one definition of a sample quantile,
/// Hyndman & Fan (1996) type 7 (linear interpolation between order statistics at
/// h = (n − 1)p; the default of R and NumPy, and the interpolation of ASTM C1239's tables).
/// Empty: NaN.
pub fn sorted_quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let i = h.floor() as usize;
    let j = (i + 1).min(sorted.len() - 1);
    sorted[i] + (h - i as f64) * (sorted[j] - sorted[i])
}

/// Where `x` falls on an ascending grid `xs` (at least 2 points): the segment
/// `[xs[j − 1], xs[j]]` (1 ≤ j < n) and the fraction t along it. The one linear interpolation of
/// the crate, with [`lerp`]: every table and curve lookup (FE and measured force–displacement
/// curves, the curve-discrepancy tables, the Tavares–King critical ratio) goes through it and
/// decides for itself what lies outside the grid. Inside, `xs[j − 1] < x ≤ xs[j]` (x on a knot
/// ends the segment below it; the first knot starts the first segment, t = 0). Below the grid
/// j = 1 and t < 0, above it j = n − 1 and t > 1 (unclamped, so callers can clamp, extrapolate
/// or refuse). A zero-length segment gives t = 0.
pub fn locate(xs: &[f64], x: f64) -> (usize, f64) {
    let j = xs.partition_point(|&v| v < x).clamp(1, xs.len() - 1);
    let (x0, x1) = (xs[j - 1], xs[j]);
    let t = if x1 > x0 { (x - x0) / (x1 - x0) } else { 0.0 };
    (j, t)
}

/// The value at `(j, t)` from [`locate`]: `ys[j − 1] + t (ys[j] − ys[j − 1])`.
pub fn lerp(ys: &[f64], (j, t): (usize, f64)) -> f64 {
    ys[j - 1] + t * (ys[j] - ys[j - 1])
}

/// A discrete distribution over indices 0..n with weights w_i ≥ 0, drawn by inversion: the
/// crate's one categorical draw (the experiment design's strength- and damage-model draws and its
/// truth draws).
#[derive(Debug, Clone, PartialEq)]
pub struct Categorical {
    /// Cumulative weights.
    cum: Vec<f64>,
}

impl Categorical {
    /// The distribution of weights `w` (None when no weight is positive or one is negative or
    /// not finite).
    pub fn new(w: &[f64]) -> Option<Categorical> {
        let mut c = 0.0;
        let mut cum = Vec::with_capacity(w.len());
        for &wi in w {
            if !(wi >= 0.0 && wi.is_finite()) {
                return None;
            }
            c += wi;
            cum.push(c);
        }
        (c > 0.0).then_some(Categorical { cum })
    }

    /// Total weight.
    pub fn total(&self) -> f64 {
        *self.cum.last().expect("a categorical distribution has a weight")
    }

    /// The index i with cum_{i−1} ≤ u·Σw < cum_i, for u ∈ [0, 1): i is drawn with probability
    /// w_i / Σw, and an index of zero weight never.
    pub fn draw(&self, u: f64) -> usize {
        let t = u * self.total();
        self.cum.partition_point(|&c| c <= t).min(self.cum.len() - 1)
    }
}

/// Cubic Hermite interpolation on a uniform grid of step `h`: the value at `(j, t)` from
/// [`locate`] (segment `[j − 1, j]`, fraction t) from the values `ys` and the slopes `dys`
/// (dy/dx) at the knots. Exact for cubics; error h⁴ max|y⁽⁴⁾|/384.
pub fn hermite(ys: &[f64], dys: &[f64], h: f64, (j, t): (usize, f64)) -> f64 {
    let (t2, t3) = (t * t, t * t * t);
    (2.0 * t3 - 3.0 * t2 + 1.0) * ys[j - 1] + (t3 - 2.0 * t2 + t) * h * dys[j - 1] + (3.0 * t2 - 2.0 * t3) * ys[j] + (t3 - t2) * h * dys[j]
}

/// Ranks of `x`, 1-based, ties given their average rank (the crate's one ranking: Spearman's ρ
/// and the rank-normalised R̂ use it).
pub fn ranks(x: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..x.len()).collect();
    idx.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let mut r = vec![0.0; x.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && x[idx[j + 1]] == x[idx[i]] {
            j += 1;
        }
        let avg = 0.5 * (i + j) as f64 + 1.0;
        for &k in &idx[i..=j] {
            r[k] = avg;
        }
        i = j + 1;
    }
    r
}

/// The maximiser of a unimodal `f` on [a, b] by golden-section search, to a bracket of `tol`
/// (the midpoint of the final bracket; ties keep the left point). The crate's one copy (damage
/// ratio profile, partial-pooling spread).
pub fn golden_max(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64, tol: f64) -> f64 {
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - phi * (b - a), a + phi * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    while b - a > tol {
        if fc >= fd {
            (b, d, fd) = (d, c, fc);
            c = b - phi * (b - a);
            fc = f(c);
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + phi * (b - a);
            fd = f(d);
        }
    }
    0.5 * (a + b)
}

/// One end of a profile-likelihood interval: the edge of the set {v : `inside`(v)} reached from
/// `start` (inside) in direction `dir` (±1). Steps of `step`, growing × 1.6, until a point is
/// outside — or the `bound`, returned if it is still inside — then bisection to `tol`; the
/// midpoint of the final bracket. None if `inside` fails (None) or 40 steps stay inside. The
/// crate's one copy (a regression coefficient, a two-population law's parameter, a pooled spread);
/// `inside` may keep state, e.g. warm-start from the last point it found inside.
pub fn region_end(mut inside: impl FnMut(f64) -> Option<bool>, start: f64, dir: f64, mut step: f64, bound: f64, tol: f64) -> Option<f64> {
    let clamp = |v: f64| if dir < 0.0 { v.max(bound) } else { v.min(bound) };
    let (mut keep, mut out) = (start, clamp(start + dir * step));
    let mut tries = 0;
    while inside(out)? {
        if out == bound {
            return Some(bound);
        }
        keep = out;
        step *= 1.6;
        out = clamp(out + dir * step);
        tries += 1;
        if tries > 40 {
            return None;
        }
    }
    for _ in 0..80 {
        if (out - keep).abs() <= tol {
            break;
        }
        let mid = 0.5 * (keep + out);
        if inside(mid)? { keep = mid } else { out = mid }
    }
    Some(0.5 * (keep + out))
}


/// The smallest and largest of `v` ((∞, −∞) for none).
pub fn min_max(v: &[f64]) -> (f64, f64) {
    v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn region_end_finds_the_edge_of_an_interval_and_stops_at_its_bound() {
        let inside = |v: f64| Some(v * v <= 2.0);
        assert!((region_end(inside, 0.0, 1.0, 0.1, f64::INFINITY, 1e-9).unwrap() - 2f64.sqrt()).abs() < 1e-8);
        assert!((region_end(inside, 0.0, -1.0, 0.1, f64::NEG_INFINITY, 1e-9).unwrap() + 2f64.sqrt()).abs() < 1e-8);
        assert_eq!(region_end(inside, 0.0, 1.0, 0.1, 1.2, 1e-9), Some(1.2));
        assert_eq!(region_end(|_| Some(true), 0.0, 1.0, 0.1, f64::INFINITY, 1e-9), None);
    }

    #[test]
    fn hermite_is_exact_for_cubics() {
        let f = |x: f64| 2.0 - x + 0.5 * x * x - 0.25 * x * x * x;
        let df = |x: f64| -1.0 + x - 0.75 * x * x;
        let xs: Vec<f64> = (0..5).map(|i| i as f64 * 0.5).collect();
        let (ys, dys): (Vec<f64>, Vec<f64>) = xs.iter().map(|&x| (f(x), df(x))).unzip();
        for x in [0.0, 0.1, 0.77, 1.5, 1.99] {
            assert!((hermite(&ys, &dys, 0.5, locate(&xs, x)) - f(x)).abs() < 1e-12, "x = {x}");
        }
    }

    #[test]
    fn categorical_draws_by_inversion_and_skips_zero_weights() {
        let c = Categorical::new(&[1.0, 0.0, 3.0]).unwrap();
        assert_eq!(c.total(), 4.0);
        assert_eq!([c.draw(0.0), c.draw(0.2499), c.draw(0.25), c.draw(0.9999)], [0, 0, 2, 2]);
        // Frequencies on a fine grid of u are the weights.
        let n = 100_000;
        let hits = (0..n).filter(|&i| c.draw((i as f64 + 0.5) / n as f64) == 2).count();
        assert_eq!(hits, 75_000);
        assert!(Categorical::new(&[0.0, 0.0]).is_none() && Categorical::new(&[1.0, -1.0]).is_none() && Categorical::new(&[f64::NAN]).is_none());
    }

    #[test]
    fn pearson_of_a_line_and_the_critical_value() {
        let x: Vec<f64> = (0..50).map(|i| i as f64).collect();
        let y: Vec<f64> = x.iter().map(|v| 2.0 * v + 1.0).collect();
        let (r, p) = pearson(&x, &y);
        assert!((r - 1.0).abs() < 1e-12 && p < 1e-10);
        let (r, _) = pearson(&x, &x.iter().map(|v| -v).collect::<Vec<_>>());
        assert!((r + 1.0).abs() < 1e-12);
        // Tables of critical values: |r| = 0.279 at n = 50, 0.361 at n = 30 (two-sided 5 %).
        assert!((correlation_p_value(0.279, 50) - 0.05).abs() < 0.002);
        assert!((correlation_p_value(-0.361, 30) - 0.05).abs() < 0.002);
    }

    #[test]
    fn line_fit_recovers_known_coefficients() {
        // y = 2 − 0.5x + e with e = ±0.1 alternating on x = 0..9: exact slope SE by hand.
        let x: Vec<f64> = (0..10).map(|i| i as f64).collect();
        let e: Vec<f64> = (0..10).map(|i| if i % 2 == 0 { 0.1 } else { -0.1 }).collect();
        let y: Vec<f64> = x.iter().zip(&e).map(|(x, e)| 2.0 - 0.5 * x + e).collect();
        let f = fit_line(&x, &y).unwrap();
        // Closed form: slope = Sxy/Sxx, SE = √(RSS/(n−2)/Sxx).
        let mx = 4.5;
        let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
        let my = y.iter().sum::<f64>() / 10.0;
        let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
        let slope = sxy / sxx;
        let rss: f64 = x.iter().zip(&y).map(|(a, b)| (b - (my - slope * mx) - slope * a).powi(2)).sum();
        assert!((f.slope - slope).abs() < 1e-12 && (f.intercept - (my - slope * mx)).abs() < 1e-12);
        assert!((f.slope_se - (rss / 8.0 / sxx).sqrt()).abs() < 1e-12);
        assert!(f.r < -0.99 && f.p_value < 1e-6);
        assert!(fit_line(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]).is_err());
    }

    #[test]
    fn medians() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(&[]).is_nan());
    }

    #[test]
    fn locate_and_lerp_inside_on_knots_and_outside() {
        let xs = [0.0, 1.0, 3.0];
        let ys = [10.0, 20.0, 0.0];
        assert_eq!(locate(&xs, 2.0), (2, 0.5));
        assert_eq!(lerp(&ys, locate(&xs, 2.0)), 10.0);
        // A knot ends the segment below it; the first knot starts the first.
        assert_eq!(locate(&xs, 1.0), (1, 1.0));
        assert_eq!(locate(&xs, 0.0), (1, 0.0));
        // Outside: unclamped fractions for the caller to clamp or extrapolate.
        assert_eq!(locate(&xs, -1.0), (1, -1.0));
        assert_eq!(locate(&xs, 5.0), (2, 2.0));
        assert_eq!(lerp(&ys, locate(&xs, 5.0)), -20.0);
        // A zero-length segment gives its first value.
        assert_eq!(locate(&[1.0, 1.0], 1.0), (1, 0.0));
    }

    #[test]
    fn ranks_average_ties() {
        assert_eq!(ranks(&[3.0, 1.0, 2.0, 1.0]), vec![4.0, 1.5, 3.0, 1.5]);
        assert_eq!(ranks(&[]), Vec::<f64>::new());
    }
}

/// The median and the central band at probability `level` of `v` (0.9: the 5 % and 95 %
/// quantiles; [`interpolated_quantiles`]).
pub fn median_and_band(v: Vec<f64>, level: f64) -> (f64, f64, f64) {
    let a = 0.5 * (1.0 - level);
    let q = interpolated_quantiles(v, &[0.5, a, 1.0 - a]);
    (q[0], q[1], q[2])
}

/// Quantiles `ps` of `v` ([`sorted_quantile`], type 7). Only the order statistics the
/// quantiles read are put in place (a selection per rank, O(n) each, instead of a sort): the
/// same values as sorting first, since the order (`total_cmp`) is total.
pub fn interpolated_quantiles(mut v: Vec<f64>, ps: &[f64]) -> Vec<f64> {
    if v.is_empty() {
        return vec![f64::NAN; ps.len()];
    }
    let last = v.len() - 1;
    let mut ranks: Vec<usize> = ps
        .iter()
        .flat_map(|&p| {
            let i = (last as f64 * p.clamp(0.0, 1.0)).floor() as usize;
            [i, (i + 1).min(last)]
        })
        .collect();
    ranks.sort_unstable();
    ranks.dedup();
    // Rank r in v[start..]: everything after it is ≥ it, so the next rank lies beyond it.
    let mut start = 0;
    for r in ranks {
        v[start..].select_nth_unstable_by(r - start, f64::total_cmp);
        start = r + 1;
    }
    ps.iter().map(|&p| sorted_quantile(&v, p)).collect()
}

/// Quantiles `ps` of a weighted sample (value, weight > 0): the inverse of its weighted
/// empirical CDF, i.e. the smallest value whose cumulative weight reaches p·(total weight).
/// The one exception to [`sorted_quantile`]: type 7 has no weighted form that respects
/// arbitrary weights, so the main study's model-averaged bands (samples weighted by the
/// stacking weights) use this inverse CDF, which is type 1 for equal weights. Empty: NaN.
pub fn weighted_quantiles(mut v: Vec<(f64, f64)>, ps: &[f64]) -> Vec<f64> {
    if v.is_empty() {
        return vec![f64::NAN; ps.len()];
    }
    // Stable (ties keep their order, hence the cumulative sums' bits), in parallel.
    rayon::slice::ParallelSliceMut::par_sort_by(&mut v[..], |a, b| a.0.total_cmp(&b.0));
    weighted_quantiles_sorted(v.iter().copied(), ps)
}

/// [`weighted_quantiles`] of a weighted sample already in ascending order of value (callers that
/// keep the order between reweightings skip the sort). Empty: NaN.
pub fn weighted_quantiles_sorted<I: Iterator<Item = (f64, f64)> + Clone>(sorted: I, ps: &[f64]) -> Vec<f64> {
    let total: f64 = sorted.clone().map(|x| x.1).sum();
    ps.iter()
        .map(|&p| {
            let target = p.clamp(0.0, 1.0) * total * (1.0 - 1e-12);
            let (mut c, mut last) = (0.0, f64::NAN);
            for (v, w) in sorted.clone() {
                c += w;
                last = v;
                if c >= target {
                    break;
                }
            }
            last
        })
        .collect()
}

#[cfg(test)]
mod weighted_tests {
    #[test]
    fn weighted_quantiles_invert_the_weighted_cdf() {
        // Values 1, 2, 3 with weights 0.2, 0.3, 0.5: CDF 0.2, 0.5, 1.0.
        let v = vec![(3.0, 0.5), (1.0, 0.2), (2.0, 0.3)];
        assert_eq!(super::weighted_quantiles(v, &[0.1, 0.2, 0.25, 0.5, 0.51, 1.0]), vec![1.0, 1.0, 2.0, 2.0, 3.0, 3.0]);
    }

    #[test]
    fn quantiles_by_selection_are_the_sorted_samples_quantiles_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        // Ranks that coincide, neighbours, the ends, p out of order and repeated.
        let ps = [0.95, 0.05, 0.5, 0.5, 0.0, 1.0, 0.25, 0.2500001, 0.999, 1.5, -0.1];
        for n in [1usize, 2, 3, 10, 101, 5000] {
            // Many ties (values on a coarse grid), signed zeros and an infinity.
            let mut v: Vec<f64> = (0..n).map(|_| (rng.random_range(-20..20) as f64) * 0.25).collect();
            if n > 3 {
                v[0] = -0.0;
                v[1] = 0.0;
                v[2] = f64::INFINITY;
            }
            let mut sorted = v.clone();
            sorted.sort_by(f64::total_cmp);
            let want: Vec<u64> = ps.iter().map(|&p| super::sorted_quantile(&sorted, p).to_bits()).collect();
            let got: Vec<u64> = super::interpolated_quantiles(v, &ps).iter().map(|x| x.to_bits()).collect();
            assert_eq!(got, want, "n = {n}");
        }
        assert!(super::interpolated_quantiles(Vec::new(), &[0.5])[0].is_nan());
    }
}

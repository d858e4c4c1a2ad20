//! Small descriptive statistics shared by the data tools and the runner: median and Pearson
//! correlation with its two-sided p-value (t = r √((n − 2)/(1 − r²)), Student t with n − 2
//! degrees of freedom).
//!
//! Verified by the unit tests below (exact line; the tabulated two-sided 5 % critical value
//! r = 0.279 at n = 50).

use statrs::distribution::{ContinuousCDF, StudentsT};

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

/// Median of a slice (NaN when empty).
pub fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let k = s.len();
    if k % 2 == 1 { s[k / 2] } else { 0.5 * (s[k / 2 - 1] + s[k / 2]) }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn medians() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(&[]).is_nan());
    }
}

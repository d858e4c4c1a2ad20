//! Attrition in a plant engineer's units: the years until a share of the inventory is broken,
//! read off P_break on a logarithmic grid of horizons (used by the main and lifetime studies).
//!
//! The grid has [`GRID`] points per decade from 10^[`DECADES`].0 to 10^[`DECADES`].1 years,
//! 1 year among them. The years to a share x are where ln P crosses ln x, interpolated
//! linearly in (ln t, ln P) between the grid points that bracket it; P is increasing in t for
//! every damage model, so the first crossing is the only one; +∞ when P stays below x on the
//! grid. Verified in this file's tests against the closed form of independent trials with one
//! particle type, P(t) = 1 − exp(−N_yr H t): t_x = −ln(1 − x)/(N_yr H), within 2 % (between
//! grid points ln P is concave in ln t and the chord lies below it).

/// Grid points per decade of years.
pub const GRID: usize = 4;
/// Shortest and longest horizon of the grid (log₁₀ years).
pub const DECADES: (i32, i32) = (-2, 2);
/// The broken shares whose times are reported.
pub const SHARES: [f64; 2] = [0.01, 0.10];

/// The grid of horizons (years).
pub fn grid() -> Vec<f64> {
    let n = (DECADES.1 - DECADES.0) as usize * GRID;
    (0..=n).map(|i| 10f64.powf(DECADES.0 as f64 + i as f64 / GRID as f64)).collect()
}

/// Years until P(t) reaches `x` on grid `t` (+∞ when it does not within the grid).
pub fn years_to(t: &[f64], p: &[f64], x: f64) -> f64 {
    if p.first().is_some_and(|&p0| p0 >= x) {
        // Reached before the first grid point: extrapolate P ∝ t (the small-P limit).
        return t[0] * x / p[0];
    }
    for i in 1..t.len() {
        if p[i] >= x {
            let (a, b) = (p[i - 1].max(1e-300).ln(), p[i].ln());
            let s = (x.ln() - a) / (b - a);
            return (t[i - 1].ln() + s * (t[i].ln() - t[i - 1].ln())).exp();
        }
    }
    f64::INFINITY
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_has_one_year_and_spans_four_decades() {
        let t = grid();
        assert_eq!(t.len(), 17);
        assert!(t.iter().any(|&y| (y - 1.0).abs() < 1e-12));
        assert!((t[0] - 0.01).abs() < 1e-15 && (t[16] - 100.0).abs() < 1e-9);
    }

    #[test]
    fn years_to_matches_independent_trials() {
        // One particle type, hazard H per impact, 730 impacts a year: P(t) = 1 − exp(−730 H t),
        // t_x = −ln(1 − x)/(730 H).
        let t = grid();
        for h in [1e-7, 3e-6, 1e-4, 2e-3] {
            let p: Vec<f64> = t.iter().map(|y| -(-730.0 * h * y).exp_m1()).collect();
            for x in SHARES {
                let exact = -(-x).ln_1p() / (730.0 * h);
                let got = years_to(&t, &p, x);
                if exact > 100.0 {
                    assert!(got.is_infinite(), "H {h}: {got} for {exact}");
                } else {
                    // Between grid points ln P is concave in ln t; the chord is within 2 %.
                    assert!((got / exact - 1.0).abs() < 0.02, "H {h}, x {x}: {got} vs {exact}");
                }
            }
        }
        // Never reached, and reached before the grid starts.
        assert!(years_to(&t, &vec![0.0; t.len()], 0.01).is_infinite());
        let fast: Vec<f64> = t.iter().map(|y| -(-730.0 * 10.0 * y).exp_m1()).collect();
        assert!(years_to(&t, &fast, 0.01) < 0.01);
    }

}

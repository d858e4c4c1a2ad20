//! Breaking probability of particles under repeated impacts (deliverable §6): the impact load
//! of one particle, N-impact breakage without underflow, and the damage models
//! ([`damage`]). The chain as a whole — contact geometry, strength law, impact, population —
//! is [`crate::strength::LifetimeModel`].
//!
//! # Numerics
//!
//! `P_N` is computed as `−expm1(N · ln1p(−p))` ([`breakage_after`]), or directly from the
//! per-impact cumulative hazard H = (σ̄/σ_θ)^m as `−expm1(−N H)` ([`breakage_from_hazard`]), so
//! there is neither underflow nor cancellation for p down to 1e-300 and N up to 1e6 and beyond
//! (the naive `1 − (1 − p)^N` returns 0 for p < 1.1e-16).
//!
//! Verified by the unit tests below (series expansion of P_N for tiny p, geometric closed form)
//! and by `tests/verification/lifetime.rs`.

pub mod attrition;
pub mod damage;
pub mod tested;

use crate::contact::{AveragingDomain, ContactState, ContactStress, Elastic, Impact, Sphere};
use crate::error::Result;

/// Largest impact velocity the chain accepts (m/s); far beyond the elastic Hertz regime anyway.
pub const MAX_VELOCITY: f64 = 100.0;

/// Default number of high-velocity impacts per particle and year (deliverable §6, from D2.3 §5.2).
pub const IMPACTS_PER_YEAR: f64 = 730.0;

/// Probability of breaking within N independent impacts of per-impact probability p:
/// 1 − (1 − p)^N, computed as −expm1(N ln1p(−p)).
///
/// ```
/// # use partlife::lifetime::breakage_after;
/// // Naive 1 − (1 − 1e-15)^1e6 loses every digit; this does not.
/// assert!((breakage_after(1e-15, 1e6) / 1e-9 - 1.0).abs() < 1e-9);
/// assert_eq!(breakage_after(1.0, 3.0), 1.0);
/// ```
pub fn breakage_after(p: f64, n: f64) -> f64 {
    if p >= 1.0 {
        return if n > 0.0 { 1.0 } else { 0.0 };
    }
    -(n * (-p).ln_1p()).exp_m1()
}

/// Probability of breaking within N impacts given the per-impact cumulative hazard
/// H = −ln(1 − p) (for a Weibull, H = (σ̄/σ_θ)^m): 1 − e^(−x) with x = N H.
///
/// For x < 0.01 by its series x(1 − x/2(1 − x/3(1 − x/4(1 − x/5(1 − x/6))))), whose remainder
/// is below x⁶/7! < 2·10⁻¹⁶ relative (no underflow or cancellation down to x = 10⁻³⁰⁰); above,
/// as 1 − e^(−x), whose relative error is at most 2 ulp/x < 5·10⁻¹⁴ there. The hot path of a
/// population's breakage: a few multiplications for most particles, one exp for the rest
/// (expm1 costs about three times as much).
///
/// ```
/// # use partlife::lifetime::breakage_from_hazard;
/// for x in [1e-300, 1e-9, 1e-3, 0.00999, 0.01001, 0.3, 40.0] {
///     assert!((breakage_from_hazard(x, 1.0) / -(-x).exp_m1() - 1.0).abs() < 5e-14);
/// }
/// ```
#[inline(always)]
pub fn breakage_from_hazard(hazard: f64, n: f64) -> f64 {
    let x = n * hazard;
    if x < 0.01 {
        x * (1.0 - x * (1.0 / 2.0) * (1.0 - x * (1.0 / 3.0) * (1.0 - x * (1.0 / 4.0) * (1.0 - x * (1.0 / 5.0) * (1.0 - x * (1.0 / 6.0))))))
    } else {
        1.0 - (-x).exp()
    }
}

/// Number of impacts in `years` of operation.
pub fn impacts_in(years: f64, per_year: f64) -> f64 {
    years * per_year
}

/// Impact loading of one particle on a wall: velocity → contact state at the force peak.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactLoad {
    /// Impact mechanics (η included).
    pub impact: Impact,
    /// Stress evaluator of the same contact.
    pub stress: ContactStress,
}

impl ImpactLoad {
    /// A sphere of the given material hitting a wall with elastic energy fraction η.
    pub fn on_wall(sphere: &Sphere, wall: &Elastic, eta: f64, domain: AveragingDomain) -> Self {
        let impact = Impact::sphere_on_wall(sphere, wall, sphere.radius(), eta);
        ImpactLoad { impact, stress: ContactStress::new(impact.hertz, domain, sphere.radius()) }
    }

    /// Contact state at the force peak of an impact at V (m/s); all zero at V = 0.
    pub fn at_velocity(&self, v: f64) -> Result<ContactState> {
        if v <= 0.0 {
            return Ok(ContactState {
                force: 0.0,
                radius: 0.0,
                approach: 0.0,
                peak_pressure: 0.0,
                max_tensile: 0.0,
                mean_tensile: 0.0,
            });
        }
        self.stress.at_force(self.impact.max_force(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiny_probabilities_match_the_series() {
        // 1 − (1−p)^N = Np − N(N−1)p²/2 + … for Np ≪ 1.
        for &(p, n) in &[(1e-15, 1e6), (1e-12, 7300.0), (3e-9, 730.0), (1e-300, 1e6)] {
            let series = n * p - n * (n - 1.0) * p * p / 2.0;
            let got = breakage_after(p, n);
            assert!((got / series - 1.0).abs() < 1e-12, "p={p} N={n}: {got} vs {series}");
            // Same through the hazard route.
            let h = -(-p).ln_1p();
            assert!((breakage_from_hazard(h, n) / got - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn hazard_route_matches_expm1_across_the_switch() {
        // Dense scan of x = N H over 1e-12 … 50, both sides of the series/exp switch at 0.01.
        for k in 0..=20_000 {
            let x = 10f64.powf(-12.0 + 13.7 * k as f64 / 20_000.0);
            let want = -(-x).exp_m1();
            assert!((breakage_from_hazard(x, 1.0) / want - 1.0).abs() < 5e-14, "x = {x}");
        }
    }

    #[test]
    fn geometric_closed_form() {
        // P(survive n) = (1 − p)^n exactly for moderate p.
        for &(p, n) in &[(0.1, 5.0), (0.5, 3.0), (0.01, 100.0)] {
            let exact = 1.0 - (1.0f64 - p).powf(n);
            assert!((breakage_after(p, n) - exact).abs() < 1e-14);
        }
        assert_eq!(breakage_after(0.0, 1e6), 0.0);
        assert_eq!(breakage_after(1.0, 1.0), 1.0);
    }
}

//! Breaking probability of particles under repeated impacts (deliverable §6).
//!
//! # Chain
//!
//! ```text
//! V ──Hertz impact, energy fraction η──► F_max, a, p0 ──averaging domain──► σ̄(V)
//!   ──Weibull of σ̄ at break (crush data)──► p(V) = 1 − exp[−(σ̄/σ_θ)^m]
//!   ──independent trials──► P_N(V) = 1 − (1 − p)^N,   N = years × impacts per year (730/yr)
//! ```
//!
//! # Numerics
//!
//! `P_N` is computed as `−expm1(N · ln1p(−p))` ([`breakage_after`]), or directly from the
//! per-impact cumulative hazard H = (σ̄/σ_θ)^m as `−expm1(−N H)` ([`breakage_from_hazard`]), so
//! there is neither underflow nor cancellation for p down to 1e-300 and N up to 1e6 and beyond
//! (the naive `1 − (1 − p)^N` returns 0 for p < 1.1e-16).
//!
//! # The Simulator
//!
//! [`LifetimeChain`] is the chain as a black box θ ↦ y for the uncertainty and calibration
//! methods: θ = (Weibull shape m, Weibull scale σ_θ (Pa), energy fraction η, impact velocity V
//! (m/s)); y = (F_max (N), σ̄ (Pa), P_N for each configured impact count N). Parameter indices
//! are fixed at construction.
//!
//! Verified by the unit tests below (series expansion of P_N for tiny p, geometric closed form,
//! monotonicity) and by `tests/verification/lifetime.rs`.

use crate::contact::{AveragingDomain, ContactState, ContactStress, Elastic, Impact, Sphere};
use crate::error::{Error, Result};
use crate::model::{OutputSpec, Simulator, check_outputs};
use crate::params::{Param, ParamSpace};
use crate::weibull::Weibull;

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
/// H = −ln(1 − p) (for a Weibull, H = (σ̄/σ_θ)^m): −expm1(−N H).
pub fn breakage_from_hazard(hazard: f64, n: f64) -> f64 {
    -(-n * hazard).exp_m1()
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

/// A fitted strength law applied to impacts: p(V) and P_N(V).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lifetime {
    /// Impact loading.
    pub load: ImpactLoad,
    /// Weibull law of σ̄ at break (Pa).
    pub strength: Weibull,
}

impl Lifetime {
    /// Per-impact cumulative hazard H(V) = (σ̄(V)/σ_θ)^m.
    pub fn hazard(&self, v: f64) -> Result<f64> {
        Ok(self.strength.cumulative_hazard(self.load.at_velocity(v)?.mean_tensile))
    }

    /// Single-impact breaking probability p(V).
    pub fn p_single(&self, v: f64) -> Result<f64> {
        Ok(-(-self.hazard(v)?).exp_m1())
    }

    /// Breaking probability after N impacts at V.
    pub fn p_after(&self, v: f64, n: f64) -> Result<f64> {
        Ok(breakage_from_hazard(self.hazard(v)?, n))
    }
}

/// A precomputed breakage curve V ↦ (σ̄, P_N) for one material, η, averaging domain and
/// Weibull law: the fast path for loops over many velocities (Monte Carlo, figures).
///
/// For a sphere on a wall δ_m ∝ V^(4/5), so the contact radius and the peak pressure at the
/// force peak both scale as t = V^(2/5): a = c_a t, p0 = c_p t, where c_a and c_p are a and p0
/// of the same impact at V = 1 m/s (taken from [`Impact`] and [`crate::contact::Hertz`], not
/// re-derived). With L = κa, σ̄ = r p0 and the cumulative hazard is
/// H = exp(m ln(r c_p/σ_θ) + (2m/5) ln V); with L = R the domain formula is evaluated at (p0, a).
/// Agrees with [`Lifetime::p_after`] to 1e-12 relative (`tests::fast_curve_matches_the_chain`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BreakageCurve {
    c_a: f64,
    c_p: f64,
    shape: f64,
    ln_scale: f64,
    /// ln(σ̄/p0 · c_p) when σ̄/p0 is constant (L = κa).
    ln_sigma_coefficient: Option<f64>,
    load: ImpactLoad,
}

impl BreakageCurve {
    /// Precomputes the curve of a lifetime model.
    pub fn new(life: &Lifetime) -> Self {
        // The impact at V = 1 m/s fixes the prefactors of a and p0 ∝ V^(2/5).
        let f1 = life.load.impact.max_force(1.0);
        let h = life.load.impact.hertz;
        let c_p = h.peak_pressure(f1);
        BreakageCurve {
            c_a: h.contact_radius(f1),
            c_p,
            shape: life.strength.shape,
            ln_scale: life.strength.scale.ln(),
            ln_sigma_coefficient: life.load.stress.domain.ratio_to_peak_pressure(&life.load.stress.zone).map(|r| (r * c_p).ln()),
            load: life.load,
        }
    }

    /// (σ̄ at the force peak (Pa), P_N) for an impact at V (m/s) repeated N times. V ≤ 0 gives
    /// (0, 0); a contact larger than an L = R domain gives NaN (the general path reports it as
    /// an error).
    #[inline(always)]
    pub fn evaluate(&self, v: f64, n: f64) -> (f64, f64) {
        if v <= 0.0 {
            return (0.0, 0.0);
        }
        let ln_t = 0.4 * v.ln();
        let ln_sigma = match self.ln_sigma_coefficient {
            Some(c) => c + ln_t,
            None => self.ln_sigma_general(ln_t),
        };
        let hazard = (self.shape * (ln_sigma - self.ln_scale)).exp();
        (ln_sigma.exp(), breakage_from_hazard(hazard, n))
    }

    /// ln σ̄ for a domain whose σ̄/p0 depends on a/R (L = R).
    #[cold]
    #[inline(never)]
    fn ln_sigma_general(&self, ln_t: f64) -> f64 {
        let s = &self.load.stress;
        let t = ln_t.exp();
        s.domain
            .mean_tensile_stress(&s.zone, self.c_p * t, self.c_a * t, s.particle_radius)
            .map(f64::ln)
            .unwrap_or(f64::NAN)
    }
}

/// The lifetime chain as a [`Simulator`].
#[derive(Debug, Clone)]
pub struct LifetimeChain {
    sphere: Sphere,
    wall: Elastic,
    domain: AveragingDomain,
    counts: Vec<f64>,
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
}

/// Indices of θ in [`LifetimeChain`].
pub mod theta {
    /// Weibull shape m (-).
    pub const SHAPE: usize = 0;
    /// Weibull scale σ_θ (Pa).
    pub const SCALE: usize = 1;
    /// Elastic energy fraction η (-).
    pub const ETA: usize = 2;
    /// Impact velocity V (m/s).
    pub const VELOCITY: usize = 3;
}

impl LifetimeChain {
    /// Chain for one particle type hitting `wall`; outputs P_N for each impact count in `counts`;
    /// `nominal` = (Weibull law of σ̄ in Pa, η, V in m/s).
    pub fn new(
        sphere: Sphere,
        wall: Elastic,
        domain: AveragingDomain,
        counts: &[f64],
        nominal: (Weibull, f64, f64),
    ) -> Result<Self> {
        if counts.iter().any(|n| !(n.is_finite() && *n >= 1.0)) {
            return Err(Error::Param { name: "impact_counts".into(), rule: format!("every count must be ≥ 1 (got {counts:?})") });
        }
        let (w, eta, v) = nominal;
        // Wide physical bounds; a nominal outside them is an error, never clamped.
        let space = ParamSpace::new(vec![
            Param::uniform("weibull_shape", "-", 0.1, 500.0, w.shape),
            Param::uniform("weibull_scale_pa", "Pa", 1e3, 1e12, w.scale),
            Param::uniform("energy_fraction", "-", 1e-9, 1.0, eta),
            Param::uniform("velocity_m_s", "m/s", 0.0, MAX_VELOCITY, v),
        ])?;
        let mut outputs = vec![OutputSpec::new("f_max_n", "N"), OutputSpec::new("sigma_bar_pa", "Pa")];
        outputs.extend(counts.iter().map(|n| OutputSpec::new(format!("p_break_{n}"), "-")));
        Ok(LifetimeChain { sphere, wall, domain, counts: counts.to_vec(), space, outputs })
    }

    /// The particle.
    pub fn sphere(&self) -> &Sphere {
        &self.sphere
    }

    /// The impact of this particle on the wall with energy fraction η.
    pub fn impact(&self, eta: f64) -> Impact {
        Impact::sphere_on_wall(&self.sphere, &self.wall, self.sphere.radius(), eta)
    }

    /// The impact counts N of the outputs.
    pub fn counts(&self) -> &[f64] {
        &self.counts
    }

    /// The [`Lifetime`] model at θ.
    pub fn lifetime_at(&self, theta: &[f64]) -> Result<Lifetime> {
        self.space.check(theta)?;
        if !self.space.contains(theta) {
            return Err(Error::Param { name: "θ".into(), rule: format!("{theta:?} lies outside the bounds") });
        }
        Ok(Lifetime {
            load: ImpactLoad::on_wall(&self.sphere, &self.wall, theta[theta::ETA], self.domain),
            strength: Weibull::new(theta[theta::SHAPE], theta[theta::SCALE])?,
        })
    }
}

impl Simulator for LifetimeChain {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        let life = self.lifetime_at(theta)?;
        let state = life.load.at_velocity(theta[theta::VELOCITY])?;
        let h = life.strength.cumulative_hazard(state.mean_tensile);
        let mut y = vec![state.force, state.mean_tensile];
        y.extend(self.counts.iter().map(|&n| breakage_from_hazard(h, n)));
        check_outputs("lifetime chain", &self.outputs, theta, &y)?;
        Ok(y)
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
    fn geometric_closed_form() {
        // P(survive n) = (1 − p)^n exactly for moderate p.
        for &(p, n) in &[(0.1, 5.0), (0.5, 3.0), (0.01, 100.0)] {
            let exact = 1.0 - (1.0f64 - p).powf(n);
            assert!((breakage_after(p, n) - exact).abs() < 1e-14);
        }
        assert_eq!(breakage_after(0.0, 1e6), 0.0);
        assert_eq!(breakage_after(1.0, 1.0), 1.0);
    }

    fn chain() -> LifetimeChain {
        let e = Elastic::new(112e9, 0.25).unwrap();
        let sphere = Sphere { diameter: 1e-3, density: 3600.0, elastic: e };
        let wall = Elastic::new(210e9, 0.3).unwrap();
        let w = Weibull::new(10.0, 800e6).unwrap();
        LifetimeChain::new(sphere, wall, AveragingDomain::default(), &[1.0, 730.0, 7300.0], (w, 0.1, 5.0)).unwrap()
    }

    #[test]
    fn chain_outputs_are_ordered_and_monotone() {
        let c = chain();
        let mut prev = vec![0.0; c.outputs().len()];
        for v in [0.0, 1.0, 5.0, 10.0, 20.0] {
            let mut th = c.space().nominal();
            th[theta::VELOCITY] = v;
            let y = c.simulate(&th).unwrap();
            assert_eq!(y.len(), 5);
            // More impacts → more breakage; faster → more of everything.
            assert!(y[2] <= y[3] && y[3] <= y[4]);
            for (a, b) in prev.iter().zip(&y) {
                assert!(b >= a);
            }
            prev = y;
        }
    }

    #[test]
    fn velocity_exponent_of_the_lower_tail() {
        // With L = κa, σ̄ ∝ V^(2/5), so p ∝ V^(2m/5) in the lower tail (mechanics.md §3.5).
        let c = chain();
        let mut th = c.space().nominal();
        th[theta::VELOCITY] = 1.0;
        let p1 = c.simulate(&th).unwrap()[2];
        th[theta::VELOCITY] = 2.0;
        let p2 = c.simulate(&th).unwrap()[2];
        assert!(((p2 / p1).log2() - 4.0).abs() < 1e-6, "{}", (p2 / p1).log2());
    }

    #[test]
    fn fast_curve_matches_the_chain() {
        use crate::contact::OuterLimit;
        for outer in [OuterLimit::ContactMultiple, OuterLimit::ParticleRadius] {
            let e = Elastic::new(112e9, 0.25).unwrap();
            let sphere = Sphere { diameter: 0.9e-3, density: 3060.0, elastic: e };
            let domain = AveragingDomain { outer, ..AveragingDomain::default() };
            let life = Lifetime {
                load: ImpactLoad::on_wall(&sphere, &Elastic::new(210e9, 0.3).unwrap(), 0.13, domain),
                strength: Weibull::new(8.3, 640e6).unwrap(),
            };
            let curve = BreakageCurve::new(&life);
            for &v in &[0.3, 1.0, 4.7, 12.0, 20.0, 45.0] {
                for &n in &[1.0, 730.0, 7300.0] {
                    let (sigma, p) = curve.evaluate(v, n);
                    let want_sigma = life.load.at_velocity(v).unwrap().mean_tensile;
                    let want_p = life.p_after(v, n).unwrap();
                    assert!((sigma / want_sigma - 1.0).abs() < 1e-12, "{outer:?} V={v}: σ̄ {sigma} vs {want_sigma}");
                    assert!((p / want_p - 1.0).abs() < 1e-11, "{outer:?} V={v} N={n}: {p} vs {want_p}");
                }
            }
            assert_eq!(curve.evaluate(0.0, 10.0), (0.0, 0.0));
        }
    }

    #[test]
    fn out_of_bounds_theta_is_an_error() {
        let c = chain();
        let mut th = c.space().nominal();
        th[theta::ETA] = 2.0;
        assert!(c.simulate(&th).is_err());
    }
}

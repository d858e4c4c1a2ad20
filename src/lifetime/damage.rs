//! Damage models: from the single-impact breakage law of the lifetime chain to the breaking
//! probability after N impacts.
//!
//! All three start from the same calibrated single-impact law. With the Hertz impact,
//! σ̄ ∝ V^(2/5), so the Weibull law of σ̄ at break is a Weibull law of the specific impact
//! energy W = V²/2 with modulus m/5:
//!
//! ```text
//! p(W) = 1 − exp(−H),   H = (σ̄(V)/σ_θ)^m = (W/W_θ)^(m/5)
//! ```
//!
//! * **Independent trials** (the deliverable's): `P_N = 1 − (1 − p)^N = 1 − exp(−N H)`.
//! * **Vogel & Peukert master curve** (§4.2): `p = 1 − exp(−f x (W − W_min)⁺)`, linear in the
//!   energy above a threshold; `P_N = 1 − exp(−N f x (W − W_min)⁺)`. Its two constants are fitted
//!   to the same single-impact law over the range a breakage test resolves: the curves agree at
//!   10 % and 63.2 % breakage ([`VogelPeukert::matched`]). Below the threshold nothing breaks.
//! * **Tavares–King damage accumulation** (§4.3): a particle is deterministic — a fixed flaw
//!   population — whose fracture energy falls by (1 − D_n) at each impact that does not break
//!   it, with `D_n = [2γ/(2γ − 5D_n + 5) · E_k/E_m,n−1]^(2γ/5)` (fixed point). With constant
//!   impacts the ratio x = E_k/E_m evolves deterministically, so a particle breaks within N
//!   impacts iff its initial ratio exceeds x*(N, γ) ([`critical_ratio`]); hence
//!   `P_N = 1 − exp(−H · x*^(−m/5))`. With γ → ∞ (no damage) x* → 1 and P_N → p: unlike
//!   independent trials, a particle that survived the first impact survives identical later
//!   ones (the second caveat of independent trials: impacts at one velocity are not independent
//!   chances for a particle whose flaws do not change).
//!
//! [`Law`] is one model at a fixed modulus m and impact count N with its constants
//! precomputed: the hot path of a population's breakage, one evaluation per particle.
//!
//! Verified against hand-computed cases in the unit tests below.

use serde::{Deserialize, Serialize};

use super::breakage_from_hazard;

/// Which damage model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DamageModel {
    /// 1 − (1 − p)^N.
    Independent,
    /// Vogel & Peukert master curve fitted to the single-impact law.
    VogelPeukert,
    /// Tavares–King damage accumulation.
    TavaresKing,
}

impl DamageModel {
    /// Every model, in report order.
    pub const ALL: [DamageModel; 3] = [DamageModel::Independent, DamageModel::VogelPeukert, DamageModel::TavaresKing];

    /// Name in tables.
    pub fn name(self) -> &'static str {
        match self {
            DamageModel::Independent => "independent",
            DamageModel::VogelPeukert => "vogel_peukert",
            DamageModel::TavaresKing => "tavares_king",
        }
    }

    /// Name in figures.
    pub fn label(self) -> &'static str {
        match self {
            DamageModel::Independent => "independent trials",
            DamageModel::VogelPeukert => "Vogel–Peukert",
            DamageModel::TavaresKing => "Tavares–King",
        }
    }
}

/// Vogel–Peukert constants in units of the energy scale W_θ: `f x W_θ` and `W_min/W_θ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VogelPeukert {
    /// f_Mat · x · W_θ (-).
    pub rate: f64,
    /// W_min / W_θ (-), ≥ 0.
    pub threshold: f64,
}

impl VogelPeukert {
    /// The master curve through the Weibull-in-energy law of modulus `k = m/5` at 10 % and
    /// 63.2 % breakage (the threshold is kept ≥ 0).
    pub fn matched(k: f64) -> VogelPeukert {
        // l1 = −ln 0.9 = 0.10536…; w1 = l1^(1/k) by exp/ln (one exp per call).
        let (l1, l2) = (-(0.9f64).ln(), 1.0);
        let (w1, w2) = ((l1.ln() / k).exp(), 1.0);
        let rate = (l2 - l1) / (w2 - w1);
        let threshold = (w1 - l1 / rate).max(0.0);
        // With the threshold clamped, pass through the 63.2 % point.
        let rate = if threshold == 0.0 { l2 / w2 } else { rate };
        VogelPeukert { rate, threshold }
    }

    /// Cumulative hazard of one impact at reduced energy w = W/W_θ.
    pub fn hazard(&self, w: f64) -> f64 {
        self.rate * (w - self.threshold).max(0.0)
    }
}

/// Damage D of one impact at ratio x = E_k/E_m < 1 (fixed point of the Tavares–King relation);
/// None when there is no fixed point below 1 (the particle breaks).
pub fn tk_damage(x: f64, gamma: f64) -> Option<f64> {
    tk_damage_from(x, gamma, 0.0)
}

/// [`tk_damage`] with the fixed-point iteration started from `d0` (a neighbouring solve's
/// damage; the same fixed point, in fewer steps).
fn tk_damage_from(x: f64, gamma: f64, d0: f64) -> Option<f64> {
    let e = 2.0 * gamma / 5.0;
    let mut d = d0.clamp(0.0, 0.999_999);
    for _ in 0..200 {
        let denom = 2.0 * gamma - 5.0 * d + 5.0;
        if denom <= 0.0 {
            return None;
        }
        let next = (2.0 * gamma / denom * x).powf(e);
        if !(next < 1.0) {
            return None;
        }
        if (next - d).abs() <= 1e-14 * next.max(1e-300) {
            return Some(next);
        }
        d = next;
    }
    Some(d)
}

/// ln x_k, k = 0..=n, of the ratio x_k = E_k/E_m,k of a particle that survives n impacts of
/// constant energy from x0 (x_(k+1) = x_k/(1 − D_k)); None if it breaks within them. Since the
/// Hertz fracture energy scales as the strength⁵, its strength after k impacts is the initial one
/// times (x0/x_k)^(1/5).
pub fn tk_ratio_path(x0: f64, gamma: f64, n: u64) -> Option<Vec<f64>> {
    let mut path = Vec::with_capacity(n as usize + 1);
    let mut x = x0;
    path.push(x.ln());
    for _ in 0..n {
        if x >= 1.0 {
            return None;
        }
        let d = tk_damage(x, gamma)?;
        x /= 1.0 - d;
        path.push(x.ln());
    }
    Some(path)
}

/// Whether a particle with initial ratio x0 = E_k/E_m,0 breaks within `n` impacts: impact k
/// breaks it when x_(k−1) ≥ 1, or when its damage has no fixed point below 1.
pub fn tk_breaks_within(x0: f64, gamma: f64, n: u64) -> bool {
    let mut x = x0;
    for _ in 0..n {
        if x >= 1.0 {
            return true;
        }
        let Some(d) = tk_damage(x, gamma) else { return true };
        let next = x / (1.0 - d);
        // No measurable growth left: the ratio is stuck below 1.
        if next - x <= 1e-15 * x {
            return false;
        }
        x = next;
    }
    // The n impacts are over; a ratio ≥ 1 now would break the particle at impact n + 1.
    false
}

/// The smallest initial ratio x* = E_k/E_m,0 at which a particle breaks within `n` impacts
/// (bisection in ln x to 1e-10 relative; x* = 1 for n = 1).
pub fn critical_ratio(gamma: f64, n: u64) -> f64 {
    if n <= 1 {
        return 1.0;
    }
    let (mut lo, mut hi) = ((1e-12f64).ln(), 0.0f64);
    if tk_breaks_within(lo.exp(), gamma, n) {
        return lo.exp();
    }
    while hi - lo > 1e-10 {
        let mid = 0.5 * (lo + hi);
        if tk_breaks_within(mid.exp(), gamma, n) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi.exp()
}

/// ln of the ratio after one impact that does not break, ln g(x) = ln x − ln(1 − D(x)), with
/// the damage's fixed point started from `d0` (the neighbouring solve's); +∞ where the impact
/// breaks the particle (x ≥ 1 or no fixed point below 1).
fn ln_next(x: f64, gamma: f64, d0: f64) -> (f64, f64) {
    if x >= 1.0 {
        return (f64::INFINITY, d0);
    }
    match tk_damage_from(x, gamma, d0) {
        Some(d) => (x.ln() - (-d).ln_1p(), d),
        None => (f64::INFINITY, d0),
    }
}

/// x*(N, γ) for every N of `ns` in one backward sweep: the one-impact threshold x*(1) (the
/// smallest ratio one impact breaks) and x*(n + 1) = g⁻¹(x*(n)), g(x) = x/(1 − D(x)) the ratio
/// after an impact that does not break — a particle breaks within n + 1 impacts iff its ratio
/// after the first reaches x*(n), and g is increasing. Each step solves ln g(x) = ln x*(n) by the
/// Illinois method, bracketed from the previous step's decrement, to 1e-13 in ln x; the cost is
/// one short solve per impact up to the largest N (tens of milliseconds for 73 000 impacts) where
/// [`critical_ratio`] bisects whole paths per N. Agrees with [`critical_ratio`] (unit test);
/// values below 1e-12 are returned as 1e-12, as there.
pub fn critical_ratios(gamma: f64, ns: &[u64]) -> Vec<f64> {
    let floor = (1e-12f64).ln();
    let top = ns.iter().copied().max().unwrap_or(1).max(1);
    // x*(1): bisection in ln x of "one impact breaks".
    let breaks_once = |u: f64| ln_next(u.exp(), gamma, 0.0).0.is_infinite();
    let (mut lo, mut hi) = (floor, 0.0f64);
    while hi - lo > 1e-13 {
        let mid = 0.5 * (lo + hi);
        if breaks_once(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let mut u = hi;
    let mut at = vec![0.0; top as usize + 1];
    at[1] = u;
    let (mut step, mut d) = (1e-3f64, 0.0f64);
    for n in 1..top {
        if u <= floor {
            at[n as usize + 1] = floor;
            continue;
        }
        // f(v) = ln g(e^v) − u: negative at a, positive at b = u (g(x) > x).
        let mut f = |v: f64| {
            let (l, dd) = ln_next(v.exp(), gamma, d);
            d = dd;
            if l.is_finite() { l - u } else { 1e3 }
        };
        let (mut b, mut fb) = (u, f(u));
        let mut width = 2.0 * step.max(1e-300);
        let (mut a, mut fa) = (u - width, f(u - width));
        while fa >= 0.0 && a > floor {
            width *= 4.0;
            a = (u - width).max(floor);
            fa = f(a);
        }
        if fa >= 0.0 {
            // Below the floor: nothing left to resolve.
            u = floor;
            at[n as usize + 1] = u;
            continue;
        }
        let mut side = 0i8;
        let mut v = a;
        for _ in 0..200 {
            v = (a * fb - b * fa) / (fb - fa);
            let fv = f(v);
            if fv == 0.0 || (b - a) <= 1e-13 {
                break;
            }
            if fv < 0.0 {
                (a, fa) = (v, fv);
                if side == -1 {
                    fb *= 0.5;
                }
                side = -1;
            } else {
                (b, fb) = (v, fv);
                if side == 1 {
                    fa *= 0.5;
                }
                side = 1;
            }
            if (b - a) <= 1e-13 {
                v = if fa.abs() < fb.abs() { a } else { b };
                break;
            }
        }
        step = u - v;
        u = v.max(floor);
        at[n as usize + 1] = u;
    }
    ns.iter().map(|&n| at[n.max(1) as usize].exp()).collect()
}

/// x*(N, γ) tabulated over γ for one N (linear interpolation in γ): the Tavares–King fast path.
#[derive(Debug, Clone, PartialEq)]
pub struct CriticalRatioTable {
    /// Impacts N.
    pub n: u64,
    gamma: Vec<f64>,
    ln_x: Vec<f64>,
}

impl CriticalRatioTable {
    /// The table on `points` γ values spanning [lo, hi] (one backward sweep per γ, as
    /// [`CriticalRatioTable::for_impacts`]).
    pub fn new(n: u64, lo: f64, hi: f64, points: usize) -> CriticalRatioTable {
        Self::for_impacts(&[n], lo, hi, points).remove(0)
    }

    /// One table per N of `ns` on `points` γ values spanning [lo, hi], from one backward sweep
    /// per γ ([`critical_ratios`]): the tables of many horizons for the cost of the longest.
    pub fn for_impacts(ns: &[u64], lo: f64, hi: f64, points: usize) -> Vec<CriticalRatioTable> {
        use rayon::prelude::*;
        let points = points.max(2);
        let gamma: Vec<f64> = (0..points).map(|i| lo + (hi - lo) * i as f64 / (points - 1) as f64).collect();
        let sweeps: Vec<Vec<f64>> = gamma.par_iter().map(|&g| critical_ratios(g, ns)).collect();
        ns.iter().enumerate().map(|(k, &n)| CriticalRatioTable { n, gamma: gamma.clone(), ln_x: sweeps.iter().map(|s| s[k].ln()).collect() }).collect()
    }

    /// x*(N, γ) (γ clamped to the table).
    pub fn ratio(&self, gamma: f64) -> f64 {
        self.ln_ratio(gamma).exp()
    }

    /// ln x*(N, γ), linear in γ between the table's points (γ clamped to the table).
    pub fn ln_ratio(&self, gamma: f64) -> f64 {
        let (k, t) = crate::stats::locate(&self.gamma, gamma);
        crate::stats::lerp(&self.ln_x, (k, t.clamp(0.0, 1.0)))
    }
}

/// One damage model at modulus m and N impacts, its constants precomputed. Independent trials
/// and Tavares–King are both P_N = 1 − exp(−c H) (c = N, and c = x*^(−m/5)); Vogel–Peukert is
/// linear in the energy above its threshold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Law {
    /// 1 − exp(−c H).
    Scaled {
        /// c = N (independent trials) or x*(N, γ)^(−m/5) (Tavares–King).
        c: f64,
    },
    /// 1 − exp(−N f x W_θ (w − w_min)⁺) with w = H^(5/m).
    VogelPeukert {
        /// Impacts N.
        n: f64,
        /// The master curve in units of W_θ.
        curve: VogelPeukert,
        /// 5/m.
        exponent: f64,
        /// ln H below which w ≤ w_min (nothing breaks): (m/5) ln w_min.
        ln_h_min: f64,
    },
}

impl Law {
    /// Model `model` at modulus `m` after `n` impacts; `ln_x_star` = ln x*(N, γ) (read by
    /// Tavares–King only).
    pub fn new(model: DamageModel, m: f64, n: f64, ln_x_star: f64) -> Law {
        match model {
            DamageModel::Independent => Law::Scaled { c: n },
            DamageModel::VogelPeukert => {
                let curve = VogelPeukert::matched(m / 5.0);
                let ln_h_min = if curve.threshold > 0.0 { m / 5.0 * curve.threshold.ln() } else { f64::NEG_INFINITY };
                Law::VogelPeukert { n, curve, exponent: 5.0 / m, ln_h_min }
            }
            DamageModel::TavaresKing => Law::Scaled { c: (-m / 5.0 * ln_x_star).exp() },
        }
    }

    /// P_N for the single-impact hazard H = e^ln_h (both given: the caller has both).
    #[inline(always)]
    pub fn p(&self, h: f64, ln_h: f64) -> f64 {
        match *self {
            Law::Scaled { c } => breakage_from_hazard(h, c),
            Law::VogelPeukert { n, curve, exponent, ln_h_min } => {
                if ln_h <= ln_h_min {
                    0.0
                } else {
                    breakage_from_hazard(curve.hazard((exponent * ln_h).exp()), n)
                }
            }
        }
    }
}

/// P_N of a damage model from the single-impact hazard H = (W/W_θ)^(m/5) at modulus m after
/// `n` impacts; `x_star` = x*(N, γ) is read by Tavares–King only.
pub fn breakage(model: DamageModel, hazard: f64, m: f64, n: f64, x_star: f64) -> f64 {
    Law::new(model, m, n, x_star.ln()).p(hazard, hazard.ln())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vogel_peukert_matches_the_weibull_law_at_10_and_63_percent() {
        for k in [1.0, 1.5, 2.0, 3.0] {
            let vp = VogelPeukert::matched(k);
            // Weibull-in-energy hazard (w)^k at the 10 % and 63.2 % points.
            let w10 = (-(0.9f64).ln()).powf(1.0 / k);
            if vp.threshold > 0.0 {
                assert!((vp.hazard(w10) - (-(0.9f64).ln())).abs() < 1e-12, "k = {k}: {vp:?}");
            }
            assert!((vp.hazard(1.0) - 1.0).abs() < 1e-12, "k = {k}: {vp:?}");
        }
        // Hand-computed, k = 2 (m = 10): w10 = √0.1053605 = 0.3245929; rate = (1 − 0.1053605)
        // /(1 − 0.3245929) = 1.3245928; threshold = 0.3245929 − 0.1053605/1.3245928 = 0.2450510.
        let vp = VogelPeukert::matched(2.0);
        assert!((vp.rate - 1.3245928).abs() < 1e-6 && (vp.threshold - 0.2450510).abs() < 1e-6, "{vp:?}");
        // k = 1: the law is exponential in energy, the master curve is exact (no threshold).
        let vp = VogelPeukert::matched(1.0);
        assert!((vp.rate - 1.0).abs() < 1e-12 && vp.threshold.abs() < 1e-12);
        // Below the threshold nothing breaks, however many impacts.
        assert_eq!(breakage(DamageModel::VogelPeukert, 0.2f64.powi(2), 10.0, 1e6, 1.0), 0.0);
    }

    #[test]
    fn tavares_king_damage_by_hand() {
        // γ = 5, x = 0.5: D = [10/(15 − 5D) · 0.5]², i.e. D(15 − 5D)² = 25, the cubic
        // 25D³ − 150D² + 225D − 25 = 0, whose root below 1 is D = 0.1206148.
        let d = tk_damage(0.5, 5.0).unwrap();
        assert!((d * (15.0 - 5.0 * d).powi(2) - 25.0).abs() < 1e-9, "D = {d}");
        assert!((d - 0.1206148).abs() < 1e-6, "D = {d}");
        // Large γ: hardly any damage below x = 1.
        assert!(tk_damage(0.5, 200.0).unwrap() < 1e-20);
        // One impact: breaks iff x ≥ 1.
        assert!(tk_breaks_within(1.0, 5.0, 1) && !tk_breaks_within(0.999, 5.0, 1));
        // Two impacts at γ = 5: x0 = 0.9 → D = fixed point, x1 = 0.9/(1 − D) ≥ 1 iff D ≥ 0.1.
        let d = tk_damage(0.9, 5.0).unwrap();
        assert_eq!(tk_breaks_within(0.9, 5.0, 2), 0.9 / (1.0 - d) >= 1.0);
        // x* falls with N and rises towards 1 with γ.
        let (a, b) = (critical_ratio(5.0, 730), critical_ratio(5.0, 7300));
        assert!(a < 1.0 && b < a, "x*(730) = {a}, x*(7300) = {b}");
        assert!(critical_ratio(50.0, 730) > a);
        assert!(tk_breaks_within(a * 1.000001, 5.0, 730) && !tk_breaks_within(a * 0.99999, 5.0, 730));
        let table = CriticalRatioTable::new(730, 2.0, 8.0, 25);
        assert!((table.ratio(5.0) / a - 1.0).abs() < 1e-6, "{} vs {a}", table.ratio(5.0));
        assert!((table.ratio(5.1) / critical_ratio(5.1, 730) - 1.0).abs() < 0.02);
    }

    #[test]
    fn one_backward_sweep_gives_the_critical_ratio_of_every_n() {
        let ns = [2u64, 3, 10, 73, 730, 7300];
        for gamma in [2.0, 3.3, 5.0, 7.0, 20.0] {
            let sweep = critical_ratios(gamma, &ns);
            for (k, &n) in ns.iter().enumerate() {
                let exact = critical_ratio(gamma, n);
                assert!((sweep[k] / exact - 1.0).abs() < 1e-7, "γ {gamma}, N {n}: {} vs {exact}", sweep[k]);
            }
            // Non-increasing in N.
            assert!(sweep.windows(2).all(|w| w[1] <= w[0]), "γ {gamma}: {sweep:?}");
        }
    }

    #[test]
    fn independent_trials_are_the_geometric_law() {
        // P(survive n) = (1 − p)^n.
        let p: f64 = 1e-3;
        let h = -(1.0 - p).ln();
        for n in [1.0, 730.0, 7300.0] {
            let got = breakage(DamageModel::Independent, h, 10.0, n, 1.0);
            assert!((1.0 - got - (1.0 - p).powf(n)).abs() < 1e-12);
        }
        // Tavares–King without damage (x* = 1) is the single-impact probability.
        assert!((breakage(DamageModel::TavaresKing, h, 10.0, 7300.0, 1.0) - p).abs() < 1e-15);
    }
}

//! Two flaw populations: the two-component Weibull mixture and the competing-risks Weibull,
//! fitted by maximum likelihood from several starts, with non-identifiability reported instead
//! of a spurious optimum.
//!
//! ```text
//! mixture:         F(x) = p F₁(x) + (1 − p) F₂(x)                 (a specimen holds flaws of one kind)
//! competing risks: F(x) = 1 − exp[−(x/σ₁)^m₁ − (x/σ₂)^m₂]          (every specimen holds both kinds;
//!                                                                  the weaker link breaks)
//! F_j(x) = 1 − exp[−(x/σ_j)^m_j]
//! ```
//!
//! (Jiang & Murthy 1995, *Reliability Engineering & System Safety* 47, 187–198 for the mixture;
//! the competing-risks form is the weakest link of two independent flaw populations, as in
//! ASTM C1239 §8 for concurrent flaw distributions.)
//!
//! The likelihood is maximised over unconstrained coordinates — logit p, ln σ_j, ln m_j, with x
//! scaled by its median — by Nelder–Mead (argmin) from [`STARTS`] deterministic starts: the two
//! components split at the 20, 35, 50, 65 and 80 % quantiles, each half given its own Weibull
//! MLE, and from the one-population fit with a component two and five times weaker. Each start
//! is restarted until ℓ stops rising by 10⁻¹⁰.
//!
//! Moduli are kept in [[`M_MIN`], [`M_MAX`]]: a mixture's likelihood is unbounded as a component
//! collapses onto one specimen with m → ∞.
//!
//! **Non-identifiability** ([`FlawFit::identifiable`]): the fit is reported as not identified,
//! with the reason, when a modulus runs to the edge of that range, when a component carries less
//! than one specimen (mixture p·n < 1 or
//! (1 − p)·n < 1), when the two components are the same law (|ln σ₁ − ln σ₂| < 0.05 and
//! |ln m₁ − ln m₂| < 0.1), when two competing risks share one modulus (|ln m₁ − ln m₂| < 0.01:
//! together they are one Weibull law, a ridge of equal likelihood), when a competing risk never
//! acts on the data (its hazard below 1 % of the other's at every specimen), or when starts reach optima within 0.1 in ℓ whose laws differ
//! (several maxima). The naming loop never names a law so reported.
//!
//! In the naming loop ([`crate::discrepancy::workflow`]) a two-population law is a candidate
//! in place of the base law (`Effect::Populations`, 3 or 2 extra parameters): offered while
//! nothing is named, and the last effect once named (scale effects are not fitted beside it).
//!
//! Verified against the `reliability` package (tests/bench/reliability/fit.py) in
//! `tests/strength_factors.rs`, and by the unit tests below (a mixture and a competing-risks
//! sample recovered; a one-population sample reported as not identified).

use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use nalgebra::DVector;
use rand::Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::weibull::fit_mle;

/// Number of starts.
pub const STARTS: usize = 7;

/// Smallest modulus a population may take.
pub const M_MIN: f64 = 0.5;

/// Largest modulus a population may take: beyond any brittle material's scatter (technical
/// ceramics and glass fibres: m ≈ 3–40).
pub const M_MAX: f64 = 100.0;

/// Which two-population law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Populations {
    /// Two-component Weibull mixture (5 parameters).
    Mixture,
    /// Competing-risks Weibull (4 parameters).
    #[serde(rename = "competing_risks")]
    Competing,
}

impl Populations {
    /// Parameters of the law.
    pub fn parameters(self) -> usize {
        match self {
            Populations::Mixture => 5,
            Populations::Competing => 4,
        }
    }

    /// Words.
    pub fn label(self) -> &'static str {
        match self {
            Populations::Mixture => "two flaw populations, one per specimen (Weibull mixture)",
            Populations::Competing => "two flaw populations in every specimen (competing risks)",
        }
    }

    /// Its equation.
    pub fn equation(self) -> &'static str {
        match self {
            Populations::Mixture => "F(x) = p F₁(x) + (1 − p) F₂(x), F_j = 1 − exp[−(x/σ_j)^m_j]",
            Populations::Competing => "F(x) = 1 − exp[−(x/σ₁)^m₁ − (x/σ₂)^m₂]",
        }
    }

    /// Key.
    pub fn name(self) -> &'static str {
        match self {
            Populations::Mixture => "mixture",
            Populations::Competing => "competing_risks",
        }
    }
}

/// A fitted two-population law (strengths in the data's own units).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlawFit {
    /// The law.
    pub kind: Populations,
    /// Mixture weight of population 1 (1 for competing risks).
    pub p: f64,
    /// (scale, modulus) of population 1 (the weaker scale).
    pub first: (f64, f64),
    /// (scale, modulus) of population 2.
    pub second: (f64, f64),
    /// Maximised log-likelihood (density of x in its own units).
    pub loglik: f64,
    /// Ok, or why the two populations are not identified by these data.
    pub identifiable: std::result::Result<(), String>,
}

fn ln_weibull_pdf(x: f64, s: f64, m: f64) -> f64 {
    let z = x / s;
    m.ln() - s.ln() + (m - 1.0) * z.ln() - z.powf(m)
}

/// Log-likelihood at unconstrained θ for x scaled by its median.
fn loglik_at(kind: Populations, x: &[f64], t: &[f64]) -> f64 {
    let l: f64 = match kind {
        Populations::Mixture => {
            let lp = -(1.0 + (-t[0]).exp()).ln();
            let lq = -(1.0 + t[0].exp()).ln();
            let (s1, m1, s2, m2) = (t[1].exp(), t[2].exp(), t[3].exp(), t[4].exp());
            x.iter()
                .map(|&v| {
                    let a = lp + ln_weibull_pdf(v, s1, m1);
                    let b = lq + ln_weibull_pdf(v, s2, m2);
                    let hi = a.max(b);
                    hi + ((a - hi).exp() + (b - hi).exp()).ln()
                })
                .sum()
        }
        Populations::Competing => {
            let (s1, m1, s2, m2) = (t[0].exp(), t[1].exp(), t[2].exp(), t[3].exp());
            x.iter()
                .map(|&v| {
                    let (z1, z2) = (v / s1, v / s2);
                    let h = m1 / s1 * z1.powf(m1 - 1.0) + m2 / s2 * z2.powf(m2 - 1.0);
                    h.ln() - z1.powf(m1) - z2.powf(m2)
                })
                .sum()
        }
    };
    if l.is_finite() { l } else { f64::NEG_INFINITY }
}

struct Nll<'a> {
    kind: Populations,
    x: &'a [f64],
}

impl CostFunction for Nll<'_> {
    type Param = DVector<f64>;
    type Output = f64;
    fn cost(&self, t: &Self::Param) -> std::result::Result<f64, argmin::core::Error> {
        // Keep the search in a sane box: scales within e^±20 of the median, moduli in
        // [M_MIN, M_MAX] (a mixture's likelihood is unbounded as a component collapses onto one
        // specimen with m → ∞; the box keeps such spikes out, and a fit on its edge is reported).
        let moduli: &[usize] = if self.kind == Populations::Mixture { &[2, 4] } else { &[1, 3] };
        if t.iter().enumerate().any(|(k, v)| !v.is_finite() || v.abs() > if self.kind == Populations::Mixture && k == 0 { 30.0 } else { 20.0 })
            || moduli.iter().any(|&k| t[k] < M_MIN.ln() || t[k] > M_MAX.ln())
        {
            return Ok(1e300);
        }
        let l = loglik_at(self.kind, self.x, t.as_slice());
        Ok(if l.is_finite() { -l } else { 1e300 })
    }
}

fn nelder_mead(kind: Populations, x: &[f64], start: &[f64]) -> Result<(Vec<f64>, f64)> {
    let mut best = (start.to_vec(), loglik_at(kind, x, start));
    for _ in 0..20 {
        let s = DVector::from_vec(best.0.clone());
        let mut simplex = vec![s.clone()];
        for k in 0..s.len() {
            let mut p = s.clone();
            p[k] += 0.3;
            simplex.push(p);
        }
        let solver = NelderMead::new(simplex).with_sd_tolerance(1e-10).map_err(|e| Error::numerical("flaw populations", e.to_string()))?;
        let res = Executor::new(Nll { kind, x }, solver).configure(|c| c.max_iters(4000)).run().map_err(|e| Error::numerical("flaw populations", e.to_string()))?;
        let Some(p) = res.state().get_best_param().cloned() else { break };
        let l = loglik_at(kind, x, p.as_slice());
        let gain = l - best.1;
        if l > best.1 {
            best = (p.as_slice().to_vec(), l);
        }
        if !(gain > 1e-10) {
            break;
        }
    }
    Ok(best)
}

/// Fits a two-population law to strengths `x` (all > 0): the best of [`STARTS`] starts, with
/// the identifiability verdict.
pub fn fit(kind: Populations, x: &[f64]) -> Result<FlawFit> {
    let n = x.len();
    if n < 10 {
        return Err(Error::numerical("flaw populations", format!("{n} specimens are too few for a two-population law (at least 10)")));
    }
    if let Some(v) = x.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        return Err(Error::numerical("flaw populations", format!("strengths must be finite and > 0 (got {v})")));
    }
    let mut sorted = x.to_vec();
    sorted.sort_by(f64::total_cmp);
    let med = crate::stats::median(x);
    let xs: Vec<f64> = x.iter().map(|v| v / med).collect();
    let sorted_s: Vec<f64> = sorted.iter().map(|v| v / med).collect();
    let one = fit_mle(&xs)?.mle;
    // Starts: splits at quantiles, each part's own MLE; the one-population fit with a weaker
    // second population.
    let mut starts: Vec<[f64; 5]> = Vec::new();
    for q in [0.2, 0.35, 0.5, 0.65, 0.8] {
        let k = ((q * n as f64) as usize).clamp(3, n - 3);
        let (lo, hi) = (fit_mle(&sorted_s[..k]), fit_mle(&sorted_s[k..]));
        if let (Ok(lo), Ok(hi)) = (lo, hi) {
            starts.push([q, lo.mle.scale, lo.mle.shape, hi.mle.scale, hi.mle.shape]);
        }
    }
    for f in [0.5, 0.2] {
        starts.push([0.2, one.scale * f, one.shape, one.scale, one.shape]);
    }
    let mut optima: Vec<(Vec<f64>, f64)> = Vec::new();
    for st in &starts {
        let t: Vec<f64> = match kind {
            Populations::Mixture => vec![(st[0] / (1.0 - st[0])).ln(), st[1].ln(), st[2].clamp(M_MIN * 1.01, M_MAX * 0.99).ln(), st[3].ln(), st[4].clamp(M_MIN * 1.01, M_MAX * 0.99).ln()],
            Populations::Competing => vec![st[1].ln(), st[2].clamp(M_MIN * 1.01, M_MAX * 0.99).ln(), st[3].ln(), st[4].clamp(M_MIN * 1.01, M_MAX * 0.99).ln()],
        };
        let (t, l) = nelder_mead(kind, &xs, &t)?;
        if l.is_finite() {
            optima.push((t, l));
        }
    }
    let Some(best) = optima.iter().max_by(|a, b| a.1.total_cmp(&b.1)).cloned() else {
        return Err(Error::numerical("flaw populations", "no start reached a finite likelihood"));
    };
    let law = |t: &[f64]| -> (f64, (f64, f64), (f64, f64)) {
        let (p, a, b) = match kind {
            Populations::Mixture => (1.0 / (1.0 + (-t[0]).exp()), (t[1].exp() * med, t[2].exp()), (t[3].exp() * med, t[4].exp())),
            Populations::Competing => (1.0, (t[0].exp() * med, t[1].exp()), (t[2].exp() * med, t[3].exp())),
        };
        // Population 1 is the one with the weaker scale.
        if a.0 <= b.0 { (p, a, b) } else { (if kind == Populations::Mixture { 1.0 - p } else { 1.0 }, b, a) }
    };
    let (p, first, second) = law(&best.0);
    let same = |a: (f64, f64), b: (f64, f64)| (a.0.ln() - b.0.ln()).abs() < 0.05 && (a.1.ln() - b.1.ln()).abs() < 0.1;
    let mut why: Option<String> = None;
    if let Some(m) = [first.1, second.1].into_iter().find(|m| *m > 0.98 * M_MAX || *m < 1.02 * M_MIN) {
        why = Some(format!("a population's modulus runs to the edge of [{M_MIN}, {M_MAX}] (m = {m:.2}): a spike on a few specimens, not a flaw population"));
    } else if kind == Populations::Mixture && (p * n as f64) < 1.0 {
        why = Some(format!("the weaker population holds {:.2} of {n} specimens", p * n as f64));
    } else if kind == Populations::Mixture && ((1.0 - p) * n as f64) < 1.0 {
        why = Some(format!("the stronger population holds {:.2} of {n} specimens", (1.0 - p) * n as f64));
    } else if same(first, second) {
        why = Some(format!("the two populations are the same law (scales {:.4} and {:.4}, moduli {:.2} and {:.2})", first.0, second.0, first.1, second.1));
    } else if kind == Populations::Competing && (first.1.ln() - second.1.ln()).abs() < 0.01 {
        why = Some(format!("the two risks have the same modulus ({:.3} and {:.3}), so together they are one Weibull law (σ^(−m) = σ₁^(−m) + σ₂^(−m)) and any split of its scale fits equally", first.1, second.1));
    } else if kind == Populations::Competing {
        let h = |x: f64, (s, m): (f64, f64)| m / s * (x / s).powf(m - 1.0);
        for (name, a, b) in [("first", first, second), ("second", second, first)] {
            if x.iter().all(|&v| h(v, a) < 0.01 * h(v, b)) {
                why = Some(format!("the {name} risk never acts on these data (its hazard is below 1 % of the other's at every specimen)"));
            }
        }
    }
    if why.is_none() {
        for (t, l) in &optima {
            let (q, a, b) = law(t);
            let differs = !(same(a, first) && same(b, second) && (q - p).abs() < 0.02);
            if best.1 - l < 0.1 && differs {
                let weight = if kind == Populations::Mixture { format!("p = {q:.3}, ") } else { String::new() };
                why = Some(format!("several maxima: a start reaches ℓ within {:.3} of the best with another law ({weight}scales {:.4} and {:.4}, moduli {:.2} and {:.2})", best.1 - l, a.0, b.0, a.1, b.1));
                break;
            }
        }
    }
    Ok(FlawFit { kind, p, first, second, loglik: best.1 - n as f64 * med.ln(), identifiable: why.map_or(Ok(()), Err) })
}

impl FlawFit {
    /// Log density at x (in the data's units).
    pub fn ln_pdf(&self, x: f64) -> f64 {
        match self.kind {
            Populations::Mixture => {
                let a = self.p.ln() + ln_weibull_pdf(x, self.first.0, self.first.1);
                let b = (1.0 - self.p).ln() + ln_weibull_pdf(x, self.second.0, self.second.1);
                let hi = a.max(b);
                hi + ((a - hi).exp() + (b - hi).exp()).ln()
            }
            Populations::Competing => {
                let (z1, z2) = (x / self.first.0, x / self.second.0);
                let h = self.first.1 / self.first.0 * z1.powf(self.first.1 - 1.0) + self.second.1 / self.second.0 * z2.powf(self.second.1 - 1.0);
                h.ln() - z1.powf(self.first.1) - z2.powf(self.second.1)
            }
        }
    }

    /// The fitted law in words (strengths in the data's units, Pa for a strength file).
    pub fn describe(&self) -> String {
        let pop = |(s, m): (f64, f64)| format!("σ = {:.1} MPa, m = {m:.2}", s / 1e6);
        match self.kind {
            Populations::Mixture => format!("{:.1} % of specimens with {} (weaker), {:.1} % with {}", 100.0 * self.p, pop(self.first), 100.0 * (1.0 - self.p), pop(self.second)),
            Populations::Competing => format!("every specimen holds both flaw populations: {} and {}", pop(self.first), pop(self.second)),
        }
    }

    /// CDF at x.
    pub fn cdf(&self, x: f64) -> f64 {
        let h = |(s, m): (f64, f64)| (x / s).powf(m);
        match self.kind {
            Populations::Mixture => self.p * -(-h(self.first)).exp_m1() + (1.0 - self.p) * -(-h(self.second)).exp_m1(),
            Populations::Competing => -(-h(self.first) - h(self.second)).exp_m1(),
        }
    }

    /// One draw by inversion of the CDF (bisection in ln x).
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let u: f64 = rng.random::<f64>().clamp(1e-300, 1.0 - 1e-16);
        let (mut lo, mut hi) = ((self.first.0.min(self.second.0) * 1e-6).ln(), (self.first.0.max(self.second.0) * 1e3).ln());
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if self.cdf(mid.exp()) < u { lo = mid } else { hi = mid }
        }
        (0.5 * (lo + hi)).exp()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn a_mixture_and_competing_risks_are_recovered_and_one_population_is_not_identified() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mix = FlawFit { kind: Populations::Mixture, p: 0.3, first: (1.0, 12.0), second: (2.0, 10.0), loglik: 0.0, identifiable: Ok(()) };
        let x: Vec<f64> = (0..600).map(|_| mix.sample(&mut rng)).collect();
        let f = fit(Populations::Mixture, &x).unwrap();
        assert!(f.identifiable.is_ok(), "{f:?}");
        assert!((f.p - 0.3).abs() < 0.06 && (f.first.0 - 1.0).abs() < 0.05 && (f.second.0 - 2.0).abs() < 0.05, "{f:?}");
        let cr = FlawFit { kind: Populations::Competing, p: 1.0, first: (1.0, 3.0), second: (1.3, 20.0), loglik: 0.0, identifiable: Ok(()) };
        let x: Vec<f64> = (0..800).map(|_| cr.sample(&mut rng)).collect();
        let f = fit(Populations::Competing, &x).unwrap();
        assert!(f.identifiable.is_ok(), "{f:?}");
        assert!((f.first.1 - 3.0).abs() < 0.6 && (f.second.1 - 20.0).abs() < 8.0, "{f:?}");
        // One Weibull population fitted as a mixture.
        let one = FlawFit { kind: Populations::Competing, p: 1.0, first: (1.0, 8.0), second: (1.0, 8.0), loglik: 0.0, identifiable: Ok(()) };
        let y: Vec<f64> = (0..400).map(|_| one.sample(&mut rng)).collect();
        let g = fit(Populations::Mixture, &y).unwrap();
        assert!(g.identifiable.is_err(), "one Weibull population must not be reported as two: {g:?}");
    }
}

//! Laws in place of the one two-parameter Weibull law: two flaw populations — the two-component
//! Weibull mixture and the competing-risks Weibull — and a threshold strength (the
//! three-parameter Weibull), fitted by maximum likelihood from several starts, with
//! non-identifiability reported instead of a spurious optimum.
//!
//! ```text
//! mixture:         F(x) = p F₁(x) + (1 − p) F₂(x)                 (a specimen holds flaws of one kind)
//! competing risks: F(x) = 1 − exp[−(x/σ₁)^m₁ − (x/σ₂)^m₂]          (every specimen holds both kinds;
//!                                                                  the weaker link breaks)
//! threshold:       F(x) = 1 − exp[−((x − γ)/σ)^m] for x > γ ≥ 0   (no specimen breaks below γ)
//! F_j(x) = 1 − exp[−(x/σ_j)^m_j]
//! ```
//!
//! **The threshold law's likelihood pathology and how it is handled.** With exact strengths the
//! three-parameter likelihood is unbounded as γ reaches the smallest strength x₍₁₎ when m < 1
//! (the density (m/σ)((x₍₁₎ − γ)/σ)^(m−1) grows without bound); for m ≥ 1 it is bounded (Smith
//! 1985, *Biometrika* 72, 67–90: regular for m > 2, a maximum exists for 1 ≤ m ≤ 2). partlife
//! uses the **restricted maximum likelihood** m ≥ 1 — the search box's lower modulus for this
//! law ([`Populations::m_min`]) — and reports a fit that reaches m = 1, or whose γ runs onto the
//! smallest value a break was recorded at, as not identified (no interior maximum), so the naming
//! loop never names it; the band it reports for γ is the **profile-likelihood** interval
//! ([`FlawFit::profile_band`]). Classes and censored rows need no correction: a class's
//! probability is bounded. γ ≥ 0 (a negative threshold is no strength); γ → 0 is the
//! two-parameter law, so the threshold law nests it with one extra parameter.
//!
//! (Jiang & Murthy 1995, *Reliability Engineering & System Safety* 47, 187–198 for the mixture;
//! the competing-risks form is the weakest link of two independent flaw populations whose
//! origins are not observed — the latent two-fold competing-risk Weibull model of Murthy, Xie &
//! Jiang 2004, *Weibull Models*, Wiley, ch. 9. ASTM C1239's concurrent flaw distributions are
//! the same law with each specimen's origin known from fractography, each population fitted
//! with the others' breaks censored: that is [`crate::strength::origins`], where a study
//! declares the origin column, not this fit.)
//!
//! The likelihood is maximised over unconstrained coordinates — logit p, ln σ_j, ln m_j, with x
//! scaled by its median — by a box-constrained BFGS with the analytic gradient (below) from
//! [`STARTS`] deterministic starts: the two components split at the 20, 35, 50, 65 and 80 %
//! quantiles, each half given its own Weibull MLE, and the one-population fit with a component
//! two and five times weaker (the likelihood, its gradient and the rows that do not say a
//! break: [`likelihood`]). The starts split the rows' points ([`crate::obs::Obs::point`]) as if
//! they were breaks; only the starts do.
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
//! **Beside scale effects** ([`fit_shifted`]): recorded columns that act on the scale (a numeric
//! factor's ln-linear or power column, a scale per level) shift both populations alike,
//! ln σ_j,i = ln σ_j + Σ_k β_k z_k,i, so ℓ_i = ℓ_law(ln x_i − η_i) − η_i with η_i = Σ_k β_k z_k,i and
//! ∂ℓ_i/∂β_k = z_k,i Σ_j ∂ℓ_i/∂ ln σ_j; the β are fitted jointly with the law (starts at the
//! one-law regression's β). A modulus per level, pooled levels and damage are not fitted
//! beside a law.
//!
//! The search finds the local maxima these starts lead to; the degenerate spikes where a
//! component collapses onto a few specimens (the likelihood is unbounded there) are not sought,
//! and a fit that reaches the modulus bound is reported as not identified.
//!
//! The threshold law starts from γ at 0, 50, 80, 90, 95 and 99 % of the smallest value a
//! threshold must stay below, each with the Weibull MLE of the points less γ. Beside scale
//! effects its γ scales with the row like σ (x_i = e^(η_i) X).
//!
//! In the naming loop ([`crate::discrepancy::workflow`]) a law is a candidate in place of the
//! base law (`Effect::Populations`, 3, 2 or 1 extra parameters): offered while
//! every named effect is such a scale effect; once named, only such scale effects remain
//! candidates.
//!
//! Verified against the `reliability` package (tests/bench/reliability/fit.py) in
//! `tests/strength_factors.rs`; the threshold law against surpyval's three-parameter fits of
//! Weibull's (1951) Bofors steel table, exact and as classes (tests/bench/reliability/bofors.py,
//! `tests/censoring.rs`, log-likelihoods to 1e-6); and by the unit tests below (a mixture, a
//! competing-risks and a threshold sample recovered, censored rows included; a one-population
//! sample reported as not identified).

use rand::Rng;
use serde::{Deserialize, Serialize};

mod likelihood;

use likelihood::{Rows, log_sum_and_shares, loglik_grad, scaled, shift_at};
use crate::error::{Error, Result};
use crate::obs::Obs;
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
    /// A threshold strength below which no specimen breaks: the three-parameter Weibull
    /// (3 parameters).
    Threshold,
}

impl Populations {
    /// Parameters of the law.
    pub fn parameters(self) -> usize {
        match self {
            Populations::Mixture => 5,
            Populations::Competing => 4,
            Populations::Threshold => 3,
        }
    }

    /// Words.
    pub fn label(self) -> &'static str {
        match self {
            Populations::Mixture => "two flaw populations, one per specimen (Weibull mixture)",
            Populations::Competing => "two flaw populations in every specimen (competing risks)",
            Populations::Threshold => "a threshold strength below which no specimen breaks (three-parameter Weibull)",
        }
    }

    /// Its equation.
    pub fn equation(self) -> &'static str {
        match self {
            Populations::Mixture => "F(x) = p F₁(x) + (1 − p) F₂(x), F_j = 1 − exp[−(x/σ_j)^m_j]",
            Populations::Competing => "F(x) = 1 − exp[−(x/σ₁)^m₁ − (x/σ₂)^m₂]",
            Populations::Threshold => "F(x) = 1 − exp[−((x − γ)/σ)^m] for x > γ, 0 below",
        }
    }

    /// Key.
    pub fn name(self) -> &'static str {
        match self {
            Populations::Mixture => "mixture",
            Populations::Competing => "competing_risks",
            Populations::Threshold => "threshold",
        }
    }

    /// Smallest modulus the law's search allows: [`M_MIN`] for two populations, 1 for the
    /// threshold law (module docs: its likelihood is unbounded as γ reaches the smallest
    /// strength only when m < 1).
    pub fn m_min(self) -> f64 {
        if self == Populations::Threshold { 1.0 } else { M_MIN }
    }

    /// What the laws in `kinds` are, in words for a sentence: "two flaw populations (mixture,
    /// competing risks)", "a threshold", or both.
    pub fn words(kinds: &[Populations]) -> String {
        let two: Vec<&str> = kinds.iter().filter(|k| **k != Populations::Threshold).map(|k| if *k == Populations::Mixture { "mixture" } else { "competing risks" }).collect();
        let mut parts = Vec::new();
        if !two.is_empty() {
            parts.push(format!("two flaw populations ({})", two.join(", ")));
        }
        if kinds.contains(&Populations::Threshold) {
            parts.push("a threshold strength (three-parameter Weibull)".to_string());
        }
        parts.join(" or ")
    }
}

/// A fitted two-population law (strengths in the data's own units).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlawFit {
    /// The law.
    pub kind: Populations,
    /// Mixture weight of population 1 (1 for competing risks and the threshold law).
    pub p: f64,
    /// (scale, modulus) of population 1 (the weaker scale; the threshold law's one population).
    pub first: (f64, f64),
    /// (scale, modulus) of population 2 (the threshold law: equal to `first`).
    pub second: (f64, f64),
    /// The threshold law's γ, the strength below which none breaks (0 for two populations).
    #[serde(skip_serializing_if = "is_zero")]
    pub threshold: f64,
    /// Coefficients of the scale effects fitted beside the law (row i's scales × e^(Σ β_k z_k,i);
    /// empty without).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub beta: Vec<f64>,
    /// Maximised log-likelihood (density of x in its own units).
    pub loglik: f64,
    /// Ok, or why the two populations are not identified by these data.
    pub identifiable: std::result::Result<(), String>,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn ln_weibull_pdf(x: f64, s: f64, m: f64) -> f64 {
    let z = x / s;
    m.ln() - s.ln() + (m - 1.0) * z.ln() - z.powf(m)
}

/// The box the search stays in: scales within e^±20 of the median, the mixture's logit weight
/// within ±30, moduli in [[`Populations::m_min`], [`M_MAX`]], the threshold's ln γ within ±20
/// as well (γ = 2·10⁻⁹ of the median is the two-parameter law; a γ at or above a break has
/// ℓ = −∞), each of `columns` scale coefficients within ±20.
fn bounds(kind: Populations, columns: usize) -> Vec<(f64, f64)> {
    let (s, m) = ((-20.0, 20.0), (kind.m_min().ln(), M_MAX.ln()));
    let mut b = match kind {
        Populations::Mixture => vec![(-30.0, 30.0), s, m, s, m],
        Populations::Competing => vec![s, m, s, m],
        Populations::Threshold => vec![s, s, m],
    };
    b.extend(std::iter::repeat_n(s, columns));
    b
}

/// Maximises the likelihood from `start` by a projected BFGS with the analytic gradient and an
/// Armijo backtracking line search, inside [`bounds`]: coordinates on a bound whose gradient
/// points out of the box are held there (the active set), and the inverse-Hessian estimate is
/// reset whenever the active set changes. Stops when the free gradient is below 10⁻⁹ per
/// specimen or three steps in a row gain less than 10⁻¹³ |ℓ|.
fn bfgs(kind: Populations, rows: &Rows, z: &[Vec<f64>], start: &[f64], b: &[(f64, f64)]) -> (Vec<f64>, f64) {
    let k = b.len();
    let n = rows.lnx.len() as f64;
    let project = |t: &mut [f64]| t.iter_mut().zip(b).for_each(|(v, (lo, hi))| *v = v.clamp(*lo, *hi));
    let mut t = start.to_vec();
    project(&mut t);
    let mut g = vec![0.0; k];
    let mut l = loglik_grad(kind, rows, z, &t, &mut g);
    if !l.is_finite() {
        return (t, l);
    }
    let active = |t: &[f64], g: &[f64]| -> Vec<bool> { (0..k).map(|i| b[i].0 == b[i].1 || (t[i] <= b[i].0 && g[i] < 0.0) || (t[i] >= b[i].1 && g[i] > 0.0)).collect() };
    let identity = |s: f64| -> Vec<f64> { (0..k * k).map(|i| if i % (k + 1) == 0 { s } else { 0.0 }).collect() };
    let mut h = identity(1.0 / n);
    let mut act = active(&t, &g);
    let (mut g_new, mut t_new) = (vec![0.0; k], vec![0.0; k]);
    let mut stalled = 0;
    for _ in 0..2000 {
        let free: Vec<f64> = (0..k).map(|i| if act[i] { 0.0 } else { g[i] }).collect();
        if free.iter().all(|v| v.abs() <= 1e-9 * n) {
            break;
        }
        // Ascent direction d = H g on the free coordinates.
        let mut d: Vec<f64> = (0..k).map(|i| if act[i] { 0.0 } else { (0..k).map(|j| h[i * k + j] * free[j]).sum() }).collect();
        let mut slope: f64 = d.iter().zip(&free).map(|(a, b)| a * b).sum();
        if !(slope > 0.0) {
            h = identity(1.0 / n);
            d = free.iter().map(|v| v / n).collect();
            slope = d.iter().zip(&free).map(|(a, b)| a * b).sum();
        }
        let mut alpha = 1.0;
        let mut accepted = None;
        for _ in 0..60 {
            for i in 0..k {
                t_new[i] = t[i] + alpha * d[i];
            }
            project(&mut t_new);
            let l_new = loglik_grad(kind, rows, z, &t_new, &mut g_new);
            let gained: f64 = t_new.iter().zip(&t).zip(&free).map(|((a, b), gi)| (a - b) * gi).sum();
            if l_new.is_finite() && l_new >= l + 1e-4 * gained.min(alpha * slope) {
                accepted = Some(l_new);
                break;
            }
            alpha *= 0.5;
        }
        let Some(l_new) = accepted else { break };
        let s: Vec<f64> = (0..k).map(|i| t_new[i] - t[i]).collect();
        // y of the minimisation of −ℓ.
        let y: Vec<f64> = (0..k).map(|i| g[i] - g_new[i]).collect();
        let gain = l_new - l;
        t.copy_from_slice(&t_new);
        g.copy_from_slice(&g_new);
        l = l_new;
        let act_new = active(&t, &g);
        if act_new != act {
            act = act_new;
            h = identity(1.0 / n);
        } else {
            let ys: f64 = y.iter().zip(&s).map(|(a, b)| a * b).sum();
            let yy: f64 = y.iter().map(|v| v * v).sum();
            if ys > 1e-12 * yy.sqrt() * s.iter().map(|v| v * v).sum::<f64>().sqrt() {
                let rho = 1.0 / ys;
                // H ← (I − ρ s yᵀ) H (I − ρ y sᵀ) + ρ s sᵀ
                let hy: Vec<f64> = (0..k).map(|i| (0..k).map(|j| h[i * k + j] * y[j]).sum()).collect();
                let yhy: f64 = y.iter().zip(&hy).map(|(a, b)| a * b).sum();
                for i in 0..k {
                    for j in 0..k {
                        h[i * k + j] += rho * ((1.0 + rho * yhy) * s[i] * s[j] - hy[i] * s[j] - s[i] * hy[j]);
                    }
                }
            }
        }
        stalled = if gain < 1e-13 * l.abs().max(1.0) { stalled + 1 } else { 0 };
        if stalled == 3 {
            break;
        }
    }
    (t, l)
}

/// Fits a two-population law to strengths `x` (all > 0): the best of [`STARTS`] starts, with
/// the identifiability verdict.
pub fn fit(kind: Populations, x: Obs) -> Result<FlawFit> {
    fit_shifted(kind, x, &[])
}

/// [`fit`] with both populations' scales shifted row by row by the scale effects of the columns
/// `z` (ln σ_j,i = ln σ_j + Σ_k β_k z_k,i: a batch or a loading rate acts on every flaw alike).
/// The starts put β at the one-law Weibull regression's and split the strengths so adjusted.
pub fn fit_shifted(kind: Populations, x: Obs, z: &[Vec<f64>]) -> Result<FlawFit> {
    let n = x.len();
    if n < 10 {
        return Err(Error::numerical("flaw populations", format!("{n} specimens are too few for a two-population law (at least 10)")));
    }
    if let Some(v) = x.x.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
        return Err(Error::numerical("flaw populations", format!("strengths must be finite and > 0 (got {v})")));
    }
    // The one-law regression's β, and the rows' points adjusted by it (the starts only).
    let beta0: Vec<f64> = if z.is_empty() { Vec::new() } else { crate::strength::regress::fit(x, &crate::strength::regress::Design { columns: z, ..Default::default() })?.beta };
    let adjusted: Vec<f64> = (0..n).map(|i| x.point(i) * (-shift_at(z, &beta0, i)).exp()).collect();
    let mut sorted = adjusted.clone();
    sorted.sort_by(f64::total_cmp);
    let med = crate::stats::median(&adjusted);
    let xs: Vec<f64> = adjusted.iter().map(|v| v / med).collect();
    let sorted_s: Vec<f64> = sorted.iter().map(|v| v / med).collect();
    let one = fit_mle(&xs)?.mle;
    let (lnx, kinds, lnu) = scaled(x, med);
    let rows = Rows { lnx: &lnx, kind: &kinds, lnu: &lnu };
    let k0 = kind.parameters();
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
    // The threshold law: γ at 0, 50, 80, 90, 95 and 99 % of the smallest value a threshold must
    // stay below (a break, a left-censored value, a class's upper end), σ and m from the
    // Weibull MLE of the points less γ.
    if kind == Populations::Threshold {
        let cap = below_threshold(x, z, &beta0, med);
        starts.clear();
        for q in [0.0, 0.5, 0.8, 0.9, 0.95, 0.99] {
            let g = if cap.is_finite() { q * cap } else { 0.0 };
            let rest: Vec<f64> = xs.iter().map(|v| v - g).filter(|v| *v > 0.0).collect();
            if let Ok(w) = fit_mle(&rest) {
                starts.push([g.max(1e-8), w.mle.scale, w.mle.shape, 0.0, 0.0]);
            }
        }
    }
    let mut optima: Vec<(Vec<f64>, f64)> = Vec::new();
    for st in &starts {
        let mut t: Vec<f64> = match kind {
            Populations::Mixture => vec![(st[0] / (1.0 - st[0])).ln(), st[1].ln(), st[2].clamp(M_MIN * 1.01, M_MAX * 0.99).ln(), st[3].ln(), st[4].clamp(M_MIN * 1.01, M_MAX * 0.99).ln()],
            Populations::Competing => vec![st[1].ln(), st[2].clamp(M_MIN * 1.01, M_MAX * 0.99).ln(), st[3].ln(), st[4].clamp(M_MIN * 1.01, M_MAX * 0.99).ln()],
            Populations::Threshold => vec![st[0].ln(), st[1].ln(), st[2].clamp(1.01, M_MAX * 0.99).ln()],
        };
        t.extend(&beta0);
        let (t, l) = bfgs(kind, &rows, z, &t, &bounds(kind, z.len()));
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
            // The threshold law's γ in place of the weight.
            Populations::Threshold => (t[0].exp() * med, (t[1].exp() * med, t[2].exp()), (t[1].exp() * med, t[2].exp())),
        };
        // Population 1 is the one with the weaker scale.
        if a.0 <= b.0 { (p, a, b) } else { (if kind == Populations::Mixture { 1.0 - p } else { 1.0 }, b, a) }
    };
    let (p, first, second) = law(&best.0);
    let (p, threshold) = if kind == Populations::Threshold { (1.0, p) } else { (p, 0.0) };
    let beta = best.0[k0..].to_vec();
    // The identifiability checks look at the rows' points with the fitted shifts taken out.
    let exact_rows = (0..n).filter(|&i| rows.exact(i)).count();
    // The smallest value a threshold must stay below, with the fitted shifts taken out.
    let lowest = below_threshold(x, z, &beta, 1.0);
    let x: Vec<f64> = (0..n).map(|i| x.point(i) * (-shift_at(z, &beta, i)).exp()).collect();
    let same = |a: (f64, f64), b: (f64, f64)| (a.0.ln() - b.0.ln()).abs() < 0.05 && (a.1.ln() - b.1.ln()).abs() < 0.1;
    let mut why: Option<String> = None;
    if kind == Populations::Threshold {
        if first.1 > 0.98 * M_MAX || first.1 < 1.02 {
            why = Some(format!("the modulus runs to the edge of [1, {M_MAX}] (m = {:.2}): the threshold law's likelihood has no interior maximum", first.1));
        } else if threshold > 0.999 * lowest {
            why = Some(format!("the threshold runs onto the smallest strength ({threshold:.4e} against {lowest:.4e}): no interior maximum"));
        } else if threshold < 1e-3 * lowest {
            why = Some(format!("the threshold is at zero ({threshold:.3e}): the two-parameter Weibull law"));
        }
    } else if let Some(m) = [first.1, second.1].into_iter().find(|m| *m > 0.98 * M_MAX || *m < 1.02 * M_MIN) {
        why = Some(format!("a population's modulus runs to the edge of [{M_MIN}, {M_MAX}] (m = {m:.2}): a spike on a few specimens, not a flaw population"));
    } else if kind == Populations::Mixture && (p * n as f64) < 1.0 {
        why = Some(format!("the weaker population holds {:.2} of {n} specimens", p * n as f64));
    } else if kind == Populations::Mixture && ((1.0 - p) * n as f64) < 1.0 {
        why = Some(format!("the stronger population holds {:.2} of {n} specimens", (1.0 - p) * n as f64));
    } else if kind == Populations::Competing && (first.1.ln() - second.1.ln()).abs() < 0.01 {
        why = Some(format!("the two risks have the same modulus ({:.3} and {:.3}), so together they are one Weibull law (σ^(−m) = σ₁^(−m) + σ₂^(−m)) and any split of its scale fits equally", first.1, second.1));
    } else if kind != Populations::Threshold && same(first, second) {
        why = Some(format!("the two populations are the same law (scales {:.4} and {:.4}, moduli {:.2} and {:.2})", first.0, second.0, first.1, second.1));
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
            let differs = if kind == Populations::Threshold { !(same(a, first) && (q - threshold).abs() < 0.02 * first.0) } else { !(same(a, first) && same(b, second) && (q - p).abs() < 0.02) };
            if best.1 - l < 0.1 && differs {
                let weight = if kind == Populations::Mixture { format!("p = {q:.3}, ") } else { String::new() };
                if kind == Populations::Threshold {
                    why = Some(format!("several maxima: a start reaches ℓ within {:.3} of the best with another law (γ = {q:.4e}, σ = {:.4e}, m = {:.2})", best.1 - l, a.0, a.1));
                    break;
                }
                why = Some(format!("several maxima: a start reaches ℓ within {:.3} of the best with another law ({weight}scales {:.4} and {:.4}, moduli {:.2} and {:.2})", best.1 - l, a.0, b.0, a.1, b.1));
                break;
            }
        }
    }
    // An exact row's density of x/med is med times its density of x; a probability is unitless.
    Ok(FlawFit { kind, p, first, second, threshold, beta, loglik: best.1 - exact_rows as f64 * med.ln(), identifiable: why.map_or(Ok(()), Err) })
}

/// The smallest value a threshold must stay below, over the rows that say a break at or below
/// a value (exact and left-censored rows, a class's upper end), each with its scale shift taken
/// out, divided by `unit`; ∞ if every row is right-censored.
fn below_threshold(x: Obs, z: &[Vec<f64>], beta: &[f64], unit: f64) -> f64 {
    use crate::obs::Censor;
    (0..x.len()).filter(|&i| x.kind(i) != Censor::Right).map(|i| if x.kind(i) == Censor::Interval { x.upper(i) } else { x.x[i] } * (-shift_at(z, beta, i)).exp() / unit).fold(f64::INFINITY, f64::min)
}

impl FlawFit {
    /// The profile-likelihood interval at `level` of the parameter the naming loop reports —
    /// the weaker population's share p of a mixture, the weaker risk's modulus m₁ of competing
    /// risks, the threshold γ of the threshold law (in the data's units) — on the strengths `x` (and scale-effect columns `z`) it was fitted to:
    /// {v : 2[ℓ̂ − max ℓ | v] ≤ χ²₁(level)}, the
    /// other parameters re-maximised at each v (warm-started BFGS). An end that reaches the
    /// search box (p → 0 or 1, m at [`M_MIN`] or [`M_MAX`]) is that bound. None if the fit is
    /// not identified.
    pub fn profile_band(&self, x: Obs, z: &[Vec<f64>], level: f64) -> Option<(f64, f64)> {
        if self.identifiable.is_err() || !(level > 0.0 && level < 1.0) {
            return None;
        }
        let points: Vec<f64> = (0..x.len()).map(|i| x.point(i)).collect();
        let med = crate::stats::median(&points);
        let (lnx, kinds, lnu) = scaled(x, med);
        let rows = Rows { lnx: &lnx, kind: &kinds, lnu: &lnu };
        let (s1, m1, s2, m2) = ((self.first.0 / med).ln(), self.first.1.ln(), (self.second.0 / med).ln(), self.second.1.ln());
        let (mut start, k) = match self.kind {
            Populations::Mixture => (vec![(self.p / (1.0 - self.p)).ln(), s1, m1, s2, m2], 0),
            Populations::Competing => (vec![s1, m1, s2, m2], 1),
            Populations::Threshold => (vec![(self.threshold / med).ln(), s1, m1], 0),
        };
        start.extend(&self.beta);
        let full = bounds(self.kind, z.len());
        let (best_t, best) = bfgs(self.kind, &rows, z, &start, &full);
        let drop = statrs::distribution::ChiSquared::new(1.0).ok().map(|c| 0.5 * statrs::distribution::ContinuousCDF::inverse_cdf(&c, level))?;
        let target = best - drop;
        // max ℓ with coordinate k fixed at v, warm-started from `from`.
        let profile = |v: f64, from: &[f64]| -> (Vec<f64>, f64) {
            let mut b = full.clone();
            b[k] = (v, v);
            let mut t = from.to_vec();
            t[k] = v;
            bfgs(self.kind, &rows, z, &t, &b)
        };
        let natural = |v: f64| match self.kind {
            Populations::Mixture => 1.0 / (1.0 + (-v).exp()),
            Populations::Competing => v.exp(),
            Populations::Threshold => v.exp() * med,
        };
        // Warm-started from the last point found inside.
        let end = |dir: f64| {
            let mut from = best_t.clone();
            let bound = if dir < 0.0 { full[k].0 } else { full[k].1 };
            crate::stats::region_end(
                |v| {
                    let (t, l) = profile(v, &from);
                    let keep = l >= target;
                    if keep {
                        from = t;
                    }
                    Some(keep)
                },
                best_t[k],
                dir,
                0.05,
                bound,
                1e-4,
            )
        };
        let ends = [end(-1.0)?, end(1.0)?];
        Some((natural(ends[0]), natural(ends[1])))
    }

    /// Row i's scale shift η_i = Σ_k β_k z_k,i (0 without scale effects).
    pub fn shift(&self, z: &[Vec<f64>], i: usize) -> f64 {
        shift_at(z, &self.beta, i)
    }

    /// Log density at x (in the data's units).
    pub fn ln_pdf(&self, x: f64) -> f64 {
        match self.kind {
            Populations::Threshold => {
                let w = x - self.threshold;
                if w > 0.0 { ln_weibull_pdf(w, self.first.0, self.first.1) } else { f64::NEG_INFINITY }
            }
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

    /// Log survival function ln S(x) = ln[1 − F(x)] (at the reference of any scale effects),
    /// without cancellation in either tail.
    pub fn ln_sf(&self, x: f64) -> f64 {
        let h = |(s, m): (f64, f64)| (x / s).powf(m);
        match self.kind {
            Populations::Mixture => {
                let (a, b) = (self.p.ln() - h(self.first), (1.0 - self.p).ln() - h(self.second));
                log_sum_and_shares([a, b]).0
            }
            Populations::Competing => -h(self.first) - h(self.second),
            Populations::Threshold => -((x - self.threshold).max(0.0) / self.first.0).powf(self.first.1),
        }
    }

    /// The fitted law in words (strengths in the data's units, Pa for a strength file).
    pub fn describe(&self) -> String {
        let pop = |(s, m): (f64, f64)| format!("σ = {:.1} MPa, m = {m:.2}", s / 1e6);
        let at = if self.beta.is_empty() { "" } else { " (scales at the reference of the scale effects beside the law, which shift both populations alike)" };
        match self.kind {
            Populations::Mixture => format!("{:.1} % of specimens with {} (weaker), {:.1} % with {}{at}", 100.0 * self.p, pop(self.first), 100.0 * (1.0 - self.p), pop(self.second)),
            Populations::Competing => format!("every specimen holds both flaw populations: {} and {}{at}", pop(self.first), pop(self.second)),
            Populations::Threshold => format!("no specimen breaks below γ = {:.1} MPa; the strength less γ is Weibull with {}{at}", self.threshold / 1e6, pop(self.first)),
        }
    }

    /// CDF at x (at the reference of any scale effects beside the law).
    pub fn cdf(&self, x: f64) -> f64 {
        match self.kind {
            Populations::Threshold => crate::weibull::threshold_cdf(self.threshold, self.first, x),
            _ => crate::weibull::two_population_cdf(self.kind == Populations::Mixture, self.p, self.first, self.second, x),
        }
    }

    /// One draw by inversion of the CDF (bisection in ln x).
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let u: f64 = rng.random::<f64>().clamp(1e-300, 1.0 - 1e-16);
        if self.kind == Populations::Threshold {
            return self.threshold + self.first.0 * (-(-u).ln_1p()).powf(1.0 / self.first.1);
        }
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
    use crate::obs::Censor;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn a_censored_row_adds_the_law_s_survival_and_a_class_its_probability() {
        // ℓ of a right-censored row is ln S of the law, of an interval row ln[S(a) − S(b)]:
        // the fitted law's own functions at its optimum reproduce the fit's ℓ.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let cr = FlawFit { kind: Populations::Competing, p: 1.0, first: (1.0, 3.0), second: (1.3, 20.0), threshold: 0.0, beta: Vec::new(), loglik: 0.0, identifiable: Ok(()) };
        let x: Vec<f64> = (0..300).map(|_| cr.sample(&mut rng)).collect();
        let n = x.len();
        let kind: Vec<Censor> = x.iter().map(|v| if *v > 1.2 { Censor::Right } else if *v < 0.5 { Censor::Interval } else { Censor::Exact }).collect();
        let obs: Vec<f64> = x.iter().map(|v| if *v > 1.2 { 1.2 } else if *v < 0.5 { 0.9 * v } else { *v }).collect();
        let upper: Vec<f64> = x.iter().map(|v| if *v < 0.5 { 1.1 * v } else { f64::NAN }).collect();
        let c = crate::obs::Censoring { kind, upper, scheme: Default::default() };
        let o = Obs { x: &obs, censoring: Some(&c) };
        let f = fit(Populations::Competing, o).unwrap();
        let l: f64 = (0..n).map(|i| o.ln_prob(i, |v| f.ln_pdf(v), |v| f.ln_sf(v))).sum();
        assert!((f.loglik - l).abs() < 1e-8 * l.abs(), "{} vs {l}", f.loglik);
        assert!((f.first.1 - 3.0).abs() < 1.0, "{f:?}");
    }

    #[test]
    fn a_mixture_and_competing_risks_are_recovered_and_one_population_is_not_identified() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mix = FlawFit { kind: Populations::Mixture, p: 0.3, first: (1.0, 12.0), second: (2.0, 10.0), threshold: 0.0, beta: Vec::new(), loglik: 0.0, identifiable: Ok(()) };
        let x: Vec<f64> = (0..600).map(|_| mix.sample(&mut rng)).collect();
        let f = fit(Populations::Mixture, Obs::exact(&x)).unwrap();
        assert!(f.identifiable.is_ok(), "{f:?}");
        assert!((f.p - 0.3).abs() < 0.06 && (f.first.0 - 1.0).abs() < 0.05 && (f.second.0 - 2.0).abs() < 0.05, "{f:?}");
        let cr = FlawFit { kind: Populations::Competing, p: 1.0, first: (1.0, 3.0), second: (1.3, 20.0), threshold: 0.0, beta: Vec::new(), loglik: 0.0, identifiable: Ok(()) };
        let x: Vec<f64> = (0..800).map(|_| cr.sample(&mut rng)).collect();
        let f = fit(Populations::Competing, Obs::exact(&x)).unwrap();
        assert!(f.identifiable.is_ok(), "{f:?}");
        assert!((f.first.1 - 3.0).abs() < 0.6 && (f.second.1 - 20.0).abs() < 8.0, "{f:?}");
        // One Weibull population fitted as a mixture.
        let one = FlawFit { kind: Populations::Competing, p: 1.0, first: (1.0, 8.0), second: (1.0, 8.0), threshold: 0.0, beta: Vec::new(), loglik: 0.0, identifiable: Ok(()) };
        let y: Vec<f64> = (0..400).map(|_| one.sample(&mut rng)).collect();
        let g = fit(Populations::Mixture, Obs::exact(&y)).unwrap();
        assert!(g.identifiable.is_err(), "one Weibull population must not be reported as two: {g:?}");
    }

    #[test]
    fn a_threshold_is_recovered_censored_rows_included_and_none_is_found_in_a_two_parameter_sample() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let thr = FlawFit { kind: Populations::Threshold, p: 1.0, first: (0.5, 2.5), second: (0.5, 2.5), threshold: 1.0, beta: Vec::new(), loglik: 0.0, identifiable: Ok(()) };
        let x: Vec<f64> = (0..600).map(|_| thr.sample(&mut rng)).collect();
        assert!(x.iter().all(|v| *v > 1.0));
        // Rows above 1.8 stop unbroken there; rows below 1.2 are read as classes (0.98 x, 1.02 x].
        let kind: Vec<Censor> = x.iter().map(|v| if *v > 1.8 { Censor::Right } else if *v < 1.2 { Censor::Interval } else { Censor::Exact }).collect();
        let obs: Vec<f64> = x.iter().map(|v| if *v > 1.8 { 1.8 } else if *v < 1.2 { 0.98 * v } else { *v }).collect();
        let upper: Vec<f64> = x.iter().map(|v| if *v < 1.2 { 1.02 * v } else { f64::NAN }).collect();
        let c = crate::obs::Censoring { kind, upper, scheme: Default::default() };
        for o in [Obs::exact(&x), Obs { x: &obs, censoring: Some(&c) }] {
            let f = fit(Populations::Threshold, o).unwrap();
            assert!(f.identifiable.is_ok(), "{f:?}");
            assert!((f.threshold - 1.0).abs() < 0.08 && (f.first.1 - 2.5).abs() < 0.6, "{f:?}");
            // The fit's ℓ is the law's own ln f, ln S and class probabilities summed.
            let l: f64 = (0..x.len()).map(|i| o.ln_prob(i, |v| f.ln_pdf(v), |v| f.ln_sf(v))).sum();
            assert!((f.loglik - l).abs() < 1e-8 * l.abs(), "{} vs {l}", f.loglik);
            // The profile band of γ holds the truth.
            let (lo, hi) = f.profile_band(o, &[], 0.95).unwrap();
            assert!(lo < 1.0 && 1.0 < hi && hi < f.first.0 + 1.0, "{lo} {hi}");
        }
        // A two-parameter sample: the threshold law gains less than χ²₁(0.99)/2 in ℓ over it.
        let two: Vec<f64> = (0..400).map(|_| 2.0 * (-(-rng.random::<f64>()).ln_1p()).powf(1.0 / 6.0)).collect();
        let f = fit(Populations::Threshold, Obs::exact(&two)).unwrap();
        let base = crate::weibull::fit_mle(&two).unwrap();
        let l0: f64 = two.iter().map(|v| ln_weibull_pdf(*v, base.mle.scale, base.mle.shape)).sum();
        assert!(f.loglik >= l0 - 1e-6 && f.loglik - l0 < 3.3, "{} against {l0}: {f:?}", f.loglik);
    }
}

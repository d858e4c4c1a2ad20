//! Known failure origins (fractography): each origin's Weibull law, and whether the origins
//! share one.
//!
//! Where a strength file names each specimen's failure origin (volume, surface, edge, pore …),
//! the origins are competing risks with known cause. ASTM C1239 (§9, concurrent flaw
//! populations) estimates each origin's law from its own breaks with **the other origins' breaks
//! right-censored at their strength**: that specimen survived this origin's flaws at least to
//! the stress that broke it elsewhere. The full likelihood of (strength, origin) pairs
//! factorises into these censored likelihoods, one per origin (Lawless 2003, §9.1):
//!
//! ```text
//! L = Π_i h_{c_i}(x_i) Π_k S_k(x_i) = Π_k [ Π_{i: c_i = k} h_k(x_i) · Π_i S_k(x_i) ] = Π_k L_k
//! ```
//!
//! A specimen that did not break is right-censored for every origin; one that broke within a
//! class of another origin survived this origin at least to the class's lower end
//! (right-censored there); one that broke at or below a value from another origin says nothing
//! of this origin and is left out of its fit.
//!
//! **Do the origins share one modulus?** Under H₀ the origins' laws have one modulus m, each
//! its own scale σ_k. Then the weakest of them is one Weibull law (m, σ) with
//! σ^(−m) = Σ_k σ_k^(−m), and which origin breaks a specimen does not depend on its strength:
//! origin k with probability p_k = (σ/σ_k)^m. The likelihood factorises into the one-law fit of
//! all specimens together and the multinomial of the origins' counts, so its maximum is
//! ℓ̂₀ = ℓ̂_c + Σ_k r_k ln(r_k / r), with r_k the breaks from origin k and r all breaks. The
//! likelihood ratio LR = 2[Σ_k ℓ̂_k − ℓ̂₀] is referred to χ² with K − 1 degrees of freedom
//! (2K parameters against K + 1). How often each origin occurs is not evidence against H₀ —
//! testing "every origin the same law" instead (p_k = 1/K) rejects on unequal counts alone. The
//! test needs every origin with at least two breaks and rows that are breaks or not broken
//! (a class or a left-censored row does not factorise this way); otherwise it is not made, and
//! the reason is given.
//!
//! **In the lifetime** (crush files, the discrepancy study): the origins are independent flaw
//! populations and the weakest breaks first, so a particle survives N impacts only if it
//! survives every origin's flaws, P_N = 1 − Π_k (1 − P_N,k) ([`combined`]), each P_N,k from
//! origin k's law through the one lifetime model.
//!
//! Files without origins keep the latent competing-risks law of [`super::flaws`] (two flaw
//! populations in every specimen, causes unknown).
//!
//! Verified against the `reliability` package's right-censored fits (tests/bench/reliability/
//! origins.py) on Nelson's connection-strength data in `tests/censoring.rs`; on crushed
//! particles with two flaw populations and a rig limit against the generator's truth there.

use serde::Serialize;

use crate::error::Result;
use crate::obs::{Censor, Obs, Observations};
use crate::strength::options::Uncertainty;
use crate::strength::regress::{Design, fit};
use crate::strength::{Sample, StrengthFit};

/// One origin's Weibull law, from its own breaks with the others censored.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OriginFit {
    /// The origin, as the file writes it.
    pub origin: String,
    /// Specimens that broke from this origin.
    pub breaks: usize,
    /// Weibull modulus (NaN with fewer than two breaks).
    pub shape: f64,
    /// Weibull scale (the data's units, Pa for a strength file; NaN with fewer than two breaks).
    pub scale: f64,
    /// The censored fit's log-likelihood.
    pub loglik: f64,
    /// The modulus's 90 % band (5 and 95 % quantiles of the bootstrap draws; NaN with fewer
    /// than two breaks).
    pub shape_band: (f64, f64),
    /// The scale's 90 % band, as `shape_band`.
    pub scale_band: (f64, f64),
    /// The bootstrap draws the bands are quantiles of (empty with fewer than two breaks): the
    /// lifetime with every origin acting combines these, not a second bootstrap.
    #[serde(skip)]
    pub draws: Vec<crate::strength::Params>,
    /// The origin's strength fit ([`origin_fit`]; None with fewer than two breaks): what its
    /// lifetime model carries.
    #[serde(skip)]
    pub strength: Option<StrengthFit>,
}

/// The likelihood-ratio test of one modulus shared by every origin (each its own scale).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SharedModulus {
    /// Σ_k ℓ̂_k, each origin its own law.
    pub loglik_separate: f64,
    /// ℓ̂ with one modulus for every origin: the one-law fit of all specimens plus
    /// Σ_k r_k ln(r_k / r).
    pub loglik_shared: f64,
    /// 2 (separate − shared).
    pub lr: f64,
    /// K − 1.
    pub df: usize,
    /// χ² p-value.
    pub p: f64,
}

/// What the origins say.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Origins {
    /// The column that names them.
    pub column: String,
    /// One law per origin, in the origins' sorted order.
    pub fits: Vec<OriginFit>,
    /// The shared-modulus test, or why it is not made.
    pub shared: std::result::Result<SharedModulus, String>,
}

/// The probability that a particle breaks when each origin's flaws alone would break it with
/// probability `p[k]`: the origins are independent flaw populations and the weakest breaks
/// first, so the survivals multiply, P = 1 − Π_k (1 − p_k). Summed in ln(1 − p) so that a
/// probability of 1e-12 keeps its digits.
pub fn combined(p: &[f64]) -> f64 {
    from_ln_survival(p.iter().map(|&q| ln_survival(q)).sum())
}

/// ln(1 − p): the log survival of one origin's flaws, which [`combined`] sums.
#[inline]
pub fn ln_survival(p: f64) -> f64 {
    (-p).ln_1p()
}

/// The breaking probability 1 − e^s of a summed log survival s ([`combined`]).
#[inline]
pub fn from_ln_survival(s: f64) -> f64 {
    -s.exp_m1()
}

/// Each origin's law from the observations `x` whose specimen i failed from `origin[i]` (ignored
/// for a specimen that did not break), its 90 % bands from `draws` bootstrap draws, and the
/// shared-modulus test (module docs).
///
/// The bands are the 5 and 95 % quantiles of the draws of [`origin_fit`] ([`StrengthFit::draws`]
/// by `how`, origin k's with seed `seed + k`): with [`Uncertainty::Bootstrap`] the plain
/// parametric bootstrap, each redrawn specimen censored as its row was (another origin's break a
/// limit at its value), in pivotal form — kept in [`OriginFit::draws`] for the lifetime with
/// every origin acting.
pub fn analyse(x: Obs, origin: &[String], column: &str, how: Uncertainty, draws: usize, seed: u64) -> Result<Origins> {
    let n = x.len();
    let mut levels: Vec<String> = (0..n).filter(|&i| x.kind(i) != Censor::Right).map(|i| origin[i].clone()).collect();
    levels.sort();
    levels.dedup();
    let mut fits = Vec::new();
    let mut why: Option<String> = None;
    let nan = (f64::NAN, f64::NAN);
    for (k, lv) in levels.iter().enumerate() {
        let (obs, breaks) = x.of_origin(origin, lv);
        if breaks < 2 {
            why.get_or_insert(format!("origin \"{lv}\" has {breaks} break: a Weibull law needs at least two"));
            fits.push(OriginFit { origin: lv.clone(), breaks, shape: f64::NAN, scale: f64::NAN, loglik: f64::NAN, shape_band: nan, scale_band: nan, draws: Vec::new(), strength: None });
            continue;
        }
        let sf = origin_fit(obs, lv)?;
        let d = sf.draws(how, draws, seed.wrapping_add(k as u64))?;
        let f = &sf.model.reg;
        let band = |v: Vec<f64>| {
            let q = crate::stats::interpolated_quantiles(v, &[0.05, 0.95]);
            (q[0], q[1])
        };
        fits.push(OriginFit {
            origin: lv.clone(),
            breaks,
            shape: f.shape(),
            scale: f.mu.exp(),
            loglik: f.loglik,
            shape_band: band(d.iter().map(|p| p.shape).collect()),
            scale_band: band(d.iter().map(|p| p.mu.exp()).collect()),
            draws: d,
            strength: Some(sf.clone()),
        });
    }
    let k = levels.len();
    let shared = if k < 2 {
        Err(format!("every break has one origin (\"{}\")", levels.first().map_or("", |s| s.as_str())))
    } else if let Some(w) = why {
        Err(w)
    } else if (0..n).any(|i| matches!(x.kind(i), Censor::Left | Censor::Interval)) {
        Err("rows that broke within a class or at or below a value do not factorise by origin; the test takes breaks and specimens not broken only".to_string())
    } else {
        let all = fit(x, &Design::default())?;
        let r = fits.iter().map(|f| f.breaks).sum::<usize>() as f64;
        let separate: f64 = fits.iter().map(|f| f.loglik).sum();
        let shared = all.loglik + fits.iter().map(|f| f.breaks as f64 * (f.breaks as f64 / r).ln()).sum::<f64>();
        let lr = (2.0 * (separate - shared)).max(0.0);
        let df = k - 1;
        let p = crate::stats::chi2_upper_tail(lr, df as f64);
        Ok(SharedModulus { loglik_separate: separate, loglik_shared: shared, lr, df, p })
    };
    Ok(Origins { column: column.to_string(), fits, shared })
}

/// Origin `origin`'s two-parameter strength fit from its observations `obs` (its own breaks, the
/// other origins censored: [`Obs::of_origin`]): what its bands and its lifetime are drawn from.
pub fn origin_fit(obs: Observations, origin: &str) -> Result<StrengthFit> {
    let sample = Sample { source: format!("origin {origin}"), strength: obs, ..Sample::default() };
    StrengthFit::new(&sample, &[], 0.0, origin)
}

/// ln P(row i of `x`) when every origin's Weibull law acts and the weakest flaw breaks the
/// specimen: `laws` holds each origin's (ln σ_k, m_k) in the units of x. The survival is
/// S(v) = Π_k S_k(v) and the density of the strength (whatever the origin)
/// f(v) = Σ_k h_k(v) · S(v), h_k = f_k/S_k the origin's hazard; a censored or class row takes S
/// as [`Obs::ln_prob`] does. This is the density of the strength alone, comparable with one
/// law's: what the main study's cross-validation weighs strength models by.
pub fn ln_prob_weakest(x: Obs, i: usize, laws: &[(f64, f64)]) -> f64 {
    let ln_sf = |v: f64| laws.iter().map(|&(ls, m)| -(m * (v.ln() - ls)).exp()).sum::<f64>();
    let ln_pdf = |v: f64| {
        // ln h_k = ln f_k − ln S_k = ln m_k − ln v + m_k (ln v − ln σ_k).
        let h: Vec<f64> = laws.iter().map(|&(ls, m)| m.ln() - v.ln() + m * (v.ln() - ls)).collect();
        let top = h.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        top + h.iter().map(|a| (a - top).exp()).sum::<f64>().ln() + ln_sf(v)
    };
    x.ln_prob(i, ln_pdf, ln_sf)
}

/// The cross-validated ln P of the rows `test` of `x` under every origin's two-parameter law
/// fitted to the rows `train` alone (each origin's breaks, the others' censored: [`Obs::of_origin`]),
/// acting together ([`ln_prob_weakest`]). `origin[i]` names row i's origin; the origins are those
/// of every break of `x`. Err (why) where an origin has fewer than two breaks among `train` or
/// a fit fails.
pub fn cv_ln_prob(x: Obs, origin: &[String], train: &[usize], test: &[usize]) -> std::result::Result<Vec<f64>, String> {
    let mut levels: Vec<&String> = (0..x.len()).filter(|&i| x.kind(i) != Censor::Right).map(|i| &origin[i]).collect();
    levels.sort();
    levels.dedup();
    let sub = x.rows(train);
    let sub_origin: Vec<String> = train.iter().map(|&i| origin[i].clone()).collect();
    let mut laws = Vec::with_capacity(levels.len());
    for lv in levels {
        let (obs, breaks) = sub.view().of_origin(&sub_origin, lv);
        if breaks < 2 {
            let all = (0..x.len()).filter(|&i| x.kind(i) != Censor::Right && origin[i] == *lv).count();
            return Err(format!("failure origin \"{lv}\" has {all} breaks, and a training fold of the cross-validation keeps {breaks}: too few for its law"));
        }
        let f = fit(obs.view(), &Design::default()).map_err(|e| format!("the fit of failure origin \"{lv}\" on a training fold failed ({e})"))?;
        laws.push((f.mu, f.shape()));
    }
    let out: Vec<f64> = test.iter().map(|&i| ln_prob_weakest(x, i, &laws)).collect();
    if out.iter().all(|v| v.is_finite()) { Ok(out) } else { Err("a held-out crush test has no finite density under the origins' laws".into()) }
}

/// Fewer breaks than this from one origin: its law is said to be poorly determined.
pub const FEW_BREAKS: usize = 10;

/// A caution where an origin's law rests on fewer than [`FEW_BREAKS`] breaks (empty
/// otherwise): its law, and any lifetime it enters, are poorly determined.
pub fn few_breaks<'a>(fits: impl IntoIterator<Item = &'a OriginFit>) -> String {
    let few: Vec<String> = fits.into_iter().filter(|f| f.shape.is_finite() && f.breaks < FEW_BREAKS).map(|f| format!("\"{}\" ({} breaks)", f.origin, f.breaks)).collect();
    match few.len() {
        0 => String::new(),
        1 => format!("**Few breaks**: origin {} has its law from fewer than {FEW_BREAKS} breaks, so its modulus and scale are poorly determined, and so is any lifetime it enters: read the bands, not the point values.", few[0]),
        _ => format!("**Few breaks**: origins {} have their laws from fewer than {FEW_BREAKS} breaks each, so their moduli and scales are poorly determined, and so is any lifetime they enter: read the bands, not the point values.", few.join(", ")),
    }
}

/// What the origins' analysis is not: said after it in the report.
const NOT_IN_LOOP: &str = "Each origin's law here is a two-parameter Weibull law fitted on its own; the naming loop above does not use the origins.";

impl Origins {
    /// The shared-modulus test in words, for the report, followed by `lifetime`: what the report
    /// does with the origins' laws in the lifetime (a strength file has no contact to carry a
    /// strength to impacts; a crush file's lifetime has every origin acting).
    pub fn sentence(&self, alpha: f64, lifetime: &str) -> String {
        format!("{} {lifetime}", self.test_words(alpha))
    }

    /// A caution where an origin's law rests on fewer than [`FEW_BREAKS`] breaks (empty
    /// otherwise): [`few_breaks`] of its fits.
    pub fn few_words(&self) -> String {
        few_breaks(&self.fits)
    }

    fn test_words(&self, alpha: f64) -> String {
        let p = |p: f64| if p < 0.001 { "< 0.001".to_string() } else { format!("= {p:.3}") };
        let df = |d: usize| if d == 1 { "1 degree of freedom".to_string() } else { format!("{d} degrees of freedom") };
        let how = "each origin its own law, against one modulus for all with a scale each; under one modulus which origin breaks a specimen does not depend on its strength, so how often each origin occurs is no evidence either way";
        match &self.shared {
            Ok(s) if s.p < alpha => format!("**The origins' Weibull moduli differ**: likelihood ratio {:.2} on {}, χ² p {} ({how}). {NOT_IN_LOOP}", s.lr, df(s.df), p(s.p)),
            Ok(s) => format!("The origins are consistent with one Weibull modulus: likelihood ratio {:.2} on {}, χ² p {} ({how}). {NOT_IN_LOOP}", s.lr, df(s.df), p(s.p)),
            Err(why) => format!("Whether the origins share one modulus is not tested: {why}. {NOT_IN_LOOP}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn the_origins_fits_recover_their_laws_and_the_shared_modulus_test_tells_two_moduli_from_one_not_from_unequal_counts() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let draw = |rng: &mut ChaCha8Rng, s: f64, m: f64| s * (-(-rng.random::<f64>()).ln_1p()).powf(1.0 / m);
        // Moduli 10 and 4: they differ. One law twice; one modulus with the second scale 1.3×,
        // so the surface breaks are about 7 % of all: unequal counts are no evidence.
        for (second, differ) in [((1.5, 4.0), true), ((1.0, 10.0), false), ((1.3, 10.0), false)] {
            let (mut x, mut o) = (Vec::new(), Vec::new());
            for _ in 0..400 {
                let (a, b) = (draw(&mut rng, 1.0, 10.0), draw(&mut rng, second.0, second.1));
                x.push(a.min(b));
                o.push(if a <= b { "volume".to_string() } else { "surface".to_string() });
            }
            let r = analyse(Obs::exact(&x), &o, "origin", Uncertainty::Bootstrap, 100, 1).unwrap();
            let v = r.fits.iter().find(|f| f.origin == "volume").unwrap();
            assert!((v.shape / 10.0 - 1.0).abs() < 0.15 && (v.scale - 1.0).abs() < 0.03, "{r:?}");
            let s = r.shared.clone().unwrap();
            assert_eq!(s.df, 1);
            assert_eq!(s.p < 0.01, differ, "{r:?}");
            // The separate fits' ℓ is the full likelihood: at least the shared modulus'.
            assert!(s.loglik_separate >= s.loglik_shared - 1e-9);
        }
    }

    #[test]
    fn the_weakest_of_the_origins_laws_has_the_density_of_its_survival_and_one_law_is_the_one_law_s() {
        let laws = [(1.0f64.ln(), 10.0), (1.2f64.ln(), 4.0), (0.9f64.ln(), 20.0)];
        let ln_s = |v: f64| -laws.iter().map(|&(ls, m)| (m * (v.ln() - ls)).exp()).sum::<f64>();
        for v in [0.3, 0.7, 0.95, 1.1] {
            // The density is −dS/dv (central difference); a right-censored row is S, a class S(a) − S(b).
            let h = 1e-6 * v;
            let numeric = -((ln_s(v + h)).exp() - (ln_s(v - h)).exp()) / (2.0 * h);
            let exact = ln_prob_weakest(Obs::exact(&[v]), 0, &laws);
            assert!((exact - numeric.ln()).abs() < 1e-6, "{v}: {exact} against {}", numeric.ln());
            let right = Observations { censoring: crate::obs::Censoring::of_rows(vec![Censor::Right], &[v], vec![f64::NAN]), x: vec![v] };
            assert!((ln_prob_weakest(right.view(), 0, &laws) - ln_s(v)).abs() < 1e-12);
            let class = Observations { censoring: crate::obs::Censoring::of_rows(vec![Censor::Interval], &[v], vec![1.2 * v]), x: vec![v] };
            let p = ln_s(v).exp() - ln_s(1.2 * v).exp();
            assert!((ln_prob_weakest(class.view(), 0, &laws) - p.ln()).abs() < 1e-9);
            // One origin: the one law's ln P.
            let one = ln_prob_weakest(Obs::exact(&[v]), 0, &laws[..1]);
            assert!((one - crate::strength::loglik::ln_prob(Obs::exact(&[v]), 0, laws[0].0, 1.0 / laws[0].1)).abs() < 1e-12);
        }
    }

    #[test]
    fn cross_validated_origins_score_the_held_out_rows_and_need_two_breaks_per_origin_in_training() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let draw = |rng: &mut ChaCha8Rng, s: f64, m: f64| s * (-(-rng.random::<f64>()).ln_1p()).powf(1.0 / m);
        let (mut x, mut o) = (Vec::new(), Vec::new());
        for _ in 0..200 {
            let (a, b) = (draw(&mut rng, 1.0, 12.0), draw(&mut rng, 1.2, 4.0));
            x.push(a.min(b));
            o.push(if a <= b { "volume" } else { "surface" }.to_string());
        }
        let (train, test): (Vec<usize>, Vec<usize>) = (0..200).partition(|i| i % 5 != 0);
        let p = cv_ln_prob(Obs::exact(&x), &o, &train, &test).unwrap();
        assert_eq!(p.len(), test.len());
        // The held-out rows score better under the two origins' laws than under one law fitted
        // to the same training rows (the data are two moduli).
        let one = fit(Obs::exact(&x).rows(&train).view(), &Design::default()).unwrap();
        let pooled: f64 = test.iter().map(|&i| crate::strength::loglik::ln_prob(Obs::exact(&x), i, one.mu, 1.0 / one.shape())).sum();
        assert!(p.iter().sum::<f64>() > pooled, "{} against one law's {pooled}", p.iter().sum::<f64>());
        // Training rows with a single surface break: no law for it.
        let few: Vec<usize> = (0..200).filter(|&i| o[i] == "volume").chain((0..200).filter(|&i| o[i] == "surface").take(1)).collect();
        let e = cv_ln_prob(Obs::exact(&x), &o, &few, &test).unwrap_err();
        assert!(e.starts_with("failure origin \"surface\" has ") && e.contains("a training fold of the cross-validation keeps 1"), "{e}");
    }

    #[test]
    fn each_origin_s_90_percent_bands_cover_its_true_modulus_and_scale_in_about_90_percent_of_campaigns() {
        // 200 campaigns of 80 specimens: a volume population (m = 10, σ = 1) and a surface one
        // (m = 5, σ = 1.2) compete; the rig stops at 1.1, so about 15 % of the specimens do not
        // break (right-censored for both origins) and each origin's fit censors the other's breaks.
        let (truth, limit) = ([("surface", 5.0, 1.2), ("volume", 10.0, 1.0)], 1.1);
        let mut rng = ChaCha8Rng::seed_from_u64(52);
        let draw = |rng: &mut ChaCha8Rng, s: f64, m: f64| s * (-(-rng.random::<f64>()).ln_1p()).powf(1.0 / m);
        let campaigns = 200;
        let mut covered = [[0usize; 2]; 2];
        for c in 0..campaigns {
            let (mut x, mut kind, mut o) = (Vec::new(), Vec::new(), Vec::new());
            for _ in 0..80 {
                let (a, b) = (draw(&mut rng, truth[0].2, truth[0].1), draw(&mut rng, truth[1].2, truth[1].1));
                let broke = a.min(b) <= limit;
                x.push(a.min(b).min(limit));
                kind.push(if broke { Censor::Exact } else { Censor::Right });
                o.push(if !broke { "none" } else if a < b { truth[0].0 } else { truth[1].0 }.to_string());
            }
            let obs = Observations { censoring: crate::obs::Censoring::of_rows(kind, &x, vec![f64::NAN; x.len()]), x };
            let r = analyse(obs.view(), &o, "origin", Uncertainty::Bootstrap, 200, c as u64).unwrap();
            for (k, (name, m, scale)) in truth.iter().enumerate() {
                let f = r.fits.iter().find(|f| f.origin == *name).unwrap();
                assert!(f.shape_band.0 < f.shape && f.shape < f.shape_band.1 && f.scale_band.0 < f.scale && f.scale < f.scale_band.1, "{f:?}");
                covered[k][0] += usize::from(f.shape_band.0 <= *m && *m <= f.shape_band.1);
                covered[k][1] += usize::from(f.scale_band.0 <= *scale && *scale <= f.scale_band.1);
            }
        }
        // 90 % ± 2.4 Monte Carlo standard errors of 200 campaigns.
        for (k, (name, ..)) in truth.iter().enumerate() {
            for (j, what) in ["modulus", "scale"].iter().enumerate() {
                let share = covered[k][j] as f64 / campaigns as f64;
                assert!((0.85..=0.95).contains(&share), "{name} {what}: covered in {share:.3} of {campaigns} campaigns ({covered:?})");
            }
        }
    }
}

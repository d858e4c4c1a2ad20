//! The name → add → diagnose-again loop on crush strengths (issue 7, steps 1–3).
//!
//! Each round starts from the current model (round 0: the deliverable's single Weibull law) and
//! 1. **diagnoses** it: quantile residuals r_i = Φ⁻¹(F_i(x_i)), their Spearman trend against
//!    every covariate with a permutation p-value, the tertile of largest departure, and AD/KS
//!    statistics whose p-values come from the round's parametric bootstrap (each replicate
//!    refits the current model). A censored or interval row's residual is randomised within
//!    what the row allows (Dunn & Smyth 1996: F(x) + V[1 − F(x)] for a specimen that did not
//!    break by x, V uniform, seeded), so the AD and KS statistics are those of randomised
//!    quantile residuals; the bootstrap censors each redraw as the campaign did
//!    ([`crate::obs::Obs::censor`]) and randomises its residuals the same way, so their
//!    p-values hold under censoring;
//! 2. **fits every remaining candidate** ([`crate::strength::effects`]) on top of it and scores it by
//!    * the likelihood ratio Λ = 2(ℓ_cand − ℓ_current), calibrated by the same bootstrap:
//!      B samples drawn from the fitted current model at the observed covariates, each
//!      refitted with and without every candidate. The marginal p-value counts Λ*_c ≥ Λ_c; the
//!      **false-discovery guard** uses a family-wise p-value over every candidate of the round
//!      ([`super::guard::family`]: Westfall–Young's min-P by default, max-T on Wilks' one-df
//!      scale with `guard = "max-t"`), so the chance of naming any effect when none is there is
//!      α whatever the number of candidates. The critical Λ reported for each candidate is the
//!      order statistic that decision uses (p < α exactly when Λ > critical). A replicate
//!      whose refit fails (the current model's, or the candidate's) counts as Λ* = +∞ — as
//!      exceeding, so failures can only raise p — and a candidate with more than
//!      [`super::guard::MAX_FAILED_SHARE`] of its replicates failed gets no verdict (neither named nor
//!      rejected; evidence.csv and the report give the count). The bootstrap is drawn in
//!      stages (99, 199, 499 … up to `bootstrap`) and stops once every decision of the round is
//!      settled ([`super::guard`]'s sequential pretest; [`round_settled`] lists the decisions),
//!      so B — each stage's and evidence row's `replicates` — varies by round;
//!    * ΔBIC = −Λ + k ln n, k the candidate's extra parameters (1 for a particle effect or a
//!      numeric factor, L − 1 for a scale or a modulus per level, 3 or 2 for a two-population
//!      law; a partially pooled factor's effective degrees of freedom, between 0 and L − 1);
//!    * the K-fold cross-validated log score, Δ against the current model; the folds are
//!      stratified by the levels of the categorical factors (`strength::fit::folds_stratified`),
//!      so no level of two or more specimens falls wholly in one fold and leaves a training
//!      set without it;
//! 3. **names** the candidate with the largest Λ (on Wilks' one-df scale) among those passing
//!    the guard — family-wise p < α, ΔBIC < 0 and a better cross-validated log score — adds it and starts the next
//!    round; otherwise it says no (further) missing effect was found. Where that candidate is a
//!    two-population law and the other law passes too, the one with the lower BIC is named
//!    (the two are rival descriptions of one departure from the single Weibull law).
//!
//! The gap measure is the residual-structure statistic G = n Σ_c ρ_c² over the covariates the
//! data carry (ρ_c Spearman's correlation of the quantile residuals with covariate c). Under a
//! model that misses nothing each term of a covariate whose effect is not in the model is ≈ χ²₁;
//! a missing effect with covariate c adds ≈ n ρ_c². A categorical factor g adds two
//! Kruskal–Wallis statistics, each ≈ χ²_(L−1) when nothing is missing: of the residuals by level
//! (a scale per level missing) and of their absolute deviations from the level medians (a
//! modulus per level missing: the levels scatter differently). A covariate whose effect the
//! model fits leaves its residuals nearly uncorrelated with it, so its term falls far below its
//! degrees of freedom (≈ 0.3 for one numeric covariate at n = 80, not 1). The expectation each
//! round reports ([`Stage::gap_expected`]) is therefore not Σ df but G's mean over the round's
//! parametric bootstrap — data drawn from the fitted model, refitted, G computed alike — every
//! term's expectation after fitting.
//!
//! Deterministic for a seed and any thread count: every replicate has its own ChaCha8 stream.

use rayon::prelude::*;
use serde::Serialize;


use super::guard::{MAX_FAILED_SHARE, decided, family, one_df_scale, settled, stages as stages_of};
use crate::strength::FamilyGuard;
use super::gof::{CovariateFinding, ad_ks_of_u, covariate_findings, level_findings, normal_scores};
use crate::strength::factors::WeakestLink;
use super::meaning::{describe, natural_band};
use crate::error::{Error, Result};
use crate::strength::fit::{cv_pointwise, folds, folds_stratified};
use crate::obs::Obs;
use crate::strength::{Effect, ModelFit, NamingSettings, Sample, Term, fit_model, fit_model_near};

/// Fewest particles the workflow accepts.
pub const MIN_PARTICLES: usize = 10;

/// Covariate columns the diagnosis looks at, in order.
pub const DIAGNOSED: [&str; 5] = crate::data::COVARIATE_COLUMNS;

/// Evidence for one candidate in one round.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evidence {
    /// Round (0: against the base model).
    pub round: usize,
    /// The candidate.
    pub candidate: Effect,
    /// Why it was not fitted (then every number is NaN).
    pub skipped: Option<String>,
    /// Why a two-population law's fit is not identified (several optima, or one on the edge of
    /// the parameter space); such a law is never named, and no estimate of it is reported.
    pub not_identified: Option<String>,
    /// Log-likelihood with the candidate added.
    pub loglik: f64,
    /// Λ = 2(ℓ_cand − ℓ_current).
    pub lr: f64,
    /// Bootstrap p-value of Λ for this candidate alone.
    pub p_bootstrap: f64,
    /// Family-wise bootstrap p-value over the round's candidates (the study's `guard`, min-P
    /// or max-T): what the guard decides by.
    pub p_family: f64,
    /// The candidate's critical Λ in the round: the order statistic of the bootstrap that the
    /// guard's decision uses, so p_family < α exactly when Λ > lr_critical
    /// ([`super::guard::Family::critical`]).
    pub lr_critical: f64,
    /// ΔBIC (negative favours the candidate).
    pub delta_bic: f64,
    /// Δ cross-validated log score (positive favours the candidate).
    pub delta_cv: f64,
    /// Fitted parameter (symbol, value, standard error; NaN where not available).
    pub parameter: Option<(String, f64, f64)>,
    /// The parameter's 90 % band (a single-column effect; in the reported parameter's units,
    /// lower first): for a named effect whose model is location-scale the exact pivotal band
    /// (999 unit-sample refits), otherwise the profile-likelihood interval.
    pub band: Option<(f64, f64)>,
    /// Whether `band` is the pivotal band (else the profile likelihood's).
    pub band_pivotal: bool,
    /// What the parameter means.
    pub meaning: String,
    /// Weibull modulus of the extended model.
    pub shape: f64,
    /// Passed the false-discovery guard.
    pub passed: bool,
    /// Named in this round.
    pub named: bool,
    /// Extra parameters of the candidate (degrees of freedom of Λ: 1; L − 1 for levels).
    pub parameters: usize,
    /// For a size measure: the test of the weakest-link exponent.
    pub weakest_link: Option<WeakestLink>,
    /// Bootstrap replicates whose Λ* could not be computed (the candidate's refit or the
    /// current model's failed), each counted as exceeding Λ; above [`super::guard::MAX_FAILED_SHARE`] of
    /// `replicates` the candidate gets no verdict.
    pub failures: usize,
    /// Bootstrap replicates of the round.
    pub replicates: usize,
}

/// Diagnosis of one model.
#[derive(Debug, Clone, PartialEq)]
pub struct Stage {
    /// The fitted model.
    pub model: ModelFit,
    /// Quantile residuals per particle.
    pub residuals: Vec<f64>,
    /// AD and KS statistics and their bootstrap p-values.
    pub ad: f64,
    /// KS statistic.
    pub ks: f64,
    /// Bootstrap p-value of AD.
    pub p_ad: f64,
    /// Bootstrap p-value of KS.
    pub p_ks: f64,
    /// Residual trends, sorted by p.
    pub findings: Vec<CovariateFinding>,
    /// Gap measure G = n Σ ρ² + Σ_g (H_g + S_g) ([`GAP_MEASURE`]).
    pub gap: f64,
    /// G's expectation when the model misses nothing: its mean over the round's bootstrap
    /// replicates (drawn from this model and refitted), so a term whose effect the model fits
    /// counts what it is after fitting (module docs). NaN when no replicate computed it.
    pub gap_expected: f64,
    /// Bootstrap replicates the round drew: the study's `bootstrap`, or fewer where the
    /// sequential bootstrap found every decision settled ([`super::guard`]).
    pub replicates: usize,
    /// Where the sequential bootstrap drew every replicate, the decision that made it draw the
    /// last stage (e.g. "at 199 replicates `moduli(batch)`'s family-wise p 0.090 lay near
    /// α = 0.05"); None otherwise.
    pub unsettled: Option<String>,
}

/// G of residuals `res` ([`GAP_MEASURE`]): numeric covariates `covs`, categorical `levels`.
fn gap_of(res: &[f64], covs: &[(String, Vec<f64>)], levels: &[(String, Vec<String>)]) -> f64 {
    0.0 + res.len() as f64 * covs.iter().map(|(_, v)| super::gof::spearman(res, v).powi(2)).sum::<f64>() + levels.iter().map(|(_, v)| super::gof::kruskal_wallis_by(res, v) + super::gof::scatter_by(res, v)).sum::<f64>()
}

/// Result of the loop.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Effects named, in order.
    pub named: Vec<Effect>,
    /// Evidence of every candidate in every round.
    pub evidence: Vec<Evidence>,
    /// One stage per round: `stages[0]` the base model, the last the final model.
    pub stages: Vec<Stage>,
    /// Covariates not diagnosed, with the reason.
    pub skipped_covariates: Vec<String>,
    /// The weakest-link test of every size effect the final model carries, in that model
    /// (the other named effects refitted under the tie).
    pub size_tests: Vec<(Effect, WeakestLink)>,
}

impl Outcome {
    /// The base model's stage.
    pub fn before(&self) -> &Stage {
        &self.stages[0]
    }
    /// The final model's stage.
    pub fn after(&self) -> &Stage {
        &self.stages[self.stages.len() - 1]
    }
}

/// Gap measure used, as written in verdict.json.
pub const GAP_MEASURE: &str = "residual structure G = n·Σ_c ρ_c² + Σ_g (H_g + S_g), ρ_c = Spearman correlation of the quantile residuals with numeric covariate c, H_g = Kruskal–Wallis statistic of the residuals by the levels of categorical factor g (location), S_g = the same statistic of the residuals' absolute deviations from their level medians (scatter), over the columns the data carry; with nothing missing its expectation is its mean over the round's parametric bootstrap from the fitted model (gap_expected: ≈ the number of numeric covariates plus 2·Σ_g (levels − 1) for a model that fits none of them, less for each fitted one)";

pub(super) fn data_err(sample: &Sample, location: String, rule: String) -> Error {
    Error::Data { file: sample.source.clone(), location, rule }
}

/// Checks the sample: enough particles, finite positive strengths, finite covariates.
pub fn validate(sample: &Sample) -> Result<()> {
    let n = sample.strength.len();
    if n < MIN_PARTICLES {
        return Err(data_err(sample, "all rows".into(), format!("{n} particles are too few to diagnose a strength model (at least {MIN_PARTICLES} are needed)")));
    }
    if let Some(i) = sample.strength.x.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(data_err(sample, format!("row {} (line {})", i + 1, i + 2), format!("the strength at break must be finite and > 0 (got {})", sample.strength.x[i])));
    }
    let tally = sample.strength.view().tally();
    if tally.right == n {
        return Err(data_err(sample, "all rows".into(), format!("none of the {n} specimens broke (every row says it did not break by its value): no strength law can be fitted")));
    }
    for (name, col) in &sample.covariates {
        if col.len() != n {
            return Err(data_err(sample, format!("column {name}"), format!("{} values for {n} particles", col.len())));
        }
        if let Some(i) = col.iter().position(|v| v.is_some_and(|x| !x.is_finite())) {
            return Err(data_err(sample, format!("row {} (line {}), column {name}", i + 1, i + 2), "must be finite".to_string()));
        }
    }
    Ok(())
}

/// Complete numeric covariate columns worth diagnosing (a crush sample's five in their order,
/// then a strength file's numeric factors), its categorical columns, and the reasons for the
/// others.
type Diagnosable = (Vec<(String, Vec<f64>)>, Vec<(String, Vec<String>)>, Vec<String>);

fn diagnosable(sample: &Sample) -> Diagnosable {
    let mut out = Vec::new();
    let mut skipped = Vec::new();
    let names: Vec<String> = if sample.particles { DIAGNOSED.iter().map(|s| s.to_string()).collect() } else { Vec::new() };
    let names = names.into_iter().chain(sample.covariates.iter().map(|(n, _)| n.clone()).filter(|n| !DIAGNOSED.contains(&n.as_str()) || !sample.particles));
    for name in names {
        match sample.covariates.iter().find(|(n, _)| *n == name) {
            Some((_, col)) if col.iter().all(|v| v.is_none()) => skipped.push(format!("{name}: no values in the dataset")),
            None => skipped.push(format!("{name}: not in the dataset")),
            Some((_, col)) if col.iter().any(|v| v.is_none()) => {
                skipped.push(format!("{name}: empty on {} rows", col.iter().filter(|v| v.is_none()).count()))
            }
            Some((_, col)) => {
                let v: Vec<f64> = col.iter().map(|x| x.unwrap_or(f64::NAN)).collect();
                if v.iter().all(|x| *x == v[0]) {
                    skipped.push(format!("{name}: the same on every row ({})", v[0]));
                } else {
                    out.push((name, v));
                }
            }
        }
    }
    let mut levels = Vec::new();
    for (name, v) in &sample.levels {
        if v.iter().all(|x| *x == v[0]) {
            skipped.push(format!("{name}: one level only (\"{}\")", v.first().map_or("", |s| s.as_str())));
        } else {
            levels.push((name.clone(), v.clone()));
        }
    }
    (out, levels, skipped)
}

/// The cross-validation folds of a sample: stratified by the levels of its categorical
/// factors (by the first factor's level, then the next's, …: every level of the first of two or
/// more specimens is spread over at least two folds, and the others nearly always), the plain
/// seeded folds when it has none.
pub fn cv_folds(sample: &Sample, k: usize, seed: u64) -> Vec<usize> {
    let n = sample.strength.len();
    if sample.levels.is_empty() {
        return folds(n, k, seed);
    }
    let key: Vec<String> = (0..n).map(|i| sample.levels.iter().map(|(_, v)| v[i].as_str()).collect::<Vec<_>>().join("\u{1f}")).collect();
    folds_stratified(&key, k, seed)
}

/// K-fold cross-validated log score of a model (None if a training fit fails).
fn cv_log_score(x: Obs, terms: &[(Effect, Term)], folds: &[usize], k: usize) -> Option<f64> {
    cv_pointwise(x, terms, folds, k).map(|v| v.iter().sum())
}

/// The first decision a round makes from its bootstrap replicates `reps` so far that is not yet
/// settled ([`super::guard::settled`]), in words; None when every one is: for every candidate
/// (named `names`) that ΔBIC, the cross-validated score and identifiability leave `open`, its
/// family-wise p against α (its Λ in `lr`, made by the study's `guard`) and its share of failed
/// refits against the no-verdict share; and when the round then names nothing — its model is
/// the final one — that model's AD and KS p-values against α (`observed` holds its
/// statistics), which the verdict "the Weibull law fits" reads. A round that names an effect
/// reports its model's AD and KS p-values but decides nothing by them.
fn unsettled(reps: &[Replicate], observed: (f64, f64), lr: &[f64], df: &[usize], open: &[bool], names: &[String], guard: FamilyGuard, alpha: f64) -> Option<String> {
    let b = reps.len();
    let fam = family(&reps.iter().map(|r| r.2.as_slice()).collect::<Vec<_>>(), lr, df, guard, alpha);
    let failed = |j: usize| reps.iter().filter(|r| r.2[j].is_infinite()).count();
    let open: Vec<usize> = (0..lr.len()).filter(|&j| open[j]).collect();
    for &j in &open {
        if !settled(fam.count[j], b, alpha) {
            return Some(format!("at {b} replicates `{}`'s family-wise p {:.3} lay near α = {alpha}", names[j], fam.p[j]));
        }
        if !settled(failed(j), b, MAX_FAILED_SHARE) {
            return Some(format!("at {b} replicates `{}`'s share of failed refits {:.3} lay near the {} % above which it gets no verdict", names[j], failed(j) as f64 / b as f64, MAX_FAILED_SHARE * 100.0));
        }
    }
    if open.iter().any(|&j| fam.p[j] < alpha && decided(failed(j), b)) {
        return None;
    }
    let p = |count: usize| (1 + count) as f64 / (b as f64 + 1.0);
    let ad = reps.iter().filter(|r| r.0 >= observed.0).count();
    let ks = reps.iter().filter(|r| r.1 >= observed.1).count();
    if !settled(ad, b, alpha) {
        return Some(format!("at {b} replicates the final model's Anderson–Darling p {:.3} lay near α = {alpha}", p(ad)));
    }
    if !settled(ks, b, alpha) {
        return Some(format!("at {b} replicates the final model's Kolmogorov–Smirnov p {:.3} lay near α = {alpha}", p(ks)));
    }
    None
}

/// Quantile residuals and probability-integral transforms of `x` under a fitted model; a
/// censored or interval row's transform randomised within what the row allows
/// ([`Obs::pit`], V from a ChaCha8 stream of `seed`; a complete sample draws nothing).
pub fn residuals(fit: &ModelFit, x: Obs, seed: u64) -> (Vec<f64>, Vec<f64>) {
    use rand::{Rng, SeedableRng};
    let mut rng = (!x.complete()).then(|| rand_chacha::ChaCha8Rng::seed_from_u64(seed));
    let u: Vec<f64> = (0..x.len())
        .map(|i| {
            let v = rng.as_mut().map_or(0.0, |r| r.random::<f64>());
            x.pit(i, |s| fit.cdf(i, s), v)
        })
        .collect();
    (normal_scores(u.iter().copied()), u)
}

/// Seed of the randomised residuals of the observed sample (one draw for every round).
const RESIDUAL_SEED: u64 = 0x5E51_D0A1;

/// What one bootstrap replicate returns: (AD*, KS*, Λ* per candidate, G*).
type Replicate = (f64, f64, Vec<f64>, f64);

/// Runs the loop on a sample. `diagnose = false` skips the residual-trend permutation tests.
/// Callers that read only the names use [`names`].
pub fn analyse(sample: &Sample, settings: &NamingSettings, diagnose: bool) -> Result<Outcome> {
    walk(sample, settings, diagnose, true)
}

/// The effects the loop names in a sample, in order: `analyse(sample, settings, false).named`,
/// without what only a report reads — each candidate's profile band and description, the named
/// effects' exact (pivotal) bands and the weakest-link tests. Nothing the decision reads is
/// left out (the guard's bootstrap, ΔBIC, ΔCV, identifiability), so the names are the same.
/// Used by every caller that needs only them: a `"diagnosed"` strength model, its
/// cross-validation, the power replicates and the experiments' naming check.
pub fn names(sample: &Sample, settings: &NamingSettings) -> Result<Vec<Effect>> {
    Ok(decide(sample, settings)?.named)
}

/// The loop's decisions with their evidence (the guard's p-values and critical values, ΔBIC,
/// ΔCV, the stages), without what only a report reads ([`names`]): for studies of the guard
/// itself, such as its size over campaigns with nothing missing.
pub fn decide(sample: &Sample, settings: &NamingSettings) -> Result<Outcome> {
    walk(sample, settings, false, false)
}

/// The loop; `report = false` leaves the evidence's band, parameter, meaning and weakest-link
/// test empty and computes no pivotal band or size test ([`names`]).
fn walk(sample: &Sample, settings: &NamingSettings, diagnose: bool, report: bool) -> Result<Outcome> {
    validate(sample)?;
    let x = sample.strength.view();
    let n = x.len();
    let (covs, level_cols, skipped_covariates) = diagnosable(sample);
    let cov_refs: Vec<(&str, Vec<f64>)> = covs.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    let folds_k = settings.cv_folds.clamp(2, n);
    let fold = cv_folds(sample, folds_k, settings.seed ^ 0xF01D);

    // Every candidate's term, or why it is skipped.
    let mut available: Vec<(Effect, Term)> = Vec::new();
    let mut skipped: Vec<(Effect, String)> = Vec::new();
    for c in sample.candidates(&settings.candidates) {
        match sample.term(&c, settings.gamma) {
            Ok(t) => available.push((c, t)),
            Err(reason) => skipped.push((c, reason)),
        }
    }

    let mut current: Vec<(Effect, Term)> = Vec::new();
    let mut named: Vec<Effect> = Vec::new();
    let mut evidence = Vec::new();
    let mut stages = Vec::new();
    for round in 0.. {
        let model = fit_model(x, &current)?;
        // A two-population law replaces the base law; scale effects of recorded columns (one
        // column, or a scale per level) are fitted beside it, shifting both populations alike.
        // So a law is a candidate while every named effect is such a scale effect, and once a
        // law is named only such scale effects remain candidates.
        let beside_law = |t: &Term| matches!(t, Term::Linear(_) | Term::Levels { .. });
        let is_law = |t: &Term| matches!(t, Term::Populations(_));
        let law_named = current.iter().any(|(_, t)| is_law(t));
        let law_allowed = current.iter().all(|(_, t)| beside_law(t));
        let remaining: Vec<&(Effect, Term)> = if named.len() < settings.max_effects {
            available.iter().filter(|(c, t)| !named.contains(c) && if law_named { beside_law(t) } else { !is_law(t) || law_allowed }).collect()
        } else {
            Vec::new()
        };
        let df: Vec<usize> = remaining.iter().map(|(_, t)| Effect::extra_parameters(t)).collect();
        // Each candidate's model: the current terms and the candidate's.
        let extended: Vec<Vec<(Effect, Term)>> = remaining
            .iter()
            .map(|(c, t)| {
                let mut terms = current.clone();
                terms.push((c.clone(), t.clone()));
                terms
            })
            .collect();
        let ext: Vec<Option<ModelFit>> = extended.iter().map(|terms| fit_model(x, terms).ok()).collect();
        let lr: Vec<f64> = ext.iter().map(|e| e.as_ref().map_or(f64::NAN, |m| (2.0 * (m.loglik() - model.loglik())).max(0.0))).collect();

        // What decides besides the bootstrap: ΔBIC, the cross-validated log score, whether a law
        // is identified. A candidate failing one of them is not named whatever its p, so its
        // p does not hold the sequential bootstrap back.
        let cv0 = cv_log_score(x, &current, &fold, folds_k);
        // A partially pooled factor is charged its effective degrees of freedom (df[j] exactly
        // for every other candidate).
        let dbic: Vec<f64> = ext.iter().zip(&lr).map(|(e, l)| e.as_ref().map_or(f64::NAN, |m| -l + (m.effective_parameters() - model.effective_parameters()) * (n as f64).ln())).collect();
        let dcv: Vec<f64> = extended
            .iter()
            .zip(&ext)
            .map(|(terms, e)| match (e, cv0) {
                (Some(_), Some(b0)) => cv_log_score(x, terms, &fold, folds_k).map_or(f64::NAN, |a| a - b0),
                _ => f64::NAN,
            })
            .collect();
        // A two-population law the data do not identify is never named.
        let identified: Vec<bool> = ext.iter().map(|e| e.as_ref().is_some_and(|m| m.law.as_ref().is_none_or(|l| l.identifiable.is_ok()))).collect();
        let open: Vec<bool> = (0..remaining.len()).map(|j| identified[j] && dbic[j] < 0.0 && dcv[j] > 0.0).collect();
        let l1: Vec<f64> = lr.iter().zip(&df).map(|(l, d)| one_df_scale(*l, *d)).collect();

        // Diagnosis of the current model: its residuals' AD and KS statistics.
        let (res, u) = residuals(&model, x, settings.seed ^ RESIDUAL_SEED);
        let (ad, ks) = ad_ks_of_u(u);

        // Parametric bootstrap from the current model, in stages until every decision of the
        // round is settled (`guard`'s sequential pretest).
        let seed = settings.seed.wrapping_add(1_000_003 * round as u64);
        // A replicate whose refit fails counts as exceeding every observed statistic (Λ* = AD*
        // = KS* = +∞): dropped or counted as not exceeding, failures would lower the p-values
        // and the critical value (module docs).
        let replicate = |r: usize| -> Replicate {
            let Some((xs, m0)) = model.bootstrap_refit(x, &current, seed, r) else {
                return (f64::INFINITY, f64::INFINITY, vec![f64::INFINITY; remaining.len()], f64::NAN);
            };
            let (res, u) = residuals(&m0, xs.view(), settings.seed ^ RESIDUAL_SEED ^ ((r as u64 + 1) << 20));
            let g = gap_of(&res, &covs, &level_cols);
            let xs = xs.view();
            let (ad, ks) = ad_ks_of_u(u);
            let l: Vec<f64> = extended
                .iter()
                .zip(&ext)
                .map(|(terms, e)| match e {
                    None => f64::NAN,
                    Some(_) => fit_model_near(xs, terms, e.as_ref()).map_or(f64::INFINITY, |m| (2.0 * (m.loglik() - m0.loglik())).max(0.0)),
                })
                .collect();
            (ad, ks, l, g)
        };
        let mut reps: Vec<Replicate> = Vec::new();
        let looks = stages_of(settings.bootstrap, settings.sequential);
        let candidate_names: Vec<String> = remaining.iter().map(|(c, _)| c.name()).collect();
        // The decision that made the round draw its last stage: the one unsettled at the look
        // before it (or still unsettled at the last).
        let mut why_all = None;
        for &upto in &looks {
            let more: Vec<Replicate> = (reps.len()..upto).into_par_iter().map(replicate).collect();
            reps.extend(more);
            match unsettled(&reps, (ad, ks), &lr, &df, &open, &candidate_names, settings.guard, settings.alpha) {
                None => break,
                why => why_all = why,
            }
        }
        // Only a sequential bootstrap that drew every replicate has a reason to report.
        let why_all = why_all.filter(|_| looks.len() > 1 && reps.len() == settings.bootstrap);
        let null_failed = reps.iter().filter(|r| r.0.is_infinite()).count();
        if reps.is_empty() || 2 * null_failed > reps.len() {
            return Err(Error::numerical("discrepancy bootstrap", format!("only {} of {} refits of the current model converged", reps.len() - null_failed, reps.len())));
        }
        let b = reps.len() as f64;
        let p_of = |count: usize| (1 + count) as f64 / (b + 1.0);
        // Per candidate, the replicates whose Λ* could not be computed (its refit or the
        // current model's failed).
        let failures: Vec<usize> = (0..remaining.len()).map(|j| reps.iter().filter(|r| r.2[j].is_infinite()).count()).collect();

        let p_ad = p_of(reps.iter().filter(|r| r.0 >= ad).count());
        let p_ks = p_of(reps.iter().filter(|r| r.1 >= ks).count());
        let findings = if diagnose {
            let mut f = covariate_findings(&res, &cov_refs, settings.permutations, settings.seed ^ (round as u64 + 7))?.0;
            f.extend(level_findings(&res, &level_cols, settings.permutations, settings.seed ^ (round as u64 + 7)).0);
            f.sort_by(|a, b| a.p.total_cmp(&b.p));
            f
        } else {
            Vec::new()
        };
        let gap = gap_of(&res, &covs, &level_cols);
        let gap_expected = {
            let g: Vec<f64> = reps.iter().map(|r| r.3).filter(|g| g.is_finite()).collect();
            if g.is_empty() { f64::NAN } else { g.iter().sum::<f64>() / g.len() as f64 }
        };
        stages.push(Stage { model: model.clone(), residuals: res, ad, ks, p_ad, p_ks, findings, gap, gap_expected, replicates: reps.len(), unsettled: why_all });

        // Evidence: the family-wise guard over every candidate.
        let fam = family(&reps.iter().map(|r| r.2.as_slice()).collect::<Vec<_>>(), &lr, &df, settings.guard, settings.alpha);
        let mut round_ev: Vec<(Evidence, f64)> = Vec::new();
        for (j, ((c, t), e)) in remaining.iter().zip(&ext).enumerate() {
            let Some(m) = e else {
                round_ev.push((skipped_evidence(round, c.clone(), "the extended model did not converge".into()), f64::NAN));
                continue;
            };
            let (l, l1, dbic, dcv) = (lr[j], l1[j], dbic[j], dcv[j]);
            let p_b = p_of(reps.iter().filter(|r| r.2[j] >= l).count());
            let p_f = fam.p[j];
            let (parameter, meaning, weakest_link) = if report { describe(c, t, m, x) } else { ((String::new(), f64::NAN, f64::NAN), String::new(), None) };
            round_ev.push((
                Evidence {
                    round,
                    candidate: c.clone(),
                    skipped: None,
                    not_identified: m.law.as_ref().and_then(|l| l.identifiable.as_ref().err().cloned()),
                    loglik: m.loglik(),
                    lr: l,
                    p_bootstrap: p_b,
                    p_family: p_f,
                    lr_critical: fam.critical[j],
                    delta_bic: dbic,
                    delta_cv: dcv,
                    parameter: report.then_some(parameter),
                    // A partially pooled factor: the band of its spread τ (its parameter).
                    band: match (report, t) {
                        (false, _) => None,
                        (true, Term::Pooled { .. }) => m.tau_band(x, c, 0.90),
                        (true, _) => m.profile_band(x, c, 0.90).map(|b| natural_band(c, b)),
                    },
                    band_pivotal: false,
                    meaning,
                    shape: m.shape(),
                    passed: p_f < settings.alpha && open[j] && decided(failures[j], reps.len()),
                    named: false,
                    parameters: df[j],
                    weakest_link,
                    failures: failures[j],
                    replicates: reps.len(),
                },
                l1,
            ));
        }
        if round == 0 {
            for (c, reason) in &skipped {
                round_ev.push((skipped_evidence(round, c.clone(), reason.clone()), f64::NAN));
            }
        }
        let best = round_ev
            .iter()
            .enumerate()
            .filter(|(_, e)| e.0.passed)
            .max_by(|a, b| a.1.1.total_cmp(&b.1.1))
            .map(|(i, _)| i);
        // The two-population laws are two descriptions of one departure, not two effects: when
        // the strongest passing candidate is one of them, the passing one with the lower BIC is
        // named. (Ranked by Λ alone, the mixture's fifth parameter lets it approximate
        // competing-risks data closely enough to win about a third of the time; it must buy
        // ½ ln n in ℓ over the four-parameter law.)
        let law_evidence = |e: &Evidence| matches!(e.candidate, Effect::Populations(_));
        let best = best.map(|i| {
            if !law_evidence(&round_ev[i].0) {
                return i;
            }
            round_ev.iter().enumerate().filter(|(_, e)| e.0.passed && law_evidence(&e.0)).min_by(|a, b| a.1.0.delta_bic.total_cmp(&b.1.0.delta_bic)).map_or(i, |(j, _)| j)
        });
        let chosen = best.map(|i| {
            round_ev[i].0.named = true;
            round_ev[i].0.candidate.clone()
        });
        evidence.extend(round_ev.into_iter().map(|e| e.0));
        match chosen {
            Some(c) => {
                let t = available.iter().find(|(a, _)| *a == c).map(|(_, t)| t.clone()).unwrap_or(Term::Linear(Vec::new()));
                current.push((c.clone(), t));
                named.push(c);
            }
            None => break,
        }
    }
    if !report {
        return Ok(Outcome { named, evidence, stages, skipped_covariates, size_tests: Vec::new() });
    }
    // A named effect's exact band, in the model of the round that named it.
    for e in evidence.iter_mut().filter(|e| e.named) {
        if let Some(b) = stages.get(e.round + 1).and_then(|st| st.model.pivotal_band(&e.candidate, 0.90, 999, settings.seed ^ 0xBA4D ^ e.round as u64)) {
            e.band = Some(natural_band(&e.candidate, b));
            e.band_pivotal = true;
        }
    }
    // The weakest-link test of each named size effect, in the final model.
    let last = &stages[stages.len() - 1].model;
    let size_tests = current.iter().filter_map(|(c, t)| describe(c, t, last, x).2.map(|w| (c.clone(), w))).collect();
    Ok(Outcome { named, evidence, stages, skipped_covariates, size_tests })
}

fn skipped_evidence(round: usize, candidate: Effect, reason: String) -> Evidence {
    Evidence {
        round,
        candidate,
        skipped: Some(reason),
        not_identified: None,
        loglik: f64::NAN,
        lr: f64::NAN,
        p_bootstrap: f64::NAN,
        p_family: f64::NAN,
        lr_critical: f64::NAN,
        delta_bic: f64::NAN,
        delta_cv: f64::NAN,
        parameter: None,
        band: None,
        band_pivotal: false,
        meaning: String::new(),
        shape: f64::NAN,
        passed: false,
        named: false,
        parameters: 0,
        weakest_link: None,
        failures: 0,
        replicates: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A level of two specimens never falls wholly in one fold.
    #[test]
    fn cross_validation_folds_spread_every_level() {
        let mut s = Sample { strength: crate::obs::Observations::exact(vec![1.0; 40]), ..Sample::default() };
        let lot: Vec<String> = (0..40).map(|i| if i == 7 || i == 31 { "rare".to_string() } else { format!("lot{}", i % 3) }).collect();
        s.levels = vec![("lot".into(), lot.clone())];
        for seed in 0..50 {
            let f = cv_folds(&s, 10, seed);
            assert_ne!(f[7], f[31], "seed {seed}: the rare level in one fold");
            for l in ["lot0", "lot1", "lot2"] {
                let folds: std::collections::BTreeSet<usize> = (0..40).filter(|&i| lot[i] == l).map(|i| f[i]).collect();
                assert!(folds.len() >= 10, "seed {seed}: {l} in folds {folds:?}");
            }
        }
    }
}

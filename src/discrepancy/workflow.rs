//! The name → add → diagnose-again loop on crush strengths (issue 7, steps 1–3).
//!
//! Each round starts from the current model (round 0: the deliverable's single Weibull law) and
//! 1. **diagnoses** it: quantile residuals r_i = Φ⁻¹(F_i(x_i)), their Spearman trend against
//!    every covariate with a permutation p-value, the tertile of largest departure, and AD/KS
//!    statistics whose p-values come from the round's parametric bootstrap (each replicate
//!    refits the current model);
//! 2. **fits every remaining candidate** ([`super::effects`]) on top of it and scores it by
//!    * the likelihood ratio Λ = 2(ℓ_cand − ℓ_current), calibrated by the same bootstrap:
//!      B samples drawn from the fitted current model at the observed covariates, each
//!      refitted with and without every candidate. The marginal p-value counts Λ*_c ≥ Λ_c; the
//!      **false-discovery guard** uses the family-wise (max-T) p-value, which counts
//!      max_c Λ*_c ≥ Λ_c, so the chance of naming any effect when none is there is α whatever
//!      the number of candidates;
//!    * ΔBIC = −Λ + k ln n (k = 1 extra parameter);
//!    * the K-fold cross-validated log score, Δ against the current model;
//! 3. **names** the candidate with the largest Λ among those passing the guard — max-T
//!    p < α, ΔBIC < 0 and a better cross-validated log score — adds it and starts the next
//!    round; otherwise it says no (further) missing effect was found.
//!
//! The gap measure is the residual-structure statistic G = n Σ_c ρ_c² over the covariates the
//! data carry (ρ_c Spearman's correlation of the quantile residuals with covariate c). Under a
//! model that misses nothing each term is ≈ χ²₁, so E(G) ≈ the number of covariates; a missing
//! effect with covariate c adds ≈ n ρ_c².
//!
//! Deterministic for a seed and any thread count: every replicate has its own ChaCha8 stream.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::effects::{Candidate, ModelFit, Term, fit_model, fit_model_near};
use super::gof::{CovariateFinding, ad_ks_of_u, covariate_findings, normal_scores};
use crate::error::{Error, Result};

/// Fewest particles the workflow accepts.
pub const MIN_PARTICLES: usize = 10;

/// Covariate columns the diagnosis looks at, in order.
pub const DIAGNOSED: [&str; 5] = ["diameter_m", "roundness", "sphericity", "temperature_c", "impacts"];

/// Settings of the loop: the `[discrepancy]` section of a study (the seed is the study's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// Candidates to consider (default: all).
    pub candidates: Vec<Candidate>,
    /// Bootstrap replicates per round: LR calibration and AD/KS p-values (default 499).
    pub bootstrap: usize,
    /// Permutations of each residual-trend test (default 999).
    pub permutations: usize,
    /// Family-wise error rate of the guard (default 0.05).
    pub alpha: f64,
    /// Folds of the cross-validated log score (default 10).
    pub cv_folds: usize,
    /// Most effects to name (default 3).
    pub max_effects: usize,
    /// Tavares–King γ of the damage candidate (default 5).
    #[serde(rename = "tavares_king_gamma")]
    pub gamma: f64,
    /// Seed (set from the study's seed, not read from the section).
    #[serde(skip)]
    pub seed: u64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            candidates: super::effects::ALL.to_vec(),
            bootstrap: 499,
            permutations: 999,
            alpha: 0.05,
            cv_folds: 10,
            max_effects: 3,
            gamma: 5.0,
            seed: 20261122,
        }
    }
}

/// Strengths and covariates of one crush sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Where it came from (for messages).
    pub source: String,
    /// σ̄ at break (Pa), per particle.
    pub strength: Vec<f64>,
    /// Covariate columns by name (`None`: empty cell).
    pub covariates: Vec<(String, Vec<Option<f64>>)>,
}

/// Evidence for one candidate in one round.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evidence {
    /// Round (0: against the base model).
    pub round: usize,
    /// The candidate.
    pub candidate: Candidate,
    /// Why it was not fitted (then every number is NaN).
    pub skipped: Option<String>,
    /// Log-likelihood with the candidate added.
    pub loglik: f64,
    /// Λ = 2(ℓ_cand − ℓ_current).
    pub lr: f64,
    /// Bootstrap p-value of Λ for this candidate alone.
    pub p_bootstrap: f64,
    /// Family-wise (max-T) bootstrap p-value: the guard.
    pub p_family: f64,
    /// The round's critical Λ: the (1 − α) quantile of max_c Λ*_c over the bootstrap.
    pub lr_critical: f64,
    /// ΔBIC (negative favours the candidate).
    pub delta_bic: f64,
    /// Δ cross-validated log score (positive favours the candidate).
    pub delta_cv: f64,
    /// Fitted parameter (symbol, value, standard error; NaN where not available).
    pub parameter: Option<(String, f64, f64)>,
    /// What the parameter means.
    pub meaning: String,
    /// Weibull modulus of the extended model.
    pub shape: f64,
    /// Passed the false-discovery guard.
    pub passed: bool,
    /// Named in this round.
    pub named: bool,
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
    /// Gap measure G = n Σ ρ².
    pub gap: f64,
}

/// Result of the loop.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Effects named, in order.
    pub named: Vec<Candidate>,
    /// Evidence of every candidate in every round.
    pub evidence: Vec<Evidence>,
    /// One stage per round: `stages[0]` the base model, the last the final model.
    pub stages: Vec<Stage>,
    /// Covariates not diagnosed, with the reason.
    pub skipped_covariates: Vec<String>,
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
pub const GAP_MEASURE: &str = "residual structure G = n·Σ_c ρ_c², ρ_c = Spearman correlation of the quantile residuals with covariate c over the covariates the data carry; ≈ number of covariates when nothing is missing";

fn data_err(sample: &Sample, location: String, rule: String) -> Error {
    Error::Data { file: sample.source.clone(), location, rule }
}

/// Checks the sample: enough particles, finite positive strengths, finite covariates.
pub fn validate(sample: &Sample) -> Result<()> {
    let n = sample.strength.len();
    if n < MIN_PARTICLES {
        return Err(data_err(sample, "all rows".into(), format!("{n} particles are too few to diagnose a strength model (at least {MIN_PARTICLES} are needed)")));
    }
    if let Some(i) = sample.strength.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(data_err(sample, format!("row {} (line {})", i + 1, i + 2), format!("the strength at break must be finite and > 0 (got {})", sample.strength[i])));
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

/// Complete numeric covariate columns worth diagnosing, and the reasons for the others.
fn diagnosable(sample: &Sample) -> (Vec<(&'static str, Vec<f64>)>, Vec<String>) {
    let mut out = Vec::new();
    let mut skipped = Vec::new();
    for name in DIAGNOSED {
        match sample.covariates.iter().find(|(n, _)| n == name) {
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
    (out, skipped)
}

/// ln σ_i of particle `i` under a model fitted on other rows: its linear terms' columns at row
/// i and the damage offset at the fitted ratio.
fn predict_ln_scale(fit: &ModelFit, terms: &[(Candidate, Term)], i: usize) -> f64 {
    let mut s = fit.reg.mu;
    let mut j = 0;
    for (_, t) in terms {
        match t {
            Term::Linear(z) => {
                s += fit.reg.beta[j] * z[i];
                j += 1;
            }
            Term::Damage { impacts, gamma } => {
                let x0 = fit.damage_ratio.unwrap_or(0.0);
                s += super::effects::damage_offset(x0, *gamma, impacts[i]).unwrap_or(f64::NEG_INFINITY);
            }
        }
    }
    s
}

fn subset(terms: &[(Candidate, Term)], rows: &[usize]) -> Vec<(Candidate, Term)> {
    terms
        .iter()
        .map(|(c, t)| {
            let t = match t {
                Term::Linear(z) => Term::Linear(rows.iter().map(|&i| z[i]).collect()),
                Term::Damage { impacts, gamma } => Term::Damage { impacts: rows.iter().map(|&i| impacts[i]).collect(), gamma: *gamma },
            };
            (*c, t)
        })
        .collect()
}

/// K-fold cross-validated log score of a model (None if a training fit fails).
fn cv_log_score(x: &[f64], terms: &[(Candidate, Term)], folds: &[usize], k: usize) -> Option<f64> {
    let mut total = 0.0;
    for f in 0..k {
        let train: Vec<usize> = (0..x.len()).filter(|&i| folds[i] != f).collect();
        let xt: Vec<f64> = train.iter().map(|&i| x[i]).collect();
        let fit = fit_model(&xt, &subset(terms, &train)).ok()?;
        for i in (0..x.len()).filter(|&i| folds[i] == f) {
            total += fit.reg.ln_density_at(predict_ln_scale(&fit, terms, i), x[i]);
        }
    }
    total.is_finite().then_some(total)
}

/// A seeded fold assignment (balanced, shuffled).
fn folds(n: usize, k: usize, seed: u64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut idx: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        idx.swap(i, rand::Rng::random_range(&mut rng, 0..=i));
    }
    let mut f = vec![0; n];
    for (pos, &i) in idx.iter().enumerate() {
        f[i] = pos % k;
    }
    f
}

/// Quantile residuals and probability-integral transforms of `x` under a fitted model.
pub fn residuals(fit: &ModelFit, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let d = fit.design();
    let u: Vec<f64> = (0..x.len()).map(|i| fit.reg.cdf(&d, i, x[i])).collect();
    (normal_scores(u.iter().copied()), u)
}

/// What one bootstrap replicate returns: (AD*, KS*, Λ* per candidate).
type Replicate = (f64, f64, Vec<f64>);

/// Runs the loop on a sample. `diagnose = false` skips the residual-trend permutation tests
/// (used by the power study, which needs only the names).
pub fn analyse(sample: &Sample, settings: &Settings, diagnose: bool) -> Result<Outcome> {
    validate(sample)?;
    let x = &sample.strength;
    let n = x.len();
    let (covs, skipped_covariates) = diagnosable(sample);
    let cov_refs: Vec<(&str, Vec<f64>)> = covs.iter().map(|(k, v)| (*k, v.clone())).collect();
    let folds_k = settings.cv_folds.clamp(2, n);
    let fold = folds(n, folds_k, settings.seed ^ 0xF01D);

    // Every candidate's term, or why it is skipped.
    let mut available: Vec<(Candidate, Term)> = Vec::new();
    let mut skipped: Vec<(Candidate, String)> = Vec::new();
    for &c in &settings.candidates {
        match c.term(&sample.covariates, settings.gamma) {
            Ok(t) => available.push((c, t)),
            Err(reason) => skipped.push((c, reason)),
        }
    }

    let mut current: Vec<(Candidate, Term)> = Vec::new();
    let mut named = Vec::new();
    let mut evidence = Vec::new();
    let mut stages = Vec::new();
    for round in 0.. {
        let model = fit_model(x, &current)?;
        let remaining: Vec<&(Candidate, Term)> = if named.len() < settings.max_effects {
            available.iter().filter(|(c, _)| !named.contains(c)).collect()
        } else {
            Vec::new()
        };
        let ext: Vec<Option<ModelFit>> = remaining
            .iter()
            .map(|(c, t)| {
                let mut terms = current.clone();
                terms.push((*c, t.clone()));
                fit_model(x, &terms).ok()
            })
            .collect();
        let lr: Vec<f64> = ext.iter().map(|e| e.as_ref().map_or(f64::NAN, |m| (2.0 * (m.loglik() - model.loglik())).max(0.0))).collect();

        // Parametric bootstrap from the current model.
        let seed = settings.seed.wrapping_add(1_000_003 * round as u64);
        let reps: Vec<Option<Replicate>> = (0..settings.bootstrap)
            .into_par_iter()
            .map(|r| {
                let (xs, m0) = model.bootstrap_refit(&current, seed, r)?;
                let (_, u) = residuals(&m0, &xs);
                let (ad, ks) = ad_ks_of_u(u);
                let l: Vec<f64> = remaining
                    .iter()
                    .zip(&ext)
                    .map(|((c, t), e)| {
                        if e.is_none() {
                            return f64::NAN;
                        }
                        let mut terms = current.clone();
                        terms.push((*c, t.clone()));
                        let hint = e.as_ref().and_then(|m| m.damage_ratio);
                        fit_model_near(&xs, &terms, hint).map_or(f64::NAN, |m| (2.0 * (m.loglik() - m0.loglik())).max(0.0))
                    })
                    .collect();
                Some((ad, ks, l))
            })
            .collect();
        let reps: Vec<Replicate> = reps.into_iter().flatten().collect();
        if reps.len() < settings.bootstrap / 2 || reps.is_empty() {
            return Err(Error::numerical("discrepancy bootstrap", format!("only {} of {} refits converged", reps.len(), settings.bootstrap)));
        }
        let b = reps.len() as f64;
        let p_of = |count: usize| (1 + count) as f64 / (b + 1.0);

        // Diagnosis of the current model.
        let (res, u) = residuals(&model, x);
        let (ad, ks) = ad_ks_of_u(u);
        let p_ad = p_of(reps.iter().filter(|r| r.0 >= ad).count());
        let p_ks = p_of(reps.iter().filter(|r| r.1 >= ks).count());
        let findings = if diagnose {
            covariate_findings(&res, &cov_refs, settings.permutations, settings.seed ^ (round as u64 + 7))?.0
        } else {
            Vec::new()
        };
        let gap = n as f64 * covs.iter().map(|(_, v)| super::gof::spearman(&res, v).powi(2)).sum::<f64>();
        stages.push(Stage { model: model.clone(), residuals: res, ad, ks, p_ad, p_ks, findings, gap });

        // Evidence.
        let cv0 = cv_log_score(x, &current, &fold, folds_k);
        let max_star: Vec<f64> = reps.iter().map(|r| r.2.iter().copied().filter(|v| v.is_finite()).fold(0.0, f64::max)).collect();
        let lr_critical = crate::stats::interpolated_quantiles(max_star.clone(), &[1.0 - settings.alpha])[0];
        let mut round_ev: Vec<Evidence> = Vec::new();
        for (j, ((c, t), e)) in remaining.iter().zip(&ext).enumerate() {
            let Some(m) = e else {
                round_ev.push(skipped_evidence(round, *c, "the extended model did not converge".into()));
                continue;
            };
            let l = lr[j];
            let p_b = p_of(reps.iter().filter(|r| r.2[j] >= l).count());
            let p_f = p_of(max_star.iter().filter(|&&s| s >= l).count());
            let dbic = -l + (n as f64).ln();
            let mut terms = current.clone();
            terms.push((*c, t.clone()));
            let dcv = match (cv_log_score(x, &terms, &fold, folds_k), cv0) {
                (Some(a), Some(b0)) => a - b0,
                _ => f64::NAN,
            };
            let (beta, se) = m.coefficient(*c).unwrap_or((f64::NAN, f64::NAN));
            let (sym, val, meaning) = c.parameter(beta, m.shape());
            // Delta method by a central difference of the reported parameter in β.
            let val_se = if *c == Candidate::Damage { f64::NAN } else { 0.5 * (c.parameter(beta + se, m.shape()).1 - c.parameter(beta - se, m.shape()).1).abs() };
            round_ev.push(Evidence {
                round,
                candidate: *c,
                skipped: None,
                loglik: m.loglik(),
                lr: l,
                p_bootstrap: p_b,
                p_family: p_f,
                lr_critical,
                delta_bic: dbic,
                delta_cv: dcv,
                parameter: Some((sym.to_string(), val, val_se)),
                meaning,
                shape: m.shape(),
                passed: p_f < settings.alpha && dbic < 0.0 && dcv > 0.0,
                named: false,
            });
        }
        if round == 0 {
            for (c, reason) in &skipped {
                round_ev.push(skipped_evidence(round, *c, reason.clone()));
            }
        }
        let best = round_ev
            .iter()
            .enumerate()
            .filter(|(_, e)| e.passed)
            .max_by(|a, b| a.1.lr.total_cmp(&b.1.lr))
            .map(|(i, _)| i);
        let chosen = best.map(|i| {
            round_ev[i].named = true;
            round_ev[i].candidate
        });
        evidence.extend(round_ev);
        match chosen {
            Some(c) => {
                let t = available.iter().find(|(a, _)| *a == c).map(|(_, t)| t.clone()).unwrap_or(Term::Linear(Vec::new()));
                current.push((c, t));
                named.push(c);
            }
            None => break,
        }
    }
    Ok(Outcome { named, evidence, stages, skipped_covariates })
}

fn skipped_evidence(round: usize, candidate: Candidate, reason: String) -> Evidence {
    Evidence {
        round,
        candidate,
        skipped: Some(reason),
        loglik: f64::NAN,
        lr: f64::NAN,
        p_bootstrap: f64::NAN,
        p_family: f64::NAN,
        lr_critical: f64::NAN,
        delta_bic: f64::NAN,
        delta_cv: f64::NAN,
        parameter: None,
        meaning: String::new(),
        shape: f64::NAN,
        passed: false,
        named: false,
    }
}

//! Preposterior analysis of one candidate experiment by importance reweighting of the current
//! state of knowledge.
//!
//! # The state of knowledge
//!
//! K weighted prior samples ([`Knowledge`]): sample k has weight w_k (Σ w = 1), the loss
//! L_ka of every action a of the decision, the values q_kj of the quantities whose posterior
//! is of interest (log10 P_break of each material, say) and labels c_kl (which damage model
//! and which strength model the sample came from).
//!
//! # One outer draw
//!
//! 1. A truth t is drawn from the prior (index t with probability w_t; optionally only among
//!    the samples with a given label, to ask "if the truth were …").
//! 2. The experiment's data y are simulated under sample t ([`Experiment::simulate`]).
//! 3. The posterior is the prior reweighted by the likelihood, w'_k ∝ w_k p(y | k) for k ≠ t,
//!    w'_t = 0: the truth is left out of the reweighted set so that it is not scored as its
//!    own best fit (with it, a sharp experiment would look better than it is).
//! 4. Its effective sample size ESS = 1 / Σ w'² is checked against `min_ess`; below it a reserve
//!    of further prior samples ([`Settings::active`]) is reweighted together with the prior
//!    (the resampling fallback), then the experiment's own [`Experiment::fallback`] posterior
//!    (a refit on the data, say) is tried; when neither reaches `min_ess` the draw is counted as
//!    collapsed and kept (its numbers are then less reliable; the count is reported). The
//!    studies' plans go on to resample-move instead ([`super::smc`]), which evaluates them
//!    test after test with this engine's definitions.
//! 5. The Bayes action a* = argmin_a Σ_k w'_k L_ka is taken; it is a correct selection when it
//!    is also a best action under the truth (L_ta* = min_a L_ta; under a tie every tied action
//!    is correct).
//!
//! # Metrics (means over J outer draws, each with its Monte Carlo standard error sd/√J)
//!
//! * probability of correct selection, PCS = P(a* is the truth's best action), against the
//!   prior's PCS_0 = Σ_k w_k [a₀ best for k] for the prior Bayes action a₀;
//! * expected value of sample information, EVSI = min_a Σ_k w_k L_ka − E_y[min_a Σ_k w'_k L_ka]
//!   (prior Bayes risk minus preposterior Bayes risk, ≥ 0). With the truths drawn only among
//!   the samples of a given label ([`Settings::truth`]) the prior PCS is taken over those
//!   truths and the value is the loss the data save under the truth, E_t[L_ta₀ − L_ta*] (a₀ the
//!   unconditioned prior's action, which is what one would choose without the experiment);
//!   over the whole prior the two definitions have the same expectation, and only the first
//!   must be ≥ 0;
//! * per quantity: the expected posterior mean, variance and width of the central 90 % band
//!   (weighted quantiles, [`crate::stats::weighted_quantiles`]);
//! * per label: the expected posterior weight of the truth's label;
//! * optionally, the mean of a score the experiment gives each simulated dataset under its
//!   truth ([`Experiment::score`]) on the first [`Settings::scored`] outer draws — for crush
//!   tests, whether the discrepancy workflow's naming loop, run on the pooled data, names the
//!   truth's effects: another decision rule on the same simulated data.
//!
//! Outer draw j uses its own random stream (ChaCha8, stream j + 1 of `seed`) and the draws are
//! evaluated in parallel and collected in order, so the result does not depend on the number of
//! threads.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::stats::Categorical;

/// Weighted prior samples with their losses, quantities and labels (row-major per sample).
#[derive(Debug, Clone, PartialEq)]
pub struct Knowledge {
    /// Weights, summing to 1.
    pub weights: Vec<f64>,
    /// Number of actions A.
    pub actions: usize,
    /// Loss of each action, K × A.
    pub loss: Vec<f64>,
    /// Number of quantities Q.
    pub quantities: usize,
    /// Quantity values, K × Q.
    pub values: Vec<f64>,
    /// Number of label kinds.
    pub label_kinds: usize,
    /// Labels, K × label kinds.
    pub labels: Vec<u32>,
    /// Per quantity, the sample indices in ascending order of its value (for the weighted
    /// quantiles without a sort per posterior).
    order: Vec<Vec<u32>>,
}

impl Knowledge {
    /// Checks the shapes and normalises the weights.
    pub fn new(weights: Vec<f64>, actions: usize, loss: Vec<f64>, quantities: usize, values: Vec<f64>, label_kinds: usize, labels: Vec<u32>) -> Result<Knowledge> {
        let k = weights.len();
        let bad = |rule: String| Err(Error::numerical("state of knowledge", rule));
        if k < 2 || actions < 1 {
            return bad(format!("needs at least 2 samples and 1 action, got {k} and {actions}"));
        }
        if loss.len() != k * actions || values.len() != k * quantities || labels.len() != k * label_kinds {
            return bad(format!("shapes: {k} samples, {} losses for {actions} actions, {} values for {quantities} quantities, {} labels for {label_kinds} kinds", loss.len(), values.len(), labels.len()));
        }
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) || loss.iter().any(|v| !v.is_finite()) {
            return bad("weights must be finite and ≥ 0, losses finite".into());
        }
        let total: f64 = weights.iter().sum();
        if total <= 0.0 {
            return bad("the weights sum to 0".into());
        }
        let order = (0..quantities)
            .map(|j| {
                let mut idx: Vec<u32> = (0..k as u32).collect();
                idx.sort_by(|&a, &b| values[a as usize * quantities + j].total_cmp(&values[b as usize * quantities + j]));
                idx
            })
            .collect();
        Ok(Knowledge { weights: weights.iter().map(|w| w / total).collect(), actions, loss, quantities, values, label_kinds, labels, order })
    }

    /// Number of samples K.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// Whether there is no sample.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// The loss of action a under sample k.
    pub fn loss_of(&self, k: usize, a: usize) -> f64 {
        self.loss[k * self.actions + a]
    }

    /// Whether action a is a best action under sample k (ties: every tied action is best).
    pub fn is_best(&self, k: usize, a: usize) -> bool {
        let row = &self.loss[k * self.actions..(k + 1) * self.actions];
        row[a] <= row[argmin(row)]
    }

    /// Expected loss of every action under weights `w`.
    pub fn expected_loss(&self, w: &[f64]) -> Vec<f64> {
        let mut e = vec![0.0; self.actions];
        for (k, &wk) in w.iter().enumerate() {
            if wk > 0.0 {
                for (a, ea) in e.iter_mut().enumerate() {
                    *ea += wk * self.loss_of(k, a);
                }
            }
        }
        e
    }

    /// The summary of the distribution with weights `w` over these samples.
    pub fn summarise(&self, w: &[f64]) -> Posterior {
        let expected_loss = self.expected_loss(w);
        let mut mean = vec![0.0; self.quantities];
        let mut var = vec![0.0; self.quantities];
        let mut width90 = vec![0.0; self.quantities];
        let mut band90 = vec![(0.0, 0.0); self.quantities];
        for j in 0..self.quantities {
            let v = |k: usize| self.values[k * self.quantities + j];
            let m: f64 = w.iter().enumerate().map(|(k, wk)| wk * v(k)).sum();
            mean[j] = m;
            var[j] = w.iter().enumerate().map(|(k, wk)| wk * (v(k) - m).powi(2)).sum();
            let sorted = self.order[j].iter().map(|&k| k as usize).filter(|&k| w[k] > 0.0).map(|k| (v(k), w[k]));
            let q = crate::stats::weighted_quantiles_sorted(sorted, &[0.05, 0.95]);
            width90[j] = q[1] - q[0];
            band90[j] = (q[0], q[1]);
        }
        let label_weight = |kind: usize, label: u32| w.iter().enumerate().filter(|(k, _)| self.labels[k * self.label_kinds + kind] == label).map(|(_, wk)| wk).sum();
        Posterior { expected_loss, mean, var, width90, band90, label_weights: (0..self.label_kinds).map(|kind| (0..=self.labels.iter().copied().max().unwrap_or(0)).map(|l| label_weight(kind, l)).collect()).collect() }
    }
}

/// The index of the smallest value (the first of equals).
fn argmin(v: &[f64]) -> usize {
    let mut best = 0;
    for (i, x) in v.iter().enumerate() {
        if *x < v[best] {
            best = i;
        }
    }
    best
}

/// A distribution over the state of knowledge, summarised.
#[derive(Debug, Clone, PartialEq)]
pub struct Posterior {
    /// Expected loss of each action.
    pub expected_loss: Vec<f64>,
    /// Mean of each quantity.
    pub mean: Vec<f64>,
    /// Variance of each quantity.
    pub var: Vec<f64>,
    /// Width of the central 90 % band of each quantity.
    pub width90: Vec<f64>,
    /// The band itself (its 5 % and 95 % weighted quantiles, inverse-CDF definition: each is a
    /// sample's value), so that the width of any non-decreasing map of the quantity — log10 P
    /// floored at some P, say — is the map's difference at the two ends, exactly.
    pub band90: Vec<(f64, f64)>,
    /// Weight of each label, per label kind.
    pub label_weights: Vec<Vec<f64>>,
}

impl Posterior {
    /// The Bayes action.
    pub fn action(&self) -> usize {
        argmin(&self.expected_loss)
    }
}

/// A candidate experiment: data simulated under a prior sample, and their likelihood under
/// every sample.
pub trait Experiment: Sync {
    /// One simulated dataset.
    type Data: Send;
    /// Data simulated under prior sample `truth`.
    fn simulate(&self, truth: usize, rng: &mut ChaCha8Rng) -> Self::Data;
    /// ln p(data | sample k), up to a constant common to every k (−∞ allowed).
    fn loglik(&self, data: &Self::Data, k: usize) -> f64;
    /// The posterior by another route when reweighting collapses (a refit on the data); None
    /// when the experiment has none.
    fn fallback(&self, _data: &Self::Data, _truth: usize) -> Option<Result<Posterior>> {
        None
    }
    /// A score of outer draw `draw`'s data under its truth (1 when the naming loop names the
    /// truth's effects, say); None when the experiment has none.
    fn score(&self, _data: &Self::Data, _truth: usize, _draw: usize) -> Option<Score> {
        None
    }
}

/// One outer draw's score ([`Experiment::score`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Score {
    /// The score (a failure scores what its experiment says, 0 for the naming loop).
    pub value: f64,
    /// Whether the scored procedure failed on the draw's data (counted apart, so that a
    /// failure is never read as a verdict).
    pub failed: bool,
}

/// Settings of the preposterior analysis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Outer draws J (simulated datasets).
    pub outer: usize,
    /// Smallest effective sample size of a reweighted posterior before the fallback.
    pub min_ess: f64,
    /// Seed of the outer draws.
    pub seed: u64,
    /// Draw the truths only among the samples with this (label kind, label): "if the truth
    /// were Tavares–King damage, …". None: from the whole prior.
    pub truth: Option<(usize, u32)>,
    /// The first `active` samples are the prior of every outer draw; the rest are a reserve of
    /// further prior samples, reweighted together with them only when the ESS falls below
    /// `min_ess` (the resampling fallback). None: no reserve.
    pub active: Option<usize>,
    /// The experiment's score ([`Experiment::score`]) is computed on the first `scored` outer
    /// draws (0: not at all).
    pub scored: usize,
}

/// One outer draw's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Draw {
    /// The truth's index.
    pub truth: usize,
    /// The posterior.
    pub posterior: Posterior,
    /// Effective sample size of the reweighted prior.
    pub ess: f64,
    /// How the posterior was obtained.
    pub route: Route,
    /// The experiment's score of the data, when computed.
    pub score: Option<Score>,
}

/// How an outer draw's posterior was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Route {
    /// Reweighting with an adequate ESS.
    Reweighted,
    /// The experiment's fallback (ESS below the threshold).
    Fallback,
    /// Resample-move ([`super::smc`]): ESS below the threshold after the fallback, the posterior
    /// tempered in and its samples moved.
    Moved,
    /// ESS below the threshold and no fallback: reweighted anyway.
    Collapsed,
}

/// A mean with its Monte Carlo standard error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Mean.
    pub mean: f64,
    /// Standard error.
    pub se: f64,
}

impl Estimate {
    /// Mean and sd/√n of `v`.
    pub fn of(v: &[f64]) -> Estimate {
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        Estimate { mean, se: (var / n).sqrt() }
    }
}

/// The metrics of one candidate at one size.
#[derive(Debug, Clone, PartialEq)]
pub struct Metrics {
    /// The prior's summary.
    pub prior: Posterior,
    /// Prior probability that the prior Bayes action is the best.
    pub prior_pcs: f64,
    /// Probability of correct selection after the experiment.
    pub pcs: Estimate,
    /// Expected value of sample information (in the loss's unit).
    pub evsi: Estimate,
    /// Expected posterior mean, per quantity.
    pub mean: Vec<Estimate>,
    /// Expected posterior variance, per quantity.
    pub var: Vec<Estimate>,
    /// Expected width of the posterior 90 % band, per quantity.
    pub width90: Vec<Estimate>,
    /// Expected posterior weight of the truth's label, per label kind.
    pub true_label_weight: Vec<Estimate>,
    /// Prior weight of the truth's label (its expectation over the truths' distribution), per
    /// label kind.
    pub prior_true_label_weight: Vec<f64>,
    /// Median ESS of the posteriors (reweighted, or after resample-move with identical samples
    /// merged).
    pub median_ess: f64,
    /// Outer draws that used the fallback.
    pub fallbacks: usize,
    /// Outer draws whose posterior came from resample-move ([`super::smc`]).
    pub moved: usize,
    /// Outer draws whose reweighting collapsed without a fallback (or stayed below the
    /// threshold after resample-move).
    pub collapsed: usize,
    /// The experiment's score over the draws that computed it; None when no draw did.
    pub score: Option<Scored>,
    /// Every outer draw.
    pub draws: Vec<Draw>,
    /// The per-draw values whose means are `pcs`, `evsi` and `true_label_weight`, in the order
    /// of `draws`: two analyses on the same outer draws (common random numbers) are compared
    /// by the standard error of their per-draw differences ([`paired`]).
    pub per_draw: PerDraw,
}

/// Per outer draw: the values averaged into [`Metrics`]' `pcs`, `evsi` and
/// `true_label_weight`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PerDraw {
    /// 1 when the posterior Bayes action is the best under the truth, else 0.
    pub pcs: Vec<f64>,
    /// The value of sample information of the draw (module docs).
    pub evsi: Vec<f64>,
    /// The posterior weight of the truth's label, per label kind.
    pub true_label_weight: Vec<Vec<f64>>,
}

/// The mean of `a − b` over paired outer draws with its standard error sd(a_j − b_j)/√J: the
/// Monte Carlo error of a difference between two analyses on the same truths and data (common
/// random numbers), usually far smaller than either's own error. `None` when the two are not
/// paired (different numbers of draws).
pub fn paired(a: &[f64], b: &[f64]) -> Option<Estimate> {
    (a.len() == b.len() && !a.is_empty()).then(|| Estimate::of(&a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<_>>()))
}

/// The experiment's score ([`Experiment::score`]) over the outer draws that computed it, with
/// the reweighting's expected posterior weight of the truth's label on the same draws (a paired
/// comparison of the two decision rules).
#[derive(Debug, Clone, PartialEq)]
pub struct Scored {
    /// Outer draws that computed the score.
    pub draws: usize,
    /// Of those, the draws on whose data the scored procedure failed (scored as it says).
    pub failures: usize,
    /// Mean score.
    pub mean: Estimate,
    /// Expected posterior weight of the truth's label, per label kind, on the same draws.
    pub true_label_weight: Vec<Estimate>,
}

/// The preposterior analysis of `experiment` on `knowledge`.
pub fn preposterior<E: Experiment>(knowledge: &Knowledge, experiment: &E, settings: Settings) -> Result<Metrics> {
    if settings.outer < 2 {
        return Err(Error::numerical("preposterior analysis", format!("needs at least 2 outer draws, got {}", settings.outer)));
    }
    let kn = knowledge;
    let truths = Truths::new(kn, &settings)?;
    let active = truths.active;
    let draws: Vec<Draw> = (0..settings.outer)
        .into_par_iter()
        .map(|j| {
            let (mut rng, truth) = truths.start(&settings, j);
            debug_assert!(kn.weights[truth] > 0.0);
            let data = experiment.simulate(truth, &mut rng);
            let score = if j < settings.scored { experiment.score(&data, truth, j) } else { None };
            let reweigh = |n: usize| -> (Vec<f64>, f64, f64) {
                let ll: Vec<f64> = (0..kn.len()).map(|k| if k >= n || k == truth || kn.weights[k] == 0.0 { f64::NEG_INFINITY } else { experiment.loglik(&data, k) }).collect();
                let top = ll.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let mut w: Vec<f64> = if top.is_finite() { ll.iter().zip(&kn.weights).map(|(l, wk)| wk * (l - top).exp()).collect() } else { vec![0.0; kn.len()] };
                let total: f64 = w.iter().sum();
                let ess = if total > 0.0 {
                    w.iter_mut().for_each(|x| *x /= total);
                    1.0 / w.iter().map(|x| x * x).sum::<f64>()
                } else {
                    0.0
                };
                (w, ess, total)
            };
            let (w, ess, total) = reweigh(active);
            if ess >= settings.min_ess {
                return Ok(Draw { truth, posterior: kn.summarise(&w), ess, route: Route::Reweighted, score });
            }
            if active < kn.len() {
                let (w, ess, _) = reweigh(kn.len());
                if ess >= settings.min_ess {
                    return Ok(Draw { truth, posterior: kn.summarise(&w), ess, route: Route::Fallback, score });
                }
            }
            match experiment.fallback(&data, truth) {
                Some(p) => Ok(Draw { truth, posterior: p?, ess, route: Route::Fallback, score }),
                None if total > 0.0 => Ok(Draw { truth, posterior: kn.summarise(&w), ess, route: Route::Collapsed, score }),
                None => Err(Error::numerical("preposterior analysis", format!("outer draw {j}: the simulated data have zero likelihood under every other prior sample"))),
            }
        })
        .collect::<Result<_>>()?;
    Metrics::of(kn, &settings, draws)
}

/// The truths of the outer draws: the samples a truth is drawn from and their distribution.
pub(crate) struct Truths {
    /// The first `active` samples are the prior ([`Settings::active`]).
    pub active: usize,
    /// Each sample's weight as a truth (0 outside the active samples and the conditioned label).
    pub eligible: Vec<f64>,
    /// The distribution of the truth's index.
    pub draw: Categorical,
}

impl Truths {
    pub(crate) fn new(kn: &Knowledge, settings: &Settings) -> Result<Truths> {
        let active = settings.active.unwrap_or(kn.len()).clamp(2, kn.len());
        let eligible: Vec<f64> = kn.weights.iter().enumerate().map(|(k, &w)| if k < active && settings.truth.is_none_or(|(kind, label)| kn.labels[k * kn.label_kinds + kind] == label) { w } else { 0.0 }).collect();
        let draw = Categorical::new(&eligible).ok_or_else(|| Error::numerical("preposterior analysis", format!("no prior sample has the truth's label {:?}", settings.truth)))?;
        Ok(Truths { active, eligible, draw })
    }

    /// Outer draw j's random stream (stream j + 1 of the seed) and its truth, drawn first from it.
    pub(crate) fn start(&self, settings: &Settings, j: usize) -> (ChaCha8Rng, usize) {
        let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
        rng.set_stream(j as u64 + 1);
        let truth = self.draw.draw(rng.random());
        (rng, truth)
    }
}

impl Metrics {
    /// The metrics of the outer draws `draws` of an analysis with `settings` on `kn`.
    pub(crate) fn of(kn: &Knowledge, settings: &Settings, draws: Vec<Draw>) -> Result<Metrics> {
    let Truths { active, eligible, draw: truths } = Truths::new(kn, settings)?;
    let prior_w: Vec<f64> = {
        let t: f64 = kn.weights[..active].iter().sum();
        kn.weights.iter().enumerate().map(|(k, w)| if k < active { w / t } else { 0.0 }).collect()
    };
    let prior = kn.summarise(&prior_w);
    let a0 = prior.action();
    // Over the truths' distribution: the prior, or its part with the conditioned label (the
    // prior Bayes action a₀ stays the unconditioned prior's: the decision-maker does not know
    // the truth's label).
    let truth_w: Vec<f64> = eligible.iter().map(|w| w / truths.total()).collect();
    let loss = |k: usize, a: usize| kn.loss[k * kn.actions + a];
    let prior_pcs = (0..active).filter(|&k| kn.is_best(k, a0)).map(|k| truth_w[k]).sum();
    let values = |f: &dyn Fn(&Draw) -> f64| draws.iter().map(f).collect::<Vec<_>>();
    let col = |f: &dyn Fn(&Draw) -> f64| Estimate::of(&values(f));
    let label = |kind: usize, k: usize| kn.labels[k * kn.label_kinds + kind] as usize;
    let true_weight = |kind: usize, d: &Draw| d.posterior.label_weights[kind].get(label(kind, d.truth)).copied().unwrap_or(0.0);
    let per_draw = PerDraw {
        pcs: values(&|d| if kn.is_best(d.truth, d.posterior.action()) { 1.0 } else { 0.0 }),
        evsi: match settings.truth {
            // Prior Bayes risk minus the posterior Bayes risk (module docs; ≥ 0 in expectation).
            None => {
                let prior_risk = prior.expected_loss[a0];
                values(&|d| prior_risk - d.posterior.expected_loss[d.posterior.action()])
            }
            // Under a conditioned truth the posterior risk is not an expectation over the
            // truths' distribution; the value is then the loss the data save under the truth
            // itself, L(t, a₀) − L(t, a*) (its expectation over the unconditioned prior is the
            // EVSI above), which may be negative: data can mislead under a given truth.
            Some(_) => values(&|d| loss(d.truth, a0) - loss(d.truth, d.posterior.action())),
        },
        true_label_weight: (0..kn.label_kinds).map(|kind| values(&|d| true_weight(kind, d))).collect(),
    };
    let (pcs, evsi) = (Estimate::of(&per_draw.pcs), Estimate::of(&per_draw.evsi));
    let scored: Vec<&Draw> = draws.iter().filter(|d| d.score.is_some()).collect();
    let score = (!scored.is_empty()).then(|| {
        let of = |f: &dyn Fn(&Draw) -> f64| Estimate::of(&scored.iter().map(|d| f(d)).collect::<Vec<_>>());
        Scored { draws: scored.len(), failures: scored.iter().filter(|d| d.score.is_some_and(|s| s.failed)).count(), mean: of(&|d| d.score.map_or(f64::NAN, |s| s.value)), true_label_weight: (0..kn.label_kinds).map(|kind| of(&|d| true_weight(kind, d))).collect() }
    });
    let mut ess: Vec<f64> = draws.iter().map(|d| d.ess).collect();
    ess.sort_by(f64::total_cmp);
    Ok(Metrics {
        prior_pcs,
        pcs,
        evsi,
        mean: (0..kn.quantities).map(|j| col(&|d| d.posterior.mean[j])).collect(),
        var: (0..kn.quantities).map(|j| col(&|d| d.posterior.var[j])).collect(),
        width90: (0..kn.quantities).map(|j| col(&|d| d.posterior.width90[j])).collect(),
        true_label_weight: per_draw.true_label_weight.iter().map(|v| Estimate::of(v)).collect(),
        // Over the truths' distribution (the prior, or its part with the conditioned label).
        prior_true_label_weight: (0..kn.label_kinds).map(|kind| (0..active).map(|k| eligible[k] / truths.total() * prior.label_weights[kind][label(kind, k)]).sum()).collect(),
        median_ess: crate::stats::sorted_quantile(&ess, 0.5),
        fallbacks: draws.iter().filter(|d| d.route == Route::Fallback).count(),
        moved: draws.iter().filter(|d| d.route == Route::Moved).count(),
        collapsed: draws.iter().filter(|d| d.route == Route::Collapsed).count(),
        score,
        prior,
        draws,
        per_draw,
    })
}
}

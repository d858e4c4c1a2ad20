//! The calibration loop: space-filling design → emulator → least squares → MCMC on the
//! emulator → adaptive refinement where the posterior lies → posterior-predictive check with
//! real simulator runs.
//!
//! 1. **Design**: the nominal θ and `design − 1` Sobol' points of the parameter box, run on
//!    the simulator (in parallel). Failures are recorded (θ + message) and left out.
//! 2. **Emulator** ([`Emulator`]): one GP per output, checked by leave-one-out.
//! 3. **Least squares** ([`super::lsq::fit`], multi-start Levenberg–Marquardt) on the emulator
//!    mapped to the observations; the estimate is then run on the simulator.
//! 4. **MCMC** ([`super::mcmc`], ensemble stretch move or adaptive Metropolis) on the emulator
//!    posterior `log p(θ) = log prior(θ) − ½ Σ_i [(d_i − m_i(θ))²/s_i² + ln s_i²]`,
//!    `s_i² = σ_i² + v_i(θ)` with v_i the emulator's predictive variance (latent + nugget), so
//!    where the emulator is unsure the posterior is wider, never falsely narrow. Walkers start in
//!    a small ball around the least-squares estimate.
//! 5. **Refinement**: the emulator error is measured at `probe` thinned posterior draws as
//!    `ε = max_o latent_sd_o / √(s_o² + τ_o²)`, the emulator's own sd against the likelihood's
//!    resolution for output o: s_o the sd of the combined observations d̄_o ([`Aggregated`]) and
//!    τ_o the simulator's run-to-run scatter (the GP nugget, [`Emulator::noise_sd`]). Both enter
//!    the likelihood, so no posterior resolves output o more finely than √(s_o² + τ_o²), and an
//!    emulator sd well below it changes the posterior little. While the 90th percentile of ε
//!    exceeds `tolerance`, the `points` draws with the largest ε (kept apart by a minimum distance in
//!    the unit cube) are run on the simulator, the emulator is refitted and steps 3–4 repeat.
//! 6. **Check** with real simulator runs at `check` thinned posterior draws:
//!    * *the emulator's stated uncertainty*: per output, the RMS of the standardised errors
//!      `z = (y − m(θ))/√v(θ)` (v latent + nugget: what the likelihood assumes of a new run),
//!      which is ≈ 1 when the emulator is honest; it is flagged beyond the 99 % point of its
//!      distribution under an honest emulator whose variance is estimated from its training runs
//!      ([`z_rms_limit`]), family-wise over the outputs — as a warning where the emulator's error
//!      matters to the posterior, its RMS at least [`MATERIAL_ERROR`] of the likelihood's
//!      resolution √(s_o² + τ_o²), and otherwise as a note: an error e in those units shifts
//!      the log-likelihood by about e per observation set at a typical residual and so moves no
//!      posterior mean by more than about e posterior sd, whatever the emulator claims of it
//!      (the crush FE's force at small displacements is emulated to a few % of what the data
//!      resolve while the GP states less still);
//!    * *the posterior itself*: the draws are importance-reweighted from the emulator's
//!      likelihood to the simulator's, `w ∝ N(d̄; y(θ), s² + τ²) / N(d̄; m(θ), s² + v(θ))` per
//!      output (the prior cancels; the simulator's scatter τ counts as noise in both), and each
//!      parameter's mean shift is reported in posterior sd with the effective sample size of the
//!      weights. The simulator's scatter alone spreads these weights, so they are judged against
//!      the same reweighting with each run drawn from the emulator's own predictive distribution
//!      ([`reweighting_null`]): an ESS below that null's 1 % point, or a shift beyond its 99 %
//!      point and beyond half a posterior sd, is flagged — the simulator's posterior is then not
//!      the emulator's;
//!    * the runs' coverage of the observations, and the emulator error in units of s_o (for
//!      information: where τ_o exceeds s_o, the simulator itself scatters by more than the data
//!      resolve, and so must the emulator).
//!
//! Every simulator call goes through the caller's simulator (wrap it in
//! [`super::cache::Cached`] to reuse runs across reruns); the MCMC checkpoints to
//! `checkpoint_dir` under a name that hashes the emulator's training data and the options, so a
//! rerun with the same runs resumes and a changed emulator starts afresh.

use std::path::PathBuf;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::data::Observations;
use super::emulator::{Emulator, Gathered, LooCheck};
use super::Runner;
use super::lsq::{LsqMethod, LsqOptions, LsqResult};
use super::mcmc::{self, AdaptiveOptions, Chains, Checkpoint, Diagnostics, EnsembleOptions};
use super::Noise;
use crate::model::OutputSpec;
use crate::design::Sobol;
use crate::error::{Error, Result};
use crate::model::Simulator;

/// Which sampler.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sampler {
    /// Affine-invariant ensemble (stretch move).
    #[default]
    Ensemble,
    /// Adaptive Metropolis, one chain per walker.
    AdaptiveMetropolis,
}

/// Settings of the loop.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PipelineOptions {
    /// Initial design size (nominal + Sobol' points).
    pub design: usize,
    /// Refinement rounds at most.
    pub rounds: usize,
    /// Simulator runs added per refinement round.
    pub points: usize,
    /// Posterior draws probed for the emulator error per round.
    pub probe: usize,
    /// Target of the 90th percentile of ε (emulator sd / posterior resolution).
    pub tolerance: f64,
    /// Least-squares starts.
    pub starts: usize,
    /// Least-squares optimiser: `levenberg_marquardt` (default), `nelder_mead` or `lbfgs`.
    pub least_squares: LsqMethod,
    /// Sampler.
    pub sampler: Sampler,
    /// Walkers (ensemble) or chains (adaptive Metropolis).
    pub walkers: usize,
    /// Kept steps per walker.
    pub steps: usize,
    /// Burn-in steps per walker.
    pub burn_in: usize,
    /// Posterior draws run on the simulator for the final check.
    pub check: usize,
    /// Steps between MCMC checkpoints.
    pub checkpoint_every: usize,
    /// Relative model error (default 0): an sd of `model_error·|d̄_o|` common to all
    /// observations of output o, for what the model cannot represent (the calibration mesh's
    /// discretisation error against the data's finer "truth", say); added in quadrature.
    pub model_error: f64,
}

impl Default for PipelineOptions {
    fn default() -> Self {
        PipelineOptions {
            design: 32,
            rounds: 3,
            points: 8,
            probe: 200,
            tolerance: 0.5,
            starts: 8,
            least_squares: LsqMethod::LevenbergMarquardt,
            sampler: Sampler::Ensemble,
            walkers: 32,
            steps: 2000,
            burn_in: 1000,
            check: 12,
            checkpoint_every: 5000,
            model_error: 0.0,
        }
    }
}

impl PipelineOptions {
    /// Checks the settings; `file` and `key` name them in messages.
    pub fn validate(&self, file: &str, key: &str, dim: usize) -> Result<()> {
        let bad = |k: &str, rule: String| Err(Error::config(file, format!("{key}.{k}"), rule));
        if self.design < 2 * dim + 2 {
            return bad("design", format!("{} runs cannot train an emulator in {dim} dimensions: use at least {}", self.design, 2 * dim + 2));
        }
        if self.rounds > 0 && self.points == 0 {
            return bad("points", "refinement rounds need points ≥ 1".into());
        }
        if !(self.tolerance > 0.0 && self.tolerance.is_finite()) {
            return bad("tolerance", format!("must be > 0, got {}", self.tolerance));
        }
        if self.starts == 0 {
            return bad("starts", "must be ≥ 1".into());
        }
        if self.walkers < 2 * dim || (self.sampler == Sampler::Ensemble && self.walkers % 2 == 1) {
            return bad("walkers", format!("need an even number ≥ 2 × {dim} parameters, got {}", self.walkers));
        }
        if !(self.model_error >= 0.0 && self.model_error < 1.0) {
            return bad("model_error", format!("must lie in [0, 1), got {}", self.model_error));
        }
        if self.steps < 40 || self.probe == 0 || self.checkpoint_every == 0 {
            return bad("steps", "steps ≥ 40, probe ≥ 1 and checkpoint_every ≥ 1 required".into());
        }
        Ok(())
    }
}

/// One pass of the loop.
#[derive(Debug, Clone, PartialEq)]
pub struct Round {
    /// Simulator runs in the emulator.
    pub runs: usize,
    /// 50th and 90th percentile of ε over the probed draws.
    pub epsilon: (f64, f64),
    /// Leave-one-out checks.
    pub loo: Vec<LooCheck>,
}

/// The emulator error, in units of the likelihood's resolution √(s_o² + τ_o²), below which an
/// understated emulator uncertainty cannot move a posterior mean by more than about a quarter of
/// a posterior sd and is noted, not warned about (module docs, step 6).
pub const MATERIAL_ERROR: f64 = 0.25;

/// The posterior-predictive check.
#[derive(Debug, Clone)]
pub struct Check {
    /// θ of the check runs.
    pub thetas: Vec<Vec<f64>>,
    /// Simulator outputs (None: failed).
    pub runs: Vec<Option<Vec<f64>>>,
    /// Per output: RMS of (simulator − emulator)/σ_o over the successful check runs, σ_o the
    /// sd of the combined observations (information: how far the emulator is from the runs in
    /// units of what the data resolve).
    pub emulator_error: Vec<f64>,
    /// Per output: RMS of the standardised errors (simulator − emulator)/√v (v the emulator's
    /// predictive variance of a new run, latent + nugget); ≈ 1 for an honest emulator.
    pub z_rms: Vec<f64>,
    /// Per output: the simulator's own scatter τ_o (GP nugget sd) over σ_o.
    pub scatter: Vec<f64>,
    /// Per output: RMS of (simulator − emulator)/√(σ_o² + τ_o²), the emulator's error in units
    /// of what the likelihood resolves (compared with [`MATERIAL_ERROR`]).
    pub resolved_error: Vec<f64>,
    /// The limit of [`z_rms`](Self::z_rms) ([`z_rms_limit`]).
    pub z_limit: f64,
    /// Per parameter: the shift of its posterior mean, in posterior sd, when the check draws
    /// are reweighted from the emulator's likelihood to the simulator's ([`reweighted_shift`]).
    pub shift: Vec<f64>,
    /// Effective sample size of those weights.
    pub shift_ess: f64,
    /// Under an honest emulator ([`reweighting_null`]): the 1 % quantile of that ESS and the
    /// 99 % quantile of the largest |shift|.
    pub null: (f64, f64),
    /// Fraction of the observations inside the 90 % posterior-predictive interval of the
    /// simulator runs ([`predictive_interval`] with z = [`Z90`]).
    pub coverage90: f64,
}

impl Check {
    /// The outputs whose stated uncertainty the check runs exceed ([`z_rms`](Self::z_rms) above
    /// [`z_limit`](Self::z_limit)), worst first, each with whether the emulator's error there is
    /// material to the posterior ([`resolved_error`](Self::resolved_error) ≥ [`MATERIAL_ERROR`]).
    pub fn understated(&self) -> Vec<(usize, bool)> {
        let mut o: Vec<usize> = (0..self.z_rms.len()).filter(|&o| self.resolved_error[o].is_finite() && self.z_rms[o] > self.z_limit).collect();
        o.sort_by(|a, b| self.z_rms[*b].total_cmp(&self.z_rms[*a]));
        o.into_iter().map(|o| (o, self.resolved_error[o] >= MATERIAL_ERROR)).collect()
    }

    /// The warning for the worst output whose understated uncertainty is material, if any.
    pub fn understated_warning(&self, outputs: &[OutputSpec]) -> Option<String> {
        let (o, _) = self.understated().into_iter().find(|(_, material)| *material)?;
        Some(format!(
            "check: the emulator misses the simulator at posterior draws by {:.2} of its own predictive sd (RMS) on output {}, above the {:.2} an honest emulator exceeds with probability 1 % (over all outputs), and by {:.2} of what the likelihood resolves there (material from {MATERIAL_ERROR}): its uncertainty is understated where it matters",
            self.z_rms[o], outputs[o].name, self.z_limit, self.resolved_error[o]
        ))
    }
}

/// Everything the loop found.
#[derive(Debug, Clone)]
pub struct Calibration {
    /// Least squares on the final emulator.
    pub lsq: LsqResult,
    /// Simulator outputs at the least-squares estimate.
    pub lsq_run: Option<Vec<f64>>,
    /// Final chains (θ).
    pub chains: Chains,
    /// Diagnostics per parameter.
    pub diagnostics: Vec<Diagnostics>,
    /// Warnings (diagnostics, refinement not converged, check).
    pub warnings: Vec<String>,
    /// The rounds, first (initial design) to last.
    pub rounds: Vec<Round>,
    /// The final emulator.
    pub emulator: Emulator,
    /// The observations combined per output (what the likelihood sees).
    pub aggregated: Aggregated,
    /// The check.
    pub check: Check,
    /// Simulator evaluations requested.
    pub evaluations: u64,
    /// Failed simulator evaluations: θ and error.
    pub failures: Vec<(Vec<f64>, String)>,
    /// Emulator-posterior evaluations (MCMC, all rounds).
    pub emulator_evaluations: u64,
}

/// The standard normal quantile of 0.95: the half-width of a central 90 % interval in sd.
pub const Z90: f64 = 1.6448536269514722;

/// The predictive interval of one observation from simulator runs at parameter draws (`runs`,
/// one output each): centre the runs' mean, half-width `z·√(var_runs + σ² + (model_error·mean)²)`
/// — the spread of the runs, the scatter σ of a new observation about the model and the relative
/// model error. Returns (centre, half-width).
pub fn predictive_interval(runs: &[f64], sigma: f64, model_error: f64, z: f64) -> (f64, f64) {
    let n = runs.len();
    let mean = runs.iter().sum::<f64>() / n.max(1) as f64;
    let var = if n > 1 { runs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64 } else { 0.0 };
    (mean, z * (var + sigma.powi(2) + (model_error * mean).powi(2)).sqrt())
}

/// Progress callback: a stage message.
pub type Progress<'a> = &'a (dyn Fn(&str) + Sync);

/// The observations of each output combined into their precision-weighted mean: for Gaussian
/// noise this carries the whole likelihood of θ (the scatter about the mean does not depend on
/// θ), and an error common to all replicates of an output (emulator, model error) enters once,
/// not once per replicate.
#[derive(Debug, Clone, PartialEq)]
pub struct Aggregated {
    /// Model output index.
    pub output: Vec<usize>,
    /// Weighted mean d̄_o.
    pub mean: Vec<f64>,
    /// Its sd: `√(1/Σ σ_i⁻² + (model_error·d̄_o)²)`.
    pub sd: Vec<f64>,
    /// Observations combined.
    pub count: Vec<usize>,
}

impl Aggregated {
    /// Combines `obs` per output.
    pub fn new(obs: &Observations, model_error: f64) -> Aggregated {
        let mut outs: Vec<usize> = obs.output.clone();
        outs.sort_unstable();
        outs.dedup();
        let mut a = Aggregated { output: vec![], mean: vec![], sd: vec![], count: vec![] };
        for o in outs {
            let (mut w, mut wd, mut n) = (0.0, 0.0, 0);
            for i in (0..obs.len()).filter(|&i| obs.output[i] == o) {
                let wi = 1.0 / (obs.sigma[i] * obs.sigma[i]);
                w += wi;
                wd += wi * obs.values[i];
                n += 1;
            }
            let mean = wd / w;
            a.output.push(o);
            a.mean.push(mean);
            a.sd.push((1.0 / w + (model_error * mean).powi(2)).sqrt());
            a.count.push(n);
        }
        a
    }
}

/// Log posterior on the emulator (−∞ outside the prior support):
/// `log prior − ½ Σ_o [(d̄_o − m_o)²/s_o² + ln s_o²]`, `s_o² = sd_o² + v_o(θ)`.
pub fn log_posterior(em: &Emulator, agg: &Aggregated, theta: &[f64]) -> f64 {
    let lp = em.space().log_prior(theta);
    if !lp.is_finite() {
        return f64::NEG_INFINITY;
    }
    let pred = em.predict(theta);
    let mut ll = 0.0;
    for (k, &o) in agg.output.iter().enumerate() {
        let (m, v) = pred[o];
        let s2 = agg.sd[k] * agg.sd[k] + v;
        ll -= 0.5 * ((agg.mean[k] - m).powi(2) / s2 + s2.ln());
    }
    lp + ll
}

fn hash_training(em: &Emulator, opts: &PipelineOptions, seed: u64) -> String {
    let mut bytes = Vec::new();
    for v in em.thetas.iter().chain(em.runs.iter()).flatten() {
        bytes.extend_from_slice(&v.to_bits().to_le_bytes());
    }
    bytes.extend_from_slice(format!("{opts:?}{seed}").as_bytes());
    crate::io::sha256_hex(&bytes)[..16].to_string()
}

fn sample(em: &Emulator, agg: &Aggregated, start: &[f64], opts: &PipelineOptions, steps: usize, seed: u64, checkpoint_dir: Option<&PathBuf>) -> Result<Chains> {
    let space = em.space();
    let d = space.len();
    let u0 = space.to_unit(start);
    let lp = |t: &[f64]| log_posterior(em, agg, t);
    // Initial ball: 1 % of the box around the estimate, redrawn until inside the support.
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5EED);
    let n01 = Normal::new(0.0, 1.0).map_err(|e| Error::numerical("MCMC", e.to_string()))?;
    let mut init = Vec::with_capacity(opts.walkers);
    for _ in 0..opts.walkers {
        let mut tries = 0;
        loop {
            let u: Vec<f64> = u0.iter().map(|x| (x + 0.01 * n01.sample(&mut rng)).clamp(1e-6, 1.0 - 1e-6)).collect();
            let t = space.from_unit(&u);
            if lp(&t).is_finite() {
                init.push(t);
                break;
            }
            tries += 1;
            if tries > 1000 {
                return Err(Error::numerical("MCMC", format!("no finite posterior density near the least-squares estimate {start:?}")));
            }
        }
    }
    match opts.sampler {
        Sampler::Ensemble => {
            let eo = EnsembleOptions { walkers: opts.walkers, steps, burn_in: opts.burn_in, stretch: 2.0, seed };
            match checkpoint_dir {
                Some(dir) => {
                    let path = dir.join(format!("mcmc_{}_{steps}.json", hash_training(em, opts, seed)));
                    mcmc::ensemble_with_checkpoint(lp, init, &eo, &Checkpoint { path, every: opts.checkpoint_every })
                }
                None => mcmc::ensemble(lp, init, &eo),
            }
        }
        Sampler::AdaptiveMetropolis => {
            let widths: Vec<f64> = space.params().iter().map(|p| 0.01 * (p.upper - p.lower)).collect();
            let ao = AdaptiveOptions { chains: opts.walkers, steps, burn_in: opts.burn_in, adapt_after: opts.burn_in.min(200).max(d * 10), initial_scale: widths, seed };
            mcmc::adaptive_metropolis(lp, init, &ao)
        }
    }
}

/// Thinned draws: `n` points spread evenly over the kept chain (step-major, walker-minor).
pub fn thinned(chains: &Chains, n: usize) -> Vec<Vec<f64>> {
    let all: Vec<&Vec<f64>> = chains.draws.iter().flatten().collect();
    let n = n.min(all.len()).max(1);
    (0..n).map(|k| all[(k * all.len()) / n + (all.len() / n) / 2].clone()).collect()
}

/// Emulator error ε of each probed draw: max over outputs of latent sd / √(sd of d̄_o² + τ_o²)
/// (module docs, step 5).
fn epsilons(em: &Emulator, agg: &Aggregated, draws: &[Vec<f64>]) -> Vec<f64> {
    let tau = em.noise_sd();
    draws
        .iter()
        .map(|t| {
            let sd = em.latent_sd(t);
            agg.output.iter().zip(&agg.sd).map(|(&o, s)| sd[o] / s.hypot(tau[o])).fold(0.0, f64::max)
        })
        .collect()
}

/// The simulator-against-emulator importance reweighting of posterior draws (module docs,
/// step 6): normalised weights and, per parameter, the weighted mean's shift in posterior sd
/// (the draws' own sd). `runs[i]` are the simulator's outputs at `thetas[i]`.
pub fn reweighted_shift(em: &Emulator, agg: &Aggregated, thetas: &[Vec<f64>], runs: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>) {
    let preds: Vec<Vec<(f64, f64)>> = thetas.iter().map(|t| em.predict(t)).collect();
    reweight(agg, &em.noise_sd(), &preds, thetas, runs)
}

/// [`reweighted_shift`] with the emulator's predictions `preds` at `thetas` and its scatter
/// `tau` given (computed once for many sets of runs).
fn reweight(agg: &Aggregated, tau: &[f64], preds: &[Vec<(f64, f64)>], thetas: &[Vec<f64>], runs: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>) {
    let lw: Vec<f64> = preds
        .iter()
        .zip(runs)
        .map(|(pred, y)| {
            let mut l = 0.0;
            for (k, &o) in agg.output.iter().enumerate() {
                let (s2_sim, s2_em) = (agg.sd[k].powi(2) + tau[o].powi(2), agg.sd[k].powi(2) + pred[o].1);
                l += -0.5 * ((agg.mean[k] - y[o]).powi(2) / s2_sim + s2_sim.ln()) + 0.5 * ((agg.mean[k] - pred[o].0).powi(2) / s2_em + s2_em.ln());
            }
            l
        })
        .collect();
    let top = lw.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut w: Vec<f64> = lw.iter().map(|l| (l - top).exp()).collect();
    let total: f64 = w.iter().sum();
    w.iter_mut().for_each(|x| *x /= total);
    let n = thetas.len() as f64;
    let shift = (0..thetas.first().map_or(0, |t| t.len()))
        .map(|k| {
            let mean = thetas.iter().map(|t| t[k]).sum::<f64>() / n;
            let sd = (thetas.iter().map(|t| (t[k] - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
            let wmean: f64 = thetas.iter().zip(&w).map(|(t, wi)| wi * t[k]).sum();
            if sd > 0.0 { (wmean - mean) / sd } else { 0.0 }
        })
        .collect();
    (w, shift)
}

/// Replicates of the reweighting under an honest emulator ([`reweighting_null`]).
pub const NULL_REPLICATES: usize = 400;

/// The reweighting of [`reweighted_shift`] when the emulator is honest: each run replaced by a
/// draw from the emulator's own predictive distribution, m(θ) + √v(θ)·z, [`NULL_REPLICATES`]
/// times. The simulator's scatter τ alone spreads the weights (a single run at θ is one
/// realisation of it), so a low ESS or a shift is evidence against the emulator only beyond what
/// this null gives: returns its 1 % quantile of the ESS and 99 % quantile of the largest
/// |shift| (posterior sd). Seeded; the result does not depend on the thread count.
pub fn reweighting_null(em: &Emulator, agg: &Aggregated, thetas: &[Vec<f64>], seed: u64) -> (f64, f64) {
    let preds: Vec<Vec<(f64, f64)>> = thetas.iter().map(|t| em.predict(t)).collect();
    let tau = em.noise_sd();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x4E55_4C4C);
    let n01 = Normal::new(0.0, 1.0).expect("unit normal");
    let (mut ess, mut shift) = (Vec::with_capacity(NULL_REPLICATES), Vec::with_capacity(NULL_REPLICATES));
    for _ in 0..NULL_REPLICATES {
        let runs: Vec<Vec<f64>> = preds.iter().map(|p| p.iter().map(|(m, v)| m + v.sqrt() * n01.sample(&mut rng)).collect()).collect();
        let (w, sh) = reweight(agg, &tau, &preds, thetas, &runs);
        ess.push(1.0 / w.iter().map(|x| x * x).sum::<f64>());
        shift.push(sh.iter().fold(0.0_f64, |a, b| a.max(b.abs())));
    }
    (crate::stats::interpolated_quantiles(ess, &[0.01])[0], crate::stats::interpolated_quantiles(shift, &[0.99])[0])
}

/// The RMS standardised error above which `n` check runs say the emulator's stated
/// uncertainty is too small: the 99 % point (family-wise over `outputs` outputs, Bonferroni) of
/// √F(n, ν), ν = `dof` the degrees of freedom of the emulator's variance estimate (its training
/// runs less its hyperparameters): the squared errors are a sample of n variances measured
/// against a variance estimated from ν, so their ratio is F-distributed, not χ²_n/n — with the
/// nugget estimated from 40 runs, a χ² limit would call an honest emulator dishonest.
pub fn z_rms_limit(n: usize, dof: usize, outputs: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, FisherSnedecor};
    let p = 1.0 - 0.01 / outputs.max(1) as f64;
    FisherSnedecor::new(n.max(1) as f64, dof.max(1) as f64).map(|f| f.inverse_cdf(p).sqrt()).unwrap_or(f64::INFINITY)
}

/// Runs the loop on simulator `sim` against `obs`.
pub fn calibrate<S: Simulator>(sim: &S, obs: &Observations, opts: &PipelineOptions, seed: u64, checkpoint_dir: Option<&PathBuf>, progress: Progress) -> Result<Calibration> {
    let space = sim.space().clone();
    let d = space.len();
    let mut runner = Runner::new(sim);
    let mut warnings = Vec::new();
    let agg = Aggregated::new(obs, opts.model_error);

    progress(&format!("design: {} simulator runs", opts.design));
    let mut thetas = vec![space.nominal()];
    thetas.extend(Sobol::points(d, opts.design - 1, 1)?.iter().map(|u| space.from_unit(u)));
    let mut train_t = Vec::new();
    let mut train_y = Vec::new();
    for (t, y) in thetas.iter().zip(runner.run(&thetas)?) {
        if let Some(y) = y {
            train_t.push(t.clone());
            train_y.push(y);
        }
    }
    if train_t.len() < d + 3 {
        return Err(Error::numerical("calibration", format!("only {} of {} design runs succeeded: too few to train an emulator (first failure: {})", train_t.len(), thetas.len(), runner.failures.first().map(|f| f.1.as_str()).unwrap_or("—"))));
    }
    let mut rounds = Vec::new();
    let mut emulator_evaluations = 0u64;
    let mut round = 0usize;
    loop {
        progress(&format!("round {round}: emulator of {} runs, least squares, MCMC", train_t.len()));
        let em = Emulator::fit(&space, sim.outputs(), train_t.clone(), train_y.clone())?;
        let gathered = Gathered::new(&em, agg.output.clone());
        let lsq = super::lsq::fit(&gathered, &agg.mean, &Noise::Known { sigma: agg.sd.clone() }, &LsqOptions { method: opts.least_squares, starts: opts.starts, fd_step: 1e-5, ..LsqOptions::default() })?;
        // Refinement rounds probe the posterior with a quarter-length chain; the final
        // posterior is sampled at full length on the final emulator.
        let chains = sample(&em, &agg, &lsq.theta, opts, (opts.steps / 4).max(40), seed.wrapping_add(round as u64), checkpoint_dir)?;
        emulator_evaluations += chains.evaluations;
        let probe = thinned(&chains, opts.probe);
        let eps = epsilons(&em, &agg, &probe);
        let q = crate::stats::interpolated_quantiles(eps.clone(), &[0.5, 0.9]);
        let eps_q = (q[0], q[1]);
        rounds.push(Round { runs: train_t.len(), epsilon: eps_q, loo: em.leave_one_out() });
        let done = eps_q.1 <= opts.tolerance;
        if done || round >= opts.rounds {
            if !done {
                warnings.push(format!(
                    "emulator refinement stopped after {round} rounds with ε90 = {:.2} > tolerance {:.2}: the emulator is still coarse where the posterior lies (its variance is in the likelihood, so the posterior is wider, not wrong)",
                    eps_q.1, opts.tolerance
                ));
            }
            progress("final MCMC on the emulator");
            let chains = sample(&em, &agg, &lsq.theta, opts, opts.steps, seed.wrapping_add(1000), checkpoint_dir)?;
            emulator_evaluations += chains.evaluations;
            return finish(&mut runner, em, lsq, chains, rounds, warnings, obs, &agg, opts, emulator_evaluations, seed, progress);
        }
        // New runs: the probed draws with the largest ε, at least 0.05 apart in the unit cube.
        let mut order: Vec<usize> = (0..probe.len()).collect();
        order.sort_by(|&a, &b| eps[b].total_cmp(&eps[a]));
        let mut picked: Vec<Vec<f64>> = Vec::new();
        for &i in &order {
            let u = space.to_unit(&probe[i]);
            let far = picked.iter().chain(train_t.iter()).all(|t| {
                let v = space.to_unit(t);
                u.iter().zip(&v).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt() >= 0.05
            });
            if far {
                picked.push(probe[i].clone());
            }
            if picked.len() == opts.points {
                break;
            }
        }
        if picked.is_empty() {
            // Everything probed is already next to a run: the emulator cannot gain more here.
            warnings.push(format!("emulator refinement: every probed draw lies within 0.05 of a run, stopping with ε90 = {:.2}", eps_q.1));
            let chains = sample(&em, &agg, &lsq.theta, opts, opts.steps, seed.wrapping_add(1000), checkpoint_dir)?;
            emulator_evaluations += chains.evaluations;
            return finish(&mut runner, em, lsq, chains, rounds, warnings, obs, &agg, opts, emulator_evaluations, seed, progress);
        }
        progress(&format!("round {}: {} refinement runs", round + 1, picked.len()));
        for (t, y) in picked.iter().zip(runner.run(&picked)?) {
            if let Some(y) = y {
                train_t.push(t.clone());
                train_y.push(y);
            }
        }
        round += 1;
    }
}

#[allow(clippy::too_many_arguments)]
fn finish<S: Simulator>(
    runner: &mut Runner<S>,
    em: Emulator,
    lsq: LsqResult,
    chains: Chains,
    rounds: Vec<Round>,
    mut warnings: Vec<String>,
    obs: &Observations,
    agg: &Aggregated,
    opts: &PipelineOptions,
    emulator_evaluations: u64,
    seed: u64,
    progress: Progress,
) -> Result<Calibration> {
    let space = em.space().clone();
    let diagnostics: Vec<Diagnostics> = (0..space.len()).map(|k| chains.diagnostics(k)).collect();
    for (p, dg) in space.params().iter().zip(&diagnostics) {
        if let Some(w) = dg.warning(&p.name) {
            warnings.push(w);
        }
    }
    progress(&format!("check: {} simulator runs at posterior draws and one at the estimate", opts.check));
    let mut thetas = thinned(&chains, opts.check);
    thetas.push(lsq.theta.clone());
    let mut runs = runner.run(&thetas)?;
    let lsq_run = runs.pop().flatten();
    thetas.pop();
    // Emulator error at the check runs, per output, in units of the sd of d̄_o (what the
    // posterior resolves).
    let m = em.outputs().len();
    let mut sigma_o = vec![f64::NAN; m];
    for (&o, s) in agg.output.iter().zip(&agg.sd) {
        sigma_o[o] = *s;
    }
    let mut err = vec![0.0; m];
    let ok: Vec<(&Vec<f64>, &Vec<f64>)> = thetas.iter().zip(&runs).filter_map(|(t, y)| y.as_ref().map(|y| (t, y))).collect();
    for (t, y) in &ok {
        let pred = em.predict(t);
        for o in 0..m {
            err[o] += ((y[o] - pred[o].0) / sigma_o[o]).powi(2);
        }
    }
    let emulator_error: Vec<f64> = err.iter().map(|e| (e / ok.len().max(1) as f64).sqrt()).collect();
    // The emulator's stated uncertainty against the runs, and the simulator's own scatter.
    let tau = em.noise_sd();
    let mut z2 = vec![0.0; m];
    for (t, y) in &ok {
        for (o, (mo, v)) in em.predict(t).into_iter().enumerate() {
            z2[o] += (y[o] - mo).powi(2) / v.max(f64::MIN_POSITIVE);
        }
    }
    let z_rms: Vec<f64> = z2.iter().map(|e| (e / ok.len().max(1) as f64).sqrt()).collect();
    let scatter: Vec<f64> = (0..m).map(|o| tau[o] / sigma_o[o]).collect();
    let resolved_error: Vec<f64> = (0..m).map(|o| emulator_error[o] / (1.0 + scatter[o] * scatter[o]).sqrt()).collect();
    let z_limit = z_rms_limit(ok.len(), em.len().saturating_sub(space.len() + 2), agg.output.len());
    // The posterior under the simulator's likelihood, by reweighting the check draws.
    let (ok_t, ok_y): (Vec<Vec<f64>>, Vec<Vec<f64>>) = ok.iter().map(|(t, y)| ((*t).clone(), (*y).clone())).unzip();
    let (weights, shift) = if ok_t.len() >= 2 { reweighted_shift(&em, agg, &ok_t, &ok_y) } else { (vec![], vec![0.0; space.len()]) };
    let shift_ess = if weights.is_empty() { 0.0 } else { 1.0 / weights.iter().map(|w| w * w).sum::<f64>() };
    // Coverage of the observations by the 90 % predictive interval of the simulator runs.
    let mut inside = 0usize;
    for i in 0..obs.len() {
        let o = obs.output[i];
        let v: Vec<f64> = ok.iter().map(|(_, y)| y[o]).collect();
        let (mean, half) = predictive_interval(&v, obs.sigma[i], opts.model_error, Z90);
        if (obs.values[i] - mean).abs() <= half {
            inside += 1;
        }
    }
    let coverage90 = inside as f64 / obs.len().max(1) as f64;
    if ok.len() < thetas.len() {
        warnings.push(format!("check: {} of {} simulator runs at posterior draws failed", thetas.len() - ok.len(), thetas.len()));
    }
    // Against what an honest emulator and the simulator's scatter alone would give.
    let (null_ess, null_shift) = if ok_t.len() >= 2 { reweighting_null(&em, agg, &ok_t, seed) } else { (0.0, f64::INFINITY) };
    let limit = null_shift.max(0.5);
    let moved: Vec<String> = space.params().iter().zip(&shift).filter(|(_, s)| s.abs() > limit).map(|(p, s)| format!("{} by {s:+.2} sd", p.name)).collect();
    if ok_t.len() >= 2 && (shift_ess < null_ess || !moved.is_empty()) {
        warnings.push(format!(
            "check: reweighting the {} check draws from the emulator's likelihood to the simulator's {} — beyond what an honest emulator gives with this simulator's scatter (1 % of its ESS below {null_ess:.1}, 1 % of its shifts above {null_shift:.2} sd): the posterior on the emulator is not the simulator's — refine the emulator (more rounds or points) or lower the tolerance",
            ok_t.len(),
            if moved.is_empty() { format!("leaves {shift_ess:.1} effective draws") } else { format!("moves the posterior mean of {} (ESS {shift_ess:.1})", moved.join(", ")) }
        ));
    }
    let check = Check { thetas, runs, emulator_error, z_rms, scatter, resolved_error, z_limit, shift, shift_ess, null: (null_ess, null_shift), coverage90 };
    warnings.extend(check.understated_warning(em.outputs()));
    Ok(Calibration {
        lsq,
        lsq_run,
        chains,
        diagnostics,
        warnings,
        rounds,
        emulator: em,
        aggregated: agg.clone(),
        check,
        evaluations: runner.evaluations,
        failures: std::mem::take(&mut runner.failures),
        emulator_evaluations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A check whose outputs have the given RMS standardised errors and errors in units of the
    /// likelihood's resolution, against the limit 1.52 (32 runs, as on the 800 °C calibration).
    fn check(z: &[f64], error: &[f64]) -> Check {
        let n = z.len();
        Check { thetas: vec![], runs: vec![], emulator_error: error.to_vec(), z_rms: z.to_vec(), scatter: vec![0.0; n], resolved_error: error.to_vec(), z_limit: 1.52, shift: vec![], shift_ess: 0.0, null: (0.0, 0.0), coverage90: 1.0 }
    }

    /// An understated uncertainty warns only where the emulator's error is material: the 800 °C
    /// calibration's force at 1.7 µm (z 1.64, error 0.07 of the resolution) is a note; an output
    /// with a smaller z but an error of 0.6 is the warning, named even though its z is not the
    /// largest; below the limit nothing is said however large the error.
    #[test]
    fn understated_uncertainty_warns_only_where_the_error_matters() {
        let names: Vec<OutputSpec> = ["force_at_1.7um", "peak_force", "fracture_displacement"].iter().map(|n| OutputSpec::new(*n, "N")).collect();
        let slight = check(&[1.64, 1.2, 1.0], &[0.07, 1.2, 0.9]);
        assert_eq!(slight.understated(), vec![(0, false)]);
        assert_eq!(slight.understated_warning(&names), None);
        let both = check(&[1.64, 1.2, 1.58], &[0.07, 1.2, 0.6]);
        assert_eq!(both.understated(), vec![(0, false), (2, true)]);
        let w = both.understated_warning(&names).unwrap();
        assert!(w.contains("1.58") && w.contains("fracture_displacement") && w.contains("0.60"), "{w}");
        assert_eq!(check(&[1.5, 1.0, 1.0], &[5.0, 5.0, 5.0]).understated_warning(&names), None);
        // An output without observations (NaN error) is never judged.
        assert_eq!(check(&[9.0, 1.0, 1.0], &[f64::NAN, 0.1, 0.1]).understated(), vec![]);
    }
}

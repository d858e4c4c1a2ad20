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
//! 6. **Check** with real simulator runs at `check` thinned posterior draws ([`super::check`]):
//!    the emulator's stated uncertainty against the runs, the posterior reweighted from the
//!    emulator's likelihood to the simulator's, and the runs' coverage of the observations.
//!
//! Every simulator call goes through the caller's simulator (wrap it in
//! [`super::cache::Cached`] to reuse runs across reruns); the MCMC checkpoints to
//! `checkpoint_dir` under a name that hashes the emulator's training data and the options, so a
//! rerun with the same runs resumes and a changed emulator starts afresh.

use std::path::PathBuf;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::check::Check;
use super::data::{Aggregated, Observations};
use super::emulator::{Emulator, Gathered, LooCheck};
use super::Runner;
use super::lsq::{LsqMethod, LsqOptions, LsqResult};
use super::mcmc::{self, AdaptiveOptions, Chains, Checkpoint, Diagnostics, EnsembleOptions};
use super::Noise;
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

/// Progress callback: a stage message.
pub type Progress<'a> = &'a (dyn Fn(&str) + Sync);

/// Log posterior on the emulator (−∞ outside the prior support):
/// `log prior − ½ Σ_o [(d̄_o − m_o)²/s_o² + ln s_o²]`, `s_o² = sd_o² + v_o(θ)`.
pub fn log_posterior(em: &Emulator, agg: &Aggregated, theta: &[f64]) -> f64 {
    let lp = em.space().log_prior(theta);
    if !lp.is_finite() {
        return f64::NEG_INFINITY;
    }
    // Only the observed outputs (a crush calibration on force points leaves the peak force and
    // the fracture displacement out).
    let pred = em.predict_outputs(theta, &agg.output);
    let mut ll = 0.0;
    for (k, &(m, v)) in pred.iter().enumerate() {
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
    let check = Check::new(&em, agg, obs, opts.model_error, thetas, runs, seed, &mut warnings);
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

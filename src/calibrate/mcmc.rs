//! Gradient-free MCMC: the affine-invariant ensemble sampler (Goodman & Weare 2010, the
//! "stretch move" of emcee), adaptive Metropolis (Haario et al. 2001, [`adaptive_metropolis`])
//! and convergence diagnostics (Vehtari, Gelman, Simpson, Carpenter &
//! Bürkner 2021: rank-normalised split-R̂, bulk and tail ESS).
//!
//! ## Stretch move
//! The walkers are split into two halves; each half is updated against the other: walker k
//! picks a walker j of the other half, draws z from g(z) ∝ 1/√z on [1/a, a] (a = 2), proposes
//! `y = x_j + z (x_k − x_j)` and accepts with probability `min(1, z^(d−1) p(y)/p(x_k))`.
//!
//! Determinism: every random number of a half-step is drawn serially from one seeded ChaCha8
//! stream, in walker order, before the log-densities of the half are evaluated in parallel with
//! rayon; so a seed gives the same chain whatever the thread count. `log_prob` may return −∞
//! (outside the prior, a failed simulator); NaN is an error.
//!
//! ## Diagnostics
//! Each walker's chain is split in halves (2W chains of length n). ESS uses Geyer's initial
//! monotone sequence on the multi-chain autocorrelation `ρ_t = 1 − (W − mean_m γ_m,t)/var⁺`.
//! Bulk ESS and R̂ are computed on rank-normalised draws `Φ⁻¹((r − 3/8)/(S + 1/4))`; R̂ is the
//! larger of the split-R̂ of those and of the rank-normalised folded draws |x − median|; tail ESS
//! is the smaller ESS of the indicators of the 5 % and 95 % quantiles. The integrated
//! autocorrelation time is τ = (draws per chain × chains)/bulk ESS in steps.
//!
//! Verified by `tests/verification/mcmc.rs` (conjugate normal, Rosenbrock banana, 10-D
//! correlated Gaussian, AR(1) ESS, R̂ of stuck chains).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal};

use crate::error::{Error, Result};

/// Ensemble sampler settings.
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleOptions {
    /// Walkers (even, ≥ 2 × dimension).
    pub walkers: usize,
    /// Steps after burn-in.
    pub steps: usize,
    /// Steps discarded first.
    pub burn_in: usize,
    /// Stretch scale a (> 1).
    pub stretch: f64,
    /// Seed.
    pub seed: u64,
}

/// A sampled ensemble.
#[derive(Debug, Clone)]
pub struct Chains {
    /// Draws: `draws[step][walker]` is a point of dimension `dim`.
    pub draws: Vec<Vec<Vec<f64>>>,
    /// Log-density of each draw.
    pub log_prob: Vec<Vec<f64>>,
    /// Acceptance rate per walker.
    pub acceptance: Vec<f64>,
    /// Log-density evaluations.
    pub evaluations: u64,
}

impl Chains {
    /// Parameter k of walker w as a chain over steps.
    pub fn chain(&self, w: usize, k: usize) -> Vec<f64> {
        self.draws.iter().map(|s| s[w][k]).collect()
    }

    /// All draws of parameter k.
    pub fn flat(&self, k: usize) -> Vec<f64> {
        self.draws.iter().flat_map(|s| s.iter().map(move |p| p[k])).collect()
    }

    /// Diagnostics of parameter k.
    pub fn diagnostics(&self, k: usize) -> Diagnostics {
        let chains: Vec<Vec<f64>> = (0..self.draws[0].len()).map(|w| self.chain(w, k)).collect();
        diagnostics(&chains)
    }
}

fn check_lp(v: f64, x: &[f64]) -> Result<f64> {
    if v.is_nan() {
        return Err(Error::numerical("MCMC", format!("log-density is NaN at {x:?}")));
    }
    Ok(v)
}

/// Periodic checkpoints of an ensemble run: the whole sampler state (walkers, log-densities,
/// draws so far, acceptance counts, the random stream's position) written atomically as JSON
/// every `every` steps. A rerun with the same options and file continues from the last
/// checkpoint and produces exactly the chain of an uninterrupted run; a killed run loses at most
/// `every` steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// Checkpoint file.
    pub path: std::path::PathBuf,
    /// Steps between checkpoints (≥ 1).
    pub every: usize,
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct EnsembleState {
    seed: u64,
    walkers: usize,
    steps: usize,
    burn_in: usize,
    stretch: f64,
    next_step: usize,
    word_pos: u128,
    x: Vec<Vec<f64>>,
    lp: Vec<f64>,
    accepted: Vec<u64>,
    evaluations: u64,
    draws: Vec<Vec<Vec<f64>>>,
    lps: Vec<Vec<f64>>,
}

/// Runs the ensemble sampler from the initial walker positions `init` (each with a finite
/// log-density).
pub fn ensemble<F>(log_prob: F, init: Vec<Vec<f64>>, opts: &EnsembleOptions) -> Result<Chains>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    run_ensemble(log_prob, init, opts, None)
}

/// [`ensemble`] with checkpoints: resumes from `checkpoint.path` when it holds a run of the same
/// options (a file of other options is an error, not silently overwritten).
pub fn ensemble_with_checkpoint<F>(log_prob: F, init: Vec<Vec<f64>>, opts: &EnsembleOptions, checkpoint: &Checkpoint) -> Result<Chains>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    if checkpoint.every == 0 {
        return Err(Error::config("<mcmc>", "checkpoint.every", "must be ≥ 1"));
    }
    run_ensemble(log_prob, init, opts, Some(checkpoint))
}

/// The sampler's loop runs on a worker of the pool ([`crate::model::on_pool`]): each
/// half-step's parallel evaluation of the proposals (a few hundred microseconds of work on an
/// emulator) is then split inside the pool instead of injected from outside and waited on, which
/// put the workers to sleep and woke them twice per half-step (a quarter of a calibration's final
/// MCMC went to those thread switches).
fn run_ensemble<F>(log_prob: F, init: Vec<Vec<f64>>, opts: &EnsembleOptions, checkpoint: Option<&Checkpoint>) -> Result<Chains>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    crate::model::on_pool(|| run_ensemble_here(&log_prob, init, opts, checkpoint))
}

fn run_ensemble_here<F>(log_prob: &F, init: Vec<Vec<f64>>, opts: &EnsembleOptions, checkpoint: Option<&Checkpoint>) -> Result<Chains>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    let nw = init.len();
    let dim = init.first().map(|x| x.len()).unwrap_or(0);
    if nw != opts.walkers || nw < 2 * dim.max(1) || nw % 2 == 1 || dim == 0 {
        return Err(Error::config("<mcmc>", "walkers", format!("need an even number ≥ 2 × dimension ({}) of walkers, given {nw} positions of dimension {dim} for {} walkers", 2 * dim, opts.walkers)));
    }
    let stretch_ok = opts.stretch > 1.0; // false for NaN too
    if !stretch_ok || opts.steps == 0 {
        return Err(Error::config("<mcmc>", "stretch", "stretch a > 1 and steps ≥ 1 required"));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    let resumed: Option<EnsembleState> = match checkpoint {
        Some(c) if c.path.exists() => {
            let text = std::fs::read_to_string(&c.path).map_err(|e| Error::read(&c.path, e))?;
            let st: EnsembleState = serde_json::from_str(&text).map_err(|e| Error::data_file(&c.path, "file", format!("not a checkpoint of this sampler: {e}")))?;
            let same = st.seed == opts.seed && st.walkers == nw && st.steps == opts.steps && st.burn_in == opts.burn_in && st.stretch == opts.stretch && st.x.first().map(|p| p.len()) == Some(dim);
            if !same {
                return Err(Error::data_file(&c.path, "file", "the checkpoint belongs to a run with other sampler options; remove it to start afresh"));
            }
            Some(st)
        }
        _ => None,
    };
    let (mut x, mut lp, mut accepted, mut evaluations, mut draws, mut lps, first) = match resumed {
        Some(st) => {
            rng.set_word_pos(st.word_pos);
            (st.x, st.lp, st.accepted, st.evaluations, st.draws, st.lps, st.next_step)
        }
        None => {
            let x = init;
            let lp: Vec<f64> = x.par_iter().map(|p| log_prob(p)).collect();
            for (p, v) in x.iter().zip(&lp) {
                check_lp(*v, p)?;
                if !v.is_finite() {
                    return Err(Error::config("<mcmc>", "initial positions", format!("walker at {p:?} has log-density {v}")));
                }
            }
            (x, lp, vec![0u64; nw], nw as u64, Vec::with_capacity(opts.steps), Vec::with_capacity(opts.steps), 0)
        }
    };
    let half = nw / 2;
    let a = opts.stretch;
    for step in first..opts.burn_in + opts.steps {
        for s in 0..2 {
            let (lo, other) = if s == 0 { (0, half) } else { (half, 0) };
            // Random numbers first, serially: partner, z, acceptance uniform.
            let draws_rn: Vec<(usize, f64, f64)> = (0..half)
                .map(|_| {
                    let j = other + rng.random_range(0..half);
                    let u: f64 = rng.random();
                    let z = ((a - 1.0) * u + 1.0).powi(2) / a;
                    (j, z, rng.random::<f64>())
                })
                .collect();
            let proposals: Vec<Vec<f64>> = (0..half)
                .map(|i| {
                    let (j, z, _) = draws_rn[i];
                    x[lo + i].iter().zip(&x[j]).map(|(xk, xj)| xj + z * (xk - xj)).collect()
                })
                .collect();
            let lp_new: Vec<f64> = proposals.par_iter().map(|p| log_prob(p)).collect();
            evaluations += half as u64;
            for (i, (p, l)) in proposals.into_iter().zip(lp_new).enumerate() {
                let l = check_lp(l, &p)?;
                let (_, z, u) = draws_rn[i];
                let k = lo + i;
                let log_ratio = (dim as f64 - 1.0) * z.ln() + l - lp[k];
                if l.is_finite() && u.ln() < log_ratio {
                    x[k] = p;
                    lp[k] = l;
                    if step >= opts.burn_in {
                        accepted[k] += 1;
                    }
                }
            }
        }
        if step >= opts.burn_in {
            draws.push(x.clone());
            lps.push(lp.clone());
        }
        if let Some(c) = checkpoint
            && (step + 1) % c.every == 0
        {
            let st = EnsembleState {
                seed: opts.seed,
                walkers: nw,
                steps: opts.steps,
                burn_in: opts.burn_in,
                stretch: opts.stretch,
                next_step: step + 1,
                word_pos: rng.get_word_pos(),
                x: x.clone(),
                lp: lp.clone(),
                accepted: accepted.clone(),
                evaluations,
                draws: draws.clone(),
                lps: lps.clone(),
            };
            let json = serde_json::to_vec(&st).map_err(|e| Error::numerical("checkpoint", e.to_string()))?;
            crate::io::write_atomic(&c.path, &json)?;
        }
    }
    let acceptance = accepted.iter().map(|&n| n as f64 / opts.steps as f64).collect();
    Ok(Chains { draws, log_prob: lps, acceptance, evaluations })
}

/// Adaptive Metropolis settings (Haario, Saksman & Tamminen 2001).
#[derive(Debug, Clone, PartialEq)]
pub struct AdaptiveOptions {
    /// Independent chains (run in parallel, one seeded stream each).
    pub chains: usize,
    /// Steps after burn-in, per chain.
    pub steps: usize,
    /// Steps discarded first, per chain (adaptation continues through them).
    pub burn_in: usize,
    /// Steps with the initial proposal before adapting.
    pub adapt_after: usize,
    /// Initial proposal standard deviation per parameter.
    pub initial_scale: Vec<f64>,
    /// Seed.
    pub seed: u64,
}

/// Adaptive Metropolis: Gaussian random-walk proposals with covariance `s_d (C_t + ε I)`,
/// s_d = 2.38²/d, C_t the running covariance of the chain so far (updated recursively), ε a
/// small regulariser; each chain starts at its `init` point. Returns the chains in the layout
/// of [`Chains`] (one "walker" per chain).
pub fn adaptive_metropolis<F>(log_prob: F, init: Vec<Vec<f64>>, opts: &AdaptiveOptions) -> Result<Chains>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    let d = opts.initial_scale.len();
    if init.len() != opts.chains || opts.chains == 0 || init.iter().any(|x| x.len() != d) || d == 0 || opts.steps == 0 {
        return Err(Error::config("<mcmc>", "chains", format!("need {} initial points of dimension {d} (= initial_scale length) and steps ≥ 1", opts.chains)));
    }
    if opts.initial_scale.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(Error::config("<mcmc>", "initial_scale", "every initial proposal scale must be positive"));
    }
    type ChainOut = (Vec<Vec<f64>>, Vec<f64>, u64, u64);
    let run = |c: usize, x0: &Vec<f64>| -> Result<ChainOut> {
        let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
        rng.set_stream(c as u64 + 1);
        let sd = 2.38 * 2.38 / d as f64;
        let mut x = x0.clone();
        let mut lp = check_lp(log_prob(&x), &x)?;
        if !lp.is_finite() {
            return Err(Error::config("<mcmc>", "initial positions", format!("chain {c} starts at {x:?} with log-density {lp}")));
        }
        let mut mean = x.clone();
        let mut cov = nalgebra::DMatrix::<f64>::zeros(d, d);
        let eps = opts.initial_scale.iter().map(|s| s * s).fold(f64::MAX, f64::min) * 1e-6;
        let mut chol = nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_vec(opts.initial_scale.clone()));
        let (mut out, mut lps, mut acc) = (Vec::with_capacity(opts.steps), Vec::with_capacity(opts.steps), 0u64);
        let total = opts.burn_in + opts.steps;
        for t in 1..=total {
            let z = nalgebra::DVector::<f64>::from_fn(d, |_, _| rng.sample::<f64, _>(rand_distr::StandardNormal));
            let step = &chol * z;
            let y: Vec<f64> = x.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            let ly = check_lp(log_prob(&y), &y)?;
            let u: f64 = rng.random();
            if ly.is_finite() && u.ln() < ly - lp {
                x = y;
                lp = ly;
                if t > opts.burn_in {
                    acc += 1;
                }
            }
            // Recursive mean and covariance of the chain so far (t + 1 points).
            let tf = t as f64;
            let old_mean = mean.clone();
            for k in 0..d {
                mean[k] += (x[k] - mean[k]) / (tf + 1.0);
            }
            for a in 0..d {
                for b in 0..d {
                    cov[(a, b)] = (tf - 1.0) / tf * cov[(a, b)] + (x[a] - old_mean[a]) * (x[b] - old_mean[b]) / (tf + 1.0);
                }
            }
            if t >= opts.adapt_after && t % 10 == 0 {
                let mut m = &cov * sd;
                for k in 0..d {
                    m[(k, k)] += sd * eps;
                }
                if let Some(ch) = m.cholesky() {
                    chol = ch.l();
                }
            }
            if t > opts.burn_in {
                out.push(x.clone());
                lps.push(lp);
            }
        }
        Ok((out, lps, acc, total as u64 + 1))
    };
    let results: Vec<Result<ChainOut>> = init.par_iter().enumerate().map(|(c, x0)| run(c, x0)).collect();
    let mut per_chain = Vec::new();
    for r in results {
        per_chain.push(r?);
    }
    let draws = (0..opts.steps).map(|s| per_chain.iter().map(|c| c.0[s].clone()).collect()).collect();
    let log_prob = (0..opts.steps).map(|s| per_chain.iter().map(|c| c.1[s]).collect()).collect();
    let acceptance = per_chain.iter().map(|c| c.2 as f64 / opts.steps as f64).collect();
    let evaluations = per_chain.iter().map(|c| c.3).sum();
    Ok(Chains { draws, log_prob, acceptance, evaluations })
}

/// Convergence diagnostics of one parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diagnostics {
    /// Rank-normalised split-R̂ (max of bulk and folded).
    pub r_hat: f64,
    /// Bulk effective sample size.
    pub ess_bulk: f64,
    /// Tail effective sample size (5 % and 95 % quantiles).
    pub ess_tail: f64,
    /// Integrated autocorrelation time (steps): draws per chain × chains / bulk ESS.
    pub tau: f64,
}

impl Diagnostics {
    /// A warning when R̂ > 1.01 or an ESS < 400 (Vehtari et al. 2021).
    pub fn warning(&self, name: &str) -> Option<String> {
        let mut w = Vec::new();
        // NaN counts as a failure: the comparisons are written so that it does.
        if self.r_hat.is_nan() || self.r_hat > 1.01 {
            w.push(format!("R̂ = {:.3} > 1.01", self.r_hat));
        }
        if self.ess_bulk.is_nan() || self.ess_bulk < 400.0 {
            w.push(format!("bulk ESS = {:.0} < 400", self.ess_bulk));
        }
        if self.ess_tail.is_nan() || self.ess_tail < 400.0 {
            w.push(format!("tail ESS = {:.0} < 400", self.ess_tail));
        }
        (!w.is_empty()).then(|| format!("{name}: {}", w.join(", ")))
    }
}

/// Splits each chain in halves (dropping a middle draw of odd lengths).
fn split(chains: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let n = chains.iter().map(|c| c.len()).min().unwrap_or(0) / 2;
    chains.iter().flat_map(|c| [c[..n].to_vec(), c[c.len() - n..].to_vec()]).collect()
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

/// Rank-normalises the pooled draws (average ranks for ties, [`crate::stats::ranks`]):
/// z = Φ⁻¹((r − 3/8)/(S + 1/4)) over all S draws.
fn rank_normalise(chains: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let pooled: Vec<f64> = chains.iter().flatten().copied().collect();
    let s = pooled.len() as f64;
    let normal = Normal::new(0.0, 1.0).expect("standard normal");
    let mut z = crate::stats::ranks(&pooled).into_iter().map(|r| normal.inverse_cdf((r - 0.375) / (s + 0.25)));
    chains.iter().map(|c| c.iter().map(|_| z.next().expect("one rank per draw")).collect()).collect()
}

/// Split-R̂ of (already split) chains.
fn r_hat_of(chains: &[Vec<f64>]) -> f64 {
    let m = chains.len() as f64;
    let n = chains[0].len() as f64;
    let means: Vec<f64> = chains.iter().map(|c| mean(c)).collect();
    let grand = mean(&means);
    let b = n / (m - 1.0) * means.iter().map(|x| (x - grand).powi(2)).sum::<f64>();
    let w = chains.iter().zip(&means).map(|(c, mu)| c.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (n - 1.0)).sum::<f64>() / m;
    let var_plus = (n - 1.0) / n * w + b / n;
    if w <= 0.0 {
        return if b <= 0.0 { 1.0 } else { f64::INFINITY };
    }
    (var_plus / w).sqrt()
}

/// Multi-chain ESS of (already split) chains, Geyer's initial monotone sequence.
fn ess_of(chains: &[Vec<f64>]) -> f64 {
    let m = chains.len();
    let n = chains[0].len();
    let means: Vec<f64> = chains.iter().map(|c| mean(c)).collect();
    let vars: Vec<f64> = chains.iter().zip(&means).map(|(c, mu)| c.iter().map(|x| (x - mu).powi(2)).sum::<f64>() / (n as f64 - 1.0)).collect();
    let w = mean(&vars);
    let grand = mean(&means);
    let b_over_n = means.iter().map(|x| (x - grand).powi(2)).sum::<f64>() / (m as f64 - 1.0);
    let var_plus = (n as f64 - 1.0) / n as f64 * w + b_over_n;
    if var_plus.is_nan() || var_plus <= 0.0 {
        return (m * n) as f64;
    }
    // Autocovariance at every lag, averaged over chains (biased estimator, as Stan), by FFT.
    let mut acov = vec![0.0; n];
    for (c, mu) in chains.iter().zip(&means) {
        for (t, v) in autocovariance(c, *mu).into_iter().enumerate() {
            acov[t] += v / m as f64;
        }
    }
    let rho = |t: usize| 1.0 - (w - acov[t]) / var_plus;
    // Geyer: sum pairs P_k = ρ_{2k} + ρ_{2k+1} while positive, made monotone.
    let mut sum = 0.0;
    let mut prev = f64::INFINITY;
    let mut k = 0;
    while 2 * k + 1 < n {
        let p = if k == 0 { 1.0 + rho(1) } else { rho(2 * k) + rho(2 * k + 1) };
        if p <= 0.0 {
            break;
        }
        let p = p.min(prev);
        sum += p;
        prev = p;
        k += 1;
    }
    let tau = (-1.0 + 2.0 * sum).max(1.0 / ((m * n) as f64).log10().max(1.0));
    (m * n) as f64 / tau
}

/// In-place radix-2 complex FFT (`inverse` conjugates the twiddles; no 1/n scaling).
fn fft(re: &mut [f64], im: &mut [f64], inverse: bool) {
    let n = re.len();
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let ang = 2.0 * std::f64::consts::PI / len as f64 * if inverse { 1.0 } else { -1.0 };
        let (wr, wi) = (ang.cos(), ang.sin());
        for start in (0..n).step_by(len) {
            let (mut cr, mut ci) = (1.0, 0.0);
            for k in 0..len / 2 {
                let (a, b) = (start + k, start + k + len / 2);
                let (tr, ti) = (re[b] * cr - im[b] * ci, re[b] * ci + im[b] * cr);
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
                let nr = cr * wr - ci * wi;
                ci = cr * wi + ci * wr;
                cr = nr;
            }
        }
        len <<= 1;
    }
}

/// Biased autocovariance `γ_t = Σ_{i<n−t} (x_i − μ)(x_{i+t} − μ)/n` for every lag, by FFT with
/// zero padding to a power of two ≥ 2n.
fn autocovariance(x: &[f64], mu: f64) -> Vec<f64> {
    let n = x.len();
    let size = (2 * n).next_power_of_two();
    let mut re: Vec<f64> = x.iter().map(|v| v - mu).chain(std::iter::repeat_n(0.0, size - n)).collect();
    let mut im = vec![0.0; size];
    fft(&mut re, &mut im, false);
    for (r, i) in re.iter_mut().zip(im.iter_mut()) {
        *r = *r * *r + *i * *i;
        *i = 0.0;
    }
    fft(&mut re, &mut im, true);
    re.truncate(n);
    re.iter().map(|v| v / (size as f64 * n as f64)).collect()
}

/// Diagnostics of one parameter from chains (one per walker or independent chain).
pub fn diagnostics(chains: &[Vec<f64>]) -> Diagnostics {
    let sp = split(chains);
    let z = rank_normalise(&sp);
    let all: Vec<f64> = sp.iter().flatten().cloned().collect();
    let mut sorted = all.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let folded: Vec<Vec<f64>> = sp.iter().map(|c| c.iter().map(|x| (x - median).abs()).collect()).collect();
    let r_hat = r_hat_of(&z).max(r_hat_of(&rank_normalise(&folded)));
    let ess_bulk = ess_of(&z);
    let q = |p: f64| sorted[((p * sorted.len() as f64) as usize).min(sorted.len() - 1)];
    let (q05, q95) = (q(0.05), q(0.95));
    let ind = |lim: f64| -> Vec<Vec<f64>> { sp.iter().map(|c| c.iter().map(|&x| if x <= lim { 1.0 } else { 0.0 }).collect()).collect() };
    let ess_tail = ess_of(&ind(q05)).min(ess_of(&ind(q95)));
    let draws = (sp.len() * sp[0].len()) as f64;
    Diagnostics { r_hat, ess_bulk, ess_tail, tau: draws / ess_bulk }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fft_autocovariance_equals_the_direct_sum() {
        let x: Vec<f64> = (0..37).map(|i| ((i * 7919) % 101) as f64 / 10.0).collect();
        let mu = mean(&x);
        let fast = autocovariance(&x, mu);
        for t in [0, 1, 5, 36] {
            let direct = (0..x.len() - t).map(|i| (x[i] - mu) * (x[i + t] - mu)).sum::<f64>() / x.len() as f64;
            assert!((fast[t] - direct).abs() < 1e-10 * direct.abs().max(1.0), "lag {t}: {} vs {direct}", fast[t]);
        }
    }
}

//! Step 6 of the calibration loop ([`super::pipeline`]): the check of the emulator's posterior
//! with real simulator runs at `check` thinned posterior draws.
//!
//! * *The emulator's stated uncertainty*: per output, the RMS of the standardised errors
//!   `z = (y − m(θ))/√v(θ)` (v latent + nugget: what the likelihood assumes of a new run), which
//!   is ≈ 1 when the emulator is honest; it is flagged beyond the 99 % point of its distribution
//!   under an honest emulator whose variance is estimated from its training runs
//!   ([`z_rms_limit`]), family-wise over the outputs — as a warning where the emulator's error
//!   matters to the posterior, its RMS at least [`MATERIAL_ERROR`] of the likelihood's resolution
//!   √(s_o² + τ_o²), and otherwise as a note: an error e in those units shifts the log-likelihood
//!   by about e per observation set at a typical residual and so moves no posterior mean by more
//!   than about e posterior sd, whatever the emulator claims of it (the crush FE's force at small
//!   displacements is emulated to a few % of what the data resolve while the GP states less
//!   still).
//! * *The posterior itself*: the draws are importance-reweighted from the emulator's likelihood
//!   to the simulator's, `w ∝ N(d̄; y(θ), s² + τ²) / N(d̄; m(θ), s² + v(θ))` per output (the prior
//!   cancels; the simulator's scatter τ counts as noise in both), and each parameter's mean shift
//!   is reported in posterior sd with the effective sample size of the weights. The simulator's
//!   scatter alone spreads these weights, so they are judged against the same reweighting with
//!   each run drawn from the emulator's own predictive distribution ([`reweighting_null`]): an ESS
//!   below that null's 1 % point, or a shift beyond its 99 % point and beyond half a posterior
//!   sd, is flagged — the simulator's posterior is then not the emulator's.
//! * The runs' coverage of the observations ([`predictive_interval`]), and the emulator error in
//!   units of s_o (for information: where τ_o exceeds s_o, the simulator itself scatters by more
//!   than the data resolve, and so must the emulator).
//!
//! Here s_o is the sd of the combined observations d̄_o ([`Aggregated`]) and τ_o the simulator's
//! run-to-run scatter (the GP nugget, [`Emulator::noise_sd`]).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::data::{Aggregated, Observations};
use super::emulator::Emulator;
use crate::model::{OutputSpec, Simulator};

/// The emulator error, in units of the likelihood's resolution √(s_o² + τ_o²), below which an
/// understated emulator uncertainty cannot move a posterior mean by more than about a quarter of
/// a posterior sd and is noted, not warned about (module docs).
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

impl Check {
    /// The check of the emulator `em` (fitted to `agg`, the combined `obs`) against simulator
    /// `runs` at posterior draws `thetas` (None: the run failed), with the studies' relative
    /// `model_error` for the coverage; the null replicates are seeded by `seed`. Its warnings are
    /// appended to `warnings`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(em: &Emulator, agg: &Aggregated, obs: &Observations, model_error: f64, thetas: Vec<Vec<f64>>, runs: Vec<Option<Vec<f64>>>, seed: u64, warnings: &mut Vec<String>) -> Check {
        let space = em.space();
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
        let (weights, shift) = if ok_t.len() >= 2 { reweighted_shift(em, agg, &ok_t, &ok_y) } else { (vec![], vec![0.0; space.len()]) };
        let shift_ess = if weights.is_empty() { 0.0 } else { 1.0 / weights.iter().map(|w| w * w).sum::<f64>() };
        // Coverage of the observations by the 90 % predictive interval of the simulator runs.
        let mut inside = 0usize;
        for i in 0..obs.len() {
            let o = obs.output[i];
            let v: Vec<f64> = ok.iter().map(|(_, y)| y[o]).collect();
            let (mean, half) = predictive_interval(&v, obs.sigma[i], model_error, Z90);
            if (obs.values[i] - mean).abs() <= half {
                inside += 1;
            }
        }
        let coverage90 = inside as f64 / obs.len().max(1) as f64;
        if ok.len() < thetas.len() {
            warnings.push(format!("check: {} of {} simulator runs at posterior draws failed", thetas.len() - ok.len(), thetas.len()));
        }
        // Against what an honest emulator and the simulator's scatter alone would give.
        let (null_ess, null_shift) = if ok_t.len() >= 2 { reweighting_null(em, agg, &ok_t, seed) } else { (0.0, f64::INFINITY) };
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
        check
    }
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

/// The simulator-against-emulator importance reweighting of posterior draws (module docs):
/// normalised weights and, per parameter, the weighted mean's shift in posterior sd
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

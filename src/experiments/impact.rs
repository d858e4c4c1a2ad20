//! Impact breakage tests as candidate experiments: n particles of one material, each shot
//! repeatedly at velocity V, the broken ones counted after each of N₁ < N₂ < … < N_m impacts
//! (a single-impact test counts after N = 1 only).
//!
//! Under sample k the probability that a particle drawn from the material's population is broken
//! by N impacts is the population's P_N at V with the sample's strength parameters, η, γ and
//! damage model ([`crate::strength::LifetimeModel::breakage_into`], the chain every study uses).
//! A particle therefore breaks in interval i — after N_{i−1} and by N_i impacts (N₀ = 0) — with
//! probability π_i = P_{N_i} − P_{N_{i−1}}, and survives all N_m with π_{m+1} = 1 − P_{N_m}.
//! The counts c of n independent particles are multinomial:
//! ln p(c | k) = Σ_i c_i ln π_i(k) + const. Single-impact tests measure the joint effect of η
//! and the strength law; repeated impacts separate the damage models (independent trials,
//! Vogel–Peukert and Tavares–King differ in how P_N grows with N).

use rand_chacha::ChaCha8Rng;
use rand_distr::{Binomial, Distribution};
use rayon::prelude::*;

use super::preposterior::Experiment;
use super::smc::Movable;
use super::state::{State, StateSample};
use crate::error::{Error, Result};
use crate::lifetime::damage::{CriticalRatioTable, DamageModel};
use crate::strength::model::Horizon;
use crate::uq::setup::Mode;

/// Smallest interval probability in the likelihood (keeps ln finite for impossible counts).
const PI_FLOOR: f64 = 1e-300;

/// A P_N that falls with N, or exceeds 1, by more than this is counted as clamped; less is
/// round-off and clamped silently.
pub const CLAMP_TOLERANCE: f64 = 1e-12;

/// An impact test with its interval probabilities under every sample.
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactTest {
    /// Material (0 candidate, 1 reference).
    pub material: usize,
    /// Particles tested.
    pub particles: u64,
    /// Impact velocity (m/s).
    pub velocity: f64,
    /// Impact counts at which broken particles are counted, increasing.
    pub counts: Vec<u64>,
    /// π per sample, K × (m + 1).
    probs: Vec<f64>,
    /// Samples whose P_N fell with N or exceeded 1 by more than [`CLAMP_TOLERANCE`] (clamped
    /// to be non-decreasing and ≤ 1, as probabilities of being broken by N impacts must be),
    /// and the largest such violation.
    pub clamped: (usize, f64),
    /// Tavares–King's critical ratios at the counted impacts (when a damage model is TK).
    tk: Option<Vec<CriticalRatioTable>>,
}

/// The interval probabilities π of P_N at the counted impacts (P clamped to be non-decreasing
/// and ≤ 1), and the largest violation it mended (0 when none).
fn intervals(pn: &[f64]) -> (Vec<f64>, f64) {
    let mut pi = Vec::with_capacity(pn.len() + 1);
    let (mut prev, mut worst) = (0.0, 0.0f64);
    for &x in pn {
        worst = worst.max(prev - x).max(x - 1.0);
        let x = x.clamp(prev, 1.0);
        pi.push(x - prev);
        prev = x;
    }
    pi.push(1.0 - prev);
    (pi, worst)
}

impl ImpactTest {
    /// The test on `state`'s samples.
    pub fn new(state: &State, material: usize, particles: u64, velocity: f64, counts: Vec<u64>) -> Result<ImpactTest> {
        let bad = |rule: String| Err(Error::numerical("impact test", rule));
        if material > 1 || particles == 0 || !(velocity.is_finite() && velocity > 0.0) || counts.is_empty() || counts[0] == 0 || counts.windows(2).any(|w| w[1] <= w[0]) {
            return bad(format!("material {material}, {particles} particles, V = {velocity} m/s, counts {counts:?}: needs particles ≥ 1, V > 0 and increasing counts ≥ 1"));
        }
        let (glo, ghi) = state.gamma_range;
        let tk: Option<Vec<CriticalRatioTable>> = state.damage.contains(&DamageModel::TavaresKing).then(|| CriticalRatioTable::for_impacts(&counts, glo, ghi.max(glo + 1e-9), 41));
        let mut test = ImpactTest { material, particles, velocity, counts, probs: Vec::new(), clamped: (0, 0.0), tk };
        let per: Vec<(Vec<f64>, f64)> = state.samples.par_iter().map(|s| test.intervals_at(state, s)).collect::<Result<_>>()?;
        let violations: Vec<f64> = per.iter().map(|(_, w)| *w).filter(|&w| w > CLAMP_TOLERANCE).collect();
        test.clamped = (violations.len(), violations.iter().copied().fold(0.0, f64::max));
        test.probs = per.into_iter().flat_map(|(p, _)| p).collect();
        Ok(test)
    }

    /// π at sample `s` of `state` and the violation of monotonicity it mended ([`intervals`]).
    fn intervals_at(&self, state: &State, s: &StateSample) -> Result<(Vec<f64>, f64)> {
        let st = &state.forms[s.form].setup;
        let (p, w) = st.params(self.material, &s.x, Mode::Joint);
        let (eta, gamma) = (s.x[st.shared(0)], s.x[st.shared(3)]);
        let model = state.damage[s.damage];
        let laws: Vec<Horizon> = self.counts.iter().enumerate().map(|(i, &n)| Horizon { model, impacts: n as f64, ln_x_star: self.tk.as_ref().map_or(0.0, |t| t[i].ln_ratio(gamma)) }).collect();
        let mut pn = vec![0.0; self.counts.len()];
        let lm = &st.materials[self.material].model;
        lm.breakage_into(&p, w, lm.ln_impact_stress(eta, self.velocity)?, &laws, &mut pn);
        Ok(intervals(&pn))
    }

    /// π of sample k.
    pub fn probabilities(&self, k: usize) -> &[f64] {
        let w = self.counts.len() + 1;
        &self.probs[k * w..(k + 1) * w]
    }
}

impl Experiment for ImpactTest {
    /// Particles broken in each interval, then the survivors.
    type Data = Vec<u64>;

    fn simulate(&self, truth: usize, rng: &mut ChaCha8Rng) -> Vec<u64> {
        let pi = self.probabilities(truth);
        let mut left = self.particles;
        let mut rest = 1.0;
        let mut out = Vec::with_capacity(pi.len());
        for &p in &pi[..pi.len() - 1] {
            let q = if rest > 0.0 { (p / rest).clamp(0.0, 1.0) } else { 0.0 };
            let c = if left == 0 || q == 0.0 { 0 } else { Binomial::new(left, q).expect("0 ≤ q ≤ 1").sample(rng) };
            out.push(c);
            left -= c;
            rest -= p;
        }
        out.push(left);
        out
    }

    fn loglik(&self, c: &Vec<u64>, k: usize) -> f64 {
        multinomial(self.probabilities(k), c)
    }
}

/// ln p(c | π) up to the multinomial coefficient.
fn multinomial(pi: &[f64], c: &[u64]) -> f64 {
    pi.iter().zip(c).filter(|(_, n)| **n > 0).map(|(p, &n)| n as f64 * p.max(PI_FLOOR).ln()).sum()
}

impl Movable<State> for ImpactTest {
    fn loglik_at(&self, state: &State, c: &Vec<u64>, s: &StateSample) -> f64 {
        // A sample whose stress cannot be computed has no likelihood (the prior samples all
        // could; a moved one that cannot is rejected).
        self.intervals_at(state, s).map_or(f64::NEG_INFINITY, |(pi, _)| multinomial(&pi, c))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_monotone_breakage_is_clamped_and_measured() {
        let (pi, worst) = intervals(&[0.3, 0.2, 0.5]);
        assert_eq!(pi, [0.3, 0.0, 0.2, 0.5]);
        assert!((worst - 0.1).abs() < 1e-15, "{worst}");
        let (pi, worst) = intervals(&[0.3, 1.25]);
        assert_eq!((pi, worst), (vec![0.3, 0.7, 0.0], 0.25));
        assert_eq!(intervals(&[0.1, 0.4]).1, 0.0);
    }
}

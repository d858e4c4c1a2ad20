//! A plan: several candidate experiments run together. Their data are simulated under the same
//! truth (one after the other from the outer draw's stream) and their log-likelihoods add (the
//! tests are independent given the sample).

use rand_chacha::ChaCha8Rng;

use super::crush::CrushTest;
use super::impact::ImpactTest;
use super::measure::Measurement;
use super::preposterior::{Experiment, Metrics};

/// One candidate experiment of any kind.
#[derive(Debug, Clone, PartialEq)]
pub enum Candidate {
    /// Crush tests.
    Crush(CrushTest),
    /// Impact breakage tests.
    Impact(ImpactTest),
    /// η or velocity measurements.
    Measure(Measurement),
}

/// Data of one candidate.
#[derive(Debug, Clone, PartialEq)]
pub enum Data {
    /// Crush strengths.
    Crush(Vec<(usize, f64)>),
    /// Impact counts.
    Impact(Vec<u64>),
    /// Mean log-measurement.
    Measure(f64),
}

impl Candidate {
    /// The same test with `n` particles or measurements (the likelihood tables are shared
    /// knowledge of the samples, not of the size).
    pub fn sized(&self, n: u64) -> Candidate {
        let mut c = self.clone();
        match &mut c {
            Candidate::Crush(t) => t.particles = n as usize,
            Candidate::Impact(t) => t.particles = n,
            Candidate::Measure(t) => t.n = n,
        }
        c
    }
}

impl Experiment for Candidate {
    type Data = Data;

    fn simulate(&self, truth: usize, rng: &mut ChaCha8Rng) -> Data {
        match self {
            Candidate::Crush(c) => Data::Crush(c.simulate(truth, rng)),
            Candidate::Impact(c) => Data::Impact(c.simulate(truth, rng)),
            Candidate::Measure(c) => Data::Measure(c.simulate(truth, rng)),
        }
    }

    fn loglik(&self, data: &Data, k: usize) -> f64 {
        match (self, data) {
            (Candidate::Crush(c), Data::Crush(d)) => c.loglik(d, k),
            (Candidate::Impact(c), Data::Impact(d)) => c.loglik(d, k),
            (Candidate::Measure(c), Data::Measure(d)) => c.loglik(d, k),
            _ => unreachable!("data of another candidate"),
        }
    }
}

/// Candidates run together.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan<'a>(pub Vec<&'a Candidate>);

impl Experiment for Plan<'_> {
    type Data = Vec<Data>;

    fn simulate(&self, truth: usize, rng: &mut ChaCha8Rng) -> Vec<Data> {
        self.0.iter().map(|c| c.simulate(truth, rng)).collect()
    }

    fn loglik(&self, data: &Vec<Data>, k: usize) -> f64 {
        self.0.iter().zip(data).map(|(c, d)| c.loglik(d, k)).sum()
    }
}

/// One evaluated (candidate, size) or plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluated {
    /// Candidate names (one for a single candidate).
    pub names: Vec<String>,
    /// Sizes, in the order of `names`.
    pub sizes: Vec<u64>,
    /// Total cost.
    pub cost: f64,
    /// The metrics.
    pub metrics: Metrics,
    /// The objective and its Monte Carlo standard error.
    pub objective: (f64, f64),
}

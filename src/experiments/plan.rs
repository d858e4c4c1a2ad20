//! A plan: several candidate experiments run together. Their data are simulated under the same
//! truth (one after the other from the outer draw's stream) and their log-likelihoods add (the
//! tests are independent given the sample). The evaluated plans and the allocation of a budget
//! over them (the rules are stated in [`crate::experiments::run`]).

use rand_chacha::ChaCha8Rng;

use super::crush::CrushTest;
use super::impact::ImpactTest;
use super::measure::Measurement;
use super::preposterior::{Experiment, Metrics, Score};
use super::smc::Movable;
use super::state::{State, StateSample};
use super::study::ExperimentsStudy;

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
    /// Crushed particles.
    Crush(Vec<super::crush::Crushed>),
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

    fn score(&self, data: &Data, truth: usize, draw: usize) -> Option<Score> {
        match (self, data) {
            (Candidate::Crush(c), Data::Crush(d)) => c.score(d, truth, draw),
            _ => None,
        }
    }
}

impl Movable<State> for Candidate {
    fn loglik_at(&self, state: &State, data: &Data, s: &StateSample) -> f64 {
        match (self, data) {
            (Candidate::Crush(c), Data::Crush(d)) => c.loglik_at(state, d, s),
            (Candidate::Impact(c), Data::Impact(d)) => c.loglik_at(state, d, s),
            (Candidate::Measure(c), Data::Measure(d)) => c.loglik_at(state, d, s),
            _ => unreachable!("data of another candidate"),
        }
    }
}

impl Movable<State> for Plan<'_> {
    fn loglik_at(&self, state: &State, data: &Vec<Data>, s: &StateSample) -> f64 {
        self.0.iter().zip(data).map(|(c, d)| c.loglik_at(state, d, s)).sum()
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

    /// A single candidate's score (a plan of several has none: the naming loop's verdict is
    /// of one crush test).
    fn score(&self, data: &Vec<Data>, truth: usize, draw: usize) -> Option<Score> {
        match (self.0.as_slice(), data.as_slice()) {
            ([c], [d]) => c.score(d, truth, draw),
            _ => None,
        }
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
    /// The objective per outer draw (mean: `objective.0`), for paired comparisons.
    pub objective_draws: Vec<f64>,
    /// A greedy step: its gain over the plan before it (over the prior at the first step);
    /// an exhaustive plan: its shortfall below the largest objective. Each with its paired
    /// Monte Carlo error (`experiments::run::objective_difference`). None for a single.
    pub compared: Option<(f64, f64)>,
}

/// The allocation of the budget.
#[derive(Debug, Clone)]
pub enum Allocated {
    /// The greedy steps, each the plan so far.
    Greedy(Vec<Evaluated>),
    /// Every affordable plan by decreasing objective, and the recommended one's index.
    Exhaustive {
        /// The plans.
        plans: Vec<Evaluated>,
        /// Index of the recommended plan (None: no affordable plan).
        chosen: Option<usize>,
    },
}

impl Allocated {
    /// The evaluated plans (steps or every affordable plan).
    pub fn plans(&self) -> &[Evaluated] {
        match self {
            Allocated::Greedy(p) | Allocated::Exhaustive { plans: p, .. } => p,
        }
    }
}

/// The most informative next step: the greedy rule's first step (the affordable single
/// (candidate, size) with the largest objective per cost among those gaining more than two
/// standard errors).
pub fn first_step<'a>(s: &ExperimentsStudy, singles: &'a [((usize, usize), Evaluated)]) -> Option<&'a Evaluated> {
    singles.iter().map(|(_, e)| e).filter(|e| e.cost <= s.budget.total && e.objective.0 > 2.0 * e.objective.1).max_by(|x, y| (x.objective.0 / x.cost).total_cmp(&(y.objective.0 / y.cost)))
}

/// For each single candidate (in `singles` order), the band narrowing of log10 P_break at each
/// floor of [`super::state::LOG_FLOORS`] (decades) and the candidates' ranks by it per cost
/// (1 = best; ties share their average rank).
pub fn floor_rankings(state: &State, singles: &[((usize, usize), Evaluated)]) -> Vec<(f64, Vec<(f64, f64)>, Vec<f64>)> {
    super::state::LOG_FLOORS
        .iter()
        .map(|&floor| {
            let narrowing: Vec<(f64, f64)> = singles.iter().map(|(_, e)| state.band_narrowing(&e.metrics, &|b| super::state::log_width(b, floor))).collect();
            let rank = crate::stats::ranks(&narrowing.iter().zip(singles).map(|(n, (_, e))| -n.0 / e.cost).collect::<Vec<_>>());
            (floor, narrowing, rank)
        })
        .collect()
}

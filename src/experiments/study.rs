//! The `kind = "experiments"` study file.
//!
//! ```toml
//! kind = "experiments"
//! seed = 20261124
//! study = "gen4_vs_bl.toml"          # the main study (kind = "uq"): its state of knowledge is the prior
//!
//! [decision]
//! horizon_years = 1                  # one of the main study's horizons
//! loss = 1.0e6                       # cost of choosing the particle that breaks more
//! currency = "EUR"
//! objective = "band_width"           # evsi | pcs | damage_model | band_width: ranks the plans
//! damage_weights = [1, 1, 1]         # prior weights of the main study's damage models (default equal)
//!
//! [analysis]
//! samples = 4000                     # prior samples of the state of knowledge
//! reserve = 4000                     # further prior samples, the resampling fallback
//! outer = 300                        # simulated datasets per candidate and size
//! min_ess = 100                      # effective sample size below which the reserve, then resample-move,
//!                                    # is used (the summary flags median ESS below 100)
//! particles = 400                    # resample-move where the reserve is not enough: population size
//! sweeps = 2                         # … and the fewest Metropolis–Hastings sweeps per tempering stage
//!
//! [budget]
//! total = 20000                      # in the decision's currency
//! allocation = "greedy"              # greedy | exhaustive (every affordable plan; small grids)
//! max_plans = 200                    # exhaustive: refuse grids with more affordable plans
//!
//! [[candidate]]
//! name = "repeated impacts, Gen 4"
//! test = "impact"                    # crush | impact | eta_measurement | velocity_measurement
//! material = "gen4"                  # crush and impact tests
//! velocity_m_s = 15                  # impact tests
//! counts = [1, 10, 100, 1000]        # impact tests: broken particles counted after these impacts
//! diameter_m = [0.0008, 0.001]       # crush tests: a sieve fraction (optional)
//! shape_measured = true              # crush tests: roundness and sphericity measured per particle (default)
//! temperature_c = 20                 # crush tests: test temperature, within the crush data's (optional)
//! force_limit_n = 150                # crush tests: the rig stops at this force; a particle not broken
//!                                    # by it is recorded as not broken (right-censored; optional)
//! naming_draws = 60                  # crush tests: run the discrepancy naming loop on the pooled data of
//!                                    # this many outer draws (its verdict on the truth's effects; optional)
//! sd_log = 0.2                       # measurements: sd of ln of one measurement
//! sizes = [25, 50, 100]              # particles (tests) or measurements
//! cost_per_unit = 60                 # per particle or measurement
//! fixed_cost = 1000                  # per campaign (optional)
//! ```

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::schema::FigureOptions;

/// The kinds of candidate experiment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TestKind {
    /// Crush tests of more particles.
    Crush,
    /// Single- or repeated-impact breakage tests.
    Impact,
    /// Measurements of η.
    EtaMeasurement,
    /// Measurements of the impact velocity.
    VelocityMeasurement,
}

impl TestKind {
    /// The unit of a size, in words.
    pub fn unit(self) -> &'static str {
        match self {
            TestKind::Crush | TestKind::Impact => "particles",
            TestKind::EtaMeasurement | TestKind::VelocityMeasurement => "measurements",
        }
    }
}

/// What ranks the plans.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// Expected value of sample information.
    #[default]
    Evsi,
    /// Gain in the probability of choosing the better particle.
    Pcs,
    /// Gain in the expected posterior weight of the true damage model.
    DamageModel,
    /// Reduction of the expected 90 % band width of P_break at the last horizon, summed over
    /// both materials (a probability; no floor: see [`super::state`]).
    BandWidth,
}

impl Objective {
    /// In words, for tables and the summary.
    pub fn describe(self) -> &'static str {
        match self {
            Objective::Evsi => "expected value of sample information",
            Objective::Pcs => "gain in the probability of choosing the better particle",
            Objective::DamageModel => "gain in the expected posterior weight of the true damage model",
            Objective::BandWidth => "narrowing of the 90 % bands of P_break at the last horizon (probability, both materials summed)",
        }
    }
}

/// `[decision]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DecisionOptions {
    /// Horizon of the decision (years), one of the main study's.
    pub horizon_years: f64,
    /// Loss of choosing the particle that breaks more.
    pub loss: f64,
    /// Its currency (also of costs and the budget).
    #[serde(default = "eur")]
    pub currency: String,
    /// What ranks the plans.
    #[serde(default)]
    pub objective: Objective,
    /// Prior weights of the main study's damage models (default equal).
    #[serde(default)]
    pub damage_weights: Option<Vec<f64>>,
}

fn eur() -> String {
    "EUR".into()
}

/// `[analysis]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AnalysisOptions {
    /// Prior samples.
    pub samples: usize,
    /// Reserve prior samples (resampling fallback).
    pub reserve: usize,
    /// Outer draws per candidate and size.
    pub outer: usize,
    /// ESS threshold.
    pub min_ess: f64,
    /// Resample-move: population size after resampling.
    pub particles: usize,
    /// Resample-move: Metropolis–Hastings sweeps per tempering stage.
    pub sweeps: usize,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        AnalysisOptions { samples: 4000, reserve: 4000, outer: 300, min_ess: 100.0, particles: 400, sweeps: 2 }
    }
}

/// `[budget]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BudgetOptions {
    /// Total budget.
    pub total: f64,
    /// How the budget is allocated across candidates.
    #[serde(default)]
    pub allocation: Allocation,
    /// Exhaustive allocation: the most plans it may evaluate.
    #[serde(default = "max_plans")]
    pub max_plans: usize,
}

fn max_plans() -> usize {
    200
}

/// How the budget is allocated ([`crate::experiments::run`] states each rule).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Allocation {
    /// Add the best gain per cost, step by step.
    #[default]
    Greedy,
    /// Every affordable plan (at most one size per candidate), evaluated jointly.
    Exhaustive,
}

/// One `[[candidate]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CandidateSpec {
    /// Name in tables.
    pub name: String,
    /// What kind of test.
    pub test: TestKind,
    /// Material key (crush and impact tests).
    #[serde(default)]
    pub material: Option<String>,
    /// Sizes tried (particles or measurements).
    pub sizes: Vec<i64>,
    /// Cost per particle or measurement.
    pub cost_per_unit: f64,
    /// Cost per campaign.
    #[serde(default)]
    pub fixed_cost: f64,
    /// Impact velocity (m/s).
    #[serde(default)]
    pub velocity_m_s: Option<f64>,
    /// Impact counts.
    #[serde(default)]
    pub counts: Option<Vec<i64>>,
    /// Sieve fraction (m).
    #[serde(default)]
    pub diameter_m: Option<[f64; 2]>,
    /// Measurement error (sd of ln).
    #[serde(default)]
    pub sd_log: Option<f64>,
    /// Crush tests: each particle's roundness and sphericity measured (default true).
    #[serde(default)]
    pub shape_measured: Option<bool>,
    /// Crush tests: the test temperature (°C).
    #[serde(default)]
    pub temperature_c: Option<f64>,
    /// Crush tests: outer draws on which the naming loop is run on the pooled data.
    #[serde(default)]
    pub naming_draws: Option<usize>,
    /// Crush tests: the rig's force limit (N); a particle not broken by it is recorded so.
    #[serde(default)]
    pub force_limit_n: Option<f64>,
}

impl CandidateSpec {
    /// The cost of `size` units.
    pub fn cost(&self, size: u64) -> f64 {
        self.fixed_cost + self.cost_per_unit * size as f64
    }
}

/// A `kind = "experiments"` study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentsStudy {
    /// `experiments`.
    pub kind: String,
    /// Seed.
    pub seed: u64,
    /// The main study file, relative to this one.
    pub study: String,
    /// The decision.
    pub decision: DecisionOptions,
    /// Sampling settings.
    #[serde(default)]
    pub analysis: AnalysisOptions,
    /// The budget.
    pub budget: BudgetOptions,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
    /// Candidates.
    pub candidate: Vec<CandidateSpec>,
}

impl ExperimentsStudy {
    /// The studies whose reports it reads: those of its main study (which is read, not run).
    pub fn prerequisites(&self, file: &crate::schema::StudyFile) -> Result<Vec<crate::schema::Prerequisite>> {
        crate::uq::study::UqStudy::prerequisites_of_file(&file.resolve(std::path::Path::new(&self.study)))
    }

    /// Checks every option that needs neither data nor the main study; `keys` are the main
    /// study's material keys when known (an unknown material is then named).
    pub fn validate(&self, file: &str, keys: Option<&[String]>) -> Result<()> {
        let bad = |k: String, rule: String| Err(Error::config(file, k, rule));
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.decision.loss) {
            return bad("decision.loss".into(), format!("must be a finite number > 0, got {}", self.decision.loss));
        }
        if let Some(w) = &self.decision.damage_weights
            && (w.iter().any(|x| !(x.is_finite() && *x >= 0.0)) || w.iter().sum::<f64>() <= 0.0)
        {
            return bad("decision.damage_weights".into(), format!("must be finite, ≥ 0 and not all 0, got {w:?}"));
        }
        let a = &self.analysis;
        if a.samples < 100 || a.outer < 20 || !positive(a.min_ess) || a.min_ess >= a.samples as f64 {
            return bad("analysis".into(), format!("needs samples ≥ 100, outer ≥ 20 and 0 < min_ess < samples, got samples = {}, outer = {}, min_ess = {}", a.samples, a.outer, a.min_ess));
        }
        if (a.particles as f64) < 2.0 * a.min_ess || a.particles > a.samples + a.reserve {
            return bad("analysis.particles".into(), format!("resample-move needs at least 2 × min_ess = {} particles (fewer cannot reach the threshold) and at most samples + reserve = {}, got {}", 2.0 * a.min_ess, a.samples + a.reserve, a.particles));
        }
        if !(1..=super::smc::MAX_SWEEPS).contains(&a.sweeps) {
            return bad("analysis.sweeps".into(), format!("must lie between 1 and {}, got {}", super::smc::MAX_SWEEPS, a.sweeps));
        }
        if !positive(self.budget.total) {
            return bad("budget.total".into(), format!("must be a finite number > 0, got {}", self.budget.total));
        }
        if self.candidate.is_empty() {
            return bad("candidate".into(), "declare at least one [[candidate]]".into());
        }
        let mut cheapest = f64::INFINITY;
        for (i, c) in self.candidate.iter().enumerate() {
            let key = |k: &str| format!("candidate[{i}].{k}");
            if self.candidate[..i].iter().any(|d| d.name == c.name) {
                return bad(key("name"), format!("\"{}\" is used by an earlier candidate", c.name));
            }
            if c.sizes.is_empty() || c.sizes.iter().any(|&n| n <= 0) {
                return bad(key("sizes"), format!("needs at least one size, each ≥ 1, got {:?}", c.sizes));
            }
            if c.sizes.windows(2).any(|w| w[1] <= w[0]) {
                return bad(key("sizes"), format!("must increase, got {:?}", c.sizes));
            }
            if !positive(c.cost_per_unit) {
                return bad(key("cost_per_unit"), format!("must be a finite number > 0, got {}", c.cost_per_unit));
            }
            if !(c.fixed_cost.is_finite() && c.fixed_cost >= 0.0) {
                return bad(key("fixed_cost"), format!("must be a finite number ≥ 0, got {}", c.fixed_cost));
            }
            let needs_material = matches!(c.test, TestKind::Crush | TestKind::Impact);
            match (&c.material, needs_material) {
                (None, true) => return bad(key("material"), "a crush or impact test needs the material's key".into()),
                (Some(_), false) => return bad(key("material"), "a measurement of η or V is not of one material: remove the key".into()),
                (Some(m), true) => {
                    if let Some(keys) = keys
                        && !keys.contains(m)
                    {
                        return bad(key("material"), format!("unknown material \"{m}\"; the main study has {}", keys.join(", ")));
                    }
                }
                (None, false) => {}
            }
            let only = |present: bool, k: &str, kinds: &str| if present { bad(key(k), format!("only {kinds} take `{k}`")) } else { Ok(()) };
            match c.test {
                TestKind::Impact => {
                    let v = c.velocity_m_s.unwrap_or(f64::NAN);
                    if !(positive(v) && v <= crate::lifetime::MAX_VELOCITY) {
                        return bad(key("velocity_m_s"), format!("an impact test needs a velocity in (0, {}] m/s, got {:?}", crate::lifetime::MAX_VELOCITY, c.velocity_m_s));
                    }
                    let counts = c.counts.clone().unwrap_or_default();
                    if counts.is_empty() || counts[0] < 1 || counts.windows(2).any(|w| w[1] <= w[0]) || counts.len() > 16 {
                        return bad(key("counts"), format!("an impact test needs 1 to 16 increasing impact counts ≥ 1, got {:?}", c.counts));
                    }
                    only(c.diameter_m.is_some(), "diameter_m", "crush tests")?;
                    only(c.shape_measured.is_some(), "shape_measured", "crush tests")?;
                    only(c.temperature_c.is_some(), "temperature_c", "crush tests")?;
                    only(c.naming_draws.is_some(), "naming_draws", "crush tests")?;
                    only(c.force_limit_n.is_some(), "force_limit_n", "crush tests")?;
                    only(c.sd_log.is_some(), "sd_log", "measurements")?;
                }
                TestKind::Crush => {
                    if let Some(f) = c.force_limit_n
                        && !positive(f)
                    {
                        return bad(key("force_limit_n"), format!("must be a finite force > 0 (N), got {f}"));
                    }
                    if let Some(n) = c.naming_draws {
                        if !(20..=a.outer).contains(&n) {
                            return bad(key("naming_draws"), format!("must lie between 20 and analysis.outer = {}, got {n}", a.outer));
                        }
                        if c.shape_measured == Some(false) {
                            return bad(key("naming_draws"), "the naming loop diagnoses each particle's roundness and sphericity: it needs shape_measured = true".into());
                        }
                    }
                    if let Some(t) = c.temperature_c
                        && !(t.is_finite() && t > -273.15)
                    {
                        return bad(key("temperature_c"), format!("must be a finite temperature above absolute zero (−273.15 °C), got {t}"));
                    }
                    if let Some([lo, hi]) = c.diameter_m
                        && !(positive(lo) && lo < hi && hi.is_finite())
                    {
                        return bad(key("diameter_m"), format!("needs 0 < lower < upper (m), got [{lo}, {hi}]"));
                    }
                    only(c.velocity_m_s.is_some(), "velocity_m_s", "impact tests")?;
                    only(c.counts.is_some(), "counts", "impact tests")?;
                    only(c.sd_log.is_some(), "sd_log", "measurements")?;
                }
                TestKind::EtaMeasurement | TestKind::VelocityMeasurement => {
                    if !positive(c.sd_log.unwrap_or(f64::NAN)) {
                        return bad(key("sd_log"), format!("a measurement needs its error (sd of ln y) > 0, got {:?}", c.sd_log));
                    }
                    only(c.velocity_m_s.is_some(), "velocity_m_s", "impact tests")?;
                    only(c.counts.is_some(), "counts", "impact tests")?;
                    only(c.diameter_m.is_some(), "diameter_m", "crush tests")?;
                    only(c.shape_measured.is_some(), "shape_measured", "crush tests")?;
                    only(c.temperature_c.is_some(), "temperature_c", "crush tests")?;
                    only(c.naming_draws.is_some(), "naming_draws", "crush tests")?;
                    only(c.force_limit_n.is_some(), "force_limit_n", "crush tests")?;
                }
            }
            cheapest = cheapest.min(c.cost(c.sizes[0] as u64));
        }
        if self.budget.total < cheapest {
            return bad("budget.total".into(), format!("{} {} is below the cheapest test ({cheapest} {})", self.budget.total, self.decision.currency, self.decision.currency));
        }
        if self.budget.allocation == Allocation::Exhaustive {
            let n = self.affordable_plans(self.budget.max_plans + 1).len();
            if n > self.budget.max_plans {
                return bad("budget.allocation".into(), format!("exhaustive allocation would evaluate more than budget.max_plans = {} affordable plans: use \"greedy\", fewer sizes or candidates, or raise max_plans", self.budget.max_plans));
            }
        }
        Ok(())
    }

    /// Every non-empty plan — at most one size per candidate, as (candidate, size index) pairs in
    /// candidate order — whose cost fits the budget, in lexicographic order; at most `limit`.
    pub fn affordable_plans(&self, limit: usize) -> Vec<Vec<(usize, usize)>> {
        fn walk(s: &ExperimentsStudy, i: usize, spent: f64, plan: &mut Vec<(usize, usize)>, out: &mut Vec<Vec<(usize, usize)>>, limit: usize) {
            if out.len() >= limit {
                return;
            }
            if i == s.candidate.len() {
                if !plan.is_empty() {
                    out.push(plan.clone());
                }
                return;
            }
            walk(s, i + 1, spent, plan, out, limit);
            for (j, &n) in s.candidate[i].sizes.iter().enumerate() {
                let c = spent + s.candidate[i].cost(n as u64);
                if c <= s.budget.total {
                    plan.push((i, j));
                    walk(s, i + 1, c, plan, out, limit);
                    plan.pop();
                }
            }
        }
        let mut out = Vec::new();
        walk(self, 0, 0.0, &mut Vec::new(), &mut out, limit);
        out
    }
}

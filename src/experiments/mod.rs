//! Decision-driven design of further experiments: which crush or impact tests, how many, and
//! how much more confident the Gen 4 vs BL 16/30 answer will be afterwards.
//!
//! The engine is a preposterior analysis ([`preposterior()`]): the current state of knowledge is a
//! set of weighted joint samples of everything uncertain (each material's strength-model
//! parameters, the strength and damage model, η, V), a candidate experiment is simulated under a
//! truth drawn from that state, the state is updated on the simulated data by importance
//! reweighting (with an effective-sample-size check and a reserve of further prior samples as
//! fallback; an experiment may add its own refit),
//! and the decision is taken again. Averaged over truths this gives the probability of choosing
//! the better particle, the expected value of sample information for a declared loss, the
//! expected posterior bands and the expected posterior weight of the true model.
//!
//! * [`mod@preposterior`]: the engine, generic over [`Experiment`].
//! * [`state`]: the main study's state of knowledge ([`crate::uq::run::weighed`]: the strength
//!   models with their stacking weights, each sampled jointly through
//!   [`crate::uq::setup::Setup`]) with the decision "which particle for the plant".
//! * [`impact`]: single- and repeated-impact breakage tests (multinomial counts of the broken
//!   particles after each impact count).
//! * [`measure`]: measurements of η or of the impact velocity with a lognormal error.
//! * [`crush`]: crush tests of n more particles (optionally a sieve fraction), with or without
//!   each particle's shape measured (unmeasured: a mixture over the population's shapes), at a
//!   temperature the crush data cover; optionally the discrepancy naming loop's verdict on the
//!   pooled data (does it name the true strength model's effects?), beside the reweighting's on
//!   the same simulated data ([`Experiment::score`]).
//!
//! Verified against the closed forms of the normal–normal model (preposterior variance, EVSI of a
//! two-action decision), on a decision that is already certain (value 0), on an η measurement
//! on the main study's state (conjugate posterior variance of ln η), on crush tests against
//! ASTM C1239's pivotal widths and against brute-force nested refitting, by the
//! discrimination of Tavares–King damage by repeated impacts, resample-move against the
//! normal–normal closed forms, nested refits and the conjugate η model on plans that defeat
//! reweighting, and by the worth of the shape
//! measurement (none under a model without shape effects; the shape model identified with it,
//! barely without), and the naming loop against the reweighting on the same crush data:
//! `tests/verification/experiments.rs`.
//!
//! * [`smc`]: resample-move — where the reweighted prior samples' effective sample size falls
//!   below the threshold even with the reserve, the likelihood is tempered in and the samples
//!   are moved by Metropolis–Hastings (preconditioned Crank–Nicolson in their normal scores);
//!   plans are evaluated test after test, and the greedy allocation carries each step's
//!   posteriors to the next ([`Experiment`]s that can score any point: [`smc::Movable`]).
//! * [`study`], [`run`], [`plan`]: the `kind = "experiments"` study — candidates with costs and
//!   sizes, the ranked plans, the allocation of a budget (greedy, or exhaustive over a small
//!   grid; plans evaluated jointly), tables, the figure `experiments_metrics` and a generated
//!   `summary.md`.
//!
//! Not yet here: crush tests at temperatures the crush data do not cover (they need a
//! temperature model of the parameters); and the strength draws a crush test can reach are the
//! main study's joint draws (resample-move moves among them, it does not refit).

pub mod crush;
pub mod impact;
pub mod measure;
pub mod plan;
pub mod preposterior;
pub mod run;
pub mod smc;
pub mod state;
pub mod study;
mod summary;

pub use crush::{CrushOptions, CrushTest, Crushed, ForceLimit};
pub use impact::ImpactTest;
pub use measure::{Measured, Measurement};
pub use preposterior::{Draw, Estimate, Experiment, Knowledge, Metrics, Posterior, Route, Score, Scored, Settings, preposterior};
pub use run::run_experiments;
pub use state::{State, StateSample};
pub use study::ExperimentsStudy;

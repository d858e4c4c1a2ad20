//! Decision-driven design of further experiments: which crush or impact tests, how many, and
//! how much more confident the Gen 4 vs BL 16/30 answer will be afterwards.
//!
//! The engine is a preposterior analysis ([`preposterior`]): the current state of knowledge is a
//! set of weighted joint samples of everything uncertain (each material's strength-model
//! parameters, the strength and damage model, η, V), a candidate experiment is simulated under a
//! truth drawn from that state, the state is updated on the simulated data by importance
//! reweighting (with an effective-sample-size check and the experiment's own refit as fallback),
//! and the decision is taken again. Averaged over truths this gives the probability of choosing
//! the better particle, the expected value of sample information for a declared loss, the
//! expected posterior bands and the expected posterior weight of the true model.
//!
//! Verified against the closed forms of the normal–normal model (preposterior variance, EVSI of a
//! two-action decision) and on a decision that is already certain (value 0):
//! `tests/verification/experiments.rs`.

pub mod preposterior;

pub use preposterior::{Draw, Estimate, Experiment, Knowledge, Metrics, Posterior, Route, Settings, preposterior};

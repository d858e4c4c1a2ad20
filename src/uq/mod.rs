//! The main study (`kind = "uq"`): Monte Carlo propagation of every uncertain input of the
//! lifetime chain, per strength model and averaged over them, and variance-based sensitivity.
//!
//! * [`study`]: the study file's schema and its validation.
//! * [`setup`]: one strength model's comparison of the two particle types — every uncertain
//!   input as a marginal, one sample evaluated through each material's
//!   [`crate::strength::LifetimeModel`].
//! * [`forms`]: each strength model fitted, weighed by stacking (the state of knowledge, also
//!   experiment design's prior) and propagated.
//! * [`attrition`]: the answer in a plant engineer's units — share broken in the first year,
//!   years to 1 % and 10 % broken, with 90 % bands.
//! * [`headline`]: the comparison rows, their model average and the ± notation.
//! * [`propagate`]: blocks of Monte Carlo, LHS or shifted Sobol' samples, collected in order.
//! * [`run`]: the run — strength models with stacking weights, the model-averaged headline,
//!   damage models and averaging domains side by side, Sobol' indices, tables and summary.
//! * [`sobol`]: Saltelli design, first-order (Saltelli 2010) and total (Jansen) Sobol' indices
//!   with bootstrap intervals.

pub mod attrition;
pub mod forms;
pub mod headline;
pub mod propagate;
pub mod run;
pub mod setup;
pub mod sobol;
pub mod study;
mod summary;

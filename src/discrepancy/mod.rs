//! The discrepancy workflow (issue 7): find where a fitted model and measurements disagree,
//! name the missing effect, add it, and show the gap shrink.
//!
//! * [`gof`]: diagnosis tools — quantile residuals, AD/KS with parametric-bootstrap p-values,
//!   residual trends against covariates with permutation p-values.
//! * the candidate effects, their equations and covariate signatures, and the Weibull
//!   regression that fits them are the strength model's ([`crate::strength::effects`],
//!   [`crate::strength::regress`]): the fits before and after naming are instances of it.
//! * `meaning` (private): what a fitted candidate's parameter means, in a report's units.
//! * [`workflow`]: the name → add → diagnose-again loop with the bootstrap-calibrated
//!   false-discovery guard and the gap measure; [`guard`]: the guard's arithmetic (the
//!   family-wise p by Westfall–Young min-P or max-T with failed refits counting against naming,
//!   each candidate's critical value, no verdict above a share of failures, the sequential
//!   bootstrap's pretest).
//! * [`specs`]: what a strength specification means on one material's data (an explicit list, or
//!   what the loop names) and its cross-validated evidence for the main study's stacking weights.
//! * [`run`]: the study (`kind = "discrepancy"`, `partlife discrepancy`): lifetime before and
//!   after, detection power vs number of particles; its tables, `verdict.json` and `summary.md`
//!   are written by the private modules `tables`, `verdict` and `report` (each candidate's evidence in words: `verdicts`).
//! * [`koh`]: Kennedy–O'Hagan calibration with a GP discrepancy δ(x) and the name → add →
//!   shrink comparison of candidate model terms, verified on the simple machine and the ball drop.
//! * [`curves`]: the same loop at the force–displacement level (`kind = "discrepancy_curves"`):
//!   the calibrated crush FE (its emulator) against measured curves, δ(displacement) and the
//!   FE-level terms platen compliance, temperature softening and contact-tip curvature.

pub mod curves;
pub mod gof;
pub mod guard;
pub mod koh;
mod meaning;
mod report;
mod tables;
mod verdict;
mod verdicts;
pub mod run;
pub mod study;
pub mod specs;
pub mod workflow;

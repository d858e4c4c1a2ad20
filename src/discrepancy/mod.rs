//! The discrepancy workflow (issue 7): find where a fitted model and measurements disagree,
//! name the missing effect, add it, and show the gap shrink.
//!
//! * [`gof`]: step 1, diagnosis of a Weibull strength fit — quantile residuals, AD/KS with
//!   parametric-bootstrap p-values, residual trends against covariates, and `diagnose`, which
//!   ranks the covariates by their trend and names the tertile where the residuals depart most.
//!
//! Still to come: the candidate-effect library, evidence ranking with a false-discovery guard,
//! the before/after report, the force–displacement GP discrepancy and the CLI.

pub mod gof;

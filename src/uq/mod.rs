//! Uncertainty quantification: Monte Carlo propagation through the lifetime chain and
//! variance-based sensitivity.
//!
//! * [`inputs`]: distributions of the study file, the DEM velocity spectrum, Weibull draws
//!   (parametric bootstrap or Bayesian posterior).
//! * [`damage`]: independent trials, Vogel–Peukert, Tavares–King.
//! * [`run`]: the `kind = "uq"` study.
//! * [`sobol`]: Saltelli design, first-order (Saltelli 2010) and total (Jansen) Sobol' indices
//!   with bootstrap intervals.

pub mod damage;
pub mod inputs;
pub mod run;
pub mod sobol;

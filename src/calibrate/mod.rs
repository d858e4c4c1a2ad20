//! Calibration: fitting a [`crate::model::Simulator`]'s parameters θ to measured outputs.
//!
//! * [`cache`]: evaluations stored on disk by a hash of the configuration and θ.
//! * [`pipeline`]: the calibration loop (design → emulator → least squares → MCMC → refinement);
//!   [`check`]: its final check with simulator runs at posterior draws.
//! * [`executor`]: where a batch of evaluations runs — this process or Slurm array jobs whose
//!   tasks (`partlife eval`, [`eval`]) fill the shared cache.
//! * [`mcmc`]: the affine-invariant ensemble sampler and convergence diagnostics (R̂, ESS).
//! * [`gp`]: Gaussian-process emulator (Matérn-5/2, ML hyperparameters by argmin Nelder–Mead, LOO).
//! * [`synth`]: the generator of the synthetic crush curves (`partlife datasets synth-curves`).
//! * [`synth_dem`]: the generator of the synthetic tube-bank measurements (`partlife datasets synth-dem`).
//! * [`lsq`]: multi-start Levenberg–Marquardt in unit-cube coordinates, covariance from the
//!   Jacobian, correlations and an identifiability report.
//!
//! The data model ([`Noise`]) turns model outputs y(θ) and data d into weighted residuals
//! `r_i = (y_i(θ) − d_i)/σ_i`. Calibration code sees only the Simulator seam.

pub mod cache;
pub mod check;
pub mod data;
pub mod emulator;
pub mod eval;
pub mod executor;
pub mod gp;
pub mod lsq;
pub mod mcmc;
pub mod pipeline;
pub mod run;
pub mod synth;
pub mod study;
pub mod synth_dem;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Measurement noise of the data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Noise {
    /// Known standard deviation per observation (same unit as the data).
    Known {
        /// σ_i, one per observation, each > 0.
        sigma: Vec<f64>,
    },
    /// One common, unknown σ: fitted by ordinary least squares and estimated as
    /// `s² = Σ r²/(n − p)` for the covariance.
    Inferred,
    /// Relative error: σ_i = `relative`·|d_i| (+ `floor`, in data units, for data near zero).
    Relative {
        /// Relative standard deviation, > 0.
        relative: f64,
        /// Absolute floor added to σ_i (≥ 0).
        #[serde(default)]
        floor: f64,
    },
}

impl Noise {
    /// σ_i for data `d` (1 for [`Noise::Inferred`]).
    pub fn sigmas(&self, d: &[f64]) -> Result<Vec<f64>> {
        let s: Vec<f64> = match self {
            Noise::Known { sigma } => {
                if sigma.len() != d.len() {
                    return Err(Error::config("<calibration>", "noise.sigma", format!("{} values for {} observations", sigma.len(), d.len())));
                }
                sigma.clone()
            }
            Noise::Inferred => vec![1.0; d.len()],
            Noise::Relative { relative, floor } => d.iter().map(|x| relative * x.abs() + floor).collect(),
        };
        if let Some((i, v)) = s.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v > 0.0)) {
            return Err(Error::config("<calibration>", "noise", format!("σ of observation {i} is {v}: every σ must be positive")));
        }
        Ok(s)
    }
}

/// Runs a simulator for the calibration methods: batches in parallel, counts the evaluations,
/// records a failing θ with its error (None in its place) and rejects a non-finite or
/// wrong-length output as an error. Shared by least squares and the calibration loop.
pub(crate) struct Runner<'a, S: crate::model::Simulator> {
    pub sim: &'a S,
    pub evaluations: u64,
    pub failures: Vec<(Vec<f64>, String)>,
}

impl<'a, S: crate::model::Simulator> Runner<'a, S> {
    /// A runner with no evaluations yet.
    pub fn new(sim: &'a S) -> Self {
        Runner { sim, evaluations: 0, failures: Vec::new() }
    }

    /// Outputs at every θ (None where the simulator failed).
    pub fn run(&mut self, thetas: &[Vec<f64>]) -> Result<Vec<Option<Vec<f64>>>> {
        self.evaluations += thetas.len() as u64;
        let ys = self.sim.simulate_batch(thetas);
        let mut out = Vec::with_capacity(ys.len());
        for (t, y) in thetas.iter().zip(ys) {
            match y {
                Ok(y) => {
                    crate::model::check_outputs("calibration", self.sim.outputs(), t, &y)?;
                    out.push(Some(y));
                }
                Err(e) => {
                    self.failures.push((t.clone(), e.to_string()));
                    out.push(None);
                }
            }
        }
        Ok(out)
    }
}

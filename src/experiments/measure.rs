//! Measurements of a shared input as candidate experiments: the elastic energy fraction η
//! (instrumented impacts or rebound tests) or the plant's impact velocity V (high-speed imaging
//! at the receiver's outlet), each of n repeated measurements with a stated lognormal error.
//!
//! In the main study η and V are one value per sample (every impact of a particle is at that V
//! with that η), so a measurement of either informs that value: n measurements
//! ln y_i ~ N(ln x_t, s²) of the truth's x_t are summarised by their mean ȳ, and
//! ln p(ȳ | k) = −n (ȳ − ln x_k)² / (2 s²) + const.

use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::preposterior::Experiment;
use super::smc::Movable;
use super::state::{State, StateSample};
use crate::error::{Error, Result};

/// Which shared input is measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measured {
    /// The elastic energy fraction η.
    EnergyFraction,
    /// The impact velocity V.
    Velocity,
}

impl Measured {
    /// Index among the shared inputs (η, V, impacts per year, γ).
    fn shared_index(self) -> usize {
        match self {
            Measured::EnergyFraction => 0,
            Measured::Velocity => 1,
        }
    }
}

/// A measurement with the measured value under every sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    /// What is measured.
    pub what: Measured,
    /// Repeated measurements.
    pub n: u64,
    /// Standard deviation of ln y of one measurement.
    pub sd_log: f64,
    ln_x: Vec<f64>,
}

impl Measurement {
    /// The measurement on `state`'s samples.
    pub fn new(state: &State, what: Measured, n: u64, sd_log: f64) -> Result<Measurement> {
        if n == 0 || !(sd_log.is_finite() && sd_log > 0.0) {
            return Err(Error::numerical("measurement", format!("needs n ≥ 1 and a finite error > 0, got n = {n}, sd_log = {sd_log}")));
        }
        let ln_x = state
            .samples
            .iter()
            .map(|s| {
                let st = &state.forms[s.form].setup;
                s.x[st.shared(what.shared_index())].ln()
            })
            .collect();
        Ok(Measurement { what, n, sd_log, ln_x })
    }
}

impl Experiment for Measurement {
    /// Mean of the n log-measurements.
    type Data = f64;

    fn simulate(&self, truth: usize, rng: &mut ChaCha8Rng) -> f64 {
        Normal::new(self.ln_x[truth], self.sd_log / (self.n as f64).sqrt()).expect("sd > 0").sample(rng)
    }

    fn loglik(&self, ybar: &f64, k: usize) -> f64 {
        self.loglik_of(*ybar, self.ln_x[k])
    }
}

impl Measurement {
    fn loglik_of(&self, ybar: f64, ln_x: f64) -> f64 {
        -(self.n as f64) * (ybar - ln_x).powi(2) / (2.0 * self.sd_log * self.sd_log)
    }
}

impl Movable<State> for Measurement {
    fn loglik_at(&self, state: &State, ybar: &f64, s: &StateSample) -> f64 {
        let st = &state.forms[s.form].setup;
        self.loglik_of(*ybar, s.x[st.shared(self.what.shared_index())].ln())
    }
}

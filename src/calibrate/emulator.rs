//! A multi-output emulator of a [`Simulator`]: one Gaussian process ([`Gp`]) per output on the
//! unit cube of the parameter space (outputs standardised inside each GP), itself a
//! [`Simulator`] (the predictive means), so least squares and MCMC run on it unchanged.
//!
//! [`Emulator::predict`] also returns the predictive variance of each output: the latent GP
//! variance (the emulator's own uncertainty, which refinement drives down) plus the nugget (the
//! simulator's run-to-run jitter, for example the FE's fracture detection), both added to the
//! data variance in the calibration likelihood.

use rayon::prelude::*;

use super::gp::Gp;
use crate::error::{Error, Result};
use crate::model::{OutputSpec, Simulator};
use crate::params::ParamSpace;

/// The emulator and its training runs.
#[derive(Debug, Clone)]
pub struct Emulator {
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
    gps: Vec<Gp>,
    /// Training θ.
    pub thetas: Vec<Vec<f64>>,
    /// Training outputs.
    pub runs: Vec<Vec<f64>>,
}

/// Leave-one-out check of one output.
#[derive(Debug, Clone, PartialEq)]
pub struct LooCheck {
    /// Output name.
    pub output: String,
    /// Root-mean-square leave-one-out error (output unit).
    pub rmse: f64,
    /// Mean squared standardised error (≈ 1 when the predicted variance is honest).
    pub mean_z2: f64,
    /// Output standard deviation over the design (for scale).
    pub spread: f64,
}

impl Emulator {
    /// Fits one GP per output to runs `runs` at `thetas` (each inside `space`).
    pub fn fit(space: &ParamSpace, outputs: &[OutputSpec], thetas: Vec<Vec<f64>>, runs: Vec<Vec<f64>>) -> Result<Emulator> {
        if thetas.len() != runs.len() || runs.iter().any(|y| y.len() != outputs.len()) {
            return Err(Error::numerical("emulator", "design and runs do not match"));
        }
        let x: Vec<Vec<f64>> = thetas.iter().map(|t| space.to_unit(t)).collect();
        let gps = (0..outputs.len())
            .into_par_iter()
            .map(|o| {
                let y: Vec<f64> = runs.iter().map(|r| r[o]).collect();
                Gp::fit(x.clone(), &y).map_err(|e| match e {
                    Error::Numerical { detail, .. } => Error::numerical(format!("emulator of {}", outputs[o].name), detail),
                    other => other,
                })
            })
            .collect::<Result<Vec<Gp>>>()?;
        Ok(Emulator { space: space.clone(), outputs: outputs.to_vec(), gps, thetas, runs })
    }

    /// (mean, latent variance + nugget) of every output at θ.
    pub fn predict(&self, theta: &[f64]) -> Vec<(f64, f64)> {
        let u = self.space.to_unit(theta);
        self.gps
            .iter()
            .map(|g| {
                let (m, v) = g.predict(&u);
                (m, v + g.noise_variance())
            })
            .collect()
    }

    /// [`Emulator::predict`] of the outputs `outputs` only (indices, in that order): a
    /// likelihood that reads some outputs does not pay for the others' variance solves.
    pub fn predict_outputs(&self, theta: &[f64], outputs: &[usize]) -> Vec<(f64, f64)> {
        let u = self.space.to_unit(theta);
        outputs
            .iter()
            .map(|&o| {
                let g = &self.gps[o];
                let (m, v) = g.predict(&u);
                (m, v + g.noise_variance())
            })
            .collect()
    }

    /// Predictive means of the first `count` outputs at θ (the others are not evaluated).
    pub fn means(&self, theta: &[f64], count: usize) -> Vec<f64> {
        let u = self.space.to_unit(theta);
        self.gps.iter().take(count).map(|g| g.mean(&u)).collect()
    }

    /// Latent (emulator-only) standard deviation of every output at θ.
    pub fn latent_sd(&self, theta: &[f64]) -> Vec<f64> {
        let u = self.space.to_unit(theta);
        self.gps.iter().map(|g| g.predict(&u).1.sqrt()).collect()
    }

    /// The simulator's own run-to-run scatter per output (the square root of each GP's
    /// nugget, in the output's unit): what no number of runs teaches the emulator, because the
    /// simulator itself does not repeat it at nearby θ (the crush FE's fracture, for one, jumps
    /// with which element fails first).
    pub fn noise_sd(&self) -> Vec<f64> {
        self.gps.iter().map(|g| g.noise_variance().sqrt()).collect()
    }

    /// Leave-one-out check per output.
    pub fn leave_one_out(&self) -> Vec<LooCheck> {
        self.gps
            .iter()
            .enumerate()
            .map(|(o, g)| {
                let loo = g.leave_one_out();
                let n = loo.len() as f64;
                let ys: Vec<f64> = self.runs.iter().map(|r| r[o]).collect();
                let mean = ys.iter().sum::<f64>() / n;
                let spread = (ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
                let (mut se, mut z2) = (0.0, 0.0);
                for ((m, v), y) in loo.iter().zip(&ys) {
                    se += (m - y).powi(2);
                    z2 += (m - y).powi(2) / v.max(f64::MIN_POSITIVE);
                }
                LooCheck { output: self.outputs[o].name.clone(), rmse: (se / n).sqrt(), mean_z2: z2 / n, spread }
            })
            .collect()
    }

    /// Training runs.
    pub fn len(&self) -> usize {
        self.thetas.len()
    }

    /// True without training runs (never, after `fit`).
    pub fn is_empty(&self) -> bool {
        self.thetas.is_empty()
    }
}

impl Simulator for Emulator {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        Ok(self.predict(theta).into_iter().map(|p| p.0).collect())
    }
}

/// A simulator whose outputs are selected (and repeated) outputs of another: output i is the
/// inner output `index[i]`. Maps a model onto a list of observations.
pub struct Gathered<'a, S: Simulator> {
    inner: &'a S,
    index: Vec<usize>,
    outputs: Vec<OutputSpec>,
}

impl<'a, S: Simulator> Gathered<'a, S> {
    /// Observation i is output `index[i]` of `inner`.
    pub fn new(inner: &'a S, index: Vec<usize>) -> Self {
        let outputs = index.iter().map(|&o| inner.outputs()[o].clone()).collect();
        Gathered { inner, index, outputs }
    }
}

impl<S: Simulator> Simulator for Gathered<'_, S> {
    fn space(&self) -> &ParamSpace {
        self.inner.space()
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        let y = self.inner.simulate(theta)?;
        Ok(self.index.iter().map(|&o| y[o]).collect())
    }
}

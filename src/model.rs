//! The seam between physical models and the methods that drive them.
//!
//! Every physical model is a black box θ ↦ y for Monte Carlo, least squares, MCMC, experiment
//! design and the discrepancy workflow. Those methods see only a [`Simulator`]: its
//! [`ParamSpace`] (names, units, bounds, priors of θ), its [`OutputSpec`]s (names and units of
//! y) and `simulate`. They never see contact, FE or DEM types.
//!
//! Error contract for the methods that drive a simulator:
//! * θ out of bounds → the caller treats it as `−∞` log prior without simulating;
//! * a simulator `Err` → recorded with θ in the run's failures list;
//! * a non-finite output is a bug → [`Error::Numerical`] (see [`check_outputs`]).
//!
//! Implementers: [`crate::strength::LifetimeChain`] and the analytic
//! [`crate::testfns::Ishigami`], the tube-bank DEM [`crate::dem::model::TubeBankModel`] and the
//! crush FE [`crate::fem::model::CrushModel`].

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::params::ParamSpace;

/// Name and unit of one model output.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutputSpec {
    /// Output name (`p_break_7300`).
    pub name: String,
    /// Unit (`N`, `Pa`, `-`).
    pub unit: String,
}

impl OutputSpec {
    /// Convenience constructor.
    pub fn new(name: impl Into<String>, unit: impl Into<String>) -> Self {
        OutputSpec { name: name.into(), unit: unit.into() }
    }
}

/// A deterministic model θ ↦ y.
pub trait Simulator: Sync {
    /// Names, units, bounds and priors of θ.
    fn space(&self) -> &ParamSpace;
    /// Names and units of y, in order.
    fn outputs(&self) -> &[OutputSpec];
    /// One evaluation. Must be deterministic for a given θ.
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>>;
    /// Many evaluations, in parallel with rayon; results are in the order of `thetas` whatever
    /// the thread count.
    fn simulate_batch(&self, thetas: &[Vec<f64>]) -> Vec<Result<Vec<f64>>> {
        par_runs(thetas, |t| self.simulate(t))
    }
}

impl<S: Simulator + ?Sized> Simulator for &S {
    fn space(&self) -> &ParamSpace {
        (**self).space()
    }
    fn outputs(&self) -> &[OutputSpec] {
        (**self).outputs()
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        (**self).simulate(theta)
    }
    fn simulate_batch(&self, thetas: &[Vec<f64>]) -> Vec<Result<Vec<f64>>> {
        (**self).simulate_batch(thetas)
    }
}

/// Runs `f` on a worker of the current rayon pool: directly when called from one, else handed
/// to the global pool once. A solver's time loop runs through it, so that each of its parallel
/// passes is an in-pool split (a pass of one task runs inline) rather than a job injected from
/// outside and waited on, which costs two thread switches per pass.
pub fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() { f() } else { rayon::scope(|_| f()) }
}

thread_local! {
    /// Set while this thread runs one item of a batch that has an item for every thread.
    static IN_FULL_BATCH: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// `f` of every item, in parallel, in the items' order. When there are at least as many items
/// as threads, the threads are kept busy by the items themselves, so each item's solver passes
/// run whole on the thread that runs it ([`pass_min_len`]): splitting them as well only adds
/// hand-offs between threads that are all busy (on 2 cores the RT calibration's batches of crush
/// runs gained little, 68.8 → 67.0 s, within the machine's noise; the hand-offs grow with the
/// thread count). The results do not depend on it: every pass gives the same bits however it is
/// split.
pub fn par_runs<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let full = items.len() >= rayon::current_num_threads();
    items
        .par_iter()
        .map(|t| {
            if !full {
                return f(t);
            }
            let was = IN_FULL_BATCH.replace(true);
            let r = f(t);
            IN_FULL_BATCH.set(was);
            r
        })
        .collect()
}

/// Whether this thread is running one item of a full batch ([`par_runs`]).
pub fn in_full_batch() -> bool {
    IN_FULL_BATCH.get()
}

/// Whether a solver running here has its thread to itself: the pool has one thread, or this is
/// one item of a full batch. Its passes then gain nothing from being split (the crush FE adds
/// each element's forces into its nodes as it goes instead of storing them for a parallel
/// gather).
pub fn alone_on_thread() -> bool {
    rayon::current_num_threads() == 1 || in_full_batch()
}

/// The least number of items a task of a solver's parallel pass takes: `min`, or all of them
/// inside an item of a full batch ([`par_runs`]).
pub fn pass_min_len(min: usize) -> usize {
    if in_full_batch() { usize::MAX } else { min }
}

/// Fails with [`Error::Numerical`] if any output is not finite, naming the output and θ.
pub fn check_outputs(model: &str, specs: &[OutputSpec], theta: &[f64], y: &[f64]) -> Result<()> {
    for (s, v) in specs.iter().zip(y) {
        if !v.is_finite() {
            return Err(Error::numerical(
                model,
                format!("output {} = {v} at θ = {theta:?}", s.name),
            ));
        }
    }
    if specs.len() != y.len() {
        return Err(Error::numerical(
            model,
            format!("{} outputs declared, {} returned", specs.len(), y.len()),
        ));
    }
    Ok(())
}

/// A simulator with some of its parameters held at their nominal values: θ of the restricted
/// model is the listed parameters (with the bounds and priors given here), in their order.
pub struct Restricted<S: Simulator> {
    inner: S,
    free: Vec<usize>,
    base: Vec<f64>,
    space: ParamSpace,
}

impl<S: Simulator> Restricted<S> {
    /// Frees the parameters `params` (matched by name; unit and nominal value from `inner`,
    /// the nominal value clamped into the new bounds); the others stay at `inner`'s nominal.
    pub fn new(inner: S, params: Vec<crate::params::Param>) -> Result<Self> {
        let mut free = Vec::new();
        let mut params = params;
        for p in params.iter_mut() {
            let k = inner.space().index_of(&p.name)?;
            let q = &inner.space().params()[k];
            p.unit = q.unit.clone();
            p.nominal = q.nominal.clamp(p.lower, p.upper);
            free.push(k);
        }
        let space = ParamSpace::new(params)?;
        let base = inner.space().nominal();
        Ok(Restricted { inner, free, base, space })
    }

    /// The full θ of the inner model.
    pub fn full(&self, theta: &[f64]) -> Vec<f64> {
        let mut t = self.base.clone();
        for (&k, &v) in self.free.iter().zip(theta) {
            t[k] = v;
        }
        t
    }
}

impl<S: Simulator> Simulator for Restricted<S> {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        self.inner.outputs()
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.space.check(theta)?;
        self.inner.simulate(&self.full(theta))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_batch_runs_each_item_whole_and_keeps_the_order() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        pool.install(|| {
            // Two items on two threads: full, every pass inside them whole.
            let full = par_runs(&[10usize, 20], |&m| (m, pass_min_len(m)));
            assert_eq!(full, vec![(10, usize::MAX), (20, usize::MAX)]);
            // One item on two threads: its passes may split.
            assert_eq!(par_runs(&[7usize], |&m| pass_min_len(m)), vec![7]);
            // And the flag does not outlive the batch.
            assert_eq!(pass_min_len(3), 3);
            let many: Vec<usize> = (0..100).collect();
            assert_eq!(par_runs(&many, |&i| i * i), many.iter().map(|i| i * i).collect::<Vec<_>>());
        });
    }
}

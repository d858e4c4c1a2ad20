//! Each strength model of the main study fitted to both materials' crush data, weighed by
//! stacking of its cross-validated log scores ([`weighed`]: the state of knowledge, also the prior
//! of experiment design) and propagated ([`forms`]).

use super::propagate::{Propagated, propagate};
use super::setup::{Setup, Shared};
use super::study::UqStudy;
use crate::error::Result;
use crate::strength::NamingSettings;
use rayon::prelude::*;

/// One strength model's run: its setup, samples and predictive evidence.
pub struct Form {
    /// The prepared comparison.
    pub setup: Setup,
    /// Its samples.
    pub prop: Propagated,
    /// Cross-validated log density of each crush test, per material (empty with one model).
    pub lpd: [Vec<f64>; 2],
    /// Stacking weight.
    pub weight: f64,
    /// Pseudo-BMA weight.
    pub weight_pbma: f64,
}

/// The naming settings of material index i (the seed the setup's `"diagnosed"` used).
fn naming(s: &UqStudy, i: usize) -> NamingSettings {
    NamingSettings { seed: s.seed.wrapping_add(7919 * i as u64), ..s.strength.naming.clone() }
}

/// One strength model fitted and weighed, not yet propagated.
pub struct Weighed {
    /// The prepared comparison.
    pub setup: Setup,
    /// Cross-validated log density of each crush test, per material (empty with one model).
    pub lpd: [Vec<f64>; 2],
    /// Stacking weight.
    pub weight: f64,
    /// Pseudo-BMA weight.
    pub weight_pbma: f64,
}

/// Fits, weighs and propagates every strength model of the study. The weights (the models'
/// cross-validation) and the propagation need only the fitted models: they run side by side, and
/// the models side by side within each (every one parallel inside as well, some over few tasks).
pub fn forms(s: &UqStudy, path: &std::path::Path, shared: &Shared, tick: &(dyn Fn() + Sync)) -> Result<Vec<Form>> {
    let setups = fitted(s, path, shared)?;
    let (weights, props) = rayon::join(|| weigh(s, &setups), || setups.par_iter().map(|st| propagate(st, &s.propagation, s.seed, tick)).collect::<Vec<_>>());
    let weighed = weights?;
    setups
        .into_iter()
        .zip(weighed)
        .zip(props)
        .map(|((setup, (lpd, weight, weight_pbma)), prop)| Ok(Form { setup, prop: prop?, lpd, weight, weight_pbma }))
        .collect()
}

/// Fits and weighs every strength model of the study: the main study's state of knowledge
/// (also the prior of experiment design).
pub fn weighed(s: &UqStudy, path: &std::path::Path, shared: &Shared) -> Result<Vec<Weighed>> {
    let setups = fitted(s, path, shared)?;
    let weighed = weigh(s, &setups)?;
    Ok(setups.into_iter().zip(weighed).map(|(setup, (lpd, weight, weight_pbma))| Weighed { setup, lpd, weight, weight_pbma }).collect())
}

/// Every strength model fitted to both materials, the models side by side; errors in the
/// models' order.
fn fitted(s: &UqStudy, path: &std::path::Path, shared: &Shared) -> Result<Vec<Setup>> {
    let setups: Vec<Result<Setup>> = s.specs().par_iter().map(|spec| Setup::new(s, path, spec, &s.contact.averaging, shared)).collect();
    setups.into_iter().collect()
}

/// Each model's cross-validated log densities (per material) and its stacking and pseudo-BMA
/// weights; every (model, material) cross-validation side by side.
fn weigh(s: &UqStudy, setups: &[Setup]) -> Result<Vec<([Vec<f64>; 2], f64, f64)>> {
    if setups.len() < 2 {
        return Ok(setups.iter().map(|_| ([Vec::new(), Vec::new()], 1.0, 1.0)).collect());
    }
    let order = s.order();
    let cells: Vec<(&Setup, usize)> = setups.iter().flat_map(|st| [(st, 0), (st, 1)]).collect();
    let scores: Vec<Result<Vec<f64>>> = cells.par_iter().map(|&(st, j)| {
        let m = &st.materials[j];
        crate::discrepancy::specs::cv_scores(&st.spec, &m.sample, &naming(s, order[j]), &m.model.key, m.origin_column.as_ref().map(|_| &m.failure_origins[..]))
    }).collect();
    let mut scores = scores.into_iter();
    let mut next = || scores.next().expect("two cross-validations per model");
    let lpd: Vec<[Vec<f64>; 2]> = setups.iter().map(|_| Ok([next()?, next()?])).collect::<Result<_>>()?;
    let pooled: Vec<Vec<f64>> = lpd.iter().map(|l| l[0].iter().chain(&l[1]).copied().collect()).collect();
    let (w, wp) = (crate::strength::weights::stacking(&pooled)?, crate::strength::weights::pseudo_bma(&pooled)?);
    Ok(lpd.into_iter().zip(w).zip(wp).map(|((lpd, w), wp)| (lpd, w, wp)).collect())
}

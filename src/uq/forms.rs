//! Each strength model of the main study fitted to both materials' crush data, weighed by
//! stacking of its cross-validated log scores ([`weighed`]: the state of knowledge, also the prior
//! of experiment design) and propagated ([`forms`]).

use super::propagate::{Propagated, propagate};
use super::setup::{Setup, Shared};
use super::study::UqStudy;
use crate::error::Result;
use crate::strength::NamingSettings;

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

/// Fits, weighs and propagates every strength model of the study.
pub fn forms(s: &UqStudy, path: &std::path::Path, shared: &Shared, tick: &(dyn Fn() + Sync)) -> Result<Vec<Form>> {
    weighed(s, path, shared)?
        .into_iter()
        .map(|w| {
            let prop = propagate(&w.setup, &s.propagation, s.seed, tick)?;
            Ok(Form { setup: w.setup, prop, lpd: w.lpd, weight: w.weight, weight_pbma: w.weight_pbma })
        })
        .collect()
}

/// Fits and weighs every strength model of the study: the main study's state of knowledge
/// (also the prior of experiment design).
pub fn weighed(s: &UqStudy, path: &std::path::Path, shared: &Shared) -> Result<Vec<Weighed>> {
    let specs = s.specs();
    let setups: Vec<Setup> = specs.iter().map(|spec| Setup::new(s, path, spec, &s.contact.averaging, shared)).collect::<Result<_>>()?;
    let order = s.order();
    let lpd: Vec<[Vec<f64>; 2]> = if setups.len() > 1 {
        setups
            .iter()
            .map(|st| -> Result<[Vec<f64>; 2]> {
                let f = |j: usize| crate::discrepancy::workflow::cv_scores(&st.spec, &st.materials[j].sample, &naming(s, order[j]), &st.materials[j].model.key);
                Ok([f(0)?, f(1)?])
            })
            .collect::<Result<_>>()?
    } else {
        vec![[Vec::new(), Vec::new()]]
    };
    let pooled: Vec<Vec<f64>> = lpd.iter().map(|l| l[0].iter().chain(&l[1]).copied().collect()).collect();
    let (w, wp) = if setups.len() > 1 { (crate::strength::weights::stacking(&pooled)?, crate::strength::weights::pseudo_bma(&pooled)?) } else { (vec![1.0], vec![1.0]) };
    Ok(setups.into_iter().zip(lpd).zip(w).zip(wp).map(|(((setup, lpd), weight), weight_pbma)| Weighed { setup, lpd, weight, weight_pbma }).collect())
}

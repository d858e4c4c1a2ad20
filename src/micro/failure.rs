//! Progressive failure of a microstructure in a virtual uniaxial test: which pixels crack first,
//! the path the cracks take, and the cell's strength.
//!
//! # Sequentially linear analysis
//!
//! Brittle phases crack when their maximum principal stress σ₁ reaches their tensile strength σ_t
//! (Rankine), and the cell stays linear elastic between cracks. So the load path is a sequence
//! of linear solutions (Rots et al., *Sequentially linear analysis of fracture*, 2008): with the
//! current stiffness, solve the cell under a unit macroscopic stress of the test (periodic
//! boundary conditions, [`super::homogenise::Periodic`] with its symbolic factorisation reused);
//! every intact pixel e would crack at the applied stress s_e = σ_t,e/σ₁,e (σ₁,e > 0); the
//! smallest s_e is the next event: the applied stress reaches it, that pixel cracks — its λ and μ
//! fall to `residual` times their values (Poisson's ratio kept) and it cannot crack again — and
//! the cell is solved anew. Each event records the applied stress and the macroscopic strain
//! ε̄xx at it, so the events trace the saw-tooth stress–strain path of the cell; its largest
//! applied stress is the cell's **strength** in that test.
//!
//! The run stops when the cell's stiffness along the load, E_x = 1/S₁₁ (S = C⁻¹), has fallen
//! below `stiffness_fraction` of its intact value (the cracks have cut its load path: under a
//! prescribed stress a cracked cell keeps finding pixels to crack at similar loads, so the load
//! alone does not tell), when the applied stress of an event falls below `stop_fraction` of the
//! strength reached, when no intact pixel is in tension, or after `max_events` cracks. Rankine
//! cracking opens cracks across the largest tension only: in compression they split the cell
//! along the load, which hardly softens it, so a compression run usually ends at `max_events`
//! and its strength is a lower bound of what this mode gives. One crack per event and no fracture energy: the post-peak branch depends
//! on the pixel size (a cracked pixel dissipates nothing), the strength much less — it is the
//! measure the summary compares. The first event is the first-failure stress of
//! [`super::fields`].

use serde::{Deserialize, Serialize};

use super::fields::{Test, under_stress};
use super::homogenise::{Periodic, Plane};
use crate::error::{Error, Result};

/// `[failure]` of a study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FailureOptions {
    /// The structures to crack (default: every structure).
    #[serde(default)]
    pub structures: Vec<String>,
    /// Realisations per structure (the first ones; default 1).
    #[serde(default = "one")]
    pub realisations: usize,
    /// Most cracked pixels per run.
    #[serde(default = "max_events")]
    pub max_events: usize,
    /// Stop when an event's applied stress falls below this fraction of the strength reached.
    #[serde(default = "stop_fraction")]
    pub stop_fraction: f64,
    /// Stop when the stiffness along the load falls below this fraction of the intact cell's.
    #[serde(default = "stiffness_fraction")]
    pub stiffness_fraction: f64,
    /// Stiffness left in a cracked pixel, as a fraction.
    #[serde(default = "residual")]
    pub residual: f64,
}

fn one() -> usize {
    1
}
fn max_events() -> usize {
    300
}
fn stop_fraction() -> f64 {
    0.3
}
fn stiffness_fraction() -> f64 {
    0.5
}
fn residual() -> f64 {
    1e-3
}

impl FailureOptions {
    /// Checks the options (`file` names the study in messages).
    pub fn validate(&self, file: &str) -> Result<()> {
        if !(1..=64).contains(&self.realisations) {
            return Err(Error::config(file, "failure.realisations", format!("must lie in 1…64, got {}", self.realisations)));
        }
        if !(1..=100_000).contains(&self.max_events) {
            return Err(Error::config(file, "failure.max_events", format!("must lie in 1…100000, got {}", self.max_events)));
        }
        if !(self.stop_fraction > 0.0 && self.stop_fraction < 1.0) {
            return Err(Error::config(file, "failure.stop_fraction", format!("must lie in (0, 1), got {}", self.stop_fraction)));
        }
        if !(self.stiffness_fraction > 0.0 && self.stiffness_fraction < 1.0) {
            return Err(Error::config(file, "failure.stiffness_fraction", format!("must lie in (0, 1), got {}", self.stiffness_fraction)));
        }
        if !(self.residual > 0.0 && self.residual <= 0.1) {
            return Err(Error::config(file, "failure.residual", format!("must lie in (0, 0.1], got {}", self.residual)));
        }
        Ok(())
    }
}

/// `Progressive::stopped` of a run that used up `max_events`.
pub const MAX_EVENTS: &str = "max_events";

/// `Progressive::stopped` of a run whose effective stiffness became singular (a numerical
/// failure, not a physical stop: its strength so far is a lower bound).
pub const SINGULAR: &str = "failed: singular effective stiffness";

/// One crack.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    /// The pixel (element index, row by row from the bottom).
    pub element: usize,
    /// The applied stress magnitude at which it cracked (Pa).
    pub applied_pa: f64,
    /// The macroscopic strain ε̄xx at that stress, before the crack.
    pub macro_strain: f64,
}

/// A progressive-failure run.
#[derive(Debug, Clone, PartialEq)]
pub struct Progressive {
    /// The test.
    pub test: Test,
    /// The cracks in order.
    pub events: Vec<Event>,
    /// The largest applied stress of any event: the cell's strength (Pa).
    pub strength_pa: f64,
    /// The event at which it was reached.
    pub peak_event: usize,
    /// The cell's stiffness along the load at the end over the intact cell's, E_x/E_x,0.
    pub stiffness_left: f64,
    /// Why the run stopped.
    pub stopped: &'static str,
    /// When the run failed ([`SINGULAR`]): the number of cracks at that step.
    pub failed_at: Option<usize>,
}

impl Progressive {
    /// Whether its strength is only a lower bound: it used up `max_events` or failed.
    pub fn lower_bound(&self) -> bool {
        self.stopped == MAX_EVENTS || self.failed_at.is_some()
    }
}

/// The stiffness along x of an effective stiffness C: 1/S₁₁; None when C is singular.
fn stiffness_x(c: &[[f64; 3]; 3]) -> Option<f64> {
    let m = nalgebra::Matrix3::from_fn(|i, j| c[i][j]);
    m.try_inverse().map(|s| 1.0 / s[(0, 0)]).filter(|e| e.is_finite())
}

/// Cracks the cell of in-plane constants `lame[e]` and tensile strengths `strength[e]` (Pa)
/// pixel by pixel in test `test` (module documentation).
pub fn progressive(periodic: &Periodic, lame: &[(f64, f64)], strength: &[f64], plane: Plane, test: Test, opts: &FailureOptions) -> Result<Progressive> {
    if lame.len() != strength.len() {
        return Err(Error::numerical("progressive failure", format!("{} elements but {} strengths", lame.len(), strength.len())));
    }
    let mut lame = lame.to_vec();
    let mut intact = vec![true; lame.len()];
    let mut events: Vec<Event> = Vec::new();
    let (mut peak, mut peak_event) = (0.0f64, 0usize);
    let mut stopped = MAX_EVENTS;
    let (mut e0, mut left) = (f64::NAN, 1.0);
    let mut failed_at = None;
    for _ in 0..=opts.max_events {
        let eff = periodic.solve(&lame)?;
        let Some(ex) = stiffness_x(&eff.c) else {
            // A failure with its step, not the stiffness criterion's ordinary stop.
            (stopped, failed_at) = (SINGULAR, Some(events.len()));
            break;
        };
        if e0.is_nan() {
            e0 = ex;
        }
        left = ex / e0;
        if left < opts.stiffness_fraction {
            stopped = "stiffness along the load fell below stiffness_fraction";
            break;
        }
        if events.len() == opts.max_events {
            break;
        }
        let unit = under_stress(&eff, &lame, plane, test.stress(1.0))?;
        let next = (0..lame.len())
            .filter(|&e| intact[e] && unit.sigma1[e] > 1e-9)
            .map(|e| (strength[e] / unit.sigma1[e], e))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let Some((s, e)) = next else {
            stopped = "no intact pixel in tension";
            break;
        };
        events.push(Event { element: e, applied_pa: s, macro_strain: s * unit.macro_strain[0] });
        if s > peak {
            peak = s;
            peak_event = events.len() - 1;
        }
        if s < opts.stop_fraction * peak {
            stopped = "load fell below stop_fraction of the strength";
            break;
        }
        intact[e] = false;
        lame[e] = (lame[e].0 * opts.residual, lame[e].1 * opts.residual);
    }
    Ok(Progressive { test, events, strength_pa: peak, peak_event, stiffness_left: left, stopped, failed_at })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::Elastic;
    use crate::micro::homogenise::plane_lame;

    /// A singular effective stiffness is no stiffness (which would end the run as the ordinary
    /// stiffness criterion): it has no value, and the run records a failure.
    #[test]
    fn a_singular_stiffness_is_a_failure_not_a_zero() {
        assert_eq!(stiffness_x(&[[0.0; 3]; 3]), None);
        assert_eq!(stiffness_x(&[[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), None);
        let e = stiffness_x(&[[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).unwrap();
        assert!((e - 2.0).abs() < 1e-12);
        let run = Progressive { test: Test::Tension, events: vec![], strength_pa: 0.0, peak_event: 0, stiffness_left: 1.0, stopped: SINGULAR, failed_at: Some(0) };
        assert!(run.lower_bound());
    }

    /// A homogeneous cell with one weaker pixel: it cracks first at its own strength, then the
    /// pixels beside it, across the load, at lower applied stresses (the crack's stress
    /// concentration): the strength is the first event's and the crack runs along y.
    #[test]
    fn a_weak_pixel_starts_a_crack_that_runs_across_the_load() {
        let n = 24;
        let glass = Elastic { youngs_modulus_pa: 70e9, poisson_ratio: 0.2 };
        let lame = vec![plane_lame(&glass, Plane::Strain); n * n];
        let mut strength = vec![50e6; n * n];
        let weak = (n / 2) * n + n / 2;
        strength[weak] = 40e6;
        let p = Periodic::new(n, n).unwrap();
        let opts = FailureOptions { structures: vec![], realisations: 1, max_events: 8, stop_fraction: 0.01, stiffness_fraction: 0.01, residual: 1e-3 };
        let r = progressive(&p, &lame, &strength, Plane::Strain, Test::Tension, &opts).unwrap();
        assert_eq!(r.events[0].element, weak);
        assert!((r.events[0].applied_pa / 40e6 - 1.0).abs() < 1e-9, "{:?}", r.events[0]);
        assert_eq!(r.peak_event, 0);
        // The next cracks extend the first one along y (same column), not along the load.
        for ev in &r.events[1..4] {
            assert_eq!(ev.element % n, n / 2, "event {ev:?} off the crack's column");
            assert!(ev.applied_pa < 40e6);
        }
        // In compression a homogeneous cell has no pixel in tension.
        let c = progressive(&p, &lame, &strength, Plane::Strain, Test::Compression, &opts).unwrap();
        assert!(c.events.is_empty() && c.stopped == "no intact pixel in tension");
    }
}

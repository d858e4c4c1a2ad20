//! Fracture on a force–displacement curve: the first sustained force drop. Shared by the crush
//! FE (which stops a run after it), the reduction of measured curves for calibration and the
//! curve-level discrepancy workflow, so that a simulated and a measured curve break by the same
//! definition. A method module, below the solvers: it reads curves, it runs nothing.

use serde::{Deserialize, Serialize};

/// Definition of fracture on the force–displacement curve.
///
/// Fracture is the **first sustained force drop**: the force falls below `(1 − drop)` times its
/// running maximum and stays below for at least `sustain` of further total displacement (m). The
/// fracture displacement is the displacement at that running maximum, the peak force its value.
/// A drop that recovers (a ring crack, a contact node snapping) is not fracture.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FractureParams {
    /// Relative drop (default 0.2).
    pub drop: f64,
    /// Displacement the drop must last (m, default 1 µm).
    pub sustain: f64,
    /// Run on after fracture by this fraction of the fracture displacement (default 0.15),
    /// then stop.
    pub run_on: f64,
}

impl Default for FractureParams {
    fn default() -> Self {
        FractureParams { drop: 0.2, sustain: 1e-6, run_on: 0.15 }
    }
}

/// Online detection of the first sustained force drop ([`FractureParams`]).
#[derive(Debug, Clone)]
pub struct FractureDetector {
    p: FractureParams,
    max_force: f64,
    at: f64,
    drop_start: Option<f64>,
    fracture: Option<(f64, f64)>,
}

impl FractureDetector {
    /// A detector with the given definition.
    pub fn new(p: FractureParams) -> Self {
        FractureDetector { p, max_force: 0.0, at: 0.0, drop_start: None, fracture: None }
    }

    /// Adds a sample; returns the fracture displacement once, when the drop is confirmed.
    pub fn push(&mut self, displacement: f64, force: f64) -> Option<f64> {
        if self.fracture.is_some() {
            return None;
        }
        if force > self.max_force {
            self.max_force = force;
            self.at = displacement;
            self.drop_start = None;
            return None;
        }
        if force < (1.0 - self.p.drop) * self.max_force {
            let start = *self.drop_start.get_or_insert(displacement);
            if displacement - start >= self.p.sustain {
                self.fracture = Some((self.max_force, self.at));
                return Some(self.at);
            }
        } else {
            self.drop_start = None;
        }
        None
    }

    /// (peak force, its displacement, fracture displacement if any).
    pub fn result(&self) -> (f64, f64, Option<f64>) {
        match self.fracture {
            Some((f, d)) => (f, d, Some(d)),
            None => (self.max_force, self.at, None),
        }
    }
}

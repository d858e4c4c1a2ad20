//! Temperature across the chain: the `kind = "temperature"` study.
//!
//! The deliverable's chain starts with computational thermodynamics — the equilibrium phases of
//! the particle's composition against temperature, with an amorphous fraction that rises from
//! about 900 °C and softens quickly — and shows a Gen 3 particle breaking much earlier at 800 °C
//! than at room temperature. This module connects the two.
//!
//! * [`study`]: the study file.
//! * [`run`]: the run — today the phase-fraction table ([`crate::phases`]): validated,
//!   written as `phases.csv`, drawn as `phase_fractions` in the style of the deliverable's
//!   Fig. 2, and described in a generated `summary.md`.
//!
//! Not yet here: the law applied to the calibrated parameters in the study (JH-2 constants and
//! the Weibull scale, fitted to the calibration posteriors at room temperature and 800 °C, with
//! a declared prior on each glassy ratio), its figure, and the lifetime at the operating
//! temperature.

pub mod run;
pub mod study;

pub use run::run_temperature;
pub use study::TemperatureStudy;

//! Temperature across the chain: the `kind = "temperature"` study.
//!
//! The deliverable's chain starts with computational thermodynamics — the equilibrium phases of
//! the particle's composition against temperature, with an amorphous fraction that rises from
//! about 900 °C and softens quickly — and shows a Gen 3 particle breaking much earlier at 800 °C
//! than at room temperature. This module connects the two.
//!
//! * [`study`]: the study file.
//! * [`run`]: the run — the phase-fraction table ([`crate::phases`]) as table, figure (the
//!   deliverable's Fig. 2 style) and summary; with `[law]`, every calibrated parameter's
//!   temperature law ([`crate::thermal`]) against temperature with bands next to the calibrated
//!   states; with `[softening]`, the discrepancy workflow's temperature term beside the laws'
//!   softening; with `[lifetime]`, the main study's breaking probability against the operating
//!   temperature for both materials, Table 1's softening temperatures marked.
//! * [`validate`]: with `[[validation]]`, crush curves at a temperature the laws were not fitted
//!   to, predicted through the crush FE from the laws and, for comparison, from each calibrated
//!   state as it is.
//!
//! The main study itself runs at an operating temperature through its `[operating]` table,
//! which names a temperature study for its laws ([`crate::uq::setup`]).

pub mod run;
pub mod study;
pub mod validate;

pub use run::run_temperature;
pub use study::TemperatureStudy;

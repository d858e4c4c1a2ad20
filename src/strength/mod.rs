//! The strength model: one lifetime chain, fitted once per material and used by every study.
//!
//! The deliverable's §6 chain — crush force at break → Hertz average radial tension σ̄ → Weibull
//! strength → Hertz impact with energy fraction η → breaking probability after N impacts — is
//! one object here, [`LifetimeModel`]. Its strength law is the Weibull law of σ̄ at break with
//! any of the effects the discrepancy workflow can name ([`effects`]): a weakest-link size
//! effect σ_θ ∝ d^(−α), roundness and sphericity as contact curvature R_c = roundness^q ·
//! sphericity^p · R (the same R_c in the crush reduction and in every impact), temperature
//! softening, and damage from impacts before the crush test. The deliverable's model is the
//! special case without effects (R_c = R, one law for all particles).
//!
//! * [`factors`]: generic effects of a strength file's recorded factors — numeric (ln-linear,
//!   power law), categorical (one scale per level), a size measure with its exponent free and
//!   the weakest-link test — for any brittle strength data, not only particles.
//! * [`flaws`]: two flaw populations — the two-component Weibull mixture and the
//!   competing-risks Weibull — fitted from several starts (BFGS, analytic gradient) with
//!   non-identifiability reported and profile bands; naming candidates in place of the one
//!   Weibull law (`Effect::Populations`), beside the scale effects of recorded columns.
//! * [`origins`]: known failure origins (fractography) — each origin's law with the other
//!   origins' breaks censored (ASTM C1239), and the test of one modulus shared by all (a scale each).
//! * [`specimens`]: strength data as input — a file of specimen strengths with a size measure
//!   and recorded factors, read through the intake into a [`Sample`] the naming loop takes
//!   like a crush sample.
//! * [`loglik`]: one row's log-likelihood (a break, a specimen not broken by its value, one that
//!   broke below it or within a class) and its derivatives, for the regression's Newton steps.
//! * [`fit`]: the crush sample (σ̄ at break per particle and its covariates), the
//!   maximum-likelihood fit of the Weibull regression ([`regress`]) with the model's effects
//!   (the fitted model and its fit at given terms: [`mle`]; the spread of partially pooled
//!   levels: [`pooling`]), cross-validated pointwise log scores.
//! * [`draws`]: the joint uncertainty of all the model's parameters — the parametric bootstrap
//!   in pivotal form (ASTM C1239's pivotal simulation, generalised) or the Bayesian posterior.
//! * [`population`]: the particles a prediction is for (the crush data's, or declared
//!   distributions); P_break is the population average, with the population's own sampling
//!   uncertainty (Bayesian bootstrap) in the bands.
//! * [`model`]: the chain itself, its fast evaluation (one exp per particle and one per law),
//!   and the [`Simulator`](crate::model::Simulator) [`LifetimeChain`].
//! * [`options`]: the `[strength]` section of studies (`effects = [] | [...] | "diagnosed"`,
//!   uncertainty, draws, the naming loop's settings).
//! * [`weights`]: stacking and pseudo-BMA weights of competing strength models from their
//!   cross-validated log scores.
//!
//! The lifetime study (`crate::lifetime_study`), the main study (`crate::uq`) and the discrepancy
//! workflow (`crate::discrepancy`) all evaluate a [`LifetimeModel`]; at fixed inputs they give
//! the same breakage (`tests/verification/strength.rs`).

pub mod draws;
pub mod effects;
pub mod factors;
pub mod fit;
pub mod flaws;
pub mod loglik;
pub mod mle;
pub mod model;
pub mod options;
pub mod origins;
pub mod pooling;
pub mod population;
pub mod regress;
pub mod specimens;
pub mod weights;

pub use draws::{MAX_LINEAR, ParameterSummary, Params, summarise};
pub use effects::{ALL, Effect, Term};
pub use fit::{ModelFit, Sample, StrengthFit, contact_at_break, crush_contact, fit_model, fit_model_near, sample_of};
pub use model::{Horizon, LifetimeChain, LifetimeModel};
pub use options::{FamilyGuard, NamingSettings, StrengthOptions, StrengthSpec, Uncertainty};
pub use crate::dist::PopulationSpec;
pub use population::{Particle, Population};

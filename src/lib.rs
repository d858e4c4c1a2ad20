//! # partlife
//!
//! How long do ceramic particles survive in a concentrated-solar-power plant, and how sure are
//! we? partlife turns single-particle crush tests into breaking probabilities under repeated
//! impacts, following the COMPASsCO₂ deliverable D2.4 §6, with every assumption an explicit,
//! documented option.
//!
//! ## Data flow
//!
//! ```text
//! lab exports (.csv any delimiter/decimal/encoding, .xlsx/.ods) ─► intake (units → SI, provenance)
//!                                                     │
//! datasets/*.csv ───────┐                             ▼
//! studies/<name>.toml ──┴► study::load + validate ─► Study (materials, options, seed)
//!                          runner: prerequisite studies first (missing or stale reports)
//!                                                     │
//!          contact (Hertz) ─► σ̄ at break ─► weibull (ASTM C1239 MLE, pivotal bounds)
//!                                                     │
//!   strength::LifetimeModel — one chain for every study: contact curvature R_c, Weibull law of
//!   σ̄ with effects (size, roundness, …), joint draws, population, impact, damage laws → P_N
//!   (strength::LifetimeChain is its Simulator: θ = (m, σ_θ, β…, γ…, η, V) ↦ (F_max, σ̄, P_N…))
//!                                                     │
//!   lifetime study (runner) · main study (uq: per strength model + stacking average)
//!   · discrepancy (names the effects; before/after are instances of the model)
//!                                                     │
//!     io::ReportDir ─► reports/<name>/{manifest.json, *.csv, summary.md} ─► report::render ─► *.svg *.png *.pdf
//!                      └► report::build (one Document) ─► report::pdf / report::html ─► report.pdf, report.html
//! ```
//!
//! ## The seam: model vs method
//!
//! Physical models implement [`model::Simulator`] over a [`params::ParamSpace`]; methods
//! (Monte Carlo, least squares, MCMC, experiment design, discrepancy) only see that trait.
//! Implementers today: [`strength::LifetimeChain`], [`dem::model::TubeBankModel`],
//! [`fem::model::CrushModel`], [`testfns::Ishigami`].
//!
//! ## Module graph
//!
//! The modules form layers without cycles: each imports only modules of lower layers
//! (`tests/structure.rs` reads every `crate::…` path outside the test modules and fails on a
//! cycle, on an import that does not point to a lower layer of this table, and on a module
//! missing from it).
//!
//! ```text
//! 17  bench                          speed figures (the CLI, src/main.rs, sits above)
//! 16  runner                         loaded study → its runner (only main and bench import it)
//! 15  study                          kind → schema + validation
//! 14  experiments · temperature      experiment design on the main study's state of knowledge; temperature across the chain
//! 13  lifetime_study · uq            the lifetime study; the main study
//! 12  discrepancy · inspect          the naming loop, KOH, the curve level; what `datasets check` says of a file (strength files through strength::specimens)
//! 11  strength                       the one lifetime model (its Bayesian draws use calibrate::mcmc)
//! 10  calibrate                      LSQ, MCMC, emulator, calibration studies, curve generator
//!  9  dem · fem · micro              the solvers with their studies (micro: microstructure micromechanics)
//!  8  runkit · synth · thermal       run helpers; the crush-data generator; parameters against temperature
//!  7  schema                         study files, TOML errors, shared options
//!  6  dist · lab · phases · report   declared distributions; the example lab exports; phase-fraction tables; figures and documents from tables
//!  5  data · testfns                 datasets with plausibility ranges; analytic simulators
//!  4  lifetime · model · weibull     P_N and damage laws; the Simulator seam; ASTM C1239
//!  3  contact · design · io · params · stats
//!  2  intake                         every tabular input: encodings, delimiters, spreadsheets, units, columns, joins
//!  1  error · fracture · obs             errors; the first force drop of a curve; what a strength row says (censoring)
//! ```
//!
//! Study modules reach the layers below only: the shared run helpers are in [`runkit`], the
//! study-file layer in [`schema`] (a runner that needs another study reads it with
//! `schema::StudyFile`), and methods reach solvers only through [`model::Simulator`] (the curve
//! workflow's FE runs are behind `fem::model::CrushModel`, fracture detection is the neutral
//! [`fracture`]).
//!
//! ## Module map
//!
//! | module | what |
//! |---|---|
//! | [`error`] | the error enum; bad input (exit 2) vs run failure (exit 1) |
//! | [`obs`] | observations, not bare strengths: each row exact, right-censored (did not break by its value), left-censored or an interval (a class), counts expanded to specimens; each row's limits, so a bootstrap redraw is censored as the campaign censored it (`Obs::censor`); ln P of a row under any law; randomised probability-integral transforms |
//! | [`params`] | `Param`, `Prior`, `ParamSpace`: bounds, truncated priors, unit-cube maps |
//! | [`model`] | `Simulator`, `OutputSpec`; `on_pool`, which runs a solver's time loop on a worker of rayon's pool; `par_runs`, a batch of runs that keeps each run's passes whole when every thread has a run (`pass_min_len`, `alone_on_thread`) |
//! | [`testfns`] | analytic simulators (Ishigami) |
//! | [`contact`] | Hertz: contact size, surface stresses, average tensile stress (explicit domain), crush, impact with η |
//! | [`weibull`] | ASTM C1239 MLE, unbiasing, pivotal and Fisher bounds, probability plot, size scaling |
//! | [`lifetime`] | P_N without underflow, impacts per year, the impact load; [`lifetime::damage`]: independent trials, Vogel–Peukert, Tavares–King as per-sample laws; [`lifetime::attrition`]: years until a share of the inventory is broken, on a grid of horizons; [`lifetime::tested`]: at which temperature each material was tested and what a lifetime is for (the first page's sentence, the warnings when materials or one material's tests differ in temperature) |
//! | [`strength`] | the one strength/lifetime model: effects (the five particle effects and generic effects of recorded factors — scale and modulus per level, partial pooling of small levels (`pooling`), ln-linear and power laws, the weakest-link size effect and its test, `factors`; two flaw populations and a threshold strength (three-parameter Weibull), `flaws`; known failure origins of strength and crush files, each origin's law with the others censored, the shared-modulus test, the probability that some origin breaks a particle and the cross-validated density of the weakest origin, `origins`), one row's log-likelihood whatever the row says (`loglik`), strength files with factor columns through the intake (`specimens`), Weibull regression and the fitted model (`regress`, `mle`), pivotal/bootstrap/Bayesian joint draws, exact pivotal and profile-likelihood bands of effects, populations (with recorded factors predicted for a level, levels in proportion, a value or a distribution: `predict`), `LifetimeModel` (a modulus and a damage law per level) and its Simulator, stacking weights |
//! | [`dist`] | distributions declared in study files and the DEM velocity spectrum, as inverse-CDF marginals |
//! | [`dem`] | native DEM of the tube bank: Hertz–Mindlin, cell lists, impacts, profiles, VTK; `TubeBankModel` |
//! | [`fem`] | native crush FE: axisymmetric/plane-strain explicit quads (the element update in two halves run back to back over blocks of elements), JH-2, platens, fields, VTU; `CrushModel` (also the runs with other contact tips) |
//! | [`micro`] | microstructure micromechanics: segmented images (PNG) or synthetic two-phase microstructures (soft matrix or soft pockets) with their phases' connectivity; periodic homogenisation on pixel quads (faer sparse Cholesky) with Voigt, Reuss and Hashin–Shtrikman bounds; virtual tension and compression, hot spots per phase, first-failure stress; the `microstructure` study with the §6.1 comparison, maps and `.vtu` |
//! | [`fracture`] | the first sustained force drop on a force–displacement curve, for simulated and measured curves alike |
//! | [`design`] | Sobol' sequences (Joe–Kuo, 64 dimensions), Latin hypercubes |
//! | [`calibrate`] | noise models; multi-start Levenberg–Marquardt (or argmin Nelder–Mead / L-BFGS) with covariance and identifiability; ensemble and adaptive-Metropolis MCMC with R̂/ESS; GP emulator; evaluation cache; the executor (local, or Slurm array jobs whose `partlife eval` tasks fill the shared cache, bit-identical to a local run); the `calibrate` study (crush FE and tube-bank DEM; crush curves at one stated test temperature); synthetic curve and rig generators |
//! | [`discrepancy`] | the discrepancy workflow: diagnosis (quantile residuals, bootstrap AD/KS, residual trends), the name → add → diagnose loop over the strength model's effects (crush data, or strength files with any recorded factors: `[[strength]]`), known failure origins with the lifetime of every origin's law acting (crush data) with a family-wise bootstrap guard, Westfall–Young min-P by default or max-T on the one-parameter scale (failed refits counted against naming, no verdict above 10 % failed; each candidate's critical Λ the order statistic the decision uses; the sequential bootstrap's pretest; the gap's expectation from the bootstrap; `workflow::decide` for the guard's own studies), categorical residual diagnosis (Kruskal–Wallis of location and of scatter) (its names alone, `workflow::names`, behind `effects = "diagnosed"` (`specs`: what a strength specification means on a material and its cross-validated scores), the power replicates and the experiments' naming check), lifetime before/after, detection power; `partlife discrepancy`; Kennedy–O'Hagan GP discrepancy with BIC comparison of model terms, on crush curves too |
//! | [`experiments`] | decision-driven experiment design: preposterior analysis by importance reweighting (probability of correct selection, EVSI, expected posterior bands and model weights, reserve-sample fallback) and resample-move where reweighting degenerates (`experiments::smc`: adaptive tempering, diagonal-pCN moves of the samples, plans evaluated test after test, greedy steps on carried posteriors); the main study's state of knowledge as weighted samples; candidates: crush tests (sieve fraction, shape measured or not, temperature, a rig's force limit leaving particles unbroken; optionally the discrepancy naming loop's verdict on the pooled data), single- and repeated-impact breakage tests, η and impact-velocity measurements; the `experiments` study: ranked plans, greedy or exhaustive budget allocation, report |
//! | [`temperature`] | the `temperature` study: the phase-fraction table (Fig. 2 style), the temperature laws of the calibrated parameters with bands next to the calibrated states, the discrepancy workflow's softening term beside them, held-out crush curves at another temperature predicted through the crush FE from the laws (and from each calibrated state as it is) with their coverage judged against the intervals' nominal level, and the main study's breakage against operating temperature with Table 1's softening temperatures |
//! | [`uq`] | the main study (`kind = "uq"`): strength models as a model-form choice with stacking weights, Monte Carlo propagation through each material's `LifetimeModel` (with known failure origins, every origin's law acting, `uq::setup`), damage models and averaging domains side by side, Sobol' indices with bootstrap intervals (their level in `sobol.csv`), attrition in a plant engineer's units (`uq::attrition`), the summary opening with the answer in one generated sentence and the headline model's attrition; optionally at operating temperatures through the laws of [`thermal`]. Independent work runs side by side (the models' fits, cross-validations and propagations; the tables, each into a `ReportDir::branch` adopted in a fixed order) |
//! | [`intake`] | the one data intake of every tabular input: bytes → text (UTF-8, BOM, UTF-16, Windows-1252) → table (delimiter and decimal mark sniffed, header row; or one sheet of .xlsx/.xls/.xlsb/.ods via calamine, or several sheets with the same columns as one table with a `sheet` column) → columns resolved to fields (study map, then name + unit grammar) → SI values (exact decimal conversion) → plausibility; material filter, join by id, recorded factor columns of any file (`factors`), what the rows say of themselves (`observed`: a `broken` column, a `count` column, classes, the rows at the highest value; pile-ups refused; undeclared yes/no, count and failure-origin columns (origin codes under a header naming them included) refused by `undeclared`, all in one message, with a missing test temperature; every row's test temperature, from its column or the study's `temperature_c`, a file stating none refused), each specimen's failure origin from a declared column (`origins`: labels compared without case, an empty cell `none` on a specimen that did not break), the provenance record; whether a file is a synthetic stand-in (the generator's settings or an export manifest beside it); a minimal .xlsx/.ods writer |
//! | [`data`] | crush datasets (with the factor columns a study declares) and Table 1 through the intake, with row/column-precise validation; the plausibility range of every numeric input column, and of the derived strength |
//! | [`lab`] | the example lab exports of `datasets/examples/` (a semicolon CSV and a workbook) from the SI crush files |
//! | [`inspect`] | what `partlife datasets check` says of a file: its kind, how it was read, a summary of its values |
//! | [`synth`] | the documented generator of the synthetic crush datasets |
//! | [`thermal`] | the temperature law of each calibrated parameter (thermal term × crystalline/glassy mixture in the amorphous fraction), fitted draw by draw to calibration posteriors at two temperatures; the factors of the Weibull scale and Young's modulus between the crush data's and the operating temperature |
//! | [`phases`] | phase-fraction tables against temperature (Thermo-Calc/pycalphad exports): format, validation, conversion of mole and mass fractions to the volume fractions a rule of mixtures takes, linear interpolation, the amorphous fraction; the rule of the shipped illustrative table |
//! | [`stats`] | median, Pearson correlation with p-value, line fit, the one sample-quantile definition (Hyndman–Fan type 7) and the weighted inverse CDF, the one linear interpolation (`locate` + `lerp`), the one ranking |
//! | [`schema`] | the study-file layer under every study module: `StudyFile` (read, kind, parse), TOML errors with line and key, relative paths, shared options (contact, impact, figures, materials) |
//! | [`runkit`] | what every run shares: options (the executor choice among them), summary, clock, progress bars, figures' records, the report commit with `manifest.json` and the documents, `summary.md` from headline lines |
//! | [`lifetime_study`] | the lifetime study (`kind = "lifetime"`): schema and run, through `strength` |
//! | [`study`] | the dispatch from `kind` to each study module's schema and validation: `load` → `LoadedStudy` |
//! | [`runner`] | the dispatch from a loaded study to its runner, after the prerequisite studies whose reports it reads when those are missing or stale (the study graph; top of the graph: only the CLI and `bench` use it) |
//! | [`io`] | atomic report directories, CSV tables, manifest (with each input's intake record and the git commit partlife was built from, embedded by `build.rs`), the one VTK `DataArray` writer; reading report tables and study files; scratch directories |
//! | [`report`] | figures from tables only: SVG (plotters) → PNG (resvg) and vector PDF (svg2pdf), drawn side by side (`report::draw_all`); the decision document of every study: one document model (`report::document`) built from a report's files (`report::build`, captions from the figures' tables in `report::captions`) and rendered to A4 PDF (`report::layout`: text metrics, line breaking, tables, pages, a heading kept with its figure and caption; `report::pdf`: fonts embedded and subset, pages' SVG conversions side by side, pdf-writer) and one self-contained HTML page (`report::html`) |
//! | [`bench`](mod@bench) | the speed figures the issues ask for |
//!
//! ## Conventions
//!
//! SI units inside, always; CSV headers carry their unit (`diameter_m`, `sigma_bar_pa`); plots
//! label theirs. Every stochastic path takes an explicit seed and parallel work is split into
//! seeded blocks collected in order, so results do not depend on the thread count.
#![warn(missing_docs)]

pub mod bench;
pub mod calibrate;
pub mod contact;
pub mod data;
pub mod design;
pub mod dem;
pub mod discrepancy;
pub mod dist;
pub mod fem;
pub mod fracture;
pub mod error;
pub mod experiments;
pub mod intake;
pub mod inspect;
pub mod io;
pub mod lab;
pub mod lifetime;
pub mod lifetime_study;
pub mod micro;
pub mod model;
pub mod obs;
pub mod phases;
pub mod params;
pub mod report;
pub mod runner;
pub mod runkit;
pub mod schema;
pub mod stats;
pub mod strength;
pub mod study;
pub mod synth;
pub mod temperature;
pub mod testfns;
pub mod thermal;
pub mod uq;
pub mod weibull;

pub use error::{Error, Result};

//! The discrepancy study (`kind = "discrepancy"`, `partlife discrepancy`): for each crush
//! dataset, diagnose the deliverable's Weibull–Hertz strength model, name the missing effects,
//! add them, and show the gap shrink — tables, figures, `summary.md` and `verdict.json`.
//!
//! ```toml
//! kind = "discrepancy"
//! seed = 20261122
//! [contact]        # crush reduction, as in the lifetime study (platen, averaging)
//! [impact]         # lifetime change: target, energy_fraction, reference_velocity_m_s,
//!                  # impacts_per_year, years
//! [discrepancy]    # candidates, bootstrap, permutations, alpha, cv_folds, max_effects,
//!                  # tavares_king_gamma (the loop's NamingSettings)
//! [lifetime]       # bootstrap: replicates of the lifetime bands
//! [power]          # particles = [20, 40, 80, 160], replicates, bootstrap (replicates = 0: off)
//! [figures]        # width_cm
//! [[material]]     # key, label, data, elastic, density_kg_m3 (as the lifetime study)
//! ```
//!
//! # Lifetime change
//!
//! The base and the final model are instances of the one strength model
//! ([`crate::strength::LifetimeModel`]), evaluated for the measured particles as the population:
//! the breaking probability after N = years × impacts per year at the reference velocity,
//! P = mean_i [1 − exp(−N H_i)] with each particle's own scale and contact curvature. The 90 %
//! band comes from the model's joint draws (the parametric bootstrap in pivotal form, with the
//! population's Bayesian bootstrap), as in the lifetime and main studies.
//!
//! # Detection power
//!
//! How many crush tests are needed: for each sample size n, `replicates` synthetic datasets are
//! drawn from the **fitted final model** (covariate rows resampled from the data, effects at
//! their estimated sizes) and the whole naming loop is run on each; the detection rate of the
//! effects named in the data is reported with Wilson 90 % intervals. The same number of datasets
//! drawn from the base model (no effect) gives the false-positive rate. The generator's truth
//! is never read.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::report::{headline, summary, verdict_json, write_tables};
use super::workflow::{MIN_PARTICLES, Outcome, analyse, validate};
use crate::data::{CrushData, read_crush};
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir};
use crate::lifetime::impacts_in;
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::strength::{Effect, LifetimeModel, ModelFit, NamingSettings, Sample, StrengthFit, Term, Uncertainty, sample_of};
use crate::schema::{ContactOptions, FigureOptions, ImpactOptions, MaterialSpec, StudyFile, check, elastic_checked};

/// Options of the lifetime bands.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LifetimeOptions {
    /// Parametric-bootstrap replicates of the 90 % bands (default 200).
    pub bootstrap: usize,
}

impl Default for LifetimeOptions {
    fn default() -> Self {
        LifetimeOptions { bootstrap: 200 }
    }
}

/// Options of the detection-power study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PowerOptions {
    /// Sample sizes (default 20, 40, 80, 160).
    pub particles: Vec<usize>,
    /// Synthetic datasets per size and scenario (default 40; 0 switches the study off).
    pub replicates: usize,
    /// Bootstrap replicates per round inside each (default 199).
    pub bootstrap: usize,
}

impl Default for PowerOptions {
    fn default() -> Self {
        PowerOptions { particles: vec![20, 40, 80, 160], replicates: 40, bootstrap: 199 }
    }
}

/// A discrepancy study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiscrepancyStudy {
    /// `discrepancy`.
    pub kind: String,
    /// Seed of every random draw.
    pub seed: u64,
    /// Crush contact (the strength reduction).
    #[serde(default)]
    pub contact: ContactOptions,
    /// Impacts (the lifetime change).
    #[serde(default)]
    pub impact: ImpactOptions,
    /// The naming loop.
    #[serde(default)]
    pub discrepancy: NamingSettings,
    /// The lifetime bands.
    #[serde(default)]
    pub lifetime: LifetimeOptions,
    /// The detection-power study.
    #[serde(default)]
    pub power: PowerOptions,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
    /// Crush datasets, one per material.
    pub material: Vec<MaterialSpec>,
}

impl DiscrepancyStudy {
    /// Validates every option (file named in messages).
    pub fn validate(&self, file: &str) -> Result<()> {
        elastic_checked(file, "contact.platen", &self.contact.platen)?;
        self.contact.averaging.validate(file, "contact.averaging")?;
        elastic_checked(file, "impact.target", &self.impact.target)?;
        let i = &self.impact;
        check(file, "impact.energy_fraction", i.energy_fraction > 0.0 && i.energy_fraction <= 1.0, format!("must lie in (0, 1] (got {})", i.energy_fraction))?;
        check(file, "impact.reference_velocity_m_s", i.reference_velocity_m_s > 0.0 && i.reference_velocity_m_s <= crate::lifetime::MAX_VELOCITY, format!("must lie in (0, {}] m/s (got {})", crate::lifetime::MAX_VELOCITY, i.reference_velocity_m_s))?;
        check(file, "impact.impacts_per_year", i.impacts_per_year > 0.0 && i.impacts_per_year.is_finite(), format!("must be > 0 (got {})", i.impacts_per_year))?;
        check(file, "impact.years", !i.years.is_empty() && i.years.iter().all(|y| *y > 0.0 && y.is_finite()), format!("needs at least one horizon, each > 0 (got {:?})", i.years))?;
        self.discrepancy.validate(file, "discrepancy")?;
        check(file, "lifetime.bootstrap", self.lifetime.bootstrap >= 20, format!("must be ≥ 20 (got {})", self.lifetime.bootstrap))?;
        let p = &self.power;
        if p.replicates > 0 {
            check(file, "power.particles", !p.particles.is_empty() && p.particles.iter().all(|n| *n >= MIN_PARTICLES && *n <= 100_000), format!("sizes must lie in [{MIN_PARTICLES}, 100000] (got {:?})", p.particles))?;
            check(file, "power.bootstrap", p.bootstrap >= 99, format!("must be ≥ 99 (got {})", p.bootstrap))?;
        }
        check(file, "figures.width_cm", self.figures.width_cm >= 4.0 && self.figures.width_cm <= 40.0, format!("must lie in [4, 40] cm (got {})", self.figures.width_cm))?;
        check(file, "material", !self.material.is_empty(), "at least one [[material]] is required".into())?;
        let mut keys = Vec::new();
        for (k, m) in self.material.iter().enumerate() {
            let key = |s: &str| format!("material[{k}].{s}");
            check(file, &key("key"), !m.key.is_empty() && m.key.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'), format!("must be lowercase letters, digits or _ (got \"{}\")", m.key))?;
            check(file, &key("key"), !keys.contains(&m.key), format!("\"{}\" is used twice", m.key))?;
            keys.push(m.key.clone());
            elastic_checked(file, &key("elastic"), &m.elastic)?;
            check(file, &key("density_kg_m3"), m.density_kg_m3 > 0.0 && m.density_kg_m3.is_finite(), format!("must be > 0 (got {})", m.density_kg_m3))?;
        }
        Ok(())
    }

    fn settings(&self) -> NamingSettings {
        NamingSettings { seed: self.seed, ..self.discrepancy.clone() }
    }
}

/// The quick study of `partlife discrepancy --data <crush.csv> --model weibull-hertz`: the
/// lifetime study's defaults (steel platens and tube, line average to 2a, η = 0.1, 5 m/s,
/// 730 impacts a year) and the deliverable's Gen 4 constants (E = 112 GPa, ν = 0.25,
/// 3600 kg/m³); the elastic constants shift σ̄ by a common factor and do not change the verdict.
pub fn quick_study(data: &Path) -> Result<(StudyFile, DiscrepancyStudy)> {
    let crush = read_crush(data)?;
    let stem = data.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "data".into());
    let key: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' }).collect();
    let file_name = data.file_name().map(PathBuf::from).unwrap_or_else(|| data.to_path_buf());
    let material = MaterialSpec {
        key,
        label: crush.material().to_string(),
        data: file_name,
        elastic: crate::contact::Elastic { youngs_modulus_pa: 112e9, poisson_ratio: 0.25 },
        density_kg_m3: 3600.0,
        impact_diameter_m: None,
        population: None,
    };
    let study = DiscrepancyStudy {
        kind: "discrepancy".into(),
        seed: 20261122,
        contact: ContactOptions::default(),
        impact: ImpactOptions::default(),
        discrepancy: NamingSettings::default(),
        lifetime: LifetimeOptions::default(),
        power: PowerOptions::default(),
        figures: FigureOptions::default(),
        material: vec![material],
    };
    let text = toml::to_string(&study).map_err(|e| Error::numerical("quick study", e.to_string()))?;
    let dir = data.parent().unwrap_or(Path::new("."));
    study.validate(&data.display().to_string())?;
    Ok((StudyFile { name: format!("discrepancy-{stem}"), path: dir.join(format!("{stem}.discrepancy.toml")), text }, study))
}

/// The terms of a model's effects for a sample (the effects were fitted, so each has a term).
fn terms_of(effects: &[Effect], sample: &Sample, gamma: f64) -> Vec<(Effect, Term)> {
    effects.iter().filter_map(|c| c.term(&sample.covariates, gamma).ok().map(|t| (*c, t))).collect()
}

/// Lifetime prediction of one model: per horizon (median-free point estimate, 5 %, 95 %).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LifetimeBand {
    /// Horizon (years).
    pub years: f64,
    /// Point estimate from the fitted model.
    pub estimate: f64,
    /// 5 % bootstrap quantile.
    pub q05: f64,
    /// 95 % bootstrap quantile.
    pub q95: f64,
}

/// The lifetime band of a fitted stage model, as an instance of the strength model.
fn lifetime_bands(model: &ModelFit, sample: &Sample, m: &Prepared, s: &DiscrepancyStudy, seed: u64) -> Result<Vec<LifetimeBand>> {
    let terms = terms_of(&model.effects, sample, s.discrepancy.gamma);
    let fit = StrengthFit::from_model(model.clone(), terms, sample);
    let lm = LifetimeModel::new(&m.spec.key, &m.spec.label, m.spec.sphere(&m.data), s.impact.target, s.contact.averaging, fit, m.population.clone())?;
    let counts: Vec<f64> = s.impact.years.iter().map(|y| impacts_in(*y, s.impact.impacts_per_year)).collect();
    let bands = lm.bands(&lm.fit.estimate(), s.impact.energy_fraction, s.impact.reference_velocity_m_s, &counts, Uncertainty::Bootstrap, s.lifetime.bootstrap, seed, 0.9)?;
    Ok(s.impact.years.iter().zip(bands).map(|(&years, (estimate, q05, q95))| LifetimeBand { years, estimate, q05, q95 }).collect())
}

/// One material's inputs: its study entry, crush data, sample and population.
struct Prepared {
    spec: MaterialSpec,
    data: CrushData,
    sample: Sample,
    population: crate::strength::Population,
}

/// Detection power at one sample size.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PowerRow {
    /// `effects` (data drawn from the fitted final model) or `none` (from the base model).
    pub scenario: String,
    /// Sample size.
    pub particles: usize,
    /// Datasets run.
    pub replicates: usize,
    /// Datasets in which the first effect named in the data was named first (`effects`), or
    /// any effect was named (`none`).
    pub first: usize,
    /// Datasets in which every effect named in the data was named (`effects`); = `first` for `none`.
    pub all: usize,
}

fn power_study(sample: &Sample, outcome: &Outcome, settings: &NamingSettings, p: &PowerOptions, tick: &(dyn Fn() + Sync)) -> Vec<PowerRow> {
    let n0 = sample.strength.len();
    let scenarios: Vec<(&str, &ModelFit)> = if outcome.named.is_empty() {
        vec![("none", &outcome.before().model)]
    } else {
        vec![("effects", &outcome.after().model), ("none", &outcome.before().model)]
    };
    let mut rows = Vec::new();
    for (si, (name, model)) in scenarios.iter().enumerate() {
        let d = model.design();
        let ln_scale: Vec<f64> = (0..n0).map(|i| model.reg.ln_scale(&d, i)).collect();
        for (ni, &n) in p.particles.iter().enumerate() {
            let hits: Vec<(bool, bool)> = (0..p.replicates)
                .into_par_iter()
                .map(|r| {
                    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed ^ 0x9077_E400);
                    rng.set_stream(((si * 64 + ni) * 100_000 + r) as u64 + 1);
                    let rows_drawn: Vec<usize> = (0..n).map(|_| rng.random_range(0..n0)).collect();
                    let strength: Vec<f64> = rows_drawn
                        .iter()
                        .map(|&i| {
                            model.reg.quantile_at(ln_scale[i], rng.random())
                        })
                        .collect();
                    let covariates = sample.covariates.iter().map(|(k, v)| (k.clone(), rows_drawn.iter().map(|&i| v[i]).collect())).collect();
                    let synthetic = Sample { source: format!("power replicate {r}"), strength, covariates };
                    let s = NamingSettings { bootstrap: p.bootstrap, seed: settings.seed ^ (r as u64 + 1), ..settings.clone() };
                    let named = analyse(&synthetic, &s, false).map(|o| o.named).unwrap_or_default();
                    tick();
                    if *name == "none" {
                        (!named.is_empty(), !named.is_empty())
                    } else {
                        (named.first() == outcome.named.first(), outcome.named.iter().all(|c| named.contains(c)))
                    }
                })
                .collect();
            rows.push(PowerRow {
                scenario: name.to_string(),
                particles: n,
                replicates: p.replicates,
                first: hits.iter().filter(|h| h.0).count(),
                all: hits.iter().filter(|h| h.1).count(),
            });
        }
    }
    rows
}

/// Wilson score interval of k successes in n at the two-sided level 90 %.
pub fn wilson90(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.644_853_626_951_472_2;
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let den = 1.0 + z * z / n;
    let c = (p + z * z / (2.0 * n)) / den;
    let h = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / den;
    ((c - h).max(0.0), (c + h).min(1.0))
}

/// Everything computed for one material.
pub(super) struct MaterialResult {
    pub(super) spec: MaterialSpec,
    pub(super) data: CrushData,
    pub(super) sample: Sample,
    pub(super) outcome: Outcome,
    pub(super) lifetime: Vec<(String, Vec<LifetimeBand>)>,
    pub(super) power: Vec<PowerRow>,
}

/// Runs the study.
pub fn run_discrepancy(loaded: &StudyFile, s: &DiscrepancyStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    // Inputs first: every bad-input error before anything is written.
    let mut inputs = Vec::new();
    if loaded.path.is_file() {
        inputs.push(InputFile::hash(&loaded.path)?);
    }
    let mut prepared = Vec::new();
    for m in &s.material {
        let path = loaded.resolve(&m.data);
        let data = read_crush(&path)?;
        inputs.push(InputFile::hash(&path)?);
        let sample = sample_of(&data, &m.elastic, &s.contact)?;
        validate(&sample)?;
        let population = crate::strength::Population::of_material(m, prepared.len(), &data, &loaded.path, s.seed)?;
        prepared.push(Prepared { spec: m.clone(), data, sample, population });
    }
    let settings = s.settings();
    let power_runs = if s.power.replicates > 0 { s.power.particles.len() * s.power.replicates * 2 } else { 0 };
    let pb = progress_bar((prepared.len() * (2 + power_runs)) as u64, opts.progress, crate::runkit::PROGRESS_COUNT);
    let mut results = Vec::new();
    for (k, m) in prepared.into_iter().enumerate() {
        pb.set_message(format!("{}: naming loop", m.spec.label));
        let material_settings = NamingSettings { seed: s.seed.wrapping_add(7919 * k as u64), ..settings.clone() };
        let outcome = analyse(&m.sample, &material_settings, true)?;
        pb.inc(1);
        pb.set_message(format!("{}: lifetime before/after", m.spec.label));
        let lifetime = vec![
            ("before".to_string(), lifetime_bands(&outcome.before().model, &m.sample, &m, s, material_settings.seed ^ 0x11FE)?),
            ("after".to_string(), lifetime_bands(&outcome.after().model, &m.sample, &m, s, material_settings.seed ^ 0x11FF)?),
        ];
        pb.inc(1);
        let power = if s.power.replicates > 0 {
            pb.set_message(format!("{}: detection power", m.spec.label));
            power_study(&m.sample, &outcome, &material_settings, &s.power, &|| pb.inc(1))
        } else {
            Vec::new()
        };
        results.push(MaterialResult { spec: m.spec, data: m.data, sample: m.sample, outcome, lifetime, power });
    }

    let mut dir = ReportDir::create(&opts.reports_root, &loaded.name)?;
    write_tables(&mut dir, &results)?;
    let verdict = verdict_json(loaded, s, &results);
    let json = serde_json::to_string_pretty(&verdict).map_err(|e| Error::numerical("verdict.json", e.to_string()))?;
    dir.write_bytes("verdict.json", json.as_bytes())?;
    let headlines: Vec<String> = results.iter().map(headline).collect();
    dir.write_bytes("summary.md", summary(s, &results).as_bytes())?;
    pb.set_message("figures");
    let mut failures = Vec::new();
    let rendered = crate::report::discrepancy::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    let mut evaluations = BTreeMap::new();
    evaluations.insert("naming_bootstrap_replicates".to_string(), results.iter().map(|r| (r.outcome.stages.len() * s.discrepancy.bootstrap) as u64).sum());
    evaluations.insert("power_datasets".to_string(), results.iter().map(|r| r.power.iter().map(|p| p.replicates as u64).sum::<u64>()).sum());
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines })
}

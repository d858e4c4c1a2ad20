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

use super::workflow::{GAP_MEASURE, MIN_PARTICLES, Outcome, analyse, validate};
use crate::data::{CrushData, read_crush};
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
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
struct MaterialResult {
    spec: MaterialSpec,
    data: CrushData,
    sample: Sample,
    outcome: Outcome,
    lifetime: Vec<(String, Vec<LifetimeBand>)>,
    power: Vec<PowerRow>,
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

fn names(c: &[Effect]) -> String {
    if c.is_empty() { "none".into() } else { c.iter().map(|c| c.name()).collect::<Vec<_>>().join(" then ") }
}

fn headline(r: &MaterialResult) -> String {
    let (b, a) = (r.outcome.before(), r.outcome.after());
    format!(
        "{}: effects named: {}; gap G {:.1} → {:.1}; Weibull modulus {:.1} → {:.1}",
        r.spec.label,
        names(&r.outcome.named),
        b.gap,
        a.gap,
        b.model.shape(),
        a.model.shape()
    )
}

fn verdict_json(loaded: &StudyFile, s: &DiscrepancyStudy, results: &[MaterialResult]) -> serde_json::Value {
    use serde_json::json;
    let mut named = serde_json::Map::new();
    let mut before = serde_json::Map::new();
    let mut after = serde_json::Map::new();
    let mut evidence = serde_json::Map::new();
    let mut details = Vec::new();
    for r in results {
        let key = r.spec.key.clone();
        let (b, a) = (r.outcome.before(), r.outcome.after());
        named.insert(key.clone(), json!(r.outcome.named.iter().map(|c| c.name()).collect::<Vec<_>>()));
        before.insert(key.clone(), json!(b.gap));
        after.insert(key.clone(), json!(a.gap));
        let ev: Vec<serde_json::Value> = r
            .outcome
            .evidence
            .iter()
            .map(|e| {
                json!({
                    "round": e.round,
                    "candidate": e.candidate.name(),
                    "equation": e.candidate.equation(),
                    "covariate": e.candidate.covariate(),
                    "skipped": e.skipped,
                    "log_likelihood": finite(e.loglik),
                    "likelihood_ratio": finite(e.lr),
                    "likelihood_ratio_critical": finite(e.lr_critical),
                    "p_bootstrap": finite(e.p_bootstrap),
                    "p_family": finite(e.p_family),
                    "delta_bic": finite(e.delta_bic),
                    "delta_cv_log_score": finite(e.delta_cv),
                    "parameter": e.parameter.as_ref().map(|(k, v, se)| json!({"name": k, "value": finite(*v), "se": finite(*se)})),
                    "meaning": e.meaning,
                    "weibull_modulus": finite(e.shape),
                    "passed_guard": e.passed,
                    "named": e.named,
                })
            })
            .collect();
        evidence.insert(key.clone(), json!(ev));
        let stage = |st: &super::workflow::Stage| {
            json!({
                "effects": st.model.effects.iter().map(|c| c.name()).collect::<Vec<_>>(),
                "weibull_modulus": st.model.shape(),
                "log_likelihood": st.model.loglik(),
                "anderson_darling": st.ad, "p_anderson_darling": st.p_ad,
                "kolmogorov_smirnov": st.ks, "p_kolmogorov_smirnov": st.p_ks,
                "gap": st.gap,
            })
        };
        details.push(json!({
            "key": key,
            "label": r.spec.label,
            "data": r.data.path.display().to_string(),
            "particles": r.sample.strength.len(),
            "covariates_diagnosed": r.outcome.stages[0].findings.iter().map(|f| f.covariate.clone()).collect::<Vec<_>>(),
            "covariates_skipped": r.outcome.skipped_covariates,
            "stages": r.outcome.stages.iter().map(stage).collect::<Vec<_>>(),
            "lifetime": r.lifetime.iter().map(|(k, v)| json!({"model": k, "bands": v})).collect::<Vec<_>>(),
        }));
    }
    json!({
        "study": loaded.name,
        "gap_measure": GAP_MEASURE,
        "guard": format!("family-wise (max-T) bootstrap p < {} with ΔBIC < 0 and a better {}-fold cross-validated log score", s.discrepancy.alpha, s.discrepancy.cv_folds),
        "effects_named": named,
        "gap_before": before,
        "gap_after": after,
        "evidence": evidence,
        "materials": details,
    })
}

fn finite(v: f64) -> serde_json::Value {
    if v.is_finite() { serde_json::json!(v) } else { serde_json::Value::Null }
}

/// Mean ln σ_i of a model over the sample: the scale of the strengths adjusted to the sample's
/// average covariates (x_i · e^(mean − ln σ_i)), which the probability plot shows.
fn reference_ln_scale(model: &ModelFit) -> f64 {
    let d = model.design();
    (0..model.n).map(|i| model.reg.ln_scale(&d, i)).sum::<f64>() / model.n.max(1) as f64
}

fn write_tables(dir: &mut ReportDir, results: &[MaterialResult]) -> Result<()> {
    // materials.csv
    let mut t = table(vec![
        scol("key", results.iter().map(|r| r.spec.key.clone()).collect()),
        scol("label", results.iter().map(|r| r.spec.label.clone()).collect()),
        ucol("particles", results.iter().map(|r| r.sample.strength.len() as u64).collect()),
        scol("effects_named", results.iter().map(|r| names(&r.outcome.named)).collect()),
    ])?;
    dir.write_table("materials", &mut t)?;

    // evidence.csv
    let ev: Vec<(&str, &super::workflow::Evidence)> = results.iter().flat_map(|r| r.outcome.evidence.iter().map(move |e| (r.spec.key.as_str(), e))).collect();
    let par = |f: fn(&(String, f64, f64)) -> f64| ev.iter().map(move |(_, e)| e.parameter.as_ref().map_or(f64::NAN, f)).collect::<Vec<f64>>();
    let mut t = table(vec![
        scol("material", ev.iter().map(|(k, _)| k.to_string()).collect()),
        ucol("round", ev.iter().map(|(_, e)| e.round as u64).collect()),
        scol("candidate", ev.iter().map(|(_, e)| e.candidate.name().to_string()).collect()),
        scol("skipped", ev.iter().map(|(_, e)| e.skipped.clone().unwrap_or_default()).collect()),
        fcol("likelihood_ratio", ev.iter().map(|(_, e)| e.lr).collect()),
        fcol("likelihood_ratio_critical", ev.iter().map(|(_, e)| e.lr_critical).collect()),
        fcol("p_bootstrap", ev.iter().map(|(_, e)| e.p_bootstrap).collect()),
        fcol("p_family", ev.iter().map(|(_, e)| e.p_family).collect()),
        fcol("delta_bic", ev.iter().map(|(_, e)| e.delta_bic).collect()),
        fcol("delta_cv_log_score", ev.iter().map(|(_, e)| e.delta_cv).collect()),
        scol("parameter", ev.iter().map(|(_, e)| e.parameter.as_ref().map(|p| p.0.clone()).unwrap_or_default()).collect()),
        fcol("value", par(|p| p.1)),
        fcol("se", par(|p| p.2)),
        fcol("weibull_modulus", ev.iter().map(|(_, e)| e.shape).collect()),
        scol("passed_guard", ev.iter().map(|(_, e)| e.passed.to_string()).collect()),
        scol("named", ev.iter().map(|(_, e)| e.named.to_string()).collect()),
    ])?;
    dir.write_table("evidence", &mut t)?;

    // stages.csv
    let st: Vec<(&MaterialResult, usize, &super::workflow::Stage)> = results.iter().flat_map(|r| r.outcome.stages.iter().enumerate().map(move |(i, s)| (r, i, s))).collect();
    let mut t = table(vec![
        scol("material", st.iter().map(|(r, _, _)| r.spec.key.clone()).collect()),
        ucol("round", st.iter().map(|(_, i, _)| *i as u64).collect()),
        scol("effects", st.iter().map(|(_, _, s)| names(&s.model.effects)).collect()),
        fcol("weibull_modulus", st.iter().map(|(_, _, s)| s.model.shape()).collect()),
        fcol("log_likelihood", st.iter().map(|(_, _, s)| s.model.loglik()).collect()),
        fcol("anderson_darling", st.iter().map(|(_, _, s)| s.ad).collect()),
        fcol("p_anderson_darling", st.iter().map(|(_, _, s)| s.p_ad).collect()),
        fcol("kolmogorov_smirnov", st.iter().map(|(_, _, s)| s.ks).collect()),
        fcol("p_kolmogorov_smirnov", st.iter().map(|(_, _, s)| s.p_ks).collect()),
        fcol("gap", st.iter().map(|(_, _, s)| s.gap).collect()),
        ucol("covariates_diagnosed", st.iter().map(|(_, _, s)| s.findings.len() as u64).collect()),
    ])?;
    dir.write_table("stages", &mut t)?;

    // findings.csv: residual trends per stage.
    let fi: Vec<(&str, usize, &super::gof::CovariateFinding)> = results
        .iter()
        .flat_map(|r| r.outcome.stages.iter().enumerate().flat_map(move |(i, s)| s.findings.iter().map(move |f| (r.spec.key.as_str(), i, f))))
        .collect();
    let mut t = table(vec![
        scol("material", fi.iter().map(|(k, _, _)| k.to_string()).collect()),
        ucol("round", fi.iter().map(|(_, i, _)| *i as u64).collect()),
        scol("covariate", fi.iter().map(|(_, _, f)| f.covariate.clone()).collect()),
        fcol("spearman_rho", fi.iter().map(|(_, _, f)| f.rho).collect()),
        fcol("p_permutation", fi.iter().map(|(_, _, f)| f.p).collect()),
        fcol("worst_tertile_from", fi.iter().map(|(_, _, f)| f.worst_range.0).collect()),
        fcol("worst_tertile_to", fi.iter().map(|(_, _, f)| f.worst_range.1).collect()),
        fcol("worst_tertile_mean_residual", fi.iter().map(|(_, _, f)| f.worst_range.2).collect()),
    ])?;
    dir.write_table("findings", &mut t)?;

    // residuals.csv: per particle, before and after, with the covariates and the strength
    // adjusted to the sample's average covariates (for the probability plot).
    let mut cols: BTreeMap<&str, Vec<String>> = BTreeMap::new();
    let mut num: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for r in results {
        for (stage, st) in [("before", r.outcome.before()), ("after", r.outcome.after())] {
            let d = st.model.design();
            let centre = reference_ln_scale(&st.model);
            for i in 0..r.sample.strength.len() {
                cols.entry("material").or_default().push(r.spec.key.clone());
                cols.entry("id").or_default().push(r.data.records[i].id.clone());
                cols.entry("stage").or_default().push(stage.into());
                let x = r.sample.strength[i];
                num.entry("strength_pa").or_default().push(x);
                num.entry("adjusted_pa").or_default().push(x * (centre - st.model.reg.ln_scale(&d, i)).exp());
                num.entry("residual").or_default().push(st.residuals[i]);
                for (name, v) in &r.sample.covariates {
                    let key: &str = super::workflow::DIAGNOSED.iter().find(|d| **d == name).copied().unwrap_or("other");
                    num.entry(key).or_default().push(v[i].unwrap_or(f64::NAN));
                }
            }
        }
    }
    let mut columns = vec![scol("material", cols.remove("material").unwrap_or_default()), scol("id", cols.remove("id").unwrap_or_default()), scol("stage", cols.remove("stage").unwrap_or_default())];
    for k in ["strength_pa", "adjusted_pa", "residual"].iter().chain(super::workflow::DIAGNOSED.iter()) {
        columns.push(fcol(k, num.remove(k).unwrap_or_default()));
    }
    let mut t = table(columns)?;
    dir.write_table("residuals", &mut t)?;

    // fits.csv: the Weibull law of the adjusted strengths of each stage (probability plot).
    let mut t = table(vec![
        scol("material", results.iter().flat_map(|r| [r.spec.key.clone(), r.spec.key.clone()]).collect()),
        scol("stage", results.iter().flat_map(|_| ["before".to_string(), "after".to_string()]).collect()),
        scol("effects", results.iter().flat_map(|r| [names(&r.outcome.before().model.effects), names(&r.outcome.after().model.effects)]).collect()),
        fcol("weibull_modulus", results.iter().flat_map(|r| [r.outcome.before().model.shape(), r.outcome.after().model.shape()]).collect()),
        fcol("scale_pa", results.iter().flat_map(|r| [reference_ln_scale(&r.outcome.before().model).exp(), reference_ln_scale(&r.outcome.after().model).exp()]).collect()),
    ])?;
    dir.write_table("fits", &mut t)?;

    // lifetime.csv
    let lt: Vec<(&str, &str, &LifetimeBand)> = results.iter().flat_map(|r| r.lifetime.iter().flat_map(move |(st, v)| v.iter().map(move |b| (r.spec.key.as_str(), st.as_str(), b)))).collect();
    let mut t = table(vec![
        scol("material", lt.iter().map(|x| x.0.to_string()).collect()),
        scol("stage", lt.iter().map(|x| x.1.to_string()).collect()),
        fcol("years", lt.iter().map(|x| x.2.years).collect()),
        fcol("p_break", lt.iter().map(|x| x.2.estimate).collect()),
        fcol("q05", lt.iter().map(|x| x.2.q05).collect()),
        fcol("q95", lt.iter().map(|x| x.2.q95).collect()),
    ])?;
    dir.write_table("lifetime", &mut t)?;

    // power.csv
    let pw: Vec<(&str, &PowerRow)> = results.iter().flat_map(|r| r.power.iter().map(move |p| (r.spec.key.as_str(), p))).collect();
    let rate = |k: usize, n: usize| if n == 0 { f64::NAN } else { k as f64 / n as f64 };
    let mut t = table(vec![
        scol("material", pw.iter().map(|x| x.0.to_string()).collect()),
        scol("scenario", pw.iter().map(|x| x.1.scenario.clone()).collect()),
        scol("effects", pw.iter().map(|x| if x.1.scenario == "none" { "none".to_string() } else { names(&results.iter().find(|r| r.spec.key == x.0).map(|r| r.outcome.named.clone()).unwrap_or_default()) }).collect()),
        ucol("particles", pw.iter().map(|x| x.1.particles as u64).collect()),
        ucol("replicates", pw.iter().map(|x| x.1.replicates as u64).collect()),
        fcol("rate_first", pw.iter().map(|x| rate(x.1.first, x.1.replicates)).collect()),
        fcol("rate_all", pw.iter().map(|x| rate(x.1.all, x.1.replicates)).collect()),
        fcol("rate_all_lo90", pw.iter().map(|x| wilson90(x.1.all, x.1.replicates).0).collect()),
        fcol("rate_all_hi90", pw.iter().map(|x| wilson90(x.1.all, x.1.replicates).1).collect()),
    ])?;
    dir.write_table("power", &mut t)?;
    Ok(())
}

/// One row of the summary's evidence table: the numbers of the guard and the verdict they gave.
fn evidence_row(e: &super::workflow::Evidence) -> String {
    if let Some(reason) = &e.skipped {
        return format!("| {} | {} | | | | | | | skipped: {} |\n", e.round, e.candidate.name(), reason);
    }
    let par = e.parameter.as_ref().map(|(k, v, se)| if se.is_finite() { format!("{k} = {v:.3} ± {se:.3}") } else { format!("{k} = {v:.3}") }).unwrap_or_default();
    let verdict = if e.named { "**named**" } else if e.passed { "passed, weaker" } else { "not supported" };
    format!("| {} | {} | {:.2} | {:.2} | {:.3} | {:.2} | {:.2} | {} | {} |\n", e.round, e.candidate.name(), e.lr, e.lr_critical, e.p_family, e.delta_bic, e.delta_cv, par, verdict)
}

fn summary(s: &DiscrepancyStudy, results: &[MaterialResult]) -> String {
    let mut md = String::from("# Discrepancy of the Weibull–Hertz strength model\n\n");
    md.push_str(&format!(
        "Each crush dataset is reduced as in the deliverable (σ̄ at break, Hertz contact with R = d/2, {}) and fitted with one Weibull law. The workflow then looks for structure the model misses, names the missing effect only when it passes the guard (family-wise bootstrap p < {}, ΔBIC < 0, better {}-fold cross-validated log score), adds it and diagnoses again.\n\nGap measure: {}.\n",
        s.contact.averaging.describe(),
        s.discrepancy.alpha,
        s.discrepancy.cv_folds,
        GAP_MEASURE
    ));
    for r in results {
        let (b, a) = (r.outcome.before(), r.outcome.after());
        md.push_str(&format!("\n## {} ({} particles, `{}`)\n\n", r.spec.label, r.sample.strength.len(), r.data.path.display()));
        md.push_str(&format!("**Effects named, in order: {}.**\n\n", names(&r.outcome.named)));
        md.push_str("| model | Weibull m | AD (p) | KS (p) | gap G |\n|---|---|---|---|---|\n");
        for (i, st) in r.outcome.stages.iter().enumerate() {
            md.push_str(&format!(
                "| {}{} | {:.1} | {:.3} ({:.3}) | {:.3} ({:.3}) | {:.1} |\n",
                if i == 0 { "base" } else { "+ " },
                if i == 0 { String::new() } else { names(&st.model.effects) },
                st.model.shape(),
                st.ad,
                st.p_ad,
                st.ks,
                st.p_ks,
                st.gap
            ));
        }
        md.push_str(&format!("\nWith nothing missing G ≈ {} (one per covariate diagnosed).\n\n", b.findings.len()));
        md.push_str("| round | candidate | Λ | Λ critical | p (family) | ΔBIC | ΔCV log score | parameter | verdict |\n|---|---|---|---|---|---|---|---|---|\n");
        for e in &r.outcome.evidence {
            md.push_str(&evidence_row(e));
        }
        if let Some(f) = b.findings.first() {
            md.push_str(&format!(
                "\nLargest residual trend before: `{}` (Spearman ρ = {:.2}, permutation p = {:.3}); the residuals depart most for {} in [{:.4}, {:.4}] (mean residual {:+.2}).\n",
                f.covariate, f.rho, f.p, f.covariate, f.worst_range.0, f.worst_range.1, f.worst_range.2
            ));
        }
        if let Some(f) = a.findings.first() {
            md.push_str(&format!("After: largest trend `{}` (ρ = {:.2}, p = {:.3}).\n", f.covariate, f.rho, f.p));
        }
        md.push_str(&format!(
            "\n**Lifetime at {} m/s, η = {}, {} impacts a year** (population of the measured particles; 90 % band of the strength model's joint draws — pivotal bootstrap of its parameters and Bayesian bootstrap of the population):\n\n| horizon | base model | final model |\n|---|---|---|\n",
            s.impact.reference_velocity_m_s, s.impact.energy_fraction, s.impact.impacts_per_year
        ));
        let (lb, la) = (&r.lifetime[0].1, &r.lifetime[1].1);
        for (x, y) in lb.iter().zip(la) {
            md.push_str(&format!("| {} yr | {:.3e} [{:.2e}, {:.2e}] | {:.3e} [{:.2e}, {:.2e}] |\n", x.years, x.estimate, x.q05, x.q95, y.estimate, y.q05, y.q95));
        }
        if !r.outcome.named.is_empty() {
            md.push_str(&format!(
                "\nAt {} m/s the impact stress lies far below the crush strengths, so the prediction is an extrapolation into the lower tail of the strength law, which the Weibull modulus governs: once the named effects explain part of the scatter the modulus is {:.1} instead of {:.1}, and the tail — hence the lifetime — changes accordingly.\n",
                s.impact.reference_velocity_m_s,
                a.model.shape(),
                b.model.shape()
            ));
        }
        if !r.power.is_empty() {
            md.push_str("\n**Detection power** (datasets drawn from the fitted model; rate of naming every effect found here, and the false-positive rate with no effect):\n\n| particles | power | false positives |\n|---|---|---|\n");
            for n in &s.power.particles {
                let pe = r.power.iter().find(|p| p.scenario == "effects" && p.particles == *n);
                let pn = r.power.iter().find(|p| p.scenario == "none" && p.particles == *n);
                let f = |p: Option<&PowerRow>| p.map(|p| format!("{}/{}", p.all, p.replicates)).unwrap_or_else(|| "–".into());
                md.push_str(&format!("| {n} | {} | {} |\n", f(pe), f(pn)));
            }
        }
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discrepancy::workflow::Evidence;

    /// The Wilson bounds are where the score test is just significant at 90 %:
    /// (p̂ − p₀)² = z² p₀(1 − p₀)/n, an independent characterisation of the closed form.
    #[test]
    fn wilson_bounds_invert_the_score_test() {
        let z = 1.644_853_626_951_472_2_f64;
        for (k, n) in [(0, 10), (3, 10), (10, 10), (1, 200), (57, 100)] {
            let (lo, hi) = wilson90(k, n);
            assert!(lo <= k as f64 / n as f64 && k as f64 / n as f64 <= hi, "{k}/{n}: [{lo}, {hi}]");
            for p0 in [lo, hi] {
                if p0 > 0.0 && p0 < 1.0 {
                    let p = k as f64 / n as f64;
                    assert!(((p - p0).powi(2) - z * z * p0 * (1.0 - p0) / n as f64).abs() < 1e-12, "{k}/{n}: bound {p0}");
                }
            }
        }
        // k = 0: lower bound 0, upper z²/(n + z²); no data: [0, 1].
        let (lo, hi) = wilson90(0, 10);
        assert_eq!(lo, 0.0);
        assert!((hi - z * z / (10.0 + z * z)).abs() < 1e-15, "{hi}");
        assert_eq!(wilson90(0, 0), (0.0, 1.0));
    }

    fn evidence(named: bool, passed: bool, skipped: Option<&str>, se: f64) -> Evidence {
        Evidence {
            round: 2,
            candidate: Effect::Roundness,
            skipped: skipped.map(String::from),
            loglik: -10.0,
            lr: 12.3456,
            p_bootstrap: 0.001,
            p_family: 0.0042,
            lr_critical: 6.5,
            delta_bic: -8.1304,
            delta_cv: 0.3751,
            parameter: Some(("β".into(), 0.5, se)),
            meaning: String::new(),
            shape: 5.0,
            passed,
            named,
        }
    }

    #[test]
    fn evidence_rows_carry_the_guard_numbers_and_their_verdict() {
        let name = Effect::Roundness.name();
        assert_eq!(evidence_row(&evidence(true, true, None, 0.125)), format!("| 2 | {name} | 12.35 | 6.50 | 0.004 | -8.13 | 0.38 | β = 0.500 ± 0.125 | **named** |\n"));
        assert_eq!(evidence_row(&evidence(false, true, None, f64::NAN)), format!("| 2 | {name} | 12.35 | 6.50 | 0.004 | -8.13 | 0.38 | β = 0.500 | passed, weaker |\n"));
        assert_eq!(evidence_row(&evidence(false, false, None, 0.125)), format!("| 2 | {name} | 12.35 | 6.50 | 0.004 | -8.13 | 0.38 | β = 0.500 ± 0.125 | not supported |\n"));
        assert_eq!(evidence_row(&evidence(false, false, Some("no roundness column"), 0.125)), format!("| 2 | {name} | | | | | | | skipped: no roundness column |\n"));
    }
}

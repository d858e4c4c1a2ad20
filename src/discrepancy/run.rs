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
//! [[material]]     # key, label, data, elastic, density_kg_m3 (as the lifetime study);
//!                  # origin: the column naming each particle's failure origin
//! ```
//!
//! # Lifetime change
//!
//! The base and the final model are instances of the one strength model
//! ([`crate::strength::LifetimeModel`]), evaluated for the measured particles as the population:
//! the breaking probability after N = years × impacts per year at the reference velocity,
//! P = mean_i [1 − exp(−N H_i)] with each particle's own scale and contact curvature. The 90 %
//! band comes from the model's joint draws (the parametric bootstrap in pivotal form, with the
//! population's Bayesian bootstrap), as in the lifetime and main studies. Where the study names
//! each particle's failure origin, a third lifetime has every origin's own law acting
//! (`origins_lifetime`).
//!
//! # Detection power
//!
//! How many crush tests are needed: for each sample size n, `replicates` synthetic datasets are
//! drawn from the **fitted final model** (covariate rows resampled from the data, effects at
//! their estimated sizes; [`crate::strength::regress::draw_particles`], the generator of
//! experiment design's crush tests too) and the whole naming loop is run on each; the detection rate of the
//! effects named in the data is reported with Wilson 90 % intervals. The same number of datasets
//! drawn from the base model (no effect) gives the false-positive rate. The generator's truth
//! is never read. Experiment design (`naming_draws` of a crush candidate) runs the same loop on
//! today's particles pooled with simulated ones, its truths drawn from the main study's state of
//! knowledge: the question "after n more tests", where this one asks "in n tests alone".

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

pub use super::study::{DiscrepancyStudy, LifetimeBand, LifetimeOptions, MaterialResult, PowerOptions, PowerRow};
pub use super::report::wilson90;
use super::report::{headline, summary};
use super::verdict::verdict_json;
use super::tables::write_tables;
use super::workflow::{Outcome, analyse, names, validate};
use crate::data::CrushData;
use crate::error::{Error, Result};
use crate::io::InputFile;
use crate::lifetime::impacts_in;
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::strength::regress::draw_rows;
use crate::strength::{Effect, LifetimeModel, ModelFit, NamingSettings, Sample, StrengthFit, Term, Uncertainty, sample_of};
use crate::schema::{ContactOptions, FigureOptions, ImpactOptions, MaterialSpec, StudyFile};

/// What a `--data` run says where the file needs a declaration: the command line has none.
pub const QUICK_DECLARES_NOTHING: &str = " — `--data` declares nothing: write a discrepancy study (`kind = \"discrepancy\"`, the file under `[[material]]` as `data = { file = \"…\", … }`) and put the key named above in its `data` table or `[[material]]`";

/// The quick study of `partlife discrepancy --data <crush.csv> --model weibull-hertz`: the
/// lifetime study's defaults (steel platens and tube, line average to 2a, η = 0.1, 5 m/s,
/// 730 impacts a year) and the particles' elastic constants and density as given (`elastic`,
/// `density_kg_m3`: the command's options, which it requires — they set the lifetime: with a
/// bauxite's constants instead of Gen 4's the 1-year breakage differs by an order of
/// magnitude; they shift σ̄ by a common factor and do not change the naming verdict).
pub fn quick_study(data: &Path, elastic: crate::contact::Elastic, density_kg_m3: f64, temperature_c: Option<f64>, operating_c: Option<f64>, label: Option<&str>) -> Result<(StudyFile, DiscrepancyStudy)> {
    let source = crate::intake::Source { temperature_c, ..crate::intake::Source::file(data) };
    if let Some(t) = temperature_c
        && !crate::data::TEMPERATURE.contains(t)
    {
        return Err(Error::config("--data", "--temperature-c", format!("a test temperature must lie in {} (got {t})", crate::data::TEMPERATURE.shown)));
    }
    let crush = crate::data::read_crush_source(&source, &crate::intake::MapOrigin { file: "--data".into(), key: String::new() }).map_err(|e| e.noted_where_declared(QUICK_DECLARES_NOTHING))?;
    // Tests at several temperatures: the lifetime after a named temperature term is at the
    // temperature the command line names.
    let tested: Vec<f64> = crush.records.iter().filter_map(|r| r.temperature_c).collect();
    if let Some(t) = operating_c
        && !crate::data::TEMPERATURE.contains(t)
    {
        return Err(Error::config("--data", "--operating-temperature-c", format!("an operating temperature must lie in {} (got {t})", crate::data::TEMPERATURE.shown)));
    }
    if operating_c.is_none() && tested.iter().any(|t| *t != tested[0]) {
        return Err(Error::config(
            "--data",
            "--operating-temperature-c",
            format!("{} was tested at {}: the loop may name temperature softening, and the lifetime after it must be at a temperature you name: give --operating-temperature-c (°C), e.g. 800", data.display(), crate::intake::observed::describe_temperatures(&tested)),
        ));
    }
    let stem = data.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "data".into());
    let key: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '_' }).collect();
    let file_name = data.file_name().map(PathBuf::from).unwrap_or_else(|| data.to_path_buf());
    let material = MaterialSpec {
        key,
        // The label given, else the file's material column, else the file's stem.
        label: match label {
            Some(l) => l.to_string(),
            None if crush.material().is_empty() => stem.clone(),
            None => crush.material().to_string(),
        },
        data: crate::intake::DataRef(crate::intake::Source { temperature_c, ..crate::intake::Source::file(file_name) }),
        elastic,
        density_kg_m3,
        impact_diameter_m: None,
        population: None,
        factors: Default::default(),
        predict: operating_c.map(|t| [("temperature_c".to_string(), toml::Value::Float(t))].into_iter().collect()).unwrap_or_default(),
        origin: None,
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
        strength: Vec::new(),
    };
    let text = toml::to_string(&study).map_err(|e| Error::numerical("quick study", e.to_string()))?;
    let dir = data.parent().unwrap_or(Path::new("."));
    study.validate(&data.display().to_string())?;
    Ok((StudyFile { name: format!("discrepancy-{stem}"), path: dir.join(format!("{stem}.discrepancy.toml")), text }, study))
}

/// The terms of a model's effects for a sample (the effects were fitted, so each has a term).
fn terms_of(effects: &[Effect], sample: &Sample, gamma: f64) -> Vec<(Effect, Term)> {
    effects.iter().filter_map(|c| sample.term(c, gamma).ok().map(|t| (c.clone(), t))).collect()
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

/// Seed of the failure origins' bootstrap draws (xor the material's naming seed): one set of
/// draws per origin gives its bands and enters the lifetime with every origin acting.
const ORIGINS_SEED: u64 = 0x0519;

/// The lifetime with every failure origin's law acting (crush data whose study names the origin
/// column): each origin's two-parameter law fitted to its own breaks with the other origins'
/// censored ([`crate::obs::Obs::of_origin`]) is one [`LifetimeModel`], and a particle
/// survives N impacts only if it survives every origin's flaws, P_N = 1 − Π_k (1 − P_N,k)
/// ([`crate::strength::origins::combined`]; exact for the base model's one σ̄ per impact). The
/// band combines each origin's parametric-bootstrap draws index by index (the censored
/// likelihoods factorise, so the origins' estimates are independent); each redraw is censored as
/// the campaign censored its row, another origin's break counted as a limit at its value.
/// `Ok(None)` where an origin has fewer than two breaks (no law to carry). Each origin's fit and
/// draws are those of its row in `origins.csv` ([`crate::strength::origins::OriginFit::strength`],
/// [`crate::strength::origins::OriginFit::draws`]): nothing is refitted.
fn origins_lifetime(origins: &crate::strength::origins::Origins, m: &Prepared, s: &DiscrepancyStudy) -> Result<Option<Vec<LifetimeBand>>> {
    if origins.fits.iter().any(|f| !f.shape.is_finite()) {
        return Ok(None);
    }
    let counts: Vec<f64> = s.impact.years.iter().map(|y| impacts_in(*y, s.impact.impacts_per_year)).collect();
    let horizons: Vec<crate::strength::Horizon> = counts.iter().map(|&n| crate::strength::Horizon::independent(n)).collect();
    let (mut point, mut draws) = (Vec::new(), Vec::new());
    for f in &origins.fits {
        let Some(fit) = f.strength.clone() else { return Ok(None) };
        let lm = LifetimeModel::new(&m.spec.key, &m.spec.label, m.spec.sphere(&m.data), s.impact.target, s.contact.averaging, fit, m.population.clone())?;
        let ln_sigma = lm.ln_impact_stress(s.impact.energy_fraction, s.impact.reference_velocity_m_s)?;
        point.push(lm.breakage(&lm.fit.estimate(), None, s.impact.energy_fraction, s.impact.reference_velocity_m_s, &counts)?);
        draws.push(
            f.draws
                .iter()
                .map(|p| {
                    let mut out = vec![0.0; counts.len()];
                    lm.breakage_into(p, None, ln_sigma, &horizons, &mut out);
                    out
                })
                .collect::<Vec<_>>(),
        );
    }
    let a = 0.05;
    Ok(Some(
        s.impact
            .years
            .iter()
            .enumerate()
            .map(|(c, &years)| {
                let per: Vec<f64> = (0..s.lifetime.bootstrap).map(|r| crate::strength::origins::combined(&draws.iter().map(|d| d[r][c]).collect::<Vec<_>>())).collect();
                let q = crate::stats::interpolated_quantiles(per, &[a, 1.0 - a]);
                LifetimeBand { years, estimate: crate::strength::origins::combined(&point.iter().map(|p| p[c]).collect::<Vec<_>>()), q05: q[0], q95: q[1] }
            })
            .collect(),
    ))
}

/// One material's inputs: its study entry, crush data, sample and population.
struct Prepared {
    spec: MaterialSpec,
    data: CrushData,
    sample: Sample,
    population: crate::strength::Population,
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
        // (A two-population law draws its own strengths below; the rows only carry the factors.)
        let ln_scale: Vec<f64> = (0..n0).map(|i| if model.law.is_some() { model.reg.mu } else { model.reg.ln_scale(&d, i) }).collect();
        for (ni, &n) in p.particles.iter().enumerate() {
            let hits: Vec<(bool, bool)> = (0..p.replicates)
                .into_par_iter()
                .map(|r| {
                    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed ^ 0x9077_E400);
                    rng.set_stream(((si * 64 + ni) * 100_000 + r) as u64 + 1);
                    let (rows_drawn, mut strength): (Vec<usize>, Vec<f64>) = draw_rows(&ln_scale, |i| if model.law.is_some() { model.reg.shape() } else { 1.0 / model.reg.b_at(&d, i) }, n, &mut rng).into_iter().map(|(i, ln_s)| (i, ln_s.exp())).unzip();
                    // A two-population law: its own draws at each drawn row's scale shift.
                    if let Some(law) = &model.law {
                        strength = rows_drawn.iter().map(|&i| law.sample(&mut rng) * law.shift(&model.columns, i).exp()).collect();
                    }
                    let covariates = sample.covariates.iter().map(|(k, v)| (k.clone(), rows_drawn.iter().map(|&i| v[i]).collect())).collect();
                    // Each drawn particle censored as its row was (the campaign's rig limit, its classes).
                    let strength = sample.strength.rows(&rows_drawn).view().censor(strength, &mut rng);
                    let synthetic = Sample { source: format!("power replicate {r}"), strength, covariates, levels: sample.levels.iter().map(|(k, v)| (k.clone(), rows_drawn.iter().map(|&i| v[i].clone()).collect())).collect(), factors: sample.factors.clone(), particles: sample.particles, populations: sample.populations.clone() };
                    let s = NamingSettings { bootstrap: p.bootstrap, seed: settings.seed ^ (r as u64 + 1), ..settings.clone() };
                    let named = names(&synthetic, &s).unwrap_or_default();
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

/// Runs the study.
pub fn run_discrepancy(loaded: &StudyFile, s: &DiscrepancyStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    // Inputs first: every bad-input error before anything is written.
    let mut inputs = Vec::new();
    if loaded.path.is_file() {
        inputs.push(InputFile::hash(&loaded.path)?);
    }
    let mut prepared = Vec::new();
    for (k, m) in s.material.iter().enumerate() {
        let data = m.read_data(&loaded.path, k)?;
        inputs.extend(InputFile::read(&data.path, &data.provenance)?);
        let sample = sample_of(&data, &m.elastic, &s.contact)?;
        validate(&sample)?;
        let population = crate::strength::Population::of_material(m, prepared.len(), &data, &loaded.path, s.seed)?;
        // Tests at several temperatures can name temperature softening, whose lifetime is at a
        // temperature the study must name (the tests' mixture is no plant's).
        let tested: Vec<f64> = data.records.iter().filter_map(|r| r.temperature_c).collect();
        if tested.iter().any(|t| *t != tested[0]) && s.settings().candidates.contains(&crate::strength::Effect::Temperature) && !population.temperature_named() {
            return Err(Error::config(
                loaded.path.display().to_string(),
                format!("material[{k}].predict.temperature_c"),
                format!("`{}` was tested at {}: the loop may name temperature softening, and the lifetime after it must be at a temperature the study names (the operating temperature, °C): predict = {{ temperature_c = 800 }}", m.key, crate::intake::observed::describe_temperatures(&tested)),
            ));
        }
        prepared.push(Prepared { spec: m.clone(), data, sample, population });
    }
    let mut specimens = Vec::new();
    for (k, m) in s.strength.iter().enumerate() {
        let origin = crate::intake::MapOrigin { file: loaded.path.display().to_string(), key: format!("strength[{k}].data") };
        let mut read = crate::strength::specimens::read_specimens_with_origins(&m.data.resolved(&loaded.path), m.size.as_ref(), &m.factors, m.origin.as_deref(), &origin)?;
        read.sample.populations = m.offered();
        inputs.extend(InputFile::read(&read.path, &read.provenance)?);
        validate(&read.sample)?;
        specimens.push((m.clone(), read));
    }
    let settings = s.settings();
    let power_runs = if s.power.replicates > 0 { s.power.particles.len() * s.power.replicates * 2 } else { 0 };
    let pb = progress_bar((prepared.len() * (2 + power_runs) + specimens.len() * (1 + power_runs)) as u64, opts.progress, crate::runkit::PROGRESS_COUNT);
    let mut results = Vec::new();
    for (k, m) in prepared.into_iter().enumerate() {
        pb.set_message(format!("{}: naming loop", m.spec.label));
        let material_settings = NamingSettings { seed: s.seed.wrapping_add(7919 * k as u64), ..settings.clone() };
        let outcome = analyse(&m.sample, &material_settings, true)?;
        pb.inc(1);
        pb.set_message(format!("{}: lifetime before/after", m.spec.label));
        // Nothing named: the final model is the base model, with the same bands (not a second
        // bootstrap of the same model, whose bands would differ by their draws alone).
        let before = lifetime_bands(&outcome.before().model, &m.sample, &m, s, material_settings.seed ^ 0x11FE)?;
        let after = if outcome.named.is_empty() { before.clone() } else { lifetime_bands(&outcome.after().model, &m.sample, &m, s, material_settings.seed ^ 0x11FF)? };
        let lifetime = vec![("before".to_string(), before), ("after".to_string(), after)];
        pb.inc(1);
        let power = if s.power.replicates > 0 {
            pb.set_message(format!("{}: detection power", m.spec.label));
            power_study(&m.sample, &outcome, &material_settings, &s.power, &|| pb.inc(1))
        } else {
            Vec::new()
        };
        // Known failure origins: each origin's law, the shared-modulus test, and the lifetime with
        // every origin's law acting.
        let origins = match &m.spec.origin {
            Some(column) => Some(crate::strength::origins::analyse(m.sample.strength.view(), &m.data.origins, column, crate::strength::Uncertainty::Bootstrap, s.lifetime.bootstrap, material_settings.seed ^ ORIGINS_SEED)?),
            None => None,
        };
        let mut lifetime = lifetime;
        // Each origin's law pools the tests' temperatures (no temperature term enters it): no
        // lifetime at one temperature follows from laws of tests at several.
        let one_temperature = m.data.records.windows(2).all(|w| w[0].temperature_c == w[1].temperature_c);
        if let Some(o) = &origins
            && one_temperature
            && let Some(bands) = origins_lifetime(o, &m, s)?
        {
            lifetime.push(("origins".to_string(), bands));
        }
        let ids = m.data.records.iter().map(|r| r.id.clone()).collect();
        let temperatures_c = m.data.records.iter().filter_map(|r| r.temperature_c).collect();
        let failure_origins = m.data.origins.clone();
        results.push(MaterialResult { key: m.spec.key.clone(), label: m.spec.label.clone(), path: m.data.path.clone(), ids, crush: Some(m.spec), sample: m.sample, outcome, lifetime, power, temperatures_c, origins, failure_origins, read_notes: m.data.provenance.summary_notes() });
    }
    for (j, (set, read)) in specimens.into_iter().enumerate() {
        let k = s.material.len() + j;
        pb.set_message(format!("{}: naming loop", set.label));
        let material_settings = NamingSettings { seed: s.seed.wrapping_add(7919 * k as u64), ..settings.clone() };
        let outcome = analyse(&read.sample, &material_settings, true)?;
        pb.inc(1);
        let power = if s.power.replicates > 0 {
            pb.set_message(format!("{}: detection power", set.label));
            power_study(&read.sample, &outcome, &material_settings, &s.power, &|| pb.inc(1))
        } else {
            Vec::new()
        };
        let origins = match &set.origin {
            Some(column) => Some(crate::strength::origins::analyse(read.sample.strength.view(), &read.origins, column, crate::strength::Uncertainty::Bootstrap, s.lifetime.bootstrap, material_settings.seed ^ ORIGINS_SEED)?),
            None => None,
        };
        results.push(MaterialResult { key: set.key.clone(), label: set.label.clone(), path: read.path, ids: read.ids, crush: None, sample: read.sample, outcome, lifetime: Vec::new(), power, temperatures_c: read.temperatures_c, origins, failure_origins: read.origins, read_notes: read.provenance.summary_notes() });
    }

    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;
    write_tables(&mut dir, &results)?;
    let verdict = verdict_json(loaded, s, &results);
    let json = serde_json::to_string_pretty(&verdict).map_err(|e| Error::numerical("verdict.json", e.to_string()))?;
    dir.write_bytes("verdict.json", json.as_bytes())?;
    let headlines: Vec<String> = results.iter().map(headline).collect();
    // A material's tests pooled across several temperatures without a temperature term, and
    // recorded factors that coincide with the test temperature.
    let mut warnings: Vec<String> = results
        .iter()
        .flat_map(|r| crate::lifetime::tested::warnings(&[crate::lifetime::tested::Tested { label: &r.label, temperatures_c: &r.temperatures_c, temperature_term: r.outcome.after().model.effects.contains(&crate::strength::Effect::Temperature) }]))
        .collect();
    for r in results.iter().filter(|r| r.origins.is_some() && r.temperatures_c.windows(2).any(|w| w[0] != w[1])) {
        warnings.push(format!("{}: each failure origin's law pools the tests at {} without a temperature term (the naming loop's effects do not enter the origins' laws), so no lifetime with every origin acting is computed", r.label, crate::intake::observed::describe_temperatures(&r.temperatures_c)));
    }
    let crushed: Vec<crate::lifetime::tested::Tested> = results.iter().filter(|r| r.crush.is_some()).map(|r| crate::lifetime::tested::Tested { label: &r.label, temperatures_c: &r.temperatures_c, temperature_term: r.outcome.after().model.effects.contains(&crate::strength::Effect::Temperature) }).collect();
    warnings.extend(crate::lifetime::tested::side_by_side(&crushed));
    for r in &results {
        for (name, levels) in &r.sample.levels {
            warnings.extend(crate::lifetime::tested::confounded(&r.label, name, levels, &r.temperatures_c));
        }
    }
    for w in &warnings {
        crate::intake::warn(w);
    }
    dir.write_bytes("summary.md", crate::lifetime::tested::with_warnings(&summary(s, &results), &warnings).as_bytes())?;
    pb.set_message("figures");
    let mut failures = Vec::new();
    let rendered = crate::report::discrepancy::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    let mut evaluations = BTreeMap::new();
    evaluations.insert("naming_bootstrap_replicates".to_string(), results.iter().map(|r| r.outcome.stages.iter().map(|st| st.replicates as u64).sum::<u64>()).sum());
    evaluations.insert("power_datasets".to_string(), results.iter().map(|r| r.power.iter().map(|p| p.replicates as u64).sum::<u64>()).sum());
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines })
}

//! The lifetime study (`kind = "lifetime"`): the deliverable's §6 chain for several materials —
//! its schema ([`LifetimeStudy`], [`validate_lifetime`]) and its run into the report directory
//! ([`run_lifetime`]).
//!
//! A lifetime study ([`run_lifetime`]) does, per material:
//! 1. read and validate the crush data;
//! 2. Hertz contact at the force at break with R = d/2 → a, δ, p0, σ_max, σ̄ (`particles.csv`);
//! 3. Weibull MLE of σ̄, C1239 unbiasing and pivotal bounds, Fisher (log-Wald) bounds
//!    (`weibull_fits.csv`), probability-plot points and the CDF with its pivotal band. Where
//!    particles did not break by the rig's limit (or broke within a force class) the sample is
//!    censored: the MLE is the censored one, the bounds and band come from the parametric
//!    bootstrap that censors each redraw as the campaign did (in pivotal form), the modulus is
//!    unbiased by those refits, the Fisher bounds from the censored likelihood's information,
//!    the plotting positions from the Kaplan–Meier/Turnbull estimate (censored points marked);
//!    `weibull_fits.csv` says which (`bound_method`, `unbiasing`);
//! 4. power-law trend of σ̄ with diameter (`size_trend.csv`);
//! 5. the radial stress profile of the median particle (`stress_profile*.csv`);
//! 6. the strength model of the `[strength]` section (the deliverable's by default, or explicit
//!    effects, or `"diagnosed"`) fitted to the crush data, with its parameters' estimates and
//!    90 % ranges (`strength_fits.csv`);
//! 7. its [`LifetimeChain`] over the velocity grid through `Simulator::simulate_batch`
//!    (`impact_curves.csv`, `breakage_curves.csv`; population averages) and the force–time
//!    history at the reference velocity (`force_time.csv`);
//! 8. the population's breaking probability after each horizon at the reference velocity,
//!    with the band of the model's joint draws (`lifetime_summary.csv`).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::contact::ContactState;
use crate::data::CrushData;
use crate::error::{Error, Result};
use crate::io::InputFile;
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::schema::{ContactOptions, FigureOptions, ImpactOptions, MaterialSpec, StudyFile, check, elastic};
use crate::strength::{LifetimeChain, LifetimeModel, ParameterSummary, Params, StrengthFit, contact_at_break, sample_of, summarise};
use crate::weibull::{FisherBounds, PivotalBounds, Weibull, WeibullFit, fisher_bounds, fit_mle, simulate_pivotal};

mod tables;
use tables::*;

/// Which modulus estimate drives predictions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeEstimate {
    /// The maximum-likelihood m̂ (biased high for small N).
    Mle,
    /// C1239's unbiased UF(N)·m̂ (default: conservative in the lower tail).
    Unbiased,
}

/// Weibull options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WeibullOptions {
    /// Two-sided confidence level of bounds and bands (default 0.90, as C1239).
    pub confidence: f64,
    /// Monte Carlo replicates of the pivotal simulation (default 10 000).
    pub pivotal_samples: usize,
    /// Modulus used for predictions (default `unbiased`).
    pub shape_estimate: ShapeEstimate,
}

impl Default for WeibullOptions {
    fn default() -> Self {
        WeibullOptions { confidence: 0.90, pivotal_samples: 10_000, shape_estimate: ShapeEstimate::Unbiased }
    }
}

/// A lifetime study (kind = "lifetime"): the deliverable's §6 chain for several materials.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LifetimeStudy {
    /// Study kind, `lifetime`.
    pub kind: String,
    /// Seed of every random draw of the run.
    pub seed: u64,
    /// Crush contact.
    #[serde(default)]
    pub contact: ContactOptions,
    /// Impacts.
    #[serde(default)]
    pub impact: ImpactOptions,
    /// Weibull statistics (ASTM C1239 analysis of σ̄ at break).
    #[serde(default)]
    pub weibull: WeibullOptions,
    /// The strength model of the predictions (default: the deliverable's, no effects).
    #[serde(default)]
    pub strength: crate::strength::StrengthOptions,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
    /// Particle types, at least one.
    pub material: Vec<MaterialSpec>,
}

/// Validates every option of a lifetime study.
pub fn validate_lifetime(s: &LifetimeStudy, file: &str) -> Result<()> {
    for (i, m) in s.material.iter().enumerate() {
        m.one_law(file, i, "lifetime study")?;
    }
    elastic(file, "contact.platen", &s.contact.platen)?;
    s.contact.averaging.validate(file, "contact.averaging")?;
    s.strength.validate(file, &s.contact.averaging)?;
    let i = &s.impact;
    elastic(file, "impact.target", &i.target)?;
    check(
        file,
        "impact.energy_fraction",
        i.energy_fraction > 0.0 && i.energy_fraction <= 1.0,
        format!("the elastic energy fraction η must lie in (0, 1] (got {})", i.energy_fraction),
    )?;
    let vmax = crate::lifetime::MAX_VELOCITY;
    check(
        file,
        "impact.velocity_max_m_s",
        i.velocity_max_m_s > 0.0 && i.velocity_max_m_s <= vmax,
        format!("must lie in (0, {vmax}] m/s (got {})", i.velocity_max_m_s),
    )?;
    check(
        file,
        "impact.velocity_points",
        (2..=100_000).contains(&i.velocity_points),
        format!("must lie in [2, 100000] (got {})", i.velocity_points),
    )?;
    check(
        file,
        "impact.impact_counts",
        !i.impact_counts.is_empty() && i.impact_counts.iter().all(|n| n.is_finite() && *n >= 1.0),
        format!("needs at least one count, each ≥ 1 (got {:?})", i.impact_counts),
    )?;
    check(
        file,
        "impact.impacts_per_year",
        i.impacts_per_year.is_finite() && i.impacts_per_year > 0.0,
        format!("must be > 0 (got {})", i.impacts_per_year),
    )?;
    check(
        file,
        "impact.years",
        !i.years.is_empty() && i.years.iter().all(|y| y.is_finite() && *y > 0.0),
        format!("needs at least one horizon, each > 0 (got {:?})", i.years),
    )?;
    check(
        file,
        "impact.reference_velocity_m_s",
        i.reference_velocity_m_s > 0.0 && i.reference_velocity_m_s <= vmax,
        format!("must lie in (0, {vmax}] m/s (got {})", i.reference_velocity_m_s),
    )?;
    let w = &s.weibull;
    check(
        file,
        "weibull.confidence",
        w.confidence > 0.0 && w.confidence < 1.0,
        format!("must lie in (0, 1) (got {})", w.confidence),
    )?;
    check(
        file,
        "weibull.pivotal_samples",
        (1000..=10_000_000).contains(&w.pivotal_samples),
        format!("must lie in [1000, 10000000] (got {})", w.pivotal_samples),
    )?;
    check(
        file,
        "figures.width_cm",
        s.figures.width_cm >= 5.0 && s.figures.width_cm <= 40.0,
        format!("must lie in [5, 40] cm (got {})", s.figures.width_cm),
    )?;
    check(file, "material", !s.material.is_empty(), "at least one [[material]] is required".into())?;
    for (k, m) in s.material.iter().enumerate() {
        let key = |f: &str| format!("material[{k}].{f}");
        check(
            file,
            &key("key"),
            !m.key.is_empty() && m.key.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'),
            format!("must be non-empty lowercase letters, digits or _ (got \"{}\")", m.key),
        )?;
        check(
            file,
            &key("key"),
            !s.material[..k].iter().any(|o| o.key == m.key),
            format!("duplicate material key \"{}\"", m.key),
        )?;
        elastic(file, &key("elastic"), &m.elastic)?;
        check(
            file,
            &key("density_kg_m3"),
            m.density_kg_m3.is_finite() && m.density_kg_m3 > 0.0,
            format!("must be > 0 (got {})", m.density_kg_m3),
        )?;
        if let Some(d) = m.impact_diameter_m {
            check(
                file,
                &key("impact_diameter_m"),
                crate::data::DIAMETER.contains(d),
                format!("must lie in {} (got {d})", crate::data::DIAMETER.shown),
            )?;
        }
    }
    Ok(())
}

/// Per-material results needed by several tables.
struct MaterialRun {
    key: String,
    label: String,
    data: CrushData,
    /// Hertz contact state at the force at break, per particle (R = d/2).
    at_break: Vec<ContactState>,
    /// σ̄ at break (Pa), per particle: `at_break[i].mean_tensile`, projected once because the
    /// Weibull fit, bounds and plots take a slice.
    sigma_bar: Vec<f64>,
    /// σ̄ as observations: what each particle's row says (broke at it, did not break by it, …).
    observed: crate::obs::Observations,
    /// How the bounds and the unbiasing factor were obtained (`weibull_fits.csv`).
    bound_method: &'static str,
    /// How the modulus was unbiased.
    unbiasing: &'static str,
    fit: WeibullFit,
    pivotal: PivotalBounds,
    fisher: FisherBounds,
    /// The Weibull law of σ̄ of the C1239 analysis (no effects; `shape_estimate` applied).
    strength: Weibull,
    /// Its pivotal draws (the CDF band).
    draws: Vec<Weibull>,
    /// The strength model's parameters used for predictions (`shape_estimate` applied).
    params: Params,
    /// The strength model's parameters: estimates and 90 % ranges of the draws.
    summary: Vec<ParameterSummary>,
    /// The strength model as a Simulator.
    chain: LifetimeChain,
}

/// `bound_method` of a complete sample.
const PIVOTAL_BOUNDS: &str = "pivotal Monte Carlo (Thoman-Bain-Antle, ASTM C1239)";
/// `bound_method` of a censored sample.
const CENSORED_BOUNDS: &str = "parametric bootstrap censoring each redraw as the campaign did, in pivotal form (C1239's pivots are for complete samples)";
/// `unbiasing` of a complete sample.
const C1239_UNBIASING: &str = "ASTM C1239 unbiasing factor (complete sample)";
/// `unbiasing` of a censored sample.
const CENSORED_UNBIASING: &str = "bias factor of the censored bootstrap refits (C1239's factor is for complete samples)";

/// Seed of the pivotal simulation for sample size n (depends on the study seed and n only).
fn pivotal_seed(seed: u64, n: usize) -> u64 {
    seed ^ (n as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// Runs a lifetime study.
pub fn run_lifetime(loaded: &StudyFile, s: &LifetimeStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let pb = progress_bar(s.material.len() as u64 * 3 + 2, opts.progress, "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} {msg}");

    // 1. Inputs first: every bad-input error happens before anything is written.
    let mut inputs = vec![InputFile::hash(&loaded.path)?];
    let mut datasets = Vec::new();
    for (k, m) in s.material.iter().enumerate() {
        pb.set_message(format!("reading {}", m.data.file.display()));
        let data = m.read_data(&loaded.path, k)?;
        inputs.extend(InputFile::read(&data.path, &data.provenance)?);
        datasets.push(data);
    }

    // 2–3. Contact at break, Weibull fits, pivotal bounds; the strength model.
    let mut evaluations: BTreeMap<String, u64> = BTreeMap::new();
    let mut runs = Vec::new();
    let mut samples = Vec::new();
    for (index, (m, data)) in s.material.iter().zip(datasets).enumerate() {
        pb.set_message(format!("{}: contact stresses and Weibull fit", m.label));
        let at_break = contact_at_break(&data, &m.elastic, &s.contact)?;
        let sigma_bar: Vec<f64> = at_break.iter().map(|c| c.mean_tensile).collect();
        let sample = sample_of(&data, &m.elastic, &s.contact)?;
        let failed = |e: Error| Error::data_file(&data.path, "all rows", format!("Weibull fit of the average tensile stress failed: {e}"));
        // The censored branch's no-effect fit, kept for the strength model when it has no effects.
        let mut base_fit = None;
        let (fit, pivotal, fisher, draws, bound_method, unbiasing) = if sample.strength.view().complete() {
            let fit = fit_mle(&sigma_bar).map_err(failed)?;
            let piv = simulate_pivotal(fit.n, s.weibull.pivotal_samples, pivotal_seed(s.seed, fit.n))?;
            *evaluations.entry("weibull_pivotal_fits".into()).or_default() += s.weibull.pivotal_samples as u64;
            let pivotal = piv.bounds(&fit, s.weibull.confidence)?;
            let fisher = fisher_bounds(&fit, &sigma_bar, s.weibull.confidence)?;
            let draws = piv.draws(&fit);
            (fit, pivotal, fisher, draws, PIVOTAL_BOUNDS, C1239_UNBIASING)
        } else {
            // A censored sample (module docs): the deliverable's two-parameter law fitted with
            // what each row says, bounds from the bootstrap that censors as the campaign did.
            let base = StrengthFit::new(&sample, &[], s.strength.naming.gamma, &m.key).map_err(failed)?;
            let reg = &base.model.reg;
            let mle = Weibull::new(reg.shape(), reg.mu.exp())?;
            let fit = WeibullFit { n: sample.strength.len(), mle, log_likelihood: reg.loglik };
            let boot = base.draws(crate::strength::Uncertainty::Bootstrap, s.weibull.pivotal_samples, pivotal_seed(s.seed, fit.n))?;
            *evaluations.entry("weibull_censored_bootstrap_fits".into()).or_default() += s.weibull.pivotal_samples as u64;
            let draws: Vec<Weibull> = boot.iter().map(|p| Weibull { shape: p.shape, scale: p.mu.exp() }).collect();
            let a = 0.5 * (1.0 - s.weibull.confidence);
            let q = |v: Vec<f64>| crate::stats::interpolated_quantiles(v, &[a, 1.0 - a]);
            let (qm, qs) = (q(draws.iter().map(|w| w.shape).collect()), q(draws.iter().map(|w| w.scale).collect()));
            let uf = base.unbiased_shape(&boot) / mle.shape;
            let pivotal = PivotalBounds { unbiasing_factor: uf, shape_unbiased: uf * mle.shape, confidence: s.weibull.confidence, shape: (qm[0], qm[1]), scale: (qs[0], qs[1]) };
            let fisher = FisherBounds::from_log_cov(mle, reg.location_scale_cov, s.weibull.confidence).map_err(failed)?;
            base_fit = Some(base);
            (fit, pivotal, fisher, draws, CENSORED_BOUNDS, CENSORED_UNBIASING)
        };
        pb.inc(1);
        let shape = match s.weibull.shape_estimate {
            ShapeEstimate::Mle => fit.mle.shape,
            ShapeEstimate::Unbiased => pivotal.shape_unbiased,
        };
        let strength = Weibull::new(shape, fit.mle.scale)?;
        // The strength model: the deliverable's unless the study names effects.
        let naming = crate::strength::NamingSettings { seed: s.seed.wrapping_add(7919 * index as u64), ..s.strength.naming.clone() };
        let effects = crate::discrepancy::specs::resolve(&s.strength.effects, &sample, &naming)?;
        let sfit = match base_fit {
            Some(base) if effects.is_empty() => base,
            _ => StrengthFit::new(&sample, &effects, s.strength.naming.gamma, &m.key)?,
        };
        samples.push(sample.clone());
        let population = crate::strength::Population::of_material(m, index, &data, &loaded.path, s.seed)?;
        let model = LifetimeModel::new(&m.key, &m.label, m.sphere(&data), s.impact.target, s.contact.averaging, sfit, population).map_err(|e| e.in_study(&loaded.path.display().to_string(), &format!("material[{index}]")))?;
        let seed = pivotal_seed(s.seed, fit.n) ^ 0x5713;
        let (params_draws, _) = model.draws(s.strength.uncertainty, s.strength.draws, seed)?;
        *evaluations.entry("strength_draws".into()).or_default() += s.strength.draws as u64;
        let mut params = model.fit.estimate();
        if s.weibull.shape_estimate == ShapeEstimate::Unbiased {
            // C1239's unbiased modulus: without effects its own simulation (the same pivots as
            // the bounds), with effects the model's draws' bias factor.
            params.shape = if effects.is_empty() { shape } else { model.fit.unbiased_shape(&params_draws) };
        }
        let summary = summarise(&model.fit, &params_draws);
        pb.inc(1);
        // The curves' counts, with N = 1 for the single-impact probability.
        let mut counts = vec![1.0];
        counts.extend(s.impact.impact_counts.iter().copied().filter(|n| *n != 1.0));
        let chain = LifetimeChain::new(model, &counts, (params, s.impact.energy_fraction, s.impact.reference_velocity_m_s))?;
        runs.push(MaterialRun {
            key: m.key.clone(),
            label: m.label.clone(),
            data,
            at_break,
            sigma_bar,
            observed: sample.strength.clone(),
            bound_method,
            unbiasing,
            fit,
            pivotal,
            fisher,
            strength,
            draws,
            params,
            summary,
            chain,
        });
    }

    if let Some(e) = crate::discrepancy::specs::unclaimed(&s.strength.effects, &samples.iter().collect::<Vec<_>>()) {
        return Err(Error::config(loaded.path.display().to_string(), "strength.effects", format!("`{}`: no material declares the factor `{}` in its `factors`", e.name(), e.covariate())));
    }

    // Tables into a temporary report directory.
    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;
    write_particles(&mut dir, &runs)?;
    write_weibull(&mut dir, &runs, s)?;
    write_size_trend(&mut dir, &runs)?;
    write_stress_profile(&mut dir, &runs, s)?;
    write_strength_fits(&mut dir, &runs)?;
    let mut failures = Vec::new();
    pb.set_message("impact and breakage curves");
    for n in write_curves(&mut dir, &runs, s, &mut failures)? {
        *evaluations.entry("lifetime_chain".into()).or_default() += n;
        pb.inc(1);
    }
    write_force_time(&mut dir, &runs, s)?;
    let tables::Summary { headlines, attrition, answer } = write_summary(&mut dir, &runs, s)?;
    // At which temperature each material was tested, and what the lifetimes hold at.
    let temperatures: Vec<Vec<f64>> = runs.iter().map(|r| r.data.records.iter().filter_map(|x| x.temperature_c).collect()).collect();
    let tested: Vec<crate::lifetime::tested::Tested> = runs
        .iter()
        .zip(&temperatures)
        .map(|(r, t)| crate::lifetime::tested::Tested { label: &r.label, temperatures_c: t, temperature_term: r.chain.model().fit.effects().contains(&crate::strength::Effect::Temperature) })
        .collect();
    let predicted: Vec<Option<String>> = runs.iter().map(|r| r.chain.model().population.predicted_temperature()).collect();
    let mut warnings = crate::lifetime::tested::warnings(&tested);
    warnings.extend(tested.iter().zip(&predicted).filter_map(|(t, p)| crate::lifetime::tested::unused_prediction(t, p.as_deref())));
    for ((t, sample), temps) in tested.iter().zip(&samples).zip(&temperatures) {
        for (name, levels) in &sample.levels {
            warnings.extend(crate::lifetime::tested::confounded(t.label, name, levels, temps));
        }
    }
    for w in &warnings {
        crate::intake::warn(w);
    }
    let lead = crate::lifetime::tested::paragraph(&tested, &crate::lifetime::tested::named_or_tests(&tested, &predicted));
    let md = crate::runkit::headline_summary("Breaking probability after repeated impacts", &headlines).replacen("\n## Headline", &format!("\n{lead}\n\n{answer}## Headline"), 1);
    let notes: Vec<(&str, Vec<String>)> = runs.iter().map(|r| (r.label.as_str(), r.data.provenance.summary_notes())).collect();
    let md = crate::lifetime::tested::with_warnings(&md, &warnings) + &attrition + &crate::lifetime::tested::read_section(&notes);
    dir.write_bytes("summary.md", md.as_bytes())?;
    pb.inc(1);

    // Figures from the tables just written.
    pb.set_message("figures");
    let rendered = crate::report::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    pb.inc(1);

    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let run = RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings };
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, run)?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schema::parse_toml;
    use std::path::Path;

    const MIN: &str = r#"
kind = "lifetime"
seed = 1
[[material]]
key = "a"
label = "A"
data = "a.csv"
elastic = { youngs_modulus_pa = 112e9, poisson_ratio = 0.25 }
density_kg_m3 = 3600
"#;

    #[test]
    fn defaults_fill_in() {
        let s: LifetimeStudy = parse_toml(Path::new("s.toml"), MIN).unwrap();
        validate_lifetime(&s, "s.toml").unwrap();
        assert_eq!(s.impact.energy_fraction, 0.1);
        assert_eq!(s.impact.impact_counts, vec![1.0, 100.0, 2100.0, 7300.0]);
        assert_eq!(s.weibull.shape_estimate, ShapeEstimate::Unbiased);
    }

    #[test]
    fn unknown_keys_name_the_line() {
        let text = MIN.replace("seed = 1", "seed = 1\nsede = 2");
        let e = parse_toml::<LifetimeStudy>(Path::new("s.toml"), &text).unwrap_err().to_string();
        assert!(e.contains("s.toml") && e.contains("line 4") && e.contains("sede"), "{e}");
    }

    #[test]
    fn impossible_options_are_rejected() {
        let text = MIN.replace("seed = 1", "seed = 1\n[impact]\nenergy_fraction = 0.0");
        let s: LifetimeStudy = parse_toml(Path::new("s.toml"), &text).unwrap();
        let e = validate_lifetime(&s, "s.toml").unwrap_err().to_string();
        assert!(e.contains("impact.energy_fraction") && e.contains("(0, 1]"), "{e}");
    }
}

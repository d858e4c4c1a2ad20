//! The lifetime study (`kind = "lifetime"`): the deliverable's §6 chain for several materials —
//! its schema ([`LifetimeStudy`], [`validate_lifetime`]) and its run into the report directory
//! ([`run_lifetime`]).
//!
//! A lifetime study ([`run_lifetime`]) does, per material:
//! 1. read and validate the crush data;
//! 2. Hertz contact at the force at break with R = d/2 → a, δ, p0, σ_max, σ̄ (`particles.csv`);
//! 3. Weibull MLE of σ̄, C1239 unbiasing and pivotal bounds, Fisher (log-Wald) bounds
//!    (`weibull_fits.csv`), probability-plot points and the CDF with its pivotal band;
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

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::contact::{ContactState, ContactStress, Hertz};
use crate::data::{CrushData, read_crush};
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
use crate::lifetime::impacts_in;
use crate::model::Simulator;
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::schema::{ContactOptions, FigureOptions, ImpactOptions, MaterialSpec, StudyFile, check, elastic};
use crate::stats::fit_line;
use crate::strength::{LifetimeChain, LifetimeModel, ParameterSummary, Params, StrengthFit, contact_at_break, sample_of, summarise};
use crate::weibull::{FisherBounds, PivotalBounds, Weibull, WeibullFit, fisher_bounds, fit_mle, probability_plot, simulate_pivotal, sorted_quantile};

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
                d.is_finite() && d > 0.0 && d <= 0.1,
                format!("must be > 0 and ≤ 0.1 m (got {d})"),
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
    for m in &s.material {
        let path = loaded.resolve(&m.data);
        pb.set_message(format!("reading {}", path.display()));
        let data = read_crush(&path)?;
        inputs.push(InputFile::hash(&path)?);
        datasets.push(data);
    }

    // 2–3. Contact at break, Weibull fits, pivotal bounds; the strength model.
    let mut evaluations: BTreeMap<String, u64> = BTreeMap::new();
    let mut runs = Vec::new();
    for (index, (m, data)) in s.material.iter().zip(datasets).enumerate() {
        pb.set_message(format!("{}: contact stresses and Weibull fit", m.label));
        let at_break = contact_at_break(&data.records, &m.elastic, &s.contact)?;
        let sigma_bar: Vec<f64> = at_break.iter().map(|c| c.mean_tensile).collect();
        let fit = fit_mle(&sigma_bar).map_err(|e| {
            Error::data_file(&data.path, "all rows", format!("Weibull fit of the average tensile stress failed: {e}"))
        })?;
        pb.inc(1);
        let piv = simulate_pivotal(fit.n, s.weibull.pivotal_samples, pivotal_seed(s.seed, fit.n))?;
        *evaluations.entry("weibull_pivotal_fits".into()).or_default() += s.weibull.pivotal_samples as u64;
        let pivotal = piv.bounds(&fit, s.weibull.confidence)?;
        let fisher = fisher_bounds(&fit, &sigma_bar, s.weibull.confidence)?;
        let shape = match s.weibull.shape_estimate {
            ShapeEstimate::Mle => fit.mle.shape,
            ShapeEstimate::Unbiased => pivotal.shape_unbiased,
        };
        let strength = Weibull::new(shape, fit.mle.scale)?;
        let draws = piv.draws(&fit);
        // The strength model: the deliverable's unless the study names effects.
        let sample = sample_of(&data, &m.elastic, &s.contact)?;
        let naming = crate::strength::NamingSettings { seed: s.seed.wrapping_add(7919 * index as u64), ..s.strength.naming.clone() };
        let effects = crate::discrepancy::workflow::resolve(&s.strength.effects, &sample, &naming)?;
        let sfit = StrengthFit::new(&sample, &effects, s.strength.naming.gamma, &m.key)?;
        let population = crate::strength::Population::of_material(m, index, &data, &loaded.path, s.seed)?;
        let model = LifetimeModel::new(&m.key, &m.label, m.sphere(&data), s.impact.target, s.contact.averaging, sfit, population)?;
        let seed = pivotal_seed(s.seed, fit.n) ^ 0x5713;
        let (params_draws, _) = model.draws(s.strength.uncertainty, s.strength.draws, seed)?;
        *evaluations.entry("strength_draws".into()).or_default() += s.strength.draws as u64;
        let mut params = model.fit.estimate();
        if s.weibull.shape_estimate == ShapeEstimate::Unbiased {
            // C1239's unbiased modulus: without effects its own simulation (the same pivots as
            // the bounds), with effects 1/mean(m̂/m) over the model's pivotal draws.
            params.shape = if effects.is_empty() { shape } else { params.shape * params_draws.len() as f64 / params_draws.iter().map(|d| params.shape / d.shape).sum::<f64>() };
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

    // Tables into a temporary report directory.
    let mut dir = ReportDir::create(&opts.reports_root, &loaded.name)?;
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
    let headlines = write_summary(&mut dir, &runs, s)?;
    pb.inc(1);

    // Figures from the tables just written.
    pb.set_message("figures");
    let rendered = crate::report::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    pb.inc(1);

    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let run = RunRecord { inputs, seed: s.seed, clock, evaluations, failures };
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, run)?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines })
}

fn repeat(s: &str, n: usize) -> Vec<String> {
    vec![s.to_string(); n]
}

fn write_particles(dir: &mut ReportDir, runs: &[MaterialRun]) -> Result<()> {
    type Row<'a> = (&'a MaterialRun, &'a crate::data::CrushRecord, &'a ContactState);
    let rows: Vec<Row> = runs
        .iter()
        .flat_map(|run| run.data.records.iter().zip(&run.at_break).map(move |(r, c)| (run, r, c)))
        .collect();
    let text = |f: &dyn Fn(&Row) -> String| rows.iter().map(f).collect::<Vec<_>>();
    let num = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).collect::<Vec<_>>();
    let mut df = table(vec![
        scol("material_key", text(&|r| r.0.key.clone())),
        scol("material", text(&|r| r.0.label.clone())),
        scol("id", text(&|r| r.1.id.clone())),
        fcol("diameter_m", num(&|r| r.1.diameter_m)),
        fcol("crush_force_n", num(&|r| r.1.crush_force_n)),
        fcol("roundness", num(&|r| r.1.roundness.unwrap_or(f64::NAN))),
        fcol("sphericity", num(&|r| r.1.sphericity.unwrap_or(f64::NAN))),
        fcol("temperature_c", num(&|r| r.1.temperature_c.unwrap_or(f64::NAN))),
        fcol("contact_radius_m", num(&|r| r.2.radius)),
        fcol("approach_per_contact_m", num(&|r| r.2.approach)),
        fcol("peak_pressure_pa", num(&|r| r.2.peak_pressure)),
        fcol("max_tensile_pa", num(&|r| r.2.max_tensile)),
        fcol("sigma_bar_pa", num(&|r| r.2.mean_tensile)),
    ])?;
    dir.write_table("particles", &mut df)
}

fn write_weibull(dir: &mut ReportDir, runs: &[MaterialRun], s: &LifetimeStudy) -> Result<()> {
    let n = runs.len();
    let get = |f: &dyn Fn(&MaterialRun) -> f64| runs.iter().map(f).collect::<Vec<f64>>();
    let mut fits = table(vec![
        scol("material_key", runs.iter().map(|r| r.key.clone()).collect()),
        scol("material", runs.iter().map(|r| r.label.clone()).collect()),
        ucol("n", runs.iter().map(|r| r.fit.n as u64).collect()),
        fcol("shape_mle", get(&|r| r.fit.mle.shape)),
        fcol("unbiasing_factor", get(&|r| r.pivotal.unbiasing_factor)),
        fcol("shape_unbiased", get(&|r| r.pivotal.shape_unbiased)),
        fcol("shape_used", get(&|r| r.strength.shape)),
        fcol("scale_pa", get(&|r| r.fit.mle.scale)),
        fcol("confidence", get(&|r| r.pivotal.confidence)),
        fcol("shape_lower", get(&|r| r.pivotal.shape.0)),
        fcol("shape_upper", get(&|r| r.pivotal.shape.1)),
        fcol("scale_lower_pa", get(&|r| r.pivotal.scale.0)),
        fcol("scale_upper_pa", get(&|r| r.pivotal.scale.1)),
        scol("bound_method", repeat("pivotal Monte Carlo (Thoman-Bain-Antle, ASTM C1239)", n)),
        fcol("fisher_shape_se", get(&|r| r.fisher.shape_se)),
        fcol("fisher_scale_se_pa", get(&|r| r.fisher.scale_se)),
        fcol("fisher_shape_lower", get(&|r| r.fisher.shape.0)),
        fcol("fisher_shape_upper", get(&|r| r.fisher.shape.1)),
        fcol("fisher_scale_lower_pa", get(&|r| r.fisher.scale.0)),
        fcol("fisher_scale_upper_pa", get(&|r| r.fisher.scale.1)),
        fcol("log_likelihood", get(&|r| r.fit.log_likelihood)),
        scol("stress_measure", repeat(&s.contact.averaging.describe(), n)),
    ])?;
    dir.write_table("weibull_fits", &mut fits)?;

    // Probability-plot points.
    let (mut k, mut l, mut x, mut f) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for r in runs {
        for (xi, fi) in probability_plot(&r.sigma_bar) {
            k.push(r.key.clone());
            l.push(r.label.clone());
            x.push(xi);
            f.push(fi);
        }
    }
    let mut pts = table(vec![scol("material_key", k), scol("material", l), fcol("sigma_bar_pa", x), fcol("cdf_rank", f)])?;
    dir.write_table("weibull_points", &mut pts)?;

    // CDF curve with the pivotal band, on a common stress grid.
    let lo = 0.0;
    let hi = runs.iter().flat_map(|r| r.sigma_bar.iter()).cloned().fold(f64::MIN, f64::max) * 1.25;
    let grid: Vec<f64> = (0..201).map(|i| lo + (hi - lo) * i as f64 / 200.0).collect();
    let a = 0.5 * (1.0 - s.weibull.confidence);
    let (mut k, mut l, mut x, mut c, mut cl, mut cu) = (vec![], vec![], vec![], vec![], vec![], vec![]);
    for r in runs {
        let band: Vec<(f64, f64)> = grid
            .par_iter()
            .map(|&sig| {
                let mut v: Vec<f64> = r.draws.iter().map(|w| w.cdf(sig)).collect();
                v.sort_by(f64::total_cmp);
                (sorted_quantile(&v, a), sorted_quantile(&v, 1.0 - a))
            })
            .collect();
        for (&sig, b) in grid.iter().zip(band) {
            k.push(r.key.clone());
            l.push(r.label.clone());
            x.push(sig);
            c.push(r.strength.cdf(sig));
            cl.push(b.0);
            cu.push(b.1);
        }
    }
    let mut cdf = table(vec![
        scol("material_key", k),
        scol("material", l),
        fcol("sigma_pa", x),
        fcol("cdf", c),
        fcol("cdf_lower", cl),
        fcol("cdf_upper", cu),
    ])?;
    dir.write_table("weibull_cdf", &mut cdf)
}

fn write_size_trend(dir: &mut ReportDir, runs: &[MaterialRun]) -> Result<()> {
    // Power law σ̄ = e^c d^b: a straight line in log–log coordinates.
    let mut rows: Vec<[f64; 7]> = Vec::new();
    for r in runs {
        let d = r.data.diameters();
        let x: Vec<f64> = d.iter().map(|d| d.ln()).collect();
        let y: Vec<f64> = r.sigma_bar.iter().map(|s| s.ln()).collect();
        let f = fit_line(&x, &y)?;
        rows.push([
            f.slope,
            f.slope_se,
            f.intercept,
            f.r,
            f.p_value,
            d.iter().cloned().fold(f64::MAX, f64::min),
            d.iter().cloned().fold(f64::MIN, f64::max),
        ]);
    }
    let col = |i: usize| rows.iter().map(|r| r[i]).collect::<Vec<f64>>();
    let mut df = table(vec![
        scol("material_key", runs.iter().map(|r| r.key.clone()).collect()),
        scol("material", runs.iter().map(|r| r.label.clone()).collect()),
        fcol("exponent", col(0)),
        fcol("exponent_se", col(1)),
        fcol("ln_prefactor", col(2)),
        fcol("pearson_r_log", col(3)),
        fcol("p_value", col(4)),
        fcol("diameter_min_m", col(5)),
        fcol("diameter_max_m", col(6)),
    ])?;
    dir.write_table("size_trend", &mut df)
}

fn write_stress_profile(dir: &mut ReportDir, runs: &[MaterialRun], s: &LifetimeStudy) -> Result<()> {
    let (mut k, mut l, mut id, mut rr, mut ra, mut sr) = (vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut summary: Vec<(String, String, String, [f64; 7])> = Vec::new();
    for r in runs {
        // The particle whose σ̄ at break is the median (lower middle for even N).
        let mut idx: Vec<usize> = (0..r.sigma_bar.len()).collect();
        idx.sort_by(|&a, &b| r.sigma_bar[a].total_cmp(&r.sigma_bar[b]));
        let i = idx[(idx.len() - 1) / 2];
        let rec = &r.data.records[i];
        let radius = 0.5 * rec.diameter_m;
        let hertz = Hertz::sphere_on_flat(&r.chain.model().sphere.elastic, &s.contact.platen, radius);
        let cs = ContactStress::new(hertz, s.contact.averaging, radius);
        let state = cs.at_force(rec.crush_force_n)?;
        let a = state.radius;
        let l_out = s.contact.averaging.outer_limit(a, radius);
        let r_max = (1.5 * l_out).max(3.0 * a);
        for j in 0..=400 {
            let rv = r_max * j as f64 / 400.0;
            k.push(r.key.clone());
            l.push(r.label.clone());
            id.push(rec.id.clone());
            rr.push(rv);
            ra.push(rv / a);
            sr.push(cs.radial_stress_at(rec.crush_force_n, rv));
        }
        summary.push((
            r.key.clone(),
            r.label.clone(),
            rec.id.clone(),
            [rec.diameter_m, rec.crush_force_n, a, state.peak_pressure, state.mean_tensile, cs.zone.s0 * a, l_out],
        ));
    }
    let mut df = table(vec![
        scol("material_key", k),
        scol("material", l),
        scol("particle_id", id),
        fcol("r_m", rr),
        fcol("r_over_a", ra),
        fcol("sigma_r_pa", sr),
    ])?;
    dir.write_table("stress_profile", &mut df)?;
    let col = |i: usize| summary.iter().map(|s| s.3[i]).collect::<Vec<f64>>();
    let mut df = table(vec![
        scol("material_key", summary.iter().map(|s| s.0.clone()).collect()),
        scol("material", summary.iter().map(|s| s.1.clone()).collect()),
        scol("particle_id", summary.iter().map(|s| s.2.clone()).collect()),
        fcol("diameter_m", col(0)),
        fcol("crush_force_n", col(1)),
        fcol("contact_radius_m", col(2)),
        fcol("peak_pressure_pa", col(3)),
        fcol("sigma_bar_pa", col(4)),
        fcol("domain_start_m", col(5)),
        fcol("domain_end_m", col(6)),
    ])?;
    dir.write_table("stress_profile_summary", &mut df)
}

/// Impact and breakage curves of every material over the velocity grid, through the
/// Simulator interface (σ̄ and F_max of the reference sphere; P of the population); returns the
/// number of evaluations per material.
fn write_curves(
    dir: &mut ReportDir,
    runs: &[MaterialRun],
    s: &LifetimeStudy,
    failures: &mut Vec<String>,
) -> Result<Vec<u64>> {
    let np = s.impact.velocity_points;
    let velocities: Vec<f64> = (0..np).map(|i| s.impact.velocity_max_m_s * i as f64 / (np - 1) as f64).collect();
    let (mut ik, mut il, mut iv, mut ifm, mut isb, mut itc, mut ip) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let (mut bk, mut bl, mut bv, mut bn, mut bp) = (vec![], vec![], vec![], vec![], vec![]);
    let mut evaluations = Vec::new();
    for run in runs {
        let thetas: Vec<Vec<f64>> = velocities.iter().map(|&v| run.chain.theta(&run.params, s.impact.energy_fraction, v)).collect();
        let results = run.chain.simulate_batch(&thetas);
        evaluations.push(thetas.len() as u64);
        let impact = run.chain.model().impact(s.impact.energy_fraction);
        let mut ok = Vec::new();
        for ((t, r), &v) in thetas.iter().zip(results).zip(&velocities) {
            match r {
                Ok(y) => ok.push((v, y)),
                Err(e) => failures.push(format!("{}: θ = {t:?}: {e}", run.key)),
            }
        }
        if ok.is_empty() {
            return Err(Error::numerical("impact curves", format!("every evaluation failed for {}", run.key)));
        }
        for (v, y) in &ok {
            ik.push(run.key.clone());
            il.push(run.label.clone());
            iv.push(*v);
            ifm.push(y[0]);
            isb.push(y[1]);
            itc.push(if *v > 0.0 { impact.contact_time(*v) } else { f64::NAN });
            ip.push(y[2]); // counts()[0] is N = 1
        }
        for (ci, &c) in run.chain.counts().iter().enumerate().filter(|(_, c)| s.impact.impact_counts.contains(c)) {
            for (v, y) in &ok {
                bk.push(run.key.clone());
                bl.push(run.label.clone());
                bv.push(*v);
                bn.push(c);
                bp.push(y[2 + ci]);
            }
        }
    }
    let mut df = table(vec![
        scol("material_key", ik),
        scol("material", il),
        fcol("velocity_m_s", iv),
        fcol("f_max_n", ifm),
        fcol("sigma_bar_pa", isb),
        fcol("contact_time_s", itc),
        fcol("p_single", ip),
    ])?;
    dir.write_table("impact_curves", &mut df)?;
    let mut df = table(vec![
        scol("material_key", bk),
        scol("material", bl),
        fcol("velocity_m_s", bv),
        fcol("impacts", bn),
        fcol("p_break", bp),
    ])?;
    dir.write_table("breakage_curves", &mut df)?;
    Ok(evaluations)
}

fn write_force_time(dir: &mut ReportDir, runs: &[MaterialRun], s: &LifetimeStudy) -> Result<()> {
    let v = s.impact.reference_velocity_m_s;
    let (mut k, mut l, mut vv, mut t, mut f, mut j) = (vec![], vec![], vec![], vec![], vec![], vec![]);
    for r in runs {
        let impact = r.chain.model().impact(s.impact.energy_fraction);
        for smp in impact.force_history(v, 301)? {
            k.push(r.key.clone());
            l.push(r.label.clone());
            vv.push(v);
            t.push(smp.time);
            f.push(smp.force);
            j.push(smp.impulse);
        }
    }
    let n = t.len();
    let mut df = table(vec![
        scol("material_key", k),
        scol("material", l),
        fcol("velocity_m_s", vv),
        fcol("time_s", t),
        fcol("force_n", f),
        fcol("impulse_n_s", j),
        fcol("energy_fraction", vec![s.impact.energy_fraction; n]),
    ])?;
    dir.write_table("force_time", &mut df)
}

fn write_summary(dir: &mut ReportDir, runs: &[MaterialRun], s: &LifetimeStudy) -> Result<Vec<String>> {
    let v = s.impact.reference_velocity_m_s;
    let (mut k, mut l, mut vv, mut yy, mut nn, mut p, mut pl, mut pu) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut headlines = Vec::new();
    for r in runs {
        let model = r.chain.model();
        let counts: Vec<f64> = s.impact.years.iter().map(|&y| impacts_in(y, s.impact.impacts_per_year)).collect();
        let seed = pivotal_seed(s.seed, r.fit.n) ^ 0x5713;
        let bands = model.bands(&r.params, s.impact.energy_fraction, v, &counts, s.strength.uncertainty, s.strength.draws, seed, s.weibull.confidence)?;
        let effects = crate::strength::fit::names(model.fit.effects());
        let mut line = format!(
            "{}: N = {}, m = {:.2} (MLE {:.2}, {:.0} % bounds {:.2}–{:.2}), σ_θ = {:.0} MPa; effects: {effects}; at {v} m/s:",
            r.label,
            r.fit.n,
            r.params.shape,
            model.fit.model.shape(),
            100.0 * s.weibull.confidence,
            r.pivotal.shape.0,
            r.pivotal.shape.1,
            r.params.mu.exp() / 1e6
        );
        for ((&years, &n), (point, lo, hi)) in s.impact.years.iter().zip(&counts).zip(bands) {
            k.push(r.key.clone());
            l.push(r.label.clone());
            vv.push(v);
            yy.push(years);
            nn.push(n);
            p.push(point);
            pl.push(lo);
            pu.push(hi);
            line.push_str(&format!(" P({years} yr) = {point:.2e} [{lo:.1e}, {hi:.1e}]"));
        }
        headlines.push(line);
    }
    let m = p.len();
    let mut df = table(vec![
        scol("material_key", k),
        scol("material", l),
        fcol("velocity_m_s", vv),
        fcol("years", yy),
        fcol("impacts", nn),
        fcol("p_break", p),
        fcol("p_break_lower", pl),
        fcol("p_break_upper", pu),
        fcol("confidence", vec![s.weibull.confidence; m]),
    ])?;
    dir.write_table("lifetime_summary", &mut df)?;
    Ok(headlines)
}

/// The strength model of every material: its effects, population, and each parameter's
/// estimate (the modulus as used for predictions) with the 90 % range of its draws.
fn write_strength_fits(dir: &mut ReportDir, runs: &[MaterialRun]) -> Result<()> {
    let mut rows: Vec<(&MaterialRun, &ParameterSummary)> = Vec::new();
    for r in runs {
        rows.extend(r.summary.iter().map(|p| (r, p)));
    }
    let text = |f: &dyn Fn(&(&MaterialRun, &ParameterSummary)) -> String| rows.iter().map(f).collect::<Vec<_>>();
    let num = |f: &dyn Fn(&(&MaterialRun, &ParameterSummary)) -> f64| rows.iter().map(f).collect::<Vec<_>>();
    let mut df = table(vec![
        scol("material_key", text(&|r| r.0.key.clone())),
        scol("material", text(&|r| r.0.label.clone())),
        scol("effects", text(&|r| crate::strength::fit::names(r.0.chain.model().fit.effects()))),
        scol("population", text(&|r| r.0.chain.model().population.source.clone())),
        ucol("particles", rows.iter().map(|r| r.0.chain.model().population.len() as u64).collect()),
        scol("parameter", text(&|r| r.1.name.clone())),
        scol("unit", text(&|r| r.1.unit.clone())),
        fcol("mle", num(&|r| r.1.estimate)),
        fcol("used", num(&|r| if r.1.name == "weibull_modulus" { r.0.params.shape } else { r.1.estimate })),
        fcol("q05", num(&|r| r.1.q05)),
        fcol("q95", num(&|r| r.1.q95)),
    ])?;
    dir.write_table("strength_fits", &mut df)
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

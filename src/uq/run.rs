//! The `kind = "uq"` study: Monte Carlo propagation of every uncertain input of the lifetime
//! chain to the breaking probabilities of two particle types and the probability that one
//! breaks more than the other — per strength model and averaged over them — with Sobol'
//! indices, and the damage models and averaging domains side by side.
//!
//! # Strength models as a model-form choice
//!
//! Each strength model of `[model_form] strength` (the primary `[strength] effects` first) is
//! fitted to both materials' crush data ([`super::setup::Setup`]; `"diagnosed"` runs the
//! naming loop on each material) and propagated with the same number of samples. Its weight
//! comes from predictive evidence: the 10-fold cross-validated log density of every crush test
//! of both materials, combined by **stacking** ([`crate::strength::weights`], which says why
//! stacking rather than pseudo-BMA; both are reported). The model-averaged headline is
//! P̄ = Σ_M w_M P_M; the models share the seed and sample points block for block, so its
//! standard error is that of the per-block averages Σ_M w_M P_M,b over the independent blocks
//! ([`averaged`]), which carries the models' correlation. The averaged breakage bands are the
//! quantiles of the weighted mixture of the models' samples.
//!
//! # One sample
//!
//! Per material: one joint draw of its strength model (m, μ, the effects' β, the population
//! weights); shared: η, V, impacts per year, γ. Each material's [`crate::strength::LifetimeModel`]
//! gives the population's P_N under every damage model ([`crate::lifetime::damage`]) for
//! N = years × impacts per year. Since σ̄ ∝ V^(2/5), the breakage-vs-velocity bands reuse the
//! samples' inputs with V replaced.

use super::summary::summary;
use std::collections::BTreeMap;

use rayon::prelude::*;

use super::propagate::{Propagated, mean_se, propagate};
use super::setup::{Mode, Setup, Shared};
use super::sobol::{SobolIndices, sobol_indices};
use super::study::{Propagation, UqStudy};
use crate::contact::AveragingDomain;
use crate::dist::Marginal;
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
use crate::lifetime::damage::DamageModel;
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::stats::{interpolated_quantiles, weighted_quantiles};
use crate::strength::{StrengthSpec, summarise};
use crate::schema::StudyFile;
pub use super::forms::{Form, Weighed, forms, weighed};
pub use super::headline::{AVERAGED, AveragingRow, Headline, Row, averaged, pm};

/// log10 of a probability, floored at 1e-300.
fn lg(p: f64) -> f64 {
    p.max(1e-300).log10()
}

/// Runs the study.
pub fn run_uq(loaded: &StudyFile, s: &UqStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    s.validate(&loaded.path.display().to_string())?;
    let shared = Shared::new(s, &loaded.path, &opts.reports_root)?;
    let specs = s.specs();
    let sens_sizes: Vec<usize> = (0..5).rev().map(|k| (s.sensitivity.n >> k).max(64)).collect();
    let pb = progress_bar((specs.len() * s.propagation.replicates + sens_sizes.len() + 3) as u64, opts.progress, crate::runkit::PROGRESS_COUNT);
    pb.set_message("strength models and Monte Carlo propagation");
    let forms = forms(s, &loaded.path, &shared, &|| pb.inc(1))?;
    let mut inputs = vec![InputFile::hash(&loaded.path)?];
    for m in &forms[0].setup.materials {
        inputs.extend(InputFile::read(&m.path, &m.read)?);
    }
    if let crate::dist::Dist::Spectrum { file, .. } = &s.impact.velocity {
        inputs.push(InputFile::hash(&loaded.resolve(std::path::Path::new(file)))?);
    }
    if let (Some(op), Some(th)) = (&s.operating, &shared.thermal) {
        inputs.push(InputFile::hash(&loaded.resolve(&op.law))?);
        inputs.push(InputFile::hash(&th.laws.phases.path)?);
        for p in &th.laws.inputs {
            inputs.push(InputFile::hash(p)?);
        }
    }

    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;
    // The tables are independent of each other given the samples: they are computed side by
    // side (each is parallel inside, but some only over a handful of tasks), each into a branch
    // of the report directory, and listed in this order whatever order they finish in.
    pb.set_message("tables, Sobol' indices and averaging-domain alternatives");
    let primary = &forms[0];
    let [mut d_head, mut d_attr, mut d_prim, mut d_sobol, mut d_avg] = [(); 5].map(|_| dir.branch());
    let (mut headline, mut attrition, mut primary_tables, mut sobol, mut averaging) = (None, None, None, None, None);
    rayon::scope(|sc| {
        sc.spawn(|_| headline = Some(write_headline(&mut d_head, &forms)));
        sc.spawn(|_| attrition = Some(super::attrition::write(&mut d_attr, &forms)));
        sc.spawn(|_| {
            primary_tables = Some((|| -> Result<()> {
                write_strength_models(&mut d_prim, &forms)?;
                write_convergence(&mut d_prim, &primary.setup, &primary.prop)?;
                write_distributions(&mut d_prim, &primary.setup, &primary.prop)?;
                write_breakage_vs_velocity(&mut d_prim, &primary.setup, &primary.prop, s.impact.velocity_range)
            })());
            pb.inc(1);
        });
        sc.spawn(|_| {
            sobol = Some(write_sobol(&mut d_sobol, &primary.setup, s, &sens_sizes, &|| pb.inc(1)).and_then(|r| write_inputs(&mut d_sobol, &primary.setup).map(|_| r)));
        });
        sc.spawn(|_| {
            averaging = Some(write_averaging(&mut d_avg, s, &loaded.path, &shared, &forms));
            pb.inc(1);
        });
    });
    let done = "every table task ran";
    let (headline, attrition, primary_tables, sobol, averaging) = (headline.expect(done), attrition.expect(done), primary_tables.expect(done), sobol.expect(done), averaging.expect(done));
    let (headline, attrition) = (headline?, attrition?);
    primary_tables?;
    let ((final_indices, outputs), averaging) = (sobol?, averaging?);
    for b in [d_head, d_attr, d_prim, d_sobol, d_avg] {
        dir.adopt(b);
    }
    let varying = primary.setup.varying(Mode::Split);
    let per_year = impacts_per_year_text(&primary.setup);
    let mut md = summary(s, &forms, &final_indices, &varying, &outputs, &headline, &averaging, &attrition, &per_year);
    // Materials tested at different temperatures, or one material's tests pooled across several.
    let temps: Vec<Vec<f64>> = primary.setup.materials.iter().map(|m| m.temperatures_c()).collect();
    let tested: Vec<_> = primary.setup.materials.iter().zip(&temps).map(|(m, t)| m.tested(t)).collect();
    let mut warnings = crate::lifetime::tested::warnings(&tested);
    warnings.extend(tested.iter().zip(&primary.setup.materials).filter_map(|(t, m)| crate::lifetime::tested::unused_prediction(t, m.model.population.predicted_temperature().as_deref())));
    for w in &warnings {
        crate::intake::warn(w);
    }
    md = crate::lifetime::tested::with_warnings(&md, &warnings);
    md.push_str(&super::attrition::markdown(&attrition, &per_year, &primary.setup.materials[0].model.label));
    let notes: Vec<(&str, Vec<String>)> = primary.setup.materials.iter().map(|m| (m.model.label.as_str(), m.read.summary_notes())).collect();
    md.push_str(&crate::lifetime::tested::read_section(&notes));
    dir.write_bytes("summary.md", md.as_bytes())?;
    pb.set_message("figures");
    let mut failures = Vec::new();
    let rendered = crate::report::uq::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    pb.inc(1);
    let mut evaluations = BTreeMap::new();
    evaluations.insert("propagation_samples".to_string(), forms.iter().map(|f| f.prop.count() as u64).sum());
    evaluations.insert("sobol_model_runs".to_string(), sens_sizes.iter().map(|n| (n * (varying.len() + 2)) as u64).sum());
    evaluations.insert("strength_draws".to_string(), forms.iter().flat_map(|f| &f.setup.materials).map(|m| ((1 + m.origins.len()) * m.draws.len()) as u64).sum());
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines: headline.lines })
}

/// "730" for a fixed number of impacts a year, "5–95 % 500–900" for an uncertain one.
fn impacts_per_year_text(st: &super::setup::Setup) -> String {
    let m = &st.inputs[st.shared(2)].marginal;
    let (lo, hi) = (m.quantile(0.05), m.quantile(0.95));
    if lo == hi { format!("{lo:.0}") } else { format!("{lo:.0}–{hi:.0} (5–95 %)") }
}

fn write_headline(dir: &mut ReportDir, forms: &[Form]) -> Result<Headline> {
    let st = &forms[0].setup;
    let names = [&st.materials[0].model.label, &st.materials[1].model.label];
    // One quantile row of `breakage.csv`: strength model, damage model, material key, years,
    // (q05, median, q95), the median's Monte Carlo se, mean.
    type QRow = (String, DamageModel, String, f64, [f64; 3], f64, f64);
    // Every (damage model, horizon) on its own task (sorts and selections of the samples);
    // the rows are put together in the serial order.
    let combos: Vec<(usize, usize)> = (0..st.models.len()).flat_map(|k| (0..st.years.len()).map(move |h| (k, h))).collect();
    let parts: Vec<(Vec<Row>, Vec<QRow>)> = combos
        .par_iter()
        .map(|&(k, h)| -> Result<(Vec<Row>, Vec<QRow>)> {
            let (damage, years) = (st.models[k], st.years[h]);
            let (mut rows, mut q_rows) = (Vec::new(), Vec::new());
            let (a, b) = (st.slot(0, h, k), st.slot(1, h, k));
            let mut fractions = Vec::new();
            for f in forms {
                let nb = f.prop.blocks[0].n;
                fractions.push(f.prop.fraction_worse(a, b, nb));
                let (worse, se) = mean_se(&fractions[fractions.len() - 1]);
                let mut median = [0.0; 2];
                let mut band = [(0.0, 0.0); 2];
                for (j, slot) in [a, b].into_iter().enumerate() {
                    let all = f.prop.values(slot);
                    let mean = all.iter().sum::<f64>() / all.len() as f64;
                    let q = interpolated_quantiles(all, &[0.05, 0.5, 0.95]);
                    let block_medians: Vec<f64> = (0..f.prop.blocks.len()).map(|bi| interpolated_quantiles(f.prop.block_values(bi, slot), &[0.5])[0]).collect();
                    median[j] = q[1];
                    band[j] = (q[0], q[2]);
                    q_rows.push((f.setup.spec.name(), damage, st.materials[j].model.key.clone(), years, [q[0], q[1], q[2]], mean_se(&block_medians).1, mean));
                }
                rows.push(Row { strength: f.setup.spec.name(), damage, years, worse, se, ties: f.prop.ties(a, b), median, band });
            }
            if forms.len() > 1 {
                // The weighted mixture of the models' samples.
                let weights: Vec<f64> = forms.iter().map(|f| f.weight).collect();
                let ties: Vec<f64> = rows.iter().map(|r| r.ties).collect();
                let (worse, se, ties) = averaged(&weights, &fractions, &ties)?;
                let mut median = [0.0; 2];
                let mut band = [(0.0, 0.0); 2];
                for (j, slot) in [a, b].into_iter().enumerate() {
                    let pooled = |block: Option<usize>| -> Vec<(f64, f64)> {
                        forms
                            .iter()
                            .flat_map(|f| {
                                let v = match block {
                                    Some(bi) => f.prop.block_values(bi, slot),
                                    None => f.prop.values(slot),
                                };
                                let w = f.weight / v.len() as f64;
                                v.into_iter().map(move |x| (x, w))
                            })
                            .filter(|x| x.1 > 0.0)
                            .collect()
                    };
                    let all = pooled(None);
                    let mean = all.iter().map(|(x, w)| x * w).sum::<f64>();
                    let q = weighted_quantiles(all, &[0.05, 0.5, 0.95]);
                    let block_medians: Vec<f64> = (0..forms[0].prop.blocks.len()).map(|bi| weighted_quantiles(pooled(Some(bi)), &[0.5])[0]).collect();
                    median[j] = q[1];
                    band[j] = (q[0], q[2]);
                    q_rows.push((AVERAGED.into(), damage, st.materials[j].model.key.clone(), years, [q[0], q[1], q[2]], mean_se(&block_medians).1, mean));
                }
                rows.push(Row { strength: AVERAGED.into(), damage, years, worse, se, ties, median, band });
            }
            Ok((rows, q_rows))
        })
        .collect::<Result<_>>()?;
    let (rows, q_rows): (Vec<Vec<Row>>, Vec<Vec<QRow>>) = parts.into_iter().unzip();
    let (rows, q_rows): (Vec<Row>, Vec<QRow>) = (rows.into_iter().flatten().collect(), q_rows.into_iter().flatten().collect());
    // Printed lines: the primary damage model, every horizon.
    let mut lines = Vec::new();
    let primary = st.models[0];
    for &years in &st.years {
        let of = |name: &str| rows.iter().find(|r| r.strength == name && r.damage == primary && r.years == years);
        let title = format!("P({} breaks more than {} in {} yr)", names[0], names[1], years);
        // The samples a row counts: its model's, or every model's for the average.
        let all: usize = forms.iter().map(|f| f.prop.count()).sum();
        if forms.len() == 1 {
            if let Some(r) = of(&forms[0].setup.spec.name()) {
                lines.push(format!("{title} = {} (Monte Carlo se; strength model: {})", pm(r.worse, r.se, forms[0].prop.count()), r.strength));
            }
        } else {
            if let Some(r) = of(AVERAGED) {
                let w: Vec<String> = forms.iter().map(|f| format!("{} {:.3}", f.setup.spec.name(), f.weight)).collect();
                lines.push(format!("{title} = {} (Monte Carlo se; averaged over the strength models with stacking weights {})", pm(r.worse, r.se, all), w.join(", ")));
            }
            let per: Vec<String> = forms.iter().filter_map(|f| of(&f.setup.spec.name()).map(|r| format!("{} {}", r.strength, pm(r.worse, r.se, f.prop.count())))).collect();
            lines.push(format!("    per strength model: {}", per.join("; ")));
        }
    }
    dir.write_table(
        "materials",
        &mut table(vec![
            scol("role", vec!["candidate".into(), "reference".into()]),
            scol("key", st.materials.iter().map(|m| m.model.key.clone()).collect()),
            scol("label", st.materials.iter().map(|m| m.model.label.clone()).collect()),
            ucol("crush_particles", st.materials.iter().map(|m| m.sample.strength.len() as u64).collect()),
            scol("population", st.materials.iter().map(|m| m.model.population.source.clone()).collect()),
            ucol("population_particles", st.materials.iter().map(|m| m.model.population.len() as u64).collect()),
            fcol("reference_diameter_m", st.materials.iter().map(|m| m.model.sphere.diameter).collect()),
            scol("primary_strength_model", vec![st.spec.name(); 2]),
            // The damage model of the figures and tables that show one (the first of the study's).
            scol("primary_damage_model", vec![st.models[0].label().to_string(); 2]),
        ])?,
    )?;
    dir.write_table(
        "comparison",
        &mut table(vec![
            scol("strength_model", rows.iter().map(|x| x.strength.clone()).collect()),
            scol("model", rows.iter().map(|x| x.damage.name().to_string()).collect()),
            fcol("years", rows.iter().map(|x| x.years).collect()),
            fcol("p_candidate_worse", rows.iter().map(|x| x.worse).collect()),
            fcol("mc_se", rows.iter().map(|x| x.se).collect()),
            fcol("ties", rows.iter().map(|x| x.ties).collect()),
        ])?,
    )?;
    dir.write_table(
        "breakage",
        &mut table(vec![
            scol("strength_model", q_rows.iter().map(|q| q.0.clone()).collect()),
            scol("model", q_rows.iter().map(|q| q.1.name().to_string()).collect()),
            scol("material", q_rows.iter().map(|q| q.2.clone()).collect()),
            fcol("years", q_rows.iter().map(|q| q.3).collect()),
            fcol("q05", q_rows.iter().map(|q| q.4[0]).collect()),
            fcol("median", q_rows.iter().map(|q| q.4[1]).collect()),
            fcol("median_mc_se", q_rows.iter().map(|q| q.5).collect()),
            fcol("q95", q_rows.iter().map(|q| q.4[2]).collect()),
            fcol("mean", q_rows.iter().map(|q| q.6).collect()),
        ])?,
    )?;
    Ok(Headline { lines, rows })
}

/// `strength_models.csv` (every model's effects and parameters per material — per failure
/// origin (`failure_origin`) where the model carries each origin's law — with the largest
/// correlation between the effect draws and the base draws) and `weights.csv`.
fn write_strength_models(dir: &mut ReportDir, forms: &[Form]) -> Result<()> {
    let mut t: (Vec<String>, Vec<String>, Vec<String>, Vec<String>, Vec<u64>, Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) = Default::default();
    let mut origin: Vec<String> = Vec::new();
    for f in forms {
        for m in &f.setup.materials {
            // One law, or every failure origin's (its own fit and draws), as the model evaluates.
            let laws: Vec<(&crate::strength::StrengthFit, &[crate::strength::Params], String)> = if m.origins.is_empty() {
                vec![(&m.model.fit, &m.draws[..], String::new())]
            } else {
                m.origins.iter().map(|o| (&o.model.fit, &o.fit.draws[..], o.fit.origin.clone())).collect()
            };
            let model = &m.model;
            let corr = split_correlation(m);
            for (fit, draws, o) in laws {
                for p in summarise(fit, draws) {
                    origin.push(o.clone());
                    t.0.push(f.setup.spec.name());
                    t.1.push(model.key.clone());
                    t.2.push(law_name(m));
                    t.3.push(model.population.source.clone());
                    t.4.push(model.population.len() as u64);
                    t.5.push(p.name);
                    t.6.push(p.estimate);
                    t.7.push(p.q05);
                    t.8.push(p.q95);
                    t.9.push(corr);
                }
            }
        }
    }
    dir.write_table(
        "strength_models",
        &mut table(vec![
            scol("strength_model", t.0),
            scol("material", t.1),
            scol("effects", t.2),
            scol("failure_origin", origin),
            scol("population", t.3),
            ucol("population_particles", t.4),
            scol("parameter", t.5),
            fcol("mle", t.6),
            fcol("q05", t.7),
            fcol("q95", t.8),
            fcol("max_abs_correlation_effects_vs_base", t.9),
        ])?,
    )?;
    let elpd = |f: &Form, j: usize| if f.lpd[j].is_empty() { f64::NAN } else { f.lpd[j].iter().sum::<f64>() };
    dir.write_table(
        "weights",
        &mut table(vec![
            scol("strength_model", forms.iter().map(|f| f.setup.spec.name()).collect()),
            scol("effects_candidate", forms.iter().map(|f| law_name(&f.setup.materials[0])).collect()),
            scol("effects_reference", forms.iter().map(|f| law_name(&f.setup.materials[1])).collect()),
            fcol("elpd_candidate", forms.iter().map(|f| elpd(f, 0)).collect()),
            fcol("elpd_reference", forms.iter().map(|f| elpd(f, 1)).collect()),
            fcol("elpd", forms.iter().map(|f| elpd(f, 0) + elpd(f, 1)).collect()),
            fcol("weight_stacking", forms.iter().map(|f| f.weight).collect()),
            fcol("weight_pseudo_bma", forms.iter().map(|f| f.weight_pbma).collect()),
        ])?,
    )
}

/// A material's strength law under a model, for tables: its effects (`none`, `size+roundness`)
/// or, with known failure origins, `failure origins (Oberfläche+Volumen)`.
fn law_name(m: &super::setup::Material) -> String {
    if m.origins.is_empty() {
        crate::strength::fit::names(m.model.fit.effects())
    } else {
        format!("failure origins ({})", m.origins.iter().map(|o| o.fit.origin.as_str()).collect::<Vec<_>>().join("+"))
    }
}

/// The largest |correlation| between an effect's β draws and the base (μ_c, ln m) draws — how
/// far the split sampling of the Sobol' indices is from the joint draws (0 without effects).
fn split_correlation(m: &super::setup::Material) -> f64 {
    let centre = &m.model.fit.centre;
    let k = centre.len();
    let base: [Vec<f64>; 2] = [
        m.draws.iter().map(|d| d.mu + (0..k).map(|l| d.beta[l] * centre[l]).sum::<f64>()).collect(),
        m.draws.iter().map(|d| d.shape.ln()).collect(),
    ];
    m.model.fit.scalar_effects().into_iter().map(|(_, l)| l).flat_map(|l| {
        let b: Vec<f64> = m.draws.iter().map(|d| d.beta[l]).collect();
        base.iter().map(move |x| crate::stats::pearson(x, &b).0.abs()).collect::<Vec<_>>()
    })
    .fold(0.0, f64::max)
}

/// Convergence of P(candidate worse), primary models, every horizon, on the first k samples of
/// every block (k doubling from 16).
fn write_convergence(dir: &mut ReportDir, st: &Setup, prop: &Propagated) -> Result<()> {
    let nb = prop.blocks[0].n;
    let mut conv: (Vec<f64>, Vec<u64>, Vec<f64>, Vec<f64>) = Default::default();
    let mut k = 16usize.min(nb);
    loop {
        for (h, &years) in st.years.iter().enumerate() {
            let (m, se) = mean_se(&prop.fraction_worse(st.slot(0, h, 0), st.slot(1, h, 0), k));
            conv.0.push(years);
            conv.1.push((k * prop.blocks.len()) as u64);
            conv.2.push(m);
            conv.3.push(se);
        }
        if k == nb {
            break;
        }
        k = (k * 2).min(nb);
    }
    dir.write_table("convergence", &mut table(vec![fcol("years", conv.0), ucol("samples", conv.1), fcol("p_candidate_worse", conv.2), fcol("mc_se", conv.3)])?)
}

/// Densities of log₁₀ P per material and horizon (primary models), 60 bins over the pooled range.
fn write_distributions(dir: &mut ReportDir, st: &Setup, prop: &Propagated) -> Result<()> {
    let mut hist: (Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>) = Default::default();
    for (h, &years) in st.years.iter().enumerate() {
        let vals: Vec<Vec<f64>> = (0..2).map(|j| prop.values(st.slot(j, h, 0)).into_iter().map(lg).collect()).collect();
        let lo = vals.iter().flatten().cloned().fold(f64::INFINITY, f64::min).max(-30.0);
        let hi = vals.iter().flatten().cloned().fold(f64::NEG_INFINITY, f64::max).max(lo + 1e-6);
        let bins = 60;
        let width = (hi - lo) / bins as f64;
        for (j, v) in vals.iter().enumerate() {
            let mut c = vec![0usize; bins];
            for &x in v {
                c[((x - lo) / width).floor().clamp(0.0, bins as f64 - 1.0) as usize] += 1;
            }
            for (b, n) in c.iter().enumerate() {
                hist.0.push(st.materials[j].model.key.clone());
                hist.1.push(years);
                hist.2.push(lo + (b as f64 + 0.5) * width);
                hist.3.push(*n as f64 / v.len() as f64 / width);
            }
        }
    }
    dir.write_table("distributions", &mut table(vec![scol("material", hist.0), fcol("years", hist.1), fcol("log10_p", hist.2), fcol("density", hist.3)])?)
}

/// P_break vs velocity with its 90 % band (primary models) from up to 4000 samples' inputs with
/// the velocity replaced.
fn write_breakage_vs_velocity(dir: &mut ReportDir, st: &Setup, prop: &Propagated, [vlo, vhi]: [f64; 2]) -> Result<()> {
    let per_block = (4000 / prop.blocks.len()).max(1);
    let xs: Vec<&[f64]> = (0..prop.blocks.len()).flat_map(|b| (0..per_block.min(prop.blocks[b].n)).map(move |i| prop.x(b, i))).collect();
    let vi = st.velocity_input();
    let mut grid: Vec<f64> = (0..48).map(|i| vlo * (vhi / vlo).powf(i as f64 / 47.0)).collect();
    // And 5 m/s exactly, the deliverable's largest velocity after the receiver, which the
    // figure's caption quotes.
    let five = crate::report::captions::REFERENCE_VELOCITY;
    if (vlo..=vhi).contains(&five) && !grid.contains(&five) {
        grid.push(five);
        grid.sort_by(f64::total_cmp);
    }
    // Per velocity, every sample's P (all slots).
    let per_v: Vec<Vec<Vec<f64>>> = grid
        .par_iter()
        .map(|&v| {
            xs.iter()
                .map(|x| {
                    let mut x = x.to_vec();
                    x[vi] = v;
                    let mut p = vec![0.0; st.outputs()];
                    st.evaluate_into(&x, Mode::Joint, &mut p).map(|_| p)
                })
                .collect::<Result<Vec<_>>>()
        })
        .collect::<Result<_>>()?;
    let mut vv: (Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) = Default::default();
    for j in 0..2 {
        for (h, &years) in st.years.iter().enumerate() {
            for (i, &v) in grid.iter().enumerate() {
                let q = interpolated_quantiles(per_v[i].iter().map(|p| p[st.slot(j, h, 0)]).collect(), &[0.05, 0.5, 0.95]);
                vv.0.push(st.materials[j].model.key.clone());
                vv.1.push(years);
                vv.2.push(v);
                vv.3.push(q[0]);
                vv.4.push(q[1]);
                vv.5.push(q[2]);
            }
        }
    }
    dir.write_table("breakage_vs_velocity", &mut table(vec![scol("material", vv.0), fcol("years", vv.1), fcol("velocity_m_s", vv.2), fcol("q05", vv.3), fcol("median", vv.4), fcol("q95", vv.5)])?)
}

/// Sobol' indices of the primary models at the last horizon for every base size in `sizes`
/// (the last is the study's n; split sampling, so every effect parameter is an input); returns
/// the final indices and the output names.
fn write_sobol(dir: &mut ReportDir, st: &Setup, s: &UqStudy, sizes: &[usize], tick: &dyn Fn()) -> Result<(Vec<SobolIndices>, Vec<String>)> {
    let h = st.years.len() - 1;
    let (a, b) = (st.slot(0, h, 0), st.slot(1, h, 0));
    let varying = st.varying(Mode::Split);
    let f = |u: &[f64]| -> Result<Vec<f64>> {
        let (_, p) = st.evaluate(u, Mode::Split)?;
        Ok(vec![lg(p[a]), lg(p[b]), p[a] - p[b]])
    };
    let keys = [&st.materials[0].model.key, &st.materials[1].model.key];
    let outputs = vec![format!("log10_p_{}", keys[0]), format!("log10_p_{}", keys[1]), format!("p_{}_minus_p_{}", keys[0], keys[1])];
    // What each output is, in words, for the figures.
    let labels = [&st.materials[0].model.label, &st.materials[1].model.label];
    let output_labels = [format!("log₁₀ P {}", labels[0]), format!("log₁₀ P {}", labels[1]), format!("P {} − P {}", labels[0], labels[1])];
    let mut sob: (Vec<String>, Vec<u64>, Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<String>) = Default::default();
    let mut sob_labels: Vec<String> = Vec::new();
    let mut final_indices: Vec<SobolIndices> = Vec::new();
    for &n in sizes {
        let ind = sobol_indices(f, varying.len(), n, s.seed ^ 0x50B0, s.sensitivity.bootstrap, s.sensitivity.level)?;
        for (o, si) in ind.iter().enumerate() {
            for (k, &i) in varying.iter().enumerate() {
                sob.0.push(outputs[o].clone());
                sob_labels.push(output_labels[o].clone());
                sob.1.push(n as u64);
                sob.2.push(st.inputs[i].name.clone());
                sob.3.push(si.first[k]);
                sob.4.push(si.first_ci[k].0);
                sob.5.push(si.first_ci[k].1);
                sob.6.push(si.total[k]);
                sob.7.push(si.total_ci[k].0);
                sob.8.push(si.total_ci[k].1);
                sob.9.push(if si.first[k] < 0.0 || si.total[k] < 0.0 {
                    "negative: zero within MC error".into()
                } else if si.first[k] > 1.0 || si.total[k] > 1.0 {
                    "above 1: an index is at most 1, Monte Carlo error".into()
                } else {
                    String::new()
                });
            }
        }
        if n == s.sensitivity.n {
            final_indices = ind;
        }
        tick();
    }
    let rows = sob.0.len();
    dir.write_table(
        "sobol",
        &mut table(vec![
            scol("output", sob.0),
            ucol("n", sob.1),
            scol("input", sob.2),
            fcol("s1", sob.3),
            fcol("s1_lo", sob.4),
            fcol("s1_hi", sob.5),
            fcol("st", sob.6),
            fcol("st_lo", sob.7),
            fcol("st_hi", sob.8),
            scol("flag", sob.9),
            // The level of the bootstrap intervals s1_lo … st_hi.
            fcol("level", vec![s.sensitivity.level; rows]),
            scol("output_label", sob_labels),
            // The horizon of the breaking probabilities the outputs are of.
            fcol("years", vec![st.years[h]; rows]),
        ])?,
    )?;
    Ok((final_indices, outputs))
}

/// The primary model's inputs with their 5/50/95 % quantiles (joint strength draws: of the
/// modulus m).
fn write_inputs(dir: &mut ReportDir, st: &Setup) -> Result<()> {
    let mut it: (Vec<String>, Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>) = Default::default();
    for i in &st.inputs {
        it.0.push(i.name.clone());
        let qs = match (&i.marginal, st.materials.iter().find(|m| i.name == format!("strength_{}", m.model.key))) {
            (Marginal::Index(_), Some(m)) => {
                // With failure origins, the origin of smallest modulus: it carries the lower tail.
                let (draws, what) = match m.origins.iter().min_by(|a, b| a.fit.shape.total_cmp(&b.fit.shape)) {
                    Some(o) => (&o.fit.draws, format!("joint draw of every failure origin's law; shown: Weibull m of \"{}\", the origin of smallest modulus", o.fit.origin)),
                    None => (&m.draws, "Weibull m of the joint draws".to_string()),
                };
                let q = interpolated_quantiles(draws.iter().map(|d| d.shape).collect(), &[0.05, 0.5, 0.95]);
                it.1.push(what);
                [q[0], q[1], q[2]]
            }
            (mg, _) => {
                it.1.push(i.unit.clone());
                [0.05, 0.5, 0.95].map(|u| mg.quantile(u))
            }
        };
        it.2.push(qs[0]);
        it.3.push(qs[1]);
        it.4.push(qs[2]);
    }
    dir.write_table("inputs", &mut table(vec![scol("input", it.0), scol("unit", it.1), fcol("q05", it.2), fcol("median", it.3), fcol("q95", it.4)])?)
}

/// The study's domain and every `[model_form] averaging` alternative, each a rerun of the
/// chain with the deliverable's strength model (its own Weibull fit) and a quarter of the
/// samples: P(candidate worse) and the medians, primary damage model, per horizon.
fn write_averaging(dir: &mut ReportDir, s: &UqStudy, path: &std::path::Path, shared: &Shared, forms: &[Form]) -> Result<Vec<AveragingRow>> {
    let mut rows = Vec::new();
    let mut add = |c: &Setup, p: &Propagated, d: &AveragingDomain| {
        for (h, &years) in c.years.iter().enumerate() {
            let (a, b) = (c.slot(0, h, 0), c.slot(1, h, 0));
            let (worse, se) = mean_se(&p.fraction_worse(a, b, p.blocks[0].n));
            rows.push((d.describe(), years, worse, se, interpolated_quantiles(p.values(a), &[0.5])[0], interpolated_quantiles(p.values(b), &[0.5])[0]));
        }
    };
    let deliverable = StrengthSpec::default();
    let opts = Propagation { samples: (s.propagation.samples / 4).max(64 * s.propagation.replicates), ..s.propagation.clone() };
    let own;
    let (bc, bp) = match forms.iter().find(|f| f.setup.spec == deliverable) {
        Some(f) => (&f.setup, &f.prop),
        None => {
            let c = Setup::new(s, path, &deliverable, &s.contact.averaging, shared)?;
            let p = propagate(&c, &opts, s.seed, &|| {})?;
            own = (c, p);
            (&own.0, &own.1)
        }
    };
    add(bc, bp, &s.contact.averaging);
    for d in &s.model_form.averaging {
        let c = Setup::new(s, path, &deliverable, d, shared)?;
        let p = propagate(&c, &opts, s.seed, &|| {})?;
        add(&c, &p, d);
    }
    dir.write_table(
        "averaging",
        &mut table(vec![
            scol("domain", rows.iter().map(|r| r.0.clone()).collect()),
            scol("strength_model", vec![deliverable.name(); rows.len()]),
            fcol("years", rows.iter().map(|r| r.1).collect()),
            fcol("p_candidate_worse", rows.iter().map(|r| r.2).collect()),
            fcol("mc_se", rows.iter().map(|r| r.3).collect()),
            fcol("median_p_candidate", rows.iter().map(|r| r.4).collect()),
            fcol("median_p_reference", rows.iter().map(|r| r.5).collect()),
        ])?,
    )?;
    Ok(rows)
}

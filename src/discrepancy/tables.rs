//! The tables of a discrepancy study's report (`materials.csv`, `stages.csv`, `evidence.csv`,
//! `findings.csv`, `residuals.csv`, `fits.csv`, `origins.csv`, `lifetime.csv`, `power.csv`, …),
//! each written from the results it describes.

use std::collections::BTreeMap;

use super::report::{names, wilson90};
use super::study::{LifetimeBand, MaterialResult, PowerRow};
use crate::error::Result;
use crate::io::{ReportDir, fcol, scol, table, ucol};
use crate::strength::ModelFit;

/// One parameter of each stage's two-population law (NaN where the stage has none), in the
/// rows of fits.csv.
fn law_column(results: &[MaterialResult], f: impl Fn(&crate::strength::flaws::FlawFit) -> f64) -> Vec<f64> {
    results.iter().flat_map(|r| [&r.outcome.before().model, &r.outcome.after().model]).map(|m| m.law.as_ref().map_or(f64::NAN, &f)).collect()
}

/// Mean ln σ_i of a model over the sample: the scale of the strengths adjusted to the sample's
/// average covariates (x_i · e^(mean − ln σ_i)), which the probability plot shows.
fn reference_ln_scale(model: &ModelFit) -> f64 {
    let d = model.design();
    (0..model.n).map(|i| model.reg.ln_scale(&d, i)).sum::<f64>() / model.n.max(1) as f64
}

pub(super) fn write_tables(dir: &mut ReportDir, results: &[MaterialResult]) -> Result<()> {
    // materials.csv
    let mut t = table(vec![
        scol("key", results.iter().map(|r| r.key.clone()).collect()),
        scol("label", results.iter().map(|r| r.label.clone()).collect()),
        ucol("particles", results.iter().map(|r| r.sample.strength.len() as u64).collect()),
        scol("data", results.iter().map(|r| if r.crush.is_some() { "crush".to_string() } else { "strength".to_string() }).collect()),
        scol("effects_named", results.iter().map(|r| names(&r.outcome.named)).collect()),
    ])?;
    dir.write_table("materials", &mut t)?;

    // evidence.csv
    let ev: Vec<(&str, &super::workflow::Evidence)> = results.iter().flat_map(|r| r.outcome.evidence.iter().map(move |e| (r.key.as_str(), e))).collect();
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
        fcol("band_q05", ev.iter().map(|(_, e)| e.band.map_or(f64::NAN, |b| b.0)).collect()),
        fcol("band_q95", ev.iter().map(|(_, e)| e.band.map_or(f64::NAN, |b| b.1)).collect()),
        scol("band", ev.iter().map(|(_, e)| e.band.map_or("", |_| if e.band_pivotal { "pivotal" } else { "profile likelihood" }).to_string()).collect()),
        fcol("weibull_modulus", ev.iter().map(|(_, e)| e.shape).collect()),
        // Replicates whose refit failed, each counted as exceeding Λ; above the stated share
        // (`discrepancy::guard::MAX_FAILED_SHARE`) no verdict.
        ucol("bootstrap_failures", ev.iter().map(|(_, e)| e.failures as u64).collect()),
        ucol("bootstrap_replicates", ev.iter().map(|(_, e)| e.replicates as u64).collect()),
        scol("passed_guard", ev.iter().map(|(_, e)| e.passed.to_string()).collect()),
        scol("named", ev.iter().map(|(_, e)| e.named.to_string()).collect()),
        scol("verdict", ev.iter().map(|(_, e)| super::verdicts::verdict(e)).collect()),
    ])?;
    dir.write_table("evidence", &mut t)?;

    // stages.csv
    let st: Vec<(&MaterialResult, usize, &super::workflow::Stage)> = results.iter().flat_map(|r| r.outcome.stages.iter().enumerate().map(move |(i, s)| (r, i, s))).collect();
    let mut t = table(vec![
        scol("material", st.iter().map(|(r, _, _)| r.key.clone()).collect()),
        ucol("round", st.iter().map(|(_, i, _)| *i as u64).collect()),
        scol("effects", st.iter().map(|(_, _, s)| names(&s.model.effects)).collect()),
        fcol("weibull_modulus", st.iter().map(|(_, _, s)| s.model.shape()).collect()),
        fcol("weibull_modulus_min", st.iter().map(|(_, _, s)| s.model.modulus_range().0).collect()),
        fcol("weibull_modulus_max", st.iter().map(|(_, _, s)| s.model.modulus_range().1).collect()),
        fcol("log_likelihood", st.iter().map(|(_, _, s)| s.model.loglik()).collect()),
        fcol("anderson_darling", st.iter().map(|(_, _, s)| s.ad).collect()),
        fcol("p_anderson_darling", st.iter().map(|(_, _, s)| s.p_ad).collect()),
        fcol("kolmogorov_smirnov", st.iter().map(|(_, _, s)| s.ks).collect()),
        fcol("p_kolmogorov_smirnov", st.iter().map(|(_, _, s)| s.p_ks).collect()),
        fcol("gap", st.iter().map(|(_, _, s)| s.gap).collect()),
        ucol("covariates_diagnosed", st.iter().map(|(_, _, s)| s.findings.len() as u64).collect()),
        // E(G) with nothing missing: one per numeric covariate, 2(L − 1) per categorical factor.
        // 0.0 + …: an empty sum of f64 is −0.0.
        // G's mean over the round's bootstrap from the fitted model (each term as it is after
        // fitting); the naive Σ df beside it, which counts every covariate as unfitted.
        fcol("gap_expected", st.iter().map(|(_, _, s)| s.gap_expected).collect()),
        fcol("gap_degrees_of_freedom", st.iter().map(|(_, _, s)| 0.0 + s.findings.iter().map(|f| f.df as f64).sum::<f64>()).collect()),
        ucol("bootstrap_replicates", st.iter().map(|(_, _, s)| s.replicates as u64).collect()),
        // Why a sequential round drew every replicate: the decision still near its level.
        scol("bootstrap_all_drawn_for", st.iter().map(|(_, _, s)| s.unsettled.clone().unwrap_or_default()).collect()),
    ])?;
    dir.write_table("stages", &mut t)?;

    // findings.csv: residual trends per stage.
    let fi: Vec<(&str, usize, &super::gof::CovariateFinding)> = results
        .iter()
        .flat_map(|r| r.outcome.stages.iter().enumerate().flat_map(move |(i, s)| s.findings.iter().map(move |f| (r.key.as_str(), i, f))))
        .collect();
    let mut t = table(vec![
        scol("material", fi.iter().map(|(k, _, _)| k.to_string()).collect()),
        ucol("round", fi.iter().map(|(_, i, _)| *i as u64).collect()),
        scol("covariate", fi.iter().map(|(_, _, f)| f.covariate.clone()).collect()),
        fcol("spearman_rho", fi.iter().map(|(_, _, f)| f.rho).collect()),
        fcol("p_permutation", fi.iter().map(|(_, _, f)| f.p).collect()),
        fcol("worst_tertile_from", fi.iter().map(|(_, _, f)| f.worst_range.0).collect()),
        fcol("worst_tertile_to", fi.iter().map(|(_, _, f)| if f.scatter { f64::NAN } else { f.worst_range.1 }).collect()),
        fcol("worst_tertile_mean_residual", fi.iter().map(|(_, _, f)| if f.scatter { f64::NAN } else { f.worst_range.2 }).collect()),
        scol("kind", fi.iter().map(|(_, _, f)| (if f.scatter { "scatter" } else if f.worst_level.is_some() { "levels" } else { "trend" }).to_string()).collect()),
        fcol("statistic", fi.iter().map(|(_, _, f)| f.statistic).collect()),
        ucol("df", fi.iter().map(|(_, _, f)| f.df as u64).collect()),
        scol("worst_level", fi.iter().map(|(_, _, f)| f.worst_level.clone().unwrap_or_default()).collect()),
        fcol("worst_level_mean_abs_deviation", fi.iter().map(|(_, _, f)| if f.scatter { f.worst_range.2 } else { f64::NAN }).collect()),
        fcol("all_levels_mean_abs_deviation", fi.iter().map(|(_, _, f)| if f.scatter { f.worst_range.1 } else { f64::NAN }).collect()),
    ])?;
    dir.write_table("findings", &mut t)?;

    // covariates.csv: the columns each material's residuals are plotted against.
    let cv: Vec<(&str, &str, &str)> = results
        .iter()
        .flat_map(|r| {
            let numeric = r.sample.covariates.iter().map(move |(n, _)| (r.key.as_str(), n.as_str(), "numeric"));
            numeric.chain(r.sample.levels.iter().map(move |(n, _)| (r.key.as_str(), n.as_str(), "categorical")))
        })
        .collect();
    let mut t = table(vec![scol("material", cv.iter().map(|c| c.0.to_string()).collect()), scol("column", cv.iter().map(|c| c.1.to_string()).collect()), scol("type", cv.iter().map(|c| c.2.to_string()).collect())])?;
    dir.write_table("covariates", &mut t)?;

    // residuals.csv: per specimen, before and after, with every covariate (a crush sample's
    // five, a strength file's size measure and factors) and the strength adjusted to the
    // sample's average covariates and, with a modulus per level, to the reference level's
    // modulus (for the probability plot).
    let mut numeric_names: Vec<String> = super::workflow::DIAGNOSED.iter().map(|s| s.to_string()).collect();
    let mut level_names: Vec<String> = Vec::new();
    for r in results {
        for (n, _) in &r.sample.covariates {
            if !numeric_names.contains(n) {
                numeric_names.push(n.clone());
            }
        }
        for (n, _) in &r.sample.levels {
            if !level_names.contains(n) {
                level_names.push(n.clone());
            }
        }
    }
    let mut cols: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut num: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    for r in results {
        for (stage, st) in [("before", r.outcome.before()), ("after", r.outcome.after())] {
            let d = st.model.design();
            let centre = if st.model.law.is_some() { 0.0 } else { reference_ln_scale(&st.model) };
            for i in 0..r.sample.strength.len() {
                cols.entry("material".into()).or_default().push(r.key.clone());
                cols.entry("id".into()).or_default().push(r.ids[i].clone());
                cols.entry("stage".into()).or_default().push(stage.into());
                let x = r.sample.strength.x[i];
                let obs = r.sample.strength.view();
                num.entry("strength_pa".into()).or_default().push(x);
                cols.entry("observed".into()).or_default().push(obs.kind(i).name().into());
                cols.entry("failure_origin".into()).or_default().push(r.failure_origins.get(i).cloned().unwrap_or_default());
                // With a modulus per level, each specimen's standardised residual is carried onto
                // the reference level's modulus, so the adjusted strengths share one law.
                // A two-population law: the strengths with the scale effects beside it taken out
                // (on the law's curve at the reference level).
                let adjust = |x: f64| {
                    if let Some(l) = &st.model.law {
                        x * (-l.shift(&st.model.columns, i)).exp()
                    } else if st.model.scale_columns.is_empty() {
                        x * (centre - st.model.reg.ln_scale(&d, i)).exp()
                    } else {
                        (centre + st.model.reg.b * (x.ln() - st.model.reg.ln_scale(&d, i)) / st.model.reg.b_at(&d, i)).exp()
                    }
                };
                num.entry("adjusted_pa".into()).or_default().push(adjust(x));
                // An interval's upper end (NaN for the other rows), as read and adjusted alike.
                num.entry("upper_pa".into()).or_default().push(obs.upper(i));
                num.entry("adjusted_upper_pa".into()).or_default().push(adjust(obs.upper(i)));
                num.entry("residual".into()).or_default().push(st.residuals[i]);
                for name in &numeric_names {
                    let v = r.sample.covariates.iter().find(|(n, _)| n == name).and_then(|(_, v)| v[i]).unwrap_or(f64::NAN);
                    num.entry(name.clone()).or_default().push(v);
                }
                for name in &level_names {
                    let v = r.sample.levels.iter().find(|(n, _)| n == name).map(|(_, v)| v[i].clone()).unwrap_or_default();
                    cols.entry(name.clone()).or_default().push(v);
                }
            }
        }
    }
    let mut columns = vec![scol("material", cols.remove("material").unwrap_or_default()), scol("id", cols.remove("id").unwrap_or_default()), scol("stage", cols.remove("stage").unwrap_or_default()), scol("observed", cols.remove("observed").unwrap_or_default())];
    for k in ["strength_pa", "upper_pa", "adjusted_pa", "adjusted_upper_pa", "residual"].iter().map(|s| s.to_string()).chain(numeric_names) {
        let v = num.remove(&k).unwrap_or_default();
        columns.push(fcol(&k, v));
    }
    for k in level_names {
        let v = cols.remove(&k).unwrap_or_default();
        columns.push(scol(&k, v));
    }
    // Each specimen's failure origin, where a study names them (the probability plot by origin).
    if results.iter().any(|r| !r.failure_origins.is_empty()) {
        columns.push(scol("failure_origin", cols.remove("failure_origin").unwrap_or_default()));
    }
    let mut t = table(columns)?;
    dir.write_table("residuals", &mut t)?;

    // fits.csv: the Weibull law of the adjusted strengths of each stage (probability plot).
    let two = |l: &crate::strength::flaws::FlawFit| l.kind != crate::strength::flaws::Populations::Threshold;
    let mut t = table(vec![
        scol("material", results.iter().flat_map(|r| [r.key.clone(), r.key.clone()]).collect()),
        scol("stage", results.iter().flat_map(|_| ["before".to_string(), "after".to_string()]).collect()),
        scol("effects", results.iter().flat_map(|r| [names(&r.outcome.before().model.effects), names(&r.outcome.after().model.effects)]).collect()),
        fcol("weibull_modulus", results.iter().flat_map(|r| [r.outcome.before().model.shape(), r.outcome.after().model.shape()]).collect()),
        // No single scale where the law is two populations (its own columns follow).
        fcol("scale_pa", results.iter().flat_map(|r| [&r.outcome.before().model, &r.outcome.after().model]).map(|m| if m.law.is_some() { f64::NAN } else { reference_ln_scale(m).exp() }).collect()),
        // A two-population law in place of the Weibull law: its parameters (empty / NaN else).
        scol("law", results.iter().flat_map(|r| [&r.outcome.before().model, &r.outcome.after().model]).map(|m| m.law.as_ref().map_or(String::new(), |l| l.kind.name().to_string())).collect()),
        // The threshold law has one population: its weight and second population are NaN.
        fcol("law_weight", law_column(results, |l| if two(l) { l.p } else { f64::NAN })),
        fcol("law_scale1_pa", law_column(results, |l| l.first.0)),
        fcol("law_modulus1", law_column(results, |l| l.first.1)),
        fcol("law_scale2_pa", law_column(results, |l| if two(l) { l.second.0 } else { f64::NAN })),
        fcol("law_modulus2", law_column(results, |l| if two(l) { l.second.1 } else { f64::NAN })),
        fcol("law_threshold_pa", law_column(results, |l| l.threshold)),
    ])?;
    dir.write_table("fits", &mut t)?;

    // origins.csv: each failure origin's law (strength and crush files that name origins).
    let rows: Vec<(&str, &crate::strength::origins::Origins, &crate::strength::origins::OriginFit)> = results.iter().filter_map(|r| r.origins.as_ref().map(|o| (r.key.as_str(), o))).flat_map(|(k, o)| o.fits.iter().map(move |f| (k, o, f))).collect();
    if !rows.is_empty() {
        let shared = |o: &crate::strength::origins::Origins, f: fn(&crate::strength::origins::SharedModulus) -> f64| o.shared.as_ref().map_or(f64::NAN, f);
        let mut t = table(vec![
            scol("material", rows.iter().map(|r| r.0.to_string()).collect()),
            scol("column", rows.iter().map(|r| r.1.column.clone()).collect()),
            scol("origin", rows.iter().map(|r| r.2.origin.clone()).collect()),
            ucol("breaks", rows.iter().map(|r| r.2.breaks as u64).collect()),
            fcol("weibull_modulus", rows.iter().map(|r| r.2.shape).collect()),
            fcol("scale_pa", rows.iter().map(|r| r.2.scale).collect()),
            // 90 % bands: the bootstrap draws the lifetime with every origin acting combines.
            fcol("modulus_q05", rows.iter().map(|r| r.2.shape_band.0).collect()),
            fcol("modulus_q95", rows.iter().map(|r| r.2.shape_band.1).collect()),
            fcol("scale_q05_pa", rows.iter().map(|r| r.2.scale_band.0).collect()),
            fcol("scale_q95_pa", rows.iter().map(|r| r.2.scale_band.1).collect()),
            // The log-likelihood of each origin's fit, a density per unit of the strengths (Pa).
            fcol("log_likelihood", rows.iter().map(|r| r.2.loglik).collect()),
            fcol("shared_modulus_lr", rows.iter().map(|r| shared(r.1, |s| s.lr)).collect()),
            fcol("shared_modulus_df", rows.iter().map(|r| shared(r.1, |s| s.df as f64)).collect()),
            fcol("shared_modulus_p", rows.iter().map(|r| shared(r.1, |s| s.p)).collect()),
        ])?;
        dir.write_table("origins", &mut t)?;
    }

    // lifetime.csv
    let lt: Vec<(&str, &str, &LifetimeBand)> = results.iter().flat_map(|r| r.lifetime.iter().flat_map(move |(st, v)| v.iter().map(move |b| (r.key.as_str(), st.as_str(), b)))).collect();
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
    let pw: Vec<(&str, &PowerRow)> = results.iter().flat_map(|r| r.power.iter().map(move |p| (r.key.as_str(), p))).collect();
    let rate = |k: usize, n: usize| if n == 0 { f64::NAN } else { k as f64 / n as f64 };
    let mut t = table(vec![
        scol("material", pw.iter().map(|x| x.0.to_string()).collect()),
        scol("scenario", pw.iter().map(|x| x.1.scenario.clone()).collect()),
        scol("effects", pw.iter().map(|x| if x.1.scenario == "none" { "none".to_string() } else { names(&results.iter().find(|r| r.key == x.0).map(|r| r.outcome.named.clone()).unwrap_or_default()) }).collect()),
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

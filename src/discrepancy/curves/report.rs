//! The report of a curve-level study: headline, `verdict.json`, tables and `summary.md`, each
//! generated from the numbers it describes.

use crate::discrepancy::koh::{BIC_STRONG, KohFit};
use crate::error::Result;
use crate::io::{ReportDir, fcol, scol, table, ucol};
use crate::schema::StudyFile;
use super::{CurveStudy, CurveCandidate};
use super::model::*;
use super::calibration::Calibrated;

pub(super) fn term_names(t: &[CurveCandidate]) -> String {
    if t.is_empty() { "none".into() } else { t.iter().map(|c| c.name()).collect::<Vec<_>>().join(" then ") }
}

pub(super) fn curve_headline(o: &CurveOutcome) -> String {
    let (b, a) = (&o.stages[0], o.stages.last().unwrap_or(&o.stages[0]));
    format!("crush curves: terms named: {}; gap RMS(δ/σ) {:.2} → {:.2}; RMS δ {:.3} N → {:.3} N", term_names(&o.named), b.gap, a.gap, b.fit.delta_rms, a.fit.delta_rms)
}

/// The parameter of the term a candidate fit added (its last θ): (median, 5 %, 95 %).
pub(super) fn added_parameter(fit: &KohFit) -> (f64, f64, f64) {
    let i = fit.theta_median.len() - 1;
    (fit.theta_median[i], fit.theta_90[i].0, fit.theta_90[i].1)
}

pub(super) fn curve_verdict(loaded: &StudyFile, s: &CurveStudy, groups: &[Group], o: &CurveOutcome, where_: &[Disagreement], trend: &[(f64, f64)]) -> serde_json::Value {
    use serde_json::json;
    let (b, a) = (&o.stages[0], o.stages.last().unwrap_or(&o.stages[0]));
    let evidence: Vec<serde_json::Value> = o
        .evidence
        .iter()
        .map(|e| {
            let par = e.fit.as_ref().map(|f| {
                let (m, lo, hi) = added_parameter(f);
                json!({ "name": e.candidate.parameter(), "median": m, "q05": lo, "q95": hi })
            });
            json!({
                "round": e.round + 1,
                "candidate": e.candidate.name(),
                "skipped": e.skipped,
                "bic": e.fit.as_ref().map(|f| f.bic),
                "delta_bic": if e.delta_bic.is_finite() { json!(e.delta_bic) } else { json!(null) },
                "gap": e.fit.as_ref().map(|_| e.gap),
                "delta_rms_n": e.fit.as_ref().map(|f| f.delta_rms),
                "parameter": par,
                "named": e.named,
            })
        })
        .collect();
    json!({
        "study": loaded.name,
        "calibration": s.calibration,
        "effects_named": o.named.iter().map(|c| c.name()).collect::<Vec<_>>(),
        "gap_before": b.gap,
        "gap_after": a.gap,
        "gap_measure": CURVE_GAP_MEASURE,
        "delta_rms_before_n": b.fit.delta_rms,
        "delta_rms_after_n": a.fit.delta_rms,
        "bic_before": b.fit.bic,
        "bic_after": a.fit.bic,
        "guard": format!("a term is named when it lowers BIC by more than {} against the current model", -BIC_STRONG),
        "evidence": evidence,
        "disagreement_before": groups.iter().zip(where_).map(|(g, w)| json!({
            "file": g.label,
            "temperature_c": g.temperature,
            "from_um": w.map(|w| w.0 * 1e6),
            "to_um": w.map(|w| w.1 * 1e6),
            "largest_relative_delta": w.map(|w| w.2),
        })).collect::<Vec<_>>(),
        "trend_along_curve": groups.iter().zip(trend).map(|(g, t)| json!({
            "file": g.label,
            "spearman_rho": if t.0.is_finite() { json!(t.0) } else { json!(null) },
            "p_permutation": if t.1.is_finite() { json!(t.1) } else { json!(null) },
        })).collect::<Vec<_>>(),
        "parameters_after": a.fit.names.iter().zip(&a.fit.theta_median).zip(&a.fit.theta_90).map(|((n, m), q)| json!({ "name": n, "median": m, "q05": q.0, "q95": q.1 })).collect::<Vec<_>>(),
    })
}

#[allow(clippy::too_many_arguments)]
pub(super) fn write_curve_tables(dir: &mut ReportDir, groups: &[Group], points: &[Point], cal: &Calibrated, o: &CurveOutcome, base_ls: &[f64], ratios: Option<&RatioTable>) -> Result<()> {
    // points.csv: data, model and δ before and after.
    let (b, a) = (&o.stages[0], o.stages.last().unwrap_or(&o.stages[0]));
    let mut t = table(vec![
        scol("file", points.iter().map(|p| groups[p.group].label.clone()).collect()),
        fcol("temperature_c", points.iter().map(|p| p.temperature).collect()),
        fcol("displacement_m", points.iter().map(|p| p.x).collect()),
        fcol("force_mean_n", points.iter().map(|p| p.mean).collect()),
        fcol("sigma_n", points.iter().map(|p| p.sigma).collect()),
        ucol("particles", points.iter().map(|p| p.particles as u64).collect()),
        fcol("model_least_squares_n", base_ls.to_vec()),
        fcol("model_before_n", b.model.clone()),
        fcol("delta_before_n", b.fit.delta.clone()),
        fcol("delta_sd_before_n", b.fit.delta_sd.clone()),
        fcol("model_after_n", a.model.clone()),
        fcol("delta_after_n", a.fit.delta.clone()),
        fcol("delta_sd_after_n", a.fit.delta_sd.clone()),
    ])?;
    dir.write_table("curve_points", &mut t)?;

    // curve_residuals.csv: every particle at every point, standardised by the particle scatter.
    let (mut f, mut part, mut x, mut r) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, p) in points.iter().enumerate() {
        for c in &groups[p.group].curves {
            if let Some(v) = c.force_at(p.x) {
                f.push(groups[p.group].label.clone());
                part.push(c.particle.clone());
                x.push(p.x);
                r.push((v - base_ls[i]) / p.scatter);
            }
        }
    }
    let mut t = table(vec![scol("file", f), scol("particle", part), fcol("displacement_m", x), fcol("residual", r)])?;
    dir.write_table("curve_residuals", &mut t)?;

    // curve_evidence.csv
    let ev = &o.evidence;
    let par = |k: usize| {
        ev.iter()
            .map(|e| {
                e.fit.as_ref().map_or(f64::NAN, |f| {
                    let p = added_parameter(f);
                    [p.0, p.1, p.2][k]
                })
            })
            .collect::<Vec<f64>>()
    };
    let mut t = table(vec![
        ucol("round", ev.iter().map(|e| e.round as u64 + 1).collect()),
        scol("candidate", ev.iter().map(|e| e.candidate.name().to_string()).collect()),
        scol("equation", ev.iter().map(|e| e.candidate.equation().to_string()).collect()),
        scol("skipped", ev.iter().map(|e| e.skipped.clone().unwrap_or_default()).collect()),
        fcol("bic", ev.iter().map(|e| e.fit.as_ref().map_or(f64::NAN, |f| f.bic)).collect()),
        fcol("delta_bic", ev.iter().map(|e| e.delta_bic).collect()),
        fcol("gap", ev.iter().map(|e| e.gap).collect()),
        scol("parameter", ev.iter().map(|e| e.candidate.parameter().to_string()).collect()),
        fcol("median", par(0)),
        fcol("q05", par(1)),
        fcol("q95", par(2)),
        scol("named", ev.iter().map(|e| if e.named { "yes" } else { "no" }.to_string()).collect()),
    ])?;
    dir.write_table("curve_evidence", &mut t)?;

    // curve_stages.csv: one row per model and parameter.
    let (mut st, mut terms, mut pn, mut med, mut lo, mut hi, mut gap, mut bic, mut ls) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    for (k, s) in o.stages.iter().enumerate() {
        for (j, n) in s.fit.names.iter().enumerate() {
            st.push(k as u64);
            terms.push(term_names(&s.terms));
            pn.push(n.clone());
            med.push(s.fit.theta_median[j]);
            lo.push(s.fit.theta_90[j].0);
            hi.push(s.fit.theta_90[j].1);
            gap.push(s.gap);
            bic.push(s.fit.bic);
            ls.push(if k == 0 { o.theta_ls[j] } else { f64::NAN });
        }
    }
    let mut t = table(vec![
        ucol("stage", st),
        scol("terms", terms),
        scol("parameter", pn),
        fcol("median", med),
        fcol("q05", lo),
        fcol("q95", hi),
        fcol("least_squares_without_delta", ls),
        fcol("gap", gap),
        fcol("bic", bic),
    ])?;
    dir.write_table("curve_stages", &mut t)?;

    // curvature_table.csv and the calibration's θ.
    if let Some(tab) = ratios {
        let (mut rho, mut xs, mut ph) = (vec![], vec![], vec![]);
        for (r, row) in tab.roundness.iter().zip(&tab.ratio) {
            for (xk, v) in cal.grid.iter().zip(row) {
                rho.push(*r);
                xs.push(*xk);
                ph.push(*v);
            }
        }
        let mut t = table(vec![fcol("roundness", rho), fcol("displacement_m", xs), fcol("force_ratio", ph)])?;
        dir.write_table("curvature_table", &mut t)?;
    }
    Ok(())
}

/// `summary.md` of a curve-level study whose calibration study file is `calibration`.
pub(super) fn curve_summary(calibration: &str, groups: &[Group], o: &CurveOutcome, where_: &[Disagreement], trend: &[(f64, f64)]) -> String {
    let (b, a) = (&o.stages[0], o.stages.last().unwrap_or(&o.stages[0]));
    let mut md = String::from("# Discrepancy of the calibrated crush FE against measured curves\n\n");
    md.push_str(&format!("Calibration: `{}` (its emulator and posterior). Data: ", calibration));
    md.push_str(&groups.iter().map(|g| format!("{} ({} curves, {} °C)", g.label, g.curves.len(), g.temperature)).collect::<Vec<_>>().join(", "));
    md.push_str(&format!(".\n\n**Terms named: {}.** Gap RMS(δ̂/σ) {:.2} → {:.2}; RMS δ̂ {:.3} N → {:.3} N; BIC {:.1} → {:.1}.\n\n", term_names(&o.named), b.gap, a.gap, b.fit.delta_rms, a.fit.delta_rms, b.fit.bic, a.fit.bic));
    md.push_str("## Where the calibrated model disagrees (base model, |δ̂| > 2σ of the mean curve)\n\n");
    for ((g, w), t) in groups.iter().zip(where_).zip(trend) {
        match w {
            Some((lo, hi, rel)) => md.push_str(&format!("* {}: from {:.1} to {:.1} µm (normalised), largest |δ̂|/F {:.1} %", g.label, lo * 1e6, hi * 1e6, 100.0 * rel)),
            None => md.push_str(&format!("* {}: nowhere", g.label)),
        }
        md.push_str(&format!("; least-squares residual trend along the curve: Spearman ρ {:.2} (permutation p {:.3})\n", t.0, t.1));
    }
    md.push_str("\n## Evidence (ΔBIC against the round's current model; named below −6)\n\n| round | candidate | ΔBIC | gap | parameter | median [90 %] | verdict |\n|---|---|---|---|---|---|---|\n");
    for e in &o.evidence {
        match &e.fit {
            Some(f) => {
                let (m, lo, hi) = added_parameter(f);
                md.push_str(&format!(
                    "| {} | {} | {:.1} | {:.2} | {} | {:.4} [{:.4}, {:.4}] | {} |\n",
                    e.round + 1,
                    e.candidate.name(),
                    e.delta_bic,
                    e.gap,
                    e.candidate.parameter(),
                    m,
                    lo,
                    hi,
                    if e.named {
                        "**named**"
                    } else if e.delta_bic < BIC_STRONG {
                        "passed, weaker"
                    } else {
                        "not supported"
                    }
                ));
            }
            None => md.push_str(&format!("| {} | {} | – | – | – | – | skipped: {} |\n", e.round + 1, e.candidate.name(), e.skipped.clone().unwrap_or_default())),
        }
    }
    md.push_str("\n## Constants before and after (posterior median [90 %])\n\n| parameter | base model | final model |\n|---|---|---|\n");
    for (j, n) in a.fit.names.iter().enumerate() {
        let before = b.fit.names.iter().position(|m| m == n).map_or("–".to_string(), |i| format!("{:.4e} [{:.4e}, {:.4e}]", b.fit.theta_median[i], b.fit.theta_90[i].0, b.fit.theta_90[i].1));
        md.push_str(&format!("| {} | {} | {:.4e} [{:.4e}, {:.4e}] |\n", n, before, a.fit.theta_median[j], a.fit.theta_90[j].0, a.fit.theta_90[j].1));
    }
    md.push_str("\nEquations of the terms, the gap measure and the guard: `partlife::discrepancy::curves` (module documentation). Figure `discrepancy_curves`: measured mean curves with the base and final model (top) and δ̂ with its 90 % band before and after (bottom).\n");
    md
}

#[cfg(test)]
mod tests {
    //! The headline and summary of a hand-made outcome: every verdict must follow its ΔBIC and
    //! every number must be the one given.
    use super::*;
    use crate::calibrate::data::Curve;

    fn fit(names: &[&str], median: &[f64], bic: f64, delta_rms: f64) -> KohFit {
        KohFit {
            name: "m".into(),
            names: names.iter().map(|n| n.to_string()).collect(),
            theta_map: median.to_vec(),
            theta_median: median.to_vec(),
            theta_90: median.iter().map(|m| (0.5 * m, 2.0 * m)).collect(),
            sigma_delta: 1.0,
            lengths: vec![1.0],
            max_loglik: -bic / 2.0,
            bic,
            delta: vec![],
            delta_sd: vec![],
            delta_rms,
        }
    }

    fn outcome() -> CurveOutcome {
        use CurveCandidate::*;
        let base = fit(&["k1", "k2"], &[10.0, 2.0], 100.0, 2.5);
        let with_c = fit(&["k1", "k2", "c"], &[11.0, 2.5, 0.25], 80.0, 0.4);
        let ev = |round, candidate, fit: Option<KohFit>, delta_bic, named| CurveEvidence { round, candidate, skipped: fit.is_none().then(|| "no temperature spread".into()), fit, delta_bic, gap: 0.9, named };
        CurveOutcome {
            named: vec![Compliance],
            evidence: vec![
                ev(0, Compliance, Some(with_c.clone()), -20.0, true),
                ev(0, Curvature, Some(fit(&["k1", "k2", "r"], &[10.0, 2.0, 0.75], 96.0, 1.0)), -7.0, false),
                ev(0, Temperature, None, f64::NAN, false),
                ev(1, Curvature, Some(fit(&["k1", "k2", "c", "r"], &[10.0, 2.0, 0.25, 0.5], 83.0, 0.4)), 3.0, false),
            ],
            stages: vec![
                CurveStage { terms: vec![], fit: base, model: vec![], gap: 3.25 },
                CurveStage { terms: vec![Compliance], fit: with_c, model: vec![], gap: 0.75 },
            ],
            theta_ls: vec![10.0, 2.0],
        }
    }

    #[test]
    fn headline_states_the_named_terms_and_the_gap_before_and_after() {
        assert_eq!(curve_headline(&outcome()), format!("crush curves: terms named: {}; gap RMS(δ/σ) 3.25 → 0.75; RMS δ 2.500 N → 0.400 N", CurveCandidate::Compliance.name()));
    }

    #[test]
    fn summary_verdicts_follow_delta_bic_and_numbers_are_the_given_ones() {
        use CurveCandidate::*;
        let curve = Curve { particle: "p".into(), diameter: 1e-3, displacement: vec![0.0, 1e-6], force: vec![0.0, 1.0], temperature_c: 20.0 };
        let groups = [Group { label: "RT".into(), temperature: 20.0, curves: vec![curve.clone(); 3] }, Group { label: "800 °C".into(), temperature: 800.0, curves: vec![curve; 2] }];
        let md = curve_summary("cal.toml", &groups, &outcome(), &[Some((2e-6, 8e-6, 0.125)), None], &[(0.5, 0.01), (-0.25, 0.5)]);
        for line in [
            "Calibration: `cal.toml` (its emulator and posterior). Data: RT (3 curves, 20 °C), 800 °C (2 curves, 800 °C).".to_string(),
            format!("**Terms named: {}.** Gap RMS(δ̂/σ) 3.25 → 0.75; RMS δ̂ 2.500 N → 0.400 N; BIC 100.0 → 80.0.", Compliance.name()),
            "* RT: from 2.0 to 8.0 µm (normalised), largest |δ̂|/F 12.5 %; least-squares residual trend along the curve: Spearman ρ 0.50 (permutation p 0.010)".to_string(),
            "* 800 °C: nowhere; least-squares residual trend along the curve: Spearman ρ -0.25 (permutation p 0.500)".to_string(),
            format!("| 1 | {} | -20.0 | 0.90 | {} | 0.2500 [0.1250, 0.5000] | **named** |", Compliance.name(), Compliance.parameter()),
            format!("| 1 | {} | -7.0 | 0.90 | {} | 0.7500 [0.3750, 1.5000] | passed, weaker |", Curvature.name(), Curvature.parameter()),
            format!("| 1 | {} | – | – | – | – | skipped: no temperature spread |", Temperature.name()),
            format!("| 2 | {} | 3.0 | 0.90 | {} | 0.5000 [0.2500, 1.0000] | not supported |", Curvature.name(), Curvature.parameter()),
            "| k1 | 1.0000e1 [5.0000e0, 2.0000e1] | 1.1000e1 [5.5000e0, 2.2000e1] |".to_string(),
            "| c | – | 2.5000e-1 [1.2500e-1, 5.0000e-1] |".to_string(),
        ] {
            assert!(md.lines().any(|l| l == line), "missing line\n{line}\nin\n{md}");
        }
    }
}

//! `verdict.json` of a discrepancy study: per material the effects named, the gap before and
//! after, every candidate's evidence (non-finite numbers as null) and each stage's fit — the
//! machine-readable counterpart of the summary ([`super::report`]).

use super::study::{DiscrepancyStudy, MaterialResult};
use super::workflow::GAP_MEASURE;
use crate::schema::StudyFile;

/// The verdict of `results` under study `s` (read from `loaded`).
pub(super) fn verdict_json(loaded: &StudyFile, s: &DiscrepancyStudy, results: &[MaterialResult]) -> serde_json::Value {
    use serde_json::json;
    let mut named = serde_json::Map::new();
    let mut before = serde_json::Map::new();
    let mut after = serde_json::Map::new();
    let mut evidence = serde_json::Map::new();
    let mut details = Vec::new();
    for r in results {
        let key = r.key.clone();
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
                    "parameter": e.parameter.as_ref().map(|(k, v, se)| json!({"name": k, "value": finite(*v), "se": finite(*se), "band_90": e.band.map(|(a, b)| json!([finite(a), finite(b)])), "band_kind": e.band.map(|_| if e.band_pivotal { "pivotal" } else { "profile likelihood" })})),
                    "meaning": e.meaning,
                    "weibull_modulus": finite(e.shape),
                    "bootstrap_failures": e.failures,
                    "bootstrap_replicates": e.replicates,
                    "passed_guard": e.passed,
                    "named": e.named,
                    "extra_parameters": e.parameters,
                    "weakest_link": e.weakest_link,
                })
            })
            .collect();
        evidence.insert(key.clone(), json!(ev));
        let stage = |st: &super::workflow::Stage| {
            json!({
                "effects": st.model.effects.iter().map(|c| c.name()).collect::<Vec<_>>(),
                "weibull_modulus": st.model.shape(),
                "weibull_modulus_min": st.model.modulus_range().0,
                "weibull_modulus_max": st.model.modulus_range().1,
                "log_likelihood": st.model.loglik(),
                "anderson_darling": st.ad, "p_anderson_darling": st.p_ad,
                "kolmogorov_smirnov": st.ks, "p_kolmogorov_smirnov": st.p_ks, "bootstrap_replicates": st.replicates,
                "gap": st.gap,
            })
        };
        details.push(json!({
            "key": key,
            "label": r.label,
            "data": r.path.display().to_string(),
            "particles": r.sample.strength.len(),
            "covariates_diagnosed": r.outcome.stages[0].findings.iter().map(|f| f.covariate.clone()).collect::<Vec<_>>(),
            "covariates_skipped": r.outcome.skipped_covariates,
            "stages": r.outcome.stages.iter().map(stage).collect::<Vec<_>>(),
            "weakest_link_final_model": r.outcome.size_tests.iter().map(|(e, w)| json!({"effect": e.name(), "test": w})).collect::<Vec<_>>(),
            "lifetime": r.lifetime.iter().map(|(k, v)| json!({"model": k, "bands": v})).collect::<Vec<_>>(),
        }));
    }
    json!({
        "study": loaded.name,
        "gap_measure": GAP_MEASURE,
        "guard": format!("family-wise ({}) bootstrap p < {} with ΔBIC < 0 and a better {}-fold cross-validated log score", s.discrepancy.guard.name(), s.discrepancy.alpha, s.discrepancy.cv_folds),
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


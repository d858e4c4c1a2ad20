//! Each candidate's evidence in words: its verdict (named, passed, not identified, skipped, no
//! verdict, not supported), its row of the summary's evidence table, the laws that did not
//! pass, and the bootstrap refits that failed. The summary ([`super::report`]) and
//! `evidence.csv`'s `verdict` column ([`super::tables`]) read them.

use super::study::MaterialResult;
use super::workflow::Evidence;
use crate::report::bootstrap_p_text as p_text;
use crate::strength::Effect;

/// Why a law in place of the Weibull law is not identified (its fit's verdict, which the guard
/// requires whatever its numbers), or None.
pub(super) fn unidentified(e: &Evidence) -> Option<&str> {
    e.not_identified.as_deref()
}

/// The laws of `tried` that did not pass the guard in round `round`, in words: those whose fit
/// is not identified with the reason (the guard requires it, whatever Λ, ΔBIC and the
/// cross-validated score say), then the others ("do not pass the guard").
pub(super) fn laws_not_passing(r: &MaterialResult, round: usize, tried: &[crate::strength::flaws::Populations]) -> String {
    use crate::strength::flaws::Populations;
    let mut parts = Vec::new();
    let mut rest = Vec::new();
    for k in tried {
        match r.outcome.evidence.iter().find(|e| e.round == round && e.candidate == Effect::Populations(*k)).and_then(unidentified) {
            Some(why) => parts.push(format!("{} {} not identified on these data ({why})", Populations::words(&[*k]), if *k == Populations::Threshold { "is" } else { "are" })),
            None => rest.push(*k),
        }
    }
    if !rest.is_empty() {
        parts.insert(0, format!("{} {} not pass the guard", Populations::words(&rest), if rest.len() == 1 { "does" } else { "do" }));
    }
    parts.join("; ")
}

/// One row of the summary's evidence table: the numbers of the guard and the verdict they gave.
pub(super) fn evidence_row(e: &Evidence) -> String {
    if let Some(reason) = &e.skipped {
        return format!("| {} | {} | | | | | | | skipped: {} |\n", e.round, e.candidate.name(), reason);
    }
    // A stress in Pa (`…_pa`) is printed in MPa to 0.1 MPa; other parameters to three decimals.
    let (unit, scale, d) = match e.parameter.as_ref() {
        Some((k, _, _)) if k.ends_with("_pa") => (" MPa", 1e-6, 1),
        _ => ("", 1.0, 3),
    };
    let band = e.band.map(|(a, b)| format!(" (90 % {} {:.d$}–{:.d$}{unit})", if e.band_pivotal { "pivotal" } else { "profile" }, a * scale, b * scale)).unwrap_or_default();
    let par = e
        .parameter
        .as_ref()
        .map(|(k, v, se)| {
            let k = if unit.is_empty() { k.as_str() } else { k.trim_end_matches("_pa") };
            if se.is_finite() { format!("{k} = {:.d$} ± {:.d$}{unit}{band}", v * scale, se * scale) } else { format!("{k} = {:.d$}{unit}{band}", v * scale) }
        })
        .unwrap_or_default();
    // A law the data do not identify has no estimate to report: its optimum is one of several,
    // or on the edge of the parameter space (the verdict says which).
    let par = if unidentified(e).is_some() { "–".to_string() } else { par };
    let verdict = match verdict(e) {
        v if v == "named" => "**named**".to_string(),
        v => v,
    };
    format!("| {} | {} | {:.2} | {:.2} | {} | {:.2} | {:.2} | {} | {} |\n", e.round, e.candidate.name(), e.lr, e.lr_critical, p_text(e.p_family, e.replicates), e.delta_bic, e.delta_cv, par, verdict)
}

/// A candidate's verdict in words (evidence.csv's `verdict`, the report's tables): named,
/// passed (a weaker candidate was named), not identified (why), skipped (why), no verdict (too
/// many failed refits), or not supported.
pub(super) fn verdict(e: &Evidence) -> String {
    if let Some(reason) = &e.skipped {
        format!("skipped: {reason}")
    } else if e.named {
        "named".to_string()
    } else if e.passed {
        "passed, weaker".to_string()
    } else if let Some(why) = unidentified(e) {
        format!("not identified: {why}")
    } else if !super::guard::decided(e.failures, e.replicates) {
        format!("no verdict: {} of {} bootstrap refits failed (more than {:.0} %)", e.failures, e.replicates, 100.0 * super::guard::MAX_FAILED_SHARE)
    } else {
        "not supported".to_string()
    }
}

/// The candidates whose bootstrap refits failed, per round, with the rule they are judged by
/// (empty when none failed).
pub(super) fn failures_sentence(evidence: &[Evidence]) -> String {
    let failed: Vec<String> = evidence.iter().filter(|e| e.failures > 0).map(|e| format!("`{}` in round {}: {} of {}", e.candidate.name(), e.round, e.failures, e.replicates)).collect();
    if failed.is_empty() {
        return String::new();
    }
    format!(
        "\nBootstrap refits that failed — {}. Each counts as a replicate exceeding the observed Λ (so failures can only raise p); a candidate with more than {:.0} % of its refits failed gets no verdict.\n",
        failed.join("; "),
        100.0 * super::guard::MAX_FAILED_SHARE
    )
}

//! A strength specification on one material's data: which effects it means there (an explicit
//! list as it applies to the material, or what the naming loop names on the material's own
//! sample) and its cross-validated predictive evidence, for the stacking weights of the main
//! study ([`cv_scores`]; with known failure origins, every origin's law acting where the model
//! has no effects on the material).
//!
//! Verified by `tests/strength.rs` (stacking on the shipped crush data) and
//! `tests/censoring.rs` (the main study with failure origins).

use super::workflow::{MIN_PARTICLES, data_err, names};
use crate::error::{Error, Result};
use crate::strength::fit::{cv_pointwise, folds};
use crate::strength::{Effect, NamingSettings, Sample, Term, fit_model};

/// The effects of a strength specification for one material: an explicit list as it applies to
/// the material ([`applying`]), or the effects the loop names on the material's own sample
/// (`"diagnosed"`, the guard included; candidates whose covariate the data lack are skipped, as
/// in the discrepancy study).
pub fn resolve(spec: &crate::strength::StrengthSpec, sample: &Sample, settings: &NamingSettings) -> Result<Vec<Effect>> {
    match spec {
        crate::strength::StrengthSpec::Effects(v) => Ok(applying(v, sample)),
        crate::strength::StrengthSpec::Diagnosed => names(sample, settings),
    }
}

/// The effects of an explicit list that apply to a sample: every particle effect, and a recorded
/// factor's effect where the sample's study declares that factor (a study-wide `levels(batch)`
/// is the model of the materials that record `batch`; another material's crush file has no
/// batches). A particle effect whose covariate is missing stays, and its fit names the column.
pub fn applying(effects: &[Effect], sample: &Sample) -> Vec<Effect> {
    effects.iter().filter(|e| !matches!(e, Effect::Factor(f) if !sample.factors.iter().any(|d| d.column == f.column))).cloned().collect()
}

/// The first recorded factor's effect of `spec` that none of `samples` declares (a misspelt or
/// undeclared factor: every material would silently skip it).
pub fn unclaimed(spec: &crate::strength::StrengthSpec, samples: &[&Sample]) -> Option<Effect> {
    let crate::strength::StrengthSpec::Effects(v) = spec else { return None };
    v.iter().find(|e| matches!(e, Effect::Factor(_)) && samples.iter().all(|s| !applying(std::slice::from_ref(*e), s).contains(e))).cloned()
}

/// Cross-validated log density of every crush test of `sample` under strength specification
/// `spec` (the model's predictive evidence, for stacking weights): K-fold with the naming
/// settings' folds and seed; for `"diagnosed"` the naming loop runs on each training fold, so
/// the selection is part of what is validated. An explicit effect whose covariate is missing is
/// an error naming `material`, the file and the column.
///
/// `origins` (each row's failure origin, where the material's file names them): a model without
/// effects on this material is then every origin's two-parameter law acting, scored by the
/// density of the strength whatever the origin ([`crate::strength::origins::cv_ln_prob`]), as
/// the main study evaluates it; for `"diagnosed"` so in every training fold where the loop
/// names nothing.
pub fn cv_scores(spec: &crate::strength::StrengthSpec, sample: &Sample, settings: &NamingSettings, material: &str, origins: Option<&[String]>) -> Result<Vec<f64>> {
    let x = sample.strength.view();
    let n = x.len();
    if n < MIN_PARTICLES {
        return Err(data_err(sample, "all rows".into(), format!("material `{material}`: {n} crush tests are too few to weigh strength models by cross-validation (at least {MIN_PARTICLES})")));
    }
    let k = settings.cv_folds.clamp(2, n);
    let origins = origins.filter(|o| !o.is_empty());
    // With failure origins, each origin's breaks spread over the folds, so that a training set
    // keeps every origin with three breaks or more.
    let fold = match origins {
        Some(o) => crate::strength::fit::folds_stratified(o, k, settings.seed ^ 0xF01D),
        None => folds(n, k, settings.seed ^ 0xF01D),
    };
    let terms_for = |effects: &[Effect]| -> Result<Vec<(Effect, Term)>> {
        effects
            .iter()
            .map(|e| {
                sample.term(e, settings.gamma)
                    .map(|t| (e.clone(), t))
                    .map_err(|reason| data_err(sample, format!("column {}", e.covariate()), format!("material `{material}`: the strength model's `{}` effect needs this column: {reason}", e.name())))
            })
            .collect()
    };
    let failed = || Error::numerical("cross-validated log score", format!("material `{material}`: a training fit of the `{}` strength model failed", spec.name()));
    // Fold f's test rows under every origin's law fitted to the other folds.
    let by_origins = |origin: &[String], f: usize, out: &mut [f64]| -> Result<()> {
        let (train, test): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| fold[i] != f);
        let p = crate::strength::origins::cv_ln_prob(x, origin, &train, &test).map_err(|why| {
            data_err(
                sample,
                "all rows".into(),
                format!("material `{material}`: the stacking weights of the strength models come from cross-validation, and the `{}` model carries every failure origin's law: {why}. With several strength models every origin needs at least three breaks: merge this origin with another (relabel its particles, where the fractography allows), compare one strength model (`model_form.strength = [[]]`), or fit one law to every origin (the column in `data.ignore` instead of `origin`)", spec.name()),
            )
        })?;
        for (i, v) in test.into_iter().zip(p) {
            out[i] = v;
        }
        Ok(())
    };
    match spec {
        crate::strength::StrengthSpec::Effects(v) => {
            let effects = applying(v, sample);
            match origins {
                Some(origin) if effects.is_empty() => {
                    let mut out = vec![f64::NAN; n];
                    for f in 0..k {
                        by_origins(origin, f, &mut out)?;
                    }
                    Ok(out)
                }
                _ => cv_pointwise(x, &terms_for(&effects)?, &fold, k).ok_or_else(failed),
            }
        }
        crate::strength::StrengthSpec::Diagnosed => {
            let mut out = vec![f64::NAN; n];
            for f in 0..k {
                let train: Vec<usize> = (0..n).filter(|&i| fold[i] != f).collect();
                let sub = sample.rows(&train, sample.source.clone());
                let named = names(&sub, settings)?;
                if let (Some(origin), true) = (origins, named.is_empty()) {
                    by_origins(origin, f, &mut out)?;
                    continue;
                }
                let terms = terms_for(&named)?;
                let fit = fit_model(sub.strength.view(), &crate::strength::fit::subset(&terms, &train)).map_err(|_| failed())?;
                for i in (0..n).filter(|&i| fold[i] == f) {
                    out[i] = crate::strength::fit::predict_ln_prob(&fit, &terms, x, i);
                }
            }
            if out.iter().all(|v| v.is_finite()) { Ok(out) } else { Err(failed()) }
        }
    }
}

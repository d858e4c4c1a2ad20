//! Captions of a discrepancy report's figures (`kind = "discrepancy"`, the strength-data studies
//! included) and of a curve-level discrepancy report (`kind = "discrepancy_curves"`), each read
//! from the table its figure is drawn from.

use std::path::Path;

use super::super::document::Block;
use super::super::{Table, distinct, prob_text};
use super::{FigureNote, p, percent};
use crate::error::Result;

/// Each material's label (from `materials.csv`), or its key.
fn material_labels(dir: &Path) -> Result<impl Fn(&str) -> String> {
    let m = Table::load(dir, "materials")?;
    let (k, l) = (m.s("key")?, m.s("label")?);
    Ok(move |key: &str| k.iter().position(|x| x == key).map_or(key.to_string(), |i| l[i].clone()))
}

/// Figures of a discrepancy (or strength-data) report.
pub(super) fn figure(dir: &Path, stem: &str) -> Result<Option<FigureNote>> {
    if let Some(key) = stem.strip_prefix("discrepancy_residuals_") {
        return residuals(dir, key).map(Some);
    }
    match stem {
        "discrepancy_lifetime" => return lifetime(dir).map(Some),
        "discrepancy_power" => return power(dir).map(Some),
        _ => {}
    }
    if stem == "discrepancy_evidence" {
        let t = Table::load(dir, "evidence")?;
        let (mat, round, cand, lr, crit, pf, dbic, named) = (t.s("material")?, t.f("round")?, t.s("candidate")?, t.f("likelihood_ratio")?, t.f("likelihood_ratio_critical")?, t.f("p_family")?, t.f("delta_bic")?, t.s("named")?);
        let (skipped, replicates, verdict) = (t.s("skipped")?, t.f("bootstrap_replicates")?, t.s("verdict")?);
        // The verdict's first words ("not identified", not its reason).
        let short = |i: usize| verdict[i].split(':').next().unwrap_or("").to_string();
        let labels = material_labels(dir)?;
        let mut rows = Vec::new();
        let mut said = Vec::new();
        // Where the figure numbers a material's candidates, which number is which.
        let mut keyed = Vec::new();
        for m in distinct(&mat) {
            let (cats, numbered) = crate::report::discrepancy::evidence_axis(&(0..mat.len()).filter(|&i| mat[i] == m && skipped[i].is_empty()).map(|i| cand[i].clone()).collect::<Vec<_>>());
            if numbered {
                keyed.push(format!("{}: {}", labels(&m), cats.iter().enumerate().map(|(j, c)| format!("{} {c}", j + 1)).collect::<Vec<_>>().join(", ")));
            }
        }
        for m in distinct(&mat) {
            for r in distinct(&round) {
                let mut idx: Vec<usize> = (0..mat.len()).filter(|&i| mat[i] == m && round[i] == r && lr[i].is_finite()).collect();
                if idx.is_empty() {
                    continue;
                }
                idx.sort_by(|&a, &b| lr[b].total_cmp(&lr[a]));
                let top = idx[0];
                let verdict = match idx.iter().find(|&&i| named[i] == "true") {
                    Some(&i) => format!("named {}", cand[i]),
                    None => "nothing named".into(),
                };
                let top_verdict = if named[top] == "true" { String::new() } else { format!(", {}", short(top)) };
                said.push(format!("{}, round {r}: largest Λ {} (Λ = {:.1} against its critical {:.1}{top_verdict}), {verdict}", labels(&m), cand[top], lr[top], crit[top]));
                for &i in idx.iter().take(3) {
                    rows.push(vec![labels(&m), format!("{r}"), cand[i].clone(), format!("{:.1}", lr[i]), format!("{:.1}", crit[i]), crate::report::bootstrap_p_text(pf[i], replicates[i] as usize), format!("{:.1}", dbic[i]), short(i)]);
                }
            }
        }
        return Ok(Some(FigureNote {
            title: Some("Evidence for each candidate effect".into()),
            caption: p(&format!(
                "Likelihood ratio Λ of every candidate effect per round of the naming loop (round 0: against the base model), against its critical value in the round (the family-wise guard over every candidate of the round): {}.{} The three candidates of each round with the largest Λ are in the table below.",
                said.join("; "),
                if keyed.is_empty() { String::new() } else { format!(" Candidates by number on the axis — {}.", keyed.join("; ")) }
            )),
            blocks: vec![Block::Table { header: vec!["material".into(), "round".into(), "candidate".into(), "Λ".into(), "critical".into(), "p (family)".into(), "ΔBIC".into(), "verdict".into()], rows }],
        }));
    }
    if stem == "discrepancy_gap" {
        let t = Table::load(dir, "stages")?;
        let (mat, round, eff, gap, exp, pad) = (t.s("material")?, t.f("round")?, t.s("effects")?, t.f("gap")?, t.f("gap_expected")?, t.f("p_anderson_darling")?);
        let labels = material_labels(dir)?;
        let rows: Vec<Vec<String>> = (0..mat.len()).map(|i| vec![labels(&mat[i]), format!("{}", round[i]), eff[i].clone(), format!("{:.1}", gap[i]), format!("{:.1}", exp[i]), prob_text(pad[i])]).collect();
        return Ok(Some(FigureNote {
            title: Some("The gap between model and data, round by round".into()),
            caption: p("Gap measure G per round of the naming loop and material, with its expectation when nothing is missing (dashed: G's mean over the round's parametric bootstrap from the fitted model, which falls as the named effects' covariates are fitted); the Anderson–Darling p-value of the model's fit at each round is in the table below."),
            blocks: vec![Block::Table { header: vec!["material".into(), "round".into(), "effects".into(), "gap G".into(), "expected".into(), "AD p".into()], rows }],
        }));
    }
    if let Some(key) = stem.strip_prefix("discrepancy_origins_") {
        let t = Table::load(dir, "origins")?.filter("material", key)?;
        let (origin, breaks, m, scale) = (t.s("origin")?, t.f("breaks")?, t.f("weibull_modulus")?, t.f("scale_pa")?);
        let parts: Vec<String> = (0..origin.len())
            .map(|i| if m[i].is_finite() { format!("{} {} breaks, m = {:.2}, σθ = {:.0} MPa", origin[i], breaks[i], m[i], scale[i] / 1e6) } else { format!("{} {} break(s), too few for a law", origin[i], breaks[i]) })
            .collect();
        // The specimens that did not break: censored for every origin, not drawn.
        let r = Table::load(dir, "residuals")?.filter("material", key)?;
        let (stage, observed) = (r.s("stage")?, r.s("observed")?);
        let unbroken = (0..stage.len()).filter(|&i| stage[i] == "before" && observed[i] == crate::obs::Censor::Right.name()).count();
        let not_drawn = match unbroken {
            0 => String::new(),
            1 => " The one specimen that did not break enters every origin's fit as right-censored and is not drawn.".to_string(),
            n => format!(" The {n} specimens that did not break enter every origin's fit as right-censored and are not drawn."),
        };
        return Ok(Some(FigureNote {
            title: Some(format!("Weibull probability plot by failure origin, {}", material_labels(dir)?(key))),
            caption: p(&format!("Each failure origin's breaks at their Kaplan–Meier plotting positions with the other origins' breaks right-censored at their strength (ASTM C1239's estimate per origin), with each origin's fitted law: {}.{not_drawn}", parts.join("; "))),
            blocks: vec![],
        }));
    }
    if let Some(key) = stem.strip_prefix("discrepancy_probability_") {
        let t = Table::load(dir, "fits")?.filter("material", key)?;
        let (stage, eff, m, scale, law) = (t.s("stage")?, t.s("effects")?, t.f("weibull_modulus")?, t.f("scale_pa")?, t.s("law")?);
        let parts: Vec<String> = (0..stage.len())
            .map(|i| {
                let what = if law[i].is_empty() { format!("m = {:.2}, σθ = {:.0} MPa", m[i], scale[i] / 1e6) } else { if law[i] == "threshold" { "a threshold strength (three-parameter Weibull)".to_string() } else { format!("a two-population law ({})", law[i].replace('_', " ")) } };
                format!("{} (effects: {}): {what}", stage[i], eff[i])
            })
            .collect();
        return Ok(Some(FigureNote {
            title: Some(format!("Weibull probability plot, {}", material_labels(dir)?(key))),
            caption: p(&format!("Weibull probability plot of the strengths before (as reduced) and after the named effects (adjusted to the average recorded factors), with the fitted laws: {}.", parts.join("; "))),
            blocks: vec![],
        }));
    }
    Ok(None)
}


/// A covariate column's name in words (`diameter_m` → "diameter").
fn covariate_name(c: &str) -> String {
    let c = c.strip_suffix("_m").or_else(|| c.strip_suffix("_c")).or_else(|| c.strip_suffix("_pa")).unwrap_or(c);
    c.replace('_', " ")
}

/// One finding in words, as `findings.csv` records its kind: a trend's Spearman ρ, a factor's
/// level shift or its scatter per level (each with the level that differs most), with the
/// permutation p.
fn finding(kind: &str, rho: f64, level: &str, p_perm: f64) -> String {
    let p = prob_text(p_perm);
    match kind {
        "trend" => format!("trend ρ = {} (p = {p})", super::minus(rho)),
        "scatter" => format!("scatter per level, most apart at {level} (p = {p})"),
        _ => format!("level shift, most apart at {level} (p = {p})"),
    }
}

fn residuals(dir: &Path, key: &str) -> Result<FigureNote> {
    let label = material_labels(dir)?(key);
    let f = Table::load(dir, "findings")?.filter("material", key)?;
    let (round, cov, rho, pp, kind, worst) = (f.f("round")?, f.s("covariate")?, f.f("spearman_rho")?, f.f("p_permutation")?, f.s("kind")?, f.s("worst_level")?);
    let rounds = distinct(&round);
    let said = |r: f64| -> String { (0..round.len()).filter(|&i| round[i] == r).map(|i| format!("{} {}", covariate_name(&cov[i]), finding(&kind[i], rho[i], &worst[i], pp[i]))).collect::<Vec<_>>().join(", ") };
    let fits = Table::load(dir, "fits")?.filter("material", key)?;
    let (stage, eff) = (fits.s("stage")?, fits.s("effects")?);
    let after = (0..stage.len()).find(|&i| stage[i] == "after").map(|i| eff[i].clone()).unwrap_or_else(|| "none".into());
    let (first, last) = (rounds.first().copied().unwrap_or(0.0), rounds.last().copied().unwrap_or(0.0));
    let end = if last > first { format!(" In the last round ({last}), after {after}: {}.", said(last)) } else { String::new() };
    Ok(FigureNote {
        title: Some(format!("Residuals against the recorded covariates, {label}")),
        caption: p(&format!(
            "The standardised residual of every specimen against each covariate its file records, with the base model (left) and with the named effects, {after} (right); for a numeric covariate a line joins binned means, for a factor each level shows its 10–90 % band and median (triangle). The residual tests with their permutation p in round {first}: {}.{end}",
            said(first)
        )),
        blocks: vec![],
    })
}

fn lifetime(dir: &Path) -> Result<FigureNote> {
    let labels = material_labels(dir)?;
    let t = Table::load(dir, "lifetime")?;
    let (mat, stage, years, pb, q05, q95) = (t.s("material")?, t.s("stage")?, t.f("years")?, t.f("p_break")?, t.f("q05")?, t.f("q95")?);
    let band = |i: usize| format!("{} [{}, {}]", prob_text(pb[i]), prob_text(q05[i]), prob_text(q95[i]));
    // Materials with known failure origins have a third stage: each origin's law, all acting.
    let known = stage.iter().any(|s| s == "origins");
    let mut rows = Vec::new();
    let mut said = Vec::new();
    for m in distinct(&mat) {
        for y in distinct(&years) {
            let find = |s: &str| (0..mat.len()).find(|&i| mat[i] == m && years[i] == y && stage[i] == s);
            let (b, a, o) = (find("before"), find("after"), find("origins"));
            let mut row = vec![labels(&m), format!("{y}"), b.map_or("—".into(), band), a.map_or("—".into(), band)];
            if known {
                row.push(o.map_or("—".into(), band));
            }
            rows.push(row);
            if let (Some(b), Some(a), true) = (b, a, y == years[0]) {
                let origins = o.map(|o| format!(", every failure origin's own law acting {}", prob_text(pb[o]))).unwrap_or_default();
                said.push(format!("{} {} → {}{origins}", labels(&m), prob_text(pb[b]), prob_text(pb[a])));
            }
        }
    }
    let mut header = vec!["material".into(), "years".into(), "base model [90 %]".into(), "with the named effects [90 %]".into()];
    if known {
        header.push("known origins [90 %]".into());
    }
    Ok(FigureNote {
        title: Some("Breaking probability before and after the named effects".into()),
        caption: p(&format!(
            "Breaking probability with its 90 % band per material, with the base model (crosses) and with the named effects (dots){}, one panel per horizon. After {} yr: {}.",
            if known { ", and with each known failure origin's own law acting together (triangles)" } else { "" },
            years.first().copied().unwrap_or(f64::NAN),
            said.join("; ")
        )),
        blocks: vec![Block::Table { header, rows }],
    })
}

fn power(dir: &Path) -> Result<FigureNote> {
    let labels = material_labels(dir)?;
    let t = Table::load(dir, "power")?;
    let (mat, scen, eff, n, reps, all, lo, hi) = (t.s("material")?, t.s("scenario")?, t.s("effects")?, t.f("particles")?, t.f("replicates")?, t.f("rate_all")?, t.f("rate_all_lo90")?, t.f("rate_all_hi90")?);
    let rate = |i: usize| format!("{} [{}, {}]", percent(all[i]), percent(lo[i]), percent(hi[i]));
    let rows: Vec<Vec<String>> = (0..mat.len())
        .map(|i| vec![labels(&mat[i]), if scen[i] == "none" { "nothing to find".into() } else { eff[i].replace(" then ", " + ") }, format!("{:.0}", n[i]), format!("{:.0}", reps[i]), rate(i)])
        .collect();
    let mut said = Vec::new();
    for m in distinct(&mat) {
        let at = |s: &str| -> Vec<usize> { (0..mat.len()).filter(|&i| mat[i] == m && scen[i] == s).collect() };
        let (e, none) = (at("effects"), at("none"));
        if let (Some(&a), Some(&b)) = (e.first(), e.last()) {
            let fp = none.iter().map(|&i| all[i]).fold(0.0, f64::max);
            said.push(format!("{} finds {} in {} of the data sets at {:.0} particles and {} at {:.0}; false positives at most {}", labels(&m), eff[a].replace(" then ", " + "), percent(all[a]), n[a], percent(all[b]), n[b], percent(fp)));
        }
    }
    Ok(FigureNote {
        title: Some("How many crush tests find these effects".into()),
        caption: p(&format!(
            "Share of synthetic data sets, drawn from the final model, in which the workflow names all its effects (solid, 90 % band) and, drawn without effects, in which it names any (dashed: false positives, against the 5 % guard level), against the number of particles per material. {}.",
            said.join("; ")
        )),
        blocks: vec![Block::Table { header: vec!["material".into(), "effects to find".into(), "particles".into(), "data sets".into(), "rate [90 %]".into()], rows }],
    })
}

/// The figure of a curve-level discrepancy report (`kind = "discrepancy_curves"`).
pub(super) fn curves(dir: &Path, stem: &str) -> Result<Option<FigureNote>> {
    if stem != "discrepancy_curves" {
        return Ok(None);
    }
    let s = Table::load(dir, "curve_stages")?;
    let (stage, terms, gap) = (s.f("stage")?, s.s("terms")?, s.f("gap")?);
    let (Some(first), Some(last)) = ((0..stage.len()).min_by(|&a, &b| stage[a].total_cmp(&stage[b])), (0..stage.len()).max_by(|&a, &b| stage[a].total_cmp(&stage[b]))) else {
        return Ok(None);
    };
    let pts = Table::load(dir, "curve_points")?;
    let (file, temp, force, before, after) = (pts.s("file")?, pts.f("temperature_c")?, pts.f("force_mean_n")?, pts.f("delta_before_n")?, pts.f("delta_after_n")?);
    let mut rows = Vec::new();
    for f in distinct(&file) {
        let idx: Vec<usize> = (0..file.len()).filter(|&i| file[i] == f).collect();
        let worst = |d: &[f64]| idx.iter().map(|&i| (d[i] / force[i]).abs()).fold(0.0, f64::max);
        rows.push(vec![f.clone(), format!("{} °C", temp[idx[0]]), percent(worst(&before)), percent(worst(&after))]);
    }
    let named = if terms[last] == "none" { "no term was named".to_string() } else { format!("named: {}", terms[last]) };
    Ok(Some(FigureNote {
        title: Some("Measured curves against the calibrated model, before and after the named terms".into()),
        caption: p(&format!(
            "Top: the measured mean force–displacement curves with the base model and the final model; bottom: the discrepancy δ̂ with its 90 % band before and after ({named}). The gap RMS(δ̂/σ) falls from {:.2} to {:.2}; the table gives each curve's largest |δ̂| relative to its measured force.",
            gap[first], gap[last]
        )),
        blocks: vec![Block::Table { header: vec!["curve".into(), "temperature".into(), "largest |δ̂|/F, base model".into(), "final model".into()], rows }],
    }))
}

#[cfg(test)]
mod tests {
    /// Each kind of residual test in words (a lab file with a batch factor gave "worst level B"
    /// twice, once for the level shift and once for the scatter, under "rank correlations").
    #[test]
    fn findings_say_their_kind() {
        assert_eq!(super::finding("trend", -0.68, "", 0.001), format!("trend ρ = −0.68 (p = {})", super::prob_text(0.001)));
        assert!(super::finding("levels", f64::NAN, "B", 0.002).starts_with("level shift, most apart at B"));
        assert!(super::finding("scatter", f64::NAN, "B", 0.39).starts_with("scatter per level, most apart at B"));
    }
}

//! The report of a discrepancy study: headline and `summary.md` (its `verdict.json`: [`super::verdict`]), each generated
//! from the numbers it describes (its tables: [`super::tables`]).

use super::study::{DiscrepancyStudy, LifetimeBand, MaterialResult, PowerRow};
use super::workflow::GAP_MEASURE;
use crate::strength::Effect;
use crate::report::bootstrap_p_text as p_text;
use super::verdicts::{evidence_row, failures_sentence, laws_not_passing, unidentified};

/// "= 0.123", or "≤ 0.005" for a bootstrap p at its floor 1/(B + 1).
fn eq_p(p: f64, replicates: usize) -> String {
    let t = p_text(p, replicates);
    if t.starts_with('≤') { t } else { format!("= {t}") }
}

/// Wilson score interval of k successes in n at the two-sided level 90 %.
pub fn wilson90(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.644_853_626_951_472_2;
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let den = 1.0 + z * z / n;
    let c = (p + z * z / (2.0 * n)) / den;
    let h = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / den;
    ((c - h).max(0.0), (c + h).min(1.0))
}

pub(super) fn names(c: &[Effect]) -> String {
    if c.is_empty() { "none".into() } else { c.iter().map(|c| c.name()).collect::<Vec<_>>().join(" then ") }
}

/// The `## Answer` section: per material, one sentence generated from its outcome — what the
/// model misses (the effects named, with the family-wise p that named each), or that nothing
/// passed the guard (with the smallest p tried); and whether the Weibull law fits the data once
/// they are in (the final model's Anderson–Darling and Kolmogorov–Smirnov bootstrap p against α).
pub(super) fn answer(s: &DiscrepancyStudy, results: &[MaterialResult]) -> String {
    let alpha = s.discrepancy.alpha;
    let model = if results.iter().any(|r| r.crush.is_some()) { "Weibull–Hertz" } else { "Weibull" };
    let lines: Vec<String> = results
        .iter()
        .map(|r| {
            let a = r.outcome.after();
            let what = if r.crush.is_some() { "particles" } else { "specimens" };
            let ev = &r.outcome.evidence;
            let misses = if r.outcome.named.is_empty() {
                // The nearest candidate among those the data identify (a law whose fit is not
                // identified is no candidate whatever its p).
                let tried = || ev.iter().filter(|e| e.skipped.is_none() && e.p_family.is_finite());
                match tried().filter(|e| unidentified(e).is_none()).min_by(|x, y| x.p_family.total_cmp(&y.p_family)) {
                    Some(e) => format!("no candidate effect passes the guard, so the data show no effect the {model} model misses at α = {alpha} — which does not show that none is there (the smallest family-wise p, `{}`, is {})", e.candidate.name(), p_text(e.p_family, e.replicates)),
                    None if tried().next().is_some() => format!("no candidate effect passes the guard, so the data show no effect the {model} model misses at α = {alpha} (no candidate law is identified by these data)"),
                    None => format!("the loop names no effect the {model} model misses — there was no candidate effect to try"),
                }
            } else {
                let named: Vec<String> = r.outcome.named.iter().filter_map(|c| ev.iter().find(|e| e.named && &e.candidate == c)).map(|e| format!("`{}` (family-wise p {})", e.candidate.name(), p_text(e.p_family, e.replicates))).collect();
                format!("the {model} model misses {}", named.join(", then "))
            };
            let below = |p: f64| if p < alpha { format!(" (below {alpha})") } else { String::new() };
            let ad_ks = format!("Anderson–Darling p {}{}, Kolmogorov–Smirnov p {}{}", eq_p(a.p_ad, a.replicates), below(a.p_ad), eq_p(a.p_ks, a.replicates), below(a.p_ks));
            let fits = |st: &super::workflow::Stage| st.p_ad >= alpha && st.p_ks >= alpha;
            let base_fits = fits(r.outcome.before());
            let with = match r.outcome.named.len() {
                0 => "",
                1 if base_fits == fits(a) => "with it, as without, ",
                1 => "with it ",
                _ if base_fits == fits(a) => "with them, as without, ",
                _ => "with them ",
            };
            // A p within a factor 2 of α: the verdict "fits" is a narrow one.
            let near = match (a.p_ad < 2.0 * alpha, a.p_ks < 2.0 * alpha) {
                (true, true) => ", though both lie near it",
                (true, false) => ", though the Anderson–Darling p lies near it",
                (false, true) => ", though the Kolmogorov–Smirnov p lies near it",
                _ => "",
            };
            let fit = if !fits(a) {
                format!("{with}the Weibull law fits these data poorly ({ad_ks}): a departure in the shape of the distribution that no recorded factor explains")
            } else {
                format!("{with}the Weibull law fits these data ({ad_ks}, neither below {alpha}{near})")
            };
            format!("**{}** ({} {what}): {misses}; {fit}.", r.label, r.sample.strength.len())
        })
        .collect();
    let body = if lines.len() == 1 { lines[0].clone() } else { lines.iter().map(|l| format!("* {l}")).collect::<Vec<_>>().join("\n") };
    format!("## Answer\n\n{body}\n")
}

pub(super) fn headline(r: &MaterialResult) -> String {
    let (b, a) = (r.outcome.before(), r.outcome.after());
    // Without a recorded factor the residuals have nothing to be diagnosed against: G is 0 by
    // construction and says nothing.
    let gap = if b.findings.is_empty() { "no recorded factor to diagnose the residuals against".to_string() } else { format!("gap G {:.1} → {:.1}", b.gap, a.gap) };
    format!("{}: effects named: {}; {gap}; Weibull modulus {} → {}", r.label, names(&r.outcome.named), modulus_text(&b.model), modulus_text(&a.model))
}

/// The model's Weibull modulus in words: one value, or the range over the levels of a factor
/// with a modulus per level, or the two populations' moduli.
pub(super) fn modulus_text(m: &crate::strength::ModelFit) -> String {
    let (lo, hi) = m.modulus_range();
    if let Some(l) = m.law.as_ref().filter(|l| l.kind == crate::strength::flaws::Populations::Threshold) {
        format!("{lo:.1} (above a threshold of {:.1} MPa)", l.threshold / 1e6)
    } else if m.law.is_some() {
        format!("{lo:.1} and {hi:.1} (two populations)")
    } else if m.scale_columns.is_empty() {
        format!("{lo:.1}")
    } else {
        format!("{lo:.1}–{hi:.1} (by level)")
    }
}

/// A covariate's range in words and in its unit: `diameter_m` in mm, `temperature_c` in °C, a
/// range whose ends print alike as one value.
fn covariate_range(name: &str, lo: f64, hi: f64) -> String {
    let (scale, unit, d) = match name {
        "diameter_m" => (1e3, " mm", 3),
        "temperature_c" => (1.0, " °C", 0),
        _ => (1.0, "", 4),
    };
    let (a, b) = (format!("{:.d$}", lo * scale), format!("{:.d$}", hi * scale));
    let shown = name.strip_suffix("_m").or_else(|| name.strip_suffix("_c")).filter(|_| !unit.is_empty()).unwrap_or(name);
    if a == b { format!("{shown} = {a}{unit}") } else { format!("{shown} in [{a}, {b}]{unit}") }
}

/// For a named temperature softening (strength × r per 100 °C) in a crush material with an
/// operating temperature to predict at: what the rate means there — the strength at that
/// temperature as a multiple of the strength at each tested temperature, r^((T − T_test)/100).
/// Empty otherwise.
fn temperature_ratio(e: &super::workflow::Evidence, r: &MaterialResult) -> String {
    let (Some(spec), crate::strength::Effect::Temperature, Some((_, per_100, _))) = (&r.crush, &e.candidate, &e.parameter) else { return String::new() };
    let Some(t) = spec.predict.get("temperature_c").and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64))) else { return String::new() };
    let mut tested = r.temperatures_c.clone();
    tested.sort_by(f64::total_cmp);
    tested.dedup();
    let parts: Vec<String> = tested.iter().filter(|&&at| at != t).map(|&at| format!("× {:.3} of its strength at {at} °C", per_100.powf((t - at) / 100.0))).collect();
    if parts.is_empty() || !per_100.is_finite() {
        return String::new();
    }
    format!("; at the study's operating temperature, {t} °C, the strength is {}", parts.join(", "))
}

/// Why the breaking probability with every known origin acting (`known`, at the first horizon)
/// differs from the one-law base model's (`base`, modulus `one_m`), generated from the numbers:
/// with one origin they are one law; within a factor of two they agree; above, the origin of
/// smallest modulus has the heavier lower tail, where impacts act; below, one law of mixed
/// origins is broadened by the mixture. The shared-modulus test says which column the data
/// support.
pub(super) fn known_against_one_law(o: &crate::strength::origins::Origins, one_m: f64, base: &LifetimeBand, known: &LifetimeBand, alpha: f64) -> String {
    let fits: Vec<&crate::strength::origins::OriginFit> = o.fits.iter().filter(|f| f.shape.is_finite()).collect();
    let moduli = fits.iter().map(|f| format!("{:.1} (\"{}\")", f.shape, f.origin)).collect::<Vec<_>>().join(", ");
    let ratio = known.estimate / base.estimate;
    if let [one] = fits.as_slice()
        && o.fits.len() == 1
    {
        return format!("Every break has one origin (\"{}\"): its law is the one law of every break, and the known-origins column's breaking probability is the base model's ({ratio:.2} times it); the bands differ by their bootstrap draws alone.", one.origin);
    }
    let at = format!("At {} yr the breaking probability with every origin acting is", known.years);
    if !(ratio.is_finite() && ratio > 0.0) {
        return format!("{at} {:.3e} against the one-law base model's {:.3e}.", known.estimate, base.estimate);
    }
    let why = if (0.5..=2.0).contains(&ratio) {
        format!("{at} within a factor of 2 of the one-law base model's ({ratio:.2} times it).")
    } else if ratio > 2.0 {
        let weakest = fits.iter().min_by(|a, b| a.shape.total_cmp(&b.shape));
        let tail = match weakest {
            Some(w) if w.shape < one_m => format!(
                " The impacts act in the lower tail of the strength laws, where a small modulus falls off slowly: origin \"{}\" has modulus {:.1}, below the {one_m:.1} of one law fitted to every break, and its law sets the probability there",
                w.origin, w.shape
            ),
            _ => format!(" The origins' moduli ({moduli}) and scales together put more probability in the lower tail, where impacts act, than one law of modulus {one_m:.1} fitted to every break"),
        };
        format!("{at} {ratio:.0} times the one-law base model's.{tail}.")
    } else {
        format!(
            "{at} {:.2} times the one-law base model's: one law fitted to breaks of several origins is broadened by their mixture (modulus {one_m:.1}, the origins' own {moduli}), and its lower tail, where impacts act, lies above theirs.",
            ratio
        )
    };
    let support = match &o.shared {
        Ok(t) if t.p < alpha => " The shared-modulus test rejects one modulus for every origin, so the known-origins column is the breaking probability the fractography supports.",
        Ok(t) => return format!("{why} The shared-modulus test does not reject one modulus for every origin (p = {:.3}): the moduli do not tell the two columns apart; read both with their bands.", t.p),
        Err(_) => "",
    };
    format!("{why}{support}")
}

/// How the family-wise p is made (the study's `guard`), and what a p at its floor means.
fn guard_sentence(n: &crate::strength::NamingSettings) -> String {
    let how = match n.guard {
        crate::strength::FamilyGuard::MinP => "A candidate's family-wise p is Westfall & Young's single-step min-P: each candidate's likelihood ratio Λ is first turned into its own p-value, from the null law of its Λ fitted to its bootstrap replicates (a scaled χ²), and the family-wise p is the share of replicates whose smallest such p lies at or below it. Each candidate is so judged against its own null distribution — a two-population law, whose Λ has a heavier null tail than Wilks' χ², does not raise the bar of the others — while the chance of naming any effect when none is there stays α. Each candidate's \"Λ critical\" is the value above which its family-wise p falls below α; candidates with as many parameters may have different ones, each from its own fitted null law.",
        crate::strength::FamilyGuard::MaxT => "A candidate's family-wise p is the max-T p: the share of replicates whose largest likelihood ratio Λ*, every candidate on Wilks' one-degree-of-freedom scale, reaches the candidate's Λ on that scale; the candidates share one critical value on that scale (\"Λ critical\" gives it on each candidate's own; `guard = \"min-p\"` judges each against its own null distribution instead).",
    };
    let floors: Vec<String> = super::guard::stages(n.bootstrap, n.sequential).iter().map(|b| format!("≤ {:.3} at B = {b}", 1.0 / (*b as f64 + 1.0))).collect();
    format!("{how} The tables give the family-wise p; `evidence.csv` gives each candidate's own bootstrap p beside it (`p_bootstrap`: the share of replicates whose Λ* reaches its Λ, which no decision reads alone). A p printed as \"≤ 1/(B + 1)\" ({}) means no replicate reached the data's Λ: it is the smallest p B replicates can give.", floors.join(", "))
}

/// How many parametric-bootstrap replicates a round draws, and why fewer than the most (each
/// material's table of models gives each round's count).
fn bootstrap_sentence(n: &crate::strength::NamingSettings) -> String {
    let stages = super::guard::stages(n.bootstrap, n.sequential);
    if stages.len() == 1 {
        return format!("Each round draws {} parametric-bootstrap replicates.", n.bootstrap);
    }
    let looks = stages[..stages.len() - 1].iter().map(|b| b.to_string()).collect::<Vec<_>>().join(", ");
    format!(
        "Each round draws its parametric-bootstrap replicates in stages ({looks}, then {}) and stops at the first stage where every decision it makes is settled: each p-value it decides by, and each share of failed refits, lies far enough from its level that the exact binomial test of that level rejects at β = {} (the pretest of Davidson & MacKinnon 2000). So a round draws all {} only where a decision lies near α (the table of models gives each round's count); `sequential = false` draws them all.",
        n.bootstrap,
        super::guard::PRETEST_LEVEL,
        n.bootstrap
    )
}

pub(super) fn summary(s: &DiscrepancyStudy, results: &[MaterialResult]) -> String {
    let crush = results.iter().any(|r| r.crush.is_some());
    let files = results.iter().any(|r| r.crush.is_none());
    let mut md = String::from(if crush { "# Discrepancy of the Weibull–Hertz strength model\n\n" } else { "# Discrepancy of the Weibull strength model\n\n" });
    let mut how = Vec::new();
    if crush {
        how.push(format!("Each crush dataset is reduced as in the deliverable (σ̄ at break, Hertz contact with R = d/2, {}) and fitted with one Weibull law.", s.contact.averaging.describe()));
    }
    if files {
        how.push("Each strength file's specimen strengths are fitted with one two-parameter Weibull law; its candidate effects are the recorded factors and size measure its study declares.".to_string());
    }
    md.push_str(&answer(s, results));
    md.push_str(&format!(
        "\n## How the workflow decides\n\n{} The workflow then looks for structure the model misses, names the missing effect only when it passes the guard (family-wise bootstrap p < {} over every candidate and factor tried, ΔBIC < 0, better {}-fold cross-validated log score), adds it and diagnoses again. {} {}\n\nGap measure: {}.\n",
        how.join(" "),
        s.discrepancy.alpha,
        s.discrepancy.cv_folds,
        guard_sentence(&s.discrepancy),
        bootstrap_sentence(&s.discrepancy),
        GAP_MEASURE
    ));
    for r in results {
        let (b, a) = (r.outcome.before(), r.outcome.after());
        let what = if r.crush.is_some() { "particles" } else { "specimens" };
        md.push_str(&format!("\n## {} ({} {what}, `{}`)\n\n", r.label, r.sample.strength.len(), r.path.display()));
        let tested = crate::intake::observed::describe_temperatures(&r.temperatures_c);
        let held = match &r.crush {
            Some(spec) if !r.lifetime.is_empty() => match spec.predict.get("temperature_c").filter(|_| r.outcome.after().model.effects.contains(&crate::strength::Effect::Temperature)) {
                Some(t) => format!(" Its lifetime after the named effects is at the study's predict.temperature_c = {t} (°C), not at the tests' temperature."),
                None if r.temperatures_c.iter().any(|t| *t != r.temperatures_c[0]) => format!(
                    " Its lifetimes below are for the tested particles at their own test temperatures, pooled, not at an operating temperature{}.",
                    spec.predict.get("temperature_c").map(|t| format!(": the study's predict.temperature_c = {t} (°C) applies only after the loop names temperature softening, and it named none")).unwrap_or_default()
                ),
                None => " Its lifetimes below hold at the tests' temperature, not at an operating temperature other than it.".to_string(),
            },
            _ => String::new(),
        };
        md.push_str(&format!("Tested at {tested}.{held}\n\n"));
        if !r.read_notes.is_empty() {
            md.push_str(&format!("Read from the file: {}.\n\n", r.read_notes.join("; ")));
        }
        let tally = r.sample.strength.view().tally();
        if !tally.complete() {
            md.push_str(&format!(
                "**{}.** Each is fitted as what its row says ({}); the residuals of those rows are randomised within what they allow (Dunn & Smyth 1996), and every bootstrap redraw is censored as the campaign censored its row{}.\n\n",
                tally.describe(what),
                [
                    (tally.right > 0, "a specimen that did not break by its value adds the probability of surviving it, not a break there"),
                    (tally.left > 0, "one that broke at or below its value the probability of breaking by it"),
                    (tally.interval > 0, "one counted in a class the probability of breaking within it"),
                ]
                .iter()
                .filter(|(on, _)| *on)
                .map(|(_, w)| *w)
                .collect::<Vec<_>>()
                .join("; "),
                if tally.interval > 0 { " (a class redraw falls into the class that holds it)" } else { "" }
            ));
        }
        md.push_str(&format!("**Effects named, in order: {}.**\n\n", names(&r.outcome.named)));
        md.push_str("| model | Weibull m | AD (p) | KS (p) | gap G | G, nothing missing | bootstrap replicates |\n|---|---|---|---|---|---|---|\n");
        for (i, st) in r.outcome.stages.iter().enumerate() {
            md.push_str(&format!(
                "| {}{} | {} | {:.3} ({}) | {:.3} ({}) | {:.1} | {:.1} | {} |\n",
                if i == 0 { "base" } else { "+ " },
                if i == 0 { String::new() } else { names(&st.model.effects) },
                modulus_text(&st.model),
                st.ad,
                p_text(st.p_ad, st.replicates),
                st.ks,
                p_text(st.p_ks, st.replicates),
                st.gap,
                st.gap_expected,
                match &st.unsettled {
                    Some(why) => format!("{} (all: {why})", st.replicates),
                    None => st.replicates.to_string(),
                }
            ));
        }
        let df: usize = b.findings.iter().map(|f| f.df).sum();
        if b.findings.is_empty() {
            md.push_str("\nThe file records no factor to diagnose the residuals against: G is 0 by construction and says nothing here.\n\n");
        } else {
            let levels = if r.sample.levels.is_empty() { "" } else { "; per categorical factor of L levels, L − 1 for the location and again for the scatter of its levels of 3 or more specimens" };
            md.push_str(&format!(
                "\nWith nothing missing, G of the base model would be about {df} (one per numeric covariate diagnosed{levels}). The column \"G, nothing missing\" gives each model's own expectation, G's mean over that round's parametric bootstrap: a covariate whose effect a model fits leaves its term near 0, so it falls as effects are named. The final model's G is {:.1} against {:.1}.\n\n",
                a.gap, a.gap_expected
            ));
        }
        if r.outcome.evidence.is_empty() {
            md.push_str("The data record no factor and no size measure and no two-population law was asked for: there is no candidate effect to name, and the workflow can only diagnose the Weibull law itself (below).\n");
        } else {
            md.push_str("| round | candidate | Λ | Λ critical | p (family) | ΔBIC (< 0 favours it) | ΔCV log score (> 0 favours it) | parameter | verdict |\n|---|---|---|---|---|---|---|---|---|\n");
            for e in &r.outcome.evidence {
                md.push_str(&evidence_row(e));
            }
            md.push_str(&failures_sentence(&r.outcome.evidence));
            // What each named effect says, as fitted in the round that named it (a size effect's
            // weakest-link test in the final model follows below).
            for e in r.outcome.evidence.iter().filter(|e| e.named && e.weakest_link.is_none() && !e.meaning.is_empty()) {
                md.push_str(&format!("\n`{}` (named in round {}): {}{}.\n", e.candidate.name(), e.round, e.meaning, temperature_ratio(e, r)));
            }
            // Several laws in place of the Weibull law passing: why the named one.
            let is_law = |e: &&crate::discrepancy::workflow::Evidence| matches!(e.candidate, crate::strength::Effect::Populations(_));
            let named_round = r.outcome.evidence.iter().filter(is_law).find(|e| e.named).map(|e| e.round);
            let laws: Vec<&crate::discrepancy::workflow::Evidence> = r.outcome.evidence.iter().filter(is_law).filter(|e| e.passed && Some(e.round) == named_round).collect();
            if let (true, Some(named)) = (laws.len() > 1, laws.iter().find(|e| e.named)) {
                let others: Vec<String> = laws.iter().filter(|e| !e.named).map(|o| format!("`{}` (ΔBIC {:.1}, {})", o.candidate.name(), o.delta_bic, o.parameters)).collect();
                md.push_str(&format!(
                    "\n{} laws in place of the Weibull law pass the guard; they describe one departure, so the one with the lower BIC is named: `{}` (ΔBIC {:.1}, {} extra parameter{}) against {}.\n",
                    if laws.len() == 2 { "Both".to_string() } else { format!("All {}", laws.len()) },
                    named.candidate.name(), named.delta_bic, named.parameters, if named.parameters == 1 { "" } else { "s" }, others.join(" and ")
                ));
            }
        }
        let k_of = |e: &crate::strength::Effect| match e {
            crate::strength::Effect::Factor(crate::strength::factors::Factor { form: crate::strength::factors::Form::Size(m), .. }) => m.k(),
            _ => 1.0,
        };
        // A named size effect is tested in the final model; one not named, as a candidate
        // against the base model.
        for (e, w) in &r.outcome.size_tests {
            let with = if r.outcome.named.len() > 1 { " (the other named effects refitted under the tie)" } else { "" };
            md.push_str(&format!("\nWeakest-link test of `{}` in the final model{with}: {}.\n", e.name(), w.sentence(k_of(e))));
        }
        for e in r.outcome.evidence.iter().filter(|e| e.round == 0 && !r.outcome.named.contains(&e.candidate)) {
            if let Some(w) = &e.weakest_link {
                md.push_str(&format!("\nWeakest-link test of `{}` (not named) against the base model: {}.\n", e.candidate.name(), w.sentence(k_of(&e.candidate))));
            }
        }
        if let Some(f) = b.findings.first() {
            match &f.worst_level {
                None => md.push_str(&format!(
                    "\nLargest residual trend before: `{}` (Spearman ρ = {:.2}, permutation p = {:.3}); the residuals depart most for {} (mean residual {:+.2}).\n",
                    f.covariate, f.rho, f.p, covariate_range(&f.covariate, f.worst_range.0, f.worst_range.1), f.worst_range.2
                )),
                Some(level) if f.scatter => md.push_str(&format!(
                    "\nLargest residual difference before: in the scatter between the levels of `{}` (Kruskal–Wallis H of the absolute deviations from the level medians = {:.2} on {} df, permutation p = {:.3}); the scatter departs most at \"{level}\" (mean absolute deviation {:.2} against {:.2} over all specimens).\n",
                    f.covariate, f.statistic, f.df, f.p, f.worst_range.2, f.worst_range.1
                )),
                Some(level) => md.push_str(&format!(
                    "\nLargest residual difference before: between the levels of `{}` (Kruskal–Wallis H = {:.2} on {} df, permutation p = {:.3}); the residuals depart most at \"{level}\" (mean residual {:+.2}).\n",
                    f.covariate, f.statistic, f.df, f.p, f.worst_range.2
                )),
            }
        }
        if let Some(f) = a.findings.first() {
            match &f.worst_level {
                None => md.push_str(&format!("After: largest trend `{}` (ρ = {:.2}, p = {:.3}).\n", f.covariate, f.rho, f.p)),
                Some(_) if f.scatter => md.push_str(&format!("After: largest difference in the scatter between the levels of `{}` (H = {:.2}, p = {:.3}).\n", f.covariate, f.statistic, f.p)),
                Some(_) => md.push_str(&format!("After: largest difference between the levels of `{}` (H = {:.2}, p = {:.3}).\n", f.covariate, f.statistic, f.p)),
            }
        }
        if a.p_ad < s.discrepancy.alpha || a.p_ks < s.discrepancy.alpha {
            let (ad, ks) = (a.p_ad < s.discrepancy.alpha, a.p_ks < s.discrepancy.alpha);
            let tests = match (ad, ks) {
                (true, true) => format!("Anderson–Darling p {} and Kolmogorov–Smirnov p {}", eq_p(a.p_ad, a.replicates), eq_p(a.p_ks, a.replicates)),
                (true, false) => format!("Anderson–Darling p {}", eq_p(a.p_ad, a.replicates)),
                _ => format!("Kolmogorov–Smirnov p {}", eq_p(a.p_ks, a.replicates)),
            };
            let tests = if tally.complete() { tests } else { format!("{tests} of the randomised quantile residuals") };
            let kinds = |round: Option<usize>| -> Vec<crate::strength::flaws::Populations> {
                let mut k: Vec<_> = r.outcome.evidence.iter().filter(|e| round.is_none_or(|k| e.round == k) && e.skipped.is_none()).filter_map(|e| if let crate::strength::Effect::Populations(k) = e.candidate { Some(k) } else { None }).collect();
                k.sort();
                k.dedup();
                k
            };
            let tried = kinds(Some(0));
            let explained = match (r.outcome.named.is_empty(), tried.is_empty()) {
                (true, true) => "and nothing recorded in the data explains the misfit".to_string(),
                (true, false) => format!("and nothing recorded in the data explains the misfit; of the laws tried in its place, {}", laws_not_passing(r, 0, &tried)),
                (false, true) => "even with the named effects".to_string(),
                (false, false) => {
                    // Were the laws offered in the last round (beside the named effects)?
                    let last = r.outcome.stages.len() - 1;
                    let law = |e: &&crate::discrepancy::workflow::Evidence| e.skipped.is_none() && matches!(e.candidate, crate::strength::Effect::Populations(_));
                    let offered = r.outcome.evidence.iter().filter(law).any(|e| e.round == last);
                    let law_named = r.outcome.named.iter().any(|e| matches!(e, crate::strength::Effect::Populations(_)));
                    match (law_named, offered) {
                        (true, _) => "even with the named effects".to_string(),
                        (false, true) => format!("even with the named effects; of the laws tried beside them, {}", laws_not_passing(r, last, &kinds(Some(last)))),
                        (false, false) => format!(
                            "even with the named effects; {} {} not tried beside {} (a law in place of the Weibull law is fitted beside scale effects of recorded columns only, not beside a partially pooled factor, a modulus per level or damage)",
                            crate::strength::flaws::Populations::words(&kinds(None)),
                            if kinds(None).len() == 1 { "was" } else { "were" },
                            r.outcome.named.iter().map(|e| format!("`{}`", e.name())).collect::<Vec<_>>().join(" and ")
                        ),
                    }
                }
            };
            // Values rounded to a few classes misfit any continuous law, whatever else is wrong.
            let mut values: Vec<f64> = r.sample.strength.x.clone();
            values.sort_by(f64::total_cmp);
            values.dedup();
            let n = r.sample.strength.x.len();
            let ties = if tally.complete() && 4 * values.len() <= n {
                format!(" The {n} strengths take only {} distinct values: values rounded to classes misfit every continuous law; if the rows are classes, declare them (`data.interval = {{ lower = …, upper = … }}`) and each specimen is fitted as breaking somewhere in its class.", values.len())
            } else {
                String::new()
            };
            md.push_str(&format!("\n**The Weibull law fits these data poorly** ({tests}, parametric bootstrap), {explained}: the departure lies in the shape of the distribution, not in a factor the data carry.{ties}\n"));
        }
        if let Some(o) = &r.origins {
            md.push_str(&format!(
                "\n**Failure origins** (column `{}`; ASTM C1239: each origin's Weibull law from its own breaks, the other origins' breaks right-censored at their strength, a specimen that did not break censored for every origin; 90 % bands from {} parametric-bootstrap refits, each redrawn specimen censored as its row was):\n\n| origin | breaks | Weibull m | m, 90 % band | scale σθ (MPa) | σθ, 90 % band (MPa) |\n|---|---|---|---|---|---|\n",
                o.column, s.lifetime.bootstrap
            ));
            for f in &o.fits {
                if f.shape.is_finite() {
                    md.push_str(&format!(
                        "| {} | {} | {:.2} | {:.2}–{:.2} | {:.1} | {:.1}–{:.1} |\n",
                        f.origin,
                        f.breaks,
                        f.shape,
                        f.shape_band.0,
                        f.shape_band.1,
                        f.scale / 1e6,
                        f.scale_band.0 / 1e6,
                        f.scale_band.1 / 1e6
                    ));
                } else {
                    md.push_str(&format!("| {} | {} | — | — | — | — |\n", f.origin, f.breaks));
                }
            }
            let lifetime = match (&r.crush, r.lifetime.iter().any(|(st, _)| st == "origins")) {
                (None, _) => "No lifetime is computed from them: a strength file has no contact that carries a strength to impacts.".to_string(),
                (Some(_), true) => "The lifetime below has every origin's law acting (column \"known origins\"): a particle survives N impacts only if it survives each origin's flaws, P_N = 1 − Π_k (1 − P_N,k).".to_string(),
                (Some(_), false) if r.temperatures_c.windows(2).any(|w| w[0] != w[1]) => format!(
                    "No lifetime is computed from them: the tests span {}, and each origin's law above pools them without a temperature term (the naming loop's effects do not enter the origins' laws), so no lifetime at one temperature follows; one `[[material]]` per test temperature (a file each) gives each temperature its origins' laws and their lifetime.",
                    crate::intake::observed::describe_temperatures(&r.temperatures_c)
                ),
                (Some(_), false) => format!("No lifetime is computed from them: {}.", o.fits.iter().find(|f| !f.shape.is_finite()).map_or_else(|| "an origin has no law".to_string(), |f| format!("origin \"{}\" has {} break{}, and a Weibull law needs at least two", f.origin, f.breaks, if f.breaks == 1 { "" } else { "s" }))),
            };
            md.push_str(&format!("\n{}\n", o.sentence(s.discrepancy.alpha, &lifetime)));
            if s.strength.iter().any(|set| set.key == r.key && set.competing_left_out()) {
                md.push_str("\nThe naming loop does not offer the latent competing-risks law (two flaw populations whose causes are unknown): the origins are known, and each origin's law above takes its place (`populations = [\"mixture\", \"competing_risks\", \"threshold\"]` offers it all the same).\n");
            }
            let few = o.few_words();
            if !few.is_empty() {
                md.push_str(&format!("\n{few}\n"));
            }
        }
        if r.crush.is_none() && r.origins.is_none() {
            md.push_str("\nNo lifetime is computed from a strength file (`lifetime.csv` holds no rows for it): its specimens carry no contact geometry that would carry their strength to an impact.\n");
        }
        if let Some(spec) = &r.crush {
        let known = r.lifetime.iter().find(|(st, _)| st == "origins").map(|(_, v)| v);
        let how = match (r.outcome.before().model.pivotal(), r.outcome.after().model.pivotal(), r.outcome.after().model.location_scale()) {
            (true, true, _) => "pivotal bootstrap of its parameters",
            (true, false, _) => "pivotal bootstrap of the base model's parameters, parametric bootstrap (refits) of the final model's",
            (false, _, true) => "parametric bootstrap in pivotal form, each redraw censored as the campaign censored its row",
            (false, _, false) => "parametric bootstrap in pivotal form of the base model, refits of the final model's, each redraw censored as the campaign censored its row",
        };
        md.push_str(&format!(
            "\n**Lifetime at {} m/s, η = {}, {} impacts a year** (particles with E = {} GPa, ν = {}, ρ = {} kg/m³; population of the measured particles; 90 % band of the strength model's joint draws — {how} — and Bayesian bootstrap of the population{}):\n\n| horizon | base model | final model |{}\n|---|---|---|{}\n",
            s.impact.reference_velocity_m_s,
            s.impact.energy_fraction,
            s.impact.impacts_per_year,
            spec.elastic.youngs_modulus_pa / 1e9,
            spec.elastic.poisson_ratio,
            spec.density_kg_m3,
            if known.is_some() { "; known origins: each origin's two-parameter law, parametric bootstrap of each, combined draw by draw" } else { "" },
            if known.is_some() { " known origins |" } else { "" },
            if known.is_some() { "---|" } else { "" },
        ));
        let (lb, la) = (&r.lifetime[0].1, &r.lifetime[1].1);
        let band = |x: &LifetimeBand| format!("{:.3e} [{:.2e}, {:.2e}]", x.estimate, x.q05, x.q95);
        for (i, (x, y)) in lb.iter().zip(la).enumerate() {
            let o = known.map(|k| format!(" {} |", band(&k[i]))).unwrap_or_default();
            md.push_str(&format!("| {} yr | {} | {} |{o}\n", x.years, band(x), band(y)));
        }
        if let (Some(k), Some(o)) = (known, &r.origins) {
            md.push_str(&format!("\n{}\n", known_against_one_law(o, b.model.shape(), &lb[0], &k[0], s.discrepancy.alpha)));
        }
        // The same file in a lifetime study gives another base-model estimate: say why.
        md.push_str(&format!(
            "\nBoth models predict with their maximum-likelihood fit (base model m = {:.2}). A lifetime study of the same file predicts by default with ASTM C1239's unbiased modulus (`[weibull] shape_estimate = \"unbiased\"`, smaller than the maximum-likelihood m for {} particles), so in the lower tail, where the impacts lie, its breaking probability is larger than the base model's here; `shape_estimate = \"mle\"` there gives this one.\n",
            b.model.shape(),
            r.sample.strength.len()
        ));
        }
        if r.crush.is_some() && !r.outcome.named.is_empty() {
            md.push_str(&format!(
                "\nAt {} m/s the impact stress lies far below the crush strengths, so the prediction is an extrapolation into the lower tail of the strength law, which the Weibull modulus governs: once the named effects explain part of the scatter the modulus is {:.1} instead of {:.1}, and the tail — hence the lifetime — changes accordingly.\n",
                s.impact.reference_velocity_m_s,
                a.model.shape(),
                b.model.shape()
            ));
        }
        if !r.power.is_empty() {
            if r.crush.is_some() {
                md.push_str("\n**Detection power** (new datasets of that many particles alone, drawn from the fitted model by the same generator the experiments study's crush tests use; rate of naming every effect found here, and the false-positive rate with no effect; an experiments study with `naming_draws` asks the same loop about today's particles plus more, with truths from the main study's state of knowledge):\n\n| particles | power | false positives |\n|---|---|---|\n");
            } else {
                md.push_str("\n**Detection power** (new datasets of that many specimens alone, their factor rows resampled from this file and their strengths drawn from the fitted model; rate of naming every effect found here, and the false-positive rate with no effect):\n\n| specimens | power | false positives |\n|---|---|---|\n");
            }
            for n in &s.power.particles {
                let pe = r.power.iter().find(|p| p.scenario == "effects" && p.particles == *n);
                let pn = r.power.iter().find(|p| p.scenario == "none" && p.particles == *n);
                let f = |p: Option<&PowerRow>| p.map(|p| format!("{}/{}", p.all, p.replicates)).unwrap_or_else(|| "–".into());
                md.push_str(&format!("| {n} | {} | {} |\n", f(pe), f(pn)));
            }
            md.push_str(&power_comment(r, s.discrepancy.alpha));
        }
    }
    md
}

/// What the power table's numbers say: why the power column is empty when nothing was named,
/// and whether the false positives over every size agree with the guard's α (their 90 % Wilson
/// band against α).
fn power_comment(r: &MaterialResult, alpha: f64) -> String {
    let mut out = String::new();
    if r.outcome.named.is_empty() {
        out.push_str("\nNothing was named on these data, so there is no effect whose detection power to measure (\"–\").");
    }
    let none: Vec<&PowerRow> = r.power.iter().filter(|p| p.scenario == "none").collect();
    let (k, n) = (none.iter().map(|p| p.all).sum::<usize>(), none.iter().map(|p| p.replicates).sum::<usize>());
    if n > 0 {
        let (lo, hi) = wilson90(k, n);
        let verdict = if lo > alpha {
            format!("more often than the guard's α = {alpha}: at these sizes the guard names effects that are not there more often than it should")
        } else if hi < alpha {
            format!("less often than the guard's α = {alpha}: at these sizes it is conservative")
        } else {
            format!("consistent with the guard's α = {alpha}")
        };
        out.push_str(&format!(
            "{}With no effect in the data the loop named one in {k} of {n} datasets over all sizes ({}; 90 % band {}–{}): {verdict}.",
            if out.is_empty() { "\n" } else { " " },
            crate::report::captions::percent(k as f64 / n as f64),
            crate::report::captions::percent(lo),
            crate::report::captions::percent(hi)
        ));
    }
    if out.is_empty() { out } else { format!("{out}\n") }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn covariate_ranges_are_in_their_units_and_one_value_is_one() {
        assert_eq!(covariate_range("diameter_m", 0.00102, 0.00141), "diameter in [1.020, 1.410] mm");
        assert_eq!(covariate_range("temperature_c", 20.0, 20.0), "temperature = 20 °C");
        assert_eq!(covariate_range("roundness", 0.7, 0.81), "roundness in [0.7000, 0.8100]");
    }
    use crate::discrepancy::workflow::Evidence;

    /// The Wilson bounds are where the score test is just significant at 90 %:
    /// (p̂ − p₀)² = z² p₀(1 − p₀)/n, an independent characterisation of the closed form.
    #[test]
    fn wilson_bounds_invert_the_score_test() {
        let z = 1.644_853_626_951_472_2_f64;
        for (k, n) in [(0, 10), (3, 10), (10, 10), (1, 200), (57, 100)] {
            let (lo, hi) = wilson90(k, n);
            assert!(lo <= k as f64 / n as f64 && k as f64 / n as f64 <= hi, "{k}/{n}: [{lo}, {hi}]");
            for p0 in [lo, hi] {
                if p0 > 0.0 && p0 < 1.0 {
                    let p = k as f64 / n as f64;
                    assert!(((p - p0).powi(2) - z * z * p0 * (1.0 - p0) / n as f64).abs() < 1e-12, "{k}/{n}: bound {p0}");
                }
            }
        }
        // k = 0: lower bound 0, upper z²/(n + z²); no data: [0, 1].
        let (lo, hi) = wilson90(0, 10);
        assert_eq!(lo, 0.0);
        assert!((hi - z * z / (10.0 + z * z)).abs() < 1e-15, "{hi}");
        assert_eq!(wilson90(0, 0), (0.0, 1.0));
    }

    fn evidence(named: bool, passed: bool, skipped: Option<&str>, se: f64) -> Evidence {
        Evidence {
            round: 2,
            candidate: Effect::Roundness,
            skipped: skipped.map(String::from),
            not_identified: None,
            loglik: -10.0,
            lr: 12.3456,
            p_bootstrap: 0.001,
            p_family: 0.01,
            lr_critical: 6.5,
            delta_bic: -8.1304,
            delta_cv: 0.3751,
            parameter: Some(("β".into(), 0.5, se)),
            band: None,
            band_pivotal: false,
            meaning: String::new(),
            shape: 5.0,
            passed,
            named,
            parameters: 1,
            weakest_link: None,
            failures: 0,
            replicates: 199,
        }
    }

    #[test]
    fn failed_refits_are_reported_and_too_many_leave_no_verdict() {
        let name = Effect::Roundness.name();
        let mut e = evidence(false, false, None, 0.125);
        assert_eq!(failures_sentence(std::slice::from_ref(&e)), "");
        e.failures = 25;
        assert_eq!(evidence_row(&e), format!("| 2 | {name} | 12.35 | 6.50 | 0.010 | -8.13 | 0.38 | β = 0.500 ± 0.125 | no verdict: 25 of 199 bootstrap refits failed (more than 10 %) |\n"));
        assert!(failures_sentence(std::slice::from_ref(&e)).contains(&format!("`{name}` in round 2: 25 of 199")));
        e.failures = 19;
        assert!(evidence_row(&e).ends_with("| not supported |\n"));
    }

    #[test]
    fn evidence_rows_carry_the_guard_numbers_and_their_verdict() {
        let name = Effect::Roundness.name();
        assert_eq!(evidence_row(&evidence(true, true, None, 0.125)), format!("| 2 | {name} | 12.35 | 6.50 | 0.010 | -8.13 | 0.38 | β = 0.500 ± 0.125 | **named** |\n"));
        assert_eq!(evidence_row(&evidence(false, true, None, f64::NAN)), format!("| 2 | {name} | 12.35 | 6.50 | 0.010 | -8.13 | 0.38 | β = 0.500 | passed, weaker |\n"));
        assert_eq!(evidence_row(&evidence(false, false, None, 0.125)), format!("| 2 | {name} | 12.35 | 6.50 | 0.010 | -8.13 | 0.38 | β = 0.500 ± 0.125 | not supported |\n"));
        assert_eq!(evidence_row(&evidence(false, false, Some("no roundness column"), 0.125)), format!("| 2 | {name} | | | | | | | skipped: no roundness column |\n"));
        // A two-population law's parameter has a profile band but no standard error.
        let law = Evidence { band: Some((0.2, 0.8)), ..evidence(false, false, None, f64::NAN) };
        assert_eq!(evidence_row(&law), format!("| 2 | {name} | 12.35 | 6.50 | 0.010 | -8.13 | 0.38 | β = 0.500 (90 % profile 0.200–0.800) | not supported |\n"));
        // A law the data do not identify: no estimate, the reason as its verdict.
        let why = "the modulus runs to the edge of [1, 100] (m = 100.00)";
        let unid = Evidence { not_identified: Some(why.into()), ..law.clone() };
        assert_eq!(evidence_row(&unid), format!("| 2 | {name} | 12.35 | 6.50 | 0.010 | -8.13 | 0.38 | – | not identified: {why} |\n"));
        // No replicate reached the observed Λ: p is at its floor 1/(B + 1), which B replicates
        // cannot resolve below.
        let floor = Evidence { p_family: 1.0 / 200.0, ..evidence(true, true, None, 0.125) };
        assert!(evidence_row(&floor).contains("| ≤ 0.005 |"), "{}", evidence_row(&floor));
        assert_eq!(p_text(0.01, 199), "0.010");
        assert_eq!(p_text(0.002, 499), "≤ 0.002");
    }
}

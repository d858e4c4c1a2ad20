//! `summary.md` of the main study: every sentence generated from the numbers it describes
//! (headline, whether accounting for the effects changes which particle is better, the
//! deliverable's shape hypothesis, what drives the answer, damage models side by side).

use super::sobol::SobolIndices;
use super::study::UqStudy;
use crate::lifetime::damage::DamageModel;
use crate::strength::{StrengthSpec, summarise};
use super::forms::Form;
use super::headline::{AVERAGED, AveragingRow, Headline, Row, pm};

/// "the deliverable's model (no effects)" or "the `x` model"; where a material carries its
/// failure origins' laws under it, said ("…; Gen 4: each failure origin's law").
pub(super) fn model_phrase(f: &Form) -> String {
    let name = f.setup.spec.name();
    let origins: Vec<String> = f.setup.materials.iter().filter_map(|m| origin_list(m).map(|l| format!("{}: each failure origin's law ({l})", m.model.label))).collect();
    match (name == "deliverable", origins.is_empty()) {
        (true, true) => "the deliverable's model (no effects)".into(),
        (true, false) => format!("the deliverable's model (no effects; {})", origins.join("; ")),
        (false, _) => format!("the `{name}` model"),
    }
}

/// The better particle for P(candidate worse) = p, and how sure.
pub(super) fn verdict(p: f64, names: [&str; 2]) -> String {
    let (better, q) = if p > 0.5 { (names[1], p) } else { (names[0], 1.0 - p) };
    if p == 0.5 {
        return "neither particle is better".into();
    }
    let sure = if q >= 0.99 {
        "with near certainty"
    } else if q >= 0.9 {
        "with high probability"
    } else if q >= 0.7 {
        "more likely than not"
    } else {
        "but the answer is close to a coin toss"
    };
    // Four decimals where three would round to 1.000 and contradict the P beside it.
    let shown = if q >= 0.9995 && q < 1.0 { format!("{q:.4}") } else { format!("{q:.3}") };
    format!("{better} is the better particle, {sure} ({shown})")
}

/// How sure a probability `q` ≥ 0.5 of one answer makes it, in words (the scale of [`verdict`]).
fn certainty(q: f64) -> &'static str {
    if q >= 0.99 {
        "near certainty"
    } else if q >= 0.9 {
        "high probability"
    } else if q >= 0.7 {
        "more likely than not"
    } else {
        "close to a coin toss"
    }
}

/// The effects each material carries under a model, in words.
pub(super) fn effects_phrase(f: &Form) -> String {
    f.setup
        .materials
        .iter()
        .map(|m| match origin_list(m) {
            Some(list) => format!("{}: each failure origin's law ({list})", m.model.label),
            None => format!("{}: {}", m.model.label, crate::strength::fit::names(m.model.fit.effects()).replace('+', ", ")),
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The failure origins a material's model carries ("\"Oberfläche\", \"Volumen\""), or None
/// where it carries one law.
fn origin_list(m: &super::setup::Material) -> Option<String> {
    (!m.origins.is_empty()).then(|| m.origins.iter().map(|o| format!("\"{}\"", o.fit.origin)).collect::<Vec<_>>().join(", "))
}

/// What the main study did with each material's failure-origin column, per strength model,
/// from the models themselves: which carry every origin's law and which fit one law to the
/// breaks of every origin (empty where no material names its origins).
pub(super) fn origins_paragraph(forms: &[Form]) -> String {
    let mut md = String::new();
    for j in 0..2 {
        let m = &forms[0].setup.materials[j];
        let Some(column) = &m.origin_column else { continue };
        let (known, pooled): (Vec<&Form>, Vec<&Form>) = forms.iter().partition(|f| !f.setup.materials[j].origins.is_empty());
        let quote = |v: &[&Form]| v.iter().map(|f| format!("`{}`", f.setup.spec.name())).collect::<Vec<_>>().join(", ");
        md.push_str(&format!("\n**Known failure origins of {}** (column `{column}`): ", m.model.label));
        let few = known.first().map_or_else(String::new, |f| crate::strength::origins::few_breaks(f.setup.materials[j].origins.iter().map(|o| &o.fit)));
        if let Some(f) = known.first() {
            let list = origin_list(&f.setup.materials[j]).unwrap_or_default();
            md.push_str(&format!(
                "in {} each origin ({list}) has its own two-parameter Weibull law, fitted to its breaks with the other origins' breaks censored (ASTM C1239), and a particle breaks at the first origin to fail: P = 1 − Π (1 − P_origin), exact under independent trials; under the damage models each origin's flaws accumulate damage on their own. ",
                if known.len() == 1 { format!("the strength model {}", quote(&known)) } else { format!("the strength models {}", quote(&known)) }
            ));
        }
        if !pooled.is_empty() {
            md.push_str(&format!(
                "{} {} effects on {}, and fit{} one law to the breaks of every origin (the origins' laws carry no effects).",
                if pooled.len() == 1 { format!("The strength model {}", quote(&pooled)) } else { format!("The strength models {}", quote(&pooled)) },
                if pooled.len() == 1 { "carries" } else { "carry" },
                m.model.label,
                if pooled.len() == 1 { "s" } else { "" }
            ));
        }
        md.push('\n');
        if !few.is_empty() {
            md.push_str(&format!("\n{few}\n"));
        }
    }
    md
}

/// The plain-language summary; every sentence with a number is built from the numbers it
/// states.
pub(super) fn summary(s: &UqStudy, forms: &[Form], ind: &[SobolIndices], varying: &[usize], outputs: &[String], headline: &Headline, averaging: &[AveragingRow], attrition: &[super::attrition::Row], per_year: &str) -> String {
    let st = &forms[0].setup;
    let [a, b] = [&st.materials[0].model.label, &st.materials[1].model.label];
    let names = [a.as_str(), b.as_str()];
    let primary_damage = st.models[0];
    let first_h = st.years[0];
    let row = |strength: &str, damage: DamageModel, years: f64| headline.rows.iter().find(|r| r.strength == strength && r.damage == damage && r.years == years);
    let mut md = format!("# {a} against {b}: breakage over {} years, with its uncertainty\n\n", st.years.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" and "));
    md.push_str(&format!(
        "{} Monte Carlo samples per strength model ({:?}, {} independent blocks for the standard errors) of every uncertain input; {} strength model{} compared; damage model of the headline: {}.{}\n\n",
        forms[0].prop.count(),
        s.propagation.method,
        forms[0].prop.blocks.len(),
        forms.len(),
        if forms.len() == 1 { "" } else { "s" },
        primary_damage.label(),
        crate::intake::synthetic_sentence("crush data", &st.materials.iter().map(|m| (m.model.label.as_str(), m.path.as_path())).collect::<Vec<_>>())
    ));
    // What the crush files' rows say beyond a break (specimens not broken by the rig, classes).
    for m in &st.materials {
        let t = m.sample.strength.view().tally();
        if !t.complete() {
            let bands = match s.strength.uncertainty {
                crate::strength::Uncertainty::Bootstrap => "bands from the bootstrap that censors each redraw as the campaign did",
                crate::strength::Uncertainty::Bayesian => "bands from the posterior of the censored likelihood",
            };
            md.push_str(&format!("**{}**: {}. Fitted as what the rows say, with {bands}.\n\n", m.model.label, t.describe("particles")));
        }
    }
    // At which temperature each material was tested, and what the comparison holds at.
    {
        use crate::lifetime::tested::{LifetimeAt, paragraph};
        let temps: Vec<Vec<f64>> = st.materials.iter().map(|m| m.temperatures_c()).collect();
        let tested: Vec<_> = st.materials.iter().zip(&temps).map(|(m, t)| m.tested(t)).collect();
        let at = if let (Some(th), Some(op)) = (&st.thermal, &s.operating) {
            let range = |i: usize| {
                let m = &st.inputs[i].marginal;
                let (lo, hi) = (m.quantile(0.0), m.quantile(1.0));
                if lo == hi { format!("{lo} °C") } else { format!("{lo}–{hi} °C") }
            };
            LifetimeAt::Operating {
                per_material: vec![range(th.temperature_inputs[0]), range(th.temperature_inputs[1])],
                by: format!("the temperature laws of `{}` ({} joint draws, input `temperature_law`; they move the Weibull scale and the particle's Young's modulus)", op.law.display(), th.laws.len()),
            }
        } else {
            let named: Vec<Option<String>> = st.materials.iter().map(|m| m.model.population.predicted_temperature()).collect();
            crate::lifetime::tested::named_or_tests(&tested, &named)
        };
        md.push_str(&paragraph(&tested, &at));
        md.push_str("\n\n");
    }
    // The answer first, in words and the plant's units, for the headline model.
    let strength = if forms.len() > 1 { AVERAGED.to_string() } else { forms[0].setup.spec.name() };
    if let Some(r) = row(&strength, primary_damage, first_h) {
        let of = |label: &str| attrition.iter().find(|x| x.strength == strength && x.model == primary_damage.name() && x.material == label);
        if let (Some(ra), Some(rb)) = (of(a), of(b)) {
            let all: usize = forms.iter().map(|f| f.prop.count()).sum();
            let n = if forms.len() > 1 { all } else { forms[0].prop.count() };
            // How much the margin rests on the models: the first year under each strength model
            // alone (the headline damage model), and P under each other damage model.
            let firsts: Vec<String> = forms
                .iter()
                .filter_map(|f| {
                    let name = f.setup.spec.name();
                    let at = |label: &str| attrition.iter().find(|x| x.strength == name && x.model == primary_damage.name() && x.material == label);
                    Some(format!("`{name}` {} against {}", crate::report::captions::percent(at(a)?.first_year[1]), crate::report::captions::percent(at(b)?.first_year[1])))
                })
                .collect();
            let others: Vec<String> = st.models.iter().skip(1).filter_map(|&d| row(&strength, d, first_h).map(|x| format!("{} {}", d.label(), if x.ties > 0.5 { format!("leaves both unbroken in {:.0} % of the samples (a tie)", 100.0 * x.ties) } else { format!("gives P = {:.3}", x.worse) }))).collect();
            let mut spread = String::new();
            if forms.len() > 1 {
                spread.push_str(&format!(" The margin rests on the strength models: the median share broken in year 1 ({a} against {b}) is {}.", firsts.join(", ")));
            }
            if !others.is_empty() {
                spread.push_str(&format!(" Among the other damage models, {}.", others.join("; ")));
            }
            md.push_str(&answer(names, (r.worse, r.se, n), [ra, rb], &strength, primary_damage.label(), per_year, first_h, &spread));
        }
    }
    md.push_str("## Headline\n\n");
    for l in &headline.lines {
        md.push_str(&format!("* {}\n", l.trim()));
    }
    md.push_str(&format!("\n| strength model | effects | weight (stacking) | {} |\n|---|---|---|{}\n", st.years.iter().map(|y| format!("P({a} worse), {y} yr")).collect::<Vec<_>>().join(" | "), "---|".repeat(st.years.len())));
    let n = forms[0].prop.count();
    for f in forms {
        let cells: Vec<String> = st.years.iter().map(|&y| row(&f.setup.spec.name(), primary_damage, y).map_or("–".into(), |r| pm(r.worse, r.se, f.prop.count()))).collect();
        md.push_str(&format!("| {} | {} | {:.3} | {} |\n", f.setup.spec.name(), effects_phrase(f), f.weight, cells.join(" | ")));
    }
    if forms.len() > 1 {
        // The average agrees in every sample only where every model's samples do.
        let all: usize = forms.iter().map(|f| f.prop.count()).sum();
        let cells: Vec<String> = st.years.iter().map(|&y| row(AVERAGED, primary_damage, y).map_or("–".into(), |r| pm(r.worse, r.se, all))).collect();
        md.push_str(&format!("| {AVERAGED} | | 1 | {} |\n", cells.join(" | ")));
    }

    // The question in plain words.
    if forms.len() > 1 {
        md.push_str(&format!("\n## Does accounting for the effects change which particle is better? ({first_h} yr, {})\n\n", primary_damage.label()));
        let base = forms.iter().find(|f| f.setup.spec == StrengthSpec::default());
        if let Some(r0) = base.and_then(|f| row(&f.setup.spec.name(), primary_damage, first_h)) {
            md.push_str(&format!("Under {} {a} breaks more than {b} with probability {}: {}.\n", base.map(model_phrase).unwrap_or_default(), pm(r0.worse, r0.se, n), verdict(r0.worse, names)));
            for f in forms.iter().filter(|f| f.setup.spec != StrengthSpec::default()) {
                let Some(r) = row(&f.setup.spec.name(), primary_damage, first_h) else { continue };
                // The naming loop may name nothing: then the model is the deliverable's.
                if f.setup.spec == StrengthSpec::Diagnosed && f.setup.materials.iter().all(|m| m.model.fit.effects().is_empty()) {
                    md.push_str(&format!("Under {}, the naming loop named no effect in either material's data: it is the deliverable's model, with probability {}.\n", model_phrase(f), pm(r.worse, r.se, n)));
                    continue;
                }
                let same = (r.worse > 0.5) == (r0.worse > 0.5);
                md.push_str(&format!(
                    "Under {} ({}), with probability {}: {}; accounting for these effects {} which particle is better.\n",
                    model_phrase(f),
                    effects_phrase(f),
                    pm(r.worse, r.se, n),
                    verdict(r.worse, names),
                    if same { "does not change" } else { "changes" }
                ));
            }
            if let Some(r) = row(AVERAGED, primary_damage, first_h) {
                // The largest weight, and every model that carries it as printed (a tie is said).
                let top = forms.iter().map(|f| f.weight).fold(f64::NEG_INFINITY, f64::max);
                let tied: Vec<String> = forms.iter().filter(|f| format!("{:.3}", f.weight) == format!("{top:.3}")).map(|f| model_phrase(f)).collect();
                let put = match tied.as_slice() {
                    [one] => format!("put {top:.3} on {one}"),
                    many => format!("put {top:.3} each on {}", many.join(" and ")),
                };
                let all: usize = forms.iter().map(|f| f.prop.count()).sum();
                md.push_str(&format!(
                    "\nThe stacking weights (from the cross-validated log density of the {} crush tests) {put}. Averaged over the strength models, P({a} breaks more) = {}: {}.\n",
                    forms[0].lpd[0].len() + forms[0].lpd[1].len(),
                    pm(r.worse, r.se, all),
                    verdict(r.worse, names)
                ));
            }
            // The deliverable's hypothesis, where the study states it: shape effects would
            // favour the candidate. Tested with the models whose shape effects were fitted to
            // both materials' data (which needs their roundness or sphericity columns).
            let shape: Vec<&Form> = forms.iter().filter(|f| f.setup.materials.iter().all(|m| m.model.fit.effects().iter().any(|e| e.is_contact_geometry()))).collect();
            if s.model_form.shape_hypothesis && !shape.is_empty() {
                let with: Vec<(String, f64, f64)> = shape.iter().filter_map(|f| row(&f.setup.spec.name(), primary_damage, first_h).map(|r| (model_phrase(f), r.worse, r.se))).collect();
                md.push_str(&shape_hypothesis(names, (r0.worse, r0.se), &with));
            }
        }
    }

    md.push_str("\n## Breaking probability per strength model (median and 90 % band)\n\n| strength model | material | horizon | median P | 90 % band |\n|---|---|---|---|---|\n");
    let strengths: Vec<String> = forms.iter().map(|f| f.setup.spec.name()).chain((forms.len() > 1).then(|| AVERAGED.to_string())).collect();
    for name in &strengths {
        for &y in &st.years {
            if let Some(r) = row(name, primary_damage, y) {
                for j in 0..2 {
                    md.push_str(&format!("| {name} | {} | {y} yr | {:.2e} | {:.1e} – {:.1e} |\n", names[j], r.median[j], r.band[j].0, r.band[j].1));
                }
            }
        }
    }

    md.push_str("\n## The strength models (per material: effects, modulus and 90 % range of the draws)\n\n| strength model | material | effects | m | other parameters |\n|---|---|---|---|---|\n");
    for f in forms {
        for m in &f.setup.materials {
            for o in &m.origins {
                let sums = summarise(&o.model.fit, &o.fit.draws);
                let scale = &sums[1];
                md.push_str(&format!(
                    "| {} | {} | failure origin \"{}\" ({} breaks) | {:.2} [{:.2}, {:.2}] | scale σθ = {:.1} [{:.1}, {:.1}] MPa |\n",
                    f.setup.spec.name(),
                    m.model.label,
                    o.fit.origin,
                    o.fit.breaks,
                    sums[0].estimate,
                    sums[0].q05,
                    sums[0].q95,
                    scale.estimate / 1e6,
                    scale.q05 / 1e6,
                    scale.q95 / 1e6
                ));
            }
            if !m.origins.is_empty() {
                continue;
            }
            let sums = summarise(&m.model.fit, &m.draws);
            let other: Vec<String> = sums.iter().skip(2).map(|p| format!("{} = {:.3} [{:.3}, {:.3}]", p.name, p.estimate, p.q05, p.q95)).collect();
            md.push_str(&format!("| {} | {} | {} | {:.2} [{:.2}, {:.2}] | {} |\n", f.setup.spec.name(), m.model.label, crate::strength::fit::names(m.model.fit.effects()), sums[0].estimate, sums[0].q05, sums[0].q95, other.join("; ")));
        }
    }

    md.push_str(&origins_paragraph(forms));

    // What the recorded factors of a model are predicted for.
    for (j, m) in st.materials.iter().enumerate() {
        let mut factors: Vec<String> = Vec::new();
        for f in forms {
            for e in f.setup.materials[j].model.fit.effects() {
                if let crate::strength::Effect::Factor(x) = e
                    && !factors.contains(&x.column)
                {
                    factors.push(x.column.clone());
                }
            }
        }
        if !factors.is_empty() {
            md.push_str(&format!("\n{} is predicted for {} — in the models that carry these factors; the others do not depend on them.\n", m.model.label, m.model.population.describe_factors(&factors)));
        }
    }

    md.push_str(&format!("\n## What drives it (Sobol' total indices, last horizon, strength model `{}`)\n\n", st.spec.name()));
    for (o, si) in ind.iter().enumerate() {
        let mut order: Vec<usize> = (0..varying.len()).collect();
        order.sort_by(|&p, &q| si.total[q].total_cmp(&si.total[p]));
        let top: Vec<String> = order.iter().take(3).map(|&k| format!("{} (S_T = {:.2}, S = {:.2})", st.inputs[varying[k]].name, si.total[k], si.first[k])).collect();
        md.push_str(&format!("* `{}`: {}\n", outputs[o], top.join("; ")));
        let neg: Vec<String> = si.negative().iter().map(|&k| st.inputs[varying[k]].name.clone()).collect();
        if !neg.is_empty() {
            md.push_str(&format!("  (negative estimates, i.e. zero within Monte Carlo error: {})\n", neg.join(", ")));
        }
    }

    md.push_str(&format!("\n## Damage models side by side (strength model `{}`)\n\n| model | horizon | P({a} worse) | both equal | median P {a} | median P {b} |\n|---|---|---|---|---|---|\n", st.spec.name()));
    let primary_rows: Vec<&Row> = headline.rows.iter().filter(|r| r.strength == st.spec.name()).collect();
    for r in &primary_rows {
        md.push_str(&format!("| {} | {} yr | {:.3} | {:.3} | {:.2e} | {:.2e} |\n", r.damage.label(), r.years, r.worse, r.ties, r.median[0], r.median[1]));
    }
    md.push('\n');
    md.push_str(&damage_sentences(*st.years.last().unwrap_or(&1.0), &primary_rows, names));
    md.push_str("The spread between the damage models is model-form uncertainty that more crush data cannot remove: it needs repeated-impact tests.\n");

    if averaging.len() > st.years.len() {
        md.push_str(&format!("\n## Averaging domain of σ̄ (deliverable's strength model, independent trials)\n\nEach domain starts at s0·a, where the radial surface stress turns tensile inside the contact of radius a (0 < s0 < 1, set by Poisson's ratio), and ends at a multiple of a or at the particle radius R.\n\n| domain | horizon | P({a} worse) | median P {a} | median P {b} |\n|---|---|---|---|---|\n"));
        for (d, years, worse, se, pa, pb) in averaging {
            md.push_str(&format!("| {d} | {years} yr | {worse:.4} ± {se:.4} | {pa:.2e} | {pb:.2e} |\n"));
        }
        md.push_str("\nEvery domain whose outer limit is a multiple of the contact radius gives σ̄ = r·p0 in the crush test and in the impact alike, so r cancels between the Weibull scale and the impact stress: those domains give identical answers up to Monte Carlo error. Only a domain reaching the particle radius (σ̄ depends on a/R, which differs between the crush at break and a 5 m/s impact) changes them.\n");
    }
    md
}

/// How each damage model's medians compare with independent trials', generated from the rows
/// at horizon `last` (years).
pub(super) fn damage_sentences(last: f64, rows: &[&Row], names: [&str; 2]) -> String {
    let Some(indep) = rows.iter().find(|r| r.damage == DamageModel::Independent && r.years == last) else { return String::new() };
    let mut out = String::new();
    for r in rows.iter().filter(|r| r.damage != DamageModel::Independent && r.years == last) {
        let parts: Vec<String> = (0..2)
            .map(|j| {
                let (x, y) = (r.median[j], indep.median[j]);
                let times = |r: f64| if r >= 1000.0 { format!("{r:.1e}") } else if r >= 10.0 { format!("{r:.0}") } else { format!("{r:.2}") };
                let cmp = if x == 0.0 && y > 0.0 {
                    "no breakage in most samples (below its energy threshold)".to_string()
                } else if x > y {
                    format!("larger median probabilities ({x:.2e} against {y:.2e}, × {})", times(x / y))
                } else if x < y {
                    format!("smaller median probabilities ({x:.2e} against {y:.2e}, × {})", times(x / y))
                } else {
                    format!("the same median probability ({x:.2e})")
                };
                format!("for {} {cmp}", names[j])
            })
            .collect();
        // Where most samples tie (under a threshold model: neither breaks), P(… breaks more)
        // alone would read as a verdict.
        let tie = if r.ties >= 0.005 { format!(", and in {} of the samples the two tie (equal P_break{})", crate::report::captions::percent(r.ties), if r.median == [0.0, 0.0] { ": neither breaks" } else { "" }) } else { String::new() };
        out.push_str(&format!("Over {last} years {} gives, compared with independent trials, {}; under it P({} breaks more) = {:.3}{tie}.\n", r.damage.label(), parts.join(", and "), names[0], r.worse));
    }
    out
}

/// The `## Answer` section: which particle breaks less, by how much in the plant's units and how
/// sure, in one sentence generated from the numbers, and the headline model's attrition.
/// `p`: P(candidate breaks more) at horizon `years`, its Monte Carlo se and the samples behind
/// it; `rows`: the headline model's attrition of candidate and reference.
/// `spread`: what the margin looks like under each strength model and each other damage model
/// alone (a sentence, or empty).
#[allow(clippy::too_many_arguments)]
fn answer(names: [&str; 2], p: (f64, f64, usize), rows: [&super::attrition::Row; 2], strength: &str, damage: &str, per_year: &str, years: f64, spread: &str) -> String {
    use crate::report::captions::{percent, with_band, years_text};
    let (worse, se, n) = p;
    // The better particle is the one that breaks less in most samples.
    let (better, other) = if worse > 0.5 { (1, 0) } else { (0, 1) };
    let sure = certainty(worse.max(1.0 - worse));
    let share = |r: &super::attrition::Row| percent(r.first_year[1]);
    let to_1 = |r: &super::attrition::Row| if r.to_1pct[1].is_infinite() { "more than 100 years".to_string() } else { format!("{} years", years_text(r.to_1pct[1])) };
    let (rb, ro) = (rows[better], rows[other]);
    // How many times less, to two figures (beyond a thousand, the power of ten it rounds to).
    let ratio = match ro.first_year[1] / rb.first_year[1] {
        q if rb.first_year[1] > 0.0 && q.is_finite() && q >= 1000.0 => format!(", about {} times less", crate::report::canvas::power_of_ten(&10f64.powf(q.log10().round()))),
        q if rb.first_year[1] > 0.0 && q.is_finite() && q > 1.0 => format!(", {} times less", crate::report::captions::sig2(q)),
        _ => String::new(),
    };
    let head = if worse == 0.5 {
        format!("**Neither particle breaks less than the other**: in the first year of operation a median {} of the {} inventory breaks and {} of the {}.", share(rows[0]), names[0], share(rows[1]), names[1])
    } else {
        format!(
            "**{} breaks less than {}**: in the first year of operation ({per_year} impacts per particle) a median {} of its inventory breaks against {} of {}'s{ratio}, and 1 % of it is broken after {} against {}.",
            names[better],
            names[other],
            share(rb),
            share(ro),
            names[other],
            to_1(rb),
            to_1(ro)
        )
    };
    let models = if strength == AVERAGED { "averaged over the strength models with their stacking weights".to_string() } else { format!("under the strength model `{strength}`") };
    let how_sure = format!(
        "How sure: P({} breaks more than {} over {}) = {}, {models}, with {damage} — {sure}",
        names[0],
        names[1],
        if years == 1.0 { "1 year".to_string() } else { format!("{years} years") },
        pm(worse, se, n)
    );
    let mut md = format!("## Answer\n\n{head} {how_sure}.{}\n\n", spread);
    let b3 = |b: &[f64; 3], f: &dyn Fn(f64) -> String| with_band(&f(b[1]), &f(b[0]), &f(b[2]));
    let y = |v: f64| if v.is_infinite() { "> 100".to_string() } else { years_text(v) };
    md.push_str("| material | broken in year 1 | years to 1 % broken | years to 10 % broken |\n|---|---|---|---|\n");
    for r in rows {
        md.push_str(&format!("| {} | {} | {} | {} |\n", r.material, b3(&r.first_year, &percent), b3(&r.to_1pct, &y), b3(&r.to_10pct, &y)));
    }
    md.push_str(&format!("\n(Median and 90 % band over the uncertain inputs, from {} of the Monte Carlo samples; every strength and damage model in \"In a plant engineer's units\" below.)\n\n", rows[0].samples));
    md
}

/// The shape hypothesis (`model_form.shape_hypothesis`): accounting for the particles' shape
/// moves the answer toward the candidate `names[0]`. Judged by the direction of the change of
/// P(candidate breaks more) from the model without shape effects (`base`: value, Monte Carlo
/// se) to each model with them (`with`: phrase, value, se) — beyond two standard errors of the
/// difference (taken as independent) — not by which particle ends up better.
fn shape_hypothesis(names: [&str; 2], base: (f64, f64), with: &[(String, f64, f64)]) -> String {
    let [a, b] = names;
    let mut md = format!(
        "\nThe study tests the hypothesis that accounting for the particles' shape (roundness, non-sphericity) moves the answer toward its candidate, {a} (the deliverable expected this of its granulated particle). "
    );
    let parts: Vec<String> = with.iter().map(|(phrase, w, _)| format!("under {phrase} P({a} breaks more than {b}) = {w:.3}")).collect();
    // +1 toward the candidate, −1 away, 0 within the noise.
    let direction: Vec<i8> = with.iter().map(|(_, w, se)| if (base.0 - w).abs() <= 2.0 * se.hypot(base.1) { 0 } else if *w < base.0 { 1 } else { -1 }).collect();
    let better = |w: f64| if w < 0.5 { a } else { b };
    let end = with.iter().map(|(_, w, _)| better(*w)).collect::<std::collections::BTreeSet<_>>();
    let ending = match end.iter().next() {
        Some(p) if end.len() == 1 => format!(" ({p} {} the better particle)", if better(base.0) == *p { "stays" } else { "becomes" }),
        _ => String::new(),
    };
    let judged = if direction.iter().all(|&d| d == 1) {
        format!("supported — accounting for shape moves the answer toward {a}{ending}")
    } else if direction.iter().all(|&d| d == -1) {
        format!("not supported — accounting for shape moves the answer away from {a}, toward {b}{ending}")
    } else if direction.iter().all(|&d| d == 0) {
        "not supported — accounting for shape changes the answer by less than two Monte Carlo standard errors".to_string()
    } else {
        "not settled — the models with shape effects move the answer in different directions".to_string()
    };
    md.push_str(&format!("With shape effects fitted to these data, {}, against {:.3} without them. The hypothesis is {judged}.\n", parts.join(", "), base.0));
    md
}

#[cfg(test)]
mod tests {
    //! The summary's sentences and the averaged headline against hand-made rows: a wrong
    //! comparison, ratio or weight would show here.
    use super::super::headline::{Row, pm};
    use super::*;

    fn row(damage: DamageModel, years: f64, worse: f64, se: f64, ties: f64, median: [f64; 2]) -> Row {
        Row { strength: "m".into(), damage, years, worse, se, ties, median, band: [(0.0, 1.0); 2] }
    }

    #[test]
    fn verdict_names_the_better_particle_and_how_sure() {
        let n = ["Gen 4", "BL 16/30"];
        assert_eq!(verdict(0.9999, n), "BL 16/30 is the better particle, with near certainty (0.9999)");
        assert_eq!(verdict(0.05, n), "Gen 4 is the better particle, with high probability (0.950)");
        assert_eq!(verdict(0.75, n), "BL 16/30 is the better particle, more likely than not (0.750)");
        assert_eq!(verdict(0.4, n), "Gen 4 is the better particle, but the answer is close to a coin toss (0.600)");
        assert_eq!(verdict(0.5, n), "neither particle is better");
    }

    /// A user's own candidate at 0.977 without shape effects and 0.768 with them: accounting for
    /// shape moved the answer away from it, although it stays the better particle — the
    /// hypothesis is not supported (it used to read "supported (… is favoured)").
    #[test]
    fn the_shape_hypothesis_is_judged_by_the_direction_of_change() {
        let n = ["Kandidat K7", "BL 16/30"];
        let away = shape_hypothesis(n, (0.023, 0.002), &[("the model `shape`".into(), 0.232, 0.004)]);
        assert!(away.contains("moves the answer toward its candidate, Kandidat K7"), "{away}");
        assert!(away.ends_with("under the model `shape` P(Kandidat K7 breaks more than BL 16/30) = 0.232, against 0.023 without them. The hypothesis is not supported — accounting for shape moves the answer away from Kandidat K7, toward BL 16/30 (Kandidat K7 stays the better particle).\n"), "{away}");
        let toward = shape_hypothesis(n, (0.6, 0.01), &[("m".into(), 0.3, 0.01)]);
        assert!(toward.ends_with("The hypothesis is supported — accounting for shape moves the answer toward Kandidat K7 (Kandidat K7 becomes the better particle).\n"), "{toward}");
        let noise = shape_hypothesis(n, (0.6, 0.01), &[("m".into(), 0.59, 0.01)]);
        assert!(noise.ends_with("not supported — accounting for shape changes the answer by less than two Monte Carlo standard errors.\n"), "{noise}");
        let mixed = shape_hypothesis(n, (0.6, 0.01), &[("m".into(), 0.3, 0.01), ("k".into(), 0.9, 0.01)]);
        assert!(mixed.ends_with("not settled — the models with shape effects move the answer in different directions.\n"), "{mixed}");
    }

    #[test]
    fn pm_never_prints_a_zero_error() {
        assert_eq!(pm(1.0, 0.0, 1000), "1.0000 (in all 1000 samples)");
        assert_eq!(pm(0.9999, 2.9e-6, 10), "0.9999 ± 2.9e-6");
        assert_eq!(pm(0.25, 0.0123, 10), "0.2500 ± 0.0123");
    }

    #[test]
    fn damage_sentences_compare_each_model_with_independent_trials() {
        let names = ["A", "B"];
        let rows = [
            row(DamageModel::Independent, 10.0, 0.9, 0.0, 0.0, [1e-3, 2e-4]),
            row(DamageModel::VogelPeukert, 10.0, 0.8, 0.0, 0.0, [0.0, 2e-3]),
            row(DamageModel::TavaresKing, 10.0, 0.7, 0.0, 0.0, [5e-2, 2e-4]),
            // Another horizon: ignored.
            row(DamageModel::TavaresKing, 1.0, 0.1, 0.0, 0.0, [1.0, 1.0]),
        ];
        let refs: Vec<&Row> = rows.iter().collect();
        let text = damage_sentences(10.0, &refs, names);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 2, "{text}");
        assert_eq!(
            lines[0],
            "Over 10 years Vogel–Peukert gives, compared with independent trials, for A no breakage in most samples (below its energy threshold), and for B larger median probabilities (2.00e-3 against 2.00e-4, × 10); under it P(A breaks more) = 0.800."
                .replace("Vogel–Peukert", DamageModel::VogelPeukert.label())
        );
        assert_eq!(
            lines[1],
            "Over 10 years Tavares–King gives, compared with independent trials, for A larger median probabilities (5.00e-2 against 1.00e-3, × 50), and for B the same median probability (2.00e-4); under it P(A breaks more) = 0.700."
                .replace("Tavares–King", DamageModel::TavaresKing.label())
        );
        // Without an independent-trials row there is nothing to compare with.
        assert_eq!(damage_sentences(10.0, &refs[1..], names), "");
        // Neither breaks under the threshold model in most samples: P(A breaks more) = 0 is a
        // tie, and the sentence says so (it used to end at "= 0.000").
        let rows = [row(DamageModel::Independent, 1.0, 0.9, 0.0, 0.0, [1e-3, 2e-4]), row(DamageModel::VogelPeukert, 1.0, 0.0, 0.0, 0.97, [0.0, 0.0])];
        let text = damage_sentences(1.0, &rows.iter().collect::<Vec<_>>(), names);
        assert!(text.trim_end().ends_with("under it P(A breaks more) = 0.000, and in 97 % of the samples the two tie (equal P_break: neither breaks)."), "{text}");
    }
}

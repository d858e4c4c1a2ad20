//! `summary.md` of an experiments study: every sentence generated from the numbers it states.

use crate::report::prob_text as prob;
use crate::report::pm_text as pm;
use super::plan::{Allocated, Evaluated, first_step};
use super::preposterior::Scored;
use super::state::State;
use super::preposterior::Metrics;
use super::study::{ExperimentsStudy, Objective};

/// A reweighted evaluation is reliable with a median effective sample size of at least this…
pub const RELIABLE_ESS: f64 = 100.0;
/// …and fewer than this share of its simulated datasets collapsed.
pub const RELIABLE_COLLAPSED: f64 = 0.05;

/// Whether an evaluation's reweighting degenerated ([`RELIABLE_ESS`], [`RELIABLE_COLLAPSED`]).
pub fn unreliable(m: &Metrics, outer: usize) -> bool {
    m.median_ess < RELIABLE_ESS || m.collapsed as f64 >= RELIABLE_COLLAPSED * outer as f64
}

/// The summary and the headline lines printed by the CLI.
pub struct Summary {
    /// Markdown.
    pub text: String,
    /// Headline lines.
    pub headlines: Vec<String>,
}

/// A candidate's name as the tables show it: with its rig's force limit, if any.
fn shown(s: &ExperimentsStudy, name: &str) -> String {
    match s.candidate.iter().find(|c| c.name == name).and_then(|c| c.force_limit_n) {
        Some(f) => format!("{name} (stops at {f} N)"),
        None => name.to_string(),
    }
}

/// "Gen 4 × 100 particles" for a single candidate or a plan.
fn plan_phrase(s: &ExperimentsStudy, e: &Evaluated) -> String {
    e.names
        .iter()
        .zip(&e.sizes)
        .map(|(n, k)| {
            let unit = s.candidate.iter().find(|c| &c.name == n).map_or("units", |c| c.test.unit());
            format!("{} ({k} {unit})", shown(s, n))
        })
        .collect::<Vec<_>>()
        .join(" + ")
}

/// ("raises", "0.333 → 0.703 ± 0.015"): the verb of `words` (up, down, neither) that the change
/// from `from` (exact: the prior's) to `to` takes beyond two Monte Carlo standard errors, and
/// the two values.
fn changed<'a>(from: f64, to: super::preposterior::Estimate, words: (&'a str, &'a str, &'a str)) -> (&'a str, String) {
    let verb = if to.mean - from > 2.0 * to.se && to.mean > from {
        words.0
    } else if from - to.mean > 2.0 * to.se && to.mean < from {
        words.1
    } else {
        words.2
    };
    (verb, format!("{} → {}", prob(from), pm(to.mean, to.se)))
}

/// What a plan changes from today, each worded by its direction beyond two Monte Carlo standard
/// errors ([`changed`]): the probability of the right choice, the weight of the true damage
/// model, and each material's 90 % band of P_break at horizon `last` (quantities `qs`).
struct Changes {
    pcs: (&'static str, String),
    weight: (&'static str, String),
    bands: Vec<String>,
}

fn changes(m: &Metrics, labels: &[String], qs: [usize; 2], last: f64) -> Changes {
    let bands = (0..2)
        .map(|j| {
            let (verb, v) = changed(m.prior.width90[qs[j]], m.width90[qs[j]], ("widens", "narrows", "leaves unchanged"));
            format!("{verb} the 90 % band of P_break of {} over {} (width {v})", labels[j], years(last))
        })
        .collect();
    Changes {
        pcs: changed(m.prior_pcs, m.pcs, ("raises", "lowers", "leaves unchanged")),
        weight: changed(m.prior_true_label_weight[0], m.true_label_weight[0], ("raises", "lowers", "leaves unchanged")),
        bands,
    }
}

/// "1 year" or "10 years".
fn years(y: f64) -> String {
    if y == 1.0 { "1 year".into() } else { format!("{y} years") }
}


/// Whether a ranking by the bands of log10 P would depend on the floor put under P, and the
/// ranking that does not (`order`: the singles by the study's objective per cost, best first).
fn floor_section(s: &ExperimentsStudy, state: &State, singles: &[((usize, usize), Evaluated)], order: &[usize]) -> String {
    let rankings = super::plan::floor_rankings(state, singles);
    let name = |i: usize| format!("{} ({} {})", singles[i].1.names[0], singles[i].1.sizes[0], s.candidate[singles[i].0.0].test.unit());
    let leader = |rank: &[f64]| (0..rank.len()).min_by(|&a, &b| rank[a].total_cmp(&rank[b])).unwrap_or(0);
    let floors: Vec<String> = rankings.iter().map(|r| crate::report::canvas::power_of_ten(&r.0)).collect();
    let mut md = format!("\n### Would a floor under P decide the ranking?\n\nVogel–Peukert gives P_break = 0 exactly for many samples, where log10 P is −∞; the 90 % bands of log10 P have a width only above a floor. Ranked instead by how much they narrow the bands of log10 P_break over {} (both materials, per cost), with P floored at {} (`floor_sensitivity.csv`), ", years(state.years[state.years.len() - 1]), floors.join(", "));
    let same = rankings.windows(2).all(|w| w[0].2 == w[1].2);
    let leaders: Vec<usize> = rankings.iter().map(|r| leader(&r.2)).collect();
    if same {
        md.push_str(&format!("the {} candidates come in the same order at every floor, led by {}.", singles.len(), name(leaders[0])));
    } else {
        let moved = (0..singles.len()).filter(|&i| rankings.iter().any(|r| r.2[i] != rankings[0].2[i])).count();
        md.push_str(&format!(
            "the order changes with the floor: {moved} of the {} candidates change rank, and the leader is {}. The floor, not the data, sets that ranking, so it is not used here.",
            singles.len(),
            if leaders.iter().all(|&l| l == leaders[0]) { format!("{} at every floor", name(leaders[0])) } else { rankings.iter().zip(&leaders).map(|(r, &l)| format!("{} at {}", name(l), crate::report::canvas::power_of_ten(&r.0))).collect::<Vec<_>>().join(", ") }
        ));
    }
    if s.decision.objective == Objective::BandWidth {
        let first = order.first().copied().unwrap_or(0);
        md.push_str(&format!(" The plans are ranked by the bands of P itself, which need no floor{}.", if leaders.iter().all(|&l| l == first) { format!(", and lead with the same candidate, {}", name(first)) } else { format!("; that ranking is led by {}", name(first)) }));
    }
    md.push('\n');
    md
}

/// The summary of the study.
/// `limits`: per crush candidate with a force limit, (candidate, limit in N, the prior's expected
/// share of particles not broken by it).
pub fn summary(s: &ExperimentsStudy, state: &State, singles: &[((usize, usize), Evaluated)], allocated: &Allocated, limits: &[(usize, f64, f64)]) -> Summary {
    let cur = &s.decision.currency;
    let labels: Vec<String> = state.forms[0].setup.materials.iter().map(|m| m.model.label.clone()).collect();
    let h = state.years.len() - 1;
    let last = state.years[h];
    let qs = [state.p_quantity(0, h), state.p_quantity(1, h)];
    let worse = state.worse_quantity();
    let prior = &singles[0].1.metrics;
    // Share of the (active) prior samples with no breakage at all at the last horizon.
    let active = &state.samples[..s.analysis.samples.min(state.samples.len())];
    let is_zero = |x: &super::state::StateSample, j: usize| x.p[j * state.years.len() + h] == 0.0;
    let zero = |j: usize| active.iter().filter(|x| is_zero(x, j)).count() as f64 / active.len().max(1) as f64;
    // Which damage models the samples with no breakage came from (Vogel–Peukert below its
    // threshold, typically), named from the samples, not assumed.
    let zero_models: Vec<&str> = state.damage.iter().enumerate().filter(|(d, _)| active.iter().any(|x| x.damage == *d && (is_zero(x, 0) || is_zero(x, 1)))).map(|(_, m)| m.label()).collect();
    let zero_note = match zero_models.as_slice() {
        [] => String::new(),
        [m] if *m == crate::lifetime::damage::DamageModel::VogelPeukert.label() => format!(" (all under {m}: below its threshold nothing breaks)"),
        models => format!(" (under {})", models.join(", ")),
    };
    let band = |j: usize| prior.prior.band90[qs[j]];
    let mut md = format!("# Which experiment next? {} against {}\n\n", labels[0], labels[1]);
    md.push_str(&format!(
        "Prior: the state of knowledge of the main study `{}` ({} samples and a reserve of {}: strength models with their stacking weights, damage models {} with prior weights {}). Decision: which particle to choose for a plant over {}, a wrong choice costing {} {cur}. Each candidate and size: {} simulated datasets (preposterior analysis by importance reweighting, and resample-move with {} particles where it degenerates; `partlife::experiments`).{}\n\n",
        s.study,
        s.analysis.samples,
        s.analysis.reserve,
        state.damage.iter().map(|d| d.label()).collect::<Vec<_>>().join(", "),
        state.damage_weights.iter().map(|w| format!("{w}")).collect::<Vec<_>>().join(", "),
        years(state.years[state.horizon]),
        s.decision.loss,
        s.analysis.outer,
        s.analysis.particles,
        crate::intake::synthetic_sentence("crush data", &state.forms[0].setup.materials.iter().map(|m| (m.model.label.as_str(), m.path.as_path())).collect::<Vec<_>>())
    ));
    md.push_str("## Today\n\n");
    // Per damage model, P(candidate breaks more) over the active samples: the main study's
    // headline is under its first damage model alone; here the models are averaged.
    let kn = &state.knowledge;
    let per_damage: Vec<(&str, f64, f64)> = state
        .damage
        .iter()
        .enumerate()
        .map(|(d, m)| {
            let (mut w, mut p, mut tie) = (0.0, 0.0, 0.0);
            for (k, x) in active.iter().enumerate().filter(|(_, x)| x.damage == d) {
                let v = kn.weights[k];
                w += v;
                p += v * kn.values[k * kn.quantities + worse];
                let at = |j: usize| x.p[j * state.years.len() + state.horizon];
                if at(0) == at(1) {
                    tie += v;
                }
            }
            (m.label(), p / w.max(f64::MIN_POSITIVE), tie / w.max(f64::MIN_POSITIVE))
        })
        .collect();
    // The action today's knowledge takes (0: the candidate).
    let today = labels[prior.prior.action()].clone();
    md.push_str(&format!(
        "P({} breaks more than {} in {}) = {:.3}; choosing {today}, the particle today's knowledge favours, is right with probability {:.3}. The 90 % band of P_break over {} is [{}, {}] for {} and [{}, {}] for {}; P_break is exactly 0 in {:.0} % and {:.0} % of the samples{}. The prior weight of the true damage model is {:.3} on average.\n\n",
        labels[0],
        labels[1],
        years(state.years[state.horizon]),
        prior.prior.mean[worse],
        prior.prior_pcs,
        years(last),
        prob(band(0).0),
        prob(band(0).1),
        labels[0],
        prob(band(1).0),
        prob(band(1).1),
        labels[1],
        100.0 * zero(0),
        100.0 * zero(1),
        zero_note,
        prior.prior_true_label_weight[0]
    ));
    if per_damage.len() > 1 {
        let ties: Vec<String> = per_damage.iter().filter(|d| d.2 >= 0.005).map(|(m, _, t)| format!("{:.0} % of the samples under {m}", 100.0 * t)).collect();
        md.push_str(&format!(
            "That P averages the damage models with the prior weights above; under each alone it is {}.{} The main study's headline P is under {} alone, so the two differ.\n\n",
            per_damage.iter().map(|(m, p, _)| format!("{p:.3} ({m})")).collect::<Vec<_>>().join(", "),
            if ties.is_empty() {
                String::new()
            } else {
                format!(" A tie — both particles breaking with the same probability, typically neither at all — counts as not breaking more: ties are {}.", ties.join(", "))
            },
            per_damage[0].0
        ));
    }

    md.push_str(&format!("## Candidates ranked by {} per cost\n\n", s.decision.objective.describe()));
    md.push_str(&format!("| rank | candidate | size | cost ({cur}) | objective | P(correct choice) | EVSI ({cur}) | width90 P {} | width90 P {} | weight of true damage model |\n|---|---|---|---|---|---|---|---|---|---|\n", labels[0], labels[1]));
    let mut order: Vec<usize> = (0..singles.len()).collect();
    order.sort_by(|&a, &b| (singles[b].1.objective.0 / singles[b].1.cost).total_cmp(&(singles[a].1.objective.0 / singles[a].1.cost)));
    for (r, &i) in order.iter().enumerate() {
        let e = &singles[i].1;
        let m = &e.metrics;
        md.push_str(&format!(
            "| {} | {} | {} | {:.0} | {} | {} | {} | {} | {} | {} |\n",
            r + 1,
            shown(s, &e.names[0]),
            e.sizes[0],
            e.cost,
            pm(e.objective.0, e.objective.1),
            pm(m.pcs.mean, m.pcs.se),
            pm(m.evsi.mean, m.evsi.se),
            prob(m.width90[qs[0]].mean),
            prob(m.width90[qs[1]].mean),
            pm(m.true_label_weight[0].mean, m.true_label_weight[0].se)
        ));
    }
    for &(i, force, share) in limits {
        let name = &s.candidate[i].name;
        let pct = 100.0 * share;
        md.push_str(&if pct < 0.05 {
            format!("\n\"{name}\" stops at the rig's force limit of {force} N, above every break today's state of knowledge expects ({pct:.1} % unbroken): the limit changes nothing.\n")
        } else if pct > 99.95 {
            format!("\n\"{name}\" stops at the rig's force limit of {force} N, below nearly every break: an expected {pct:.1} % of its particles do not break by it, so the test records lower bounds only and carries almost no information.\n")
        } else {
            format!("\n\"{name}\" stops at the rig's force limit of {force} N: under today's state of knowledge an expected {pct:.1} % of its particles do not break by it. Each enters the test's likelihood as not broken by the σ̄ its diameter gives at {force} N (right-censored), not as a break at the limit.\n")
        });
    }
    md.push_str(&floor_section(s, state, singles, &order));

    let rule = match allocated {
        Allocated::Greedy(_) => "greedily".to_string(),
        Allocated::Exhaustive { plans, .. } => format!("exhaustively over its {} affordable plans", plans.len()),
    };
    md.push_str(&format!("\n## The budget ({} {cur}), allocated {rule}\n\n", s.budget.total));
    let mut headlines = Vec::new();
    match first_step(s, singles) {
        None => {
            let line = format!("With a budget of {} {cur}, no candidate gains more than two Monte Carlo standard errors of the objective ({}): on these numbers no further test is worth its cost.", s.budget.total, s.decision.objective.describe());
            md.push_str(&format!("{line}\n"));
            headlines.push(line);
        }
        Some(first) => {
            let m = &first.metrics;
            let Changes { pcs: (pcs, pcs_v), weight: (weight, weight_v), bands } = changes(m, &labels, qs, last);
            let line = format!(
                "With a budget of {} {cur}, the most informative next step is {} for {:.0} {cur}: it {pcs} the probability of choosing the better particle ({pcs_v}), {weight} the expected weight of the true damage model ({weight_v}), {} and {}; its expected value of information is {} {cur}.",
                s.budget.total,
                plan_phrase(s, first),
                first.cost,
                bands[0],
                bands[1],
                pm(m.evsi.mean, m.evsi.se)
            );
            md.push_str(&format!("{line}\n\n"));
            headlines.push(line);
            let compared = |e: &Evaluated| e.compared.map_or("–".to_string(), |(d, se)| pm(d, se));
            let row = |k: String, e: &Evaluated| format!("| {k} | {} | {:.0} | {} | {} | {} | {} |\n", plan_phrase(s, e), e.cost, pm(e.objective.0, e.objective.1), compared(e), pm(e.metrics.pcs.mean, e.metrics.pcs.se), pm(e.metrics.true_label_weight[0].mean, e.metrics.true_label_weight[0].se));
            let head = |k: &str, c: &str| format!("| {k} | plan | cost | objective | {c} | P(correct choice) | weight of true damage model |\n|---|---|---|---|---|---|---|\n");
            match allocated {
                Allocated::Greedy(steps) => {
                    md.push_str(&head("step", "gain over the step before (paired se)"));
                    for (k, e) in steps.iter().enumerate() {
                        md.push_str(&row(format!("{}", k + 1), e));
                    }
                    let total = steps.last().map_or(0.0, |e| e.cost);
                    md.push_str(&format!(
                        "\nThe plan spends {total:.0} of {} {cur}. The rule: each step adds the test with the largest gain per cost among those that fit the budget, and the plan stops when nothing fits or no addition gains more than two standard errors of its gain; every step's additions are scored on the same simulated truths and data as the plan before them, so the gain's error is that of the paired difference (stated in `partlife::experiments::run`).\n",
                        s.budget.total
                    ));
                    // Steps whose reweighting degenerated: their numbers are not reliable.
                    let weak: Vec<String> = steps
                        .iter()
                        .enumerate()
                        .filter(|(_, e)| unreliable(&e.metrics, s.analysis.outer))
                        .map(|(k, e)| format!("step {} (median ESS {:.1}, {} of {} simulated datasets collapsed)", k + 1, e.metrics.median_ess, e.metrics.collapsed, s.analysis.outer))
                        .collect();
                    if !weak.is_empty() {
                        // The steps before the first unreliable one stand; say which, or that none does.
                        let first_weak = steps.iter().position(|e| unreliable(&e.metrics, s.analysis.outer)).unwrap_or(0);
                        let stands = match first_weak {
                            0 => format!("No step of this allocation is reliable: raise `analysis.samples`, `reserve` or `outer` (now {}, {}, {}) and rerun.", s.analysis.samples, s.analysis.reserve, s.analysis.outer),
                            1 => "Step 1 stands; beyond it, rerun the study once that test is done.".to_string(),
                            k => format!("Steps 1–{k} stand; beyond them, rerun the study once those tests are done."),
                        };
                        md.push_str(&format!("\n**Not reliable:** {} — below a median effective sample size of {RELIABLE_ESS} or with {:.0} % or more of the reweighted posteriors collapsed, neither the reweighted prior samples nor resample-move represent the posterior of these plans, and their objectives, P(correct choice) and weights may be far off. {stands}\n", weak.join("; "), 100.0 * RELIABLE_COLLAPSED));
                    }
                }
                Allocated::Exhaustive { plans, chosen } => {
                    md.push_str(&head("rank", "below the largest (paired se)"));
                    for (k, e) in plans.iter().enumerate().take(10) {
                        md.push_str(&row(format!("{}{}", k + 1, if Some(k) == *chosen { " (recommended)" } else { "" }), e));
                    }
                    if plans.len() > 10 {
                        md.push_str(&format!("\n(the first 10 of {}; every plan is in `allocation.csv`)\n", plans.len()));
                    }
                    if let Some(i) = *chosen {
                        let (c, best) = (&plans[i], &plans[0]);
                        md.push_str(&format!(
                            "\nRecommended: {} for {:.0} of {} {cur}, objective {} — {}. The rule (every affordable plan on the same simulated truths; the cheapest within two standard errors of the largest objective, the errors those of the paired differences) is stated in `partlife::experiments::run`.\n",
                            plan_phrase(s, c),
                            c.cost,
                            s.budget.total,
                            pm(c.objective.0, c.objective.1),
                            if i == 0 {
                                "the largest of every plan".to_string()
                            } else {
                                let (d, se) = c.compared.unwrap_or((f64::NAN, f64::NAN));
                                format!("{} below the largest, {} for {:.0} {cur}: within two standard errors of the paired difference", pm(d, se), pm(best.objective.0, best.objective.1), best.cost)
                            }
                        ));
                    }
                }
            }
        }
    }
    let max_evsi = singles.iter().map(|(_, e)| e.metrics.evsi.mean + 2.0 * e.metrics.evsi.se).fold(f64::NEG_INFINITY, f64::max);
    if max_evsi < 0.01 * s.decision.loss {
        md.push_str(&format!(
            "\nNo candidate's expected value of information exceeds 1 % of the loss (largest upper 2-se bound {:.3e} {cur}): the choice between the particles is already settled by today's knowledge ({:.3}), and the tests are worth running for what they teach about the lifetime itself — the damage model and the breakage bands — rather than for the choice.\n",
            max_evsi, prior.prior_pcs
        ));
    }
    // An objective that ranks by what the tests teach about the lifetime while the choice
    // itself is still open: say so, with the candidate that serves the choice best.
    let clear_evsi = |e: &Evaluated| e.metrics.evsi.mean > 2.0 * e.metrics.evsi.se && e.metrics.evsi.mean > 0.01 * s.decision.loss;
    if matches!(s.decision.objective, Objective::BandWidth | Objective::DamageModel)
        && let Some(k) = (0..order.len()).filter(|&r| clear_evsi(&singles[order[r]].1)).max_by(|&a, &b| {
            let v = |r: usize| singles[order[r]].1.metrics.evsi.mean / singles[order[r]].1.cost;
            v(a).total_cmp(&v(b))
        })
    {
        let e = &singles[order[k]].1;
        md.push_str(&format!(
            "\n**The objective does not fit the decision:** the choice between the particles is not settled today (P(correct choice) {:.3}) and {} ({} {}) has a clearly positive expected value of information ({} {cur}), yet ranks {} by {}. That objective ranks what the tests teach about the lifetime; to rank by what they are worth for the choice, set `objective = \"evsi\"` (or \"pcs\").\n",
            prior.prior_pcs,
            e.names[0],
            e.sizes[0],
            s.candidate[singles[order[k]].0.0].test.unit(),
            pm(e.metrics.evsi.mean, e.metrics.evsi.se),
            k + 1,
            s.decision.objective.describe()
        ));
    }
    // Negative EVSI estimates: noise, or a sign that the reweighting failed.
    let negative: Vec<&Evaluated> = singles.iter().map(|(_, e)| e).filter(|e| e.metrics.evsi.mean < 0.0).collect();
    if !negative.is_empty() {
        let beyond: Vec<String> = negative.iter().filter(|e| e.metrics.evsi.mean < -2.0 * e.metrics.evsi.se).map(|e| format!("{} ({})", e.names[0], e.sizes[0])).collect();
        md.push_str(&format!(
            "\n{} of the candidates' EVSI estimates are negative. The EVSI of an experiment is never negative in expectation (the truths are drawn from the same prior the posterior is reweighted from), so a small negative estimate is Monte Carlo noise{}.\n",
            negative.len(),
            if beyond.is_empty() { ": every one lies within two standard errors of 0".to_string() } else { format!("; beyond two standard errors — {} — it is not noise but a sign that the reweighting did not represent the posterior (see `median_ess` and `collapsed` in `plans.csv`), and those rows are not reliable", beyond.join(", ")) }
        ));
    }
    // The answer opens the document (and heads its first page): the recommended plan and what it
    // changes, from the same numbers as the sections below.
    let plan = match allocated {
        _ if first_step(s, singles).is_none() => None,
        Allocated::Greedy(steps) => steps.last(),
        Allocated::Exhaustive { plans, chosen } => chosen.map(|i| &plans[i]),
    };
    md = md.replacen("## Today\n\n", &format!("{}## Today\n\n", answer(s, plan, prior, &labels, &today, qs, last)), 1);
    md.push_str(&naming_section(s, state, singles));
    let plans: Vec<&Metrics> = singles.iter().map(|(_, e)| &e.metrics).chain(allocated.plans().iter().map(|e| &e.metrics)).collect();
    let count = |f: &dyn Fn(&Metrics) -> usize| plans.iter().map(|m| f(m)).sum::<usize>();
    md.push_str(&format!(
        "\nPosteriors: of {} simulated datasets (every candidate and size, and every {} plan in `allocation.csv`), {} needed the reserve samples, {} resample-move (the reweighted prior samples fell below the effective-sample-size threshold of {}: the likelihood tempered in and the samples moved), and {}.\n",
        plans.len() * s.analysis.outer,
        if matches!(allocated, Allocated::Greedy(_)) { "greedy step's" } else { "affordable" },
        count(&|m| m.fallbacks),
        count(&|m| m.moved),
        s.analysis.min_ess,
        match count(&|m| m.collapsed) {
            0 => "none stayed below the threshold".to_string(),
            n => format!("{n} stayed below the threshold (their posteriors are less reliable: `collapsed` in `plans.csv` and `allocation.csv`)"),
        },
    ));
    Summary { text: md, headlines }
}

/// The `## Answer` section: the plan to spend the budget on (`plan`; None when no test gains
/// more than two Monte Carlo standard errors), the particle today's knowledge favours, and what
/// the plan changes — the probability of the right choice, each material's 90 % band of P_break
/// at horizon `last` (quantities `qs`) and the weight of the true damage model — each worded by
/// its direction beyond two standard errors ([`changed`]), from the metrics of `prior` (today)
/// and of the plan.
fn answer(s: &ExperimentsStudy, plan: Option<&Evaluated>, prior: &Metrics, labels: &[String], today: &str, qs: [usize; 2], last: f64) -> String {
    let cur = &s.decision.currency;
    let favours = format!("today's knowledge favours {today} (right with probability {:.3})", prior.prior_pcs);
    let sentence = match plan {
        None => format!(
            "**No further test is worth its cost on these numbers**: with {} {cur} to spend, no candidate gains more than two Monte Carlo standard errors of the objective ({}); {favours}.",
            s.budget.total,
            s.decision.objective.describe()
        ),
        Some(e) => {
            let Changes { pcs: (pcs, pcs_v), weight: (weight, weight_v), bands } = changes(&e.metrics, labels, qs, last);
            format!(
                "**Spend {:.0} of the {} {cur} on {}.** {}; the plan {pcs} the probability of that choice being right ({pcs_v}), {}, {}, and {weight} the expected weight of the true damage model ({weight_v}).",
                e.cost,
                s.budget.total,
                plan_phrase(s, e),
                capitalised(&favours),
                bands[0],
                bands[1]
            )
        }
    };
    format!("## Answer\n\n{sentence}\n\n")
}

fn capitalised(t: &str) -> String {
    let mut c = t.chars();
    c.next().map_or(String::new(), |f| f.to_uppercase().collect::<String>() + c.as_str())
}

/// The naming loop's verdict beside the reweighting's, for the crush candidates that ran it
/// (empty when none did).
fn naming_section(s: &ExperimentsStudy, state: &State, singles: &[((usize, usize), Evaluated)]) -> String {
    let scored: Vec<(usize, &Evaluated, &Scored)> = singles.iter().filter_map(|((i, _), e)| e.metrics.score.as_ref().map(|sc| (*i, e, sc))).collect();
    if scored.is_empty() {
        return String::new();
    }
    let mut md = String::from("\n## Would the discrepancy workflow find the true strength model?\n\n");
    md.push_str("The main study's diagnosed strength model is what the discrepancy naming loop names in each material's crush data. For the crush candidates below, the loop was also run on the pooled data — today's crushed particles and the simulated ones — of the first simulated campaigns, and scored 1 when it named exactly the effects of the strength model the campaign was simulated under (0 when it named other effects or failed on the data; failures are counted apart). Beside it, on the same campaigns, the Bayesian update's expected posterior weight of that model.\n\n");
    md.push_str("| candidate | particles | campaigns | loop failed | naming loop names the true model's effects | expected weight of the true strength model |\n|---|---|---|---|---|---|\n");
    for (_, e, sc) in &scored {
        let (verdict, weight) = (sc.mean, sc.true_label_weight[1]);
        md.push_str(&format!("| {} | {} | {} | {} | {} | {} |\n", e.names[0], e.sizes[0], sc.draws, sc.failures, pm(verdict.mean, verdict.se), pm(weight.mean, weight.se)));
    }
    // Each candidate's largest size: which rule identifies the truth more often.
    for (i, c) in s.candidate.iter().enumerate() {
        let Some(&(_, e, sc)) = scored.iter().filter(|(ci, _, _)| *ci == i).max_by_key(|(_, e, _)| e.sizes[0]) else { continue };
        let Some(m) = state.forms[0].setup.materials.iter().find(|m| Some(&m.model.key) == c.material.as_ref()) else { continue };
        let (verdict, weight) = (sc.mean, sc.true_label_weight[1]);
        let (gap, se) = (weight.mean - verdict.mean, weight.se.hypot(verdict.se));
        let words = if gap > 2.0 * se {
            "the reweighting identifies the true strength model more often than a rerun of the naming loop on the pooled data would"
        } else if gap < -2.0 * se {
            "a rerun of the naming loop on the pooled data identifies the true strength model more often than the reweighting"
        } else {
            "the two rules agree within two Monte Carlo standard errors"
        };
        md.push_str(&format!(
            "\nWith {} more {} crush tests (today {}), the naming loop names exactly the true model's effects in {} of the simulated campaigns{} and the expected posterior weight of the true model is {}: {words}.\n",
            e.sizes[0],
            m.model.label,
            m.sample.strength.len(),
            pm(verdict.mean, verdict.se),
            match sc.failures {
                0 => String::new(),
                f => format!(" (it failed on the data of {f} of the {} and these count as not naming it)", sc.draws),
            },
            pm(weight.mean, weight.se)
        ));
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::preposterior::Estimate;

    /// A narrower band is "narrows", a fall is "lowers", a change within two standard errors
    /// "leaves unchanged" (before: "raises … from 0.334 to 0.3337", "narrows … from 1.000 to
    /// 1.000").
    #[test]
    fn each_change_is_worded_by_its_direction() {
        let band = ("widens", "narrows", "leaves unchanged");
        assert_eq!(changed(0.987, Estimate { mean: 0.215, se: 0.014 }, band), ("narrows", "0.987 → 0.215 ± 0.014".to_string()));
        assert_eq!(changed(0.2, Estimate { mean: 0.5, se: 0.01 }, band).0, "widens");
        let up = ("raises", "lowers", "leaves unchanged");
        assert_eq!(changed(0.334, Estimate { mean: 0.3337, se: 0.0001 }, up).0, "lowers");
        assert_eq!(changed(1.0, Estimate { mean: 1.0, se: 0.0 }, up).0, "leaves unchanged");
        assert_eq!(changed(0.72, Estimate { mean: 0.70, se: 0.02 }, up).0, "leaves unchanged");
    }
}

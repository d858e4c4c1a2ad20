//! Runs a `kind = "experiments"` study: the main study's state of knowledge, every candidate at
//! every size through the preposterior analysis, the ranked plans, the allocation of the budget
//! (greedy or exhaustive), tables, figures and `summary.md`.
//!
//! # Ranking
//!
//! Each (candidate, size) gets the study's objective ([`Objective`]) with its Monte Carlo error,
//! and the plans are ranked by objective per cost.
//!
//! # Budget allocation
//!
//! Every plan takes at most one size per candidate and is evaluated jointly: its tests'
//! likelihoods multiply, so overlapping information is not counted twice.
//!
//! **Greedy** (the default): starting from no experiment, each step adds the (candidate, size)
//! whose addition to the plan so far gives the largest gain of the objective per cost among
//! those that fit the remaining budget. It stops when nothing fits or no addition gains more
//! than two Monte Carlo standard errors of the gain. The gain's error is paired: every step's
//! additions and the plan so far are scored on the same outer draws (common random numbers), so
//! the error of the gain is sd(per-draw difference)/√J ([`super::preposterior::paired`]),
//! usually far smaller than either plan's own error (at the first step the plan so far is the
//! prior, a constant, and the error is the single's own). Its first step is the "most informative next step" of
//! the summary under either rule (chosen by the singles' ranking). Every step's additions are
//! evaluated on the same outer draws — truths and the earlier tests' data — and the chosen
//! addition's posteriors are carried to the next step ([`super::smc`], sequential plans), where
//! reweighting gives way to resample-move as tests accumulate; `allocation.csv` gives each
//! step's metrics on those draws.
//!
//! Every plan — a single candidate, a greedy step, an exhaustive plan — is evaluated test after
//! test from the prior: reweighting, the reserve as fallback, and resample-move (`[analysis]
//! particles`, `sweeps`) where the effective sample size stays below `min_ess`.
//!
//! **Exhaustive** (`allocation = "exhaustive"`, for small grids): every affordable plan is
//! evaluated with the same outer draws (common random numbers, so plans are compared on the
//! same simulated truths); the recommended plan is the cheapest whose objective lies within two
//! Monte Carlo standard errors of the largest, the error that of the paired difference — more
//! money for a difference the analysis cannot resolve is not recommended. Greedy allocation can miss the best plan when a costly
//! test is worth more than two cheap ones together (a knapsack); exhaustive cannot, on its grid.


use super::crush::{CrushOptions, CrushTest, ForceLimit};
use super::impact::ImpactTest;
use super::measure::{Measured, Measurement};
pub use super::plan::{Allocated, Evaluated, first_step};
use super::plan::Candidate;
use super::preposterior::{Estimate, Metrics, Settings, paired};
use super::smc::{self, Moves};
use super::state::State;
use super::study::{Allocation, ExperimentsStudy, Objective, TestKind};
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::schema::StudyFile;
use crate::uq::study::UqStudy;

/// The objective's value per outer draw of `m` (its mean is the plan's objective), in the order of
/// `m.draws`: what a paired comparison of two plans on the same draws differences.
pub fn objective_per_draw(o: Objective, state: &State, m: &Metrics) -> Vec<f64> {
    let minus = |v: &[f64], c: f64| v.iter().map(|x| x - c).collect();
    match o {
        Objective::Evsi => m.per_draw.evsi.clone(),
        Objective::Pcs => minus(&m.per_draw.pcs, m.prior_pcs),
        Objective::DamageModel => minus(&m.per_draw.true_label_weight[0], m.prior_true_label_weight[0]),
        Objective::BandWidth => state.band_narrowing_per_draw(m, &|b| b.1 - b.0),
    }
}

/// The difference of two plans' objectives evaluated on the same outer draws, a − b, with its
/// paired Monte Carlo error ([`paired`]); where they are not paired, with the two errors
/// combined as independent.
pub fn objective_difference(a: &Evaluated, b: &Evaluated) -> (f64, f64) {
    match paired(&a.objective_draws, &b.objective_draws) {
        Some(d) => (d.mean, d.se),
        None => (a.objective.0 - b.objective.0, a.objective.1.hypot(b.objective.1)),
    }
}

/// The main study the experiments study builds on, validated (its path, study, material keys
/// in the order candidate, reference).
fn main_study(loaded: &StudyFile, s: &ExperimentsStudy) -> Result<(std::path::PathBuf, UqStudy, Vec<String>)> {
    let file = loaded.path.display().to_string();
    let path = loaded.resolve(std::path::Path::new(&s.study));
    if !path.is_file() {
        return Err(Error::config(&file, "study", format!("the main study {} does not exist", path.display())));
    }
    let main = StudyFile::read(&path)?;
    if main.kind(&["uq"])? != "uq" {
        return Err(Error::config(&file, "study", format!("{} is not a main study (kind = \"uq\")", path.display())));
    }
    let u: UqStudy = main.parse()?;
    u.validate(&path.display().to_string())?;
    let keys = u.order().iter().map(|&i| u.material[i].key.clone()).collect();
    Ok((path, u, keys))
}

/// Runs the study.
pub fn run_experiments(loaded: &StudyFile, s: &ExperimentsStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let file = loaded.path.display().to_string();
    s.validate(&file, None)?;
    let (main_path, u, keys) = main_study(loaded, s)?;
    s.validate(&file, Some(&keys))?;
    let horizon = u.impact.years.iter().position(|&y| y == s.decision.horizon_years).ok_or_else(|| Error::config(&file, "decision.horizon_years", format!("must be one of the main study's horizons {:?}, got {}", u.impact.years, s.decision.horizon_years)))?;
    // The candidate tests' models draw one Weibull law per material; the main study's models
    // with known failure origins carry one law per origin.
    if let Some((k, m)) = u.material.iter().enumerate().find(|(_, m)| m.origin.is_some()) {
        return Err(Error::config(
            &main_path.display().to_string(),
            format!("material[{k}].origin"),
            format!("the experiments study {file} models each candidate test with one Weibull law per material, and material `{}` carries one law per failure origin in this main study; the experiments need a main study that fits one law (the column in `material[{k}].data.ignore` instead of `origin`) — which pools the origins and can change the comparison: read both main studies' answers", m.key),
        ));
    }
    let shared = crate::uq::setup::Shared::new(&u, &main_path, &opts.reports_root)?;
    let damage_weights = s.decision.damage_weights.clone().unwrap_or_else(|| vec![1.0; shared.models.len()]);
    if damage_weights.len() != shared.models.len() {
        return Err(Error::config(&file, "decision.damage_weights", format!("needs one weight per damage model of the main study ({}), got {}", shared.models.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "), damage_weights.len())));
    }
    let mut inputs = vec![InputFile::hash(&loaded.path)?, InputFile::hash(&main_path)?];
    let runs: usize = s.candidate.iter().map(|c| c.sizes.len()).sum();
    let pb = progress_bar((1 + runs + s.candidate.len() * runs) as u64, opts.progress, crate::runkit::PROGRESS_COUNT);
    pb.set_message("state of knowledge (the main study's strength models)");
    let forms = crate::uq::run::weighed(&u, &main_path, &shared)?;
    let a = s.analysis;
    let state = State::new(forms, damage_weights, horizon, s.decision.loss, a.samples + a.reserve, s.seed)?;
    pb.inc(1);
    for m in &state.forms[0].setup.materials {
        inputs.extend(InputFile::read(&m.path, &m.read)?);
    }

    // Every candidate at every size.
    pb.set_message("candidates");
    let mut built: Vec<Vec<Candidate>> = Vec::new();
    // What the run had to mend without stopping (recorded in the manifest and the summary).
    let mut notes: Vec<String> = Vec::new();
    for (i, c) in s.candidate.iter().enumerate() {
        let material = c.material.as_ref().map(|m| keys.iter().position(|k| k == m).unwrap_or(0)).unwrap_or(0);
        // The per-sample likelihood tables do not depend on the size: built once at the first
        // size, then resized.
        let n0 = c.sizes[0] as u64;
        let base = match c.test {
            TestKind::Crush => {
                // The main study's naming settings for this material (its seed as in the main study).
                let index = u.order()[material];
                let naming = c.naming_draws.map(|_| crate::strength::NamingSettings { seed: u.seed.wrapping_add(7919 * index as u64), ..u.strength.naming.clone() });
                // The rig's limit in σ̄ through the main study's elastic constants and contact.
                let force_limit = c.force_limit_n.map(|force_n| ForceLimit { force_n, elastic: u.material[index].elastic, contact: u.contact.clone() });
                CrushTest::new(&state, material, n0 as usize, &CrushOptions { diameter: c.diameter_m.map(|[lo, hi]| (lo, hi)), shape_measured: c.shape_measured.unwrap_or(true), temperature_c: c.temperature_c, naming, force_limit }).map(Candidate::Crush)
            }
            TestKind::Impact => ImpactTest::new(&state, material, n0, c.velocity_m_s.unwrap_or(0.0), c.counts.clone().unwrap_or_default().iter().map(|&k| k as u64).collect()).map(Candidate::Impact),
            TestKind::EtaMeasurement => Measurement::new(&state, Measured::EnergyFraction, n0, c.sd_log.unwrap_or(0.0)).map(Candidate::Measure),
            TestKind::VelocityMeasurement => Measurement::new(&state, Measured::Velocity, n0, c.sd_log.unwrap_or(0.0)).map(Candidate::Measure),
        }
        // What fails here is the candidate as declared (a sieve fraction with no crushed
        // particle, a strength model without a crush likelihood): bad input.
        .map_err(|e| Error::config(&file, format!("candidate[{i}]"), format!("\"{}\": {e}", c.name)))?;
        if let Candidate::Impact(t) = &base
            && t.clamped.0 > 0
        {
            notes.push(format!("candidate \"{}\": P_N fell with N or exceeded 1 in {} of {} prior samples (largest by {:.2e}); clamped to be non-decreasing and at most 1", c.name, t.clamped.0, state.samples.len(), t.clamped.1));
        }
        built.push(c.sizes.iter().map(|&n| base.sized(n as u64)).collect());
    }
    let settings = |salt: u64, scored: usize| Settings { outer: a.outer, min_ess: a.min_ess, seed: s.seed ^ salt.wrapping_mul(0x9E37_79B9_7F4A_7C15), truth: None, active: Some(a.samples), scored };
    let moves = Some(Moves { particles: a.particles, sweeps: a.sweeps });
    let evaluated = |picks: &[(usize, usize)], metrics: Metrics| -> Evaluated {
        let objective_draws = objective_per_draw(s.decision.objective, &state, &metrics);
        let e = Estimate::of(&objective_draws);
        Evaluated {
            names: picks.iter().map(|&(i, _)| s.candidate[i].name.clone()).collect(),
            sizes: picks.iter().map(|&(i, j)| s.candidate[i].sizes[j] as u64).collect(),
            cost: picks.iter().map(|&(i, j)| s.candidate[i].cost(s.candidate[i].sizes[j] as u64)).sum(),
            metrics,
            objective: (e.mean, e.se),
            objective_draws,
            compared: None,
        }
    };
    // A plan evaluated test after test from the prior (resample-move where reweighting
    // degenerates, `smc`); the naming loop's verdict is asked of single candidates only
    // (`scored`), not of plans.
    let evaluate_scored = |picks: &[(usize, usize)], salt: u64, scored: usize| -> Result<Evaluated> {
        let set = settings(salt, scored);
        let mut tracks = smc::start::<State, Candidate>(&state.knowledge, &set)?;
        let tests: Vec<&Candidate> = picks.iter().map(|&(i, j)| &built[i][j]).collect();
        for (t, test) in tests.iter().enumerate() {
            let last = t + 1 == tests.len();
            let (metrics, next) = smc::extend(&state.knowledge, &state, &tracks, &tests[..t], test, &set, moves, move_seed(set.seed, t), !last)?;
            match next {
                Some(next) => tracks = next,
                None => return Ok(evaluated(picks, metrics)),
            }
        }
        Err(Error::numerical("experiment design", "an empty plan"))
    };
    let evaluate = |picks: &[(usize, usize)], salt: u64| evaluate_scored(picks, salt, 0);
    let mut singles = Vec::new();
    for (i, c) in s.candidate.iter().enumerate() {
        for j in 0..c.sizes.len() {
            singles.push(((i, j), evaluate_scored(&[(i, j)], single_salt((i, j)), c.naming_draws.unwrap_or(0))?));
            pb.inc(1);
        }
    }

    let allocated = match s.budget.allocation {
        Allocation::Greedy => {
            pb.set_message("budget allocation (greedy)");
            Allocated::Greedy(greedy(s, &state, &built, &singles, &|salt| settings(salt, 0), moves, &evaluated, &pb)?)
        }
        Allocation::Exhaustive => {
            pb.set_message("budget allocation (exhaustive)");
            let plans = s.affordable_plans(s.budget.max_plans);
            pb.set_length((1 + runs + plans.len()) as u64);
            // One salt for every plan: common random numbers.
            let mut evaluated = Vec::with_capacity(plans.len());
            for p in &plans {
                evaluated.push(evaluate(p, 0xE7A7)?);
                pb.inc(1);
            }
            evaluated.sort_by(|a, b| b.objective.0.total_cmp(&a.objective.0).then(a.cost.total_cmp(&b.cost)));
            // Each plan's shortfall below the largest objective, with the paired error of the
            // difference (the same truths and data for every plan).
            if let Some(best) = evaluated.first().cloned() {
                for e in &mut evaluated {
                    e.compared = Some(objective_difference(&best, e));
                }
            }
            let within = |e: &Evaluated| e.compared.is_some_and(|(d, se)| d <= 2.0 * se);
            let chosen = (0..evaluated.len()).filter(|&i| within(&evaluated[i])).min_by(|&a, &b| evaluated[a].cost.total_cmp(&evaluated[b].cost).then(a.cmp(&b)));
            Allocated::Exhaustive { plans: evaluated, chosen }
        }
    };
    pb.set_position(pb.length().unwrap_or(0));

    // Per crush candidate with a force limit: the limit and the prior's expected share of
    // particles not broken by it.
    let limits: Vec<(usize, f64, f64)> = built
        .iter()
        .enumerate()
        .filter_map(|(i, b)| match b.first() {
            Some(Candidate::Crush(t)) => Some((i, t.force_limit_n()?, t.expected_unbroken(&state.knowledge.weights)?)),
            _ => None,
        })
        .collect();
    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;
    write_tables(&mut dir, s, &state, &keys, &singles, &allocated, &limits)?;
    let summary = super::summary::summary(s, &state, &singles, &allocated, &limits);
    let mut text = summary.text.clone();
    if !notes.is_empty() {
        text.push_str("\n## What the run mended\n\n");
        text.extend(notes.iter().map(|n| format!("- {n}.\n")));
    }
    dir.write_bytes("summary.md", text.as_bytes())?;
    pb.set_message("figures");
    let mut failures = notes.clone();
    let rendered = crate::report::experiments::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    let mut evaluations = std::collections::BTreeMap::new();
    evaluations.insert("prior_samples".to_string(), state.samples.len() as u64);
    evaluations.insert("simulated_datasets".to_string(), (singles.len() + allocated.plans().len()) as u64 * a.outer as u64);
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings: Vec::new() })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines: summary.headlines })
}

/// Salt of the outer draws of the single (candidate, size) `p`; the greedy allocation goes on
/// from its first step's (one set of outer draws for every step: common random numbers).
fn single_salt(p: (usize, usize)) -> u64 {
    1 + (p.0 * 64 + p.1) as u64
}

/// The seed of the moves of the `t`-th test (0-based) of a sequence with seed `seed`.
fn move_seed(seed: u64, t: usize) -> u64 {
    seed ^ (0xA11C_E5ED_0000_0000 | t as u64)
}

/// The greedy allocation (module docs): every step's additions evaluated on the same outer draws
/// (truths and earlier data), the chosen addition's posteriors carried to the next step.
#[allow(clippy::too_many_arguments)]
fn greedy(s: &ExperimentsStudy, state: &State, built: &[Vec<Candidate>], singles: &[((usize, usize), Evaluated)], settings_of: &(dyn Fn(u64) -> Settings + Sync), moves: Option<Moves>, evaluated: &(dyn Fn(&[(usize, usize)], Metrics) -> Evaluated + Sync), pb: &indicatif::ProgressBar) -> Result<Vec<Evaluated>> {
    let kn = &state.knowledge;
    let mut plan: Vec<(usize, usize)> = Vec::new();
    let mut steps: Vec<Evaluated> = Vec::new();
    // Started at the first step, on the chosen single's outer draws.
    let mut tracks = Vec::new();
    let mut settings = settings_of(0);
    let mut spent = 0.0;
    loop {
        let options: Vec<(usize, usize)> = (0..s.candidate.len()).filter(|i| !plan.iter().any(|p| p.0 == *i)).flat_map(|i| (0..s.candidate[i].sizes.len()).map(move |j| (i, j))).filter(|&(i, j)| spent + s.candidate[i].cost(s.candidate[i].sizes[j] as u64) <= s.budget.total).collect();
        if options.is_empty() {
            break;
        }
        let earlier: Vec<&Candidate> = plan.iter().map(|&(i, j)| &built[i][j]).collect();
        let seed = move_seed(settings.seed, plan.len());
        let with = |p: (usize, usize)| -> Vec<(usize, usize)> { plan.iter().copied().chain([p]).collect() };
        // The first step's choice is the singles' ranking (the most informative next step).
        let tried: Vec<((usize, usize), Evaluated)> = if plan.is_empty() {
            singles.iter().filter(|(p, _)| options.contains(p)).cloned().collect()
        } else {
            let mut tried = Vec::with_capacity(options.len());
            for &p in &options {
                let (m, _) = smc::extend(kn, state, &tracks, &earlier, &built[p.0][p.1], &settings, moves, seed, false)?;
                tried.push((p, evaluated(&with(p), m)));
                pb.inc(1);
            }
            tried
        };
        // The gain over the plan so far with its Monte Carlo error: at the first step over the
        // prior (a constant: the single's own error), after it paired on the step's outer draws.
        let tried: Vec<((usize, usize), Evaluated)> = tried
            .into_iter()
            .map(|(p, mut e)| {
                e.compared = Some(match steps.last() {
                    None => e.objective,
                    Some(last) => objective_difference(&e, last),
                });
                (p, e)
            })
            .collect();
        let gain = |e: &Evaluated| e.compared.map_or(f64::NAN, |g| g.0) / (e.cost - spent);
        let Some((p, chosen)) = tried.into_iter().filter(|(_, e)| e.compared.is_some_and(|(g, se)| g > 2.0 * se)).max_by(|x, y| gain(&x.1).total_cmp(&gain(&y.1))) else { break };
        // The chosen addition again, keeping its posteriors (the same seeds: the same numbers as
        // the search's, or at the first step as the single's).
        if plan.is_empty() {
            settings = settings_of(single_salt(p));
            tracks = smc::start::<State, Candidate>(kn, &settings)?;
        }
        let seed = move_seed(settings.seed, plan.len());
        let (m, next) = smc::extend(kn, state, &tracks, &earlier, &built[p.0][p.1], &settings, moves, seed, true)?;
        tracks = next.expect("kept");
        plan.push(p);
        let mut step = evaluated(&plan, m);
        step.compared = chosen.compared;
        spent = step.cost;
        steps.push(step);
    }
    Ok(steps)
}

/// `plans.csv` (every candidate at every size, ranked), `allocation.csv` (the greedy steps, or
/// every affordable plan by decreasing objective with the recommended one marked),
/// `prior.csv` (the state of knowledge's prior metrics), `floor_sensitivity.csv` (the ranking
/// by the log10 P bands at each floor of [`super::state::LOG_FLOORS`]).
/// `limits`: per force-limited crush candidate, (candidate, limit in N, the prior's expected share
/// of its particles not broken by it) — columns of `plans.csv`.
fn write_tables(dir: &mut ReportDir, s: &ExperimentsStudy, state: &State, keys: &[String], singles: &[((usize, usize), Evaluated)], allocated: &Allocated, limits: &[(usize, f64, f64)]) -> Result<()> {
    let h = state.years.len() - 1;
    let last = state.years[h];
    let qs = [state.p_quantity(0, h), state.p_quantity(1, h)];
    let worse = state.worse_quantity();
    // Rank 1 = the largest objective per cost (ties share their average rank).
    let rank = crate::stats::ranks(&singles.iter().map(|(_, e)| -e.objective.0 / e.cost).collect::<Vec<_>>());
    let col = |f: &dyn Fn(&Evaluated) -> f64, rows: &[&Evaluated]| rows.iter().map(|e| f(e)).collect::<Vec<f64>>();
    let metric_columns = |rows: &[&Evaluated]| -> Vec<polars::prelude::Column> {
        let mut c = vec![
            fcol("cost", col(&|e| e.cost, rows)),
            fcol("objective", col(&|e| e.objective.0, rows)),
            fcol("objective_se", col(&|e| e.objective.1, rows)),
            fcol("objective_per_cost", col(&|e| e.objective.0 / e.cost, rows)),
            fcol("pcs", col(&|e| e.metrics.pcs.mean, rows)),
            fcol("pcs_se", col(&|e| e.metrics.pcs.se, rows)),
            fcol("p_candidate_worse", col(&|e| e.metrics.mean[worse].mean, rows)),
            fcol("evsi", col(&|e| e.metrics.evsi.mean, rows)),
            fcol("evsi_se", col(&|e| e.metrics.evsi.se, rows)),
            fcol("evsi_per_cost", col(&|e| e.metrics.evsi.mean / e.cost, rows)),
        ];
        for (j, &q) in qs.iter().enumerate() {
            c.push(fcol(&format!("width90_p_{}_{last}yr", keys[j]), col(&|e| e.metrics.width90[q].mean, rows)));
            c.push(fcol(&format!("width90_p_{}_{last}yr_se", keys[j]), col(&|e| e.metrics.width90[q].se, rows)));
        }
        c.extend([
            fcol("true_damage_model_weight", col(&|e| e.metrics.true_label_weight[0].mean, rows)),
            fcol("true_damage_model_weight_se", col(&|e| e.metrics.true_label_weight[0].se, rows)),
            fcol("true_strength_model_weight", col(&|e| e.metrics.true_label_weight[1].mean, rows)),
            fcol("true_strength_model_weight_se", col(&|e| e.metrics.true_label_weight[1].se, rows)),
            // The naming loop's verdict (crush tests with naming_draws; NaN elsewhere) and, on
            // the same draws, the Bayesian expected weight of the true strength model.
            fcol("naming_names_truth", col(&|e| e.metrics.score.as_ref().map_or(f64::NAN, |s| s.mean.mean), rows)),
            fcol("naming_names_truth_se", col(&|e| e.metrics.score.as_ref().map_or(f64::NAN, |s| s.mean.se), rows)),
            ucol("naming_draws", rows.iter().map(|e| e.metrics.score.as_ref().map_or(0, |s| s.draws as u64)).collect()),
            // Of those, the campaigns on which the loop failed (each scored 0).
            ucol("naming_failures", rows.iter().map(|e| e.metrics.score.as_ref().map_or(0, |s| s.failures as u64)).collect()),
            fcol("true_strength_model_weight_naming_draws", col(&|e| e.metrics.score.as_ref().map_or(f64::NAN, |s| s.true_label_weight[1].mean), rows)),
            fcol("median_ess", col(&|e| e.metrics.median_ess, rows)),
            ucol("fallbacks", rows.iter().map(|e| e.metrics.fallbacks as u64).collect()),
            ucol("moved", rows.iter().map(|e| e.metrics.moved as u64).collect()),
            ucol("collapsed", rows.iter().map(|e| e.metrics.collapsed as u64).collect()),
        ]);
        c
    };
    let rows: Vec<&Evaluated> = singles.iter().map(|(_, e)| e).collect();
    let mut cols = vec![
        fcol("rank", rank),
        scol("candidate", singles.iter().map(|((i, _), _)| s.candidate[*i].name.clone()).collect()),
        scol("test", singles.iter().map(|((i, _), _)| serde_json::to_value(s.candidate[*i].test).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default()).collect()),
        scol("material", singles.iter().map(|((i, _), _)| s.candidate[*i].material.clone().unwrap_or_else(|| "both".into())).collect()),
        ucol("size", singles.iter().map(|(_, e)| e.sizes[0]).collect()),
        scol("unit", singles.iter().map(|((i, _), _)| s.candidate[*i].test.unit().to_string()).collect()),
        scol("currency", vec![s.decision.currency.clone(); singles.len()]),
        // A crush test at the rig's force limit (NaN without one) and the share of its particles
        // today's state of knowledge expects not to break by it.
        fcol("force_limit_n", singles.iter().map(|((i, _), _)| limits.iter().find(|l| l.0 == *i).map_or(f64::NAN, |l| l.1)).collect()),
        fcol("expected_unbroken_share", singles.iter().map(|((i, _), _)| limits.iter().find(|l| l.0 == *i).map_or(f64::NAN, |l| l.2)).collect()),
    ];
    cols.extend(metric_columns(&rows));
    dir.write_table("plans", &mut table(cols)?)?;

    let steps = allocated.plans();
    let steps_ref: Vec<&Evaluated> = steps.iter().collect();
    let plan_names = scol("plan", steps.iter().map(|e| e.names.iter().zip(&e.sizes).map(|(n, k)| format!("{n} × {k}")).collect::<Vec<_>>().join(" + ")).collect());
    let mut cols = match allocated {
        // The step's gain over the plan before it (the prior at step 1) with its paired error.
        Allocated::Greedy(_) => vec![
            ucol("step", (1..=steps.len() as u64).collect()),
            scol("added", steps.iter().map(|e| e.names.last().cloned().unwrap_or_default()).collect()),
            ucol("added_size", steps.iter().map(|e| *e.sizes.last().unwrap_or(&0)).collect()),
            plan_names,
            fcol("gain", steps.iter().map(|e| e.compared.map_or(f64::NAN, |c| c.0)).collect()),
            fcol("gain_se_paired", steps.iter().map(|e| e.compared.map_or(f64::NAN, |c| c.1)).collect()),
        ],
        // The plan's shortfall below the largest objective with the paired error.
        Allocated::Exhaustive { chosen, .. } => vec![
            ucol("rank", (1..=steps.len() as u64).collect()),
            plan_names,
            scol("recommended", (0..steps.len()).map(|i| if Some(i) == *chosen { "yes" } else { "" }.to_string()).collect()),
            fcol("below_best", steps.iter().map(|e| e.compared.map_or(f64::NAN, |c| c.0)).collect()),
            fcol("below_best_se_paired", steps.iter().map(|e| e.compared.map_or(f64::NAN, |c| c.1)).collect()),
        ],
    };
    cols.extend(metric_columns(&steps_ref));
    dir.write_table("allocation", &mut table(cols)?)?;

    let p = &singles[0].1.metrics;
    let mut cols = vec![
        scol("quantity", state.quantity_names.clone()),
        fcol("prior_mean", p.prior.mean.clone()),
        fcol("prior_sd", p.prior.var.iter().map(|v| v.sqrt()).collect()),
        fcol("prior_width90", p.prior.width90.clone()),
    ];
    cols.push(fcol("prior_pcs", vec![p.prior_pcs; state.quantity_names.len()]));
    dir.write_table("prior", &mut table(cols)?)?;
    // The ranking the log10 P bands would give, at each floor (state module docs): whether the
    // floor moves it is shown, and only the floor-free objective ranks the plans.
    let mut cols = vec![scol("candidate", singles.iter().map(|((i, _), _)| s.candidate[*i].name.clone()).collect()), ucol("size", singles.iter().map(|(_, e)| e.sizes[0]).collect()), fcol("cost", singles.iter().map(|(_, e)| e.cost).collect())];
    for (floor, narrowing, rank) in super::plan::floor_rankings(state, singles) {
        let tag = format!("{floor:e}");
        cols.push(fcol(&format!("narrowing_log10_p_floor_{tag}"), narrowing.iter().map(|n| n.0).collect()));
        cols.push(fcol(&format!("narrowing_log10_p_floor_{tag}_se"), narrowing.iter().map(|n| n.1).collect()));
        cols.push(fcol(&format!("rank_floor_{tag}"), rank));
    }
    dir.write_table("floor_sensitivity", &mut table(cols)?)?;
    let mut t = table(vec![
        scol("key", keys.to_vec()),
        scol("label", state.forms[0].setup.materials.iter().map(|m| m.model.label.clone()).collect()),
        scol("role", vec!["candidate".into(), "reference".into()]),
    ])?;
    dir.write_table("materials", &mut t)?;
    let mut t = table(vec![
        scol("model", state.damage.iter().map(|d| d.name().to_string()).collect()),
        fcol("prior_weight", { let t: f64 = state.damage_weights.iter().sum(); state.damage_weights.iter().map(|w| w / t).collect() }),
    ])?;
    dir.write_table("damage_models", &mut t)?;
    Ok(())
}

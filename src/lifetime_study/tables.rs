//! The tables of a lifetime study's report (`particles.csv`, `weibull_*.csv`, `size_trend.csv`,
//! `stress_profile*.csv`, `impact_curves.csv`, `breakage_curves.csv`, `force_time.csv`,
//! `lifetime_summary.csv`, `strength_fits.csv`) from the per-material results of the run.

use rayon::prelude::*;
use crate::contact::{ContactState, ContactStress, Hertz};
use crate::error::{Error, Result};
use crate::io::{ReportDir, fcol, scol, table, ucol};
use crate::lifetime::impacts_in;
use crate::model::Simulator;
use crate::stats::fit_line;
use crate::strength::ParameterSummary;
use crate::weibull::{probability_plot_observed, sorted_quantile};

use super::{LifetimeStudy, MaterialRun, pivotal_seed};

pub(super) fn repeat(s: &str, n: usize) -> Vec<String> {
    vec![s.to_string(); n]
}

pub(super) fn write_particles(dir: &mut ReportDir, runs: &[MaterialRun]) -> Result<()> {
    type Row<'a> = (&'a MaterialRun, &'a crate::data::CrushRecord, &'a ContactState);
    let rows: Vec<Row> = runs
        .iter()
        .flat_map(|run| run.data.records.iter().zip(&run.at_break).map(move |(r, c)| (run, r, c)))
        .collect();
    let text = |f: &dyn Fn(&Row) -> String| rows.iter().map(f).collect::<Vec<_>>();
    let num = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).collect::<Vec<_>>();
    let mut columns = vec![
        scol("material_key", text(&|r| r.0.key.clone())),
        scol("material", text(&|r| r.0.label.clone())),
        scol("id", text(&|r| r.1.id.clone())),
        fcol("diameter_m", num(&|r| r.1.diameter_m)),
        fcol("crush_force_n", num(&|r| r.1.crush_force_n)),
        fcol("roundness", num(&|r| r.1.roundness.unwrap_or(f64::NAN))),
        fcol("sphericity", num(&|r| r.1.sphericity.unwrap_or(f64::NAN))),
        fcol("temperature_c", num(&|r| r.1.temperature_c.unwrap_or(f64::NAN))),
        fcol("contact_radius_m", num(&|r| r.2.radius)),
        fcol("approach_per_contact_m", num(&|r| r.2.approach)),
        fcol("peak_pressure_pa", num(&|r| r.2.peak_pressure)),
        fcol("max_tensile_pa", num(&|r| r.2.max_tensile)),
        fcol("sigma_bar_pa", num(&|r| r.2.mean_tensile)),
    ];
    // What each particle's row says (broke at its force, did not break by it, …) and a force
    // class's upper end: only where some row is not an exact break.
    if runs.iter().any(|r| r.data.censoring.is_some()) {
        let obs: Vec<(crate::obs::Censor, f64)> = runs
            .iter()
            .flat_map(|run| {
                let o = crate::obs::Obs { x: &[], censoring: run.data.censoring.as_ref() };
                (0..run.data.records.len()).map(move |i| (o.kind(i), o.upper(i)))
            })
            .collect();
        columns.push(scol("observed", obs.iter().map(|o| o.0.name().to_string()).collect()));
        columns.push(fcol("crush_force_upper_n", obs.iter().map(|o| o.1).collect()));
    }
    let mut df = table(columns)?;
    dir.write_table("particles", &mut df)
}

pub(super) fn write_weibull(dir: &mut ReportDir, runs: &[MaterialRun], s: &LifetimeStudy) -> Result<()> {
    let n = runs.len();
    let get = |f: &dyn Fn(&MaterialRun) -> f64| runs.iter().map(f).collect::<Vec<f64>>();
    let mut fits = table(vec![
        scol("material_key", runs.iter().map(|r| r.key.clone()).collect()),
        scol("material", runs.iter().map(|r| r.label.clone()).collect()),
        ucol("n", runs.iter().map(|r| r.fit.n as u64).collect()),
        fcol("shape_mle", get(&|r| r.fit.mle.shape)),
        fcol("unbiasing_factor", get(&|r| r.pivotal.unbiasing_factor)),
        fcol("shape_unbiased", get(&|r| r.pivotal.shape_unbiased)),
        fcol("shape_used", get(&|r| r.strength.shape)),
        fcol("scale_pa", get(&|r| r.fit.mle.scale)),
        fcol("confidence", get(&|r| r.pivotal.confidence)),
        fcol("shape_lower", get(&|r| r.pivotal.shape.0)),
        fcol("shape_upper", get(&|r| r.pivotal.shape.1)),
        fcol("scale_lower_pa", get(&|r| r.pivotal.scale.0)),
        fcol("scale_upper_pa", get(&|r| r.pivotal.scale.1)),
        scol("bound_method", runs.iter().map(|r| r.bound_method.to_string()).collect()),
        scol("unbiasing", runs.iter().map(|r| r.unbiasing.to_string()).collect()),
        ucol("not_broken", runs.iter().map(|r| r.observed.view().tally().right as u64).collect()),
        ucol("censored_or_classes", runs.iter().map(|r| { let t = r.observed.view().tally(); (t.right + t.left + t.interval) as u64 }).collect()),
        fcol("fisher_shape_se", get(&|r| r.fisher.shape_se)),
        fcol("fisher_scale_se_pa", get(&|r| r.fisher.scale_se)),
        fcol("fisher_shape_lower", get(&|r| r.fisher.shape.0)),
        fcol("fisher_shape_upper", get(&|r| r.fisher.shape.1)),
        fcol("fisher_scale_lower_pa", get(&|r| r.fisher.scale.0)),
        fcol("fisher_scale_upper_pa", get(&|r| r.fisher.scale.1)),
        fcol("log_likelihood", get(&|r| r.fit.log_likelihood)),
        scol("stress_measure", repeat(&s.contact.averaging.describe(), n)),
    ])?;
    dir.write_table("weibull_fits", &mut fits)?;

    // Probability-plot points: C1239's ranks, or the Kaplan–Meier/Turnbull positions of a
    // censored sample with each point's kind (a censored point is drawn as one).
    let (mut k, mut l, mut x, mut f, mut o) = (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for r in runs {
        for p in probability_plot_observed(r.observed.view()) {
            k.push(r.key.clone());
            l.push(r.label.clone());
            x.push(p.x);
            f.push(p.f);
            o.push(p.kind.name().to_string());
        }
    }
    let mut pts = table(vec![scol("material_key", k), scol("material", l), fcol("sigma_bar_pa", x), fcol("cdf_rank", f), scol("observed", o)])?;
    dir.write_table("weibull_points", &mut pts)?;

    // CDF curve with the pivotal band, on a common stress grid.
    let lo = 0.0;
    let hi = runs.iter().flat_map(|r| r.sigma_bar.iter()).cloned().fold(f64::MIN, f64::max) * 1.25;
    let grid: Vec<f64> = (0..201).map(|i| lo + (hi - lo) * i as f64 / 200.0).collect();
    let a = 0.5 * (1.0 - s.weibull.confidence);
    let (mut k, mut l, mut x, mut c, mut cl, mut cu) = (vec![], vec![], vec![], vec![], vec![], vec![]);
    for r in runs {
        let band: Vec<(f64, f64)> = grid
            .par_iter()
            .map(|&sig| {
                let mut v: Vec<f64> = r.draws.iter().map(|w| w.cdf(sig)).collect();
                v.sort_by(f64::total_cmp);
                (sorted_quantile(&v, a), sorted_quantile(&v, 1.0 - a))
            })
            .collect();
        for (&sig, b) in grid.iter().zip(band) {
            k.push(r.key.clone());
            l.push(r.label.clone());
            x.push(sig);
            c.push(r.strength.cdf(sig));
            cl.push(b.0);
            cu.push(b.1);
        }
    }
    let mut cdf = table(vec![
        scol("material_key", k),
        scol("material", l),
        fcol("sigma_pa", x),
        fcol("cdf", c),
        fcol("cdf_lower", cl),
        fcol("cdf_upper", cu),
    ])?;
    dir.write_table("weibull_cdf", &mut cdf)
}

/// `method` of the size trend of a complete sample.
const LEAST_SQUARES: &str = "least squares on ln σ̄";
/// `method` of the size trend of a censored sample.
const CENSORED_REGRESSION: &str = "Weibull regression on ln d with the censored rows (median line)";

pub(super) fn write_size_trend(dir: &mut ReportDir, runs: &[MaterialRun]) -> Result<()> {
    // Power law σ̄ = e^c d^b: a straight line in log–log coordinates.
    let mut rows: Vec<[f64; 7]> = Vec::new();
    let mut methods = Vec::new();
    for r in runs {
        let d = r.data.diameters();
        let x: Vec<f64> = d.iter().map(|d| d.ln()).collect();
        let f = if r.observed.view().complete() {
            methods.push(LEAST_SQUARES);
            let y: Vec<f64> = r.sigma_bar.iter().map(|s| s.ln()).collect();
            fit_line(&x, &y)?
        } else {
            // A censored σ̄ is a bound, not a strength, and a force limit censors the larger
            // particles first: least squares on the broken ones alone would bend the line. The
            // Weibull regression of σ̄ on ln d with every row as it says (its median line:
            // ln σ̃ = μ + b ln ln 2 + β ln d; Wald p of β; no correlation coefficient).
            methods.push(CENSORED_REGRESSION);
            let cols = vec![x.clone()];
            let reg = crate::strength::regress::fit(r.observed.view(), &crate::strength::regress::Design { columns: &cols, ..Default::default() })?;
            let z = reg.beta[0] / reg.beta_se[0];
            let p = 2.0 * statrs::distribution::ContinuousCDF::sf(&statrs::distribution::Normal::standard(), z.abs());
            crate::stats::LineFit { intercept: reg.mu + reg.b * std::f64::consts::LN_2.ln(), slope: reg.beta[0], slope_se: reg.beta_se[0], r: f64::NAN, p_value: p }
        };
        rows.push([
            f.slope,
            f.slope_se,
            f.intercept,
            f.r,
            f.p_value,
            d.iter().cloned().fold(f64::MAX, f64::min),
            d.iter().cloned().fold(f64::MIN, f64::max),
        ]);
    }
    let col = |i: usize| rows.iter().map(|r| r[i]).collect::<Vec<f64>>();
    let mut df = table(vec![
        scol("material_key", runs.iter().map(|r| r.key.clone()).collect()),
        scol("material", runs.iter().map(|r| r.label.clone()).collect()),
        fcol("exponent", col(0)),
        fcol("exponent_se", col(1)),
        fcol("ln_prefactor", col(2)),
        fcol("pearson_r_log", col(3)),
        fcol("p_value", col(4)),
        fcol("diameter_min_m", col(5)),
        fcol("diameter_max_m", col(6)),
        scol("method", methods.iter().map(|m| m.to_string()).collect()),
    ])?;
    dir.write_table("size_trend", &mut df)
}

pub(super) fn write_stress_profile(dir: &mut ReportDir, runs: &[MaterialRun], s: &LifetimeStudy) -> Result<()> {
    let (mut k, mut l, mut id, mut rr, mut ra, mut sr) = (vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut summary: Vec<(String, String, String, [f64; 7])> = Vec::new();
    for r in runs {
        // The particle whose σ̄ at break is the median (lower middle for even N).
        let mut idx: Vec<usize> = (0..r.sigma_bar.len()).collect();
        idx.sort_by(|&a, &b| r.sigma_bar[a].total_cmp(&r.sigma_bar[b]));
        let i = idx[(idx.len() - 1) / 2];
        let rec = &r.data.records[i];
        let radius = 0.5 * rec.diameter_m;
        let hertz = Hertz::sphere_on_flat(&r.chain.model().sphere.elastic, &s.contact.platen, radius);
        let cs = ContactStress::new(hertz, s.contact.averaging, radius);
        let state = cs.at_force(rec.crush_force_n)?;
        let a = state.radius;
        let l_out = s.contact.averaging.outer_limit(a, radius);
        let r_max = (1.5 * l_out).max(3.0 * a);
        for j in 0..=400 {
            let rv = r_max * j as f64 / 400.0;
            k.push(r.key.clone());
            l.push(r.label.clone());
            id.push(rec.id.clone());
            rr.push(rv);
            ra.push(rv / a);
            sr.push(cs.radial_stress_at(rec.crush_force_n, rv));
        }
        summary.push((
            r.key.clone(),
            r.label.clone(),
            rec.id.clone(),
            [rec.diameter_m, rec.crush_force_n, a, state.peak_pressure, state.mean_tensile, cs.zone.s0 * a, l_out],
        ));
    }
    let mut df = table(vec![
        scol("material_key", k),
        scol("material", l),
        scol("particle_id", id),
        fcol("r_m", rr),
        fcol("r_over_a", ra),
        fcol("sigma_r_pa", sr),
    ])?;
    dir.write_table("stress_profile", &mut df)?;
    let col = |i: usize| summary.iter().map(|s| s.3[i]).collect::<Vec<f64>>();
    let mut df = table(vec![
        scol("material_key", summary.iter().map(|s| s.0.clone()).collect()),
        scol("material", summary.iter().map(|s| s.1.clone()).collect()),
        scol("particle_id", summary.iter().map(|s| s.2.clone()).collect()),
        fcol("diameter_m", col(0)),
        fcol("crush_force_n", col(1)),
        fcol("contact_radius_m", col(2)),
        fcol("peak_pressure_pa", col(3)),
        fcol("sigma_bar_pa", col(4)),
        fcol("domain_start_m", col(5)),
        fcol("domain_end_m", col(6)),
    ])?;
    dir.write_table("stress_profile_summary", &mut df)
}

/// Impact and breakage curves of every material over the velocity grid, through the
/// Simulator interface (σ̄ and F_max of the reference sphere; P of the population); returns the
/// number of evaluations per material.
pub(super) fn write_curves(
    dir: &mut ReportDir,
    runs: &[MaterialRun],
    s: &LifetimeStudy,
    failures: &mut Vec<String>,
) -> Result<Vec<u64>> {
    let np = s.impact.velocity_points;
    let velocities: Vec<f64> = (0..np).map(|i| s.impact.velocity_max_m_s * i as f64 / (np - 1) as f64).collect();
    let (mut ik, mut il, mut iv, mut ifm, mut isb, mut itc, mut ip) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let (mut bk, mut bl, mut bv, mut bn, mut bp) = (vec![], vec![], vec![], vec![], vec![]);
    let mut evaluations = Vec::new();
    for run in runs {
        let thetas: Vec<Vec<f64>> = velocities.iter().map(|&v| run.chain.theta(&run.params, s.impact.energy_fraction, v)).collect();
        let results = run.chain.simulate_batch(&thetas);
        evaluations.push(thetas.len() as u64);
        let impact = run.chain.model().impact(s.impact.energy_fraction);
        let mut ok = Vec::new();
        for ((t, r), &v) in thetas.iter().zip(results).zip(&velocities) {
            match r {
                Ok(y) => ok.push((v, y)),
                Err(e) => failures.push(format!("{}: θ = {t:?}: {e}", run.key)),
            }
        }
        if ok.is_empty() {
            return Err(Error::numerical("impact curves", format!("every evaluation failed for {}", run.key)));
        }
        for (v, y) in &ok {
            ik.push(run.key.clone());
            il.push(run.label.clone());
            iv.push(*v);
            ifm.push(y[0]);
            isb.push(y[1]);
            itc.push(if *v > 0.0 { impact.contact_time(*v) } else { f64::NAN });
            ip.push(y[2]); // counts()[0] is N = 1
        }
        for (ci, &c) in run.chain.counts().iter().enumerate().filter(|(_, c)| s.impact.impact_counts.contains(c)) {
            for (v, y) in &ok {
                bk.push(run.key.clone());
                bl.push(run.label.clone());
                bv.push(*v);
                bn.push(c);
                bp.push(y[2 + ci]);
            }
        }
    }
    let mut df = table(vec![
        scol("material_key", ik),
        scol("material", il),
        fcol("velocity_m_s", iv),
        fcol("f_max_n", ifm),
        fcol("sigma_bar_pa", isb),
        fcol("contact_time_s", itc),
        fcol("p_single", ip),
    ])?;
    dir.write_table("impact_curves", &mut df)?;
    let mut df = table(vec![
        scol("material_key", bk),
        scol("material", bl),
        fcol("velocity_m_s", bv),
        fcol("impacts", bn),
        fcol("p_break", bp),
    ])?;
    dir.write_table("breakage_curves", &mut df)?;
    Ok(evaluations)
}

pub(super) fn write_force_time(dir: &mut ReportDir, runs: &[MaterialRun], s: &LifetimeStudy) -> Result<()> {
    let v = s.impact.reference_velocity_m_s;
    let (mut k, mut l, mut vv, mut t, mut f, mut j) = (vec![], vec![], vec![], vec![], vec![], vec![]);
    for r in runs {
        let impact = r.chain.model().impact(s.impact.energy_fraction);
        for smp in impact.force_history(v, 301)? {
            k.push(r.key.clone());
            l.push(r.label.clone());
            vv.push(v);
            t.push(smp.time);
            f.push(smp.force);
            j.push(smp.impulse);
        }
    }
    let n = t.len();
    let mut df = table(vec![
        scol("material_key", k),
        scol("material", l),
        fcol("velocity_m_s", vv),
        fcol("time_s", t),
        fcol("force_n", f),
        fcol("impulse_n_s", j),
        fcol("energy_fraction", vec![s.impact.energy_fraction; n]),
    ])?;
    dir.write_table("force_time", &mut df)
}

/// The summary's headline lines and its section in a plant engineer's units.
pub(super) struct Summary {
    /// One line per material.
    pub headlines: Vec<String>,
    /// Markdown section: share broken in the first year, years to 1 % and 10 % broken.
    pub attrition: String,
    /// Markdown section `## Answer`: which material breaks least, by how much and how sure
    /// ([`answer`]).
    pub answer: String,
}

pub(super) fn write_summary(dir: &mut ReportDir, runs: &[MaterialRun], s: &LifetimeStudy) -> Result<Summary> {
    use crate::lifetime::attrition::{SHARES, grid, years_to};
    use crate::report::captions::{percent, years_text};
    let v = s.impact.reference_velocity_m_s;
    let t = grid();
    let one = t.iter().position(|&y| (y - 1.0).abs() < 1e-12).unwrap_or(0);
    let longest = t[t.len() - 1];
    let yt = |y: f64| if y.is_infinite() { format!("> {longest:.0}") } else { years_text(y) };
    let conf = 100.0 * s.weibull.confidence;
    let mut att = format!(
        "\n## In a plant engineer's units\n\nAttrition at {v} m/s: the share of the particle inventory broken in the first year of operation ({:.0} impacts per particle), and the years of operation until 1 % and 10 % of it are broken — the estimate and its {conf:.0} % confidence band from the strength law's uncertainty (independent trials). \"> {longest:.0}\": not within {longest:.0} years.\n\n| material | broken in year 1 | years to 1 % broken | years to 10 % broken |\n|---|---|---|---|\n",
        s.impact.impacts_per_year
    );
    let mut a: (Vec<String>, Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 3]>) = Default::default();
    let (mut k, mut l, mut vv, mut yy, mut nn, mut p, mut pl, mut pu) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut headlines = Vec::new();
    for r in runs {
        let model = r.chain.model();
        let counts: Vec<f64> = s.impact.years.iter().map(|&y| impacts_in(y, s.impact.impacts_per_year)).collect();
        let seed = pivotal_seed(s.seed, r.fit.n) ^ 0x5713;
        let bands = model.bands(&r.params, s.impact.energy_fraction, v, &counts, s.strength.uncertainty, s.strength.draws, seed, s.weibull.confidence)?;
        let effects = crate::strength::fit::names(model.fit.effects());
        // Without effects the modulus bounds are C1239's pivotal bounds; with effects, the 90 %
        // range of the model's own draws (the C1239 bounds belong to the law without effects).
        let (lo, hi, what) = match r.summary.iter().find(|p| p.name == "weibull_modulus").filter(|_| !model.fit.effects().is_empty()) {
            Some(p) => (p.q05, p.q95, "range of the model's draws"),
            None => (r.pivotal.shape.0, r.pivotal.shape.1, "bounds"),
        };
        let reference = match model.fit.reference_words() {
            w if w.is_empty() => String::new(),
            w if model.fit.model.scale_columns.is_empty() => format!(" (σ_θ at {w})"),
            w => format!(" (m and σ_θ at {w})"),
        };
        let predicted = if model.population.predicted.is_empty() { String::new() } else { format!(" predicted for {};", model.population.predicted.join(", ")) };
        // What the rows said beyond a break (particles not broken by the rig, classes).
        let tally = r.observed.view().tally();
        let rows = if tally.complete() { String::new() } else { format!(" ({}; m from the censored likelihood, bounds from the censored bootstrap)", tally.describe("particles")) };
        let mut line = format!(
            "{}: N = {}{rows}, m = {:.2} (MLE {:.2}, {:.0} % {what} {lo:.2}–{hi:.2}), σ_θ = {:.0} MPa{reference}; effects: {effects};{predicted} at {v} m/s:",
            r.label,
            r.fit.n,
            r.params.shape,
            model.fit.model.shape(),
            100.0 * s.weibull.confidence,
            r.params.mu.exp() / 1e6
        );
        for ((&years, &n), (point, lo, hi)) in s.impact.years.iter().zip(&counts).zip(bands) {
            k.push(r.key.clone());
            l.push(r.label.clone());
            vv.push(v);
            yy.push(years);
            nn.push(n);
            p.push(point);
            pl.push(lo);
            pu.push(hi);
            line.push_str(&format!(" P({years} yr) = {point:.2e} [{lo:.1e}, {hi:.1e}]"));
        }
        headlines.push(line);
        // The same bands on the grid of horizons: P curves of the draws do not cross (one
        // hazard scales them all), so the band of the years to a share is read off the band's
        // edges, the upper P edge giving the earlier time.
        let grid_counts: Vec<f64> = t.iter().map(|&y| impacts_in(y, s.impact.impacts_per_year)).collect();
        let g = model.bands(&r.params, s.impact.energy_fraction, v, &grid_counts, s.strength.uncertainty, s.strength.draws, seed, s.weibull.confidence)?;
        let (gp, gl, gu): (Vec<f64>, Vec<f64>, Vec<f64>) = (g.iter().map(|x| x.0).collect(), g.iter().map(|x| x.1).collect(), g.iter().map(|x| x.2).collect());
        let to = |x: f64| [years_to(&t, &gu, x), years_to(&t, &gp, x), years_to(&t, &gl, x)];
        let first = [gl[one], gp[one], gu[one]];
        let b3 = |b: &[f64; 3], f: &dyn Fn(f64) -> String| crate::report::captions::with_band(&f(b[1]), &f(b[0]), &f(b[2]));
        att.push_str(&format!("| {} | {} | {} | {} |\n", r.label, b3(&first, &percent), b3(&to(SHARES[0]), &yt), b3(&to(SHARES[1]), &yt)));
        a.0.push(r.label.clone());
        a.1.push(first);
        a.2.push(to(SHARES[0]));
        a.3.push(to(SHARES[1]));
    }
    let q = |v: &[[f64; 3]], i: usize| v.iter().map(|b| b[i]).collect::<Vec<f64>>();
    let na = a.0.len();
    let rows: Vec<Attrition> = a.0.iter().zip(&a.1).zip(&a.2).map(|((label, first), to_1pct)| Attrition { label, first_year: *first, to_1pct: *to_1pct }).collect();
    let answer_text = answer(&rows, v, s.impact.impacts_per_year, s.weibull.confidence);
    dir.write_table(
        "attrition",
        &mut table(vec![
            scol("material", a.0),
            fcol("velocity_m_s", vec![v; na]),
            fcol("first_year_lower", q(&a.1, 0)),
            fcol("first_year", q(&a.1, 1)),
            fcol("first_year_upper", q(&a.1, 2)),
            fcol("years_to_1pct_lower", q(&a.2, 0)),
            fcol("years_to_1pct", q(&a.2, 1)),
            fcol("years_to_1pct_upper", q(&a.2, 2)),
            fcol("years_to_10pct_lower", q(&a.3, 0)),
            fcol("years_to_10pct", q(&a.3, 1)),
            fcol("years_to_10pct_upper", q(&a.3, 2)),
            fcol("confidence", vec![s.weibull.confidence; na]),
        ])?,
    )?;
    let m = p.len();
    let mut df = table(vec![
        scol("material_key", k),
        scol("material", l),
        fcol("velocity_m_s", vv),
        fcol("years", yy),
        fcol("impacts", nn),
        fcol("p_break", p),
        fcol("p_break_lower", pl),
        fcol("p_break_upper", pu),
        fcol("confidence", vec![s.weibull.confidence; m]),
    ])?;
    dir.write_table("lifetime_summary", &mut df)?;
    Ok(Summary { headlines, attrition: att, answer: answer_text })
}

/// One material's attrition at the reference velocity: share broken in the first year and
/// years to 1 % broken, each [lower, estimate, upper] of the confidence band.
pub(super) struct Attrition<'a> {
    pub label: &'a str,
    pub first_year: [f64; 3],
    pub to_1pct: [f64; 3],
}

/// The `## Answer` section, one sentence generated from the attrition rows: which material
/// breaks least in its first year at velocity `v` (ranked by the estimate), by how much, when 1 %
/// of it is broken, and how sure — whether the confidence bands of the first-year share
/// overlap. This study fits each material's strength law on its own; it gives no probability
/// that one breaks more than another (the main study does), and the sentence says so when the
/// bands overlap.
pub(super) fn answer(rows: &[Attrition], v: f64, per_year: f64, confidence: f64) -> String {
    use crate::report::captions::{percent, sig2, with_band, years_text};
    let band = |b: &[f64; 3], f: &dyn Fn(f64) -> String| with_band(&f(b[1]), &f(b[0]), &f(b[2]));
    let years = |y: f64| if y.is_infinite() { "more than 100 years".to_string() } else { format!("{} years", years_text(y)) };
    let years_band = |b: &[f64; 3]| {
        let y = |v: f64| if v.is_infinite() { "> 100".to_string() } else { years_text(v) };
        format!("{} (band {} – {})", years(b[1]), y(b[0]), y(b[2]))
    };
    let conf = format!("{:.0} %", 100.0 * confidence);
    let mut order: Vec<&Attrition> = rows.iter().collect();
    order.sort_by(|a, b| a.first_year[1].total_cmp(&b.first_year[1]));
    let per = format!("{per_year:.0} impacts per particle");
    let sentence = match order.as_slice() {
        [] => return String::new(),
        [one] => format!(
            "**At {v} m/s, {} of {}'s particle inventory breaks in the first year of operation** ({per}; {conf} confidence band {} – {}), and 1 % of it is broken after {}.",
            percent(one.first_year[1]),
            one.label,
            percent(one.first_year[0]),
            percent(one.first_year[2]),
            years_band(&one.to_1pct)
        ),
        [best, next, ..] if best.first_year[1] == next.first_year[1] => {
            format!("**At {v} m/s neither {} nor {} breaks less**: in the first year of operation ({per}) {} of each inventory breaks.", best.label, next.label, percent(best.first_year[1]))
        }
        [best, next, rest @ ..] => {
            let ratio = match next.first_year[1] / best.first_year[1] {
                q if best.first_year[1] > 0.0 && q.is_finite() && q > 1.0 => format!(", {} times less", sig2(q)),
                _ => String::new(),
            };
            let others: String = rest.iter().map(|r| format!(", {} of {}'s", percent(r.first_year[1]), r.label)).collect();
            let overlap = best.first_year[2] >= next.first_year[0];
            let less = if rest.is_empty() { "less" } else { "least" };
            // A verdict in bold only where the bands settle it; else what the estimates say.
            let head = if overlap {
                format!("On the estimates, {} breaks {less} at {v} m/s", best.label)
            } else {
                format!("**{} breaks {less} at {v} m/s**", best.label)
            };
            let (verb, then) = if overlap {
                ("overlap", ": this study does not say how sure the order is — the main study (`kind = \"uq\"`) gives the probability that one breaks more than the other")
            } else {
                ("do not overlap", ", so the order stands within that uncertainty")
            };
            let sure = format!(
                "the {conf} confidence bands of the first-year share, from each strength law's uncertainty, {verb} ({} {}, {} {}){then}",
                best.label,
                band(&best.first_year, &percent),
                next.label,
                band(&next.first_year, &percent)
            );
            format!(
                "{head}: in the first year of operation ({per}) {} of its inventory breaks against {} of {}'s{ratio}{others}, and 1 % of it is broken after {} against {}. How sure: {sure}.",
                percent(best.first_year[1]),
                percent(next.first_year[1]),
                next.label,
                years(best.to_1pct[1]),
                years(next.to_1pct[1])
            )
        }
    };
    format!("## Answer\n\n{sentence}\n\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(label: &str, first: [f64; 3], to_1: [f64; 3]) -> Attrition<'_> {
        Attrition { label, first_year: first, to_1pct: to_1 }
    }

    #[test]
    fn the_answer_ranks_by_the_first_year_and_says_whether_the_bands_overlap() {
        // The shipped lifetime study's rows: BL 16/30 breaks less, the bands overlap (2.1 % > 1.5 %).
        let rows = [row("Gen 4", [0.015, 0.11, 0.44], [0.017, 0.087, 0.65]), row("BL 16/30", [0.00014, 0.0022, 0.021], [0.48, 4.5, 70.0])];
        let a = answer(&rows, 5.0, 730.0, 0.9);
        assert!(a.starts_with("## Answer\n\nOn the estimates, BL 16/30 breaks less at 5 m/s: in the first year of operation (730 impacts per particle) 0.22 % of its inventory breaks against 11 % of Gen 4's, 50 times less, and 1 % of it is broken after 4.5 years against 0.087 years."), "{a}");
        assert!(a.contains("overlap (BL 16/30 0.22 % (0.014 % – 2.1 %), Gen 4 11 % (1.5 % – 44 %)): this study does not say how sure"), "{a}");
        // Apart: the order stands.
        let rows = [row("A", [0.001, 0.002, 0.004], [4.0, 5.0, 9.0]), row("B", [0.01, 0.02, 0.04], [0.3, 0.5, 0.9])];
        let a = answer(&rows, 5.0, 730.0, 0.9);
        assert!(a.contains("**A breaks less at 5 m/s**") && a.contains("10 times less") && a.contains("do not overlap") && a.contains("the order stands"), "{a}");
        // Three materials: "least", and the third's share is given too.
        let rows3 = [row("A", [0.001, 0.002, 0.004], [4.0, 5.0, 9.0]), row("B", [0.01, 0.02, 0.04], [0.3, 0.5, 0.9]), row("C", [0.05, 0.1, 0.2], [0.05, 0.1, 0.2])];
        let a = answer(&rows3, 5.0, 730.0, 0.9);
        assert!(a.contains("**A breaks least at 5 m/s**") && a.contains("2.0 % of B's, 10 times less, 10 % of C's"), "{a}");
        // A tie names neither; one material gives its own numbers, a share never reached says so.
        let rows = [row("A", [0.0, 0.0, 0.0], [f64::INFINITY; 3]), row("B", [0.0, 0.0, 0.0], [f64::INFINITY; 3])];
        assert!(answer(&rows, 5.0, 730.0, 0.9).contains("neither A nor B breaks less"));
        let a = answer(&rows[..1], 5.0, 730.0, 0.9);
        assert!(a.contains("**At 5 m/s, 0 % of A's particle inventory breaks in the first year") && a.contains("more than 100 years"), "{a}");
    }
}

/// The strength model of every material: its effects, population, and each parameter's
/// estimate (the modulus as used for predictions) with the 90 % range of its draws.
pub(super) fn write_strength_fits(dir: &mut ReportDir, runs: &[MaterialRun]) -> Result<()> {
    let mut rows: Vec<(&MaterialRun, &ParameterSummary)> = Vec::new();
    for r in runs {
        rows.extend(r.summary.iter().map(|p| (r, p)));
    }
    let text = |f: &dyn Fn(&(&MaterialRun, &ParameterSummary)) -> String| rows.iter().map(f).collect::<Vec<_>>();
    let num = |f: &dyn Fn(&(&MaterialRun, &ParameterSummary)) -> f64| rows.iter().map(f).collect::<Vec<_>>();
    let mut df = table(vec![
        scol("material_key", text(&|r| r.0.key.clone())),
        scol("material", text(&|r| r.0.label.clone())),
        scol("effects", text(&|r| crate::strength::fit::names(r.0.chain.model().fit.effects()))),
        scol("population", text(&|r| r.0.chain.model().population.source.clone())),
        scol("predicted_for", text(&|r| r.0.chain.model().population.predicted.join("; "))),
        ucol("particles", rows.iter().map(|r| r.0.chain.model().population.len() as u64).collect()),
        scol("parameter", text(&|r| r.1.name.clone())),
        scol("unit", text(&|r| r.1.unit.clone())),
        fcol("mle", num(&|r| r.1.estimate)),
        fcol("used", num(&|r| if r.1.name == "weibull_modulus" { r.0.params.shape } else { r.1.estimate })),
        fcol("q05", num(&|r| r.1.q05)),
        fcol("q95", num(&|r| r.1.q95)),
    ])?;
    dir.write_table("strength_fits", &mut df)
}

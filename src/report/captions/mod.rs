//! What a study kind adds to its document ([`super::build`]): blocks for the first page and, per
//! figure, a title, a caption generated from the numbers the figure shows (read from the same
//! tables it is drawn from) and the rows of its table that matter. A kind or figure without an
//! entry in [`figure`] gets a caption that says it is drawn from the report's tables and names
//! its files — never a sentence about numbers it did not read.
//!
//! The main study, the experiments, lifetime, calibration, crush FE and DEM kinds are here; the
//! discrepancy kinds (strength data and curves) in `discrepancy`, the temperature kind in
//! `temperature` and the microstructure kind in `micro`.

use std::path::Path;

use super::document::{Block, Span, Text};
use super::{Table, pm_text as pm, prob_text};
use crate::error::Result;

mod discrepancy;
mod micro;
mod temperature;

/// The velocity the main study's breakage-against-velocity figure quotes (m/s): the
/// deliverable's largest impact velocity after the receiver (the run puts it on the figure's
/// velocity grid).
pub const REFERENCE_VELOCITY: f64 = 5.0;

/// Blocks for the first page, and summary sections (by heading prefix) to move up to it.
#[derive(Default)]
pub struct FirstPage {
    /// Blocks after the answer.
    pub blocks: Vec<Block>,
    /// Headings of summary sections to move onto the first page.
    pub move_up: Vec<String>,
    /// The figure (file stem) that shows the answer: on the first page, with its caption,
    /// instead of in a section of its own.
    pub figure: Option<String>,
}

/// What a figure's section says.
#[derive(Default)]
pub struct FigureNote {
    /// Title (None: from the file stem).
    pub title: Option<String>,
    /// Caption.
    pub caption: Text,
    /// Blocks after the figure (rows of its table).
    pub blocks: Vec<Block>,
}

/// Text with the summary's markup (`code`, **bold**) as spans.
fn p(t: &str) -> Text {
    super::document::spans(t)
}

/// A probability in a plant engineer's words: a percentage with two significant figures.
pub fn percent(p: f64) -> String {
    if !p.is_finite() {
        return "—".into();
    }
    let v = 100.0 * p;
    if v == 0.0 {
        "0 %".into()
    } else if v < 1e-3 {
        format!("{v:.1e} %")
    } else {
        format!("{} %", sig2(v))
    }
}

/// "value (low – high)", or the value alone when the band is that same text ("> 100", "0 %").
pub fn with_band(value: &str, low: &str, high: &str) -> String {
    if value == low && value == high { value.to_string() } else { format!("{value} ({low} – {high})") }
}

/// Two significant figures, no exponent from 0.001 up ("0.036", "5.3", "49", "1234").
pub fn sig2(v: f64) -> String {
    if v >= 10.0 {
        format!("{v:.0}")
    } else {
        let d = (1.0 - v.log10().floor()).max(0.0) as usize;
        format!("{v:.d$}")
    }
}

/// Years in a plant engineer's words ("never" for an infinite time).
pub fn years_text(y: f64) -> String {
    if y.is_infinite() {
        "never".into()
    } else if !y.is_finite() || y < 0.0 {
        "—".into()
    } else if y < 1e-3 {
        format!("{y:.1e}")
    } else {
        sig2(y)
    }
}

/// First-page blocks of a study kind (and, for a kind whose figures depend on what the study
/// asks, the one its report in `dir` holds).
pub fn first_page(kind: &str, dir: &Path) -> Result<FirstPage> {
    let first_of = |stems: &[&str]| stems.iter().find(|s| dir.join(format!("{s}.svg")).is_file()).map(|s| s.to_string());
    Ok(match kind {
        // The answer (a sentence and the headline model's attrition) and the distributions of
        // both particles' P: the full attrition table and the drivers keep their sections.
        "uq" => FirstPage { figure: Some("uq_distributions".into()), ..FirstPage::default() },
        // The answer, the attrition table it is read from and the breakage curves.
        "lifetime" => FirstPage { move_up: vec!["In a plant engineer's units".into()], figure: Some("fig16_breakage".into()), ..FirstPage::default() },
        // The answer (the plan and what it changes), today's state of knowledge and the
        // candidates' metrics; the budget's steps keep their section.
        "experiments" => FirstPage { move_up: vec!["Today".into()], figure: Some("experiments_metrics".into()), ..FirstPage::default() },
        // The answer (what the model misses, per material) and the evidence of every round.
        "discrepancy" => FirstPage { figure: Some("discrepancy_evidence".into()), ..FirstPage::default() },
        // Breakage against temperature where the study carries it to the lifetime, else the
        // parameters' laws, else the phases.
        "temperature" => FirstPage { figure: first_of(&["breakage_vs_temperature", "parameters_vs_temperature", "phase_fractions"]), ..FirstPage::default() },
        "calibrate" => FirstPage { figure: first_of(&["calibration_fit"]), ..FirstPage::default() },
        "crush" => FirstPage { figure: first_of(&["crush_force_displacement"]), ..FirstPage::default() },
        "dem" => FirstPage { figure: first_of(&["dem_impact_spectra"]), ..FirstPage::default() },
        "microstructure" => FirstPage { figure: first_of(&["comparison"]), ..FirstPage::default() },
        _ => FirstPage::default(),
    })
}

/// The note of figure `stem` of a study kind.
pub fn figure(kind: &str, dir: &Path, stem: &str) -> Result<FigureNote> {
    let note = match (kind, stem) {
        ("uq", _) => uq(dir, stem)?,
        ("experiments", "experiments_metrics") => Some(experiments(dir)?),
        ("lifetime", _) => lifetime(dir, stem)?,
        ("discrepancy", _) => discrepancy::figure(dir, stem)?,
        ("discrepancy_curves", _) => discrepancy::curves(dir, stem)?,
        ("temperature", _) => temperature::figure(dir, stem)?,
        ("microstructure", _) => micro::figure(dir, stem)?,
        ("calibrate", _) => calibration(dir, stem)?,
        ("crush", _) => crush(dir, stem)?,
        ("dem", _) => dem(dir, stem)?,
        _ => None,
    };
    Ok(note.unwrap_or_else(|| FigureNote {
        title: None,
        caption: vec![Span::plain("Drawn from this report's tables; the summary above states its numbers. Files: "), Span { text: format!("{stem}.svg"), bold: false, code: true }, Span::plain(", .pdf, .png.")],
        blocks: vec![],
    }))
}

fn uq_labels(dir: &Path) -> Result<(Vec<String>, Vec<String>, String, String)> {
    let m = Table::load(dir, "materials")?;
    let primary = m.s("primary_strength_model")?.first().cloned().unwrap_or_default();
    let damage = m.s("primary_damage_model")?.first().cloned().unwrap_or_default();
    Ok((m.s("key")?, m.s("label")?, primary, damage))
}

fn yr(y: f64) -> String {
    if y == 1.0 { "1 yr".into() } else { format!("{y} yr") }
}

fn uq(dir: &Path, stem: &str) -> Result<Option<FigureNote>> {
    let (keys, labels, primary, damage) = uq_labels(dir)?;
    let label = |k: &str| keys.iter().position(|x| x == k).map_or(k.to_string(), |i| labels[i].clone());
    let (cand, refr) = (labels.first().cloned().unwrap_or_default(), labels.get(1).cloned().unwrap_or_default());
    Ok(Some(match stem {
        "uq_breakage_vs_velocity" => {
            let t = Table::load(dir, "breakage_vs_velocity")?;
            let (mat, years, v, med, lo, hi) = (t.s("material")?, t.f("years")?, t.f("velocity_m_s")?, t.f("median")?, t.f("q05")?, t.f("q95")?);
            let last = years.iter().cloned().fold(f64::MIN, f64::max);
            let vmax = v.iter().cloned().fold(f64::MIN, f64::max);
            // 5 m/s, the deliverable's maximum after the receiver (on the grid since the
            // runs put it there; older reports: the grid velocity nearest it, said so).
            let five = REFERENCE_VELOCITY;
            let v5 = v.iter().cloned().min_by(|a, b| (a - five).abs().total_cmp(&(b - five).abs())).unwrap_or(five);
            let at_v5 = if v5 == five { format!("{five} m/s") } else { format!("{v5:.2} m/s (the velocity nearest {five} m/s)") };
            let at = |k: &str, vv: f64| (0..mat.len()).find(|&i| mat[i] == k && years[i] == last && v[i] == vv);
            let mut parts = Vec::new();
            for k in &keys {
                if let Some(i) = at(k, v5) {
                    parts.push(format!("{} {} (90 % band {} – {})", label(k), prob_text(med[i]), prob_text(lo[i]), prob_text(hi[i])));
                }
            }
            FigureNote {
                title: Some("Breaking probability against impact velocity".into()),
                caption: p(&format!(
                    "P_break of {cand} and {refr} against the impact velocity (0 – {vmax:.0} m/s), median and 90 % band over every uncertain input except the velocity, under the `{primary}` strength model and {damage}, one panel per horizon. At {at_v5} over {}: {}.",
                    yr(last),
                    parts.join(", ")
                )),
                blocks: vec![],
            }
        }
        "uq_distributions" => {
            let b = Table::load(dir, "breakage")?.filter("strength_model", &primary)?;
            let (mat, model, years, med, lo, hi) = (b.s("material")?, b.s("model")?, b.f("years")?, b.f("median")?, b.f("q05")?, b.f("q95")?);
            let code = model.first().cloned().unwrap_or_default();
            let rows: Vec<Vec<String>> = (0..mat.len()).filter(|&i| model[i] == code).map(|i| vec![label(&mat[i]), yr(years[i]), prob_text(med[i]), format!("{} – {}", prob_text(lo[i]), prob_text(hi[i]))]).collect();
            FigureNote {
                title: Some("Distribution of the breaking probability".into()),
                caption: p(&format!("Density of log₁₀ P_break over the Monte Carlo samples for {cand} and {refr}, `{primary}` strength model, {damage}; the medians and 90 % bands it shows are in the table below.")),
                blocks: vec![Block::Table { header: vec!["material".into(), "horizon".into(), "median P".into(), "90 % band".into()], rows }],
            }
        }
        "uq_convergence" => {
            let t = Table::load(dir, "convergence")?;
            let (years, n, pw, se) = (t.f("years")?, t.f("samples")?, t.f("p_candidate_worse")?, t.f("mc_se")?);
            let nmax = n.iter().cloned().fold(0.0, f64::max);
            let last: Vec<String> = (0..n.len()).filter(|&i| n[i] == nmax).map(|i| format!("{} at {}", pm(pw[i], se[i]), yr(years[i]))).collect();
            FigureNote {
                title: Some("Convergence of the comparison".into()),
                caption: p(&format!("P({cand} breaks more than {refr}) against the number of Monte Carlo samples, with ±2 Monte Carlo standard errors (`{primary}` strength model). With all {nmax:.0} samples: {}.", last.join("; "))),
                blocks: vec![],
            }
        }
        "uq_sobol" | "uq_sobol_convergence" => {
            let t = Table::load(dir, "sobol")?;
            let (out, n, input, s1, s1l, s1h, st, stl, sth, ol) = (t.s("output")?, t.f("n")?, t.s("input")?, t.f("s1")?, t.f("s1_lo")?, t.f("s1_hi")?, t.f("st")?, t.f("st_lo")?, t.f("st_hi")?, t.s("output_label")?);
            let nmax = n.iter().cloned().fold(0.0, f64::max);
            // The intervals' level as the table states it (older reports: the default, 95 %).
            let level = percent(t.f("level").ok().and_then(|l| l.first().copied()).unwrap_or(0.95));
            let mut rows = Vec::new();
            let mut lead = Vec::new();
            // Indices above 1 at the largest size: Monte Carlo error, said so.
            let mut above = Vec::new();
            for o in super::distinct(&out) {
                let mut idx: Vec<usize> = (0..out.len()).filter(|&i| out[i] == o && n[i] == nmax).collect();
                idx.sort_by(|&a, &b| st[b].total_cmp(&st[a]));
                if let Some(&i) = idx.first() {
                    lead.push(format!("{}: {} (S_T = {:.2}, {level} {:.2} – {:.2})", ol[i], input[i], st[i], stl[i], sth[i]));
                }
                above.extend(idx.iter().filter(|&&i| st[i] > 1.0 || s1[i] > 1.0).map(|&i| format!("{} of {} ({:.2})", input[i], ol[i], st[i].max(s1[i]))));
                for &i in idx.iter().take(3) {
                    rows.push(vec![ol[i].clone(), input[i].clone(), format!("{:.2} [{:.2}, {:.2}]", s1[i], s1l[i], s1h[i]), format!("{:.2} [{:.2}, {:.2}]", st[i], stl[i], sth[i])]);
                }
            }
            if stem == "uq_sobol" {
                FigureNote {
                    title: Some("What drives it: Sobol' indices".into()),
                    caption: p(&format!(
                        "First-order (S) and total (S_T) Sobol' indices with their {level} bootstrap intervals, Saltelli base sample {nmax:.0}, `{primary}` strength model, one panel per output. The largest total index per output: {}.{}",
                        lead.join("; "),
                        if above.is_empty() { String::new() } else { format!(" An index is at most 1: the estimates above it — {} — are Monte Carlo error at this sample size (`flag` in `sobol.csv`).", above.join(", ")) }
                    )),
                    blocks: vec![Block::Table { header: vec!["output".into(), "input".into(), format!("S ({level})"), format!("S_T ({level})")], rows }],
                }
            } else {
                let sizes: Vec<f64> = super::distinct(&n);
                FigureNote {
                    title: Some("Convergence of the Sobol' indices".into()),
                    caption: p(&format!(
                        "Total Sobol' indices of the first output against the Saltelli base sample size ({} sizes, {} – {nmax:.0}); flat lines over the last sizes mean the indices have converged. At the largest size: {}.",
                        sizes.len(),
                        sizes.iter().cloned().fold(f64::MAX, f64::min),
                        lead.first().cloned().unwrap_or_default()
                    )),
                    blocks: vec![],
                }
            }
        }
        "uq_model_form" => {
            let b = Table::load(dir, "breakage")?.filter("strength_model", &primary)?;
            let (mat, model, years, med, lo, hi) = (b.s("material")?, b.s("model")?, b.f("years")?, b.f("median")?, b.f("q05")?, b.f("q95")?);
            let rows: Vec<Vec<String>> = (0..mat.len()).map(|i| vec![model[i].replace('_', " "), label(&mat[i]), yr(years[i]), prob_text(med[i]), format!("{} – {}", prob_text(lo[i]), prob_text(hi[i]))]).collect();
            FigureNote {
                title: Some("The damage models side by side".into()),
                caption: p(&format!("P_break of {cand} and {refr} under each damage model (`{primary}` strength model): dot the median, bar the 90 % band; a P of exactly 0 (below Vogel–Peukert's threshold) sits on the axis floor. The values are in the table below.")),
                blocks: vec![Block::Table { header: vec!["damage model".into(), "material".into(), "horizon".into(), "median P".into(), "90 % band".into()], rows }],
            }
        }
        "uq_strength_models" => {
            let c = Table::load(dir, "comparison")?.filter("model", &damage_code(dir)?)?;
            let (sm, years, pw, se) = (c.s("strength_model")?, c.f("years")?, c.f("p_candidate_worse")?, c.f("mc_se")?);
            let w = Table::load(dir, "weights")?;
            let (wn, ww) = (w.s("strength_model")?, w.f("weight_stacking")?);
            let rows: Vec<Vec<String>> = (0..sm.len())
                .map(|i| {
                    let weight = wn.iter().position(|x| *x == sm[i]).map_or("1 (average)".into(), |j| format!("{:.3}", ww[j]));
                    vec![sm[i].clone(), weight, yr(years[i]), pm(pw[i], se[i])]
                })
                .collect();
            let best = (0..wn.len()).max_by(|&a, &b| ww[a].total_cmp(&ww[b]));
            FigureNote {
                title: Some("The strength models side by side".into()),
                caption: p(&format!(
                    "P({cand} breaks more than {refr}) under each strength model and averaged with the stacking weights (±2 Monte Carlo standard errors), and P_break at the last horizon per material (median, 90 % band). The stacking weights put {} on `{}`.",
                    best.map_or("—".into(), |j| format!("{:.3}", ww[j])),
                    best.map_or("—".into(), |j| wn[j].clone())
                )),
                blocks: vec![Block::Table { header: vec!["strength model".into(), "stacking weight".into(), "horizon".into(), format!("P({cand} worse) ± se")], rows }],
            }
        }
        _ => return Ok(None),
    }))
}

/// The primary damage model's code (`independent`) from `breakage.csv`'s first row.
fn damage_code(dir: &Path) -> Result<String> {
    Ok(Table::load(dir, "comparison")?.s("model")?.first().cloned().unwrap_or_default())
}


/// Two decimals with a typographic minus ("−0.54").
fn minus(v: f64) -> String {
    format!("{v:.2}").replace('-', "−")
}

/// Per material of a lifetime report, `f(label, row)` over the rows of `table`.
fn per_material(dir: &Path, table: &str, f: &dyn Fn(&Table, usize) -> Result<String>) -> Result<String> {
    let t = Table::load(dir, table)?;
    let labels = t.s("material")?;
    let parts: Vec<String> = (0..labels.len()).map(|i| Ok(format!("{} {}", labels[i], f(&t, i)?))).collect::<Result<_>>()?;
    Ok(parts.join("; "))
}

/// The deliverable's figures (Figs. 5, 13–16) of a lifetime report.
fn lifetime(dir: &Path, stem: &str) -> Result<Option<FigureNote>> {
    let note = |title: &str, caption: String| Some(FigureNote { title: Some(title.into()), caption: p(&caption), blocks: vec![] });
    Ok(match stem {
        "fig05_force_time" => {
            let t = Table::load(dir, "force_time")?;
            let (mat, f, v) = (t.s("material")?, t.f("force_n")?, t.f("velocity_m_s")?);
            let mut parts = Vec::new();
            for m in super::distinct(&mat) {
                let peak = (0..mat.len()).filter(|&i| mat[i] == m).map(|i| f[i]).fold(0.0, f64::max);
                parts.push(format!("{m} {peak:.1} N"));
            }
            note("Impact force and impulse (deliverable Fig. 5)", format!("Contact force and running impulse against time of one particle hitting a steel tube at {} m/s; peak force {}.", v.first().copied().unwrap_or(f64::NAN), parts.join(", ")))
        }
        "fig13_stress_profile" => note(
            "Radial surface stress of the crush test (deliverable Fig. 13)",
            format!(
                "Radial surface stress against distance from the contact centre for the median particle at its crush force, and σ̄, the mean tensile σᵣ over its averaging domain (dashed): {}.",
                per_material(dir, "stress_profile_summary", &|t, i| Ok(format!("d = {:.2} mm, F = {:.0} N, σ̄ = {:.0} MPa", t.f("diameter_m")?[i] * 1e3, t.f("crush_force_n")?[i], t.f("sigma_bar_pa")?[i] / 1e6)))?
            ),
        ),
        "fig14_sigma_vs_diameter" => note(
            "Strength against particle size (deliverable Fig. 14, left)",
            format!(
                "σ̄ at break against particle diameter with a power-law fit σ̄ ∝ d^b: {}.",
                per_material(dir, "size_trend", &|t, i| {
                    let r = t.f("pearson_r_log")?[i];
                    Ok(if r.is_finite() {
                        format!("b = {} ± {:.2} (r = {}, p = {})", minus(t.f("exponent")?[i]), t.f("exponent_se")?[i], minus(r), prob_text(t.f("p_value")?[i]))
                    } else {
                        format!("b = {} ± {:.2} (Weibull regression with the particles not broken by the limit as censored, open circles; median line; Wald p = {})", minus(t.f("exponent")?[i]), t.f("exponent_se")?[i], prob_text(t.f("p_value")?[i]))
                    })
                })?
            ),
        ),
        "fig14_weibull_cdf" => note(
            "Weibull strength distribution (deliverable Fig. 14, right)",
            format!(
                "Breaking probability against σ̄ at break: {}: {}.",
                {
                    // A censored sample (weibull_points `observed`; older reports lack it).
                    let censored = Table::load(dir, "weibull_points")?.s("observed").is_ok_and(|o| o.iter().any(|k| k != "exact"));
                    if censored {
                        "the data at Kaplan–Meier positions (open circles: not broken by the rig's limit, or broke within a class), the Weibull law fitted with them as censored and its confidence band from the bootstrap that censors each redraw as the campaign did"
                    } else {
                        "the data at (i − 0.5)/N, the fitted Weibull law (ASTM C1239) and its pivotal confidence band"
                    }
                },
                per_material(dir, "weibull_fits", &|t, i| Ok(format!(
                    "N = {:.0}, m = {:.2} ({:.0} % bounds {:.2}–{:.2}), σθ = {:.0} MPa",
                    t.f("n")?[i],
                    t.f("shape_used")?[i],
                    100.0 * t.f("confidence")?[i],
                    t.f("shape_lower")?[i],
                    t.f("shape_upper")?[i],
                    t.f("scale_pa")?[i] / 1e6
                )))?
            ),
        ),
        "fig15_impact" => {
            let t = Table::load(dir, "impact_curves")?;
            let (mat, v, f, sb) = (t.s("material")?, t.f("velocity_m_s")?, t.f("f_max_n")?, t.f("sigma_bar_pa")?);
            let vmax = v.iter().cloned().fold(0.0, f64::max);
            let parts: Vec<String> = (0..mat.len()).filter(|&i| v[i] == vmax).map(|i| format!("{} F_max = {:.1} N, σ̄ = {:.0} MPa", mat[i], f[i], sb[i] / 1e6)).collect();
            note("Impact load against velocity (deliverable Fig. 15)", format!("Maximum contact force and σ̄ at that force against the impact velocity on a steel tube; at {vmax:.0} m/s: {}.", parts.join("; ")))
        }
        "fig16_breakage" => note(
            "Breaking probability after repeated impacts (deliverable Fig. 16)",
            format!(
                "Breaking probability after N impacts against the impact velocity (independent trials, lines); the dots with bars at the reference velocity, {} m/s, are the lifetimes the study reports (each material's horizons side by side, shortest first), with their bands: {}.",
                Table::load(dir, "lifetime_summary")?.f("velocity_m_s")?.first().copied().unwrap_or(f64::NAN),
                per_material(dir, "lifetime_summary", &|t, i| Ok(format!(
                    "{} yr ({:.0} impacts) {} ({:.0} % band {} – {})",
                    t.f("years")?[i],
                    t.f("impacts")?[i],
                    prob_text(t.f("p_break")?[i]),
                    100.0 * t.f("confidence")?[i],
                    prob_text(t.f("p_break_lower")?[i]),
                    prob_text(t.f("p_break_upper")?[i])
                )))?
            ),
        ),
        _ => None,
    })
}

/// Figures of a calibration report.
fn calibration(dir: &Path, stem: &str) -> Result<Option<FigureNote>> {
    let t = Table::load(dir, "parameters")?;
    let (name, unit, mean, q05, q95, rhat, ess) = (t.s("name")?, t.s("unit")?, t.f("posterior_mean")?, t.f("q05")?, t.f("q95")?, t.f("r_hat")?, t.f("ess_bulk")?);
    let value = |v: f64, u: &str| if u == "Pa" { format!("{:.3} GPa", v / 1e9) } else { format!("{v:.3}") };
    Ok(Some(match stem {
        "calibration_corner" => {
            let c = Table::load(dir, "correlation")?;
            let names = c.s("name")?;
            // The strongest posterior correlation between two parameters.
            let mut best = (0.0f64, String::new(), String::new());
            for (i, a) in names.iter().enumerate() {
                for b in names.iter().skip(i + 1) {
                    let r = c.f(b)?[i];
                    if r.abs() > best.0.abs() {
                        best = (r, a.clone(), b.clone());
                    }
                }
            }
            let rows: Vec<Vec<String>> = (0..name.len()).map(|i| vec![name[i].clone(), value(mean[i], &unit[i]), format!("{} – {}", value(q05[i], &unit[i]), value(q95[i], &unit[i]))]).collect();
            FigureNote {
                title: Some("Posterior of the calibrated constants".into()),
                caption: p(&format!(
                    "Posterior pair plot: each constant's histogram and the draws of every pair. The strongest correlation is between {} and {} (r = {}); means and 90 % intervals are in the table below.",
                    best.1,
                    best.2,
                    minus(best.0)
                )),
                blocks: vec![Block::Table { header: vec!["constant".into(), "posterior mean".into(), "90 % interval".into()], rows }],
            }
        }
        "calibration_comparison" => {
            let c = Table::load(dir, "comparison")?;
            let (names, rl, tl, ch) = (c.s("name")?, c.s("reference_label")?, c.s("this_label")?, c.f("change_percent")?);
            let (reference, this) = (rl.first().cloned().unwrap_or_default(), tl.first().cloned().unwrap_or_default());
            let changes: Vec<String> = (0..names.len()).map(|i| format!("{} {} %", names[i], format!("{:+.1}", ch[i]).replace('-', "−"))).collect();
            let big: Vec<&str> = (0..names.len()).filter(|&i| ch[i].abs() > 30.0).map(|i| names[i].as_str()).collect();
            let big = if big.is_empty() { "No mean moves by more than 30 %.".to_string() } else { format!("More than 30 % (red): {}.", big.join(", ")) };
            FigureNote {
                title: Some(format!("{this} against {reference}")),
                caption: p(&format!("Posterior mean and 90 % interval of each constant in {reference} and in this calibration ({this}), with the change of the mean shaded by size (pale below 10 %, amber to 30 %, red above): {}. {big}", changes.join(", "))),
                blocks: vec![],
            }
        }
        "calibration_trace" => FigureNote {
            title: Some("MCMC traces".into()),
            caption: p(&format!(
                "Traces of four walkers per constant; R̂ {} and bulk effective sample sizes {} (R̂ ≤ 1.01 and ESS ≥ 400 say the chains mixed).",
                (0..name.len()).map(|i| format!("{} {:.3}", name[i], rhat[i])).collect::<Vec<_>>().join(", "),
                (0..name.len()).map(|i| format!("{} {:.0}", name[i], ess[i])).collect::<Vec<_>>().join(", ")
            )),
            blocks: vec![],
        },
        "calibration_fit" | "calibration_residuals" => {
            let o = Table::load(dir, "observations")?;
            let (v, lo, hi) = (o.f("value")?, o.f("predictive_q05")?, o.f("predictive_q95")?);
            let inside = (0..v.len()).filter(|&i| v[i] >= lo[i] && v[i] <= hi[i]).count();
            let share = format!("{inside} of {} observations ({}) lie inside their 90 % posterior-predictive interval", v.len(), percent(inside as f64 / v.len().max(1) as f64));
            if stem == "calibration_fit" {
                // Curve calibrations draw every particle scaled to one reference diameter.
                let scaled = match Table::load(dir, "grid").ok().and_then(|g| g.f("reference_diameter_m").ok()).and_then(|d| d.first().copied()) {
                    Some(d0) if dir.join("curves.csv").is_file() => format!(" Each particle's curve is scaled to the reference diameter D₀ = {:.0} µm (force × (D₀/D)², displacement × D₀/D).", d0 * 1e6),
                    _ => String::new(),
                };
                FigureNote { title: Some("Measured against calibrated".into()), caption: p(&format!("The measurements with the calibrated model at posterior draws and its 90 % posterior-predictive band: {share}.{scaled}")), blocks: vec![] }
            } else {
                FigureNote { title: Some("Standardised residuals".into()), caption: p(&format!("Standardised residuals (d − median)/σ of every observation with the 90 % predictive band: {share}.")), blocks: vec![] }
            }
        }
        _ => return Ok(None),
    }))
}

/// Figures of a crush FE report.
fn crush(dir: &Path, stem: &str) -> Result<Option<FigureNote>> {
    let t = Table::load(dir, "crush_summary")?;
    let (label, d, peak, at, frac, warn) = (t.s("label")?, t.f("diameter_m")?, t.f("peak_force_n")?, t.f("peak_displacement_m")?, t.f("fracture_displacement_m")?, t.s("quasi_static_warning")?);
    let first = label.first().cloned().unwrap_or_default();
    let snapshot = || -> Result<String> {
        let f = Table::load(dir, "fields")?;
        let u = f.f("displacement_m")?;
        Ok(format!("{:.1} µm", u.iter().cloned().fold(0.0, f64::max) * 1e6))
    };
    Ok(Some(match stem {
        "crush_force_displacement" => {
            let parts: Vec<String> = (0..label.len())
                .map(|i| {
                    let q = if warn[i].is_empty() { String::new() } else { format!(" ({})", warn[i]) };
                    format!("{} (d = {:.2} mm): peak {:.1} N at δ = {:.1} µm, fracture at δ = {:.1} µm{q}", label[i], d[i] * 1e3, peak[i], at[i] * 1e6, frac[i] * 1e6)
                })
                .collect();
            FigureNote { title: Some("Force against platen displacement".into()), caption: p(&format!("Crush force against platen displacement per case, fracture marked: {}.", parts.join("; "))), blocks: vec![] }
        }
        "crush_strain_map" | "crush_strain_map_contact" => FigureNote {
            title: Some(if stem == "crush_strain_map" { "Maximum principal strain, whole section".into() } else { "Maximum principal strain at the contact".into() }),
            caption: p(&format!("Maximum principal log strain of {first} in the axisymmetric section at the last snapshot (platen displacement {}); the colour range is ± the 98th percentile of |ε₁| in the window.", snapshot()?)),
            blocks: vec![],
        },
        "crush_depth_profile" => {
            let dp = Table::load(dir, "depth_profile")?;
            let (case, u, z, e1, e3) = (dp.s("case")?, dp.f("displacement_m")?, dp.f("depth_m")?, dp.f("max_principal_log_strain")?, dp.f("min_principal_log_strain")?);
            // The first case's last snapshot.
            let c0 = case.first().cloned().unwrap_or_default();
            let last = (0..u.len()).filter(|&i| case[i] == c0).map(|i| u[i]).fold(f64::MIN, f64::max);
            let rows: Vec<usize> = (0..u.len()).filter(|&i| case[i] == c0 && u[i] == last).collect();
            let i = rows.iter().copied().max_by(|&a, &b| e1[a].total_cmp(&e1[b]));
            let j = rows.iter().copied().min_by(|&a, &b| e3[a].total_cmp(&e3[b]));
            let strain = |v: f64| format!("{v:.4}").replace('-', "−");
            FigureNote {
                title: Some("Principal strains below the contact".into()),
                caption: p(&format!(
                    "Principal log strains on the axis below the contact against depth ({first}); at the last snapshot (platen displacement {:.1} µm) the largest ε₁ is {} at a depth of {}, the most compressive ε₃ {} at {}.",
                    last * 1e6,
                    i.map_or("—".into(), |i| strain(e1[i])),
                    i.map_or("—".into(), |i| format!("{:.1} µm", z[i] * 1e6)),
                    j.map_or("—".into(), |j| strain(e3[j])),
                    j.map_or("—".into(), |j| format!("{:.1} µm", z[j] * 1e6))
                )),
                blocks: vec![],
            }
        }
        _ => return Ok(None),
    }))
}

/// Figures of a DEM report.
fn dem(dir: &Path, stem: &str) -> Result<Option<FigureNote>> {
    Ok(Some(match stem {
        "dem_velocity_profile" => {
            let t = Table::load(dir, "velocity_profile")?;
            let v = t.f("mean_vz_m_s")?;
            let (lo, hi) = (v.iter().cloned().fold(f64::MAX, f64::min), v.iter().cloned().fold(f64::MIN, f64::max));
            FigureNote {
                title: Some("Mean vertical velocity through the bank (deliverable Fig. 4, right)".into()),
                caption: p(&format!("Mean vertical particle velocity against height through the tube bank, tube rows marked; it oscillates between {} and {} m/s.", minus(lo), minus(hi))),
                blocks: vec![],
            }
        }
        "dem_speed_map" => FigureNote {
            title: Some("Mean speed between the tubes (deliverable Fig. 4, left)".into()),
            caption: p("Time-averaged particle speed on a grid over the section of the bank, the tubes drawn in; the values are in `speed_map.csv`."),
            blocks: vec![],
        },
        "dem_impact_spectra" => {
            let t = Table::load(dir, "impact_spectrum")?;
            let (target, row, n, q50, q95) = (t.s("target")?, t.f("row")?, t.f("impacts")?, t.f("q50_v_normal_m_s")?, t.f("q95_v_normal_m_s")?);
            // Row 0 holds every impact of its target.
            let rows: Vec<Vec<String>> = (0..row.len()).map(|i| vec![target[i].clone(), if row[i] == 0.0 { "all".into() } else { format!("{}", row[i]) }, format!("{:.0}", n[i]), format!("{:.3}", q50[i]), format!("{:.3}", q95[i])]).collect();
            let top = (0..row.len()).filter(|&i| target[i] == "tube" && row[i] > 0.0).max_by(|&a, &b| q95[a].total_cmp(&q95[b]));
            FigureNote {
                title: Some("Impact velocities per tube row".into()),
                caption: p(&format!(
                    "Distribution of the normal impact velocities per row of the bank ({}); the highest 95th percentile on a tube is {}. Impacts and quantiles per row are in the table below.",
                    super::distinct(&target).iter().map(|t| match t.as_str() { "tube" => "on the tubes".to_string(), "particle" => "between particles".to_string(), o => format!("on {o}") }).collect::<Vec<_>>().join(" and "),
                    top.map_or("—".into(), |i| format!("{:.3} m/s (row {})", q95[i], row[i]))
                )),
                blocks: vec![Block::Table { header: vec!["target".into(), "row".into(), "impacts".into(), "median v_n (m/s)".into(), "95th percentile (m/s)".into()], rows }],
            }
        }
        "dem_force_time" => {
            let t = Table::load(dir, "force_trace")?;
            let (f, j, v) = (t.f("normal_force_n")?, t.f("cumulative_impulse_n_s")?, t.f("v_normal_m_s")?);
            FigureNote {
                title: Some("Force of one impact (deliverable Fig. 5)".into()),
                caption: p(&format!(
                    "Normal contact force and its running impulse during one recorded tube impact at {:.2} m/s: peak force {:.3} N, impulse {:.3} µN·s.",
                    v.first().copied().unwrap_or(f64::NAN),
                    f.iter().cloned().fold(0.0, f64::max),
                    j.last().copied().unwrap_or(f64::NAN) * 1e6
                )),
                blocks: vec![],
            }
        }
        _ => return Ok(None),
    }))
}

fn experiments(dir: &Path) -> Result<FigureNote> {
    let t = Table::load(dir, "plans")?;
    let (cand, size, pcs, evsi) = (t.s("candidate")?, t.f("size")?, t.f("pcs")?, t.f("evsi")?);
    let currency = t.s("currency")?.first().cloned().unwrap_or_default();
    let cands = super::distinct(&cand);
    let mut rows = Vec::new();
    for c in &cands {
        // The largest size evaluated for each candidate.
        if let Some(i) = (0..cand.len()).filter(|&i| &cand[i] == c).max_by(|&a, &b| size[a].total_cmp(&size[b])) {
            rows.push(vec![c.clone(), format!("{:.0}", size[i]), format!("{:.3}", pcs[i]), format!("{:.3}", evsi[i])]);
        }
    }
    let best = (0..cand.len()).max_by(|&a, &b| evsi[a].total_cmp(&evsi[b]));
    Ok(FigureNote {
        title: Some("What each candidate experiment would teach".into()),
        caption: p(&format!(
            "Each metric against the number of tests, one line per candidate experiment ({} candidates): probability of choosing the better particle, expected posterior weight of the true damage model, expected width of the 90 % bands of P_break, and the expected value of sample information (EVSI, {currency}); bars: ±2 Monte Carlo standard errors (the summed band widths have none). The largest EVSI is {} with {}.",
            cands.len(),
            best.map_or("—".into(), |i| format!("{:.3} {currency}", evsi[i])),
            best.map_or("—".into(), |i| format!("{} × {:.0}", cand[i], size[i]))
        )),
        blocks: vec![Block::Table { header: vec!["candidate".into(), "largest size".into(), "P(correct choice)".into(), format!("EVSI ({currency})")], rows }],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plant_units() {
        assert_eq!(percent(0.0), "0 %");
        assert_eq!(percent(0.2038), "20 %");
        assert_eq!(percent(0.0204), "2.0 %");
        assert_eq!(percent(0.00096), "0.096 %");
        assert_eq!(percent(2.5e-7), "2.5e-5 %");
        assert_eq!(years_text(f64::INFINITY), "never");
        assert_eq!(years_text(0.4937), "0.49");
        assert_eq!(years_text(0.0361), "0.036");
        assert_eq!(years_text(5.35), "5.3");
        assert_eq!(years_text(37.2), "37");
    }
}

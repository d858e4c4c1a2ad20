//! `[[validation]]` of a temperature study: crush data measured at a temperature the laws were not
//! fitted to, predicted from the laws.
//!
//! ```toml
//! [[validation]]
//! temperature_c = 950                   # the temperature of the held-out data (°C)
//! study = "calibrate_gen3_950c.toml"    # a crush calibration study of that data (read, not run)
//! draws = 24                            # joint draws run through the crush FE per source
//! ```
//!
//! The calibration study supplies what a prediction of its data needs besides the calibrated
//! constants: the data and their reduction (forces at grid displacements, peak force, fracture
//! displacement, normalised to the mean diameter D₀; σ the scatter between particles), the crush
//! model (mesh, platen, the constants without a law) and the relative model error. Each of its
//! `[[param]]` must have a temperature law.
//!
//! Three sources predict the data, each through the crush FE (the [`crate::model::Simulator`]
//! of the study) at `draws` joint parameter draws:
//!
//! * the laws at the data's temperature;
//! * each calibrated state as it is — its posterior draws, as if temperature did not matter
//!   between it and the data. The nearer state shows how much the laws add over it.
//!
//! An observation lies inside its predictive interval at probability `level` when it is within
//! z·√(var_runs + σ² + (model_error·mean)²) of the runs' mean
//! ([`crate::calibrate::check::predictive_interval`], the calibration's own check). The summary
//! says whether the laws cover as many observations as their intervals claim: below 1 %
//! binomial probability of so few inside at `level`, it says the laws (their form or their
//! bands) miss something there — a held-out truth of the laws' own form can pass this check by
//! construction, so the shipped study also holds out curves of another form. With
//! `partlife run --executor slurm` the FE runs are Slurm array tasks
//! ([`crate::calibrate::executor`]; the calibration study's `[executor]` options). Writes
//! `validation.csv` (per data set — its calibration study and that study's `label` — source and output: the grid displacement of a grid force, the level, observed mean,
//! predicted centre and interval, observations inside), `validation_observations.csv` (every
//! observation, normalised to D₀) and `validation_parameters.csv` (the laws' median and band of
//! every parameter at the data's temperature); figure `held_out`.

use std::path::{Path, PathBuf};

use statrs::distribution::{ContinuousCDF, Normal};

use super::study::ValidationOptions;
use crate::calibrate::Runner;
use crate::calibrate::cache::Cached;
use crate::calibrate::executor::{Dispatched, Slurm};
use crate::calibrate::check::predictive_interval;
use crate::calibrate::study::{Built, CalibrateStudy};
use crate::error::{Error, Result};
use crate::io::{ReportDir, fcol, scol, table, ucol};
use crate::model::Simulator;
use crate::schema::StudyFile;
use crate::stats::median_and_band as band;
use crate::thermal::ParameterLaws;

/// The sources that predict held-out data.
pub const SOURCES: usize = 3;

/// One row of `validation.csv`.
struct Row {
    study: String,
    label: String,
    temperature_c: f64,
    source: String,
    source_kind: &'static str,
    source_temperature_c: f64,
    output: String,
    grid_displacement_m: f64,
    unit: String,
    observations: u64,
    observed_mean: f64,
    predicted: f64,
    lo: f64,
    hi: f64,
    inside: u64,
    /// Σ over the row's observations of the log predictive density.
    lpd: f64,
}

/// ln of the normal predictive density, mean `centre` and sd `half`/z (the interval
/// centre ± half is its central interval at z), at `y`. Summed over held-out observations it is
/// the log score, a proper scoring rule: unlike coverage, a wider predictive does not score
/// better by covering more (Gneiting & Raftery 2007). Differences between sources on the same
/// observations are free of the observations' units.
pub fn log_predictive_density(y: f64, centre: f64, half: f64, z: f64) -> f64 {
    use statrs::distribution::{Continuous, Normal};
    Normal::new(centre, half / z).map_or(f64::NAN, |n| n.ln_pdf(y))
}

/// Predicts every `[[validation]]` data set; `tick` after each source. With `slurm` (the reports
/// root) the FE runs go to Slurm array jobs ([`crate::calibrate::executor`], the held-out
/// calibration study's `[executor]` options) through the evaluation cache that study's own
/// calibration uses (`<root>/.cache/<its name>/`); their events are appended to `events`.
/// Returns the summary's section, the files read and the FE runs made.
#[allow(clippy::too_many_arguments)]
pub(super) fn write_validation(dir: &mut ReportDir, file: &str, vs: &[ValidationOptions], laws: &ParameterLaws, level: f64, resolve: &dyn Fn(&Path) -> PathBuf, tick: &(dyn Fn() + Sync), slurm: Option<&Path>, events: &mut Vec<String>) -> Result<(String, Vec<PathBuf>, u64)> {
    let z = Normal::new(0.0, 1.0).map_err(|e| Error::numerical("validation", e.to_string()))?.inverse_cdf(0.5 + 0.5 * level);
    let pct = (100.0 * level).round();
    let (mut rows, mut prows, mut orows) = (Vec::<Row>::new(), Vec::new(), Vec::new());
    let (mut inputs, mut fe_runs, mut md) = (Vec::new(), 0u64, Vec::new());
    for (i, v) in vs.iter().enumerate() {
        let key = format!("validation[{i}]");
        let t = v.temperature_c;
        laws.check_range(file, &format!("{key}.temperature_c"), t, t)?;
        let path = resolve(&v.study);
        if !path.is_file() {
            return Err(Error::config(file, format!("{key}.study"), format!("{} does not exist", path.display())));
        }
        let loaded = StudyFile::read(&path)?;
        if loaded.kind(&["calibrate"])? != "calibrate" {
            return Err(Error::config(file, format!("{key}.study"), format!("{} must be a calibration study (kind = \"calibrate\") of the held-out crush curves", path.display())));
        }
        let cs: CalibrateStudy = loaded.parse()?;
        let prep = cs.prepare(&path, &|p: &str| loaded.resolve(Path::new(p)))?;
        let Built::Crush(model, red) = &prep.built else {
            return Err(Error::config(file, format!("{key}.study"), format!("{} is not a crush calibration (model kind = \"crush\" on crush curves): the laws are of crush constants", path.display())));
        };
        if (red.temperature_c - t).abs() > crate::intake::observed::TEMPERATURE_TOLERANCE_C {
            return Err(Error::config(file, format!("{key}.temperature_c"), format!("{t} °C, but the curves of {} were measured at {} °C: the laws are checked at the curves' own temperature", path.display(), red.temperature_c)));
        }
        inputs.push(path.clone());
        inputs.extend(prep.inputs.iter().cloned());
        // The law of each of the study's parameters.
        let map: Vec<usize> = cs
            .param
            .iter()
            .map(|p| {
                laws.names.iter().position(|n| *n == p.name).ok_or_else(|| {
                    Error::config(file, format!("{key}.study"), format!("the parameter `{}` of {} has no temperature law (the laws are of {})", p.name, path.display(), laws.names.join(", ")))
                })
            })
            .collect::<Result<_>>()?;
        let n = laws.len();
        let draws = v.draws.min(n);
        let picks: Vec<usize> = (0..draws).map(|k| k * n / draws).collect();
        let mut sources: Vec<(String, &'static str, f64, Vec<Vec<f64>>)> = Vec::new();
        let law_thetas: Vec<Vec<f64>> = picks.iter().map(|&j| laws.values_at(j, t).map(|all| map.iter().map(|&k| all[k]).collect())).collect::<Result<_>>()?;
        sources.push((format!("laws at {t} °C"), "laws", t, law_thetas));
        for (tc, cols) in &laws.calibrated {
            sources.push((format!("calibrated state at {tc} °C, as is"), "calibrated state", *tc, picks.iter().map(|&j| map.iter().map(|&k| cols[k][j]).collect()).collect()));
        }
        // The laws' parameters at the data's temperature.
        let params = model.space().params();
        let mut shown = Vec::new();
        for (k, p) in params.iter().enumerate() {
            let all: Vec<f64> = (0..n).map(|j| laws.values_at(j, t).map(|v| v[map[k]])).collect::<Result<_>>()?;
            let b = band(all, level);
            shown.push(if p.unit == "Pa" { format!("{} {:.3} GPa [{:.3}, {:.3}]", p.name, b.0 / 1e9, b.1 / 1e9, b.2 / 1e9) } else { format!("{} {:.3} [{:.3}, {:.3}]", p.name, b.0, b.1, b.2) });
            prows.push((v.study.display().to_string(), t, p.name.clone(), p.unit.clone(), b));
        }
        let obs = &prep.observations;
        let outputs = model.outputs();
        for i in 0..obs.len() {
            orows.push((v.study.display().to_string(), outputs[obs.output[i]].name.clone(), red.curves[obs.group[i]].particle.clone(), obs.values[i]));
        }
        let model_error = cs.calibration.model_error;
        // The synthetic label travels with the data file, never with the sentence.
        let synthetic: String = prep.inputs.iter().filter_map(|p| crate::intake::synthetic_label(p)).map(|l| format!(" These curves are **synthetic stand-ins** ({l})."))
            .next()
            .unwrap_or_default();
        // Slurm: one driver for this data set's runs, on its calibration's cache.
        let slurm = match slurm {
            Some(root) => {
                let cache_dir = root.join(".cache").join(loaded.name.as_str());
                let driver = Slurm::new(&cs.executor, &path, &cache_dir, &prep.config)?;
                Some((Cached::new(model, &cache_dir, prep.config.clone())?, driver))
            }
            None => None,
        };
        let mut lines = vec![format!("| source | inside its {pct} % interval | peak force: observed mean; predicted [{pct} % interval] (N) |"), "|---|---|---|".into()];
        let (mut coverage, mut inside_counts, mut scores) = (Vec::new(), Vec::new(), Vec::new());
        for (label, kind, ts, thetas) in &sources {
            let (runs, runner_failures) = match &slurm {
                None => {
                    let mut runner = Runner::new(model);
                    let runs = runner.run(thetas)?;
                    fe_runs += runner.evaluations;
                    (runs, runner.failures)
                }
                Some((cached, driver)) => {
                    let dispatched = Dispatched::new(cached, driver, &|_: &str| {});
                    let mut runner = Runner::new(&dispatched);
                    let runs = runner.run(thetas)?;
                    fe_runs += runner.evaluations;
                    (runs, runner.failures)
                }
            };
            tick();
            let ok: Vec<&Vec<f64>> = runs.iter().flatten().collect();
            if ok.len() < 2 {
                let why = runner_failures.first().map_or(String::new(), |f| f.1.clone());
                return Err(Error::numerical("validation", format!("{key} ({label}): {} of {} crush runs failed ({why}): widen the parameter bounds of {}", thetas.len() - ok.len(), thetas.len(), path.display())));
            }
            let (mut inside_all, mut peak) = (0u64, String::from("(no fracture observed)"));
            let mut lpd_all = 0.0;
            // One row per output and scatter σ (a reduction of crush curves has one σ per
            // output; an observation file may give each row its own): the interval a row
            // prints is the one its observations are counted against.
            for (o, sigma, idx) in by_output_and_sigma(&obs.output, &obs.sigma) {
                let spec = &outputs[o];
                let y: Vec<f64> = ok.iter().map(|r| r[o]).collect();
                let (centre, half) = predictive_interval(&y, sigma, model_error, z);
                let inside = idx.iter().filter(|&&i| (obs.values[i] - centre).abs() <= half).count() as u64;
                inside_all += inside;
                let lpd: f64 = idx.iter().map(|&i| log_predictive_density(obs.values[i], centre, half, z)).sum();
                lpd_all += lpd;
                let observed_mean = idx.iter().map(|&i| obs.values[i]).sum::<f64>() / idx.len() as f64;
                if spec.name == "peak_force" {
                    peak = format!("{observed_mean:.1}; {centre:.1} [{:.1}, {:.1}]", centre - half, centre + half);
                }
                rows.push(Row {
                    study: v.study.display().to_string(),
                    label: cs.label.clone(),
                    temperature_c: t,
                    source: label.clone(),
                    source_kind: kind,
                    source_temperature_c: *ts,
                    output: spec.name.clone(),
                    grid_displacement_m: red.grid.get(o).copied().unwrap_or(f64::NAN),
                    unit: spec.unit.clone(),
                    observations: idx.len() as u64,
                    observed_mean,
                    predicted: centre,
                    lo: centre - half,
                    hi: centre + half,
                    inside,
                    lpd,
                });
            }
            let failed = thetas.len() - ok.len();
            let runs_failed = if failed > 0 { format!("; {failed} of {} runs failed", thetas.len()) } else { String::new() };
            lines.push(format!("| {label} | {inside_all} of {} ({:.0} %){runs_failed} | {peak} |", obs.len(), 100.0 * inside_all as f64 / obs.len() as f64));
            coverage.push((label.clone(), inside_all as f64 / obs.len() as f64));
            inside_counts.push(inside_all);
            scores.push((label.clone(), lpd_all));
        }
        if let Some((_, driver)) = &slurm {
            events.extend(driver.log().events.iter().map(|e| format!("slurm ({}): {e}", v.study.display())));
        }
        let particles = red.curves.len();
        let k = red.grid.len();
        // Which source predicts the held-out data better is judged by the log score (proper),
        // not by coverage, which a wider interval wins; coverage is judged apart, against its
        // nominal level.
        let verdict = {
            let (law, states) = (scores[0].1, &scores[1..]);
            let best = states.iter().map(|c| c.1).fold(f64::NEG_INFINITY, f64::max);
            let which = if law > best { "the laws predict these data better than either calibrated state as it is" } else if law < best { "a calibrated state as it is predicts these data better than the laws" } else { "the laws and the better calibrated state predict these data equally well" };
            format!(
                "By the log predictive density of the held-out observations (a proper score: a wider interval does not win by covering more; {}), {which}",
                scores.iter().map(|(l, v)| format!("{l}: {v:.1}")).collect::<Vec<_>>().join("; ")
            )
        };
        let nominal = nominal_coverage(inside_counts[0], obs.len() as u64, level)?;
        md.push(format!(
            "The crush curves of `{}` ({}) at {t} °C ({particles} particles; {} observations: the force at {k} displacements, the peak force and the fracture displacement, normalised to D₀ = {:.3} mm) are held out: no law was fitted to them.{synthetic} They are predicted through the crush FE of that study (its mesh, its constants without a law, its model error {model_error}) at {draws} joint draws of each source; an observation is inside when it lies within the runs' mean ± {z:.3}·√(var of the runs + σ² + (model error·mean)²), σ the scatter between particles (`validation.csv`). The laws at {t} °C give {} ({pct} % bands; `validation_parameters.csv`). {verdict}. Observations inside their {pct} % interval: {}. {nominal}\n\n{}",
            v.study.display(),
            cs.label,
            obs.len(),
            red.reference_diameter * 1e3,
            shown.join(", "),
            coverage.iter().map(|(l, c)| format!("{l}: {:.0} %", 100.0 * c)).collect::<Vec<_>>().join("; "),
            lines.join("\n"),
        ));
    }
    let mut t = table(vec![
        scol("study", rows.iter().map(|r| r.study.clone()).collect()),
        scol("label", rows.iter().map(|r| r.label.clone()).collect()),
        fcol("temperature_c", rows.iter().map(|r| r.temperature_c).collect()),
        scol("source", rows.iter().map(|r| r.source.clone()).collect()),
        scol("source_kind", rows.iter().map(|r| r.source_kind.to_string()).collect()),
        fcol("source_temperature_c", rows.iter().map(|r| r.source_temperature_c).collect()),
        scol("output", rows.iter().map(|r| r.output.clone()).collect()),
        fcol("grid_displacement_m", rows.iter().map(|r| r.grid_displacement_m).collect()),
        scol("unit", rows.iter().map(|r| r.unit.clone()).collect()),
        ucol("observations", rows.iter().map(|r| r.observations).collect()),
        fcol("observed_mean", rows.iter().map(|r| r.observed_mean).collect()),
        fcol("predicted", rows.iter().map(|r| r.predicted).collect()),
        fcol("lo", rows.iter().map(|r| r.lo).collect()),
        fcol("hi", rows.iter().map(|r| r.hi).collect()),
        fcol("level", vec![level; rows.len()]),
        ucol("inside", rows.iter().map(|r| r.inside).collect()),
        // Σ ln predictive density of the row's observations (the log score the verdict ranks by).
        fcol("log_predictive_density", rows.iter().map(|r| r.lpd).collect()),
    ])?;
    dir.write_table("validation", &mut t)?;
    let mut t = table(vec![
        scol("study", prows.iter().map(|r| r.0.clone()).collect()),
        fcol("temperature_c", prows.iter().map(|r| r.1).collect()),
        scol("parameter", prows.iter().map(|r| r.2.clone()).collect()),
        scol("unit", prows.iter().map(|r| r.3.clone()).collect()),
        fcol("q50", prows.iter().map(|r| r.4.0).collect()),
        fcol("lo", prows.iter().map(|r| r.4.1).collect()),
        fcol("hi", prows.iter().map(|r| r.4.2).collect()),
    ])?;
    dir.write_table("validation_parameters", &mut t)?;
    let mut t = table(vec![
        scol("study", orows.iter().map(|r| r.0.clone()).collect()),
        scol("output", orows.iter().map(|r| r.1.clone()).collect()),
        scol("particle", orows.iter().map(|r| r.2.clone()).collect()),
        fcol("value", orows.iter().map(|r| r.3).collect()),
    ])?;
    dir.write_table("validation_observations", &mut t)?;
    Ok((md.join("\n\n"), inputs, fe_runs))
}

/// Whether the laws cover the held-out observations as often as their intervals claim: the
/// binomial probability of `inside` or fewer of `n` at the nominal `level`, as a sentence. Below
/// 1 % the laws (their form or their bands) miss something at that temperature. The observations
/// of one particle (its forces along one curve) are correlated, so the probability overstates
/// the evidence; the sentence says so.
fn nominal_coverage(inside: u64, n: u64, level: f64) -> Result<String> {
    use statrs::distribution::{Binomial, DiscreteCDF};
    let p = Binomial::new(level, n).map_err(|e| Error::numerical("validation", e.to_string()))?.cdf(inside);
    let pct = (100.0 * level).round();
    let how = format!("binomial probability of {inside} or fewer of {n} inside at the nominal {pct} %: {}, counting the observations as independent; they are not — the forces of one particle lie on one curve — so this overstates the evidence", crate::report::prob_text(p));
    Ok(if p < 0.01 {
        format!("**The laws cover fewer observations than their {pct} % intervals claim** ({how}): at this temperature the laws' form or their bands miss something, and the bands do not include the error of the form itself.")
    } else {
        format!("The laws' coverage is consistent with the nominal {pct} % ({how}).")
    })
}

/// The observations grouped by output and scatter σ (bitwise), by output, then σ in order of
/// first appearance: (output, σ, the observations' indices).
fn by_output_and_sigma(output: &[usize], sigma: &[f64]) -> Vec<(usize, f64, Vec<usize>)> {
    let mut g: Vec<(usize, f64, Vec<usize>)> = Vec::new();
    for (i, (&o, &s)) in output.iter().zip(sigma).enumerate() {
        match g.iter_mut().find(|(go, gs, _)| *go == o && gs.to_bits() == s.to_bits()) {
            Some((_, _, idx)) => idx.push(i),
            None => g.push((o, s, vec![i])),
        }
    }
    g.sort_by_key(|(o, _, _)| *o);
    g
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Data from N(0, 1) at their quantiles: the honest 90 % interval (±1.645) covers 90 %, an
    /// interval ten times wider covers all of them — coverage would prefer it — while the log
    /// score prefers the honest one.
    #[test]
    fn the_log_score_does_not_reward_a_wider_interval() {
        use statrs::distribution::{ContinuousCDF, Normal};
        let z = 1.6448536269514722;
        let y: Vec<f64> = (0..200).map(|i| Normal::standard().inverse_cdf((i as f64 + 0.5) / 200.0)).collect();
        let cover = |half: f64| y.iter().filter(|v| v.abs() <= half).count();
        let score = |half: f64| y.iter().map(|&v| log_predictive_density(v, 0.0, half, z)).sum::<f64>();
        assert!(cover(10.0 * z) > cover(z) && score(z) > score(10.0 * z) && score(z) > score(0.5 * z), "{} {} {}", score(z), score(10.0 * z), score(0.5 * z));
        // The density itself: N(0, 1) at 0.
        assert!((log_predictive_density(0.0, 0.0, z, z) + 0.5 * (2.0 * std::f64::consts::PI).ln()).abs() < 1e-12);
    }

    #[test]
    fn observations_with_their_own_scatter_get_their_own_interval() {
        // Output 0 twice with σ 1, once with σ 2 (an observation file's own sd); output 1 once.
        let g = by_output_and_sigma(&[0, 1, 0, 0], &[1.0, 5.0, 2.0, 1.0]);
        assert_eq!(g, vec![(0, 1.0, vec![0, 3]), (0, 2.0, vec![2]), (1, 5.0, vec![1])]);
    }
}

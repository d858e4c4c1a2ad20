//! Runs a `kind = "temperature"` study (every sentence of `summary.md` is generated from the
//! numbers it states):
//!
//! | file | what |
//! |---|---|
//! | `phases.csv`, `amorphous.csv` | the phase table ([`crate::phases`]): one row per temperature and phase (`temperature_c`, `phase`, the basis column, `amorphous`); the amorphous fraction per temperature; figure `phase_fractions` |
//! | `parameters_vs_temperature.csv` | with `[law]`: median and central band of every calibrated parameter's law and of Young's modulus E = 9KG/(3K + G) per temperature; figure `parameters_vs_temperature` |
//! | `calibrated_states.csv` | the calibration posteriors at their temperatures next to the laws there (the laws pass through every calibrated draw) |
//! | `softening.csv` | with `[softening]`: the plane-strain modulus ratio E/(1 − ν²) between the calibrated temperatures from the laws, next to the discrepancy workflow's force ratio over the same interval (F ∝ E/(1 − ν²) on a Hertzian curve against a rigid platen) |
//! | `validation.csv`, `validation_parameters.csv` | with `[[validation]]`: held-out crush curves predicted from the laws and from each calibrated state as it is ([`super::validate`]) |
//! | `lifetime_vs_temperature.csv` | with `[lifetime]`: each material's breaking probability after each horizon against the operating temperature (mean, median, band; the main study's primary strength and damage models; the same samples at every temperature); figure `breakage_vs_temperature` with Table 1's softening temperatures (`softening_marks.csv`) |

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use rayon::prelude::*;

use super::study::{LifetimeOptions, TemperatureStudy};
use crate::dist::Marginal;
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table};
use crate::phases::PhaseTable;
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::schema::StudyFile;
use crate::stats::median_and_band as band;
use crate::thermal::{ParameterLaws, youngs_modulus};
use crate::uq::setup::{Mode, Setup, Shared};

/// The summary's sentences about the phase table.
fn describe(s: &TemperatureStudy, t: &PhaseTable, shown_path: &str) -> (String, String) {
    let (lo, hi) = t.range();
    let fa = t.amorphous_fractions();
    let amorphous: Vec<&str> = t.phases.iter().zip(&t.amorphous).filter(|(_, a)| **a).map(|(n, _)| n.as_str()).collect();
    let basis = match (t.file_basis, &s.phases.source) {
        (crate::phases::Basis::Volume, _) => "volume fractions".to_string(),
        (b, source) => format!("{}, converted to volume fractions (the basis of the rule of mixtures) with the phases' {} from {}", b.words(), if b == crate::phases::Basis::Mole { "molar volumes" } else { "densities" }, source.as_deref().unwrap_or("the study")),
    };
    let crystalline: Vec<String> = t.phases.iter().zip(&t.amorphous).enumerate().filter(|(_, (_, a))| !**a).map(|(p, (n, _))| format!("{n} {:.3}", t.fractions[0][p])).collect();
    let mut md = format!(
        "The phase table `{shown_path}` — {} — gives {} phases at {} temperatures from {lo} to {hi} °C as {basis}. At {lo} °C{}: {}.",
        s.phases.composition,
        t.phases.len(),
        t.temperatures_c.len(),
        if t.file_basis == crate::phases::Basis::Volume { "" } else { " (as volume fractions)" },
        if crystalline.is_empty() { "no crystalline phase".to_string() } else { crystalline.join(", ") }
    );
    let headline = if amorphous.is_empty() {
        md.push_str(" No phase is flagged amorphous (`amorphous = true`): the amorphous fraction is 0 at every temperature.");
        format!("{}: no amorphous phase flagged in {shown_path}", s.phases.composition)
    } else {
        let top = fa.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let at = t.temperatures_c[fa.iter().position(|&f| f == top).unwrap_or(0)];
        match t.amorphous_onset(s.phases.onset_level) {
            Some(onset) => {
                md.push_str(&format!(" The amorphous fraction ({}) first exceeds {} at {onset} °C and reaches {top:.3} at {at} °C.", amorphous.join(", "), s.phases.onset_level));
                format!("{}: amorphous fraction above {} from {onset} °C, {top:.3} at {at} °C", s.phases.composition, s.phases.onset_level)
            }
            None => {
                md.push_str(&format!(" The amorphous fraction ({}) stays at or below {} (largest {top:.3} at {at} °C).", amorphous.join(", "), s.phases.onset_level));
                format!("{}: amorphous fraction at most {top:.3}", s.phases.composition)
            }
        }
    };
    (md, headline)
}

/// A number with its band, in `unit` scaled for reading.
fn shown(unit: &str, (m, lo, hi): (f64, f64, f64)) -> String {
    if unit == "Pa" { format!("{:.3} GPa [{:.3}, {:.3}]", m / 1e9, lo / 1e9, hi / 1e9) } else { format!("{m:.3} [{lo:.3}, {hi:.3}]") }
}

/// The unit of each parameter from the calibration's `parameters.csv` beside its chains ("" when
/// absent).
fn units(laws: &ParameterLaws) -> Vec<String> {
    let from = |chains: &Path| -> Option<(Vec<String>, Vec<String>)> {
        let t = crate::report::Table::load_file(&chains.with_file_name("parameters.csv")).ok()?;
        Some((t.s("name").ok()?, t.s("unit").ok()?))
    };
    let table = laws.inputs.first().and_then(|p| from(p));
    laws.names.iter().map(|n| table.as_ref().and_then(|(names, units)| names.iter().position(|x| x == n).map(|i| units[i].clone())).unwrap_or_default()).collect()
}

/// Every law (and Young's modulus) against temperature; the calibrated states next to the laws.
/// Returns the summary's paragraph.
fn write_laws(dir: &mut ReportDir, laws: &ParameterLaws, grid: &[f64], level: f64) -> Result<String> {
    let units = units(laws);
    let (gi, ki) = laws.shear_bulk();
    let mut names: Vec<String> = laws.names.clone();
    names.push("youngs_modulus".into());
    let mut units_all = units.clone();
    units_all.push(if units[gi] == units[ki] { units[gi].clone() } else { String::new() });
    let n = laws.len();
    // Per temperature: every draw's parameters and Young's modulus.
    let at = |t: f64| -> Result<Vec<Vec<f64>>> {
        let per: Vec<Vec<f64>> = (0..n).map(|j| laws.values_at(j, t)).collect::<Result<_>>()?;
        let cols: Vec<Vec<f64>> = (0..names.len()).map(|k| if k < laws.names.len() { per.iter().map(|d| d[k]).collect() } else { per.iter().map(|d| youngs_modulus(d[gi], d[ki])).collect() }).collect();
        Ok(cols)
    };
    let fa: Vec<f64> = grid.iter().map(|&t| laws.phases.amorphous_at(t)).collect::<Result<_>>()?;
    let (mut pn, mut pu, mut tc, mut af, mut q50, mut qlo, mut qhi) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let per_t: Vec<Vec<Vec<f64>>> = grid.iter().map(|&t| at(t)).collect::<Result<_>>()?;
    for (k, name) in names.iter().enumerate() {
        for (i, &t) in grid.iter().enumerate() {
            let (m, lo, hi) = band(per_t[i][k].clone(), level);
            pn.push(name.clone());
            pu.push(units_all[k].clone());
            tc.push(t);
            af.push(fa[i]);
            q50.push(m);
            qlo.push(lo);
            qhi.push(hi);
        }
    }
    let mut t = table(vec![scol("parameter", pn), scol("unit", pu), fcol("temperature_c", tc), fcol("amorphous_fraction", af), fcol("q50", q50), fcol("lo", qlo), fcol("hi", qhi)])?;
    dir.write_table("parameters_vs_temperature", &mut t)?;
    // The calibrated states: the posterior draws used, and the laws at the same temperature.
    let (mut pn, mut pu, mut tc, mut c50, mut clo, mut chi, mut l50, mut llo, mut lhi) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut para = Vec::new();
    for (t_c, draws) in &laws.calibrated {
        let law_cols = at(*t_c)?;
        for (k, name) in names.iter().enumerate() {
            let cal: Vec<f64> = if k < laws.names.len() { draws[k].clone() } else { draws[gi].iter().zip(&draws[ki]).map(|(g, kk)| youngs_modulus(*g, *kk)).collect() };
            let c = band(cal, level);
            let l = band(law_cols[k].clone(), level);
            pn.push(name.clone());
            pu.push(units_all[k].clone());
            tc.push(*t_c);
            c50.push(c.0);
            clo.push(c.1);
            chi.push(c.2);
            l50.push(l.0);
            llo.push(l.1);
            lhi.push(l.2);
        }
    }
    let mut t = table(vec![scol("parameter", pn.clone()), scol("unit", pu), fcol("temperature_c", tc.clone()), fcol("calibration_q50", c50.clone()), fcol("calibration_lo", clo.clone()), fcol("calibration_hi", chi.clone()), fcol("law_q50", l50.clone()), fcol("law_lo", llo.clone()), fcol("law_hi", lhi.clone())])?;
    dir.write_table("calibrated_states", &mut t)?;
    let worst = (0..pn.len()).map(|i| ((l50[i] - c50[i]).abs() / c50[i]).max((llo[i] - clo[i]).abs() / clo[i]).max((lhi[i] - chi[i]).abs() / chi[i])).fold(0.0, f64::max);
    let (t1, t2) = (laws.calibrated[0].0, laws.calibrated[1].0);
    let last = *grid.last().unwrap_or(&t2);
    let pct = (100.0 * level).round();
    para.push(format!(
        "Each calibrated parameter follows θ(T) = θ_c·exp(a(T − {t1}))·[(1 − f_a) + r·f_a] with f_a the amorphous fraction of the phase table, fitted draw by draw to {n} pairs of posterior draws at {t1} and {t2} °C with r from its declared prior (medians and {pct} % bands; `parameters_vs_temperature.csv`). At the calibrated temperatures the laws reproduce the calibration posteriors (largest relative difference of median or band ends {worst:.1e}; `calibrated_states.csv`)."
    ));
    let mut lines = vec![format!("| parameter | {t1} °C | {t2} °C | {last} °C | band width at {last} °C / at {t2} °C |"), "|---|---|---|---|---|".into()];
    let i_last = grid.len() - 1;
    let (at1, at2) = (at(t1)?, at(t2)?);
    for (k, name) in names.iter().enumerate() {
        let b = |cols: &[Vec<f64>]| band(cols[k].clone(), level);
        let (b1, b2, bl) = (b(&at1), b(&at2), b(&per_t[i_last]));
        let widen = (bl.2 - bl.1) / bl.0 / ((b2.2 - b2.1) / b2.0);
        lines.push(format!("| {name} | {} | {} | {} | {widen:.2} |", shown(&units_all[k], b1), shown(&units_all[k], b2), shown(&units_all[k], bl)));
    }
    para.push(lines.join("\n"));
    let e1 = band(at1[names.len() - 1].clone(), level).0;
    let e_last = band(per_t[i_last][names.len() - 1].clone(), level).0;
    para.push(format!("Young's modulus from the shear and bulk laws falls from {:.1} GPa at {t1} °C to {:.1} GPa at {last} °C (medians); where the amorphous fraction is 0 at both calibrated temperatures, the glassy ratio comes from its prior alone, and the bands widen beyond {t2} °C as the amorphous fraction rises.", e1 / 1e9, e_last / 1e9));
    Ok(para.join("\n\n"))
}

/// The laws' plane-strain modulus ratio between the calibrated temperatures next to the
/// discrepancy workflow's temperature term. Returns the summary's paragraph.
fn write_softening(dir: &mut ReportDir, laws: &ParameterLaws, evidence: &Path, level: f64) -> Result<String> {
    let (t1, t2) = (laws.calibrated[0].0, laws.calibrated[1].0);
    let plane = |(g, k): (f64, f64)| 1.0 / crate::contact::Elastic::from_shear_and_bulk(g, k).compliance();
    let ratio: Vec<f64> = (0..laws.len()).map(|j| Ok(plane(laws.shear_bulk_at(j, t2)?) / plane(laws.shear_bulk_at(j, t1)?))).collect::<Result<_>>()?;
    let law = band(ratio, level);
    let t = crate::report::Table::load_file(evidence)?;
    let (cand, med, q05, q95, named) = (t.s("candidate")?, t.f("median")?, t.f("q05")?, t.f("q95")?, t.s("named")?);
    let Some(i) = (0..cand.len()).rev().find(|&i| cand[i] == "temperature") else {
        return Err(Error::data_file(evidence, "candidate", "no row for the `temperature` term: the discrepancy study did not try it (it needs curves at two temperatures)"));
    };
    let span = (t2 - t1) / 100.0;
    let disc = (med[i].powf(span), q05[i].powf(span), q95[i].powf(span));
    let overlap = law.1 <= disc.2 && disc.1 <= law.2;
    let pct = (100.0 * level).round();
    let mut tab = table(vec![
        scol("source", vec!["temperature laws (calibration posteriors)".into(), format!("discrepancy workflow (force ratio per 100 °C)^{span}")]),
        fcol("from_c", vec![t1; 2]),
        fcol("to_c", vec![t2; 2]),
        fcol("level", vec![level, 0.9]),
        fcol("q50", vec![law.0, disc.0]),
        fcol("lo", vec![law.1, disc.1]),
        fcol("hi", vec![law.2, disc.2]),
        scol("named", vec![String::new(), named[i].clone()]),
    ])?;
    dir.write_table("softening", &mut tab)?;
    Ok(format!(
        "Between {t1} and {t2} °C the laws soften the plane-strain modulus E/(1 − ν²) by the factor {:.3} [{:.3}, {:.3}] ({pct} % band). The discrepancy workflow's temperature term, an independent estimate from the force–displacement curves alone (the force at a displacement of a Hertzian contact with a rigid platen is proportional to E/(1 − ν²)), gives {:.3} [{:.3}, {:.3}] (90 % interval; the term was {}named) over the same interval: the two {}.",
        law.0,
        law.1,
        law.2,
        disc.0,
        disc.1,
        disc.2,
        if named[i] == "yes" { "" } else { "not " },
        if overlap { "intervals overlap" } else { "intervals do not overlap — the laws and the curves disagree on the softening" }
    ))
}

/// Table 1's softening temperature of each material key that names a row.
fn softening_marks(file: &str, l: &LifetimeOptions, resolve: &dyn Fn(&Path) -> PathBuf, keys: &[String; 2], labels: &[String; 2]) -> Result<Vec<(String, String, String, f64)>> {
    let Some(t1) = &l.table1 else { return Ok(vec![]) };
    let path = resolve(t1);
    if !path.is_file() {
        return Err(Error::config(file, "lifetime.table1", format!("{} does not exist", path.display())));
    }
    let rows = crate::data::read_table1(&path)?;
    let col = crate::data::TABLE1_PROPERTIES.iter().position(|p| *p == "softening_temperature_c").unwrap_or(0);
    let mut out = Vec::new();
    for (key, name) in &l.softening {
        let Some(j) = keys.iter().position(|k| k == key) else {
            return Err(Error::config(file, format!("lifetime.softening.{key}"), format!("`{key}` is not a material of the main study ({}, {})", keys[0], keys[1])));
        };
        let row = rows.iter().find(|r| &r.material == name).ok_or_else(|| Error::data_file(&path, "material", format!("no row `{name}` (lifetime.softening.{key} of {file})")))?;
        let Some(t) = row.cells[col].min else {
            return Err(Error::data_file(&path, format!("row `{name}`, column softening_temperature_c_min"), "empty: no softening temperature to mark"));
        };
        out.push((key.clone(), labels[j].clone(), name.clone(), t));
    }
    Ok(out)
}

/// Breakage against temperature. Returns the summary's paragraph and the inputs read.
#[allow(clippy::too_many_arguments)]
fn write_lifetime(dir: &mut ReportDir, file: &str, l: &LifetimeOptions, laws: &ParameterLaws, grid: &[f64], at: &[f64], level: f64, seed: u64, resolve: &dyn Fn(&Path) -> PathBuf, reports_root: &Path, tick: &(dyn Fn() + Sync)) -> Result<(String, Vec<PathBuf>, Option<String>)> {
    let main_path = resolve(&l.main);
    if !main_path.is_file() {
        return Err(Error::config(file, "lifetime.main", format!("{} does not exist", main_path.display())));
    }
    let mf = StudyFile::read(&main_path)?;
    if mf.kind(&["uq"])? != "uq" {
        return Err(Error::config(file, "lifetime.main", "must be a main study (kind = \"uq\")"));
    }
    let mut u: crate::uq::study::UqStudy = mf.parse()?;
    u.validate(&main_path.display().to_string())?;
    // The operating temperatures are this study's grid, with this study's laws.
    u.operating = None;
    let shared = Shared::new(&u, &main_path, reports_root)?;
    let mut setup = Setup::new(&u, &main_path, &u.strength.effects, &u.contact.averaging, &shared)?;
    let t0 = grid[0];
    setup.attach_thermal(Arc::new(laws.clone()), [Marginal::Fixed(t0), Marginal::Fixed(t0)])?;
    let d = setup.varying(Mode::Joint).len();
    let pts = crate::uq::propagate::block_points(crate::uq::study::Method::Sobol, d, l.samples, seed, 0)?;
    let xs: Vec<Vec<f64>> = pts.iter().map(|p| setup.values(p, Mode::Joint)).collect();
    let keys = [setup.materials[0].model.key.clone(), setup.materials[1].model.key.clone()];
    let labels = [setup.materials[0].model.label.clone(), setup.materials[1].model.label.clone()];
    let years = setup.years.clone();
    let evaluate = |t: f64| -> Result<Vec<Vec<f64>>> {
        xs.par_iter()
            .map(|x| {
                let mut out = vec![0.0; setup.outputs()];
                setup.evaluate_at_temperatures(x, Mode::Joint, Some([t, t]), &mut out)?;
                Ok(out)
            })
            .collect()
    };
    let columns = |temps: &[f64], tick: &(dyn Fn() + Sync)| -> Result<Vec<(String, String, f64, f64, f64, (f64, f64, f64))>> {
        let mut rows = Vec::new();
        for &t in temps {
            let per = evaluate(t)?;
            for j in 0..2 {
                for (h, &y) in years.iter().enumerate() {
                    let v: Vec<f64> = per.iter().map(|o| o[setup.slot(j, h, 0)]).collect();
                    let mean = v.iter().sum::<f64>() / v.len() as f64;
                    rows.push((keys[j].clone(), labels[j].clone(), y, t, mean, band(v, level)));
                }
            }
            tick();
        }
        Ok(rows)
    };
    let write = |dir: &mut ReportDir, name: &str, rows: &[(String, String, f64, f64, f64, (f64, f64, f64))]| -> Result<()> {
        let mut t = table(vec![
            scol("material_key", rows.iter().map(|r| r.0.clone()).collect()),
            scol("material", rows.iter().map(|r| r.1.clone()).collect()),
            fcol("years", rows.iter().map(|r| r.2).collect()),
            fcol("temperature_c", rows.iter().map(|r| r.3).collect()),
            fcol("p_mean", rows.iter().map(|r| r.4).collect()),
            fcol("p_q50", rows.iter().map(|r| r.5.0).collect()),
            fcol("p_lo", rows.iter().map(|r| r.5.1).collect()),
            fcol("p_hi", rows.iter().map(|r| r.5.2).collect()),
        ])?;
        dir.write_table(name, &mut t)
    };
    let rows = columns(grid, tick)?;
    write(dir, "lifetime_vs_temperature", &rows)?;
    let marks = softening_marks(file, l, resolve, &keys, &labels)?;
    let mut t = table(vec![
        scol("material_key", marks.iter().map(|m| m.0.clone()).collect()),
        scol("material", marks.iter().map(|m| m.1.clone()).collect()),
        scol("table1_material", marks.iter().map(|m| m.2.clone()).collect()),
        fcol("softening_temperature_c", marks.iter().map(|m| m.3).collect()),
    ])?;
    dir.write_table("softening_marks", &mut t)?;
    let pct = (100.0 * level).round();
    let data_c = [setup.materials[0].data_temperature_c()?, setup.materials[1].data_temperature_c()?];
    let mut md = format!(
        "The main study `{}` (primary strength model `{}`, damage model {:?}) is run at every temperature of the grid with {} samples — the same samples at every temperature — each carrying one joint draw of the laws: the Weibull scale moves with the law of the strength parameter and the particle's Young's modulus with the shear and bulk laws, from the crush data's temperature ({} °C for {}, {} °C for {}). Softer particles meet lower contact stresses, weaker ones break at lower stresses; the breaking probability shows which wins (`lifetime_vs_temperature.csv`, figure `breakage_vs_temperature`, mean, median and {pct} % band; the figure draws probabilities below 10⁻¹² at 10⁻¹²).",
        l.main.display(),
        u.strength.effects.name(),
        setup.models[0],
        l.samples,
        data_c[0],
        labels[0],
        data_c[1],
        labels[1],
    );
    let mut inputs = vec![main_path.clone()];
    inputs.extend(setup.materials.iter().map(|m| m.path.clone()));
    if let Some(t1) = &l.table1 {
        inputs.push(resolve(t1));
    }
    if !marks.is_empty() {
        md.push_str(&format!(" Table 1's softening temperatures are marked: {}.", marks.iter().map(|m| format!("{} °C ({})", m.3, m.1)).collect::<Vec<_>>().join(", ")));
    }
    let mut answer_text = None;
    if !at.is_empty() {
        let rows = columns(at, &|| {})?;
        write(dir, "lifetime_at", &rows)?;
        let last = years[years.len() - 1];
        let at_last: Vec<(usize, f64, f64, (f64, f64, f64))> = rows.iter().filter(|r| r.2 == last).map(|r| (usize::from(r.0 != keys[0]), r.3, r.2, r.5)).collect();
        answer_text = Some(answer(&labels, &at_last, last, level));
        let mut lines = vec![format!("| material | years | temperature (°C) | mean P | median P [{pct} % band] |"), "|---|---|---|---|---|".into()];
        for r in &rows {
            lines.push(format!("| {} | {} | {} | {:.3e} | {:.3e} [{:.3e}, {:.3e}] |", r.1, r.2, r.3, r.4, r.5.0, r.5.1, r.5.2));
        }
        md.push_str(&format!("\n\nAt the reported temperatures (`lifetime_at.csv`):\n\n{}", lines.join("\n")));
    }
    Ok((md, inputs, answer_text))
}

/// The answer at the reported temperatures, one sentence from `rows` — (material index,
/// temperature (°C), years, (median, low, high) of P_break) at horizon `years`: which particle
/// breaks less (by the median) at each temperature, and each one's median and `level` band there.
fn answer(labels: &[String; 2], rows: &[(usize, f64, f64, (f64, f64, f64))], years: f64, level: f64) -> String {
    use crate::report::prob_text as prob;
    let mut temps: Vec<f64> = rows.iter().map(|r| r.1).collect();
    temps.sort_by(f64::total_cmp);
    temps.dedup();
    let at = |j: usize, t: f64| rows.iter().find(|r| r.0 == j && r.1 == t).map(|r| r.3);
    let less: Vec<Option<usize>> = temps
        .iter()
        .map(|&t| match (at(0, t), at(1, t)) {
            (Some(a), Some(b)) if a.0 < b.0 => Some(0),
            (Some(a), Some(b)) if b.0 < a.0 => Some(1),
            _ => None,
        })
        .collect();
    let over = if years == 1.0 { "1 year".to_string() } else { format!("{years} years") };
    let head = match less.first() {
        Some(Some(j)) if less.iter().all(|l| *l == Some(*j)) => format!("**{} breaks less than {} at every reported temperature**", labels[*j], labels[1 - j]),
        _ if less.iter().all(|l| l.is_none()) => format!("**Neither {} nor {} breaks less at any reported temperature**", labels[0], labels[1]),
        _ => format!(
            "**Which particle breaks less depends on the temperature**: {}",
            temps.iter().zip(&less).map(|(t, l)| format!("{} at {t} °C", l.map_or("neither".to_string(), |j| labels[j].clone()))).collect::<Vec<_>>().join(", ")
        ),
    };
    let each: Vec<String> = (0..2)
        .map(|j| format!("{}: {}", labels[j], temps.iter().filter_map(|&t| at(j, t).map(|(m, lo, hi)| format!("{} [{}, {}] at {t} °C", prob(m), prob(lo), prob(hi)))).collect::<Vec<_>>().join(", ")))
        .collect();
    format!("{head} (median P_break over {over} and its {:.0} % band; the laws' joint draws and the main study's samples): {}.", 100.0 * level, each.join("; "))
}

/// Runs the study.
pub fn run_temperature(loaded: &StudyFile, s: &TemperatureStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let file = loaded.path.display().to_string();
    s.validate(&file)?;
    let path = loaded.resolve(&s.phases.file);
    let phases = s.phases.read(&file, &path)?;
    let grid = s.grid(phases.range());
    let (lo, hi) = phases.range();
    if grid[0] < lo || grid[grid.len() - 1] > hi {
        return Err(Error::config(&file, "temperatures_c", format!("{}–{} °C reaches outside the phase table {} ({lo}–{hi} °C): nothing is extrapolated beyond it", grid[0], grid[grid.len() - 1], path.display())));
    }
    let at = s.lifetime.as_ref().map_or(vec![], |l| l.at.clone());
    if let Some(&t) = at.iter().find(|&&t| !(t >= lo && t <= hi)) {
        return Err(Error::config(&file, "lifetime.at", format!("{t} °C lies outside the phase table {} ({lo}–{hi} °C)", path.display())));
    }
    let steps = 3 + s.lifetime.as_ref().map_or(0, |_| grid.len()) as u64 + (s.validation.len() * super::validate::SOURCES) as u64;
    let pb = progress_bar(steps, opts.progress, crate::runkit::PROGRESS_COUNT);
    pb.set_message("phase table and laws");
    let mut inputs = vec![InputFile::hash(&loaded.path)?, InputFile::hash(&path)?];
    let resolve = |p: &Path| loaded.resolve(p);
    let laws = match &s.law {
        Some(l) => Some(ParameterLaws::load(&file, &resolve, &opts.reports_root, phases.clone(), l, s.seed)?),
        None => None,
    };
    if let Some(l) = &laws {
        for p in &l.inputs {
            inputs.push(InputFile::hash(p)?);
        }
    }
    pb.inc(1);

    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;
    write_phases(&mut dir, &phases)?;
    let (text, headline) = describe(s, &phases, &s.phases.file.display().to_string());
    let mut md = format!("# Temperature: {}\n\n## Phases\n\n{text}\n\nThe figure `phase_fractions` draws every phase against temperature (amorphous phases dashed), in the style of the deliverable's Fig. 2. Between the tabulated temperatures the fractions are interpolated linearly; nothing is extrapolated beyond them.{}\n", s.phases.composition, illustrative_sentence(&s.phases.file));
    let mut headlines = vec![headline];
    let mut executor_events = Vec::new();
    let mut evaluations = BTreeMap::new();
    evaluations.insert("phase_table_rows".to_string(), (phases.temperatures_c.len() * phases.phases.len()) as u64);
    if let Some(laws) = &laws {
        md.push_str(&format!("\n## Parameters against temperature\n\n{}\n", write_laws(&mut dir, laws, &grid, s.level)?));
        evaluations.insert("law_draws".to_string(), laws.len() as u64);
        if let Some(so) = &s.softening {
            let (ev, key) = match (&so.study, &so.evidence) {
                (Some(st), _) => (crate::schema::report_file(&opts.reports_root, &loaded.resolve(st), "curve_evidence.csv"), "softening.study"),
                (_, Some(e)) => (loaded.resolve(e), "softening.evidence"),
                _ => return Err(Error::config(&file, "softening", "needs `study` or `evidence`")),
            };
            if !ev.is_file() {
                return Err(Error::config(&file, key, format!("{} does not exist: it is the curve_evidence.csv a `discrepancy_curves` study's run writes", ev.display())));
            }
            md.push_str(&format!("\n## Softening: the laws and the discrepancy workflow\n\n{}\n", write_softening(&mut dir, laws, &ev, s.level)?));
            inputs.push(InputFile::hash(&ev)?);
        }
    }
    pb.inc(1);
    if let (Some(laws), false) = (&laws, s.validation.is_empty()) {
        pb.set_message("held-out data");
        let tick = || pb.inc(1);
        let slurm = (opts.executor == Some(crate::runkit::ExecutorKind::Slurm)).then_some(opts.reports_root.as_path());
        let (text, read, runs) = super::validate::write_validation(&mut dir, &file, &s.validation, laws, s.level, &resolve, &tick, slurm, &mut executor_events)?;
        md.push_str(&format!("\n## Held-out data\n\n{text}\n"));
        for p in read {
            inputs.push(InputFile::hash(&p)?);
        }
        evaluations.insert("validation_fe_runs".to_string(), runs);
    }
    if let (Some(laws), Some(l)) = (&laws, &s.lifetime) {
        pb.set_message("breakage against temperature");
        let tick = || pb.inc(1);
        let (text, read, answer) = write_lifetime(&mut dir, &file, l, laws, &grid, &at, s.level, s.seed, &resolve, &opts.reports_root, &tick)?;
        md.push_str(&format!("\n## Breakage against temperature\n\n{text}\n"));
        if let Some(a) = answer {
            md = md.replacen("\n## Phases\n", &format!("\n## Answer\n\n{a}\n\n## Phases\n"), 1);
        }
        for p in read {
            inputs.push(InputFile::hash(&p)?);
        }
        evaluations.insert("lifetime_samples".to_string(), (l.samples * (grid.len() + at.len())) as u64);
        headlines.push(format!("breakage against temperature: {} temperatures, {} samples each", grid.len(), l.samples));
    }
    dir.write_bytes("summary.md", md.as_bytes())?;
    pb.set_message("figures");
    let mut failures = executor_events;
    let rendered = crate::report::temperature::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    pb.inc(1);
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings: Vec::new() })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines })
}

/// The sentence saying that the phase table is the illustrative one partlife ships (by its file
/// name, wherever it was copied), empty for any other table: a user's own export is not called
/// illustrative.
fn illustrative_sentence(file: &Path) -> &'static str {
    if file.file_name().and_then(|n| n.to_str()) == Some(crate::phases::ILLUSTRATIVE_FILE) {
        " **The phase table is the illustrative one partlife ships** — not computed, not measured; its rule is in `partlife::phases` and datasets/README.md."
    } else {
        ""
    }
}

/// `phases.csv` and `amorphous.csv`.
fn write_phases(dir: &mut ReportDir, phases: &PhaseTable) -> Result<()> {
    let rows: Vec<(usize, usize)> = (0..phases.temperatures_c.len()).flat_map(|i| (0..phases.phases.len()).map(move |p| (i, p))).collect();
    let mut t = table(vec![
        fcol("temperature_c", rows.iter().map(|&(i, _)| phases.temperatures_c[i]).collect()),
        scol("phase", rows.iter().map(|&(_, p)| phases.phases[p].clone()).collect()),
        fcol(phases.basis.column(), rows.iter().map(|&(i, p)| phases.fractions[i][p]).collect()),
        scol("amorphous", rows.iter().map(|&(_, p)| phases.amorphous[p].to_string()).collect()),
    ])?;
    dir.write_table("phases", &mut t)?;
    let mut t = table(vec![fcol("temperature_c", phases.temperatures_c.clone()), fcol("amorphous_fraction", phases.amorphous_fractions())])?;
    dir.write_table("amorphous", &mut t)
}

//! Runs a `kind = "microstructure"` study. Every realisation of every structure is built,
//! homogenised and loaded in the two virtual uniaxial tests; the tables below are written and the
//! figures drawn from them; every sentence of `summary.md` is generated from the numbers it
//! states ([`super::summary`]).
//!
//! | file | what |
//! |---|---|
//! | `phases.csv` | the phase table: E, ν, σ_t, the in-plane κ and μ, source |
//! | `structures.csv` | per structure and realisation: size, seed, the effective stiffness C, κ̄, μ̄, E, ν and their Voigt, Reuss and Hashin–Shtrikman bounds, whether κ̄ and μ̄ lie within the HS bounds |
//! | `connectivity.csv` | per structure, realisation and phase: area fraction, clusters, largest cluster's share, percolation in x and y |
//! | `hot_spots.csv` | per structure, realisation, test and phase: σ₁, σ_vM, ε₁ and γ_max quantiles, stress-concentration factors, the area above σ_t at the applied stress, the first-failure stress |
//! | `structure_summary.csv` | per structure: mean, standard deviation, minimum and maximum over the realisations of E, κ̄, μ̄, the hot-spot area and the first-failure stress of each test; with `[failure]` the strength of each test (`strength_<test>`, or `strength_<test>_lower_bound` when a run used up `max_events`) |
//! | `distributions.csv` | per structure, test, phase and measure, quantiles over every pixel of every realisation (figure `exceedance`) |
//! | `first_failure_weibull.csv` | per structure with at least 5 realisations and test: the Weibull fit of the first-failure stress over the realisations (ASTM C1239 MLE, pivotal bounds) |
//! | `map_<structure>.csv` | the first realisation's phase, σ₁ (both tests) and γ_max (tension) per pixel, in blocks of b × b pixels (b = ⌈side/256⌉) when larger (phase: the most frequent; σ₁, γ_max: the largest) — figures `phases_…`, `sigma1_tension_…`, `sigma1_compression_…`, `shear_strain_…` |
//! | `<structure>.vtu` | the first realisation at full resolution, every measure of both tests as cell data, for ParaView |
//! | `failure_summary.csv` | with `[failure]`: per structure, realisation and test, the cell's strength (the largest applied stress of the progressive-failure run), the event it was reached at, the first crack's stress and phase, the cracked pixels' shares by phase at the peak, the stiffness along the load left at the end, why the run stopped |
//! | `failure_events.csv` | with `[failure]`: every crack in order — applied stress, macroscopic strain, pixel, phase (figures `failure_curves`, `cracks_<test>_<structure>`) |

use std::collections::BTreeMap;

use rayon::prelude::*;

use super::failure::progressive;
use super::fields::{Local, PhaseHotSpots, QUANTILES, Test};
use super::homogenise::{Periodic, Plane, element_lame, plane_lame};
use super::material::Phase;
use super::solve::{Built, Cracked, FirstFailureWeibull, Solved, WEIBULL_MIN, build, quantities, solve};
use crate::stats::mean_and_sd;
use super::structure::Connectivity;
use super::study::MicroStudy;
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::schema::StudyFile;

/// Probabilities of `distributions.csv`.
pub const DISTRIBUTION_P: [f64; 21] = [0.001, 0.01, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.98, 0.99, 0.995, 0.998, 0.999, 0.9995, 0.9998, 0.9999];

/// Runs the study.
pub fn run_microstructure(loaded: &StudyFile, s: &MicroStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let file = loaded.path.display().to_string();
    let phases = s.validate(&file)?;
    let resolve = |p: &std::path::Path| loaded.resolve(p);
    let mut inputs = vec![InputFile::hash(&loaded.path)?];
    let built: Vec<Built> = s.structure.iter().enumerate().map(|(i, st)| build(&file, &format!("structure[{i}]"), st, &phases, s.seed, &resolve)).collect::<Result<_>>()?;
    for b in &built {
        if let Some(p) = &b.input {
            inputs.push(InputFile::hash(p)?);
        }
    }
    // One symbolic factorisation per grid size.
    let mut sizes: Vec<(usize, usize)> = built.iter().flat_map(|b| b.realisations.iter().map(|(m, _)| (m.nx, m.ny))).collect();
    sizes.sort_unstable();
    sizes.dedup();
    let periodic: Vec<((usize, usize), Periodic)> = sizes.iter().map(|&(nx, ny)| Ok(((nx, ny), Periodic::new(nx, ny)?))).collect::<Result<_>>()?;
    let jobs: Vec<(usize, usize)> = built.iter().enumerate().flat_map(|(i, b)| (0..b.realisations.len()).map(move |r| (i, r))).collect();
    let crack_jobs: Vec<(usize, usize, Test)> = match &s.failure {
        Some(f) => (0..built.len())
            .filter(|&i| s.cracked(&s.structure[i].name))
            .flat_map(|i| (0..f.realisations.min(built[i].realisations.len())).flat_map(move |r| Test::BOTH.map(|t| (i, r, t))))
            .collect(),
        None => Vec::new(),
    };
    let pb = progress_bar((jobs.len() + crack_jobs.len()) as u64 + 1, opts.progress, crate::runkit::PROGRESS_COUNT);
    pb.set_message("homogenisation and virtual tests");
    let solved: Vec<Solved> = jobs
        .par_iter()
        .map(|&(i, r)| {
            let (m, seed) = built[i].realisations[r].clone();
            let p = &periodic.iter().find(|(sz, _)| *sz == (m.nx, m.ny)).ok_or_else(|| Error::numerical("microstructure", "no factorisation for a grid size"))?.1;
            let out = solve(p, m, seed, &built[i].phase_of_label, &phases, s.plane, s.applied_stress_pa);
            pb.inc(1);
            out
        })
        .collect::<Result<_>>()?;
    pb.set_message("progressive failure");
    let cracked: Vec<Cracked> = crack_jobs
        .par_iter()
        .map(|&(i, r, test)| {
            let m = &built[i].realisations[r].0;
            let p = &periodic.iter().find(|(sz, _)| *sz == (m.nx, m.ny)).ok_or_else(|| Error::numerical("microstructure", "no factorisation for a grid size"))?.1;
            let elastic: Vec<_> = built[i].phase_of_label.iter().map(|&q| phases[q].elastic).collect();
            let strength: Vec<f64> = m.labels.iter().map(|&l| phases[built[i].phase_of_label[l as usize]].tensile_strength_pa).collect();
            let f = s.failure.as_ref().ok_or_else(|| Error::numerical("microstructure", "no [failure] options"))?;
            let run = progressive(p, &element_lame(m, &elastic, s.plane)?, &strength, s.plane, test, f)?;
            pb.inc(1);
            Ok(Cracked { structure: i, realisation: r, run })
        })
        .collect::<Result<_>>()?;
    drop(periodic);
    let mut by_structure: Vec<Vec<&Solved>> = vec![Vec::new(); built.len()];
    for (&(i, _), r) in jobs.iter().zip(&solved) {
        by_structure[i].push(r);
    }

    pb.set_message("tables and figures");
    let mut dir = crate::runkit::report_dir(opts, &loaded.name)?;
    write_phases(&mut dir, &phases, s.plane)?;
    write_structures(&mut dir, s, &built, &by_structure, &phases)?;
    write_hot_spots(&mut dir, s, &built, &by_structure, &phases)?;
    write_summary_table(&mut dir, s, &by_structure, &cracked)?;
    write_distributions(&mut dir, s, &built, &by_structure, &phases)?;
    let weibull = write_weibull(&mut dir, s, &by_structure)?;
    if s.failure.is_some() {
        write_failure(&mut dir, s, &built, &cracked, &phases)?;
    }
    for (i, st) in s.structure.iter().enumerate() {
        let first = by_structure[i][0];
        super::output::write_map(&mut dir, &st.name, first, &built[i].phase_of_label, &phases)?;
        super::output::write_vtu(&mut dir, &st.name, first, &built[i].phase_of_label)?;
    }
    let (md, headlines) = super::summary::summary(loaded, s, &phases, &built, &by_structure, &weibull, &cracked);
    dir.write_bytes("summary.md", md.as_bytes())?;
    let mut failures = Vec::new();
    for (i, st) in s.structure.iter().enumerate() {
        for (r, x) in by_structure[i].iter().enumerate() {
            if !x.within_hs() {
                failures.push(format!("{} realisation {r}: κ̄ = {:.4e}, μ̄ = {:.4e} Pa outside the Hashin–Shtrikman bounds {:?}–{:?}", st.name, x.bulk_shear.0, x.bulk_shear.1, x.bounds.hs_lower, x.bounds.hs_upper));
            }
        }
    }
    let rendered = crate::report::micro::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    pb.inc(1);
    let mut evaluations = BTreeMap::new();
    evaluations.insert("fe_solves".to_string(), (solved.len() + cracked.iter().map(|c| c.run.events.len() + 1).sum::<usize>()) as u64);
    evaluations.insert("cracked_pixels".to_string(), cracked.iter().map(|c| c.run.events.len() as u64).sum());
    evaluations.insert("pixels".to_string(), solved.iter().map(|r| r.micro.labels.len() as u64).sum());
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures, warnings: Vec::new() })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines })
}

fn write_phases(dir: &mut ReportDir, phases: &[Phase], plane: Plane) -> Result<()> {
    let lame: Vec<(f64, f64)> = phases.iter().map(|p| plane_lame(&p.elastic, plane)).collect();
    let mut t = table(vec![
        scol("phase", phases.iter().map(|p| p.name.clone()).collect()),
        fcol("youngs_modulus_pa", phases.iter().map(|p| p.elastic.youngs_modulus_pa).collect()),
        fcol("poisson_ratio", phases.iter().map(|p| p.elastic.poisson_ratio).collect()),
        fcol("tensile_strength_pa", phases.iter().map(|p| p.tensile_strength_pa).collect()),
        fcol("bulk_modulus_2d_pa", lame.iter().map(|(l, m)| l + m).collect()),
        fcol("shear_modulus_pa", lame.iter().map(|p| p.1).collect()),
        scol("source", phases.iter().map(|p| p.source.clone()).collect()),
    ])?;
    dir.write_table("phases", &mut t)
}

fn write_structures(dir: &mut ReportDir, s: &MicroStudy, built: &[Built], by: &[Vec<&Solved>], phases: &[Phase]) -> Result<()> {
    let rows: Vec<(usize, usize)> = by.iter().enumerate().flat_map(|(i, v)| (0..v.len()).map(move |r| (i, r))).collect();
    let get = |f: &dyn Fn(&Solved) -> f64| -> Vec<f64> { rows.iter().map(|&(i, r)| f(by[i][r])).collect() };
    let e = |k: f64, m: f64| s.plane.youngs_and_poisson(k, m).0;
    let source = |i: usize| match (&s.structure[i].synthetic, &s.structure[i].image) {
        (Some(g), _) => format!("synthetic {}", serde_json::to_value(g.topology).ok().and_then(|v| v.as_str().map(String::from)).unwrap_or_default()),
        (_, Some(im)) => format!("image {}", im.file.display()),
        _ => String::new(),
    };
    let mut cols = vec![
        scol("structure", rows.iter().map(|&(i, _)| s.structure[i].name.clone()).collect()),
        scol("label", rows.iter().map(|&(i, _)| s.structure[i].label.clone()).collect()),
        ucol("realisation", rows.iter().map(|&(_, r)| r as u64).collect()),
        scol("source", rows.iter().map(|&(i, _)| source(i)).collect()),
        scol("seed", rows.iter().map(|&(i, r)| by[i][r].seed.map_or(String::new(), |x| x.to_string())).collect()),
        ucol("nx", rows.iter().map(|&(i, r)| by[i][r].micro.nx as u64).collect()),
        ucol("ny", rows.iter().map(|&(i, r)| by[i][r].micro.ny as u64).collect()),
        fcol("pixel_m", rows.iter().map(|&(i, r)| by[i][r].micro.pixel_m).collect()),
        scol("phases", rows.iter().map(|&(i, _)| built[i].phase_of_label.iter().map(|&p| phases[p].name.clone()).collect::<Vec<_>>().join(" ")).collect()),
        scol("fractions", rows.iter().map(|&(i, r)| by[i][r].fractions.iter().map(|f| format!("{f:.6}")).collect::<Vec<_>>().join(" ")).collect()),
    ];
    for (a, b, name) in [(0, 0, "c11_pa"), (1, 1, "c22_pa"), (0, 1, "c12_pa"), (2, 2, "c33_pa"), (0, 2, "c13_pa"), (1, 2, "c23_pa")] {
        cols.push(fcol(name, get(&|x| x.c[a][b])));
    }
    cols.extend([
        fcol("bulk_modulus_2d_pa", get(&|x| x.bulk_shear.0)),
        fcol("shear_modulus_pa", get(&|x| x.bulk_shear.1)),
        fcol("youngs_modulus_pa", get(&|x| x.youngs_poisson.0)),
        fcol("poisson_ratio", get(&|x| x.youngs_poisson.1)),
        fcol("bulk_voigt_pa", get(&|x| x.bounds.voigt.0)),
        fcol("bulk_reuss_pa", get(&|x| x.bounds.reuss.0)),
        fcol("bulk_hs_lower_pa", get(&|x| x.bounds.hs_lower.0)),
        fcol("bulk_hs_upper_pa", get(&|x| x.bounds.hs_upper.0)),
        fcol("shear_voigt_pa", get(&|x| x.bounds.voigt.1)),
        fcol("shear_reuss_pa", get(&|x| x.bounds.reuss.1)),
        fcol("shear_hs_lower_pa", get(&|x| x.bounds.hs_lower.1)),
        fcol("shear_hs_upper_pa", get(&|x| x.bounds.hs_upper.1)),
        fcol("youngs_voigt_pa", get(&|x| e(x.bounds.voigt.0, x.bounds.voigt.1))),
        fcol("youngs_reuss_pa", get(&|x| e(x.bounds.reuss.0, x.bounds.reuss.1))),
        fcol("youngs_hs_lower_pa", get(&|x| e(x.bounds.hs_lower.0, x.bounds.hs_lower.1))),
        fcol("youngs_hs_upper_pa", get(&|x| e(x.bounds.hs_upper.0, x.bounds.hs_upper.1))),
        ucol("within_hs", rows.iter().map(|&(i, r)| u64::from(by[i][r].within_hs())).collect()),
    ]);
    dir.write_table("structures", &mut table(cols)?)?;
    let crow: Vec<(usize, usize, usize)> = rows.iter().flat_map(|&(i, r)| (0..built[i].phase_of_label.len()).map(move |l| (i, r, l))).collect();
    let con = |i: usize, r: usize, l: usize| -> &Connectivity { &by[i][r].connectivity[l] };
    let mut t = table(vec![
        scol("structure", crow.iter().map(|&(i, _, _)| s.structure[i].name.clone()).collect()),
        ucol("realisation", crow.iter().map(|&(_, r, _)| r as u64).collect()),
        scol("phase", crow.iter().map(|&(i, _, l)| phases[built[i].phase_of_label[l]].name.clone()).collect()),
        fcol("area_fraction", crow.iter().map(|&(i, r, l)| con(i, r, l).fraction).collect()),
        ucol("clusters", crow.iter().map(|&(i, r, l)| con(i, r, l).clusters as u64).collect()),
        fcol("largest_cluster_share", crow.iter().map(|&(i, r, l)| con(i, r, l).largest_fraction).collect()),
        ucol("percolates_x", crow.iter().map(|&(i, r, l)| u64::from(con(i, r, l).percolates_x)).collect()),
        ucol("percolates_y", crow.iter().map(|&(i, r, l)| u64::from(con(i, r, l).percolates_y)).collect()),
    ])?;
    dir.write_table("connectivity", &mut t)
}

fn write_hot_spots(dir: &mut ReportDir, s: &MicroStudy, built: &[Built], by: &[Vec<&Solved>], phases: &[Phase]) -> Result<()> {
    let rows: Vec<(usize, usize, usize, usize)> = by.iter().enumerate().flat_map(|(i, v)| (0..v.len()).flat_map(move |r| (0..2).flat_map(move |t| (0..built[i].phase_of_label.len()).map(move |l| (i, r, t, l))))).collect();
    let h = |&(i, r, t, l): &(usize, usize, usize, usize)| -> &PhaseHotSpots { &by[i][r].hot[t][l] };
    let sv = s.applied_stress_pa;
    let mut cols = vec![
        scol("structure", rows.iter().map(|x| s.structure[x.0].name.clone()).collect()),
        ucol("realisation", rows.iter().map(|x| x.1 as u64).collect()),
        scol("test", rows.iter().map(|x| Test::BOTH[x.2].name().to_string()).collect()),
        scol("phase", rows.iter().map(|x| phases[built[x.0].phase_of_label[x.3]].name.clone()).collect()),
        fcol("applied_stress_pa", vec![sv; rows.len()]),
        fcol("tensile_strength_pa", rows.iter().map(|x| phases[built[x.0].phase_of_label[x.3]].tensile_strength_pa).collect()),
        fcol("area_fraction", rows.iter().map(|x| h(x).area_fraction).collect()),
        fcol("sigma1_mean_pa", rows.iter().map(|x| h(x).sigma1_mean).collect()),
    ];
    let tag = |p: f64| format!("{}", (p * 1000.0).round() as u64);
    for (k, &p) in QUANTILES.iter().enumerate() {
        cols.push(fcol(&format!("sigma1_q{}_pa", tag(p)), rows.iter().map(|x| h(x).sigma1_q[k]).collect()));
    }
    cols.push(fcol("sigma1_max_pa", rows.iter().map(|x| h(x).sigma1_max).collect()));
    cols.push(fcol("scf_q999", rows.iter().map(|x| h(x).sigma1_q[3] / sv).collect()));
    cols.push(fcol("scf_max", rows.iter().map(|x| h(x).sigma1_max / sv).collect()));
    for (k, &p) in QUANTILES.iter().enumerate() {
        cols.push(fcol(&format!("von_mises_q{}_pa", tag(p)), rows.iter().map(|x| h(x).von_mises_q[k]).collect()));
    }
    for (k, &p) in QUANTILES.iter().enumerate() {
        cols.push(fcol(&format!("strain1_q{}", tag(p)), rows.iter().map(|x| h(x).strain1_q[k]).collect()));
    }
    for (k, &p) in QUANTILES.iter().enumerate() {
        cols.push(fcol(&format!("shear_strain_q{}", tag(p)), rows.iter().map(|x| h(x).shear_strain_q[k]).collect()));
    }
    cols.push(fcol("above_strength", rows.iter().map(|x| h(x).above_strength).collect()));
    cols.push(fcol("above_strength_in_phase", rows.iter().map(|x| h(x).above_strength_in_phase).collect()));
    cols.push(fcol("first_failure_pa", rows.iter().map(|x| h(x).first_failure_pa).collect()));
    dir.write_table("hot_spots", &mut table(cols)?)
}

fn write_summary_table(dir: &mut ReportDir, s: &MicroStudy, by: &[Vec<&Solved>], cracked: &[Cracked]) -> Result<()> {
    let q = quantities();
    let (mut name, mut label, mut qn, mut unit, mut n) = (vec![], vec![], vec![], vec![], vec![]);
    let (mut mean, mut sd, mut lo, mut hi) = (vec![], vec![], vec![], vec![]);
    for (i, st) in s.structure.iter().enumerate() {
        let mut rows: Vec<(String, &str, Vec<f64>)> = q.iter().map(|(qname, u, f)| (qname.to_string(), *u, by[i].iter().map(|r| f(r)).collect())).collect();
        for test in Test::BOTH {
            let runs: Vec<&Cracked> = cracked.iter().filter(|c| c.structure == i && c.run.test == test).collect();
            if !runs.is_empty() {
                // A run that used up max_events gives a lower bound, named as such.
                let bound = if runs.iter().any(|c| c.run.lower_bound()) { "_lower_bound" } else { "" };
                rows.push((format!("strength_{}{bound}", test.name()), "Pa", runs.iter().map(|c| c.run.strength_pa).collect()));
            }
        }
        for (qname, u, v) in rows {
            let (m, d) = mean_and_sd(&v);
            let (a, b) = (v.iter().cloned().fold(f64::INFINITY, f64::min), v.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
            name.push(st.name.clone());
            label.push(st.label.clone());
            qn.push(qname);
            unit.push(u.to_string());
            n.push(v.len() as u64);
            mean.push(m);
            sd.push(d);
            lo.push(a);
            hi.push(b);
        }
    }
    let mut t = table(vec![scol("structure", name), scol("label", label), scol("quantity", qn), scol("unit", unit), ucol("realisations", n), fcol("mean", mean), fcol("sd", sd), fcol("min", lo), fcol("max", hi)])?;
    dir.write_table("structure_summary", &mut t)
}

fn write_distributions(dir: &mut ReportDir, s: &MicroStudy, built: &[Built], by: &[Vec<&Solved>], phases: &[Phase]) -> Result<()> {
    let (mut st, mut te, mut ph, mut me, mut pp, mut val) = (vec![], vec![], vec![], vec![], vec![], vec![]);
    type Measure = fn(&Local) -> &Vec<f64>;
    let measures: [(&str, Measure); 4] = [("sigma1_pa", |l| &l.sigma1), ("von_mises_pa", |l| &l.von_mises), ("strain1", |l| &l.strain1), ("shear_strain", |l| &l.shear_strain)];
    for (i, structure) in s.structure.iter().enumerate() {
        for (t, test) in Test::BOTH.iter().enumerate() {
            for (l, &p) in built[i].phase_of_label.iter().enumerate() {
                for (mname, f) in &measures {
                    let v: Vec<f64> = by[i].iter().flat_map(|r| r.micro.labels.iter().zip(f(&r.locals[t])).filter(|(lab, _)| **lab as usize == l).map(|(_, v)| *v)).collect();
                    if v.is_empty() {
                        continue;
                    }
                    let q = crate::stats::interpolated_quantiles(v, &DISTRIBUTION_P);
                    for (k, &pr) in DISTRIBUTION_P.iter().enumerate() {
                        st.push(structure.name.clone());
                        te.push(test.name().to_string());
                        ph.push(phases[p].name.clone());
                        me.push(mname.to_string());
                        pp.push(pr);
                        val.push(q[k]);
                    }
                }
            }
        }
    }
    let n = st.len();
    let mut t = table(vec![scol("structure", st), scol("test", te), scol("phase", ph), scol("measure", me), fcol("p", pp), fcol("value", val), fcol("applied_stress_pa", vec![s.applied_stress_pa; n])])?;
    dir.write_table("distributions", &mut t)
}

fn write_weibull(dir: &mut ReportDir, s: &MicroStudy, by: &[Vec<&Solved>]) -> Result<Vec<FirstFailureWeibull>> {
    let mut out = Vec::new();
    for (i, v) in by.iter().enumerate() {
        if v.len() < WEIBULL_MIN {
            continue;
        }
        let pivots = crate::weibull::simulate_pivotal(v.len(), 10_000, s.seed)?;
        for t in 0..2 {
            let x: Vec<f64> = v.iter().map(|r| r.first_failure(t)).collect();
            if x.iter().any(|f| !f.is_finite()) {
                continue;
            }
            let fit = crate::weibull::fit_mle(&x)?;
            let b = pivots.bounds(&fit, 0.9)?;
            out.push(FirstFailureWeibull { structure: i, test: t, n: x.len(), shape: fit.mle.shape, shape_unbiased: b.shape_unbiased, shape_bounds: b.shape, scale: fit.mle.scale });
        }
    }
    let mut t = table(vec![
        scol("structure", out.iter().map(|w| s.structure[w.structure].name.clone()).collect()),
        scol("test", out.iter().map(|w| Test::BOTH[w.test].name().to_string()).collect()),
        ucol("realisations", out.iter().map(|w| w.n as u64).collect()),
        fcol("shape", out.iter().map(|w| w.shape).collect()),
        fcol("shape_unbiased", out.iter().map(|w| w.shape_unbiased).collect()),
        fcol("shape_lo_90", out.iter().map(|w| w.shape_bounds.0).collect()),
        fcol("shape_hi_90", out.iter().map(|w| w.shape_bounds.1).collect()),
        fcol("scale_pa", out.iter().map(|w| w.scale).collect()),
    ])?;
    dir.write_table("first_failure_weibull", &mut t)?;
    Ok(out)
}

/// `failure_summary.csv` and `failure_events.csv`.
fn write_failure(dir: &mut ReportDir, s: &MicroStudy, built: &[Built], cracked: &[Cracked], phases: &[Phase]) -> Result<()> {
    let phase_at = |c: &Cracked, e: usize| -> String {
        let m = &built[c.structure].realisations[c.realisation].0;
        phases[built[c.structure].phase_of_label[m.labels[e] as usize]].name.clone()
    };
    let (mut st, mut re, mut te, mut strength, mut peak, mut events, mut first, mut first_phase, mut shares, mut stopped) = (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    for c in cracked {
        st.push(s.structure[c.structure].name.clone());
        re.push(c.realisation as u64);
        te.push(c.run.test.name().to_string());
        strength.push(c.run.strength_pa);
        peak.push(c.run.peak_event as u64);
        events.push(c.run.events.len() as u64);
        first.push(c.run.events.first().map_or(f64::NAN, |e| e.applied_pa));
        first_phase.push(c.run.events.first().map_or(String::new(), |e| phase_at(c, e.element)));
        let upto = &c.run.events[..(c.run.peak_event + 1).min(c.run.events.len())];
        let names: Vec<String> = built[c.structure].phase_of_label.iter().map(|&p| phases[p].name.clone()).collect();
        shares.push(names.iter().map(|n| format!("{n} {:.3}", upto.iter().filter(|e| &phase_at(c, e.element) == n).count() as f64 / upto.len().max(1) as f64)).collect::<Vec<_>>().join(" "));
        stopped.push(c.run.stopped.to_string());
    }
    let mut t = table(vec![
        scol("structure", st),
        ucol("realisation", re),
        scol("test", te),
        fcol("strength_pa", strength),
        ucol("peak_event", peak),
        ucol("events", events),
        fcol("first_crack_pa", first),
        scol("first_crack_phase", first_phase),
        scol("cracked_share_at_peak", shares),
        fcol("stiffness_left", cracked.iter().map(|c| c.run.stiffness_left).collect()),
        scol("stopped", stopped),
        // The number of cracks at which the run failed (empty: it did not).
        scol("failed_at_event", cracked.iter().map(|c| c.run.failed_at.map_or(String::new(), |k| k.to_string())).collect()),
    ])?;
    dir.write_table("failure_summary", &mut t)?;
    let rows: Vec<(&Cracked, usize)> = cracked.iter().flat_map(|c| (0..c.run.events.len()).map(move |k| (c, k))).collect();
    let geo = |c: &Cracked, e: usize| {
        let m = &built[c.structure].realisations[c.realisation].0;
        (e % m.nx, e / m.nx, m.pixel_m)
    };
    let mut t = table(vec![
        scol("structure", rows.iter().map(|(c, _)| s.structure[c.structure].name.clone()).collect()),
        ucol("realisation", rows.iter().map(|(c, _)| c.realisation as u64).collect()),
        scol("test", rows.iter().map(|(c, _)| c.run.test.name().to_string()).collect()),
        ucol("event", rows.iter().map(|(_, k)| *k as u64).collect()),
        fcol("applied_stress_pa", rows.iter().map(|(c, k)| c.run.events[*k].applied_pa).collect()),
        fcol("macro_strain", rows.iter().map(|(c, k)| c.run.events[*k].macro_strain).collect()),
        ucol("i", rows.iter().map(|(c, k)| geo(c, c.run.events[*k].element).0 as u64).collect()),
        ucol("j", rows.iter().map(|(c, k)| geo(c, c.run.events[*k].element).1 as u64).collect()),
        fcol("pixel_m", rows.iter().map(|(c, k)| geo(c, c.run.events[*k].element).2).collect()),
        scol("phase", rows.iter().map(|(c, k)| phase_at(c, c.run.events[*k].element)).collect()),
    ])?;
    dir.write_table("failure_events", &mut t)
}

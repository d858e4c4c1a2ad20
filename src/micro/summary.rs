//! `summary.md` of a microstructure report: every number is computed from the solved
//! realisations and every verdict follows from those numbers by the rules stated here.
//!
//! # The §6.1 comparison
//!
//! The deliverable argues (§6.1) that a soft phase forming a continuous matrix around the hard
//! grains (Gen 4) makes a better composite than soft pockets between touching hard grains
//! (BL 16/30), whose deformation bands "develop stress hot spots easily, promoting early
//! fracture". With `[comparison]` the summary tests the consequences the argument predicts for
//! the continuous structure, in each virtual test: a smaller area above strength at the applied
//! stress, a higher first-failure stress and, when both structures were cracked progressively
//! (`[failure]`), a higher strength. A difference is *clear* when it exceeds
//! twice its standard error — over paired realisations (the same grain seeds) when both
//! structures are synthetic with the same seeds, else Welch's √(s₁²/n₁ + s₂²/n₂). In each test
//! the numbers *support* the argument when at least one difference is clear in its favour and
//! none clear against it, *contradict* it in the opposite case, are *mixed* when clear
//! differences point both ways, and *do not decide* when none is clear (no hot spots at the
//! applied stress in either structure, say, leaves only the first-failure stress to decide).

use super::fields::Test;
use super::material::Phase;
use super::solve::{Built, Cracked, FirstFailureWeibull, Solved};
use crate::stats::mean_and_sd;
use super::structure::SOFT;
use super::study::MicroStudy;
use crate::schema::StudyFile;

fn gpa(v: f64) -> String {
    format!("{:.1}", v / 1e9)
}

fn mpa(v: f64) -> String {
    if v.is_finite() { format!("{:.1}", v / 1e6) } else { "none".into() }
}

fn pct(v: f64) -> String {
    format!("{:.2}", 100.0 * v)
}

/// "mean ± sd" of a quantity over the realisations, shown by `f`.
fn pm(v: &[f64], f: fn(f64) -> String) -> String {
    let (m, sd) = mean_and_sd(v);
    if v.len() > 1 { format!("{} ± {}", f(m), f(sd)) } else { f(m) }
}

/// The difference continuous − discontinuous of a quantity and its standard error.
fn difference(c: &[f64], d: &[f64], paired: bool) -> (f64, Option<f64>) {
    let (mc, sc) = mean_and_sd(c);
    let (md, sd) = mean_and_sd(d);
    if paired && c.len() == d.len() && c.len() > 1 {
        let diff: Vec<f64> = c.iter().zip(d).map(|(a, b)| a - b).collect();
        let (m, s) = mean_and_sd(&diff);
        return (m, Some(s / (diff.len() as f64).sqrt()));
    }
    let se = (c.len() > 1 && d.len() > 1).then(|| (sc * sc / c.len() as f64 + sd * sd / d.len() as f64).sqrt());
    (mc - md, se)
}

/// +1 clear in favour, −1 clear against, 0 not clear. `want_positive`: the argument predicts
/// continuous − discontinuous > 0.
fn judge(diff: f64, se: Option<f64>, want_positive: bool) -> i32 {
    let clear = match se {
        Some(se) => diff.abs() > 2.0 * se,
        None => false,
    };
    if !clear {
        return 0;
    }
    if (diff > 0.0) == want_positive { 1 } else { -1 }
}

/// The phase whose connectivity the comparison reports: `soft` of a synthetic structure, the
/// most compliant phase of an image.
fn matrix_label(s: &MicroStudy, i: usize, b: &Built, phases: &[Phase]) -> usize {
    if s.structure[i].synthetic.is_some() {
        return SOFT as usize;
    }
    (0..b.phase_of_label.len()).fold(0, |best, l| if phases[b.phase_of_label[l]].elastic.youngs_modulus_pa < phases[b.phase_of_label[best]].elastic.youngs_modulus_pa { l } else { best })
}

/// The summary and the CLI's headlines.
pub fn summary(loaded: &StudyFile, s: &MicroStudy, phases: &[Phase], built: &[Built], by: &[Vec<&Solved>], weibull: &[FirstFailureWeibull], cracked: &[Cracked]) -> (String, Vec<String>) {
    let sv = s.applied_stress_pa;
    let mut md = format!(
        "# Microstructure: {}\n\n{} structure{}, {} realisation{} in all, solved by periodic homogenisation on pixel-conforming bilinear quads in {} and loaded in two virtual uniaxial tests along x at the applied stress s = {} MPa: tension and compression (module `partlife::micro`).\n\n## Phases\n\n| phase | E (GPa) | ν | σ_t (MPa) | source |\n|---|---|---|---|---|\n",
        loaded.name,
        s.structure.len(),
        if s.structure.len() == 1 { "" } else { "s" },
        by.iter().map(Vec::len).sum::<usize>(),
        if by.iter().map(Vec::len).sum::<usize>() == 1 { "" } else { "s" },
        s.plane.label(),
        mpa(sv)
    );
    for p in phases {
        md.push_str(&format!("| {} | {} | {:.3} | {} | {} |\n", p.name, gpa(p.elastic.youngs_modulus_pa), p.elastic.poisson_ratio, mpa(p.tensile_strength_pa), p.source));
    }
    for (i, st) in s.structure.iter().enumerate() {
        if st.synthetic.is_some() {
            let (h, so) = (&phases[built[i].phase_of_label[0]], &phases[built[i].phase_of_label[1]]);
            if so.elastic.youngs_modulus_pa > h.elastic.youngs_modulus_pa {
                md.push_str(&format!(
                    "\nIn `{}` the phase arranged as the matrix (`soft` = {}, E = {} GPa) is stiffer than the one arranged as grains (`hard` = {}, E = {} GPa): `soft` and `hard` name the arrangement, and stiffness ranks these two phases the other way.\n",
                    st.name,
                    so.name,
                    gpa(so.elastic.youngs_modulus_pa),
                    h.name,
                    gpa(h.elastic.youngs_modulus_pa)
                ));
            }
        }
    }

    md.push_str("\n## Structures and effective moduli\n\nE and ν are the isotropic projections of the effective stiffness (`structures.csv`); the Hashin–Shtrikman (HS) bounds are those of the phases at each realisation's area fractions.\n\n| structure | source | pixels (pixel size) | area fractions | percolating (x or y) in realisations | E (GPa) | HS bounds on E (GPa) | inside HS |\n|---|---|---|---|---|---|---|---|\n");
    let mut headlines = Vec::new();
    for (i, st) in s.structure.iter().enumerate() {
        let v = &by[i];
        let names: Vec<&str> = built[i].phase_of_label.iter().map(|&p| phases[p].name.as_str()).collect();
        let fr: Vec<String> = (0..names.len()).map(|l| format!("{} {:.3}", names[l], mean_and_sd(&v.iter().map(|r| r.fractions[l]).collect::<Vec<_>>()).0)).collect();
        let perc: Vec<String> = (0..names.len()).map(|l| format!("{} {}/{}", names[l], v.iter().filter(|r| r.connectivity[l].percolates()).count(), v.len())).collect();
        let e: Vec<f64> = v.iter().map(|r| r.youngs_poisson.0).collect();
        let ehs = |r: &Solved, lo: bool| {
            let b = if lo { r.bounds.hs_lower } else { r.bounds.hs_upper };
            s.plane.youngs_and_poisson(b.0, b.1).0
        };
        let (lo, hi) = (v.iter().map(|r| ehs(r, true)).fold(f64::INFINITY, f64::min), v.iter().map(|r| ehs(r, false)).fold(f64::NEG_INFINITY, f64::max));
        let source = match (&st.synthetic, &st.image) {
            (Some(g), _) => format!("synthetic, {} grains", g.grains),
            (_, Some(im)) => format!("image `{}`", im.file.display()),
            _ => String::new(),
        };
        md.push_str(&format!(
            "| {} | {source} | {} × {} ({:.3} µm) | {} | {} | {} | {}–{} | {}/{} |\n",
            st.label,
            v[0].micro.nx,
            v[0].micro.ny,
            v[0].micro.pixel_m * 1e6,
            fr.join(", "),
            perc.join(", "),
            pm(&e, gpa),
            gpa(lo),
            gpa(hi),
            v.iter().filter(|r| r.within_hs()).count(),
            v.len()
        ));
        let ht: Vec<f64> = v.iter().map(|r| r.above_strength(0)).collect();
        let ff: Vec<f64> = v.iter().map(|r| r.first_failure(0)).collect();
        headlines.push(format!("{}: E = {} GPa, area above strength in tension at {} MPa {} %, first failure in tension at {} MPa", st.name, pm(&e, gpa), mpa(sv), pm(&ht, pct), pm(&ff, mpa)));
    }

    md.push_str("\n### Connectivity of each phase\n\nClusters are 4-connected pixel sets of a phase (the box not wrapped); a phase percolates when one cluster touches two opposite edges (`connectivity.csv`). Means over the realisations:\n\n| structure | phase | area fraction | clusters | largest cluster's share of the phase | percolating in x / in y |\n|---|---|---|---|---|---|\n");
    for (i, st) in s.structure.iter().enumerate() {
        let v = &by[i];
        for (l, &p) in built[i].phase_of_label.iter().enumerate() {
            let mean = |f: &dyn Fn(&Solved) -> f64| mean_and_sd(&v.iter().map(|r| f(r)).collect::<Vec<_>>()).0;
            md.push_str(&format!(
                "| {} | {} | {:.3} | {:.1} | {:.3} | {}/{} / {}/{} |\n",
                st.label,
                phases[p].name,
                mean(&|r| r.connectivity[l].fraction),
                mean(&|r| r.connectivity[l].clusters as f64),
                mean(&|r| r.connectivity[l].largest_fraction),
                v.iter().filter(|r| r.connectivity[l].percolates_x).count(),
                v.len(),
                v.iter().filter(|r| r.connectivity[l].percolates_y).count(),
                v.len()
            ));
        }
    }

    md.push_str(&format!(
        "\n## Hot spots at s = {} MPa\n\nThe area above strength is the share of the cell whose maximum principal stress σ₁ exceeds its phase's tensile strength σ_t at the applied stress; the first-failure stress is the applied stress at which the first pixel reaches σ_t (the lowest over the phases; which phase that is, in how many realisations); the stress-concentration factor (SCF) is the 99.9 % quantile of σ₁ in a phase over s (`hot_spots.csv`). Pixel-level maxima, and with them the first-failure stress, depend on the pixel size near the corners of a pixelated interface; the quantiles and areas converge with refinement.\n\n| structure | test | area above strength (%) | first failure (MPa) | first to fail | SCF q99.9 per phase |\n|---|---|---|---|---|---|\n",
        mpa(sv)
    ));
    for (i, st) in s.structure.iter().enumerate() {
        let v = &by[i];
        let names: Vec<&str> = built[i].phase_of_label.iter().map(|&p| phases[p].name.as_str()).collect();
        for (t, test) in Test::BOTH.iter().enumerate() {
            let above: Vec<f64> = v.iter().map(|r| r.above_strength(t)).collect();
            let ff: Vec<f64> = v.iter().map(|r| r.first_failure(t)).collect();
            let first: Vec<usize> = v.iter().map(|r| (0..names.len()).fold(0, |b, l| if r.hot[t][l].first_failure_pa < r.hot[t][b].first_failure_pa { l } else { b })).collect();
            let counts: Vec<String> = (0..names.len()).filter(|&l| first.contains(&l)).map(|l| format!("{} {}/{}", names[l], first.iter().filter(|&&f| f == l).count(), v.len())).collect();
            let scf: Vec<String> = (0..names.len()).map(|l| format!("{} {:.2}", names[l], mean_and_sd(&v.iter().map(|r| r.hot[t][l].sigma1_q[3] / sv).collect::<Vec<_>>()).0)).collect();
            let ff_shown = if ff.iter().all(|f| f.is_finite()) { pm(&ff, mpa) } else { "no pixel in tension".into() };
            md.push_str(&format!("| {} | {} | {} | {ff_shown} | {} | {} |\n", st.label, test.name(), pm(&above, pct), counts.join(", "), scf.join(", ")));
        }
    }

    let mut argument = None;
    if let Some(c) = &s.comparison {
        let (ic, id) = (s.structure.iter().position(|x| x.name == c.continuous).unwrap_or(0), s.structure.iter().position(|x| x.name == c.discontinuous).unwrap_or(0));
        let (vc, vd) = (&by[ic], &by[id]);
        let seeds = |v: &Vec<&Solved>| v.iter().map(|r| r.seed).collect::<Vec<_>>();
        let paired = seeds(vc) == seeds(vd) && vc.iter().all(|r| r.seed.is_some());
        let names = |i: usize| built[i].phase_of_label.iter().map(|&p| phases[p].name.clone()).collect::<Vec<_>>();
        let mean_fr = |v: &Vec<&Solved>, l: usize| mean_and_sd(&v.iter().map(|r| r.fractions[l]).collect::<Vec<_>>()).0;
        let same_phases = names(ic) == names(id);
        let same_fractions = same_phases && (0..names(ic).len()).all(|l| (mean_fr(vc, l) - mean_fr(vd, l)).abs() < 0.01);
        let (lc, ld) = (matrix_label(s, ic, &built[ic], phases), matrix_label(s, id, &built[id], phases));
        let perc = |v: &Vec<&Solved>, l: usize| v.iter().filter(|r| r.connectivity[l].percolates()).count();
        let (lab_c, lab_d) = (&s.structure[ic].label, &s.structure[id].label);
        md.push_str(&format!(
            "\n## The deliverable's §6.1 argument\n\n§6.1 attributes Gen 4's advantage to its soft phase forming a continuous matrix around the hard grains, and BL 16/30's weakness to soft pockets between touching hard grains. Here {lab_c} (`{}`) is the continuous structure and {lab_d} (`{}`) the discontinuous one. {} {} percolates in {}/{} realisations of the continuous structure and {}/{} of the discontinuous one. The argument predicts, for the continuous structure, a smaller area above strength and a higher first-failure stress; a difference is clear when it exceeds twice its standard error ({}).\n",
            c.continuous,
            c.discontinuous,
            if same_fractions {
                "They have the same phases at the same area fractions (within 0.01), so they differ in arrangement alone.".to_string()
            } else if same_phases {
                "They have the same phases but different area fractions (by 0.01 or more): the comparison is not of arrangement alone.".to_string()
            } else {
                format!("Their phases differ ({} vs {}): the comparison is not of arrangement alone.", names(ic).join(", "), names(id).join(", "))
            },
            {
                let (a, b) = (&phases[built[ic].phase_of_label[lc]].name, &phases[built[id].phase_of_label[ld]].name);
                if a == b { format!("Their soft phase, {a},") } else { format!("The soft phase ({a} and {b} respectively)") }
            },
            perc(vc, lc),
            vc.len(),
            perc(vd, ld),
            vd.len(),
            if paired { format!("paired over the {} realisations that share their grain seeds", vc.len()) } else { "Welch".to_string() }
        ));
        // The cells' strengths from progressive failure, when both structures were cracked (the
        // first realisations of each: paired like the rest when the seeds are).
        let strengths = |i: usize, t: Test| -> Vec<f64> { cracked.iter().filter(|c| c.structure == i && c.run.test == t).map(|c| c.run.strength_pa).collect() };
        let with_strength = !strengths(ic, Test::Tension).is_empty() && !strengths(id, Test::Tension).is_empty();
        if with_strength {
            md.push_str("\nWith `[failure]` the cell's strength — the largest applied stress of its progressive failure — is a third measure, which the argument predicts higher for the continuous structure.\n");
        }
        md.push_str(&format!(
            "\n| test | area above strength (%): continuous; discontinuous; difference ± se | first failure (MPa): continuous; discontinuous; difference ± se |{} verdict |\n|---|---|---|{}---|\n",
            if with_strength { " strength (MPa): continuous; discontinuous; difference ± se |" } else { "" },
            if with_strength { "---|" } else { "" }
        ));
        let mut verdicts = Vec::new();
        let se = |x: Option<f64>, f: fn(f64) -> String| x.map_or("(no spread)".to_string(), f);
        for (t, test) in Test::BOTH.iter().enumerate() {
            let a = |v: &Vec<&Solved>| v.iter().map(|r| r.above_strength(t)).collect::<Vec<f64>>();
            let f = |v: &Vec<&Solved>| v.iter().map(|r| r.first_failure(t)).collect::<Vec<f64>>();
            let (da, sa) = difference(&a(vc), &a(vd), paired);
            let finite = f(vc).iter().chain(&f(vd)).all(|x| x.is_finite());
            let (df, sf) = if finite { difference(&f(vc), &f(vd), paired) } else { (f64::NAN, None) };
            let mut judged = vec![judge(da, sa, false), if finite { judge(df, sf, true) } else { 0 }];
            let mut cells = vec![
                format!("{}; {}; {} ± {}", pm(&a(vc), pct), pm(&a(vd), pct), pct(da), se(sa, pct)),
                format!("{}; {}; {} ± {}", if finite { pm(&f(vc), mpa) } else { "–".into() }, if finite { pm(&f(vd), mpa) } else { "–".into() }, mpa(df), se(sf, mpa)),
            ];
            if with_strength {
                let (sc, sd) = (strengths(ic, *test), strengths(id, *test));
                // A run that ended at max_events or failed has a lower bound for a strength: not compared.
                let bounded = cracked.iter().filter(|c| (c.structure == ic || c.structure == id) && c.run.test == *test).all(|c| !c.run.lower_bound());
                let ok = bounded && !sc.is_empty() && !sd.is_empty() && sc.iter().chain(&sd).all(|x| *x > 0.0);
                let (ds, ss) = if ok { difference(&sc, &sd, paired && sc.len() == sd.len()) } else { (f64::NAN, None) };
                judged.push(if ok { judge(ds, ss, true) } else { 0 });
                cells.push(if ok {
                    format!("{}; {}; {} ± {}", pm(&sc, mpa), pm(&sd, mpa), mpa(ds), se(ss, mpa))
                } else if !bounded {
                    "– (runs ended at max_events or failed: lower bounds)".into()
                } else {
                    "–".into()
                });
            }
            let (best, worst) = (judged.iter().copied().max().unwrap_or(0), judged.iter().copied().min().unwrap_or(0));
            let verdict = match (best, worst) {
                (1, -1) => "mixed: measures for and against",
                (1, _) => "support the argument",
                (_, -1) => "contradict the argument",
                _ => "do not decide",
            };
            verdicts.push((test.name(), verdict));
            md.push_str(&format!("| {} | {} | {verdict} |\n", test.name(), cells.join(" | ")));
        }
        let sentence = |v: &str| if v.starts_with("mixed") { "are mixed (measures for the argument and against it)".to_string() } else { v.to_string() };
        argument = Some(format!(
            "For the deliverable's §6.1 argument — a continuous soft matrix ({lab_c}) fails later than soft pockets ({lab_d}) — the numbers in tension {}; in compression they {}.",
            sentence(verdicts[0].1),
            sentence(verdicts[1].1)
        ));
        md.push_str(&format!(
            "\nIn tension the numbers {}; in compression they {}. {}\n",
            sentence(verdicts[0].1),
            sentence(verdicts[1].1),
            if with_strength { "The strengths come from brittle, pixel-by-pixel cracking without a fracture energy: they rank the arrangements, their absolute values depend on the pixel size." } else { "These are elastic fields with deterministic phase strengths: they test where stress concentrates, not how a crack then runs (add `[failure]` for that)." }
        ));
    }

    if !cracked.is_empty() {
        md.push_str("\n## Progressive failure\n\nEach cell is cracked pixel by pixel (sequentially linear analysis: the pixel that reaches its tensile strength at the lowest applied stress cracks, its stiffness drops to a residual, the cell is solved again; `failure_summary.csv`, `failure_events.csv`). The strength is the largest applied stress on the way; a run that ended at `max_events` gives a lower bound, and so does a run that failed (its effective stiffness became singular: `failed_at_event` names the step) (cracks across the largest tension split a compressed cell along the load and hardly soften it, so compression runs tend to end there).\n\n| structure | test | runs | strength (MPa) | first crack (MPa) | cracks to the peak | first cracks in | cracked pixels at the peak, by phase | runs ended by |\n|---|---|---|---|---|---|---|---|---|\n");
        for (i, st) in s.structure.iter().enumerate() {
            for test in Test::BOTH {
                let runs: Vec<&Cracked> = cracked.iter().filter(|c| c.structure == i && c.run.test == test).collect();
                if runs.is_empty() {
                    continue;
                }
                let m_of = |c: &Cracked| &built[i].realisations[c.realisation].0;
                let phase_of = |c: &Cracked, e: usize| built[i].phase_of_label[m_of(c).labels[e] as usize];
                let strength: Vec<f64> = runs.iter().map(|c| c.run.strength_pa).collect();
                let first: Vec<f64> = runs.iter().filter_map(|c| c.run.events.first().map(|e| e.applied_pa)).collect();
                let to_peak: Vec<f64> = runs.iter().map(|c| (c.run.peak_event + 1) as f64).collect();
                let firsts: Vec<usize> = runs.iter().filter_map(|c| c.run.events.first().map(|e| phase_of(c, e.element))).collect();
                let first_in: Vec<String> = built[i].phase_of_label.iter().filter(|p| firsts.contains(p)).map(|&p| format!("{} {}/{}", phases[p].name, firsts.iter().filter(|&&q| q == p).count(), runs.len())).collect();
                let shares: Vec<String> = built[i]
                    .phase_of_label
                    .iter()
                    .map(|&p| {
                        let v: Vec<f64> = runs.iter().map(|c| {
                            let upto = &c.run.events[..(c.run.peak_event + 1).min(c.run.events.len())];
                            upto.iter().filter(|e| phase_of(c, e.element) == p).count() as f64 / upto.len().max(1) as f64
                        }).collect();
                        format!("{} {:.2}", phases[p].name, mean_and_sd(&v).0)
                    })
                    .collect();
                let none = runs.iter().all(|c| c.run.events.is_empty());
                let mut ended: Vec<(&str, usize)> = Vec::new();
                for c in &runs {
                    match ended.iter_mut().find(|e| e.0 == c.run.stopped) {
                        Some(e) => e.1 += 1,
                        None => ended.push((c.run.stopped, 1)),
                    }
                }
                md.push_str(&format!(
                    "| {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
                    st.label,
                    test.name(),
                    runs.len(),
                    if none { "no pixel in tension".to_string() } else { pm(&strength, mpa) },
                    if first.is_empty() { "–".to_string() } else { pm(&first, mpa) },
                    if none { "–".to_string() } else { pm(&to_peak, |x| format!("{x:.0}")) },
                    first_in.join(", "),
                    shares.join(", "),
                    ended.iter().map(|(why, n)| format!("{why} {n}/{}", runs.len())).collect::<Vec<_>>().join("; ")
                ));
            }
        }
    }

    if !weibull.is_empty() {
        md.push_str("\n## Scatter of the first failure between realisations\n\nThe first-failure stress of each realisation, fitted by a two-parameter Weibull law over the realisations (ASTM C1239 maximum likelihood, 90 % pivotal bounds; `first_failure_weibull.csv`):\n\n| structure | test | realisations | m̂ [90 % bounds] | unbiased m | scale (MPa) |\n|---|---|---|---|---|---|\n");
        for w in weibull {
            md.push_str(&format!("| {} | {} | {} | {:.1} [{:.1}, {:.1}] | {:.1} | {} |\n", s.structure[w.structure].label, Test::BOTH[w.test].name(), w.n, w.shape, w.shape_bounds.0, w.shape_bounds.1, w.shape_unbiased, mpa(w.scale)));
        }
        md.push_str("\nThis modulus measures how much the stress concentration of the microstructure alone varies between cells of the same statistics, with the same strength in every pixel of a phase. A crush test's modulus also contains the scatter of flaw sizes and of the stressed volume between particles, so the two are comparable only in kind: a microstructure modulus well above a crush modulus says that the arrangement of the phases explains little of the particles' scatter.\n");
    }
    md.push_str(&format!(
        "\n## Figures\n\nPer structure (first realisation): `phases_<structure>` (the phase map), `sigma1_tension_<structure>` and `sigma1_compression_<structure>` (σ₁ at s = {} MPa), `shear_strain_<structure>` (γ_max in tension, the deformation bands of the deliverable's Fig. 11a); `exceedance` (the share of each phase's area whose σ₁ exceeds a multiple of the phase's tensile strength, both tests; at 1, the share above strength); `comparison` (E with its HS bounds, the area above strength, the first-failure stress and, with `[failure]`, the strength of every structure); with `[failure]`, `failure_curves` (the applied stress at each crack against the pixels cracked so far) and `cracks_<test>_<structure>` (the cracked pixels of the first realisation in their order). The first realisation's fields are in `<structure>.vtu` for ParaView.\n",
        mpa(sv)
    ));
    // The answer opens the document, after the title and what was solved.
    let answer = answer(s, by, argument);
    let at = md.find("\n## Phases").unwrap_or(md.len());
    md.insert_str(at, &answer);
    (md, headlines)
}

/// The `## Answer`: which structure's first pixel fails at the highest applied stress in virtual
/// tension (the mean over its realisations, with the others'), and with `[comparison]` what the
/// numbers say of the deliverable's §6.1 argument (`argument`, the verdict sentence of that
/// section).
fn answer(s: &MicroStudy, by: &[Vec<&Solved>], argument: Option<String>) -> String {
    let values = |i: usize| by[i].iter().map(|r| r.first_failure(0)).collect::<Vec<_>>();
    let tension = |i: usize| mean_and_sd(&values(i)).0;
    let order: Vec<usize> = {
        let mut o: Vec<usize> = (0..s.structure.len()).filter(|&i| !by[i].is_empty() && tension(i).is_finite()).collect();
        o.sort_by(|&a, &b| tension(b).total_cmp(&tension(a)));
        o
    };
    let each = |i: usize| format!("{} {} MPa", s.structure[i].label, pm(&values(i), mpa));
    let first = match order.as_slice() {
        [] => "No structure has a pixel reaching its phase's tensile strength in virtual tension.".to_string(),
        [i] => format!("In virtual tension the first pixel of {} fails at an applied stress of {} MPa (mean{} over its {} realisation{}).", s.structure[*i].label, pm(&values(*i), mpa), if by[*i].len() > 1 { " ± sd" } else { "" }, by[*i].len(), if by[*i].len() == 1 { "" } else { "s" }),
        [i, rest @ ..] => format!(
            "In virtual tension the first pixel fails at the highest applied stress in {}, {} MPa, against {} (mean ± sd over the realisations).",
            s.structure[*i].label,
            pm(&values(*i), mpa),
            rest.iter().map(|&j| each(j)).collect::<Vec<_>>().join(", ")
        ),
    };
    let argument = argument.map(|a| format!(" {a} Each measure's difference and its standard error are in the section on the §6.1 argument.")).unwrap_or_default();
    format!("\n## Answer\n\n{first}{argument}\n")
}

//! Captions of a microstructure report's figures (`kind = "microstructure"`), each read from the
//! table its figure is drawn from: the maps of the first realisation from `map_<structure>.csv`
//! (with the phases' strengths from `phases.csv`), the hot-spot tail from `hot_spots.csv`, the
//! comparison from `structure_summary.csv` and the cracks from `failure_summary.csv`.

use std::path::Path;

use super::super::document::Block;
use super::super::micro::structure_labels;
use super::super::{Table, distinct};
use super::{FigureNote, p, percent};
use crate::error::Result;

/// A phase's name as the figures' legends write it.
fn phase_name(p: &str) -> String {
    p.replace('_', " ")
}

/// A length in µm to four significant figures, trailing zeros dropped ("0.125", "32").
fn length(v: f64) -> String {
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    let t = format!("{v:.digits$}");
    if t.contains('.') { t.trim_end_matches('0').trim_end_matches('.').to_string() } else { t }
}

/// The note of figure `stem` of a microstructure report (None: not one of its figures).
pub(super) fn figure(dir: &Path, stem: &str) -> Result<Option<FigureNote>> {
    let structures = distinct(&Table::load(dir, "structures")?.s("structure")?);
    // Longest key first: a structure named `a_b` is not taken for `b`.
    let mut by_length = structures.clone();
    by_length.sort_by_key(|s| std::cmp::Reverse(s.len()));
    let of = |prefix: &str| by_length.iter().find(|s| stem.strip_prefix(prefix).is_some_and(|rest| rest == s.as_str())).cloned();
    Ok(Some(if let Some(s) = of("phases_") {
        phases(dir, &s)?
    } else if let Some(s) = of("sigma1_tension_") {
        sigma1(dir, &s, "tension")?
    } else if let Some(s) = of("sigma1_compression_") {
        sigma1(dir, &s, "compression")?
    } else if let Some(s) = of("shear_strain_") {
        shear(dir, &s)?
    } else if let Some(s) = of("cracks_tension_") {
        cracks(dir, &s, "tension")?
    } else if let Some(s) = of("cracks_compression_") {
        cracks(dir, &s, "compression")?
    } else {
        match stem {
            "exceedance" => exceedance(dir)?,
            "comparison" => comparison(dir)?,
            "failure_curves" => failure_curves(dir)?,
            _ => return Ok(None),
        }
    }))
}

/// The applied stress of the virtual tests (MPa).
fn applied_mpa(dir: &Path) -> Result<f64> {
    Ok(Table::load(dir, "hot_spots")?.f("applied_stress_pa")?.first().copied().unwrap_or(f64::NAN) / 1e6)
}

fn phases(dir: &Path, s: &str) -> Result<FigureNote> {
    let label = structure_labels(dir)?(s);
    let t = Table::load(dir, "structures")?.filter("structure", s)?;
    let (nx, ny, px, seed, source) = (t.f("nx")?, t.f("ny")?, t.f("pixel_m")?, t.s("seed")?, t.s("source")?);
    let (names, fr) = (t.s("phases")?, t.s("fractions")?);
    let fractions: Vec<String> = names[0].split_whitespace().zip(fr[0].split_whitespace()).map(|(n, f)| format!("{} {}", phase_name(n), f.parse::<f64>().map_or(f.to_string(), |v| format!("{v:.3}")))).collect();
    let c = Table::load(dir, "connectivity")?.filter("structure", s)?;
    let (re, ph, px_, py_) = (c.f("realisation")?, c.s("phase")?, c.f("percolates_x")?, c.f("percolates_y")?);
    let perc: Vec<String> = (0..ph.len())
        .filter(|&i| re[i] == 0.0)
        .map(|i| {
            let how = match (px_[i] > 0.0, py_[i] > 0.0) {
                (true, true) => "percolates in x and y",
                (true, false) => "percolates in x only",
                (false, true) => "percolates in y only",
                _ => "does not percolate",
            };
            format!("{} {how}", phase_name(&ph[i]))
        })
        .collect();
    let side = nx[0] * px[0] * 1e6;
    Ok(FigureNote {
        title: Some(format!("Phases of {label}")),
        caption: p(&format!(
            "The phases of the first realisation of {label} ({}, seed {}): {:.0} × {:.0} pixels of {} µm, {} µm a side; area fractions {}. In this realisation {}.",
            source[0],
            seed[0],
            nx[0],
            ny[0],
            length(px[0] * 1e6),
            length(side),
            fractions.join(", "),
            perc.join(", ")
        )),
        blocks: vec![],
    })
}

/// The map of a structure with each row's phase and the phase's tensile strength.
fn map_with_strength(dir: &Path, s: &str) -> Result<(Table, Vec<String>, Vec<f64>)> {
    let map = Table::load(dir, &format!("map_{s}"))?;
    let ph = Table::load(dir, "phases")?;
    let (names, strength) = (ph.s("phase")?, ph.f("tensile_strength_pa")?);
    let phase = map.s("phase")?;
    let st = phase.iter().map(|q| names.iter().position(|n| n == q).map_or(f64::NAN, |k| strength[k])).collect();
    Ok((map, phase, st))
}

fn sigma1(dir: &Path, s: &str, test: &str) -> Result<FigureNote> {
    let label = structure_labels(dir)?(s);
    let applied = applied_mpa(dir)?;
    let (map, phase, strength) = map_with_strength(dir, s)?;
    let v = map.f(&format!("sigma1_{test}_pa"))?;
    let sign = if test == "tension" { "" } else { "−" };
    let above = (0..v.len()).filter(|&i| v[i] > strength[i]).count();
    let mut per = Vec::new();
    for q in distinct(&phase) {
        let idx: Vec<usize> = (0..v.len()).filter(|&i| phase[i] == q).collect();
        let hi = idx.iter().map(|&i| v[i]).fold(f64::NEG_INFINITY, f64::max);
        let st = strength[idx[0]];
        per.push(format!("{} up to {:.0} MPa ({:.2} of its σ_t = {:.0} MPa)", phase_name(&q), hi / 1e6, hi / st, st / 1e6));
    }
    let lo = v.iter().cloned().fold(f64::INFINITY, f64::min) / 1e6;
    Ok(FigureNote {
        title: Some(format!("Maximum principal stress in {label}, {test}")),
        caption: p(&format!(
            "σ₁ over the first realisation of {label} under uniaxial {test}, Σxx = {sign}{applied:.0} MPa, with the phase boundaries: σ₁ from {} MPa; {}. {} of the map's {} cells ({}) carry σ₁ above their phase's tensile strength.",
            format!("{lo:.0}").replace('-', "−"),
            per.join(", "),
            above,
            v.len(),
            percent(above as f64 / v.len().max(1) as f64)
        )),
        blocks: vec![],
    })
}

fn shear(dir: &Path, s: &str) -> Result<FigureNote> {
    let label = structure_labels(dir)?(s);
    let applied = applied_mpa(dir)?;
    let map = Table::load(dir, &format!("map_{s}"))?;
    let (phase, g) = (map.s("phase")?, map.f("shear_strain_tension")?);
    let per: Vec<String> = distinct(&phase)
        .iter()
        .map(|q| {
            let mut x: Vec<f64> = (0..g.len()).filter(|&i| &phase[i] == q).map(|i| g[i]).collect();
            x.sort_by(f64::total_cmp);
            format!("{} median {:.2} ‰, largest {:.2} ‰", phase_name(q), 1e3 * x[x.len() / 2], 1e3 * x[x.len() - 1])
        })
        .collect();
    Ok(FigureNote {
        title: Some(format!("Maximum shear strain in {label}")),
        caption: p(&format!("The maximum shear strain γ_max over the first realisation of {label} under uniaxial tension, Σxx = {applied:.0} MPa: {}. Bands of high γ_max mark where the cell deforms.", per.join("; "))),
        blocks: vec![],
    })
}

fn exceedance(dir: &Path) -> Result<FigureNote> {
    let labels = structure_labels(dir)?;
    let t = Table::load(dir, "hot_spots")?;
    let (st, te, ph, above) = (t.s("structure")?, t.s("test")?, t.s("phase")?, t.f("above_strength_in_phase")?);
    let mut rows = Vec::new();
    let mut largest = (f64::NEG_INFINITY, String::new());
    for s in distinct(&st) {
        for test in ["tension", "compression"] {
            for q in distinct(&(0..st.len()).filter(|&i| st[i] == s).map(|i| ph[i].clone()).collect::<Vec<_>>()) {
                let idx: Vec<usize> = (0..st.len()).filter(|&i| st[i] == s && te[i] == test && ph[i] == q).collect();
                if idx.is_empty() {
                    continue;
                }
                let mean = idx.iter().map(|&i| above[i]).sum::<f64>() / idx.len() as f64;
                if mean > largest.0 {
                    largest = (mean, format!("{} of the {} of {} in {test}", percent(mean), phase_name(&q), labels(&s)));
                }
                rows.push(vec![labels(&s), test.to_string(), phase_name(&q), percent(mean)]);
            }
        }
    }
    let most = if largest.0 > 0.0 { format!("The largest share above strength: {}.", largest.1) } else { "No phase exceeds its strength anywhere.".into() };
    Ok(FigureNote {
        title: Some("The hot-spot tail of each phase".into()),
        caption: p(&format!(
            "Share of each phase's area whose σ₁ exceeds a multiple of that phase's tensile strength σ_t, over every realisation, in tension (top) and compression (bottom); at σ₁/σ_t = 1 (dotted line) it is the share above strength. {most} The table gives that share per structure, test and phase (mean over the realisations)."
        )),
        blocks: vec![Block::Table { header: vec!["structure".into(), "test".into(), "phase".into(), "area above σ_t".into()], rows }],
    })
}

fn comparison(dir: &Path) -> Result<FigureNote> {
    let t = Table::load(dir, "structure_summary")?;
    let (st, lab, q, mean, sd, n) = (t.s("structure")?, t.s("label")?, t.s("quantity")?, t.f("mean")?, t.f("sd")?, t.f("realisations")?);
    let get = |s: &str, what: &str| (0..st.len()).find(|&k| st[k] == s && q[k] == what);
    let ms = |k: Option<usize>, scale: f64, unit: &str, digits: usize| k.map_or("—".to_string(), |k| format!("{:.digits$} ± {:.digits$}{unit}", mean[k] * scale, sd[k] * scale));
    let mut rows = Vec::new();
    for s in distinct(&st) {
        let first = get(&s, "youngs_modulus");
        let label = lab[first.unwrap_or(0)].clone();
        let strength = |test: &str| match get(&s, &format!("strength_{test}")) {
            Some(k) => ms(Some(k), 1e-6, "", 1),
            None => match get(&s, &format!("strength_{test}_lower_bound")) {
                Some(k) => format!("> {}", ms(Some(k), 1e-6, "", 1)),
                None => "—".into(),
            },
        };
        let mut row = vec![
            label,
            format!("{:.0}", first.map_or(f64::NAN, |k| n[k])),
            ms(first, 1e-9, "", 1),
            ms(get(&s, "above_strength_tension"), 100.0, "", 2),
            ms(get(&s, "first_failure_tension"), 1e-6, "", 1),
            ms(get(&s, "first_failure_compression"), 1e-6, "", 1),
        ];
        if q.iter().any(|x| x.starts_with("strength_")) {
            row.extend([strength("tension"), strength("compression")]);
        }
        rows.push(row);
    }
    let mut header: Vec<String> = ["structure", "realisations", "E (GPa)", "area above strength, tension (%)", "first failure, tension (MPa)", "first failure, compression (MPa)"].map(String::from).to_vec();
    if q.iter().any(|x| x.starts_with("strength_")) {
        header.extend(["strength, tension (MPa)".into(), "strength, compression (MPa)".into()]);
    }
    let strength = if header.len() > 6 { " and the strength of the progressive failure runs (\"> \": the runs stopped at their event limit first, a lower bound)" } else { "" };
    Ok(FigureNote {
        title: Some("The structures compared".into()),
        caption: p(&format!(
            "Per structure, mean ± one standard deviation over its realisations: the effective Young's modulus E within its Hashin–Shtrikman bounds, the area above strength and the first-failure stress in tension and compression{strength}. The numbers are in the table below."
        )),
        blocks: vec![Block::Table { header, rows }],
    })
}

fn failure_curves(dir: &Path) -> Result<FigureNote> {
    let labels = structure_labels(dir)?;
    let t = Table::load(dir, "failure_summary")?;
    let (st, re, te, strength, peak, events, first, phase, stopped) = (t.s("structure")?, t.f("realisation")?, t.s("test")?, t.f("strength_pa")?, t.f("peak_event")?, t.f("events")?, t.f("first_crack_pa")?, t.s("first_crack_phase")?, t.s("stopped")?);
    let bound = lower_bounds(&t)?;
    let rows: Vec<Vec<String>> = (0..st.len())
        .filter(|&i| re[i] == 0.0)
        .map(|i| vec![labels(&st[i]), te[i].clone(), format!("{:.1}", first[i] / 1e6), phase_name(&phase[i]), format!("{}{:.1}", if bound[i] { "> " } else { "" }, strength[i] / 1e6), format!("{:.0}", peak[i] + 1.0), format!("{:.0}", events[i]), stopped[i].clone()])
        .collect();
    Ok(FigureNote {
        title: Some("Progressive failure of the first realisation".into()),
        caption: p("The applied stress |Σxx| at which each pixel cracks against the number of pixels cracked so far, first realisation of each structure, tension (top) and compression (bottom): rising where the cell carries more load after a crack, falling where a crack runs on by itself; the highest point is the cell's strength. The table gives the first crack, the strength (\"> \": the run stopped at its event limit or failed first, a lower bound), at which crack it was reached and why each run stopped."),
        blocks: vec![Block::Table {
            header: ["structure", "test", "first crack (MPa)", "in phase", "strength (MPa)", "at crack", "cracks", "stopped"].map(String::from).to_vec(),
            rows,
        }],
    })
}

/// Per row of `failure_summary.csv`: whether its strength is only a lower bound — the run used up
/// its event limit (`stopped` = "max_events", as the table writes it) or its solve failed (an
/// event in `failed_at_event`).
fn lower_bounds(t: &Table) -> Result<Vec<bool>> {
    let (stopped, failed) = (t.s("stopped")?, t.s("failed_at_event")?);
    Ok((0..stopped.len()).map(|i| stopped[i] == "max_events" || !failed[i].is_empty()).collect())
}

/// "alumina 0.000 fused_silica 1.000" → "alumina 0 %, fused silica 100 %".
fn shares(s: &str) -> String {
    let w: Vec<&str> = s.split_whitespace().collect();
    w.chunks(2).map(|c| format!("{} {}", phase_name(c[0]), c.get(1).and_then(|v| v.parse::<f64>().ok()).map_or("—".into(), percent))).collect::<Vec<_>>().join(", ")
}

fn cracks(dir: &Path, s: &str, test: &str) -> Result<FigureNote> {
    let label = structure_labels(dir)?(s);
    let t = Table::load(dir, "failure_summary")?;
    let (st, re, te, strength, peak, events, first, phase, share) = (t.s("structure")?, t.f("realisation")?, t.s("test")?, t.f("strength_pa")?, t.f("peak_event")?, t.f("events")?, t.f("first_crack_pa")?, t.s("first_crack_phase")?, t.s("cracked_share_at_peak")?);
    let bound = lower_bounds(&t)?;
    let failed = t.s("failed_at_event")?;
    let caption = match (0..st.len()).find(|&i| st[i] == s && te[i] == test && re[i] == 0.0) {
        Some(i) => format!(
            "The {:.0} pixels cracked in the first realisation of {label} under {test}, coloured by the order they cracked in, over the phases in pale tones. The first crack, in {}, at |Σxx| = {:.1} MPa; {} {:.1} MPa, at crack {:.0} (the cracks so far by phase: {}).",
            events[i],
            phase_name(&phase[i]),
            first[i] / 1e6,
            if !bound[i] {
                "the strength".to_string()
            } else if failed[i].is_empty() {
                format!("the run stopped at its limit of {:.0} cracks before the cell gave way: its strength is at least", events[i])
            } else {
                format!("the solve failed at crack {}: the strength is at least", failed[i])
            },
            strength[i] / 1e6,
            peak[i] + 1.0,
            shares(&share[i])
        ),
        None => format!("The cracked pixels of the first realisation of {label} under {test}, coloured by the order they cracked in."),
    };
    Ok(FigureNote { title: Some(format!("Cracks in {label}, {test}")), caption: p(&caption), blocks: vec![] })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::TempDir;

    fn caption(n: &FigureNote) -> String {
        n.caption.iter().map(|s| s.text.as_str()).collect()
    }

    /// A structure key that ends in another's (`b`, `a_b`) is matched whole, and a run that used up
    /// its event limit gives its strength as a lower bound, one that stopped on its own as the
    /// strength.
    #[test]
    fn crack_captions_read_their_row() {
        let dir = TempDir::new("captions-micro").unwrap();
        let d = dir.path();
        std::fs::write(d.join("structures.csv"), "structure\nb\na_b\n").unwrap();
        std::fs::write(d.join("structure_summary.csv"), "structure,label\nb,Bee\na_b,Ay bee\n").unwrap();
        std::fs::write(
            d.join("failure_summary.csv"),
            "structure,realisation,test,strength_pa,peak_event,events,first_crack_pa,first_crack_phase,cracked_share_at_peak,stopped,failed_at_event\n\
             b,0,tension,3.0e7,0,59,3.0e7,fused_silica,alumina 0.250 fused_silica 0.750,load fell below stop_fraction of the strength,\n\
             a_b,0,tension,1.5e8,72,200,1.2e8,alumina,alumina 1.000 fused_silica 0.000,max_events,\n",
        )
        .unwrap();
        let b = caption(&figure(d, "cracks_tension_b").unwrap().unwrap());
        assert!(b.contains("59 pixels") && b.contains("first realisation of Bee") && b.contains("the strength 30.0 MPa, at crack 1"), "{b}");
        assert!(b.contains("alumina 25 %, fused silica 75 %"), "{b}");
        let ab = caption(&figure(d, "cracks_tension_a_b").unwrap().unwrap());
        assert!(ab.contains("Ay bee") && ab.contains("limit of 200 cracks") && ab.contains("at least 150.0 MPa, at crack 73"), "{ab}");
        assert!(figure(d, "cracks_tension_c").unwrap().is_none());
    }

    #[test]
    fn lengths_keep_their_digits() {
        assert_eq!(length(0.125), "0.125");
        assert_eq!(length(32.0), "32");
        assert_eq!(length(16.0), "16");
        assert_eq!(length(1.5), "1.5");
    }
}

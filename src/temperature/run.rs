//! Runs a `kind = "temperature"` study: the phase-fraction table, validated ([`crate::phases`]),
//! written as `phases.csv` (one row per temperature and phase: `temperature_c`, `phase`, the
//! basis column, `amorphous`) and `amorphous.csv` (the amorphous fraction per temperature),
//! drawn as `phase_fractions`, and described in `summary.md` (every number in it comes from the
//! table).

use std::collections::BTreeMap;

use super::study::TemperatureStudy;
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table};
use crate::phases::{PhaseTable, read_phases};
use crate::runkit::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::schema::StudyFile;

/// The summary's sentences about the phase table.
fn describe(s: &TemperatureStudy, t: &PhaseTable, shown_path: &str) -> (String, String) {
    let (lo, hi) = t.range();
    let fa = t.amorphous_fractions();
    let amorphous: Vec<&str> = t.phases.iter().zip(&t.amorphous).filter(|(_, a)| **a).map(|(n, _)| n.as_str()).collect();
    let basis = match t.basis {
        crate::phases::Basis::Mole => "mole",
        crate::phases::Basis::Mass => "mass",
    };
    let crystalline: Vec<String> = t.phases.iter().zip(&t.amorphous).enumerate().filter(|(_, (_, a))| !**a).map(|(p, (n, _))| format!("{n} {:.3}", t.fractions[0][p])).collect();
    let mut md = format!(
        "The phase table `{shown_path}` — {} — gives {} phases at {} temperatures from {lo} to {hi} °C as {basis} fractions. At {lo} °C: {}.",
        s.phases.composition,
        t.phases.len(),
        t.temperatures_c.len(),
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

/// Runs the study.
pub fn run_temperature(loaded: &StudyFile, s: &TemperatureStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let file = loaded.path.display().to_string();
    s.validate(&file)?;
    let path = loaded.resolve(&s.phases.file);
    if !path.is_file() {
        return Err(Error::config(&file, "phases.file", format!("{} does not exist", path.display())));
    }
    let pb = progress_bar(2, opts.progress, crate::runkit::PROGRESS_COUNT);
    pb.set_message("phase table");
    let phases = read_phases(&path)?;
    let inputs = vec![InputFile::hash(&loaded.path)?, InputFile::hash(&path)?];
    pb.inc(1);

    let mut dir = ReportDir::create(&opts.reports_root, &loaded.name)?;
    let rows: Vec<(usize, usize)> = (0..phases.temperatures_c.len()).flat_map(|i| (0..phases.phases.len()).map(move |p| (i, p))).collect();
    let mut t = table(vec![
        fcol("temperature_c", rows.iter().map(|&(i, _)| phases.temperatures_c[i]).collect()),
        scol("phase", rows.iter().map(|&(_, p)| phases.phases[p].clone()).collect()),
        fcol(phases.basis.column(), rows.iter().map(|&(i, p)| phases.fractions[i][p]).collect()),
        scol("amorphous", rows.iter().map(|&(_, p)| phases.amorphous[p].to_string()).collect()),
    ])?;
    dir.write_table("phases", &mut t)?;
    let mut t = table(vec![fcol("temperature_c", phases.temperatures_c.clone()), fcol("amorphous_fraction", phases.amorphous_fractions())])?;
    dir.write_table("amorphous", &mut t)?;
    let (text, headline) = describe(s, &phases, &s.phases.file.display().to_string());
    let md = format!(
        "# Temperature: {}\n\n## Phases\n\n{text}\n\nThe figure `phase_fractions` draws every phase against temperature (amorphous phases dashed), in the style of the deliverable's Fig. 2. Between the tabulated temperatures the fractions are interpolated linearly; nothing is extrapolated beyond them. What each dataset is (measured, computed, synthetic or illustrative) is stated in datasets/README.md.\n\nNot yet in this study: the temperature model of the material parameters and the lifetime at the operating temperature.\n",
        s.phases.composition
    );
    dir.write_bytes("summary.md", md.as_bytes())?;
    pb.set_message("figures");
    let mut failures = Vec::new();
    let rendered = crate::report::temperature::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    let mut evaluations = BTreeMap::new();
    evaluations.insert("phase_table_rows".to_string(), rows.len() as u64);
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines: vec![headline] })
}

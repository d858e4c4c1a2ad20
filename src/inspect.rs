//! What `partlife datasets check` says of a file: which kind of input it is, what was read
//! (format, columns, units and conversions, the material filter and joins, through
//! [`crate::intake`]), a one-line summary of its values, and any warning.
//!
//! The kind is recognised from the header: Table 1 (`size_um_min`), a phase-fraction table
//! (`phase`), observations (`output`, `unit`, `value`, `sd`), an impact spectrum
//! (`q<k>_v_normal_m_s`), force–displacement curves (a displacement column), a shape file
//! (an id and roundness or sphericity, no force), a strength file (a column named as a strength
//! or stating a stress unit, no force), else crush data. A crush file holding several
//! materials is summarised per material; a workbook sheet by sheet. A study's files are read as
//! the kind the study reads them as (a calibration's curve file whose German header names no
//! displacement, mapped by the study's `columns`, is still curves).
//!
//! Verified by `tests/intake.rs`.

use std::path::Path;

use crate::error::Result;
use crate::intake::{MapOrigin, Provenance, RawTable, SheetRef, Source, read_raw, resolve};

/// One checked table (a file, a sheet of a workbook, a material of a campaign file).
#[derive(Debug, Clone, PartialEq)]
pub struct Checked {
    /// What was checked: the file, with its sheet and material filter if any.
    pub what: String,
    /// The kind of input and a summary of its values.
    pub summary: String,
    /// How it was read (when the reader records it).
    pub read: Option<Provenance>,
}

impl Checked {
    /// The lines `datasets check` prints.
    pub fn lines(&self) -> Vec<String> {
        let mut out = vec![format!("{}: {}: ok", self.what, self.summary)];
        if let Some(p) = &self.read {
            out.push(format!("  read: {}", p.describe()));
        }
        out
    }
}

/// `lo–hi` as printed (scaled, `places` decimals), or the one value when both print alike.
fn span((lo, hi): (f64, f64), scale: f64, places: usize) -> String {
    let (a, b) = (format!("{:.*}", places, lo * scale), format!("{:.*}", places, hi * scale));
    if a == b { a } else { format!("{a}–{b}") }
}

/// The folded names a strength column goes by (the strength file's field).

/// The kind of table a header shows (module docs).
fn kind_of(t: &RawTable) -> &'static str {
    let has = |n: &str| t.column(n).is_some();
    let folded: Vec<String> = t.headers.iter().map(|h| crate::intake::units::fold(&crate::intake::units::parse_header(h).name)).collect();
    let any = |names: &[&str]| folded.iter().any(|f| names.contains(&f.as_str()));
    let strength = crate::strength::specimens::strength_names();
    if has("size_um_min") {
        "table1"
    } else if has("phase") {
        "phases"
    } else if has("output") && has("value") && has("sd") {
        "observations"
    } else if t.headers.iter().any(|h| h.starts_with('q') && h.ends_with("_v_normal_m_s")) {
        "spectrum"
    } else if any(&["displacement", "s", "delta", "travel", "deformation"]) {
        "curves"
    } else if any(&["roundness", "sphericity", "wadellroundness", "b/l"]) && !any(&["crushforce", "f", "fmax", "force", "load", "breakingforce", "peakforce", "crushingforce"]) {
        "shape"
    } else if !any(&["crushforce", "f", "fmax", "force", "load", "breakingforce", "peakforce", "crushingforce"]) && (strength.iter().any(|n| folded.contains(n)) || t.headers.iter().any(|h| crate::intake::units::parse_header(h).unit.is_some_and(|u| crate::intake::units::unit_of(crate::intake::Quantity::Stress, &u).is_some()))) {
        "strength"
    } else {
        "crush"
    }
}

/// Checks one file as `src` describes it (every sheet of a workbook when no sheet is named), as
/// the kind `kind` (`"curves"`, `"observations"`, …; None: the kind its header shows); a
/// mistake in the study's column or unit map is reported at `origin` (the study file and key).
/// A strength file is read with its study table's size, factor and origin columns (`set`).
pub fn check(src: &Source, kind: Option<&'static str>, origin: &MapOrigin, set: Option<&crate::strength::specimens::SetColumns>) -> Result<Vec<Checked>> {
    let path = src.file.as_path();
    if crate::intake::sheet::is_spreadsheet(path) && src.sheet.is_none() {
        let names = sheet_names(path)?;
        let mut out = Vec::new();
        for (k, _) in names.iter().enumerate() {
            let s = Source { sheet: Some(SheetRef::Index(k + 1)), ..src.clone() };
            out.extend(check_table(&s, kind, origin, set)?);
        }
        return Ok(out);
    }
    check_table(src, kind, origin, set)
}

/// The failure origins of the specimens that broke, with their counts, where the study names
/// the column (`; failure origins (`Bruchursprung`) of the breaks: Kante 3, Volumen 40`).
fn origins_of_breaks(o: crate::obs::Obs, origins: &[String], column: Option<&str>) -> String {
    let Some(col) = column else { return String::new() };
    let mut counts: std::collections::BTreeMap<&str, usize> = std::collections::BTreeMap::new();
    for i in (0..o.len()).filter(|&i| o.kind(i) != crate::obs::Censor::Right) {
        *counts.entry(origins[i].as_str()).or_default() += 1;
    }
    // What a study can do with a rare origin, said before the run refuses it.
    let rare = |n: usize| counts.iter().filter(|(_, v)| **v == n).map(|(k, _)| format!("\"{k}\"")).collect::<Vec<_>>();
    let mut caution = String::new();
    if let [one @ .., last] = &rare(1)[..] {
        let who = if one.is_empty() { last.clone() } else { format!("{} and {last}", one.join(", ")) };
        caution.push_str(&format!(" ({who} with one break: too few for a law of its own, which a study fitting each origin refuses)"));
    }
    if let [two @ .., last] = &rare(2)[..] {
        let who = if two.is_empty() { last.clone() } else { format!("{} and {last}", two.join(", ")) };
        caution.push_str(&format!(" ({who} with two breaks: a law of its own, but a main study weighing several strength models by cross-validation needs three)"));
    }
    format!("; failure origins (`{col}`) of the breaks: {}{caution}", counts.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", "))
}

fn sheet_names(path: &Path) -> Result<Vec<String>> {
    let bytes = crate::intake::read_bytes(path)?;
    crate::intake::sheet::sheet_names(path, bytes)
}

fn check_table(src: &Source, kind: Option<&'static str>, origin: &MapOrigin, set: Option<&crate::strength::specimens::SetColumns>) -> Result<Vec<Checked>> {
    let path = src.file.as_path();
    let t = read_raw(src)?;
    let mut sheets: Vec<&String> = t.row_sheets.iter().collect();
    sheets.dedup();
    let what = match &t.origin.sheet {
        _ if sheets.len() > 1 => format!("{} sheets {}", path.display(), sheets.iter().map(|s| format!("\"{s}\"")).collect::<Vec<_>>().join(", ")),
        Some(s) => format!("{} sheet \"{s}\"", path.display()),
        None => path.display().to_string(),
    };
    let one = |summary: String, read: Option<Provenance>| Ok(vec![Checked { what: what.clone(), summary, read }]);
    match kind.unwrap_or_else(|| kind_of(&t)) {
        "table1" => {
            let rows = crate::data::read_table1(path)?;
            one(format!("Table 1, {} rows ({})", rows.len(), t.format), None)
        }
        "phases" => {
            let (p, read) = crate::phases::read_phases_source(src)?;
            let fa = p.amorphous_fractions();
            let (lo, hi) = crate::stats::min_max(&fa);
            one(format!("phase fractions ({}), {} phases at {} temperatures ({}–{} °C), amorphous fraction {lo:.3}–{hi:.3}", p.basis.column(), p.phases.len(), p.temperatures_c.len(), p.range().0, p.range().1), Some(read))
        }
        "observations" => {
            let (rows, _) = crate::calibrate::data::read_observation_rows(path)?;
            let outputs: Vec<String> = rows.iter().map(|r| format!("{} [{}]", r.output, r.unit)).collect();
            one(format!("{} observations ({}): {}", rows.len(), t.format, outputs.join(", ")), None)
        }
        "spectrum" => {
            let c = t.require(&["target", "row"])?;
            let mut lines = Vec::new();
            for i in 0..t.rows.len() {
                let (target, row) = (t.need_text(i, c[0])?, t.need_number(i, c[1])?);
                let q = crate::dist::read_spectrum(path, &target, row as u32)?;
                lines.push(format!("{target} row {row}: median {:.2} m/s", q.iter().find(|x| x.0 >= 0.5).map_or(f64::NAN, |x| x.1)));
            }
            one(format!("impact spectrum ({}), {} rows: {}", t.format, t.rows.len(), lines.join("; ")), None)
        }
        "strength" => {
            let keys = set.cloned().unwrap_or_default();
            let s = crate::strength::specimens::read_specimens_with_origins(src, keys.size.as_ref(), &keys.factors, keys.origin.as_deref(), origin)?;
            let o = s.sample.strength.view();
            // A class's upper end counts for the range.
            let (lo, hi) = crate::stats::min_max(&(0..o.len()).flat_map(|i| [o.x[i], o.upper(i)]).filter(|v| v.is_finite()).collect::<Vec<_>>());
            let n = if o.complete() { format!("{} specimen{}", o.len(), if o.len() == 1 { "" } else { "s" }) } else { o.tally().describe("specimens") };
            let origins = origins_of_breaks(o, &s.origins, keys.origin.as_deref());
            one(format!("strength data, {n}, strength = {} MPa{origins}", span((lo, hi), 1e-6, 1)), Some(s.provenance))
        }
        "curves" => {
            let (curves, read) = crate::calibrate::data::curves_of(&t, path, &src.columns, &src.units, origin, src.temperature_c)?;
            let d = span(crate::stats::min_max(&curves.iter().map(|c| c.diameter).collect::<Vec<_>>()), 1e6, 0);
            one(format!("crush curves, {} particles, d = {d} µm, {} samples", curves.len(), t.rows.len()), Some(read))
        }
        "shape" => {
            let r = resolve(&t, &crate::data::SHAPE_FIELDS, &src.columns, &src.units, origin)?;
            for row in 0..t.rows.len() {
                r.need_text("id", row)?;
                for k in ["roundness", "sphericity", "temperature", "impacts"] {
                    r.number(k, row)?;
                }
            }
            one(format!("shape data of {} particles, to be joined by id to crush data (data = {{ …, shape = {{ file = \"…\" }} }})", t.rows.len()), Some(r.provenance.clone()))
        }
        _ => {
            // A campaign file with several materials is checked material by material.
            let ((fields, columns, units), _) = crate::intake::observed::fields_for(&t, &crate::data::CRUSH_FIELDS, "crush_force", crate::data::CRUSH_FORCE_ENDS, src, origin)?;
            let r = resolve(&t, &fields, &columns, &units, origin)?;
            let mut materials: Vec<String> = Vec::new();
            if src.material.is_none() && r.has("material") {
                for row in 0..t.rows.len() {
                    if let Some(m) = r.text("material", row)
                        && !materials.contains(&m)
                    {
                        materials.push(m);
                    }
                }
            }
            if materials.len() < 2 {
                materials = vec![src.material.clone().unwrap_or_default()];
            }
            let mut out = Vec::new();
            for m in materials {
                let s = Source { material: (!m.is_empty()).then_some(m.clone()), ..src.clone() };
                let keys = set.cloned().unwrap_or_default();
                let d = crate::data::read_crush_with_factors(&s, &keys.factors, keys.origin.as_deref(), origin)?;
                let forces = d.observed();
                let origins = origins_of_breaks(forces.view(), &d.origins, keys.origin.as_deref());
                let (dia, force) = (span(crate::stats::min_max(&d.diameters()), 1e6, 0), span(crate::stats::min_max(&d.forces()), 1.0, 1));
                let label = if d.material().is_empty() { "no material column".to_string() } else { format!("material \"{}\"", d.material()) };
                out.push(Checked {
                    what: if s.material.is_some() && src.material.is_none() { format!("{what} [{m}]") } else { what.clone() },
                    summary: match &d.censoring {
                        None => format!("crush data, {label}, {} particle{}, d = {dia} µm, F = {force} N{origins}", d.records.len(), if d.records.len() == 1 { "" } else { "s" }),
                        Some(_) => format!("crush data, {label}, {}, d = {dia} µm, F = {force} N{origins}", forces.view().tally().describe("particles")),
                    },
                    read: Some(d.provenance),
                });
            }
            Ok(out)
        }
    }
}

//! The data intake: every tabular input file — crush tests, force–displacement curves,
//! observations, impact spectra, phase tables, Table 1 — is read through this one pipeline of
//! plain steps, each of which records what it decided:
//!
//! ```text
//! bytes ─► text (encoding: UTF-8, BOM, UTF-16, Windows-1252)          text::decode
//!       ─► table (delimiter, decimal mark, header row; or one sheet)  table::read_delimited, sheet::read_sheet
//!       ─► columns resolved to fields (study map, then name + unit)    columns::resolve
//!       ─► SI values (exact decimal conversion)                       decimal, units
//!       ─► plausibility (in SI, with "did you mean …?")                columns::Plausible
//!       ─► typed records + Provenance (manifest, `datasets check`)
//! ```
//!
//! A reader declares the fields it needs ([`Field`]) and reads their cells through
//! [`Resolved`]; it never parses a file itself. Rows are picked by a material filter
//! ([`select`]) and a second file is joined by particle id ([`join`]) here too, so every reader
//! that needs them gets the same rules and messages.
//!
//! Bad input gets one message naming the file, the sheet, the row (with its physical line or
//! sheet row), the column and the rule, and is bad input (exit 2).
//!
//! Verified by the unit tests of each step and `tests/intake.rs` (lab exports, spreadsheets,
//! every refusal, the round trip of the shipped data through the example exports).

pub mod columns;
pub mod decimal;
pub mod factors;
pub mod observed;
pub mod origins;
pub mod undeclared;
pub mod sheet;
pub mod table;
pub mod text;
pub mod units;
pub mod write;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use columns::{ColumnRecord, Field, Kind, MapOrigin, Plausible, Provenance, Resolved, resolve};
pub use sheet::SheetRef;
pub use table::{Cell, RawTable};
pub use text::{DecimalMark, Delimiter};
pub use units::Quantity;

use crate::error::{Error, Result};

/// A data file and how to read it, where the file does not say it itself. In a study, `data`
/// is either the file's path (`data = "crush.csv"`) or this table (`data = { file = "…",
/// sheet = "BL", units = { diameter = "mm" } }`); every key but `file` is optional.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Source {
    /// The file (relative to the study file in a study).
    pub file: PathBuf,
    /// The sheet of a spreadsheet: its name, or its position from 1 (default: the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sheet: Option<SheetRef>,
    /// The line (text) or sheet row (spreadsheet) of the header, from 1 (default: the first line;
    /// a sheet's first row that holds anything).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub header_row: Option<usize>,
    /// The delimiter of a text file: `","`, `";"` or `"tab"` (default: detected).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delimiter: Option<Delimiter>,
    /// The decimal mark of a text file: `"point"` or `"comma"` (default: detected).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decimal: Option<DecimalMark>,
    /// Fields mapped to columns by header, when a header does not explain itself
    /// (`{ diameter = "Dp", crush_force = "Last" }`); wins over names.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub columns: BTreeMap<String, String>,
    /// Units of fields whose header states none (`{ diameter = "mm", crush_force = "kgf" }`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub units: BTreeMap<String, String>,
    /// The rows to use in a file holding several materials: those whose `material` column
    /// holds this (default: every row, and a file with several materials is refused).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// A second file joined to this one by particle id (a shape analyser's export with
    /// roundness and sphericity), read with the same keys.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<Box<Source>>,
    /// In `shape` only: what to do with ids present in one file only (`"exact"`, the default,
    /// refuses them; `"inner"` keeps the common ids and lists the others in the manifest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub join: Option<JoinMode>,
    /// The column saying whether each specimen broke (crush and strength files;
    /// [`observed`]): `broken = { column = "gebrochen", yes = "ja", no = "nein" }`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub broken: Option<observed::Broken>,
    /// The column counting the specimens each row stands for (`count = "Anzahl"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<String>,
    /// Classes instead of values: `interval = { lower = "von [MPa]", upper = "bis [MPa]" }`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval: Option<observed::Interval>,
    /// What the rows at the file's highest value are, where no column says it
    /// (`"not_broken"`: the rig's limit; `"broken"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at_highest: Option<observed::AtHighest>,
    /// Columns that say nothing of the strength, looked at and left out on purpose.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ignore: Vec<String>,
    /// The test temperature (°C) of the rows whose file gives none (no temperature column, or
    /// an empty cell): every crush and strength row must have one ([`observed::test_temperatures`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temperature_c: Option<f64>,
}

impl Source {
    /// A file read with every default.
    pub fn file(path: impl Into<PathBuf>) -> Source {
        Source { file: path.into(), ..Source::default() }
    }

    /// The same source with its files resolved relative to the study file `study`.
    pub fn resolved(&self, study: &Path) -> Source {
        let mut s = self.clone();
        s.file = resolve_relative(study, &self.file);
        if let Some(j) = &self.shape {
            s.shape = Some(Box::new(j.resolved(study)));
        }
        s
    }

    /// Every file it names (the data file, then the shape file).
    pub fn files(&self) -> Vec<PathBuf> {
        std::iter::once(self.file.clone()).chain(self.shape.iter().map(|j| j.file.clone())).collect()
    }

    /// Checks what can be checked without the file: rows and sheets numbered from 1, every
    /// unit known for some quantity, `join` only in `shape`, no shape of a shape. `file` and
    /// `key` name the study table holding it (`material[0].data`).
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        self.validate_at(file, key, false)
    }

    fn validate_at(&self, file: &str, key: &str, nested: bool) -> Result<()> {
        if self.file.as_os_str().is_empty() {
            return Err(Error::config(file, format!("{key}.file"), "the data file's path is empty"));
        }
        if self.header_row == Some(0) {
            return Err(Error::config(file, format!("{key}.header_row"), "rows are numbered from 1"));
        }
        if self.sheet == Some(SheetRef::Index(0)) || matches!(&self.sheet, Some(SheetRef::Several(l)) if l.contains(&SheetRef::Index(0))) {
            return Err(Error::config(file, format!("{key}.sheet"), "sheets are numbered from 1"));
        }
        for (k, u) in &self.units {
            if units::lookup(u).is_empty() {
                let mut all: Vec<&str> = units::UNITS.iter().map(|u| u.symbol).filter(|s| *s != "-").collect();
                all.dedup();
                return Err(Error::config(file, format!("{key}.units.{k}"), format!("unknown unit \"{u}\" (known: {})", all.join(", "))));
            }
        }
        if !nested && self.join.is_some() {
            return Err(Error::config(file, format!("{key}.join"), "join says how a shape file is joined: put it in `shape = { …, join = \"inner\" }`"));
        }
        if let Some(j) = &self.shape {
            if nested {
                return Err(Error::config(file, format!("{key}.shape"), "a shape file cannot have a shape file of its own"));
            }
            j.validate_at(file, &format!("{key}.shape"), true)?;
        }
        if nested {
            return self.refuse_rows(file, key, "a shape file");
        }
        self.validate_rows(file, key)
    }
}

impl<'de> Deserialize<'de> for DataRef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = DataRef;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a file path, or a table { file = \"…\", sheet = …, columns = { … }, units = { … }, … }")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<DataRef, E> {
                Ok(DataRef(Source::file(v)))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> std::result::Result<DataRef, A::Error> {
                Source::deserialize(serde::de::value::MapAccessDeserializer::new(map)).map(DataRef)
            }
        }
        d.deserialize_any(V)
    }
}

/// A study's `data` key: a path, or a [`Source`] table (written back as a path when it is only
/// one).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DataRef(pub Source);

impl Serialize for DataRef {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        if self.0 == Source::file(self.0.file.clone()) { self.0.file.serialize(s) } else { self.0.serialize(s) }
    }
}

impl std::ops::Deref for DataRef {
    type Target = Source;
    fn deref(&self) -> &Source {
        &self.0
    }
}

/// Resolves `p` relative to the directory of the file `study` (lexically:
/// `studies/../datasets/x.csv` becomes `datasets/x.csv`); absolute paths stay.
pub fn resolve_relative(study: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        return p.to_path_buf();
    }
    let joined = study.parent().unwrap_or(Path::new(".")).join(p);
    let mut out = PathBuf::new();
    for c in joined.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir if matches!(out.components().next_back(), Some(std::path::Component::Normal(_))) => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// Whether a data file is a synthetic stand-in, and by what: the label travels with the data,
/// in the directory that holds them, never in a sentence. A file is labelled synthetic when
///
/// * a generator's settings beside it (`synth*.toml`) name it as an output (`file = "…"`, at
///   any depth): "generated by partlife's generator from `<settings>` (seed N)"; or
/// * an export manifest beside it (`exports.toml`, `[[export]] file = "…", from = […]`) names
///   it, and every file it was exported from is itself labelled synthetic.
///
/// Any other file — a user's own — has no label (None), and a report says nothing about it
/// being synthetic.
pub fn synthetic_label(path: &Path) -> Option<String> {
    synthetic_label_at(path, 0)
}

/// The summary's sentence on which materials' data (`(label, data file)`, one per material) are
/// synthetic stand-ins, from their labels ([`synthetic_label`]); empty when none is.
pub fn synthetic_sentence(what: &str, materials: &[(&str, &Path)]) -> String {
    let labelled: Vec<(&str, String)> = materials.iter().filter_map(|(m, p)| synthetic_label(p).map(|l| (*m, l))).collect();
    if labelled.is_empty() {
        return String::new();
    }
    let mut why: Vec<String> = labelled.iter().map(|(_, l)| l.clone()).collect();
    why.dedup();
    let whose = if labelled.len() == materials.len() { format!("The {what} are") } else { format!("The {what} of {} are", labelled.iter().map(|(m, _)| *m).collect::<Vec<_>>().join(" and ")) };
    format!(" **{whose} synthetic stand-ins** ({}; datasets/README.md).", why.join("; "))
}

fn synthetic_label_at(path: &Path, depth: usize) -> Option<String> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name()?.to_str()?;
    let read = |p: &Path| std::fs::read_to_string(p).ok().and_then(|t| t.parse::<toml::Table>().ok());
    fn names(v: &toml::Value, name: &str) -> bool {
        match v {
            toml::Value::Table(t) => t.get("file").and_then(|f| f.as_str()) == Some(name) || t.values().any(|v| names(v, name)),
            toml::Value::Array(a) => a.iter().any(|v| names(v, name)),
            _ => false,
        }
    }
    let mut settings: Vec<PathBuf> = std::fs::read_dir(dir).ok()?.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "toml") && p.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with("synth"))).collect();
    settings.sort();
    for s in settings {
        if let Some(t) = read(&s)
            && names(&toml::Value::Table(t.clone()), name)
        {
            let seed = t.get("seed").and_then(|v| v.as_integer()).map_or(String::new(), |v| format!(" (seed {v})"));
            return Some(format!("generated by partlife's generator from {}{seed}", s.display()));
        }
    }
    // Exports of synthetic files (a bounded depth: a manifest naming itself is not followed).
    let manifest = read(&dir.join("exports.toml"))?;
    let export = manifest.get("export")?.as_array()?.iter().find(|e| e.get("file").and_then(|f| f.as_str()) == Some(name))?;
    let from: Vec<PathBuf> = export.get("from")?.as_array()?.iter().filter_map(|f| f.as_str().map(|f| resolve_relative(&dir.join("exports.toml"), Path::new(f)))).collect();
    if from.is_empty() || depth > 4 {
        return None;
    }
    let labels: Option<Vec<String>> = from.iter().map(|f| synthetic_label_at(f, depth + 1)).collect();
    labels.map(|_| format!("exported from {}, themselves synthetic ({})", from.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join(" and "), dir.join("exports.toml").display()))
}

/// The bytes of an input file; a missing path, a directory or an unreadable file are named as
/// such.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    let why = |what: &str| Error::read(path, std::io::Error::other(what.to_string()));
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(why("no such file")),
        Err(e) => return Err(Error::read(path, e)),
        Ok(m) if m.is_dir() => return Err(why("is a directory, not a file")),
        Ok(m) if !m.is_file() => return Err(why("is not a regular file")),
        Ok(_) => {}
    }
    std::fs::read(path).map_err(|e| Error::read(path, e))
}

/// Reads a file as a raw table: a spreadsheet by its extension (.xlsx, .xlsm, .xls, .xlsb,
/// .ods), anything else as delimited text.
pub fn read_raw(opts: &Source) -> Result<RawTable> {
    let path = opts.file.as_path();
    let bytes = read_bytes(path)?;
    if sheet::is_spreadsheet(path) {
        return sheet::read_sheet(path, bytes, opts);
    }
    if bytes.starts_with(b"PK\x03\x04") {
        return Err(Error::data_file(path, "file", "is a zip archive (a spreadsheet?), not text: give it its spreadsheet extension (.xlsx or .ods) to read it as one"));
    }
    if opts.sheet.is_some() {
        return Err(Error::data_file(path, "file", "`sheet` is given, but this is a text file, not a spreadsheet"));
    }
    table::read_delimited(path, &bytes, opts)
}

/// The rows whose text field `key` equals `wanted` (a material filter), with its record line.
/// Without `wanted`, every row — unless the column holds several values, which is refused with
/// the list of values found (a campaign file must be filtered, never mixed).
pub fn select(r: &Resolved, key: &str, wanted: Option<&str>, origin: &MapOrigin, option: &str) -> Result<(Vec<usize>, Option<String>)> {
    let n = r.table.rows.len();
    if !r.has(key) {
        return match wanted {
            None => Ok(((0..n).collect(), None)),
            Some(w) => Err(Error::config(&origin.file, format!("{}.{option}", origin.key), format!("picks the rows of {key} \"{w}\", but {} has no {key} column (its columns: {}); if one of them names the {key}, map it: {}.columns = {{ {key} = \"…\" }}", r.table.origin.path.display(), r.table.headers.iter().map(|h| format!("`{h}`")).collect::<Vec<_>>().join(", "), origin.key))),
        };
    }
    let mut values: Vec<(String, usize)> = Vec::new();
    for row in 0..n {
        let v = r.need_text(key, row)?;
        match values.iter_mut().find(|(x, _)| *x == v) {
            Some(e) => e.1 += 1,
            None => values.push((v, 1)),
        }
    }
    let listed = || values.iter().map(|(v, k)| format!("\"{v}\" ({k} rows)")).collect::<Vec<_>>().join(", ");
    match wanted {
        None if values.len() > 1 => Err(r.table.header_error(
            r.column(key),
            format!("the file holds {} {key}s: {}; pick one in the study ({option} = \"{}\")", values.len(), listed(), values[0].0),
        )),
        None => Ok(((0..n).collect(), None)),
        Some(w) => {
            let rows: Vec<usize> = (0..n).filter(|&row| r.text(key, row).as_deref() == Some(w)).collect();
            if rows.is_empty() {
                return Err(Error::config(&origin.file, format!("{}.{option}", origin.key), format!("no row of {} has {key} \"{w}\" (found: {})", r.table.origin.path.display(), listed())));
            }
            Ok((rows.clone(), Some(format!("{option} = \"{w}\": {} of {n} rows", rows.len()))))
        }
    }
}

/// How two files joined by id treat ids present in one of them only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JoinMode {
    /// Both files must hold the same ids (default): any id in one file only is refused.
    #[default]
    Exact,
    /// Keep the ids both files hold; the others are listed in the manifest.
    Inner,
}

/// The join of a main file's rows (`main`, with their ids) to a second file's rows by id:
/// for each kept main row, the second file's row; and the ids dropped (inner join). Duplicated
/// ids in the second file are refused naming both rows; ids in one file only are refused in
/// [`JoinMode::Exact`], listed all at once.
pub fn join(main: &[(usize, String)], second: &Resolved, id_key: &str, rows: &[usize], mode: JoinMode, main_file: &str) -> Result<(Vec<(usize, usize)>, Vec<String>)> {
    let mut by_id: HashMap<String, usize> = HashMap::new();
    for &row in rows {
        let id = second.need_text(id_key, row)?;
        if let Some(&first) = by_id.get(&id) {
            return Err(second.error(row, id_key, format!("duplicate id \"{id}\" (also on {}): a join by id needs each id once", second.table.place(first, None))));
        }
        by_id.insert(id, row);
    }
    let in_main: std::collections::HashSet<&str> = main.iter().map(|(_, id)| id.as_str()).collect();
    let only_main: Vec<&str> = main.iter().map(|(_, id)| id.as_str()).filter(|id| !by_id.contains_key(*id)).collect();
    let only_second: Vec<&str> = rows.iter().filter_map(|&row| second.text(id_key, row)).filter(|id| !in_main.contains(id.as_str())).map(|id| by_id.get_key_value(&id).map(|(k, _)| k.as_str()).unwrap_or("")).collect();
    if mode == JoinMode::Exact && (!only_main.is_empty() || !only_second.is_empty()) {
        let list = |ids: &[&str]| {
            let shown: Vec<String> = ids.iter().take(10).map(|s| format!("\"{s}\"")).collect();
            format!("{}{}", shown.join(", "), if ids.len() > 10 { format!(" and {} more", ids.len() - 10) } else { String::new() })
        };
        let mut parts = Vec::new();
        if !only_main.is_empty() {
            parts.push(format!("{} ids of {main_file} are not in it: {}", only_main.len(), list(&only_main)));
        }
        if !only_second.is_empty() {
            parts.push(format!("{} of its ids are not in {main_file}: {}", only_second.len(), list(&only_second)));
        }
        return Err(Error::data_file(
            &second.table.origin.path,
            second.table.origin.sheet.as_ref().map(|s| format!("sheet \"{s}\", column {}", second.table.headers[second.column(id_key).unwrap_or(0)])).unwrap_or_else(|| format!("column {}", second.table.headers[second.column(id_key).unwrap_or(0)])),
            format!("the join by id does not match: {}; fix the ids, or keep the common ones with join = \"inner\"", parts.join("; ")),
        ));
    }
    let pairs: Vec<(usize, usize)> = main.iter().filter_map(|(row, id)| by_id.get(id).map(|&s| (*row, s))).collect();
    let mut dropped: Vec<String> = only_main.iter().chain(&only_second).map(|s| s.to_string()).collect();
    dropped.sort();
    Ok((pairs, dropped))
}

/// Prints a warning of the intake on stderr, once per process (a study may read a file several
/// times); the warning also stays in the file's [`Provenance`], and so in the manifest.
pub fn warn(message: &str) {
    static SEEN: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    let Ok(mut seen) = SEEN.lock() else { return };
    if !seen.iter().any(|m| m == message) {
        seen.push(message.to_string());
        eprintln!("warning: {message}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_synthetic_label_comes_from_the_generator_or_the_export_manifest() {
        let dir = crate::io::TempDir::new("label").unwrap();
        let d = dir.path();
        std::fs::write(d.join("synth_x.toml"), "seed = 7\n[[material]]\nfile = \"a.csv\"\n").unwrap();
        std::fs::create_dir_all(d.join("ex")).unwrap();
        std::fs::write(d.join("ex/exports.toml"), "[[export]]\nfile = \"b.csv\"\nfrom = [\"../a.csv\"]\n[[export]]\nfile = \"c.csv\"\nfrom = [\"../a.csv\", \"../mine.csv\"]\n").unwrap();
        let a = synthetic_label(&d.join("a.csv")).unwrap();
        assert!(a.contains("synth_x.toml") && a.contains("(seed 7)"), "{a}");
        assert!(synthetic_label(&d.join("ex/b.csv")).unwrap().contains("exported from"));
        // A user's own file, and an export of one, carry no label.
        assert_eq!(synthetic_label(&d.join("mine.csv")), None);
        assert_eq!(synthetic_label(&d.join("ex/c.csv")), None);
        // The sentence: every material, some, none.
        let (a, mine) = (d.join("a.csv"), d.join("mine.csv"));
        assert!(synthetic_sentence("crush data", &[("A", &a), ("B", &a)]).starts_with(" **The crush data are synthetic stand-ins** (generated"));
        assert!(synthetic_sentence("crush data", &[("A", &a), ("Mine", &mine)]).starts_with(" **The crush data of A are synthetic stand-ins**"));
        assert_eq!(synthetic_sentence("crush data", &[("Mine", &mine)]), "");
    }
}

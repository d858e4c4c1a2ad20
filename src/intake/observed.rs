//! What a file says about its own rows: which specimens did not break, how many specimens a
//! row counts, strength classes. The study declares each in the file's `data` table; a column
//! that looks like one of them and is not declared is refused with the key to declare — never
//! guessed, never passed over.
//!
//! ```toml
//! data = { file = "Bruchversuche.xlsx", broken = { column = "gebrochen", yes = "ja", no = "nein" } }
//! data = { file = "classes.csv", interval = { lower = "von [MPa]", upper = "bis [MPa]" }, count = "Anzahl" }
//! data = { file = "rig.csv", at_highest = "not_broken" }   # rows at the file's highest value did not break
//! data = { file = "rig.csv", ignore = ["Prüfer"] }          # a column that says nothing of strength
//! ```
//!
//! * `broken`: a column saying whether each specimen broke. `yes` (broke at the row's value),
//!   `no` (did not break by it: the value is the highest load reached, right-censored) and
//!   optionally `below` (broke at or below it, left-censored: during set-up, under the preload).
//!   Cells are compared trimmed and without case; any other value is refused with its row.
//! * `interval`: two columns holding each row's class, in the value's quantity with their own
//!   units (`von [MPa]`, or `unit = "MPa"` in the table). Both ends: broke in the class; equal
//!   ends: broke at that value; only the lower end: did not break by it; only the upper end:
//!   broke at or below it (the convention of surpyval's `xl, xr`). The value column is not read.
//! * `count`: a column of whole numbers, the specimens each row stands for; a row counting k is
//!   k specimens (a row counting 0 is dropped, and listed).
//! * `at_highest`: what the rows holding the file's highest value are, when no column says it:
//!   `"not_broken"` (a rig's limit: right-censored there) or `"broken"` (they broke at it).
//! * `ignore`: columns the study has looked at and that say nothing of the strength.
//! * `temperature_c`: the test temperature (°C) of rows whose file gives none — no temperature
//!   column (`temperature_c`, `T [°C]`, `temp` …) or an empty cell. Every row of a crush or
//!   strength file has a test temperature: a file that gives none, and whose study gives none,
//!   is refused with the key to declare ([`test_temperatures`]). A strength measured at 20 °C is
//!   not a strength at 800 °C, and a comparison must be able to say which it is.
//!
//! Refused unless declared ([`super::undeclared::check_unused`], [`pile_up`]): an unused column of yes/no values
//! (`ja`/`nein`, `yes`/`no`, `true`/`false`, `broken`/`intact` …; a 0/1 column whose header
//! names an outcome), an unused column of whole numbers whose header names a count (`count`,
//! `n`, `Anzahl`, `frequency` …), and a pile-up of rows at the file's highest value (at least
//! [`PILE_UP_ROWS`] rows and [`PILE_UP_SHARE`] of the file) — what a rig's limit leaves —
//! and an unused column of failure origins (a header such as `origin`, `failure_mode`,
//! `Bruchursprung`, or values that are all origin words: `volume`, `surface`, `Oberfläche`,
//! `Kante` …), which the discrepancy study reads by the material's `origin` key.
//!
//! Verified by the unit tests below and `tests/censoring.rs`.

use serde::{Deserialize, Serialize};

use super::{ColumnRecord, MapOrigin, Provenance, RawTable, Resolved, Source};
use crate::error::{Error, Result};
use crate::obs::Censor;

/// `broken = { column = "gebrochen", yes = "ja", no = "nein" }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Broken {
    /// The column, as in the header.
    pub column: String,
    /// Its value for a specimen that broke at the row's value.
    pub yes: String,
    /// Its value for a specimen that did not break by the row's value.
    pub no: String,
    /// Its value for a specimen that broke at or below the row's value (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub below: Option<String>,
}

/// `interval = { lower = "von [MPa]", upper = "bis [MPa]" }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Interval {
    /// The column of each class's lower end.
    pub lower: String,
    /// The column of each class's upper end.
    pub upper: String,
    /// Their unit, where the headers state none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<String>,
}

/// What the rows at the file's highest value are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AtHighest {
    /// They did not break by it (the rig's limit).
    NotBroken,
    /// They broke at it.
    Broken,
}

/// Rows at the highest value that make a pile-up: at least this many …
pub const PILE_UP_ROWS: usize = 3;
/// … and at least this share of the file's rows.
pub const PILE_UP_SHARE: f64 = 0.05;

/// One row as read: what it says, its value and an interval's upper value (SI; NaN for the
/// others), and the specimens it counts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowValue {
    /// What the row says.
    pub kind: Censor,
    /// The value: the strength or force at break, the limit, an interval's lower end.
    pub value: f64,
    /// An interval's upper end (NaN for the other kinds).
    pub upper: f64,
    /// Specimens the row counts.
    pub count: usize,
}

/// The keys of the value's interval ends in a reader's fields (`crush_force_lower`,
/// `crush_force_upper`), when the study declares `interval`.
#[derive(Debug, Clone, Copy)]
pub struct Ends {
    /// Field key of the lower end.
    pub lower: &'static str,
    /// Field key of the upper end.
    pub upper: &'static str,
}

/// What a reader resolves when the study may declare `interval`: its fields (with `value`
/// replaced by the interval's ends `ends`, fields built like `value`'s), and the study's column
/// and unit maps with the ends mapped to the declared columns (their exact headers).
pub type Resolution = (Vec<super::Field>, std::collections::BTreeMap<String, String>, std::collections::BTreeMap<String, String>);

/// The fields and maps to resolve (see [`Resolution`]); without `interval`, the reader's own.
pub fn fields_for(table: &RawTable, fields: &[super::Field], value: &str, ends: (super::Field, super::Field), src: &Source, origin: &MapOrigin) -> Result<(Resolution, Option<Ends>)> {
    let Some(iv) = &src.interval else { return Ok(((fields.to_vec(), src.columns.clone(), src.units.clone()), None)) };
    let key = prefix(origin);
    if src.columns.contains_key(value) {
        return Err(Error::config(&origin.file, format!("{key}columns.{value}"), format!("with `interval` the {value} is read from the class's two columns: remove this mapping")));
    }
    let (lower, upper) = ends;
    let mut out: Vec<super::Field> = fields.iter().filter(|f| f.key != value).copied().collect();
    out.push(lower);
    out.push(upper);
    let mut columns = src.columns.clone();
    let lc = column_of(table, &iv.lower, origin, "interval.lower")?;
    let uc = column_of(table, &iv.upper, origin, "interval.upper")?;
    if lc == uc {
        return Err(Error::config(&origin.file, format!("{key}interval.upper"), "the lower and upper ends must be two columns"));
    }
    columns.insert(lower.key.to_string(), table.headers[lc].clone());
    columns.insert(upper.key.to_string(), table.headers[uc].clone());
    let mut units = src.units.clone();
    let unit = iv.unit.clone().or_else(|| units.remove(value));
    if let Some(u) = unit {
        for e in [lower.key, upper.key] {
            let header = super::units::parse_header(&table.headers[if e == lower.key { lc } else { uc }]);
            if header.unit.is_none() {
                units.insert(e.to_string(), u.clone());
            }
        }
    }
    Ok(((out, columns, units), Some(Ends { lower: lower.key, upper: upper.key })))
}

impl Source {
    /// Whether the study declares anything about the rows (`broken`, `count`, `interval`,
    /// `at_highest`, `ignore`).
    pub fn declares_rows(&self) -> bool {
        self.broken.is_some() || self.count.is_some() || self.interval.is_some() || self.at_highest.is_some() || !self.ignore.is_empty()
    }

    /// Refuses what a reader of another kind of table cannot use (`what`: "a shape file").
    pub fn refuse_rows(&self, file: &str, key: &str, what: &str) -> Result<()> {
        let declared = [
            ("broken", self.broken.is_some()),
            ("count", self.count.is_some()),
            ("interval", self.interval.is_some()),
            ("at_highest", self.at_highest.is_some()),
            ("ignore", !self.ignore.is_empty()),
            ("temperature_c", self.temperature_c.is_some()),
        ];
        match declared.iter().find(|(_, d)| *d) {
            Some((k, _)) => Err(Error::config(file, format!("{key}.{k}"), format!("{what} has no strength or force at break: `{k}` belongs to a crush or strength file's `data`"))),
            None => Ok(()),
        }
    }

    /// Checks the row declarations without the file: `broken`'s values distinct and non-empty,
    /// `broken` and `interval` not both, `at_highest` only with neither.
    pub fn validate_rows(&self, file: &str, key: &str) -> Result<()> {
        if let Some(b) = &self.broken {
            let values: Vec<&str> = [Some(b.yes.as_str()), Some(b.no.as_str()), b.below.as_deref()].into_iter().flatten().collect();
            if values.iter().any(|v| v.trim().is_empty()) {
                return Err(Error::config(file, format!("{key}.broken"), "`yes`, `no` (and `below`) must not be empty"));
            }
            let folded: Vec<String> = values.iter().map(|v| v.trim().to_lowercase()).collect();
            if (1..folded.len()).any(|i| folded[..i].contains(&folded[i])) {
                return Err(Error::config(file, format!("{key}.broken"), format!("`yes`, `no` and `below` must differ (got {})", values.iter().map(|v| format!("\"{v}\"")).collect::<Vec<_>>().join(", "))));
            }
            if self.interval.is_some() {
                return Err(Error::config(file, format!("{key}.broken"), "declare `broken` or `interval`, not both: a class with an empty upper end already says the specimen did not break by its lower end"));
            }
        }
        if let Some(t) = self.temperature_c
            && !TEMPERATURE.contains(t)
        {
            return Err(Error::config(file, format!("{key}.temperature_c"), format!("a test temperature must lie in {} ({}; got {t})", TEMPERATURE.shown, TEMPERATURE.why)));
        }
        if self.at_highest.is_some() && (self.broken.is_some() || self.interval.is_some()) {
            return Err(Error::config(file, format!("{key}.at_highest"), "the rows already say whether they broke (`broken` or `interval`): `at_highest` is for files that do not"));
        }
        if let Some(u) = self.interval.as_ref().and_then(|i| i.unit.as_ref())
            && super::units::lookup(u).is_empty()
        {
            return Err(Error::config(file, format!("{key}.interval.unit"), format!("unknown unit \"{u}\"")));
        }
        Ok(())
    }
}

/// The column named `name` (the header as written, or the header without its unit), or an
/// error naming the study key.
fn column_of(table: &RawTable, name: &str, origin: &MapOrigin, key: &str) -> Result<usize> {
    super::factors::find_column(&table.headers, name).ok_or_else(|| {
        let all = table.headers.iter().map(|h| format!("`{h}`")).collect::<Vec<_>>().join(", ");
        Error::config(&origin.file, format!("{}{key}", prefix(origin)), format!("{} has no column `{name}` (its columns: {all})", table.origin.path.display()))
    })
}

/// `material[0].data.` for a study's data table, empty for a file outside a study.
pub(super) fn prefix(origin: &MapOrigin) -> String {
    if origin.key.is_empty() { String::new() } else { format!("{}.", origin.key) }
}

/// Reads what each row of `rows` says (module docs): its kind and value from the value field
/// `value` (or the interval ends `ends`, when the study declares `interval`), the `broken`
/// column, the `count` column; then `at_highest`. Records the columns it used in `provenance`
/// and takes them off the unused ones.
pub fn read_rows(r: &Resolved, rows: &[usize], value: &str, ends: Option<Ends>, src: &Source, origin: &MapOrigin, provenance: &mut Provenance) -> Result<Vec<RowValue>> {
    let table = r.table;
    let broken = match &src.broken {
        Some(b) => Some((b, column_of(table, &b.column, origin, "broken.column")?)),
        None => None,
    };
    let count = match &src.count {
        Some(c) => Some(column_of(table, c, origin, "count")?),
        None => None,
    };
    let used: Vec<usize> = provenance.columns.iter().filter_map(|c| table.headers.iter().position(|h| *h == c.source)).collect();
    for (c, k) in broken.iter().map(|(_, c)| (*c, "broken.column")).chain(count.map(|c| (c, "count"))) {
        if used.contains(&c) {
            return Err(Error::config(&origin.file, format!("{}{k}", prefix(origin)), format!("`{}` is the column read as a field; it must be another column", table.headers[c])));
        }
    }
    if let (Some((_, b)), Some(c)) = (broken, count)
        && b == c
    {
        return Err(Error::config(&origin.file, format!("{}count", prefix(origin)), "the count and the broken column must differ"));
    }
    let mut out = Vec::with_capacity(rows.len());
    for &row in rows {
        let (kind, v, upper) = match ends {
            Some(e) => match (r.number(e.lower, row)?, r.number(e.upper, row)?) {
                (Some(a), Some(b)) if a < b => (Censor::Interval, a, b),
                (Some(a), Some(b)) if a == b => (Censor::Exact, a, f64::NAN),
                (Some(a), Some(b)) => return Err(r.error(row, e.lower, format!("the class's lower end {a} is above its upper end {b} (SI)"))),
                (Some(a), None) => (Censor::Right, a, f64::NAN),
                (None, Some(b)) => (Censor::Left, b, f64::NAN),
                (None, None) => return Err(r.error(row, e.lower, "both ends of the class are empty: a row needs at least one")),
            },
            None => {
                let v = r.need_number(value, row)?;
                let kind = match broken {
                    None => Censor::Exact,
                    Some((b, c)) => {
                        let cell = table.text(row, c).map(|t| t.trim().to_lowercase());
                        let is = |v: &str| cell.as_deref() == Some(v.trim().to_lowercase().as_str());
                        if is(&b.yes) {
                            Censor::Exact
                        } else if is(&b.no) {
                            Censor::Right
                        } else if b.below.as_deref().is_some_and(is) {
                            Censor::Left
                        } else {
                            let allowed = [Some(&b.yes), Some(&b.no), b.below.as_ref()].into_iter().flatten().map(|v| format!("\"{v}\"")).collect::<Vec<_>>().join(", ");
                            let got = table.text(row, c).map_or("an empty cell".to_string(), |t| format!("\"{t}\""));
                            return Err(table.error(row, Some(c), format!("holds {got}; the study's `broken` declares {allowed}")));
                        }
                    }
                };
                (kind, v, f64::NAN)
            }
        };
        let n = match count {
            None => 1,
            Some(c) => {
                let k = table.need_number(row, c)?;
                if !(k >= 0.0 && k.fract() == 0.0 && k <= 1e7) {
                    return Err(table.error(row, Some(c), format!("a count must be a whole number in [0, 1e7] (got {k})")));
                }
                k as usize
            }
        };
        out.push(RowValue { kind, value: v, upper, count: n });
    }
    if out.iter().all(|v| v.count == 0) {
        return Err(Error::data_file(&table.origin.path, "all rows", "every row counts 0 specimens"));
    }
    // The rows at the highest value, where the study says what they are (a pile-up there
    // that nothing declares is refused by [`pile_up`], after the unused columns are checked).
    if src.at_highest == Some(AtHighest::NotBroken) {
        let top = out.iter().map(|v| v.value).fold(f64::NEG_INFINITY, f64::max);
        for v in out.iter_mut().filter(|v| v.value == top) {
            v.kind = Censor::Right;
        }
    }
    // The record.
    for (c, field, conversion) in broken.iter().map(|(b, c)| (*c, "broken", describe_broken(b))).chain(count.map(|c| (c, "count", "specimens per row".to_string()))) {
        provenance.columns.push(ColumnRecord { source: table.headers[c].clone(), field: field.into(), unit: String::new(), conversion, found_by: "study".into() });
        provenance.unused.retain(|u| *u != table.headers[c]);
    }
    Ok(out)
}

fn describe_broken(b: &Broken) -> String {
    let below = b.below.as_ref().map(|v| format!(", \"{v}\" = broke at or below the value")).unwrap_or_default();
    format!("\"{}\" = broke at the value, \"{}\" = did not break by it{below}", b.yes, b.no)
}

/// Refuses a pile-up of rows at the file's highest value (module docs) where the study says
/// nothing of those rows (no `broken`, `interval` or `at_highest`). `value` is the field key,
/// `what` its word (`force`: shown in N, `strength`: in MPa).
pub fn pile_up(r: &Resolved, rows: &[usize], out: &[RowValue], value: &str, src: &Source, origin: &MapOrigin, what: &str) -> Result<()> {
    if src.broken.is_some() || src.interval.is_some() || src.at_highest.is_some() {
        return Ok(());
    }
    let top = out.iter().map(|v| v.value).fold(f64::NEG_INFINITY, f64::max);
    let at: Vec<usize> = (0..out.len()).filter(|&k| out[k].value == top).collect();
    let specimens: usize = out.iter().map(|v| v.count).sum();
    let piled: usize = at.iter().map(|&k| out[k].count).sum();
    if at.len() < PILE_UP_ROWS || (piled as f64) < PILE_UP_SHARE * specimens as f64 {
        return Ok(());
    }
    let key = prefix(origin);
    Err(r.error(
        rows[at[0]],
        value,
        format!(
            "{} of {} specimens hold the file's highest {what}, {}: a rig's limit? Say what they are: declare the column that says whether each broke ({key}broken = {{ column = \"…\", yes = \"…\", no = \"…\" }}), or {key}at_highest = \"not_broken\" (they did not break by it) or \"broken\" (they broke there)",
            piled,
            specimens,
            if what == "force" { format!("{} N", super::columns::shown(top)) } else { format!("{} MPa", super::columns::shown(top / 1e6)) }
        ),
    ))
}

/// The header `T [°C]` — a `t` that states a temperature unit — where the study maps no
/// temperature column: in a strength file a bare `t` is a bend bar's thickness, in a curve file a
/// time, but with a temperature unit it is the test temperature.
pub fn temperature_named_t(headers: &[String], columns: &std::collections::BTreeMap<String, String>) -> Option<String> {
    if columns.contains_key("temperature") {
        return None;
    }
    headers
        .iter()
        .find(|h| {
            let p = super::units::parse_header(h);
            super::units::fold(&p.name) == "t" && p.unit.is_some_and(|u| super::units::unit_of(super::Quantity::Temperature, &u).is_some())
        })
        .cloned()
}

/// Marks the temperature column as found by its header's name: what [`temperature_named_t`]
/// put in the map is the reading of a header (`T [°C]`), not the study's mapping.
pub fn found_by_name(provenance: &mut Provenance) {
    for c in provenance.columns.iter_mut().filter(|c| c.field == "temperature_c") {
        c.found_by = "name".into();
    }
}

/// Plausible test temperatures (°C), of a temperature column and of a study's `temperature_c`.
pub const TEMPERATURE: super::Plausible = super::Plausible { what: "temperature", lo: -273.15, hi: 2100.0, shown: "[-273.15, 2100] °C", why: "from absolute zero to the melting point of alumina (2072 °C), above which no ceramic particle is solid" };

/// Readings of one test temperature — a furnace's thermocouple log along one test, the tests of
/// one campaign — scatter by a few kelvin: values within this many °C of each other are one
/// temperature (°C).
pub const TEMPERATURE_TOLERANCE_C: f64 = 10.0;

/// The test temperature of each row (°C): its own (`cells`: the file's temperature column,
/// None for no column or an empty cell), else the study's `temperature_c`. A row with neither
/// is refused: `place(k)` names row k in the message, `column` is the file's temperature
/// column if it has one, as said in words (`` `T [°C]` ``). A study's value that no row uses
/// (the column gives every row's) and that lies more than [`TEMPERATURE_TOLERANCE_C`] from every
/// one of them contradicts the file and is refused, naming both. Records in `provenance` where
/// the temperatures came from and what they are (`test temperature: 20 °C (column `T [°C]`)`).
pub fn test_temperatures(cells: &[Option<f64>], place: &dyn Fn(usize) -> String, column: Option<&str>, src: &Source, origin: &MapOrigin, provenance: &mut Provenance) -> Result<Vec<f64>> {
    let key = prefix(origin);
    let mut out = Vec::with_capacity(cells.len());
    let mut from_study = 0;
    for (k, cell) in cells.iter().enumerate() {
        match (cell, src.temperature_c) {
            (Some(t), _) => out.push(*t),
            (None, Some(t)) => {
                from_study += 1;
                out.push(t);
            }
            (None, None) => {
                let rule = match column {
                    Some(c) if origin.key.is_empty() => format!("has no test temperature (column {c} is empty there): fill the cell, or give the test temperature of the rows without one (`--temperature-c 20` on the command line, `temperature_c = 20` in a study's data table; °C)"),
                    Some(c) => format!("has no test temperature (column {c} is empty there): fill the cell, or give the test temperature of the rows without one in {}: {key}temperature_c = … (°C)", origin.file),
                    None if origin.key.is_empty() => "states no test temperature: it has no temperature column (temperature_c, temp, test_temperature …). A test at 20 °C is not one at 800 °C: add the column, or give the file's test temperature (`--temperature-c 20` on the command line, `temperature_c = 20` in a study's data table; °C)".to_string(),
                    None => format!(
                        "states no test temperature: it has no temperature column (temperature_c, temp, test_temperature …) and the study gives none. A test at 20 °C is not one at 800 °C: add the column, or declare the file's test temperature in {}: {key}temperature_c = 20 (°C{})",
                        origin.file,
                        // A material's or strength set's `data` may be a bare path.
                        if origin.key.ends_with(".data") { "; a `data` given as a path becomes a table: data = { file = \"…\", temperature_c = 20 }" } else { "" }
                    ),
                };
                return Err(Error::data_file(&src.file, if column.is_some() { place(k) } else { "file".into() }, rule));
            }
        }
    }
    if let (Some(t), Some(c), 0) = (src.temperature_c, column, from_study)
        && out.iter().all(|v| (v - t).abs() > TEMPERATURE_TOLERANCE_C)
    {
        let (given, fix) = if origin.key.is_empty() { ("--temperature-c".to_string(), "drop the option".to_string()) } else { (format!("the study's {key}temperature_c"), format!("remove the key from {} or correct it", origin.file)) };
        return Err(Error::data_file(
            &src.file,
            format!("column {c}"),
            format!("gives every row's test temperature, {}, but {given} says {} °C: which is right? If the column is, {fix}; if the key is, correct the column", describe_temperatures(&out), super::columns::shown(t)),
        ));
    }
    let source = match (column, from_study) {
        (Some(c), 0) => format!("column {c}"),
        (Some(c), n) if origin.key.is_empty() => format!("column {c}; {n} empty cells from --temperature-c"),
        (Some(c), n) => format!("column {c}; {n} empty cells from the study's {key}temperature_c"),
        (None, _) if origin.key.is_empty() => "given: --temperature-c".to_string(),
        (None, _) => format!("the study's {key}temperature_c"),
    };
    provenance.observed.push(format!("test temperature: {} ({source})", describe_temperatures(&out)));
    Ok(out)
}

/// Test temperatures in words: `20 °C`, or `20 °C (45) and 800 °C (30)` (rows at each).
pub fn describe_temperatures(t: &[f64]) -> String {
    let mut seen: Vec<(f64, usize)> = Vec::new();
    for &x in t {
        match seen.iter_mut().find(|(v, _)| *v == x) {
            Some(s) => s.1 += 1,
            None => seen.push((x, 1)),
        }
    }
    seen.sort_by(|a, b| a.0.total_cmp(&b.0));
    match seen.len() {
        0 => "none".into(),
        1 => format!("{} °C", super::columns::shown(seen[0].0)),
        _ => {
            let parts: Vec<String> = seen.iter().map(|(v, n)| format!("{} °C ({n})", super::columns::shown(*v))).collect();
            let (last, head) = parts.split_last().unwrap_or((&parts[0], &[]));
            format!("{} and {last}", head.join(", "))
        }
    }
}

/// The specimens a file's rows stand for: a row counting k becomes k specimens, and what each
/// says (exact, censored, interval) becomes the observations' censoring. Records in
/// `provenance` the expansion (`count column `Anzahl`: 10 rows → 389 specimens; dropped
/// (counting 0): row 4`) and the tally of what the specimens say; `noun` names them
/// (`particles`, `specimens`).
pub fn specimens(values: &[RowValue], places: &[String], src: &Source, provenance: &mut Provenance, noun: &str) -> Specimens {
    let counts: Vec<usize> = values.iter().map(|v| v.count).collect();
    let (rows, copy) = if counts.iter().all(|k| *k == 1) {
        ((0..values.len()).collect(), vec![None; values.len()])
    } else {
        let rows = crate::obs::expand(&counts);
        // Specimens of one row are consecutive: the j-th of a row counting several is `id#j`.
        let (mut last, mut j) = (usize::MAX, 0);
        let copy = rows
            .iter()
            .map(|&k| {
                if k != last {
                    (last, j) = (k, 0);
                }
                j += 1;
                (counts[k] > 1).then_some(j)
            })
            .collect();
        let zero: Vec<&str> = counts.iter().zip(places).filter(|(k, _)| **k == 0).map(|(_, p)| p.as_str()).collect();
        let dropped = if zero.is_empty() { String::new() } else { format!("; dropped (counting 0): {}", zero.join(", ")) };
        provenance.observed.push(format!("count column `{}`: {} rows → {} {noun}{dropped}", src.count.as_deref().unwrap_or(""), values.len(), rows.len()));
        provenance.rows = rows.len();
        (rows, copy)
    };
    let x: Vec<f64> = rows.iter().map(|&k| values[k].value).collect();
    let censoring = crate::obs::Censoring::of_rows(rows.iter().map(|&k| values[k].kind).collect(), &x, rows.iter().map(|&k| values[k].upper).collect());
    if let Some(c) = &censoring {
        provenance.observed.push(crate::obs::Obs { x: &x, censoring: Some(c) }.tally().describe(noun));
    }
    Specimens { rows, copy, observations: crate::obs::Observations { x, censoring } }
}

/// A file's rows as specimens ([`specimens`]): a row counting k stands k times.
#[derive(Debug, Clone)]
pub struct Specimens {
    /// The row (index into the rows read) each specimen comes from.
    pub rows: Vec<usize>,
    /// Each specimen's number within its row, where the row counts several (`id#j`).
    pub copy: Vec<Option<usize>>,
    /// The specimens' values and what each says (exact, censored, interval).
    pub observations: crate::obs::Observations,
}

impl Specimens {
    /// Specimen `i`'s id from its row's: `A` or, of a row counting several, `A#j`.
    pub fn id(&self, i: usize, row_id: &str) -> String {
        match self.copy[i] {
            Some(j) => format!("{row_id}#{j}"),
            None => row_id.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::intake::undeclared::check_unused;
    use crate::intake::{Field, Kind, Quantity, read_raw, resolve};

    const FIELDS: [Field; 2] = [
        Field { key: "id", column: "id", kind: Kind::Text, synonyms: &[], required: true, plausible: None },
        Field { key: "force", column: "force_n", kind: Kind::Number(Quantity::Force), synonyms: &[], required: true, plausible: None },
    ];

    fn read(body: &str, src: impl Fn(&mut Source)) -> Result<(Vec<RowValue>, Provenance)> {
        let dir = crate::io::TempDir::new("observed").unwrap();
        let p = dir.path().join("f.csv");
        std::fs::write(&p, body).unwrap();
        let mut s = Source::file(&p);
        src(&mut s);
        s.validate_rows("s.toml", "material[0].data")?;
        let t = read_raw(&s)?;
        let r = resolve(&t, &FIELDS, &s.columns, &s.units, &MapOrigin { file: "s.toml".into(), key: "material[0].data".into() })?;
        let rows: Vec<usize> = (0..t.rows.len()).collect();
        let mut prov = r.provenance.clone();
        let origin = MapOrigin { file: "s.toml".into(), key: "material[0].data".into() };
        let v = read_rows(&r, &rows, "force", None, &s, &origin, &mut prov)?;
        check_unused(&t, &rows, &mut prov, &s, &origin)?;
        pile_up(&r, &rows, &v, "force", &s, &origin, "force")?;
        Ok((v, prov))
    }

    #[test]
    fn a_declared_broken_column_and_count_are_read() {
        let body = "id;force_n;gebrochen;Anzahl\nA;100;ja;1\nB;150;nein;2\nC;120;JA ;0\n";
        let (v, prov) = read(body, |s| {
            s.broken = Some(Broken { column: "gebrochen".into(), yes: "ja".into(), no: "nein".into(), below: None });
            s.count = Some("Anzahl".into());
        })
        .unwrap();
        assert_eq!(v.iter().map(|r| (r.kind, r.count)).collect::<Vec<_>>(), [(Censor::Exact, 1), (Censor::Right, 2), (Censor::Exact, 0)]);
        assert!(prov.unused.is_empty(), "{:?}", prov.unused);
        assert!(prov.columns.iter().any(|c| c.field == "broken" && c.conversion.contains("did not break")));
        // Another value in the broken column names its row.
        let e = read("id;force_n;gebrochen\nA;100;ja\nB;150;vielleicht\n", |s| s.broken = Some(Broken { column: "gebrochen".into(), yes: "ja".into(), no: "nein".into(), below: None })).unwrap_err().to_string();
        assert!(e.contains("row 2") && e.contains("\"vielleicht\"") && e.contains("\"nein\""), "{e}");
    }

    #[test]
    fn undeclared_yes_no_count_and_origin_columns_and_pile_ups_are_refused() {
        let e = read("id;force_n;gebrochen\nA;100;ja\nB;150;nein\nC;120;ja\n", |_| {}).unwrap_err().to_string();
        assert!(e.contains("column gebrochen") && e.contains("material[0].data.broken = { column = \"gebrochen\"") && e.contains("ignore"), "{e}");
        let e = read("id;force_n;n\nA;100;3\nB;150;2\nC;120;1\n", |_| {}).unwrap_err().to_string();
        assert!(e.contains("material[0].data.count = \"n\""), "{e}");
        let e = read("id;force_n;status\nA;100;1\nB;150;0\nC;120;1\n", |_| {}).unwrap_err().to_string();
        assert!(e.contains("yes/no"), "{e}");
        // Ignored, it passes.
        read("id;force_n;gebrochen\nA;100;ja\nB;150;nein\nC;120;ja\n", |s| s.ignore = vec!["gebrochen".into()]).unwrap();
        // Failure origins, by the header or by the values alone.
        let e = read("id;force_n;Bruchursprung\nA;100;Volumen\nB;150;Oberfläche\nC;120;Pore 3\n", |_| {}).unwrap_err().to_string();
        assert!(e.contains("column Bruchursprung") && e.contains("failure origins") && e.contains("material[0].origin = \"Bruchursprung\"") && e.contains("material[0].data.ignore = [\"Bruchursprung\"]"), "{e}");
        let e = read("id;force_n;where\nA;100;volume\nB;150;Surface\nC;120;none\n", |_| {}).unwrap_err().to_string();
        assert!(e.contains("column where") && e.contains("material[0].origin = \"where\""), "{e}");
        read("id;force_n;Bruchursprung\nA;100;Volumen\nB;150;Oberfläche\nC;120;Volumen\n", |s| s.ignore = vec!["Bruchursprung".into()]).unwrap();
        // Origins written as codes under a header that names them.
        let e = read("id;force_n;Bruch-Typ\nA;100;V\nB;150;O\nC;120;V\n", |_| {}).unwrap_err().to_string();
        assert!(e.contains("column Bruch-Typ: looks like failure origins") && e.contains("\"V\", \"O\""), "{e}");
        // Several columns to declare: one message names them all.
        let e = read("id;force_n;gebrochen;Anzahl;Bruchursprung\nA;100;ja;1;Volumen\nB;150;nein;2;none\nC;120;ja;1;Oberfläche\n", |_| {}).unwrap_err().to_string();
        assert!(e.contains("column gebrochen: holds yes/no") && e.contains("; and column Anzahl: holds whole numbers") && e.contains("; and column Bruchursprung: looks like failure origins"), "{e}");
        // Not origins: a remark column, and a column holding only `none`.
        read("id;force_n;remark\nA;100;chipped\nB;150;ok then\nC;120;none\n", |_| {}).unwrap();
        read("id;force_n;remark\nA;100;none\nB;150;none\nC;120;none\n", |_| {}).unwrap();
        // A pile-up at the highest force.
        let body = "id;force_n\nA;100\nB;150\nC;150\nD;150\nE;120\n";
        let e = read(body, |_| {}).unwrap_err().to_string();
        assert!(e.contains("3 of 5 specimens hold the file's highest force, 150 N") && e.contains("at_highest"), "{e}");
        let (v, _) = read(body, |s| s.at_highest = Some(AtHighest::NotBroken)).unwrap();
        assert_eq!(v.iter().filter(|r| r.kind == Censor::Right).count(), 3);
        let (v, _) = read(body, |s| s.at_highest = Some(AtHighest::Broken)).unwrap();
        assert!(v.iter().all(|r| r.kind == Censor::Exact));
    }

    #[test]
    fn declarations_that_contradict_are_refused_before_reading() {
        let mut s = Source::file("f.csv");
        s.broken = Some(Broken { column: "b".into(), yes: "ja".into(), no: "JA".into(), below: None });
        assert!(s.validate_rows("s.toml", "d").unwrap_err().to_string().contains("must differ"));
        s.broken = Some(Broken { column: "b".into(), yes: "ja".into(), no: "nein".into(), below: None });
        s.interval = Some(Interval { lower: "a".into(), upper: "b".into(), unit: None });
        assert!(s.validate_rows("s.toml", "d").unwrap_err().to_string().contains("not both"));
    }
}

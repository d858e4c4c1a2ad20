//! Columns resolved to the fields a reader needs, and their cells converted to SI.
//!
//! A reader declares its fields ([`Field`]: key, SI column name, quantity, synonyms, whether
//! required, plausible range). Each field is found
//!
//! 1. by the study's explicit map (`columns = { diameter = "Dp" }`), which wins; else
//! 2. by name: a header whose name (without its unit, compared without case, blanks, `_`, `-`,
//!    `.`) is the field's SI column name or one of its synonyms. Two headers that both fit
//!    are refused: the study must map one.
//!
//! Its unit is the one the study declares (`units = { diameter = "mm" }`), else the one the
//! header states (`D [mm]`, `diameter_mm`); a study unit that contradicts the header's is
//! refused. A numeric field of a dimensioned quantity with no unit is refused with what to
//! declare — never guessed. Missing required fields are reported all at once. A header that is
//! used by no field and lies within two edits of a field's name is reported as a likely
//! misspelling (`roundnes` → `roundness`).
//!
//! Every value is then converted to SI ([`super::decimal`]) and checked against the field's
//! plausible range, which is stated in SI and applies after conversion (900 mm is refused as
//! 0.9 m would be). A value outside it that would be plausible in another unit of the quantity
//! gets the hint "did you mean …?".

use std::collections::BTreeMap;

use serde::Serialize;

use super::table::{Cell, RawTable, number_text};
use super::units::{Quantity, Unit, fold, parse_header, unit_of};
use crate::error::{Error, Result};

/// The plausibility range of a numeric input column (closed, in SI), with the reason for it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plausible {
    /// What the value is (`diameter`).
    pub what: &'static str,
    /// Lowest plausible value.
    pub lo: f64,
    /// Highest plausible value.
    pub hi: f64,
    /// The range as written in messages, with its unit (`[1e-6, 0.1] m`).
    pub shown: &'static str,
    /// Why.
    pub why: &'static str,
}

impl Plausible {
    /// Whether v lies in the range.
    pub fn contains(&self, v: f64) -> bool {
        v >= self.lo && v <= self.hi
    }

    /// The rule a value `v` breaks, or None when it lies in the range.
    pub fn broken(&self, v: f64) -> Option<String> {
        let finite = if v.is_finite() { "" } else { "a finite number " };
        (!self.contains(v)).then(|| format!("{} must be {finite}in {} ({}); got {}", self.what, self.shown, self.why, shown(v)))
    }

    /// v if it lies in the range, else an error naming file, row and column (a file whose
    /// header is line 1).
    pub fn check(&self, path: &std::path::Path, row: usize, column: &str, v: f64) -> Result<f64> {
        match self.broken(v) {
            None => Ok(v),
            Some(rule) => Err(Error::data_row(path, row, column, rule)),
        }
    }
}

/// A number as a message shows it: plain in [10⁻⁴, 10⁶), else in scientific notation (1e308,
/// not 309 digits).
pub fn shown(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&v.abs()) { format!("{v}") } else { format!("{v:e}") }
}

/// What a field holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Text (ids, labels).
    Text,
    /// A number of a quantity.
    Number(Quantity),
}

/// A field a reader needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Field {
    /// The key a study maps it by (`diameter`).
    pub key: &'static str,
    /// Its column name in partlife's own SI form (`diameter_m`).
    pub column: &'static str,
    /// What it holds.
    pub kind: Kind,
    /// Other names it is found by (compared folded: `Fmax`, `F_max` and `f max` are one).
    pub synonyms: &'static [&'static str],
    /// Whether the reader cannot do without it.
    pub required: bool,
    /// Its plausible range (numbers).
    pub plausible: Option<Plausible>,
}

impl Field {
    /// The names it is found by: its key, its SI column name and synonyms.
    fn names(&self) -> impl Iterator<Item = &'static str> + '_ {
        [self.key, self.column].into_iter().chain(self.synonyms.iter().copied())
    }

    /// How a missing field is described: `diameter (a length: diameter_m, D [mm], …)`.
    fn wanted(&self) -> String {
        match self.kind {
            Kind::Text => format!("{} (`{}`)", self.key, self.names().skip(1).take(4).collect::<Vec<_>>().join("`, `")),
            Kind::Number(q) => {
                // A header a lab would write for this field, with its unit: the field's own
                // (a curve's displacement is `s [mm]`, not a diameter's `D [mm]`).
                let header = match (self.key, q) {
                    ("diameter", _) => Some("D [mm]"),
                    ("crush_force", _) => Some("Fmax [N]"),
                    ("displacement", _) => Some("s [mm]"),
                    ("force", _) => Some("F [N]"),
                    (_, Quantity::Stress) => Some("strength [MPa]"),
                    (_, Quantity::Temperature) => Some("T [°C]"),
                    _ => None,
                };
                let example = match header {
                    Some(h) => format!("`{}`, `{h}`", self.column),
                    None => format!("`{}`", self.column),
                };
                format!("{} ({}, e.g. {example})", self.key, q.word())
            }
        }
    }
}

impl Kind {
    /// The internal unit of a numeric kind, for messages.
    fn si_of(k: Kind) -> &'static str {
        match k {
            Kind::Number(q) => q.si(),
            Kind::Text => "-",
        }
    }
}

/// How a column was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Found {
    /// By the study's map.
    Mapped,
    /// By its name.
    Named,
}

/// A field resolved to a column.
#[derive(Debug, Clone, PartialEq)]
pub struct Mapped {
    /// Column index.
    pub col: usize,
    /// Unit (numbers).
    pub unit: Option<&'static Unit>,
    /// Its exact conversion to SI (None: values taken as written).
    conversion: Option<super::decimal::Conversion>,
    found: Found,
}

/// One converted column, as the record lists it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ColumnRecord {
    /// The header as written.
    pub source: String,
    /// The SI column it became.
    pub field: String,
    /// Its unit as read (`mm`), empty for text and dimensionless columns.
    pub unit: String,
    /// The conversion (`× 1e-3`), empty when values are taken as written.
    pub conversion: String,
    /// How it was found: `name` or `study` (the study's `columns` map).
    pub found_by: String,
}

/// What a reader took from a file: every decision, for the manifest and `datasets check`.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct Provenance {
    /// The file.
    pub file: String,
    /// The sheet, for a spreadsheet.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sheet: Option<String>,
    /// How it was read (`semicolon-separated, decimal comma, UTF-8`).
    pub format: String,
    /// Data rows used.
    pub rows: usize,
    /// The columns used, with units and conversions.
    pub columns: Vec<ColumnRecord>,
    /// Headers no field used.
    pub unused: Vec<String>,
    /// Rows picked by a material filter: `material = "BL 16/30": 50 of 95 rows`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub filter: Option<String>,
    /// Ids dropped by an inner join (present in one file only).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub dropped_ids: Vec<String>,
    /// Files joined to this one by id.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub joined: Vec<Provenance>,
    /// Warnings (likely misspelt headers); also printed.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Headers the study lists in `ignore`: looked at and left out on purpose.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ignored: Vec<String>,
    /// What the rows say of themselves, as read ([`super::observed`]): rows counting several
    /// specimens, specimens that did not break by their limit, classes.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub observed: Vec<String>,
}

impl Provenance {
    /// The lines of the reading that change what a fit saw, for a summary to state beside the
    /// material and not only on the report's Inputs page: columns not used (read by no field
    /// and no declaration), columns ignored as the study says, the count column (rows →
    /// specimens, rows counting 0 dropped) and what was read of the failure origins.
    pub fn summary_notes(&self) -> Vec<String> {
        let list = |v: &[String]| v.iter().map(|u| format!("`{u}`")).collect::<Vec<_>>().join(", ");
        let mut out = Vec::new();
        if !self.unused.is_empty() {
            out.push(format!("column{} not used: {} (read by no field of the file's kind and no declaration of the study)", if self.unused.len() == 1 { "" } else { "s" }, list(&self.unused)));
        }
        if !self.ignored.is_empty() {
            out.push(format!("column{} ignored as the study's `ignore` says: {}", if self.ignored.len() == 1 { "" } else { "s" }, list(&self.ignored)));
        }
        out.extend(self.observed.iter().filter(|l| l.starts_with("failure origin") || l.starts_with("count column")).cloned());
        out
    }

    /// One line, e.g. "semicolon-separated, decimal comma, UTF-8; `D [mm]` → diameter_m (× 1e-3); …".
    pub fn describe(&self) -> String {
        let mut parts = vec![self.format.clone()];
        for c in &self.columns {
            let mut s = if c.source == c.field { format!("`{}`", c.source) } else { format!("`{}` → {}", c.source, c.field) };
            if !c.conversion.is_empty() {
                // A unit symbol precedes its conversion ("mm × 1e-3"); a phrase ("as in the
                // file") follows it.
                let said = match c.unit.as_str() {
                    "" => c.conversion.clone(),
                    u if u.contains(' ') => format!("{}, unit {u}", c.conversion),
                    u => format!("{u} {}", c.conversion),
                };
                s.push_str(&format!(" ({said})"));
            }
            if c.found_by == "study" {
                s.push_str(" [mapped by the study]");
            }
            parts.push(s);
        }
        if !self.unused.is_empty() {
            parts.push(format!("not used: {}", self.unused.iter().map(|u| format!("`{u}`")).collect::<Vec<_>>().join(", ")));
        }
        if !self.ignored.is_empty() {
            parts.push(format!("ignored as the study says: {}", self.ignored.iter().map(|u| format!("`{u}`")).collect::<Vec<_>>().join(", ")));
        }
        if let Some(f) = &self.filter {
            parts.push(f.clone());
        }
        parts.extend(self.observed.iter().cloned());
        let mut out = parts.join("; ");
        for j in &self.joined {
            let file = if j.file == self.file { String::new() } else { format!("{}, ", j.file) };
            out.push_str(&format!("; joined by id: ({file}{})", j.describe()));
        }
        if !self.dropped_ids.is_empty() {
            out.push_str(&format!("; dropped (in one file only): {}", self.dropped_ids.join(", ")));
        }
        out
    }
}

/// Where the study's map of a file is (for configuration errors): the study file and the
/// dotted key of the table holding `columns` and `units` (`material[1]`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MapOrigin {
    /// The study file.
    pub file: String,
    /// The key of the table.
    pub key: String,
}

impl MapOrigin {
    fn error(&self, sub: &str, rule: String) -> Error {
        let key = if self.key.is_empty() { sub.to_string() } else { format!("{}.{sub}", self.key) };
        Error::config(if self.file.is_empty() { "<study>" } else { &self.file }, key, rule)
    }
}

/// The edit distance of two short strings (for misspelling hints).
fn distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != cb)).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// A table with its fields resolved.
#[derive(Debug, Clone)]
pub struct Resolved<'a> {
    /// The table.
    pub table: &'a RawTable,
    fields: &'a [Field],
    map: Vec<Option<Mapped>>,
    /// The record so far.
    pub provenance: Provenance,
}

/// Resolves `fields` in `table` with the study's `columns` and `units` maps (module docs).
pub fn resolve<'a>(table: &'a RawTable, fields: &'a [Field], columns: &BTreeMap<String, String>, units: &BTreeMap<String, String>, origin: &MapOrigin) -> Result<Resolved<'a>> {
    let known = || fields.iter().map(|f| f.key).collect::<Vec<_>>().join(", ");
    for k in columns.keys().chain(units.keys()) {
        if !fields.iter().any(|f| f.key == k) {
            let sub = if columns.contains_key(k) { "columns" } else { "units" };
            return Err(origin.error(&format!("{sub}.{k}"), format!("unknown field; this file's fields are {}", known())));
        }
    }
    let headers: Vec<_> = table.headers.iter().map(|h| parse_header(h)).collect();
    let mut map: Vec<Option<(usize, Found)>> = vec![None; fields.len()];
    if let Some(k) = units.keys().find(|k| fields.iter().any(|f| f.key == k.as_str() && f.kind == Kind::Text)) {
        return Err(origin.error(&format!("units.{k}"), format!("{k} holds text: it has no unit")));
    }
    // 1. The study's map.
    for (i, f) in fields.iter().enumerate() {
        if let Some(name) = columns.get(f.key) {
            match table.headers.iter().position(|h| h == name.trim()) {
                Some(c) if map.iter().flatten().any(|(k, _)| *k == c) => {
                    let other = fields.iter().zip(&map).find(|(_, m)| m.is_some_and(|(k, _)| k == c)).map_or("", |(g, _)| g.key);
                    return Err(origin.error(&format!("columns.{}", f.key), format!("column \"{name}\" is already mapped to {other}: a column holds one field")));
                }
                Some(c) => map[i] = Some((c, Found::Mapped)),
                None => {
                    return Err(origin.error(
                        &format!("columns.{}", f.key),
                        format!("{}{} has no column \"{name}\" (its columns: {})", table.origin.path.display(), table.origin.sheet.as_ref().map(|s| format!(" sheet \"{s}\"")).unwrap_or_default(), table.headers.iter().map(|h| format!("\"{h}\"")).collect::<Vec<_>>().join(", ")),
                    ));
                }
            }
        }
    }
    // 2. Names.
    let claimed = |map: &[Option<(usize, Found)>], c: usize| map.iter().flatten().any(|(k, _)| *k == c);
    for (i, f) in fields.iter().enumerate() {
        if map[i].is_some() {
            continue;
        }
        let names: Vec<String> = f.names().map(fold).collect();
        let fits: Vec<usize> = (0..headers.len()).filter(|&c| !claimed(&map, c) && names.contains(&fold(&headers[c].name))).collect();
        match fits.len() {
            0 => {}
            1 => map[i] = Some((fits[0], Found::Named)),
            _ => {
                let listed: Vec<String> = fits.iter().map(|&c| format!("`{}` (column {})", table.headers[c], c + 1)).collect();
                return Err(table.header_error(None, format!("two columns map to the {}: {}; map one in the study: columns = {{ {} = \"{}\" }}", f.key, listed.join(" and "), f.key, table.headers[fits[0]])));
            }
        }
    }
    // Missing required fields, all at once.
    let missing: Vec<String> = fields.iter().zip(&map).filter(|(f, m)| f.required && m.is_none()).map(|(f, _)| f.wanted()).collect();
    if !missing.is_empty() {
        let cols = table.headers.iter().map(|h| format!("`{h}`")).collect::<Vec<_>>().join(", ");
        return Err(table.header_error(None, format!("missing {} {}: the file's columns are {cols}; rename a column or map it in the study (columns = {{ … }})", if missing.len() == 1 { "column" } else { "columns" }, missing.join("; "))));
    }
    // Units.
    let mut resolved = Vec::with_capacity(fields.len());
    for (i, f) in fields.iter().enumerate() {
        let Some((c, found)) = map[i] else {
            if units.contains_key(f.key) {
                return Err(origin.error(&format!("units.{}", f.key), format!("the file has no {} column to give a unit to", f.key)));
            }
            resolved.push(None);
            continue;
        };
        let h = &headers[c];
        let header_unit = |q: Quantity| -> Result<Option<&'static Unit>> {
            match &h.unit {
                None => Ok(None),
                Some(u) => match unit_of(q, u) {
                    Some(unit) => Ok(Some(unit)),
                    None => Err(table.header_error(Some(c), format!("unit \"{u}\" is not {} ({} is {}; accepted: {})", q.word(), f.key, q.word(), q.accepted()))),
                },
            }
        };
        let unit = match f.kind {
            Kind::Text => None,
            Kind::Number(q) => {
                let from_header = header_unit(q)?;
                match units.get(f.key) {
                    Some(u) => {
                        let Some(unit) = unit_of(q, u) else {
                            return Err(origin.error(&format!("units.{}", f.key), format!("\"{u}\" is not {} (accepted: {})", q.word(), q.accepted())));
                        };
                        if let Some(hu) = from_header
                            && hu != unit
                        {
                            return Err(origin.error(&format!("units.{}", f.key), format!("\"{u}\" contradicts the header `{}` of {}, which states {}", h.text, table.origin.path.display(), hu.symbol)));
                        }
                        Some(unit)
                    }
                    None => match from_header {
                        Some(unit) => Some(unit),
                        None if q.unitless() => Some(super::units::si_unit(q)),
                        None => {
                            return Err(table.header_error(
                                Some(c),
                                format!("states no unit for the {} ({}): write it in the header (`{} [{}]`) or declare it in the study (units = {{ {} = \"{}\" }}); accepted: {}", f.key, q.word(), h.name, q.si(), f.key, q.si(), q.accepted()),
                            ));
                        }
                    },
                }
            }
        };
        resolved.push(Some(Mapped { col: c, unit, conversion: unit.filter(|u| !u.is_si()).map(|u| u.conversion()), found }));
    }
    // The record: columns used, unused ones, likely misspellings.
    let mut provenance = Provenance {
        file: table.origin.path.display().to_string(),
        sheet: table.origin.sheet.clone(),
        format: table.format.clone(),
        rows: table.rows.len(),
        ..Provenance::default()
    };
    for (f, m) in fields.iter().zip(&resolved) {
        if let Some(m) = m {
            let unit = m.unit.filter(|u| !u.symbol.starts_with('-'));
            provenance.columns.push(ColumnRecord {
                source: table.headers[m.col].clone(),
                field: f.column.to_string(),
                unit: unit.map(|u| u.symbol.to_string()).unwrap_or_default(),
                conversion: unit.map(|u| u.describe()).unwrap_or_default(),
                found_by: if m.found == Found::Mapped { "study".into() } else { "name".into() },
            });
        }
    }
    for (c, h) in headers.iter().enumerate() {
        if resolved.iter().flatten().any(|m| m.col == c) {
            continue;
        }
        provenance.unused.push(h.text.clone());
        let folded = fold(&h.name);
        if folded.len() >= 4
            && let Some((f, name)) = fields.iter().zip(&resolved).filter(|(_, m)| m.is_none()).flat_map(|(f, _)| f.names().map(move |n| (f, n))).find(|(_, n)| {
                let d = distance(&folded, &fold(n));
                d > 0 && d <= 2 && fold(n).len() >= 4
            })
        {
            provenance.warnings.push(format!("{}: column `{}` is not used: did you mean `{name}` (the {} column)?", table.origin.path.display(), h.text, f.key));
        }
    }
    Ok(Resolved { table, fields, map: resolved, provenance })
}

impl Resolved<'_> {
    fn index(&self, key: &str) -> usize {
        self.fields.iter().position(|f| f.key == key).unwrap_or_else(|| panic!("no field `{key}` was declared"))
    }

    /// Whether the file has the field.
    pub fn has(&self, key: &str) -> bool {
        self.map[self.index(key)].is_some()
    }

    /// The column of a field, if the file has it.
    pub fn column(&self, key: &str) -> Option<usize> {
        self.map[self.index(key)].as_ref().map(|m| m.col)
    }

    /// The text of field `key` at data row `row` (None: no column or an empty cell).
    pub fn text(&self, key: &str, row: usize) -> Option<String> {
        let m = self.map[self.index(key)].as_ref()?;
        match &self.table.rows[row][m.col] {
            Cell::Empty => None,
            Cell::Text(t) => Some(t.clone()),
            Cell::Number(v) => Some(format!("{v}")),
            Cell::Other(w) => Some(w.clone()),
        }
    }

    /// The text of a required field at a row; an empty cell is an error.
    pub fn need_text(&self, key: &str, row: usize) -> Result<String> {
        self.text(key, row).ok_or_else(|| self.table.error(row, self.column(key), "cell is empty; a value is required"))
    }

    /// The SI value of field `key` at `row` (None: no column or an empty cell), checked against
    /// the field's plausible range (module docs).
    pub fn number(&self, key: &str, row: usize) -> Result<Option<f64>> {
        let i = self.index(key);
        let Some(m) = &self.map[i] else { return Ok(None) };
        let col = Some(m.col);
        let unit = m.unit.expect("numeric fields have a unit");
        // A spreadsheet's number in the internal unit is taken as it is.
        if let (Cell::Number(v), None) = (&self.table.rows[row][m.col], &m.conversion) {
            return self.plausible(i, row, *v, unit, &|| format!("{v}"));
        }
        if let Cell::Text(raw) = &self.table.rows[row][m.col]
            && self.table.origin.sheet.is_some()
        {
            return Err(self.table.error(row, col, format!("holds the text \"{raw}\", not a number (stored as text in the spreadsheet: make it a number cell)")));
        }
        let text = match number_text(&self.table.rows[row][m.col], self.table.decimal) {
            Ok(None) => return Ok(None),
            Ok(Some(t)) => t,
            Err(rule) => return Err(self.table.error(row, col, rule)),
        };
        let raw = match &self.table.rows[row][m.col] {
            Cell::Text(t) => t.clone(),
            _ => text.clone(),
        };
        let parsed: f64 = text.parse().map_err(|_| self.table.error(row, col, format!("value \"{raw}\" is not a number")))?;
        if !parsed.is_finite() {
            return Err(self.table.error(row, col, format!("value \"{raw}\" is not a finite number")));
        }
        let v = match &m.conversion {
            None => parsed,
            Some(c) => c.apply(&text).ok_or_else(|| self.table.error(row, col, format!("value \"{raw}\" is not a decimal number")))?,
        };
        if !v.is_finite() {
            return Err(self.table.error(row, col, format!("value \"{raw}\" {} is not a finite number in {}", unit.symbol, Kind::si_of(self.fields[i].kind))));
        }
        self.plausible(i, row, v, unit, &|| text.clone())
    }

    /// v if it lies in field `i`'s plausible range, else the error with its hint (module docs);
    /// `text` gives the cell's decimal form (only on the error path).
    fn plausible(&self, i: usize, row: usize, v: f64, unit: &Unit, text: &dyn Fn() -> String) -> Result<Option<f64>> {
        let f = &self.fields[i];
        let col = self.map[i].as_ref().map(|m| m.col);
        if let Some(p) = &f.plausible
            && let Some(mut rule) = p.broken(v)
        {
            let text = text();
            if !unit.is_si() {
                rule = format!("{rule} (read as {text} {})", unit.symbol);
            }
            let Kind::Number(q) = f.kind else { unreachable!("plausible ranges belong to numbers") };
            let other: Vec<&str> = super::units::UNITS
                .iter()
                .filter(|u| u.quantity == q && u.symbol != unit.symbol && u.offset == "0")
                .filter(|u| u.conversion().apply(&text).is_some_and(|x| p.contains(x)))
                .map(|u| u.symbol)
                .collect();
            if !other.is_empty() && unit.offset == "0" {
                rule.push_str(&format!(": did you mean {}?", other.join(" or ")));
            }
            return Err(self.table.error(row, col, rule));
        }
        Ok(Some(v))
    }

    /// The SI value of a required field at a row; an empty cell is an error.
    pub fn need_number(&self, key: &str, row: usize) -> Result<f64> {
        self.number(key, row)?.ok_or_else(|| self.table.error(row, self.column(key), "cell is empty; a value is required"))
    }

    /// An error at a row and a field's column.
    pub fn error(&self, row: usize, key: &str, rule: impl Into<String>) -> Error {
        self.table.error(row, self.column(key), rule)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::intake::{Source, table::read_delimited};

    const LEN: Plausible = Plausible { what: "diameter", lo: 1e-6, hi: 0.1, shown: "[1e-6, 0.1] m", why: "a particle" };
    const FIELDS: [Field; 4] = [
        Field { key: "id", column: "id", kind: Kind::Text, synonyms: &["probe", "particle"], required: true, plausible: None },
        Field { key: "diameter", column: "diameter_m", kind: Kind::Number(Quantity::Length), synonyms: &["d", "dp"], required: true, plausible: Some(LEN) },
        Field { key: "crush_force", column: "crush_force_n", kind: Kind::Number(Quantity::Force), synonyms: &["f", "fmax", "force"], required: true, plausible: None },
        Field { key: "roundness", column: "roundness", kind: Kind::Number(Quantity::Ratio), synonyms: &[], required: false, plausible: None },
    ];

    fn table(text: &str) -> RawTable {
        read_delimited(std::path::Path::new("lab.csv"), text.as_bytes(), &Source::default()).unwrap()
    }

    fn maps(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
        pairs.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect()
    }

    #[test]
    fn names_and_units_resolve_and_convert_exactly() {
        let t = table("Probe;D [mm];F_max (kN);roundnes\n1;0,91;0,1312;0,8\n");
        let r = resolve(&t, &FIELDS, &BTreeMap::new(), &BTreeMap::new(), &MapOrigin::default()).unwrap();
        assert_eq!(r.need_text("id", 0).unwrap(), "1");
        assert_eq!(r.need_number("diameter", 0).unwrap(), 0.00091);
        assert_eq!(r.need_number("crush_force", 0).unwrap(), 131.2);
        assert_eq!(r.number("roundness", 0).unwrap(), None);
        assert!(r.provenance.warnings[0].contains("did you mean `roundness`"), "{:?}", r.provenance.warnings);
        assert_eq!(r.provenance.describe(), "semicolon-separated, decimal comma, UTF-8; `Probe` → id; `D [mm]` → diameter_m (mm × 1e-3); `F_max (kN)` → crush_force_n (kN × 1e3); not used: `roundnes`");
    }

    #[test]
    fn the_study_map_wins_and_gives_units() {
        let t = table("Nr,Dp,Last,d\nA,0.9,13.38,5\n");
        let r = resolve(&t, &FIELDS, &maps(&[("id", "Nr"), ("diameter", "Dp"), ("crush_force", "Last")]), &maps(&[("diameter", "mm"), ("crush_force", "kgf")]), &MapOrigin::default()).unwrap();
        assert_eq!(r.need_number("diameter", 0).unwrap(), 0.0009);
        assert_eq!(r.need_number("crush_force", 0).unwrap(), 131.212977);
        assert_eq!(r.provenance.unused, vec!["d"]);
    }

    #[test]
    fn refusals_say_what_to_do() {
        let err = |text: &str, cols: &[(&str, &str)], units: &[(&str, &str)]| resolve(&table(text), &FIELDS, &maps(cols), &maps(units), &MapOrigin { file: "s.toml".into(), key: "material[0]".into() }).unwrap_err().to_string();
        let e = err("x,y\n1,2\n", &[], &[]);
        assert!(e.contains("missing columns") && e.contains("id (") && e.contains("diameter (a length") && e.contains("crush_force (a force"), "{e}");
        let e = err("id,D [N],F [N]\n1,2,3\n", &[], &[]);
        assert!(e.contains("column D [N]: unit \"N\" is not a length"), "{e}");
        let e = err("id,D,F [N]\n1,2,3\n", &[], &[]);
        assert!(e.contains("column D: states no unit for the diameter") && e.contains("units = { diameter = \"m\" }"), "{e}");
        let e = err("id,D [mm],diameter_m,F [N]\n1,2,0.002,3\n", &[], &[]);
        assert!(e.contains("two columns map to the diameter") && e.contains("`D [mm]` (column 2) and `diameter_m` (column 3)"), "{e}");
        let e = err("id,D [mm],F [N]\n1,2,3\n", &[], &[("diameter", "m")]);
        assert!(e.starts_with("s.toml: material[0].units.diameter") && e.contains("contradicts"), "{e}");
        let e = err("id,D [mm],F [N]\n1,2,3\n", &[("diameter", "Dp")], &[]);
        assert!(e.contains("material[0].columns.diameter") && e.contains("no column \"Dp\""), "{e}");
        let e = err("id,D [mm],F [N]\n1,2,3\n", &[("size", "D [mm]")], &[]);
        assert!(e.contains("columns.size") && e.contains("unknown field"), "{e}");
        let e = err("id,D,F [N]\n1,2,3\n", &[("diameter", "D"), ("crush_force", "D")], &[]);
        assert!(e.contains("columns.crush_force") && e.contains("already mapped to diameter"), "{e}");
        let e = err("id,D [mm],F [N]\n1,2,3\n", &[], &[("id", "mm")]);
        assert!(e.contains("units.id") && e.contains("holds text"), "{e}");
    }

    #[test]
    fn plausibility_applies_in_si_with_a_hint() {
        let t = table("id,D [mm],F [N]\nA,900,1\nB,0.9,1\n");
        let r = resolve(&t, &FIELDS, &BTreeMap::new(), &BTreeMap::new(), &MapOrigin::default()).unwrap();
        let e = r.need_number("diameter", 0).unwrap_err().to_string();
        assert!(e.contains("row 1 (line 2), column D [mm]") && e.contains("got 0.9") && e.contains("read as 900 mm") && e.contains("did you mean µm?"), "{e}");
        let t = table("id,diameter_m,F [N]\nA,0.9,1\n");
        let r = resolve(&t, &FIELDS, &BTreeMap::new(), &BTreeMap::new(), &MapOrigin::default()).unwrap();
        let e = r.need_number("diameter", 0).unwrap_err().to_string();
        assert!(e.contains("did you mean mm?"), "{e}");
    }
}

//! Recorded factors: the columns of a data file that a study declares as factors of the test
//! campaign (powder batch, laboratory, sintering temperature, loading rate …), read from the same
//! table and rows as the file's own fields.
//!
//! ```toml
//! factors = ["batch", "rate"]                          # types from the data
//! factors = { batch = "categorical", rate = "numeric" } # or declared
//! ```
//!
//! A column is found by its header, with or without its unit (`rate` finds `rate [mm/min]`). A
//! factor's type is the study's where it says it; in a list, a column of text is categorical and
//! a column of numbers numeric — except whole numbers with at most [`FEW_LEVELS`] distinct values
//! (codes of a batch or a lab?), which are refused with the question, never guessed. Every row
//! needs a value. Numbers are taken as written (a factor's coefficient is per unit of the column
//! as the file holds it).
//!
//! Used by strength files ([`crate::strength::specimens`]) and crush files (`factors` of a
//! study's `[[material]]`, [`crate::data::read_crush_source`]).

use std::collections::BTreeMap;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::units::{fold, parse_header};
use super::{ColumnRecord, MapOrigin, Provenance, RawTable};
use crate::error::{Error, Result};

/// A numeric column with at most this many distinct whole-number values is a possible code of
/// levels: the study must say whether it is numeric or categorical.
pub const FEW_LEVELS: usize = 6;

/// The type of a factor column, as a study declares it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FactorType {
    /// Numbers: linear and (where every value is > 0) power-law candidates.
    Numeric,
    /// Labels (or codes): one scale per level, one modulus per level.
    Categorical,
}

/// The factor columns of a data file: a list (types from the data) or a table of types.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Factors {
    /// `factors = ["lab", "rate"]`.
    Names(Vec<String>),
    /// `factors = { lab = "categorical", rate = "numeric" }`.
    Typed(BTreeMap<String, FactorType>),
}

impl Default for Factors {
    fn default() -> Self {
        Factors::Names(Vec::new())
    }
}

impl Factors {
    /// (column, declared type) pairs, in the study's order.
    pub fn declared(&self) -> Vec<(String, Option<FactorType>)> {
        match self {
            Factors::Names(v) => v.iter().map(|n| (n.clone(), None)).collect(),
            Factors::Typed(m) => m.iter().map(|(n, t)| (n.clone(), Some(*t))).collect(),
        }
    }

    /// Whether no factor is declared.
    pub fn is_empty(&self) -> bool {
        match self {
            Factors::Names(v) => v.is_empty(),
            Factors::Typed(m) => m.is_empty(),
        }
    }
}

/// The values of one factor column over the rows read.
#[derive(Debug, Clone, PartialEq)]
pub enum FactorValues {
    /// Numbers, as written.
    Numeric(Vec<f64>),
    /// Levels (text, trimmed).
    Levels(Vec<String>),
}

impl FactorValues {
    /// Keeps the values at `rows`, in that order.
    pub fn keep(&mut self, rows: &[usize]) {
        match self {
            FactorValues::Numeric(v) => *v = rows.iter().map(|&i| v[i]).collect(),
            FactorValues::Levels(v) => *v = rows.iter().map(|&i| v[i].clone()).collect(),
        }
    }

    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            FactorValues::Numeric(v) => v.len(),
            FactorValues::Levels(v) => v.len(),
        }
    }

    /// Whether there is no value.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The factor columns read from a file, in the study's order: (name as the study writes it,
/// values per row read).
pub type FactorColumns = Vec<(String, FactorValues)>;

/// The column of `table` a study's name refers to: the header itself, or the header whose
/// name without its unit folds to the same (`gauge length [mm]` for `gauge_length`).
pub fn find_column(headers: &[String], name: &str) -> Option<usize> {
    headers.iter().position(|h| h == name).or_else(|| {
        let want = fold(name);
        headers.iter().position(|h| fold(h) == want || fold(&parse_header(h).name) == want)
    })
}

/// The columns of `table` that `wanted` (study key, column name) name: each must exist, must not
/// be a column the reader already took as a field (`provenance.columns`), and must be named once.
pub fn declared_columns(table: &RawTable, provenance: &Provenance, wanted: &[(String, String)], origin: &MapOrigin, path: &Path) -> Result<Vec<(String, usize)>> {
    let used: Vec<usize> = provenance.columns.iter().filter_map(|c| table.headers.iter().position(|h| *h == c.source)).collect();
    let mut columns: Vec<(String, usize)> = Vec::new();
    for (key, name) in wanted {
        let Some(c) = find_column(&table.headers, name) else {
            let all = table.headers.iter().map(|h| format!("`{h}`")).collect::<Vec<_>>().join(", ");
            return Err(Error::config(&origin.file, key.clone(), format!("{} has no column `{name}` (its columns: {all})", path.display())));
        };
        if used.contains(&c) {
            let field = provenance.columns.iter().find(|x| x.source == table.headers[c]).map_or("a field", |x| x.field.as_str());
            let as_what = if field == table.headers[c] || field == name.as_str() { "as a factor".to_string() } else { format!("as the {}", field.replace('_', " ")) };
            return Err(Error::config(&origin.file, key.clone(), format!("`{name}` is already read {as_what}; each column is read once: name another column here, or take it off the other key")));
        }
        if let Some((other, _)) = columns.iter().find(|(_, k)| *k == c) {
            return Err(Error::config(&origin.file, key.clone(), format!("`{name}` is the same column as `{other}`: declare each column once")));
        }
        columns.push((name.clone(), c));
    }
    Ok(columns)
}

/// Reads the declared factor columns of `table` over `rows` (the rows the reader kept), typed as
/// declared or from the data (module docs); records each in `provenance` and takes it off the
/// unused columns. The study table that declares them is `origin`'s ([`table_key`]: for the
/// source `material[0].data` the factors are `material[0].factors.<name>`).
pub fn read_factors(table: &RawTable, rows: &[usize], factors: &Factors, provenance: &mut Provenance, origin: &MapOrigin, path: &Path) -> Result<FactorColumns> {
    let table_key = table_key(origin);
    let declared = factors.declared();
    let wanted: Vec<(String, String)> = declared.iter().map(|(name, _)| (format!("{table_key}.factors.{name}"), name.clone())).collect();
    let columns = declared_columns(table, provenance, &wanted, origin, path)?;
    let mut out = Vec::new();
    for ((name, kind), (_, c)) in declared.into_iter().zip(&columns) {
        let c = *c;
        let texts: Vec<Option<String>> = rows.iter().map(|&row| table.text(row, c)).collect();
        if let Some(i) = texts.iter().position(|t| t.is_none()) {
            return Err(table.error(rows[i], Some(c), format!("factor `{name}` is empty here: every row needs its value")));
        }
        let numeric: Option<Vec<f64>> = rows.iter().map(|&row| table.number(row, c).ok().flatten()).collect();
        let kind = match (kind, &numeric) {
            (Some(t), _) => t,
            (None, None) => FactorType::Categorical,
            (None, Some(v)) => {
                let mut distinct: Vec<f64> = v.clone();
                distinct.sort_by(f64::total_cmp);
                distinct.dedup();
                if distinct.len() <= FEW_LEVELS && distinct.iter().all(|x| x.fract() == 0.0) {
                    return Err(Error::config(
                        &origin.file,
                        format!("{table_key}.factors"),
                        format!("`{name}` holds {} distinct whole numbers ({}): codes of levels or a measured number? Say which: factors = {{ {name} = \"categorical\" }} or {{ {name} = \"numeric\" }}", distinct.len(), distinct.iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(", ")),
                    ));
                }
                FactorType::Numeric
            }
        };
        // A numeric factor keeps the file's unit; a categorical one's levels have none.
        let record = |unit: &str, what: &str| ColumnRecord { source: table.headers[c].clone(), field: name.clone(), unit: unit.into(), conversion: what.to_string(), found_by: "study".into() };
        match kind {
            FactorType::Numeric => {
                let v: Vec<f64> = rows.iter().map(|&row| table.need_number(row, c)).collect::<Result<_>>()?;
                provenance.columns.push(record("as in the file", "numeric factor"));
                out.push((name, FactorValues::Numeric(v)));
            }
            FactorType::Categorical => {
                let v: Vec<String> = texts.into_iter().map(|t| t.unwrap_or_default().trim().to_string()).collect();
                provenance.columns.push(record("", "categorical factor"));
                out.push((name, FactorValues::Levels(v)));
            }
        }
    }
    provenance.unused.retain(|u| !columns.iter().any(|(_, c)| table.headers[*c] == *u));
    Ok(out)
}

/// The study table that holds a data source: `material[0]` for the origin `material[0].data`.
pub fn table_key(origin: &MapOrigin) -> &str {
    origin.key.strip_suffix(".data").unwrap_or(&origin.key)
}

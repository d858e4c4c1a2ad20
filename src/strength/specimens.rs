//! Strength data as input: a file of specimen strengths (particles, pellets, bend bars, fibres —
//! the strength already computed) with an optional size measure and any number of recorded
//! factors, read through the intake like every other table.
//!
//! A study names the file and what its columns are (`[[strength]]` of a discrepancy study):
//!
//! ```toml
//! [[strength]]
//! key = "carbon"
//! label = "Carbon fibres (Bader & Priest 1982)"
//! data = { file = "../datasets/real/bader_priest_carbon_fibres.csv", units = { strength = "GPa" } }
//! size = { column = "gauge_length_mm", measure = "gauge_length" }
//! factors = { lab = "categorical", rate = "numeric" }   # or a list: factors = ["lab", "rate"]
//! ```
//!
//! * `strength` (required; a stress, any unit of the intake: `strength [MPa]`, `sigma_f_GPa`,
//!   or a unit declared in `units`) and the optional `id` and `material` columns are found like
//!   every field of the intake (study map, then name + unit). Every strength is checked against
//!   [`SPECIMEN_STRENGTH`].
//! * `size` and the factors are the file's own columns, named as in the header (with or
//!   without its unit: `gauge_length_mm` or `gauge length [mm]` for `gauge_length`). A size
//!   measure or numeric factor is taken as written: the size effect depends on ratios s/s̃
//!   only, and a numeric factor's β is per unit of the column as the file holds it.
//! * A factor's type is the study's where it says it; in a list, a column of text is
//!   categorical and a column of numbers numeric — except whole numbers with at most
//!   [`FEW_LEVELS`] distinct values (codes of a batch or a lab?), which are refused with the
//!   question, never guessed.
//!
//! Bad input is refused naming the file, row (and line), column and rule; exit 2.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::factors::{FEW_LEVELS, Factor, FactorType, Form, SizeMeasure, candidates_of};
use super::fit::Sample;
use crate::error::{Error, Result};
use crate::intake::units::{fold, parse_header};
use crate::intake::{ColumnRecord, Field, Kind, MapOrigin, Plausible, Provenance, Quantity, Source, read_raw, resolve, select};

/// Plausible specimen strength.
pub const SPECIMEN_STRENGTH: Plausible = Plausible {
    what: "specimen strength",
    lo: 1e4,
    hi: 1e11,
    shown: "[10 kPa, 100 GPa]",
    why: "from a weak green body to beyond the strongest fibre; outside it the value is in other units",
};

/// Fields of a strength file.
pub const STRENGTH_FIELDS: [Field; 3] = [
    Field { key: "id", column: "id", kind: Kind::Text, synonyms: &["specimen", "specimen_id", "sample", "sample_id"], required: false, plausible: None },
    Field { key: "material", column: "material", kind: Kind::Text, synonyms: &["grade"], required: false, plausible: None },
    Field {
        key: "strength",
        column: "strength_pa",
        kind: Kind::Number(Quantity::Stress),
        synonyms: &["strength", "fracture_strength", "fracture_stress", "breaking_strength", "tensile_strength", "flexural_strength", "sigma_f", "sigma", "σ", "σf", "stress_at_break"],
        required: true,
        plausible: Some(SPECIMEN_STRENGTH),
    },
];

/// A declared size measure.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SizeSpec {
    /// The column (as in the header, with or without its unit).
    pub column: String,
    /// What it measures (`effective_volume`, `effective_area`, `gauge_length`,
    /// `diameter_volume`, `diameter_surface`).
    pub measure: SizeMeasure,
}

/// The factor columns of a strength file: a list (types from the data) or a table of types.
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
}

/// A strength file read: ids, the sample (strengths in Pa, numeric and categorical columns,
/// candidates) and the intake's record.
#[derive(Debug, Clone)]
pub struct Specimens {
    /// The file.
    pub path: PathBuf,
    /// What the intake decided.
    pub provenance: Provenance,
    /// Specimen ids (the row's record line where the file has no id column).
    pub ids: Vec<String>,
    /// Strengths, covariates, levels and the generic candidates.
    pub sample: Sample,
}

/// The column of `table` a study's name refers to: the header itself, or the header whose
/// name without its unit folds to the same (`gauge length [mm]` for `gauge_length`).
fn find_column(headers: &[String], name: &str) -> Option<usize> {
    headers.iter().position(|h| h == name).or_else(|| {
        let want = fold(name);
        headers.iter().position(|h| fold(h) == want || fold(&parse_header(h).name) == want)
    })
}

/// Reads a strength file as `src` describes it, with the size measure and factor columns
/// a study declares. `origin` names the study table (`strength[0].data`) for messages.
pub fn read_specimens(src: &Source, size: Option<&SizeSpec>, factors: &Factors, origin: &MapOrigin) -> Result<Specimens> {
    let path = src.file.as_path();
    let table = read_raw(src)?;
    let r = resolve(&table, &STRENGTH_FIELDS, &src.columns, &src.units, origin)?;
    if table.rows.is_empty() {
        return Err(Error::data_file(path, "file", "no data rows"));
    }
    let (rows, filter) = select(&r, "material", src.material.as_deref(), origin, "material")?;
    let mut provenance = r.provenance.clone();
    provenance.rows = rows.len();
    provenance.filter = filter;

    let mut ids = Vec::with_capacity(rows.len());
    let mut seen: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    let mut strength = Vec::with_capacity(rows.len());
    for &row in &rows {
        let id = if r.has("id") { r.need_text("id", row)? } else { format!("line {}", table.lines[row]) };
        if r.has("id") {
            if let Some(&first) = seen.get(&id) {
                return Err(r.error(row, "id", format!("duplicate id \"{id}\" (also on {})", table.place(first, None))));
            }
            seen.insert(id.clone(), row);
        }
        ids.push(id);
        strength.push(r.need_number("strength", row)?);
    }

    // The declared columns: size first, then the factors.
    let mut wanted: Vec<(String, String)> = Vec::new(); // (study key, column)
    if let Some(s) = size {
        wanted.push((format!("{}.size.column", origin.key), s.column.clone()));
    }
    for (name, _) in factors.declared() {
        wanted.push((format!("{}.factors.{name}", origin.key), name));
    }
    let used: Vec<usize> = provenance.columns.iter().filter_map(|c| table.headers.iter().position(|h| *h == c.source)).collect();
    let mut columns: Vec<(String, usize)> = Vec::new();
    for (key, name) in &wanted {
        let Some(c) = find_column(&table.headers, name) else {
            let all = table.headers.iter().map(|h| format!("`{h}`")).collect::<Vec<_>>().join(", ");
            return Err(Error::config(&origin.file, key.clone(), format!("{} has no column `{name}` (its columns: {all})", path.display())));
        };
        if used.contains(&c) {
            return Err(Error::config(&origin.file, key.clone(), format!("`{name}` is the column read as the {}; a factor must be another column", provenance.columns.iter().find(|x| x.source == table.headers[c]).map_or("strength", |x| x.field.as_str()))));
        }
        if let Some((other, _)) = columns.iter().find(|(_, k)| *k == c) {
            return Err(Error::config(&origin.file, key.clone(), format!("`{name}` is the same column as `{other}`: declare each column once")));
        }
        columns.push((name.clone(), c));
    }

    let mut sample = Sample { source: path.display().to_string(), strength, ..Sample::default() };
    let numbers = |c: usize| -> Result<Vec<f64>> { rows.iter().map(|&row| table.need_number(row, c)).collect() };
    let record = |name: &str, c: usize, what: &str| ColumnRecord { source: table.headers[c].clone(), field: name.to_string(), unit: "as in the file".into(), conversion: what.to_string(), found_by: "study".into() };
    let mut k = 0;
    if let Some(s) = size {
        let c = columns[0].1;
        let v = numbers(c)?;
        if let Some(i) = v.iter().position(|x| !(*x > 0.0)) {
            return Err(table.error(rows[i], Some(c), format!("a size measure must be > 0 (got {})", v[i])));
        }
        sample.covariates.push((s.column.clone(), v.into_iter().map(Some).collect()));
        sample.factors.push(Factor { column: s.column.clone(), form: Form::Size(s.measure) });
        provenance.columns.push(record(&s.column, c, &format!("size measure: {} (ratios only)", s.measure.describe())));
        k = 1;
    }
    for ((name, declared), (_, c)) in factors.declared().into_iter().zip(&columns[k..]) {
        let c = *c;
        let texts: Vec<Option<String>> = rows.iter().map(|&row| table.text(row, c)).collect();
        if let Some(i) = texts.iter().position(|t| t.is_none()) {
            return Err(table.error(rows[i], Some(c), format!("factor `{name}` is empty here: every specimen needs its value")));
        }
        let numeric: Option<Vec<f64>> = rows.iter().map(|&row| table.number(row, c).ok().flatten()).collect();
        let kind = match (declared, &numeric) {
            (Some(t), _) => t,
            (None, None) => FactorType::Categorical,
            (None, Some(v)) => {
                let mut distinct: Vec<f64> = v.clone();
                distinct.sort_by(f64::total_cmp);
                distinct.dedup();
                if distinct.len() <= FEW_LEVELS && distinct.iter().all(|x| x.fract() == 0.0) {
                    return Err(Error::config(
                        &origin.file,
                        format!("{}.factors", origin.key),
                        format!("`{name}` holds {} distinct whole numbers ({}): codes of levels or a measured number? Say which: factors = {{ {name} = \"categorical\" }} or {{ {name} = \"numeric\" }}", distinct.len(), distinct.iter().map(|x| format!("{x}")).collect::<Vec<_>>().join(", ")),
                    ));
                }
                FactorType::Numeric
            }
        };
        match kind {
            FactorType::Numeric => {
                let v = numbers(c)?;
                let positive = v.iter().all(|x| *x > 0.0);
                sample.covariates.push((name.clone(), v.into_iter().map(Some).collect()));
                sample.factors.extend(candidates_of(&name, kind, positive));
                provenance.columns.push(record(&name, c, "numeric factor"));
            }
            FactorType::Categorical => {
                let v: Vec<String> = texts.into_iter().map(|t| t.unwrap_or_default().trim().to_string()).collect();
                sample.levels.push((name.clone(), v));
                sample.factors.extend(candidates_of(&name, kind, false));
                provenance.columns.push(record(&name, c, "categorical factor"));
            }
        }
    }
    provenance.unused.retain(|u| !columns.iter().any(|(_, c)| table.headers[*c] == *u));
    Ok(Specimens { path: path.to_path_buf(), provenance, ids, sample })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(body: &str, size: Option<SizeSpec>, factors: Factors, units: &[(&str, &str)]) -> Result<Specimens> {
        let dir = crate::io::TempDir::new("specimens").unwrap();
        let p = dir.path().join("s.csv");
        std::fs::write(&p, body).unwrap();
        let mut src = Source::file(&p);
        src.units = units.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
        read_specimens(&src, size.as_ref(), &factors, &MapOrigin { file: "study.toml".into(), key: "strength[0].data".into() })
    }

    #[test]
    fn reads_strengths_size_and_factors_with_their_types() {
        let body = "id;sigma_f [MPa];L [mm];batch;rate\nA;312,5;10;B1;0,5\nB;298;20;B2;1,5\nC;305;10;B1;2,5\nD;290;20;B2;3,5\n";
        let s = read(body, Some(SizeSpec { column: "L".into(), measure: SizeMeasure::GaugeLength }), Factors::Names(vec!["batch".into(), "rate".into()]), &[]).unwrap();
        assert_eq!(s.ids, ["A", "B", "C", "D"]);
        assert_eq!(s.sample.strength[0], 312.5e6);
        assert_eq!(s.sample.covariates[0], ("L".to_string(), vec![Some(10.0), Some(20.0), Some(10.0), Some(20.0)]));
        assert_eq!(s.sample.levels[0].1, ["B1", "B2", "B1", "B2"]);
        let names: Vec<String> = s.sample.factors.iter().map(|f| f.name()).collect();
        assert_eq!(names, ["size(L)", "levels(batch)", "moduli(batch)", "linear(rate)", "power(rate)"]);
        assert!(!s.sample.particles);
    }

    #[test]
    fn integer_codes_are_asked_about_and_missing_columns_named() {
        let body = "strength_pa,lab\n3e8,1\n3.1e8,2\n2.9e8,1\n";
        let e = read(body, None, Factors::Names(vec!["lab".into()]), &[]).unwrap_err().to_string();
        assert!(e.contains("strength[0].data.factors") && e.contains("codes of levels or a measured number"), "{e}");
        let ok = read(body, None, Factors::Typed([("lab".to_string(), FactorType::Categorical)].into()), &[]).unwrap();
        assert_eq!(ok.sample.levels[0].1, ["1", "2", "1"]);
        let e = read(body, None, Factors::Names(vec!["batch".into()]), &[]).unwrap_err().to_string();
        assert!(e.contains("strength[0].data.factors.batch") && e.contains("no column `batch`") && e.contains("`lab`"), "{e}");
        // A strength in GPa read as Pa is implausible and named with its row.
        let e = read("strength_pa\n1.2\n1.3\n", None, Factors::default(), &[]).unwrap_err().to_string();
        assert!(e.contains("specimen strength") && e.contains("row 1"), "{e}");
    }
}

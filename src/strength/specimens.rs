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
//! * What the rows say of their strengths — a `broken` column (specimens that did not break by
//!   the highest stress reached), strength classes (`interval = { lower, upper }`), a `count`
//!   column — is declared in the `data` table and never passed over
//!   ([`crate::intake::observed`]); a row counting k specimens becomes k specimens.
//!
//! Bad input is refused naming the file, row (and line), column and rule; exit 2.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::factors::{Factor, Form, SizeMeasure};
use super::fit::Sample;
use crate::error::{Error, Result};
use crate::obs::Observations;
pub use crate::intake::factors::{FEW_LEVELS, FactorType, Factors};
use crate::intake::factors::{declared_columns, read_factors, table_key};
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
pub const STRENGTH_FIELDS: [Field; 4] = [
    Field { key: "id", column: "id", kind: Kind::Text, synonyms: &["specimen", "specimen_id", "sample", "sample_id", "probe", "probennummer", "probennr", "nr"], required: false, plausible: None },
    Field { key: "material", column: "material", kind: Kind::Text, synonyms: &["grade"], required: false, plausible: None },
    Field {
        key: "strength",
        column: "strength_pa",
        kind: Kind::Number(Quantity::Stress),
        synonyms: &[
            "strength",
            "fracture_strength",
            "fracture_stress",
            "breaking_strength",
            "tensile_strength",
            "flexural_strength",
            "sigma_f",
            "sigma",
            "σ",
            "σf",
            "stress_at_break",
            // As German laboratories head them.
            "festigkeit",
            "bruchfestigkeit",
            "biegefestigkeit",
            "zugfestigkeit",
            "druckfestigkeit",
            "bruchspannung",
        ],
        required: true,
        plausible: Some(SPECIMEN_STRENGTH),
    },
    // Not `t`: a bend bar's thickness goes by it.
    Field { key: "temperature", column: "temperature_c", kind: Kind::Number(Quantity::Temperature), synonyms: &["temp", "test_temperature", "temperature", "temperatur", "prüftemperatur", "prueftemperatur"], required: false, plausible: Some(crate::intake::observed::TEMPERATURE) },
];

/// The strength's class ends, read in place of `strength` when the study declares `interval`.
pub const STRENGTH_ENDS: (Field, Field) = (
    Field { key: "strength_lower", column: "strength_lower_pa", kind: Kind::Number(Quantity::Stress), synonyms: &[], required: true, plausible: Some(SPECIMEN_STRENGTH) },
    Field { key: "strength_upper", column: "strength_upper_pa", kind: Kind::Number(Quantity::Stress), synonyms: &[], required: true, plausible: Some(SPECIMEN_STRENGTH) },
);

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

/// What a study's `[[strength]]` (or a crush file's `[[material]]`) table says of its file's
/// columns beside `data`: the size measure, the recorded factors and the failure-origin column
/// (`datasets check --study` reads the file with them, as the run does).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SetColumns {
    /// The size measure.
    pub size: Option<SizeSpec>,
    /// The recorded factors.
    pub factors: Factors,
    /// The failure-origin column.
    pub origin: Option<String>,
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
    /// Each specimen's test temperature (°C): its row's, else the study's `temperature_c`.
    pub temperatures_c: Vec<f64>,
    /// Each specimen's failure origin, where the study names the column (`origin = "…"`;
    /// empty otherwise).
    pub origins: Vec<String>,
}

/// Reads a strength file as `src` describes it, with the size measure and factor columns
/// a study declares. `origin` names the study table (`strength[0].data`) for messages.
pub fn read_specimens(src: &Source, size: Option<&SizeSpec>, factors: &Factors, origin: &MapOrigin) -> Result<Specimens> {
    read_specimens_with_origins(src, size, factors, None, origin)
}

/// [`read_specimens`] with each specimen's failure origin read from the column `origins`
/// (fractography: volume, surface, edge, pore …; an empty cell is refused).
pub fn read_specimens_with_origins(src: &Source, size: Option<&SizeSpec>, factors: &Factors, origins: Option<&str>, origin: &MapOrigin) -> Result<Specimens> {
    let path = src.file.as_path();
    let table = read_raw(src)?;
    // `T [°C]`: a `t` that states a temperature unit is the test temperature, not a thickness.
    let mapped;
    let named_t = crate::intake::observed::temperature_named_t(&table.headers, &src.columns);
    let src = match named_t.clone() {
        Some(h) => {
            mapped = Source { columns: src.columns.iter().map(|(k, v)| (k.clone(), v.clone())).chain([("temperature".to_string(), h)]).collect(), ..src.clone() };
            &mapped
        }
        None => src,
    };
    classes_undeclared(&table, src)?;
    let ((fields, columns, units), ends) = crate::intake::observed::fields_for(&table, &STRENGTH_FIELDS, "strength", STRENGTH_ENDS, src, origin)?;
    let r = resolve(&table, &fields, &columns, &units, origin)?;
    if table.rows.is_empty() {
        return Err(Error::data_file(path, "file", "no data rows"));
    }
    let (rows, filter) = select(&r, "material", src.material.as_deref(), origin, "material")?;
    let mut provenance = r.provenance.clone();
    if named_t.is_some() {
        crate::intake::observed::found_by_name(&mut provenance);
    }
    provenance.rows = rows.len();
    provenance.filter = filter;

    let values = crate::intake::observed::read_rows(&r, &rows, "strength", ends, src, origin, &mut provenance)?;
    let mut ids = Vec::with_capacity(rows.len());
    let mut seen: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    for &row in &rows {
        let id = if r.has("id") { r.need_text("id", row)? } else { format!("line {}", table.lines[row]) };
        if r.has("id") {
            if let Some(&first) = seen.get(&id) {
                return Err(r.error(row, "id", format!("duplicate id \"{id}\" (also on {})", table.place(first, None))));
            }
            seen.insert(id.clone(), row);
        }
        ids.push(id);
    }

    // The size measure first, then the factors (a factor may not be the size column).
    let mut sample = Sample { source: path.display().to_string(), strength: Observations::exact(values.iter().map(|v| v.value).collect()), ..Sample::default() };
    if let Some(s) = size {
        let c = declared_columns(&table, &provenance, &[(format!("{}.size.column", table_key(origin)), s.column.clone())], origin, path)?[0].1;
        let v: Vec<f64> = rows.iter().map(|&row| table.need_number(row, c)).collect::<Result<_>>()?;
        if let Some(i) = v.iter().position(|x| !(*x > 0.0)) {
            return Err(table.error(rows[i], Some(c), format!("a size measure must be > 0 (got {})", v[i])));
        }
        sample.covariates.push((s.column.clone(), v.into_iter().map(Some).collect()));
        sample.factors.push(Factor { column: s.column.clone(), form: Form::Size(s.measure) });
        provenance.columns.push(ColumnRecord { source: table.headers[c].clone(), field: s.column.clone(), unit: "as in the file".into(), conversion: format!("size measure: {} (ratios only)", s.measure.describe()), found_by: "study".into() });
        provenance.unused.retain(|u| *u != table.headers[c]);
    }
    let mut columns = read_factors(&table, &rows, factors, &mut provenance, origin, path)?;
    let (mut failure_origins, origin_column) = match origins {
        Some(col) => {
            let (o, c) = crate::intake::origins::failure_origins(&table, &rows, col, format!("{}.origin", table_key(origin)), origin, &mut provenance)?;
            (o, Some(c))
        }
        None => (Vec::new(), None),
    };
    let tc = r.column("temperature");
    let cells: Vec<Option<f64>> = rows.iter().map(|&row| r.number("temperature", row)).collect::<Result<_>>()?;
    let temperatures = crate::intake::observed::test_temperatures(&cells, &|k| table.place(rows[k], tc), tc.map(|c| format!("`{}`", table.headers[c])).as_deref(), src, origin, &mut provenance);
    // What the file must declare and a missing test temperature, in one message.
    // (a pile-up at the highest value is asked about once every column is declared: an undeclared
    // yes/no column is its likely cause)
    let undeclared = match crate::intake::undeclared::check_unused(&table, &rows, &mut provenance, src, origin) {
        Err(e) => Some(e),
        Ok(()) => crate::intake::observed::pile_up(&r, &rows, &values, "strength", src, origin, "strength").err(),
    };
    let mut temperatures_c = match (temperatures, undeclared) {
        (Ok(t), None) => t,
        (Ok(_), Some(e)) => return Err(e),
        (Err(t), Some(u)) => return Err(u.then(t)),
        (Err(t), None) => return Err(t),
    };
    // Rows counting several specimens become that many (ids `A#1` … `A#k`); then what the rows say.
    let named: Vec<String> = rows.iter().map(|&row| table.place(row, None)).collect();
    let sp = crate::intake::observed::specimens(&values, &named, src, &mut provenance, "specimens");
    if sp.rows.len() != rows.len() || sp.rows.iter().enumerate().any(|(i, &k)| i != k) {
        ids = sp.rows.iter().enumerate().map(|(i, &k)| sp.id(i, &ids[k])).collect();
        sample.covariates = sample.covariates.iter().map(|(n, v)| (n.clone(), sp.rows.iter().map(|&k| v[k]).collect())).collect();
        for (_, v) in columns.iter_mut() {
            v.keep(&sp.rows);
        }
        temperatures_c = sp.rows.iter().map(|&k| temperatures_c[k]).collect();
        if !failure_origins.is_empty() {
            failure_origins = sp.rows.iter().map(|&k| failure_origins[k].clone()).collect();
        }
    }
    // `none` is for a specimen that did not break: a break needs its origin.
    if let Some(c) = origin_column {
        if let Some((i, rule)) = crate::intake::origins::check_origins(sp.observations.view(), &mut failure_origins, &ids, &mut provenance) {
            return Err(table.error(rows[sp.rows[i]], Some(c), rule));
        }
    }
    sample.strength = sp.observations;
    sample.add_factors(&columns);
    Ok(Specimens { path: path.to_path_buf(), provenance, ids, sample, temperatures_c, origins: failure_origins })
}

/// The folded names a strength column goes by.
pub fn strength_names() -> Vec<String> {
    let f = &STRENGTH_FIELDS[2];
    [f.key, f.column].into_iter().chain(f.synonyms.iter().copied()).map(crate::intake::units::fold).collect()
}

/// Two stress columns and no strength column, and no `interval` declared: classes the study must
/// declare — refused with the key to write.
pub fn classes_undeclared(t: &crate::intake::RawTable, src: &Source) -> Result<()> {
    let stress: Vec<&String> = t.headers.iter().filter(|h| crate::intake::units::parse_header(h).unit.is_some_and(|u| crate::intake::units::unit_of(Quantity::Stress, &u).is_some())).collect();
    let names = strength_names();
    let named = t.headers.iter().any(|h| names.contains(&crate::intake::units::fold(&crate::intake::units::parse_header(h).name)));
    if src.interval.is_none() && !src.columns.contains_key("strength") && !named && stress.len() >= 2 {
        return Err(t.header_error(None, format!("holds stress columns {} and no strength column: if they are classes, say which ends they are in the study's data table: interval = {{ lower = \"{}\", upper = \"{}\" }} (and count = \"…\" for a column of specimens per class)", stress.iter().map(|h| format!("`{h}`")).collect::<Vec<_>>().join(", "), stress[0], stress[1])));
    }
    Ok(())
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
        src.temperature_c = Some(20.0);
        read_specimens(&src, size.as_ref(), &factors, &MapOrigin { file: "study.toml".into(), key: "strength[0].data".into() })
    }

    #[test]
    fn german_strength_and_temperature_headers_are_found_and_origins_are_read_and_checked() {
        let dir = crate::io::TempDir::new("specimens").unwrap();
        let p = dir.path().join("s.csv");
        std::fs::write(&p, "Probe;Festigkeit [MPa];Prüftemperatur [°C];Bruchursprung\nA;312,5;20;Volumen\nB;298;20;Kante\nC;305;800;Volumen\n").unwrap();
        let src = Source::file(&p);
        let at = MapOrigin { file: "study.toml".into(), key: "strength[0].data".into() };
        let s = read_specimens_with_origins(&src, None, &Factors::default(), Some("Bruchursprung"), &at).unwrap();
        assert_eq!(s.sample.strength.x, [312.5e6, 298e6, 305e6]);
        assert_eq!(s.temperatures_c, [20.0, 20.0, 800.0]);
        assert_eq!(s.origins, ["Volumen", "Kante", "Volumen"]);
        // `none` is for a specimen that did not break.
        std::fs::write(&p, "Probe;Festigkeit [MPa];Prüftemperatur [°C];Bruchursprung\nA;312,5;20;Volumen\nB;298;20;none\n").unwrap();
        let e = read_specimens_with_origins(&src, None, &Factors::default(), Some("Bruchursprung"), &at).unwrap_err().to_string();
        assert!(e.contains("row 2") && e.contains("Bruchursprung") && e.contains("failure origin `none` on a specimen that broke"), "{e}");
    }

    #[test]
    fn reads_strengths_size_and_factors_with_their_types() {
        let body = "id;sigma_f [MPa];L [mm];batch;rate\nA;312,5;10;B1;0,5\nB;298;20;B2;1,5\nC;305;10;B1;2,5\nD;290;20;B2;3,5\n";
        let s = read(body, Some(SizeSpec { column: "L".into(), measure: SizeMeasure::GaugeLength }), Factors::Names(vec!["batch".into(), "rate".into()]), &[]).unwrap();
        assert_eq!(s.ids, ["A", "B", "C", "D"]);
        assert_eq!(s.sample.strength.x[0], 312.5e6);
        assert_eq!(s.sample.covariates[0], ("L".to_string(), vec![Some(10.0), Some(20.0), Some(10.0), Some(20.0)]));
        assert_eq!(s.sample.levels[0].1, ["B1", "B2", "B1", "B2"]);
        let names: Vec<String> = s.sample.factors.iter().map(|f| f.name()).collect();
        assert_eq!(names, ["size(L)", "levels(batch)", "moduli(batch)", "linear(rate)", "power(rate)"]);
        assert!(!s.sample.particles);
    }

    #[test]
    fn a_strength_file_states_its_test_temperature_and_t_in_celsius_is_one() {
        let dir = crate::io::TempDir::new("specimens_t").unwrap();
        let origin = MapOrigin { file: "study.toml".into(), key: "strength[0].data".into() };
        let at = |body: &str, t: Option<f64>| {
            let p = dir.path().join("s.csv");
            std::fs::write(&p, body).unwrap();
            read_specimens(&Source { temperature_c: t, ..Source::file(&p) }, None, &Factors::default(), &origin)
        };
        let e = at("sigma_f [MPa]\n300\n310\n", None).unwrap_err().to_string();
        assert!(e.contains("states no test temperature") && e.contains("strength[0].data.temperature_c = 20"), "{e}");
        // With a count column to declare as well: both in one message.
        let e = at("sigma_f [MPa];Anzahl\n300;2\n310;1\n", None).unwrap_err().to_string();
        assert!(e.contains("column Anzahl: holds whole numbers") && e.contains("; and file: states no test temperature"), "{e}");
        assert_eq!(at("sigma_f [MPa]\n300\n310\n", Some(1000.0)).unwrap().temperatures_c, [1000.0, 1000.0]);
        // `T [°C]` is the test temperature; `t [mm]` (a bar's thickness) is not.
        assert_eq!(at("sigma_f [MPa];T [°C]\n300;20\n310;1200\n", None).unwrap().temperatures_c, [20.0, 1200.0]);
        let e = at("sigma_f [MPa];t [mm]\n300;3\n310;3\n", None).unwrap_err().to_string();
        assert!(e.contains("states no test temperature"), "{e}");
        // A count expands the temperatures with the specimens.
        let e = at("sigma_f [MPa];n;temperature_c\n300;2;20\n310;1;800\n", None).unwrap_err().to_string();
        assert!(e.contains("count = \"n\""), "{e}");
        let p = dir.path().join("s.csv");
        let s = read_specimens(&Source { count: Some("n".into()), ..Source::file(&p) }, None, &Factors::default(), &origin).unwrap();
        assert_eq!(s.temperatures_c, [20.0, 20.0, 800.0]);
    }

    #[test]
    fn integer_codes_are_asked_about_and_missing_columns_named() {
        let body = "strength_pa,lab\n3e8,1\n3.1e8,2\n2.9e8,1\n";
        let e = read(body, None, Factors::Names(vec!["lab".into()]), &[]).unwrap_err().to_string();
        assert!(e.contains("strength[0].factors") && e.contains("codes of levels or a measured number"), "{e}");
        let ok = read(body, None, Factors::Typed([("lab".to_string(), FactorType::Categorical)].into()), &[]).unwrap();
        assert_eq!(ok.sample.levels[0].1, ["1", "2", "1"]);
        let e = read(body, None, Factors::Names(vec!["batch".into()]), &[]).unwrap_err().to_string();
        assert!(e.contains("strength[0].factors.batch") && e.contains("no column `batch`") && e.contains("`lab`"), "{e}");
        // A strength in GPa read as Pa is implausible and named with its row.
        let e = read("strength_pa\n1.2\n1.3\n", None, Factors::default(), &[]).unwrap_err().to_string();
        assert!(e.contains("specimen strength") && e.contains("row 1"), "{e}");
    }
}

//! Datasets: single-particle crush records and the deliverable's Table 1.
//!
//! Files are read with polars as text (no type inference), then every cell is parsed and
//! checked here, so a bad cell produces one message naming the file, the data row (with its
//! physical line: the header is line 1) and the column, and the rule that was broken.
//!
//! # Crush CSV (one row per particle)
//!
//! | column | unit | rule |
//! |---|---|---|
//! | `id` | – | required, non-empty, unique |
//! | `material` | – | required, the same on every row |
//! | `diameter_m` | m | required, in [10⁻⁶, 0.1] ([`DIAMETER`]) |
//! | `crush_force_n` | N | required, in [10⁻⁶, 10⁵] ([`CRUSH_FORCE`]) |
//! | `roundness` | – | optional column; empty cell = unknown; else in [0.01, 1] ([`ROUNDNESS`]) |
//! | `sphericity` | – | optional column; empty cell = unknown; else in [0.01, 1] ([`SPHERICITY`]) |
//! | `temperature_c` | °C | optional column; empty cell = unknown; else in [−273.15, 2100] ([`TEMPERATURE`]) |
//! | `impacts` | – | optional column: impacts before the crush test; empty = unknown; else a whole number in [0, 10⁶] ([`IMPACTS`]) |
//!
//! Every numeric column of every input file has a plausibility range ([`Plausible`], listed
//! with the reasons in `datasets/README.md`): a value outside it is a unit slip or a corrupt
//! cell, and would otherwise travel on as an infinite contact radius or an underflowed strength.
//! The file's shape is checked before any cell ([`crate::io::read_input_text`]): a directory or
//! unreadable path is named as such, a duplicated column name and a row with fewer or more
//! fields than the header are errors naming the line.
//!
//! Verified by the unit tests below and `tests/bad_input.rs`.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use polars::prelude::*;

use crate::error::{Error, Result};

/// One crushed particle.
#[derive(Debug, Clone, PartialEq)]
pub struct CrushRecord {
    /// Particle identifier.
    pub id: String,
    /// Material label (`BL 16/30`).
    pub material: String,
    /// Diameter d (m).
    pub diameter_m: f64,
    /// Force at break F (N).
    pub crush_force_n: f64,
    /// Wadell roundness (-), if measured.
    pub roundness: Option<f64>,
    /// Sphericity B/L (-), if measured.
    pub sphericity: Option<f64>,
    /// Test temperature (°C), if recorded.
    pub temperature_c: Option<f64>,
    /// Impacts the particle received before the crush test, if recorded (optional column
    /// `impacts`; the synthetic generator writes it only with its `prior_impacts` option).
    pub impacts: Option<u64>,
}

/// A crush dataset read from one file.
#[derive(Debug, Clone, PartialEq)]
pub struct CrushData {
    /// Where it was read from.
    pub path: PathBuf,
    /// The particles, in file order.
    pub records: Vec<CrushRecord>,
}

impl CrushData {
    /// Material label (the same on every row).
    pub fn material(&self) -> &str {
        self.records.first().map(|r| r.material.as_str()).unwrap_or("")
    }
    /// Diameters (m).
    pub fn diameters(&self) -> Vec<f64> {
        self.records.iter().map(|r| r.diameter_m).collect()
    }
    /// Forces at break (N).
    pub fn forces(&self) -> Vec<f64> {
        self.records.iter().map(|r| r.crush_force_n).collect()
    }
}

/// The covariate columns of a crush file: what a strength model's effects and the discrepancy
/// workflow's residual trends can use.
pub const COVARIATE_COLUMNS: [&str; 5] = ["diameter_m", "roundness", "sphericity", "temperature_c", "impacts"];

/// Column names of a crush file, in canonical order.
pub const CRUSH_COLUMNS: [&str; 7] =
    ["id", "material", "diameter_m", "crush_force_n", "roundness", "sphericity", "temperature_c"];
const CRUSH_REQUIRED: [&str; 4] = ["id", "material", "diameter_m", "crush_force_n"];

/// The plausibility range of a numeric input column (closed), with the reason for it.
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

    /// v if it lies in the range, else an error naming file, row and column.
    pub fn check(&self, path: &Path, row: usize, column: &str, v: f64) -> Result<f64> {
        let finite = if v.is_finite() { "" } else { "a finite number " };
        if self.contains(v) { Ok(v) } else { Err(Error::data_row(path, row, column, format!("{} must be {finite}in {} ({}); got {}", self.what, self.shown, self.why, shown(v)))) }
    }
}

/// A number as a message shows it: plain in [10⁻⁴, 10⁶), else in scientific notation (1e308,
/// not 309 digits).
fn shown(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&v.abs()) { format!("{v}") } else { format!("{v:e}") }
}

/// Particle diameter.
pub const DIAMETER: Plausible = Plausible { what: "diameter", lo: 1e-6, hi: 0.1, shown: "[1e-6, 0.1] m", why: "a particle from 1 µm to 10 cm; outside it the value is in µm or mm, not metres" };
/// Force at break of a single-particle crush test.
pub const CRUSH_FORCE: Plausible = Plausible { what: "crush force", lo: 1e-6, hi: 1e5, shown: "[1e-6, 1e5] N", why: "from below any load cell's resolution to beyond any single-particle test; outside it the cell is corrupt or in other units" };
/// Wadell roundness.
pub const ROUNDNESS: Plausible = Plausible { what: "roundness", lo: 0.01, hi: 1.0, shown: "[0.01, 1]", why: "at most 1 by definition; below 0.01 the grain is a shard, and the contact curvature roundness^q leaves the floating-point range" };
/// Sphericity.
pub const SPHERICITY: Plausible = Plausible { what: "sphericity", lo: 0.01, hi: 1.0, shown: "[0.01, 1]", why: "at most 1 by definition; below 0.01 the grain is a needle or flake, not a flowing particle" };
/// Test temperature.
pub const TEMPERATURE: Plausible = Plausible { what: "temperature", lo: -273.15, hi: 2100.0, shown: "[-273.15, 2100] °C", why: "from absolute zero to the melting point of alumina (2072 °C), above which no ceramic particle is solid" };
/// Impacts before a crush test (also a whole number).
pub const IMPACTS: Plausible = Plausible { what: "impacts", lo: 0.0, hi: 1e6, shown: "[0, 1e6]", why: "10⁶ impacts are over a thousand years at 730 a year" };
/// Force of a crush curve sample (a small negative value is the load cell's zero offset).
pub const CURVE_FORCE: Plausible = Plausible { what: "force", lo: -1e3, hi: 1e5, shown: "[-1e3, 1e5] N", why: "a single-particle test; below −1 kN the load cell's zero is wrong, above 100 kN no particle is crushed" };
/// Impact (normal) speed of a particle on a tube.
pub const VELOCITY: Plausible = Plausible { what: "speed", lo: 0.0, hi: crate::lifetime::MAX_VELOCITY, shown: "[0, 100] m/s", why: "gravity-driven particle flows hit tubes at a few m/s; beyond 100 m/s the Hertz impact model is out of its range" };

/// Reads a CSV file with every column as text.
pub fn read_text_table(path: &Path) -> Result<DataFrame> {
    crate::io::read_csv(path, Some(0))
}

/// Text cells of one column (`None` for an empty cell); `None` if the column is absent.
pub(crate) fn text_column(df: &DataFrame, name: &str) -> Result<Option<Vec<Option<String>>>> {
    let Ok(col) = df.column(name) else { return Ok(None) };
    let ca = col.str().map_err(|e| Error::numerical("reading text column", e.to_string()))?;
    Ok(Some(
        ca.iter()
            .map(|v| v.map(str::trim).filter(|s| !s.is_empty()).map(str::to_owned))
            .collect(),
    ))
}

/// Parses a number cell; `rule` describes the admissible range for messages.
pub(crate) fn parse_number(path: &Path, row: usize, column: &str, cell: &str) -> Result<f64> {
    let v: f64 = cell
        .parse()
        .map_err(|_| Error::data_row(path, row, column, format!("value \"{cell}\" is not a number")))?;
    if !v.is_finite() {
        return Err(Error::data_row(path, row, column, format!("value \"{cell}\" is not a finite number")));
    }
    Ok(v)
}

/// Reads and validates a crush CSV (see the module docs for the rules).
pub fn read_crush(path: &Path) -> Result<CrushData> {
    let df = read_text_table(path)?;
    for c in CRUSH_REQUIRED {
        if df.column(c).is_err() {
            return Err(Error::data_file(
                path,
                "header",
                format!(
                    "missing column `{c}` (required: {}; optional: roundness, sphericity, temperature_c, impacts)",
                    CRUSH_REQUIRED.join(", ")
                ),
            ));
        }
    }
    if df.height() == 0 {
        return Err(Error::data_file(path, "file", "no data rows"));
    }
    let get = |name: &str| text_column(&df, name);
    let ids = get("id")?.unwrap_or_default();
    let materials = get("material")?.unwrap_or_default();
    let diam = get("diameter_m")?.unwrap_or_default();
    let force = get("crush_force_n")?.unwrap_or_default();
    let round = get("roundness")?;
    let spher = get("sphericity")?;
    let temp = get("temperature_c")?;
    let imp = get("impacts")?;

    let mut seen = HashSet::new();
    let mut records = Vec::with_capacity(df.height());
    for row in 0..df.height() {
        let need = |col: &[Option<String>], name: &str| -> Result<String> {
            col[row].clone().ok_or_else(|| Error::data_row(path, row, name, "cell is empty; a value is required"))
        };
        let id = need(&ids, "id")?;
        if !seen.insert(id.clone()) {
            return Err(Error::data_row(path, row, "id", format!("duplicate id \"{id}\"")));
        }
        let material = need(&materials, "material")?;
        if let Some(first) = records.first().map(|r: &CrushRecord| r.material.clone())
            && first != material
        {
            return Err(Error::data_row(
                path,
                row,
                "material",
                format!("one file holds one material: \"{material}\" differs from \"{first}\" on row 1"),
            ));
        }
        let d = DIAMETER.check(path, row, "diameter_m", parse_number(path, row, "diameter_m", &need(&diam, "diameter_m")?)?)?;
        let f = CRUSH_FORCE.check(path, row, "crush_force_n", parse_number(path, row, "crush_force_n", &need(&force, "crush_force_n")?)?)?;
        let optional = |col: &Option<Vec<Option<String>>>, name: &str, range: &Plausible| -> Result<Option<f64>> {
            match col.as_ref().and_then(|c| c[row].as_deref()) {
                None => Ok(None),
                Some(cell) => range.check(path, row, name, parse_number(path, row, name, cell)?).map(Some),
            }
        };
        let roundness = optional(&round, "roundness", &ROUNDNESS)?;
        let sphericity = optional(&spher, "sphericity", &SPHERICITY)?;
        let temperature_c = optional(&temp, "temperature_c", &TEMPERATURE)?;
        let impacts = optional(&imp, "impacts", &IMPACTS)?;
        if let Some(k) = impacts
            && k.fract() != 0.0
        {
            return Err(Error::data_row(path, row, "impacts", format!("impacts must be a whole number (got {k})")));
        }
        records.push(CrushRecord {
            id,
            material,
            diameter_m: d,
            crush_force_n: f,
            roundness,
            sphericity,
            temperature_c,
            impacts: impacts.map(|k| k as u64),
        });
    }
    Ok(CrushData { path: path.to_path_buf(), records })
}

/// Numeric properties of Table 1, each stored as `<name>_min`, `<name>_max`, `<name>_qualifier`.
pub const TABLE1_PROPERTIES: [&str; 15] = [
    "size_um",
    "cost_eur_per_kg",
    "cp_1000c_j_per_g_k",
    "bulk_density_g_cm3",
    "material_density_specific_g_cm3",
    "material_density_absolute_g_cm3",
    "softening_temperature_c",
    "vickers_hardness_hv01",
    "breaking_force_n",
    "sphericity",
    "roundness",
    "solar_absorptance",
    "thermal_emittance_900c",
    "delta_absorptance_4000h_1000c",
    "delta_emittance_900c_4000h_1000c",
];

/// One property cell of Table 1: bounds and qualifier (`<`, `>`, `~` or none).
#[derive(Debug, Clone, PartialEq)]
pub struct TableCell {
    /// Lower value (equal to `max` for a single value).
    pub min: Option<f64>,
    /// Upper value.
    pub max: Option<f64>,
    /// Qualifier of the transcribed cell.
    pub qualifier: Option<String>,
}

/// One row (material or the target column) of Table 1.
#[derive(Debug, Clone, PartialEq)]
pub struct Table1Row {
    /// Material name as in the deliverable (`BauxLite BL 16/30`), or `Target values`.
    pub material: String,
    /// `target`, `state_of_the_art` or `new_development`.
    pub group: String,
    /// Cells in the order of [`TABLE1_PROPERTIES`].
    pub cells: Vec<TableCell>,
    /// Free-text cells kept verbatim (`cp: Similar to Gen2`).
    pub notes: Option<String>,
}

/// Reads and validates `table1_particle_properties.csv`: numbers parse, min ≤ max, qualifiers
/// are one of `<`, `>`, `~`.
pub fn read_table1(path: &Path) -> Result<Vec<Table1Row>> {
    let df = read_text_table(path)?;
    let mut required = vec!["material".to_string(), "group".to_string(), "notes".to_string()];
    for p in TABLE1_PROPERTIES {
        for s in ["min", "max", "qualifier"] {
            required.push(format!("{p}_{s}"));
        }
    }
    for c in &required {
        if df.column(c).is_err() {
            return Err(Error::data_file(path, "header", format!("missing column `{c}`")));
        }
    }
    let col = |name: &str| -> Result<Vec<Option<String>>> { Ok(text_column(&df, name)?.unwrap_or_default()) };
    let materials = col("material")?;
    let groups = col("group")?;
    let notes = col("notes")?;
    let mut rows = Vec::new();
    for row in 0..df.height() {
        let material = materials[row]
            .clone()
            .ok_or_else(|| Error::data_row(path, row, "material", "cell is empty; a value is required"))?;
        let group = groups[row].clone().unwrap_or_default();
        if !["target", "state_of_the_art", "new_development"].contains(&group.as_str()) {
            return Err(Error::data_row(
                path,
                row,
                "group",
                format!("must be target, state_of_the_art or new_development (got \"{group}\")"),
            ));
        }
        let mut cells = Vec::new();
        for p in TABLE1_PROPERTIES {
            let num = |s: &str| -> Result<Option<f64>> {
                let name = format!("{p}_{s}");
                match col(&name)?[row].as_deref() {
                    None => Ok(None),
                    Some(c) => parse_number(path, row, &name, c).map(Some),
                }
            };
            let (min, max) = (num("min")?, num("max")?);
            if let (Some(a), Some(b)) = (min, max)
                && a > b
            {
                return Err(Error::data_row(path, row, &format!("{p}_min"), format!("min {a} exceeds max {b}")));
            }
            let qualifier = col(&format!("{p}_qualifier"))?[row].clone();
            if let Some(q) = &qualifier
                && !["<", ">", "~"].contains(&q.as_str())
            {
                return Err(Error::data_row(
                    path,
                    row,
                    &format!("{p}_qualifier"),
                    format!("must be <, > or ~ (got \"{q}\")"),
                ));
            }
            cells.push(TableCell { min, max, qualifier });
        }
        rows.push(Table1Row { material, group, cells, notes: notes[row].clone() });
    }
    Ok(rows)
}

/// What `partlife datasets check` found.
#[derive(Debug, Clone, PartialEq)]
pub enum CheckedFile {
    /// A crush dataset.
    Crush(CrushData),
    /// Table 1.
    Table1(Vec<Table1Row>),
}

/// Validates a dataset file, recognising its kind from its header.
pub fn check_file(path: &Path) -> Result<CheckedFile> {
    let df = read_text_table(path)?;
    if df.column("size_um_min").is_ok() {
        read_table1(path).map(CheckedFile::Table1)
    } else {
        read_crush(path).map(CheckedFile::Crush)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn write(dir: &Path, name: &str, body: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::File::create(&p).unwrap().write_all(body.as_bytes()).unwrap();
        p
    }

    #[test]
    fn reads_a_valid_file_with_optional_cells() {
        let dir = crate::io::TempDir::new("test").unwrap();
        let p = write(
            dir.path(),
            "a.csv",
            "id,material,diameter_m,crush_force_n,roundness\nA1,X,0.0009,120.5,0.8\nA2,X,0.001,99,\n",
        );
        let d = read_crush(&p).unwrap();
        assert_eq!(d.records.len(), 2);
        assert_eq!(d.records[1].roundness, None);
        assert_eq!(d.records[0].sphericity, None);
        assert_eq!(d.material(), "X");
    }

    #[test]
    fn errors_name_row_line_column_and_rule() {
        let dir = crate::io::TempDir::new("test").unwrap();
        let p = write(
            dir.path(),
            "b.csv",
            "id,material,diameter_m,crush_force_n\nA1,X,0.0009,120\nA2,X,abc,120\n",
        );
        let msg = read_crush(&p).unwrap_err().to_string();
        assert!(msg.contains("b.csv") && msg.contains("row 2 (line 3)") && msg.contains("diameter_m"), "{msg}");
        assert!(msg.contains("not a number"), "{msg}");
        let p = write(dir.path(), "c.csv", "id,material,diameter_m,crush_force_n\nA1,X,900,120\n");
        let msg = read_crush(&p).unwrap_err().to_string();
        assert!(msg.contains("metres"), "{msg}");
        let p = write(dir.path(), "d.csv", "id,material,diameter_m,crush_force_n\nA1,X,0.001,1\nA1,X,0.001,2\n");
        assert!(read_crush(&p).unwrap_err().to_string().contains("duplicate id"));
    }
}

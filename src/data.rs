//! Datasets: single-particle crush records and the deliverable's Table 1.
//!
//! Files are read with polars as text (no type inference), then every cell is parsed and
//! checked here, so a bad cell produces one message naming the file, the data row (with its
//! physical line: the header is line 1) and the column, and the rule that was broken.
//!
//! # Crush data (one row per particle)
//!
//! Read through [`crate::intake`]: delimited text in any delimiter, decimal mark and common
//! encoding, or one sheet of a spreadsheet; columns found by name with the unit the header
//! states (`diameter_m`, `D [mm]`, `Fmax (kN)`) or mapped by the study, converted to SI. The
//! fields ([`CRUSH_FIELDS`]; synonyms compared without case, blanks, `_`, `-` and `.`):
//!
//! | field | SI column | also found as | unit | rule |
//! |---|---|---|---|---|
//! | `id` | `id` | particle, particle_id, probe, sample, sample_id, specimen, nr | – | required, non-empty, unique |
//! | `material` | `material` | – | – | optional; a file with several materials needs the study's `material` filter |
//! | `diameter` | `diameter_m` | d, dp, particle_diameter | length | required, in [10⁻⁶, 0.1] m ([`DIAMETER`]) |
//! | `crush_force` | `crush_force_n` | f, fmax, force, load, breaking_force, peak_force, crushing_force | force | required, in [10⁻⁶, 10⁵] N ([`CRUSH_FORCE`]) |
//! | `roundness` | `roundness` | wadell_roundness | – or % | optional; empty cell = unknown; else in [0.01, 1] ([`ROUNDNESS`]) |
//! | `sphericity` | `sphericity` | b/l | – or % | optional; empty cell = unknown; else in [0.01, 1] ([`SPHERICITY`]) |
//! | `temperature` | `temperature_c` | t, temp, test_temperature | temperature | a number in [−273.15, 2100] °C ([`TEMPERATURE`]); no column or an empty cell: the study's `data.temperature_c`, else the file is refused |
//! | `impacts` | `impacts` | prior_impacts, n_impacts | count | optional: impacts before the crush test; empty = unknown; else a whole number in [0, 10⁶] ([`IMPACTS`]) |
//!
//! A second file joined by id (a shape analyser's export) may supply the optional fields
//! ([`read_crush_source`]); a field in both files is refused.
//!
//! What the rows say of their forces is declared by the study and never passed over
//! ([`crate::intake::observed`]): a `broken` column (a particle that did not break by the rig's
//! limit holds the highest force reached), force classes (`interval`), a `count` column, or
//! what the rows at the file's highest force are (`at_highest`). An undeclared yes/no or count
//! column, or a pile-up of rows at the highest force, is refused with the key to declare. A row
//! counting k particles becomes k particles (ids `A#1` … `A#k`).
//!
//! Every numeric column of every input file has a plausibility range ([`Plausible`], listed
//! with the reasons in `datasets/README.md`), in SI, applied after conversion: a value outside it
//! is a unit slip or a corrupt cell, and would otherwise travel on as an infinite contact radius
//! or an underflowed strength.
//!
//! Verified by the unit tests below and `tests/bad_input.rs`.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
pub use crate::intake::Plausible;
use crate::intake::columns::shown;
use crate::intake::{Field, JoinMode, Kind, MapOrigin, Provenance, Quantity, Source, join, read_raw, resolve, select};

/// One crushed particle.
#[derive(Debug, Clone, PartialEq)]
pub struct CrushRecord {
    /// Particle identifier.
    pub id: String,
    /// Material label (`BL 16/30`); empty when the file has no material column.
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

/// A crush dataset read from one file (and its shape file, if any).
#[derive(Debug, Clone, PartialEq)]
pub struct CrushData {
    /// Where it was read from.
    pub path: PathBuf,
    /// The particles, in file order.
    pub records: Vec<CrushRecord>,
    /// How it was read: format, columns, units and conversions, filter, join.
    pub provenance: Provenance,
    /// Where each record is in the file: (data row from 0, physical line or sheet row), for
    /// messages about it.
    pub places: Vec<(usize, usize)>,
    /// The sheet, for a spreadsheet.
    pub sheet: Option<String>,
    /// Several sheets read as one table: each table row's sheet (empty otherwise).
    pub row_sheets: Vec<String>,
    /// The factor columns the study declares (`factors` of its `[[material]]`), per record.
    pub factors: crate::intake::factors::FactorColumns,
    /// What the rows say of their forces, in newtons (None: every particle broke at its
    /// `crush_force_n`): a particle that did not break by the rig's limit, a force class
    /// ([`crate::obs`]; the study declares the columns: `broken`, `count`, `interval`).
    pub censoring: Option<crate::obs::Censoring>,
    /// Each particle's failure origin (fractography), where the study names the column
    /// (`origin = "…"` of a `[[material]]`); empty otherwise.
    pub origins: Vec<String>,
}

impl CrushData {
    /// Data made in code (a generator, a test): places as if written to `path` in partlife's own
    /// form, header on line 1.
    pub fn new(path: impl Into<PathBuf>, records: Vec<CrushRecord>) -> CrushData {
        let places = (0..records.len()).map(|k| (k, k + 2)).collect();
        CrushData { path: path.into(), records, provenance: Provenance::default(), places, sheet: None, row_sheets: Vec::new(), factors: Vec::new(), censoring: None, origins: Vec::new() }
    }

    /// The forces (N) as observations: each particle's `crush_force_n` with what its row says of
    /// it.
    pub fn observed(&self) -> crate::obs::Observations {
        crate::obs::Observations { x: self.forces(), censoring: self.censoring.clone() }
    }

    /// An error about record `k` and a column.
    pub fn error(&self, k: usize, column: &str, rule: impl Into<String>) -> Error {
        let sheet = self.places.get(k).and_then(|(row, _)| self.row_sheets.get(*row)).or(self.sheet.as_ref());
        let place = match (self.places.get(k), sheet) {
            (Some((row, line)), None) => format!("row {} (line {line})", row + 1),
            (Some((row, line)), Some(sheet)) => format!("sheet \"{sheet}\", row {} (sheet row {line})", row + 1),
            (None, _) => format!("particle {}", k + 1),
        };
        // The column as the file names it (`Fmax [N]` for crush_force_n).
        let named = self.provenance.columns.iter().find(|c| c.field == column).map_or(column, |c| c.source.as_str());
        Error::data_file(&self.path, format!("{place}, column {named}"), rule)
    }

    /// Material label (the same on every row; empty when the file has no material column).
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

/// Column names of a crush file in partlife's own SI form, in canonical order.
pub const CRUSH_COLUMNS: [&str; 7] =
    ["id", "material", "diameter_m", "crush_force_n", "roundness", "sphericity", "temperature_c"];

/// The fields of a crush file (module docs).
pub const CRUSH_FIELDS: [Field; 8] = [
    Field { key: "id", column: "id", kind: Kind::Text, synonyms: &["particle", "particle_id", "probe", "sample", "sample_id", "specimen", "nr", "probennummer", "probennr", "partikel", "partikelnummer"], required: true, plausible: None },
    Field { key: "material", column: "material", kind: Kind::Text, synonyms: &[], required: false, plausible: None },
    Field { key: "diameter", column: "diameter_m", kind: Kind::Number(Quantity::Length), synonyms: &["d", "dp", "particle_diameter", "durchmesser", "partikeldurchmesser", "korndurchmesser"], required: true, plausible: Some(DIAMETER) },
    Field { key: "crush_force", column: "crush_force_n", kind: Kind::Number(Quantity::Force), synonyms: &["f", "fmax", "force", "load", "breaking_force", "peak_force", "crushing_force", "bruchkraft", "bruchlast", "höchstkraft", "hoechstkraft", "maximalkraft", "druckkraft"], required: true, plausible: Some(CRUSH_FORCE) },
    Field { key: "roundness", column: "roundness", kind: Kind::Number(Quantity::Ratio), synonyms: &["wadell_roundness", "rundheit"], required: false, plausible: Some(ROUNDNESS) },
    Field { key: "sphericity", column: "sphericity", kind: Kind::Number(Quantity::Ratio), synonyms: &["b/l", "sphärizität", "sphaerizitaet"], required: false, plausible: Some(SPHERICITY) },
    Field { key: "temperature", column: "temperature_c", kind: Kind::Number(Quantity::Temperature), synonyms: &["t", "temp", "test_temperature", "temperatur", "prüftemperatur", "prueftemperatur"], required: false, plausible: Some(TEMPERATURE) },
    Field { key: "impacts", column: "impacts", kind: Kind::Number(Quantity::Count), synonyms: &["prior_impacts", "n_impacts"], required: false, plausible: Some(IMPACTS) },
];

/// The crush force's class ends, read in place of `crush_force` when the study declares
/// `interval` ([`crate::intake::observed`]).
pub const CRUSH_FORCE_ENDS: (Field, Field) = (
    Field { key: "crush_force_lower", column: "crush_force_lower_n", kind: Kind::Number(Quantity::Force), synonyms: &[], required: true, plausible: Some(CRUSH_FORCE) },
    Field { key: "crush_force_upper", column: "crush_force_upper_n", kind: Kind::Number(Quantity::Force), synonyms: &[], required: true, plausible: Some(CRUSH_FORCE) },
);

/// The fields a shape file may supply (joined by id): the optional measurements.
const JOINABLE: [&str; 4] = ["roundness", "sphericity", "temperature", "impacts"];

/// The fields of a shape file: an id, a material (for a filter), and the optional measurements
/// of a crush file.
pub const SHAPE_FIELDS: [Field; 6] = [CRUSH_FIELDS[0], CRUSH_FIELDS[1], CRUSH_FIELDS[4], CRUSH_FIELDS[5], CRUSH_FIELDS[6], CRUSH_FIELDS[7]];

/// Particle diameter.
pub const DIAMETER: Plausible = Plausible { what: "diameter", lo: 1e-6, hi: 0.1, shown: "[1e-6, 0.1] m", why: "a particle from 1 µm to 10 cm; outside it the value is in µm or mm, not metres" };
/// Force at break of a single-particle crush test.
pub const CRUSH_FORCE: Plausible = Plausible { what: "crush force", lo: 1e-6, hi: 1e5, shown: "[1e-6, 1e5] N", why: "from below any load cell's resolution to beyond any single-particle test; outside it the cell is corrupt or in other units" };
/// Wadell roundness.
pub const ROUNDNESS: Plausible = Plausible { what: "roundness", lo: 0.01, hi: 1.0, shown: "[0.01, 1]", why: "at most 1 by definition; below 0.01 the grain is a shard, and the contact curvature roundness^q leaves the floating-point range" };
/// Sphericity.
pub const SPHERICITY: Plausible = Plausible { what: "sphericity", lo: 0.01, hi: 1.0, shown: "[0.01, 1]", why: "at most 1 by definition; below 0.01 the grain is a needle or flake, not a flowing particle" };
/// Test temperature (the intake's, which checks a study's `temperature_c` against it).
pub use crate::intake::observed::TEMPERATURE;
/// Impacts before a crush test (also a whole number).
pub const IMPACTS: Plausible = Plausible { what: "impacts", lo: 0.0, hi: 1e6, shown: "[0, 1e6]", why: "10⁶ impacts are over a thousand years at 730 a year" };
/// Force of a crush curve sample (a small negative value is the load cell's zero offset).
pub const CURVE_FORCE: Plausible = Plausible { what: "force", lo: -1e3, hi: 1e5, shown: "[-1e3, 1e5] N", why: "a single-particle test; below −1 kN the load cell's zero is wrong, above 100 kN no particle is crushed" };
/// Impact (normal) speed of a particle on a tube.
pub const VELOCITY: Plausible = Plausible { what: "speed", lo: 0.0, hi: crate::lifetime::MAX_VELOCITY, shown: "[0, 100] m/s", why: "gravity-driven particle flows hit tubes at a few m/s; beyond 100 m/s the Hertz impact model is out of its range" };

/// The nominal tensile strength of a crushed particle, Hiramatsu & Oka (1966):
/// σ = 2.8 F / (π d²) (Pa; F in N, d in m) — the classic strength of an irregular particle
/// between platens, used here only to catch unit slips.
pub fn nominal_strength(force_n: f64, diameter_m: f64) -> f64 {
    2.8 * force_n / (std::f64::consts::PI * diameter_m * diameter_m)
}

/// The plausible nominal strength of a crushed ceramic particle ([`nominal_strength`]).
/// The Hertz σ̄ at break is checked too ([`SIGMA_BAR`]), but it grows only as F^(1/3): forces
/// entered in kN into a newton column lower σ̄ tenfold and stay plausible, while the nominal
/// strength falls a thousandfold, below any ceramic.
pub const NOMINAL_STRENGTH: Plausible = Plausible { what: "nominal strength 2.8F/(πd²) (Hiramatsu–Oka)", lo: 1e6, hi: 1e10, shown: "[1 MPa, 10 GPa]", why: "from the weakest porous granulate to beyond the strongest engineering ceramic" };

/// The plausible Hertz average tensile stress at break of a ceramic particle.
pub const SIGMA_BAR: Plausible = Plausible { what: "σ̄ at break", lo: 1e6, hi: 5e10, shown: "[1 MPa, 50 GPa]", why: "the Hertz average tensile stress at break of a ceramic, from a weak porous granulate to beyond diamond's tensile strength" };

/// Reads and validates a crush file with every default (module docs).
pub fn read_crush(path: &Path) -> Result<CrushData> {
    read_crush_source(&Source::file(path), &MapOrigin::default())
}

/// Reads and validates a crush file as a study describes it: sheet, header row, column map,
/// units, material filter and shape file ([`Source`]); `origin` names the study table for
/// errors in the map. Every data error names file, sheet, row and column.
pub fn read_crush_source(src: &Source, origin: &MapOrigin) -> Result<CrushData> {
    read_crush_with_factors(src, &crate::intake::factors::Factors::default(), None, origin)
}

/// [`read_crush_source`] with the factor columns a study declares for the file (`factors` of a
/// `[[material]]`; [`crate::intake::factors`]), read over the same rows (after the material
/// filter; a join by id keeps the factor values of the particles it keeps), and each particle's
/// failure origin from the column `failure_origin` names (`origin` of a `[[material]]`;
/// fractography: where the break started).
pub fn read_crush_with_factors(src: &Source, factor_spec: &crate::intake::factors::Factors, failure_origin: Option<&str>, origin: &MapOrigin) -> Result<CrushData> {
    let path = src.file.as_path();
    let table = read_raw(src)?;
    let ((fields, columns, units), ends) = crate::intake::observed::fields_for(&table, &CRUSH_FIELDS, "crush_force", CRUSH_FORCE_ENDS, src, origin)?;
    let r = resolve(&table, &fields, &columns, &units, origin)?;
    if table.rows.is_empty() {
        return Err(Error::data_file(path, table.origin.sheet.as_ref().map(|s| format!("sheet \"{s}\"")).unwrap_or_else(|| "file".into()), "no data rows"));
    }
    // The material filter applies to each file that has a material column; a main file
    // without one takes the filter's value as its particles' material.
    let wanted = src.material.as_deref();
    if wanted.is_some() && !r.has("material") && src.shape.is_none() {
        select(&r, "material", wanted, origin, "material")?;
    }
    let (rows, filter) = select(&r, "material", wanted.filter(|_| r.has("material")), origin, "material")?;
    let mut provenance = r.provenance.clone();
    provenance.rows = rows.len();
    provenance.filter = filter;
    let mut values = crate::intake::observed::read_rows(&r, &rows, "crush_force", ends, src, origin, &mut provenance)?;

    let mut seen: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    let mut records = Vec::with_capacity(rows.len());
    let mut places = Vec::with_capacity(rows.len());
    for (k, &row) in rows.iter().enumerate() {
        let id = r.need_text("id", row)?;
        if let Some(&first) = seen.get(&id) {
            return Err(r.error(row, "id", format!("duplicate id \"{id}\" (also on {})", table.place(first, None))));
        }
        seen.insert(id.clone(), row);
        let impacts = r.number("impacts", row)?;
        if let Some(k) = impacts
            && k.fract() != 0.0
        {
            return Err(r.error(row, "impacts", format!("impacts must be a whole number (got {k})")));
        }
        records.push(CrushRecord {
            id,
            material: r.text("material", row).or_else(|| wanted.map(str::to_string)).unwrap_or_default(),
            diameter_m: r.need_number("diameter", row)?,
            crush_force_n: values[k].value,
            roundness: r.number("roundness", row)?,
            sphericity: r.number("sphericity", row)?,
            temperature_c: r.number("temperature", row)?,
            impacts: impacts.map(|k| k as u64),
        });
        places.push((row, table.lines[row]));
        let rec = &records[records.len() - 1];
        for f in [rec.crush_force_n, values[k].upper].into_iter().filter(|f| f.is_finite()) {
            if let Some(rule) = NOMINAL_STRENGTH.broken(nominal_strength(f, rec.diameter_m)) {
                let key = ends.map_or("crush_force", |e| if f == rec.crush_force_n { e.lower } else { e.upper });
                return Err(r.error(row, key, format!("{rule}, from F = {} N and d = {} m: check the force and diameter units", shown(f), shown(rec.diameter_m))));
            }
        }
    }
    let mut factors = crate::intake::factors::read_factors(&table, &rows, factor_spec, &mut provenance, origin, path)?;
    let (mut origins, origin_column) = match failure_origin {
        Some(col) => {
            let (o, c) = crate::intake::origins::failure_origins(&table, &rows, col, format!("{}.origin", crate::intake::factors::table_key(origin)), origin, &mut provenance)?;
            (o, Some(c))
        }
        None => (Vec::new(), None),
    };
    // What the file must declare, said with a missing test temperature in one message.
    // (a pile-up at the highest value is asked about once every column is declared: an undeclared
    // yes/no column is its likely cause)
    let undeclared = match crate::intake::undeclared::check_unused(&table, &rows, &mut provenance, src, origin) {
        Err(e) => Some(e),
        Ok(()) => crate::intake::observed::pile_up(&r, &rows, &values, "crush_force", src, origin, "force").err(),
    };
    // The temperature column, of this file or (below) of the joined shape file.
    let mut temperature_column = r.column("temperature").map(|c| format!("`{}`", table.headers[c]));
    if let Some(shape) = &src.shape {
        let rows_of_ids: Vec<(usize, String)> = records.iter().enumerate().map(|(k, rec)| (k, rec.id.clone())).collect();
        let main_name = table.origin.sheet.as_ref().map(|s| format!("{} sheet \"{s}\"", path.display())).unwrap_or_else(|| path.display().to_string());
        let shape_origin = MapOrigin { file: origin.file.clone(), key: if origin.key.is_empty() { "shape".into() } else { format!("{}.shape", origin.key) } };
        let st = read_raw(shape)?;
        let sr = resolve(&st, &SHAPE_FIELDS, &shape.columns, &shape.units, &shape_origin)?;
        let supplied: Vec<&str> = JOINABLE.iter().copied().filter(|k| sr.has(k)).collect();
        if supplied.is_empty() {
            return Err(st.header_error(None, format!("the shape file supplies none of {}: nothing to join", JOINABLE.join(", "))));
        }
        if let Some(k) = supplied.iter().find(|k| r.has(k)) {
            return Err(st.header_error(sr.column(k), format!("{k} is in both {main_name} and this file: keep it in one, or map the other away")));
        }
        if wanted.is_some() && !r.has("material") && !sr.has("material") {
            select(&r, "material", wanted, origin, "material")?;
        }
        let (srows, sfilter) = select(&sr, "material", wanted.filter(|_| sr.has("material")), &shape_origin, "material")?;
        let (pairs, dropped) = join(&rows_of_ids, &sr, "id", &srows, shape.join.unwrap_or(JoinMode::Exact), &main_name)?;
        if let Some(c) = sr.column("temperature") {
            temperature_column = Some(format!("`{}` of {}", st.headers[c], shape.file.display()));
        }
        let mut joined = Vec::with_capacity(pairs.len());
        let mut joined_places = Vec::with_capacity(pairs.len());
        let kept: Vec<usize> = pairs.iter().map(|(k, _)| *k).collect();
        for (_, values) in factors.iter_mut() {
            values.keep(&kept);
        }
        if !origins.is_empty() {
            origins = kept.iter().map(|&k| origins[k].clone()).collect();
        }
        values = kept.iter().map(|&k| values[k]).collect();
        for (k, srow) in pairs {
            joined_places.push(places[k]);
            let mut rec = records[k].clone();
            for key in &supplied {
                let v = sr.number(key, srow)?;
                match *key {
                    "roundness" => rec.roundness = v,
                    "sphericity" => rec.sphericity = v,
                    "temperature" => rec.temperature_c = v,
                    _ => {
                        if let Some(x) = v
                            && x.fract() != 0.0
                        {
                            return Err(sr.error(srow, key, format!("impacts must be a whole number (got {x})")));
                        }
                        rec.impacts = v.map(|x| x as u64);
                    }
                }
            }
            joined.push(rec);
        }
        records = joined;
        places = joined_places;
        let mut sp = sr.provenance.clone();
        sp.rows = srows.len();
        sp.filter = sfilter;
        provenance.joined.push(sp);
        provenance.dropped_ids = dropped;
        provenance.rows = records.len();
        if records.is_empty() {
            return Err(Error::data_file(path, "file", "no particle is in both files: the join by id keeps nothing"));
        }
    }
    // Every particle's test temperature: its row's, else the study's.
    let temperatures = crate::intake::observed::test_temperatures(
        &records.iter().map(|rec| rec.temperature_c).collect::<Vec<_>>(),
        &|k| table.place(places[k].0, r.column("temperature")),
        temperature_column.as_deref(),
        src,
        origin,
        &mut provenance,
    );
    let temperatures = match (temperatures, undeclared) {
        (Ok(t), None) => t,
        (Ok(_), Some(e)) => return Err(e),
        (Err(t), Some(u)) => return Err(u.then(t)),
        (Err(t), None) => return Err(t),
    };
    for (rec, t) in records.iter_mut().zip(temperatures) {
        rec.temperature_c = Some(t);
    }
    // Rows counting several particles become that many; then what the rows say.
    let named: Vec<String> = places.iter().map(|(row, _)| table.place(*row, None)).collect();
    let sp = crate::intake::observed::specimens(&values, &named, src, &mut provenance, "particles");
    if sp.rows.len() != records.len() || sp.rows.iter().enumerate().any(|(i, &k)| i != k) {
        records = sp
            .rows
            .iter()
            .enumerate()
            .map(|(i, &k)| {
                let mut rec = records[k].clone();
                rec.id = sp.id(i, &rec.id);
                rec
            })
            .collect();
        places = sp.rows.iter().map(|&k| places[k]).collect();
        for (_, v) in factors.iter_mut() {
            v.keep(&sp.rows);
        }
        if !origins.is_empty() {
            origins = sp.rows.iter().map(|&k| origins[k].clone()).collect();
        }
    }
    // `none` is for a particle that did not break: a break needs its origin.
    if let Some(c) = origin_column
        && let Some((i, rule)) = crate::intake::origins::check_origins(sp.observations.view(), &mut origins, &records.iter().map(|r| r.id.clone()).collect::<Vec<_>>(), &mut provenance)
    {
        return Err(table.error(places[i].0, Some(c), rule));
    }
    let censoring = sp.observations.censoring;
    if records.is_empty() {
        return Err(Error::data_file(path, "file", "no particle is left: every row counts 0"));
    }
    for w in provenance.warnings.iter().chain(provenance.joined.iter().flat_map(|j| &j.warnings)) {
        crate::intake::warn(w);
    }
    Ok(CrushData { path: path.to_path_buf(), records, provenance, places, sheet: table.origin.sheet.clone(), row_sheets: table.row_sheets.clone(), factors, censoring, origins })
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

/// Reads and validates `table1_particle_properties.csv` (through [`crate::intake`]: any
/// delimiter, decimal mark or encoding, or a sheet): numbers parse, min ≤ max, qualifiers are
/// one of `<`, `>`, `~`.
pub fn read_table1(path: &Path) -> Result<Vec<Table1Row>> {
    let t = read_raw(&Source::file(path))?;
    let mut required = vec!["material".to_string(), "group".to_string(), "notes".to_string()];
    for p in TABLE1_PROPERTIES {
        for s in ["min", "max", "qualifier"] {
            required.push(format!("{p}_{s}"));
        }
    }
    let names: Vec<&str> = required.iter().map(String::as_str).collect();
    let cols = t.require(&names)?;
    let (c_material, c_group, c_notes) = (cols[0], cols[1], cols[2]);
    let mut rows = Vec::new();
    for row in 0..t.rows.len() {
        let material = t.need_text(row, c_material)?;
        let group = t.text(row, c_group).unwrap_or_default();
        if !["target", "state_of_the_art", "new_development"].contains(&group.as_str()) {
            return Err(t.error(row, Some(c_group), format!("must be target, state_of_the_art or new_development (got \"{group}\")")));
        }
        let mut cells = Vec::new();
        for (k, _) in TABLE1_PROPERTIES.iter().enumerate() {
            let (c_min, c_max, c_q) = (cols[3 + 3 * k], cols[4 + 3 * k], cols[5 + 3 * k]);
            let (min, max) = (t.number(row, c_min)?, t.number(row, c_max)?);
            if let (Some(a), Some(b)) = (min, max)
                && a > b
            {
                return Err(t.error(row, Some(c_min), format!("min {a} exceeds max {b}")));
            }
            let qualifier = t.text(row, c_q);
            if let Some(q) = &qualifier
                && !["<", ">", "~"].contains(&q.as_str())
            {
                return Err(t.error(row, Some(c_q), format!("must be <, > or ~ (got \"{q}\")")));
            }
            cells.push(TableCell { min, max, qualifier });
        }
        rows.push(Table1Row { material, group, cells, notes: t.text(row, c_notes) });
    }
    Ok(rows)
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
    fn every_particle_has_a_test_temperature_from_its_row_or_the_study() {
        let dir = crate::io::TempDir::new("temperature").unwrap();
        let origin = MapOrigin { file: "s.toml".into(), key: "material[1].data".into() };
        // No column and no key: refused, naming the key to declare.
        let p = write(dir.path(), "a.csv", "id,diameter_m,crush_force_n\nA1,0.0009,120.5\nA2,0.001,99\n");
        let e = read_crush_source(&Source::file(&p), &origin).unwrap_err().to_string();
        assert!(e.contains("a.csv") && e.contains("states no test temperature") && e.contains("material[1].data.temperature_c = 20"), "{e}");
        // The study's value for every row.
        let d = read_crush_source(&Source { temperature_c: Some(800.0), ..Source::file(&p) }, &origin).unwrap();
        assert!(d.records.iter().all(|r| r.temperature_c == Some(800.0)));
        assert!(d.provenance.observed.iter().any(|l| l == "test temperature: 800 °C (the study's material[1].data.temperature_c)"), "{:?}", d.provenance.observed);
        // A column with an empty cell: refused at that row; the study's value fills it.
        let p = write(dir.path(), "b.csv", "id,diameter_m,crush_force_n,T [°C]\nA1,0.0009,120.5,800\nA2,0.001,99,\nA3,0.001,90,20\n");
        let e = read_crush_source(&Source::file(&p), &origin).unwrap_err().to_string();
        assert!(e.contains("row 2 (line 3), column T [°C]") && e.contains("has no test temperature"), "{e}");
        let d = read_crush_source(&Source { temperature_c: Some(20.0), ..Source::file(&p) }, &origin).unwrap();
        assert_eq!(d.records.iter().map(|r| r.temperature_c.unwrap()).collect::<Vec<_>>(), [800.0, 20.0, 20.0]);
        assert!(d.provenance.observed.iter().any(|l| l == "test temperature: 20 °C (2) and 800 °C (1) (column `T [°C]`; 1 empty cells from the study's material[1].data.temperature_c)"), "{:?}", d.provenance.observed);
        // A column to declare and no test temperature: both in one message.
        let p = write(dir.path(), "c.csv", "id,diameter_m,crush_force_n,gebrochen\nA1,0.0009,120.5,ja\nA2,0.001,99,nein\nA3,0.001,90,ja\n");
        let e = read_crush_source(&Source::file(&p), &origin).unwrap_err().to_string();
        assert!(e.contains("c.csv") && e.contains("column gebrochen: holds yes/no") && e.contains("; and file: states no test temperature") && e.contains("material[1].data.temperature_c = 20"), "{e}");
        // A key outside the physical range is refused before reading.
        let e = Source { temperature_c: Some(-300.0), ..Source::file(&p) }.validate("s.toml", "material[1].data").unwrap_err().to_string();
        assert!(e.contains("material[1].data.temperature_c") && e.contains("[-273.15, 2100] °C"), "{e}");
    }

    #[test]
    fn reads_a_valid_file_with_optional_cells() {
        let dir = crate::io::TempDir::new("test").unwrap();
        let p = write(
            dir.path(),
            "a.csv",
            "id,material,diameter_m,crush_force_n,roundness,temperature_c\nA1,X,0.0009,120.5,0.8,20\nA2,X,0.001,99,,20\n",
        );
        let d = read_crush(&p).unwrap();
        assert_eq!(d.records.len(), 2);
        assert_eq!(d.records[1].roundness, None);
        assert_eq!(d.records[0].sphericity, None);
        assert_eq!(d.material(), "X");
    }

    #[test]
    fn german_headers_of_a_crush_export_are_recognised() {
        let dir = crate::io::TempDir::new("german").unwrap();
        let p = write(dir.path(), "b.csv", "Probe;Durchmesser [mm];Bruchkraft [N];Prüftemperatur [°C]\nA-1;1,5;55,3;800\nA-2;1,3;38,3;800\n");
        let d = read_crush(&p).unwrap();
        let want = [("A-1", 1.5e-3, 55.3), ("A-2", 1.3e-3, 38.3)];
        assert_eq!(d.records.len(), 2);
        for (r, (id, dm, f)) in d.records.iter().zip(want) {
            assert!(r.id == id && (r.diameter_m / dm - 1.0).abs() < 1e-12 && (r.crush_force_n / f - 1.0).abs() < 1e-12, "{r:?}");
        }
        assert!(d.provenance.unused.is_empty(), "{:?}", d.provenance.unused);
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
        let p = write(dir.path(), "d.csv", "id,material,diameter_m,crush_force_n\nA1,X,0.001,100\nA1,X,0.001,200\n");
        assert!(read_crush(&p).unwrap_err().to_string().contains("duplicate id"));
    }
}

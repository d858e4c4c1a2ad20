//! Phase-fraction tables: the equilibrium phases of a particle's composition against
//! temperature, from computational thermodynamics (Thermo-Calc, pycalphad), and the amorphous
//! fraction that the temperature model of the material parameters takes as its argument.
//!
//! The deliverable (§2, Fig. 2) computes the stable phases of a granulated composition with
//! Thermo-Calc and TCOXID: a corundum-type M₂O₃ phase (mostly Al₂O₃), a mullite-type
//! 2M₂O₃·SiO₂ phase, a pseudo-brookite phase, and a disordered (amorphous) fraction that starts to
//! rise around 900 °C and softens quickly.
//!
//! # File format
//!
//! CSV, one row per temperature and phase (the long form both tools export):
//!
//! | column | meaning |
//! |---|---|
//! | `temperature_c` or `temperature_k` | temperature, °C or K (exactly one of the two columns) |
//! | `phase` | the phase's name as the database spells it (`CORUNDUM`, `MULLITE`, …) |
//! | `volume_fraction`, `mole_fraction` or `mass_fraction` | the phase's fraction; the column's name states the basis (exactly one) |
//! | `amorphous` | optional: `true` for a disordered or glassy phase, `false` or empty otherwise |
//!
//! Rules, each refused with the file, row and rule (exit 2):
//! * temperatures lie above absolute zero; the rows of one temperature are contiguous and the
//!   temperatures increase down the file; at least two temperatures;
//! * each phase appears at most once per temperature; a phase not listed at a temperature has
//!   fraction 0 there;
//! * fractions are finite and ≥ 0 (values down to −10⁻⁹, solver round-off, are read as 0);
//! * at every temperature the fractions sum to 1 within [`SUM_TOLERANCE`]; they are then
//!   rescaled to sum to 1 exactly;
//! * a phase is spelled the same way in every row: two names that differ only in case, spaces,
//!   `_` or `-` are refused, and so is a phase whose `amorphous` flag changes between rows.
//!
//! # From Thermo-Calc and pycalphad
//!
//! * **Thermo-Calc** (Console mode, POLY: a stepped calculation in T, then `tabulate` of `NP(*)`,
//!   or Graphical mode's table of "amount of all phases" against temperature): `T` (K) →
//!   `temperature_k`, the phase name → `phase`, `NP(phase)` (moles of the phase per mole of
//!   system) → `mole_fraction`; `BPW(phase)` → `mass_fraction` instead. The liquid/glass phase
//!   of TCOXID (`IONIC_LIQ`) gets `amorphous = true`. Drop phases whose amount is 0 everywhere,
//!   or keep them with 0.
//! * **pycalphad**: `eq = equilibrium(db, comps, phases, {v.T: (…), v.P: 101325, v.N: 1, …})`,
//!   then `eq[["NP", "Phase"]].to_dataframe()` gives one row per T, vertex and phase; drop the
//!   rows whose `Phase` is empty, sum `NP` over the vertices of the same phase at each T
//!   (a miscibility gap gives two vertices of one phase), and rename `T` → `temperature_k`,
//!   `Phase` → `phase`, `NP` → `mole_fraction`.
//!
//! Between the tabulated temperatures the fractions are interpolated linearly; outside them
//! nothing is extrapolated ([`PhaseTable::at`] refuses).
//!
//! # Volume fractions
//!
//! The temperature law ([`crate::thermal::law`]) mixes crystalline and glassy behaviour by a
//! rule of mixtures, which is a rule in **volume** fractions. A table of volume fractions is used
//! as it is; mole or mass fractions are converted ([`PhaseTable::to_volume`]) with a per-phase
//! quantity the study declares with its source (`[phases]` of a temperature study):
//!
//! ```text
//! φ_i = x_i q_i / Σ_j x_j q_j,   q = molar volume V_m (mole fractions) or 1/ρ (mass fractions)
//! ```
//!
//! The molar volume is per mole as the table counts moles: Thermo-Calc's `NP` and pycalphad's
//! `NP` count moles of components (atoms) in the phase, so V_m = M/(ρ·n) for a formula unit of
//! molar mass M and n atoms. A table in mole or mass fractions without those quantities is
//! refused with what to declare: mixing mole fractions as volume fractions would be silently
//! wrong by the phases' ratio of molar volumes.

use std::path::{Path, PathBuf};

use crate::intake::{Field, Kind, MapOrigin, Provenance, Quantity, Source, read_raw, resolve};
use crate::error::{Error, Result};

/// The shipped illustrative table's file name in `datasets/`.
pub const ILLUSTRATIVE_FILE: &str = "phases_granulated_illustrative.csv";

/// How far the fractions at one temperature may sum from 1.
pub const SUM_TOLERANCE: f64 = 1e-3;

/// Negative fractions down to this are solver round-off and read as 0.
const ROUND_OFF: f64 = 1e-9;

/// 0 °C in kelvin.
const KELVIN: f64 = 273.15;

/// The basis of the fractions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    /// Volume fractions of phase (what a rule of mixtures takes).
    Volume,
    /// Mole fractions of phase.
    Mole,
    /// Mass fractions of phase.
    Mass,
}

impl Basis {
    /// The column that holds fractions of this basis.
    pub fn column(self) -> &'static str {
        match self {
            Basis::Volume => "volume_fraction",
            Basis::Mole => "mole_fraction",
            Basis::Mass => "mass_fraction",
        }
    }

    /// In words ("mole fractions").
    pub fn words(self) -> &'static str {
        match self {
            Basis::Volume => "volume fractions",
            Basis::Mole => "mole fractions",
            Basis::Mass => "mass fractions",
        }
    }
}

/// What converts a table's mole or mass fractions to volume fractions: per phase, its molar
/// volume (m³/mol, as the table counts moles) or its density (kg/m³), and the study key that
/// declared them (the study requires their source next to them).
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeConversion {
    /// Per phase name, q_i: the molar volume (mole basis) or the density (mass basis).
    pub per_phase: std::collections::BTreeMap<String, f64>,
    /// The key that held them (for messages): `phases.molar_volume_m3_mol`, say.
    pub key: String,
}

/// A validated phase-fraction table.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseTable {
    /// The file it was read from (empty for a generated table).
    pub path: PathBuf,
    /// The basis of the fractions.
    pub basis: Basis,
    /// The basis the file held (≠ `basis` after [`PhaseTable::to_volume`] converted it).
    pub file_basis: Basis,
    /// Temperatures (°C), increasing.
    pub temperatures_c: Vec<f64>,
    /// Phase names, in order of first appearance.
    pub phases: Vec<String>,
    /// Whether each phase is amorphous.
    pub amorphous: Vec<bool>,
    /// Fractions, per temperature and phase (each row sums to 1).
    pub fractions: Vec<Vec<f64>>,
}

/// A phase name reduced to what tells phases apart: lower case without spaces, `_` and `-`.
fn folded(name: &str) -> String {
    name.chars().filter(|c| !matches!(c, ' ' | '_' | '-')).flat_map(char::to_lowercase).collect()
}

/// The fields of a phase-fraction table.
pub const PHASE_FIELDS: [Field; 6] = [
    Field { key: "temperature", column: "temperature_c", kind: Kind::Number(Quantity::Temperature), synonyms: &["t"], required: true, plausible: None },
    Field { key: "phase", column: "phase", kind: Kind::Text, synonyms: &[], required: true, plausible: None },
    Field { key: "volume_fraction", column: "volume_fraction", kind: Kind::Number(Quantity::Ratio), synonyms: &[], required: false, plausible: None },
    Field { key: "mole_fraction", column: "mole_fraction", kind: Kind::Number(Quantity::Ratio), synonyms: &[], required: false, plausible: None },
    Field { key: "mass_fraction", column: "mass_fraction", kind: Kind::Number(Quantity::Ratio), synonyms: &[], required: false, plausible: None },
    Field { key: "amorphous", column: "amorphous", kind: Kind::Text, synonyms: &[], required: false, plausible: None },
];

/// Reads and validates a phase-fraction table (module docs: format and rules), through
/// [`crate::intake`] (any delimiter, decimal mark and encoding, or a sheet; the temperature in
/// °C or K, `temperature_c`, `temperature_k`, `T [K]`).
pub fn read_phases(path: &Path) -> Result<PhaseTable> {
    read_phases_source(&Source::file(path)).map(|(t, _)| t)
}

/// [`read_phases`] as a study describes the file, with the record of how it was read.
pub fn read_phases_source(src: &Source) -> Result<(PhaseTable, Provenance)> {
    let path = src.file.as_path();
    src.refuse_rows(&path.display().to_string(), "data", "a phase-fraction table")?;
    let raw = read_raw(src)?;
    let r = resolve(&raw, &PHASE_FIELDS, &src.columns, &src.units, &MapOrigin::default())?;
    let bases: Vec<Basis> = [Basis::Volume, Basis::Mole, Basis::Mass].into_iter().filter(|b| r.has(b.column())).collect();
    let basis = match bases.as_slice() {
        [b] => *b,
        [] => return Err(raw.header_error(None, "missing column `volume_fraction`, `mole_fraction` or `mass_fraction` (the column's name states the basis)")),
        _ => return Err(raw.header_error(None, format!("{}: one file holds one basis", bases.iter().map(|b| format!("`{}`", b.column())).collect::<Vec<_>>().join(" and ")))),
    };
    let key = basis.column();
    if raw.rows.is_empty() {
        return Err(Error::data_file(path, "file", "no data rows"));
    }
    let t_col = raw.headers[r.column("temperature").unwrap_or(0)].clone();

    let mut table = PhaseTable { path: path.to_path_buf(), basis, file_basis: basis, temperatures_c: Vec::new(), phases: Vec::new(), amorphous: Vec::new(), fractions: Vec::new() };
    // The row each temperature starts at, and each phase's first row.
    let (mut starts, mut first_row): (Vec<usize>, Vec<usize>) = (Vec::new(), Vec::new());
    let mut names: Vec<String> = Vec::new();
    for row in 0..raw.rows.len() {
        let t = r.need_number("temperature", row)?;
        let shown_t = r.text("temperature", row).unwrap_or_default();
        if !(t.is_finite() && t > -KELVIN) {
            return Err(r.error(row, "temperature", format!("{shown_t} lies at or below absolute zero (−273.15 °C, 0 K)")));
        }
        let name = r.need_text("phase", row)?;
        names.push(name.clone());
        let value = r.need_number(key, row)?;
        if !value.is_finite() || value < -ROUND_OFF {
            return Err(r.error(row, key, format!("a fraction must be finite and ≥ 0, got {value}")));
        }
        let amorphous = match r.text("amorphous", row) {
            None => false,
            Some(v) => match v.to_ascii_lowercase().as_str() {
                "true" | "1" | "yes" => true,
                "false" | "0" | "no" => false,
                _ => return Err(r.error(row, "amorphous", format!("must be true or false, got \"{v}\""))),
            },
        };
        // A new temperature starts a new block; it must be above the previous one.
        if table.temperatures_c.last() != Some(&t) {
            if let Some(&prev) = table.temperatures_c.last()
                && t <= prev
            {
                return Err(r.error(row, "temperature", format!("temperatures must increase down the file, with the rows of one temperature together: {shown_t} ({t} °C) after {prev} °C")));
            }
            table.temperatures_c.push(t);
            table.fractions.push(vec![0.0; table.phases.len()]);
            starts.push(row);
        }
        let p = match table.phases.iter().position(|n| *n == name) {
            Some(p) => {
                if table.amorphous[p] != amorphous {
                    return Err(r.error(row, "amorphous", format!("phase \"{name}\" is {} here but {} on row {}: a phase is amorphous or not at every temperature", if amorphous { "amorphous" } else { "not amorphous" }, if amorphous { "not amorphous" } else { "amorphous" }, first_row[p] + 1)));
                }
                p
            }
            None => {
                if let Some(q) = table.phases.iter().position(|n| folded(n) == folded(&name)) {
                    return Err(r.error(row, "phase", format!("\"{name}\" differs from \"{}\" (row {}) only in case, spaces, '_' or '-': spell each phase the same way at every temperature", table.phases[q], first_row[q] + 1)));
                }
                table.phases.push(name.clone());
                table.amorphous.push(amorphous);
                first_row.push(row);
                table.fractions.iter_mut().for_each(|f| f.push(0.0));
                table.phases.len() - 1
            }
        };
        let block = table.fractions.last_mut().expect("a block was started");
        if (starts[starts.len() - 1]..row).any(|q| names[q] == name) {
            return Err(r.error(row, "phase", format!("phase \"{name}\" appears twice at {shown_t} ({t_col})")));
        }
        block[p] = value.max(0.0);
    }
    if table.temperatures_c.len() < 2 {
        return Err(Error::data_file(path, "file", "needs at least two temperatures"));
    }
    for (b, f) in table.fractions.iter_mut().enumerate() {
        let sum: f64 = f.iter().sum();
        if (sum - 1.0).abs() > SUM_TOLERANCE {
            let (row, t) = (starts[b], table.temperatures_c[b]);
            return Err(r.error(row, key, format!("the fractions at {t} °C sum to {sum:.6}, not 1 within {SUM_TOLERANCE} (rows {}–{})", row + 1, starts.get(b + 1).map_or(raw.rows.len(), |&s| s))));
        }
        f.iter_mut().for_each(|x| *x /= sum);
    }
    let mut provenance = r.provenance.clone();
    for w in &provenance.warnings {
        crate::intake::warn(w);
    }
    provenance.rows = raw.rows.len();
    Ok((table, provenance))
}

impl PhaseTable {
    /// The tabulated temperature range (°C).
    pub fn range(&self) -> (f64, f64) {
        (self.temperatures_c[0], self.temperatures_c[self.temperatures_c.len() - 1])
    }

    /// The sum of the amorphous phases' fractions in `fractions` (one per phase).
    fn amorphous_of(&self, fractions: &[f64]) -> f64 {
        fractions.iter().zip(&self.amorphous).filter(|(_, a)| **a).map(|(x, _)| x).sum()
    }

    /// The amorphous fraction at every tabulated temperature.
    pub fn amorphous_fractions(&self) -> Vec<f64> {
        self.fractions.iter().map(|f| self.amorphous_of(f)).collect()
    }

    /// Every phase's fraction at `t_c` °C, interpolated linearly; a temperature outside the
    /// table is refused (nothing is extrapolated).
    pub fn at(&self, t_c: f64) -> Result<Vec<f64>> {
        let (lo, hi) = self.range();
        if !(t_c >= lo && t_c <= hi) {
            return Err(Error::numerical("phase fractions", format!("{t_c} °C lies outside the phase table {} ({lo}–{hi} °C)", self.path.display())));
        }
        let j = self.temperatures_c.partition_point(|&t| t <= t_c).clamp(1, self.temperatures_c.len() - 1);
        let (t0, t1) = (self.temperatures_c[j - 1], self.temperatures_c[j]);
        let w = (t_c - t0) / (t1 - t0);
        Ok(self.fractions[j - 1].iter().zip(&self.fractions[j]).map(|(a, b)| a + w * (b - a)).collect())
    }

    /// The amorphous fraction at `t_c` °C ([`PhaseTable::at`]).
    pub fn amorphous_at(&self, t_c: f64) -> Result<f64> {
        Ok(self.amorphous_of(&self.at(t_c)?))
    }

    /// The lowest tabulated temperature at which the amorphous fraction exceeds `level`, if any.
    pub fn amorphous_onset(&self, level: f64) -> Option<f64> {
        self.amorphous_fractions().iter().position(|&f| f > level).map(|i| self.temperatures_c[i])
    }

    /// The table in volume fractions (module docs): as it is when it holds volume fractions;
    /// else converted with `conversion` (molar volumes for mole fractions, densities for mass
    /// fractions). Refused, naming what to declare, when the table needs a conversion and none
    /// is given, when a phase with a non-zero fraction lacks its value, or when a value is not
    /// finite and positive.
    /// `file` is the study file that declares the table (for messages).
    pub fn to_volume(&self, file: &str, conversion: Option<&VolumeConversion>) -> Result<PhaseTable> {
        let (what, unit, example) = match self.basis {
            Basis::Volume => return Ok(self.clone()),
            Basis::Mole => ("molar volume", "m³ per mole as the table counts moles", "molar_volume_m3_mol"),
            Basis::Mass => ("density", "kg/m³", "density_kg_m3"),
        };
        let used: Vec<&String> = self.phases.iter().enumerate().filter(|(p, _)| self.fractions.iter().any(|f| f[*p] > 0.0)).map(|(_, n)| n).collect();
        let Some(c) = conversion else {
            return Err(Error::config(
                file,
                "phases.file",
                format!(
                    "{} holds {} (column `{}`), and the temperature law mixes phases by volume (a rule of mixtures): declare each phase's {what} ({unit}) in the temperature study's [phases] {example} = {{ {} }} with its `source`, or give volume fractions (a `volume_fraction` column)",
                    self.path.display(),
                    self.basis.words(),
                    self.basis.column(),
                    used.iter().map(|n| format!("{n} = …")).collect::<Vec<_>>().join(", ")
                ),
            ));
        };
        let missing: Vec<&&String> = used.iter().filter(|n| !c.per_phase.contains_key(n.as_str())).collect();
        if !missing.is_empty() {
            return Err(Error::config(file, &c.key, format!("lacks the {what} of {} (phases of the table with a non-zero fraction)", missing.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(", "))));
        }
        if let Some((n, v)) = c.per_phase.iter().find(|(_, v)| !(v.is_finite() && **v > 0.0)) {
            return Err(Error::config(file, &c.key, format!("the {what} of \"{n}\" must be finite and > 0, got {v}")));
        }
        let q: Vec<f64> = self
            .phases
            .iter()
            .map(|n| {
                let v = c.per_phase.get(n).copied().unwrap_or(1.0);
                if self.basis == Basis::Mass { 1.0 / v } else { v }
            })
            .collect();
        let fractions = self
            .fractions
            .iter()
            .map(|f| {
                let v: Vec<f64> = f.iter().zip(&q).map(|(x, q)| x * q).collect();
                let total: f64 = v.iter().sum();
                v.iter().map(|x| x / total).collect()
            })
            .collect();
        Ok(PhaseTable { basis: Basis::Volume, fractions, ..self.clone() })
    }

    /// The table as CSV (`temperature_c`, `phase`, the basis column, `amorphous`), every phase at
    /// every temperature, fractions to 6 decimals.
    pub fn to_csv(&self) -> String {
        let mut s = format!("temperature_c,phase,{},amorphous\n", self.basis.column());
        for (t, f) in self.temperatures_c.iter().zip(&self.fractions) {
            for ((name, x), a) in self.phases.iter().zip(f).zip(&self.amorphous) {
                s.push_str(&format!("{t},{name},{x:.6},{a}\n"));
            }
        }
        s
    }
}

/// The shipped illustrative table (`datasets/phases_granulated_illustrative.csv`): **not
/// computed** — a shape that follows the deliverable's text, made by this rule:
///
/// * temperatures 20 °C, then 50–1400 °C in steps of 50 °C; volume fractions (the basis the
///   temperature law mixes in; the table is illustrative, so no conversion is pretended);
/// * amorphous phase `IONIC_LIQ`: f_a = 0 up to 880 °C, then f_a = 0.30 · s((T − 880)/300) with
///   the smoothstep s(x) = 3x² − 2x³ (x clipped to [0, 1]), so it starts to rise around 900 °C
///   and reaches 0.30 at 1180 °C;
/// * crystalline phases at low temperature: `CORUNDUM` 0.55, `MULLITE` 0.30,
///   `PSEUDO_BROOKITE` 0.15; the amorphous phase takes half of its fraction from pseudo-brookite
///   and half from corundum and mullite in proportion to their low-temperature fractions
///   (pseudo-brookite is used up exactly at f_a = 0.30).
pub fn illustrative() -> PhaseTable {
    let temperatures_c: Vec<f64> = std::iter::once(20.0).chain((1..=28).map(|k| 50.0 * k as f64)).collect();
    let fractions = temperatures_c
        .iter()
        .map(|&t| {
            let x: f64 = ((t - 880.0) / 300.0).clamp(0.0, 1.0);
            let fa = 0.30 * x * x * (3.0 - 2.0 * x);
            let half = 0.5 * fa;
            vec![0.55 - half * 0.55 / 0.85, 0.30 - half * 0.30 / 0.85, 0.15 - half, fa]
        })
        .collect();
    PhaseTable {
        path: PathBuf::new(),
        basis: Basis::Volume,
        file_basis: Basis::Volume,
        temperatures_c,
        phases: ["CORUNDUM", "MULLITE", "PSEUDO_BROOKITE", "IONIC_LIQ"].map(String::from).to_vec(),
        amorphous: vec![false, false, false, true],
        fractions,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(body: &str) -> (crate::io::TempDir, PathBuf) {
        let dir = crate::io::TempDir::new("phases").unwrap();
        let p = dir.path().join("phases.csv");
        std::fs::write(&p, body).unwrap();
        (dir, p)
    }

    #[test]
    fn reads_kelvin_mass_fractions_and_interpolates() {
        let (_d, p) = write("temperature_k,phase,mass_fraction,amorphous\n1073.15,A,0.7,\n1073.15,GLASS,0.3,true\n1273.15,A,0.5,false\n1273.15,GLASS,0.5,true\n1373.15,GLASS,1.0,true\n");
        let t = read_phases(&p).unwrap();
        assert_eq!(t.basis, Basis::Mass);
        assert_eq!(t.phases, ["A", "GLASS"]);
        assert!((t.temperatures_c[0] - 800.0).abs() < 1e-9 && (t.temperatures_c[2] - 1100.0).abs() < 1e-9);
        // Not listed at 1100 °C: 0.
        assert_eq!(t.fractions[2], [0.0, 1.0]);
        assert!((t.amorphous_at(900.0).unwrap() - 0.4).abs() < 1e-12);
        assert!((t.at(1050.0).unwrap()[0] - 0.25).abs() < 1e-12);
        assert!(t.at(799.0).is_err() && t.at(1100.1).is_err());
        assert_eq!(t.amorphous_onset(0.45), Some(t.temperatures_c[1]));
    }

    #[test]
    fn mass_and_mole_fractions_convert_to_volume_fractions() {
        // Equal masses of a phase twice as dense as the other: a third of the volume.
        let (_d, p) = write("temperature_c,phase,mass_fraction,amorphous\n20,DENSE,0.5,\n20,GLASS,0.5,true\n900,DENSE,0.8,\n900,GLASS,0.2,true\n");
        let t = read_phases(&p).unwrap();
        let per_phase = [("DENSE".to_string(), 4000.0), ("GLASS".to_string(), 2000.0)].into_iter().collect();
        let v = t.to_volume("s.toml", Some(&VolumeConversion { per_phase, key: "phases.density_kg_m3".into() })).unwrap();
        assert_eq!((v.basis, v.file_basis), (Basis::Volume, Basis::Mass));
        assert!((v.amorphous_at(20.0).unwrap() - 2.0 / 3.0).abs() < 1e-12, "{:?}", v.fractions);
        // 0.8/4000 : 0.2/2000 = 2 : 1.
        assert!((v.amorphous_at(900.0).unwrap() - 1.0 / 3.0).abs() < 1e-12, "{:?}", v.fractions);
        // Mole fractions with molar volumes 1 : 3.
        let (_d, p) = write("temperature_c,phase,mole_fraction,amorphous\n20,A,0.5,\n20,GLASS,0.5,true\n900,A,0.5,\n900,GLASS,0.5,true\n");
        let t = read_phases(&p).unwrap();
        let per_phase = [("A".to_string(), 1e-6), ("GLASS".to_string(), 3e-6)].into_iter().collect();
        let v = t.to_volume("s.toml", Some(&VolumeConversion { per_phase, key: "phases.molar_volume_m3_mol".into() })).unwrap();
        assert!((v.amorphous_at(20.0).unwrap() - 0.75).abs() < 1e-12);
        // Without the conversion: refused, saying what to declare; a phase's value missing.
        let e = t.to_volume("s.toml", None).unwrap_err().to_string();
        assert!(e.contains("s.toml") && e.contains("phases.file") && e.contains("mole fractions") && e.contains("molar_volume_m3_mol = { A = …, GLASS = … }") && e.contains("volume_fraction"), "{e}");
        let per_phase = [("A".to_string(), 1e-6)].into_iter().collect();
        let e = t.to_volume("s.toml", Some(&VolumeConversion { per_phase, key: "phases.molar_volume_m3_mol".into() })).unwrap_err().to_string();
        assert!(e.contains("phases.molar_volume_m3_mol") && e.contains("lacks the molar volume of \"GLASS\""), "{e}");
        // Volume fractions are used as they are.
        let (_d, p) = write("temperature_c,phase,volume_fraction,amorphous\n20,A,0.5,\n20,GLASS,0.5,true\n900,A,0.5,\n900,GLASS,0.5,true\n");
        let t = read_phases(&p).unwrap();
        assert_eq!(t.to_volume("s.toml", None).unwrap(), t);
    }

    #[test]
    fn the_illustrative_table_reads_back_and_rises_from_900_c() {
        let dir = crate::io::TempDir::new("phases").unwrap();
        let p = dir.path().join("t.csv");
        let t = illustrative();
        std::fs::write(&p, t.to_csv()).unwrap();
        let back = read_phases(&p).unwrap();
        assert_eq!(back.phases, t.phases);
        for (a, b) in back.fractions.iter().zip(&t.fractions) {
            assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() < 2e-6), "{a:?} vs {b:?}");
        }
        let fa = t.amorphous_fractions();
        assert!(fa.windows(2).all(|w| w[1] >= w[0]) && fa.iter().all(|&f| (0.0..=0.30 + 1e-12).contains(&f)));
        assert_eq!(t.amorphous_onset(0.0), Some(900.0));
        assert!(t.fractions.iter().all(|f| f.iter().all(|&x| x >= -1e-12) && (f.iter().sum::<f64>() - 1.0).abs() < 1e-12));
    }
}

//! The example lab exports of `datasets/examples/`: the shipped crush data of both materials
//! (`datasets/crush_bl1630.csv`, `datasets/crush_gen4.csv`, SI) written the way lab software and
//! colleagues' spreadsheets write them, so that a new user has a file of each common shape to
//! copy, and the intake is tested on files that are not in partlife's own schema.
//!
//! * `crush_campaign_semicolon.csv` — one campaign file holding both materials: semicolons,
//!   decimal commas, Windows-1252 text (the `°` of `T [°C]` is the byte 0xB0), CRLF line ends,
//!   diameters in mm and forces in N, a `Material` column, ids under `Probe`;
//! * `crush_campaign.xlsx` — one workbook: a sheet per material (`BL 16-30`, `Gen 4`) whose
//!   headers state no unit (`Nr.`, `Dp`, `Last`: the study maps them and declares mm and kgf),
//!   and a `shape` sheet with roundness and sphericity of both materials' particles, in another
//!   order, joined by id.
//!
//! Values are converted from the SI text exactly ([`crate::intake::decimal`]): diameters by a
//! decimal shift, forces to kgf with 17 significant digits (what an `f64` cell holds). Read back
//! through the intake they are the SI files' numbers bit for bit, so the studies reading them
//! give byte-identical tables (`tests/intake.rs`). Written by `partlife datasets lab-examples`;
//! `datasets/examples/exports.toml` records what each export was made from, which labels them
//! synthetic as their sources are ([`crate::intake::synthetic_label`]).

use std::path::{Path, PathBuf};

use crate::data::{CrushData, read_crush};
use crate::error::{Error, Result};
use crate::intake::units::{Quantity, unit_of};
use crate::intake::write::{Sheet, Value, xlsx};

/// The semicolon-separated campaign file's name.
pub const CSV_FILE: &str = "crush_campaign_semicolon.csv";
/// The workbook's name.
pub const XLSX_FILE: &str = "crush_campaign.xlsx";
/// The SI files exported, in order.
pub const SOURCES: [&str; 2] = ["crush_bl1630.csv", "crush_gen4.csv"];

/// The SI text of each crush file's column `name`, per row (the exact decimals written).
fn column_text(path: &Path, name: &str) -> Result<Vec<String>> {
    let t = crate::intake::read_raw(&crate::intake::Source::file(path))?;
    let c = t.require(&[name])?[0];
    Ok((0..t.rows.len()).map(|r| t.text(r, c).unwrap_or_default()).collect())
}

fn convert(text: &str, quantity: Quantity, unit: &str, digits: usize) -> Result<String> {
    let u = unit_of(quantity, unit).ok_or_else(|| Error::numerical("lab export", format!("no unit {unit}")))?;
    u.conversion().from_si(text, digits).ok_or_else(|| Error::numerical("lab export", format!("cannot convert \"{text}\" to {unit}")))
}

fn opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// Writes both example exports into `out` from the SI crush files in `datasets`; returns the
/// files written.
pub fn write_examples(datasets: &Path, out: &Path) -> Result<Vec<PathBuf>> {
    let mut data: Vec<(CrushData, Vec<String>, Vec<String>)> = Vec::new();
    for f in SOURCES {
        let p = datasets.join(f);
        data.push((read_crush(&p)?, column_text(&p, "diameter_m")?, column_text(&p, "crush_force_n")?));
    }
    // (a) One semicolon-separated campaign file in mm and N, Windows-1252, CRLF.
    let comma = |s: String| s.replace('.', ",");
    let mut csv = String::from("Probe;Material;D [mm];Fmax [N];roundness;sphericity;T [°C]\r\n");
    for (d, diam, force) in &data {
        for (k, r) in d.records.iter().enumerate() {
            csv.push_str(&format!(
                "{};{};{};{};{};{};{}\r\n",
                r.id,
                r.material,
                comma(convert(&diam[k], Quantity::Length, "mm", 17)?),
                comma(force[k].clone()),
                comma(opt(r.roundness)),
                comma(opt(r.sphericity)),
                comma(opt(r.temperature_c))
            ));
        }
    }
    let (bytes, _, unmappable) = encoding_rs::WINDOWS_1252.encode(&csv);
    if unmappable {
        return Err(Error::numerical("lab export", "a character has no Windows-1252 code"));
    }
    let csv_path = out.join(CSV_FILE);
    crate::io::write_atomic(&csv_path, &bytes)?;

    // (b) A workbook: a sheet per material in mm and kgf with unit-less headers, and a shape
    // sheet of both materials (Gen 4 first, each in reverse order) joined by id.
    let t = |s: &str| Value::Text(s.to_string());
    let num = |s: String| -> Result<Value> { s.parse::<f64>().map(Value::Number).map_err(|e| Error::numerical("lab export", e.to_string())) };
    let mut sheets = Vec::new();
    for (d, diam, force) in &data {
        let mut rows = vec![vec![t("Nr."), t("Dp"), t("Last"), t("T [°C]")]];
        for (k, r) in d.records.iter().enumerate() {
            rows.push(vec![
                t(&r.id),
                num(convert(&diam[k], Quantity::Length, "mm", 17)?)?,
                num(convert(&force[k], Quantity::Force, "kgf", 17)?)?,
                r.temperature_c.map(Value::Number).unwrap_or(Value::Empty),
            ]);
        }
        sheets.push(Sheet { name: d.material().replace('/', "-"), rows, merged: vec![] });
    }
    let mut shape = vec![vec![t("Particle"), t("Material"), t("Roundness"), t("Sphericity")]];
    for (d, _, _) in data.iter().rev() {
        for r in d.records.iter().rev() {
            shape.push(vec![t(&r.id), t(&r.material), r.roundness.map(Value::Number).unwrap_or(Value::Empty), r.sphericity.map(Value::Number).unwrap_or(Value::Empty)]);
        }
    }
    sheets.push(Sheet { name: "shape".into(), rows: shape, merged: vec![] });
    let xlsx_path = out.join(XLSX_FILE);
    crate::io::write_atomic(&xlsx_path, &xlsx(&sheets)?)?;
    Ok(vec![csv_path, xlsx_path])
}

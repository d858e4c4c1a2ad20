//! A minimal spreadsheet writer: workbooks of plain sheets (numbers, text, formulas with or
//! without their cached value, merged cells) as .xlsx (Office Open XML, ECMA-376) or .ods
//! (OpenDocument 1.2). It writes the example lab exports of `datasets/examples/` and the
//! spreadsheets the tests read; bytes are reproducible (deflated, fixed zip timestamps, fixed
//! order).
//!
//! Numbers are written in Rust's shortest round-trip form, so a spreadsheet reader gets the very
//! `f64` that was written.

use std::io::Write;

use crate::error::{Error, Result};

/// A cell to write.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// Nothing.
    Empty,
    /// A number.
    Number(f64),
    /// Text.
    Text(String),
    /// A formula and its cached value (None: stored without a value, as a program that does not
    /// calculate writes it).
    Formula(String, Option<f64>),
}

/// One sheet: a name, rows of cells, merged ranges (`A1:B1`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Sheet {
    /// Its name (at most 31 characters, no `/ \ ? * [ ]`).
    pub name: String,
    /// Rows from the first, cells from column A.
    pub rows: Vec<Vec<Value>>,
    /// Merged ranges (.xlsx only).
    pub merged: Vec<String>,
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

fn zip(parts: &[(&str, String)]) -> Result<Vec<u8>> {
    let mut z = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated).last_modified_time(zip::DateTime::DEFAULT);
    let fail = |e: String| Error::numerical("writing a spreadsheet", e);
    for (name, body) in parts {
        z.start_file(*name, opts).map_err(|e| fail(e.to_string()))?;
        z.write_all(body.as_bytes()).map_err(|e| fail(e.to_string()))?;
    }
    Ok(z.finish().map_err(|e| fail(e.to_string()))?.into_inner())
}

/// A workbook as .xlsx bytes.
pub fn xlsx(sheets: &[Sheet]) -> Result<Vec<u8>> {
    const MAIN: &str = "http://schemas.openxmlformats.org/spreadsheetml/2006/main";
    const REL: &str = "http://schemas.openxmlformats.org/officeDocument/2006/relationships";
    const PKG: &str = "http://schemas.openxmlformats.org/package/2006/relationships";
    let head = "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\"?>\n";
    let mut types = format!("{head}<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\"><Default Extension=\"rels\" ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/><Default Extension=\"xml\" ContentType=\"application/xml\"/><Override PartName=\"/xl/workbook.xml\" ContentType=\"application/vnd.openxmlformats-officedocument.spreadsheetml.sheet.main+xml\"/><Override PartName=\"/xl/styles.xml\" ContentType=\"application/vnd.openxmlformats-officedocument.spreadsheetml.styles+xml\"/>");
    let mut book = format!("{head}<workbook xmlns=\"{MAIN}\" xmlns:r=\"{REL}\"><sheets>");
    let mut rels = format!("{head}<Relationships xmlns=\"{PKG}\">");
    let mut parts: Vec<(String, String)> = Vec::new();
    for (k, s) in sheets.iter().enumerate() {
        let n = k + 1;
        types.push_str(&format!("<Override PartName=\"/xl/worksheets/sheet{n}.xml\" ContentType=\"application/vnd.openxmlformats-officedocument.spreadsheetml.worksheet+xml\"/>"));
        book.push_str(&format!("<sheet name=\"{}\" sheetId=\"{n}\" r:id=\"rId{n}\"/>", escape(&s.name)));
        rels.push_str(&format!("<Relationship Id=\"rId{n}\" Type=\"{REL}/worksheet\" Target=\"worksheets/sheet{n}.xml\"/>"));
        let mut x = format!("{head}<worksheet xmlns=\"{MAIN}\"><sheetData>");
        for (r, row) in s.rows.iter().enumerate() {
            x.push_str(&format!("<row r=\"{}\">", r + 1));
            for (c, v) in row.iter().enumerate() {
                let at = format!("{}{}", super::table::column_letters(c), r + 1);
                match v {
                    Value::Empty => {}
                    Value::Number(v) => x.push_str(&format!("<c r=\"{at}\"><v>{v}</v></c>")),
                    Value::Text(t) => x.push_str(&format!("<c r=\"{at}\" t=\"inlineStr\"><is><t>{}</t></is></c>", escape(t))),
                    Value::Formula(f, Some(v)) => x.push_str(&format!("<c r=\"{at}\"><f>{}</f><v>{v}</v></c>", escape(f))),
                    Value::Formula(f, None) => x.push_str(&format!("<c r=\"{at}\"><f>{}</f></c>", escape(f))),
                }
            }
            x.push_str("</row>");
        }
        x.push_str("</sheetData>");
        if !s.merged.is_empty() {
            x.push_str(&format!("<mergeCells count=\"{}\">", s.merged.len()));
            for m in &s.merged {
                x.push_str(&format!("<mergeCell ref=\"{m}\"/>"));
            }
            x.push_str("</mergeCells>");
        }
        x.push_str("</worksheet>");
        parts.push((format!("xl/worksheets/sheet{n}.xml"), x));
    }
    types.push_str("</Types>");
    book.push_str("</sheets></workbook>");
    let n = sheets.len() + 1;
    rels.push_str(&format!("<Relationship Id=\"rId{n}\" Type=\"{REL}/styles\" Target=\"styles.xml\"/></Relationships>"));
    let styles = format!("{head}<styleSheet xmlns=\"{MAIN}\"><fonts count=\"1\"><font><sz val=\"11\"/><name val=\"Calibri\"/></font></fonts><fills count=\"1\"><fill><patternFill patternType=\"none\"/></fill></fills><borders count=\"1\"><border/></borders><cellStyleXfs count=\"1\"><xf/></cellStyleXfs><cellXfs count=\"1\"><xf xfId=\"0\"/></cellXfs></styleSheet>");
    let root = format!("{head}<Relationships xmlns=\"{PKG}\"><Relationship Id=\"rId1\" Type=\"{REL}/officeDocument\" Target=\"xl/workbook.xml\"/></Relationships>");
    let mut all: Vec<(&str, String)> = vec![("[Content_Types].xml", types), ("_rels/.rels", root), ("xl/workbook.xml", book), ("xl/_rels/workbook.xml.rels", rels), ("xl/styles.xml", styles)];
    all.extend(parts.iter().map(|(n, b)| (n.as_str(), b.clone())));
    zip(&all)
}

/// A workbook as .ods bytes (merged ranges are not written).
pub fn ods(sheets: &[Sheet]) -> Result<Vec<u8>> {
    let mut content = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<office:document-content xmlns:office=\"urn:oasis:names:tc:opendocument:xmlns:office:1.0\" xmlns:table=\"urn:oasis:names:tc:opendocument:xmlns:table:1.0\" xmlns:text=\"urn:oasis:names:tc:opendocument:xmlns:text:1.0\" xmlns:of=\"urn:oasis:names:tc:opendocument:xmlns:of:1.2\" office:version=\"1.2\"><office:body><office:spreadsheet>");
    for s in sheets {
        content.push_str(&format!("<table:table table:name=\"{}\">", escape(&s.name)));
        for row in &s.rows {
            content.push_str("<table:table-row>");
            for v in row {
                match v {
                    Value::Empty => content.push_str("<table:table-cell/>"),
                    Value::Number(x) => content.push_str(&format!("<table:table-cell office:value-type=\"float\" office:value=\"{x}\"><text:p>{x}</text:p></table:table-cell>")),
                    Value::Text(t) => content.push_str(&format!("<table:table-cell office:value-type=\"string\"><text:p>{}</text:p></table:table-cell>", escape(t))),
                    Value::Formula(f, Some(x)) => content.push_str(&format!("<table:table-cell table:formula=\"of:={}\" office:value-type=\"float\" office:value=\"{x}\"><text:p>{x}</text:p></table:table-cell>", escape(f))),
                    Value::Formula(f, None) => content.push_str(&format!("<table:table-cell table:formula=\"of:={}\"/>", escape(f))),
                }
            }
            content.push_str("</table:table-row>");
        }
        content.push_str("</table:table>");
    }
    content.push_str("</office:spreadsheet></office:body></office:document-content>");
    let manifest = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<manifest:manifest xmlns:manifest=\"urn:oasis:names:tc:opendocument:xmlns:manifest:1.0\" manifest:version=\"1.2\"><manifest:file-entry manifest:full-path=\"/\" manifest:media-type=\"application/vnd.oasis.opendocument.spreadsheet\"/><manifest:file-entry manifest:full-path=\"content.xml\" manifest:media-type=\"text/xml\"/></manifest:manifest>".to_string();
    zip(&[("mimetype", "application/vnd.oasis.opendocument.spreadsheet".to_string()), ("META-INF/manifest.xml", manifest), ("content.xml", content)])
}

//! Spreadsheets (.xlsx, .xlsm, .xls, .xlsb, .ods) read with calamine: one sheet, by name or by
//! 1-based index (default: the first), its header on a settable sheet row (default: the first row
//! that holds anything).
//!
//! Cells keep their type: numbers (a formula's cached value, which is what the spreadsheet
//! shows), text, and other values (dates, booleans, error values such as `#DIV/0!`) that no
//! numeric column accepts. Refused, naming the sheet, row and column: an empty sheet, a sheet that
//! does not exist (with the list of sheets), merged cells in the header row (.xlsx), a formula
//! without a cached value.

use std::io::Cursor;
use std::path::Path;

use calamine::{Data, Reader, Sheets};
use serde::{Deserialize, Serialize};

use super::table::{Cell, Origin, RawTable, column_letters, from_sheet};
use super::Source;
use crate::error::{Error, Result};

/// A sheet by name or by 1-based position — or several sheets read as one table
/// (`sheet = ["RT", "800 °C"]`: the same columns on each; their rows one after the other, with
/// the sheet's name in an added column `sheet`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum SheetRef {
    /// Its name.
    Name(String),
    /// Its position, 1 for the first.
    Index(usize),
    /// Several sheets as one table.
    Several(Vec<SheetRef>),
}

/// The column that holds each row's sheet when several sheets are read as one table.
pub const SHEET_COLUMN: &str = "sheet";

/// The spreadsheet formats by file extension (lower case).
pub const EXTENSIONS: [&str; 5] = ["xlsx", "xlsm", "xls", "xlsb", "ods"];

/// True when `path` names a spreadsheet by its extension.
pub fn is_spreadsheet(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

fn open(path: &Path, bytes: Vec<u8>) -> Result<Sheets<Cursor<Vec<u8>>>> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let bad = |e: String| Error::data_file(path, "file", format!("is not a readable {ext} spreadsheet: {}", e.split_whitespace().collect::<Vec<_>>().join(" ")));
    let rs = Cursor::new(bytes);
    Ok(match ext.as_str() {
        "xlsx" | "xlsm" => Sheets::Xlsx(calamine::Xlsx::new(rs).map_err(|e| bad(e.to_string()))?),
        "xls" => Sheets::Xls(calamine::Xls::new(rs).map_err(|e| bad(e.to_string()))?),
        "xlsb" => Sheets::Xlsb(calamine::Xlsb::new(rs).map_err(|e| bad(e.to_string()))?),
        "ods" => Sheets::Ods(calamine::Ods::new(rs).map_err(|e| bad(e.to_string()))?),
        _ => return Err(bad("unknown extension".into())),
    })
}

/// Reads one sheet of a spreadsheet as a raw table.
pub fn read_sheet(path: &Path, bytes: Vec<u8>, opts: &Source) -> Result<RawTable> {
    if let Some(SheetRef::Several(list)) = &opts.sheet {
        return read_sheets(path, bytes, opts, list);
    }
    let mut book = open(path, bytes)?;
    let names = book.sheet_names();
    let listed = || names.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(", ");
    let (name, position) = match &opts.sheet {
        None => match names.first() {
            Some(n) => (n.clone(), 0),
            None => return Err(Error::data_file(path, "file", "the workbook has no sheets")),
        },
        Some(SheetRef::Name(n)) => match names.iter().position(|s| s == n) {
            Some(k) => (n.clone(), k),
            None => return Err(Error::data_file(path, format!("sheet \"{n}\""), format!("no such sheet; the workbook has {}", listed()))),
        },
        Some(SheetRef::Index(k)) => match names.get(k.wrapping_sub(1)) {
            Some(n) => (n.clone(), k - 1),
            None => return Err(Error::data_file(path, format!("sheet {k}"), format!("no such sheet: the workbook has {} ({}), numbered from 1", names.len(), listed()))),
        },
        Some(SheetRef::Several(_)) => unreachable!("several sheets are read by read_sheets"),
    };
    let at = |what: String| format!("sheet \"{name}\"{what}");
    let range = book.worksheet_range(&name).map_err(|e| Error::data_file(path, at(String::new()), format!("cannot be read: {}", e.to_string().split_whitespace().collect::<Vec<_>>().join(" "))))?;
    let Some((r0, c0)) = range.start() else {
        return Err(Error::data_file(path, at(String::new()), "the sheet is empty: a header row and data rows are expected"));
    };
    let (r1, c1) = range.end().unwrap_or((r0, c0));
    // Sheet rows are 1-based in messages, as a spreadsheet numbers them.
    let header_row = match opts.header_row {
        Some(h) if h == 0 || h as u64 > r1 as u64 + 1 => return Err(Error::data_file(path, at(format!(", row {h}")), format!("header_row = {h} lies outside the sheet's rows {}–{}", r0 + 1, r1 + 1))),
        Some(h) => h as u32 - 1,
        None => r0,
    };
    if header_row < r0 {
        return Err(Error::data_file(path, at(format!(", row {}", header_row + 1)), "header_row points to an empty row above the sheet's data"));
    }
    if let Sheets::Xlsx(x) = &mut book
        && let Ok(merged) = x.merge_cells_by_sheet_name(&name)
        && let Some(m) = merged.iter().find(|m| m.start.0 <= header_row && header_row <= m.end.0)
    {
        // A merged title above the header (the header row not given): the first row below it
        // that no merge covers and that names every column is most likely the header.
        let named = |r: u32| (c0..=c1).all(|c| matches!(range.get_value((r, c)), Some(Data::String(v)) if !v.trim().is_empty()));
        let later = (opts.header_row.is_none()).then(|| (m.end.0 + 1..=r1).find(|&r| named(r) && !merged.iter().any(|k| k.start.0 <= r && r <= k.end.0))).flatten();
        let advice = match later {
            Some(r) => format!(
                ": give each column its own header cell, or, if the header is sheet row {} under a title, say so — header_row = {} in the study's data entry (`--header-row {}` for `datasets check`)",
                r + 1,
                r + 1,
                r + 1
            ),
            None => ": give each column its own header cell".to_string(),
        };
        return Err(Error::data_file(
            path,
            at(format!(", header (sheet row {})", header_row + 1)),
            format!("merged cells {}{}:{}{} in the header row{advice}", column_letters(m.start.1 as usize), m.start.0 + 1, column_letters(m.end.1 as usize), m.end.0 + 1),
        ));
    }
    let value = |r: u32, c: u32| range.get_value((r, c)).cloned().unwrap_or(Data::Empty);
    let mut headers = Vec::new();
    for c in c0..=c1 {
        headers.push(match value(header_row, c) {
            Data::String(s) => s.trim().to_string(),
            Data::Empty => String::new(),
            Data::Float(v) => format!("{v}"),
            Data::Int(v) => v.to_string(),
            other => other.to_string(),
        });
    }
    // Columns right of the last named header that hold nothing are not part of the table.
    let mut formulas: Option<calamine::Range<String>> = None;
    let mut rows = Vec::new();
    let mut lines = Vec::new();
    for r in header_row + 1..=r1 {
        let cells: Vec<Cell> = (c0..=c1)
            .map(|c| match value(r, c) {
                Data::Empty => Cell::Empty,
                Data::String(s) if s.trim().is_empty() => Cell::Empty,
                Data::String(s) => Cell::Text(s.trim().to_string()),
                Data::Float(v) => Cell::Number(v),
                Data::Int(v) => Cell::Number(v as f64),
                Data::Bool(b) => Cell::Other(format!("the logical value {}", if b { "TRUE" } else { "FALSE" })),
                Data::DateTime(d) => Cell::Other(format!("a date or time ({d})")),
                Data::DateTimeIso(d) => Cell::Other(format!("a date or time ({d})")),
                Data::DurationIso(d) => Cell::Other(format!("a duration ({d})")),
                Data::Error(e) => Cell::Other(format!("the spreadsheet error {e}")),
            })
            .collect();
        if cells.iter().all(|c| matches!(c, Cell::Empty)) {
            continue;
        }
        // An empty cell where the sheet holds a formula: the file was written without cached
        // values (by a program, not saved by a spreadsheet application).
        if cells.iter().any(|c| matches!(c, Cell::Empty)) {
            let f = formulas.get_or_insert_with(|| book.worksheet_formula(&name).unwrap_or_default());
            if let Some(c) = (c0..=c1).find(|&c| matches!(cells[(c - c0) as usize], Cell::Empty) && f.get_value((r, c)).is_some_and(|s| !s.is_empty())) {
                return Err(Error::data_file(
                    path,
                    at(format!(", row {} (sheet row {}), column {}", rows.len() + 1, r + 1, column_letters(c as usize))),
                    "a formula without a saved value: open the file in a spreadsheet application and save it, so the computed values are stored",
                ));
            }
        }
        rows.push(cells);
        lines.push(r as usize + 1);
    }
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let mut format = format!("{ext} sheet \"{name}\"");
    if opts.sheet.is_none() && names.len() > 1 {
        format.push_str(&format!(" (the first of {} sheets: {})", names.len(), listed()));
    } else if names.len() > 1 {
        format.push_str(&format!(" ({} of {})", position + 1, names.len()));
    }
    format.push_str(&format!(", header on sheet row {}", header_row + 1));
    let origin = Origin { path: path.to_path_buf(), sheet: Some(name), first_column: c0 as usize };
    from_sheet(origin, format, headers, rows, lines, header_row as usize + 1)
}

/// Several sheets as one table: each read as [`read_sheet`] reads one, with the same columns
/// (in any order; a column missing from a sheet, or one only a sheet has, is refused), their rows
/// in the order the sheets are listed, and a column [`SHEET_COLUMN`] holding each row's sheet.
/// Each row keeps its own sheet and sheet row for messages ([`RawTable::row_sheets`]).
fn read_sheets(path: &Path, bytes: Vec<u8>, opts: &Source, list: &[SheetRef]) -> Result<RawTable> {
    if list.is_empty() {
        return Err(Error::data_file(path, "file", "`sheet = []` names no sheet: give one or several"));
    }
    let mut tables = Vec::with_capacity(list.len());
    for s in list {
        if matches!(s, SheetRef::Several(_)) {
            return Err(Error::data_file(path, "file", "`sheet` lists a list: give the sheets' names or positions"));
        }
        tables.push(read_sheet(path, bytes.clone(), &Source { sheet: Some(s.clone()), ..opts.clone() })?);
    }
    let first = tables.remove(0);
    let name_of = |t: &RawTable| t.origin.sheet.clone().unwrap_or_default();
    if let Some(c) = first.headers.iter().position(|h| crate::intake::units::fold(h) == SHEET_COLUMN) {
        return Err(first.header_error(Some(c), format!("already has a column `{}`: reading several sheets as one table adds a column `{SHEET_COLUMN}` with each row's sheet; rename this one", first.headers[c])));
    }
    let mut seen = vec![name_of(&first)];
    let mut headers = first.headers.clone();
    headers.push(SHEET_COLUMN.to_string());
    let mut rows: Vec<Vec<Cell>> = Vec::new();
    let mut lines = Vec::new();
    let mut row_sheets = Vec::new();
    let mut formats = vec![first.format.clone()];
    for t in std::iter::once(&first).chain(&tables) {
        let name = name_of(t);
        if !std::ptr::eq(t, &first) && seen.contains(&name) {
            return Err(Error::data_file(path, format!("sheet \"{name}\""), "is listed twice in `sheet`"));
        }
        if !std::ptr::eq(t, &first) {
            seen.push(name.clone());
            formats.push(t.format.clone());
        }
        // Each of the first sheet's columns in this sheet.
        let mut at = Vec::with_capacity(first.headers.len());
        for h in &first.headers {
            match t.headers.iter().position(|x| x == h) {
                Some(c) => at.push(c),
                None => return Err(t.header_error(None, format!("has no column `{h}`, which sheet \"{}\" has: sheets read as one table need the same columns", name_of(&first)))),
            }
        }
        if let Some(extra) = t.headers.iter().find(|x| !first.headers.contains(x)) {
            return Err(t.header_error(None, format!("has a column `{extra}` that sheet \"{}\" has not: sheets read as one table need the same columns", name_of(&first))));
        }
        for (r, line) in t.rows.iter().zip(&t.lines) {
            let mut cells: Vec<Cell> = at.iter().map(|&c| r[c].clone()).collect();
            cells.push(Cell::Text(name.clone()));
            rows.push(cells);
            lines.push(*line);
            row_sheets.push(name.clone());
        }
    }
    let format = format!("{} sheets as one table, their name in column `{SHEET_COLUMN}`: {}", seen.len(), formats.join("; "));
    let mut table = RawTable { origin: first.origin.clone(), format, headers, rows, lines, header_line: first.header_line, decimal: first.decimal, row_sheets: Vec::new() };
    table.row_sheets = row_sheets;
    Ok(table)
}

/// The sheet names of a workbook, in order.
pub fn sheet_names(path: &Path, bytes: Vec<u8>) -> Result<Vec<String>> {
    Ok(open(path, bytes)?.sheet_names())
}

#[cfg(test)]
mod tests {
    use super::super::write::{Sheet, Value, ods, xlsx};
    use super::*;

    fn sheet(name: &str, rows: Vec<Vec<Value>>) -> Sheet {
        Sheet { name: name.into(), rows, merged: vec![] }
    }
    fn t(s: &str) -> Value {
        Value::Text(s.into())
    }

    fn read(bytes: Vec<u8>, ext: &str, opts: Source) -> Result<RawTable> {
        read_sheet(&std::path::PathBuf::from(format!("book.{ext}")), bytes, &opts)
    }

    #[test]
    fn reads_numbers_text_and_cached_formula_values_from_xlsx_and_ods() {
        let rows = vec![vec![t("Nr"), t("D [mm]"), t("F [N]")], vec![t("A1"), Value::Number(0.912), Value::Formula("2*65.6".into(), Some(131.2))], vec![], vec![t("A2"), Value::Number(0.85), Value::Number(120.7)]];
        for (ext, bytes) in [("xlsx", xlsx(&[sheet("other", vec![vec![t("x")]]), sheet("BL 16-30", rows.clone())]).unwrap()), ("ods", ods(&[sheet("other", vec![vec![t("x")]]), sheet("BL 16-30", rows.clone())]).unwrap())] {
            let tab = read(bytes, ext, Source { sheet: Some(SheetRef::Name("BL 16-30".into())), ..Source::default() }).unwrap();
            assert_eq!(tab.headers, vec!["Nr", "D [mm]", "F [N]"], "{ext}");
            assert_eq!(tab.rows.len(), 2, "{ext}: the blank row is dropped");
            assert_eq!(tab.rows[0][2], Cell::Number(131.2), "{ext}: the formula's cached value");
            assert_eq!(tab.lines, vec![2, 4]);
            assert_eq!(tab.place(1, Some(1)), "sheet \"BL 16-30\", row 2 (sheet row 4), column B \"D [mm]\"");
            assert!(tab.format.starts_with(&format!("{ext} sheet \"BL 16-30\" (2 of 2)")), "{}", tab.format);
        }
    }

    #[test]
    fn several_sheets_read_as_one_table_with_the_sheet_as_a_column() {
        let rt = sheet("RT", vec![vec![t("Nr"), t("D [mm]"), t("F [N]")], vec![t("A1"), Value::Number(0.9), Value::Number(131.2)], vec![t("A2"), Value::Number(0.85), Value::Number(120.7)]]);
        // The hot sheet orders its columns differently and starts lower.
        let hot = sheet("800 °C", vec![vec![], vec![t("F [N]"), t("Nr"), t("D [mm]")], vec![Value::Number(90.5), t("H1"), Value::Number(0.88)]]);
        let book = xlsx(&[rt.clone(), sheet("notes", vec![vec![t("x")]]), hot]).unwrap();
        let both = Some(SheetRef::Several(vec![SheetRef::Name("RT".into()), SheetRef::Name("800 °C".into())]));
        let tab = read(book.clone(), "xlsx", Source { sheet: both.clone(), ..Source::default() }).unwrap();
        assert_eq!(tab.headers, ["Nr", "D [mm]", "F [N]", SHEET_COLUMN]);
        assert_eq!(tab.rows.len(), 3);
        assert_eq!(tab.rows[2], vec![t_cell("H1"), Cell::Number(0.88), Cell::Number(90.5), t_cell("800 °C")]);
        assert_eq!(tab.rows[0][3], t_cell("RT"));
        // Each row's messages name its own sheet and sheet row.
        assert_eq!(tab.place(2, Some(2)), "sheet \"800 °C\", row 3 (sheet row 3), column \"F [N]\"");
        assert_eq!(tab.place(0, None), "sheet \"RT\", row 1 (sheet row 2)");
        // By position too; a sheet without a column the first has is refused, naming both.
        let tab = read(book.clone(), "xlsx", Source { sheet: Some(SheetRef::Several(vec![SheetRef::Index(1), SheetRef::Index(3)])), ..Source::default() }).unwrap();
        assert_eq!(tab.rows.len(), 3);
        let e = read(book, "xlsx", Source { sheet: Some(SheetRef::Several(vec![SheetRef::Name("RT".into()), SheetRef::Name("notes".into())])), ..Source::default() }).unwrap_err().to_string();
        assert!(e.contains("sheet \"notes\"") && e.contains("has no column `Nr`, which sheet \"RT\" has"), "{e}");
    }

    fn t_cell(s: &str) -> Cell {
        Cell::Text(s.into())
    }

    #[test]
    fn refuses_missing_sheets_empty_sheets_merged_headers_and_uncached_formulas() {
        let book = xlsx(&[sheet("A", vec![vec![t("id"), t("d [mm]")], vec![t("x"), Value::Number(1.0)]]), sheet("empty", vec![])]).unwrap();
        let e = read(book.clone(), "xlsx", Source { sheet: Some(SheetRef::Name("B".into())), ..Source::default() }).unwrap_err().to_string();
        assert!(e.contains("sheet \"B\"") && e.contains("no such sheet") && e.contains("\"A\", \"empty\""), "{e}");
        let e = read(book.clone(), "xlsx", Source { sheet: Some(SheetRef::Index(3)), ..Source::default() }).unwrap_err().to_string();
        assert!(e.contains("sheet 3") && e.contains("has 2"), "{e}");
        let e = read(book, "xlsx", Source { sheet: Some(SheetRef::Index(2)), ..Source::default() }).unwrap_err().to_string();
        assert!(e.contains("sheet \"empty\"") && e.contains("is empty"), "{e}");
        let merged = Sheet { name: "M".into(), rows: vec![vec![t("id"), t("size"), Value::Empty], vec![t("x"), Value::Number(1.0), Value::Number(2.0)]], merged: vec!["B1:C1".into()] };
        let e = read(xlsx(&[merged]).unwrap(), "xlsx", Source::default()).unwrap_err().to_string();
        assert!(e.contains("merged cells B1:C1") && e.contains("sheet row 1"), "{e}");
        assert!(e.ends_with("give each column its own header cell"), "no later header row to suggest: {e}");
        // A merged title above the header on sheet row 3: the message points at header_row.
        let titled = Sheet {
            name: "T".into(),
            rows: vec![vec![t("Druckversuch Charge 7"), Value::Empty], vec![Value::Empty, Value::Empty], vec![t("id"), t("F [N]")], vec![t("x"), Value::Number(1.0)]],
            merged: vec!["A1:B1".into()],
        };
        let e = read(xlsx(&[titled]).unwrap(), "xlsx", Source::default()).unwrap_err().to_string();
        assert!(e.contains("merged cells A1:B1") && e.contains("if the header is sheet row 3 under a title, say so — header_row = 3 in the study's data entry (`--header-row 3` for `datasets check`)"), "{e}");
        let uncached = sheet("U", vec![vec![t("id"), t("F [N]")], vec![t("x"), Value::Formula("1+1".into(), None)]]);
        let e = read(xlsx(&[uncached]).unwrap(), "xlsx", Source::default()).unwrap_err().to_string();
        assert!(e.contains("row 1 (sheet row 2), column B") && e.contains("formula without a saved value"), "{e}");
        let e = read(b"not a zip at all".to_vec(), "xlsx", Source::default()).unwrap_err().to_string();
        assert!(e.contains("book.xlsx") && e.contains("not a readable xlsx spreadsheet"), "{e}");
    }

    #[test]
    fn the_header_row_is_settable() {
        let book = xlsx(&[sheet("S", vec![vec![t("Rig 4 export")], vec![], vec![t("id"), t("d [mm]")], vec![t("x"), Value::Number(1.0)]])]).unwrap();
        let tab = read(book.clone(), "xlsx", Source { header_row: Some(3), ..Source::default() }).unwrap();
        assert_eq!(tab.headers, vec!["id", "d [mm]"]);
        assert_eq!(tab.lines, vec![4]);
        let e = read(book, "xlsx", Source { header_row: Some(9), ..Source::default() }).unwrap_err().to_string();
        assert!(e.contains("header_row = 9"), "{e}");
    }
}

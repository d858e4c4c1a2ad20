//! A raw table: a header and rows of cells, from delimited text or a spreadsheet sheet, with the
//! physical place of every row so that any later rule can name it.

use std::path::{Path, PathBuf};

use super::text::{DecimalMark, Delimiter, Lines, decode, is_comma_number, sniff, split_line};
use super::Source;
use crate::error::{Error, Result};

/// One cell as read.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// Empty (or blank text).
    Empty,
    /// Text as written (a delimited file's every cell, a spreadsheet's text cells).
    Text(String),
    /// A spreadsheet's number (its cached value for a formula).
    Number(f64),
    /// A spreadsheet value that is neither text nor number: what it is, in words.
    Other(String),
}

/// Where a table came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Origin {
    /// The file.
    pub path: PathBuf,
    /// The sheet, for a spreadsheet.
    pub sheet: Option<String>,
    /// First column's index in the sheet (0 = A), for column letters.
    pub first_column: usize,
}

/// A header and its rows.
#[derive(Debug, Clone, PartialEq)]
pub struct RawTable {
    /// Where it came from.
    pub origin: Origin,
    /// How it was read, in words (`semicolon-separated, decimal comma, UTF-8`).
    pub format: String,
    /// Column headers as written (trimmed).
    pub headers: Vec<String>,
    /// Data rows (blank rows dropped), each as long as the header.
    pub rows: Vec<Vec<Cell>>,
    /// Physical line (delimited text) or sheet row (1-based) of each data row.
    pub lines: Vec<usize>,
    /// Physical line or sheet row of the header.
    pub header_line: usize,
    /// The decimal mark of text cells.
    pub decimal: DecimalMark,
    /// Several sheets read as one table: each row's sheet (its columns named by header, not
    /// letter: the sheets may order them differently); empty otherwise (every row is `origin`'s).
    pub row_sheets: Vec<String>,
}

/// Column letters of a 0-based index: 0 → A, 26 → AA.
pub fn column_letters(mut k: usize) -> String {
    let mut s = Vec::new();
    loop {
        s.push(b'A' + (k % 26) as u8);
        if k < 26 {
            break;
        }
        k = k / 26 - 1;
    }
    s.reverse();
    String::from_utf8(s).unwrap_or_default()
}

impl RawTable {
    /// Where data row `row` (0-based) and column `col` are, as messages name it:
    /// `row 3 (line 4), column D [mm]` or `sheet BL, row 3 (sheet row 5), column C "D [mm]"`.
    pub fn place(&self, row: usize, col: Option<usize>) -> String {
        let line = self.lines.get(row).copied().unwrap_or(0);
        if let Some(sheet) = self.row_sheets.get(row) {
            let c = col.map(|c| format!(", column \"{}\"", self.headers[c])).unwrap_or_default();
            return format!("sheet \"{sheet}\", row {} (sheet row {line}){c}", row + 1);
        }
        match &self.origin.sheet {
            None => {
                let c = col.map(|c| format!(", column {}", self.headers[c])).unwrap_or_default();
                format!("row {} (line {line}){c}", row + 1)
            }
            Some(sheet) => {
                let c = col.map(|c| format!(", column {} \"{}\"", column_letters(self.origin.first_column + c), self.headers[c])).unwrap_or_default();
                format!("sheet \"{sheet}\", row {} (sheet row {line}){c}", row + 1)
            }
        }
    }

    /// Where the header (or one of its columns) is.
    pub fn header_place(&self, col: Option<usize>) -> String {
        match &self.origin.sheet {
            None => format!("header (line {}){}", self.header_line, col.map(|c| if self.headers[c].is_empty() { format!(", column {}", c + 1) } else { format!(", column {}", self.headers[c]) }).unwrap_or_default()),
            Some(sheet) => format!("sheet \"{sheet}\", header (sheet row {}){}", self.header_line, col.map(|c| if self.headers[c].is_empty() { format!(", column {}", column_letters(self.origin.first_column + c)) } else { format!(", column {} \"{}\"", column_letters(self.origin.first_column + c), self.headers[c]) }).unwrap_or_default()),
        }
    }

    /// An error at a data row and column.
    pub fn error(&self, row: usize, col: Option<usize>, rule: impl Into<String>) -> Error {
        Error::data_file(&self.origin.path, self.place(row, col), rule)
    }

    /// An error about the header.
    pub fn header_error(&self, col: Option<usize>, rule: impl Into<String>) -> Error {
        Error::data_file(&self.origin.path, self.header_place(col), rule)
    }

    /// The column named exactly `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.headers.iter().position(|h| h == name)
    }

    /// The columns named exactly `names`, in order; every missing one is named in one error.
    pub fn require(&self, names: &[&str]) -> Result<Vec<usize>> {
        let missing: Vec<String> = names.iter().filter(|n| self.column(n).is_none()).map(|n| format!("`{n}`")).collect();
        if !missing.is_empty() {
            return Err(self.header_error(None, format!("missing {} {}", if missing.len() == 1 { "column" } else { "columns" }, missing.join(", "))));
        }
        Ok(names.iter().filter_map(|n| self.column(n)).collect())
    }

    /// The text of a cell (None: empty).
    pub fn text(&self, row: usize, col: usize) -> Option<String> {
        match &self.rows[row][col] {
            Cell::Empty => None,
            Cell::Text(t) => Some(t.clone()),
            Cell::Number(v) => Some(format!("{v}")),
            Cell::Other(w) => Some(w.clone()),
        }
    }

    /// The number in a cell taken as written (no unit), finite; None for an empty cell.
    pub fn number(&self, row: usize, col: usize) -> Result<Option<f64>> {
        if let Cell::Text(raw) = &self.rows[row][col]
            && self.origin.sheet.is_some()
        {
            return Err(self.error(row, Some(col), format!("holds the text \"{raw}\", not a number (stored as text in the spreadsheet: make it a number cell)")));
        }
        let text = match number_text(&self.rows[row][col], self.decimal) {
            Ok(None) => return Ok(None),
            Ok(Some(t)) => t,
            Err(rule) => return Err(self.error(row, Some(col), rule)),
        };
        let raw = self.text(row, col).unwrap_or_default();
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            Ok(_) => Err(self.error(row, Some(col), format!("value \"{raw}\" is not a finite number"))),
            Err(_) => Err(self.error(row, Some(col), format!("value \"{raw}\" is not a number"))),
        }
    }

    /// The number in a cell that must not be empty.
    pub fn need_number(&self, row: usize, col: usize) -> Result<f64> {
        self.number(row, col)?.ok_or_else(|| self.error(row, Some(col), "cell is empty; a value is required"))
    }

    /// The text in a cell that must not be empty.
    pub fn need_text(&self, row: usize, col: usize) -> Result<String> {
        self.text(row, col).ok_or_else(|| self.error(row, Some(col), "cell is empty; a value is required"))
    }

    /// Checks the header: every column named, no name twice. An unnamed column whose cells are
    /// all empty (a trailing delimiter) is dropped.
    fn check_header(mut self) -> Result<RawTable> {
        let mut k = 0;
        while k < self.headers.len() {
            if self.headers[k].is_empty() {
                if self.rows.iter().all(|r| matches!(r[k], Cell::Empty)) {
                    self.headers.remove(k);
                    self.rows.iter_mut().for_each(|r| {
                        r.remove(k);
                    });
                    continue;
                }
                let merged = if self.origin.sheet.is_some() { " (a merged header cell gives the columns it covers no name: give each column its own header)" } else { "" };
                return Err(self.header_error(Some(k), format!("column {} has no name{merged}", k + 1)));
            }
            if let Some(j) = self.headers[..k].iter().position(|n| *n == self.headers[k]) {
                return Err(self.header_error(Some(k), format!("column `{}` appears twice (columns {} and {})", self.headers[k], j + 1, k + 1)));
            }
            k += 1;
        }
        Ok(self)
    }
}

/// Reads a delimited text file (the module docs of [`super::text`]).
pub fn read_delimited(path: &Path, bytes: &[u8], opts: &Source) -> Result<RawTable> {
    let decoded = decode(path, bytes)?;
    let all: Lines = decoded.text.lines().enumerate().map(|(i, l)| (i + 1, l)).collect();
    let start = opts.header_row.unwrap_or(1);
    let lines: Lines = all.into_iter().filter(|(n, _)| *n >= start).collect();
    let Some(&(header_line, header)) = lines.first().filter(|(_, h)| !h.trim().is_empty()) else {
        let what = if opts.header_row.is_some() { format!("line {start} (header_row)") } else { "header".to_string() };
        return Err(Error::data_file(path, what, "the file is empty or its header line is blank: a header row is expected"));
    };
    let sniffed = sniff(path, &lines, opts.delimiter, opts.decimal)?;
    let d = sniffed.delimiter.char();
    let headers = split_line(header, d);
    let mut rows = Vec::new();
    let mut at = Vec::new();
    for &(n, l) in lines[1..].iter().filter(|(_, l)| !l.trim().is_empty()) {
        let cells = split_line(l, d);
        if cells.len() != headers.len() {
            let row = rows.len() + 1;
            let mut rule = format!("has {} fields, the header has {}", cells.len(), headers.len());
            if sniffed.delimiter == Delimiter::Comma && cells.len() > headers.len() && cells.windows(2).any(|w| w[0].bytes().all(|b| b.is_ascii_digit() || b == b'-') && !w[0].is_empty() && w[1].bytes().next().is_some_and(|b| b.is_ascii_digit())) {
                rule.push_str(": a decimal comma in a comma-separated file? Quote such cells (\"0,91\"), or separate fields with ';'");
            } else if sniffed.delimiter != Delimiter::Comma && headers.len() == 1 {
                rule.push_str(&format!(" (the header has no '{d}')"));
            }
            return Err(Error::data_file(path, format!("row {row} (line {n})"), rule));
        }
        rows.push(cells.into_iter().map(|c| if c.is_empty() { Cell::Empty } else { Cell::Text(c) }).collect());
        at.push(n);
    }
    let mut format = sniffed.delimiter.word().to_string();
    if sniffed.stated.0 {
        format.push_str(" (stated)");
    }
    format.push_str(match sniffed.decimal {
        DecimalMark::Point => ", decimal point",
        DecimalMark::Comma => ", decimal comma",
    });
    if sniffed.stated.1 {
        format.push_str(" (stated)");
    }
    format.push_str(&format!(", {}", decoded.encoding));
    if start > 1 {
        format.push_str(&format!(", header on line {start}"));
    }
    RawTable {
        origin: Origin { path: path.to_path_buf(), sheet: None, first_column: 0 },
        format,
        headers,
        rows,
        lines: at,
        header_line,
        decimal: sniffed.decimal,
        row_sheets: Vec::new(),
    }
    .check_header()
}

/// A spreadsheet's table (see [`super::sheet`]) checked like a text table's.
pub(super) fn from_sheet(origin: Origin, format: String, headers: Vec<String>, rows: Vec<Vec<Cell>>, lines: Vec<usize>, header_line: usize) -> Result<RawTable> {
    RawTable { origin, format, headers, rows, lines, header_line, decimal: DecimalMark::Point, row_sheets: Vec::new() }.check_header()
}

/// The text of a number cell, ready for parsing with a decimal point; Err(rule) when the cell
/// cannot hold a number.
pub fn number_text(cell: &Cell, decimal: DecimalMark) -> std::result::Result<Option<String>, String> {
    match cell {
        Cell::Empty => Ok(None),
        Cell::Number(v) => Ok(Some(format!("{v}"))),
        Cell::Other(what) => Err(format!("holds {what}, not a number")),
        Cell::Text(t) => {
            let t = t.trim();
            match decimal {
                DecimalMark::Comma if t.contains('.') && t.contains(',') => Err(format!("value \"{t}\" is not a number (a thousands separator? write numbers without one)")),
                DecimalMark::Comma if t.contains('.') && t.parse::<f64>().is_ok() => Err(format!("value \"{t}\" has a decimal point, but this file's decimal mark is a comma")),
                DecimalMark::Comma => Ok(Some(t.replacen(',', ".", 1))),
                DecimalMark::Point if is_comma_number(t) => Err(format!("value \"{t}\" has a decimal comma, but this file's decimal mark is a point (a decimal comma in a comma-separated file?)")),
                DecimalMark::Point => Ok(Some(t.to_string())),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<RawTable> {
        read_delimited(Path::new("lab.csv"), text.as_bytes(), &Source::default())
    }

    #[test]
    fn reads_a_lab_export_and_names_places() {
        let t = read("Probe;D [mm];Fmax [N]\n1;0,91;131,2\n\n2;0,85;120,7\n\n\n").unwrap();
        assert_eq!(t.headers, vec!["Probe", "D [mm]", "Fmax [N]"]);
        assert_eq!(t.rows.len(), 2);
        assert_eq!(t.lines, vec![2, 4]);
        assert_eq!(t.format, "semicolon-separated, decimal comma, UTF-8");
        assert_eq!(t.place(1, Some(1)), "row 2 (line 4), column D [mm]");
        assert_eq!(number_text(&t.rows[0][1], t.decimal).unwrap().as_deref(), Some("0.91"));
    }

    #[test]
    fn a_trailing_delimiter_is_not_a_column() {
        let t = read("a;b;\n1;2;\n").unwrap();
        assert_eq!(t.headers, vec!["a", "b"]);
        assert!(read("a;;c\n1;2;3\n").unwrap_err().to_string().contains("column 2 has no name"));
        assert!(read("a,a\n1,2\n").unwrap_err().to_string().contains("appears twice"));
    }

    #[test]
    fn a_decimal_comma_in_a_comma_file_is_named() {
        let e = read("id,d,F\nA,0,91,131\n").unwrap_err().to_string();
        assert!(e.contains("row 1 (line 2)") && e.contains("decimal comma in a comma-separated file"), "{e}");
        let t = read("id,d\nA,\"0,91\"\n").unwrap();
        assert!(number_text(&t.rows[0][1], t.decimal).unwrap_err().contains("decimal comma"));
    }

    #[test]
    fn header_row_skips_a_preamble() {
        let opts = Source { header_row: Some(3), ..Source::default() };
        let t = read_delimited(Path::new("x.csv"), b"Rig 4, export of 2026-11-02\n\nid;d [mm]\nA;0,9\n", &opts).unwrap();
        assert_eq!(t.headers, vec!["id", "d [mm]"]);
        assert_eq!(t.lines, vec![4]);
        assert!(t.format.ends_with("header on line 3"));
    }

    #[test]
    fn column_letters_count_like_a_spreadsheet() {
        assert_eq!(column_letters(0), "A");
        assert_eq!(column_letters(25), "Z");
        assert_eq!(column_letters(26), "AA");
        assert_eq!(column_letters(701), "ZZ");
        assert_eq!(column_letters(702), "AAA");
    }
}

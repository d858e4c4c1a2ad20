//! Delimited text: bytes → text (encoding), then → rows of cells (delimiter and decimal mark).
//!
//! # Encoding
//!
//! A UTF-8 byte-order mark is dropped; UTF-16 with its mark (Excel's "Unicode text" export) is
//! decoded; bytes that are valid UTF-8 are UTF-8; anything else is read as Windows-1252 (the
//! superset of Latin-1 that Western Windows lab software writes: `µ` is 0xB5, `°` is 0xB0) and
//! the record says so. A file with NUL bytes outside UTF-16 is not text and is refused.
//!
//! # Delimiter
//!
//! Comma, semicolon or tab, decided on the header line: the candidate that splits it into two
//! fields or more (outside double quotes and outside a unit's brackets, as in `F (N, peak)`).
//! A header split by two candidates mixes delimiters and is refused; a header split by none is
//! one column. A study may state the delimiter (`delimiter = ";"`).
//!
//! # Decimal mark
//!
//! A point, or a comma where the delimiter is not a comma and number cells are written `0,91`.
//! A file holds one decimal mark: `0,91` beside `0.91` is refused. Where the delimiter is a
//! comma, a decimal comma splits cells: a row with more fields than the header whose extra
//! fields are digits is refused as "a decimal comma in a comma-separated file". A study may state
//! the mark (`decimal = "comma"`).
//!
//! Verified by the unit tests below and `tests/intake.rs`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// A field delimiter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Delimiter {
    /// `,`
    #[serde(rename = ",")]
    Comma,
    /// `;`
    #[serde(rename = ";")]
    Semicolon,
    /// A tab.
    #[serde(rename = "tab", alias = "\t")]
    Tab,
}

impl Delimiter {
    /// Its character.
    pub fn char(self) -> char {
        match self {
            Delimiter::Comma => ',',
            Delimiter::Semicolon => ';',
            Delimiter::Tab => '\t',
        }
    }
    /// How the record names it.
    pub fn word(self) -> &'static str {
        match self {
            Delimiter::Comma => "comma-separated",
            Delimiter::Semicolon => "semicolon-separated",
            Delimiter::Tab => "tab-separated",
        }
    }
    const ALL: [Delimiter; 3] = [Delimiter::Comma, Delimiter::Semicolon, Delimiter::Tab];
}

/// A decimal mark.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DecimalMark {
    /// `0.91`
    Point,
    /// `0,91`
    Comma,
}

/// The text of a file and how it was decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded {
    /// The text (no byte-order mark).
    pub text: String,
    /// `UTF-8`, `UTF-8 with BOM`, `UTF-16LE`, `Windows-1252`.
    pub encoding: &'static str,
}

/// Decodes the bytes of a text file (module docs).
pub fn decode(path: &Path, bytes: &[u8]) -> Result<Decoded> {
    if let Some(rest) = bytes.strip_prefix(&[0xEF, 0xBB, 0xBF]) {
        return match std::str::from_utf8(rest) {
            Ok(t) => Ok(Decoded { text: t.to_string(), encoding: "UTF-8 with BOM" }),
            Err(e) => Err(not_utf8(path, rest, e.valid_up_to())),
        };
    }
    for (bom, enc, name) in [(&[0xFF, 0xFE][..], encoding_rs::UTF_16LE, "UTF-16LE"), (&[0xFE, 0xFF][..], encoding_rs::UTF_16BE, "UTF-16BE")] {
        if bytes.starts_with(bom) {
            let (text, _, bad) = enc.decode(bytes);
            if bad {
                return Err(Error::data_file(path, "file", format!("is not valid {name} text although it starts with the {name} byte-order mark")));
            }
            return Ok(Decoded { text: text.trim_start_matches('\u{feff}').to_string(), encoding: name });
        }
    }
    if let Some(k) = bytes.iter().position(|&b| b == 0) {
        let line = bytes[..k].iter().filter(|&&b| b == b'\n').count() + 1;
        return Err(Error::data_file(path, format!("line {line}"), "holds a NUL byte: this is not a text file (a spreadsheet is read by its extension: .xlsx, .xls, .ods)"));
    }
    match std::str::from_utf8(bytes) {
        Ok(t) => Ok(Decoded { text: t.to_string(), encoding: "UTF-8" }),
        Err(_) => {
            let (text, _, _) = encoding_rs::WINDOWS_1252.decode(bytes);
            Ok(Decoded { text: text.into_owned(), encoding: "Windows-1252" })
        }
    }
}

fn not_utf8(path: &Path, bytes: &[u8], at: usize) -> Error {
    let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
    Error::data_file(path, format!("line {line}"), "is not UTF-8 text although the file starts with the UTF-8 byte-order mark")
}

/// Fields of one line split at `delim` (double quotes respected and removed, `""` inside quotes
/// is a quote; blanks around fields trimmed).
pub fn split_line(line: &str, delim: char) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.trim_end_matches('\r').chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                out.last_mut().expect("one field at least").push('"');
            }
            '"' => quoted = !quoted,
            c if c == delim && !quoted => out.push(String::new()),
            _ => out.last_mut().expect("one field at least").push(c),
        }
    }
    out.into_iter().map(|f| f.trim().to_string()).collect()
}

/// A number cell written with a decimal comma: `0,91`, `-1,5e-3`, `12,`.
pub fn is_comma_number(cell: &str) -> bool {
    let t = cell.trim().trim_start_matches(['-', '+']);
    match t.split_once(',') {
        Some((a, b)) => {
            let b = match b.find(['e', 'E']) {
                Some(k) if b[k + 1..].trim_start_matches(['-', '+']).bytes().all(|c| c.is_ascii_digit()) && k + 1 < b.len() => &b[..k],
                Some(_) => return false,
                None => b,
            };
            !(a.is_empty() && b.is_empty()) && a.bytes().all(|c| c.is_ascii_digit()) && b.bytes().all(|c| c.is_ascii_digit())
        }
        None => false,
    }
}

/// A number cell written with a decimal point: `0.91`, `.5`, `1.5e3` (not integers, which read
/// the same with either mark).
pub fn is_point_number(cell: &str) -> bool {
    let t = cell.trim();
    t.contains('.') && !t.contains(',') && t.parse::<f64>().is_ok_and(f64::is_finite)
}

/// Lines of a text table: (physical line number, 1-based; the line).
pub type Lines<'a> = Vec<(usize, &'a str)>;

/// What the sniffer decided and the lines it applies to.
#[derive(Debug, Clone, PartialEq)]
pub struct Sniffed {
    /// The delimiter.
    pub delimiter: Delimiter,
    /// The decimal mark.
    pub decimal: DecimalMark,
    /// Whether each was stated by the study rather than detected.
    pub stated: (bool, bool),
}

/// Decides delimiter and decimal mark of a table whose header is `lines[0]` (module docs);
/// `stated` are the study's choices.
pub fn sniff(path: &Path, lines: &Lines, delimiter: Option<Delimiter>, decimal: Option<DecimalMark>) -> Result<Sniffed> {
    let (header_line, header) = lines[0];
    let delim = match delimiter {
        Some(d) => d,
        None => {
            // Header names do not hold delimiters, except inside a unit's brackets
            // (`F (N, peak)`): those are set aside.
            let mut bare = String::new();
            let mut depth = 0i32;
            for c in header.chars() {
                match c {
                    '(' | '[' => depth += 1,
                    ')' | ']' => depth -= 1,
                    _ if depth <= 0 => bare.push(c),
                    _ => {}
                }
            }
            let splits: Vec<Delimiter> = Delimiter::ALL.into_iter().filter(|d| split_line(&bare, d.char()).len() >= 2).collect();
            match splits.len() {
                0 => Delimiter::Comma,
                1 => splits[0],
                _ => {
                    let counts: Vec<String> = splits.iter().map(|d| format!("{} fields at '{}'", split_line(header, d.char()).len(), if *d == Delimiter::Tab { "\\t".to_string() } else { d.char().to_string() })).collect();
                    return Err(Error::data_file(
                        path,
                        format!("line {header_line} (header)"),
                        format!("mixed delimiters: the header splits into {}; use one delimiter throughout, or state it in the study (delimiter = \";\")", counts.join(" and ")),
                    ));
                }
            }
        }
    };
    let mark = match decimal {
        Some(m) => m,
        None if delim == Delimiter::Comma => DecimalMark::Point,
        None => {
            let (mut comma, mut point): (Option<(usize, String)>, Option<(usize, String)>) = (None, None);
            for (line, l) in &lines[1..] {
                for cell in split_line(l, delim.char()) {
                    if comma.is_none() && is_comma_number(&cell) {
                        comma = Some((*line, cell));
                    } else if point.is_none() && is_point_number(&cell) {
                        point = Some((*line, cell));
                    }
                }
                if comma.is_some() && point.is_some() {
                    break;
                }
            }
            match (comma, point) {
                (Some((lc, c)), Some((lp, p))) => {
                    return Err(Error::data_file(
                        path,
                        format!("lines {lc} and {lp}"),
                        format!("mixed decimal marks: \"{c}\" (line {lc}) has a decimal comma, \"{p}\" (line {lp}) a decimal point; use one throughout, or state it in the study (decimal = \"comma\")"),
                    ));
                }
                (Some(_), None) => DecimalMark::Comma,
                _ => DecimalMark::Point,
            }
        }
    };
    Ok(Sniffed { delimiter: delim, decimal: mark, stated: (delimiter.is_some(), decimal.is_some()) })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(t: &str) -> Vec<(usize, &str)> {
        t.lines().enumerate().map(|(i, l)| (i + 1, l)).collect()
    }

    fn sniffed(t: &str) -> Result<(Delimiter, DecimalMark)> {
        sniff(Path::new("x.csv"), &lines(t), None, None).map(|s| (s.delimiter, s.decimal))
    }

    #[test]
    fn finds_delimiter_and_decimal_mark() {
        assert_eq!(sniffed("Probe;D [mm];Fmax [N]\n1;0,91;131,2\n2;0,85;120,7\n").unwrap(), (Delimiter::Semicolon, DecimalMark::Comma));
        assert_eq!(sniffed("id,material,diameter_m\nA,X,0.0009\n").unwrap(), (Delimiter::Comma, DecimalMark::Point));
        assert_eq!(sniffed("id\td\nA\t0,9\n").unwrap(), (Delimiter::Tab, DecimalMark::Comma));
        assert_eq!(sniffed("id;d\nA;0.9\n").unwrap(), (Delimiter::Semicolon, DecimalMark::Point));
        // Integers only: either mark reads the same; a point is assumed.
        assert_eq!(sniffed("id;n\nA;12\n").unwrap(), (Delimiter::Semicolon, DecimalMark::Point));
        // A comma inside a unit's brackets does not make a semicolon header mixed.
        assert_eq!(sniffed("id;F (N, peak);d\nA;1,5;2,5\nB;3,5;4\n").unwrap().0, Delimiter::Semicolon);
        // One column.
        assert_eq!(sniffed("id\nA\n").unwrap().0, Delimiter::Comma);
    }

    #[test]
    fn refuses_mixed_delimiters_and_marks() {
        let e = sniffed("id;material;d,F\nA;X;1,2\n").unwrap_err().to_string();
        assert!(e.contains("mixed delimiters") && e.contains("line 1"), "{e}");
        let e = sniffed("id;d\nA;0,91\nB;0.85\n").unwrap_err().to_string();
        assert!(e.contains("mixed decimal marks") && e.contains("\"0,91\"") && e.contains("line 3"), "{e}");
    }

    #[test]
    fn decodes_bom_utf16_and_windows_1252() {
        let p = Path::new("x.csv");
        assert_eq!(decode(p, b"\xEF\xBB\xBFid\n").unwrap(), Decoded { text: "id\n".into(), encoding: "UTF-8 with BOM" });
        let latin = decode(p, b"d [\xB5m];T [\xB0C]\n").unwrap();
        assert_eq!(latin.text, "d [µm];T [°C]\n");
        assert_eq!(latin.encoding, "Windows-1252");
        let utf16: Vec<u8> = [0xFF, 0xFE].into_iter().chain("id\td\n".encode_utf16().flat_map(|u| u.to_le_bytes())).collect();
        assert_eq!(decode(p, &utf16).unwrap().text, "id\td\n");
        assert!(decode(p, b"PK\x03\x04\x00\x00").unwrap_err().to_string().contains("NUL"));
    }

    #[test]
    fn splits_quoted_fields() {
        assert_eq!(split_line("a;\"b;c\";\"say \"\"hi\"\"\"", ';'), vec!["a", "b;c", "say \"hi\""]);
        assert_eq!(split_line(" a , b \r", ','), vec!["a", "b"]);
        assert!(is_comma_number("0,91") && is_comma_number("-1,5e-3") && !is_comma_number("1,2,3") && !is_comma_number("a,b") && !is_comma_number(","));
        assert!(is_point_number("0.91") && !is_point_number("12") && !is_point_number("a.b"));
    }
}

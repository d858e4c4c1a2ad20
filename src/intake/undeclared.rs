//! Columns a study must declare, refused where it does not: an unused column of yes/no values,
//! of whole numbers under a count's name, or of failure origins is never guessed and never
//! passed over ([`check_unused`]); the keys to declare are those of [`super::observed`] (and
//! `origin` of [`super::origins`]). A column the study lists in `ignore` is looked at and left
//! out on purpose — a column of failure origins so ignored is said with what it changes.
//!
//! Verified by `intake::observed`'s unit tests (they read files through both) and
//! `tests/censoring.rs`.

use super::observed::prefix;
use super::units::fold;
use super::{Cell, MapOrigin, Provenance, RawTable, Source};
use crate::error::{Error, Result};

/// Yes/no words of lab sheets (compared folded): English, German, French, Spanish, Italian,
/// Dutch, Scandinavian, and outcome words.
const YES_NO: [&str; 42] = [
    "yes", "no", "y", "n", "true", "false", "t", "f", "ja", "nein", "j", "oui", "non", "si", "sí", "vero", "falso", "nee", "nej", "x", "✓", "✗", "wahr", "falsch", "broken", "unbroken", "notbroken", "intact", "gebrochen", "nichtgebrochen", "ungebrochen", "heil", "failed", "survived", "runout", "censored", "durchläufer", "durchlaeufer", "bruch", "keinbruch", "ok", "nok",
];

/// Header words of an outcome column (a 0/1 column under one of these is a yes/no column).
const OUTCOME_HEADERS: [&str; 14] = ["broken", "gebrochen", "bruch", "failed", "failure", "censored", "censor", "status", "runout", "survived", "intact", "durchläufer", "durchlaeufer", "outcome"];

/// Header words of a count column.
const COUNT_HEADERS: [&str; 18] = ["count", "counts", "n", "anzahl", "number", "numberof", "frequency", "freq", "häufigkeit", "haeufigkeit", "stückzahl", "stueckzahl", "stück", "stk", "specimens", "nspecimens", "quantity", "qty"];

/// Outcome words that say the specimen broke, and that it did not (folded), whatever the header.
const BROKE_WORDS: [&str; 4] = ["broken", "gebrochen", "bruch", "failed"];
const NOT_BROKEN_WORDS: [&str; 12] = ["unbroken", "notbroken", "intact", "nichtgebrochen", "ungebrochen", "heil", "survived", "runout", "censored", "durchläufer", "durchlaeufer", "keinbruch"];

/// Affirmative and negative words (folded): their meaning is the header's.
const AFFIRMATIVE: [&str; 15] = ["yes", "y", "true", "t", "ja", "j", "oui", "si", "sí", "vero", "wahr", "x", "✓", "1", "ok"];
const NEGATIVE: [&str; 13] = ["no", "n", "false", "f", "nein", "non", "falso", "nee", "nej", "✗", "falsch", "0", "nok"];

/// Which of a yes/no column's `values` says a specimen broke and which that it did not, as the
/// declaration `broken = { yes, no }` needs them; None where the header (`header`, folded) and
/// the values leave it open. An outcome word says it alone (`intact`, `gebrochen`); a yes/no
/// word means what the header asks: yes under `gebrochen` or `failed` broke, yes under
/// `Durchläufer`, `runout`, `survived` or `censored` did not. `ok`/`nok` count as yes/no only
/// under such a header.
fn broke_and_not(header: &str, values: &[String]) -> Option<(String, String)> {
    // The header's question: +1 "did it break?", −1 "did it survive?" (checked first: the
    // words of survival hold those of breaking, `nichtgebrochen`).
    let asks = if NOT_BROKEN_WORDS.iter().chain(&["suspended", "survival"]).any(|w| header.contains(w)) {
        Some(false)
    } else if BROKE_WORDS.iter().chain(&["failure", "fracture", "break"]).any(|w| header.contains(w)) {
        Some(true)
    } else {
        None
    };
    let broke = |v: &String| -> Option<bool> {
        let f = fold(v);
        if BROKE_WORDS.contains(&f.as_str()) {
            Some(true)
        } else if NOT_BROKEN_WORDS.contains(&f.as_str()) {
            Some(false)
        } else if AFFIRMATIVE.contains(&f.as_str()) {
            asks
        } else if NEGATIVE.contains(&f.as_str()) {
            asks.map(|a| !a)
        } else {
            None
        }
    };
    let [a, b] = values else { return None };
    match (broke(a), broke(b)) {
        (Some(true), Some(false)) => Some((a.clone(), b.clone())),
        (Some(false), Some(true)) => Some((b.clone(), a.clone())),
        _ => None,
    }
}

/// The distinct non-empty values of column `c` over `rows`, as text, in order of appearance.
fn distinct_cells(table: &RawTable, rows: &[usize], c: usize) -> Vec<String> {
    let mut distinct: Vec<String> = Vec::new();
    for &row in rows {
        let t = match &table.rows[row][c] {
            Cell::Number(v) => format!("{v}"),
            Cell::Text(t) | Cell::Other(t) => t.trim().to_string(),
            Cell::Empty => continue,
        };
        if !distinct.contains(&t) {
            distinct.push(t);
        }
    }
    distinct
}

/// Refuses every unused column of `rows` that looks like what a study must declare (module
/// docs): yes/no values, a count, or failure origins — every such column in one message, so
/// that a file with several to declare needs one run. `ignore`d columns move from the unused to the ignored ones
/// of `provenance`; an `ignore` naming no column is refused.
pub fn check_unused(table: &RawTable, rows: &[usize], provenance: &mut Provenance, src: &Source, origin: &MapOrigin) -> Result<()> {
    let key = prefix(origin);
    for name in &src.ignore {
        let Some(c) = super::factors::find_column(&table.headers, name) else {
            return Err(Error::config(&origin.file, format!("{key}ignore"), format!("{} has no column `{name}` (its columns: {})", table.origin.path.display(), table.headers.iter().map(|h| format!("`{h}`")).collect::<Vec<_>>().join(", "))));
        };
        let h = table.headers[c].clone();
        if !provenance.unused.contains(&h) {
            return Err(Error::config(&origin.file, format!("{key}ignore"), format!("`{name}` is a column the study reads; `ignore` is for columns it does not")));
        }
        provenance.unused.retain(|u| *u != h);
        // Failure origins ignored on purpose still change what a fit saw: said with the material.
        let distinct = distinct_cells(table, rows, c);
        if super::origins::looks_like_origins(&fold(&super::units::parse_header(&h).name), &distinct.iter().map(|v| fold(v)).collect::<Vec<_>>()) {
            let key = if origin.key.is_empty() { "origin".to_string() } else { format!("{}.origin", super::factors::table_key(origin)) };
            provenance.observed.push(format!(
                "failure origins (`{h}`, ignored): one law is fitted to the breaks of every origin; {key} = \"{h}\" would give each origin its own law (discrepancy and main studies), which can change a comparison"
            ));
        }
        provenance.ignored.push(h);
    }
    // Every refusal at once, so that a file with several columns to declare needs one run.
    let mut refused: Vec<(String, String)> = Vec::new();
    for h in &provenance.unused {
        let Some(c) = table.headers.iter().position(|x| x == h) else { continue };
        let cells: Vec<&Cell> = rows.iter().map(|&row| &table.rows[row][c]).filter(|cell| !matches!(cell, Cell::Empty)).collect();
        if cells.is_empty() {
            continue;
        }
        let distinct = distinct_cells(table, rows, c);
        let name = fold(&super::units::parse_header(h).name);
        let folded_values: Vec<String> = distinct.iter().map(|v| fold(v)).collect();
        let words = folded_values.iter().all(|v| YES_NO.contains(&v.as_str()));
        let zero_one = folded_values.iter().all(|v| v == "0" || v == "1") && OUTCOME_HEADERS.contains(&name.as_str());
        if (words || zero_one) && distinct.len() <= 3 {
            let shown = distinct.iter().map(|v| format!("\"{v}\"")).collect::<Vec<_>>().join(", ");
            let declare = match broke_and_not(&name, &distinct) {
                Some((yes, no)) => format!("{key}broken = {{ column = \"{h}\", yes = \"{yes}\", no = \"{no}\" }} (yes: broke at the row's value; no: did not break by it)"),
                None => format!("{key}broken = {{ column = \"{h}\", yes = …, no = … }} with yes the value of a specimen that broke at the row's value and no that of one that did not break by it (the header and values do not say which is which)"),
            };
            refused.push((
                format!("column {h}"),
                format!("holds yes/no values ({shown}) that nothing declares: if it says which specimens broke, declare it: {declare}; if it is a recorded factor, declare it in `factors`; if it says nothing of the strength, {key}ignore = [\"{h}\"]"),
            ));
            continue;
        }
        let whole = cells.iter().all(|cell| {
            let t = match cell {
                Cell::Number(v) => Some(*v),
                Cell::Text(t) => t.trim().parse::<f64>().ok(),
                _ => None,
            };
            t.is_some_and(|v| v >= 0.0 && v.fract() == 0.0)
        });
        if whole && COUNT_HEADERS.contains(&name.as_str()) {
            refused.push((
                format!("column {h}"),
                format!("holds whole numbers under a count's name, and nothing declares it: if each row stands for that many specimens, declare it: {key}count = \"{h}\"; if it is something else, {key}ignore = [\"{h}\"]"),
            ));
            continue;
        }
        if super::origins::looks_like_origins(&name, &folded_values) {
            let shown = distinct.iter().take(6).map(|v| format!("\"{v}\"")).collect::<Vec<_>>().join(", ");
            let more = if distinct.len() > 6 { format!(" and {} more", distinct.len() - 6) } else { String::new() };
            let table_key = super::factors::table_key(origin);
            let origin_key = if table_key.is_empty() { "origin".to_string() } else { format!("{table_key}.origin") };
            refused.push((
                format!("column {h}"),
                format!("looks like failure origins (fractography: {shown}{more}) that nothing declares: declare it: {origin_key} = \"{h}\" (a discrepancy study: each origin's Weibull law with the other origins' breaks censored, the test of one shared modulus, the lifetime with every origin acting; a main study: every origin's law acting in its strength models without effects); if it is a recorded factor, declare it in `factors`; to fit one law to the breaks of every origin (the lifetime study does), {key}ignore = [\"{h}\"]"),
            ));
        }
    }
    match refused.split_first() {
        None => Ok(()),
        Some(((location, rule), rest)) => {
            let more: String = rest.iter().map(|(l, r)| format!("; and {l}: {r}")).collect();
            Err(Error::data_file(&table.origin.path, location.clone(), format!("{rule}{more}")))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::broke_and_not;

    fn of(header: &str, values: &[&str]) -> Option<(String, String)> {
        broke_and_not(&super::fold(header), &values.iter().map(|v| v.to_string()).collect::<Vec<_>>())
    }

    #[test]
    fn the_declaration_offered_puts_the_value_of_a_break_under_yes_whatever_its_order() {
        let pair = |y: &str, n: &str| Some((y.to_string(), n.to_string()));
        // A new user's file listed "no" first: yes is still the break.
        assert_eq!(of("broken", &["no", "yes"]), pair("yes", "no"));
        assert_eq!(of("gebrochen", &["nein", "ja"]), pair("ja", "nein"));
        assert_eq!(of("Bruch", &["ja", "nein"]), pair("ja", "nein"));
        // A question of survival: yes did not break.
        assert_eq!(of("Durchläufer", &["ja", "nein"]), pair("nein", "ja"));
        assert_eq!(of("runout", &["1", "0"]), pair("0", "1"));
        assert_eq!(of("nicht gebrochen", &["ja", "nein"]), pair("nein", "ja"));
        assert_eq!(of("failed", &["0", "1"]), pair("1", "0"));
        // Outcome words say it under any header.
        assert_eq!(of("Zustand", &["intact", "broken"]), pair("broken", "intact"));
        // Open: a header that asks nothing, one value only, two values of one meaning.
        assert_eq!(of("status", &["ok", "nok"]), None);
        assert_eq!(of("gebrochen", &["ja"]), None);
        assert_eq!(of("Zustand", &["yes", "no"]), None);
    }
}

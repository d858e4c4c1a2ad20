//! Failure origins (fractography) as a lab file writes them: the column the study declares by
//! the material's `origin` key, read for every row ([`failure_origins`]; labels that differ only
//! in case are one origin), checked against what each row says once the rows are read
//! ([`check_origins`]: a break needs its origin, an empty cell or `none` is for a specimen that
//! did not break), and the words by which an undeclared column is recognised as origins
//! ([`looks_like_origins`], for [`super::undeclared::check_unused`] to refuse it with the key to
//! declare). Strength and crush files read them alike.

use super::{ColumnRecord, MapOrigin, Provenance, RawTable};
use crate::error::Result;
use crate::obs::Censor;

/// Header words of a failure-origin column (fractography), compared folded.
const ORIGIN_HEADERS: [&str; 36] = [
    "origin", "origins", "failureorigin", "fractureorigin", "flaworigin", "originoffracture", "originoffailure", "failuremode", "failuresite", "fracturesite", "initiationsite", "flawtype", "flaw", "defect", "defecttype", "fractography", "bruchursprung", "bruchausgang", "bruchausgangsort", "bruchstelle", "ursprung", "fehlerart", "fraktographie", "origine",
    // Headers under which labs write origins as codes (`V`, `O`, `K`): the values say nothing.
    "failuretype", "fracturetype", "fracturemode", "modeoffailure", "failurelocation", "fracturelocation", "bruchtyp", "bruchart", "bruchort", "fehlertyp", "versagensart", "typedefracture",
];

/// Words of failure origins (English, German, French), compared folded; `none` and its kin
/// alone do not make a column of origins.
const ORIGIN_WORDS: [&str; 40] = [
    "volume", "surface", "edge", "corner", "pore", "pores", "porosity", "inclusion", "agglomerate", "machining", "machiningdamage", "internal", "bulk", "subsurface", "nearsurface", "chamfer", "handling", "volumen", "oberfläche", "oberflaeche", "kante", "ecke", "poren", "porosität", "einschluss", "einschluß", "agglomerat", "bearbeitung", "innen", "rand", "arête", "arete", "coin", "pore(s)", "none", "keiner", "kein", "aucun", "unknown", "unbekannt",
];

/// Whether an unused column (folded header `name`, folded distinct values `values`) looks
/// like failure origins: a header naming origins over text values, or values that are all
/// origin words, at least one of them more than `none` or `unknown`.
pub(super) fn looks_like_origins(name: &str, values: &[String]) -> bool {
    let text = values.iter().any(|v| v.parse::<f64>().is_err());
    let blank = ["none", "keiner", "kein", "aucun", "unknown", "unbekannt"];
    let words = values.iter().all(|v| ORIGIN_WORDS.contains(&v.as_str())) && values.iter().any(|v| !blank.contains(&v.as_str()));
    text && ((ORIGIN_HEADERS.contains(&name) && values.len() <= 20) || words)
}

/// Each row's failure origin (fractography: volume, surface, edge, pore …) from the column
/// `column` that the study's key `key` names, over `rows`, as written (an empty cell empty:
/// [`check_origins`] refuses it on a break and reads it `none` on a specimen that did not
/// break). Records the column in `provenance` and
/// takes it off the unused columns; returns the origins and the column's index. Labels that
/// differ only in case are one origin ([`one_spelling`], said in `provenance`). Strength and
/// crush files read it alike.
pub fn failure_origins(table: &RawTable, rows: &[usize], column: &str, key: String, origin: &MapOrigin, provenance: &mut Provenance) -> Result<(Vec<String>, usize)> {
    let c = super::factors::declared_columns(table, provenance, &[(key, column.to_string())], origin, &table.origin.path)?[0].1;
    let mut out = Vec::with_capacity(rows.len());
    for &row in rows {
        // An empty cell is `none` where the specimen did not break, refused where it broke
        // ([`check_origins`], once the rows say which).
        out.push(table.text(row, c).map(|t| t.trim().to_string()).unwrap_or_default());
    }
    provenance.columns.push(ColumnRecord { source: table.headers[c].clone(), field: "failure origin".into(), unit: String::new(), conversion: "fractography".into(), found_by: "study".into() });
    provenance.unused.retain(|u| *u != table.headers[c]);
    provenance.observed.extend(one_spelling(&mut out));
    Ok((out, c))
}

/// Reads labels that differ only in case (`Oberfläche`, `oberfläche`) as one origin, spelt as
/// most rows spell it (the first seen among equals) — as the `broken` column's values are
/// compared without case; returns a line per label so read, for the run to say.
fn one_spelling(labels: &mut [String]) -> Vec<String> {
    let mut spellings: Vec<(String, Vec<(String, usize)>)> = Vec::new();
    for l in labels.iter() {
        let key = l.to_lowercase();
        let k = match spellings.iter().position(|(f, _)| *f == key) {
            Some(k) => k,
            None => {
                spellings.push((key, Vec::new()));
                spellings.len() - 1
            }
        };
        match spellings[k].1.iter_mut().find(|(s, _)| s == l) {
            Some(e) => e.1 += 1,
            None => spellings[k].1.push((l.clone(), 1)),
        }
    }
    let mut said = Vec::new();
    for (_, forms) in spellings.iter().filter(|(_, forms)| forms.len() > 1) {
        let main = forms.iter().fold(&forms[0], |best, f| if f.1 > best.1 { f } else { best }).0.clone();
        for (form, n) in forms.iter().filter(|(f, _)| *f != main) {
            for l in labels.iter_mut().filter(|l| *l == form) {
                *l = main.clone();
            }
            said.push(format!("failure origin `{form}` ({n} row{}) read as `{main}` (origin labels are compared without case)", if *n == 1 { "" } else { "s" }));
        }
    }
    said
}

/// Checks each specimen's failure origin against what its row says: the first specimen that
/// broke (exact, in a class or at or below its value) and whose origin is empty or reads
/// `none`, the word kept for a specimen that did not break, is returned with the rule for the
/// caller to refuse ([`EMPTY_ON_A_BREAK`], [`NONE_ON_A_BREAK`]); an empty cell of a specimen
/// that did not break becomes `none`. An origin written on a specimen that did not break is not used (it
/// survived every origin's flaws, whatever the cell says): recorded in `provenance` with the
/// count and the specimens' `ids` (the first eight), so the run says it instead of dropping it.
pub fn check_origins(x: crate::obs::Obs, origins: &mut [String], ids: &[String], provenance: &mut Provenance) -> Option<(usize, &'static str)> {
    if let Some(i) = (0..x.len()).find(|&i| x.kind(i) != Censor::Right && origins[i].is_empty()) {
        return Some((i, EMPTY_ON_A_BREAK));
    }
    if let Some(i) = (0..x.len()).find(|&i| x.kind(i) != Censor::Right && origins[i].eq_ignore_ascii_case("none")) {
        return Some((i, NONE_ON_A_BREAK));
    }
    for o in origins.iter_mut().filter(|o| o.is_empty()) {
        *o = "none".into();
    }
    let named: Vec<usize> = (0..x.len()).filter(|&i| x.kind(i) == Censor::Right && !origins[i].eq_ignore_ascii_case("none")).collect();
    if !named.is_empty() {
        const SHOWN: usize = 8;
        let mut which = named.iter().take(SHOWN).map(|&i| format!("{} (`{}`)", ids[i], origins[i])).collect::<Vec<_>>().join(", ");
        if named.len() > SHOWN {
            which.push_str(&format!(" and {} more", named.len() - SHOWN));
        }
        let n = named.len();
        provenance.observed.push(format!("failure origin: {n} specimen{} that did not break {} an origin ({which}); not used: a specimen that did not break survived every origin's flaws", if n == 1 { "" } else { "s" }, if n == 1 { "names" } else { "name" }));
    }
    None
}

/// The rule [`check_origins`] enforces on an empty cell, in words.
pub const EMPTY_ON_A_BREAK: &str = "an empty failure origin on a specimen that broke: write where it broke (an empty cell, like `none`, is for a specimen that did not break)";

/// The rule [`check_origins`] enforces, in words.
pub const NONE_ON_A_BREAK: &str = "failure origin `none` on a specimen that broke: write where it broke (`none` is for a specimen that did not break)";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn origin_labels_that_differ_in_case_are_one_origin_and_said() {
        let mut l: Vec<String> = ["Oberfläche", "Volumen", "oberfläche", "Oberfläche", "VOLUMEN", "Volumen"].iter().map(|s| s.to_string()).collect();
        let said = one_spelling(&mut l);
        assert_eq!(l, ["Oberfläche", "Volumen", "Oberfläche", "Oberfläche", "Volumen", "Volumen"]);
        assert_eq!(said, ["failure origin `oberfläche` (1 row) read as `Oberfläche` (origin labels are compared without case)", "failure origin `VOLUMEN` (1 row) read as `Volumen` (origin labels are compared without case)"]);
        let mut same: Vec<String> = vec!["a".into(), "b".into()];
        assert!(one_spelling(&mut same).is_empty());
    }
}

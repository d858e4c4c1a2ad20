//! Property-based tests of every input parser: whatever the bytes, a parser returns either a
//! value without a non-finite number or a clean `partlife::Error` — never a panic — and the CLI
//! never leaves a half-written report.
//!
//! Inputs come from two strategies:
//! * arbitrary bytes (with and without the valid file's header in front of them);
//! * near-valid mutations of the shipped files: a cell replaced by a nasty token (`NaN`, `1e308`,
//!   `-0`, a quote, a comma, an empty string, …), lines deleted, duplicated or swapped, a field
//!   dropped or added, a header name repeated, the text truncated or spliced with odd bytes.
//!
//! Parsers: crush CSV, force–displacement curve CSV, observation CSV, impact spectrum CSV,
//! Table 1 CSV, phase-fraction CSV, and one shipped study of every kind (`study::load`, which also reads the files a
//! study names). The CI tests run a fixed-seed sample (about 4 000 cases); the ignored test runs
//! twenty times more from a random seed. `PARTLIFE_PROPERTY_TRACE=1` prints every case a parser
//! took more than 0.5 s over (a parser must not hang on any input).

mod common;

use std::path::{Path, PathBuf};

use partlife::io::TempDir;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};

/// Tokens that break parsers: non-numbers, extremes, separators, quotes, odd Unicode.
const NASTY: [&str; 24] = [
    "", " ", "NaN", "nan", "inf", "-inf", "1e308", "1e-300", "-0", "0", "-1", "1e999", "abc", "\"", "\"\"", ",", "1,2", "0x10", "１", "1e", "--1", "[]", "{}", "\u{feff}",
];
/// Byte runs spliced into a file.
const SPLICE: [&str; 10] = ["\"", "\0", "\r\n", "\u{feff}", "é", ",,,", "[[", "]]", " = ", "#"];

/// One parser under test: the valid file it starts from and what it returns (every number of
/// the parsed value, to check they are finite). A case is written next to its valid file
/// (`datasets/case.csv`, `studies/case.toml`), so that a study's relative paths resolve.
struct Parser {
    name: &'static str,
    /// The valid file, relative to the repository.
    base: &'static str,
    parse: fn(&Path) -> partlife::Result<Vec<f64>>,
}

impl Parser {
    /// Where a case is written in the scratch copy of the repository.
    fn target(&self) -> &'static str {
        if self.base.ends_with(".toml") { "studies/case.toml" } else { "datasets/case.csv" }
    }
}

/// A campaign file as lab software writes it (semicolons, decimal commas, units in the
/// headers), one material picked.
fn crush_lab(p: &Path) -> partlife::Result<Vec<f64>> {
    let src = partlife::intake::Source { material: Some("BL 16/30".into()), ..partlife::intake::Source::file(p) };
    let d = partlife::data::read_crush_source(&src, &Default::default())?;
    Ok(d.records.iter().flat_map(|r| [Some(r.diameter_m), Some(r.crush_force_n), r.roundness, r.sphericity, r.temperature_c].into_iter().flatten()).collect())
}

fn crush(p: &Path) -> partlife::Result<Vec<f64>> {
    let d = partlife::data::read_crush(p)?;
    Ok(d.records.iter().flat_map(|r| [Some(r.diameter_m), Some(r.crush_force_n), r.roundness, r.sphericity, r.temperature_c].into_iter().flatten()).collect())
}

fn curves(p: &Path) -> partlife::Result<Vec<f64>> {
    let c = partlife::calibrate::data::load_curves(p, Some(20.0))?;
    Ok(c.iter().flat_map(|c| std::iter::once(c.diameter).chain(c.displacement.iter().copied()).chain(c.force.iter().copied())).collect())
}

fn observations(p: &Path) -> partlife::Result<Vec<f64>> {
    let mut outputs: Vec<partlife::model::OutputSpec> = [15, 35, 60, 70, 80, 110].iter().map(|h| partlife::model::OutputSpec::new(format!("vz_at_{h}mm"), "m/s")).collect();
    outputs.push(partlife::model::OutputSpec::new("mass_flow", "kg/s"));
    let o = partlife::calibrate::data::load_observations(p, &outputs)?;
    Ok(o.values.iter().chain(&o.sigma).copied().collect())
}

fn spectrum(p: &Path) -> partlife::Result<Vec<f64>> {
    Ok(partlife::dist::read_spectrum(p, "tube", 1)?.into_iter().flat_map(|(a, b)| [a, b]).collect())
}

fn table1(p: &Path) -> partlife::Result<Vec<f64>> {
    let rows = partlife::data::read_table1(p)?;
    Ok(rows.iter().flat_map(|r| r.cells.iter().flat_map(|c| [c.min, c.max].into_iter().flatten())).collect())
}

fn phases(p: &Path) -> partlife::Result<Vec<f64>> {
    let t = partlife::phases::read_phases(p)?;
    Ok(t.temperatures_c.iter().copied().chain(t.fractions.iter().flatten().copied()).collect())
}

/// A study: loads (and validates) it; a non-finite number in an accepted study is a failure.
fn study(p: &Path) -> partlife::Result<Vec<f64>> {
    partlife::study::load(p)?;
    let text = std::fs::read_to_string(p).unwrap_or_default();
    let mut numbers = Vec::new();
    if let Ok(table) = text.parse::<toml::Table>() {
        collect_floats(&toml::Value::Table(table), &mut numbers);
    }
    Ok(numbers)
}

fn collect_floats(v: &toml::Value, out: &mut Vec<f64>) {
    match v {
        toml::Value::Float(f) => out.push(*f),
        toml::Value::Array(a) => a.iter().for_each(|v| collect_floats(v, out)),
        toml::Value::Table(t) => t.values().for_each(|v| collect_floats(v, out)),
        _ => {}
    }
}

const CSV_PARSERS: [Parser; 7] = [
    Parser { name: "crush CSV", base: "datasets/crush_gen4.csv", parse: crush },
    Parser { name: "lab export CSV (semicolons, decimal commas, mm)", base: "datasets/examples/crush_campaign_semicolon.csv", parse: crush_lab },
    Parser { name: "curve CSV", base: "datasets/crush_curves_gen3_rt.csv", parse: curves },
    Parser { name: "observation CSV", base: "datasets/dem_rig_profile.csv", parse: observations },
    Parser { name: "spectrum CSV", base: "datasets/dem_cold_test_impact_spectrum.csv", parse: spectrum },
    Parser { name: "Table 1 CSV", base: "datasets/table1_particle_properties.csv", parse: table1 },
    Parser { name: "phase-fraction CSV", base: "datasets/phases_granulated_illustrative.csv", parse: phases },
];

/// One shipped study of every kind.
const STUDY_PARSERS: [Parser; 10] = [
    Parser { name: "lifetime study", base: "studies/lifetime.toml", parse: study },
    Parser { name: "dem study", base: "studies/dem_cold_test.toml", parse: study },
    Parser { name: "crush study", base: "studies/crush_gen3_rt.toml", parse: study },
    Parser { name: "calibrate study", base: "studies/calibrate_gen3_rt.toml", parse: study },
    Parser { name: "uq study", base: "studies/gen4_vs_bl.toml", parse: study },
    Parser { name: "discrepancy study", base: "studies/discrepancy_crush.toml", parse: study },
    Parser { name: "discrepancy_curves study", base: "studies/discrepancy_curves.toml", parse: study },
    Parser { name: "experiments study", base: "studies/experiments.toml", parse: study },
    Parser { name: "temperature study", base: "studies/temperature.toml", parse: study },
    Parser { name: "microstructure study", base: "studies/microstructure_image.toml", parse: study },
];

/// A scratch copy of the repository's studies/ and datasets/.
fn scratch() -> TempDir {
    let dir = TempDir::new("properties").unwrap();
    for sub in ["studies", "datasets"] {
        std::fs::create_dir_all(dir.path().join(sub)).unwrap();
        for e in std::fs::read_dir(common::root().join(sub)).unwrap().flatten() {
            if e.path().is_file() {
                std::fs::copy(e.path(), dir.path().join(sub).join(e.file_name())).unwrap();
            }
        }
    }
    dir
}

/// The file names under the scratch's studies/ and datasets/ (what a study's message may name).
fn known_files(dir: &Path) -> Vec<String> {
    ["studies", "datasets"].iter().flat_map(|sub| std::fs::read_dir(dir.join(sub)).into_iter().flatten().flatten().map(|e| e.file_name().to_string_lossy().into_owned())).filter(|n| !n.starts_with("case.")).collect()
}

/// Mutation operations: (kind, position, argument).
fn ops() -> impl Strategy<Value = Vec<(u8, u32, u32)>> {
    prop::collection::vec((0u8..9, any::<u32>(), any::<u32>()), 1..5)
}

/// Applies the operations to a text: cells of a CSV (fields between commas) or values of a
/// TOML file (right of `=`) replaced, lines deleted/duplicated/swapped, fields dropped/added,
/// header names repeated, truncation, splices.
fn mutate(base: &str, ops: &[(u8, u32, u32)]) -> String {
    let mut lines: Vec<String> = base.lines().map(String::from).collect();
    for &(kind, pos, arg) in ops {
        if lines.is_empty() {
            lines.push(String::new());
        }
        let n = lines.len();
        let l = pos as usize % n;
        match kind {
            0 => {
                let token = NASTY[arg as usize % NASTY.len()];
                if let Some((key, _)) = lines[l].split_once('=') {
                    lines[l] = format!("{key}= {token}");
                } else {
                    let mut f: Vec<String> = lines[l].split(',').map(String::from).collect();
                    let k = (arg as usize / NASTY.len()) % f.len();
                    f[k] = token.to_string();
                    lines[l] = f.join(",");
                }
            }
            1 => {
                lines.remove(l);
            }
            2 => {
                let copy = lines[l].clone();
                lines.insert(l, copy);
            }
            3 => {
                if let Some(cut) = lines[l].rfind([',', '=']) {
                    lines[l].truncate(cut);
                }
            }
            4 => lines[l].push_str(",x"),
            5 => {
                let text = lines.join("\n");
                let mut at = arg as usize % (text.len() + 1);
                while !text.is_char_boundary(at) {
                    at -= 1;
                }
                lines = text[..at].lines().map(String::from).collect();
            }
            6 => {
                let s = SPLICE[arg as usize % SPLICE.len()];
                let mut at = (arg as usize / SPLICE.len()) % (lines[l].len() + 1);
                while !lines[l].is_char_boundary(at) {
                    at -= 1;
                }
                lines[l].insert_str(at, s);
            }
            7 => lines.swap(l, arg as usize % n),
            _ => {
                // Repeat a name: a header column (CSV) or a key (TOML).
                let first = lines[0].split(',').next().unwrap_or("").to_string();
                if lines[0].contains(',') {
                    let mut f: Vec<String> = lines[0].split(',').map(String::from).collect();
                    let k = arg as usize % f.len();
                    f[k] = first;
                    lines[0] = f.join(",");
                } else {
                    let copy = lines[l].clone();
                    lines.push(copy);
                }
            }
        }
    }
    lines.join("\n") + "\n"
}

/// Cases accepted and refused.
#[derive(Default)]
struct Tally {
    ok: std::sync::atomic::AtomicUsize,
    refused: std::sync::atomic::AtomicUsize,
}

/// Writes the case, parses it, checks the property: Ok with finite numbers, or an Err (whose
/// message is one line naming the file).
fn check(dir: &Path, p: &Parser, bytes: &[u8], tally: &Tally) -> Result<(), TestCaseError> {
    use std::sync::atomic::Ordering::Relaxed;
    let path: PathBuf = dir.join(p.target());
    std::fs::write(&path, bytes).unwrap();
    let start = std::time::Instant::now();
    let parsed = (p.parse)(&path);
    if std::env::var_os("PARTLIFE_PROPERTY_TRACE").is_some() && start.elapsed().as_secs_f64() > 0.5 {
        eprintln!("{}: {:.1} s for\n{}", p.name, start.elapsed().as_secs_f64(), String::from_utf8_lossy(bytes));
    }
    if parsed.is_ok() { tally.ok.fetch_add(1, Relaxed) } else { tally.refused.fetch_add(1, Relaxed) };
    match parsed {
        Ok(numbers) => {
            if let Some(v) = numbers.iter().find(|v| !v.is_finite()) {
                return Err(TestCaseError::fail(format!("{} accepted a non-finite number {v}:\n{}", p.name, String::from_utf8_lossy(bytes))));
            }
        }
        Err(e) => {
            // A study's message names the study or a file the study points at (one of the
            // scratch's studies and datasets).
            let msg = e.to_string();
            let names_a_file = msg.contains("case.") || (p.target().ends_with(".toml") && known_files(dir).iter().any(|f| msg.contains(f.as_str())));
            prop_assert!(names_a_file, "{}: the message does not name the file: {msg}", p.name);
            prop_assert!(!msg.trim().contains('\n'), "{}: the message is not one line: {msg}", p.name);
        }
    }
    Ok(())
}

fn runner(cases: u32, fixed_seed: bool) -> TestRunner {
    let config = Config { cases, failure_persistence: None, ..Config::default() };
    if fixed_seed { TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha)) } else { TestRunner::new(config) }
}

/// Runs both strategies on every parser with `cases` cases each.
fn all_parsers(cases: u32, fixed_seed: bool) {
    let dir = scratch();
    for p in CSV_PARSERS.iter().chain(&STUDY_PARSERS) {
        let path = common::root().join(p.base);
        let base = partlife::intake::text::decode(&path, &std::fs::read(&path).unwrap()).unwrap().text;
        // The valid file itself parses.
        check(dir.path(), p, base.as_bytes(), &Tally::default()).unwrap();
        (p.parse)(&dir.path().join(p.target())).unwrap_or_else(|e| panic!("{}: the shipped file fails: {e}", p.name));
        let header = base.lines().next().unwrap_or("").to_string();
        let bytes = (any::<bool>(), prop::collection::vec(any::<u8>(), 0..400)).prop_map(move |(with_header, b)| if with_header { [header.as_bytes(), b"\n", &b].concat() } else { b });
        let (raw, mutated) = (Tally::default(), Tally::default());
        runner(cases, fixed_seed).run(&bytes, |b| check(dir.path(), p, &b, &raw)).unwrap_or_else(|e| panic!("{} (arbitrary bytes): {e}", p.name));
        let text = base.clone();
        runner(cases, fixed_seed).run(&ops(), |o| check(dir.path(), p, mutate(&text, &o).as_bytes(), &mutated)).unwrap_or_else(|e| panic!("{} (mutations): {e}", p.name));
        let n = |t: &Tally| (t.ok.load(std::sync::atomic::Ordering::Relaxed), t.refused.load(std::sync::atomic::Ordering::Relaxed));
        eprintln!("{}: arbitrary bytes {:?}, mutations {:?} (accepted, refused)", p.name, n(&raw), n(&mutated));
        // Both branches of the property are exercised: mutations are near-valid, not all fatal.
        assert!(n(&mutated).0 > 0 && n(&mutated).1 > 0, "{}: mutations {:?} (accepted, refused)", p.name, n(&mutated));
    }
}

#[test]
fn parsers_never_panic_nor_accept_non_finite_numbers() {
    all_parsers(160, true);
}

#[test]
#[ignore = "slow: 20× the cases of the CI test, from a random seed"]
fn parsers_never_panic_nor_accept_non_finite_numbers_many_cases() {
    all_parsers(3200, false);
}

/// The CLI on mutated crush data: exit 0 with a complete report, or exit 2 with one message and
/// nothing written; never exit 1 or a panic.
#[test]
fn runs_on_mutated_data_finish_cleanly_or_write_nothing() {
    let crush = std::fs::read_to_string(common::root().join("datasets/crush_gen4.csv")).unwrap();
    runner(12, true)
        .run(&ops(), |o| {
            let s = common::Scratch::new();
            s.write("datasets/crush_gen4.csv", &mutate(&crush, &o));
            let out = s.run(&["run", "studies/lifetime.toml", "--quiet"]);
            prop_assert!(out.code == 0 || out.code == 2, "exit {}: {}", out.code, out.stderr);
            if out.code == 0 {
                prop_assert!(s.path("reports/lifetime/manifest.json").is_file(), "exit 0 without a manifest");
            } else {
                prop_assert!(!out.stderr.contains("panicked"), "{}", out.stderr);
                prop_assert_eq!(out.stderr.trim().lines().filter(|l| !l.starts_with("warning: ")).count(), 1, "{}", out.stderr);
                prop_assert!(s.report_files().is_empty(), "a failed run wrote {:?}", s.report_files());
            }
            Ok(())
        })
        .unwrap();
}

/// Reads `bytes` as the example workbook's sheet "Gen 4" with the example study's map and shape
/// join; Ok only with finite numbers.
fn workbook_case(dir: &Path, bytes: &[u8], name: &str) -> Result<(), TestCaseError> {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let mut src = partlife::intake::Source::file(&path);
    src.sheet = Some(partlife::intake::SheetRef::Name("Gen 4".into()));
    src.material = Some("Gen 4".into());
    src.columns = [("id", "Nr."), ("diameter", "Dp"), ("crush_force", "Last")].iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
    src.units = [("diameter", "mm"), ("crush_force", "kgf")].iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
    src.shape = Some(Box::new(partlife::intake::Source { sheet: Some(partlife::intake::SheetRef::Name("shape".into())), ..partlife::intake::Source::file(&path) }));
    match partlife::data::read_crush_source(&src, &Default::default()) {
        Ok(d) => {
            let bad = d.records.iter().flat_map(|r| [Some(r.diameter_m), Some(r.crush_force_n), r.roundness, r.sphericity, r.temperature_c].into_iter().flatten()).find(|v| !v.is_finite());
            prop_assert!(bad.is_none(), "accepted a non-finite number");
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.contains(name), "the message does not name the file: {msg}");
            prop_assert!(!msg.trim().contains('\n'), "the message is not one line: {msg}");
        }
    }
    Ok(())
}

/// A spreadsheet reader meets arbitrary bytes and damaged workbooks (bytes flipped, cut,
/// spliced): a clean error naming the file, or finite numbers; never a panic.
#[test]
fn workbooks_never_panic_on_any_bytes() {
    let dir = TempDir::new("properties-xlsx").unwrap();
    let book = std::fs::read(common::root().join("datasets/examples/crush_campaign.xlsx")).unwrap();
    workbook_case(dir.path(), &book, "case.xlsx").unwrap();
    let arbitrary = (any::<bool>(), prop::collection::vec(any::<u8>(), 0..600)).prop_map(|(zip, b)| if zip { [b"PK\x03\x04".as_slice(), &b].concat() } else { b });
    runner(200, true).run(&arbitrary, |b| workbook_case(dir.path(), &b, "case.xlsx")).unwrap();
    runner(60, true).run(&arbitrary, |b| workbook_case(dir.path(), &b, "case.ods")).unwrap();
    let damage = prop::collection::vec((any::<u32>(), any::<u8>(), 0u8..3), 1..6);
    runner(200, true)
        .run(&damage, |ops| {
            let mut b = book.clone();
            for &(at, v, kind) in &ops {
                let k = at as usize % b.len().max(1);
                match kind {
                    0 => b[k] = v,
                    1 => b.truncate(k.max(1)),
                    _ => b.insert(k, v),
                }
            }
            workbook_case(dir.path(), &b, "case.xlsx")
        })
        .unwrap();
}

/// The unit grammar and the exact conversion on arbitrary text: no panic; a conversion gives a
/// number or nothing, and the identity gives the text's own value.
#[test]
fn the_unit_grammar_never_panics() {
    let text = prop::collection::vec(prop::sample::select(vec!["D", "d", " ", "[", "]", "(", ")", "/", "_", "mm", "µ", "°C", "K", "kgf", "m", "s", "N", "1", "0", ".", ",", "e", "-", "+", "9", "ä", "\u{feff}"]), 0..12).prop_map(|v| v.concat());
    runner(2000, true)
        .run(&text, |t| {
            let h = partlife::intake::units::parse_header(&t);
            prop_assert!(t.trim().starts_with(h.name.trim()) || h.name.is_empty() || t.contains(&h.name), "{t:?} → {h:?}");
            for u in &partlife::intake::units::UNITS {
                let _ = u.conversion().apply(&t);
                let _ = u.conversion().from_si(&t, 17);
            }
            if let (Ok(v), Some(w)) = (t.trim().parse::<f64>(), partlife::intake::units::UNITS[0].conversion().apply(&t)) {
                prop_assert!(v == w || !v.is_finite(), "{t:?}: {v} vs {w}");
            }
            Ok(())
        })
        .unwrap();
}

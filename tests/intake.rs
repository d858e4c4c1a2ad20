//! The data intake as a new user meets it: lab exports and spreadsheets through the studies, the
//! example exports against the SI files they were made from, `datasets check`, and every bad
//! input of the issue with its message, exit code 2 and nothing written.

mod common;

use std::path::Path;

use common::{Scratch, edited, root};

/// A lifetime study of one material reading `data` (a TOML value) from `studies/lab.toml`.
/// A lifetime study of one lab file; `data` is the study's `data` as written (a path or a
/// table), which states the test temperature the lab files here do not: 20 °C.
fn lab_study(data: &str) -> String {
    let data = match data.strip_prefix('{') {
        Some(table) => format!("{{ temperature_c = 20,{table}"),
        None => format!("{{ file = {data}, temperature_c = 20 }}"),
    };
    format!(
        "# Purpose: a test.\n# Good result: it runs.\nkind = \"lifetime\"\nseed = 1\n\n[[material]]\nkey = \"lab\"\nlabel = \"Lab\"\ndata = {data}\nelastic = {{ youngs_modulus_pa = 112e9, poisson_ratio = 0.25 }}\ndensity_kg_m3 = 3600\n"
    )
}

/// Runs `studies/lab.toml` over `data_file` (written with `bytes`) and checks the bad-input
/// contract: exit 2, one line naming every `expect`, no panic, nothing under reports/.
fn refused(file: &str, bytes: &[u8], data: &str, expect: &[&str]) {
    let s = Scratch::new();
    std::fs::write(s.path(&format!("datasets/{file}")), bytes).unwrap();
    s.write("studies/lab.toml", &lab_study(data));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 2, "exit code; stdout {} stderr {}", out.stdout, out.stderr);
    assert!(!out.stderr.contains("panicked"), "{}", out.stderr);
    let errors: Vec<&str> = out.stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "one message: {}", out.stderr);
    for e in expect {
        assert!(errors[0].contains(e), "message lacks \"{e}\": {}", errors[0]);
    }
    assert!(s.report_files().is_empty(), "a failed run wrote {:?}", s.report_files());
}

/// The crush file of the issue: a lab export.
const LAB: &str = "Probe;D [mm];Fmax [N]\n1;0,91;131,2\n2;0,85;120,7\n3;0,95;140,1\n4;0,88;101,3\n5;0,79;150,2\n";

#[test]
fn mixed_delimiters_are_refused() {
    refused("lab.csv", b"id;D [mm],F [N]\n1;0,9,120\n2;0,8,110\n", "\"../datasets/lab.csv\"", &["lab.csv", "header", "mixed delimiters"]);
}

#[test]
fn a_unit_that_does_not_fit_its_quantity_is_refused() {
    refused("lab.csv", b"id;D [N];F [N]\n1;0,9;120\n", "\"../datasets/lab.csv\"", &["lab.csv", "header (line 1), column D [N]", "unit \"N\" is not a length"]);
}

#[test]
fn two_columns_for_the_diameter_are_refused() {
    refused("lab.csv", b"id,D [mm],diameter_m,F [N]\n1,0.9,0.0009,120\n", "\"../datasets/lab.csv\"", &["lab.csv", "two columns map to the diameter", "`D [mm]` (column 2) and `diameter_m` (column 3)"]);
}

#[test]
fn a_decimal_comma_in_a_comma_separated_file_is_refused() {
    refused("lab.csv", b"id,D [mm],F [N]\n1,0,91,131\n", "\"../datasets/lab.csv\"", &["lab.csv", "row 1 (line 2)", "decimal comma in a comma-separated file"]);
}

#[test]
fn a_sheet_that_does_not_exist_is_refused() {
    let book = std::fs::read(root().join("datasets/examples/crush_campaign.xlsx")).unwrap();
    refused("book.xlsx", &book, "{ file = \"../datasets/book.xlsx\", sheet = \"BL 16/30\" }", &["book.xlsx", "sheet \"BL 16/30\"", "no such sheet", "\"BL 16-30\", \"Gen 4\", \"shape\""]);
}

#[test]
fn a_join_with_duplicated_ids_is_refused() {
    let s = Scratch::new();
    s.write("datasets/crush.csv", "id;D [mm];F [N]\nA;0,9;120\nB;0,8;110\nC;0,85;115\n");
    s.write("datasets/shape.csv", "Particle;Roundness\nA;0,8\nB;0,7\nA;0,75\nC;0,9\n");
    s.write("studies/lab.toml", &lab_study("{ file = \"../datasets/crush.csv\", shape = { file = \"../datasets/shape.csv\" } }"));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("shape.csv: row 3 (line 4), column Particle: duplicate id \"A\" (also on row 1 (line 2))"), "{}", out.stderr);
    assert!(s.report_files().is_empty());
}

#[test]
fn a_join_names_the_ids_in_one_file_only_and_inner_keeps_the_common_ones() {
    let s = Scratch::new();
    s.write("datasets/crush.csv", "id;D [mm];F [N]\nA;0,9;120\nB;0,8;110\nC;0,85;115\nD;0,95;140\nE;0,9;100\nF;0,92;135\n");
    s.write("datasets/shape.csv", "Particle;Roundness\nA;0,8\nB;0,7\nC;0,9\nD;0,75\nE;0,81\nX;0,77\n");
    s.write("studies/lab.toml", &lab_study("{ file = \"../datasets/crush.csv\", shape = { file = \"../datasets/shape.csv\" } }"));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("1 ids of datasets/crush.csv are not in it: \"F\"") && out.stderr.contains("1 of its ids are not in datasets/crush.csv: \"X\"") && out.stderr.contains("join = \"inner\""), "{}", out.stderr);
    s.write("studies/lab.toml", &lab_study("{ file = \"../datasets/crush.csv\", shape = { file = \"../datasets/shape.csv\", join = \"inner\" } }"));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let manifest: serde_json::Value = serde_json::from_str(&s.read("reports/lab/manifest.json")).unwrap();
    let read = &manifest["inputs"][1]["read"];
    assert_eq!(read["dropped_ids"], serde_json::json!(["F", "X"]), "{manifest}");
    assert_eq!(read["joined"][0]["file"], "studies/../datasets/shape.csv".replace("studies/../", ""), "{manifest}");
    assert_eq!(manifest["inputs"][2]["path"], "datasets/shape.csv", "the joined file is hashed too: {manifest}");
    let particles = s.read("reports/lab/particles.csv");
    assert_eq!(particles.lines().count(), 1 + 5, "{particles}");
    assert!(particles.lines().nth(1).unwrap().contains(",A,0.0009,120.0,0.8,"), "{particles}");
}

#[test]
fn a_lab_export_runs_and_gives_the_si_files_tables() {
    // The file, and the same particles in partlife's SI schema.
    let s = Scratch::new();
    s.write("datasets/lab.csv", LAB);
    let si: String = std::iter::once("id,diameter_m,crush_force_n".to_string())
        .chain(LAB.lines().skip(1).map(|l| {
            let f: Vec<&str> = l.split(';').collect();
            let d = partlife::intake::decimal::Decimal::parse(&f[1].replace(',', ".")).unwrap().mul(&partlife::intake::decimal::Decimal::parse("1e-3").unwrap()).to_plain();
            format!("{},{d},{}", f[0], f[2].replace(',', "."))
        }))
        .collect::<Vec<_>>()
        .join("\n");
    s.write("datasets/si.csv", &si);
    s.write("studies/lab.toml", &lab_study("\"../datasets/lab.csv\""));
    s.write("studies/si.toml", &lab_study("\"../datasets/si.csv\""));
    for study in ["studies/lab.toml", "studies/si.toml"] {
        let out = s.run(&["run", study, "--quiet"]);
        assert_eq!(out.code, 0, "{study}: {}", out.stderr);
    }
    let tables = same_tables(&s.path("reports/si"), &s.path("reports/lab"), &[("datasets/si.csv", "datasets/lab.csv")]);
    assert!(tables >= 10, "{tables} tables compared");
    // The manifest records how the file was read.
    let manifest = s.read("reports/lab/manifest.json");
    for e in ["semicolon-separated, decimal comma, UTF-8", "\"source\": \"D [mm]\"", "\"field\": \"diameter_m\"", "\"conversion\": \"× 1e-3\"", "\"source\": \"Probe\""] {
        assert!(manifest.contains(e), "manifest lacks {e}: {manifest}");
    }
}

/// Compares every CSV table of two report directories byte for byte, after replacing in `b`
/// each data path by the one `a` names (the tables that name their data file); returns how
/// many were compared.
fn same_tables(a: &Path, b: &Path, paths: &[(&str, &str)]) -> usize {
    let mut n = 0;
    for e in std::fs::read_dir(a).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if !name.ends_with(".csv") {
            continue;
        }
        let want = std::fs::read_to_string(e.path()).unwrap();
        let mut got = std::fs::read_to_string(b.join(&name)).unwrap_or_else(|_| panic!("{} has no {name}", b.display()));
        for (si, lab) in paths {
            got = got.replace(lab, si);
        }
        assert!(want == got, "{name} differs between {} and {}", a.display(), b.display());
        n += 1;
    }
    n
}

/// A copy of the repository's examples into a scratch project (the studies find them at
/// ../datasets/examples/).
fn with_examples(s: &Scratch) {
    std::fs::create_dir_all(s.path("datasets/examples")).unwrap();
    for f in [partlife::lab::CSV_FILE, partlife::lab::XLSX_FILE, "exports.toml"] {
        std::fs::copy(root().join("datasets/examples").join(f), s.path("datasets/examples").join(f)).unwrap();
    }
    for f in ["lab_campaign_csv.toml", "lab_campaign_xlsx.toml", "gen4_vs_bl.toml"] {
        std::fs::copy(root().join("studies").join(f), s.path("studies").join(f)).unwrap();
    }
}

/// The `[[material]]` data of the SI studies, replaced by each example's (as the example studies
/// write them).
fn example_data(kind: &str) -> Vec<(&'static str, String)> {
    let xlsx = |sheet: &str, material: &str| {
        format!("data = {{ file = \"../datasets/examples/crush_campaign.xlsx\", sheet = \"{sheet}\", material = \"{material}\", columns = {{ id = \"Nr.\", diameter = \"Dp\", crush_force = \"Last\" }}, units = {{ diameter = \"mm\", crush_force = \"kgf\" }}, shape = {{ file = \"../datasets/examples/crush_campaign.xlsx\", sheet = \"shape\" }} }}")
    };
    let csv = |material: &str| format!("data = {{ file = \"../datasets/examples/crush_campaign_semicolon.csv\", material = \"{material}\" }}");
    match kind {
        "csv" => vec![("data = \"../datasets/crush_bl1630.csv\"", csv("BL 16/30")), ("data = \"../datasets/crush_gen4.csv\"", csv("Gen 4"))],
        _ => vec![("data = \"../datasets/crush_bl1630.csv\"", xlsx("BL 16-30", "BL 16/30")), ("data = \"../datasets/crush_gen4.csv\"", xlsx("Gen 4", "Gen 4"))],
    }
}

const EXAMPLE_PATHS: [(&str, &str); 4] = [
    ("datasets/crush_bl1630.csv", "datasets/examples/crush_campaign_semicolon.csv"),
    ("datasets/crush_gen4.csv", "datasets/examples/crush_campaign_semicolon.csv"),
    ("datasets/crush_bl1630.csv", "datasets/examples/crush_campaign.xlsx"),
    ("datasets/crush_gen4.csv", "datasets/examples/crush_campaign.xlsx"),
];

/// Replaces the example paths of the material rows of `got` by the SI files, row by row (both
/// examples hold both materials, so the material key decides).
fn si_paths(dir: &Path) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        if !e.file_name().to_string_lossy().ends_with(".csv") {
            continue;
        }
        let text = std::fs::read_to_string(e.path()).unwrap();
        let fixed: String = text
            .lines()
            .map(|l| {
                let mut l = l.to_string();
                for (si, ex) in EXAMPLE_PATHS {
                    let gen4 = si.contains("gen4");
                    if l.contains(ex) && (l.contains("gen4") || l.contains("Gen 4")) == gen4 {
                        l = l.replace(ex, si);
                    }
                }
                l + "\n"
            })
            .collect();
        std::fs::write(e.path(), fixed).unwrap();
    }
}

#[test]
fn the_examples_give_the_si_tables_through_the_lifetime_study() {
    let s = Scratch::new();
    with_examples(&s);
    let lifetime = s.read("studies/lifetime.toml");
    for kind in ["csv", "xlsx"] {
        let data = example_data(kind);
        let pairs: Vec<(&str, &str)> = data.iter().map(|(a, b)| (*a, b.as_str())).collect();
        s.write(&format!("studies/lifetime_{kind}.toml"), &edited(&lifetime, &pairs));
    }
    for study in ["lifetime", "lifetime_csv", "lifetime_xlsx", "lab_campaign_csv"] {
        let out = s.run(&["run", &format!("studies/{study}.toml"), "--quiet"]);
        assert_eq!(out.code, 0, "{study}: {}", out.stderr);
    }
    for other in ["lifetime_csv", "lifetime_xlsx", "lab_campaign_csv"] {
        si_paths(&s.path(&format!("reports/{other}")));
        let n = same_tables(&s.path("reports/lifetime"), &s.path(&format!("reports/{other}")), &[]);
        assert!(n >= 12, "{other}: {n} tables");
    }
}

#[test]
fn the_examples_give_the_si_tables_through_the_main_study() {
    // The main study with fewer samples (the tables' identity does not depend on their number).
    let s = Scratch::new();
    with_examples(&s);
    let fast = |text: &str| edited(text, &[("samples = 262144", "samples = 4096"), ("replicates = 8", "replicates = 2"), ("n = 8192", "n = 256"), ("bootstrap = 500", "bootstrap = 20"), ("draws = 4000", "draws = 400")]);
    let main = fast(&s.read("studies/gen4_vs_bl.toml"));
    s.write("studies/gen4_vs_bl.toml", &main);
    let data = example_data("csv");
    let pairs: Vec<(&str, &str)> = data.iter().map(|(a, b)| (*a, b.as_str())).collect();
    // main_csv does not state the deliverable's shape hypothesis: its summary must not test it.
    let mut pairs = pairs;
    pairs.push(("shape_hypothesis = true", ""));
    s.write("studies/main_csv.toml", &edited(&main, &pairs));
    s.write("studies/lab_campaign_xlsx.toml", &fast(&s.read("studies/lab_campaign_xlsx.toml")));
    for study in ["gen4_vs_bl", "main_csv", "lab_campaign_xlsx"] {
        let out = s.run(&["run", &format!("studies/{study}.toml"), "--quiet"]);
        assert_eq!(out.code, 0, "{study}: {}", out.stderr);
    }
    for other in ["main_csv", "lab_campaign_xlsx"] {
        si_paths(&s.path(&format!("reports/{other}")));
        let n = same_tables(&s.path("reports/gen4_vs_bl"), &s.path(&format!("reports/{other}")), &[]);
        assert!(n >= 10, "{other}: {n} tables");
    }
    // The shape hypothesis only where the study states it (before: in every main study).
    assert!(s.read("reports/gen4_vs_bl/summary.md").contains("The study tests the hypothesis that accounting for the particles' shape"));
    assert!(!s.read("reports/main_csv/summary.md").contains("The study tests the hypothesis"));
    // The synthetic label comes with the data (the generator's settings beside the SI files,
    // the export manifest beside the examples), not from the sentence: this scratch has no
    // generator settings, so nothing is labelled; with them, the SI files and the exports are.
    assert!(!s.read("reports/gen4_vs_bl/summary.md").contains("synthetic"), "labelled without a label");
    std::fs::copy(root().join("datasets/synth_crush.toml"), s.path("datasets/synth_crush.toml")).unwrap();
    for study in ["gen4_vs_bl", "lab_campaign_xlsx"] {
        let out = s.run(&["run", &format!("studies/{study}.toml"), "--quiet"]);
        assert_eq!(out.code, 0, "{study}: {}", out.stderr);
    }
    assert!(s.read("reports/gen4_vs_bl/summary.md").contains("**The crush data are synthetic stand-ins** (generated by partlife's generator from datasets/synth_crush.toml (seed 40); datasets/README.md)"), "{}", s.read("reports/gen4_vs_bl/summary.md"));
    assert!(s.read("reports/lab_campaign_xlsx/summary.md").contains("**The crush data are synthetic stand-ins** (exported from datasets/crush_bl1630.csv and datasets/crush_gen4.csv, themselves synthetic (datasets/examples/exports.toml); datasets/README.md)"), "{}", s.read("reports/lab_campaign_xlsx/summary.md"));
}

#[test]
fn the_examples_regenerate_byte_for_byte() {
    let dir = partlife::io::TempDir::new("lab").unwrap();
    let files = partlife::lab::write_examples(&root().join("datasets"), dir.path()).unwrap();
    assert_eq!(files.len(), 2);
    for f in files {
        let name = f.file_name().unwrap();
        assert!(std::fs::read(&f).unwrap() == std::fs::read(root().join("datasets/examples").join(name)).unwrap(), "{name:?} differs: regenerate with `partlife datasets lab-examples`");
    }
}

#[test]
fn datasets_check_explains_what_it_read() {
    let s = Scratch::new();
    with_examples(&s);
    let out = s.run(&["datasets", "check", "datasets/examples/crush_campaign_semicolon.csv"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    for e in [
        "crush_campaign_semicolon.csv [BL 16/30]: crush data, material \"BL 16/30\", 50 particles",
        "crush_campaign_semicolon.csv [Gen 4]: crush data, material \"Gen 4\", 45 particles",
        "semicolon-separated, decimal comma, Windows-1252; `Probe` → id; `Material` → material; `D [mm]` → diameter_m (mm × 1e-3); `Fmax [N]` → crush_force_n",
        "`T [°C]` → temperature_c; material = \"Gen 4\": 45 of 95 rows",
    ] {
        assert!(out.stdout.contains(e), "lacks {e}: {}", out.stdout);
    }
    let out = s.run(&["datasets", "check", "--study", "studies/lab_campaign_xlsx.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    for e in ["sheet \"Gen 4\": crush data, material \"Gen 4\", 45 particles", "`Last` → crush_force_n (kgf × 9.80665) [mapped by the study]", "joined by id: (xlsx sheet \"shape\" (3 of 3)", "material = \"BL 16/30\": 50 of 95 rows"] {
        assert!(out.stdout.contains(e), "lacks {e}: {}", out.stdout);
    }
    // Without the study, the workbook's unit-less headers are refused with what to declare.
    let out = s.run(&["datasets", "check", "datasets/examples/crush_campaign.xlsx"]);
    assert_eq!(out.code, 2, "{}", out.stdout);
    assert!(out.stderr.contains("sheet \"BL 16-30\"") && out.stderr.contains("missing column crush_force"), "{}", out.stderr);
    // A shape sheet on its own is recognised as such.
    let out = s.run(&["datasets", "check", "datasets/examples/crush_campaign.xlsx", "--sheet", "shape"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("shape data of 95 particles"), "{}", out.stdout);
}

#[test]
fn friction_of_the_old_reader_is_gone() {
    let s = Scratch::new();
    // Every missing required column in one message.
    s.write("datasets/lab.csv", "x,y\n1,2\n");
    s.write("studies/lab.toml", &lab_study("\"../datasets/lab.csv\""));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("missing columns id (") && out.stderr.contains("diameter (a length") && out.stderr.contains("crush_force (a force"), "{}", out.stderr);
    // Trailing blank lines are accepted; a misspelt optional column is named with the nearest
    // known name.
    s.write("datasets/lab.csv", "Probe;D [mm];Fmax [N];roundnes\n1;0,91;131,2;0,8\n2;0,85;120,7;0,8\n3;0,95;140,1;0,8\n4;0,88;101,3;0,8\n5;0,79;150,2;0,8\n\n\n");
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stderr.contains("warning: datasets/lab.csv: column `roundnes` is not used: did you mean `roundness`"), "{}", out.stderr);
    // Forces in kN in a newton column: refused on the derived strength, with the hint.
    let kn: String = LAB.lines().enumerate().map(|(i, l)| if i == 0 { l.to_string() } else { let f: Vec<&str> = l.split(';').collect(); format!("{};{};{}", f[0], f[1], (f[2].replace(',', ".").parse::<f64>().unwrap() / 1000.0).to_string().replace('.', ",")) }).collect::<Vec<_>>().join("\n");
    s.write("datasets/lab.csv", &kn);
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("row 1 (line 2), column Fmax [N]") && out.stderr.contains("nominal strength") && out.stderr.contains("check the force and diameter units"), "{}", out.stderr);
    // 900 in a millimetre column: refused in SI with the hint.
    s.write("datasets/lab.csv", &LAB.replace("0,91", "910"));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("got 0.91") && out.stderr.contains("read as 910 mm") && out.stderr.contains("did you mean µm?"), "{}", out.stderr);
}

#[test]
fn a_study_maps_columns_and_units_that_the_header_does_not_state() {
    let s = Scratch::new();
    s.write("datasets/lab.csv", "Nr;Dp;Last\n1;0,91;13,38\n2;0,85;12,3\n3;0,95;14,3\n4;0,88;10,3\n");
    s.write("studies/lab.toml", &lab_study("\"../datasets/lab.csv\""));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("missing column crush_force"), "{}", out.stderr);
    s.write("studies/lab.toml", &lab_study("{ file = \"../datasets/lab.csv\", columns = { crush_force = \"Last\" } }"));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("column Dp: states no unit for the diameter") && out.stderr.contains("units = { diameter = \"m\" }"), "{}", out.stderr);
    s.write("studies/lab.toml", &lab_study("{ file = \"../datasets/lab.csv\", columns = { crush_force = \"Last\" }, units = { diameter = \"mm\", crush_force = \"kgf\" } }"));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let particles = s.read("reports/lab/particles.csv");
    assert!(particles.lines().nth(1).unwrap().contains(",1,0.00091,131.212977,"), "{particles}");
    // A unit the grammar does not know, in the study.
    s.write("studies/lab.toml", &lab_study("{ file = \"../datasets/lab.csv\", columns = { crush_force = \"Last\" }, units = { diameter = \"inch\", crush_force = \"kgf\" } }"));
    let out = s.run(&["run", "studies/lab.toml", "--quiet"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("lab.toml: material[0].data.units.diameter: unknown unit \"inch\""), "{}", out.stderr);
}

/// A crush-curve file exported by lab software in German (`Probe;D [mm];Weg [µm];Kraft [N]`,
/// semicolons, decimal commas, CRLF) is read through the calibration's `[data] columns` map as
/// the SI file it was made from; without the map, or with a misspelled field, the study is
/// refused with exit 2, naming the file's columns or the study key.
#[test]
fn a_german_curve_export_is_read_through_the_calibrations_column_map() {
    let s = Scratch::new();
    let si = root().join("datasets/crush_curves_gen3_rt.csv");
    let text = std::fs::read_to_string(&si).unwrap();
    let mut export = String::from("Probe;D [mm];Weg [µm];Kraft [N]\r\n");
    for line in text.lines().skip(1) {
        let f: Vec<f64> = line.split(',').skip(1).map(|v| v.parse().unwrap()).collect();
        let id = line.split(',').next().unwrap();
        export.push_str(&format!("{id};{};{};{}\r\n", f[0] * 1e3, f[1] * 1e6, f[2]).replace('.', ","));
    }
    s.write("datasets/kurven.csv", &export);
    let want = partlife::calibrate::data::load_curves(&si, Some(20.0)).unwrap();
    let columns: std::collections::BTreeMap<String, String> = [("displacement", "Weg [µm]"), ("force", "Kraft [N]")].into_iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    let got = partlife::calibrate::data::load_curves_mapped(&s.path("datasets/kurven.csv"), &columns, &Default::default(), &Default::default(), Some(20.0)).unwrap();
    assert_eq!(got.len(), want.len());
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-9);
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g.particle, w.particle);
        assert!(close(g.diameter, w.diameter), "{} against {}", g.diameter, w.diameter);
        assert_eq!(g.displacement.len(), w.displacement.len());
        assert!(g.displacement.iter().zip(&w.displacement).all(|(a, b)| (a - b).abs() <= 1e-18 + 1e-12 * b.abs()), "particle {}", g.particle);
        assert!(g.force.iter().zip(&w.force).all(|(a, b)| close(*a, *b)), "particle {}", g.particle);
    }
    // Through a calibration study: unmapped, the file's columns are named; misspelled, the key.
    common::tiny_calibration(&s, "");
    let study = s.read("studies/cal.toml").replace("crush_curves_gen3_rt.csv\"", "kurven.csv\"");
    s.write("studies/cal.toml", &study);
    let out = s.run(&["run", "studies/cal.toml", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert_eq!(out.stderr.trim().lines().count(), 1, "one message: {}", out.stderr);
    for e in ["kurven.csv", "line 1", "Weg [µm]", "Kraft [N]", "columns"] {
        assert!(out.stderr.contains(e), "message lacks \"{e}\": {}", out.stderr);
    }
    assert!(s.report_files().is_empty(), "a refused run wrote {:?}", s.report_files());
    s.expect_bad_study("studies/cal.toml", "kurven.csv\"", "kurven.csv\"\ncolumns = { displacment = \"Weg [µm]\", force = \"Kraft [N]\" }", &["data.columns.displacment", "unknown field", "displacement"]);
    // The curve-level discrepancy study's [[data]] takes the same map: read (the run then stops
    // at its missing calibration report, with --no-deps), or refused naming data[0].
    let curves = std::fs::read_to_string(root().join("studies/discrepancy_curves.toml")).unwrap();
    let mapped = curves.replacen("file = \"../datasets/crush_curves_gen3_rt.csv\"", "file = \"../datasets/kurven.csv\"\ncolumns = { displacement = \"Weg [µm]\", force = \"Kraft [N]\" }", 1);
    assert_ne!(mapped, curves);
    std::fs::copy(root().join("datasets/crush_curves_gen3_800c.csv"), s.path("datasets/crush_curves_gen3_800c.csv")).unwrap();
    // Unmapped, the run stops at the file (it is read before the calibration report is looked
    // for); mapped, it gets past it.
    s.write("studies/curves.toml", &mapped.replacen("\ncolumns = { displacement = \"Weg [µm]\", force = \"Kraft [N]\" }", "", 1));
    let out = s.run(&["run", "studies/curves.toml", "--quiet", "--no-deps"]);
    assert!(out.code == 2 && out.stderr.contains("kurven.csv") && out.stderr.contains("Weg [µm]"), "{}", out.stderr);
    s.write("studies/curves.toml", &mapped);
    let out = s.run(&["run", "studies/curves.toml", "--quiet", "--no-deps"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(!out.stderr.contains("kurven.csv") && out.stderr.contains("calibration"), "the mapped file was read, the calibration is what is missing: {}", out.stderr);
    s.expect_bad_study("studies/curves.toml", "columns = { displacement", "columns = { displacment", &["data[0].columns.displacment", "unknown field"]);
    // `datasets check --study` reads a calibration's curve file and a curve study's files as
    // the study maps them (the German header alone says nothing of a displacement).
    s.write("studies/curves.toml", &mapped);
    s.write("studies/cal_mapped.toml", &study.replace("kurven.csv\"", "kurven.csv\"\ncolumns = { displacement = \"Weg [µm]\", force = \"Kraft [N]\" }"));
    for (file, count) in [("studies/cal_mapped.toml", 1), ("studies/curves.toml", 2)] {
        let out = s.run(&["datasets", "check", "--study", file]);
        assert_eq!(out.code, 0, "{file}: {}", out.stderr);
        assert_eq!(out.stdout.matches(": crush curves, ").count(), count, "{file}: {}", out.stdout);
        for e in [format!("kurven.csv: crush curves, {} particles", want.len()), "`Weg [µm]` → displacement_m (µm × 1e-6)".to_string(), "decimal comma".to_string()] {
            assert!(out.stdout.contains(&e), "{file}: lacks \"{e}\": {}", out.stdout);
        }
    }
    // A misspelled map key: `datasets check --study` names the study file and the key, as the
    // run does (it said "<study>: columns.displacment").
    for (file, key) in [("studies/cal_mapped.toml", "data.columns.displacment"), ("studies/curves.toml", "data[0].columns.displacment")] {
        s.write(file, &s.read(file).replacen("columns = { displacement", "columns = { displacment", 1));
        let out = s.run(&["datasets", "check", "--study", file]);
        assert_eq!(out.code, 2, "{file}: {}", out.stderr);
        assert!(out.stderr.contains(&format!("{file}: {key}: unknown field")), "{file}: {}", out.stderr);
    }
}

#[test]
fn several_sheets_of_a_workbook_are_one_table_with_the_sheet_name_as_a_column() {
    use partlife::intake::write::{Sheet, Value, xlsx};
    // A lab's bend-bar workbook: one sheet per test temperature, the hot sheet's columns in
    // another order, a notes sheet between them.
    let t = |s: &str| Value::Text(s.into());
    let n = Value::Number;
    let mut rt = vec![vec![t("Probe"), t("Festigkeit [MPa]"), t("T [°C]")]];
    let mut hot = vec![vec![t("T [°C]"), t("Probe"), t("Festigkeit [MPa]")]];
    for k in 0..20 {
        rt.push(vec![t(&format!("R{k}")), n(500.0 + 7.0 * ((k * 37 % 20) as f64)), n(20.0)]);
        hot.push(vec![n(800.0), t(&format!("H{k}")), n(420.0 + 6.0 * ((k * 53 % 20) as f64))]);
    }
    let sheet = |name: &str, rows: Vec<Vec<Value>>| Sheet { name: name.into(), rows, merged: vec![] };
    let book = xlsx(&[sheet("RT", rt), sheet("Notizen", vec![vec![t("Prüfer: Müller")]]), sheet("800 °C", hot.clone())]).unwrap();
    let s = Scratch::new();
    std::fs::write(s.path("datasets/biegung.xlsx"), &book).unwrap();
    s.write(
        "studies/sheets.toml",
        "kind = \"discrepancy\"\nseed = 3\n[discrepancy]\nbootstrap = 99\npermutations = 99\n[power]\nreplicates = 0\n[[strength]]\nkey = \"bars\"\nlabel = \"Bend bars, two sheets\"\ndata = { file = \"../datasets/biegung.xlsx\", sheet = [\"RT\", \"800 °C\"] }\nfactors = [\"sheet\"]\npopulations = []\n",
    );
    let out = s.run(&["datasets", "check", "--study", "studies/sheets.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("datasets/biegung.xlsx sheets \"RT\", \"800 °C\": strength data, 40 specimens") && out.stdout.contains("2 sheets as one table, their name in column `sheet`"), "{}", out.stdout);
    let out = s.run(&["run", "studies/sheets.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let summary = s.read("reports/sheets/summary.md");
    assert!(summary.contains("(40 specimens, `datasets/biegung.xlsx`)") && summary.contains("Tested at 20 °C (20) and 800 °C (20)."), "{summary}");
    // The hot sheet is 17 % weaker: the sheet's scale is named.
    assert!(summary.contains("**Effects named, in order: levels(sheet)"), "{summary}");
    // … and the sheet stands for the temperature: said.
    let manifest = s.read("reports/sheets/manifest.json");
    assert!(manifest.contains("`sheet` coincides with the test temperature (RT at 20 °C, 800 °C at 800 °C)"), "{manifest}");
    // A bad cell in the second sheet is named by its own sheet and sheet row.
    hot[5][2] = t("n.b.");
    let book = xlsx(&[sheet("RT", vec![vec![t("Probe"), t("Festigkeit [MPa]"), t("T [°C]")], vec![t("R0"), n(500.0), n(20.0)]]), sheet("800 °C", hot)]).unwrap();
    std::fs::write(s.path("datasets/biegung.xlsx"), &book).unwrap();
    let out = s.run(&["run", "studies/sheets.toml", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("sheet \"800 °C\", row 6 (sheet row 6), column \"Festigkeit [MPa]\""), "{}", out.stderr);
}

/// A curve workbook as a lab keeps it — a notes sheet first, the curves on a later sheet under
/// two lines of preamble — is read through `sheet` and `header_row` as the CSV it was made from,
/// by a calibration's `[data]` and a curve study's `[[data]]` alike; several sheets are refused.
#[test]
fn a_curve_workbook_is_read_from_its_sheet_and_header_row() {
    use partlife::intake::write::{Sheet, Value, xlsx};
    let s = Scratch::new();
    let si = root().join("datasets/crush_curves_gen3_rt.csv");
    let text = std::fs::read_to_string(&si).unwrap();
    let t = |v: &str| Value::Text(v.to_string());
    let mut rows = vec![vec![t("Prüfmaschine Z010, 0,5 mm/min")], vec![t("Charge G3-RT")], vec![t("Probe"), t("D [mm]"), t("Weg [µm]"), t("Kraft [N]")]];
    for line in text.lines().skip(1) {
        let f: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        rows.push(vec![Value::Number(f[0]), Value::Number(f[1] * 1e3), Value::Number(f[2] * 1e6), Value::Number(f[3])]);
    }
    let book = xlsx(&[Sheet { name: "Notizen".into(), rows: vec![vec![t("nichts")]], merged: vec![] }, Sheet { name: "Kurven".into(), rows, merged: vec![] }]).unwrap();
    std::fs::write(s.path("datasets/kurven.xlsx"), book).unwrap();
    let columns: std::collections::BTreeMap<String, String> = [("displacement", "Weg [µm]"), ("force", "Kraft [N]")].into_iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
    let src = partlife::intake::Source { sheet: Some(partlife::intake::SheetRef::Name("Kurven".into())), header_row: Some(3), columns, temperature_c: Some(20.0), ..partlife::intake::Source::file(s.path("datasets/kurven.xlsx")) };
    let (got, _) = partlife::calibrate::data::read_curves(&src, &Default::default()).unwrap();
    let want = partlife::calibrate::data::load_curves(&si, Some(20.0)).unwrap();
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g.particle, w.particle);
        assert!((g.diameter / w.diameter - 1.0).abs() < 1e-12 && g.force.iter().zip(&w.force).all(|(a, b)| (a - b).abs() <= 1e-12 * b.abs().max(1e-9)), "particle {}", g.particle);
        assert!(g.displacement.iter().zip(&w.displacement).all(|(a, b)| (a - b).abs() <= 1e-18 + 1e-12 * b.abs()), "particle {}", g.particle);
    }
    // Through the study keys: `datasets check --study` reads the file as the run does.
    common::tiny_calibration(&s, "");
    let keys = "kurven.xlsx\"\nsheet = \"Kurven\"\nheader_row = 3\ncolumns = { displacement = \"Weg [µm]\", force = \"Kraft [N]\" }";
    let study = s.read("studies/cal.toml").replace("crush_curves_gen3_rt.csv\"", keys);
    s.write("studies/cal.toml", &study);
    let out = s.run(&["datasets", "check", "--study", "studies/cal.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains(&format!("crush curves, {} particles", want.len())) && out.stdout.contains("Kurven"), "{}", out.stdout);
    let curves = std::fs::read_to_string(root().join("studies/discrepancy_curves.toml")).unwrap();
    s.write("studies/curves.toml", &curves.replacen("crush_curves_gen3_rt.csv\"", keys, 1));
    std::fs::copy(root().join("datasets/crush_curves_gen3_800c.csv"), s.path("datasets/crush_curves_gen3_800c.csv")).unwrap();
    let out = s.run(&["datasets", "check", "--study", "studies/curves.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains(&format!("crush curves, {} particles", want.len())), "{}", out.stdout);
    // Several sheets would merge curves whose particle numbers repeat: refused, naming the key.
    s.write("studies/cal.toml", &study.replace("sheet = \"Kurven\"", "sheet = [\"Notizen\", \"Kurven\"]"));
    let out = s.run(&["run", "studies/cal.toml", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("data.sheet") && out.stderr.contains("one sheet"), "{}", out.stderr);
}

/// Two materials tested at different temperatures: the warning heads the summary's answer on
/// the report's first page (it went to stderr and the Warnings page only), and is absent where
/// they agree. The first page opens with the answer in one sentence and shows the breakage
/// curves.
#[test]
fn materials_tested_at_different_temperatures_are_warned_of_in_the_summary_s_headline() {
    let s = Scratch::new();
    let out = s.run(&["run", "studies/lifetime.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(!s.read("reports/lifetime/summary.md").contains("**Warning**"));
    let (page, figures) = common::first_page(&s.path("reports/lifetime"));
    assert!(page.contains("Answer") && page.contains("On the estimates, BL 16/30 breaks less at 5 m/s: in the first year of operation (730 impacts per particle)"), "{page}");
    assert_eq!(figures, ["fig16_breakage"]);
    let gen4 = s.read("datasets/crush_gen4.csv");
    let hot: String = gen4.lines().map(|l| if l.ends_with(",20") { format!("{}800\n", &l[..l.len() - 2]) } else { format!("{l}\n") }).collect();
    assert_ne!(hot, gen4);
    s.write("datasets/crush_gen4.csv", &hot);
    let out = s.run(&["run", "studies/lifetime.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let summary = s.read("reports/lifetime/summary.md");
    let warning = "## Answer\n\n**Warning**: the two materials were tested at different temperatures (BL 16/30 at 20 °C, Gen 4 at 800 °C): the comparison sets a strength measured at one temperature against one measured at another.\n\nOn the estimates, BL 16/30 breaks less";
    assert!(summary.contains(warning), "{summary}");
    let (page, _) = common::first_page(&s.path("reports/lifetime"));
    assert!(page.contains("the two materials were tested at different temperatures (BL 16/30 at 20 °C, Gen 4 at 800 °C)"), "{page}");
}

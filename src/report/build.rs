//! The [`Document`] of a report directory, built from its files alone (no re-simulation), the
//! same way for every study kind:
//!
//! * **first page** — the question (the study file's opening comment; without one, the question
//!   its kind answers, said as such), the summary's lead paragraphs and its first `Answer`,
//!   `Headline` or `Verdict` section (the answer in one sentence generated from the numbers, for
//!   the main, lifetime, experiments, discrepancy, temperature and calibration kinds), then the
//!   summary sections its kind moves up and the one figure that shows the answer
//!   ([`super::captions::first_page`]: both particles' distributions for the main study, the
//!   attrition table and breakage curves for the lifetime study, today's state of knowledge and
//!   the candidates' metrics for the experiments, the evidence of every round for the
//!   discrepancy workflow, breakage against temperature, the calibration's fit, the crush
//!   curves, the impact spectra, the microstructures' comparison);
//! * the summary's other sections (`summary.md`, whose sentences the run generated from its
//!   numbers);
//! * **one section per figure** (every `*.svg` the manifest lists, in order) with a caption
//!   generated from the numbers it shows and, where the kind names one, the rows of its table
//!   that matter ([`super::captions`]);
//! * **inputs** — each file with its SHA-256, size, rows, columns, units and conversions — and
//!   the study file verbatim;
//! * **provenance** from `manifest.json` (version, git revision, seed, threads, wall time,
//!   evaluation counts);
//! * **warnings** — every failure and intake warning the run recorded, on a page of its own.
//!
//! A missing or unreadable `manifest.json`, `summary.md` or listed figure is an input error that
//! names the file.

use std::path::Path;

use serde_json::Value;

use super::document::{Block, Document, Section, Span, from_markdown, spans};
use crate::error::{Error, Result};

fn read(dir: &Path, name: &str) -> Result<String> {
    let p = dir.join(name);
    if !p.exists() {
        return Err(Error::data_file(&p, "file", format!("missing: the report directory {} has no {name} (run the study again)", dir.display())));
    }
    std::fs::read_to_string(&p).map_err(|e| Error::read(&p, e))
}

/// The study's question: its file's opening comment up to the first blank comment line or the
/// line that says what a good result looks like.
pub fn question(study_toml: &str) -> String {
    let mut out = Vec::new();
    for line in study_toml.lines() {
        let Some(c) = line.strip_prefix('#') else { break };
        let c = c.trim();
        if c.is_empty() || c.starts_with("Good result") || c.starts_with("Chain") {
            if out.is_empty() {
                continue;
            }
            break;
        }
        out.push(c.to_string());
    }
    let q = out.join(" ");
    // The line saying what a good result looks like may begin mid-line.
    let cut = ["A good result", "Good result", "a good result"].iter().filter_map(|k| q.find(k)).min();
    match cut {
        Some(k) => q[..k].trim_end().to_string(),
        None => q,
    }
}

/// The question a study of `kind` answers, for a study file without an opening comment.
fn kind_question(kind: &str) -> &'static str {
    match kind {
        "uq" => "How sure are we that the candidate particle breaks more than the reference, under which strength model, and what drives it?",
        "lifetime" => "What share of the particles breaks after a year and after ten years of impacts, and how sure are we?",
        "discrepancy" => "What do the data carry that the Weibull strength model misses, and does naming it change the lifetime?",
        "discrepancy_curves" => "What does the calibrated crush model miss in the measured force–displacement curves?",
        "experiments" => "Which experiment next, for the decision between the particles?",
        "calibrate" => "Which material constants reproduce the measured crush curves, and how well do the data fix them?",
        "crush" => "How does a single particle load and break between the platens?",
        "dem" => "How do the particles flow through the tube bank, and how hard do they hit the tubes?",
        "temperature" => "How do the phases, the strength and the lifetime change with temperature?",
        "microstructure" => "How do the microstructure's phases set the particle's stiffness and strength?",
        _ => "What does this study find?",
    }
}

fn s(v: &Value, key: &str) -> String {
    match v.get(key) {
        Some(Value::String(s)) => s.clone(),
        Some(Value::Null) | None => "—".into(),
        Some(x) => x.to_string(),
    }
}

/// Inputs and their provenance as key–value rows.
fn inputs(m: &Value) -> Vec<Block> {
    let mut blocks = Vec::new();
    let list = m.get("inputs").and_then(Value::as_array).cloned().unwrap_or_default();
    if list.is_empty() {
        blocks.push(Block::Paragraph(vec![Span::plain("The run read no input file besides the study file.")]));
    }
    for (k, f) in list.iter().enumerate() {
        let mut kv = vec![
            ("file".to_string(), s(f, "path")),
            ("SHA-256".to_string(), s(f, "sha256")),
            ("size".to_string(), format!("{} bytes", s(f, "bytes"))),
        ];
        if k == 0 {
            kv.push(("role".into(), "the study file (verbatim below)".into()));
        }
        if let Some(r) = f.get("read") {
            kv.push(("read as".into(), s(r, "format")));
            if let Some(sheet) = r.get("sheet").and_then(Value::as_str) {
                kv.push(("sheet".into(), sheet.into()));
            }
            kv.push(("rows used".into(), s(r, "rows")));
            if let Some(filter) = r.get("filter").and_then(Value::as_str) {
                kv.push(("filter".into(), filter.into()));
            }
            let cols: Vec<String> = r
                .get("columns")
                .and_then(Value::as_array)
                .map(|cs| {
                    cs.iter()
                        .map(|c| {
                            let (src, field, unit, conv) = (s(c, "source"), s(c, "field"), s(c, "unit"), s(c, "conversion"));
                            let mut t = if src == field { src } else { format!("{src} → {field}") };
                            if !unit.is_empty() {
                                t.push_str(&format!(" [{unit}]"));
                            }
                            if !conv.is_empty() {
                                t.push_str(&format!(" ({conv})"));
                            }
                            t
                        })
                        .collect()
                })
                .unwrap_or_default();
            if !cols.is_empty() {
                kv.push(("columns, units, conversions".into(), cols.join("; ")));
            }
            let unused: Vec<String> = r.get("unused").and_then(Value::as_array).map(|u| u.iter().filter_map(|x| x.as_str().map(String::from)).collect()).unwrap_or_default();
            if !unused.is_empty() {
                kv.push(("columns not used".into(), format!("{} (read by no field of the file's kind and no declaration of the study)", unused.join(", "))));
            }
            let list = |k: &str| -> Vec<String> { r.get(k).and_then(Value::as_array).map(|u| u.iter().filter_map(|x| x.as_str().map(String::from)).collect()).unwrap_or_default() };
            let ignored = list("ignored");
            if !ignored.is_empty() {
                kv.push(("columns ignored".into(), format!("{} (the study's `ignore`)", ignored.join(", "))));
            }
            let observed = list("observed");
            if !observed.is_empty() {
                kv.push(("what the rows say".into(), observed.join("; ")));
            }
        }
        blocks.push(Block::KeyValues(kv));
    }
    blocks
}

/// Every warning the run recorded: the study's warnings on its inputs (materials tested at
/// different temperatures), its failures and the intake's warnings on each file.
pub fn warnings(m: &Value) -> Vec<String> {
    let list = |k: &str| -> Vec<String> { m.get(k).and_then(Value::as_array).map(|f| f.iter().filter_map(|x| x.as_str().map(String::from)).collect()).unwrap_or_default() };
    let mut out = list("warnings");
    out.extend(list("failures"));
    fn intake(r: &Value, out: &mut Vec<String>) {
        let file = s(r, "file");
        for w in r.get("warnings").and_then(Value::as_array).into_iter().flatten() {
            if let Some(w) = w.as_str() {
                out.push(format!("{file}: {w}"));
            }
        }
        for j in r.get("joined").and_then(Value::as_array).into_iter().flatten() {
            intake(j, out);
        }
    }
    for f in m.get("inputs").and_then(Value::as_array).into_iter().flatten() {
        if let Some(r) = f.get("read") {
            intake(r, &mut out);
        }
    }
    out
}

/// A manifest's evaluation counter in words, where its key alone would not say what it counts.
fn evaluation_label(key: &str) -> String {
    match key {
        "naming_bootstrap_replicates" => "bootstrap replicates the naming loop drew (every round of every material; each table of models gives a round's)".into(),
        "power_datasets" => "synthetic datasets of the detection-power study".into(),
        other => other.replace('_', " "),
    }
}

fn provenance(m: &Value) -> Block {
    let git = match (m.get("git_revision").and_then(Value::as_str), m.get("git_dirty").and_then(Value::as_bool)) {
        (Some(r), Some(true)) => format!("{r} (with uncommitted changes)"),
        (Some(r), _) => r.to_string(),
        _ => "not in a git working tree".into(),
    };
    let evals: Vec<String> = m
        .get("evaluations")
        .and_then(Value::as_object)
        .map(|o| o.iter().map(|(k, v)| format!("{}: {v}", evaluation_label(k))).collect())
        .unwrap_or_default();
    let wall = m.get("wall_time_s").and_then(Value::as_f64).map_or("—".into(), |w| format!("{w:.2} s"));
    let failures = m.get("failures").and_then(Value::as_array).map_or(0, Vec::len);
    Block::KeyValues(vec![
        ("partlife version".into(), s(m, "partlife_version")),
        ("git revision".into(), git),
        ("study file".into(), s(m, "study_file")),
        ("study kind".into(), m.pointer("/study_resolved/kind").and_then(Value::as_str).unwrap_or("lifetime").to_string()),
        ("seed".into(), s(m, "seed")),
        ("worker threads".into(), s(m, "threads")),
        ("started (Unix time, s)".into(), s(m, "started_unix_s")),
        ("wall time".into(), wall),
        ("model evaluations".into(), if evals.is_empty() { "none recorded".into() } else { evals.join("; ") }),
        ("failures".into(), if failures == 0 { "none".into() } else { format!("{failures} (listed under Warnings)") }),
    ])
}

/// Turns a figure's file stem into a title when its kind gives none (`uq_sobol_convergence` →
/// "Sobol convergence").
fn title_of(stem: &str) -> String {
    let words: Vec<&str> = stem.split('_').collect();
    let skip = usize::from(words.len() > 1 && (words[0].starts_with("fig") || matches!(words[0], "uq" | "dem" | "crush" | "cal" | "exp" | "micro" | "temperature")));
    let t = words[skip..].join(" ");
    let mut c = t.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => stem.to_string(),
    }
}

/// The document of the report in `dir`.
pub fn document(dir: &Path) -> Result<Document> {
    let mtext = read(dir, "manifest.json")?;
    let m: Value = serde_json::from_str(&mtext).map_err(|e| Error::data_file(&dir.join("manifest.json"), "file", format!("not valid JSON: {e}")))?;
    let kind = m.pointer("/study_resolved/kind").and_then(Value::as_str).unwrap_or("lifetime").to_string();
    let study = s(&m, "study");
    let md = read(dir, "summary.md")?;
    let (title, lead, mut sections) = from_markdown(&md);
    let mut first: Vec<Block> = Vec::new();
    let q = question(m.get("study_toml").and_then(Value::as_str).unwrap_or(""));
    let mut t = vec![Span::bold("Question. ")];
    if q.is_empty() {
        t.push(Span::plain(format!("{} (the study file opens with no comment; this is the question every {kind} study answers.)", kind_question(&kind))));
    } else {
        t.extend(spans(&q));
    }
    first.push(Block::Paragraph(t));
    first.extend(lead);
    if let Some(k) = sections.iter().position(|s| s.heading == "Headline" || s.heading == "Verdict" || s.heading == "Answer") {
        let h = sections.remove(k);
        first.push(Block::Subheading("Answer".into()));
        first.extend(h.blocks);
    }
    let extra = super::captions::first_page(&kind, dir)?;
    first.extend(extra.blocks);
    for heading in &extra.move_up {
        if let Some(k) = sections.iter().position(|s| s.heading.starts_with(heading.as_str())) {
            let sct = sections.remove(k);
            first.push(Block::Subheading(sct.heading));
            first.extend(sct.blocks);
        }
    }
    // One section per figure.
    let outputs: Vec<String> = m.get("outputs").and_then(Value::as_array).map(|o| o.iter().filter_map(|x| x.as_str().map(String::from)).collect()).unwrap_or_default();
    let mut figure_sections = Vec::new();
    for f in outputs.iter().filter(|f| f.ends_with(".svg") && !f.contains('/')) {
        let stem = f.trim_end_matches(".svg").to_string();
        let svg = read(dir, f)?;
        let note = super::captions::figure(&kind, dir, &stem)?;
        let title = note.title.unwrap_or_else(|| title_of(&stem));
        let mut blocks = vec![Block::Figure { stem: stem.clone(), svg, caption: note.caption }];
        blocks.extend(note.blocks);
        if extra.figure.as_deref() == Some(stem.as_str()) {
            first.push(Block::Subheading(title));
            first.extend(blocks);
            continue;
        }
        let mut sct = Section::new(title, blocks);
        sct.anchor = stem;
        figure_sections.push(sct);
    }
    let summary_sections = std::mem::take(&mut sections);
    let mut doc_sections = summary_sections;
    doc_sections.extend(figure_sections);
    let mut inp = Section::new("Inputs", inputs(&m));
    inp.new_page = true;
    doc_sections.push(inp);
    doc_sections.push(Section::new("Study file", vec![Block::Verbatim(m.get("study_toml").and_then(Value::as_str).unwrap_or("").to_string())]));
    doc_sections.push(Section::new("Provenance", vec![provenance(&m)]));
    let w = warnings(&m);
    let mut warn = Section::new(
        format!("Warnings ({})", w.len()),
        if w.is_empty() {
            vec![Block::Paragraph(vec![Span::plain("The run recorded no warning: no failed evaluation, no figure whose legend hides data, no intake warning.")])]
        } else {
            w.iter().map(|x| Block::Warning(vec![Span::plain(x.clone())])).collect()
        },
    );
    warn.anchor = "warnings".into();
    warn.new_page = true;
    doc_sections.push(warn);
    let mut doc = Document {
        title: title.unwrap_or_else(|| study.clone()),
        running: format!("partlife · {study} ({kind} study) · report"),
        first,
        sections: doc_sections,
    };
    doc.unique_anchors();
    Ok(doc)
}

/// Writes `report.pdf` and `report.html` for the report in `dir`; returns their names.
pub fn write(dir: &Path) -> Result<Vec<String>> {
    let doc = document(dir)?;
    let pdf = super::pdf::render(&doc)?;
    let html = super::html::render(&doc)?;
    crate::io::write_atomic(&dir.join("report.pdf"), &pdf)?;
    crate::io::write_atomic(&dir.join("report.html"), html.as_bytes())?;
    Ok(vec!["report.pdf".into(), "report.html".into()])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn question_is_the_opening_comment() {
        let t = "# The main study: how sure are we\n# that Gen 4 breaks more?\n#\n# Chain: ...\nkind = \"uq\"\n";
        assert_eq!(question(t), "The main study: how sure are we that Gen 4 breaks more?");
        assert_eq!(question("# Purpose.\n# Good result: x\n"), "Purpose.");
        assert_eq!(question("kind = \"uq\""), "");
        assert_eq!(question("# Purpose: the loop on real data. A good result: nothing\n# named.\n"), "Purpose: the loop on real data.");
    }

    #[test]
    fn titles_from_stems() {
        assert_eq!(title_of("uq_sobol_convergence"), "Sobol convergence");
        assert_eq!(title_of("fig14_weibull_cdf"), "Weibull cdf");
        assert_eq!(title_of("evidence"), "Evidence");
    }
}

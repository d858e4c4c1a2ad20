//! report.pdf and report.html: every run writes both (and `partlife report` rewrites them from
//! the tables alone, byte for byte); the PDF read back by an independent reader (poppler's
//! pdfinfo, pdffonts, pdftotext: A4, page count, every font embedded and subset, the headline
//! numbers and every figure); the HTML opened in a real headless browser (Debian's chromium: no
//! console error, no network request, every figure drawn with a non-zero box, the headline
//! present, no horizontal overflow at a phone's 360 px); bad input to `report` exits 2 naming
//! what is missing. Where poppler or chromium is missing the test says SKIPPED with the reason
//! (`.ci/run` installs both and then sets PARTLIFE_EXPECT_POPPLER / PARTLIFE_EXPECT_BROWSER,
//! which turn a skip into a failure). The lifetime study (under a second) is the subject; the
//! main study's document is checked in `tests/studies.rs`.

mod common;
use common::{Scratch, one_space, pdf_text, program};

/// Runs the lifetime study; returns its stdout (the headline lines).
fn lifetime(s: &Scratch, extra: &[&str]) -> String {
    let mut args = vec!["run", "studies/lifetime.toml", "--quiet"];
    args.extend_from_slice(extra);
    let out = s.run(&args);
    assert_eq!(out.code, 0, "{}", out.stderr);
    out.stdout
}

fn manifest(s: &Scratch) -> serde_json::Value {
    serde_json::from_str(&s.read("reports/lifetime/manifest.json")).unwrap()
}

/// The figures the manifest lists (SVG stems, in order).
fn figures(s: &Scratch) -> Vec<String> {
    manifest(s)["outputs"].as_array().unwrap().iter().filter_map(|o| o.as_str()).filter(|o| o.ends_with(".svg")).map(|o| o.trim_end_matches(".svg").to_string()).collect()
}

/// The headline lines of a run's stdout (not the "wrote …" line).
fn headlines(stdout: &str) -> Vec<String> {
    stdout.lines().filter(|l| !l.starts_with("wrote ")).map(one_space).collect()
}

#[test]
fn every_run_writes_both_documents_and_report_rewrites_them_byte_identically() {
    let s = Scratch::new();
    lifetime(&s, &[]);
    let pdf = std::fs::read(s.path("reports/lifetime/report.pdf")).unwrap();
    let html = s.read("reports/lifetime/report.html");
    assert!(pdf.starts_with(b"%PDF-") && pdf.ends_with(b"%%EOF") || pdf.ends_with(b"%%EOF\n"), "report.pdf is not a whole PDF");
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    let outputs = manifest(&s)["outputs"].clone();
    for f in ["report.pdf", "report.html"] {
        assert!(outputs.as_array().unwrap().iter().any(|o| o == f), "manifest lists no {f}");
    }
    // One figure element per figure, each with its generated caption.
    let figs = figures(&s);
    assert_eq!(figs.len(), 6);
    assert_eq!(html.matches("<figure ").count(), figs.len());
    // The figure that shows the answer sits on the first page, under its own subheading; every
    // other figure has a section.
    let (_, on_first) = common::first_page(&s.path("reports/lifetime"));
    assert_eq!(on_first, ["fig16_breakage"]);
    for (k, f) in figs.iter().enumerate() {
        let headed = on_first.contains(f) || html.contains(&format!("<h2 id=\"{f}\">"));
        assert!(html.contains(&format!("<figure id=\"fig-{f}\">")) && headed && html.contains(&format!("<strong>Figure {}.</strong>", k + 1)), "{f}");
    }
    // The plant engineer's units on the first page, from this run's attrition table.
    let first = html.split("<nav id=\"contents\">").next().unwrap();
    assert!(first.contains("In a plant engineer") && first.contains("broken in year 1"), "first page lacks the attrition table");
    // Redrawn from the tables alone (the datasets gone): the same bytes.
    std::fs::remove_dir_all(s.path("datasets")).unwrap();
    let out = s.run(&["report", "lifetime"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("wrote report.pdf and report.html"), "{}", out.stdout);
    assert!(std::fs::read(s.path("reports/lifetime/report.pdf")).unwrap() == pdf, "report.pdf differs after partlife report");
    assert_eq!(s.read("reports/lifetime/report.html"), html, "report.html differs after partlife report");
    // --no-document: neither is written nor listed.
    let t = Scratch::new();
    lifetime(&t, &["--no-document"]);
    assert!(!t.path("reports/lifetime/report.pdf").exists() && !t.path("reports/lifetime/report.html").exists());
    assert!(!t.read("reports/lifetime/manifest.json").contains("report.pdf"));
}

#[test]
fn report_on_a_missing_or_incomplete_directory_is_bad_input() {
    let s = Scratch::new();
    let out = s.run(&["report", "nosuch"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("nosuch") && out.stderr.contains("no report named nosuch"), "{}", out.stderr);
    lifetime(&s, &[]);
    for (gone, named) in [("summary.md", "summary.md"), ("manifest.json", "manifest.json")] {
        let keep = s.read(&format!("reports/lifetime/{gone}"));
        std::fs::remove_file(s.path(&format!("reports/lifetime/{gone}"))).unwrap();
        let out = s.run(&["report", "lifetime"]);
        assert_eq!(out.code, 2, "without {gone}: {}", out.stderr);
        assert!(out.stderr.contains(named) && !out.stderr.contains("panicked"), "without {gone}: {}", out.stderr);
        assert_eq!(out.stderr.trim().lines().count(), 1, "one message: {}", out.stderr);
        s.write(&format!("reports/lifetime/{gone}"), &keep);
    }
    // A table a figure needs.
    std::fs::remove_file(s.path("reports/lifetime/lifetime_summary.csv")).unwrap();
    let out = s.run(&["report", "lifetime"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("lifetime_summary.csv"), "{}", out.stderr);
}

#[test]
fn pdf_reads_in_poppler() {
    const T: &str = "tests/documents.rs pdf_reads_in_poppler";
    let (Some(info), Some(fonts), Some(text)) = (
        program(T, "pdfinfo", "poppler-utils", "PARTLIFE_EXPECT_POPPLER"),
        program(T, "pdffonts", "poppler-utils", "PARTLIFE_EXPECT_POPPLER"),
        program(T, "pdftotext", "poppler-utils", "PARTLIFE_EXPECT_POPPLER"),
    ) else {
        return;
    };
    let s = Scratch::new();
    let stdout = lifetime(&s, &[]);
    let pdf = s.path("reports/lifetime/report.pdf");
    let o = std::process::Command::new(info).arg(&pdf).output().unwrap();
    assert!(o.status.success(), "pdfinfo: {}", String::from_utf8_lossy(&o.stderr));
    let info = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(info.contains("Page size:       595.28 x 841.89 pts (A4)"), "{info}");
    let pages: usize = info.lines().find_map(|l| l.strip_prefix("Pages:")).unwrap().trim().parse().unwrap();
    assert!((3..40).contains(&pages), "{pages} pages");
    // Every font embedded and subset (columns emb, sub: yes yes).
    let o = std::process::Command::new(fonts).arg(&pdf).output().unwrap();
    let list = String::from_utf8_lossy(&o.stdout).into_owned();
    let rows: Vec<&str> = list.lines().skip(2).collect();
    assert!(!rows.is_empty(), "no font: {list}");
    for r in &rows {
        assert!(r.contains("DejaVuSans") && r.contains(" yes yes yes "), "font not embedded and subset: {r}");
    }
    let all = pdf_text(&text, &pdf, None);
    // Running page numbers, the headline lines of the run, every figure with its caption.
    for k in 1..=pages {
        assert!(all.contains(&format!("page {k} of {pages}")), "page {k} of {pages}");
    }
    // σ is dropped from the extracted text on a page whose text also holds σ̄ (σ and a combining
    // macron): svg2pdf writes one ToUnicode string per glyph, and σ's glyph keeps the empty text
    // of its cluster in "σ̄". The glyphs drawn are right; the headlines' numbers are compared
    // with σ left out of both.
    let all_no_sigma = all.replace('σ', "");
    for h in headlines(&stdout) {
        assert!(all_no_sigma.contains(&h.replace('σ', "")), "the PDF lacks the headline \"{h}\"");
    }
    for k in 1..=figures(&s).len() {
        assert!(all.contains(&format!("Figure {k}.")), "Figure {k}");
    }
    assert!(all.contains("Warnings (0)") && all.contains("Provenance") && all.contains("SHA-256"), "inputs, provenance and warnings sections");
    let hash = partlife::io::sha256_hex(&std::fs::read(s.path("datasets/crush_gen4.csv")).unwrap());
    assert!(all.contains(&hash), "the input's SHA-256");
    // The answer in a plant engineer's units on page 1.
    let first = pdf_text(&text, &pdf, Some((1, 1)));
    assert!(first.contains("In a plant engineer's units") && first.contains("years to 10 %"), "{first}");
}

/// The report page inside a 360 px wide frame (a phone) with a probe script appended (the
/// document itself has none): it records errors, resource requests, the figures' boxes, the
/// page's overflow and its text into the parent page, which chromium's --dump-dom prints.
fn harness(html: &str) -> String {
    let probe = r#"<script>
(function(){var errors=[];window.addEventListener('error',function(e){errors.push(String(e.message))});
var ce=console.error;console.error=function(){errors.push(Array.prototype.join.call(arguments,' '));ce.apply(console,arguments)};
window.__probeErrors=errors;})();
</script>"#;
    let tail = r#"<script>
(function(){var figs=Array.prototype.map.call(document.querySelectorAll('figure svg'),function(s){var r=s.getBoundingClientRect();return [r.width,r.height]});
var res=performance.getEntriesByType('resource').map(function(e){return e.name});
var out={errors:window.__probeErrors,resources:res,figures:figs,scrollWidth:document.documentElement.scrollWidth,innerWidth:window.innerWidth,text:document.body.innerText};
var pre=parent.document.createElement('pre');pre.id='partlife-probe';pre.textContent=JSON.stringify(out);parent.document.body.appendChild(pre);})();
</script>"#;
    let page = html.replacen("<head>", &format!("<head>{probe}"), 1).replacen("</body>", &format!("{tail}</body>"), 1);
    let escaped = page.replace('&', "&amp;").replace('"', "&quot;");
    format!("<!DOCTYPE html><html><body style=\"margin:0\"><iframe style=\"width:360px;height:740px;border:0\" srcdoc=\"{escaped}\"></iframe></body></html>")
}

#[test]
fn html_renders_in_a_headless_browser() {
    const T: &str = "tests/documents.rs html_renders_in_a_headless_browser";
    let Some(chromium) = program(T, "chromium", "chromium", "PARTLIFE_EXPECT_BROWSER") else { return };
    let s = Scratch::new();
    let stdout = lifetime(&s, &[]);
    let html = s.read("reports/lifetime/report.html");
    // Self-contained: no script, no external reference.
    assert!(!html.contains("<script") && !html.contains(" src=") && !html.contains("href=\"http") && !html.contains("url(") && !html.contains("@import"), "report.html reaches outside itself");
    let page = s.path("probe.html");
    std::fs::write(&page, harness(&html)).unwrap();
    let profile = s.path("chromium-profile");
    let o = std::process::Command::new(chromium)
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--window-size=800,900", "--virtual-time-budget=3000", "--dump-dom"])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("file://{}", page.display()))
        .output()
        .unwrap();
    let dom = String::from_utf8_lossy(&o.stdout).into_owned();
    let start = dom.find("<pre id=\"partlife-probe\">").unwrap_or_else(|| panic!("the probe did not run: {}", String::from_utf8_lossy(&o.stderr))) + "<pre id=\"partlife-probe\">".len();
    let end = start + dom[start..].find("</pre>").unwrap();
    let json = dom[start..end].replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", "\"").replace("&amp;", "&");
    let probe: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(probe["errors"].as_array().unwrap().len(), 0, "console errors: {}", probe["errors"]);
    assert_eq!(probe["resources"].as_array().unwrap().len(), 0, "network requests: {}", probe["resources"]);
    let boxes = probe["figures"].as_array().unwrap();
    assert_eq!(boxes.len(), figures(&s).len(), "figures drawn");
    for b in boxes {
        assert!(b[0].as_f64().unwrap() > 100.0 && b[1].as_f64().unwrap() > 50.0, "a figure's box: {b}");
    }
    let (sw, iw) = (probe["scrollWidth"].as_f64().unwrap(), probe["innerWidth"].as_f64().unwrap());
    assert_eq!(iw, 360.0, "the frame is a phone's width");
    assert!(sw <= iw, "the page overflows a phone's width: {sw} > {iw}");
    let text = one_space(probe["text"].as_str().unwrap());
    for h in headlines(&stdout) {
        assert!(text.contains(&h), "the page lacks the headline \"{h}\"");
    }
}

/// Other kinds through the same model: the crush FE (its summary from its headline lines) and a
/// strength-data study on real published data; each writes both documents with one figure
/// element per figure it drew.
#[test]
fn other_study_kinds_write_both_documents() {
    let s = Scratch::new();
    std::fs::create_dir_all(s.path("datasets/real")).unwrap();
    std::fs::copy(common::root().join("studies/strength_glass_fibres.toml"), s.path("studies/strength_glass_fibres.toml")).unwrap();
    std::fs::copy(common::root().join("datasets/real/smith_naylor_glass_fibres.csv"), s.path("datasets/real/smith_naylor_glass_fibres.csv")).unwrap();
    for study in ["crush_gen3_rt", "strength_glass_fibres"] {
        let out = s.run(&["run", &format!("studies/{study}.toml"), "--quiet"]);
        assert_eq!(out.code, 0, "{study}: {}", out.stderr);
        let dir = format!("reports/{study}");
        let pdf = std::fs::read(s.path(&format!("{dir}/report.pdf"))).unwrap();
        assert!(pdf.starts_with(b"%PDF-"), "{study}");
        let html = s.read(&format!("{dir}/report.html"));
        let m: serde_json::Value = serde_json::from_str(&s.read(&format!("{dir}/manifest.json"))).unwrap();
        let svgs = m["outputs"].as_array().unwrap().iter().filter(|o| o.as_str().is_some_and(|o| o.ends_with(".svg") && !o.contains('/'))).count();
        assert!(svgs > 0 && html.matches("<figure ").count() == svgs, "{study}: {svgs} figures, {} in the page", html.matches("<figure ").count());
        // Every figure's caption is read from its numbers (none is the generic one).
        assert_eq!(common::figure_captions(&s.path(&dir)).len(), svgs, "{study}");
        // The question is the study file's opening comment.
        let question = partlife::report::build::question(&s.read(&format!("studies/{study}.toml")));
        assert!(!question.is_empty() && html.contains(&format!("<strong>Question. </strong>")), "{study}");
    }
}

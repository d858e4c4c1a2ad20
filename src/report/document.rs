//! The document model of a study's report: what `report.pdf` ([`super::pdf`]) and
//! `report.html` ([`super::html`]) render, built from the report's files by
//! [`super::build`]. One model, two renderers: no study kind writes PDF or HTML itself.
//!
//! A [`Document`] is a title, a first page and sections; a [`Section`] holds [`Block`]s —
//! paragraph, bullet list, figure (its SVG and a caption), table, key–value list, verbatim
//! text and warning. Text is a list of [`Span`]s (plain, bold or code), so the renderers never
//! parse markup. [`from_markdown`] reads the subset of Markdown the runs write in `summary.md`
//! (headings, paragraphs, `*`/`-` bullets, pipe tables, fenced code, `**bold**` and
//! `` `code` ``). Verified by this file's unit tests and by `tests/documents.rs`.

/// A run of text with one style.
#[derive(Debug, Clone, PartialEq)]
pub struct Span {
    /// The text (no markup).
    pub text: String,
    /// Bold.
    pub bold: bool,
    /// Code (a name from the study file or a table).
    pub code: bool,
}

impl Span {
    /// Plain text.
    pub fn plain(text: impl Into<String>) -> Span {
        Span { text: text.into(), bold: false, code: false }
    }
    /// Bold text.
    pub fn bold(text: impl Into<String>) -> Span {
        Span { text: text.into(), bold: true, code: false }
    }
}

/// Text: a sequence of spans.
pub type Text = Vec<Span>;

/// The plain text of spans.
pub fn plain_text(t: &[Span]) -> String {
    t.iter().map(|s| s.text.as_str()).collect()
}

/// One block of a section.
#[derive(Debug, Clone, PartialEq)]
pub enum Block {
    /// A sub-heading inside a section.
    Subheading(String),
    /// A paragraph.
    Paragraph(Text),
    /// A bullet list.
    Bullets(Vec<Text>),
    /// A figure: its file stem, its SVG (as the run wrote it) and a caption.
    Figure {
        /// File stem (`uq_sobol`), also the HTML anchor.
        stem: String,
        /// The SVG as the run wrote it.
        svg: String,
        /// Caption generated from the numbers the figure shows.
        caption: Text,
    },
    /// A table: header and rows of cell text.
    Table {
        /// Column headings.
        header: Vec<String>,
        /// Rows of cells.
        rows: Vec<Vec<String>>,
    },
    /// Key–value pairs (provenance, inputs).
    KeyValues(Vec<(String, String)>),
    /// Preformatted text (the study file), shown verbatim.
    Verbatim(String),
    /// A warning of the run.
    Warning(Text),
}

/// A section: a heading, an anchor and blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// Heading.
    pub heading: String,
    /// Anchor (HTML id), unique within the document.
    pub anchor: String,
    /// Start on a new page in the PDF.
    pub new_page: bool,
    /// Content.
    pub blocks: Vec<Block>,
}

impl Section {
    /// A section with an anchor derived from the heading.
    pub fn new(heading: impl Into<String>, blocks: Vec<Block>) -> Section {
        let heading = heading.into();
        Section { anchor: anchor(&heading), heading, new_page: false, blocks }
    }
}

/// A report document.
#[derive(Debug, Clone, PartialEq)]
pub struct Document {
    /// Title (the summary's first heading).
    pub title: String,
    /// Running title of the PDF pages (study name).
    pub running: String,
    /// The first page: question, headline, answer per model, what drives it.
    pub first: Vec<Block>,
    /// Sections after the first page.
    pub sections: Vec<Section>,
}

impl Document {
    /// Makes section anchors unique (a repeated heading gets `-2`, `-3`, …).
    pub fn unique_anchors(&mut self) {
        let mut seen: Vec<String> = vec!["answer".into(), "contents".into()];
        for s in &mut self.sections {
            let base = s.anchor.clone();
            let mut k = 2;
            while seen.contains(&s.anchor) {
                s.anchor = format!("{base}-{k}");
                k += 1;
            }
            seen.push(s.anchor.clone());
        }
    }
}

/// An HTML id from a heading: lower-case ASCII letters and digits joined by `-`.
pub fn anchor(heading: &str) -> String {
    let mut out = String::new();
    for c in heading.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') && !out.is_empty() {
            out.push('-');
        }
    }
    let out = out.trim_end_matches('-').to_string();
    if out.is_empty() { "section".into() } else { out }
}

/// Spans of one line of Markdown text: `**bold**` and `` `code` ``; anything else is plain.
pub fn spans(line: &str) -> Text {
    let mut out: Text = Vec::new();
    let mut rest = line;
    let push = |out: &mut Text, s: Span| {
        if s.text.is_empty() {
            return;
        }
        match out.last_mut() {
            Some(last) if last.bold == s.bold && last.code == s.code => last.text.push_str(&s.text),
            _ => out.push(s),
        }
    };
    while !rest.is_empty() {
        let b = rest.find("**");
        let c = rest.find('`');
        match (b, c) {
            (Some(i), cc) if cc.is_none_or(|j| i < j) => match rest[i + 2..].find("**") {
                Some(k) => {
                    push(&mut out, Span::plain(&rest[..i]));
                    for mut s in spans(&rest[i + 2..i + 2 + k]) {
                        s.bold = true;
                        push(&mut out, s);
                    }
                    rest = &rest[i + 2 + k + 2..];
                }
                None => {
                    push(&mut out, Span::plain(rest));
                    rest = "";
                }
            },
            (_, Some(j)) => match rest[j + 1..].find('`') {
                Some(k) => {
                    push(&mut out, Span::plain(&rest[..j]));
                    push(&mut out, Span { text: rest[j + 1..j + 1 + k].to_string(), bold: false, code: true });
                    rest = &rest[j + 1 + k + 1..];
                }
                None => {
                    push(&mut out, Span::plain(rest));
                    rest = "";
                }
            },
            _ => {
                push(&mut out, Span::plain(rest));
                rest = "";
            }
        }
    }
    out
}

/// Cells of a pipe-table row (`| a | b |`).
fn cells(line: &str) -> Vec<String> {
    let t = line.trim();
    let t = t.strip_prefix('|').unwrap_or(t);
    let t = t.strip_suffix('|').unwrap_or(t);
    t.split('|').map(|c| c.trim().replace('`', "").replace("**", "")).collect()
}

fn is_rule(line: &str) -> bool {
    let t = line.trim();
    t.starts_with('|') && t.chars().all(|c| matches!(c, '|' | '-' | ':' | ' '))
}

/// Reads the Markdown the runs write: the title (first `#` heading), the blocks before the
/// first `##` heading, and one section per `##` heading (`###` becomes a sub-heading).
pub fn from_markdown(md: &str) -> (Option<String>, Vec<Block>, Vec<Section>) {
    let mut title = None;
    let mut lead: Vec<Block> = Vec::new();
    let mut sections: Vec<Section> = Vec::new();
    let mut para: Vec<String> = Vec::new();
    let mut bullets: Vec<Text> = Vec::new();
    let mut table: Vec<Vec<String>> = Vec::new();
    let mut code: Option<String> = None;
    fn target<'a>(lead: &'a mut Vec<Block>, sections: &'a mut [Section]) -> &'a mut Vec<Block> {
        match sections.last_mut() {
            Some(s) => &mut s.blocks,
            None => lead,
        }
    }
    fn flush(lead: &mut Vec<Block>, sections: &mut [Section], para: &mut Vec<String>, bullets: &mut Vec<Text>, table: &mut Vec<Vec<String>>) {
        let t = target(lead, sections);
        if !para.is_empty() {
            t.push(Block::Paragraph(spans(&para.join(" "))));
            para.clear();
        }
        if !bullets.is_empty() {
            t.push(Block::Bullets(std::mem::take(bullets)));
        }
        if !table.is_empty() {
            let mut rows = std::mem::take(table);
            let header = rows.remove(0);
            t.push(Block::Table { header, rows });
        }
    }
    for line in md.lines() {
        if let Some(buf) = code.as_mut() {
            if line.trim_start().starts_with("```") {
                let text = std::mem::take(buf);
                target(&mut lead, &mut sections).push(Block::Verbatim(text));
                code = None;
            } else {
                buf.push_str(line);
                buf.push('\n');
            }
            continue;
        }
        let t = line.trim_end();
        if t.trim_start().starts_with("```") {
            flush(&mut lead, &mut sections, &mut para, &mut bullets, &mut table);
            code = Some(String::new());
        } else if let Some(h) = t.strip_prefix("# ") {
            flush(&mut lead, &mut sections, &mut para, &mut bullets, &mut table);
            if title.is_none() {
                title = Some(h.trim().to_string());
            } else {
                sections.push(Section::new(h.trim(), vec![]));
            }
        } else if let Some(h) = t.strip_prefix("## ") {
            flush(&mut lead, &mut sections, &mut para, &mut bullets, &mut table);
            sections.push(Section::new(h.trim().replace('`', ""), vec![]));
        } else if let Some(h) = t.strip_prefix("### ").or_else(|| t.strip_prefix("#### ")) {
            flush(&mut lead, &mut sections, &mut para, &mut bullets, &mut table);
            target(&mut lead, &mut sections).push(Block::Subheading(h.trim().replace('`', "")));
        } else if t.trim_start().starts_with('|') {
            if !para.is_empty() || !bullets.is_empty() {
                flush(&mut lead, &mut sections, &mut para, &mut bullets, &mut table);
            }
            if !is_rule(t) {
                table.push(cells(t));
            }
        } else if let Some(b) = t.strip_prefix("* ").or_else(|| t.strip_prefix("- ")) {
            if !para.is_empty() || !table.is_empty() {
                flush(&mut lead, &mut sections, &mut para, &mut bullets, &mut table);
            }
            bullets.push(spans(b.trim()));
        } else if t.trim().is_empty() {
            flush(&mut lead, &mut sections, &mut para, &mut bullets, &mut table);
        } else if !bullets.is_empty() && (t.starts_with("  ") || para.is_empty() && table.is_empty()) && t.starts_with(' ') {
            // Continuation of a bullet.
            if let Some(last) = bullets.last_mut() {
                last.push(Span::plain(" "));
                last.extend(spans(t.trim()));
            }
        } else {
            if !bullets.is_empty() || !table.is_empty() {
                flush(&mut lead, &mut sections, &mut para, &mut bullets, &mut table);
            }
            para.push(t.trim().to_string());
        }
    }
    if let Some(buf) = code {
        target(&mut lead, &mut sections).push(Block::Verbatim(buf));
    }
    flush(&mut lead, &mut sections, &mut para, &mut bullets, &mut table);
    (title, lead, sections)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_split_bold_and_code() {
        let s = spans("a **b `c`** and `d` **e");
        assert_eq!(plain_text(&s), "a b c and d **e");
        assert!(s.iter().any(|x| x.bold && x.text == "b "));
        assert!(s.iter().any(|x| x.bold && x.code && x.text == "c"));
        assert!(s.iter().any(|x| !x.bold && x.code && x.text == "d"));
    }

    #[test]
    fn markdown_blocks() {
        let md = "# Title\n\nLead **one**\nline two.\n\n## Headline\n\n* first\n* second `x`\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n### Sub\n\nText.\n\n```\ncode\n```\n";
        let (title, lead, sections) = from_markdown(md);
        assert_eq!(title.as_deref(), Some("Title"));
        assert_eq!(lead.len(), 1);
        assert_eq!(plain_text(match &lead[0] { Block::Paragraph(t) => t, _ => panic!() }), "Lead one line two.");
        assert_eq!(sections.len(), 1);
        assert_eq!(sections[0].anchor, "headline");
        let b = &sections[0].blocks;
        assert!(matches!(&b[0], Block::Bullets(v) if v.len() == 2));
        assert!(matches!(&b[1], Block::Table { header, rows } if header == &["a", "b"] && rows == &[vec!["1".to_string(), "2".to_string()]]));
        assert!(matches!(&b[2], Block::Subheading(s) if s == "Sub"));
        assert!(matches!(&b[4], Block::Verbatim(s) if s == "code\n"));
    }

    #[test]
    fn anchors_are_unique() {
        let mut d = Document { title: "t".into(), running: "r".into(), first: vec![], sections: vec![Section::new("A b", vec![]), Section::new("A  b!", vec![]), Section::new("Answer", vec![])] };
        d.unique_anchors();
        let a: Vec<_> = d.sections.iter().map(|s| s.anchor.as_str()).collect();
        assert_eq!(a, ["a-b", "a-b-2", "answer-2"]);
    }
}

//! Page layout of a [`Document`] for `report.pdf` ([`super::pdf`]), in points (1/72 in), with
//! the glyph advances of the fonts that will be embedded (DejaVu Sans regular and bold, DejaVu
//! Sans Mono for code; the `dejavu` crate, no font read from the machine): greedy line breaking
//! (a word longer than the line is cut by characters), tables with columns sized to their content
//! and wrapped to the text width (narrow columns keep their width, the others share the rest,
//! never below their longest word; the header repeats on a new page), figures at their physical
//! width (narrowed to the text width, a heading kept with its figure) on A4. Also the SVG and XML
//! helpers the HTML renderer shares. Verified by this file's tests and `tests/documents.rs`.

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef};

use super::document::{Block, Document, Span, Text};
#[cfg(test)]
use super::document::plain_text;
use crate::error::{Error, Result};

/// A4 in points.
pub const PAGE: (f64, f64) = (595.28, 841.89);
pub(super) const LEFT: f64 = 56.7;
const TOP: f64 = 62.0;
const BOTTOM: f64 = 60.0;
const WIDTH: f64 = PAGE.0 - 2.0 * LEFT;
const BODY: f64 = 9.5;
const SMALL: f64 = 7.5;
const LEAD: f64 = 1.38;

#[derive(Clone, Copy, PartialEq)]
pub(super) enum Face {
    Regular,
    Bold,
    Mono,
}

struct Fonts {
    regular: FontRef<'static>,
    bold: FontRef<'static>,
    mono: FontRef<'static>,
}

fn fonts() -> &'static Fonts {
    static F: OnceLock<Fonts> = OnceLock::new();
    F.get_or_init(|| Fonts {
        // The dejavu crate's fonts are valid TrueType: parsing cannot fail.
        regular: FontRef::try_from_slice(dejavu::sans::regular()).expect("DejaVu Sans"),
        bold: FontRef::try_from_slice(dejavu::sans::bold()).expect("DejaVu Sans Bold"),
        mono: FontRef::try_from_slice(dejavu::sans_mono::regular()).expect("DejaVu Sans Mono"),
    })
}

/// Width in points of `text` set in `face` at `size` points.
pub(super) fn width(text: &str, face: Face, size: f64) -> f64 {
    let f = fonts();
    let font = match face {
        Face::Regular => &f.regular,
        Face::Bold => &f.bold,
        Face::Mono => &f.mono,
    };
    let em = font.units_per_em().unwrap_or(2048.0) as f64;
    text.chars().map(|c| font.h_advance_unscaled(font.glyph_id(c)) as f64).sum::<f64>() / em * size
}

fn face(s: &Span) -> Face {
    if s.code {
        Face::Mono
    } else if s.bold {
        Face::Bold
    } else {
        Face::Regular
    }
}

/// One thing drawn on a page (coordinates in points from the top-left corner).
#[derive(Clone)]
pub(super) enum El {
    /// Text on a baseline at (x, y).
    Text { x: f64, y: f64, size: f64, runs: Vec<(Face, String)>, grey: bool, middle: bool },
    /// A horizontal rule.
    Rule { x0: f64, x1: f64, y: f64, w: f64 },
    /// A filled rectangle (warning background, table stripe).
    Fill { x: f64, y: f64, w: f64, h: f64, rgb: (u8, u8, u8) },
    /// A figure's SVG placed at (x, y) with width w and height h.
    Figure { x: f64, y: f64, w: f64, h: f64, index: usize },
}

/// A wrapped line: its runs and width.
type Line = (Vec<(Face, String)>, f64);

/// Greedy line breaking of spans into lines of at most `max` points.
fn wrap(text: &[Span], size: f64, max: f64) -> Vec<Line> {
    let mut lines: Vec<Line> = Vec::new();
    let mut cur: Vec<(Face, String)> = Vec::new();
    let mut w = 0.0;
    let space = |f: Face| width(" ", f, size);
    let mut words: Vec<(Face, String, bool)> = Vec::new(); // (face, word, space before)
    let mut pending_space = false;
    for s in text {
        let f = face(s);
        for (i, part) in s.text.split(' ').enumerate() {
            if i > 0 {
                pending_space = true;
            }
            if part.is_empty() {
                continue;
            }
            words.push((f, part.to_string(), pending_space && !words.is_empty()));
            pending_space = false;
        }
    }
    for (f, word, sp) in words {
        let ww = width(&word, f, size);
        let sw = if sp && !cur.is_empty() { space(f) } else { 0.0 };
        if !cur.is_empty() && w + sw + ww > max {
            lines.push((std::mem::take(&mut cur), w));
            w = 0.0;
        }
        let mut word = word;
        let mut ww = ww;
        // A word longer than the line (a path, a hash) is broken by characters.
        while ww > max && cur.is_empty() {
            let mut cut = 0;
            let mut acc = 0.0;
            for (i, c) in word.char_indices() {
                let cw = width(&c.to_string(), f, size);
                if acc + cw > max && i > 0 {
                    break;
                }
                acc += cw;
                cut = i + c.len_utf8();
            }
            lines.push((vec![(f, word[..cut].to_string())], acc));
            word = word[cut..].to_string();
            ww = width(&word, f, size);
        }
        if word.is_empty() {
            continue;
        }
        let sw = if sp && !cur.is_empty() { space(f) } else { 0.0 };
        match cur.last_mut() {
            Some((lf, lt)) if *lf == f => {
                if sw > 0.0 {
                    lt.push(' ');
                }
                lt.push_str(&word);
            }
            _ => {
                let mut t = String::new();
                if sw > 0.0 {
                    t.push(' ');
                }
                t.push_str(&word);
                cur.push((f, t));
            }
        }
        w += sw + ww;
    }
    if !cur.is_empty() || lines.is_empty() {
        lines.push((cur, w));
    }
    lines
}

/// The pages being laid out.
pub(super) struct Layout {
    pub(super) pages: Vec<Vec<El>>,
    y: f64,
    pub(super) figures: Vec<String>,
}

impl Layout {
    fn new() -> Self {
        Layout { pages: vec![Vec::new()], y: TOP, figures: Vec::new() }
    }
    fn page(&mut self) -> &mut Vec<El> {
        self.pages.last_mut().expect("a page")
    }
    fn bottom() -> f64 {
        PAGE.1 - BOTTOM
    }
    fn new_page(&mut self) {
        if !self.page().is_empty() {
            self.pages.push(Vec::new());
        }
        self.y = TOP;
    }
    /// Makes room for `h` points, starting a new page when they do not fit.
    fn need(&mut self, h: f64) {
        if self.y + h > Self::bottom() && self.y > TOP {
            self.new_page();
        }
    }
    fn lines(&mut self, lines: &[Line], x: f64, size: f64, keep: usize) {
        let lh = size * LEAD;
        self.need(lh * keep.min(lines.len()) as f64);
        for (runs, _) in lines {
            self.need(lh);
            self.y += lh;
            let y = self.y - 0.28 * lh;
            self.page().push(El::Text { x, y, size, runs: runs.clone(), grey: false, middle: false });
        }
    }
    fn paragraph(&mut self, t: &[Span], x: f64, max: f64, size: f64) {
        let lines = wrap(t, size, max);
        self.lines(&lines, x, size, 2);
        self.y += 0.45 * size;
    }
    fn heading(&mut self, text: &str, size: f64, keep: f64) {
        let lines = wrap(&[Span::bold(text)], size, WIDTH);
        // Keep a heading with the start of what follows (`keep` points of it).
        self.need(size * LEAD * lines.len() as f64 + 0.5 * size + keep);
        if self.y > TOP {
            self.y += 0.6 * size;
        }
        self.lines(&lines, LEFT, size, lines.len());
        self.y += 0.35 * size;
    }
    fn bullets(&mut self, items: &[Text]) {
        for it in items {
            let lines = wrap(it, BODY, WIDTH - 12.0);
            let lh = BODY * LEAD;
            self.need(lh * lines.len().min(2) as f64);
            let y0 = self.y + lh - 0.28 * lh;
            self.page().push(El::Text { x: LEFT + 3.0, y: y0, size: BODY, runs: vec![(Face::Regular, "•".into())], grey: false, middle: false });
            self.lines(&lines, LEFT + 12.0, BODY, 2);
            self.y += 0.2 * BODY;
        }
        self.y += 0.3 * BODY;
    }
    fn table(&mut self, header: &[String], rows: &[Vec<String>], key_values: bool) {
        let n = header.len().max(rows.iter().map(|r| r.len()).max().unwrap_or(0));
        if n == 0 {
            return;
        }
        let size = SMALL;
        let pad = 4.0;
        let cell_face = |c: usize, head: bool| if head || (key_values && c == 0) { Face::Bold } else { Face::Regular };
        // Natural width of each column (widest cell) and the longest word (the least it takes).
        let mut natural = vec![0.0f64; n];
        let mut least = vec![0.0f64; n];
        let all = std::iter::once((true, header)).chain(rows.iter().map(|r| (false, r.as_slice())));
        for (head, r) in all {
            for (c, cell) in r.iter().enumerate() {
                let f = cell_face(c, head);
                natural[c] = natural[c].max(width(cell, f, size) + 2.0 * pad);
                for w in cell.split(' ') {
                    least[c] = least[c].max((width(w, f, size) + 2.0 * pad).min(WIDTH / n as f64));
                }
            }
        }
        // Columns whose natural width fits their fair share of what is left keep it, narrowest
        // first; the others share the rest in proportion to their natural widths, never below
        // their longest word.
        let mut cols = natural.clone();
        if natural.iter().sum::<f64>() > WIDTH {
            let mut order: Vec<usize> = (0..n).collect();
            order.sort_by(|&a, &b| natural[a].total_cmp(&natural[b]));
            let mut left = WIDTH;
            let mut open: Vec<usize> = order.clone();
            while let Some(&c) = open.first() {
                if natural[c] <= left / open.len() as f64 {
                    left -= natural[c];
                    open.remove(0);
                } else {
                    break;
                }
            }
            let nat: f64 = open.iter().map(|&c| natural[c]).sum();
            for &c in &open {
                cols[c] = (left * natural[c] / nat).max(least[c]);
            }
        }
        // Columns held at their longest word can push the sum over the width: take the excess
        // from the columns wider than their longest word, then, if still over, from all alike.
        let sum: f64 = cols.iter().sum();
        if sum > WIDTH {
            let slack: f64 = (0..n).map(|c| cols[c] - least[c]).sum();
            let excess = sum - WIDTH;
            if slack >= excess {
                for c in 0..n {
                    cols[c] -= excess * (cols[c] - least[c]) / slack;
                }
            } else {
                cols.iter_mut().for_each(|c| *c *= WIDTH / sum);
            }
        }
        let total: f64 = cols.iter().sum();
        let lh = size * LEAD;
        let wrap_row = |r: &[String], head: bool| -> Vec<Vec<Line>> {
            (0..n)
                .map(|c| {
                    let cell = r.get(c).map(String::as_str).unwrap_or("");
                    let span = Span { text: cell.to_string(), bold: cell_face(c, head) == Face::Bold, code: false };
                    wrap(&[span], size, cols[c] - 2.0 * pad)
                })
                .collect()
        };
        let head = if key_values { None } else { Some(wrap_row(header, true)) };
        let height = |cells: &[Vec<Line>]| cells.iter().map(|l| l.len()).max().unwrap_or(1) as f64 * lh + 3.0;
        let draw_row = |lay: &mut Layout, cells: &[Vec<Line>], stripe: bool| {
            let h = height(cells);
            let top = lay.y;
            if stripe {
                lay.page().push(El::Fill { x: LEFT, y: top, w: total, h, rgb: (242, 244, 247) });
            }
            let mut x = LEFT;
            for (c, lines) in cells.iter().enumerate() {
                let mut y = top + 1.5;
                for (runs, _) in lines {
                    y += lh;
                    lay.page().push(El::Text { x: x + pad, y: y - 0.28 * lh, size, runs: runs.clone(), grey: false, middle: false });
                }
                x += cols[c];
            }
            lay.y = top + h;
        };
        let draw_head = |lay: &mut Layout| {
            let y = lay.y;
            lay.page().push(El::Rule { x0: LEFT, x1: LEFT + total, y, w: 0.8 });
            if let Some(hc) = &head {
                draw_row(lay, hc, false);
                let y = lay.y;
                lay.page().push(El::Rule { x0: LEFT, x1: LEFT + total, y, w: 0.4 });
            }
        };
        let first = rows.first().map(|r| height(&wrap_row(r, false))).unwrap_or(0.0);
        self.need(head.as_ref().map_or(0.0, |h| height(h)) + first + 2.0);
        self.y += 2.0;
        draw_head(self);
        for (i, r) in rows.iter().enumerate() {
            let cells = wrap_row(r, false);
            if self.y + height(&cells) > Self::bottom() {
                let y = self.y;
                self.page().push(El::Rule { x0: LEFT, x1: LEFT + total, y, w: 0.8 });
                self.new_page();
                draw_head(self);
            }
            draw_row(self, &cells, i % 2 == 1);
        }
        let y = self.y;
        self.page().push(El::Rule { x0: LEFT, x1: LEFT + total, y, w: 0.8 });
        self.y += 0.9 * BODY;
    }
    fn figure(&mut self, svg: &str, caption: &[Span], number: usize) -> Result<()> {
        let (vw, vh, natural_w) = figure_size(svg)?;
        let w = natural_w.min(WIDTH);
        let h = w * vh / vw;
        let cap_lines = wrap(&figure_caption(caption, number), 8.5, WIDTH);
        let cap_h = cap_lines.len() as f64 * 8.5 * LEAD;
        // A figure taller than a page is scaled to one; right under a heading at the top of a
        // page, to the room below the heading — else it would leave the heading alone on that
        // page.
        let under_heading = self.y < TOP + HEADING_ROOM;
        let avail = if under_heading { Self::bottom() - self.y } else { Self::bottom() - TOP } - 1.0; // (a point to spare: rounding)
        let (w, h) = if h + cap_h + 8.0 > avail { let s = ((avail - cap_h - 8.0) / h).max(0.1); (w * s, h * s) } else { (w, h) };
        self.need(h + cap_h + 8.0);
        let x = LEFT + 0.5 * (WIDTH - w);
        let y = self.y + 4.0;
        let index = self.figures.len();
        self.figures.push(svg.to_string());
        self.page().push(El::Figure { x, y, w, h, index });
        self.y = y + h + 2.0;
        self.lines(&cap_lines, LEFT, 8.5, cap_lines.len());
        self.y += 0.8 * BODY;
        Ok(())
    }
    fn verbatim(&mut self, text: &str) {
        let size = 7.0;
        for line in text.lines() {
            let lines = wrap(&[Span { text: line.to_string(), bold: false, code: true }], size, WIDTH);
            self.lines(&lines, LEFT, size, 1);
        }
        self.y += 0.6 * BODY;
    }
    fn warning(&mut self, t: &[Span]) {
        let text: Text = std::iter::once(Span::bold("Warning: ")).chain(t.iter().cloned()).collect();
        let lines = wrap(&text, BODY, WIDTH - 12.0);
        let h = lines.len() as f64 * BODY * LEAD + 6.0;
        self.need(h);
        let y = self.y;
        self.page().push(El::Fill { x: LEFT, y, w: WIDTH, h, rgb: (253, 243, 224) });
        self.y += 3.0;
        self.lines(&lines, LEFT + 6.0, BODY, lines.len());
        self.y = y + h + 0.5 * BODY;
    }
    fn block(&mut self, b: &Block, figure_no: &mut usize) -> Result<()> {
        match b {
            Block::Subheading(s) => self.heading(s, 10.5, 3.0 * BODY * LEAD),
            Block::Paragraph(t) => self.paragraph(t, LEFT, WIDTH, BODY),
            Block::Bullets(items) => self.bullets(items),
            Block::Table { header, rows } => self.table(header, rows, false),
            Block::KeyValues(kv) => {
                let rows: Vec<Vec<String>> = kv.iter().map(|(k, v)| vec![k.clone(), v.clone()]).collect();
                self.table(&["".into(), "".into()], &rows, true)
            }
            Block::Figure { svg, caption, .. } => {
                *figure_no += 1;
                self.figure(svg, caption, *figure_no)?;
            }
            Block::Verbatim(t) => self.verbatim(t),
            Block::Warning(t) => self.warning(t),
        }
        Ok(())
    }
}

/// viewBox width and height of a figure's SVG and its physical width in points.
pub(super) fn figure_size(svg: &str) -> Result<(f64, f64, f64)> {
    let head = svg_head(svg)?;
    let attr = |name: &str| -> Option<&str> {
        let k = head.find(&format!(" {name}=\""))? + name.len() + 3;
        let end = head[k..].find('"')?;
        Some(&head[k..k + end])
    };
    let vb: Vec<f64> = attr("viewBox").unwrap_or("").split_whitespace().filter_map(|v| v.parse().ok()).collect();
    let physical = |v: &str| -> Option<f64> {
        if let Some(cm) = v.strip_suffix("cm") {
            cm.parse::<f64>().ok().map(|c| c / 2.54 * 72.0)
        } else if let Some(pt) = v.strip_suffix("pt") {
            pt.parse().ok()
        } else {
            v.trim_end_matches("px").parse::<f64>().ok().map(|p| p * 0.75)
        }
    };
    let w = attr("width").and_then(physical);
    match (vb.as_slice(), w) {
        ([_, _, vw, vh], Some(w)) if *vw > 0.0 && *vh > 0.0 => Ok((*vw, *vh, w)),
        _ => Err(Error::Figure { name: "document".into(), detail: "a figure's SVG has no viewBox or width".into() }),
    }
}

/// The opening `<svg …>` tag of an SVG document.
pub(crate) fn svg_head(svg: &str) -> Result<&str> {
    let start = svg.find("<svg").ok_or_else(|| Error::Figure { name: "document".into(), detail: "not an SVG".into() })?;
    let end = svg[start..].find('>').ok_or_else(|| Error::Figure { name: "document".into(), detail: "unterminated <svg> tag".into() })?;
    Ok(&svg[start..start + end + 1])
}

/// The content of an SVG document between its `<svg …>` and `</svg>` tags.
pub(crate) fn svg_body(svg: &str) -> Result<&str> {
    let head = svg_head(svg)?;
    let start = svg.find(head).unwrap_or(0) + head.len();
    let end = svg.rfind("</svg>").ok_or_else(|| Error::Figure { name: "document".into(), detail: "no </svg>".into() })?;
    Ok(&svg[start..end.max(start)])
}

pub(crate) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            _ => out.push(c),
        }
    }
    out
}

/// Lays out the document into pages of elements, with the figures' SVGs.
/// Room a section heading takes at the top of a page (points), and more than it: a figure
/// right under it is sized to the rest of the page.
const HEADING_ROOM: f64 = 60.0;

/// "Figure n. " and the caption, as the figure prints it.
fn figure_caption(caption: &[Span], number: usize) -> Text {
    std::iter::once(Span::bold(format!("Figure {number}. "))).chain(caption.iter().cloned()).collect()
}

/// The room (points) a heading keeps below it on its page for the block `next` after it: a
/// figure (number `fig` + 1) with its caption — at most a page less the heading's room, since a
/// taller one starts the page, scaled to fit under the heading — or three lines of text.
fn keep_with(next: Option<&Block>, fig: usize) -> f64 {
    match next {
        Some(Block::Figure { svg, caption, .. }) => {
            let cap_h = wrap(&figure_caption(caption, fig + 1), 8.5, WIDTH).len() as f64 * 8.5 * LEAD;
            figure_size(svg).map_or(0.0, |(vw, vh, w)| w.min(WIDTH) * vh / vw + cap_h + 12.0).min(Layout::bottom() - TOP - HEADING_ROOM)
        }
        _ => 3.0 * BODY * LEAD,
    }
}

pub(super) fn layout(doc: &Document) -> Result<Layout> {
    let mut lay = Layout::new();
    let mut fig = 0;
    // First page: title, then its blocks.
    let title = wrap(&[Span::bold(&doc.title)], 16.0, WIDTH);
    lay.lines(&title, LEFT, 16.0, title.len());
    lay.y += 8.0;
    // A first-page subheading right above a figure (the figure that shows the answer) is kept
    // with it, as a section's heading is.
    for (i, b) in doc.first.iter().enumerate() {
        match (b, doc.first.get(i + 1)) {
            (Block::Subheading(h), next @ Some(Block::Figure { .. })) => lay.heading(h, 10.5, keep_with(next, fig)),
            _ => lay.block(b, &mut fig)?,
        }
    }
    for s in &doc.sections {
        if s.new_page {
            lay.new_page();
        }
        lay.heading(&s.heading, 13.0, keep_with(s.blocks.first(), fig));
        for b in &s.blocks {
            lay.block(b, &mut fig)?;
        }
    }
    Ok(lay)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_keeps_lines_within_width_and_words_whole() {
        let t = vec![Span::plain("The probability that Gen 4 breaks more than BL 16/30 in one year is "), Span::bold("0.9999"), Span::plain(" with a standard error.")];
        let lines = wrap(&t, 10.0, 120.0);
        assert!(lines.len() > 2);
        for (runs, w) in &lines {
            assert!(*w <= 120.0 + 1e-9, "{w}");
            let text: String = runs.iter().map(|r| r.1.as_str()).collect();
            assert!((width(&text.replace('\u{0}', ""), Face::Regular, 10.0) - w).abs() < 10.0);
        }
        let joined: Vec<String> = lines.iter().map(|(r, _)| r.iter().map(|x| x.1.as_str()).collect::<String>().trim().to_string()).collect();
        assert_eq!(joined.join(" "), plain_text(&t));
        // A word longer than the line is cut by characters.
        let long = wrap(&[Span::plain("a".repeat(200))], 10.0, 50.0);
        assert!(long.len() > 3 && long.iter().all(|(_, w)| *w <= 50.0));
    }

    #[test]
    fn no_page_holds_only_a_heading() {
        use super::super::document::Section;
        // Figures of every height up to well over a page, each opening its section under a
        // long caption, after paragraphs that leave the page at every depth.
        let caption: Text = vec![Span::plain("A caption of several lines. ".repeat(12))];
        let mut sections = Vec::new();
        for k in 0..12 {
            let h = 4.0 + 3.0 * k as f64;
            let svg = format!("<svg width=\"8.5cm\" height=\"{h}cm\" viewBox=\"0 0 850 {}\" xmlns=\"x\"></svg>", h * 100.0);
            sections.push(Section::new(format!("Residuals against covariate {k}"), vec![Block::Figure { stem: format!("f{k}"), svg, caption: caption.clone() }]));
            sections.push(Section::new(format!("Text {k}"), vec![Block::Paragraph(vec![Span::plain("Words. ".repeat(40 * k + 10))])]));
        }
        let doc = Document { title: "T".into(), running: "r".into(), first: vec![], sections };
        let lay = layout(&doc).unwrap();
        for (i, page) in lay.pages.iter().enumerate() {
            let texts = page.iter().filter(|e| matches!(e, El::Text { .. })).count();
            let other = page.iter().filter(|e| !matches!(e, El::Text { .. } | El::Rule { .. })).count();
            assert!(other > 0 || texts > 1, "page {} holds only a heading: {:?}", i + 1, page.iter().filter_map(|e| match e { El::Text { runs, .. } => Some(runs.iter().map(|r| r.1.clone()).collect::<String>()), _ => None }).collect::<Vec<_>>());
        }
        // Every figure sits on the page of its heading: a figure element on each page that a
        // "Residuals" heading ends.
        for page in &lay.pages {
            let headed = page.iter().rev().find_map(|e| match e { El::Text { runs, .. } => Some(runs.iter().any(|r| r.1.starts_with("Residuals against"))), _ => None });
            if headed == Some(true) {
                panic!("a page ends with a figure's heading, its figure on the next");
            }
        }
    }

    #[test]
    fn a_first_page_subheading_stays_with_its_figure() {
        // Paragraphs that fill the first page to every depth, then the answer's figure under a
        // subheading: the subheading is never the last line of a page.
        let svg = "<svg width=\"8.5cm\" height=\"8cm\" viewBox=\"0 0 850 800\" xmlns=\"x\"></svg>".to_string();
        for k in 0..30 {
            let first = vec![
                Block::Paragraph(vec![Span::plain("Words of the answer. ".repeat(20 + 12 * k))]),
                Block::Subheading("The figure of the answer".into()),
                Block::Figure { stem: "f".into(), svg: svg.clone(), caption: vec![Span::plain("A caption.")] },
            ];
            let lay = layout(&Document { title: "T".into(), running: "r".into(), first, sections: vec![] }).unwrap();
            for page in &lay.pages {
                let last = page.iter().rev().find_map(|e| match e { El::Text { runs, .. } => Some(runs.iter().map(|r| r.1.as_str()).collect::<String>()), _ => None });
                let has_figure = page.iter().any(|e| matches!(e, El::Figure { .. }));
                assert!(has_figure || last.as_deref().map(str::trim) != Some("The figure of the answer"), "k = {k}: a page ends with the subheading, its figure on the next");
            }
        }
    }

    #[test]
    fn figure_size_reads_physical_width() {
        let (vw, vh, w) = figure_size("<svg width=\"8.500cm\" height=\"6cm\" viewBox=\"0 0 1928 1361\" xmlns=\"x\"></svg>").unwrap();
        assert_eq!((vw, vh), (1928.0, 1361.0));
        assert!((w - 8.5 / 2.54 * 72.0).abs() < 1e-9);
    }
}

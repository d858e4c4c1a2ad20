//! Figure canvas and export: plotters draws SVG; the same SVG becomes a 300-dpi PNG (resvg)
//! and a vector PDF with embedded fonts (svg2pdf), its reference dictionaries sorted
//! ([`canonical`]) so that a figure's bytes do not change from run to run.
//!
//! Text is the trap (ARCHITECTURE.md, "Figures"): usvg resolves the SVG's `font-family`
//! through its own font database and silently drops text in a family it does not have. So one
//! font, DejaVu Sans (embedded by the `dejavu` crate, Bitstream Vera licence), is registered
//! with plotters for glyph metrics under the family name "DejaVu Sans", loaded explicitly into
//! the usvg database, and named in every chart. No font is read from the machine.
//!
//! Units: the canvas has 8 px per typographic point (plotters snaps to integer pixels; at
//! 8 px/pt the snapping is invisible even at 300 dpi). The SVG is written with its physical size
//! in cm (`width="8.5cm"`, with the pixel `viewBox`), so it imports at the right size; the PDF
//! page has that size; the PNG is rendered at 300 dpi.

use std::sync::{Arc, OnceLock};

use plotters::prelude::*;
use resvg::tiny_skia;
use svg2pdf::usvg;

use crate::error::{Error, Result};

/// The one font family used by every figure.
pub const FONT: &str = "DejaVu Sans";
/// Canvas pixels per typographic point.
pub const PX_PER_PT: f64 = 8.0;
/// PNG resolution.
pub const PNG_DPI: f32 = 300.0;

/// plotters font size (its unit) for a size in points: plotters writes `size/1.24` into SVG.
pub fn font_size(pt: f64) -> f64 {
    pt * PX_PER_PT * 1.24
}

/// A text style of the figure font.
pub fn text(pt: f64) -> TextStyle<'static> {
    (FONT, font_size(pt)).into_font().color(&BLACK)
}

/// Registers the font with plotters (once per process).
pub fn register_fonts() -> Result<()> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular()).is_ok()
            && plotters::style::register_font(FONT, FontStyle::Bold, dejavu::sans::bold()).is_ok()
            && plotters::style::register_font(FONT, FontStyle::Oblique, dejavu::sans::oblique()).is_ok()
            && plotters::style::register_font(FONT, FontStyle::Italic, dejavu::sans::oblique()).is_ok()
    });
    if ok { Ok(()) } else { Err(Error::Figure { name: "fonts".into(), detail: "DejaVu Sans could not be registered".into() }) }
}

pub(crate) fn usvg_options() -> &'static usvg::Options<'static> {
    static OPTS: OnceLock<usvg::Options<'static>> = OnceLock::new();
    OPTS.get_or_init(|| {
        let mut db = usvg::fontdb::Database::new();
        db.load_font_data(dejavu::sans::regular().to_vec());
        db.load_font_data(dejavu::sans::bold().to_vec());
        db.load_font_data(dejavu::sans::oblique().to_vec());
        db.set_sans_serif_family(FONT);
        db.set_serif_family(FONT);
        usvg::Options { font_family: FONT.to_string(), fontdb: Arc::new(db), ..usvg::Options::default() }
    })
}

/// Pixel size of a figure of `width_cm` and aspect ratio height/width.
pub fn canvas_size(width_cm: f64, aspect: f64) -> (u32, u32) {
    let w = (width_cm / 2.54 * 72.0 * PX_PER_PT).round();
    (w as u32, (w * aspect).round() as u32)
}

/// Maps a plotters drawing error to [`Error::Figure`].
pub fn fig_err<E: std::fmt::Debug>(name: &str) -> impl Fn(E) -> Error + '_ {
    move |e| Error::Figure { name: name.to_string(), detail: format!("{e:?}") }
}

/// The three encodings of one figure.
#[derive(Debug, Clone)]
pub struct Encoded {
    /// SVG text with physical size.
    pub svg: String,
    /// PNG bytes, 300 dpi.
    pub png: Vec<u8>,
    /// PDF bytes, vector, fonts embedded.
    pub pdf: Vec<u8>,
}

/// Gives the plotters SVG its physical size and converts it to PNG and PDF.
pub fn encode(name: &str, svg: &str, size: (u32, u32), width_cm: f64) -> Result<Encoded> {
    let height_cm = width_cm * size.1 as f64 / size.0 as f64;
    let from = format!("<svg width=\"{}\" height=\"{}\"", size.0, size.1);
    if !svg.contains(&from) {
        return Err(Error::Figure { name: name.into(), detail: "unexpected SVG header from plotters".into() });
    }
    let svg = svg.replacen(&from, &format!("<svg width=\"{width_cm:.3}cm\" height=\"{height_cm:.3}cm\""), 1);
    let tree = usvg::Tree::from_str(&svg, usvg_options())
        .map_err(|e| Error::Figure { name: name.into(), detail: format!("SVG parse: {e}") })?;
    // PNG at 300 dpi on white.
    let scale = PNG_DPI / usvg_options().dpi;
    let (w, h) = ((tree.size().width() * scale).ceil() as u32, (tree.size().height() * scale).ceil() as u32);
    let mut pixmap = tiny_skia::Pixmap::new(w, h)
        .ok_or_else(|| Error::Figure { name: name.into(), detail: format!("cannot allocate {w}×{h} pixmap") })?;
    pixmap.fill(tiny_skia::Color::WHITE);
    resvg::render(&tree, tiny_skia::Transform::from_scale(scale, scale), &mut pixmap.as_mut());
    let png = pixmap.encode_png().map_err(|e| Error::Figure { name: name.into(), detail: format!("PNG: {e}") })?;
    let pdf = svg2pdf::to_pdf(
        &tree,
        svg2pdf::ConversionOptions::default(),
        svg2pdf::PageOptions { dpi: usvg_options().dpi },
    )
    .map_err(|e| Error::Figure { name: name.into(), detail: format!("PDF: {e:?}") })?;
    // svg2pdf writes resource dictionaries in hash-map order: sorted, the same figure gives the
    // same bytes from run to run.
    Ok(Encoded { svg, png, pdf: canonical(&pdf) })
}

/// Fails when the figure font has no glyph for a character of `text` (it would print as a
/// box or vanish).
pub fn check_glyphs(figure: &str, text: &str) -> Result<()> {
    use ab_glyph::Font;
    let font = ab_glyph::FontRef::try_from_slice(dejavu::sans::regular())
        .map_err(|e| Error::Figure { name: figure.into(), detail: format!("font: {e}") })?;
    match text.chars().find(|&c| !c.is_whitespace() && font.glyph_id(c).0 == 0) {
        Some(c) => Err(Error::Figure {
            name: figure.into(),
            detail: format!("{FONT} has no glyph for '{c}' (U+{:04X}) in \"{text}\"", c as u32),
        }),
        None => Ok(()),
    }
}

/// Okabe–Ito colours (colour-blind safe), in assignment order.
pub const PALETTE: [RGBColor; 6] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(230, 159, 0),   // orange
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(86, 180, 233),  // sky blue
];

/// Colour of the i-th material.
pub fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// The step between the tick labels plotters draws on [lo, hi] with at most `max_labels` of them:
/// the finest of 1, 2 and 5 × 10^k whose labels fit (plotters' float key points count the
/// multiples of a step inside the range the same way).
fn tick_step(lo: f64, hi: f64, max_labels: usize) -> f64 {
    let (lo, hi) = (lo.min(hi), lo.max(hi));
    let span = (hi - lo).max(1e-300);
    let count = |step: f64| 1.0 + ((hi / step).floor() - (lo / step).ceil());
    let mut step = 10f64.powf(span.log10().floor());
    if count(step) > max_labels.max(1) as f64 {
        step *= 10.0;
    }
    for _ in 0..64 {
        let finer = [step / 2.0, step / 5.0, step / 10.0];
        match finer.iter().find(|&&s| count(s).round() > max_labels.max(1) as f64) {
            Some(_) => {
                // The finest of the three that still fits, if any.
                return finer.iter().copied().take_while(|&s| count(s).round() <= max_labels.max(1) as f64).last().unwrap_or(step);
            }
            None => step /= 10.0,
        }
    }
    step
}

/// Tick-label formatter with as many decimals as the step between the labels needs, for an axis
/// drawn with at most `max_labels` labels (before: decimals from the span alone, so "0.30 0.40
/// … 0.70" ran together on a narrow panel where "0.3 … 0.7" says the same).
pub fn tick_format(lo: f64, hi: f64, max_labels: usize) -> impl Fn(&f64) -> String {
    let mut step = tick_step(lo, hi, max_labels);
    // Where the next finer step would fit but for one label, rounding inside plotters may take
    // it: its digits then, so that two labels never read the same.
    let (lo_, hi_) = (lo.min(hi), lo.max(hi));
    let mantissa = step / 10f64.powf((step.log10() + 1e-9).floor());
    let finer = if mantissa > 4.0 { step * 0.4 } else { step * 0.5 };
    if 1.0 + ((hi_ / finer).floor() - (lo_ / finer).ceil()) <= max_labels as f64 + 1.0 {
        step = finer;
    }
    let decimals = (-(step.log10() + 1e-9).floor()).clamp(0.0, 8.0) as usize;
    move |v: &f64| {
        let s = format!("{:.*}", decimals, v);
        // Avoid "-0".
        if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') { format!("{:.*}", decimals, 0.0) } else { s.replace('-', "−") }
    }
}

/// "10⁻⁶"-style label for a power of ten, "2×10⁻⁶" otherwise.
pub fn power_of_ten(v: &f64) -> String {
    if *v <= 0.0 {
        return "0".into();
    }
    let e = v.log10().floor();
    let m = v / 10f64.powf(e);
    let sup: String = format!("{}", e as i64)
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            _ => '⁹',
        })
        .collect();
    if e == 0.0 && (m - 1.0).abs() < 1e-6 {
        "1".into()
    } else if (m - 1.0).abs() < 1e-6 {
        format!("10{sup}")
    } else {
        format!("{m:.0}×10{sup}")
    }
}

/// The PDF with the entries of every dictionary of references in one order. svg2pdf writes the
/// resource dictionaries of an XObject (`/xo0 40 0 R`, `/gs0 39 0 R`, …) from hash maps, in an
/// order that changes from run to run; the order of a dictionary's entries has no meaning, so
/// sorting them gives the same bytes for the same document. Stream data (after `stream`, its
/// `/Length` bytes) is copied untouched.
pub(crate) fn canonical(pdf: &[u8]) -> Vec<u8> {
    const START: &[u8] = b">>\nstream\n";
    let find = |hay: &[u8], from: usize, needle: &[u8]| hay[from..].windows(needle.len()).position(|w| w == needle).map(|i| i + from);
    let mut out = Vec::with_capacity(pdf.len());
    let mut pos = 0;
    while pos < pdf.len() {
        let Some(i) = find(pdf, pos, START) else {
            out.extend(sorted_pairs(&pdf[pos..]));
            break;
        };
        let data = i + START.len();
        let text = &pdf[pos..data];
        let length = text
            .windows(8)
            .rposition(|w| w == b"/Length ")
            .and_then(|k| {
                let digits: Vec<u8> = text[k + 8..].iter().take_while(|c| c.is_ascii_digit()).copied().collect();
                std::str::from_utf8(&digits).ok()?.parse::<usize>().ok()
            })
            .unwrap_or(0);
        out.extend(sorted_pairs(text));
        let end = (data + length).min(pdf.len());
        out.extend_from_slice(&pdf[data..end]);
        pos = end;
    }
    out
}

/// Text of PDF objects with each run of `/name N 0 R` lines between a line ending in `<<` and a
/// `>>` line sorted.
fn sorted_pairs(text: &[u8]) -> Vec<u8> {
    let is_pair = |l: &[u8]| {
        let t = l.trim_ascii();
        let parts: Vec<&[u8]> = t.split(|&c| c == b' ').collect();
        parts.len() == 4 && parts[0].first() == Some(&b'/') && parts[1].iter().all(u8::is_ascii_digit) && parts[2] == b"0" && parts[3] == b"R"
    };
    let lines: Vec<&[u8]> = text.split(|&c| c == b'\n').collect();
    let mut out: Vec<&[u8]> = Vec::with_capacity(lines.len());
    let mut i = 0;
    while i < lines.len() {
        out.push(lines[i]);
        if lines[i].trim_ascii_end().ends_with(b"<<") {
            let mut j = i + 1;
            while j < lines.len() && is_pair(lines[j]) {
                j += 1;
            }
            if j > i + 2 && j < lines.len() && lines[j].trim_ascii() == b">>" {
                let mut run: Vec<&[u8]> = lines[i + 1..j].to_vec();
                run.sort();
                out.extend(run);
                i = j;
                continue;
            }
        }
        i += 1;
    }
    out.join(&b'\n')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dictionaries_of_references_are_sorted_and_streams_kept() {
        let a = b"1 0 obj\n<<\n  /XObject <<\n    /xo1 43 0 R\n    /xo0 40 0 R\n  >>\n  /Length 9\n>>\nstream\n<<\n/b 1 0 R\nendstream\n";
        let b = b"1 0 obj\n<<\n  /XObject <<\n    /xo0 40 0 R\n    /xo1 43 0 R\n  >>\n  /Length 9\n>>\nstream\n<<\n/b 1 0 R\nendstream\n";
        assert_eq!(canonical(a), canonical(b));
        assert_eq!(canonical(b), b.to_vec());
    }

    #[test]
    fn labels() {
        assert_eq!(power_of_ten(&1e-6), "10⁻⁶");
        assert!(check_glyphs("t", "σ̄ σᵣ Fₘₐₓ µm η θ ∫ ⁻¹²³ − × ·").is_ok());
        assert!(check_glyphs("t", "\u{10FFFD}").is_err());
        assert_eq!(power_of_ten(&1.0), "1");
        assert_eq!(power_of_ten(&3e2), "3×10²");
        let f = tick_format(0.0, 20.0, 6);
        assert_eq!(f(&5.0), "5");
        let f = tick_format(0.0, 1.0, 6);
        assert_eq!(f(&-0.5), "−0.5");
        // The corner plot's t axis (0.23–0.72 GPa): labels every 0.1, one decimal.
        assert_eq!(tick_step(0.23, 0.72, 6), 0.1);
        assert_eq!(tick_format(0.23, 0.72, 6)(&0.3), "0.3");
        // Finer steps keep their digits: 0.05 on a 0.25 span, 0.02 with more labels allowed.
        assert_eq!(tick_format(0.0, 0.25, 6)(&0.05), "0.05");
        assert_eq!(tick_step(0.0, 0.1, 6), 0.02);
        assert_eq!(tick_step(0.0, 20.0, 6), 5.0);
        assert_eq!(canvas_size(8.5, 0.75).0, 1928);
    }
}

//! `report.pdf`: any [`Document`] laid out on A4 pages ([`super::layout`]) and written as a
//! vector PDF. Each page becomes form XObjects made by svg2pdf from SVG, fonts embedded and
//! subset: one layer per font face (svg2pdf writes the fonts of one conversion in hash-map order,
//! so one face per conversion keeps the bytes the same from run to run) and each figure's own
//! SVG. The conversions run side by side (each is a chunk numbered on its own) and are
//! renumbered into the document in the pages' order; pdf-writer assembles the pages, with a
//! running title and "page k of n". Reference dictionaries are sorted
//! ([`super::canvas::canonical`], as in every figure's PDF): nothing in the file depends on the
//! time, the machine or the process, so the same document gives the same bytes. Verified by
//! `tests/documents.rs` (pdfinfo, pdffonts, pdftotext, byte-identical rewrites).

use std::collections::HashMap;
use std::sync::OnceLock;

use pdf_writer::{Content, Finish, Name, Pdf, Rect, Ref, TextStr};
use rayon::prelude::*;
use svg2pdf::usvg;

use super::document::Document;
use super::layout::{El, Face, LEFT, Layout, PAGE, escape, layout, width};
use crate::error::{Error, Result};

/// One page as XObjects: SVG layers, each holding at most one font face (svg2pdf writes the
/// fonts of one conversion in hash-map order, so a layer with two faces would give different
/// bytes from run to run), and the figures with their placement (x, y, w, h from the top left).
struct Page {
    layers: Vec<String>,
    figures: Vec<(usize, [f64; 4])>,
}

fn page_layers(lay: &Layout, k: usize, running: &str) -> Page {
    let n = lay.pages.len();
    let head = format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n", w = PAGE.0, h = PAGE.1);
    // Layer 0: white page, fills, rules and regular text; 1: bold text; 2: code.
    let mut layers = [head.clone() + &format!("<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#FFFFFF\"/>\n", PAGE.0, PAGE.1), head.clone(), head];
    let mut used = [true, false, false];
    let mut figures = Vec::new();
    let mut els = lay.pages[k].clone();
    // Running title and page number.
    els.push(El::Text { x: LEFT, y: 36.0, size: 7.5, runs: vec![(Face::Regular, running.to_string())], grey: true, middle: false });
    els.push(El::Rule { x0: LEFT, x1: PAGE.0 - LEFT, y: 40.0, w: 0.3 });
    els.push(El::Text { x: PAGE.0 / 2.0, y: PAGE.1 - 30.0, size: 7.5, runs: vec![(Face::Regular, format!("page {} of {n}", k + 1))], grey: true, middle: true });
    for el in &els {
        match el {
            El::Text { x, y, size, runs, grey, middle } => {
                // Each run is its own text element at the x its predecessors' advances give.
                let mut xr = *x;
                for (f, t) in runs {
                    let (layer, attrs) = match f {
                        Face::Regular => (0, ""),
                        Face::Bold => (1, " font-weight=\"bold\""),
                        Face::Mono => (2, ""),
                    };
                    let family = if *f == Face::Mono { "DejaVu Sans Mono" } else { "DejaVu Sans" };
                    used[layer] = true;
                    layers[layer].push_str(&format!(
                        "<text x=\"{xr:.2}\" y=\"{y:.2}\" font-size=\"{size}\" font-family=\"{family}\"{attrs} xml:space=\"preserve\" fill=\"{}\"{}>{}</text>\n",
                        if *grey { "#555555" } else { "#000000" },
                        if *middle { " text-anchor=\"middle\"" } else { "" },
                        escape(t)
                    ));
                    xr += width(t, *f, *size);
                }
            }
            El::Rule { x0, x1, y, w } => layers[0].push_str(&format!("<line x1=\"{x0:.2}\" y1=\"{y:.2}\" x2=\"{x1:.2}\" y2=\"{y:.2}\" stroke=\"#000000\" stroke-width=\"{w}\"/>\n")),
            El::Fill { x, y, w, h, rgb } => layers[0].push_str(&format!("<rect x=\"{x:.2}\" y=\"{y:.2}\" width=\"{w:.2}\" height=\"{h:.2}\" fill=\"#{:02X}{:02X}{:02X}\"/>\n", rgb.0, rgb.1, rgb.2)),
            El::Figure { x, y, w, h, index } => figures.push((*index, [*x, *y, *w, *h])),
        }
    }
    let layers = layers.into_iter().zip(used).filter(|(_, u)| *u).map(|(l, _)| l + "</svg>\n").collect();
    Page { layers, figures }
}

fn options() -> &'static usvg::Options<'static> {
    static OPTS: OnceLock<usvg::Options<'static>> = OnceLock::new();
    OPTS.get_or_init(|| {
        // The figures' database (canvas) plus the mono face for code.
        let base = super::canvas::usvg_options();
        let mut db = (*base.fontdb).clone();
        db.load_font_data(dejavu::sans_mono::regular().to_vec());
        db.set_monospace_family("DejaVu Sans Mono");
        usvg::Options { font_family: base.font_family.clone(), fontdb: std::sync::Arc::new(db), ..usvg::Options::default() }
    })
}


/// The document as PDF bytes.
pub fn render(doc: &Document) -> Result<Vec<u8>> {
    let lay = layout(doc)?;
    let pages: Vec<Page> = (0..lay.pages.len()).map(|k| page_layers(&lay, k, &doc.running)).collect();
    let mut alloc = Ref::new(1);
    let catalog = alloc.bump();
    let tree_id = alloc.bump();
    let info = alloc.bump();
    let page_ids: Vec<Ref> = pages.iter().map(|_| alloc.bump()).collect();
    let content_ids: Vec<Ref> = pages.iter().map(|_| alloc.bump()).collect();
    let mut pdf = Pdf::new();
    pdf.catalog(catalog).pages(tree_id);
    pdf.pages(tree_id).kids(page_ids.iter().copied()).count(pages.len() as i32);
    pdf.document_info(info).title(TextStr(&doc.title)).producer(TextStr(concat!("partlife ", env!("CARGO_PKG_VERSION"))));
    // Every SVG (each page's layers, then its figures) converted side by side: each conversion
    // is a chunk of its own, numbered from 1, whatever runs beside it.
    let what = |k: usize| format!("report.pdf page {}", k + 1);
    let svgs: Vec<(usize, &str)> = pages.iter().enumerate().flat_map(|(k, page)| page.layers.iter().map(String::as_str).chain(page.figures.iter().map(|(index, _)| lay.figures[*index].as_str())).map(move |svg| (k, svg))).collect();
    let converted: Vec<Result<(pdf_writer::Chunk, Ref)>> = svgs
        .par_iter()
        .map(|&(k, svg)| {
            let t = usvg::Tree::from_str(svg, options()).map_err(|e| Error::Figure { name: what(k), detail: format!("SVG parse: {e}") })?;
            svg2pdf::to_chunk(&t, svg2pdf::ConversionOptions::default()).map_err(|e| Error::Figure { name: what(k), detail: format!("PDF: {e:?}") })
        })
        .collect();
    let mut converted = converted.into_iter();
    // The next conversion as a form XObject of this PDF, its objects renumbered into the
    // document's in the pages' order (the same numbers as converting one after another).
    let mut embed = |pdf: &mut Pdf| -> Result<Ref> {
        let (chunk, x_ref) = converted.next().expect("one conversion per layer and figure")?;
        let mut map = HashMap::new();
        let chunk = chunk.renumber(|old| *map.entry(old).or_insert_with(|| alloc.bump()));
        pdf.extend(&chunk);
        Ok(map[&x_ref])
    };
    for (k, page) in pages.iter().enumerate() {
        let mut content = Content::new();
        let mut xobjects: Vec<(String, Ref)> = Vec::new();
        for (i, _) in page.layers.iter().enumerate() {
            let r = embed(&mut pdf)?;
            let name = format!("L{i}");
            content.save_state().transform([PAGE.0 as f32, 0.0, 0.0, PAGE.1 as f32, 0.0, 0.0]).x_object(Name(name.as_bytes())).restore_state();
            xobjects.push((name, r));
        }
        for (i, (_, [x, y, w, h])) in page.figures.iter().enumerate() {
            let r = embed(&mut pdf)?;
            let name = format!("F{i}");
            let (x, y, w, h) = (*x as f32, *y as f32, *w as f32, *h as f32);
            content.save_state().transform([w, 0.0, 0.0, h, x, PAGE.1 as f32 - y - h]).x_object(Name(name.as_bytes())).restore_state();
            xobjects.push((name, r));
        }
        let mut p = pdf.page(page_ids[k]);
        p.media_box(Rect::new(0.0, 0.0, PAGE.0 as f32, PAGE.1 as f32));
        p.parent(tree_id);
        p.contents(content_ids[k]);
        {
            let mut res = p.resources();
            let mut xo = res.x_objects();
            for (name, r) in &xobjects {
                xo.pair(Name(name.as_bytes()), *r);
            }
        }
        p.finish();
        pdf.stream(content_ids[k], &content.finish());
    }
    Ok(super::canvas::canonical(&pdf.finish()))
}

//! `report.html`: any [`Document`] as one self-contained web page.
//!
//! Figures are inline SVG (their width and height attributes dropped so CSS scales them to the
//! column), styles are in the page, there is no script and no external request: the file reads
//! offline, in any browser, on a phone (the body is at most 46 em wide, figures scale to it,
//! wide tables scroll inside their own box). A table of contents links every section's anchor.
//! Verified in a headless browser by `tests/documents.rs`.

use super::document::{Block, Document, Span};
use super::layout::{escape, svg_body, svg_head};
use crate::error::Result;

const STYLE: &str = "\
:root{color-scheme:light}\
body{font-family:'DejaVu Sans',Verdana,'Segoe UI',Roboto,sans-serif;line-height:1.45;color:#111;background:#fff;max-width:46em;margin:0 auto;padding:0.8em 1em 3em}\
h1{font-size:1.45em;line-height:1.25}h2{font-size:1.2em;margin-top:1.8em;border-bottom:1px solid #ccc}h3{font-size:1.02em}\
nav ol{padding-left:1.3em}code,pre{font-family:'DejaVu Sans Mono',Menlo,Consolas,monospace;font-size:0.9em}\
pre{white-space:pre-wrap;overflow-wrap:anywhere;background:#f5f6f8;padding:0.6em;border-radius:3px}\
figure{margin:1.2em 0}figure svg{display:block;width:100%;max-width:var(--w);height:auto;margin:0 auto}\
figcaption{font-size:0.9em;margin-top:0.4em}\
.scroll{overflow-x:auto;margin:0.6em 0}table{border-collapse:collapse;font-size:0.82em}\
th,td{padding:0.2em 0.5em;text-align:left;vertical-align:top;border-bottom:1px solid #ddd}th{border-bottom:1.5px solid #333}\
tbody tr:nth-child(even){background:#f2f4f7}dl{display:grid;grid-template-columns:minmax(6em,max-content) 1fr;gap:0.15em 1em;font-size:0.9em}\
dt{font-weight:bold}dd{margin:0;overflow-wrap:anywhere}.warning{background:#fdf3e0;padding:0.5em 0.7em;border-left:4px solid #d55e00;margin:0.5em 0}\
p,li{overflow-wrap:break-word}";

fn text(t: &[Span]) -> String {
    t.iter()
        .map(|s| {
            let e = escape(&s.text);
            match (s.bold, s.code) {
                (true, true) => format!("<strong><code>{e}</code></strong>"),
                (true, false) => format!("<strong>{e}</strong>"),
                (false, true) => format!("<code>{e}</code>"),
                _ => e,
            }
        })
        .collect()
}

/// An SVG figure without its XML prologue, width and height (CSS sizes it), keeping its
/// viewBox; its physical width becomes the most it is drawn at.
fn inline_svg(svg: &str, stem: &str) -> Result<String> {
    let head = svg_head(svg)?;
    let attr = |name: &str| -> Option<String> {
        let k = head.find(&format!(" {name}=\""))? + name.len() + 3;
        let end = head[k..].find('"')?;
        Some(head[k..k + end].to_string())
    };
    let view = attr("viewBox").unwrap_or_default();
    let max = attr("width").unwrap_or_else(|| "100%".into());
    Ok(format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"{}\" role=\"img\" aria-label=\"{}\" style=\"--w:{}\">{}</svg>",
        escape(&view),
        escape(stem),
        escape(&max),
        svg_body(svg)?
    ))
}

fn block(out: &mut String, b: &Block, figure_no: &mut usize) -> Result<()> {
    match b {
        Block::Subheading(s) => out.push_str(&format!("<h3>{}</h3>\n", escape(s))),
        Block::Paragraph(t) => out.push_str(&format!("<p>{}</p>\n", text(t))),
        Block::Bullets(items) => {
            out.push_str("<ul>\n");
            for it in items {
                out.push_str(&format!("<li>{}</li>\n", text(it)));
            }
            out.push_str("</ul>\n");
        }
        Block::Table { header, rows } => {
            out.push_str("<div class=\"scroll\"><table>\n<thead><tr>");
            for h in header {
                out.push_str(&format!("<th>{}</th>", escape(h)));
            }
            out.push_str("</tr></thead>\n<tbody>\n");
            for r in rows {
                out.push_str("<tr>");
                for c in r {
                    out.push_str(&format!("<td>{}</td>", escape(c)));
                }
                out.push_str("</tr>\n");
            }
            out.push_str("</tbody></table></div>\n");
        }
        Block::KeyValues(kv) => {
            out.push_str("<dl>\n");
            for (k, v) in kv {
                out.push_str(&format!("<dt>{}</dt><dd>{}</dd>\n", escape(k), escape(v)));
            }
            out.push_str("</dl>\n");
        }
        Block::Figure { stem, svg, caption } => {
            *figure_no += 1;
            out.push_str(&format!(
                "<figure id=\"fig-{}\">\n{}\n<figcaption><strong>Figure {}.</strong> {}</figcaption>\n</figure>\n",
                escape(stem),
                inline_svg(svg, stem)?,
                figure_no,
                text(caption)
            ));
        }
        Block::Verbatim(t) => out.push_str(&format!("<pre>{}</pre>\n", escape(t))),
        Block::Warning(t) => out.push_str(&format!("<p class=\"warning\"><strong>Warning:</strong> {}</p>\n", text(t))),
    }
    Ok(())
}

/// The document as one HTML page.
pub fn render(doc: &Document) -> Result<String> {
    let mut out = String::new();
    out.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    out.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    out.push_str(&format!("<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n", escape(&doc.title)));
    out.push_str(&format!("<header><p><small>{}</small></p><h1 id=\"answer\">{}</h1></header>\n<main>\n", escape(&doc.running), escape(&doc.title)));
    let mut fig = 0;
    for b in &doc.first {
        block(&mut out, b, &mut fig)?;
    }
    out.push_str("<nav id=\"contents\"><h2>Contents</h2>\n<ol>\n");
    for s in &doc.sections {
        out.push_str(&format!("<li><a href=\"#{}\">{}</a></li>\n", escape(&s.anchor), escape(&s.heading)));
    }
    out.push_str("</ol></nav>\n");
    for s in &doc.sections {
        out.push_str(&format!("<section>\n<h2 id=\"{}\">{}</h2>\n", escape(&s.anchor), escape(&s.heading)));
        for b in &s.blocks {
            block(&mut out, b, &mut fig)?;
        }
        out.push_str("</section>\n");
    }
    out.push_str("</main>\n</body>\n</html>\n");
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figure_keeps_viewbox_and_drops_size() {
        let s = inline_svg("<?xml version=\"1.0\"?>\n<svg width=\"8.5cm\" height=\"6cm\" viewBox=\"0 0 10 7\" xmlns=\"http://www.w3.org/2000/svg\"><rect/></svg>", "f").unwrap();
        assert!(s.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 10 7\""));
        assert!(s.contains("--w:8.5cm") && !s.contains("height=") && s.ends_with("<rect/></svg>"));
    }
}

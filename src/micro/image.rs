//! A segmented micrograph (PNG) as a labelled pixel grid.
//!
//! The segmentation (ImageJ's Trainable WEKA Segmentation in the deliverable's Fig. 10, or any
//! other tool) is saved as a PNG, either as 8-bit labels (grey value k = class k, WEKA's
//! "Create result" with a grey look-up table) or as a colour overlay (one colour per class).
//! The study maps each value to a phase of its table:
//!
//! ```toml
//! image = { file = "../datasets/micro_bl1630_segmented.png", pixel_m = 0.1e-6 }
//! phases = { "#2ca02c" = "alumina", "#d62728" = "fused_silica" }   # colours, or
//! phases = { "0" = "alumina", "1" = "fused_silica" }               # grey values 0…255
//! ```
//!
//! Grey, grey + alpha, RGB, RGBA and palette PNGs of 1 to 16 bits per sample are read (pure
//! Rust, the `png` crate; 16-bit samples keep their high byte, alpha is ignored). A grey value
//! g matches the key `"g"` and the colour `#gggggg`. The image's top row is the microstructure's
//! highest row (y grows upwards in every table and figure).
//!
//! Refused with the file and the rule (exit 2): a file that is not a PNG; a pixel whose value the
//! map does not name (its position, counted from the image's top-left corner as image viewers
//! do, and how many such pixels there are); an image with fewer than two of the mapped phases; an
//! image smaller than 2 × 2 pixels.

use std::collections::BTreeMap;
use std::path::Path;

use super::structure::Microstructure;
use crate::error::{Error, Result};

/// A value → phase map key, parsed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Key {
    Grey(u8),
    Rgb([u8; 3]),
}

fn parse_key(k: &str) -> Option<Key> {
    if let Some(hex) = k.strip_prefix('#') {
        if hex.len() != 6 || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
            return None;
        }
        let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).ok();
        return Some(Key::Rgb([byte(0)?, byte(2)?, byte(4)?]));
    }
    k.parse::<u8>().ok().map(Key::Grey)
}

/// Checks a value → phase map's keys (`#rrggbb` or a grey value 0…255); `key` names it in the
/// study.
pub fn check_keys(file: &str, key: &str, map: &BTreeMap<String, String>) -> Result<()> {
    for k in map.keys() {
        if parse_key(k).is_none() {
            return Err(Error::config(file, format!("{key}.\"{k}\""), "an image value must be a colour \"#rrggbb\" or a grey value \"0\"…\"255\""));
        }
    }
    Ok(())
}

/// Reads a segmented PNG: label k of the result is `phases[k]`, the map's phase names in the
/// map's key order (a phase named by two keys appears once).
pub fn read_segmented(path: &Path, pixel_m: f64, map: &BTreeMap<String, String>) -> Result<(Microstructure, Vec<String>)> {
    let bytes = std::fs::read(path).map_err(|e| Error::read(path, e))?;
    let not_png = |e: png::DecodingError| Error::data_file(path, "file", format!("not a readable PNG image ({e})"));
    let mut decoder = png::Decoder::new(std::io::Cursor::new(&bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(not_png)?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).map_err(not_png)?;
    let (w, h) = (info.width as usize, info.height as usize);
    if w < 2 || h < 2 {
        return Err(Error::data_file(path, "file", format!("the image is {w} × {h} pixels: a microstructure needs at least 2 × 2")));
    }
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Err(Error::data_file(path, "file", "a palette image that could not be expanded to colours")),
    };
    let mut names: Vec<String> = Vec::new();
    let mut lookup: BTreeMap<Key, u8> = BTreeMap::new();
    for (k, name) in map {
        let key = parse_key(k).ok_or_else(|| Error::data_file(path, "phases", format!("the key \"{k}\" is neither \"#rrggbb\" nor a grey value 0…255")))?;
        let idx = match names.iter().position(|n| n == name) {
            Some(i) => i,
            None => {
                names.push(name.clone());
                names.len() - 1
            }
        };
        if idx > u8::MAX as usize {
            return Err(Error::data_file(path, "phases", "the map names more than 256 phases"));
        }
        lookup.insert(key, idx as u8);
    }
    let mut labels = vec![0u8; w * h];
    let (mut unmapped, mut first): (usize, Option<(usize, usize, String)>) = (0, None);
    let row_bytes = info.line_size;
    for row in 0..h {
        for col in 0..w {
            let p = &buf[row * row_bytes + col * channels..];
            let rgb = if channels < 3 { [p[0]; 3] } else { [p[0], p[1], p[2]] };
            let hit = lookup.get(&Key::Rgb(rgb)).or_else(|| (rgb[0] == rgb[1] && rgb[1] == rgb[2]).then(|| lookup.get(&Key::Grey(rgb[0]))).flatten());
            match hit {
                Some(&l) => labels[(h - 1 - row) * w + col] = l,
                None => {
                    unmapped += 1;
                    if first.is_none() {
                        let v = if rgb[0] == rgb[1] && rgb[1] == rgb[2] { format!("grey value {} (#{:02x}{:02x}{:02x})", rgb[0], rgb[0], rgb[1], rgb[2]) } else { format!("colour #{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2]) };
                        first = Some((col, row, v));
                    }
                }
            }
        }
    }
    if let Some((x, y, v)) = first {
        return Err(Error::data_file(
            path,
            format!("pixel x = {x}, y = {y} (from the top-left)"),
            format!("{v} is not in the study's phase map ({}); {unmapped} of {} pixels are unmapped", map.keys().cloned().collect::<Vec<_>>().join(", "), w * h),
        ));
    }
    let m = Microstructure::new(w, h, pixel_m, labels)?;
    let present = (0..names.len()).filter(|&k| m.labels.contains(&(k as u8))).count();
    if present < 2 {
        return Err(Error::data_file(path, "file", format!("only {present} of the mapped phases ({}) appear in the image: a two-phase microstructure needs at least two", names.join(", "))));
    }
    Ok((m, names))
}

/// Writes a labelled grid as an RGB PNG, label k in `colours[k]` (top row = highest row).
pub fn write_png(m: &Microstructure, colours: &[[u8; 3]]) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, m.nx as u32, m.ny as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_compression(png::Compression::Best);
        let mut w = enc.write_header().map_err(|e| Error::numerical("png", e.to_string()))?;
        let mut data = Vec::with_capacity(3 * m.nx * m.ny);
        for row in 0..m.ny {
            for col in 0..m.nx {
                let l = m.labels[(m.ny - 1 - row) * m.nx + col] as usize;
                data.extend_from_slice(colours.get(l).ok_or_else(|| Error::numerical("png", format!("no colour for label {l}")))?);
            }
        }
        w.write_image_data(&data).map_err(|e| Error::numerical("png", e.to_string()))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_image_reads_back_with_its_colours_and_orientation() {
        let labels: Vec<u8> = (0..12).map(|p| u8::from(p % 4 == 0 || p >= 8)).collect();
        let m = Microstructure::new(4, 3, 1e-6, labels).unwrap();
        let png = write_png(&m, &[[44, 160, 44], [214, 39, 40]]).unwrap();
        let dir = crate::io::TempDir::new("png").unwrap();
        let path = dir.path().join("m.png");
        std::fs::write(&path, &png).unwrap();
        let map: BTreeMap<String, String> = [("#2ca02c".into(), "alumina".into()), ("#d62728".into(), "fused_silica".into())].into();
        let (back, names) = read_segmented(&path, 1e-6, &map).unwrap();
        assert_eq!(names, ["alumina", "fused_silica"]);
        assert_eq!(back, m);
        // A colour the map lacks: named with its position from the top-left.
        let map: BTreeMap<String, String> = [("#2ca02c".into(), "alumina".into())].into();
        let msg = read_segmented(&path, 1e-6, &map).unwrap_err().to_string();
        assert!(msg.contains("m.png") && msg.contains("#d62728") && msg.contains("x = 0, y = 0") && msg.contains("6 of 12"), "{msg}");
        // Not a PNG.
        std::fs::write(&path, b"P5 not a png").unwrap();
        assert!(read_segmented(&path, 1e-6, &map).unwrap_err().to_string().contains("not a readable PNG"));
    }
}

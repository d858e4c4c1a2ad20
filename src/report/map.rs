//! A colour-map figure shared by the DEM speed map, the crush strain maps and the microstructure
//! maps: an equal-aspect plot area (left 80 % of the canvas) whose content the caller draws, and
//! a colour bar — continuous, or one block per category (a phase map).

use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::canvas::{Encoded, canvas_size, check_glyphs, encode, fig_err, register_fonts, text, tick_format};
use super::panel::pt;
use crate::error::Result;

/// The chart the caller draws its cells into (data coordinates).
pub type MapChart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Axes and colour bar of a map.
pub struct MapSpec<'a> {
    /// Figure name (errors, glyph check).
    pub name: &'a str,
    /// Figure width (cm).
    pub width_cm: f64,
    /// x range and label.
    pub x: (f64, f64, &'a str),
    /// y range and label.
    pub y: (f64, f64, &'a str),
    /// Tick-label counts (x, y).
    pub labels: (usize, usize),
    /// Colour-bar range and label.
    pub bar: (f64, f64, &'a str),
    /// Colour of a data value.
    pub colour: &'a dyn Fn(f64) -> RGBColor,
    /// Categories instead of a continuous bar (a phase map): each gets an equal block of the bar
    /// in its colour with its name written along it; `bar` and `colour` are then not drawn.
    pub categories: Option<&'a [(String, RGBColor)]>,
}

/// Draws the map: `cells` fills the plot area, then the colour bar is added.
pub fn map_figure(m: &MapSpec, cells: impl FnOnce(&mut MapChart) -> Result<()>) -> Result<(Encoded, usize)> {
    let ((x0, x1, x_desc), (y0, y1, y_desc), (b0, b1, bar_desc)) = (m.x, m.y, m.bar);
    for t in [x_desc, y_desc, bar_desc] {
        check_glyphs(m.name, t)?;
    }
    register_fonts()?;
    // Equal data aspect: the plotting area (left 80 % less margins and label areas) gets the
    // window's height/width ratio.
    let w_px = canvas_size(m.width_cm, 1.0).0 as f64;
    let plot_w = 0.8 * w_px - pt(33.0) as f64;
    let h_px = plot_w * (y1 - y0) / (x1 - x0) + pt(27.0) as f64;
    let size = canvas_size(m.width_cm, h_px / w_px);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        let err = fig_err(m.name);
        root.fill(&WHITE).map_err(&err)?;
        let (left, right) = root.split_horizontally((size.0 as f64 * 0.80) as u32);
        let mut chart = ChartBuilder::on(&left)
            .margin_top(pt(6.0))
            .margin_right(pt(4.0))
            .margin_left(pt(2.0))
            .margin_bottom(pt(2.0))
            .x_label_area_size(pt(19.0))
            .y_label_area_size(pt(27.0))
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(&err)?;
        let (xf, yf) = (tick_format(x0, x1, m.labels.0), tick_format(y0, y1, m.labels.1));
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .label_style(text(7.0))
            .axis_desc_style(text(8.0))
            .x_labels(m.labels.0)
            .y_labels(m.labels.1)
            .x_label_formatter(&xf)
            .y_label_formatter(&yf)
            .disable_mesh()
            .axis_style(BLACK.stroke_width(pt(0.5)))
            .draw()
            .map_err(&err)?;
        cells(&mut chart)?;
        if let Some(cats) = m.categories {
            for (c, _) in cats {
                check_glyphs(m.name, c)?;
            }
            let n = cats.len().max(1) as f64;
            let bar = ChartBuilder::on(&right)
                .margin_top(pt(6.0))
                .margin_right(pt(2.0))
                .margin_left(pt(4.0))
                .margin_bottom(pt(2.0))
                .x_label_area_size(pt(19.0))
                .build_cartesian_2d(0.0..1.0, 0.0..n)
                .map_err(&err)?;
            // Each name reads bottom to top along its block.
            let style = text(7.0).transform(FontTransform::Rotate270).pos(Pos::new(HPos::Center, VPos::Center));
            for (k, (name, c)) in cats.iter().enumerate() {
                let (a, b) = (k as f64, k as f64 + 1.0);
                bar.plotting_area().draw(&Rectangle::new([(0.0, a), (1.0, b)], c.filled())).map_err(&err)?;
                bar.plotting_area().draw(&Rectangle::new([(0.0, a), (1.0, b)], BLACK.stroke_width(pt(0.5)))).map_err(&err)?;
                let ink = if (c.0 as f64 * 0.299 + c.1 as f64 * 0.587 + c.2 as f64 * 0.114) < 140.0 { WHITE } else { BLACK };
                bar.plotting_area().draw(&Text::new(name.clone(), (0.5, 0.5 * (a + b)), style.color(&ink))).map_err(&err)?;
            }
        } else {
            let mut bar = ChartBuilder::on(&right)
                .margin_top(pt(6.0))
                .margin_right(pt(2.0))
                .margin_left(pt(4.0))
                .margin_bottom(pt(2.0))
                .x_label_area_size(pt(19.0))
                .y_label_area_size(pt(0.0))
                .right_y_label_area_size(pt(31.0))
                .build_cartesian_2d(0.0..1.0, b0..b1)
                .map_err(&err)?
                .set_secondary_coord(0.0..1.0, b0..b1);
            bar.draw_series((0..100).map(|k| {
                let (a, b) = (b0 + (b1 - b0) * k as f64 / 100.0, b0 + (b1 - b0) * (k + 1) as f64 / 100.0);
                Rectangle::new([(0.0, a), (1.0, b)], (m.colour)(0.5 * (a + b)).filled())
            }))
            .map_err(&err)?;
            let bf = tick_format(b0, b1, 5);
            bar.configure_secondary_axes()
                .y_desc(bar_desc)
                .label_style(text(7.0))
                .axis_desc_style(text(7.0))
                .y_labels(5)
                .y_label_formatter(&bf)
                .x_labels(0)
                .axis_style(BLACK.stroke_width(pt(0.5)))
                .draw()
                .map_err(&err)?;
        }
        root.present().map_err(&err)?;
    }
    Ok((encode(m.name, &svg, size, m.width_cm)?, 0))
}

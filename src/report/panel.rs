//! A small declarative layer over plotters: a figure is a stack of panels, a panel is a list
//! of series (lines, dashed lines, markers, bands, segments) with axis labels and a legend
//! position. Logarithmic axes are drawn as linear axes of log10 values with "10ⁿ" labels, which
//! keeps one code path for every panel.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::canvas::{Encoded, FONT, canvas_size, check_glyphs, encode, fig_err, font_size, power_of_ten, register_fonts, text, tick_format};
use crate::error::Result;

/// Marker shapes (distinct in grey-scale print).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Filled circle.
    Circle,
    /// Filled triangle.
    Triangle,
    /// Diagonal cross.
    Cross,
    /// Open circle: a specimen that did not break by its value, or broke within a class
    /// (censored).
    Ring,
}

/// How a series is drawn.
#[derive(Debug, Clone, PartialEq)]
pub enum Kind {
    /// Solid line of a width in points.
    Line(f64),
    /// Dashed line: width, dash and gap in points.
    Dashed(f64, f64, f64),
    /// Markers of a size in points (radius).
    Markers(Marker, f64),
    /// Shaded band between `points` (lower) and these upper values, with an opacity.
    Band(Vec<f64>, f64),
}

/// One series.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry (none: not in the legend).
    pub label: Option<String>,
    /// (x, y) in data units (y as log10 when the panel is logarithmic: use [`Panel::y_log`]).
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub colour: RGBColor,
    /// Drawing kind.
    pub kind: Kind,
}

impl Series {
    /// A solid line.
    pub fn line(label: Option<String>, points: Vec<(f64, f64)>, colour: RGBColor, width_pt: f64) -> Self {
        Series { label, points, colour, kind: Kind::Line(width_pt) }
    }
}

/// One panel of a figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Names of categories at x = 1, 2, …: the x-axis then labels only those positions with
    /// their names (empty: a numeric axis).
    pub x_categories: Vec<String>,
    /// x-axis label with unit.
    pub x_desc: String,
    /// y-axis label with unit.
    pub y_desc: String,
    /// x range.
    pub x_range: (f64, f64),
    /// y range (log10 values when `y_log`).
    pub y_range: (f64, f64),
    /// Logarithmic y axis: y values are log10 and labels read 10ⁿ.
    pub y_log: bool,
    /// Series, drawn in order.
    pub series: Vec<Series>,
    /// Preferred legend corner (none: no legend). The legend goes to the first corner, in the
    /// order preferred, upper right, upper left, lower right, lower left, where it hides no
    /// data; if every corner hides some, to the one hiding the fewest points.
    pub legend: Option<SeriesLabelPosition>,
}

/// The parts of polyline `points` inside the rectangle `x` × `y` (Liang–Barsky per segment;
/// consecutive visible segments joined), each a polyline of its own.
pub fn clip_polyline(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut open = false;
    for w in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        let (dx, dy) = (x1 - x0, y1 - y0);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let mut visible = true;
        for (p, q) in [(-dx, x0 - x.0), (dx, x.1 - x0), (-dy, y0 - y.0), (dy, y.1 - y0)] {
            if p == 0.0 {
                visible &= q >= 0.0;
            } else if p < 0.0 {
                t0 = t0.max(q / p);
            } else {
                t1 = t1.min(q / p);
            }
        }
        if !visible || t0 > t1 || !(t0.is_finite() && t1.is_finite()) {
            open = false;
            continue;
        }
        let (a, b) = ((x0 + t0 * dx, y0 + t0 * dy), (x0 + t1 * dx, y0 + t1 * dy));
        if open && t0 == 0.0 {
            out.last_mut().expect("an open piece").push(b);
        } else {
            out.push(vec![a, b]);
        }
        open = t1 == 1.0;
    }
    if points.len() == 1 && points[0].0 >= x.0 && points[0].0 <= x.1 && points[0].1 >= y.0 && points[0].1 <= y.1 {
        out.push(points.to_vec());
    }
    out
}

/// Range of values padded by a fraction on each side (and never empty).
pub fn padded(values: impl IntoIterator<Item = f64>, lo_frac: f64, hi_frac: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.into_iter().filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi <= lo {
        hi = lo + 1.0;
    }
    let span = hi - lo;
    (lo - lo_frac * span, hi + hi_frac * span)
}

/// Points to pixels.
pub fn pt(v: f64) -> u32 {
    (v * super::canvas::PX_PER_PT).round().max(1.0) as u32
}

/// Legend entry font size (pt), margin (pt) and sample width (pt).
const LEGEND_PT: f64 = 6.5;
const LEGEND_MARGIN_PT: f64 = 3.0;
const LEGEND_SAMPLE_PT: f64 = 16.0;

/// Pixel rectangle (x0, y0, x1, y1), absolute backend coordinates.
type Rect = (i32, i32, i32, i32);

fn corner_rect(pos: &SeriesLabelPosition, size: (i32, i32), area_base: (i32, i32), area_dim: (u32, u32)) -> Rect {
    use SeriesLabelPosition::*;
    // As plotters' `layout_label_area`: 5 px from the plotting-area edges.
    let x = match pos {
        UpperLeft | MiddleLeft | LowerLeft => 5,
        UpperMiddle | MiddleMiddle | LowerMiddle => (area_dim.0 as i32 - size.0) / 2,
        _ => area_dim.0 as i32 - size.0 - 5,
    };
    let y = match pos {
        UpperLeft | UpperMiddle | UpperRight => 5,
        MiddleLeft | MiddleMiddle | MiddleRight => (area_dim.1 as i32 - size.1) / 2,
        _ => area_dim.1 as i32 - size.1 - 5,
    };
    (area_base.0 + x, area_base.1 + y, area_base.0 + x + size.0, area_base.1 + y + size.1)
}

/// Number of drawn data samples (points, line samples, band samples) inside a rectangle.
fn hidden_samples(p: &Panel, rect: Rect, to_px: &dyn Fn((f64, f64)) -> (i32, i32)) -> usize {
    let inside = |q: (i32, i32), pad: i32| q.0 >= rect.0 - pad && q.0 <= rect.2 + pad && q.1 >= rect.1 - pad && q.1 <= rect.3 + pad;
    let mut n = 0;
    for s in &p.series {
        match &s.kind {
            Kind::Markers(_, size) => n += s.points.iter().filter(|&&q| inside(to_px(q), pt(*size) as i32)).count(),
            Kind::Line(w) | Kind::Dashed(w, _, _) => {
                // Sample each segment so that a segment crossing the box is caught.
                for win in s.points.windows(2) {
                    n += (0..=16)
                        .map(|k| {
                            let t = k as f64 / 16.0;
                            (win[0].0 + t * (win[1].0 - win[0].0), win[0].1 + t * (win[1].1 - win[0].1))
                        })
                        .filter(|&q| inside(to_px(q), pt(*w) as i32))
                        .count();
                }
                if s.points.len() == 1 {
                    n += inside(to_px(s.points[0]), pt(*w) as i32) as usize;
                }
            }
            Kind::Band(upper, _) => {
                for (&(x, lo), &hi) in s.points.iter().zip(upper) {
                    n += (0..=8).filter(|k| inside(to_px((x, lo + (hi - lo) * *k as f64 / 8.0)), 0)).count();
                }
            }
        }
    }
    n
}

fn draw_panel(area: &DrawingArea<SVGBackend<'_>, Shift>, p: &Panel, name: &str) -> Result<usize> {
    let err = fig_err(name);
    check_glyphs(name, &p.x_desc)?;
    check_glyphs(name, &p.y_desc)?;
    for l in p.series.iter().filter_map(|s| s.label.as_ref()) {
        check_glyphs(name, l)?;
    }
    let mut chart = ChartBuilder::on(area)
        .margin_top(pt(6.0))
        .margin_right(pt(8.0))
        .margin_left(pt(2.0))
        .margin_bottom(pt(2.0))
        .x_label_area_size(pt(19.0))
        .y_label_area_size(pt(31.0))
        .build_cartesian_2d(p.x_range.0..p.x_range.1, p.y_range.0..p.y_range.1)
        .map_err(&err)?;
    let xf_num = tick_format(p.x_range.0, p.x_range.1, 6);
    let xf = |v: &f64| {
        if p.x_categories.is_empty() {
            return xf_num(v);
        }
        let k = v.round();
        if (v - k).abs() < 1e-9 && k >= 1.0 { p.x_categories.get(k as usize - 1).cloned().unwrap_or_default() } else { String::new() }
    };
    let yf_lin = tick_format(p.y_range.0, p.y_range.1, 6);
    let yf = |v: &f64| if p.y_log { power_of_ten(&10f64.powf(*v)) } else { yf_lin(v) };
    let span = (p.y_range.1 - p.y_range.0).round() as usize;
    let y_labels = if p.y_log { if span <= 8 { span + 1 } else { span / 2 + 1 } } else { 6 };
    chart
        .configure_mesh()
        .x_desc(p.x_desc.as_str())
        .y_desc(p.y_desc.as_str())
        .label_style(text(7.0))
        .axis_desc_style(text(8.0))
        .x_labels(if p.x_categories.is_empty() { 6 } else { p.x_categories.len() + 2 })
        .y_labels(y_labels)
        .x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .bold_line_style(RGBColor(222, 222, 222).stroke_width(pt(0.4)))
        .light_line_style(TRANSPARENT)
        .axis_style(BLACK.stroke_width(pt(0.5)))
        .draw()
        .map_err(&err)?;
    for s in &p.series {
        let c = s.colour;
        match &s.kind {
            Kind::Line(w) => {
                let style = c.stroke_width(pt(*w));
                // Clipped to the axes as lines, so that a line leaving them keeps its slope
                // (coordinates clamped one by one would bend it).
                let pieces = clip_polyline(&s.points, p.x_range, p.y_range);
                for piece in pieces.iter().skip(1) {
                    chart.draw_series(LineSeries::new(piece.iter().cloned(), style)).map_err(&err)?;
                }
                // The first piece carries the legend entry (an empty one when nothing shows).
                let a = chart.draw_series(LineSeries::new(pieces.first().cloned().unwrap_or_default(), style)).map_err(&err)?;
                if let Some(l) = &s.label {
                    a.label(l.as_str()).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + pt(12.0) as i32, y)], style));
                }
            }
            Kind::Dashed(w, dash, gap) => {
                let style = c.stroke_width(pt(*w));
                let a = chart
                    .draw_series(DashedLineSeries::new(s.points.iter().cloned(), pt(*dash), pt(*gap), style))
                    .map_err(&err)?;
                if let Some(l) = &s.label {
                    let (dash, gap) = (pt(*dash) as i32, pt(*gap) as i32);
                    a.label(l.as_str()).legend(move |(x, y)| {
                        // Composed legend elements use coordinates relative to the anchor.
                        // Three periods of the pattern, clipped to the 12 pt legend sample.
                        let end = pt(12.0) as i32;
                        let seg = |k: i32| {
                            let x0 = (k * (dash + gap)).min(end);
                            PathElement::new(vec![(x0, 0), ((x0 + dash).min(end), 0)], style)
                        };
                        EmptyElement::at((x, y)) + seg(0) + seg(1) + seg(2)
                    });
                }
            }
            Kind::Markers(m, size) => {
                let r = pt(*size) as i32;
                let filled = c.filled();
                let open = c.stroke_width(pt(0.6));
                let m = *m;
                let a = chart
                    .draw_series(s.points.iter().map(move |&(x, y)| marker((x, y), m, r, filled, open)))
                    .map_err(&err)?;
                if let Some(l) = &s.label {
                    let off = pt(6.0) as i32;
                    a.label(l.as_str()).legend(move |(x, y)| marker((x + off, y), m, r, filled, open));
                }
            }
            Kind::Band(upper, opacity) => {
                let mut poly: Vec<(f64, f64)> = s.points.clone();
                poly.extend(s.points.iter().zip(upper).rev().map(|(&(x, _), &u)| (x, u)));
                let style = c.mix(*opacity).filled();
                let shapes = (!poly.is_empty()).then(|| Polygon::new(poly, style));
                let a = chart.draw_series(shapes).map_err(&err)?;
                if let Some(l) = &s.label {
                    let w = pt(12.0) as i32;
                    let h = pt(3.0) as i32;
                    a.label(l.as_str()).legend(move |(x, y)| Rectangle::new([(x, y - h), (x + w, y + h)], style));
                }
            }
        }
    }
    let labels: Vec<&str> = p.series.iter().filter_map(|s| s.label.as_deref()).collect();
    let mut hidden = 0;
    if let (Some(pref), false) = (&p.legend, labels.is_empty()) {
        // The legend box exactly as plotters lays it out.
        let font = (FONT, font_size(LEGEND_PT)).into_font();
        let mut w = 0i32;
        let mut last_h = 0i32;
        for l in &labels {
            let (dx, dy) = font.box_size(l).map_err(fig_err(name))?;
            w = w.max(dx as i32);
            last_h = dy as i32;
        }
        let m = pt(LEGEND_MARGIN_PT) as i32;
        let h = ((labels.len() - 1) as f64 * 1.25 * font.get_size()).round() as i32 + last_h + 2 * m;
        let size = (w + pt(LEGEND_SAMPLE_PT) as i32 + 2 * m, h);
        let pa = chart.plotting_area();
        let (base, dim) = (pa.get_base_pixel(), pa.dim_in_pixel());
        let to_px = |q: (f64, f64)| chart.backend_coord(&q);
        use SeriesLabelPosition::*;
        let mut order = vec![pref.clone()];
        order.extend([UpperRight, UpperLeft, LowerRight, LowerLeft].into_iter().filter(|c| c != pref));
        let counts: Vec<usize> = order.iter().map(|c| hidden_samples(p, corner_rect(c, size, base, dim), &to_px)).collect();
        let best = counts.iter().position(|&c| c == 0).unwrap_or_else(|| {
            (0..counts.len()).min_by_key(|&i| counts[i]).unwrap_or(0)
        });
        hidden = counts[best];
        chart
            .configure_series_labels()
            .position(order[best].clone())
            .margin(pt(LEGEND_MARGIN_PT))
            .legend_area_size(pt(LEGEND_SAMPLE_PT))
            .label_font((FONT, font_size(LEGEND_PT)))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160).stroke_width(1))
            .draw()
            .map_err(&err)?;
    }
    Ok(hidden)
}

/// A marker element at a data or backend coordinate.
fn marker<'a, C: Clone + 'static>(
    at: C,
    m: Marker,
    r: i32,
    filled: ShapeStyle,
    open: ShapeStyle,
) -> DynElement<'static, SVGBackend<'a>, C>
where
    Circle<C, i32>: IntoDynElement<'static, SVGBackend<'a>, C>,
    TriangleMarker<C, i32>: IntoDynElement<'static, SVGBackend<'a>, C>,
    Cross<C, i32>: IntoDynElement<'static, SVGBackend<'a>, C>,
{
    match m {
        Marker::Circle => Circle::new(at, r, filled).into_dyn(),
        Marker::Triangle => TriangleMarker::new(at, r * 13 / 10, filled).into_dyn(),
        Marker::Cross => Cross::new(at, r, open).into_dyn(),
        Marker::Ring => Circle::new(at, r, open).into_dyn(),
    }
}

/// Draws a figure of stacked panels (heights as fractions of the whole) and encodes it; also
/// returns the number of data samples the legends hide (0 unless no corner was free).
pub fn figure(name: &str, width_cm: f64, aspect: f64, panels: &[(Panel, f64)]) -> Result<(Encoded, usize)> {
    register_fonts()?;
    let size = canvas_size(width_cm, aspect);
    let mut svg = String::new();
    let mut hidden = 0;
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(fig_err(name))?;
        let mut rest = root.clone();
        for (i, (panel, frac)) in panels.iter().enumerate() {
            let area = if i + 1 == panels.len() {
                rest.clone()
            } else {
                let (top, bottom) = rest.split_vertically((size.1 as f64 * frac).round() as u32);
                rest = bottom;
                top
            };
            hidden += draw_panel(&area, panel, name)?;
        }
        root.present().map_err(fig_err(name))?;
    }
    Ok((encode(name, &svg, size, width_cm)?, hidden))
}

/// Draws a figure of panels on a grid of `cols` columns (row-major; `None` leaves a cell
/// blank, as above the diagonal of a corner plot) and encodes it; returns the hidden-sample
/// count as [`figure`].
pub fn figure_grid(name: &str, width_cm: f64, aspect: f64, cols: usize, panels: &[Option<Panel>]) -> Result<(Encoded, usize)> {
    register_fonts()?;
    let size = canvas_size(width_cm, aspect);
    let rows = panels.len().div_ceil(cols.max(1));
    let mut svg = String::new();
    let mut hidden = 0;
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(fig_err(name))?;
        for (area, panel) in root.split_evenly((rows, cols.max(1))).iter().zip(panels) {
            if let Some(p) = panel {
                hidden += draw_panel(area, p, name)?;
            }
        }
        root.present().map_err(fig_err(name))?;
    }
    Ok((encode(name, &svg, size, width_cm)?, hidden))
}

/// Draws stacked panels (heights as fractions of the panel part, as [`figure`]) above a legend
/// strip that lists `entries` (their labels, colours and kinds; points unused) in `cols`
/// columns, so that a legend with many entries hides no data. Returns the hidden-sample count of
/// the panels' own legends.
pub fn figure_legend_below(name: &str, width_cm: f64, aspect: f64, panels: &[(Panel, f64)], entries: &[Series], cols: usize) -> Result<(Encoded, usize)> {
    register_fonts()?;
    let size = canvas_size(width_cm, aspect);
    let cols = cols.max(1);
    let rows = entries.len().div_ceil(cols);
    let line_px = (1.35 * font_size(LEGEND_PT)).round() as i32;
    let strip = (rows as i32 * line_px + 2 * pt(LEGEND_MARGIN_PT) as i32) as u32;
    let mut svg = String::new();
    let mut hidden = 0;
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        let err = fig_err(name);
        root.fill(&WHITE).map_err(&err)?;
        let (top, bottom) = root.split_vertically(size.1.saturating_sub(strip));
        let mut rest = top.clone();
        let h = size.1.saturating_sub(strip) as f64;
        for (i, (panel, frac)) in panels.iter().enumerate() {
            let area = if i + 1 == panels.len() {
                rest.clone()
            } else {
                let (a, b) = rest.split_vertically((h * frac).round() as u32);
                rest = b;
                a
            };
            hidden += draw_panel(&area, panel, name)?;
        }
        let font = (FONT, font_size(LEGEND_PT)).into_font().color(&BLACK);
        let (w, _) = bottom.dim_in_pixel();
        let col_w = (w as i32 - pt(8.0) as i32) / cols as i32;
        let sample = pt(12.0) as i32;
        for (k, e) in entries.iter().enumerate() {
            let label = e.label.clone().unwrap_or_default();
            check_glyphs(name, &label)?;
            let (c, r) = ((k % cols) as i32, (k / cols) as i32);
            let x = pt(8.0) as i32 + c * col_w;
            let y = pt(LEGEND_MARGIN_PT) as i32 + r * line_px + line_px / 2;
            let colour = e.colour;
            match &e.kind {
                Kind::Line(wd) => bottom.draw(&PathElement::new(vec![(x, y), (x + sample, y)], colour.stroke_width(pt(*wd)))).map_err(&err)?,
                Kind::Dashed(wd, dash, gap) => {
                    let (dash, gap) = (pt(*dash) as i32, pt(*gap) as i32);
                    let mut x0 = x;
                    while x0 < x + sample {
                        bottom.draw(&PathElement::new(vec![(x0, y), ((x0 + dash).min(x + sample), y)], colour.stroke_width(pt(*wd)))).map_err(&err)?;
                        x0 += dash + gap;
                    }
                }
                Kind::Markers(m, s) => bottom.draw(&marker((x + sample / 2, y), *m, pt(*s) as i32, colour.filled(), colour.stroke_width(pt(0.6)))).map_err(&err)?,
                Kind::Band(_, opacity) => bottom.draw(&Rectangle::new([(x, y - pt(3.0) as i32), (x + sample, y + pt(3.0) as i32)], colour.mix(*opacity).filled())).map_err(&err)?,
            }
            bottom.draw(&Text::new(label, (x + sample + pt(3.0) as i32, y - line_px / 3), font.clone())).map_err(&err)?;
        }
        root.present().map_err(&err)?;
    }
    Ok((encode(name, &svg, size, width_cm)?, hidden))
}

#[cfg(test)]
mod clip_tests {
    use super::clip_polyline;

    #[test]
    fn a_clipped_line_keeps_its_slope() {
        // Slope 38 from (−1, −38) to (2, 76) through the box [0, 1] × [−10, 10]: it enters at
        // the left edge (0, 0) and leaves at the top (10/38, 10).
        let pieces = clip_polyline(&[(-1.0, -38.0), (2.0, 76.0)], (0.0, 1.0), (-10.0, 10.0));
        assert_eq!(pieces.len(), 1);
        let [(xa, ya), (xb, yb)] = pieces[0][..] else { panic!("{pieces:?}") };
        assert!(((yb - ya) / (xb - xa) - 38.0).abs() < 1e-9 && xa.abs() < 1e-12 && ya.abs() < 1e-9 && (yb - 10.0).abs() < 1e-9, "{pieces:?}");
        // Inside: unchanged and joined; leaving and coming back: two pieces; outside: none.
        assert_eq!(clip_polyline(&[(0.1, 0.0), (0.5, 1.0), (0.9, 0.0)], (0.0, 1.0), (-1.0, 2.0)), vec![vec![(0.1, 0.0), (0.5, 1.0), (0.9, 0.0)]]);
        assert_eq!(clip_polyline(&[(0.1, 0.0), (0.5, 5.0), (0.9, 0.0)], (0.0, 1.0), (-1.0, 2.0)).len(), 2);
        assert!(clip_polyline(&[(2.0, 0.0), (3.0, 0.0)], (0.0, 1.0), (-1.0, 2.0)).is_empty());
    }
}

//! Figures: the one plotting layer every figure of the tool goes through (`plot`,
//! margins, diagnose). Charts are drawn with `plotters` into SVG; PNG is that SVG
//! rendered by `resvg` with the embedded DejaVu Sans, so no system font, GUI or C
//! library is needed and the SVG and the PNG show the same figure. Annotations (the
//! legend, the smallest backlash, the verdict) are placed by [`labels::Placer`], which
//! measures text with the same font and never puts two labels on top of each other;
//! every [`Figure`] keeps the boxes it placed, so tests can check them.
//!
//! Pure: the figures are strings and bytes; the CLI writes them.

pub mod diagnose;
pub mod drawn;
pub mod faces;
mod fine;
pub mod labels;
pub mod margins;
pub mod orbit;
pub mod outline;
pub mod overview;
mod panels;
pub mod run;

use std::sync::OnceLock;

pub use labels::{Placer, Rect};

/// DejaVu Sans (Bitstream Vera licence: `assets/fonts/LICENSE-DejaVu.txt`).
pub const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// The family the SVG names (plotters writes `sans-serif`; the PNG maps it to DejaVu).
pub const FAMILY: &str = "sans-serif";

#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("drawing the figure: {0}")]
    Draw(String),
    #[error("rendering the figure as PNG: {0}")]
    Png(String),
    #[error("{0}")]
    Data(String),
}

pub(crate) fn draw_err<E: std::fmt::Debug>(e: E) -> PlotError {
    PlotError::Draw(format!("{e:?}"))
}

/// A text label as placed on a figure, in pixels (y down).
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    pub text: String,
    pub rect: Rect,
}

/// A drawn figure: its SVG and the labels it placed.
#[derive(Debug, Clone)]
pub struct Figure {
    /// The figure with its labels as `<text>` (what the tests read the labels back
    /// from); the file written is [`Figure::svg_file`].
    pub svg: String,
    pub width: u32,
    pub height: u32,
    pub labels: Vec<Label>,
}

impl Figure {
    /// The figure drawn: `svg` as plotters wrote it (its curves still placeholders,
    /// spliced in here), `width` × `height` px, and the labels placed on it.
    pub(crate) fn new(svg: String, width: u32, height: u32, labels: Vec<Label>) -> Figure {
        Figure {
            svg: fine::splice(svg),
            width,
            height,
            labels,
        }
    }

    /// The SVG to write: the figure with its text as outlines of the embedded font,
    /// so it looks the same everywhere ([`outline::outline_text`]).
    pub fn svg_file(&self) -> String {
        outline::outline_text(&self.svg)
    }

    /// The figure as PNG at `scale` × its size (2 for a sharp figure on a screen).
    pub fn png(&self, scale: f32) -> Result<Vec<u8>, PlotError> {
        use resvg::{tiny_skia, usvg};
        let mut opt = usvg::Options::default();
        {
            let db = opt.fontdb_mut();
            db.load_font_data(FONT.to_vec());
            db.set_sans_serif_family("DejaVu Sans");
        }
        let tree = usvg::Tree::from_str(&self.svg_file(), &opt)
            .map_err(|e| PlotError::Png(e.to_string()))?;
        let (w, h) = (
            (self.width as f32 * scale).ceil() as u32,
            (self.height as f32 * scale).ceil() as u32,
        );
        let mut pixmap =
            tiny_skia::Pixmap::new(w, h).ok_or_else(|| PlotError::Png(format!("{w}×{h} px")))?;
        pixmap.fill(tiny_skia::Color::WHITE);
        resvg::render(
            &tree,
            tiny_skia::Transform::from_scale(scale, scale),
            &mut pixmap.as_mut(),
        );
        pixmap
            .encode_png()
            .map_err(|e| PlotError::Png(e.to_string()))
    }

    /// Pairs of labels whose boxes overlap (none, on a figure drawn right).
    pub fn overlapping_labels(&self) -> Vec<(String, String)> {
        let mut out = Vec::new();
        for (i, a) in self.labels.iter().enumerate() {
            for b in &self.labels[i + 1..] {
                if a.rect.intersects(&b.rect) {
                    out.push((a.text.clone(), b.text.clone()));
                }
            }
        }
        out
    }

    /// What is wrong with the labels as the SVG draws them (their boxes measured at the
    /// font size written into the file): a label not found among the drawn texts, two
    /// labels that overlap, a label off the page, a drawn line (a curve, a reference
    /// line, an axis) through a label. Empty on a figure drawn right.
    pub fn drawn_problems(&self) -> Vec<String> {
        let (texts, lines) = drawn::read(&self.svg);
        let mut used = vec![false; texts.len()];
        let mut boxes: Vec<(&str, Rect)> = Vec::new();
        let mut out = Vec::new();
        let mut kept: Vec<(&str, Rect)> = Vec::new();
        for l in &self.labels {
            match texts
                .iter()
                .enumerate()
                .find(|(i, t)| !used[*i] && t.text == l.text)
            {
                Some((i, t)) => {
                    used[i] = true;
                    boxes.push((&l.text, t.rect));
                    kept.push((&l.text, l.rect));
                }
                None => out.push(format!("{:?} is not drawn as one text", l.text)),
            }
        }
        let page = Rect::new(0.0, 0.0, self.width as f64, self.height as f64);
        for (i, (a, ra)) in boxes.iter().enumerate() {
            if !page.contains(ra) {
                out.push(format!("{a:?} leaves the page"));
            }
            for (b, rb) in &boxes[i + 1..] {
                if ra.intersects(rb) {
                    out.push(format!("{a:?} overlaps {b:?}"));
                }
            }
            // the text as drawn, and the box the label was given (a boxed label's
            // white background is drawn there)
            let given = kept[i].1;
            for (what, r) in [("", ra), (" (its box)", &given)] {
                let crossing = lines
                    .iter()
                    .find(|p| p.windows(2).any(|w| drawn::segment_crosses(w[0], w[1], r)));
                if let Some(p) = crossing {
                    out.push(format!(
                        "a line through {a:?}{what} (from {:?} to {:?})",
                        p[0],
                        p[p.len() - 1]
                    ));
                }
            }
        }
        out.extend(outline::misplaced_glyphs(&self.svg, &self.svg_file()));
        out
    }

    /// Labels that leave the figure.
    pub fn labels_outside(&self) -> Vec<String> {
        let page = Rect::new(0.0, 0.0, self.width as f64, self.height as f64);
        self.labels
            .iter()
            .filter(|l| !page.contains(&l.rect))
            .map(|l| l.text.clone())
            .collect()
    }
}

pub(crate) fn face() -> &'static ttf_parser::Face<'static> {
    static FACE: OnceLock<ttf_parser::Face<'static>> = OnceLock::new();
    FACE.get_or_init(|| ttf_parser::Face::parse(FONT, 0).expect("the embedded font parses"))
}

/// plotters writes a font size asked of it divided by this into the SVG (14 → 11.29
/// px): what is drawn, and so what is measured, is that size.
pub const PLOTTERS_FONT_SCALE: f64 = 1.24;

/// The size, px, of text drawn at `size_px` through plotters.
pub fn drawn_px(size_px: f64) -> f64 {
    size_px / PLOTTERS_FONT_SCALE
}

/// The width of `text` drawn through plotters at `size_px` (the size asked of it; the
/// text is [`drawn_px`] of that), px.
pub fn text_width(text: &str, size_px: f64) -> f64 {
    advance_width(text, drawn_px(size_px))
}

/// The font's x-height, em (what `dy="0.5ex"` is measured in).
pub fn font_x_height() -> f64 {
    let f = face();
    f.x_height()
        .map_or(0.5, |h| h as f64 / f.units_per_em() as f64)
}

/// The font's ascent and descent, em.
pub fn font_extent() -> (f64, f64) {
    let f = face();
    let units = f.units_per_em() as f64;
    (f.ascender() as f64 / units, -(f.descender() as f64) / units)
}

/// The advance width of `text` at a font size of `px` as written in the SVG, px.
pub fn advance_width(text: &str, px: f64) -> f64 {
    let size_px = px;
    let f = face();
    let units = f.units_per_em() as f64;
    let mut w = 0.0;
    for c in text.chars() {
        let adv = f
            .glyph_index(c)
            .and_then(|g| f.glyph_hor_advance(g))
            .unwrap_or(f.units_per_em() / 2);
        w += adv as f64;
    }
    w / units * size_px
}

/// Round tick step for a span: 1, 2 or 5 × 10ⁿ, about `n` ticks.
pub fn nice_step(span: f64, n: f64) -> f64 {
    if !(span.is_finite() && span > 0.0) {
        return 1.0;
    }
    let raw = span / n;
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| *s >= raw * 0.999)
        .unwrap_or(10.0 * p)
}

/// A range widened to whole tick steps, with a little room.
pub fn nice_range(lo: f64, hi: f64) -> (f64, f64) {
    // No finite data (a pair with no valid mesh anywhere): an empty 0 … 1 axis; an
    // infinite range would never finish its ticks.
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        (lo - 1.0, hi + 1.0)
    };
    let s = nice_step(hi - lo, 6.0);
    ((lo / s).floor() * s, (hi / s).ceil() * s)
}

/// The `i`-th colour of [`PALETTE`], cycling.
pub(crate) fn palette(i: usize) -> plotters::style::RGBColor {
    let (r, g, b) = PALETTE[i % PALETTE.len()];
    plotters::style::RGBColor(r, g, b)
}

/// Colours of series, distinguishable in print and for the common colour blindnesses
/// (Okabe & Ito 2008), then darker variants and two more hues: as many as the most
/// curves a run figure draws ([`run::MAX_TEMPS`]), so that no two share a colour.
pub const PALETTE: [(u8, u8, u8); 12] = [
    (0, 114, 178),
    (213, 94, 0),
    (0, 158, 115),
    (204, 121, 167),
    (230, 159, 0),
    (86, 180, 233),
    (120, 120, 120),
    (0, 0, 0),
    (150, 60, 0),
    (0, 90, 60),
    (110, 60, 160),
    (160, 150, 0),
];

/// Decimals a tick label needs at tick spacing `step` (0 from 1 up).
pub(crate) fn decimals(step: f64) -> usize {
    if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    }
}

/// The unit of a time axis ending at `t_end_s`: hours up to three days, then days
/// (seconds per unit, name). One rule for every figure.
pub fn time_unit(t_end_s: f64) -> (f64, &'static str) {
    if t_end_s <= 3.0 * 86_400.0 {
        (3600.0, "h")
    } else {
        (86_400.0, "days")
    }
}

/// A drawing area of a figure: the whole page, or a panel cut from it.
pub(crate) type Area<'b> =
    plotters::drawing::DrawingArea<plotters::prelude::SVGBackend<'b>, plotters::coord::Shift>;

/// A chart with linear x and y axes, drawn on an [`Area`].
pub(crate) type Chart<'a, 'b> = plotters::prelude::ChartContext<
    'a,
    plotters::prelude::SVGBackend<'b>,
    plotters::prelude::Cartesian2d<
        plotters::coord::types::RangedCoordf64,
        plotters::coord::types::RangedCoordf64,
    >,
>;

/// The plotting area of `chart` (inside its axes), px.
pub(crate) fn plot_rect(chart: &Chart<'_, '_>) -> Rect {
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    Rect::new(
        xr.start as f64,
        yr.start as f64,
        xr.end as f64,
        yr.end as f64,
    )
}

/// The time axis of a figure: the unit of [`time_unit`] and the axis's ends in it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TimeAxis {
    /// Seconds per unit.
    pub unit_s: f64,
    /// The unit's name ("h" or "days").
    pub unit: &'static str,
    /// The axis's ends, in the unit.
    pub x0: f64,
    pub x1: f64,
}

impl TimeAxis {
    /// The axis from `start_s` over `span_s`, its unit chosen by where it ends.
    pub fn new(start_s: f64, span_s: f64) -> TimeAxis {
        let (unit_s, unit) = time_unit(span_s + start_s);
        TimeAxis {
            unit_s,
            unit,
            x0: start_s / unit_s,
            x1: (start_s + span_s) / unit_s,
        }
    }

    /// A time, s, on the axis (in its unit).
    pub fn x(&self, t_s: f64) -> f64 {
        t_s / self.unit_s
    }
}

/// The labels of a figure being drawn: the placer that keeps them apart and the list
/// the [`Figure`] reports.
#[derive(Debug, Default)]
pub(crate) struct Annotations {
    pub placer: Placer,
    pub labels: Vec<Label>,
}

impl Annotations {
    /// Keeps a label drawn at `rect`.
    pub fn keep(&mut self, text: impl Into<String>, rect: Rect) {
        self.labels.push(Label {
            text: text.into(),
            rect,
        });
    }
}

/// Shading of eclipses, and of a diagnosis's held-out orbits.
/// A series as the lines to draw: (t, v) points split where v is not finite and
/// where the time step exceeds 3 × the series' median step (a gap in the recording,
/// which a straight line across would fill with a ramp the model never made).
pub(crate) fn line_segments(time_s: &[f64], values: &[f64]) -> Vec<Vec<(f64, f64)>> {
    let mut steps: Vec<f64> = time_s.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let gap = steps
        .get(steps.len() / 2)
        .map_or(f64::INFINITY, |m| 3.0 * m);
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut last_t = f64::NAN;
    for (&t, &v) in time_s.iter().zip(values) {
        if !v.is_finite() {
            last_t = f64::NAN;
            continue;
        }
        // a new segment at the start, after a non-finite value (last_t NaN) or a gap
        if last_t.is_nan() || t - last_t > gap {
            out.push(Vec::new());
        }
        out.last_mut().expect("a segment").push((t, v));
        last_t = t;
    }
    out
}

/// Lines to draw, each a run of (t s, value) points.
pub(crate) type Segments = Vec<Vec<(f64, f64)>>;

/// A diagnosis's two models as the lines to draw, baseline then corrected, (t s, value):
/// along the models' own even grid when the series has it (through the recording's
/// gaps, as the models are there), else through the recording's times, broken at its
/// gaps ([`line_segments`]).
pub(crate) fn model_lines(
    s: &crate::diagnose::Series,
    c: usize,
) -> [(Segments, plotters::style::RGBColor); 2] {
    // an even grid has no gap, so only its non-finite values break its lines
    let lines = |grid: &[Vec<f64>], at_readings: &[Vec<f64>]| match grid.get(c) {
        Some(g) if s.model_time_s.len() >= 2 => line_segments(&s.model_time_s, g),
        _ => line_segments(&s.time_s, &at_readings[c]),
    };
    [
        (lines(&s.baseline_grid, &s.baseline), BEFORE),
        (lines(&s.corrected_grid, &s.corrected), AFTER),
    ]
}

/// Every value either model takes where a figure draws it (at the readings and on the
/// models' grid), for the value axis's range.
pub(crate) fn model_values(
    s: &crate::diagnose::Series,
    c: usize,
) -> impl Iterator<Item = f64> + '_ {
    fn grid(g: &[Vec<f64>], c: usize) -> &[f64] {
        g.get(c).map_or(&[], |v| v.as_slice())
    }
    s.baseline[c]
        .iter()
        .chain(&s.corrected[c])
        .chain(grid(&s.baseline_grid, c))
        .chain(grid(&s.corrected_grid, c))
        .copied()
        .filter(|v| v.is_finite())
}

pub(crate) const ECLIPSE: plotters::style::RGBColor = plotters::style::RGBColor(222, 226, 236);
pub(crate) const HELD_OUT: plotters::style::RGBColor = plotters::style::RGBColor(254, 243, 216);
/// The model before a diagnosis (orange) and after it (blue).
pub(crate) const BEFORE: plotters::style::RGBColor = plotters::style::RGBColor(213, 94, 0);
pub(crate) const AFTER: plotters::style::RGBColor = plotters::style::RGBColor(0, 114, 178);

/// What stands left of a legend line.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Swatch {
    /// A line of this colour and width.
    Line(plotters::style::RGBColor, u32),
    /// A dashed line of this colour and width (a limit drawn dashed).
    Dashed(plotters::style::RGBColor, u32),
    /// A point (a recording's samples).
    Dot(plotters::style::RGBColor),
    /// A ring (a marked point, such as the run's smallest backlash).
    Ring(plotters::style::RGBColor),
    /// A shaded area.
    Patch(plotters::style::RGBColor),
    /// Nothing (a note under the entries).
    None,
}

/// A legend drawn as a column with its swatches at `x` (24 px wide) and the texts
/// after them from `top` down, the boxes placed by `placer` and kept in `labels`;
/// returns the boxes.
pub(crate) fn legend(
    root: &plotters::drawing::DrawingArea<
        plotters::prelude::SVGBackend<'_>,
        plotters::coord::Shift,
    >,
    placer: &mut Placer,
    labels: &mut Vec<Label>,
    x: i32,
    top: f64,
    entries: &[(String, Swatch)],
) -> Result<Vec<Rect>, PlotError> {
    use plotters::prelude::*;
    let texts: Vec<String> = entries.iter().map(|e| e.0.clone()).collect();
    let placed = placer.column(&texts, 14.0, (x as f64 + 34.0, top));
    for ((text, swatch), ((tx, ty), r)) in entries.iter().zip(&placed) {
        let ym = ((r.y0 + r.y1) / 2.0) as i32;
        match *swatch {
            Swatch::Line(c, w) => root
                .draw(&PathElement::new(
                    vec![(x + 4, ym), (x + 28, ym)],
                    c.stroke_width(w),
                ))
                .map_err(draw_err)?,
            Swatch::Dashed(c, w) => {
                for (a, b) in [(4, 10), (15, 21), (26, 28)] {
                    root.draw(&PathElement::new(
                        vec![(x + a, ym), (x + b, ym)],
                        c.stroke_width(w),
                    ))
                    .map_err(draw_err)?;
                }
            }
            Swatch::Dot(c) => root
                .draw(&Circle::new((x + 16, ym), 4, c.filled()))
                .map_err(draw_err)?,
            Swatch::Ring(c) => root
                .draw(&Circle::new((x + 16, ym), 6, c.stroke_width(2)))
                .map_err(draw_err)?,
            Swatch::Patch(c) => root
                .draw(&Rectangle::new(
                    [(x + 4, ym - 6), (x + 28, ym + 6)],
                    c.filled(),
                ))
                .map_err(draw_err)?,
            Swatch::None => {}
        }
        root.draw(&Text::new(
            text.clone(),
            (*tx as i32, *ty as i32),
            (FAMILY, 14).into_font().color(&BLACK),
        ))
        .map_err(draw_err)?;
        labels.push(Label {
            text: text.clone(),
            rect: *r,
        });
    }
    Ok(placed.into_iter().map(|p| p.1).collect())
}

#[cfg(test)]
mod tests {
    use super::line_segments;

    /// Every curve of a run figure (at most `MAX_TEMPS` nodes) has a colour of its own
    /// (with 12 nodes, two shared one).
    #[test]
    fn core_the_palette_covers_a_run_figure() {
        let n = super::run::MAX_TEMPS;
        let colours: std::collections::BTreeSet<_> = (0..n)
            .map(|k| super::PALETTE[k % super::PALETTE.len()])
            .collect();
        assert_eq!(colours.len(), n);
    }

    /// A gap over 3 × the median step and a non-finite value each end a line; a
    /// fill row (a finite model value between readings) does not.
    #[test]
    fn core_model_lines_break_at_gaps_and_holes() {
        let t = [0.0, 60.0, 120.0, 180.0, 1200.0, 1260.0, 1320.0, 1380.0];
        let v = [1.0, 2.0, 3.0, 4.0, 5.0, f64::NAN, 7.0, 8.0];
        let segs = line_segments(&t, &v);
        let lens: Vec<usize> = segs.iter().map(Vec::len).collect();
        assert_eq!(lens, vec![4, 1, 2], "{segs:?}");
        assert_eq!(segs[1], vec![(1200.0, 5.0)]);
        assert_eq!(line_segments(&t[..4], &v[..4]).len(), 1);
        assert!(line_segments(&[], &[]).is_empty());
    }
}

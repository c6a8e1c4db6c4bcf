//! Curves at sub-pixel positions. plotters hands its backends whole pixels, so a
//! curve drawn through it is rounded to the pixel grid and wobbles in a 2× PNG or a
//! zoomed SVG. A curve drawn here is mapped onto the chart's pixels exactly (to 0.01
//! px) and written as an SVG element into a placeholder text, drawn through plotters
//! at the curve's place in the drawing order; [`splice`] swaps each placeholder for
//! its element when the figure is finished. A placeholder starts with a private-use
//! character and this process's random key, so no label (a title, a column name)
//! can pass for one: only the tool's own elements are ever written as markup. Axes, ticks and reference lines, which
//! are straight and meant to sit on the pixel grid, stay with plotters.

use plotters::prelude::*;

use super::{Chart, PlotError, draw_err};

/// The first character of a placeholder's text (Unicode private use).
const MARK: char = '\u{E000}';

/// What starts a placeholder: [`MARK`] and a key drawn once per process (from the
/// clock and an address), which no text given to the tool can know.
fn placeholder_key() -> &'static str {
    static KEY: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    KEY.get_or_init(|| {
        use std::hash::{BuildHasher, Hasher};
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write_u128(
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos()),
        );
        h.write_usize(&KEY as *const _ as usize);
        format!("{MARK}{:016x}:", h.finish())
    })
}

/// The exact pixel position of the data point `(x, y)` on `chart`: plotters' own
/// mapping (the plotting area's first to last pixel, y up) without its rounding down.
pub(crate) fn to_px(chart: &Chart<'_, '_>, (x, y): (f64, f64)) -> (f64, f64) {
    let spec = chart.as_coord_spec();
    let (xr, yr) = (spec.get_x_range(), spec.get_y_range());
    let (px, py) = chart.plotting_area().get_pixel_range();
    let (x0, x1) = (px.start as f64, (px.end - 1) as f64);
    let (y_bottom, y_top) = ((py.end - 1) as f64, py.start as f64);
    (
        x0 + (x - xr.start) / (xr.end - xr.start) * (x1 - x0),
        y_bottom + (y - yr.start) / (yr.end - yr.start) * (y_top - y_bottom),
    )
}

/// The points of an SVG `points` attribute ("x,y", 0.01 px); non-finite ones left out.
fn pixel_pairs(chart: &Chart<'_, '_>, points: impl IntoIterator<Item = (f64, f64)>) -> Vec<String> {
    points
        .into_iter()
        .map(|p| to_px(chart, p))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(x, y)| format!("{},{}", round2(x), round2(y)))
        .collect()
}

/// `v` to 0.01, written without trailing zeros.
fn round2(v: f64) -> String {
    let r = (v * 100.0).round() / 100.0;
    let s = format!("{r:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

fn colour(c: RGBColor) -> String {
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

/// Draws a line through `points` (data coordinates) on `chart`, `width_px` wide.
pub(crate) fn line(
    chart: &Chart<'_, '_>,
    points: impl IntoIterator<Item = (f64, f64)>,
    color: RGBColor,
    width_px: f64,
) -> Result<(), PlotError> {
    let head = format!(
        "polyline fill=\"none\" opacity=\"1\" stroke=\"{}\" stroke-width=\"{width_px}\" \
         stroke-linejoin=\"round\"",
        colour(color)
    );
    shape(chart, points, 2, &head)
}

/// Fills the polygon through `points` (data coordinates) on `chart`.
pub(crate) fn area(
    chart: &Chart<'_, '_>,
    points: impl IntoIterator<Item = (f64, f64)>,
    color: RGBColor,
    opacity: f64,
) -> Result<(), PlotError> {
    let head = format!(
        "polygon opacity=\"{opacity}\" fill=\"{}\" stroke=\"none\"",
        colour(color)
    );
    shape(chart, points, 3, &head)
}

/// The element `<{head} points="…"/>` through `points` (data coordinates), drawn
/// when it has at least `min_points` finite ones.
fn shape(
    chart: &Chart<'_, '_>,
    points: impl IntoIterator<Item = (f64, f64)>,
    min_points: usize,
    head: &str,
) -> Result<(), PlotError> {
    let pts = pixel_pairs(chart, points);
    if pts.len() < min_points {
        return Ok(());
    }
    place(chart, format!("<{head} points=\"{}\"/>", pts.join(" ")))
}

/// Draws the placeholder that [`splice`] replaces with `element`.
fn place(chart: &Chart<'_, '_>, element: String) -> Result<(), PlotError> {
    chart
        .plotting_area()
        .strip_coord_spec()
        .draw(&Text::new(
            format!("{}{element}", placeholder_key()),
            (0, 0),
            ("sans-serif", 1.0).into_font(),
        ))
        .map_err(draw_err)
}

/// `svg` with every placeholder (a `<text>` whose body starts with the key) replaced by
/// the element it carries.
pub(crate) fn splice(svg: String) -> String {
    let key = placeholder_key();
    if !svg.contains(key) {
        return svg;
    }
    let mut out = String::with_capacity(svg.len());
    let mut rest = svg.as_str();
    while let Some(m) = rest.find(key) {
        let (Some(open), Some(close)) = (
            rest[..m].rfind("<text"),
            rest[m..].find("</text>").map(|c| m + c),
        ) else {
            break;
        };
        out.push_str(&rest[..open]);
        let body = rest[m + key.len()..close].trim_end_matches('\n');
        out.push_str(&super::drawn::unescape(body));
        rest = &rest[close + "</text>".len()..];
        rest = rest.strip_prefix('\n').unwrap_or(rest);
        out.push('\n');
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine drawn both ways: each fine point rounds down to plotters' own pixel, and
    /// the fine points lie off the pixel grid (what makes the curve smooth).
    #[test]
    fn val_closed_form_fine_points_are_plotters_pixels_unrounded() {
        let mut svg = String::new();
        let pts: Vec<(f64, f64)> = (0..200)
            .map(|i| {
                let x = i as f64 * 0.05;
                (x, x.sin())
            })
            .collect();
        {
            let root = SVGBackend::with_string(&mut svg, (640, 400)).into_drawing_area();
            let mut chart = ChartBuilder::on(&root)
                .margin(10)
                .x_label_area_size(30)
                .y_label_area_size(40)
                .build_cartesian_2d(0.0..10.0, -1.2..1.2)
                .unwrap();
            chart.configure_mesh().draw().unwrap();
            let mut off_grid = 0;
            for &p in &pts {
                let (fx, fy) = to_px(&chart, p);
                let (ix, iy) = chart.backend_coord(&p);
                assert_eq!((fx + 1e-3).floor() as i32, ix, "x of {p:?}");
                assert_eq!((fy - 1e-3).ceil() as i32, iy, "y of {p:?}");
                if (fy - fy.round()).abs() > 0.05 {
                    off_grid += 1;
                }
            }
            assert!(off_grid > 150, "{off_grid} of 200 points off the grid");
            line(&chart, pts.iter().copied(), RED, 2.0).unwrap();
            area(&chart, [(1.0, 0.0), (2.0, 1.0), (3.0, 0.0)], BLUE, 0.25).unwrap();
        }
        let svg = splice(svg);
        assert!(!svg.contains(MARK) && !svg.contains("&lt;polyline"));
        // a label that starts like a placeholder stays text
        let forged =
            format!("<svg><text x=\"0\" y=\"0\">{MARK}&lt;script&gt;x&lt;/script&gt;</text></svg>");
        assert_eq!(splice(forged.clone()), forged);
        let (_, lines) = crate::plot::drawn::read(&svg);
        let curve = lines.iter().find(|l| l.len() == 200).expect("the curve");
        assert!(curve.iter().any(|p| p.1.fract().abs() > 0.05));
        assert!(svg.contains("<polygon opacity=\"0.25\" fill=\"#0000FF\""));
        assert!(svg.trim_end().ends_with("</svg>"));
    }
}

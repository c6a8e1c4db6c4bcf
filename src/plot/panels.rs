//! The page both figures of `environment --plot` share (the faces' fluxes, the orbit's
//! environment): a title at the top, panels stacked under it left of a legend column,
//! each with its time and value axes and the eclipses shaded.

use plotters::prelude::*;

use super::labels::Placer;
use super::{Area, Chart, ECLIPSE, FAMILY, Label, PlotError, decimals, draw_err, nice_step};

/// The page, px.
pub(crate) const W: u32 = 1100;
pub(crate) const H: u32 = 820;
/// Where the legend column starts, px.
pub(crate) const LEGEND_X: i32 = 880;
/// Each panel's height, px (the first starts under the title).
const PANEL_H: i32 = 250;

/// Draws `title` at the top left and keeps every label off it.
pub(crate) fn title(
    root: &Area<'_>,
    title: &str,
    placer: &mut Placer,
    labels: &mut Vec<Label>,
) -> Result<(), PlotError> {
    root.draw(&Text::new(
        title.to_string(),
        (20, 12),
        (FAMILY, 19).into_font().color(&BLACK),
    ))
    .map_err(draw_err)?;
    let r = Placer::text_box(title, 19.0, 20.0, 12.0);
    placer.avoid(r);
    labels.push(Label {
        text: title.to_string(),
        rect: r,
    });
    Ok(())
}

/// The area of panel `k` (0 at the top), left of the legend column.
pub(crate) fn area<'b>(root: &Area<'b>, k: usize) -> Area<'b> {
    root.clone().shrink(
        (0, 46 + k as i32 * PANEL_H),
        (LEGEND_X as u32, PANEL_H as u32 - 6),
    )
}

/// A panel's axes: x (in the time unit) and y ranges, the y axis's description, its
/// tick labels' decimals (None: as the tick step needs), and the time axis's
/// description (on the last panel only).
pub(crate) struct Axes<'s> {
    pub x: (f64, f64),
    pub y: (f64, f64),
    pub desc: &'s str,
    pub y_decimals: Option<usize>,
    pub time_desc: Option<String>,
}

/// The panel's chart on `area`: its grid and axes drawn, the eclipses (in the time
/// unit) shaded under what comes next.
pub(crate) fn chart<'a, 'b>(
    area: &'a Area<'b>,
    ax: &Axes<'_>,
    eclipses: &[(f64, f64)],
) -> Result<Chart<'a, 'b>, PlotError> {
    let ((x0, x1), (ylo, yhi)) = (ax.x, ax.y);
    let mut chart = ChartBuilder::on(area)
        .margin_left(10)
        .margin_right(10)
        .x_label_area_size(if ax.time_desc.is_some() { 50 } else { 26 })
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, ylo..yhi)
        .map_err(draw_err)?;
    let (ystep, xstep) = (nice_step(yhi - ylo, 5.0), nice_step(x1 - x0, 10.0));
    let (ydec, xdec) = (ax.y_decimals.unwrap_or(decimals(ystep)), decimals(xstep));
    let yfmt = move |v: &f64| format!("{v:.ydec$}");
    let xfmt = move |v: &f64| format!("{v:.xdec$}");
    let mut mesh = chart.configure_mesh();
    mesh.y_desc(ax.desc)
        .y_labels(((yhi - ylo) / ystep).round() as usize + 1)
        .x_labels(((x1 - x0) / xstep).round() as usize + 1)
        .y_label_formatter(&yfmt)
        .x_label_formatter(&xfmt)
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(230, 230, 230))
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 14));
    if let Some(d) = &ax.time_desc {
        mesh.x_desc(d.as_str());
    }
    mesh.draw().map_err(draw_err)?;
    chart
        .draw_series(
            eclipses
                .iter()
                .map(|&(a, b)| Rectangle::new([(a, ylo), (b, yhi)], ECLIPSE.filled())),
        )
        .map_err(draw_err)?;
    Ok(chart)
}

//! The overview of a diagnosis: every channel in a grid, the recording against the
//! baseline and corrected models, each panel titled with its held-out RMSE before and
//! after; eclipses and the held-out orbits shaded; one legend on top (the figure of
//! `docs/validation.md`, written by `diagnose --out` as `overview.svg`).

use plotters::prelude::*;

use super::diagnose::shade_held_out_and_eclipses;
use super::labels::{Placer, Rect};
use super::{
    AFTER, Annotations, Area, BEFORE, Chart, ECLIPSE, FAMILY, Figure, HELD_OUT, PlotError,
    TimeAxis, decimals, draw_err, nice_range, nice_step, text_width,
};
use crate::diagnose::Series;

const RECORDED: RGBColor = RGBColor(40, 40, 40);

/// The overview's layout: a grid of panels, one per channel, under the title and the
/// legend, above the time axis's caption.
#[derive(Debug, Clone, Copy)]
struct Grid {
    rows: usize,
    cols: usize,
    /// The figure's width and height, px.
    w: u32,
    h: u32,
    /// A panel's height and the grid's top, px.
    panel_h: u32,
    top: u32,
}

impl Grid {
    /// One column for a single channel, else two.
    fn of(s: &Series) -> Grid {
        let n = s.channels.len().max(1);
        let cols = if n == 1 { 1 } else { 2 };
        let rows = n.div_ceil(cols);
        let (w, panel_h, top) = (1200u32, 230u32, 80u32);
        let h = top + rows as u32 * panel_h + 40;
        Grid {
            rows,
            cols,
            w,
            h,
            panel_h,
            top,
        }
    }
}

/// RMS of recorded − model over the held-out orbits (NaN: none there).
fn heldout_rms(s: &Series, c: usize, model: &[f64]) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (j, &t) in s.time_s.iter().enumerate() {
        if t > s.train_end_s
            && t <= s.holdout_end_s
            && let Some(v) = s.recorded[c][j]
        {
            sum += (v - model[j]).powi(2);
            n += 1;
        }
    }
    if n == 0 {
        f64::NAN
    } else {
        (sum / n as f64).sqrt()
    }
}

/// The overview figure of `s`, titled `title`.
pub fn overview(s: &Series, title: &str) -> Result<Figure, PlotError> {
    let grid = Grid::of(s);
    let span = s.time_s.last().copied().unwrap_or(1.0).max(1.0);
    let start = s.figure_start_s().min(span);
    let axis = TimeAxis::new(start, (span - start).max(1.0));
    let mut svg = String::new();
    let mut notes = Annotations::default();
    {
        let root = SVGBackend::with_string(&mut svg, (grid.w, grid.h)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        draw_title(&root, title, &mut notes)?;
        draw_legend_row(&root, &grid, &mut notes)?;
        let area = root
            .clone()
            .shrink((0, grid.top), (grid.w, grid.rows as u32 * grid.panel_h));
        let panels = area.split_evenly((grid.rows, grid.cols));
        for (c, panel) in panels.iter().enumerate().take(s.channels.len()) {
            draw_channel(&root, panel, s, c, &axis, &mut notes)?;
        }
        draw_time_caption(&root, &grid, &axis, &mut notes)?;
        root.present().map_err(draw_err)?;
    }
    Ok(Figure::new(svg, grid.w, grid.h, notes.labels))
}

/// Draws the figure's title at its top left.
fn draw_title(root: &Area<'_>, title: &str, notes: &mut Annotations) -> Result<(), PlotError> {
    root.draw(&Text::new(
        title.to_string(),
        (20, 10),
        (FAMILY, 19).into_font().color(&BLACK),
    ))
    .map_err(draw_err)?;
    let r = Placer::text_box(title, 19.0, 20.0, 10.0);
    notes.placer.avoid(r);
    notes.keep(title, r);
    Ok(())
}

/// Draws the one legend of the figure, a row under the title: the recording, both
/// models and the two shadings.
fn draw_legend_row(root: &Area<'_>, grid: &Grid, notes: &mut Annotations) -> Result<(), PlotError> {
    let page = Rect::new(0.0, 0.0, grid.w as f64, grid.h as f64);
    let items: [(&str, RGBColor, u8); 5] = [
        ("recorded", RECORDED, 0),
        ("baseline model", BEFORE, 1),
        ("corrected model", AFTER, 1),
        ("eclipse", ECLIPSE, 2),
        ("held out (never fitted)", HELD_OUT, 2),
    ];
    let mut x = 24.0;
    for (text, color, kind) in items {
        let ym = 50;
        match kind {
            0 => root
                .draw(&Circle::new((x as i32 + 12, ym), 3, color.filled()))
                .map_err(draw_err)?,
            1 => root
                .draw(&PathElement::new(
                    vec![(x as i32, ym), (x as i32 + 24, ym)],
                    color.stroke_width(3),
                ))
                .map_err(draw_err)?,
            _ => root
                .draw(&Rectangle::new(
                    [(x as i32, ym - 6), (x as i32 + 24, ym + 6)],
                    color.filled(),
                ))
                .map_err(draw_err)?,
        }
        let ((tx0, ty0), r) = notes.placer.place(
            text,
            14.0,
            (x + 26.0, ym as f64),
            &[super::labels::Side::Right],
            &page,
        );
        root.draw(&Text::new(
            text.to_string(),
            (tx0 as i32, ty0 as i32),
            (FAMILY, 14).into_font().color(&BLACK),
        ))
        .map_err(draw_err)?;
        notes.keep(text, r);
        x = r.x1 + 24.0;
    }
    Ok(())
}

/// Draws channel `c` in `panel`: the shading, both models as lines, the recording as
/// dots, and the head with the channel's held-out RMSE before and after (nothing for
/// a channel with no finite value).
fn draw_channel(
    root: &Area<'_>,
    panel: &Area<'_>,
    s: &Series,
    c: usize,
    axis: &TimeAxis,
    notes: &mut Annotations,
) -> Result<(), PlotError> {
    let unit = s.value_units.get(c).copied().unwrap_or("");
    let rec: Vec<(f64, f64)> = s
        .time_s
        .iter()
        .zip(&s.recorded[c])
        .filter_map(|(t, v)| v.filter(|v| v.is_finite()).map(|v| (axis.x(*t), v)))
        .collect();
    let vals = rec.iter().map(|p| p.1).chain(super::model_values(s, c));
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return Ok(());
    }
    let (ylo, yhi) = nice_range(lo, hi);
    // the channel's own unit on its axis; the RMSE, a difference, in kelvin for °C
    let diff_unit = if unit == "°C" { "K" } else { unit };
    let head = format!(
        "{}{}: held-out RMSE {:.2} → {:.2} {diff_unit}",
        s.channels[c],
        if unit.is_empty() {
            String::new()
        } else {
            format!(" ({unit})")
        },
        heldout_rms(s, c, &s.baseline[c]),
        heldout_rms(s, c, &s.corrected[c])
    );
    let mut chart = panel_chart(panel, axis, (ylo, yhi))?;
    shade_held_out_and_eclipses(&mut chart, s, axis, (ylo, yhi))?;
    for (segs, color) in super::model_lines(s, c) {
        for seg in segs {
            super::fine::line(
                &chart,
                seg.into_iter().map(|(t, v)| (axis.x(t), v)),
                color,
                2.0,
            )?;
        }
    }
    chart
        .draw_series(
            rec.iter()
                .map(|p| Circle::new(*p, 1, RECORDED.mix(0.8).filled())),
        )
        .map_err(draw_err)?;
    draw_panel_head(root, &chart, head, notes)
}

/// Draws a panel's axes and grid over the recording's time and `y`.
fn panel_chart<'a, 'b>(
    panel: &'a Area<'b>,
    axis: &TimeAxis,
    (ylo, yhi): (f64, f64),
) -> Result<Chart<'a, 'b>, PlotError> {
    let (x0, x1) = (axis.x0, axis.x1);
    let mut chart = ChartBuilder::on(panel)
        .margin(8)
        .margin_top(28)
        .x_label_area_size(28)
        .y_label_area_size(48)
        .build_cartesian_2d(x0..x1, ylo..yhi)
        .map_err(draw_err)?;
    let ystep = nice_step(yhi - ylo, 4.0);
    let ydec = decimals(ystep);
    let xstep = nice_step(x1 - x0, 8.0);
    let xdec = decimals(xstep);
    chart
        .configure_mesh()
        .y_labels(((yhi - ylo) / ystep).round() as usize + 1)
        .x_labels(((x1 - x0) / xstep).round() as usize + 1)
        .y_label_formatter(&|v| format!("{v:.ydec$}"))
        .x_label_formatter(&|v| format!("{v:.xdec$}"))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(230, 230, 230))
        .label_style((FAMILY, 12))
        .draw()
        .map_err(draw_err)?;
    Ok(chart)
}

/// Draws a panel's head centred above its plot.
fn draw_panel_head(
    root: &Area<'_>,
    chart: &Chart<'_, '_>,
    head: String,
    notes: &mut Annotations,
) -> Result<(), PlotError> {
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let tw = text_width(&head, 13.0);
    let pos = (
        ((xr.start + xr.end) as f64 - tw) / 2.0,
        yr.start as f64 - 22.0,
    );
    let r = Placer::text_box(&head, 13.0, pos.0, pos.1);
    root.draw(&Text::new(
        head.clone(),
        (pos.0 as i32, pos.1 as i32),
        (FAMILY, 13).into_font().color(&BLACK),
    ))
    .map_err(draw_err)?;
    notes.keep(head, r);
    Ok(())
}

/// Draws the time axis's caption, centred under the grid.
fn draw_time_caption(
    root: &Area<'_>,
    grid: &Grid,
    axis: &TimeAxis,
    notes: &mut Annotations,
) -> Result<(), PlotError> {
    let foot = format!("time since the scenario's t = 0 ({})", axis.unit);
    let fw = text_width(&foot, 14.0);
    let pos = ((grid.w as f64 - fw) / 2.0, grid.h as f64 - 28.0);
    root.draw(&Text::new(
        foot.clone(),
        (pos.0 as i32, pos.1 as i32),
        (FAMILY, 14).into_font().color(&BLACK),
    ))
    .map_err(draw_err)?;
    let r = Placer::text_box(&foot, 14.0, pos.0, pos.1);
    notes.keep(foot, r);
    Ok(())
}

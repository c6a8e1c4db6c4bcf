//! The figure of one recording channel in a diagnosis: above, the recording against
//! the baseline and the corrected model; below, the residual before and after with the
//! noise bands. Eclipses and the held-out orbits are shaded in both, the legend sits
//! beside the plots (never over the data), and time is in the unit of `plot` (hours up
//! to three days, then days).

use plotters::prelude::*;

use super::labels::Placer;
use super::{
    AFTER, Annotations, Area, BEFORE, Chart, ECLIPSE, FAMILY, Figure, HELD_OUT, PlotError, Swatch,
    TimeAxis, decimals, draw_err, nice_range, nice_step,
};
use crate::diagnose::Series;

const W: u32 = 1200;
const H: u32 = 760;
const LEGEND_X: i32 = 930;
const RECORDED: RGBColor = RGBColor(60, 60, 60);
/// The panels' top and bottom, px, and whether each shows the values (else the
/// residuals).
const PANELS_PX: [(i32, i32, bool); 2] = [(46, 400, true), (420, 740, false)];

/// A reading of the channel where the recording and both models are finite: its time
/// on the figure's axis and the three values.
#[derive(Debug, Clone, Copy)]
struct Reading {
    t: f64,
    recorded: f64,
    baseline: f64,
    corrected: f64,
}

/// The channel a figure shows, with what both its panels need.
struct ChannelView<'s> {
    s: &'s Series,
    /// Its index in the series.
    c: usize,
    name: &'s str,
    /// The unit of the values as recorded (the channel's own).
    unit: &'static str,
    /// The unit of the residuals: K or µm.
    res_unit: &'static str,
    /// The recording's estimated noise, σ (NaN: none).
    sigma: f64,
    axis: TimeAxis,
    readings: Vec<Reading>,
}

impl<'s> ChannelView<'s> {
    /// Channel `c` of `s`: its units, noise, time axis and readings.
    fn new(s: &'s Series, c: usize) -> ChannelView<'s> {
        let is_temp = s.units[c] != "um";
        let span = s.time_s.last().copied().unwrap_or(1.0).max(1.0);
        let start = s.figure_start_s().min(span);
        let axis = TimeAxis::new(start, (span - start).max(1.0));
        let readings = s
            .time_s
            .iter()
            .enumerate()
            .filter_map(|(j, &t)| {
                s.recorded[c][j].map(|v| Reading {
                    t: axis.x(t),
                    recorded: v,
                    baseline: s.baseline[c][j],
                    corrected: s.corrected[c][j],
                })
            })
            .filter(|p| p.recorded.is_finite() && p.baseline.is_finite() && p.corrected.is_finite())
            .collect();
        ChannelView {
            s,
            c,
            name: &s.channels[c],
            unit: s
                .value_units
                .get(c)
                .copied()
                .unwrap_or(if is_temp { "K" } else { "µm" }),
            res_unit: if is_temp { "K" } else { "µm" },
            sigma: s.noise.get(c).copied().unwrap_or(f64::NAN),
            axis,
            readings,
        }
    }

    /// The ranges of the values (recorded and both models) and of the residuals (with
    /// room for ±3σ).
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let (mut vlo, mut vhi) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut rlo, mut rhi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &self.readings {
            vlo = vlo.min(p.recorded.min(p.baseline).min(p.corrected));
            vhi = vhi.max(p.recorded.max(p.baseline).max(p.corrected));
            for r in [p.recorded - p.baseline, p.recorded - p.corrected] {
                rlo = rlo.min(r);
                rhi = rhi.max(r);
            }
        }
        // the models are drawn between readings too (their own grid, fill rows)
        for v in super::model_values(self.s, self.c) {
            vlo = vlo.min(v);
            vhi = vhi.max(v);
        }
        if self.sigma.is_finite() {
            rlo = rlo.min(-3.0 * self.sigma);
            rhi = rhi.max(3.0 * self.sigma);
        }
        ((vlo, vhi), (rlo, rhi))
    }
}

/// The figure of channel `c` of `s`.
pub fn channel(s: &Series, c: usize) -> Result<Figure, PlotError> {
    let view = ChannelView::new(s, c);
    let mut svg = String::new();
    let mut notes = Annotations::default();
    {
        let root = SVGBackend::with_string(&mut svg, (W, H)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        draw_title(&root, view.name, &mut notes)?;
        // No reading to compare: the title alone.
        if !view.readings.is_empty() {
            let (values, residuals) = view.ranges();
            for &(y_top, y_bottom, shows_values) in &PANELS_PX {
                let range = if shows_values { values } else { residuals };
                draw_panel(
                    &root,
                    &view,
                    (y_top, y_bottom),
                    shows_values,
                    range,
                    &mut notes,
                )?;
            }
        }
        root.present().map_err(draw_err)?;
    }
    Ok(Figure::new(svg, W, H, notes.labels))
}

/// Draws the figure's title, naming the channel.
fn draw_title(root: &Area<'_>, name: &str, notes: &mut Annotations) -> Result<(), PlotError> {
    let title = format!("{name}: recording against the model, before and after the diagnosis");
    root.draw(&Text::new(
        title.clone(),
        (20, 12),
        (FAMILY, 19).into_font().color(&BLACK),
    ))
    .map_err(draw_err)?;
    let r = Placer::text_box(&title, 19.0, 20.0, 12.0);
    notes.placer.avoid(r);
    notes.keep(title, r);
    Ok(())
}

/// Draws one panel between `y_px` (top, bottom): the values against both models, or
/// the residuals before and after with the noise bands, over the shading, with its
/// legend beside it.
fn draw_panel(
    root: &Area<'_>,
    view: &ChannelView<'_>,
    (y_top, y_bottom): (i32, i32),
    values: bool,
    (lo, hi): (f64, f64),
    notes: &mut Annotations,
) -> Result<(), PlotError> {
    let area = root
        .clone()
        .shrink((0, y_top), (LEGEND_X as u32, (y_bottom - y_top) as u32));
    let (ylo, yhi) = nice_range(lo, hi);
    let mut chart = panel_chart(&area, view, (ylo, yhi), values)?;
    // Shading under everything: held-out orbits, then eclipses.
    shade_held_out_and_eclipses(&mut chart, view.s, &view.axis, (ylo, yhi))?;
    if values {
        draw_values(&mut chart, view)?;
    } else {
        draw_residuals(&mut chart, view)?;
    }
    let (_, yr) = chart.plotting_area().get_pixel_range();
    // The legend beside the panel.
    super::legend(
        root,
        &mut notes.placer,
        &mut notes.labels,
        LEGEND_X,
        yr.start as f64,
        &legend_entries(view, values),
    )?;
    Ok(())
}

/// Draws a panel's axes and grid over the recording's time and `y` (the values in
/// the channel's unit, or the residuals); the time axis is described under the
/// residuals.
fn panel_chart<'a, 'b>(
    area: &'a Area<'b>,
    view: &ChannelView<'_>,
    (ylo, yhi): (f64, f64),
    values: bool,
) -> Result<Chart<'a, 'b>, PlotError> {
    let (x0, x1) = (view.axis.x0, view.axis.x1);
    let mut chart = ChartBuilder::on(area)
        .margin_left(10)
        .margin_right(10)
        .x_label_area_size(if values { 30 } else { 50 })
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, ylo..yhi)
        .map_err(draw_err)?;
    let ystep = nice_step(yhi - ylo, 6.0);
    let ydec = decimals(ystep);
    let xstep = nice_step(x1 - x0, 10.0);
    let xdec = decimals(xstep);
    let yfmt = move |v: &f64| format!("{v:.ydec$}");
    let xfmt = move |v: &f64| format!("{v:.xdec$}");
    let ydesc = if values {
        format!("{} ({})", view.name, view.unit)
    } else {
        format!("recorded − model ({})", view.res_unit)
    };
    let mut mesh = chart.configure_mesh();
    mesh.y_desc(ydesc)
        .y_label_formatter(&yfmt)
        .x_label_formatter(&xfmt)
        .y_labels(((yhi - ylo) / ystep).round() as usize + 1)
        .x_labels(((x1 - x0) / xstep).round() as usize + 1)
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(225, 225, 225))
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 15));
    if !values {
        mesh.x_desc(format!(
            "time since the scenario's t = 0 ({})",
            view.axis.unit
        ));
    }
    mesh.draw().map_err(draw_err)?;
    Ok(chart)
}

/// Shades a diagnosis's held-out orbits, then the model's eclipses, over `y` (the
/// shading of both the channel figure and the overview).
pub(super) fn shade_held_out_and_eclipses(
    chart: &mut Chart<'_, '_>,
    s: &Series,
    axis: &TimeAxis,
    (ylo, yhi): (f64, f64),
) -> Result<(), PlotError> {
    let held = (
        axis.x(s.train_end_s),
        axis.x(s.holdout_end_s.max(s.train_end_s)),
    );
    if held.0 < axis.x1 {
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(held.0, ylo), (held.1.min(axis.x1), yhi)],
                HELD_OUT.filled(),
            )))
            .map_err(draw_err)?;
    }
    chart
        .draw_series(s.eclipses.iter().map(|&(a, b)| {
            Rectangle::new(
                [(axis.x(a), ylo), (axis.x(b), yhi)],
                ECLIPSE.mix(0.8).filled(),
            )
        }))
        .map_err(draw_err)?;
    Ok(())
}

/// Draws the models as lines over every time they were computed (as the overview
/// does: on their own grid, through the recording's gaps), then the recording's
/// readings over them as dots.
fn draw_values(chart: &mut Chart<'_, '_>, view: &ChannelView<'_>) -> Result<(), PlotError> {
    let (s, c, readings) = (view.s, view.c, &view.readings);
    for (segs, color) in super::model_lines(s, c) {
        for seg in segs {
            super::fine::line(
                chart,
                seg.into_iter().map(|(t, v)| (view.axis.x(t), v)),
                color,
                2.0,
            )?;
        }
    }
    chart
        .draw_series(
            readings
                .iter()
                .map(|p| Circle::new((p.t, p.recorded), 2, RECORDED.mix(0.6).filled())),
        )
        .map_err(draw_err)?;
    Ok(())
}

/// Draws the noise bands (±3σ, ±1σ) and the residuals as dots: after the diagnosis
/// first, before over it (the baseline's residual is the one to see).
fn draw_residuals(chart: &mut Chart<'_, '_>, view: &ChannelView<'_>) -> Result<(), PlotError> {
    let (x0, x1, sigma) = (view.axis.x0, view.axis.x1, view.sigma);
    if sigma.is_finite() {
        for (k, a) in [(3.0, 0.35), (1.0, 0.5)] {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x0, -k * sigma), (x1, k * sigma)],
                    RGBColor(200, 200, 200).mix(a).filled(),
                )))
                .map_err(draw_err)?;
        }
    }
    chart
        .draw_series(
            view.readings
                .iter()
                .map(|p| Circle::new((p.t, p.recorded - p.corrected), 2, AFTER.mix(0.8).filled())),
        )
        .map_err(draw_err)?;
    chart
        .draw_series(
            view.readings
                .iter()
                .map(|p| Circle::new((p.t, p.recorded - p.baseline), 2, BEFORE.mix(0.7).filled())),
        )
        .map_err(draw_err)?;
    Ok(())
}

/// The legend of the values' panel, or of the residuals' (with the noise when known).
fn legend_entries(view: &ChannelView<'_>, values: bool) -> Vec<(String, Swatch)> {
    let mut entries: Vec<(String, Swatch)> = if values {
        vec![
            ("recorded".into(), Swatch::Dot(RECORDED)),
            ("baseline model".into(), Swatch::Line(BEFORE, 3)),
            ("corrected model".into(), Swatch::Line(AFTER, 3)),
            ("eclipse".into(), Swatch::Patch(ECLIPSE)),
            ("held out (never fitted)".into(), Swatch::Patch(HELD_OUT)),
        ]
    } else {
        vec![
            ("before (baseline)".into(), Swatch::Dot(BEFORE)),
            ("after (corrected)".into(), Swatch::Dot(AFTER)),
        ]
    };
    if !values && view.sigma.is_finite() {
        entries.push((
            format!("noise ±1σ, ±3σ (σ = {:.3} {})", view.sigma, view.res_unit),
            Swatch::Patch(RGBColor(200, 200, 200)),
        ));
    }
    entries
}

//! The figure of one recording channel in a diagnosis: above, the recording against
//! the baseline and the corrected model; below, the residual before and after with the
//! noise bands. Eclipses and the held-out orbits are shaded in both, the legend sits
//! beside the plots (never over the data), and time is in the unit of `plot` (hours up
//! to three days, then days).

use plotters::prelude::*;

use super::labels::Placer;
use super::{
    AFTER, BEFORE, ECLIPSE, FAMILY, Figure, HELD_OUT, Label, PlotError, Swatch, decimals, draw_err,
    nice_range, nice_step, time_unit,
};
use crate::diagnose::Series;

const W: u32 = 1200;
const H: u32 = 760;
const LEGEND_X: i32 = 930;
const RECORDED: RGBColor = RGBColor(60, 60, 60);

/// The figure of channel `c` of `s`.
pub fn channel(s: &Series, c: usize) -> Result<Figure, PlotError> {
    let name = &s.channels[c];
    let is_temp = s.units[c] != "um";
    // Values as recorded (the channel's own unit); residuals in K or µm.
    let unit = s
        .value_units
        .get(c)
        .copied()
        .unwrap_or(if is_temp { "K" } else { "µm" });
    let res_unit = if is_temp { "K" } else { "µm" };
    let sigma = s.noise.get(c).copied().unwrap_or(f64::NAN);
    let span = s.time_s.last().copied().unwrap_or(1.0).max(1.0);
    let (unit_s, tunit) = time_unit(span);
    let tx = |t: f64| t / unit_s;
    let (x0, x1) = (0.0, tx(span));
    // (t, recorded, baseline, corrected) where there is a reading
    let pts: Vec<(f64, f64, f64, f64)> = s
        .time_s
        .iter()
        .enumerate()
        .filter_map(|(j, &t)| {
            s.recorded[c][j].map(|v| (tx(t), v, s.baseline[c][j], s.corrected[c][j]))
        })
        .filter(|p| p.1.is_finite() && p.2.is_finite() && p.3.is_finite())
        .collect();
    let mut svg = String::new();
    let mut labels = Vec::new();
    let mut placer = Placer::new();
    {
        let root = SVGBackend::with_string(&mut svg, (W, H)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let title = format!("{name}: recording against the model, before and after the diagnosis");
        root.draw(&Text::new(
            title.clone(),
            (20, 12),
            (FAMILY, 19).into_font().color(&BLACK),
        ))
        .map_err(draw_err)?;
        let r = Placer::text_box(&title, 19.0, 20.0, 12.0);
        placer.avoid(r);
        labels.push(Label {
            text: title,
            rect: r,
        });
        if pts.is_empty() {
            root.present().map_err(draw_err)?;
            drop(root);
            return Ok(Figure {
                svg,
                width: W,
                height: H,
                labels,
            });
        }
        let (mut vlo, mut vhi) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut rlo, mut rhi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &pts {
            vlo = vlo.min(p.1.min(p.2).min(p.3));
            vhi = vhi.max(p.1.max(p.2).max(p.3));
            for r in [p.1 - p.2, p.1 - p.3] {
                rlo = rlo.min(r);
                rhi = rhi.max(r);
            }
        }
        if sigma.is_finite() {
            rlo = rlo.min(-3.0 * sigma);
            rhi = rhi.max(3.0 * sigma);
        }
        let held = (tx(s.train_end_s), tx(s.holdout_end_s.max(s.train_end_s)));
        let panels = [(46, 400, true), (420, 740, false)];
        for &(y_top, y_bottom, values) in &panels {
            let area = root
                .clone()
                .shrink((0, y_top), (LEGEND_X as u32, (y_bottom - y_top) as u32));
            let (ylo, yhi) = if values {
                nice_range(vlo, vhi)
            } else {
                nice_range(rlo, rhi)
            };
            let mut chart = ChartBuilder::on(&area)
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
                format!("{name} ({unit})")
            } else {
                format!("recorded − model ({res_unit})")
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
                mesh.x_desc(format!("time since the recording's start ({tunit})"));
            }
            mesh.draw().map_err(draw_err)?;
            // Shading under everything: held-out orbits, then eclipses.
            if held.0 < x1 {
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(held.0, ylo), (held.1.min(x1), yhi)],
                        HELD_OUT.filled(),
                    )))
                    .map_err(draw_err)?;
            }
            chart
                .draw_series(s.eclipses.iter().map(|&(a, b)| {
                    Rectangle::new([(tx(a), ylo), (tx(b), yhi)], ECLIPSE.mix(0.8).filled())
                }))
                .map_err(draw_err)?;
            if values {
                // The models, then the recording over them.
                chart
                    .draw_series(LineSeries::new(
                        pts.iter().map(|p| (p.0, p.2)),
                        BEFORE.stroke_width(2),
                    ))
                    .map_err(draw_err)?;
                chart
                    .draw_series(LineSeries::new(
                        pts.iter().map(|p| (p.0, p.3)),
                        AFTER.stroke_width(2),
                    ))
                    .map_err(draw_err)?;
                chart
                    .draw_series(
                        pts.iter()
                            .map(|p| Circle::new((p.0, p.1), 2, RECORDED.mix(0.6).filled())),
                    )
                    .map_err(draw_err)?;
            } else {
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
                // After first, before over it: the baseline's residual is the one to see.
                chart
                    .draw_series(
                        pts.iter()
                            .map(|p| Circle::new((p.0, p.1 - p.3), 2, AFTER.mix(0.8).filled())),
                    )
                    .map_err(draw_err)?;
                chart
                    .draw_series(
                        pts.iter()
                            .map(|p| Circle::new((p.0, p.1 - p.2), 2, BEFORE.mix(0.7).filled())),
                    )
                    .map_err(draw_err)?;
            }
            let (_, yr) = chart.plotting_area().get_pixel_range();
            // The legend beside the panel.
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
            if !values && sigma.is_finite() {
                entries.push((
                    format!("noise ±1σ, ±3σ (σ = {sigma:.3} {res_unit})"),
                    Swatch::Patch(RGBColor(200, 200, 200)),
                ));
            }
            super::legend(
                &root,
                &mut placer,
                &mut labels,
                LEGEND_X,
                yr.start as f64,
                &entries,
            )?;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(Figure {
        svg,
        width: W,
        height: H,
        labels,
    })
}

//! The figures of a margins run: the distribution of the smallest backlash (histogram
//! and empirical CDF, the minimum allowed and the 95/95 bound marked, the verdict and
//! the counts on the figure) and the tornado chart of the Spearman sensitivities (every
//! key path in full, each ρ with its 95 % interval, weak ones pale, a constant input
//! said as such rather than drawn as 0).

use plotters::chart::DualCoordChartContext;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::labels::{Placer, Rect, Side};
use super::{
    Annotations, Area, FAMILY, Figure, Label, PlotError, decimals, draw_err, nice_step, plot_rect,
    text_width,
};

/// What the distribution figure shows.
#[derive(Debug, Clone)]
pub struct DistributionInput<'a> {
    pub title: String,
    /// The smallest backlash of each valid sample, µm.
    pub values: &'a [f64],
    pub limit_um: f64,
    pub bound_um: Option<f64>,
    pub bins: usize,
    pub pass: bool,
    /// Samples below the minimum allowed, and interfering.
    pub below: u64,
    pub interfering: u64,
    /// Why the verdict is what it is (the report's `reason`), drawn under it: a FAIL
    /// with no sample below the minimum is too few samples for 95/95, or samples the
    /// model could not run, which the counts alone do not say.
    pub reason: String,
}

const W: u32 = 900;
const H: u32 = 560;

fn label(
    root: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    text: &str,
    size: f64,
    pos: (f64, f64),
    color: &RGBColor,
    boxed: bool,
) -> Result<(), PlotError> {
    if boxed {
        let r = Placer::text_box(text, size, pos.0, pos.1);
        root.draw(&Rectangle::new(
            [(r.x0 as i32, r.y0 as i32), (r.x1 as i32, r.y1 as i32)],
            WHITE.mix(0.85).filled(),
        ))
        .map_err(draw_err)?;
    }
    root.draw(&Text::new(
        text.to_string(),
        (pos.0 as i32, pos.1 as i32),
        (FAMILY, size).into_font().color(color),
    ))
    .map_err(draw_err)
}

/// The distribution figure's chart: the histogram's axes (µm, samples per bin) and
/// the CDF's on the right (µm, fraction of samples).
type DualChart<'a, 'b> = DualCoordChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<RangedCoordf64, RangedCoordf64>,
    Cartesian2d<RangedCoordf64, RangedCoordf64>,
>;

/// The histogram of the smallest backlash: the x axis's range (the values, the
/// minimum allowed and the bound, with a little room), the bins and the y axis.
#[derive(Debug, Clone)]
struct Histogram {
    /// The x axis's ends, µm.
    lo: f64,
    hi: f64,
    /// A bin's width, µm.
    width: f64,
    /// Samples per bin.
    counts: Vec<usize>,
    /// The y axis's tick step and top (room above the tallest bar for the labels of
    /// the two lines).
    ystep: f64,
    ytop: f64,
}

impl Histogram {
    /// Of the valid samples `v` (ascending, at least one), in `d.bins` bins.
    fn of(v: &[f64], d: &DistributionInput<'_>) -> Histogram {
        let mut lo = v[0]
            .min(d.limit_um)
            .min(d.bound_um.unwrap_or(f64::INFINITY));
        let mut hi = v[v.len() - 1].max(d.limit_um);
        let pad = 0.05 * (hi - lo).max(1e-9);
        lo -= pad;
        hi += pad;
        let bins = d.bins.max(1);
        let width = (hi - lo) / bins as f64;
        let mut counts = vec![0usize; bins];
        for x in v {
            counts[(((x - lo) / width) as usize).min(bins - 1)] += 1;
        }
        let top = *counts.iter().max().unwrap_or(&1) as f64;
        let ystep = nice_step(top, 5.0).max(1.0);
        let ytop = ((top * 1.35) / ystep).ceil() * ystep;
        Histogram {
            lo,
            hi,
            width,
            counts,
            ystep,
            ytop,
        }
    }
}

/// Histogram (left axis: samples per bin) and empirical CDF (right axis: the fraction
/// of samples at or below), with the minimum allowed (red) and the 95/95 bound (blue).
pub fn distribution(d: &DistributionInput<'_>) -> Result<Figure, PlotError> {
    let mut v: Vec<f64> = d.values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let mut svg = String::new();
    let mut notes = Annotations::default();
    {
        let root = SVGBackend::with_string(&mut svg, (W, H)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        draw_headings(&root, d, v.len(), &mut notes)?;
        // No valid sample: the headings alone.
        if !v.is_empty() {
            let hist = Histogram::of(&v, d);
            let area = root.clone().shrink((0, 84), (W, H - 84));
            let mut chart = distribution_chart(&area, &hist)?;
            let plot_px = plot_rect(&chart);
            draw_bars(&mut chart, &hist, &mut notes.placer)?;
            draw_cdf(&mut chart, &v)?;
            draw_marks(&root, &mut chart, d, hist.ytop, &plot_px, &mut notes)?;
        }
        root.present().map_err(draw_err)?;
    }
    Ok(Figure::new(svg, W, H, notes.labels))
}

/// Draws the title, then the verdict and the counts (of `n_valid` samples) on a line
/// of their own.
fn draw_headings(
    root: &Area<'_>,
    d: &DistributionInput<'_>,
    n_valid: usize,
    notes: &mut Annotations,
) -> Result<(), PlotError> {
    let verdict = format!(
        "{}: {} samples, {} below the minimum, {} interfering",
        if d.pass { "PASS" } else { "FAIL" },
        n_valid,
        d.below,
        d.interfering
    );
    let color = if d.pass {
        RGBColor(0, 120, 60)
    } else {
        RGBColor(200, 0, 0)
    };
    let reason = clip_chars(&d.reason, 120);
    for (text, y, size, color) in [
        (d.title.as_str(), 10.0, 17.0, BLACK),
        (verdict.as_str(), 34.0, 15.0, color),
        (reason.as_str(), 52.0, 12.5, color),
    ] {
        if text.is_empty() {
            continue;
        }
        let ((x, y), r) = notes.placer.place(
            text,
            size,
            (20.0 - 6.0, y + 6.0 + 1.2 * size),
            &[Side::AboveRight],
            &Rect::new(0.0, 0.0, W as f64, H as f64),
        );
        label(root, text, size, (x, y), &color, false)?;
        notes.keep(text, r);
    }
    Ok(())
}

/// `text` cut to `n` characters, with an ellipsis when cut.
fn clip_chars(text: &str, n: usize) -> String {
    if text.chars().count() <= n {
        text.to_string()
    } else {
        text.chars().take(n - 1).chain(['…']).collect()
    }
}

/// Draws the axes and grid of the histogram (left) and of the CDF (right).
fn distribution_chart<'a, 'b>(
    area: &'a Area<'b>,
    hist: &Histogram,
) -> Result<DualChart<'a, 'b>, PlotError> {
    let (lo, hi, ystep, ytop) = (hist.lo, hist.hi, hist.ystep, hist.ytop);
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(64)
        .right_y_label_area_size(70)
        .build_cartesian_2d(lo..hi, 0.0..ytop)
        .map_err(draw_err)?
        .set_secondary_coord(lo..hi, 0.0..1.0);
    let xstep = nice_step(hi - lo, 8.0);
    let xdec = decimals(xstep);
    chart
        .configure_mesh()
        .x_desc("smallest backlash of a sample (µm)")
        .y_desc("samples per bin (bars)")
        .x_labels(((hi - lo) / xstep) as usize + 1)
        .y_labels((ytop / ystep) as usize + 1)
        .x_label_formatter(&|x| format!("{x:.xdec$}"))
        .y_label_formatter(&|y| format!("{y:.0}"))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(230, 230, 230))
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 14))
        .draw()
        .map_err(draw_err)?;
    chart
        .configure_secondary_axes()
        .y_desc("cumulative fraction of samples (line)")
        .y_labels(6)
        .y_label_formatter(&|y| format!("{y:.1}"))
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 14))
        .draw()
        .map_err(draw_err)?;
    Ok(chart)
}

/// Draws the histogram's bars (white edges between them); no label may cover a
/// drawn bar.
fn draw_bars(
    chart: &mut DualChart<'_, '_>,
    hist: &Histogram,
    placer: &mut Placer,
) -> Result<(), PlotError> {
    let (lo, width) = (hist.lo, hist.width);
    for (k, c) in hist.counts.iter().enumerate() {
        let (xa, xb) = (lo + k as f64 * width, lo + (k + 1) as f64 * width);
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(xa, 0.0), (xb, *c as f64)],
                RGBColor(150, 175, 200).filled(),
            )))
            .map_err(draw_err)?;
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(xa, 0.0), (xb, *c as f64)],
                WHITE.stroke_width(1),
            )))
            .map_err(draw_err)?;
        if *c > 0 {
            let (pa, pb) = (
                chart.backend_coord(&(xa, *c as f64)),
                chart.backend_coord(&(xb, 0.0)),
            );
            placer.avoid(Rect::new(
                pa.0 as f64,
                pa.1 as f64,
                pb.0 as f64,
                pb.1 as f64,
            ));
        }
    }
    Ok(())
}

/// Draws the empirical CDF of the samples `v` (ascending) as a step line on the
/// right axis.
fn draw_cdf(chart: &mut DualChart<'_, '_>, v: &[f64]) -> Result<(), PlotError> {
    let n = v.len() as f64;
    let cdf: Vec<(f64, f64)> = v
        .iter()
        .enumerate()
        .flat_map(|(i, x)| [(*x, i as f64 / n), (*x, (i + 1) as f64 / n)])
        .collect();
    chart
        .draw_secondary_series(LineSeries::new(cdf, BLACK.stroke_width(2)))
        .map_err(draw_err)?;
    Ok(())
}

/// Draws the minimum allowed (red) and the 95/95 bound (blue) as vertical lines up to
/// `ytop`, then labels them near their tops inside `plot_px`.
fn draw_marks(
    root: &Area<'_>,
    chart: &mut DualChart<'_, '_>,
    d: &DistributionInput<'_>,
    ytop: f64,
    plot_px: &Rect,
    notes: &mut Annotations,
) -> Result<(), PlotError> {
    let mut marks: Vec<(f64, RGBColor, String)> = vec![(
        d.limit_um,
        RGBColor(200, 0, 0),
        format!("minimum {} µm", crate::units::num(d.limit_um)),
    )];
    if let Some(b) = d.bound_um {
        marks.push((b, RGBColor(0, 80, 170), format!("95/95 bound {b:.3} µm")));
    }
    for (x, color, _) in &marks {
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(*x, 0.0), (*x, ytop)],
                color.stroke_width(2),
            )))
            .map_err(draw_err)?;
    }
    // every mark's line is off limits to every label (boxed labels would hide it)
    for (x, _, _) in &marks {
        let (px, top) = chart.backend_coord(&(*x, ytop));
        let (_, bottom) = chart.backend_coord(&(*x, 0.0));
        notes
            .placer
            .avoid_path(&[(px as f64, top as f64), (px as f64, bottom as f64)]);
    }
    for (x, color, text) in &marks {
        let (px, py) = chart.backend_coord(&(*x, ytop));
        let (pos, r) = notes.placer.place(
            text,
            14.0,
            (px as f64, py as f64 + 22.0),
            &[Side::Right, Side::Left],
            plot_px,
        );
        label(root, text, 14.0, pos, color, true)?;
        notes.keep(text.clone(), r);
    }
    Ok(())
}

/// The 95 % interval of a Spearman ρ of `n` samples (Fisher's z, standard error
/// 1.03/√(n − 3) for ranks: Fieller, Hartley & Pearson 1957).
pub fn rho_interval(rho: f64, n: usize) -> Option<(f64, f64)> {
    if !rho.is_finite() || n < 5 {
        return None;
    }
    let z = rho.clamp(-0.999_999, 0.999_999).atanh();
    let se = 1.03 / ((n - 3) as f64).sqrt();
    Some(((z - 1.96 * se).tanh(), (z + 1.96 * se).tanh()))
}

/// Tornado chart: one bar per `(key path, ρ)` in the given order, with its 95 %
/// interval (`samples` ranked); a bar whose interval holds 0 is pale; a ρ that is not
/// a number (a constant input) gets no bar and says "no variation".
pub fn tornado(title: &str, rows: &[(String, f64)], samples: usize) -> Result<Figure, PlotError> {
    let label_of = |(path, rho): &(String, f64)| {
        if rho.is_finite() {
            format!("{path} ({rho:+.2})")
        } else {
            format!("{path} (no variation)")
        }
    };
    let longest = rows
        .iter()
        .map(|r| text_width(&label_of(r), 14.0))
        .fold(0.0, f64::max);
    let left = (24.0 + longest + 12.0).max(220.0);
    let plot_w = 520.0;
    let width = (left + plot_w + 40.0).ceil() as u32;
    let row_h = 30.0;
    let top = 70.0;
    let height = (top + rows.len().max(1) as f64 * row_h + 110.0).ceil() as u32;
    let (x0, x1) = (left, left + plot_w);
    let xm = |r: f64| x0 + (r + 1.0) / 2.0 * (x1 - x0);
    let mut svg = String::new();
    let mut labels = Vec::new();
    let mut placer = Placer::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let page = Rect::new(0.0, 0.0, width as f64, height as f64);
        let ((tx, ty), r) = placer.place(title, 17.0, (14.0, 36.0), &[Side::AboveRight], &page);
        label(&root, title, 17.0, (tx, ty), &BLACK, false)?;
        labels.push(Label {
            text: title.to_string(),
            rect: r,
        });
        let y_end = top + rows.len().max(1) as f64 * row_h;
        // Grid at −1 … 1 and the axis.
        for t in [-1.0, -0.5, 0.0, 0.5, 1.0] {
            let x = xm(t) as i32;
            let style = if t == 0.0 {
                BLACK.stroke_width(1)
            } else {
                RGBColor(225, 225, 225).stroke_width(1)
            };
            root.draw(&PathElement::new(
                vec![(x, top as i32 - 6), (x, y_end as i32)],
                style,
            ))
            .map_err(draw_err)?;
            let s = match t {
                -1.0 => "−1",
                -0.5 => "−0.5",
                0.0 => "0",
                0.5 => "+0.5",
                _ => "+1",
            };
            let w = text_width(s, 13.0);
            let ((px, py), r) = placer.place(
                s,
                13.0,
                (x as f64 - w / 2.0 - 6.0, y_end + 4.0),
                &[Side::BelowRight],
                &page,
            );
            label(&root, s, 13.0, (px, py), &BLACK, false)?;
            labels.push(Label {
                text: s.to_string(),
                rect: r,
            });
        }
        for (i, row) in rows.iter().enumerate() {
            let y = top + i as f64 * row_h;
            let rho = row.1;
            let ci = rho_interval(rho, samples);
            let weak = ci.is_none_or(|(a, b)| a <= 0.0 && b >= 0.0);
            if rho.is_finite() {
                let base = if rho < 0.0 {
                    RGBColor(200, 70, 70)
                } else {
                    RGBColor(70, 120, 190)
                };
                let fill = if weak { base.mix(0.3) } else { base.mix(1.0) };
                root.draw(&Rectangle::new(
                    [
                        (xm(rho.min(0.0)) as i32, (y + 6.0) as i32),
                        (xm(rho.max(0.0)) as i32, (y + row_h - 6.0) as i32),
                    ],
                    fill.filled(),
                ))
                .map_err(draw_err)?;
                if let Some((a, b)) = ci {
                    let ym = (y + row_h / 2.0) as i32;
                    let whisker = BLACK.stroke_width(1);
                    root.draw(&PathElement::new(
                        vec![(xm(a) as i32, ym), (xm(b) as i32, ym)],
                        whisker,
                    ))
                    .map_err(draw_err)?;
                    for e in [a, b] {
                        root.draw(&PathElement::new(
                            vec![(xm(e) as i32, ym - 5), (xm(e) as i32, ym + 5)],
                            whisker,
                        ))
                        .map_err(draw_err)?;
                    }
                }
            }
            let text = label_of(row);
            let w = text_width(&text, 14.0);
            let pos = (x0 - 12.0 - w, y + row_h / 2.0 - 8.4);
            let r = Placer::text_box(&text, 14.0, pos.0, pos.1);
            label(
                &root,
                &text,
                14.0,
                pos,
                &if weak { RGBColor(110, 110, 110) } else { BLACK },
                false,
            )?;
            labels.push(Label { text, rect: r });
        }
        let notes = [
            "Spearman ρ of each input with the smallest backlash".to_string(),
            format!(
                "whiskers: 95 % interval ({samples} samples); pale: the interval holds 0, no evidence of an effect"
            ),
        ];
        for (k, n) in notes.iter().enumerate() {
            let y = y_end + 34.0 + 22.0 * k as f64;
            let ((px, py), r) = placer.place(n, 13.0, (14.0, y), &[Side::Right], &page);
            label(&root, n, 13.0, (px, py), &BLACK, false)?;
            labels.push(Label {
                text: n.clone(),
                rect: r,
            });
        }
        root.present().map_err(draw_err)?;
    }
    Ok(Figure::new(svg, width, height, labels))
}

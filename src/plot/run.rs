//! The figure of a run: node temperatures (°C) above the backlash (µm) against
//! simulated time, eclipses shaded, the smallest allowed backlash drawn and the run's
//! smallest marked and labelled. A long run (more than [`ENVELOPE_DAYS`] days or
//! [`ENVELOPE_POINTS`] samples) is drawn as the envelope of each series per orbit
//! (per day past [`MAX_BINS`] orbits): the band between its smallest and largest value.
//!
//! The input is the table of `run --csv` / `export-csv --all` (a log is read into the
//! latter first): `time_s`, `<node>_k`, `backlash_um` (or `<pair>.backlash_um`), and
//! where present `/orbit/state.sunlit`, `/orbit/state.orbit_number` and
//! `/gears/<pair>.margin_um` (which gives the smallest allowed backlash).

use plotters::prelude::*;

use super::labels::{Placer, Rect, Side};
use super::{
    ECLIPSE, Figure, Label, PlotError, Swatch, decimals, draw_err, nice_range, palette, text_width,
    time_unit,
};
use crate::constants::ZERO_CELSIUS_K;
pub use crate::run::summary::RunEnd;

/// A run longer than this many days is drawn as per-orbit envelopes.
pub const ENVELOPE_DAYS: f64 = 5.0;
/// … and so is one with more samples than this.
pub const ENVELOPE_POINTS: usize = 20_000;
/// Past this many orbits the envelope is per day.
pub const MAX_BINS: usize = 1500;
/// Temperature series drawn at most (those that swing most) …
pub const MAX_TEMPS: usize = 12;
/// … and as envelopes (more bands would hide each other).
pub const MAX_ENVELOPE_TEMPS: usize = 4;

const W: u32 = 1200;
const H: u32 = 820;
const LEGEND_X: i32 = 930;

/// The series of one run, SI as logged (K, µm, s).
#[derive(Debug, Clone)]
pub struct RunSeries {
    pub title: String,
    pub time_s: Vec<f64>,
    pub temps_k: Vec<(String, Vec<f64>)>,
    /// The exact backlash of each gear pair.
    pub backlash_um: Vec<(String, Vec<f64>)>,
    /// Each pair's smallest allowed backlash.
    pub allowed_um: Vec<(String, f64)>,
    /// 1 sunlit, 0 eclipse.
    pub sunlit: Option<Vec<f64>>,
    pub orbit: Option<Vec<f64>>,
    /// How the run ended, from the run itself (its log's end record, or the run that
    /// draws its own figure): the verdict, each pair's smallest backlash and its time,
    /// and the eclipse windows. Without it they are taken from the rows, which may
    /// have missed the run's smallest value.
    pub end: Option<RunEnd>,
}

impl RunSeries {
    /// From a table whose first column is `time_s` (see the module doc).
    pub fn from_table(
        title: &str,
        headers: &[String],
        rows: &[Vec<f64>],
    ) -> Result<RunSeries, PlotError> {
        if headers.first().map(String::as_str) != Some("time_s") {
            return Err(PlotError::Data(
                "the first column must be time_s (a `run --csv` or `export-csv` table)".into(),
            ));
        }
        if rows.is_empty() {
            return Err(PlotError::Data("the table has no rows".into()));
        }
        let col = |i: usize| rows.iter().map(|r| r[i]).collect::<Vec<f64>>();
        let mut s = RunSeries {
            title: title.to_string(),
            time_s: col(0),
            temps_k: Vec::new(),
            backlash_um: Vec::new(),
            allowed_um: Vec::new(),
            sunlit: None,
            orbit: None,
            end: None,
        };
        let mut margins: Vec<(String, Vec<f64>)> = Vec::new();
        for (i, h) in headers.iter().enumerate().skip(1) {
            if !h.starts_with('/') && h.ends_with("_k") {
                s.temps_k
                    .push((h.trim_end_matches("_k").to_string(), col(i)));
            } else if h == "backlash_um" {
                s.backlash_um.push((String::new(), col(i)));
            } else if let Some(p) = h
                .strip_suffix(".backlash_um")
                .filter(|p| !p.starts_with('/'))
            {
                s.backlash_um.push((p.to_string(), col(i)));
            } else if h == "/orbit/state.sunlit" || h == "sunlit" {
                s.sunlit = Some(col(i));
            } else if h == "/orbit/state.orbit_number" {
                s.orbit = Some(col(i));
            } else if let Some(p) = h
                .strip_prefix("/gears/")
                .and_then(|p| p.strip_suffix(".margin_um"))
            {
                margins.push((p.to_string(), col(i)));
            }
        }
        // The smallest allowed backlash: backlash − margin (the same at every row).
        for (pair, b) in &s.backlash_um {
            let m = margins
                .iter()
                // the log's topic is the pair's name made an identifier (`Stage-2` →
                // `/gears/stage_2`)
                .find(|(p, _)| p == pair || *p == crate::units::identifier(pair))
                .or_else(|| (s.backlash_um.len() == 1 && margins.len() == 1).then(|| &margins[0]));
            if let Some((_, m)) = m
                && let Some(v) = b.iter().zip(m).map(|(b, m)| b - m).find(|v| v.is_finite())
            {
                s.allowed_um.push((pair.clone(), v));
            }
        }
        if s.temps_k.is_empty() && s.backlash_um.is_empty() {
            return Err(PlotError::Data(
                "no <node>_k or backlash_um column to plot".into(),
            ));
        }
        Ok(s)
    }
}

/// Per-bin extremes of each series: bins by orbit (the log's orbit number, else from
/// eclipse entry to eclipse entry; 400 equal bins without either), by day past
/// [`MAX_BINS`] orbits.
#[derive(Debug, Clone)]
pub struct Envelope {
    /// Each bin's middle time, s.
    pub t: Vec<f64>,
    /// Per series, each bin's smallest and largest value.
    pub lo: Vec<Vec<f64>>,
    pub hi: Vec<Vec<f64>>,
    /// "orbit", "day" or "bin".
    pub per: &'static str,
}

/// The envelope of `series` (columns of `s`) that a long run's figure draws.
pub fn envelope(s: &RunSeries, series: &[&Vec<f64>]) -> Envelope {
    let period_bins = |t: &[f64]| -> Vec<usize> {
        if let Some(o) = &s.orbit {
            o.iter().map(|v| v.max(0.0) as usize).collect()
        } else if let Some(sl) = &s.sunlit {
            let mut k = 0;
            let mut out = Vec::with_capacity(sl.len());
            for (i, v) in sl.iter().enumerate() {
                if i > 0 && sl[i - 1] >= 0.5 && *v < 0.5 {
                    k += 1;
                }
                out.push(k);
            }
            out
        } else {
            let span = t.last().unwrap() - t[0];
            t.iter()
                .map(|x| ((x - t[0]) / span * 399.999) as usize)
                .collect()
        }
    };
    let mut bins = period_bins(&s.time_s);
    let mut per = if s.orbit.is_some() || s.sunlit.is_some() {
        "orbit"
    } else {
        "bin"
    };
    // distinct bins (a CSV excerpt late in a long run starts at a high orbit number)
    let n_bins = 1 + bins.windows(2).filter(|w| w[0] != w[1]).count();
    if n_bins > MAX_BINS {
        bins = s
            .time_s
            .iter()
            .map(|t| (t / 86_400.0).floor().max(0.0) as usize)
            .collect();
        per = "day";
    }
    let mut env = Envelope {
        t: Vec::new(),
        lo: vec![Vec::new(); series.len()],
        hi: vec![Vec::new(); series.len()],
        per,
    };
    let mut start = 0;
    for i in 1..=bins.len() {
        if i == bins.len() || bins[i] != bins[start] {
            env.t.push(0.5 * (s.time_s[start] + s.time_s[i - 1]));
            for (k, v) in series.iter().enumerate() {
                let w = &v[start..i];
                env.lo[k].push(w.iter().copied().fold(f64::INFINITY, f64::min));
                env.hi[k].push(w.iter().copied().fold(f64::NEG_INFINITY, f64::max));
            }
            start = i;
        }
    }
    env
}

/// Each pair's smallest backlash: (pair, time s, value µm), from the run's end when
/// known, else from the rows.
fn smallest_points(s: &RunSeries) -> Vec<(String, f64, f64)> {
    s.backlash_um
        .iter()
        .map(|(p, v)| {
            let from_end = s.end.as_ref().and_then(|e| {
                let pe = e.pairs.iter().find(|q| {
                    q.name == *p
                        || crate::units::identifier(&q.name) == *p
                        || (p.is_empty() && e.pairs.len() == 1)
                })?;
                Some((pe.t_min_s?, pe.min_backlash_um?))
            });
            let (t, m) = from_end.unwrap_or_else(|| {
                let (i, m) = v.iter().enumerate().filter(|(_, x)| x.is_finite()).fold(
                    (0, f64::INFINITY),
                    |b, (i, x)| if *x < b.1 { (i, *x) } else { b },
                );
                (s.time_s[i], m)
            });
            (p.clone(), t, m)
        })
        .collect()
}

/// The title's verdict: the run's own when known, else judged from the rows.
fn verdict_suffix(s: &RunSeries, smallest: &[(String, f64, f64)]) -> String {
    let fails = match s.end.as_ref().map(|e| e.verdict.as_str()) {
        Some("pass") => false,
        Some("fail") => true,
        Some("incomplete") => {
            return "  —  INCOMPLETE: the run stopped before its end (no pair below its minimum so far)"
                .to_string();
        }
        Some(_) => return String::new(),
        None if s.allowed_um.is_empty() => return String::new(),
        None => smallest
            .iter()
            .any(|(p, _, m)| s.allowed_um.iter().any(|(q, a)| q == p && m < a)),
    };
    if fails {
        "  —  FAIL: backlash below the smallest allowed".to_string()
    } else {
        "  —  PASS".to_string()
    }
}

/// Eclipse spans (t0, t1), s: the run's own windows when known, else from the rows'
/// sunlit flag.
fn eclipses(s: &RunSeries) -> Vec<(f64, f64)> {
    if let Some(e) = &s.end {
        return e.eclipses_s.iter().map(|w| (w[0], w[1])).collect();
    }
    let Some(sl) = &s.sunlit else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut open: Option<f64> = None;
    for (i, v) in sl.iter().enumerate() {
        match (open, *v < 0.5) {
            (None, true) => {
                open = Some(if i > 0 {
                    0.5 * (s.time_s[i - 1] + s.time_s[i])
                } else {
                    s.time_s[0]
                })
            }
            (Some(t0), false) => {
                out.push((t0, 0.5 * (s.time_s[i - 1] + s.time_s[i])));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(t0) = open {
        out.push((t0, *s.time_s.last().unwrap()));
    }
    out
}

fn range_of<'a>(v: impl Iterator<Item = &'a f64>) -> (f64, f64) {
    v.filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        })
}

/// Draws the run figure.
pub fn figure(s: &RunSeries) -> Result<Figure, PlotError> {
    let t0 = s.time_s[0];
    let span = (s.time_s.last().unwrap() - t0).max(1.0);
    let (unit_s, unit) = time_unit(span + t0);
    let long = span > ENVELOPE_DAYS * 86_400.0 || s.time_s.len() > ENVELOPE_POINTS;
    let tx = |t: f64| t / unit_s;
    let (x0, x1) = (tx(t0), tx(t0 + span));

    // The temperature series shown: all, or the MAX_TEMPS that swing most.
    let mut temps: Vec<(String, Vec<f64>)> = s
        .temps_k
        .iter()
        .map(|(n, v)| (n.clone(), v.iter().map(|k| k - ZERO_CELSIUS_K).collect()))
        .collect();
    let n_nodes = temps.len();
    let max_temps = if long { MAX_ENVELOPE_TEMPS } else { MAX_TEMPS };
    if temps.len() > max_temps {
        let swing = |v: &Vec<f64>| {
            let (a, b) = range_of(v.iter());
            b - a
        };
        temps.sort_by(|a, b| swing(&b.1).total_cmp(&swing(&a.1)).then(a.0.cmp(&b.0)));
        temps.truncate(max_temps);
    }

    let mut svg = String::new();
    let mut labels: Vec<Label> = Vec::new();
    let mut placer = Placer::new();
    {
        let root = SVGBackend::with_string(&mut svg, (W, H)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        let title_style = TextStyle::from((super::FAMILY, 20).into_font()).color(&BLACK);

        // The verdict, when the run's end or the log's margins give it.
        let smallest = smallest_points(s);
        let verdict = verdict_suffix(s, &smallest);
        let title = format!("{}{}", s.title, verdict);
        root.draw(&Text::new(title.clone(), (20, 12), title_style.clone()))
            .map_err(draw_err)?;
        labels.push(Label {
            text: title.clone(),
            rect: Placer::text_box(&title, 20.0, 20.0, 12.0),
        });
        placer.avoid(Placer::text_box(&title, 20.0, 20.0, 12.0));

        let x_desc = format!(
            "simulated time ({unit}){}",
            if long {
                format!(
                    "; each series: its smallest and largest per {}",
                    envelope(s, &[]).per
                )
            } else {
                String::new()
            }
        );
        let has_backlash = !s.backlash_um.is_empty();
        let panels: Vec<(i32, i32)> = if has_backlash && !temps.is_empty() {
            vec![(50, 420), (450, 800)]
        } else {
            vec![(50, 800)]
        };
        let ecl = if long { Vec::new() } else { eclipses(s) };
        let mut legend_top: f64 = 60.0;
        for (pi, &(y_top, y_bottom)) in panels.iter().enumerate() {
            let temps_panel = pi == 0 && !temps.is_empty();
            let area = root
                .clone()
                .shrink((0, y_top), (LEGEND_X as u32, (y_bottom - y_top) as u32));
            let (lo, hi) = if temps_panel {
                range_of(temps.iter().flat_map(|t| t.1.iter()))
            } else {
                let (a, b) = range_of(s.backlash_um.iter().flat_map(|b| b.1.iter()));
                let (c, d) = range_of(s.allowed_um.iter().map(|a| &a.1));
                (a.min(c), b.max(d))
            };
            let (ylo, yhi) = nice_range(lo, hi);
            let y_desc = if temps_panel {
                "temperature (°C)"
            } else {
                "backlash (µm)"
            };
            let mut chart = ChartBuilder::on(&area)
                .margin_left(10)
                .margin_right(10)
                .x_label_area_size(if pi + 1 == panels.len() { 50 } else { 30 })
                .y_label_area_size(70)
                .build_cartesian_2d(x0..x1, ylo..yhi)
                .map_err(draw_err)?;
            let mut mesh = chart.configure_mesh();
            let ystep = super::nice_step(yhi - ylo, 6.0);
            let ydec = decimals(ystep);
            let xstep = super::nice_step(x1 - x0, 10.0);
            let xdec = decimals(xstep);
            let yfmt = move |v: &f64| format!("{v:.ydec$}");
            let xfmt = move |v: &f64| format!("{v:.xdec$}");
            mesh.y_desc(y_desc)
                .y_label_formatter(&yfmt)
                .x_label_formatter(&xfmt)
                .y_labels(((yhi - ylo) / ystep).round() as usize + 1)
                .x_labels(((x1 - x0) / xstep).round() as usize + 1)
                .label_style((super::FAMILY, 14))
                .axis_desc_style((super::FAMILY, 15))
                .light_line_style(TRANSPARENT)
                .bold_line_style(RGBColor(215, 215, 215));
            if pi + 1 == panels.len() {
                mesh.x_desc(x_desc.clone());
            }
            mesh.draw().map_err(draw_err)?;
            // Eclipses, under the lines.
            chart
                .draw_series(
                    ecl.iter().map(|&(a, b)| {
                        Rectangle::new([(tx(a), ylo), (tx(b), yhi)], ECLIPSE.filled())
                    }),
                )
                .map_err(draw_err)?;
            let plot_px = {
                let (xr, yr) = chart.plotting_area().get_pixel_range();
                Rect::new(
                    xr.start as f64,
                    yr.start as f64,
                    xr.end as f64,
                    yr.end as f64,
                )
            };
            let series: Vec<(String, &Vec<f64>)> = if temps_panel {
                temps.iter().map(|(n, v)| (n.clone(), v)).collect()
            } else {
                s.backlash_um
                    .iter()
                    .map(|(p, v)| {
                        (
                            if p.is_empty() {
                                "backlash".into()
                            } else {
                                format!("{p} backlash")
                            },
                            v,
                        )
                    })
                    .collect()
            };
            let mut legend: Vec<String> = Vec::new();
            if long {
                let refs: Vec<&Vec<f64>> = series.iter().map(|x| x.1).collect();
                let env = envelope(s, &refs);
                for (k, (name, _)) in series.iter().enumerate() {
                    let c = palette(k);
                    let band: Vec<(f64, f64)> = env
                        .t
                        .iter()
                        .zip(&env.hi[k])
                        .map(|(t, v)| (tx(*t), *v))
                        .chain(
                            env.t
                                .iter()
                                .zip(&env.lo[k])
                                .rev()
                                .map(|(t, v)| (tx(*t), *v)),
                        )
                        .collect();
                    // Temperature envelopes as their two edges (bands of several nodes
                    // would hide each other), the backlash as a filled band.
                    if !temps_panel {
                        chart
                            .draw_series(std::iter::once(Polygon::new(band, c.mix(0.25).filled())))
                            .map_err(draw_err)?;
                    }
                    for edge in [&env.hi[k], &env.lo[k]] {
                        chart
                            .draw_series(LineSeries::new(
                                env.t.iter().zip(edge).map(|(t, v)| (tx(*t), *v)),
                                c.stroke_width(if temps_panel { 2 } else { 1 }),
                            ))
                            .map_err(draw_err)?;
                    }
                    legend.push(name.clone());
                }
            } else {
                for (k, (name, v)) in series.iter().enumerate() {
                    let c = palette(k);
                    chart
                        .draw_series(LineSeries::new(
                            s.time_s
                                .iter()
                                .zip(v.iter())
                                .filter(|(_, y)| y.is_finite())
                                .map(|(t, y)| (tx(*t), *y)),
                            c.stroke_width(if temps_panel { 1 } else { 2 }),
                        ))
                        .map_err(draw_err)?;
                    legend.push(name.clone());
                }
            }
            // The smallest allowed backlash and the run's smallest.
            if !temps_panel {
                for (pair, a) in &s.allowed_um {
                    chart
                        .draw_series(DashedLineSeries::new(
                            vec![(x0, *a), (x1, *a)],
                            8,
                            5,
                            RED.stroke_width(2),
                        ))
                        .map_err(draw_err)?;
                    let (ax, ay) = chart.backend_coord(&(x1, *a));
                    let text = format!(
                        "smallest allowed {a:.3} µm{}",
                        if pair.is_empty() {
                            String::new()
                        } else {
                            format!(" ({pair})")
                        }
                    );
                    let (pos, r) = placer.place(
                        &text,
                        14.0,
                        (ax as f64 - 4.0, ay as f64),
                        &[Side::AboveLeft, Side::BelowLeft],
                        &plot_px,
                    );
                    root.draw(&Text::new(
                        text.clone(),
                        (pos.0 as i32, pos.1 as i32),
                        (super::FAMILY, 14).into_font().color(&RED),
                    ))
                    .map_err(draw_err)?;
                    labels.push(Label { text, rect: r });
                }
                for (pair, t, m) in &smallest {
                    if !m.is_finite() {
                        continue;
                    }
                    let t = *t;
                    let (px, py) = chart.backend_coord(&(tx(t), *m));
                    root.draw(&Circle::new((px, py), 6, BLACK.stroke_width(2)))
                        .map_err(draw_err)?;
                    placer.avoid(Rect::new(
                        px as f64 - 7.0,
                        py as f64 - 7.0,
                        px as f64 + 7.0,
                        py as f64 + 7.0,
                    ));
                    let text = format!(
                        "smallest{} {m:.3} µm at {:.2} {unit}",
                        if pair.is_empty() {
                            String::new()
                        } else {
                            format!(" ({pair})")
                        },
                        tx(t)
                    );
                    let (pos, r) = placer.place(
                        &text,
                        14.0,
                        (px as f64, py as f64),
                        &[
                            Side::BelowRight,
                            Side::BelowLeft,
                            Side::AboveRight,
                            Side::AboveLeft,
                        ],
                        &plot_px,
                    );
                    root.draw(&Text::new(
                        text.clone(),
                        (pos.0 as i32, pos.1 as i32),
                        (super::FAMILY, 14).into_font().color(&BLACK),
                    ))
                    .map_err(draw_err)?;
                    labels.push(Label { text, rect: r });
                }
            }
            // The legend, right of the plot, a swatch and a name per line.
            let mut lines: Vec<String> = legend.clone();
            if temps_panel && n_nodes > temps.len() {
                lines.push(format!("({} of {n_nodes} nodes:", temps.len()));
                lines.push(" the largest swings)".to_string());
            }
            if pi == 0 && !ecl.is_empty() {
                lines.push("eclipse".to_string());
            }
            legend_top = legend_top.max(plot_px.y0);
            let entries: Vec<(String, Swatch)> = lines
                .iter()
                .enumerate()
                .map(|(k, t)| {
                    let swatch = if k < legend.len() {
                        Swatch::Line(palette(k), if long { 8 } else { 3 })
                    } else if t == "eclipse" {
                        Swatch::Patch(ECLIPSE)
                    } else {
                        Swatch::None
                    };
                    (t.clone(), swatch)
                })
                .collect();
            let placed = super::legend(
                &root,
                &mut placer,
                &mut labels,
                LEGEND_X,
                legend_top,
                &entries,
            )?;
            legend_top = placed
                .last()
                .map_or(legend_top, |r| r.y1 + 24.0)
                .max(panels.get(pi + 1).map_or(0.0, |p| p.0 as f64 + 10.0));
        }
        root.present().map_err(draw_err)?;
    }
    debug_assert!(labels.iter().all(|l| text_width(&l.text, 14.0) > 0.0));
    Ok(Figure {
        svg,
        width: W,
        height: H,
        labels,
    })
}

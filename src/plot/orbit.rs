//! The figure of `environment --plot` for a scenario without faces: the orbit's β, the
//! solar flux at the spacecraft (before any shadow) and each eclipse's length, against
//! time, eclipses shaded.

use plotters::prelude::*;

use super::labels::Placer;
use super::panels::{self, H, LEGEND_X, W};
use super::{ECLIPSE, Figure, PlotError, Swatch, draw_err, nice_range, palette, time_unit};

/// What the figure draws, at `time_s` (ascending) unless said.
#[derive(Debug, Clone)]
pub struct OrbitSeries<'a> {
    pub time_s: &'a [f64],
    pub beta_deg: &'a [f64],
    /// At the spacecraft, before any shadow.
    pub solar_flux_w_per_m2: &'a [f64],
    /// Each eclipse (umbra entry, exit), s.
    pub eclipses_s: &'a [(f64, f64)],
}

/// One panel: its axis description and its series (time, value) with their names.
struct Panel {
    desc: &'static str,
    lines: Vec<(String, Vec<(f64, f64)>)>,
    points: bool,
}

/// β, solar flux and eclipse lengths in three panels, the legend beside them.
pub fn orbit_environment(title: &str, s: &OrbitSeries<'_>) -> Result<Figure, PlotError> {
    let n = s.time_s.len();
    if n < 2 {
        return Err(PlotError::Data("fewer than two times to plot".into()));
    }
    let (t0, t1) = (s.time_s[0], s.time_s[n - 1]);
    let (unit_s, unit) = time_unit((t1 - t0).max(1.0));
    let tx = |t: f64| t / unit_s;
    let along = |v: &[f64]| -> Vec<(f64, f64)> {
        s.time_s.iter().zip(v).map(|(t, y)| (tx(*t), *y)).collect()
    };
    let lengths: Vec<(f64, f64)> = s
        .eclipses_s
        .iter()
        .map(|(a, b)| (tx(*a), (b - a) / 60.0))
        .collect();
    let rows = [
        Panel {
            desc: "β, Sun above the orbit plane (deg)",
            lines: vec![("β".into(), along(s.beta_deg))],
            points: false,
        },
        Panel {
            desc: "solar flux (W/m²)",
            lines: vec![(
                "solar flux, unshadowed".into(),
                along(s.solar_flux_w_per_m2),
            )],
            points: false,
        },
        Panel {
            desc: "eclipse length (min)",
            lines: vec![("eclipse length, at entry".into(), lengths)],
            points: true,
        },
    ];
    let mut svg = String::new();
    let mut labels = Vec::new();
    let mut placer = Placer::new();
    {
        let root = SVGBackend::with_string(&mut svg, (W, H)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        panels::title(&root, title, &mut placer, &mut labels)?;
        let mut entries: Vec<(String, Swatch)> = Vec::new();
        let shade: Vec<(f64, f64)> = s.eclipses_s.iter().map(|&(a, b)| (tx(a), tx(b))).collect();
        for (k, p) in rows.iter().enumerate() {
            let last = k + 1 == rows.len();
            let area = panels::area(&root, k);
            let (lo, hi) = p
                .lines
                .iter()
                .flat_map(|l| l.1.iter().map(|q| q.1))
                .filter(|v| v.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
            let axes = panels::Axes {
                x: (tx(t0), tx(t1)),
                y: nice_range(lo.min(0.0), hi.max(lo + 1.0)),
                desc: p.desc,
                y_decimals: None,
                time_desc: last.then(|| format!("time ({unit})")),
            };
            let mut chart = panels::chart(&area, &axes, &shade)?;
            for (name, pts) in &p.lines {
                let c = palette(k);
                super::fine::line(
                    &chart,
                    pts.iter().copied().filter(|q| q.1.is_finite()),
                    c,
                    2.0,
                )?;
                if p.points {
                    chart
                        .draw_series(pts.iter().map(|&q| Circle::new(q, 3, c.filled())))
                        .map_err(draw_err)?;
                }
                entries.push((name.clone(), Swatch::Line(c, 3)));
            }
        }
        if !s.eclipses_s.is_empty() {
            entries.push(("eclipse".into(), Swatch::Patch(ECLIPSE)));
        }
        super::legend(&root, &mut placer, &mut labels, LEGEND_X, 56.0, &entries)?;
        root.present().map_err(draw_err)?;
    }
    Ok(Figure::new(svg, W, H, labels))
}

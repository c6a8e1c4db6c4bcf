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
    Annotations, Area, Chart, ECLIPSE, Figure, PlotError, Swatch, TimeAxis, decimals, draw_err,
    nice_range, palette, plot_rect, text_width,
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
    /// A log without its end record (a killed run, a cut-off or recovered copy): its
    /// rows stop before the run did, and no verdict is drawn from them.
    pub cut_off: bool,
    /// Set by [`RunSeries::keep_nodes`]: how many nodes the table had before the user
    /// chose some (they are then all drawn, in the order given).
    pub chosen_of: Option<usize>,
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
            cut_off: false,
            chosen_of: None,
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
    /// Samples per bin, on average: with few, the drawn extremes fall short of the
    /// run's (the figure says so).
    pub samples_per_bin: f64,
}

/// Fewer samples per bin than this on average, and the figure says that its envelopes
/// miss extremes between the samples.
pub const FEW_SAMPLES_PER_BIN: f64 = 30.0;

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
    // the run's last sample alone in a bin (it ends on an orbit's or a day's start) is
    // its bin's end, not a bin of one point (drawn as a plunge to that point)
    let n = bins.len();
    if n >= 3 && bins[n - 1] != bins[n - 2] && bins[n - 2] == bins[n - 3] {
        bins[n - 1] = bins[n - 2];
    }
    let distinct = 1 + bins.windows(2).filter(|w| w[0] != w[1]).count();
    let mut env = Envelope {
        t: Vec::new(),
        lo: vec![Vec::new(); series.len()],
        hi: vec![Vec::new(); series.len()],
        per,
        samples_per_bin: n as f64 / distinct as f64,
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
                let pe = end_pair(e, p)?;
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

/// The failing verdicts of a pair (as `PairVerdict` serialises them), from the least
/// to the most severe, with what the title says of each.
const FAILURES: [(&str, &str); 3] = [
    ("margin_violated", "backlash below the smallest allowed"),
    (
        "interference",
        "the teeth interfere (backlash at or below zero)",
    ),
    (
        "no_valid_mesh",
        "no valid mesh (base circles overlap or the teeth lose contact)",
    ),
];

/// A pair's verdict as one of [`FAILURES`], or "pass", with its severity (0 for pass).
fn failing(verdict: &str) -> (usize, &'static str) {
    FAILURES
        .iter()
        .position(|(n, _)| *n == verdict)
        .map_or((0, "pass"), |i| (i + 1, FAILURES[i].0))
}

/// What the title says of a failing verdict.
fn failure(verdict: &str) -> &'static str {
    FAILURES
        .iter()
        .find(|(n, _)| *n == verdict)
        .map_or(FAILURES[0].1, |(_, why)| why)
}

/// The worst verdict the rows show: a pair's backlash that is not a number in some row
/// (no valid mesh: a run writes NaN only then; a false FAIL rather than a false PASS
/// for a table with holes), that reaches zero, or that falls below its minimum.
fn verdict_of_rows(s: &RunSeries, smallest: &[(String, f64, f64)]) -> &'static str {
    let mut worst = "pass";
    for (p, v) in &s.backlash_um {
        let verdict = if v.iter().any(|x| x.is_nan()) {
            "no_valid_mesh"
        } else {
            let m = smallest
                .iter()
                .find(|(q, _, _)| q == p)
                .map_or(f64::INFINITY, |x| x.2);
            let below = s.allowed_um.iter().any(|(q, a)| q == p && m < *a);
            match (m <= 0.0, below) {
                (true, _) => "interference",
                (false, true) => "margin_violated",
                _ => "pass",
            }
        };
        if failing(verdict).0 > failing(worst).0 {
            worst = verdict;
        }
    }
    worst
}

/// The title's verdict: the run's own when known, else judged from the rows.
fn verdict_suffix(s: &RunSeries, smallest: &[(String, f64, f64)]) -> String {
    let worst = s.end.as_ref().map_or_else(
        || verdict_of_rows(s, smallest),
        |e| {
            e.pairs
                .iter()
                .map(|p| failing(&p.verdict))
                .max_by_key(|f| f.0)
                .map_or("pass", |f| f.1)
        },
    );
    let fails = match s.end.as_ref().map(|e| e.verdict.as_str()) {
        Some("pass") => false,
        Some("fail") => true,
        Some("incomplete") => {
            return "  —  INCOMPLETE: the run stopped before its end (no pair below its minimum so far)"
                .to_string();
        }
        Some(_) => return String::new(),
        // without the smallest allowed, rows can still show a failure (no mesh, or
        // teeth that interfere), never a pass
        None if s.allowed_um.is_empty() && worst == "pass" => return String::new(),
        None => {
            let fails = worst != "pass";
            // rows that stop before the run did can fail it, not pass it
            if s.cut_off && !fails {
                return "  —  INCOMPLETE: the log holds no verdict (a killed run, a cut-off or recovered copy)"
                    .to_string();
            }
            fails
        }
    };
    if fails {
        format!(
            "  —  FAIL: {}{}",
            failure(worst),
            if s.cut_off {
                " (the log holds no verdict)"
            } else {
                ""
            }
        )
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

/// What every panel of the run figure shares: the series shown, the time axis, the
/// eclipses, each pair's smallest backlash and where the panels go.
struct RunLayout<'s> {
    s: &'s RunSeries,
    /// The temperature series shown, °C: all, those chosen (`--nodes`), or the
    /// [`MAX_TEMPS`] (on a long run [`MAX_ENVELOPE_TEMPS`]) that swing most.
    temps_c: Vec<(String, Vec<f64>)>,
    /// The run's nodes, shown or not.
    n_nodes: usize,
    /// Drawn as per-bin envelopes (a long run).
    long: bool,
    axis: TimeAxis,
    /// Eclipse spans (t0, t1), s; none shaded on a long run.
    eclipses_s: Vec<(f64, f64)>,
    /// Each pair's smallest backlash: (pair, time s, value µm).
    smallest: Vec<(String, f64, f64)>,
    /// Each panel's top and bottom, px: temperatures above the backlash, or either alone.
    panels_px: Vec<(i32, i32)>,
}

impl<'s> RunLayout<'s> {
    /// The layout of `s`'s figure.
    fn new(s: &'s RunSeries) -> RunLayout<'s> {
        let t0 = s.time_s[0];
        let span = (s.time_s.last().unwrap() - t0).max(1.0);
        let long = span > ENVELOPE_DAYS * 86_400.0 || s.time_s.len() > ENVELOPE_POINTS;
        let (temps_c, n_nodes) = shown_temps_c(s, long);
        let panels_px = if !s.backlash_um.is_empty() && !temps_c.is_empty() {
            vec![(50, 420), (450, 800)]
        } else {
            vec![(50, 800)]
        };
        RunLayout {
            s,
            temps_c,
            n_nodes,
            long,
            axis: TimeAxis::new(t0, span),
            eclipses_s: if long { Vec::new() } else { eclipses(s) },
            smallest: smallest_points(s),
            panels_px,
        }
    }

    /// Panel `pi` shows the temperatures (else the backlash).
    fn temps_panel(&self, pi: usize) -> bool {
        pi == 0 && !self.temps_c.is_empty()
    }

    /// The range of the values a panel shows (the backlash's with the smallest allowed).
    fn value_range(&self, temps_panel: bool) -> (f64, f64) {
        if temps_panel {
            range_of(self.temps_c.iter().flat_map(|t| t.1.iter()))
        } else {
            let (a, b) = range_of(self.s.backlash_um.iter().flat_map(|b| b.1.iter()));
            let (c, d) = range_of(self.s.allowed_um.iter().map(|a| &a.1));
            (a.min(c), b.max(d))
        }
    }

    /// The description of the time axis (and on a long run, of the envelopes).
    fn time_desc(&self) -> String {
        format!(
            "simulated time ({}){}",
            self.axis.unit,
            if self.long {
                let env = envelope(self.s, &[]);
                let thin = if env.samples_per_bin < FEW_SAMPLES_PER_BIN {
                    format!(
                        " of the log's {:.0} samples per {}: extremes between them are not drawn",
                        env.samples_per_bin, env.per
                    )
                } else {
                    String::new()
                };
                format!(
                    "; each series: its smallest and largest per {}{thin}",
                    env.per
                )
            } else {
                String::new()
            }
        )
    }

    /// The series a panel draws, each with its name in the legend.
    fn series(&self, temps_panel: bool) -> Vec<(String, &Vec<f64>)> {
        if temps_panel {
            self.temps_c.iter().map(|(n, v)| (n.clone(), v)).collect()
        } else {
            self.s
                .backlash_um
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
        }
    }
}

/// The end record's entry of the pair a table calls `p`: its exact name first, then the
/// name made an identifier (a log's topic: `Stage-1` → `stage_1`, which another pair may
/// be called exactly), then the only pair for a table's bare `backlash_um`.
fn end_pair<'e>(e: &'e RunEnd, p: &str) -> Option<&'e crate::run::summary::PairEnd> {
    e.pairs
        .iter()
        .find(|q| q.name == p)
        .or_else(|| {
            e.pairs
                .iter()
                .find(|q| crate::units::identifier(&q.name) == p)
        })
        .or_else(|| (p.is_empty() && e.pairs.len() == 1).then(|| &e.pairs[0]))
}

impl RunSeries {
    /// Sets how the run ended, and takes from it each pair's smallest allowed backlash
    /// where the rows do not give it (a CSV has no margin column): the limit line is on
    /// the figure whatever the table was.
    pub fn with_end(mut self, end: Option<RunEnd>) -> RunSeries {
        if let Some(e) = &end {
            for (p, _) in &self.backlash_um {
                let known = self.allowed_um.iter().any(|(q, _)| q == p);
                if !known && let Some(a) = end_pair(e, p).and_then(|q| q.min_allowed_um) {
                    self.allowed_um.push((p.clone(), a));
                }
            }
        }
        self.end = end;
        self
    }

    /// Keeps the temperatures of the nodes `names`, in that order (a name given twice
    /// once); an unknown name is an error that lists the nodes there are.
    pub fn keep_nodes(&mut self, names: &[String]) -> Result<(), PlotError> {
        let total = self.temps_k.len();
        let mut kept: Vec<(String, Vec<f64>)> = Vec::new();
        for n in names {
            if kept.iter().any(|(k, _)| k == n) {
                continue;
            }
            match self.temps_k.iter().find(|(k, _)| k == n) {
                Some(t) => kept.push(t.clone()),
                None => {
                    let there: Vec<&str> = self.temps_k.iter().map(|(k, _)| k.as_str()).collect();
                    return Err(PlotError::Data(format!(
                        "--nodes: no node `{n}` in the table (its nodes: {})",
                        there.join(", ")
                    )));
                }
            }
        }
        self.temps_k = kept;
        self.chosen_of = Some(total);
        Ok(())
    }
}

/// The temperature series shown, °C, and the number of nodes: all, the ones chosen
/// (`--nodes`), or the ones that swing most.
fn shown_temps_c(s: &RunSeries, long: bool) -> (Vec<(String, Vec<f64>)>, usize) {
    let mut temps: Vec<(String, Vec<f64>)> = s
        .temps_k
        .iter()
        .map(|(n, v)| (n.clone(), v.iter().map(|k| k - ZERO_CELSIUS_K).collect()))
        .collect();
    let n_nodes = s.chosen_of.unwrap_or(temps.len());
    let max_temps = if long { MAX_ENVELOPE_TEMPS } else { MAX_TEMPS };
    if s.chosen_of.is_none() && temps.len() > max_temps {
        let swing = |v: &Vec<f64>| {
            let (a, b) = range_of(v.iter());
            b - a
        };
        temps.sort_by(|a, b| swing(&b.1).total_cmp(&swing(&a.1)).then(a.0.cmp(&b.0)));
        temps.truncate(max_temps);
    }
    (temps, n_nodes)
}

/// Draws the run figure.
pub fn figure(s: &RunSeries) -> Result<Figure, PlotError> {
    let layout = RunLayout::new(s);
    let mut svg = String::new();
    let mut notes = Annotations::default();
    {
        let root = SVGBackend::with_string(&mut svg, (W, H)).into_drawing_area();
        root.fill(&WHITE).map_err(draw_err)?;
        draw_title(&root, &layout, &mut notes)?;
        let mut legend_top: f64 = 60.0;
        for pi in 0..layout.panels_px.len() {
            legend_top = draw_panel(&root, &layout, pi, legend_top, &mut notes)?;
        }
        root.present().map_err(draw_err)?;
    }
    let labels = notes.labels;
    debug_assert!(labels.iter().all(|l| text_width(&l.text, 14.0) > 0.0));
    Ok(Figure::new(svg, W, H, labels))
}

/// Draws the title with the verdict, when the run's end or the log's margins give it.
fn draw_title(
    root: &Area<'_>,
    layout: &RunLayout<'_>,
    notes: &mut Annotations,
) -> Result<(), PlotError> {
    let title_style = TextStyle::from((super::FAMILY, 20).into_font()).color(&BLACK);
    let verdict = verdict_suffix(layout.s, &layout.smallest);
    let title = format!("{}{}", layout.s.title, verdict);
    root.draw(&Text::new(title.clone(), (20, 12), title_style))
        .map_err(draw_err)?;
    notes.keep(title.clone(), Placer::text_box(&title, 20.0, 20.0, 12.0));
    notes
        .placer
        .avoid(Placer::text_box(&title, 20.0, 20.0, 12.0));
    Ok(())
}

/// Draws panel `pi`: its axes, the eclipses, its series, on the backlash panel the
/// smallest allowed and the run's smallest, and its legend (from `legend_top` down);
/// returns where the next panel's legend may start.
fn draw_panel(
    root: &Area<'_>,
    layout: &RunLayout<'_>,
    pi: usize,
    legend_top: f64,
    notes: &mut Annotations,
) -> Result<f64, PlotError> {
    let temps_panel = layout.temps_panel(pi);
    let (y_top, y_bottom) = layout.panels_px[pi];
    let area = root
        .clone()
        .shrink((0, y_top), (LEGEND_X as u32, (y_bottom - y_top) as u32));
    let (lo, hi) = layout.value_range(temps_panel);
    let (ylo, yhi) = nice_range(lo, hi);
    let last = pi + 1 == layout.panels_px.len();
    let mut chart = panel_chart(&area, layout, (ylo, yhi), temps_panel, last)?;
    // Eclipses, under the lines.
    let axis = &layout.axis;
    chart
        .draw_series(
            layout.eclipses_s.iter().map(|&(a, b)| {
                Rectangle::new([(axis.x(a), ylo), (axis.x(b), yhi)], ECLIPSE.filled())
            }),
        )
        .map_err(draw_err)?;
    let plot_px = plot_rect(&chart);
    let series = layout.series(temps_panel);
    // a long run's per-bin envelopes, once: drawn, and kept clear of the labels
    let env = layout.long.then(|| {
        let refs: Vec<&Vec<f64>> = series.iter().map(|x| x.1).collect();
        envelope(layout.s, &refs)
    });
    let legend = match &env {
        Some(env) => draw_envelopes(&mut chart, layout, &series, env, temps_panel)?,
        None => draw_lines(&mut chart, layout, &series, temps_panel)?,
    };
    // The smallest allowed backlash and the run's smallest, their labels off the
    // curves and the allowed lines (in the legend when the plot has no such room).
    let mut overflow = Vec::new();
    if !temps_panel {
        avoid_curves(&chart, layout, &series, env.as_ref(), notes);
        // labels 2 px inside the axes, off their tick marks
        let inside = Rect::new(
            plot_px.x0 + 2.0,
            plot_px.y0 + 2.0,
            plot_px.x1 - 2.0,
            plot_px.y1 - 2.0,
        );
        draw_allowed(root, &mut chart, layout, &inside, notes, &mut overflow)?;
        draw_smallest(root, &chart, layout, &inside, notes, &mut overflow)?;
    }
    draw_panel_legend(
        root,
        layout,
        pi,
        &legend,
        &overflow,
        legend_top.max(plot_px.y0),
        notes,
    )
}

/// Draws a panel's axes and grid over the run's time and `y` (°C or µm); the time
/// axis is described on the bottom panel (`last`).
fn panel_chart<'a, 'b>(
    area: &'a Area<'b>,
    layout: &RunLayout<'_>,
    (ylo, yhi): (f64, f64),
    temps_panel: bool,
    last: bool,
) -> Result<Chart<'a, 'b>, PlotError> {
    let (x0, x1) = (layout.axis.x0, layout.axis.x1);
    let y_desc = if temps_panel {
        "temperature (°C)"
    } else {
        "backlash (µm)"
    };
    let mut chart = ChartBuilder::on(area)
        .margin_left(10)
        .margin_right(10)
        .x_label_area_size(if last { 50 } else { 30 })
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
    if last {
        mesh.x_desc(layout.time_desc());
    }
    mesh.draw().map_err(draw_err)?;
    Ok(chart)
}

/// Draws a long run's series as their per-bin envelopes `env`: temperatures as their two edges
/// (bands of several nodes would hide each other), the backlash as a filled band;
/// returns the legend's names.
fn draw_envelopes(
    chart: &mut Chart<'_, '_>,
    layout: &RunLayout<'_>,
    series: &[(String, &Vec<f64>)],
    env: &Envelope,
    temps_panel: bool,
) -> Result<Vec<String>, PlotError> {
    let tx = |t: f64| layout.axis.x(t);
    let mut legend = Vec::new();
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
        if !temps_panel {
            super::fine::area(chart, band, c, 0.25)?;
        }
        for edge in [&env.hi[k], &env.lo[k]] {
            super::fine::line(
                chart,
                env.t.iter().zip(edge).map(|(t, v)| (tx(*t), *v)),
                c,
                if temps_panel { 2.0 } else { 1.0 },
            )?;
        }
        legend.push(name.clone());
    }
    Ok(legend)
}

/// Draws each series as lines through its finite samples, broken where a value is not
/// finite (a pair's backlash while it has no valid mesh); returns the legend's names.
fn draw_lines(
    chart: &mut Chart<'_, '_>,
    layout: &RunLayout<'_>,
    series: &[(String, &Vec<f64>)],
    temps_panel: bool,
) -> Result<Vec<String>, PlotError> {
    let mut legend = Vec::new();
    for (k, (name, v)) in series.iter().enumerate() {
        let c = palette(k);
        let points: Vec<(f64, f64)> = layout
            .s
            .time_s
            .iter()
            .zip(v.iter())
            .map(|(t, y)| (layout.axis.x(*t), *y))
            .collect();
        for run in points.split(|(_, y)| !y.is_finite()) {
            super::fine::line(
                chart,
                run.iter().copied(),
                c,
                if temps_panel { 1.0 } else { 2.0 },
            )?;
        }
        legend.push(name.clone());
    }
    Ok(legend)
}

/// `text` in lines no wider than `width` px at `size_px`, broken at spaces (a word
/// longer than the width stays whole on its line).
fn wrap(text: &str, width: f64, size_px: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split(' ') {
        match lines.last_mut() {
            Some(l) if text_width(&format!("{l} {word}"), size_px) <= width => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// How far (in steps of its height) a label of the backlash panel may slide from what
/// it names before it goes to the legend instead.
const NEAR: usize = 2;

/// Tells the placer where the panel's curves (or a long run's envelope `env`: its
/// edges and the band between them) and the allowed lines run, in px.
fn avoid_curves(
    chart: &Chart<'_, '_>,
    layout: &RunLayout<'_>,
    series: &[(String, &Vec<f64>)],
    env: Option<&Envelope>,
    notes: &mut Annotations,
) {
    let px = |x: f64, y: f64| {
        let (a, b) = chart.backend_coord(&(x, y));
        (a as f64, b as f64)
    };
    let axis = &layout.axis;
    if let Some(env) = env {
        for (edge_hi, edge_lo) in env.hi.iter().zip(&env.lo) {
            for edge in [edge_hi, edge_lo] {
                let pts: Vec<(f64, f64)> = env
                    .t
                    .iter()
                    .zip(edge)
                    .map(|(t, v)| px(axis.x(*t), *v))
                    .collect();
                notes.placer.avoid_path(&pts);
            }
            // the filled band between the edges: no label inside it either
            for k in 0..env.t.len().saturating_sub(1) {
                let (x0, x1) = (axis.x(env.t[k]), axis.x(env.t[k + 1]));
                let hi = edge_hi[k].max(edge_hi[k + 1]);
                let lo = edge_lo[k].min(edge_lo[k + 1]);
                if hi.is_finite() && lo.is_finite() {
                    let (a, b) = (px(x0, hi), px(x1, lo));
                    notes.placer.avoid(Rect::new(a.0, a.1, b.0, b.1));
                }
            }
        }
    } else {
        // as draw_lines draws them: one line through the finite samples
        for (_, v) in series {
            let pts: Vec<(f64, f64)> = layout
                .s
                .time_s
                .iter()
                .zip(v.iter())
                .filter(|(_, y)| y.is_finite())
                .map(|(t, y)| px(axis.x(*t), *y))
                .collect();
            notes.placer.avoid_path(&pts);
        }
    }
    for (_, a) in &layout.s.allowed_um {
        notes.placer.avoid_path(&[px(axis.x0, *a), px(axis.x1, *a)]);
    }
}

/// Draws each pair's smallest allowed backlash as a dashed red line, labelled at its
/// right end.
fn draw_allowed(
    root: &Area<'_>,
    chart: &mut Chart<'_, '_>,
    layout: &RunLayout<'_>,
    plot_px: &Rect,
    notes: &mut Annotations,
    overflow: &mut Vec<(String, Swatch)>,
) -> Result<(), PlotError> {
    let (x0, x1) = (layout.axis.x0, layout.axis.x1);
    for (pair, a) in &layout.s.allowed_um {
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
        let Some((pos, r)) = notes.placer.try_place(
            &text,
            14.0,
            (ax as f64 - 4.0, ay as f64),
            &[Side::AboveLeft, Side::BelowLeft],
            plot_px,
            NEAR,
        ) else {
            // no room off the curves: the legend says it
            overflow.push((text, Swatch::Dashed(RED, 2)));
            continue;
        };
        root.draw(&Text::new(
            text.clone(),
            (pos.0 as i32, pos.1 as i32),
            (super::FAMILY, 14).into_font().color(&RED),
        ))
        .map_err(draw_err)?;
        notes.keep(text, r);
    }
    Ok(())
}

/// Marks each pair's smallest backlash with a circle and labels it with its value and
/// time.
fn draw_smallest(
    root: &Area<'_>,
    chart: &Chart<'_, '_>,
    layout: &RunLayout<'_>,
    plot_px: &Rect,
    notes: &mut Annotations,
    overflow: &mut Vec<(String, Swatch)>,
) -> Result<(), PlotError> {
    let axis = &layout.axis;
    for (pair, t, m) in &layout.smallest {
        if !m.is_finite() {
            continue;
        }
        let t = *t;
        let (px, py) = chart.backend_coord(&(axis.x(t), *m));
        root.draw(&Circle::new((px, py), 6, BLACK.stroke_width(2)))
            .map_err(draw_err)?;
        notes.placer.avoid(Rect::new(
            px as f64 - 7.0,
            py as f64 - 7.0,
            px as f64 + 7.0,
            py as f64 + 7.0,
        ));
        let text = format!(
            "smallest{} {m:.3} µm at {:.3} {}",
            if pair.is_empty() {
                String::new()
            } else {
                format!(" ({pair})")
            },
            axis.x(t),
            axis.unit
        );
        let Some((pos, r)) = notes.placer.try_place(
            &text,
            14.0,
            (px as f64, py as f64),
            &[
                Side::BelowRight,
                Side::BelowLeft,
                Side::AboveRight,
                Side::AboveLeft,
            ],
            plot_px,
            NEAR,
        ) else {
            // no room off the curves: the legend says it beside a circle like the mark
            overflow.push((text, Swatch::Ring(BLACK)));
            continue;
        };
        root.draw(&Text::new(
            text.clone(),
            (pos.0 as i32, pos.1 as i32),
            (super::FAMILY, 14).into_font().color(&BLACK),
        ))
        .map_err(draw_err)?;
        notes.keep(text, r);
    }
    Ok(())
}

/// Draws panel `pi`'s legend right of the plot from `top` down, a swatch and a name
/// per line (with a note when not every node is shown, and the eclipse's shade under
/// the first panel's); returns where the next panel's legend may start.
fn draw_panel_legend(
    root: &Area<'_>,
    layout: &RunLayout<'_>,
    pi: usize,
    legend: &[String],
    extra: &[(String, Swatch)],
    top: f64,
    notes: &mut Annotations,
) -> Result<f64, PlotError> {
    let mut lines: Vec<String> = legend.to_vec();
    let shown = layout.temps_c.len();
    if layout.temps_panel(pi) && layout.n_nodes > shown {
        lines.push(format!("({shown} of {} nodes:", layout.n_nodes));
        lines.push(if layout.s.chosen_of.is_some() {
            " chosen by --nodes)".to_string()
        } else {
            " the largest swings)".to_string()
        });
    }
    if pi == 0 && !layout.eclipses_s.is_empty() {
        lines.push("eclipse".to_string());
    }
    let mut entries: Vec<(String, Swatch)> = lines
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let swatch = if k < legend.len() {
                Swatch::Line(palette(k), if layout.long { 8 } else { 3 })
            } else if t == "eclipse" {
                Swatch::Patch(ECLIPSE)
            } else {
                Swatch::None
            };
            (t.clone(), swatch)
        })
        .collect();
    // a label moved here from the plot may be longer than the column: wrapped at
    // spaces, its first line beside its swatch
    let room = f64::from(W) - f64::from(LEGEND_X) - 34.0 - 8.0;
    for (text, swatch) in extra {
        for (k, line) in wrap(text, room, 14.0).into_iter().enumerate() {
            entries.push((line, if k == 0 { *swatch } else { Swatch::None }));
        }
    }
    let placed = super::legend(
        root,
        &mut notes.placer,
        &mut notes.labels,
        LEGEND_X,
        top,
        &entries,
    )?;
    Ok(placed.last().map_or(top, |r| r.y1 + 24.0).max(
        layout
            .panels_px
            .get(pi + 1)
            .map_or(0.0, |p| p.0 as f64 + 10.0),
    ))
}

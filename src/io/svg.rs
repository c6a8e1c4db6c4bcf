//! Plots of a margin report as SVG, written as text: no plotting backend, no system
//! font (the viewer renders the labels with its own sans-serif), no GUI. Two kinds:
//! the distribution of the smallest backlash (histogram and empirical CDF, with the
//! minimum allowed and the 95/95 bound marked) and a tornado chart of the Spearman
//! sensitivities.

use std::fmt::Write as _;

const W: f64 = 720.0;
const H: f64 = 420.0;
const LEFT: f64 = 70.0;
const RIGHT: f64 = 30.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 60.0;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn header(o: &mut String, title: &str) {
    header_w(o, title, W);
}

/// The SVG header of a figure `w` wide.
fn header_w(o: &mut String, title: &str, w: f64) {
    let _ = write!(
        o,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{H}\" viewBox=\"0 0 {w} {H}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"{w}\" height=\"{H}\" fill=\"white\"/>\n<text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">{}</text>\n",
        w / 2.0,
        esc(title)
    );
}

/// Round tick step for a span (1, 2 or 5 × 10ⁿ, about 6 ticks).
fn step(span: f64) -> f64 {
    let raw = span / 6.0;
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p)
}

/// The plot area's axes: bottom (at `y0`) and left (up to `y1`).
fn frame(o: &mut String, y0: f64, y1: f64) {
    let _ = writeln!(
        o,
        "<line x1=\"{LEFT}\" y1=\"{y0}\" x2=\"{}\" y2=\"{y0}\" stroke=\"black\"/>\n<line x1=\"{LEFT}\" y1=\"{y0}\" x2=\"{LEFT}\" y2=\"{y1}\" stroke=\"black\"/>",
        W - RIGHT
    );
}

/// Round ticks with labels along the bottom axis for values lo … hi.
fn x_ticks(o: &mut String, lo: f64, hi: f64, y0: f64) {
    let s = step(hi - lo);
    let mut t = (lo / s).ceil() * s;
    while t <= hi {
        let x = x_of(t, lo, hi);
        let _ = writeln!(
            o,
            "<line x1=\"{x:.2}\" y1=\"{y0}\" x2=\"{x:.2}\" y2=\"{}\" stroke=\"black\"/><text x=\"{x:.2}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
            y0 + 5.0,
            y0 + 18.0,
            crate::units::num(t)
        );
        t += s;
    }
}

/// The axis titles: `x` under the plot, `y` turned along the left side.
fn axis_labels(o: &mut String, x: &str, y: &str, y0: f64, y1: f64) {
    let _ = writeln!(
        o,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n<text x=\"18\" y=\"{}\" transform=\"rotate(-90 18 {})\" text-anchor=\"middle\">{}</text>",
        (LEFT + W - RIGHT) / 2.0,
        H - 18.0,
        esc(x),
        (y0 + y1) / 2.0,
        (y0 + y1) / 2.0,
        esc(y)
    );
}

/// The plot area's x position of value `v` on [lo, hi].
pub fn x_of(v: f64, lo: f64, hi: f64) -> f64 {
    LEFT + (v - lo) / (hi - lo) * (W - LEFT - RIGHT)
}

/// Histogram (bars, left axis: samples) and empirical CDF (line, right scale 0 … 1) of
/// `values` (µm), with vertical lines at `limit` (red) and `bound` (blue, when given).
pub fn distribution(
    title: &str,
    values: &[f64],
    limit: f64,
    bound: Option<f64>,
    bins: usize,
) -> String {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let mut o = String::new();
    header(&mut o, title);
    if v.is_empty() {
        o.push_str("</svg>\n");
        return o;
    }
    let mut lo = v[0].min(limit).min(bound.unwrap_or(f64::INFINITY));
    let mut hi = v[v.len() - 1].max(limit);
    let pad = 0.05 * (hi - lo).max(1e-9);
    lo -= pad;
    hi += pad;
    let bins = bins.max(1);
    let width = (hi - lo) / bins as f64;
    let mut counts = vec![0usize; bins];
    for x in &v {
        counts[(((x - lo) / width) as usize).min(bins - 1)] += 1;
    }
    let top = *counts.iter().max().unwrap_or(&1) as f64;
    let (y0, y1) = (H - BOTTOM, TOP);
    let y_of = |c: f64| y0 - c / top * (y0 - y1);
    // axes and ticks
    frame(&mut o, y0, y1);
    x_ticks(&mut o, lo, hi, y0);
    axis_labels(
        &mut o,
        "smallest normal backlash per sample, µm",
        "samples per bin; CDF (line, 0 … 1)",
        y0,
        y1,
    );
    // counts on the left, CDF on the right
    for f in [0.0, 0.5, 1.0] {
        let y = y0 - f * (y0 - y1);
        let _ = writeln!(
            o,
            "<text x=\"{}\" y=\"{:.2}\" text-anchor=\"end\">{}</text><text x=\"{}\" y=\"{:.2}\">{}</text>",
            LEFT - 6.0,
            y + 4.0,
            crate::units::num((f * top).round()),
            W - RIGHT + 4.0,
            y + 4.0,
            crate::units::num(f)
        );
    }
    // bars
    for (k, c) in counts.iter().enumerate() {
        let (xa, xb) = (
            x_of(lo + k as f64 * width, lo, hi),
            x_of(lo + (k + 1) as f64 * width, lo, hi),
        );
        let y = y_of(*c as f64);
        let _ = writeln!(
            o,
            "<rect class=\"bar\" x=\"{xa:.2}\" y=\"{y:.2}\" width=\"{:.2}\" height=\"{:.2}\" fill=\"#9ab\" stroke=\"white\"/>",
            xb - xa,
            y0 - y
        );
    }
    // CDF
    let n = v.len() as f64;
    let mut path = String::new();
    for (i, x) in v.iter().enumerate() {
        let px = x_of(*x, lo, hi);
        let (ya, yb) = (
            y0 - i as f64 / n * (y0 - y1),
            y0 - (i + 1) as f64 / n * (y0 - y1),
        );
        let _ = write!(
            path,
            "{}{px:.2},{ya:.2} L{px:.2},{yb:.2} ",
            if i == 0 { "M" } else { "L" }
        );
    }
    let _ = writeln!(
        o,
        "<path class=\"cdf\" d=\"{}\" fill=\"none\" stroke=\"black\"/>",
        path.trim_end()
    );
    let mark = |o: &mut String, class: &str, v: f64, colour: &str, label: String| {
        let x = x_of(v, lo, hi);
        let _ = writeln!(
            o,
            "<line class=\"{class}\" x1=\"{x:.2}\" y1=\"{y0}\" x2=\"{x:.2}\" y2=\"{y1}\" stroke=\"{colour}\" stroke-width=\"2\"/><text x=\"{:.2}\" y=\"{}\" fill=\"{colour}\">{}</text>",
            x + 4.0,
            y1 + 14.0,
            esc(&label)
        );
    };
    mark(
        &mut o,
        "limit",
        limit,
        "#c00",
        format!("minimum {} µm", crate::units::num(limit)),
    );
    if let Some(b) = bound {
        mark(&mut o, "bound", b, "#05a", format!("95/95 bound {b:.3} µm"));
    }
    o.push_str("</svg>\n");
    o
}

/// Tornado chart: one horizontal bar per `(label, ρ)`, largest |ρ| on top, ρ in −1 … 1.
pub fn tornado(title: &str, rows: &[(String, f64)]) -> String {
    let mut o = String::new();
    // the labels (key path and ρ) fit left of the bars: about 6.8 px per character of
    // the 12 px sans-serif, and the figure widens with them
    let longest = rows
        .iter()
        .map(|(l, _)| l.chars().count() + 16)
        .max()
        .unwrap_or(0) as f64;
    let left = (12.0 + 6.8 * longest).max(330.0);
    let width = left + (W - RIGHT - 330.0) + RIGHT;
    header_w(&mut o, title, width);
    let (x0, x1) = (left, width - RIGHT);
    let mid = (x0 + x1) / 2.0;
    let row_h = ((H - TOP - BOTTOM) / rows.len().max(1) as f64).min(40.0);
    let _ = writeln!(
        o,
        "<line x1=\"{mid}\" y1=\"{TOP}\" x2=\"{mid}\" y2=\"{}\" stroke=\"black\"/>",
        H - BOTTOM
    );
    for (k, t) in [-1.0, -0.5, 0.0, 0.5, 1.0].iter().enumerate() {
        let x = mid + t * (x1 - x0) / 2.0;
        let _ = writeln!(
            o,
            "<text x=\"{x:.2}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
            H - BOTTOM + 18.0,
            ["−1", "−0.5", "0", "+0.5", "+1"][k]
        );
    }
    let _ = writeln!(
        o,
        "<text x=\"{mid}\" y=\"{}\" text-anchor=\"middle\">Spearman ρ with the smallest backlash</text>",
        H - 18.0
    );
    for (i, (label, rho)) in rows.iter().enumerate() {
        let y = TOP + i as f64 * row_h + 4.0;
        let r = if rho.is_finite() { *rho } else { 0.0 };
        let x = mid + r.min(0.0) * (x1 - x0) / 2.0;
        let _ = writeln!(
            o,
            "<rect class=\"bar\" x=\"{x:.2}\" y=\"{y:.2}\" width=\"{:.2}\" height=\"{:.2}\" fill=\"{}\"/><text x=\"{}\" y=\"{:.2}\" text-anchor=\"end\">{} ({})</text>",
            r.abs() * (x1 - x0) / 2.0,
            row_h - 8.0,
            if r < 0.0 { "#c55" } else { "#58b" },
            left - 8.0,
            y + row_h / 2.0,
            esc(label),
            // a constant input or output has no rank correlation: no bar, no number
            if rho.is_finite() {
                format!("{rho:+.2}")
            } else {
                "no variation".to_string()
            }
        );
    }
    o.push_str("</svg>\n");
    o
}

/// Residual of one recording channel against time, before (the baseline, grey) and
/// after (the corrected model, blue), with the noise band (±1σ, ±3σ) and the held-out
/// orbits shaded.
pub fn residuals(s: &crate::diagnose::Series, c: usize) -> String {
    let name = &s.channels[c];
    let unit = if s.units[c] == "um" { "µm" } else { "K" };
    let sigma = s.noise.get(c).copied().unwrap_or(f64::NAN);
    let mut o = String::new();
    header(
        &mut o,
        &format!("{name}: residual (recorded − model), before and after"),
    );
    let pts: Vec<(f64, f64, f64)> = s
        .time_s
        .iter()
        .enumerate()
        .filter_map(|(j, &t)| {
            s.recorded[c][j].map(|v| (t / 3600.0, v - s.baseline[c][j], v - s.corrected[c][j]))
        })
        .filter(|p| p.1.is_finite() && p.2.is_finite())
        .collect();
    if pts.is_empty() {
        o.push_str("</svg>\n");
        return o;
    }
    let (t_lo, t_hi) = (0.0, pts.last().unwrap().0.max(1e-6));
    let mut lo = pts
        .iter()
        .map(|p| p.1.min(p.2))
        .fold(f64::INFINITY, f64::min);
    let mut hi = pts
        .iter()
        .map(|p| p.1.max(p.2))
        .fold(f64::NEG_INFINITY, f64::max);
    if sigma.is_finite() {
        lo = lo.min(-3.0 * sigma);
        hi = hi.max(3.0 * sigma);
    }
    let pad = 0.05 * (hi - lo).max(1e-9);
    lo -= pad;
    hi += pad;
    let (y0, y1) = (H - BOTTOM, TOP);
    let y_of = |v: f64| y0 - (v - lo) / (hi - lo) * (y0 - y1);
    let x_of_t = |t: f64| x_of(t, t_lo, t_hi);
    // held-out orbits
    let (ha, hb) = (s.train_end_s / 3600.0, s.holdout_end_s / 3600.0);
    if ha.is_finite() && ha < t_hi {
        let (xa, xb) = (x_of_t(ha), x_of_t(hb.min(t_hi)));
        let _ = writeln!(
            o,
            "<rect class=\"holdout\" x=\"{xa:.2}\" y=\"{y1}\" width=\"{:.2}\" height=\"{:.2}\" fill=\"#fef3d8\"/><text x=\"{:.2}\" y=\"{}\" fill=\"#a70\">held out (never fitted)</text>",
            xb - xa,
            y0 - y1,
            xa + 4.0,
            y0 - 8.0
        );
    }
    if sigma.is_finite() {
        for (k, fill) in [(3.0, "#eeeeee"), (1.0, "#dddddd")] {
            let (ya, yb) = (y_of(k * sigma), y_of(-k * sigma));
            let _ = writeln!(
                o,
                "<rect class=\"noise\" x=\"{LEFT}\" y=\"{ya:.2}\" width=\"{:.2}\" height=\"{:.2}\" fill=\"{fill}\" fill-opacity=\"0.7\"/>",
                W - RIGHT - LEFT,
                yb - ya
            );
        }
    }
    frame(&mut o, y0, y1);
    x_ticks(&mut o, t_lo, t_hi, y0);
    let sv = step(hi - lo);
    let mut v = (lo / sv).ceil() * sv;
    while v <= hi {
        let y = y_of(v);
        let _ = writeln!(
            o,
            "<line x1=\"{}\" y1=\"{y:.2}\" x2=\"{LEFT}\" y2=\"{y:.2}\" stroke=\"black\"/><text x=\"{}\" y=\"{:.2}\" text-anchor=\"end\">{}</text>",
            LEFT - 5.0,
            LEFT - 7.0,
            y + 4.0,
            crate::units::num((v / sv).round() * sv + 0.0)
        );
        v += sv;
    }
    axis_labels(
        &mut o,
        "time since t = 0, h",
        &format!("residual, {unit}"),
        y0,
        y1,
    );
    for (class, k, colour) in [("before", 1, "#888888"), ("after", 2, "#1f5fbf")] {
        let mut path = String::new();
        for p in &pts {
            let v = if k == 1 { p.1 } else { p.2 };
            let _ = write!(path, "M{:.1},{:.1}h0.01", x_of_t(p.0), y_of(v));
        }
        let _ = writeln!(
            o,
            "<path class=\"{class}\" d=\"{path}\" stroke=\"{colour}\" stroke-width=\"2.2\" stroke-linecap=\"round\" fill=\"none\"/>"
        );
    }
    let _ = writeln!(
        o,
        "<text x=\"{}\" y=\"{}\" fill=\"#888888\">● before (baseline)</text><text x=\"{}\" y=\"{}\" fill=\"#1f5fbf\">● after (corrected)</text><text x=\"{}\" y=\"{}\" fill=\"#777\">bands: ±1σ, ±3σ noise</text>",
        LEFT + 10.0,
        y1 + 14.0,
        LEFT + 170.0,
        y1 + 14.0,
        LEFT + 330.0,
        y1 + 14.0
    );
    o.push_str("</svg>\n");
    o
}

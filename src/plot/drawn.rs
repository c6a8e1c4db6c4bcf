//! What a figure's SVG draws, read back from its text: each `<text>`'s box at the font
//! size written into the file (plotters writes a requested size divided by 1.24) and
//! each `<polyline>` (curves, reference lines, axes). Tests check the labels a figure
//! placed against these, not against what the placer believed.

use super::Rect;

/// A text as drawn: its content and its box (the font's ascent to descent, the
/// advance widths), px, y down.
#[derive(Debug, Clone, PartialEq)]
pub struct DrawnText {
    pub text: String,
    pub rect: Rect,
}

/// The drawn texts (rotated ones, the axis titles, left out) and polylines of `svg`.
pub fn read(svg: &str) -> (Vec<DrawnText>, Vec<Vec<(f64, f64)>>) {
    let mut texts = Vec::new();
    let mut lines = Vec::new();
    let mut rest = svg;
    while let Some(at) = rest.find('<') {
        rest = &rest[at + 1..];
        let end = rest.find('>').unwrap_or(rest.len());
        let tag = &rest[..end];
        if let Some(attrs) = tag.strip_prefix("text ") {
            let body_end = rest.find("</text>").unwrap_or(end);
            let body = rest.get(end + 1..body_end).unwrap_or("");
            if let Some(t) = text_box(attrs, &unescape(body.trim_matches('\n'))) {
                texts.push(t);
            }
        } else if let Some(attrs) = tag.strip_prefix("polyline ") {
            let pts: Vec<(f64, f64)> = attr(attrs, "points")
                .unwrap_or("")
                .split_whitespace()
                .filter_map(|p| {
                    let (x, y) = p.split_once(',')?;
                    Some((x.parse().ok()?, y.parse().ok()?))
                })
                .collect();
            if pts.len() >= 2 {
                lines.push(pts);
            }
        }
        rest = &rest[end.min(rest.len())..];
    }
    (texts, lines)
}

/// The value of attribute `name` in a tag's attribute text.
pub(crate) fn attr<'a>(attrs: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let padded_at = format!(" {attrs}").find(&key)?;
    let start = padded_at + key.len() - 1;
    let v = attrs.get(start..)?;
    Some(&v[..v.find('"')?])
}

pub(crate) fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// Where a `<text>` with attributes `attrs` and words `body` is drawn, px: from its
/// x, y, dy (em, or ex: the font's x-height, of its size), anchor and font size.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Placement {
    pub size: f64,
    /// Where its first glyph's advance starts.
    pub x0: f64,
    pub baseline: f64,
    /// The advance widths, added.
    pub width: f64,
}

pub(crate) fn placement(attrs: &str, body: &str) -> Option<Placement> {
    let x: f64 = attr(attrs, "x")?.parse().ok()?;
    let y: f64 = attr(attrs, "y")?.parse().ok()?;
    let size: f64 = attr(attrs, "font-size")?.parse().ok()?;
    let dy = match attr(attrs, "dy") {
        Some(d) if d.ends_with("em") => d.trim_end_matches("em").parse::<f64>().ok()? * size,
        Some(d) if d.ends_with("ex") => {
            d.trim_end_matches("ex").parse::<f64>().ok()? * size * super::font_x_height()
        }
        Some(d) => d.parse().ok()?,
        None => 0.0,
    };
    let width = super::advance_width(body, size);
    let x0 = match attr(attrs, "text-anchor") {
        Some("middle") => x - width / 2.0,
        Some("end") => x - width,
        _ => x,
    };
    Some(Placement {
        size,
        x0,
        baseline: y + dy,
        width,
    })
}

/// The box of one `<text>` (not rotated): its [`placement`], the font's ascent to
/// descent.
fn text_box(attrs: &str, body: &str) -> Option<DrawnText> {
    if attr(attrs, "transform").is_some() || body.is_empty() {
        return None;
    }
    let p = placement(attrs, body)?;
    let (ascent, descent) = super::font_extent();
    Some(DrawnText {
        text: body.to_string(),
        rect: Rect::new(
            p.x0,
            p.baseline - ascent * p.size,
            p.x0 + p.width,
            p.baseline + descent * p.size,
        ),
    })
}

/// Whether the segment from `a` to `b` passes through the inside of `r`.
pub fn segment_crosses(a: (f64, f64), b: (f64, f64), r: &Rect) -> bool {
    // Liang–Barsky: clip the segment to the box; it crosses when something is left
    // (strictly inside, so a line along an edge does not count).
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - r.x0),
        (dx, r.x1 - a.0),
        (-dy, a.1 - r.y0),
        (dy, r.y1 - a.1),
    ] {
        if p == 0.0 {
            if q <= 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 < t1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_drawn_texts_and_lines_are_read_back() {
        let svg = r##"<svg><text x="100" y="50" dy="0.76em" text-anchor="end" font-family="sans-serif" font-size="11.29" fill="#000">a &amp; b</text>
<text x="10" y="220" dy="0.76em" font-size="12" transform="rotate(270, 10, 220)">axis</text>
<polyline fill="none" stroke="#000" points="0,0 10,10 "/></svg>"##;
        let (texts, lines) = read(svg);
        assert_eq!(texts.len(), 1, "the rotated axis title is left out");
        assert_eq!(texts[0].text, "a & b");
        let w = crate::plot::advance_width("a & b", 11.29);
        assert!(
            (texts[0].rect.x1 - 100.0).abs() < 1e-9
                && (texts[0].rect.x0 - (100.0 - w)).abs() < 1e-9
        );
        assert_eq!(lines, vec![vec![(0.0, 0.0), (10.0, 10.0)]]);
        let r = Rect::new(2.0, 2.0, 4.0, 4.0);
        assert!(segment_crosses((0.0, 0.0), (10.0, 10.0), &r));
        assert!(!segment_crosses((0.0, 5.0), (10.0, 5.0), &r));
        assert!(
            !segment_crosses((0.0, 4.0), (10.0, 4.0), &r),
            "along an edge"
        );
        assert!(segment_crosses((3.0, 0.0), (3.0, 10.0), &r));
    }
}

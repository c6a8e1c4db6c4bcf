//! Text as outlines: every `<text>` of a figure replaced by the glyphs of the embedded
//! DejaVu Sans, so the SVG looks the same in every browser, editor and converter
//! whatever fonts it has (plotters names only `font-family="sans-serif"`, which each
//! reader resolves to its own font, and `0.5ex` to its own x-height).
//!
//! Each glyph used is defined once in `<defs>` (font units, y up) and placed with
//! `<use>`; a text becomes a group carrying its words in `aria-label`, so it is still
//! read out and found by search. Glyphs advance by the font's advance widths, exactly
//! as [`super::advance_width`] measures labels (no kerning), so the outlines fill the
//! boxes the labels were placed in.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use super::drawn::{Placement, attr, placement, unescape};

/// `svg` with its texts drawn as outlines (texts in bold or italic, which the embedded
/// regular face cannot draw, and texts with a character it lacks are left as text).
pub fn outline_text(svg: &str) -> String {
    let face = super::face();
    let mut used = BTreeSet::new();
    let mut body = String::with_capacity(svg.len());
    let mut rest = svg;
    while let Some(at) = rest.find("<text ") {
        let tail = &rest[at..];
        let (Some(open_end), Some(close)) = (tail.find('>'), tail.find("</text>")) else {
            break;
        };
        if close < open_end {
            break;
        }
        body.push_str(&rest[..at]);
        let attrs = &tail["<text ".len()..open_end];
        let text = unescape(tail[open_end + 1..close].trim_matches('\n'));
        match outlined(face, attrs, &text, &mut used) {
            Some(group) => body.push_str(&group),
            None => body.push_str(&tail[..close + "</text>".len()]),
        }
        rest = &tail[close + "</text>".len()..];
    }
    body.push_str(rest);
    if used.is_empty() {
        return body;
    }
    let mut defs = String::from("<defs>\n");
    for &gid in &used {
        let mut path = PathData(String::new());
        if face
            .outline_glyph(ttf_parser::GlyphId(gid), &mut path)
            .is_some()
        {
            let _ = writeln!(defs, "<path id=\"g{gid}\" d=\"{}\"/>", path.0.trim_end());
        }
    }
    defs.push_str("</defs>\n");
    // after the root's opening tag, which also declares the xlink namespace
    match body
        .find("<svg")
        .and_then(|s| body[s..].find('>').map(|e| s + e))
    {
        Some(end) => {
            let mut head = body[..end].to_string();
            if !head.contains("xmlns:xlink") {
                head.push_str(" xmlns:xlink=\"http://www.w3.org/1999/xlink\"");
            }
            format!(
                "{head}>\n{defs}{}",
                body[end + 1..].trim_start_matches('\n')
            )
        }
        None => body,
    }
}

/// One text's group of glyphs, or `None` to keep it as text.
fn outlined(
    face: &ttf_parser::Face<'_>,
    attrs: &str,
    text: &str,
    used: &mut BTreeSet<u16>,
) -> Option<String> {
    // bold or italic, or a character the font has no glyph for: left to the reader's
    // fonts (a browser falls back to one that has it)
    if attr(attrs, "font-weight").is_some()
        || attr(attrs, "font-style").is_some()
        || text
            .chars()
            .any(|c| !c.is_whitespace() && face.glyph_index(c).is_none())
    {
        return None;
    }
    let Placement {
        size,
        x0: pen,
        baseline,
        ..
    } = placement(attrs, text)?;
    let scale = size / face.units_per_em() as f64;
    let mut g = format!(
        "<g aria-label=\"{}\" fill=\"{}\" opacity=\"{}\"",
        escape(text),
        attr(attrs, "fill").unwrap_or("#000000"),
        attr(attrs, "opacity").unwrap_or("1")
    );
    if let Some(t) = attr(attrs, "transform") {
        let _ = write!(g, " transform=\"{t}\"");
    }
    // the glyphs in font units from the text's start on its baseline
    let _ = writeln!(
        g,
        "><g transform=\"matrix({} 0 0 {} {} {})\">",
        num(scale, 7),
        num(-scale, 7),
        num(pen, 2),
        num(baseline, 2)
    );
    let mut advance_units = 0u32;
    for c in text.chars() {
        let gid = face.glyph_index(c);
        if let Some(id) = gid.filter(|id| face.glyph_bounding_box(*id).is_some()) {
            used.insert(id.0);
            let _ = writeln!(g, "<use xlink:href=\"#g{}\" x=\"{advance_units}\"/>", id.0);
        }
        advance_units += gid
            .and_then(|id| face.glyph_hor_advance(id))
            .unwrap_or(face.units_per_em() / 2) as u32;
    }
    g.push_str("</g>");
    g.push_str("</g>");
    Some(g)
}

/// `v` to `decimals`, without trailing zeros.
fn num(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        &s
    };
    if s == "-0" { "0".into() } else { s.to_string() }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A glyph's outline as SVG path data, font units.
struct PathData(String);

impl ttf_parser::OutlineBuilder for PathData {
    fn move_to(&mut self, x: f32, y: f32) {
        let _ = write!(self.0, "M{x} {y}");
    }
    fn line_to(&mut self, x: f32, y: f32) {
        let _ = write!(self.0, "L{x} {y}");
    }
    fn quad_to(&mut self, x1: f32, y1: f32, x: f32, y: f32) {
        let _ = write!(self.0, "Q{x1} {y1} {x} {y}");
    }
    fn curve_to(&mut self, x1: f32, y1: f32, x2: f32, y2: f32, x: f32, y: f32) {
        let _ = write!(self.0, "C{x1} {y1} {x2} {y2} {x} {y}");
    }
    fn close(&mut self) {
        self.0.push('Z');
    }
}

/// A glyph's ink box: left, top, right, bottom, px.
type Ink = (f64, f64, f64, f64);

/// What is wrong with the outlines of `outlined` against the texts of `svg` as
/// [`super::drawn::read`] measures them (read back from the outlined file: each
/// group's transform, each glyph's offset and its outline's box): a text (not
/// rotated) with no group of glyphs, or a glyph whose ink
/// leaves its text's box by more than half a pixel. Empty on a figure drawn right.
pub fn misplaced_glyphs(svg: &str, outlined: &str) -> Vec<String> {
    let face = super::face();
    let (texts, _) = super::drawn::read(svg);
    let mut groups: Vec<(String, Vec<Ink>)> = Vec::new();
    let mut rest = outlined;
    while let Some(at) = rest.find("<g aria-label=\"") {
        let tail = &rest[at..];
        let end = tail.find("</g></g>").unwrap_or(tail.len());
        let open = &tail[3..tail.find('>').unwrap_or(end)];
        let rotated = attr(open, "transform").is_some();
        let label = unescape(attr(open, "aria-label").unwrap_or(""));
        let mut ink = Vec::new();
        let m: Vec<f64> = tail[..end]
            .split("<g transform=\"matrix(")
            .nth(1)
            .and_then(|t| t.split(')').next())
            .unwrap_or("")
            .split_whitespace()
            .filter_map(|v| v.parse().ok())
            .collect();
        for u in tail[..end].split("<use ").skip(1) {
            let gid: u16 = attr(u, "xlink:href")
                .and_then(|h| h.trim_start_matches("#g").parse().ok())
                .unwrap_or(0);
            let dx: f64 = attr(u, "x").and_then(|v| v.parse().ok()).unwrap_or(0.0);
            if let (Some(b), [a, _, _, d, e, f]) = (
                face.glyph_bounding_box(ttf_parser::GlyphId(gid)),
                m.as_slice(),
            ) {
                ink.push((
                    e + a * (dx + b.x_min as f64),
                    f + d * b.y_max as f64,
                    e + a * (dx + b.x_max as f64),
                    f + d * b.y_min as f64,
                ));
            }
        }
        if !rotated {
            groups.push((label, ink));
        }
        rest = &tail[end..];
    }
    let mut out = Vec::new();
    let mut used = vec![false; groups.len()];
    for t in &texts {
        let Some(i) = (0..groups.len()).find(|&i| !used[i] && groups[i].0 == t.text) else {
            out.push(format!("{:?} has no outline", t.text));
            continue;
        };
        used[i] = true;
        let r = t.rect;
        for &(x0, y0, x1, y1) in &groups[i].1 {
            if x0 < r.x0 - 0.5 || x1 > r.x1 + 0.5 || y0 < r.y0 - 0.5 || y1 > r.y1 + 0.5 {
                out.push(format!(
                    "{:?}: a glyph's ink ({x0:.1}, {y0:.1})–({x1:.1}, {y1:.1}) leaves its box \
                     ({:.1}, {:.1})–({:.1}, {:.1})",
                    t.text, r.x0, r.y0, r.x1, r.y1
                ));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const SVG: &str = r##"<svg width="300" height="100" viewBox="0 0 300 100" xmlns="http://www.w3.org/2000/svg">
<rect x="0" y="0" width="300" height="100" fill="#FFFFFF"/>
<text x="150" y="20" dy="0.76em" text-anchor="middle" font-family="sans-serif" font-size="16" opacity="1" fill="#000000">Backlash µm &amp; °C</text>
<text x="290" y="70" dy="0.5ex" text-anchor="end" font-family="sans-serif" font-size="11.29" opacity="1" fill="#D55E00">25.659 µm, t = 8.385 h</text>
<text x="10" y="90" dy="0.76em" text-anchor="middle" font-family="sans-serif" font-size="11.29" opacity="1" fill="#000000" transform="rotate(270, 10, 90)">axis</text>
</svg>
"##;

    #[test]
    fn core_outlines_replace_texts_inside_their_boxes() {
        let out = outline_text(SVG);
        assert!(!out.contains("<text"), "{out}");
        assert!(out.contains("xmlns:xlink=") && out.contains("<defs>"));
        assert!(out.contains("aria-label=\"Backlash µm &amp; °C\""));
        assert!(out.contains("transform=\"rotate(270, 10, 90)\""));
        assert_eq!(misplaced_glyphs(SVG, &out), Vec::<String>::new());
        // a character the font lacks: that text stays text; a cut-off text is kept
        let cjk = SVG.replace(">axis<", ">轴 axis<");
        let out_cjk = outline_text(&cjk);
        assert_eq!(out_cjk.matches("<text").count(), 1);
        assert!(out_cjk.contains("轴 axis"));
        let cut = "<svg><text x=\"1\" y=\"2\" font-size=\"9\">no end";
        assert_eq!(outline_text(cut), cut);
        // a glyph moved down by 6 px (beyond the descent) is caught
        let moved = out.replacen(" 32.16)", " 38.16)", 1);
        assert!(out.contains(" 32.16)\""), "{out}");
        assert_ne!(moved, out);
        assert!(!misplaced_glyphs(SVG, &moved).is_empty());
    }

    /// The outlined figure needs no font: rendered with an empty font database it is
    /// the same picture as with DejaVu loaded, and it draws the text (the plain SVG,
    /// without fonts, draws none).
    #[test]
    fn core_outlined_svg_renders_without_fonts() {
        use resvg::{tiny_skia, usvg};
        let render = |svg: &str, fonts: bool| -> Vec<u8> {
            let mut opt = usvg::Options::default();
            if fonts {
                opt.fontdb_mut().load_font_data(super::super::FONT.to_vec());
                opt.fontdb_mut().set_sans_serif_family("DejaVu Sans");
            }
            let tree = usvg::Tree::from_str(svg, &opt).unwrap();
            let mut pm = tiny_skia::Pixmap::new(300, 100).unwrap();
            resvg::render(&tree, tiny_skia::Transform::identity(), &mut pm.as_mut());
            pm.data().to_vec()
        };
        let out = outline_text(SVG);
        let ink = |px: &[u8]| px.chunks(4).filter(|p| p[0] < 128).count();
        assert_eq!(render(&out, false), render(&out, true));
        assert!(ink(&render(&out, false)) > 200);
        assert!(
            ink(&render(SVG, false)) < 10,
            "text without fonts should not draw"
        );
        // and what it draws is where the font would draw it: most ink in common
        let (a, b) = (render(&out, false), render(SVG, true));
        let dark = |px: &[u8], i: usize| px[4 * i] < 160;
        let both = (0..300 * 100)
            .filter(|&i| dark(&a, i) && dark(&b, i))
            .count();
        let either = (0..300 * 100)
            .filter(|&i| dark(&a, i) || dark(&b, i))
            .count();
        assert!(
            both as f64 > 0.6 * either as f64,
            "{both} of {either} dark pixels shared"
        );
    }
}

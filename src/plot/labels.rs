//! Label placement: each label goes to the first of its candidate places that stays
//! inside its area and overlaps neither a label placed before nor a region to avoid
//! (a bar, a plotted point) nor a drawn line (a curve, a reference line); failing all,
//! it slides down (or up) in steps of its own
//! height until it fits. Only a figure with no room left at all keeps an overlap, and
//! [`super::Figure::overlapping_labels`] reports it.

use super::{drawn_px, text_width};

/// A box in pixels, y down.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub x0: f64,
    pub y0: f64,
    pub x1: f64,
    pub y1: f64,
}

impl Rect {
    pub fn new(x0: f64, y0: f64, x1: f64, y1: f64) -> Rect {
        Rect {
            x0: x0.min(x1),
            y0: y0.min(y1),
            x1: x0.max(x1),
            y1: y0.max(y1),
        }
    }

    pub fn intersects(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }

    pub fn contains(&self, o: &Rect) -> bool {
        o.x0 >= self.x0 - 0.5
            && o.x1 <= self.x1 + 0.5
            && o.y0 >= self.y0 - 0.5
            && o.y1 <= self.y1 + 0.5
    }

    fn shifted(&self, dx: f64, dy: f64) -> Rect {
        Rect::new(self.x0 + dx, self.y0 + dy, self.x1 + dx, self.y1 + dy)
    }
}

/// Where a label may go relative to its anchor point: the box's corner or edge that
/// touches the anchor.
#[derive(Debug, Clone, Copy)]
pub enum Side {
    /// Above and to the right of the anchor.
    AboveRight,
    AboveLeft,
    BelowRight,
    BelowLeft,
    Right,
    Left,
}

/// The labels of one figure.
#[derive(Debug, Default)]
pub struct Placer {
    placed: Vec<Rect>,
    avoid: Vec<Rect>,
    /// Segments of drawn lines (curves, reference lines) no label may cross.
    lines: Vec<((f64, f64), (f64, f64))>,
}

/// Padding around a label's text, px.
const PAD: f64 = 3.0;

impl Placer {
    pub fn new() -> Placer {
        Placer::default()
    }

    /// A region no label may cover.
    pub fn avoid(&mut self, r: Rect) {
        self.avoid.push(r);
    }

    /// A drawn line (px, in drawing order) no label may cross.
    pub fn avoid_path(&mut self, points: &[(f64, f64)]) {
        self.lines.extend(points.windows(2).map(|w| (w[0], w[1])));
    }

    fn crosses_a_line(&self, r: &Rect) -> bool {
        self.lines.iter().any(|&(a, b)| {
            // a cheap test of the segment's bounds first
            a.0.max(b.0) > r.x0
                && a.0.min(b.0) < r.x1
                && a.1.max(b.1) > r.y0
                && a.1.min(b.1) < r.y1
                && super::drawn::segment_crosses(a, b, r)
        })
    }

    fn free(&self, r: &Rect, area: &Rect) -> bool {
        area.contains(r)
            && !self.placed.iter().any(|p| p.intersects(r))
            && !self.avoid.iter().any(|p| p.intersects(r))
            && !self.crosses_a_line(r)
    }

    /// The box of `text` at `size_px` (its top-left corner at `x`, `y`), padded.
    pub fn text_box(text: &str, size_px: f64, x: f64, y: f64) -> Rect {
        Rect::new(
            x - PAD,
            y - PAD,
            x + text_width(text, size_px) + PAD,
            y + 1.2 * drawn_px(size_px) + PAD,
        )
    }

    /// Places `text` near `anchor` inside `area`, trying `sides` in order; returns the
    /// top-left corner of the text and its (padded) box. The box is recorded. With no
    /// free place, it goes to the first side's place anyway (and overlaps): a caller
    /// with somewhere else to put the text uses [`Placer::try_place`].
    pub fn place(
        &mut self,
        text: &str,
        size_px: f64,
        anchor: (f64, f64),
        sides: &[Side],
        area: &Rect,
    ) -> ((f64, f64), Rect) {
        self.try_place(text, size_px, anchor, sides, area, 60)
            .unwrap_or_else(|| {
                let (pos, r) = self.candidate(text, size_px, anchor, sides[0], 0.0);
                self.placed.push(r);
                (pos, r)
            })
    }

    /// The place of `text` on `side` of `anchor`, moved down by `dy`.
    fn candidate(
        &self,
        text: &str,
        size_px: f64,
        anchor: (f64, f64),
        side: Side,
        dy: f64,
    ) -> ((f64, f64), Rect) {
        let w = text_width(text, size_px);
        let h = 1.2 * drawn_px(size_px);
        let gap = 6.0;
        let (ax, ay) = anchor;
        let (x, y) = match side {
            Side::AboveRight => (ax + gap, ay - gap - h),
            Side::AboveLeft => (ax - gap - w, ay - gap - h),
            Side::BelowRight => (ax + gap, ay + gap),
            Side::BelowLeft => (ax - gap - w, ay + gap),
            Side::Right => (ax + gap, ay - h / 2.0),
            Side::Left => (ax - gap - w, ay - h / 2.0),
        };
        ((x, y + dy), Placer::text_box(text, size_px, x, y + dy))
    }

    /// As [`Placer::place`], sliding at most `slides` steps of its height away from the
    /// anchor (a label far from what it names reads wrong), but `None` (nothing
    /// recorded) when no place is free.
    pub fn try_place(
        &mut self,
        text: &str,
        size_px: f64,
        anchor: (f64, f64),
        sides: &[Side],
        area: &Rect,
        slides: usize,
    ) -> Option<((f64, f64), Rect)> {
        let h = 1.2 * drawn_px(size_px);
        for k in 0..=slides {
            for &s in sides {
                for dy in [k as f64 * (h + 2.0), -(k as f64) * (h + 2.0)] {
                    let (pos, r) = self.candidate(text, size_px, anchor, s, dy);
                    if self.free(&r, area) {
                        self.placed.push(r);
                        return Some((pos, r));
                    }
                }
            }
        }
        None
    }

    /// Places a column of lines (a legend) starting at `top_left`, each under the one
    /// before; returns the text corners and records the boxes.
    pub fn column(
        &mut self,
        lines: &[String],
        size_px: f64,
        top_left: (f64, f64),
    ) -> Vec<((f64, f64), Rect)> {
        let mut out = Vec::new();
        let mut y = top_left.1;
        for t in lines {
            let mut r = Placer::text_box(t, size_px, top_left.0, y);
            while self
                .placed
                .iter()
                .chain(&self.avoid)
                .any(|p| p.intersects(&r))
            {
                r = r.shifted(0.0, 2.0);
                y += 2.0;
            }
            self.placed.push(r);
            out.push(((top_left.0, y), r));
            y = r.y1 + PAD + 1.0;
        }
        out
    }
}

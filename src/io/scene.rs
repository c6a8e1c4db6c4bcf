//! An optional 3-D view of each gear pair for Foxglove: the tooth outlines as
//! `foxglove.SceneUpdate` line loops in frame `gears` (metres), coloured by each gear's
//! rim temperature (blue −60 °C … red +100 °C). Outlines are drawn at their assembly
//! size: thermal displacements are micrometres.

use super::protobuf::Encoder;
use crate::gear::involute::inv;
use crate::gear::{Gear, GearPair};

/// A gear's outline placed at an x offset (the wheel sits at the centre distance), m.
pub type PlacedOutline = (f64, Vec<(f64, f64)>);

/// Outline of `g` in its own frame, tooth 0 centred at angle `rot` (rad), metres.
pub fn gear_outline_m(pair: &GearPair, g: &Gear, rot: f64) -> Vec<(f64, f64)> {
    let rb = g.base_radius_m(pair.module_m, pair.pressure_angle_rad);
    let half_base = g.base_thickness_m(pair.module_m, pair.pressure_angle_rad) / (2.0 * rb);
    let (rf, ra) = (g.root_radius_m, g.tip_radius_m);
    let half = |r: f64| {
        if r <= rb {
            half_base
        } else {
            (half_base - inv((rb / r).acos())).max(0.0)
        }
    };
    // flank radii: root, base circle, then the involute up to the tip
    let mut radii = vec![rf.min(rb)];
    if rb > rf {
        radii.push(rb);
    }
    for k in 1..=5 {
        radii.push(rb.max(rf) + (ra - rb.max(rf)) * k as f64 / 5.0);
    }
    let tau = std::f64::consts::TAU / g.teeth as f64;
    let mut pts = Vec::with_capacity(g.teeth as usize * (2 * radii.len() + 2));
    let polar = |r: f64, a: f64| (r * a.cos(), r * a.sin());
    for k in 0..g.teeth {
        let c = rot + k as f64 * tau;
        for &r in &radii {
            pts.push(polar(r, c - half(r)));
        }
        pts.push(polar(ra, c));
        for &r in radii.iter().rev() {
            pts.push(polar(r, c + half(r)));
        }
        pts.push(polar(rf, c + tau / 2.0));
    }
    pts
}

/// Colour of a temperature: blue at −60 °C to red at +100 °C.
pub fn temperature_rgb(t_k: f64) -> (f64, f64, f64) {
    let s = ((t_k - 213.15) / 160.0).clamp(0.0, 1.0);
    (
        0.15 + 0.85 * s,
        0.35 * (1.0 - (2.0 * s - 1.0).abs()) + 0.15,
        1.0 - 0.85 * s,
    )
}

/// The outlines of a pair, placed: pinion at the origin, wheel at the centre distance,
/// a pinion tooth facing a wheel tooth space.
pub fn pair_outlines_m(pair: &GearPair) -> [PlacedOutline; 2] {
    let z2 = pair.gears[1].teeth as f64;
    [
        (0.0, gear_outline_m(pair, &pair.gears[0], 0.0)),
        (
            pair.center_distance_m,
            gear_outline_m(
                pair,
                &pair.gears[1],
                std::f64::consts::PI + std::f64::consts::PI / z2,
            ),
        ),
    ]
}

/// One `foxglove.SceneUpdate` with an entity per gear.
pub fn encode_scene(
    e: &mut Encoder,
    pair_id: &str,
    outlines: &[PlacedOutline; 2],
    rim_k: [f64; 2],
    t_s: f64,
    names: [&str; 2],
) {
    let secs = t_s.floor();
    for k in 0..2 {
        let (x0, pts) = &outlines[k];
        let (r, g, b) = temperature_rgb(rim_k[k]);
        e.message(2, |ent| {
            ent.message(1, |ts| {
                ts.int64(1, secs as i64);
                ts.int64(2, ((t_s - secs) * 1e9).round().min(999_999_999.0) as i64);
            });
            ent.string(2, "gears");
            ent.string(3, &format!("{pair_id}/{}", names[k]));
            ent.message(11, |line| {
                line.int64(1, 1); // LINE_LOOP
                line.message(2, |pose| {
                    pose.message(1, |v| {
                        v.double(1, *x0);
                        v.double(2, 0.0);
                        v.double(3, 0.0);
                    });
                    pose.message(2, |q| q.double(4, 1.0));
                });
                line.double(3, 2.0);
                line.uint64(4, 1);
                for &(x, y) in pts {
                    line.message(5, |p| {
                        p.double(1, x);
                        p.double(2, y);
                    });
                }
                line.message(6, |c| {
                    c.double(1, r);
                    c.double(2, g);
                    c.double(3, b);
                    c.double(4, 1.0);
                });
            });
        });
    }
}

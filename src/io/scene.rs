//! An optional 3-D view of each gear pair for Foxglove: the tooth outlines as
//! `foxglove.SceneUpdate` line loops in frame `gears` (metres), coloured by each gear's
//! rim temperature (blue −60 °C … red +100 °C). Outlines are drawn at their assembly
//! size: thermal displacements are micrometres.

use crate::gear::involute::inv;
use crate::gear::{Gear, GearPair};
use foxglove::messages::{
    Color, LinePrimitive, Point3, Pose, Quaternion, SceneEntity, SceneUpdate, Timestamp, Vector3,
    line_primitive,
};

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

/// One `foxglove.SceneUpdate` with an entity per gear (the official `foxglove` crate's
/// message type).
pub fn scene_update(
    pair_id: &str,
    outlines: &[PlacedOutline; 2],
    rim_k: [f64; 2],
    t_s: f64,
    names: [&str; 2],
) -> SceneUpdate {
    let entities = (0..2)
        .map(|k| {
            let (x0, pts) = &outlines[k];
            let (r, g, b) = temperature_rgb(rim_k[k]);
            SceneEntity {
                timestamp: Some(timestamp(t_s)),
                frame_id: "gears".into(),
                id: format!("{pair_id}/{}", names[k]),
                lines: vec![LinePrimitive {
                    r#type: line_primitive::Type::LineLoop as i32,
                    pose: Some(Pose {
                        position: Some(Vector3 {
                            x: *x0,
                            y: 0.0,
                            z: 0.0,
                        }),
                        orientation: Some(Quaternion {
                            x: 0.0,
                            y: 0.0,
                            z: 0.0,
                            w: 1.0,
                        }),
                    }),
                    thickness: 2.0,
                    scale_invariant: true,
                    points: pts.iter().map(|&(x, y)| Point3 { x, y, z: 0.0 }).collect(),
                    color: Some(Color { r, g, b, a: 1.0 }),
                    ..Default::default()
                }],
                ..Default::default()
            }
        })
        .collect();
    SceneUpdate {
        deletions: vec![],
        entities,
    }
}

/// A simulated time as a `foxglove` timestamp: `t_s` after `origin_ns` (ns since the
/// Unix epoch; 0: seconds since t = 0).
pub fn timestamp_at(origin_ns: u64, t_s: f64) -> Timestamp {
    if origin_ns == 0 {
        return timestamp(t_s);
    }
    let total = origin_ns + super::log_schema::ns(t_s);
    Timestamp::new(
        (total / 1_000_000_000).min(u64::from(u32::MAX)) as u32,
        (total % 1_000_000_000) as u32,
    )
}

/// A simulated time as a `foxglove` timestamp (seconds since t = 0, not the epoch).
pub fn timestamp(t_s: f64) -> Timestamp {
    let secs = t_s.max(0.0).floor();
    Timestamp::new(
        secs.min(f64::from(u32::MAX)) as u32,
        ((t_s.max(0.0) - secs) * 1e9).round().min(999_999_999.0) as u32,
    )
}

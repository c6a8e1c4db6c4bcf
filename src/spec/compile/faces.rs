//! `[attitude]` and `[[face]]`: loads from body-fixed faces under an attitude.

use super::*;
use crate::spec::registry as r;

/// `v` as a unit vector of `N` finite numbers (`shape` says what they are when the
/// count is wrong); an error naming `path` when it is short, long or zero.
pub(super) fn unit_vector<const N: usize>(
    cx: &Cx,
    path: &KeyPath,
    v: &[f64],
    shape: &str,
) -> Result<[f64; N], SpecError> {
    let Ok(arr) = <[f64; N]>::try_from(v) else {
        return Err(cx.err(path, format!("lists {} number(s); {shape}", v.len())));
    };
    for (k, x) in arr.iter().enumerate() {
        cx.finite(&path.at(k), *x)?;
    }
    direction(arr).ok_or_else(|| cx.err(path, "is the zero vector; it needs a direction"))
}

/// `v` scaled to unit length, `None` for the zero vector. Scaled by its largest
/// component first, so that no square overflows or underflows: `[1e200, 0, 0]` and
/// `[1e-170, 1e-170, 0]` have directions like any other vector.
pub fn direction<const N: usize>(v: [f64; N]) -> Option<[f64; N]> {
    let m = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if m == 0.0 || !m.is_finite() {
        return None;
    }
    let scaled = v.map(|x| x / m);
    let n = scaled.iter().map(|x| x * x).sum::<f64>().sqrt();
    Some(scaled.map(|x| x / n))
}

/// Two faces of one name would share one key path (`face.<name>.…`): refused, naming
/// both, not renamed.
pub(super) fn unique_face_names(cx: &Cx, specs: &[FaceSpec]) -> Result<(), SpecError> {
    let name = |f: &FaceSpec, i| {
        f.name
            .clone()
            .unwrap_or_else(|| crate::spec::keys::face_name(&f.node, i))
    };
    for (i, f) in specs.iter().enumerate() {
        if let Some(j) = (0..i).find(|&j| name(&specs[j], j) == name(f, i)) {
            return Err(cx.clash(
                &KeyPath::new("face").at(i).key("name"),
                &KeyPath::new("face").at(j).key("name"),
                format!("face `{}` is defined twice", name(f, i)),
            ));
        }
    }
    Ok(())
}

/// `[attitude]` and `[[face]]`: each face a load on its node (direct Sun, albedo,
/// Earth infrared from its orientation) and a radiative coupling εA to space, after the
/// spec's own loads and couplings (their indices stay those of the spec); per face, the
/// indices of its load and its coupling.
pub(super) fn faces(
    cx: &Cx,
    keys: &ElementKeys,
    table: &NodeTable,
    attitude: Option<AttitudeSpec>,
    specs: Vec<FaceSpec>,
    loads: &mut Vec<Load>,
    radiators: &mut Vec<Radiator>,
) -> Result<Vec<(usize, usize)>, SpecError> {
    use crate::orbit::faces::{Attitude, Face};
    let ap = KeyPath::new("attitude");
    let a = attitude.unwrap_or_default();
    let yaw_deg = cx.read_or_default(&r::YAW_DEG, &ap, a.yaw_deg)?;
    use AttitudeMode as M;
    let spinning = a.mode == Some(M::Spin);
    if a.quaternion.is_some() && a.mode != Some(M::Inertial) && !spinning {
        return Err(cx.err(
            &ap.key("quaternion"),
            "orients an inertially fixed or spinning body: give mode = \"inertial\" or \"spin\"",
        ));
    }
    for (given, key) in [
        (a.spin_axis.is_some(), "spin_axis"),
        (a.spin_rate_deg_per_s.is_some(), r::SPIN_RATE_DEG_PER_S.name),
        (a.spin_averaged.is_some(), "spin_averaged"),
    ] {
        if given && !spinning {
            return Err(cx.err(
                &ap.key(key),
                "describes a spinning body: give mode = \"spin\"",
            ));
        }
    }
    let attitude = match a.mode {
        None | Some(M::Nadir) => Attitude::Nadir {
            yaw_rad: yaw_deg.to_radians(),
        },
        Some(m) if a.yaw_deg.is_some() => {
            return Err(cx.err(
                &r::YAW_DEG.key(&ap),
                format!(
                    "turns a nadir-pointing body; mode `{}` has no yaw",
                    m.name()
                ),
            ));
        }
        Some(M::Sun) => Attitude::Sun,
        Some(M::Tumble) => Attitude::Tumble,
        Some(M::Inertial) => {
            let Some(q) = &a.quaternion else {
                return Err(cx.err(
                    &ap,
                    "an inertial attitude needs `quaternion = [w, x, y, z]` (body to inertial)",
                ));
            };
            Attitude::Inertial {
                quaternion: unit_vector::<4>(
                    cx,
                    &ap.key("quaternion"),
                    q,
                    "a quaternion is [w, x, y, z]",
                )?,
            }
        }
        Some(M::Spin) => {
            let quaternion = match &a.quaternion {
                Some(q) => {
                    unit_vector::<4>(cx, &ap.key("quaternion"), q, "a quaternion is [w, x, y, z]")?
                }
                None => [1.0, 0.0, 0.0, 0.0],
            };
            let Some(axis) = &a.spin_axis else {
                return Err(cx.err(
                    &ap,
                    "a spinning body needs `spin_axis = [x, y, z]` (body frame)",
                ));
            };
            let axis_body =
                unit_vector::<3>(cx, &ap.key("spin_axis"), axis, "an axis is [x, y, z]")?;
            let Some(rate) = a.spin_rate_deg_per_s else {
                let key = r::SPIN_RATE_DEG_PER_S.name;
                return Err(cx.err(&ap, format!("a spinning body needs `{key}`")));
            };
            let rate = cx.read(&r::SPIN_RATE_DEG_PER_S, &ap, rate)?;
            Attitude::Spin {
                quaternion,
                axis_body,
                rate_rad_per_s: rate.to_radians(),
                averaged: a.spin_averaged.unwrap_or(false),
            }
        }
    };
    let space = table.lookup(cx, &KeyPath::new("boundary"), SPACE)?;
    unique_face_names(cx, &specs)?;
    let mut bound = Vec::with_capacity(specs.len());
    for (i, f) in specs.into_iter().enumerate() {
        let p = KeyPath::new("face").elem(i, &keys.face[i]);
        let node = table.diffusion(cx, &p.key("node"), &f.node)?;
        let normal_body = unit_vector::<3>(
            cx,
            &p.key("normal"),
            &f.normal,
            "a normal is [x, y, z] in the body frame",
        )?;
        let area = cx.read(&r::AREA_M2, &p, f.area_m2)?;
        let absorptivity = cx.read(&r::ABSORPTIVITY, &p, f.absorptivity)?;
        let emissivity = cx.read(&r::EMISSIVITY, &p, f.emissivity)?;
        bound.push((loads.len(), radiators.len()));
        loads.push(Load {
            name: f
                .name
                .clone()
                .unwrap_or_else(|| crate::spec::keys::face_name(&f.node, i)),
            node,
            kind: LoadKind::Face(Face {
                normal_body,
                area_m2: area,
                absorptivity,
                emissivity,
                attitude,
            }),
        });
        radiators.push(Radiator {
            a: NodeRef::Diffusion(node),
            b: space,
            emissivity_area_m2: emissivity * area,
        });
    }
    Ok(bound)
}

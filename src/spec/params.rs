//! Every numeric value of a scenario, addressable by its key path (see [`super::keys`]):
//! listed with its unit and valid range ([`params`]), read ([`get`]) and written
//! ([`set`]) on a spec. Writing checks only that the path exists and the value is a
//! number; whether the value is valid is the compiler's call (`spec::compile`), so a
//! value set by path and the same value in a TOML file give the same error.

use std::borrow::Cow;

use super::keys::{ElementKeys, Part, element_keys, parse_path, quote_key};
use super::*;
use crate::spec::quantity::{self as q, Quantity};

/// How a number is stored in the spec.
pub enum Slot<'a> {
    /// Always given.
    Value(&'a mut f64),
    /// Optional, with what it stands for when absent.
    Optional(&'a mut Option<f64>, Default),
    /// An integer (a number of teeth).
    Integer(&'a mut i64),
}

/// What an absent optional value stands for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Default {
    /// A fixed default.
    Value(f64),
    /// The orbit's view factor of the Earth, (R / (R + h))².
    EarthViewFactor,
    /// Nothing: the key is not in the scenario (listed only when given).
    Absent,
}

/// Unit and valid range of a value, for `orbitlash params` and `scenarios/README.md`:
/// those of its quantity in the table ([`crate::spec::quantity`]), or for numbers checked
/// only in context (gear geometry, table times, windows), written here.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Meta {
    pub unit: &'static str,
    pub range: &'static str,
    pub quantity: Option<&'static Quantity>,
}

const fn m(unit: &'static str, range: &'static str) -> Meta {
    Meta {
        unit,
        range,
        quantity: None,
    }
}

/// A number of quantity `q`: its unit and range.
const fn of(q: &'static Quantity) -> Meta {
    Meta {
        unit: q.unit,
        range: q.range,
        quantity: Some(q),
    }
}

/// An optional number of quantity `q`, absent standing for its default.
const fn default_of(q: &'static Quantity) -> Default {
    match q.default {
        Some(v) => Default::Value(v),
        None => Default::Absent,
    }
}

/// One addressable value: its key path, its value (what an absent optional value
/// stands for, when it stands for one), unit and valid range.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    pub path: String,
    pub value: f64,
    pub unit: &'static str,
    pub range: &'static str,
    /// Given in the scenario (false: a default).
    pub given: bool,
    /// Its kind in the table of quantities (None: checked only in context).
    pub quantity: Option<&'static Quantity>,
}

/// A key path that does not lead to a number of the scenario, or a value that is not
/// one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{key}`: {message}")]
pub struct ParamError {
    pub key: String,
    pub message: String,
}

type Visit<'f> = dyn FnMut(&[Cow<'_, str>], Slot<'_>, Meta) + 'f;

/// Walks every number of `spec`, with its path, and calls `f` with its slot; with
/// `only`, just the section (and element) that path is in.
///
/// Long by choice (about 175 lines): it is the table of keys, one line per number in
/// file order with its quantity; splitting it would only split the table.
fn walk(spec: &mut ScenarioSpec, keys: &ElementKeys, only: Option<&[String]>, f: &mut Visit<'_>) {
    let section = |name: &str| only.is_none_or(|w| w.first().is_some_and(|s| s == name));
    let element = |name: &str, key: &str| {
        only.is_none_or(|w| {
            w.first().is_some_and(|s| s == name) && w.get(1).is_some_and(|k| k == key)
        })
    };
    let mut path: Vec<Cow<'_, str>> = Vec::new();
    macro_rules! at {
        ($($seg:expr),*; $body:expr) => {{
            let n = path.len();
            $(path.push($seg);)*
            $body;
            path.truncate(n);
        }};
    }
    let o = &mut spec.orbit;
    if section("orbit") {
        at!("orbit".into(); {
            if o.tle.is_some() {
                // a real orbit: its numbers are the start's shift and the Earth's radius
                at!("start_offset_s".into(); f(&path, Slot::Optional(&mut o.start_offset_s, default_of(&q::START_OFFSET_S)), of(&q::START_OFFSET_S)));
                at!("earth_radius_m".into(); f(&path, Slot::Optional(&mut o.earth_radius_m, default_of(&q::EARTH_RADIUS_M)), of(&q::EARTH_RADIUS_M)));
            } else {
                if let Some(a) = &mut o.altitude_m {
                    at!("altitude_m".into(); f(&path, Slot::Value(a), of(&q::ALTITUDE_M)));
                }
                at!("earth_radius_m".into(); f(&path, Slot::Optional(&mut o.earth_radius_m, default_of(&q::EARTH_RADIUS_M)), of(&q::EARTH_RADIUS_M)));
                at!("mu_m3_per_s2".into(); f(&path, Slot::Optional(&mut o.mu_m3_per_s2, default_of(&q::MU_M3_PER_S2)), of(&q::MU_M3_PER_S2)));
                at!("orbit_angle_at_start_deg".into(); f(&path, Slot::Optional(&mut o.orbit_angle_at_start_deg, default_of(&q::ORBIT_ANGLE_AT_START_DEG)), of(&q::ORBIT_ANGLE_AT_START_DEG)));
            }
        });
    }
    let e = &mut spec.environment;
    if section("environment") {
        at!("environment".into(); {
            if let Some(b) = &mut e.beta_deg {
                at!("beta_deg".into(); profile(&mut path, b, of(&q::BETA_DEG), f));
            }
            match &mut e.solar_flux_w_per_m2 {
                Some(p) => at!("solar_flux_w_per_m2".into(); profile(&mut path, p, of(&q::SOLAR_FLUX_W_PER_M2), f)),
                None => {
                    // absent: the solar constant, settable as a number
                    let mut value = None;
                    at!("solar_flux_w_per_m2".into(); f(&path, Slot::Optional(&mut value, default_of(&q::SOLAR_FLUX_W_PER_M2)), of(&q::SOLAR_FLUX_W_PER_M2)));
                    if let Some(v) = value {
                        e.solar_flux_w_per_m2 = Some(ProfileSpec::Constant(v));
                    }
                }
            }
            at!("space_sink_k".into(); f(&path, Slot::Optional(&mut e.space_sink_k, default_of(&q::SPACE_SINK_K)), of(&q::SPACE_SINK_K)));
            at!("albedo".into(); f(&path, Slot::Optional(&mut e.albedo, default_of(&q::ALBEDO)), of(&q::ALBEDO)));
            at!("earth_ir_w_per_m2".into(); f(&path, Slot::Optional(&mut e.earth_ir_w_per_m2, default_of(&q::EARTH_IR_W_PER_M2)), of(&q::EARTH_IR_W_PER_M2)));
        });
    }
    let r = &mut spec.run;
    if section("run") {
        at!("run".into(); {
            let duration = m("", "the run lasts 1 s … 1e9 s");
            at!("orbits".into(); f(&path, Slot::Optional(&mut r.orbits, Default::Absent), Meta { unit: "orbits", ..duration }));
            at!("duration_s".into(); f(&path, Slot::Optional(&mut r.duration_s, Default::Absent), Meta { unit: "s", ..duration }));
            at!("duration_days".into(); f(&path, Slot::Optional(&mut r.duration_days, Default::Absent), Meta { unit: "days", ..duration }));
            at!("output_interval_s".into(); f(&path, Slot::Optional(&mut r.output_interval_s, default_of(&q::OUTPUT_INTERVAL_S)), of(&q::OUTPUT_INTERVAL_S)));
        });
    }
    let s = &mut spec.solver;
    if section("solver") {
        at!("solver".into(); {
            at!("tolerance_k".into(); f(&path, Slot::Optional(&mut s.tolerance_k, default_of(&q::TOLERANCE_K)), of(&q::TOLERANCE_K)));
            at!("max_step_s".into(); f(&path, Slot::Optional(&mut s.max_step_s, default_of(&q::MAX_STEP_S)), of(&q::MAX_STEP_S)));
        });
    }
    for (n, key) in spec.node.iter_mut().zip(&keys.node) {
        if !element("node", key) {
            continue;
        }
        at!("node".into(), key.as_str().into(); {
            at!("capacitance_j_per_k".into(); f(&path, Slot::Value(&mut n.capacitance_j_per_k), of(&q::CAPACITANCE_J_PER_K)));
            at!("initial_temperature_k".into(); f(&path, Slot::Value(&mut n.initial_temperature_k), of(&q::TEMPERATURE_K)));
            at!("radius_mm".into(); f(&path, Slot::Optional(&mut n.radius_mm, Default::Absent), of(&q::NODE_RADIUS_MM)));
        });
    }
    for (b, key) in spec.boundary.iter_mut().zip(&keys.boundary) {
        if !element("boundary", key) {
            continue;
        }
        at!("boundary".into(), key.as_str().into(); {
            at!("temperature_k".into(); profile(&mut path, &mut b.temperature_k, of(&q::TEMPERATURE_K), f));
        });
    }
    for (c, key) in spec.conductor.iter_mut().zip(&keys.conductor) {
        if !element("conductor", key) {
            continue;
        }
        at!("conductor".into(), key.as_str().into(); {
            at!("conductance_w_per_k".into(); f(&path, Slot::Value(&mut c.conductance_w_per_k), of(&q::CONDUCTANCE_W_PER_K)));
        });
    }
    for (r, key) in spec.radiation.iter_mut().zip(&keys.radiation) {
        if !element("radiation", key) {
            continue;
        }
        at!("radiation".into(), key.as_str().into(); {
            area_product(&mut path, &mut r.emissivity_area_m2, &mut r.emissivity, &mut r.area_m2, ("emissivity_area_m2", "emissivity", &q::EMISSIVITY), f);
        });
    }
    for (l, key) in spec.sun.iter_mut().zip(&keys.sun) {
        if !element("sun", key) {
            continue;
        }
        at!("sun".into(), key.as_str().into(); {
            area_product(&mut path, &mut l.absorptivity_area_m2, &mut l.absorptivity, &mut l.area_m2, ("absorptivity_area_m2", "absorptivity", &q::ABSORPTIVITY), f);
        });
    }
    for (l, key) in spec.albedo.iter_mut().zip(&keys.albedo) {
        if !element("albedo", key) {
            continue;
        }
        at!("albedo".into(), key.as_str().into(); {
            area_product(&mut path, &mut l.absorptivity_area_m2, &mut l.absorptivity, &mut l.area_m2, ("absorptivity_area_m2", "absorptivity", &q::ABSORPTIVITY), f);
            at!("view_factor".into(); f(&path, Slot::Optional(&mut l.view_factor, Default::EarthViewFactor), of(&q::VIEW_FACTOR)));
        });
    }
    for (l, key) in spec.earth_ir.iter_mut().zip(&keys.earth_ir) {
        if !element("earth_ir", key) {
            continue;
        }
        at!("earth_ir".into(), key.as_str().into(); {
            area_product(&mut path, &mut l.emissivity_area_m2, &mut l.emissivity, &mut l.area_m2, ("emissivity_area_m2", "emissivity", &q::EMISSIVITY), f);
            at!("view_factor".into(); f(&path, Slot::Optional(&mut l.view_factor, Default::EarthViewFactor), of(&q::VIEW_FACTOR)));
        });
    }
    for (d, key) in spec.dissipation.iter_mut().zip(&keys.dissipation) {
        if !element("dissipation", key) {
            continue;
        }
        at!("dissipation".into(), key.as_str().into(); {
            at!("power_w".into(); profile(&mut path, &mut d.power_w, of(&q::POWER_W), f));
        });
    }
    for (h, key) in spec.heater.iter_mut().zip(&keys.heater) {
        if !element("heater", key) {
            continue;
        }
        at!("heater".into(), key.as_str().into(); {
            at!("power_w".into(); f(&path, Slot::Value(&mut h.power_w), of(&q::HEATER_POWER_W)));
            at!("on_k".into(); f(&path, Slot::Value(&mut h.on_k), of(&q::HEATER_ON_K)));
            at!("off_k".into(); f(&path, Slot::Value(&mut h.off_k), of(&q::HEATER_OFF_K)));
        });
    }
    // A nadir-pointing body's yaw, where there are faces to turn (an absent
    // [attitude] table is only written when the yaw is set).
    let nadir = spec
        .attitude
        .as_ref()
        .is_none_or(|a| matches!(a.mode.as_deref(), None | Some("nadir")));
    if nadir && !spec.face.is_empty() && section("attitude") {
        let mut yaw = spec.attitude.as_ref().and_then(|a| a.yaw_deg);
        at!("attitude".into(); {
            at!("yaw_deg".into(); f(&path, Slot::Optional(&mut yaw, default_of(&q::YAW_DEG)), of(&q::YAW_DEG)));
        });
        if yaw.is_some() {
            spec.attitude
                .get_or_insert_with(crate::spec::AttitudeSpec::default)
                .yaw_deg = yaw;
        }
    }
    // A spinning body's rate (required for that mode, so always given).
    let spinning = spec
        .attitude
        .as_ref()
        .is_some_and(|a| a.mode.as_deref() == Some("spin"));
    if spinning && !spec.face.is_empty() && section("attitude") {
        let a = spec.attitude.as_mut().expect("spinning");
        at!("attitude".into(); {
            at!("spin_rate_deg_per_s".into(); f(&path, Slot::Optional(&mut a.spin_rate_deg_per_s, Default::Absent), of(&q::SPIN_RATE_DEG_PER_S)));
        });
    }
    for (fc, key) in spec.face.iter_mut().zip(&keys.face) {
        if !element("face", key) {
            continue;
        }
        at!("face".into(), key.as_str().into(); {
            at!("area_m2".into(); f(&path, Slot::Value(&mut fc.area_m2), of(&q::AREA_M2)));
            at!("absorptivity".into(); f(&path, Slot::Value(&mut fc.absorptivity), of(&q::ABSORPTIVITY)));
            at!("emissivity".into(); f(&path, Slot::Value(&mut fc.emissivity), of(&q::EMISSIVITY)));
        });
    }
    for (md, key) in spec.mode.iter_mut().zip(&keys.mode) {
        if !element("mode", key) {
            continue;
        }
        at!("mode".into(), key.as_str().into(); {
            for (name, windows, unit) in [("windows_s", &mut md.windows_s, "s"), ("windows_days", &mut md.windows_days, "days")] {
                if let Some(ws) = windows {
                    for (i, w) in ws.iter_mut().enumerate() {
                        for (j, v) in w.iter_mut().enumerate() {
                            at!(format!("{name}[{i}][{j}]").into(); f(&path, Slot::Value(v), m(unit, "windows [start, end], increasing, not overlapping")));
                        }
                    }
                }
            }
        });
    }
    for (sn, key) in spec.sensor.iter_mut().zip(&keys.sensor) {
        if !element("sensor", key) {
            continue;
        }
        if sn.node.is_some() {
            at!("sensor".into(), key.as_str().into(); {
                at!("tau_s".into(); f(&path, Slot::Optional(&mut sn.tau_s, default_of(&q::SENSOR_TAU_S)), of(&q::SENSOR_TAU_S)));
                at!("offset_k".into(); f(&path, Slot::Optional(&mut sn.offset_k, default_of(&q::SENSOR_OFFSET_K)), of(&q::SENSOR_OFFSET_K)));
            });
        }
    }
    for (g, key) in spec.gear_pair.iter_mut().zip(&keys.gear_pair) {
        if !element("gear_pair", key) {
            continue;
        }
        at!("gear_pair".into(), key.as_str().into(); gear_pair(&mut path, g, f));
    }
}

/// A value that is either a product (`emissivity_area_m2`) or a fraction (of quantity
/// `fraction_q`) times an area.
fn area_product<'k>(
    path: &mut Vec<Cow<'k, str>>,
    product: &mut Option<f64>,
    fraction: &mut Option<f64>,
    area: &mut Option<f64>,
    (product_key, fraction_key, fraction_q): (&'k str, &'k str, &'static Quantity),
    f: &mut Visit<'_>,
) {
    let n = path.len();
    path.push(product_key.into());
    f(
        path,
        Slot::Optional(product, Default::Absent),
        of(&q::AREA_PRODUCT_M2),
    );
    path.truncate(n);
    path.push(fraction_key.into());
    f(
        path,
        Slot::Optional(fraction, Default::Absent),
        of(fraction_q),
    );
    path.truncate(n);
    path.push("area_m2".into());
    f(path, Slot::Optional(area, Default::Absent), of(&q::AREA_M2));
    path.truncate(n);
}

/// A profile: a number, or a table of times and values.
fn profile(path: &mut Vec<Cow<'_, str>>, p: &mut ProfileSpec, meta: Meta, f: &mut Visit<'_>) {
    match p {
        ProfileSpec::Constant(v) => f(path, Slot::Value(v), meta),
        ProfileSpec::Table(t) => {
            let n = path.len();
            for (name, times, unit) in [
                ("time_s", &mut t.time_s, "s"),
                ("time_days", &mut t.time_days, "days"),
            ] {
                if let Some(ts) = times {
                    for (i, v) in ts.iter_mut().enumerate() {
                        path.push(format!("{name}[{i}]").into());
                        f(path, Slot::Value(v), m(unit, "strictly increasing"));
                        path.truncate(n);
                    }
                }
            }
            for (i, v) in t.value.iter_mut().enumerate() {
                path.push(format!("value[{i}]").into());
                f(path, Slot::Value(v), meta);
                path.truncate(n);
            }
        }
    }
}

/// The keys of a thermal strain law: α, dα/dT, a strain polynomial, an α polynomial,
/// a strain table.
type StrainKeys<'s> = (
    &'s mut Option<f64>,
    &'s mut Option<f64>,
    &'s mut Option<PolynomialSpec>,
    &'s mut Option<Vec<f64>>,
    &'s mut Option<StrainTableSpec>,
);

/// The keys of a thermal strain law.
fn strain(
    path: &mut Vec<Cow<'_, str>>,
    (alpha, dalpha, poly, alpha_poly, table): StrainKeys<'_>,
    f: &mut Visit<'_>,
) {
    let n = path.len();
    path.push("alpha_per_k".into());
    f(
        path,
        Slot::Optional(alpha, Default::Absent),
        of(&q::EXPANSION_PER_K),
    );
    path.truncate(n);
    path.push("dalpha_dt_per_k2".into());
    f(
        path,
        Slot::Optional(dalpha, Default::Absent),
        of(&q::DALPHA_DT_PER_K2),
    );
    path.truncate(n);
    let law = m("", "thermal strain within ±0.1 over 20 … 1000 K");
    if let Some(p) = poly {
        for (i, c) in p.coefficients.iter_mut().enumerate() {
            path.push(format!("strain_polynomial.coefficients[{i}]").into());
            f(path, Slot::Value(c), law);
            path.truncate(n);
        }
        path.push("strain_polynomial.scale".into());
        f(path, Slot::Value(&mut p.scale), law);
        path.truncate(n);
    }
    if let Some(cs) = alpha_poly {
        for (i, c) in cs.iter_mut().enumerate() {
            path.push(format!("alpha_polynomial[{i}]").into());
            f(path, Slot::Value(c), law);
            path.truncate(n);
        }
    }
    if let Some(t) = table {
        for (i, v) in t.temperature_k.iter_mut().enumerate() {
            path.push(format!("strain_table.temperature_k[{i}]").into());
            f(path, Slot::Value(v), m("K", "strictly increasing"));
            path.truncate(n);
        }
        for (i, v) in t.strain.iter_mut().enumerate() {
            path.push(format!("strain_table.strain[{i}]").into());
            f(path, Slot::Value(v), law);
            path.truncate(n);
        }
    }
}

fn material(path: &mut Vec<Cow<'_, str>>, mt: &mut MaterialSpec, f: &mut Visit<'_>) {
    strain(
        path,
        (
            &mut mt.alpha_per_k,
            &mut mt.dalpha_dt_per_k2,
            &mut mt.strain_polynomial,
            &mut mt.alpha_polynomial,
            &mut mt.strain_table,
        ),
        f,
    );
    let n = path.len();
    path.push("youngs_modulus_pa".into());
    f(
        path,
        Slot::Value(&mut mt.youngs_modulus_pa),
        m("Pa", "≥ 1e8"),
    );
    path.truncate(n);
    path.push("poisson".into());
    f(path, Slot::Value(&mut mt.poisson), of(&q::POISSON));
    path.truncate(n);
}

fn gear_pair(path: &mut Vec<Cow<'_, str>>, g: &mut GearPairSpec, f: &mut Visit<'_>) {
    let n = path.len();
    let mut one = |path: &mut Vec<Cow<'_, str>>, key: &'static str, slot: Slot<'_>, meta: Meta| {
        path.push(key.into());
        f(path, slot, meta);
        path.truncate(n);
    };
    one(
        path,
        "module_mm",
        Slot::Value(&mut g.module_mm),
        of(&q::MODULE_MM),
    );
    one(
        path,
        "pressure_angle_deg",
        Slot::Value(&mut g.pressure_angle_deg),
        of(&q::PRESSURE_ANGLE_DEG),
    );
    one(
        path,
        "face_width_mm",
        Slot::Value(&mut g.face_width_mm),
        of(&q::FACE_WIDTH_MM),
    );
    one(
        path,
        "center_distance_mm",
        Slot::Value(&mut g.center_distance_mm),
        m("mm", "> 0, a positive backlash at assembly"),
    );
    one(
        path,
        "reference_temperature_k",
        Slot::Value(&mut g.reference_temperature_k),
        of(&q::TEMPERATURE_K),
    );
    one(
        path,
        "min_backlash_um",
        Slot::Value(&mut g.min_backlash_um),
        of(&q::MIN_BACKLASH_UM),
    );
    one(
        path,
        "coating.thickness_um",
        Slot::Value(&mut g.coating.thickness_um),
        of(&q::COATING_THICKNESS_UM),
    );
    one(
        path,
        "coating.alpha_per_k",
        Slot::Value(&mut g.coating.alpha_per_k),
        of(&q::EXPANSION_PER_K),
    );
    one(
        path,
        "coating.poisson",
        Slot::Value(&mut g.coating.poisson),
        of(&q::POISSON),
    );
    if let Some(c) = &mut g.center_distance {
        path.push("center_distance".into());
        strain(
            path,
            (
                &mut c.alpha_per_k,
                &mut c.dalpha_dt_per_k2,
                &mut c.strain_polynomial,
                &mut c.alpha_polynomial,
                &mut c.strain_table,
            ),
            f,
        );
        path.truncate(n);
    }
    for (name, gear) in [("pinion", &mut g.pinion), ("wheel", &mut g.wheel)] {
        path.push(name.into());
        let k = path.len();
        let mut one =
            |path: &mut Vec<Cow<'_, str>>, key: &'static str, slot: Slot<'_>, meta: Meta| {
                path.push(key.into());
                f(path, slot, meta);
                path.truncate(k);
            };
        one(
            path,
            "teeth",
            Slot::Integer(&mut gear.teeth),
            m("", "5 … 10000"),
        );
        let mut shift = Some(gear.profile_shift);
        one(
            path,
            "profile_shift",
            Slot::Optional(&mut shift, default_of(&q::PROFILE_SHIFT)),
            of(&q::PROFILE_SHIFT),
        );
        gear.profile_shift = shift.unwrap_or(0.0);
        one(
            path,
            "tip_radius_mm",
            Slot::Value(&mut gear.tip_radius_mm),
            of(&q::TIP_RADIUS_MM),
        );
        one(
            path,
            "root_radius_mm",
            Slot::Value(&mut gear.root_radius_mm),
            of(&q::ROOT_RADIUS_MM),
        );
        one(
            path,
            "bore_radius_mm",
            Slot::Value(&mut gear.bore_radius_mm),
            of(&q::BORE_RADIUS_MM),
        );
        one(
            path,
            "tooth_thickness_mm",
            Slot::Optional(&mut gear.tooth_thickness_mm, Default::Absent),
            m("mm", "0 … π m, not pointed at the tip"),
        );
        one(
            path,
            "tooth_thinning_um",
            Slot::Optional(&mut gear.tooth_thinning_um, Default::Absent),
            m("µm", "a tooth of 0 … π m, not pointed at the tip"),
        );
        one(
            path,
            "interference_um",
            Slot::Optional(&mut gear.interference_um, Default::Absent),
            m("µm", "any (elastic bore fit)"),
        );
        path.push("material".into());
        material(path, &mut gear.material, f);
        path.truncate(k);
        if let Some(sm) = &mut gear.shaft_material {
            path.push("shaft_material".into());
            material(path, sm, f);
            path.truncate(k);
        }
        path.truncate(n);
    }
}

/// The path as printed: keys joined by `.`, element keys quoted when needed.
fn join(path: &[Cow<'_, str>]) -> String {
    let mut s = String::new();
    for (i, p) in path.iter().enumerate() {
        // element keys are the second part of an array's path; other parts are keys as
        // the schema names them (with their indices)
        let part = if i == 1 && ELEMENT_SECTIONS.contains(&path[0].as_ref()) {
            quote_key(p)
        } else {
            p.to_string()
        };
        if i > 0 {
            s.push('.');
        }
        s.push_str(&part);
    }
    s
}

/// The sections whose elements are addressed by key.
const ELEMENT_SECTIONS: [&str; 13] = [
    "node",
    "boundary",
    "conductor",
    "radiation",
    "sun",
    "albedo",
    "earth_ir",
    "dissipation",
    "heater",
    "mode",
    "sensor",
    "gear_pair",
    "face",
];

/// The canonical form of a path the user typed: element keys unquoted for comparison,
/// indices attached to their key (`value[1]`).
fn canonical(text: &str) -> Result<Vec<String>, String> {
    let parts = parse_path(text)?;
    let mut out: Vec<String> = Vec::new();
    for p in parts {
        match p {
            Part::Key(k) => out.push(k),
            Part::Index(i) => {
                let at_element = out.len() == 1 && ELEMENT_SECTIONS.contains(&out[0].as_str());
                match out.last_mut() {
                    Some(last) if !at_element => last.push_str(&format!("[{i}]")),
                    _ => return Err(format!("`[{i}]`: name the element by its key instead")),
                }
            }
        }
    }
    // `strain_polynomial.coefficients[0]` and `coating.poisson` are single parts here
    Ok(out)
}

fn same_path(walked: &[Cow<'_, str>], wanted: &[String]) -> bool {
    // Walked parts may hold dots (`coating.poisson`) except an element key, which is
    // one part however it is spelled; wanted parts are split at every dot outside
    // quotes. Compare part by part without allocating.
    let element = walked
        .first()
        .is_some_and(|s| ELEMENT_SECTIONS.contains(&s.as_ref()));
    let mut want = wanted.iter();
    for (i, p) in walked.iter().enumerate() {
        if i == 1 && element {
            if want.next().is_none_or(|w| w != p) {
                return false;
            }
            continue;
        }
        for piece in p.split('.') {
            if want.next().is_none_or(|w| w != piece) {
                return false;
            }
        }
    }
    want.next().is_none()
}

/// (R / (R + h))² of the spec's orbit.
fn earth_view_factor(spec: &ScenarioSpec) -> f64 {
    let r = spec
        .orbit
        .earth_radius_m
        .unwrap_or(q::EARTH_RADIUS_M.default_value());
    let radius = match (&spec.orbit.tle, spec.orbit.altitude_m) {
        (Some(lines), _) => lines
            .get(1)
            .and_then(|l| crate::orbit::tle::mean_radius_m(l))
            .unwrap_or(f64::NAN),
        (None, Some(h)) => r + h,
        (None, None) => f64::NAN,
    };
    (r / radius).powi(2)
}

/// Every number of `spec` by key path, with unit and range; optional values that are
/// absent are listed with what they stand for, or left out when they stand for nothing
/// (the other form of a value given as a product, a duration given otherwise).
pub fn params(spec: &ScenarioSpec) -> Vec<Param> {
    let vf = earth_view_factor(spec);
    let mut copy = spec.clone();
    let keys = element_keys(spec);
    let mut out = Vec::new();
    walk(&mut copy, &keys, None, &mut |path, slot, meta| {
        let (value, given) = match slot {
            Slot::Value(v) => (*v, true),
            Slot::Integer(v) => (*v as f64, true),
            Slot::Optional(v, d) => match (v.as_ref(), d) {
                (Some(x), _) => (*x, true),
                (None, Default::Value(x)) => (x, false),
                (None, Default::EarthViewFactor) => (vf, false),
                (None, Default::Absent) => return,
            },
        };
        out.push(Param {
            path: join(path),
            value,
            unit: meta.unit,
            range: meta.range,
            given,
            quantity: meta.quantity,
        });
    });
    out
}

fn unknown(text: &str, spec: &ScenarioSpec) -> ParamError {
    // name the elements of the section asked for, to help with typos
    let keys = element_keys(spec);
    let hint = canonical(text).ok().and_then(|c| {
        // sensors are named by their column, which the error already quotes
        let list = match c.first()?.as_str() {
            "sensor" => return None,
            section => keys.section(section)?,
        };
        let known: Vec<String> = list.iter().map(|k| quote_key(k)).collect();
        Some(format!(" ({}: {})", c[0], known.join(", ")))
    });
    ParamError {
        key: text.to_string(),
        message: format!(
            "no such number in this scenario{} (`orbitlash params` lists them)",
            hint.unwrap_or_default()
        ),
    }
}

/// The value at `path` (what an absent optional value stands for).
pub fn get(spec: &ScenarioSpec, path: &str) -> Result<f64, ParamError> {
    let wanted = canonical(path).map_err(|message| ParamError {
        key: path.to_string(),
        message,
    })?;
    let vf = earth_view_factor(spec);
    let mut copy = spec.clone();
    let keys = element_keys(spec);
    let mut found = None;
    walk(&mut copy, &keys, Some(&wanted), &mut |p, slot, _| {
        if found.is_none() && same_path(p, &wanted) {
            found = match slot {
                Slot::Value(v) => Some(*v),
                Slot::Integer(v) => Some(*v as f64),
                Slot::Optional(v, d) => match (v.as_ref(), d) {
                    (Some(x), _) => Some(*x),
                    (None, Default::Value(x)) => Some(x),
                    (None, Default::EarthViewFactor) => Some(vf),
                    (None, Default::Absent) => None,
                },
            };
        }
    });
    found.ok_or_else(|| unknown(path, spec))
}

/// Writes `value` at `path`. Only the path and that the value is a number (an integer
/// for a number of teeth) are checked here; [`super::compile`] judges the value.
pub fn set(spec: &mut ScenarioSpec, path: &str, value: f64) -> Result<(), ParamError> {
    let keys = element_keys(spec);
    set_with_keys(spec, &keys, path, value)
}

/// [`set`] with the spec's element keys already at hand.
pub fn set_with_keys(
    spec: &mut ScenarioSpec,
    keys: &ElementKeys,
    path: &str,
    value: f64,
) -> Result<(), ParamError> {
    let wanted = canonical(path).map_err(|message| ParamError {
        key: path.to_string(),
        message,
    })?;
    set_canonical(spec, keys, path, &wanted, value)
}

/// The path in the form [`set_canonical`] takes (parsed once, written many times).
pub fn canonical_path(path: &str) -> Result<Vec<String>, ParamError> {
    canonical(path).map_err(|message| ParamError {
        key: path.to_string(),
        message,
    })
}

/// The position of `wanted` among the numbers of its section or element, in the order
/// [`set_at`] counts them: a path resolved once is then written without comparing
/// strings.
pub fn position(spec: &ScenarioSpec, keys: &ElementKeys, wanted: &[String]) -> Option<usize> {
    let mut copy = spec.clone();
    let (mut k, mut found) = (0usize, None);
    walk(&mut copy, keys, Some(wanted), &mut |p, _, _| {
        if found.is_none() && same_path(p, wanted) {
            found = Some(k);
        }
        k += 1;
    });
    found
}

/// Writes `value` to the number at `position` (from [`position`]) of the section or
/// element `wanted` is in. The spec's structure (which keys are given) must not have
/// changed since.
pub fn set_at(
    spec: &mut ScenarioSpec,
    keys: &ElementKeys,
    wanted: &[String],
    position: usize,
    value: f64,
) -> bool {
    let (mut k, mut done) = (0usize, false);
    walk(spec, keys, Some(wanted), &mut |_, slot, _| {
        if k == position {
            done = match slot {
                Slot::Value(v) => {
                    *v = value;
                    true
                }
                // not an integer: the full write says why
                Slot::Integer(v) if value.fract() == 0.0 && value.abs() < 1e15 => {
                    *v = value as i64;
                    true
                }
                Slot::Integer(_) => false,
                Slot::Optional(v, _) => {
                    *v = Some(value);
                    true
                }
            };
        }
        k += 1;
    });
    done
}

/// [`set_with_keys`] with the path already parsed by [`canonical_path`].
pub fn set_canonical(
    spec: &mut ScenarioSpec,
    keys: &ElementKeys,
    path: &str,
    wanted: &[String],
    value: f64,
) -> Result<(), ParamError> {
    let mut done: Option<Result<(), String>> = None;
    walk(spec, keys, Some(wanted), &mut |p, slot, _| {
        if done.is_none() && same_path(p, wanted) {
            done = Some(match slot {
                Slot::Value(v) => {
                    *v = value;
                    Ok(())
                }
                Slot::Integer(v) => {
                    if value.fract() == 0.0 && value.abs() < 1e15 {
                        *v = value as i64;
                        Ok(())
                    } else {
                        Err(format!("must be an integer (got {value})"))
                    }
                }
                Slot::Optional(v, d) => {
                    if v.is_none() && d == Default::Absent {
                        Err(
                            "is not given in this scenario (it uses another form of this value)"
                                .into(),
                        )
                    } else {
                        *v = Some(value);
                        Ok(())
                    }
                }
            });
        }
    });
    match done {
        Some(Ok(())) => Ok(()),
        Some(Err(message)) => Err(ParamError {
            key: path.to_string(),
            message,
        }),
        None => Err(unknown(path, spec)),
    }
}

/// Parses `KEY=VALUE` (as `--set` takes it).
pub fn parse_assignment(text: &str) -> Result<(String, f64), ParamError> {
    let (key, value) = text.split_once('=').ok_or_else(|| ParamError {
        key: text.to_string(),
        message: "give KEY=VALUE, e.g. node.housing.capacitance_j_per_k=130".into(),
    })?;
    let key = key.trim().to_string();
    let v: f64 = value.trim().parse().map_err(|_| ParamError {
        key: key.clone(),
        message: format!("`{}` is not a number", value.trim()),
    })?;
    Ok((key, v))
}

//! The invariants of a model (`docs/ARCHITECTURE.md`), checked whatever built it: a
//! scenario compiled from a spec meets them by construction (`spec::compile` refuses
//! what would break one, naming the key), and a program that builds or edits a
//! `Scenario` directly checks it with [`Scenario::validate`] before running it.

use crate::gear::GearPair;
use crate::orbit::{CircularEnvironment, Environment, EnvironmentModel, Profile};
use crate::spec::compile::{
    MAX_AREA_M2, MAX_CAPACITANCE_J_PER_K, MAX_CONDUCTANCE_W_PER_K, MAX_PERIOD_S, MAX_POWER_W,
    MIN_CAPACITANCE_J_PER_K, MIN_PERIOD_S,
};
use crate::spec::quantity::MIN_MAX_STEP_S;
use crate::spec::quantity::{self as q, Quantity};
use crate::spec::quantity::{MAX_SENSOR_OFFSET_K, MAX_SENSOR_TAU_S};
use crate::spec::scenario::{
    MAX_DURATION_S, MIN_DURATION_S, MIN_OUTPUT_INTERVAL_S, Scenario, SensorTarget,
};
use crate::thermal::{LoadKind, NodeRef, ThermalModel, When};

/// A broken invariant: what (e.g. `network.conductors[3]`) and how.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{what}: {message}")]
pub struct Invalid {
    pub what: String,
    pub message: String,
}

fn bad(what: impl Into<String>, message: impl Into<String>) -> Invalid {
    Invalid {
        what: what.into(),
        message: message.into(),
    }
}

fn within(what: &str, v: f64, lo: f64, hi: f64) -> Result<(), Invalid> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(bad(what, format!("{v} is not within {lo} … {hi}")))
    }
}

/// `v` within the closed range of quantity `q` (the compiler's check, with its open
/// ends, is the precise one).
fn within_q(what: &str, v: f64, q: &Quantity) -> Result<(), Invalid> {
    let (lo, _, hi, _) = q.interval().expect("a quantity with a range");
    within(what, v, lo, hi)
}

fn temperature(what: &str, v: f64) -> Result<(), Invalid> {
    if v.is_finite() && v > 0.0 && v < 5000.0 {
        Ok(())
    } else {
        Err(bad(
            what,
            format!("{v} K is not a temperature within 0 … 5000 K"),
        ))
    }
}

fn profile(
    what: &str,
    p: &Profile,
    check: &dyn Fn(&str, f64) -> Result<(), Invalid>,
) -> Result<(), Invalid> {
    match p {
        Profile::Constant(v) => check(what, *v),
        Profile::Table { time_s, value } => {
            if time_s.is_empty() || time_s.len() != value.len() {
                return Err(bad(
                    what,
                    "a table needs as many values as times, at least one",
                ));
            }
            if time_s.iter().any(|t| !t.is_finite()) || time_s.windows(2).any(|w| w[1] <= w[0]) {
                return Err(bad(
                    what,
                    "table times must be finite and increase strictly",
                ));
            }
            value.iter().try_for_each(|v| check(what, *v))
        }
    }
}

fn environment(e: &Environment) -> Result<(), Invalid> {
    match e {
        Environment::Circular(c) => circular(c),
        Environment::Dated(d) => dated(d),
    }
}

fn circular(e: &CircularEnvironment) -> Result<(), Invalid> {
    let o = &e.orbit;
    within_q("environment.orbit.altitude_m", o.altitude_m, &q::ALTITUDE_M)?;
    within(
        "environment.orbit.earth_radius_m",
        o.earth_radius_m,
        1e5,
        1e8,
    )?;
    within("environment.orbit.mu_m3_per_s2", o.mu_m3_per_s2, 1e9, 1e17)?;
    if !o.orbit_angle_at_start_rad.is_finite() {
        return Err(bad(
            "environment.orbit.orbit_angle_at_start_rad",
            "not finite",
        ));
    }
    within(
        "environment.orbit period (s)",
        e.mean_period_s(),
        MIN_PERIOD_S,
        MAX_PERIOD_S,
    )?;
    let (lo, _, hi, _) = q::BETA_DEG.interval().expect("β has a range");
    profile("environment.beta_rad", &e.beta_rad, &|w, v| {
        within(w, v, lo.to_radians(), hi.to_radians())
    })?;
    profile(
        "environment.solar_flux_w_per_m2",
        &e.solar_flux_w_per_m2,
        &|w, v| within_q(w, v, &q::SOLAR_FLUX_W_PER_M2),
    )?;
    earth_and_space(e.albedo, e.earth_ir_w_per_m2, e.space_sink_k)
}

/// The albedo, the Earth's infrared flux and the space sink of any environment.
fn earth_and_space(albedo: f64, earth_ir_w_per_m2: f64, space_sink_k: f64) -> Result<(), Invalid> {
    within_q("environment.albedo", albedo, &q::ALBEDO)?;
    within_q(
        "environment.earth_ir_w_per_m2",
        earth_ir_w_per_m2,
        &q::EARTH_IR_W_PER_M2,
    )?;
    within_q("environment.space_sink_k", space_sink_k, &q::SPACE_SINK_K)
}

fn dated(e: &crate::orbit::dated::DatedEnvironment) -> Result<(), Invalid> {
    within("environment.earth_radius_m", e.earth_radius_m, 1e5, 1e8)?;
    within(
        "environment.orbit period (s)",
        e.mean_period_s(),
        MIN_PERIOD_S,
        MAX_PERIOD_S,
    )?;
    within_q(
        "environment.solar_flux_w_per_m2",
        e.solar_flux_1au_w_per_m2,
        &q::SOLAR_FLUX_W_PER_M2,
    )?;
    earth_and_space(e.albedo, e.earth_ir_w_per_m2, e.space_sink_k)
}

impl ThermalModel {
    /// Checks every invariant of a thermal model (see the module docs).
    ///
    /// Long by choice (about 150 lines): the list of invariants, one check after
    /// another, each with its own error; splitting it would only split the list.
    pub fn validate(&self) -> Result<(), Invalid> {
        environment(&self.environment)?;
        let net = &self.network;
        let n = net.nodes.len();
        if n == 0 {
            return Err(bad(
                "network.nodes",
                "the network needs at least one diffusion node",
            ));
        }
        for (i, nd) in net.nodes.iter().enumerate() {
            let w = format!("network.nodes[{i}] ({})", nd.name);
            if !(MIN_CAPACITANCE_J_PER_K..=MAX_CAPACITANCE_J_PER_K)
                .contains(&nd.capacitance_j_per_k)
            {
                return Err(bad(
                    w,
                    format!(
                        "capacitance {} J/K outside {MIN_CAPACITANCE_J_PER_K} … {MAX_CAPACITANCE_J_PER_K:e} J/K",
                        crate::units::num(nd.capacitance_j_per_k)
                    ),
                ));
            }
            temperature(&w, nd.initial_temperature_k)?;
            if nd.radius_m.is_some_and(|r| !(r.is_finite() && r > 0.0)) {
                return Err(bad(w, "a radius must be finite and positive"));
            }
        }
        if net.boundaries.first().is_none_or(|b| b.name != "space") {
            return Err(bad("network.boundaries[0]", "must be the built-in `space`"));
        }
        for (i, b) in net.boundaries.iter().enumerate() {
            profile(
                &format!("network.boundaries[{i}] ({})", b.name),
                &b.temperature_k,
                &|w, v| {
                    if v.is_finite() && (0.0..5000.0).contains(&v) {
                        Ok(())
                    } else {
                        Err(bad(w, format!("{v} K is not within 0 … 5000 K")))
                    }
                },
            )?;
        }
        let node_ok = |r: NodeRef| match r {
            NodeRef::Diffusion(i) => i < n,
            NodeRef::Boundary(b) => b < net.boundaries.len(),
        };
        let link =
            |what: String, a: NodeRef, b: NodeRef, g: f64, max: f64| -> Result<(), Invalid> {
                if !(node_ok(a) && node_ok(b)) {
                    return Err(bad(what, "refers to a node that does not exist"));
                }
                if a == b {
                    return Err(bad(what, "links a node to itself"));
                }
                if matches!((a, b), (NodeRef::Boundary(_), NodeRef::Boundary(_))) {
                    return Err(bad(what, "links two boundary nodes"));
                }
                if !(g.is_finite() && g > 0.0 && g <= max) {
                    return Err(bad(what, format!("{g} is not within 0 … {max}")));
                }
                Ok(())
            };
        for (i, c) in net.conductors.iter().enumerate() {
            link(
                format!("network.conductors[{i}]"),
                c.a,
                c.b,
                c.conductance_w_per_k,
                MAX_CONDUCTANCE_W_PER_K,
            )?;
        }
        for (i, r) in net.radiators.iter().enumerate() {
            link(
                format!("network.radiators[{i}]"),
                r.a,
                r.b,
                r.emissivity_area_m2,
                MAX_AREA_M2,
            )?;
        }
        for (i, l) in net.loads.iter().enumerate() {
            let w = format!("network.loads[{i}] ({})", l.name);
            if l.node >= n {
                return Err(bad(w, "refers to a node that does not exist"));
            }
            let area = |a: f64| {
                if a.is_finite() && a > 0.0 && a <= MAX_AREA_M2 {
                    Ok(())
                } else {
                    Err(bad(
                        &w,
                        format!("area product {a} m² is not within 0 … {MAX_AREA_M2}"),
                    ))
                }
            };
            match &l.kind {
                LoadKind::Sun {
                    absorptivity_area_m2,
                    ..
                } => area(*absorptivity_area_m2)?,
                LoadKind::Albedo {
                    absorptivity_area_m2,
                    view_factor,
                } => {
                    area(*absorptivity_area_m2)?;
                    within_q(&w, *view_factor, &q::VIEW_FACTOR)?;
                }
                LoadKind::EarthIr {
                    emissivity_area_m2,
                    view_factor,
                } => {
                    area(*emissivity_area_m2)?;
                    within_q(&w, *view_factor, &q::VIEW_FACTOR)?;
                }
                LoadKind::Face(f) => {
                    area(f.area_m2)?;
                    within_q(&w, f.absorptivity, &q::ABSORPTIVITY)?;
                    within_q(&w, f.emissivity, &q::EMISSIVITY)?;
                    let n2: f64 = f.normal_body.iter().map(|x| x * x).sum();
                    if (n2 - 1.0).abs() > 1e-9 {
                        return Err(bad(w, "a face's normal must be a unit vector"));
                    }
                }
                LoadKind::Dissipation { power_w, when } => {
                    profile(&w, power_w, &|ww, v| within_q(ww, v, &q::POWER_W))?;
                    if let When::Mode(m) = when
                        && *m >= self.modes.len()
                    {
                        return Err(bad(w, "refers to a mode that does not exist"));
                    }
                }
            }
        }
        for (i, h) in net.heaters.iter().enumerate() {
            let w = format!("network.heaters[{i}] ({})", h.name);
            if h.node >= n || h.sensor_node >= n {
                return Err(bad(w, "refers to a node that does not exist"));
            }
            if !(h.power_w.is_finite() && h.power_w > 0.0 && h.power_w <= MAX_POWER_W) {
                return Err(bad(
                    w,
                    format!("power {} W is not within 0 … {MAX_POWER_W} W", h.power_w),
                ));
            }
            temperature(&w, h.on_k)?;
            temperature(&w, h.off_k)?;
            if h.on_k >= h.off_k {
                return Err(bad(w, "switches on at or above its switch-off temperature"));
            }
        }
        for (i, m) in self.modes.iter().enumerate() {
            let mut last = f64::NEG_INFINITY;
            for &(a, b) in &m.windows_s {
                if !(a.is_finite() && b.is_finite() && b > a && a >= last) {
                    return Err(bad(
                        format!("modes[{i}] ({})", m.name),
                        "windows must be finite, increasing and not overlap",
                    ));
                }
                last = b;
            }
        }
        Ok(())
    }
}

fn gear_pair(k: usize, p: &GearPair, n: usize) -> Result<(), Invalid> {
    let w = format!("gears[{k}] ({})", p.name);
    for g in &p.gears {
        if g.nodes.len() < 2 || g.nodes.len() != g.node_radii_m.len() {
            return Err(bad(&w, "a gear needs its profile nodes with their radii"));
        }
        if g.nodes.iter().chain(g.shaft_node.iter()).any(|&i| i >= n) {
            return Err(bad(&w, "refers to a node that does not exist"));
        }
        if g.node_radii_m.windows(2).any(|r| r[1] <= r[0]) {
            return Err(bad(
                &w,
                "node radii must increase from the bore to the base circle",
            ));
        }
        let w = format!("{w}, {}", g.name);
        if g.teeth < 5 {
            return Err(bad(&w, format!("{} teeth: at least 5", g.teeth)));
        }
        let rb = g.base_radius_m(p.module_m, p.pressure_angle_rad);
        if !(g.bore_radius_m > 0.0 && g.bore_radius_m < rb.min(g.root_radius_m)) {
            return Err(bad(
                &w,
                format!(
                    "the bore ({} m) must lie within 0 … the base and root radii ({rb} m, {} m)",
                    g.bore_radius_m, g.root_radius_m
                ),
            ));
        }
        if g.tip_radius_m.partial_cmp(&rb.max(g.root_radius_m)) != Some(std::cmp::Ordering::Greater)
        {
            return Err(bad(&w, "the tip must lie above the base and root radii"));
        }
        let pitch = std::f64::consts::PI * p.module_m;
        if !(g.tooth_thickness_m > 0.0 && g.tooth_thickness_m < pitch) {
            return Err(bad(
                &w,
                format!(
                    "tooth thickness {} m outside 0 … π m = {pitch} m",
                    g.tooth_thickness_m
                ),
            ));
        }
        let m = &g.material;
        if !(m.youngs_modulus_pa > 0.0 && q::POISSON.accepts(m.poisson)) {
            return Err(bad(
                &w,
                "the material needs E > 0 and a Poisson ratio within −1 … 0.5",
            ));
        }
    }
    if !(p.module_m > 0.0 && p.module_m.is_finite()) {
        return Err(bad(&w, "the module must be positive"));
    }
    let (lo_deg, _, hi_deg, _) = q::PRESSURE_ANGLE_DEG.interval().expect("a range");
    if !(lo_deg.to_radians()..=hi_deg.to_radians()).contains(&p.pressure_angle_rad) {
        return Err(bad(&w, "the pressure angle must lie within 10° … 35°"));
    }
    if let crate::gear::CenterDistance::Housing { node, .. } = p.center
        && node >= n
    {
        return Err(bad(
            &w,
            "the centre distance follows a node that does not exist",
        ));
    }
    temperature(&w, p.reference_temperature_k)?;
    if !(p.min_backlash_m.is_finite() && p.min_backlash_m >= 0.0) {
        return Err(bad(&w, "the minimum backlash must be finite and ≥ 0"));
    }
    let nominal = p.nominal_backlash_m();
    if nominal.is_nan() || nominal <= 0.0 {
        return Err(bad(
            &w,
            format!("no positive backlash at assembly ({nominal} m)"),
        ));
    }
    Ok(())
}

impl Scenario {
    /// Every name (scenario, nodes, boundaries, loads, heaters, modes, gear pairs,
    /// sensor columns) by the one rule of [`crate::spec::scenario::check_name`], and a
    /// description without control characters.
    fn check_names(&self) -> Result<(), Invalid> {
        let net = &self.thermal.network;
        let named = |what: &str, i: usize, name: &str| {
            crate::spec::scenario::check_name(name).map_err(|m| bad(format!("{what}[{i}].name"), m))
        };
        named("scenario", 0, &self.name)?;
        for (i, x) in net.nodes.iter().enumerate() {
            named("network.nodes", i, &x.name)?;
        }
        for (i, x) in net.boundaries.iter().enumerate() {
            named("network.boundaries", i, &x.name)?;
        }
        for (i, x) in net.loads.iter().enumerate() {
            named("network.loads", i, &x.name)?;
        }
        for (i, x) in net.heaters.iter().enumerate() {
            named("network.heaters", i, &x.name)?;
        }
        for (i, x) in self.thermal.modes.iter().enumerate() {
            named("modes", i, &x.name)?;
        }
        for (i, x) in self.gears.iter().enumerate() {
            named("gears", i, &x.name)?;
        }
        for (i, x) in self.sensors.iter().enumerate() {
            crate::spec::scenario::check_name(&x.column)
                .map_err(|m| bad(format!("sensors[{i}].column"), m))?;
        }
        if self
            .description
            .chars()
            .any(|c| c.is_control() && c != '\n' && c != '\t')
        {
            return Err(bad("description", "holds control characters"));
        }
        if self.description.chars().count() > crate::spec::compile::MAX_DESCRIPTION_LEN {
            return Err(bad("description", "is too long"));
        }
        Ok(())
    }

    /// Checks every invariant of the scenario: its thermal model, gear pairs, run
    /// control, solver settings and sensors.
    pub fn validate(&self) -> Result<(), Invalid> {
        self.check_names()?;
        self.thermal.validate()?;
        let n = self.thermal.network.nodes.len();
        for (k, p) in self.gears.iter().enumerate() {
            gear_pair(k, p, n)?;
        }
        within(
            "run.duration_s",
            self.run.duration_s,
            MIN_DURATION_S,
            MAX_DURATION_S,
        )?;
        if !(self.run.output_interval_s.is_finite()
            && self.run.output_interval_s >= MIN_OUTPUT_INTERVAL_S)
        {
            return Err(bad(
                "run.output_interval_s",
                format!("below {MIN_OUTPUT_INTERVAL_S} s"),
            ));
        }
        within_q(
            "solver.tolerance_k",
            self.solver.tolerance_k,
            &q::TOLERANCE_K,
        )?;
        if !(self.solver.max_step_s.is_finite() && self.solver.max_step_s >= MIN_MAX_STEP_S) {
            return Err(bad(
                "solver.max_step_s",
                format!("below {MIN_MAX_STEP_S} s"),
            ));
        }
        for (i, s) in self.sensors.iter().enumerate() {
            let at = || format!("sensors[{i}] ({})", s.column);
            match &s.target {
                SensorTarget::Node(j) if *j >= n => {
                    return Err(bad(at(), "refers to a node that does not exist"));
                }
                SensorTarget::Backlash(k) if *k >= self.gears.len() => {
                    return Err(bad(at(), "refers to a gear pair that does not exist"));
                }
                _ => {}
            }
            if !(0.0..=MAX_SENSOR_TAU_S).contains(&s.tau_s) {
                return Err(bad(
                    at(),
                    format!(
                        "time constant {} s outside 0 … {MAX_SENSOR_TAU_S} s",
                        s.tau_s
                    ),
                ));
            }
            if !(-MAX_SENSOR_OFFSET_K..=MAX_SENSOR_OFFSET_K).contains(&s.offset_k) {
                return Err(bad(
                    at(),
                    format!("offset {} K beyond ±{MAX_SENSOR_OFFSET_K} K", s.offset_k),
                ));
            }
            if matches!(s.target, SensorTarget::Backlash(_))
                && (s.tau_s != 0.0 || s.offset_k != 0.0)
            {
                return Err(bad(at(), "a backlash sensor has no lag or offset"));
            }
        }
        Ok(())
    }
}

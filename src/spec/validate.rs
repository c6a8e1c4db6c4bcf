//! The invariants of a model (`docs/ARCHITECTURE.md`), checked whatever built it: a
//! scenario compiled from a spec meets them by construction (`spec::compile` refuses
//! what would break one, naming the key), and a program that builds or edits a
//! `Scenario` directly checks it with [`Scenario::validate`] before running it.
//!
//! Every bound is the one the compiler checks: a value against its registry field's
//! quantity ([`value`]), a gear's geometry by `gear::check`. Nothing here writes a
//! number of its own but the structure (indices in range, a link's two ends).

use crate::gear::GearPair;
use crate::gear::check as geometry;
use crate::orbit::{CircularEnvironment, Environment, EnvironmentModel, Profile};
use crate::spec::compile::{MAX_PERIOD_S, MIN_PERIOD_S};
use crate::spec::quantity::Quantity;
use crate::spec::registry::{self as r, Field};
use crate::spec::scenario::{MAX_DURATION_S, MIN_DURATION_S, Scenario, SensorTarget};
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

/// Model units per unit of a field: m per mm, rad per degree.
const MM: f64 = 1e-3;
const UM: f64 = 1e-6;
const DEG: f64 = std::f64::consts::PI / 180.0;

/// `v` (in the model's unit, `per` times the quantity's) accepted by quantity `q`.
fn quantity(what: &str, v: f64, q: &Quantity, per: f64) -> Result<(), Invalid> {
    let ok = v.is_finite()
        && q.interval().is_none_or(|(lo, lo_in, hi, hi_in)| {
            let (lo, hi) = (lo * per, hi * per);
            (v > lo || (lo_in && v == lo)) && (v < hi || (hi_in && v == hi))
        });
    if ok {
        Ok(())
    } else {
        let unit = if per == 1.0 { q.unit } else { "(SI)" };
        Err(bad(
            what,
            format!("{v} {unit} is not within {} {}", q.range(), q.unit),
        ))
    }
}

/// `v` accepted as a value of `field` (in the field's own unit).
fn value(what: &str, v: f64, field: &Field) -> Result<(), Invalid> {
    quantity(what, v, field.quantity, 1.0)
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

fn period(p: f64) -> Result<(), Invalid> {
    if (MIN_PERIOD_S..=MAX_PERIOD_S).contains(&p) {
        Ok(())
    } else {
        Err(bad(
            "environment.orbit period (s)",
            format!("{p} is not within {MIN_PERIOD_S} … {MAX_PERIOD_S}"),
        ))
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
    value("environment.orbit.altitude_m", o.altitude_m, &r::ALTITUDE_M)?;
    value(
        "environment.orbit.earth_radius_m",
        o.earth_radius_m,
        &r::EARTH_RADIUS_M,
    )?;
    value(
        "environment.orbit.mu_m3_per_s2",
        o.mu_m3_per_s2,
        &r::MU_M3_PER_S2,
    )?;
    if !o.orbit_angle_at_start_rad.is_finite() {
        return Err(bad(
            "environment.orbit.orbit_angle_at_start_rad",
            "not finite",
        ));
    }
    period(e.mean_period_s())?;
    profile("environment.beta_rad", &e.beta_rad, &|w, v| {
        quantity(w, v, r::BETA_DEG.quantity, DEG)
    })?;
    profile(
        "environment.solar_flux_w_per_m2",
        &e.solar_flux_w_per_m2,
        &|w, v| value(w, v, &r::SOLAR_FLUX_W_PER_M2),
    )?;
    earth_and_space(e.albedo, e.earth_ir_w_per_m2, e.space_sink_k)
}

/// The albedo, the Earth's infrared flux and the space sink of any environment.
fn earth_and_space(albedo: f64, earth_ir_w_per_m2: f64, space_sink_k: f64) -> Result<(), Invalid> {
    value("environment.albedo", albedo, &r::ALBEDO)?;
    value(
        "environment.earth_ir_w_per_m2",
        earth_ir_w_per_m2,
        &r::EARTH_IR_W_PER_M2,
    )?;
    value("environment.space_sink_k", space_sink_k, &r::SPACE_SINK_K)
}

fn dated(e: &crate::orbit::dated::DatedEnvironment) -> Result<(), Invalid> {
    value(
        "environment.earth_radius_m",
        e.earth_radius_m,
        &r::EARTH_RADIUS_M,
    )?;
    period(e.mean_period_s())?;
    value(
        "environment.solar_flux_w_per_m2",
        e.solar_flux_1au_w_per_m2,
        &r::SOLAR_FLUX_W_PER_M2,
    )?;
    earth_and_space(e.albedo, e.earth_ir_w_per_m2, e.space_sink_k)
}

impl ThermalModel {
    /// Checks every invariant of a thermal model (see the module docs).
    pub fn validate(&self) -> Result<(), Invalid> {
        environment(&self.environment)?;
        self.nodes_and_boundaries()?;
        self.links()?;
        self.loads()?;
        self.heaters_and_modes()
    }

    fn nodes_and_boundaries(&self) -> Result<(), Invalid> {
        let net = &self.network;
        if net.nodes.is_empty() {
            return Err(bad(
                "network.nodes",
                "the network needs at least one diffusion node",
            ));
        }
        for (i, nd) in net.nodes.iter().enumerate() {
            let w = format!("network.nodes[{i}] ({})", nd.name);
            value(&w, nd.capacitance_j_per_k, &r::CAPACITANCE_J_PER_K)?;
            value(&w, nd.initial_temperature_k, &r::INITIAL_TEMPERATURE_K)?;
            if let Some(radius) = nd.radius_m {
                quantity(&w, radius, r::RADIUS_MM.quantity, MM)?;
            }
        }
        if net.boundaries.first().is_none_or(|b| b.name != "space") {
            return Err(bad("network.boundaries[0]", "must be the built-in `space`"));
        }
        for (i, b) in net.boundaries.iter().enumerate() {
            // the built-in `space` sits at the sink temperature, the others at theirs
            let field = if i == 0 {
                &r::SPACE_SINK_K
            } else {
                &r::BOUNDARY_TEMPERATURE_K
            };
            profile(
                &format!("network.boundaries[{i}] ({})", b.name),
                &b.temperature_k,
                &|w, v| value(w, v, field),
            )?;
        }
        Ok(())
    }

    fn links(&self) -> Result<(), Invalid> {
        let net = &self.network;
        let n = net.nodes.len();
        let node_ok = |r: NodeRef| match r {
            NodeRef::Diffusion(i) => i < n,
            NodeRef::Boundary(b) => b < net.boundaries.len(),
        };
        let link = |what: String, a: NodeRef, b: NodeRef, g: f64, field| -> Result<(), Invalid> {
            if !(node_ok(a) && node_ok(b)) {
                return Err(bad(what, "refers to a node that does not exist"));
            }
            if a == b {
                return Err(bad(what, "links a node to itself"));
            }
            if matches!((a, b), (NodeRef::Boundary(_), NodeRef::Boundary(_))) {
                return Err(bad(what, "links two boundary nodes"));
            }
            value(&what, g, field)
        };
        for (i, c) in net.conductors.iter().enumerate() {
            let w = format!("network.conductors[{i}]");
            link(w, c.a, c.b, c.conductance_w_per_k, &r::CONDUCTANCE_W_PER_K)?;
        }
        for (i, x) in net.radiators.iter().enumerate() {
            let w = format!("network.radiators[{i}]");
            link(w, x.a, x.b, x.emissivity_area_m2, &r::EMISSIVITY_AREA_M2)?;
        }
        Ok(())
    }

    fn loads(&self) -> Result<(), Invalid> {
        let net = &self.network;
        for (i, l) in net.loads.iter().enumerate() {
            let w = format!("network.loads[{i}] ({})", l.name);
            if l.node >= net.nodes.len() {
                return Err(bad(w, "refers to a node that does not exist"));
            }
            match &l.kind {
                LoadKind::Sun {
                    absorptivity_area_m2,
                    ..
                } => value(&w, *absorptivity_area_m2, &r::ABSORPTIVITY_AREA_M2)?,
                LoadKind::Albedo {
                    absorptivity_area_m2,
                    view_factor,
                } => {
                    value(&w, *absorptivity_area_m2, &r::ABSORPTIVITY_AREA_M2)?;
                    value(&w, *view_factor, &r::VIEW_FACTOR)?;
                }
                LoadKind::EarthIr {
                    emissivity_area_m2,
                    view_factor,
                } => {
                    value(&w, *emissivity_area_m2, &r::EMISSIVITY_AREA_M2)?;
                    value(&w, *view_factor, &r::VIEW_FACTOR)?;
                }
                LoadKind::Face(f) => {
                    value(&w, f.area_m2, &r::AREA_M2)?;
                    value(&w, f.absorptivity, &r::ABSORPTIVITY)?;
                    value(&w, f.emissivity, &r::EMISSIVITY)?;
                    let n2: f64 = f.normal_body.iter().map(|x| x * x).sum();
                    if (n2 - 1.0).abs() > 1e-9 {
                        return Err(bad(w, "a face's normal must be a unit vector"));
                    }
                }
                LoadKind::Dissipation { power_w, when } => {
                    profile(&w, power_w, &|ww, v| value(ww, v, &r::DISSIPATION_POWER_W))?;
                    if let When::Mode(m) = when
                        && *m >= self.modes.len()
                    {
                        return Err(bad(w, "refers to a mode that does not exist"));
                    }
                }
            }
        }
        Ok(())
    }

    fn heaters_and_modes(&self) -> Result<(), Invalid> {
        let net = &self.network;
        let n = net.nodes.len();
        for (i, h) in net.heaters.iter().enumerate() {
            let w = format!("network.heaters[{i}] ({})", h.name);
            if h.node >= n || h.sensor_node >= n {
                return Err(bad(w, "refers to a node that does not exist"));
            }
            value(&w, h.power_w, &r::HEATER_POWER_W)?;
            value(&w, h.on_k, &r::ON_K)?;
            value(&w, h.off_k, &r::OFF_K)?;
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

/// Gear pair `k` of a model with `n` diffusion nodes: its numbers by their fields, its
/// geometry and materials by the compiler's own checks (`gear::check`).
fn gear_pair(k: usize, p: &GearPair, n: usize) -> Result<(), Invalid> {
    let w = format!("gears[{k}] ({})", p.name);
    let geometry = |w: &str, e: geometry::GeometryError| bad(w, e.message);
    quantity(&w, p.module_m, r::MODULE_MM.quantity, MM)?;
    quantity(
        &w,
        p.pressure_angle_rad,
        r::PRESSURE_ANGLE_DEG.quantity,
        DEG,
    )?;
    quantity(&w, p.face_width_m, r::FACE_WIDTH_MM.quantity, MM)?;
    value(&w, p.reference_temperature_k, &r::REFERENCE_TEMPERATURE_K)?;
    quantity(&w, p.min_backlash_m, r::MIN_BACKLASH_UM.quantity, UM)?;
    for g in &p.gears {
        if g.nodes.len() < 2 || g.nodes.len() != g.node_radii_m.len() {
            return Err(bad(&w, "a gear needs its profile nodes with their radii"));
        }
        if g.nodes.iter().chain(g.shaft_node.iter()).any(|&i| i >= n) {
            return Err(bad(&w, "refers to a node that does not exist"));
        }
        let w = format!("{w}, {}", g.name);
        geometry::teeth(g.teeth.into()).map_err(|e| geometry(&w, e))?;
        let (m, a0) = (p.module_m, p.pressure_angle_rad);
        let (r_ref, r_b) = (m * g.teeth as f64 / 2.0, g.base_radius_m(m, a0));
        geometry::radii(r_b, g.tip_radius_m, g.root_radius_m, g.bore_radius_m)
            .map_err(|e| geometry(&w, e))?;
        geometry::tooth(m, a0, g.tooth_thickness_m, r_ref, r_b, g.tip_radius_m)
            .map_err(|e| geometry(&w, e))?;
        for (j, r) in g.node_radii_m.iter().enumerate() {
            let before = j.checked_sub(1).map(|i| g.node_radii_m[i]);
            geometry::next_node(j, before, *r).map_err(|e| geometry(&w, e))?;
        }
        geometry::node_ends(&g.node_radii_m, g.bore_radius_m, r_b).map_err(|e| geometry(&w, e))?;
        let mt = &g.material;
        if mt.youngs_modulus_pa.is_nan() || mt.youngs_modulus_pa <= 0.0 {
            return Err(bad(&w, "the material needs E > 0"));
        }
        geometry::youngs_modulus(mt.youngs_modulus_pa).map_err(|e| geometry(&w, e))?;
        value(&w, mt.poisson, &r::POISSON)?;
        geometry::strain_law(&mt.strain).map_err(|e| geometry(&w, e))?;
    }
    if let crate::gear::CenterDistance::Housing { node, strain } = &p.center {
        if *node >= n {
            return Err(bad(
                &w,
                "the centre distance follows a node that does not exist",
            ));
        }
        geometry::strain_law(strain).map_err(|e| geometry(&w, e))?;
    }
    geometry::mesh(p).map_err(|e| geometry(&w, e))
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
        let d = self.run.duration_s;
        if !(MIN_DURATION_S..=MAX_DURATION_S).contains(&d) {
            return Err(bad(
                "run.duration_s",
                format!("{d} is not within {MIN_DURATION_S} … {MAX_DURATION_S}"),
            ));
        }
        value(
            "run.output_interval_s",
            self.run.output_interval_s,
            &r::OUTPUT_INTERVAL_S,
        )?;
        value(
            "solver.tolerance_k",
            self.solver.tolerance_k,
            &r::TOLERANCE_K,
        )?;
        value("solver.max_step_s", self.solver.max_step_s, &r::MAX_STEP_S)?;
        for (i, s) in self.sensors.iter().enumerate() {
            let at = format!("sensors[{i}] ({})", s.column);
            match &s.target {
                SensorTarget::Node(j) if *j >= n => {
                    return Err(bad(at, "refers to a node that does not exist"));
                }
                SensorTarget::Backlash(k) if *k >= self.gears.len() => {
                    return Err(bad(at, "refers to a gear pair that does not exist"));
                }
                _ => {}
            }
            value(&at, s.tau_s, &r::TAU_S)?;
            value(&at, s.offset_k, &r::OFFSET_K)?;
            if matches!(s.target, SensorTarget::Backlash(_))
                && (s.tau_s != 0.0 || s.offset_k != 0.0)
            {
                return Err(bad(at, "a backlash sensor has no lag or offset"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound that had drifted: a boundary at 0 K is refused here as by the TOML
    /// reader and `--set` (the built-in `space` may sit at a 0 K sink).
    #[test]
    fn core_a_boundary_at_0_k_is_refused_as_the_compiler_refuses_it() {
        let text = include_str!("../../scenarios/reference-hinge.toml");
        let mut sc = crate::io::scenario_toml::parse(text, "r.toml").unwrap();
        sc.validate().unwrap();
        sc.thermal.network.boundaries[1].temperature_k = Profile::Constant(0.0);
        let e = sc.validate().unwrap_err();
        assert!(e.what.starts_with("network.boundaries[1]"), "{e}");
        sc.thermal.network.boundaries[1].temperature_k = Profile::Constant(3.0);
        sc.thermal.network.boundaries[0].temperature_k = Profile::Constant(0.0);
        sc.validate().unwrap();
        use crate::spec::quantity as q;
        assert!(!q::TEMPERATURE_K.accepts(0.0) && q::SPACE_SINK_K.accepts(0.0));
    }
}

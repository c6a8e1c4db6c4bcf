//! A scenario as a built model: the spec as the user wrote it and the validated numeric
//! model compiled from it, kept in step. Every number is read and written by its key
//! path ([`crate::spec::keys`]); a write, or an added element, goes through the same
//! compiler as a TOML file, so it meets the same checks with the same error text, and
//! everything that depends on the changed value (a view factor on the altitude, a run
//! length in orbits on the period, a tooth thickness on its thinning) follows.

use crate::spec::keys::{ElementKeys, element_keys};
use crate::spec::params::{self, Param, ParamError};
use crate::spec::quantity::{self as q, Quantity};
use crate::spec::scenario::Scenario;
use crate::spec::{
    AlbedoSpec, DissipationSpec, EarthIrSpec, HeaterSpec, KeyPath, ProfileSpec, ScenarioSpec,
    SensorSpec, SpecError, SunSpec, compile,
};

/// Why a change to a model was refused; the model is left as it was.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// The key path leads to no number, or the value is not one.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The changed scenario is not valid.
    #[error(transparent)]
    Invalid(#[from] SpecError),
}

/// A load to add to a model.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadSpec {
    Sun(SunSpec),
    Albedo(AlbedoSpec),
    EarthIr(EarthIrSpec),
    Dissipation(DissipationSpec),
}

#[derive(Debug, Clone)]
pub struct Model {
    spec: ScenarioSpec,
    keys: ElementKeys,
    scenario: Scenario,
    /// Which elements the model has, and how they are written: changed by
    /// [`Model::modify`] (and what calls it), not by writing values. A [`ParamId`] of
    /// another shape is resolved again.
    shape: u64,
}

static SHAPES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn new_shape() -> u64 {
    SHAPES.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl Model {
    /// Compiles `spec` (see [`crate::spec::compile`]).
    pub fn new(spec: ScenarioSpec) -> Result<Model, SpecError> {
        let scenario = compile(spec.clone())?;
        let model = Model {
            keys: element_keys(&spec),
            spec,
            scenario,
            shape: new_shape(),
        };
        model.check_uncertain()?;
        model.check_inputs()?;
        Ok(model)
    }

    /// Each `[[input]]` drives a boundary's temperature or a dissipation's power that
    /// the scenario has, with finite scale and offset.
    fn check_inputs(&self) -> Result<(), SpecError> {
        use crate::spec::keys::KeyPath;
        for (i, inp) in self.spec.input.iter().enumerate() {
            let at = KeyPath::new("input").at(i);
            if inp.column.trim().is_empty() {
                return Err(SpecError {
                    key: at.key("column"),
                    message: "must not be empty".into(),
                    also: None,
                });
            }
            if inp.drives == "sunlit" {
                if self.spec.orbit.tle.is_none() {
                    return Err(SpecError {
                        key: at.key("drives"),
                        message: "\"sunlit\" needs a dated scenario ([orbit] tle and start_utc)"
                            .into(),
                        also: None,
                    });
                }
                if !inp.below.is_some_and(f64::is_finite) {
                    return Err(SpecError {
                        key: at.key("below"),
                        message: "\"sunlit\" needs `below`: the reading under which the spacecraft is in eclipse".into(),
                        also: None,
                    });
                }
            } else if inp.below.is_some() {
                return Err(SpecError {
                    key: at.key("below"),
                    message: "applies to drives = \"sunlit\" only".into(),
                    also: None,
                });
            } else if input_target(&self.spec, &inp.drives).is_none() {
                return Err(SpecError {
                    key: at.key("drives"),
                    message: format!(
                        "`{}` is not a boundary's temperature or a dissipation's power of this scenario (`boundary.<name>.temperature_k`, `dissipation.<name>.power_w`)",
                        inp.drives
                    ),
                    also: None,
                });
            }
            // A column is one thing: the time, an ignored column or one input's.
            let fmt = &self.scenario.recording;
            if inp.column == fmt.time_column || fmt.ignore_columns.contains(&inp.column) {
                return Err(SpecError {
                    key: at.key("column"),
                    message: format!(
                        "`{}` is the recording's {}; an input reads a column of readings",
                        inp.column,
                        if inp.column == fmt.time_column {
                            "time column"
                        } else {
                            "ignored column ([recording] ignore_columns)"
                        }
                    ),
                    also: None,
                });
            }
            if let Some(j) = (0..i).find(|&j| self.spec.input[j].drives == inp.drives) {
                return Err(SpecError {
                    key: at.key("drives"),
                    message: format!(
                        "`{}` is driven by two inputs; one input drives a target",
                        inp.drives
                    ),
                    also: Some(KeyPath::new("input").at(j).key("drives")),
                });
            }
            for (key, v) in [("scale", inp.scale), ("offset", inp.offset)] {
                if v.is_some_and(|v| !v.is_finite()) {
                    return Err(SpecError {
                        key: at.key(key),
                        message: "must be a finite number".into(),
                        also: None,
                    });
                }
            }
        }
        Ok(())
    }

    /// Makes `[[input]]` number `i` follow `readings` (time s, value) of its channel:
    /// the driven profile becomes the table of `scale` × reading + `offset` (linear
    /// between readings), or, for `sunlit`, the eclipse windows of the readings below
    /// `below`. Returns what it did, in a line.
    pub fn follow_input(&mut self, i: usize, readings: &[(f64, f64)]) -> Result<String, String> {
        let inp = self.spec.input[i].clone();
        let (scale, offset) = (inp.scale.unwrap_or(1.0), inp.offset.unwrap_or(0.0));
        let time_s: Vec<f64> = readings.iter().map(|r| r.0).collect();
        let value: Vec<f64> = readings.iter().map(|r| scale * r.1 + offset).collect();
        let n = value.len();
        if inp.drives == "sunlit" {
            let below = inp.below.unwrap_or(f64::NAN);
            let period =
                crate::orbit::EnvironmentModel::mean_period_s(&self.scenario.thermal.environment);
            let windows = eclipse_windows(&time_s, &value, below, period);
            let count = windows.len();
            self.modify(|s| s.orbit.eclipses_s = Some(windows))
                .map_err(|e| format!("[[input]] sunlit from `{}`: {e}", inp.column))?;
            return Ok(format!(
                "eclipses follow `{}` below {below} ({n} readings, {count} eclipses)",
                inp.column
            ));
        }
        let table = ProfileSpec::Table(crate::spec::TableSpec {
            time_s: Some(time_s),
            time_days: None,
            value,
        });
        self.modify(|s| {
            if let Some(p) = input_target_mut(s, &inp.drives) {
                *p = table;
            }
        })
        .map_err(|e| format!("[[input]] `{}` from `{}`: {e}", inp.drives, inp.column))?;
        Ok(format!(
            "`{}` follows `{}` ({n} readings × {scale} + {offset})",
            inp.drives, inp.column
        ))
    }

    /// Each `[[uncertain]]` names a number of the model, with finite bounds min < max
    /// that the model accepts at both ends.
    fn check_uncertain(&self) -> Result<(), SpecError> {
        use crate::spec::keys::KeyPath;
        for (i, u) in self.spec.uncertain.iter().enumerate() {
            let at = KeyPath::new("uncertain").at(i);
            let err = |key: &'static str, message: String| SpecError {
                also: None,
                key: at.key(key),
                message,
            };
            self.get(&u.path).map_err(|e| err("path", e.to_string()))?;
            if !(u.min.is_finite() && u.max.is_finite() && u.min < u.max) {
                return Err(err(
                    "max",
                    format!(
                        "the bounds must be finite with min < max (got {} … {})",
                        u.min, u.max
                    ),
                ));
            }
            for (key, v) in [("min", u.min), ("max", u.max)] {
                let mut m = self.clone();
                m.set(&u.path, v)
                    .map_err(|e| err(key, format!("`{}` cannot be {v}: {e}", u.path)))?;
            }
        }
        Ok(())
    }

    pub fn spec(&self) -> &ScenarioSpec {
        &self.spec
    }

    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Every number by key path, with unit and range.
    pub fn params(&self) -> Vec<Param> {
        params::params(&self.spec)
    }

    /// The number at `path`.
    pub fn get(&self, path: &str) -> Result<f64, ParamError> {
        params::get(&self.spec, path)
    }

    /// Writes one number; on any error the model is unchanged.
    pub fn set(&mut self, path: &str, value: f64) -> Result<(), ModelError> {
        self.set_many(&[(path, value)])
    }

    /// Writes several numbers and compiles once; on any error the model is unchanged
    /// and the error is that of the first offending key.
    pub fn set_many<K: AsRef<str>>(&mut self, changes: &[(K, f64)]) -> Result<(), ModelError> {
        let mut spec = self.spec.clone();
        for (path, value) in changes {
            params::set_with_keys(&mut spec, &self.keys, path.as_ref(), *value)?;
        }
        self.replace(spec)
    }

    /// Changes the spec with `edit` (any change: values, added or removed elements) and
    /// compiles it; on an error the model is unchanged.
    pub fn modify(&mut self, edit: impl FnOnce(&mut ScenarioSpec)) -> Result<(), ModelError> {
        let mut spec = self.spec.clone();
        edit(&mut spec);
        self.replace(spec)?;
        self.shape = new_shape();
        Ok(())
    }

    /// Adds a thermostat heater.
    pub fn add_heater(&mut self, heater: HeaterSpec) -> Result<(), ModelError> {
        self.modify(|s| s.heater.push(heater))
    }

    /// Adds a load.
    pub fn add_load(&mut self, load: LoadSpec) -> Result<(), ModelError> {
        self.modify(|s| match load {
            LoadSpec::Sun(l) => s.sun.push(l),
            LoadSpec::Albedo(l) => s.albedo.push(l),
            LoadSpec::EarthIr(l) => s.earth_ir.push(l),
            LoadSpec::Dissipation(l) => s.dissipation.push(l),
        })
    }

    /// Adds a sensor (a recording column and what it measures).
    pub fn add_sensor(&mut self, sensor: SensorSpec) -> Result<(), ModelError> {
        self.modify(|s| s.sensor.push(sensor))
    }

    fn replace(&mut self, spec: ScenarioSpec) -> Result<(), ModelError> {
        let scenario = compile(spec.clone())?;
        self.keys = element_keys(&spec);
        self.spec = spec;
        self.scenario = scenario;
        Ok(())
    }
}

/// A parameter resolved once ([`Model::param`]) and written many times
/// ([`Model::set_param`]): the values Monte Carlo samples disperse. The common ones
/// (capacitances, initial temperatures, conductances, radiative and load areas and
/// optical properties, heater settings, albedo, Earth IR, sink, β and solar flux when
/// constant) are written straight into the spec and the compiled model after the
/// compiler's own check of the value; a gear-pair value recompiles that pair; any
/// other recompiles the scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamId {
    path: String,
    canonical: Vec<String>,
    /// Its position in its section or element (see `spec::params::position`).
    position: Option<usize>,
    key: KeyPath,
    target: Target,
    /// The model shape it was resolved for.
    shape: u64,
}

impl ParamId {
    /// The path as it was given.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The path in one spelling (`node."housing" . capacitance_j_per_k` and
    /// `node.housing.capacitance_j_per_k` give the same), for messages and comparisons.
    pub fn canonical_path(&self) -> String {
        self.canonical
            .iter()
            .enumerate()
            .map(|(i, p)| {
                // inner keys may hold dots (`coating.poisson`); only element keys quote
                if i == 1 {
                    crate::spec::keys::quote_key(p)
                } else {
                    p.clone()
                }
            })
            .collect::<Vec<_>>()
            .join(".")
    }

    /// True when both name the same number of the scenario, however spelled.
    pub fn same_number(&self, other: &ParamId) -> bool {
        self.canonical == other.canonical
    }
}

/// Which part of an area product.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Part3 {
    Product,
    Fraction,
    Area,
}

/// The kinds of load addressed by path, in the order the compiler lists loads.
#[derive(Debug, Clone, Copy, PartialEq)]
enum LoadSection {
    Sun,
    Albedo,
    EarthIr,
}

#[derive(Debug, Clone, PartialEq)]
enum Target {
    NodeCapacitance(usize),
    NodeInitial(usize),
    Conductance(usize),
    Radiation(usize, Part3),
    Load(LoadSection, usize, Part3),
    ViewFactor(LoadSection, usize),
    HeaterPower(usize),
    HeaterOn(usize),
    HeaterOff(usize),
    Albedo,
    EarthIr,
    Sink,
    BetaConstant,
    FluxConstant,
    GearPair(usize),
    Other,
}

impl Model {
    /// Resolves `path` for [`Model::set_param`].
    pub fn param(&self, path: &str) -> Result<ParamId, ParamError> {
        self.get(path)?; // it exists
        let parts = crate::spec::keys::parse_path(path).map_err(|message| ParamError {
            key: path.to_string(),
            message,
        })?;
        use crate::spec::keys::Part::Key;
        let k: Vec<&str> = parts
            .iter()
            .map(|p| match p {
                Key(s) => s.as_str(),
                _ => "[]",
            })
            .collect();
        let find = |list: &[String], key: &str| list.iter().position(|x| x == key);
        let keys = &self.keys;
        let elem_path = |section: &'static str, i: usize, key: &str, field: &'static str| {
            KeyPath::new(section).elem(i, key).key(field)
        };
        let part3 = |f: &str| match f {
            "emissivity_area_m2" | "absorptivity_area_m2" => Some(Part3::Product),
            "emissivity" | "absorptivity" => Some(Part3::Fraction),
            "area_m2" => Some(Part3::Area),
            _ => None,
        };
        let env = |field: &'static str| KeyPath::new("environment").key(field);
        let (target, key) = match k.as_slice() {
            [
                "node",
                n,
                f @ ("capacitance_j_per_k" | "initial_temperature_k"),
            ] => {
                let i = find(&keys.node, n).expect("exists");
                let field = if *f == "capacitance_j_per_k" {
                    "capacitance_j_per_k"
                } else {
                    "initial_temperature_k"
                };
                (
                    if field == "capacitance_j_per_k" {
                        Target::NodeCapacitance(i)
                    } else {
                        Target::NodeInitial(i)
                    },
                    elem_path("node", i, n, field),
                )
            }
            ["conductor", c, "conductance_w_per_k"] => {
                let i = find(&keys.conductor, c).expect("exists");
                (
                    Target::Conductance(i),
                    elem_path("conductor", i, c, "conductance_w_per_k"),
                )
            }
            ["radiation", r, f] if part3(f).is_some() => {
                let i = find(&keys.radiation, r).expect("exists");
                (
                    Target::Radiation(i, part3(f).expect("some")),
                    KeyPath::new("radiation").elem(i, r).key(static_field(f)),
                )
            }
            [s @ ("sun" | "albedo" | "earth_ir"), l, f]
                if part3(f).is_some() || *f == "view_factor" =>
            {
                let (section, list, name) = match *s {
                    "sun" => (LoadSection::Sun, &keys.sun, "sun"),
                    "albedo" => (LoadSection::Albedo, &keys.albedo, "albedo"),
                    _ => (LoadSection::EarthIr, &keys.earth_ir, "earth_ir"),
                };
                let i = find(list, l).expect("exists");
                let target = match part3(f) {
                    Some(p) => Target::Load(section, i, p),
                    None => Target::ViewFactor(section, i),
                };
                (target, KeyPath::new(name).elem(i, l).key(static_field(f)))
            }
            ["heater", h, f @ ("power_w" | "on_k" | "off_k")] => {
                let i = find(&keys.heater, h).expect("exists");
                let target = match *f {
                    "power_w" => Target::HeaterPower(i),
                    "on_k" => Target::HeaterOn(i),
                    _ => Target::HeaterOff(i),
                };
                (
                    target,
                    KeyPath::new("heater").elem(i, h).key(static_field(f)),
                )
            }
            ["environment", "albedo"] => (Target::Albedo, env("albedo")),
            ["environment", "earth_ir_w_per_m2"] => (Target::EarthIr, env("earth_ir_w_per_m2")),
            ["environment", "space_sink_k"] => (Target::Sink, env("space_sink_k")),
            ["environment", "beta_deg"] => (Target::BetaConstant, env("beta_deg")),
            ["environment", "solar_flux_w_per_m2"] => {
                (Target::FluxConstant, env("solar_flux_w_per_m2"))
            }
            ["gear_pair", g, ..] => {
                let i = find(&keys.gear_pair, g).expect("exists");
                (Target::GearPair(i), KeyPath::new("gear_pair"))
            }
            _ => (Target::Other, KeyPath::new("scenario")),
        };
        let canonical = params::canonical_path(path)?;
        Ok(ParamId {
            path: path.to_string(),
            position: params::position(&self.spec, &self.keys, &canonical),
            canonical,
            key,
            target,
            shape: self.shape,
        })
    }

    /// Writes the value of a resolved parameter (see [`ParamId`]); on an error the
    /// model is unchanged.
    pub fn set_param(&mut self, id: &ParamId, value: f64) -> Result<(), ModelError> {
        if id.shape != self.shape {
            // resolved on a model with other elements: its indices may not hold here
            let id = self.param(&id.path)?;
            return self.set_param(&id, value);
        }
        use crate::spec::check;
        use crate::thermal::LoadKind;
        let path = &id.key;
        let sc = &mut self.scenario;
        let net = &mut sc.thermal.network;
        match &id.target {
            Target::NodeCapacitance(i) => {
                let c = check::value(&q::CAPACITANCE_J_PER_K, path, value)?;
                self.spec.node[*i].capacitance_j_per_k = value;
                net.nodes[*i].capacitance_j_per_k = c;
            }
            Target::NodeInitial(i) => {
                let t = check::value(&q::TEMPERATURE_K, path, value)?;
                self.spec.node[*i].initial_temperature_k = value;
                net.nodes[*i].initial_temperature_k = t;
            }
            Target::Conductance(i) => {
                let g = check::value(&q::CONDUCTANCE_W_PER_K, path, value)?;
                self.spec.conductor[*i].conductance_w_per_k = value;
                net.conductors[*i].conductance_w_per_k = g;
            }
            Target::Radiation(i, part) => {
                let r = &mut self.spec.radiation[*i];
                let product = area_product(
                    path,
                    *part,
                    value,
                    (&mut r.emissivity_area_m2, &mut r.emissivity, &mut r.area_m2),
                    &q::EMISSIVITY,
                )?;
                net.radiators[*i].emissivity_area_m2 = product;
            }
            Target::Load(section, i, part) => {
                self.set_area_load(path, *section, *i, *part, value)?
            }
            Target::ViewFactor(section, i) => {
                let f = check::value(&q::VIEW_FACTOR, path, value)?;
                let at = match section {
                    LoadSection::Albedo => {
                        self.spec.albedo[*i].view_factor = Some(value);
                        sc.bindings.albedo[*i]
                    }
                    _ => {
                        self.spec.earth_ir[*i].view_factor = Some(value);
                        sc.bindings.earth_ir[*i]
                    }
                };
                match &mut net.loads[at].kind {
                    LoadKind::Albedo { view_factor, .. }
                    | LoadKind::EarthIr { view_factor, .. } => *view_factor = f,
                    _ => unreachable!("a load with a view factor"),
                }
            }
            Target::HeaterPower(i) => {
                let p = check::value(&q::HEATER_POWER_W, path, value)?;
                self.spec.heater[*i].power_w = value;
                net.heaters[*i].power_w = p;
            }
            Target::HeaterOn(i) | Target::HeaterOff(i) => {
                let on = matches!(id.target, Target::HeaterOn(_));
                self.set_heater_switch(path, *i, on, value)?
            }
            Target::Albedo => {
                let a = check::value(&q::ALBEDO, path, value)?;
                self.spec.environment.albedo = Some(value);
                *sc.thermal.environment.earth_and_space_mut().0 = a;
            }
            Target::EarthIr => {
                let q = check::value(&q::EARTH_IR_W_PER_M2, path, value)?;
                self.spec.environment.earth_ir_w_per_m2 = Some(value);
                *sc.thermal.environment.earth_and_space_mut().1 = q;
            }
            Target::Sink => {
                let t = check::value(&q::SPACE_SINK_K, path, value)?;
                self.spec.environment.space_sink_k = Some(value);
                *sc.thermal.environment.earth_and_space_mut().2 = t;
                // the built-in boundary `space` sits at the sink temperature
                net.boundaries[0].temperature_k = crate::orbit::Profile::Constant(t);
            }
            Target::BetaConstant
                if matches!(
                    self.spec.environment.beta_deg,
                    Some(ProfileSpec::Constant(_))
                ) =>
            {
                let b = check::value(&q::BETA_DEG, path, value)?;
                self.spec.environment.beta_deg = Some(ProfileSpec::Constant(value));
                sc.thermal
                    .environment
                    .circular_mut()
                    .expect("β is a key of circular orbits")
                    .beta_rad = crate::orbit::Profile::Constant(b.to_radians());
            }
            Target::FluxConstant
                if !matches!(
                    self.spec.environment.solar_flux_w_per_m2,
                    Some(ProfileSpec::Table(_))
                ) =>
            {
                let s = check::value(&q::SOLAR_FLUX_W_PER_M2, path, value)?;
                self.spec.environment.solar_flux_w_per_m2 = Some(ProfileSpec::Constant(value));
                match &mut sc.thermal.environment {
                    crate::orbit::Environment::Circular(c) => {
                        c.solar_flux_w_per_m2 = crate::orbit::Profile::Constant(s)
                    }
                    // a dated orbit's flux is the flux at 1 AU
                    crate::orbit::Environment::Dated(d) => d.solar_flux_1au_w_per_m2 = s,
                }
            }
            Target::GearPair(g) => self.set_gear_value(id, *g, value)?,
            _ => return self.set(&id.path, value),
        }
        Ok(())
    }

    /// Writes one number of an area load (`sun`, `albedo`, `earth_ir` element `i`):
    /// the product or one of its factors, checked as the compiler checks it; the
    /// compiled load is found through the compiler's [`Bindings`](crate::spec::scenario::Bindings).
    fn set_area_load(
        &mut self,
        path: &KeyPath,
        section: LoadSection,
        i: usize,
        part: Part3,
        value: f64,
    ) -> Result<(), ModelError> {
        use crate::thermal::LoadKind;
        let (fields, what, at) = match section {
            LoadSection::Sun => {
                let l = &mut self.spec.sun[i];
                (
                    (
                        &mut l.absorptivity_area_m2,
                        &mut l.absorptivity,
                        &mut l.area_m2,
                    ),
                    &q::ABSORPTIVITY,
                    self.scenario.bindings.sun[i],
                )
            }
            LoadSection::Albedo => {
                let l = &mut self.spec.albedo[i];
                (
                    (
                        &mut l.absorptivity_area_m2,
                        &mut l.absorptivity,
                        &mut l.area_m2,
                    ),
                    &q::ABSORPTIVITY,
                    self.scenario.bindings.albedo[i],
                )
            }
            LoadSection::EarthIr => {
                let l = &mut self.spec.earth_ir[i];
                (
                    (&mut l.emissivity_area_m2, &mut l.emissivity, &mut l.area_m2),
                    &q::EMISSIVITY,
                    self.scenario.bindings.earth_ir[i],
                )
            }
        };
        let product = area_product(path, part, value, fields, what)?;
        match &mut self.scenario.thermal.network.loads[at].kind {
            LoadKind::Sun {
                absorptivity_area_m2,
                ..
            }
            | LoadKind::Albedo {
                absorptivity_area_m2,
                ..
            } => *absorptivity_area_m2 = product,
            LoadKind::EarthIr {
                emissivity_area_m2, ..
            } => *emissivity_area_m2 = product,
            LoadKind::Dissipation { .. } | LoadKind::Face(_) => unreachable!("not an area load"),
        }
        Ok(())
    }

    /// Writes heater `i`'s switch-on (`on`) or switch-off temperature, keeping the band
    /// valid.
    fn set_heater_switch(
        &mut self,
        path: &KeyPath,
        i: usize,
        on: bool,
        value: f64,
    ) -> Result<(), ModelError> {
        use crate::spec::check;
        let quantity = if on {
            &q::HEATER_ON_K
        } else {
            &q::HEATER_OFF_K
        };
        let t = check::value(quantity, path, value)?;
        let h = &self.spec.heater[i];
        let (on_k, off_k) = if on { (t, h.off_k) } else { (h.on_k, t) };
        let off_path = KeyPath::new("heater")
            .elem(i, &self.keys.heater[i])
            .key("off_k");
        check::heater_band(&off_path, on_k, off_k)?;
        let (hs, hm) = (
            &mut self.spec.heater[i],
            &mut self.scenario.thermal.network.heaters[i],
        );
        if on {
            hs.on_k = value;
            hm.on_k = t;
        } else {
            hs.off_k = value;
            hm.off_k = t;
        }
        Ok(())
    }

    /// Writes a number of gear pair `g` and recompiles that pair only (its checks tie
    /// many numbers together); on an error the pair is as before.
    fn set_gear_value(&mut self, id: &ParamId, g: usize, value: f64) -> Result<(), ModelError> {
        let old = self.spec.gear_pair[g].clone();
        let direct = id
            .position
            .is_some_and(|k| params::set_at(&mut self.spec, &self.keys, &id.canonical, k, value));
        if !direct {
            params::set_canonical(&mut self.spec, &self.keys, &id.path, &id.canonical, value)?;
        }
        match crate::spec::check::gear_pair_again(
            &self.spec,
            g,
            &self.keys.gear_pair[g],
            &self.scenario.thermal.network,
        ) {
            Ok(pair) => self.scenario.gears[g] = pair,
            Err(e) => {
                self.spec.gear_pair[g] = old;
                return Err(e.into());
            }
        }
        Ok(())
    }
}

/// The field name of a load or link key as a `'static str`.
fn static_field(f: &str) -> &'static str {
    match f {
        "emissivity_area_m2" => "emissivity_area_m2",
        "absorptivity_area_m2" => "absorptivity_area_m2",
        "emissivity" => "emissivity",
        "absorptivity" => "absorptivity",
        "area_m2" => "area_m2",
        "view_factor" => "view_factor",
        "power_w" => "power_w",
        "on_k" => "on_k",
        _ => "off_k",
    }
}

/// Writes one part of an area product (the product itself, the fraction or the area)
/// after the compiler's check, and returns the product the model uses.
fn area_product(
    path: &KeyPath,
    part: Part3,
    value: f64,
    (product, fraction, area): (&mut Option<f64>, &mut Option<f64>, &mut Option<f64>),
    fraction_q: &Quantity,
) -> Result<f64, ModelError> {
    use crate::spec::check;
    let (p, x, a) = match part {
        Part3::Product => (check::value(&q::AREA_PRODUCT_M2, path, value)?, None, None),
        Part3::Fraction => (0.0, Some(check::value(fraction_q, path, value)?), *area),
        Part3::Area => (
            0.0,
            *fraction,
            Some(check::value(&q::AREA_M2, path, value)?),
        ),
    };
    Ok(match part {
        Part3::Product => {
            *product = Some(value);
            p
        }
        Part3::Fraction => {
            *fraction = Some(value);
            x.expect("checked") * a.expect("the area is given with the fraction")
        }
        Part3::Area => {
            *area = Some(value);
            x.expect("the fraction is given with the area") * a.expect("checked")
        }
    })
}

/// The profile an `[[input]]`'s `drives` names, if the scenario has it.
fn input_target<'s>(spec: &'s ScenarioSpec, drives: &str) -> Option<&'s ProfileSpec> {
    let parts = crate::spec::keys::parse_path(drives).ok()?;
    let key = |i: usize| match parts.get(i) {
        Some(crate::spec::keys::Part::Key(k)) => Some(k.as_str()),
        _ => None,
    };
    match (key(0)?, key(2)?, parts.len()) {
        ("boundary", "temperature_k", 3) => spec
            .boundary
            .iter()
            .find(|b| Some(b.name.as_str()) == key(1))
            .map(|b| &b.temperature_k),
        ("dissipation", "power_w", 3) => {
            let keys = crate::spec::keys::element_keys(spec);
            let i = keys
                .dissipation
                .iter()
                .position(|k| Some(k.as_str()) == key(1))?;
            spec.dissipation.get(i).map(|d| &d.power_w)
        }
        _ => None,
    }
}

fn input_target_mut<'s>(spec: &'s mut ScenarioSpec, drives: &str) -> Option<&'s mut ProfileSpec> {
    let parts = crate::spec::keys::parse_path(drives).ok()?;
    let key = |i: usize| match parts.get(i) {
        Some(crate::spec::keys::Part::Key(k)) => Some(k.clone()),
        _ => None,
    };
    match (key(0)?.as_str(), key(2)?.as_str()) {
        ("boundary", "temperature_k") => {
            let name = key(1)?;
            spec.boundary
                .iter_mut()
                .find(|b| b.name == name)
                .map(|b| &mut b.temperature_k)
        }
        ("dissipation", "power_w") => {
            let keys = crate::spec::keys::element_keys(spec);
            let name = key(1)?;
            let i = keys.dissipation.iter().position(|k| *k == name)?;
            spec.dissipation.get_mut(i).map(|d| &mut d.power_w)
        }
        _ => None,
    }
}

/// Longest step between two readings that an eclipse edge is placed inside, s; a
/// longer gap (a ground segment's fill, no pass) is bridged from the orbit's period.
pub const INPUT_MAX_GAP_S: f64 = 600.0;

/// Eclipse windows from readings `value` at `time_s` (dark below `below`): each change
/// of state halfway between the two readings around it. Across a gap longer than
/// [`INPUT_MAX_GAP_S`] the readings say nothing, and the last whole eclipse before it
/// is repeated every `period_s`. A recording that starts (ends) dark starts (ends) an
/// eclipse at its first (last) reading.
fn eclipse_windows(time_s: &[f64], value: &[f64], below: f64, period_s: f64) -> Vec<Vec<f64>> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut entry: Option<f64> = None;
    let mut template: Option<(f64, f64)> = None;
    let mut last: Option<(f64, bool)> = None;
    for (&t, &v) in time_s.iter().zip(value) {
        let dark = v < below;
        match last {
            None if dark => {
                entry = Some(if t <= INPUT_MAX_GAP_S { 0.0 } else { t });
            }
            None => {}
            Some((t0, _)) if t - t0 > INPUT_MAX_GAP_S => {
                // close what is open at the gap's start, bridge the gap, reopen after
                if let Some(a) = entry.take() {
                    out.push((a, t0));
                }
                if let Some((a, b)) = template {
                    let mut k = 1.0;
                    while a + k * period_s < t {
                        out.push((a + k * period_s, b + k * period_s));
                        k += 1.0;
                    }
                }
                if dark {
                    entry = Some(t);
                }
            }
            Some((t0, d0)) if d0 != dark => {
                let mid = 0.5 * (t0 + t);
                if dark {
                    entry = Some(mid);
                } else if let Some(a) = entry.take() {
                    out.push((a, mid));
                    template = Some((a, mid));
                }
            }
            _ => {}
        }
        last = Some((t, dark));
    }
    if let (Some(a), Some((t, _))) = (entry, last) {
        out.push((a, t));
    }
    // in order, overlaps (a bridged eclipse meeting a measured one) merged
    out.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for (a, b) in out {
        match merged.last_mut() {
            Some(l) if a <= l.1 => l.1 = l.1.max(b),
            _ => merged.push((a, b)),
        }
    }
    merged.into_iter().map(|(a, b)| vec![a, b]).collect()
}

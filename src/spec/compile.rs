//! Spec → validated numeric model. Every check of a scenario lives here (and in the
//! constructors it calls), so that a scenario built from TOML, from `--set` or from a
//! program meets the same invariants with the same error text.

use std::collections::HashMap;

use super::keys::{ElementKeys, KeyPath, element_keys};
use super::*;
use crate::gear::disc::{BoreFit, DiscMaterial};
use crate::gear::involute::{inv, shifted_tooth_thickness};
use crate::gear::strain::StrainLaw;
use crate::gear::{CenterDistance, Coating, Gear, GearPair, MAX_GEAR_NODES};
use crate::orbit::dated::{DatedEnvironment, Shadow};
use crate::orbit::tle::{TleError, TleOrbit};
use crate::orbit::{CircularEnvironment, Environment, EnvironmentModel, Incidence, Orbit, Profile};
use crate::spec::quantity::{self as q, Quantity, Rule};
use crate::spec::scenario::SolverSettings;
use crate::spec::scenario::{
    Bindings, DERIVED_QUANTITIES, MAX_DURATION_S, MIN_DURATION_S, RunControl, Scenario, Sensor,
    SensorTarget,
};
use crate::thermal::iteration::{
    DENSE_MAX_NODES, LinearSolver, SPARSE_MAX_FLOPS, direct_fill_estimate,
};
use crate::thermal::{
    BoundaryNode, Conductor, DiffusionNode, Heater, Load, LoadKind, Mode, Network, NodeRef,
    Radiator, ThermalModel, When,
};
use crate::units::{SECONDS_PER_DAY, exact, num};

/// A spec that does not make a valid model: the key path and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{key}`: {message}")]
pub struct SpecError {
    pub key: KeyPath,
    pub message: String,
    /// Another key the error concerns (the first of two that clash): its line is named
    /// too where the error is placed in the file.
    pub also: Option<KeyPath>,
}

/// The checks, each naming the key path it checks.
struct Cx;

impl Cx {
    /// An error at `path`.
    fn err(&self, path: &KeyPath, message: impl Into<String>) -> SpecError {
        SpecError {
            key: path.clone(),
            message: message.into(),
            also: None,
        }
    }

    /// An error at `path` that clashes with `other` (two of one name).
    fn clash(&self, path: &KeyPath, other: &KeyPath, message: impl Into<String>) -> SpecError {
        SpecError {
            key: path.clone(),
            message: message.into(),
            also: Some(other.clone()),
        }
    }

    fn finite(&self, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(path, format!("must be a finite number (got {})", exact(v))))
        }
    }

    fn positive(&self, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.err(path, format!("must be > 0 (got {})", exact(v))))
        }
    }

    /// A value > 0 and ≤ `hi` (a physically sensible upper bound, named in the error).
    fn positive_up_to(
        &self,
        path: &KeyPath,
        v: f64,
        hi: f64,
        unit: &str,
    ) -> Result<f64, SpecError> {
        self.positive(path, v)?;
        if v <= hi {
            Ok(v)
        } else {
            Err(self.err(
                path,
                format!("must be at most {} {unit} (got {})", num(hi), exact(v)),
            ))
        }
    }

    /// A finite value ≥ `lo` (a physically sensible lower bound, named in the error).
    fn at_least(&self, path: &KeyPath, v: f64, lo: f64, unit: &str) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        if v >= lo {
            Ok(v)
        } else {
            Err(self.err(
                path,
                format!("must be at least {} {unit} (got {})", num(lo), exact(v)),
            ))
        }
    }

    fn non_negative(&self, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(self.err(path, format!("must be ≥ 0 (got {})", exact(v))))
        }
    }

    /// `v` checked by the rule of quantity `q` (see [`crate::spec::quantity`]), with its
    /// error text.
    fn quantity(&self, q: &Quantity, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        match q.rule {
            Rule::Within { lo, hi, what } => self.within(path, v, lo, hi, what),
            Rule::Span {
                lo,
                hi,
                open,
                shown,
                got_unit,
            } => {
                self.finite(path, v)?;
                let inside = if open {
                    v > lo && v < hi
                } else {
                    (lo..=hi).contains(&v)
                };
                if inside {
                    Ok(v)
                } else {
                    Err(self.err(path, format!("must be within {shown} (got {v}{got_unit})")))
                }
            }
            Rule::Positive => self.positive(path, v),
            Rule::NonNegative => self.non_negative(path, v),
            Rule::PositiveUpTo { hi } => self.positive_up_to(path, v, hi, q.unit),
            Rule::PositiveAtLeast { lo, hi } => {
                let v = self.positive_up_to(path, v, hi, q.unit)?;
                self.at_least(path, v, lo, q.unit)
            }
            Rule::AtLeast { lo } => self.at_least(path, v, lo, q.unit),
            Rule::Temperature => self.temperature(path, v),
            Rule::InContext => self.finite(path, v),
        }
    }

    /// An optional value of quantity `q`, absent standing for the quantity's default,
    /// checked by its rule.
    fn quantity_or_default(
        &self,
        q: &Quantity,
        path: &KeyPath,
        v: Option<f64>,
    ) -> Result<f64, SpecError> {
        self.quantity(q, path, v.unwrap_or(q.default_value()))
    }

    fn within(
        &self,
        path: &KeyPath,
        v: f64,
        lo: f64,
        hi: f64,
        what: &str,
    ) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.err(
                path,
                format!(
                    "{what} must be within {} … {} (got {})",
                    num(lo),
                    num(hi),
                    exact(v)
                ),
            ))
        }
    }

    fn temperature(&self, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        if v > 0.0 && v < 5000.0 {
            Ok(v)
        } else {
            Err(self.err(
                path,
                format!("is a temperature in kelvin and must be above 0 and below 5000 K (got {v}; °C values need + 273.15)"),
            ))
        }
    }

    fn profile(
        &self,
        path: &KeyPath,
        raw: ProfileSpec,
        check: &dyn Fn(&KeyPath, f64) -> Result<f64, SpecError>,
    ) -> Result<Profile, SpecError> {
        match raw {
            ProfileSpec::Constant(v) => Ok(Profile::Constant(check(path, v)?)),
            ProfileSpec::Table(t) => {
                let (time_s, tkey) = match (t.time_s, t.time_days) {
                    (Some(s), None) => (s, "time_s"),
                    (None, Some(d)) => (
                        d.into_iter().map(|x| x * SECONDS_PER_DAY).collect(),
                        "time_days",
                    ),
                    _ => {
                        return Err(
                            self.err(path, "a table needs exactly one of `time_s` or `time_days`")
                        );
                    }
                };
                let tpath = path.key(tkey);
                if time_s.is_empty() {
                    return Err(self.err(&tpath, "must not be empty"));
                }
                if time_s.len() != t.value.len() {
                    return Err(self.err(
                        &path.key("value"),
                        format!(
                            "has {} entries but `{tkey}` has {}",
                            t.value.len(),
                            time_s.len()
                        ),
                    ));
                }
                for (i, w) in time_s.windows(2).enumerate() {
                    self.finite(&tpath.at(i + 1), w[1])?;
                    if w[1] <= w[0] {
                        return Err(self.err(
                            &tpath.at(i + 1),
                            format!(
                                "times must increase strictly (entry {} is not after entry {i})",
                                i + 1
                            ),
                        ));
                    }
                }
                self.finite(&tpath.at(0), time_s[0])?;
                let mut value = Vec::with_capacity(t.value.len());
                for (i, v) in t.value.into_iter().enumerate() {
                    value.push(check(&path.key("value").at(i), v)?);
                }
                Ok(Profile::Table { time_s, value })
            }
        }
    }

    /// `product` or both `a` and `b` (their product; `a` a `fraction`), never both forms.
    fn product(
        &self,
        path: &KeyPath,
        product: (Option<f64>, &'static str),
        a: (Option<f64>, &'static str),
        b: (Option<f64>, &'static str),
        fraction: &Quantity,
    ) -> Result<f64, SpecError> {
        match (product.0, a.0, b.0) {
            (Some(p), None, None) => self.quantity(&q::AREA_PRODUCT_M2, &path.key(product.1), p),
            (None, Some(x), Some(y)) => {
                let x = self.quantity(fraction, &path.key(a.1), x)?;
                let y = self.quantity(&q::AREA_M2, &path.key(b.1), y)?;
                Ok(x * y)
            }
            _ => Err(self.err(
                path,
                format!(
                    "give either `{}` or both `{}` and `{}`",
                    product.1, a.1, b.1
                ),
            )),
        }
    }
}

// ---------------------------------------------------------------- validation

pub use crate::spec::quantity::{
    MAX_AREA_M2, MAX_CAPACITANCE_J_PER_K, MAX_CONDUCTANCE_W_PER_K, MAX_POWER_W,
    MIN_CAPACITANCE_J_PER_K,
};

/// Orbital periods the model accepts, s: 10 minutes … 30 days.
pub const MIN_PERIOD_S: f64 = 600.0;
pub const MAX_PERIOD_S: f64 = 30.0 * SECONDS_PER_DAY;

const SPACE: &str = "space";

/// Validates `raw` into the numeric model.
pub fn compile(raw: ScenarioSpec) -> Result<Scenario, SpecError> {
    let cx = &Cx;
    let keys = element_keys(&raw);
    check_names(cx, &raw)?;

    let (mut environment, space_sink_k) = environment(cx, &raw.orbit, raw.environment)?;
    let period_s = environment.mean_period_s();
    let view_factor_default = match &environment {
        Environment::Circular(c) => c.orbit.earth_view_factor(),
        Environment::Dated(d) => d.mean_view_factor(),
    };
    let run = run_control(cx, &raw.run, period_s)?;
    if let Environment::Dated(d) = &mut environment {
        d.set_horizon_s(run.duration_s)
            .map_err(|m| cx.err(&KeyPath::new("orbit").key("tle"), m))?;
    }
    let solver = solver_settings(cx, &raw.solver)?;

    let (table, nodes, boundaries) =
        nodes_and_boundaries(cx, &keys, raw.node, raw.boundary, space_sink_k)?;
    let diffusion = |p: &KeyPath, name: &str| table.diffusion(cx, p, name);
    let (conductors, radiators) = links(cx, &keys, &table, &raw.conductor, &raw.radiation)?;
    // Modes before loads, which may refer to them.
    let modes = modes(cx, &keys, raw.mode)?;
    let sections = LoadSections {
        sun: raw.sun,
        albedo: raw.albedo,
        earth_ir: raw.earth_ir,
        dissipation: raw.dissipation,
    };
    let (loads, mut bindings) = loads(cx, &keys, &table, sections, &modes, view_factor_default)?;
    let heaters = heaters(cx, &keys, &table, raw.heater)?;
    let (mut loads, mut radiators) = (loads, radiators);
    // Each face's key and node, for the sensors that read a face.
    let face_nodes: Vec<(String, String)> = keys
        .face
        .iter()
        .zip(&raw.face)
        .map(|(k, f)| (k.clone(), f.node.clone()))
        .collect();
    bindings.face = faces(
        cx,
        &keys,
        &table,
        raw.attitude,
        raw.face,
        &mut loads,
        &mut radiators,
    )?;

    // Gear pairs.
    let mut gears = Vec::new();
    for (i, g) in raw.gear_pair.into_iter().enumerate() {
        let p = KeyPath::new("gear_pair").elem(i, &keys.gear_pair[i]);
        let pair = gear_pair(cx, &p, g, i, &nodes, &diffusion)?;
        if gears.iter().any(|x: &GearPair| x.name == pair.name) {
            return Err(cx.err(
                &KeyPath::new("gear_pair").at(i).key("name"),
                format!("gear pair `{}` is defined twice", pair.name),
            ));
        }
        gears.push(pair);
    }

    // Sensors (after the gear pairs they may name).
    let sensors = sensors(
        cx,
        raw.sensor,
        &keys.sensor,
        &gears,
        &face_nodes,
        &diffusion,
    )?;
    let recording = recording_format(cx, raw.recording, &environment)?;

    let network = Network {
        nodes,
        boundaries,
        conductors,
        radiators,
        loads,
        heaters,
    };
    // An explicit direct solver must fit the network.
    let sp = KeyPath::new("solver");
    let n = network.nodes.len();
    match solver.linear {
        LinearSolver::Dense if n > DENSE_MAX_NODES => {
            return Err(cx.err(
                &sp.key("linear"),
                format!(
                    "\"dense\" takes 16 n² bytes ({:.1} GB) and O(n³) per factorisation for {n} nodes; it is limited to {DENSE_MAX_NODES} nodes: use \"iterative\" or \"auto\"",
                    16.0 * (n * n) as f64 / 1e9
                ),
            ));
        }
        LinearSolver::Sparse => {
            let (fill, flops) = direct_fill_estimate(&crate::thermal::Compiled::new(&network));
            if flops > SPARSE_MAX_FLOPS {
                return Err(cx.err(
                    &sp.key("linear"),
                    format!(
                        "the sparse LU of this network would fill in to about {} entries and take about {} operations per factorisation (the limit is {}): use \"iterative\" or \"auto\"",
                        num(fill as f64),
                        num(flops),
                        num(SPARSE_MAX_FLOPS)
                    ),
                ));
            }
        }
        _ => {}
    }

    Ok(Scenario {
        gears,
        bindings,
        name: raw.scenario.name,
        description: raw.scenario.description,
        thermal: ThermalModel {
            environment,
            network,
            modes,
        },
        run,
        solver,
        sensors,
        recording,
    })
}

/// `[orbit] eclipses_s`: [entry, exit] windows, finite, ≥ 0, each entry before its exit
/// and before the next entry.
fn given_eclipses(
    cx: &Cx,
    op: &KeyPath,
    w: Option<&[Vec<f64>]>,
) -> Result<Option<crate::orbit::dated::GivenEclipses>, SpecError> {
    let Some(w) = w else { return Ok(None) };
    let p = op.key("eclipses_s");
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (i, pair) in w.iter().enumerate() {
        let [a, b] = pair[..] else {
            return Err(cx.err(&p.at(i), "an eclipse is [entry, exit] in s"));
        };
        let after = out.last().map_or(0.0, |l| l.1);
        if !(a.is_finite() && b.is_finite() && a >= after && b > a) {
            return Err(cx.err(
                &p.at(i),
                format!("[{a}, {b}]: windows must be finite, from 0 on, each entry before its exit and after the last exit"),
            ));
        }
        out.push((a, b));
    }
    Ok(Some(out.into()))
}

/// `[recording]`: the layout of this spacecraft's recordings. UTC time needs a dated
/// scenario (its `start_utc` is the recording's t = 0).
fn recording_format(
    cx: &Cx,
    spec: Option<RecordingSpec>,
    environment: &Environment,
) -> Result<crate::spec::scenario::RecordingFormat, SpecError> {
    use crate::spec::scenario::{DuplicateTimes, RecordingFormat, TimeFormat};
    use crate::spec::{RepeatedRows, TimeFormatName};
    let p = KeyPath::new("recording");
    let Some(spec) = spec else {
        return Ok(RecordingFormat::default());
    };
    let mut f = RecordingFormat::default();
    if let Some(c) = spec.time_column {
        if c.trim().is_empty() {
            return Err(cx.err(&p.key("time_column"), "is empty"));
        }
        f.time_column = c;
    }
    f.time = match spec.time_format {
        None | Some(TimeFormatName::Seconds) => TimeFormat::Seconds,
        Some(TimeFormatName::Utc) => match environment.start_utc() {
            Some(origin) => TimeFormat::Utc { origin },
            None => {
                return Err(cx.err(
                    &p.key("time_format"),
                    "\"utc\" needs a dated scenario: give [orbit] tle and start_utc (the recording's t = 0)",
                ));
            }
        },
    };
    f.ignore_columns = spec.ignore_columns.unwrap_or_default();
    if let Some(dup) = f
        .ignore_columns
        .iter()
        .enumerate()
        .find(|(i, c)| f.ignore_columns[..*i].contains(c) || **c == f.time_column)
    {
        return Err(cx.err(
            &p.key("ignore_columns").at(dup.0),
            format!("`{}` is listed twice or is the time column", dup.1),
        ));
    }
    f.repeated_rows_are_fill = spec.repeated_rows == Some(RepeatedRows::Fill);
    f.duplicate_times = spec.duplicate_times.unwrap_or(DuplicateTimes::Refuse);
    Ok(f)
}

/// The names of a network's nodes, diffusion and boundary, as the spec's elements
/// refer to them.
struct NodeTable {
    names: HashMap<String, NodeRef>,
}

impl NodeTable {
    /// The node `name` (at key `p`).
    fn lookup(&self, cx: &Cx, p: &KeyPath, name: &str) -> Result<NodeRef, SpecError> {
        self.names.get(name).copied().ok_or_else(|| {
            let mut known: Vec<&str> = self.names.keys().map(String::as_str).collect();
            known.sort();
            cx.err(
                p,
                format!("unknown node `{name}` (known: {})", known.join(", ")),
            )
        })
    }

    /// The diffusion node `name` (at key `p`): a boundary is refused.
    fn diffusion(&self, cx: &Cx, p: &KeyPath, name: &str) -> Result<usize, SpecError> {
        match self.lookup(cx, p, name)? {
            NodeRef::Diffusion(i) => Ok(i),
            NodeRef::Boundary(_) => Err(cx.err(
                p,
                format!("`{name}` is a boundary node; this needs a diffusion node"),
            )),
        }
    }

    /// The two ends of a link (`between` at element `p`): two different nodes, not
    /// both boundaries.
    fn pair(
        &self,
        cx: &Cx,
        p: &KeyPath,
        between: &[String],
    ) -> Result<(NodeRef, NodeRef), SpecError> {
        let bp = p.key("between");
        if between.len() != 2 {
            return Err(cx.err(
                &bp,
                format!(
                    "lists {} node(s); a link joins exactly two: between = [\"a\", \"b\"]",
                    between.len()
                ),
            ));
        }
        let a = self.lookup(cx, &bp.at(0), &between[0])?;
        let b = self.lookup(cx, &bp.at(1), &between[1])?;
        if a == b {
            return Err(cx.err(&bp, format!("links `{}` to itself", between[0])));
        }
        if matches!((a, b), (NodeRef::Boundary(_), NodeRef::Boundary(_))) {
            return Err(cx.err(
                &bp,
                "links two boundary nodes; it would carry no heat the model tracks",
            ));
        }
        Ok((a, b))
    }
}

/// `[[node]]` and `[[boundary]]` (after the built-in `space` at `space_sink_k`), and
/// the table of their names.
fn nodes_and_boundaries(
    cx: &Cx,
    keys: &ElementKeys,
    node_specs: Vec<NodeSpec>,
    boundary_specs: Vec<BoundarySpec>,
    space_sink_k: f64,
) -> Result<(NodeTable, Vec<DiffusionNode>, Vec<BoundaryNode>), SpecError> {
    let mut names: HashMap<String, NodeRef> = HashMap::new();
    let np = KeyPath::new("node");
    let mut nodes = Vec::new();
    for (i, n) in node_specs.into_iter().enumerate() {
        let p = np.elem(i, &keys.node[i]);
        check_name(cx, &np.at(i).key("name"), &n.name, &names)?;
        let node = DiffusionNode {
            capacitance_j_per_k: cx.quantity(
                &q::CAPACITANCE_J_PER_K,
                &p.key("capacitance_j_per_k"),
                n.capacitance_j_per_k,
            )?,
            initial_temperature_k: cx.quantity(
                &q::TEMPERATURE_K,
                &p.key("initial_temperature_k"),
                n.initial_temperature_k,
            )?,
            radius_m: match n.radius_mm {
                Some(r) => Some(cx.quantity(&q::NODE_RADIUS_MM, &p.key("radius_mm"), r)? * 1e-3),
                None => None,
            },
            name: n.name,
        };
        names.insert(node.name.clone(), NodeRef::Diffusion(i));
        nodes.push(node);
    }
    if nodes.is_empty() {
        return Err(cx.err(
            &np,
            "the network needs at least one diffusion node ([[node]])",
        ));
    }
    let bp = KeyPath::new("boundary");
    let mut boundaries = vec![BoundaryNode {
        name: SPACE.to_string(),
        temperature_k: Profile::Constant(space_sink_k),
    }];
    names.insert(SPACE.to_string(), NodeRef::Boundary(0));
    for (i, b) in boundary_specs.into_iter().enumerate() {
        let p = bp.elem(i, &keys.boundary[i]);
        if b.name == SPACE {
            return Err(cx.err(
                &bp.at(i).key("name"),
                "`space` is built in; set its temperature with environment.space_sink_k",
            ));
        }
        check_name(cx, &bp.at(i).key("name"), &b.name, &names)?;
        let t = cx.profile(&p.key("temperature_k"), b.temperature_k, &|pp, v| {
            cx.quantity(&q::TEMPERATURE_K, pp, v)
        })?;
        names.insert(b.name.clone(), NodeRef::Boundary(boundaries.len()));
        boundaries.push(BoundaryNode {
            name: b.name,
            temperature_k: t,
        });
    }
    Ok((NodeTable { names }, nodes, boundaries))
}

/// `[[conductor]]` and `[[radiation]]`.
fn links(
    cx: &Cx,
    keys: &ElementKeys,
    table: &NodeTable,
    conductor_specs: &[ConductorSpec],
    radiation_specs: &[RadiationSpec],
) -> Result<(Vec<Conductor>, Vec<Radiator>), SpecError> {
    let mut conductors = Vec::new();
    for (i, c) in conductor_specs.iter().enumerate() {
        let p = KeyPath::new("conductor").elem(i, &keys.conductor[i]);
        let (a, b) = table.pair(cx, &p, &c.between)?;
        conductors.push(Conductor {
            a,
            b,
            conductance_w_per_k: check::value(
                &q::CONDUCTANCE_W_PER_K,
                &p.key("conductance_w_per_k"),
                c.conductance_w_per_k,
            )?,
        });
    }
    let mut radiators = Vec::new();
    for (i, r) in radiation_specs.iter().enumerate() {
        let p = KeyPath::new("radiation").elem(i, &keys.radiation[i]);
        let (a, b) = table.pair(cx, &p, &r.between)?;
        let ea = cx.product(
            &p,
            (r.emissivity_area_m2, "emissivity_area_m2"),
            (r.emissivity, "emissivity"),
            (r.area_m2, "area_m2"),
            &q::EMISSIVITY,
        )?;
        radiators.push(Radiator {
            a,
            b,
            emissivity_area_m2: ea,
        });
    }

    Ok((conductors, radiators))
}

/// `[[mode]]`: named windows of mission time.
fn modes(cx: &Cx, keys: &ElementKeys, specs: Vec<ModeSpec>) -> Result<Vec<Mode>, SpecError> {
    let mut modes = Vec::new();
    for (i, m) in specs.into_iter().enumerate() {
        let p = KeyPath::new("mode").elem(i, &keys.mode[i]);
        if ["always", "sunlit", "eclipse"].contains(&m.name.as_str()) {
            return Err(cx.err(
                &KeyPath::new("mode").at(i).key("name"),
                format!("`{}` cannot name a mode", m.name),
            ));
        }
        if modes.iter().any(|x: &Mode| x.name == m.name) {
            return Err(cx.err(
                &KeyPath::new("mode").at(i).key("name"),
                format!("mode `{}` is defined twice", m.name),
            ));
        }
        let (windows, wkey, scale) = match (m.windows_s, m.windows_days) {
            (Some(w), None) => (w, "windows_s", 1.0),
            (None, Some(w)) => (w, "windows_days", SECONDS_PER_DAY),
            _ => return Err(cx.err(&p, "give exactly one of `windows_s` or `windows_days`")),
        };
        let mut windows_s = Vec::new();
        let mut last_end = f64::NEG_INFINITY;
        for (k, w) in windows.into_iter().enumerate() {
            let wp = p.key(wkey).at(k);
            let [a, b] = w[..] else {
                return Err(cx.err(
                    &wp,
                    format!("a window is [start, end] (got {} numbers)", w.len()),
                ));
            };
            cx.finite(&wp, a)?;
            cx.finite(&wp, b)?;
            if b <= a || a < last_end {
                return Err(cx.err(
                    &wp,
                    "windows are [start, end] with end > start, in increasing order, not overlapping",
                ));
            }
            last_end = b;
            windows_s.push((a * scale, b * scale));
        }
        modes.push(Mode {
            name: m.name,
            windows_s,
        });
    }

    Ok(modes)
}

/// The load sections of a spec, in the order their loads are compiled.
struct LoadSections {
    sun: Vec<SunSpec>,
    albedo: Vec<AlbedoSpec>,
    earth_ir: Vec<EarthIrSpec>,
    dissipation: Vec<DissipationSpec>,
}

/// The loads (`[[sun]]`, `[[albedo]]`, `[[earth_ir]]`, `[[dissipation]]`, in that
/// order) and where each element landed among them ([`Bindings`]). Earth-facing loads
/// take `view_factor_default` ((R/(R+h))²) unless they give one.
fn loads(
    cx: &Cx,
    keys: &ElementKeys,
    table: &NodeTable,
    raw: LoadSections,
    modes: &[Mode],
    view_factor_default: f64,
) -> Result<(Vec<Load>, Bindings), SpecError> {
    let diffusion = |p: &KeyPath, name: &str| table.diffusion(cx, p, name);
    let mut loads = Vec::new();
    let load_name = |given: Option<String>, kind: &str, node: &str, i: usize| {
        given.unwrap_or_else(|| {
            format!(
                "{kind}{}.{node}",
                if i == 0 {
                    String::new()
                } else {
                    format!("{i}")
                }
            )
        })
    };
    // Where each load element of the spec lands among the compiled loads.
    let mut bindings = Bindings::default();
    for (i, s) in raw.sun.into_iter().enumerate() {
        let p = KeyPath::new("sun").elem(i, &keys.sun[i]);
        let node = diffusion(&p.key("node"), &s.node)?;
        let aa = cx.product(
            &p,
            (s.absorptivity_area_m2, "absorptivity_area_m2"),
            (s.absorptivity, "absorptivity"),
            (s.area_m2, "area_m2"),
            &q::ABSORPTIVITY,
        )?;
        let incidence = match s.incidence.as_deref() {
            None => Incidence::Tracking,
            Some(name) => Incidence::from_name(name).ok_or_else(|| {
                cx.err(
                    &p.key("incidence"),
                    format!(
                        "unknown incidence `{name}` (known: {})",
                        Incidence::NAMES.join(", ")
                    ),
                )
            })?,
        };
        bindings.sun.push(loads.len());
        loads.push(Load {
            name: load_name(s.name, "sun", &s.node, i),
            node,
            kind: LoadKind::Sun {
                absorptivity_area_m2: aa,
                incidence,
            },
        });
    }
    // Earth-facing loads: an area product and a view factor, (R/(R+h))² by default.
    let earth_face = |p: &KeyPath,
                      product: (Option<f64>, &'static str),
                      a: (Option<f64>, &'static str, &Quantity),
                      area: Option<f64>,
                      vf: Option<f64>| {
        let aa = cx.product(p, product, (a.0, a.1), (area, "area_m2"), a.2)?;
        let vf = cx.quantity(
            &q::VIEW_FACTOR,
            &p.key("view_factor"),
            vf.unwrap_or(view_factor_default),
        )?;
        Ok::<_, SpecError>((aa, vf))
    };
    for (i, s) in raw.albedo.into_iter().enumerate() {
        let p = KeyPath::new("albedo").elem(i, &keys.albedo[i]);
        let node = diffusion(&p.key("node"), &s.node)?;
        let (aa, vf) = earth_face(
            &p,
            (s.absorptivity_area_m2, "absorptivity_area_m2"),
            (s.absorptivity, "absorptivity", &q::ABSORPTIVITY),
            s.area_m2,
            s.view_factor,
        )?;
        bindings.albedo.push(loads.len());
        loads.push(Load {
            name: load_name(s.name, "albedo", &s.node, i),
            node,
            kind: LoadKind::Albedo {
                absorptivity_area_m2: aa,
                view_factor: vf,
            },
        });
    }
    for (i, s) in raw.earth_ir.into_iter().enumerate() {
        let p = KeyPath::new("earth_ir").elem(i, &keys.earth_ir[i]);
        let node = diffusion(&p.key("node"), &s.node)?;
        let (ea, vf) = earth_face(
            &p,
            (s.emissivity_area_m2, "emissivity_area_m2"),
            (s.emissivity, "emissivity", &q::EMISSIVITY),
            s.area_m2,
            s.view_factor,
        )?;
        bindings.earth_ir.push(loads.len());
        loads.push(Load {
            name: load_name(s.name, "earth_ir", &s.node, i),
            node,
            kind: LoadKind::EarthIr {
                emissivity_area_m2: ea,
                view_factor: vf,
            },
        });
    }
    for (i, s) in raw.dissipation.into_iter().enumerate() {
        let p = KeyPath::new("dissipation").elem(i, &keys.dissipation[i]);
        let node = diffusion(&p.key("node"), &s.node)?;
        let power = cx.profile(&p.key("power_w"), s.power_w, &|pp, v| {
            cx.quantity(&q::POWER_W, pp, v)
        })?;
        let when = match s.when.as_deref() {
            None | Some("always") => When::Always,
            Some("sunlit") => When::Sunlit,
            Some("eclipse") => When::Eclipse,
            Some(m) => When::Mode(modes.iter().position(|x| x.name == m).ok_or_else(|| {
                cx.err(
                    &p.key("when"),
                    format!(
                        "`{m}` is neither always, sunlit, eclipse nor a mode defined with [[mode]]"
                    ),
                )
            })?),
        };
        bindings.dissipation.push(loads.len());
        loads.push(Load {
            name: load_name(s.name, "dissipation", &s.node, i),
            node,
            kind: LoadKind::Dissipation {
                power_w: power,
                when,
            },
        });
    }
    Ok((loads, bindings))
}

/// `v` as a unit vector of `N` finite numbers (`shape` says what they are when the
/// count is wrong); an error naming `path` when it is short, long or zero.
fn unit_vector<const N: usize>(
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
fn unique_face_names(cx: &Cx, specs: &[FaceSpec]) -> Result<(), SpecError> {
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
fn faces(
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
    let yaw_deg = cx.quantity_or_default(&q::YAW_DEG, &ap.key("yaw_deg"), a.yaw_deg)?;
    let spinning = a.mode.as_deref() == Some("spin");
    if a.quaternion.is_some() && a.mode.as_deref() != Some("inertial") && !spinning {
        return Err(cx.err(
            &ap.key("quaternion"),
            "orients an inertially fixed or spinning body: give mode = \"inertial\" or \"spin\"",
        ));
    }
    for (given, key) in [
        (a.spin_axis.is_some(), "spin_axis"),
        (a.spin_rate_deg_per_s.is_some(), "spin_rate_deg_per_s"),
        (a.spin_averaged.is_some(), "spin_averaged"),
    ] {
        if given && !spinning {
            return Err(cx.err(
                &ap.key(key),
                "describes a spinning body: give mode = \"spin\"",
            ));
        }
    }
    let attitude = match a.mode.as_deref() {
        None | Some("nadir") => Attitude::Nadir {
            yaw_rad: yaw_deg.to_radians(),
        },
        Some(m) if a.yaw_deg.is_some() && Attitude::NAMES.contains(&m) => {
            return Err(cx.err(
                &ap.key("yaw_deg"),
                format!("turns a nadir-pointing body; mode `{m}` has no yaw"),
            ));
        }
        Some("sun") => Attitude::Sun,
        Some("tumble") => Attitude::Tumble,
        Some("inertial") => {
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
        Some("spin") => {
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
                return Err(cx.err(&ap, "a spinning body needs `spin_rate_deg_per_s`"));
            };
            let rate = cx.quantity(
                &q::SPIN_RATE_DEG_PER_S,
                &ap.key("spin_rate_deg_per_s"),
                rate,
            )?;
            Attitude::Spin {
                quaternion,
                axis_body,
                rate_rad_per_s: rate.to_radians(),
                averaged: a.spin_averaged.unwrap_or(false),
            }
        }
        Some(other) => {
            return Err(cx.err(
                &ap.key("mode"),
                format!(
                    "unknown attitude `{other}` (known: {})",
                    Attitude::NAMES.join(", ")
                ),
            ));
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
        let area = cx.quantity(&q::AREA_M2, &p.key("area_m2"), f.area_m2)?;
        let absorptivity = cx.quantity(&q::ABSORPTIVITY, &p.key("absorptivity"), f.absorptivity)?;
        let emissivity = cx.quantity(&q::EMISSIVITY, &p.key("emissivity"), f.emissivity)?;
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

/// `[[heater]]`: thermostat-controlled heaters.
fn heaters(
    cx: &Cx,
    keys: &ElementKeys,
    table: &NodeTable,
    specs: Vec<HeaterSpec>,
) -> Result<Vec<Heater>, SpecError> {
    let diffusion = |p: &KeyPath, name: &str| table.diffusion(cx, p, name);
    let mut heaters = Vec::new();
    for (i, h) in specs.into_iter().enumerate() {
        let p = KeyPath::new("heater").elem(i, &keys.heater[i]);
        let node = diffusion(&p.key("node"), &h.node)?;
        let sensor_node = match &h.sensor_node {
            Some(s) => diffusion(&p.key("sensor_node"), s)?,
            None => node,
        };
        let on_k = cx.quantity(&q::HEATER_ON_K, &p.key("on_k"), h.on_k)?;
        let off_k = cx.quantity(&q::HEATER_OFF_K, &p.key("off_k"), h.off_k)?;
        check::heater_band(&p.key("off_k"), on_k, off_k)?;
        heaters.push(Heater {
            name: h.name.unwrap_or_else(|| format!("heater.{}", h.node)),
            node,
            sensor_node,
            power_w: cx.quantity(&q::HEATER_POWER_W, &p.key("power_w"), h.power_w)?,
            on_k,
            off_k,
        });
    }

    Ok(heaters)
}

/// The sensors: recording columns read as a node's temperature (with a lag and an
/// offset) or as a gear pair's backlash.
fn sensors(
    cx: &Cx,
    specs: Vec<SensorSpec>,
    keys: &[String],
    gears: &[GearPair],
    face_nodes: &[(String, String)],
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
) -> Result<Vec<Sensor>, SpecError> {
    let mut sensors: Vec<Sensor> = Vec::new();
    for (i, s) in specs.into_iter().enumerate() {
        let p = KeyPath::new("sensor").elem(i, &keys[i]);
        if sensors.iter().any(|x| x.source_column == s.column) {
            return Err(cx.err(
                &p.key("column"),
                format!("column `{}` is defined twice", s.column),
            ));
        }
        let name = s
            .name
            .clone()
            .unwrap_or_else(|| crate::spec::scenario::sensor_name_of(&s.column));
        if let Some(other) = sensors.iter().find(|x| x.column == name) {
            return Err(cx.err(
                &p.key(if s.name.is_some() { "name" } else { "column" }),
                format!(
                    "names the channel `{name}`, as the sensor of column `{}` does; give each a `name`",
                    other.source_column
                ),
            ));
        }
        let node = match (s.node, &s.face) {
            (Some(_), Some(_)) => {
                return Err(cx.err(&p.key("face"), "give `node` or `face`, not both"));
            }
            (None, Some(face)) => Some(
                face_nodes
                    .iter()
                    .find(|(k, _)| k == face)
                    .map(|(_, n)| n.clone())
                    .ok_or_else(|| {
                        let known: Vec<&str> = face_nodes.iter().map(|(k, _)| k.as_str()).collect();
                        cx.err(
                            &p.key("face"),
                            format!(
                                "unknown face `{face}` ({})",
                                if known.is_empty() {
                                    "the scenario has no [[face]]".to_string()
                                } else {
                                    format!("known: {}", known.join(", "))
                                }
                            ),
                        )
                    })?,
            ),
            (n, None) => n,
        };
        let target = match (node, s.quantity) {
            (Some(n), None) => {
                if s.gear_pair.is_some() {
                    return Err(cx.err(
                        &p.key("gear_pair"),
                        "a temperature sensor reads a node, not a gear pair",
                    ));
                }
                SensorTarget::Node(diffusion(&p.key("node"), &n)?)
            }
            (None, Some(q)) => {
                if !DERIVED_QUANTITIES.contains(&q.as_str()) {
                    return Err(cx.err(
                        &p.key("quantity"),
                        format!(
                            "unknown quantity `{q}` (known: {})",
                            DERIVED_QUANTITIES.join(", ")
                        ),
                    ));
                }
                for (key, given) in [("tau_s", s.tau_s), ("offset_k", s.offset_k)] {
                    if given.is_some() {
                        return Err(cx.err(
                            &p.key(key),
                            format!("applies to temperature sensors only (`{q}` is derived)"),
                        ));
                    }
                }
                let pair = match &s.gear_pair {
                    None if gears.is_empty() => {
                        return Err(
                            cx.err(&p.key("quantity"), "needs a [[gear_pair]] in the scenario")
                        );
                    }
                    None => 0,
                    Some(name) => gears.iter().position(|g| &g.name == name).ok_or_else(|| {
                        cx.err(&p.key("gear_pair"), format!("unknown gear pair `{name}`"))
                    })?,
                };
                SensorTarget::Backlash(pair)
            }
            _ => {
                return Err(cx.err(&p, "give exactly one of `node`, `face` or `quantity`"));
            }
        };
        let unit_given = match s.unit.as_deref() {
            None => None,
            Some(_) if matches!(target, SensorTarget::Backlash(_)) => {
                return Err(cx.err(
                    &p.key("unit"),
                    "applies to temperature sensors only (backlash is in µm)",
                ));
            }
            Some("C" | "°C" | "degC") => Some(crate::spec::scenario::ColumnUnit::Celsius),
            Some("K") => Some(crate::spec::scenario::ColumnUnit::Kelvin),
            Some(other) => {
                return Err(cx.err(
                    &p.key("unit"),
                    format!("unknown unit `{other}` (known: C, K)"),
                ));
            }
        };
        let tau_s = cx.quantity_or_default(&q::SENSOR_TAU_S, &p.key("tau_s"), s.tau_s)?;
        let offset_k =
            cx.quantity_or_default(&q::SENSOR_OFFSET_K, &p.key("offset_k"), s.offset_k)?;
        sensors.push(Sensor {
            column: name,
            source_column: s.column,
            target,
            offset_k,
            tau_s,
            unit_given,
        });
    }
    Ok(sensors)
}

/// The orbit, its eclipses' geometry and the mission profile (β, solar flux, albedo,
/// Earth infrared, the space sink): the environment and the sink temperature. A TLE
/// makes a dated environment ([`dated_environment`]); otherwise the orbit is circular.
fn environment(
    cx: &Cx,
    orbit_spec: &OrbitSpec,
    environment_spec: EnvironmentSpec,
) -> Result<(Environment, f64), SpecError> {
    if orbit_spec.tle.is_some() {
        return dated_environment(cx, orbit_spec, environment_spec);
    }
    let op = KeyPath::new("orbit");
    for (given, key) in [
        (orbit_spec.start_utc.is_some(), "start_utc"),
        (orbit_spec.start_offset_s.is_some(), "start_offset_s"),
        (orbit_spec.eclipses_s.is_some(), "eclipses_s"),
        (orbit_spec.shadow.is_some(), "shadow"),
    ] {
        if given {
            return Err(cx.err(
                &op.key(key),
                "belongs to a real orbit: give `tle` too (or remove it for a circular orbit)",
            ));
        }
    }
    // Orbit.
    let earth_radius_m = cx.quantity_or_default(
        &q::EARTH_RADIUS_M,
        &op.key("earth_radius_m"),
        orbit_spec.earth_radius_m,
    )?;
    let Some(altitude_m) = orbit_spec.altitude_m else {
        return Err(cx.err(
            &op,
            "give `altitude_m` (a circular orbit) or `tle` and `start_utc` (a real orbit)",
        ));
    };
    let altitude_m = cx.quantity(&q::ALTITUDE_M, &op.key("altitude_m"), altitude_m)?;
    let orbit = Orbit {
        altitude_m,
        earth_radius_m,
        mu_m3_per_s2: cx.quantity_or_default(
            &q::MU_M3_PER_S2,
            &op.key("mu_m3_per_s2"),
            orbit_spec.mu_m3_per_s2,
        )?,
        // Reduced modulo 360° exactly (fmod is exact) before the conversion, so that a
        // large angle keeps its fraction of a turn.
        orbit_angle_at_start_rad: cx
            .quantity_or_default(
                &q::ORBIT_ANGLE_AT_START_DEG,
                &op.key("orbit_angle_at_start_deg"),
                orbit_spec.orbit_angle_at_start_deg,
            )?
            .rem_euclid(360.0)
            .to_radians(),
    };
    let period_s = orbit.period_s();
    if !(MIN_PERIOD_S..=MAX_PERIOD_S).contains(&period_s) {
        let which = if orbit_spec.mu_m3_per_s2.is_some() {
            "mu_m3_per_s2"
        } else {
            "altitude_m"
        };
        return Err(cx.err(
            &op.key(which),
            format!(
                "gives an orbital period of {period_s:.3e} s; it must be within {MIN_PERIOD_S} … {MAX_PERIOD_S:.0} s (10 min … 30 days)"
            ),
        ));
    }

    // Environment and mission profile.
    let ep = KeyPath::new("environment");
    let e = environment_spec;
    let Some(beta_spec) = e.beta_deg else {
        return Err(cx.err(
            &ep,
            "a circular orbit needs `beta_deg` (a number or a table over mission time)",
        ));
    };
    let beta_deg = cx.profile(&ep.key("beta_deg"), beta_spec, &|p, v| {
        cx.quantity(&q::BETA_DEG, p, v)
    })?;
    let solar_flux = cx.profile(
        &ep.key("solar_flux_w_per_m2"),
        e.solar_flux_w_per_m2.unwrap_or(ProfileSpec::Constant(
            q::SOLAR_FLUX_W_PER_M2.default_value(),
        )),
        &|p, v| cx.quantity(&q::SOLAR_FLUX_W_PER_M2, p, v),
    )?;
    let (space_sink_k, albedo, earth_ir_w_per_m2) =
        earth_and_space(cx, e.space_sink_k, e.albedo, e.earth_ir_w_per_m2)?;
    let environment = CircularEnvironment {
        orbit,
        beta_rad: beta_deg.map(f64::to_radians),
        solar_flux_w_per_m2: solar_flux,
        albedo,
        earth_ir_w_per_m2,
        space_sink_k,
    };
    Ok((environment.into(), space_sink_k))
}

/// The environment's numbers every orbit has, in the order they are checked: the
/// space sink (K), the Earth's albedo and its infrared flux (W/m²).
fn earth_and_space(
    cx: &Cx,
    space_sink_k: Option<f64>,
    albedo: Option<f64>,
    earth_ir_w_per_m2: Option<f64>,
) -> Result<(f64, f64, f64), SpecError> {
    let ep = KeyPath::new("environment");
    Ok((
        cx.quantity_or_default(&q::SPACE_SINK_K, &ep.key("space_sink_k"), space_sink_k)?,
        cx.quantity_or_default(&q::ALBEDO, &ep.key("albedo"), albedo)?,
        cx.quantity_or_default(
            &q::EARTH_IR_W_PER_M2,
            &ep.key("earth_ir_w_per_m2"),
            earth_ir_w_per_m2,
        )?,
    ))
}

/// A real orbit: the TLE (`orbit.tle`, two lines) from `orbit.start_utc` (shifted by
/// `start_offset_s`), with its shadow model; β, eclipses and period follow from the
/// geometry, and `environment.solar_flux_w_per_m2` is the flux at 1 AU.
fn dated_environment(
    cx: &Cx,
    orbit_spec: &OrbitSpec,
    e: EnvironmentSpec,
) -> Result<(Environment, f64), SpecError> {
    let op = KeyPath::new("orbit");
    for (given, key) in [
        (orbit_spec.altitude_m.is_some(), "altitude_m"),
        (orbit_spec.mu_m3_per_s2.is_some(), "mu_m3_per_s2"),
        (
            orbit_spec.orbit_angle_at_start_deg.is_some(),
            "orbit_angle_at_start_deg",
        ),
    ] {
        if given {
            return Err(cx.err(
                &op.key(key),
                "follows from the TLE; remove it (or remove `tle` for a circular orbit)",
            ));
        }
    }
    let ep = KeyPath::new("environment");
    if e.beta_deg.is_some() {
        return Err(cx.err(
            &ep.key("beta_deg"),
            "follows from the TLE and the dates; remove it (or remove `tle` for a circular orbit)",
        ));
    }
    let tp = op.key("tle");
    let lines = orbit_spec.tle.as_deref().unwrap_or_default();
    let [l1, l2] = lines else {
        return Err(cx.err(
            &tp,
            format!(
                "lists {} line(s); a TLE is two: tle = [\"1 …\", \"2 …\"]",
                lines.len()
            ),
        ));
    };
    let Some(start_text) = &orbit_spec.start_utc else {
        return Err(cx.err(
            &op,
            "a TLE needs `start_utc`: when the run starts (e.g. \"2016-02-04T00:00:00Z\")",
        ));
    };
    let start =
        crate::orbit::tle::parse_utc(start_text).map_err(|m| cx.err(&op.key("start_utc"), m))?;
    let offset_s = cx.quantity_or_default(
        &q::START_OFFSET_S,
        &op.key("start_offset_s"),
        orbit_spec.start_offset_s,
    )?;
    let start = start + sgp4::chrono::Duration::nanoseconds((offset_s * 1e9).round() as i64);
    let orbit = TleOrbit::new([l1, l2], start).map_err(|err| match err {
        TleError::Line { line, message } => cx.err(&tp.at(line - 1), message),
        TleError::Elements(m) => cx.err(&tp, m),
        TleError::Start(m) => cx.err(&op.key("start_utc"), m),
        TleError::Propagation(m) => cx.err(&tp, m),
    })?;
    let shadow = orbit_spec.shadow.unwrap_or(Shadow::Cylindrical);
    let solar_flux = match e.solar_flux_w_per_m2 {
        None => q::SOLAR_FLUX_W_PER_M2.default_value(),
        Some(ProfileSpec::Constant(v)) => {
            cx.quantity(&q::SOLAR_FLUX_W_PER_M2, &ep.key("solar_flux_w_per_m2"), v)?
        }
        Some(ProfileSpec::Table(_)) => {
            return Err(cx.err(
                &ep.key("solar_flux_w_per_m2"),
                "with a TLE is one number, the flux at 1 AU (the Sun's distance on each date scales it)",
            ));
        }
    };
    let (space_sink_k, albedo, earth_ir_w_per_m2) =
        earth_and_space(cx, e.space_sink_k, e.albedo, e.earth_ir_w_per_m2)?;
    let environment = DatedEnvironment {
        orbit,
        shadow,
        solar_flux_1au_w_per_m2: solar_flux,
        earth_radius_m: cx.quantity_or_default(
            &q::EARTH_RADIUS_M,
            &op.key("earth_radius_m"),
            orbit_spec.earth_radius_m,
        )?,
        albedo,
        earth_ir_w_per_m2,
        space_sink_k,
        horizon_s: 0.0,
        eclipses_s: given_eclipses(cx, &op, orbit_spec.eclipses_s.as_deref())?,
    };
    let period_s = environment.mean_period_s();
    if !(MIN_PERIOD_S..=MAX_PERIOD_S).contains(&period_s) {
        return Err(cx.err(
            &tp.at(1),
            format!(
                "gives an orbital period of {period_s:.3e} s; it must be within {MIN_PERIOD_S} … {MAX_PERIOD_S:.0} s (10 min … 30 days)"
            ),
        ));
    }
    Ok((environment.into(), space_sink_k))
}

/// The run's length and output interval.
fn run_control(cx: &Cx, run_spec: &RunSpec, period_s: f64) -> Result<RunControl, SpecError> {
    let rp = KeyPath::new("run");
    let duration = |key: &'static str, v: f64, unit_s: f64| {
        let d = cx.positive(&rp.key(key), v)? * unit_s;
        if d < MIN_DURATION_S {
            return Err(cx.err(
                &rp.key(key),
                format!(
                    "gives a run of {} s; runs last at least {MIN_DURATION_S} s",
                    num(d)
                ),
            ));
        }
        if d > MAX_DURATION_S {
            return Err(cx.err(
                &rp.key(key),
                format!(
                    "gives a run of {d:.3e} s; runs are limited to {MAX_DURATION_S:.0e} s (31.7 years), where time still resolves the shortest step"
                ),
            ));
        }
        Ok(d)
    };
    let duration_s = match (run_spec.orbits, run_spec.duration_s, run_spec.duration_days) {
        (Some(o), None, None) => duration("orbits", o, period_s)?,
        (None, Some(s), None) => duration("duration_s", s, 1.0)?,
        (None, None, Some(d)) => duration("duration_days", d, SECONDS_PER_DAY)?,
        _ => {
            return Err(cx.err(
                &rp,
                "give exactly one of `orbits`, `duration_s` or `duration_days`",
            ));
        }
    };
    let run = RunControl {
        duration_s,
        output_interval_s: cx.quantity_or_default(
            &q::OUTPUT_INTERVAL_S,
            &rp.key("output_interval_s"),
            run_spec.output_interval_s,
        )?,
    };
    Ok(run)
}

/// The solver's settings, defaults filled in.
fn solver_settings(cx: &Cx, solver_spec: &SolverSpec) -> Result<SolverSettings, SpecError> {
    let sp = KeyPath::new("solver");
    let defaults = SolverSettings::default();
    let solver = SolverSettings {
        tolerance_k: cx.quantity(
            &q::TOLERANCE_K,
            &sp.key("tolerance_k"),
            solver_spec.tolerance_k.unwrap_or(defaults.tolerance_k),
        )?,
        max_step_s: cx.quantity(
            &q::MAX_STEP_S,
            &sp.key("max_step_s"),
            solver_spec.max_step_s.unwrap_or(defaults.max_step_s),
        )?,
        adaptive: solver_spec.adaptive.unwrap_or(defaults.adaptive),
        linear: solver_spec.linear.unwrap_or(defaults.linear),
    };
    Ok(solver)
}

/// Every name a scenario gives (scenario, nodes, boundaries, conductors, radiative
/// couplings, loads, heaters, modes, gear pairs, sensor columns), checked by the one
/// rule [`crate::spec::scenario::check_name`]: names become file names (the default log,
/// `diagnose`'s `residuals-<column>.svg`), log fields, CSV headers, key paths and
/// terminal text. The description, free text, may hold no control characters (no
/// escape sequences reach a terminal).
fn check_names(cx: &Cx, raw: &ScenarioSpec) -> Result<(), SpecError> {
    let named = |section: &'static str, i: usize| KeyPath::new(section).at(i).key("name");
    let mut all: Vec<(KeyPath, &str)> =
        vec![(KeyPath::new("scenario").key("name"), &raw.scenario.name)];
    all.extend(
        raw.node
            .iter()
            .enumerate()
            .map(|(i, x)| (named("node", i), x.name.as_str())),
    );
    all.extend(
        raw.boundary
            .iter()
            .enumerate()
            .map(|(i, x)| (named("boundary", i), x.name.as_str())),
    );
    all.extend(
        raw.mode
            .iter()
            .enumerate()
            .map(|(i, x)| (named("mode", i), x.name.as_str())),
    );
    let optional = [
        (
            "conductor",
            raw.conductor
                .iter()
                .map(|x| x.name.as_deref())
                .collect::<Vec<_>>(),
        ),
        (
            "radiation",
            raw.radiation.iter().map(|x| x.name.as_deref()).collect(),
        ),
        ("sun", raw.sun.iter().map(|x| x.name.as_deref()).collect()),
        (
            "albedo",
            raw.albedo.iter().map(|x| x.name.as_deref()).collect(),
        ),
        (
            "earth_ir",
            raw.earth_ir.iter().map(|x| x.name.as_deref()).collect(),
        ),
        (
            "dissipation",
            raw.dissipation.iter().map(|x| x.name.as_deref()).collect(),
        ),
        (
            "heater",
            raw.heater.iter().map(|x| x.name.as_deref()).collect(),
        ),
        (
            "gear_pair",
            raw.gear_pair.iter().map(|x| x.name.as_deref()).collect(),
        ),
        ("face", raw.face.iter().map(|x| x.name.as_deref()).collect()),
    ];
    for (section, names) in optional {
        for (i, n) in names.into_iter().enumerate() {
            if let Some(n) = n {
                all.push((named(section, i), n));
            }
        }
    }
    all.extend(raw.sensor.iter().enumerate().filter_map(|(i, x)| {
        x.name
            .as_deref()
            .map(|n| (KeyPath::new("sensor").at(i).key("name"), n))
    }));
    // A recording's own column names may hold spaces and signs (telemetry), not
    // control characters.
    for (i, x) in raw.sensor.iter().enumerate() {
        let c = &x.column;
        let problem = if c.trim().is_empty() {
            Some("must not be empty".to_string())
        } else if c.len() > 200 {
            Some("is longer than 200 characters".to_string())
        } else if c.chars().any(char::is_control) {
            Some(format!("{c:?} holds a control character"))
        } else {
            None
        };
        if let Some(m) = problem {
            return Err(cx.err(&KeyPath::new("sensor").at(i).key("column"), m));
        }
    }
    for (p, name) in all {
        crate::spec::scenario::check_name(name).map_err(|m| cx.err(&p, m))?;
    }
    let d = &raw.scenario.description;
    if let Some(c) = d
        .chars()
        .find(|c| c.is_control() && *c != '\n' && *c != '\t')
    {
        return Err(cx.err(
            &KeyPath::new("scenario").key("description"),
            format!(
                "holds the control character {}: a description is plain text",
                c.escape_unicode()
            ),
        ));
    }
    if d.chars().count() > MAX_DESCRIPTION_LEN {
        return Err(cx.err(
            &KeyPath::new("scenario").key("description"),
            format!("is longer than {MAX_DESCRIPTION_LEN} characters"),
        ));
    }
    Ok(())
}

/// Longest scenario description.
pub const MAX_DESCRIPTION_LEN: usize = 2000;

/// A node name not yet taken (its form is checked by [`check_names`]).
fn check_name(
    cx: &Cx,
    p: &KeyPath,
    name: &str,
    names: &HashMap<String, NodeRef>,
) -> Result<(), SpecError> {
    if names.contains_key(name) {
        return Err(cx.err(p, format!("node `{name}` is defined twice")));
    }
    Ok(())
}

/// The keys that give a thermal strain law (exactly one form).
struct StrainKeys {
    alpha: Option<f64>,
    dalpha: Option<f64>,
    poly: Option<PolynomialSpec>,
    alpha_poly: Option<Vec<f64>>,
    table: Option<StrainTableSpec>,
}

/// Largest thermal strain a law may give between 20 K and 1000 K, relative to room
/// temperature: ten times that of aluminium (1.5 %) between those temperatures.
const MAX_THERMAL_STRAIN: f64 = 0.1;

/// A strain law whose values stay within ±[`MAX_THERMAL_STRAIN`] of its value at
/// 293.15 K over 20 … 1000 K (a polynomial with a wrong `scale` fails here).
fn strain_law(cx: &Cx, p: &KeyPath, keys: StrainKeys) -> Result<StrainLaw, SpecError> {
    let law = strain_law_unchecked(cx, p, keys)?;
    // every 35 K from 20 K to 1000 K (a wrong scale or coefficient shows everywhere)
    let worst = (0..=28)
        .map(|k| 20.0 + 35.0 * k as f64)
        .map(|t| (t, law.strain(t, 293.15)))
        .find(|(_, e)| e.is_nan() || e.abs() > MAX_THERMAL_STRAIN);
    if let Some((t, e)) = worst {
        return Err(cx.err(
            p,
            format!(
                "the thermal strain law gives {e:.3e} at {t} K relative to 293.15 K; a solid's thermal strain stays within ±{MAX_THERMAL_STRAIN} over 20 … 1000 K (check the coefficients and `scale`)"
            ),
        ));
    }
    Ok(law)
}

fn strain_law_unchecked(cx: &Cx, p: &KeyPath, keys: StrainKeys) -> Result<StrainLaw, SpecError> {
    let StrainKeys {
        alpha,
        dalpha,
        poly,
        alpha_poly,
        table,
    } = keys;
    if let Some(coefficients) = alpha_poly {
        if alpha.is_some() || dalpha.is_some() || poly.is_some() || table.is_some() {
            return Err(cx.err(p, "give only one thermal strain law"));
        }
        let ap = p.key("alpha_polynomial");
        if coefficients.is_empty() {
            return Err(cx.err(&ap, "must not be empty"));
        }
        for (k, c) in coefficients.iter().enumerate() {
            cx.finite(&ap.at(k), *c)?;
        }
        return Ok(StrainLaw::AlphaPolynomial { coefficients });
    }
    let alpha_ok = |v: f64, key: &'static str| cx.quantity(&q::EXPANSION_PER_K, &p.key(key), v);
    match (alpha, dalpha, poly, table) {
        (Some(a), None, None, None) => Ok(StrainLaw::Linear { alpha_per_k: alpha_ok(a, "alpha_per_k")? }),
        (Some(a), Some(d), None, None) => Ok(StrainLaw::Quadratic {
            alpha_per_k: alpha_ok(a, "alpha_per_k")?,
            dalpha_dt_per_k2: cx.quantity(&q::DALPHA_DT_PER_K2, &p.key("dalpha_dt_per_k2"), d)?,
        }),
        (None, None, Some(poly), None) => {
            let pp = p.key("strain_polynomial");
            if poly.coefficients.is_empty() {
                return Err(cx.err(&pp.key("coefficients"), "must not be empty"));
            }
            for (k, c) in poly.coefficients.iter().enumerate() {
                cx.finite(&pp.key("coefficients").at(k), *c)?;
            }
            cx.finite(&pp.key("scale"), poly.scale)?;
            Ok(StrainLaw::Polynomial { coefficients: poly.coefficients, scale: poly.scale })
        }
        (None, None, None, Some(t)) => {
            let tp = p.key("strain_table");
            if t.temperature_k.len() < 2 || t.temperature_k.len() != t.strain.len() {
                return Err(cx.err(&tp, "needs at least two points and as many `strain` as `temperature_k` entries"));
            }
            for (k, w) in t.temperature_k.windows(2).enumerate() {
                if w[1] <= w[0] || w[1].is_nan() || w[0].is_nan() {
                    return Err(cx.err(&tp.key("temperature_k").at(k + 1), "temperatures must increase strictly"));
                }
            }
            for (k, v) in t.strain.iter().enumerate() {
                cx.finite(&tp.key("strain").at(k), *v)?;
            }
            Ok(StrainLaw::Table { temperature_k: t.temperature_k, strain: t.strain })
        }
        _ => Err(cx.err(
            p,
            "give the thermal strain as `alpha_per_k` (optionally with `dalpha_dt_per_k2`), or `alpha_polynomial`, or `strain_polynomial`, or `strain_table`",
        )),
    }
}

fn disc_material(cx: &Cx, p: &KeyPath, m: MaterialSpec) -> Result<DiscMaterial, SpecError> {
    let youngs = cx.positive(&p.key("youngs_modulus_pa"), m.youngs_modulus_pa)?;
    if youngs < 1e8 {
        return Err(cx.err(
            &p.key("youngs_modulus_pa"),
            format!("is in pascal: {youngs} Pa is not a metal (steel is 2e11)"),
        ));
    }
    let poisson = cx.quantity(&q::POISSON, &p.key("poisson"), m.poisson)?;
    Ok(DiscMaterial {
        strain: strain_law(
            cx,
            p,
            StrainKeys {
                alpha: m.alpha_per_k,
                dalpha: m.dalpha_dt_per_k2,
                poly: m.strain_polynomial,
                alpha_poly: m.alpha_polynomial,
                table: m.strain_table,
            },
        )?,
        youngs_modulus_pa: youngs,
        poisson,
    })
}

/// Relative tolerance for node radii that must sit on the bore and the base circle.
const RADIUS_TOLERANCE: f64 = 1e-5;

fn gear_pair(
    cx: &Cx,
    p: &KeyPath,
    g: GearPairSpec,
    index: usize,
    nodes: &[DiffusionNode],
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
) -> Result<GearPair, SpecError> {
    let module_m = cx.quantity(&q::MODULE_MM, &p.key("module_mm"), g.module_mm)? * 1e-3;
    let alpha0_deg = cx.quantity(
        &q::PRESSURE_ANGLE_DEG,
        &p.key("pressure_angle_deg"),
        g.pressure_angle_deg,
    )?;
    let alpha0 = alpha0_deg.to_radians();
    let t_ref = cx.quantity(
        &q::TEMPERATURE_K,
        &p.key("reference_temperature_k"),
        g.reference_temperature_k,
    )?;
    let coating = coating(cx, p, g.coating)?;
    let cutter = Cutter { module_m, alpha0 };
    let pinion = gear(
        cx,
        &p.key("pinion"),
        "pinion",
        g.pinion,
        cutter,
        nodes,
        diffusion,
    )?;
    let wheel = gear(
        cx,
        &p.key("wheel"),
        "wheel",
        g.wheel,
        cutter,
        nodes,
        diffusion,
    )?;
    let center = center_distance(cx, p, g.center_distance, diffusion)?;
    let pair = GearPair {
        name: g.name.unwrap_or_else(|| {
            if index == 0 {
                "mesh".into()
            } else {
                format!("mesh{index}")
            }
        }),
        module_m,
        pressure_angle_rad: alpha0,
        face_width_m: cx.quantity(&q::FACE_WIDTH_MM, &p.key("face_width_mm"), g.face_width_mm)?
            * 1e-3,
        center_distance_m: cx.positive(&p.key("center_distance_mm"), g.center_distance_mm)? * 1e-3,
        center,
        reference_temperature_k: t_ref,
        coating,
        min_backlash_m: cx.quantity(
            &q::MIN_BACKLASH_UM,
            &p.key("min_backlash_um"),
            g.min_backlash_um,
        )? * 1e-6,
        gears: [pinion, wheel],
        constants: Default::default(),
        paper_model: true,
    };
    check_mesh(cx, p, &pair)?;
    Ok(pair)
}

/// The coating of a pair's teeth (`gear_pair.….coating`).
fn coating(cx: &Cx, p: &KeyPath, c: CoatingSpec) -> Result<Coating, SpecError> {
    let cp = p.key("coating");
    Ok(Coating {
        thickness_m: cx.quantity(
            &q::COATING_THICKNESS_UM,
            &cp.key("thickness_um"),
            c.thickness_um,
        )? * 1e-6,
        alpha_per_k: cx.quantity(&q::EXPANSION_PER_K, &cp.key("alpha_per_k"), c.alpha_per_k)?,
        poisson: cx.quantity(&q::POISSON, &cp.key("poisson"), c.poisson)?,
    })
}

/// The module and pressure angle a pair's gears are cut with.
#[derive(Clone, Copy)]
struct Cutter {
    module_m: f64,
    alpha0: f64,
}

/// One gear (`gear_pair.….pinion` or `.wheel`, at key `gp`): its teeth, radii, tooth
/// thickness, nodes from the bore to the base circle, material and bore fit.
fn gear(
    cx: &Cx,
    gp: &KeyPath,
    key: &str,
    raw: GearSpec,
    cutter: Cutter,
    nodes: &[DiffusionNode],
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
) -> Result<Gear, SpecError> {
    let Cutter { module_m, alpha0 } = cutter;
    let teeth = raw.teeth;
    if !(5..=10_000).contains(&teeth) {
        return Err(cx.err(
            &gp.key("teeth"),
            format!("must be within 5 … 10000 (got {teeth})"),
        ));
    }
    let teeth = teeth as u32;
    let shift = cx.quantity(
        &q::PROFILE_SHIFT,
        &gp.key("profile_shift"),
        raw.profile_shift,
    )?;
    let r_ref = module_m * teeth as f64 / 2.0;
    let r_b = r_ref * alpha0.cos();
    let tip = cx.quantity(
        &q::TIP_RADIUS_MM,
        &gp.key("tip_radius_mm"),
        raw.tip_radius_mm,
    )? * 1e-3;
    let root = cx.quantity(
        &q::ROOT_RADIUS_MM,
        &gp.key("root_radius_mm"),
        raw.root_radius_mm,
    )? * 1e-3;
    let bore = cx.quantity(
        &q::BORE_RADIUS_MM,
        &gp.key("bore_radius_mm"),
        raw.bore_radius_mm,
    )? * 1e-3;
    let mm = |x: f64| format!("{} mm", crate::units::fixed(x * 1e3, 6));
    if bore >= r_b {
        return Err(cx.err(
            &gp.key("bore_radius_mm"),
            format!(
                "bore radius {} must be below the base radius r_b = m z cos α₀ / 2 = {}",
                mm(bore),
                mm(r_b)
            ),
        ));
    }
    if bore >= root {
        return Err(cx.err(
            &gp.key("bore_radius_mm"),
            format!(
                "bore radius {} must be below the root radius {}",
                mm(bore),
                mm(root)
            ),
        ));
    }
    if tip <= r_b || tip <= root {
        return Err(cx.err(
            &gp.key("tip_radius_mm"),
            format!(
                "tip radius {} must exceed the base radius {} and the root radius {}",
                mm(tip),
                mm(r_b),
                mm(root)
            ),
        ));
    }
    let (thickness, tkey) = tooth_thickness(cx, gp, &raw, cutter, shift)?;
    check_tooth(cx, &gp.key(tkey), cutter, thickness, r_ref, r_b, tip)?;
    let (node_ids, radii) = gear_nodes(cx, gp, &raw.nodes, nodes, diffusion, bore, r_b)?;
    let material = disc_material(cx, &gp.key("material"), raw.material)?;
    let shaft_node = match &raw.shaft_node {
        Some(n) => Some(diffusion(&gp.key("shaft_node"), n)?),
        None => None,
    };
    let fit = match raw.bore_fit.as_deref() {
        None | Some("free") => BoreFit::Free,
        Some("rigid") => BoreFit::Rigid,
        Some("elastic") => {
            let shaft = raw
                .shaft_material
                .ok_or_else(|| cx.err(gp, "an elastic bore fit needs `shaft_material`"))?;
            if shaft_node.is_none() {
                return Err(cx.err(
                    gp,
                    "an elastic bore fit needs `shaft_node` (the shaft's temperature)",
                ));
            }
            let sm = disc_material(cx, &gp.key("shaft_material"), shaft)?;
            BoreFit::Elastic {
                interference_m: cx.finite(
                    &gp.key("interference_um"),
                    raw.interference_um.unwrap_or(0.0),
                )? * 1e-6,
                shaft_youngs_modulus_pa: sm.youngs_modulus_pa,
                shaft_poisson: sm.poisson,
                shaft_strain: sm.strain,
            }
        }
        Some(other) => {
            return Err(cx.err(
                &gp.key("bore_fit"),
                format!("unknown bore fit `{other}` (known: free, rigid, elastic)"),
            ));
        }
    };
    Ok(Gear {
        name: key.to_string(),
        teeth,
        profile_shift: shift,
        tip_radius_m: tip,
        root_radius_m: root,
        bore_radius_m: bore,
        tooth_thickness_m: thickness,
        material,
        fit,
        nodes: node_ids,
        node_radii_m: radii,
        shaft_node,
    })
}

/// The tooth thickness on the reference circle, from `tooth_thickness_mm` or from
/// `tooth_thinning_um` (below the profile-shifted nominal), and the key it came from.
fn tooth_thickness(
    cx: &Cx,
    gp: &KeyPath,
    raw: &GearSpec,
    cutter: Cutter,
    shift: f64,
) -> Result<(f64, &'static str), SpecError> {
    let Cutter { module_m, alpha0 } = cutter;
    Ok(match (raw.tooth_thickness_mm, raw.tooth_thinning_um) {
        (Some(s), None) => (
            cx.positive(&gp.key("tooth_thickness_mm"), s)? * 1e-3,
            "tooth_thickness_mm",
        ),
        (None, Some(t)) => {
            let t = cx.finite(&gp.key("tooth_thinning_um"), t)?;
            (
                shifted_tooth_thickness(module_m, shift, alpha0) - t * 1e-6,
                "tooth_thinning_um",
            )
        }
        _ => {
            return Err(cx.err(
                gp,
                "give exactly one of `tooth_thickness_mm` or `tooth_thinning_um`",
            ));
        }
    })
}

/// The tooth must exist and fit: 0 < s < π m on the reference circle, and not come to
/// a point below the tip (s_a > 0 on the tip circle). Errors name `key`.
fn check_tooth(
    cx: &Cx,
    key: &KeyPath,
    cutter: Cutter,
    thickness: f64,
    r_ref: f64,
    r_b: f64,
    tip: f64,
) -> Result<(), SpecError> {
    let Cutter { module_m, alpha0 } = cutter;
    let mm = |x: f64| format!("{} mm", crate::units::fixed(x * 1e3, 6));
    let pitch = std::f64::consts::PI * module_m;
    if !(thickness > 0.0 && thickness < pitch) {
        return Err(cx.err(
            key,
            format!(
                "gives a tooth thickness of {} on the reference circle; it must be within 0 … {} (the circular pitch π m)",
                mm(thickness),
                mm(pitch)
            ),
        ));
    }
    let alpha_tip = (r_b / tip).acos();
    let tip_thickness = tip * (thickness / r_ref + 2.0 * inv(alpha0) - 2.0 * inv(alpha_tip));
    if tip_thickness <= 0.0 {
        return Err(cx.err(
            key,
            format!(
                "gives a tooth thickness of {} on the reference circle, which comes to a point below the tip radius {} (thickness at the tip {})",
                mm(thickness),
                mm(tip),
                mm(tip_thickness)
            ),
        ));
    }
    Ok(())
}

/// A gear's nodes (`names`, at `gp.nodes`): 2 … MAX_GEAR_NODES diffusion nodes with
/// radii increasing from the bore (`bore`) to the base circle (`r_b`); their indices
/// and radii.
fn gear_nodes(
    cx: &Cx,
    gp: &KeyPath,
    names: &[String],
    nodes: &[DiffusionNode],
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
    bore: f64,
    r_b: f64,
) -> Result<(Vec<usize>, Vec<f64>), SpecError> {
    let mm = |x: f64| format!("{} mm", crate::units::fixed(x * 1e3, 6));
    let np = gp.key("nodes");
    if names.len() < 2 || names.len() > MAX_GEAR_NODES {
        return Err(cx.err(
            &np,
            format!("list 2 … {MAX_GEAR_NODES} nodes from the bore to the base circle"),
        ));
    }
    let mut node_ids = Vec::new();
    let mut radii = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let id = diffusion(&np.at(k), name)?;
        let r = nodes[id].radius_m.ok_or_else(|| {
            cx.err(
                &np.at(k),
                format!("node `{name}` needs `radius_mm` to be part of a gear profile"),
            )
        })?;
        if radii.last().is_some_and(|&prev| r <= prev) {
            return Err(cx.err(
                &np.at(k),
                "node radii must increase from the bore to the base circle",
            ));
        }
        node_ids.push(id);
        radii.push(r);
    }
    if (radii[0] - bore).abs() > RADIUS_TOLERANCE * bore {
        return Err(cx.err(
            &np.at(0),
            format!(
                "the first node sits at {} but the bore radius is {}",
                mm(radii[0]),
                mm(bore)
            ),
        ));
    }
    let last = *radii.last().expect("two nodes");
    if (last - r_b).abs() > RADIUS_TOLERANCE * r_b {
        return Err(cx.err(
            &np.at(radii.len() - 1),
            format!(
                "the last node sits at {} but the base radius is {}",
                mm(last),
                mm(r_b)
            ),
        ));
    }
    Ok((node_ids, radii))
}

/// How the centre distance moves (`gear_pair.….center_distance`): fixed, or with a
/// housing node's strain.
fn center_distance(
    cx: &Cx,
    p: &KeyPath,
    spec: Option<CenterDistanceSpec>,
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
) -> Result<CenterDistance, SpecError> {
    Ok(match spec {
        None => CenterDistance::Fixed,
        Some(c) => {
            let cp = p.key("center_distance");
            match c.follows.as_str() {
                "fixed" => CenterDistance::Fixed,
                "housing" => {
                    let node_name = c
                        .node
                        .as_deref()
                        .ok_or_else(|| cx.err(&cp, "needs `node`: the housing node"))?;
                    CenterDistance::Housing {
                        node: diffusion(&cp.key("node"), node_name)?,
                        strain: strain_law(
                            cx,
                            &cp,
                            StrainKeys {
                                alpha: c.alpha_per_k,
                                dalpha: c.dalpha_dt_per_k2,
                                poly: c.strain_polynomial,
                                alpha_poly: c.alpha_polynomial,
                                table: c.strain_table,
                            },
                        )?,
                    }
                }
                other => {
                    return Err(cx.err(
                        &cp.key("follows"),
                        format!("unknown `{other}` (known: fixed, housing)"),
                    ));
                }
            }
        }
    })
}

/// The assembled pair must mesh with positive backlash.
fn check_mesh(cx: &Cx, p: &KeyPath, pair: &GearPair) -> Result<(), SpecError> {
    let (module_m, alpha0) = (pair.module_m, pair.pressure_angle_rad);
    let nominal = pair.nominal_backlash_m();
    let rb_sum = pair
        .gears
        .iter()
        .map(|g| g.base_radius_m(module_m, alpha0))
        .sum::<f64>();
    if rb_sum >= pair.center_distance_m {
        return Err(cx.err(
            &p.key("center_distance_mm"),
            "is shorter than the sum of the base radii",
        ));
    }
    if nominal.is_nan() {
        return Err(cx.err(
            &p.key("center_distance_mm"),
            "the gears do not mesh at this centre distance (contact ratio below 1)",
        ));
    }
    if nominal <= 0.0 {
        return Err(cx.err(
            &p.key("center_distance_mm"),
            format!("the pair has negative backlash at assembly ({:.3} µm): the teeth are too thick for this centre distance", nominal * 1e6),
        ));
    }
    Ok(())
}

/// The checks of single values, shared with the fast parameter writes of
/// `model::Model` so that a value written by path meets the compiler's checks with its
/// error text.
pub(crate) mod check {
    use super::*;

    /// `v` checked as a value of quantity `q`, with the compiler's error text.
    pub fn value(q: &Quantity, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        Cx.quantity(q, path, v)
    }

    /// A heater's band: `on_k < off_k` (the error is at `off_k`).
    pub fn heater_band(off_path: &KeyPath, on_k: f64, off_k: f64) -> Result<(), SpecError> {
        if on_k >= off_k {
            return Err(Cx.err(
                off_path,
                format!("must be above on_k ({on_k} K): the heater switches on when the sensor falls to on_k and off when it rises to off_k"),
            ));
        }
        Ok(())
    }

    /// Gear pair `index` of `spec` compiled again against the nodes of `network` (its
    /// other parts unchanged).
    pub fn gear_pair_again(
        spec: &ScenarioSpec,
        index: usize,
        key: &str,
        network: &Network,
    ) -> Result<GearPair, SpecError> {
        let diffusion = |p: &KeyPath, name: &str| -> Result<usize, SpecError> {
            network
                .nodes
                .iter()
                .position(|n| n.name == name)
                .ok_or_else(|| Cx.err(p, format!("unknown node `{name}`")))
        };
        let p = KeyPath::new("gear_pair").elem(index, key);
        gear_pair(
            &Cx,
            &p,
            spec.gear_pair[index].clone(),
            index,
            &network.nodes,
            &diffusion,
        )
    }
}

//! A validated scenario: the thermal model, how long to run it, solver settings and
//! the sensors that name recording columns. Built by `io::scenario_toml`; everything
//! downstream may rely on it being physically valid.

use crate::gear::GearPair;
use crate::spec::quantity::MIN_MAX_STEP_S;
use crate::spec::registry;
use crate::thermal::ThermalModel;
use crate::thermal::iteration::LinearSolver;

#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    pub name: String,
    pub description: String,
    pub thermal: ThermalModel,
    pub run: RunControl,
    pub solver: SolverSettings,
    pub sensors: Vec<Sensor>,
    /// Gear pairs whose backlash is evaluated at every step.
    pub gears: Vec<GearPair>,
    /// Where the compiler put each element of the spec that the model writes into
    /// directly (`Model::set_param`).
    pub bindings: Bindings,
    /// How this spacecraft's recordings are laid out (`[recording]`).
    pub recording: RecordingFormat,
}

/// Per load element of the spec (`[[sun]]`, `[[albedo]]`, `[[earth_ir]]`,
/// `[[dissipation]]`, `[[face]]`, in file order), its index among the compiled
/// `Network::loads` (and a face's among the radiative couplings), recorded by
/// `spec::compile` as it builds them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Bindings {
    pub sun: Vec<usize>,
    pub albedo: Vec<usize>,
    pub earth_ir: Vec<usize>,
    pub dissipation: Vec<usize>,
    /// Per `[[face]]`: the index of its load and of its radiative coupling to space.
    pub face: Vec<(usize, usize)>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct RunControl {
    /// How long to simulate, s.
    pub duration_s: f64,
    /// Interval between rows of the CSV export, s.
    pub output_interval_s: f64,
}

/// A recording column and what it measures.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensor {
    /// The channel's name (a valid name: reports, plots, logs, key paths).
    pub column: String,
    /// The column as the recording spells it (telemetry's own names).
    pub source_column: String,
    pub target: SensorTarget,
    /// Constant bias added to the reading, K (temperature sensors; 0 for none).
    pub offset_k: f64,
    /// First-order time constant of the instrument, s (temperature sensors; 0: it
    /// reads its node's temperature instantly).
    pub tau_s: f64,
    /// The column's unit when the scenario says it (`unit`); else from the name.
    pub unit_given: Option<ColumnUnit>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum SensorTarget {
    /// A diffusion node's temperature.
    Node(usize),
    /// Gear pair k's exact backlash (the smallest over a mesh cycle).
    Backlash(usize),
}

/// The unit of a recording column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColumnUnit {
    Celsius,
    Kelvin,
    Micrometre,
}

impl Sensor {
    /// A sensor reading `target` directly (no offset, no lag).
    pub fn new(column: impl Into<String>, target: SensorTarget) -> Sensor {
        let column = column.into();
        Sensor {
            source_column: column.clone(),
            column,
            target,
            offset_k: 0.0,
            tau_s: 0.0,
            unit_given: None,
        }
    }

    /// As the scenario says (`unit`), else: temperatures in °C unless the column name
    /// ends in `_k`; backlash in µm.
    pub fn unit(&self) -> ColumnUnit {
        if let Some(u) = self.unit_given {
            return u;
        }
        match self.target {
            SensorTarget::Backlash(_) => ColumnUnit::Micrometre,
            SensorTarget::Node(_) if self.column.ends_with("_k") => ColumnUnit::Kelvin,
            SensorTarget::Node(_) => ColumnUnit::Celsius,
        }
    }
}

/// Integration settings. Defaults meet 0.05 K against a step-converged solution on
/// the reference network (see `tests/core_step_halving.rs`).
#[derive(Debug, Clone, PartialEq)]
pub struct SolverSettings {
    /// Local error per step allowed on any node, K. Default 0.002; typical 1e-4 … 0.01.
    pub tolerance_k: f64,
    /// Longest step, s. Default 300; the step is also capped by events.
    pub max_step_s: f64,
    /// Adaptive step-size control; when false every step is `max_step_s` (except
    /// where it lands on an event).
    pub adaptive: bool,
    /// How the implicit stages solve their linear systems. Default `Auto`: dense up to
    /// 40 nodes, iterative above (the crossover in `docs/performance.md`).
    pub linear: LinearSolver,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            tolerance_k: crate::spec::quantity::TOLERANCE_K.default_value(),
            max_step_s: crate::spec::quantity::MAX_STEP_S.default_value(),
            adaptive: true,
            linear: LinearSolver::Auto,
        }
    }
}

/// What to do about a fixed step longer than a node's time constant `tau_s`.
pub fn fixed_step_advice(tau_s: f64) -> String {
    if tau_s >= MIN_MAX_STEP_S {
        format!("use solver.adaptive = true or a solver.max_step_s below {tau_s:.3e} s")
    } else {
        format!(
            "use solver.adaptive = true (the time constant is below the shortest fixed step allowed, {MIN_MAX_STEP_S} s)"
        )
    }
}

/// Longest run, s (about 31.7 years). Beyond it the time of day no longer resolves the
/// solver's shortest step (1e-7 s) in double precision.
pub const MAX_DURATION_S: f64 = 1e9;

/// Shortest run, s.
pub const MIN_DURATION_S: f64 = 1.0;

pub use crate::spec::quantity::MIN_OUTPUT_INTERVAL_S;

/// Longest name of a scenario, node, boundary, load, heater, mode or gear pair.
pub const MAX_NAME_LEN: usize = 100;

/// Checks a name given in a scenario: 1 … 100 characters from `A–Z a–z 0–9 _ - .`,
/// beginning with a letter, a digit or `_`. Names become file names (the default log
/// `logs/<scenario>.mcap`), log field names and key paths, so nothing that could leave
/// a folder (`/`, `..`) or break a CSV header (`,`, spaces) gets in.
pub fn check_name(name: &str) -> Result<(), String> {
    let first_ok = name
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
    let rest_ok = name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    if name.is_empty() {
        Err("must not be empty".into())
    } else if name.len() > MAX_NAME_LEN {
        Err(format!("is longer than {MAX_NAME_LEN} characters"))
    } else if !(first_ok && rest_ok) {
        Err(format!(
            "{name:?} is not a valid name: use letters, digits, `_`, `-` and `.`, beginning with a letter, digit or `_`"
        ))
    } else {
        Ok(())
    }
}

/// A likely mistake that leaves the scenario valid: `check` and `run` print these.
#[derive(Debug, Clone, PartialEq)]
pub struct Warning {
    /// The key path it concerns, e.g. `node.housing.initial_temperature_k`.
    pub key: String,
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "`{}`: {}", self.key, self.message)
    }
}

/// A name as a key-path segment: quoted as in TOML when it holds a dot.
pub fn key_segment(name: &str) -> String {
    if name.contains('.') {
        format!("\"{name}\"")
    } else {
        name.to_string()
    }
}

/// The channel name of a recording column: the column itself when it is a valid name
/// ([`check_name`]), else lower-cased with each run of other characters made one `_`,
/// a sign before a letter or digit kept as `p` or `m` (`Solar Panel -X deg. C` →
/// `solar_panel_mx_deg_c`).
pub fn sensor_name_of(column: &str) -> String {
    if check_name(column).is_ok() {
        return column.to_string();
    }
    let chars: Vec<char> = column.chars().collect();
    let mut out = String::new();
    for (i, &c) in chars.iter().enumerate() {
        let next_alnum = chars.get(i + 1).is_some_and(|n| n.is_ascii_alphanumeric());
        let prev_alnum = i > 0 && chars[i - 1].is_ascii_alphanumeric();
        if c.is_ascii_alphanumeric() || c == '_' {
            out.push(c.to_ascii_lowercase());
        } else if matches!(c, '+' | '-') && next_alnum && !prev_alnum {
            out.push(if c == '+' { 'p' } else { 'm' });
        } else if !out.ends_with('_') {
            out.push('_');
        }
    }
    let out = out.trim_matches('_');
    let mut out: String = out.chars().take(MAX_NAME_LEN).collect();
    if out.is_empty() {
        out.push_str("channel");
    }
    out
}

/// Temperatures (K) below which a node's initial or reference temperature or a heater
/// set point most likely is a Celsius value typed as kelvin (150 K = −123 °C).
pub const CELSIUS_AS_KELVIN_BELOW_K: f64 = 150.0;

impl Scenario {
    /// Likely mistakes: a node with no path to a boundary (its temperature can run
    /// away), a fixed step longer than the fastest node's time constant, temperatures
    /// that look like °C typed as kelvin. O(nodes + links).
    pub fn warnings(&self) -> Vec<Warning> {
        use crate::thermal::analysis::{node_time_constants_s, unanchored_nodes};
        let net = &self.thermal.network;
        let mut w = Vec::new();
        let node_key =
            |i: usize, key: &str| format!("node.{}.{key}", key_segment(&net.nodes[i].name));
        let loose: Vec<usize> = unanchored_nodes(net)
            .iter()
            .enumerate()
            .filter_map(|(i, &u)| u.then_some(i))
            .collect();
        if let Some(&first) = loose.first() {
            let names: Vec<&str> = loose
                .iter()
                .take(8)
                .map(|&i| net.nodes[i].name.as_str())
                .collect();
            w.push(Warning {
                key: node_key(first, "name"),
                message: format!(
                    "{} node(s) have no conductive or radiative path to a boundary (space or a [[boundary]]): {}{}; their temperature can run away under any load",
                    loose.len(),
                    names.join(", "),
                    if loose.len() > names.len() { ", …" } else { "" }
                ),
            });
        }
        if let crate::orbit::Environment::Dated(d) = &self.thermal.environment {
            let year = sgp4::chrono::Datelike::year(&d.orbit.start_utc);
            let (lo, hi) = crate::orbit::sun::STATED_YEARS;
            if !(lo..=hi).contains(&year) {
                w.push(Warning {
                    key: "orbit.start_utc".into(),
                    message: format!(
                        "is in {year}: the Sun's position (the Astronomical Almanac's low-precision formulas) is stated to 0.01° for {lo} … {hi} only; beyond, its error grows slowly"
                    ),
                });
            }
            let days = d.orbit.epoch_age_days();
            if days.abs() > crate::orbit::tle::EPOCH_WARN_DAYS {
                w.push(Warning {
                    key: "orbit.start_utc".into(),
                    message: format!(
                        "starts {:.1} days from the TLE's epoch; a LEO TLE's along-track error grows to tens of km within a few days (β and eclipse lengths stay close, the minute of each eclipse drifts): a TLE nearer the start is better",
                        days.abs()
                    ),
                });
            }
        }
        // A resolved spin needs steps shorter than its turn.
        let spin = net.loads.iter().find_map(|l| match l.kind {
            crate::thermal::LoadKind::Face(crate::orbit::faces::Face {
                attitude:
                    crate::orbit::faces::Attitude::Spin {
                        rate_rad_per_s,
                        averaged: false,
                        ..
                    },
                ..
            }) if rate_rad_per_s != 0.0 => Some(2.0 * std::f64::consts::PI / rate_rad_per_s.abs()),
            _ => None,
        });
        if let Some(turn_s) = spin.filter(|t| self.solver.max_step_s > t / 8.0) {
            w.push(Warning {
                key: format!("attitude.{}", registry::SPIN_RATE_DEG_PER_S.name),
                message: format!(
                    "one turn takes {turn_s:.1} s but steps may be {} s long: the faces' loads are sampled, not followed; set solver.max_step_s ≤ {:.2} s or spin_averaged = true",
                    self.solver.max_step_s,
                    turn_s / 8.0
                ),
            });
        }
        if !self.solver.adaptive {
            let temps = net.initial_temperatures_k();
            let tau = node_time_constants_s(&self.thermal, &temps, 0.0);
            if let Some((i, &t)) = tau
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(b.1))
                .filter(|(_, t)| self.solver.max_step_s > **t)
            {
                w.push(Warning {
                    key: format!("solver.{}", registry::MAX_STEP_S.name),
                    message: format!(
                        "the fixed step of {} s (adaptive = false) exceeds the time constant of node {} ({t:.3e} s): its transients are not resolved; {}",
                        self.solver.max_step_s,
                        net.nodes[i].name,
                        fixed_step_advice(t)
                    ),
                });
            }
        }
        let celsius = |key: String, v: f64, w: &mut Vec<Warning>| {
            if v < CELSIUS_AS_KELVIN_BELOW_K {
                w.push(Warning {
                    key,
                    message: format!(
                        "{v} K ({:.2} °C) looks like a Celsius value typed as kelvin; {v} °C is {:.2} K",
                        v - crate::constants::ZERO_CELSIUS_K,
                        v + crate::constants::ZERO_CELSIUS_K
                    ),
                });
            }
        };
        for (i, n) in net.nodes.iter().enumerate() {
            celsius(
                node_key(i, registry::INITIAL_TEMPERATURE_K.name),
                n.initial_temperature_k,
                &mut w,
            );
        }
        for b in net.boundaries.iter().skip(1) {
            let (lo, _) = b.temperature_k.range();
            if (5.0..60.0).contains(&lo) {
                w.push(Warning {
                    key: format!(
                        "boundary.{}.{}",
                        key_segment(&b.name),
                        registry::BOUNDARY_TEMPERATURE_K.name
                    ),
                    message: format!(
                        "{lo} K ({:.2} °C) looks like a Celsius value typed as kelvin (cryogenic shrouds aside); {lo} °C is {:.2} K",
                        lo - crate::constants::ZERO_CELSIUS_K,
                        lo + crate::constants::ZERO_CELSIUS_K
                    ),
                });
            }
        }
        for h in &net.heaters {
            let k = format!("heater.{}", key_segment(&h.name));
            celsius(format!("{k}.{}", registry::ON_K.name), h.on_k, &mut w);
            celsius(format!("{k}.{}", registry::OFF_K.name), h.off_k, &mut w);
        }
        for g in &self.gears {
            celsius(
                format!(
                    "gear_pair.{}.{}",
                    key_segment(&g.name),
                    registry::REFERENCE_TEMPERATURE_K.name
                ),
                g.reference_temperature_k,
                &mut w,
            );
        }
        w
    }

    /// Orbital period, s.
    pub fn period_s(&self) -> f64 {
        use crate::orbit::EnvironmentModel;
        self.thermal.environment.mean_period_s()
    }

    /// The same scenario run for `orbits` orbits; refused beyond [`MAX_DURATION_S`].
    pub fn with_orbits(mut self, orbits: f64) -> Result<Scenario, String> {
        let d = orbits * self.period_s();
        if !(d.is_finite() && (MIN_DURATION_S..=MAX_DURATION_S).contains(&d)) {
            return Err(format!(
                "gives a run of {d:.3e} s; runs last {MIN_DURATION_S} s … {MAX_DURATION_S:.0e} s (31.7 years)"
            ));
        }
        if let crate::orbit::Environment::Dated(e) = &mut self.thermal.environment {
            e.set_horizon_s(d)?;
        }
        self.run.duration_s = d;
        Ok(self)
    }
}

/// The column every recording gives its time in (unless `[recording]` names another).
pub const TIME_COLUMN: &str = "time_s";

/// How a scenario's recordings are laid out (`[recording]`): which column holds the
/// time and how, which columns are not channels, and what repeated rows and repeated
/// time stamps mean. The default is the layout of `reference-mechanism.md` §4.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingFormat {
    /// The time column's name.
    pub time_column: String,
    pub time: TimeFormat,
    /// Columns that are neither the time nor a sensor (read, kept out of the channels).
    pub ignore_columns: Vec<String>,
    /// Rows whose cells all repeat the previous row's are a ground segment's fill, not
    /// measurements: their cells are dropped (reported in [`Recording::fill_rows`]).
    pub repeated_rows_are_fill: bool,
    pub duplicate_times: DuplicateTimes,
}

/// How a recording gives its time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeFormat {
    /// Seconds since t = 0 of the scenario.
    Seconds,
    /// UTC date-times (`2016-02-04 00:01:00.0`, or RFC 3339), counted from `origin`
    /// (the scenario's `start_utc`).
    Utc { origin: sgp4::chrono::NaiveDateTime },
}

/// What two rows with the same time stamp mean when their cells differ (equal rows are
/// always merged).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DuplicateTimes {
    /// An error naming both lines.
    Refuse,
    /// Two readings within one time stamp: their mean.
    Mean,
}

impl Default for RecordingFormat {
    fn default() -> Self {
        RecordingFormat {
            time_column: TIME_COLUMN.to_string(),
            time: TimeFormat::Seconds,
            ignore_columns: Vec::new(),
            repeated_rows_are_fill: false,
            duplicate_times: DuplicateTimes::Refuse,
        }
    }
}

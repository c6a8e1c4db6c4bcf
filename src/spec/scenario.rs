//! A validated scenario: the thermal model, how long to run it, solver settings and
//! the sensors that name recording columns. Built by `io::scenario_toml`; everything
//! downstream may rely on it being physically valid.

use crate::gear::GearPair;
use crate::spec::quantity::MIN_MAX_STEP_S;
use crate::thermal::ThermalModel;

pub use crate::spec::keys::{MAX_NAME_LEN, check_name, key_segment, sensor_name_of};
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

/// Temperatures (K) below which a node's initial or reference temperature or a heater
/// set point most likely is a Celsius value typed as kelvin (150 K = −123 °C).
pub const CELSIUS_AS_KELVIN_BELOW_K: f64 = 150.0;

impl Scenario {
    /// Orbital period, s.
    pub fn period_s(&self) -> f64 {
        use crate::orbit::EnvironmentModel;
        self.thermal.environment.mean_period_s()
    }

    /// The same scenario run for `orbits` orbits; refused beyond [`MAX_DURATION_S`].
    pub fn with_orbits(mut self, orbits: f64) -> Result<Scenario, RunLengthError> {
        let d = orbits * self.period_s();
        if !(d.is_finite() && (MIN_DURATION_S..=MAX_DURATION_S).contains(&d)) {
            return Err(RunLengthError::OutOfRange { duration_s: d });
        }
        if let crate::orbit::Environment::Dated(e) = &mut self.thermal.environment {
            e.set_horizon_s(d).map_err(RunLengthError::Orbit)?;
        }
        self.run.duration_s = d;
        Ok(self)
    }
}

/// Why a scenario cannot run for a length.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunLengthError {
    #[error(
        "gives a run of {duration_s:.3e} s; runs last {MIN_DURATION_S} s … {MAX_DURATION_S:.0e} s (31.7 years)"
    )]
    OutOfRange { duration_s: f64 },
    /// A real orbit that cannot be propagated that far (it decays).
    #[error("{0}")]
    Orbit(String),
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
    /// Seconds added to every time stamp, s: a row measured at its stamp plus this.
    pub time_offset_s: f64,
    /// The column that tells sunlight from eclipse, for the clock's check.
    pub eclipse: Option<EclipseColumn>,
}

/// A recording's column that tells sunlight from eclipse (`[recording] eclipse_column`,
/// `eclipse_below`): a row reading below `below` is in eclipse.
#[derive(Debug, Clone, PartialEq)]
pub struct EclipseColumn {
    pub column: String,
    pub below: f64,
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

/// What an error about a time says of `[recording] time_offset_s` when it is set
/// (" with [recording] time_offset_s (25 s) added"; nothing at 0).
pub fn time_offset_note(offset_s: f64) -> String {
    if offset_s == 0.0 {
        String::new()
    } else {
        format!(" with [recording] time_offset_s ({offset_s} s) added")
    }
}

impl Default for RecordingFormat {
    fn default() -> Self {
        RecordingFormat {
            time_column: TIME_COLUMN.to_string(),
            time: TimeFormat::Seconds,
            ignore_columns: Vec::new(),
            repeated_rows_are_fill: false,
            duplicate_times: DuplicateTimes::Refuse,
            time_offset_s: 0.0,
            eclipse: None,
        }
    }
}

//! The scenario as the user wrote it: every key of a scenario file, nothing derived
//! (α and A kept apart, tooth thinning as thinning, view factors and run length left to
//! what the orbit gives). [`compile`] turns a spec into the validated numeric model
//! ([`crate::spec::scenario::Scenario`]); the checks live there, whatever built the spec (a TOML
//! file, `--set`, a program), and its errors name the key path. `io::scenario_toml`
//! reads TOML into a spec and maps those key paths back to file:line:column.
//!
//! Every key is documented in `scenarios/README.md`; keep the two in step.

pub(crate) mod compile;
pub mod keys;
pub mod model;
pub mod quantity;
pub mod registry;
pub mod scenario;
pub mod validate;
mod warnings;

pub(crate) use compile::check;
pub use compile::{SpecError, compile};
pub use keys::{KeyPath, Seg};

use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioSpec {
    pub scenario: MetaSpec,
    pub orbit: OrbitSpec,
    pub environment: EnvironmentSpec,
    pub run: RunSpec,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub node: Vec<NodeSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub boundary: Vec<BoundarySpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub conductor: Vec<ConductorSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub radiation: Vec<RadiationSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sun: Vec<SunSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub albedo: Vec<AlbedoSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub earth_ir: Vec<EarthIrSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dissipation: Vec<DissipationSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub heater: Vec<HeaterSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub mode: Vec<ModeSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sensor: Vec<SensorSpec>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub gear_pair: Vec<GearPairSpec>,
    /// How the body frame is oriented (for `[[face]]`s); nadir-pointing when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attitude: Option<AttitudeSpec>,
    /// Body-fixed faces of nodes, loaded from their geometry.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub face: Vec<FaceSpec>,
    /// How numbers scatter in `orbitlash margins` (the nominal run ignores them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub dispersion: Vec<DispersionSpec>,
    /// How recordings of this spacecraft are laid out (`diagnose --recording`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recording: Option<RecordingSpec>,
    /// Numbers the user is unsure of, with bounds: calibration candidates for
    /// `diagnose` (as are the `[[dispersion]]` entries).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub uncertain: Vec<UncertainSpec>,
    /// Inputs that follow a recording channel instead of the model (`diagnose`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub input: Vec<InputSpec>,
}

/// One dispersed number: a key path and its distribution (the `dispersion` module
/// samples it).
#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DispersionSpec {
    /// Key path of the number, as `orbitlash params` lists it.
    pub path: String,
    /// `normal`, `truncated_normal`, `uniform`, `triangular`, `lognormal` or `cases`.
    pub distribution: DistributionName,
    /// Normal and truncated normal: the mean (default: the nominal value).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean: Option<f64>,
    /// Normal and truncated normal: the standard deviation (before truncation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sd: Option<f64>,
    /// Truncated normal, uniform, triangular: the bounds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max: Option<f64>,
    /// Triangular: the most likely value (default: the nominal value).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode: Option<f64>,
    /// Log-normal: the median (default: the nominal value) and σ of ln x.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub median: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f64>,
    /// Cases: the discrete values, equally likely.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub values: Option<Vec<f64>>,
    /// Dispersions of one group draw together (one quantile per sample: the same lot).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub group: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GearPairSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub module_mm: f64,
    pub pressure_angle_deg: f64,
    pub face_width_mm: f64,
    pub center_distance_mm: f64,
    pub reference_temperature_k: f64,
    pub min_backlash_um: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center_distance: Option<CenterDistanceSpec>,
    pub coating: CoatingSpec,
    pub pinion: GearSpec,
    pub wheel: GearSpec,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CenterDistanceSpec {
    pub follows: Follows,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub node: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_per_k: Option<f64>,
    pub dalpha_dt_per_k2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strain_polynomial: Option<PolynomialSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_polynomial: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strain_table: Option<StrainTableSpec>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CoatingSpec {
    pub thickness_um: f64,
    pub alpha_per_k: f64,
    pub poisson: f64,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GearSpec {
    #[serde(deserialize_with = "integer")]
    pub teeth: i64,
    #[serde(default)]
    pub profile_shift: f64,
    pub tip_radius_mm: f64,
    pub root_radius_mm: f64,
    pub bore_radius_mm: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tooth_thickness_mm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tooth_thinning_um: Option<f64>,
    pub nodes: Vec<String>,
    pub material: MaterialSpec,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bore_fit: Option<BoreFitName>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shaft_node: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interference_um: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shaft_material: Option<MaterialSpec>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Descriptive only (e.g. "17-4PH").
    #[serde(default)]
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_per_k: Option<f64>,
    pub dalpha_dt_per_k2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strain_polynomial: Option<PolynomialSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_polynomial: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strain_table: Option<StrainTableSpec>,
    pub youngs_modulus_pa: f64,
    pub poisson: f64,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PolynomialSpec {
    pub coefficients: Vec<f64>,
    pub scale: f64,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StrainTableSpec {
    pub temperature_k: Vec<f64>,
    pub strain: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MetaSpec {
    pub name: String,
    #[serde(default)]
    pub description: String,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OrbitSpec {
    /// A circular orbit's altitude (absent with a TLE).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub altitude_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub earth_radius_m: Option<f64>,
    pub mu_m3_per_s2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orbit_angle_at_start_deg: Option<f64>,
    /// A real orbit: the two lines of a TLE (propagated by SGP4) …
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tle: Option<Vec<String>>,
    /// … from this UTC time (RFC 3339, `2016-02-04T00:00:00Z`) …
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_utc: Option<String>,
    /// … shifted by this many seconds (a number: settable and dispersible).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_offset_s: Option<f64>,
    /// … with a `cylindrical` (default) or `conical` Earth shadow.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shadow: Option<crate::orbit::dated::Shadow>,
    /// Eclipses given instead of the shadow's geometry: [entry, exit] windows in s
    /// (a TLE orbit only; `diagnose` sets them from a telemetry channel through
    /// `[[input]] drives = "sunlit"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eclipses_s: Option<Vec<Vec<f64>>>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentSpec {
    /// β of a circular orbit (derived from the geometry with a TLE).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta_deg: Option<ProfileSpec>,
    pub solar_flux_w_per_m2: Option<ProfileSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub space_sink_k: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub albedo: Option<f64>,
    pub earth_ir_w_per_m2: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(
    untagged,
    expecting = "a number, or a table {time_s = [...], value = [...]} (or time_days)"
)]
pub enum ProfileSpec {
    Constant(f64),
    Table(TableSpec),
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TableSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_s: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_days: Option<Vec<f64>>,
    pub value: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orbits: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration_days: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_interval_s: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<SolverMethod>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance_k: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_step_s: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linear: Option<crate::thermal::iteration::LinearSolver>,
}

/// `solver.method`: the integration method (one so far).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
pub enum SolverMethod {
    /// TR-BDF2 (Hosea & Shampine 1996), L-stable, second order.
    #[serde(rename = "tr-bdf2")]
    TrBdf2,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSpec {
    pub name: String,
    pub capacitance_j_per_k: f64,
    pub initial_temperature_k: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_mm: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    pub name: String,
    pub temperature_k: ProfileSpec,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ConductorSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub between: Vec<String>,
    pub conductance_w_per_k: f64,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RadiationSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub between: Vec<String>,
    pub emissivity_area_m2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emissivity: Option<f64>,
    pub area_m2: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SunSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub node: String,
    pub absorptivity_area_m2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub absorptivity: Option<f64>,
    pub area_m2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub incidence: Option<crate::orbit::Incidence>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct AlbedoSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub node: String,
    pub absorptivity_area_m2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub absorptivity: Option<f64>,
    pub area_m2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view_factor: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EarthIrSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub node: String,
    pub emissivity_area_m2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emissivity: Option<f64>,
    pub area_m2: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view_factor: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DissipationSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub node: String,
    pub power_w: ProfileSpec,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub when: Option<Schedule>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
pub struct AttitudeSpec {
    /// `nadir` (default), `sun`, `tumble`, `inertial` or `spin`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode: Option<AttitudeMode>,
    /// Nadir pointing: the body frame turned about nadir, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yaw_deg: Option<f64>,
    /// Inertially fixed: `[w, x, y, z]`, body to inertial (normalised); spinning: the
    /// orientation at t = 0 (identity when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quaternion: Option<Vec<f64>>,
    /// Spinning: the body axis it spins about, `[x, y, z]` (normalised).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spin_axis: Option<Vec<f64>>,
    /// Spinning: the rate about `spin_axis`, degrees per second (right-handed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spin_rate_deg_per_s: Option<f64>,
    /// Spinning: faces see the mean over a turn instead of the instant.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spin_averaged: Option<bool>,
}

/// `[[input]]`: a boundary's temperature or a dissipation's power that follows a
/// recording channel (value = `scale` × reading + `offset`, in the key's unit) where
/// operations prefer telemetry to a model.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InputSpec {
    /// The recording's column, as the file spells it.
    pub column: String,
    /// `boundary.<name>.temperature_k`, `dissipation.<name>.power_w` or `sunlit`.
    pub drives: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<f64>,
    /// `drives = "sunlit"`: the spacecraft is in eclipse where the reading is below this.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub below: Option<f64>,
}

/// `[[uncertain]]`: a number (by key path) the user is unsure of, between `min` and
/// `max`: `diagnose` may calibrate it.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct UncertainSpec {
    pub path: String,
    pub min: f64,
    pub max: f64,
}

/// `recording.time_format`: how the time column is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeFormatName {
    /// Seconds since the scenario's t = 0.
    Seconds,
    /// UTC date-times, counted from the scenario's `start_utc`.
    Utc,
}

/// `recording.repeated_rows`: what a row repeating every cell of the row before is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RepeatedRows {
    /// A measurement like any other.
    Data,
    /// A ground segment's fill: no reading.
    Fill,
}

/// `[recording]`: the layout of the recordings `diagnose` reads for this scenario.
#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingSpec {
    /// The time column (default `time_s`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_column: Option<String>,
    /// `"seconds"` since t = 0 (default) or `"utc"` date-times (a dated scenario's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_format: Option<TimeFormatName>,
    /// Columns that are neither the time nor a sensor.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ignore_columns: Option<Vec<String>>,
    /// `"data"` (default) or `"fill"`: a row repeating every cell of the row before is
    /// a ground segment's fill, not a measurement.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub repeated_rows: Option<RepeatedRows>,
    /// `"refuse"` (default) or `"mean"`: rows sharing a time stamp with other readings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duplicate_times: Option<crate::spec::scenario::DuplicateTimes>,
    /// Seconds added to every time stamp (when a row was measured against its stamp).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_offset_s: Option<f64>,
    /// A column that tells sunlight from eclipse (a photo-current, a Sun sensor), read
    /// by `diagnose` to check the recording's clock against the orbit's eclipses.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eclipse_column: Option<String>,
    /// The reading of `eclipse_column` below which a row is in eclipse (its units).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eclipse_below: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FaceSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub node: String,
    /// Outward normal in the body frame (normalised).
    pub normal: Vec<f64>,
    pub area_m2: f64,
    pub absorptivity: f64,
    pub emissivity: f64,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct HeaterSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    pub node: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor_node: Option<String>,
    pub power_w: f64,
    pub on_k: f64,
    pub off_k: f64,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ModeSpec {
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub windows_s: Option<Vec<Vec<f64>>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub windows_days: Option<Vec<Vec<f64>>>,
}

#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// The recording's column, as the file spells it.
    pub column: String,
    /// The channel's name in reports, plots, logs and key paths (default: the column
    /// when it is a valid name, else one made from it, see
    /// [`crate::spec::scenario::sensor_name_of`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub node: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quantity: Option<SensorQuantity>,
    /// For a derived quantity: the gear pair (default: the first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gear_pair: Option<String>,
    /// Temperature sensors: first-order time constant, s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau_s: Option<f64>,
    /// Temperature sensors: constant bias, K.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset_k: Option<f64>,
    /// A face whose node the sensor reads (instead of `node`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub face: Option<String>,
    /// Temperature sensors: the column's unit, `"C"` or `"K"` (default: K when the
    /// column ends in `_k`, else °C).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<UnitName>,
}

/// `[attitude] mode`: how the body frame is oriented.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AttitudeMode {
    Nadir,
    Sun,
    Tumble,
    Inertial,
    Spin,
}

impl AttitudeMode {
    pub fn name(self) -> &'static str {
        match self {
            AttitudeMode::Nadir => "nadir",
            AttitudeMode::Sun => "sun",
            AttitudeMode::Tumble => "tumble",
            AttitudeMode::Inertial => "inertial",
            AttitudeMode::Spin => "spin",
        }
    }
}

/// `[[dissipation]] when`: always, in sunlight, in eclipse, or in a `[[mode]]`'s windows
/// (by its name; the compiler checks that the mode exists).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Schedule {
    Always,
    Sunlit,
    Eclipse,
    Mode(String),
}

impl Schedule {
    /// The names that are not modes' (a mode may not take one).
    pub const RESERVED: [&'static str; 3] = ["always", "sunlit", "eclipse"];

    pub fn name(&self) -> &str {
        match self {
            Schedule::Always => "always",
            Schedule::Sunlit => "sunlit",
            Schedule::Eclipse => "eclipse",
            Schedule::Mode(m) => m,
        }
    }

    pub fn from_name(name: &str) -> Schedule {
        match name {
            "always" => Schedule::Always,
            "sunlit" => Schedule::Sunlit,
            "eclipse" => Schedule::Eclipse,
            m => Schedule::Mode(m.to_string()),
        }
    }
}

impl Serialize for Schedule {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for Schedule {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Schedule, D::Error> {
        String::deserialize(d).map(|s| Schedule::from_name(&s))
    }
}

/// `[[dispersion]] distribution`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DistributionName {
    #[default]
    Normal,
    TruncatedNormal,
    Uniform,
    Triangular,
    Lognormal,
    Cases,
}

impl DistributionName {
    pub fn name(self) -> &'static str {
        match self {
            DistributionName::Normal => "normal",
            DistributionName::TruncatedNormal => "truncated_normal",
            DistributionName::Uniform => "uniform",
            DistributionName::Triangular => "triangular",
            DistributionName::Lognormal => "lognormal",
            DistributionName::Cases => "cases",
        }
    }
}

impl std::fmt::Display for DistributionName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

/// `[[sensor]] quantity`: a quantity the model derives (not a node's temperature).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
pub enum SensorQuantity {
    /// A gear pair's backlash, µm.
    #[serde(rename = "backlash_um")]
    BacklashUm,
}

impl std::fmt::Display for SensorQuantity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(match self {
            SensorQuantity::BacklashUm => "backlash_um",
        })
    }
}

/// `[[sensor]] unit`: a temperature column's unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
pub enum UnitName {
    #[serde(rename = "C", alias = "°C", alias = "degC")]
    Celsius,
    #[serde(rename = "K")]
    Kelvin,
}

/// `bore_fit`: how a gear's bore sits on its shaft.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BoreFitName {
    Free,
    Rigid,
    Elastic,
}

/// `center_distance.follows`: what the centre distance follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Follows {
    Fixed,
    Housing,
}

/// A whole number, also when written as a float (`20.0`); any other number is refused
/// with the words `--set` uses ("must be an integer (got 20.5)").
fn integer<'de, D: serde::Deserializer<'de>>(d: D) -> Result<i64, D::Error> {
    struct Whole;
    impl serde::de::Visitor<'_> for Whole {
        type Value = i64;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("an integer")
        }
        fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<i64, E> {
            Ok(v)
        }
        fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<i64, E> {
            i64::try_from(v).map_err(|_| E::custom(format!("must be an integer (got {v})")))
        }
        fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<i64, E> {
            if v.fract() == 0.0 && v.abs() < 1e15 {
                Ok(v as i64)
            } else {
                Err(E::custom(format!("must be an integer (got {v})")))
            }
        }
    }
    d.deserialize_any(Whole)
}

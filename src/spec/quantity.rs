//! The table of quantities: each kind of number a scenario holds, defined once — its
//! unit, its valid range (as a rule the code checks and as the text `orbitlash params`
//! shows), its default. The TOML reader and `--set` (both through `spec::compile`),
//! the fast writes of `Model::set_param`, `Scenario::validate`, `orbitlash params` and
//! `SolverSettings::default()` read these definitions; none of them writes a bound or
//! a default of its own for a number listed here.
//!
//! Adding a key: a field in the spec (`spec/mod.rs`), one line in `spec::params`' walk
//! naming its quantity, and the compiler reading it through [`Quantity`]'s check
//! (`spec::compile::check::value`). A new kind of number is one constant here.
//!
//! This module depends on nothing else in the crate: the run layer (`sim`) and the spec
//! layer both read it.

/// How a value is checked. Every rule first requires a finite number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rule {
    /// `lo ≤ v ≤ hi`; the error names the quantity: "`what` must be within lo … hi".
    Within {
        lo: f64,
        hi: f64,
        what: &'static str,
    },
    /// `lo ≤ v ≤ hi` (`lo < v < hi` when `open`), with the error "must be within
    /// `shown` (got v`got_unit`)": for ranges said in other units than the value's
    /// (an altitude in km), or with a symbol (degrees).
    Span {
        lo: f64,
        hi: f64,
        open: bool,
        shown: &'static str,
        got_unit: &'static str,
    },
    /// `v > 0`.
    Positive,
    /// `v ≥ 0`.
    NonNegative,
    /// `0 < v ≤ hi` (a physically sensible upper bound, named with the unit).
    PositiveUpTo { hi: f64 },
    /// `0 < v ≤ hi` and `v ≥ lo`.
    PositiveAtLeast { lo: f64, hi: f64 },
    /// `v ≥ lo`.
    AtLeast { lo: f64 },
    /// A temperature in kelvin, `0 < v < 5000` (the error reminds of °C + 273.15).
    Temperature,
    /// Checked by the compiler against other values (a radius on its gear, increasing
    /// table times, mode windows, a run length in orbits): the range text says how.
    InContext,
}

/// One kind of number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantity {
    /// As shown after values (`orbitlash params`), e.g. "W/m²"; "" for a pure number.
    pub unit: &'static str,
    /// The valid range as `orbitlash params` and `scenarios/README.md` show it.
    pub range: &'static str,
    /// What an absent value stands for (None: required, or a default that depends on
    /// the scenario, such as the Earth view factor).
    pub default: Option<f64>,
    pub rule: Rule,
}

impl Quantity {
    /// The closed interval the rule accepts, with whether each end is itself
    /// accepted: `(lo, lo_included, hi, hi_included)`. None for [`Rule::InContext`].
    pub fn interval(&self) -> Option<(f64, bool, f64, bool)> {
        match self.rule {
            Rule::Within { lo, hi, .. } => Some((lo, true, hi, true)),
            Rule::Span { lo, hi, open, .. } => Some((lo, !open, hi, !open)),
            Rule::Positive => Some((0.0, false, f64::INFINITY, true)),
            Rule::NonNegative => Some((0.0, true, f64::INFINITY, true)),
            Rule::PositiveUpTo { hi } => Some((0.0, false, hi, true)),
            Rule::PositiveAtLeast { lo, hi } => Some((lo, true, hi, true)),
            Rule::AtLeast { lo } => Some((lo, true, f64::INFINITY, true)),
            Rule::Temperature => Some((0.0, false, MAX_TEMPERATURE_K, false)),
            Rule::InContext => None,
        }
    }

    /// Whether `v` is accepted (the compiler's check gives the error text).
    pub fn accepts(&self, v: f64) -> bool {
        v.is_finite()
            && self.interval().is_none_or(|(lo, lo_in, hi, hi_in)| {
                (v > lo || (lo_in && v == lo)) && (v < hi || (hi_in && v == hi))
            })
    }

    /// The default; panics for a quantity without one (a programming error).
    pub const fn default_value(&self) -> f64 {
        match self.default {
            Some(v) => v,
            None => panic!("this quantity has no default"),
        }
    }
}

/// Highest temperature a scenario may give, K (exclusive).
pub const MAX_TEMPERATURE_K: f64 = 5000.0;
/// Smallest node capacitance, J/K: a microgram of metal. Below it a node is numerically
/// indistinguishable from an infinitely fast one and only costs conditioning.
pub const MIN_CAPACITANCE_J_PER_K: f64 = 1e-6;
/// Largest capacitance of a node: a thousand tonnes of steel (≈ 5e8 J/K) with a wide
/// margin; beyond it a node is a boundary (fixed temperature), and energy sums lose
/// every digit.
pub const MAX_CAPACITANCE_J_PER_K: f64 = 1e12;
/// Largest conductance, W/K (a square metre of bonded joint conducts ~1e4 W/K): beyond it
/// two nodes are one, and the Newton systems lose their precision (tested to 1e12).
pub const MAX_CONDUCTANCE_W_PER_K: f64 = 1e9;
/// Largest dissipation or heater power, W.
pub const MAX_POWER_W: f64 = 1e6;
/// Largest area (or area product) of a face, a radiative link or a load, m².
pub const MAX_AREA_M2: f64 = 1e4;
/// Tightest local error per step a scenario may ask for, K: the Newton iterations stop
/// at 1 % of it, which stays well above the round-off of temperatures near 300 K
/// (~1e-13 K) and of the stage sums.
pub const MIN_TOLERANCE_K: f64 = 1e-6;
/// Loosest, K: beyond it the step controller no longer tracks an orbit's transients.
pub const MAX_TOLERANCE_K: f64 = 10.0;
/// Smallest `max_step_s`, s: no node of a lumped spacecraft network needs shorter steps
/// to be resolved (gear rims and thin films settle in ≳ 0.1 s), and a millisecond step
/// over an orbit is already 6 million steps.
pub const MIN_MAX_STEP_S: f64 = 1e-3;
/// Shortest interval between CSV rows, s.
pub const MIN_OUTPUT_INTERVAL_S: f64 = 1e-3;
/// Longest sensor time constant, s (a day: longer is no longer a sensor lag).
pub const MAX_SENSOR_TAU_S: f64 = 86_400.0;
/// Largest sensor offset, K.
pub const MAX_SENSOR_OFFSET_K: f64 = 100.0;

const fn q(unit: &'static str, range: &'static str, default: Option<f64>, rule: Rule) -> Quantity {
    Quantity {
        unit,
        range,
        default,
        rule,
    }
}

const fn within(lo: f64, hi: f64, what: &'static str) -> Rule {
    Rule::Within { lo, hi, what }
}

// ---------------------------------------------------------------- thermal network

pub const TEMPERATURE_K: Quantity = q("K", "0 … 5000", None, Rule::Temperature);
pub const CAPACITANCE_J_PER_K: Quantity = q(
    "J/K",
    "1e-6 … 1e12",
    None,
    Rule::PositiveAtLeast {
        lo: MIN_CAPACITANCE_J_PER_K,
        hi: MAX_CAPACITANCE_J_PER_K,
    },
);
pub const CONDUCTANCE_W_PER_K: Quantity = q(
    "W/K",
    "0 < G ≤ 1e9",
    None,
    Rule::PositiveUpTo {
        hi: MAX_CONDUCTANCE_W_PER_K,
    },
);
/// An emissivity or absorptivity times its area, m².
pub const AREA_PRODUCT_M2: Quantity = q(
    "m²",
    "0 < … ≤ 1e4",
    None,
    Rule::PositiveUpTo { hi: MAX_AREA_M2 },
);
pub const AREA_M2: Quantity = q(
    "m²",
    "0 < A ≤ 1e4",
    None,
    Rule::PositiveUpTo { hi: MAX_AREA_M2 },
);
pub const ABSORPTIVITY: Quantity = q("", "0 … 1", None, within(0.0, 1.0, "absorptivity"));
pub const EMISSIVITY: Quantity = q("", "0 … 1", None, within(0.0, 1.0, "emissivity"));
/// An Earth-facing load's view factor of the Earth (default: the orbit's (R/(R+h))²).
pub const VIEW_FACTOR: Quantity = q("", "0 … 1", None, within(0.0, 1.0, "view factor"));
/// A dissipation's power (constant or table value), W.
pub const POWER_W: Quantity = q("W", "0 … 1e6", None, within(0.0, MAX_POWER_W, "power (W)"));
pub const HEATER_POWER_W: Quantity = q(
    "W",
    "0 < P ≤ 1e6",
    None,
    Rule::PositiveUpTo { hi: MAX_POWER_W },
);
pub const HEATER_ON_K: Quantity = q("K", "0 … 5000, below off_k", None, Rule::Temperature);
pub const HEATER_OFF_K: Quantity = q("K", "0 … 5000, above on_k", None, Rule::Temperature);

// ---------------------------------------------------------------- environment

pub const BETA_DEG: Quantity = q(
    "deg",
    "−90 … 90",
    None,
    within(-90.0, 90.0, "beta angle (deg)"),
);
pub const SOLAR_FLUX_W_PER_M2: Quantity = q(
    "W/m²",
    "0 … 1e5",
    Some(crate::constants::SOLAR_CONSTANT_W_PER_M2),
    within(0.0, 1e5, "solar flux (W/m²; 14 500 at Mercury)"),
);
pub const SPACE_SINK_K: Quantity = q(
    "K",
    "0 … 5000",
    Some(crate::constants::SPACE_SINK_K),
    within(0.0, 5000.0, "sink temperature (K)"),
);
pub const ALBEDO: Quantity = q(
    "",
    "0 … 1",
    Some(crate::constants::EARTH_ALBEDO),
    within(0.0, 1.0, "albedo"),
);
pub const EARTH_IR_W_PER_M2: Quantity = q(
    "W/m²",
    "0 … 1e4",
    Some(crate::constants::EARTH_IR_W_PER_M2),
    within(0.0, 1e4, "planetary infrared flux (W/m²)"),
);

// ---------------------------------------------------------------- orbit

pub const EARTH_RADIUS_M: Quantity = q(
    "m",
    "1e5 … 1e8",
    Some(crate::constants::EARTH_RADIUS_M),
    within(1e5, 1e8, "the central body's radius (m)"),
);
pub const MU_M3_PER_S2: Quantity = q(
    "m³/s²",
    "1e9 … 1e17, period 10 min … 30 days",
    Some(crate::constants::EARTH_MU_M3_PER_S2),
    within(1e9, 1e17, "gravitational parameter (m³/s²; Earth 3.986e14)"),
);
/// Height of a circular orbit above the Earth's surface.
pub const ALTITUDE_M: Quantity = q(
    "m",
    "100 km … 100 000 km",
    None,
    Rule::Span {
        lo: 100e3,
        hi: 100_000e3,
        open: false,
        shown: "100 km … 100 000 km, in metres",
        got_unit: " m",
    },
);
/// The yaw of a nadir-pointing body about nadir.
pub const YAW_DEG: Quantity = q(
    "deg",
    "−180 … 180",
    Some(0.0),
    within(-180.0, 180.0, "yaw angle (deg)"),
);
/// A spinning body's rate about its spin axis (two turns a second at most: faster
/// spins are spin-averaged, `spin_averaged = true`).
pub const SPIN_RATE_DEG_PER_S: Quantity = q(
    "deg/s",
    "−720 … 720",
    None,
    within(-720.0, 720.0, "spin rate (deg/s)"),
);
/// A shift of a dated run's start, s (a TLE is good for about a month around its epoch).
pub const START_OFFSET_S: Quantity = q(
    "s",
    "−30 … 30 days (in s)",
    Some(0.0),
    within(-2_592_000.0, 2_592_000.0, "start offset (s)"),
);
pub const ORBIT_ANGLE_AT_START_DEG: Quantity = q(
    "deg",
    "any (reduced modulo 360°)",
    Some(0.0),
    Rule::InContext,
);

// ---------------------------------------------------------------- gear pairs

pub const MODULE_MM: Quantity = q("mm", "> 0", None, Rule::Positive);
/// The pressure angle a gear is cut with (standard 20°).
pub const PRESSURE_ANGLE_DEG: Quantity = q(
    "deg",
    "10 … 35",
    None,
    Rule::Span {
        lo: 10.0,
        hi: 35.0,
        open: false,
        shown: "10° … 35°",
        got_unit: "°",
    },
);
/// Poisson's ratio of an isotropic material (a gear's, a shaft's, a coating's).
pub const POISSON: Quantity = q(
    "",
    "−1 … 0.5",
    None,
    Rule::Span {
        lo: -1.0,
        hi: 0.5,
        open: true,
        shown: "−1 … 0.5",
        got_unit: "",
    },
);
pub const FACE_WIDTH_MM: Quantity = q("mm", "> 0", None, Rule::Positive);
pub const MIN_BACKLASH_UM: Quantity = q("µm", "≥ 0", None, Rule::NonNegative);
pub const COATING_THICKNESS_UM: Quantity = q("µm", "≥ 0", None, Rule::NonNegative);
/// A linear expansion coefficient (a material's α, a coating's).
pub const EXPANSION_PER_K: Quantity = q(
    "1/K",
    "−1e-3 … 1e-3",
    None,
    within(-1e-3, 1e-3, "expansion coefficient (1/K)"),
);
pub const DALPHA_DT_PER_K2: Quantity = q(
    "1/K²",
    "−1e-5 … 1e-5",
    None,
    within(-1e-5, 1e-5, "dα/dT (1/K²)"),
);
pub const PROFILE_SHIFT: Quantity = q("", "−2 … 2", Some(0.0), within(-2.0, 2.0, "profile shift"));
pub const ROOT_RADIUS_MM: Quantity = q("mm", "> 0", None, Rule::Positive);
/// Positive, then checked against the gear's base and root radii.
pub const TIP_RADIUS_MM: Quantity = q("mm", "above the base and root radii", None, Rule::Positive);
pub const BORE_RADIUS_MM: Quantity = q("mm", "below the base and root radii", None, Rule::Positive);
/// A diffusion node's radius on its gear: positive, then checked against the bore and
/// base circles.
pub const NODE_RADIUS_MM: Quantity = q(
    "mm",
    "> 0, on the gear's bore … base circle",
    None,
    Rule::Positive,
);

// ---------------------------------------------------------------- run and solver

pub const OUTPUT_INTERVAL_S: Quantity = q(
    "s",
    "≥ 0.001",
    Some(30.0),
    Rule::AtLeast {
        lo: MIN_OUTPUT_INTERVAL_S,
    },
);
pub const TOLERANCE_K: Quantity = q(
    "K",
    "1e-6 … 10",
    Some(0.002),
    within(
        MIN_TOLERANCE_K,
        MAX_TOLERANCE_K,
        "the local error per step (K)",
    ),
);
pub const MAX_STEP_S: Quantity = q(
    "s",
    "≥ 0.001",
    Some(300.0),
    Rule::AtLeast { lo: MIN_MAX_STEP_S },
);

// ---------------------------------------------------------------- sensors

pub const SENSOR_TAU_S: Quantity = q(
    "s",
    "0 … 86 400",
    Some(0.0),
    within(0.0, MAX_SENSOR_TAU_S, "a sensor time constant (s)"),
);
pub const SENSOR_OFFSET_K: Quantity = q(
    "K",
    "−100 … 100",
    Some(0.0),
    within(
        -MAX_SENSOR_OFFSET_K,
        MAX_SENSOR_OFFSET_K,
        "a sensor offset (K)",
    ),
);

/// Every quantity above with a range, by name (for the generated test and the
/// documentation).
pub const TABLE: &[(&str, &Quantity)] = &[
    ("ALTITUDE_M", &ALTITUDE_M),
    ("START_OFFSET_S", &START_OFFSET_S),
    ("YAW_DEG", &YAW_DEG),
    ("SPIN_RATE_DEG_PER_S", &SPIN_RATE_DEG_PER_S),
    ("PRESSURE_ANGLE_DEG", &PRESSURE_ANGLE_DEG),
    ("POISSON", &POISSON),
    ("TEMPERATURE_K", &TEMPERATURE_K),
    ("CAPACITANCE_J_PER_K", &CAPACITANCE_J_PER_K),
    ("CONDUCTANCE_W_PER_K", &CONDUCTANCE_W_PER_K),
    ("AREA_PRODUCT_M2", &AREA_PRODUCT_M2),
    ("AREA_M2", &AREA_M2),
    ("ABSORPTIVITY", &ABSORPTIVITY),
    ("EMISSIVITY", &EMISSIVITY),
    ("VIEW_FACTOR", &VIEW_FACTOR),
    ("POWER_W", &POWER_W),
    ("HEATER_POWER_W", &HEATER_POWER_W),
    ("HEATER_ON_K", &HEATER_ON_K),
    ("HEATER_OFF_K", &HEATER_OFF_K),
    ("BETA_DEG", &BETA_DEG),
    ("SOLAR_FLUX_W_PER_M2", &SOLAR_FLUX_W_PER_M2),
    ("SPACE_SINK_K", &SPACE_SINK_K),
    ("ALBEDO", &ALBEDO),
    ("EARTH_IR_W_PER_M2", &EARTH_IR_W_PER_M2),
    ("EARTH_RADIUS_M", &EARTH_RADIUS_M),
    ("MU_M3_PER_S2", &MU_M3_PER_S2),
    ("MODULE_MM", &MODULE_MM),
    ("FACE_WIDTH_MM", &FACE_WIDTH_MM),
    ("MIN_BACKLASH_UM", &MIN_BACKLASH_UM),
    ("COATING_THICKNESS_UM", &COATING_THICKNESS_UM),
    ("EXPANSION_PER_K", &EXPANSION_PER_K),
    ("DALPHA_DT_PER_K2", &DALPHA_DT_PER_K2),
    ("PROFILE_SHIFT", &PROFILE_SHIFT),
    ("ROOT_RADIUS_MM", &ROOT_RADIUS_MM),
    ("TIP_RADIUS_MM", &TIP_RADIUS_MM),
    ("BORE_RADIUS_MM", &BORE_RADIUS_MM),
    ("NODE_RADIUS_MM", &NODE_RADIUS_MM),
    ("OUTPUT_INTERVAL_S", &OUTPUT_INTERVAL_S),
    ("TOLERANCE_K", &TOLERANCE_K),
    ("MAX_STEP_S", &MAX_STEP_S),
    ("SENSOR_TAU_S", &SENSOR_TAU_S),
    ("SENSOR_OFFSET_K", &SENSOR_OFFSET_K),
];

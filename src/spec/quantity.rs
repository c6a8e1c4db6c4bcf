//! The table of quantities: each kind of number a scenario holds, defined once — its
//! unit, its valid range (as a rule the code checks and as the text `orbitlash params`
//! shows), its default. The TOML reader and `--set` (both through `spec::compile`),
//! the fast writes of `Model::set_param`, `Scenario::validate`, `orbitlash params` and
//! `SolverSettings::default()` read these definitions; none of them writes a bound or
//! a default of its own for a number listed here.
//!
//! A number of a scenario is a row of the registry (`spec::registry`), which names its
//! quantity; a new kind of number is one constant here. Each range is written once, as
//! the rule the code checks; the text `params` shows is made from it
//! ([`Quantity::range`]), with the context a rule cannot say.
//!
//! This module depends on nothing else in the crate but `units`: the run layer (`sim`)
//! and the spec layer both read it.

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
    /// `shown` (got v`got_unit`)" ("must be `shown`" when `open`, whose `shown` writes
    /// its ends as excluded: "−1 < … < 0.5"): for ranges said in other units than the
    /// value's (an altitude in km), or with a symbol (degrees).
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
    /// What the rule cannot say: the context the value is checked in by the compiler
    /// ("below off_k"), appended to the range [`Quantity::range`] writes; "" for none.
    pub context: &'static str,
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

    /// The valid range as `orbitlash params` and `scenarios/README.md` show it: the
    /// rule's interval, then the context it is checked in.
    pub fn range(&self) -> String {
        let n = |v: f64| {
            // powers of ten as 1e5 and 1e-6, a negative number with a minus sign
            let a = v.abs();
            let e = a.log10().round();
            let body = if a != 0.0 && !(1e-3..1e4).contains(&a) && 10f64.powf(e) == a {
                format!("1e{e}")
            } else {
                crate::units::num(a)
            };
            if v < 0.0 { format!("−{body}") } else { body }
        };
        let rule = match self.rule {
            Rule::Within { lo, hi, .. } => format!("{} … {}", n(lo), n(hi)),
            Rule::Span { shown, .. } => shown.to_string(),
            Rule::Positive => "> 0".into(),
            Rule::NonNegative => "≥ 0".into(),
            Rule::PositiveUpTo { hi } => format!("0 < … ≤ {}", n(hi)),
            Rule::PositiveAtLeast { lo, hi } => format!("{} … {}", n(lo), n(hi)),
            Rule::AtLeast { lo } => format!("≥ {}", n(lo)),
            Rule::Temperature => format!("0 < … < {}", n(MAX_TEMPERATURE_K)),
            Rule::InContext => String::new(),
        };
        match (rule.is_empty(), self.context.is_empty()) {
            (_, true) => rule,
            (true, false) => self.context.to_string(),
            (false, false) => format!("{rule}, {}", self.context),
        }
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

const fn q(
    unit: &'static str,
    context: &'static str,
    default: Option<f64>,
    rule: Rule,
) -> Quantity {
    Quantity {
        unit,
        context,
        default,
        rule,
    }
}

const fn within(lo: f64, hi: f64, what: &'static str) -> Rule {
    Rule::Within { lo, hi, what }
}

// ---------------------------------------------------------------- thermal network

pub const TEMPERATURE_K: Quantity = q("K", "", None, Rule::Temperature);
pub const CAPACITANCE_J_PER_K: Quantity = q(
    "J/K",
    "",
    None,
    Rule::PositiveAtLeast {
        lo: MIN_CAPACITANCE_J_PER_K,
        hi: MAX_CAPACITANCE_J_PER_K,
    },
);
pub const CONDUCTANCE_W_PER_K: Quantity = q(
    "W/K",
    "",
    None,
    Rule::PositiveUpTo {
        hi: MAX_CONDUCTANCE_W_PER_K,
    },
);
/// An emissivity or absorptivity times its area, m².
pub const AREA_PRODUCT_M2: Quantity = q("m²", "", None, Rule::PositiveUpTo { hi: MAX_AREA_M2 });
pub const AREA_M2: Quantity = q("m²", "", None, Rule::PositiveUpTo { hi: MAX_AREA_M2 });
pub const ABSORPTIVITY: Quantity = q("", "", None, within(0.0, 1.0, "absorptivity"));
pub const EMISSIVITY: Quantity = q("", "", None, within(0.0, 1.0, "emissivity"));
/// An Earth-facing load's view factor of the Earth (default: the orbit's (R/(R+h))²).
pub const VIEW_FACTOR: Quantity = q("", "", None, within(0.0, 1.0, "view factor"));
/// A dissipation's power (constant or table value), W.
pub const POWER_W: Quantity = q("W", "", None, within(0.0, MAX_POWER_W, "power (W)"));
pub const HEATER_POWER_W: Quantity = q("W", "", None, Rule::PositiveUpTo { hi: MAX_POWER_W });
pub const HEATER_ON_K: Quantity = q("K", "below off_k", None, Rule::Temperature);
pub const HEATER_OFF_K: Quantity = q("K", "above on_k", None, Rule::Temperature);
/// A time of a profile table, s or days.
pub const TABLE_TIME_S: Quantity = q("s", "strictly increasing", None, Rule::InContext);
pub const TABLE_TIME_DAYS: Quantity = q("days", "strictly increasing", None, Rule::InContext);
/// An end of a mode's window, s or days.
pub const WINDOW_S: Quantity = q(
    "s",
    "windows [start, end], increasing, not overlapping",
    None,
    Rule::InContext,
);
pub const WINDOW_DAYS: Quantity = q(
    "days",
    "windows [start, end], increasing, not overlapping",
    None,
    Rule::InContext,
);

// ---------------------------------------------------------------- environment

pub const BETA_DEG: Quantity = q("deg", "", None, within(-90.0, 90.0, "beta angle (deg)"));
pub const SOLAR_FLUX_W_PER_M2: Quantity = q(
    "W/m²",
    "",
    Some(crate::constants::SOLAR_CONSTANT_W_PER_M2),
    within(0.0, 1e5, "solar flux (W/m²; 14 500 at Mercury)"),
);
pub const SPACE_SINK_K: Quantity = q(
    "K",
    "",
    Some(crate::constants::SPACE_SINK_K),
    within(0.0, MAX_TEMPERATURE_K, "sink temperature (K)"),
);
pub const ALBEDO: Quantity = q(
    "",
    "",
    Some(crate::constants::EARTH_ALBEDO),
    within(0.0, 1.0, "albedo"),
);
pub const EARTH_IR_W_PER_M2: Quantity = q(
    "W/m²",
    "",
    Some(crate::constants::EARTH_IR_W_PER_M2),
    within(0.0, 1e4, "planetary infrared flux (W/m²)"),
);

// ---------------------------------------------------------------- orbit

pub const EARTH_RADIUS_M: Quantity = q(
    "m",
    "",
    Some(crate::constants::EARTH_RADIUS_M),
    within(1e5, 1e8, "the central body's radius (m)"),
);
pub const MU_M3_PER_S2: Quantity = q(
    "m³/s²",
    "period 10 min … 30 days",
    Some(crate::constants::EARTH_MU_M3_PER_S2),
    within(1e9, 1e17, "gravitational parameter (m³/s²; Earth 3.986e14)"),
);
/// Height of a circular orbit above the Earth's surface.
pub const ALTITUDE_M: Quantity = q(
    "m",
    "",
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
    "",
    Some(0.0),
    within(-180.0, 180.0, "yaw angle (deg)"),
);
/// A spinning body's rate about its spin axis (two turns a second at most: faster
/// spins are spin-averaged, `spin_averaged = true`).
pub const SPIN_RATE_DEG_PER_S: Quantity = q(
    "deg/s",
    "",
    None,
    within(-720.0, 720.0, "spin rate (deg/s)"),
);
/// A shift of a dated run's start, s (a TLE is good for about a month around its epoch).
pub const START_OFFSET_S: Quantity = q(
    "s",
    "±30 days",
    Some(0.0),
    within(-2_592_000.0, 2_592_000.0, "start offset (s)"),
);
/// Seconds added to every time stamp of a recording: when its rows were measured
/// against when they are stamped (a ground segment stamping a packet when it arrives).
pub const TIME_OFFSET_S: Quantity = q(
    "s",
    "±1 day",
    Some(0.0),
    within(-86_400.0, 86_400.0, "a recording's time offset (s)"),
);
pub const ORBIT_ANGLE_AT_START_DEG: Quantity = q(
    "deg",
    "any (reduced modulo 360°)",
    Some(0.0),
    Rule::InContext,
);

// ---------------------------------------------------------------- run

/// A run's length, given one of three ways.
pub const RUN_ORBITS: Quantity = q("orbits", "the run lasts 1 s … 1e9 s", None, Rule::InContext);
pub const RUN_DURATION_S: Quantity = q("s", "the run lasts 1 s … 1e9 s", None, Rule::InContext);
pub const RUN_DURATION_DAYS: Quantity =
    q("days", "the run lasts 1 s … 1e9 s", None, Rule::InContext);

// ---------------------------------------------------------------- gear pairs

pub const MODULE_MM: Quantity = q("mm", "", None, Rule::Positive);
/// The pressure angle a gear is cut with (standard 20°).
pub const PRESSURE_ANGLE_DEG: Quantity = q(
    "deg",
    "",
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
    "",
    None,
    Rule::Span {
        lo: -1.0,
        hi: 0.5,
        open: true,
        shown: "−1 < … < 0.5",
        got_unit: "",
    },
);
pub const FACE_WIDTH_MM: Quantity = q("mm", "", None, Rule::Positive);
/// The centre distance of a pair at its reference temperature.
pub const CENTER_DISTANCE_MM: Quantity = q(
    "mm",
    "a positive backlash at assembly",
    None,
    Rule::Positive,
);
/// The smallest backlash allowed: up to 10 mm, far above any gear pair's backlash
/// (a limit past it is a slip of unit, and printed 300 digits long).
pub const MIN_BACKLASH_UM: Quantity = q(
    "µm",
    "",
    None,
    within(0.0, 1e4, "the smallest allowed backlash (µm)"),
);
pub const COATING_THICKNESS_UM: Quantity = q("µm", "", None, Rule::NonNegative);
/// A linear expansion coefficient (a material's α, a coating's).
pub const EXPANSION_PER_K: Quantity = q(
    "1/K",
    "",
    None,
    within(-1e-3, 1e-3, "expansion coefficient (1/K)"),
);
pub const DALPHA_DT_PER_K2: Quantity = q("1/K²", "", None, within(-1e-5, 1e-5, "dα/dT (1/K²)"));
/// A coefficient or value of a strain law (polynomial, table): checked by the strain
/// the whole law gives.
pub const STRAIN_LAW: Quantity = q(
    "",
    "thermal strain within ±0.1 over 20 … 1000 K",
    None,
    Rule::InContext,
);
/// A temperature of a strain table.
pub const STRAIN_TABLE_TEMPERATURE_K: Quantity =
    q("K", "strictly increasing", None, Rule::InContext);
/// A material's Young's modulus, checked to be a metal's.
pub const YOUNGS_MODULUS_PA: Quantity = q("Pa", "≥ 1e8", None, Rule::InContext);
/// A gear's number of teeth (an integer).
pub const TEETH: Quantity = q("", "5 … 10000", None, Rule::InContext);
pub const PROFILE_SHIFT: Quantity = q("", "", Some(0.0), within(-2.0, 2.0, "profile shift"));
pub const ROOT_RADIUS_MM: Quantity = q("mm", "", None, Rule::Positive);
/// Positive, then checked against the gear's base and root radii.
pub const TIP_RADIUS_MM: Quantity = q("mm", "above the base and root radii", None, Rule::Positive);
pub const BORE_RADIUS_MM: Quantity = q("mm", "below the base and root radii", None, Rule::Positive);
/// A diffusion node's radius on its gear: positive, then checked against the bore and
/// base circles.
pub const NODE_RADIUS_MM: Quantity = q(
    "mm",
    "on the gear's bore … base circle",
    None,
    Rule::Positive,
);
/// A tooth's thickness on the reference circle, given or as a thinning below nominal.
pub const TOOTH_THICKNESS_MM: Quantity = q(
    "mm",
    "0 … π m, not pointed at the tip",
    None,
    Rule::InContext,
);
pub const TOOTH_THINNING_UM: Quantity = q(
    "µm",
    "a tooth of 0 … π m, not pointed at the tip",
    None,
    Rule::InContext,
);
/// An elastic bore fit's radial interference.
pub const INTERFERENCE_UM: Quantity = q("µm", "any (elastic bore fit)", None, Rule::InContext);

// ---------------------------------------------------------------- run and solver

pub const OUTPUT_INTERVAL_S: Quantity = q(
    "s",
    "",
    Some(30.0),
    Rule::AtLeast {
        lo: MIN_OUTPUT_INTERVAL_S,
    },
);
pub const TOLERANCE_K: Quantity = q(
    "K",
    "",
    Some(0.002),
    within(
        MIN_TOLERANCE_K,
        MAX_TOLERANCE_K,
        "the local error per step (K)",
    ),
);
pub const MAX_STEP_S: Quantity = q("s", "", Some(300.0), Rule::AtLeast { lo: MIN_MAX_STEP_S });

// ---------------------------------------------------------------- sensors

pub const SENSOR_TAU_S: Quantity = q(
    "s",
    "",
    Some(0.0),
    within(0.0, MAX_SENSOR_TAU_S, "a sensor time constant (s)"),
);
pub const SENSOR_OFFSET_K: Quantity = q(
    "K",
    "",
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
    ("TIME_OFFSET_S", &TIME_OFFSET_S),
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

//! The fields of the registry: each key a scenario file holds numbers under, once,
//! with its quantity; and the tables inside a gear pair that hold numbers.

use super::Field;
use crate::spec::quantity as q;

macro_rules! fields {
    ($($(#[$doc:meta])* $id:ident = $name:literal, $q:ident;)*) => {
        $($(#[$doc])* pub static $id: Field = Field { name: $name, quantity: &q::$q };)*
    };
}

fields! {
    START_OFFSET_S = "start_offset_s", START_OFFSET_S;
    ALTITUDE_M = "altitude_m", ALTITUDE_M;
    EARTH_RADIUS_M = "earth_radius_m", EARTH_RADIUS_M;
    MU_M3_PER_S2 = "mu_m3_per_s2", MU_M3_PER_S2;
    ORBIT_ANGLE_AT_START_DEG = "orbit_angle_at_start_deg", ORBIT_ANGLE_AT_START_DEG;
    BETA_DEG = "beta_deg", BETA_DEG;
    SOLAR_FLUX_W_PER_M2 = "solar_flux_w_per_m2", SOLAR_FLUX_W_PER_M2;
    SPACE_SINK_K = "space_sink_k", SPACE_SINK_K;
    ALBEDO = "albedo", ALBEDO;
    EARTH_IR_W_PER_M2 = "earth_ir_w_per_m2", EARTH_IR_W_PER_M2;
    ORBITS = "orbits", RUN_ORBITS;
    DURATION_S = "duration_s", RUN_DURATION_S;
    DURATION_DAYS = "duration_days", RUN_DURATION_DAYS;
    OUTPUT_INTERVAL_S = "output_interval_s", OUTPUT_INTERVAL_S;
    TOLERANCE_K = "tolerance_k", TOLERANCE_K;
    MAX_STEP_S = "max_step_s", MAX_STEP_S;
    CAPACITANCE_J_PER_K = "capacitance_j_per_k", CAPACITANCE_J_PER_K;
    INITIAL_TEMPERATURE_K = "initial_temperature_k", TEMPERATURE_K;
    RADIUS_MM = "radius_mm", NODE_RADIUS_MM;
    BOUNDARY_TEMPERATURE_K = "temperature_k", TEMPERATURE_K;
    CONDUCTANCE_W_PER_K = "conductance_w_per_k", CONDUCTANCE_W_PER_K;
    EMISSIVITY_AREA_M2 = "emissivity_area_m2", AREA_PRODUCT_M2;
    EMISSIVITY = "emissivity", EMISSIVITY;
    ABSORPTIVITY_AREA_M2 = "absorptivity_area_m2", AREA_PRODUCT_M2;
    ABSORPTIVITY = "absorptivity", ABSORPTIVITY;
    AREA_M2 = "area_m2", AREA_M2;
    VIEW_FACTOR = "view_factor", VIEW_FACTOR;
    DISSIPATION_POWER_W = "power_w", POWER_W;
    HEATER_POWER_W = "power_w", HEATER_POWER_W;
    ON_K = "on_k", HEATER_ON_K;
    OFF_K = "off_k", HEATER_OFF_K;
    YAW_DEG = "yaw_deg", YAW_DEG;
    SPIN_RATE_DEG_PER_S = "spin_rate_deg_per_s", SPIN_RATE_DEG_PER_S;
    WINDOWS_S = "windows_s", WINDOW_S;
    WINDOWS_DAYS = "windows_days", WINDOW_DAYS;
    TAU_S = "tau_s", SENSOR_TAU_S;
    OFFSET_K = "offset_k", SENSOR_OFFSET_K;
    MODULE_MM = "module_mm", MODULE_MM;
    PRESSURE_ANGLE_DEG = "pressure_angle_deg", PRESSURE_ANGLE_DEG;
    FACE_WIDTH_MM = "face_width_mm", FACE_WIDTH_MM;
    CENTER_DISTANCE_MM = "center_distance_mm", CENTER_DISTANCE_MM;
    REFERENCE_TEMPERATURE_K = "reference_temperature_k", TEMPERATURE_K;
    MIN_BACKLASH_UM = "min_backlash_um", MIN_BACKLASH_UM;
    THICKNESS_UM = "thickness_um", COATING_THICKNESS_UM;
    ALPHA_PER_K = "alpha_per_k", EXPANSION_PER_K;
    DALPHA_DT_PER_K2 = "dalpha_dt_per_k2", DALPHA_DT_PER_K2;
    COEFFICIENTS = "coefficients", STRAIN_LAW;
    SCALE = "scale", STRAIN_LAW;
    ALPHA_POLYNOMIAL = "alpha_polynomial", STRAIN_LAW;
    STRAIN_TABLE_TEMPERATURE_K = "temperature_k", STRAIN_TABLE_TEMPERATURE_K;
    STRAIN = "strain", STRAIN_LAW;
    YOUNGS_MODULUS_PA = "youngs_modulus_pa", YOUNGS_MODULUS_PA;
    POISSON = "poisson", POISSON;
    TEETH = "teeth", TEETH;
    PROFILE_SHIFT = "profile_shift", PROFILE_SHIFT;
    TIP_RADIUS_MM = "tip_radius_mm", TIP_RADIUS_MM;
    ROOT_RADIUS_MM = "root_radius_mm", ROOT_RADIUS_MM;
    BORE_RADIUS_MM = "bore_radius_mm", BORE_RADIUS_MM;
    TOOTH_THICKNESS_MM = "tooth_thickness_mm", TOOTH_THICKNESS_MM;
    TOOTH_THINNING_UM = "tooth_thinning_um", TOOTH_THINNING_UM;
    INTERFERENCE_UM = "interference_um", INTERFERENCE_UM;
}

/// The tables inside a gear pair that hold numbers.
pub const COATING: &str = "coating";
pub const CENTER_DISTANCE: &str = "center_distance";
pub const PINION: &str = "pinion";
pub const WHEEL: &str = "wheel";
pub const MATERIAL: &str = "material";
pub const SHAFT_MATERIAL: &str = "shaft_material";
pub const STRAIN_POLYNOMIAL: &str = "strain_polynomial";
pub const STRAIN_TABLE: &str = "strain_table";

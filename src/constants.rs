//! Physical constants, each from one place with its source.

/// Stefan–Boltzmann constant, W/(m² K⁴). CODATA 2018 exact value
/// (σ = 2π⁵k⁴/(15h³c²) with the SI-defined k, h, c).
pub const STEFAN_BOLTZMANN_W_PER_M2_K4: f64 = 5.670_374_419e-8;

/// Earth's gravitational parameter GM, m³/s². WGS 84 (NIMA TR8350.2, 3rd ed., 2000).
pub const EARTH_MU_M3_PER_S2: f64 = 3.986_004_418e14;

/// Earth's equatorial radius, m. WGS 84 semi-major axis.
pub const EARTH_RADIUS_M: f64 = 6_378_137.0;

/// Mean total solar irradiance at 1 AU, W/m². Kopp & Lean (2011), GRL 38, L01706.
pub const SOLAR_CONSTANT_W_PER_M2: f64 = 1361.0;

/// 0 °C in kelvin (SI definition).
pub const ZERO_CELSIUS_K: f64 = 273.15;

/// Effective temperature of deep space as a radiative sink, K: the cosmic microwave
/// background is 2.725 K (Fixsen 2009, ApJ 707, 916); 3 K is the value spacecraft
/// thermal analyses use (Gilmore, Spacecraft Thermal Control Handbook, 2nd ed., 2002,
/// §2). Default of `environment.space_sink_k`.
pub const SPACE_SINK_K: f64 = 3.0;

/// Earth's mean albedo for orbital thermal analysis: 0.30 (Gilmore 2002, Table 2.3, the
/// orbit-average design value). Default of `environment.albedo`.
pub const EARTH_ALBEDO: f64 = 0.30;

/// Earth's mean outgoing long-wave radiation at the top of the atmosphere, W/m²: 237
/// (Gilmore 2002, Table 2.3; the CERES-era global annual mean is 240 ± 3). Default of
/// `environment.earth_ir_w_per_m2`.
pub const EARTH_IR_W_PER_M2: f64 = 237.0;

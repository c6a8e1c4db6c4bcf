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

//! Unit conversions used at the edges (SI inside; °C, µm, mm, days outside).

use crate::constants::ZERO_CELSIUS_K;

/// Kelvin to degrees Celsius.
pub fn k_to_c(t_k: f64) -> f64 {
    t_k - ZERO_CELSIUS_K
}

/// Degrees Celsius to kelvin.
pub fn c_to_k(t_c: f64) -> f64 {
    t_c + ZERO_CELSIUS_K
}

/// Seconds in one day.
pub const SECONDS_PER_DAY: f64 = 86_400.0;

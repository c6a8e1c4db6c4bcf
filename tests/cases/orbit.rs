//! Orbit and environment of `reference-mechanism.md` §1, written from the spec.

use std::f64::consts::PI;

/// Earth radius R (m).
pub const EARTH_RADIUS_M: f64 = 6378.137e3;
/// Orbit altitude h (m).
pub const ALTITUDE_M: f64 = 500.0e3;
/// Gravitational parameter μ (m³/s²).
pub const MU_M3_PER_S2: f64 = 3.986004418e14;
/// Beta angle β (deg).
pub const BETA_DEG: f64 = 20.0;
/// Solar flux S (W/m²).
pub const SOLAR_FLUX_W_PER_M2: f64 = 1361.0;
/// Earth albedo a (for the albedo load, off in the reference model).
pub const ALBEDO: f64 = 0.30;
/// Earth infrared flux (W/m²).
pub const EARTH_IR_W_PER_M2: f64 = 237.0;
/// Stefan–Boltzmann constant (CODATA 2018, exact in SI).
pub const SIGMA_W_PER_M2_K4: f64 = 5.670374419e-8;
/// Deep-space sink (K).
pub const SPACE_K: f64 = 3.0;
/// Spacecraft bus boundary node (K).
pub const BUS_K: f64 = 293.15;
/// Initial temperature of every diffusion node (K).
pub const INITIAL_K: f64 = 293.15;
/// Sun absorptivity × sun-facing area of the housing (m²): 0.7 × 0.025.
pub const SUN_ALPHA_AREA_M2: f64 = 0.0175;

/// Orbit period T = 2π √((R+h)³/μ) (s).
pub fn period_s() -> f64 {
    let r = EARTH_RADIUS_M + ALTITUDE_M;
    2.0 * PI * (r * r * r / MU_M3_PER_S2).sqrt()
}

/// Orbit angle θ(t) = 2π t / T (rad), θ(0) = 0 at orbit noon.
pub fn orbit_angle(t_s: f64) -> f64 {
    2.0 * PI * t_s / period_s()
}

/// cos θ cos β: the cosine of the angle between the Sun direction and the nadir.
pub fn cos_sun_nadir(t_s: f64) -> f64 {
    orbit_angle(t_s).cos() * BETA_DEG.to_radians().cos()
}

/// Cylindrical shadow, no penumbra: eclipsed when cos θ cos β < 0 and
/// (R+h)² (1 − cos²θ cos²β) < R².
pub fn sunlit(t_s: f64) -> bool {
    let c = cos_sun_nadir(t_s);
    let r = EARTH_RADIUS_M + ALTITUDE_M;
    !(c < 0.0 && r * r * (1.0 - c * c) < EARTH_RADIUS_M * EARTH_RADIUS_M)
}

/// Eclipse half-angle φ (rad): cos φ = √((R+h)² − R²) / ((R+h) cos β).
pub fn eclipse_half_angle() -> f64 {
    let r = EARTH_RADIUS_M + ALTITUDE_M;
    ((r * r - EARTH_RADIUS_M * EARTH_RADIUS_M).sqrt() / (r * BETA_DEG.to_radians().cos())).acos()
}

/// Times of eclipse entry and exit in [0, t_end] (s), sorted. Eclipse is
/// θ ∈ (π − φ, π + φ) modulo 2π.
pub fn eclipse_boundaries(t_end_s: f64) -> Vec<f64> {
    let t = period_s();
    let phi = eclipse_half_angle();
    let mut out = Vec::new();
    let mut k = 0.0;
    loop {
        let entry = (k + (PI - phi) / (2.0 * PI)) * t;
        let exit = (k + (PI + phi) / (2.0 * PI)) * t;
        if entry > t_end_s {
            break;
        }
        out.push(entry);
        if exit <= t_end_s {
            out.push(exit);
        }
        k += 1.0;
    }
    out
}

/// View factor of the Earth from a nadir face, F = (R/(R+h))².
pub fn earth_view_factor() -> f64 {
    let q = EARTH_RADIUS_M / (EARTH_RADIUS_M + ALTITUDE_M);
    q * q
}

/// Earth albedo on a nadir face of absorptivity × area `alpha_area_m2`:
/// Q = αA S a F max(0, cos θ cos β) (W). Zero on the night side, hence in eclipse.
pub fn albedo_load_w(alpha_area_m2: f64, t_s: f64) -> f64 {
    alpha_area_m2 * SOLAR_FLUX_W_PER_M2 * ALBEDO * earth_view_factor() * cos_sun_nadir(t_s).max(0.0)
}

/// Earth infrared on a nadir face of emissivity × area `eps_area_m2`: εA × 237 × F (W).
pub fn earth_ir_load_w(eps_area_m2: f64) -> f64 {
    eps_area_m2 * EARTH_IR_W_PER_M2 * earth_view_factor()
}

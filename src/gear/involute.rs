//! Involute geometry of spur gears.

/// inv α = tan α − α.
pub fn inv(alpha_rad: f64) -> f64 {
    alpha_rad.tan() - alpha_rad
}

/// Base tooth thickness (arc on the base circle) from the tooth thickness `s` on the
/// reference circle of radius `r`: s_b = r_b (s/r + 2 inv α₀).
pub fn base_tooth_thickness(r_b: f64, s: f64, r: f64, alpha0_rad: f64) -> f64 {
    r_b * (s / r + 2.0 * inv(alpha0_rad))
}

/// Tooth thickness on the reference circle of a profile-shifted gear with no
/// thinning: s = m (π/2 + 2 x tan α₀).
pub fn shifted_tooth_thickness(module: f64, shift: f64, alpha0_rad: f64) -> f64 {
    module * (std::f64::consts::FRAC_PI_2 + 2.0 * shift * alpha0_rad.tan())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn val_published_involute_function() {
        // inv 20° = tan 20° − 20° in radians (tables: 0.0149044).
        assert!((inv(20f64.to_radians()) - 0.014_904_383_8).abs() < 1e-10);
        assert_eq!(inv(0.0), 0.0);
    }
}

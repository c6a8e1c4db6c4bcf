//! Involute geometry of spur gears.

/// inv α = tan α − α.
pub fn inv(alpha_rad: f64) -> f64 {
    alpha_rad.tan() - alpha_rad
}

/// α such that inv α = `x` (x ≥ 0), by Newton's method on tan α − α − x.
pub fn inv_inverse(x: f64) -> f64 {
    // Start from the series inv α ≈ α³/3 for small α, capped below π/2.
    let mut a = (3.0 * x).cbrt().min(1.4);
    for _ in 0..50 {
        let t = a.tan();
        let f = t - a - x;
        let d = t * t; // d/dα (tan α − α) = tan² α
        let step = f / d.max(1e-300);
        a -= step;
        if step.abs() < 1e-15 {
            break;
        }
    }
    a
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
    fn inverse_of_inv() {
        for deg in [5.0f64, 14.5, 20.0, 26.0886, 40.0, 60.0] {
            let a = deg.to_radians();
            assert!((inv_inverse(inv(a)) - a).abs() < 1e-13, "{deg}");
        }
        assert!((inv(20f64.to_radians()) - 0.014_904_383_8).abs() < 1e-10);
    }
}

//! Normal backlash of an involute spur pair (`shared/spec/physics.md` §4).
//!
//! Each flank crosses its line of action at a position that moves linearly with its
//! gear's rotation. With gear 1 at travel u = r_b1 θ1 and gear 2 at v = r_b2 θ2, the
//! flank of gear-1 tooth k meets its partner at
//!   gap_A(k) = G + v − u + kΔ     on the drive line A, at ξ = u + c + k p_b1,
//!   gap_B(k) = G − v + u − kΔ     on the coast line B, at η = −u + c − k p_b1,
//! with Δ = p_b2 − p_b1, c = r_b1 α_w + s_b1/2 and
//! 2G = p_b2 − s_b1 − s_b2 + 2(r_b1 + r_b2) inv α_w. A pair counts while its gear-1
//! flank point lies on the path of contact [ξ_s, ξ_e] between the tip circles.
//! Holding A in contact (smallest gap zero) and reading the smallest gap on B gives
//!   j(u) = 2G − |Δ| · spread(u),
//! spread = max_A k − min_B k (Δ < 0) or max_B k − min_A k (Δ > 0). Over one base
//! pitch of rotation the largest spread is floor(2(ξ_e − c)/p_b1) (Δ < 0) or
//! floor(2(c − ξ_s)/p_b1) (Δ > 0), so the worst case over the mesh cycle is O(1):
//! no scan over phases or tooth pairs. Equal pitches give the textbook
//! j_n = p_b − s_b1 − s_b2 + 2(r_b1 + r_b2) inv α_w.

use super::involute::inv;

/// Deformed geometry of one gear entering the backlash computation, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlankGeometry {
    pub teeth: u32,
    pub base_radius_m: f64,
    /// Base tooth thickness including both coatings, m.
    pub base_thickness_m: f64,
    pub tip_radius_m: f64,
}

impl FlankGeometry {
    pub fn base_pitch_m(&self) -> f64 {
        std::f64::consts::TAU * self.base_radius_m / self.teeth as f64
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Backlash {
    /// Operating pressure angle, cos α_w = (r_b1 + r_b2)/a.
    pub pressure_angle_rad: f64,
    /// Smallest normal backlash over a mesh cycle, m.
    pub exact_m: f64,
    /// Pitch-averaged closed form, (p_b1 + p_b2)/2 − s_b1 − s_b2 + 2(r_b1 + r_b2) inv α_w, m.
    pub closed_form_m: f64,
    /// Transverse contact ratio (path of contact / base pitch of gear 1).
    pub contact_ratio: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error(
        "the base circles do not fit in the centre distance: r_b1 + r_b2 = {:.5} mm ≥ a = {:.5} mm",
        sum_m * 1e3,
        a_m * 1e3
    )]
    BaseCirclesOverlap { sum_m: f64, a_m: f64 },
    #[error("contact ratio {0:.3} < 1: the teeth lose contact during the mesh cycle")]
    ContactLost(f64),
}

/// Backlash of the pair at centre distance `a_m`.
pub fn backlash(g1: &FlankGeometry, g2: &FlankGeometry, a_m: f64) -> Result<Backlash, MeshError> {
    let (rb1, rb2) = (g1.base_radius_m, g2.base_radius_m);
    let cos_aw = (rb1 + rb2) / a_m;
    if cos_aw >= 1.0 || cos_aw.is_nan() {
        return Err(MeshError::BaseCirclesOverlap {
            sum_m: rb1 + rb2,
            a_m,
        });
    }
    let aw = cos_aw.acos();
    let (pb1, pb2) = (g1.base_pitch_m(), g2.base_pitch_m());
    let (sb1, sb2) = (g1.base_thickness_m, g2.base_thickness_m);
    let involute_term = 2.0 * (rb1 + rb2) * inv(aw);
    let two_g = pb2 - sb1 - sb2 + involute_term;
    let closed_form = 0.5 * (pb1 + pb2) - sb1 - sb2 + involute_term;

    let g = (a_m * a_m - (rb1 + rb2) * (rb1 + rb2)).sqrt();
    let xi_s = g
        - (g2.tip_radius_m * g2.tip_radius_m - rb2 * rb2)
            .max(0.0)
            .sqrt();
    let xi_e = (g1.tip_radius_m * g1.tip_radius_m - rb1 * rb1)
        .max(0.0)
        .sqrt();
    let contact_ratio = (xi_e - xi_s) / pb1;
    if contact_ratio < 1.0 {
        return Err(MeshError::ContactLost(contact_ratio));
    }
    let c = rb1 * aw + 0.5 * sb1;
    let delta = pb2 - pb1;
    let spread = if delta < 0.0 {
        (2.0 * (xi_e - c) / pb1).floor()
    } else {
        (2.0 * (c - xi_s) / pb1).floor()
    };
    Ok(Backlash {
        pressure_angle_rad: aw,
        exact_m: two_g - delta.abs() * spread,
        closed_form_m: closed_form,
        contact_ratio,
    })
}

/// The same worst case found the slow way: the phase of gear 1 scanned over one base
/// pitch and the pairs on each line of action enumerated. `backlash` must agree with
/// it (tested below).
pub fn backlash_by_scan(g1: &FlankGeometry, g2: &FlankGeometry, a_m: f64, phases: usize) -> f64 {
    let (rb1, rb2) = (g1.base_radius_m, g2.base_radius_m);
    let aw = ((rb1 + rb2) / a_m).acos();
    let (pb1, pb2) = (g1.base_pitch_m(), g2.base_pitch_m());
    let (sb1, sb2) = (g1.base_thickness_m, g2.base_thickness_m);
    let gg = pb2 - sb1 - sb2 + 2.0 * (rb1 + rb2) * inv(aw);
    let half_g = 0.5 * gg;
    let g = (a_m * a_m - (rb1 + rb2) * (rb1 + rb2)).sqrt();
    let xi_s = g - (g2.tip_radius_m * g2.tip_radius_m - rb2 * rb2).sqrt();
    let xi_e = (g1.tip_radius_m * g1.tip_radius_m - rb1 * rb1).sqrt();
    let c = rb1 * aw + 0.5 * sb1;
    let delta = pb2 - pb1;
    let kmax = (g / pb1).ceil() as i64 + 2;
    let mut worst = f64::INFINITY;
    for step in 0..phases {
        let u = pb1 * step as f64 / phases as f64;
        // v that closes the drive line A.
        let mut v = f64::NEG_INFINITY;
        for k in -kmax..=kmax {
            let xi = u + c + k as f64 * pb1;
            if (xi_s..=xi_e).contains(&xi) {
                v = v.max(u - half_g - k as f64 * delta);
            }
        }
        let mut j = f64::INFINITY;
        for k in -kmax..=kmax {
            let eta = -u + c - k as f64 * pb1;
            if (xi_s..=xi_e).contains(&eta) {
                j = j.min(half_g - v + u - k as f64 * delta);
            }
        }
        worst = worst.min(j);
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A standard 1 mm pair (z1, z2), each gear scaled by its own λ.
    fn pair(z1: u32, z2: u32, l1: f64, l2: f64) -> (FlankGeometry, FlankGeometry, f64) {
        let (m, a0) = (1e-3, 20f64.to_radians());
        let g = |z: u32, l: f64| {
            let r = m * z as f64 / 2.0;
            let rb = r * a0.cos();
            FlankGeometry {
                teeth: z,
                base_radius_m: rb * l,
                base_thickness_m: l
                    * rb
                    * ((std::f64::consts::FRAC_PI_2 * m - 20e-6) / r + 2.0 * inv(a0)),
                tip_radius_m: l * (r + m),
            }
        };
        (g(z1, l1), g(z2, l2), m * (z1 + z2) as f64 / 2.0)
    }

    #[test]
    fn core_closed_form_worst_case_matches_the_phase_scan() {
        let mut checked = 0;
        for (z1, z2) in [(20, 40), (17, 53), (31, 31), (12, 90)] {
            for d1 in [-150.0, -40.0, 0.0, 25.0, 90.0] {
                for d2 in [-120.0, -10.0, 0.0, 60.0] {
                    let (g1, g2, a) = pair(z1, z2, 1.0 + 11e-6 * d1, 1.0 + 11e-6 * d2);
                    let Ok(fast) = backlash(&g1, &g2, a) else {
                        continue;
                    };
                    let scan = backlash_by_scan(&g1, &g2, a, 4000);
                    // The scan samples phases, so it can only find a larger minimum;
                    // the plateau of the worst case is wide enough here to be hit.
                    assert!(
                        fast.exact_m <= scan + 1e-15,
                        "{z1}/{z2} {d1}/{d2}: {} > {scan}",
                        fast.exact_m
                    );
                    assert!(
                        scan - fast.exact_m < 1e-12,
                        "{z1}/{z2} {d1}/{d2}: {} vs {scan}",
                        fast.exact_m
                    );
                    assert!(fast.exact_m <= fast.closed_form_m + 1e-15);
                    checked += 1;
                }
            }
        }
        assert!(checked > 60, "{checked}");
    }
}

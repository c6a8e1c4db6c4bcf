//! The checks of a gear pair's geometry and materials: a gear that can be cut, a tooth
//! that exists and is not pointed, nodes from the bore to the base circle, a pair that
//! meshes with positive backlash, a metal's stiffness, a strain law a solid can have.
//! Each error says which part of the gear it concerns ([`Part`]); the spec layer places
//! it at that part's key in the scenario file.

use super::GearPair;
use super::involute::inv;
use super::strain::StrainLaw;

/// The part of a gear or pair a check concerns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// The number of teeth.
    Teeth,
    TipRadius,
    BoreRadius,
    /// The tooth thickness, however it was given.
    ToothThickness,
    /// The gear's node `k` (from the bore).
    Node(usize),
    /// The centre distance of the pair.
    CenterDistance,
    /// A material's Young's modulus.
    YoungsModulus,
    /// A thermal strain law as a whole.
    StrainLaw,
}

/// A geometry or material that cannot be: where and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct GeometryError {
    pub part: Part,
    pub message: String,
}

fn err(part: Part, message: String) -> GeometryError {
    GeometryError { part, message }
}

/// A length in mm with six decimals, for messages.
fn mm(x: f64) -> String {
    format!("{} mm", crate::units::fixed(x * 1e3, 6))
}

/// Fewest and most teeth of a gear.
pub const TEETH: std::ops::RangeInclusive<i64> = 5..=10_000;

/// The number of teeth, within [`TEETH`].
pub fn teeth(z: i64) -> Result<u32, GeometryError> {
    if TEETH.contains(&z) {
        Ok(z as u32)
    } else {
        Err(err(
            Part::Teeth,
            format!(
                "must be within {} … {} (got {z})",
                TEETH.start(),
                TEETH.end()
            ),
        ))
    }
}

/// The bore below the base (`r_b`) and root radii, the tip above both, m.
pub fn radii(r_b: f64, tip: f64, root: f64, bore: f64) -> Result<(), GeometryError> {
    if bore >= r_b {
        return Err(err(
            Part::BoreRadius,
            format!(
                "bore radius {} must be below the base radius r_b = m z cos α₀ / 2 = {}",
                mm(bore),
                mm(r_b)
            ),
        ));
    }
    if bore >= root {
        return Err(err(
            Part::BoreRadius,
            format!(
                "bore radius {} must be below the root radius {}",
                mm(bore),
                mm(root)
            ),
        ));
    }
    if tip <= r_b || tip <= root {
        return Err(err(
            Part::TipRadius,
            format!(
                "tip radius {} must exceed the base radius {} and the root radius {}",
                mm(tip),
                mm(r_b),
                mm(root)
            ),
        ));
    }
    Ok(())
}

/// The tooth must exist and fit: 0 < s < π m on the reference circle (radius `r_ref`),
/// and not come to a point below the tip (s_a > 0 on the tip circle); module `module_m`,
/// pressure angle `alpha0`, base radius `r_b`, tip radius `tip`, all in m and rad.
pub fn tooth(
    module_m: f64,
    alpha0: f64,
    thickness: f64,
    r_ref: f64,
    r_b: f64,
    tip: f64,
) -> Result<(), GeometryError> {
    let pitch = std::f64::consts::PI * module_m;
    if !(thickness > 0.0 && thickness < pitch) {
        return Err(err(
            Part::ToothThickness,
            format!(
                "gives a tooth thickness of {} on the reference circle; it must be within 0 … {} (the circular pitch π m)",
                mm(thickness),
                mm(pitch)
            ),
        ));
    }
    let alpha_tip = (r_b / tip).acos();
    let tip_thickness = tip * (thickness / r_ref + 2.0 * inv(alpha0) - 2.0 * inv(alpha_tip));
    if tip_thickness <= 0.0 {
        return Err(err(
            Part::ToothThickness,
            format!(
                "gives a tooth thickness of {} on the reference circle, which comes to a point below the tip radius {} (thickness at the tip {})",
                mm(thickness),
                mm(tip),
                mm(tip_thickness)
            ),
        ));
    }
    Ok(())
}

/// Relative tolerance for node radii that must sit on the bore and the base circle.
pub const RADIUS_TOLERANCE: f64 = 1e-5;

/// Node `k` at radius `r` (m) after the nodes before it (the last at `before`): radii
/// increase from the bore to the base circle.
pub fn next_node(k: usize, before: Option<f64>, r: f64) -> Result<(), GeometryError> {
    if before.is_some_and(|prev| r <= prev) {
        return Err(err(
            Part::Node(k),
            "node radii must increase from the bore to the base circle".into(),
        ));
    }
    Ok(())
}

/// The first node on the bore circle, the last on the base circle (`r_b`).
pub fn node_ends(radii: &[f64], bore: f64, r_b: f64) -> Result<(), GeometryError> {
    if (radii[0] - bore).abs() > RADIUS_TOLERANCE * bore {
        return Err(err(
            Part::Node(0),
            format!(
                "the first node sits at {} but the bore radius is {}",
                mm(radii[0]),
                mm(bore)
            ),
        ));
    }
    let last = *radii.last().expect("nodes");
    if (last - r_b).abs() > RADIUS_TOLERANCE * r_b {
        return Err(err(
            Part::Node(radii.len() - 1),
            format!(
                "the last node sits at {} but the base radius is {}",
                mm(last),
                mm(r_b)
            ),
        ));
    }
    Ok(())
}

/// The assembled pair must mesh with positive backlash.
pub fn mesh(pair: &GearPair) -> Result<(), GeometryError> {
    let (module_m, alpha0) = (pair.module_m, pair.pressure_angle_rad);
    let nominal = pair.nominal_backlash_m();
    let rb_sum = pair
        .gears
        .iter()
        .map(|g| g.base_radius_m(module_m, alpha0))
        .sum::<f64>();
    let at = |m: String| Err(err(Part::CenterDistance, m));
    if rb_sum >= pair.center_distance_m {
        return at("is shorter than the sum of the base radii".into());
    }
    if nominal.is_nan() {
        return at("the gears do not mesh at this centre distance (contact ratio below 1)".into());
    }
    if nominal <= 0.0 {
        return at(format!(
            "the pair has negative backlash at assembly ({:.3} µm): the teeth are too thick for this centre distance",
            nominal * 1e6
        ));
    }
    Ok(())
}

/// Smallest Young's modulus of a metal, Pa.
pub const MIN_YOUNGS_MODULUS_PA: f64 = 1e8;

/// A metal's Young's modulus (already positive), Pa.
pub fn youngs_modulus(e: f64) -> Result<(), GeometryError> {
    if e < MIN_YOUNGS_MODULUS_PA {
        return Err(err(
            Part::YoungsModulus,
            format!("is in pascal: {e} Pa is not a metal (steel is 2e11)"),
        ));
    }
    Ok(())
}

/// Largest thermal strain a law may give between 20 K and 1000 K, relative to room
/// temperature: ten times that of aluminium (1.5 %) between those temperatures.
pub const MAX_THERMAL_STRAIN: f64 = 0.1;

/// A strain law whose values stay within ±[`MAX_THERMAL_STRAIN`] of its value at
/// 293.15 K over 20 … 1000 K (a polynomial with a wrong `scale` fails here).
pub fn strain_law(law: &StrainLaw) -> Result<(), GeometryError> {
    // every 35 K from 20 K to 1000 K (a wrong scale or coefficient shows everywhere)
    let worst = (0..=28)
        .map(|k| 20.0 + 35.0 * k as f64)
        .map(|t| (t, law.strain(t, 293.15)))
        .find(|(_, e)| e.is_nan() || e.abs() > MAX_THERMAL_STRAIN);
    if let Some((t, e)) = worst {
        return Err(err(
            Part::StrainLaw,
            format!(
                "the thermal strain law gives {e:.3e} at {t} K relative to 293.15 K; a solid's thermal strain stays within ±{MAX_THERMAL_STRAIN} over 20 … 1000 K (check the coefficients and `scale`)"
            ),
        ));
    }
    Ok(())
}

//! The rows of gear pairs: a pair's own numbers, its strain laws and each gear's
//! numbers and materials, built for every place they sit (pinion and wheel, material and
//! shaft material, the centre distance's law).

use super::{Fast, Field, Row, Section, Slot, row};
use crate::spec::{GearSpec, MaterialSpec, PolynomialSpec, ScenarioSpec, StrainTableSpec};

fields! {
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

/// The keys of a thermal strain law in a spec.
struct Strain<'a> {
    alpha: &'a mut Option<f64>,
    dalpha: &'a mut Option<f64>,
    poly: &'a mut Option<PolynomialSpec>,
    alpha_poly: &'a mut Option<Vec<f64>>,
    table: &'a mut Option<StrainTableSpec>,
}

fn strain_of(m: &mut MaterialSpec) -> Strain<'_> {
    Strain {
        alpha: &mut m.alpha_per_k,
        dalpha: &mut m.dalpha_dt_per_k2,
        poly: &mut m.strain_polynomial,
        alpha_poly: &mut m.alpha_polynomial,
        table: &mut m.strain_table,
    }
}

/// A table path made once (the registry is built once).
fn leak(parts: Vec<&'static str>) -> &'static [&'static str] {
    Box::leak(parts.into_boxed_slice())
}

/// The rows of a strain law at `table` of a gear pair.
fn strain_rows<F>(t: &mut Vec<Row>, table: &'static [&'static str], get: F)
where
    F: for<'a> Fn(&'a mut ScenarioSpec, usize) -> Option<Strain<'a>> + Copy + Send + Sync + 'static,
{
    let within = |k: &'static str| leak(table.iter().copied().chain([k]).collect());
    let (poly, strain_table) = (within(STRAIN_POLYNOMIAL), within(STRAIN_TABLE));
    let g = Section::GearPair;
    t.extend([
        row(
            g,
            table,
            &ALPHA_PER_K,
            "the linear expansion coefficient α",
            move |s, e| get(s, e).map(|x| Slot::Optional(x.alpha)),
        ),
        row(
            g,
            table,
            &DALPHA_DT_PER_K2,
            "dα/dT, with `alpha_per_k`",
            move |s, e| get(s, e).map(|x| Slot::Optional(x.dalpha)),
        ),
        row(
            g,
            poly,
            &COEFFICIENTS,
            "the strain polynomial's coefficients",
            move |s, e| {
                get(s, e)?
                    .poly
                    .as_mut()
                    .map(|p| Slot::List(&mut p.coefficients))
            },
        ),
        row(
            g,
            poly,
            &SCALE,
            "the strain polynomial's scale",
            move |s, e| get(s, e)?.poly.as_mut().map(|p| Slot::Value(&mut p.scale)),
        ),
        row(
            g,
            table,
            &ALPHA_POLYNOMIAL,
            "α as a polynomial of temperature",
            move |s, e| get(s, e)?.alpha_poly.as_mut().map(Slot::List),
        ),
        row(
            g,
            strain_table,
            &STRAIN_TABLE_TEMPERATURE_K,
            "the strain table's temperatures",
            move |s, e| {
                get(s, e)?
                    .table
                    .as_mut()
                    .map(|x| Slot::List(&mut x.temperature_k))
            },
        ),
        row(
            g,
            strain_table,
            &STRAIN,
            "the strain table's strains",
            move |s, e| get(s, e)?.table.as_mut().map(|x| Slot::List(&mut x.strain)),
        ),
    ]);
    for r in t.iter_mut().rev().take(7) {
        r.fast = Fast::GearPair;
    }
}

/// The rows of a disc material at `table`.
fn material_rows<F>(t: &mut Vec<Row>, table: &'static [&'static str], get: F)
where
    F: for<'a> Fn(&'a mut ScenarioSpec, usize) -> Option<&'a mut MaterialSpec>
        + Copy
        + Send
        + Sync
        + 'static,
{
    strain_rows(t, table, move |s, e| get(s, e).map(strain_of));
    let g = Section::GearPair;
    t.extend([
        row(
            g,
            table,
            &YOUNGS_MODULUS_PA,
            "Young's modulus E",
            move |s, e| get(s, e).map(|m| Slot::Value(&mut m.youngs_modulus_pa)),
        )
        .gear_pair(),
        row(g, table, &POISSON, "Poisson's ratio ν", move |s, e| {
            get(s, e).map(|m| Slot::Value(&mut m.poisson))
        })
        .gear_pair(),
    ]);
}

/// The rows of one gear (`pinion` or `wheel`).
fn gear_rows(
    t: &mut Vec<Row>,
    which: &'static str,
    get: for<'a> fn(&'a mut ScenarioSpec, usize) -> &'a mut GearSpec,
) {
    let table = leak(vec![which]);
    let g = Section::GearPair;
    t.extend([
        row(g, table, &TEETH, "the number of teeth z", move |s, e| {
            Some(Slot::Integer(&mut get(s, e).teeth))
        }),
        row(
            g,
            table,
            &PROFILE_SHIFT,
            "the profile shift coefficient x",
            move |s, e| Some(Slot::Value(&mut get(s, e).profile_shift)),
        ),
        row(g, table, &TIP_RADIUS_MM, "the tip radius", move |s, e| {
            Some(Slot::Value(&mut get(s, e).tip_radius_mm))
        }),
        row(g, table, &ROOT_RADIUS_MM, "the root radius", move |s, e| {
            Some(Slot::Value(&mut get(s, e).root_radius_mm))
        }),
        row(g, table, &BORE_RADIUS_MM, "the bore radius", move |s, e| {
            Some(Slot::Value(&mut get(s, e).bore_radius_mm))
        }),
        row(
            g,
            table,
            &TOOTH_THICKNESS_MM,
            "the tooth thickness on the reference circle",
            move |s, e| Some(Slot::Optional(&mut get(s, e).tooth_thickness_mm)),
        ),
        row(
            g,
            table,
            &TOOTH_THINNING_UM,
            "the thinning below the profile-shifted nominal tooth",
            move |s, e| Some(Slot::Optional(&mut get(s, e).tooth_thinning_um)),
        ),
        row(
            g,
            table,
            &INTERFERENCE_UM,
            "an elastic bore fit's radial interference",
            move |s, e| Some(Slot::Optional(&mut get(s, e).interference_um)),
        ),
    ]);
    for r in t.iter_mut().rev().take(8) {
        r.fast = Fast::GearPair;
    }
    material_rows(t, leak(vec![which, MATERIAL]), move |s, e| {
        Some(&mut get(s, e).material)
    });
    material_rows(t, leak(vec![which, SHAFT_MATERIAL]), move |s, e| {
        get(s, e).shaft_material.as_mut()
    });
}

pub(super) fn gear_pairs(t: &mut Vec<Row>) {
    let g = Section::GearPair;
    t.extend([
        row(g, &[], &MODULE_MM, "the module m", |s, e| {
            Some(Slot::Value(&mut s.gear_pair[e].module_mm))
        }),
        row(
            g,
            &[],
            &PRESSURE_ANGLE_DEG,
            "the pressure angle α₀ the gears are cut with",
            |s, e| Some(Slot::Value(&mut s.gear_pair[e].pressure_angle_deg)),
        ),
        row(g, &[], &FACE_WIDTH_MM, "the face width", |s, e| {
            Some(Slot::Value(&mut s.gear_pair[e].face_width_mm))
        }),
        row(
            g,
            &[],
            &CENTER_DISTANCE_MM,
            "the centre distance at the reference temperature",
            |s, e| Some(Slot::Value(&mut s.gear_pair[e].center_distance_mm)),
        ),
        row(
            g,
            &[],
            &REFERENCE_TEMPERATURE_K,
            "the temperature the geometry is given at",
            |s, e| Some(Slot::Value(&mut s.gear_pair[e].reference_temperature_k)),
        ),
        row(
            g,
            &[],
            &MIN_BACKLASH_UM,
            "the smallest backlash allowed (the verdict's margin)",
            |s, e| Some(Slot::Value(&mut s.gear_pair[e].min_backlash_um)),
        ),
        row(
            g,
            &[COATING],
            &THICKNESS_UM,
            "the tooth coating's thickness",
            |s, e| Some(Slot::Value(&mut s.gear_pair[e].coating.thickness_um)),
        ),
        row(
            g,
            &[COATING],
            &ALPHA_PER_K,
            "the coating's expansion coefficient",
            |s, e| Some(Slot::Value(&mut s.gear_pair[e].coating.alpha_per_k)),
        ),
        row(
            g,
            &[COATING],
            &POISSON,
            "the coating's Poisson ratio",
            |s, e| Some(Slot::Value(&mut s.gear_pair[e].coating.poisson)),
        ),
    ]);
    for r in t.iter_mut().rev().take(9) {
        r.fast = Fast::GearPair;
    }
    strain_rows(t, &[CENTER_DISTANCE], |s, e| {
        s.gear_pair[e].center_distance.as_mut().map(|c| Strain {
            alpha: &mut c.alpha_per_k,
            dalpha: &mut c.dalpha_dt_per_k2,
            poly: &mut c.strain_polynomial,
            alpha_poly: &mut c.alpha_polynomial,
            table: &mut c.strain_table,
        })
    });
    gear_rows(t, PINION, |s, e| &mut s.gear_pair[e].pinion);
    gear_rows(t, WHEEL, |s, e| &mut s.gear_pair[e].wheel);
}

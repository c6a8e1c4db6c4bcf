//! `[[gear_pair]]`: each pair's values read through their registry fields, its nodes
//! looked up, the form of each strain law and tooth thickness chosen; the geometry and
//! the materials are checked by `crate::gear::check`, whose errors are placed at their
//! keys here ([`place`]).

use super::*;
use crate::gear::check::{self as geometry, GeometryError, Part};
use crate::spec::registry as r;

/// A geometry error at its key: `gp` the gear's path (or the pair's, for the centre
/// distance), `tooth` the key the tooth thickness came from, `nodes` the gear's
/// `nodes` list.
fn place(e: GeometryError, gp: &KeyPath, tooth: &'static str) -> SpecError {
    let at = match e.part {
        Part::Teeth => r::TEETH.key(gp),
        Part::TipRadius => r::TIP_RADIUS_MM.key(gp),
        Part::BoreRadius => r::BORE_RADIUS_MM.key(gp),
        Part::ToothThickness => gp.key(tooth),
        Part::Node(k) => gp.key(NODES).at(k),
        Part::CenterDistance => r::CENTER_DISTANCE_MM.key(gp),
        Part::YoungsModulus => r::YOUNGS_MODULUS_PA.key(gp),
        Part::StrainLaw => gp.clone(),
    };
    Cx.err(&at, e.message)
}

/// A gear's list of node names.
const NODES: &str = "nodes";

/// The keys that give a thermal strain law (exactly one form).
pub(super) struct StrainKeys {
    pub(super) alpha: Option<f64>,
    pub(super) dalpha: Option<f64>,
    pub(super) poly: Option<PolynomialSpec>,
    pub(super) alpha_poly: Option<Vec<f64>>,
    pub(super) table: Option<StrainTableSpec>,
}

/// The strain law at `p`, of a form a solid can have (`gear::check::strain_law`).
pub(super) fn strain_law(cx: &Cx, p: &KeyPath, keys: StrainKeys) -> Result<StrainLaw, SpecError> {
    let law = strain_law_unchecked(cx, p, keys)?;
    geometry::strain_law(&law).map_err(|e| place(e, p, ""))?;
    Ok(law)
}

/// The one form of strain law `keys` give.
fn strain_law_unchecked(cx: &Cx, p: &KeyPath, keys: StrainKeys) -> Result<StrainLaw, SpecError> {
    let StrainKeys {
        alpha,
        dalpha,
        poly,
        alpha_poly,
        table,
    } = keys;
    if let Some(coefficients) = alpha_poly {
        if alpha.is_some() || dalpha.is_some() || poly.is_some() || table.is_some() {
            return Err(cx.err(p, "give only one thermal strain law"));
        }
        let ap = r::ALPHA_POLYNOMIAL.key(p);
        if coefficients.is_empty() {
            return Err(cx.err(&ap, "must not be empty"));
        }
        for (k, c) in coefficients.iter().enumerate() {
            cx.finite(&ap.at(k), *c)?;
        }
        return Ok(StrainLaw::AlphaPolynomial { coefficients });
    }
    match (alpha, dalpha, poly, table) {
        (Some(a), None, None, None) => Ok(StrainLaw::Linear {
            alpha_per_k: cx.read(&r::ALPHA_PER_K, p, a)?,
        }),
        (Some(a), Some(d), None, None) => Ok(StrainLaw::Quadratic {
            alpha_per_k: cx.read(&r::ALPHA_PER_K, p, a)?,
            dalpha_dt_per_k2: cx.read(&r::DALPHA_DT_PER_K2, p, d)?,
        }),
        (None, None, Some(poly), None) => {
            let pp = p.key(r::STRAIN_POLYNOMIAL);
            let cp = r::COEFFICIENTS.key(&pp);
            if poly.coefficients.is_empty() {
                return Err(cx.err(&cp, "must not be empty"));
            }
            for (k, c) in poly.coefficients.iter().enumerate() {
                cx.finite(&cp.at(k), *c)?;
            }
            cx.read(&r::SCALE, &pp, poly.scale)?;
            Ok(StrainLaw::Polynomial {
                coefficients: poly.coefficients,
                scale: poly.scale,
            })
        }
        (None, None, None, Some(t)) => {
            let tp = p.key(r::STRAIN_TABLE);
            let temperature = r::STRAIN_TABLE_TEMPERATURE_K.key(&tp);
            if t.temperature_k.len() < 2 || t.temperature_k.len() != t.strain.len() {
                return Err(cx.err(
                    &tp,
                    format!(
                        "needs at least two points and as many `{}` as `{}` entries",
                        r::STRAIN.name,
                        r::STRAIN_TABLE_TEMPERATURE_K.name
                    ),
                ));
            }
            for (k, w) in t.temperature_k.windows(2).enumerate() {
                if w[1] <= w[0] || w[1].is_nan() || w[0].is_nan() {
                    return Err(cx.err(
                        &temperature.at(k + 1),
                        "temperatures must increase strictly",
                    ));
                }
            }
            for (k, v) in t.strain.iter().enumerate() {
                cx.finite(&r::STRAIN.key(&tp).at(k), *v)?;
            }
            Ok(StrainLaw::Table {
                temperature_k: t.temperature_k,
                strain: t.strain,
            })
        }
        _ => Err(cx.err(
            p,
            format!(
                "give the thermal strain as `{}` (optionally with `{}`), or `{}`, or `{}`, or `{}`",
                r::ALPHA_PER_K.name,
                r::DALPHA_DT_PER_K2.name,
                r::ALPHA_POLYNOMIAL.name,
                r::STRAIN_POLYNOMIAL,
                r::STRAIN_TABLE
            ),
        )),
    }
}

/// A gear's or a shaft's material at `p`.
fn disc_material(cx: &Cx, p: &KeyPath, m: MaterialSpec) -> Result<DiscMaterial, SpecError> {
    let youngs = cx.positive(&r::YOUNGS_MODULUS_PA.key(p), m.youngs_modulus_pa)?;
    geometry::youngs_modulus(youngs).map_err(|e| place(e, p, ""))?;
    let poisson = cx.read(&r::POISSON, p, m.poisson)?;
    Ok(DiscMaterial {
        strain: strain_law(
            cx,
            p,
            StrainKeys {
                alpha: m.alpha_per_k,
                dalpha: m.dalpha_dt_per_k2,
                poly: m.strain_polynomial,
                alpha_poly: m.alpha_polynomial,
                table: m.strain_table,
            },
        )?,
        youngs_modulus_pa: youngs,
        poisson,
    })
}

/// Gear pair `index` at `p`: its values, both gears, its centre distance, and that it
/// meshes.
pub(super) fn gear_pair(
    cx: &Cx,
    p: &KeyPath,
    g: GearPairSpec,
    index: usize,
    nodes: &[DiffusionNode],
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
) -> Result<GearPair, SpecError> {
    let module_m = cx.read(&r::MODULE_MM, p, g.module_mm)? * 1e-3;
    let alpha0 = cx
        .read(&r::PRESSURE_ANGLE_DEG, p, g.pressure_angle_deg)?
        .to_radians();
    let t_ref = cx.read(&r::REFERENCE_TEMPERATURE_K, p, g.reference_temperature_k)?;
    let coating = coating(cx, p, g.coating)?;
    let cutter = Cutter { module_m, alpha0 };
    let pinion = gear(cx, p, r::PINION, g.pinion, cutter, nodes, diffusion)?;
    let wheel = gear(cx, p, r::WHEEL, g.wheel, cutter, nodes, diffusion)?;
    let center = center_distance(cx, p, g.center_distance, diffusion)?;
    let pair = GearPair {
        name: g.name.unwrap_or_else(|| {
            if index == 0 {
                "mesh".into()
            } else {
                format!("mesh{index}")
            }
        }),
        module_m,
        pressure_angle_rad: alpha0,
        face_width_m: cx.read(&r::FACE_WIDTH_MM, p, g.face_width_mm)? * 1e-3,
        center_distance_m: cx.read(&r::CENTER_DISTANCE_MM, p, g.center_distance_mm)? * 1e-3,
        center,
        reference_temperature_k: t_ref,
        coating,
        min_backlash_m: cx.read(&r::MIN_BACKLASH_UM, p, g.min_backlash_um)? * 1e-6,
        gears: [pinion, wheel],
        constants: Default::default(),
        paper_model: true,
    };
    geometry::mesh(&pair).map_err(|e| place(e, p, ""))?;
    Ok(pair)
}

/// The coating of a pair's teeth (`gear_pair.….coating`).
fn coating(cx: &Cx, p: &KeyPath, c: CoatingSpec) -> Result<Coating, SpecError> {
    let cp = p.key(r::COATING);
    Ok(Coating {
        thickness_m: cx.read(&r::THICKNESS_UM, &cp, c.thickness_um)? * 1e-6,
        alpha_per_k: cx.read(&r::ALPHA_PER_K, &cp, c.alpha_per_k)?,
        poisson: cx.read(&r::POISSON, &cp, c.poisson)?,
    })
}

/// The module and pressure angle a pair's gears are cut with.
#[derive(Clone, Copy)]
struct Cutter {
    module_m: f64,
    alpha0: f64,
}

/// One gear (`which`, `pinion` or `wheel`, of the pair at `p`): its teeth, radii,
/// tooth thickness, nodes from the bore to the base circle, material and bore fit.
fn gear(
    cx: &Cx,
    p: &KeyPath,
    which: &'static str,
    raw: GearSpec,
    cutter: Cutter,
    nodes: &[DiffusionNode],
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
) -> Result<Gear, SpecError> {
    let gp = &p.key(which);
    let Cutter { module_m, alpha0 } = cutter;
    let teeth = geometry::teeth(raw.teeth).map_err(|e| place(e, gp, ""))?;
    let shift = cx.read(&r::PROFILE_SHIFT, gp, raw.profile_shift)?;
    let r_ref = module_m * teeth as f64 / 2.0;
    let r_b = r_ref * alpha0.cos();
    let tip = cx.read(&r::TIP_RADIUS_MM, gp, raw.tip_radius_mm)? * 1e-3;
    let root = cx.read(&r::ROOT_RADIUS_MM, gp, raw.root_radius_mm)? * 1e-3;
    let bore = cx.read(&r::BORE_RADIUS_MM, gp, raw.bore_radius_mm)? * 1e-3;
    geometry::radii(r_b, tip, root, bore).map_err(|e| place(e, gp, ""))?;
    let (thickness, tkey) = tooth_thickness(cx, gp, &raw, cutter, shift)?;
    geometry::tooth(module_m, alpha0, thickness, r_ref, r_b, tip)
        .map_err(|e| place(e, gp, tkey))?;
    let (node_ids, radii) = gear_nodes(cx, gp, &raw.nodes, nodes, diffusion, bore, r_b)?;
    let material = disc_material(cx, &gp.key(r::MATERIAL), raw.material)?;
    let shaft_node = match &raw.shaft_node {
        Some(n) => Some(diffusion(&gp.key("shaft_node"), n)?),
        None => None,
    };
    let fit = match raw.bore_fit {
        None | Some(BoreFitName::Free) => BoreFit::Free,
        Some(BoreFitName::Rigid) => BoreFit::Rigid,
        Some(BoreFitName::Elastic) => {
            let shaft = raw.shaft_material.ok_or_else(|| {
                cx.err(
                    gp,
                    format!("an elastic bore fit needs `{}`", r::SHAFT_MATERIAL),
                )
            })?;
            if shaft_node.is_none() {
                return Err(cx.err(
                    gp,
                    "an elastic bore fit needs `shaft_node` (the shaft's temperature)",
                ));
            }
            let sm = disc_material(cx, &gp.key(r::SHAFT_MATERIAL), shaft)?;
            BoreFit::Elastic {
                interference_m: cx.read(
                    &r::INTERFERENCE_UM,
                    gp,
                    raw.interference_um.unwrap_or(0.0),
                )? * 1e-6,
                shaft_youngs_modulus_pa: sm.youngs_modulus_pa,
                shaft_poisson: sm.poisson,
                shaft_strain: sm.strain,
            }
        }
    };
    Ok(Gear {
        name: which.to_string(),
        teeth,
        profile_shift: shift,
        tip_radius_m: tip,
        root_radius_m: root,
        bore_radius_m: bore,
        tooth_thickness_m: thickness,
        material,
        fit,
        nodes: node_ids,
        node_radii_m: radii,
        shaft_node,
    })
}

/// The tooth thickness on the reference circle, from `tooth_thickness_mm` or from
/// `tooth_thinning_um` (below the profile-shifted nominal), and the key it came from.
fn tooth_thickness(
    cx: &Cx,
    gp: &KeyPath,
    raw: &GearSpec,
    cutter: Cutter,
    shift: f64,
) -> Result<(f64, &'static str), SpecError> {
    let Cutter { module_m, alpha0 } = cutter;
    let (given, thinning) = (&r::TOOTH_THICKNESS_MM, &r::TOOTH_THINNING_UM);
    Ok(match (raw.tooth_thickness_mm, raw.tooth_thinning_um) {
        (Some(s), None) => (cx.positive(&given.key(gp), s)? * 1e-3, given.name),
        (None, Some(t)) => {
            let t = cx.read(thinning, gp, t)?;
            (
                shifted_tooth_thickness(module_m, shift, alpha0) - t * 1e-6,
                thinning.name,
            )
        }
        _ => {
            return Err(cx.err(
                gp,
                format!(
                    "give exactly one of `{}` or `{}`",
                    given.name, thinning.name
                ),
            ));
        }
    })
}

/// A gear's nodes (`names`, at `gp.nodes`): 2 … MAX_GEAR_NODES diffusion nodes with
/// radii increasing from the bore (`bore`) to the base circle (`r_b`); their indices
/// and radii.
fn gear_nodes(
    cx: &Cx,
    gp: &KeyPath,
    names: &[String],
    nodes: &[DiffusionNode],
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
    bore: f64,
    r_b: f64,
) -> Result<(Vec<usize>, Vec<f64>), SpecError> {
    let np = gp.key(NODES);
    if names.len() < 2 || names.len() > MAX_GEAR_NODES {
        return Err(cx.err(
            &np,
            format!("list 2 … {MAX_GEAR_NODES} nodes from the bore to the base circle"),
        ));
    }
    let mut node_ids = Vec::new();
    let mut radii: Vec<f64> = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let id = diffusion(&np.at(k), name)?;
        let r = nodes[id].radius_m.ok_or_else(|| {
            cx.err(
                &np.at(k),
                format!(
                    "node `{name}` needs `{}` to be part of a gear profile",
                    r::RADIUS_MM.name
                ),
            )
        })?;
        geometry::next_node(k, radii.last().copied(), r).map_err(|e| place(e, gp, ""))?;
        node_ids.push(id);
        radii.push(r);
    }
    geometry::node_ends(&radii, bore, r_b).map_err(|e| place(e, gp, ""))?;
    Ok((node_ids, radii))
}

/// How the centre distance moves (`gear_pair.….center_distance`): fixed, or with a
/// housing node's strain.
fn center_distance(
    cx: &Cx,
    p: &KeyPath,
    spec: Option<CenterDistanceSpec>,
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
) -> Result<CenterDistance, SpecError> {
    Ok(match spec {
        None => CenterDistance::Fixed,
        Some(c) => {
            let cp = p.key(r::CENTER_DISTANCE);
            match c.follows {
                Follows::Fixed => CenterDistance::Fixed,
                Follows::Housing => {
                    let node_name = c
                        .node
                        .as_deref()
                        .ok_or_else(|| cx.err(&cp, "needs `node`: the housing node"))?;
                    CenterDistance::Housing {
                        node: diffusion(&cp.key("node"), node_name)?,
                        strain: strain_law(
                            cx,
                            &cp,
                            StrainKeys {
                                alpha: c.alpha_per_k,
                                dalpha: c.dalpha_dt_per_k2,
                                poly: c.strain_polynomial,
                                alpha_poly: c.alpha_polynomial,
                                table: c.strain_table,
                            },
                        )?,
                    }
                }
            }
        }
    })
}

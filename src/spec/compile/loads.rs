//! `[[sun]]`, `[[albedo]]`, `[[earth_ir]]`, `[[dissipation]]`: loads on nodes.

use super::*;
use crate::spec::registry::{self as r, Field};

/// The load sections of a spec, in the order their loads are compiled.
pub(super) struct LoadSections {
    pub(super) sun: Vec<SunSpec>,
    pub(super) albedo: Vec<AlbedoSpec>,
    pub(super) earth_ir: Vec<EarthIrSpec>,
    pub(super) dissipation: Vec<DissipationSpec>,
}

/// The loads (`[[sun]]`, `[[albedo]]`, `[[earth_ir]]`, `[[dissipation]]`, in that
/// order) and where each element landed among them ([`Bindings`]). Earth-facing loads
/// take `view_factor_default` ((R/(R+h))²) unless they give one.
pub(super) fn loads(
    cx: &Cx,
    keys: &ElementKeys,
    table: &NodeTable,
    raw: LoadSections,
    modes: &[Mode],
    view_factor_default: f64,
) -> Result<(Vec<Load>, Bindings), SpecError> {
    let diffusion = |p: &KeyPath, name: &str| table.diffusion(cx, p, name);
    let mut loads = Vec::new();
    let load_name = |given: Option<String>, kind: &str, node: &str, i: usize| {
        given.unwrap_or_else(|| {
            format!(
                "{kind}{}.{node}",
                if i == 0 {
                    String::new()
                } else {
                    format!("{i}")
                }
            )
        })
    };
    // Where each load element of the spec lands among the compiled loads.
    let mut bindings = Bindings::default();
    for (i, s) in raw.sun.into_iter().enumerate() {
        let p = KeyPath::new("sun").elem(i, &keys.sun[i]);
        let node = diffusion(&p.key("node"), &s.node)?;
        let aa = cx.product(
            &p,
            (s.absorptivity_area_m2, &r::ABSORPTIVITY_AREA_M2),
            (s.absorptivity, &r::ABSORPTIVITY),
            s.area_m2,
        )?;
        let incidence = s.incidence.unwrap_or(Incidence::Tracking);
        bindings.sun.push(loads.len());
        loads.push(Load {
            name: load_name(s.name, "sun", &s.node, i),
            node,
            kind: LoadKind::Sun {
                absorptivity_area_m2: aa,
                incidence,
            },
        });
    }
    // Earth-facing loads: an area product and a view factor, (R/(R+h))² by default.
    let earth_face = |p: &KeyPath,
                      product: (Option<f64>, &Field),
                      fraction: (Option<f64>, &Field),
                      area: Option<f64>,
                      vf: Option<f64>| {
        let aa = cx.product(p, product, fraction, area)?;
        let vf = cx.read(&r::VIEW_FACTOR, p, vf.unwrap_or(view_factor_default))?;
        Ok::<_, SpecError>((aa, vf))
    };
    for (i, s) in raw.albedo.into_iter().enumerate() {
        let p = KeyPath::new("albedo").elem(i, &keys.albedo[i]);
        let node = diffusion(&p.key("node"), &s.node)?;
        let (aa, vf) = earth_face(
            &p,
            (s.absorptivity_area_m2, &r::ABSORPTIVITY_AREA_M2),
            (s.absorptivity, &r::ABSORPTIVITY),
            s.area_m2,
            s.view_factor,
        )?;
        bindings.albedo.push(loads.len());
        loads.push(Load {
            name: load_name(s.name, "albedo", &s.node, i),
            node,
            kind: LoadKind::Albedo {
                absorptivity_area_m2: aa,
                view_factor: vf,
            },
        });
    }
    for (i, s) in raw.earth_ir.into_iter().enumerate() {
        let p = KeyPath::new("earth_ir").elem(i, &keys.earth_ir[i]);
        let node = diffusion(&p.key("node"), &s.node)?;
        let (ea, vf) = earth_face(
            &p,
            (s.emissivity_area_m2, &r::EMISSIVITY_AREA_M2),
            (s.emissivity, &r::EMISSIVITY),
            s.area_m2,
            s.view_factor,
        )?;
        bindings.earth_ir.push(loads.len());
        loads.push(Load {
            name: load_name(s.name, "earth_ir", &s.node, i),
            node,
            kind: LoadKind::EarthIr {
                emissivity_area_m2: ea,
                view_factor: vf,
            },
        });
    }
    for (i, s) in raw.dissipation.into_iter().enumerate() {
        let p = KeyPath::new("dissipation").elem(i, &keys.dissipation[i]);
        let node = diffusion(&p.key("node"), &s.node)?;
        let field = &r::DISSIPATION_POWER_W;
        let power = cx.profile(&field.key(&p), s.power_w, &|pp, v| {
            cx.quantity(field.quantity, pp, v)
        })?;
        let when = match s.when {
            None | Some(Schedule::Always) => When::Always,
            Some(Schedule::Sunlit) => When::Sunlit,
            Some(Schedule::Eclipse) => When::Eclipse,
            Some(Schedule::Mode(m)) => {
                When::Mode(modes.iter().position(|x| x.name == m).ok_or_else(|| {
                    cx.err(
                    &p.key("when"),
                    format!(
                        "`{m}` is neither always, sunlit, eclipse nor a mode defined with [[mode]]"
                    ),
                )
                })?)
            }
        };
        bindings.dissipation.push(loads.len());
        loads.push(Load {
            name: load_name(s.name, "dissipation", &s.node, i),
            node,
            kind: LoadKind::Dissipation {
                power_w: power,
                when,
            },
        });
    }
    Ok((loads, bindings))
}

//! The vocabulary of `shared/spec/physics.md` §6 as model extensions: every effect, on
//! every node, conductor, load, gear or channel the scenario has, is a [`Candidate`]:
//! the scenario with the effect added (a real element of the scenario: a heater with a
//! thermostat, a dissipation with a schedule, albedo and Earth-IR loads, a centre
//! distance that follows a node, α(T), an elastic bore fit, a sensor's lag or offset, a
//! scaled number) and its physical parameters, written through key paths.

use serde::Serialize;

use crate::model::Model;
use crate::spec::keys::quote_key;
use crate::spec::{
    AlbedoSpec, CenterDistanceSpec, DissipationSpec, EarthIrSpec, HeaterSpec, ProfileSpec,
    ScenarioSpec,
};

/// The effect ids of `physics.md` §6.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    EarthAlbedoIr,
    HeaterThermostat,
    InternalDissipation,
    HousingExpansion,
    CteTemperature,
    BoreFit,
    SensorLag,
    SensorOffset,
    AbsorptivityScale,
    ConductanceScale,
    CteScale,
}

/// What an effect is: physics the model left out, a sensor's own behaviour, or a
/// calibration of a number the model has. Serialised as "physics", "sensor",
/// "calibration".
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    Physics,
    Sensor,
    Calibration,
}

impl EffectKind {
    pub fn as_str(self) -> &'static str {
        match self {
            EffectKind::Physics => "physics",
            EffectKind::Sensor => "sensor",
            EffectKind::Calibration => "calibration",
        }
    }
}

impl std::fmt::Display for EffectKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

impl Effect {
    pub const ALL: [Effect; 11] = [
        Effect::EarthAlbedoIr,
        Effect::HeaterThermostat,
        Effect::InternalDissipation,
        Effect::HousingExpansion,
        Effect::CteTemperature,
        Effect::BoreFit,
        Effect::SensorLag,
        Effect::SensorOffset,
        Effect::AbsorptivityScale,
        Effect::ConductanceScale,
        Effect::CteScale,
    ];

    pub fn id(self) -> &'static str {
        match self {
            Effect::EarthAlbedoIr => "earth_albedo_ir",
            Effect::HeaterThermostat => "heater_thermostat",
            Effect::InternalDissipation => "internal_dissipation",
            Effect::HousingExpansion => "housing_expansion",
            Effect::CteTemperature => "cte_temperature",
            Effect::BoreFit => "bore_fit",
            Effect::SensorLag => "sensor_lag",
            Effect::SensorOffset => "sensor_offset",
            Effect::AbsorptivityScale => "absorptivity_scale",
            Effect::ConductanceScale => "conductance_scale",
            Effect::CteScale => "cte_scale",
        }
    }

    pub fn kind(self) -> EffectKind {
        match self {
            Effect::SensorLag | Effect::SensorOffset => EffectKind::Sensor,
            Effect::AbsorptivityScale | Effect::ConductanceScale | Effect::CteScale => {
                EffectKind::Calibration
            }
            _ => EffectKind::Physics,
        }
    }

    pub fn from_id(id: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.id() == id)
    }
}

/// One fitted parameter of a candidate, in report units.
#[derive(Debug, Clone)]
pub struct ParamDef {
    /// Report name (`power_w`, `on_c`, `scale`, …).
    pub name: &'static str,
    pub lower: f64,
    pub upper: f64,
    /// Finite-difference step.
    pub step: f64,
}

/// A key path written as a linear function of the parameters:
/// value = constant + Σ coefficient · θ\[index\].
#[derive(Debug, Clone)]
pub struct Setter {
    pub path: String,
    pub constant: f64,
    pub terms: Vec<(usize, f64)>,
}

impl ParamDef {
    pub fn new(name: &'static str, lower: f64, upper: f64, step: f64) -> ParamDef {
        ParamDef {
            name,
            lower,
            upper,
            step,
        }
    }
}

impl Setter {
    /// The key path set to `scale` × parameter `index`.
    pub fn scaled(path: String, index: usize, scale: f64) -> Setter {
        Setter {
            path,
            constant: 0.0,
            terms: vec![(index, scale)],
        }
    }
}

/// The key-path values of `setters` for parameters `theta`.
pub fn values(setters: &[Setter], theta: &[f64]) -> Vec<(String, f64)> {
    setters
        .iter()
        .map(|s| {
            let v = s.constant + s.terms.iter().map(|&(i, c)| c * theta[i]).sum::<f64>();
            (s.path.clone(), v)
        })
        .collect()
}

/// An effect on one target, ready to be fitted.
#[derive(Clone)]
pub struct Candidate {
    pub effect: Effect,
    /// What it acts on, as the report names it.
    pub node: Option<String>,
    pub channel: Option<String>,
    pub conductor: Option<String>,
    pub load: Option<String>,
    pub gear_pair: Option<String>,
    pub gear: Option<String>,
    /// Dissipation schedule: `always`, `sunlit`, `eclipse` or a mode.
    pub schedule: Option<String>,
    pub params: Vec<ParamDef>,
    pub setters: Vec<Setter>,
    /// Start points for the cheap ranking (the best one starts the fit).
    pub starts: Vec<Vec<f64>>,
    /// Parameters at which the effect vanishes (the baseline), when there are such:
    /// the ranking then also projects the residual onto the line from there through
    /// each start point (a one-step linearised fit).
    pub null: Option<Vec<f64>>,
    /// The elements the effect adds to the scenario (none for a change of existing
    /// numbers); applied in order to build a model with several effects.
    pub edits: Vec<Edit>,
}

/// A change of the scenario's elements.
pub type Edit = std::sync::Arc<dyn Fn(&mut ScenarioSpec) + Send + Sync>;

impl Candidate {
    /// A short label: `heater_thermostat on housing`.
    pub fn label(&self) -> String {
        let on = [
            &self.node,
            &self.channel,
            &self.conductor,
            &self.load,
            &self.gear,
            &self.gear_pair,
        ]
        .into_iter()
        .flatten()
        .next()
        .cloned()
        .unwrap_or_default();
        match &self.schedule {
            Some(s) => format!("{} on {on} ({s})", self.effect.id()),
            None => format!("{} on {on}", self.effect.id()),
        }
    }

    /// The key-path values for parameters `theta`.
    pub fn values(&self, theta: &[f64]) -> Vec<(String, f64)> {
        values(&self.setters, theta)
    }

    /// Parameters as the report gives them (derived ones added: a heater's `off_c`).
    pub fn report_params(
        &self,
        theta: &[f64],
        cov: Option<&[Vec<f64>]>,
    ) -> Vec<(String, f64, f64)> {
        let se = |i: usize| cov.map_or(f64::NAN, |c| c[i][i].max(0.0).sqrt());
        let mut out: Vec<(String, f64, f64)> = self
            .params
            .iter()
            .enumerate()
            .filter(|(_, p)| p.name != "hysteresis_k")
            .map(|(i, p)| (p.name.to_string(), theta[i], se(i)))
            .collect();
        if self.effect == Effect::HeaterThermostat {
            // off = on + hysteresis; var = var(on) + var(h) + 2 cov(on, h).
            let v = cov.map_or(f64::NAN, |c| {
                (c[1][1] + c[2][2] + 2.0 * c[1][2]).max(0.0).sqrt()
            });
            out.push(("off_c".into(), theta[1] + theta[2], v));
        }
        out
    }
}

/// What the data say before any fit, used to start candidates that a cost surface
/// alone would not find: per diffusion node, the baseline temperature (K) at which a
/// warming residual starts in the cold phase (a thermostat's set point).
#[derive(Debug, Clone, Default)]
pub struct Hints {
    pub heater_on_k: Vec<Option<f64>>,
}

const C_TO_K: f64 = 273.15;

/// Every candidate of the vocabulary on every element of `model` that the recording's
/// `channels` (sensor columns) can see.
pub fn candidates(model: &Model, channels: &[(String, bool)], hints: &Hints) -> Vec<Candidate> {
    let spec = model.spec();
    let gear_nodes: Vec<&str> = spec
        .gear_pair
        .iter()
        .flat_map(|g| g.pinion.nodes.iter().chain(&g.wheel.nodes))
        .map(|s| s.as_str())
        .collect();
    let mut out = Vec::new();
    let blank = |effect: Effect, edit: Option<Edit>| Candidate {
        effect,
        node: None,
        channel: None,
        conductor: None,
        load: None,
        gear_pair: None,
        gear: None,
        schedule: None,
        params: Vec::new(),
        setters: Vec::new(),
        starts: Vec::new(),
        null: None,
        edits: edit.into_iter().collect(),
    };
    let path_of = |m: &Model, prefix: &str, name: &str, key: &str| -> Option<String> {
        let p = format!("{prefix}.{}.{key}", quote_key(name));
        m.get(&p).ok().map(|_| p)
    };
    let with = |edit: &Edit| -> Option<Model> {
        let mut m = model.clone();
        m.modify(|s| edit(s)).ok().map(|_| m)
    };

    for (ni, node) in spec.node.iter().enumerate() {
        let n = node.name.clone();
        // Earth albedo and IR on the node, referred to the areas the node already
        // shows the Sun and space (or 0.01 m² where it shows neither).
        let sun_aa: f64 = spec
            .sun
            .iter()
            .filter(|s| s.node == n)
            .map(|s| {
                s.absorptivity_area_m2
                    .unwrap_or(s.absorptivity.unwrap_or(0.0) * s.area_m2.unwrap_or(0.0))
            })
            .sum();
        let space_ea: f64 = spec
            .radiation
            .iter()
            .filter(|r| r.between.contains(&n) && r.between.iter().any(|b| b == "space"))
            .map(|r| {
                r.emissivity_area_m2
                    .unwrap_or(r.emissivity.unwrap_or(0.0) * r.area_m2.unwrap_or(0.0))
            })
            .sum();
        let a_ref = if sun_aa > 0.0 { sun_aa } else { 0.01 };
        let e_ref = if space_ea > 0.0 { space_ea } else { 0.01 };
        let env_albedo = spec
            .environment
            .albedo
            .unwrap_or(crate::constants::EARTH_ALBEDO);
        let env_ir = spec
            .environment
            .earth_ir_w_per_m2
            .unwrap_or(crate::constants::EARTH_IR_W_PER_M2);
        let (an, en) = (
            format!("diagnose.albedo.{n}"),
            format!("diagnose.earth_ir.{n}"),
        );
        if env_albedo > 0.0 && env_ir > 0.0 {
            let edit: Edit = {
                let (n, an, en) = (n.clone(), an.clone(), en.clone());
                std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                    s.albedo.push(AlbedoSpec {
                        name: Some(an.clone()),
                        node: n.clone(),
                        absorptivity_area_m2: Some(a_ref),
                        absorptivity: None,
                        area_m2: None,
                        view_factor: None,
                    });
                    s.earth_ir.push(EarthIrSpec {
                        name: Some(en.clone()),
                        node: n.clone(),
                        emissivity_area_m2: Some(e_ref),
                        emissivity: None,
                        area_m2: None,
                        view_factor: None,
                    });
                })
            };
            let base = with(&edit);
            if let Some(base) = base {
                let pa = path_of(&base, "albedo", &an, "absorptivity_area_m2");
                let pe = path_of(&base, "earth_ir", &en, "emissivity_area_m2");
                if let (Some(pa), Some(pe)) = (pa, pe) {
                    let mut c = blank(Effect::EarthAlbedoIr, Some(edit.clone()));
                    c.node = Some(n.clone());
                    c.params = vec![
                        ParamDef::new("albedo", 1e-4, 1.0, 0.005),
                        ParamDef::new("earth_ir_w_per_m2", 0.01, 500.0, 2.0),
                    ];
                    c.setters = vec![
                        Setter::scaled(pa, 0, a_ref / env_albedo),
                        Setter::scaled(pe, 1, e_ref / env_ir),
                    ];
                    c.starts = vec![
                        vec![0.15, 0.01],
                        vec![1e-4, 100.0],
                        vec![0.15, 100.0],
                        vec![0.3, 237.0],
                    ];
                    c.null = Some(vec![0.0, 0.0]);
                    out.push(c);
                }
            }
        }
        // A heater with a thermostat on the node (reading the node).
        if let Some(on_k) = hints.heater_on_k.get(ni).copied().flatten() {
            let hn = format!("diagnose.heater.{n}");
            let edit: Edit = {
                let (n, hn) = (n.clone(), hn.clone());
                std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                    s.heater.push(HeaterSpec {
                        name: Some(hn.clone()),
                        node: n.clone(),
                        sensor_node: None,
                        power_w: 1.0,
                        on_k,
                        off_k: on_k + 5.0,
                    })
                })
            };
            let base = with(&edit);
            if let Some(base) = base {
                let pp = path_of(&base, "heater", &hn, "power_w");
                let pon = path_of(&base, "heater", &hn, "on_k");
                let poff = path_of(&base, "heater", &hn, "off_k");
                if let (Some(pp), Some(pon), Some(poff)) = (pp, pon, poff) {
                    let on_c = on_k - C_TO_K;
                    let mut c = blank(Effect::HeaterThermostat, Some(edit.clone()));
                    c.node = Some(n.clone());
                    c.params = vec![
                        ParamDef::new("power_w", 0.01, 1000.0, 0.02),
                        ParamDef::new("on_c", on_c - 30.0, on_c + 30.0, 0.05),
                        ParamDef::new("hysteresis_k", 0.1, 50.0, 0.05),
                    ];
                    c.setters = vec![
                        Setter::scaled(pp, 0, 1.0),
                        Setter {
                            path: pon,
                            constant: C_TO_K,
                            terms: vec![(1, 1.0)],
                        },
                        Setter {
                            path: poff,
                            constant: C_TO_K,
                            terms: vec![(1, 1.0), (2, 1.0)],
                        },
                    ];
                    for p in [1.0, 3.0, 8.0] {
                        for h in [2.0, 5.0] {
                            for d in [-1.0, 0.0] {
                                c.starts.push(vec![p, on_c + d, h]);
                            }
                        }
                    }
                    c.null = Some(vec![0.0, on_c, 5.0]);
                    out.push(c);
                }
            }
        }
        // Internal dissipation, always or on a schedule.
        let mut whens = vec!["always".to_string(), "sunlit".into(), "eclipse".into()];
        whens.extend(spec.mode.iter().map(|m| m.name.clone()));
        for when in whens {
            let dn = format!("diagnose.dissipation.{n}.{when}");
            let edit: Edit = {
                let (n, dn, when) = (n.clone(), dn.clone(), when.clone());
                std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                    s.dissipation.push(DissipationSpec {
                        name: Some(dn.clone()),
                        node: n.clone(),
                        power_w: ProfileSpec::Constant(0.5),
                        when: Some(when.clone()),
                    })
                })
            };
            let base = with(&edit);
            let Some(base) = base else { continue };
            let Some(pp) = path_of(&base, "dissipation", &dn, "power_w") else {
                continue;
            };
            let mut c = blank(Effect::InternalDissipation, Some(edit.clone()));
            c.node = Some(n.clone());
            c.schedule = Some(when);
            c.params = vec![ParamDef::new("power_w", 0.0, 1000.0, 0.02)];
            c.setters = vec![Setter::scaled(pp, 0, 1.0)];
            c.starts = vec![vec![0.25], vec![1.0], vec![4.0]];
            c.null = Some(vec![0.0]);
            out.push(c);
        }
        // The centre distance of a gear pair follows this node.
        if !gear_nodes.contains(&n.as_str()) {
            for (gi, gp) in spec.gear_pair.iter().enumerate() {
                if gp
                    .center_distance
                    .as_ref()
                    .is_some_and(|c| c.follows != "fixed")
                {
                    continue;
                }
                let pair = pair_name(spec, gi);
                let edit: Edit = {
                    let (n,) = (n.clone(),);
                    std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                        s.gear_pair[gi].center_distance = Some(CenterDistanceSpec {
                            follows: "housing".into(),
                            node: Some(n.clone()),
                            alpha_per_k: Some(5e-6),
                            dalpha_dt_per_k2: None,
                            strain_polynomial: None,
                            alpha_polynomial: None,
                            strain_table: None,
                        })
                    })
                };
                let base = with(&edit);
                let Some(base) = base else { continue };
                let p = format!("gear_pair.{}.center_distance.alpha_per_k", quote_key(&pair));
                if base.get(&p).is_err() {
                    continue;
                }
                let mut c = blank(Effect::HousingExpansion, Some(edit.clone()));
                c.node = Some(n.clone());
                c.gear_pair = Some(pair);
                c.params = vec![ParamDef::new("alpha_per_k", -2e-5, 1e-4, 1e-7)];
                c.setters = vec![Setter::scaled(p, 0, 1.0)];
                c.starts = vec![vec![2e-6], vec![8e-6], vec![2e-5]];
                c.null = Some(vec![0.0]);
                out.push(c);
            }
        }
    }

    // Gear-pair effects: α(T), a bore fit, a scaled α.
    for (gi, gp) in spec.gear_pair.iter().enumerate() {
        let pair = pair_name(spec, gi);
        let q = quote_key(&pair);
        let linear = |m: &crate::spec::MaterialSpec| {
            m.alpha_per_k.is_some()
                && m.strain_polynomial.is_none()
                && m.alpha_polynomial.is_none()
                && m.strain_table.is_none()
        };
        if linear(&gp.pinion.material) && linear(&gp.wheel.material) {
            let a1 = gp.pinion.material.alpha_per_k.unwrap();
            let a2 = gp.wheel.material.alpha_per_k.unwrap();
            if gp.pinion.material.dalpha_dt_per_k2.is_none()
                && gp.wheel.material.dalpha_dt_per_k2.is_none()
            {
                let edit: Edit = {
                    std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                        s.gear_pair[gi].pinion.material.dalpha_dt_per_k2 = Some(0.0);
                        s.gear_pair[gi].wheel.material.dalpha_dt_per_k2 = Some(0.0);
                    })
                };
                let base = with(&edit);
                if let Some(base) = base {
                    let p1 = format!("gear_pair.{q}.pinion.material.dalpha_dt_per_k2");
                    let p2 = format!("gear_pair.{q}.wheel.material.dalpha_dt_per_k2");
                    if base.get(&p1).is_ok() && base.get(&p2).is_ok() {
                        let mut c = blank(Effect::CteTemperature, Some(edit.clone()));
                        c.gear_pair = Some(pair.clone());
                        c.params = vec![ParamDef::new("dalpha_dt_per_k2", -1e-6, 1e-6, 1e-9)];
                        c.setters = vec![Setter::scaled(p1, 0, 1.0), Setter::scaled(p2, 0, 1.0)];
                        c.starts = vec![vec![-5e-8], vec![-1.5e-8], vec![1.5e-8], vec![5e-8]];
                        c.null = Some(vec![0.0]);
                        out.push(c);
                    }
                }
            }
            let mut c = blank(Effect::CteScale, None);
            c.gear_pair = Some(pair.clone());
            c.params = vec![ParamDef::new("scale", 0.1, 5.0, 0.005)];
            c.setters = vec![
                Setter::scaled(format!("gear_pair.{q}.pinion.material.alpha_per_k"), 0, a1),
                Setter::scaled(format!("gear_pair.{q}.wheel.material.alpha_per_k"), 0, a2),
            ];
            c.starts = vec![vec![0.8], vec![0.9], vec![1.1], vec![1.25]];
            c.null = Some(vec![1.0]);
            out.push(c);
        }
        for (which, g) in [("pinion", &gp.pinion), ("wheel", &gp.wheel)] {
            if !matches!(g.bore_fit.as_deref(), None | Some("free")) {
                continue;
            }
            // The shaft: the node outside the gear that its bore node conducts to.
            let bore = &g.nodes[0];
            let shaft = spec.conductor.iter().find_map(|c| {
                let other = match (c.between.first(), c.between.get(1)) {
                    (Some(a), Some(b)) if a == bore => b,
                    (Some(a), Some(b)) if b == bore => a,
                    _ => return None,
                };
                (!gear_nodes.contains(&other.as_str())
                    && spec.node.iter().any(|n| n.name == *other))
                .then(|| other.clone())
            });
            let Some(shaft) = shaft else { continue };
            let edit: Edit = {
                let (shaft,) = (shaft.clone(),);
                std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                    let gs = if which == "pinion" {
                        &mut s.gear_pair[gi].pinion
                    } else {
                        &mut s.gear_pair[gi].wheel
                    };
                    gs.bore_fit = Some("elastic".into());
                    gs.shaft_node = Some(shaft.clone());
                    gs.shaft_material = Some(gs.material.clone());
                    gs.interference_um = Some(5.0);
                })
            };
            let base = with(&edit);
            let Some(base) = base else { continue };
            let p = format!("gear_pair.{q}.{which}.interference_um");
            if base.get(&p).is_err() {
                continue;
            }
            let mut c = blank(Effect::BoreFit, Some(edit.clone()));
            c.gear_pair = Some(pair.clone());
            c.gear = Some(format!("{pair}.{which}"));
            c.node = Some(shaft.clone());
            c.params = vec![ParamDef::new("interference_um", 0.0, 500.0, 0.2)];
            c.setters = vec![Setter::scaled(p, 0, 1.0)];
            c.starts = vec![vec![2.0], vec![10.0], vec![40.0]];
            out.push(c);
        }
    }

    // Sensors: a lag or an offset on any temperature channel of the recording.
    for (col, is_temp) in channels {
        if !is_temp {
            continue;
        }
        let q = quote_key(col);
        let (pt, po) = (format!("sensor.{q}.tau_s"), format!("sensor.{q}.offset_k"));
        let (Ok(tau0), Ok(off0)) = (model.get(&pt), model.get(&po)) else {
            continue;
        };
        let mut c = blank(Effect::SensorLag, None);
        c.channel = Some(col.clone());
        c.params = vec![ParamDef::new("tau_s", 0.0, 7200.0, 1.0)];
        c.setters = vec![Setter {
            path: pt,
            constant: tau0,
            terms: vec![(0, 1.0)],
        }];
        c.starts = vec![vec![20.0], vec![60.0], vec![200.0], vec![600.0]];
        c.null = Some(vec![0.0]);
        out.push(c);
        let mut c = blank(Effect::SensorOffset, None);
        c.channel = Some(col.clone());
        c.params = vec![ParamDef::new("offset_k", -50.0, 50.0, 0.05)];
        c.setters = vec![Setter {
            path: po,
            constant: off0,
            terms: vec![(0, 1.0)],
        }];
        c.starts = vec![vec![-0.5], vec![0.5]];
        c.null = Some(vec![0.0]);
        out.push(c);
    }

    // Calibration: a sun load's absorptivity, one conductor.
    for p in model.params() {
        let (effect, what) = if p.path.starts_with("sun.")
            && (p.path.ends_with(".absorptivity") || p.path.ends_with(".absorptivity_area_m2"))
        {
            (Effect::AbsorptivityScale, "load")
        } else if (p.path.starts_with("conductor.") && p.path.ends_with(".conductance_w_per_k"))
            || (p.path.starts_with("radiation.")
                && (p.path.ends_with(".emissivity_area_m2") || p.path.ends_with(".emissivity")))
        {
            (Effect::ConductanceScale, "conductor")
        } else {
            continue;
        };
        if p.value.is_nan() || p.value <= 0.0 {
            continue;
        }
        let name = element_of(&p.path);
        let mut c = blank(effect, None);
        let upper = if p.path.ends_with(".absorptivity") || p.path.ends_with(".emissivity") {
            1.0 / p.value
        } else {
            20.0
        };
        if what == "load" {
            c.load = Some(name);
            c.params = vec![ParamDef::new("scale", 0.05, upper, 0.003)];
            c.starts = vec![
                vec![0.8],
                vec![0.9],
                vec![1.1f64.min(upper)],
                vec![1.25f64.min(upper)],
            ];
        } else {
            c.conductor = Some(name);
            c.params = vec![ParamDef::new("scale", 0.02, upper, 0.01)];
            c.starts = vec![
                vec![0.3],
                vec![0.6],
                vec![1.5f64.min(upper)],
                vec![3.0f64.min(upper)],
            ];
        }
        c.setters = vec![Setter::scaled(p.path.clone(), 0, p.value)];
        c.null = Some(vec![1.0]);
        out.push(c);
    }
    out
}

fn pair_name(spec: &ScenarioSpec, i: usize) -> String {
    spec.gear_pair[i].name.clone().unwrap_or_else(|| {
        if i == 0 {
            "mesh".to_string()
        } else {
            format!("mesh{i}")
        }
    })
}

/// The element name of `kind.name.key` (name unquoted).
fn element_of(path: &str) -> String {
    match crate::spec::keys::parse_path(path) {
        Ok(parts) => match parts.get(1) {
            Some(crate::spec::keys::Part::Key(k)) => k.clone(),
            _ => path.to_string(),
        },
        Err(_) => path.to_string(),
    }
}

//! The rows of the registry: every number of a scenario file, in the order `orbitlash
//! params` lists them (gear pairs in `gear_rows.rs`), with their fast writes and
//! calibrations.

use super::{Calibration, Field, Row, ScaleFamily, Section, Slot, row};
use crate::spec::keys::ElementKeys;
use crate::spec::quantity as q;
use crate::spec::scenario::Scenario;
use crate::spec::{AttitudeMode, ScenarioSpec, SpecError};
use crate::thermal::LoadKind;

fields! {
    START_OFFSET_S = "start_offset_s", START_OFFSET_S;
    ALTITUDE_M = "altitude_m", ALTITUDE_M;
    EARTH_RADIUS_M = "earth_radius_m", EARTH_RADIUS_M;
    MU_M3_PER_S2 = "mu_m3_per_s2", MU_M3_PER_S2;
    ORBIT_ANGLE_AT_START_DEG = "orbit_angle_at_start_deg", ORBIT_ANGLE_AT_START_DEG;
    BETA_DEG = "beta_deg", BETA_DEG;
    SOLAR_FLUX_W_PER_M2 = "solar_flux_w_per_m2", SOLAR_FLUX_W_PER_M2;
    SPACE_SINK_K = "space_sink_k", SPACE_SINK_K;
    ALBEDO = "albedo", ALBEDO;
    EARTH_IR_W_PER_M2 = "earth_ir_w_per_m2", EARTH_IR_W_PER_M2;
    ORBITS = "orbits", RUN_ORBITS;
    DURATION_S = "duration_s", RUN_DURATION_S;
    DURATION_DAYS = "duration_days", RUN_DURATION_DAYS;
    OUTPUT_INTERVAL_S = "output_interval_s", OUTPUT_INTERVAL_S;
    TOLERANCE_K = "tolerance_k", TOLERANCE_K;
    MAX_STEP_S = "max_step_s", MAX_STEP_S;
    CAPACITANCE_J_PER_K = "capacitance_j_per_k", CAPACITANCE_J_PER_K;
    INITIAL_TEMPERATURE_K = "initial_temperature_k", TEMPERATURE_K;
    RADIUS_MM = "radius_mm", NODE_RADIUS_MM;
    BOUNDARY_TEMPERATURE_K = "temperature_k", TEMPERATURE_K;
    CONDUCTANCE_W_PER_K = "conductance_w_per_k", CONDUCTANCE_W_PER_K;
    EMISSIVITY_AREA_M2 = "emissivity_area_m2", AREA_PRODUCT_M2;
    EMISSIVITY = "emissivity", EMISSIVITY;
    ABSORPTIVITY_AREA_M2 = "absorptivity_area_m2", AREA_PRODUCT_M2;
    ABSORPTIVITY = "absorptivity", ABSORPTIVITY;
    AREA_M2 = "area_m2", AREA_M2;
    VIEW_FACTOR = "view_factor", VIEW_FACTOR;
    DISSIPATION_POWER_W = "power_w", POWER_W;
    HEATER_POWER_W = "power_w", HEATER_POWER_W;
    ON_K = "on_k", HEATER_ON_K;
    OFF_K = "off_k", HEATER_OFF_K;
    YAW_DEG = "yaw_deg", YAW_DEG;
    SPIN_RATE_DEG_PER_S = "spin_rate_deg_per_s", SPIN_RATE_DEG_PER_S;
    WINDOWS_S = "windows_s", WINDOW_S;
    WINDOWS_DAYS = "windows_days", WINDOW_DAYS;
    TAU_S = "tau_s", SENSOR_TAU_S;
    OFFSET_K = "offset_k", SENSOR_OFFSET_K;
    TIME_OFFSET_S = "time_offset_s", TIME_OFFSET_S;
}

type Done = Result<(), SpecError>;

/// Scales a node's thermal mass.
const MASS: Calibration = Calibration {
    family: ScaleFamily::ThermalMass,
    first: true,
    lower: 0.2,
    upper: Some(5.0),
    step: 0.005,
    starts: &[0.5, 0.8, 1.25, 2.0],
};
/// Scales a face's emissivity.
const FACE_EMISSIVITY: Calibration = Calibration {
    family: ScaleFamily::Emissivity,
    first: true,
    lower: 0.05,
    upper: None,
    step: 0.003,
    starts: &[0.6, 0.85, 1.1, 1.25],
};
/// Scales an absorptivity (of a face: first).
const fn absorptivity(first: bool, upper: Option<f64>) -> Calibration {
    Calibration {
        family: ScaleFamily::Absorptivity,
        first,
        lower: 0.05,
        upper,
        step: 0.003,
        starts: &[0.8, 0.9, 1.1, 1.25],
    }
}
/// Scales a conductive or radiative link.
const fn link(upper: Option<f64>) -> Calibration {
    Calibration {
        family: ScaleFamily::Conductance,
        first: false,
        lower: 0.02,
        upper,
        step: 0.01,
        starts: &[0.3, 0.6, 1.5, 3.0],
    }
}
/// The largest scale of a number that is not an optical property.
const SCALE_UP_TO: Option<f64> = Some(20.0);

/// Every row, in listing order (see the module docs of `registry`).
pub(super) fn table() -> Vec<Row> {
    let mut t = Vec::new();
    orbit(&mut t);
    environment(&mut t);
    run_and_solver(&mut t);
    network(&mut t);
    area_loads(&mut t);
    dissipations_and_heaters(&mut t);
    faces_modes_sensors(&mut t);
    t
}

fn orbit(t: &mut Vec<Row>) {
    use Section::Orbit;
    let tle = |s: &ScenarioSpec| s.orbit.tle.is_some();
    t.extend([
        row(
            Orbit,
            &[],
            &START_OFFSET_S,
            "a dated run's start shifted, s",
            move |s, _| tle(s).then_some(Slot::Optional(&mut s.orbit.start_offset_s)),
        ),
        row(
            Orbit,
            &[],
            &ALTITUDE_M,
            "a circular orbit's altitude h above the spherical Earth",
            move |s, _| (!tle(s)).then_some(Slot::Optional(&mut s.orbit.altitude_m)),
        ),
        row(
            Orbit,
            &[],
            &EARTH_RADIUS_M,
            "the Earth's radius R (WGS 84)",
            |s, _| Some(Slot::Optional(&mut s.orbit.earth_radius_m)),
        ),
        row(
            Orbit,
            &[],
            &MU_M3_PER_S2,
            "the gravitational parameter μ (WGS 84); period 2π √((R+h)³/μ)",
            move |s, _| (!tle(s)).then_some(Slot::Optional(&mut s.orbit.mu_m3_per_s2)),
        ),
        row(
            Orbit,
            &[],
            &ORBIT_ANGLE_AT_START_DEG,
            "the orbit angle θ at t = 0 (θ = 0 at orbit noon)",
            move |s, _| (!tle(s)).then_some(Slot::Optional(&mut s.orbit.orbit_angle_at_start_deg)),
        ),
    ]);
}

fn environment(t: &mut Vec<Row>) {
    use Section::Environment as Env;
    t.extend([
        row(
            Env,
            &[],
            &BETA_DEG,
            "β, the Sun's angle to the orbit plane (circular orbit), *profile*",
            |s, _| Some(Slot::OptionalProfile(&mut s.environment.beta_deg)),
        )
        .fast(|s, _, sc, _| {
            if let Some(crate::spec::ProfileSpec::Constant(b)) = s.environment.beta_deg {
                sc.thermal
                    .environment
                    .circular_mut()
                    .expect("β is a key of circular orbits")
                    .beta_rad = crate::orbit::Profile::Constant(b.to_radians());
            }
            Ok(())
        }),
        row(
            Env,
            &[],
            &SOLAR_FLUX_W_PER_M2,
            "the solar flux S (with a TLE: at 1 AU), *profile*",
            |s, _| {
                Some(Slot::OptionalProfile(
                    &mut s.environment.solar_flux_w_per_m2,
                ))
            },
        )
        .fast(|s, _, sc, _| {
            if let Some(crate::spec::ProfileSpec::Constant(f)) = s.environment.solar_flux_w_per_m2 {
                match &mut sc.thermal.environment {
                    crate::orbit::Environment::Circular(c) => {
                        c.solar_flux_w_per_m2 = crate::orbit::Profile::Constant(f)
                    }
                    // a dated orbit's flux is the flux at 1 AU
                    crate::orbit::Environment::Dated(d) => d.solar_flux_1au_w_per_m2 = f,
                }
            }
            Ok(())
        }),
        row(
            Env,
            &[],
            &SPACE_SINK_K,
            "the temperature of the built-in boundary node `space`",
            |s, _| Some(Slot::Optional(&mut s.environment.space_sink_k)),
        )
        .fast(|s, _, sc, _| {
            let t = s.environment.space_sink_k.expect("written");
            *sc.thermal.environment.earth_and_space_mut().2 = t;
            // the built-in boundary `space` sits at the sink temperature
            sc.thermal.network.boundaries[0].temperature_k = crate::orbit::Profile::Constant(t);
            Ok(())
        }),
        row(
            Env,
            &[],
            &ALBEDO,
            "the Earth's albedo a, for `[[albedo]]` loads and faces",
            |s, _| Some(Slot::Optional(&mut s.environment.albedo)),
        )
        .fast(|s, _, sc, _| {
            *sc.thermal.environment.earth_and_space_mut().0 =
                s.environment.albedo.expect("written");
            Ok(())
        }),
        row(
            Env,
            &[],
            &EARTH_IR_W_PER_M2,
            "the Earth's infrared flux, for `[[earth_ir]]` loads and faces",
            |s, _| Some(Slot::Optional(&mut s.environment.earth_ir_w_per_m2)),
        )
        .fast(|s, _, sc, _| {
            *sc.thermal.environment.earth_and_space_mut().1 =
                s.environment.earth_ir_w_per_m2.expect("written");
            Ok(())
        }),
    ]);
}

fn run_and_solver(t: &mut Vec<Row>) {
    use Section::{Run, Solver};
    t.extend([
        row(
            Run,
            &[],
            &ORBITS,
            "the run's length in orbits (or `duration_s`, `duration_days`)",
            |s, _| Some(Slot::Optional(&mut s.run.orbits)),
        ),
        row(
            Run,
            &[],
            &DURATION_S,
            "the run's length in seconds",
            |s, _| Some(Slot::Optional(&mut s.run.duration_s)),
        ),
        row(
            Run,
            &[],
            &DURATION_DAYS,
            "the run's length in days",
            |s, _| Some(Slot::Optional(&mut s.run.duration_days)),
        ),
        row(
            Run,
            &[],
            &OUTPUT_INTERVAL_S,
            "the row interval of the `--csv` export",
            |s, _| Some(Slot::Optional(&mut s.run.output_interval_s)),
        ),
        row(
            Solver,
            &[],
            &TOLERANCE_K,
            "the local error allowed per step on any node",
            |s, _| Some(Slot::Optional(&mut s.solver.tolerance_k)),
        ),
        row(Solver, &[], &MAX_STEP_S, "the longest step", |s, _| {
            Some(Slot::Optional(&mut s.solver.max_step_s))
        }),
    ]);
}

/// The product of an area load or link: given, or its fraction times its area.
fn product(p: Option<f64>, fraction: Option<f64>, area: Option<f64>) -> f64 {
    p.unwrap_or_else(|| {
        fraction.expect("the fraction is given with the area")
            * area.expect("the area is given with the fraction")
    })
}

fn network(t: &mut Vec<Row>) {
    use Section::{Boundary, Conductor, Node, Radiation};
    t.extend([
        row(
            Node,
            &[],
            &CAPACITANCE_J_PER_K,
            "the node's thermal capacitance C",
            |s, e| Some(Slot::Value(&mut s.node[e].capacitance_j_per_k)),
        )
        .fast(|s, _, sc, e| {
            sc.thermal.network.nodes[e].capacitance_j_per_k = s.node[e].capacitance_j_per_k;
            Ok(())
        })
        .calibrated(MASS),
        row(
            Node,
            &[],
            &INITIAL_TEMPERATURE_K,
            "the node's temperature at t = 0",
            |s, e| Some(Slot::Value(&mut s.node[e].initial_temperature_k)),
        )
        .fast(|s, _, sc, e| {
            sc.thermal.network.nodes[e].initial_temperature_k = s.node[e].initial_temperature_k;
            Ok(())
        }),
        row(
            Node,
            &[],
            &RADIUS_MM,
            "a gear node's radius along its gear (optional)",
            |s, e| Some(Slot::Optional(&mut s.node[e].radius_mm)),
        ),
        row(
            Boundary,
            &[],
            &BOUNDARY_TEMPERATURE_K,
            "the boundary's temperature, *profile*",
            |s, e| Some(Slot::Profile(&mut s.boundary[e].temperature_k)),
        ),
        row(
            Conductor,
            &[],
            &CONDUCTANCE_W_PER_K,
            "the conductance G of the link",
            |s, e| Some(Slot::Value(&mut s.conductor[e].conductance_w_per_k)),
        )
        .fast(|s, _, sc, e| {
            sc.thermal.network.conductors[e].conductance_w_per_k =
                s.conductor[e].conductance_w_per_k;
            Ok(())
        })
        .calibrated(link(SCALE_UP_TO)),
    ]);
    let radiation_fast: super::FastFn = |s, _, sc, e| {
        let r = &s.radiation[e];
        sc.thermal.network.radiators[e].emissivity_area_m2 =
            product(r.emissivity_area_m2, r.emissivity, r.area_m2);
        Ok(())
    };
    t.extend([
        row(
            Radiation,
            &[],
            &EMISSIVITY_AREA_M2,
            "εA, the effective emissivity times the area (with view factors)",
            |s, e| Some(Slot::Optional(&mut s.radiation[e].emissivity_area_m2)),
        )
        .fast(radiation_fast)
        .calibrated(link(SCALE_UP_TO)),
        row(
            Radiation,
            &[],
            &EMISSIVITY,
            "ε, with `area_m2` instead of `emissivity_area_m2`",
            |s, e| Some(Slot::Optional(&mut s.radiation[e].emissivity)),
        )
        .fast(radiation_fast)
        .calibrated(link(None)),
        row(Radiation, &[], &AREA_M2, "A, with `emissivity`", |s, e| {
            Some(Slot::Optional(&mut s.radiation[e].area_m2))
        })
        .fast(radiation_fast),
    ]);
}

/// Writes an area load's product into compiled load `at`.
fn set_load_product(sc: &mut Scenario, at: usize, v: f64) {
    match &mut sc.thermal.network.loads[at].kind {
        LoadKind::Sun {
            absorptivity_area_m2,
            ..
        }
        | LoadKind::Albedo {
            absorptivity_area_m2,
            ..
        } => *absorptivity_area_m2 = v,
        LoadKind::EarthIr {
            emissivity_area_m2, ..
        } => *emissivity_area_m2 = v,
        LoadKind::Dissipation { .. } | LoadKind::Face(_) => unreachable!("not an area load"),
    }
}

/// Writes an Earth-facing load's view factor into compiled load `at`.
fn set_view_factor(sc: &mut Scenario, at: usize, v: Option<f64>) {
    match &mut sc.thermal.network.loads[at].kind {
        LoadKind::Albedo { view_factor, .. } | LoadKind::EarthIr { view_factor, .. } => {
            *view_factor = v.expect("written")
        }
        _ => unreachable!("a load with a view factor"),
    }
}

fn area_loads(t: &mut Vec<Row>) {
    use Section::{Albedo, EarthIr, Sun};
    let sun: super::FastFn = |s, _, sc, e| {
        let l = &s.sun[e];
        set_load_product(
            sc,
            sc.bindings.sun[e],
            product(l.absorptivity_area_m2, l.absorptivity, l.area_m2),
        );
        Ok(())
    };
    let albedo: super::FastFn = |s, _, sc, e| {
        let l = &s.albedo[e];
        set_load_product(
            sc,
            sc.bindings.albedo[e],
            product(l.absorptivity_area_m2, l.absorptivity, l.area_m2),
        );
        Ok(())
    };
    let earth_ir: super::FastFn = |s, _, sc, e| {
        let l = &s.earth_ir[e];
        set_load_product(
            sc,
            sc.bindings.earth_ir[e],
            product(l.emissivity_area_m2, l.emissivity, l.area_m2),
        );
        Ok(())
    };
    t.extend([
        row(
            Sun,
            &[],
            &ABSORPTIVITY_AREA_M2,
            "αA, the absorptivity times the area facing the Sun",
            |s, e| Some(Slot::Optional(&mut s.sun[e].absorptivity_area_m2)),
        )
        .fast(sun)
        .calibrated(absorptivity(false, SCALE_UP_TO)),
        row(Sun, &[], &ABSORPTIVITY, "α, with `area_m2`", |s, e| {
            Some(Slot::Optional(&mut s.sun[e].absorptivity))
        })
        .fast(sun)
        .calibrated(absorptivity(false, None)),
        row(Sun, &[], &AREA_M2, "A, with `absorptivity`", |s, e| {
            Some(Slot::Optional(&mut s.sun[e].area_m2))
        })
        .fast(sun),
        row(
            Albedo,
            &[],
            &ABSORPTIVITY_AREA_M2,
            "αA facing the Earth",
            |s, e| Some(Slot::Optional(&mut s.albedo[e].absorptivity_area_m2)),
        )
        .fast(albedo),
        row(Albedo, &[], &ABSORPTIVITY, "α, with `area_m2`", |s, e| {
            Some(Slot::Optional(&mut s.albedo[e].absorptivity))
        })
        .fast(albedo),
        row(Albedo, &[], &AREA_M2, "A, with `absorptivity`", |s, e| {
            Some(Slot::Optional(&mut s.albedo[e].area_m2))
        })
        .fast(albedo),
        row(
            Albedo,
            &[],
            &VIEW_FACTOR,
            "F, the view factor of the Earth (default (R/(R+h))²)",
            |s, e| Some(Slot::Optional(&mut s.albedo[e].view_factor)),
        )
        .earth_view_factor()
        .fast(|s, _, sc, e| {
            set_view_factor(sc, sc.bindings.albedo[e], s.albedo[e].view_factor);
            Ok(())
        }),
        row(
            EarthIr,
            &[],
            &EMISSIVITY_AREA_M2,
            "εA facing the Earth",
            |s, e| Some(Slot::Optional(&mut s.earth_ir[e].emissivity_area_m2)),
        )
        .fast(earth_ir),
        row(EarthIr, &[], &EMISSIVITY, "ε, with `area_m2`", |s, e| {
            Some(Slot::Optional(&mut s.earth_ir[e].emissivity))
        })
        .fast(earth_ir),
        row(EarthIr, &[], &AREA_M2, "A, with `emissivity`", |s, e| {
            Some(Slot::Optional(&mut s.earth_ir[e].area_m2))
        })
        .fast(earth_ir),
        row(
            EarthIr,
            &[],
            &VIEW_FACTOR,
            "F, the view factor of the Earth (default (R/(R+h))²)",
            |s, e| Some(Slot::Optional(&mut s.earth_ir[e].view_factor)),
        )
        .earth_view_factor()
        .fast(|s, _, sc, e| {
            set_view_factor(sc, sc.bindings.earth_ir[e], s.earth_ir[e].view_factor);
            Ok(())
        }),
    ]);
}

fn dissipations_and_heaters(t: &mut Vec<Row>) {
    use Section::{Dissipation, Heater};
    t.extend([
        row(
            Dissipation,
            &[],
            &DISSIPATION_POWER_W,
            "the power dissipated in the node, *profile*",
            |s, e| Some(Slot::Profile(&mut s.dissipation[e].power_w)),
        )
        .fast(|s, _, sc, e| {
            if let crate::spec::ProfileSpec::Constant(p) = s.dissipation[e].power_w {
                let at = sc.bindings.dissipation[e];
                match &mut sc.thermal.network.loads[at].kind {
                    LoadKind::Dissipation { power_w, .. } => {
                        *power_w = crate::orbit::Profile::Constant(p)
                    }
                    _ => unreachable!("a dissipation"),
                }
            }
            Ok(())
        }),
        row(
            Heater,
            &[],
            &HEATER_POWER_W,
            "the heater's power P",
            |s, e| Some(Slot::Value(&mut s.heater[e].power_w)),
        )
        .fast(|s, _, sc, e| {
            sc.thermal.network.heaters[e].power_w = s.heater[e].power_w;
            Ok(())
        }),
        row(
            Heater,
            &[],
            &ON_K,
            "switches on when its sensor node falls to `on_k`",
            |s, e| Some(Slot::Value(&mut s.heater[e].on_k)),
        )
        .fast(heater_band),
        row(
            Heater,
            &[],
            &OFF_K,
            "switches off when its sensor node rises to `off_k`",
            |s, e| Some(Slot::Value(&mut s.heater[e].off_k)),
        )
        .fast(heater_band),
    ]);
}

/// A heater's switching temperatures, checked as a band (the error at `off_k`).
fn heater_band(s: &ScenarioSpec, keys: &ElementKeys, sc: &mut Scenario, e: usize) -> Done {
    let h = &s.heater[e];
    let off = OFF_K.key(&Section::Heater.path(Some((e, &keys.heater[e]))));
    crate::spec::check::heater_band(&off, h.on_k, h.off_k)?;
    let m = &mut sc.thermal.network.heaters[e];
    (m.on_k, m.off_k) = (h.on_k, h.off_k);
    Ok(())
}

/// A face's load and its radiative coupling to space, made again from its spec.
fn face(s: &ScenarioSpec, _: &ElementKeys, sc: &mut Scenario, e: usize) -> Done {
    let f = &s.face[e];
    let (load, radiator) = sc.bindings.face[e];
    let net = &mut sc.thermal.network;
    match &mut net.loads[load].kind {
        LoadKind::Face(x) => {
            (x.area_m2, x.absorptivity, x.emissivity) = (f.area_m2, f.absorptivity, f.emissivity)
        }
        _ => unreachable!("a face"),
    }
    net.radiators[radiator].emissivity_area_m2 = f.emissivity * f.area_m2;
    Ok(())
}

/// A sensor's lag and offset, made again from its spec.
fn sensor(s: &ScenarioSpec, _: &ElementKeys, sc: &mut Scenario, e: usize) -> Done {
    let x = &s.sensor[e];
    let m = &mut sc.sensors[e];
    m.tau_s = x.tau_s.unwrap_or(q::SENSOR_TAU_S.default_value());
    m.offset_k = x.offset_k.unwrap_or(q::SENSOR_OFFSET_K.default_value());
    Ok(())
}

fn faces_modes_sensors(t: &mut Vec<Row>) {
    use Section::{Attitude, Face, Mode, Recording, Sensor};
    let mode = |s: &ScenarioSpec| s.attitude.as_ref().and_then(|a| a.mode);
    t.extend([
        // a nadir-pointing body's yaw, where there are faces to turn (an absent
        // [attitude] table is written only when the yaw is)
        row(
            Attitude,
            &[],
            &YAW_DEG,
            "a nadir-pointing body turned about nadir",
            move |s, _| {
                (matches!(mode(s), None | Some(AttitudeMode::Nadir)) && !s.face.is_empty()).then(
                    || {
                        Slot::Optional(
                            &mut s
                                .attitude
                                .get_or_insert_with(crate::spec::AttitudeSpec::default)
                                .yaw_deg,
                        )
                    },
                )
            },
        ),
        row(
            Attitude,
            &[],
            &SPIN_RATE_DEG_PER_S,
            "a spinning body's rate about `spin_axis`",
            move |s, _| {
                let spinning = mode(s) == Some(AttitudeMode::Spin) && !s.face.is_empty();
                spinning.then(|| {
                    Slot::Optional(&mut s.attitude.as_mut().expect("spinning").spin_rate_deg_per_s)
                })
            },
        ),
        row(Face, &[], &AREA_M2, "the face's area", |s, e| {
            Some(Slot::Value(&mut s.face[e].area_m2))
        })
        .fast(face),
        row(
            Face,
            &[],
            &ABSORPTIVITY,
            "the face's solar absorptivity α (direct Sun and albedo)",
            |s, e| Some(Slot::Value(&mut s.face[e].absorptivity)),
        )
        .fast(face)
        .calibrated(absorptivity(true, None)),
        row(
            Face,
            &[],
            &EMISSIVITY,
            "the face's infrared emissivity ε (Earth infrared, emission to space)",
            |s, e| Some(Slot::Value(&mut s.face[e].emissivity)),
        )
        .fast(face)
        .calibrated(FACE_EMISSIVITY),
        row(
            Mode,
            &[],
            &WINDOWS_S,
            "[start, end] windows in s, increasing, not overlapping",
            |s, e| s.mode[e].windows_s.as_mut().map(Slot::Windows),
        ),
        row(
            Mode,
            &[],
            &WINDOWS_DAYS,
            "[start, end] windows in days",
            |s, e| s.mode[e].windows_days.as_mut().map(Slot::Windows),
        ),
        // written only where the scenario reads recordings ([recording] is given)
        row(
            Recording,
            &[],
            &TIME_OFFSET_S,
            "seconds added to each of a recording's time stamps (when a row was measured)",
            |s, _| {
                s.recording
                    .as_mut()
                    .map(|r| Slot::Optional(&mut r.time_offset_s))
            },
        ),
        row(
            Sensor,
            &[],
            &TAU_S,
            "a temperature sensor's first-order time constant",
            |s, e| {
                let x = &mut s.sensor[e];
                x.quantity.is_none().then_some(Slot::Optional(&mut x.tau_s))
            },
        )
        .fast(sensor),
        row(
            Sensor,
            &[],
            &OFFSET_K,
            "a temperature sensor's constant bias",
            |s, e| {
                let x = &mut s.sensor[e];
                x.quantity
                    .is_none()
                    .then_some(Slot::Optional(&mut x.offset_k))
            },
        )
        .fast(sensor),
    ]);
}

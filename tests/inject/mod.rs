//! Independent real-data injection suite for FUNcube-1: concealed effects added to the
//! flight telemetry of 2016-02-04 (`../shared/data/funcube-1`), each as a *signature*
//! (per channel, the generator's model with the effect minus the same model without
//! it, at every row's time) added to the measured rows, so that `orbitlash diagnose`
//! can be scored on real data with a known answer.
//!
//! The generator uses nothing from the `orbitlash` crate (no `orbitlash::` path in this
//! module), so that the test does not commit the inverse crime of fitting data made by
//! the fitter's own code. It reads `scenarios/funcube-1.toml` as plain TOML data (the
//! numbers: nodes, conductors, radiative couplings, faces, dissipation, sensors,
//! environment constants, TLE) and implements the physics from the scenario format's
//! meaning (`scenarios/README.md`: tumble attitude, faces, thermostats).
//!
//! How it differs from orbitlash's forward model:
//! - Integrator: fixed-step classical explicit RK4 (2 s), steps landing on row times,
//!   eclipse entries and exits and switch-on times, the sunlit flag held over a step;
//!   not adaptive TR-BDF2 (tolerance 0.01 K, steps up to 120 s).
//! - Thermostats: checked at the end of each step, the crossing located by bisection of
//!   the step length (1 ms), integration restarted there. A concealed thermostat reads
//!   its node's *flight* temperature plus its heater's own signature (this model's
//!   node with the heater minus without, the flight the mean of the node's sensors
//!   between measured rows), so its set points are those of the real spacecraft's
//!   node; this model's node is several kelvin from the flight, and a thermostat
//!   reading it would switch where the recording is elsewhere.
//! - Sensor lag: an extra state integrated by the same RK4 (orbitlash integrates the
//!   lag exactly over each of its steps).
//! - Eclipses: from the telemetry itself, not SGP4: the photo-current's transitions
//!   (below 20 mA is eclipse) fitted by strictly periodic entry and exit times, a step
//!   function without penumbra (orbitlash: SGP4 on the TLE, the dated Sun, a conical
//!   shadow with its penumbra).
//! - Orbit: circular at the TLE mean motion's radius, the orbit angle uniform and
//!   midnight at the middle of each fitted eclipse; β from the fitted eclipse length
//!   under a cylindrical shadow (orbitlash: the SGP4 state, eccentricity included).
//! - Fluxes: S/4 direct while sunlit, the scenario's 1 AU flux over d² with a one-line
//!   Sun distance; albedo as a quarter of the Lambertian radiance integrated over the
//!   visible cap by a midpoint rule, tabulated per degree of sub-satellite solar zenith
//!   (orbitlash: its own cell integral over the sunlit disc at each instant); Earth
//!   infrared times the cap's solid angle over 4π (the same closed form).
//! - Start: four orbits of spin-up before 00:00 UTC from the scenario's initial
//!   temperatures, the effect present through them (orbitlash's `diagnose` starts its
//!   model at 00:00 from the initial temperatures).
//!
//! A signature is a difference of two runs of this model with the same steps, so the
//! modest environment errors above cancel to first order. Channel values are in °C.
#![allow(dead_code)]

pub mod environment;
pub mod scenario;
pub mod score;
pub mod telemetry;
pub mod thermal;

use std::path::{Path, PathBuf};

use environment::Environment;
use scenario::Spacecraft;
use serde_json::{Value, json};
use std::sync::Arc;
use telemetry::{Telemetry, unix_s};
use thermal::{Additions, Lag, Run, Solver, Switched, Table, Thermostat};

/// Orbits integrated before 00:00 UTC to settle the orbit cycle (the slowest time
/// constant of the network is about half an orbit).
pub const SPINUP_ORBITS: f64 = 4.0;
/// 0 °C in K.
pub const ZERO_C_K: f64 = 273.15;

/// A concealed effect. Nodes, faces and channels are named as the scenario names them
/// (`chassis`, `py`, `panel_mx_c`).
#[derive(Clone, Debug, PartialEq)]
pub enum Effect {
    /// Nothing added: the signature is zero.
    None,
    /// A heater on `node` with a thermostat reading that node: on below `on_c`, off
    /// above `off_c` (°C); its state carried through the run.
    Heater {
        node: &'static str,
        power_w: f64,
        on_c: f64,
        off_c: f64,
    },
    /// `power_w` more dissipated in `node` from `switch_utc` on.
    SwitchedDissipation {
        node: &'static str,
        power_w: f64,
        switch_utc: &'static str,
    },
    /// A first-order sensor on `channel`.
    SensorLag { channel: &'static str, tau_s: f64 },
    /// A constant bias on `channel`.
    SensorOffset {
        channel: &'static str,
        offset_k: f64,
    },
    /// Face `face`'s solar absorptivity (direct Sun and albedo) × `scale`.
    AbsorptivityScale { face: &'static str, scale: f64 },
    /// Outside the vocabulary: `channel` drifts linearly, 0 at 00:00 UTC.
    Drift {
        channel: &'static str,
        k_per_day: f64,
    },
}

/// One case of the suite: a folder name and its effect.
#[derive(Clone, Debug)]
pub struct Case {
    pub name: &'static str,
    pub effect: Effect,
}

/// The suite's cases, in the order they are written and scored.
///
/// Targets were chosen away from what `diagnose` already finds on the untouched day
/// (`docs/validation.md`: panel +X's coupling and capacity, +X's absorptivity, the
/// silver chassis' offset), so that a hit is the injected effect and not the day's own
/// residual: the lag on −X, the absorptivity on +Y, the offset on the black chassis,
/// the drift on −Y. `chassis_lag` is one more than the brief's list (written when
/// `diagnose` offered sensor effects only on channels whose `[[sensor]]` names a
/// `node`; face channels have them now).
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "null",
            effect: Effect::None,
        },
        Case {
            name: "heater",
            effect: Effect::Heater {
                node: "chassis",
                power_w: 2.0,
                on_c: -6.0,
                off_c: -3.0,
            },
        },
        Case {
            name: "switched_dissipation",
            effect: Effect::SwitchedDissipation {
                node: "stack",
                power_w: 0.8,
                switch_utc: "2016-02-04T12:00:00Z",
            },
        },
        Case {
            name: "panel_lag",
            effect: Effect::SensorLag {
                channel: "panel_mx_c",
                tau_s: 300.0,
            },
        },
        Case {
            name: "chassis_lag",
            effect: Effect::SensorLag {
                channel: "chassis_silver_c",
                tau_s: 300.0,
            },
        },
        Case {
            name: "chassis_offset",
            effect: Effect::SensorOffset {
                channel: "chassis_black_c",
                offset_k: 1.5,
            },
        },
        Case {
            name: "face_absorptivity",
            effect: Effect::AbsorptivityScale {
                face: "py",
                scale: 0.8,
            },
        },
        Case {
            name: "control",
            effect: Effect::Drift {
                channel: "panel_my_c",
                k_per_day: 2.0,
            },
        },
    ]
}

/// A run of the model read through the sensors: `channels_c[sensor][time]` in °C.
#[derive(Clone, Debug)]
pub struct Simulation {
    pub times_s: Vec<f64>,
    pub channels_c: Vec<Vec<f64>>,
    pub run: Run,
}

/// What an effect changes: the network's additions, and per sensor the lag state it
/// reads (sensor, state index), its offset (K) and its drift (K/day).
struct Changes {
    add: Additions,
    lagged: Vec<(usize, usize)>,
    offset_k: Vec<f64>,
    drift_k_per_day: Vec<f64>,
}

/// The scenario, the environment and the telemetry, loaded once.
pub struct Generator {
    pub craft: Spacecraft,
    pub env: Environment,
    pub telemetry: Telemetry,
    /// RK4 step (s), [`thermal::STEP_S`] unless changed for a convergence check.
    pub step_s: f64,
}

/// The repository's root (where `scenarios/` is).
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

impl Generator {
    /// The scenario `scenarios/funcube-1.toml` and the telemetry file at `telemetry`.
    pub fn load(telemetry: &Path) -> Generator {
        let craft = Spacecraft::read(&repo_root().join(scenario::SCENARIO));
        let telemetry = Telemetry::read(
            telemetry,
            &craft.time_column,
            &craft.start_utc,
            craft.time_offset_s,
        );
        let env = Environment::new(&craft, &telemetry);
        Generator {
            craft,
            env,
            telemetry,
            step_s: thermal::STEP_S,
        }
    }

    /// Seconds from the recording's start (`start_utc`) of a UTC time stamp.
    pub fn time_of(&self, utc: &str) -> f64 {
        unix_s(utc) - unix_s(&self.craft.start_utc)
    }

    /// What `effect` changes: the network's additions and the sensors' readings.
    fn changes(&self, effect: &Effect) -> Changes {
        let net = &self.craft.net;
        let sensors = self.craft.sensors.len();
        let mut ch = Changes {
            add: Additions::default(),
            lagged: Vec::new(),
            offset_k: vec![0.0; sensors],
            drift_k_per_day: vec![0.0; sensors],
        };
        match *effect {
            Effect::None => {}
            Effect::Heater {
                node,
                power_w,
                on_c,
                off_c,
            } => {
                assert!(on_c < off_c, "a thermostat needs on_c < off_c");
                ch.add.thermostats.push(Thermostat {
                    node: net.index(node),
                    power_w,
                    on_k: on_c + ZERO_C_K,
                    off_k: off_c + ZERO_C_K,
                    reads_offset: Some(Arc::new(self.flight_minus_model(node))),
                });
            }
            Effect::SwitchedDissipation {
                node,
                power_w,
                switch_utc,
            } => ch.add.switched.push(Switched {
                node: net.index(node),
                power_w,
                t_on_s: self.time_of(switch_utc),
            }),
            Effect::SensorLag { channel, tau_s } => {
                let s = self.craft.sensor(channel);
                ch.lagged.push((s, net.names.len() + ch.add.lags.len()));
                ch.add.lags.push(Lag {
                    node: self.craft.sensors[s].node,
                    tau_s,
                });
            }
            Effect::SensorOffset { channel, offset_k } => {
                ch.offset_k[self.craft.sensor(channel)] += offset_k;
            }
            Effect::AbsorptivityScale { face, scale } => {
                ch.add.absorptivity_scale.push((net.face(face), scale));
            }
            Effect::Drift { channel, k_per_day } => {
                ch.drift_k_per_day[self.craft.sensor(channel)] += k_per_day;
            }
        }
        ch
    }

    /// The times the steps of every run with `effect` land on besides the requested
    /// ones (its switch-on time), shared by the run without it.
    fn breaks(&self, effect: &Effect) -> Vec<f64> {
        match *effect {
            Effect::SwitchedDissipation { switch_utc, .. } => vec![self.time_of(switch_utc)],
            _ => Vec::new(),
        }
    }

    /// The model with `effect`, read by every sensor at `times_s` (non-decreasing, ≥ 0),
    /// with the steps of [`Generator::breaks`] of `steps_of`.
    pub fn simulate_with_steps_of(
        &self,
        effect: &Effect,
        steps_of: &Effect,
        times_s: &[f64],
    ) -> Simulation {
        let ch = self.changes(effect);
        let solver = Solver {
            net: &self.craft.net,
            env: &self.env,
            add: ch.add,
            step_s: self.step_s,
            t_start_s: -SPINUP_ORBITS * self.env.eclipses.period_s,
            breaks_s: self.breaks(steps_of),
        };
        let run = solver.run(times_s);
        let channels_c = self
            .craft
            .sensors
            .iter()
            .enumerate()
            .map(|(s, sensor)| {
                let state = ch
                    .lagged
                    .iter()
                    .find(|l| l.0 == s)
                    .map_or(sensor.node, |l| l.1);
                let (offset_k, k_per_day) = (ch.offset_k[s], ch.drift_k_per_day[s]);
                run.states
                    .iter()
                    .zip(times_s)
                    .map(|(y, t)| y[state] - ZERO_C_K + offset_k + k_per_day * t / 86_400.0)
                    .collect()
            })
            .collect();
        Simulation {
            times_s: times_s.to_vec(),
            channels_c,
            run,
        }
    }

    /// The model with `effect` at `times_s`.
    pub fn simulate(&self, effect: &Effect, times_s: &[f64]) -> Simulation {
        self.simulate_with_steps_of(effect, effect, times_s)
    }

    /// The model with `effect` at every telemetry row's time.
    pub fn simulate_rows(&self, effect: &Effect) -> Simulation {
        self.simulate(effect, &self.telemetry.times_s)
    }

    /// The signature of `effect`: per sensor, at every telemetry row, the model with
    /// the effect minus the model without it (both with the same steps), K.
    pub fn signature(&self, effect: &Effect) -> Vec<Vec<f64>> {
        let times = &self.telemetry.times_s;
        let with = self.simulate(effect, times);
        let without = self.simulate_with_steps_of(&Effect::None, effect, times);
        with.channels_c
            .iter()
            .zip(&without.channels_c)
            .map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect())
            .collect()
    }

    /// The recording of a signature: the telemetry rewritten with it added (see
    /// [`Telemetry::with_signature`]).
    pub fn recording(&self, signature: &[Vec<f64>]) -> String {
        let columns: Vec<(usize, Vec<f64>)> = self
            .craft
            .sensors
            .iter()
            .zip(signature)
            .map(|(s, v)| (self.telemetry.column(&s.column), v.clone()))
            .collect();
        self.telemetry.with_signature(&columns)
    }

    /// Writes every case into `dir/<case>/recording.csv` and `expected.json`; returns
    /// the case folders.
    pub fn write_cases(&self, dir: &Path) -> std::io::Result<Vec<PathBuf>> {
        let mut out = Vec::new();
        for case in cases() {
            let folder = dir.join(case.name);
            std::fs::create_dir_all(&folder)?;
            let signature = self.signature(&case.effect);
            std::fs::write(folder.join("recording.csv"), self.recording(&signature))?;
            let expected = self.expected(&case, &signature);
            let text = serde_json::to_string_pretty(&expected).expect("JSON");
            std::fs::write(folder.join("expected.json"), text + "\n")?;
            out.push(folder);
        }
        Ok(out)
    }

    /// The heater's duty cycle over the recording and its switches per orbit (0, 0
    /// without a heater).
    pub fn heater_duty(&self, sim: &Simulation) -> (f64, f64) {
        let span = sim.times_s.last().copied().unwrap_or(0.0);
        let duty = sim.run.heater_on_s.first().map_or(0.0, |on| on / span);
        let switches = sim.run.switches.iter().filter(|s| s.0 >= 0.0).count();
        (duty, switches as f64 * self.env.eclipses.period_s / span)
    }

    /// `expected.json` of a case (in the spirit of `shared/cases/*/expected.json`).
    pub fn expected(&self, case: &Case, signature: &[Vec<f64>]) -> Value {
        let (effect, kind, target, parameters, tolerances) = describe(&case.effect);
        let mut doc = json!({
            "case": case.name,
            "effect": effect,
            "kind": kind,
            "parameters": parameters,
            "tolerances": tolerances,
            "channels": self.affected_channels(signature),
            "signature": self.signature_summary(signature),
            "truth": self.truth(case),
        });
        if let (Some((key, name)), Some(map)) = (target, doc.as_object_mut()) {
            map.insert(key.to_string(), json!(name));
        }
        doc
    }

    /// Channels whose signature exceeds 0.05 K somewhere on a measured row.
    fn affected_channels(&self, signature: &[Vec<f64>]) -> Vec<String> {
        self.craft
            .sensors
            .iter()
            .zip(signature)
            .filter(|(_, v)| self.measured(v).any(|x| x.abs() > 0.05))
            .map(|(s, _)| s.name.clone())
            .collect()
    }

    /// A series' values on the measured rows.
    pub fn measured<'a>(&'a self, v: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
        v.iter()
            .zip(&self.telemetry.fill)
            .filter(|(_, f)| !**f)
            .map(|(x, _)| *x)
    }

    /// Per channel: RMS, mean, smallest and largest signature on the measured rows.
    fn signature_summary(&self, signature: &[Vec<f64>]) -> Value {
        let mut map = serde_json::Map::new();
        for (s, v) in self.craft.sensors.iter().zip(signature) {
            let m: Vec<f64> = self.measured(v).collect();
            let n = m.len() as f64;
            let rms = (m.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
            let mean = m.iter().sum::<f64>() / n;
            let min = m.iter().copied().fold(f64::INFINITY, f64::min);
            let max = m.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            map.insert(
                s.name.clone(),
                json!({"rms_k": round4(rms), "mean_k": round4(mean), "min_k": round4(min), "max_k": round4(max)}),
            );
        }
        Value::Object(map)
    }

    /// How the case was made: the generator, the data, and the effect's own facts
    /// (heater duty cycle and switches, the switch time in s).
    fn truth(&self, case: &Case) -> Value {
        let fill = self.telemetry.fill.iter().filter(|f| **f).count();
        let mut truth = json!({
            "generator": "tests/inject (independent of orbitlash: own network, RK4, telemetry eclipses)",
            "data": "../shared/data/funcube-1/funcube1_wod_2016-02-04.csv",
            "rows": self.telemetry.rows.len(),
            "fill_rows": fill,
            "measured_rows": self.telemetry.rows.len() - fill,
            "step_s": self.step_s,
            "spinup_orbits": SPINUP_ORBITS,
            "eclipse_period_s": round4(self.env.eclipses.period_s),
            "eclipse_duration_s": round4(self.env.eclipses.duration_s()),
            "beta_deg": round4(self.env.beta_rad.to_degrees()),
        });
        let map = truth.as_object_mut().expect("an object");
        match case.effect {
            Effect::Heater { node, .. } => {
                let sim = self.simulate_rows(&case.effect);
                let (duty, per_orbit) = self.heater_duty(&sim);
                map.insert("heater_duty_cycle".into(), json!(round4(duty)));
                map.insert("heater_switches_per_orbit".into(), json!(round4(per_orbit)));
                let [on_c, off_c] = self.flight_at_switches(&sim, node);
                map.insert(
                    "set_points_note".into(),
                    json!("the thermostat reads the node's flight temperature (the mean of its sensors, interpolated between measured rows) plus the heater's own signature; the flight sensors on that node, without the heater, read flight_at_switch_on_c/off_c at the switches"),
                );
                map.insert("flight_at_switch_on_c".into(), json!(round4(on_c)));
                map.insert("flight_at_switch_off_c".into(), json!(round4(off_c)));
            }
            Effect::SwitchedDissipation { switch_utc, .. } => {
                map.insert("switch_utc".into(), json!(switch_utc));
                map.insert("switch_time_s".into(), json!(self.time_of(switch_utc)));
            }
            Effect::Drift { channel, k_per_day } => {
                map.insert(
                    "outside_vocabulary".into(),
                    json!({"drift": {"channel": channel, "k_per_day": k_per_day}}),
                );
            }
            _ => {}
        }
        truth
    }
}

impl Generator {
    /// The sensors on `node`: each one's index and its flight values (°C, `None` on
    /// fill rows).
    pub fn node_sensors(&self, node: &str) -> Vec<(usize, Vec<Option<f64>>)> {
        let k = self.craft.net.index(node);
        (0..self.craft.sensors.len())
            .filter(|&s| self.craft.sensors[s].node == k)
            .map(|s| {
                let column = self.telemetry.column(&self.craft.sensors[s].column);
                (s, self.telemetry.values(column))
            })
            .collect()
    }

    /// The flight temperature of `node` (the mean of its sensors) minus this model's
    /// own temperature of it without effects, at the measured rows where every sensor
    /// of the node reads, K. A concealed thermostat reads its node through this, so it
    /// switches where the real spacecraft's node, warmed by its heater, crosses the set
    /// point: the flight temperature plus the heater's own signature.
    pub fn flight_minus_model(&self, node: &str) -> Table {
        let k = self.craft.net.index(node);
        let columns: Vec<Vec<Option<f64>>> =
            self.node_sensors(node).into_iter().map(|c| c.1).collect();
        assert!(!columns.is_empty(), "no sensor on node {node}");
        let model = self.simulate_rows(&Effect::None);
        let (mut times_s, mut values) = (Vec::new(), Vec::new());
        for (j, t) in self.telemetry.times_s.iter().enumerate() {
            let v: Option<Vec<f64>> = columns.iter().map(|c| c[j]).collect();
            if let Some(v) = v {
                let flight_k = v.iter().sum::<f64>() / v.len() as f64 + ZERO_C_K;
                if times_s.last().is_none_or(|&last| *t > last) {
                    times_s.push(*t);
                    values.push(flight_k - model.run.states[j][k]);
                }
            }
        }
        Table {
            times_s,
            values,
            period_s: self.env.eclipses.period_s,
        }
    }

    /// The flight's reading of `node` (the mean of the sensors on it) at the measured
    /// row nearest each thermostat switch of `sim` (within 60 s), averaged over the
    /// switches on and over the switches off, °C.
    pub fn flight_at_switches(&self, sim: &Simulation, node: &str) -> [f64; 2] {
        let columns: Vec<Vec<Option<f64>>> =
            self.node_sensors(node).into_iter().map(|c| c.1).collect();
        let mut sums = [(0.0, 0.0); 2];
        for &(t, _, on) in sim.run.switches.iter().filter(|s| s.0 >= 0.0) {
            let nearest = (0..self.telemetry.rows.len())
                .filter(|&k| !self.telemetry.fill[k])
                .min_by(|&a, &b| {
                    let d = |k: usize| (self.telemetry.times_s[k] - t).abs();
                    d(a).total_cmp(&d(b))
                });
            let Some(k) = nearest.filter(|&k| (self.telemetry.times_s[k] - t).abs() <= 60.0) else {
                continue;
            };
            let v: Vec<f64> = columns.iter().filter_map(|c| c[k]).collect();
            let slot = &mut sums[usize::from(!on)];
            slot.0 += v.iter().sum::<f64>() / v.len() as f64;
            slot.1 += 1.0;
        }
        sums.map(|(s, n)| s / n)
    }
}

fn round4(x: f64) -> f64 {
    (x * 1e4).round() / 1e4
}

/// A case's expected finding: effect id (as `docs/vocabulary.md` names it, `none` for
/// nothing or an effect outside the vocabulary), kind, target (the finding's key and
/// the element's name), true parameters in the report's units, and tolerances
/// (`relative` or `absolute`, in the parameter's unit).
pub fn describe(
    effect: &Effect,
) -> (
    &'static str,
    &'static str,
    Option<(&str, &str)>,
    Value,
    Value,
) {
    let rel = |x: f64| json!({ "relative": x });
    let abs = |x: f64| json!({ "absolute": x });
    match *effect {
        Effect::None | Effect::Drift { .. } => ("none", "none", None, json!({}), json!({})),
        Effect::Heater {
            node,
            power_w,
            on_c,
            off_c,
        } => (
            "heater_thermostat",
            "physics",
            Some(("node", node)),
            json!({"power_w": power_w, "on_c": on_c, "off_c": off_c}),
            json!({"power_w": rel(0.25), "on_c": abs(1.5), "off_c": abs(1.5)}),
        ),
        Effect::SwitchedDissipation {
            node,
            power_w,
            switch_utc,
        } => (
            "switched_dissipation",
            "physics",
            Some(("node", node)),
            json!({"power_w": power_w, "on_s": seconds_of_day(switch_utc)}),
            json!({"power_w": rel(0.25), "on_s": abs(1800.0)}),
        ),
        Effect::SensorLag { channel, tau_s } => (
            "sensor_lag",
            "sensor",
            Some(("channel", channel)),
            json!({"tau_s": tau_s}),
            json!({"tau_s": rel(0.30)}),
        ),
        Effect::SensorOffset { channel, offset_k } => (
            "sensor_offset",
            "sensor",
            Some(("channel", channel)),
            json!({"offset_k": offset_k}),
            json!({"offset_k": abs(0.5)}),
        ),
        Effect::AbsorptivityScale { face, scale } => (
            "absorptivity_scale",
            "calibration",
            Some(("face", face)),
            json!({"scale": scale}),
            json!({"scale": rel(0.20)}),
        ),
    }
}

/// Seconds after midnight of a UTC time `YYYY-MM-DDTHH:MM:SSZ` (the scenario starts at
/// midnight of the day).
fn seconds_of_day(utc: &str) -> f64 {
    let hms: Vec<f64> = utc[11..19]
        .split(':')
        .map(|v| v.parse().expect("a UTC time"))
        .collect();
    hms[0] * 3600.0 + hms[1] * 60.0 + hms[2]
}

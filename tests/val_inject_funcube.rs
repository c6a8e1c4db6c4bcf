//! The real-data injection suite for FUNcube-1 (`tests/inject`): concealed effects added
//! to the flight telemetry of 2016-02-04 as signatures of an independent model.
//!
//! These tests check the generator, not `diagnose`:
//! - its model without effects is a model of the same spacecraft: against the flight
//!   telemetry (per-channel RMS, correlation, the eclipse-phase and sunlit biases the
//!   public numbers leave, `docs/validation.md`), against orbitlash's own run of the
//!   scenario (through the binary), and its eclipses against the photo-current and
//!   the TLE;
//! - its integrator converges;
//! - each signature has the shape its effect must give;
//! - signatures hardly move when the environment is modelled differently (they are
//!   differences);
//! - the written recordings differ from the flight file exactly by the signature.
//!
//! Two ignored tests write the cases for a human (`val_inject_funcube_write_cases`:
//! `target/inject/<case>/`) and score `orbitlash diagnose` on them
//! (`val_inject_funcube_diagnose_score`, a few minutes: it reports, it does not
//! assert). Every test skips with one line without `../shared`
//! (`ORBITLASH_REQUIRE_SHARED=1` makes that a failure).

mod common;
mod inject;

use inject::{Effect, Generator, cases};

/// The flight telemetry, relative to `../shared`.
const WOD: &str = "data/funcube-1/funcube1_wod_2016-02-04.csv";

/// The generator on the flight day, or `None` (after the skip line) without
/// `../shared`.
fn generator() -> Option<Generator> {
    common::shared(WOD).map(|p| Generator::load(&p))
}

/// Mean of a slice.
fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Root mean square of a slice.
fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

/// Pearson correlation of paired samples.
fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let (ma, mb) = (mean(a), mean(b));
    let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

/// Per-channel RMS of (model − flight) on the measured rows, as measured with the
/// frame at the ISIS structure's 164 J/K (°C; `docs/validation.md` reports
/// 4.45 … 9.85 for orbitlash's own baseline). Each bound is that figure plus 0.5 K.
/// (With the earlier 432 J/K frame: 5.7 … 10.6 K, correlations 0.957 … 0.986.)
const FLIGHT_RMS_BOUND_K: [(&str, f64); 8] = [
    ("chassis_black_c", 6.5),
    ("chassis_silver_c", 7.3),
    ("panel_black_c", 6.9),
    ("panel_silver_c", 10.6),
    ("panel_px_c", 5.0),
    ("panel_mx_c", 5.9),
    ("panel_py_c", 5.7),
    ("panel_my_c", 5.4),
];

/// The model without effects against the flight day, channel by channel: RMS within
/// its bound, correlation ≥ 0.97 (the orbit's shape and phase), the sunlit mean
/// 4 … 12 K too cold (the shortfall the scenario's public numbers leave, the same for
/// orbitlash's baseline), the eclipse mean within 3 K of the sunlit one (the model
/// lacks heat, by about as much in both phases, not timing), the eclipse mean within
/// 9.3 K (measured −2.2 … −8.8 K, plus 0.5; it was within 6 K with the earlier 432 J/K
/// frame, which kept the eclipses warm and the sunlit phase cold) and the whole
/// orbits' within 10 K.
#[test]
fn val_inject_funcube_model_reproduces_the_flight_day() {
    let Some(g) = generator() else { return };
    let sim = g.simulate_rows(&Effect::None);
    let whole_orbits_end = g.env.eclipses.entry0_s
        + g.env.eclipses.period_s
            * ((g.telemetry.times_s.last().unwrap() - g.env.eclipses.entry0_s)
                / g.env.eclipses.period_s)
                .floor();
    for (s, sensor) in g.craft.sensors.iter().enumerate() {
        let data = g.telemetry.values(g.telemetry.column(&sensor.column));
        let (mut model, mut flight, mut eclipse, mut sunlit, mut orbits) =
            (vec![], vec![], vec![], vec![], vec![]);
        for (k, d) in data.iter().enumerate() {
            let Some(d) = *d else { continue };
            let (m, t) = (sim.channels_c[s][k], g.telemetry.times_s[k]);
            model.push(m);
            flight.push(d);
            if g.env.eclipses.sunlit(t) {
                sunlit.push(m - d);
            } else {
                eclipse.push(m - d);
            }
            if (g.env.eclipses.entry0_s..whole_orbits_end).contains(&t) {
                orbits.push(m - d);
            }
        }
        let diff: Vec<f64> = model.iter().zip(&flight).map(|(m, d)| m - d).collect();
        let (e_rms, corr) = (rms(&diff), correlation(&model, &flight));
        let (e_ecl, e_sun, e_orbits) = (mean(&eclipse), mean(&sunlit), mean(&orbits));
        eprintln!(
            "{:<17} RMS {e_rms:5.2} K  corr {corr:.3}  mean (model − flight): eclipse {e_ecl:+5.2}, sunlit {e_sun:+6.2}, whole orbits {e_orbits:+6.2} K",
            sensor.name
        );
        let bound = FLIGHT_RMS_BOUND_K
            .iter()
            .find(|b| b.0 == sensor.name)
            .unwrap()
            .1;
        assert!(e_rms <= bound, "{}: RMS {e_rms} > {bound}", sensor.name);
        assert!(corr >= 0.97, "{}: correlation {corr}", sensor.name);
        assert!(e_ecl.abs() <= 9.3, "{}: eclipse bias {e_ecl}", sensor.name);
        assert!(
            (e_ecl - e_sun).abs() <= 3.0,
            "{}: eclipse {e_ecl} against sunlit {e_sun}",
            sensor.name
        );
        assert!(
            (-12.0..=-4.0).contains(&e_sun),
            "{}: sunlit {e_sun}",
            sensor.name
        );
        assert!(e_orbits.abs() <= 10.0, "{}: {e_orbits}", sensor.name);
    }
}

/// The eclipse windows the model uses (a periodic fit to the photo-current) against
/// the data and the TLE: every observed transition within 60 s of its window (the rows
/// are a minute apart), the period within 10 s of the TLE's 1/n, β (from the eclipse
/// length) within 1° of β from the TLE's plane, the eclipse fraction 0.29 … 0.31.
#[test]
fn val_inject_funcube_eclipses_fit_the_photo_current_and_the_tle() {
    let Some(g) = generator() else { return };
    let e = &g.env.eclipses;
    let worst = e.residuals_s.iter().fold(0.0f64, |a, r| a.max(r.abs()));
    let tle_period = 86_400.0 / inject::environment::mean_motion_rev_per_day(&g.craft.tle);
    let noon = inject::telemetry::unix_s("2016-02-04T12:00:00Z");
    let beta_tle = inject::environment::beta_from_tle_rad(&g.craft.tle, noon).to_degrees();
    let beta = g.env.beta_rad.to_degrees();
    let fraction = e.duration_s() / e.period_s;
    eprintln!(
        "{} transitions, worst {worst:.1} s off; period {:.1} s (TLE {tle_period:.1}); eclipse {:.0} s, fraction {fraction:.4}; β {beta:.2}° (TLE {beta_tle:.2}°)",
        e.residuals_s.len(),
        e.period_s,
        e.duration_s()
    );
    assert!(
        e.residuals_s.len() >= 20,
        "{} transitions",
        e.residuals_s.len()
    );
    assert!(worst <= 60.0, "a transition {worst} s off");
    assert!((e.period_s - tle_period).abs() <= 10.0);
    assert!((beta - beta_tle).abs() <= 1.0, "β {beta} vs {beta_tle}");
    assert!((0.29..=0.31).contains(&fraction), "fraction {fraction}");
}

/// The suite's model against orbitlash's own run of the same scenario (through the
/// binary, `run --csv`: node temperatures every minute), from the third orbit on
/// (orbitlash starts at the initial temperatures at 00:00, this model four orbits
/// earlier): two independent implementations of the same network, with different
/// eclipses (telemetry vs SGP4), albedo integrals and integrators, agree to 0.35 K
/// RMS and 2 K at worst (at eclipse entries and exits, about 25 s apart).
#[test]
fn val_inject_funcube_model_agrees_with_orbitlash_run() {
    let Some(g) = generator() else { return };
    let dir = common::tmpdir("inject-run");
    let csv = dir.join("run.csv");
    let scenario = inject::repo_root().join(inject::scenario::SCENARIO);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_orbitlash"))
        .arg("run")
        .arg(&scenario)
        .arg("--csv")
        .arg(&csv)
        .args(["--no-log", "--quiet"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", common::stderr(&out));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .filter(|r: &Vec<f64>| r[0] >= 2.0 * g.env.eclipses.period_s)
        .collect();
    let times: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let ours = g.simulate(&Effect::None, &times);
    for (i, name) in g.craft.net.names.iter().enumerate() {
        let col = header
            .iter()
            .position(|h| *h == format!("{name}_k"))
            .unwrap();
        let d: Vec<f64> = (0..rows.len())
            .map(|k| ours.run.states[k][i] - rows[k][col])
            .collect();
        let worst = d.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        eprintln!(
            "{name:<9} ours − orbitlash: RMS {:.3} K, worst {worst:.3} K, mean {:+.3} K",
            rms(&d),
            mean(&d)
        );
        assert!(rms(&d) <= 0.35 && worst <= 2.0, "{name}");
    }
}

/// Halving the RK4 step (2 s → 1 s) changes no channel by more than 1 mK, with a
/// cycling thermostat (its switches located by bisection) and a lag.
#[test]
fn val_inject_funcube_integrator_converges() {
    let Some(mut g) = generator() else { return };
    for case in cases() {
        let a = g.simulate_rows(&case.effect);
        g.step_s = 1.0;
        let b = g.simulate_rows(&case.effect);
        g.step_s = inject::thermal::STEP_S;
        let worst = a
            .channels_c
            .iter()
            .zip(&b.channels_c)
            .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
            .fold(0.0f64, f64::max);
        eprintln!("{:<21} 2 s vs 1 s: worst {worst:.2e} K", case.name);
        assert!(worst < 1e-3, "{}: {worst}", case.name);
    }
}

/// The case's signature, and the measured-row values of channel `s` of it.
fn signature_of(g: &Generator, name: &str) -> (Effect, Vec<Vec<f64>>) {
    let case = cases().into_iter().find(|c| c.name == name).unwrap();
    let sig = g.signature(&case.effect);
    (case.effect, sig)
}

/// Null, offset and drift: exactly zero, exactly the constant on one channel, exactly
/// the ramp on one channel.
#[test]
fn val_inject_funcube_sensor_signatures_are_exact() {
    let Some(g) = generator() else { return };
    let (_, null) = signature_of(&g, "null");
    assert!(null.iter().flatten().all(|x| *x == 0.0));
    let (_, offset) = signature_of(&g, "chassis_offset");
    let target = g.craft.sensor("chassis_black_c");
    for (s, v) in offset.iter().enumerate() {
        let want = if s == target { 1.5 } else { 0.0 };
        assert!(v.iter().all(|x| (x - want).abs() < 1e-12), "sensor {s}");
    }
    let (_, drift) = signature_of(&g, "control");
    let target = g.craft.sensor("panel_my_c");
    for (s, v) in drift.iter().enumerate() {
        for (x, t) in v.iter().zip(&g.telemetry.times_s) {
            let want = if s == target { 2.0 * t / 86_400.0 } else { 0.0 };
            assert!((x - want).abs() < 1e-9, "sensor {s} at {t}: {x}");
        }
    }
}

/// The lag: only its channel moves; over whole orbits its signature averages to ~0
/// (a first-order lag keeps the mean of a periodic signal); its RMS grows with τ.
#[test]
fn val_inject_funcube_lag_signature() {
    let Some(g) = generator() else { return };
    let target = g.craft.sensor("panel_mx_c");
    let e = &g.env.eclipses;
    let times: Vec<f64> = (0..(10.0 * e.period_s / 10.0) as usize)
        .map(|k| e.entry0_s + 10.0 * k as f64)
        .collect();
    let mut last = 0.0;
    for tau_s in [100.0, 300.0, 600.0] {
        let effect = Effect::SensorLag {
            channel: "panel_mx_c",
            tau_s,
        };
        let with = g.simulate(&effect, &times);
        let without = g.simulate(&Effect::None, &times);
        let d: Vec<Vec<f64>> = (0..g.craft.sensors.len())
            .map(|s| {
                let (a, b) = (&with.channels_c[s], &without.channels_c[s]);
                a.iter().zip(b).map(|(x, y)| x - y).collect()
            })
            .collect();
        for (s, v) in d.iter().enumerate().filter(|(s, _)| *s != target) {
            assert!(v.iter().all(|x| *x == 0.0), "sensor {s} moved");
        }
        let (m, r) = (mean(&d[target]), rms(&d[target]));
        eprintln!("lag τ = {tau_s} s: signature RMS {r:.3} K, mean over 10 orbits {m:+.4} K");
        assert!(m.abs() < 0.02 * r.max(1.0), "mean {m}");
        assert!(r > 1.3 * last, "RMS {r} after {last}");
        last = r;
    }
}

/// The heater: it cycles (duty in (0.05, 0.6), at least one on and one off per
/// orbit), switches where the node crosses its set points, and only warms (the network
/// is monotone: more heat, no node colder).
#[test]
fn val_inject_funcube_heater_cycles() {
    let Some(g) = generator() else { return };
    let (effect, sig) = signature_of(&g, "heater");
    let sim = g.simulate_rows(&effect);
    let (duty, per_orbit) = g.heater_duty(&sim);
    eprintln!("heater: duty {duty:.3}, {per_orbit:.2} switches per orbit");
    assert!((0.05..0.6).contains(&duty), "duty {duty}");
    assert!(per_orbit >= 1.9, "{per_orbit} switches per orbit");
    assert!(sig.iter().flatten().all(|x| *x >= -1e-9));
    let Effect::Heater { on_c, off_c, .. } = effect else {
        unreachable!()
    };
    // at each switch, the thermostat reads the set point it crossed (located to 1 ms):
    // the chassis' flight temperature plus the heater's own signature
    let chassis = g.craft.net.index("chassis");
    let flight_minus_model = g.flight_minus_model("chassis");
    let times: Vec<f64> = sim.run.switches.iter().map(|s| s.0).collect();
    let at = g.simulate(&effect, &times);
    for ((t, _, on), y) in sim.run.switches.iter().zip(&at.run.states) {
        let want = if *on { on_c } else { off_c };
        let got = y[chassis] + flight_minus_model.at(*t) - inject::ZERO_C_K;
        assert!((got - want).abs() < 2e-3, "switch at {t}: {got} vs {want}");
    }
    // the same from the written recording, without the table: the chassis sensors'
    // mean (flight plus signature), interpolated between the measured rows around each
    // switch, is at the set point (to what 60 s rows resolve of a heater's kink)
    let sensors = g.node_sensors("chassis");
    let reads: Vec<Option<f64>> = (0..g.telemetry.rows.len())
        .map(|j| {
            let v: Option<Vec<f64>> = sensors
                .iter()
                .map(|(k, flight)| flight[j].map(|x| x + sig[*k][j]))
                .collect();
            v.map(|v| v.iter().sum::<f64>() / v.len() as f64)
        })
        .collect();
    let rows: Vec<(f64, f64)> = g
        .telemetry
        .times_s
        .iter()
        .zip(&reads)
        .filter_map(|(t, r)| r.map(|r| (*t, r)))
        .collect();
    let mut checked = 0;
    for (t, _, on) in sim.run.switches.iter().filter(|s| s.0 >= rows[0].0) {
        let k = rows.partition_point(|r| r.0 <= *t);
        if k == 0 || k == rows.len() || rows[k].0 - rows[k - 1].0 > 90.0 {
            continue;
        }
        let ((t0, r0), (t1, r1)) = (rows[k - 1], rows[k]);
        let read = r0 + (t - t0) / (t1 - t0) * (r1 - r0);
        let want = if *on { on_c } else { off_c };
        assert!(
            (read - want).abs() < 0.25,
            "switch at {t}: the recording reads {read:.3} °C, set point {want}"
        );
        checked += 1;
    }
    assert!(
        checked >= 10,
        "only {checked} switches between measured rows"
    );
}

/// The switched dissipation: exactly zero before the switch, positive on every channel
/// an orbit after it and growing.
#[test]
fn val_inject_funcube_switched_dissipation_signature() {
    let Some(g) = generator() else { return };
    let (effect, sig) = signature_of(&g, "switched_dissipation");
    let Effect::SwitchedDissipation { switch_utc, .. } = effect else {
        unreachable!()
    };
    let t_on = g.time_of(switch_utc);
    let p = g.env.eclipses.period_s;
    for v in &sig {
        for (x, t) in v.iter().zip(&g.telemetry.times_s) {
            if *t <= t_on {
                assert_eq!(*x, 0.0, "at {t}");
            } else if *t > t_on + p {
                assert!(*x > 0.3, "{x} at {t}");
            }
        }
        let late = |a: f64| {
            let w: Vec<f64> = v
                .iter()
                .zip(&g.telemetry.times_s)
                .filter(|(_, t)| (t_on + a * p..t_on + (a + 1.0) * p).contains(*t))
                .map(|(x, _)| *x)
                .collect();
            mean(&w)
        };
        assert!(late(2.0) > late(0.0), "{} vs {}", late(2.0), late(0.0));
    }
}

/// The absorptivity: α × 0.8 on +Y cools every channel and +Y's the most, more in
/// sunlight than in eclipse on +Y; α × 1.2 warms.
#[test]
fn val_inject_funcube_absorptivity_signature() {
    let Some(g) = generator() else { return };
    let target = g.craft.sensor("panel_py_c");
    for (scale, sign) in [(0.8, -1.0), (1.2, 1.0)] {
        let sig = g.signature(&Effect::AbsorptivityScale { face: "py", scale });
        assert!(sig.iter().flatten().all(|x| x * sign > 0.0), "α × {scale}");
        let means: Vec<f64> = sig.iter().map(|v| mean(v).abs()).collect();
        let largest = (0..means.len())
            .max_by(|&a, &b| means[a].total_cmp(&means[b]))
            .unwrap();
        assert_eq!(largest, target, "α × {scale}: {means:?}");
        let by_phase = |lit: bool| {
            let w: Vec<f64> = sig[target]
                .iter()
                .zip(&g.telemetry.times_s)
                .filter(|(_, t)| g.env.eclipses.sunlit(**t) == lit)
                .map(|(x, _)| x.abs())
                .collect();
            mean(&w)
        };
        eprintln!(
            "α × {scale} on py: +Y mean |signature| sunlit {:.3} K, eclipse {:.3} K",
            by_phase(true),
            by_phase(false)
        );
        assert!(by_phase(true) > by_phase(false));
    }
}

/// How much a case's signature may move (RMS of the change over its RMS) when the
/// environment is modelled differently. Linear effects move little; the lag's
/// signature is a shifted copy of its channel's slope, so moving the eclipses 30 s
/// moves it; a thermostat is not linear at all: when its node runs warmer or colder
/// it switches at other times, so its signature depends at first order on the
/// model's absolute temperature (see `expected.json`'s `truth` for the flight
/// chassis at the switching times).
const ROBUSTNESS: [(&str, f64); 7] = [
    ("heater", 0.30),
    ("switched_dissipation", 0.05),
    ("panel_lag", 0.12),
    ("chassis_lag", 0.12),
    ("chassis_offset", 0.0),
    ("face_absorptivity", 0.05),
    ("control", 0.0),
];

/// The signatures are differences, so the environment's own errors mostly cancel:
/// with the eclipse windows 30 s later, or the albedo halved (each about as large as
/// this model's own errors or larger), every signature moves by less than its bound
/// in [`ROBUSTNESS`] (printed).
#[test]
fn val_inject_funcube_signatures_robust_to_the_environment() {
    let Some(g) = generator() else { return };
    let perturbations = [
        ("eclipses 30 s later", 30.0, 1.0),
        ("albedo halved", 0.0, 0.5),
    ];
    for (what, shift_s, albedo) in perturbations {
        let mut env = g.env.clone();
        env.eclipses.entry0_s += shift_s;
        env.eclipses.exit0_s += shift_s;
        env.albedo *= albedo;
        let other = Generator {
            craft: g.craft.clone(),
            env,
            telemetry: g.telemetry.clone(),
            step_s: g.step_s,
        };
        for case in cases().into_iter().filter(|c| c.effect != Effect::None) {
            let (a, b) = (g.signature(&case.effect), other.signature(&case.effect));
            let d: Vec<f64> = a
                .iter()
                .flatten()
                .zip(b.iter().flatten())
                .map(|(x, y)| x - y)
                .collect();
            let ratio = rms(&d) / rms(&a.concat());
            eprintln!(
                "{what:<20} {:<21} signature change {:4.1} % of its RMS",
                case.name,
                100.0 * ratio
            );
            let bound = ROBUSTNESS.iter().find(|r| r.0 == case.name).unwrap().1;
            assert!(ratio <= bound + 1e-12, "{what}: {}: {ratio}", case.name);
        }
    }
}

/// Every written recording against the flight file: the same header and time stamps
/// (as text), the same number of rows and columns as CSV; on measured rows every
/// temperature cell is the flight value plus the signature to the file's 0.01
/// (±0.005), every other cell as written; fill rows repeat the row before; the fill
/// the recording reader sees is unchanged. The null case is the flight file byte for
/// byte.
#[test]
fn val_inject_funcube_recordings_differ_by_the_signature() {
    let Some(g) = generator() else { return };
    let original = std::fs::read_to_string(common::shared(WOD).unwrap()).unwrap();
    for case in cases() {
        let sig = g.signature(&case.effect);
        let text = g.recording(&sig);
        if case.effect == Effect::None {
            assert_eq!(text, original, "the null case must be the flight file");
        }
        let mut reader = csv::Reader::from_reader(text.as_bytes());
        let header: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
        assert_eq!(header, g.telemetry.header);
        let rows: Vec<Vec<String>> = reader
            .records()
            .map(|r| r.unwrap().iter().map(String::from).collect())
            .collect();
        assert_eq!(rows.len(), g.telemetry.rows.len());
        let signed: Vec<(usize, usize)> = g
            .craft
            .sensors
            .iter()
            .enumerate()
            .map(|(s, sensor)| (g.telemetry.column(&sensor.column), s))
            .collect();
        for (k, (new, old)) in rows.iter().zip(&g.telemetry.rows).enumerate() {
            assert_eq!(new[0], old[0], "{}: time stamp of row {k}", case.name);
            if g.telemetry.fill[k] {
                assert_eq!(new[1..], rows[k - 1][1..], "{}: fill row {k}", case.name);
                continue;
            }
            for c in 1..new.len() {
                match signed.iter().find(|x| x.0 == c) {
                    Some(&(_, s)) => {
                        let (n, o): (f64, f64) = (new[c].parse().unwrap(), old[c].parse().unwrap());
                        let err = (n - o - sig[s][k]).abs();
                        assert!(
                            err <= 0.005 + 1e-9,
                            "{}: row {k} column {c}: {err}",
                            case.name
                        );
                        assert_eq!(new[c].split('.').nth(1).map(str::len), Some(2));
                    }
                    None => assert_eq!(new[c], old[c], "{}: row {k} column {c}", case.name),
                }
            }
        }
        let fill = (1..rows.len())
            .filter(|&k| rows[k][1..] == rows[k - 1][1..])
            .count();
        assert_eq!(fill, 226, "{}: fill rows", case.name);
    }
}

/// The effect ids of `docs/vocabulary.md` an expected finding may name.
const VOCABULARY: [&str; 17] = [
    "earth_albedo_ir",
    "heater_thermostat",
    "internal_dissipation",
    "housing_expansion",
    "cte_temperature",
    "bore_fit",
    "sensor_lag",
    "sensor_offset",
    "absorptivity_scale",
    "conductance_scale",
    "cte_scale",
    "capacitance_scale",
    "emissivity_scale",
    "uncertain_parameter",
    "switched_dissipation",
    "sunlight_scale",
    "infrared_scale",
];

/// Each `expected.json` names an effect of the vocabulary (or `none`), a target the
/// scenario has (node, channel or face), its true parameters with a tolerance each, and
/// the channels its signature moves.
#[test]
fn val_inject_funcube_expected_files_name_what_the_scenario_has() {
    let Some(g) = generator() else { return };
    for case in cases() {
        let sig = g.signature(&case.effect);
        let doc = g.expected(&case, &sig);
        let effect = doc["effect"].as_str().unwrap();
        assert!(effect == "none" || VOCABULARY.contains(&effect), "{effect}");
        let params = doc["parameters"].as_object().unwrap();
        let tolerances = doc["tolerances"].as_object().unwrap();
        assert_eq!(
            params.keys().collect::<Vec<_>>(),
            tolerances.keys().collect::<Vec<_>>()
        );
        if let Some(n) = doc.get("node") {
            g.craft.net.index(n.as_str().unwrap());
        }
        if let Some(c) = doc.get("channel") {
            g.craft.sensor(c.as_str().unwrap());
        }
        if let Some(f) = doc.get("face") {
            g.craft.net.face(f.as_str().unwrap());
        }
        let moved = doc["channels"].as_array().unwrap().len();
        assert_eq!(moved == 0, case.effect == Effect::None, "{}", case.name);
    }
}

/// Writes every case into `target/inject/<case>/` (`recording.csv`, `expected.json`)
/// for a human: `orbitlash diagnose scenarios/funcube-1.toml --recording
/// target/inject/heater/recording.csv --json heater.json`.
#[test]
#[ignore = "writes target/inject for a human; run with --ignored"]
fn val_inject_funcube_write_cases() {
    let Some(g) = generator() else { return };
    let dir = inject::repo_root().join("target/inject");
    for folder in g.write_cases(&dir).unwrap() {
        eprintln!("wrote {}", folder.display());
    }
}

/// Scores `orbitlash diagnose` on every case and on the untouched day: prints a table
/// (expected against found, hit or miss, parameter errors against their tolerances)
/// and writes it to `target/inject/score.md`. Reports, does not assert: the
/// diagnose improvements it measures are being built. `INJECT_DIAGNOSE_ARGS` adds
/// arguments to every diagnose run (e.g. `--max-effects 4`).
#[test]
#[ignore = "runs diagnose on every case (a few minutes); run with --ignored --nocapture"]
fn val_inject_funcube_diagnose_score() {
    let Some(g) = generator() else { return };
    let dir = inject::repo_root().join("target/inject");
    g.write_cases(&dir).unwrap();
    let flight = common::shared(WOD).unwrap();
    let table = inject::score::score_all(&dir, &flight);
    eprintln!("{table}");
    std::fs::write(dir.join("score.md"), &table).unwrap();
}

/// The operator workflow (README, "Two workflows"): the untouched day diagnosed with
/// `--out D` writes a calibrated `D/corrected.toml`; a later recording diagnosed
/// against it with `--no-calibration` names what changed, and only that. Here the
/// later recordings are the day with a 1.5 K offset on the black chassis channel
/// (found, within ±0.5 K, and nothing else new), with face +Y's absorptivity × 0.8
/// (found within ±20 %, and nothing else new: a thermostat on the frame whose band
/// ends on its floor in the final joint fit once took 4.1 W and pulled the scale to
/// × 0.45) and with a drift outside the vocabulary (nothing named).
#[test]
fn val_inject_funcube_workflow_names_what_changed() {
    let Some(g) = generator() else { return };
    let dir = inject::repo_root().join("target/inject-workflow");
    let _ = std::fs::remove_dir_all(&dir);
    g.write_cases(&dir).unwrap();
    let flight = common::shared(WOD).unwrap();
    let shipped = inject::repo_root().join(inject::scenario::SCENARIO);
    let day_dir = dir.join("day");
    let (day, _) =
        inject::score::run_diagnose(&shipped, &flight, &dir.join("day.json"), Some(&day_dir));
    // diagnose.mcap of a dated scenario is on UTC log time (viewers show dates): its
    // first message at the recording's start, 2016-02-04T00:00:00Z or after
    let bytes = std::fs::read(day_dir.join("diagnose.mcap")).unwrap();
    let first = mcap::MessageStream::new(&bytes)
        .unwrap()
        .next()
        .unwrap()
        .unwrap();
    assert!(
        first.log_time >= 1_454_544_000_000_000_000 && first.log_time < 1_454_630_400_000_000_000,
        "diagnose.mcap's first log time {} ns is not on 2016-02-04 UTC",
        first.log_time
    );
    let corrected = day_dir.join("corrected.toml");
    let text = std::fs::read_to_string(&corrected).expect("diagnose --out wrote corrected.toml");
    assert!(
        text.contains("# calibrated: sunlight_scale on the spacecraft"),
        "corrected.toml names its calibration in its header"
    );
    assert!(
        day["calibration"].as_array().is_some_and(|c| !c.is_empty()),
        "the day is calibrated"
    );
    let run = |case: &str| {
        inject::score::run_diagnose_with(
            &corrected,
            &dir.join(case).join("recording.csv"),
            &dir.join(format!("{case}.json")),
            &["--no-calibration"],
        )
        .0
    };
    let named = |r: &serde_json::Value| -> Vec<(String, String, f64)> {
        r["findings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| {
                let on = f["channel"].as_str().or(f["node"].as_str()).unwrap_or("");
                let share = f["heldout_share"].as_f64().unwrap();
                (
                    f["effect"].as_str().unwrap().to_string(),
                    on.to_string(),
                    share,
                )
            })
            .collect()
    };
    let again = named(&run("null"));
    // the parameters of the finding of `effect` whose `key` is `on` in `report`
    let parameters = |report: &serde_json::Value, effect: &str, key: &str, on: &str| {
        report["findings"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["effect"] == effect && f[key] == on)
            .unwrap_or_else(|| panic!("{effect} on {on} is named: {:?}", named(report)))
            ["parameters"]
            .clone()
    };
    // besides the findings `is_it` picks, nothing new (not named on the null case)
    // takes 3 % of the residual or more
    type Named = (String, String, f64);
    let nothing_else_new = |found: &[Named], is_it: &dyn Fn(&Named) -> bool, what: &str| {
        let news: Vec<_> = found
            .iter()
            .filter(|f| !is_it(f))
            .filter(|f| !again.iter().any(|a| a.0 == f.0 && a.1 == f.1))
            .collect();
        assert!(
            news.iter().all(|f| f.2 < 0.03),
            "besides {what}, nothing new above 3 % of the residual: {news:?}"
        );
    };
    let offset = run("chassis_offset");
    let found = named(&offset);
    let k = parameters(&offset, "sensor_offset", "channel", "chassis_black_c")["offset_k"]
        .as_f64()
        .unwrap();
    assert!((k - 1.5).abs() <= 0.5, "offset {k} K, truth 1.5 K");
    assert_eq!(found[0].0, "sensor_offset", "the offset leads: {found:?}");
    let is_it = |f: &Named| f.0 == "sensor_offset" && f.1 == "chassis_black_c";
    nothing_else_new(&found, &is_it, "the offset");
    let alpha = run("face_absorptivity");
    let scale = parameters(&alpha, "absorptivity_scale", "face", "py")["scale"]
        .as_f64()
        .unwrap();
    assert!((scale / 0.8 - 1.0).abs() <= 0.2, "scale {scale}, truth 0.8");
    let is_it = |f: &Named| f.0 == "absorptivity_scale";
    nothing_else_new(&named(&alpha), &is_it, "the absorptivity");
    let control = named(&run("control"));
    let news: Vec<_> = control
        .iter()
        .filter(|f| !again.iter().any(|a| a.0 == f.0 && a.1 == f.1))
        .collect();
    assert!(
        news.is_empty(),
        "a drift outside the vocabulary names nothing new: {news:?}"
    );
}

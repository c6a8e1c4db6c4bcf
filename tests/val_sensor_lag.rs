//! Sensors with a first-order lag (τ dS/dt = T − S) and an offset, checked against
//! closed forms and a second numerical method.

use orbitlash::io::scenario_toml;
use orbitlash::run::sample::Cadence;
use orbitlash::run::sensor::{Readings, Sensor, SensorTarget, lag_over};
use orbitlash::run::sim::simulate;
use orbitlash::run::summary::Samples;

/// A ramp T(t) = a + b t from S0: S(t) = T(t) − τ b + (S0 − a + τ b) e^{−t/τ}.
#[test]
fn val_closed_form_lag_of_a_ramp() {
    let (a, rate, s0, h): (f64, f64, f64, f64) = (250.0, 0.01, 245.0, 300.0);
    for tau in [0.03, 1.0, 100.0, 149.0, 151.0, 600.0, 3e4, 8.64e4] {
        let exact = a + rate * h - tau * rate + (s0 - a + tau * rate) * (-h / tau).exp();
        let got = lag_over(s0, tau, h, [a, rate * h, 0.0, 0.0]);
        assert!(
            (got - exact).abs() < 1e-10,
            "τ = {tau}: {got} vs {exact} ({:e})",
            got - exact
        );
    }
    // no lag: the node's temperature; no time: the state
    assert_eq!(lag_over(s0, 0.0, h, [a, 3.0, 0.0, 0.0]), a + 3.0);
    assert_eq!(lag_over(s0, 60.0, 0.0, [a, 3.0, 0.0, 0.0]), s0);
}

/// A cubic forcing, integrated by classical RK4 with 20 000 steps.
#[test]
fn val_second_method_lag_of_a_cubic_matches_rk4() {
    let c = [280.0, -12.0, 30.0, -9.5];
    let (s0, h) = (275.0, 420.0);
    for tau in [5.0, 60.0, 209.0, 211.0, 900.0, 5e4] {
        let t_of = |t: f64| {
            let v = t / h;
            c[0] + v * (c[1] + v * (c[2] + v * c[3]))
        };
        let f = |t: f64, s: f64| (t_of(t) - s) / tau;
        let n = 20_000;
        let dt = h / n as f64;
        let mut s = s0;
        for k in 0..n {
            let t = k as f64 * dt;
            let k1 = f(t, s);
            let k2 = f(t + 0.5 * dt, s + 0.5 * dt * k1);
            let k3 = f(t + 0.5 * dt, s + 0.5 * dt * k2);
            let k4 = f(t + dt, s + dt * k3);
            s += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        let got = lag_over(s0, tau, h, c);
        assert!((got - s).abs() < 1e-9, "τ = {tau}: {got} vs RK4 {s}");
    }
}

/// Through a run: the lagged housing thermistor read by the library equals the lag
/// integrated independently from the temperatures sampled every second (exact for the
/// straight line between samples); it differs from the unlagged reading by kelvins, so
/// the comparison means something. The offset shifts the reading exactly.
#[test]
fn val_second_method_lagged_sensor_through_a_run() {
    let sc = scenario_toml::reference();
    let housing = sc.thermal.network.node_index("housing").unwrap();
    let tau = 600.0;
    let sensors = vec![
        Sensor::new("housing_c", SensorTarget::Node(housing)),
        Sensor {
            tau_s: tau,
            ..Sensor::new("housing_lagged_c", SensorTarget::Node(housing))
        },
        Sensor {
            offset_k: 1.25,
            ..Sensor::new("housing_offset_k", SensorTarget::Node(housing))
        },
    ];
    let t_end = 2.0 * 5560.0;
    let mut readings = Readings::new(sensors, Cadence::Interval(30.0));
    let mut fine = Samples::every(1.0);
    simulate(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        t_end,
        &mut (&mut readings, &mut fine),
        None,
    )
    .unwrap();

    // independent lag: exact over straight lines between the 1 s samples
    let mut s = fine.temps_k[0][housing];
    let mut lagged = vec![s];
    for w in fine.temps_k.windows(2).zip(fine.times_s.windows(2)) {
        let ((a, b), (t0, t1)) = ((w.0[0][housing], w.0[1][housing]), (w.1[0], w.1[1]));
        let (dt, rate) = (t1 - t0, (b - a) / (t1 - t0));
        s = b - tau * rate + (s - a + tau * rate) * (-dt / tau).exp();
        lagged.push(s);
    }
    let plain = readings.column("housing_c").unwrap();
    let lag = readings.column("housing_lagged_c").unwrap();
    let offset = readings.column("housing_offset_k").unwrap();
    let (mut worst, mut biggest_lag) = (0.0f64, 0.0f64);
    for (j, &t) in readings.times_s.iter().enumerate() {
        let i = t.round() as usize;
        assert_eq!(fine.times_s[i], t);
        let reference_c = lagged[i] - 273.15;
        worst = worst.max((lag[j] - reference_c).abs());
        biggest_lag = biggest_lag.max((lag[j] - plain[j]).abs());
        assert!((offset[j] - (plain[j] + 273.15 + 1.25)).abs() < 1e-9);
    }
    eprintln!("lag: worst difference {worst:.2e} K, largest lag effect {biggest_lag:.2} K");
    assert!(worst < 1e-3, "lagged sensor off by {worst} K");
    assert!(
        biggest_lag > 2.0,
        "the lag changed the reading by only {biggest_lag} K"
    );
}

/// Sampling at given times (a recording's) gives the numbers of sampling at an
/// interval, at the same times.
#[test]
fn core_times_and_interval_sampling_agree() {
    let sc = scenario_toml::reference();
    let t_end = 5560.0;
    let times: Vec<f64> = (0..=185).map(|k| k as f64 * 30.0).collect();
    let mut by_interval = Readings::new(sc.sensors.clone(), Cadence::Interval(30.0));
    let mut by_times = Readings::new(sc.sensors.clone(), Cadence::Times(times.clone().into()));
    simulate(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        t_end,
        &mut (&mut by_interval, &mut by_times),
        None,
    )
    .unwrap();
    assert_eq!(by_times.times_s, times);
    assert_eq!(by_interval.times_s, times);
    assert_eq!(by_interval.values, by_times.values);
}

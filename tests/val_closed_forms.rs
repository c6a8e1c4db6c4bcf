//! Thermal solver against closed-form solutions and published numbers.

mod common;

use common::scenario;
use orbitlash::constants::STEFAN_BOLTZMANN_W_PER_M2_K4;
use orbitlash::run::sim::{Event, EventKind, Observer, ObserverResult, SolverSettings, simulate};
use orbitlash::run::summary::Samples;
use std::f64::consts::PI;

const NO_ECLIPSE_ENV: &str = "beta_deg = 90.0\nspace_sink_k = 0.0";

fn run_samples(
    sc: &orbitlash::spec::scenario::Scenario,
    settings: &SolverSettings,
    t_end: f64,
    every: f64,
) -> Samples {
    let mut s = Samples::every(every);
    simulate(&sc.thermal, &sc.gears, settings, t_end, &mut s, None).unwrap();
    s
}

#[test]
fn val_closed_form_exponential_relaxation() {
    // C dT/dt = G (Tb − T): T = Tb + (T0 − Tb) exp(−G t / C)
    let (c, g, tb, t0) = (10.0, 0.5, 300.0, 400.0);
    let sc = scenario(
        "",
        NO_ECLIPSE_ENV,
        "duration_s = 200.0",
        &format!(
            "[[node]]\nname = \"n\"\ncapacitance_j_per_k = {c}\ninitial_temperature_k = {t0}\n\
             [[boundary]]\nname = \"b\"\ntemperature_k = {tb}\n\
             [[conductor]]\nbetween = [\"n\", \"b\"]\nconductance_w_per_k = {g}\n"
        ),
    );
    let exact = |t: f64| tb + (t0 - tb) * (-g * t / c).exp();
    let s = run_samples(&sc, &sc.solver, 200.0, 1.0);
    let err = s
        .times_s
        .iter()
        .zip(&s.temps_k)
        .map(|(&t, y)| (y[0] - exact(t)).abs())
        .fold(0.0, f64::max);
    assert!(
        err < 0.01,
        "adaptive run deviates {err} K from the closed form"
    );

    // Second order: halving a fixed step divides the error by ~4.
    let fixed = |h: f64| {
        let st = SolverSettings {
            adaptive: false,
            max_step_s: h,
            ..SolverSettings::default()
        };
        let s = run_samples(&sc, &st, 200.0, 8.0);
        s.times_s
            .iter()
            .zip(&s.temps_k)
            .map(|(&t, y)| (y[0] - exact(t)).abs())
            .fold(0.0, f64::max)
    };
    let (e1, e2, e3) = (fixed(4.0), fixed(2.0), fixed(1.0));
    for (a, b) in [(e1, e2), (e2, e3)] {
        let ratio = a / b;
        assert!(
            (3.5..4.5).contains(&ratio),
            "error ratio {ratio} ({a} / {b}) is not second order"
        );
    }
}

#[test]
fn val_closed_form_radiative_cooling() {
    // C dT/dt = −σ εA T⁴ (sink at 0 K): T = (T0⁻³ + 3σεA t / C)^(−1/3)
    let (c, ea, t0): (f64, f64, f64) = (50.0, 0.02, 400.0);
    let sc = scenario(
        "",
        NO_ECLIPSE_ENV,
        "duration_s = 20000.0",
        &format!(
            "[[node]]\nname = \"n\"\ncapacitance_j_per_k = {c}\ninitial_temperature_k = {t0}\n\
             [[radiation]]\nbetween = [\"n\", \"space\"]\nemissivity_area_m2 = {ea}\n"
        ),
    );
    let s = STEFAN_BOLTZMANN_W_PER_M2_K4;
    let exact = |t: f64| (t0.powi(-3) + 3.0 * s * ea * t / c).powf(-1.0 / 3.0);
    let max_err = |settings: &SolverSettings| {
        let out = run_samples(&sc, settings, 20000.0, 10.0);
        assert!(out.temps_k.last().unwrap()[0] < 200.0, "it did cool");
        out.times_s
            .iter()
            .zip(&out.temps_k)
            .map(|(&t, y)| (y[0] - exact(t)).abs())
            .fold(0.0, f64::max)
    };
    let err = max_err(&sc.solver);
    assert!(
        err < 0.05,
        "default settings deviate {err} K from the closed form"
    );
    let tight = SolverSettings {
        tolerance_k: 1e-4,
        ..sc.solver.clone()
    };
    let err_tight = max_err(&tight);
    // 20× tighter local tolerance: steps (20)^(1/3) shorter, global error ~7× smaller.
    assert!(
        err_tight < err / 5.0,
        "tolerance 1e-4 K deviates {err_tight} K, default {err} K"
    );
}

#[test]
fn val_published_black_sphere_settles_at_278_k() {
    // A black isothermal sphere at 1 AU absorbs S πr² and emits σ 4πr² T⁴:
    // T = (S / 4σ)^(1/4) ≈ 278 K for S = 1360 W/m² (Gilmore, Spacecraft Thermal Control
    // Handbook, vol. 1, ch. 2).
    let r: f64 = 0.1;
    let area = std::f64::consts::PI * r * r;
    let sc = scenario(
        "",
        "beta_deg = 90.0\nspace_sink_k = 0.0\nsolar_flux_w_per_m2 = 1360.0",
        "duration_s = 20000.0",
        &format!(
            "[[node]]\nname = \"sphere\"\ncapacitance_j_per_k = 200.0\ninitial_temperature_k = 200.0\n\
             [[radiation]]\nbetween = [\"sphere\", \"space\"]\nemissivity = 1.0\narea_m2 = {}\n\
             [[sun]]\nnode = \"sphere\"\nabsorptivity = 1.0\narea_m2 = {area}\n",
            4.0 * area
        ),
    );
    let stats = simulate(&sc.thermal, &sc.gears, &sc.solver, 20000.0, &mut (), None).unwrap();
    let t = stats.final_temperatures_k[0];
    let closed = (1360.0 / (4.0 * STEFAN_BOLTZMANN_W_PER_M2_K4)).powf(0.25);
    assert!(
        (t - 278.0).abs() < 0.5,
        "sphere settles at {t} K, published 278 K"
    );
    assert!(
        (t - closed).abs() < 1e-3,
        "sphere settles at {t} K, closed form {closed} K"
    );
}

#[test]
fn val_published_eclipse_example() {
    // R = 6370 km, h = 300 km, β = 0: period 5424 s, eclipse 40 % (≈ 2190 s)
    // (Wertz & Larson, Space Mission Analysis and Design, eclipse example).
    let sc = scenario(
        "altitude_m = 300e3\nearth_radius_m = 6370e3",
        "beta_deg = 0.0",
        "orbits = 3",
        "[[node]]\nname = \"n\"\ncapacitance_j_per_k = 1.0\ninitial_temperature_k = 300.0\n",
    );
    let orbit = &sc.thermal.environment.circular().unwrap().orbit;
    let period = orbit.period_s();
    assert!((period - 5424.0).abs() < 5.0, "period {period} s");
    let f = orbit.eclipse_fraction(0.0);
    assert!((f - 0.40).abs() < 0.005, "eclipse fraction {f}");
    assert!(
        (f * period - 2190.0).abs() < 5.0,
        "eclipse {} s",
        f * period
    );
    // The stepping loop sees the same eclipses as the formula.
    let stats = simulate(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        3.0 * period,
        &mut (),
        None,
    )
    .unwrap();
    assert_eq!(stats.eclipse_entries, 3);
    assert!((stats.eclipse_time_s / (3.0 * period) - f).abs() < 1e-9);
}

#[test]
fn val_reference_mechanism_period_and_eclipse() {
    let sc = orbitlash::io::scenario_toml::reference();
    let orbit = &sc.thermal.environment.circular().unwrap().orbit;
    assert!(
        (orbit.period_s() - 5676.978).abs() < 5e-4,
        "period {}",
        orbit.period_s()
    );
    let phi = orbit
        .eclipse_half_angle_rad(20f64.to_radians())
        .to_degrees();
    assert!((phi - 66.526).abs() < 5e-4, "half-angle {phi}");
    assert!((orbit.eclipse_fraction(20f64.to_radians()) - 0.36959).abs() < 5e-6);
    assert!((orbit.earth_view_factor() - 0.859896).abs() < 5e-7);
}

/// Collects event times.
#[derive(Default)]
struct Events(Vec<Event>);
impl Observer for Events {
    fn on_event(&mut self, e: &Event) -> ObserverResult {
        self.0.push(*e);
        Ok(())
    }
}

#[test]
fn val_closed_form_thermostat_cycle() {
    // One node losing heat through G to a boundary at Tb, heated by P between set points:
    // heating from T_on to T_off takes τ ln((T∞ − T_on)/(T∞ − T_off)), T∞ = Tb + P/G;
    // cooling back takes τ ln((T_off − Tb)/(T_on − Tb)); τ = C/G.
    let (c, g, tb, p, on, off): (f64, f64, f64, f64, f64, f64) =
        (100.0, 0.2, 250.0, 10.0, 270.0, 280.0);
    let sc = scenario(
        "",
        NO_ECLIPSE_ENV,
        "duration_s = 20000.0",
        &format!(
            "[[node]]\nname = \"n\"\ncapacitance_j_per_k = {c}\ninitial_temperature_k = 290.0\n\
             [[boundary]]\nname = \"b\"\ntemperature_k = {tb}\n\
             [[conductor]]\nbetween = [\"n\", \"b\"]\nconductance_w_per_k = {g}\n\
             [[heater]]\nnode = \"n\"\npower_w = {p}\non_k = {on}\noff_k = {off}\n"
        ),
    );
    let tau = c / g;
    let t_inf = tb + p / g;
    let heat = tau * ((t_inf - on) / (t_inf - off)).ln();
    let cool = tau * ((off - tb) / (on - tb)).ln();
    let first_on = tau * ((290.0 - tb) / (on - tb)).ln();
    // A tight tolerance, so that what is tested is where the steps land, not the
    // solution error (0.002 K at a slope of 0.04 K/s would move a switch by 0.05 s).
    let tight = SolverSettings {
        tolerance_k: 1e-5,
        ..sc.solver.clone()
    };
    let mut ev = Events::default();
    let stats = simulate(&sc.thermal, &sc.gears, &tight, 20000.0, &mut ev, None).unwrap();
    let switches: Vec<(f64, bool)> =
        ev.0.iter()
            .filter_map(|e| match e.kind {
                EventKind::HeaterOn(_) => Some((e.t_s, true)),
                EventKind::HeaterOff(_) => Some((e.t_s, false)),
                _ => None,
            })
            .collect();
    assert!(switches.len() >= 10, "{} switches", switches.len());
    assert_eq!(stats.heater_switches as usize, switches.len());
    assert!(
        switches[0].1 && (switches[0].0 - first_on).abs() < 0.05,
        "first on at {}",
        switches[0].0
    );
    for w in switches.windows(2) {
        let want = if w[0].1 { heat } else { cool };
        let got = w[1].0 - w[0].0;
        assert!(
            (got - want).abs() < 0.05,
            "phase lasted {got} s, closed form {want} s"
        );
    }
}

#[test]
fn val_closed_form_eclipse_duration_with_drifting_beta() {
    // β drifts 0° → 80° over 5 days: each eclipse lasts (2φ(β)/2π) T with β at its
    // middle, and eclipses stop once β passes arcsin(R/(R+h)).
    let sc = scenario(
        "",
        "beta_deg = { time_days = [0.0, 5.0], value = [0.0, 80.0] }",
        "duration_days = 5.0",
        "[[node]]\nname = \"n\"\ncapacitance_j_per_k = 1.0\ninitial_temperature_k = 300.0\n",
    );
    let env = sc.thermal.environment.circular().unwrap();
    let mut ev = Events::default();
    simulate(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        5.0 * 86400.0,
        &mut ev,
        None,
    )
    .unwrap();
    // Written out from reference-mechanism.md §2, not taken from the code: the period,
    // the eclipse half-angle φ(β) (cos φ = √((R+h)² − R²) / ((R+h) cos β)), the
    // critical β = asin(R/(R+h)) and the β table itself (0 → 80° over 5 days).
    let (r, a) = (
        env.orbit.earth_radius_m,
        env.orbit.earth_radius_m + env.orbit.altitude_m,
    );
    let period = 2.0 * PI * (a.powi(3) / env.orbit.mu_m3_per_s2).sqrt();
    let crit = (r / a).asin();
    let beta_at = |t_s: f64| (80f64 * t_s / (5.0 * 86400.0)).to_radians();
    let half_angle = |beta: f64| ((a * a - r * r).sqrt() / (a * beta.cos())).acos();
    let mut checked = 0;
    for w in ev.0.windows(2) {
        if let (EventKind::EclipseEntry, EventKind::EclipseExit) = (w[0].kind, w[1].kind) {
            let beta = beta_at(0.5 * (w[0].t_s + w[1].t_s));
            let want = half_angle(beta) / PI * period;
            let got = w[1].t_s - w[0].t_s;
            if beta < crit - 0.02 {
                assert!(
                    (got - want).abs() < 1.0,
                    "β {:.2}°: eclipse {got} s, closed form {want} s",
                    beta.to_degrees()
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 50, "{checked} eclipses checked");
    let last =
        ev.0.iter()
            .rfind(|e| e.kind == EventKind::EclipseExit)
            .unwrap();
    let beta_last = beta_at(last.t_s);
    assert!(
        beta_last <= crit + 1e-6,
        "eclipse at β {}°",
        beta_last.to_degrees()
    );
    assert!(
        crit - beta_last < 0.05,
        "eclipses stopped early, at β {}°",
        beta_last.to_degrees()
    );
}

#[test]
fn val_closed_form_orbit_averaged_environment_loads() {
    // Heat absorbed over one orbit at β = 20° (eclipse half-angle φ), per unit αA:
    //   tracking face  S T (1 − φ/π)
    //   zenith face    S T cos β / π                 (lit only on the day side)
    //   nadir face     S T cos β (1 − sin φ) / π     (lit between terminator and eclipse)
    //   albedo         S a F T cos β / π
    //   Earth IR       q F T
    let (s, albedo, q) = (1361.0, 0.3, 237.0);
    let sc = scenario(
        "",
        &format!(
            "beta_deg = 20.0\nsolar_flux_w_per_m2 = {s}\nalbedo = {albedo}\nearth_ir_w_per_m2 = {q}"
        ),
        "orbits = 1\n[solver]\nmax_step_s = 20.0\ntolerance_k = 1e-4",
        "[[node]]\nname = \"n\"\ncapacitance_j_per_k = 1e9\ninitial_temperature_k = 300.0\n",
    );
    let orbit = sc.thermal.environment.circular().unwrap().orbit.clone();
    // Period and view factor from their definitions (reference-mechanism.md §2).
    let a = orbit.earth_radius_m + orbit.altitude_m;
    let t = 2.0 * PI * (a.powi(3) / orbit.mu_m3_per_s2).sqrt();
    let f_view = (orbit.earth_radius_m / a).powi(2);
    let beta = 20f64.to_radians();
    // The eclipse half-angle from reference-mechanism.md §2, not from the code:
    // cos φ = √((R+h)² − R²) / ((R+h) cos β).
    let r = orbit.earth_radius_m;
    let phi = ((a * a - r * r).sqrt() / (a * beta.cos())).acos();
    let cases = [
        (
            "[[sun]]\nnode = \"n\"\nabsorptivity_area_m2 = 1.0\nincidence = \"tracking\"",
            s * t * (1.0 - phi / PI),
        ),
        (
            "[[sun]]\nnode = \"n\"\nabsorptivity_area_m2 = 1.0\nincidence = \"zenith\"",
            s * t * beta.cos() / PI,
        ),
        (
            "[[sun]]\nnode = \"n\"\nabsorptivity_area_m2 = 1.0\nincidence = \"nadir\"",
            s * t * beta.cos() * (1.0 - phi.sin()) / PI,
        ),
        (
            "[[albedo]]\nnode = \"n\"\nabsorptivity_area_m2 = 1.0",
            s * albedo * f_view * t * beta.cos() / PI,
        ),
        (
            "[[earth_ir]]\nnode = \"n\"\nemissivity_area_m2 = 1.0",
            q * f_view * t,
        ),
    ];
    for (load, want) in cases {
        let sc = scenario(
            "",
            &format!(
                "beta_deg = 20.0\nsolar_flux_w_per_m2 = {s}\nalbedo = {albedo}\nearth_ir_w_per_m2 = {q}"
            ),
            // Steps land on the terminator, where these loads have kinks; between kinks
            // the method integrates them to second order, ~(ωh)²/12 = 4e-5 at h = 20 s.
            "orbits = 1\n[solver]\nmax_step_s = 20.0\ntolerance_k = 1e-4",
            &format!(
                "[[node]]\nname = \"n\"\ncapacitance_j_per_k = 1e9\ninitial_temperature_k = 300.0\n{load}\n"
            ),
        );
        let stats = simulate(&sc.thermal, &sc.gears, &sc.solver, t, &mut (), None).unwrap();
        let got = stats.energy.absorbed_j;
        assert!(
            (got - want).abs() < 1e-4 * want,
            "{load}: {got} J, closed form {want} J"
        );
    }
}

#[test]
fn val_closed_form_boundary_ramp_and_scheduled_dissipation() {
    // A node coupled (G) to a boundary ramping at r K/s for 1000 s, then held:
    //   T(t) = T0 + r t − r τ (1 − e^{−t/τ}),  t ≤ 1000 s, τ = C/G;
    //   afterwards it relaxes to the held temperature.
    // A second node receives P W only in the mode window [500 s, 1500 s) and loses it
    // through G to a fixed boundary: T = Tb + (P/G)(1 − e^{−(t−500)/τ}) inside the window.
    let (c, g, t0, r, p) = (50.0f64, 0.5f64, 280.0f64, 0.02f64, 3.0f64);
    let tau = c / g;
    let sc = scenario(
        "",
        NO_ECLIPSE_ENV,
        "duration_s = 3000.0",
        &format!(
            "[[mode]]\nname = \"on\"\nwindows_s = [[500.0, 1500.0]]\n\
             [[node]]\nname = \"a\"\ncapacitance_j_per_k = {c}\ninitial_temperature_k = {t0}\n\
             [[node]]\nname = \"b\"\ncapacitance_j_per_k = {c}\ninitial_temperature_k = {t0}\n\
             [[boundary]]\nname = \"ramp\"\ntemperature_k = {{ time_s = [0.0, 1000.0], value = [{t0}, {}] }}\n\
             [[boundary]]\nname = \"fixed\"\ntemperature_k = {t0}\n\
             [[conductor]]\nbetween = [\"a\", \"ramp\"]\nconductance_w_per_k = {g}\n\
             [[conductor]]\nbetween = [\"b\", \"fixed\"]\nconductance_w_per_k = {g}\n\
             [[dissipation]]\nnode = \"b\"\npower_w = {p}\nwhen = \"on\"\n",
            t0 + r * 1000.0
        ),
    );
    let s = run_samples(&sc, &sc.solver, 3000.0, 10.0);
    let a_end = t0 + r * 1000.0 - r * tau * (1.0 - (-1000.0 / tau).exp());
    let exact_a = |t: f64| {
        if t <= 1000.0 {
            t0 + r * t - r * tau * (1.0 - (-t / tau).exp())
        } else {
            let held = t0 + r * 1000.0;
            held + (a_end - held) * (-(t - 1000.0) / tau).exp()
        }
    };
    let b_end = t0 + p / g * (1.0 - (-1000.0 / tau).exp());
    let exact_b = |t: f64| {
        if t < 500.0 {
            t0
        } else if t <= 1500.0 {
            t0 + p / g * (1.0 - (-(t - 500.0) / tau).exp())
        } else {
            t0 + (b_end - t0) * (-(t - 1500.0) / tau).exp()
        }
    };
    for (&t, y) in s.times_s.iter().zip(&s.temps_k) {
        assert!(
            (y[0] - exact_a(t)).abs() < 0.01,
            "ramped node at {t} s: {} vs {}",
            y[0],
            exact_a(t)
        );
        assert!(
            (y[1] - exact_b(t)).abs() < 0.01,
            "scheduled node at {t} s: {} vs {}",
            y[1],
            exact_b(t)
        );
    }
}

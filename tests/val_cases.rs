//! The recordings in `shared/cases` were made by an independent implementation of the
//! reference mechanism with one concealed effect each. With that effect added to our
//! scenario, every channel's residual must fall to the recording's noise (0.15 K on
//! temperatures, 0.3 µm on backlash); without it, the affected channels must not.
//! This validates our heater/thermostat, albedo and Earth-IR, and housing-expansion
//! physics against a second implementation.

mod common;

use orbitlash::io::scenario_toml::{REFERENCE_HINGE_TOML, parse};
use orbitlash::scenario::{Scenario, SensorTarget};
use orbitlash::sim::{Observer, ObserverResult, RunStart, StepView, simulate};
use orbitlash::units::k_to_c;

/// Sensor values (°C, µm) every 30 s.
struct Channels {
    sensors: Vec<(String, SensorTarget)>,
    rows: Vec<Vec<f64>>,
    temps: Vec<f64>,
}

impl Channels {
    fn row(&self, temps: &[f64], gears: &[orbitlash::gear::GearPair]) -> Vec<f64> {
        self.sensors
            .iter()
            .map(|(_, s)| match s {
                SensorTarget::Node(i) => k_to_c(temps[*i]),
                SensorTarget::Derived(_) => {
                    gears[0].evaluate(temps).unwrap().backlash_exact_m * 1e6
                }
            })
            .collect()
    }
}

impl Observer for Channels {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        self.temps = r.temps_k.to_vec();
        let row = self.row(r.temps_k, r.gears);
        self.rows.push(row);
        Ok(())
    }
    fn on_step(&mut self, s: &StepView<'_>) -> ObserverResult {
        loop {
            let t = self.rows.len() as f64 * 30.0;
            if t > s.t1_s() + 1e-9 {
                return Ok(());
            }
            let mut temps = std::mem::take(&mut self.temps);
            s.temperatures_at(t, &mut temps);
            let row = self.row(&temps, s.probe.gears());
            self.rows.push(row);
            self.temps = temps;
        }
    }
}

fn scenario(edits: &[(&str, &str)]) -> Scenario {
    let mut t = REFERENCE_HINGE_TOML.to_string();
    for (a, b) in edits {
        assert!(t.contains(a), "`{a}`");
        t = t.replacen(a, b, 1);
    }
    parse(&t, "<case scenario>").unwrap()
}

/// RMS residual per recording channel.
fn residual_rms(case: &str, sc: &Scenario) -> Vec<(String, f64)> {
    let rec = common::Recording::read(&common::shared(&format!("cases/{case}/recording.csv")));
    let time = rec.column("time_s");
    let t_end = time.iter().flatten().copied().fold(0.0, f64::max);
    let mut obs = Channels {
        sensors: sc
            .sensors
            .iter()
            .map(|s| (s.column.clone(), s.target.clone()))
            .collect(),
        rows: vec![],
        temps: vec![],
    };
    simulate(&sc.thermal, &sc.gears, &sc.solver, t_end, &mut obs, None).unwrap();
    obs.sensors
        .iter()
        .enumerate()
        .map(|(k, (name, _))| {
            let col = rec.column(name);
            let (mut s2, mut n) = (0.0, 0.0);
            for (t, v) in time.iter().zip(&col) {
                let (Some(t), Some(v)) = (t, v) else { continue };
                let r = v - obs.rows[(t / 30.0).round() as usize][k];
                s2 += r * r;
                n += 1.0;
            }
            (name.clone(), (s2 / n).sqrt())
        })
        .collect()
}

fn noise(channel: &str) -> f64 {
    if channel.ends_with("_um") { 0.3 } else { 0.15 }
}

/// With the effect, every channel sits at the noise; without it, `affected` does not.
fn check(case: &str, with: &Scenario, affected: &[&str]) {
    for (ch, rms) in residual_rms(case, with) {
        eprintln!("{case} with the effect: {ch} rms {rms:.3}");
        assert!(
            rms < 1.15 * noise(&ch),
            "{case}: {ch} residual {rms} with the effect added"
        );
    }
    let baseline = scenario(&[]);
    for (ch, rms) in residual_rms(case, &baseline) {
        eprintln!("{case} baseline: {ch} rms {rms:.3}");
        if affected.contains(&ch.as_str()) {
            assert!(
                rms > 3.0 * noise(&ch),
                "{case}: {ch} residual {rms} even without the effect"
            );
        }
    }
}

#[test]
fn val_cases_heater_thermostat() {
    let sc = scenario(&[(
        "[[sun]]",
        "[[heater]]\nnode = \"housing\"\npower_w = 4.0\non_k = 263.15\noff_k = 268.15\n\n[[sun]]",
    )]);
    check("heater", &sc, &["housing_c"]);
}

#[test]
fn val_cases_albedo_and_earth_ir() {
    let sc = scenario(&[
        ("# [[albedo]]", "[[albedo]]"),
        (
            "# node = \"housing\"                  # nadir face",
            "node = \"housing\"",
        ),
        (
            "# absorptivity_area_m2 = 0.007",
            "absorptivity_area_m2 = 0.007",
        ),
        (
            "# [[earth_ir]]\n# node = \"housing\"\n# emissivity_area_m2 = 0.0085",
            "[[earth_ir]]\nnode = \"housing\"\nemissivity_area_m2 = 0.0085",
        ),
    ]);
    check("albedo-ir", &sc, &["housing_c", "motor_c", "gear1_c"]);
}

#[test]
fn val_cases_housing_expansion() {
    let sc = scenario(&[(
        "min_backlash_um = 5.0               # interference margin threshold",
        "min_backlash_um = 5.0\n[gear_pair.center_distance]\nfollows = \"housing\"\nnode = \"housing\"\nalpha_per_k = 8.6e-6",
    )]);
    check("housing-expansion", &sc, &["backlash_um"]);
}

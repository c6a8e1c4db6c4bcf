//! The recordings in `shared/cases` were made by an independent implementation of the
//! reference mechanism with one concealed effect each. With that effect added to our
//! scenario, every channel's residual must fall to the recording's noise (0.15 K on
//! temperatures, 0.3 µm on backlash); without it, the affected channels must not.
//! This validates our heater/thermostat, albedo and Earth-IR, and housing-expansion
//! physics against a second implementation.

mod common;

use orbitlash::io::recording::Recording;
use orbitlash::io::scenario_toml;
use orbitlash::run::sample::Cadence;
use orbitlash::run::sensor::Readings;
use orbitlash::run::sim::simulate;
use orbitlash::spec::model::Model;
use orbitlash::spec::scenario::Scenario;

/// The reference scenario with `edit` made through the library's model API.
fn scenario(edit: impl FnOnce(&mut Model)) -> Scenario {
    let spec = scenario_toml::parse_spec(scenario_toml::REFERENCE_HINGE_TOML, "<reference>");
    let mut model = Model::new(spec.unwrap()).unwrap();
    edit(&mut model);
    model.scenario().clone()
}

/// RMS residual per recording channel: the scenario's sensors read at the recording's
/// own times (the library's recording reader and sensors).
fn residual_rms(case: &str, sc: &Scenario) -> Vec<(String, f64)> {
    let rec = Recording::read(
        &common::shared(&format!("cases/{case}/recording.csv")).expect("the test's guard"),
    )
    .unwrap();
    let sensor_of = rec.match_sensors(&sc.sensors).unwrap();
    let t_end = *rec.time_s.last().unwrap();
    let mut readings = Readings::new(
        sc.sensors.clone(),
        Cadence::Times(rec.time_s.clone().into()),
    );
    simulate(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        t_end,
        &mut readings,
        None,
    )
    .unwrap();
    assert_eq!(readings.times_s, rec.time_s);
    rec.columns
        .iter()
        .zip(&rec.values)
        .zip(&sensor_of)
        .map(|((name, recorded), &k)| {
            let (mut s2, mut n) = (0.0, 0.0);
            for (v, sim) in recorded.iter().zip(&readings.values[k]) {
                if let Some(v) = v {
                    s2 += (v - sim).powi(2);
                    n += 1.0;
                }
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
    let baseline = scenario(|_| {});
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

fn spec<T: serde::de::DeserializeOwned>(toml_text: &str) -> T {
    toml::from_str(toml_text).unwrap()
}

/// The recording with nothing concealed: the reference scenario as it is fits every
/// channel to the noise.
#[test]
fn val_cases_null_fits_to_the_noise() {
    let Some(_) = common::shared("cases") else {
        return;
    };
    for (ch, rms) in residual_rms("null", &scenario(|_| {})) {
        eprintln!("null: {ch} rms {rms:.3}");
        assert!(rms < 1.15 * noise(&ch), "null: {ch} residual {rms}");
    }
}

#[test]
fn val_cases_heater_thermostat() {
    let Some(_) = common::shared("cases") else {
        return;
    };
    let sc = scenario(|m| {
        m.add_heater(spec(
            "node = \"housing\"\npower_w = 4.0\non_k = 263.15\noff_k = 268.15",
        ))
        .unwrap()
    });
    check("heater", &sc, &["housing_c"]);
}

#[test]
fn val_cases_albedo_and_earth_ir() {
    let Some(_) = common::shared("cases") else {
        return;
    };
    let sc = scenario(|m| {
        m.modify(|s| {
            s.albedo
                .push(spec("node = \"housing\"\nabsorptivity_area_m2 = 0.007"));
            s.earth_ir
                .push(spec("node = \"housing\"\nemissivity_area_m2 = 0.0085"));
        })
        .unwrap()
    });
    check("albedo-ir", &sc, &["housing_c", "motor_c", "gear1_c"]);
}

#[test]
fn val_cases_housing_expansion() {
    let Some(_) = common::shared("cases") else {
        return;
    };
    let sc = scenario(|m| {
        m.modify(|s| {
            s.gear_pair[0].center_distance = Some(spec(
                "follows = \"housing\"\nnode = \"housing\"\nalpha_per_k = 8.6e-6",
            ))
        })
        .unwrap()
    });
    check("housing-expansion", &sc, &["backlash_um"]);
}

//! `diagnose` on the recordings of `shared/cases` (made by an independent
//! implementation of the reference mechanism, one concealed effect each, and one with
//! none), against their `expected.json`: the verdict, the effect and where it acts,
//! the fitted parameters within 20 % (set points within 1.5 K), and the held-out RMS
//! after the fit within 1.5 × the recording's noise on the affected channels.

mod common;

use orbitlash::diagnose::{Options, Verdict, diagnose};
use orbitlash::io::recording::Recording;
use orbitlash::io::scenario_toml::{REFERENCE_HINGE_TOML, parse_spec};
use orbitlash::spec::model::Model;
use serde_json::Value;

fn reference() -> Model {
    Model::new(parse_spec(REFERENCE_HINGE_TOML, "<reference>").unwrap()).unwrap()
}

fn expected(case: &str) -> Value {
    let p = common::shared(&format!("cases/{case}/expected.json")).expect("the test's guard");
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn run(case: &str) -> orbitlash::diagnose::Diagnosis {
    run_on(case, &reference())
}

fn run_on(case: &str, model: &Model) -> orbitlash::diagnose::Diagnosis {
    let rec = Recording::read(
        &common::shared(&format!("cases/{case}/recording.csv")).expect("the test's guard"),
    )
    .unwrap();
    diagnose(model, &rec, &Options::default(), &|_, _, _| {}).unwrap()
}

fn check_case(case: &str) {
    check_case_on(case, &reference());
}

fn check_case_on(case: &str, model: &Model) -> orbitlash::diagnose::Diagnosis {
    let exp = expected(case);
    let d = run_on(case, model);
    let verdict = exp["verdict"].as_str().unwrap();
    assert_eq!(
        d.verdict.as_str(),
        verdict,
        "{case}: {:#?}",
        d.candidates.iter().take(5).collect::<Vec<_>>()
    );
    // Whole orbits held out, never fitted: the last third of the twelve.
    assert_eq!((d.split.orbits, d.split.holdout_orbits), (12, 4), "{case}");
    let truth = &exp["truth"];
    let noise_of = |ch: &str| {
        if ch.ends_with("_um") {
            truth["noise_um"].as_f64().unwrap()
        } else {
            truth["noise_k"].as_f64().unwrap()
        }
    };
    // The estimated noise is the recording's.
    for (ch, sigma) in &d.noise.0 {
        let truth_sigma = noise_of(ch);
        assert!(
            (sigma / truth_sigma - 1.0).abs() < 0.15,
            "{case}: noise of {ch} estimated {sigma}, recorded with {truth_sigma}"
        );
    }
    if verdict == "consistent" {
        assert!(d.findings.is_empty(), "{case}: {:?}", d.findings);
        return d;
    }
    assert_eq!(d.findings.len(), 1, "{case}: {:?}", d.findings);
    let f = &d.findings[0];
    assert_eq!(f.effect, exp["effect"].as_str().unwrap(), "{case}");
    if let Some(node) = exp.get("node").and_then(Value::as_str) {
        assert_eq!(f.target.node().as_deref(), Some(node), "{case}");
    }
    if let Some(params) = exp.get("parameters").and_then(Value::as_object) {
        for (k, v) in params {
            let want = v.as_f64().unwrap();
            let got = f.parameters[k];
            if k.ends_with("_c") {
                assert!(
                    (got - want).abs() <= 1.5,
                    "{case}: {k} = {got}, expected {want} ± 1.5 K"
                );
            } else {
                assert!(
                    (got / want - 1.0).abs() <= 0.2,
                    "{case}: {k} = {got}, expected {want} ± 20 %"
                );
            }
            let se = f.std_errors[k].expect("a standard error");
            assert!(
                se > 0.0 && se < 0.2 * got.abs().max(1.0),
                "{case}: {k} ± {se}"
            );
        }
    }
    let channels: Vec<String> = match exp.get("channels").and_then(Value::as_array) {
        Some(a) => a.iter().map(|c| c.as_str().unwrap().to_string()).collect(),
        None => d.noise.0.iter().map(|(c, _)| c.clone()).collect(),
    };
    for ch in &channels {
        let after = d.heldout_rmse.get(ch).unwrap();
        let before = d.baseline.heldout_rmse.get(ch).unwrap();
        assert!(
            after <= 1.5 * noise_of(ch),
            "{case}: held-out RMS of {ch} after the fit {after} > 1.5 × {}",
            noise_of(ch)
        );
        assert!(after < before, "{case}: {ch} {after} !< {before}");
    }
    // The mismatches name every affected channel, in the expected phase if given.
    for ch in &channels {
        assert!(
            d.mismatches.iter().any(|m| &m.channel == ch),
            "{case}: no mismatch on {ch}"
        );
    }
    if let Some(phase) = exp.get("phase").and_then(Value::as_str) {
        assert!(
            d.mismatches.iter().any(|m| m.phase.starts_with(phase)),
            "{case}: no mismatch in {phase}: {:?}",
            d.mismatches
        );
    }
    d
}

#[test]
fn val_shared_cases_null_is_consistent() {
    let Some(_) = common::shared("cases") else {
        return;
    };
    check_case("null");
    assert_eq!(run("null").verdict, Verdict::Consistent);
}

#[test]
fn val_shared_cases_heater() {
    let Some(_) = common::shared("cases") else {
        return;
    };
    check_case("heater");
}

/// The heater case against a reference whose housing is 8 % too heavy (130 J/K where
/// the recording's mechanism has 120) and declared uncertain: the calibration finds the
/// mass and discovery the heater, as on the true model. The thermostat was started
/// where the wrong model's residual first warmed, in sunlight (+24 °C), and its fit
/// ended on a bound: a heater on the motor at 0 °C was named instead (black-box
/// helper-19).
#[test]
fn val_shared_cases_heater_after_an_uncertain_mass_is_calibrated() {
    let Some(_) = common::shared("cases") else {
        return;
    };
    let heavy = REFERENCE_HINGE_TOML.replacen(
        "capacitance_j_per_k = 120.0",
        "capacitance_j_per_k = 130.0",
        1,
    );
    assert_ne!(heavy, REFERENCE_HINGE_TOML);
    let text = format!(
        "{heavy}\n[[uncertain]]\npath = \"node.housing.capacitance_j_per_k\"\nmin = 90.0\nmax = 160.0\n"
    );
    let model = Model::new(parse_spec(&text, "<heavy housing>").unwrap()).unwrap();
    let d = check_case_on("heater", &model);
    let mass = &d.calibration[0];
    assert_eq!(
        mass.nominal.values().next(),
        Some(&130.0),
        "{:?}",
        d.calibration
    );
    let got = *mass.parameters.values().next().unwrap();
    assert!((got / 120.0 - 1.0).abs() < 0.02, "housing mass {got} J/K");
}

/// The heater case with its first two orbits cut off: a recording that starts while
/// the heater already cycles, as a flight recording does, the model run from the
/// scenario's t = 0 up to it. The thermostat's start was taken only where the
/// residual was back at zero, which in this recording is nowhere (the heater's tail
/// stays 0.15–0.2 K above it through the warm phase): no heater was tried and an
/// eclipse dissipation, a mass and a conductance were named instead. Its orbits keep
/// the scenario's numbers, and a third of those with data are held out.
#[test]
fn val_shared_cases_heater_in_a_recording_that_starts_late() {
    let Some(path) = common::shared("cases/heater/recording.csv") else {
        return;
    };
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let mut late = format!("{}\n", lines.next().unwrap());
    for l in lines {
        let t: f64 = l.split(',').next().unwrap().parse().unwrap();
        if t >= 11_400.0 {
            late.push_str(l);
            late.push('\n');
        }
    }
    // cut to its last orbit: too short, and said in its own orbits (it read "ends at
    // t = 68100 s, 12 whole orbit(s)": review helper-26)
    let last: String = late
        .lines()
        .enumerate()
        .filter(|(i, l)| {
            *i == 0 || l.split(',').next().unwrap().parse::<f64>().unwrap() >= 62_460.0
        })
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    let rec = Recording::from_csv(last.as_bytes(), "last.csv").unwrap();
    let e = diagnose(&reference(), &rec, &Options::default(), &|_, _, _| {})
        .expect_err("one orbit cannot be split")
        .to_string();
    assert!(
        e.contains("runs from t = 62460 to 68100 s, 1 whole orbit(s)"),
        "{e}"
    );
    let rec = Recording::from_csv(late.as_bytes(), "late.csv").unwrap();
    let d = diagnose(&reference(), &rec, &Options::default(), &|_, _, _| {}).unwrap();
    let s = &d.split;
    assert_eq!(
        (s.first_orbit, s.orbits, s.train_orbits, s.holdout_orbits),
        (2, 12, 9, 3),
        "{s:?}"
    );
    assert_eq!(
        (s.fitted_span(), s.held_span()),
        ("orbits 3–9".to_string(), "orbits 10–12".to_string())
    );
    assert_eq!(d.verdict, Verdict::Explained, "{:?}", d.findings);
    // its figures start where it does: they drew three hours of model alone first
    assert_eq!(d.series.figure_start_s(), 11_400.0);
    assert_eq!(d.series.model_time_s.first(), Some(&11_400.0));
    assert_eq!(d.findings.len(), 1, "{:?}", d.findings);
    let f = &d.findings[0];
    assert_eq!(f.effect, "heater_thermostat");
    assert_eq!(f.target.node().as_deref(), Some("housing"));
    let p = &f.parameters;
    assert!((p["power_w"] / 4.0 - 1.0).abs() < 0.1, "{p:?}");
    assert!((p["on_c"] + 10.0).abs() < 1.5, "{p:?}");
    assert!((p["off_c"] + 5.0).abs() < 1.5, "{p:?}");
}

#[test]
fn val_shared_cases_albedo_ir() {
    let Some(_) = common::shared("cases") else {
        return;
    };
    check_case("albedo-ir");
    // Effective albedo and IR on the housing's sun and space areas: the truth's
    // 0.30 × 0.007 m² / 0.0175 m² and 237 W/m² × 0.0085 m² / 0.030 m².
    let d = run("albedo-ir");
    let p = &d.findings[0].parameters;
    assert!(
        (p["albedo"] / (0.30 * 0.007 / 0.0175) - 1.0).abs() < 0.2,
        "{p:?}"
    );
    assert!(
        (p["earth_ir_w_per_m2"] / (237.0 * 0.0085 / 0.030) - 1.0).abs() < 0.2,
        "{p:?}"
    );
}

#[test]
fn val_shared_cases_housing_expansion() {
    let Some(_) = common::shared("cases") else {
        return;
    };
    check_case("housing-expansion");
}

//! One generated test over the table of quantities (`orbitlash::spec::quantity`): every
//! number of the shipped scenarios that has a quantity with a range is pushed just
//! below, at and just above each end of that range through the four ways a value
//! reaches a model — the TOML reader (the scenario file edited), `--set`
//! (`Model::set`), the fast write of a resolved parameter (`Model::set_param`) and the
//! dispersion check (`Plan::new` with the value as its only case). All four must agree:
//! accept, or refuse naming the same key with the same message; when accepted, the fast
//! write gives the same compiled model as the recompiled one. A value outside the
//! quantity's range must be refused (a value inside may still be refused by its
//! context, e.g. a heater's on_k above its off_k, as long as all four say so).

use orbitlash::io::scenario_toml::{ScenarioError, edited, parse, parse_spec};
use orbitlash::margins::dispersion::{Plan, PlanError, Sampling};
use orbitlash::spec::model::{Model, ModelError};
use orbitlash::spec::quantity::{Quantity, TABLE};
use orbitlash::spec::{DispersionSpec, ScenarioSpec, registry as params};

/// What one way made of a value: accepted, or refused with (key, message).
type Verdict = Result<(), (String, String)>;

fn of_model(r: Result<(), ModelError>) -> Verdict {
    match r {
        Ok(()) => Ok(()),
        Err(ModelError::Invalid(e)) => Err((e.key.to_string(), e.message)),
        Err(ModelError::Param(e)) => panic!("the path itself was refused: {e}"),
    }
}

fn through_toml(text: &str, spec: &ScenarioSpec, path: &str, v: f64) -> Verdict {
    let mut changed = spec.clone();
    params::set(&mut changed, path, v).unwrap();
    let text = edited(text, spec, &changed, &[], &|_, _| None).unwrap();
    match parse(&text, "q.toml") {
        Ok(_) => Ok(()),
        Err(ScenarioError::Invalid { key, message, .. }) => Err((key, message)),
        Err(e) => panic!("{path} = {v}: not a scenario error: {e}"),
    }
}

/// The dispersion check's verdict, reduced to the model's error it quotes.
fn through_dispersion(model: &Model, path: &str, v: f64) -> Result<(), String> {
    let d = DispersionSpec {
        path: path.to_string(),
        distribution: orbitlash::spec::DistributionName::Cases,
        values: Some(vec![v]),
        ..DispersionSpec::default()
    };
    match Plan::new(model, &[d], Sampling::Random, 1, 0) {
        Ok(_) => Ok(()),
        Err(PlanError::Spec(e)) => Err(e.message),
        Err(e) => panic!("{e}"),
    }
}

/// Values just below, at and just above each finite end of `[lo, hi]`.
fn probes(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    for end in [lo, hi] {
        if end.is_finite() {
            let eps = 1e-9 * end.abs().max(1.0);
            out.extend([end - eps, end, end + eps]);
        }
    }
    out
}

/// Checks every value of `file`'s numbers that have a ranged quantity; returns how many
/// values were checked and the quantities seen.
fn check_scenario(file: &str, text: &str) -> (usize, Vec<&'static Quantity>) {
    let spec = parse_spec(text, file).unwrap();
    let model = Model::new(spec.clone()).unwrap();
    let mut checked = 0;
    let mut seen = Vec::new();
    for p in model.params() {
        let q = p.quantity;
        seen.push(q);
        let Some((lo, _, hi, _)) = q.interval() else {
            continue;
        };
        for v in probes(lo, hi) {
            let what = format!("{file}: {} = {v:e} ({} {})", p.path, q.unit, q.range());
            let by_toml = through_toml(text, &spec, &p.path, v);
            let (mut set, mut fast) = (model.clone(), model.clone());
            let by_set = of_model(set.set(&p.path, v));
            let id = model.param(&p.path).unwrap();
            let by_param = of_model(fast.set_param(&id, v));
            if by_set.is_ok() && by_param.is_ok() {
                // the fast write lands where the compiler put the number
                assert!(
                    set.scenario() == fast.scenario(),
                    "{what}: set_param gives another model than --set"
                );
            }
            assert_eq!(by_set, by_toml, "{what}: --set vs the TOML file");
            assert_eq!(by_param, by_toml, "{what}: set_param vs the TOML file");
            let by_dispersion = through_dispersion(&model, &p.path, v);
            let recording = id.not_of_the_model();
            if let Some(why) = &recording {
                // how a recording is read: set, never dispersed
                assert_eq!(by_dispersion, Err(why.clone()), "{what}");
                assert!(why.contains("cannot be calibrated or dispersed"), "{why}");
            }
            match (&by_toml, &by_dispersion) {
                _ if recording.is_some() => {}
                (Ok(()), Ok(())) => {}
                (Err((key, message)), Err(quoted)) => assert!(
                    quoted.contains(&format!("`{key}`: {message}")),
                    "{what}: the dispersion check says `{quoted}`, the model `{key}`: {message}"
                ),
                _ => panic!("{what}: dispersion {by_dispersion:?} vs the TOML file {by_toml:?}"),
            }
            if !q.accepts(v) {
                let Err((key, _)) = &by_toml else {
                    panic!("{what}: outside the quantity's range, but accepted");
                };
                assert!(
                    p.path.ends_with(key.rsplit('.').next().unwrap()),
                    "{what}: refused at `{key}`, not at the key given"
                );
            }
            checked += 1;
        }
    }
    (checked, seen)
}

#[test]
fn core_every_quantity_bound_agrees_across_toml_set_set_param_and_dispersion() {
    let (mut checked, mut seen): (usize, Vec<&Quantity>) = (0, Vec::new());
    let read = |file: &str| {
        std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(file))
            .unwrap()
    };
    let reference = read("scenarios/reference-hinge.toml");
    // the reference with its first radiative link given as emissivity × area
    let spec = parse_spec(&reference, "r.toml").unwrap();
    let mut split = spec.clone();
    let r = &mut split.radiation[0];
    r.emissivity = Some(0.5);
    r.area_m2 = Some(2.0 * r.emissivity_area_m2.take().unwrap());
    // and the pinion's steel with a dα/dT
    split.gear_pair[0].pinion.material.dalpha_dt_per_k2 = Some(1e-9);
    let split_text = edited(&reference, &spec, &split, &[], &|_, _| None).unwrap();
    for (file, text) in [
        ("scenarios/reference-hinge.toml", reference.clone()),
        (
            "scenarios/hinge-90-day-drift.toml",
            read("scenarios/hinge-90-day-drift.toml"),
        ),
        ("reference-hinge with ε × A and a dα/dT", split_text),
        (
            "scenarios/hinge-tle-year.toml",
            read("scenarios/hinge-tle-year.toml"),
        ),
        (
            "scenarios/cubesat-1u.toml",
            read("scenarios/cubesat-1u.toml"),
        ),
        (
            "scenarios/funcube-1.toml",
            read("scenarios/funcube-1.toml"),
        ),
        (
            "cubesat-1u spinning",
            read("scenarios/cubesat-1u.toml").replacen(
                "mode = \"nadir\"\nyaw_deg = 0.0",
                "mode = \"spin\"\nspin_axis = [0.0, 0.0, 1.0]\nspin_rate_deg_per_s = 2.0\nspin_averaged = true",
                1,
            ),
        ),
    ] {
        let (n, q) = check_scenario(file, &text);
        checked += n;
        seen.extend(q);
    }
    assert!(checked > 500, "{checked} values checked");
    // every quantity of the table is exercised by these scenarios
    for (name, q) in TABLE {
        assert!(seen.contains(q), "{name} is not exercised");
    }
}

//! Parameters by key path (issue 9): every number of a scenario is listed, read and
//! written by its path; `--set` gives the output of the same edit made in the file;
//! a bad value gives the error the file would.

use std::path::Path;

mod common;
use common::{bin, reference_text, tmpdir};
use orbitlash::io::scenario_toml;
use orbitlash::spec::model::Model;

fn spec_of(file: &str) -> orbitlash::spec::ScenarioSpec {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(file);
    scenario_toml::read_spec_file(&path).unwrap().0
}

#[test]
fn cli_every_key_path_round_trips() {
    for file in ["reference-hinge.toml", "hinge-90-day-drift.toml"] {
        let mut model = Model::new(spec_of(file)).unwrap();
        let params = model.params();
        assert!(params.len() > 60, "{file}: {} parameters", params.len());
        let mut moved = 0;
        let mut stuck = Vec::new();
        for p in &params {
            let v = model.get(&p.path).unwrap_or_else(|e| panic!("{file}: {e}"));
            assert_eq!(v.to_bits(), p.value.to_bits(), "{}", p.path);
            // another valid value: it must land at this path and nowhere else (defaults
            // derived from it, such as view factors from the altitude, may follow)
            let Some(w) = [v * 1.001, v * 0.999, v + 1e-3, v - 1e-3, v + 1.0]
                .into_iter()
                .find(|&w| w != v && model.clone().set(&p.path, w).is_ok())
            else {
                stuck.push(p.path.clone());
                continue;
            };
            model
                .set(&p.path, w)
                .unwrap_or_else(|e| panic!("{file}: set {} = {w}: {e}", p.path));
            assert_eq!(
                model.get(&p.path).unwrap().to_bits(),
                w.to_bits(),
                "{}",
                p.path
            );
            for (a, b) in params.iter().zip(model.params()) {
                assert_eq!(a.path, b.path);
                if a.path != p.path && a.given {
                    assert_eq!(
                        a.value.to_bits(),
                        b.value.to_bits(),
                        "{file}: setting {} changed {}",
                        p.path,
                        a.path
                    );
                }
            }
            model
                .set(&p.path, v)
                .unwrap_or_else(|e| panic!("{file}: set {} = {v}: {e}", p.path));
            assert_eq!(model.get(&p.path).unwrap().to_bits(), v.to_bits());
            moved += 1;
        }
        // Only the geometry tied together (node radii on the bore and base circles,
        // which follow module, teeth and bore) cannot move alone.
        assert!(
            stuck.iter().all(|p| ["radius_mm", "module_mm", "teeth"]
                .iter()
                .any(|k| p.ends_with(k))),
            "{file}: {moved} of {} parameters took another value; not: {stuck:?}",
            params.len()
        );
        assert!(moved > 60, "{file}: {moved} moved");
        // the forms the issue names
        for path in [
            "node.housing.capacitance_j_per_k",
            "environment.beta_deg",
            "gear_pair.mesh.pinion.tooth_thinning_um",
            "node.\"gear1.r2\".capacitance_j_per_k",
            "conductor.housing-bus.conductance_w_per_k",
        ] {
            if file == "reference-hinge.toml" || !path.starts_with("environment") {
                let v = model.get(path).unwrap_or_else(|e| panic!("{file}: {e}"));
                model.set(path, v * 1.01).unwrap();
                assert_eq!(model.get(path).unwrap(), v * 1.01);
            }
        }
    }
}

#[test]
fn cli_a_change_follows_into_what_depends_on_it() {
    let mut model = Model::new(spec_of("reference-hinge.toml")).unwrap();
    let before = model.scenario().run.duration_s;
    // the run is in orbits: a higher orbit lasts longer
    model.set("orbit.altitude_m", 800e3).unwrap();
    assert!(model.scenario().run.duration_s > before);
    // α and A are kept apart: the product follows the absorptivity
    let load = |m: &Model| match &m.scenario().thermal.network.loads[0].kind {
        orbitlash::thermal::LoadKind::Sun {
            absorptivity_area_m2,
            ..
        } => *absorptivity_area_m2,
        _ => unreachable!(),
    };
    let a0 = load(&model);
    let alpha = model.get("sun.\"sun.housing\".absorptivity").unwrap();
    model
        .set("sun.\"sun.housing\".absorptivity", alpha / 2.0)
        .unwrap();
    assert!((load(&model) - a0 / 2.0).abs() < 1e-15);
    // a refused change leaves the model as it was
    let good = model.scenario().clone();
    assert!(model.set("node.housing.capacitance_j_per_k", -1.0).is_err());
    assert_eq!(model.scenario(), &good);
}

/// (`run --set`'s CSV, the CSV of the file with the same edit).
fn both(set: &str, old: &str, new: &str) -> (Vec<u8>, Vec<u8>) {
    let dir = tmpdir(&format!("set-{}", set.len()));
    std::fs::write(dir.join("s.toml"), reference_text()).unwrap();
    let text = reference_text();
    assert!(text.contains(old), "{old}");
    std::fs::write(dir.join("e.toml"), text.replacen(old, new, 1)).unwrap();
    let run = |args: &[&str], csv: &str| {
        let out = bin()
            .args(["run", "--orbits", "2", "--quiet", "--no-log", "--csv", csv])
            .args(args)
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            out.status.code() != Some(2),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(dir.join(csv)).unwrap()
    };
    let a = run(&["s.toml", "--set", set], "a.csv");
    let b = run(&["e.toml"], "b.csv");
    let _ = std::fs::remove_dir_all(&dir);
    (a, b)
}

#[test]
fn cli_set_equals_the_same_edit_in_the_file() {
    // the unchanged reference (the first key set to its own value)
    let (baseline, _) = both("node.motor.capacitance_j_per_k=75", "x", "x");
    for (set, old, new) in [
        (
            "node.motor.capacitance_j_per_k=80",
            "capacitance_j_per_k = 75.0",
            "capacitance_j_per_k = 80",
        ),
        (
            "environment.beta_deg=35",
            "beta_deg = 20.0",
            "beta_deg = 35",
        ),
        (
            "gear_pair.mesh.pinion.tooth_thinning_um=25",
            "tooth_thinning_um = 19.4745",
            "tooth_thinning_um = 25",
        ),
    ] {
        let (a, b) = both(set, old, new);
        assert!(
            a == b,
            "--set {set} and the edited file give different CSVs"
        );
        // and the change did something
        assert!(a != baseline, "--set {set} changed nothing");
    }
}

#[test]
fn cli_a_bad_value_gives_the_files_error() {
    let dir = tmpdir("set-bad");
    std::fs::write(dir.join("s.toml"), reference_text()).unwrap();
    let text =
        reference_text().replacen("capacitance_j_per_k = 75.0", "capacitance_j_per_k = -3", 1);
    std::fs::write(dir.join("e.toml"), text).unwrap();
    let err = |args: &[&str]| {
        let out = bin().args(args).current_dir(&dir).output().unwrap();
        assert_eq!(out.status.code(), Some(2));
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        // what follows the location (file:line:column, or the --set)
        stderr
            .split_once(": `")
            .map(|(_, rest)| rest.to_string())
            .unwrap_or(stderr)
    };
    let a = err(&[
        "check",
        "s.toml",
        "--set",
        "node.motor.capacitance_j_per_k=-3",
    ]);
    let b = err(&["check", "e.toml"]);
    assert_eq!(a, b);
    assert!(
        a.starts_with("node.motor.capacitance_j_per_k`: must be > 0"),
        "{a}"
    );
    // a whole number: the same words and the same named key path in both
    let text = reference_text().replacen("teeth = 20", "teeth = 20.5", 1);
    std::fs::write(dir.join("t.toml"), text).unwrap();
    let a = err(&[
        "check",
        "s.toml",
        "--set",
        "gear_pair.mesh.pinion.teeth=20.5",
    ]);
    let b = err(&["check", "t.toml"]);
    let first = |s: &str| s.lines().next().unwrap_or_default().to_string();
    assert_eq!(first(&a), first(&b));
    assert_eq!(
        first(&a),
        "gear_pair.mesh.pinion.teeth`: must be an integer (got 20.5)"
    );
    // unknown paths and non-numbers name the key
    let c = err(&["run", "s.toml", "--set", "node.rotor.capacitance_j_per_k=3"]);
    assert!(
        c.contains("no such number") && c.contains("housing, motor"),
        "{c}"
    );
    // the reference hinge has no [recording] table: the clock offset is named with
    // where it lives
    let r = err(&["run", "s.toml", "--set", "recording.time_offset_s=25"]);
    assert!(
        r.contains("no such number") && r.contains("in a [recording] table"),
        "{r}"
    );
    let d = err(&["run", "s.toml", "--set", "environment.beta_deg=twenty"]);
    assert!(
        d.contains("environment.beta_deg") && d.contains("not a number"),
        "{d}"
    );
    // a key given twice is refused, naming both values, before any work
    let out = bin()
        .args([
            "run",
            "s.toml",
            "--no-log",
            "--set",
            "node.motor.capacitance_j_per_k=80",
            "--set",
            "node.motor.capacitance_j_per_k = 90",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let twice = String::from_utf8_lossy(&out.stderr);
    // the same number spelled two ways is the same key
    let out = bin()
        .args([
            "check",
            "s.toml",
            "--set",
            "environment.space_sink_k=4",
            "--set",
            "environment.\"space_sink_k\"=5",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let spelled = String::from_utf8_lossy(&out.stderr);
    assert!(
        spelled.contains("--set environment.space_sink_k is given twice"),
        "{spelled}"
    );
    assert!(
        twice.contains("--set node.motor.capacitance_j_per_k is given twice")
            && twice.contains("=80 and")
            && twice.contains("= 90"),
        "{twice}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_params_lists_every_number_with_unit_and_range() {
    let out = bin().arg("params").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("node.housing.capacitance_j_per_k = 120 J/K  (1e-6 … 1e12)"),
        "{text}"
    );
    assert!(text.contains("orbit.earth_radius_m = 6378137 m"), "{text}");
    assert!(text.contains("environment.albedo = 0.3  (0 … 1)"), "{text}");
    assert!(
        text.contains("gear_pair.mesh.pinion.teeth = 20  (5 … 10000)"),
        "{text}"
    );
    // a value the file leaves out is listed with its default
    let dir = tmpdir("params-default");
    let short = reference_text().replacen("albedo = 0.30", "", 1);
    std::fs::write(dir.join("s.toml"), short).unwrap();
    let out = bin()
        .args(["params", "s.toml"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let listed = String::from_utf8_lossy(&out.stdout);
    assert!(
        listed.contains("environment.albedo = 0.3  (0 … 1)  [default]"),
        "{listed}"
    );
    let given = bin()
        .args(["params", "s.toml", "--given"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(!String::from_utf8_lossy(&given.stdout).contains("environment.albedo"));
    let _ = std::fs::remove_dir_all(&dir);
    // every listed path can be set
    for line in text.lines() {
        let (path, rest) = line.split_once(" = ").unwrap();
        let value = rest.split_whitespace().next().unwrap();
        let out = bin()
            .args(["check", "scenarios/reference-hinge.toml", "--set"])
            .arg(format!("{path}={value}"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{path}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn cli_run_json_has_the_documented_keys() {
    let dir = tmpdir("json");
    let out = bin()
        .args(["run", "--no-log", "--quiet", "--json", "r.json"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(out.status.success());
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("r.json")).unwrap()).unwrap();
    assert_eq!(j["verdict"], "pass");
    assert_eq!(j["nodes"].as_array().unwrap().len(), 10);
    let pair = &j["gear_pairs"][0];
    assert_eq!(pair["name"], "mesh");
    assert!((pair["min_backlash_um"].as_f64().unwrap() - 24.398).abs() < 0.01);
    assert!((pair["min_margin_um"].as_f64().unwrap() - 19.398).abs() < 0.01);
    for key in ["energy", "solver", "events", "window"] {
        assert!(j[key].is_object(), "{key}");
    }
    assert!(j["energy"]["relative_error"].as_f64().unwrap() < 1e-5);
    assert!(j["solver"]["steps"].as_u64().unwrap() > 400);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_resolved_parameters_write_what_a_full_compile_gives() {
    for file in ["reference-hinge.toml", "hinge-90-day-drift.toml"] {
        let base = Model::new(spec_of(file)).unwrap();
        for p in base.params() {
            // a nearby valid value (integers stay integers)
            let v = if p.path.ends_with("teeth") {
                p.value
            } else if p.value == 0.0 {
                0.0
            } else {
                p.value * (1.0 + 1e-4)
            };
            let mut fast = base.clone();
            let mut full = base.clone();
            let id = fast.param(&p.path).unwrap();
            let a = fast.set_param(&id, v);
            let b = full.set(&p.path, v);
            assert_eq!(a.is_ok(), b.is_ok(), "{file} {}: {a:?} vs {b:?}", p.path);
            assert!(
                fast.scenario() == full.scenario() && fast.spec() == full.spec(),
                "{file} {}: the resolved write differs from a full compile",
                p.path
            );
            // a bad value: the same error, and the model unchanged
            let bad = if p.path.ends_with("teeth") {
                3.0
            } else {
                -1e30
            };
            let (mut f2, mut g2) = (base.clone(), base.clone());
            let ea = f2.set_param(&id, bad).err().map(|e| e.to_string());
            let eb = g2.set(&p.path, bad).err().map(|e| e.to_string());
            assert_eq!(ea, eb, "{file} {}", p.path);
            if ea.is_some() {
                assert!(f2.scenario() == base.scenario() && f2.spec() == base.spec());
            }
        }
    }
}

#[test]
fn core_a_resolved_parameter_survives_a_change_of_elements() {
    // Resolved on the model as loaded, used after a conductor was added in front of it:
    // it still writes the conductor it names.
    let mut model = Model::new(spec_of("reference-hinge.toml")).unwrap();
    let id = model
        .param("conductor.housing-bus.conductance_w_per_k")
        .unwrap();
    model
        .modify(|s| {
            s.conductor.insert(
                0,
                orbitlash::spec::ConductorSpec {
                    name: None,
                    between: vec!["motor".into(), "bus".into()],
                    conductance_w_per_k: 0.01,
                },
            )
        })
        .unwrap();
    model.set_param(&id, 0.05).unwrap();
    assert_eq!(
        model
            .get("conductor.housing-bus.conductance_w_per_k")
            .unwrap(),
        0.05
    );
    assert_eq!(
        model
            .get("conductor.motor-bus.conductance_w_per_k")
            .unwrap(),
        0.01
    );
    let net = &model.scenario().thermal.network;
    assert_eq!(net.conductors[0].conductance_w_per_k, 0.01);
    assert_eq!(net.conductors[1].conductance_w_per_k, 0.05);
}

/// The key table of `scenarios/README.md` is the registry's, generated (`orbitlash
/// params --keys`); a row added to the registry without regenerating the README fails
/// here, and so does a hand edit of the table.
#[test]
fn cli_the_readme_key_table_is_the_registrys() {
    let readme = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/README.md"),
    )
    .unwrap();
    let (_, rest) = readme
        .split_once("<!-- registry:begin -->\n")
        .expect("the README marks its key table");
    let (committed, _) = rest.split_once("<!-- registry:end -->").unwrap();
    let out = bin().args(["params", "--keys"]).output().unwrap();
    assert!(out.status.success());
    let generated = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        committed, generated,
        "scenarios/README.md's key table differs from the registry: paste `orbitlash params --keys` between its markers"
    );
    // and it has every row, one line each
    assert_eq!(
        generated.lines().count(),
        orbitlash::spec::registry::rows().len() + 2
    );
}

/// A range as `params`, the README's key table and the errors show it says which ends
/// are excluded, as the rule checks them: an excluded finite end is written with
/// "<" or ">" (black-box helper-27: an initial temperature of 5000 K and a Poisson
/// ratio of 0.5 were refused by a range shown as "0 … 5000" and "−1 … 0.5", the error
/// then saying "must be within −1 … 0.5 (got 0.5)").
#[test]
fn core_a_shown_range_marks_its_excluded_ends() {
    let mut seen = 0;
    for row in orbitlash::spec::registry::rows() {
        let q = row.field.quantity;
        let Some((lo, lo_in, hi, hi_in)) = q.interval() else {
            continue;
        };
        // "a … b", "a < … < b", "0 < … ≤ b", "> 0", "≥ a" (and a context after a comma)
        let text = q.range();
        let rule = text.split(", ").next().unwrap();
        let (left, right) = rule.split_once('…').unwrap_or((rule, ""));
        let (left, right) = (left.trim(), right.trim());
        let name = row.field.name;
        if lo.is_finite() {
            let shown_out = left.ends_with('<') || left.starts_with('>');
            assert_eq!(
                shown_out, !lo_in,
                "{name}: {text:?} against the lower end {lo} ({lo_in})"
            );
            assert!(!left.starts_with('≥') || lo_in, "{name}: {text:?}");
        }
        if hi.is_finite() {
            let shown_out = right.starts_with('<');
            assert_eq!(
                shown_out, !hi_in,
                "{name}: {text:?} against the upper end {hi} ({hi_in})"
            );
        } else {
            assert!(
                right.is_empty(),
                "{name}: {text:?} bounds an unbounded range"
            );
        }
        seen += usize::from(!lo_in && lo.is_finite() || !hi_in && hi.is_finite());
    }
    assert!(seen > 0, "no quantity with an excluded end was checked");
    // and the error of an excluded end says the same range
    let out = bin()
        .args([
            "backlash",
            "--set",
            "gear_pair.mesh.pinion.material.poisson=0.5",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("must be −1 < … < 0.5 (got 0.5)"), "{err}");
}

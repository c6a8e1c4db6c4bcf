//! Bad input gives a clear error naming the file, key and line, a non-zero exit, no
//! panic and no output file.

use std::path::Path;
use std::process::Output;

mod common;
use common::{bin, tmpdir};

fn reference_text() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/reference-hinge.toml"),
    )
    .unwrap()
}

/// Runs `orbitlash check` and `orbitlash run` on the reference scenario with `old`
/// replaced by `new`; both must fail with a message containing every needle, where
/// `{line}` stands for the line `old` started on.
fn assert_rejected(case: &str, old: &str, new: &str, needles: &[&str]) {
    let text = reference_text();
    let at = text
        .find(old)
        .unwrap_or_else(|| panic!("{case}: `{old}` not in the reference scenario"));
    let line = text[..at].matches('\n').count() + 1;
    let needles: Vec<String> = needles
        .iter()
        .map(|n| n.replace("{line}", &line.to_string()))
        .collect();
    let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
    let needles = &needles[..];
    let bad = text.replacen(old, new, 1);
    let dir = tmpdir(case);
    let file = dir.join(format!("{case}.toml"));
    std::fs::write(&file, bad).unwrap();
    let log = dir.join("out.mcap");
    for args in [vec!["check"], vec!["run", "--out", log.to_str().unwrap()]] {
        let out = bin().args(&args).arg(&file).output().unwrap();
        assert_failed(case, &out, &[&[file.to_str().unwrap()], needles].concat());
    }
    assert!(
        !log.exists(),
        "{case}: a log was written for a bad scenario"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

fn assert_failed(case: &str, out: &Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "{case}: exit status {:?}",
        out.status
    );
    assert!(!stderr.contains("panicked"), "{case}: panic\n{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "{case}: `{n}` missing from\n{stderr}");
    }
}

#[test]
fn cli_malformed_toml_names_the_line() {
    assert_rejected(
        "malformed",
        "capacitance_j_per_k = 120.0",
        "capacitance_j_per_k = = 120.0",
        &["line {line}"],
    );
}

/// A malformed line of 400 000 characters is shown around its error's column, not
/// whole (black-box helper-25), the caret still under the character it marks, in
/// characters (a line of "é", two bytes each); a long value in a type error is cut in
/// the message's lines too (review helper-26: quoted whole, twice).
#[test]
fn cli_a_long_malformed_line_is_shown_around_its_column() {
    let dir = common::tmpdir("long-line");
    let n = 200_000;
    let cases = [
        (
            "deep.toml",
            format!("x = {}{}\n", "[".repeat(n), "]".repeat(n)),
            '[',
        ),
        (
            "accents.toml",
            format!("x = \"{}\" b{}\n", "é".repeat(300), "d".repeat(300)),
            'b',
        ),
    ];
    for (file, text, marked) in cases {
        std::fs::write(dir.join(file), text).unwrap();
        let out = common::bin()
            .args(["check", file])
            .current_dir(&dir)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.len() < 1200, "{file}: {} bytes", err.len());
        assert!(err.contains(file) && err.contains("line 1"), "{err}");
        let lines: Vec<&str> = err.lines().collect();
        let caret = lines
            .iter()
            .position(|l| l.trim_end().ends_with('^'))
            .unwrap();
        let source: Vec<char> = lines[caret - 1].chars().collect();
        let at = lines[caret].chars().count() - 1;
        assert!(lines[caret - 1].contains("| …"), "{err}");
        assert_eq!(source[at], marked, "{err}");
    }
    // a type error quotes the value: cut as well
    let text = common::reference_text();
    let long = text.replacen(
        "orbits = 6",
        &format!("orbits = \"{}\"", "a".repeat(5000)),
        1,
    );
    assert_ne!(long, text);
    std::fs::write(dir.join("value.toml"), long).unwrap();
    let out = common::bin()
        .args(["check", "value.toml"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.len() < 2000, "{} bytes: {err}", err.len());
}

#[test]
fn cli_unknown_key_is_named_with_its_line() {
    assert_rejected(
        "unknown-key",
        "capacitance_j_per_k = 120.0",
        "colour = \"red\"\ncapacitance_j_per_k = 120.0",
        &["colour", "line {line}"],
    );
}

#[test]
fn cli_missing_key_is_named() {
    assert_rejected(
        "missing",
        "initial_temperature_k = 293.15\n\n[[node]]\nname = \"motor\"",
        "\n[[node]]\nname = \"motor\"",
        &["initial_temperature_k"],
    );
}

#[test]
fn cli_negative_capacitance() {
    assert_rejected(
        "neg-cap",
        "capacitance_j_per_k = 4.06",
        "capacitance_j_per_k = -4.06",
        &["node.shaft1.capacitance_j_per_k", ":{line}:", "must be > 0"],
    );
}

#[test]
fn cli_emissivity_above_one() {
    assert_rejected(
        "emissivity",
        "emissivity_area_m2 = 0.030",
        "emissivity = 1.2\narea_m2 = 0.03",
        &["radiation.housing-space.emissivity", "0 … 1"],
    );
}

#[test]
fn cli_absorptivity_above_one() {
    assert_rejected(
        "absorptivity",
        "absorptivity = 0.7",
        "absorptivity = 1.7",
        &["sun.\"sun.housing\".absorptivity", "0 … 1"],
    );
}

#[test]
fn cli_unknown_node_reference() {
    assert_rejected(
        "unknown-node",
        "between = [\"housing\", \"motor\"]",
        "between = [\"housing\", \"mottor\"]",
        &[
            "conductor.housing-mottor.between[1]",
            "unknown node `mottor`",
            ":{line}:",
        ],
    );
}

#[test]
fn cli_duplicate_node_name() {
    assert_rejected(
        "duplicate",
        "name = \"motor\"",
        "name = \"housing\"",
        &["node[1].name", "defined twice"],
    );
}

#[test]
fn cli_temperature_in_celsius_by_mistake() {
    assert_rejected(
        "celsius",
        "initial_temperature_k = 293.15",
        "initial_temperature_k = -20.0",
        &["node.housing.initial_temperature_k", "kelvin"],
    );
}

#[test]
fn cli_beta_out_of_range() {
    assert_rejected(
        "beta",
        "beta_deg = 20.0",
        "beta_deg = 120.0",
        &["environment.beta_deg", "-90 … 90"],
    );
}

#[test]
fn cli_non_monotonic_profile_time() {
    assert_rejected(
        "non-monotonic",
        "beta_deg = 20.0",
        "beta_deg = { time_s = [0.0, 100.0, 50.0], value = [0.0, 10.0, 20.0] }",
        &["environment.beta_deg.time_s[2]", "increase"],
    );
}

#[test]
fn cli_heater_set_points_inverted() {
    assert_rejected(
        "heater",
        "[[sun]]",
        "[[heater]]\nnode = \"housing\"\npower_w = 4.0\non_k = 270.0\noff_k = 265.0\n\n[[sun]]",
        &["heater.housing.off_k", "above on_k"],
    );
}

#[test]
fn cli_zero_time_step() {
    assert_rejected(
        "step",
        "max_step_s = 300.0",
        "max_step_s = 0.0",
        &["solver.max_step_s", "at least 0.001 s"],
    );
}

#[test]
fn cli_both_run_lengths() {
    assert_rejected(
        "run-length",
        "orbits = 6",
        "orbits = 6\nduration_s = 100.0",
        &["run", "exactly one"],
    );
}

#[test]
fn cli_self_link() {
    assert_rejected(
        "self-link",
        "between = [\"housing\", \"motor\"]",
        "between = [\"housing\", \"housing\"]",
        &["conductor.housing-housing.between", "itself"],
    );
}

#[test]
fn cli_wrong_type() {
    assert_rejected(
        "type",
        "capacitance_j_per_k = 120.0",
        "capacitance_j_per_k = \"120 J/K\"",
        &["capacitance_j_per_k", "line {line}"],
    );
}

#[test]
fn cli_missing_scenario_file() {
    let out = bin()
        .args(["run", "/nonexistent/nothing.toml"])
        .output()
        .unwrap();
    assert_failed("missing-file", &out, &["/nonexistent/nothing.toml"]);
}

#[test]
fn cli_unwritable_output_path_fails_before_the_run() {
    let dir = tmpdir("unwritable");
    let blocker = dir.join("file");
    std::fs::write(&blocker, "not a folder").unwrap();
    let log = blocker.join("run.mcap");
    let out = bin()
        .args(["run", "--out", log.to_str().unwrap()])
        .output()
        .unwrap();
    assert_failed("unwritable", &out, &[log.to_str().unwrap()]);
    assert!(
        String::from_utf8_lossy(&out.stdout).is_empty(),
        "the run went ahead"
    );
    let csv = dir.join("dir-as-csv");
    std::fs::create_dir_all(&csv).unwrap();
    let out = bin()
        .args(["run", "--no-log", "--csv", csv.to_str().unwrap()])
        .output()
        .unwrap();
    assert_failed("csv-dir", &out, &[csv.to_str().unwrap()]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_bad_orbit_count_on_the_command_line() {
    for bad in ["0", "-3", "nan", "many"] {
        let out = bin()
            .args(["run", "--no-log", &format!("--orbits={bad}")])
            .output()
            .unwrap();
        assert_failed("orbits", &out, &["--orbits"]);
    }
}

#[test]
fn cli_gear_bore_not_below_base_radius() {
    assert_rejected(
        "bore",
        "bore_radius_mm = 3.0",
        "bore_radius_mm = 9.5",
        &[
            "gear_pair.mesh.pinion.bore_radius_mm",
            "base radius",
            ":{line}:",
        ],
    );
}

#[test]
fn cli_gear_too_few_teeth() {
    assert_rejected(
        "teeth",
        "teeth = 20",
        "teeth = 4",
        &["gear_pair.mesh.pinion.teeth", "5 … 10000"],
    );
}

#[test]
fn cli_gear_negative_backlash_at_assembly() {
    assert_rejected(
        "thick-teeth",
        "tooth_thinning_um = 19.4745         # s",
        "tooth_thinning_um = -30.0           # s",
        &[
            "gear_pair.mesh.center_distance_mm",
            "negative backlash at assembly",
        ],
    );
}

#[test]
fn cli_gear_pressure_angle_out_of_range() {
    assert_rejected(
        "alpha0",
        "pressure_angle_deg = 20.0",
        "pressure_angle_deg = 45.0",
        &["gear_pair.mesh.pressure_angle_deg", "10° … 35°"],
    );
}

#[test]
fn cli_gear_node_not_on_the_base_circle() {
    assert_rejected(
        "node-radius",
        "radius_mm = 9.396926",
        "radius_mm = 9.5",
        &["gear_pair.mesh.pinion.nodes[2]", "base radius"],
    );
}

#[test]
fn cli_gear_unknown_bore_fit() {
    assert_rejected(
        "fit",
        "bore_fit = \"free\"",
        "bore_fit = \"glued\"",
        &[
            "gear_pair.mesh.pinion.bore_fit",
            "unknown variant `glued`",
            "`free`, `rigid`, `elastic`",
        ],
    );
}

#[test]
fn cli_not_a_number_is_rejected() {
    assert_rejected(
        "nan",
        "capacitance_j_per_k = 4.06",
        "capacitance_j_per_k = nan",
        &["node.shaft1.capacitance_j_per_k", "finite", ":{line}:"],
    );
    assert_rejected(
        "inf",
        "conductance_w_per_k = 0.30",
        "conductance_w_per_k = inf",
        &["conductor.housing-motor.conductance_w_per_k", "finite"],
    );
}

#[test]
fn cli_empty_and_binary_files() {
    let dir = tmpdir("empty");
    let empty = dir.join("empty.toml");
    std::fs::write(&empty, "").unwrap();
    let out = bin().arg("check").arg(&empty).output().unwrap();
    assert_failed("empty", &out, &[empty.to_str().unwrap(), "scenario"]);
    let binary = dir.join("binary.toml");
    std::fs::write(&binary, [0xff, 0xfe, 0x00, 0x41]).unwrap();
    let out = bin().arg("check").arg(&binary).output().unwrap();
    assert_failed("binary", &out, &[binary.to_str().unwrap()]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_a_log_that_is_not_mcap_is_a_clear_error() {
    let dir = tmpdir("bad-log");
    let log = dir.join("not.mcap");
    std::fs::write(&log, "time_s,housing_c\n0,20\n").unwrap();
    let out = bin().arg("export-csv").arg(&log).output().unwrap();
    assert_failed("bad-log", &out, &[log.to_str().unwrap(), "MCAP"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_sensor_lag_and_offset_are_checked() {
    assert_rejected(
        "sensor-tau",
        "column = \"housing_c\"\nnode = \"housing\"",
        "column = \"housing_c\"\nnode = \"housing\"\ntau_s = -5.0",
        &["sensor.housing_c.tau_s", "0 … 86400", "got -5"],
    );
    assert_rejected(
        "sensor-offset",
        "column = \"motor_c\"\nnode = \"motor\"",
        "column = \"motor_c\"\nnode = \"motor\"\noffset_k = 250.0",
        &["sensor.motor_c.offset_k", "-100 … 100"],
    );
    assert_rejected(
        "sensor-derived-lag",
        "quantity = \"backlash_um\"",
        "quantity = \"backlash_um\"\ntau_s = 10.0",
        &["sensor.backlash_um.tau_s", "temperature sensors only"],
    );
    assert_rejected(
        "sensor-pair",
        "quantity = \"backlash_um\"",
        "quantity = \"backlash_um\"\ngear_pair = \"spur\"",
        &["sensor.backlash_um.gear_pair", "unknown gear pair `spur`"],
    );
}

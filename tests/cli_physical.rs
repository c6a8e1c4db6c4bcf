//! Results stay physical: every output within 0 … 10 000 K or the run ends naming the
//! node, the time and the likely cause; `check` warns about the usual mistakes
//! (issue 8, item 4).

use std::path::Path;
use std::process::Output;

mod common;
use common::{assert_error, bin, reference_with, tmpdir};

fn run_in(dir: &Path, args: &[&str]) -> Output {
    bin().args(args).current_dir(dir).output().unwrap()
}

/// A small network: node `a` (optionally tied to space), node `b` stiffly tied to space.
fn small(solver: &str, a_link: &str, a_initial_k: f64) -> String {
    format!(
        r#"[scenario]
name = "small"
[orbit]
altitude_m = 500e3
[environment]
beta_deg = 0
[run]
duration_days = 3
[solver]
{solver}
[[node]]
name = "a"
capacitance_j_per_k = 10
initial_temperature_k = {a_initial_k}
[[node]]
name = "b"
capacitance_j_per_k = 0.001
initial_temperature_k = 293
[[conductor]]
between = ["b", "space"]
conductance_w_per_k = 1
{a_link}
[[dissipation]]
node = "a"
power_w = 100
"#
    )
}

#[test]
fn cli_an_isolated_heated_node_ends_the_run_with_its_name_and_cause() {
    let dir = tmpdir("isolated");
    std::fs::write(dir.join("s.toml"), small("", "", 293.0)).unwrap();
    let out = run_in(
        &dir,
        &["run", "s.toml", "--out", "x.mcap", "--csv", "x.csv"],
    );
    assert_error(
        "isolated",
        &out,
        &[
            "node a reached",
            "K at t =",
            "no conductive or radiative path",
        ],
    );
    // the failed run's log is closed and says so; the CSV is not presented
    let stderr = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.starts_with("warning:"))
        .collect();
    assert!(
        lines[0].starts_with("error: running s.toml: node a"),
        "{stderr}"
    );
    assert!(
        lines[1].contains("the log x.mcap holds the run up to the failure"),
        "{stderr}"
    );
    assert!(!dir.join("x.csv").exists() && !dir.join("x.csv.partial").exists());
    // ... with the failure's time in its run_end record and its last event
    let t_fail: f64 = lines[0]
        .split("K at t = ")
        .nth(1)
        .and_then(|r| r.split(" s").next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no failure time in {stderr}"));
    let log = orbitlash::io::mcap_read::read_log(&dir.join("x.mcap")).unwrap();
    let end = &log.metadata["orbitlash.run_end"];
    assert_eq!(end["status"], "failed");
    let t_end: f64 = end["t_end_s"].parse().unwrap();
    assert!(
        (t_end - t_fail).abs() < 1e-3,
        "run_end at {t_end} s, failure at {t_fail} s"
    );
    assert!(t_end > 0.0);
    // `check` saw it coming
    let check = run_in(&dir, &["check", "s.toml"]);
    assert!(check.status.success());
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(
        text.contains("warning: `node.a.name`: 1 node(s) have no conductive or radiative path"),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_a_fixed_step_far_above_a_time_constant_ends_the_run() {
    // b starts at 293 K and falls to the 3 K sink with a 1 ms time constant; a fixed
    // 100 s step cannot follow it and its interpolant dips below 0 K.
    let dir = tmpdir("fixed-step");
    let link = "[[conductor]]\nbetween = [\"a\", \"space\"]\nconductance_w_per_k = 1";
    std::fs::write(
        dir.join("s.toml"),
        small("adaptive = false\nmax_step_s = 100", link, 293.0),
    )
    .unwrap();
    let out = run_in(&dir, &["run", "s.toml", "--no-log"]);
    assert_error(
        "fixed-step",
        &out,
        &[
            "node b reached",
            "fixed step of 100",
            "time constant of 1.000e-3 s",
        ],
    );
    let check = run_in(&dir, &["check", "s.toml"]);
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(
        text.contains("warning: `solver.max_step_s`: the fixed step of 100 s")
            && text.contains("node b (1.000e-3 s)"),
        "{text}"
    );
    // adaptive steps follow it
    std::fs::write(dir.join("s.toml"), small("", link, 293.0)).unwrap();
    let out = run_in(&dir, &["run", "s.toml", "--no-log"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// (min, max) °C of `node` in a run summary.
fn node_range(stdout: &str, node: &str) -> (f64, f64) {
    let line = stdout
        .lines()
        .find(|l| l.split_whitespace().next() == Some(node))
        .unwrap_or_else(|| panic!("{node} not in\n{stdout}"));
    let v: Vec<f64> = line
        .split_whitespace()
        .skip(1)
        .map(|x| x.parse().unwrap())
        .collect();
    (v[0], v[1])
}

#[test]
fn cli_a_stiff_node_with_fixed_steps_stays_physical() {
    // The case of the issue: a thin film (0.05 J/K … 1e-6 J/K) stiffly tied to the
    // housing, run with fixed 300 s steps. Its end-of-step rates belong to the damped
    // fast transient; interpolating with them gave −24.7 K and worse. The film's
    // last-orbit range must match an adaptive run's within 1 K, and every CSV value
    // must be a physical temperature.
    let dir = tmpdir("stiff");
    let film = |c: &str, g: &str| {
        format!(
            "\n[[node]]\nname = \"film\"\ncapacitance_j_per_k = {c}\ninitial_temperature_k = 293.15\n\
             [[conductor]]\nbetween = [\"film\", \"housing\"]\nconductance_w_per_k = {g}\n\
             [[radiation]]\nbetween = [\"film\", \"space\"]\nemissivity_area_m2 = 0.05\n\
             [[sun]]\nnode = \"film\"\nabsorptivity_area_m2 = 0.05\n"
        )
    };
    for (c, g) in [("0.05", "50"), ("1e-6", "1000")] {
        let mut ranges = Vec::new();
        for adaptive in ["true", "false"] {
            let text = reference_with(&[(
                "max_step_s = 300.0",
                &format!("max_step_s = 300.0\nadaptive = {adaptive}"),
            )]) + &film(c, g);
            std::fs::write(dir.join("s.toml"), text).unwrap();
            let out = run_in(&dir, &["run", "s.toml", "--no-log", "--csv", "x.csv"]);
            assert!(out.status.success() || out.status.code() == Some(1));
            let stdout = String::from_utf8_lossy(&out.stdout).to_string();
            ranges.push(node_range(&stdout, "film"));
            let csv = std::fs::read_to_string(dir.join("x.csv")).unwrap();
            let col = csv
                .lines()
                .next()
                .unwrap()
                .split(',')
                .position(|h| h == "film_k")
                .unwrap();
            for row in csv.lines().skip(1) {
                let v: f64 = row.split(',').nth(col).unwrap().parse().unwrap();
                assert!(v > 150.0 && v < 450.0, "C = {c}: film at {v} K in {row}");
            }
        }
        let (a, f) = (ranges[0], ranges[1]);
        assert!(
            (a.0 - f.0).abs() < 1.0 && (a.1 - f.1).abs() < 1.0,
            "C = {c}: adaptive {a:?} °C, fixed {f:?} °C"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_check_warns_about_celsius_typed_as_kelvin() {
    let dir = tmpdir("celsius");
    let text = reference_with(&[
        (
            "initial_temperature_k = 293.15",
            "initial_temperature_k = 20",
        ),
        (
            "reference_temperature_k = 298.15",
            "reference_temperature_k = 25",
        ),
    ]);
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let out = run_in(&dir, &["check", "s.toml"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("valid (reference-hinge), 2 warning(s)"),
        "{text}"
    );
    assert!(
        text.contains("warning: `node.housing.initial_temperature_k`: 20 K (-253.15 °C) looks like a Celsius value"),
        "{text}"
    );
    assert!(
        text.contains("warning: `gear_pair.mesh.reference_temperature_k`: 25 K"),
        "{text}"
    );
    // the reference scenario itself is clean
    let out = bin()
        .args(["check"])
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/reference-hinge.toml"))
        .output()
        .unwrap();
    assert!(!String::from_utf8_lossy(&out.stdout).contains("warning"));
    let _ = std::fs::remove_dir_all(&dir);
}

//! `orbitlash run` and `check` end to end.

use std::path::{Path, PathBuf};
mod common;
use common::{bin, tmpdir};

fn scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

#[test]
fn cli_run_without_arguments_uses_the_embedded_reference_and_writes_a_log() {
    let dir = tmpdir("default");
    let out = bin().arg("run").current_dir(&dir).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("reference-hinge: 6 orbits"), "{stdout}");
    assert!(stdout.contains("last orbit (orbit 6"), "{stdout}");
    // a run of 2.5 orbits: its last period is not an orbit, and the summary says so;
    // shorter than an orbit: the whole run, in the mesh table too
    for (orbits, heading, column, absent) in [
        (
            "2.5",
            "last period (the end of orbit 2, the start of 3, t = ",
            "last period min",
            &["last orbit"][..],
        ),
        (
            "0.3",
            "the whole run (0.30 of an orbit, t = 0 … ",
            "whole run min",
            &["last orbit", "last period"][..],
        ),
    ] {
        let out = bin()
            .args(["run", "--orbits", orbits, "--no-log", "--quiet"])
            .current_dir(&dir)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains(heading), "{text}");
        assert!(text.contains(column), "{text}");
        assert!(absent.iter().all(|a| !text.contains(a)), "{text}");
    }
    for node in ["housing", "gear1.r2", "gear2.r2"] {
        assert!(stdout.contains(node), "{node} missing from the summary");
    }
    assert!(stdout.contains("energy balance"));
    let log = dir.join("logs/reference-hinge.mcap");
    let bytes = std::fs::read(&log).unwrap();
    assert!(
        bytes.starts_with(b"\x89MCAP0\r\n") && bytes.ends_with(b"\x89MCAP0\r\n"),
        "not a complete MCAP file"
    );
    assert!(!dir.join("logs/reference-hinge.mcap.partial").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_csv_has_a_column_per_node_and_runs_are_reproducible() {
    let dir = tmpdir("csv");
    let run = |tag: &str| {
        let csv = dir.join(format!("{tag}.csv"));
        let log = dir.join(format!("{tag}.mcap"));
        let out = bin()
            .args([
                "run",
                "--orbits",
                "1",
                "--quiet",
                "--csv",
                csv.to_str().unwrap(),
                "--out",
                log.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        (std::fs::read(csv).unwrap(), std::fs::read(log).unwrap())
    };
    let (csv_a, log_a) = run("a");
    let (csv_b, log_b) = run("b");
    assert_eq!(csv_a, csv_b, "CSV differs between two runs");
    assert_eq!(log_a, log_b, "MCAP differs between two runs");

    let text = String::from_utf8(csv_a).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut want = vec!["time_s", "housing_k", "motor_k", "shaft1_k", "shaft2_k"];
    want.extend([
        "gear1.r0_k",
        "gear1.r1_k",
        "gear1.r2_k",
        "gear2.r0_k",
        "gear2.r1_k",
        "gear2.r2_k",
    ]);
    want.extend([
        "backlash_um",
        "backlash_closed_form_um",
        "backlash_paper_um",
    ]);
    want.extend(["pressure_angle_deg", "center_distance_mm"]);
    assert_eq!(header, want);
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let period = 5676.978;
    // the grid, and between its rows those at each new smallest backlash (one per
    // descent: the start of the run falls, then each orbit's minimum)
    let on_grid = |t: f64| (t / 30.0 - (t / 30.0).round()).abs() < 1e-9;
    let grid: Vec<&Vec<f64>> = rows.iter().filter(|r| on_grid(r[0])).collect();
    assert_eq!(grid.len(), (period / 30.0f64).floor() as usize + 1);
    for (k, r) in grid.iter().enumerate() {
        assert!((r[0] - 30.0 * k as f64).abs() < 1e-9);
    }
    let extra: Vec<&Vec<f64>> = rows.iter().filter(|r| !on_grid(r[0])).collect();
    assert!(
        (1..=3).contains(&extra.len()),
        "{} rows off the grid",
        extra.len()
    );
    assert!(
        rows.windows(2).all(|w| w[0][0] < w[1][0]),
        "rows in time order"
    );
    let smallest = rows.iter().map(|r| r[11]).fold(f64::INFINITY, f64::min);
    assert!(
        extra.iter().any(|r| r[11] == smallest),
        "the smallest is off the grid"
    );
    for r in &rows {
        assert_eq!(r.len(), header.len());
        assert!(
            r[1..11]
                .iter()
                .all(|t| t.is_finite() && *t > 200.0 && *t < 400.0)
        );
        let (b, cf, paper, aw, a) = (r[11], r[12], r[13], r[14], r[15]);
        assert!(
            (20.0..45.0).contains(&b) && b <= cf + 1e-9,
            "backlash {b} µm, closed form {cf} µm"
        );
        assert!(paper.is_finite() && (19.5..20.5).contains(&aw) && a == 30.0);
    }
    assert!(
        rows[0][1..11].iter().all(|&t| (t - 293.15).abs() < 1e-9),
        "first row is the initial state"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_check_prints_derived_quantities() {
    let out = bin()
        .args(["check"])
        .arg(scenario("reference-hinge.toml"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    for needle in [
        "period                  5676.978 s",
        "half-angle 66.526°",
        "fraction 0.36959",
        "stiffness ratio",
        "normal backlash 32.600 µm",
        "contact ratio 1.6",
        "gear1.r0",
    ] {
        assert!(stdout.contains(needle), "`{needle}` missing:\n{stdout}");
    }
    let out = bin()
        .args(["check"])
        .arg(scenario("hinge-90-day-drift.toml"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("beta  60.000°"), "{stdout}");
    assert!(stdout.contains("1 heater, 1 mode"), "{stdout}");
    assert!(
        stdout.contains(
            "4 loads (1 Sun absorber, 1 albedo absorber, 1 Earth-IR absorber, 1 dissipation)"
        ),
        "{stdout}"
    );
}

#[test]
fn cli_every_shipped_scenario_is_valid() {
    for entry in std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios")).unwrap()
    {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "toml") {
            let out = bin().arg("check").arg(&p).output().unwrap();
            assert!(
                out.status.success(),
                "{}: {}",
                p.display(),
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
}

#[test]
fn cli_backlash_calculator_table_and_json() {
    let out = bin().arg("backlash").output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("32.600"), "nominal missing:\n{stdout}");
    assert!(
        stdout.contains("100.00") && stdout.contains("-75.00"),
        "{stdout}"
    );

    let out = bin()
        .args(["backlash", "--json", "--pinion-c", "65", "--wheel-c", "35"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let cases = v["pairs"][0]["cases"].as_array().unwrap();
    let given = cases.iter().find(|c| c["case"] == "given").unwrap();
    // physics.md §4: pinion 40 K and wheel 10 K above 25 °C.
    let exact = given["backlash_um"]["exact"].as_f64().unwrap();
    let closed = given["backlash_um"]["closed_form"].as_f64().unwrap();
    assert!(
        (exact - 26.64).abs() < 0.005 && (closed - 28.10).abs() < 0.005,
        "{exact} {closed}"
    );
    assert_eq!(
        cases[0]["backlash_um"]["exact"].as_f64().unwrap().round(),
        33.0
    );

    let out = bin()
        .args(["backlash", "--pinion-c", "nan", "--wheel-c", "3"])
        .output()
        .unwrap();
    assert!(!out.status.success());
}

/// A smallest backlash at the run's very end (β = 90°: no eclipse, the mechanism still
/// cooling) is in the run's last orbit, whatever the rounding of N periods: the instant
/// N T ends orbit N (it was reported as orbit N + 1 for 1, 2 and 4 orbits, orbit N for
/// 3).
#[test]
fn cli_the_run_s_last_instant_is_in_its_last_orbit() {
    let dir = common::tmpdir("last-orbit");
    let file = dir.join("beta90.toml");
    std::fs::write(
        &file,
        common::reference_with(&[("beta_deg = 20.0", "beta_deg = 90.0")]),
    )
    .unwrap();
    for n in 1..=4 {
        let out = common::bin()
            .arg("run")
            .arg(&file)
            .args(["--no-log", "--orbits", &n.to_string()])
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        let line = text
            .lines()
            .find(|l| l.starts_with("PASS mesh") || l.starts_with("FAIL mesh"))
            .unwrap_or_else(|| panic!("{text}"));
        assert!(line.contains(&format!("orbit {n}, ")), "{n} orbits: {line}");
    }
}

/// A run of a whole number of orbits says that number in its JSON's `orbits`: 6 and
/// 3, not 5.999999999999999 and 2.9999999999999996 (its length over the period;
/// black-box helper-25); 2.5 stays 2.5.
#[test]
fn cli_run_json_counts_whole_orbits_as_whole() {
    let dir = common::tmpdir("json-orbits");
    for (args, want) in [
        (vec![], 6.0),
        (vec!["--orbits", "3"], 3.0),
        (vec!["--orbits", "2.5"], 2.5),
    ] {
        let out = common::bin()
            .arg("run")
            .args(&args)
            .args(["--no-log", "--quiet", "--json", "o.json"])
            .current_dir(&dir)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{args:?}");
        let j: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("o.json")).unwrap()).unwrap();
        assert_eq!(j["orbits"].as_f64(), Some(want), "{args:?}");
    }
}

/// The β range a run's summary and `environment` print is the run's own, as the
/// orbit's series over the run gives it: 40 orbits of the 90-day drift, whose β table
/// goes 0° → 60° over the mission, printed "0.00° … 60.00°" (black-box helper-21).
#[test]
fn cli_the_beta_range_is_the_runs_own() {
    let dir = tmpdir("beta-range");
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-90-day-drift.toml");
    let scenario = scenario.to_str().unwrap();
    let env = bin()
        .args(["environment", scenario, "--orbits", "40", "--csv", "e.csv"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&env.stdout).into_owned();
    assert_eq!(env.status.code(), Some(0), "{said}");
    let csv = std::fs::read_to_string(dir.join("e.csv")).unwrap();
    let mut lines = csv.lines();
    let col = lines
        .next()
        .unwrap()
        .split(',')
        .position(|h| h == "beta_deg")
        .expect("a beta_deg column");
    let betas: Vec<f64> = lines
        .map(|l| l.split(',').nth(col).unwrap().parse().unwrap())
        .collect();
    let lo = betas.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = betas.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert!(hi < 5.0, "the series over 40 orbits reaches {hi}°");
    let range = format!("{lo:.2}° … {hi:.2}°");
    assert!(
        said.contains(&format!("β over these orbits     {range}")),
        "{range}\n{said}"
    );
    let run = bin()
        .args(["run", scenario, "--orbits", "40", "--no-log", "--quiet"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(text.contains(&format!("beta {range},")), "{range}\n{text}");
}

/// `backlash --uniform-c T --housing-c H`: the case is labelled "gears" (only the
/// gears at T), not "uniform", and its housing column shows H (black-box helper-21).
#[test]
fn cli_backlash_labels_a_case_uniform_only_when_the_housing_is_too() {
    let out = bin()
        .args(["backlash", "--uniform-c", "25", "--housing-c", "60"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    let row = text
        .lines()
        .find(|l| l.trim_start().starts_with("gears "))
        .unwrap_or_else(|| panic!("no gears row: {text}"));
    assert!(row.contains("60.00"), "{row}");
    assert!(!text.contains("  uniform "), "{text}");
    let out = bin()
        .args(["backlash", "--uniform-c", "25"])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stdout).contains("  uniform "));
}

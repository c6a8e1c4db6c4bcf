//! Runs stay bounded and inputs that used to be accepted but wrong are refused by key
//! (issue 8, items 3 and 5).

use std::path::Path;
use std::process::Output;

mod common;
use common::{assert_error, bin, reference_text, reference_with, snapshot, tmpdir};

fn run_in(dir: &Path, args: &[&str]) -> Output {
    bin().args(args).current_dir(dir).output().unwrap()
}

/// `command` on the reference scenario with `edits`: refused with exit 2, the first
/// error line naming `needles`, nothing written.
fn refused(case: &str, edits: &[(&str, &str)], command: &[&str], needles: &[&str]) {
    let dir = tmpdir(case);
    std::fs::write(dir.join("s.toml"), reference_with(edits)).unwrap();
    let before = snapshot(&dir);
    let mut args = command.to_vec();
    args.insert(1, "s.toml");
    let out = run_in(&dir, &args);
    assert_error(case, &out, needles);
    assert_eq!(snapshot(&dir), before, "{case}: something was written");
    let _ = std::fs::remove_dir_all(&dir);
}

const RUN: &[&str] = &["run", "--quiet"];

#[test]
fn cli_absurd_run_lengths_are_refused_by_key() {
    refused(
        "days",
        &[("orbits = 6", "duration_days = 1e9")],
        RUN,
        &["run.duration_days", "limited to 1e9 s"],
    );
    refused(
        "orbits-key",
        &[("orbits = 6", "orbits = 1e12")],
        RUN,
        &["run.orbits"],
    );
    refused(
        "orbits-flag",
        &[],
        &["run", "--orbits", "1e12", "--quiet"],
        &["--orbits 1e12", "1e9 s"],
    );
    refused(
        "orbits-bench",
        &[],
        &["bench", "--orbits", "1e12"],
        &["--orbits"],
    );
}

#[test]
fn cli_solver_limits_have_physical_lower_bounds() {
    refused(
        "max-step",
        &[("max_step_s = 300.0", "max_step_s = 1e-300")],
        RUN,
        &["solver.max_step_s", "at least 0.001 s"],
    );
    refused(
        "tolerance",
        &[("tolerance_k = 0.002", "tolerance_k = 1e-300")],
        RUN,
        &["solver.tolerance_k", "1e-6 … 10 (got 1e-300)"],
    );
    refused(
        "output-interval",
        &[("output_interval_s = 30.0", "output_interval_s = 1e-300")],
        RUN,
        &["run.output_interval_s", "at least 0.001 s"],
    );
    refused(
        "log-every",
        &[],
        &["run", "--log-every", "1e-300s"],
        &["1e-300s", "at least 0.001 s"],
    );
}

#[test]
fn cli_a_run_over_the_step_limit_needs_force() {
    // 30 days in 1 ms steps: 2.6e9 steps
    let edits = [
        ("orbits = 6", "duration_days = 30"),
        ("max_step_s = 300.0", "max_step_s = 0.001"),
    ];
    refused(
        "step-limit",
        &edits,
        &["run", "--quiet", "--no-log"],
        &["steps", "limit of 5e7", "--force"],
    );
    // with --force it would start: --dry-run shows it gets past the limit
    let dir = tmpdir("step-limit-force");
    std::fs::write(dir.join("s.toml"), reference_with(&edits)).unwrap();
    let out = run_in(&dir, &["run", "s.toml", "--no-log", "--force", "--dry-run"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("estimate: about 2.59"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_a_log_larger_than_the_free_space_is_refused_before_writing() {
    // ten years as CSV every millisecond: 3e11 rows, tens of terabytes (a log is never
    // bigger than one sample per solver step, whatever --log-every asks)
    refused(
        "disk",
        &[("orbits = 6", "duration_days = 3650")],
        &[
            "run",
            "--quiet",
            "--no-log",
            "--csv",
            "big.csv",
            "--set",
            "run.output_interval_s=0.001",
        ],
        &["the outputs would take about", "free", "output_interval_s"],
    );
}

#[test]
fn cli_large_runs_print_their_estimate_and_it_is_close() {
    let dir = tmpdir("estimate");
    std::fs::write(dir.join("s.toml"), reference_text()).unwrap();
    // 2000 orbits logged every step: about 110 MB, so the estimate is printed
    let dry = run_in(&dir, &["run", "s.toml", "--orbits", "2000", "--dry-run"]);
    assert!(
        dry.status.success(),
        "{}",
        String::from_utf8_lossy(&dry.stderr)
    );
    let stderr = String::from_utf8_lossy(&dry.stderr).to_string();
    assert!(
        !dir.join("logs/reference-hinge.mcap").exists(),
        "dry run wrote a log"
    );
    let mb: f64 = stderr
        .split("log about ")
        .nth(1)
        .and_then(|s| s.split(" MB").next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no log size in {stderr}"));
    let out = run_in(
        &dir,
        &[
            "run", "s.toml", "--orbits", "2000", "--quiet", "--out", "big.mcap",
        ],
    );
    assert!(out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("estimate: about"),
        "a 100 MB log without its estimate"
    );
    let actual = std::fs::metadata(dir.join("big.mcap")).unwrap().len() as f64 / 1e6;
    // the estimate errs high (the first orbit's transient), never low
    assert!(
        mb >= actual && mb < 1.3 * actual,
        "estimated {mb} MB, wrote {actual} MB"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_between_takes_exactly_two_nodes() {
    refused(
        "between-3",
        &[(
            "between = [\"housing\", \"motor\"]",
            "between = [\"housing\", \"motor\", \"shaft1\"]",
        )],
        &["check"],
        &["conductor.housing-motor-shaft1.between", "3 node(s)"],
    );
}

#[test]
fn cli_mode_windows_take_exactly_two_times() {
    let dir = tmpdir("windows-3");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-90-day-drift.toml"),
    )
    .unwrap();
    let at = text.find("windows_days = [").expect("a mode window");
    let close = at + text[at..].find(']').unwrap();
    let bad = format!("{}, 99.5{}", &text[..close], &text[close..]);
    std::fs::write(dir.join("s.toml"), bad).unwrap();
    let out = run_in(&dir, &["check", "s.toml"]);
    assert_error("windows-3", &out, &["windows_days[0]", "3 numbers"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_tooth_thinning_larger_than_the_tooth() {
    refused(
        "thinning",
        &[("tooth_thinning_um = 19.4745", "tooth_thinning_um = 2000")],
        &["check"],
        &["gear_pair.mesh.pinion.tooth_thinning_um", "tooth thickness"],
    );
    // a 20-tooth pinion whose tip circle is raised to 12.5 mm: its teeth end in a
    // point at 12.0 mm
    refused(
        "pointed",
        &[("tip_radius_mm = 11.0", "tip_radius_mm = 12.5")],
        &["check"],
        &[
            "gear_pair.mesh.pinion.tooth_thinning_um",
            "point below the tip radius",
        ],
    );
}

#[test]
fn cli_gravitational_parameters_that_break_the_period() {
    refused(
        "mu-big",
        &[("mu_m3_per_s2 = 3.986004418e14", "mu_m3_per_s2 = 1e300")],
        &["check"],
        &["orbit.mu_m3_per_s2"],
    );
    refused(
        "mu-small",
        &[("mu_m3_per_s2 = 3.986004418e14", "mu_m3_per_s2 = 1e-300")],
        &["run", "--quiet"],
        &["orbit.mu_m3_per_s2"],
    );
    // within the range of μ but with a period of 500 days
    refused(
        "period",
        &[("mu_m3_per_s2 = 3.986004418e14", "mu_m3_per_s2 = 1e9")],
        &["check"],
        &["orbit.mu_m3_per_s2", "period"],
    );
}

#[test]
fn cli_a_huge_start_angle_is_reduced_modulo_360_exactly() {
    // 1e20 = 360 × 277777777777777777 + 280 exactly (1e20 is an integer double), so
    // the run must be the one started at 280°.
    let dir = tmpdir("angle");
    let run = |angle: &str| {
        let text = reference_with(&[(
            "orbit_angle_at_start_deg = 0.0",
            &format!("orbit_angle_at_start_deg = {angle}"),
        )]);
        std::fs::write(dir.join("s.toml"), text).unwrap();
        let out = run_in(&dir, &["run", "s.toml", "--orbits", "2", "--no-log"]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    let huge = run("1e20");
    assert!(huge.contains("0.369"), "eclipse fraction lost: {huge}");
    assert_eq!(huge, run("280"));
    assert_ne!(huge, run("0"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_bench_needs_at_least_one_repetition() {
    let out = bin().args(["bench", "--repeat", "0"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--repeat"), "{stderr}");
}

#[test]
fn cli_values_beyond_physical_sense_are_refused_by_key() {
    refused(
        "conductance",
        &[("conductance_w_per_k = 0.25", "conductance_w_per_k = 1e20")],
        &["run", "--quiet", "--no-log"],
        &[
            "conductor.motor-shaft1.conductance_w_per_k",
            "at most 1e9 W/K",
        ],
    );
    refused(
        "capacitance",
        &[("capacitance_j_per_k = 4.06", "capacitance_j_per_k = 1e-300")],
        &["check"],
        &["capacitance_j_per_k", "at least 1e-6 J/K"],
    );
    refused(
        "area",
        &[("emissivity_area_m2 = 0.030", "emissivity_area_m2 = 1e9")],
        &["check"],
        &["emissivity_area_m2", "at most 10000 m²"],
    );
}

#[test]
fn cli_a_strain_polynomial_with_a_wrong_scale_is_refused() {
    let dir = tmpdir("strain-scale");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-90-day-drift.toml"),
    )
    .unwrap()
    .replacen("scale = 1e-5", "scale = 1e20", 1);
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let out = run_in(&dir, &["check", "s.toml"]);
    assert_error(
        "strain-scale",
        &out,
        &[
            "gear_pair.mesh.center_distance",
            "thermal strain law",
            "scale",
        ],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_powers_and_fluxes_have_upper_bounds() {
    let dir = tmpdir("power");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-90-day-drift.toml"),
    )
    .unwrap();
    let at = text.find("power_w = ").unwrap();
    let end = at + text[at..].find('\n').unwrap();
    let bad = format!("{}power_w = 1e308{}", &text[..at], &text[end..]);
    std::fs::write(dir.join("s.toml"), bad).unwrap();
    let out = run_in(&dir, &["check", "s.toml"]);
    assert_error("power", &out, &["power_w", "1e6"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_explicit_direct_solvers_must_fit_the_network() {
    let dir = tmpdir("direct-limits");
    let emit = |spec: &str| {
        let out = bin()
            .args(["bench", "--emit-network", spec])
            .output()
            .unwrap();
        String::from_utf8(out.stdout).unwrap()
    };
    std::fs::write(
        dir.join("d.toml"),
        emit("chain:3001") + "\n[solver]\nlinear = \"dense\"\n",
    )
    .unwrap();
    let out = run_in(&dir, &["check", "d.toml"]);
    assert_error("dense", &out, &["solver.linear", "limited to 3000 nodes"]);
    std::fs::write(
        dir.join("s.toml"),
        emit("random:10000") + "\n[solver]\nlinear = \"sparse\"\n",
    )
    .unwrap();
    let out = run_in(&dir, &["run", "s.toml", "--dry-run"]);
    assert_error(
        "sparse",
        &out,
        &["solver.linear", "operations per factorisation"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

//! Large networks (issue 8, item 9). The sparse LU and the preconditioned conjugate
//! gradients solve the same discrete equations as the dense LU by other numerical
//! methods: their temperatures must agree with the dense solver's, and all three
//! with a step-converged solution, on the reference mechanism and on synthetic
//! networks of hundreds of nodes. Large networks also run end to end through the CLI.
//! They share the residual and its assembly with the dense path, so these are
//! consistency checks (`core_`), not validations.

use orbitlash::io::scenario_toml::reference;
use orbitlash::run::sim::{SolverSettings, simulate};
use orbitlash::run::summary::Samples;
use orbitlash::thermal::ThermalModel;
use orbitlash::thermal::iteration::LinearSolver;
use orbitlash::thermal::synthetic::{Shape, network, network_scaled};

mod common;
use common::{bin, tmpdir};

fn samples(model: &ThermalModel, settings: &SolverSettings, t_end_s: f64) -> Samples {
    let mut s = Samples::every(60.0);
    let stats = simulate(model, &[], settings, t_end_s, &mut s, None).unwrap();
    assert_eq!(
        stats.linear_solver,
        settings.linear.resolve(model.network.nodes.len())
    );
    s
}

fn with(linear: LinearSolver) -> SolverSettings {
    SolverSettings {
        linear,
        ..SolverSettings::default()
    }
}

/// The three solvers against each other and against fixed 2 s steps (dense).
fn compare(name: &str, model: &ThermalModel, t_end_s: f64, bar_k: f64) {
    let dense = samples(model, &with(LinearSolver::Dense), t_end_s);
    let converged = samples(
        model,
        &SolverSettings {
            adaptive: false,
            max_step_s: 2.0,
            ..with(LinearSolver::Dense)
        },
        t_end_s,
    );
    let base = dense.max_abs_diff_k(&converged);
    assert!(base < bar_k, "{name}: dense {base} K from converged");
    for linear in [LinearSolver::Sparse, LinearSolver::Iterative] {
        let s = samples(model, &with(linear), t_end_s);
        let d = s.max_abs_diff_k(&dense);
        let c = s.max_abs_diff_k(&converged);
        eprintln!(
            "{name} {linear:?}: {d:.2e} K from dense, {c:.2e} K from converged (dense {base:.2e} K)"
        );
        // Same discrete equations, solved to far below the Newton tolerance: the same
        // temperatures to 1e-6 K (measured: ~1e-11 K), the same step sequence.
        assert!(d < 1e-6, "{name} {linear:?}: {d} K from dense");
        assert!(
            c < base + 1e-6,
            "{name} {linear:?}: {c} K from converged (dense {base} K)"
        );
    }
}

#[test]
fn core_linear_solvers_agree_on_the_reference_mechanism() {
    let sc = reference().with_orbits(2.0).unwrap();
    compare("reference", &sc.thermal, sc.run.duration_s, 0.05);
    // `auto` keeps the reference on the dense path, so its results are unchanged
    assert_eq!(LinearSolver::Auto.resolve(10), LinearSolver::Dense);
}

#[test]
fn core_linear_solvers_agree_on_synthetic_networks() {
    let period = network(Shape::Chain, 10)
        .environment
        .circular()
        .unwrap()
        .orbit
        .period_s();
    compare("lattice 343", &network(Shape::Lattice, 343), period, 0.05);
    compare("random 200", &network(Shape::Random, 200), period, 0.05);
    // stiff: node time constants of a few tenths of a second
    compare(
        "stiff chain 300",
        &network_scaled(Shape::Chain, 300, 100.0),
        period,
        0.05,
    );
}

#[test]
fn core_iterative_runs_are_deterministic() {
    let m = network(Shape::Lattice, 1000);
    let t = m.environment.circular().unwrap().orbit.period_s() / 3.0;
    let a = samples(&m, &with(LinearSolver::Iterative), t);
    let b = samples(&m, &with(LinearSolver::Iterative), t);
    assert_eq!(a.temps_k, b.temps_k);
}

#[test]
fn cli_a_2000_node_lattice_runs_from_the_command_line() {
    let dir = tmpdir("lattice-2000");
    let out = bin()
        .args(["bench", "--emit-network", "lattice:2000"])
        .output()
        .unwrap();
    assert!(out.status.success());
    std::fs::write(dir.join("lattice.toml"), &out.stdout).unwrap();
    let check = bin()
        .args(["check", "lattice.toml"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stderr)
    );
    assert!(
        text.contains("2000 diffusion nodes") && text.contains("linear systems: iterative"),
        "{text}"
    );
    assert!(text.contains("the 12 fastest of 2000 nodes"), "{text}");
    let run = bin()
        .args([
            "run",
            "lattice.toml",
            "--quiet",
            "--out",
            "l.mcap",
            "--csv",
            "l.csv",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        stdout.contains("no gear pair: no backlash verdict"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(dir.join("l.csv")).unwrap();
    assert_eq!(csv.lines().next().unwrap().split(',').count(), 2001);
    assert!(dir.join("l.mcap").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

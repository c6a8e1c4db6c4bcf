//! Regressions of solver cost and bookkeeping on the shipped scenarios: a change that
//! makes the solver take many more steps, reject steps, or leak energy shows here.

use orbitlash::io::scenario_toml::{load_file, reference};
use orbitlash::run::sim::{RunStats, simulate};
use orbitlash::spec::scenario::Scenario;

/// The scenario run for its own duration, with no observer.
fn run_to_end(sc: &Scenario) -> RunStats {
    simulate(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        sc.run.duration_s,
        &mut (),
        None,
    )
    .unwrap()
}

#[test]
fn regress_reference_solver_cost() {
    // The "was" figures: `orbitlash run --no-log --verbose` (solver statistics), and
    // `orbitlash bench` for steps per orbit.
    let sc = reference();
    let stats = run_to_end(&sc);
    let per_orbit = stats.steps as f64 / 6.0;
    assert!(
        (70.0..=100.0).contains(&per_orbit),
        "{per_orbit} steps per orbit (was 86)"
    );
    assert!(
        stats.rejected_steps <= 3,
        "{} rejected steps (was 1)",
        stats.rejected_steps
    );
    let newton = stats.newton_iterations as f64 / stats.steps as f64;
    assert!(
        newton < 4.5,
        "{newton} Newton iterations per step (was 3.9)"
    );
    assert_eq!(stats.eclipse_entries, 6);
    // The iteration matrix is reused across many steps (was 214 for 516 steps).
    assert!(
        stats.factorizations * 2 < stats.steps,
        "{} factorisations for {} steps",
        stats.factorizations,
        stats.steps
    );
    // The balance closes to the Newton tolerance (1 % of the step tolerance).
    assert!(
        stats.energy.relative_error() < 1e-5,
        "energy error {}",
        stats.energy.relative_error()
    );
}

#[test]
fn regress_mission_profile_runs_90_days() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-90-day-drift.toml");
    let (sc, _) = load_file(&path).unwrap();
    let stats = run_to_end(&sc);
    // `orbitlash run scenarios/hinge-90-day-drift.toml --no-log --verbose`: 1370 eclipse
    // entries.
    // β passes 0 → 60°, below the 68° where eclipses stop: one eclipse per orbit.
    assert_eq!(stats.eclipse_entries, 1370);
    assert!(
        stats.heater_switches > 100,
        "{} heater switches",
        stats.heater_switches
    );
    assert!(
        stats.energy.relative_error() < 1e-5,
        "energy error {}",
        stats.energy.relative_error()
    );
    let measured = stats.eclipse_time_s / stats.t_end_s;
    assert!(
        (0.30..0.36).contains(&measured),
        "eclipse fraction over the mission {measured}"
    );
}

#[test]
fn regress_reference_orbit6_golden_values() {
    // Golden values of the reference run (the physics behind them is validated in
    // tests/val_*): a change beyond these tolerances is a change of results and must be
    // explained. Produced by `orbitlash run --no-log` (the "last orbit" table and the
    // exact row of the gear-pair table), commit 3cfc369.
    use orbitlash::run::summary::{MeshStats, WindowStats};
    let sc = reference();
    let period = sc.period_s();
    let mut nodes = WindowStats::last(period);
    let mut mesh = MeshStats::last(period);
    simulate(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        sc.run.duration_s,
        &mut (&mut nodes, &mut mesh),
        None,
    )
    .unwrap();
    let golden = [
        ("housing", -24.74, 62.81, 28.35),
        ("gear1.r2", -18.85, 61.71, 28.36),
        ("gear2.r2", -16.30, 61.13, 28.37),
    ];
    let stats = nodes.nodes();
    for (name, lo, hi, mean) in golden {
        let s = stats.iter().find(|s| s.name == name).unwrap();
        let c = |k: f64| k - 273.15;
        assert!((c(s.min_k) - lo).abs() < 0.01, "{name} min {}", c(s.min_k));
        assert!((c(s.max_k) - hi).abs() < 0.01, "{name} max {}", c(s.max_k));
        assert!(
            (c(s.mean_k) - mean).abs() < 0.01,
            "{name} mean {}",
            c(s.mean_k)
        );
    }
    let p = &mesh.pairs[0];
    assert!(
        (p.min_exact_m * 1e6 - 24.398).abs() < 0.002,
        "min backlash {}",
        p.min_exact_m * 1e6
    );
    assert!(
        (p.max_exact_m * 1e6 - 41.982).abs() < 0.002,
        "max backlash {}",
        p.max_exact_m * 1e6
    );
}

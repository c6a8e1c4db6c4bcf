//! The backlash extremes skip the interior probes of steps whose backlash is clearly
//! monotone (`summary::MeshStats`). Second method: the same run with every step
//! probed. Both must give the same extremes, times and counts to the last bit, on the
//! reference orbit and on ten days of the drifting-β mission (with its heater, drive
//! windows and the paper model on).

use orbitlash::io::scenario_toml::{load_file, reference};
use orbitlash::run::sim::simulate;
use orbitlash::run::summary::MeshStats;
use orbitlash::spec::scenario::Scenario;

/// (skipping, probing every step) after the scenario's run of `duration_s`.
fn both(sc: &Scenario, duration_s: f64) -> (MeshStats, MeshStats) {
    let period = sc.period_s();
    let run = |mut mesh: MeshStats| {
        simulate(
            &sc.thermal,
            &sc.gears,
            &sc.solver,
            duration_s,
            &mut mesh,
            None,
        )
        .unwrap();
        mesh
    };
    (
        run(MeshStats::last(period)),
        run(MeshStats::last(period).probing_every_step()),
    )
}

fn assert_same(fast: &MeshStats, every: &MeshStats, what: &str) {
    // Debug prints each f64 exactly (shortest round trip), NaN included.
    assert_eq!(
        format!("{:?}", fast.run_pairs),
        format!("{:?}", every.run_pairs),
        "{what}: whole run"
    );
    assert_eq!(
        format!("{:?}", fast.pairs),
        format!("{:?}", every.pairs),
        "{what}: last orbit"
    );
    // The fast path is taken (most steps are monotone) and the probes still run.
    let steps = fast.skipped_steps + fast.probed_steps;
    assert!(
        fast.skipped_steps * 10 > steps * 8 && fast.probed_steps > 0,
        "{what}: {} of {steps} steps skipped",
        fast.skipped_steps
    );
    assert_eq!(every.skipped_steps, 0);
}

#[test]
fn val_second_method_reference_extremes_with_every_step_probed() {
    let sc = reference();
    let (fast, every) = both(&sc, sc.run.duration_s);
    assert_same(&fast, &every, "reference");
}

#[test]
fn val_second_method_mission_extremes_with_every_step_probed() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-90-day-drift.toml");
    let (sc, _) = load_file(&path).unwrap();
    let (fast, every) = both(&sc, 10.0 * 86400.0);
    assert_same(&fast, &every, "10 days of hinge-90-day-drift");
}

//! The default step against a step-converged solution of the same scenario: fixed
//! steps halved until the second-order error sequence has converged. A convergence
//! check of the integrator against itself, hence `core_`: the independent checks of
//! the same accuracy are the closed forms in `val_closed_forms.rs` and the truth model.

use orbitlash::io::scenario_toml::reference;
use orbitlash::run::sim::{SolverSettings, simulate};
use orbitlash::run::summary::Samples;

fn samples(settings: &SolverSettings, orbits: f64) -> Samples {
    let sc = reference().with_orbits(orbits).unwrap();
    let mut s = Samples::every(30.0);
    simulate(
        &sc.thermal,
        &sc.gears,
        settings,
        sc.run.duration_s,
        &mut s,
        None,
    )
    .unwrap();
    s
}

#[test]
fn core_step_halving_reference_default_step_within_0_05_k() {
    let orbits = 6.0;
    let fixed = |h: f64| SolverSettings {
        adaptive: false,
        max_step_s: h,
        ..SolverSettings::default()
    };
    let s4 = samples(&fixed(4.0), orbits);
    let s2 = samples(&fixed(2.0), orbits);
    let s1 = samples(&fixed(1.0), orbits);
    let d42 = s4.max_abs_diff_k(&s2);
    let d21 = s2.max_abs_diff_k(&s1);
    // Halving the step quarters the change: the sequence is in its asymptotic range,
    // and the 1 s solution is within d21/3 of the limit (Richardson).
    let ratio = d42 / d21;
    assert!(
        (3.0..5.0).contains(&ratio),
        "step-halving ratio {ratio} ({d42} / {d21})"
    );
    let converged_error_bound = d21 / 3.0;
    assert!(
        converged_error_bound < 1e-3,
        "1 s steps still {converged_error_bound} K from the limit"
    );

    let default = samples(&SolverSettings::default(), orbits);
    let err = default.max_abs_diff_k(&s1);
    assert!(
        err + converged_error_bound < 0.05,
        "default settings deviate {err} K from the step-converged solution"
    );
    // The scenario file's settings are the defaults.
    assert_eq!(reference().solver, SolverSettings::default());
}

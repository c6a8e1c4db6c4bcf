//! `[run]` and `[solver]`: how long to run and how to step.

use super::*;
use crate::spec::registry as r;

/// The run's length and output interval.
pub(super) fn run_control(
    cx: &Cx,
    run_spec: &RunSpec,
    period_s: f64,
) -> Result<RunControl, SpecError> {
    let rp = KeyPath::new("run");
    let duration = |field: &'static r::Field, v: f64, unit_s: f64| {
        let key = field.name;
        let d = cx.positive(&rp.key(key), v)? * unit_s;
        if d < MIN_DURATION_S {
            return Err(cx.err(
                &rp.key(key),
                format!(
                    "gives a run of {} s; runs last at least {MIN_DURATION_S} s",
                    num(d)
                ),
            ));
        }
        if d > MAX_DURATION_S {
            return Err(cx.err(
                &rp.key(key),
                format!(
                    "gives a run of {d:.3e} s; runs are limited to {MAX_DURATION_S:.0e} s (31.7 years), where time still resolves the shortest step"
                ),
            ));
        }
        Ok(d)
    };
    let duration_s = match (run_spec.orbits, run_spec.duration_s, run_spec.duration_days) {
        (Some(o), None, None) => duration(&r::ORBITS, o, period_s)?,
        (None, Some(s), None) => duration(&r::DURATION_S, s, 1.0)?,
        (None, None, Some(d)) => duration(&r::DURATION_DAYS, d, SECONDS_PER_DAY)?,
        _ => {
            return Err(cx.err(
                &rp,
                format!(
                    "give exactly one of `{}`, `{}` or `{}`",
                    r::ORBITS.name,
                    r::DURATION_S.name,
                    r::DURATION_DAYS.name
                ),
            ));
        }
    };
    let run = RunControl {
        duration_s,
        output_interval_s: cx.read_or_default(
            &r::OUTPUT_INTERVAL_S,
            &rp,
            run_spec.output_interval_s,
        )?,
    };
    Ok(run)
}

/// The solver's settings, defaults filled in.
pub(super) fn solver_settings(
    cx: &Cx,
    solver_spec: &SolverSpec,
) -> Result<SolverSettings, SpecError> {
    let sp = KeyPath::new("solver");
    let defaults = SolverSettings::default();
    let solver = SolverSettings {
        tolerance_k: cx.read(
            &r::TOLERANCE_K,
            &sp,
            solver_spec.tolerance_k.unwrap_or(defaults.tolerance_k),
        )?,
        max_step_s: cx.read(
            &r::MAX_STEP_S,
            &sp,
            solver_spec.max_step_s.unwrap_or(defaults.max_step_s),
        )?,
        adaptive: solver_spec.adaptive.unwrap_or(defaults.adaptive),
        linear: solver_spec.linear.unwrap_or(defaults.linear),
    };
    Ok(solver)
}

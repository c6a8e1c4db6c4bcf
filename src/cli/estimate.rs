//! What a command will cost, estimated before it starts, and the refusal of a run too
//! large to be meant (unless `--force`): `run` (in `run.rs`, with its output sizes),
//! `run --steady-state`, `margins` and `diagnose` share the limits and the words.

use anyhow::Result;

use orbitlash::margins::Horizon;
use orbitlash::run::sim::{MAX_STEPS, RunEstimate, estimate_run};
use orbitlash::run::steady::SteadyOptions;
use orbitlash::spec::scenario::Scenario;

/// Most solver steps of all the runs of one command (samples, candidates): about an
/// hour of computing on two cores for the reference mechanism.
pub const MAX_TOTAL_STEPS: f64 = 1e9;

/// Steps and wall time of a run of `sc` to `t_end_s` (from a short pilot run).
pub fn run_cost(sc: &Scenario, t_end_s: f64) -> RunEstimate {
    estimate_run(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        t_end_s,
        sc.period_s(),
        &mut (),
    )
}

/// Orbits the periodic search of `sc` may take (`steady::periodic_orbit` with its
/// default options): Newton's worst case (warm-up and every iteration's n + 1 orbits),
/// or marching's, from the slowest time constant (the start decays by e per τ, from
/// about 100 K to the tolerance), whichever `Method::Auto` would pick; at most its
/// budget.
pub fn steady_orbits(sc: &Scenario) -> f64 {
    let o = SteadyOptions::default();
    let net = &sc.thermal.network;
    let n = net.nodes.len();
    let temps: Vec<f64> = net.nodes.iter().map(|x| x.initial_temperature_k).collect();
    let boundary: Vec<f64> = net
        .boundaries
        .iter()
        .map(|b| b.temperature_k.at(0.0))
        .collect();
    let tau = orbitlash::thermal::analysis::time_constants(net, &temps, &boundary).slowest_s;
    let marching = o.warmup_orbits as f64
        + (tau / sc.period_s()).max(0.0) * (100.0 / o.tolerance_k).ln()
        + 1.0;
    let newton = o.warmup_orbits as f64 + o.max_newton_iterations as f64 * (n as f64 + 1.0);
    let orbits = if n <= o.max_newton_nodes && marching.is_finite() {
        marching.min(newton)
    } else if n <= o.max_newton_nodes {
        newton
    } else {
        marching
    };
    orbits.min(o.max_orbits as f64).max(1.0)
}

/// The periodic search of `sc` and the period reported after it.
fn steady_cost(sc: &Scenario) -> RunEstimate {
    let mut orbit = run_cost(sc, sc.period_s());
    let orbits = steady_orbits(sc) + 1.0;
    orbit.steps *= orbits;
    orbit.wall_s *= orbits;
    orbit
}

/// Refuses `steps` over `limit` unless `force`; says what a long job will take.
fn judge(what: &str, steps: f64, wall_s: f64, limit: f64, force: bool, hint: &str) -> Result<()> {
    let time = if wall_s.is_finite() {
        format!(", about {} of computing", duration(wall_s))
    } else {
        String::new()
    };
    if steps > limit && !force {
        anyhow::bail!(
            "{what} would take about {steps:.2e} solver steps{time}, more than the limit of {limit:.0e}: {hint}, or pass --force"
        );
    }
    if wall_s > 5.0 {
        eprintln!("estimate: {what}: about {steps:.3e} solver steps{time}");
    }
    Ok(())
}

/// `run --steady-state`: the periodic search and the reported period.
pub fn steady(sc: &Scenario, force: bool) -> Result<()> {
    let cost = steady_cost(sc);
    judge(
        "the periodic search",
        cost.steps,
        cost.wall_s,
        MAX_STEPS,
        force,
        "loosen solver.tolerance_k or raise solver.max_step_s, or widen a chattering heater's band (on_k … off_k)",
    )
}

/// `margins`: `samples` runs over `horizon`, spread over the cores. Returns each
/// sample's step budget: 20 × the nominal sample's estimate (and at least 1e5), so a
/// sample whose dispersed values make a thermostat chatter stops and is reported
/// instead of running without bound; none with `force`.
pub fn margins(sc: &Scenario, horizon: Horizon, samples: u64, force: bool) -> Result<u64> {
    let per = match horizon {
        Horizon::Orbits(n) => run_cost(sc, n * sc.period_s()),
        Horizon::Mission => run_cost(sc, sc.run.duration_s),
        Horizon::SteadyState => steady_cost(sc),
    };
    judge(
        "each sample",
        per.steps,
        per.wall_s,
        MAX_STEPS,
        force,
        "shorten the horizon (--orbits, --steady-state), loosen solver.tolerance_k or raise solver.max_step_s",
    )?;
    let threads = rayon::current_num_threads().max(1) as f64;
    judge(
        &format!("{samples} samples"),
        per.steps * samples as f64,
        per.wall_s * samples as f64 / threads,
        MAX_TOTAL_STEPS,
        force,
        "run fewer samples, shard them over a cluster (--shard I/N), or shorten the horizon",
    )?;
    Ok(if force {
        u64::MAX
    } else {
        (20.0 * per.steps).max(1e5).min(u64::MAX as f64) as u64
    })
}

/// `diagnose`: about `runs` runs of the scenario over `span_s` of recording.
pub fn diagnose(sc: &Scenario, span_s: f64, runs: f64, force: bool) -> Result<()> {
    let per = run_cost(sc, span_s);
    judge(
        "the model over the recording",
        per.steps,
        per.wall_s,
        MAX_STEPS,
        force,
        "check the recording's time column (seconds from the start), or cut the recording",
    )?;
    judge(
        &format!("diagnose (about {runs:.0} runs of the model)"),
        per.steps * runs,
        per.wall_s * runs / rayon::current_num_threads().max(1) as f64,
        MAX_TOTAL_STEPS,
        force,
        "cut the recording into shorter stretches",
    )
}

pub fn duration(s: f64) -> String {
    match s {
        s if s >= 3.15576e9 => format!("{} years", orbitlash::units::num(s / 3.15576e7)),
        s if s >= 86400.0 => format!("{:.1} days", s / 86400.0),
        s if s >= 3600.0 => format!("{:.1} h", s / 3600.0),
        s if s >= 60.0 => format!("{:.1} min", s / 60.0),
        s => format!("{s:.1} s"),
    }
}

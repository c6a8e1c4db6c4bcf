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

/// The longest computation a command starts without `--force`, s of wall time on
/// this machine's cores (the step limits are about the same for the reference).
pub const MAX_WALL_S: f64 = 3600.0;

/// The most memory a command takes without `--force`, bytes: half the machine's
/// (8 GiB when it cannot be read).
pub fn max_memory_bytes() -> f64 {
    let total_kib = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines()
            .find_map(|l| l.strip_prefix("MemTotal:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
    });
    total_kib.map_or(8.0 * (1u64 << 30) as f64, |k| 0.5 * k * 1024.0)
}

/// A job refused by its cost: what it would take and over which limit (`cost`), and
/// what to change (`hint`). Shown with `--force` as the last resort; a command without
/// `--force` (`bench`) words its own advice from `cost`.
#[derive(Debug, thiserror::Error)]
#[error("{cost}: {hint}, or pass --force")]
pub struct OverLimit {
    pub cost: String,
    pub hint: String,
}

/// Refuses a job past any of the limits (`limit` solver steps, [`MAX_WALL_S`],
/// [`max_memory_bytes`]) unless `force`; says what a long or large job will take.
pub fn judge_cost(
    what: &str,
    steps: f64,
    wall_s: f64,
    memory_bytes: f64,
    limit: f64,
    force: bool,
    hint: &str,
) -> Result<(), OverLimit> {
    let time = if wall_s.is_finite() {
        format!(", about {} of computing", duration(wall_s))
    } else {
        String::new()
    };
    let memory = if memory_bytes > 100e6 {
        format!(" and {:.1} GB of memory", memory_bytes / 1e9)
    } else {
        String::new()
    };
    let over = if steps > limit {
        Some(format!("more than the limit of {limit:.0e} steps"))
    } else if wall_s > MAX_WALL_S {
        Some(format!("more than {} of computing", duration(MAX_WALL_S)))
    } else if memory_bytes > max_memory_bytes() {
        Some(format!(
            "more than the {:.1} GB of memory allowed (half the machine's)",
            max_memory_bytes() / 1e9
        ))
    } else {
        None
    };
    if let Some(over) = over
        && !force
    {
        return Err(OverLimit {
            cost: format!("{what} would take about {steps:.2e} solver steps{time}{memory}, {over}"),
            hint: hint.to_string(),
        });
    }
    if wall_s > 5.0 || memory_bytes > 1e9 {
        eprintln!("estimate: {what}: about {steps:.3e} solver steps{time}{memory}");
    }
    Ok(())
}

/// [`judge_cost`] without a memory estimate.
fn judge(
    what: &str,
    steps: f64,
    wall_s: f64,
    limit: f64,
    force: bool,
    hint: &str,
) -> Result<(), OverLimit> {
    judge_cost(what, steps, wall_s, 0.0, limit, force, hint)
}

/// `run --steady-state`: the periodic search and the reported period.
pub fn steady(sc: &Scenario, force: bool) -> Result<(), OverLimit> {
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
pub fn margins(
    sc: &Scenario,
    horizon: Horizon,
    samples: u64,
    force: bool,
) -> Result<u64, OverLimit> {
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

/// Each model run of a diagnosis, per recorded value (row × channel): sampling the
/// run there, the residual and its statistics, s. Measured on the reference with the
/// heater recording resampled from 2 271 to 227 000 rows (docs/performance.md: the
/// CPU time grows by 0.40 ms per row over its ~820 runs of 6 channels).
pub const DIAGNOSE_S_PER_VALUE_RUN: f64 = 81e-9;
/// Memory per recorded value (row × channel), bytes, and the base (same measurements:
/// 18 MB at 2 271 rows, 280 MB at 68 000, 830 MB at 227 000).
pub const DIAGNOSE_BYTES_PER_VALUE: f64 = 620.0;
pub const DIAGNOSE_BASE_BYTES: f64 = 15e6;

/// `diagnose`: about `runs` runs of the scenario over `span_s` of a recording of
/// `values` readings (rows × channels).
pub fn diagnose(
    sc: &Scenario,
    span_s: f64,
    values: f64,
    runs: f64,
    force: bool,
) -> Result<(), OverLimit> {
    let per = run_cost(sc, span_s);
    judge(
        "the model over the recording",
        per.steps,
        per.wall_s,
        MAX_STEPS,
        force,
        "check the recording's time column (seconds from the start), or cut the recording",
    )?;
    let per_run_s = per.wall_s + values * DIAGNOSE_S_PER_VALUE_RUN;
    judge_cost(
        &format!("diagnose (about {runs:.0} runs of the model, {values:.0} recorded values)"),
        per.steps * runs,
        per_run_s * runs / rayon::current_num_threads().max(1) as f64,
        DIAGNOSE_BASE_BYTES + values * DIAGNOSE_BYTES_PER_VALUE,
        MAX_TOTAL_STEPS,
        force,
        "cut the recording into shorter stretches or thin its rows",
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

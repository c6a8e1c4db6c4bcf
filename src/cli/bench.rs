//! `orbitlash bench`: cost of the thermal solver per step and per orbit, with the
//! accuracy it reached against a step-converged run of the same scenario.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;

use orbitlash::sim::{SolverSettings, simulate};
use orbitlash::summary::Samples;

use super::{load, orbits_arg, print_out};

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scenario file (TOML). Default: the embedded reference-hinge scenario.
    scenario: Option<PathBuf>,
    /// Orbits per timed run.
    #[arg(long, value_parser = orbits_arg, default_value = "6")]
    orbits: f64,
    /// Timed repetitions (the median is reported).
    #[arg(long, default_value_t = 31)]
    repeat: usize,
    /// Skip the accuracy comparison with a step-converged run (for profiling).
    #[arg(long)]
    no_accuracy: bool,
}

pub fn bench(a: BenchArgs) -> Result<()> {
    let mut o = String::new();
    let loaded = load(a.scenario.as_deref())?;
    let sc = loaded.scenario.with_orbits(a.orbits);
    let t_end = sc.run.duration_s;
    let period = sc.period_s();
    let repeat = a.repeat.max(1);

    let mut times = Vec::with_capacity(repeat);
    let mut steps = 0;
    for _ in 0..repeat {
        let start = Instant::now();
        let stats = simulate(&sc.thermal, &sc.gears, &sc.solver, t_end, &mut (), None)?;
        times.push(start.elapsed().as_secs_f64());
        steps = stats.steps;
    }
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    let orbits = t_end / period;

    outln!(
        o,
        "{}: {orbits:.2} orbits, {} nodes",
        sc.name,
        sc.thermal.network.nodes.len()
    );
    outln!(
        o,
        "solver tr-bdf2 tolerance {} K, max step {} s: {steps} steps ({:.1} per orbit)",
        sc.solver.tolerance_k,
        sc.solver.max_step_s,
        steps as f64 / orbits
    );
    outln!(
        o,
        "median of {repeat} runs: {:.3} ms per run, {:.1} µs per orbit, {:.3} µs per step",
        median * 1e3,
        median * 1e6 / orbits,
        median * 1e6 / steps as f64
    );
    if a.no_accuracy {
        return print_out(&o);
    }
    // Accuracy against a step-converged run (fixed 0.5 s steps; TR-BDF2 is second order,
    // so its own error is ~(0.5/300)² of the default's).
    let mut ours = Samples::every(30.0);
    simulate(&sc.thermal, &sc.gears, &sc.solver, t_end, &mut ours, None)?;
    let fine = SolverSettings {
        adaptive: false,
        max_step_s: 0.5,
        ..sc.solver.clone()
    };
    let mut reference = Samples::every(30.0);
    simulate(&sc.thermal, &sc.gears, &fine, t_end, &mut reference, None)?;

    outln!(
        o,
        "accuracy: max |T − T_converged| = {:.4} K over all nodes, every 30 s",
        ours.max_abs_diff_k(&reference)
    );
    print_out(&o)
}

//! `orbitlash bench`: cost of the thermal solver per step and per orbit, with the
//! accuracy it reached against a step-converged run of the same scenario.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use orbitlash::orbit::EnvironmentModel;

use orbitlash::io::mcap_log::{LogCadence, McapLog, Provenance, estimated_bytes_per_sample};
use orbitlash::io::output::OutputPolicy;
use orbitlash::run::sim::{MAX_STEPS, SolverSettings, estimate_run, simulate};
use orbitlash::run::summary::{MeshStats, Samples, WindowStats};
use orbitlash::spec::scenario::Scenario;
use orbitlash::thermal::iteration::LinearSolver;

use super::{load, orbits_arg, print_out};

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scenario file (TOML). Default: the embedded reference-hinge scenario.
    scenario: Option<PathBuf>,
    /// Orbits per timed run.
    #[arg(long, value_parser = orbits_arg, default_value = "6")]
    orbits: f64,
    /// Timed repetitions (the median is reported), 1 … 10000.
    #[arg(long, default_value_t = 31, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    repeat: u32,
    /// Skip the accuracy comparison with a step-converged run (for profiling).
    #[arg(long)]
    no_accuracy: bool,
    /// Instead: the cost per step of synthetic networks (chains, 3-D lattices, random
    /// sparse graphs) of 10 … 10 000 nodes with the dense, sparse LU and iterative
    /// linear solvers.
    #[arg(long)]
    scaling: bool,
    /// With --scaling: node counts to measure, 2 … 1000000 (default 10,100,1000,2000,10000).
    #[arg(long, value_delimiter = ',', requires = "scaling",
          value_parser = clap::value_parser!(u64).range(2..=1_000_000))]
    nodes: Vec<u64>,
    /// With --scaling: shapes to measure (chain, lattice, random; default all).
    #[arg(long, value_delimiter = ',', requires = "scaling")]
    shapes: Vec<String>,
    /// With --scaling: multiply every node-to-node conductance (100: a stiff network),
    /// 1e-3 … 1e6.
    #[arg(long, default_value_t = 1.0, requires = "scaling", value_parser = scale_arg)]
    conductance_scale: f64,
    /// Instead: the wall time of `diagnose` on this recording (CSV or MCAP) with the
    /// full vocabulary, the median of --repeat runs (at most 9), and the time per
    /// candidate.
    #[arg(long, value_name = "RECORDING", conflicts_with_all = ["scaling", "emit_network"])]
    diagnose: Option<PathBuf>,
    /// Instead: the wall time of `margins` on the scenario (its [[dispersion]] entries)
    /// with one thread and with every core, the parallel efficiency, and that both give
    /// the same report. Horizon: --margins-horizon.
    #[arg(long, conflicts_with_all = ["scaling", "diagnose", "emit_network"])]
    margins: bool,
    /// With --margins: samples per timed run, 1 … 1000000.
    #[arg(long, default_value_t = 1000, requires = "margins",
          value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    samples: u64,
    /// With --margins: `steady` (one period of each sample's periodic orbit), `mission`
    /// (the scenario's run) or a number of orbits.
    #[arg(long, default_value = "steady", requires = "margins")]
    margins_horizon: String,
    /// Print a synthetic network as a scenario file (e.g. `lattice:2000`) and exit.
    #[arg(long, value_name = "SHAPE:NODES", conflicts_with = "scaling")]
    emit_network: Option<String>,
    /// With --scaling: seconds of wall time per measurement at most, 0.01 … 3600.
    #[arg(long, default_value_t = 10.0, requires = "scaling", value_parser = budget_arg)]
    budget_s: f64,
}

/// One measurement of the cost per step.
struct PerStep {
    ms: f64,
    steps: u64,
    factorizations: f64,
    newton: f64,
    cg_per_solve: f64,
}

/// Wall time per step of `model` with `linear`, over at most one orbit, 300 steps or
/// `budget_s` of wall time.
fn time_per_step(
    model: &orbitlash::thermal::ThermalModel,
    linear: LinearSolver,
    budget_s: f64,
) -> Result<PerStep> {
    use std::sync::atomic::{AtomicBool, Ordering};
    struct Budget<'a>(Instant, u64, f64, &'a AtomicBool);
    impl orbitlash::run::sim::Observer for Budget<'_> {
        fn on_step(
            &mut self,
            _: &orbitlash::run::sim::StepView<'_>,
        ) -> orbitlash::run::sim::ObserverResult {
            self.1 += 1;
            if self.1 >= 300 || self.0.elapsed().as_secs_f64() > self.2 {
                self.3.store(true, Ordering::Relaxed);
            }
            Ok(())
        }
    }
    let settings = SolverSettings {
        linear,
        ..SolverSettings::default()
    };
    let stop = AtomicBool::new(false);
    let start = Instant::now();
    let period = model.environment.mean_period_s();
    let stats = simulate(
        model,
        &[],
        &settings,
        period,
        &mut Budget(start, 0, budget_s, &stop),
        Some(&stop),
    )?;
    let wall = start.elapsed().as_secs_f64();
    let steps = stats.steps.max(1) as f64;
    Ok(PerStep {
        ms: wall * 1e3 / steps,
        steps: stats.steps,
        factorizations: stats.factorizations as f64 / steps,
        newton: stats.newton_iterations as f64 / steps,
        cg_per_solve: stats.krylov_iterations as f64 / stats.linear_solves.max(1) as f64,
    })
}

/// Above this many nodes the scaling table leaves out the dense and sparse direct
/// solvers (n² memory and minutes per factorisation for dense; for sparse LU, the fill
/// of a random graph's factors is that of a dense matrix).
const DIRECT_MAX_NODES: usize = orbitlash::thermal::iteration::DENSE_MAX_NODES;

fn scaling(a: &BenchArgs) -> Result<()> {
    use orbitlash::thermal::synthetic::network_scaled;
    let sizes: Vec<usize> = if a.nodes.is_empty() {
        vec![10, 100, 1000, 2000, 10000]
    } else {
        a.nodes.iter().map(|&n| n as usize).collect()
    };
    let names = if a.shapes.is_empty() {
        vec!["chain".to_string(), "lattice".into(), "random".into()]
    } else {
        a.shapes.clone()
    };
    let shapes = names
        .iter()
        .map(|s| parse_shape(s))
        .collect::<Result<Vec<_>>>()?;
    let mut o = String::new();
    outln!(
        o,
        "cost per step, ms (TR-BDF2, tolerance 0.002 K, one orbit or {} s of wall time; conductances ×{}):",
        a.budget_s,
        a.conductance_scale
    );
    // Fixed widths, not `cli::table`: each row prints as soon as it is measured (a
    // large network takes minutes), so the widths cannot wait for the last row.
    outln!(
        o,
        "{:8} {:>6} {:>6} | {:>10} {:>10} {:>10} | {:>5} {:>7} {:>6} {:>6}",
        "shape",
        "nodes",
        "links",
        "dense",
        "sparse LU",
        "iterative",
        "steps",
        "fact/st",
        "Newton",
        "CG/sol"
    );
    print_out(&o)?;
    for &shape in &shapes {
        for &n in &sizes {
            // 2000 is the 20 × 10 × 10 lattice; other shapes skip it unless asked
            if n == 2000 && shape.name() != "lattice" && a.nodes.is_empty() {
                continue;
            }
            let model = network_scaled(shape, n, a.conductance_scale);
            let nodes = model.network.nodes.len();
            let links = model.network.conductors.len() + model.network.radiators.len();
            let direct = |linear| -> Result<String> {
                Ok(if nodes <= DIRECT_MAX_NODES {
                    format!("{:.4}", time_per_step(&model, linear, a.budget_s)?.ms)
                } else {
                    "–".to_string()
                })
            };
            let dense = direct(LinearSolver::Dense)?;
            let sparse = direct(LinearSolver::Sparse)?;
            let it = time_per_step(&model, LinearSolver::Iterative, a.budget_s)?;
            let mut o = String::new();
            outln!(
                o,
                "{:8} {:>6} {:>6} | {:>10} {:>10} {:>10.4} | {:>5} {:>7.2} {:>6.2} {:>6.1}",
                shape.name(),
                nodes,
                links,
                dense,
                sparse,
                it.ms,
                it.steps,
                it.factorizations,
                it.newton,
                it.cg_per_solve
            );
            print_out(&o)?;
        }
    }
    Ok(())
}

fn ranged(s: &str, lo: f64, hi: f64) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a number within {lo} … {hi}")),
    }
}

fn scale_arg(s: &str) -> Result<f64, String> {
    ranged(s, 1e-3, 1e6)
}

fn budget_arg(s: &str) -> Result<f64, String> {
    ranged(s, 0.01, 3600.0)
}

fn parse_shape(s: &str) -> Result<orbitlash::thermal::synthetic::Shape> {
    use orbitlash::thermal::synthetic::Shape;
    Ok(match s {
        "chain" => Shape::Chain,
        "lattice" => Shape::Lattice,
        "random" => Shape::Random,
        other => anyhow::bail!("unknown shape `{other}` (known: chain, lattice, random)"),
    })
}

/// What `orbitlash bench` measures, from its flags.
enum Mode<'a> {
    /// Synthetic networks of many sizes (`--scaling`).
    Scaling,
    /// `diagnose` on a recording (`--diagnose`).
    Diagnose(&'a std::path::Path),
    /// `margins` with one thread and every core (`--margins`).
    Margins,
    /// Print a synthetic network as a scenario (`--emit-network SHAPE:NODES`).
    EmitNetwork(&'a str),
    /// The solver, logging, parameter writes, the backlash and the accuracy on a
    /// scenario (the default).
    Solver,
}

impl BenchArgs {
    fn mode(&self) -> Mode<'_> {
        if self.scaling {
            Mode::Scaling
        } else if let Some(rec) = &self.diagnose {
            Mode::Diagnose(rec)
        } else if self.margins {
            Mode::Margins
        } else if let Some(spec) = &self.emit_network {
            Mode::EmitNetwork(spec)
        } else {
            Mode::Solver
        }
    }
}

pub fn bench(a: BenchArgs) -> Result<()> {
    match a.mode() {
        Mode::Scaling => scaling(&a),
        Mode::Diagnose(rec) => bench_diagnose(&a, rec),
        Mode::Margins => bench_margins(&a),
        Mode::EmitNetwork(spec) => emit_network(spec),
        Mode::Solver => bench_solver(&a),
    }
}

/// `bench --emit-network SHAPE:NODES`: a synthetic network as scenario text.
fn emit_network(spec: &str) -> Result<()> {
    use orbitlash::thermal::synthetic::{network, to_toml};
    let (shape, n) = spec.split_once(':').ok_or_else(|| {
        anyhow::anyhow!("--emit-network {spec}: give SHAPE:NODES, e.g. lattice:2000")
    })?;
    let n: usize = n
        .parse()
        .ok()
        .filter(|&n| (2..=1_000_000).contains(&n))
        .ok_or_else(|| anyhow::anyhow!("--emit-network {spec}: NODES must be 2 … 1000000"))?;
    let model = network(parse_shape(shape)?, n);
    print_out(&to_toml(&model, &format!("{shape}-{n}"), 1.0))
}

/// `bench` on a scenario: solver cost per orbit and step, logging, parameter writes,
/// backlash evaluation and accuracy against a step-converged run.
fn bench_solver(a: &BenchArgs) -> Result<()> {
    let mut o = String::new();
    let loaded = load(a.scenario.as_deref())?;
    let sc = loaded
        .scenario()
        .clone()
        .with_orbits(a.orbits)
        .map_err(|m| anyhow::anyhow!("--orbits {}: {m}", orbitlash::units::num(a.orbits)))?;
    let est = estimate_run(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        sc.run.duration_s,
        sc.period_s(),
        &mut (),
    );
    if est.steps > MAX_STEPS {
        anyhow::bail!(
            "--orbits {}: one timed run would take about {:.2e} steps, more than the limit of {MAX_STEPS:.0e}",
            a.orbits,
            est.steps
        );
    }
    let t_end = sc.run.duration_s;
    let repeat = a.repeat as usize;

    let steps = solver_cost(&sc, repeat, &mut o)?;
    logging_cost(&sc, steps, repeat, &mut o)?;
    parameter_cost(&loaded.model, &mut o)?;
    backlash_cost(&sc, &mut o)?;
    if a.no_accuracy {
        return print_out(&o);
    }
    if t_end / 0.5 > MAX_STEPS / 10.0 {
        outln!(
            o,
            "accuracy: not measured (the step-converged run would take {:.1e} steps; use fewer --orbits)",
            t_end / 0.5
        );
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

/// The thermal solver alone: the median of `repeat` runs, per run, orbit and step.
/// Returns the steps of one run.
fn solver_cost(sc: &Scenario, repeat: usize, o: &mut String) -> Result<u64> {
    let (t_end, period) = (sc.run.duration_s, sc.period_s());
    let mut times = Vec::with_capacity(repeat);
    let mut steps = 0;
    for _ in 0..repeat {
        let start = Instant::now();
        // The thermal part alone; gear evaluation is timed below.
        let stats = simulate(&sc.thermal, &[], &sc.solver, t_end, &mut (), None)?;
        times.push(start.elapsed().as_secs_f64());
        steps = stats.steps;
    }
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    let orbits = t_end / period;

    outln!(
        *o,
        "{}: {}, {} nodes",
        sc.name,
        orbitlash::units::orbits(orbits, 2),
        sc.thermal.network.nodes.len()
    );
    outln!(
        *o,
        "solver tr-bdf2 tolerance {} K, max step {} s: {steps} steps ({:.1} per orbit)",
        sc.solver.tolerance_k,
        sc.solver.max_step_s,
        steps as f64 / orbits
    );
    outln!(
        *o,
        "median of {repeat} runs: {:.3} ms per run, {:.1} µs per orbit, {:.3} µs per step",
        median * 1e3,
        median * 1e6 / orbits,
        median * 1e6 / steps as f64
    );
    Ok(steps)
}

/// A run with the observers `run` uses, with and without an MCAP log of every step,
/// unless that log would be large.
fn logging_cost(sc: &Scenario, steps: u64, repeat: usize, o: &mut String) -> Result<()> {
    let (t_end, period) = (sc.run.duration_s, sc.period_s());
    let orbits = t_end / period;
    // Logging every step: the full run (summaries and gear evaluation included) with
    // and without the MCAP log, unless that log would be large.
    let log_bytes = (steps as f64 + 1.0) * estimated_bytes_per_sample(&sc.thermal, &sc.gears);
    let tmp = std::env::temp_dir();
    let free = orbitlash::io::output::available_bytes(&tmp.join("x")).unwrap_or(u64::MAX) as f64;
    if log_bytes > 200e6 || log_bytes > 0.5 * free {
        outln!(
            *o,
            "logging every step: not measured (the log would take about {:.0} MB; use fewer --orbits)",
            log_bytes / 1e6
        );
    } else {
        let dir = std::env::temp_dir().join(format!("orbitlash-bench-{}", std::process::id()));
        let path = dir.join("bench.mcap");
        let prov = || Provenance {
            scenario_name: sc.name.clone(),
            scenario_file: "<bench>".into(),
            scenario_toml: String::new(),
            solver: String::new(),
            seed: None,
            sets: vec![],
        };
        let run = |log: bool| -> Result<(f64, u64)> {
            // the observers `run` uses besides the outputs
            let mut summary = (
                MeshStats::last(period),
                WindowStats::last(period),
                WindowStats::last(t_end),
            );
            let mut mcap = if log {
                Some(McapLog::create(
                    &path,
                    prov(),
                    LogCadence::Steps(1),
                    &OutputPolicy::default_in_logs(&[]),
                )?)
            } else {
                None
            };
            let start = Instant::now();
            simulate(
                &sc.thermal,
                &sc.gears,
                &sc.solver,
                t_end,
                &mut (&mut summary, &mut mcap),
                None,
            )?;
            let wall = start.elapsed().as_secs_f64();
            Ok((
                wall,
                if log {
                    std::fs::metadata(&path)?.len()
                } else {
                    0
                },
            ))
        };
        let mut with = Vec::new();
        let mut without = Vec::new();
        let mut size = 0;
        for _ in 0..repeat.min(15) {
            without.push(run(false)?.0);
            let (w, s) = run(true)?;
            with.push(w);
            size = s;
        }
        with.sort_by(f64::total_cmp);
        without.sort_by(f64::total_cmp);
        let (w, wo) = (with[with.len() / 2], without[without.len() / 2]);
        outln!(
            *o,
            "logging every step: {:.3} ms with the MCAP log vs {:.3} ms without (+{:.0} %), {:.1} kB per orbit",
            w * 1e3,
            wo * 1e3,
            (w / wo - 1.0) * 100.0,
            size as f64 / 1e3 / orbits
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(())
}

/// Ten changes to a built model by resolved key path, then a run set up and its start
/// state made (what a Monte Carlo sample does before it steps); and a change that
/// recompiles the whole scenario.
fn parameter_cost(model: &orbitlash::spec::model::Model, o: &mut String) -> Result<()> {
    // Parameters: ten changes to a built model by resolved key path, then a run set up
    // and its start state made (what a Monte Carlo sample does before it steps).
    {
        let mut model = model.clone();
        let wanted = [
            "node.housing.capacitance_j_per_k",
            "node.motor.capacitance_j_per_k",
            "node.shaft1.capacitance_j_per_k",
            "conductor.housing-bus.conductance_w_per_k",
            "conductor.housing-motor.conductance_w_per_k",
            "sun.\"sun.housing\".absorptivity",
            "radiation.housing-space.emissivity_area_m2",
            "environment.albedo",
            "gear_pair.mesh.pinion.tooth_thinning_um",
            "gear_pair.mesh.pinion.material.alpha_per_k",
        ];
        let ids: Vec<_> = wanted.iter().filter_map(|p| model.param(p).ok()).collect();
        if ids.len() == wanted.len() {
            let base: Vec<f64> = ids.iter().map(|id| model.get(id.path()).unwrap()).collect();
            let rounds = 2000;
            let mut times = Vec::with_capacity(rounds);
            let mut writes = Vec::with_capacity(rounds);
            for r in 0..rounds {
                let start = Instant::now();
                for (id, b) in ids.iter().zip(&base) {
                    let v = b * (1.0 + 1e-3 * ((r % 7) as f64 - 3.0));
                    model.set_param(id, v)?;
                }
                writes.push(start.elapsed().as_secs_f64());
                let sc = model.scenario();
                let setup = orbitlash::run::sim::Setup::new(&sc.thermal, &sc.gears, &sc.solver);
                std::hint::black_box(setup.initial_state());
                times.push(start.elapsed().as_secs_f64());
            }
            times.sort_by(f64::total_cmp);
            writes.sort_by(f64::total_cmp);
            outln!(
                *o,
                "parameters: {:.2} µs to apply 10 changes by key path and start a run, {:.2} µs of it the changes (medians of {rounds})",
                times[rounds / 2] * 1e6,
                writes[rounds / 2] * 1e6
            );
        }
        evaluation_write_cost(&model, o)?;
        // A change that recompiles the whole scenario (the altitude: period, view
        // factors, eclipse geometry).
        if let Ok(id) = model.param("orbit.altitude_m") {
            let base = model.get(id.path()).unwrap();
            let rounds = 500;
            let mut times = Vec::with_capacity(rounds);
            for r in 0..rounds {
                let start = Instant::now();
                model.set_param(&id, base * (1.0 + 1e-3 * ((r % 7) as f64 - 3.0)))?;
                times.push(start.elapsed().as_secs_f64());
            }
            times.sort_by(f64::total_cmp);
            outln!(
                *o,
                "            {:.2} µs for a change that recompiles the scenario (orbit.altitude_m, median of {rounds})",
                times[rounds / 2] * 1e6
            );
        }
    }
    Ok(())
}

/// What one evaluation of a `diagnose` fit costs before it simulates: a copy of the
/// model with three calibrated numbers written, by key path and compiled (`set_many`,
/// how diagnose wrote them before the registry) and by resolved parameters through
/// the fast writes (`set_params`, how it writes them now).
fn evaluation_write_cost(model: &orbitlash::spec::model::Model, o: &mut String) -> Result<()> {
    let chosen: Vec<_> = model
        .params()
        .into_iter()
        .filter(|p| p.id.row().calibration.is_some() && p.value > 0.0)
        .take(3)
        .collect();
    if chosen.is_empty() {
        return Ok(());
    }
    let ids: Vec<_> = chosen
        .iter()
        .map(|p| model.param(&p.path))
        .collect::<Result<_, _>>()?;
    let rounds = 1000;
    let median = |f: &mut dyn FnMut(f64) -> Result<()>| -> Result<f64> {
        let mut times = Vec::with_capacity(rounds);
        for r in 0..rounds {
            let scale = 1.0 + 1e-3 * ((r % 7) as f64 - 3.0);
            let start = Instant::now();
            f(scale)?;
            times.push(start.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        Ok(times[rounds / 2])
    };
    let by_path = median(&mut |k| {
        let mut m = model.clone();
        let values: Vec<(&str, f64)> = chosen
            .iter()
            .map(|p| (p.path.as_str(), p.value * k))
            .collect();
        m.set_many(&values)?;
        std::hint::black_box(m);
        Ok(())
    })?;
    let by_id = median(&mut |k| {
        let mut m = model.clone();
        let values: Vec<_> = ids
            .iter()
            .zip(&chosen)
            .map(|(id, p)| (id, p.value * k))
            .collect();
        m.set_params(&values)?;
        std::hint::black_box(m);
        Ok(())
    })?;
    outln!(
        *o,
        "diagnose:   {:.2} µs per evaluation to copy the model and write {} calibrated numbers ({}): {:.2} µs by key path and compile (median of {rounds})",
        by_id * 1e6,
        chosen.len(),
        chosen
            .iter()
            .map(|p| p.path.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        by_path * 1e6
    );
    Ok(())
}

/// Every pair evaluated at the node temperatures of the end of a run, slightly varied.
fn backlash_cost(sc: &Scenario, o: &mut String) -> Result<()> {
    let t_end = sc.run.duration_s;
    // Backlash: every pair evaluated at the node temperatures of the end of a run.
    if !sc.gears.is_empty() {
        let stats = simulate(&sc.thermal, &sc.gears, &sc.solver, t_end, &mut (), None)?;
        let temps = stats.final_temperatures_k;
        let evals = 200_000;
        let mut times = Vec::new();
        let mut sink = 0.0;
        for _ in 0..5 {
            let start = Instant::now();
            for i in 0..evals {
                let mut t = temps.clone();
                let len = t.len();
                t[i % len] += 1e-3 * (i % 7) as f64;
                for g in &sc.gears {
                    sink += g.evaluate(&t).map_or(0.0, |m| m.backlash_exact_m);
                }
            }
            times.push(start.elapsed().as_secs_f64());
        }
        times.sort_by(f64::total_cmp);
        outln!(
            *o,
            "backlash: {:.3} µs per evaluation of all {} pair(s) (exact, closed form, paper), median of 5 × {evals}{}",
            times[2] * 1e6 / evals as f64,
            sc.gears.len(),
            if sink.is_nan() {
                " (some states invalid)"
            } else {
                ""
            }
        );
    }
    Ok(())
}

/// `bench --margins`: margins with 1 thread and with every core.
fn bench_margins(a: &BenchArgs) -> Result<()> {
    use orbitlash::margins::dispersion::Sampling;
    use orbitlash::margins::{Horizon, run_samples};
    let loaded = load(a.scenario.as_deref())?;
    if loaded.model.spec().dispersion.is_empty() {
        anyhow::bail!("{} has no [[dispersion]]: nothing to sample", loaded.file);
    }
    let horizon = match a.margins_horizon.as_str() {
        "steady" => {
            orbitlash::run::steady::check_repeats(&loaded.scenario().thermal)
                .map_err(|e| anyhow::anyhow!("--margins-horizon steady: {e}"))?;
            Horizon::SteadyState
        }
        "mission" => Horizon::Mission,
        other => Horizon::Orbits(super::orbits_arg(other).map_err(|e| {
            anyhow::anyhow!(
                "--margins-horizon {other}: steady, mission or a number of orbits ({e})"
            )
        })?),
    };
    // margins' own advice names margins' flags (--orbits, --force): bench has its own
    let max_steps = super::estimate::margins(loaded.scenario(), horizon, a.samples, false)
        .map_err(|e| {
            anyhow::anyhow!(
                "{}: bench measures only what margins would run without --force; shorten --margins-horizon or lower --samples",
                e.cost
            )
        })?;
    let plan = super::plan(
        &loaded,
        Sampling::Random,
        a.samples,
        1,
        super::SetsOnDispersed::Refused,
    )?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let timed = |threads: usize| -> Result<(f64, Vec<orbitlash::margins::SampleOutcome>)> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let done = std::sync::atomic::AtomicU64::new(0);
        let t0 = Instant::now();
        let out = pool.install(|| {
            run_samples(
                &loaded.model,
                &plan,
                0..a.samples,
                horizon,
                max_steps,
                &done,
            )
        });
        Ok((t0.elapsed().as_secs_f64(), out))
    };
    // One untimed sample first: it fills what every sample shares (a TLE orbit's
    // table), so that neither timing pays for it.
    let _ = orbitlash::margins::run_sample(&loaded.model, &plan, 0, horizon, max_steps);
    let (t1, one) = timed(1)?;
    let (tn, all) = timed(cores)?;
    // bit for bit: compare the serialised outcomes (NaN = NaN, −0 ≠ 0)
    let same = serde_json::to_string(&one)? == serde_json::to_string(&all)?;
    let mut o = String::new();
    outln!(
        o,
        "margins on {}: {} samples, {}, {} dispersed numbers",
        loaded.file,
        a.samples,
        match horizon {
            Horizon::SteadyState => "one period of each sample's periodic orbit".to_string(),
            Horizon::Mission => format!(
                "the scenario's run ({:.1} days) each",
                &loaded.scenario().run.duration_s / 86400.0
            ),
            Horizon::Orbits(n) => format!("{} each", orbitlash::units::count(n, "orbit")),
        },
        plan.dispersions.len()
    );
    outln!(
        o,
        "  1 thread:   {t1:.3} s ({:.2} ms per sample)",
        t1 * 1e3 / a.samples as f64
    );
    outln!(
        o,
        "  {cores} threads: {tn:.3} s ({:.2} ms per sample); parallel efficiency {:.0} %",
        tn * 1e3 / a.samples as f64,
        100.0 * t1 / (cores as f64 * tn)
    );
    outln!(
        o,
        "  the same samples for 1 and {cores} threads: {}",
        if same { "yes, bit for bit" } else { "NO" }
    );
    print_out(&o)?;
    if !same {
        anyhow::bail!("the thread count changed a result");
    }
    Ok(())
}

/// `bench --diagnose`: whole diagnoses of one recording.
fn bench_diagnose(a: &BenchArgs, recording: &std::path::Path) -> Result<()> {
    use orbitlash::diagnose::{Options, diagnose};
    let loaded = load(a.scenario.as_deref())?;
    let rec = orbitlash::io::recording::Recording::read(recording)?;
    let n = a.repeat.clamp(1, 9) as usize;
    let mut runs = Vec::new();
    for _ in 0..n {
        let t0 = std::time::Instant::now();
        let d = diagnose(&loaded.model, &rec, &Options::default(), &|_, _, _| {})?;
        runs.push((t0.elapsed().as_secs_f64(), d));
    }
    runs.sort_by(|x, y| x.0.total_cmp(&y.0));
    let (wall, d) = &runs[n / 2];
    let fitted = d
        .candidates
        .iter()
        .filter(|c| c.status != orbitlash::diagnose::CandidateStatus::NotFitted)
        .count();
    let mut o = String::new();
    outln!(
        o,
        "diagnose {} against {} ({} threads): median of {n} runs",
        rec.file,
        loaded.file,
        rayon::current_num_threads()
    );
    outln!(
        o,
        "  {:.2} s wall (fastest {:.2} s, slowest {:.2} s); verdict {}",
        wall,
        runs[0].0,
        runs[n - 1].0,
        d.verdict.as_str()
    );
    outln!(
        o,
        "  {} candidates ranked, {fitted} fitted by least squares: {:.1} ms of wall time per candidate",
        d.candidates.len(),
        1e3 * d.time_per_candidate_s
    );
    outln!(
        o,
        "  {} samples × {} channels, {} whole orbits ({} held out)",
        d.series.time_s.len(),
        d.series.channels.len(),
        d.split.recorded_orbits(),
        d.split.holdout_orbits
    );
    print_out(&o)
}

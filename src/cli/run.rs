//! `orbitlash run`: simulate, observe, summarise.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use anyhow::{Result, anyhow};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use orbitlash::io::csv_export::CsvExport;
use orbitlash::io::mcap_log::{LogCadence, McapLog, Provenance, estimated_bytes_per_sample};
use orbitlash::io::output::{OutputError, OutputPolicy, Outputs, available_bytes};
use orbitlash::orbit::EnvironmentModel;
use orbitlash::run::sim::{
    MAX_STEPS, Observer, ObserverResult, RunStats, SimError, StepView, estimate_run,
};
use orbitlash::run::summary::{MeshStats, PairStats, PairVerdict, RunSummary, WindowStats};
use orbitlash::spec::scenario::Scenario;
use orbitlash::thermal::ThermalModel;
use orbitlash::units::{fixed, k_to_c};

use super::table::{self, Align};
use super::{Loaded, Outcome, default_log_path, error_chain, load_with, orbits_arg, print_out};

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scenario file (TOML). Default: the embedded reference-hinge scenario.
    scenario: Option<PathBuf>,
    /// Number of orbits to simulate (overrides the scenario's [run]).
    #[arg(long, value_parser = orbits_arg)]
    orbits: Option<f64>,
    /// MCAP log path. Default: logs/<scenario name>.mcap.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also export the time series as CSV (time_s, <node>_k, …).
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Do not write an MCAP log.
    #[arg(long, conflicts_with_all = ["out", "log_every", "scene"])]
    no_log: bool,
    /// Add a 3-D view of the gear pairs to the log (foxglove.SceneUpdate on
    /// /gears/<pair>/scene, tooth outlines coloured by rim temperature), one update
    /// every 300 s of simulated time.
    #[arg(long)]
    scene: bool,
    /// Log cadence: every N steps (e.g. 10) or every interval of simulated time (e.g.
    /// 60s). Default: every step.
    #[arg(long, value_name = "N|SECONDSs")]
    log_every: Option<LogCadence>,
    /// Change a number of the scenario by its key path (repeatable), e.g.
    /// `--set node.housing.capacitance_j_per_k=130`; `orbitlash params` lists them.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// Also write the run summary as JSON (stable keys, see the README).
    #[arg(long, value_name = "FILE.json")]
    json: Option<PathBuf>,
    /// Also draw the run (as `orbitlash plot` draws its log): `.png` or `.svg`. Needs
    /// the log (or `--csv` with `--no-log`: no eclipse shading then).
    #[arg(long, value_name = "FILE.png|svg")]
    plot: Option<PathBuf>,
    /// Find the orbit-periodic solution first (Newton shooting, marching as the
    /// fallback) and report one period of it; with --csv, exactly that period. Needs an
    /// environment that repeats every orbit (no tables or mode windows).
    #[arg(long, conflicts_with = "orbits")]
    steady_state: bool,
    /// Replay sample K of `orbitlash margins` (0-based, as its report numbers them):
    /// the scenario with that sample's dispersed values. Needs --seed.
    #[arg(long, requires = "seed")]
    sample: Option<u64>,
    /// The margins run's seed (with --sample).
    #[arg(long, requires = "sample")]
    seed: Option<u64>,
    /// The margins run's sampling (with --sample; `lhs` also needs --samples).
    #[arg(long, value_enum, default_value = "random", requires = "sample")]
    sampling: super::margins::SamplingArg,
    /// The margins run's number of samples (with --sample --sampling lhs).
    #[arg(long, requires = "sample", value_parser = super::margins::samples_arg)]
    samples: Option<u64>,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Run even when the estimate exceeds the hard limit of steps (5e7).
    #[arg(long)]
    force: bool,
    /// Check the scenario and the outputs, print the estimate of steps, time and output
    /// sizes, and stop before running (nothing is written).
    #[arg(long)]
    dry_run: bool,
    /// Also print the solver's statistics (steps, rejections, factorisations, Newton
    /// iterations, wall time).
    #[arg(long, short)]
    verbose: bool,
}

struct Progress(ProgressBar, f64);

impl Observer for Progress {
    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        self.0.set_position((step.t1_s() / self.1 * 1000.0) as u64);
        Ok(())
    }
    fn on_finish(&mut self, _stats: &RunStats) -> ObserverResult {
        self.0.finish_and_clear();
        Ok(())
    }
}

/// The scenario a run steps: loaded with its `--set` changes (and a replayed
/// margins sample, with the line that says so), its length from `--orbits` or one
/// orbit for `--steady-state`; its warnings printed. Also the orbit's period.
fn scenario_to_run(a: &RunArgs) -> Result<(Loaded, Option<String>, Scenario, f64)> {
    let mut loaded = load_with(a.scenario.as_deref(), &a.sets)?;
    let replay = match (a.sample, a.seed) {
        (Some(k), Some(seed)) => Some(replay_sample(&mut loaded, a, k, seed)?),
        _ => None,
    };
    let mut sc = loaded.scenario().clone();
    if let Some(o) = a.orbits {
        sc = sc
            .with_orbits(o)
            .map_err(|m| anyhow!("--orbits {}: {m}", orbitlash::units::num(o)))?;
    }
    let period_s = sc.period_s();
    if a.steady_state {
        orbitlash::run::steady::check_repeats(&sc.thermal)
            .map_err(|e| anyhow!("--steady-state: {e}"))?;
        sc = sc
            .with_orbits(1.0)
            .map_err(|m| anyhow!("--steady-state: {m}"))?;
    }
    for w in sc.warnings() {
        eprintln!(
            "warning: {}: {}",
            loaded.file,
            orbitlash::units::shown(&w.to_string())
        );
    }
    Ok((loaded, replay, sc, period_s))
}

/// `orbitlash run`: the scenario stepped under its observers (the log, the CSV, the
/// statistics of the summary), then the report ([`report_run`]).
pub fn run(a: RunArgs) -> Result<Outcome> {
    let (loaded, replay, sc, period_s) = scenario_to_run(&a)?;
    let t_end_s = sc.run.duration_s;

    let (outs, log_path, log_policy) = plan_outputs(&a, &loaded, &sc)?;
    bounded(&a, &sc, log_path.as_deref(), loaded.toml.len())?;
    if a.steady_state {
        super::estimate::steady(&sc, a.force)?;
    }
    if a.dry_run {
        return Ok(Outcome::Pass);
    }
    // the periodic-orbit search writes nothing: stopped (Ctrl-C, SIGTERM), it exits 2
    let steady = if a.steady_state {
        Some(super::watched(
            || {},
            || {
                "--steady-state: the periodic-orbit search was interrupted; nothing was written"
                    .to_string()
            },
            || periodic_start(&sc),
        )?)
    } else {
        None
    };
    // A real orbit that fails on the way fails here, before an output is opened (a log
    // it replaced would be lost to a record of nothing).
    orbitlash::run::sim::check_orbit(&sc.thermal.environment, t_end_s)
        .map_err(|e| anyhow!("{}: {e}; nothing was written", loaded.file))?;

    // The log keeps the pair statistics (its end record carries the verdict and each
    // pair's smallest backlash); without a log they are kept here.
    let mesh_window_s = period_s.min(t_end_s);
    let log = open_log(&a, &loaded, &sc, log_path.as_deref(), &log_policy)?
        .map(|l| l.with_mesh_stats(MeshStats::last(mesh_window_s)));
    let mut log = match log {
        Some(l) if a.scene => Some(l.with_scene(300.0)),
        other => other,
    };
    let mut mesh_alone = log.is_none().then(|| MeshStats::last(mesh_window_s));
    let mut eclipses = orbitlash::run::summary::EclipseWindows::default();
    let csv = match &a.csv {
        Some(p) => Some(CsvExport::create(
            p,
            sc.run.output_interval_s,
            &OutputPolicy::reading(&loaded.inputs()),
        )?),
        None => None,
    };
    let progress = progress_bar(&a, &sc.name, t_end_s);

    let mut stats_obs = WindowStats::last(period_s.min(t_end_s));
    // Over the whole run: reported instead when an interrupted run ends before the
    // last orbit's window.
    let mut stats_run = WindowStats::last(t_end_s);
    let mut daily = orbitlash::run::summary::DailyStats::default();
    let interrupt = interrupt_flag();
    let wall = Instant::now();
    let result = {
        let mut observers = (
            (
                &mut stats_obs,
                &mut stats_run,
                &mut mesh_alone,
                &mut daily,
                &mut eclipses,
            ),
            csv,
            &mut log,
            progress,
        );
        let mut setup = orbitlash::run::sim::Setup::new(&sc.thermal, &sc.gears, &sc.solver);
        let mut state = match &steady {
            Some((start, _)) => start.clone(),
            None => setup.initial_state(),
        };
        setup.run(
            &mut state,
            t_end_s,
            &mut observers,
            orbitlash::run::sim::Stop {
                cancel: Some(interrupt),
                pause_after_s: None,
            },
        )
    };
    let stats = match result {
        Ok(stats) => stats,
        Err(e) => return Err(run_failed(e, log.as_mut(), &loaded.file, a.csv.is_some())),
    };
    let wall_s = wall.elapsed().as_secs_f64();
    let mesh = match (&log, &mesh_alone) {
        (Some(l), _) => l.mesh_stats(),
        (None, Some(m)) => m,
        (None, None) => unreachable!("the statistics are kept by the log or here"),
    };
    daily.include_run_extremes(&mesh.run_pairs);
    let run_end = orbitlash::run::summary::RunEnd::new(
        &mesh.run_pairs,
        &sc.gears
            .iter()
            .map(|g| g.min_backlash_m)
            .collect::<Vec<_>>(),
        eclipses.closed_at(stats.t_end_s),
        !stats.interrupted,
    );

    let window = if stats.t_end_s > stats_obs.window_start_s() {
        &stats_obs
    } else {
        &stats_run
    };
    let ran = Ran {
        sc: &sc,
        stats: &stats,
        window,
        mesh,
        daily: &daily,
        period_s,
        wall_s,
    };
    let notes = [replay, steady.map(|(_, line)| line)];
    report_run(&a, &ran, &notes, &outs, log_path.as_deref(), &run_end)
}

/// What a run left for its report.
struct Ran<'r> {
    sc: &'r Scenario,
    stats: &'r RunStats,
    /// The statistics of the last orbit (of the whole run, when interrupted before it).
    window: &'r WindowStats,
    mesh: &'r MeshStats,
    daily: &'r orbitlash::run::summary::DailyStats,
    period_s: f64,
    wall_s: f64,
}

/// The report of a run: the verdict, the `notes` (a replayed sample, the periodic
/// start), the summary, the gear pairs, the days, the solver (`--verbose`); the JSON
/// summary written; the figure and the log named. FAIL when a pair fails; an error
/// when the run was interrupted.
fn report_run(
    a: &RunArgs,
    ran: &Ran<'_>,
    notes: &[Option<String>],
    outs: &Outputs,
    log_path: Option<&Path>,
    run_end: &orbitlash::run::summary::RunEnd,
) -> Result<Outcome> {
    let Ran {
        sc,
        stats,
        window,
        mesh,
        daily,
        period_s,
        wall_s,
    } = *ran;
    let t_end_s = sc.run.duration_s;
    let verdicts: Vec<PairVerdict> = mesh.run_pairs.iter().map(PairStats::verdict).collect();
    let mut o = format_verdict(sc, stats, mesh);
    for line in notes.iter().flatten() {
        outln!(o, "{line}");
    }
    o.push_str(&format_summary(&sc.thermal, stats, window, period_s));
    o.push_str(&format_mesh(sc, mesh, stats));
    o.push_str(&format_days(sc, daily, stats));
    if a.verbose {
        o.push_str(&format_solver(stats, wall_s, t_end_s / period_s));
    }
    if let Some(p) = &a.json {
        let summary = RunSummary::new(sc, stats, window, mesh, daily, wall_s);
        let text = serde_json::to_string_pretty(&summary)? + "\n";
        outs.write_all(&[(p.as_path(), text.as_bytes())])?;
        outln!(o, "json: {}", super::shown_path(p));
    }
    if let Some(p) = &a.csv {
        outln!(o, "csv: {}", super::shown_path(p));
    }
    // a replayed margins sample says which on its figure, a steady state that the
    // figure is one period of the periodic orbit
    let mut parts = Vec::new();
    if let Some((k, seed)) = a.sample.zip(a.seed) {
        // a Latin hypercube's sample K depends on N too
        let lhs = match (a.sampling, a.samples) {
            (super::margins::SamplingArg::Lhs, Some(n)) => format!(", lhs of {n}"),
            _ => String::new(),
        };
        parts.push(format!("margins sample {k} (seed {seed}{lhs})"));
    }
    if a.steady_state {
        parts.push("steady state: one period of the periodic orbit".to_string());
    }
    let title = (!parts.is_empty()).then(|| format!("{}, {}", sc.name, parts.join(", ")));
    o.push_str(&figure_and_log(
        a,
        log_path,
        stats,
        run_end,
        title.as_deref(),
    )?);
    print_out(&o)?;
    let pass = verdicts.iter().all(|v| v.passes());
    if stats.interrupted {
        anyhow::bail!(
            "interrupted at t = {:.1} s of {:.1} s; the outputs above are complete up to then (verdict so far: {})",
            stats.t_end_s,
            t_end_s,
            if pass { "no pair failed" } else { "FAIL" }
        );
    }
    Ok(Outcome::from_pass(pass))
}

/// The figure of `run --plot` (from the log, else the CSV, with the run's own end) and
/// the lines that name it and the log.
fn figure_and_log(
    a: &RunArgs,
    log_path: Option<&std::path::Path>,
    stats: &RunStats,
    run_end: &orbitlash::run::summary::RunEnd,
    title: Option<&str>,
) -> Result<String> {
    let mut o = String::new();
    if a.plot.is_some() && stats.interrupted {
        outln!(
            o,
            "plot: not drawn (the run was interrupted); `orbitlash plot` draws the log as far as it goes"
        );
    }
    if let Some(f) = &a.plot
        && !stats.interrupted
    {
        let source = log_path
            .or(a.csv.as_deref())
            .expect("checked in plan_outputs");
        super::plot::draw(source, f, title, Some(run_end), &[])
            .map_err(|e| anyhow!("--plot {}: {}", f.display(), error_chain(&e)))?;
        outln!(o, "plot: {}", super::shown_path(f));
    }
    if let Some(p) = log_path {
        let p = super::shown_path(p);
        outln!(
            o,
            "log: {}  (Foxglove: `orbitlash layout {}` writes the layout of this log to import; \
             Rerun with its plots: `pip install -r viewer/requirements.txt` once, then \
             `python3 viewer/rerun_export.py {}` and `rerun` the .rrd)",
            p,
            p,
            p
        );
    }
    Ok(o)
}

/// A progress bar on a terminal (none with --quiet or when stderr is not one).
fn progress_bar(a: &RunArgs, name: &str, t_end_s: f64) -> Option<Progress> {
    (!a.quiet && std::io::stderr().is_terminal()).then(|| {
        let pb = ProgressBar::new(1000);
        pb.set_style(
            ProgressStyle::with_template("{spinner} {msg} [{bar:40}] {percent}% ({eta})")
                .expect("template")
                .progress_chars("=> "),
        );
        pb.set_message(name.to_string());
        Progress(pb, t_end_s)
    })
}

/// Every output of a run, checked before it starts so that a bad path fails now: none
/// may be an input (the scenario file), a device, a FIFO or a link (`io::output`), nor
/// another output of this run. Returns the plan, the log's path (None: `--no-log`) and
/// the policy it is written under (the default log only inside `logs/`).
fn plan_outputs(
    a: &RunArgs,
    loaded: &Loaded,
    sc: &Scenario,
) -> Result<(Outputs, Option<PathBuf>, OutputPolicy)> {
    let inputs = loaded.inputs();
    let mut outs = Outputs::new(OutputPolicy::reading(&inputs));
    let (log_path, log_policy) = match (&a.out, a.no_log) {
        (_, true) => (None, OutputPolicy::reading(&inputs)),
        (Some(p), false) => (Some(p.clone()), OutputPolicy::reading(&inputs)),
        (None, false) => (
            Some(default_log_path(&sc.name)?),
            OutputPolicy::default_in_logs(&inputs),
        ),
    };
    if let Some(l) = &log_path {
        if a.out.is_none() {
            outs.folder(
                "the default log folder",
                l.parent().expect("logs/<name>"),
                true,
            )?;
        }
        outs.file(if a.out.is_some() { "--out" } else { "the log" }, l)?;
    }
    if let Some(c) = &a.csv {
        outs.file("--csv", c)?;
    }
    // The JSON summary is written after the run, but its path is checked now.
    if let Some(j) = &a.json {
        outs.file("--json", j)?;
    }
    if let Some(f) = &a.plot {
        super::plot::format_of(f, "--plot")?;
        if log_path.is_none() && a.csv.is_none() {
            anyhow::bail!(
                "--plot {} draws the run from its log or its CSV: drop --no-log or add --csv",
                f.display()
            );
        }
        outs.file("--plot", f)?;
    }
    Ok((outs, log_path, log_policy))
}

/// The run's MCAP log at `log_path`, with its provenance (scenario text, solver,
/// seed, `--set`s).
fn open_log(
    a: &RunArgs,
    loaded: &Loaded,
    sc: &Scenario,
    log_path: Option<&Path>,
    log_policy: &OutputPolicy,
) -> Result<Option<McapLog>> {
    Ok(match log_path {
        Some(p) => Some(McapLog::create(
            p,
            Provenance {
                scenario_name: sc.name.clone(),
                scenario_file: loaded.file.clone(),
                scenario_toml: loaded.toml.clone(),
                solver: format!(
                    "tr-bdf2 tolerance_k={} max_step_s={} adaptive={}",
                    sc.solver.tolerance_k, sc.solver.max_step_s, sc.solver.adaptive
                ),
                seed: a.seed,
                sets: loaded.sets.clone(),
            },
            a.log_every.unwrap_or(LogCadence::Steps(1)),
            log_policy,
        )?),
        None => None,
    })
}

/// The error of a failed run: the cause first, then where its partial output is. The
/// log is closed as the record of the failed run; other outputs are discarded.
fn run_failed(e: SimError, log: Option<&mut McapLog>, file: &str, csv: bool) -> anyhow::Error {
    let t_fail = e.t_s().unwrap_or(f64::NAN);
    let cause = error_chain(&anyhow::Error::new(e));
    let closed = log.map(|l| l.close_failed(t_fail, &cause));
    let mut msg = format!("running {file}: {cause}");
    match closed {
        Some(Ok(p)) => msg.push_str(&format!(
            "\n  the log {} holds the run up to the failure",
            p.display()
        )),
        Some(Err(OutputError::NotWritten { .. })) => msg.push_str("\n  no log was written"),
        Some(Err(e)) => {
            let why = error_chain(&e.into());
            if cause.contains(&why) {
                msg.push_str("\n  no log was written");
            } else {
                msg.push_str(&format!("\n  no log was written: {why}"));
            }
        }
        None => {}
    }
    if csv {
        msg.push_str("\n  no CSV was written");
    }
    anyhow!(msg)
}

/// Refuses a run over the step limit (unless `--force`) or whose outputs would not fit
/// on their file systems; says what a long or large run will take.
fn bounded(
    a: &RunArgs,
    sc: &Scenario,
    log: Option<&std::path::Path>,
    toml_len: usize,
) -> Result<()> {
    let t_end_s = sc.run.duration_s;
    // The pilot carries the run's summaries; the log adds about a third.
    let window = sc.period_s().min(t_end_s);
    let mut summaries = (
        WindowStats::last(window),
        WindowStats::last(t_end_s),
        MeshStats::last(window),
    );
    let mut est = estimate_run(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        t_end_s,
        sc.period_s(),
        &mut summaries,
    );
    if log.is_some() {
        est.wall_s *= 1.35;
    }
    // A real orbit's table is kept for the whole run.
    let table_bytes = match &sc.thermal.environment {
        orbitlash::orbit::Environment::Dated(_) => {
            t_end_s / 86_400.0 * orbitlash::orbit::tle::TABLE_BYTES_PER_DAY
        }
        _ => 0.0,
    };
    if table_bytes > super::estimate::max_memory_bytes() && !a.force {
        anyhow::bail!(
            "the run's orbit table would take about {:.1} GB of memory ({:.0} days of propagation), more than the {:.1} GB allowed: shorten it, or pass --force",
            table_bytes / 1e9,
            t_end_s / 86_400.0,
            super::estimate::max_memory_bytes() / 1e9
        );
    }
    if (est.steps > MAX_STEPS || est.wall_s > super::estimate::MAX_WALL_S) && !a.force {
        anyhow::bail!(
            "the run would take about {:.2e} steps ({:.3e} s simulated{}), more than {}: \
shorten it, loosen solver.tolerance_k or raise solver.max_step_s, or pass --force",
            est.steps,
            t_end_s,
            if est.wall_s.is_finite() {
                format!(
                    ", about {} of computing",
                    super::estimate::duration(est.wall_s)
                )
            } else {
                String::new()
            },
            if est.steps > MAX_STEPS {
                format!("the limit of {MAX_STEPS:.0e} steps")
            } else {
                format!(
                    "{} of computing",
                    super::estimate::duration(super::estimate::MAX_WALL_S)
                )
            }
        );
    }
    let cadence = a.log_every.unwrap_or(LogCadence::Steps(1));
    // Samples, plus what every log holds once: schemas, provenance, the scenario
    // attached, the summary section.
    let log_bytes = log.map(|_| {
        cadence.samples(est.steps, t_end_s) * estimated_bytes_per_sample(&sc.thermal, &sc.gears)
            + toml_len as f64
            + 8e3
            + 60.0 * sc.thermal.network.nodes.len() as f64
            + if a.scene {
                (t_end_s / 300.0) * 25e3 * sc.gears.len() as f64
            } else {
                0.0
            }
    });
    // A CSV row: the time and every column at ~11 characters.
    let csv_bytes = a.csv.as_ref().map(|_| {
        let columns = 1 + sc.thermal.network.nodes.len() + 5 * sc.gears.len();
        (t_end_s / sc.run.output_interval_s + 1.0) * columns as f64 * 11.0
    });
    let outputs = [
        (log, log_bytes, "log"),
        (a.csv.as_deref(), csv_bytes, "CSV"),
    ];
    // Outputs on the same file system need the sum of their sizes there.
    let device = |p: &std::path::Path| {
        use std::os::unix::fs::MetadataExt;
        let dir = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => std::path::Path::new("."),
        };
        std::fs::metadata(dir).map(|m| m.dev()).ok()
    };
    for (path, bytes) in outputs.iter().filter_map(|(p, b, _)| Some(((*p)?, (*b)?))) {
        let need: f64 = outputs
            .iter()
            .filter(|o| o.0.is_some_and(|q| device(q) == device(path)))
            .filter_map(|o| o.1)
            .sum::<f64>()
            .max(bytes);
        if let Some(free) = available_bytes(path)
            && need > free as f64
        {
            anyhow::bail!(
                "the outputs would take about {} but the file system of {} has {} free; \
log less often (--log-every 600s), sample the CSV more coarsely (--set run.output_interval_s=…), \
skip the log (--no-log) or shorten the run",
                size(need),
                path.display(),
                size(free as f64)
            );
        }
    }
    let total: f64 = outputs.iter().filter_map(|o| o.1).sum();
    if est.wall_s > 5.0 || total > 100e6 || a.dry_run {
        let parts: Vec<String> = outputs
            .iter()
            .filter_map(|(_, b, what)| b.map(|b| format!("{what} about {}", size(b))))
            .collect();
        eprintln!(
            "estimate: about {:.3e} steps, {} of computing{}{}",
            est.steps,
            if est.wall_s.is_finite() {
                super::estimate::duration(est.wall_s)
            } else {
                "an unknown time".into()
            },
            if parts.is_empty() { "" } else { ", " },
            parts.join(", ")
        );
    }
    Ok(())
}

fn size(bytes: f64) -> String {
    match bytes {
        b if b >= 1e9 => format!("{:.1} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.1} MB", b / 1e6),
        b => format!("{:.0} kB", b / 1e3),
    }
}

/// Where in the orbit `t` falls, for reports.
fn orbit_phase(sc: &Scenario, t: f64) -> String {
    if !t.is_finite() {
        return "no time (no valid sample)".to_string();
    }
    let env = &sc.thermal.environment;
    // the run's last instant ends its last orbit (the next one starts there)
    let last = env.orbit_number(sc.run.duration_s - 1e-9 * env.mean_period_s());
    format!(
        "{}, orbit {}, θ = {:.1}° from noon, {}",
        when(sc, t),
        env.orbit_number(t).min(last),
        env.orbit_phase_deg(t),
        if env.sunlit(t) { "sunlit" } else { "eclipse" }
    )
}

/// A time of the run for reports, in the unit of the run's figure (`plot::time_unit`):
/// hours in a run of up to three days, past that days (day 1 is t = 0 … 86 400 s),
/// each with the seconds after them; and the UTC date and time when the scenario is
/// dated.
fn when(sc: &Scenario, t: f64) -> String {
    let utc = sc.thermal.environment.utc_at(t);
    let long = sc.run.duration_s > 3.0 * orbitlash::run::summary::DAY_S;
    let base = if long {
        format!(
            "t = {:.3} d ({t:.1} s, day {})",
            t / orbitlash::run::summary::DAY_S,
            (t / orbitlash::run::summary::DAY_S).floor() as u64 + 1
        )
    } else {
        // hours, as the figure's time axis; the seconds after them
        format!("t = {:.3} h ({t:.1} s)", t / 3600.0)
    };
    match utc {
        Some(u) => format!("{base}, {} UTC", u.format("%Y-%m-%d %H:%M:%S")),
        None => base,
    }
}

/// The per-day summary of a run longer than three days: per day (per week past 60
/// days), each pair's smallest and largest backlash, the coldest and hottest node, and
/// the heaters' duty cycle; then each heater's duty cycle and energy over the run.
fn format_days(
    sc: &Scenario,
    daily: &orbitlash::run::summary::DailyStats,
    stats: &RunStats,
) -> String {
    use orbitlash::run::summary::DAY_S;
    let mut o = String::new();
    let span = stats.t_end_s - stats.t_start_s;
    if !daily.heaters.is_empty() {
        outln!(
            o,
            "
heaters over the run:"
        );
        let mut t = table::new(
            &[
                "heater",
                "power W",
                "on h",
                "duty %",
                "energy kJ",
                "energy Wh",
            ],
            &[
                Align::Left,
                Align::Right,
                Align::Right,
                Align::Right,
                Align::Right,
                Align::Right,
            ],
        );
        for h in daily.heater_summaries(span) {
            t.add_row(vec![
                h.name,
                format!("{:.2}", h.power_w),
                format!("{:.2}", h.on_s / 3600.0),
                format!("{:.1}", 100.0 * h.duty_fraction),
                format!("{:.1}", h.energy_j / 1e3),
                format!("{:.2}", h.energy_j / 3600.0),
            ]);
        }
        o += &table::render(&t, "  ");
    }
    if span <= 3.0 * DAY_S || daily.days.is_empty() {
        return o;
    }
    let per = if daily.days.len() > 60 { 7 } else { 1 };
    outln!(
        o,
        "
per {} (day 1 starts at t = 0{}; each node's range per orbit: `orbitlash plot` on the log):",
        if per == 7 { "week" } else { "day" },
        sc.thermal
            .environment
            .start_utc()
            .map_or(String::new(), |u| format!(
                ", {} UTC",
                u.format("%Y-%m-%d %H:%M")
            ))
    );
    let mut head: Vec<String> = vec![if per == 7 {
        "days".into()
    } else {
        "day".into()
    }];
    for g in &sc.gears {
        head.push(format!("{} min µm", g.name));
        head.push(format!("{} max µm", g.name));
    }
    head.extend(["coldest node °C".to_string(), "hottest node °C".to_string()]);
    if !daily.heaters.is_empty() {
        head.push("heaters on %".to_string());
    }
    let refs: Vec<&str> = head.iter().map(String::as_str).collect();
    let mut aligns = vec![Align::Right; head.len()];
    aligns[head.len() - 2 - usize::from(!daily.heaters.is_empty())] = Align::Left;
    aligns[head.len() - 1 - usize::from(!daily.heaters.is_empty())] = Align::Left;
    let mut t = table::new(&refs, &aligns);
    for chunk in daily.days.chunks(per) {
        let first = chunk[0].day + 1;
        let last = chunk[chunk.len() - 1].day + 1;
        let mut row = vec![if first == last {
            first.to_string()
        } else {
            format!("{first}–{last}")
        }];
        for k in 0..sc.gears.len() {
            let lo = chunk
                .iter()
                .map(|d| d.backlash_m[k].0)
                .fold(f64::INFINITY, f64::min);
            let hi = chunk
                .iter()
                .map(|d| d.backlash_m[k].1)
                .fold(f64::NEG_INFINITY, f64::max);
            let um = |v: f64| table::number(v * 1e6, 3);
            row.push(um(lo));
            row.push(um(hi));
        }
        let (mut cold, mut hot) = ((f64::INFINITY, 0usize), (f64::NEG_INFINITY, 0usize));
        for d in chunk {
            for (i, &(a, b)) in d.node_k.iter().enumerate() {
                if a < cold.0 {
                    cold = (a, i);
                }
                if b > hot.0 {
                    hot = (b, i);
                }
            }
        }
        row.push(format!("{:.2} {}", k_to_c(cold.0), daily.nodes[cold.1]));
        row.push(format!("{:.2} {}", k_to_c(hot.0), daily.nodes[hot.1]));
        if !daily.heaters.is_empty() {
            let on: f64 = chunk.iter().flat_map(|d| d.heater_on_s.iter()).sum();
            let cov: f64 = chunk.iter().map(|d| d.covered_s).sum();
            row.push(format!(
                "{:.1}",
                100.0 * on / (cov * daily.heaters.len() as f64).max(1e-9)
            ));
        }
        t.add_row(row);
    }
    o += &table::render(&t, "  ");
    o
}

/// The first lines of the summary: one PASS/FAIL line per gear pair, then what ran.
fn format_verdict(sc: &Scenario, stats: &RunStats, mesh: &MeshStats) -> String {
    let mut o = String::new();
    if sc.gears.is_empty() {
        outln!(o, "no gear pair: no backlash verdict");
    }
    for (pair, r) in sc.gears.iter().zip(&mesh.run_pairs) {
        // the backlash, its minimum and the margin between them to the decimals that
        // tell the first two apart
        let (b_um, least_um) = (r.min_exact_m * 1e6, pair.min_backlash_m * 1e6);
        let d = orbitlash::units::decimals_apart(b_um, least_um, 3);
        let (smallest, least) = (fixed(b_um, d), fixed(least_um, d));
        let margin = fixed(r.min_margin_m * 1e6, d);
        let line = match r.verdict() {
            // no pass before the run's end
            PairVerdict::Pass if stats.interrupted => format!(
                "INCOMPLETE {}: margin {margin} µm so far (smallest backlash {smallest} µm ≥ {least} µm minimum) at {}; the run was interrupted before its end",
                pair.name,
                orbit_phase(sc, r.t_min_s)
            ),
            PairVerdict::Pass => format!(
                "PASS {}: margin {margin} µm (smallest backlash {smallest} µm ≥ {least} µm minimum) at {}",
                pair.name,
                orbit_phase(sc, r.t_min_s)
            ),
            PairVerdict::MarginViolated => format!(
                "FAIL {}: margin {margin} µm (smallest backlash {smallest} µm < {least} µm minimum) at {}",
                pair.name,
                orbit_phase(sc, r.t_min_s)
            ),
            PairVerdict::Interference => format!(
                "FAIL {}: interference, margin {:.3} µm (smallest backlash {:.3} µm ≤ 0) at {}",
                pair.name,
                r.min_margin_m * 1e6,
                r.min_exact_m * 1e6,
                orbit_phase(sc, r.t_min_s)
            ),
            PairVerdict::NoValidMesh => format!(
                "FAIL {}: no valid mesh (base circles overlap or contact ratio below 1) from {}",
                pair.name,
                orbit_phase(sc, r.t_first_invalid_s)
            ),
        };
        outln!(o, "{line}");
    }
    outln!(
        o,
        "{}: {}, {:.1} s simulated{}",
        sc.name,
        orbitlash::units::orbits(stats.t_end_s / sc.period_s(), 2),
        stats.t_end_s,
        if stats.interrupted {
            " (interrupted)"
        } else {
            ""
        }
    );
    o
}

/// Solver internals (`--verbose`).
fn format_solver(stats: &RunStats, wall_s: f64, orbits: f64) -> String {
    let mut o = String::new();
    outln!(
        o,
        "\nsolver: tr-bdf2, {} steps ({} rejected, {} factorisations), {:.2} Newton iterations/step, {} eclipse entries, {} heater switches",
        stats.steps,
        stats.rejected_steps,
        stats.factorizations,
        stats.newton_iterations as f64 / stats.steps.max(1) as f64,
        stats.eclipse_entries,
        stats.heater_switches
    );
    outln!(
        o,
        "wall time {:.3} ms, {:.0} steps/s, {:.3} ms/orbit",
        wall_s * 1e3,
        stats.steps as f64 / wall_s,
        wall_s * 1e3 / orbits
    );
    o
}

/// A flag set by Ctrl-C (SIGINT/SIGTERM): the run stops after the current step and
/// closes its outputs properly.
fn interrupt_flag() -> &'static AtomicBool {
    super::interrupt_flag()
}

fn format_summary(
    model: &ThermalModel,
    stats: &RunStats,
    window: &WindowStats,
    period_s: f64,
) -> String {
    let mut o = String::new();
    let env = &model.environment;
    let (b_lo, b_hi) = env.beta_range_rad(stats.t_start_s, stats.t_end_s);
    outln!(
        o,
        "orbit: period {period_s:.3} s, beta {}, eclipse fraction {:.5} (predicted at t = 0), {:.5} (over the run)",
        if b_lo == b_hi {
            format!("{:.2}°", b_lo.to_degrees())
        } else {
            format!("{:.2}° … {:.2}°", b_lo.to_degrees(), b_hi.to_degrees())
        },
        env.eclipse_fraction_at(stats.t_start_s),
        stats.eclipse_time_s / (stats.t_end_s - stats.t_start_s)
    );
    let (heading, _) = window_label(env, window.window_start_s(), stats);
    outln!(o, "\n{heading}:");
    let mut table = table::new(
        &["node", "min °C", "max °C", "mean °C"],
        &[Align::Left, Align::Right, Align::Right, Align::Right],
    );
    // Every node of a mechanism; the extremes of a large network (all of them are in
    // the log and the CSV).
    let mut nodes = window.nodes();
    if nodes.len() > 40 {
        let total = nodes.len();
        nodes.sort_by(|a, b| a.min_k.total_cmp(&b.min_k));
        let mut shown: Vec<_> = nodes[..5].to_vec();
        nodes.sort_by(|a, b| b.max_k.total_cmp(&a.max_k));
        for s in nodes.iter().take(5) {
            if !shown.iter().any(|x| x.name == s.name) {
                shown.push(s.clone());
            }
        }
        outln!(
            o,
            "  (the 5 coldest and the 5 hottest of {total} nodes; all of them: --csv or the log)"
        );
        nodes = shown;
    }
    for s in nodes {
        table.add_row(vec![
            s.name.to_string(),
            format!("{:.2}", k_to_c(s.min_k)),
            format!("{:.2}", k_to_c(s.max_k)),
            format!("{:.2}", k_to_c(s.mean_k)),
        ]);
    }
    o += &table::render(&table, "  ");
    let e = &stats.energy;
    outln!(o, "\nenergy balance over the run:");
    let mut table = table::new(&["", "", ""], &[Align::Left, Align::Right, Align::Left]);
    let joules = |v: f64| orbitlash::units::fixed(v, 1);
    table.add_row(vec![
        "absorbed (sun, albedo, IR)".to_string(),
        joules(e.absorbed_j),
        "J".to_string(),
    ]);
    table.add_row(vec![
        "dissipated (loads, heaters)".to_string(),
        joules(e.dissipated_j),
        "J".to_string(),
    ]);
    for (b, q) in model.network.boundaries.iter().zip(&e.to_boundary_j) {
        table.add_row(vec![
            format!("to boundary {}", b.name),
            joules(*q),
            "J".to_string(),
        ]);
    }
    table.add_row(vec![
        "stored".to_string(),
        joules(e.stored_j),
        "J".to_string(),
    ]);
    table.add_row(vec![
        "error".to_string(),
        format!("{:.3e}", e.error_j()),
        format!("J ({:.2e} of the heat in)", e.relative_error()),
    ]);
    o += &table::render(&table, "  ");
    o
}

/// A model variant's (smallest, largest) backlash from a pair's statistics.
type Extremes = fn(&PairStats) -> (f64, f64);

/// What the summary's window (from `start_s` to the run's end) is: its heading and the
/// name its columns take. The last orbit when it is one whole orbit; "last period" when
/// the run ends inside an orbit (14.3 orbits: the end of orbit 14 and the start of 15);
/// the whole run when the run is shorter than an orbit, or was interrupted before its
/// last orbit began (the window then starts at 0; a window that starts after the end
/// saw nothing, and keeps the last orbit's name over its dashes).
fn window_label(
    env: &orbitlash::orbit::Environment,
    start_s: f64,
    stats: &RunStats,
) -> (String, &'static str) {
    let period_s = env.mean_period_s();
    let end_s = stats.t_end_s;
    let eps = 1e-6 * period_s;
    let (first, last) = (
        env.orbit_number(start_s + eps),
        env.orbit_number(end_s - eps),
    );
    if start_s >= end_s {
        ("last orbit (not reached)".into(), "last orbit")
    } else if start_s == 0.0 && stats.interrupted {
        (
            format!("the whole run (interrupted before its last orbit), t = 0 … {end_s:.1} s"),
            "whole run",
        )
    } else if start_s == 0.0 && end_s < period_s - eps {
        (
            format!(
                "the whole run ({} of an orbit, t = 0 … {end_s:.1} s)",
                fixed(end_s / period_s, 2)
            ),
            "whole run",
        )
    } else if first == last {
        (
            format!("last orbit (orbit {first}, t = {start_s:.1} … {end_s:.1} s)"),
            "last orbit",
        )
    } else {
        (
            format!(
                "last period (the end of orbit {first}, the start of {last}, t = {start_s:.1} … {end_s:.1} s)"
            ),
            "last period",
        )
    }
}

fn format_mesh(sc: &Scenario, mesh: &MeshStats, stats: &RunStats) -> String {
    let mut o = String::new();
    let phase = |t: f64| orbit_phase(sc, t);
    // the pair statistics' own window (it is not the temperatures' when interrupted)
    let (_, name) = window_label(&sc.thermal.environment, mesh.window_start_s(), stats);
    let (min, max) = (format!("{name} min"), format!("{name} max"));
    for ((pair, r), l) in sc.gears.iter().zip(&mesh.run_pairs).zip(&mesh.pairs) {
        outln!(
            o,
            "\ngear pair {} (normal backlash, µm; minimum allowed {:.3} µm):",
            pair.name,
            pair.min_backlash_m * 1e6
        );
        let mut table = table::new(
            &["", "run min", "run max", &min, &max],
            &[
                Align::Left,
                Align::Right,
                Align::Right,
                Align::Right,
                Align::Right,
            ],
        );
        // "–" where a window saw no step (an interrupted run).
        let um = |v: f64| table::number(v * 1e6, 3);
        let variants: [(&str, Extremes); 3] = [
            ("exact (worst over a mesh)", |p| {
                (p.min_exact_m, p.max_exact_m)
            }),
            ("closed form", |p| {
                (p.min_closed_form_m, p.max_closed_form_m)
            }),
            ("paper (16)-(22)", |p| (p.min_paper_m, p.max_paper_m)),
        ];
        for (label, f) in variants {
            let (a, b) = f(r);
            let (c, d) = f(l);
            table.add_row(vec![label.to_string(), um(a), um(b), um(c), um(d)]);
        }
        o += &table::render(&table, "  ");
        outln!(o, "  smallest backlash at {}", phase(r.t_min_s));
        outln!(o, "  largest backlash at  {}", phase(r.t_max_s));
        outln!(
            o,
            "  margin {:.3} µm (smallest over the run); {} interference events, {} times below the minimum{}",
            r.min_margin_m * 1e6,
            r.interference_events,
            r.margin_events,
            if r.invalid_samples > 0 {
                format!(", {} samples with no valid mesh", r.invalid_samples)
            } else {
                String::new()
            }
        );
    }
    o
}

/// Writes sample `k`'s dispersed values into the loaded model (as `margins` drew them)
/// and records them with the `--set` changes; returns a line for the summary.
fn replay_sample(loaded: &mut super::Loaded, a: &RunArgs, k: u64, seed: u64) -> Result<String> {
    use orbitlash::margins::dispersion::Sampling;
    let sampling: Sampling = a.sampling.into();
    let max = orbitlash::margins::dispersion::MAX_SAMPLES;
    if k >= max {
        anyhow::bail!(
            "--sample {k}: a margins run has at most {max} samples, numbered 0 … {}",
            max - 1
        );
    }
    let n = match (sampling, a.samples) {
        (_, Some(n)) => n,
        (Sampling::Random, None) => k + 1,
        (Sampling::LatinHypercube, None) => {
            anyhow::bail!(
                "--sample with --sampling lhs needs --samples N: a Latin hypercube sample depends on N"
            )
        }
    };
    if k >= n {
        anyhow::bail!("--sample {k} is not below --samples {n}");
    }
    if loaded.model.spec().dispersion.is_empty() {
        anyhow::bail!(
            "{} has no [[dispersion]]: there is no sample {k} to replay",
            loaded.file
        );
    }
    let plan = super::plan(loaded, sampling, n, seed, super::SetsOnDispersed::Refused)?;
    let values = plan.apply(&mut loaded.model, k)?;
    let mut line = format!("sample {k} of seed {seed}:");
    for (d, v) in plan.dispersions.iter().zip(values) {
        loaded.sets.push((d.path.clone(), v));
        line += &format!(" {} = {}", d.path, orbitlash::units::exact(v));
    }
    Ok(line)
}

/// The start of the periodic orbit of `sc` (at t = 0) and a line saying how it was
/// found.
fn periodic_start(sc: &Scenario) -> Result<(orbitlash::run::sim::State, String)> {
    use orbitlash::run::steady::{SteadyOptions, periodic_orbit};
    let period = sc.period_s();
    let mut setup = orbitlash::run::sim::Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let start = setup.initial_state();
    let p = periodic_orbit(&mut setup, &start, period, SteadyOptions::default())
        .map_err(|e| anyhow!("--steady-state: {e}"))?;
    let line = format!(
        "periodic orbit: found by {} in {} orbits ({} Newton steps), periodicity error {:.2e} K; the summary covers one period of it",
        p.method, p.orbits, p.newton_iterations, p.periodicity_error_k
    );
    Ok((p.state, line))
}

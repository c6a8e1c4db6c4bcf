//! Command definitions (clap) and dispatch. Library code never sees clap.

/// `writeln!` into a String (infallible).
macro_rules! outln {
    ($o:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($o, $($arg)*);
    }};
}

mod backlash;
mod bench;
mod check;
mod diagnose;
mod environment;
mod estimate;
mod export;
mod layout;
mod margins;
mod params;
mod plot;
mod recover;
mod run;
mod table;

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::{Parser, Subcommand};

use orbitlash::io::scenario_toml::{self, REFERENCE_HINGE_NAME, REFERENCE_HINGE_TOML};
use orbitlash::spec::model::{Model, ModelError};
use orbitlash::spec::registry::parse_assignment;
use orbitlash::spec::scenario::Scenario;

#[derive(Parser, Debug)]
#[command(
    name = "orbitlash",
    version,
    about = "Orbital thermal transients of spacecraft mechanisms and the backlash of their gears",
    after_help = "Exit status: 0 when the command succeeded and, for `run` and `backlash`, every gear pair \
kept its minimum backlash; 1 when a gear pair's margin was violated or its teeth interfere; \
2 on any error (bad input, unwritable output, solver failure, interrupted run)."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

const VERDICT_HELP: &str = "Exit status: 0 when every gear pair kept its minimum backlash (PASS), \
1 when a pair's margin was violated or its teeth interfere (FAIL), 2 on any error.";

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scenario (the embedded reference-hinge when none is given).
    #[command(after_help = VERDICT_HELP)]
    Run(run::RunArgs),
    /// Validate a scenario and print derived quantities without running it.
    Check(check::CheckArgs),
    /// Monte Carlo margins: the scenario's `[[dispersion]]` entries sampled, each sample
    /// run in parallel, and the verdict with its confidence (95/95 bound, probabilities).
    #[command(after_help = VERDICT_HELP)]
    Margins(margins::MarginsArgs),
    /// Merge the shard files of `margins --shard I/N` into the unsharded run's report
    /// (refusing shards of other runs, duplicates and gaps).
    #[command(after_help = VERDICT_HELP)]
    Merge(margins::MergeArgs),
    /// Measure the cost of the thermal solver (per step, per orbit, accuracy), of the
    /// backlash evaluation and of logging.
    Bench(bench::BenchArgs),
    /// Every number of a scenario by key path (what `--set KEY=VALUE` changes), with its
    /// value, unit and valid range.
    Params(params::ParamsArgs),
    /// Static backlash calculator: every model variant at given temperatures.
    #[command(after_help = VERDICT_HELP)]
    Backlash(backlash::BacklashArgs),
    /// A recording (test or flight data) against the scenario: where they differ, which
    /// physics the model left out (or which parameter or sensor is off), that physics
    /// added and fitted, and the fit checked on held-out orbits it never saw.
    #[command(
        after_help = "Exit status: 0 when the analysis ran, whatever the verdict \
(consistent, explained or unexplained); 2 on any error."
    )]
    Diagnose(diagnose::DiagnoseArgs),
    /// The orbit's environment: β, eclipses (entry, exit, length), the Sun's distance
    /// and flux, and with --csv their time series.
    Environment(environment::EnvironmentArgs),
    /// Convert an MCAP log back to CSV (the layout of `run --csv`); a cut-off log is
    /// read up to its last whole message.
    ExportCsv(export::ExportArgs),
    /// A run's temperatures and backlash against time (eclipses shaded, the smallest
    /// backlash marked; a long run as per-orbit envelopes), from its log or CSV, as PNG
    /// or SVG.
    Plot(plot::PlotArgs),
    /// A Foxglove layout made from a run log's own channels (every panel plots what the
    /// log has, temperatures in °C): written to logs/<log name>.foxglove.json.
    Layout(layout::LayoutArgs),
    /// Make a killed run's log (`<name>.<pid>.partial`) or a truncated copy into a valid MCAP
    /// file holding everything up to its last whole message.
    Recover(recover::RecoverArgs),
}

/// How a command that ran to its end came out; errors are the `Err` of [`dispatch`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Done, and every verdict passed (exit status 0).
    Pass,
    /// Done, but a verdict failed: a margin violated, interference (exit status 1).
    Fail,
}

impl Outcome {
    pub fn from_pass(pass: bool) -> Outcome {
        if pass { Outcome::Pass } else { Outcome::Fail }
    }
}

pub fn dispatch(cli: Cli) -> Result<Outcome> {
    let done = |r: Result<()>| r.map(|()| Outcome::Pass);
    if matches!(
        cli.command,
        Command::Margins(_) | Command::Bench(_) | Command::Diagnose(_)
    ) {
        start_thread_pool()?;
    }
    match cli.command {
        Command::Run(a) => run::run(a),
        Command::Check(a) => done(check::check(a)),
        Command::Margins(a) => margins::margins(a),
        Command::Merge(a) => margins::merge_shards(a),
        Command::Params(a) => done(params::params(a)),
        Command::Bench(a) => done(bench::bench(a)),
        Command::Backlash(a) => backlash::backlash(a),
        Command::Diagnose(a) => diagnose::diagnose(a),
        Command::Environment(a) => done(environment::environment(a)),
        Command::ExportCsv(a) => done(export::export(a)),
        Command::Plot(a) => done(plot::plot(a)),
        Command::Layout(a) => done(layout::layout(a)),
        Command::Recover(a) => done(recover::recover(a)),
    }
}

/// Set when the process is asked to stop (SIGINT, SIGTERM, SIGHUP), once a command
/// installs the handler by calling this: it then stops at a safe point and says so.
pub fn interrupt_flag() -> &'static std::sync::atomic::AtomicBool {
    use std::sync::atomic::{AtomicBool, Ordering};
    static FLAG: AtomicBool = AtomicBool::new(false);
    static HANDLER: std::sync::Once = std::sync::Once::new();
    HANDLER.call_once(|| {
        let _ = ctrlc::set_handler(|| FLAG.store(true, Ordering::Relaxed));
    });
    &FLAG
}

/// Runs `work` while a thread watches for a stop request (Ctrl-C, SIGTERM, SIGHUP):
/// asked to stop before `work` is done, the process prints `error: {stopped()}` and
/// exits 2 (the commands that use this write their outputs after `work`, so nothing
/// has been written). `tick` runs every 50 ms meanwhile (a progress bar). The watcher
/// ends when `work` ends, by a panic too (a guard tells it), so a panic is not a hang.
pub fn watched<T>(
    tick: impl Fn() + Sync,
    stopped: impl Fn() -> String + Sync,
    work: impl FnOnce() -> T,
) -> T {
    use std::sync::atomic::{AtomicBool, Ordering};
    struct Done<'a>(&'a AtomicBool);
    impl Drop for Done<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Relaxed);
        }
    }
    let interrupt = interrupt_flag();
    let finished = AtomicBool::new(false);
    std::thread::scope(|s| {
        let (finished, tick, stopped) = (&finished, &tick, &stopped);
        s.spawn(move || {
            while !finished.load(Ordering::Relaxed) {
                if interrupt.load(Ordering::Relaxed) {
                    eprintln!("error: {}", stopped());
                    std::process::exit(2);
                }
                tick();
                std::thread::sleep(std::time::Duration::from_millis(50));
            }
        });
        let _done = Done(finished);
        work()
    })
}

/// Worker threads at most per core: past this, more threads only cost memory (each
/// has its stack) and start-up.
pub const MAX_THREADS_PER_CORE: usize = 8;

/// Builds the worker pool of the commands that run in parallel (margins, diagnose,
/// bench): `RAYON_NUM_THREADS` threads when set (0: one per core), at most
/// [`MAX_THREADS_PER_CORE`] per core (said on standard error when capped). Threads
/// that cannot be started (a memory or process limit) are an error, not rayon's panic
/// at the first parallel loop. Results do not depend on the count.
fn start_thread_pool() -> Result<()> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let requested = match std::env::var("RAYON_NUM_THREADS") {
        Ok(v) => v.trim().parse::<usize>().map_err(|_| {
            anyhow::anyhow!("RAYON_NUM_THREADS={v}: not a thread count (a whole number ≥ 0)")
        })?,
        Err(_) => 0,
    };
    let cap = MAX_THREADS_PER_CORE * cores;
    let threads = match requested {
        0 => cores,
        n if n > cap => {
            eprintln!(
                "warning: RAYON_NUM_THREADS={n}: using {cap} threads ({MAX_THREADS_PER_CORE} per core on {cores} cores)"
            );
            cap
        }
        n => n,
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global()
        .map_err(|e| anyhow::anyhow!("cannot start {threads} worker threads: {e}"))
}

/// An error and its causes on one line, outermost first, each cause once (a cause
/// already quoted by the message before it is not repeated).
pub fn error_chain(e: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if parts.last().is_some_and(|p| p.ends_with(&text)) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}

/// A scenario as loaded: the model, its TOML text and where it came from.
pub struct Loaded {
    /// The spec and model the scenario is compiled from (with the `--set` changes): the
    /// scenario is the model's ([`Loaded::scenario`]), never a copy beside it.
    pub model: Model,
    /// The `--set` changes applied, in order.
    pub sets: Vec<(String, f64)>,
    pub toml: String,
    pub file: String,
    /// The scenario file, when it came from one (an input outputs must not replace).
    pub path: Option<PathBuf>,
}

impl Loaded {
    /// The compiled scenario (the model's).
    pub fn scenario(&self) -> &Scenario {
        self.model.scenario()
    }

    /// The files this scenario was read from.
    pub fn inputs(&self) -> Vec<&Path> {
        self.path.iter().map(PathBuf::as_path).collect()
    }
}

/// Loads `path`, or the embedded reference scenario when `None`.
pub fn load(path: Option<&Path>) -> Result<Loaded> {
    load_with(path, &[])
}

/// Loads `path` (or the embedded reference) and applies `--set KEY=VALUE` changes: the
/// same compiler checks them, with the same error text as in the file.
pub fn load_with(path: Option<&Path>, sets: &[String]) -> Result<Loaded> {
    let (spec, toml, file) = match path {
        Some(p) => {
            let (spec, toml) = scenario_toml::read_spec_file(p)?;
            // the name as every message and report shows it (control characters
            // escaped: a line end would split a report's line or a TOML comment)
            (spec, toml, shown_path(p))
        }
        None => (
            scenario_toml::parse_spec(REFERENCE_HINGE_TOML, "<embedded>")?,
            REFERENCE_HINGE_TOML.to_string(),
            format!("<embedded {REFERENCE_HINGE_NAME}.toml>"),
        ),
    };
    // Each key in one spelling (`environment."space_sink_k"` is
    // `environment.space_sink_k`): what runs and shards record, and compare. A number
    // given twice is a slip (a script's default and an override), not an order to
    // follow: which one holds would be a guess.
    let keys = orbitlash::spec::keys::element_keys(&spec);
    let mut changes: Vec<(String, f64)> = Vec::new();
    for s in sets {
        let (key, value) = parse_assignment(s).map_err(|e| anyhow::anyhow!("--set {s}: {e}"))?;
        let key = orbitlash::spec::registry::resolve(&spec, &keys, &key)
            .map_or(key, |at| at.key_path(&keys).to_string());
        if let Some(j) = changes.iter().position(|(k, _)| *k == key) {
            anyhow::bail!(
                "--set {key} is given twice ({} and {s}): give it once",
                sets[j]
            );
        }
        changes.push((key, value));
    }
    let set_error = |e: ModelError| match e {
        ModelError::Param(p) => {
            let s = changes
                .iter()
                .position(|(k, _)| *k == p.key)
                .map(|j| sets[j].clone())
                .unwrap_or_default();
            anyhow::anyhow!("--set {s}: {p}")
        }
        ModelError::Invalid(v) => {
            anyhow::anyhow!("{file} with --set {}: {v}", sets.join(" --set "))
        }
    };
    let model = match Model::new(spec.clone()) {
        Ok(mut m) => {
            if !changes.is_empty() {
                m.set_many(&changes).map_err(set_error)?;
            }
            m
        }
        Err(e) if changes.is_empty() => return Err(scenario_toml::located(&toml, &file, e).into()),
        // The file's values may fail where the changes fix them (`--set
        // run.duration_days` within the days a decaying orbit lasts), as editing the
        // file would. A change that is itself wrong is named; else the file's own
        // error stands, with its line.
        Err(e) => match Model::with_changes(spec, &changes) {
            Ok(m) => m,
            Err(p @ ModelError::Param(_)) => return Err(set_error(p)),
            Err(ModelError::Invalid(_)) => {
                return Err(scenario_toml::located(&toml, &file, e).into());
            }
        },
    };
    Ok(Loaded {
        model,
        toml,
        file,
        path: path.map(Path::to_path_buf),
        sets: changes,
    })
}

/// What a plan's `--set` changes may touch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SetsOnDispersed {
    /// Samples are drawn (`margins`, `run --sample`): a `--set` on a dispersed number
    /// would be replaced in every sample, so it is refused.
    Refused,
    /// Nothing is sampled (`check`): a `--set` is the nominal value a user checks.
    Allowed,
}

/// The margins plan of a loaded scenario: its `[[dispersion]]` entries checked (errors
/// with the file's line), and (`SetsOnDispersed::Refused`) no `--set` on a number they
/// disperse (the dispersion would silently replace it in every sample).
pub fn plan(
    loaded: &Loaded,
    sampling: orbitlash::margins::dispersion::Sampling,
    samples: u64,
    seed: u64,
    sets: SetsOnDispersed,
) -> Result<orbitlash::margins::dispersion::Plan> {
    use orbitlash::margins::dispersion::{Plan, PlanError};
    let plan = Plan::new(
        &loaded.model,
        &loaded.model.spec().dispersion,
        sampling,
        samples,
        seed,
    )
    .map_err(|e| match e {
        PlanError::Spec(e) => {
            anyhow::Error::new(scenario_toml::located(&loaded.toml, &loaded.file, e))
        }
        other => anyhow::Error::new(other),
    })?;
    let checked = if sets == SetsOnDispersed::Refused {
        &loaded.sets[..]
    } else {
        &[]
    };
    for (key, _) in checked {
        let id = loaded
            .model
            .param(key)
            .map_err(|e| anyhow::anyhow!("--set {key}: {e}"))?;
        if let Some((k, d)) = plan.dispersion_of(&id) {
            anyhow::bail!(
                "--set {key}: `{}` is dispersed by dispersion[{k}] (path `{}`), which gives it a value in every sample; \
remove the --set, or change the dispersion (its mean, mode or median defaults to the nominal value)",
                id.canonical_path(),
                d.path
            );
        }
    }
    Ok(plan)
}

/// Validates a user-given orbit count.
pub fn orbits_arg(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("orbits must be > 0 (got {s})"))
    }
}

/// The default log of a scenario: `logs/<name>.mcap`. Scenario names are checked
/// (`scenario::check_name`) so that this stays inside `logs/`; a name that would not is
/// refused here as well.
pub fn default_log_path(name: &str) -> Result<PathBuf> {
    orbitlash::spec::scenario::check_name(name)
        .map_err(|m| anyhow::anyhow!("scenario name {m}; it names the default log"))?;
    Ok(PathBuf::from("logs").join(format!("{name}.mcap")))
}

/// A path as printed on a terminal: control characters escaped (`units::shown`), a
/// line end in it too.
pub fn shown_path(p: &std::path::Path) -> String {
    orbitlash::units::shown(&p.display().to_string()).into_owned()
}

/// Writes a report to stdout; a closed pipe (`| head`) is not an error. No control
/// character but line ends and tabs reaches the terminal: a path given with an escape
/// sequence in it is printed escaped, as `main` prints errors.
pub fn print_out(text: &str) -> Result<()> {
    use std::io::Write;
    let text = orbitlash::units::shown_keeping(text, &['\n', '\t']);
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => Ok(r?),
    }
}

#[cfg(test)]
mod tests {
    /// A panic in the watched work reaches the caller instead of leaving the watcher
    /// waiting for a `finished` that never comes (the process hung).
    #[test]
    fn core_a_panic_in_watched_work_is_not_a_hang() {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let r = std::panic::catch_unwind(|| {
                super::watched(|| {}, String::new, || -> u32 { panic!("in the work") })
            });
            tx.send(r.is_err()).unwrap();
        });
        let panicked = rx
            .recv_timeout(std::time::Duration::from_secs(20))
            .expect("watched returned");
        assert!(panicked);
        assert_eq!(super::watched(|| {}, String::new, || 7), 7);
    }
}

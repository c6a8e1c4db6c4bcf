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
mod export;
mod run;

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::{Parser, Subcommand};

use orbitlash::io::scenario_toml::{self, REFERENCE_HINGE_NAME, REFERENCE_HINGE_TOML};
use orbitlash::scenario::Scenario;

#[derive(Parser, Debug)]
#[command(
    name = "orbitlash",
    version,
    about = "Orbital thermal transients of spacecraft mechanisms and the backlash of their gears"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scenario (the embedded reference-hinge when none is given).
    Run(run::RunArgs),
    /// Validate a scenario and print derived quantities without running it.
    Check(check::CheckArgs),
    /// Measure the cost of the thermal solver (per step, per orbit, accuracy), of the
    /// backlash evaluation and of logging.
    Bench(bench::BenchArgs),
    /// Static backlash calculator: every model variant at given temperatures.
    Backlash(backlash::BacklashArgs),
    /// Convert an MCAP log back to CSV (the layout of `run --csv`).
    ExportCsv(export::ExportArgs),
}

pub fn dispatch(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Run(a) => run::run(a),
        Command::Check(a) => check::check(a),
        Command::Bench(a) => bench::bench(a),
        Command::Backlash(a) => backlash::backlash(a),
        Command::ExportCsv(a) => export::export(a),
    }
}

/// A scenario as loaded: the model, its TOML text and where it came from.
pub struct Loaded {
    pub scenario: Scenario,
    pub toml: String,
    pub file: String,
}

/// Loads `path`, or the embedded reference scenario when `None`.
pub fn load(path: Option<&Path>) -> Result<Loaded> {
    match path {
        Some(p) => {
            let (scenario, toml) = scenario_toml::load_file(p)?;
            Ok(Loaded {
                scenario,
                toml,
                file: p.display().to_string(),
            })
        }
        None => Ok(Loaded {
            scenario: scenario_toml::reference(),
            toml: REFERENCE_HINGE_TOML.to_string(),
            file: format!("<embedded {REFERENCE_HINGE_NAME}.toml>"),
        }),
    }
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

pub fn default_log_path(name: &str) -> PathBuf {
    PathBuf::from("logs").join(format!("{name}.mcap"))
}

/// Writes a report to stdout; a closed pipe (`| head`) is not an error.
pub fn print_out(text: &str) -> Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|_| out.flush()) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => Ok(r?),
    }
}

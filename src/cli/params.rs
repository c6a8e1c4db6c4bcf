//! `orbitlash params`: every number of a scenario that `--set` can change, one per line,
//! with its key path, value, unit and valid range.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use orbitlash::units::exact;

use super::{load_with, print_out};

#[derive(Args, Debug)]
pub struct ParamsArgs {
    /// Scenario file (TOML). Default: the embedded reference-hinge scenario.
    scenario: Option<PathBuf>,
    /// Change a number first (repeatable), as `run --set` does.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// Only the numbers the file gives (not the defaults).
    #[arg(long)]
    given: bool,
    /// Instead: every key a scenario file can hold a number under, as a Markdown table
    /// (key path, unit, range, default, meaning), whatever the file.
    #[arg(long, conflicts_with_all = ["scenario", "sets", "given"])]
    keys: bool,
}

pub fn params(a: ParamsArgs) -> Result<()> {
    if a.keys {
        return print_out(&orbitlash::spec::registry::markdown_table());
    }
    let loaded = load_with(a.scenario.as_deref(), &a.sets)?;
    let mut o = String::new();
    for p in loaded.model.params() {
        if a.given && !p.given {
            continue;
        }
        outln!(
            o,
            "{} = {}{}{}  ({}){}",
            p.path,
            exact(p.value),
            if p.unit.is_empty() { "" } else { " " },
            p.unit,
            p.range,
            if p.given { "" } else { "  [default]" }
        );
    }
    print_out(&o)
}

//! `orbitlash layout`: a Foxglove layout made from a run log's own channels, so that
//! every panel plots what that log has (any scenario), temperatures in °C.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use orbitlash::io::foxglove_layout::{layout as make_layout, outline};
use orbitlash::io::mcap_scan::scan;
use orbitlash::io::output::{OutputPolicy, Outputs};

use super::print_out;

#[derive(Args, Debug)]
pub struct LayoutArgs {
    /// The run log (e.g. logs/reference-hinge.mcap).
    log: PathBuf,
    /// Where to write the layout. Default: logs/<log name>.foxglove.json.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// `logs/<stem>.foxglove.json` for `<dir>/<stem>.mcap`.
fn default_out(log: &Path) -> PathBuf {
    let name = log
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = name.strip_suffix(".mcap").unwrap_or(&name);
    PathBuf::from("logs").join(format!("{stem}.foxglove.json"))
}

pub fn layout(a: LayoutArgs) -> Result<()> {
    let bytes = orbitlash::io::output::check_input(&a.log)
        .and_then(|()| std::fs::read(&a.log))
        .with_context(|| format!("cannot read {}", a.log.display()))?;
    let s =
        scan(&bytes).with_context(|| format!("{} is not a readable MCAP log", a.log.display()))?;
    if let Some(d) = &s.tail_damage {
        eprintln!("{}", orbitlash::io::mcap_read::tail_note(&a.log, d));
    }
    let o = outline(&s).map_err(|e| anyhow::anyhow!("{}: {e}", a.log.display()))?;
    if !o.topics.keys().any(|t| t.starts_with("/thermal/")) {
        anyhow::bail!(
            "{} is not an orbitlash run log (no /thermal/ topic): nothing to lay out",
            a.log.display()
        );
    }
    let (out, mut outs) = match &a.out {
        Some(p) => (p.clone(), Outputs::new(OutputPolicy::reading(&[&a.log]))),
        None => {
            let p = default_out(&a.log);
            let mut outs = Outputs::new(OutputPolicy::default_in_logs(&[&a.log]));
            outs.folder("the default log folder", Path::new("logs"), true)?;
            (p, outs)
        }
    };
    outs.file(
        if a.out.is_some() {
            "--out"
        } else {
            "the layout"
        },
        &out,
    )?;
    let mut text = serde_json::to_string_pretty(&make_layout(&o)).expect("JSON of JSON values");
    text.push('\n');
    outs.write_all(&[(&out, text.as_bytes())])?;
    print_out(&format!(
        "wrote {}: Foxglove layout for {} (open the log in Foxglove, then Layouts → Import from file…)\n",
        super::shown_path(&out),
        super::shown_path(&a.log)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cli_default_layout_name_stays_in_logs() {
        assert_eq!(
            default_out(Path::new("/tmp/x/run.mcap")),
            PathBuf::from("logs/run.foxglove.json")
        );
    }
}

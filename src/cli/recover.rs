//! `orbitlash recover`: a killed run's log (`<name>.partial`) or a truncated copy made
//! into a valid MCAP file holding everything up to its last whole message.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use orbitlash::io::mcap_scan::{recover as write_recovered, scan};
use orbitlash::io::output::OutputPolicy;

use super::print_out;

#[derive(Args, Debug)]
pub struct RecoverArgs {
    /// The cut-off log (e.g. logs/reference-hinge.mcap.partial).
    log: PathBuf,
    /// Where to write the recovered log. Default: logs/<name>.recovered.mcap.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// `logs/<name>.recovered.mcap` for `<dir>/<name>.mcap[.partial]`.
fn default_out(log: &Path) -> PathBuf {
    let name = log
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = name
        .strip_suffix(".partial")
        .unwrap_or(&name)
        .strip_suffix(".mcap")
        .unwrap_or(&name)
        .to_string();
    let stem = stem.strip_suffix(".mcap").unwrap_or(&stem);
    PathBuf::from("logs").join(format!("{stem}.recovered.mcap"))
}

pub fn recover(a: RecoverArgs) -> Result<()> {
    let bytes =
        std::fs::read(&a.log).with_context(|| format!("cannot read {}", a.log.display()))?;
    let s = scan(&bytes).with_context(|| format!("{} cannot be recovered", a.log.display()))?;
    if s.complete {
        return print_out(&format!(
            "{} is a complete log (run_end: {}); nothing to recover\n",
            a.log.display(),
            s.metadata_value("orbitlash.run_end", "status")
                .unwrap_or("none")
        ));
    }
    let (out, policy) = match &a.out {
        Some(p) => (p.clone(), OutputPolicy::reading(&[&a.log])),
        None => (
            default_out(&a.log),
            OutputPolicy::default_in_logs(&[&a.log]),
        ),
    };
    let r = write_recovered(&s, &out, &policy)?;
    print_out(&format!(
        "recovered {} messages up to t = {:.3} s from {} ({} of {} bytes were whole; the rest was cut off)\nwrote {}\n",
        r.messages,
        r.t_end_s,
        a.log.display(),
        r.recovered_bytes,
        r.file_bytes,
        out.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_names_stay_in_logs() {
        assert_eq!(
            default_out(Path::new("logs/a.mcap.partial")),
            PathBuf::from("logs/a.recovered.mcap")
        );
        assert_eq!(
            default_out(Path::new("/elsewhere/b.mcap")),
            PathBuf::from("logs/b.recovered.mcap")
        );
        assert_eq!(
            default_out(Path::new("c")),
            PathBuf::from("logs/c.recovered.mcap")
        );
    }
}

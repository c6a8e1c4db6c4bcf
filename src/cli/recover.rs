//! `orbitlash recover`: a killed run's log (`<name>.<pid>.partial`) or a truncated copy made
//! into a valid MCAP file holding everything up to its last whole message.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;

use orbitlash::io::mcap_read::{drop_undecodable, keep_valid_messages};
use orbitlash::io::mcap_scan::{LeftOut, recover as write_recovered, scan};
use orbitlash::io::output::OutputPolicy;

use super::print_out;

#[derive(Args, Debug)]
pub struct RecoverArgs {
    /// The cut-off log (e.g. logs/reference-hinge.mcap.4242.partial).
    log: PathBuf,
    /// Where to write the recovered log. Default: logs/<name>.recovered.mcap.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// `logs/<name>.recovered.mcap` for `<dir>/<name>[.mcap][.<pid>[-<k>]][.partial]`.
fn default_out(log: &Path) -> PathBuf {
    let name = log
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut stem = name.as_str();
    if let Some(s) = stem.strip_suffix(".partial") {
        stem = s;
        // the writer's process id (and counter): `run.mcap.4242.partial`
        if let Some((head, tail)) = stem.rsplit_once('.')
            && !tail.is_empty()
            && tail.chars().all(|c| c.is_ascii_digit() || c == '-')
        {
            stem = head;
        }
    }
    let stem = stem.strip_suffix(".mcap").unwrap_or(stem);
    PathBuf::from("logs").join(format!("{stem}.recovered.mcap"))
}

pub fn recover(a: RecoverArgs) -> Result<()> {
    let bytes = orbitlash::io::output::check_input(&a.log)
        .and_then(|()| std::fs::read(&a.log))
        .with_context(|| format!("cannot read {}", a.log.display()))?;
    let mut s = match scan(&bytes) {
        Ok(s) => s,
        // a killed run's CSV (`<name>.csv.<pid>.partial`): its log holds the same rows
        Err(orbitlash::io::mcap_scan::ScanError::NotMcap) if bytes.starts_with(b"time_s,") => {
            bail!(
                "{} cannot be recovered: it is a CSV a killed run left, not its log; its rows up to its last whole line are as written. The run's log (`<name>.mcap.<pid>.partial`) holds them too: `orbitlash recover` it, then `orbitlash export-csv RECOVERED.mcap --every Ts` writes the CSV's grid",
                a.log.display()
            )
        }
        Err(e) => {
            return Err(
                anyhow::Error::new(e).context(format!("{} cannot be recovered", a.log.display()))
            );
        }
    };
    keep_valid_messages(&mut s);
    // A log that ends properly may still hold damaged messages (a flipped byte).
    let damaged = drop_undecodable(&mut s);
    if let Some(first) = damaged.first() {
        eprintln!(
            "{}: {} message(s) are damaged (their chunk fails its CRC, or they do not decode with their schema) and are left out (first: message {} on {} at t = {:.3} s)",
            super::shown_path(&a.log),
            damaged.len(),
            first.number,
            orbitlash::units::shown(&first.topic),
            first.t_s
        );
    }
    // A chunk that fails its CRC without a message in it (schemas, channels): the
    // readers refuse the file, so a copy is written all the same.
    let damaged_chunks = s.damaged_chunks.len();
    if damaged_chunks > 0 && damaged.is_empty() {
        eprintln!(
            "{}: {damaged_chunks} chunk(s) fail their CRC (first at byte {}); their records are kept where they still parse and every message decodes with its schema",
            super::shown_path(&a.log),
            s.damaged_chunks[0]
        );
    }
    if s.complete && damaged_chunks == 0 {
        return print_out(&format!(
            "{} is a complete log (run_end: {}); nothing to recover\n",
            super::shown_path(&a.log),
            s.metadata_value("orbitlash.run_end", "status")
                .unwrap_or("none")
        ));
    }
    if s.messages.is_empty() {
        anyhow::bail!(
            "{} cannot be recovered: it was cut off after {} bytes, before its first whole message",
            a.log.display(),
            s.recovered_bytes
        );
    }
    let (out, policy) =
        match &a.out {
            Some(p) => (p.clone(), OutputPolicy::reading(&[&a.log])),
            None => {
                // a `logs` that is not a folder is refused as `run` and `layout` refuse it
                // (it read "Not a directory (os error 20)")
                orbitlash::io::output::Outputs::new(OutputPolicy::default_in_logs(&[&a.log]))
                    .folder("the default log folder", Path::new("logs"), true)?;
                (
                    default_out(&a.log),
                    OutputPolicy::default_in_logs(&[&a.log]),
                )
            }
        };
    let mut kept_s = s.message_times_s();
    kept_s.sort_by(f64::total_cmp);
    let left_s: Vec<f64> = damaged.iter().map(|d| d.t_s).collect();
    let left_out = LeftOut::of(&left_s, &kept_s);
    // Ctrl-C while writing: the copy is left unfinished and its temporary file removed
    // (reading is not watched: stopped then, nothing is on disk)
    let flag = super::interrupt_flag();
    let stop = || flag.load(std::sync::atomic::Ordering::Relaxed);
    let r = write_recovered(&s, &out, &policy, left_out.clone(), &stop)?;
    let how = if damaged.is_empty() && damaged_chunks > 0 {
        format!("{damaged_chunks} damaged chunk(s) written again with their CRCs")
    } else if let (true, Some(d)) = (damaged.is_empty() && s.data_complete, &s.tail_damage) {
        format!("every message was whole, but {d}; the summary and footer are written again")
    } else if damaged.is_empty() && r.recovered_bytes == r.file_bytes {
        format!(
            "all {} bytes were whole records, but the log stops there, before its end: its writer was stopped",
            r.file_bytes
        )
    } else if damaged.is_empty() {
        format!(
            "{} of {} bytes were whole; the rest was cut off",
            r.recovered_bytes, r.file_bytes
        )
    } else {
        let l = left_out.expect("damaged messages");
        format!(
            "{} damaged messages left out: the copy lacks messages {}",
            l.messages,
            l.stretches()
        )
    };
    print_out(&format!(
        "recovered {} messages up to t = {:.3} s from {} ({how}{})\nwrote {}\n",
        r.messages,
        r.t_end_s,
        super::shown_path(&a.log),
        match &r.original_status {
            Some(s) => format!("; the run had ended: {s}"),
            None => String::new(),
        },
        super::shown_path(&out)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cli_default_names_stay_in_logs() {
        assert_eq!(
            default_out(Path::new("logs/a.mcap.partial")),
            PathBuf::from("logs/a.recovered.mcap")
        );
        assert_eq!(
            default_out(Path::new("logs/a.mcap.4242.partial")),
            PathBuf::from("logs/a.recovered.mcap")
        );
        assert_eq!(
            default_out(Path::new("logs/a.mcap.4242-3.partial")),
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

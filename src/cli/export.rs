//! `orbitlash export-csv`: a log back to CSV, in the layout of `run --csv`.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use orbitlash::io::atomic::{AtomicFile, OutputPolicy};
use orbitlash::io::mcap_read::{read_log, run_table};

use super::print_out;

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// An MCAP log written by `orbitlash run`.
    log: PathBuf,
    /// Output CSV file (default: standard output).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Every numeric series of the log, as `<topic>.<field>` columns, after the
    /// `run --csv` columns.
    #[arg(long)]
    all: bool,
}

pub fn export(a: ExportArgs) -> Result<()> {
    // The output is checked and opened first: a bad path fails before the log is read.
    let mut out = match &a.out {
        Some(p) => Some(AtomicFile::create(p, &OutputPolicy::reading(&[&a.log]))?),
        None => None,
    };
    let table = read_log(&a.log)?;
    if let Some(t) = &table.truncated {
        eprintln!(
            "note: {} was cut off: read {} messages up to t = {:.3} s ({} of {} bytes were whole)",
            a.log.display(),
            t.messages,
            t.t_end_s,
            t.recovered_bytes,
            t.file_bytes
        );
    }
    let (headers, rows) =
        run_table(&table, a.all).map_err(|m| anyhow::anyhow!("{}: {m}", a.log.display()))?;
    let mut text = headers.join(",");
    text.push('\n');
    for row in &rows {
        use std::fmt::Write as _;
        let _ = write!(text, "{:.3}", row[0]);
        for v in &row[1..] {
            let _ = write!(text, ",{v:.6}");
        }
        text.push('\n');
    }
    match out.take() {
        None => print_out(&text),
        Some(mut f) => {
            let p = f.path().to_path_buf();
            f.write_all(text.as_bytes())
                .map_err(|e| orbitlash::io::output::OutputError::io(&p, e))?;
            f.commit()?;
            Ok(())
        }
    }
}

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
    /// Resample onto a grid of this interval (e.g. 30s): t = 0, 30, 60 … s up to the
    /// log's end, each column linear between the logged rows around it. Without it,
    /// the rows are the log's own (every solver step, or `run --log-every`), unevenly
    /// spaced. `run --csv` writes the same grid from the solver's own interpolant.
    #[arg(long, value_name = "SECONDSs", value_parser = every_arg)]
    every: Option<f64>,
}

fn every_arg(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .strip_suffix('s')
        .unwrap_or(s)
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not an interval in seconds (e.g. 30s)"))?;
    if v.is_finite() && v >= 1e-3 {
        Ok(v)
    } else {
        Err(format!("`{s}`: the interval must be at least 0.001 s"))
    }
}

/// The most rows `--every` writes.
const MAX_EVERY_ROWS: f64 = 1e7;

/// `rows` (time first, ascending) at t = 0, dt, 2 dt … ≤ the last row's time, each
/// column linear between the rows around it (a row at the time itself is taken as
/// is); a column whose every value is a whole number (an orbit number, the sunlit
/// flag, a heater's state) keeps the value of the row before instead.
pub fn resample(rows: &[Vec<f64>], dt: f64) -> Vec<Vec<f64>> {
    let Some(last) = rows.last() else {
        return Vec::new();
    };
    let discrete: Vec<bool> = (0..last.len())
        .map(|c| c > 0 && rows.iter().all(|r| r[c].is_nan() || r[c].fract() == 0.0))
        .collect();
    let t_end = last[0];
    let mut out = Vec::new();
    let mut j = 0;
    let mut k = 0u64;
    loop {
        let t = k as f64 * dt;
        if t > t_end * (1.0 + 1e-12) {
            break;
        }
        while j + 1 < rows.len() && rows[j + 1][0] < t {
            j += 1;
        }
        let (a, b) = (&rows[j], &rows[(j + 1).min(rows.len() - 1)]);
        let mut row = if (b[0] - t).abs() <= 1e-9 * t.abs().max(1.0) {
            b.clone()
        } else if b[0] > a[0] && t >= a[0] {
            let w = (t - a[0]) / (b[0] - a[0]);
            a.iter()
                .zip(b)
                .zip(&discrete)
                .map(|((x, y), d)| if *d { *x } else { x + w * (y - x) })
                .collect()
        } else {
            a.clone()
        };
        row[0] = t;
        out.push(row);
        k += 1;
    }
    out
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
    let rows = match a.every {
        Some(dt) => {
            let t_end = rows.last().map_or(0.0, |r| r[0]);
            if t_end / dt > MAX_EVERY_ROWS {
                anyhow::bail!(
                    "--every {dt} s over {t_end:.0} s would write {:.1e} rows (at most {MAX_EVERY_ROWS:.0e}): choose a longer interval",
                    t_end / dt
                );
            }
            resample(&rows, dt)
        }
        None => rows,
    };
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

//! `orbitlash export-csv`: a log back to CSV, in the layout of `run --csv`.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use orbitlash::io::atomic::{AtomicFile, OutputPolicy};
use orbitlash::io::mcap_read::{read_log, run_table};

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// An MCAP log written by `orbitlash run`.
    log: PathBuf,
    /// Output CSV file (default: standard output).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Every numeric series of the log, as `<topic>.<field>` columns, after the
    /// `run --csv` columns (but `/thermal/temperature_c`, the viewers' °C copy of the
    /// `<node>_k` columns).
    #[arg(long)]
    all: bool,
    /// Resample onto a grid of this interval (e.g. 30s): t = 0, 30, 60 … s up to the
    /// log's end, each column linear between the logged rows around it, and, in time
    /// order among them, the log's own row at each pair's smallest backlash (its end
    /// record says when), so the table's smallest is the run's. Without it, the rows
    /// are the log's own (every solver step, or `run --log-every`), unevenly spaced.
    /// `run --csv` writes the same grid from the solver's own interpolant.
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

/// `rows` (time first, ascending) at t = 0, dt, 2 dt … ≤ the last row's time, one row
/// at a time (nothing is built in memory), each column linear between the rows around
/// it (a row at the time itself is taken as is); a column whose every value is a whole
/// number (an orbit number, the sunlit flag, a heater's state) keeps the value of the
/// row before instead.
pub struct Resampled<'a> {
    rows: &'a [Vec<f64>],
    dt: f64,
    discrete: Vec<bool>,
    t_end: f64,
    j: usize,
    k: u64,
}

impl<'a> Resampled<'a> {
    pub fn new(rows: &'a [Vec<f64>], dt: f64) -> Resampled<'a> {
        let width = rows.first().map_or(0, Vec::len);
        let discrete = (0..width)
            .map(|c| c > 0 && rows.iter().all(|r| r[c].is_nan() || r[c].fract() == 0.0))
            .collect();
        Resampled {
            rows,
            dt,
            discrete,
            t_end: rows.last().map_or(f64::NEG_INFINITY, |r| r[0]),
            j: 0,
            k: 0,
        }
    }

    /// The rows it gives.
    pub fn count(&self) -> u64 {
        if self.rows.is_empty() {
            0
        } else {
            (self.t_end * (1.0 + 1e-12) / self.dt).floor() as u64 + 1
        }
    }

    /// The next row into `row`; false past the end.
    pub fn next_into(&mut self, row: &mut Vec<f64>) -> bool {
        let rows = self.rows;
        let t = self.k as f64 * self.dt;
        if rows.is_empty() || t > self.t_end * (1.0 + 1e-12) {
            return false;
        }
        while self.j + 1 < rows.len() && rows[self.j + 1][0] < t {
            self.j += 1;
        }
        let (a, b) = (&rows[self.j], &rows[(self.j + 1).min(rows.len() - 1)]);
        row.clear();
        if (b[0] - t).abs() <= 1e-9 * t.abs().max(1.0) {
            row.extend_from_slice(b);
        } else if b[0] > a[0] && t >= a[0] {
            let w = (t - a[0]) / (b[0] - a[0]);
            row.extend(
                a.iter()
                    .zip(b)
                    .zip(&self.discrete)
                    .map(|((x, y), d)| if *d { *x } else { x + w * (y - x) }),
            );
        } else {
            row.extend_from_slice(a);
        }
        row[0] = t;
        self.k += 1;
        true
    }
}

/// A writer of rows that checks, every 4096 rows, whether the process was asked to
/// stop (when `watch`: [`super::interrupt_flag`] installed).
struct Stoppable<'a, W: Write> {
    w: &'a mut W,
    written: u32,
    watch: bool,
}

impl<W: Write> Stoppable<'_, W> {
    fn row(&mut self, row: &[f64]) -> std::io::Result<()> {
        self.written = self.written.wrapping_add(1);
        if self.watch && self.written.is_multiple_of(4096) && stop_asked() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::Interrupted,
                "interrupted: nothing was written",
            ));
        }
        write_row(self.w, row)
    }
}

/// Whether the process was asked to stop (installs the handler on the first call).
fn stop_asked() -> bool {
    super::interrupt_flag().load(std::sync::atomic::Ordering::Relaxed)
}

/// One CSV row as `export-csv` writes it.
fn write_row(w: &mut impl Write, row: &[f64]) -> std::io::Result<()> {
    write!(w, "{:.3}", row[0])?;
    for v in &row[1..] {
        write!(w, ",{v:.6}")?;
    }
    w.write_all(b"\n")
}

/// Writes the header and every row, streamed; with `every`, the grid and, in time
/// order among its rows, the rows `extra` (a grid row at the same millisecond stands
/// for one).
fn write_table(
    w: &mut impl Write,
    headers: &[String],
    rows: &[Vec<f64>],
    every: Option<f64>,
    extra: &[&Vec<f64>],
    watch: bool,
) -> std::io::Result<()> {
    // Asked to stop (SIGINT, SIGTERM) while `watch`: an `Interrupted` error every 4096
    // rows, so that the unfinished file is removed and the command exits 2 (only for
    // a file: a pipe to stdout stops as pipes do).
    let mut w = Stoppable {
        w,
        written: 0,
        watch,
    };
    let w = &mut w;
    writeln!(w.w, "{}", headers.join(","))?;
    let ms = |t: f64| (t * 1e3).round();
    match every {
        Some(dt) => {
            let mut grid = Resampled::new(rows, dt);
            let mut row = Vec::new();
            let mut extra = extra.iter().peekable();
            while grid.next_into(&mut row) {
                while let Some(x) = extra.next_if(|x| ms(x[0]) < ms(row[0])) {
                    w.row(x)?;
                }
                extra.next_if(|x| ms(x[0]) == ms(row[0]));
                w.row(&row)?;
            }
            for x in extra {
                w.row(x)?;
            }
        }
        None => {
            for row in rows {
                w.row(row)?;
            }
        }
    }
    Ok(())
}

pub fn export(a: ExportArgs) -> Result<()> {
    // The output is checked and opened first: a bad path fails before the log is read.
    let mut out = match &a.out {
        Some(p) => Some(AtomicFile::create(p, &OutputPolicy::reading(&[&a.log]))?),
        None => None,
    };
    let watch = out.is_some();
    if watch {
        stop_asked(); // the handler, before the long read
    }
    let table = read_log(&a.log)?;
    if watch && stop_asked() {
        anyhow::bail!(
            "interrupted while reading {}: nothing was written",
            a.log.display()
        );
    }
    if let Some(d) = &table.tail_damage {
        eprintln!("{}", orbitlash::io::mcap_read::tail_note(&a.log, d));
    }
    if let Some(t) = &table.truncated {
        eprintln!(
            "note: {} was cut off: read {} messages up to t = {:.3} s ({} of {} bytes were whole)",
            super::shown_path(&a.log),
            t.messages,
            t.t_end_s,
            t.recovered_bytes,
            t.file_bytes
        );
    }
    let (headers, rows) =
        run_table(&table, a.all).map_err(|m| anyhow::anyhow!("{}: {m}", a.log.display()))?;
    // The log's rows at each pair's smallest backlash, by the end record's times.
    let t_min: Vec<f64> = table
        .metadata
        .get("orbitlash.run_end")
        .and_then(orbitlash::run::summary::RunEnd::from_metadata)
        .map(|e| e.pairs.iter().filter_map(|p| p.t_min_s).collect())
        .unwrap_or_default();
    let mut extra: Vec<&Vec<f64>> = rows
        .iter()
        .filter(|r| {
            t_min
                .iter()
                .any(|&t| (r[0] - t).abs() <= 1e-9 * t.abs().max(1.0))
        })
        .collect();
    extra.dedup_by(|a, b| a[0] == b[0]);
    if let Some(dt) = a.every {
        let t_end = rows.last().map_or(0.0, |r| r[0]);
        if t_end / dt > MAX_EVERY_ROWS {
            anyhow::bail!(
                "--every {dt} s over {t_end:.0} s would write {:.1e} rows (at most {MAX_EVERY_ROWS:.0e}): choose a longer interval",
                t_end / dt
            );
        }
    }
    // The size, from the first row's width: refused when the file system has less.
    if let (Some(f), Some(first)) = (&out, rows.first()) {
        let mut probe = Vec::new();
        write_row(&mut probe, first)?;
        let count = match a.every {
            Some(dt) => Resampled::new(&rows, dt).count() as f64,
            None => rows.len() as f64,
        };
        let need = 1.1 * count * probe.len() as f64;
        if let Some(free) = orbitlash::io::output::available_bytes(f.path())
            && need > free as f64
        {
            anyhow::bail!(
                "the CSV would take about {:.1} MB but the file system of {} has {:.1} MB free; \
choose a longer --every or export fewer columns (without --all)",
                need / 1e6,
                f.path().display(),
                free as f64 / 1e6
            );
        }
    }
    match out.take() {
        None => {
            let mut w = std::io::BufWriter::new(std::io::stdout().lock());
            match write_table(&mut w, &headers, &rows, a.every, &extra, false)
                .and_then(|()| w.flush())
            {
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
                r => Ok(r?),
            }
        }
        Some(mut f) => {
            let p = f.path().to_path_buf();
            match write_table(&mut f, &headers, &rows, a.every, &extra, true) {
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {
                    anyhow::bail!("interrupted: nothing was written to {}", p.display())
                }
                r => r.map_err(|e| orbitlash::io::output::OutputError::io(&p, e))?,
            }
            f.commit()?;
            Ok(())
        }
    }
}

//! `orbitlash plot`: a run's temperatures and backlash against time, from its log or
//! its CSV, as PNG or SVG (see `orbitlash::plot::run`).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;

use orbitlash::io::atomic::AtomicFile;
use orbitlash::io::atomic::OutputPolicy;
use orbitlash::io::mcap_read::{read_log, run_table};
use orbitlash::io::output::Outputs;
use orbitlash::plot::run::{RunEnd, RunSeries, figure};

use super::print_out;

#[derive(Args, Debug)]
pub struct PlotArgs {
    /// A run's MCAP log, or a CSV table of `run --csv` or `export-csv [--all]` (the
    /// eclipse shading and the smallest allowed backlash need the log, or `--all`).
    input: PathBuf,
    /// The figure: `.png` or `.svg` (default: logs/<input's name>.png).
    #[arg(long)]
    out: Option<PathBuf>,
    /// The figure's title (default: the scenario's name, or the input's file name).
    #[arg(long)]
    title: Option<String>,
    /// The nodes whose temperatures to draw, comma-separated, in this order (default:
    /// all, or on a run with many the ones that swing most).
    #[arg(long, value_name = "NODE,…", value_delimiter = ',')]
    nodes: Vec<String>,
}

/// What `--out` asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Png,
    Svg,
}

pub fn format_of(p: &Path, option: &str) -> Result<Format> {
    match p
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("png") => Ok(Format::Png),
        Some("svg") => Ok(Format::Svg),
        _ => bail!(
            "{option} {}: the figure's name must end in .png or .svg",
            p.display()
        ),
    }
}

/// A figure written atomically to `out` (never over an input of the command).
pub fn write_figure(fig: &orbitlash::plot::Figure, out: &Path, inputs: &[&Path]) -> Result<()> {
    let bytes = match format_of(out, "--out")? {
        Format::Png => fig.png(2.0)?,
        Format::Svg => fig.svg_file().into_bytes(),
    };
    let mut f = AtomicFile::create(out, &OutputPolicy::reading(inputs))?;
    f.write_all(&bytes)
        .map_err(|e| orbitlash::io::output::OutputError::io(out, e))?;
    f.commit()?;
    Ok(())
}

/// The UTF-8 byte-order mark a spreadsheet may put before a table's header.
const BOM: &[u8] = "\u{feff}".as_bytes();

/// How much of the table `bytes` (read from `path`) to read: all of it, but for a
/// killed run's (`<name>.csv.<pid>.partial`) whose last line has no end (`\n`, or the
/// `\r` of a CRLF file): that line was being written when the run stopped, and its
/// last cell may be short of digits, so it is left out, with a note. (A finished
/// table of the tool always ends its last line; one from elsewhere without the end is
/// read whole, and a short line is an error naming it.)
fn whole_lines_len(path: &Path, bytes: &[u8]) -> usize {
    let killed = path.to_string_lossy().ends_with(".partial");
    match bytes.last() {
        Some(b'\n' | b'\r') | None => bytes.len(),
        Some(_) if !killed => bytes.len(),
        Some(_) => {
            let end = bytes
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(bytes.len(), |i| i + 1);
            if end < bytes.len() {
                eprintln!(
                    "note: {}: its last line has no end (a killed run's table): read up to the last whole line",
                    super::shown_path(path)
                );
            }
            end
        }
    }
}

/// A CSV table with `time_s` first, every cell a number (a row's error names its line).
fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>)> {
    orbitlash::io::output::check_input(path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    // a byte-order mark (a table saved by a spreadsheet) is not part of `time_s`
    let text = bytes.strip_prefix(BOM).unwrap_or(&bytes);
    let mut r = csv::ReaderBuilder::new().from_reader(&text[..whole_lines_len(path, text)]);
    let headers: Vec<String> = r
        .headers()
        .with_context(|| format!("{}: no header line", path.display()))?
        .iter()
        .map(|h| h.trim().to_string())
        .collect();
    if headers.first().map(String::as_str) != Some("time_s") {
        bail!(
            "{}: not a run table: its first column is `{}`, not time_s (plot draws a run's log, a `run --csv` or an `export-csv` table)",
            path.display(),
            orbitlash::units::shown(headers.first().map_or("", String::as_str))
        );
    }
    let mut rows = Vec::new();
    // per temperature column: NaN cells and the first one's line (a run never writes a
    // NaN temperature, so each is said, not only drawn as a gap)
    let mut nan_k: Vec<(usize, usize)> = vec![(0, 0); headers.len()];
    for (k, rec) in r.records().enumerate() {
        let line = k + 2;
        let rec = rec.with_context(|| format!("{}: line {line}", path.display()))?;
        let mut row = Vec::with_capacity(headers.len());
        for (c, cell) in rec.iter().enumerate() {
            let v: f64 = cell
                .trim()
                .parse()
                .ok()
                // NaN is the tool's own "no valid mesh here" (run --csv, export-csv),
                // drawn as a gap; an infinity, text, or a time that is not finite is
                // not a value.
                .filter(|v: &f64| !v.is_infinite() && (c > 0 || v.is_finite()))
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "{}: line {line}, column {} ({}): {:?} is not a number (NaN or finite; time finite)",
                        path.display(),
                        c + 1,
                        headers.get(c).map_or("?", String::as_str),
                        cell
                    )
                })?;
            row.push(v);
        }
        if row.len() != headers.len() {
            bail!(
                "{}: line {line} has {} cells, the header {}",
                path.display(),
                row.len(),
                headers.len()
            );
        }
        if let Some(prev) = rows.last().map(|r: &Vec<f64>| r[0])
            && row[0] < prev
        {
            bail!(
                "{}: line {line}: time_s {} is not after {prev} (time must not go back)",
                path.display(),
                row[0]
            );
        }
        check_values(path, line, &headers, &row)?;
        for ((h, v), n) in headers.iter().zip(&row).zip(nan_k.iter_mut()) {
            if v.is_nan() && h.ends_with("_k") {
                *n = (n.0 + 1, if n.0 == 0 { line } else { n.1 });
            }
        }
        rows.push(row);
    }
    for (h, (count, first)) in headers.iter().zip(&nan_k) {
        if *count > 0 {
            eprintln!(
                "note: {}: column {h} has no value (NaN) in {count} row(s), the first at line {first}: drawn as a gap (a run writes NaN only for the gears with no valid mesh, never for a temperature)",
                super::shown_path(path)
            );
        }
    }
    if rows.len() >= 2 && rows[0][0] == rows[rows.len() - 1][0] {
        bail!(
            "{}: time_s does not advance ({} row(s), all at t = {} s): nothing to draw against time",
            path.display(),
            rows.len(),
            rows.first().map_or(0.0, |r| r[0])
        );
    }
    Ok((headers, rows))
}

/// A temperature (`<node>_k`) a thermometer can read (0 … 10 000 K) and a backlash
/// (`…backlash_um`) a gear can have (within ±1 cm), else an error naming line and column.
fn check_values(path: &Path, line: usize, headers: &[String], row: &[f64]) -> Result<()> {
    for (c, (h, v)) in headers.iter().zip(row).enumerate().skip(1) {
        let ok = if h.starts_with('/') || v.is_nan() {
            true
        } else if h.ends_with("_k") {
            (0.0..=orbitlash::run::sim::MAX_TEMPERATURE_K).contains(v)
        } else if h.ends_with("backlash_um") {
            v.abs() <= orbitlash::diagnose::data::MAX_BACKLASH_UM
        } else {
            true
        };
        if !ok {
            bail!(
                "{}: line {line}, column {} ({h}): {} is not a {} a run gives",
                path.display(),
                c + 1,
                orbitlash::units::num(*v),
                if h.ends_with("_k") {
                    "temperature (0 … 10 000 K)"
                } else {
                    "backlash (within ±1 cm)"
                }
            );
        }
    }
    Ok(())
}

/// `logs/<stem>.png` for `<dir>/<stem>.<ext>`.
fn default_out(input: &Path) -> PathBuf {
    let stem = input
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    PathBuf::from("logs").join(format!("{stem}.png"))
}

pub fn plot(a: PlotArgs) -> Result<()> {
    if let Some(t) = &a.title
        && t.chars().any(char::is_control)
    {
        bail!(
            "--title {}: holds a control character; a title is one line of plain text",
            orbitlash::units::shown(t)
        );
    }
    let out = match &a.out {
        Some(o) => o.clone(),
        None => {
            // the default, logs/<name>.png: logs/ is made if missing
            let o = default_out(&a.input);
            // the input first: a mistyped name makes no logs/ folder
            if let Err(e) = std::fs::metadata(&a.input) {
                bail!("cannot read {}: {e}", a.input.display());
            }
            let mut folder = Outputs::new(OutputPolicy::default_in_logs(&[&a.input]));
            folder.folder(
                "the default figure folder",
                o.parent().expect("logs/<name>"),
                true,
            )?;
            folder.create_folders()?;
            o
        }
    };
    draw(&a.input, &out, a.title.as_deref(), None, &a.nodes)?;
    print_out(&format!("figure: {}\n", super::shown_path(&out)))
}

/// The figure of the run in `input` (a log or a CSV) written to `out`. The verdict,
/// smallest backlash and eclipses come from the log's end record, else from `end` (the
/// run drawing its own figure), else from the rows.
/// `nodes`: the temperatures to draw (empty: the default choice).
pub fn draw(
    input: &Path,
    out: &Path,
    title: Option<&str>,
    end: Option<&RunEnd>,
    nodes: &[String],
) -> Result<()> {
    format_of(out, "--out")?;
    // The output's place is checked before the input is read.
    Outputs::new(OutputPolicy::reading(&[input])).file("--out", out)?;
    // a log by its first bytes (the MCAP magic), whatever its name; a table by its
    // header (a killed run's `<name>.csv.<pid>.partial` too); a file that is neither
    // is read as what its name says, so that its error speaks of the right format
    let head = file_head(input, 11);
    let head = head.strip_prefix(BOM).unwrap_or(&head);
    let is_log = head.starts_with(orbitlash::io::mcap_scan::MAGIC)
        || !head.starts_with(b"time_s") && named_like_a_log(input);
    let mut end = end.cloned();
    let mut cut_off = false;
    let (name, headers, rows) = if is_log {
        let table = read_log(input)?;
        if let Some(d) = &table.tail_damage {
            eprintln!("{}", orbitlash::io::mcap_read::tail_note(input, d));
        }
        let given = end.is_some();
        // a recovered copy that lost messages of a run that ended: its verdict is the
        // run's, its rows have a hole
        if let Some(m) = table.metadata.get("orbitlash.run_end")
            && m.contains_key("original_status")
            && let Some(d) = m.get("detail")
        {
            eprintln!(
                "note: {}: {}",
                super::shown_path(input),
                orbitlash::units::shown(d)
            );
        }
        if let Some(e) = table
            .metadata
            .get("orbitlash.run_end")
            .and_then(RunEnd::from_metadata)
        {
            end = Some(e);
        }
        // no end record that tells the run's verdict (a `recover`ed copy has one
        // without it)
        cut_off = !given && end.is_none();
        if cut_off {
            // a recovered copy of a killed run has an end record, of its own status
            let which = match table
                .metadata
                .get("orbitlash.run_end")
                .and_then(|m| m.get("status"))
            {
                Some(status) if status == "recovered" => "its end record (status `recovered`: a copy of a killed or cut-off run) holds no verdict".to_string(),
                Some(status) => format!(
                    "its end record (status `{}`) holds no verdict (a log written before end records kept it)",
                    orbitlash::units::shown(status)
                ),
                None => "it has no end record (a killed run or a cut-off copy)".to_string(),
            };
            eprintln!(
                "note: {}: {which}: the figure shows the rows it holds, and no PASS",
                super::shown_path(input)
            );
        }
        let name = table
            .metadata
            .get("orbitlash.provenance")
            .and_then(|m| m.get("scenario_name"))
            .cloned();
        let (h, r) =
            run_table(&table, true).map_err(|m| anyhow::anyhow!("{}: {m}", input.display()))?;
        (name, h, r)
    } else {
        let (h, r) = read_csv(input)?;
        (None, h, r)
    };
    let title = title.map(str::to_string).or(name).unwrap_or_else(|| {
        input
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    });
    // a file's name may hold control characters, which XML cannot: shown escaped
    let title = orbitlash::units::shown(&title).into_owned();
    let mut series = RunSeries::from_table(&title, &headers, &rows)
        .with_context(|| format!("cannot plot {}", input.display()))?
        .with_end(end);
    series.cut_off = cut_off;
    if !nodes.is_empty() {
        series
            .keep_nodes(nodes)
            .with_context(|| format!("cannot plot {}", input.display()))?;
    }
    let fig = figure(&series)?;
    write_figure(&fig, out, &[input])
}

/// Whether a file whose first bytes decide nothing (empty, cut short, neither a log
/// nor a table) is named like a log: `.mcap`, or a killed run's `.<pid>.partial` of a
/// name that is not a `.csv`'s.
fn named_like_a_log(path: &Path) -> bool {
    let name = path.to_string_lossy().to_ascii_lowercase();
    let name = match name.strip_suffix(".partial") {
        // `<name>.<ext>.<pid>[-<k>].partial`: the writer's process id
        Some(stem) => match stem.rsplit_once('.') {
            Some((head, pid)) if pid.chars().all(|c| c.is_ascii_digit() || c == '-') => {
                return !head.ends_with(".csv");
            }
            _ => return true,
        },
        None => name,
    };
    name.ends_with(".mcap")
}

/// The first `n` bytes of the file at `path` (fewer when it is shorter, none when it
/// cannot be read: reading it then names the error).
fn file_head(path: &Path, n: u64) -> Vec<u8> {
    use std::io::Read as _;
    let mut head = Vec::new();
    if orbitlash::io::output::check_input(path).is_ok()
        && let Ok(f) = std::fs::File::open(path)
    {
        let _ = f.take(n).read_to_end(&mut head);
    }
    head
}

//! `orbitlash export-csv`: a log back to CSV, in the layout of `run --csv`.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;

use orbitlash::io::atomic::{AtomicFile, OutputPolicy};
use orbitlash::io::csv_export::GEAR_COLUMNS;
use orbitlash::io::mcap_read::read_log;

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

/// Log fields of `/gears/<pair>/mesh` in the order of the CSV's gear columns.
const GEAR_FIELDS: [&str; 5] = [
    "backlash_exact_um",
    "backlash_closed_form_um",
    "backlash_paper_um",
    "pressure_angle_deg",
    "center_distance_mm",
];

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
    let temp_topic = "/thermal/temperature";
    if table.column(&format!("{temp_topic}.time_s")).is_none() {
        bail!(
            "{} has no {temp_topic} channel: not an orbitlash run log",
            a.log.display()
        );
    }
    // (header, column index in the table)
    let mut cols: Vec<(String, usize)> = Vec::new();
    let meta = table
        .channel_metadata
        .get(temp_topic)
        .cloned()
        .unwrap_or_default();
    let prefix = format!("{temp_topic}.");
    for (i, c) in table.columns.iter().enumerate() {
        if let Some(field) = c.strip_prefix(&prefix)
            && field != "time_s"
        {
            let node = meta
                .get(&format!("node:{field}"))
                .cloned()
                .unwrap_or_else(|| field.trim_end_matches("_k").to_string());
            cols.push((format!("{node}_k"), i));
        }
    }
    let mut pairs: Vec<(String, String)> = table
        .channel_metadata
        .iter()
        .filter(|(t, _)| t.starts_with("/gears/"))
        .map(|(t, m)| {
            (
                t.clone(),
                m.get("pair").cloned().unwrap_or_else(|| t.clone()),
            )
        })
        .collect();
    pairs.sort();
    let several = pairs.len() > 1;
    for (topic, pair) in &pairs {
        for (field, header) in GEAR_FIELDS.iter().zip(GEAR_COLUMNS) {
            if let Some(i) = table.column(&format!("{topic}.{field}")) {
                cols.push((
                    if several {
                        format!("{pair}.{header}")
                    } else {
                        header.to_string()
                    },
                    i,
                ));
            }
        }
    }
    if a.all {
        let used: Vec<usize> = cols.iter().map(|c| c.1).collect();
        for (i, c) in table.columns.iter().enumerate() {
            if !used.contains(&i) && !c.ends_with(".time_s") {
                cols.push((c.clone(), i));
            }
        }
    }
    let mut text = String::from("time_s");
    for (h, _) in &cols {
        text.push(',');
        text.push_str(h);
    }
    text.push('\n');
    for (t_ns, row) in &table.rows {
        use std::fmt::Write as _;
        let _ = write!(
            text,
            "{:.3}",
            t_ns.saturating_sub(table.time_origin_ns) as f64 * 1e-9
        );
        for (_, i) in &cols {
            let _ = write!(text, ",{:.6}", row[*i]);
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

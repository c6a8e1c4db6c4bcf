//! Reading MCAP logs back: every protobuf channel is decoded through the descriptor set
//! its schema stores (`prost-reflect`) and flattened into named numeric columns, joined
//! on log time.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::csv_export::GEAR_COLUMNS;

use prost_reflect::{DescriptorPool, DynamicMessage, MessageDescriptor, ReflectMessage, Value};

#[derive(Debug, thiserror::Error)]
pub enum LogReadError {
    #[error("cannot read {file}")]
    Io {
        file: String,
        source: std::io::Error,
    },
    #[error("{file} is not a readable MCAP file: {message}")]
    Mcap { file: String, message: String },
    #[error("{file}: message {sequence} on {topic} does not decode with its schema: {message}")]
    Decode {
        file: String,
        topic: String,
        sequence: u32,
        message: String,
    },
}

/// Numeric series of a log, one row per log time.
#[derive(Debug, Clone, Default)]
pub struct LogTable {
    /// Column names: `<topic>.<field path>`, e.g. `/thermal/temperature.housing_k`,
    /// `/gears/mesh/mesh.pinion.radius_mm[2]`.
    pub columns: Vec<String>,
    /// (log time ns, values; NaN where a column has no value at that time).
    pub rows: Vec<(u64, Vec<f64>)>,
    /// The log time of t = 0, ns (a dated run's UTC start; 0 otherwise): a row's
    /// simulated time is its log time less this.
    pub time_origin_ns: u64,
    /// Channel metadata by topic.
    pub channel_metadata: HashMap<String, BTreeMap<String, String>>,
    /// Metadata records by name.
    pub metadata: HashMap<String, BTreeMap<String, String>>,
    /// Attachments: (name, bytes).
    pub attachments: Vec<(String, Vec<u8>)>,
    /// The file was cut off: what was read of it.
    pub truncated: Option<Truncation>,
    /// Damage after the data section (the summary's CRC, bytes after the end): the
    /// messages were read whole, but a viewer may not open the file.
    pub tail_damage: Option<super::mcap_scan::TailDamage>,
}

/// The note a reader of `file` prints when its data was read whole but `d` is wrong
/// after it.
pub fn tail_note(file: &Path, d: &super::mcap_scan::TailDamage) -> String {
    format!(
        "note: {}: {d}. Every message was read (each chunk matches its own CRC), but a viewer that reads the summary (found from the file's end) may refuse the file or show the wrong data; `orbitlash recover {}` writes a clean copy",
        file.display(),
        file.display()
    )
}

impl LogTable {
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }
}

/// The message type `name` from the descriptor set a channel's schema stores.
pub fn message_type(schema_data: &[u8], name: &str) -> Result<MessageDescriptor, String> {
    let pool = DescriptorPool::decode(schema_data)
        .map_err(|e| format!("its schema {name} is not a readable descriptor set: {e}"))?;
    pool.get_message_by_name(name)
        .ok_or_else(|| format!("schema {name} not found in its descriptor set"))
}

/// A message decoded through its descriptor, flattened into `(path, value)` pairs:
/// every numeric field (double, float, integers, bool as 1/0), repeated ones as
/// `name[k]`, nested messages as `outer.inner`; absent fields at their proto3 default.
pub fn flatten_message(
    desc: &MessageDescriptor,
    data: &[u8],
    prefix: &str,
    out: &mut Vec<(String, f64)>,
) -> Result<(), String> {
    let msg = DynamicMessage::decode(desc.clone(), data).map_err(|e| e.to_string())?;
    flatten(&msg, prefix, out, 0);
    Ok(())
}

fn number(v: &Value) -> Option<f64> {
    Some(match v {
        Value::F64(x) => *x,
        Value::F32(x) => f64::from(*x),
        Value::I32(x) => f64::from(*x),
        Value::I64(x) => *x as f64,
        Value::U32(x) => f64::from(*x),
        Value::U64(x) => *x as f64,
        Value::Bool(b) => f64::from(u8::from(*b)),
        _ => return None,
    })
}

fn flatten(msg: &DynamicMessage, prefix: &str, out: &mut Vec<(String, f64)>, depth: usize) {
    for field in msg.descriptor().fields() {
        let path = format!("{prefix}.{}", field.name());
        match &*msg.get_field(&field) {
            Value::List(items) => {
                for (k, v) in items.iter().enumerate() {
                    match v {
                        Value::Message(m) if depth < 8 => {
                            flatten(m, &format!("{path}[{k}]"), out, depth + 1)
                        }
                        v => {
                            if let Some(x) = number(v) {
                                out.push((format!("{path}[{k}]"), x));
                            }
                        }
                    }
                }
            }
            Value::Message(m) if depth < 8 => flatten(m, &path, out, depth + 1),
            v => {
                if let Some(x) = number(v) {
                    out.push((path, x));
                }
            }
        }
    }
}

/// Drops the tail of a scan from the first message the writer may not have finished
/// (beyond the last finished chunk) that does not decode with its schema or whose log
/// time is not plausible: earlier than the message before it (logs are written in
/// time order) or beyond the run's end (`t_end_s` of the provenance record).
pub fn keep_valid_messages(scan: &mut super::mcap_scan::Scan<'_>) {
    let origin_ns = scan.time_origin_ns();
    let t_end_ns = scan
        .metadata_value("orbitlash.provenance", "t_end_s")
        .and_then(|v| v.parse::<f64>().ok())
        .map(|t| origin_ns + ((t + 1.0) * 1e9) as u64)
        .unwrap_or(u64::MAX);
    let schemas = scan.schemas.clone();
    let channels = scan.channels.clone();
    let mut types: HashMap<u16, Option<MessageDescriptor>> = HashMap::new();
    let mut last_ns = 0u64;
    let mut flat = Vec::new();
    scan.keep_valid(|m| {
        let t = m.header.log_time;
        let Some(ch) = channels.get(&m.header.channel_id) else {
            return false;
        };
        let Some(schema) = schemas.get(&ch.schema_id) else {
            return false;
        };
        if t < last_ns || t > t_end_ns {
            return false;
        }
        let ty = types
            .entry(ch.id)
            .or_insert_with(|| message_type(&schema.data, &schema.name).ok());
        flat.clear();
        let ok = ty.as_ref().is_some_and(|ty| {
            if schema.name.starts_with("foxglove.") {
                DynamicMessage::decode(ty.clone(), m.data).is_ok()
            } else {
                flatten_message(ty, m.data, &ch.topic, &mut flat).is_ok()
            }
        });
        if ok {
            last_ns = t;
        }
        ok
    });
}

/// A message of a scanned log that does not decode with its schema.
#[derive(Debug, Clone, PartialEq)]
pub struct Undecodable {
    /// 1-based position among the log's messages.
    pub number: usize,
    pub topic: String,
    pub t_s: f64,
}

/// Drops every message of `scan` that does not decode with its channel's schema or
/// whose chunk fails its CRC, finished chunks included (a flipped byte inside a log
/// that otherwise ends properly), and returns them. A scan that loses any is no longer complete.
pub fn drop_undecodable(scan: &mut super::mcap_scan::Scan<'_>) -> Vec<Undecodable> {
    let mut types: HashMap<u16, Option<MessageDescriptor>> = HashMap::new();
    let mut flat = Vec::new();
    let mut bad = Vec::new();
    let origin_ns = scan.time_origin_ns();
    let (schemas, channels) = (&scan.schemas, &scan.channels);
    let mut keep = Vec::with_capacity(scan.messages.len());
    for (k, m) in scan.messages.iter().enumerate() {
        let ok = !m.damaged
            && channels.get(&m.header.channel_id).is_some_and(|ch| {
                schemas.get(&ch.schema_id).is_some_and(|schema| {
                    let ty = types
                        .entry(ch.id)
                        .or_insert_with(|| message_type(&schema.data, &schema.name).ok());
                    flat.clear();
                    ty.as_ref().is_some_and(|ty| {
                        if schema.name.starts_with("foxglove.") {
                            DynamicMessage::decode(ty.clone(), m.data).is_ok()
                        } else {
                            flatten_message(ty, m.data, &ch.topic, &mut flat).is_ok()
                        }
                    })
                })
            });
        if !ok {
            bad.push(Undecodable {
                number: k + 1,
                topic: channels.get(&m.header.channel_id).map_or_else(
                    || format!("channel {}", m.header.channel_id),
                    |c| c.topic.clone(),
                ),
                t_s: super::mcap_scan::seconds_since(m.header.log_time, origin_ns),
            });
        }
        keep.push(ok);
    }
    if !bad.is_empty() {
        let mut it = keep.into_iter();
        scan.messages.retain(|_| it.next().unwrap_or(false));
        scan.complete = false;
    }
    bad
}

/// How much of a cut-off log was read (see `mcap_scan`).
#[derive(Debug, Clone, PartialEq)]
pub struct Truncation {
    pub recovered_bytes: usize,
    pub file_bytes: usize,
    pub messages: usize,
    /// Log time of the last message read, s.
    pub t_end_s: f64,
}

/// Reads every protobuf channel of the log at `path` (foxglove.* channels skipped). A
/// log that was cut off (a killed run's `.partial`, a truncated copy) is read up to its
/// last whole message; `LogTable::truncated` then says how much that was.
pub fn read_log(path: &Path) -> Result<LogTable, LogReadError> {
    let file = path.display().to_string();
    let bytes = super::output::check_input(path)
        .and_then(|()| std::fs::read(path))
        .map_err(|source| LogReadError::Io {
            file: file.clone(),
            source,
        })?;
    let mut scan = super::mcap_scan::scan(&bytes).map_err(|e| LogReadError::Mcap {
        file: file.clone(),
        message: e.to_string(),
    })?;
    keep_valid_messages(&mut scan);
    if let Some(&at) = scan.damaged_chunks.first() {
        return Err(LogReadError::Mcap {
            file,
            message: format!(
                "the chunk at byte {at} does not match its CRC ({} damaged chunk(s)): the file changed after it was written; `orbitlash recover` writes a copy without them",
                scan.damaged_chunks.len()
            ),
        });
    }
    if scan.messages.is_empty() && !scan.data_complete {
        return Err(LogReadError::Mcap {
            file,
            message: format!(
                "it was cut off after {} bytes, before its first whole message: nothing to read",
                scan.recovered_bytes
            ),
        });
    }
    let mut table = LogTable {
        time_origin_ns: scan.time_origin_ns(),
        tail_damage: scan.tail_damage.clone(),
        ..LogTable::default()
    };
    for ch in scan.channels.values() {
        table
            .channel_metadata
            .insert(ch.topic.clone(), ch.metadata.clone());
    }
    for m in &scan.metadata {
        table.metadata.insert(m.name.clone(), m.metadata.clone());
    }
    for a in &scan.attachments {
        table.attachments.push((a.name.clone(), a.data.to_vec()));
    }
    let mut types: HashMap<u16, Result<MessageDescriptor, String>> = HashMap::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut rows: BTreeMap<u64, Vec<(usize, f64)>> = BTreeMap::new();
    let mut flat = Vec::new();
    for msg in &scan.messages {
        let Some(ch) = scan.channels.get(&msg.header.channel_id) else {
            continue;
        };
        let Some(schema) = scan.schemas.get(&ch.schema_id) else {
            continue;
        };
        // foxglove.* messages (events, the 3-D view) are not series.
        if ch.message_encoding != "protobuf" || schema.name.starts_with("foxglove.") {
            continue;
        }
        let t = types
            .entry(ch.id)
            .or_insert_with(|| message_type(&schema.data, &schema.name));
        let t = t.as_ref().map_err(|message| LogReadError::Decode {
            file: file.clone(),
            topic: ch.topic.clone(),
            sequence: msg.header.sequence,
            message: message.clone(),
        })?;
        flat.clear();
        flatten_message(t, msg.data, &ch.topic, &mut flat).map_err(|message| {
            LogReadError::Decode {
                file: file.clone(),
                topic: ch.topic.clone(),
                sequence: msg.header.sequence,
                message,
            }
        })?;
        let row = rows.entry(msg.header.log_time).or_default();
        for (name, v) in flat.drain(..) {
            let next = index.len();
            let i = *index.entry(name.clone()).or_insert_with(|| {
                table.columns.push(name);
                next
            });
            row.push((i, v));
        }
    }
    if !scan.data_complete {
        table.truncated = Some(Truncation {
            recovered_bytes: scan.recovered_bytes,
            file_bytes: scan.file_bytes,
            messages: scan.messages.len(),
            t_end_s: scan.time_span_ns().map_or(0.0, |(_, b)| {
                b.saturating_sub(scan.time_origin_ns()) as f64 * 1e-9
            }),
        });
    }
    let n = table.columns.len();
    // The last rows of a cut-off (or recovered) log may lack the topics written after
    // the cut; every topic is written at every sample otherwise. Counted by the fields
    // written, not by their values: a NaN written (a lost mesh) is there.
    let mut seen = vec![false; n];
    let written: Vec<usize> = rows
        .values()
        .map(|vals| {
            seen.fill(false);
            vals.iter()
                .filter(|(i, _)| !std::mem::replace(&mut seen[*i], true))
                .count()
        })
        .collect();
    let full = written.iter().copied().max().unwrap_or(0);
    let keep = written
        .iter()
        .rposition(|&w| w == full)
        .map_or(0, |k| k + 1);
    table.rows = rows
        .into_iter()
        .take(keep)
        .map(|(t, vals)| {
            let mut r = vec![f64::NAN; n];
            for (i, v) in vals {
                r[i] = v;
            }
            (t, r)
        })
        .collect();
    Ok(table)
}

/// Log fields of `/gears/<pair>` in the order of the CSV's gear columns.
const GEAR_FIELDS: [&str; 5] = [
    "backlash_exact_um",
    "backlash_closed_form_um",
    "backlash_paper_um",
    "pressure_angle_deg",
    "center_distance_mm",
];

/// A log as the table of `run --csv`: `time_s` (from the log's time origin), then
/// `<node>_k` by node name and the gear columns (`<pair>.` before them when there are
/// several pairs); with `all`, every other numeric series as `<topic>.<field>`.
/// `export-csv` writes it; `plot` draws it.
#[allow(clippy::type_complexity)]
pub fn run_table(table: &LogTable, all: bool) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let temp_topic = "/thermal/temperature";
    if table.column(&format!("{temp_topic}.time_s")).is_none() {
        return Err(format!("no {temp_topic} channel: not an orbitlash run log"));
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
        // the gear pairs (a `--scene` log also has `/gears/<pair>/scene`: not a pair)
        .filter(|(t, _)| t.starts_with("/gears/") && !t.ends_with("/scene"))
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
    if all {
        let used: Vec<usize> = cols.iter().map(|c| c.1).collect();
        for (i, c) in table.columns.iter().enumerate() {
            // the °C copy of the temperatures (for viewers) adds nothing to the K columns
            if !used.contains(&i)
                && !c.ends_with(".time_s")
                && !c.starts_with("/thermal/temperature_c.")
            {
                cols.push((c.clone(), i));
            }
        }
    }
    let mut headers = vec!["time_s".to_string()];
    headers.extend(cols.iter().map(|c| c.0.clone()));
    let rows = table
        .rows
        .iter()
        .map(|(t_ns, row)| {
            let mut r = vec![t_ns.saturating_sub(table.time_origin_ns) as f64 * 1e-9];
            r.extend(cols.iter().map(|(_, i)| row[*i]));
            r
        })
        .collect();
    Ok((headers, rows))
}

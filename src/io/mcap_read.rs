//! Reading MCAP logs back: every protobuf channel is decoded through the schema stored
//! in the file and flattened into named numeric columns, joined on log time.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::log_schema::{DecodedType, Kind, decode_type};
use super::protobuf::{Wire, fields};

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
    /// Channel metadata by topic.
    pub channel_metadata: HashMap<String, BTreeMap<String, String>>,
    /// Metadata records by name.
    pub metadata: HashMap<String, BTreeMap<String, String>>,
    /// Attachments: (name, bytes).
    pub attachments: Vec<(String, Vec<u8>)>,
}

impl LogTable {
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }
}

fn flatten(
    t: &DecodedType,
    data: &[u8],
    prefix: &str,
    out: &mut Vec<(String, f64)>,
) -> Result<(), String> {
    let decoded = fields(data).map_err(|e| e.to_string())?;
    for (number, name, kind) in &t.fields {
        let path = format!("{prefix}.{name}");
        let values: Vec<&Wire<'_>> = decoded
            .iter()
            .filter(|(n, _)| n == number)
            .map(|(_, v)| v)
            .collect();
        match kind {
            Kind::Double => {
                let v = match values.last() {
                    Some(Wire::Fixed64(b)) => f64::from_le_bytes(*b),
                    None => 0.0, // proto3 default
                    Some(other) => {
                        return Err(format!("{path}: expected a double, found {other:?}"));
                    }
                };
                out.push((path, v));
            }
            Kind::RepeatedDouble => {
                let mut k = 0;
                for v in values {
                    let bytes: Vec<[u8; 8]> = match v {
                        Wire::Len(b) if b.len() % 8 == 0 => b
                            .chunks_exact(8)
                            .map(|c| c.try_into().expect("8"))
                            .collect(),
                        Wire::Fixed64(b) => vec![*b],
                        other => {
                            return Err(format!(
                                "{path}: expected packed doubles, found {other:?}"
                            ));
                        }
                    };
                    for b in bytes {
                        out.push((format!("{path}[{k}]"), f64::from_le_bytes(b)));
                        k += 1;
                    }
                }
            }
            Kind::Message(m) => {
                let nested = t
                    .nested
                    .get(m)
                    .ok_or_else(|| format!("{path}: unknown type {m}"))?;
                let body = match values.last() {
                    Some(Wire::Len(b)) => *b,
                    None => &[],
                    Some(other) => {
                        return Err(format!("{path}: expected a message, found {other:?}"));
                    }
                };
                flatten(nested, body, &path, out)?;
            }
        }
    }
    Ok(())
}

/// Reads every protobuf channel of the log at `path` (foxglove.* channels skipped).
pub fn read_log(path: &Path) -> Result<LogTable, LogReadError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| LogReadError::Io {
        file: file.clone(),
        source,
    })?;
    let mcap_err = |e: mcap::McapError| LogReadError::Mcap {
        file: file.clone(),
        message: e.to_string(),
    };
    let summary = mcap::Summary::read(&bytes)
        .map_err(mcap_err)?
        .ok_or_else(|| LogReadError::Mcap {
            file: file.clone(),
            message: "no summary section (the file was not closed)".into(),
        })?;
    let mut table = LogTable::default();
    for (_, ch) in summary.channels.iter() {
        table
            .channel_metadata
            .insert(ch.topic.clone(), ch.metadata.clone());
    }
    for record in mcap::read::LinearReader::new(&bytes).map_err(mcap_err)? {
        match record.map_err(mcap_err)? {
            mcap::records::Record::Metadata(m) => {
                table.metadata.insert(m.name, m.metadata);
            }
            mcap::records::Record::Attachment { header, data, .. } => {
                table.attachments.push((header.name, data.into_owned()));
            }
            _ => {}
        }
    }
    let mut types: HashMap<u16, Option<DecodedType>> = HashMap::new();
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut rows: BTreeMap<u64, Vec<(usize, f64)>> = BTreeMap::new();
    let mut flat = Vec::new();
    for msg in mcap::MessageStream::new(&bytes).map_err(mcap_err)? {
        let msg = msg.map_err(mcap_err)?;
        let ch = &msg.channel;
        let Some(schema) = ch.schema.as_ref() else {
            continue;
        };
        // foxglove.* messages (events, the 3-D view) are not series.
        if ch.message_encoding != "protobuf" || schema.name.starts_with("foxglove.") {
            continue;
        }
        let t = types
            .entry(ch.id)
            .or_insert_with(|| decode_type(&schema.data, &schema.name));
        let Some(t) = t.as_ref() else {
            return Err(LogReadError::Decode {
                file: file.clone(),
                topic: ch.topic.clone(),
                sequence: msg.sequence,
                message: format!("schema {} not found in its descriptor set", schema.name),
            });
        };
        flat.clear();
        flatten(t, &msg.data, &ch.topic, &mut flat).map_err(|message| LogReadError::Decode {
            file: file.clone(),
            topic: ch.topic.clone(),
            sequence: msg.sequence,
            message,
        })?;
        let row = rows.entry(msg.log_time).or_default();
        for (name, v) in flat.drain(..) {
            let next = index.len();
            let i = *index.entry(name.clone()).or_insert_with(|| {
                table.columns.push(name);
                next
            });
            row.push((i, v));
        }
    }
    let n = table.columns.len();
    table.rows = rows
        .into_iter()
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

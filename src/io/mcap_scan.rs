//! A linear scan of an MCAP file that tolerates a cut-off end: a log whose writer was
//! killed (power loss, `kill -9`: only `<name>.partial` is left) or a file truncated in
//! a copy. Records are read from the start; the scan stops at the first record that is
//! not whole, and inside an uncompressed chunk (what `orbitlash` writes; the writer
//! streams a chunk to the file behind a placeholder header and fixes the header when
//! the chunk is done) it keeps every message that is whole. A complete file gives its
//! data section, the same as a normal reader.
//!
//! [`recover`] writes the scanned records to a new, valid MCAP file.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::Path;

use mcap::records::{self, Record};

/// The bytes an MCAP file starts and ends with.
pub const MAGIC: &[u8] = b"\x89MCAP0\r\n";
const OP_CHUNK: u8 = 0x06;

/// A message found by the scan: its header, its bytes and where its record ends in
/// the file (byte offset just past it).
#[derive(Debug, Clone)]
pub struct ScannedMessage<'a> {
    pub header: records::MessageHeader,
    pub data: &'a [u8],
    pub end_offset: usize,
    /// From a chunk the writer finished (its header says how long it is). Messages of
    /// a chunk cut off are only as good as the bytes after the cut, which a power loss
    /// may have left as zeros: check them before use ([`Scan::keep_valid`]).
    pub verified: bool,
    /// Its chunk fails its CRC: some byte of the chunk changed after it was written
    /// (a flipped bit); the message may decode and still be wrong.
    pub damaged: bool,
}

/// Everything a scan recovered.
#[derive(Debug, Default)]
pub struct Scan<'a> {
    pub schemas: BTreeMap<u16, mcap::Schema<'a>>,
    pub channels: BTreeMap<u16, records::Channel>,
    pub messages: Vec<ScannedMessage<'a>>,
    pub metadata: Vec<records::Metadata>,
    pub attachments: Vec<mcap::Attachment<'a>>,
    /// The data section ended properly (its DataEnd record was reached): no message
    /// is missing.
    pub data_complete: bool,
    /// The whole file is there: data section, summary, footer and closing magic.
    pub complete: bool,
    /// Bytes up to the end of the last whole record or message kept.
    pub recovered_bytes: usize,
    pub file_bytes: usize,
    /// Where the first record not in a finished chunk starts.
    first_unverified_offset: usize,
    /// File offsets of the chunks whose CRC does not match their bytes.
    pub damaged_chunks: Vec<usize>,
    /// What is wrong after the data section of a file whose footer was reached: the
    /// summary fails its CRC, or bytes follow the closing magic. The messages are not
    /// affected (the chunks carry CRCs of their own), but a reader that seeks through
    /// the summary's index (a viewer) may refuse the file or read the wrong bytes.
    pub tail_damage: Option<TailDamage>,
}

/// Damage after a log's data section (see [`Scan::tail_damage`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TailDamage {
    /// The summary section and the footer's start (bytes `from .. to`) do not match the
    /// footer's `summary_crc`.
    SummaryCrc { from: usize, to: usize },
    /// The footer's `summary_start` points at or past the footer itself.
    SummaryStart {
        summary_start: u64,
        footer_at: usize,
    },
    /// No whole footer after the data section: the file is cut off, or a record of the
    /// summary or the footer is damaged, at byte `at` (`bytes` from there to the end).
    NoFooter { at: usize, bytes: usize },
    /// The footer is not followed by the closing magic (`bytes` after the footer).
    NoClosingMagic { bytes: usize },
    /// `bytes` more bytes follow the closing magic.
    Trailing { bytes: usize },
}

impl std::fmt::Display for TailDamage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TailDamage::SummaryCrc { from, to } => write!(
                f,
                "its summary section (the index and statistics, bytes {from} … {to}) does not match the footer's CRC: it changed after the file was written"
            ),
            TailDamage::SummaryStart {
                summary_start,
                footer_at,
            } => write!(
                f,
                "its footer (at byte {footer_at}) says the summary starts at byte {summary_start}, which is not before the footer"
            ),
            TailDamage::NoFooter { at, bytes } => write!(
                f,
                "it has no whole footer: from byte {at} ({bytes} byte(s) to its end) its summary or footer is cut off or damaged"
            ),
            TailDamage::NoClosingMagic { bytes } => write!(
                f,
                "its footer is not followed by the closing MCAP magic ({bytes} byte(s) after the footer)"
            ),
            TailDamage::Trailing { bytes } => {
                write!(f, "{bytes} byte(s) follow its closing MCAP magic")
            }
        }
    }
}

/// What follows a footer record (`bytes[at..end]`, opcode at `at`): the summary's CRC,
/// then the closing magic and nothing after it.
fn tail_damage(bytes: &[u8], at: usize, end: usize, f: &records::Footer) -> Option<TailDamage> {
    // The CRC covers the summary and the footer up to its own field (opcode, length,
    // summary_start, summary_offset_start: 25 bytes); a summary_start of 0 means there
    // is no summary. A CRC of 0 means none was computed.
    let from = if f.summary_start == 0 {
        Some(at)
    } else {
        usize::try_from(f.summary_start).ok().filter(|&s| s < at)
    };
    let Some(from) = from else {
        return Some(TailDamage::SummaryStart {
            summary_start: f.summary_start,
            footer_at: at,
        });
    };
    let to = at + 25;
    if f.summary_crc != 0 && crc32fast::hash(&bytes[from..to]) != f.summary_crc {
        return Some(TailDamage::SummaryCrc { from, to });
    }
    let after = &bytes[end..];
    if !after.starts_with(MAGIC) {
        return Some(TailDamage::NoClosingMagic { bytes: after.len() });
    }
    (after.len() > MAGIC.len()).then(|| TailDamage::Trailing {
        bytes: after.len() - MAGIC.len(),
    })
}

impl Scan<'_> {
    /// Keeps the messages up to the first unverified one that `valid` rejects (a
    /// message that does not decode, or whose time is not plausible): the end of the
    /// real data in a file whose tail is garbage.
    pub fn keep_valid(&mut self, mut valid: impl FnMut(&ScannedMessage<'_>) -> bool) {
        if let Some(k) = self.messages.iter().position(|m| !m.verified && !valid(m)) {
            self.messages.truncate(k);
            self.recovered_bytes = self.messages.last().map_or(
                self.recovered_bytes.min(self.first_unverified_offset),
                |m| m.end_offset,
            );
            self.data_complete = false;
            self.complete = false;
        }
    }

    /// Log time span of the recovered messages, ns.
    pub fn time_span_ns(&self) -> Option<(u64, u64)> {
        let mut it = self.messages.iter().map(|m| m.header.log_time);
        let first = it.next()?;
        Some(it.fold((first, first), |(a, b), t| (a.min(t), b.max(t))))
    }

    /// Every message's time, s from t = 0 ([`seconds_since`] the time origin), in the
    /// scan's order.
    pub fn message_times_s(&self) -> Vec<f64> {
        let origin_ns = self.time_origin_ns();
        (self.messages.iter())
            .map(|m| seconds_since(m.header.log_time, origin_ns))
            .collect()
    }

    /// The log time of t = 0, ns: a dated run's start (`time_origin_unix_ns` of the
    /// provenance record), else 0.
    pub fn time_origin_ns(&self) -> u64 {
        self.metadata_value("orbitlash.provenance", super::mcap_log::TIME_ORIGIN_KEY)
            .and_then(|v| v.parse().ok())
            .unwrap_or(0)
    }

    /// The value of `key` in the metadata record `name`, if any.
    pub fn metadata_value(&self, name: &str, key: &str) -> Option<&str> {
        self.metadata
            .iter()
            .rev()
            .find(|m| m.name == name)
            .and_then(|m| m.metadata.get(key))
            .map(String::as_str)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ScanError {
    #[error("not an MCAP file (its first bytes are not the MCAP magic)")]
    NotMcap,
    #[error("the file ends within its first 8 bytes (the MCAP magic): nothing was written to it")]
    Empty,
    #[error("the file is damaged: the record at byte {offset} is malformed: {message}")]
    Malformed { offset: usize, message: String },
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    b.get(at..at + 8)
        .map(|s| u64::from_le_bytes(s.try_into().expect("8 bytes")))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    b.get(at..at + 4)
        .map(|s| u32::from_le_bytes(s.try_into().expect("4 bytes")))
}

/// Scans `bytes` (see the module docs).
pub fn scan(bytes: &[u8]) -> Result<Scan<'_>, ScanError> {
    if bytes.len() < MAGIC.len() && MAGIC.starts_with(bytes) {
        return Err(ScanError::Empty);
    }
    if !bytes.starts_with(MAGIC) {
        return Err(ScanError::NotMcap);
    }
    let mut s = Scan {
        file_bytes: bytes.len(),
        recovered_bytes: MAGIC.len(),
        first_unverified_offset: bytes.len(),
        ..Scan::default()
    };
    let mut at = MAGIC.len();
    // Ends where a record's opcode or length is cut off.
    while let (Some(&op), Some(len)) = (bytes.get(at), u64_at(bytes, at + 1)) {
        let body_start = at + 9;
        let whole = usize::try_from(len)
            .ok()
            .and_then(|l| body_start.checked_add(l))
            .filter(|&end| end <= bytes.len());
        if op == 0 {
            break; // no record has opcode 0: the bytes from here are not MCAP (zeros)
        }
        let Some(end) = whole else {
            // A record cut off: only a chunk can still give whole messages.
            s.first_unverified_offset = at;
            if op == OP_CHUNK {
                partial_chunk(bytes, body_start, &mut s)?;
            }
            break;
        };
        let body = &bytes[body_start..end];
        let parsed = super::mcap_lengths::check_record(op, body)
            .and_then(|()| mcap::parse_record(op, body).map_err(|e| e.to_string()));
        let record = match parsed {
            Ok(r) => r,
            // past the data section (the summary): the messages are whole; the damage
            // is said as a missing footer ([`TailDamage::NoFooter`])
            Err(_) if s.data_complete => break,
            Err(message) => {
                return Err(ScanError::Malformed {
                    offset: at,
                    message,
                });
            }
        };
        match record {
            Record::DataEnd(_) => s.data_complete = true,
            Record::Footer(f) => {
                s.data_complete = true;
                s.tail_damage = tail_damage(bytes, at, end, &f);
                s.complete = s.tail_damage.is_none();
                s.recovered_bytes = end;
                break;
            }
            Record::Chunk { header, data } => {
                if !header.compression.is_empty() {
                    return Err(ScanError::Malformed {
                        offset: at,
                        message: format!(
                            "chunk compressed with {} (this reader takes uncompressed chunks, as orbitlash writes them)",
                            header.compression
                        ),
                    });
                }
                let Cow::Borrowed(data) = data else {
                    unreachable!("an uncompressed chunk borrows the file")
                };
                let offset = data.as_ptr() as usize - bytes.as_ptr() as usize;
                // a CRC of 0 means none was computed
                let damaged = header.uncompressed_crc != 0
                    && crc32fast::hash(data) != header.uncompressed_crc;
                let before = s.messages.len();
                match inner_records(bytes, offset, offset + data.len(), true, &mut s) {
                    Ok(()) => {}
                    // a changed byte that broke a record inside the chunk: what came
                    // before it is kept (marked damaged), and the CRC names the damage
                    Err(_) if damaged => {}
                    Err(e) => return Err(e),
                }
                if damaged {
                    s.damaged_chunks.push(at);
                    for m in &mut s.messages[before..] {
                        m.damaged = true;
                    }
                }
            }
            // the summary repeats the schemas and channels: the data section's copies
            // are the ones the messages were written with (a changed byte in the
            // summary must not replace them)
            Record::Schema { header, .. }
                if s.data_complete && s.schemas.contains_key(&header.id) => {}
            Record::Channel(c) if s.data_complete && s.channels.contains_key(&c.id) => {}
            other => keep(other, end, true, &mut s),
        }
        s.recovered_bytes = s.recovered_bytes.max(end);
        at = end;
    }
    // the data section ended (its DataEnd record) but no footer was read: cut off or
    // damaged in the summary or the footer
    if s.data_complete && !s.complete && s.tail_damage.is_none() {
        s.tail_damage = Some(TailDamage::NoFooter {
            bytes: bytes.len() - at,
            at,
        });
    }
    Ok(s)
}

/// A chunk whose record is cut off: its header (after the opcode and length) starts at
/// `at`; whole inner records are kept.
fn partial_chunk<'a>(bytes: &'a [u8], at: usize, s: &mut Scan<'a>) -> Result<(), ScanError> {
    // start time, end time, uncompressed size, CRC, compression (u32 length + text),
    // records length, records.
    let Some(name_len) = u32_at(bytes, at + 28) else {
        return Ok(());
    };
    let name_start = at + 32;
    let Some(name) = bytes.get(name_start..name_start + name_len as usize) else {
        return Ok(());
    };
    if !name.is_empty() {
        return Ok(()); // a compressed stream cut off cannot be read
    }
    let records_start = name_start + name.len() + 8;
    if records_start > bytes.len() {
        return Ok(());
    }
    inner_records(bytes, records_start, bytes.len(), false, s)
}

/// The records inside a chunk, `bytes[from..to]`, up to the last whole one.
fn inner_records<'a>(
    bytes: &'a [u8],
    from: usize,
    to: usize,
    verified: bool,
    s: &mut Scan<'a>,
) -> Result<(), ScanError> {
    let mut at = from;
    while at + 9 <= to {
        let (Some(&op), Some(len)) = (bytes.get(at), u64_at(bytes, at + 1)) else {
            break;
        };
        if op == 0 {
            break; // zeros: the writer never got here
        }
        let body_start = at + 9;
        let Some(end) = usize::try_from(len)
            .ok()
            .and_then(|l| body_start.checked_add(l))
            .filter(|&end| end <= to)
        else {
            break;
        };
        let body = &bytes[body_start..end];
        let record = match super::mcap_lengths::check_record(op, body)
            .and_then(|()| mcap::parse_record(op, body).map_err(|e| e.to_string()))
        {
            Ok(r) => r,
            // in a chunk cut off, a record that does not parse is where the data ends
            Err(_) if !verified => break,
            Err(message) => {
                return Err(ScanError::Malformed {
                    offset: at,
                    message,
                });
            }
        };
        keep(record, end, verified, s);
        s.recovered_bytes = s.recovered_bytes.max(end);
        at = end;
    }
    Ok(())
}

fn keep<'a>(record: Record<'a>, end: usize, verified: bool, s: &mut Scan<'a>) {
    match record {
        Record::Schema { header, data } => {
            s.schemas.insert(
                header.id,
                mcap::Schema {
                    id: header.id,
                    name: header.name,
                    encoding: header.encoding,
                    data,
                },
            );
        }
        Record::Channel(c) => {
            s.channels.insert(c.id, c);
        }
        Record::Message { header, data } => {
            let Cow::Borrowed(data) = data else {
                unreachable!("a message record borrows the file")
            };
            s.messages.push(ScannedMessage {
                header,
                data,
                end_offset: end,
                verified,
                damaged: false,
            });
        }
        Record::Metadata(m) => s.metadata.push(m),
        Record::Attachment { header, data, .. } => s.attachments.push(mcap::Attachment {
            log_time: header.log_time,
            create_time: header.create_time,
            name: header.name,
            media_type: header.media_type,
            data,
        }),
        _ => {}
    }
}

/// What [`recover`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Recovery {
    pub messages: usize,
    /// Log time of the last message kept, s.
    pub t_end_s: f64,
    pub recovered_bytes: usize,
    pub file_bytes: usize,
    /// The run_end status the original file had, if it got that far.
    pub original_status: Option<String>,
}

/// A log time (ns) as seconds after `origin_ns` (a log's t = 0), none before it.
pub fn seconds_since(log_time_ns: u64, origin_ns: u64) -> f64 {
    log_time_ns.saturating_sub(origin_ns) as f64 * 1e-9
}

/// Messages a recovery leaves out of a log that otherwise ends properly (damaged
/// ones): how many, and the stretches of log time (s, first and last) they fall in,
/// split wherever a kept message lies between two left out.
#[derive(Debug, Clone, PartialEq)]
pub struct LeftOut {
    pub messages: usize,
    pub spans_s: Vec<(f64, f64)>,
}

/// Stretches listed by name before "and N more".
const SPANS_SHOWN: usize = 3;

impl LeftOut {
    /// The messages left out at log times `left_s` (any order), split into stretches
    /// by the log times `kept_s` (sorted) of the messages kept; None when none was left
    /// out. A kept message at the same time as one left out does not split them.
    pub fn of(left_s: &[f64], kept_s: &[f64]) -> Option<LeftOut> {
        let mut t = left_s.to_vec();
        t.sort_by(f64::total_cmp);
        let (&first, rest) = t.split_first()?;
        let mut spans_s = vec![(first, first)];
        for &x in rest {
            let last = spans_s.last_mut().expect("one span");
            // a kept message strictly between the span's end and x splits them
            let i = kept_s.partition_point(|&k| k <= last.1);
            if kept_s.get(i).is_some_and(|&k| k < x) {
                spans_s.push((x, x));
            } else {
                last.1 = x;
            }
        }
        Some(LeftOut {
            messages: t.len(),
            spans_s,
        })
    }

    /// "at t = a … b s", or "in N stretches, t = a … b, c … d s" (the first few, then
    /// how many more).
    pub fn stretches(&self) -> String {
        let each: Vec<String> = self
            .spans_s
            .iter()
            .take(SPANS_SHOWN)
            .map(|(a, b)| {
                if a == b {
                    format!("{a:.3}")
                } else {
                    format!("{a:.3} … {b:.3}")
                }
            })
            .collect();
        let more = self.spans_s.len().saturating_sub(SPANS_SHOWN);
        match self.spans_s.len() {
            1 => format!("at t = {} s", each[0]),
            n => format!(
                "in {n} stretches, t = {} s{}",
                each.join(", "),
                if more > 0 {
                    format!(" and {more} more")
                } else {
                    String::new()
                }
            ),
        }
    }
}

/// Writes every record `scan` recovered into a new MCAP file at `out` (atomically, never
/// over an input: `policy`), with a `orbitlash.run_end` record of status `recovered`
/// when the original had none, or when `left_out` messages were left out of one that
/// had it (its verdict, the run's own, kept; its status kept as `original_status`).
/// Messages whose channel or schema was lost are skipped. `stop` is asked every 256
/// messages: when it says yes, the temporary file is removed and nothing is written.
pub fn recover(
    scan: &Scan<'_>,
    out: &Path,
    policy: &super::output::OutputPolicy,
    left_out: Option<LeftOut>,
    stop: &dyn Fn() -> bool,
) -> Result<Recovery, super::output::OutputError> {
    use super::output::OutputError;
    let err = |e: mcap::McapError| OutputError::other(out, e);
    let file = super::atomic::AtomicFile::create(out, policy)?;
    let mut w = mcap::WriteOptions::new()
        .library(format!(
            "orbitlash {} (recovered)",
            env!("CARGO_PKG_VERSION")
        ))
        .profile("")
        .compression(None)
        .chunk_size(Some(1 << 16))
        .calculate_chunk_crcs(true)
        .create(file)
        .map_err(err)?;
    for sc in scan.schemas.values() {
        w.add_schema_with_id(sc.id, &sc.name, &sc.encoding, &sc.data)
            .map_err(err)?;
    }
    let mut usable = std::collections::BTreeSet::new();
    for ch in scan.channels.values() {
        if ch.schema_id != 0 && !scan.schemas.contains_key(&ch.schema_id) {
            continue;
        }
        w.add_channel_with_id(
            ch.id,
            ch.schema_id,
            &ch.topic,
            &ch.message_encoding,
            &ch.metadata,
        )
        .map_err(err)?;
        usable.insert(ch.id);
    }
    for m in scan
        .metadata
        .iter()
        .filter(|m| m.name != "orbitlash.run_end")
    {
        w.write_metadata(m).map_err(err)?;
    }
    for a in &scan.attachments {
        w.attach(a).map_err(err)?;
    }
    // the temporary file goes with `w`: nothing is left under any name
    let stopped = || OutputError::other(out, "interrupted: nothing was written");
    let mut kept = 0usize;
    let mut last_ns = 0u64;
    for m in &scan.messages {
        if !usable.contains(&m.header.channel_id) {
            continue;
        }
        w.write_to_known_channel(&m.header, m.data).map_err(err)?;
        kept += 1;
        if kept.is_multiple_of(256) && stop() {
            return Err(stopped());
        }
        last_ns = last_ns.max(m.header.log_time);
    }
    // asked once more after the last messages (the file is then whole at the rename)
    if stop() {
        return Err(stopped());
    }
    let original_status = scan
        .metadata_value("orbitlash.run_end", "status")
        .map(str::to_string);
    let t_end_s = seconds_since(last_ns, scan.time_origin_ns());
    let end: BTreeMap<String, String> = match scan
        .metadata
        .iter()
        .rev()
        .find(|m| m.name == "orbitlash.run_end")
    {
        Some(m) => {
            let mut end = m.metadata.clone();
            if let Some(l) = left_out {
                let was = end.insert("status".into(), "recovered".into());
                // a copy of a copy keeps the first original's status
                end.entry("original_status".into())
                    .or_insert_with(|| was.unwrap_or_default());
                end.insert(
                    "detail".into(),
                    format!(
                        "recovered: {} damaged messages left out {}; the verdict is the run's own, over every step",
                        l.messages,
                        l.stretches()
                    ),
                );
            }
            end
        }
        None => [
            ("status", "recovered".to_string()),
            ("t_end_s", format!("{t_end_s}")),
            (
                "detail",
                format!(
                    "recovered from a log cut off after {} of {} bytes: {kept} messages up to t = {t_end_s:.3} s",
                    scan.recovered_bytes, scan.file_bytes
                ),
            ),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect(),
    };
    w.write_metadata(&records::Metadata {
        name: "orbitlash.run_end".into(),
        metadata: end,
    })
    .map_err(err)?;
    w.finish().map_err(err)?;
    w.into_inner().commit()?;
    Ok(Recovery {
        messages: kept,
        t_end_s,
        recovered_bytes: scan.recovered_bytes,
        file_bytes: scan.file_bytes,
        original_status,
    })
}

#[cfg(test)]
mod damaged_chunk_tests {
    use super::*;

    /// A small log: one channel `/thermal/x` and a few messages in one chunk, with or
    /// without the chunk's CRC.
    fn small_log(crc: bool) -> Vec<u8> {
        let mut w = mcap::WriteOptions::new()
            .compression(None)
            .calculate_chunk_crcs(crc)
            .create(std::io::Cursor::new(Vec::new()))
            .unwrap();
        let schema = w.add_schema("x", "jsonschema", b"{}").unwrap();
        let ch = w
            .add_channel(schema, "/thermal/x", "json", &BTreeMap::new())
            .unwrap();
        for k in 0..5u32 {
            let header = mcap::records::MessageHeader {
                channel_id: ch,
                sequence: k,
                log_time: u64::from(k),
                publish_time: u64::from(k),
            };
            w.write_to_known_channel(&header, b"{}").unwrap();
        }
        w.finish().unwrap();
        w.into_inner().into_inner()
    }

    /// The channel record's topic length inside the chunk made huge.
    fn broken_topic_length(mut bytes: Vec<u8>) -> Vec<u8> {
        let at = bytes
            .windows(10)
            .position(|w| w == b"/thermal/x")
            .expect("the topic in the chunk");
        bytes[at - 4..at].copy_from_slice(&0x7fff_ffffu32.to_le_bytes());
        bytes
    }

    /// A changed byte that breaks a record inside a chunk with a CRC is the chunk's
    /// damage (readers then name the CRC and `recover`); without a CRC it stays a
    /// malformed record, the only thing known about it.
    #[test]
    fn core_a_broken_record_in_a_chunk_with_a_crc_is_its_damage() {
        let bytes = broken_topic_length(small_log(true));
        let s = scan(&bytes).expect("a damaged chunk is not a scan error");
        assert_eq!(s.damaged_chunks.len(), 1);
        let bytes = broken_topic_length(small_log(false));
        let e = scan(&bytes).expect_err("no CRC: a malformed record");
        assert!(e.to_string().contains("topic"), "{e}");
    }
}

#[cfg(test)]
mod tests {
    use super::LeftOut;

    /// Messages left out are told as the stretches of time they fall in: a kept
    /// message between two of them splits them (two damaged chunks far apart were one
    /// stretch from the first to the last, over everything kept between), one at the
    /// same time does not; none left out is None.
    #[test]
    fn core_left_out_messages_are_told_as_their_stretches() {
        assert_eq!(LeftOut::of(&[], &[1.0]), None);
        let kept = [0.0, 10.0, 20.0, 30.0, 40.0, 50.0];
        let one = LeftOut::of(&[12.0, 11.0, 25.0, 13.0], &kept).unwrap();
        assert_eq!(one.messages, 4);
        assert_eq!(one.spans_s, vec![(11.0, 13.0), (25.0, 25.0)]);
        assert_eq!(
            one.stretches(),
            "in 2 stretches, t = 11.000 … 13.000, 25.000 s"
        );
        let same = LeftOut::of(&[20.0, 21.0, 29.0], &kept).unwrap();
        assert_eq!(same.spans_s, vec![(20.0, 29.0)]);
        assert_eq!(same.stretches(), "at t = 20.000 … 29.000 s");
        let many = LeftOut::of(&[1.0, 11.0, 21.0, 31.0, 41.0], &kept).unwrap();
        assert_eq!(many.spans_s.len(), 5);
        assert!(
            many.stretches()
                .starts_with("in 5 stretches, t = 1.000, 11.000, 21.000 s and 2 more"),
            "{}",
            many.stretches()
        );
    }
}

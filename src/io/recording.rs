//! Recordings: telemetry, thermal-vacuum test data, the cases in `shared/cases`. Time
//! series of named channels, read from
//!
//! - CSV as `reference-mechanism.md` §4 defines it: a header row with `time_s` (seconds
//!   since t = 0 of the scenario) and one column per channel, then one row per sample;
//!   an empty cell is a missing sample; lines starting with `#` are comments;
//! - MCAP: the messages of one topic (`/recording` when there is one, else the only
//!   topic with numbers), protobuf decoded through the descriptor set its schema stores,
//!   or JSON; every numeric field is a channel, `time_s` (or else the log time) is the
//!   time; a JSON `null` is a missing sample, a field that is never a number (a note)
//!   is no channel, and text in a number's field is an error.
//!
//! Anything else (a non-numeric cell, NaN, time that does not increase, an empty file,
//! a row of the wrong length) is an error naming the file, line and column.

use std::path::Path;

pub use crate::recording::{
    DuplicateTimes, Recording, RecordingError, RecordingFormat, TIME_COLUMN, TimeFormat,
};

/// A time cell as seconds since t = 0: a number of seconds, or a UTC date-time
/// (`2016-02-04 00:01:00.0`, `2016-02-04T00:01:00Z`, RFC 3339 with an offset) less the
/// origin, plus `offset_s` (`[recording] time_offset_s`). `err` makes the error at the
/// cell.
fn time_of(
    cell: &str,
    format: &TimeFormat,
    offset_s: f64,
    column: &str,
    err: impl Fn(String) -> RecordingError,
) -> Result<f64, RecordingError> {
    if cell.is_empty() {
        return Err(err(format!("the time (`{column}`) is missing")));
    }
    match format {
        TimeFormat::Seconds => {
            let t: f64 = cell
                .parse()
                .map_err(|_| err(format!("`{cell}` in column `{column}` is not a number")))?;
            if !t.is_finite() {
                return Err(err(format!(
                    "`{cell}` in column `{column}` is not a finite number"
                )));
            }
            Ok(t + offset_s)
        }
        TimeFormat::Utc { origin } => {
            use sgp4::chrono::{DateTime, NaiveDateTime};
            let utc = DateTime::parse_from_rfc3339(cell)
                .map(|d| d.naive_utc())
                .or_else(|_| NaiveDateTime::parse_from_str(cell, "%Y-%m-%d %H:%M:%S%.f"))
                .or_else(|_| NaiveDateTime::parse_from_str(cell, "%Y-%m-%dT%H:%M:%S%.f"))
                .or_else(|_| NaiveDateTime::parse_from_str(cell.trim_end_matches('Z'), "%Y-%m-%dT%H:%M:%S%.f"))
                .map_err(|_| {
                    err(format!(
                        "`{cell}` in column `{column}` is not a UTC date-time (`2016-02-04 00:01:00`, or RFC 3339)"
                    ))
                })?;
            let ns = (utc - *origin).num_nanoseconds().ok_or_else(|| {
                err(format!(
                    "`{cell}` is centuries from the scenario's start_utc"
                ))
            })?;
            let t = ns as f64 / 1e9 + offset_s;
            if t < 0.0 {
                let shifted = crate::spec::scenario::time_offset_note(offset_s);
                return Err(err(format!(
                    "`{cell}` is before the scenario's start_utc ({}){shifted}: the run starts at the recording's first row or earlier",
                    origin.format("%Y-%m-%dT%H:%M:%SZ")
                )));
            }
            Ok(t)
        }
    }
}

impl Recording {
    /// Reads a CSV or MCAP recording (told apart by the MCAP magic bytes).
    pub fn read(path: &Path) -> Result<Recording, RecordingError> {
        Recording::read_with(path, &RecordingFormat::default())
    }

    /// Reads a recording laid out as `fmt` says (CSV; an MCAP recording is always
    /// `time_s` and its channels, its times shifted by `fmt.time_offset_s` too).
    pub fn read_with(path: &Path, fmt: &RecordingFormat) -> Result<Recording, RecordingError> {
        let file = path.display().to_string();
        let bytes = super::output::check_input(path)
            .and_then(|()| std::fs::read(path))
            .map_err(|source| RecordingError::Io {
                file: file.clone(),
                source,
            })?;
        if bytes.starts_with(mcap::MAGIC) {
            let mut rec = read_mcap(&bytes, &file)?;
            rec.time_s.iter_mut().for_each(|t| *t += fmt.time_offset_s);
            return Ok(rec);
        }
        let named_mcap = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("mcap"));
        // the first 4 kB must be text; a character cut by that limit is not an error
        let not_text = matches!(
            std::str::from_utf8(&bytes[..bytes.len().min(4096)]),
            Err(e) if e.error_len().is_some()
        );
        if named_mcap || not_text {
            // not text: say what it is not, rather than where the text breaks
            let bad = std::str::from_utf8(&bytes).err().map(|e| e.valid_up_to());
            return Err(RecordingError::File {
                file,
                message: match (named_mcap, bad) {
                    (true, _) => "is not an MCAP file (it does not start with the MCAP magic bytes); a recording is an MCAP or a CSV file".into(),
                    (false, Some(at)) => format!(
                        "is neither CSV text nor an MCAP file (byte {} is not UTF-8 text, and it does not start with the MCAP magic bytes)",
                        at + 1
                    ),
                    (false, None) => "is not CSV text".into(),
                },
            });
        }
        Recording::from_csv_with(&bytes, &file, fmt)
    }

    /// Parses CSV text in the layout of `reference-mechanism.md` §4; `file` names it in
    /// errors.
    pub fn from_csv(bytes: &[u8], file: &str) -> Result<Recording, RecordingError> {
        Recording::from_csv_with(bytes, file, &RecordingFormat::default())
    }

    /// Parses CSV text laid out as `fmt` says; `file` names it in errors. One pass over
    /// the rows checks each cell where it is read (header, column names, numbers,
    /// times increasing, repeated stamps and rows), so an error names its line and
    /// column: the header by [`CsvLayout::of`], a row's cells by [`read_cells`], its
    /// place among the rows by [`CsvRows::add`].
    pub fn from_csv_with(
        bytes: &[u8],
        file: &str,
        fmt: &RecordingFormat,
    ) -> Result<Recording, RecordingError> {
        // the file's text may hold anything: control characters are shown escaped
        let at = |line: u64, column: usize, message: String| RecordingError::At {
            file: file.to_string(),
            line,
            column,
            message: crate::units::shown(&message).into_owned(),
        };
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(bytes);
        let lines = LineIndex::of(bytes);
        let csv_error = |e: csv::Error| {
            let line = lines.line(e.position());
            match e.kind() {
                csv::ErrorKind::UnequalLengths {
                    expected_len, len, ..
                } => at(
                    line,
                    0,
                    format!("the row has {len} fields, the header {expected_len}"),
                ),
                csv::ErrorKind::Utf8 { .. } => at(line, 0, "not UTF-8 text".into()),
                _ => at(line, 0, e.to_string()),
            }
        };
        let header = reader.headers().map_err(&csv_error)?.clone();
        let header_line = lines.line(header.position()).max(1);
        if header.is_empty() || header.iter().all(str::is_empty) {
            return Err(RecordingError::File {
                file: file.into(),
                message: "is empty: a recording starts with a header row (`time_s,…`)".into(),
            });
        }
        let layout = CsvLayout::of(&header, fmt, &|column, m| at(header_line, column, m))?;
        let mut rows = CsvRows::new(file, layout.channels());
        let mut row = csv::StringRecord::new();
        let mut values: Vec<Option<f64>> = Vec::new();
        loop {
            match reader.read_record(&mut row) {
                Ok(false) => break,
                Ok(true) => {}
                Err(e) => return Err(csv_error(e)),
            }
            let line = lines.line(row.position());
            let cell_error = |column, m| at(line, column, m);
            let time_col = layout.time_col;
            let t = time_of(
                row.get(time_col).unwrap_or(""),
                &fmt.time,
                fmt.time_offset_s,
                &fmt.time_column,
                |m| cell_error(time_col + 1, m),
            )?;
            read_cells(&row, &layout, &mut values, &cell_error)?;
            rows.add(t, line, &row, &values, &layout, fmt, &cell_error)?;
        }
        rows.finish()
    }
}

/// Where each line of a text begins: the csv crate does not count blank lines. A line
/// ends at LF, CR LF or a lone CR (as the csv crate reads them).
struct LineIndex<'b> {
    bytes: &'b [u8],
    newlines: Vec<usize>,
}

impl<'b> LineIndex<'b> {
    fn of(bytes: &'b [u8]) -> LineIndex<'b> {
        let newlines = bytes
            .iter()
            .enumerate()
            .filter_map(|(i, &b)| {
                (b == b'\n' || (b == b'\r' && bytes.get(i + 1) != Some(&b'\n'))).then_some(i)
            })
            .collect();
        LineIndex { bytes, newlines }
    }

    /// The line a record at `p` is on (0 when there is no position).
    fn line(&self, p: Option<&csv::Position>) -> u64 {
        p.map_or(0, |p| {
            // a record's position is where its reading began, before blank lines
            let mut at = p.byte() as usize;
            while matches!(self.bytes.get(at), Some(b'\n' | b'\r')) {
                at += 1;
            }
            self.newlines.partition_point(|&i| i < at) as u64 + 1
        })
    }
}

/// An error at a column (1-based; 0: the whole line) of the line at hand.
type CellError<'e> = dyn Fn(usize, String) -> RecordingError + 'e;

/// A CSV recording's columns: their names, the time column and which are channels.
struct CsvLayout {
    names: Vec<String>,
    time_col: usize,
    channel: Vec<bool>,
}

impl CsvLayout {
    /// The layout of `header` (checked: named, unique, one column per delimiter, the
    /// time column and the ignored ones there) as `fmt` says; errors on the header line.
    fn of(
        header: &csv::StringRecord,
        fmt: &RecordingFormat,
        at: &CellError<'_>,
    ) -> Result<CsvLayout, RecordingError> {
        let names: Vec<String> = header.iter().map(str::to_string).collect();
        if names.len() == 1 {
            // one column: another delimiter?
            for (d, what) in [(';', "semicolons"), ('\t', "tabs"), ('|', "bars")] {
                if names[0].contains(d) {
                    return Err(at(
                        0,
                        format!(
                            "the header is one column that holds {what} ({}): the fields seem separated by {what}; a recording separates them by commas",
                            crate::units::shown(&names[0])
                        ),
                    ));
                }
            }
        }
        for (k, name) in names.iter().enumerate() {
            if name.is_empty() {
                return Err(at(k + 1, "a column has no name".into()));
            }
            if names[..k].contains(name) {
                return Err(at(
                    k + 1,
                    format!("column `{}` appears twice", crate::units::shown(name)),
                ));
            }
        }
        let time_name = fmt.time_column.as_str();
        let Some(time_col) = names.iter().position(|n| n == time_name) else {
            let joined = names.join(",");
            let header = crate::units::shown(&joined);
            return Err(at(
                0,
                if time_name == TIME_COLUMN {
                    format!(
                        "no `{TIME_COLUMN}` column (the header is {header}): a recording gives its time in seconds since t = 0 of the scenario (or name its time column in the scenario's [recording] time_column)",
                    )
                } else {
                    format!(
                        "no `{}` column, the time column the scenario's [recording] names (the header is {header})",
                        crate::units::shown(time_name),
                    )
                },
            ));
        };
        if let Some(missing) = fmt.ignore_columns.iter().find(|c| !names.contains(c)) {
            return Err(at(
                0,
                format!(
                    "no `{}` column, which the scenario's [recording] ignore_columns names",
                    crate::units::shown(missing)
                ),
            ));
        }
        let channel = (0..names.len())
            .map(|k| k != time_col && !fmt.ignore_columns.contains(&names[k]))
            .collect();
        Ok(CsvLayout {
            names,
            time_col,
            channel,
        })
    }

    /// The channels' names, in column order.
    fn channels(&self) -> Vec<String> {
        self.names
            .iter()
            .zip(&self.channel)
            .filter(|(_, c)| **c)
            .map(|(n, _)| n.clone())
            .collect()
    }
}

/// The channels' readings of `row` into `values` (an empty cell is no reading; a cell
/// that is not a finite number is an error at its column).
fn read_cells(
    row: &csv::StringRecord,
    layout: &CsvLayout,
    values: &mut Vec<Option<f64>>,
    at: &CellError<'_>,
) -> Result<(), RecordingError> {
    values.clear();
    for (k, cell) in row.iter().enumerate() {
        if !layout.channel[k] {
            continue;
        }
        let name = &layout.names[k];
        values.push(if cell.is_empty() {
            None
        } else {
            let v: f64 = cell.parse().map_err(|_| {
                at(
                    k + 1,
                    format!("`{cell}` in column `{name}` is not a number"),
                )
            })?;
            if !v.is_finite() {
                return Err(at(
                    k + 1,
                    format!(
                        "`{cell}` in column `{name}` is not a finite number (a missing sample is an empty cell)"
                    ),
                ));
            }
            Some(v)
        });
    }
    Ok(())
}

/// The recording as its rows are added: a row of a new time is a sample (or a fill
/// row, repeating the one before); a row of the same time is merged into it.
struct CsvRows {
    rec: Recording,
    /// The previous row's cells (time excluded).
    previous: Vec<String>,
    /// Per channel, how many readings its value averages (an empty cell is no reading).
    averaged: Vec<f64>,
}

impl CsvRows {
    fn new(file: &str, columns: Vec<String>) -> CsvRows {
        CsvRows {
            averaged: vec![0.0; columns.len()],
            rec: Recording {
                file: file.into(),
                values: vec![Vec::new(); columns.len()],
                columns,
                time_s: Vec::new(),
                rows_at: Vec::new(),
                fill_rows: Vec::new(),
                merged_rows: Vec::new(),
            },
            previous: Vec::new(),
        }
    }

    /// Adds `row` (on `line`, at time `t`, its channels' `values`): times must not
    /// decrease; a repeated stamp is refused, or merged (`duplicate_times = "mean"`);
    /// a row repeating the one before is a fill row when `fmt` says so.
    #[allow(clippy::too_many_arguments)]
    fn add(
        &mut self,
        t: f64,
        line: u64,
        row: &csv::StringRecord,
        values: &[Option<f64>],
        layout: &CsvLayout,
        fmt: &RecordingFormat,
        at: &CellError<'_>,
    ) -> Result<(), RecordingError> {
        let (time_col, rec) = (layout.time_col, &mut self.rec);
        let same_cells = row
            .iter()
            .enumerate()
            .filter(|&(k, _)| k != time_col)
            .map(|(_, c)| c)
            .eq(self.previous.iter().map(String::as_str));
        if let Some(&last) = rec.time_s.last() {
            let last_line = rec.rows_at.last().copied().unwrap_or(0);
            let not_increasing =
                || format!("time does not increase: {t} s after {last} s on line {last_line}");
            if t < last {
                return Err(at(time_col + 1, not_increasing()));
            }
            if t == last {
                if !same_cells && fmt.duplicate_times == DuplicateTimes::Refuse {
                    return Err(at(
                        time_col + 1,
                        if fmt.time == TimeFormat::Seconds && fmt.time_column == TIME_COLUMN {
                            not_increasing()
                        } else {
                            format!(
                                "the same time stamp as line {last_line} with other readings; if they are two readings within one stamp, set [recording] duplicate_times = \"mean\""
                            )
                        },
                    ));
                }
                if !same_cells {
                    mean_into(&mut rec.values, values, &mut self.averaged);
                    // the next row of the stamp is compared with this one
                    remember(&mut self.previous, row, time_col);
                }
                rec.merged_rows.push(line);
                return Ok(());
            }
        }
        let fill = fmt.repeated_rows_are_fill && !rec.time_s.is_empty() && same_cells;
        for (n, v) in self.averaged.iter_mut().zip(values) {
            *n = if v.is_some() && !fill { 1.0 } else { 0.0 };
        }
        if fill {
            rec.fill_rows.push(line);
        }
        for (ch, v) in rec.values.iter_mut().zip(values) {
            ch.push(if fill { None } else { *v });
        }
        rec.time_s.push(t);
        rec.rows_at.push(line);
        remember(&mut self.previous, row, time_col);
        Ok(())
    }

    /// The recording, which must hold a sample.
    fn finish(self) -> Result<Recording, RecordingError> {
        if self.rec.time_s.is_empty() {
            return Err(RecordingError::File {
                file: self.rec.file,
                message: "has a header but no samples".into(),
            });
        }
        Ok(self.rec)
    }
}

/// A message's JSON object (each key once), or why it is not one.
fn json_object(data: &[u8]) -> Result<UniqueObject, String> {
    serde_json::from_slice(data).map_err(|e| {
        if e.is_data() {
            e.to_string()
        } else {
            format!("is not JSON: {e}")
        }
    })
}

/// A JSON object read with each key once: a key given twice is an error (as a CSV
/// header given twice is), not the last value silently kept.
struct UniqueObject(Vec<(String, serde_json::Value)>);

impl<'de> serde::Deserialize<'de> for UniqueObject {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = UniqueObject;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a JSON object")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<UniqueObject, A::Error> {
                // keys in sorted order, as serde_json's own map gives them
                let mut fields = std::collections::BTreeMap::new();
                while let Some((k, v)) = map.next_entry::<String, serde_json::Value>()? {
                    if fields.contains_key(&k) {
                        return Err(serde::de::Error::custom(format!(
                            "field `{}` is given twice",
                            crate::units::shown(&k)
                        )));
                    }
                    fields.insert(k, v);
                }
                Ok(UniqueObject(fields.into_iter().collect()))
            }
        }
        d.deserialize_map(Visit)
    }
}

/// Every length of an MCAP file checked before the mcap crate's parser allocates what
/// a length says (`io::mcap_lengths`).
fn check_lengths(bytes: &[u8], file: &str) -> Result<(), RecordingError> {
    let magic = super::mcap_scan::MAGIC;
    if !bytes.starts_with(magic) {
        return Ok(());
    }
    super::mcap_lengths::check_file(bytes, magic.len()).map_err(|(offset, m)| RecordingError::File {
        file: file.to_string(),
        message: format!(
            "is not a readable MCAP file (damaged or cut off): the record at byte {offset} is malformed: {m} (a file cut off by a killed run is recovered by `orbitlash recover`)"
        ),
    })
}

/// Keeps a row's cells (the time's excepted) for comparing the next row with it.
fn remember(previous: &mut Vec<String>, row: &csv::StringRecord, time_col: usize) {
    previous.clear();
    previous.extend(
        row.iter()
            .enumerate()
            .filter(|&(k, _)| k != time_col)
            .map(|(_, c)| c.to_string()),
    );
}

/// The readings `values` of a row sharing the last row's time stamp, averaged into that
/// row cell by cell; `averaged` counts each channel's readings so far (an empty cell is
/// no reading).
fn mean_into(rows: &mut [Vec<Option<f64>>], values: &[Option<f64>], averaged: &mut [f64]) {
    for ((ch, v), n) in rows.iter_mut().zip(values).zip(averaged) {
        let old = ch.last_mut().expect("a row before");
        if let Some(b) = v {
            *old = Some(old.map_or(*b, |a| (a * *n + b) / (*n + 1.0)));
            *n += 1.0;
        }
    }
}

/// The topic a recording is read from when an MCAP file has several.
pub const RECORDING_TOPIC: &str = "/recording";

/// A recording from an MCAP file: the messages of its recording topic
/// ([`recording_channel`]) decoded as JSON ([`json_fields`]) or protobuf (through the
/// stored schema) into channels at times ([`add_sample`]), each checked where it is
/// read (schema, encoding, fields, times increasing), so that an error names its
/// message.
fn read_mcap(bytes: &[u8], file: &str) -> Result<Recording, RecordingError> {
    use super::mcap_read::{flatten_message, message_type};
    let fail = |message: String| RecordingError::File {
        file: file.to_string(),
        message,
    };
    check_lengths(bytes, file)?;
    // The mcap crate's reader: any chunk compression, a whole file.
    let mut messages = Vec::new();
    for m in mcap::MessageStream::new(bytes)
        .map_err(|e| fail(format!("is not a readable MCAP file: {e}")))?
    {
        messages.push(m.map_err(|e| {
            fail(format!(
                "is not a readable MCAP file: {e} (a file cut off by a killed run is recovered by `orbitlash recover`)"
            ))
        })?);
    }
    let channel_id = recording_channel(&messages).map_err(fail)?;
    let mut rec = Recording {
        file: file.into(),
        columns: Vec::new(),
        time_s: Vec::new(),
        values: Vec::new(),
        rows_at: Vec::new(),
        fill_rows: Vec::new(),
        merged_rows: Vec::new(),
    };
    let mut descriptor = None;
    let mut flat: Vec<(String, Option<f64>)> = Vec::new();
    let mut numbers = Vec::new();
    let mut time_base: Option<bool> = None;
    let mut text_fields = std::collections::BTreeSet::new();
    let mut n = 0u64;
    for m in messages.iter().filter(|m| m.channel.id == channel_id) {
        n += 1;
        let ch = &m.channel;
        let where_ = |message: String| {
            fail(format!(
                "topic {}, message {n} (log time {} s): {message}",
                ch.topic,
                m.log_time as f64 * 1e-9
            ))
        };
        flat.clear();
        if ch.message_encoding == "protobuf" {
            if descriptor.is_none() {
                let schema = ch.schema.as_ref().expect("a protobuf topic has a schema");
                descriptor = Some(message_type(&schema.data, &schema.name).map_err(&where_)?);
            }
            numbers.clear();
            flatten_message(descriptor.as_ref().expect("set"), &m.data, "", &mut numbers)
                .map_err(|e| where_(format!("does not decode with its schema: {e}")))?;
            flat.extend(
                numbers
                    .drain(..)
                    .map(|(k, v)| (k.trim_start_matches('.').to_string(), Some(v))),
            );
        } else {
            json_fields(&m.data, &rec.columns, &mut text_fields, &mut flat).map_err(where_)?;
        }
        let mut time = None;
        for (name, v) in &flat {
            if v.is_some_and(|x| !x.is_finite()) {
                return Err(where_(format!("field `{name}` is not a finite number")));
            }
            if name == TIME_COLUMN {
                time = Some(v.ok_or_else(|| where_(format!("`{TIME_COLUMN}` is missing")))?);
            }
        }
        // One time base for the whole recording: `time_s` in every message, or in none
        // (then the log time).
        let own_time = time.is_some();
        if *time_base.get_or_insert(own_time) != own_time {
            return Err(where_(format!(
                "`{TIME_COLUMN}` is in some messages and not in others: one time base per recording"
            )));
        }
        let t = time.unwrap_or(m.log_time as f64 / 1e9);
        add_sample(&mut rec, n, t, &mut flat).map_err(where_)?;
    }
    Ok(rec)
}

/// The channel a recording is read from: the topic `/recording`, or the one topic
/// that can hold series (JSON, or protobuf other than foxglove's own types).
fn recording_channel(messages: &[mcap::Message<'_>]) -> Result<u16, String> {
    let mut topics: Vec<(&str, u16)> = Vec::new();
    for m in messages {
        let ch = &m.channel;
        let series = ch.message_encoding == "json"
            || (ch.message_encoding == "protobuf"
                && ch
                    .schema
                    .as_ref()
                    .is_some_and(|s| !s.name.starts_with("foxglove.")));
        if series && !topics.iter().any(|&(_, id)| id == ch.id) {
            topics.push((ch.topic.as_str(), ch.id));
        }
    }
    topics.sort();
    match topics.iter().find(|(t, _)| *t == RECORDING_TOPIC) {
        Some(&(_, id)) => Ok(id),
        None if topics.len() == 1 => Ok(topics[0].1),
        None if topics.is_empty() => {
            Err("has no topic with numeric series (protobuf or JSON messages)".into())
        }
        None => {
            let names: Vec<&str> = topics.iter().map(|(t, _)| *t).collect();
            Err(format!(
                "has several topics ({}); a recording is read from the topic `{RECORDING_TOPIC}`",
                names.join(", ")
            ))
        }
    }
}

/// A JSON message's fields into `flat` (number or null). A field that is never a
/// number (a note, a label) is not a channel and is remembered in `text_fields`; one
/// that is a number elsewhere (a known column, the time) is a bad cell.
fn json_fields(
    data: &[u8],
    columns: &[String],
    text_fields: &mut std::collections::BTreeSet<String>,
    flat: &mut Vec<(String, Option<f64>)>,
) -> Result<(), String> {
    let UniqueObject(fields) = json_object(data)?;
    for (k, v) in fields {
        match v {
            serde_json::Value::Number(_) if text_fields.contains(&k) => {
                return Err(format!(
                    "field `{k}` is a number here and text in earlier messages"
                ));
            }
            serde_json::Value::Number(x) => flat.push((k, x.as_f64())),
            serde_json::Value::Null => flat.push((k, None)),
            other => {
                if k == TIME_COLUMN || columns.contains(&k) {
                    return Err(format!("field `{k}` is not a number or null: {other}"));
                }
                text_fields.insert(k);
            }
        }
    }
    Ok(())
}

/// Message `n`'s fields `flat` (emptied) as the sample at `t`, after the ones before
/// (times increase); a field not seen before is a new channel, empty until now.
fn add_sample(
    rec: &mut Recording,
    n: u64,
    t: f64,
    flat: &mut Vec<(String, Option<f64>)>,
) -> Result<(), String> {
    if let Some(&last) = rec.time_s.last()
        && t <= last
    {
        return Err(format!("time does not increase: {t} s after {last} s"));
    }
    let row = rec.time_s.len();
    rec.time_s.push(t);
    rec.rows_at.push(n);
    for (name, v) in flat.drain(..) {
        if name == TIME_COLUMN {
            continue;
        }
        let k = match rec.columns.iter().position(|c| *c == name) {
            Some(k) => k,
            None => {
                rec.columns.push(name);
                rec.values.push(vec![None; row]);
                rec.columns.len() - 1
            }
        };
        rec.values[k].push(v);
    }
    for column in &mut rec.values {
        column.resize(row + 1, None);
    }
    Ok(())
}

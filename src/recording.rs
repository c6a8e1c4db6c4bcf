//! A recording as the library sees it: named channels sampled at times, with where
//! each row came from (for messages). Reading files into one is `io::recording`'s job;
//! `diagnose` and the sensors work on this type only.

use crate::spec::scenario::Sensor;

/// A recording: `values[k][j]` is channel `columns[k]` at `time_s[j]` (None: missing).
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The file it was read from, for messages.
    pub file: String,
    pub columns: Vec<String>,
    pub time_s: Vec<f64>,
    pub values: Vec<Vec<Option<f64>>>,
    /// Where each row is in the file: its line (CSV) or message number (MCAP), 1-based.
    pub rows_at: Vec<u64>,
    /// Lines whose cells repeat the previous row's, dropped as a ground segment's fill
    /// (their rows are kept, every cell missing).
    pub fill_rows: Vec<u64>,
    /// Lines merged into the row before them (the same time stamp).
    pub merged_rows: Vec<u64>,
}

#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    #[error("cannot read {file}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// At a line and column of a CSV file (both 1-based; column 0: the whole line).
    #[error("{file}:{line}{}: {message}", if *column > 0 { format!(":{column}") } else { String::new() })]
    At {
        file: String,
        line: u64,
        column: usize,
        message: String,
    },
    #[error("{file}: {message}")]
    File { file: String, message: String },
}

/// The column every recording gives its time in.
pub const TIME_COLUMN: &str = "time_s";

impl Recording {
    /// The values of channel `name`.
    pub fn channel(&self, name: &str) -> Option<&[Option<f64>]> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(&self.values[k])
    }

    /// Renames the columns the scenario's sensors read to those sensors' channel names
    /// (telemetry's `Black Chassis deg. C` becomes the sensor's `chassis_black_c`).
    pub fn name_channels(&mut self, sensors: &[Sensor]) {
        for c in &mut self.columns {
            if let Some(s) = sensors.iter().find(|s| s.source_column == *c) {
                c.clone_from(&s.column);
            }
        }
    }

    /// For each channel, the index of the sensor of that column: every channel must be
    /// a sensor of the scenario.
    pub fn match_sensors(&self, sensors: &[Sensor]) -> Result<Vec<usize>, RecordingError> {
        self.columns
            .iter()
            .map(|c| {
                sensors.iter().position(|s| &s.column == c).ok_or_else(|| {
                    let known: Vec<&str> = sensors.iter().map(|s| s.column.as_str()).collect();
                    RecordingError::File {
                        file: self.file.clone(),
                        message: format!(
                            "channel `{c}` is not a sensor of the scenario ({known}); add a [[sensor]] with column = \"{c}\", or list it in [recording] ignore_columns",
                            c = crate::units::shown(c),
                            known = if known.is_empty() {
                                "it has none".to_string()
                            } else {
                                format!("its sensors: {}", known.join(", "))
                            }
                        ),
                    }
                })
            })
            .collect()
    }
}

/// How a scenario's recordings are laid out (`[recording]`): which column holds the
/// time and how, which columns are not channels, and what repeated rows and repeated
/// time stamps mean. The default is the layout of `reference-mechanism.md` §4.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingFormat {
    /// The time column's name.
    pub time_column: String,
    pub time: TimeFormat,
    /// Columns that are neither the time nor a sensor (read, kept out of the channels).
    pub ignore_columns: Vec<String>,
    /// Rows whose cells all repeat the previous row's are a ground segment's fill, not
    /// measurements: their cells are dropped (reported in [`Recording::fill_rows`]).
    pub repeated_rows_are_fill: bool,
    pub duplicate_times: DuplicateTimes,
}

/// How a recording gives its time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeFormat {
    /// Seconds since t = 0 of the scenario.
    Seconds,
    /// UTC date-times (`2016-02-04 00:01:00.0`, or RFC 3339), counted from `origin`
    /// (the scenario's `start_utc`).
    Utc { origin: sgp4::chrono::NaiveDateTime },
}

/// What two rows with the same time stamp mean when their cells differ (equal rows are
/// always merged).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DuplicateTimes {
    /// An error naming both lines.
    Refuse,
    /// Two readings within one time stamp: their mean.
    Mean,
}

impl DuplicateTimes {
    pub const NAMES: [&'static str; 2] = ["refuse", "mean"];
}

impl Default for RecordingFormat {
    fn default() -> Self {
        RecordingFormat {
            time_column: TIME_COLUMN.to_string(),
            time: TimeFormat::Seconds,
            ignore_columns: Vec::new(),
            repeated_rows_are_fill: false,
            duplicate_times: DuplicateTimes::Refuse,
        }
    }
}

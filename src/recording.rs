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
                            "channel `{c}` is not a sensor of the scenario ({known}); add a [[sensor]] with column = \"{c}\"",
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

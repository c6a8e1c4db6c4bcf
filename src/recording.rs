//! A recording as the library sees it: named channels sampled at times, with where
//! each row came from (for messages). Reading files into one is `io::recording`'s job;
//! `diagnose` and the sensors work on this type only.

use crate::spec::model::Model;
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

impl Recording {
    /// The values of channel `name`.
    pub fn channel(&self, name: &str) -> Option<&[Option<f64>]> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(&self.values[k])
    }

    /// Takes each of `model`'s `[[input]]` channels out of the recording (an input, not
    /// a measurement to fit) and makes the model follow its readings
    /// ([`Model::follow_input`]). Returns what it did, a line per input.
    pub fn feed_inputs(
        &mut self,
        model: &mut Model,
    ) -> Result<Vec<String>, crate::spec::model::InputError> {
        use crate::spec::model::InputError;
        let mut done = Vec::new();
        for (i, inp) in model.spec().input.clone().iter().enumerate() {
            let Some(k) = self.columns.iter().position(|c| *c == inp.column) else {
                return Err(InputError::NoColumn {
                    file: self.file.clone(),
                    column: inp.column.clone(),
                    drives: inp.drives.clone(),
                });
            };
            let readings: Vec<(f64, f64)> = self
                .time_s
                .iter()
                .zip(&self.values[k])
                .filter_map(|(t, v)| v.map(|v| (*t, v)))
                .collect();
            if readings.is_empty() {
                return Err(InputError::NoReadings {
                    file: self.file.clone(),
                    column: inp.column.clone(),
                });
            }
            done.push(model.follow_input(i, &readings)?);
            self.columns.remove(k);
            self.values.remove(k);
        }
        Ok(done)
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

pub use crate::spec::scenario::{DuplicateTimes, RecordingFormat, TIME_COLUMN, TimeFormat};

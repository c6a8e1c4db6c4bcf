//! A recording as the library sees it: named channels sampled at times, with where
//! each row came from (for messages). Reading files into one is `io::recording`'s job;
//! `diagnose` and the sensors work on this type only.

use crate::orbit::EnvironmentModel;
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
            let (readings, lines): (Vec<(f64, f64)>, Vec<u64>) = self
                .time_s
                .iter()
                .zip(&self.values[k])
                .zip(&self.rows_at)
                .filter_map(|((t, v), line)| v.map(|v| ((*t, v), *line)))
                .unzip();
            if readings.is_empty() {
                return Err(InputError::NoReadings {
                    file: self.file.clone(),
                    column: inp.column.clone(),
                });
            }
            let placed = |e: InputError| match e.reading_index() {
                Some(j) if j < readings.len() => InputError::AtReading {
                    file: self.file.clone(),
                    line: lines[j],
                    column: inp.column.clone(),
                    reading: readings[j].1,
                    refused: Box::new(e),
                },
                _ => e,
            };
            done.push(model.follow_input(i, &readings).map_err(placed)?);
            self.remove_channel(&inp.column);
        }
        Ok(done)
    }

    /// Takes channel `name` out of the recording; whether it was there.
    pub fn remove_channel(&mut self, name: &str) -> bool {
        let Some(k) = self.columns.iter().position(|c| c == name) else {
            return false;
        };
        self.columns.remove(k);
        self.values.remove(k);
        true
    }

    /// The recording's eclipses (rows of channel `column` reading below `below`)
    /// against `env`'s shadow: the share of rows that agree, and each entry and exit
    /// (the middle of the two rows around a change of state, where they are at most
    /// 1.5 of the usual row interval apart, the state held a row either side) less the
    /// nearest predicted crossing of the same kind within a quarter orbit.
    pub fn eclipse_check(
        &self,
        column: &str,
        below: f64,
        env: &impl EnvironmentModel,
    ) -> Result<EclipseCheck, RecordingError> {
        let values = self.channel(column).ok_or_else(|| RecordingError::File {
            file: self.file.clone(),
            message: format!(
                "no `{column}` column, which the scenario's [recording] eclipse_column names"
            ),
        })?;
        let rows: Vec<(f64, bool)> = self
            .time_s
            .iter()
            .zip(values)
            .filter_map(|(&t, v)| v.map(|v| (t, v < below)))
            .collect();
        let agree = rows
            .iter()
            .filter(|&&(t, dark)| (env.sun_fraction(t) < 0.5) == dark)
            .count();
        let mut gaps: Vec<f64> = rows.windows(2).map(|w| w[1].0 - w[0].0).collect();
        gaps.sort_by(f64::total_cmp);
        let usual = gaps.get(gaps.len() / 2).copied().unwrap_or(0.0);
        let period = env.mean_period_s();
        let crossings = match (rows.first(), rows.last()) {
            (Some(&(first, _)), Some(&(last, _))) => {
                let window = 0.25 * period;
                shadow_crossings(env, first - window, last + window)
            }
            _ => Vec::new(),
        };
        let (mut entries_s, mut exits_s) = (Vec::new(), Vec::new());
        for k in 0..rows.len().saturating_sub(1) {
            let ((t0, d0), (t1, dark)) = (rows[k], rows[k + 1]);
            // a change of state held a row either side, between rows the usual
            // interval apart (a flicker or a gap is no edge)
            let held =
                k >= 1 && rows[k - 1].1 == d0 && rows.get(k + 2).is_some_and(|r| r.1 == dark);
            if d0 == dark || t1 - t0 > 1.5 * usual || !held {
                continue;
            }
            let middle = 0.5 * (t0 + t1);
            // within a quarter orbit: an edge the model has no eclipse near is no
            // measure of the clock
            let nearest = crossings
                .iter()
                .filter(|c| c.1 == dark && (c.0 - middle).abs() <= 0.25 * period)
                .map(|c| c.0)
                .min_by(|a, b| (a - middle).abs().total_cmp(&(b - middle).abs()));
            if let Some(tc) = nearest {
                if dark {
                    entries_s.push(middle - tc);
                } else {
                    exits_s.push(middle - tc);
                }
            }
        }
        Ok(EclipseCheck {
            column: column.to_string(),
            below,
            rows: rows.len(),
            agreement: if rows.is_empty() {
                0.0
            } else {
                agree as f64 / rows.len() as f64
            },
            row_interval_s: usual,
            entries_s,
            exits_s,
        })
    }

    /// The check of [`Recording::eclipse_check`] on the column `model`'s `[recording]
    /// eclipse_column` names, against the model's own shadow (None without one); the
    /// column then leaves the recording (it is no sensor), unless an `[[input]]` reads
    /// it. Call it before [`Recording::feed_inputs`], which may make the shadow follow
    /// that very column.
    pub fn take_eclipse_check(
        &mut self,
        model: &Model,
    ) -> Result<Option<EclipseCheck>, RecordingError> {
        let Some(e) = &model.scenario().recording.eclipse else {
            return Ok(None);
        };
        let check =
            self.eclipse_check(&e.column, e.below, &model.scenario().thermal.environment)?;
        if !model.spec().input.iter().any(|i| i.column == e.column) {
            self.remove_channel(&e.column);
        }
        Ok(Some(check))
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

pub use crate::spec::scenario::{
    DuplicateTimes, EclipseColumn, RecordingFormat, TIME_COLUMN, TimeFormat,
};

/// A recording's eclipses against the orbit's ([`Recording::eclipse_check`]): how far
/// its clock is from the model's.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EclipseCheck {
    pub column: String,
    pub below: f64,
    /// Rows with a reading of `column`.
    pub rows: usize,
    /// The share of those rows the orbit's shadow puts in the same state.
    pub agreement: f64,
    /// The usual interval between those rows (their median), s: each edge is known to
    /// about this.
    pub row_interval_s: f64,
    /// Each entry into eclipse in the recording less the predicted one, s.
    pub entries_s: Vec<f64>,
    /// Each exit in the recording less the predicted one, s.
    pub exits_s: Vec<f64>,
}

/// Every crossing of `env`'s shadow from `from_s` to `until_s`: (time, entering).
fn shadow_crossings(env: &impl EnvironmentModel, from_s: f64, until_s: f64) -> Vec<(f64, bool)> {
    let mut out = Vec::new();
    let mut t = from_s;
    while let Some((tc, entering)) = env.next_shadow_crossing(t, until_s) {
        out.push((tc, entering));
        // on past it (a microsecond is above the float spacing of any run's time)
        let next = tc + 1e-6;
        if next <= t {
            break;
        }
        t = next;
    }
    out
}

impl EclipseCheck {
    fn mean(v: &[f64]) -> Option<f64> {
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    }

    pub fn mean_entry_s(&self) -> Option<f64> {
        Self::mean(&self.entries_s)
    }

    pub fn mean_exit_s(&self) -> Option<f64> {
        Self::mean(&self.exits_s)
    }

    /// The clock's offset the edges show, s (recorded − predicted, entries and exits
    /// together), when they tell one: at least two entries and two exits, each kind off
    /// by 10 s or more the same way (a shadow of the wrong size moves them apart), the
    /// mean beyond three of its standard errors (an edge between rows `row_interval_s`
    /// apart is uniform over that interval), and the rows' states agreeing with the
    /// shadow on 90 % or more. The recording's stamps then want that much less of
    /// `[recording] time_offset_s`.
    pub fn clock_offset_s(&self) -> Option<f64> {
        let (entry, exit) = (self.mean_entry_s()?, self.mean_exit_s()?);
        let all: Vec<f64> = self
            .entries_s
            .iter()
            .chain(&self.exits_s)
            .copied()
            .collect();
        let m = Self::mean(&all)?;
        let standard_error = self.row_interval_s / (12.0 * all.len() as f64).sqrt();
        (self.entries_s.len() >= 2
            && self.exits_s.len() >= 2
            && entry.signum() == exit.signum()
            && entry.abs() >= 10.0
            && exit.abs() >= 10.0
            && m.abs() >= 3.0 * standard_error
            && self.agreement >= AGREEMENT)
            .then_some(m)
    }

    /// Whether the rows' states agree with the orbit's shadow on less than 90 %: the
    /// clock, the orbit or the threshold is off by more than the edges can say (a clock
    /// minutes off, or a day: the edges then meet other crossings, or none).
    pub fn disagrees(&self) -> bool {
        self.rows > 0 && self.agreement < AGREEMENT
    }
}

/// The share of rows whose state must agree with the orbit's shadow for the edges to
/// tell the clock's offset.
const AGREEMENT: f64 = 0.9;

//! The recording as the fit sees it: channels matched to the model's sensors, the
//! training and held-out orbits, each channel's noise, orbit phases, and where a
//! residual sits (mismatches).

use serde::Serialize;

use crate::orbit::EnvironmentModel;
use crate::recording::Recording;
use crate::spec::scenario::Scenario;

use super::DiagnoseError;

/// Which part of the recording a sample belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    Train,
    Holdout,
    /// After the last whole orbit: used by neither the fit nor the held-out check.
    Tail,
}

/// The recording's orbits and how they are split.
#[derive(Debug, Clone, Serialize)]
pub struct Split {
    pub period_s: f64,
    /// Whole orbits the recording covers (from t = 0).
    pub orbits: usize,
    /// The recording's first orbit, counted from 0 at the scenario's t = 0 (as
    /// `baseline.orbit_rmse` is): the one its first sample is in, or the next when the
    /// recording holds less than half of that one (the lead-in is fitted with it). The
    /// orbits before it hold no data (the model runs through them as it runs up to any
    /// recording's start).
    pub first_orbit: usize,
    /// The recording's first sample, s from the scenario's t = 0.
    pub start_s: f64,
    /// The training orbits end here (an orbit count from t = 0, as `orbits`).
    pub train_orbits: usize,
    pub holdout_orbits: usize,
    pub train_end_s: f64,
    pub holdout_end_s: f64,
    /// How far before the last whole orbit's end the recording stops (0 when it
    /// reaches it): an orbit short by less than `slack_s` still counts as whole.
    #[serde(skip)]
    pub last_orbit_short_s: f64,
}

impl Split {
    /// The last `holdout` of the whole orbits are held out; `None`: a third of the
    /// orbits that hold data (at least one). Fewer than two orbits with data: nothing
    /// can be held out (`holdout_orbits` 0, everything is training).
    /// `t_first_s`, `t_last_s`: the recording's first and last sample times.
    /// `slack_s`: an orbit counts as whole when the recording ends within this of its
    /// end (one sampling interval).
    pub fn new(
        period_s: f64,
        t_first_s: f64,
        t_last_s: f64,
        slack_s: f64,
        holdout: Option<usize>,
    ) -> Result<Split, String> {
        let orbits = ((t_last_s + slack_s.max(1e-6 * period_s)) / period_s).floor() as usize;
        let last_orbit_short_s = (orbits as f64 * period_s - t_last_s).max(0.0);
        // the orbit the first sample is in, or the next when it holds less than half
        // of that one (a few samples before a boundary are a lead-in, not an orbit)
        let t0 = t_first_s.max(0.0) / period_s;
        let first_orbit = ((t0 + 0.5).floor() as usize).min(orbits);
        let recorded = orbits - first_orbit;
        if recorded < 2 {
            return Ok(Split {
                period_s,
                orbits,
                first_orbit,
                start_s: t_first_s,
                train_orbits: orbits,
                holdout_orbits: 0,
                train_end_s: f64::INFINITY,
                holdout_end_s: f64::INFINITY,
                last_orbit_short_s,
            });
        }
        let h = holdout.unwrap_or((recorded / 3).max(1));
        if h == 0 || h >= recorded {
            let from = if first_orbit > 0 {
                format!(" (orbits {}–{orbits} of the scenario)", first_orbit + 1)
            } else {
                String::new()
            };
            return Err(format!(
                "--holdout-orbits {h}: the recording has {recorded} whole orbits{from}; hold out \
                 at least 1 and leave at least 1 to fit"
            ));
        }
        let train = orbits - h;
        Ok(Split {
            period_s,
            orbits,
            first_orbit,
            start_s: t_first_s,
            train_orbits: train,
            holdout_orbits: h,
            train_end_s: train as f64 * period_s,
            holdout_end_s: orbits as f64 * period_s,
            last_orbit_short_s,
        })
    }

    /// Orbits with data before the held-out ones (`train_orbits` counts from t = 0).
    pub fn fitted_orbits(&self) -> usize {
        self.train_orbits.saturating_sub(self.first_orbit)
    }

    /// Whole orbits with data (the recording's, not the scenario's from t = 0).
    pub fn recorded_orbits(&self) -> usize {
        self.orbits - self.first_orbit
    }

    /// The fitted orbits as the report names them, numbered from 1 at the scenario's
    /// t = 0 ("orbits 3–8"; "orbit 3").
    pub fn fitted_span(&self) -> String {
        orbit_span(self.first_orbit + 1, self.train_orbits)
    }

    /// The held-out orbits as the report names them ("orbits 9–12").
    pub fn held_span(&self) -> String {
        orbit_span(self.train_orbits + 1, self.orbits)
    }

    pub fn part(&self, t_s: f64) -> Part {
        if t_s < self.train_end_s {
            Part::Train
        } else if t_s <= self.holdout_end_s {
            Part::Holdout
        } else {
            Part::Tail
        }
    }

    pub fn can_validate(&self) -> bool {
        self.holdout_orbits > 0
    }
}

/// "orbit a" or "orbits a–b".
fn orbit_span(a: usize, b: usize) -> String {
    if a == b {
        format!("orbit {a}")
    } else {
        format!("orbits {a}–{b}")
    }
}

/// Orbit phases a residual is folded by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    Sunlit,
    Eclipse,
    EclipseEntry,
    EclipseExit,
}

impl Phase {
    pub const ALL: [Phase; 4] = [
        Phase::Sunlit,
        Phase::EclipseEntry,
        Phase::Eclipse,
        Phase::EclipseExit,
    ];

    pub fn as_str(self) -> &'static str {
        match self {
            Phase::Sunlit => "sunlit",
            Phase::Eclipse => "eclipse",
            Phase::EclipseEntry => "eclipse_entry",
            Phase::EclipseExit => "eclipse_exit",
        }
    }
}

/// A channel of the recording and the model's sensor that reads it.
#[derive(Debug, Clone)]
pub struct Channel {
    pub name: String,
    /// Index into the scenario's sensors.
    pub sensor: usize,
    /// `K` for temperatures (residuals of °C and K columns are kelvin), `um` for backlash.
    pub unit: &'static str,
    /// The unit of the channel's values as recorded: `°C`, `K` or `µm`.
    pub value_unit: &'static str,
    pub is_temperature: bool,
}

/// The recording aligned to the model.
#[derive(Debug, Clone)]
pub struct Observations {
    pub file: String,
    pub channels: Vec<Channel>,
    pub time_s: Vec<f64>,
    /// Per channel, per time.
    pub values: Vec<Vec<Option<f64>>>,
    pub split: Split,
    /// Per time: its part and orbit phase.
    pub part: Vec<Part>,
    pub phase: Vec<Phase>,
    /// Per time: the orbit it falls in (0-based).
    pub orbit: Vec<usize>,
    /// Eclipse windows (entry, exit) over the recording.
    pub eclipses: Vec<(f64, f64)>,
    /// Channels too thinly sampled in the held-out orbits to check a fit on them.
    pub short_holdout: Vec<ShortHoldout>,
}

/// Width of the eclipse-entry and eclipse-exit windows, as a fraction of the orbit.
pub const TRANSITION_FRACTION: f64 = 0.1;

/// One sampling interval with slack: 1.5 × the median step of `time_s` (0 for fewer
/// than two rows). An orbit counts as whole when the recording ends within it of the
/// orbit's end, and a spike's neighbours must lie within it.
fn near_s(time_s: &[f64]) -> f64 {
    let mut gaps: Vec<f64> = time_s.windows(2).map(|w| w[1] - w[0]).collect();
    if gaps.is_empty() {
        0.0
    } else {
        1.5 * median(&mut gaps)
    }
}

/// How many typical steps a reading must stand off both its neighbours to be an
/// isolated spike ([`Observations::drop_spikes`]).
pub const SPIKE_SIGMAS: f64 = 20.0;

/// A reading left out as an isolated spike: its channel (index), row, value (the
/// recording's unit) and the two readings it was judged against, in time order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spike {
    pub channel: usize,
    pub row: usize,
    pub reading: f64,
    pub neighbours: (f64, f64),
    /// Where those two are.
    pub around: Around,
}

/// Where the two readings a spike was judged against are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Around {
    /// One before and one after it.
    Both,
    /// The two before it (the last reading, or one before an empty cell or a gap).
    Before,
    /// The two after it (the first reading, or one after an empty cell or a gap).
    After,
}

impl Observations {
    pub fn new(
        rec: &Recording,
        sc: &Scenario,
        holdout: Option<usize>,
    ) -> Result<Observations, DiagnoseError> {
        let sensor_of = rec
            .match_sensors(&sc.sensors)
            .map_err(|e| DiagnoseError::Recording(e.to_string()))?;
        if rec.time_s.is_empty() {
            return Err(DiagnoseError::Recording(format!(
                "{}: the recording has no rows",
                rec.file
            )));
        }
        if rec.time_s[0] < 0.0 {
            let shifted = crate::spec::scenario::time_offset_note(sc.recording.time_offset_s);
            return Err(DiagnoseError::Recording(format!(
                "{}: time_s starts at {} s{shifted}; recordings are timed from the scenario's t = 0",
                rec.file, rec.time_s[0]
            )));
        }
        let channels: Vec<Channel> = rec
            .columns
            .iter()
            .zip(&sensor_of)
            .map(|(name, &k)| {
                let temp = matches!(
                    sc.sensors[k].target,
                    crate::run::sensor::SensorTarget::Node(_)
                );
                Channel {
                    name: name.clone(),
                    sensor: k,
                    unit: if temp { "K" } else { "um" },
                    value_unit: match sc.sensors[k].unit() {
                        crate::run::sensor::ColumnUnit::Celsius => "°C",
                        crate::run::sensor::ColumnUnit::Kelvin => "K",
                        crate::run::sensor::ColumnUnit::Micrometre => "µm",
                    },
                    is_temperature: temp,
                }
            })
            .collect();
        if channels.is_empty() {
            return Err(DiagnoseError::Recording(format!(
                "{}: no column besides the time is a sensor of the scenario (its sensors: {}): there is nothing to compare",
                rec.file,
                sc.sensors
                    .iter()
                    .map(|s| s.column.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        if rec.values.iter().all(|v| v.iter().all(|x| x.is_none())) {
            return Err(DiagnoseError::Recording(format!(
                "{}: every cell of every sensor's column is empty: there is nothing to compare",
                rec.file
            )));
        }
        for (c, v) in channels.iter().zip(&rec.values) {
            if v.iter().all(|x| x.is_none()) {
                return Err(DiagnoseError::Recording(format!(
                    "{}: channel `{}` has no values (every cell of its column is empty)",
                    rec.file, c.name
                )));
            }
        }
        check_temperatures(rec, sc, &sensor_of)?;
        check_time_base(rec, sc)?;
        let period = sc.period_s();
        let t_last = *rec.time_s.last().unwrap();
        let split = Split::new(period, rec.time_s[0], t_last, near_s(&rec.time_s), holdout)
            .map_err(DiagnoseError::Options)?;
        if !split.can_validate() {
            // a recording that starts late: its orbits, not the scenario's from t = 0
            let span = if split.first_orbit > 0 {
                format!(
                    "runs from t = {} to {} s, {} whole orbit(s) of {:.1} s",
                    crate::units::num(rec.time_s[0]),
                    crate::units::num(t_last),
                    split.recorded_orbits(),
                    period
                )
            } else {
                format!(
                    "ends at t = {} s, {} whole orbit(s) of {:.1} s",
                    crate::units::num(t_last),
                    split.orbits,
                    period
                )
            };
            return Err(DiagnoseError::Recording(format!(
                "{}: the recording {span}: diagnose fits whole orbits and checks the fit on \
later ones held out, so it needs at least two (is the time column in seconds from the \
scenario's t = 0?)",
                rec.file,
            )));
        }
        let short_holdout = check_split_holds_data(rec, &channels, &split)?;
        let env = &sc.thermal.environment;
        let mut eclipses = Vec::new();
        let mut t = 0.0;
        let mut entry = if env.sunlit(0.0) { None } else { Some(0.0) };
        while let Some((tc, entering)) = env.next_shadow_crossing(t, t_last + period) {
            if entering {
                entry = Some(tc);
            } else if let Some(e) = entry.take() {
                eclipses.push((e, tc));
            }
            t = tc;
        }
        if let Some(e) = entry {
            eclipses.push((e, f64::INFINITY));
        }
        let width = TRANSITION_FRACTION * period;
        let phase = rec
            .time_s
            .iter()
            .map(|&t| phase_at(&eclipses, t, width))
            .collect();
        Ok(Observations {
            file: rec.file.clone(),
            part: rec.time_s.iter().map(|&t| split.part(t)).collect(),
            orbit: rec
                .time_s
                .iter()
                .map(|&t| (t / period).floor() as usize)
                .collect(),
            phase,
            eclipses,
            channels,
            time_s: rec.time_s.clone(),
            values: rec.values.clone(),
            split,
            short_holdout,
        })
    }

    /// Isolated spikes, left out: a reading beyond both its neighbours, on the same
    /// side, by more than [`SPIKE_SIGMAS`] times the channel's typical step, where both
    /// neighbours are present and within 1.5 × the recording's median sampling
    /// interval of it: a glitch of the telemetry (a bit error, a bad conversion), not
    /// a temperature or backlash a body can reach and leave within one sample. (A
    /// reading alone between gaps in time is never one: its neighbours are not
    /// minutes apart.) The channel's typical step is 1.4826 × the median of its
    /// nonzero steps between consecutive readings, at least its resolution. Their
    /// cells are emptied, and returned. A reading without a neighbour on one side (the
    /// first and last, one next to an empty cell or a gap) is judged against the two
    /// on its other side, each within 1.5 sampling intervals of the next: a spike
    /// when it stands off the nearer by more than the limit plus the step between
    /// those two (so a steady slope or a fast change that goes on is never one).
    pub fn drop_spikes(&mut self) -> Vec<Spike> {
        let near = near_s(&self.time_s);
        let t = &self.time_s;
        let mut out = Vec::new();
        for (c, v) in self.values.iter_mut().enumerate() {
            let mut steps: Vec<f64> = v
                .windows(2)
                .filter_map(|w| Some((w[1]? - w[0]?).abs()))
                .filter(|d| *d > 0.0)
                .collect();
            if steps.len() < 3 {
                continue;
            }
            let typical = (1.4826 * median(&mut steps)).max(resolution(v).unwrap_or(0.0));
            let limit = SPIKE_SIGMAS * typical;
            let mut found = Vec::new();
            // the reading at row k when it is present and within `near` of row j
            let at = |k: usize, j: usize| v[k].filter(|_| (t[k] - t[j]).abs() <= near);
            for j in 0..v.len() {
                let Some(x) = v[j] else { continue };
                let before = (j >= 1).then(|| at(j - 1, j)).flatten();
                let after = v.get(j + 1).and_then(|_| at(j + 1, j));
                let spike = match (before, after) {
                    // how far beyond the nearer neighbour, on the side of neither
                    (Some(p), Some(n)) => {
                        ((x - p.max(n)).max(p.min(n) - x) > limit).then_some(((p, n), Around::Both))
                    }
                    // one side only: against the two there, beyond their own step
                    (None, Some(a)) => v
                        .get(j + 2)
                        .and_then(|_| at(j + 2, j + 1))
                        .filter(|b| (x - a).abs() - (a - b).abs() > limit)
                        .map(|b| ((a, b), Around::After)),
                    (Some(a), None) => (j >= 2)
                        .then(|| at(j - 2, j - 1))
                        .flatten()
                        .filter(|b| (x - a).abs() - (a - b).abs() > limit)
                        .map(|b| ((b, a), Around::Before)),
                    (None, None) => None,
                };
                if let Some((neighbours, around)) = spike {
                    found.push((j, x, neighbours, around));
                }
            }
            for (row, reading, neighbours, around) in found {
                v[row] = None;
                out.push(Spike {
                    channel: c,
                    row,
                    reading,
                    neighbours,
                    around,
                });
            }
        }
        out
    }

    /// Residuals (recorded − simulated) per channel, None where the cell is missing.
    pub fn residuals(&self, predicted: &[Vec<f64>]) -> Vec<Vec<Option<f64>>> {
        self.channels
            .iter()
            .enumerate()
            .map(|(c, ch)| {
                self.values[c]
                    .iter()
                    .zip(&predicted[ch.sensor])
                    .map(|(v, p)| v.map(|v| v - p))
                    .collect()
            })
            .collect()
    }

    /// Root-mean-square residual per channel over the samples of `part`.
    pub fn rms(&self, residuals: &[Vec<Option<f64>>], part: Part) -> Vec<f64> {
        residuals
            .iter()
            .map(|r| {
                let (mut s, mut n) = (0.0, 0usize);
                for (j, v) in r.iter().enumerate() {
                    if let (Some(v), true) = (v, self.part[j] == part) {
                        s += v * v;
                        n += 1;
                    }
                }
                if n == 0 {
                    f64::NAN
                } else {
                    (s / n as f64).sqrt()
                }
            })
            .collect()
    }
}

/// The largest backlash reading taken as one, µm (either sign): a centimetre, far
/// beyond any gear mesh's play.
pub const MAX_BACKLASH_UM: f64 = 1e4;

/// Temperatures a thermometer cannot read: below absolute zero, or above the
/// 10 000 K every model output stays within, and backlash beyond ±[`MAX_BACKLASH_UM`]
/// (a wrong unit or a corrupt cell). Refused with the row's line (CSV) or message
/// number (MCAP) and the column.
fn check_temperatures(
    rec: &Recording,
    sc: &Scenario,
    sensor_of: &[usize],
) -> Result<(), DiagnoseError> {
    use crate::run::sensor::ColumnUnit;
    for (c, &k) in sensor_of.iter().enumerate() {
        let (offset, unit) = match sc.sensors[k].unit() {
            ColumnUnit::Celsius => (crate::constants::ZERO_CELSIUS_K, "°C"),
            ColumnUnit::Kelvin => (0.0, "K"),
            ColumnUnit::Micrometre => (0.0, "µm"),
        };
        let backlash = unit == "µm";
        for (j, v) in rec.values[c].iter().enumerate() {
            let Some(v) = *v else { continue };
            let t_k = v + offset;
            let why = if backlash {
                if v.abs() <= MAX_BACKLASH_UM {
                    continue;
                }
                "beyond ±1 cm"
            } else if t_k < 0.0 {
                "below absolute zero"
            } else if t_k > crate::run::sim::MAX_TEMPERATURE_K {
                "above 10 000 K"
            } else {
                continue;
            };
            return Err(DiagnoseError::Recording(format!(
                "{}:{}: `{}` = {} {unit} is {why}: not a {} a sensor can read (a wrong unit, a scale factor or a corrupt cell?)",
                rec.file,
                rec.rows_at.get(j).copied().unwrap_or(j as u64 + 1),
                crate::units::shown(&rec.columns[c]),
                crate::units::num(v),
                if backlash { "backlash" } else { "temperature" }
            )));
        }
    }
    Ok(())
}

/// Refuses a recording whose time steps cannot resolve the orbit: a median spacing of
/// more than a twelfth of the period (fewer than about four samples per eclipse). The
/// usual cause is a time column in milliseconds (or another unit) instead of seconds;
/// this catches it for cadences up to about 2 Hz (faster ones come out as recordings
/// of thousands of orbits, which the cost estimate bounds).
pub fn check_time_base(rec: &Recording, sc: &Scenario) -> Result<(), DiagnoseError> {
    let period = sc.period_s();
    let last = rec.time_s.last().copied().unwrap_or(0.0);
    if last > crate::spec::scenario::MAX_DURATION_S {
        return Err(DiagnoseError::Recording(format!(
            "{}: the recording ends at t = {} s, later than any run can last ({:.0e} s, 31.7 years): is the time column in seconds from the scenario's t = 0?",
            rec.file,
            crate::units::num(last),
            crate::spec::scenario::MAX_DURATION_S
        )));
    }
    let mut gaps: Vec<f64> = rec.time_s.windows(2).map(|w| w[1] - w[0]).collect();
    if gaps.is_empty() {
        return Ok(());
    }
    let step = median(&mut gaps);
    if step > period / 12.0 {
        return Err(DiagnoseError::Recording(format!(
            "{}: time_s steps by {} s (the median), more than a twelfth of the orbit period ({:.1} s): \
the samples cannot resolve sunlight and eclipse. Is the time column in milliseconds? It must be seconds from the scenario's t = 0",
            rec.file,
            crate::units::num(step),
            period
        )));
    }
    Ok(())
}

/// The fewest samples per channel each part of the split must hold.
pub const MIN_PART_SAMPLES: usize = 10;

/// A channel whose held-out orbits hold fewer samples than a check of its fit needs
/// (a sensor lost part-way through the recording): it is fitted on the training
/// orbits, and its held-out figures rest on what there is.
#[derive(Debug, Clone, PartialEq)]
pub struct ShortHoldout {
    pub channel: usize,
    pub samples: usize,
    pub expected: f64,
}

/// Checks that the training orbits hold at least [`MIN_PART_SAMPLES`] samples of every
/// channel, and the held-out orbits at least that and a quarter of what the training
/// orbits' cadence would put there. A recording whose held-out orbits are short of
/// every channel (it stops, or jumps far ahead) is refused: its verdict would rest on
/// nothing. When only some channels are short (a sensor lost), those are returned,
/// to be reported with a warning.
fn check_split_holds_data(
    rec: &Recording,
    channels: &[Channel],
    split: &Split,
) -> Result<Vec<ShortHoldout>, DiagnoseError> {
    if !split.can_validate() {
        return Ok(Vec::new());
    }
    // where the recording has its longest stretch without a sample (for the messages)
    let gap_note = || {
        let gap = rec
            .time_s
            .windows(2)
            .map(|w| (w[1] - w[0], w[0], w[1]))
            .fold((0.0, 0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a });
        if gap.0 > split.period_s {
            format!(
                "; the recording has no sample from t = {} s to {} s",
                crate::units::num(gap.1),
                crate::units::num(gap.2)
            )
        } else {
            String::new()
        }
    };
    let mut short = Vec::new();
    let mut refusal = None;
    for (c, ch) in channels.iter().enumerate() {
        let (mut train, mut held) = (0usize, 0usize);
        for (t, v) in rec.time_s.iter().zip(&rec.values[c]) {
            if v.is_none() {
                continue;
            }
            match split.part(*t) {
                Part::Train => train += 1,
                Part::Holdout => held += 1,
                Part::Tail => {}
            }
        }
        let expected =
            train as f64 * split.holdout_orbits as f64 / split.fitted_orbits().max(1) as f64;
        let need = (MIN_PART_SAMPLES as f64).max((0.25 * expected).ceil());
        if (train as f64) < MIN_PART_SAMPLES as f64 {
            return Err(DiagnoseError::Recording(format!(
                "{}: the fitted {} hold {train} samples of `{}`; at least {MIN_PART_SAMPLES} are needed{}",
                rec.file,
                split.fitted_span(),
                ch.name,
                gap_note()
            )));
        }
        if (held as f64) < need {
            refusal.get_or_insert_with(|| {
                format!(
                    "{}: the held-out {} hold {held} samples of `{}`, against about {expected:.0} at the cadence of the fitted orbits; \
at least {need:.0} are needed to check a fit on them{}. Hold out fewer orbits (--holdout-orbits N) or cut the recording where its data end",
                    rec.file,
                    split.held_span(),
                    ch.name,
                    gap_note()
                )
            });
            short.push(ShortHoldout {
                channel: c,
                samples: held,
                expected,
            });
        }
    }
    match refusal {
        Some(why) if short.len() == channels.len() => Err(DiagnoseError::Recording(why)),
        _ => Ok(short),
    }
}

fn phase_at(eclipses: &[(f64, f64)], t: f64, width: f64) -> Phase {
    // eclipses are in time order: only the last one starting at or before t can hold
    // t or have just ended (O(log n) per sample, so a long recording stays linear)
    let k = eclipses.partition_point(|&(a, _)| a <= t);
    for &(a, b) in &eclipses[k.saturating_sub(1)..k] {
        if t >= a && t < b {
            return if t - a < width {
                Phase::EclipseEntry
            } else {
                Phase::Eclipse
            };
        }
        if t >= b && t - b < width {
            return Phase::EclipseExit;
        }
    }
    Phase::Sunlit
}

/// A channel's noise from its residual: the robust spread (1.4826 × MAD) of the
/// second differences of consecutive samples, scaled to one sample's standard
/// deviation. Smooth model error has almost no second difference at the recording's
/// cadence, so this sees the measurement noise, not the mismatch; the median makes it
/// blind to the few kinks (switchings, eclipse edges). Irregular sampling is weighted
/// exactly; triples spanning a gap of more than 4 typical spacings are skipped.
pub fn noise(
    time_s: &[f64],
    residual: &[Option<f64>],
    keep: impl Fn(usize) -> bool,
) -> Option<f64> {
    let pts: Vec<(f64, f64)> = residual
        .iter()
        .enumerate()
        .filter(|(j, v)| v.is_some() && keep(*j))
        .map(|(j, v)| (time_s[j], v.unwrap()))
        .collect();
    if pts.len() < 12 {
        return None;
    }
    let mut gaps: Vec<f64> = pts.windows(2).map(|w| w[1].0 - w[0].0).collect();
    let typical = median(&mut gaps);
    let mut z = Vec::with_capacity(pts.len());
    for w in pts.windows(3) {
        let (ta, ra) = w[0];
        let (tb, rb) = w[1];
        let (tc, rc) = w[2];
        let span = tc - ta;
        if span <= 0.0 || span > 8.0 * typical {
            continue;
        }
        let wa = (tc - tb) / span;
        let wc = (tb - ta) / span;
        let d = rb - (wa * ra + wc * rc);
        z.push(d / (1.0 + wa * wa + wc * wc).sqrt());
    }
    if z.len() < 10 {
        return None;
    }
    let m = median(&mut z);
    let mut dev: Vec<f64> = z.iter().map(|v| (v - m).abs()).collect();
    Some(1.4826 * median(&mut dev))
}

/// A channel's orbit-to-orbit scatter: its readings binned by orbit phase (1-minute
/// bins of `period_s`, from t = 0), the RMS of each about its bin's mean over the
/// orbits, with one degree of freedom per bin used. None when fewer than two orbits
/// share a bin anywhere.
pub fn orbit_scatter(time_s: &[f64], values: &[Option<f64>], period_s: f64) -> Option<f64> {
    if period_s.is_nan() || period_s <= 60.0 {
        return None;
    }
    let bins = (period_s / 60.0).ceil() as usize;
    // Welford per bin: mean and the sum of squared deviations, without cancellation
    let mut mean = vec![0.0; bins];
    let mut m2 = vec![0.0; bins];
    let mut count = vec![0usize; bins];
    for (t, v) in time_s.iter().zip(values) {
        if let Some(v) = v {
            let b = ((t.rem_euclid(period_s) / 60.0) as usize).min(bins - 1);
            count[b] += 1;
            let d = v - mean[b];
            mean[b] += d / count[b] as f64;
            m2[b] += d * (v - mean[b]);
        }
    }
    let ss: f64 = m2.iter().sum();
    let dof: usize = count.iter().map(|&n| n.saturating_sub(1)).sum();
    (dof > 0).then(|| (ss / dof as f64).sqrt())
}

/// A channel's resolution: the smallest step between two consecutive readings (none
/// when no reading changes). A quantised sensor cannot be fitted closer than its
/// quantum / √12, however smooth its residual.
pub fn resolution(values: &[Option<f64>]) -> Option<f64> {
    let read: Vec<f64> = values.iter().flatten().copied().collect();
    read.windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 1e-9)
        .min_by(f64::total_cmp)
}

pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Where a channel's residual sits.
#[derive(Debug, Clone, Serialize)]
pub struct Mismatch {
    pub channel: String,
    /// `sunlit`, `eclipse`, `eclipse_entry`, `eclipse_exit` or `all`.
    pub phase: String,
    /// The first window of the recording where it shows (absolute time).
    pub t_start_s: f64,
    pub t_end_s: f64,
    /// The same window folded into the orbit: seconds after orbit noon, over all
    /// orbits where it shows.
    pub orbit_t_start_s: f64,
    pub orbit_t_end_s: f64,
    /// Orbits (0-based) in which it shows.
    pub orbits: Vec<usize>,
    /// RMS residual in this phase (K or µm).
    pub rms: f64,
    /// Mean residual in this phase (sign: recorded above the model when positive).
    pub mean: f64,
    /// Share of the channel's residual energy in this phase.
    pub share: f64,
    /// RMS over the noise.
    pub rms_over_noise: f64,
}

/// Residual energy folded by orbit phase and by orbit, and the mismatches: for each
/// channel whose residual exceeds `ratio` × its noise, the phases where it sits, or
/// `all` when it is spread over the orbit. Sorted by residual energy over the noise,
/// largest first.
pub fn mismatches(
    obs: &Observations,
    residuals: &[Vec<Option<f64>>],
    noise: &[f64],
    ratio: f64,
) -> Vec<Mismatch> {
    let mut out = Vec::new();
    let period = obs.split.period_s;
    for (c, r) in residuals.iter().enumerate() {
        let sigma = noise[c];
        let (mut total, mut n_total) = (0.0, 0usize);
        let mut by_phase = [(0.0f64, 0.0f64, 0usize); 4];
        for (j, v) in r.iter().enumerate() {
            let Some(v) = v else { continue };
            if obs.part[j] == Part::Tail {
                continue;
            }
            total += v * v;
            n_total += 1;
            let p = Phase::ALL.iter().position(|&p| p == obs.phase[j]).unwrap();
            by_phase[p].0 += v * v;
            by_phase[p].1 += v;
            by_phase[p].2 += 1;
        }
        if n_total == 0 || total <= 0.0 {
            continue;
        }
        let smooth = smoothed(r, 5);
        let rms_all = (total / n_total as f64).sqrt();
        if rms_all.is_nan() || rms_all <= ratio * sigma {
            continue;
        }
        // Phases whose mean square stands out against the channel's.
        let ms_all = total / n_total as f64;
        let mut phases: Vec<usize> = (0..4)
            .filter(|&p| by_phase[p].2 > 0 && by_phase[p].0 / by_phase[p].2 as f64 > 1.5 * ms_all)
            .collect();
        let spread = phases.is_empty();
        if spread {
            phases = vec![usize::MAX];
        }
        for p in phases {
            let in_phase = |j: usize| p == usize::MAX || Phase::ALL[p] == obs.phase[j];
            let (e, s, n) = if p == usize::MAX {
                (total, r.iter().flatten().sum::<f64>(), n_total)
            } else {
                by_phase[p]
            };
            let rms = (e / n as f64).sqrt();
            // Where it shows: samples of this phase whose smoothed residual exceeds
            // three noise widths of the smoothed series.
            let limit = (3.0 * sigma / 5f64.sqrt()).max(0.5 * rms);
            let mut hits: Vec<usize> = (0..r.len())
                .filter(|&j| obs.part[j] != Part::Tail && in_phase(j))
                .filter(|&j| smooth[j].is_some_and(|v| v.abs() > limit))
                .collect();
            if hits.is_empty() {
                hits = (0..r.len())
                    .filter(|&j| obs.part[j] != Part::Tail && in_phase(j) && r[j].is_some())
                    .collect();
            }
            let first = hits[0];
            let mut last = first;
            for &j in &hits[1..] {
                if obs.time_s[j] - obs.time_s[last] > 0.05 * period
                    || obs.orbit[j] != obs.orbit[first]
                {
                    break;
                }
                last = j;
            }
            let mut orbits: Vec<usize> = hits.iter().map(|&j| obs.orbit[j]).collect();
            orbits.dedup();
            let folded: Vec<f64> = hits
                .iter()
                .map(|&j| obs.time_s[j] - obs.orbit[j] as f64 * period)
                .collect();
            out.push(Mismatch {
                channel: obs.channels[c].name.clone(),
                phase: if p == usize::MAX {
                    "all".into()
                } else {
                    Phase::ALL[p].as_str().into()
                },
                t_start_s: obs.time_s[first],
                t_end_s: obs.time_s[last],
                orbit_t_start_s: folded.iter().copied().fold(f64::INFINITY, f64::min),
                orbit_t_end_s: folded.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                orbits,
                rms,
                mean: s / n as f64,
                share: e / total,
                rms_over_noise: rms / sigma,
            });
        }
    }
    out.sort_by(|a, b| {
        let ka = a.share * a.rms_over_noise.powi(2);
        let kb = b.share * b.rms_over_noise.powi(2);
        kb.total_cmp(&ka)
    });
    out
}

/// Centred moving average over up to `w` present neighbours.
pub fn smoothed(r: &[Option<f64>], w: usize) -> Vec<Option<f64>> {
    let h = w / 2;
    (0..r.len())
        .map(|j| {
            r[j]?;
            let lo = j.saturating_sub(h);
            let hi = (j + h + 1).min(r.len());
            let v: Vec<f64> = r[lo..hi].iter().flatten().copied().collect();
            Some(v.iter().sum::<f64>() / v.len() as f64)
        })
        .collect()
}

/// RMS residual per channel and orbit (NaN where an orbit has no samples).
pub fn orbit_rms(obs: &Observations, residuals: &[Vec<Option<f64>>]) -> Vec<Vec<f64>> {
    let n = obs.orbit.iter().copied().max().unwrap_or(0) + 1;
    residuals
        .iter()
        .map(|r| {
            let mut s = vec![(0.0, 0usize); n];
            for (j, v) in r.iter().enumerate() {
                if let Some(v) = v {
                    s[obs.orbit[j]].0 += v * v;
                    s[obs.orbit[j]].1 += 1;
                }
            }
            s.iter()
                .map(|&(e, k)| {
                    if k == 0 {
                        f64::NAN
                    } else {
                        (e / k as f64).sqrt()
                    }
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A recording that starts late counts its orbits from its first (the scenario's
    /// numbers kept), holds a third of those out, and takes a lead-in of less than half
    /// an orbit as part of the next: 2 samples before a boundary made "orbit 6" of 60 s
    /// (review helper-26).
    #[test]
    fn core_a_late_recording_counts_its_own_orbits() {
        let p = 5677.0;
        let s = Split::new(p, 11_400.0, 12.0 * p, 30.0, None).unwrap();
        assert_eq!(
            (s.first_orbit, s.recorded_orbits(), s.holdout_orbits),
            (2, 10, 3)
        );
        assert_eq!(
            (s.fitted_span(), s.held_span()),
            ("orbits 3–9".into(), "orbits 10–12".into())
        );
        let s = Split::new(p, 5.0 * p + 0.6 * p, 12.0 * p, 30.0, None).unwrap();
        assert_eq!(
            (s.first_orbit, s.recorded_orbits()),
            (6, 6),
            "less than half: a lead-in"
        );
        let s = Split::new(p, 5.0 * p + 0.4 * p, 12.0 * p, 30.0, None).unwrap();
        assert_eq!(
            (s.first_orbit, s.recorded_orbits()),
            (5, 7),
            "more than half: an orbit"
        );
        let s = Split::new(p, 0.0, 12.0 * p, 30.0, None).unwrap();
        assert_eq!(
            (s.first_orbit, s.holdout_orbits, s.fitted_span()),
            (0, 4, "orbits 1–8".into())
        );
        // hold out all the recording's orbits: refused, naming them
        let e = Split::new(p, 11_400.0, 12.0 * p, 30.0, Some(10)).unwrap_err();
        assert!(
            e.contains("10 whole orbits (orbits 3–12 of the scenario)"),
            "{e}"
        );
    }

    /// The resolution is the smallest change between consecutive readings: repeats
    /// and gaps are skipped.
    #[test]
    fn core_resolution_is_the_smallest_step_between_readings() {
        let v = [
            Some(1.0),
            Some(1.0),
            None,
            Some(1.25),
            Some(2.0),
            Some(1.5),
            Some(1.75),
        ];
        assert_eq!(resolution(&v), Some(0.25));
        assert_eq!(resolution(&[Some(3.0), None, Some(3.0)]), None);
    }

    /// A signal that repeats every orbit has no scatter; added ±a alternating from
    /// orbit to orbit, its scatter is a (corrected for the bins' means).
    #[test]
    fn core_orbit_scatter_of_a_periodic_signal() {
        let period = 600.0;
        // one reading a minute over 10 orbits: one reading per bin and orbit
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 60.0).collect();
        let periodic: Vec<Option<f64>> = t
            .iter()
            .map(|t| Some((2.0 * std::f64::consts::PI * t / period).sin()))
            .collect();
        assert!(orbit_scatter(&t, &periodic, period).unwrap() < 1e-9);
        let shaken: Vec<Option<f64>> = t
            .iter()
            .zip(&periodic)
            .map(|(t, v)| {
                let orbit = (t / period) as i64;
                Some(v.unwrap() + if orbit % 2 == 0 { 0.5 } else { -0.5 })
            })
            .collect();
        // 10 readings per bin, 5 at +0.5 and 5 at −0.5 about its mean:
        // Σ (x − mean)² / (n − 1) = 10 · 0.25 / 9 in every bin
        let want = (10.0 * 0.25 / 9.0f64).sqrt();
        let got = orbit_scatter(&t, &shaken, period).unwrap();
        assert!((got - want).abs() < 1e-9, "{got} {want}");
    }
}

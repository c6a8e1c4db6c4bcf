//! `[[sensor]]` and `[recording]`: the columns of a recording and what each reads.

use super::*;
use crate::spec::registry as r;

/// `[recording]`: the layout of this spacecraft's recordings. UTC time needs a dated
/// scenario (its `start_utc` is the recording's t = 0).
pub(super) fn recording_format(
    cx: &Cx,
    spec: Option<RecordingSpec>,
    environment: &Environment,
) -> Result<crate::spec::scenario::RecordingFormat, SpecError> {
    use crate::spec::scenario::{DuplicateTimes, RecordingFormat, TimeFormat};
    use crate::spec::{RepeatedRows, TimeFormatName};
    let p = KeyPath::new("recording");
    let Some(spec) = spec else {
        return Ok(RecordingFormat::default());
    };
    let mut f = RecordingFormat::default();
    if let Some(c) = spec.time_column {
        if c.trim().is_empty() {
            return Err(cx.err(&p.key("time_column"), "is empty"));
        }
        f.time_column = c;
    }
    f.time = match spec.time_format {
        None | Some(TimeFormatName::Seconds) => TimeFormat::Seconds,
        Some(TimeFormatName::Utc) => match environment.start_utc() {
            Some(origin) => TimeFormat::Utc { origin },
            None => {
                return Err(cx.err(
                    &p.key("time_format"),
                    "\"utc\" needs a dated scenario: give [orbit] tle and start_utc (the recording's t = 0)",
                ));
            }
        },
    };
    f.ignore_columns = spec.ignore_columns.unwrap_or_default();
    if let Some(dup) = f
        .ignore_columns
        .iter()
        .enumerate()
        .find(|(i, c)| f.ignore_columns[..*i].contains(c) || **c == f.time_column)
    {
        return Err(cx.err(
            &p.key("ignore_columns").at(dup.0),
            format!("`{}` is listed twice or is the time column", dup.1),
        ));
    }
    f.repeated_rows_are_fill = spec.repeated_rows == Some(RepeatedRows::Fill);
    f.duplicate_times = spec.duplicate_times.unwrap_or(DuplicateTimes::Refuse);
    f.time_offset_s = cx.read_or_default(&r::TIME_OFFSET_S, &p, spec.time_offset_s)?;
    f.eclipse = match (spec.eclipse_column, spec.eclipse_below) {
        (None, None) => None,
        (Some(column), Some(below)) => {
            if column.trim().is_empty() || column == f.time_column {
                return Err(cx.err(&p.key("eclipse_column"), "is empty or the time column"));
            }
            if f.ignore_columns.contains(&column) {
                return Err(cx.err(
                    &p.key("eclipse_column"),
                    format!("`{column}` is also in ignore_columns: a column is read or ignored, not both"),
                ));
            }
            if !below.is_finite() {
                return Err(cx.err(
                    &p.key("eclipse_below"),
                    format!("must be a finite number (got {below})"),
                ));
            }
            Some(crate::spec::scenario::EclipseColumn { column, below })
        }
        (Some(_), None) => {
            return Err(cx.err(
                &p.key("eclipse_below"),
                "is missing: give the reading of eclipse_column below which a row is in eclipse",
            ));
        }
        (None, Some(_)) => {
            return Err(cx.err(
                &p.key("eclipse_column"),
                "is missing: eclipse_below needs the column it reads",
            ));
        }
    };
    Ok(f)
}

/// The sensors: recording columns read as a node's temperature (with a lag and an
/// offset) or as a gear pair's backlash.
pub(super) fn sensors(
    cx: &Cx,
    specs: Vec<SensorSpec>,
    keys: &[String],
    gears: &[GearPair],
    face_nodes: &[(String, String)],
    diffusion: &dyn Fn(&KeyPath, &str) -> Result<usize, SpecError>,
) -> Result<Vec<Sensor>, SpecError> {
    let mut sensors: Vec<Sensor> = Vec::new();
    for (i, s) in specs.into_iter().enumerate() {
        let p = KeyPath::new("sensor").elem(i, &keys[i]);
        if sensors.iter().any(|x| x.source_column == s.column) {
            return Err(cx.err(
                &p.key("column"),
                format!("column `{}` is defined twice", s.column),
            ));
        }
        let name = s
            .name
            .clone()
            .unwrap_or_else(|| crate::spec::scenario::sensor_name_of(&s.column));
        if let Some(other) = sensors.iter().find(|x| x.column == name) {
            return Err(cx.err(
                &p.key(if s.name.is_some() { "name" } else { "column" }),
                format!(
                    "names the channel `{name}`, as the sensor of column `{}` does; give each a `name`",
                    other.source_column
                ),
            ));
        }
        let node = match (s.node, &s.face) {
            (Some(_), Some(_)) => {
                return Err(cx.err(&p.key("face"), "give `node` or `face`, not both"));
            }
            (None, Some(face)) => Some(
                face_nodes
                    .iter()
                    .find(|(k, _)| k == face)
                    .map(|(_, n)| n.clone())
                    .ok_or_else(|| {
                        let known: Vec<&str> = face_nodes.iter().map(|(k, _)| k.as_str()).collect();
                        cx.err(
                            &p.key("face"),
                            format!(
                                "unknown face `{face}` ({})",
                                if known.is_empty() {
                                    "the scenario has no [[face]]".to_string()
                                } else {
                                    format!("known: {}", known.join(", "))
                                }
                            ),
                        )
                    })?,
            ),
            (n, None) => n,
        };
        let target = match (node, s.quantity) {
            (Some(n), None) => {
                if s.gear_pair.is_some() {
                    return Err(cx.err(
                        &p.key("gear_pair"),
                        "a temperature sensor reads a node, not a gear pair",
                    ));
                }
                SensorTarget::Node(diffusion(&p.key("node"), &n)?)
            }
            (None, Some(q)) => {
                for (key, given) in [(r::TAU_S.name, s.tau_s), (r::OFFSET_K.name, s.offset_k)] {
                    if given.is_some() {
                        return Err(cx.err(
                            &p.key(key),
                            format!("applies to temperature sensors only (`{q}` is derived)"),
                        ));
                    }
                }
                let pair = match &s.gear_pair {
                    None if gears.is_empty() => {
                        return Err(
                            cx.err(&p.key("quantity"), "needs a [[gear_pair]] in the scenario")
                        );
                    }
                    None => 0,
                    Some(name) => gears.iter().position(|g| &g.name == name).ok_or_else(|| {
                        cx.err(&p.key("gear_pair"), format!("unknown gear pair `{name}`"))
                    })?,
                };
                SensorTarget::Backlash(pair)
            }
            _ => {
                return Err(cx.err(&p, "give exactly one of `node`, `face` or `quantity`"));
            }
        };
        use crate::spec::scenario::ColumnUnit;
        let unit_given = match s.unit {
            None => None,
            Some(_) if matches!(target, SensorTarget::Backlash(_)) => {
                return Err(cx.err(
                    &p.key("unit"),
                    "applies to temperature sensors only (backlash is in µm)",
                ));
            }
            Some(UnitName::Celsius) => Some(ColumnUnit::Celsius),
            Some(UnitName::Kelvin) => Some(ColumnUnit::Kelvin),
        };
        let tau_s = cx.read_or_default(&r::TAU_S, &p, s.tau_s)?;
        let offset_k = cx.read_or_default(&r::OFFSET_K, &p, s.offset_k)?;
        sensors.push(Sensor {
            column: name,
            source_column: s.column,
            target,
            offset_k,
            tau_s,
            unit_given,
        });
    }
    Ok(sensors)
}

/// A column is one thing: a sensor's column is neither the recording's time column,
/// an ignored column nor its eclipse column.
pub(super) fn columns_read_once(
    cx: &Cx,
    sensors: &[Sensor],
    keys: &[String],
    recording: &crate::spec::scenario::RecordingFormat,
) -> Result<(), SpecError> {
    if let Some((i, s)) = sensors.iter().enumerate().find(|(_, s)| {
        s.source_column == recording.time_column
            || recording.ignore_columns.contains(&s.source_column)
    }) {
        return Err(cx.err(
            &KeyPath::new("sensor").elem(i, &keys[i]).key("column"),
            format!(
                "`{}` is the recording's {}: a column is read or ignored, not both",
                crate::units::shown(&s.source_column),
                if s.source_column == recording.time_column {
                    "time column ([recording] time_column)"
                } else {
                    "ignored column ([recording] ignore_columns)"
                }
            ),
        ));
    }
    if let Some(e) = &recording.eclipse
        && sensors.iter().any(|s| s.source_column == e.column)
    {
        return Err(cx.err(
            &KeyPath::new("recording").key("eclipse_column"),
            format!(
                "`{}` is a [[sensor]]'s column: the eclipse column is read to check the clock, not fitted",
                e.column
            ),
        ));
    }
    Ok(())
}

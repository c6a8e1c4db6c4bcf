//! The MCAP file of `diagnose --out`: per recording channel, a topic
//! `/diagnose/<channel>` with `recorded`, `baseline`, `corrected`, `residual_before`
//! and `residual_after` side by side, one message per recorded sample (missing cells
//! have no message, so every field of every message is a real number); and
//! `/diagnose/model/<channel>` with the baseline and corrected series at every time.
//! Protobuf with the schemas stored in the file, as the run logs, so Foxglove's Plot
//! panel and Rerun's importer read them (`tools/check_mcap.py`).

use crate::diagnose::Diagnosis;
use std::collections::BTreeMap;

use super::log_schema::ns;
use super::log_schema::{Kind, MessageType, descriptor_set, identifier};
use super::protobuf::Encoder;

/// The side-by-side file's bytes (the caller writes them with the command's other
/// outputs, all or none). Log time is the recording's time since its t = 0, offset by
/// `time_origin_ns` (ns since the Unix epoch of t = 0 for a dated scenario, else 0),
/// which the metadata record `orbitlash.provenance` names as the run logs do, so that
/// viewers show UTC; `scenario_name` names the recording in them.
pub fn mcap_bytes(
    d: &Diagnosis,
    scenario_name: &str,
    time_origin_ns: u64,
) -> Result<Vec<u8>, mcap::McapError> {
    let err = |e: mcap::McapError| e;
    let file = std::io::Cursor::new(Vec::new());
    let mut w = mcap::WriteOptions::new()
        .library(format!("orbitlash {}", env!("CARGO_PKG_VERSION")))
        .profile("")
        .compression(None)
        .create(file)
        .map_err(err)?;
    let s = &d.series;
    let side = MessageType::new("DiagnoseSample")
        .with("recorded", Kind::Double)
        .with("baseline", Kind::Double)
        .with("corrected", Kind::Double)
        .with("residual_before", Kind::Double)
        .with("residual_after", Kind::Double)
        .with("train", Kind::Double);
    let model = MessageType::new("DiagnoseModel")
        .with("baseline", Kind::Double)
        .with("corrected", Kind::Double);
    let side_schema = w
        .add_schema(
            "orbitlash.DiagnoseSample",
            "protobuf",
            &descriptor_set("DiagnoseSample", &[side]),
        )
        .map_err(err)?;
    let model_schema = w
        .add_schema(
            "orbitlash.DiagnoseModel",
            "protobuf",
            &descriptor_set("DiagnoseModel", &[model]),
        )
        .map_err(err)?;
    let mut meta = BTreeMap::new();
    meta.insert("verdict".to_string(), d.verdict.as_str().to_string());
    meta.insert("train_end_s".to_string(), format!("{}", s.train_end_s));
    meta.insert("holdout_end_s".to_string(), format!("{}", s.holdout_end_s));
    w.write_metadata(&mcap::records::Metadata {
        name: "diagnose".into(),
        metadata: meta,
    })
    .map_err(err)?;
    let provenance: BTreeMap<String, String> = [
        ("tool".to_string(), "orbitlash".to_string()),
        ("scenario_name".to_string(), scenario_name.to_string()),
        (
            super::mcap_log::TIME_ORIGIN_KEY.to_string(),
            time_origin_ns.to_string(),
        ),
    ]
    .into_iter()
    .collect();
    w.write_metadata(&mcap::records::Metadata {
        name: "orbitlash.provenance".into(),
        metadata: provenance,
    })
    .map_err(err)?;
    let mut enc = Encoder::default();
    let mut seq = 0u32;
    for (c, name) in s.channels.iter().enumerate() {
        let unit = s.units[c];
        let mut m = BTreeMap::new();
        m.insert("unit".to_string(), unit.to_string());
        let topic = identifier(name);
        let ch = w
            .add_channel(side_schema, &format!("/diagnose/{topic}"), "protobuf", &m)
            .map_err(err)?;
        let chm = w
            .add_channel(
                model_schema,
                &format!("/diagnose/model/{topic}"),
                "protobuf",
                &m,
            )
            .map_err(err)?;
        for (j, &t) in s.time_s.iter().enumerate() {
            let (b, k) = (s.baseline[c][j], s.corrected[c][j]);
            if !(b.is_finite() && k.is_finite()) {
                continue;
            }
            seq += 1;
            let header = |channel_id| mcap::records::MessageHeader {
                channel_id,
                sequence: seq,
                log_time: time_origin_ns.saturating_add(ns(t)),
                publish_time: time_origin_ns.saturating_add(ns(t)),
            };
            enc.clear();
            enc.double(1, b);
            enc.double(2, k);
            w.write_to_known_channel(&header(chm), &enc.buf)
                .map_err(err)?;
            if let Some(v) = s.recorded[c][j] {
                enc.clear();
                enc.double(1, v);
                enc.double(2, b);
                enc.double(3, k);
                enc.double(4, v - b);
                enc.double(5, v - k);
                enc.double(6, if t < s.train_end_s { 1.0 } else { 0.0 });
                w.write_to_known_channel(&header(ch), &enc.buf)
                    .map_err(err)?;
            }
        }
    }
    w.finish().map_err(err)?;
    Ok(w.into_inner().into_inner())
}

/// The series of `diagnose --out` as CSV (`series.csv`): `time_s`, `part` (`train`,
/// `holdout`, or `tail` after the last whole orbit), then per channel
/// `<channel>.recorded` (empty where the recording has no reading), `.baseline` and
/// `.corrected`, in the channel's unit (°C, K or µm, as the recording).
pub fn series_csv(d: &Diagnosis) -> String {
    use std::fmt::Write;
    let s = &d.series;
    let mut o = String::from("time_s,part");
    for name in &s.channels {
        for f in ["recorded", "baseline", "corrected"] {
            let _ = write!(o, ",{name}.{f}");
        }
    }
    o.push('\n');
    for (j, &t) in s.time_s.iter().enumerate() {
        let part = if t <= s.train_end_s {
            "train"
        } else if t <= s.holdout_end_s {
            "holdout"
        } else {
            "tail"
        };
        let _ = write!(o, "{t},{part}");
        for c in 0..s.channels.len() {
            match s.recorded[c][j] {
                Some(v) => {
                    let _ = write!(o, ",{v}");
                }
                None => o.push(','),
            }
            let _ = write!(o, ",{},{}", s.baseline[c][j], s.corrected[c][j]);
        }
        o.push('\n');
    }
    o
}

//! Recordings read by the library (`io::recording`): the CSV layout of
//! `reference-mechanism.md` §4 and MCAP (JSON and protobuf topics); every malformed
//! input is an error naming the file, line and column.

mod common;

use std::collections::BTreeMap;

use orbitlash::io::log_schema::{Kind, MessageType, descriptor_set};
use orbitlash::io::protobuf::Encoder;
use orbitlash::io::recording::{Recording, RecordingError};
use orbitlash::run::sensor::{Sensor, SensorTarget};

/// Channels by name: (time, name → values).
type ByName = (Vec<f64>, BTreeMap<String, Vec<Option<f64>>>);
fn by_name(r: &Recording) -> ByName {
    let m = r
        .columns
        .iter()
        .cloned()
        .zip(r.values.iter().cloned())
        .collect();
    (r.time_s.clone(), m)
}

fn csv(text: &str) -> Result<Recording, RecordingError> {
    Recording::from_csv(text.as_bytes(), "rec.csv")
}

fn error(text: &str) -> String {
    csv(text).unwrap_err().to_string()
}

#[test]
fn core_recording_reads_the_reference_layout() {
    let r = csv(
        "\u{feff}# thermal-vacuum test 3\ntime_s, housing_c ,backlash_um\n0,20.5,33.5\n30,,33.6\n\n60,21.0,\n",
    )
    .unwrap();
    assert_eq!(r.columns, ["housing_c", "backlash_um"]);
    assert_eq!(r.time_s, [0.0, 30.0, 60.0]);
    assert_eq!(
        r.channel("housing_c").unwrap(),
        [Some(20.5), None, Some(21.0)]
    );
    assert_eq!(
        r.channel("backlash_um").unwrap(),
        [Some(33.5), Some(33.6), None]
    );
    assert_eq!(r.rows_at, [3, 4, 6]);
    // time need not come first
    let r = csv("housing_c,time_s\n1,0\n2,30\n").unwrap();
    assert_eq!(
        (r.columns.as_slice(), r.time_s.as_slice()),
        (&["housing_c".to_string()][..], &[0.0, 30.0][..])
    );
}

#[test]
fn core_recording_errors_name_file_line_and_column() {
    for (text, needles) in [
        (
            "time_s,a\n0,1\n30,x\n",
            &["rec.csv:3:2", "`x` in column `a` is not a number"][..],
        ),
        (
            "time_s,a\n0,1\n30,NaN\n",
            &["rec.csv:3:2", "not a finite number", "empty cell"],
        ),
        (
            "time_s,a\n0,1\n30,inf\n",
            &["rec.csv:3:2", "not a finite number"],
        ),
        (
            "time_s,a\n0,1\n0,2\n",
            &[
                "rec.csv:3:1",
                "time does not increase: 0 s after 0 s on line 2",
            ],
        ),
        (
            "time_s,a\n60,1\n30,2\n",
            &["rec.csv:3:1", "30 s after 60 s"],
        ),
        (
            "time_s,a\n0,1\n,2\n",
            &["rec.csv:3:1", "time (`time_s`) is missing"],
        ),
        (
            "time_s,a\n0,1\n30,2,3\n",
            &["rec.csv:3", "3 fields, the header 2"],
        ),
        ("t,a\n0,1\n", &["rec.csv:1", "no `time_s` column", "t,a"]),
        ("time_s,a,a\n0,1,2\n", &["rec.csv:1:3", "`a` appears twice"]),
        ("time_s,,a\n0,1,2\n", &["rec.csv:1:2", "no name"]),
        ("", &["rec.csv", "is empty"]),
        ("time_s,a\n", &["rec.csv", "no samples"]),
        (
            "time_s,a\n0,\u{fffd}\u{0}\n",
            &["rec.csv:2:2", "not a number"],
        ),
    ] {
        let e = error(text);
        for n in needles {
            assert!(e.contains(n), "{text:?}: `{e}` lacks `{n}`");
        }
    }
    // A control character of the file is shown escaped, never sent to the terminal
    // (a NUL, an escape sequence, a line break inside a quoted cell).
    for (text, shown) in [
        ("time_s,a\n0,1.2\u{0}3\n", "`1.2\\u{0}3`"),
        ("time_s,a\n0,\u{1b}[31m\n", "`\\u{1b}[31m`"),
        ("time_s,a\n0,\"12\n.5\"\n", "`12\\u{a}.5`"),
    ] {
        let e = error(text);
        assert!(e.contains(shown), "{text:?}: `{e}` lacks `{shown}`");
        assert!(!e.chars().any(char::is_control), "{text:?}: `{e:?}`");
    }
    // Lines that end in a lone CR (old Mac files) are counted as lines, as with LF and
    // CR LF: the error names the line where the time goes back.
    for eol in ["\n", "\r\n", "\r"] {
        let text = ["time_s,a", "0,1", "60,2", "30,3", ""].join(eol);
        let e = error(&text);
        assert!(
            e.contains("rec.csv:4:1") && e.contains("30 s after 60 s on line 3"),
            "{eol:?}: {e}"
        );
    }
    // not UTF-8
    let e = Recording::from_csv(b"time_s,a\n0,\xff\n", "rec.csv")
        .unwrap_err()
        .to_string();
    assert!(e.contains("rec.csv:2") && e.contains("UTF-8"), "{e}");
    // a missing file
    let e = Recording::read(std::path::Path::new("/nonexistent/rec.csv")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/rec.csv"), "{e}");
}

#[test]
fn core_recording_channels_must_be_sensors() {
    let r = csv("time_s,housing_c,pressure_pa\n0,1,2\n").unwrap();
    let sensors = vec![Sensor::new("housing_c", SensorTarget::Node(0))];
    let e = r.match_sensors(&sensors).unwrap_err().to_string();
    assert!(
        e.contains("rec.csv")
            && e.contains("`pressure_pa` is not a sensor")
            && e.contains("housing_c"),
        "{e}"
    );
    let sensors = vec![
        Sensor::new("pressure_pa", SensorTarget::Node(1)),
        Sensor::new("housing_c", SensorTarget::Node(0)),
    ];
    assert_eq!(r.match_sensors(&sensors).unwrap(), [1, 0]);
}

/// Writes an MCAP file with one topic of `encoding` and the given messages (log time
/// ns, bytes), plus an unrelated topic when `extra`.
fn mcap_file(
    path: &std::path::Path,
    topic: &str,
    encoding: &str,
    schema: Option<(&str, Vec<u8>)>,
    messages: &[(u64, Vec<u8>)],
    extra: bool,
) {
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(path).unwrap(),
    ))
    .unwrap();
    let schema_id = match &schema {
        Some((name, data)) => w.add_schema(name, "protobuf", data).unwrap(),
        None => 0,
    };
    let ch = w
        .add_channel(schema_id, topic, encoding, &BTreeMap::new())
        .unwrap();
    let other = extra.then(|| {
        w.add_channel(0, "/notes", "json", &BTreeMap::new())
            .unwrap()
    });
    for (seq, (t, data)) in messages.iter().enumerate() {
        let header = mcap::records::MessageHeader {
            channel_id: ch,
            sequence: seq as u32,
            log_time: *t,
            publish_time: *t,
        };
        w.write_to_known_channel(&header, data).unwrap();
        if let Some(o) = other {
            let header = mcap::records::MessageHeader {
                channel_id: o,
                ..header
            };
            w.write_to_known_channel(&header, b"{\"x\": 1}").unwrap();
        }
    }
    w.finish().unwrap();
}

#[test]
fn core_recording_reads_mcap_json_and_protobuf_like_csv() {
    let dir = common::tmpdir("core_recording_mcap");
    let from_csv =
        csv("time_s,housing_c,backlash_um\n0,20.5,33.5\n30,21,33.6\n60,21.5,33.7\n").unwrap();

    // JSON, with the time in a field
    let json: Vec<(u64, Vec<u8>)> = [(0.0, 20.5, 33.5), (30.0, 21.0, 33.6), (60.0, 21.5, 33.7)]
        .iter()
        .map(|&(t, h, b)| {
            (
                (t * 1e9) as u64,
                format!("{{\"time_s\": {t}, \"housing_c\": {h}, \"backlash_um\": {b}, \"note\": \"ok\"}}")
                    .into_bytes(),
            )
        })
        .collect();
    let path = dir.join("json.mcap");
    mcap_file(&path, "/recording", "json", None, &json, true);
    let r = Recording::read(&path).unwrap();
    assert_eq!(by_name(&r), by_name(&from_csv));

    // protobuf, the time from the log time; a null JSON value is a missing sample
    let ty = MessageType::new("Rec")
        .with("housing_c", Kind::Double)
        .with("backlash_um", Kind::Double);
    let proto: Vec<(u64, Vec<u8>)> = [(0.0, 20.5, 33.5), (30.0, 21.0, 33.6), (60.0, 21.5, 33.7)]
        .iter()
        .map(|&(t, h, b)| {
            let mut e = Encoder::default();
            e.double(1, h);
            e.double(2, b);
            ((t * 1e9) as u64, e.buf.clone())
        })
        .collect();
    let path = dir.join("proto.mcap");
    mcap_file(
        &path,
        "/tvac",
        "protobuf",
        Some((
            "orbitlash.Rec",
            descriptor_set("Rec", std::slice::from_ref(&ty)),
        )),
        &proto,
        false,
    );
    let r = Recording::read(&path).unwrap();
    assert_eq!(by_name(&r), by_name(&from_csv));

    // errors: NaN, time going back, several topics without /recording, not JSON
    let mut e = Encoder::default();
    e.double(1, f64::NAN);
    e.double(2, 1.0);
    let path = dir.join("nan.mcap");
    mcap_file(
        &path,
        "/tvac",
        "protobuf",
        Some(("orbitlash.Rec", descriptor_set("Rec", &[ty]))),
        &[(0, e.buf.clone())],
        false,
    );
    let msg = Recording::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("nan.mcap")
            && msg.contains("message 1")
            && msg.contains("`housing_c` is not a finite number"),
        "{msg}"
    );
    let path = dir.join("back.mcap");
    mcap_file(
        &path,
        "/recording",
        "json",
        None,
        &[
            (0, b"{\"time_s\": 5, \"a\": 1}".to_vec()),
            (1, b"{\"time_s\": 4, \"a\": 1}".to_vec()),
        ],
        false,
    );
    let msg = Recording::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("message 2") && msg.contains("4 s after 5 s"),
        "{msg}"
    );
    let path = dir.join("two.mcap");
    mcap_file(
        &path,
        "/a",
        "json",
        None,
        &[(0, b"{\"a\": 1}".to_vec())],
        true,
    );
    let msg = Recording::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("several topics (/a, /notes)") && msg.contains("/recording"),
        "{msg}"
    );
    let path = dir.join("bad.mcap");
    mcap_file(
        &path,
        "/recording",
        "json",
        None,
        &[(0, b"{oops".to_vec())],
        false,
    );
    let msg = Recording::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("bad.mcap") && msg.contains("is not JSON"),
        "{msg}"
    );
    // text where a number belongs, and two time bases in one recording
    for (name, messages, needle) in [
        (
            "text.mcap",
            vec![
                (0, b"{\"time_s\": 0, \"a\": 21.0}".to_vec()),
                (1, b"{\"time_s\": 30, \"a\": \"21.5\"}".to_vec()),
            ],
            "field `a` is not a number or null",
        ),
        (
            "notime.mcap",
            vec![(0, b"{\"time_s\": null, \"a\": 1}".to_vec())],
            "`time_s` is missing",
        ),
        (
            "mixed.mcap",
            vec![
                (0, b"{\"time_s\": 0, \"a\": 1}".to_vec()),
                (2_000_000_000, b"{\"a\": 2}".to_vec()),
            ],
            "one time base per recording",
        ),
    ] {
        let path = dir.join(name);
        mcap_file(&path, "/recording", "json", None, &messages, false);
        let msg = Recording::read(&path).unwrap_err().to_string();
        assert!(msg.contains(name) && msg.contains(needle), "{msg}");
    }
}

/// A truncated MCAP recording is refused (with the way out), not read in part.
#[test]
fn core_recording_refuses_a_cut_off_mcap() {
    let dir = common::tmpdir("core_recording_cut");
    let path = dir.join("rec.mcap");
    let msgs: Vec<(u64, Vec<u8>)> = (0..200)
        .map(|k| {
            (
                k * 1_000_000_000,
                format!("{{\"time_s\": {k}, \"a\": {k}}}").into_bytes(),
            )
        })
        .collect();
    mcap_file(&path, "/recording", "json", None, &msgs, false);
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let msg = Recording::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("rec.mcap")
            && msg.contains("not a readable MCAP file")
            && msg.contains("orbitlash recover"),
        "{msg}"
    );
}

/// Issue 27 item 18: a JSON message with a key given twice is refused, as a CSV header
/// given twice is (the last value was silently kept).
#[test]
fn core_json_mcap_with_a_key_twice_is_refused() {
    let dir = std::env::temp_dir().join(format!("orbitlash-json-dup-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("dup.mcap");
    let msgs: Vec<(u64, Vec<u8>)> = (0..5u64)
        .map(|k| {
            (
                k * 30_000_000_000,
                format!("{{\"time_s\": {}, \"a\": 1.0, \"a\": {k}}}", k * 30).into_bytes(),
            )
        })
        .collect();
    mcap_file(&path, "/recording", "json", None, &msgs, false);
    let msg = Recording::read(&path).unwrap_err().to_string();
    assert!(
        msg.contains("dup.mcap") && msg.contains("field `a` is given twice"),
        "{msg}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

//! Recordings as satellites send them (`[recording]`): a UTC time column counted from
//! the scenario's start, columns that are not sensors, repeated time stamps merged when
//! equal and refused (or averaged, when the scenario says so) when not, and the rows a
//! ground segment repeats where no packet arrived kept out as fill.

use orbitlash::io::recording::{DuplicateTimes, Recording, RecordingFormat, TimeFormat};
use orbitlash::spec::scenario::sensor_name_of;
use sgp4::chrono::NaiveDate;

fn utc_format() -> RecordingFormat {
    RecordingFormat {
        time_column: "UTC".into(),
        time: TimeFormat::Utc {
            origin: NaiveDate::from_ymd_opt(2016, 2, 4)
                .unwrap()
                .and_hms_opt(0, 0, 0)
                .unwrap(),
        },
        ignore_columns: vec!["Battery mV".into()],
        repeated_rows_are_fill: true,
        duplicate_times: DuplicateTimes::Refuse,
        time_offset_s: 0.0,
        eclipse: None,
    }
}

fn read(text: &str, f: &RecordingFormat) -> Result<Recording, String> {
    Recording::from_csv_with(text.as_bytes(), "wod.csv", f).map_err(|e| e.to_string())
}

#[test]
fn core_utc_time_counts_from_the_start_and_ignored_columns_are_no_channels() {
    let text = "UTC,Panel deg. C,Battery mV\n\
                2016-02-04 00:00:00.0,1.5,8200\n\
                2016-02-04T00:01:00Z,2.5,8210\n\
                2016-02-04 01:00:30.5,3.5,8220\n";
    let r = read(text, &utc_format()).unwrap();
    assert_eq!(r.columns, vec!["Panel deg. C".to_string()]);
    assert_eq!(r.time_s, vec![0.0, 60.0, 3630.5]);
    assert_eq!(r.values[0], vec![Some(1.5), Some(2.5), Some(3.5)]);
    // before the start, and not a date
    let e = read(
        "UTC,Panel deg. C,Battery mV\n2016-02-03 23:59:00,1,2\n",
        &utc_format(),
    )
    .unwrap_err();
    assert!(
        e.contains("wod.csv:2:1") && e.contains("before the scenario's start_utc"),
        "{e}"
    );
    // a clock offset is added to every stamp, and named when it puts a row before the
    // start
    let late = RecordingFormat {
        time_offset_s: 25.0,
        ..utc_format()
    };
    assert_eq!(read(text, &late).unwrap().time_s, vec![25.0, 85.0, 3655.5]);
    let early = RecordingFormat {
        time_offset_s: -30.0,
        ..utc_format()
    };
    let e = read(text, &early).unwrap_err();
    assert!(
        e.contains("wod.csv:2:1") && e.contains("time_offset_s (-30 s)"),
        "{e}"
    );
    let e = read(
        "UTC,Panel deg. C,Battery mV\nyesterday,1,2\n",
        &utc_format(),
    )
    .unwrap_err();
    assert!(
        e.contains("wod.csv:2:1") && e.contains("not a UTC date-time"),
        "{e}"
    );
    // the time column and the ignored columns must be there
    let e = read("time,Panel deg. C,Battery mV\n", &utc_format()).unwrap_err();
    assert!(
        e.contains("no `UTC` column") && e.contains("[recording]"),
        "{e}"
    );
    let e = read("UTC,Panel deg. C\n2016-02-04 00:00:00,1\n", &utc_format()).unwrap_err();
    assert!(
        e.contains("ignore_columns names") && e.contains("Battery mV"),
        "{e}"
    );
}

#[test]
fn core_repeated_time_stamps_merge_when_equal_and_are_refused_or_averaged_when_not() {
    let equal = "UTC,a,Battery mV\n\
                 2016-02-04 00:00:00,1,5\n\
                 2016-02-04 00:01:00,2,6\n\
                 2016-02-04 00:01:00,2,6\n\
                 2016-02-04 00:02:00,3,7\n";
    let r = read(equal, &utc_format()).unwrap();
    assert_eq!(r.time_s, vec![0.0, 60.0, 120.0]);
    assert_eq!(r.merged_rows, vec![4]);
    assert!(r.fill_rows.is_empty());
    let differ = equal.replacen(
        "00:01:00,2,6\n2016-02-04 00:01:00,2,6",
        "00:01:00,2,6\n2016-02-04 00:01:00,4,6",
        1,
    );
    let e = read(&differ, &utc_format()).unwrap_err();
    assert!(
        e.contains("wod.csv:4:1")
            && e.contains("same time stamp as line 3")
            && e.contains("duplicate_times = \"mean\""),
        "{e}"
    );
    let mean = RecordingFormat {
        duplicate_times: DuplicateTimes::Mean,
        ..utc_format()
    };
    let r = read(&differ, &mean).unwrap();
    assert_eq!(r.values[0], vec![Some(1.0), Some(3.0), Some(3.0)]);
    assert_eq!(r.merged_rows, vec![4]);
    // time going back is an error in any case
    let back = "UTC,a,Battery mV\n2016-02-04 00:02:00,1,5\n2016-02-04 00:01:00,2,6\n";
    let e = read(back, &mean).unwrap_err();
    assert!(
        e.contains("wod.csv:3:1") && e.contains("does not increase"),
        "{e}"
    );
}

/// Fill: a row whose every cell (ignored columns included) repeats the row before is
/// kept as a time with no readings; a row that differs in any cell is data.
#[test]
fn core_rows_repeating_the_row_before_are_fill() {
    let text = "UTC,a,b,Battery mV\n\
                2016-02-04 00:00:00,1,2,8200\n\
                2016-02-04 00:01:00,1,2,8200\n\
                2016-02-04 00:02:00,1,2,8200\n\
                2016-02-04 00:03:00,1,2,8201\n\
                2016-02-04 00:04:00,5,6,8202\n";
    let r = read(text, &utc_format()).unwrap();
    assert_eq!(r.fill_rows, vec![3, 4]);
    assert_eq!(
        r.values[0],
        vec![Some(1.0), None, None, Some(1.0), Some(5.0)]
    );
    assert_eq!(
        r.values[1],
        vec![Some(2.0), None, None, Some(2.0), Some(6.0)]
    );
    // as data when the scenario does not say otherwise
    let data = RecordingFormat {
        repeated_rows_are_fill: false,
        ..utc_format()
    };
    let r = read(text, &data).unwrap();
    assert!(r.fill_rows.is_empty());
    assert_eq!(r.values[0][1], Some(1.0));
}

#[test]
fn core_telemetry_columns_get_channel_names() {
    for (column, name) in [
        ("housing_c", "housing_c"),
        ("Black Chassis deg. C", "black_chassis_deg_c"),
        ("Solar Panel +X deg. C", "solar_panel_px_deg_c"),
        ("Solar Panel -X deg. C", "solar_panel_mx_deg_c"),
        ("Tot. Photo Curr. mA", "tot_photo_curr_ma"),
        ("  ", "channel"),
    ] {
        assert_eq!(sensor_name_of(column), name, "{column}");
        orbitlash::spec::scenario::check_name(&sensor_name_of(column)).unwrap();
    }
}

/// Issue 27 item 7: an empty cell is no reading, so it does not count in a mean of
/// rows sharing a stamp (10, empty, 20 → 15, not 13.333), in any position.
#[test]
fn core_mean_of_a_shared_stamp_counts_readings_not_rows() {
    let mean = RecordingFormat {
        duplicate_times: DuplicateTimes::Mean,
        ..utc_format()
    };
    let text = "UTC,a,b,Battery mV\n\
                2016-02-04 00:00:00,10,,1\n\
                2016-02-04 00:00:00,,4,2\n\
                2016-02-04 00:00:00,20,8,3\n\
                2016-02-04 00:01:00,,,4\n\
                2016-02-04 00:01:00,7,,5\n";
    let r = read(text, &mean).unwrap();
    assert_eq!(r.values[0], vec![Some(15.0), Some(7.0)]);
    assert_eq!(r.values[1], vec![Some(6.0), None]);
    // each row of a stamp is compared with the one before it: 10, 20, 10 is a mean of
    // three readings (the third equals the first, not the second)
    let text = "UTC,a,Battery mV\n\
                2016-02-04 00:00:00,10,1\n\
                2016-02-04 00:00:00,20,1\n\
                2016-02-04 00:00:00,10,1\n\
                2016-02-04 00:01:00,5,2\n\
                2016-02-04 00:01:00,5,2\n";
    let r = read(text, &mean).unwrap();
    assert!(
        (r.values[0][0].unwrap() - 40.0 / 3.0).abs() < 1e-12,
        "{:?}",
        r.values[0]
    );
    // an equal repeat of a stamp is one reading
    assert_eq!(r.values[0][1], Some(5.0));
    // a fill row (the row before repeated) holds no reading: readings merged into its
    // stamp average among themselves
    let text = "UTC,a,Battery mV\n\
                2016-02-04 00:00:00,1,7\n\
                2016-02-04 00:01:00,1,7\n\
                2016-02-04 00:01:00,4,8\n\
                2016-02-04 00:01:00,6,9\n";
    let r = read(text, &mean).unwrap();
    assert_eq!(r.values[0], vec![Some(1.0), Some(5.0)]);
}

/// A clock's offset moves a recording's eclipse entries and exits alike; a shadow of
/// the wrong size moves them apart, and is no clock's offset.
#[test]
fn core_a_clock_offset_moves_entries_and_exits_alike() {
    use orbitlash::recording::EclipseCheck;
    let check = |entries_s: Vec<f64>, exits_s: Vec<f64>| EclipseCheck {
        column: "photo".into(),
        below: 20.0,
        rows: 100,
        agreement: 0.99,
        row_interval_s: 60.0,
        entries_s,
        exits_s,
    };
    let early = check(
        vec![-20.0, -22.0, -20.0, -22.0],
        vec![-21.0, -19.0, -21.0, -19.0],
    );
    assert_eq!(early.clock_offset_s(), Some(-20.5));
    // each rule alone, on edges known to the second (the standard error then allows
    // every mean below)
    let exact = |entries_s: Vec<f64>, exits_s: Vec<f64>| EclipseCheck {
        row_interval_s: 1.0,
        ..check(entries_s, exits_s)
    };
    assert_eq!(
        exact(vec![-30.0, -30.0], vec![-30.0, -30.0]).clock_offset_s(),
        Some(-30.0)
    );
    // a longer shadow: entries early, exits late
    assert_eq!(
        exact(vec![-40.0, -40.0], vec![20.0, 20.0]).clock_offset_s(),
        None
    );
    // within 10 s, one edge of a kind, or one kind near zero is no finding
    assert_eq!(
        exact(vec![-8.0, -9.0], vec![-8.0, -9.0]).clock_offset_s(),
        None
    );
    assert_eq!(
        exact(vec![-30.0], vec![-30.0, -30.0]).clock_offset_s(),
        None
    );
    assert_eq!(
        exact(vec![-30.0, -30.0], vec![-2.0, -2.0]).clock_offset_s(),
        None
    );
    // rows that mostly disagree with the shadow tell nothing
    let poor = EclipseCheck {
        agreement: 0.8,
        ..exact(vec![-30.0, -30.0], vec![-30.0, -30.0])
    };
    assert_eq!(poor.clock_offset_s(), None);
    // but they are a disagreement of their own, which the offset rule cannot judge
    assert!(poor.disagrees() && !early.disagrees());
    // eight edges of hourly rows: a mean of 20 s is inside three standard errors
    // (3 × 3600 / √96 s)
    let hourly = EclipseCheck {
        row_interval_s: 3600.0,
        ..early.clone()
    };
    assert_eq!(hourly.clock_offset_s(), None);
}

/// The eclipse check on a circular orbit (no shared data): a photo-current every
/// minute whose stamps run 40 s late gives entries and exits 40 ± 30 s late and that
/// clock offset; on time, no offset; a gap and a one-row flicker make no edge; an empty
/// column makes no edge and no offset.
#[test]
fn core_the_eclipse_check_finds_a_late_clock_on_a_circular_orbit() {
    use orbitlash::orbit::EnvironmentModel;
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/reference-hinge.toml"),
    )
    .unwrap();
    let sc = orbitlash::io::scenario_toml::parse(&text, "r.toml").unwrap();
    let env = &sc.thermal.environment;
    let period = env.mean_period_s();
    let photo = |late_s: f64, flicker: bool| {
        let (mut time_s, mut values) = (Vec::new(), Vec::new());
        let mut t = 60.0;
        while t < 4.0 * period {
            // twenty minutes without packets in the second orbit
            if !(t > 1.2 * period && t < 1.2 * period + 1200.0) {
                time_s.push(t);
                let lit = env.sun_fraction(t - late_s) >= 0.5;
                values.push(Some(if lit { 300.0 } else { 0.0 }));
            }
            t += 60.0;
        }
        if flicker {
            // one dark reading in sunlight, after the second orbit, five to seven
            // minutes before an eclipse: within reach of that entry
            let k = time_s
                .iter()
                .position(|&t| {
                    t > 2.0 * period
                        && [-120.0, 0.0, 120.0, 300.0]
                            .iter()
                            .all(|d| env.sun_fraction(t + d) == 1.0)
                        && env.sun_fraction(t + 420.0) == 0.0
                })
                .unwrap();
            values[k] = Some(0.0);
        }
        Recording {
            file: "pc.csv".into(),
            columns: vec!["pc".into()],
            rows_at: (1..=time_s.len() as u64).collect(),
            values: vec![values],
            time_s,
            fill_rows: Vec::new(),
            merged_rows: Vec::new(),
        }
    };
    let late = photo(40.0, false).eclipse_check("pc", 20.0, env).unwrap();
    assert_eq!(late.row_interval_s, 60.0);
    assert!(
        late.entries_s.len() >= 3 && late.exits_s.len() >= 3,
        "{late:?}"
    );
    for e in late.entries_s.iter().chain(&late.exits_s) {
        assert!((e - 40.0).abs() <= 30.0 + 1e-6, "{late:?}");
    }
    let m = late.clock_offset_s().expect("a late clock");
    assert!((m - 40.0).abs() < 15.0, "{m}");
    assert!(late.agreement > 0.95, "{late:?}");
    // a flicker is no edge
    let flickers = photo(40.0, true).eclipse_check("pc", 20.0, env).unwrap();
    assert_eq!(flickers.entries_s, late.entries_s);
    assert_eq!(flickers.exits_s, late.exits_s);
    // on time: the edges straddle zero and tell no offset
    let on_time = photo(0.0, false).eclipse_check("pc", 20.0, env).unwrap();
    assert_eq!(on_time.clock_offset_s(), None, "{on_time:?}");
    assert!(!on_time.disagrees() && !late.disagrees());
    // a clock a quarter of an hour late: the rows disagree with the shadow (an eclipse
    // lasts about 35 minutes), which is said, not hidden behind the offset rule
    let far = photo(900.0, false).eclipse_check("pc", 20.0, env).unwrap();
    assert!(far.agreement < 0.9 && far.disagrees(), "{far:?}");
    // no readings: no edges
    let mut empty = photo(0.0, false);
    empty.values[0].iter_mut().for_each(|v| *v = None);
    let none = empty.eclipse_check("pc", 20.0, env).unwrap();
    assert_eq!((none.rows, none.entries_s.len()), (0, 0));
    assert_eq!(none.clock_offset_s(), None);
    assert!(!none.disagrees());
    // a column that is not there is named
    let e = late_missing(&photo(0.0, false), env);
    assert!(
        e.contains("no `sun` column") && e.contains("eclipse_column"),
        "{e}"
    );
}

fn late_missing(r: &Recording, env: &impl orbitlash::orbit::EnvironmentModel) -> String {
    r.eclipse_check("sun", 20.0, env).unwrap_err().to_string()
}

//! Telemetry in the scenario: `[recording]` and sensors that name a recording's own
//! columns; bad definitions are refused naming the file, line and key; and FUNcube-1's
//! day of flight telemetry reads with its fill and repeated stamps reported.

mod common;
use common::{assert_check_refuses, assert_error, bin, shared, tmpdir};
use std::path::Path;

fn funcube_text() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/funcube-1.toml"))
        .unwrap()
}

#[test]
fn cli_bad_recording_layouts_and_sensors_are_refused_with_key_and_line() {
    let dir = tmpdir("telemetry-bad");
    let text = funcube_text();
    let cases: [(&str, &str, &str, &[&str]); 14] = [
        (
            "time-format",
            "time_format = \"utc\"",
            "time_format = \"gps\"",
            &[
                "`recording.time_format`",
                "unknown variant `gps`",
                "`seconds` or `utc`",
            ],
        ),
        (
            "repeated",
            "repeated_rows = \"fill\"",
            "repeated_rows = \"maybe\"",
            &[
                "`recording.repeated_rows`",
                "unknown variant `maybe`",
                "`data` or `fill`",
            ],
        ),
        (
            "duplicates",
            "duplicate_times = \"mean\"",
            "duplicate_times = \"last\"",
            &[
                "`recording.duplicate_times`",
                "unknown variant `last`",
                "`refuse` or `mean`",
            ],
        ),
        (
            "clock",
            "time_offset_s = 25.0",
            "time_offset_s = nan",
            &["`recording.time_offset_s`", "finite"],
        ),
        (
            "eclipse-ignored",
            "  \"Battery mV\",\n",
            "  \"Battery mV\",\n  \"Tot. Photo Curr. mA\",\n",
            &["`recording.eclipse_column`", "also in ignore_columns"],
        ),
        (
            "eclipse-sensor",
            "eclipse_column = \"Tot. Photo Curr. mA\"",
            "eclipse_column = \"Black Chassis deg. C\"",
            &["`recording.eclipse_column`", "a [[sensor]]'s column"],
        ),
        (
            "sensor-ignored",
            "  \"Battery mV\",\n",
            "  \"Battery mV\",\n  \"Black Chassis deg. C\",\n",
            &[
                "`sensor.chassis_black_c.column`",
                "ignored column",
                "read or ignored, not both",
            ],
        ),
        (
            "sensor-time",
            "column = \"Silver Chassis deg. C\"",
            "column = \"Satellite Date/Time UTC\"",
            &["`sensor.chassis_silver_c.column`", "time column"],
        ),
        (
            "eclipse-below",
            "eclipse_below = 20.0\n",
            "",
            &["`recording.eclipse_below`", "is missing"],
        ),
        (
            "clock-range",
            "time_offset_s = 25.0",
            "time_offset_s = 1e6",
            &["`recording.time_offset_s`", "86400"],
        ),
        (
            "unit",
            "name = \"chassis_black_c\"\nnode = \"chassis\"\nunit = \"C\"",
            "name = \"chassis_black_c\"\nnode = \"chassis\"\nunit = \"F\"",
            &["`sensor.chassis_black_c.unit`", "unknown variant `F`"],
        ),
        (
            "face",
            "face = \"px\"",
            "face = \"qx\"",
            &["`sensor.panel_px_c.face`", "unknown face `qx`", "known: px"],
        ),
        (
            "node-and-face",
            "face = \"px\"",
            "face = \"px\"\nnode = \"chassis\"",
            &["`sensor.panel_px_c.face`", "not both"],
        ),
        (
            "same-name",
            "name = \"chassis_silver_c\"",
            "name = \"chassis_black_c\"",
            &["`sensor", "names the channel `chassis_black_c`"],
        ),
    ];
    for (case, old, new, needles) in cases {
        assert!(text.contains(old), "{case}: `{old}` not in the scenario");
        assert_check_refuses(&dir, case, &text.replacen(old, new, 1), needles);
    }
    // UTC time needs a dated scenario
    let reference = common::reference_text() + "\n[recording]\ntime_format = \"utc\"\n";
    let file = dir.join("utc-circular.toml");
    std::fs::write(&file, reference).unwrap();
    let out = bin().arg("check").arg(&file).output().unwrap();
    assert_error(
        "utc-circular",
        &out,
        &["`recording.time_format`", "needs a dated scenario"],
    );
}

/// FUNcube-1's day: 1394 rows, 226 of them the warehouse's fill and two time stamps
/// given twice (lines 392 and 638), reported by `diagnose` and kept out of its numbers.
#[test]
fn cli_funcube_telemetry_reads_with_its_fill_and_repeated_stamps() {
    let Some(csv) = shared("data/funcube-1/funcube1_wod_2016-02-04.csv") else {
        return;
    };
    let format = orbitlash::io::scenario_toml::parse(&funcube_text(), "funcube-1.toml")
        .unwrap()
        .recording;
    let mut rec = orbitlash::io::recording::Recording::read_with(&csv, &format).unwrap();
    assert_eq!(rec.time_s.len() + rec.merged_rows.len(), 1394);
    assert_eq!(rec.merged_rows, vec![392, 638]);
    assert_eq!(rec.fill_rows.len(), 226);
    // the eight temperatures and the photo-current (`eclipse_column`)
    assert_eq!(rec.columns.len(), 9);
    assert!(rec.remove_channel("Tot. Photo Curr. mA"));
    let scenario = orbitlash::io::scenario_toml::parse(&funcube_text(), "funcube-1.toml").unwrap();
    rec.name_channels(&scenario.sensors);
    assert!(rec.columns.contains(&"chassis_black_c".to_string()));
    rec.match_sensors(&scenario.sensors).unwrap();
    // a fill row has no readings
    let k = rec
        .rows_at
        .iter()
        .position(|&l| l == rec.fill_rows[0])
        .unwrap();
    assert!(rec.values.iter().all(|c| c[k].is_none()));
    // refused without the scenario's policy for repeated stamps, naming both lines
    let dir = tmpdir("telemetry-refuse");
    let file = dir.join("refuse.toml");
    std::fs::write(
        &file,
        funcube_text().replacen("duplicate_times = \"mean\"", "", 1),
    )
    .unwrap();
    let out = bin()
        .args(["diagnose"])
        .arg(&file)
        .arg("--recording")
        .arg(&csv)
        .output()
        .unwrap();
    assert_error(
        "refuse",
        &out,
        &[
            "funcube1_wod_2016-02-04.csv:392:1",
            "same time stamp as line 391",
        ],
    );
}

/// `diagnose` checks the recording's clock on its eclipse column (FUNcube-1's
/// photo-current): with the scenario's 25 s offset the edges straddle zero; with the
/// stamps as sent they come early by about that much, entries and exits alike, and a
/// warning gives the offset to set.
#[test]
fn cli_diagnose_checks_the_recordings_clock_on_its_eclipses() {
    let Some(csv) = shared("data/funcube-1/funcube1_wod_2016-02-04.csv") else {
        return;
    };
    let dir = tmpdir("telemetry-clock");
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/funcube-1.toml");
    let report = |name: &str, sets: &[&str]| {
        let json = dir.join(format!("{name}.json"));
        let mut cmd = bin();
        cmd.args(["diagnose"])
            .arg(&scenario)
            .arg("--recording")
            .arg(&csv)
            .arg("--json")
            .arg(&json)
            .arg("--quiet");
        for s in sets {
            cmd.args(["--set", s]);
        }
        let out = cmd.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{name}: {stderr}");
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        (v, stderr, String::from_utf8_lossy(&out.stdout).to_string())
    };
    let mean = |v: &serde_json::Value| {
        let a = v.as_array().unwrap();
        a.iter().map(|x| x.as_f64().unwrap()).sum::<f64>() / a.len() as f64
    };
    let (with, stderr, stdout) = report("with", &[]);
    assert!(
        stdout.contains("eclipses: `Tot. Photo Curr. mA` below 20 against the orbit's shadow: 99.49 % of 1166 rows agree; 12 entries -3.9 s, 11 exits +3.4 s"),
        "{stdout}"
    );
    // the channel table's columns line up with names longer than 13 characters
    // (chassis_silver_c): each row's noise figure ends where the header's "noise" does
    let header = stdout
        .lines()
        .find(|l| l.starts_with("channel ") && l.contains("noise"))
        .unwrap();
    let end = header.find("noise").unwrap() + "noise".len();
    let rows: Vec<&str> = stdout
        .lines()
        .skip_while(|l| *l != header)
        .skip(1)
        .take(8)
        .collect();
    assert!(
        rows.iter().any(|r| r.starts_with("chassis_silver_c ")),
        "{rows:?}"
    );
    for r in &rows {
        let noise_end = r.find(" K ").unwrap();
        assert_eq!(noise_end, end, "{header}\n{r}");
    }
    let e = &with["recording"]["eclipses"];
    assert_eq!(e["column"], "Tot. Photo Curr. mA");
    assert_eq!(e["rows"], 1166);
    assert!(e["agreement"].as_f64().unwrap() > 0.99, "{e}");
    assert!(e["entries_s"].as_array().unwrap().len() >= 10, "{e}");
    assert!(
        mean(&e["entries_s"]).abs() < 10.0 && mean(&e["exits_s"]).abs() < 10.0,
        "{e}"
    );
    assert!(!stderr.contains("clock is off"), "{stderr}");
    // the photo-current is no channel of the fit
    assert_eq!(with["heldout_rmse"].as_object().unwrap().len(), 8);
    let (sent, stderr, _) = report("as-sent", &["recording.time_offset_s=0"]);
    let e = &sent["recording"]["eclipses"];
    assert!(
        mean(&e["entries_s"]) < -15.0 && mean(&e["exits_s"]) < -15.0,
        "{e}"
    );
    assert!(
        stderr.contains("clock is off") && stderr.contains("time_offset_s = 25 (now 0)"),
        "{stderr}"
    );
    // Ten minutes off: the rows disagree with the shadow on a fifth of the day, and
    // the warning says so (the offset rule asks for 90 % agreement).
    let (far, stderr, _) = report("far", &["recording.time_offset_s=625"]);
    assert!(
        stderr.contains("agree with the orbit's shadow on only")
            && stderr.contains("its clock ([recording] time_offset_s, now 625 s)"),
        "{stderr}"
    );
    assert!(
        far["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("on only")),
        "{far}"
    );
    // A sensor whose column the recording lacks is named, not dropped in silence.
    let text = std::fs::read_to_string(&csv).unwrap();
    let without: String = text
        .lines()
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            cells.remove(2);
            cells.join(",") + "\n"
        })
        .collect();
    let cut = dir.join("without-silver-chassis.csv");
    std::fs::write(&cut, without).unwrap();
    let out = bin()
        .arg("diagnose")
        .arg(&scenario)
        .arg("--recording")
        .arg(&cut)
        .arg("--quiet")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains(
            "sensor `chassis_silver_c` (column `Silver Chassis deg. C`) is not in the recording: diagnose fits the other 7 channel(s)"
        ),
        "{stderr}"
    );
}

/// User-declared uncertain numbers become calibration candidates within their bounds
/// (`[[uncertain]]`, and the `[[dispersion]]` entries: a uniform range, a normal's
/// mean ± 3 sd); a bad declaration is refused naming its line and key.
#[test]
fn cli_uncertain_numbers_are_calibration_candidates() {
    use orbitlash::diagnose::effects::{Hints, candidates};
    let text = funcube_text()
        + "\n[[uncertain]]\npath = \"conductor.panel_px-chassis.conductance_w_per_k\"\nmin = 0.1\nmax = 2.0\n\
           \n[[dispersion]]\npath = \"dissipation.electronics.power_w\"\ndistribution = \"normal\"\nmean = 1.3\nsd = 0.1\n";
    let spec = orbitlash::io::scenario_toml::parse_spec(&text, "u.toml").unwrap();
    let model = orbitlash::spec::model::Model::new(spec).unwrap();
    let cands = candidates(&model, &[], &Hints::default());
    let declared: Vec<_> = cands
        .iter()
        .filter(|c| c.effect.id() == "uncertain_parameter")
        .map(|c| (c.label(), c.params[0].lower, c.params[0].upper))
        .collect();
    assert_eq!(declared.len(), 2, "{declared:?}");
    assert_eq!(
        declared[0].0,
        "uncertain_parameter on conductor.panel_px-chassis.conductance_w_per_k"
    );
    assert_eq!((declared[0].1, declared[0].2), (0.1, 2.0));
    assert!((declared[1].1 - 1.0).abs() < 1e-12 && (declared[1].2 - 1.6).abs() < 1e-12);
    // the new calibrations: every node's thermal mass, every face's α and ε
    let count = |id: &str| cands.iter().filter(|c| c.effect.id() == id).count();
    assert_eq!(count("capacitance_scale"), 8);
    assert_eq!(count("emissivity_scale"), 6);
    assert!(count("absorptivity_scale") >= 6);

    let dir = tmpdir("uncertain-bad");
    for (case, block, needles) in [
        (
            "path",
            "path = \"conductor.panel_px-chassis.conductanc_w_per_k\"\nmin = 0.1\nmax = 2.0",
            &["`uncertain[0].path`", "no such number"][..],
        ),
        (
            "bounds",
            "path = \"conductor.panel_px-chassis.conductance_w_per_k\"\nmin = 2.0\nmax = 0.1",
            &["`uncertain[0].max`", "min < max"][..],
        ),
        (
            "range",
            "path = \"conductor.panel_px-chassis.conductance_w_per_k\"\nmin = -1.0\nmax = 2.0",
            &["`uncertain[0].min`", "cannot be -1"][..],
        ),
        // the key that is wrong is named (a NaN min was reported as `max`)
        (
            "nan",
            "path = \"conductor.panel_px-chassis.conductance_w_per_k\"\nmin = nan\nmax = 2.0",
            &["`uncertain[0].min`", "finite"][..],
        ),
        (
            "recording",
            "path = \"recording.time_offset_s\"\nmin = 0.0\nmax = 60.0",
            &["`uncertain[0].path`", "how a recording is read"][..],
        ),
    ] {
        assert_check_refuses(
            &dir,
            case,
            &(funcube_text() + "\n[[uncertain]]\n" + block + "\n"),
            needles,
        );
    }
    // a dispersed number is a calibration candidate too
    assert_check_refuses(
        &dir,
        "dispersed-clock",
        &(funcube_text()
            + "\n[[dispersion]]\npath = \"recording.time_offset_s\"\ndistribution = \"uniform\"\nmin = 0.0\nmax = 60.0\n"),
        &["`dispersion[0].path`", "how a recording is read"],
    );
}

/// Telemetry-driven inputs (`[[input]]`): a dissipation's power follows the system
/// current (W = 0.00825 × mA − 0.3), a boundary's temperature a channel in °C; the
/// driving channels leave the recording (inputs are not fitted); a bad `drives` or a
/// missing column is refused.
#[test]
fn cli_inputs_follow_recording_channels() {
    use orbitlash::spec::ProfileSpec;
    // a boundary's temperature, on the reference hinge
    let text = common::reference_text()
        + "\n[[input]]\ncolumn = \"bus_c\"\ndrives = \"boundary.bus.temperature_k\"\noffset = 273.15\n";
    let spec = orbitlash::io::scenario_toml::parse_spec(&text, "in.toml").unwrap();
    let mut model = orbitlash::spec::model::Model::new(spec).unwrap();
    let mut rec = orbitlash::io::recording::Recording::from_csv(
        b"time_s,housing_c,bus_c\n0,20,10\n60,21,\n120,22,12\n",
        "rec.csv",
    )
    .unwrap();
    let done = rec.feed_inputs(&mut model).unwrap();
    assert_eq!(done.len(), 1, "{done:?}");
    assert_eq!(rec.columns, vec!["housing_c".to_string()]);
    let bus = model
        .spec()
        .boundary
        .iter()
        .find(|b| b.name == "bus")
        .unwrap();
    match &bus.temperature_k {
        ProfileSpec::Table(t) => {
            assert_eq!(t.time_s.as_deref(), Some(&[0.0, 120.0][..]));
            assert_eq!(t.value, vec![283.15, 285.15]);
        }
        other => panic!("{other:?}"),
    }
    // a missing column
    let mut rec =
        orbitlash::io::recording::Recording::from_csv(b"time_s,housing_c\n0,20\n", "r.csv")
            .unwrap();
    let e = rec.feed_inputs(&mut model).unwrap_err();
    assert!(e.to_string().contains("no column `bus_c`"), "{e}");
    // a reading the model refuses (below 0 K) is named by its line and value
    let mut rec = orbitlash::io::recording::Recording::from_csv(
        b"time_s,housing_c,bus_c\n0,20,10\n60,21,11\n120,22,-400\n180,23,12\n",
        "r.csv",
    )
    .unwrap();
    let e = rec.feed_inputs(&mut model).unwrap_err().to_string();
    assert!(
        e.starts_with("r.csv:4: the reading -400 of `bus_c`: ")
            && e.contains("boundary.bus.temperature_k"),
        "{e}"
    );

    // FUNcube-1's dissipation from its system current
    let Some(csv) = shared("data/funcube-1/funcube1_wod_2016-02-04.csv") else {
        return;
    };
    let text = funcube_text().replacen("  \"Tot. System Curr. mA\",\n", "", 1)
        + "\n[[input]]\ncolumn = \"Tot. System Curr. mA\"\ndrives = \"dissipation.electronics.power_w\"\nscale = 0.00825\noffset = -0.3\n";
    let dir = tmpdir("inputs");
    let file = dir.join("fin.toml");
    std::fs::write(&file, &text).unwrap();
    let spec = orbitlash::io::scenario_toml::parse_spec(&text, "fin.toml").unwrap();
    let mut model = orbitlash::spec::model::Model::new(spec).unwrap();
    let mut rec =
        orbitlash::io::recording::Recording::read_with(&csv, &model.scenario().recording).unwrap();
    rec.feed_inputs(&mut model).unwrap();
    // the temperatures and the photo-current (the eclipse column `diagnose` takes out)
    assert_eq!(rec.columns.len(), 9);
    match &model.spec().dissipation[0].power_w {
        ProfileSpec::Table(t) => {
            assert_eq!(t.value.len(), 1166);
            // the first row: 215 mA
            assert!((t.value[0] - (0.00825 * 215.0 - 0.3)).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    // a bad target, named with its line
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        text.replace(
            "dissipation.electronics.power_w",
            "dissipation.electrons.power_w",
        ),
    )
    .unwrap();
    let out = bin().arg("check").arg(&bad).output().unwrap();
    assert_error(
        "bad-input",
        &out,
        &[
            "bad.toml:",
            "`input[0].drives`",
            "not a boundary's temperature or a dissipation's power",
        ],
    );
}

/// The eclipse flag from a channel (`drives = "sunlit"`, dark `below` a reading): each
/// change of state halfway between the readings around it; across a gap of more than
/// ten minutes the last whole eclipse repeats every orbit; the run then steps on those
/// edges instead of the shadow's. Refused without `below`, with `below` elsewhere, and
/// on a circular orbit.
#[test]
fn cli_the_eclipse_flag_follows_a_channel() {
    use orbitlash::orbit::EnvironmentModel;
    let text = funcube_text()
        + "\n[[input]]\ncolumn = \"Tot. Photo Curr. mA\"\ndrives = \"sunlit\"\nbelow = 20.0\n";
    let spec = orbitlash::io::scenario_toml::parse_spec(&text, "sun.toml").unwrap();
    let mut model = orbitlash::spec::model::Model::new(spec).unwrap();
    let period = model.scenario().thermal.environment.mean_period_s();
    // lit, dark from 150 s (between 120 and 180) to 330 s, then a gap of two hours
    // (distinct readings: a row repeating the one before would be fill)
    let mut csv = String::from("UTC,Tot. Photo Curr. mA\n");
    for (t, pc) in [
        (60, 300),
        (120, 301),
        (180, 0),
        (240, 1),
        (300, 2),
        (360, 310),
        (7560, 300),
    ] {
        csv += &format!(
            "2016-02-04T{:02}:{:02}:{:02}Z,{pc}\n",
            t / 3600,
            t / 60 % 60,
            t % 60
        );
    }
    let format = orbitlash::recording::RecordingFormat {
        time_column: "UTC".into(),
        ignore_columns: Vec::new(),
        // the stamps as the edges below say (the scenario's clock offset aside)
        time_offset_s: 0.0,
        ..model.scenario().recording.clone()
    };
    let mut rec =
        orbitlash::io::recording::Recording::from_csv_with(csv.as_bytes(), "pc.csv", &format)
            .unwrap();
    rec.feed_inputs(&mut model).unwrap();
    assert!(rec.columns.is_empty());
    let w = model.spec().orbit.eclipses_s.clone().unwrap();
    assert_eq!(w[0], vec![150.0, 330.0]);
    assert_eq!(w[1], vec![150.0 + period, 330.0 + period], "{w:?}");
    assert_eq!(w.len(), 2, "{w:?}");
    let env = &model.scenario().thermal.environment;
    assert!(env.sunlit(149.0) && !env.sunlit(150.0) && !env.sunlit(329.9) && env.sunlit(330.0));
    assert_eq!(env.next_shadow_crossing(0.0, 1e6), Some((150.0, true)));
    assert_eq!(env.next_shadow_crossing(150.0, 1e6), Some((330.0, false)));

    let dir = tmpdir("sunlit-bad");
    for (case, text, needles) in [
        (
            "no-below",
            text.replace("\nbelow = 20.0\n", "\n"),
            &["`input[0].below`", "needs `below`"][..],
        ),
        (
            "below-elsewhere",
            funcube_text()
                + "\n[[input]]\ncolumn = \"x\"\ndrives = \"dissipation.electronics.power_w\"\nbelow = 1.0\n",
            &["`input[0].below`", "sunlit\" only"][..],
        ),
        (
            "windows",
            funcube_text().replacen(
                "shadow = \"conical\"",
                "shadow = \"conical\"\neclipses_s = [[100.0, 50.0]]",
                1,
            ),
            &["`orbit.eclipses_s[0]`", "entry before its exit"][..],
        ),
    ] {
        assert_check_refuses(&dir, case, &text, needles);
    }
    let circular =
        common::reference_text().replacen("[orbit]", "[orbit]\neclipses_s = [[0.0, 10.0]]", 1);
    let file = dir.join("circular.toml");
    std::fs::write(&file, circular).unwrap();
    let out = bin().arg("check").arg(&file).output().unwrap();
    assert_error("circular", &out, &["`orbit.eclipses_s`"]);
    // given eclipses are reported as given, not as the shadow's geometry
    let given = funcube_text().replacen(
        "shadow = \"conical\"",
        "shadow = \"conical\"\neclipses_s = [[100.0, 1900.0], [5900.0, 7700.0]]",
        1,
    );
    let file = dir.join("given.toml");
    std::fs::write(&file, given).unwrap();
    let out = bin().arg("check").arg(&file).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success()
            && text.contains("(the first orbit; the eclipses given, `orbit.eclipses_s`)")
            && !text.contains("conical shadow"),
        "{text}"
    );
}

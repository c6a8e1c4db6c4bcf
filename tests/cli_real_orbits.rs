//! Real orbits from the command line: `check` reports what a TLE orbit derives (β,
//! eclipse fraction, period, Sun distance), a dated run passes, and a bad TLE, a bad
//! date, a wrong shadow or a circular orbit's key beside a TLE is refused with an error
//! naming the file, line and key (exit 2, no panic).

use std::path::Path;

mod common;
use common::{assert_check_refuses, assert_error, bin, tmpdir};

fn tle_text() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-tle-year.toml"),
    )
    .unwrap()
}

/// `check` on the TLE scenario with `old` replaced by `new`; the line `old` is on.
fn check_with(dir: &Path, case: &str, old: &str, new: &str) -> (std::process::Output, usize) {
    let text = tle_text();
    let at = text
        .find(old)
        .unwrap_or_else(|| panic!("{case}: `{old}` not found"));
    let line = text[..at].matches('\n').count() + 1;
    let file = dir.join(format!("{case}.toml"));
    std::fs::write(&file, text.replacen(old, new, 1)).unwrap();
    (bin().arg("check").arg(&file).output().unwrap(), line)
}

#[test]
fn cli_check_reports_the_derived_orbit() {
    let out = bin()
        .arg("check")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-tle-year.toml"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "TLE orbit (SGP4)        epoch 2016-02-04T09:10:54Z",
        "period                  5834.5",
        "β at the start          43.4",
        "eclipse fraction        0.30",
        "Sun distance            0.985",
    ] {
        assert!(text.contains(needle), "`{needle}` missing:\n{text}");
    }
}

#[test]
fn cli_bad_tles_and_dates_are_refused_with_key_and_line() {
    let dir = tmpdir("real-orbits");
    let l1 = "1 39444U 13066AE  16035.38257241  .00000865  00000-0  11531-3 0  9990";
    let cases: [(&str, &str, &str, &[&str]); 8] = [
        (
            "checksum",
            l1,
            &l1.replace("0  9990", "0  9991"),
            &["`orbit.tle[0]`", "checksum 1", "sum to 150"],
        ),
        (
            "short",
            "262.6940 14.80829622117779",
            "262.6940 14.80829622",
            &["`orbit.tle[1]`", "has 63 characters"],
        ),
        (
            "one-line",
            "  \"2 39444  97.7004  94.3150 0060634  98.1157 262.6940 14.80829622117779\",\n",
            "",
            &["`orbit.tle`", "lists 1 line(s)"],
        ),
        (
            "date",
            "2016-02-04T00:00:00Z",
            "2016-02-30T00:00:00Z",
            &["`orbit.start_utc`", "not a UTC time"],
        ),
        (
            "far-from-epoch",
            "2016-02-04T00:00:00Z",
            "2016-06-04T00:00:00Z",
            &["`orbit.start_utc`", "days after the TLE's epoch"],
        ),
        (
            "shadow",
            "shadow = \"conical\"",
            "shadow = \"round\"",
            // a choice is refused by the reader, at its line (issue 28 item 2)
            &[
                "`orbit.shadow`",
                "unknown variant `round`",
                "`cylindrical` or `conical`",
            ],
        ),
        (
            "altitude-beside-tle",
            "shadow = \"conical\"",
            "altitude_m = 5.0e5",
            &["`orbit.altitude_m`", "follows from the TLE"],
        ),
        (
            "beta-beside-tle",
            "space_sink_k = 3.0",
            "space_sink_k = 3.0\nbeta_deg = 20.0",
            &["`environment.beta_deg`", "follows from the TLE"],
        ),
    ];
    for (case, old, new, needles) in cases {
        let (out, line) = check_with(&dir, case, old, new);
        let file = format!("{case}.toml:");
        let mut all: Vec<&str> = needles.to_vec();
        all.push(&file);
        assert_error(case, &out, &all);
        // the error points at the line the change is on (or the table holding it)
        let first = common::first_error_line(&out);
        let at: usize = first
            .split(&file)
            .nth(1)
            .and_then(|s| s.split(':').next())
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        assert!(
            at > 0 && at.abs_diff(line) <= 6,
            "{case}: error at line {at}, change at line {line}: {first}"
        );
    }
}

/// A step that ends on the umbra's edge of a cylindrical shadow sees the Sun at its
/// end, as in the circular model: the TLE orbit then steps through an eclipse entry
/// without retrying (before the fix every entry was retried about 15 times, the first
/// shadowed float at the step's end being a jump inside the step).
#[test]
fn cli_a_cylindrical_eclipse_edge_is_not_a_jump_inside_the_step() {
    let dir = tmpdir("cylinder-edge");
    let file = dir.join("cyl.toml");
    let text = tle_text();
    assert!(text.contains("shadow = \"conical\""));
    std::fs::write(
        &file,
        text.replacen("shadow = \"conical\"", "shadow = \"cylindrical\"", 1),
    )
    .unwrap();
    let out = bin()
        .arg("run")
        .arg(&file)
        .args(["--orbits", "20", "--no-log", "--quiet", "--json"])
        .arg(dir.join("s.json"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(json["events"]["eclipse_entries"], 20);
    let rejected = json["solver"]["rejected_steps"].as_u64().unwrap();
    assert!(rejected <= 20, "{rejected} rejected steps over 20 eclipses");
}

#[test]
fn cli_a_dated_run_passes_and_reports_its_beta_range() {
    let dir = tmpdir("real-orbit-run");
    let out = bin()
        .arg("run")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-tle-year.toml"))
        .args(["--orbits", "20", "--json"])
        .arg(dir.join("s.json"))
        .arg("--no-log")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("beta 43.4"), "{text}");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(json["verdict"], "pass");
}

#[test]
fn cli_environment_reports_eclipses_and_writes_the_series() {
    let dir = tmpdir("environment");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // Circular reference: two eclipses of 2φ/ω = 0.36959 × 5676.978 s = 2098.16 s.
    let out = bin()
        .arg("environment")
        .arg(root.join("scenarios/reference-hinge.toml"))
        .args(["--orbits", "2", "--csv"])
        .arg(dir.join("c.csv"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("eclipses: 2 (0.3696"), "{text}");
    assert!(text.contains("2098.16"), "{text}");
    let csv = std::fs::read_to_string(dir.join("c.csv")).unwrap();
    assert_eq!(
        csv.lines().next().unwrap(),
        "time_s,orbit_angle_deg,sun_fraction,beta_deg,solar_flux_w_per_m2,solar_flux_unshadowed_w_per_m2"
    );
    assert_eq!(csv.lines().count(), 1 + 721);
    // TLE, conical shadow: a dated series with a penumbra ramp between full and none.
    let out = bin()
        .arg("environment")
        .arg(root.join("scenarios/hinge-tle-year.toml"))
        .args(["--orbits", "1", "--step-s", "1", "--csv"])
        .arg(dir.join("t.csv"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("t.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time_s,utc,orbit_angle_deg,sun_fraction,beta_deg,solar_flux_w_per_m2,solar_flux_unshadowed_w_per_m2"
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert!(rows[0][1].starts_with("2016-02-04T00:00:00"));
    let lit: Vec<f64> = rows.iter().map(|r| r[3].parse().unwrap()).collect();
    let partial = lit.iter().filter(|&&f| f > 0.0 && f < 1.0).count();
    // two penumbra crossings of about 12 s each at 1 s rows
    assert!((16..=40).contains(&partial), "{partial} penumbra rows");
    assert!(lit.iter().all(|f| (0.0..=1.0).contains(f)));
    // the flux reaching the spacecraft is the log's (black-box helper-27: it was the
    // unshadowed flux under that name): the unshadowed one dimmed by the Sun's
    // fraction, 0 in the umbra, full in sunlight
    for r in &rows {
        let (f, reaching, unshadowed): (f64, f64, f64) = (
            r[3].parse().unwrap(),
            r[5].parse().unwrap(),
            r[6].parse().unwrap(),
        );
        assert!(unshadowed > 1300.0, "{r:?}");
        assert!((reaching - f * unshadowed).abs() < 0.01, "{r:?}");
    }
    assert!(rows.iter().any(|r| r[5] == "0.0000") && rows.iter().any(|r| r[3] == "1.000000"));
    // the output may not be the scenario it reads
    let copy = dir.join("s.toml");
    std::fs::copy(root.join("scenarios/hinge-tle-year.toml"), &copy).unwrap();
    let out = bin()
        .arg("environment")
        .arg(&copy)
        .arg("--csv")
        .arg(&copy)
        .output()
        .unwrap();
    assert_error("clobber", &out, &["s.toml"]);
    // a step longer than half the run is refused (it wrote one row, a point, not a
    // series); half the run exactly gives three rows
    let out = bin()
        .arg("environment")
        .arg(root.join("scenarios/reference-hinge.toml"))
        .args(["--step-s", "1e9", "--csv"])
        .arg(dir.join("one.csv"))
        .output()
        .unwrap();
    assert_error("step", &out, &["--step-s 1e9", "5677.0 s", "1 row(s)"]);
    assert!(!dir.join("one.csv").exists());
    let out = bin()
        .arg("environment")
        .arg(root.join("scenarios/reference-hinge.toml"))
        .args(["--step-s", "2838.489", "--csv"])
        .arg(dir.join("three.csv"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("three.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 3, "{csv}");
}

#[test]
fn cli_environment_writes_each_faces_fluxes() {
    let dir = tmpdir("environment-faces");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = bin()
        .arg("environment")
        .arg(root.join("scenarios/cubesat-1u.toml"))
        .args(["--orbits", "1", "--step-s", "60", "--csv"])
        .arg(dir.join("f.csv"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("f.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(header.len(), 7 + 6 * 3);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (ir_pz, ir_mz, sol_my) = (
        col("panel_pz.pz.earth_ir_w_per_m2"),
        col("panel_mz.mz.earth_ir_w_per_m2"),
        col("panel_my.my.solar_w_per_m2"),
    );
    for line in csv.lines().skip(1) {
        let v: Vec<&str> = line.split(',').collect();
        let num = |i: usize| v[i].parse::<f64>().unwrap();
        // nadir face: q (R/r)² with r within FUNcube-1's 6960 … 7050 km
        assert!((190.0..=202.0).contains(&num(ir_pz)), "{line}");
        assert_eq!(num(ir_mz), 0.0);
        // the −Y face (toward +orbit normal) sees S sin β in sunlight, none in eclipse
        let lit: f64 = num(3);
        let flux: f64 = num(6);
        assert!((num(5) - lit * flux).abs() < 0.01, "{line}");
        let beta = num(4).to_radians();
        assert!(
            (num(sol_my) - lit * flux * beta.sin()).abs() < 0.5,
            "{line}"
        );
    }
}

#[test]
fn cli_a_start_days_from_the_epoch_is_a_warning() {
    let dir = tmpdir("epoch-warning");
    let (out, _) = check_with(
        &dir,
        "six-days",
        "2016-02-04T00:00:00Z",
        "2016-02-10T00:00:00Z",
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("1 warning(s)"), "{text}");
    assert!(
        text.contains("starts 5.6 days from the TLE's epoch"),
        "{text}"
    );
    // a day from it is not
    let (out, _) = check_with(
        &dir,
        "one-day",
        "2016-02-04T00:00:00Z",
        "2016-02-05T00:00:00Z",
    );
    assert!(!String::from_utf8_lossy(&out.stdout).contains("warning(s)"));
}

#[test]
fn cli_a_dated_log_is_on_utc_and_reads_back_from_zero() {
    let dir = tmpdir("utc-log");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let log = dir.join("tle.mcap");
    let out = bin()
        .arg("run")
        .arg(root.join("scenarios/hinge-tle-year.toml"))
        .args(["--orbits", "1", "--out"])
        .arg(&log)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = orbitlash::io::mcap_read::read_log(&log).unwrap();
    // 2016-02-04T00:00:00Z
    let start_ns = 1_454_544_000u64 * 1_000_000_000;
    assert_eq!(table.time_origin_ns, start_ns);
    assert_eq!(table.rows[0].0, start_ns);
    assert!(table.rows.last().unwrap().0 > start_ns + 5_000 * 1_000_000_000);
    // the CSV export counts from the start
    let csv = dir.join("tle.csv");
    let out = bin()
        .arg("export-csv")
        .arg(&log)
        .arg("--out")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.lines().nth(1).unwrap().starts_with("0.000,"),
        "{text:.200}"
    );
}

#[test]
fn cli_bad_attitudes_and_faces_are_refused_with_key_and_line() {
    let dir = tmpdir("faces-bad");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/cubesat-1u.toml"),
    )
    .unwrap();
    let cases: [(&str, &str, &str, &[&str]); 11] = [
        (
            "mode",
            "mode = \"nadir\"",
            "mode = \"spinning\"",
            &["`attitude.mode`", "unknown variant `spinning`"],
        ),
        (
            "yaw-not-nadir",
            "mode = \"nadir\"",
            "mode = \"sun\"",
            &["`attitude.yaw_deg`", "mode `sun` has no yaw"],
        ),
        (
            "no-quaternion",
            "mode = \"nadir\"\nyaw_deg = 0.0",
            "mode = \"inertial\"",
            &["`attitude`", "needs `quaternion"],
        ),
        (
            "short-quaternion",
            "mode = \"nadir\"\nyaw_deg = 0.0",
            "mode = \"inertial\"\nquaternion = [1.0, 0.0]",
            &["`attitude.quaternion`", "lists 2 number(s)"],
        ),
        (
            "spin-no-axis",
            "mode = \"nadir\"\nyaw_deg = 0.0",
            "mode = \"spin\"\nspin_rate_deg_per_s = 3.0",
            &["`attitude`", "needs `spin_axis"],
        ),
        (
            "spin-zero-axis",
            "mode = \"nadir\"\nyaw_deg = 0.0",
            "mode = \"spin\"\nspin_axis = [0.0, 0.0, 0.0]\nspin_rate_deg_per_s = 3.0",
            &["`attitude.spin_axis`", "zero vector"],
        ),
        (
            "spin-rate",
            "mode = \"nadir\"\nyaw_deg = 0.0",
            "mode = \"spin\"\nspin_axis = [0.0, 0.0, 1.0]\nspin_rate_deg_per_s = 1000.0",
            &[
                "`attitude.spin_rate_deg_per_s`",
                "must be within -720 … 720",
            ],
        ),
        (
            "spin-key-not-spin",
            "mode = \"nadir\"\nyaw_deg = 0.0",
            "mode = \"sun\"\nspin_axis = [0.0, 0.0, 1.0]",
            &["`attitude.spin_axis`", "give mode = \"spin\""],
        ),
        (
            "zero-normal",
            "normal = [1.0, 0.0, 0.0]",
            "normal = [0.0, 0.0, 0.0]",
            &["`face.px.normal`", "zero vector"],
        ),
        (
            "emissivity",
            "emissivity = 0.85",
            "emissivity = 1.5",
            &["`face.px.emissivity`", "emissivity must be within 0 … 1"],
        ),
        (
            "node",
            "node = \"panel_px\"\nname = \"px\"",
            "node = \"panel_qx\"\nname = \"px\"",
            &["`face.px.node`", "unknown node `panel_qx`"],
        ),
    ];
    for (case, old, new, needles) in cases {
        assert!(text.contains(old), "{case}");
        assert_check_refuses(&dir, case, &text.replacen(old, new, 1), needles);
    }
}

/// Energy in the log: each face's load on `/thermal/heat` equals
/// A (α (solar + albedo) + ε Earth IR) from its incident fluxes on `/orbit/faces`, at every logged instant, and
/// the network's absorbed power is their sum (the CubeSat has no other absorbed load).
/// The optical properties are moved by `--set` so that a log ignoring them would fail.
#[test]
fn cli_the_logged_face_fluxes_account_for_the_face_loads() {
    let dir = tmpdir("face-energy");
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/cubesat-1u.toml");
    let log = dir.join("cube.mcap");
    let out = bin()
        .args(["run", "--quiet", "--orbits", "1", "--log-every", "120s"])
        .args(["--set", "face.px.absorptivity=0.5"])
        .args(["--set", "face.mz.emissivity=0.3"])
        .arg(&scenario)
        .arg("--out")
        .arg(&log)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let spec: toml::Table = std::fs::read_to_string(&scenario).unwrap().parse().unwrap();
    let faces = spec["face"].as_array().unwrap();
    assert_eq!(faces.len(), 6);
    let table = orbitlash::io::mcap_read::read_log(&log).unwrap();
    let col = |name: &str| {
        table
            .columns
            .iter()
            .position(|c| c == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    };
    let absorbed = col("/thermal/heat.absorbed_w");
    let mut rows = 0;
    for (_, v) in &table.rows {
        if v[absorbed].is_nan() {
            continue;
        }
        rows += 1;
        let mut sum = 0.0;
        for f in faces {
            let f = f.as_table().unwrap();
            let (node, name) = (f["node"].as_str().unwrap(), f["name"].as_str().unwrap());
            let area = f["area_m2"].as_float().unwrap();
            let alpha = if name == "px" {
                0.5
            } else {
                f["absorptivity"].as_float().unwrap()
            };
            let eps = if name == "mz" {
                0.3
            } else {
                f["emissivity"].as_float().unwrap()
            };
            let q = |k: &str| v[col(&format!("/orbit/faces.{node}_{name}_{k}_w_per_m2"))];
            let want = area * (alpha * (q("solar") + q("albedo")) + eps * q("earth_ir"));
            let load = v[col(&format!("/thermal/heat.{name}_w"))];
            assert!(
                (load - want).abs() <= 1e-9 * (1.0 + want.abs()),
                "{name}: {load} vs {want}"
            );
            sum += load;
        }
        assert!(
            (v[absorbed] - sum).abs() <= 1e-9 * (1.0 + sum),
            "{} vs {sum}",
            v[absorbed]
        );
    }
    assert!(rows > 40, "{rows} rows");
}

/// A TLE whose orbit decays in about two weeks (an ISS-like orbit at 16.25 revolutions a
/// day with a strong drag term). `check` refuses a run past its decay, by the orbit's
/// perigee, not by where a day's point happens to fall; a `--set` of the run's length
/// within its life runs, as the same edit in the file would; `environment` refuses the
/// days after it instead of writing NaN; and a refused run leaves a log already at its
/// path as it was.
#[test]
fn cli_a_decaying_orbit_is_refused_before_anything_is_written() {
    let dir = tmpdir("tle-decay");
    let text = tle_text()
        .replace(
            "1 39444U 13066AE  16035.38257241  .00000865  00000-0  11531-3 0  9990",
            "1 99999U 16001A   16035.38257241  .02000000  00000-0  48000-3 0  9997",
        )
        .replace(
            "2 39444  97.7004  94.3150 0060634  98.1157 262.6940 14.80829622117779",
            "2 99999  51.6400  94.3150 0005000  98.1157 262.6940 16.25000000 10005",
        )
        .replace("duration_days = 365.0", "duration_days = 16.0");
    assert!(text.contains("99999U") && text.contains("duration_days = 16.0"));
    let file = dir.join("decay.toml");
    std::fs::write(&file, &text).unwrap();
    // the run would meet the decay at 15.7 days; a day's points (0 … 16) all lie above
    // 80 km, the perigee does not
    let out = bin().arg("check").arg(&file).output().unwrap();
    assert_error(
        "decay",
        &out,
        &["`orbit.tle`", "has decayed", "its perigee is at"],
    );
    // shortened by --set, as in the file
    let out = bin()
        .arg("check")
        .arg(&file)
        .args(["--set", "run.duration_days=2"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // a change that is itself wrong is named, not the file's error it would fix
    let out = bin()
        .arg("check")
        .arg(&file)
        .args(["--set", "run.duration_dayz=2"])
        .output()
        .unwrap();
    assert_error("decay-typo", &out, &["--set run.duration_dayz=2"]);
    // a good log at the path stays as it was when the run is refused
    let log = dir.join("kept.mcap");
    let good = bin()
        .args(["run", "--orbits", "1", "--quiet", "--out"])
        .arg(&log)
        .output()
        .unwrap();
    assert!(good.status.success());
    let before = std::fs::read(&log).unwrap();
    let out = bin()
        .arg("run")
        .arg(&file)
        .args(["--quiet", "--out"])
        .arg(&log)
        .output()
        .unwrap();
    assert_error("decay-run", &out, &["has decayed"]);
    assert_eq!(std::fs::read(&log).unwrap(), before, "the log was replaced");
    // environment past the decay: refused, no CSV
    let csv = dir.join("env.csv");
    let out = bin()
        .arg("environment")
        .arg(&file)
        .args(["--set", "run.duration_days=2", "--orbits", "262", "--csv"])
        .arg(&csv)
        .output()
        .unwrap();
    assert_error("decay-environment", &out, &["--orbits 262", "has decayed"]);
    assert!(!csv.exists());
}

/// An Earth radius that reaches the orbit (the orbit's own size or larger) is
/// refused, naming the key: the spacecraft would be inside the Earth, in its shadow all
/// day.
#[test]
fn cli_an_earth_radius_above_the_orbit_is_refused() {
    let dir = tmpdir("tle-earth-radius");
    let (out, _) = check_with(
        &dir,
        "earth-radius",
        "shadow = \"conical\"",
        "shadow = \"conical\"\nearth_radius_m = 7.5e6",
    );
    assert_error(
        "earth-radius",
        &out,
        &[
            "`orbit.earth_radius_m`",
            "(7500 km) reaches the orbit's perigee",
            "inside the Earth",
        ],
    );
    let (out, _) = check_with(
        &dir,
        "earth-radius-ok",
        "shadow = \"conical\"",
        "shadow = \"conical\"\nearth_radius_m = 6.371e6",
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// An eclipse's UTC is its seconds after the start, rounded to the millisecond both
/// show (black-box helper-27: chrono's `%.3f` cut 3235.5699… s to `00:53:55.569`
/// beside `3235.570`).
#[test]
fn cli_environment_utc_agrees_with_its_seconds() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = bin()
        .arg("environment")
        .arg(root.join("scenarios/hinge-tle-year.toml"))
        .args(["--orbits", "3"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    let mut rows = 0;
    for line in text.lines() {
        let cells: Vec<&str> = line.split_whitespace().collect();
        let (Some(s), Some(utc)) = (cells.first(), cells.last()) else {
            continue;
        };
        let (Ok(s), Some(clock)) = (s.parse::<f64>(), utc.strip_prefix("2016-02-04T")) else {
            continue;
        };
        // the start is 2016-02-04T00:00:00Z: the clock is the seconds, to the ms
        let ms = (s * 1e3).round() as u64;
        let want = format!(
            "{:02}:{:02}:{:02}.{:03}Z",
            ms / 3_600_000,
            ms / 60_000 % 60,
            ms / 1000 % 60,
            ms % 1000
        );
        assert_eq!(clock, want, "{line}");
        rows += 1;
    }
    assert_eq!(rows, 3, "{text}");
}

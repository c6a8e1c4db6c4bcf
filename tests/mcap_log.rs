//! MCAP logs: contents by name, provenance, cadence, round trip through export-csv,
//! and what an interrupted or killed run leaves behind.

mod common;

use std::path::Path;
use std::time::Duration;

use common::{bin, tmpdir};
use orbitlash::io::mcap_read::read_log;
use sha2::{Digest, Sha256};

fn reference_file() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/reference-hinge.toml")
}

fn run_ok(args: &[&str]) -> String {
    let out = bin().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn cli_log_holds_every_series_by_name_and_its_provenance() {
    let dir = tmpdir("log-contents");
    let log = dir.join("ref.mcap");
    let scenario = reference_file();
    run_ok(&[
        "run",
        scenario.to_str().unwrap(),
        "--quiet",
        "--out",
        log.to_str().unwrap(),
    ]);
    let t = read_log(&log).unwrap();

    let meta = &t.channel_metadata["/thermal/temperature"];
    for node in ["housing", "motor", "gear1.r0", "gear2.r2"] {
        let field = format!("{}_k", node.replace('.', "_"));
        assert_eq!(
            meta.get(&format!("node:{field}")).map(String::as_str),
            Some(node)
        );
        let c = t.column(&format!("/thermal/temperature.{field}")).unwrap();
        assert!(t.rows.iter().all(|(_, r)| r[c].is_finite() && r[c] > 200.0));
    }
    for field in [
        "backlash_exact_um",
        "margin_um",
        "pinion.base_pitch_mm",
        "wheel.temperature_k[2]",
        "pinion.radius_mm[0]",
    ] {
        let c = t
            .column(&format!("/gears/mesh.{field}"))
            .unwrap_or_else(|| panic!("{field}"));
        assert!(t.rows.iter().all(|(_, r)| r[c].is_finite()), "{field}");
    }
    for field in [
        "/thermal/heat.sun_housing_w",
        "/thermal/heat.to_space_w",
        "/orbit/state.beta_deg",
        "/orbit/state.sunlit",
    ] {
        assert!(t.column(field).is_some(), "{field}");
    }
    // Log time = simulated time in ns, the first sample at t = 0, one per step.
    assert_eq!(t.rows[0].0, 0);
    let time = t.column("/thermal/temperature.time_s").unwrap();
    assert!(
        t.rows
            .iter()
            .all(|(ns, r)| (*ns as f64 * 1e-9 - r[time]).abs() < 1e-6)
    );
    assert!(t.rows.windows(2).all(|w| w[1].0 > w[0].0));

    let text = std::fs::read(&scenario).unwrap();
    let prov = &t.metadata["orbitlash.provenance"];
    let sha: String = Sha256::digest(&text)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    assert_eq!(prov["scenario_sha256"], sha);
    assert_eq!(prov["tool_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(prov["scenario_name"], "reference-hinge");
    assert!(prov["solver"].contains("tr-bdf2"));
    assert_eq!(t.metadata["orbitlash.run_end"]["status"], "complete");
    // /events ends with the run's end: its time, verdict and the pair's smallest
    // backlash (the viewers' event panels promise it)
    let bytes = std::fs::read(&log).unwrap();
    let scan = orbitlash::io::mcap_scan::scan(&bytes).unwrap();
    let last_event = scan
        .messages
        .iter()
        .filter(|m| scan.channels[&m.header.channel_id].topic == "/events")
        .max_by_key(|m| m.header.log_time)
        .expect("events");
    let end_text = String::from_utf8_lossy(last_event.data);
    assert!(
        end_text.contains("run complete at t = ") && end_text.contains("verdict pass"),
        "{end_text}"
    );
    assert!(end_text.contains("mesh smallest backlash"), "{end_text}");
    assert_eq!(last_event.header.log_time, t.rows.last().unwrap().0);
    assert_eq!(
        t.attachments,
        vec![("reference-hinge.toml".to_string(), text)]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_export_csv_round_trips_the_run_csv() {
    let dir = tmpdir("roundtrip");
    let (log, csv, back) = (dir.join("r.mcap"), dir.join("r.csv"), dir.join("back.csv"));
    run_ok(&[
        "run",
        "--quiet",
        "--orbits",
        "2",
        "--log-every",
        "600s",
        "--set",
        "run.output_interval_s=600",
        "--out",
        log.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    run_ok(&[
        "export-csv",
        log.to_str().unwrap(),
        "--out",
        back.to_str().unwrap(),
    ]);
    let (a, b) = (
        std::fs::read_to_string(&csv).unwrap(),
        std::fs::read_to_string(&back).unwrap(),
    );
    // every step reaches at most one 600 s grid time here, so the log holds the grid,
    // and besides it the samples at the smallest backlash (one per descent to a new
    // smallest) and at the run's end, which the CSV's grid does not have
    assert!(a.lines().count() > 15);
    let b_lines: Vec<&str> = b.lines().collect();
    let extra: Vec<&str> = b_lines
        .iter()
        .copied()
        .filter(|l| !a.lines().any(|x| x == *l))
        .collect();
    assert!(
        a.lines().all(|l| b_lines.contains(&l)),
        "export-csv of the log lacks rows of the run's CSV"
    );
    assert!(
        (1..=4).contains(&extra.len()),
        "{} rows besides the CSV's: {extra:?}",
        extra.len()
    );
    // the last is the end of the run, and the smallest backlash of the log is the run's
    let t_last: f64 = b_lines
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (t_last - 2.0 * 5676.978).abs() < 1.0,
        "last row at {t_last}"
    );
    let col = |l: &str, i: usize| l.split(',').nth(i).unwrap().parse::<f64>().unwrap();
    let bi = b_lines[0]
        .split(',')
        .position(|h| h == "backlash_um")
        .unwrap();
    let smallest = |ls: &[&str]| {
        ls[1..]
            .iter()
            .map(|l| col(l, bi))
            .fold(f64::INFINITY, f64::min)
    };
    let a_lines: Vec<&str> = a.lines().collect();
    // both hold the row at the run's smallest
    assert_eq!(smallest(&b_lines), smallest(&a_lines));
    // --all adds every other series.
    let all = run_ok(&["export-csv", log.to_str().unwrap(), "--all"]);
    let header = all.lines().next().unwrap();
    assert!(header.starts_with(a.lines().next().unwrap()));
    assert!(
        header.contains("/orbit/state.orbit_angle_deg")
            && header.contains("/gears/mesh.wheel.base_radius_mm")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_log_cadence_by_steps_and_by_interval() {
    let dir = tmpdir("cadence");
    let rows = |args: &[&str]| {
        let log = dir.join("c.mcap");
        let mut a = vec![
            "run",
            "--quiet",
            "--orbits",
            "1",
            "--out",
            log.to_str().unwrap(),
        ];
        a.extend_from_slice(args);
        run_ok(&a);
        read_log(&log).unwrap().rows.len()
    };
    // besides its cadence, a log holds the sample at each new smallest backlash (one
    // per descent: at most a few here) and the last step's end
    let extra = |n: usize, cadence: usize| {
        assert!(
            n > cadence && n <= cadence + 4,
            "{n} rows for {cadence} at the cadence"
        );
    };
    let every = rows(&["--log-every", "1"]);
    // the accepted steps, as `run -v` counts them
    let verbose = run_ok(&["run", "--orbits", "1", "-v", "--no-log"]);
    let steps: usize = verbose
        .split("tr-bdf2, ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("the step count in run -v");
    extra(every, steps + 1);
    let by_10 = rows(&["--log-every", "10"]);
    extra(by_10, steps / 10 + 1);
    extra(
        rows(&["--log-every", "600s"]),
        (5676.978f64 / 600.0).floor() as usize + 1,
    );
    for bad in ["0", "-5s", "ten", "0s"] {
        let out = bin()
            .args(["run", "--quiet", &format!("--log-every={bad}")])
            .output()
            .unwrap();
        assert!(!out.status.success(), "--log-every {bad} accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--log-every"), "{err}");
        // an interval too short (zero, negative) says the shortest there is
        if bad.ends_with('s') {
            assert!(err.contains("at least 0.001 s"), "{err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The long run's log and CSV cadence, s: once a day, so that its outputs (a few MB
/// for 170 000 orbits) are not refused up front on a file system with little free
/// space, while it computes for tens of seconds.
const LONG_RUN_EVERY_S: f64 = 86_400.0;

/// Starts a long run and returns it once its temporary log exists.
fn start_long_run(dir: &Path) -> (std::process::Child, std::path::PathBuf, std::path::PathBuf) {
    let (log, csv) = (dir.join("long.mcap"), dir.join("long.csv"));
    let every = format!("{LONG_RUN_EVERY_S}s");
    let csv_every = format!("run.output_interval_s={LONG_RUN_EVERY_S}");
    // std's Command: this run is signalled while it runs, which assert_cmd does not do
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_orbitlash"))
        .args([
            "run",
            "--quiet",
            "--orbits",
            "170000",
            "--log-every",
            &every,
        ])
        .args(["--set", &csv_every])
        .args([
            "--out",
            log.to_str().unwrap(),
            "--csv",
            csv.to_str().unwrap(),
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let partial = dir.join("long.mcap.partial");
    for _ in 0..200 {
        if partial.exists() {
            break;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(300));
    (child, log, csv)
}

fn signal(child: &std::process::Child, sig: &str) {
    let status = std::process::Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

#[test]
fn cli_ctrl_c_closes_the_log_and_says_so() {
    let dir = tmpdir("interrupt");
    let (child, log, csv) = start_long_run(&dir);
    signal(&child, "-INT");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "an interrupted run must not exit 0");
    assert!(stderr.contains("interrupted at t ="), "{stderr}");
    // the summary's window is the whole run, and says so (not "last period")
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("the whole run (interrupted before its last orbit), t = 0 … ")
            && !stdout.contains("last period"),
        "{stdout}"
    );
    let t = read_log(&log).unwrap();
    let end = &t.metadata["orbitlash.run_end"];
    assert_eq!(end["status"], "interrupted");
    let t_end: f64 = end["t_end_s"].parse().unwrap();
    assert!(t_end > 0.0 && t_end < 170_000.0 * 5676.978);
    let last = t.rows.last().unwrap().0 as f64 * 1e-9;
    assert!(last <= t_end + 1e-6 && t_end - last <= LONG_RUN_EVERY_S + 1e-6);
    // The CSV is complete up to the same time.
    let text = std::fs::read_to_string(&csv).unwrap();
    let last_csv: f64 = text
        .lines()
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(last_csv <= t_end && t_end - last_csv <= LONG_RUN_EVERY_S + 1e-6);
    assert!(!dir.join("long.mcap.partial").exists() && !dir.join("long.csv.partial").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_a_killed_run_leaves_no_file_under_the_final_name() {
    let dir = tmpdir("kill");
    let (mut child, log, csv) = start_long_run(&dir);
    signal(&child, "-KILL");
    let _ = child.wait();
    assert!(!log.exists(), "a killed run left {}", log.display());
    assert!(!csv.exists(), "a killed run left {}", csv.display());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_scene_view_is_optional_and_decodes() {
    let dir = tmpdir("scene");
    let log = dir.join("s.mcap");
    run_ok(&[
        "run",
        "--quiet",
        "--orbits",
        "1",
        "--scene",
        "--out",
        log.to_str().unwrap(),
    ]);
    let bytes = std::fs::read(&log).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let scene = summary
        .channels
        .values()
        .find(|c| c.topic == "/gears/mesh/scene")
        .expect("scene channel");
    assert_eq!(scene.schema.as_ref().unwrap().name, "foxglove.SceneUpdate");
    let stats = summary.stats.unwrap();
    let n = stats.channel_message_counts[&scene.id];
    assert_eq!(n as usize, (5676.978f64 / 300.0).floor() as usize + 1);
    // The series are unchanged by it, and without --scene there is no such channel.
    assert!(
        read_log(&log)
            .unwrap()
            .column("/gears/mesh.backlash_exact_um")
            .is_some()
    );
    let plain = dir.join("p.mcap");
    run_ok(&[
        "run",
        "--quiet",
        "--orbits",
        "1",
        "--out",
        plain.to_str().unwrap(),
    ]);
    let t = read_log(&plain).unwrap();
    assert!(!t.channel_metadata.contains_key("/gears/mesh/scene"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A log every step, resampled onto `run --csv`'s 30 s grid by `export-csv --every 30s`:
/// the same times, and values linear between step ends within 0.1 K and 0.02 µm of the
/// solver's own interpolant. And `--log-every` never makes a log bigger than logging
/// every step, however short its interval.
#[test]
fn cli_export_csv_every_resamples_onto_the_run_grid_and_logs_never_grow() {
    let dir = tmpdir("every");
    let (log, csv) = (dir.join("r.mcap"), dir.join("r.csv"));
    run_ok(&[
        "run",
        "--quiet",
        "--orbits",
        "2",
        "--out",
        log.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let back = run_ok(&["export-csv", log.to_str().unwrap(), "--every", "30s"]);
    let grid = std::fs::read_to_string(&csv).unwrap();
    let rows = |t: &str| -> Vec<Vec<f64>> {
        t.lines()
            .skip(1)
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect()
    };
    // the grid rows of both; off it, the run's CSV holds a row at each new smallest
    // and the export the log's row at the run's smallest, which is the CSV's smallest
    let on_grid = |r: &Vec<f64>| (r[0] / 30.0 - (r[0] / 30.0).round()).abs() < 1e-9;
    let (all_a, all_b) = (rows(&grid), rows(&back));
    let bi = grid
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|h| h == "backlash_um")
        .unwrap();
    let off_b: Vec<&Vec<f64>> = all_b.iter().filter(|r| !on_grid(r)).collect();
    assert_eq!(off_b.len(), 1, "the export's row at the smallest");
    let min_a = all_a.iter().min_by(|x, y| x[bi].total_cmp(&y[bi])).unwrap();
    assert_eq!(off_b[0][0], min_a[0], "at the CSV's smallest");
    assert!((off_b[0][bi] - min_a[bi]).abs() < 2e-6);
    assert!(
        all_b.windows(2).all(|w| w[0][0] < w[1][0]),
        "rows in time order"
    );
    let (a, b): (Vec<Vec<f64>>, Vec<Vec<f64>>) = (
        all_a.into_iter().filter(on_grid).collect(),
        all_b.into_iter().filter(on_grid).collect(),
    );
    assert_eq!(grid.lines().next(), back.lines().next());
    assert_eq!(a.len(), b.len());
    let header: Vec<&str> = grid.lines().next().unwrap().split(',').collect();
    for (ra, rb) in a.iter().zip(&b) {
        assert_eq!(ra[0], rb[0]);
        for (i, (x, y)) in ra.iter().zip(rb).enumerate() {
            let tol = if header[i].ends_with("_um") {
                0.02
            } else {
                0.1
            };
            assert!(
                (x - y).abs() <= tol,
                "{} at t = {}: {x} vs {y}",
                header[i],
                ra[0]
            );
        }
    }
    // whole-number columns (orbit number, the eclipse flag) are held, not blended
    let all = run_ok(&[
        "export-csv",
        log.to_str().unwrap(),
        "--all",
        "--every",
        "30s",
    ]);
    let head: Vec<&str> = all.lines().next().unwrap().split(',').collect();
    for name in ["/orbit/state.orbit_number", "/orbit/state.sunlit"] {
        let c = head.iter().position(|h| *h == name).unwrap();
        for l in all.lines().skip(1) {
            let v: f64 = l.split(',').nth(c).unwrap().parse().unwrap();
            assert_eq!(v.fract(), 0.0, "{name} = {v}");
        }
    }
    // a grid of more than 1e7 rows is refused, not built in memory
    let out = bin()
        .args(["export-csv", log.to_str().unwrap(), "--every", "0.001s"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("choose a longer interval"));
    let every_step = std::fs::metadata(&log).unwrap().len();
    let per_sample = every_step as f64 / read_log(&log).unwrap().rows.len() as f64;
    for every in ["1s", "30s"] {
        let p = dir.join(format!("e{every}.mcap"));
        run_ok(&[
            "run",
            "--quiet",
            "--orbits",
            "2",
            "--log-every",
            every,
            "--out",
            p.to_str().unwrap(),
        ]);
        // no more than every step, but for at most a few samples: each at a new smallest
        // backlash inside a step, which an every-step log holds besides the step ends
        // too, though not always at the same steps
        let n = std::fs::metadata(&p).unwrap().len();
        assert!(
            n as f64 <= every_step as f64 + 3.0 * per_sample,
            "--log-every {every}: {n} bytes > {every_step} every step"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

//! Long missions summarised by day (issue 20 item 5): `DailyStats` over the 90-day
//! scenario against what other observers of the same run saw: the days cover the run,
//! the smallest backlash of the days is the run's (MeshStats, which refines within
//! steps: to a few nanometres), and each heater's time on
//! is the sum of the intervals between its on and off events; the CLI prints times in
//! days and the per-week table, and the heater's duty cycle and energy.

mod common;

use orbitlash::io::scenario_toml::load_file;
use orbitlash::run::sim::{Event, EventKind, Observer, ObserverResult, Setup, Stop};
use orbitlash::run::summary::{DAY_S, DailyStats, MeshStats};

#[derive(Default)]
struct Events(Vec<Event>);
impl Observer for Events {
    fn on_event(&mut self, e: &Event) -> ObserverResult {
        self.0.push(*e);
        Ok(())
    }
}

#[test]
fn core_daily_stats_of_90_days_agree_with_the_run() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/hinge-90-day-drift.toml");
    let (sc, _) = load_file(&path).unwrap();
    let t_end = sc.run.duration_s;
    let mut daily = DailyStats::default();
    let mut mesh = MeshStats::last(sc.period_s());
    let mut events = Events::default();
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let mut state = setup.initial_state();
    let stats = setup
        .run(
            &mut state,
            t_end,
            &mut (&mut daily, &mut mesh, &mut events),
            Stop::default(),
        )
        .unwrap();
    assert_eq!(daily.days.len(), (t_end / DAY_S).ceil() as usize);
    let covered: f64 = daily.days.iter().map(|d| d.covered_s).sum();
    assert!(
        (covered - t_end).abs() < 1e-6 * t_end,
        "{covered} of {t_end} s"
    );
    let smallest = daily
        .days
        .iter()
        .map(|d| d.backlash_m[0].0)
        .fold(f64::INFINITY, f64::min);
    // The days see step ends; MeshStats refines the extremes within steps: the same to
    // a few nanometres, never beyond it.
    let run_min = mesh.run_pairs[0].min_exact_m;
    assert!(
        smallest >= run_min && smallest - run_min < 5e-9,
        "{smallest} vs {run_min}"
    );
    let largest = daily
        .days
        .iter()
        .map(|d| d.backlash_m[0].1)
        .fold(f64::NEG_INFINITY, f64::max);
    let run_max = mesh.run_pairs[0].max_exact_m;
    assert!(
        largest <= run_max && run_max - largest < 5e-9,
        "{largest} vs {run_max}"
    );
    // the heater's time on from its switching events
    assert_eq!(daily.heaters.len(), 1);
    let mut on_s = 0.0;
    let mut since: Option<f64> = None;
    for e in &events.0 {
        match e.kind {
            EventKind::HeaterOn(0) => since = Some(e.t_s),
            EventKind::HeaterOff(0) => on_s += e.t_s - since.take().expect("off after on"),
            _ => {}
        }
    }
    if let Some(t) = since {
        on_s += stats.t_end_s - t;
    }
    let counted: f64 = daily.days.iter().map(|d| d.heater_on_s[0]).sum();
    assert!(on_s > 3600.0, "the heater never ran: {on_s} s");
    assert!(
        (counted - on_s).abs() < 1e-6 * on_s,
        "{counted} s counted, {on_s} s between events"
    );
    let energy: f64 = daily.days.iter().map(|d| d.heater_j[0]).sum();
    assert!((energy - daily.heaters[0].1 * on_s).abs() < 1e-6 * energy);
    assert!(energy <= stats.energy.dissipated_j);
}

#[test]
fn cli_a_long_run_reports_days_weeks_and_heaters() {
    let out = common::bin()
        .args(["run", "--no-log"])
        .arg(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scenarios/hinge-90-day-drift.toml"),
        )
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in [
        "smallest backlash at t = 0.154 d",
        "per week (day 1 starts at t = 0",
        "   1–7 ",
        "85–90",
        "heaters over the run:",
        "duty %",
        "energy Wh",
    ] {
        assert!(text.contains(needle), "no {needle:?} in\n{text}");
    }
    // a run of hours keeps seconds
    let out = common::bin()
        .args(["run", "--no-log", "--orbits", "2"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("smallest backlash at t = ")
            && !text.contains(" d (")
            && !text.contains("per day")
    );
    // in hours, the unit of its figure, with the seconds after them
    assert!(
        text.lines()
            .any(|l| l.starts_with("PASS") && l.contains(" h (") && l.contains(" s), orbit")),
        "{text}"
    );
}

/// `run --json` carries the days and heaters in machine form (issue 30 item 8): one
/// entry per day covering the run, the days' smallest backlash the run's (to a few
/// nanometres, as the text), each heater's energy its power times its time on, its
/// duty that time over the run, and the days' heater shares adding up to it; the
/// heater's hours and energy are those the text table prints.
#[test]
fn cli_run_json_has_days_and_heaters() {
    let dir = common::tmpdir("daily-json");
    let json = dir.join("s.json");
    let out = common::bin()
        .args(["run", "--no-log", "--json"])
        .arg(&json)
        .arg(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scenarios/hinge-90-day-drift.toml"),
        )
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let days = s["days"].as_array().expect("days");
    let span = s["t_end_s"].as_f64().unwrap() - s["t_start_s"].as_f64().unwrap();
    assert_eq!(
        days.len() as f64,
        (span / DAY_S).ceil(),
        "one entry per day"
    );
    let covered: f64 = days.iter().map(|d| d["covered_s"].as_f64().unwrap()).sum();
    assert!(
        (covered - span).abs() < 1e-6 * span,
        "the days cover {covered} of {span} s"
    );
    for (k, d) in days.iter().enumerate() {
        assert_eq!(d["day"].as_u64(), Some(k as u64 + 1));
        assert!(d["coldest_k"].as_f64().unwrap() <= d["hottest_k"].as_f64().unwrap());
    }
    let smallest = days
        .iter()
        .filter_map(|d| d["gear_pairs"][0]["min_backlash_um"].as_f64())
        .fold(f64::INFINITY, f64::min);
    let run_min = s["gear_pairs"][0]["min_backlash_um"].as_f64().unwrap();
    // the same number: the run's extremes are put in their days (they differed by
    // nanometres, 36.738 against 36.740 in the 3-decimal tables)
    assert_eq!(smallest, run_min, "days' smallest, the run's");
    let largest = days
        .iter()
        .filter_map(|d| d["gear_pairs"][0]["max_backlash_um"].as_f64())
        .fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(
        largest,
        s["gear_pairs"][0]["max_backlash_um"].as_f64().unwrap(),
        "days' largest, the run's"
    );
    let h = &s["heaters"][0];
    let (p, on, e) = (
        h["power_w"].as_f64().unwrap(),
        h["on_s"].as_f64().unwrap(),
        h["energy_j"].as_f64().unwrap(),
    );
    assert!(
        on > 0.0 && (e - p * on).abs() < 1e-6 * e,
        "energy {e} J, power × time {} J",
        p * on
    );
    assert!((h["duty_fraction"].as_f64().unwrap() - on / span).abs() < 1e-12);
    let shared: f64 = days
        .iter()
        .map(|d| d["heaters_on_fraction"].as_f64().unwrap() * d["covered_s"].as_f64().unwrap())
        .sum();
    assert!(
        (shared - on).abs() < 1e-6 * on,
        "days' heater time {shared} s, the heater's {on} s"
    );
    let name = h["name"].as_str().unwrap();
    let row: Vec<&str> = text
        .lines()
        .find(|l| l.trim_start().starts_with(name))
        .unwrap_or_else(|| panic!("no row of {name} in\n{text}"))
        .split_whitespace()
        .collect();
    let want = [
        format!("{p:.2}"),
        format!("{:.2}", on / 3600.0),
        format!("{:.1}", 100.0 * on / span),
        format!("{:.1}", e / 1e3),
        format!("{:.2}", e / 3600.0),
    ];
    assert_eq!(row[1..], want, "the text's heater row and the JSON");
    let _ = std::fs::remove_dir_all(&dir);
}

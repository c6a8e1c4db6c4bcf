//! FUNcube-1's flight telemetry of 2016-02-04 (`../shared/data/funcube-1`, AMSAT-UK Data
//! Warehouse) against `scenarios/funcube-1.toml`: the eclipses the TLE, SGP4, the dated
//! Sun and the conical shadow predict against the photo-current the satellite measured
//! (≈ 0 in eclipse), minute by minute on the measured rows (the warehouse's fill
//! left out); β and the eclipse fraction; the mean offset of entries and exits.

mod common;

use orbitlash::io::recording::Recording;
use orbitlash::orbit::EnvironmentModel;

const PHOTO: &str = "Tot. Photo Curr. mA";
/// Photo-current below which a row is in eclipse, mA (the day's sunlit rows carry
/// 100 … 412 mA; in eclipse it reads 0).
const DARK_MA: f64 = 20.0;

/// The eclipse entries and exits of the photo-current less the predicted crossings, s:
/// (entries, exits), as `diagnose`'s clock check finds them (`Recording::eclipse_check`).
fn edge_offsets(rec: &Recording, env: &impl EnvironmentModel) -> (Vec<f64>, Vec<f64>) {
    let c = rec.eclipse_check(PHOTO, DARK_MA, env).unwrap();
    (c.entries_s, c.exits_s)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// The eclipses, read through the scenario's `[recording]` (its `time_offset_s`
/// included), against the TLE's; and that offset against the edges' own: with the
/// stamps as sent, entries and exits both come early by about the scenario's offset
/// (a clock's offset, not a shadow's size); with it added, they straddle zero.
#[test]
fn val_funcube_flight_eclipses_beta_and_fraction_from_the_tle() {
    let Some(csv) = common::shared("data/funcube-1/funcube1_wod_2016-02-04.csv") else {
        return;
    };
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/funcube-1.toml"),
    )
    .unwrap();
    let sc = orbitlash::io::scenario_toml::parse(&text, "funcube-1.toml").unwrap();
    // the photo-current is the scenario's eclipse column: read, not ignored
    let format = sc.recording.clone();
    let rec = Recording::read_with(&csv, &format).unwrap();
    let photo = rec.channel(PHOTO).unwrap();
    let env = &sc.thermal.environment;

    // minute by minute on the measured rows
    let (mut rows, mut agree, mut dark_measured, mut dark_model) = (0, 0, 0, 0);
    for (j, &t) in rec.time_s.iter().enumerate() {
        let Some(pc) = photo[j] else { continue };
        let measured = pc < DARK_MA;
        let model = env.sun_fraction(t) < 0.5;
        rows += 1;
        agree += usize::from(measured == model);
        dark_measured += usize::from(measured);
        dark_model += usize::from(model);
    }
    let agreement = agree as f64 / rows as f64;
    let (f_measured, f_model) = (
        dark_measured as f64 / rows as f64,
        dark_model as f64 / rows as f64,
    );
    let (entries, exits) = edge_offsets(&rec, env);
    let as_sent = {
        let mut f = format.clone();
        f.time_offset_s = 0.0;
        Recording::read_with(&csv, &f).unwrap()
    };
    let (entries_sent, exits_sent) = edge_offsets(&as_sent, env);
    let all_sent: Vec<f64> = entries_sent.iter().chain(&exits_sent).copied().collect();
    let beta = env.state_with(43_200.0, true).beta_rad.to_degrees();
    eprintln!(
        "FUNcube-1 2016-02-04: {rows} measured rows, eclipse agreement {:.2} %, eclipse fraction {f_measured:.4} measured, {f_model:.4} predicted; β {beta:.2}°; measured − predicted (±30 s from one-minute rows): as stamped, {} entries {:+.1} s, {} exits {:+.1} s, all {:+.1} s; with time_offset_s = {} s, entries {:+.1} s, exits {:+.1} s",
        100.0 * agreement,
        entries_sent.len(),
        mean(&entries_sent),
        exits_sent.len(),
        mean(&exits_sent),
        mean(&all_sent),
        format.time_offset_s,
        mean(&entries),
        mean(&exits)
    );
    assert!(rows > 1100, "{rows} measured rows");
    assert!(agreement >= 0.97, "agreement {agreement}");
    assert!((beta - 43.5).abs() < 1.0, "β {beta}");
    assert!(
        (f_measured - f_model).abs() < 0.01,
        "{f_measured} vs {f_model}"
    );
    assert!(entries.len() >= 10 && exits.len() >= 10);
    // the stamps as sent are early, entries and exits alike: a clock's offset
    assert!(
        mean(&entries_sent) < -10.0 && mean(&exits_sent) < -10.0,
        "{entries_sent:?} {exits_sent:?}"
    );
    // the scenario's offset is the edges' own, within what 23 edges known to their
    // minute tell (±17 s each, about ±4 s for the mean)
    assert!(
        (format.time_offset_s + mean(&all_sent)).abs() < 5.0,
        "time_offset_s {} against the edges' {:+.1} s",
        format.time_offset_s,
        mean(&all_sent)
    );
    assert!(mean(&entries).abs() < 10.0 && mean(&exits).abs() < 10.0);
}

/// `diagnose` on the day: fitted on the first ten whole orbits, checked on the last
/// four it never saw. The corrected model's held-out RMSE is below the baseline's on
/// every temperature channel, the verdict stays `unexplained` (a partial explanation:
/// the attitude is outside the vocabulary), and the report accounts for the fill.
#[test]
fn val_funcube_flight_diagnose_improves_every_held_out_channel() {
    let Some(csv) = common::shared("data/funcube-1/funcube1_wod_2016-02-04.csv") else {
        return;
    };
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/funcube-1.toml"),
    )
    .unwrap();
    let spec = orbitlash::io::scenario_toml::parse_spec(&text, "funcube-1.toml").unwrap();
    let model = orbitlash::spec::model::Model::new(spec).unwrap();
    let mut rec = Recording::read_with(&csv, &model.scenario().recording).unwrap();
    let eclipses = rec.take_eclipse_check(&model).unwrap().unwrap();
    assert!(eclipses.agreement > 0.99, "{eclipses:?}");
    rec.name_channels(&model.scenario().sensors);
    let d = orbitlash::diagnose::diagnose(
        &model,
        &rec,
        &orbitlash::diagnose::Options::default(),
        &|_, _, _| {},
    )
    .unwrap();
    assert_eq!(d.split.holdout_orbits, 4);
    assert_eq!(d.recording.fill_rows.len(), 226);
    assert_eq!(d.verdict.as_str(), "unexplained");
    assert!(!d.findings.is_empty());
    for ((ch, before), (_, after)) in d.baseline.heldout_rmse.0.iter().zip(&d.heldout_rmse.0) {
        eprintln!("{ch}: held-out RMSE {before:.2} → {after:.2} K");
        assert!(after < before, "{ch}: {before} → {after}");
    }
    assert_eq!(d.heldout_rmse.0.len(), 8);
    // The figures of `diagnose --out` on real data (gaps, fill): their labels, as the
    // SVG draws them, apart, on the page and off every drawn line.
    let overview = orbitlash::plot::overview::overview(&d.series, "funcube-1").unwrap();
    let mut problems = overview.drawn_problems();
    for c in 0..d.series.channels.len() {
        let fig = orbitlash::plot::diagnose::channel(&d.series, c).unwrap();
        problems.extend(fig.drawn_problems());
    }
    assert!(problems.is_empty(), "{problems:#?}");
    // The figures draw the models on their own even grid, through the recording's
    // gaps: the same models as at the readings (linear between grid points, RMS within
    // 0.05 K; the corrected and baseline models differ by kelvins here), and points
    // inside the longest gap.
    let s = &d.series;
    let grid = &s.model_time_s;
    assert_eq!(grid.len(), orbitlash::diagnose::MODEL_GRID_POINTS);
    assert_eq!(
        (grid[0], grid[grid.len() - 1]),
        (0.0, *s.time_s.last().unwrap())
    );
    let at = |g: &[f64], t: f64| {
        let k = grid.partition_point(|&x| x <= t).clamp(1, grid.len() - 1);
        let w = (t - grid[k - 1]) / (grid[k] - grid[k - 1]);
        g[k - 1] + w * (g[k] - g[k - 1])
    };
    for c in 0..s.channels.len() {
        for (on_grid, at_readings, what) in [
            (&s.corrected_grid[c], &s.corrected[c], "corrected"),
            (&s.baseline_grid[c], &s.baseline[c], "baseline"),
        ] {
            let d2: Vec<f64> = s
                .time_s
                .iter()
                .zip(at_readings)
                .map(|(&t, &v)| (at(on_grid, t) - v).powi(2))
                .collect();
            let rms = (d2.iter().sum::<f64>() / d2.len() as f64).sqrt();
            assert!(
                rms < 0.05,
                "{}: {what} model on its grid {rms} K off",
                s.channels[c]
            );
        }
    }
    // the longest stretch without a reading (fill rows) between two readings
    let read: Vec<f64> = s
        .time_s
        .iter()
        .zip(&s.recorded[0])
        .filter(|(_, v)| v.is_some())
        .map(|(t, _)| *t)
        .collect();
    let gap = read
        .windows(2)
        .max_by(|a, b| (a[1] - a[0]).total_cmp(&(b[1] - b[0])))
        .unwrap();
    assert!(gap[1] - gap[0] > 1800.0, "a gap of {} s", gap[1] - gap[0]);
    assert!(grid.iter().filter(|&&t| t > gap[0] && t < gap[1]).count() > 30);
    // The calibration is fitted first and reported as calibration: the global sunlight
    // and infrared scales and the two largest thermal masses (chassis, stack), which
    // remove most of the baseline's held-out residual on this day; none of them is a
    // finding.
    let calibrated: Vec<(&str, String)> = d
        .calibration
        .iter()
        .map(|c| (c.effect.id(), c.target.node().unwrap_or_default()))
        .collect();
    for want in [
        ("capacitance_scale", "chassis"),
        ("capacitance_scale", "stack"),
        ("sunlight_scale", ""),
        ("infrared_scale", ""),
    ] {
        assert!(
            calibrated.iter().any(|(e, n)| *e == want.0 && n == want.1),
            "{want:?} not in the calibration {calibrated:?}"
        );
    }
    let share = d.calibration_heldout_share.expect("a calibration share");
    eprintln!(
        "the calibration removes {:.0} % of the held-out χ²",
        100.0 * share
    );
    assert!(share > 0.5, "{share}");
    // In a model with faces the outside is its faces: no node, faced or inside, is
    // offered Earth loads (on an inner node they would be more heat by another name).
    assert!(
        d.candidates
            .iter()
            .all(|c| c.effect.id() != "earth_albedo_ir"),
        "Earth loads offered in a faced model"
    );
    for f in &d.findings {
        assert!(
            !matches!(f.effect.id(), "sunlight_scale" | "infrared_scale"),
            "a calibration number reported as a finding: {}",
            f.effect
        );
        // no stand-in for "more heat"
        assert_ne!(f.effect.id(), "earth_albedo_ir", "{:?}", f.target);
        // every finding lowers the held-out χ² in the final joint fit, and carries its
        // intervals around its values
        assert!(
            f.heldout_chi2_drop > 0.0,
            "{}: {}",
            f.effect,
            f.heldout_chi2_drop
        );
        // ... by at least the 1 % of what the final fit leaves without it that the
        // report now prints beside the share of the calibrated model's (the −Y offset's
        // 0.7 % of that read as a finding under 1 % accepted)
        assert!(
            f.heldout_share_without >= orbitlash::diagnose::MIN_FINDING_SHARE
                && f.heldout_share_without >= f.heldout_share,
            "{}: {} of the fit without it, {} of the calibrated model's",
            f.effect,
            f.heldout_share_without,
            f.heldout_share
        );
        for (k, v) in &f.parameters {
            if let Some(Some([lo, hi])) = f.intervals_95.get(k) {
                assert!(lo <= v && v <= hi, "{k}: {lo} … {hi} around {v}");
            }
        }
    }
    // The goals of issue 29 this day meets: the silver chassis at ≤ 2 °C and the
    // panels at ≤ 3 °C held out; the black chassis (goal 2 °C, docs/validation.md) is
    // kept from getting worse than it is (2.01 with the telemetry's clock offset, 2.10
    // without).
    let rmse = |ch: &str| d.heldout_rmse.get(ch).unwrap();
    assert!(
        rmse("chassis_silver_c") <= 2.0,
        "{}",
        rmse("chassis_silver_c")
    );
    for ch in ["panel_px_c", "panel_mx_c", "panel_py_c", "panel_my_c"] {
        assert!(rmse(ch) <= 3.0, "{ch}: {}", rmse(ch));
    }
    assert!(
        rmse("chassis_black_c") <= 2.05,
        "{}",
        rmse("chassis_black_c")
    );
}

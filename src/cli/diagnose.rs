//! `orbitlash diagnose`: a recording against the scenario (see `orbitlash::diagnose`).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result};
use clap::Args;

use orbitlash::diagnose::{self, CandidateStatus, Diagnosis, Options, Verdict};
use orbitlash::io::output::{OutputPolicy, Outputs};
use orbitlash::io::recording::Recording;
use orbitlash::units::sig;

use super::table::{self, Align};
use super::{Outcome, load_with, print_out};

#[derive(Args, Debug)]
pub struct DiagnoseArgs {
    /// The scenario as the model has it (e.g. scenarios/reference-hinge.toml).
    scenario: PathBuf,
    /// The recording: CSV (time_s and the scenario's sensor columns) or MCAP.
    #[arg(long)]
    recording: PathBuf,
    /// Also write the machine-readable report (stable keys, see the README).
    #[arg(long, value_name = "REPORT.json")]
    json: Option<PathBuf>,
    /// Also write into this folder (created if missing; a default-free name, any
    /// place that is not an input): `corrected.toml` (the scenario with the accepted
    /// effects, runnable as it is), `diagnose.mcap` (recording, baseline, corrected and
    /// residuals side by side), `series.csv` (the same series as CSV, for any plotting
    /// tool), `overview.svg` (every channel, recorded against the baseline and
    /// corrected models) and `residuals-<channel>.svg` (one channel and its residual
    /// before and after).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Whole orbits held out at the end of the recording for validation (default: a
    /// third of them, at least one). They are never used for fitting or ranking.
    #[arg(long, value_name = "N")]
    holdout_orbits: Option<usize>,
    /// Forward selection adds at most this many effects (1 … 8). Each step costs a
    /// ranking of every candidate and 4 joint fits; see `docs/performance.md`.
    #[arg(long, value_name = "N", default_value_t = Options::default().max_effects as u8,
          value_parser = clap::value_parser!(u8).range(1..=8))]
    max_effects: u8,
    /// Search the vocabulary on the model as it is, without fitting the calibration
    /// set first (`[[uncertain]]`, and for a model with faces the global sunlight and
    /// infrared scales and its two largest thermal masses).
    #[arg(long)]
    no_calibration: bool,
    /// Fit at most this many single candidates, the best ranked first (1 … 200); the
    /// report says how many more could have passed on their ranking.
    #[arg(long, value_name = "N", default_value_t = Options::default().fits as u16,
          value_parser = clap::value_parser!(u16).range(1..=200))]
    fits: u16,
    /// A partial explanation (one that leaves the held-out orbits above the noise) is
    /// reported only when it removes at least this share of the reference's held-out
    /// residual (0 … 1).
    #[arg(long, value_name = "SHARE", default_value_t = Options::default().min_partial_share,
          value_parser = share_arg)]
    min_partial_share: f64,
    /// The most one channel may weigh against the typical channel of its unit (weight
    /// = 1/noise², 1 … 1e6): a smooth channel's estimated noise is raised to keep it
    /// there.
    #[arg(long, value_name = "RATIO", default_value_t = Options::default().max_weight_ratio,
          value_parser = weight_ratio_arg)]
    max_weight_ratio: f64,
    /// Change a number of the scenario by its key path (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Run even when the estimate exceeds the limits (5e7 steps for one run of the model
    /// over the recording, 1e9 in all).
    #[arg(long)]
    force: bool,
}

pub fn diagnose(a: DiagnoseArgs) -> Result<Outcome> {
    // Ctrl-C from the start is a stop that says so (exit 2), not a death by signal
    super::interrupt_flag();
    let loaded = load_with(Some(&a.scenario), &a.sets)?;
    let mut inputs = loaded.inputs();
    inputs.push(&a.recording);
    // The outputs' places are checked before anything is read or run: the recording's
    // columns name the residual plots, so those are checked once it is read.
    let mut outs = Outputs::new(OutputPolicy::reading(&inputs));
    if let Some(p) = &a.json {
        outs.file("--json", p)?;
    }
    if let Some(dir) = &a.out {
        outs.folder("--out", dir, true)?;
        for name in [
            "corrected.toml",
            "diagnose.mcap",
            "series.csv",
            "overview.svg",
        ] {
            outs.file(&format!("--out ({name})"), &dir.join(name))?;
        }
    }
    // Inputs that follow the recording ([[input]]) are set in the model diagnosed.
    let mut model = loaded.model.clone();
    let (mut rec, read_notes, eclipses) = read_recording(&a.recording, &mut model)?;
    let mut absent = absent_sensors(&rec, &model);
    absent.extend(empty_sensors(&mut rec, &model));
    // The recording against the model (channels, values, time base, the held-out
    // split), before the cost estimate: what cannot be judged is refused first.
    diagnose::data::Observations::new(&rec, model.scenario(), a.holdout_orbits)?;
    if let Some(dir) = &a.out {
        for c in &rec.columns {
            let name = residual_plot_name(c);
            outs.file(&format!("--out ({name})"), &dir.join(&name))?;
        }
    }
    let span_s = rec.time_s.last().copied().unwrap_or(0.0);
    let values = rec
        .values
        .iter()
        .map(|c| c.iter().flatten().count())
        .sum::<usize>() as f64;
    super::estimate::diagnose(
        loaded.scenario(),
        span_s,
        values,
        diagnose::expected_runs(&model),
        a.force,
    )?;
    let opts = Options {
        holdout_orbits: a.holdout_orbits,
        max_effects: usize::from(a.max_effects),
        calibrate: !a.no_calibration,
        max_weight_ratio: a.max_weight_ratio,
        min_partial_share: a.min_partial_share,
        fits: usize::from(a.fits),
        ..Options::default()
    };
    let bar = (!a.quiet && std::io::stderr().is_terminal()).then(|| {
        let b = indicatif::ProgressBar::new(1);
        b.set_style(
            indicatif::ProgressStyle::with_template("{msg:10} {bar:40} {pos}/{len}, {elapsed}")
                .expect("a valid template"),
        );
        b
    });
    let stage = Mutex::new(String::new());
    let t0 = std::time::Instant::now();
    let trace = std::env::var_os("ORBITLASH_TRACE").is_some();
    let progress = |name: &str, done: usize, total: usize| {
        if trace && done == total {
            eprintln!(
                "TRACE {name} {total} at {:.2} s",
                t0.elapsed().as_secs_f64()
            );
        }
        if let Some(b) = &bar {
            let mut s = stage.lock().unwrap();
            if *s != name {
                *s = name.to_string();
                b.set_message(name.to_string());
                b.set_length(total as u64);
            }
            b.set_position(done as u64);
        }
    };
    // Stopped while diagnosing: nothing is written yet, exit 2 saying so (`watched`).
    let result = super::watched(
        || {},
        || {
            if let Some(b) = &bar {
                b.abandon();
            }
            format!(
                "interrupted after {:.1} s: nothing was written (diagnose writes its outputs when the analysis is done)",
                t0.elapsed().as_secs_f64()
            )
        },
        || diagnose::diagnose(&model, &rec, &opts, &progress),
    );
    let mut d = result.with_context(|| format!("diagnose {} against {}", rec.file, loaded.file))?;
    for n in read_notes.into_iter().rev() {
        d.notes.insert(0, n);
    }
    if let Some(w) = eclipses
        .as_ref()
        .and_then(|c| eclipse_warning(c, loaded.scenario().recording.time_offset_s))
    {
        d.warnings.push(w);
    }
    d.warnings.extend(absent);
    d.recording.eclipses = eclipses;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    for n in &d.warnings {
        eprintln!("warning: {n}");
    }
    let mut o = format_report(
        &d,
        &loaded.file,
        &rec.file,
        &loaded.scenario().thermal.environment,
    );
    let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    if let Some(p) = &a.json {
        files.push((
            p.clone(),
            (serde_json::to_string_pretty(&d)? + "\n").into_bytes(),
        ));
    }
    if let Some(dir) = &a.out {
        files.extend(out_files(dir, &d, &loaded, &rec.file, span_s)?);
    }
    let refs: Vec<(&Path, &[u8])> = files
        .iter()
        .map(|(p, b)| (p.as_path(), b.as_slice()))
        .collect();
    outs.write_all(&refs)?;
    if let Some(p) = &a.json {
        outln!(o, "json: {}", super::shown_path(p));
    }
    for (p, _) in files.iter().filter(|(p, _)| Some(p) != a.json.as_ref()) {
        outln!(o, "wrote: {}", super::shown_path(p));
    }
    print_out(&o)?;
    Ok(Outcome::Pass)
}

/// The recording at `path` as `model`'s `[recording]` lays it out (or an orbitlash run
/// log): its clock checked on the eclipse column, its `[[input]]` channels fed to
/// `model`, its channels named after the sensors. Returns it with notes for the report
/// (what the inputs did; for a log cut off by a killed run, what was read of it) and
/// the clock's check.
fn read_recording(
    path: &Path,
    model: &mut orbitlash::spec::model::Model,
) -> Result<(
    Recording,
    Vec<String>,
    Option<orbitlash::recording::EclipseCheck>,
)> {
    match Recording::read_with(path, &model.scenario().recording) {
        Ok(mut r) => {
            let eclipses = r.take_eclipse_check(model)?;
            let followed = r.feed_inputs(model)?;
            let followed = followed.iter().map(|f| format!("input: {f}")).collect();
            r.name_channels(&model.scenario().sensors);
            Ok((r, followed, eclipses))
        }
        // An orbitlash run log: its node temperatures and backlash as the sensors read.
        Err(e) => match recording_from_log(path, model.scenario()) {
            Some((r, cut)) => Ok((r, cut.into_iter().collect(), None)),
            None => Err(e.into()),
        },
    }
}

/// What the recording's eclipses say of its clock, when it is off: the offset to set
/// when its edges tell one ([`EclipseCheck::clock_offset_s`]), else, when its rows
/// disagree with the orbit's shadow ([`EclipseCheck::disagrees`]), where to look.
fn eclipse_warning(c: &orbitlash::recording::EclipseCheck, now: f64) -> Option<String> {
    if let Some(m) = c.clock_offset_s() {
        return Some(format!(
            "the recording's eclipses come {m:+.1} s from the orbit's, entries and exits alike: its clock is off; try [recording] time_offset_s = {:.0} (now {now})",
            now - m
        ));
    }
    c.disagrees().then(|| {
        let edges = match (c.mean_entry_s(), c.mean_exit_s()) {
            (Some(e), Some(x)) => format!(
                "its entries come {e:+.1} s and its exits {x:+.1} s from the orbit's"
            ),
            (Some(e), None) => format!("its entries come {e:+.1} s from the orbit's (no exit is within a quarter orbit of one)"),
            (None, Some(x)) => format!("its exits come {x:+.1} s from the orbit's (no entry is within a quarter orbit of one)"),
            (None, None) => "none of its edges is within a quarter orbit of the orbit's".to_string(),
        };
        format!(
            "the recording's eclipses (`{}` below {}) agree with the orbit's shadow on only {:.1} % of its rows and {edges}: its clock ([recording] time_offset_s, now {now} s), the orbit ([orbit] tle, start_utc) or eclipse_below is off",
            orbitlash::units::shown(&c.column),
            c.below,
            100.0 * c.agreement
        )
    })
}

/// The sensors' columns of `rec` with every cell empty, taken out of it with a warning
/// each, as a column the recording lacks is ([`absent_sensors`]): the fit goes on
/// without them. Kept (and refused by the diagnosis, naming them) when no sensor's
/// column has a value.
fn empty_sensors(rec: &mut Recording, model: &orbitlash::spec::model::Model) -> Vec<String> {
    let sensors = &model.scenario().sensors;
    let is_sensor = |c: &String| sensors.iter().any(|s| &s.column == c);
    let empty: Vec<usize> = (0..rec.columns.len())
        .filter(|&k| is_sensor(&rec.columns[k]) && rec.values[k].iter().all(Option::is_none))
        .collect();
    let with_values = (0..rec.columns.len())
        .filter(|k| is_sensor(&rec.columns[*k]) && !empty.contains(k))
        .count();
    if empty.is_empty() || with_values == 0 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for &k in empty.iter().rev() {
        let column = rec.columns.remove(k);
        rec.values.remove(k);
        let source = sensors
            .iter()
            .find(|s| s.column == column)
            .map_or(column.as_str(), |s| s.source_column.as_str());
        out.push(format!(
            "sensor `{}` (column `{}`): every cell of its column in {} is empty: diagnose fits the other {with_values} channel(s) without it",
            orbitlash::units::shown(&column),
            orbitlash::units::shown(source),
            rec.file
        ));
    }
    out.reverse();
    out
}

/// A warning for each sensor of the scenario the recording has no column for (an input
/// that follows a sensor's column takes it on purpose): the fit goes on without it.
fn absent_sensors(rec: &Recording, model: &orbitlash::spec::model::Model) -> Vec<String> {
    let inputs = &model.spec().input;
    let sensors = &model.scenario().sensors;
    sensors
        .iter()
        .filter(|s| {
            !rec.columns.contains(&s.column) && !inputs.iter().any(|i| i.column == s.source_column)
        })
        .map(|s| {
            format!(
                "sensor `{}` (column `{}`) is not in the recording: diagnose fits the other {} channel(s) without it",
                orbitlash::units::shown(&s.column),
                orbitlash::units::shown(&s.source_column),
                rec.columns.len()
            )
        })
        .collect()
}

fn residual_plot_name(channel: &str) -> String {
    format!("residuals-{channel}.svg")
}

/// The corrected scenario's name: the original's with `-corrected` (so that running it
/// writes its own default log).
fn corrected_name(name: &str) -> String {
    const SUFFIX: &str = "-corrected";
    let keep = orbitlash::spec::scenario::MAX_NAME_LEN - SUFFIX.len();
    let mut base: String = name.chars().take(keep).collect();
    while base.len() > keep {
        base.pop();
    }
    base + SUFFIX
}

/// `--out DIR`: corrected scenario, side-by-side MCAP, residual plots, as
/// (path, bytes).
fn out_files(
    dir: &Path,
    d: &Diagnosis,
    loaded: &super::Loaded,
    recording: &str,
    span_s: f64,
) -> Result<Vec<(PathBuf, Vec<u8>)>> {
    let mut files = Vec::new();
    // The corrected scenario: the user's file edited (comments and spellings kept),
    // the accepted effects added as commented elements, its own name, and a run as long
    // as the recording.
    // The file as the user wrote it (without the --set changes, which the corrected
    // model carries and which are therefore written into it).
    let from = &orbitlash::io::scenario_toml::parse_spec(&loaded.toml, &loaded.file)?;
    let mut to = d
        .corrected
        .as_ref()
        .map_or(loaded.model.spec(), |m| m.spec())
        .clone();
    to.scenario.name = corrected_name(&from.scenario.name);
    to.run.orbits = None;
    to.run.duration_days = None;
    to.run.duration_s = Some(span_s);
    let mut header = vec![
        format!(
            "{} corrected by `orbitlash diagnose` against {} (verdict: {}).",
            loaded.file,
            recording,
            d.verdict.as_str()
        ),
        format!(
            "Its name is {}; [run] lasts as long as the recording ({} s).",
            to.scenario.name,
            orbitlash::units::exact(span_s)
        ),
    ];
    for (k, v) in &loaded.sets {
        header.push(format!(
            "--set {k}={} of the diagnosed model is written in",
            orbitlash::units::exact(*v)
        ));
    }
    for c in &d.calibration {
        let values: Vec<String> = c
            .parameters
            .iter()
            .map(|(k, v)| match c.nominal.get(k) {
                Some(n) => format!("{k} = {} (nominal {})", sig(*v), sig(*n)),
                None => format!("{k} = {}", sig(*v)),
            })
            .collect();
        let keys: Vec<&str> = c.set.keys().map(String::as_str).collect();
        header.push(format!(
            "calibrated: {} on {}: {}; written into {}",
            c.effect,
            target_text(&c.target),
            values.join(", "),
            keys.join(", ")
        ));
    }
    for f in &d.findings {
        header.push(format!("added: {} on {}", f.effect, finding_target(f)));
    }
    if d.findings.is_empty() {
        header.push("no effect was accepted: the model is the original's".into());
    }
    let keys = orbitlash::spec::keys::element_keys(&to);
    let comment = |section: &str, i: usize| {
        let key = keys.section(section)?.get(i)?;
        let prefix = format!("{section}.{}.", orbitlash::spec::keys::quote_key(key));
        let f = d
            .findings
            .iter()
            .find(|f| f.set.keys().any(|k| k.starts_with(&prefix)))?;
        let mut c = format!(
            "added by `orbitlash diagnose`: {} ({}) on {}; ΔBIC {:.0}, held-out χ² lower by {:.0}",
            f.effect,
            f.kind,
            finding_target(f),
            f.delta_bic,
            f.heldout_chi2_drop
        );
        for (k, v) in &f.parameters {
            c += &format!("\nfitted {k} = {}", sig(*v));
            if let Some(Some(se)) = f.std_errors.get(k) {
                c += &format!(" ± {}", sig(*se));
            }
        }
        if let Some(note) = f.effect.parameters_note() {
            c += &format!("\n({note})");
        }
        Some(c)
    };
    let text = orbitlash::io::scenario_toml::edited(&loaded.toml, from, &to, &header, &comment)?;
    files.push((dir.join("corrected.toml"), text.into_bytes()));
    let sc = loaded.scenario();
    let origin_ns = sc.thermal.environment.start_unix_ns();
    let mcap = orbitlash::io::diagnose_out::mcap_bytes(d, &sc.name, origin_ns).map_err(|e| {
        anyhow::anyhow!("cannot write {}: {e}", dir.join("diagnose.mcap").display())
    })?;
    files.push((dir.join("diagnose.mcap"), mcap));
    files.push((
        dir.join("series.csv"),
        orbitlash::io::diagnose_out::series_csv(d).into_bytes(),
    ));
    let title = format!(
        "{}: {} against the model, before and after",
        &loaded.scenario().name,
        Path::new(recording)
            .file_name()
            .map_or(recording.to_string(), |n| n.to_string_lossy().into_owned())
    );
    let fig = orbitlash::plot::overview::overview(&d.series, &title)
        .map_err(|e| anyhow::anyhow!("cannot draw overview.svg: {e}"))?;
    files.push((dir.join("overview.svg"), fig.svg_file().into_bytes()));
    for (c, name) in d.series.channels.iter().enumerate() {
        let fig = orbitlash::plot::diagnose::channel(&d.series, c)
            .map_err(|e| anyhow::anyhow!("cannot draw {}: {e}", residual_plot_name(name)))?;
        files.push((
            dir.join(residual_plot_name(name)),
            fig.svg_file().into_bytes(),
        ));
    }
    Ok(files)
}

/// A finding's target as the report says it: `node housing, schedule sunlit` (a gear
/// stands for its pair).
fn finding_target(f: &diagnose::Finding) -> String {
    target_text(&f.target)
}

/// What an effect acts on, as the report says it.
fn target_text(t: &diagnose::effects::Target) -> String {
    if *t == diagnose::effects::Target::Spacecraft {
        return "the spacecraft".into();
    }
    let mut parts = Vec::new();
    for (k, v) in t.fields() {
        let Some(v) = v else { continue };
        if k == "gear_pair" && t.gear().is_some() {
            continue;
        }
        let k = if k == "path" { "key path" } else { k };
        parts.push(format!("{} {v}", k.replace('_', " ")));
    }
    parts.join(", ")
}

/// `--min-partial-share`: a share within 0 … 1.
fn share_arg(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a share within 0 … 1")),
    }
}

/// `--max-weight-ratio`: a number within 1 … 1e6.
fn weight_ratio_arg(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (1.0..=1e6).contains(&v) => Ok(v),
        _ => Err(format!("`{s}` is not a number within 1 … 1e6")),
    }
}

fn unit_of(name: &str) -> &'static str {
    if name.ends_with("_um") { "µm" } else { "K" }
}

/// ` (lines 3, 7, 9, …)`: the first few of `lines`, or nothing.
fn lines_shown(lines: &[u64]) -> String {
    if lines.is_empty() {
        return String::new();
    }
    let first: Vec<String> = lines.iter().take(6).map(u64::to_string).collect();
    format!(
        " (line{} {}{})",
        if lines.len() > 1 { "s" } else { "" },
        first.join(", "),
        if lines.len() > first.len() {
            ", …"
        } else {
            ""
        }
    )
}

/// The human report: its sections in order (verdict and split, the channel table,
/// where the baseline residual sits, the findings, the residual that remains, the
/// candidates), each formatted by its own function.
pub fn format_report(
    d: &Diagnosis,
    scenario: &str,
    recording: &str,
    env: &orbitlash::orbit::Environment,
) -> String {
    // the unit of the figures, chosen by the series' last time as they do
    let span = d
        .series
        .time_s
        .last()
        .copied()
        .unwrap_or(d.split.holdout_end_s);
    let clock = Clock::new(span, env);
    let mut o = String::new();
    report_head(&mut o, d, scenario, recording);
    report_channels(&mut o, d);
    report_where(&mut o, d, &clock);
    report_calibration(&mut o, d);
    report_findings(&mut o, d, &clock);
    report_remaining(&mut o, d);
    report_candidates(&mut o, d);
    o
}

/// The verdict, the files, the held-out split, the recording's rows and the notes.
fn report_head(o: &mut String, d: &Diagnosis, scenario: &str, recording: &str) {
    let verdict = match d.verdict {
        Verdict::Consistent => {
            "CONSISTENT: the model fits the recording to its noise; nothing to add"
        }
        Verdict::Explained => "EXPLAINED: the model left out what the findings below add",
        Verdict::Unexplained if !d.findings.is_empty() => {
            "UNEXPLAINED: the findings below explain part of the residual; a structured residual remains that no effect of the vocabulary fits"
        }
        Verdict::Unexplained => {
            "UNEXPLAINED: a structured residual remains that no effect of the vocabulary fits"
        }
    };
    outln!(o, "{verdict}");
    outln!(o, "scenario {scenario}, recording {recording}");
    let s = &d.split;
    if s.holdout_orbits > 0 {
        // an orbit short by under a sampling interval counts as whole: said when it is;
        // a recording that starts after the scenario's t = 0 keeps the scenario's orbit
        // numbers (as its times, the figures and `baseline.orbit_rmse` do)
        let stops = (s.last_orbit_short_s >= 0.05).then(|| {
            format!(
                "stops {:.1} s before the last one ends, within a sampling interval",
                s.last_orbit_short_s
            )
        });
        let what = if s.first_orbit > 0 {
            let starts = format!("starts at t = {} s", orbitlash::units::num(s.start_s));
            let and = stops.map(|x| format!(" and {x}")).unwrap_or_default();
            format!(
                "{} orbits of {:.1} s, {}–{} of the scenario (the recording {starts}{and})",
                s.recorded_orbits(),
                s.period_s,
                s.first_orbit + 1,
                s.orbits
            )
        } else {
            let stops = stops
                .map(|x| format!(" (the recording {x})"))
                .unwrap_or_default();
            format!("{} whole orbits of {:.1} s{stops}", s.orbits, s.period_s)
        };
        outln!(
            o,
            "{what}: fitted on {}, checked on {} (held out, never fitted)",
            s.fitted_span(),
            s.held_span()
        );
    }
    let r = &d.recording;
    if !r.plain() {
        outln!(
            o,
            "recording: {} rows, {} measured; {} fill (rows repeating the row before, kept out of noise, fits and scores){}; {} merged into the row before (a repeated time stamp){}",
            r.rows,
            r.measured_rows,
            r.fill_rows.len(),
            lines_shown(&r.fill_rows),
            r.merged_rows.len(),
            lines_shown(&r.merged_rows)
        );
    }
    if let Some(c) = &r.eclipses {
        let shown = |m: Option<f64>| m.map_or("–".to_string(), |m| format!("{m:+.1} s"));
        outln!(
            o,
            "eclipses: `{}` below {} against the orbit's shadow: {:.2} % of {} rows agree; {} entries {}, {} exits {} from the orbit's (recorded − predicted)",
            c.column,
            c.below,
            100.0 * c.agreement,
            c.rows,
            c.entries_s.len(),
            shown(c.mean_entry_s()),
            c.exits_s.len(),
            shown(c.mean_exit_s())
        );
    }
    for n in &d.notes {
        outln!(o, "note: {n}");
    }
}

/// Each channel's noise and its baseline and corrected residuals.
fn report_channels(o: &mut String, d: &Diagnosis) {
    outln!(o, "");
    // the channel column as wide as the longest name
    let w = d
        .noise
        .0
        .iter()
        .map(|(n, _)| n.chars().count())
        .max()
        .unwrap_or(0)
        .max(13);
    outln!(
        o,
        "{:<w$}  noise   baseline rms (fit / held-out)   corrected held-out rms",
        "channel"
    );
    for (name, sigma) in &d.noise.0 {
        let u = unit_of(name);
        let b = d.baseline.rmse.get(name).unwrap_or(f64::NAN);
        let bh = d.baseline.heldout_rmse.get(name).unwrap_or(f64::NAN);
        let ch = d.heldout_rmse.get(name).unwrap_or(f64::NAN);
        // a channel with no held-out readings (a sensor lost) has no held-out figures
        let shown = |v: f64| {
            if v.is_finite() {
                format!("{v:>8.3}")
            } else {
                format!("{:>8}", "—")
            }
        };
        let times = if ch.is_finite() {
            format!("({:.2}× noise)", ch / sigma)
        } else {
            "(no held-out readings)".to_string()
        };
        outln!(
            o,
            "{name:<w$} {sigma:>6.3} {u:<2}  {b:>8.3} / {} {u:<2}        {} {u:<2} {times}",
            shown(bh),
            shown(ch)
        );
    }
    let scatter: Vec<String> = d
        .orbit_scatter
        .0
        .iter()
        .filter(|(_, v)| v.is_finite())
        .map(|(n, v)| format!("{n} {v:.3} {}", unit_of(n)))
        .collect();
    if !scatter.is_empty() {
        outln!(
            o,
            "orbit-to-orbit scatter (readings about the mean orbit; no periodic model fits closer): {}",
            scatter.join(", ")
        );
    }
    outln!(o, "");
}

/// Times of the report in the unit of the figures (`plot::time_unit` of the
/// recording's span: hours up to three days), with the UTC date and time when the
/// scenario is dated.
struct Clock<'a> {
    unit_s: f64,
    unit: &'static str,
    env: &'a orbitlash::orbit::Environment,
}

impl Clock<'_> {
    fn new(span_s: f64, env: &orbitlash::orbit::Environment) -> Clock<'_> {
        let (unit_s, unit) = orbitlash::plot::time_unit(span_s);
        Clock { unit_s, unit, env }
    }

    /// `12.510 h` (`, 2016-02-04 12:30:37 UTC` when dated).
    fn at(&self, t_s: f64) -> String {
        match self.env.utc_at(t_s) {
            Some(u) => format!(
                "{:.3} {}, {} UTC",
                t_s / self.unit_s,
                self.unit,
                u.format("%Y-%m-%d %H:%M:%S")
            ),
            None => format!("{:.3} {}", t_s / self.unit_s, self.unit),
        }
    }

    /// `1.400 … 1.433 h`.
    fn span(&self, a_s: f64, b_s: f64) -> String {
        format!(
            "{:.3} … {:.3} {}",
            a_s / self.unit_s,
            b_s / self.unit_s,
            self.unit
        )
    }
}

/// Where the baseline residual sits, largest first.
fn report_where(o: &mut String, d: &Diagnosis, clock: &Clock<'_>) {
    if d.mismatches.is_empty() {
        outln!(o, "where: no channel's baseline residual exceeds its noise");
    } else {
        outln!(o, "where the baseline residual sits (largest first):");
        let shown = &d.mismatches[..d.mismatches.len().min(12)];
        let w = shown
            .iter()
            .map(|m| m.channel.chars().count())
            .max()
            .unwrap_or(0)
            .max(13);
        for m in shown {
            outln!(
                o,
                "  {:<w$} {:<13} rms {:.3} {} ({:.1}× noise, mean {:+.3}), {:.0} % of the channel's residual; \
                 first at t = {}; {:.0} … {:.0} s after orbit noon in {} orbit(s)",
                m.channel,
                m.phase,
                m.rms,
                unit_of(&m.channel),
                m.rms_over_noise,
                m.mean,
                100.0 * m.share,
                clock.span(m.t_start_s, m.t_end_s),
                m.orbit_t_start_s,
                m.orbit_t_end_s,
                m.orbits.len()
            );
        }
    }
    outln!(o, "");
}

/// What the model left out: each finding's parameters, correlations and evidence.
/// The calibration: the model's own numbers, adjusted (never missing physics).
fn report_calibration(o: &mut String, d: &Diagnosis) {
    if d.calibration.is_empty() {
        return;
    }
    outln!(
        o,
        "the model's numbers, adjusted (calibration{}):",
        d.calibration_heldout_share
            .map_or(String::new(), |s| format!(
                ": alone it removes {:.0} % of the baseline's held-out residual",
                100.0 * s
            ))
    );
    for c in &d.calibration {
        let values: Vec<String> = c
            .parameters
            .iter()
            .map(|(k, v)| {
                let se = c.std_errors.get(k).copied().flatten();
                let nominal = c
                    .nominal
                    .get(k)
                    .map_or(String::new(), |n| format!(", nominal {}", sig(*n)));
                match se {
                    Some(se) => format!("{k} = {} ± {}{nominal}", sig(*v), sig(se)),
                    None => format!("{k} = {}{nominal}", sig(*v)),
                }
            })
            .collect();
        outln!(
            o,
            "  {} on {}: {}",
            c.effect,
            target_text(&c.target),
            values.join("; ")
        );
    }
    outln!(o, "");
}

fn report_findings(o: &mut String, d: &Diagnosis, clock: &Clock<'_>) {
    if !d.findings.is_empty() {
        outln!(o, "what the model left out:");
        for f in &d.findings {
            outln!(o, "  {} ({}) on {}", f.effect, f.kind, finding_target(f));
            if let Some(note) = f.effect.parameters_note() {
                outln!(o, "      ({note})");
            }
            for (k, v) in &f.parameters {
                let se = f.std_errors.get(k).copied().flatten();
                match (se, f.intervals_95.get(k).copied().flatten()) {
                    (Some(se), Some([lo, hi])) => outln!(
                        o,
                        "      {k} = {} ± {} (95 %: {} … {})",
                        sig(*v),
                        sig(se),
                        sig(lo),
                        sig(hi)
                    ),
                    _ => outln!(o, "      {k} = {} (its interval is not defined)", sig(*v)),
                }
                // a time of the recording (a switch-on): also in the figures' unit
                if k == "on_s" {
                    outln!(o, "      ({k} is t = {})", clock.at(*v));
                }
            }
            if f.correlation.len() > 1 {
                for i in 0..f.correlation.len() {
                    for j in i + 1..f.correlation.len() {
                        if let Some(r) = f.correlation[i][j] {
                            outln!(
                                o,
                                "      correlation({}, {}) = {:+.2}",
                                f.correlation_order[i],
                                f.correlation_order[j],
                                r
                            );
                        }
                    }
                }
            }
            outln!(
                o,
                "      evidence: ΔBIC {:.0} on the fitted orbits (the final joint fit with it against without), held-out χ² lower by {:.0} in the final joint fit ({:.1} % of what it leaves without this finding, {:.0} % needed; {:.1} % of the {}'s)",
                f.delta_bic,
                f.heldout_chi2_drop,
                100.0 * f.heldout_share_without,
                100.0 * orbitlash::diagnose::MIN_FINDING_SHARE,
                100.0 * f.heldout_share,
                if d.calibration.is_empty() {
                    "baseline"
                } else {
                    "calibrated model"
                }
            );
            report_doubts(o, f);
        }
        outln!(o, "");
    }
}

/// What weakens a finding: numbers it is confounded with, rivals that explain about
/// as well, a size that moves when another effect is allowed.
fn report_doubts(o: &mut String, f: &orbitlash::diagnose::Finding) {
    for c in &f.correlated {
        outln!(
            o,
            "      confounded: {} correlates {:+.2} with {} of {}",
            c.parameter,
            c.correlation,
            c.with_parameter,
            c.with
        );
    }
    if !f.alternatives.is_empty() {
        let alts: Vec<String> = f
            .alternatives
            .iter()
            .map(|a| format!("{} (ΔBIC {:+.1})", a.candidate, a.delta_bic))
            .collect();
        outln!(
            o,
            "      explains about as well (ΔBIC against this finding, on the fit's noise scale): {}",
            alts.join("; ")
        );
    }
    if let Some(why) = &f.unstable {
        outln!(o, "      unstable: {why}");
    }
}

/// Where the residual that no finding explains sits (an unexplained verdict).
fn report_remaining(o: &mut String, d: &Diagnosis) {
    if d.verdict != Verdict::Consistent
        && !d.remaining.is_empty()
        && d.verdict == Verdict::Unexplained
    {
        outln!(o, "the residual that remains sits:");
        let mut t = table::new(
            &["channel", "phase", "rms", "× noise", "s after orbit noon"],
            &[
                Align::Left,
                Align::Left,
                Align::Right,
                Align::Right,
                Align::Left,
            ],
        );
        for m in d.remaining.iter().take(6) {
            t.add_row(vec![
                m.channel.clone(),
                m.phase.to_string(),
                format!("{:.3} {}", m.rms, unit_of(&m.channel)),
                format!("{:.1}", m.rms_over_noise),
                format!("{:.0} … {:.0}", m.orbit_t_start_s, m.orbit_t_end_s),
            ]);
        }
        o.push_str(&table::render(&t, "  "));
        outln!(o, "");
    }
}

/// The candidates tried, the fitted ones first, and the time taken.
fn report_candidates(o: &mut String, d: &Diagnosis) {
    outln!(
        o,
        "candidates ({} tried; ΔBIC: each fitted against the model of the step it was tried at):",
        d.candidates.len()
    );
    let mut unfitted = 0;
    for c in &d.candidates {
        if c.status == CandidateStatus::NotFitted && c.rank_chi2_drop <= 0.0 {
            continue;
        }
        if c.status == CandidateStatus::NotFitted {
            unfitted += 1;
            if unfitted > 4 {
                continue;
            }
        }
        let bic = c
            .delta_bic
            .map_or(String::new(), |b| format!(" (ΔBIC {b:.0})"));
        let reason = if c.reason.is_empty() {
            "fits".to_string()
        } else {
            c.reason.clone()
        };
        outln!(o, "  {:<10} {}: {reason}{bic}", c.status, c.target);
    }
    if unfitted > 4 {
        outln!(
            o,
            "  ({} more ranked below the fitted candidates)",
            unfitted - 4
        );
    }
    let quiet = d
        .candidates
        .iter()
        .filter(|c| c.status == CandidateStatus::NotFitted && c.rank_chi2_drop <= 0.0)
        .count();
    if quiet > 0 {
        outln!(
            o,
            "  ({quiet} more do not lower the training residual at any start point)"
        );
    }
    outln!(
        o,
        "time: {:.2} s ({:.3} s per candidate)",
        d.time_s,
        d.time_per_candidate_s
    );
}

/// A run log of `orbitlash run` as a recording: each sensor's node temperature (in the
/// column's unit) or its pair's exact backlash at every logged time. The sensors' lags
/// and offsets are not applied (a log holds the model's own values). None when the
/// file is not an orbitlash log.
/// With a note when the log was cut off (read up to its last whole message).
fn recording_from_log(
    path: &Path,
    sc: &orbitlash::spec::scenario::Scenario,
) -> Option<(Recording, Option<String>)> {
    use orbitlash::run::sensor::{ColumnUnit, SensorTarget};
    let table = orbitlash::io::mcap_read::read_log(path).ok()?;
    let topic = "/thermal/temperature";
    let t_col = table.column(&format!("{topic}.time_s"))?;
    let meta = table
        .channel_metadata
        .get(topic)
        .cloned()
        .unwrap_or_default();
    let node_col = |name: &str| {
        table.columns.iter().position(|c| {
            c.strip_prefix(&format!("{topic}.")).is_some_and(|field| {
                meta.get(&format!("node:{field}"))
                    .map_or(field.trim_end_matches("_k") == name, |n| n == name)
            })
        })
    };
    let mut cols = Vec::new();
    for s in &sc.sensors {
        let i = match s.target {
            SensorTarget::Node(n) => node_col(&sc.thermal.network.nodes[n].name)?,
            SensorTarget::Backlash(k) => {
                let pair = &sc.gears[k].name;
                let (t, _) = table
                    .channel_metadata
                    .iter()
                    .find(|(t, m)| t.starts_with("/gears/") && m.get("pair") == Some(pair))?;
                table.column(&format!("{t}.backlash_exact_um"))?
            }
        };
        cols.push((s.column.clone(), i, s.unit()));
    }
    let mut rec = Recording {
        file: path.display().to_string(),
        columns: cols.iter().map(|c| c.0.clone()).collect(),
        time_s: Vec::new(),
        values: vec![Vec::new(); cols.len()],
        rows_at: Vec::new(),
        fill_rows: Vec::new(),
        merged_rows: Vec::new(),
    };
    for (k, (_, row)) in table.rows.iter().enumerate() {
        let t = row[t_col];
        if !t.is_finite() || rec.time_s.last().is_some_and(|&l| t <= l) {
            continue;
        }
        rec.time_s.push(t);
        rec.rows_at.push(k as u64 + 1);
        for (c, (_, i, unit)) in cols.iter().enumerate() {
            let v = row[*i];
            let v = match unit {
                ColumnUnit::Celsius => v - orbitlash::constants::ZERO_CELSIUS_K,
                _ => v,
            };
            rec.values[c].push(v.is_finite().then_some(v));
        }
    }
    let cut = table.truncated.map(|t| {
        format!(
            "{} was cut off (a killed run's log, or a truncated copy): read its {} messages up to t = {:.3} s ({} of {} bytes were whole)",
            path.display(),
            t.messages,
            t.t_end_s,
            t.recovered_bytes,
            t.file_bytes
        )
    });
    Some((rec, cut))
}

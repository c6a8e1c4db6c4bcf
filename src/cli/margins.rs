//! `orbitlash margins`: the scenario's `[[dispersion]]` entries sampled N times, each
//! sample run in parallel, and the report an engineer signs (verdict first).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{Result, bail};
use clap::{Args, ValueEnum};

use orbitlash::dispersion::{Plan, Sampling};
use orbitlash::io::output::{OutputPolicy, check_output, resolved};
use orbitlash::margins::{
    Horizon, MergeError, Report, RunIdentity, SHARD_FORMAT, SampleOutcome, Shard, merge, report,
    run_samples, shard_range,
};

use super::table::{self, Align};
use super::{Outcome, load_with, orbits_arg, print_out, write_file};

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum SamplingArg {
    Random,
    Lhs,
}

impl From<SamplingArg> for Sampling {
    fn from(a: SamplingArg) -> Sampling {
        match a {
            SamplingArg::Random => Sampling::Random,
            SamplingArg::Lhs => Sampling::LatinHypercube,
        }
    }
}

#[derive(Args, Debug)]
pub struct MarginsArgs {
    /// Scenario file (TOML) with `[[dispersion]]` entries.
    scenario: PathBuf,
    /// Number of samples, 1 … 10 000 000 (59 or more for a 95/95 bound).
    #[arg(long, value_parser = samples_arg)]
    samples: u64,
    /// Seed of the draws: the same seed gives the same samples.
    #[arg(long)]
    seed: u64,
    /// Orbits per sample (default: the scenario's run length).
    #[arg(long, value_parser = orbits_arg, conflicts_with = "mission")]
    orbits: Option<f64>,
    /// Run the scenario's whole mission profile per sample (its `[run]` length).
    #[arg(long, conflicts_with = "steady_state")]
    mission: bool,
    /// Each sample's orbit-periodic solution (Newton shooting), one period of it.
    #[arg(long, conflicts_with = "orbits")]
    steady_state: bool,
    /// How samples cover the distributions: independent draws (sample K depends only on
    /// the seed and K), or a Latin hypercube over all N samples.
    #[arg(long, value_enum, default_value = "random")]
    sampling: SamplingArg,
    /// Change a number of the nominal scenario by its key path (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
    /// Also write the report as JSON (stable keys, see the README).
    #[arg(long, value_name = "FILE.json")]
    json: Option<PathBuf>,
    /// Also write every sample (index, dispersed values, results) as CSV.
    #[arg(long, value_name = "FILE.csv")]
    csv: Option<PathBuf>,
    /// Also write plots into this folder (it must exist): per gear pair
    /// `<pair>-min-backlash.svg` (histogram and CDF with the limit and the 95/95 bound)
    /// and `<pair>-sensitivity.svg` (tornado chart).
    #[arg(long, value_name = "DIR", conflicts_with = "shard")]
    plots: Option<PathBuf>,
    /// Run only shard i of n (0-based, e.g. `3/16`): a deterministic slice of the
    /// samples, written with --json as a shard file for `orbitlash merge`.
    #[arg(long, value_name = "I/N", value_parser = shard_arg, requires = "json")]
    shard: Option<(u64, u64)>,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
}

fn shard_arg(s: &str) -> Result<(u64, u64), String> {
    let bad = || format!("`{s}` is not a shard I/N with 0 ≤ I < N ≤ 100000");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (u64, u64) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if n == 0 || n > 100_000 || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

fn samples_arg(s: &str) -> Result<u64, String> {
    match s.parse::<u64>() {
        Ok(n) if (1..=10_000_000).contains(&n) => Ok(n),
        _ => Err(format!(
            "`{s}` is not a whole number of samples within 1 … 10000000"
        )),
    }
}

pub fn margins(a: MarginsArgs) -> Result<Outcome> {
    let loaded = load_with(Some(&a.scenario), &a.sets)?;
    let inputs = loaded.inputs();
    let policy = OutputPolicy::reading(&inputs);
    let outputs: Vec<&Path> = [a.json.as_deref(), a.csv.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    for p in &outputs {
        check_output(p, &policy)?;
    }
    if outputs.len() == 2 && resolved(outputs[0]) == resolved(outputs[1]) {
        bail!("--json and --csv are the same file");
    }
    if let Some(dir) = &a.plots
        && !dir.is_dir()
    {
        bail!("--plots {}: no such directory", dir.display());
    }
    let spec = loaded.model.spec();
    if spec.dispersion.is_empty() {
        bail!(
            "{} has no [[dispersion]]: nothing to sample (see scenarios/README.md)",
            loaded.file
        );
    }
    let plan = Plan::new(
        &loaded.model,
        &spec.dispersion,
        a.sampling.into(),
        a.samples,
        a.seed,
    )
    .map_err(|e| orbitlash::io::scenario_toml::located(&loaded.toml, &loaded.file, e))?;
    let horizon = match (a.orbits, a.steady_state) {
        (Some(n), _) => Horizon::Orbits(n),
        (None, true) => {
            // before any sample runs
            orbitlash::steady::check_repeats(&loaded.scenario.thermal).map_err(|e| {
                anyhow::anyhow!("--steady-state needs an environment that repeats every orbit; {e}")
            })?;
            Horizon::SteadyState
        }
        (None, false) => Horizon::Mission, // the scenario's own run length
    };
    let sc = &loaded.scenario;
    let id = RunIdentity::new(&loaded.toml, &loaded.sets, sc, &plan, horizon);
    let range = match a.shard {
        Some((i, n)) => shard_range(plan.samples, i, n),
        None => 0..plan.samples,
    };
    let done = AtomicU64::new(0);
    let outcomes = run_with_progress(&loaded.model, &plan, range.clone(), horizon, &done, a.quiet)?;
    if let Some((i, n)) = a.shard {
        let shard = Shard {
            format: SHARD_FORMAT.into(),
            run: id,
            shard: (i, n),
            range: (range.start, range.end),
            outcomes,
        };
        let p = a.json.as_ref().expect("--shard requires --json");
        write_file(
            p,
            &policy,
            (serde_json::to_string(&shard)? + "\n").as_bytes(),
        )?;
        print_out(&format!(
            "shard {i}/{n}: samples {} … {} of {} written to {} (merge the shards with `orbitlash merge`)\n",
            range.start,
            range.end.saturating_sub(1),
            plan.samples,
            p.display()
        ))?;
        return Ok(Outcome::Pass);
    }
    let rep = report(&id, &outcomes);
    let mut o = format_report(&rep);
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(&rep)? + "\n";
        write_file(p, &policy, text.as_bytes())?;
        outln!(o, "json: {}", p.display());
    }
    if let Some(p) = &a.csv {
        write_file(p, &policy, samples_csv(&plan, &outcomes, sc).as_bytes())?;
        outln!(o, "csv: {}", p.display());
    }
    if let Some(dir) = &a.plots {
        for p in write_plots(dir, &policy, &rep, &outcomes)? {
            outln!(o, "plot: {}", p.display());
        }
    }
    print_out(&o)?;
    Ok(Outcome::from_pass(rep.verdict == "pass"))
}

fn run_with_progress(
    model: &orbitlash::model::Model,
    plan: &Plan,
    range: std::ops::Range<u64>,
    horizon: Horizon,
    done: &AtomicU64,
    quiet: bool,
) -> Result<Vec<SampleOutcome>> {
    let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
        let b = indicatif::ProgressBar::new(range.end - range.start);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} samples, {elapsed} elapsed, ETA {eta}",
            )
            .expect("a valid template"),
        );
        b
    });
    let finished = std::sync::atomic::AtomicBool::new(false);
    let result = std::thread::scope(|s| {
        if let Some(b) = &bar {
            let finished = &finished;
            s.spawn(move || {
                while !finished.load(Ordering::Relaxed) {
                    b.set_position(done.load(Ordering::Relaxed));
                    std::thread::sleep(std::time::Duration::from_millis(200));
                }
            });
        }
        let r = run_samples(model, plan, range, horizon, done);
        finished.store(true, Ordering::Relaxed);
        r
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    Ok(result?)
}

/// The plots of `rep` into `dir`; returns the files written.
fn write_plots(
    dir: &Path,
    policy: &OutputPolicy,
    rep: &Report,
    outcomes: &[SampleOutcome],
) -> Result<Vec<PathBuf>> {
    if !dir.is_dir() {
        bail!("--plots {}: no such directory", dir.display());
    }
    let mut written = Vec::new();
    for (k, p) in rep.pairs.iter().enumerate() {
        let values: Vec<f64> = outcomes
            .iter()
            .map(|o| o.pairs[k].min_backlash_um)
            .collect();
        let svg = orbitlash::io::svg::distribution(
            &format!(
                "{} / {}: smallest backlash of {} samples",
                rep.scenario, p.name, rep.samples
            ),
            &values,
            p.min_backlash_allowed_um,
            p.tolerance_95_95_um,
            30,
        );
        let file = dir.join(format!("{}-min-backlash.svg", p.name));
        write_file(&file, policy, svg.as_bytes())?;
        written.push(file);
        let rows: Vec<(String, f64)> = p
            .sensitivities
            .iter()
            .map(|s| (s.path.clone(), s.spearman))
            .collect();
        let svg = orbitlash::io::svg::tornado(
            &format!(
                "{} / {}: sensitivity of the smallest backlash",
                rep.scenario, p.name
            ),
            &rows,
        );
        let file = dir.join(format!("{}-sensitivity.svg", p.name));
        write_file(&file, policy, svg.as_bytes())?;
        written.push(file);
    }
    Ok(written)
}

pub fn format_report(r: &Report) -> String {
    let mut o = String::new();
    for p in &r.pairs {
        outln!(o, "{} {}: {}", p.verdict.to_uppercase(), p.name, p.reason);
    }
    outln!(
        o,
        "{}: {} samples ({}), seed {}, {} each; dispersed: {}",
        r.scenario,
        r.samples,
        r.sampling,
        r.seed,
        r.horizon,
        r.dispersed.join(", ")
    );
    for p in &r.pairs {
        outln!(
            o,
            "\ngear pair {} (smallest normal backlash and margin per sample, µm; minimum allowed {:.1} µm):",
            p.name,
            p.min_backlash_allowed_um
        );
        let (d, m) = (&p.min_backlash_um, &p.min_margin_um);
        let mut t = table::new(
            &["", "backlash", "95 % interval", "margin", "95 % interval"],
            &[
                Align::Left,
                Align::Right,
                Align::Left,
                Align::Right,
                Align::Left,
            ],
        );
        let um = |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{v:.3}"));
        let plain = |label: &str, a: f64, b: f64| {
            vec![
                label.to_string(),
                format!("{a:.3}"),
                String::new(),
                format!("{b:.3}"),
                String::new(),
            ]
        };
        t.add_row(plain("min", d.min, m.min));
        for (pc, pm) in d.percentiles.iter().zip(&m.percentiles) {
            t.add_row(vec![
                format!("p{}", pc.percent),
                format!("{:.3}", pc.value),
                format!("{} … {}", um(pc.ci95[0]), um(pc.ci95[1])),
                format!("{:.3}", pm.value),
                format!("{} … {}", um(pm.ci95[0]), um(pm.ci95[1])),
            ]);
        }
        t.add_row(plain("max", d.max, m.max));
        t.add_row(plain("mean", d.mean, m.mean));
        o += &table::render(&t, "  ");
        match p.tolerance_95_95_um {
            Some(v) => outln!(
                o,
                "  95/95 lower tolerance bound: {v:.3} µm (the {} of {} samples, Wilks)",
                ordinal(p.tolerance_rank.unwrap_or(1)),
                r.samples
            ),
            None => outln!(
                o,
                "  95/95 lower tolerance bound: not shown: it needs at least {} samples (Wilks), {} run",
                p.tolerance_samples_needed,
                r.samples
            ),
        }
        for (what, pr) in [
            ("below the minimum", &p.violations),
            ("interference or lost mesh", &p.interference),
        ] {
            outln!(
                o,
                "  P({what}) = {}/{} = {:.4}, 95 % interval {:.4} … {:.4} (Clopper–Pearson)",
                pr.count,
                r.samples,
                pr.estimate,
                pr.ci95[0],
                pr.ci95[1]
            );
        }
        outln!(o, "  sensitivity (Spearman ρ with the smallest backlash):");
        let mut t = table::new(&["", ""], &[Align::Left, Align::Right]);
        for s in &p.sensitivities {
            t.add_row(vec![s.path.clone(), format!("{:+.3}", s.spearman)]);
        }
        o += &table::render(&t, "    ");
        outln!(
            o,
            "  worst samples (replay one with `orbitlash run SCENARIO --sample K --seed {}{}`):",
            r.seed,
            if r.sampling == "latin_hypercube" {
                format!(" --sampling lhs --samples {}", r.samples)
            } else {
                String::new()
            }
        );
        for w in &p.worst {
            outln!(
                o,
                "    #{}: {:.3} µm at t = {:.1} s, orbit {}, θ = {:.1}° from noon; {}",
                w.index,
                w.min_backlash_um,
                w.t_min_s,
                w.orbit_number,
                w.orbit_phase_deg,
                w.values
                    .iter()
                    .map(|(k, v)| format!("{k} = {}", orbitlash::units::exact(*v)))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    o
}

fn ordinal(r: u64) -> String {
    match r {
        1 => "smallest".into(),
        2 => "2nd smallest".into(),
        3 => "3rd smallest".into(),
        n => format!("{n}th smallest"),
    }
}

/// Every sample: index, dispersed values, then per pair the smallest backlash, its
/// margin, time, orbit, phase and flags.
fn samples_csv(
    plan: &Plan,
    outcomes: &[SampleOutcome],
    sc: &orbitlash::scenario::Scenario,
) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = vec!["sample".to_string()];
    header.extend(plan.dispersions.iter().map(|d| d.path.clone()));
    for g in &sc.gears {
        for f in [
            "min_backlash_um",
            "min_margin_um",
            "t_min_s",
            "orbit_number",
            "orbit_phase_deg",
            "violated",
            "interference",
        ] {
            header.push(format!("{}.{f}", g.name));
        }
    }
    w.write_record(&header).expect("in memory");
    for s in outcomes {
        let mut row = vec![s.index.to_string()];
        row.extend(s.values.iter().map(|v| orbitlash::units::exact(*v)));
        for p in &s.pairs {
            row.extend([
                orbitlash::units::exact(p.min_backlash_um),
                orbitlash::units::exact(p.min_margin_um),
                orbitlash::units::exact(p.t_min_s),
                p.orbit_number.to_string(),
                orbitlash::units::exact(p.orbit_phase_deg),
                (p.violated as u8).to_string(),
                (p.interference as u8).to_string(),
            ]);
        }
        w.write_record(&row).expect("in memory");
    }
    String::from_utf8(w.into_inner().expect("in memory")).expect("utf-8")
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Shard files written by `orbitlash margins --shard I/N --json FILE`.
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// Write the merged report as JSON (the same as the unsharded run's).
    #[arg(long, value_name = "FILE.json")]
    json: Option<PathBuf>,
}

pub fn merge_shards(a: MergeArgs) -> Result<Outcome> {
    let inputs: Vec<&Path> = a.shards.iter().map(PathBuf::as_path).collect();
    let policy = OutputPolicy::reading(&inputs);
    if let Some(p) = &a.json {
        check_output(p, &policy)?;
    }
    let mut shards = Vec::new();
    for p in &a.shards {
        orbitlash::io::output::check_input(p)?;
        let text = std::fs::read_to_string(p)
            .map_err(|e| anyhow::anyhow!("reading {}: {e}", p.display()))?;
        let shard: Shard = serde_json::from_str(&text).map_err(|e| MergeError::NotAShard {
            file: p.display().to_string(),
            why: e.to_string(),
        })?;
        shards.push((p.display().to_string(), shard));
    }
    let (id, outcomes) = merge(&shards)?;
    let rep = report(&id, &outcomes);
    let mut o = format_report(&rep);
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(&rep)? + "\n";
        write_file(p, &policy, text.as_bytes())?;
        outln!(o, "json: {}", p.display());
    }
    print_out(&o)?;
    Ok(Outcome::from_pass(rep.verdict == "pass"))
}

//! `orbitlash margins`: the scenario's `[[dispersion]]` entries sampled N times, each
//! sample run in parallel, and the report an engineer signs (verdict first).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};

use orbitlash::io::output::{OutputPolicy, Outputs};
use orbitlash::margins::dispersion::{Plan, Sampling};
use orbitlash::margins::{
    Horizon, Report, RunIdentity, SHARD_FORMAT, SampleOutcome, Shard, merge, read_shard, report,
    run_samples, shard_range,
};

use super::table::{self, Align};
use super::{Outcome, load_with, orbits_arg, print_out};

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
    /// Also write plots into this folder (created if missing; its parent must exist):
    /// per gear pair `<pair>-min-backlash.svg` (histogram and CDF with the limit and the
    /// 95/95 bound) and `<pair>-sensitivity.svg` (tornado chart); `.png` with
    /// `--plots-format png`.
    #[arg(long, value_name = "DIR", conflicts_with = "shard")]
    plots: Option<PathBuf>,
    /// The format of the --plots figures: SVG, or PNG at twice their size (for slides).
    #[arg(long, value_enum, default_value = "svg", requires = "plots")]
    plots_format: PlotsFormat,
    /// Run only shard i of n (0-based, e.g. `3/16`): a deterministic slice of the
    /// samples, written with --json as a shard file for `orbitlash merge`.
    #[arg(long, value_name = "I/N", value_parser = shard_arg, requires = "json")]
    shard: Option<(u64, u64)>,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Run even when the estimate exceeds the limits (5e7 steps per sample, 1e9 in all).
    #[arg(long)]
    force: bool,
}

fn shard_arg(s: &str) -> Result<(u64, u64), String> {
    let max = orbitlash::margins::MAX_SHARDS;
    let bad = || format!("`{s}` is not a shard I/N with 0 ≤ I < N ≤ {max}");
    let (i, n) = s.split_once('/').ok_or_else(bad)?;
    let (i, n): (u64, u64) = (
        i.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if n == 0 || n > max || i >= n {
        return Err(bad());
    }
    Ok((i, n))
}

pub fn samples_arg(s: &str) -> Result<u64, String> {
    let max = orbitlash::margins::dispersion::MAX_SAMPLES;
    match s.parse::<u64>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!(
            "`{s}` is not a whole number of samples within 1 … {max}"
        )),
    }
}

pub fn margins(a: MarginsArgs) -> Result<Outcome> {
    let loaded = load_with(Some(&a.scenario), &a.sets)?;
    let sc = loaded.scenario();
    if sc.gears.is_empty() {
        bail!(
            "{} has no [[gear_pair]]: margins judge the backlash of gear pairs, so there is nothing to judge",
            loaded.file
        );
    }
    if a.shard.is_some() && a.csv.is_some() {
        bail!(
            "--csv with --shard: a shard writes only its shard file (--json); give --csv to `orbitlash merge`, which writes every sample"
        );
    }
    // Every output, checked against the inputs and each other before anything runs.
    let mut outs = Outputs::new(OutputPolicy::reading(&loaded.inputs()));
    let files = ReportFiles {
        json: a.json.as_deref(),
        csv: a.csv.as_deref(),
        plots: a.plots.as_deref(),
        format: a.plots_format,
    };
    files.plan(&mut outs, sc.gears.iter().map(|g| g.name.as_str()))?;
    let spec = loaded.model.spec();
    if spec.dispersion.is_empty() {
        bail!(
            "{} has no [[dispersion]]: nothing to sample (see scenarios/README.md)",
            loaded.file
        );
    }
    let plan = super::plan(
        &loaded,
        a.sampling.into(),
        a.samples,
        a.seed,
        super::SetsOnDispersed::Refused,
    )?;
    let horizon = match (a.orbits, a.steady_state) {
        (Some(n), _) => {
            // the bounds of `run --orbits`
            sc.clone()
                .with_orbits(n)
                .map_err(|m| anyhow::anyhow!("--orbits {}: {m}", orbitlash::units::num(n)))?;
            Horizon::Orbits(n)
        }
        (None, true) => {
            // before any sample runs
            orbitlash::run::steady::check_repeats(&sc.thermal)
                .map_err(|e| anyhow::anyhow!("--steady-state: {e}"))?;
            Horizon::SteadyState
        }
        (None, false) => Horizon::Mission, // the scenario's own run length
    };
    let range = match a.shard {
        Some((i, n)) => shard_range(plan.samples, i, n),
        None => 0..plan.samples,
    };
    let max_steps = super::estimate::margins(sc, horizon, range.end - range.start, a.force)?;
    let id = RunIdentity::new(&loaded.toml, &loaded.sets, sc, &plan, horizon);
    let done = AtomicU64::new(0);
    let outcomes = run_with_progress(
        &loaded.model,
        &plan,
        range.clone(),
        horizon,
        max_steps,
        &done,
        a.quiet,
    );
    if let Some((i, n)) = a.shard {
        let shard = Shard {
            format: SHARD_FORMAT.into(),
            run: id,
            shard: (i, n),
            range: (range.start, range.end),
            tool: orbitlash::margins::build_identity(),
            limits: orbitlash::margins::ShardLimits::new(
                &loaded.model,
                &plan,
                horizon,
                range.clone(),
            ),
            outcomes,
            sha256: String::new(),
        }
        .sealed();
        let p = a.json.as_deref().expect("--shard requires --json");
        let text = serde_json::to_string(&shard)? + "\n";
        outs.write_all(&[(p, text.as_bytes())])?;
        let invalid = shard
            .outcomes
            .iter()
            .filter(|o| o.invalid.is_some())
            .count();
        // more shards than samples: some hold none (still needed by `merge`)
        let held = if range.is_empty() {
            format!(
                "none of the {} samples (more shards than samples), an empty shard,",
                plan.samples
            )
        } else {
            format!(
                "samples {} … {} of {}",
                range.start,
                range.end - 1,
                plan.samples
            )
        };
        print_out(&format!(
            "shard {i}/{n}: {held} written to {}{} (merge the shards with `orbitlash merge`)\n",
            super::shown_path(p),
            if invalid > 0 {
                format!("; {invalid} of them could not be run")
            } else {
                String::new()
            }
        ))?;
        return Ok(Outcome::Pass);
    }
    finish(&outs, &id, &outcomes, files)
}

/// The format of the margins figures.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum PlotsFormat {
    Svg,
    Png,
}

impl PlotsFormat {
    fn ext(self) -> &'static str {
        match self {
            PlotsFormat::Svg => "svg",
            PlotsFormat::Png => "png",
        }
    }

    /// The figure's bytes in this format (PNG at twice its size).
    fn bytes(self, fig: orbitlash::plot::Figure) -> Result<Vec<u8>, orbitlash::plot::PlotError> {
        match self {
            PlotsFormat::Svg => Ok(fig.svg_file().into_bytes()),
            PlotsFormat::Png => fig.png(2.0),
        }
    }
}

/// Where `margins` or `merge` write the report, the samples and the plots.
#[derive(Clone, Copy)]
struct ReportFiles<'a> {
    json: Option<&'a Path>,
    csv: Option<&'a Path>,
    plots: Option<&'a Path>,
    format: PlotsFormat,
}

impl ReportFiles<'_> {
    /// Plans them: the report, the samples and the plots of each gear pair
    /// (`<pair>-min-backlash.svg`, `<pair>-sensitivity.svg`).
    fn plan<'p>(&self, outs: &mut Outputs, pairs: impl Iterator<Item = &'p str>) -> Result<()> {
        if let Some(p) = self.json {
            outs.file("--json", p)?;
        }
        if let Some(p) = self.csv {
            outs.file("--csv", p)?;
        }
        if let Some(dir) = self.plots {
            outs.folder("--plots", dir, true)?;
            for pair in pairs {
                for name in plot_names(pair, self.format) {
                    outs.file(&format!("--plots ({name})"), &dir.join(name))?;
                }
            }
        }
        Ok(())
    }
}

fn plot_names(pair: &str, format: PlotsFormat) -> [String; 2] {
    let ext = format.ext();
    [
        format!("{pair}-min-backlash.{ext}"),
        format!("{pair}-sensitivity.{ext}"),
    ]
}

/// The report of every sample: printed, and written where asked (all files or none).
fn finish(
    outs: &Outputs,
    id: &RunIdentity,
    outcomes: &[SampleOutcome],
    files_to: ReportFiles<'_>,
) -> Result<Outcome> {
    let ReportFiles {
        json,
        csv,
        plots,
        format,
    } = files_to;
    let Some(rep) = report(id, outcomes) else {
        let first = outcomes
            .iter()
            .find_map(|o| o.invalid.as_ref().map(|w| (o.index, w.clone())));
        match first {
            Some((k, why)) => {
                bail!("no sample could be run, so there is nothing to judge (sample {k}: {why})")
            }
            None => bail!("no sample and no gear pair: there is nothing to judge"),
        }
    };
    let mut o = format_report(&rep);
    let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    if let Some(p) = json {
        files.push((
            p.to_path_buf(),
            (serde_json::to_string_pretty(&rep)? + "\n").into_bytes(),
        ));
    }
    if let Some(p) = csv {
        files.push((p.to_path_buf(), samples_csv(id, outcomes).into_bytes()));
    }
    if let Some(dir) = plots {
        files.extend(plots_of(dir, &rep, outcomes, format)?);
    }
    let refs: Vec<(&Path, &[u8])> = files
        .iter()
        .map(|(p, b)| (p.as_path(), b.as_slice()))
        .collect();
    outs.write_all(&refs)?;
    if let Some(p) = json {
        outln!(o, "json: {}", super::shown_path(p));
    }
    if let Some(p) = csv {
        outln!(o, "csv: {}", super::shown_path(p));
    }
    for (p, _) in files
        .iter()
        .filter(|(p, _)| plots.is_some_and(|d| p.starts_with(d)))
    {
        outln!(o, "plot: {}", super::shown_path(p));
    }
    print_out(&o)?;
    Ok(Outcome::from_pass(rep.verdict.passes()))
}

fn run_with_progress(
    model: &orbitlash::spec::model::Model,
    plan: &Plan,
    range: std::ops::Range<u64>,
    horizon: Horizon,
    max_steps: u64,
    done: &AtomicU64,
    quiet: bool,
) -> Vec<SampleOutcome> {
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
    // Asked to stop while samples run: nothing has been written yet (every output is
    // written once all samples are in), so the process stops here and says so.
    let total = range.end - range.start;
    let result = super::watched(
        || {
            if let Some(b) = &bar {
                b.set_position(done.load(Ordering::Relaxed));
            }
        },
        || {
            if let Some(b) = &bar {
                b.abandon();
            }
            format!(
                "interrupted after {} of {total} samples: nothing was written (margins writes its outputs when every sample has run; shard a long run with --shard I/N)",
                done.load(Ordering::Relaxed)
            )
        },
        || run_samples(model, plan, range, horizon, max_steps, done),
    );
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    result
}

/// The plots of `rep` for `dir`: (path, bytes in `format`) per gear pair.
fn plots_of(
    dir: &Path,
    rep: &Report,
    outcomes: &[SampleOutcome],
    format: PlotsFormat,
) -> Result<Vec<(PathBuf, Vec<u8>)>, orbitlash::plot::PlotError> {
    let mut files = Vec::new();
    for (k, p) in rep.pairs.iter().enumerate() {
        let values: Vec<f64> = outcomes
            .iter()
            .filter(|o| o.invalid.is_none())
            .map(|o| o.pairs[k].min_backlash_um)
            .collect();
        let [dist_name, tornado_name] = plot_names(&p.name, format);
        let fig =
            orbitlash::plot::margins::distribution(&orbitlash::plot::margins::DistributionInput {
                title: format!(
                    "{} / {}: smallest backlash per sample",
                    rep.scenario, p.name
                ),
                values: &values,
                limit_um: p.min_backlash_allowed_um,
                bound_um: p.tolerance_95_95_um,
                bins: 30,
                pass: p.verdict == orbitlash::run::summary::PassFail::Pass,
                below: p.violations.count,
                interfering: p.interference.count,
                reason: p.reason.clone(),
            })?;
        files.push((dir.join(dist_name), format.bytes(fig)?));
        let rows: Vec<(String, f64)> = p
            .sensitivities
            .iter()
            .map(|s| (s.path.clone(), s.spearman))
            .collect();
        let fig = orbitlash::plot::margins::tornado(
            &format!(
                "{} / {}: sensitivity of the smallest backlash",
                rep.scenario, p.name
            ),
            &rows,
            rep.valid_samples as usize,
        )?;
        files.push((dir.join(tornado_name), format.bytes(fig)?));
    }
    Ok(files)
}

/// The human report of a margins run.
///
/// Long by choice (about 150 lines): the report's sections printed in order, no logic
/// beyond formatting.
pub fn format_report(r: &Report) -> String {
    let mut o = String::new();
    for p in &r.pairs {
        outln!(
            o,
            "{} {}: {}",
            p.verdict.as_str().to_uppercase(),
            p.name,
            p.reason
        );
    }
    outln!(
        o,
        "{}: {} ({}), seed {}, {} each; dispersed: {}",
        r.scenario,
        orbitlash::units::count(r.samples as f64, "sample"),
        r.sampling,
        r.seed,
        r.horizon,
        r.dispersed.join(", ")
    );
    if !r.invalid.is_empty() {
        outln!(
            o,
            "{} of {} samples could not be run; the statistics below are over the {} that ran:",
            r.invalid.len(),
            r.samples,
            r.valid_samples
        );
        for s in r.invalid.iter().take(5) {
            outln!(o, "  sample {}: {}", s.index, s.reason);
        }
        if r.invalid.len() > 5 {
            outln!(
                o,
                "  … and {} more (all of them in --json)",
                r.invalid.len() - 5
            );
        }
    }
    for p in &r.pairs {
        outln!(
            o,
            "\ngear pair {} (smallest normal backlash and margin per sample, µm; minimum allowed {:.3} µm):",
            p.name,
            p.min_backlash_allowed_um
        );
        o += &distribution_table(p);
        match p.tolerance_95_95_um {
            Some(v) => outln!(
                o,
                "  95/95 lower tolerance bound: {v:.3} µm (the {} of {} samples, Wilks)",
                ordinal(p.tolerance_rank.unwrap_or(1)),
                r.valid_samples
            ),
            None => outln!(
                o,
                "  95/95 lower tolerance bound: not shown: it needs at least {} samples (Wilks), {} run",
                p.tolerance_samples_needed,
                r.valid_samples
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
                r.valid_samples,
                pr.estimate,
                pr.ci95[0],
                pr.ci95[1]
            );
        }
        outln!(o, "  sensitivity (Spearman ρ with the smallest backlash):");
        let mut t = table::new(&["", ""], &[Align::Left, Align::Right]);
        for s in &p.sensitivities {
            t.add_row(vec![
                s.path.clone(),
                if s.spearman.is_finite() {
                    format!("{:+.3}", s.spearman)
                } else {
                    "– (no variation to rank)".to_string()
                },
            ]);
        }
        o += &table::render(&t, "    ");
        outln!(o, "  worst samples (replay one with `{}`):", r.replay);
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
                    .map(|(k, v)| format!("{k} = {}", orbitlash::units::digits(*v, 6)))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
    }
    o
}

/// A pair's smallest backlash and margin per sample: min, percentiles with their 95 %
/// intervals, max and mean.
fn distribution_table(p: &orbitlash::margins::PairReport) -> String {
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
    table::render(&t, "  ")
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
/// margin, time, orbit, phase and flags (derived from the values); a sample that could
/// not be run has empty results and its reason in `invalid`.
fn samples_csv(id: &RunIdentity, outcomes: &[SampleOutcome]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = vec!["sample".to_string()];
    header.extend(id.dispersed.iter().cloned());
    for (name, _) in &id.pairs {
        for f in [
            "min_backlash_um",
            "min_margin_um",
            "t_min_s",
            "orbit_number",
            "orbit_phase_deg",
            "violated",
            "interference",
        ] {
            header.push(format!("{name}.{f}"));
        }
    }
    header.push("invalid".to_string());
    w.write_record(&header).expect("in memory");
    for s in outcomes {
        let mut row = vec![s.index.to_string()];
        row.extend(s.values.iter().map(|v| orbitlash::units::exact(*v)));
        row.resize(1 + id.dispersed.len(), String::new());
        for (k, (_, allowed)) in id.pairs.iter().enumerate() {
            match s.pairs.get(k) {
                Some(p) => {
                    let (violated, interference) =
                        orbitlash::margins::PairOutcome::flags_from_values(
                            p.min_backlash_um,
                            *allowed,
                        );
                    row.extend([
                        orbitlash::units::exact(p.min_backlash_um),
                        orbitlash::units::exact(p.min_margin_um),
                        orbitlash::units::exact(p.t_min_s),
                        p.orbit_number.to_string(),
                        orbitlash::units::exact(p.orbit_phase_deg),
                        (violated as u8).to_string(),
                        ((interference || p.interference) as u8).to_string(),
                    ]);
                }
                None => row.extend(std::iter::repeat_n(String::new(), 7)),
            }
        }
        row.push(s.invalid.clone().unwrap_or_default());
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
    /// Also write every sample as CSV (the same as the unsharded run's).
    #[arg(long, value_name = "FILE.csv")]
    csv: Option<PathBuf>,
    /// Also write the plots into this folder (created if missing), as `margins --plots`.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// The format of the --plots figures, as `margins --plots-format`.
    #[arg(long, value_enum, default_value = "svg", requires = "plots")]
    plots_format: PlotsFormat,
}

/// The largest shard file read (a shard of 10⁷ samples with a few dispersions and pairs
/// is about 3 GB; anything larger is not a shard).
const MAX_SHARD_BYTES: u64 = 4 << 30;

pub fn merge_shards(a: MergeArgs) -> Result<Outcome> {
    let inputs: Vec<&Path> = a.shards.iter().map(PathBuf::as_path).collect();
    // one file named twice (by the same or another path) is said as such, not as a
    // sample "in both sh1.json and sh1.json"
    let mut seen: Vec<(PathBuf, &Path)> = Vec::new();
    for p in &a.shards {
        if let Ok(c) = std::fs::canonicalize(p) {
            if let Some((_, first)) = seen.iter().find(|(s, _)| *s == c) {
                anyhow::bail!(
                    "the shard {} is given twice (also as {}): give each shard once",
                    p.display(),
                    first.display()
                );
            }
            seen.push((c, p));
        }
    }
    let mut shards = Vec::new();
    for p in &a.shards {
        let text = orbitlash::io::output::check_input(p)
            .and_then(|()| {
                let len = std::fs::metadata(p)?.len();
                if len > MAX_SHARD_BYTES {
                    return Err(std::io::Error::other(format!(
                        "{len} bytes is larger than any shard file"
                    )));
                }
                std::fs::read_to_string(p)
            })
            .with_context(|| format!("cannot read the shard {}", p.display()))?;
        let shard = read_shard(&text, &p.display().to_string())?;
        shards.push((p.display().to_string(), shard));
    }
    let (id, outcomes) = merge(&shards)?;
    let mut outs = Outputs::new(OutputPolicy::reading(&inputs));
    let files = ReportFiles {
        json: a.json.as_deref(),
        csv: a.csv.as_deref(),
        plots: a.plots.as_deref(),
        format: a.plots_format,
    };
    files.plan(&mut outs, id.pairs.iter().map(|(n, _)| n.as_str()))?;
    finish(&outs, &id, &outcomes, files)
}

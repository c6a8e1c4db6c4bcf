//! Monte Carlo margins: each sample is the nominal model with its dispersed values
//! ([`crate::margins::dispersion::Plan`]), run over a horizon; the smallest backlash of each
//! gear pair and when it happened are kept. Samples are independent and evaluated in
//! parallel (rayon); their results depend only on (seed, index), so any thread count
//! and any slice of indices give the same numbers. The statistics an engineer signs
//! (percentiles, a Wilks tolerance bound, Clopper–Pearson intervals, Spearman
//! sensitivities) are in [`stats`].

pub mod dispersion;

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use crate::margins::dispersion::{Plan, Sampling};
use crate::orbit::EnvironmentModel;
use crate::run::sim::{RunStats, Setup, SimError, Stop};
use crate::run::summary::{MeshStats, PassFail};
use crate::spec::model::Model;

/// How long each sample runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Horizon {
    /// This many orbits from the scenario's start.
    Orbits(f64),
    /// The scenario's own run length (its mission profile).
    Mission,
    /// One period of the sample's orbit-periodic solution (environment repeating
    /// every orbit).
    SteadyState,
}

/// A gear pair's outcome in one sample.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairOutcome {
    /// Smallest exact backlash over the sample's run, µm (NaN, null in JSON: the mesh
    /// was lost).
    #[serde(deserialize_with = "nan_from_null")]
    pub min_backlash_um: f64,
    /// Smallest margin to the minimum allowed, µm.
    #[serde(deserialize_with = "nan_from_null")]
    pub min_margin_um: f64,
    pub t_min_s: f64,
    /// Orbit number and angle from orbit noon at the minimum.
    pub orbit_number: u64,
    pub orbit_phase_deg: f64,
    /// The teeth interfered (backlash reached zero) or the mesh was lost.
    pub interference: bool,
    /// The backlash fell below the minimum allowed.
    pub violated: bool,
}

/// One sample: its index, its dispersed values (in the plan's order) and each pair's
/// outcome; or, for a sample that could not be run, why (and no pair outcomes).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SampleOutcome {
    pub index: u64,
    pub values: Vec<f64>,
    pub pairs: Vec<PairOutcome>,
    /// Why the sample could not be run: the model refused its values together (a
    /// heater's on_k above its off_k), or its run failed. Such a sample has no result,
    /// and a report with one fails.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub invalid: Option<String>,
}

impl PairOutcome {
    /// The flags that follow from the smallest backlash and the minimum allowed:
    /// (violated, interference). A lost mesh (NaN) is both.
    pub fn flags_from_values(min_backlash_um: f64, allowed_um: f64) -> (bool, bool) {
        // NaN (a lost mesh) is below everything
        let lost = min_backlash_um.is_nan();
        (
            lost || min_backlash_um < allowed_um,
            lost || min_backlash_um <= 0.0,
        )
    }
}

/// JSON writes NaN as null; read null back as NaN.
fn nan_from_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let v: Option<f64> = serde::Deserialize::deserialize(d)?;
    Ok(v.unwrap_or(f64::NAN))
}

/// Runs sample `k` of `plan` on a copy of `nominal`. A sample whose values the model
/// refuses, or whose run fails, is an outcome too (`invalid`), so that one bad
/// combination of tolerances does not lose the other samples.
pub fn run_sample(
    nominal: &Model,
    plan: &Plan,
    k: u64,
    horizon: Horizon,
    max_steps: u64,
) -> SampleOutcome {
    let invalid = |values: Vec<f64>, why: String| SampleOutcome {
        index: k,
        values,
        pairs: Vec::new(),
        invalid: Some(why),
    };
    let mut model = nominal.clone();
    let values = match plan.apply(&mut model, k) {
        Ok(v) => v,
        Err(e) => {
            let why = match &e {
                crate::margins::dispersion::SampleError::Model { source, path, .. } => {
                    format!("the model refuses {path} with the other values: {source}")
                }
                other => other.to_string(),
            };
            return invalid(plan.values(k).unwrap_or_default(), why);
        }
    };
    let sc = model.scenario();
    let env = &sc.thermal.environment;
    // the report judges the exact backlash only: the paper's model is not evaluated
    let gears: Vec<_> = sc
        .gears
        .iter()
        .map(|g| crate::gear::GearPair {
            paper_model: false,
            ..g.clone()
        })
        .collect();
    let mut setup = Setup::new(&sc.thermal, &gears, &sc.solver);
    let mut state = setup.initial_state();
    let t_end = match horizon {
        Horizon::Orbits(n) => n * env.mean_period_s(),
        Horizon::Mission => sc.run.duration_s,
        Horizon::SteadyState => {
            let period = env.mean_period_s();
            match crate::run::steady::periodic_orbit(
                &mut setup,
                &state,
                period,
                crate::run::steady::SteadyOptions {
                    max_steps,
                    ..crate::run::steady::SteadyOptions::default()
                },
            ) {
                Ok(p) => state = p.state,
                Err(e) => {
                    return invalid(
                        values,
                        format!("periodic orbit: {}", crate::error_chain(&e)),
                    );
                }
            }
            state.t_s + period
        }
    };
    let mut mesh = MeshStats::last(env.mean_period_s());
    let mut budget = crate::run::sim::StepBudget::new(max_steps);
    let run: Result<RunStats, SimError> = setup.run(
        &mut state,
        t_end,
        &mut (&mut mesh, &mut budget),
        Stop::default(),
    );
    if let Err(e) = run {
        return invalid(
            values,
            format!("the run failed: {}", crate::error_chain(&e)),
        );
    }
    let pairs = gears
        .iter()
        .zip(&mesh.run_pairs)
        .map(|(g, p)| {
            let lost = p.invalid_samples > 0;
            let t = if lost { p.t_first_invalid_s } else { p.t_min_s };
            let min_um = if lost { f64::NAN } else { p.min_exact_m * 1e6 };
            let allowed_um = g.min_backlash_m * 1e6;
            let (violated, interference) = PairOutcome::flags_from_values(min_um, allowed_um);
            PairOutcome {
                min_backlash_um: min_um,
                min_margin_um: if lost { f64::NAN } else { p.min_margin_m * 1e6 },
                t_min_s: t,
                orbit_number: env.orbit_number(t),
                orbit_phase_deg: env.orbit_phase_deg(t),
                interference: interference || p.interference_events > 0,
                violated,
            }
        })
        .collect();
    SampleOutcome {
        index: k,
        values,
        pairs,
        invalid: None,
    }
}

/// Runs samples `range` in parallel; results in index order. `done` counts finished
/// samples (for a progress bar). A sample that takes more than `max_steps` solver
/// steps (its run and, at steady state, its periodic search each) is stopped and
/// reported invalid (`u64::MAX`: no limit).
pub fn run_samples(
    nominal: &Model,
    plan: &Plan,
    range: Range<u64>,
    horizon: Horizon,
    max_steps: u64,
    done: &AtomicU64,
) -> Vec<SampleOutcome> {
    range
        .into_par_iter()
        .map(|k| {
            let r = run_sample(nominal, plan, k, horizon, max_steps);
            done.fetch_add(1, Ordering::Relaxed);
            r
        })
        .collect()
}

/// The statistics of a margin report, each a pure function of the sample values.
pub mod stats {
    use statrs::distribution::{Beta, ContinuousCDF};

    /// The q-quantile (0 ≤ q ≤ 1) of `sorted` by linear interpolation between order
    /// statistics (Hyndman & Fan type 7).
    pub fn quantile(sorted: &[f64], q: f64) -> f64 {
        if sorted.is_empty() {
            return f64::NAN;
        }
        let h = (sorted.len() - 1) as f64 * q;
        let (i, f) = (h.floor() as usize, h - h.floor());
        if i + 1 < sorted.len() {
            sorted[i] + f * (sorted[i + 1] - sorted[i])
        } else {
            sorted[i]
        }
    }

    /// Wilks: the rank r (1-based) of the order statistic that is a one-sided lower
    /// tolerance bound covering `coverage` of the population with `confidence`, from
    /// n samples: the largest r with P(Bin(n, 1 − coverage) ≥ r) ≥ confidence. `None`
    /// when even r = 1 is not enough (n < 59 for 95/95).
    pub fn wilks_rank(n: u64, coverage: f64, confidence: f64) -> Option<u64> {
        // the largest r with 1 − P(Bin(n, 1 − coverage) ≤ r − 1) ≥ confidence
        let cdf = binomial_cdf(n, 1.0 - coverage);
        (1..=n)
            .take_while(|&r| 1.0 - cdf[(r - 1) as usize] >= confidence)
            .last()
    }

    /// `cdf[r]` = P(Bin(n, p) ≤ r) for r = 0 … n, 0 < p < 1: the probabilities by their
    /// ratio recurrence in logs (O(n), no underflow for large n).
    pub fn binomial_cdf(n: u64, p: f64) -> Vec<f64> {
        let (lp, lq) = (p.ln(), (1.0 - p).ln());
        let mut ln_pmf = n as f64 * lq;
        let mut acc = 0.0;
        let mut cdf = Vec::with_capacity(n as usize + 1);
        for r in 0..=n {
            acc += ln_pmf.exp();
            cdf.push(acc.min(1.0));
            if r < n {
                ln_pmf += ((n - r) as f64).ln() - ((r + 1) as f64).ln() + lp - lq;
            }
        }
        cdf
    }

    /// The fewest samples for which [`wilks_rank`] exists.
    pub fn wilks_minimum_samples(coverage: f64, confidence: f64) -> u64 {
        // 1 − coverageⁿ ≥ confidence
        ((1.0 - confidence).ln() / coverage.ln()).ceil() as u64
    }

    /// Clopper–Pearson two-sided interval at `level` for k events in n trials.
    pub fn clopper_pearson(k: u64, n: u64, level: f64) -> (f64, f64) {
        let a = (1.0 - level) / 2.0;
        let lo = if k == 0 {
            0.0
        } else {
            Beta::new(k as f64, (n - k + 1) as f64)
                .expect("positive shapes")
                .inverse_cdf(a)
        };
        let hi = if k == n {
            1.0
        } else {
            Beta::new((k + 1) as f64, (n - k) as f64)
                .expect("positive shapes")
                .inverse_cdf(1.0 - a)
        };
        (lo, hi)
    }

    /// Ranks 1 … n with ties averaged.
    fn ranks(x: &[f64]) -> Vec<f64> {
        let mut order: Vec<usize> = (0..x.len()).collect();
        order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
        let mut r = vec![0.0; x.len()];
        let mut i = 0;
        while i < order.len() {
            let mut j = i;
            while j + 1 < order.len() && x[order[j + 1]] == x[order[i]] {
                j += 1;
            }
            let avg = (i + j) as f64 / 2.0 + 1.0;
            for &o in &order[i..=j] {
                r[o] = avg;
            }
            i = j + 1;
        }
        r
    }

    /// Spearman's rank correlation of x and y (Pearson's of their ranks); NaN when
    /// either is constant.
    pub fn spearman(x: &[f64], y: &[f64]) -> f64 {
        let (rx, ry) = (ranks(x), ranks(y));
        let n = rx.len() as f64;
        let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
        let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
        for (a, b) in rx.iter().zip(&ry) {
            sxy += (a - mx) * (b - my);
            sxx += (a - mx) * (a - mx);
            syy += (b - my) * (b - my);
        }
        sxy / (sxx * syy).sqrt()
    }
}

/// The margin report: verdict, per gear pair the distribution of the smallest backlash,
/// the one-sided 95/95 lower tolerance bound, violation and interference probabilities
/// with Clopper–Pearson intervals, sensitivities and the worst samples. Keys are
/// stable (documented in the README).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Report {
    pub scenario: String,
    /// "pass" when every pair's 95/95 lower bound of the smallest backlash is at or
    /// above its minimum allowed and no sample interfered; else "fail".
    pub verdict: PassFail,
    pub seed: u64,
    pub samples: u64,
    /// Samples that ran (the statistics are over these); `samples` minus `invalid`.
    pub valid_samples: u64,
    /// Samples that could not be run, with why (a report with any fails).
    pub invalid: Vec<InvalidSample>,
    pub sampling: Sampling,
    pub horizon: String,
    pub dispersed: Vec<String>,
    /// The command that replays sample K with full logging, to the last digit of its
    /// smallest backlash: `orbitlash run SCENARIO --sample K` and every flag of this run
    /// that changes a sample (seed, sampling, horizon, `--set`).
    pub replay: String,
    pub pairs: Vec<PairReport>,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct InvalidSample {
    pub index: u64,
    pub reason: String,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PairReport {
    pub name: String,
    /// "pass" or "fail".
    pub verdict: PassFail,
    /// Why, in words.
    pub reason: String,
    pub min_backlash_allowed_um: f64,
    /// The smallest backlash of each sample, over its run.
    pub min_backlash_um: Distribution,
    /// The smallest margin of each sample (backlash − minimum allowed).
    pub min_margin_um: Distribution,
    /// The one-sided lower bound covering 95 % of samples with 95 % confidence (Wilks),
    /// or null with fewer than `tolerance_samples_needed` samples.
    pub tolerance_95_95_um: Option<f64>,
    pub tolerance_rank: Option<u64>,
    pub tolerance_samples_needed: u64,
    pub violations: Probability,
    pub interference: Probability,
    /// Spearman rank correlation of each dispersed number with the smallest backlash,
    /// largest magnitude first.
    pub sensitivities: Vec<Sensitivity>,
    /// The five samples with the smallest backlash.
    pub worst: Vec<Worst>,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Distribution {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
    /// Percentiles 1, 5, 50, 95, 99, each with a distribution-free 95 % interval.
    pub percentiles: Vec<Percentile>,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Percentile {
    pub percent: f64,
    pub value: f64,
    /// From order statistics; null where the samples cannot bound it.
    pub ci95: [Option<f64>; 2],
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Probability {
    pub count: u64,
    pub estimate: f64,
    /// Clopper–Pearson, two-sided 95 %.
    pub ci95: [f64; 2],
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Sensitivity {
    pub path: String,
    pub spearman: f64,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Worst {
    pub index: u64,
    pub min_backlash_um: f64,
    pub t_min_s: f64,
    pub orbit_number: u64,
    pub orbit_phase_deg: f64,
    pub values: Vec<(String, f64)>,
}

/// Distribution-free interval of the q-quantile from order statistics: ranks l, u
/// with P(l ≤ rank of the quantile < u) ≥ level under Bin(n, q).
fn quantile_ci(sorted: &[f64], q: f64, level: f64) -> [Option<f64>; 2] {
    let n = sorted.len() as u64;
    let a = (1.0 - level) / 2.0;
    let cdf = stats::binomial_cdf(n, q);
    // lower: the largest l with P(Bin ≤ l − 1) ≤ a; upper: the smallest u with
    // P(Bin ≤ u − 1) ≥ 1 − a
    let lo = (1..=n).rev().find(|&l| cdf[(l - 1) as usize] <= a);
    let hi = (1..=n).find(|&u| cdf[(u - 1) as usize] >= 1.0 - a);
    [
        lo.map(|l| sorted[(l - 1) as usize]),
        hi.map(|u| sorted[(u - 1) as usize]),
    ]
}

fn probability(count: u64, n: u64) -> Probability {
    let (lo, hi) = stats::clopper_pearson(count, n, 0.95);
    Probability {
        count,
        estimate: count as f64 / n as f64,
        ci95: [lo, hi],
    }
}

/// A horizon of the scenario's own run length, as a report names it.
const MISSION_HORIZON: &str = "the scenario's run";
/// A steady-state horizon, as a report names it.
const STEADY_HORIZON: &str = "one period of the periodic orbit";

/// What a margin run is, apart from its samples: enough to write its report and to
/// tell whether two shards belong to the same run.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunIdentity {
    pub scenario: String,
    /// SHA-256 of the scenario text, and the `--set` changes, in order.
    pub scenario_sha256: String,
    pub sets: Vec<(String, f64)>,
    pub seed: u64,
    pub samples: u64,
    pub sampling: Sampling,
    pub horizon: String,
    pub dispersed: Vec<String>,
    /// Gear pairs: name and minimum allowed backlash, µm.
    pub pairs: Vec<(String, f64)>,
}

impl RunIdentity {
    /// `orbitlash run SCENARIO --sample K` and the flags that make it this run's
    /// sample K: the seed, the sampling, the horizon, every `--set` in order (values
    /// as the shortest text that reads back to the same number).
    pub fn replay(&self) -> String {
        let mut f = format!("orbitlash run SCENARIO --sample K --seed {}", self.seed);
        if self.sampling == Sampling::LatinHypercube {
            f += &format!(" --sampling lhs --samples {}", self.samples);
        }
        if self.horizon == STEADY_HORIZON {
            f += " --steady-state";
        } else if let Some(n) =
            (self.horizon.strip_suffix(" orbits")).or_else(|| self.horizon.strip_suffix(" orbit"))
        {
            f += &format!(" --orbits {n}");
        }
        for (k, v) in &self.sets {
            f += &format!(" --set {}", shell_word(&format!("{k}={v}")));
        }
        f
    }

    pub fn new(
        scenario_toml: &str,
        sets: &[(String, f64)],
        sc: &crate::spec::scenario::Scenario,
        plan: &Plan,
        horizon: Horizon,
    ) -> RunIdentity {
        use sha2::{Digest, Sha256};
        RunIdentity {
            scenario: sc.name.clone(),
            scenario_sha256: Sha256::digest(scenario_toml.as_bytes())
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect(),
            sets: sets.to_vec(),
            seed: plan.seed,
            samples: plan.samples,
            sampling: plan.sampling,
            horizon: match horizon {
                // exact (the shortest text that reads back to the number): two runs of
                // 0.00054321 and 0.00054322 orbits are not one run, and `replay` reads
                // the number back from here
                Horizon::Orbits(1.0) => "1 orbit".to_string(),
                Horizon::Orbits(o) => format!("{o} orbits"),
                Horizon::Mission => MISSION_HORIZON.to_string(),
                Horizon::SteadyState => STEADY_HORIZON.to_string(),
            },
            dispersed: plan.dispersions.iter().map(|d| d.path.clone()).collect(),
            pairs: sc
                .gears
                .iter()
                .map(|g| (g.name.clone(), g.min_backlash_m * 1e6))
                .collect(),
        }
    }
}

/// A word as a POSIX shell reads it back: as it is when it holds only characters no
/// shell treats specially, else in single quotes.
fn shell_word(w: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "._-=+:/,@%".contains(c);
    if !w.is_empty() && w.chars().all(plain) {
        w.to_string()
    } else {
        format!("'{}'", w.replace('\'', "'\\''"))
    }
}

/// One shard's samples: `range` of the run's indices.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// "orbitlash margins shard"
    pub format: String,
    pub run: RunIdentity,
    /// Shard i of n (0-based).
    pub shard: (u64, u64),
    pub range: (u64, u64),
    /// The build that wrote it ([`build_identity`]): shards of different builds are
    /// not merged (their numbers may differ).
    pub tool: String,
    /// What bounds its numbers: each sample's horizon and the orbit's period (a
    /// smallest backlash's time and orbit number), and each dispersion's support.
    pub limits: ShardLimits,
    pub outcomes: Vec<SampleOutcome>,
    /// SHA-256 (hex) of the shard as written with this field empty ([`Shard::checksum`]):
    /// a shard edited after it was written, even consistently, is refused by `merge`.
    #[serde(default)]
    pub sha256: String,
}

impl Shard {
    /// SHA-256 (hex) of the shard's JSON with `sha256` empty. The JSON of a shard read
    /// back is the JSON written (floats round-trip exactly), so a shard's checksum
    /// holds until a byte of its contents changes.
    pub fn checksum(&self) -> String {
        use sha2::{Digest, Sha256};
        let mut bare = self.clone();
        bare.sha256.clear();
        let text = serde_json::to_string(&bare).expect("a shard serialises");
        Sha256::digest(text.as_bytes())
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    }

    /// The shard with its checksum set.
    pub fn sealed(mut self) -> Shard {
        self.sha256 = self.checksum();
        self
    }
}

/// The bounds a shard's numbers must keep (see [`Shard::limits`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShardLimits {
    pub horizon_s: f64,
    pub period_s: f64,
    /// Per dispersion, the values its distribution can draw.
    pub supports: Vec<(f64, f64)>,
}

impl ShardLimits {
    /// Over the samples `range` of `plan` on `nominal`: the longest horizon and the
    /// shortest period any of them has (a dispersed altitude changes both), each
    /// sample's model made as `run_sample` makes it (a few µs each).
    pub fn new(nominal: &Model, plan: &Plan, horizon: Horizon, range: Range<u64>) -> ShardLimits {
        let of = |sc: &crate::spec::scenario::Scenario| {
            let period_s = sc.period_s();
            let horizon_s = match horizon {
                Horizon::Orbits(o) => o * period_s,
                Horizon::Mission => sc.run.duration_s,
                Horizon::SteadyState => period_s,
            };
            (horizon_s, period_s)
        };
        let (mut horizon_s, mut period_s) = of(nominal.scenario());
        let mut model = nominal.clone();
        for k in range.filter(|_| !plan.dispersions.is_empty()) {
            if plan.apply(&mut model, k).is_ok() {
                let (h, p) = of(model.scenario());
                horizon_s = horizon_s.max(h);
                period_s = period_s.min(p);
            }
        }
        ShardLimits {
            horizon_s,
            period_s,
            supports: plan
                .dispersions
                .iter()
                .map(|d| d.distribution.support())
                .collect(),
        }
    }
}

/// The build of this program: its version and the first 16 hex digits of the SHA-256
/// of its executable (two builds of one version differ), computed once.
pub fn build_identity() -> String {
    static ID: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        use sha2::Digest;
        let hash = std::env::current_exe()
            .and_then(std::fs::read)
            .map(|b| {
                let h = sha2::Sha256::digest(&b);
                h.iter()
                    .take(8)
                    .map(|x| format!("{x:02x}"))
                    .collect::<String>()
            })
            .unwrap_or_else(|_| "unknown".into());
        format!("orbitlash {} {hash}", env!("CARGO_PKG_VERSION"))
    })
    .clone()
}

pub const SHARD_FORMAT: &str = "orbitlash margins shard";

/// The sample indices of shard `i` of `n` for `samples` samples: contiguous, in order,
/// sizes differing by at most one.
pub fn shard_range(samples: u64, i: u64, n: u64) -> Range<u64> {
    (samples * i / n)..(samples * (i + 1) / n)
}

/// Why shards do not make one run.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MergeError {
    #[error("{file}: not a margins shard ({why})")]
    NotAShard { file: String, why: String },
    #[error("{file} is from another run than {first}: they differ in {what}")]
    OtherRun {
        file: String,
        first: String,
        what: String,
    },
    #[error("sample {index} is in both {a} and {b}")]
    Duplicate { index: u64, a: String, b: String },
    #[error("samples {from} … {to} are in no shard ({count} of {total} missing)")]
    Gap {
        from: u64,
        to: u64,
        count: u64,
        total: u64,
    },
}

/// Reads a shard file's text and checks it against itself: its sizes (samples, shard
/// i of n, the range shard i of n has, one outcome per index of it, one value per
/// dispersion, one result per gear pair) and its flags (each must follow from the
/// values: a shard damaged or edited so that it contradicts itself is refused, naming
/// the sample; one edited consistently is refused by [`merge`], by its checksum).
/// Never panics, whatever the text.
pub fn read_shard(text: &str, file: &str) -> Result<Shard, MergeError> {
    let bad = |why: String| MergeError::NotAShard {
        file: file.to_string(),
        why,
    };
    let s: Shard = serde_json::from_str(text).map_err(|e| {
        let m = e.to_string();
        bad(if m.contains("missing field `tool`") || m.contains("missing field `limits`") {
            format!("{m}: written by an older orbitlash, which named no build; run the shard again with this one")
        } else {
            m
        })
    })?;
    check_shard(&s, file)?;
    Ok(s)
}

/// The checks of [`read_shard`] on a parsed shard.
pub fn check_shard(s: &Shard, file: &str) -> Result<(), MergeError> {
    let bad = |why: String| MergeError::NotAShard {
        file: file.to_string(),
        why,
    };
    if s.format != SHARD_FORMAT {
        return Err(bad(format!("format `{}`", crate::units::shown(&s.format))));
    }
    let r = &s.run;
    if !(1..=crate::margins::dispersion::MAX_SAMPLES).contains(&r.samples) {
        return Err(bad(format!(
            "the run has {} samples, outside 1 … {}",
            r.samples,
            crate::margins::dispersion::MAX_SAMPLES
        )));
    }
    let (i, n) = s.shard;
    if !(1..=MAX_SHARDS).contains(&n) || i >= n {
        return Err(bad(format!(
            "shard {i}/{n} is not a shard I/N with 0 ≤ I < N ≤ {MAX_SHARDS}"
        )));
    }
    // Names reach file names (plots) and the terminal: the scenario's own rule; text
    // shown (dispersion paths, reasons) holds no control characters.
    let named = std::iter::once(("the scenario name", r.scenario.as_str())).chain(
        r.pairs
            .iter()
            .map(|(p, _)| ("a gear pair name", p.as_str())),
    );
    for (what, name) in named {
        crate::spec::scenario::check_name(name).map_err(|m| bad(format!("{what} {m}")))?;
    }
    let mut texts = r
        .dispersed
        .iter()
        .chain(s.outcomes.iter().filter_map(|o| o.invalid.as_ref()))
        .chain(r.sets.iter().map(|(k, _)| k));
    if texts.any(|t| t.chars().any(char::is_control)) {
        return Err(bad(
            "a dispersion path, a --set key or a reason holds control characters".into(),
        ));
    }
    if r.sets.iter().any(|(_, v)| !v.is_finite()) {
        return Err(bad("a --set value is not a finite number".into()));
    }
    let range = shard_range(r.samples, i, n);
    if (s.range.0, s.range.1) != (range.start, range.end) {
        return Err(bad(format!(
            "its range {} … {} is not shard {i}/{n} of {} samples ({} … {})",
            s.range.0, s.range.1, r.samples, range.start, range.end
        )));
    }
    let l = &s.limits;
    if !(l.horizon_s > 0.0
        && l.horizon_s <= crate::spec::scenario::MAX_DURATION_S
        && l.period_s > 0.0
        && l.period_s.is_finite()
        && l.supports.len() == r.dispersed.len()
        && l.supports.iter().all(|(lo, hi)| lo <= hi))
    {
        return Err(bad(
            "its limits (horizon, period, one support per dispersion) are not a run's".into(),
        ));
    }
    if s.tool.is_empty() || s.tool.chars().any(char::is_control) {
        return Err(bad("it names no tool build".into()));
    }
    if s.outcomes.len() as u64 != range.end - range.start {
        return Err(bad(format!(
            "{} outcomes for the {} samples of its range",
            s.outcomes.len(),
            range.end - range.start
        )));
    }
    if r.pairs.is_empty()
        || r.pairs
            .iter()
            .any(|(_, a)| !(0.0..=MAX_BACKLASH_UM).contains(a))
    {
        return Err(bad(format!(
            "its run needs gear pairs with a minimum backlash within 0 … {MAX_BACKLASH_UM} µm"
        )));
    }
    for (j, o) in s.outcomes.iter().enumerate() {
        let at = range.start + j as u64;
        let sample = |why: String| bad(format!("sample {}: {why}", o.index));
        if o.index != at {
            return Err(bad(format!(
                "outcome {j} is sample {}, not {at} (outcomes go in index order)",
                o.index
            )));
        }
        if o.values.len() != r.dispersed.len() && o.invalid.is_none() {
            return Err(sample(format!(
                "{} values for {} dispersions",
                o.values.len(),
                r.dispersed.len()
            )));
        }
        if o.values.iter().any(|v| !v.is_finite()) {
            return Err(sample("a dispersed value is not a finite number".into()));
        }
        for ((v, (lo, hi)), path) in o.values.iter().zip(&l.supports).zip(&r.dispersed) {
            if v < lo || v > hi {
                return Err(sample(format!(
                    "{path} = {} lies outside what its distribution draws ({} … {})",
                    crate::units::num(*v),
                    crate::units::num(*lo),
                    crate::units::num(*hi)
                )));
            }
        }
        let expected_pairs = if o.invalid.is_some() {
            0
        } else {
            r.pairs.len()
        };
        if o.pairs.len() != expected_pairs {
            return Err(sample(format!(
                "{} gear pair results for {expected_pairs} gear pairs",
                o.pairs.len()
            )));
        }
        for (p, (name, allowed)) in o.pairs.iter().zip(&r.pairs) {
            check_pair(p, name, *allowed, l).map_err(sample)?;
        }
    }
    Ok(())
}

/// One pair's result in a shard: values a run can give within the shard's limits, and
/// flags and margin that follow from them.
fn check_pair(p: &PairOutcome, name: &str, allowed: f64, l: &ShardLimits) -> Result<(), String> {
    // the sizes a run can give (a 1 m backlash, a run of 1e9 s); NaN: a lost mesh
    let plausible = |v: f64, max: f64| v.is_nan() || v.abs() <= max;
    // the time within the sample's horizon, its orbit the one that time falls in
    let t_ok = p.t_min_s.is_nan() || (0.0..=l.horizon_s * (1.0 + 1e-9)).contains(&p.t_min_s);
    let last_orbit = (p.t_min_s.max(0.0) / l.period_s).floor() + 2.0;
    let orbit_ok =
        p.t_min_s.is_nan() || (p.orbit_number >= 1 && p.orbit_number as f64 <= last_orbit);
    if !(plausible(p.min_backlash_um, MAX_BACKLASH_UM)
        && plausible(p.min_margin_um, 2.0 * MAX_BACKLASH_UM)
        && t_ok
        && orbit_ok
        && (0.0..=360.0).contains(&p.orbit_phase_deg))
    {
        return Err(format!(
            "{name}: a value no run can give (min_backlash_um {}, min_margin_um {}, t_min_s {} in a horizon of {} s, orbit_number {}, orbit_phase_deg {})",
            crate::units::num(p.min_backlash_um),
            crate::units::num(p.min_margin_um),
            crate::units::num(p.t_min_s),
            crate::units::num(l.horizon_s),
            p.orbit_number,
            crate::units::num(p.orbit_phase_deg)
        ));
    }
    let (violated, interference) = PairOutcome::flags_from_values(p.min_backlash_um, allowed);
    if p.violated != violated || p.interference != interference {
        return Err(format!(
            "{name}: min_backlash_um = {} with a minimum of {} µm means violated = {violated}, interference = {interference}, but the shard says {} and {}",
            crate::units::num(p.min_backlash_um),
            crate::units::num(allowed),
            p.violated,
            p.interference
        ));
    }
    let margin = p.min_backlash_um - allowed;
    let agrees = if p.min_backlash_um.is_nan() {
        p.min_margin_um.is_nan()
    } else {
        (p.min_margin_um - margin).abs() <= 1e-6 * margin.abs().max(1.0)
    };
    if !agrees || p.min_backlash_um.is_infinite() {
        return Err(format!(
            "{name}: min_margin_um = {} does not follow from min_backlash_um = {} and the minimum {} µm",
            crate::units::num(p.min_margin_um),
            crate::units::num(p.min_backlash_um),
            crate::units::num(allowed)
        ));
    }
    Ok(())
}

/// The largest backlash a shard may hold, µm (a metre: far beyond any gear).
pub const MAX_BACKLASH_UM: f64 = 1e6;

/// The most shards a run may be split into.
pub const MAX_SHARDS: u64 = 100_000;

/// The whole run's samples from its shards (`(file name, shard)`, each checked by
/// [`read_shard`]), checked: one run, no sample twice, none missing.
pub fn merge(shards: &[(String, Shard)]) -> Result<(RunIdentity, Vec<SampleOutcome>), MergeError> {
    let Some((first_file, first)) = shards.first() else {
        return Err(MergeError::NotAShard {
            file: "(none)".into(),
            why: "no shard given".into(),
        });
    };
    let id = &first.run;
    for (file, s) in shards {
        check_shard(s, file)?;
        let r = &s.run;
        let differs = [
            (
                "the scenario (SHA-256)",
                r.scenario_sha256 != id.scenario_sha256,
            ),
            ("--set", r.sets != id.sets),
            ("the seed", r.seed != id.seed),
            ("the number of samples", r.samples != id.samples),
            ("the sampling", r.sampling != id.sampling),
            ("the horizon", r.horizon != id.horizon),
            ("the dispersions", r.dispersed != id.dispersed),
            ("the scenario's name", r.scenario != id.scenario),
            ("the gear pairs", r.pairs != id.pairs),
            ("the tool build", s.tool != first.tool),
            (
                "the dispersions' supports",
                s.limits.supports != first.limits.supports,
            ),
        ]
        .into_iter()
        .find(|(_, d)| *d);
        if let Some((what, _)) = differs {
            return Err(MergeError::OtherRun {
                file: file.clone(),
                first: first_file.clone(),
                what: what.into(),
            });
        }
    }
    if !(1..=crate::margins::dispersion::MAX_SAMPLES).contains(&id.samples) {
        return Err(MergeError::NotAShard {
            file: first_file.clone(),
            why: format!("the run has {} samples", id.samples),
        });
    }
    // Each shard holds exactly its range (checked): order the shards by range and
    // walk them, so gaps and overlaps are found from the ranges, before anything is
    // gathered (no slot per sample of a run that may not be there).
    let mut order: Vec<usize> = (0..shards.len()).collect();
    order.sort_by_key(|&k| (shards[k].1.range.0, shards[k].1.range.1));
    let mut next = 0u64;
    let mut missing = 0u64;
    let mut first_gap: Option<(u64, u64)> = None;
    let mut last_owner: Option<usize> = None;
    for &k in &order {
        let (a, b) = shards[k].1.range;
        if a < next {
            return Err(MergeError::Duplicate {
                index: a,
                a: shards[last_owner.expect("an earlier shard")].0.clone(),
                b: shards[k].0.clone(),
            });
        }
        if a > next {
            missing += a - next;
            first_gap.get_or_insert((next, a - 1));
        }
        next = next.max(b);
        if b > a {
            last_owner = Some(k);
        }
    }
    if next < id.samples {
        missing += id.samples - next;
        first_gap.get_or_insert((next, id.samples - 1));
    }
    if let Some((from, to)) = first_gap {
        return Err(MergeError::Gap {
            from,
            to,
            count: missing,
            total: id.samples,
        });
    }
    // last, so that a shard that contradicts itself or its partners is told why: one
    // whose contents changed after it was written (a value moved within its range, a
    // result rewritten with its flags) is refused too
    for (file, s) in shards {
        if s.sha256 != s.checksum() {
            return Err(MergeError::NotAShard {
                file: file.clone(),
                why: if s.sha256.is_empty() {
                    "it has no SHA-256 of its contents (`sha256`): written by an older orbitlash, or the field was removed; run the shard again".into()
                } else {
                    "its contents do not match the SHA-256 it was written with (`sha256`): edited or damaged after it was written; run the shard again".into()
                },
            });
        }
    }
    let all = order
        .iter()
        .flat_map(|&k| shards[k].1.outcomes.iter().cloned())
        .collect();
    Ok((id.clone(), all))
}

/// The report of `all` (every sample of the run, in index order). Statistics are over
/// the samples that ran; the flags (below the minimum, interference) are derived from
/// each sample's smallest backlash, never taken from the outcome. `None` when no
/// sample ran: there is nothing to judge. Each gear pair's part is [`pair_report`].
pub fn report(id: &RunIdentity, all: &[SampleOutcome]) -> Option<Report> {
    let outcomes: Vec<&SampleOutcome> = all.iter().filter(|o| o.invalid.is_none()).collect();
    let invalid: Vec<InvalidSample> = all
        .iter()
        .filter_map(|o| {
            o.invalid.as_ref().map(|why| InvalidSample {
                index: o.index,
                reason: why.clone(),
            })
        })
        .collect();
    if outcomes.is_empty() || id.pairs.is_empty() {
        return None;
    }
    let n = outcomes.len() as u64;
    let pairs: Vec<PairReport> = id
        .pairs
        .iter()
        .enumerate()
        .map(|(p, (name, allowed_um))| {
            let samples = Samples {
                id,
                outcomes: &outcomes,
                invalid: &invalid,
                all: all.len(),
            };
            samples.pair_report(p, name, *allowed_um)
        })
        .collect();
    Some(Report {
        scenario: id.scenario.clone(),
        verdict: PassFail::all(pairs.iter().map(|p| p.verdict.passes())),
        seed: id.seed,
        samples: all.len() as u64,
        valid_samples: n,
        invalid,
        sampling: id.sampling,
        horizon: id.horizon.clone(),
        dispersed: id.dispersed.clone(),
        replay: id.replay(),
        pairs,
    })
}

/// The samples a report judges: those that ran, in index order, and those that could
/// not (`all` in all).
struct Samples<'a> {
    id: &'a RunIdentity,
    outcomes: &'a [&'a SampleOutcome],
    invalid: &'a [InvalidSample],
    all: usize,
}

impl Samples<'_> {
    /// Pair `p`'s part of the report (`name`, its smallest backlash allowed): the
    /// distribution of each sample's smallest backlash and margin, the 95/95 bound,
    /// the probabilities of a violation and of interference, the sensitivities, the
    /// worst samples and the verdict.
    fn pair_report(&self, p: usize, name: &str, allowed_um: f64) -> PairReport {
        let outcomes = self.outcomes;
        let n = outcomes.len() as u64;
        let needed = stats::wilks_minimum_samples(0.95, 0.95);
        let rank = stats::wilks_rank(n, 0.95, 0.95);
        // a lost mesh counts as no backlash at all
        let mins: Vec<f64> = outcomes
            .iter()
            .map(|o| {
                let v = o.pairs[p].min_backlash_um;
                if v.is_nan() { f64::NEG_INFINITY } else { v }
            })
            .collect();
        let mut sorted = mins.clone();
        sorted.sort_by(f64::total_cmp);
        let distribution = |sorted: &[f64]| Distribution {
            min: sorted.first().copied().unwrap_or(f64::NAN),
            mean: sorted.iter().sum::<f64>() / n as f64,
            max: sorted.last().copied().unwrap_or(f64::NAN),
            percentiles: [1.0, 5.0, 50.0, 95.0, 99.0]
                .iter()
                .map(|&pc| Percentile {
                    percent: pc,
                    value: stats::quantile(sorted, pc / 100.0),
                    ci95: quantile_ci(sorted, pc / 100.0, 0.95),
                })
                .collect(),
        };
        let margins: Vec<f64> = sorted.iter().map(|v| v - allowed_um).collect();
        let tolerance = rank.map(|r| sorted[(r - 1) as usize]);
        let flags: Vec<(bool, bool)> = outcomes
            .iter()
            .map(|o| PairOutcome::flags_from_values(o.pairs[p].min_backlash_um, allowed_um))
            .collect();
        let violations = flags.iter().filter(|f| f.0).count() as u64;
        let interference = flags.iter().filter(|f| f.1).count() as u64;
        let (verdict, reason) = self.verdict(n, interference, tolerance, allowed_um);
        PairReport {
            name: name.to_string(),
            verdict,
            reason,
            min_backlash_allowed_um: allowed_um,
            min_backlash_um: distribution(&sorted),
            min_margin_um: distribution(&margins),
            tolerance_95_95_um: tolerance,
            tolerance_rank: rank,
            tolerance_samples_needed: needed,
            violations: probability(violations, n),
            interference: probability(interference, n),
            sensitivities: self.sensitivities(&mins),
            worst: self.worst(p, &mins),
        }
    }

    /// Each dispersed number's Spearman correlation with the smallest backlash `mins`,
    /// strongest first.
    fn sensitivities(&self, mins: &[f64]) -> Vec<Sensitivity> {
        let mut sensitivities: Vec<Sensitivity> = self
            .id
            .dispersed
            .iter()
            .enumerate()
            .map(|(d, path)| {
                let x: Vec<f64> = self.outcomes.iter().map(|o| o.values[d]).collect();
                Sensitivity {
                    path: path.clone(),
                    spearman: stats::spearman(&x, mins),
                }
            })
            .collect();
        sensitivities.sort_by(|a, b| {
            b.spearman
                .abs()
                .total_cmp(&a.spearman.abs())
                .then(a.path.cmp(&b.path))
        });
        sensitivities
    }

    /// The five samples of pair `p` with the smallest backlash `mins`, with their
    /// dispersed values.
    fn worst(&self, p: usize, mins: &[f64]) -> Vec<Worst> {
        let mut order: Vec<usize> = (0..self.outcomes.len()).collect();
        order.sort_by(|&a, &b| mins[a].total_cmp(&mins[b]).then(a.cmp(&b)));
        order
            .iter()
            .take(5)
            .map(|&i| {
                let o = &self.outcomes[i];
                Worst {
                    index: o.index,
                    min_backlash_um: o.pairs[p].min_backlash_um,
                    t_min_s: o.pairs[p].t_min_s,
                    orbit_number: o.pairs[p].orbit_number,
                    orbit_phase_deg: o.pairs[p].orbit_phase_deg,
                    values: self
                        .id
                        .dispersed
                        .iter()
                        .zip(&o.values)
                        .map(|(d, v)| (d.clone(), *v))
                        .collect(),
                }
            })
            .collect()
    }

    /// The pair's verdict and why: every sample must run, none interfere, and the
    /// 95/95 bound `tolerance` (from `n` samples) reach the minimum `allowed_um`.
    fn verdict(
        &self,
        n: u64,
        interference: u64,
        tolerance: Option<f64>,
        allowed_um: f64,
    ) -> (PassFail, String) {
        let invalid = self.invalid;
        if !invalid.is_empty() {
            return (
                PassFail::Fail,
                format!(
                    "{} of {} samples could not be run (first: sample {}: {}); the tolerances allow combinations the model cannot take, so 95/95 cannot be shown",
                    invalid.len(),
                    self.all,
                    invalid[0].index,
                    invalid[0].reason
                ),
            );
        }
        if interference > 0 {
            return (
                PassFail::Fail,
                format!("{interference} of {n} samples interfere or lose the mesh"),
            );
        }
        let needed = stats::wilks_minimum_samples(0.95, 0.95);
        match tolerance {
            None => (
                PassFail::Fail,
                format!(
                    "{n} samples cannot show 95/95: a one-sided Wilks bound needs at least {needed}"
                ),
            ),
            Some(t) => {
                let (bound, least) = crate::units::apart(t, allowed_um, 3);
                if t >= allowed_um {
                    (
                        PassFail::Pass,
                        format!(
                            "95/95 lower bound of the smallest backlash {bound} µm ≥ {least} µm minimum"
                        ),
                    )
                } else {
                    (
                        PassFail::Fail,
                        format!(
                            "95/95 lower bound of the smallest backlash {bound} µm < {least} µm minimum"
                        ),
                    )
                }
            }
        }
    }
}

//! Monte Carlo margins: each sample is the nominal model with its dispersed values
//! ([`crate::dispersion::Plan`]), run over a horizon; the smallest backlash of each
//! gear pair and when it happened are kept. Samples are independent and evaluated in
//! parallel (rayon); their results depend only on (seed, index), so any thread count
//! and any slice of indices give the same numbers. The statistics an engineer signs
//! (percentiles, a Wilks tolerance bound, Clopper–Pearson intervals, Spearman
//! sensitivities) are in [`stats`].

use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use crate::dispersion::Plan;
use crate::model::{Model, ModelError};
use crate::orbit::EnvironmentModel;
use crate::sim::{RunStats, Setup, SimError, Stop};
use crate::summary::MeshStats;

/// How long each sample runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Horizon {
    /// This many orbits from the scenario's start.
    Orbits(f64),
    /// The scenario's own run length (its mission profile).
    Mission,
}

/// A gear pair's outcome in one sample.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PairOutcome {
    /// Smallest exact backlash over the sample's run, µm (NaN: the mesh was lost).
    pub min_backlash_um: f64,
    /// Smallest margin to the minimum allowed, µm.
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
/// outcome.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SampleOutcome {
    pub index: u64,
    pub values: Vec<f64>,
    pub pairs: Vec<PairOutcome>,
}

#[derive(Debug, thiserror::Error)]
pub enum MarginError {
    #[error("sample {index}: its values make an invalid model: {source}")]
    Model {
        index: u64,
        #[source]
        source: ModelError,
    },
    #[error("sample {index}: {source}")]
    Run {
        index: u64,
        #[source]
        source: SimError,
    },
}

/// Runs sample `k` of `plan` on a copy of `nominal`.
pub fn run_sample(
    nominal: &Model,
    plan: &Plan,
    k: u64,
    horizon: Horizon,
) -> Result<SampleOutcome, MarginError> {
    let mut model = nominal.clone();
    let values = plan
        .apply(&mut model, k)
        .map_err(|source| MarginError::Model { index: k, source })?;
    let sc = model.scenario();
    let env = &sc.thermal.environment;
    let t_end = match horizon {
        Horizon::Orbits(n) => n * env.mean_period_s(),
        Horizon::Mission => sc.run.duration_s,
    };
    let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver);
    let mut state = setup.initial_state();
    let mut mesh = MeshStats::last(env.mean_period_s());
    let _: RunStats = setup
        .run(&mut state, t_end, &mut mesh, Stop::default())
        .map_err(|source| MarginError::Run { index: k, source })?;
    let pairs = sc
        .gears
        .iter()
        .zip(&mesh.run_pairs)
        .map(|(g, p)| {
            let lost = p.invalid_samples > 0;
            let t = if lost { p.t_first_invalid_s } else { p.t_min_s };
            let min = if lost { f64::NAN } else { p.min_exact_m };
            PairOutcome {
                min_backlash_um: min * 1e6,
                min_margin_um: if lost { f64::NAN } else { p.min_margin_m * 1e6 },
                t_min_s: t,
                orbit_number: env.orbit_number(t),
                orbit_phase_deg: env.orbit_phase_deg(t),
                interference: lost || p.interference_events > 0 || min <= 0.0,
                violated: lost || min < g.min_backlash_m,
            }
        })
        .collect();
    Ok(SampleOutcome {
        index: k,
        values,
        pairs,
    })
}

/// Runs samples `range` in parallel; results in index order. `done` counts finished
/// samples (for a progress bar).
pub fn run_samples(
    nominal: &Model,
    plan: &Plan,
    range: Range<u64>,
    horizon: Horizon,
    done: &AtomicU64,
) -> Result<Vec<SampleOutcome>, MarginError> {
    range
        .into_par_iter()
        .map(|k| {
            let r = run_sample(nominal, plan, k, horizon);
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
        let q = 1.0 - coverage;
        // P(Bin(n, q) ≤ r − 1), summed term by term in logs
        let ln_choose =
            |n: u64, k: u64| -> f64 { (1..=k).map(|i| ((n - k + i) as f64 / i as f64).ln()).sum() };
        let mut best = None;
        let mut below = 0.0; // P(Bin ≤ r − 1)
        for r in 1..=n {
            let i = r - 1;
            below += (ln_choose(n, i) + i as f64 * q.ln() + (n - i) as f64 * coverage.ln()).exp();
            if 1.0 - below >= confidence {
                best = Some(r);
            } else {
                break;
            }
        }
        best
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

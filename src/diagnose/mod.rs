//! `diagnose`: a recording against the model. Where the residual sits, which physics
//! of the vocabulary (`shared/spec/physics.md` §6) the model left out, that physics
//! added and fitted on the training orbits, and the fit checked on held-out whole
//! orbits it never saw.
//!
//! Steps (each in its own function below):
//! 1. [`data::Observations`]: the recording matched to the model's sensors; the last
//!    third of the whole orbits held out; every sample's orbit phase.
//! 2. Baseline: the model simulated at the recording's times; residuals; each
//!    channel's noise from the residual's second differences ([`data::noise`]);
//!    mismatches folded by phase and orbit.
//! 3. [`effects::candidates`]: every effect on every element; thermostat set points
//!    started from the data (where a warming residual starts).
//! 4. Ranking: the training χ² at a few start points per candidate (cheap, parallel).
//! 5. Fitting: the leading candidates by bounded Levenberg–Marquardt ([`lm`]) on the
//!    training orbits, Jacobian by finite differences of whole simulations.
//! 6. Selection: an effect is accepted when it wins BIC by [`Options::bic_margin`]
//!    (with the estimated noise) *and* lowers the held-out χ² by
//!    [`Options::holdout_margin`] *and* is material ([`Options::min_effect`]); pairs are tried when one effect leaves a
//!    structured residual. The verdict is `explained` when the accepted effects bring
//!    every channel's held-out RMS to [`Options::noise_ratio`] × its noise,
//!    `consistent` when nothing is accepted and the baseline is at the noise, and
//!    `unexplained` otherwise.
//!
//! Pure: no files, no terminal. The CLI (`cli/diagnose.rs`) reads and writes.

pub mod data;
pub mod effects;
pub mod lm;

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use serde::ser::SerializeMap;

use crate::model::{Model, ModelError};
use crate::recording::Recording;
use crate::sample::Cadence;
use crate::sensor::{Readings, Sensor, SensorTarget};
use crate::sim::{
    Event, Observer, ObserverResult, RunStart, RunStats, SimError, StepView, simulate,
};

use data::{Mismatch, Observations, Part};
use effects::{Candidate, Hints, ParamDef, Setter};

#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    #[error("{0}")]
    Recording(String),
    #[error("{0}")]
    Options(String),
    #[error("the baseline simulation failed")]
    Baseline(#[source] SimError),
    #[error("the corrected model failed over the whole recording")]
    Corrected(#[source] SimError),
    #[error(transparent)]
    Model(#[from] ModelError),
}

/// The smallest noise assumed for a channel (K or µm): a recording can resolve no
/// better, and the model itself is computed to a tolerance of this order.
pub const NOISE_FLOOR: f64 = 1e-3;

/// How much a channel varies beyond its noise: the larger of the recording's spread
/// less the noise variance, and the baseline model's spread, over the samples `part`
/// admits.
fn signal_rms(
    obs: &data::Observations,
    c: usize,
    model: &[f64],
    noise: f64,
    part: impl Fn(usize) -> bool,
) -> f64 {
    let spread = |x: &mut dyn Iterator<Item = f64>| {
        let v: Vec<f64> = x.collect();
        if v.len() < 2 {
            return 0.0;
        }
        let m = v.iter().sum::<f64>() / v.len() as f64;
        v.iter().map(|y| (y - m) * (y - m)).sum::<f64>() / (v.len() - 1) as f64
    };
    let recorded = spread(
        &mut obs.values[c]
            .iter()
            .enumerate()
            .filter(|(j, v)| part(*j) && v.is_some())
            .map(|(_, v)| v.unwrap()),
    );
    let modelled = spread(
        &mut model
            .iter()
            .enumerate()
            .filter(|(j, _)| part(*j))
            .map(|(_, v)| *v),
    );
    (recorded - noise * noise)
        .max(0.0)
        .sqrt()
        .max(modelled.sqrt())
}

/// About how many runs of the model a diagnosis takes (for the estimate before it
/// starts): a handful per candidate to rank it, and a few fits of tens of runs each.
/// Candidates grow with the elements the vocabulary can attach to.
pub fn expected_runs(model: &Model) -> f64 {
    let sc = model.scenario();
    let net = &sc.thermal.network;
    let targets = net.nodes.len()
        + net.conductors.len()
        + net.radiators.len()
        + net.loads.len()
        + sc.sensors.len();
    (10 * targets + 500) as f64
}

/// Settings of a diagnosis.
#[derive(Debug, Clone)]
pub struct Options {
    /// Whole orbits held out at the end (None: a third, at least one).
    pub holdout_orbits: Option<usize>,
    /// An effect must lower BIC (χ² + k ln n with the estimated noise) by more than
    /// this on the training orbits. Calibrated on null recordings
    /// (`tests/val_diagnose_null.rs`).
    pub bic_margin: f64,
    /// … and lower the held-out χ² by more than this.
    pub holdout_margin: f64,
    /// … and be material: on some channel, lower the held-out mean square residual by
    /// at least this fraction of the noise variance (a real effect changes what a
    /// sensor reads; fitting the last hundredths of a kelvin of model error does not).
    pub min_effect: f64,
    /// A channel is at its noise when its RMS residual is at most this × the noise.
    pub noise_ratio: f64,
    /// Candidates fitted by least squares after the ranking.
    pub fits: usize,
    /// Partners tried with the best effect when one is not enough.
    pub pair_partners: usize,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            holdout_orbits: None,
            bic_margin: 40.0,
            holdout_margin: 20.0,
            min_effect: 0.05,
            noise_ratio: 1.3,
            fits: 8,
            pair_partners: 5,
        }
    }
}

/// Progress: (stage, done, total).
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// Values per channel, serialised as a JSON object in channel order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ChannelMap(pub Vec<(String, f64)>);

impl Serialize for ChannelMap {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, &finite(*v))?;
        }
        m.end()
    }
}

impl ChannelMap {
    pub fn get(&self, k: &str) -> Option<f64> {
        self.0.iter().find(|(n, _)| n == k).map(|(_, v)| *v)
    }
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    Consistent,
    Explained,
    Unexplained,
}

impl Verdict {
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Consistent => "consistent",
            Verdict::Explained => "explained",
            Verdict::Unexplained => "unexplained",
        }
    }
}

/// The baseline's fit.
#[derive(Debug, Clone, Serialize)]
pub struct Baseline {
    /// Over the training orbits (the whole recording when nothing is held out).
    pub rmse: ChannelMap,
    pub heldout_rmse: ChannelMap,
    /// RMS residual per channel and orbit.
    pub orbit_rmse: BTreeMap<String, Vec<Option<f64>>>,
    /// Σ (residual/noise)² over the training samples, and their number.
    pub chi2: f64,
    pub samples: usize,
}

/// A fitted parameter.
#[derive(Debug, Clone, Serialize)]
pub struct Fitted {
    pub value: f64,
    pub std_error: Option<f64>,
    /// On a bound of its range after the fit (its error is then not meaningful).
    pub at_bound: bool,
}

/// An accepted effect.
#[derive(Debug, Clone, Serialize)]
pub struct Finding {
    pub effect: &'static str,
    pub kind: effects::EffectKind,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub channel: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub conductor: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gear_pair: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gear: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub schedule: Option<String>,
    /// Fitted values in SI (°C where the name ends in `_c`).
    pub parameters: BTreeMap<String, f64>,
    /// Standard errors (from the Jacobian at the optimum, scaled by the residual
    /// variance).
    pub std_errors: BTreeMap<String, Option<f64>>,
    /// Parameter names in the order of `correlation`'s rows.
    pub correlation_order: Vec<String>,
    pub correlation: Vec<Vec<Option<f64>>>,
    /// Held-out RMS of the corrected model (with every accepted effect).
    pub heldout_rmse: ChannelMap,
    /// BIC of the model with this effect minus the model without it (training).
    pub delta_bic: f64,
    /// Held-out χ² drop this effect brings.
    pub heldout_chi2_drop: f64,
    /// The key-path values written into the corrected scenario.
    pub set: BTreeMap<String, f64>,
}

/// What became of a candidate: serialised as "accepted", "rejected", "not_fitted".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CandidateStatus {
    Accepted,
    Rejected,
    NotFitted,
}

impl CandidateStatus {
    pub fn as_str(self) -> &'static str {
        match self {
            CandidateStatus::Accepted => "accepted",
            CandidateStatus::Rejected => "rejected",
            CandidateStatus::NotFitted => "not_fitted",
        }
    }
}

impl std::fmt::Display for CandidateStatus {
    /// As serialised; honours width and alignment (`{:<10}`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

/// One line per candidate tried.
#[derive(Debug, Clone, Serialize)]
pub struct CandidateReport {
    pub effect: &'static str,
    pub target: String,
    /// `accepted`, `rejected` or `not_fitted`.
    pub status: CandidateStatus,
    pub reason: String,
    /// Training χ² drop at the best start point (the ranking score).
    pub rank_chi2_drop: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta_bic: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heldout_chi2_drop: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub parameters: Option<BTreeMap<String, f64>>,
    /// Wall time spent on this candidate (ranking and fit), s.
    pub time_s: f64,
}

/// The result of a diagnosis (the JSON report, plus the series and the corrected
/// model for the files).
#[derive(Debug, Clone, Serialize)]
pub struct Diagnosis {
    pub verdict: Verdict,
    pub noise: ChannelMap,
    pub baseline: Baseline,
    pub mismatches: Vec<Mismatch>,
    pub findings: Vec<Finding>,
    /// Held-out RMS of the corrected model (the baseline's when nothing is accepted).
    pub heldout_rmse: ChannelMap,
    /// Training RMS of the corrected model.
    pub rmse: ChannelMap,
    /// Where the corrected model's residual still sits.
    pub remaining: Vec<Mismatch>,
    pub split: data::Split,
    pub candidates: Vec<CandidateReport>,
    pub notes: Vec<String>,
    /// Reasons to doubt the verdict (a channel whose noise is far larger than its
    /// signal); also printed on standard error.
    pub warnings: Vec<String>,
    /// Wall time of the whole analysis, s, and of the candidate search per candidate.
    pub time_s: f64,
    pub time_per_candidate_s: f64,
    #[serde(skip)]
    pub series: Series,
    #[serde(skip)]
    pub corrected: Option<Model>,
}

/// Recorded, baseline and corrected values per channel at the recording's times.
#[derive(Debug, Clone, Default)]
pub struct Series {
    pub time_s: Vec<f64>,
    pub channels: Vec<String>,
    pub units: Vec<&'static str>,
    pub recorded: Vec<Vec<Option<f64>>>,
    pub baseline: Vec<Vec<f64>>,
    pub corrected: Vec<Vec<f64>>,
    pub train_end_s: f64,
    pub holdout_end_s: f64,
    /// Each channel's estimated noise (K or µm).
    pub noise: Vec<f64>,
}

/// Simulated sensor values at `times` (ascending, from ≥ 0), per sensor (the
/// scenario's, then `extra`), and the solver's steps. A run that needs more than
/// `max_steps` steps is stopped with an error (a thermostat chattering on a fast node
/// would otherwise take minutes).
pub fn predict(
    model: &Model,
    times: &Arc<[f64]>,
    extra: &[Sensor],
    max_steps: u64,
) -> Result<(Vec<Vec<f64>>, u64), SimError> {
    let sc = model.scenario();
    let mut sensors = sc.sensors.clone();
    sensors.extend_from_slice(extra);
    let t_end = times.last().copied().unwrap_or(0.0).max(1e-3);
    let mut readings = Budget {
        inner: Readings::new(sensors, Cadence::Times(times.clone())),
        steps: 0,
        max_steps,
    };
    let stats = simulate(
        &sc.thermal,
        &sc.gears,
        &sc.solver,
        t_end,
        &mut readings,
        None,
    )?;
    Ok((readings.inner.values, stats.steps))
}

/// Readings with a budget of steps.
struct Budget {
    inner: Readings,
    steps: u64,
    max_steps: u64,
}

impl Observer for Budget {
    fn on_start(&mut self, s: &RunStart<'_>) -> ObserverResult {
        self.inner.on_start(s)
    }
    fn on_step(&mut self, s: &StepView<'_>) -> ObserverResult {
        self.steps += 1;
        if self.steps > self.max_steps {
            return Err(format!(
                "more than {} solver steps (the baseline needs far fewer): a thermostat \
                 switching many times a minute or a very fast transient",
                self.max_steps
            )
            .into());
        }
        self.inner.on_step(s)
    }
    fn on_event(&mut self, e: &Event) -> ObserverResult {
        self.inner.on_event(e)
    }
    fn on_finish(&mut self, s: &RunStats) -> ObserverResult {
        self.inner.on_finish(s)
    }
}

/// A model with one or more candidates' effects, parameters concatenated.
struct Composite {
    base: Model,
    params: Vec<ParamDef>,
    setters: Vec<Setter>,
}

impl Composite {
    fn new(model: &Model, members: &[&Candidate]) -> Result<Composite, ModelError> {
        let mut base = model.clone();
        let edits: Vec<_> = members
            .iter()
            .flat_map(|c| c.edits.iter().cloned())
            .collect();
        if !edits.is_empty() {
            base.modify(|s| {
                for e in &edits {
                    e(s)
                }
            })?;
        }
        let mut params = Vec::new();
        let mut setters = Vec::new();
        for c in members {
            let off = params.len();
            params.extend(c.params.iter().cloned());
            setters.extend(c.setters.iter().map(|s| Setter {
                path: s.path.clone(),
                constant: s.constant,
                terms: s.terms.iter().map(|&(i, k)| (i + off, k)).collect(),
            }));
        }
        Ok(Composite {
            base,
            params,
            setters,
        })
    }

    fn model_at(&self, theta: &[f64]) -> Result<Model, ModelError> {
        let mut m = self.base.clone();
        m.set_many(&effects::values(&self.setters, theta))?;
        Ok(m)
    }
}

/// The data a fit needs, shared by every candidate.
struct Problem<'a> {
    obs: &'a Observations,
    noise: Vec<f64>,
    /// Times up to the end of the training orbits, and up to the end of the held-out.
    train_times: Arc<[f64]>,
    all_times: Arc<[f64]>,
    /// Step budget of one simulation of the whole recording.
    max_steps: u64,
}

impl Problem<'_> {
    /// Weighted training residuals (recorded − predicted)/noise.
    fn train_residuals(&self, pred: &[Vec<f64>]) -> Vec<f64> {
        let mut out = Vec::new();
        for (c, ch) in self.obs.channels.iter().enumerate() {
            let p = &pred[ch.sensor];
            for (j, v) in self.obs.values[c].iter().enumerate().take(p.len()) {
                if let (Some(v), Part::Train) = (v, self.obs.part[j]) {
                    out.push((v - p[j]) / self.noise[c]);
                }
            }
        }
        out
    }

    /// The largest, over channels, drop of the held-out mean square residual from
    /// `before` to `after`, in units of the channel's noise variance.
    fn material(&self, before: &[Vec<f64>], after: &[Vec<f64>]) -> f64 {
        let mut best = f64::NEG_INFINITY;
        for (c, ch) in self.obs.channels.iter().enumerate() {
            let (b, a) = (&before[ch.sensor], &after[ch.sensor]);
            let (mut s, mut n) = (0.0, 0usize);
            for (j, v) in self.obs.values[c]
                .iter()
                .enumerate()
                .take(a.len().min(b.len()))
            {
                if let (Some(v), Part::Holdout) = (v, self.obs.part[j]) {
                    s += ((v - b[j]).powi(2) - (v - a[j]).powi(2)) / self.noise[c].powi(2);
                    n += 1;
                }
            }
            if n > 0 {
                best = best.max(s / n as f64);
            }
        }
        best
    }

    fn chi2(&self, pred: &[Vec<f64>], part: Part) -> f64 {
        let mut s = 0.0;
        for (c, ch) in self.obs.channels.iter().enumerate() {
            let p = &pred[ch.sensor];
            for (j, v) in self.obs.values[c].iter().enumerate().take(p.len()) {
                if let (Some(v), true) = (v, self.obs.part[j] == part) {
                    s += ((v - p[j]) / self.noise[c]).powi(2);
                }
            }
        }
        s
    }

    fn train_residuals_at(&self, comp: &Composite, theta: &[f64]) -> Result<Vec<f64>, String> {
        let m = comp.model_at(theta).map_err(|e| e.to_string())?;
        let pred = self.predict(&m, &self.train_times)?;
        Ok(self.train_residuals(&pred))
    }

    fn predict(&self, m: &Model, times: &Arc<[f64]>) -> Result<Vec<Vec<f64>>, String> {
        predict(m, times, &[], self.max_steps)
            .map(|p| p.0)
            .map_err(|e| crate::error_chain(&e))
    }
}

/// A candidate's ranking: its best training χ² and parameters (None: it could not be
/// simulated), the last error, and the wall time.
type Ranked = (Option<(f64, Vec<f64>)>, String, f64);

/// A fitted hypothesis (one or two candidates).
#[derive(Debug, Clone)]
struct Hypothesis {
    members: Vec<usize>,
    theta: Vec<f64>,
    fit: lm::LmFit,
    train_chi2: f64,
    holdout_chi2: f64,
    pred: Vec<Vec<f64>>,
    model: Model,
}

/// Runs the diagnosis of `recording` against `model`.
pub fn diagnose(
    model: &Model,
    recording: &Recording,
    opts: &Options,
    progress: Progress<'_>,
) -> Result<Diagnosis, DiagnoseError> {
    let started = Instant::now();
    let sc = model.scenario();
    let obs = Observations::new(recording, sc, opts.holdout_orbits)?;
    let mut notes = Vec::new();
    let validate = obs.split.can_validate();
    if !validate {
        notes.push(format!(
            "the recording covers {} whole orbit(s) of {:.1} s; held-out validation needs at \
             least two (one to fit, one to check), so only the baseline and the mismatches \
             are reported",
            obs.split.orbits, obs.split.period_s
        ));
    }

    // Baseline, with every diffusion node read too (for the thermostat start points).
    progress("baseline", 0, 1);
    let all_times: Arc<[f64]> = obs
        .time_s
        .iter()
        .copied()
        .take_while(|&t| t <= obs.split.holdout_end_s)
        .collect::<Vec<_>>()
        .into();
    let train_times: Arc<[f64]> = obs
        .time_s
        .iter()
        .copied()
        .take_while(|&t| t < obs.split.train_end_s)
        .collect::<Vec<_>>()
        .into();
    let whole: Arc<[f64]> = obs.time_s.clone().into();
    let node_count = sc.thermal.network.nodes.len();
    let node_sensors: Vec<Sensor> = (0..node_count)
        .map(|i| Sensor::new(format!("__node{i}_k"), SensorTarget::Node(i)))
        .collect();
    let (base_pred_ext, base_steps) =
        predict(model, &whole, &node_sensors, u64::MAX).map_err(DiagnoseError::Baseline)?;
    let n_sensors = sc.sensors.len();
    let node_temps_k = &base_pred_ext[n_sensors..];
    let base_pred: Vec<Vec<f64>> = base_pred_ext[..n_sensors].to_vec();
    let base_res = obs.residuals(&base_pred);
    let fit_part = |j: usize| !validate || obs.part[j] == Part::Train;
    let mut noise = Vec::new();
    for (c, r) in base_res.iter().enumerate() {
        let sigma = data::noise(&obs.time_s, r, fit_part).ok_or_else(|| {
            DiagnoseError::Recording(format!(
                "{}: channel `{}` has too few consecutive samples to estimate its noise",
                obs.file, obs.channels[c].name
            ))
        })?;
        if sigma < NOISE_FLOOR {
            notes.push(format!(
                "channel `{}` is smoother than {NOISE_FLOOR} {} (noise estimated {sigma:.1e}): \
                 model output rather than a measurement? Its noise is taken as {NOISE_FLOOR}",
                obs.channels[c].name, obs.channels[c].unit
            ));
        }
        noise.push(sigma.max(NOISE_FLOOR));
    }
    let mut warnings = Vec::new();
    for (c, ch) in obs.channels.iter().enumerate() {
        let signal = signal_rms(&obs, c, &base_pred[ch.sensor], noise[c], fit_part);
        if noise[c] > 2.0 * signal && noise[c] > 1.0 {
            warnings.push(format!(
                "channel `{}`: its noise ({:.3} {u}) is far larger than its signal ({:.3} {u} rms, recorded and modelled): \
the verdict rests on noise; check the channel's unit and scaling",
                ch.name,
                noise[c],
                signal,
                u = ch.unit
            ));
        }
    }
    let names: Vec<String> = obs.channels.iter().map(|c| c.name.clone()).collect();
    let cmap = |v: &[f64]| ChannelMap(names.iter().cloned().zip(v.iter().copied()).collect());
    let base_rms = obs.rms(&base_res, Part::Train);
    let base_rms_h = obs.rms(&base_res, Part::Holdout);
    let problem = Problem {
        obs: &obs,
        noise: noise.clone(),
        train_times,
        all_times,
        max_steps: 20 * base_steps + 5000,
    };
    let base_chi2 = problem.chi2(&base_pred, Part::Train);
    let base_chi2_h = problem.chi2(&base_pred, Part::Holdout);
    let n_train = problem.train_residuals(&base_pred).len();
    let orbit_rmse = data::orbit_rms(&obs, &base_res)
        .into_iter()
        .zip(&names)
        .map(|(v, n)| (n.clone(), v.into_iter().map(finite).collect()))
        .collect();
    let mismatches = data::mismatches(&obs, &base_res, &noise, opts.noise_ratio);
    let baseline = Baseline {
        rmse: cmap(&base_rms),
        heldout_rmse: cmap(&base_rms_h),
        orbit_rmse,
        chi2: base_chi2,
        samples: n_train,
    };
    progress("baseline", 1, 1);
    let at_noise = |rms: &[f64]| {
        rms.iter()
            .zip(&noise)
            .all(|(r, s)| r.is_nan() || *r <= opts.noise_ratio * s)
    };
    let baseline_at_noise = at_noise(&base_rms) && (!validate || at_noise(&base_rms_h));

    let mut series = Series {
        time_s: obs.time_s.clone(),
        channels: names.clone(),
        units: obs.channels.iter().map(|c| c.unit).collect(),
        recorded: obs.values.clone(),
        baseline: obs
            .channels
            .iter()
            .map(|c| base_pred[c.sensor].clone())
            .collect(),
        corrected: obs
            .channels
            .iter()
            .map(|c| base_pred[c.sensor].clone())
            .collect(),
        train_end_s: obs.split.train_end_s.min(*obs.time_s.last().unwrap()),
        holdout_end_s: obs.split.holdout_end_s.min(*obs.time_s.last().unwrap()),
        noise: noise.clone(),
    };
    let mut report = Diagnosis {
        verdict: if baseline_at_noise {
            Verdict::Consistent
        } else {
            Verdict::Unexplained
        },
        noise: cmap(&noise),
        baseline,
        mismatches: mismatches.clone(),
        findings: Vec::new(),
        heldout_rmse: cmap(&base_rms_h),
        rmse: cmap(&base_rms),
        remaining: mismatches,
        split: obs.split.clone(),
        candidates: Vec::new(),
        notes,
        warnings,
        time_s: 0.0,
        time_per_candidate_s: 0.0,
        series: Series::default(),
        corrected: None,
    };
    if !validate {
        report.series = series;
        report.time_s = started.elapsed().as_secs_f64();
        return Ok(report);
    }

    // Candidates, thermostats started from the data.
    let hints = heater_hints(&obs, &base_res, &noise, node_temps_k);
    let channels: Vec<(String, bool)> = obs
        .channels
        .iter()
        .map(|c| (c.name.clone(), c.is_temperature))
        .collect();
    let cands = effects::candidates(model, &channels, &hints);
    let search_started = Instant::now();

    // Ranking: the training χ² at each start point, and along the line from the
    // effect's null through it (the residual projected on the change it makes).
    let r0 = problem.train_residuals(&base_pred);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let total = cands.len();
    let ranked: Vec<Ranked> = cands
        .par_iter()
        .map(|c| {
            let t0 = Instant::now();
            let out = match Composite::new(model, &[c]) {
                Err(e) => (None, e.to_string()),
                Ok(comp) => {
                    let mut best: Option<(f64, Vec<f64>)> = None;
                    let mut err = String::new();
                    for s in &c.starts {
                        match problem.train_residuals_at(&comp, s) {
                            Ok(r1) => {
                                for (x2, theta) in rank_point(&r0, &r1, c, s) {
                                    if best.as_ref().is_none_or(|b| x2 < b.0) {
                                        best = Some((x2, theta));
                                    }
                                }
                            }
                            Err(e) => err = e,
                        }
                    }
                    (best, err)
                }
            };
            let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress("ranking", k, total);
            (out.0, out.1, t0.elapsed().as_secs_f64())
        })
        .collect();
    let mut order: Vec<usize> = (0..cands.len())
        .filter(|&i| ranked[i].0.is_some())
        .collect();
    let score = |i: usize| base_chi2 - ranked[i].0.as_ref().unwrap().0;
    order.sort_by(|&a, &b| score(b).total_cmp(&score(a)).then(a.cmp(&b)));
    let to_fit: Vec<usize> = order
        .iter()
        .copied()
        .filter(|&i| score(i) > 0.0)
        .take(opts.fits)
        .collect();

    // Fitting the leading candidates.
    let done = std::sync::atomic::AtomicUsize::new(0);
    let nfit = to_fit.len();
    let fitted: Vec<(Result<Hypothesis, String>, f64)> = to_fit
        .par_iter()
        .map(|&i| {
            let t0 = Instant::now();
            let start = ranked[i].0.as_ref().unwrap().1.clone();
            let h = fit(&problem, model, &cands, &[i], &start);
            let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress("fitting", k, nfit);
            (h, t0.elapsed().as_secs_f64())
        })
        .collect();
    let ln_n = (n_train.max(2) as f64).ln();
    let bic_gain = |h: &Hypothesis, chi2_ref: f64, k_extra: usize| {
        chi2_ref - h.train_chi2 - k_extra as f64 * ln_n
    };
    let mut singles: Vec<Hypothesis> = Vec::new();
    let mut reports: Vec<CandidateReport> = Vec::new();
    for (ci, c) in cands.iter().enumerate() {
        let fit_pos = to_fit.iter().position(|&i| i == ci);
        let rank_drop = ranked[ci].0.as_ref().map_or(f64::NAN, |r| base_chi2 - r.0);
        let mut rep = CandidateReport {
            effect: c.effect.id(),
            target: c.label(),
            status: CandidateStatus::NotFitted,
            reason: String::new(),
            rank_chi2_drop: rank_drop,
            delta_bic: None,
            heldout_chi2_drop: None,
            parameters: None,
            time_s: ranked[ci].2,
        };
        match fit_pos {
            None if ranked[ci].0.is_none() => {
                rep.reason = format!("could not be simulated: {}", ranked[ci].1);
            }
            None => {
                rep.reason = if rank_drop <= 0.0 {
                    "does not lower the training residual at any start point".into()
                } else {
                    format!("ranked below the {} fitted candidates", opts.fits)
                };
            }
            Some(p) => {
                rep.time_s += fitted[p].1;
                match &fitted[p].0 {
                    Err(e) => {
                        rep.status = CandidateStatus::Rejected;
                        rep.reason = format!("fit failed: {e}");
                    }
                    Ok(h) => {
                        let gain = bic_gain(h, base_chi2, c.params.len());
                        let hdrop = base_chi2_h - h.holdout_chi2;
                        rep.delta_bic = Some(-gain);
                        rep.heldout_chi2_drop = Some(hdrop);
                        rep.parameters = Some(
                            c.report_params(&h.theta, None)
                                .into_iter()
                                .map(|(k, v, _)| (k, v))
                                .collect(),
                        );
                        rep.status = CandidateStatus::Rejected;
                        if gain <= opts.bic_margin {
                            rep.reason = format!(
                                "BIC improves by {gain:.1}, not by more than the margin {:.0}",
                                opts.bic_margin
                            );
                        } else if hdrop <= opts.holdout_margin {
                            rep.reason = format!(
                                "fits the training orbits (BIC −{gain:.0}) but does not improve \
                                 the held-out orbits (χ² drop {hdrop:.1} ≤ {:.0})",
                                opts.holdout_margin
                            );
                        } else if problem.material(&base_pred, &h.pred) < opts.min_effect {
                            rep.reason = format!(
                                "significant but immaterial: lowers no channel's held-out mean \
                                 square residual by {:.0} % of its noise variance",
                                100.0 * opts.min_effect
                            );
                        } else {
                            rep.status = CandidateStatus::Accepted;
                            singles.push(h.clone());
                        }
                    }
                }
            }
        }
        reports.push(rep);
    }
    let single_gain = |h: &Hypothesis| bic_gain(h, base_chi2, h.theta.len());
    singles.sort_by(|a, b| single_gain(b).total_cmp(&single_gain(a)));
    let explains = |h: &Hypothesis| {
        let res = obs.residuals(&h.pred);
        at_noise(&obs.rms(&res, Part::Holdout)) && at_noise(&obs.rms(&res, Part::Train))
    };

    let mut best: Option<Hypothesis> = None;
    if let Some(first) = singles.first() {
        if explains(first) {
            best = Some(first.clone());
        } else {
            // One effect is not enough: rank every other candidate again on the
            // residual the best one leaves (forward selection), then fit the leading
            // ones together with it.
            let f0 = first.members[0];
            let r_first = problem.train_residuals(&first.pred);
            let done = std::sync::atomic::AtomicUsize::new(0);
            let second: Vec<Option<(f64, Vec<f64>)>> = (0..cands.len())
                .into_par_iter()
                .map(|j| {
                    let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    progress("pairs: ranking", k, cands.len());
                    if j == f0 || ranked[j].0.is_none() {
                        return None;
                    }
                    let comp = Composite::new(model, &[&cands[f0], &cands[j]]).ok()?;
                    let mut best: Option<(f64, Vec<f64>)> = None;
                    for s in &cands[j].starts {
                        let mut theta = first.theta.clone();
                        theta.extend_from_slice(s);
                        let Ok(r1) = problem.train_residuals_at(&comp, &theta) else {
                            continue;
                        };
                        for (x2, th) in rank_point(&r_first, &r1, &cands[j], s) {
                            if best.as_ref().is_none_or(|b| x2 < b.0) {
                                best = Some((x2, th));
                            }
                        }
                    }
                    best
                })
                .collect();
            let mut partners: Vec<usize> = (0..cands.len())
                .filter(|&j| second[j].as_ref().is_some_and(|b| b.0 < first.train_chi2))
                .collect();
            partners.sort_by(|&a, &b| {
                let (xa, xb) = (second[a].as_ref().unwrap().0, second[b].as_ref().unwrap().0);
                xa.total_cmp(&xb).then(a.cmp(&b))
            });
            partners.truncate(opts.pair_partners);
            let npairs = partners.len();
            let done = std::sync::atomic::AtomicUsize::new(0);
            let pairs: Vec<Result<Hypothesis, String>> = partners
                .par_iter()
                .map(|&j| {
                    let mut start = first.theta.clone();
                    start.extend_from_slice(&second[j].as_ref().unwrap().1);
                    let r = fit(&problem, model, &cands, &[first.members[0], j], &start);
                    let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    progress("pairs", k, npairs);
                    r
                })
                .collect();
            let mut best_pair: Option<Hypothesis> = None;
            for h in pairs.into_iter().flatten() {
                let extra = bic_gain(&h, first.train_chi2, cands[h.members[1]].params.len());
                let hdrop = first.holdout_chi2 - h.holdout_chi2;
                if extra > opts.bic_margin
                    && hdrop > opts.holdout_margin
                    && problem.material(&first.pred, &h.pred) >= opts.min_effect
                    && best_pair
                        .as_ref()
                        .is_none_or(|b| h.train_chi2 < b.train_chi2)
                {
                    best_pair = Some(h);
                }
            }
            match best_pair {
                Some(p) if explains(&p) => best = Some(p),
                Some(p) => {
                    report.notes.push(format!(
                        "{} with {} improves on either alone but leaves a structured residual",
                        cands[p.members[0]].label(),
                        cands[p.members[1]].label()
                    ));
                }
                None => {}
            }
            if best.is_none() {
                report.notes.push(format!(
                    "the best candidate, {}, improves the fit (BIC −{:.0}) but does not bring the \
                     held-out orbits to the noise; no effect of the vocabulary, alone or in a \
                     pair, explains the residual",
                    cands[first.members[0]].label(),
                    single_gain(first)
                ));
            }
        }
    }

    // The verdict and the corrected model.
    match &best {
        Some(h) => {
            report.verdict = Verdict::Explained;
            let res = obs.residuals(&h.pred);
            report.heldout_rmse = cmap(&obs.rms(&res, Part::Holdout));
            report.rmse = cmap(&obs.rms(&res, Part::Train));
            report.remaining = data::mismatches(&obs, &res, &noise, opts.noise_ratio);
            let cov = h.fit.covariance.as_ref().map(|c| {
                (0..c.nrows())
                    .map(|i| (0..c.ncols()).map(|j| c[(i, j)]).collect::<Vec<f64>>())
                    .collect::<Vec<_>>()
            });
            let corr = h.fit.correlation();
            let mut off = 0;
            for (m, &ci) in h.members.iter().enumerate() {
                let c = &cands[ci];
                let k = c.params.len();
                let theta = &h.theta[off..off + k];
                let sub_cov: Option<Vec<Vec<f64>>> = cov.as_ref().map(|cv| {
                    (off..off + k)
                        .map(|i| cv[i][off..off + k].to_vec())
                        .collect()
                });
                let params = c.report_params(theta, sub_cov.as_deref());
                // Evidence of this member: the hypothesis against it without this member.
                let (delta_bic, hdrop) = if h.members.len() == 1 {
                    (-single_gain(h), base_chi2_h - h.holdout_chi2)
                } else {
                    let other = h.members[1 - m];
                    let alone = singles.iter().find(|s| s.members == [other]);
                    match alone {
                        Some(a) => (
                            -(a.train_chi2 - h.train_chi2 - k as f64 * ln_n),
                            a.holdout_chi2 - h.holdout_chi2,
                        ),
                        None => (-single_gain(h), base_chi2_h - h.holdout_chi2),
                    }
                };
                let names_k: Vec<String> = c.params.iter().map(|p| p.name.to_string()).collect();
                report.findings.push(Finding {
                    effect: c.effect.id(),
                    kind: c.effect.kind(),
                    node: c.node.clone(),
                    channel: c.channel.clone(),
                    conductor: c.conductor.clone(),
                    load: c.load.clone(),
                    gear_pair: c.gear_pair.clone(),
                    gear: c.gear.clone(),
                    schedule: c.schedule.clone(),
                    parameters: params.iter().map(|(n, v, _)| (n.clone(), *v)).collect(),
                    std_errors: params
                        .iter()
                        .map(|(n, _, s)| (n.clone(), finite(*s)))
                        .collect(),
                    correlation: (off..off + k)
                        .map(|i| (off..off + k).map(|j| finite(corr[i][j])).collect())
                        .collect(),
                    correlation_order: names_k,
                    heldout_rmse: cmap(&obs.rms(&res, Part::Holdout)),
                    delta_bic,
                    heldout_chi2_drop: hdrop,
                    set: c.values(theta).into_iter().collect(),
                });
                off += k;
            }
            // The corrected series over the whole recording (tail included).
            let (p, _) =
                predict(&h.model, &whole, &[], u64::MAX).map_err(DiagnoseError::Corrected)?;
            series.corrected = obs.channels.iter().map(|c| p[c.sensor].clone()).collect();
            report.corrected = Some(h.model.clone());
            for (ci, rep) in reports.iter_mut().enumerate() {
                if h.members.contains(&ci) {
                    rep.status = CandidateStatus::Accepted;
                    rep.reason = match h.members.iter().find(|&&m| m != ci) {
                        Some(&other) => format!("together with {}", cands[other].label()),
                        None => String::new(),
                    };
                } else if rep.status == CandidateStatus::Accepted {
                    rep.status = CandidateStatus::Rejected;
                    rep.reason = format!(
                        "improves the fit, but {} explains the residual better",
                        h.members
                            .iter()
                            .map(|&m| cands[m].label())
                            .collect::<Vec<_>>()
                            .join(" with ")
                    );
                }
            }
        }
        None => {
            for rep in reports
                .iter_mut()
                .filter(|r| r.status == CandidateStatus::Accepted)
            {
                rep.status = CandidateStatus::Rejected;
                rep.reason = "improves the fit but does not explain the residual".into();
            }
            report.verdict = if baseline_at_noise {
                Verdict::Consistent
            } else {
                Verdict::Unexplained
            };
            report.corrected = None;
        }
    }
    reports.sort_by(|a, b| {
        let key = |r: &CandidateReport| match r.status {
            CandidateStatus::Accepted => 0,
            CandidateStatus::Rejected => 1,
            CandidateStatus::NotFitted => 2,
        };
        key(a)
            .cmp(&key(b))
            .then(b.rank_chi2_drop.total_cmp(&a.rank_chi2_drop))
    });
    report.candidates = reports;
    report.series = series;
    report.time_per_candidate_s =
        search_started.elapsed().as_secs_f64() / cands.len().max(1) as f64;
    report.time_s = started.elapsed().as_secs_f64();
    Ok(report)
}

/// The training χ² a start point `s` reaches (residuals `r1`), and, for an effect with
/// a null, the best point on the line from the null through `s` under a linear model
/// of the change (r(α) = r0 − α (r0 − r1)), within the bounds.
fn rank_point(r0: &[f64], r1: &[f64], c: &Candidate, s: &[f64]) -> Vec<(f64, Vec<f64>)> {
    let x2_0: f64 = r0.iter().map(|v| v * v).sum();
    let x2_1: f64 = r1.iter().map(|v| v * v).sum();
    let mut out = vec![(x2_1, s.to_vec())];
    let Some(null) = &c.null else { return out };
    let (mut rd, mut dd) = (0.0, 0.0);
    for (a, b) in r0.iter().zip(r1) {
        let d = a - b;
        rd += a * d;
        dd += d * d;
    }
    if dd.is_nan() || dd <= 0.0 {
        return out;
    }
    // The largest α that keeps every parameter within its bounds.
    let mut alpha_max = f64::INFINITY;
    for (i, p) in c.params.iter().enumerate() {
        let dir = s[i] - null[i];
        if dir > 0.0 {
            alpha_max = alpha_max.min((p.upper - null[i]) / dir);
        } else if dir < 0.0 {
            alpha_max = alpha_max.min((p.lower - null[i]) / dir);
        }
    }
    let alpha = (rd / dd).clamp(0.0, alpha_max.max(0.0));
    let theta: Vec<f64> = (0..s.len())
        .map(|i| (null[i] + alpha * (s[i] - null[i])).clamp(c.params[i].lower, c.params[i].upper))
        .collect();
    out.push((x2_0 - (2.0 * alpha * rd - alpha * alpha * dd), theta));
    out
}

/// Fits `members` together from `start` on the training orbits, then predicts the
/// held-out orbits.
fn fit(
    problem: &Problem<'_>,
    model: &Model,
    cands: &[Candidate],
    members: &[usize],
    start: &[f64],
) -> Result<Hypothesis, String> {
    let refs: Vec<&Candidate> = members.iter().map(|&i| &cands[i]).collect();
    let comp = Composite::new(model, &refs).map_err(|e| e.to_string())?;
    let lower: Vec<f64> = comp.params.iter().map(|p| p.lower).collect();
    let upper: Vec<f64> = comp.params.iter().map(|p| p.upper).collect();
    let steps: Vec<f64> = comp.params.iter().map(|p| p.step).collect();
    let f = |theta: &[f64]| -> Result<Vec<f64>, String> {
        let m = comp.model_at(theta).map_err(|e| e.to_string())?;
        let pred = problem.predict(&m, &problem.train_times)?;
        Ok(problem.train_residuals(&pred))
    };
    let opts = lm::LmOptions {
        max_iterations: 40,
        ftol: 1e-6,
        xtol: 1e-4,
        cost_floor: 0.0,
    };
    let fit = lm::minimize(f, start, &lower, &upper, &steps, opts)?;
    let m = comp.model_at(&fit.x).map_err(|e| e.to_string())?;
    let pred = problem.predict(&m, &problem.all_times)?;
    Ok(Hypothesis {
        members: members.to_vec(),
        theta: fit.x.clone(),
        train_chi2: problem.chi2(&pred, Part::Train),
        holdout_chi2: problem.chi2(&pred, Part::Holdout),
        fit,
        pred,
        model: m,
    })
}

/// Thermostat start points: the channel with the most warming residual in the
/// training orbits; in each orbit, where that residual starts (walking back from where
/// it clearly shows to where it was still at the noise); each node's baseline
/// temperature then, the median over the orbits.
fn heater_hints(
    obs: &Observations,
    res: &[Vec<Option<f64>>],
    noise: &[f64],
    node_temps_k: &[Vec<f64>],
) -> Hints {
    let mut hints = Hints {
        heater_on_k: vec![None; node_temps_k.len()],
    };
    let smooth: Vec<Vec<Option<f64>>> = res.iter().map(|r| data::smoothed(r, 5)).collect();
    let mut best: Option<(usize, f64)> = None;
    for (c, ch) in obs.channels.iter().enumerate() {
        if !ch.is_temperature {
            continue;
        }
        let limit = 4.0 * noise[c] / 5f64.sqrt();
        let e: f64 = smooth[c]
            .iter()
            .enumerate()
            .filter(|(j, _)| obs.part[*j] == Part::Train)
            .filter_map(|(_, v)| *v)
            .filter(|v| *v > limit)
            .map(|v| v * v / (noise[c] * noise[c]))
            .sum();
        if e > 0.0 && best.is_none_or(|b| e > b.1) {
            best = Some((c, e));
        }
    }
    let Some((c, _)) = best else { return hints };
    let hi = 4.0 * noise[c] / 5f64.sqrt();
    let lo = noise[c] / 5f64.sqrt();
    let mut starts = Vec::new();
    for orbit in 0..obs.split.train_orbits {
        let idx: Vec<usize> = (0..obs.time_s.len())
            .filter(|&j| obs.orbit[j] == orbit && obs.part[j] == Part::Train)
            .collect();
        let Some(pos) = idx
            .iter()
            .position(|&j| smooth[c][j].is_some_and(|v| v > hi))
        else {
            continue;
        };
        let mut k = pos;
        while k > 0 && smooth[c][idx[k]].is_none_or(|v| v > lo) {
            k -= 1;
        }
        if k > 0 || smooth[c][idx[0]].is_some_and(|v| v <= lo) {
            starts.push(idx[k]);
        }
    }
    if starts.is_empty() {
        return hints;
    }
    for (n, temps) in node_temps_k.iter().enumerate() {
        let mut v: Vec<f64> = starts.iter().map(|&j| temps[j]).collect();
        hints.heater_on_k[n] = Some(data::median(&mut v));
    }
    hints
}

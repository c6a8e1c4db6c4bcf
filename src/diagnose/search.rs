//! The candidate search of a diagnosis (steps 4–6 of the module doc): candidates
//! ranked at their start points, the leading ones fitted, each fit judged against a
//! reference (the baseline or the calibrated model, or the best single effect when a
//! second is tried with it), and forward selection, one effect at a time, while the
//! accepted effects leave a structured residual.
//!
//! The calibration ([`Problem::calibrate`]): a few numbers of the model itself, fitted
//! first with a prior toward nominal, then present in every model of the search as the
//! first parameters of every composite, re-fitted jointly with each candidate; so a
//! calibration number cannot keep what a new effect explains, and a candidate cannot
//! stand in for it.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use super::data::{Observations, Part};
use super::effects::{Candidate, Floor, ParamDef, Setter};
use super::{Options, Progress, lm, predict};
use crate::spec::model::{Model, ModelError};

/// A stage's progress, counted from parallel workers: `tick` once per item done.
struct Counter<'a> {
    stage: &'static str,
    total: usize,
    done: AtomicUsize,
    progress: Progress<'a>,
}

impl<'a> Counter<'a> {
    fn new(stage: &'static str, total: usize, progress: Progress<'a>) -> Counter<'a> {
        Counter {
            stage,
            total,
            done: AtomicUsize::new(0),
            progress,
        }
    }

    fn tick(&self) {
        let k = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        (self.progress)(self.stage, k, self.total);
    }
}

/// A model with the calibration's and one or more candidates' effects, parameters
/// concatenated (the calibration's first).
pub(super) struct Composite {
    base: Model,
    params: Vec<ParamDef>,
    setters: Vec<Setter>,
    ids: Vec<crate::spec::model::ParamId>,
}

impl Composite {
    fn new(
        model: &Model,
        calibration: &[Candidate],
        members: &[&Candidate],
    ) -> Result<Composite, ModelError> {
        let members: Vec<&Candidate> = calibration.iter().chain(members.iter().copied()).collect();
        let members = members.as_slice();
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
        // each member's setters, by index
        let mut blocks = Vec::new();
        for c in members {
            blocks.push(setters.len()..setters.len() + c.setters.len());
            let off = params.len();
            params.extend(c.params.iter().cloned());
            setters.extend(c.setters.iter().map(|s| Setter {
                number: s.number.clone(),
                constant: s.constant,
                terms: s.terms.iter().map(|&(i, k)| (i + off, k)).collect(),
            }));
        }
        // each number resolved once in this model, then written by the fast writes
        let ids = setters
            .iter()
            .map(|s| s.number.resolve(&base))
            .collect::<Result<Vec<_>, _>>()?;
        // A number written twice keeps the later value: a face's absorptivity scale
        // beside the global sunlight scale takes that face out of the global one (its
        // value then relative to nominal), which still scales the others. A member all
        // of whose numbers a later one overwrites would fit parameters that do nothing
        // (and be counted): refused, naming the number.
        let overwritten = |j: usize| ids[j + 1..].iter().any(|later| later.same_number(&ids[j]));
        for b in &blocks {
            if !b.is_empty() && b.clone().all(overwritten) {
                return Err(ModelError::Param(crate::spec::registry::ParamError {
                    key: ids[b.start].canonical_path(),
                    message: "every number of one of the effects or calibration numbers fitted together is set again by another, so its parameters would do nothing".into(),
                }));
            }
        }
        Ok(Composite {
            base,
            params,
            setters,
            ids,
        })
    }

    fn model_at(&self, theta: &[f64]) -> Result<Model, ModelError> {
        let mut m = self.base.clone();
        let values: Vec<_> = self
            .ids
            .iter()
            .zip(&self.setters)
            .map(|(id, s)| (id, s.value(theta)))
            .collect();
        m.set_params(&values)?;
        Ok(m)
    }
}

/// The data a fit needs, shared by every candidate.
pub(super) struct Problem<'a> {
    obs: &'a Observations,
    noise: Vec<f64>,
    /// Times up to the end of the training orbits, and up to the end of the held-out.
    train_times: Arc<[f64]>,
    all_times: Arc<[f64]>,
    /// Step budget of one simulation of the whole recording.
    max_steps: u64,
    /// The tighter budget of a point of a global stage (a grid point or a compass
    /// move): a thermostat that chatters on a light node at a power far too high costs
    /// many short steps and is a poor fit anyway.
    quick_steps: u64,
    /// ln n of the number of training residuals: BIC's price of a parameter.
    ln_n: f64,
    /// The calibration: its candidates, first in every composite (empty: none).
    pub calibration: Vec<Candidate>,
    /// Their values in the calibrated model (where every search starts from).
    pub calibrated: Vec<f64>,
}

impl<'a> Problem<'a> {
    /// The fit problem of `obs` with each channel's `noise`; `baseline_steps` (the
    /// baseline's solver steps) sets the budget of every later simulation.
    pub(super) fn new(obs: &'a Observations, noise: Vec<f64>, baseline_steps: u64) -> Problem<'a> {
        let times_to = |keep: &dyn Fn(f64) -> bool| -> Arc<[f64]> {
            obs.time_s
                .iter()
                .copied()
                .take_while(|&t| keep(t))
                .collect::<Vec<_>>()
                .into()
        };
        let n_train = obs
            .values
            .iter()
            .map(|v| {
                v.iter()
                    .enumerate()
                    .filter(|(j, x)| x.is_some() && obs.part[*j] == Part::Train)
                    .count()
            })
            .sum::<usize>();
        Problem {
            obs,
            noise,
            train_times: times_to(&|t| t < obs.split.train_end_s),
            all_times: times_to(&|t| t <= obs.split.holdout_end_s),
            max_steps: 20 * baseline_steps + 5000,
            quick_steps: 3 * baseline_steps + 500,
            ln_n: (n_train.max(2) as f64).ln(),
            calibration: Vec::new(),
            calibrated: Vec::new(),
        }
    }

    /// ln n of the training residuals: BIC's price of one parameter.
    pub(super) fn ln_n(&self) -> f64 {
        self.ln_n
    }

    /// How many parameters the calibration puts first in every hypothesis.
    pub(super) fn calibration_len(&self) -> usize {
        self.calibrated.len()
    }

    /// Step 3½: the calibration `set` fitted on the training orbits from its nominal
    /// values `nominal`, each with its prior. Kept (and made the start of every later
    /// search) when it lowers the training and the held-out χ² of `reference`; None
    /// otherwise, and the problem keeps no calibration.
    pub(super) fn calibrate(
        &mut self,
        model: &Model,
        set: Vec<Candidate>,
        nominal: Vec<f64>,
        reference: &Reference<'_>,
    ) -> Option<Result<Hypothesis, String>> {
        if set.is_empty() {
            return None;
        }
        self.calibration = set;
        self.calibrated = nominal.clone();
        let h = fit(self, model, &[], &[], &nominal);
        let keep = h.as_ref().is_ok_and(|h| {
            h.train_chi2 < reference.train_chi2 && h.holdout_chi2 < reference.holdout_chi2
        });
        if keep {
            self.calibrated = h.as_ref().expect("kept").theta.clone();
        } else {
            self.calibration.clear();
            self.calibrated.clear();
        }
        Some(h)
    }

    /// Weighted training residuals (recorded − predicted)/noise.
    pub(super) fn train_residuals(&self, pred: &[Vec<f64>]) -> Vec<f64> {
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
    pub(super) fn material(&self, before: &[Vec<f64>], after: &[Vec<f64>]) -> f64 {
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

    pub(super) fn chi2(&self, pred: &[Vec<f64>], part: Part) -> f64 {
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

    pub(super) fn train_residuals_at(
        &self,
        comp: &Composite,
        theta: &[f64],
    ) -> Result<Vec<f64>, String> {
        let m = comp.model_at(theta).map_err(|e| e.to_string())?;
        let pred = self.predict(&m, &self.train_times)?;
        Ok(self.train_residuals(&pred))
    }

    /// The training residuals at `theta` within the global stage's step budget.
    fn quick_residuals_at(&self, comp: &Composite, theta: &[f64]) -> Result<Vec<f64>, String> {
        let m = comp.model_at(theta).map_err(|e| e.to_string())?;
        let pred = predict(&m, &self.train_times, &[], self.quick_steps)
            .map(|p| p.0)
            .map_err(|e| crate::error_chain(&e))?;
        Ok(self.train_residuals(&pred))
    }

    pub(super) fn predict(&self, m: &Model, times: &Arc<[f64]>) -> Result<Vec<Vec<f64>>, String> {
        predict(m, times, &[], self.max_steps)
            .map(|p| p.0)
            .map_err(|e| crate::error_chain(&e))
    }
}

/// A fitted hypothesis (one or more candidates, in the order they were added).
#[derive(Debug, Clone)]
pub(super) struct Hypothesis {
    pub members: Vec<usize>,
    pub theta: Vec<f64>,
    pub fit: lm::LmFit,
    pub train_chi2: f64,
    pub holdout_chi2: f64,
    pub pred: Vec<Vec<f64>>,
    pub model: Model,
    /// How much the training residual's information is below white noise of the
    /// estimated level: s² (its mean square per degree of freedom, the variance
    /// ratio a model error adds) times the AR(1) factor of its correlation in time
    /// ([`correlated_noise_factor`]), at least 1. The covariance carries the same
    /// scale; [`rivals`] compares on it.
    pub noise_scale: f64,
    /// The AR(1) factor alone: n over the effective number of independent samples.
    pub inflation: f64,
}

/// A candidate's ranking: its best training χ² and parameters (None: it could not be
/// simulated), the last error, and the wall time, s.
pub(super) struct Ranking {
    pub best: Option<(f64, Vec<f64>)>,
    /// The change each start point makes to the weighted training residuals (the
    /// calibrated residual minus the residual with the candidate at that point), with
    /// the point: the linear model by which later steps rank the candidate on another
    /// residual without simulating it again.
    pub signatures: Vec<(Vec<f64>, Arc<[f64]>)>,
    /// The runners-up after `best`, best first (distinct points): further starts for a
    /// candidate fitted from several ([`Candidate::multi_start`]).
    pub runners_up: Vec<(f64, Vec<f64>)>,
    pub error: String,
    pub time_s: f64,
}

/// What a hypothesis is judged against: the baseline, or the best single effect when
/// a second effect is tried with it.
pub(super) struct Reference<'p> {
    pub train_chi2: f64,
    pub holdout_chi2: f64,
    pub pred: &'p [Vec<f64>],
}

/// Why a fitted hypothesis is not accepted over its reference.
#[derive(Debug, Clone, Copy)]
pub(super) enum Rejection {
    /// BIC improves by `gain`, not by more than the margin.
    Bic { gain: f64 },
    /// The training orbits improve (BIC by `gain`), the held-out ones by only `drop`.
    Holdout { gain: f64, drop: f64 },
    /// Significant, but no channel's held-out residual drops by enough.
    Immaterial,
    /// The fit left parameter `name` on a bound of its range that is not its null:
    /// the data want a value outside the effect's range, so the effect stands in for
    /// something else.
    Pinned { name: &'static str },
}

impl Rejection {
    /// The reason as the candidate table gives it.
    pub(super) fn reason(self, opts: &Options) -> String {
        match self {
            Rejection::Bic { gain } if gain.is_nan() => format!(
                "BIC not computed (its χ² is not a number); the margin to pass is {:.0}",
                opts.bic_margin
            ),
            Rejection::Bic { gain } if gain > 0.0 => format!(
                "BIC improves by {gain:.1}, not by more than the margin {:.0}",
                opts.bic_margin
            ),
            Rejection::Bic { gain } => format!(
                "BIC does not improve (it rises by {:.1}; the margin to pass is {:.0})",
                -gain, opts.bic_margin
            ),
            Rejection::Holdout { gain, drop } => format!(
                "fits the training orbits (BIC −{gain:.0}) but does not improve \
                 the held-out orbits (χ² drop {drop:.1} ≤ {:.0})",
                opts.holdout_margin
            ),
            Rejection::Pinned { name } => format!(
                "a stand-in: its {name} ends on a bound of its range (the data want a value \
                 outside it, so the effect stands in for something else)"
            ),
            Rejection::Immaterial => format!(
                "significant but immaterial: lowers no channel's held-out mean \
                 square residual by {:.0} % of its noise variance",
                100.0 * opts.min_effect
            ),
        }
    }
}

impl Problem<'_> {
    /// The BIC gain of `h` over a reference with training χ² `chi2_ref`, for the
    /// `k_extra` parameters it adds.
    pub(super) fn bic_gain(&self, h: &Hypothesis, chi2_ref: f64, k_extra: usize) -> f64 {
        chi2_ref - h.train_chi2 - k_extra as f64 * self.ln_n
    }

    /// The one acceptance test, for single effects and pairs alike: `h` (adding
    /// `k_extra` parameters to `reference`) must win BIC by the margin, lower the
    /// held-out χ² by the margin, and be material.
    pub(super) fn judge(
        &self,
        h: &Hypothesis,
        reference: &Reference<'_>,
        c: &Candidate,
        opts: &Options,
    ) -> Result<(), Rejection> {
        let k_extra = c.params.len();
        let gain = self.bic_gain(h, reference.train_chi2, k_extra);
        let drop = reference.holdout_chi2 - h.holdout_chi2;
        // Each test passes only on a number (NaN fails it).
        let wins_bic = gain > opts.bic_margin;
        let improves_holdout = drop > opts.holdout_margin;
        if !wins_bic {
            Err(Rejection::Bic { gain })
        } else if !improves_holdout {
            Err(Rejection::Holdout { gain, drop })
        } else if let Some(name) = pinned(h, c) {
            Err(Rejection::Pinned { name })
        } else if self.material(reference.pred, &h.pred) >= opts.min_effect {
            Ok(())
        } else {
            Err(Rejection::Immaterial)
        }
    }
}

/// The first of candidate `c`'s parameters (the last of `h`'s) that the fit left on a
/// bound of its range as it enters: [`pinned_at`], judged [`Fit::of`] `h`.
pub(super) fn pinned(h: &Hypothesis, c: &Candidate) -> Option<&'static str> {
    pinned_at(
        &h.theta,
        h.theta.len().checked_sub(c.params.len())?,
        c,
        Fit::of(h),
    )
}

/// Which fit a parameter on its floor is judged in ([`Floor::ValueAlone`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Fit {
    /// A candidate fitted alone (beside the calibration).
    Alone,
    /// A fit of two or more findings: an extension entering beside the findings
    /// before it, or the final joint fit.
    Joint,
}

impl Fit {
    /// Alone for a hypothesis of one member, else joint.
    pub(super) fn of(h: &Hypothesis) -> Fit {
        if h.members.len() > 1 {
            Fit::Joint
        } else {
            Fit::Alone
        }
    }
}

/// The first of candidate `c`'s parameters (from `off` in `theta`) on a bound of its
/// range, within its finite-difference step (a bounded fit creeps up to a bound it
/// wants to cross), unless that bound is the parameter's null (a load's power of zero
/// is the effect absent, not a stand-in) or a value the effect takes in `fit`
/// ([`Floor`]).
pub(super) fn pinned_at(
    theta: &[f64],
    off: usize,
    c: &Candidate,
    fit: Fit,
) -> Option<&'static str> {
    c.params.iter().enumerate().find_map(|(i, p)| {
        let v = *theta.get(off + i)?;
        let floor_is_a_value = match p.floor {
            Floor::Bound => false,
            Floor::Value => true,
            Floor::ValueAlone => fit == Fit::Alone,
        };
        let on_floor = v - p.lower <= p.step && !floor_is_a_value;
        let on_ceiling = p.upper - v <= p.step;
        let at_null = c.null.as_ref().is_some_and(|z| (v - z[i]).abs() <= p.step);
        ((on_floor || on_ceiling) && !at_null).then_some(p.name)
    })
}

/// Every point a candidate's start points give (the starts and, for an effect with a
/// null, the best point on each line from it), best first (a stable sort: ties keep the
/// order of the start points), without repeats.
fn ranked_starts(
    problem: &Problem<'_>,
    comp: &Composite,
    c: &Candidate,
    fixed_theta: &[f64],
    r0: &[f64],
) -> StartPoints {
    let mut all: Vec<(f64, Vec<f64>)> = Vec::new();
    let mut signatures = Vec::new();
    let mut err = String::new();
    for s in &c.starts {
        let mut theta = fixed_theta.to_vec();
        theta.extend_from_slice(s);
        match problem.train_residuals_at(comp, &theta) {
            Ok(r1) => {
                for (x2, th) in rank_point(r0, &r1, c, s) {
                    if !x2.is_nan() && !all.iter().any(|(_, t)| *t == th) {
                        all.push((x2, th));
                    }
                }
                let d: Arc<[f64]> = r0.iter().zip(&r1).map(|(a, b)| a - b).collect();
                if d.iter().all(|v| v.is_finite()) {
                    signatures.push((s.clone(), d));
                }
            }
            Err(e) => err = e,
        }
    }
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    StartPoints {
        all,
        signatures,
        error: err,
    }
}

/// What [`ranked_starts`] finds: every point, best first; each simulated start's
/// signature; the last error.
struct StartPoints {
    all: Vec<(f64, Vec<f64>)>,
    signatures: Vec<(Vec<f64>, Arc<[f64]>)>,
    error: String,
}

/// Step 4: every candidate's training χ² at its start points, and along the line
/// from its null through each (the baseline residual `r0` projected on the change it
/// makes). In parallel; results in candidate order.
pub(super) fn rank(
    problem: &Problem<'_>,
    model: &Model,
    cands: &[Candidate],
    r0: &[f64],
    progress: Progress<'_>,
) -> Vec<Ranking> {
    let counter = Counter::new("ranking", cands.len(), progress);
    cands
        .par_iter()
        .map(|c| {
            let t0 = Instant::now();
            let StartPoints {
                mut all,
                signatures,
                error,
            } = match Composite::new(model, &problem.calibration, &[c]) {
                Err(e) => StartPoints {
                    all: Vec::new(),
                    signatures: Vec::new(),
                    error: e.to_string(),
                },
                Ok(comp) => ranked_starts(problem, &comp, c, &problem.calibrated, r0),
            };
            counter.tick();
            let best = if all.is_empty() {
                None
            } else {
                Some(all.remove(0))
            };
            all.truncate(c.multi_start.saturating_sub(1));
            Ranking {
                best,
                signatures,
                runners_up: all,
                error,
                time_s: t0.elapsed().as_secs_f64(),
            }
        })
        .collect()
}

/// Step 5: the candidates `to_fit` fitted from their ranking's best point, in
/// parallel; each result with its wall time, s.
pub(super) fn fit_leading(
    problem: &Problem<'_>,
    model: &Model,
    cands: &[Candidate],
    ranked: &[Ranking],
    to_fit: &[usize],
    progress: Progress<'_>,
) -> Vec<(Result<Hypothesis, String>, f64)> {
    let counter = Counter::new("fitting", to_fit.len(), progress);
    // The global stage for the leading rugged candidates only (`to_fit` is best
    // first): it costs a few hundred runs each.
    let robust: Vec<usize> = to_fit
        .iter()
        .copied()
        .filter(|&i| !cands[i].grid.is_empty())
        .take(GLOBAL_CANDIDATES)
        .collect();
    to_fit
        .par_iter()
        .map(|&i| {
            let t0 = Instant::now();
            // From the best ranked point, and for a candidate whose cost is not smooth
            // in its parameters from the runners-up too: the lowest training χ² wins
            // (the first on a tie).
            let c = &cands[i];
            let best_ranked = ranked[i].best.as_ref().unwrap().clone();
            let mut others: Vec<(f64, Vec<f64>)> = Vec::new();
            if robust.contains(&i)
                && let Ok(comp) = Composite::new(model, &problem.calibration, &[c])
            {
                others = global_stage(
                    problem,
                    &comp,
                    c,
                    best_ranked.clone(),
                    ranked[i].runners_up.clone(),
                );
                others.retain(|o| o.1 != best_ranked.1);
                others.truncate(c.multi_start.saturating_sub(1));
            }
            let starts = std::iter::once(&best_ranked).chain(&others).map(|(_, th)| {
                problem
                    .calibrated
                    .iter()
                    .chain(th)
                    .copied()
                    .collect::<Vec<_>>()
            });
            let starts: Vec<Vec<f64>> = starts.collect();
            let best = if starts.len() > 1 && problem.calibration_len() > 0 {
                // Several starts: each fitted with the calibration held (its own
                // parameters only, the cheap part), the best then fitted jointly.
                let held: Vec<(f64, Vec<f64>)> = starts
                    .par_iter()
                    .filter_map(|s| fit_held(problem, model, cands, &[i], s).ok())
                    .collect();
                let held = held.into_iter().min_by(|a, b| a.0.total_cmp(&b.0));
                let from = held.map_or_else(|| starts[0].clone(), |h| h.1);
                fit(problem, model, cands, &[i], &from)
            } else {
                let mut best: Option<Result<Hypothesis, String>> = None;
                for start in starts {
                    let h = fit(problem, model, cands, &[i], &start);
                    best = match (best, h) {
                        (None, h) => Some(h),
                        (Some(Ok(b)), Ok(h)) if h.train_chi2 < b.train_chi2 => Some(Ok(h)),
                        (Some(Err(_)), Ok(h)) => Some(Ok(h)),
                        (b, _) => b,
                    };
                }
                best.expect("one start at least")
            };
            counter.tick();
            (best, t0.elapsed().as_secs_f64())
        })
        .collect()
}

/// The global stage of a candidate whose cost is rugged (a thermostat): its grid and
/// ranked points evaluated, then each of the best [`GLOBAL_SEEDS`] refined by a compass
/// search (each parameter stepped up and down, steps halved when neither helps), which
/// needs no derivative and so crosses the steps a switching heater puts in the cost.
/// Returns the refined points, best first (LM starts from them).
fn global_stage(
    problem: &Problem<'_>,
    comp: &Composite,
    c: &Candidate,
    best: (f64, Vec<f64>),
    mut points: Vec<(f64, Vec<f64>)>,
) -> Vec<(f64, Vec<f64>)> {
    let cost = |th: &[f64]| {
        let theta: Vec<f64> = problem.calibrated.iter().chain(th).copied().collect();
        problem
            .quick_residuals_at(comp, &theta)
            .map_or(f64::INFINITY, |r| r.iter().map(|v| v * v).sum())
    };
    let mut grid: Vec<(f64, Vec<f64>)> = c.grid.par_iter().map(|g| (cost(g), g.clone())).collect();
    grid.sort_by(|a, b| a.0.total_cmp(&b.0));
    points.push(best);
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Seeds: the best points overall, and the best grid point of each value of the
    // first parameter (a heater's power), so that every basin the grid touches is
    // searched, not only the deepest at its coarse points.
    let mut seeds: Vec<(f64, Vec<f64>)> = Vec::new();
    for p in points
        .into_iter()
        .chain(grid.iter().cloned())
        .take(GLOBAL_SEEDS)
    {
        if !seeds.iter().any(|s| s.1 == p.1) {
            seeds.push(p);
        }
    }
    for g in &grid {
        if !seeds.iter().any(|s| s.1[0] == g.1[0]) {
            seeds.push(g.clone());
        }
    }
    let mut refined: Vec<(f64, Vec<f64>)> = seeds
        .into_par_iter()
        .map(|(x0, th0)| compass(&cost, c, x0, th0))
        .collect();
    refined.sort_by(|a, b| a.0.total_cmp(&b.0));
    refined
}

/// A compass search from `th0` (cost `x0`): each parameter stepped up and down by
/// 15 % (at least 10 finite-difference steps), the first move that helps taken, the
/// steps halved when none does, at most [`COMPASS_EVALUATIONS`] costs.
fn compass(
    cost: &(dyn Fn(&[f64]) -> f64 + Sync),
    c: &Candidate,
    x0: f64,
    th0: Vec<f64>,
) -> (f64, Vec<f64>) {
    let (mut x, mut th) = (x0, th0);
    let mut step: Vec<f64> = th
        .iter()
        .zip(&c.params)
        .map(|(v, p)| (0.15 * v.abs()).max(10.0 * p.step))
        .collect();
    for _ in 0..COMPASS_EVALUATIONS / (2 * th.len()) {
        let mut moved = false;
        for k in 0..th.len() {
            for sign in [1.0, -1.0] {
                let mut t = th.clone();
                t[k] = (t[k] + sign * step[k]).clamp(c.params[k].lower, c.params[k].upper);
                let xt = cost(&t);
                if xt < x {
                    (x, th) = (xt, t);
                    moved = true;
                    break;
                }
            }
        }
        if !moved {
            if step.iter().zip(&c.params).all(|(s, p)| *s <= 2.0 * p.step) {
                break;
            }
            step.iter_mut().for_each(|s| *s *= 0.5);
        }
    }
    (x, th)
}

/// Seeds of the global stage refined by compass search (besides the best grid point
/// of each power), its evaluations per seed, and how many of the fitted candidates
/// get it (the best ranked rugged ones).
const GLOBAL_SEEDS: usize = 2;
const COMPASS_EVALUATIONS: usize = 24;
const GLOBAL_CANDIDATES: usize = 2;

/// One step of forward selection when the accepted effects `current` do not explain
/// the residual: every other candidate ranked again on the residual `current` leaves
/// (its own parameters from its start points, those of `current` held at their fit),
/// the leading `opts.pair_partners` fitted together with `current`, and the best of
/// them that passes [`Problem::judge`] against `current` returned (None: no further
/// effect earns its place).
pub(super) fn best_extension(
    problem: &Problem<'_>,
    model: &Model,
    cands: &[Candidate],
    ranked: &[Ranking],
    current: &Hypothesis,
    opts: &Options,
    progress: Progress<'_>,
) -> (Option<Hypothesis>, Vec<Hypothesis>) {
    let n = current.members.len() + 1;
    let with = |j: usize| -> Vec<usize> {
        let mut m = current.members.clone();
        m.push(j);
        m
    };
    let r_current = problem.train_residuals(&current.pred);
    let stage_rank: &'static str = if n == 2 {
        "pairs: ranking"
    } else {
        "sets: ranking"
    };
    let counter = Counter::new(stage_rank, cands.len(), progress);
    let next: Vec<Option<(f64, Vec<f64>)>> = (0..cands.len())
        .into_par_iter()
        .map(|j| {
            counter.tick();
            if current.members.contains(&j) || ranked[j].best.is_none() {
                return None;
            }
            linear_best(&r_current, &cands[j], &ranked[j].signatures)
        })
        .collect();
    let mut partners: Vec<usize> = (0..cands.len())
        .filter(|&j| next[j].as_ref().is_some_and(|b| b.0 < current.train_chi2))
        .collect();
    partners.sort_by(|&a, &b| {
        let (xa, xb) = (next[a].as_ref().unwrap().0, next[b].as_ref().unwrap().0);
        xa.total_cmp(&xb).then(a.cmp(&b))
    });
    partners.truncate(opts.pair_partners);
    let counter = Counter::new(
        if n == 2 { "pairs" } else { "sets" },
        partners.len(),
        progress,
    );
    let fitted: Vec<Result<Hypothesis, String>> = partners
        .par_iter()
        .map(|&j| {
            let mut start = current.theta.clone();
            start.extend_from_slice(&next[j].as_ref().unwrap().1);
            let r = fit(problem, model, cands, &with(j), &start);
            counter.tick();
            r
        })
        .collect();
    let reference = Reference {
        train_chi2: current.train_chi2,
        holdout_chi2: current.holdout_chi2,
        pred: &current.pred,
    };
    let fitted: Vec<Hypothesis> = fitted.into_iter().flatten().collect();
    let mut best: Option<Hypothesis> = None;
    for h in &fitted {
        let c = &cands[*h.members.last().unwrap()];
        if problem.judge(h, &reference, c, opts).is_ok()
            && best.as_ref().is_none_or(|b| h.train_chi2 < b.train_chi2)
        {
            best = Some(h.clone());
        }
    }
    (best, fitted)
}

/// The rivals of `accepted` among `others` (hypotheses of the same step: the same
/// members but the last): each other last member whose BIC is within
/// [`RIVAL_DELTA_BIC`] of the accepted one's and not [`pinned`] on a bound (`cands`
/// the candidates), with that difference (≥ 0 is worse) and the noise scale it was
/// taken on.
///
/// The BIC is taken on the accepted fit's own noise scale (a quasi-likelihood BIC:
/// χ² / [`Hypothesis::noise_scale`] + k ln n_eff, n_eff = n / AR(1) factor), the
/// scale its intervals carry. On synthetic data with white noise of the stated level
/// this is the plain BIC; on flight data, where the model's own error dominates the
/// residual and persists from sample to sample, a χ² difference of a few tens is
/// within what that error moves, and the plain BIC would call two rivals distinct
/// that the data cannot tell apart (FUNcube-1: 0.8 W switched on the stack or the
/// chassis, 0.4 % apart in χ²).
pub(super) fn rivals(
    problem: &Problem<'_>,
    cands: &[Candidate],
    accepted: &Hypothesis,
    others: &[&Hypothesis],
) -> Vec<(usize, f64, f64)> {
    let bic = |h: &Hypothesis| {
        quasi_bic(
            h.train_chi2,
            h.theta.len(),
            accepted.noise_scale,
            accepted.inflation,
            problem.ln_n,
        )
    };
    let last = *accepted.members.last().expect("a member");
    let mut out: Vec<(usize, f64, f64)> = others
        .iter()
        .filter(|o| o.members.last() != Some(&last))
        // a stand-in (a parameter on a bound) is no alternative to a finding
        .filter(|o| pinned(o, &cands[*o.members.last().expect("a member")]).is_none())
        .map(|o| {
            (
                *o.members.last().expect("a member"),
                bic(o) - bic(accepted),
                accepted.noise_scale,
            )
        })
        .filter(|(_, d, _)| *d <= RIVAL_DELTA_BIC)
        .collect();
    out.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    out
}

/// BIC on a noise scale: χ² / `noise_scale` + k ln(n / `inflation`), n = e^`ln_n` the
/// training samples and n / `inflation` the effectively independent ones (the plain
/// BIC χ² + k ln n when both are 1).
fn quasi_bic(chi2: f64, k: usize, noise_scale: f64, inflation: f64, ln_n: f64) -> f64 {
    chi2 / noise_scale + k as f64 * (ln_n - inflation.ln()).max(0.0)
}

/// Alternatives within this BIC of a finding "explain about as well" (Kass & Raftery:
/// a difference under 2 is not worth more than a bare mention).
pub(super) const RIVAL_DELTA_BIC: f64 = 2.0;

/// The best point of candidate `c` on the residual `r` by the linear model of its
/// `signatures` (the change each start point made to the calibrated residual): its
/// start points and, for an effect with a null, the best point on each line from the
/// null; no simulation. Ranks the candidates of a later step of forward selection,
/// which are then fitted properly.
fn linear_best(
    r: &[f64],
    c: &Candidate,
    signatures: &[(Vec<f64>, Arc<[f64]>)],
) -> Option<(f64, Vec<f64>)> {
    let mut best: Option<(f64, Vec<f64>)> = None;
    for (s, d) in signatures {
        if d.len() != r.len() {
            continue;
        }
        let r1: Vec<f64> = r.iter().zip(d.iter()).map(|(a, b)| a - b).collect();
        for (x2, th) in rank_point(r, &r1, c, s) {
            if !x2.is_nan() && best.as_ref().is_none_or(|b| x2 < b.0) {
                best = Some((x2, th));
            }
        }
    }
    best
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

/// Fits the parameters of `members` from `start` with the calibration's (the first
/// [`Problem::calibration_len`]) held at their values in `start`: the training cost
/// (priors included) and the whole parameter vector reached.
fn fit_held(
    problem: &Problem<'_>,
    model: &Model,
    cands: &[Candidate],
    members: &[usize],
    start: &[f64],
) -> Result<(f64, Vec<f64>), String> {
    let refs: Vec<&Candidate> = members.iter().map(|&i| &cands[i]).collect();
    let comp = Composite::new(model, &problem.calibration, &refs).map_err(|e| e.to_string())?;
    let held = problem.calibration_len();
    let free = &comp.params[held..];
    let lower: Vec<f64> = free.iter().map(|p| p.lower).collect();
    let upper: Vec<f64> = free.iter().map(|p| p.upper).collect();
    let steps: Vec<f64> = free.iter().map(|p| p.step).collect();
    let whole = |x: &[f64]| -> Vec<f64> { start[..held].iter().chain(x).copied().collect() };
    let f = |x: &[f64]| problem.train_residuals_at(&comp, &whole(x));
    let fit = lm::minimize(f, &start[held..], &lower, &upper, &steps, FIT_OPTIONS)?;
    Ok((fit.sum_squares, whole(&fit.x)))
}

/// The stopping rules of every fit of the search.
const FIT_OPTIONS: lm::LmOptions = lm::LmOptions {
    max_iterations: 40,
    ftol: 1e-6,
    xtol: 1e-4,
    cost_floor: 0.0,
};

/// How much wider the parameters' errors are than white noise would make them, when
/// the residuals `r` (one channel after another, in time order) are correlated from
/// one sample to the next: (1 + ρ₁)/(1 − ρ₁) for their lag-1 autocorrelation ρ₁ (an
/// AR(1) residual: the effective number of independent samples is n (1 − ρ₁)/(1 + ρ₁)),
/// 1 when ρ₁ ≤ 0, at most 400 (ρ₁ capped at 0.995).
pub(super) fn correlated_noise_factor(r: &[f64]) -> f64 {
    if r.len() < 3 {
        return 1.0;
    }
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let var: f64 = r.iter().map(|v| (v - mean).powi(2)).sum();
    let lag: f64 = r.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)).sum();
    if var.is_nan() || var <= 0.0 {
        return 1.0;
    }
    let rho = (lag / var).clamp(0.0, 0.995);
    (1.0 + rho) / (1.0 - rho)
}

/// Fits `members` together from `start` on the training orbits, then predicts the
/// held-out orbits. Its covariance is widened for residuals correlated in time
/// ([`correlated_noise_factor`]).
pub(super) fn fit(
    problem: &Problem<'_>,
    model: &Model,
    cands: &[Candidate],
    members: &[usize],
    start: &[f64],
) -> Result<Hypothesis, String> {
    let refs: Vec<&Candidate> = members.iter().map(|&i| &cands[i]).collect();
    let comp = Composite::new(model, &problem.calibration, &refs).map_err(|e| e.to_string())?;
    let lower: Vec<f64> = comp.params.iter().map(|p| p.lower).collect();
    let upper: Vec<f64> = comp.params.iter().map(|p| p.upper).collect();
    let steps: Vec<f64> = comp.params.iter().map(|p| p.step).collect();
    // A calibration number's prior toward its nominal value: one more residual each.
    let priors: Vec<(usize, f64, f64)> = comp
        .params
        .iter()
        .enumerate()
        .filter_map(|(i, p)| p.prior.map(|(c, sd)| (i, c, sd)))
        .collect();
    let f = |theta: &[f64]| -> Result<Vec<f64>, String> {
        let m = comp.model_at(theta).map_err(|e| e.to_string())?;
        let pred = problem.predict(&m, &problem.train_times)?;
        let mut r = problem.train_residuals(&pred);
        r.extend(priors.iter().map(|&(i, c, sd)| (theta[i] - c) / sd));
        Ok(r)
    };
    let mut fit = lm::minimize(f, start, &lower, &upper, &steps, FIT_OPTIONS)?;
    let data = fit.residuals.len() - priors.len();
    let inflation = correlated_noise_factor(&fit.residuals[..data]);
    if let Some(c) = fit.covariance.as_mut() {
        *c *= inflation;
    }
    let dof = data.saturating_sub(start.len()).max(1) as f64;
    let s2 = fit.residuals[..data].iter().map(|v| v * v).sum::<f64>() / dof;
    let noise_scale = (s2 * inflation).max(1.0);
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
        noise_scale,
        inflation,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every candidate of FUNcube-1 composes with its calibration (a face's α scale
    /// takes its face out of the global sunlight scale, which keeps the others), and a
    /// composite in which one member's every number is written again by another is
    /// refused, naming it, instead of fitting parameters that do nothing.
    #[test]
    fn core_one_number_is_written_by_one_setter() {
        use super::super::effects::fixtures::{funcube_text, model_and_channels};
        use super::super::effects::{Hints, calibration_set, candidates};
        let (model, channels) = model_and_channels(&funcube_text(""));
        let mut cands = candidates(&model, &channels, &Hints::default());
        let (set, _) = calibration_set(&model, &mut cands);
        assert!(!set.is_empty() && cands.len() > 50);
        for c in &cands {
            if let Err(e) = Composite::new(&model, &set, &[c]) {
                panic!("{}: {e}", c.label());
            }
        }
        let scale = cands
            .iter()
            .find(|c| c.effect == super::super::effects::Effect::ConductanceScale)
            .expect("a conductance scale");
        let e = Composite::new(&model, &set, &[scale, scale])
            .err()
            .expect("one number twice");
        assert!(e.to_string().contains("set again by another"), "{e}");
    }

    fn candidate(params: Vec<ParamDef>, null: Option<Vec<f64>>) -> Candidate {
        Candidate {
            effect: super::super::effects::Effect::CapacitanceScale,
            target: super::super::effects::Target::Node("stack".into()),
            params,
            setters: Vec::new(),
            starts: Vec::new(),
            null,
            edits: Vec::new(),
            multi_start: 1,
            grid: Vec::new(),
        }
    }

    /// A fit that ends on a bound of a parameter's range (within its step) is a
    /// stand-in; not when the bound is the parameter's null (the effect absent) or a
    /// floor the effect takes (no interference; a thermostat's smallest hysteresis
    /// alone, not beside other findings).
    /// The candidate's parameters are found from their offset, after the
    /// calibration's.
    #[test]
    fn core_a_parameter_on_a_bound_of_its_range_is_a_stand_in() {
        let scale = candidate(
            vec![ParamDef::new("scale", 0.2, 5.0, 0.003)],
            Some(vec![1.0]),
        );
        let alone = |t: &[f64], off, c| pinned_at(t, off, c, Fit::Alone);
        let joint = |t: &[f64], off, c| pinned_at(t, off, c, Fit::Joint);
        assert_eq!(alone(&[0.2, 0.2], 1, &scale), Some("scale"));
        assert_eq!(alone(&[0.7, 0.2025], 1, &scale), Some("scale"));
        assert_eq!(alone(&[0.7, 4.999], 1, &scale), Some("scale"));
        assert_eq!(alone(&[0.2, 0.25], 1, &scale), None);
        assert_eq!(joint(&[0.2, 0.2], 1, &scale), Some("scale"));
        let heater = candidate(
            vec![
                ParamDef::new("power_w", 0.0, 1000.0, 0.02),
                ParamDef::new("on_c", -30.0, 30.0, 0.05),
                ParamDef::new("hysteresis_k", 0.1, 50.0, 0.05).floored_alone(),
            ],
            Some(vec![0.0, 0.0, 5.0]),
        );
        // no power is the effect absent; the smallest hysteresis a proportional heater
        // alone, a stand-in beside other findings
        assert_eq!(alone(&[0.0, -6.0, 0.1], 0, &heater), None);
        assert_eq!(alone(&[2.0, -6.0, 0.1], 0, &heater), None);
        assert_eq!(joint(&[2.0, -6.0, 0.1], 0, &heater), Some("hysteresis_k"));
        assert_eq!(joint(&[0.0, -6.0, 5.0], 0, &heater), None);
        assert_eq!(joint(&[2.0, -6.0, 3.0], 0, &heater), None);
        assert_eq!(alone(&[2.0, -30.0, 3.0], 0, &heater), Some("on_c"));
        assert_eq!(alone(&[2.0, -6.0, 50.0], 0, &heater), Some("hysteresis_k"));
        assert_eq!(alone(&[1000.0, -6.0, 3.0], 0, &heater), Some("power_w"));
        // no null, but a floor the effect takes: a bore fit of no interference
        let bore = candidate(
            vec![ParamDef::new("interference_um", 0.0, 500.0, 0.2).floored()],
            None,
        );
        assert_eq!(alone(&[0.0], 0, &bore), None);
        assert_eq!(joint(&[0.0], 0, &bore), None);
        assert_eq!(alone(&[500.0], 0, &bore), Some("interference_um"));
    }

    /// The quasi-likelihood BIC by which rivals are compared: the plain BIC on white
    /// noise of the stated level, and on a residual with s² = 2.8 and AR(1) factor 3
    /// (FUNcube-1's) a χ² difference of 19 between two one-parameter fits is 2.26,
    /// and one more parameter costs ln(n/3).
    #[test]
    fn val_closed_form_quasi_bic() {
        let ln_n = (6700.0f64).ln();
        assert_eq!(quasi_bic(100.0, 2, 1.0, 1.0, ln_n), 100.0 + 2.0 * ln_n);
        let scale = 2.8 * 3.0;
        let d = quasi_bic(18_907.0, 1, scale, 3.0, ln_n) - quasi_bic(18_888.0, 1, scale, 3.0, ln_n);
        assert!((d - 19.0 / 8.4).abs() < 1e-9, "{d}");
        let k = quasi_bic(0.0, 2, scale, 3.0, ln_n) - quasi_bic(0.0, 1, scale, 3.0, ln_n);
        assert!((k - (6700.0f64 / 3.0).ln()).abs() < 1e-9, "{k}");
    }

    /// A deterministic AR(1) series x_k = ρ x_{k-1} + e_k (e from a fixed LCG, uniform):
    /// the factor is (1 + ρ)/(1 − ρ) within sampling error; white noise gives ≈ 1.
    #[test]
    fn val_closed_form_ar1_noise_factor() {
        let mut state: u64 = 12345;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let series = |rho: f64, u: &mut dyn FnMut() -> f64| -> Vec<f64> {
            let mut x = 0.0;
            (0..200_000)
                .map(|_| {
                    x = rho * x + u();
                    x
                })
                .collect()
        };
        let white = correlated_noise_factor(&series(0.0, &mut uniform));
        assert!((white - 1.0).abs() < 0.02, "{white}");
        let ar = correlated_noise_factor(&series(0.8, &mut uniform));
        assert!((ar - 9.0).abs() < 0.3, "{ar}");
        // anticorrelated residuals do not narrow the errors; short ones are left alone
        let alternating: Vec<f64> = (0..100)
            .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        assert_eq!(correlated_noise_factor(&alternating), 1.0);
        assert_eq!(correlated_noise_factor(&[1.0, 2.0]), 1.0);
    }
}

//! Run summaries computed as an observer: per-node min/max/mean over the last orbit
//! (or the whole run when it is shorter), using the solver's cubic interpolant so that
//! extremes between steps are not missed.

use crate::gear::MeshState;
use crate::run::sample::{Cadence, Sample, Sampler, Want};
use crate::run::sim::{Event, EventKind, Observer, ObserverResult, RunStart, StepView};

#[derive(Debug, Clone, PartialEq)]
pub struct NodeStats {
    pub name: String,
    pub min_k: f64,
    pub max_k: f64,
    pub mean_k: f64,
}

/// Collects [`NodeStats`] over the window [t_end − window_s, t_end].
#[derive(Debug, Clone, Default)]
pub struct WindowStats {
    window_s: f64,
    start_s: f64,
    names: Vec<String>,
    min_k: Vec<f64>,
    max_k: Vec<f64>,
    integral_ks: Vec<f64>,
    covered_s: f64,
    /// Every node's temperature where the window meets the step and at the middle of
    /// what of the step is in the window (scratch, one evaluation of the basis each).
    at_start_k: Vec<f64>,
    at_middle_k: Vec<f64>,
}

impl WindowStats {
    /// Statistics over the last `window_s` seconds of the run.
    pub fn last(window_s: f64) -> WindowStats {
        WindowStats {
            window_s,
            ..Default::default()
        }
    }

    pub fn window_start_s(&self) -> f64 {
        self.start_s
    }

    pub fn nodes(&self) -> Vec<NodeStats> {
        (0..self.names.len())
            .map(|i| NodeStats {
                name: self.names[i].clone(),
                min_k: self.min_k[i],
                max_k: self.max_k[i],
                mean_k: self.integral_ks[i] / self.covered_s.max(1e-300),
            })
            .collect()
    }

    fn see(&mut self, i: usize, v: f64) {
        self.min_k[i] = self.min_k[i].min(v);
        self.max_k[i] = self.max_k[i].max(v);
    }
}

impl Observer for WindowStats {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        let temps_k = r.temps_k;
        let n = temps_k.len();
        self.names = r
            .model
            .network
            .nodes
            .iter()
            .map(|n| n.name.clone())
            .collect();
        self.start_s = (r.t_end_s - self.window_s).max(r.t_start_s);
        self.min_k = vec![f64::INFINITY; n];
        self.max_k = vec![f64::NEG_INFINITY; n];
        self.integral_ks = vec![0.0; n];
        self.covered_s = 0.0;
        if self.start_s == r.t_start_s {
            for (i, &t) in temps_k.iter().enumerate() {
                self.see(i, t);
            }
        }
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let (t0, t1) = (step.t0_s(), step.t1_s());
        if t1 <= self.start_s {
            return Ok(());
        }
        let a = t0.max(self.start_s);
        let d = step.data;
        self.covered_s += t1 - a;
        let n = self.names.len();
        let sa = (a - t0) / d.h_s;
        self.at_start_k.resize(n, 0.0);
        self.at_middle_k.resize(n, 0.0);
        d.temperatures_at_fraction(sa, &mut self.at_start_k);
        d.temperatures_at_fraction(0.5 * (sa + 1.0), &mut self.at_middle_k);
        for i in 0..n {
            let (ya, mid, y1) = (self.at_start_k[i], self.at_middle_k[i], d.temps1_k[i]);
            self.see(i, ya);
            self.see(i, y1);
            if sa == 0.0 {
                for (_, v) in d.interior_extrema(i).into_iter().flatten() {
                    self.see(i, v);
                }
            } else {
                for k in 1..32 {
                    self.see(
                        i,
                        d.temperature_at_fraction(i, sa + (1.0 - sa) * k as f64 / 32.0),
                    );
                }
            }
            // Simpson's rule is exact for the cubic interpolant.
            self.integral_ks[i] += (t1 - a) / 6.0 * (ya + 4.0 * mid + y1);
        }
        Ok(())
    }
}

/// Records every node's temperature at fixed times k·`interval_s` (k = 0, 1, …),
/// from the solver's cubic interpolant. For comparisons between runs.
#[derive(Debug, Clone)]
pub struct Samples {
    pub interval_s: f64,
    pub times_s: Vec<f64>,
    /// One row per time, one column per node, K.
    pub temps_k: Vec<Vec<f64>>,
    sampler: Sampler,
}

impl Samples {
    pub fn every(interval_s: f64) -> Samples {
        Samples {
            interval_s,
            times_s: vec![],
            temps_k: vec![],
            sampler: Sampler::new(Cadence::Interval(interval_s), Want::TEMPERATURES),
        }
    }

    /// Largest |difference| between two sample sets over common rows, K.
    pub fn max_abs_diff_k(&self, other: &Samples) -> f64 {
        self.temps_k
            .iter()
            .zip(&other.temps_k)
            .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
            .fold(0.0, f64::max)
    }
}

impl Observer for Samples {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        self.sampler = Sampler::new(Cadence::Interval(self.interval_s), Want::TEMPERATURES);
        self.times_s.clear();
        self.temps_k.clear();
        if let Some(s) = self.sampler.start(r) {
            self.times_s.push(s.t_s);
            self.temps_k.push(s.temperatures_k.clone());
        }
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let (times, temps) = (&mut self.times_s, &mut self.temps_k);
        self.sampler.each(step, |s| {
            times.push(s.t_s);
            temps.push(s.temperatures_k.clone());
            Ok(())
        })
    }
}

/// Extremes of one gear pair's backlash over a window of the run.
#[derive(Debug, Clone, PartialEq)]
pub struct PairStats {
    pub name: String,
    /// Smallest exact backlash and when it happened.
    pub min_exact_m: f64,
    pub t_min_s: f64,
    pub max_exact_m: f64,
    pub t_max_s: f64,
    pub min_closed_form_m: f64,
    pub max_closed_form_m: f64,
    pub min_paper_m: f64,
    pub max_paper_m: f64,
    pub min_margin_m: f64,
    /// Times backlash reached zero / fell below the minimum allowed.
    pub interference_events: u64,
    pub margin_events: u64,
    /// Samples with no valid mesh, and the first time one was seen.
    pub invalid_samples: u64,
    pub t_first_invalid_s: f64,
}

/// The verdict of a whole analysis (a run, a margins report, a pair's margin):
/// serialised as "pass" / "fail", and what decides the exit status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PassFail {
    Pass,
    Fail,
}

impl PassFail {
    /// Pass when every one of `passes` is true (an empty list passes).
    pub fn all(passes: impl IntoIterator<Item = bool>) -> PassFail {
        if passes.into_iter().all(|p| p) {
            PassFail::Pass
        } else {
            PassFail::Fail
        }
    }

    pub fn passes(self) -> bool {
        self == PassFail::Pass
    }

    /// "pass" or "fail", as serialised.
    pub fn as_str(self) -> &'static str {
        match self {
            PassFail::Pass => "pass",
            PassFail::Fail => "fail",
        }
    }
}

/// Whether a gear pair kept its minimum backlash. Serialised as "pass",
/// "margin_violated", "interference" or "no_valid_mesh".
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PairVerdict {
    /// The exact backlash stayed at or above the minimum allowed.
    Pass,
    /// The backlash fell below the minimum allowed (but stayed positive).
    MarginViolated,
    /// The teeth interfere: backlash reached zero.
    Interference,
    /// No valid mesh at some time (base circles overlap or contact lost).
    NoValidMesh,
}

impl PairVerdict {
    pub fn passes(self) -> bool {
        self == PairVerdict::Pass
    }
}

impl PairStats {
    fn new(name: &str) -> PairStats {
        PairStats {
            name: name.to_string(),
            min_exact_m: f64::INFINITY,
            t_min_s: f64::NAN,
            max_exact_m: f64::NEG_INFINITY,
            t_max_s: f64::NAN,
            min_closed_form_m: f64::INFINITY,
            max_closed_form_m: f64::NEG_INFINITY,
            min_paper_m: f64::INFINITY,
            max_paper_m: f64::NEG_INFINITY,
            min_margin_m: f64::INFINITY,
            interference_events: 0,
            margin_events: 0,
            invalid_samples: 0,
            t_first_invalid_s: f64::NAN,
        }
    }

    /// The verdict over the samples seen (the worst of them).
    pub fn verdict(&self) -> PairVerdict {
        if self.invalid_samples > 0 {
            PairVerdict::NoValidMesh
        } else if self.min_exact_m <= 0.0 || self.interference_events > 0 {
            PairVerdict::Interference
        } else if self.min_margin_m < 0.0 || self.margin_events > 0 {
            PairVerdict::MarginViolated
        } else {
            PairVerdict::Pass
        }
    }

    fn see(&mut self, t_s: f64, m: &MeshState) {
        if m.backlash_exact_m.is_nan() {
            if self.invalid_samples == 0 {
                self.t_first_invalid_s = t_s;
            }
            self.invalid_samples += 1;
            return;
        }
        if m.backlash_exact_m < self.min_exact_m {
            self.min_exact_m = m.backlash_exact_m;
            self.t_min_s = t_s;
        }
        if m.backlash_exact_m > self.max_exact_m {
            self.max_exact_m = m.backlash_exact_m;
            self.t_max_s = t_s;
        }
        self.min_closed_form_m = self.min_closed_form_m.min(m.backlash_closed_form_m);
        self.max_closed_form_m = self.max_closed_form_m.max(m.backlash_closed_form_m);
        self.min_paper_m = self.min_paper_m.min(m.backlash_paper_m);
        self.max_paper_m = self.max_paper_m.max(m.backlash_paper_m);
        self.min_margin_m = self.min_margin_m.min(m.margin_m);
    }
}

/// Backlash extremes of every gear pair over the whole run (`run_pairs`) and over its
/// last `window_s` (`pairs`), from the same evaluations. Each step is evaluated at its
/// ends. Where the backlash may turn inside the step, it is also evaluated at three
/// interior points of the solver's interpolant, and an interior minimum is refined by
/// golden-section search, so minima between long steps are not missed.
///
/// "May turn" is decided from the backlash and its rate at both ends (the rate along
/// the temperature path's tangent, by a one-sided difference over a thousandth of the
/// step; the end rate is reused as the next step's start rate when the path's tangent
/// there is the same): unless both rates have the sign of the change over the step, by
/// a clear margin, and their cubic has no interior extremum, the step is probed. A
/// step skipped is monotone, so its extremes are at its ends, which are seen anyway.
#[derive(Debug, Clone, Default)]
pub struct MeshStats {
    window_s: f64,
    start_s: f64,
    pub pairs: Vec<PairStats>,
    pub run_pairs: Vec<PairStats>,
    /// Exact, closed-form and paper backlash at the end of the previous step, per pair.
    last_tracked_m: Vec<[f64; 3]>,
    /// The previous step's end: its time, the temperature path's tangent there
    /// (K/s per node) and each pair's rates of the tracked backlash along it (m/s;
    /// NaN: unknown).
    edge_t_s: f64,
    edge_rates_k_per_s: Vec<f64>,
    edge_slope_m_per_s: Vec<[f64; 3]>,
    /// This step's start tangent (scratch).
    start_rates_k_per_s: Vec<f64>,
    /// Steps probed and skipped (for the record and the tests).
    pub probed_steps: u64,
    pub skipped_steps: u64,
    /// Probe every step (the reference the skipping is tested against).
    always_probe: bool,
}

/// The difference step of the backlash rate, as a fraction of the solver step.
const SLOPE_STEP_FRACTION: f64 = 1e-3;
/// A step is skipped only when each end's rate, times the step, is at least this
/// fraction of the change over the step.
const SLOPE_MARGIN: f64 = 0.05;

impl MeshStats {
    pub fn last(window_s: f64) -> MeshStats {
        MeshStats {
            window_s,
            ..Default::default()
        }
    }

    /// The same statistics with every step probed: slower, and the reference that
    /// skipping monotone steps must reproduce bit for bit.
    pub fn probing_every_step(self) -> MeshStats {
        MeshStats {
            always_probe: true,
            ..self
        }
    }

    pub fn window_start_s(&self) -> f64 {
        self.start_s
    }

    /// Pair `k` lost its mesh for the first time within a step probed at `times` with
    /// exact backlash `values`: where, to the millisecond (bisected on `lost` between
    /// the last point that meshes and the first that does not), not at the first
    /// quarter point or step end that saw it. Nothing when the step starts without it.
    fn refine_first_loss(
        &mut self,
        k: usize,
        times: &[f64; 5],
        values: &[f64; 5],
        lost: impl Fn(f64) -> bool,
    ) {
        if values[0].is_nan() {
            return;
        }
        let Some(j) = (1..5).find(|&j| values[j].is_nan()) else {
            return;
        };
        let (mut lo, mut hi) = (times[j - 1], times[j]);
        while hi - lo > MIN_TIME_TOLERANCE_S {
            let mid = 0.5 * (lo + hi);
            if lost(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        self.run_pairs[k].t_first_invalid_s = hi;
        if hi >= self.start_s && self.pairs[k].invalid_samples > 0 {
            let w = &mut self.pairs[k].t_first_invalid_s;
            *w = w.min(hi);
        }
    }

    fn see(&mut self, k: usize, t_s: f64, m: &MeshState) {
        self.run_pairs[k].see(t_s, m);
        if t_s >= self.start_s {
            self.pairs[k].see(t_s, m);
        }
    }
}

/// Each pair's sample at the run's smallest backlash so far, held while steps keep
/// lowering it and let go (once) when a step no longer does: what a log or table adds
/// to its cadence so that it holds the run's own minimum, one extra row per descent,
/// not per step.
#[derive(Debug, Clone, Default)]
pub struct SmallestSamples {
    /// The pair statistics the smallest values come from.
    pub mesh: MeshStats,
    held: Vec<Option<Sample>>,
    /// Each pair's `t_min_s` before the step (scratch).
    t_min_before: Vec<f64>,
}

impl SmallestSamples {
    pub fn new(mesh: MeshStats) -> SmallestSamples {
        SmallestSamples {
            mesh,
            ..Default::default()
        }
    }

    pub fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        self.mesh.on_start(r)?;
        self.held = vec![None; r.gears.len()];
        Ok(())
    }

    /// Sees `step`: a pair's new smallest within it is sampled and held (replacing
    /// the one held), a held sample the step did not lower is handed to `release`.
    pub fn on_step(
        &mut self,
        step: &StepView<'_>,
        mut release: impl FnMut(&Sample),
    ) -> ObserverResult {
        self.t_min_before.clear();
        self.t_min_before
            .extend(self.mesh.run_pairs.iter().map(|p| p.t_min_s));
        self.mesh.on_step(step)?;
        for k in 0..self.held.len() {
            let t_min = self.mesh.run_pairs[k].t_min_s;
            if t_min.to_bits() != self.t_min_before[k].to_bits() {
                let s = self.held[k].get_or_insert_with(Sample::default);
                if t_min == step.t1_s() {
                    step.sample_end(Want::ALL, s);
                } else {
                    step.sample_at(t_min, Want::ALL, s);
                }
            } else if let Some(s) = self.held[k].take() {
                release(&s);
            }
        }
        Ok(())
    }

    /// Hands every held sample to `release`.
    pub fn release_all(&mut self, mut release: impl FnMut(&Sample)) {
        for h in &mut self.held {
            if let Some(s) = h.take() {
                release(&s);
            }
        }
    }

    /// The earliest time a sample is held at, s (infinite when none is).
    pub fn earliest_held_s(&self) -> f64 {
        self.held
            .iter()
            .flatten()
            .map(|s| s.t_s)
            .fold(f64::INFINITY, f64::min)
    }
}

impl Observer for MeshStats {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        self.start_s = (r.t_end_s - self.window_s).max(r.t_start_s);
        self.pairs = r.gears.iter().map(|g| PairStats::new(&g.name)).collect();
        self.run_pairs = self.pairs.clone();
        self.edge_t_s = f64::NAN;
        self.last_tracked_m = r.mesh.iter().map(tracked).collect();
        self.edge_slope_m_per_s = vec![[f64::NAN; 3]; r.mesh.len()];
        for k in 0..self.pairs.len() {
            self.see(k, r.t_start_s, &r.mesh[k]);
        }
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let (t0, t1) = (step.t0_s(), step.t1_s());
        let h = t1 - t0;
        let d = step.data;
        let n = d.temps1_k.len();
        // The path's tangents at the step's ends: the solver's rates unless a node
        // is interpolated by its quadratic.
        let plain = !d.quadratic.contains(&true);
        let mut scratch = std::mem::take(&mut self.start_rates_k_per_s);
        let start_rates: &[f64] = if plain {
            &d.rates0_k_per_s
        } else {
            scratch.clear();
            scratch.extend((0..n).map(|i| d.rate_at_edge(i, false)));
            &scratch
        };
        let same_start = t0 == self.edge_t_s && start_rates == &self.edge_rates_k_per_s[..];
        self.edge_rates_k_per_s.clear();
        if plain {
            self.edge_rates_k_per_s.extend_from_slice(&d.rates1_k_per_s);
        } else {
            self.edge_rates_k_per_s
                .extend((0..n).map(|i| d.rate_at_edge(i, true)));
        }
        self.edge_t_s = t1;
        let dt = SLOPE_STEP_FRACTION * h;
        for k in 0..step.mesh.len() {
            let at = |t: f64| step.probe.mesh_at(step, k, t);
            // The window's first instant, when this step straddles it.
            if t0 < self.start_s && self.start_s < t1 {
                let m = at(self.start_s);
                self.pairs[k].see(self.start_s, &m);
            }
            let (b0, b1) = (self.last_tracked_m[k], tracked(&step.mesh[k]));
            self.last_tracked_m[k] = b1;
            let slope0 = if same_start {
                self.edge_slope_m_per_s[k]
            } else {
                let m = step.probe.mesh_along(k, &d.temps0_k, start_rates, dt);
                let ahead = tracked(&m);
                std::array::from_fn(|q| (ahead[q] - b0[q]) / dt)
            };
            let back = tracked(&step.probe.mesh_along(
                k,
                &d.temps1_k,
                &self.edge_rates_k_per_s,
                -dt,
            ));
            let slope1: [f64; 3] = std::array::from_fn(|q| (b1[q] - back[q]) / dt);
            self.edge_slope_m_per_s[k] = slope1;
            // The paper model's values are NaN throughout when it is off.
            let skip = (0..3).all(|q| {
                (q == 2 && b0[q].is_nan() && b1[q].is_nan())
                    || monotone(b0[q], b1[q], slope0[q], slope1[q], h)
            });
            if skip && !self.always_probe {
                self.skipped_steps += 1;
                self.see(k, t1, &step.mesh[k]);
                continue;
            }
            self.probed_steps += 1;
            let had_lost = self.run_pairs[k].invalid_samples > 0;
            let ts = [t0, t0 + 0.25 * h, t0 + 0.5 * h, t0 + 0.75 * h];
            let mut values = [b0[0], 0.0, 0.0, 0.0, b1[0]];
            for i in 1..4 {
                let m = at(ts[i]);
                values[i] = m.backlash_exact_m;
                self.see(k, ts[i], &m);
            }
            self.see(k, t1, &step.mesh[k]);
            if !had_lost && self.run_pairs[k].invalid_samples > 0 {
                let times = [t0, ts[1], ts[2], ts[3], t1];
                self.refine_first_loss(k, &times, &values, |t| at(t).backlash_exact_m.is_nan());
            }
            // Golden-section refinement around an interior minimum.
            let i = (1..4)
                .min_by(|&x, &y| values[x].total_cmp(&values[y]))
                .unwrap_or(2);
            // Around an interior minimum: the smallest quarter point, or an end that
            // is smallest while the path leaves it downwards (a dip within the first
            // or last quarter).
            let bracket = if values[i] < values[0] && values[i] < values[4] {
                Some((ts[i - 1], if i + 1 < 4 { ts[i + 1] } else { t1 }))
            } else if values[0] <= values[4] && slope0[0] < 0.0 {
                Some((t0, ts[1]))
            } else if values[4] < values[0] && slope1[0] > 0.0 {
                Some((ts[3], t1))
            } else {
                None
            };
            if let Some((lo, hi)) = bracket {
                crate::numeric::golden_section(lo, hi, MIN_TIME_TOLERANCE_S, &mut |t| {
                    let m = at(t);
                    self.see(k, t, &m);
                    m.backlash_exact_m
                });
            }
        }
        self.start_rates_k_per_s = scratch;
        Ok(())
    }

    fn on_event(&mut self, e: &Event) -> ObserverResult {
        let in_window = e.t_s >= self.start_s;
        match e.kind {
            EventKind::InterferenceStart(k) => {
                self.run_pairs[k].interference_events += 1;
                self.pairs[k].interference_events += u64::from(in_window);
            }
            EventKind::MarginLow(k) => {
                self.run_pairs[k].margin_events += 1;
                self.pairs[k].margin_events += u64::from(in_window);
            }
            _ => {}
        }
        Ok(())
    }
}

/// How closely a step's interior smallest backlash is located in time, s: to the
/// millisecond, so that no sample of the path between the step's ends lies below the
/// run's smallest (on a periodic run, successive orbits' minima differ by
/// micrometres' millionths, and which is the smallest must not depend on how the
/// search was cut).
const MIN_TIME_TOLERANCE_S: f64 = 1e-3;

/// The backlash values whose extremes are kept: exact, closed form, paper.
fn tracked(m: &MeshState) -> [f64; 3] {
    [
        m.backlash_exact_m,
        m.backlash_closed_form_m,
        m.backlash_paper_m,
    ]
}

/// Whether the cubic through backlash values `b0`, `b1` and rates `slope0`, `slope1`
/// (per second) at the ends of a step of `h_s` is clearly monotone: both end slopes
/// have the sign of the change, each at least [`SLOPE_MARGIN`] of it, and no interior
/// extremum.
fn monotone(b0: f64, b1: f64, slope0: f64, slope1: f64, h_s: f64) -> bool {
    let change = b1 - b0;
    let clear = |slope: f64| slope * h_s * change.signum() >= SLOPE_MARGIN * change.abs();
    [b0, b1, slope0, slope1].iter().all(|v| v.is_finite())
        && change != 0.0
        && clear(slope0)
        && clear(slope1)
        && crate::thermal::solver::hermite_interior_extrema_at(b0, b1, slope0, slope1, h_s)
            == [None, None]
}

/// The summary of a run for scripts (`orbitlash run --json`): stable keys, SI units in
/// their names. Documented in the README.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunSummary {
    pub scenario: String,
    /// "pass" when every gear pair kept its minimum backlash, else "fail";
    /// "incomplete" for an interrupted run in which no pair failed so far (as the
    /// log's end record says).
    pub verdict: &'static str,
    pub t_start_s: f64,
    pub t_end_s: f64,
    pub orbits: f64,
    pub interrupted: bool,
    /// The window the node statistics cover: the last orbit, or the whole run when it
    /// stopped before its last orbit.
    pub window: Window,
    pub nodes: Vec<NodeSummary>,
    pub gear_pairs: Vec<PairSummary>,
    pub events: EventCounts,
    pub energy: EnergySummary,
    /// Each heater over the run: power, time on, duty and energy.
    pub heaters: Vec<HeaterSummary>,
    /// Each day of simulated time (day 1 starts at t = 0): each pair's backlash range,
    /// the coldest and hottest node, the heaters' share of the day on.
    pub days: Vec<DaySummary>,
    pub solver: SolverSummary,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HeaterSummary {
    pub name: String,
    pub power_w: f64,
    pub on_s: f64,
    /// Time on over the run's span.
    pub duty_fraction: f64,
    pub energy_j: f64,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DaySummary {
    /// From 1.
    pub day: u64,
    pub start_s: f64,
    /// Seconds of the day the run covered (less than a day for a last, cut day).
    pub covered_s: f64,
    pub gear_pairs: Vec<PairDay>,
    pub coldest_node: String,
    pub coldest_k: f64,
    pub hottest_node: String,
    pub hottest_k: f64,
    /// The heaters' time on over (their number × the covered time); null without one.
    pub heaters_on_fraction: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PairDay {
    pub name: String,
    /// Null when the pair had no valid mesh that day.
    pub min_backlash_um: Option<f64>,
    pub max_backlash_um: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Window {
    pub start_s: f64,
    pub end_s: f64,
    pub last_orbit: bool,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NodeSummary {
    pub name: String,
    pub min_k: f64,
    pub max_k: f64,
    pub mean_k: f64,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PairSummary {
    pub name: String,
    /// "pass", "margin_violated", "interference" or "no_valid_mesh".
    pub verdict: PairVerdict,
    pub min_backlash_allowed_um: f64,
    /// Over the whole run.
    pub min_backlash_um: f64,
    pub t_min_backlash_s: f64,
    pub max_backlash_um: f64,
    pub t_max_backlash_s: f64,
    pub min_margin_um: f64,
    pub min_backlash_closed_form_um: f64,
    pub max_backlash_closed_form_um: f64,
    pub min_backlash_paper_um: f64,
    pub max_backlash_paper_um: f64,
    /// Over the window.
    pub window_min_backlash_um: f64,
    pub window_max_backlash_um: f64,
    pub interference_events: u64,
    pub margin_events: u64,
    pub invalid_samples: u64,
    /// When the mesh was first lost, s (null: never).
    pub t_first_invalid_s: f64,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EventCounts {
    pub eclipse_entries: u64,
    pub heater_switches: u64,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EnergySummary {
    pub absorbed_j: f64,
    pub dissipated_j: f64,
    pub to_boundary_j: std::collections::BTreeMap<String, f64>,
    pub stored_j: f64,
    pub error_j: f64,
    pub relative_error: f64,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SolverSummary {
    pub method: &'static str,
    /// "dense", "sparse" or "iterative".
    pub linear_solver: crate::thermal::iteration::LinearSolver,
    pub steps: u64,
    pub rejected_steps: u64,
    pub factorizations: u64,
    pub newton_iterations: u64,
    pub wall_time_s: f64,
}

impl RunSummary {
    /// The summary of a run of `scenario` from its statistics and observers.
    pub fn new(
        scenario: &crate::spec::scenario::Scenario,
        stats: &crate::run::sim::RunStats,
        window: &WindowStats,
        mesh: &MeshStats,
        daily: &DailyStats,
        wall_time_s: f64,
    ) -> RunSummary {
        let um = |m: f64| m * 1e6;
        let pairs: Vec<PairSummary> = scenario
            .gears
            .iter()
            .zip(mesh.run_pairs.iter().zip(&mesh.pairs))
            .map(|(g, (r, w))| PairSummary {
                name: g.name.clone(),
                verdict: r.verdict(),
                min_backlash_allowed_um: um(g.min_backlash_m),
                min_backlash_um: um(r.min_exact_m),
                t_min_backlash_s: r.t_min_s,
                max_backlash_um: um(r.max_exact_m),
                t_max_backlash_s: r.t_max_s,
                min_margin_um: um(r.min_margin_m),
                min_backlash_closed_form_um: um(r.min_closed_form_m),
                max_backlash_closed_form_um: um(r.max_closed_form_m),
                min_backlash_paper_um: um(r.min_paper_m),
                max_backlash_paper_um: um(r.max_paper_m),
                window_min_backlash_um: um(w.min_exact_m),
                window_max_backlash_um: um(w.max_exact_m),
                interference_events: r.interference_events,
                margin_events: r.margin_events,
                invalid_samples: r.invalid_samples,
                t_first_invalid_s: r.t_first_invalid_s,
            })
            .collect();
        let e = &stats.energy;
        let net = &scenario.thermal.network;
        RunSummary {
            scenario: scenario.name.clone(),
            verdict: match PassFail::all(pairs.iter().map(|p| p.verdict.passes())) {
                PassFail::Pass if stats.interrupted => "incomplete",
                v => v.as_str(),
            },
            t_start_s: stats.t_start_s,
            t_end_s: stats.t_end_s,
            // a whole number of orbits as that number, not 5.999999999999999
            orbits: crate::units::snap_whole(
                (stats.t_end_s - stats.t_start_s) / scenario.period_s(),
            ),
            interrupted: stats.interrupted,
            window: Window {
                start_s: window.window_start_s(),
                end_s: stats.t_end_s,
                last_orbit: window.window_start_s() > stats.t_start_s
                    || stats.t_end_s - stats.t_start_s <= scenario.period_s() * 1.000001,
            },
            nodes: window
                .nodes()
                .into_iter()
                .map(|n| NodeSummary {
                    name: n.name,
                    min_k: n.min_k,
                    max_k: n.max_k,
                    mean_k: n.mean_k,
                })
                .collect(),
            gear_pairs: pairs,
            events: EventCounts {
                eclipse_entries: stats.eclipse_entries,
                heater_switches: stats.heater_switches,
            },
            energy: EnergySummary {
                absorbed_j: e.absorbed_j,
                dissipated_j: e.dissipated_j,
                to_boundary_j: net
                    .boundaries
                    .iter()
                    .zip(&e.to_boundary_j)
                    .map(|(b, q)| (b.name.clone(), *q))
                    .collect(),
                stored_j: e.stored_j,
                error_j: e.error_j(),
                relative_error: e.relative_error(),
            },
            heaters: daily.heater_summaries(stats.t_end_s - stats.t_start_s),
            days: daily.day_summaries(&scenario.gears),
            solver: SolverSummary {
                method: "tr-bdf2",
                linear_solver: stats.linear_solver,
                steps: stats.steps,
                rejected_steps: stats.rejected_steps,
                factorizations: stats.factorizations,
                newton_iterations: stats.newton_iterations,
                wall_time_s,
            },
        }
    }
}

/// A run's days (of simulated time, from t = 0): per day, each gear pair's smallest
/// and largest exact backlash, each node's range, and each heater's time on and
/// energy. A step counts to the day it starts in (steps are minutes; a day is 86 400 s);
/// extremes are those at step ends (`MeshStats` refines the run's within steps, a few
/// nanometres further: [`DailyStats::include_run_extremes`] puts those in their days).
#[derive(Debug, Clone, Default)]
pub struct DailyStats {
    pub nodes: Vec<String>,
    pub heaters: Vec<(String, f64)>,
    pub days: Vec<Day>,
}

impl DailyStats {
    /// Each pair's run-wide smallest and largest backlash (`pairs`, refined within
    /// steps by `MeshStats`) folded into the day each falls in, so that the day of the
    /// run's extreme shows the run's figure, not the step end's a few nanometres off.
    pub fn include_run_extremes(&mut self, pairs: &[PairStats]) {
        for (k, p) in pairs.iter().enumerate() {
            for (t, v) in [(p.t_min_s, p.min_exact_m), (p.t_max_s, p.max_exact_m)] {
                if !(t.is_finite() && v.is_finite()) {
                    continue;
                }
                // its day, or, when no step starts in that day (the run's last step
                // crosses midnight), the day of the step it is in
                let d = (t / DAY_S).floor().max(0.0) as u64;
                if let Some(e) = self
                    .days
                    .iter_mut()
                    .rev()
                    .find(|x| x.day <= d)
                    .and_then(|x| x.backlash_m.get_mut(k))
                {
                    *e = (e.0.min(v), e.1.max(v));
                }
            }
        }
    }

    /// Each heater's power, time on, duty over `span_s` and energy.
    pub fn heater_summaries(&self, span_s: f64) -> Vec<HeaterSummary> {
        self.heaters
            .iter()
            .enumerate()
            .map(|(k, (name, p))| {
                let on_s: f64 = self.days.iter().map(|d| d.heater_on_s[k]).sum();
                HeaterSummary {
                    name: name.clone(),
                    power_w: *p,
                    on_s,
                    duty_fraction: on_s / span_s.max(1e-9),
                    energy_j: self.days.iter().map(|d| d.heater_j[k]).sum(),
                }
            })
            .collect()
    }

    /// Each day as the JSON summary gives it.
    pub fn day_summaries(&self, gears: &[crate::gear::GearPair]) -> Vec<DaySummary> {
        let finite = |v: f64| v.is_finite().then_some(v * 1e6);
        self.days
            .iter()
            .map(|d| {
                let (mut cold, mut hot) = ((f64::INFINITY, 0), (f64::NEG_INFINITY, 0));
                for (i, &(a, b)) in d.node_k.iter().enumerate() {
                    if a < cold.0 {
                        cold = (a, i);
                    }
                    if b > hot.0 {
                        hot = (b, i);
                    }
                }
                let name = |i: usize| self.nodes.get(i).cloned().unwrap_or_default();
                let on: f64 = d.heater_on_s.iter().sum();
                DaySummary {
                    day: d.day + 1,
                    start_s: d.day as f64 * DAY_S,
                    covered_s: d.covered_s,
                    gear_pairs: gears
                        .iter()
                        .zip(&d.backlash_m)
                        .map(|(g, &(lo, hi))| PairDay {
                            name: g.name.clone(),
                            min_backlash_um: finite(lo),
                            max_backlash_um: finite(hi),
                        })
                        .collect(),
                    coldest_node: name(cold.1),
                    coldest_k: cold.0,
                    hottest_node: name(hot.1),
                    hottest_k: hot.0,
                    heaters_on_fraction: (!self.heaters.is_empty())
                        .then(|| on / (d.covered_s * self.heaters.len() as f64).max(1e-9)),
                }
            })
            .collect()
    }
}

/// One day of [`DailyStats`].
#[derive(Debug, Clone, PartialEq)]
pub struct Day {
    /// Day number from 0.
    pub day: u64,
    /// Per pair: (smallest, largest) exact backlash, m ((∞, −∞): no valid mesh that
    /// day).
    pub backlash_m: Vec<(f64, f64)>,
    /// Per node: (smallest, largest) temperature, K.
    pub node_k: Vec<(f64, f64)>,
    /// Per heater: seconds on, and energy, J.
    pub heater_on_s: Vec<f64>,
    pub heater_j: Vec<f64>,
    /// Seconds of the day the run covered.
    pub covered_s: f64,
}

pub const DAY_S: f64 = 86_400.0;

/// The day `t_s` falls in, started when it is a new one (a new day allocates; a step
/// within a day does not).
fn day_of(days: &mut Vec<Day>, t_s: f64, pairs: usize, nodes: usize, heaters: usize) -> &mut Day {
    let d = (t_s / DAY_S).floor().max(0.0) as u64;
    if days.last().is_none_or(|l| l.day != d) {
        days.push(Day {
            day: d,
            backlash_m: vec![(f64::INFINITY, f64::NEG_INFINITY); pairs],
            node_k: vec![(f64::INFINITY, f64::NEG_INFINITY); nodes],
            heater_on_s: vec![0.0; heaters],
            heater_j: vec![0.0; heaters],
            covered_s: 0.0,
        });
    }
    days.last_mut().expect("pushed")
}

impl Observer for DailyStats {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        self.nodes = r
            .model
            .network
            .nodes
            .iter()
            .map(|n| n.name.clone())
            .collect();
        self.heaters = r
            .model
            .network
            .heaters
            .iter()
            .map(|h| (h.name.clone(), h.power_w))
            .collect();
        self.days.clear();
        let day = day_of(
            &mut self.days,
            r.t_start_s,
            r.gears.len(),
            self.nodes.len(),
            self.heaters.len(),
        );
        for (i, &t) in r.temps_k.iter().enumerate() {
            day.node_k[i] = (t, t);
        }
        // The start state counts, as it does for MeshStats (a cold start's backlash).
        for (k, m) in r.mesh.iter().enumerate() {
            let b = m.backlash_exact_m;
            if b.is_finite() {
                day.backlash_m[k] = (b, b);
            }
        }
        Ok(())
    }

    fn on_step(&mut self, s: &StepView<'_>) -> ObserverResult {
        let heaters = &self.heaters;
        let day = day_of(
            &mut self.days,
            s.data.t0_s,
            s.mesh.len(),
            self.nodes.len(),
            heaters.len(),
        );
        day.covered_s += s.data.h_s;
        for (k, m) in s.mesh.iter().enumerate() {
            let b = m.backlash_exact_m;
            if b.is_finite() {
                let e = &mut day.backlash_m[k];
                *e = (e.0.min(b), e.1.max(b));
            }
        }
        for (i, &t) in s.data.temps1_k.iter().enumerate() {
            let e = &mut day.node_k[i];
            *e = (e.0.min(t), e.1.max(t));
        }
        for (k, &on) in s.heaters_on.iter().enumerate() {
            if on {
                day.heater_on_s[k] += s.data.h_s;
                day.heater_j[k] += heaters[k].1 * s.data.h_s;
            }
        }
        Ok(())
    }
}

/// How a run ended, as its log's `orbitlash.run_end` record carries it (keys
/// `verdict`, `pairs_json`, `eclipses_json`) and as its figures take it: the verdict,
/// each pair's smallest backlash and its time from the run itself (the mesh statistics,
/// which see inside every step), not from whichever samples a log or CSV kept.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunEnd {
    /// "pass", "fail", "none" (no gear pair), or "incomplete" (the run stopped before
    /// its end with no pair failing so far).
    pub verdict: String,
    pub pairs: Vec<PairEnd>,
    /// Eclipse windows (entry, exit), s since t = 0; one still open at the end closes
    /// at the run's end.
    pub eclipses_s: Vec<[f64; 2]>,
}

/// One gear pair's part of [`RunEnd`]; a value that is not finite is `None` (JSON null).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairEnd {
    pub name: String,
    pub min_backlash_um: Option<f64>,
    pub t_min_s: Option<f64>,
    pub min_allowed_um: Option<f64>,
    /// As [`PairVerdict`] serialises.
    pub verdict: String,
}

impl RunEnd {
    /// From the run-wide pair statistics, each pair's smallest allowed backlash (m, in
    /// the same order), the eclipse windows and whether the run reached its end.
    pub fn new(
        pairs: &[PairStats],
        min_allowed_m: &[f64],
        eclipses_s: Vec<[f64; 2]>,
        complete: bool,
    ) -> RunEnd {
        let finite = |v: f64| v.is_finite().then_some(v);
        let verdict = match PassFail::all(pairs.iter().map(|p| p.verdict().passes())) {
            _ if pairs.is_empty() => "none",
            PassFail::Pass if !complete => "incomplete",
            v => v.as_str(),
        };
        RunEnd {
            verdict: verdict.to_string(),
            pairs: pairs
                .iter()
                .zip(min_allowed_m)
                .map(|(p, a)| PairEnd {
                    name: p.name.clone(),
                    min_backlash_um: finite(p.min_exact_m * 1e6),
                    t_min_s: finite(p.t_min_s),
                    min_allowed_um: finite(a * 1e6),
                    verdict: serde_json::to_value(p.verdict())
                        .ok()
                        .and_then(|v| v.as_str().map(str::to_string))
                        .unwrap_or_default(),
                })
                .collect(),
            eclipses_s,
        }
    }

    /// The record's keys and values (`pairs_json` and `eclipses_json` as JSON).
    pub fn to_metadata(&self) -> Vec<(String, String)> {
        vec![
            ("verdict".into(), self.verdict.clone()),
            (
                "pairs_json".into(),
                serde_json::to_string(&self.pairs).expect("plain data"),
            ),
            (
                "eclipses_json".into(),
                serde_json::to_string(&self.eclipses_s).expect("plain data"),
            ),
        ]
    }

    /// Back from a `run_end` record; `None` for a log written before these keys (or
    /// by a run that failed before its first step).
    pub fn from_metadata(m: &std::collections::BTreeMap<String, String>) -> Option<RunEnd> {
        Some(RunEnd {
            verdict: m.get("verdict")?.clone(),
            pairs: serde_json::from_str(m.get("pairs_json")?).ok()?,
            eclipses_s: serde_json::from_str(m.get("eclipses_json")?).ok()?,
        })
    }
}

/// Eclipse windows from a run's events (an observer): entry to exit, one open at the
/// start (the run starts in shadow) from the start, one open at the end to the end.
#[derive(Debug, Clone, Default)]
pub struct EclipseWindows {
    pub windows_s: Vec<[f64; 2]>,
    open_s: Option<f64>,
}

impl EclipseWindows {
    /// The windows, with one still open closed at `t_end_s`.
    pub fn closed_at(&self, t_end_s: f64) -> Vec<[f64; 2]> {
        let mut w = self.windows_s.clone();
        if let Some(t0) = self.open_s {
            w.push([t0, t_end_s]);
        }
        w
    }
}

impl Observer for EclipseWindows {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        if !r.sunlit {
            self.open_s = Some(r.t_start_s);
        }
        Ok(())
    }
    fn on_event(&mut self, e: &Event) -> ObserverResult {
        match e.kind {
            EventKind::EclipseEntry => self.open_s = Some(e.t_s),
            EventKind::EclipseExit => {
                let t0 = self.open_s.take().unwrap_or(e.t_s);
                self.windows_s.push([t0, e.t_s]);
            }
            _ => {}
        }
        Ok(())
    }
}

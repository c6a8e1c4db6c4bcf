//! Sampling a run: what observers record about one instant, evaluated by the run once
//! and handed to them as values.
//!
//! Observers see, they do not recompute. A [`Sample`] holds everything the outputs
//! record at a time (temperatures, switch states, environment, gear mesh states, heat
//! flows); [`Probe`] evaluates one from the step's interpolant and the model the run
//! was set up with; [`Sampler`] is the one helper that decides *when* to sample (every
//! n-th step, a fixed interval, or given times such as a recording's) and fills the
//! sample. The CSV export, the MCAP log, the summaries and the sensors all sample
//! through it, so "the temperature at 3600 s" is the same number in every output.

use crate::gear::{GearPair, MeshState};
use crate::orbit::faces::Incident;
use crate::orbit::{EnvState, EnvironmentModel};
pub use crate::run::sim::{Probe, ProbeWork};
use crate::run::sim::{RunStart, StepView, mesh_or_nan};
use crate::thermal::{Compiled, StepSwitches, ThermalModel};

/// Heat flows at one instant, W.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HeatFlows {
    /// Sun, albedo and Earth infrared absorbed, summed over the network.
    pub absorbed_w: f64,
    /// Scheduled dissipation and heaters, summed.
    pub dissipated_w: f64,
    /// Net heat into each boundary node (as `Network::boundaries`).
    pub to_boundary_w: Vec<f64>,
    /// Each load (as `Network::loads`).
    pub load_w: Vec<f64>,
    /// Each heater's power: its rating when on, 0 when off (as `Network::heaters`).
    pub heater_w: Vec<f64>,
}

/// What to evaluate besides temperatures, switch states and environment (which are
/// always filled).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Want {
    /// Every gear pair's mesh state ([`Sample::mesh`]).
    pub mesh: bool,
    /// Heat flows ([`Sample::flows`]).
    pub flows: bool,
}

impl Want {
    pub const TEMPERATURES: Want = Want {
        mesh: false,
        flows: false,
    };
    pub const MESH: Want = Want {
        mesh: true,
        flows: false,
    };
    pub const ALL: Want = Want {
        mesh: true,
        flows: true,
    };
}

/// One instant of a run, as every output records it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Sample {
    pub t_s: f64,
    /// Sunlit as during the step the sample falls in.
    pub sunlit: bool,
    /// Sun and Earth geometry and fluxes at `t_s`.
    pub env: Option<EnvState>,
    /// Orbit count (1 for the first) and angle from orbit noon, degrees in [0, 360).
    pub orbit_number: u64,
    pub orbit_phase_deg: f64,
    /// Per diffusion node, K.
    pub temperatures_k: Vec<f64>,
    pub heaters_on: Vec<bool>,
    pub modes_active: Vec<bool>,
    /// Per gear pair (NaN backlash where there is no valid mesh), when wanted.
    pub mesh: Vec<MeshState>,
    /// When wanted.
    pub flows: HeatFlows,
    /// What each face receives before absorptivity (the face loads in
    /// `Network::loads` order), when flows are wanted.
    pub faces: Vec<Incident>,
}

impl<'a> Probe<'a> {
    pub fn model(&self) -> &'a ThermalModel {
        self.model
    }
    pub fn gears(&self) -> &'a [GearPair] {
        self.gears
    }

    /// Fills everything but the temperatures (already in `out`) at `out.t_s`.
    pub(crate) fn complete(&self, want: Want, mesh: Option<&[MeshState]>, out: &mut Sample) {
        let env_model = &self.model.environment;
        let env = env_model.state_with(out.t_s, out.sunlit);
        out.env = Some(env);
        out.orbit_number = env_model.orbit_number(out.t_s);
        out.orbit_phase_deg = env_model.orbit_phase_deg(out.t_s);
        out.mesh.clear();
        if want.mesh {
            match mesh {
                Some(m) => out.mesh.extend_from_slice(m),
                None => out.mesh.extend(
                    self.gears
                        .iter()
                        .map(|g| mesh_or_nan(g, &out.temperatures_k)),
                ),
            }
        }
        out.faces.clear();
        if want.flows {
            let net = &self.model.network;
            let mut faces = net.face_loads().map(|(_, f)| f).peekable();
            if faces.peek().is_some() {
                let fe = env_model.face_environment(&env);
                out.faces
                    .extend(faces.map(|f| crate::orbit::faces::incident(f, &fe)));
            }
            let mut w = self.work.borrow_mut();
            let w = &mut *w;
            let compiled = w.compiled.get_or_insert_with(|| Compiled::new(net));
            w.scratch_w.resize(net.nodes.len(), 0.0);
            compiled.set_time(
                self.model,
                &env,
                StepSwitches {
                    heaters_on: &out.heaters_on,
                    modes_active: &out.modes_active,
                },
            );
            compiled.heat_w(&out.temperatures_k, &mut w.scratch_w, Some(&mut w.flows));
            let f = &mut out.flows;
            f.absorbed_w = w.flows.absorbed_w;
            f.dissipated_w = w.flows.dissipated_w;
            f.to_boundary_w.clone_from(&w.flows.to_boundary_w);
            f.load_w.clone_from(&compiled.each_load_w);
            f.heater_w.clear();
            f.heater_w.extend(
                net.heaters
                    .iter()
                    .zip(&out.heaters_on)
                    .map(|(h, &on)| if on { h.power_w } else { 0.0 }),
            );
        }
    }

    /// The mesh state of gear pair `k` at node temperatures `temps_k`.
    pub fn mesh(&self, k: usize, temps_k: &[f64]) -> MeshState {
        mesh_or_nan(&self.gears[k], temps_k)
    }

    /// The mesh state of gear pair `k` at temperatures `temps_k + dt_s · rates_k_per_s`
    /// (a point along a tangent of the temperature path).
    pub fn mesh_along(
        &self,
        k: usize,
        temps_k: &[f64],
        rates_k_per_s: &[f64],
        dt_s: f64,
    ) -> MeshState {
        let mut w = self.work.borrow_mut();
        w.temps_k.clear();
        w.temps_k
            .extend(temps_k.iter().zip(rates_k_per_s).map(|(t, r)| t + dt_s * r));
        mesh_or_nan(&self.gears[k], &w.temps_k)
    }

    /// The mesh state of gear pair `k` at `t_s` within `step`.
    pub fn mesh_at(&self, step: &StepView<'_>, k: usize, t_s: f64) -> MeshState {
        let mut w = self.work.borrow_mut();
        w.temps_k.resize(step.temps1_k().len(), 0.0);
        step.temperatures_at(t_s, &mut w.temps_k);
        mesh_or_nan(&self.gears[k], &w.temps_k)
    }
}

impl RunStart<'_> {
    /// The run's start as a sample.
    pub fn sample(&self, want: Want, out: &mut Sample) {
        out.t_s = self.t_start_s;
        out.sunlit = self.sunlit;
        out.temperatures_k.clear();
        out.temperatures_k.extend_from_slice(self.temps_k);
        out.heaters_on.clear();
        out.heaters_on.extend_from_slice(self.heaters_on);
        out.modes_active.clear();
        out.modes_active.extend_from_slice(self.modes_active);
        self.probe.complete(want, Some(self.mesh), out);
    }
}

impl StepView<'_> {
    /// The step's end values a sample is completed from later ([`Probe::complete`]
    /// with the same model): time, temperatures, switch states, sunlit and mesh
    /// states, copied (no evaluation).
    pub fn end_state_into(&self, out: &mut Sample) {
        out.t_s = self.t1_s();
        out.temperatures_k.clear();
        out.temperatures_k.extend_from_slice(self.temps1_k());
        self.switches_into(out);
        out.mesh.clear();
        out.mesh.extend_from_slice(self.mesh);
    }

    /// The step's end as a sample (the step's own end values, not interpolated).
    pub fn sample_end(&self, want: Want, out: &mut Sample) {
        out.t_s = self.t1_s();
        out.temperatures_k.clear();
        out.temperatures_k.extend_from_slice(self.temps1_k());
        self.switches_into(out);
        self.probe.complete(want, Some(self.mesh), out);
    }

    /// The instant `t_s` within the step as a sample (temperatures from the solver's
    /// interpolant).
    pub fn sample_at(&self, t_s: f64, want: Want, out: &mut Sample) {
        out.t_s = t_s;
        out.temperatures_k.resize(self.temps1_k().len(), 0.0);
        self.temperatures_at(t_s, &mut out.temperatures_k);
        self.switches_into(out);
        self.probe.complete(want, None, out);
    }

    fn switches_into(&self, out: &mut Sample) {
        out.sunlit = self.env1.sunlit;
        out.heaters_on.clear();
        out.heaters_on.extend_from_slice(self.heaters_on);
        out.modes_active.clear();
        out.modes_active.extend_from_slice(self.modes_active);
    }
}

/// Fixed-interval sampling times (for [`Cadence::Interval`]): the start of the run,
/// then each multiple of `interval_s` after it, once, from the step that reaches it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    interval_s: f64,
    next: i64,
}

impl Grid {
    pub fn new(interval_s: f64) -> Grid {
        Grid {
            interval_s,
            next: 1,
        }
    }

    pub fn interval_s(&self) -> f64 {
        self.interval_s
    }

    /// A run starts at `t_start_s` (sampled by the caller): the next grid time is the
    /// first multiple of the interval after it.
    pub fn start(&mut self, t_start_s: f64) {
        self.next = (t_start_s / self.interval_s).floor() as i64 + 1;
    }

    /// The last grid time at or before `t1_s` not given yet, if any; the ones before
    /// it are skipped (in one jump: a step may pass millions of them).
    pub fn last_due(&mut self, t1_s: f64) -> Option<f64> {
        let first = self.next_due(t1_s)?;
        let lim = t1_s * (1.0 + 1e-12);
        let mut n = (lim / self.interval_s).floor() as i64;
        // the same test as next_due's, whatever the division rounded to
        while n as f64 * self.interval_s > lim {
            n -= 1;
        }
        while (n + 1) as f64 * self.interval_s <= lim {
            n += 1;
        }
        if n >= self.next {
            self.next = n + 1;
            Some(n as f64 * self.interval_s)
        } else {
            Some(first)
        }
    }

    /// The next grid time at or before `t1_s` (a step's end), if any; each once.
    pub fn next_due(&mut self, t1_s: f64) -> Option<f64> {
        let t = self.next as f64 * self.interval_s;
        (t <= t1_s * (1.0 + 1e-12)).then(|| {
            self.next += 1;
            t
        })
    }
}

/// When a [`Sampler`] samples.
#[derive(Debug, Clone, PartialEq)]
pub enum Cadence {
    /// The start, then the end of every n-th step (n ≥ 1): the solver's own values.
    Steps(u64),
    /// The start, then every multiple of the interval, s (interpolated).
    Interval(f64),
    /// As `Interval`, but at most one sample per accepted step: the last multiple of
    /// the interval the step reaches (none if it reaches none). Where the solver's
    /// steps are longer than the interval, the samples follow the steps, so there are
    /// never more samples than steps (a log's `--log-every 60s`).
    IntervalAtMostPerStep(f64),
    /// The given times, s, ascending (interpolated; a time equal to the run's start is
    /// the start state; times before the start are skipped).
    Times(std::sync::Arc<[f64]>),
}

/// Samples a run at its [`Cadence`]: call [`Sampler::start`] from `on_start` and
/// [`Sampler::each`] from `on_step`. Buffers are reused: no allocation after the first
/// sample. A run that starts where the last one this sampler saw ended (a split run
/// resumed from its end state) continues the same sequence: no second start sample,
/// the step count and the grid go on.
#[derive(Debug, Clone)]
pub struct Sampler {
    cadence: Cadence,
    want: Want,
    grid: Grid,
    next_time: usize,
    /// Steps seen since the (first) start, for [`Cadence::Steps`].
    steps: u64,
    /// End of the last step seen.
    last_t_s: Option<f64>,
    sample: Sample,
}

impl Sampler {
    pub fn new(cadence: Cadence, want: Want) -> Sampler {
        let grid = Grid::new(match &cadence {
            Cadence::Interval(dt) | Cadence::IntervalAtMostPerStep(dt) => *dt,
            _ => 1.0,
        });
        Sampler {
            cadence,
            want,
            grid,
            next_time: 0,
            steps: 0,
            last_t_s: None,
            sample: Sample::default(),
        }
    }

    pub fn cadence(&self) -> &Cadence {
        &self.cadence
    }

    /// Whether a run starting at `t_start_s` continues the last one this sampler saw.
    pub fn continues(&self, t_start_s: f64) -> bool {
        self.last_t_s
            .is_some_and(|t| t.to_bits() == t_start_s.to_bits())
    }

    /// The start of a run: its sample, unless the cadence skips it or the run continues
    /// the previous one (whose last step ended here).
    pub fn start(&mut self, r: &RunStart<'_>) -> Option<&Sample> {
        let t0 = r.t_start_s;
        if self.continues(t0) {
            return None;
        }
        self.steps = 0;
        match &self.cadence {
            Cadence::Interval(_) | Cadence::IntervalAtMostPerStep(_) => self.grid.start(t0),
            Cadence::Steps(_) => {}
            Cadence::Times(ts) => {
                self.next_time = ts.partition_point(|&t| t < t0);
                if ts.get(self.next_time) != Some(&t0) {
                    return None;
                }
                self.next_time += 1;
            }
        }
        r.sample(self.want, &mut self.sample);
        Some(&self.sample)
    }

    /// Calls `f` with each sample due within `step`, in time order.
    pub fn each<E>(
        &mut self,
        step: &StepView<'_>,
        mut f: impl FnMut(&Sample) -> Result<(), E>,
    ) -> Result<(), E> {
        let t1 = step.t1_s();
        self.last_t_s = Some(t1);
        self.steps += 1;
        match &self.cadence {
            Cadence::Steps(n) => {
                if self.steps.is_multiple_of(*n) {
                    step.sample_end(self.want, &mut self.sample);
                    f(&self.sample)?;
                }
            }
            Cadence::Interval(_) => {
                while let Some(t) = self.grid.next_due(t1) {
                    step.sample_at(t, self.want, &mut self.sample);
                    f(&self.sample)?;
                }
            }
            Cadence::IntervalAtMostPerStep(_) => {
                let last = self.grid.last_due(t1);
                if let Some(t) = last {
                    step.sample_at(t, self.want, &mut self.sample);
                    f(&self.sample)?;
                }
            }
            Cadence::Times(ts) => {
                while let Some(&t) = ts.get(self.next_time) {
                    if t > t1 * (1.0 + 1e-12) {
                        break;
                    }
                    self.next_time += 1;
                    step.sample_at(t, self.want, &mut self.sample);
                    f(&self.sample)?;
                }
            }
        }
        Ok(())
    }
}

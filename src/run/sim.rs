//! The stepping loop: adaptive TR-BDF2 steps that land exactly on eclipse entry and
//! exit, mission-profile breakpoints and thermostat switching times; energy
//! bookkeeping; observers that see every accepted step and every event.
//!
//! Observers follow the "()` costs nothing" pattern: `()` is an observer that does
//! nothing, tuples and `Option`s of observers are observers.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::gear::{GearPair, MeshState};
use crate::orbit::{EnvState, EnvironmentModel, LoadKink};
pub use crate::spec::scenario::{SolverSettings, fixed_step_advice};
use crate::thermal::iteration::LinearSolver;
use crate::thermal::solver::{StepData, StepFailure, Stepper, StepperMemory, W0, W1};
use crate::thermal::{Network, StepSwitches, ThermalModel};

/// Steps shorter than this are not attempted, s.
pub const MIN_STEP_S: f64 = 1e-7;

pub use crate::spec::quantity::{MAX_TOLERANCE_K, MIN_MAX_STEP_S, MIN_TOLERANCE_K};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventKind {
    EclipseEntry,
    EclipseExit,
    HeaterOn(usize),
    HeaterOff(usize),
    ModeStart(usize),
    ModeEnd(usize),
    /// Gear pair k: exact backlash fell below its minimum allowed / rose back above it.
    MarginLow(usize),
    MarginRestored(usize),
    /// Gear pair k: exact backlash reached zero (teeth interfere) / opened again.
    InterferenceStart(usize),
    InterferenceEnd(usize),
    /// Gear pair k: no valid mesh (base circles overlap or contact ratio below 1).
    MeshInvalid(usize),
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Event {
    pub t_s: f64,
    pub kind: EventKind,
}

/// What an observer sees of one accepted step.
pub struct StepView<'a> {
    pub index: u64,
    pub data: &'a StepData,
    /// Environment at the end of the step (sunlit as during the step).
    pub env1: EnvState,
    pub heaters_on: &'a [bool],
    pub modes_active: &'a [bool],
    /// Each load's heat at the end of the step, W (as `Network::loads`).
    pub load_w: &'a [f64],
    /// The gear pairs' state at the end of the step (NaN backlash where the mesh is
    /// invalid).
    pub mesh: &'a [MeshState],
    /// Evaluates samples within the step (the `sample` module's methods).
    pub probe: Probe<'a>,
}

/// What an observer is told before the first step: the start state.
pub struct RunStart<'a> {
    pub model: &'a ThermalModel,
    pub gears: &'a [GearPair],
    pub t_start_s: f64,
    pub t_end_s: f64,
    pub temps_k: &'a [f64],
    pub heaters_on: &'a [bool],
    pub modes_active: &'a [bool],
    /// Sunlit until the first shadow crossing.
    pub sunlit: bool,
    pub mesh: &'a [MeshState],
    pub probe: Probe<'a>,
}

/// A run from `t_s` to `t_end_s` must go forward; a real orbit is propagated as far as
/// it goes (and no further): a decayed or diverging orbit fails before the run's first
/// step, with its date.
fn check_span(env: &crate::orbit::Environment, t_s: f64, t_end_s: f64) -> Result<(), SimError> {
    if !(t_end_s.is_finite() && t_end_s > t_s) {
        return Err(SimError::BadDuration(t_end_s - t_s));
    }
    match env {
        crate::orbit::Environment::Dated(d) => {
            d.orbit.check_until(t_end_s).map_err(SimError::Orbit)
        }
        _ => Ok(()),
    }
}

/// Propagates a real orbit over a run to `t_end_s` (the table its steps read), so that
/// an orbit that fails on the way (it decays, SGP4 diverges) is refused before any
/// output is opened; nothing for a circular orbit.
pub fn check_orbit(env: &crate::orbit::Environment, t_end_s: f64) -> Result<(), SimError> {
    check_span(env, 0.0, t_end_s)
}

/// The days a run from t = 0 to `t_end_s` touches (a real orbit's table is propagated
/// a day at a time).
fn days_spanned(t_end_s: f64) -> f64 {
    (t_end_s.max(0.0) / 86_400.0).floor() + 1.0
}

/// The pair's state, or a state with NaN backlash when there is no valid mesh.
pub fn mesh_or_nan(pair: &GearPair, temps_k: &[f64]) -> MeshState {
    pair.evaluate_or_invalid(temps_k).0
}

impl StepView<'_> {
    pub fn t0_s(&self) -> f64 {
        self.data.t0_s
    }
    pub fn t1_s(&self) -> f64 {
        self.data.t0_s + self.data.h_s
    }
    pub fn temps1_k(&self) -> &[f64] {
        &self.data.temps1_k
    }
    /// Temperature of node `i` at `t_s` within the step (cubic Hermite).
    pub fn temperature_at(&self, i: usize, t_s: f64) -> f64 {
        let d = self.data;
        d.temperature_at_fraction(i, ((t_s - d.t0_s) / d.h_s).clamp(0.0, 1.0))
    }
    /// All node temperatures at `t_s` within the step.
    pub fn temperatures_at(&self, t_s: f64, out_k: &mut [f64]) {
        let d = self.data;
        d.temperatures_at_fraction(((t_s - d.t0_s) / d.h_s).clamp(0.0, 1.0), out_k);
    }
}

/// Evaluates samples from the model a run was set up with: handed to observers inside
/// [`RunStart`] and [`StepView`]. Cheap to copy; its workspace is the setup's. Its
/// methods (sampling an instant, the mesh at a time) are in the `sample` module.
#[derive(Clone, Copy)]
pub struct Probe<'a> {
    pub(crate) model: &'a ThermalModel,
    pub(crate) gears: &'a [GearPair],
    pub(crate) work: &'a std::cell::RefCell<ProbeWork>,
}

/// The probe's workspace: a compiled network of its own (the stepper's is in the middle
/// of a step) and scratch vectors, made on first use.
#[derive(Default)]
pub struct ProbeWork {
    pub(crate) compiled: Option<crate::thermal::Compiled>,
    pub(crate) flows: crate::thermal::Flows,
    pub(crate) scratch_w: Vec<f64>,
    pub(crate) temps_k: Vec<f64>,
}

pub type ObserverResult = Result<(), Box<dyn std::error::Error + Send + Sync>>;

pub trait Observer {
    fn on_start(&mut self, _start: &RunStart<'_>) -> ObserverResult {
        Ok(())
    }
    fn on_step(&mut self, _step: &StepView<'_>) -> ObserverResult {
        Ok(())
    }
    fn on_event(&mut self, _event: &Event) -> ObserverResult {
        Ok(())
    }
    fn on_finish(&mut self, _stats: &RunStats) -> ObserverResult {
        Ok(())
    }
}

impl Observer for () {}

/// A budget of solver steps shared by the runs it watches: a run that would take more
/// stops with an error (a thermostat chattering on a fast node, far more steps than
/// the estimate said), instead of running without bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StepBudget {
    pub left: u64,
    pub total: u64,
}

impl StepBudget {
    pub fn new(total: u64) -> StepBudget {
        StepBudget { left: total, total }
    }

    /// No limit.
    pub fn unlimited() -> StepBudget {
        StepBudget::new(u64::MAX)
    }
}

impl Observer for StepBudget {
    fn on_step(&mut self, _: &StepView<'_>) -> ObserverResult {
        if self.left == 0 {
            return Err(format!(
                "more than {} solver steps, its budget (far more than the estimate): a thermostat switching many times a minute?",
                self.total
            )
            .into());
        }
        self.left -= 1;
        Ok(())
    }
}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        (**self).on_start(r)
    }
    fn on_step(&mut self, s: &StepView<'_>) -> ObserverResult {
        (**self).on_step(s)
    }
    fn on_event(&mut self, e: &Event) -> ObserverResult {
        (**self).on_event(e)
    }
    fn on_finish(&mut self, s: &RunStats) -> ObserverResult {
        (**self).on_finish(s)
    }
}

impl<O: Observer> Observer for Option<O> {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        self.as_mut().map_or(Ok(()), |o| o.on_start(r))
    }
    fn on_step(&mut self, s: &StepView<'_>) -> ObserverResult {
        self.as_mut().map_or(Ok(()), |o| o.on_step(s))
    }
    fn on_event(&mut self, e: &Event) -> ObserverResult {
        self.as_mut().map_or(Ok(()), |o| o.on_event(e))
    }
    fn on_finish(&mut self, s: &RunStats) -> ObserverResult {
        self.as_mut().map_or(Ok(()), |o| o.on_finish(s))
    }
}

macro_rules! tuple_observer {
    ($($name:ident $idx:tt),+) => {
        impl<$($name: Observer),+> Observer for ($($name,)+) {
            fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
                $(self.$idx.on_start(r)?;)+ Ok(())
            }
            fn on_step(&mut self, s: &StepView<'_>) -> ObserverResult {
                $(self.$idx.on_step(s)?;)+ Ok(())
            }
            fn on_event(&mut self, e: &Event) -> ObserverResult {
                $(self.$idx.on_event(e)?;)+ Ok(())
            }
            fn on_finish(&mut self, s: &RunStats) -> ObserverResult {
                $(self.$idx.on_finish(s)?;)+ Ok(())
            }
        }
    };
}
tuple_observer!(A 0, B 1);
tuple_observer!(A 0, B 1, C 2);
tuple_observer!(A 0, B 1, C 2, D 3);
tuple_observer!(A 0, B 1, C 2, D 3, E 4);

/// Energy bookkeeping of a run, J. `error_j` = stored + to boundaries − absorbed −
/// dissipated, each integrated with the method's own quadrature, so it measures how
/// well the discrete equations were solved (Newton residuals, bookkeeping bugs), not
/// the time-discretisation error.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct EnergyBalance {
    pub stored_j: f64,
    pub absorbed_j: f64,
    pub dissipated_j: f64,
    /// Net heat into each boundary node (as `Network::boundaries`).
    pub to_boundary_j: Vec<f64>,
}

impl EnergyBalance {
    pub fn error_j(&self) -> f64 {
        self.stored_j + self.to_boundary_j.iter().sum::<f64>() - self.absorbed_j - self.dissipated_j
    }
    /// |error| relative to the heat that came in.
    pub fn relative_error(&self) -> f64 {
        self.error_j().abs() / (self.absorbed_j + self.dissipated_j).abs().max(1e-300)
    }
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunStats {
    /// The run covered t_start_s … t_end_s.
    pub t_start_s: f64,
    pub t_end_s: f64,
    pub steps: u64,
    pub rejected_steps: u64,
    pub newton_iterations: u64,
    /// Factorisations of the iteration matrix (the rest reuse one).
    pub factorizations: u64,
    /// How the linear systems were solved: dense, sparse or iterative (`Auto`: no step
    /// was taken).
    pub linear_solver: LinearSolver,
    /// Iterative solver only: linear solves and conjugate-gradient iterations.
    pub linear_solves: u64,
    pub krylov_iterations: u64,
    pub eclipse_time_s: f64,
    pub eclipse_entries: u64,
    pub heater_switches: u64,
    pub energy: EnergyBalance,
    pub final_temperatures_k: Vec<f64>,
    /// The run stopped early on request; everything up to `t_end_s` is valid.
    pub interrupted: bool,
    /// The run paused at `Stop::pause_after_s`; its end state resumes it.
    pub paused: bool,
}

#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("solver failed at t = {t_s:.6} s with step {h_s:.3e} s: {cause}")]
    StepFailed {
        t_s: f64,
        h_s: f64,
        cause: StepFailure,
    },
    #[error("stopped at t = {t_s:.3} s")]
    Observer {
        t_s: f64,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    #[error("invalid run length {0} s")]
    BadDuration(f64),
    #[error("the orbit cannot be propagated over the run: {0}")]
    Orbit(String),
    #[error(
        "node {node} reached {temperature_k:.4e} K at t = {t_s:.3} s: temperatures must stay within 0 … {MAX_TEMPERATURE_K} K; {cause}"
    )]
    NonPhysical {
        node: String,
        t_s: f64,
        temperature_k: f64,
        /// The likely cause, in words.
        cause: String,
    },
    #[error("the step at t = {t_s} s is below the time resolution of the run")]
    TimeResolution { t_s: f64 },
}

/// Highest temperature a result may reach, K: above the vaporisation point of every
/// spacecraft material. A node that gets there has no way to lose its heat.
pub const MAX_TEMPERATURE_K: f64 = 10_000.0;

/// Why node `i` may have left the physical range, in words for the error message.
fn likely_cause(
    model: &ThermalModel,
    temps_k: &[f64],
    t_s: f64,
    i: usize,
    h_s: f64,
    adaptive: bool,
) -> String {
    use crate::thermal::analysis::{node_time_constant_s, unanchored_nodes};
    if unanchored_nodes(&model.network)[i] {
        return "it has no conductive or radiative path to a boundary (space or a [[boundary]]), \
so the heat it receives has nowhere to go; link it (see `orbitlash check`)"
            .to_string();
    }
    let tau = node_time_constant_s(model, temps_k, t_s, i);
    if !adaptive && h_s > tau {
        return format!(
            "the fixed step of {h_s:.4} s is {:.0}× the node's time constant of {tau:.3e} s \
(C over the sum of its conductances, see `orbitlash check`); {}",
            h_s / tau,
            fixed_step_advice(tau)
        );
    }
    format!(
        "the step of {h_s:.4} s could not resolve it (node time constant {tau:.3e} s); check its \
loads, capacitance and conductances, or tighten solver.tolerance_k"
    )
}

impl SimError {
    /// Simulated time of the failure, when known.
    pub fn t_s(&self) -> Option<f64> {
        match self {
            SimError::StepFailed { t_s, .. }
            | SimError::NonPhysical { t_s, .. }
            | SimError::TimeResolution { t_s }
            | SimError::Observer { t_s, .. } => Some(*t_s),
            _ => None,
        }
    }
}

/// The first node whose interpolant over the step falls to 0 K or below, rises above
/// [`MAX_TEMPERATURE_K`] or is not finite: (node, fraction of the step, value). Cheap when all is well: a node whose
/// values and rates at both ends keep the cubic Hermite above
/// min(y0, y1) − 4/27 h (|y0'| + |y1'|) > 0 (and a quadratic node whose three stage values
/// are positive and monotone) needs no search for its extrema.
fn first_nonphysical(d: &StepData) -> Option<(usize, f64, f64)> {
    let h = d.h_s;
    for i in 0..d.temps1_k.len() {
        let (y0, y1) = (d.temps0_k[i], d.temps1_k[i]);
        if !(y1.is_finite() && d.rates1_k_per_s[i].is_finite())
            || y1 <= 0.0
            || y1 > MAX_TEMPERATURE_K
        {
            return Some((i, 1.0, y1));
        }
        let safe = if d.quadratic[i] {
            let yg = d.temps_gamma_k[i];
            yg > 0.0 && (yg - y0) * (y1 - yg) >= 0.0
        } else {
            let slack = 4.0 / 27.0 * h * (d.rates0_k_per_s[i].abs() + d.rates1_k_per_s[i].abs());
            y0.min(y1) - slack > 0.0 && y0.max(y1) + slack <= MAX_TEMPERATURE_K
        };
        if safe {
            continue;
        }
        for (s, v) in d.interior_extrema(i).into_iter().flatten() {
            if !(v > 0.0 && v <= MAX_TEMPERATURE_K) {
                return Some((i, s, v));
            }
        }
    }
    None
}

/// Everything that shapes a run from a time on: the physical state (time, temperatures,
/// heater switches, sunlit or eclipsed) and the solver's memory (the step size in use,
/// the restart steps remembered per kind of event, the next shadow crossing and load
/// kink, the Jacobian and factorisation in use). The end state of a run is a valid
/// start state of the next: a run split anywhere and resumed from its end state gives
/// the unsplit run's numbers bit for bit.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    pub t_s: f64,
    pub temperatures_k: Vec<f64>,
    /// Per heater (as `Network::heaters`).
    pub heaters_on: Vec<bool>,
    /// Sunlit (or eclipsed) until the next shadow crossing.
    pub sunlit: bool,
    memory: Option<Memory>,
}

/// The kinds of event after which a step starts again short. Each remembers the step
/// the controller reached after its last occurrence, and the next one restarts there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum EventClass {
    EclipseEntry,
    EclipseExit,
    HeaterSwitch,
    /// A table point, a mode edge, a load kink.
    Other,
}

/// The restart step of each [`EventClass`], s.
#[derive(Debug, Clone, Copy, PartialEq)]
struct RestartSteps([f64; 4]);

impl std::ops::Index<EventClass> for RestartSteps {
    type Output = f64;
    fn index(&self, c: EventClass) -> &f64 {
        &self.0[c as usize]
    }
}

impl std::ops::IndexMut<EventClass> for RestartSteps {
    fn index_mut(&mut self, c: EventClass) -> &mut f64 {
        &mut self.0[c as usize]
    }
}

/// The step controller's factors. The local error of TR-BDF2 grows as h³, so a step
/// that gave the error ratio `err` (error / tolerance) is scaled by
/// `STEP_SAFETY · err^(−1/3)`.
const STEP_SAFETY: f64 = 0.9;
const STEP_ERROR_EXPONENT: f64 = -1.0 / 3.0;
/// Growth after a step with no measurable error.
const STEP_GROWTH_WITHOUT_ERROR: f64 = 5.0;
/// Growth below this factor holds the step, so the factorised iteration matrix is kept.
const STEP_HOLD_BELOW_GROWTH: f64 = 1.2;
/// Bounds of the factor after an accepted step, and after a rejected one.
const STEP_FACTOR_RANGE: (f64, f64) = (0.2, 3.0);
const REJECTED_STEP_FACTOR_RANGE: (f64, f64) = (0.1, 0.9);

/// The solver's part of a [`State`].
#[derive(Debug, Clone, PartialEq)]
struct Memory {
    step_s: f64,
    restart_steps_s: RestartSteps,
    event_class: Option<EventClass>,
    schedule: EventSchedule,
    modes_active: Vec<bool>,
    mesh_flags: Vec<MeshFlags>,
    stepper: StepperMemory,
    /// The setup and run that left it: that setup's stepper is still in this state.
    made_by: (u64, u64),
    /// The model it belongs to ([`Setup::fingerprint`]).
    model_print: u64,
    /// The public part of the state as the run left it: a state changed since (new
    /// temperatures for shooting, a heater switched by hand, another time) no longer
    /// matches its memory, which is then dropped.
    left: (f64, Vec<f64>, Vec<bool>, bool),
}

impl State {
    /// Whether the state carries a solver memory (it ended a run).
    pub fn is_resumed(&self) -> bool {
        self.memory.is_some()
    }

    /// The same physical state with the solver's memory forgotten: the next run starts
    /// as a fresh one would (first step, Jacobian, restart steps). Done by itself when
    /// the public fields were changed after the run that left them, or the state is
    /// run on a setup of another model.
    pub fn forget_solver(&mut self) {
        self.memory = None;
    }
}

/// When a run stops early.
#[derive(Debug, Clone, Copy, Default)]
pub struct Stop<'c> {
    /// Set from outside (Ctrl-C): the run stops after the current step.
    pub cancel: Option<&'c AtomicBool>,
    /// The run pauses at the end of the first step that reaches this time, without
    /// landing on it: resuming its end state continues the same steps.
    pub pause_after_s: Option<f64>,
}

/// Built once per model: the compiled network and the stepper's workspace, the
/// breakpoints and load kinks. [`Setup::run`] advances a [`State`] to an end time
/// under observers; any number of runs share one setup.
pub struct Setup<'a> {
    model: &'a ThermalModel,
    gears: &'a [GearPair],
    settings: SolverSettings,
    /// Every table point and mode edge, sorted.
    breakpoints: Vec<f64>,
    kinks: Vec<LoadKink>,
    stepper: Stepper,
    mesh: Vec<MeshState>,
    probe_work: std::cell::RefCell<ProbeWork>,
    id: u64,
    runs: u64,
    print: std::cell::OnceCell<u64>,
    /// Whether a run leaves the solver's memory in its state (false in [`simulate`],
    /// whose state is dropped: the memory's model print, a hash of the model's whole
    /// `Debug` text, is then never computed).
    remembers: bool,
}

static SETUP_IDS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

impl<'a> Setup<'a> {
    pub fn new(
        model: &'a ThermalModel,
        gears: &'a [GearPair],
        settings: &SolverSettings,
    ) -> Setup<'a> {
        Setup {
            model,
            gears,
            settings: settings.clone(),
            breakpoints: model.breakpoints_s(),
            kinks: model.load_kinks(),
            stepper: Stepper::new(model, settings.tolerance_k, settings.linear),
            mesh: gears
                .iter()
                .map(|g| mesh_or_nan(g, &model.network.initial_temperatures_k()))
                .collect(),
            probe_work: Default::default(),
            id: SETUP_IDS.fetch_add(1, Ordering::Relaxed),
            runs: 0,
            print: std::cell::OnceCell::new(),
            remembers: true,
        }
    }

    pub fn model(&self) -> &ThermalModel {
        self.model
    }

    /// A hash of everything that shapes a run's steps (the thermal model, the gear
    /// pairs, the solver settings), computed once: a state's solver memory is only
    /// reused by a setup of the same numbers.
    fn fingerprint(&self) -> u64 {
        *self.print.get_or_init(|| {
            struct Fnv(u64);
            impl std::fmt::Write for Fnv {
                fn write_str(&mut self, s: &str) -> std::fmt::Result {
                    for b in s.bytes() {
                        self.0 = (self.0 ^ b as u64).wrapping_mul(0x100_0000_01b3);
                    }
                    Ok(())
                }
            }
            let mut h = Fnv(0xcbf2_9ce4_8422_2325);
            let _ = std::fmt::Write::write_fmt(
                &mut h,
                format_args!("{:?}{:?}{:?}", self.model, self.gears, self.settings),
            );
            h.0
        })
    }

    /// The scenario's start: t = 0 at its initial temperatures.
    pub fn initial_state(&self) -> State {
        self.state_at(0.0, self.model.network.initial_temperatures_k())
    }

    /// A fresh state at `t_s` with `temperatures_k`: heaters on where their sensor is at
    /// or below the switch-on temperature (set `heaters_on` afterwards for a heater
    /// inside its band that is on), sunlit as the environment is just after `t_s`.
    pub fn state_at(&self, t_s: f64, temperatures_k: Vec<f64>) -> State {
        let net = &self.model.network;
        let env = &self.model.environment;
        let heaters_on = net
            .heaters
            .iter()
            .map(|h| temperatures_k[h.sensor_node] <= h.on_k)
            .collect();
        // Sunlit or eclipsed between shadow events: decided just after t (before the
        // next crossing) and toggled at every crossing the solver lands on.
        let probe = env.next_shadow_crossing(t_s, t_s + env.mean_period_s());
        let sunlit = env.sunlit(probe.map_or(t_s, |(ts, _)| t_s + 0.5 * (ts - t_s).min(1.0)));
        State {
            t_s,
            temperatures_k,
            heaters_on,
            sunlit,
            memory: None,
        }
    }

    fn next_kink(&self, t: f64) -> f64 {
        self.model.environment.next_load_kink(t, &self.kinks)
    }

    /// The solver's memory for a run from `state` to `t_end_s`, taken from `state`: the
    /// one it carries when the state is as its run left it and the model is the same,
    /// else that of a fresh start (then `true`). The setup's stepper is put in that
    /// memory's state.
    fn resume(&mut self, state: &mut State, t_end_s: f64) -> (Memory, bool) {
        let settings = &self.settings;
        let model = self.model;
        let env = &model.environment;
        let t_start = state.t_s;
        let resumed = state.memory.take().filter(|m| {
            let (t, temps, heaters, lit) = &m.left;
            t.to_bits() == t_start.to_bits()
                && temps.len() == state.temperatures_k.len()
                && temps
                    .iter()
                    .zip(&state.temperatures_k)
                    .all(|(a, b)| a.to_bits() == b.to_bits())
                && *heaters == state.heaters_on
                && *lit == state.sunlit
                && (m.made_by.0 == self.id || m.model_print == self.fingerprint())
        });
        let fresh = resumed.is_none();
        let mut memory = match resumed {
            Some(m) => m,
            None => Memory {
                step_s: settings.max_step_s.min(if settings.adaptive {
                    1.0
                } else {
                    f64::INFINITY
                }),
                // One memory per kind of event: entering eclipse, leaving it, a heater
                // switching, anything else (table point, mode edge, load kink).
                restart_steps_s: RestartSteps([settings.max_step_s / 30.0; 4]),
                event_class: None,
                schedule: EventSchedule {
                    next_shadow: env.next_shadow_crossing(t_start, t_end_s),
                    shadow_horizon_s: t_end_s,
                    next_breakpoint: 0,
                    t_kink_s: self.next_kink(t_start),
                },
                modes_active: model.modes.iter().map(|m| m.active(t_start)).collect(),
                mesh_flags: vec![MeshFlags::default(); self.gears.len()],
                stepper: self.stepper.fresh_memory(),
                made_by: (0, 0),
                model_print: 0,
                left: (0.0, Vec::new(), Vec::new(), false),
            },
        };
        // The setup's stepper is in that state already when it ended that very run.
        if memory.made_by != (self.id, self.runs) {
            self.stepper.restore(&memory.stepper);
        }
        let schedule = &mut memory.schedule;
        if schedule.next_shadow.is_none() && schedule.shadow_horizon_s < t_end_s {
            // the last search stopped at an earlier end
            schedule.next_shadow = env.next_shadow_crossing(t_start, t_end_s);
        }
        schedule.next_breakpoint = self.breakpoints.partition_point(|&b| b <= t_start);
        (memory, fresh)
    }

    /// The solver's work since the counts `factorizations_before` and `solves_before`
    /// (linear solves, Krylov iterations), and the linear solver it used, into `stats`.
    fn count_solver_work(
        &self,
        stats: &mut RunStats,
        factorizations_before: u64,
        solves_before: (u64, u64),
    ) {
        stats.factorizations = self.stepper.factorizations - factorizations_before;
        stats.linear_solver = self.stepper.linear_solver();
        let solves = self.stepper.solve_counts();
        stats.linear_solves = solves.0 - solves_before.0;
        stats.krylov_iterations = solves.1 - solves_before.1;
    }

    /// Advances `state` to `t_end_s` (landing on it), or until `stop` says. Observers
    /// see every accepted step and event. The energy balance is measured from the start
    /// state. `state` is left at the end, with the solver's memory.
    ///
    /// The loop's state between steps is a [`Stepping`]; each step is
    /// [`Setup::advance`]: the step toward the next event of its [`EventSchedule`]
    /// ([`Setup::try_step`]), its acceptance ([`Setup::accept`]), the events at its
    /// end ([`Stepping::pass_events`]) and the next step size.
    pub fn run<O: Observer>(
        &mut self,
        state: &mut State,
        t_end_s: f64,
        observer: &mut O,
        stop: Stop<'_>,
    ) -> Result<RunStats, SimError> {
        check_span(&self.model.environment, state.t_s, t_end_s)?;
        let (model, gears) = (self.model, self.gears);
        let net = &model.network;
        let t_start = state.t_s;
        let (memory, fresh) = self.resume(state, t_end_s);
        let y_start = state.temperatures_k.clone();
        let mut s = Stepping {
            t: t_start,
            y: std::mem::take(&mut state.temperatures_k),
            heaters_on: std::mem::take(&mut state.heaters_on),
            sunlit: state.sunlit,
            h: memory.step_s,
            restart: memory.restart_steps_s,
            event_class: memory.event_class,
            schedule: memory.schedule,
            modes_active: memory.modes_active,
            mesh_flags: memory.mesh_flags,
        };
        let factorizations_before = self.stepper.factorizations;
        let solves_before = self.stepper.solve_counts();
        let mut stats = RunStats {
            t_start_s: t_start,
            energy: EnergyBalance {
                to_boundary_j: vec![0.0; net.boundaries.len()],
                ..Default::default()
            },
            ..Default::default()
        };
        for (m, g) in self.mesh.iter_mut().zip(gears) {
            *m = mesh_or_nan(g, &s.y);
        }
        let early = observer
            .on_start(&RunStart {
                model,
                gears,
                t_start_s: t_start,
                t_end_s,
                temps_k: &s.y,
                heaters_on: &s.heaters_on,
                modes_active: &s.modes_active,
                sunlit: s.sunlit,
                mesh: &self.mesh,
                probe: Probe {
                    model,
                    gears,
                    work: &self.probe_work,
                },
            })
            .map_err(|source| SimError::Observer {
                t_s: t_start,
                source,
            })
            .and_then(|()| {
                if fresh {
                    mesh_events(&self.mesh, &mut s.mesh_flags, t_start, observer)
                } else {
                    Ok(())
                }
            });
        if let Err(e) = early {
            // Nothing ran: the caller keeps its start state (the solver forgotten).
            state.temperatures_k = s.y;
            state.heaters_on = s.heaters_on;
            return Err(e);
        }
        let mut result: Result<(), SimError> = Ok(());
        while s.t < t_end_s {
            if stop.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                stats.interrupted = true;
                break;
            }
            if stop.pause_after_s.is_some_and(|p| s.t >= p) {
                stats.paused = true;
                break;
            }
            if let Err(e) = self.advance(&mut s, &mut stats, t_end_s, observer) {
                result = Err(e);
                break;
            }
        }
        stats.t_end_s = s.t;
        self.count_solver_work(&mut stats, factorizations_before, solves_before);
        stats.energy.stored_j = stored_energy_j(net, &y_start, &s.y);
        stats.final_temperatures_k = s.y.clone();
        self.leave(state, s, t_end_s);
        result?;
        observer
            .on_finish(&stats)
            .map_err(|source| SimError::Observer {
                t_s: state.t_s,
                source,
            })?;
        Ok(stats)
    }

    /// Leaves `state` at the end of a run to `t_end_s` with the loop's state `s` and the
    /// solver's memory: a valid start of the next run.
    fn leave(&mut self, state: &mut State, s: Stepping, t_end_s: f64) {
        self.runs += 1;
        state.t_s = s.t;
        state.temperatures_k = s.y;
        state.heaters_on = s.heaters_on;
        state.sunlit = s.sunlit;
        if !self.remembers {
            state.memory = None;
            return;
        }
        let mut schedule = s.schedule;
        schedule.shadow_horizon_s = schedule.shadow_horizon_s.max(t_end_s);
        state.memory = Some(Memory {
            step_s: s.h,
            restart_steps_s: s.restart,
            event_class: s.event_class,
            schedule,
            modes_active: s.modes_active,
            mesh_flags: s.mesh_flags,
            stepper: self.stepper.memory(),
            made_by: (self.id, self.runs),
            model_print: self.fingerprint(),
            left: (
                state.t_s,
                state.temperatures_k.clone(),
                state.heaters_on.clone(),
                state.sunlit,
            ),
        });
    }

    /// One step of the loop: toward the next event, accepted (observers see it) or
    /// retried shorter, then the events at its end and the next step size. An error
    /// ends the run (after the step size, kept in the state it leaves).
    fn advance<O: Observer>(
        &mut self,
        s: &mut Stepping,
        stats: &mut RunStats,
        t_end_s: f64,
        observer: &mut O,
    ) -> Result<(), SimError> {
        let next = s.schedule.next(&self.breakpoints, t_end_s);
        let Some(tried) = self.try_step(s, stats, next)? else {
            return Ok(()); // retried shorter
        };
        self.accept(s, stats, &tried, observer)?;
        let class_before_step = s.event_class.take();
        let events = s.pass_events(
            self.model,
            &self.breakpoints,
            &self.kinks,
            &tried,
            stats,
            t_end_s,
            observer,
        );
        if s.event_class.is_none() {
            self.stepper.continue_from_last_end();
        }
        s.h = if self.settings.adaptive {
            next_step_s(
                tried.err,
                tried.h_s,
                s.h,
                tried.lands || tried.switched.is_some(),
                class_before_step,
                s.event_class,
                &mut s.restart,
            )
        } else {
            self.settings.max_step_s
        };
        events
    }

    /// The step from `s.t` toward `next` (modes as at its middle), cut at the earliest
    /// thermostat switch inside it. None when it was refused and is to be retried
    /// shorter (`s.h` set): a failed solve (a quarter as long), an error over the
    /// tolerance, a value below 0 K. An error when it cannot be shortened further.
    fn try_step(
        &mut self,
        s: &mut Stepping,
        stats: &mut RunStats,
        next: NextEvent,
    ) -> Result<Option<Tried>, SimError> {
        let (model, settings) = (self.model, &self.settings);
        let (net, env) = (&model.network, &model.environment);
        let stepper = &mut self.stepper;
        let (t, sunlit) = (s.t, s.sunlit);
        let (mut h_try, mut lands) = plan_step(s.h.min(settings.max_step_s), next.t_s - t);
        let phase_time = t + 0.5 * h_try;
        for (a, m) in s.modes_active.iter_mut().zip(&model.modes) {
            *a = m.active(phase_time);
        }
        let env_at = |tt: f64| env.state_with(tt, sunlit);
        let sw = StepSwitches {
            heaters_on: &s.heaters_on,
            modes_active: &s.modes_active,
        };
        if let Err(e) = stepper.step(model, &env_at, sw, t, &s.y, h_try) {
            if h_try * 0.25 < MIN_STEP_S {
                return Err(if let StepFailure::NonPhysical { node } = e {
                    SimError::NonPhysical {
                        node: net.nodes[node].name.clone(),
                        t_s: t + h_try,
                        temperature_k: stepper.data.temps1_k[node],
                        cause: likely_cause(model, &s.y, t, node, h_try, settings.adaptive),
                    }
                } else {
                    SimError::StepFailed {
                        t_s: t,
                        h_s: h_try,
                        cause: e,
                    }
                });
            }
            s.h = h_try * 0.25;
            stats.rejected_steps += 1;
            return Ok(None);
        }
        stats.newton_iterations += stepper.data.newton_iterations as u64;
        // Error control: a step over the tolerance is retried shorter.
        let err = stepper.data.error_max_k() / settings.tolerance_k;
        if settings.adaptive && err > 1.0 && h_try > 1e3 * MIN_STEP_S {
            s.h = h_try
                * (STEP_SAFETY * err.powf(STEP_ERROR_EXPONENT))
                    .clamp(REJECTED_STEP_FACTOR_RANGE.0, REJECTED_STEP_FACTOR_RANGE.1);
            stats.rejected_steps += 1;
            return Ok(None);
        }
        // Thermostats: land on the earliest switching time inside the step.
        let switch = earliest_thermostat_switch(net, &s.heaters_on, &stepper.data);
        if let Some((_, f)) = switch
            && f * h_try > MIN_STEP_S
            && f < 1.0
        {
            h_try *= f;
            lands = false;
            stepper
                .step(model, &env_at, sw, t, &s.y, h_try)
                .map_err(|cause| SimError::StepFailed {
                    t_s: t,
                    h_s: h_try,
                    cause,
                })?;
            stats.newton_iterations += stepper.data.newton_iterations as u64;
        }
        // Every output (step ends, and the interpolant observers sample between them)
        // must stay within 0 … 10 000 K. An adaptive run retries with a shorter step; a
        // fixed-step run cannot, and ends with the node, the time and the likely cause.
        if let Some((i, f, v)) = first_nonphysical(&stepper.data) {
            let h_now = stepper.data.h_s;
            // Below 0 K a shorter step can help; a run-away to 10 000 K cannot.
            if v <= 0.0 && settings.adaptive && h_now * 0.5 > MIN_STEP_S {
                s.h = h_now * 0.5;
                stats.rejected_steps += 1;
                return Ok(None);
            }
            return Err(SimError::NonPhysical {
                node: net.nodes[i].name.clone(),
                t_s: t + f * h_now,
                temperature_k: v,
                cause: likely_cause(model, &s.y, t, i, h_now, settings.adaptive),
            });
        }
        Ok(Some(Tried {
            h_s: h_try,
            lands,
            next,
            err,
            switched: switch.map(|(k, _)| k),
        }))
    }

    /// The step `tried` accepted: its end time (the event it lands on), the energy
    /// balance and counts, the gear pairs at its end; observers see it, then the mesh
    /// events at its end; the loop moves to its end.
    fn accept<O: Observer>(
        &mut self,
        s: &mut Stepping,
        stats: &mut RunStats,
        tried: &Tried,
        observer: &mut O,
    ) -> Result<(), SimError> {
        let (model, gears) = (self.model, self.gears);
        let t = s.t;
        let t_new = if tried.lands {
            tried.next.t_s
        } else {
            t + tried.h_s
        };
        if t_new <= t {
            return Err(SimError::TimeResolution { t_s: t });
        }
        let stepper = &mut self.stepper;
        stepper.data.h_s = t_new - t;
        accumulate_energy(&mut stats.energy, &stepper.data);
        stats.steps += 1;
        if !s.sunlit {
            stats.eclipse_time_s += t_new - t;
        }
        for (m, g) in self.mesh.iter_mut().zip(gears) {
            *m = mesh_or_nan(g, &stepper.data.temps1_k);
        }
        // The stepper's loads are those of the step's end (its last stage), which is
        // what observers see.
        let view = StepView {
            index: stats.steps,
            data: &stepper.data,
            // the step's last stage was at its end (unless it landed a rounding away)
            env1: match stepper.env_end {
                Some(e) if e.t_s.to_bits() == t_new.to_bits() && e.sunlit == s.sunlit => e,
                _ => model.environment.state_with(t_new, s.sunlit),
            },
            heaters_on: &s.heaters_on,
            modes_active: &s.modes_active,
            load_w: &stepper.compiled.each_load_w,
            mesh: &self.mesh,
            probe: Probe {
                model,
                gears,
                work: &self.probe_work,
            },
        };
        observer
            .on_step(&view)
            .map_err(|source| SimError::Observer { t_s: t_new, source })?;
        mesh_events(&self.mesh, &mut s.mesh_flags, t_new, observer)?;
        s.t = t_new;
        s.y.copy_from_slice(&stepper.data.temps1_k);
        Ok(())
    }
}

/// The step loop's state between steps (what a run leaves in its [`State`] and
/// memory).
struct Stepping {
    t: f64,
    y: Vec<f64>,
    heaters_on: Vec<bool>,
    sunlit: bool,
    /// The controller's step, s.
    h: f64,
    restart: RestartSteps,
    /// The class of the events the last step landed on: the next step starts from its
    /// restart step.
    event_class: Option<EventClass>,
    schedule: EventSchedule,
    modes_active: Vec<bool>,
    mesh_flags: Vec<MeshFlags>,
}

/// The events no step crosses, after the loop's time: the next shadow crossing (time,
/// entering), searched up to `shadow_horizon_s`; the next table point or mode edge, an
/// index into the setup's sorted breakpoints; the next load kink.
#[derive(Debug, Clone, PartialEq)]
struct EventSchedule {
    next_shadow: Option<(f64, bool)>,
    shadow_horizon_s: f64,
    next_breakpoint: usize,
    t_kink_s: f64,
}

/// The next event a step must land on, and when the next shadow crossing is.
#[derive(Debug, Clone, Copy)]
struct NextEvent {
    t_s: f64,
    shadow_s: f64,
}

impl EventSchedule {
    /// The earliest of the next shadow crossing, table point or mode edge (before the
    /// end), load kink and the run's end.
    fn next(&self, breakpoints: &[f64], t_end_s: f64) -> NextEvent {
        let shadow_s = self.next_shadow.map_or(f64::INFINITY, |(ts, _)| ts);
        let t_bp = breakpoints
            .get(self.next_breakpoint)
            .copied()
            .filter(|&b| b < t_end_s)
            .unwrap_or(f64::INFINITY);
        NextEvent {
            t_s: shadow_s.min(t_bp).min(self.t_kink_s).min(t_end_s),
            shadow_s,
        }
    }
}

/// A step tried and not refused: its length, whether it lands on `next`, its error
/// ratio (error / tolerance) and the heater whose thermostat switches at its end.
struct Tried {
    h_s: f64,
    lands: bool,
    next: NextEvent,
    err: f64,
    switched: Option<usize>,
}

impl Stepping {
    /// The events at the loop's time after the step `tried`: a shadow crossing it
    /// landed on, load kinks, table points and mode edges passed, modes starting or
    /// ending, the heater whose thermostat switched. Each is emitted to `observer`; the
    /// class of the event whose restart step is shortest is kept for the next step. Every
    /// event is emitted and counted even when one observer call fails; the first error
    /// is returned.
    #[allow(clippy::too_many_arguments)]
    fn pass_events<O: Observer>(
        &mut self,
        model: &ThermalModel,
        breakpoints: &[f64],
        kinks: &[LoadKink],
        tried: &Tried,
        stats: &mut RunStats,
        t_end_s: f64,
        observer: &mut O,
    ) -> Result<(), SimError> {
        let env = &model.environment;
        let t = self.t;
        let restart = self.restart;
        let mark = |class: EventClass, slot: &mut Option<EventClass>| {
            // the class whose restart step is shortest wins when events coincide
            if slot.is_none_or(|c| restart[class] < restart[c]) {
                *slot = Some(class);
            }
        };
        let mut events = Ok(());
        let schedule = &mut self.schedule;
        if tried.lands && tried.next.t_s == tried.next.shadow_s {
            let (_, entering) = schedule.next_shadow.expect("shadow event");
            self.sunlit = !entering;
            let (kind, class) = if entering {
                stats.eclipse_entries += 1;
                (EventKind::EclipseEntry, EventClass::EclipseEntry)
            } else {
                (EventKind::EclipseExit, EventClass::EclipseExit)
            };
            events = events.and(emit(observer, t, kind));
            schedule.next_shadow = env.next_shadow_crossing(t, t_end_s);
            mark(class, &mut self.event_class);
        }
        if t >= schedule.t_kink_s {
            schedule.t_kink_s = env.next_load_kink(t, kinks);
            mark(EventClass::Other, &mut self.event_class);
        }
        while breakpoints
            .get(schedule.next_breakpoint)
            .is_some_and(|&b| b <= t)
        {
            schedule.next_breakpoint += 1;
            mark(EventClass::Other, &mut self.event_class);
        }
        for (k, m) in model.modes.iter().enumerate() {
            let now = m.active(t + 1e-9 * (1.0 + t));
            if now != self.modes_active[k] {
                let kind = if now {
                    EventKind::ModeStart(k)
                } else {
                    EventKind::ModeEnd(k)
                };
                events = events.and(emit(observer, t, kind));
            }
        }
        if let Some(k) = tried.switched {
            self.heaters_on[k] = !self.heaters_on[k];
            stats.heater_switches += 1;
            mark(EventClass::HeaterSwitch, &mut self.event_class);
            let kind = if self.heaters_on[k] {
                EventKind::HeaterOn(k)
            } else {
                EventKind::HeaterOff(k)
            };
            events = events.and(emit(observer, t, kind));
        }
        events
    }
}

/// The energy the diffusion nodes of `net` gained from `y_start_k` to `y_k`, J.
fn stored_energy_j(net: &Network, y_start_k: &[f64], y_k: &[f64]) -> f64 {
    net.nodes
        .iter()
        .zip(y_k.iter().zip(y_start_k))
        .map(|(nd, (&yt, &y0))| nd.capacitance_j_per_k * (yt - y0))
        .sum()
}

/// The step to try toward the next event `dt_event_s` ahead, from the controller's
/// step `h_s`: land on the event when the step reaches it or would stop within 10 %
/// of a step short of it (then `true`); halve the way when two steps would reach it,
/// so that no sliver of a step is left before it.
fn plan_step(h_s: f64, dt_event_s: f64) -> (f64, bool) {
    if h_s >= dt_event_s || dt_event_s - h_s < 0.1 * h_s {
        (dt_event_s, true)
    } else if dt_event_s < 2.0 * h_s {
        (0.5 * dt_event_s, false)
    } else {
        (h_s, false)
    }
}

/// The adaptive controller's next step after an accepted step `h_try_s` with error
/// ratio `err` (error / tolerance). A step cut short by an event (`cut_short`: it landed
/// on one or on a thermostat switch) says little about the next one, so it never
/// shrinks the controller's step `h_s`. The step after an event of a class starts from
/// that class's restart step, which the first step after it (`class_before_step`)
/// updates.
fn next_step_s(
    err: f64,
    h_try_s: f64,
    h_s: f64,
    cut_short: bool,
    class_before_step: Option<EventClass>,
    event_class: Option<EventClass>,
    h_after_event: &mut RestartSteps,
) -> f64 {
    let fac = if err > 0.0 {
        STEP_SAFETY * err.powf(STEP_ERROR_EXPONENT)
    } else {
        STEP_GROWTH_WITHOUT_ERROR
    };
    // Hold the step when it would grow by less than 20 %: the solver then reuses its
    // factorised iteration matrix.
    let fac = if (1.0..STEP_HOLD_BELOW_GROWTH).contains(&fac) {
        1.0
    } else {
        fac
    };
    let proposed = h_try_s * fac.clamp(STEP_FACTOR_RANGE.0, STEP_FACTOR_RANGE.1);
    if let Some(c) = class_before_step {
        h_after_event[c] = proposed;
    }
    let next = if cut_short {
        proposed.max(h_s)
    } else {
        proposed
    };
    match event_class {
        Some(c) => next.min(h_after_event[c]),
        None => next,
    }
}

/// Integrates `model` from t = 0 at its initial temperatures to `t_end_s`: a setup and
/// one run.
pub fn simulate<O: Observer>(
    model: &ThermalModel,
    gears: &[GearPair],
    settings: &SolverSettings,
    t_end_s: f64,
    observer: &mut O,
    cancel: Option<&AtomicBool>,
) -> Result<RunStats, SimError> {
    let mut setup = Setup::new(model, gears, settings);
    setup.remembers = false; // the state is dropped below
    let mut state = setup.initial_state();
    setup.run(
        &mut state,
        t_end_s,
        observer,
        Stop {
            cancel,
            pause_after_s: None,
        },
    )
}

fn emit<O: Observer>(observer: &mut O, t_s: f64, kind: EventKind) -> Result<(), SimError> {
    observer
        .on_event(&Event { t_s, kind })
        .map_err(|source| SimError::Observer { t_s, source })
}

/// The heater whose thermostat switches first within the step, and where (fraction of
/// the step, from the solver's cubic interpolant of the sensor node).
fn earliest_thermostat_switch(
    net: &crate::thermal::Network,
    heaters_on: &[bool],
    d: &StepData,
) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for (k, ht) in net.heaters.iter().enumerate() {
        let i = ht.sensor_node;
        let (target, crossed) = if heaters_on[k] {
            (ht.off_k, d.temps1_k[i] >= ht.off_k)
        } else {
            (ht.on_k, d.temps1_k[i] <= ht.on_k)
        };
        if !crossed {
            continue;
        }
        let g = |s: f64| d.temperature_at_fraction(i, s) - target;
        let s = first_root(&g, heaters_on[k]);
        if best.is_none_or(|(_, b)| s < b) {
            best = Some((k, s));
        }
    }
    best
}

/// A gear pair's state as its last events told it: below the smallest backlash
/// allowed, in interference, its mesh invalid.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct MeshFlags {
    margin_low: bool,
    interference: bool,
    invalid: bool,
}

impl MeshFlags {
    /// The flags of mesh state `m`.
    fn of(m: &MeshState) -> MeshFlags {
        let invalid = m.backlash_exact_m.is_nan();
        MeshFlags {
            margin_low: !invalid && m.margin_m < 0.0,
            interference: !invalid && m.backlash_exact_m <= 0.0,
            invalid,
        }
    }
}

/// Reports gear-pair state changes as events (pair `k`, in the order margin,
/// interference, validity; an invalid mesh is reported when it becomes invalid only)
/// and brings `flags` up to date.
fn mesh_events<O: Observer>(
    mesh: &[MeshState],
    flags: &mut [MeshFlags],
    t_s: f64,
    observer: &mut O,
) -> Result<(), SimError> {
    let emit = |observer: &mut O, kind| {
        observer
            .on_event(&Event { t_s, kind })
            .map_err(|source| SimError::Observer { t_s, source })
    };
    for (k, (m, f)) in mesh.iter().zip(flags.iter_mut()).enumerate() {
        let now = MeshFlags::of(m);
        // each flag follows before its event, so an observer's error leaves the flags
        // of the events it saw
        if f.margin_low != now.margin_low {
            f.margin_low = now.margin_low;
            let kind = if now.margin_low {
                EventKind::MarginLow(k)
            } else {
                EventKind::MarginRestored(k)
            };
            emit(observer, kind)?;
        }
        if f.interference != now.interference {
            f.interference = now.interference;
            let kind = if now.interference {
                EventKind::InterferenceStart(k)
            } else {
                EventKind::InterferenceEnd(k)
            };
            emit(observer, kind)?;
        }
        if f.invalid != now.invalid {
            f.invalid = now.invalid;
            if now.invalid {
                emit(observer, EventKind::MeshInvalid(k))?;
            }
        }
    }
    Ok(())
}

fn accumulate_energy(e: &mut EnergyBalance, d: &StepData) {
    let w = [W0 * d.h_s, W0 * d.h_s, W1 * d.h_s];
    for (fl, wk) in d.flows.iter().zip(w) {
        e.absorbed_j += wk * fl.absorbed_w;
        e.dissipated_j += wk * fl.dissipated_w;
        for (acc, q) in e.to_boundary_j.iter_mut().zip(&fl.to_boundary_w) {
            *acc += wk * q;
        }
    }
}

/// First s in (0, 1] where g changes sign from its value at 0 (rising through zero when
/// `rising`), found by a scan and bisection. Returns 1 when it only crosses at the end.
fn first_root(g: &dyn Fn(f64) -> f64, rising: bool) -> f64 {
    let past = |v: f64| if rising { v >= 0.0 } else { v <= 0.0 };
    let mut lo = 0.0;
    let scan = 16;
    for k in 1..=scan {
        let s = k as f64 / scan as f64;
        if past(g(s)) {
            let mut hi = s;
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if past(g(mid)) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return hi;
        }
        lo = s;
    }
    1.0
}

/// Most steps a run may take without `--force` (about a minute of solver time on a
/// small network, 400 years of the reference orbit).
pub const MAX_STEPS: f64 = 5e7;

/// A run's size, estimated before it starts (see [`estimate_run`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RunEstimate {
    /// Accepted steps the run will take.
    pub steps: f64,
    /// Wall time of the solver and gear evaluation, s (observers come on top).
    pub wall_s: f64,
    /// Simulated time and steps of the pilot stretch the estimate comes from (0 when
    /// the pilot failed and only the lower bound `t_end / max_step` is known).
    pub pilot_s: f64,
    pub pilot_steps: u64,
}

/// Steps and wall time of a run to `t_end_s`, extrapolated from a pilot stretch from
/// t = 0 (at most `pilot_end_s` of simulated time, 20 000 steps or 0.25 s of wall
/// time, checked after every step: one step of a very large network can take longer) observed by `observer` (pass the run's own in-memory observers, so that their
/// cost is counted), and never below `t_end_s / max_step_s`. The first orbit holds the
/// start-up transient, so the estimate errs on the high side (17 % more steps than a
/// 2000-orbit reference run takes). A pilot that fails is no estimate: the run itself
/// then reports the failure with its log.
pub fn estimate_run<O: Observer>(
    model: &ThermalModel,
    gears: &[GearPair],
    settings: &SolverSettings,
    t_end_s: f64,
    pilot_end_s: f64,
    observer: &mut O,
) -> RunEstimate {
    struct Budget<'a> {
        start: std::time::Instant,
        steps: u64,
        stop: &'a AtomicBool,
        /// End time of every pilot step (at most 20 000).
        times: Vec<f64>,
        /// When the first step and the last were seen: the wall time per step is
        /// taken between them, without the setup before the first.
        first_last: Option<(std::time::Instant, std::time::Instant)>,
    }
    impl Observer for Budget<'_> {
        fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
            self.steps += 1;
            self.times.push(step.t1_s());
            let now = std::time::Instant::now();
            self.first_last = Some((self.first_last.map_or(now, |f| f.0), now));
            if self.steps >= 20_000 || now.duration_since(self.start).as_secs_f64() > 0.25 {
                self.stop.store(true, Ordering::Relaxed);
            }
            Ok(())
        }
    }
    let lower = t_end_s / settings.max_step_s;
    let pilot_end = pilot_end_s.min(t_end_s);
    // A real orbit's table for the pilot, timed apart from the steps: its cost grows
    // with the run's days, not with its steps (counted per day below, the days shared
    // by the cores as `TleOrbit::check_until` shares them). An error is the pilot's to
    // report.
    let table_start = std::time::Instant::now();
    let _ = check_span(&model.environment, 0.0, pilot_end);
    let table_per_day_s = match &model.environment {
        crate::orbit::Environment::Dated(_) => {
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            table_start.elapsed().as_secs_f64() / days_spanned(pilot_end) / cores as f64
        }
        _ => 0.0,
    };
    let stop = AtomicBool::new(false);
    let mut budget = Budget {
        start: std::time::Instant::now(),
        steps: 0,
        stop: &stop,
        times: Vec::with_capacity(20_000),
        first_last: None,
    };
    match simulate(
        model,
        gears,
        settings,
        pilot_end,
        &mut (&mut budget, observer),
        Some(&stop),
    ) {
        Ok(stats) if stats.t_end_s > 0.0 && stats.steps > 0 => {
            // per step between the first step and the last (with one step, from the
            // start: setup included, erring high)
            let per_step_s = match budget.first_last {
                Some((f, l)) if stats.steps > 1 => {
                    l.duration_since(f).as_secs_f64() / (stats.steps - 1) as f64
                }
                _ => budget.start.elapsed().as_secs_f64() / stats.steps as f64,
            };
            let n = budget.times.len();
            let steps = if stats.t_end_s < pilot_end && n >= 8 {
                // Stopped early (the step or time budget): the rest goes at the pace of
                // the pilot's last quarter, so a thermostat that starts chattering
                // during the pilot counts at its chattering pace.
                let t_q = budget.times[n - n / 4 - 1];
                let span = (stats.t_end_s - t_q).max(f64::MIN_POSITIVE);
                let pace = (n / 4) as f64 / span;
                let average = stats.steps as f64 / stats.t_end_s;
                stats.steps as f64 + (t_end_s - stats.t_end_s) * pace.max(average)
            } else {
                stats.steps as f64 * (t_end_s / stats.t_end_s)
            }
            .max(lower);
            RunEstimate {
                steps,
                wall_s: per_step_s * steps + table_per_day_s * days_spanned(t_end_s),
                pilot_s: stats.t_end_s,
                pilot_steps: stats.steps,
            }
        }
        _ => RunEstimate {
            steps: lower,
            wall_s: f64::NAN,
            pilot_s: 0.0,
            pilot_steps: 0,
        },
    }
}

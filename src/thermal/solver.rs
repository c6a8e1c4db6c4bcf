//! TR-BDF2 (Bank et al. 1985; Hosea & Shampine 1996): a one-step, L-stable,
//! second-order implicit Runge–Kutta method for C dT/dt = f(t, T).
//!
//! Stage 1 is the trapezoidal rule to t + γh, stage 2 the BDF2 formula through
//! t, t + γh and t + h, with γ = 2 − √2 so that both stages share one iteration
//! matrix W = C − (γ/2) h J. Radiation makes f non-linear: each stage is solved by
//! Newton iterations with the Jacobian taken at the start of the step.
//!
//! The local error estimate is the method's leading term
//! (−3γ² + 4γ − 2)/(12(2 − γ)) h³ T''' with T''' from the divided difference of
//! dT/dt over the three stage points, filtered through W⁻¹C as Hosea and Shampine
//! recommend so that stiff components do not inflate it.

// Index loops over nodes mirror the equations of the method; kept as they are.
#![allow(clippy::needless_range_loop)]

use super::iteration::{IterationMatrix, LinearSolver};
use super::{Compiled, Flows, StepSwitches, ThermalModel};
use crate::orbit::EnvState;

/// γ = 2 − √2.
pub const GAMMA: f64 = 2.0 - std::f64::consts::SQRT_2;
const D: f64 = GAMMA / 2.0;
/// BDF2 stage: T1 = A Tγ − B T0 + D h F1 (note (1−γ)/(2−γ) = γ/2 = D).
const A: f64 = 1.0 / (GAMMA * (2.0 - GAMMA));
const B: f64 = (1.0 - GAMMA) * (1.0 - GAMMA) / (GAMMA * (2.0 - GAMMA));
/// Quadrature weights of the whole step: T1 = T0 + h (W0 F0 + W0 Fγ + W1 F1).
pub const W0: f64 = 1.0 / (2.0 * (2.0 - GAMMA));
pub const W1: f64 = (1.0 - GAMMA) / (2.0 - GAMMA);
const ERR_CONST: f64 = (-3.0 * GAMMA * GAMMA + 4.0 * GAMMA - 2.0) / (12.0 * (2.0 - GAMMA));

/// Newton iterations stop when the update is below this fraction of the step
/// tolerance (and never below 1e-9 K).
const NEWTON_TOL_FRACTION: f64 = 1e-2;
const NEWTON_MAX_ITER: usize = 12;
/// Newton's contraction rate assumed before the first iteration.
const INITIAL_THETA: f64 = 0.5;
/// Re-evaluate the Jacobian when Newton contracts slower than this.
const JACOBIAN_REFRESH_THETA: f64 = 0.02;

#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum StepFailure {
    #[error("Newton iterations did not converge")]
    NewtonDiverged,
    #[error("iteration matrix is singular")]
    Singular,
    #[error("the temperature of node index {node} became non-finite or non-positive")]
    NonPhysical { node: usize },
}

/// Stopping rule of the simplified Newton iterations (Hairer & Wanner, Solving
/// ODEs II, §IV.8): with contraction rate θ estimated from successive updates, the
/// remaining error is about θ/(1 − θ)·|Δ|; stop when that is below the tolerance.
#[derive(Debug, Clone, Copy)]
struct NewtonMonitor {
    tol_k: f64,
    theta: f64,
    last_k: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Newton {
    Converged,
    Continue,
    Diverged,
}

impl NewtonMonitor {
    fn new(tol_k: f64, theta_guess: f64) -> NewtonMonitor {
        NewtonMonitor {
            tol_k,
            theta: theta_guess,
            last_k: f64::INFINITY,
        }
    }

    fn update(&mut self, iteration: usize, dmax_k: f64) -> Newton {
        if iteration > 0 {
            self.theta = dmax_k / self.last_k;
            if self.theta >= 0.9 || !dmax_k.is_finite() {
                return Newton::Diverged;
            }
        }
        self.last_k = dmax_k;
        let theta = self.theta.clamp(1e-3, 0.5);
        if dmax_k <= 1e-12 || theta / (1.0 - theta) * dmax_k <= self.tol_k {
            Newton::Converged
        } else if iteration + 1 >= NEWTON_MAX_ITER {
            Newton::Diverged
        } else {
            Newton::Continue
        }
    }
}

/// One accepted or rejected trial step, with everything observers and the energy
/// bookkeeping need. Buffers are owned by the stepper and reused.
#[derive(Debug, Clone, Default)]
pub struct StepData {
    pub t0_s: f64,
    pub h_s: f64,
    pub temps0_k: Vec<f64>,
    pub temps1_k: Vec<f64>,
    /// dT/dt at the start and end of the step, K/s.
    pub rates0_k_per_s: Vec<f64>,
    pub rates1_k_per_s: Vec<f64>,
    /// Network heat flows at the three stage points.
    pub flows: [Flows; 3],
    /// Local error estimate per node, K.
    pub error_k: Vec<f64>,
    pub newton_iterations: usize,
    /// Stage values at t0 + γh, K.
    pub temps_gamma_k: Vec<f64>,
    /// Per node: interpolate with the quadratic through the three stage values instead
    /// of the cubic Hermite of the end values and rates. Set for a node much faster than
    /// the step (a thin film, a small part stiffly coupled): its end rates are those of
    /// the fast transient the L-stable method damps, not of the smooth solution, and the
    /// cubic would overshoot by hundreds of kelvin. Detected when the cubic misses the
    /// stage value at t0 + γh by more than the step tolerance.
    pub quadratic: Vec<bool>,
}

impl StepData {
    /// Temperature of node `i` at fraction `s` ∈ [0, 1] of the step, K: the cubic
    /// Hermite interpolant of the end values and rates, or for a node marked
    /// `quadratic` the quadratic through the stage values.
    pub fn temperature_at_fraction(&self, i: usize, s: f64) -> f64 {
        if self.quadratic[i] {
            quadratic(self.temps0_k[i], self.temps_gamma_k[i], self.temps1_k[i], s)
        } else {
            hermite(
                self.temps0_k[i],
                self.temps1_k[i],
                self.rates0_k_per_s[i],
                self.rates1_k_per_s[i],
                self.h_s,
                s,
            )
        }
    }

    /// Every node's temperature at fraction `s` ∈ [0, 1] of the step, K: the same
    /// numbers as [`StepData::temperature_at_fraction`] node by node, with the basis
    /// of the interpolants evaluated once.
    pub fn temperatures_at_fraction(&self, s: f64, out_k: &mut [f64]) {
        let (s2, h) = (s * s, self.h_s);
        let s3 = s2 * s;
        let (h00, h10, h01, h11) = (
            2.0 * s3 - 3.0 * s2 + 1.0,
            (s3 - 2.0 * s2 + s) * h,
            -2.0 * s3 + 3.0 * s2,
            (s3 - s2) * h,
        );
        let n = out_k.len();
        let (y0, y1) = (&self.temps0_k[..n], &self.temps1_k[..n]);
        let (d0, d1) = (&self.rates0_k_per_s[..n], &self.rates1_k_per_s[..n]);
        for i in 0..n {
            out_k[i] = if self.quadratic[i] {
                quadratic(y0[i], self.temps_gamma_k[i], y1[i], s)
            } else {
                h00 * y0[i] + h10 * d0[i] + h01 * y1[i] + h11 * d1[i]
            };
        }
    }

    /// dT/dt of node `i`'s interpolant at the start (`end` false) or the end of the
    /// step, K/s: the solver's rates for a cubic Hermite node, the quadratic's slope
    /// for a node marked `quadratic`.
    pub fn rate_at_edge(&self, i: usize, end: bool) -> f64 {
        if self.quadratic[i] {
            let [_, a1, a2, _] = self.polynomial(i);
            (if end { a1 + 2.0 * a2 } else { a1 }) / self.h_s
        } else if end {
            self.rates1_k_per_s[i]
        } else {
            self.rates0_k_per_s[i]
        }
    }

    /// Node `i`'s interpolant as a polynomial in the fraction s of the step:
    /// `[a0, a1, a2, a3]` with T(s) = a0 + a1 s + a2 s² + a3 s³ (a3 = 0 for a quadratic).
    pub fn polynomial(&self, i: usize) -> [f64; 4] {
        let (y0, y1) = (self.temps0_k[i], self.temps1_k[i]);
        if self.quadratic[i] {
            let (yg, g) = (self.temps_gamma_k[i], GAMMA);
            let c = ((yg - y0) / g - (y1 - y0)) / (g - 1.0);
            [y0, (y1 - y0) - c, c, 0.0]
        } else {
            let (d0, d1) = (
                self.h_s * self.rates0_k_per_s[i],
                self.h_s * self.rates1_k_per_s[i],
            );
            [
                y0,
                d0,
                3.0 * (y1 - y0) - 2.0 * d0 - d1,
                2.0 * (y0 - y1) + d0 + d1,
            ]
        }
    }

    /// Interior extrema (fraction of the step, value) of node `i`'s interpolant.
    pub fn interior_extrema(&self, i: usize) -> [Option<(f64, f64)>; 2] {
        let (y0, y1) = (self.temps0_k[i], self.temps1_k[i]);
        if self.quadratic[i] {
            // p(s) = y0 + b s + c s²: one extremum at −b / 2c.
            let yg = self.temps_gamma_k[i];
            let g = GAMMA;
            let c = ((yg - y0) / g - (y1 - y0)) / (g - 1.0);
            let b = (y1 - y0) - c;
            let s = -b / (2.0 * c);
            let inside = c != 0.0 && s > 0.0 && s < 1.0;
            return [inside.then(|| (s, quadratic(y0, yg, y1, s))), None];
        }
        let (dy0, dy1, h) = (self.rates0_k_per_s[i], self.rates1_k_per_s[i], self.h_s);
        hermite_interior_extrema_at(y0, y1, dy0, dy1, h)
            .map(|s| s.map(|s| (s, hermite(y0, y1, dy0, dy1, h, s))))
    }

    /// Largest |error| over all nodes, K.
    pub fn error_max_k(&self) -> f64 {
        self.error_k.iter().fold(0.0f64, |m, e| m.max(e.abs()))
    }
}

/// Reusable workspace of the implicit stepper.
pub struct Stepper {
    pub compiled: Compiled,
    cap: Vec<f64>,
    /// W = C − D h J and its factorisation (dense or sparse).
    matrix: IterationMatrix,
    f0: Vec<f64>,
    f: Vec<f64>,
    fg: Vec<f64>,
    yg: Vec<f64>,
    r: Vec<f64>,
    /// Right-hand side of the current stage.
    k: Vec<f64>,
    /// Contraction rate of the last Newton iteration, to judge the first update.
    theta: f64,
    newton_tol_k: f64,
    /// Largest miss of the cubic interpolant at t0 + γh before a node is interpolated
    /// by the quadratic through its stage values, K (the step tolerance).
    interpolant_tol_k: f64,
    /// The next step starts from the end of the last one, with the same switches.
    start_is_last_end: bool,
    /// Step size the current factorisation was made for (NaN: none).
    lu_h: f64,
    /// Temperatures the current Jacobian was evaluated at.
    jac_temps_k: Vec<f64>,
    /// The Jacobian must be re-evaluated before the next step.
    jac_stale: bool,
    /// Factorisations made (for statistics).
    pub factorizations: u64,
    /// The linear solver asked for, and the kind it gave at the start.
    linear_choice: LinearSolver,
    initial_linear: crate::thermal::iteration::LinearSolver,
    pub data: StepData,
    /// The environment of the last step's end (its last stage), for observers of that
    /// step, so that it is not evaluated again: set by every step that reaches its last
    /// stage, failed or not, so a reader checks its time and sunlit flag.
    pub env_end: Option<EnvState>,
}

impl Stepper {
    /// A stepper for `model` whose steps aim at a local error of `tolerance_k`, solving
    /// its linear systems as `linear` says.
    pub fn new(model: &ThermalModel, tolerance_k: f64, linear: LinearSolver) -> Stepper {
        let compiled = Compiled::new(&model.network);
        let n = compiled.n;
        let matrix = IterationMatrix::new(&compiled, linear);
        Stepper {
            cap: compiled.capacitance_j_per_k.clone(),
            linear_choice: linear,
            initial_linear: matrix.kind(),
            matrix,
            compiled,
            f0: vec![0.0; n],
            f: vec![0.0; n],
            fg: vec![0.0; n],
            yg: vec![0.0; n],
            r: vec![0.0; n],
            k: vec![0.0; n],
            theta: INITIAL_THETA,
            newton_tol_k: (NEWTON_TOL_FRACTION * tolerance_k).max(1e-9),
            interpolant_tol_k: tolerance_k,
            start_is_last_end: false,
            env_end: None,
            lu_h: f64::NAN,
            jac_temps_k: vec![0.0; n],
            jac_stale: true,
            factorizations: 0,
            data: StepData {
                temps0_k: vec![0.0; n],
                temps1_k: vec![0.0; n],
                rates0_k_per_s: vec![0.0; n],
                rates1_k_per_s: vec![0.0; n],
                error_k: vec![0.0; n],
                temps_gamma_k: vec![0.0; n],
                quadratic: vec![false; n],
                ..StepData::default()
            },
        }
    }

    /// Takes one TR-BDF2 step of size `h_s` from (`t0_s`, `temps0_k`). `env_at(t)`
    /// gives the environment at a stage time; the switches hold for the whole step.
    /// The result is in `self.data`.
    pub fn step(
        &mut self,
        model: &ThermalModel,
        env_at: &dyn Fn(f64) -> EnvState,
        sw: StepSwitches<'_>,
        t0_s: f64,
        temps0_k: &[f64],
        h_s: f64,
    ) -> Result<(), StepFailure> {
        let newton_tol_k = self.newton_tol_k;
        let n = self.compiled.n;
        self.data.t0_s = t0_s;
        self.data.h_s = h_s;
        self.data.newton_iterations = 0;
        self.data.temps0_k.copy_from_slice(temps0_k);

        // f0 and the iteration matrix W = C − D h J(T0).
        if self.start_is_last_end {
            // Nothing changed since the accepted step that ended here: f0 is its f1.
            std::mem::swap(&mut self.f0, &mut self.f);
            let [first, _, last] = &mut self.data.flows;
            std::mem::swap(first, last);
        } else {
            self.compiled.set_time(model, &env_at(t0_s), sw);
            self.compiled
                .heat_w(temps0_k, &mut self.f0, Some(&mut self.data.flows[0]));
        }
        self.start_is_last_end = false;
        // The iteration matrix is kept while the step size is unchanged and Newton
        // converges fast; the Jacobian only affects convergence, not the solution.
        if self.jac_stale {
            self.matrix.set_jacobian(&self.compiled, temps0_k);
            self.jac_temps_k.copy_from_slice(temps0_k);
            self.jac_stale = false;
            self.lu_h = f64::NAN;
        }
        if self.lu_h != h_s {
            self.factorizations += 1;
            if self.matrix.factor(&self.cap, D * h_s).is_err() {
                self.jac_stale = true;
                return Err(StepFailure::Singular);
            }
            self.lu_h = h_s;
        }
        for i in 0..n {
            self.data.rates0_k_per_s[i] = self.f0[i] / self.cap[i];
        }

        // Stage 1: trapezoidal rule to t0 + γh: C yγ − D h f(yγ) = C y0 + D h f0.
        self.compiled
            .set_time(model, &env_at(t0_s + GAMMA * h_s), sw);
        for i in 0..n {
            self.yg[i] = temps0_k[i] + GAMMA * h_s * self.data.rates0_k_per_s[i];
            self.k[i] = self.cap[i] * temps0_k[i] + D * h_s * self.f0[i];
        }
        let mut monitor = NewtonMonitor::new(newton_tol_k, self.theta);
        if !self.newton(StageTarget::Gamma, D * h_s, &mut monitor) {
            self.jac_stale = true;
            return Err(StepFailure::NewtonDiverged);
        }
        self.compiled
            .heat_w(&self.yg, &mut self.fg, Some(&mut self.data.flows[1]));

        // Stage 2: BDF2 to t0 + h: C y1 − D h f(y1) = C (A yγ − B y0).
        let env_end = env_at(t0_s + h_s);
        self.compiled.set_time(model, &env_end, sw);
        self.env_end = Some(env_end);
        for i in 0..n {
            self.data.temps1_k[i] = temps0_k[i] + (self.yg[i] - temps0_k[i]) / GAMMA;
            self.k[i] = self.cap[i] * (A * self.yg[i] - B * temps0_k[i]);
        }
        monitor = NewtonMonitor::new(newton_tol_k, monitor.theta);
        if !self.newton(StageTarget::End, D * h_s, &mut monitor) {
            self.jac_stale = true;
            return Err(StepFailure::NewtonDiverged);
        }
        self.theta = monitor.theta;
        if self.theta > JACOBIAN_REFRESH_THETA {
            self.jac_stale = true;
        }
        if let Some(node) = self
            .data
            .temps1_k
            .iter()
            .position(|&t| !(t.is_finite() && t > 0.0))
        {
            return Err(StepFailure::NonPhysical { node });
        }
        self.compiled.heat_w(
            &self.data.temps1_k,
            &mut self.f,
            Some(&mut self.data.flows[2]),
        );

        // Error estimate, filtered: e = W⁻¹ C (ERR_CONST · 2h ((F1 − Fγ)/(1−γ) − (Fγ − F0)/γ)).
        for i in 0..n {
            let f1 = self.f[i] / self.cap[i];
            let fg = self.fg[i] / self.cap[i];
            let f0 = self.data.rates0_k_per_s[i];
            self.data.rates1_k_per_s[i] = f1;
            let (y0, yg, y1) = (temps0_k[i], self.yg[i], self.data.temps1_k[i]);
            self.data.temps_gamma_k[i] = yg;
            self.data.quadratic[i] =
                (hermite(y0, y1, f0, f1, h_s, GAMMA) - yg).abs() > self.interpolant_tol_k;
            let raw = ERR_CONST * 2.0 * h_s * ((f1 - fg) / (1.0 - GAMMA) - (fg - f0) / GAMMA);
            self.data.error_k[i] = self.cap[i] * raw;
        }
        self.matrix.solve(&mut self.data.error_k);
        Ok(())
    }
}

impl Stepper {
    /// Dense, sparse or iterative: how this stepper solves its linear systems.
    pub fn linear_solver(&self) -> crate::thermal::iteration::LinearSolver {
        self.matrix.kind()
    }

    /// (linear solves, Krylov iterations) so far (iterative solver only).
    pub fn solve_counts(&self) -> (u64, u64) {
        self.matrix.solve_counts()
    }

    /// Declares that the next step starts where the last successful one ended, with
    /// the same loads and switches, so its start values can be reused. The caller must
    /// not call this after a rejected step or an event.
    pub fn continue_from_last_end(&mut self) {
        self.start_is_last_end = true;
    }
}

/// What the stepper carries from one step to the next besides the temperatures: where
/// its Jacobian was taken, the step its iteration matrix was factorised for, Newton's
/// last contraction rate and, when the next step starts where the last ended, the heat
/// flows there. A run that ends hands this on in its state, so that a run resumed from
/// that state takes bit for bit the steps the unsplit run would have taken.
#[derive(Debug, Clone, PartialEq)]
pub struct StepperMemory {
    jacobian_at_k: Option<Vec<f64>>,
    factored_step_s: f64,
    theta: f64,
    last_end: Option<(Vec<f64>, Flows)>,
    /// The linear solver in use: an iterative solver may have turned to the sparse LU.
    linear: crate::thermal::iteration::LinearSolver,
}

impl StepperMemory {
    fn fresh(linear: crate::thermal::iteration::LinearSolver) -> StepperMemory {
        StepperMemory {
            jacobian_at_k: None,
            factored_step_s: f64::NAN,
            theta: INITIAL_THETA,
            last_end: None,
            linear,
        }
    }
}

impl Stepper {
    /// The memory of a stepper just built: what a fresh run starts from.
    pub fn fresh_memory(&self) -> StepperMemory {
        StepperMemory::fresh(self.initial_linear)
    }

    /// The memory to resume from (see [`StepperMemory`]).
    pub fn memory(&self) -> StepperMemory {
        StepperMemory {
            jacobian_at_k: (!self.jac_stale).then(|| self.jac_temps_k.clone()),
            factored_step_s: if self.jac_stale { f64::NAN } else { self.lu_h },
            theta: self.theta,
            last_end: self
                .start_is_last_end
                .then(|| (self.f.clone(), self.data.flows[2].clone())),
            linear: self.matrix.kind(),
        }
    }

    /// Puts the stepper in the state `m` describes: the Jacobian evaluated again at the
    /// same temperatures and factorised for the same step, which gives the same bits.
    pub fn restore(&mut self, m: &StepperMemory) {
        if m.linear != self.matrix.kind() {
            if m.linear == crate::thermal::iteration::LinearSolver::Sparse {
                self.matrix.turn_sparse(&self.compiled);
            } else {
                self.matrix = IterationMatrix::new(&self.compiled, self.linear_choice);
            }
        }
        self.theta = m.theta;
        self.lu_h = f64::NAN;
        self.jac_stale = true;
        if let Some(temps) = &m.jacobian_at_k {
            self.matrix.set_jacobian(&self.compiled, temps);
            self.jac_temps_k.copy_from_slice(temps);
            self.jac_stale = false;
            if m.factored_step_s.is_finite() {
                if self.matrix.factor(&self.cap, D * m.factored_step_s).is_ok() {
                    self.lu_h = m.factored_step_s;
                } else {
                    self.jac_stale = true;
                }
            }
        }
        self.start_is_last_end = false;
        if let Some((f, flows)) = &m.last_end {
            self.f.copy_from_slice(f);
            self.data.flows[2].clone_from(flows);
            self.start_is_last_end = true;
        }
    }
}

/// Which stage value a Newton solve updates.
#[derive(Debug, Clone, Copy)]
enum StageTarget {
    /// y at t0 + γh (`Stepper::yg`).
    Gamma,
    /// y at t0 + h (`StepData::temps1_k`).
    End,
}

impl Stepper {
    /// One implicit stage: solves C y − dh f(y) = k (k in `self.k`) for y, from the
    /// guess already in place, by simplified Newton iterations with the factorised
    /// iteration matrix C − dh J. False when Newton does not converge.
    fn newton(&mut self, target: StageTarget, dh: f64, monitor: &mut NewtonMonitor) -> bool {
        let y = match target {
            StageTarget::Gamma => &mut self.yg,
            StageTarget::End => &mut self.data.temps1_k,
        };
        for it in 0..NEWTON_MAX_ITER {
            self.data.newton_iterations += 1;
            self.compiled.heat_w(y, &mut self.f, None);
            for i in 0..y.len() {
                self.r[i] = self.k[i] - (self.cap[i] * y[i] - dh * self.f[i]);
            }
            self.matrix.solve(&mut self.r);
            let mut dmax = 0.0f64;
            for i in 0..y.len() {
                y[i] += self.r[i];
                dmax = dmax.max(self.r[i].abs());
            }
            match monitor.update(it, dmax) {
                Newton::Converged => return true,
                Newton::Diverged => return false,
                Newton::Continue => {}
            }
        }
        false
    }
}

/// Cubic Hermite interpolation on [0, 1] of one component: value at `s`.
pub fn hermite(y0: f64, y1: f64, dy0: f64, dy1: f64, h: f64, s: f64) -> f64 {
    let s2 = s * s;
    let s3 = s2 * s;
    (2.0 * s3 - 3.0 * s2 + 1.0) * y0
        + (s3 - 2.0 * s2 + s) * h * dy0
        + (-2.0 * s3 + 3.0 * s2) * y1
        + (s3 - s2) * h * dy1
}

/// The quadratic through (0, y0), (γ, yγ), (1, y1), at `s`.
pub fn quadratic(y0: f64, yg: f64, y1: f64, s: f64) -> f64 {
    let g = GAMMA;
    y0 * (s - g) * (s - 1.0) / g
        + yg * s * (s - 1.0) / (g * (g - 1.0))
        + y1 * s * (s - g) / (1.0 - g)
}

/// Interior extrema (s in (0,1)) of the cubic Hermite interpolant, as values.
pub fn hermite_interior_extrema(y0: f64, y1: f64, dy0: f64, dy1: f64, h: f64) -> [Option<f64>; 2] {
    hermite_interior_extrema_at(y0, y1, dy0, dy1, h)
        .map(|s| s.map(|s| hermite(y0, y1, dy0, dy1, h, s)))
}

/// Where (s in (0,1)) the cubic Hermite interpolant has its interior extrema.
pub fn hermite_interior_extrema_at(
    y0: f64,
    y1: f64,
    dy0: f64,
    dy1: f64,
    h: f64,
) -> [Option<f64>; 2] {
    // p'(s) = a s² + b s + c
    let m0 = h * dy0;
    let m1 = h * dy1;
    let a = 6.0 * y0 + 3.0 * m0 - 6.0 * y1 + 3.0 * m1;
    let b = -6.0 * y0 - 4.0 * m0 + 6.0 * y1 - 2.0 * m1;
    let c = m0;
    let mut out = [None, None];
    let mut push = |s: f64, k: usize| {
        if s > 0.0 && s < 1.0 {
            out[k] = Some(s);
        }
    };
    if a.abs() < 1e-300 {
        if b.abs() > 1e-300 {
            push(-c / b, 0);
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            push(q / a, 0);
            if q != 0.0 {
                push(c / q, 1);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_tr_bdf2_coefficients_are_consistent() {
        assert!((A - B - 1.0).abs() < 1e-15);
        assert!((2.0 * W0 + W1 - 1.0).abs() < 1e-15);
        assert!(((1.0 - GAMMA) / (2.0 - GAMMA) - D).abs() < 1e-15);
    }

    #[test]
    fn val_closed_form_hermite_reproduces_cubic() {
        // p(t) = t³ − 2t on [1, 3]
        let p = |t: f64| t * t * t - 2.0 * t;
        let dp = |t: f64| 3.0 * t * t - 2.0;
        let (t0, h) = (1.0, 2.0);
        for s in [0.0, 0.3, 0.5, 1.0] {
            let v = hermite(p(t0), p(t0 + h), dp(t0), dp(t0 + h), h, s);
            assert!((v - p(t0 + s * h)).abs() < 1e-12);
        }
        // p on [-2, 2] has extrema at ±√(2/3)
        let (t0, h) = (-2.0, 4.0);
        let ex = hermite_interior_extrema(p(t0), p(t0 + h), dp(t0), dp(t0 + h), h);
        let r = (2.0f64 / 3.0).sqrt();
        let mut got: Vec<f64> = ex.iter().flatten().copied().collect();
        got.sort_by(f64::total_cmp);
        assert_eq!(got.len(), 2);
        assert!((got[0] - p(r)).abs() < 1e-12 && (got[1] - p(-r)).abs() < 1e-12);
    }
}

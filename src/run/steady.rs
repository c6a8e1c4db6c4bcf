//! The orbit-periodic solution of a scenario whose environment repeats every orbit:
//! the start-of-orbit temperatures x with Φ(x) = x, Φ the one-orbit map (run one period
//! from x). Found by Newton shooting on F(x) = Φ(x) − x with the monodromy matrix ∂Φ/∂x
//! from finite differences (one warm orbit per node), falling back to marching orbit
//! after orbit when Newton does not converge (thermostats make Φ piecewise smooth) or
//! the network is too large for a dense monodromy.

use nalgebra::{DMatrix, DVector};

use crate::run::sim::{Setup, SimError, State, Stop};

/// Which way to the periodic orbit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Newton when marching looks slower than a few monodromy matrices (from how fast
    /// the warm-up orbits contract), else marching.
    Auto,
    /// Newton shooting (marching if it fails to converge).
    Newton,
    /// Marching only.
    Marching,
}

/// How hard to try.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyOptions {
    pub method: Method,
    /// Converged when every node returns within this, K.
    pub tolerance_k: f64,
    /// Orbits marched before Newton starts (from the given state).
    pub warmup_orbits: u64,
    pub max_newton_iterations: u32,
    /// Most orbits in all (Newton's included) before giving up.
    pub max_orbits: u64,
    /// Above this many nodes, march only (a dense monodromy costs one orbit per node).
    pub max_newton_nodes: usize,
    /// Most solver steps of the whole search (a chattering thermostat); u64::MAX: none.
    pub max_steps: u64,
}

impl Default for SteadyOptions {
    fn default() -> SteadyOptions {
        SteadyOptions {
            method: Method::Auto,
            tolerance_k: 1e-4,
            warmup_orbits: 2,
            max_newton_iterations: 8,
            max_orbits: 20_000,
            max_newton_nodes: 200,
            max_steps: u64::MAX,
        }
    }
}

/// How the periodic orbit was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeriodicMethod {
    /// Newton shooting on the one-orbit map.
    Newton,
    /// Orbit after orbit until it repeats.
    Marching,
}

impl PeriodicMethod {
    /// "newton" or "marching".
    pub fn as_str(self) -> &'static str {
        match self {
            PeriodicMethod::Newton => "newton",
            PeriodicMethod::Marching => "marching",
        }
    }
}

impl std::fmt::Display for PeriodicMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

/// The periodic orbit's start state and how it was found.
#[derive(Debug, Clone)]
pub struct Periodic {
    /// At t = `t0_s`: temperatures and heater states that return after one period.
    pub state: State,
    pub method: PeriodicMethod,
    /// One-orbit runs spent (warm-up, Jacobian columns, Newton steps, marching).
    pub orbits: u64,
    pub newton_iterations: u32,
    /// max |Φ(x) − x| at the solution, K.
    pub periodicity_error_k: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum SteadyError {
    #[error(transparent)]
    Run(#[from] SimError),
    #[error(
        "a periodic orbit needs an environment that repeats every orbit, and this scenario has a time table or a mode window (its first point at t = {0} s): no two orbits are alike"
    )]
    NotPeriodic(f64),
    #[error(
        "a periodic orbit needs an environment that repeats every orbit, and a real orbit's does not: β, the Sun's distance and the shadow move from orbit to orbit (run the mission, or a circular orbit with constant β)"
    )]
    RealOrbit,
    #[error(
        "no periodic orbit within {orbits} orbits: the last orbit still moved a node by {error_k:.3e} K, about {distance_k:.3e} K from the orbit at its contraction (tolerance {tolerance_k} K)"
    )]
    NotConverged {
        orbits: u64,
        error_k: f64,
        /// The estimated distance to the orbit ([`distance`]; infinite when not
        /// contracting).
        distance_k: f64,
        tolerance_k: f64,
    },
}

/// Whether `model`'s environment and loads repeat every orbit (no table knots or mode
/// edges), as a periodic orbit needs.
pub fn check_repeats(model: &crate::thermal::ThermalModel) -> Result<(), SteadyError> {
    if matches!(model.environment, crate::orbit::Environment::Dated(_)) {
        return Err(SteadyError::RealOrbit);
    }
    match model.breakpoints_s().first() {
        Some(&t) => Err(SteadyError::NotPeriodic(t)),
        None => Ok(()),
    }
}

/// One orbit from temperatures `x` and heater states `heaters` at `t0`: the end
/// temperatures and heater states.
fn one_orbit(
    setup: &mut Setup<'_>,
    t0: f64,
    period: f64,
    x: &[f64],
    heaters: &[bool],
    budget: &mut crate::run::sim::StepBudget,
) -> Result<(Vec<f64>, Vec<bool>), SimError> {
    let mut s = setup.state_at(t0, x.to_vec());
    s.heaters_on.copy_from_slice(heaters);
    setup.run(&mut s, t0 + period, budget, Stop::default())?;
    Ok((s.temperatures_k, s.heaters_on))
}

/// Each node's move over one orbit, from `x` to `y`.
fn node_moves_of(y: &[f64], x: &[f64]) -> Vec<f64> {
    y.iter().zip(x).map(|(a, b)| a - b).collect()
}

/// The largest move of any node.
fn largest(moves: &[f64]) -> f64 {
    moves.iter().map(|m| m.abs()).fold(0.0, f64::max)
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The periodic orbit starting at `start.t_s`, for an environment of period `period_s`.
pub fn periodic_orbit(
    setup: &mut Setup<'_>,
    start: &State,
    period_s: f64,
    opts: SteadyOptions,
) -> Result<Periodic, SteadyError> {
    check_repeats(setup.model())?;
    let mut budget = crate::run::sim::StepBudget::new(opts.max_steps);
    let t0 = start.t_s;
    let mut x = start.temperatures_k.clone();
    let mut heaters = start.heaters_on.clone();
    let mut orbits = 0u64;
    let n = x.len();
    // warm-up: march towards the orbit
    let mut moves = Vec::new();
    let mut warm_moves = Vec::new();
    for _ in 0..opts.warmup_orbits.max(2) {
        let (y, h) = one_orbit(setup, t0, period_s, &x, &heaters, &mut budget)?;
        orbits += 1;
        warm_moves = node_moves_of(&y, &x);
        moves.push(largest(&warm_moves));
        x = y;
        heaters = h;
    }
    let last_move = *moves.last().expect("two warm-up orbits");
    // Marching contracts by about ρ per orbit, so the state is about move·ρ/(1 − ρ)
    // from the orbit ([`distance`]), which takes [`orbits_to_go`]; Newton needs n + 1
    // orbits per iteration, two iterations at least.
    let rho = moves[moves.len() - 1] / moves[moves.len() - 2];
    let marching_orbits = orbits_to_go(last_move, rho, opts.tolerance_k);
    let newton = match opts.method {
        Method::Marching => false,
        Method::Newton => true,
        Method::Auto => marching_orbits > 2.0 * (n as f64 + 1.0),
    };
    let mut iterations = 0;
    let far = distance(last_move, rho) > opts.tolerance_k;
    let may_newton = opts.method != Method::Marching && n <= opts.max_newton_nodes;
    let mut newton_tried = false;
    // Newton before marching, when the warm-up asks for it
    let mut try_newton = newton && n <= opts.max_newton_nodes && far;
    // the last move and contraction (NaN: not known, after Newton moved the state)
    let (mut previous, mut last_rho) = (last_move, rho);
    // each node's last move (None: not known, after Newton moved the state)
    let mut node_moves = Some(warm_moves);
    // Newton when asked for, then marching: done when the state is within the
    // tolerance of the orbit, estimated from the last move and the larger of the last
    // two contractions (one ratio can come from a fast mode's last move while a slow
    // one remains), and from each node's own contraction (a heavy node's slow mode
    // moves it less per orbit than the fast nodes' last settling moves them)
    loop {
        if try_newton {
            newton_tried = true;
            let (x0, h0) = (std::mem::take(&mut x), std::mem::take(&mut heaters));
            match newton_search(setup, t0, period_s, x0, h0, &opts, &mut budget)? {
                Shooting::Converged(p) => return Ok(p.counted(orbits)),
                Shooting::Fell(fell) => {
                    (x, heaters) = (fell.x, fell.heaters);
                    orbits += fell.orbits;
                    iterations = fell.iterations;
                    (previous, last_rho) = (f64::NAN, f64::NAN);
                    node_moves = None;
                }
            }
        }
        let (y, h) = one_orbit(setup, t0, period_s, &x, &heaters, &mut budget)?;
        orbits += 1;
        let moves = node_moves_of(&y, &x);
        let r = largest(&moves);
        let slowest = node_moves
            .as_deref()
            .map(|before| SlowestNode::of(&moves, before, opts.tolerance_k));
        node_moves = Some(moves);
        x = y;
        heaters = h;
        let rho = r / previous;
        let rho_max = if rho.is_nan() || last_rho.is_nan() {
            f64::NAN
        } else {
            rho.max(last_rho)
        };
        (previous, last_rho) = (r, rho);
        let distance_k = match slowest {
            Some(s) => distance(r, rho_max).max(s.distance_k()),
            None => f64::INFINITY,
        };
        if r <= opts.tolerance_k && distance_k <= opts.tolerance_k {
            return Ok(Periodic {
                state: start_state(setup, t0, x, heaters),
                method: PeriodicMethod::Marching,
                orbits,
                newton_iterations: iterations,
                periodicity_error_k: r,
            });
        }
        if orbits >= opts.max_orbits {
            return Err(SteadyError::NotConverged {
                orbits,
                error_k: r,
                distance_k,
                tolerance_k: opts.tolerance_k,
            });
        }
        // a slow mode that the warm-up did not show: Newton, once, when marching
        // would take longer than a few monodromies
        let to_go = orbits_to_go(r, rho, opts.tolerance_k)
            .max(slowest.map_or(0.0, |s| s.orbits_to_go(opts.tolerance_k)));
        try_newton = may_newton && !newton_tried && to_go > 2.0 * (n as f64 + 1.0);
    }
}

/// The node furthest from the periodic orbit by its own contraction over the last two
/// orbits: its last move and the ratio of its last two moves (in magnitude). Nodes
/// that moved less than a thousandth of the tolerance are left out: their ratio is
/// rounding, and they are that close already.
#[derive(Debug, Clone, Copy)]
struct SlowestNode {
    moved_k: f64,
    rho: f64,
}

impl SlowestNode {
    fn of(moves: &[f64], before: &[f64], tol: f64) -> SlowestNode {
        let mut slowest = SlowestNode {
            moved_k: 0.0,
            rho: 0.0,
        };
        for (&m, &b) in moves.iter().zip(before) {
            if m.abs() <= 1e-3 * tol {
                continue;
            }
            let node = SlowestNode {
                moved_k: m.abs(),
                rho: (m / b).abs(),
            };
            if node.distance_k() > slowest.distance_k() || !node.rho.is_finite() {
                slowest = node;
            }
        }
        slowest
    }

    fn distance_k(self) -> f64 {
        distance(self.moved_k, self.rho)
    }

    fn orbits_to_go(self, tol: f64) -> f64 {
        orbits_to_go(self.moved_k, self.rho, tol)
    }
}

/// Orbits marching still needs from a move of `moved` contracting by `rho` per orbit
/// until the state is within `tol` of the orbit (infinite when it does not contract).
fn orbits_to_go(moved: f64, rho: f64, tol: f64) -> f64 {
    if moved == 0.0 {
        0.0
    } else if rho.is_finite() && rho > 0.0 && rho < 1.0 {
        ((tol * (1.0 - rho) / (moved * rho)).ln() / rho.ln()).max(0.0)
    } else {
        f64::INFINITY
    }
}

/// Where Newton shooting ended.
enum Shooting {
    Converged(Box<Periodic>),
    /// Not converged: the best iterate, to march from, and what it spent.
    Fell(Fell),
}

struct Fell {
    x: Vec<f64>,
    heaters: Vec<bool>,
    orbits: u64,
    iterations: u32,
}

impl Periodic {
    /// With the orbits spent before the search that found it added.
    fn counted(mut self: Box<Self>, orbits_before: u64) -> Periodic {
        self.orbits += orbits_before;
        *self
    }
}

/// Newton shooting on F(x) = Φ(x) − x from `x`.
fn newton_search(
    setup: &mut Setup<'_>,
    t0: f64,
    period_s: f64,
    mut x: Vec<f64>,
    mut heaters: Vec<bool>,
    opts: &SteadyOptions,
    budget: &mut crate::run::sim::StepBudget,
) -> Result<Shooting, SteadyError> {
    let n = x.len();
    let (mut orbits, mut iterations) = (0u64, 0u32);
    let mut best = (f64::INFINITY, x.clone(), heaters.clone());
    let mut last_step_k = f64::INFINITY;
    // the last monodromy's factors (of ∂Φ/∂x − I)
    let mut factors: Option<nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>> = None;
    for _ in 0..opts.max_newton_iterations {
        let (fx, h) = one_orbit(setup, t0, period_s, &x, &heaters, budget)?;
        orbits += 1;
        let r = max_diff(&fx, &x);
        let f = DVector::from_iterator(n, fx.iter().zip(&x).map(|(a, b)| a - b));
        // Converged when the orbit returns within the tolerance and the Newton step
        // from here, (∂Φ/∂x − I)⁻¹ (Φ(x) − x), the distance to the periodic orbit,
        // is as small. A small return alone is not enough: a node whose time
        // constant is thousands of orbits returns within 1e-4 K per orbit while
        // kelvins from its periodic orbit.
        // the distance to the periodic orbit, estimated by the step through the last
        // monodromy: (∂Φ/∂x − I)⁻¹ (Φ(x) − x)
        let chord_k = factors
            .as_ref()
            .and_then(|lu| lu.solve(&f))
            .map_or(f64::INFINITY, |d| d.amax());
        // Converged when the orbit returns within the tolerance and that distance is
        // as small. A small return alone is not enough: a node whose time constant is
        // thousands of orbits returns within 1e-4 K per orbit while kelvins from its
        // periodic orbit.
        if r <= opts.tolerance_k && chord_k <= opts.tolerance_k {
            return Ok(Shooting::Converged(Box::new(Periodic {
                state: start_state(setup, t0, x, heaters),
                method: PeriodicMethod::Newton,
                orbits,
                newton_iterations: iterations,
                periodicity_error_k: r,
            })));
        }
        // Diverging when the state is estimated no nearer the orbit than before the
        // last step: march from the best point. (Judged by the distance, not by the
        // orbit's return: with a slow node the first step takes the state from a
        // small return far from the orbit to a larger return near it.)
        if chord_k.is_finite() && chord_k >= last_step_k {
            break;
        }
        // monodromy by forward differences (0.01 K per node)
        let dx = 1e-2;
        let mut j = DMatrix::<f64>::zeros(n, n);
        for c in 0..n {
            let mut xp = x.clone();
            xp[c] += dx;
            let (fp, _) = one_orbit(setup, t0, period_s, &xp, &heaters, budget)?;
            orbits += 1;
            for rrow in 0..n {
                j[(rrow, c)] = (fp[rrow] - fx[rrow]) / dx;
            }
        }
        for d in 0..n {
            j[(d, d)] -= 1.0;
        }
        let lu = j.lu();
        let Some(delta) = lu.solve(&(-f)) else {
            break;
        };
        // the best point is the one estimated nearest the orbit, by its Newton step
        last_step_k = delta.amax();
        if last_step_k < best.0 {
            best = (last_step_k, x.clone(), heaters.clone());
        }
        factors = Some(lu);
        for (xi, di) in x.iter_mut().zip(delta.iter()) {
            *xi += di;
        }
        heaters = h;
        iterations += 1;
    }
    Ok(Shooting::Fell(Fell {
        x: best.1,
        heaters: best.2,
        orbits,
        iterations,
    }))
}

/// How far from the periodic orbit a state is whose last orbit moved it by `moved`
/// while contracting by `rho` per orbit: moved × ρ/(1 − ρ), the sum of the moves still
/// to come (infinite when it does not contract; 0 when it did not move).
fn distance(moved: f64, rho: f64) -> f64 {
    if moved == 0.0 {
        0.0
    } else if rho.is_finite() && (0.0..1.0).contains(&rho) {
        moved * rho / (1.0 - rho)
    } else {
        f64::INFINITY
    }
}

fn start_state(setup: &Setup<'_>, t0: f64, x: Vec<f64>, heaters: Vec<bool>) -> State {
    let mut s = setup.state_at(t0, x);
    s.heaters_on = heaters;
    s
}

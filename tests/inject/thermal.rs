//! The lumped network of FUNcube-1 and its integration by fixed-step classical RK4,
//! written from the scenario's meaning (`scenarios/README.md`). Each node's heat
//! balance is C dT/dt = Σ G (Tj − Ti) + Σ σ εA (Tj⁴ − Ti⁴) + its dissipation, and on
//! each of its faces α A (direct Sun and albedo) plus ε A (Earth infrared) minus
//! ε A σ (T⁴ − T_sink⁴); an effect adds a thermostat heater, a switched dissipation, a
//! first-order sensor lag (an extra state) or a face's absorptivity scaled.

use super::environment::{Environment, SIGMA_W_PER_M2_K4};
use super::scenario::Network;
use std::sync::Arc;

/// Largest RK4 step (s). The fastest node, a panel (45 J/K on ≈ 0.6 W/K), has a time
/// constant of about 75 s: 2 s steps are well inside RK4's stability and accurate to
/// far below the telemetry's 0.01 K (checked by halving the step).
pub const STEP_S: f64 = 2.0;

/// A heater on `node` with a thermostat reading that node: on below `on_k`, off above
/// `off_k`. The thermostat reads the node's temperature plus `reads_offset` (K, a
/// function of time; none: the node as modelled).
#[derive(Clone, Debug)]
pub struct Thermostat {
    pub node: usize,
    pub power_w: f64,
    pub on_k: f64,
    pub off_k: f64,
    pub reads_offset: Option<Arc<Table>>,
}

impl Thermostat {
    /// What the thermostat reads at time `t` in state `y`, K.
    pub fn reads_k(&self, t: f64, y: &[f64]) -> f64 {
        y[self.node] + self.reads_offset.as_ref().map_or(0.0, |o| o.at(t))
    }
}

/// A function of time by linear interpolation between its points (times increasing):
/// before the first, the first `period_s` repeated (the spin-up orbits before a
/// recording see its first orbit again); after the last, held.
#[derive(Clone, Debug)]
pub struct Table {
    pub times_s: Vec<f64>,
    pub values: Vec<f64>,
    pub period_s: f64,
}

impl Table {
    pub fn at(&self, t: f64) -> f64 {
        let (ts, vs) = (&self.times_s, &self.values);
        assert!(!ts.is_empty(), "a table without points");
        if t < ts[0] && self.period_s > 0.0 {
            let back = ((ts[0] - t) / self.period_s).ceil();
            return self.at(t + back * self.period_s);
        }
        let k = ts.partition_point(|&x| x <= t);
        if k == 0 {
            return vs[0];
        }
        if k == ts.len() {
            return vs[k - 1];
        }
        let w = (t - ts[k - 1]) / (ts[k] - ts[k - 1]);
        vs[k - 1] + w * (vs[k] - vs[k - 1])
    }
}

/// A dissipation on `node` from time `t_on_s` on.
#[derive(Clone, Debug)]
pub struct Switched {
    pub node: usize,
    pub power_w: f64,
    pub t_on_s: f64,
}

/// A first-order sensor on `node`: dL/dt = (T_node − L)/τ.
#[derive(Clone, Debug)]
pub struct Lag {
    pub node: usize,
    pub tau_s: f64,
}

/// What an effect adds to the network.
#[derive(Clone, Debug, Default)]
pub struct Additions {
    pub thermostats: Vec<Thermostat>,
    pub switched: Vec<Switched>,
    pub lags: Vec<Lag>,
    /// (face index, factor on its absorptivity).
    pub absorptivity_scale: Vec<(usize, f64)>,
}

/// A run: the states (node temperatures, then lag states, K) at the requested times,
/// each thermostat's switching times with its new state, and each thermostat's time
/// on within `[0, last requested time]`.
#[derive(Clone, Debug)]
pub struct Run {
    pub states: Vec<Vec<f64>>,
    pub switches: Vec<(f64, usize, bool)>,
    pub heater_on_s: Vec<f64>,
}

/// The network, its environment and the additions, integrated from `t_start_s`.
pub struct Solver<'a> {
    pub net: &'a Network,
    pub env: &'a Environment,
    pub add: Additions,
    pub step_s: f64,
    /// Where integration starts (s; before the recording, to settle the orbit cycle).
    pub t_start_s: f64,
    /// Extra times the steps land on (so that two runs compared share their steps).
    pub breaks_s: Vec<f64>,
}

/// What is held over one step: sunlit or not, the step's middle time, heaters on.
struct StepCtx<'a> {
    sunlit: bool,
    t_mid: f64,
    heater_on: &'a [bool],
}

impl Solver<'_> {
    fn n(&self) -> usize {
        self.net.names.len()
    }

    /// The state at `t_start_s`: every node at its initial temperature, every lag
    /// state at its node's.
    pub fn initial_state(&self) -> Vec<f64> {
        let mut y = self.net.initial_k.clone();
        y.extend(self.add.lags.iter().map(|l| self.net.initial_k[l.node]));
        y
    }

    /// Net heat into each node (W) from the network and its loads.
    fn heat_w(&self, t: f64, y: &[f64], ctx: &StepCtx, q: &mut [f64]) {
        let net = self.net;
        q.copy_from_slice(&net.dissipation_w);
        for l in &net.conductors {
            let flow = l.value * (y[l.b] - y[l.a]);
            q[l.a] += flow;
            q[l.b] -= flow;
        }
        for l in &net.radiation {
            let flow = SIGMA_W_PER_M2_K4 * l.value * (y[l.b].powi(4) - y[l.a].powi(4));
            q[l.a] += flow;
            q[l.b] -= flow;
        }
        let solar = self.env.direct_w_per_m2(ctx.sunlit) + self.env.albedo_w_per_m2(t);
        let ir = self.env.earth_ir_face_w_per_m2();
        let sink4 = self.env.sink_k.powi(4);
        for (k, f) in net.faces.iter().enumerate() {
            let scale: f64 = self
                .add
                .absorptivity_scale
                .iter()
                .filter(|a| a.0 == k)
                .map(|a| a.1)
                .product();
            let t4 = y[f.node].powi(4);
            q[f.node] += scale * f.absorptivity * f.area_m2 * solar
                + f.emissivity * f.area_m2 * (ir - SIGMA_W_PER_M2_K4 * (t4 - sink4));
        }
        for s in self.add.switched.iter().filter(|s| ctx.t_mid >= s.t_on_s) {
            q[s.node] += s.power_w;
        }
        for (h, &on) in self.add.thermostats.iter().zip(ctx.heater_on) {
            if on {
                q[h.node] += h.power_w;
            }
        }
    }

    /// dy/dt: node temperatures, then lag states.
    fn rhs(&self, t: f64, y: &[f64], ctx: &StepCtx, dy: &mut [f64]) {
        let n = self.n();
        self.heat_w(t, y, ctx, &mut dy[..n]);
        for (d, c) in dy[..n].iter_mut().zip(&self.net.capacitance_j_per_k) {
            *d /= c;
        }
        for (k, lag) in self.add.lags.iter().enumerate() {
            dy[n + k] = (y[lag.node] - y[n + k]) / lag.tau_s;
        }
    }

    /// One classical RK4 step of length `h` from (t, y).
    fn rk4(&self, t: f64, h: f64, y: &[f64], ctx: &StepCtx) -> Vec<f64> {
        let m = y.len();
        let mut k: [Vec<f64>; 4] = std::array::from_fn(|_| vec![0.0; m]);
        let mut tmp = vec![0.0; m];
        self.rhs(t, y, ctx, &mut k[0]);
        for (stage, (dt, w)) in [(0.5, 0.5), (0.5, 0.5), (1.0, 1.0)].iter().enumerate() {
            for i in 0..m {
                tmp[i] = y[i] + w * h * k[stage][i];
            }
            let (_, rest) = k.split_at_mut(stage + 1);
            self.rhs(t + dt * h, &tmp, ctx, &mut rest[0]);
        }
        (0..m)
            .map(|i| y[i] + h / 6.0 * (k[0][i] + 2.0 * k[1][i] + 2.0 * k[2][i] + k[3][i]))
            .collect()
    }

    /// Whether any thermostat must switch at time `t` in state `y`.
    fn must_switch(&self, t: f64, y: &[f64], on: &[bool]) -> bool {
        self.add.thermostats.iter().zip(on).any(|(h, &is_on)| {
            if is_on {
                h.reads_k(t, y) > h.off_k
            } else {
                h.reads_k(t, y) < h.on_k
            }
        })
    }

    /// The sorted times steps must land on up to `t_end`: eclipse entries and exits,
    /// switch-on times, the extra breaks.
    fn breakpoints(&self, t_end: f64) -> Vec<f64> {
        let mut b = self.env.eclipses.boundaries(self.t_start_s, t_end);
        b.extend(self.add.switched.iter().map(|s| s.t_on_s));
        b.extend(self.breaks_s.iter().copied());
        b.retain(|t| *t > self.t_start_s && *t <= t_end);
        b.sort_by(f64::total_cmp);
        b
    }

    /// The states at the non-decreasing `times` (each ≥ `t_start_s`). Steps of
    /// `step_s` at most, shortened to land on the requested times and the
    /// breakpoints; the sunlit flag and the switched loads are held over a step (taken
    /// at its middle). Thermostats are checked at the end of every step; a crossing is
    /// located by bisection of the step length (to 1 ms), the heater switches there
    /// and integration goes on from it.
    pub fn run(&self, times: &[f64]) -> Run {
        let t_end = times.last().copied().unwrap_or(self.t_start_s);
        let breaks = self.breakpoints(t_end);
        let mut y = self.initial_state();
        let mut on: Vec<bool> = self
            .add
            .thermostats
            .iter()
            .map(|h| h.reads_k(self.t_start_s, &y) < h.on_k)
            .collect();
        let mut run = Run {
            states: Vec::with_capacity(times.len()),
            switches: Vec::new(),
            heater_on_s: vec![0.0; on.len()],
        };
        let (mut t, mut bi) = (self.t_start_s, 0);
        for &ts in times {
            assert!(
                ts >= t,
                "times must not decrease and start at t_start_s or later"
            );
            while t < ts {
                while bi < breaks.len() && breaks[bi] <= t {
                    bi += 1;
                }
                let mut t_next = (t + self.step_s).min(ts);
                if ts - t_next < 1e-9 {
                    t_next = ts;
                }
                if bi < breaks.len() && breaks[bi] < t_next {
                    t_next = breaks[bi];
                }
                let h = t_next - t;
                let ctx = StepCtx {
                    sunlit: self.env.eclipses.sunlit(t + 0.5 * h),
                    t_mid: t + 0.5 * h,
                    heater_on: &on,
                };
                let mut y1 = self.rk4(t, h, &y, &ctx);
                let mut t1 = t_next;
                let switching = self.must_switch(t_next, &y1, &on);
                if switching {
                    (t1, y1) = self.locate_switch(t, h, &y, &ctx);
                }
                for (k, is_on) in on.iter().enumerate() {
                    if *is_on {
                        run.heater_on_s[k] += (t1.min(t_end) - t.max(0.0)).max(0.0);
                    }
                }
                if switching {
                    self.switch(t1, &y1, &mut on, &mut run.switches);
                }
                (t, y) = (t1, y1);
            }
            run.states.push(y.clone());
        }
        run
    }

    /// The time and state where a thermostat crossing inside the step (t, h) happens.
    fn locate_switch(&self, t: f64, h: f64, y: &[f64], ctx: &StepCtx) -> (f64, Vec<f64>) {
        let (mut lo, mut hi) = (0.0, h);
        let mut y_hi = self.rk4(t, h, y, ctx);
        while hi - lo > 1e-3 {
            let mid = 0.5 * (lo + hi);
            let ym = self.rk4(t, mid, y, ctx);
            if self.must_switch(t + mid, &ym, ctx.heater_on) {
                (hi, y_hi) = (mid, ym);
            } else {
                lo = mid;
            }
        }
        (if hi == h { t + h } else { t + hi }, y_hi)
    }

    /// Switches every thermostat whose set point `y` has crossed, logging it.
    fn switch(&self, t: f64, y: &[f64], on: &mut [bool], log: &mut Vec<(f64, usize, bool)>) {
        for (k, (h, is_on)) in self.add.thermostats.iter().zip(on.iter_mut()).enumerate() {
            let reads = h.reads_k(t, y);
            if (*is_on && reads > h.off_k) || (!*is_on && reads < h.on_k) {
                *is_on = !*is_on;
                log.push((t, k, *is_on));
            }
        }
    }
}

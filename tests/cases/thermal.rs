//! Thermal network of `reference-mechanism.md` §2 and its integration by fixed-step
//! classical RK4, written from the spec.

use super::orbit;

/// Steel conductivity for re-derived gear bodies (W/m K) and face width (m).
pub const GEAR_K_W_PER_M_K: f64 = 18.0;
pub const FACE_WIDTH_M: f64 = 8.0e-3;

/// Largest RK4 step (s); smaller when the network is stiffer (see `Solver::step_s`).
pub const MAX_STEP_S: f64 = 0.25;

/// Diffusion nodes in order; the gear bodies follow as `gear1.r0 …`, `gear2.r0 …`.
pub const HOUSING: usize = 0;
pub const MOTOR: usize = 1;
pub const SHAFT1: usize = 2;
pub const SHAFT2: usize = 3;

/// A linear (W/K) or radiative (εA, m²) conductor between nodes i and j (j may be a
/// boundary index). `step`: (scale after, switch time) for a conductor that changes
/// abruptly.
#[derive(Clone, Debug)]
pub struct Cond {
    pub i: usize,
    pub j: usize,
    pub g: f64,
    pub step: Option<(f64, f64)>,
}

/// A heat load on one node.
#[derive(Clone, Debug)]
pub enum Load {
    /// Sun on a face: αA × S while sunlit.
    Sun {
        node: usize,
        alpha_area_m2: f64,
    },
    Albedo {
        node: usize,
        alpha_area_m2: f64,
    },
    Constant {
        node: usize,
        power_w: f64,
    },
    /// `sunlit`: `Some(true)` only in sunlight, `Some(false)` only in eclipse.
    Scheduled {
        node: usize,
        power_w: f64,
        sunlit: Option<bool>,
    },
    Periodic {
        node: usize,
        amplitude_w: f64,
        period_s: f64,
    },
    Heater {
        node: usize,
        power_w: f64,
        on_k: f64,
        off_k: f64,
    },
}

#[derive(Clone, Debug)]
pub struct Network {
    pub names: Vec<String>,
    pub cap: Vec<f64>,
    /// Boundary temperatures; boundary b has index `cap.len() + b`.
    pub boundary_k: Vec<f64>,
    pub boundary_names: Vec<String>,
    pub lin: Vec<Cond>,
    pub rad: Vec<Cond>,
    /// Node indices and radii (m) of each gear body, bore first.
    pub gear_nodes: [Vec<usize>; 2],
    pub gear_radii_m: [Vec<f64>; 2],
}

/// Reference gear bodies: bore and base radii (m), capacitances and body conductance
/// of the 3-node table.
struct GearBody {
    bore_m: f64,
    base_m: f64,
    c_ref: [f64; 3],
    g_ref: f64,
}

const GEAR_BODIES: [GearBody; 2] = [
    GearBody {
        bore_m: 3.0e-3,
        base_m: 9.396926e-3,
        c_ref: [0.624, 3.06, 4.41],
        g_ref: 1.585,
    },
    GearBody {
        bore_m: 5.0e-3,
        base_m: 18.793852e-3,
        c_ref: [2.12, 12.06, 19.30],
        g_ref: 1.367,
    },
];

/// Radii of `n` nodes from bore to base circle, equally spaced in ln r (3 nodes: the
/// reference radii, the middle one √(r_a r_b)).
pub fn gear_radii_m(gear: usize, n: usize) -> Vec<f64> {
    let b = &GEAR_BODIES[gear];
    (0..n)
        .map(|i| b.bore_m * (b.base_m / b.bore_m).powf(i as f64 / (n - 1) as f64))
        .collect()
}

/// Capacitances (J/K) and neighbour conductances (W/K) of a gear body on `n` nodes.
/// n = 3: the reference table. Otherwise re-derived: each node owns the annulus between
/// the geometric means of its neighbours' radii (bore and base circle at the ends);
/// ρc is the reference inner two nodes' capacitance over their annulus volume; the
/// rim node also carries the teeth (the reference rim capacitance minus its annulus);
/// G = 2π k b / ln(r₊/r₋).
fn gear_body(gear: usize, n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 2, "a gear body needs at least 2 nodes");
    let b = &GEAR_BODIES[gear];
    if n == 3 {
        return (b.c_ref.to_vec(), vec![b.g_ref; 2]);
    }
    let annulus = |r0: f64, r1: f64| std::f64::consts::PI * (r1 * r1 - r0 * r0) * FACE_WIDTH_M;
    let r3 = gear_radii_m(gear, 3);
    let edge3 = (r3[1] * r3[2]).sqrt();
    let rho_c = (b.c_ref[0] + b.c_ref[1]) / annulus(b.bore_m, edge3);
    let teeth = b.c_ref[2] - rho_c * annulus(edge3, b.base_m);
    let r = gear_radii_m(gear, n);
    let mut edges = vec![b.bore_m];
    edges.extend(r.windows(2).map(|w| (w[0] * w[1]).sqrt()));
    edges.push(b.base_m);
    let mut caps: Vec<f64> = edges
        .windows(2)
        .map(|w| rho_c * annulus(w[0], w[1]))
        .collect();
    caps[n - 1] += teeth;
    let gs = r
        .windows(2)
        .map(|w| 2.0 * std::f64::consts::PI * GEAR_K_W_PER_M_K * FACE_WIDTH_M / (w[1] / w[0]).ln())
        .collect();
    (caps, gs)
}

impl Network {
    /// The reference network with `gear_nodes` radial nodes per gear body.
    pub fn reference(gear_nodes: usize) -> Network {
        let mut names: Vec<String> = ["housing", "motor", "shaft1", "shaft2"]
            .map(String::from)
            .to_vec();
        let mut cap = vec![120.0, 75.0, 4.06, 14.1];
        let mut gear_nodes_idx: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
        let mut body_g = Vec::new();
        for (g, idx) in gear_nodes_idx.iter_mut().enumerate() {
            let (c, gs) = gear_body(g, gear_nodes);
            for (i, ci) in c.iter().enumerate() {
                idx.push(names.len());
                names.push(format!("gear{}.r{}", g + 1, i));
                cap.push(*ci);
            }
            body_g.push(gs);
        }
        let n = cap.len();
        let (bus, space) = (n, n + 1);
        let c = |i: usize, j: usize, g: f64| Cond {
            i,
            j,
            g,
            step: None,
        };
        let [g1, g2] = &gear_nodes_idx;
        let (rim1, rim2) = (*g1.last().unwrap(), *g2.last().unwrap());
        let mut lin = vec![
            c(HOUSING, bus, 0.03),
            c(HOUSING, MOTOR, 0.30),
            c(MOTOR, SHAFT1, 0.25),
            c(HOUSING, SHAFT1, 0.05),
            c(HOUSING, SHAFT2, 0.12),
            c(SHAFT1, g1[0], 0.60),
            c(SHAFT2, g2[0], 0.90),
        ];
        for (g, nodes) in gear_nodes_idx.iter().enumerate() {
            for (w, gw) in nodes.windows(2).zip(&body_g[g]) {
                lin.push(c(w[0], w[1], *gw));
            }
        }
        lin.push(c(rim1, rim2, 0.03));
        let rad = vec![
            c(rim1, HOUSING, 1.41e-4),
            c(rim2, HOUSING, 5.23e-4),
            c(MOTOR, HOUSING, 6.0e-4),
            c(HOUSING, space, 0.030),
        ];
        Network {
            names,
            cap,
            boundary_k: vec![orbit::BUS_K, orbit::SPACE_K],
            boundary_names: vec!["bus".into(), "space".into()],
            lin,
            rad,
            gear_radii_m: [gear_radii_m(0, gear_nodes), gear_radii_m(1, gear_nodes)],
            gear_nodes: gear_nodes_idx,
        }
    }

    /// Index of a diffusion or boundary node by name.
    pub fn index(&self, name: &str) -> usize {
        if let Some(i) = self.names.iter().position(|n| n == name) {
            return i;
        }
        match self.boundary_names.iter().position(|n| n == name) {
            Some(b) => self.cap.len() + b,
            None => panic!("unknown node {name:?}; nodes are {:?}", self.names),
        }
    }

    /// The linear conductor between `a` and `b` if there is one, else the radiative one.
    pub fn conductor_mut(&mut self, a: &str, b: &str) -> &mut Cond {
        let (ia, ib) = (self.index(a), self.index(b));
        let hit = |c: &Cond| (c.i == ia && c.j == ib) || (c.i == ib && c.j == ia);
        if let Some(k) = self.lin.iter().position(hit) {
            return &mut self.lin[k];
        }
        match self.rad.iter_mut().find(|c| hit(c)) {
            Some(c) => c,
            None => panic!("no conductor between {a:?} and {b:?}"),
        }
    }
}

/// What is held fixed over one step.
struct StepCtx<'a> {
    sunlit: bool,
    t_mid: f64,
    heater_on: &'a [bool],
}

/// Network, loads and first-order sensor states, integrated by classical RK4 with a
/// fixed step.
pub struct Solver {
    pub net: Network,
    pub loads: Vec<Load>,
    /// Lagged sensors: (node, τ). Their states follow the node temperatures in `y`.
    pub lags: Vec<(usize, f64)>,
    pub step_s: f64,
}

impl Solver {
    pub fn new(net: Network, loads: Vec<Load>, lags: Vec<(usize, f64)>) -> Solver {
        // RK4 is stable for real eigenvalues with hλ < 2.78; a Gershgorin bound of the
        // largest |λ| of C⁻¹G (radiation linearised at 400 K) keeps hλ ≤ 2.
        let n = net.cap.len();
        let mut diag = vec![0.0; n];
        let lin4 = 4.0 * orbit::SIGMA_W_PER_M2_K4 * 400f64.powi(3);
        for (c, f) in net
            .lin
            .iter()
            .map(|c| (c, 1.0))
            .chain(net.rad.iter().map(|c| (c, lin4)))
        {
            let g = c.g * f * c.step.map_or(1.0, |s| s.0.max(1.0));
            for k in [c.i, c.j] {
                if k < n {
                    diag[k] += g;
                }
            }
        }
        let mut bound: f64 = (0..n)
            .map(|k| 2.0 * diag[k] / net.cap[k])
            .fold(0.0, f64::max);
        for &(_, tau) in &lags {
            assert!(
                tau >= 0.1,
                "sensor lag τ = {tau} s is below the 0.1 s this integrator resolves"
            );
            bound = bound.max(1.0 / tau);
        }
        let step_s = MAX_STEP_S.min(2.0 / bound);
        Solver {
            net,
            loads,
            lags,
            step_s,
        }
    }

    fn n(&self) -> usize {
        self.net.cap.len()
    }

    pub fn initial_state(&self) -> Vec<f64> {
        vec![orbit::INITIAL_K; self.n() + self.lags.len()]
    }

    fn heaters(&self) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        self.loads.iter().filter_map(|l| match *l {
            Load::Heater {
                node, on_k, off_k, ..
            } => Some((node, on_k, off_k)),
            _ => None,
        })
    }

    fn rhs(&self, t: f64, y: &[f64], ctx: &StepCtx, dy: &mut [f64]) {
        let n = self.n();
        let temp = |k: usize| {
            if k < n {
                y[k]
            } else {
                self.net.boundary_k[k - n]
            }
        };
        dy.iter_mut().for_each(|d| *d = 0.0);
        let factor = |c: &Cond| match c.step {
            Some((scale, t_switch)) if ctx.t_mid >= t_switch => scale,
            _ => 1.0,
        };
        for c in &self.net.lin {
            let q = c.g * factor(c) * (temp(c.j) - temp(c.i));
            dy[c.i] += q;
            if c.j < n {
                dy[c.j] -= q;
            }
        }
        for c in &self.net.rad {
            let (ti, tj) = (temp(c.i), temp(c.j));
            let q = orbit::SIGMA_W_PER_M2_K4 * c.g * factor(c) * (tj.powi(4) - ti.powi(4));
            dy[c.i] += q;
            if c.j < n {
                dy[c.j] -= q;
            }
        }
        let mut heater = 0;
        for l in &self.loads {
            match *l {
                Load::Sun {
                    node,
                    alpha_area_m2,
                } => {
                    if ctx.sunlit {
                        dy[node] += alpha_area_m2 * orbit::SOLAR_FLUX_W_PER_M2;
                    }
                }
                Load::Albedo {
                    node,
                    alpha_area_m2,
                } => dy[node] += orbit::albedo_load_w(alpha_area_m2, t),
                Load::Constant { node, power_w } => dy[node] += power_w,
                Load::Scheduled {
                    node,
                    power_w,
                    sunlit,
                } => {
                    if sunlit.is_none_or(|s| s == ctx.sunlit) {
                        dy[node] += power_w;
                    }
                }
                Load::Periodic {
                    node,
                    amplitude_w,
                    period_s,
                } => dy[node] += amplitude_w * (2.0 * std::f64::consts::PI * t / period_s).sin(),
                Load::Heater { node, power_w, .. } => {
                    if ctx.heater_on[heater] {
                        dy[node] += power_w;
                    }
                    heater += 1;
                }
            }
        }
        for (d, c) in dy.iter_mut().zip(&self.net.cap) {
            *d /= c;
        }
        for (s, &(node, tau)) in self.lags.iter().enumerate() {
            dy[n + s] = (y[node] - y[n + s]) / tau;
        }
    }

    /// One classical RK4 step of length `h` from (t, y).
    fn rk4(&self, t: f64, h: f64, y: &[f64], ctx: &StepCtx, k: &mut [Vec<f64>; 5]) -> Vec<f64> {
        let m = y.len();
        let [k1, k2, k3, k4, tmp] = k;
        self.rhs(t, y, ctx, k1);
        for i in 0..m {
            tmp[i] = y[i] + 0.5 * h * k1[i];
        }
        self.rhs(t + 0.5 * h, tmp, ctx, k2);
        for i in 0..m {
            tmp[i] = y[i] + 0.5 * h * k2[i];
        }
        self.rhs(t + 0.5 * h, tmp, ctx, k3);
        for i in 0..m {
            tmp[i] = y[i] + h * k3[i];
        }
        self.rhs(t + h, tmp, ctx, k4);
        (0..m)
            .map(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
            .collect()
    }

    /// Whether any thermostat must switch in state `y`.
    fn must_switch(&self, y: &[f64], on: &[bool]) -> bool {
        self.heaters().zip(on).any(|((node, on_k, off_k), &is_on)| {
            if is_on {
                y[node] > off_k
            } else {
                y[node] < on_k
            }
        })
    }

    /// States at the (increasing) `times`. Steps of `step_s` at most, shortened to land
    /// exactly on sample times and on known discontinuities (eclipse entry/exit,
    /// conductor switches); the sunlit flag and switched conductors are held over a step
    /// (evaluated at its midpoint). Thermostats are checked at the end of every step and
    /// the crossing is located by bisection on the step length; the heater then switches
    /// there and integration restarts from the crossing.
    pub fn run(&self, times: &[f64]) -> Vec<Vec<f64>> {
        let t_end = times.last().copied().unwrap_or(0.0);
        let mut disc = orbit::eclipse_boundaries(t_end);
        disc.extend(
            self.net
                .lin
                .iter()
                .chain(&self.net.rad)
                .filter_map(|c| c.step.map(|s| s.1)),
        );
        disc.sort_by(f64::total_cmp);
        let mut y = self.initial_state();
        let mut on: Vec<bool> = self
            .heaters()
            .map(|(node, on_k, _)| y[node] < on_k)
            .collect();
        let mut k: [Vec<f64>; 5] = std::array::from_fn(|_| vec![0.0; y.len()]);
        let mut t = 0.0;
        let mut di = 0;
        let mut out = Vec::with_capacity(times.len());
        for &ts in times {
            assert!(ts >= t, "sample times must increase");
            while t < ts {
                while di < disc.len() && disc[di] <= t {
                    di += 1;
                }
                let mut t_next = t + self.step_s;
                if t_next > ts - 1e-9 {
                    t_next = ts;
                }
                if di < disc.len() && disc[di] < t_next {
                    t_next = disc[di];
                }
                let h = t_next - t;
                let ctx = StepCtx {
                    sunlit: orbit::sunlit(t + 0.5 * h),
                    t_mid: t + 0.5 * h,
                    heater_on: &on,
                };
                let y1 = self.rk4(t, h, &y, &ctx, &mut k);
                if self.must_switch(&y1, &on) {
                    let (mut lo, mut hi) = (0.0, h);
                    let mut y_hi = y1;
                    while hi - lo > 1e-6 {
                        let mid = 0.5 * (lo + hi);
                        let ym = self.rk4(t, mid, &y, &ctx, &mut k);
                        if self.must_switch(&ym, &on) {
                            hi = mid;
                            y_hi = ym;
                        } else {
                            lo = mid;
                        }
                    }
                    for ((node, on_k, off_k), is_on) in self.heaters().zip(on.iter_mut()) {
                        if (*is_on && y_hi[node] > off_k) || (!*is_on && y_hi[node] < on_k) {
                            *is_on = !*is_on;
                        }
                    }
                    t = if hi == h { t_next } else { t + hi };
                    y = y_hi;
                    continue;
                }
                t = t_next;
                y = y1;
            }
            out.push(y.clone());
        }
        out
    }
}

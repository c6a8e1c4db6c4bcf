//! Independent truth generator for test recordings of the reference gearbox.
//!
//! A second implementation of `shared/spec/reference-mechanism.md` and
//! `shared/spec/physics.md` §2–§4 and §6, written from the specification alone. It uses
//! nothing from the `orbitlash` crate, so that tests of `diagnose` (which fits models to
//! recordings) do not commit the inverse crime: the recordings come from different code
//! with a different integrator, discretisation options and functional forms, plus noise,
//! quantisation, jitter and drop-outs.
//!
//! How it differs from orbitlash's forward model:
//! - Integrator: fixed-step classical explicit RK4 (step 0.25 s, smaller when a finer
//!   gear discretisation is stiffer: h ≤ 2/λ from a Gershgorin bound), not adaptive
//!   TR-BDF2 (tolerance 0.002 K, max step 300 s). Steps are shortened only to land on
//!   sample times, eclipse entry/exit (computed from the eclipse half-angle) and
//!   conductor switches; the sunlit flag is held over a step.
//! - Thermostats: checked at the end of each fixed step; the crossing is then located by
//!   bisection of the step length (to 1 µs) and integration restarts from there.
//! - Sensor lag: extra state variables integrated by the same RK4 steps.
//! - Gear bodies: 3 radial nodes (the reference table) or any other count (e.g. 5), with
//!   capacitances and conductances re-derived from the geometry (k = 18 W/m K, b = 8 mm,
//!   ρc from the reference inner-node capacitances, teeth lumped into the rim).
//! - Disc displacement: ∫ ε(T(r)) r dr by Gauss–Legendre in ln r on each segment of the
//!   logarithmic profile (no closed form), for any strain law ε(T).
//! - Backlash: the exact smallest normal backlash over a mesh cycle by a tooth-pair scan
//!   on the two lines of action, one evaluation per interval of mesh phase between the
//!   phases where a flank enters or leaves the path of contact (the backlash is constant
//!   in between); a plain fine phase scan is kept as a cross-check.
//! - Noise: ChaCha8 with Box–Muller Gaussians; noise first, then quantisation, then
//!   drop-outs.
//!
//! Channel values returned by [`simulate_clean`] are in recording units: °C and µm.
#![allow(dead_code)]

pub mod gear;
pub mod orbit;
pub mod thermal;

use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{Rng, SeedableRng};

use gear::{Material, Pair, PairTemps, T_REF_K};
use thermal::{Load, Network, Solver};

/// Recording columns after `time_s`, in order.
pub const CHANNELS: [&str; 6] = [
    "housing_c",
    "motor_c",
    "shaft2_c",
    "gear1_c",
    "gear2_c",
    "backlash_um",
];

/// When a dissipation is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Schedule {
    Always,
    Sunlit,
    Eclipse,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gear {
    Pinion,
    Wheel,
}

/// An effect added to the reference model (physics.md §6), or one outside that
/// vocabulary (for "unexplained" tests). Node names as in the reference table
/// (`housing`, `motor`, `shaft1`, `shaft2`, `gear1.r0` …, boundaries `bus`, `space`);
/// channel names as in the recording header.
#[derive(Clone, Debug)]
pub enum Effect {
    /// Earth albedo Q = αA S a F max(0, cos θ cos β) and Earth IR Q = εA 237 F on `node`.
    AlbedoIr {
        node: String,
        albedo_absorptivity_area_m2: f64,
        ir_emissivity_area_m2: f64,
    },
    /// Heater on `node` with a thermostat reading the same node: on below `on_k`, off
    /// above `off_k`.
    Heater {
        node: String,
        power_w: f64,
        on_k: f64,
        off_k: f64,
    },
    Dissipation {
        node: String,
        power_w: f64,
        schedule: Schedule,
    },
    /// Centre distance a' = a (1 + α (T_node − T_ref)).
    HousingExpansion { node: String, alpha_per_k: f64 },
    /// Both gears (and, for a bore fit, their shafts): α(T) = α + dα/dT (T − T_ref),
    /// strain integrated.
    CteTemperature { dalpha_dt_per_k2: f64 },
    /// Bore on an elastic solid 17-4PH shaft with radial interference (shaft radius minus
    /// bore radius at 25 °C); shaft temperature = the shaft node the bore conducts to;
    /// contact transmits compression only.
    BoreFit { gear: Gear, interference_um: f64 },
    /// First-order thermistor on a temperature channel.
    SensorLag { channel: String, tau_s: f64 },
    /// Constant bias of a temperature channel.
    SensorOffset { channel: String, offset_k: f64 },
    /// Sun absorptivity × scale.
    AbsorptivityScale { scale: f64 },
    /// The linear conductor between `a` and `b` × scale (the radiative one if there is no
    /// linear one).
    ConductanceScale { a: String, b: String, scale: f64 },
    /// Both gears' α × scale (the whole strain law, dα/dT included; with a bore fit the
    /// shafts too, being the same 17-4PH). Shaft and housing conduction are unaffected.
    CteScale { scale: f64 },
    /// A node's heat capacity × scale.
    CapacitanceScale { node: String, scale: f64 },
    /// Outside the vocabulary: heat A sin(2π t / P) into `node`.
    PeriodicDisturbance {
        node: String,
        amplitude_w: f64,
        period_s: f64,
    },
    /// Outside the vocabulary: a conductor (as in `ConductanceScale`) × `scale_after`
    /// from `t_switch_s` on.
    StepConductance {
        a: String,
        b: String,
        scale_after: f64,
        t_switch_s: f64,
    },
}

/// How to make one recording.
#[derive(Clone, Debug)]
pub struct Recipe {
    pub effects: Vec<Effect>,
    /// Recording length in orbits; samples at k·sample_s up to orbits × period.
    pub orbits: f64,
    /// Nominal cadence (s).
    pub sample_s: f64,
    /// Sample k ≥ 1 at k·sample_s + U(−jitter, +jitter); at most 0.45 sample_s.
    pub jitter_s: f64,
    /// Gaussian noise on temperatures (K) and on backlash (µm).
    pub noise_k: f64,
    pub noise_um: f64,
    /// Quantisation steps (0 = none; then 6 decimals are written).
    pub quantum_k: f64,
    pub quantum_um: f64,
    /// Fraction of cells (not `time_s`) left empty.
    pub dropout: f64,
    /// Fraction of rows removed in whole-row gaps (bursts of 10 rows; the first row is
    /// kept).
    pub row_gaps: f64,
    pub seed: u64,
    /// Radial nodes per gear body (3 = the reference).
    pub gear_nodes: usize,
}

impl Default for Recipe {
    /// The settings of `shared/cases`: 12 orbits at 30 s, 0.15 K / 0.3 µm noise,
    /// 0.01 K / 0.001 µm quanta, no jitter, no drop-outs, reference discretisation.
    fn default() -> Self {
        Recipe {
            effects: Vec::new(),
            orbits: 12.0,
            sample_s: 30.0,
            jitter_s: 0.0,
            noise_k: 0.15,
            noise_um: 0.3,
            quantum_k: 0.01,
            quantum_um: 0.001,
            dropout: 0.0,
            row_gaps: 0.0,
            seed: 1,
            gear_nodes: 3,
        }
    }
}

impl Recipe {
    /// Default recipe with these effects.
    pub fn with(effects: Vec<Effect>) -> Recipe {
        Recipe {
            effects,
            ..Recipe::default()
        }
    }
}

fn channel_index(channel: &str) -> usize {
    match CHANNELS[..5].iter().position(|c| *c == channel) {
        Some(i) => i,
        None => panic!(
            "{channel:?} is not a temperature channel; they are {:?}",
            &CHANNELS[..5]
        ),
    }
}

/// The model a recipe describes: solver, gear pair and sensors.
struct Model {
    solver: Solver,
    pair: Pair,
    /// Node read by each temperature channel, and its lag state (if any).
    sensed: [usize; 5],
    lag_state: [Option<usize>; 5],
    offset_k: [f64; 5],
    housing_node: usize,
}

fn build(recipe: &Recipe) -> Model {
    let mut net = Network::reference(recipe.gear_nodes);
    let mut sun_scale = 1.0;
    let mut loads = Vec::new();
    let mut pair = Pair::default();
    let mut cte_scale = 1.0;
    let mut lags = Vec::new();
    let mut lag_state = [None; 5];
    let mut offset_k = [0.0; 5];
    let mut housing_node = thermal::HOUSING;
    for e in &recipe.effects {
        match e {
            Effect::AlbedoIr {
                node,
                albedo_absorptivity_area_m2,
                ir_emissivity_area_m2,
            } => {
                let node = net.index(node);
                loads.push(Load::Albedo {
                    node,
                    alpha_area_m2: *albedo_absorptivity_area_m2,
                });
                loads.push(Load::Constant {
                    node,
                    power_w: orbit::earth_ir_load_w(*ir_emissivity_area_m2),
                });
            }
            Effect::Heater {
                node,
                power_w,
                on_k,
                off_k,
            } => {
                assert!(on_k < off_k, "thermostat needs on < off");
                loads.push(Load::Heater {
                    node: net.index(node),
                    power_w: *power_w,
                    on_k: *on_k,
                    off_k: *off_k,
                });
            }
            Effect::Dissipation {
                node,
                power_w,
                schedule,
            } => loads.push(Load::Scheduled {
                node: net.index(node),
                power_w: *power_w,
                sunlit: match schedule {
                    Schedule::Always => None,
                    Schedule::Sunlit => Some(true),
                    Schedule::Eclipse => Some(false),
                },
            }),
            Effect::HousingExpansion { node, alpha_per_k } => {
                housing_node = net.index(node);
                pair.housing_alpha_per_k = Some(*alpha_per_k);
            }
            Effect::CteTemperature { dalpha_dt_per_k2 } => {
                pair.material.dalpha_dt_per_k2 = *dalpha_dt_per_k2
            }
            Effect::BoreFit {
                gear,
                interference_um,
            } => {
                pair.fit[*gear as usize] = Some(interference_um * 1e-6);
            }
            Effect::SensorLag { channel, tau_s } => {
                let c = channel_index(channel);
                lag_state[c] = Some(lags.len());
                lags.push((c, *tau_s)); // node filled in below
            }
            Effect::SensorOffset {
                channel,
                offset_k: o,
            } => offset_k[channel_index(channel)] += o,
            Effect::AbsorptivityScale { scale } => sun_scale *= scale,
            Effect::ConductanceScale { a, b, scale } => net.conductor_mut(a, b).g *= scale,
            Effect::CteScale { scale } => cte_scale *= scale,
            Effect::CapacitanceScale { node, scale } => {
                let i = net.index(node);
                net.cap[i] *= scale;
            }
            Effect::PeriodicDisturbance {
                node,
                amplitude_w,
                period_s,
            } => loads.push(Load::Periodic {
                node: net.index(node),
                amplitude_w: *amplitude_w,
                period_s: *period_s,
            }),
            Effect::StepConductance {
                a,
                b,
                scale_after,
                t_switch_s,
            } => net.conductor_mut(a, b).step = Some((*scale_after, *t_switch_s)),
        }
    }
    let m: &mut Material = &mut pair.material;
    m.alpha_per_k *= cte_scale;
    m.dalpha_dt_per_k2 *= cte_scale;
    loads.push(Load::Sun {
        node: thermal::HOUSING,
        alpha_area_m2: orbit::SUN_ALPHA_AREA_M2 * sun_scale,
    });
    let sensed = [
        thermal::HOUSING,
        thermal::MOTOR,
        thermal::SHAFT2,
        *net.gear_nodes[0].last().unwrap(),
        *net.gear_nodes[1].last().unwrap(),
    ];
    for lag in &mut lags {
        lag.0 = sensed[lag.0];
    }
    Model {
        solver: Solver::new(net, loads, lags),
        pair,
        sensed,
        lag_state,
        offset_k,
        housing_node,
    }
}

impl Model {
    /// Channel values (°C, µm) of one state.
    fn channels(&self, y: &[f64]) -> [f64; 6] {
        let n = self.solver.net.cap.len();
        let mut out = [0.0; 6];
        for c in 0..5 {
            let t = match self.lag_state[c] {
                Some(s) => y[n + s],
                None => y[self.sensed[c]],
            };
            out[c] = t + self.offset_k[c] - 273.15;
        }
        let net = &self.solver.net;
        let dts: [Vec<f64>; 2] =
            std::array::from_fn(|g| net.gear_nodes[g].iter().map(|&k| y[k] - T_REF_K).collect());
        let temps = PairTemps {
            radii_m: [&net.gear_radii_m[0], &net.gear_radii_m[1]],
            dt_k: [&dts[0], &dts[1]],
            shaft_dt_k: [y[thermal::SHAFT1] - T_REF_K, y[thermal::SHAFT2] - T_REF_K],
            housing_dt_k: y[self.housing_node] - T_REF_K,
        };
        out[5] = self.pair.backlash_m(&temps) * 1e6;
        out
    }
}

/// Noise-free channel values (°C, µm) at the given increasing times (s).
pub fn simulate_clean_at(recipe: &Recipe, times_s: &[f64]) -> Vec<[f64; 6]> {
    let model = build(recipe);
    model
        .solver
        .run(times_s)
        .iter()
        .map(|y| model.channels(y))
        .collect()
}

/// As [`simulate_clean_at`] with the largest RK4 step set to `step_s` (for convergence
/// checks of the generator itself).
pub fn simulate_clean_at_step(recipe: &Recipe, times_s: &[f64], step_s: f64) -> Vec<[f64; 6]> {
    let mut model = build(recipe);
    model.solver.step_s = step_s;
    model
        .solver
        .run(times_s)
        .iter()
        .map(|y| model.channels(y))
        .collect()
}

/// The RK4 step the recipe's network is integrated with (s).
pub fn step_s(recipe: &Recipe) -> f64 {
    build(recipe).solver.step_s
}

fn rng(seed: u64, purpose: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed ^ purpose.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// Uniform in (0, 1).
fn uniform(r: &mut ChaCha8Rng) -> f64 {
    ((r.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
}

/// Standard normal by Box–Muller.
fn gaussian(r: &mut ChaCha8Rng) -> f64 {
    let (u1, u2) = (uniform(r), uniform(r));
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// The recipe's sample times (with jitter and row gaps).
pub fn sample_times(recipe: &Recipe) -> Vec<f64> {
    assert!(recipe.sample_s > 0.0 && recipe.orbits > 0.0);
    assert!(
        recipe.jitter_s >= 0.0 && recipe.jitter_s <= 0.45 * recipe.sample_s,
        "jitter must be within 0 … 0.45 × cadence"
    );
    let t_end = recipe.orbits * orbit::period_s();
    let n = (t_end / recipe.sample_s + 1e-9).floor() as usize;
    let mut jr = rng(recipe.seed, 1);
    let mut gr = rng(recipe.seed, 2);
    let mut times = Vec::with_capacity(n + 1);
    let mut gap_left = 0;
    for k in 0..=n {
        let jitter = if k == 0 {
            0.0
        } else {
            recipe.jitter_s * (2.0 * uniform(&mut jr) - 1.0)
        };
        // one draw per row whatever happens, so gaps do not shift the jitter sequence
        let start_gap = uniform(&mut gr) < recipe.row_gaps / 10.0;
        if k > 0 && start_gap && gap_left == 0 {
            gap_left = 10;
        }
        if gap_left > 0 {
            gap_left -= 1;
            continue;
        }
        let t = (k as f64 * recipe.sample_s + jitter).min(t_end);
        // written with 3 decimals: round here so the CSV and the clean series agree
        times.push((t * 1000.0).round() / 1000.0);
    }
    times
}

/// Noise-free channel values (°C, µm) at the recipe's sample times.
pub fn simulate_clean(recipe: &Recipe) -> (Vec<f64>, Vec<[f64; 6]>) {
    let times = sample_times(recipe);
    let values = simulate_clean_at(recipe, &times);
    (times, values)
}

fn decimals(quantum: f64) -> usize {
    if quantum <= 0.0 {
        6
    } else {
        (-quantum.log10() - 1e-9).ceil().clamp(0.0, 9.0) as usize
    }
}

fn quantise(v: f64, q: f64) -> f64 {
    if q > 0.0 { (v / q).round() * q } else { v }
}

/// A recording as CSV text (reference-mechanism.md §4): header, then one row per
/// sample; an empty cell is a missing sample.
pub fn generate(recipe: &Recipe) -> String {
    let (times, clean) = simulate_clean(recipe);
    let mut nr = rng(recipe.seed, 3);
    let mut dr = rng(recipe.seed, 4);
    let (dk, du) = (decimals(recipe.quantum_k), decimals(recipe.quantum_um));
    let td = if recipe.jitter_s > 0.0 { 3 } else { 1 };
    let mut out = String::from("time_s,");
    out.push_str(&CHANNELS.join(","));
    out.push('\n');
    for (t, row) in times.iter().zip(&clean) {
        out.push_str(&format!("{t:.td$}"));
        for (c, v) in row.iter().enumerate() {
            let (sd, q, d) = if c < 5 {
                (recipe.noise_k, recipe.quantum_k, dk)
            } else {
                (recipe.noise_um, recipe.quantum_um, du)
            };
            let noisy = quantise(v + sd * gaussian(&mut nr), q);
            out.push(',');
            if uniform(&mut dr) >= recipe.dropout {
                out.push_str(&format!("{noisy:.d$}"));
            }
        }
        out.push('\n');
    }
    out
}

/// A recording read back: times and cells (`None` = empty), columns as [`CHANNELS`].
/// Panics on anything but the §4 format with exactly these columns.
pub fn read_recording(text: &str) -> (Vec<f64>, Vec<[Option<f64>; 6]>) {
    let mut lines = text.lines();
    let header = lines.next().expect("empty recording");
    let want = format!("time_s,{}", CHANNELS.join(","));
    assert_eq!(header.trim(), want, "unexpected header");
    let mut times = Vec::new();
    let mut rows = Vec::new();
    for (n, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), 7, "line {}: {} cells", n + 2, cells.len());
        times.push(cells[0].trim().parse::<f64>().unwrap());
        rows.push(std::array::from_fn(|c| {
            let s = cells[c + 1].trim();
            (!s.is_empty()).then(|| s.parse::<f64>().unwrap())
        }));
    }
    (times, rows)
}

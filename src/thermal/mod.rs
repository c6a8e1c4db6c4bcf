//! The lumped thermal network: diffusion nodes with capacitance, boundary nodes with
//! prescribed temperatures, linear and radiative conductors, environmental loads,
//! scheduled dissipation and thermostat-switched heaters.
//!
//! Invariants (established by the scenario reader, relied on here): capacitances and
//! conductances are positive and finite, every reference points at an existing node,
//! no conductor links a node to itself, heater `on_k < off_k`.

pub mod analysis;
pub mod iteration;
pub mod lu;
pub mod solver;
pub mod synthetic;

use crate::constants::STEFAN_BOLTZMANN_W_PER_M2_K4;
use crate::orbit::{EnvState, Environment, EnvironmentModel, Incidence, LoadKink, Profile};

#[derive(Debug, Clone, PartialEq)]
pub struct DiffusionNode {
    pub name: String,
    pub capacitance_j_per_k: f64,
    pub initial_temperature_k: f64,
    /// Radius along a gear, m (gear nodes only).
    pub radius_m: Option<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct BoundaryNode {
    pub name: String,
    pub temperature_k: Profile,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeRef {
    Diffusion(usize),
    Boundary(usize),
}

/// Heat flow G (Tb − Ta) into `a`.
#[derive(Debug, Clone, PartialEq)]
pub struct Conductor {
    pub a: NodeRef,
    pub b: NodeRef,
    pub conductance_w_per_k: f64,
}

/// Heat flow σ εA (Tb⁴ − Ta⁴) into `a`.
#[derive(Debug, Clone, PartialEq)]
pub struct Radiator {
    pub a: NodeRef,
    pub b: NodeRef,
    pub emissivity_area_m2: f64,
}

/// When a dissipation is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    Always,
    Sunlit,
    Eclipse,
    /// While the operating mode with this index is active.
    Mode(usize),
}

#[derive(Debug, Clone, PartialEq)]
pub enum LoadKind {
    Sun {
        absorptivity_area_m2: f64,
        incidence: Incidence,
    },
    Albedo {
        absorptivity_area_m2: f64,
        view_factor: f64,
    },
    EarthIr {
        emissivity_area_m2: f64,
        view_factor: f64,
    },
    Dissipation {
        power_w: Profile,
        when: When,
    },
    /// A body-fixed face: direct Sun, albedo and Earth infrared from its orientation
    /// (its emission is a radiative coupling to space beside it).
    Face(crate::orbit::faces::Face),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Load {
    pub name: String,
    pub node: usize,
    pub kind: LoadKind,
}

/// A heater on `node`, switched on when `sensor_node` falls to `on_k` and off when it
/// rises to `off_k`.
#[derive(Debug, Clone, PartialEq)]
pub struct Heater {
    pub name: String,
    pub node: usize,
    pub sensor_node: usize,
    pub power_w: f64,
    pub on_k: f64,
    pub off_k: f64,
}

/// An operating mode, active over half-open windows [start, end) of mission time.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    pub name: String,
    pub windows_s: Vec<(f64, f64)>,
}

impl Mode {
    pub fn active(&self, t_s: f64) -> bool {
        self.windows_s.iter().any(|&(a, b)| a <= t_s && t_s < b)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Network {
    pub nodes: Vec<DiffusionNode>,
    pub boundaries: Vec<BoundaryNode>,
    pub conductors: Vec<Conductor>,
    pub radiators: Vec<Radiator>,
    pub loads: Vec<Load>,
    pub heaters: Vec<Heater>,
}

/// Everything the thermal transient needs: environment, network, operating modes.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalModel {
    pub environment: Environment,
    pub network: Network,
    pub modes: Vec<Mode>,
}

impl Network {
    /// The loads that are faces, with their geometry, in load order.
    pub fn face_loads(&self) -> impl Iterator<Item = (&Load, &crate::orbit::faces::Face)> {
        self.loads.iter().filter_map(|l| match &l.kind {
            LoadKind::Face(f) => Some((l, f)),
            _ => None,
        })
    }

    pub fn node_index(&self, name: &str) -> Option<usize> {
        self.nodes.iter().position(|n| n.name == name)
    }

    pub fn initial_temperatures_k(&self) -> Vec<f64> {
        self.nodes.iter().map(|n| n.initial_temperature_k).collect()
    }
}

impl ThermalModel {
    /// Where a load's slope jumps: the terminator for albedo and for Sun on zenith or
    /// nadir faces, orbit noon and midnight for ram and wake faces. The solver lands
    /// steps on them.
    pub fn load_kinks(&self) -> Vec<LoadKink> {
        let mut v = Vec::new();
        for l in &self.network.loads {
            let a = match &l.kind {
                LoadKind::Albedo { .. }
                | LoadKind::Sun {
                    incidence: Incidence::Zenith | Incidence::Nadir,
                    ..
                } => LoadKink::Terminator,
                LoadKind::Sun {
                    incidence: Incidence::Ram | Incidence::Wake,
                    ..
                } => LoadKink::NoonMidnight,
                _ => continue,
            };
            if !v.contains(&a) {
                v.push(a);
            }
        }
        v
    }

    /// Every time at which a load or boundary changes its law (table knots, mode
    /// window edges), sorted and deduplicated. The solver lands steps on them.
    pub fn breakpoints_s(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self.environment.breakpoints_s();
        for b in &self.network.boundaries {
            v.extend_from_slice(b.temperature_k.knots_s());
        }
        for l in &self.network.loads {
            if let LoadKind::Dissipation { power_w, .. } = &l.kind {
                v.extend_from_slice(power_w.knots_s());
            }
        }
        for m in &self.modes {
            for &(a, b) in &m.windows_s {
                v.push(a);
                v.push(b);
            }
        }
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    }
}

/// Heat flows summed over the network at one instant, W.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Flows {
    /// Sun, albedo and Earth infrared absorbed.
    pub absorbed_w: f64,
    /// Scheduled dissipation and heaters.
    pub dissipated_w: f64,
    /// Net heat flowing into each boundary node (index as `Network::boundaries`).
    pub to_boundary_w: Vec<f64>,
}

/// What is switched during one step (decided at the step's midpoint).
#[derive(Debug, Clone, Copy)]
pub struct StepSwitches<'a> {
    pub heaters_on: &'a [bool],
    pub modes_active: &'a [bool],
}

/// The network compiled into flat edge lists for fast evaluation of
/// C dT/dt = f(t, T) and its Jacobian.
#[derive(Debug, Clone)]
pub struct Compiled {
    pub n: usize,
    pub capacitance_j_per_k: Vec<f64>,
    lin_nn: Vec<(usize, usize, f64)>,
    lin_nb: Vec<(usize, usize, f64)>,
    rad_nn: Vec<(usize, usize, f64)>,
    rad_nb: Vec<(usize, usize, f64)>,
    /// Boundary temperatures (and T⁴) at the time of the last `set_time`.
    boundary_k: Vec<f64>,
    boundary_k4: Vec<f64>,
    /// Loads per diffusion node at the time of the last `set_time`, W.
    load_w: Vec<f64>,
    /// Each load's own value at the last `set_time`, W.
    pub each_load_w: Vec<f64>,
    absorbed_w: f64,
    dissipated_w: f64,
}

impl Compiled {
    pub fn new(net: &Network) -> Compiled {
        let mut c = Compiled {
            n: net.nodes.len(),
            capacitance_j_per_k: net.nodes.iter().map(|n| n.capacitance_j_per_k).collect(),
            lin_nn: vec![],
            lin_nb: vec![],
            rad_nn: vec![],
            rad_nb: vec![],
            boundary_k: vec![0.0; net.boundaries.len()],
            boundary_k4: vec![0.0; net.boundaries.len()],
            load_w: vec![0.0; net.nodes.len()],
            each_load_w: vec![0.0; net.loads.len()],
            absorbed_w: 0.0,
            dissipated_w: 0.0,
        };
        let mut add = |a: NodeRef, b: NodeRef, g: f64, nn: bool| {
            use NodeRef::*;
            let (lists_nn, lists_nb) = if nn {
                (&mut c.lin_nn, &mut c.lin_nb)
            } else {
                (&mut c.rad_nn, &mut c.rad_nb)
            };
            match (a, b) {
                (Diffusion(i), Diffusion(j)) => lists_nn.push((i, j, g)),
                (Diffusion(i), Boundary(j)) | (Boundary(j), Diffusion(i)) => {
                    lists_nb.push((i, j, g))
                }
                (Boundary(_), Boundary(_)) => {}
            }
        };
        for k in &net.conductors {
            add(k.a, k.b, k.conductance_w_per_k, true);
        }
        for r in &net.radiators {
            add(
                r.a,
                r.b,
                STEFAN_BOLTZMANN_W_PER_M2_K4 * r.emissivity_area_m2,
                false,
            );
        }
        c
    }

    /// Evaluates boundary temperatures and loads at time `s.t_s`.
    pub fn set_time(&mut self, model: &ThermalModel, s: &EnvState, sw: StepSwitches<'_>) {
        let net = &model.network;
        let env = &model.environment;
        for (k, b) in net.boundaries.iter().enumerate() {
            let t = b.temperature_k.at(s.t_s);
            self.boundary_k[k] = t;
            self.boundary_k4[k] = t * t * t * t;
        }
        self.load_w.iter_mut().for_each(|q| *q = 0.0);
        self.absorbed_w = 0.0;
        self.dissipated_w = 0.0;
        // what faces see, evaluated once for all the faces of this instant, and the
        // albedo of two or more faces summed in one pass
        let mut faces_env = None;
        if net.face_loads().nth(1).is_some() {
            let fe = env.face_environment(s);
            crate::orbit::faces::prime_albedo(&fe, net.face_loads().map(|(_, f)| f));
            faces_env = Some(fe);
        }
        for (k, l) in net.loads.iter().enumerate() {
            let (q, absorbed) = load_w(env, s, &l.kind, sw.modes_active, &mut faces_env);
            self.each_load_w[k] = q;
            self.load_w[l.node] += q;
            if absorbed {
                self.absorbed_w += q;
            } else {
                self.dissipated_w += q;
            }
        }
        for (h, &on) in net.heaters.iter().zip(sw.heaters_on) {
            if on {
                self.load_w[h.node] += h.power_w;
                self.dissipated_w += h.power_w;
            }
        }
    }

    /// f(T) = net heat into each diffusion node, W, at the time of the last
    /// `set_time`. When `flows` is given, the network totals are written there.
    pub fn heat_w(&self, temps_k: &[f64], out_w: &mut [f64], flows: Option<&mut Flows>) {
        out_w.copy_from_slice(&self.load_w);
        for &(i, j, g) in &self.lin_nn {
            let q = g * (temps_k[j] - temps_k[i]);
            out_w[i] += q;
            out_w[j] -= q;
        }
        for &(i, j, s) in &self.rad_nn {
            let (ti, tj) = (temps_k[i], temps_k[j]);
            let q = s * (tj * tj * tj * tj - ti * ti * ti * ti);
            out_w[i] += q;
            out_w[j] -= q;
        }
        match flows {
            None => {
                for &(i, b, g) in &self.lin_nb {
                    out_w[i] += g * (self.boundary_k[b] - temps_k[i]);
                }
                for &(i, b, s) in &self.rad_nb {
                    let ti = temps_k[i];
                    out_w[i] += s * (self.boundary_k4[b] - ti * ti * ti * ti);
                }
            }
            Some(fl) => {
                fl.absorbed_w = self.absorbed_w;
                fl.dissipated_w = self.dissipated_w;
                fl.to_boundary_w.clear();
                fl.to_boundary_w.resize(self.boundary_k.len(), 0.0);
                for &(i, b, g) in &self.lin_nb {
                    let q = g * (self.boundary_k[b] - temps_k[i]);
                    out_w[i] += q;
                    fl.to_boundary_w[b] -= q;
                }
                for &(i, b, s) in &self.rad_nb {
                    let ti = temps_k[i];
                    let q = s * (self.boundary_k4[b] - ti * ti * ti * ti);
                    out_w[i] += q;
                    fl.to_boundary_w[b] -= q;
                }
            }
        }
    }

    /// Jacobian ∂f/∂T (row-major, n×n) at `temps_k`.
    pub fn jacobian(&self, temps_k: &[f64], jac: &mut [f64]) {
        let n = self.n;
        jac.iter_mut().for_each(|x| *x = 0.0);
        let mut link = |i: usize, j: usize, d_i: f64, d_j: f64| {
            // q = flow into i; ∂q/∂Ti = -d_i, ∂q/∂Tj = d_j
            jac[i * n + i] -= d_i;
            jac[i * n + j] += d_j;
            jac[j * n + j] -= d_j;
            jac[j * n + i] += d_i;
        };
        for &(i, j, g) in &self.lin_nn {
            link(i, j, g, g);
        }
        for &(i, j, s) in &self.rad_nn {
            let (ti, tj) = (temps_k[i], temps_k[j]);
            link(i, j, 4.0 * s * ti * ti * ti, 4.0 * s * tj * tj * tj);
        }
        for &(i, _, g) in &self.lin_nb {
            jac[i * n + i] -= g;
        }
        for &(i, _, s) in &self.rad_nb {
            let ti = temps_k[i];
            jac[i * n + i] -= 4.0 * s * ti * ti * ti;
        }
    }
}

/// A load's heat at one instant, W, and whether it is absorbed from the environment
/// (true) or dissipated inside (false).
fn load_w(
    env: &Environment,
    s: &EnvState,
    kind: &LoadKind,
    modes_active: &[bool],
    faces_env: &mut Option<crate::orbit::faces::FaceEnvironment>,
) -> (f64, bool) {
    match kind {
        LoadKind::Sun {
            absorptivity_area_m2,
            incidence,
        } => (env.sun_w(s, *absorptivity_area_m2, *incidence), true),
        LoadKind::Albedo {
            absorptivity_area_m2,
            view_factor,
        } => (env.albedo_w(s, *absorptivity_area_m2, *view_factor), true),
        LoadKind::EarthIr {
            emissivity_area_m2,
            view_factor,
        } => (env.earth_ir_w(*emissivity_area_m2, *view_factor), true),
        LoadKind::Face(face) => (
            crate::orbit::faces::absorbed_w(
                face,
                faces_env.get_or_insert_with(|| env.face_environment(s)),
            ),
            true,
        ),
        LoadKind::Dissipation { power_w, when } => {
            let on = match when {
                When::Always => true,
                When::Sunlit => s.sunlit,
                When::Eclipse => !s.sunlit,
                When::Mode(m) => modes_active[*m],
            };
            (if on { power_w.at(s.t_s) } else { 0.0 }, false)
        }
    }
}

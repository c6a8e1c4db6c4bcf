//! Derived quantities of a network that need no time stepping: the conductance
//! matrix linearised about a temperature state, node time constants and the
//! stiffness of the system (for `orbitlash check`).

use nalgebra::{DMatrix, DVector};

use super::{Network, NodeRef};
use crate::constants::STEFAN_BOLTZMANN_W_PER_M2_K4;

/// K such that the heat into the diffusion nodes is −K T + (boundary terms),
/// radiation linearised as 4σεA T̄³ with T̄ the mean of the two ends' temperatures.
pub fn linearized_conductance(net: &Network, temps_k: &[f64], boundary_k: &[f64]) -> DMatrix<f64> {
    let n = net.nodes.len();
    let mut k = DMatrix::zeros(n, n);
    let temp = |r: NodeRef| match r {
        NodeRef::Diffusion(i) => temps_k[i],
        NodeRef::Boundary(b) => boundary_k[b],
    };
    let mut add = |a: NodeRef, b: NodeRef, g: f64| {
        if let NodeRef::Diffusion(i) = a {
            k[(i, i)] += g;
            if let NodeRef::Diffusion(j) = b {
                k[(i, j)] -= g;
            }
        }
        if let NodeRef::Diffusion(j) = b {
            k[(j, j)] += g;
            if let NodeRef::Diffusion(i) = a {
                k[(j, i)] -= g;
            }
        }
    };
    for c in &net.conductors {
        add(c.a, c.b, c.conductance_w_per_k);
    }
    for r in &net.radiators {
        // σεA (Tb⁴ − Ta⁴) = σεA (Ta² + Tb²)(Ta + Tb)(Tb − Ta): exact secant conductance.
        let (ta, tb) = (temp(r.a), temp(r.b));
        let g =
            STEFAN_BOLTZMANN_W_PER_M2_K4 * r.emissivity_area_m2 * (ta * ta + tb * tb) * (ta + tb);
        add(r.a, r.b, g);
    }
    k
}

/// Time constants of the network about a state.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeConstants {
    /// C_i / K_ii per node: how fast a node follows its neighbours, s.
    pub node_s: Vec<f64>,
    /// Slowest and fastest eigen time constants of C⁻¹K, s.
    pub slowest_s: f64,
    pub fastest_s: f64,
}

impl TimeConstants {
    /// Stiffness ratio: slowest / fastest time constant.
    pub fn stiffness_ratio(&self) -> f64 {
        self.slowest_s / self.fastest_s
    }
}

pub fn time_constants(net: &Network, temps_k: &[f64], boundary_k: &[f64]) -> TimeConstants {
    let k = linearized_conductance(net, temps_k, boundary_k);
    let c: DVector<f64> = DVector::from_iterator(
        net.nodes.len(),
        net.nodes.iter().map(|n| n.capacitance_j_per_k),
    );
    let node_s = (0..c.len()).map(|i| c[i] / k[(i, i)]).collect();
    // C^-1/2 K C^-1/2 is symmetric with the eigenvalues of C⁻¹K.
    let s = c.map(|x| 1.0 / x.sqrt());
    let m = DMatrix::from_fn(c.len(), c.len(), |i, j| s[i] * k[(i, j)] * s[j]);
    let eig = m.symmetric_eigenvalues();
    let lo = eig.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = eig.iter().copied().fold(0.0, f64::max);
    TimeConstants {
        node_s,
        slowest_s: 1.0 / lo,
        fastest_s: 1.0 / hi,
    }
}

/// Time constant of every diffusion node at time `t_s` and temperatures `temps_k`:
/// C_i over the sum of its conductances, radiation linearised as in
/// [`linearized_conductance`], s; infinite for a node with no link. O(links).
pub fn node_time_constants_s(model: &super::ThermalModel, temps_k: &[f64], t_s: f64) -> Vec<f64> {
    let net = &model.network;
    let boundary_k: Vec<f64> = net
        .boundaries
        .iter()
        .map(|b| b.temperature_k.at(t_s))
        .collect();
    let temp = |r: NodeRef| match r {
        NodeRef::Diffusion(j) => temps_k[j].max(0.0),
        NodeRef::Boundary(b) => boundary_k[b],
    };
    let mut g = vec![0.0; net.nodes.len()];
    let mut add = |a: NodeRef, b: NodeRef, x: f64| {
        for r in [a, b] {
            if let NodeRef::Diffusion(i) = r {
                g[i] += x;
            }
        }
    };
    for c in &net.conductors {
        add(c.a, c.b, c.conductance_w_per_k);
    }
    for r in &net.radiators {
        let (ta, tb) = (temp(r.a), temp(r.b));
        add(
            r.a,
            r.b,
            STEFAN_BOLTZMANN_W_PER_M2_K4 * r.emissivity_area_m2 * (ta * ta + tb * tb) * (ta + tb),
        );
    }
    net.nodes
        .iter()
        .zip(g)
        .map(|(n, g)| n.capacitance_j_per_k / g)
        .collect()
}

/// [`node_time_constants_s`] of node `i`.
pub fn node_time_constant_s(
    model: &super::ThermalModel,
    temps_k: &[f64],
    t_s: f64,
    i: usize,
) -> f64 {
    node_time_constants_s(model, temps_k, t_s)[i]
}

/// Per diffusion node: true when no chain of conductors or radiative links joins it to
/// a boundary node, so the heat it receives has nowhere to go and its temperature can
/// run away (or, with no load, it drifts with its neighbours forever). O(links).
pub fn unanchored_nodes(net: &Network) -> Vec<bool> {
    let n = net.nodes.len();
    // Union-find over diffusion nodes plus one extra element standing for "a boundary".
    let mut parent: Vec<usize> = (0..=n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let index = |r: NodeRef| match r {
        NodeRef::Diffusion(i) => i,
        NodeRef::Boundary(_) => n,
    };
    let links = net
        .conductors
        .iter()
        .map(|c| (c.a, c.b))
        .chain(net.radiators.iter().map(|r| (r.a, r.b)));
    for (a, b) in links {
        let (ra, rb) = (find(&mut parent, index(a)), find(&mut parent, index(b)));
        if ra != rb {
            parent[ra] = rb;
        }
    }
    let anchor = find(&mut parent, n);
    (0..n).map(|i| find(&mut parent, i) != anchor).collect()
}

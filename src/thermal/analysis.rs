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

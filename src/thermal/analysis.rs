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

/// Above this many nodes the eigen time constants come from sparse iterations (power
/// and inverse iteration) instead of a dense eigen decomposition (O(n³)).
pub const DENSE_EIGEN_MAX_NODES: usize = 400;

pub fn time_constants(net: &Network, temps_k: &[f64], boundary_k: &[f64]) -> TimeConstants {
    if net.nodes.len() > DENSE_EIGEN_MAX_NODES {
        return time_constants_sparse(net, temps_k, boundary_k);
    }
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

/// The linearised conductance matrix K of [`linearized_conductance`] in compressed
/// rows (row pointers, columns, values; the diagonal included).
fn conductance_csr(
    net: &Network,
    temps_k: &[f64],
    boundary_k: &[f64],
) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let n = net.nodes.len();
    let mut rows: Vec<Vec<(usize, f64)>> = (0..n).map(|i| vec![(i, 0.0)]).collect();
    let temp = |r: NodeRef| match r {
        NodeRef::Diffusion(i) => temps_k[i],
        NodeRef::Boundary(b) => boundary_k[b],
    };
    let mut add = |a: NodeRef, b: NodeRef, g: f64| match (a, b) {
        (NodeRef::Diffusion(i), NodeRef::Diffusion(j)) => {
            rows[i][0].1 += g;
            rows[j][0].1 += g;
            rows[i].push((j, -g));
            rows[j].push((i, -g));
        }
        (NodeRef::Diffusion(i), NodeRef::Boundary(_))
        | (NodeRef::Boundary(_), NodeRef::Diffusion(i)) => {
            rows[i][0].1 += g;
        }
        _ => {}
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
    let mut ptr = vec![0];
    let mut col = Vec::new();
    let mut val = Vec::new();
    for row in rows {
        for (j, v) in row {
            col.push(j);
            val.push(v);
        }
        ptr.push(col.len());
    }
    (ptr, col, val)
}

/// Slowest and fastest eigen time constants of C⁻¹K by iterations on the sparse K: the
/// largest eigenvalue of C^-½ K C^-½ by power iteration, the smallest by inverse
/// iteration (K y = C x by diagonally preconditioned conjugate gradients). A network
/// with a node that has no path to a boundary has a zero eigenvalue: slowest = ∞.
/// Three significant digits, which is what `check` prints.
fn time_constants_sparse(net: &Network, temps_k: &[f64], boundary_k: &[f64]) -> TimeConstants {
    let n = net.nodes.len();
    let (ptr, col, val) = conductance_csr(net, temps_k, boundary_k);
    let c: Vec<f64> = net.nodes.iter().map(|x| x.capacitance_j_per_k).collect();
    let kmul = |x: &[f64], y: &mut [f64]| {
        for i in 0..n {
            y[i] = (ptr[i]..ptr[i + 1]).map(|k| val[k] * x[col[k]]).sum();
        }
    };
    let diag: Vec<f64> = (0..n).map(|i| val[ptr[i]]).collect();
    let node_s = (0..n).map(|i| c[i] / diag[i]).collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    // Power iteration on S = C^-1/2 K C^-1/2.
    let s = |x: &[f64], y: &mut [f64], tmp: &mut [f64]| {
        for i in 0..n {
            tmp[i] = x[i] / c[i].sqrt();
        }
        kmul(tmp, y);
        for i in 0..n {
            y[i] /= c[i].sqrt();
        }
    };
    // Lanczos with full reorthogonalisation: the largest Ritz value converges to the
    // largest eigenvalue in a few dozen steps.
    let steps = n.min(80);
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(steps);
    let mut v: Vec<f64> = (0..n).map(|i| 1.0 + ((i * 7919) % 13) as f64).collect();
    let norm = dot(&v, &v).sqrt();
    v.iter_mut().for_each(|x| *x /= norm);
    let (mut alpha, mut beta) = (Vec::new(), Vec::new());
    let (mut y, mut tmp) = (vec![0.0; n], vec![0.0; n]);
    for _ in 0..steps {
        s(&v, &mut y, &mut tmp);
        let a = dot(&v, &y);
        alpha.push(a);
        basis.push(v.clone());
        for b in &basis {
            let proj = dot(b, &y);
            y.iter_mut().zip(b).for_each(|(yi, bi)| *yi -= proj * bi);
        }
        let b = dot(&y, &y).sqrt();
        if b <= 1e-12 * a.abs().max(1e-300) {
            break;
        }
        beta.push(b);
        v = y.iter().map(|x| x / b).collect();
    }
    let k = alpha.len();
    let t = DMatrix::from_fn(k, k, |i, j| {
        if i == j {
            alpha[i]
        } else if i + 1 == j || j + 1 == i {
            beta[i.min(j)]
        } else {
            0.0
        }
    });
    let lambda_max = t
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .fold(0.0, f64::max);
    let lambda_min = if unanchored_nodes(net).iter().any(|&u| u) {
        0.0
    } else {
        // Inverse iteration for K v = λ C v.
        let mut v: Vec<f64> = vec![1.0; n];
        let mut lambda = f64::NAN;
        let (mut r, mut z, mut p, mut q, mut w) = (
            vec![0.0; n],
            vec![0.0; n],
            vec![0.0; n],
            vec![0.0; n],
            vec![0.0; n],
        );
        for _ in 0..60 {
            // w = K⁻¹ C v
            let b: Vec<f64> = (0..n).map(|i| c[i] * v[i]).collect();
            let bnorm = dot(&b, &b).sqrt();
            w.iter_mut().for_each(|x| *x = 0.0);
            r.copy_from_slice(&b);
            for i in 0..n {
                z[i] = r[i] / diag[i];
            }
            p.copy_from_slice(&z);
            let mut rz = dot(&r, &z);
            for _ in 0..20 * n.max(50) {
                if dot(&r, &r).sqrt() <= 1e-10 * bnorm {
                    break;
                }
                kmul(&p, &mut q);
                let alpha = rz / dot(&p, &q);
                for i in 0..n {
                    w[i] += alpha * p[i];
                    r[i] -= alpha * q[i];
                    z[i] = r[i] / diag[i];
                }
                let rz_new = dot(&r, &z);
                let beta = rz_new / rz;
                rz = rz_new;
                for i in 0..n {
                    p[i] = z[i] + beta * p[i];
                }
            }
            // Rayleigh quotient λ = wᵀ K w / wᵀ C w
            kmul(&w, &mut q);
            let cw: f64 = (0..n).map(|i| w[i] * c[i] * w[i]).sum();
            let l = dot(&w, &q) / cw;
            let norm = cw.sqrt();
            for i in 0..n {
                v[i] = w[i] / norm;
            }
            let done = (l - lambda).abs() <= 1e-9 * l;
            lambda = l;
            if done {
                break;
            }
        }
        lambda
    };
    TimeConstants {
        node_s,
        slowest_s: 1.0 / lambda_min,
        fastest_s: 1.0 / lambda_max,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sparse iterations agree with the dense eigen decomposition.
    #[test]
    fn core_sparse_time_constants_match_dense() {
        use crate::thermal::synthetic::{Shape, network};
        for shape in [Shape::Lattice, Shape::Random, Shape::Chain] {
            let m = network(shape, 120);
            let net = &m.network;
            let temps = net.initial_temperatures_k();
            let boundary = [3.0];
            let k = linearized_conductance(net, &temps, &boundary);
            let c: Vec<f64> = net.nodes.iter().map(|n| n.capacitance_j_per_k).collect();
            let s = DMatrix::from_fn(c.len(), c.len(), |i, j| k[(i, j)] / (c[i] * c[j]).sqrt());
            let eig = s.symmetric_eigenvalues();
            let lo = eig.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = eig.iter().copied().fold(0.0, f64::max);
            let t = time_constants_sparse(net, &temps, &boundary);
            assert!(
                (t.slowest_s * lo - 1.0).abs() < 1e-3,
                "{shape:?}: slowest {} vs {}",
                t.slowest_s,
                1.0 / lo
            );
            assert!(
                (t.fastest_s * hi - 1.0).abs() < 1e-3,
                "{shape:?}: fastest {} vs {}",
                t.fastest_s,
                1.0 / hi
            );
        }
    }
}

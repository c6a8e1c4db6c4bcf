//! Steady state of a linear network from time stepping against a direct linear solve
//! of the conductance matrix assembled here, independently of the library's assembly.

mod common;

use nalgebra::{DMatrix, DVector};
use orbitlash::run::sim::simulate;
use orbitlash::thermal::{LoadKind, NodeRef};

#[test]
fn val_direct_solve_steady_state_network() {
    let body = r#"
[[node]]
name = "a"
capacitance_j_per_k = 40.0
initial_temperature_k = 300.0
[[node]]
name = "b"
capacitance_j_per_k = 5.0
initial_temperature_k = 250.0
[[node]]
name = "c"
capacitance_j_per_k = 12.0
initial_temperature_k = 280.0
[[node]]
name = "d"
capacitance_j_per_k = 0.8
initial_temperature_k = 320.0
[[boundary]]
name = "cold"
temperature_k = 240.0
[[boundary]]
name = "warm"
temperature_k = 310.0
[[conductor]]
between = ["a", "b"]
conductance_w_per_k = 0.4
[[conductor]]
between = ["b", "c"]
conductance_w_per_k = 1.3
[[conductor]]
between = ["c", "d"]
conductance_w_per_k = 0.05
[[conductor]]
between = ["a", "cold"]
conductance_w_per_k = 0.2
[[conductor]]
between = ["warm", "d"]
conductance_w_per_k = 0.7
[[conductor]]
between = ["a", "c"]
conductance_w_per_k = 0.15
[[dissipation]]
node = "b"
power_w = 3.5
[[dissipation]]
node = "d"
power_w = 0.6
"#;
    let sc = common::scenario("", "beta_deg = 90.0", "duration_s = 40000.0", body);
    let net = &sc.thermal.network;
    let n = net.nodes.len();

    // Assemble K T = q directly from the scenario's conductors and loads.
    let mut k = DMatrix::<f64>::zeros(n, n);
    let mut q = DVector::<f64>::zeros(n);
    for c in &net.conductors {
        let g = c.conductance_w_per_k;
        match (c.a, c.b) {
            (NodeRef::Diffusion(i), NodeRef::Diffusion(j)) => {
                k[(i, i)] += g;
                k[(j, j)] += g;
                k[(i, j)] -= g;
                k[(j, i)] -= g;
            }
            (NodeRef::Diffusion(i), NodeRef::Boundary(b))
            | (NodeRef::Boundary(b), NodeRef::Diffusion(i)) => {
                k[(i, i)] += g;
                q[i] += g * net.boundaries[b].temperature_k.at(0.0);
            }
            _ => unreachable!(),
        }
    }
    for l in &net.loads {
        if let LoadKind::Dissipation { power_w, .. } = &l.kind {
            q[l.node] += power_w.at(0.0);
        }
    }
    let direct = k.lu().solve(&q).unwrap();

    let stats = simulate(&sc.thermal, &sc.gears, &sc.solver, 40000.0, &mut (), None).unwrap();
    for i in 0..n {
        let d = (stats.final_temperatures_k[i] - direct[i]).abs();
        assert!(
            d < 1e-3,
            "node {}: stepped {} K, direct {} K",
            net.nodes[i].name,
            stats.final_temperatures_k[i],
            direct[i]
        );
    }
    // Energy bookkeeping closes.
    assert!(
        stats.energy.relative_error() < 1e-8,
        "energy error {}",
        stats.energy.relative_error()
    );
}

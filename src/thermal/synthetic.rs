//! Synthetic networks of any size, for the scaling benchmarks (`orbitlash bench
//! --scaling`) and the tests of large networks: chains, 3-D lattices shaped like a
//! meshed structure (nearest-neighbour conduction, plus long-range links standing for
//! bolted joints and radiative couplings), and random sparse graphs. Deterministic:
//! the same arguments give the same network.
//!
//! Every network sits on the reference orbit (500 km, β = 20°); its outer nodes take
//! Sun and radiate to space, so it cycles through sunlight and eclipse like a real one.

use super::{
    BoundaryNode, Conductor, DiffusionNode, Load, LoadKind, Network, NodeRef, Radiator,
    ThermalModel,
};
use crate::constants::{
    EARTH_ALBEDO, EARTH_IR_W_PER_M2, EARTH_MU_M3_PER_S2, EARTH_RADIUS_M, SOLAR_CONSTANT_W_PER_M2,
    SPACE_SINK_K,
};
use crate::orbit::{CircularEnvironment, Incidence, Orbit, Profile};

/// The shape of a synthetic network.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// Nodes in a line.
    Chain,
    /// A 3-D grid with nearest-neighbour links plus one long-range link per ten nodes.
    Lattice,
    /// Each node linked to three others drawn at random (mean degree 6, as a lattice).
    Random,
}

impl Shape {
    pub fn name(self) -> &'static str {
        match self {
            Shape::Chain => "chain",
            Shape::Lattice => "lattice",
            Shape::Random => "random",
        }
    }
}

/// SplitMix64: a small, fixed generator, so networks do not depend on a crate's
/// version.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// The dimensions of the lattice of about `n` nodes: 20 × 10 × 10 for 2000, cubes
/// elsewhere.
pub fn lattice_dims(n: usize) -> [usize; 3] {
    match n {
        2000 => [20, 10, 10],
        _ => {
            let side = (n as f64).cbrt().round().max(1.0) as usize;
            let nz = side.max(1);
            let ny = side.max(1);
            let nx = n.div_ceil(ny * nz).max(1);
            [nx, ny, nz]
        }
    }
}

/// A network of (about, for lattices) `n` nodes of the given shape.
pub fn network(shape: Shape, n: usize) -> ThermalModel {
    network_scaled(shape, n, 1.0)
}

/// [`network`] with every node-to-node conductance multiplied by `g_scale` (100: node
/// time constants of a fraction of a second, a stiff network).
pub fn network_scaled(shape: Shape, n: usize, g_scale: f64) -> ThermalModel {
    let mut rng = Rng(0x5EED ^ n as u64);
    let dims = lattice_dims(n);
    let count = match shape {
        Shape::Lattice => dims[0] * dims[1] * dims[2],
        _ => n.max(2),
    };
    let nodes: Vec<DiffusionNode> = (0..count)
        .map(|i| DiffusionNode {
            name: format!("n{i}"),
            // 50–100 g of aluminium
            capacitance_j_per_k: 45.0 + 45.0 * (i % 7) as f64 / 6.0,
            initial_temperature_k: 293.15,
            radius_m: None,
        })
        .collect();
    let d = NodeRef::Diffusion;
    let mut conductors = Vec::new();
    let mut radiators = Vec::new();
    let link = |c: &mut Vec<Conductor>, a: usize, b: usize, g: f64| {
        c.push(Conductor {
            a: d(a),
            b: d(b),
            conductance_w_per_k: g * g_scale,
        })
    };
    // The nodes that face space: they take Sun and radiate.
    let mut outer: Vec<usize> = Vec::new();
    match shape {
        Shape::Chain => {
            for i in 0..count - 1 {
                link(&mut conductors, i, i + 1, 0.5);
            }
            outer.extend((0..count).step_by(10));
        }
        Shape::Lattice => {
            let [nx, ny, nz] = dims;
            let id = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
            for z in 0..nz {
                for y in 0..ny {
                    for x in 0..nx {
                        let i = id(x, y, z);
                        if x + 1 < nx {
                            link(&mut conductors, i, id(x + 1, y, z), 0.5);
                        }
                        if y + 1 < ny {
                            link(&mut conductors, i, id(x, y + 1, z), 0.5);
                        }
                        if z + 1 < nz {
                            link(&mut conductors, i, id(x, y, z + 1), 0.5);
                        }
                        if z + 1 == nz {
                            outer.push(i);
                        }
                    }
                }
            }
            // Bolted joints and radiative couplings between distant parts.
            for k in 0..count / 10 {
                let (a, b) = (rng.below(count), rng.below(count));
                if a == b {
                    continue;
                }
                if k % 2 == 0 {
                    link(&mut conductors, a, b, 0.05);
                } else {
                    radiators.push(Radiator {
                        a: d(a),
                        b: d(b),
                        emissivity_area_m2: 0.01,
                    });
                }
            }
        }
        Shape::Random => {
            for a in 0..count {
                for _ in 0..3 {
                    let b = rng.below(count);
                    if b != a {
                        link(&mut conductors, a, b, 0.5);
                    }
                }
            }
            outer.extend((0..count).step_by(10));
        }
    }
    let mut loads = Vec::new();
    for &i in &outer {
        radiators.push(Radiator {
            a: d(i),
            b: NodeRef::Boundary(0),
            emissivity_area_m2: 0.004,
        });
        loads.push(Load {
            name: format!("sun.n{i}"),
            node: i,
            kind: LoadKind::Sun {
                absorptivity_area_m2: 0.002,
                incidence: Incidence::Tracking,
            },
        });
    }
    ThermalModel {
        environment: CircularEnvironment {
            orbit: Orbit {
                altitude_m: 500e3,
                earth_radius_m: EARTH_RADIUS_M,
                mu_m3_per_s2: EARTH_MU_M3_PER_S2,
                orbit_angle_at_start_rad: 0.0,
            },
            beta_rad: Profile::Constant(20f64.to_radians()),
            solar_flux_w_per_m2: Profile::Constant(SOLAR_CONSTANT_W_PER_M2),
            albedo: EARTH_ALBEDO,
            earth_ir_w_per_m2: EARTH_IR_W_PER_M2,
            space_sink_k: SPACE_SINK_K,
        }
        .into(),
        network: Network {
            nodes,
            boundaries: vec![BoundaryNode {
                name: "space".into(),
                temperature_k: Profile::Constant(SPACE_SINK_K),
            }],
            conductors,
            radiators,
            loads,
            heaters: vec![],
        },
        modes: vec![],
    }
}

/// A synthetic network as scenario text (TOML) that `orbitlash run` and `check`
/// accept, running `orbits` orbits: for trying large networks end to end.
pub fn to_toml(model: &ThermalModel, name: &str, orbits: f64) -> String {
    use std::fmt::Write as _;
    let net = &model.network;
    let node = |r: NodeRef| match r {
        NodeRef::Diffusion(i) => net.nodes[i].name.clone(),
        NodeRef::Boundary(b) => net.boundaries[b].name.clone(),
    };
    let mut o = String::new();
    let _ = write!(
        o,
        "# A synthetic network of {} nodes (orbitlash bench --emit-network).\n\
         [scenario]\nname = \"{name}\"\n\n[orbit]\naltitude_m = {}\n\n\
         [environment]\nbeta_deg = {}\n\n[run]\norbits = {orbits}\n\n",
        net.nodes.len(),
        model
            .environment
            .circular()
            .expect("synthetic networks fly a circular orbit")
            .orbit
            .altitude_m,
        model
            .environment
            .circular()
            .expect("synthetic networks fly a circular orbit")
            .beta_rad
            .at(0.0)
            .to_degrees()
    );
    for n in &net.nodes {
        let _ = writeln!(
            o,
            "[[node]]\nname = \"{}\"\ncapacitance_j_per_k = {}\ninitial_temperature_k = {}\n",
            n.name, n.capacitance_j_per_k, n.initial_temperature_k
        );
    }
    for c in &net.conductors {
        let _ = writeln!(
            o,
            "[[conductor]]\nbetween = [\"{}\", \"{}\"]\nconductance_w_per_k = {}\n",
            node(c.a),
            node(c.b),
            c.conductance_w_per_k
        );
    }
    for r in &net.radiators {
        let _ = writeln!(
            o,
            "[[radiation]]\nbetween = [\"{}\", \"{}\"]\nemissivity_area_m2 = {}\n",
            node(r.a),
            node(r.b),
            r.emissivity_area_m2
        );
    }
    for l in &net.loads {
        if let LoadKind::Sun {
            absorptivity_area_m2,
            ..
        } = l.kind
        {
            let _ = writeln!(
                o,
                "[[sun]]\nnode = \"{}\"\nabsorptivity_area_m2 = {absorptivity_area_m2}\n",
                net.nodes[l.node].name
            );
        }
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_the_2000_node_lattice_is_the_issue_s_structure() {
        let m = network(Shape::Lattice, 2000);
        let net = &m.network;
        assert_eq!(net.nodes.len(), 2000);
        // 5500 nearest-neighbour links, about 200 long-range, 200 faces to space
        let links = net.conductors.len() + net.radiators.len();
        assert!((5850..=5900).contains(&links), "{links}");
        assert!(
            crate::thermal::analysis::unanchored_nodes(net)
                .iter()
                .all(|u| !u)
        );
        assert_eq!(network(Shape::Lattice, 2000), m, "not deterministic");
    }
}

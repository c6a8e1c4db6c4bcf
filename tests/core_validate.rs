//! The model's invariants are checked whatever built the model (issue 9): every
//! compiled scenario passes `Scenario::validate`, and a model edited by a program into
//! breaking one is refused, naming what.

use orbitlash::io::scenario_toml;
use orbitlash::orbit::Profile;
use orbitlash::spec::scenario::Scenario;
use orbitlash::thermal::synthetic::{Shape, network};
use orbitlash::thermal::{Conductor, NodeRef};

fn scenarios() -> Vec<Scenario> {
    ["reference-hinge.toml", "hinge-90-day-drift.toml"]
        .iter()
        .map(|f| {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("scenarios")
                .join(f);
            scenario_toml::load_file(&path).unwrap().0
        })
        .collect()
}

#[test]
fn core_compiled_models_are_valid() {
    // every shipped scenario: the invariants are the compiler's own checks
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    for f in std::fs::read_dir(dir).unwrap() {
        let path = f.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let sc = scenario_toml::load_file(&path).unwrap().0;
            sc.validate()
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        }
    }
    for shape in [Shape::Chain, Shape::Lattice, Shape::Random] {
        network(shape, 500).validate().unwrap();
    }
}

#[test]
fn core_broken_models_are_refused_naming_what() {
    let base = scenarios().remove(1);
    type Edit = Box<dyn Fn(&mut Scenario)>;
    let cases: Vec<(&str, Edit)> = vec![
        (
            "network.nodes[0]",
            Box::new(|s| s.thermal.network.nodes[0].capacitance_j_per_k = -1.0),
        ),
        (
            "network.nodes[2]",
            Box::new(|s| s.thermal.network.nodes[2].initial_temperature_k = f64::NAN),
        ),
        (
            "network.conductors[",
            Box::new(|s| {
                s.thermal.network.conductors.push(Conductor {
                    a: NodeRef::Diffusion(0),
                    b: NodeRef::Diffusion(0),
                    conductance_w_per_k: 1.0,
                })
            }),
        ),
        (
            "network.conductors[",
            Box::new(|s| {
                s.thermal.network.conductors.push(Conductor {
                    a: NodeRef::Diffusion(0),
                    b: NodeRef::Diffusion(99),
                    conductance_w_per_k: 1.0,
                })
            }),
        ),
        (
            "network.heaters[0]",
            Box::new(|s| {
                let h = &mut s.thermal.network.heaters[0];
                h.on_k = h.off_k + 1.0;
            }),
        ),
        (
            "network.boundaries[",
            Box::new(|s| {
                s.thermal.network.boundaries[0].temperature_k = Profile::Table {
                    time_s: vec![0.0, 0.0],
                    value: vec![3.0, 3.0],
                }
            }),
        ),
        (
            "environment.albedo",
            Box::new(|s| s.thermal.environment.circular_mut().unwrap().albedo = 1.5),
        ),
        (
            "environment.orbit period",
            Box::new(|s| {
                s.thermal
                    .environment
                    .circular_mut()
                    .unwrap()
                    .orbit
                    .mu_m3_per_s2 = 1e9
            }),
        ),
        (
            "modes[0]",
            Box::new(|s| s.thermal.modes[0].windows_s = vec![(10.0, 5.0)]),
        ),
        ("gears[0]", Box::new(|s| s.gears[0].gears[0].nodes[0] = 999)),
        (
            "gears[0]",
            Box::new(|s| s.gears[0].center_distance_m *= 0.5),
        ),
        (
            "gears[0] (mesh), pinion: bore radius",
            Box::new(|s| s.gears[0].gears[0].bore_radius_m = 0.0095),
        ),
        (
            "gears[0] (mesh), wheel: gives a tooth thickness",
            Box::new(|s| s.gears[0].gears[1].tooth_thickness_m = 4e-3),
        ),
        (
            "gears[0] (mesh): 0.1 (SI) is not within 10° … 35°",
            Box::new(|s| s.gears[0].pressure_angle_rad = 0.1),
        ),
        ("run.duration_s", Box::new(|s| s.run.duration_s = 0.0)),
        (
            "solver.tolerance_k",
            Box::new(|s| s.solver.tolerance_k = 1e-300),
        ),
    ];
    for (what, edit) in cases {
        let mut s = base.clone();
        edit(&mut s);
        let e = s.validate().expect_err(what);
        assert!(e.to_string().starts_with(what), "{what}: {e}");
    }
}

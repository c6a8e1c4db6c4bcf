//! The recordings shipped in `examples/recordings/` for the README's worked examples
//! (so that they run from a clone alone) are made by the independent truth generator
//! of `tests/cases/` (not the crate's forward model), and this test says so: it makes
//! them again and compares. To write them after a change of the generator:
//! `ORBITLASH_WRITE_EXAMPLES=1 cargo test --release --test example_recordings`.
//!
//! Also, ignored: `write_diagnose_scaling_recordings` writes the recordings of the
//! diagnose cost table (`docs/performance.md`) into `$ORBITLASH_SCALING_DIR`.

mod cases;

use cases::{Effect, Recipe};

fn k(c: f64) -> f64 {
    c + 273.15
}

/// A 4 W thermostat heater on the housing (on at −10 °C, off at −5 °C) that the
/// reference model leaves out, 12 orbits at 30 s, noise 0.15 K and 0.3 µm.
fn heater_housing(orbits: f64) -> Recipe {
    Recipe {
        orbits,
        seed: 2026,
        ..Recipe::with(vec![Effect::Heater {
            node: "housing".into(),
            power_w: 4.0,
            on_k: k(-10.0),
            off_k: k(-5.0),
        }])
    }
}

/// (file under the clone, recipe)
fn examples() -> Vec<(&'static str, Recipe)> {
    vec![
        (
            "examples/recordings/heater-housing.csv",
            heater_housing(12.0),
        ),
        (
            "examples/recordings/null.csv",
            Recipe {
                seed: 7,
                ..Recipe::default()
            },
        ),
    ]
}

#[test]
fn regress_example_recordings_come_from_the_generator() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for (file, recipe) in examples() {
        let text = cases::generate(&recipe);
        let path = root.join(file);
        if std::env::var_os("ORBITLASH_WRITE_EXAMPLES").is_some() {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &text).unwrap();
            continue;
        }
        let shipped = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{file}: {e} (write it with ORBITLASH_WRITE_EXAMPLES=1)"));
        // The same rows; a cell may differ by one quantum where a last-bit difference
        // of the platform's libm moved a value across a rounding boundary.
        let (t0, a) = cases::read_recording(&shipped);
        let (t1, b) = cases::read_recording(&text);
        assert_eq!(t0, t1, "{file}: other sample times");
        let mut differing = 0;
        for (ra, rb) in a.iter().zip(&b) {
            for (c, (x, y)) in ra.iter().zip(rb).enumerate() {
                let q = if c < 5 {
                    recipe.quantum_k
                } else {
                    recipe.quantum_um
                };
                match (x, y) {
                    (Some(x), Some(y)) if x != y => {
                        assert!((x - y).abs() <= 1.5 * q, "{file}: {x} vs {y}");
                        differing += 1;
                    }
                    (Some(_), Some(_)) | (None, None) => {}
                    _ => panic!("{file}: a missing cell moved"),
                }
            }
        }
        assert!(
            differing * 1000 <= a.len() * 6,
            "{file}: {differing} cells differ from the generator's"
        );
    }
}

#[test]
#[ignore = "writes the diagnose cost-table recordings (docs/performance.md)"]
fn write_diagnose_scaling_recordings() {
    let dir = std::path::PathBuf::from(
        std::env::var("ORBITLASH_SCALING_DIR").expect("set ORBITLASH_SCALING_DIR"),
    );
    std::fs::create_dir_all(&dir).unwrap();
    for orbits in [12.0, 48.0, 120.0, 480.0] {
        std::fs::write(
            dir.join(format!("heater-housing-{orbits}.csv")),
            cases::generate(&heater_housing(orbits)),
        )
        .unwrap();
    }
}

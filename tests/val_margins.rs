//! Margin statistics against published values (Wilks' 59/93/124 samples for 95/95,
//! Clopper–Pearson intervals, Spearman's closed form), and sample results that depend
//! only on (seed, index): the same for 1 or 2 threads and for any slice.

use std::sync::atomic::AtomicU64;

use orbitlash::io::scenario_toml::{REFERENCE_HINGE_TOML, parse_spec};
use orbitlash::margins::dispersion::{Plan, Sampling};
use orbitlash::margins::stats::{
    clopper_pearson, quantile, spearman, wilks_minimum_samples, wilks_rank,
};
use orbitlash::margins::{Horizon, run_samples};
use orbitlash::spec::model::Model;

#[test]
fn val_published_wilks_sample_sizes() {
    // One-sided 95/95 by the 1st, 2nd, 3rd, 4th smallest: 59, 93, 124, 153 samples.
    assert_eq!(wilks_minimum_samples(0.95, 0.95), 59);
    assert_eq!(wilks_rank(58, 0.95, 0.95), None);
    assert_eq!(wilks_rank(59, 0.95, 0.95), Some(1));
    assert_eq!(wilks_rank(92, 0.95, 0.95), Some(1));
    assert_eq!(wilks_rank(93, 0.95, 0.95), Some(2));
    assert_eq!(wilks_rank(124, 0.95, 0.95), Some(3));
    assert_eq!(wilks_rank(153, 0.95, 0.95), Some(4));
    // 99/95: 299 samples for the smallest
    assert_eq!(wilks_minimum_samples(0.99, 0.95), 299);
}

#[test]
fn val_closed_form_clopper_pearson() {
    // No events in n: the upper limit is 1 − (α/2)^(1/n).
    for n in [10u64, 59, 1000] {
        let (lo, hi) = clopper_pearson(0, n, 0.95);
        assert_eq!(lo, 0.0);
        let want = 1.0 - 0.025f64.powf(1.0 / n as f64);
        assert!((hi - want).abs() < 1e-9, "n {n}: {hi} vs {want}");
    }
    // 5 of 20 (tabulated: 0.0866 … 0.4910)
    let (lo, hi) = clopper_pearson(5, 20, 0.95);
    assert!(
        (lo - 0.0866).abs() < 5e-5 && (hi - 0.4910).abs() < 5e-5,
        "{lo} {hi}"
    );
    // all events
    assert_eq!(clopper_pearson(7, 7, 0.95).1, 1.0);
}

#[test]
fn val_closed_form_spearman_and_quantiles() {
    // no ties: ρ = 1 − 6 Σd² / (n (n² − 1)); d = (1, −1, 1, −1, 0) → 0.8
    let x = [1.0, 2.0, 3.0, 4.0, 5.0];
    let y = [2.0, 1.0, 4.0, 3.0, 5.0];
    assert!((spearman(&x, &y) - 0.8).abs() < 1e-12);
    // monotone, however curved: ±1
    let z: Vec<f64> = x.iter().map(|v: &f64| v.exp()).collect();
    assert!((spearman(&x, &z) - 1.0).abs() < 1e-12);
    let w: Vec<f64> = x.iter().map(|v| -v * v * v).collect();
    assert!((spearman(&x, &w) + 1.0).abs() < 1e-12);
    // type-7 quantiles
    let s = [1.0, 2.0, 3.0, 4.0];
    assert_eq!(quantile(&s, 0.5), 2.5);
    assert!((quantile(&s, 1.0 / 3.0) - 2.0).abs() < 1e-12);
    assert_eq!(quantile(&s, 1.0), 4.0);
}

#[test]
fn core_samples_depend_only_on_seed_and_index() {
    let text = format!(
        "{REFERENCE_HINGE_TOML}\n[[dispersion]]\npath = \"node.housing.capacitance_j_per_k\"\ndistribution = \"normal\"\nsd = 10.0\n\n[[dispersion]]\npath = \"gear_pair.mesh.pinion.tooth_thinning_um\"\ndistribution = \"uniform\"\nmin = 17.0\nmax = 22.0\n"
    );
    let model = Model::new(parse_spec(&text, "m.toml").unwrap()).unwrap();
    let plan = Plan::new(
        &model,
        &model.spec().dispersion,
        Sampling::LatinHypercube,
        8,
        11,
    )
    .unwrap();
    let run = |threads: usize, range: std::ops::Range<u64>| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let done = AtomicU64::new(0);
        pool.install(|| run_samples(&model, &plan, range, Horizon::Orbits(0.6), u64::MAX, &done))
    };
    let one = run(1, 0..8);
    let two = run(2, 0..8);
    assert_eq!(one, two);
    assert_eq!(run(2, 3..6), one[3..6].to_vec());
    // the thinner tooth (more thinning) leaves more backlash: Spearman says so
    let thinning: Vec<f64> = one.iter().map(|s| s.values[1]).collect();
    let min: Vec<f64> = one.iter().map(|s| s.pairs[0].min_backlash_um).collect();
    assert!(spearman(&thinning, &min) > 0.8, "{thinning:?} {min:?}");
}

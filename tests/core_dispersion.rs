//! Dispersions (issue 10): distributions against their closed forms, Latin hypercube
//! strata, draws that depend only on (seed, sample index), groups, and errors that name
//! the `[[dispersion]]` entry and its line before any sample runs.

use orbitlash::io::scenario_toml::{REFERENCE_HINGE_TOML, located, parse_spec};
use orbitlash::margins::dispersion::{Distribution, Plan, Sampling};
use orbitlash::spec::model::Model;

/// The reference scenario with `extra` appended (dispersion entries).
fn with(extra: &str) -> (String, Model) {
    let text = format!("{REFERENCE_HINGE_TOML}\n{extra}");
    let spec = parse_spec(&text, "d.toml").unwrap();
    (text, Model::new(spec).unwrap())
}

fn plan(extra: &str, sampling: Sampling, n: u64, seed: u64) -> Plan {
    let (_, model) = with(extra);
    Plan::new(&model, &model.spec().dispersion, sampling, n, seed).unwrap()
}

const THREE: &str = r#"
[[dispersion]]
path = "node.housing.capacitance_j_per_k"
distribution = "normal"
sd = 6.0

[[dispersion]]
path = "gear_pair.mesh.pinion.material.alpha_per_k"
distribution = "uniform"
min = 10.5e-6
max = 11.5e-6
group = "steel"

[[dispersion]]
path = "gear_pair.mesh.wheel.material.alpha_per_k"
distribution = "triangular"
min = 10.0e-6
max = 12.0e-6
group = "steel"
"#;

#[test]
fn val_closed_form_quantiles() {
    // Φ⁻¹(0.975) = 1.959963985 (tables).
    let n = Distribution::Normal {
        mean: 10.0,
        sd: 2.0,
    };
    assert!((n.quantile(0.975) - (10.0 + 2.0 * 1.959_963_985)).abs() < 1e-8);
    assert!((n.quantile(0.5) - 10.0).abs() < 1e-12);
    // Triangular: F(x) = (x−a)²/((b−a)(c−a)) below the mode, 1 − (b−x)²/((b−a)(b−c)) above.
    let (a, c, b) = (1.0, 2.0, 5.0);
    let t = Distribution::Triangular {
        min: a,
        mode: c,
        max: b,
    };
    for u in [0.01, 0.1, 0.2, 0.25, 0.5, 0.9, 0.999] {
        let x = t.quantile(u);
        let f = if x < c {
            (x - a).powi(2) / ((b - a) * (c - a))
        } else {
            1.0 - (b - x).powi(2) / ((b - a) * (b - c))
        };
        assert!((f - u).abs() < 1e-12, "u {u}: F(x) = {f}");
    }
    // Log-normal: the median at 0.5, e^{σ·1.959963985} × median at 0.975.
    let l = Distribution::LogNormal {
        median: 3.0,
        sigma: 0.1,
    };
    assert!((l.quantile(0.5) - 3.0).abs() < 1e-12);
    assert!((l.quantile(0.975) - 3.0 * (0.1f64 * 1.959_963_985).exp()).abs() < 1e-8);
    // Truncated normal: inside its bounds, and F_trunc(x) = (Φ(z) − Φ(α))/(Φ(β) − Φ(α)):
    // symmetric bounds put the median at the mean.
    let tn = Distribution::TruncatedNormal {
        mean: 0.0,
        sd: 1.0,
        min: -1.0,
        max: 1.0,
    };
    assert!(tn.quantile(0.5).abs() < 1e-12);
    assert!(
        (-1.0..=1.0).contains(&tn.quantile(1e-9))
            && (-1.0..=1.0).contains(&tn.quantile(1.0 - 1e-9))
    );
    // Φ(1) = 0.841344746: a quarter of the way through [Φ(−1), Φ(1)].
    let p = 0.158_655_254 + 0.25 * (0.841_344_746 - 0.158_655_254);
    let z = tn.quantile(0.25);
    let std_cdf = |x: f64| 0.5 * (1.0 + erf(x / std::f64::consts::SQRT_2));
    assert!((std_cdf(z) - p).abs() < 1e-8, "{z}");
    let cases = Distribution::Cases(vec![1.0, 2.0, 3.0, 4.0]);
    assert_eq!(
        [0.1, 0.3, 0.6, 0.99].map(|u| cases.quantile(u)),
        [1.0, 2.0, 3.0, 4.0]
    );
}

/// erf by Abramowitz & Stegun 7.1.26 is too coarse; this is the series (|x| ≤ 3).
fn erf(x: f64) -> f64 {
    let mut sum = 0.0;
    let mut term = x;
    let mut n = 0.0;
    while term.abs() > 1e-17 {
        sum += term / (2.0 * n + 1.0);
        n += 1.0;
        term *= -x * x / n;
    }
    2.0 / std::f64::consts::PI.sqrt() * sum
}

#[test]
fn core_draws_depend_only_on_seed_and_index() {
    let p = plan(THREE, Sampling::LatinHypercube, 200, 42);
    let forward: Vec<_> = (0..200).map(|k| p.values(k).unwrap()).collect();
    let backward: Vec<_> = (0..200).rev().map(|k| p.values(k).unwrap()).collect();
    for (k, v) in forward.iter().enumerate() {
        assert_eq!(v, &backward[199 - k]);
    }
    // the same plan again, and a shard's view of it, give the same numbers
    let again = plan(THREE, Sampling::LatinHypercube, 200, 42);
    assert_eq!(again.values(137).unwrap(), forward[137]);
    // another seed, other numbers
    let other = plan(THREE, Sampling::LatinHypercube, 200, 43);
    assert_ne!(other.values(137).unwrap(), forward[137]);
    // a group draws one quantile: the uniform and the triangular rise together
    let mut pairs: Vec<(f64, f64)> = forward.iter().map(|v| (v[1], v[2])).collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert!(pairs.windows(2).all(|w| w[1].1 >= w[0].1));
}

#[test]
fn core_latin_hypercube_puts_one_sample_in_each_stratum() {
    let n = 500;
    let p = plan(THREE, Sampling::LatinHypercube, n, 7);
    for d in 0..2 {
        let mut strata: Vec<u64> = (0..n)
            .map(|k| (p.quantiles(k).unwrap()[d] * n as f64) as u64)
            .collect();
        strata.sort();
        assert_eq!(strata, (0..n).collect::<Vec<_>>(), "dimension {d}");
    }
}

#[test]
fn val_closed_form_sample_moments() {
    // 20 000 random draws of the normal capacitance: mean and sd within 4 standard errors.
    let n = 20_000;
    let p = plan(THREE, Sampling::Random, n, 1);
    let xs: Vec<f64> = (0..n).map(|k| p.values(k).unwrap()[0]).collect();
    let mean = xs.iter().sum::<f64>() / n as f64;
    let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
    assert!(
        (mean - 120.0).abs() < 4.0 * 6.0 / (n as f64).sqrt(),
        "{mean}"
    );
    assert!(
        (sd - 6.0).abs() < 4.0 * 6.0 / (2.0 * n as f64).sqrt(),
        "{sd}"
    );
    // the uniform's mean, (a + b)/2
    let u: f64 = (0..n).map(|k| p.values(k).unwrap()[1]).sum::<f64>() / n as f64;
    assert!((u - 11e-6).abs() < 4.0 * (1e-6 / 12f64.sqrt()) / (n as f64).sqrt());
}

#[test]
fn core_applied_values_reach_the_compiled_model() {
    let (_, mut model) = with(THREE);
    let p = Plan::new(
        &model,
        &model.spec().dispersion.clone(),
        Sampling::Random,
        10,
        5,
    )
    .unwrap();
    let values = p.apply(&mut model, 3).unwrap();
    assert_eq!(
        model.scenario().thermal.network.nodes[0].capacitance_j_per_k,
        values[0]
    );
    assert_eq!(
        model
            .get("gear_pair.mesh.wheel.material.alpha_per_k")
            .unwrap(),
        values[2]
    );
}

#[test]
fn core_bad_dispersions_are_named_with_their_line() {
    for (extra, needles) in [
        (
            "[[dispersion]]\npath = \"node.rotor.capacitance_j_per_k\"\ndistribution = \"normal\"\nsd = 1.0\n",
            vec!["dispersion[0].path", "rotor"],
        ),
        (
            "[[dispersion]]\npath = \"environment.albedo\"\ndistribution = \"normal\"\nsd = 0.1\n",
            vec!["dispersion[0]", "environment.albedo", "cannot take"],
        ),
        (
            "[[dispersion]]\npath = \"environment.albedo\"\ndistribution = \"normal\"\nsd = -0.01\n",
            vec!["dispersion[0].sd", "must be > 0"],
        ),
        (
            "[[dispersion]]\npath = \"environment.albedo\"\ndistribution = \"uniform\"\nmin = 0.2\nsd = 0.1\n",
            vec!["dispersion[0].sd", "not a parameter of `uniform`"],
        ),
        (
            "[[dispersion]]\npath = \"environment.albedo\"\ndistribution = \"cases\"\nvalues = [0.2, 1.4]\n",
            vec!["dispersion[0]", "1.4"],
        ),
    ] {
        let (text, model) = with(extra);
        let e = match Plan::new(&model, &model.spec().dispersion, Sampling::Random, 10, 1) {
            Err(orbitlash::margins::dispersion::PlanError::Spec(e)) => e,
            other => panic!("expected an entry's error, got {other:?}"),
        };
        let shown = located(&text, "d.toml", e).to_string();
        for n in &needles {
            assert!(shown.contains(n), "`{n}` missing: {shown}");
        }
        // the line of the entry (or its key), past the reference's own lines
        let line: usize = shown
            .split(':')
            .nth(1)
            .and_then(|l| l.parse().ok())
            .unwrap_or_else(|| panic!("no line in {shown}"));
        assert!(line > REFERENCE_HINGE_TOML.lines().count(), "{shown}");
    }
    // an unknown distribution is refused by the reader, with its line and the choices
    let text = format!(
        "{REFERENCE_HINGE_TOML}\n[[dispersion]]\npath = \"environment.albedo\"\ndistribution = \"gaussian\"\nsd = 0.01\n"
    );
    let e = parse_spec(&text, "d.toml").unwrap_err().to_string();
    for n in [
        "d.toml:",
        "dispersion[0].distribution",
        "unknown variant `gaussian`",
        "`truncated_normal`",
    ] {
        assert!(e.contains(n), "`{n}` missing: {e}");
    }
    // an unknown key in an entry is a schema error with its line
    let text = format!(
        "{REFERENCE_HINGE_TOML}\n[[dispersion]]\npath = \"environment.albedo\"\ndistribution = \"normal\"\nstdev = 0.01\n"
    );
    let e = parse_spec(&text, "d.toml").unwrap_err().to_string();
    assert!(e.contains("d.toml:") && e.contains("stdev"), "{e}");
}

#[test]
fn cli_check_lists_dispersions_and_refuses_bad_ones() {
    let dir = std::env::temp_dir().join(format!("orbitlash-test-{}-disp", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let good = format!("{REFERENCE_HINGE_TOML}\n{THREE}");
    std::fs::write(dir.join("good.toml"), &good).unwrap();
    let bad = format!(
        "{REFERENCE_HINGE_TOML}\n[[dispersion]]\npath = \"environment.albedo\"\ndistribution = \"normal\"\nsd = 0.1\n"
    );
    std::fs::write(dir.join("bad.toml"), &bad).unwrap();
    let bin = env!("CARGO_BIN_EXE_orbitlash");
    let out = std::process::Command::new(bin)
        .args(["check", "good.toml"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("gear_pair.mesh.wheel.material.alpha_per_k")
            && text.contains("triangular, 1e-5 … 1.1e-5 … 1.2e-5")
            && text.contains("steel"),
        "{text}"
    );
    let out = std::process::Command::new(bin)
        .args(["check", "bad.toml"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    let line = REFERENCE_HINGE_TOML.lines().count() + 2;
    assert!(
        err.contains(&format!("bad.toml:{line}:")) && err.contains("dispersion[0]"),
        "{err}"
    );
    // the nominal run ignores dispersions: the same summary as without them
    let run = |file: &str| {
        let out = std::process::Command::new(bin)
            .args(["run", file, "--no-log", "--quiet", "--orbits", "1"])
            .current_dir(&dir)
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stdout).replace(file, "")
    };
    std::fs::write(dir.join("plain.toml"), REFERENCE_HINGE_TOML).unwrap();
    assert_eq!(run("good.toml"), run("plain.toml"));
    let _ = std::fs::remove_dir_all(&dir);
}

// ---- truncated normal far in a tail (issue 16, item 4) -------------------------------

/// ln Φ̄(z) = ln P(Z > z), written out here independently of the crate: for z ≥ 8 the
/// asymptotic series of the Mills ratio R(z) = Φ̄(z)/φ(z) ≈ (1/z)(1 − 1/z² + 3/z⁴ −
/// 15/z⁶ + 105/z⁸ − 945/z¹⁰) (relative error < 1e-8 there), below it Simpson's rule
/// on φ up to 8 plus that tail; for z < −8, ln(1 − Φ̄(−z)).
fn ln_upper_ref(z: f64) -> f64 {
    let ln_phi = |t: f64| -0.5 * t * t - 0.5 * (2.0 * std::f64::consts::PI).ln();
    let asym = |t: f64| {
        let x = 1.0 / (t * t);
        (1.0 / t)
            * (1.0 - x + 3.0 * x * x - 15.0 * x.powi(3) + 105.0 * x.powi(4) - 945.0 * x.powi(5))
    };
    if z >= 8.0 {
        return ln_phi(z) + asym(z).ln();
    }
    if z < -8.0 {
        return (-ln_upper_ref(-z).exp()).ln_1p();
    }
    let n = 200_000;
    let h = (8.0 - z) / n as f64;
    let f = |t: f64| ln_phi(t).exp();
    let mut s = f(z) + f(8.0);
    for k in 1..n {
        s += f(z + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    (s * h / 3.0 + (ln_phi(8.0) + asym(8.0).ln()).exp()).ln()
}

/// The CDF of the standard normal truncated to [a, b] at z, from [`ln_upper_ref`].
fn truncated_cdf_ref(a: f64, b: f64, z: f64) -> f64 {
    if b <= 0.0 {
        // the lower tail, by symmetry
        return 1.0 - truncated_cdf_ref(-b, -a, -z);
    }
    let (la, lb, lz) = (ln_upper_ref(a), ln_upper_ref(b), ln_upper_ref(z));
    (1.0 - (lz - la).exp()) / (1.0 - (lb - la).exp())
}

/// Its mean: (φ(a) − φ(b)) / (Φ̄(a) − Φ̄(b)).
fn truncated_mean_ref(a: f64, b: f64) -> f64 {
    if b <= 0.0 {
        return -truncated_mean_ref(-b, -a);
    }
    let ln_phi = |t: f64| -0.5 * t * t - 0.5 * (2.0 * std::f64::consts::PI).ln();
    let (la, lb) = (ln_upper_ref(a), ln_upper_ref(b));
    // scaled by φ(a) to keep 40σ tails finite
    (1.0 - (ln_phi(b) - ln_phi(a)).exp()) / ((la - ln_phi(a)).exp() - (lb - ln_phi(a)).exp())
}

#[test]
fn val_closed_form_truncated_normal_tails_to_40_sigma() {
    for (mean, sd, min, max) in [
        (20.0, 1.0, 30.0, 40.0),  // the reported case: 10σ … 20σ above the mean
        (0.0, 1.0, 40.0, 41.0),   // 40σ out
        (0.0, 1.0, -41.0, -40.0), // the lower tail
        (5.0, 2.0, -75.0, -1.0),  // both bounds below the mean: 3σ … 40σ
        (0.0, 2.0, 1.0, 3.0),     // a moderate one-sided interval
        (0.0, 1.0, -1.0, 2.0),    // around the mean
        (0.0, 1.0, 6.0, 1e3),     // a far upper bound
    ] {
        let d = Distribution::TruncatedNormal { mean, sd, min, max };
        let (a, b) = ((min - mean) / sd, (max - mean) / sd);
        // quantiles: the closed-form CDF of each quantile is its level
        for u in [1e-6, 0.001, 0.1, 0.5, 0.9, 0.999, 1.0 - 1e-6] {
            let x = d.quantile(u);
            assert!((min..=max).contains(&x), "{x} outside {min} … {max}");
            let f = truncated_cdf_ref(a, b, (x - mean) / sd);
            // relative to the distance from the nearer end: a quantile on a bound
            // (CDF 0 or 1) fails even at u = 1e-6
            assert!(
                (f - u).abs() < 1e-4 * u.min(1.0 - u) + 1e-13,
                "[{min}, {max}] of N({mean}, {sd}²): quantile({u}) = {x} has CDF {f}"
            );
        }
        // the mean over 20 000 equal strata against the closed form, and no pile-up on
        // a bound
        let n = 20_000;
        let xs: Vec<f64> = (0..n)
            .map(|k| d.quantile((k as f64 + 0.5) / n as f64))
            .collect();
        let m = xs.iter().sum::<f64>() / n as f64;
        let want = mean + sd * truncated_mean_ref(a, b);
        assert!(
            (m - want).abs() < 1e-4 * sd,
            "[{min}, {max}] of N({mean}, {sd}²): mean {m}, closed form {want}"
        );
        let on_bounds = xs.iter().filter(|&&x| x == min || x == max).count();
        assert!(
            on_bounds <= 2,
            "{on_bounds} samples on a bound of [{min}, {max}]"
        );
    }
}

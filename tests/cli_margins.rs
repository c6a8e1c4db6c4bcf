//! `orbitlash margins` end to end: the verdict in the first line and the exit status,
//! the JSON report's keys, the same numbers on every run, and refusals.

mod common;
use common::{bin, reference_text, tmpdir};

const DISPERSIONS: &str = r#"
[[dispersion]]
path = "gear_pair.mesh.pinion.tooth_thinning_um"
distribution = "truncated_normal"
sd = 2.0
min = 15.0
max = 24.0

[[dispersion]]
path = "sun.\"sun.housing\".absorptivity"
distribution = "uniform"
min = 0.6
max = 0.8
"#;

fn setup(name: &str, min_backlash: &str) -> common::TestDir {
    let dir = tmpdir(name);
    let text = reference_text().replacen("min_backlash_um = 5.0", min_backlash, 1) + DISPERSIONS;
    std::fs::write(dir.join("m.toml"), text).unwrap();
    dir
}

#[test]
fn cli_margins_pass_fail_and_report() {
    let dir = setup("margins", "min_backlash_um = 5.0");
    let args = [
        "margins",
        "m.toml",
        "--samples",
        "60",
        "--seed",
        "3",
        "--orbits",
        "2",
    ];
    let out = bin()
        .args(args)
        .args(["--json", "a.json", "--csv", "a.csv"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.starts_with("PASS mesh: 95/95 lower bound"), "{text}");
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("a.json")).unwrap()).unwrap();
    assert_eq!(j["verdict"], "pass");
    assert_eq!(j["samples"], 60);
    let p = &j["pairs"][0];
    // the margin is the backlash less the minimum allowed, percentile by percentile
    let (b, m) = (&p["min_backlash_um"], &p["min_margin_um"]);
    for i in 0..5 {
        let d = b["percentiles"][i]["value"].as_f64().unwrap()
            - m["percentiles"][i]["value"].as_f64().unwrap();
        assert!((d - 5.0).abs() < 1e-9, "{d}");
    }
    for key in [
        "min_backlash_um",
        "tolerance_95_95_um",
        "violations",
        "interference",
        "sensitivities",
        "worst",
    ] {
        assert!(!p[key].is_null(), "{key}");
    }
    // 60 samples: the smallest is the 95/95 bound
    assert_eq!(p["tolerance_rank"], 1);
    assert_eq!(p["tolerance_95_95_um"], p["min_backlash_um"]["min"]);
    // the thinning raises the backlash, the absorptivity lowers it
    let s = p["sensitivities"].as_array().unwrap();
    let rho = |path: &str| {
        s.iter().find(|x| x["path"] == path).unwrap()["spearman"]
            .as_f64()
            .unwrap()
    };
    assert!(rho("gear_pair.mesh.pinion.tooth_thinning_um") > 0.3);
    assert!(rho("sun.\"sun.housing\".absorptivity") < -0.3);
    let csv = std::fs::read_to_string(dir.join("a.csv")).unwrap();
    assert_eq!(csv.lines().count(), 61);
    // the same command again: the same report
    let again = bin()
        .args(args)
        .args(["--json", "b.json"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(again.status.code(), Some(0));
    assert_eq!(
        std::fs::read(dir.join("a.json")).unwrap(),
        std::fs::read(dir.join("b.json")).unwrap()
    );
    // fewer than 59 samples cannot show 95/95: FAIL, exit 1, saying why
    let few = bin()
        .args([
            "margins",
            "m.toml",
            "--samples",
            "20",
            "--seed",
            "3",
            "--orbits",
            "1",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(few.status.code(), Some(1));
    let t = String::from_utf8_lossy(&few.stdout);
    assert!(
        t.starts_with("FAIL mesh: 20 samples cannot show 95/95") && t.contains("59"),
        "{t}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_margins_fail_when_the_bound_is_below_the_minimum() {
    let dir = setup("margins-fail", "min_backlash_um = 22.0");
    let out = bin()
        .args([
            "margins",
            "m.toml",
            "--samples",
            "60",
            "--seed",
            "1",
            "--orbits",
            "2",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.starts_with("FAIL mesh: 95/95 lower bound"), "{text}");
    assert!(text.contains("P(below the minimum) = "), "{text}");
    // no dispersions: an error, exit 2
    std::fs::write(dir.join("plain.toml"), reference_text()).unwrap();
    let out = bin()
        .args(["margins", "plain.toml", "--samples", "10", "--seed", "1"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no [[dispersion]]"));
    // more shards than samples: an empty shard says so
    let out = bin()
        .args([
            "margins",
            "m.toml",
            "--samples",
            "2",
            "--seed",
            "7",
            "--orbits",
            "1",
            "-q",
            "--shard",
            "0/3",
            "--json",
            "e0.json",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success()
            && said.starts_with("shard 0/3: none of the 2 samples (more shards than samples)"),
        "{said}"
    );
    // bench's refusal gives bench's own advice (it has no --force or --orbits)
    let out = bin()
        .args([
            "bench",
            "--margins",
            "m.toml",
            "--samples",
            "3",
            "--margins-horizon",
            "1e12",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    common::assert_error("bench horizon", &out, &["shorten --margins-horizon"]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(
        !said.contains("--force,") && !said.contains("pass --force"),
        "{said}"
    );
    // the limit itself dispersed: refused (each sample judged against its own limit
    // while the report judged the nominal gave PASS over samples that failed)
    std::fs::write(
        dir.join("limit.toml"),
        reference_text()
            + "\n[[dispersion]]\npath = \"gear_pair.mesh.min_backlash_um\"\ndistribution = \"uniform\"\nmin = 20\nmax = 40\n",
    )
    .unwrap();
    for args in [
        &["margins", "limit.toml", "--samples", "10", "--seed", "1"][..],
        &["check", "limit.toml"][..],
    ] {
        let out = bin().args(args).current_dir(&dir).output().unwrap();
        common::assert_error(
            "dispersed limit",
            &out,
            &[
                "`dispersion[0].path`",
                "gear_pair.mesh.min_backlash_um",
                "acceptance limit",
            ],
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The report's replay command (`replay`, printed above the worst samples) run as it
/// says gives the worst sample's smallest backlash to the last digit, for each flag
/// that changes a sample. It named the seed and the sampling only: with `--orbits 2`,
/// `--set` or `--steady-state` it replayed another run (black-box helper-25).
#[test]
fn cli_run_replays_a_margins_sample_to_the_last_digit() {
    let dir = setup("margins-replay", "min_backlash_um = 5.0");
    let two = ["--orbits", "2"];
    let cases: [(&str, &[&str]); 5] = [
        ("random", &two),
        ("lhs", &two),
        (
            "random",
            &[
                "--orbits",
                "2",
                "--set",
                "node.housing.capacitance_j_per_k=400",
            ],
        ),
        ("random", &["--steady-state"]),
        // a horizon that 4 significant digits would change (it read 5.432e-4: review
        // helper-26)
        ("random", &["--orbits", "0.00054321"]),
    ];
    for (sampling, flags) in cases {
        let out = bin()
            .args(["margins", "m.toml", "--samples", "60", "--seed", "5"])
            .args(flags)
            .args(["--sampling", sampling, "--json", "r.json", "--quiet"])
            .current_dir(&dir)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0), "{flags:?}");
        let r: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("r.json")).unwrap()).unwrap();
        let worst = &r["pairs"][0]["worst"][0];
        let k = worst["index"].as_u64().unwrap().to_string();
        let replay = r["replay"].as_str().unwrap();
        assert!(
            String::from_utf8_lossy(&out.stdout).contains(&format!("replay one with `{replay}`")),
            "{replay}"
        );
        // every flag of the margins run that changes a sample is in it
        assert!(
            replay.contains(&flags.join(" ")),
            "{replay} lacks {flags:?}"
        );
        let words: Vec<String> = replay
            .split_whitespace()
            .skip(1) // orbitlash
            .map(|w| match w {
                "SCENARIO" => "m.toml".to_string(),
                "K" => k.clone(),
                w => w.trim_matches('\'').to_string(),
            })
            .collect();
        let _ = std::fs::remove_file(dir.join("s.json"));
        let out = bin()
            .args(&words)
            .args(["--no-log", "--quiet", "--json", "s.json"])
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            out.status.code() != Some(2),
            "{words:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains(&format!("sample {k} of seed 5:")), "{text}");
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
        assert_eq!(
            s["gear_pairs"][0]["min_backlash_um"], worst["min_backlash_um"],
            "{words:?}"
        );
    }
    // a Latin hypercube sample depends on N: without --samples, an error
    let out = bin()
        .args([
            "run",
            "m.toml",
            "--sample",
            "3",
            "--seed",
            "5",
            "--sampling",
            "lhs",
            "--no-log",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("needs --samples N"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_shards_merge_to_the_unsharded_report_bit_for_bit() {
    let dir = setup("margins-shards", "min_backlash_um = 5.0");
    let base = [
        "margins",
        "m.toml",
        "--samples",
        "61",
        "--seed",
        "8",
        "--orbits",
        "1",
        "--quiet",
    ];
    let ok = |args: &[&str]| {
        let out = bin().args(args).current_dir(&dir).output().unwrap();
        assert!(
            out.status.code() != Some(2),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    ok(&[&base[..], &["--json", "full.json"]].concat());
    for i in 0..4 {
        let shard = format!("{i}/4");
        let file = format!("s{i}.json");
        ok(&[&base[..], &["--shard", &shard, "--json", &file]].concat());
    }
    // in any order
    ok(&[
        "merge",
        "s3.json",
        "s1.json",
        "s0.json",
        "s2.json",
        "--json",
        "merged.json",
    ]);
    assert_eq!(
        std::fs::read(dir.join("full.json")).unwrap(),
        std::fs::read(dir.join("merged.json")).unwrap()
    );
    let refused = |args: &[&str], needle: &str| {
        let out = bin().args(args).current_dir(&dir).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(e.contains(needle), "{args:?}: {e}");
    };
    refused(
        &["merge", "s0.json", "s1.json", "s3.json"],
        "samples 30 … 44 are in no shard",
    );
    // one file given twice is said as such (it read "in both s0.json and s0.json");
    // a copy of a shard under another name holds the same samples
    refused(
        &[
            "merge",
            "s0.json",
            "./s0.json",
            "s1.json",
            "s2.json",
            "s3.json",
        ],
        "the shard ./s0.json is given twice (also as s0.json)",
    );
    std::fs::copy(dir.join("s0.json"), dir.join("s0-copy.json")).unwrap();
    refused(
        &[
            "merge",
            "s0.json",
            "s0-copy.json",
            "s1.json",
            "s2.json",
            "s3.json",
        ],
        "is in both s0.json and s0-copy.json",
    );
    ok(&[
        "margins",
        "m.toml",
        "--samples",
        "61",
        "--seed",
        "9",
        "--orbits",
        "1",
        "--quiet",
        "--shard",
        "1/4",
        "--json",
        "t1.json",
    ]);
    refused(
        &["merge", "s0.json", "t1.json", "s2.json", "s3.json"],
        "they differ in the seed",
    );
    std::fs::write(dir.join("junk.json"), "{}").unwrap();
    refused(&["merge", "junk.json"], "not a margins shard");
    // edits that keep a shard consistent with itself: a value moved within its range,
    // a result rewritten with its flags, the horizon; each merged with exit 0 before
    // (black-box helper-19), each refused now by the shard's checksum
    let shard: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s1.json")).unwrap()).unwrap();
    type Edit = fn(&mut serde_json::Value);
    let edits: [(&str, Edit); 3] = [
        ("value", |v| {
            let x = v["outcomes"][0]["values"][0].as_f64().unwrap();
            v["outcomes"][0]["values"][0] = (x * (1.0 + 1e-9)).into();
        }),
        ("result", |v| {
            let p = &mut v["outcomes"][0]["pairs"][0];
            let b = p["min_backlash_um"].as_f64().unwrap();
            p["min_backlash_um"] = (b + 1.0).into();
            p["min_margin_um"] = (p["min_margin_um"].as_f64().unwrap() + 1.0).into();
        }),
        ("horizon", |v| {
            let h = v["limits"]["horizon_s"].as_f64().unwrap();
            v["limits"]["horizon_s"] = (h * 2.0).into();
        }),
    ];
    for (name, edit) in edits {
        let mut v = shard.clone();
        edit(&mut v);
        assert_ne!(v, shard, "{name}");
        let file = format!("edited-{name}.json");
        std::fs::write(dir.join(&file), serde_json::to_string(&v).unwrap()).unwrap();
        refused(
            &["merge", "s0.json", &file, "s2.json", "s3.json"],
            "do not match the SHA-256 it was written with",
        );
    }
    let mut v = shard.clone();
    v.as_object_mut().unwrap().remove("sha256");
    std::fs::write(dir.join("bare.json"), serde_json::to_string(&v).unwrap()).unwrap();
    refused(
        &["merge", "s0.json", "bare.json", "s2.json", "s3.json"],
        "it has no SHA-256 of its contents",
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_margins_plots_are_svg_with_the_limit_and_the_bound() {
    let dir = setup("margins-plots", "min_backlash_um = 5.0");
    std::fs::create_dir_all(dir.join("plots")).unwrap();
    let out = bin()
        .args([
            "margins",
            "m.toml",
            "--samples",
            "60",
            "--seed",
            "2",
            "--orbits",
            "1",
        ])
        .args(["--quiet", "--plots", "plots", "--json", "r.json"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("r.json")).unwrap()).unwrap();
    let hist = std::fs::read_to_string(dir.join("plots/mesh-min-backlash.svg")).unwrap();
    assert!(hist.starts_with("<svg ") && hist.ends_with("</svg>\n"));
    // 30 bars (the bar colour, #96AFC8); the limit and the 95/95 bound labelled; the
    // verdict and the counts on the figure; both axes named
    assert_eq!(hist.matches("fill=\"#96AFC8\"").count(), 30);
    assert!(hist.contains("minimum 5 µm"));
    assert!(hist.contains("PASS: 60 samples, 0 below the minimum, 0 interfering"));
    assert!(
        hist.contains("samples per bin (bars)")
            && hist.contains("cumulative fraction of samples (line)")
    );
    let bound = r["pairs"][0]["tolerance_95_95_um"].as_f64().unwrap();
    assert!(
        hist.contains(&format!("95/95 bound {bound:.3} µm")),
        "{bound}"
    );
    let tornado = std::fs::read_to_string(dir.join("plots/mesh-sensitivity.svg")).unwrap();
    assert!(tornado.contains("whiskers: 95 % interval (60 samples)"));
    assert!(tornado.contains("gear_pair.mesh.pinion.tooth_thinning_um (+"));
    // a missing folder is created (its parent must exist), and the figures can be PNG
    // at twice their size, the same figures as the SVGs
    let margins = |plots: &str, format: &str| {
        bin()
            .args([
                "margins",
                "m.toml",
                "--samples",
                "60",
                "--seed",
                "2",
                "--orbits",
                "1",
            ])
            .args(["--quiet", "--plots", plots, "--plots-format", format])
            .current_dir(&dir)
            .output()
            .unwrap()
    };
    let out = margins("slides", "png");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let png = std::fs::read(dir.join("slides/mesh-min-backlash.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let (w, h) = (
        u32::from_be_bytes(png[16..20].try_into().unwrap()),
        u32::from_be_bytes(png[20..24].try_into().unwrap()),
    );
    let size = |svg: &str, key: &str| -> u32 {
        let at = svg.find(&format!("{key}=\"")).unwrap() + key.len() + 2;
        svg[at..].split('"').next().unwrap().parse().unwrap()
    };
    assert_eq!(
        (w, h),
        (2 * size(&hist, "width"), 2 * size(&hist, "height"))
    );
    assert!(dir.join("slides/mesh-sensitivity.png").is_file());
    assert!(!dir.join("slides/mesh-min-backlash.svg").exists());
    // a folder whose parent is missing is an error, nothing written
    let out = margins("nowhere/deeper", "svg");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no such directory"));
    assert!(!dir.join("nowhere").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

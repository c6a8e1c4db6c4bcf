//! Reliability, round 3 (issue 16): outputs of one command never overwrite each other;
//! names that become paths are checked; dispersions are compared as resolved numbers;
//! no verdict without something to judge; shards are checked against themselves;
//! impossible recordings are refused; counts are bounded; costs are estimated first;
//! damaged files are named as such. Each case: the exit status, the first error line
//! naming the file, key, line or path, and nothing written when refused.

use std::path::{Path, PathBuf};

mod common;
use common::{
    assert_error, bin, first_error_line, reference_text, reference_with, run_in, snapshot, stderr,
    stdout, tmpdir,
};

/// The reference with a dispersion of tooth thinning (a margins scenario).
fn margins_text() -> String {
    reference_text()
        + "\n[[dispersion]]\npath = \"gear_pair.mesh.pinion.tooth_thinning_um\"\ndistribution = \"uniform\"\nmin = 16.0\nmax = 23.0\n\n[[dispersion]]\npath = \"environment.beta_deg\"\ndistribution = \"uniform\"\nmin = 10.0\nmax = 30.0\n"
}

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/recordings")
        .join(name)
}

/// `args` run in `dir` must be refused (exit 2, first error line holding `needles`) and
/// leave every file of `dir` as it was, with no temporary left behind.
fn refused_in(dir: &Path, case: &str, args: &[&str], needles: &[&str]) {
    let before = snapshot(dir);
    let out = run_in(dir, args);
    assert_error(case, &out, needles);
    assert_eq!(
        snapshot(dir),
        before,
        "{case}: files changed although refused"
    );
}

// 1, 10: every output of a command is checked against the inputs and the others
// before any work starts.
#[test]
fn cli_outputs_of_one_command_never_overwrite_each_other() {
    let dir = tmpdir("rel-clobber");
    std::fs::write(dir.join("m.toml"), margins_text()).unwrap();
    std::fs::create_dir(dir.join("P")).unwrap();
    let m = [
        "margins",
        "m.toml",
        "--samples",
        "60",
        "--seed",
        "1",
        "--orbits",
        "0.5",
        "--quiet",
    ];
    let with = |extra: &[&'static str]| -> Vec<&str> {
        m.iter().copied().chain(extra.iter().copied()).collect()
    };
    refused_in(
        &dir,
        "json and csv onto plots",
        &with(&[
            "--json",
            "P/mesh-min-backlash.svg",
            "--csv",
            "P/mesh-sensitivity.svg",
            "--plots",
            "P",
        ]),
        &["P/mesh-min-backlash.svg", "--json", "--plots"],
    );
    refused_in(
        &dir,
        "json onto csv",
        &with(&["--json", "a.out", "--csv", "./a.out"]),
        &["a.out", "--csv", "--json"],
    );
    // a plot name that is a link: refused before any sample runs, no report written
    std::os::unix::fs::symlink("elsewhere.svg", dir.join("P/mesh-sensitivity.svg")).unwrap();
    refused_in(
        &dir,
        "a plot is a link",
        &with(&["--json", "r.json", "--plots", "P"]),
        &["P/mesh-sensitivity.svg", "symbolic link"],
    );
    std::fs::remove_file(dir.join("P/mesh-sensitivity.svg")).unwrap();
    // run: --csv and --json the same file
    refused_in(
        &dir,
        "run csv = json",
        &["run", "m.toml", "--no-log", "--csv", "x", "--json", "x"],
        &["x", "--json", "--csv"],
    );

    // diagnose: --json onto a file --out writes, and a symlinked plot name
    std::fs::create_dir(dir.join("D")).unwrap();
    let rec = example("heater-housing.csv");
    let d = |extra: &[&str]| -> Vec<String> {
        [
            "diagnose",
            "m.toml",
            "--recording",
            rec.to_str().unwrap(),
            "--quiet",
        ]
        .iter()
        .chain(extra.iter())
        .map(|s| s.to_string())
        .collect()
    };
    let args = d(&["--json", "D/corrected.toml", "--out", "D"]);
    refused_in(
        &dir,
        "diagnose json onto corrected.toml",
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        &["D/corrected.toml", "--json", "--out"],
    );
    std::os::unix::fs::symlink("nowhere.svg", dir.join("D/residuals-housing_c.svg")).unwrap();
    let args = d(&["--json", "r.json", "--out", "D"]);
    refused_in(
        &dir,
        "diagnose plot is a link",
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        &["residuals-housing_c.svg", "symbolic link"],
    );
    // --out onto an input file
    let args = d(&["--out", "m.toml"]);
    refused_in(
        &dir,
        "diagnose out is the scenario",
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        &["m.toml", "--out", "not a directory"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

// 2: names that can reach a path or a terminal obey one rule.
#[test]
fn cli_names_that_become_paths_are_checked() {
    let dir = tmpdir("rel-names");
    for (case, old, new, needles) in [
        (
            "name escapes",
            "column = \"housing_c\"",
            "column = \"housing_c\"\nname = \"../../../escaped_c\"",
            vec!["sensor[0].name", "escaped_c", "not a valid name"],
        ),
        (
            "name with a folder",
            "column = \"housing_c\"",
            "column = \"housing_c\"\nname = \"sub/x_c\"",
            vec!["sensor[0].name", "sub/x_c"],
        ),
        (
            "empty column",
            "column = \"housing_c\"",
            "column = \"\"",
            vec!["sensor[0].column", "must not be empty"],
        ),
        (
            "control characters",
            "column = \"housing_c\"",
            "column = \"a\\u001b[2Jb_c\"",
            vec!["sensor[0].column", "\\u{1b}"],
        ),
        (
            "conductor name",
            "between = [\"housing\", \"bus\"]",
            "name = \"a/b\"\nbetween = [\"housing\", \"bus\"]",
            vec!["conductor[0].name", "a/b"],
        ),
        (
            "description escape",
            "description = \"Solar-array",
            "description = \"\\u001b]0;pwned\\u0007Solar-array",
            vec!["scenario.description", "control character"],
        ),
    ] {
        std::fs::write(dir.join("s.toml"), reference_with(&[(old, new)])).unwrap();
        for cmd in ["check", "run"] {
            let out = run_in(
                &dir,
                &[cmd, "s.toml", "--no-log"][..if cmd == "check" { 2 } else { 3 }],
            );
            assert_error(case, &out, &needles);
            assert!(
                !stderr(&out).contains('\u{1b}'),
                "{case}: an escape byte reached the terminal"
            );
        }
    }
    assert!(!dir.join("logs").exists());
    // A recording's own column text may hold anything printable (telemetry names it):
    // the channel takes a name made from it, which cannot leave a folder.
    for (column, channel) in [("../../../escaped_c", "escaped_c"), ("sub/x_c", "sub_x_c")] {
        std::fs::write(
            dir.join("s.toml"),
            reference_with(&[("column = \"housing_c\"", &format!("column = \"{column}\""))]),
        )
        .unwrap();
        let out = run_in(&dir, &["check", "s.toml"]);
        assert!(out.status.success(), "{column}: {}", stderr(&out));
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains(&format!("sensors: {channel},")),
            "{column}: {text}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

// 3: the same number spelled twice, and --set on a dispersed number.
#[test]
fn cli_dispersions_are_compared_as_resolved_numbers() {
    let dir = tmpdir("rel-dup");
    let twice = |a: &str, b: &str| {
        reference_text()
            + &format!(
                "\n[[dispersion]]\npath = '{a}'\ndistribution = \"uniform\"\nmin = 100.0\nmax = 130.0\n\n[[dispersion]]\npath = '{b}'\ndistribution = \"uniform\"\nmin = 100.0\nmax = 130.0\n"
            )
    };
    for (a, b) in [
        (
            "node.\"housing\".capacitance_j_per_k",
            "node.housing.capacitance_j_per_k",
        ),
        (
            "node . housing . capacitance_j_per_k",
            "node.housing.capacitance_j_per_k",
        ),
    ] {
        std::fs::write(dir.join("d.toml"), twice(a, b)).unwrap();
        let out = run_in(
            &dir,
            &[
                "margins",
                "d.toml",
                "--samples",
                "60",
                "--seed",
                "1",
                "--orbits",
                "0.5",
                "--quiet",
            ],
        );
        assert_error(
            a,
            &out,
            &[
                "d.toml:",
                "dispersion[1].path",
                "same number",
                "dispersion[0]",
            ],
        );
        let out = run_in(&dir, &["check", "d.toml"]);
        assert_error(a, &out, &["dispersion[1].path"]);
    }
    std::fs::write(dir.join("m.toml"), margins_text()).unwrap();
    for set in ["environment.beta_deg=25", "environment . beta_deg=25"] {
        let out = run_in(
            &dir,
            &[
                "margins",
                "m.toml",
                "--samples",
                "60",
                "--seed",
                "1",
                "--orbits",
                "0.5",
                "--set",
                set,
                "--quiet",
            ],
        );
        assert_error(set, &out, &["--set", "dispersed by dispersion[1]"]);
        let out = run_in(
            &dir,
            &[
                "run", "m.toml", "--no-log", "--sample", "3", "--seed", "1", "--set", set,
            ],
        );
        assert_error(set, &out, &["--set", "dispersed by dispersion[1]"]);
    }
    // a --set on a number that is not dispersed is fine
    let out = run_in(
        &dir,
        &[
            "margins",
            "m.toml",
            "--samples",
            "60",
            "--seed",
            "1",
            "--orbits",
            "0.5",
            "--set",
            "node.housing.capacitance_j_per_k=130",
            "--quiet",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let _ = std::fs::remove_dir_all(&dir);
}

// 5: no verdict without something to judge.
#[test]
fn cli_no_verdict_without_something_to_judge() {
    let dir = tmpdir("rel-judge");
    std::fs::write(dir.join("m.toml"), margins_text()).unwrap();
    refused_in(
        &dir,
        "tiny horizon",
        &[
            "margins",
            "m.toml",
            "--samples",
            "60",
            "--seed",
            "1",
            "--orbits",
            "1e-12",
            "--quiet",
        ],
        &["--orbits 1e-12", "runs last 1 s"],
    );
    refused_in(
        &dir,
        "endless horizon",
        &[
            "margins",
            "m.toml",
            "--samples",
            "60",
            "--seed",
            "1",
            "--orbits",
            "1e7",
            "--quiet",
        ],
        &["--orbits 1e7"],
    );
    // a scenario with no gear pair
    let text = margins_text();
    let start = text.find("[[gear_pair]]").unwrap();
    let end = text[start..]
        .find("\n[[sensor]]")
        .map_or(text.len(), |k| start + k);
    let body = text[..start].to_string() + &text[end..];
    let body = body.replace(
        "[[sensor]]\ncolumn = \"backlash_um\"\nquantity = \"backlash_um\"\n",
        "",
    );
    let body = body.replace(
        "[[dispersion]]\npath = \"gear_pair.mesh.pinion.tooth_thinning_um\"\ndistribution = \"uniform\"\nmin = 16.0\nmax = 23.0\n",
        "",
    );
    std::fs::write(dir.join("nogear.toml"), body).unwrap();
    refused_in(
        &dir,
        "no gear pair",
        &[
            "margins",
            "nogear.toml",
            "--samples",
            "60",
            "--seed",
            "1",
            "--orbits",
            "1",
            "--quiet",
        ],
        &["nogear.toml", "no [[gear_pair]]", "nothing to judge"],
    );
    // diagnose: no channel of the recording is a sensor
    std::fs::write(dir.join("t.csv"), "time_s\n0\n30\n60\n").unwrap();
    refused_in(
        &dir,
        "no channel",
        &["diagnose", "m.toml", "--recording", "t.csv", "--quiet"],
        &["t.csv", "nothing to compare"],
    );
    // a recording whose last time stamp jumps far ahead: the held-out orbits are empty
    let text = std::fs::read_to_string(example("heater-housing.csv")).unwrap();
    let last = text.lines().last().unwrap();
    let jumped = text.clone() + &last.replacen("68100.0", "1000000.0", 1) + "\n";
    std::fs::write(dir.join("jump.csv"), jumped).unwrap();
    refused_in(
        &dir,
        "jump",
        &["diagnose", "m.toml", "--recording", "jump.csv", "--quiet"],
        &[
            "jump.csv",
            "held-out orbits",
            "samples of `housing_c`",
            "at least",
        ],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Shard files of the margins scenario in `dir`: s0.json, s1.json (60 samples).
fn shards(dir: &Path) {
    std::fs::write(dir.join("m.toml"), margins_text()).unwrap();
    for i in 0..2 {
        let out = run_in(
            dir,
            &[
                "margins",
                "m.toml",
                "--samples",
                "60",
                "--seed",
                "4",
                "--orbits",
                "0.5",
                "--quiet",
                "--shard",
                &format!("{i}/2"),
                "--json",
                &format!("s{i}.json"),
            ],
        );
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    }
}

fn edit_shard(dir: &Path, name: &str, f: impl Fn(&mut serde_json::Value)) {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s0.json")).unwrap()).unwrap();
    f(&mut v);
    std::fs::write(dir.join(name), v.to_string()).unwrap();
}

// 6, 8: merge recomputes every flag, checks sizes against the header, never panics.
#[test]
fn cli_merge_trusts_no_shard() {
    let dir = tmpdir("rel-merge");
    shards(&dir);
    // a smallest backlash of -50 µm with its flags left false: refused, naming it
    edit_shard(&dir, "bad-flags.json", |v| {
        v["outcomes"][3]["pairs"][0]["min_backlash_um"] = (-50.0).into();
    });
    refused_in(
        &dir,
        "flags",
        &["merge", "bad-flags.json", "s1.json", "--json", "r.json"],
        &[
            "bad-flags.json",
            "sample 3",
            "min_backlash_um = -50",
            "violated = true",
        ],
    );
    // the same made consistent: the merged verdict fails
    edit_shard(&dir, "consistent.json", |v| {
        let pr = &mut v["outcomes"][3]["pairs"][0];
        pr["min_backlash_um"] = (-50.0).into();
        pr["min_margin_um"] = (-55.0).into();
        pr["violated"] = true.into();
        pr["interference"] = true.into();
    });
    // refused by its checksum (it merged before: helper-19)
    refused_in(
        &dir,
        "consistent",
        &["merge", "consistent.json", "s1.json"],
        &["consistent.json", "do not match the SHA-256"],
    );
    // sealed again, as one who recomputes the checksum: the merged verdict, taken from
    // the values, fails
    let text = std::fs::read_to_string(dir.join("consistent.json")).unwrap();
    let resealed = orbitlash::margins::read_shard(&text, "consistent.json")
        .unwrap()
        .sealed();
    std::fs::write(
        dir.join("resealed.json"),
        serde_json::to_string(&resealed).unwrap(),
    )
    .unwrap();
    let out = run_in(&dir, &["merge", "resealed.json", "s1.json"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stdout(&out).starts_with("FAIL mesh"), "{}", stdout(&out));
    // sizes against the shard's own header, and counts bounded before allocating
    for (case, edit, needle) in [
        (
            "samples u64::MAX",
            Box::new(|v: &mut serde_json::Value| v["run"]["samples"] = u64::MAX.into())
                as Box<dyn Fn(&mut serde_json::Value)>,
            "18446744073709551615 samples, outside 1 … 10000000",
        ),
        (
            "samples 1e12",
            Box::new(|v: &mut serde_json::Value| v["run"]["samples"] = 1_000_000_000_000u64.into()),
            "1000000000000 samples, outside",
        ),
        (
            "a pair that leaves the plots folder",
            Box::new(|v: &mut serde_json::Value| v["run"]["pairs"][0][0] = "../escaped".into()),
            "gear pair name",
        ),
        (
            "an escape in the scenario name",
            Box::new(|v: &mut serde_json::Value| v["run"]["scenario"] = "a\u{1b}[31mb".into()),
            "scenario name",
        ),
        (
            "a 300-digit backlash",
            Box::new(|v: &mut serde_json::Value| {
                v["outcomes"][2]["pairs"][0]["min_backlash_um"] = 1e300.into();
                v["outcomes"][2]["pairs"][0]["min_margin_um"] = 1e300.into();
            }),
            "a value no run can give",
        ),
        (
            "an outcome missing",
            Box::new(|v: &mut serde_json::Value| {
                v["outcomes"].as_array_mut().unwrap().pop();
            }),
            "outcomes",
        ),
        (
            "a value missing",
            Box::new(|v: &mut serde_json::Value| {
                v["outcomes"][2]["values"].as_array_mut().unwrap().pop();
            }),
            "values",
        ),
        (
            "a pair missing",
            Box::new(|v: &mut serde_json::Value| {
                v["outcomes"][2]["pairs"].as_array_mut().unwrap().pop();
            }),
            "gear pair",
        ),
        (
            "range off",
            Box::new(|v: &mut serde_json::Value| v["range"][1] = 31.into()),
            "range",
        ),
        (
            "index out of order",
            Box::new(|v: &mut serde_json::Value| v["outcomes"][1]["index"] = 5000.into()),
            "outcome 1",
        ),
        (
            "shard beyond n",
            Box::new(|v: &mut serde_json::Value| v["shard"][0] = 7.into()),
            "shard 7/2",
        ),
    ] {
        edit_shard(&dir, "x.json", edit);
        refused_in(
            &dir,
            case,
            &["merge", "x.json", "s1.json", "--json", "r.json"],
            &["x.json", needle],
        );
    }
    // a file that is not there, named
    refused_in(
        &dir,
        "missing",
        &["merge", "nonexist.json"],
        &["nonexist.json"],
    );
    // an lhs replay beyond u32 is refused, not truncated
    refused_in(
        &dir,
        "lhs samples",
        &[
            "run",
            "m.toml",
            "--no-log",
            "--sample",
            "1",
            "--seed",
            "1",
            "--sampling",
            "lhs",
            "--samples",
            "4294967297",
        ],
        &["4294967297", "1 … 10000000"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

// 7: physically impossible recordings are refused; noise far above the signal warns.
#[test]
fn cli_diagnose_refuses_impossible_recordings() {
    let dir = tmpdir("rel-impossible");
    std::fs::write(dir.join("s.toml"), reference_text()).unwrap();
    let text = std::fs::read_to_string(example("heater-housing.csv")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<String> = lines[40].split(',').map(String::from).collect();
    cells[2] = "-500".into();
    lines[40] = cells.join(",");
    std::fs::write(dir.join("cold.csv"), lines.join("\n") + "\n").unwrap();
    refused_in(
        &dir,
        "-500 °C",
        &["diagnose", "s.toml", "--recording", "cold.csv", "--quiet"],
        &["cold.csv:41", "`motor_c` = -500 °C", "below absolute zero"],
    );
    // kelvin columns too
    let k = reference_with(&[("column = \"housing_c\"", "column = \"housing_k\"")]);
    std::fs::write(dir.join("k.toml"), k).unwrap();
    std::fs::write(dir.join("k.csv"), "time_s,housing_k\n0,290\n30,-3\n").unwrap();
    refused_in(
        &dir,
        "negative kelvin",
        &["diagnose", "k.toml", "--recording", "k.csv", "--quiet"],
        &["k.csv:3", "housing_k", "below absolute zero"],
    );
    // σ = 100 µm of noise on a backlash of a few µm's swing: a warning that the verdict
    // rests on noise
    let mut state = 12345u64;
    let mut gauss = || {
        let mut u = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (a, b) = (u(), u());
        (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
    };
    let noisy: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                return l.to_string();
            }
            let mut c: Vec<String> = l.split(',').map(String::from).collect();
            let v: f64 = c[6].parse().unwrap();
            c[6] = format!("{:.3}", v + 100.0 * gauss());
            c.join(",")
        })
        .collect();
    std::fs::write(dir.join("noisy.csv"), noisy.join("\n") + "\n").unwrap();
    let out = run_in(
        &dir,
        &[
            "diagnose",
            "s.toml",
            "--recording",
            "noisy.csv",
            "--quiet",
            "--json",
            "n.json",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("warning: channel `backlash_um`: its noise"),
        "{}",
        stderr(&out)
    );
    assert!(
        !stderr(&out).contains("channel `housing_c`"),
        "{}",
        stderr(&out)
    );
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("n.json")).unwrap()).unwrap();
    assert!(j["warnings"][0].as_str().unwrap().contains("backlash_um"));
    let _ = std::fs::remove_dir_all(&dir);
}

// 9: up-front estimates and refusals; implausible time units.
#[test]
fn cli_costs_are_estimated_before_anything_runs() {
    let dir = tmpdir("rel-cost");
    std::fs::write(dir.join("m.toml"), margins_text()).unwrap();
    // 1000 samples of 50 000 orbits: over the limit of all samples' steps
    refused_in(
        &dir,
        "margins total",
        &[
            "margins",
            "m.toml",
            "--samples",
            "1000",
            "--seed",
            "1",
            "--orbits",
            "50000",
            "--quiet",
            "--json",
            "r.json",
        ],
        &["1000 samples would take", "--force"],
    );
    // a thermostat chattering on a 0.6 J/K node: the periodic search is refused
    let chatter = reference_text()
        + "\n[[heater]]\nnode = \"gear1.r0\"\npower_w = 50.0\non_k = 293.0\noff_k = 293.001\n";
    std::fs::write(dir.join("c.toml"), chatter).unwrap();
    refused_in(
        &dir,
        "steady chatter",
        &["run", "c.toml", "--steady-state", "--no-log", "--quiet"],
        &["periodic search would take", "--force"],
    );
    let chatter_m = std::fs::read_to_string(dir.join("c.toml")).unwrap()
        + "\n[[dispersion]]\npath = \"environment.beta_deg\"\ndistribution = \"uniform\"\nmin = 10.0\nmax = 30.0\n";
    std::fs::write(dir.join("cm.toml"), chatter_m).unwrap();
    refused_in(
        &dir,
        "margins steady chatter",
        &[
            "margins",
            "cm.toml",
            "--samples",
            "60",
            "--seed",
            "1",
            "--steady-state",
            "--quiet",
        ],
        &["each sample would take", "--force"],
    );
    // a thermostat that chatters only in some samples: those are stopped at their step
    // budget and reported, and the run ends
    let dispersed = reference_text()
        + "\n[[heater]]\nname = \"h\"\nnode = \"gear1.r0\"\npower_w = 50.0\non_k = 293.0\noff_k = 300.0\n\n[[dispersion]]\npath = \"heater.h.off_k\"\ndistribution = \"cases\"\nvalues = [300.0, 293.001]\n";
    std::fs::write(dir.join("cd.toml"), dispersed).unwrap();
    let out = run_in(
        &dir,
        &[
            "margins",
            "cd.toml",
            "--samples",
            "8",
            "--seed",
            "2",
            "--orbits",
            "1",
            "--quiet",
            "--json",
            "cd.json",
        ],
    );
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("cd.json")).unwrap()).unwrap();
    let invalid = r["invalid"].as_array().unwrap();
    assert!(
        !invalid.is_empty() && r["valid_samples"].as_u64().unwrap() < 8,
        "{r}"
    );
    assert!(
        invalid[0]["reason"]
            .as_str()
            .unwrap()
            .contains("solver steps, its budget"),
        "{invalid:?}"
    );
    // a dry run checks outputs and cost, and stops before the periodic search
    let out = run_in(
        &dir,
        &[
            "run",
            "m.toml",
            "--steady-state",
            "--dry-run",
            "--csv",
            "x.csv",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(!stdout(&out).contains("periodic orbit"), "{}", stdout(&out));
    assert!(!dir.join("x.csv").exists() && !dir.join("logs").exists());
    // recordings in milliseconds, or ending past any run
    let text = std::fs::read_to_string(example("heater-housing.csv")).unwrap();
    let ms: Vec<String> = text
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                return l.to_string();
            }
            let (t, rest) = l.split_once(',').unwrap();
            format!("{},{rest}", t.parse::<f64>().unwrap() * 1000.0)
        })
        .collect();
    std::fs::write(dir.join("ms.csv"), ms.join("\n") + "\n").unwrap();
    refused_in(
        &dir,
        "ms",
        &["diagnose", "m.toml", "--recording", "ms.csv", "--quiet"],
        &["ms.csv", "milliseconds"],
    );
    // milliseconds at 1 Hz: steps of 1000 "s"
    let mut hz = String::from("time_s,housing_c\n");
    for k in 0..2000 {
        hz += &format!("{},{:.2}\n", k * 1000, 10.0 * ((k as f64) / 300.0).sin());
    }
    std::fs::write(dir.join("hz.csv"), hz).unwrap();
    refused_in(
        &dir,
        "ms at 1 Hz",
        &["diagnose", "m.toml", "--recording", "hz.csv", "--quiet"],
        &["hz.csv", "steps by 1000 s", "milliseconds"],
    );
    let last = text.lines().last().unwrap();
    std::fs::write(
        dir.join("far.csv"),
        text.clone() + &last.replacen("68100.0", "1e300", 1) + "\n",
    )
    .unwrap();
    refused_in(
        &dir,
        "1e300",
        &["diagnose", "m.toml", "--recording", "far.csv", "--quiet"],
        &["far.csv", "1e300 s", "later than any run"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

// 11: small things.
#[test]
fn cli_damaged_and_foreign_files_are_named_as_such() {
    let dir = tmpdir("rel-files");
    std::fs::write(dir.join("s.toml"), reference_text()).unwrap();
    // random bytes: not an MCAP file, not CSV text
    let noise: Vec<u8> = (0..5000u32)
        .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
        .collect();
    std::fs::write(dir.join("r.mcap"), &noise).unwrap();
    std::fs::write(dir.join("r.csv"), &noise).unwrap();
    refused_in(
        &dir,
        "random mcap",
        &["diagnose", "s.toml", "--recording", "r.mcap", "--quiet"],
        &["r.mcap", "not an MCAP file"],
    );
    refused_in(
        &dir,
        "random csv",
        &["diagnose", "s.toml", "--recording", "r.csv", "--quiet"],
        &["r.csv", "neither CSV text nor an MCAP file"],
    );
    // a CSV whose multi-byte character straddles the 4 kB looked at first is text
    let mut head = String::from("# ");
    while head.len() < 4095 {
        head.push('x');
    }
    head.push_str("°C\n");
    std::fs::write(
        dir.join("deg.csv"),
        head + &std::fs::read_to_string(example("null.csv")).unwrap(),
    )
    .unwrap();
    let out = run_in(
        &dir,
        &["diagnose", "s.toml", "--recording", "deg.csv", "--quiet"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // a semicolon CSV names its delimiter
    let text = std::fs::read_to_string(example("null.csv")).unwrap();
    std::fs::write(dir.join("semi.csv"), text.replace(',', ";")).unwrap();
    refused_in(
        &dir,
        "semicolons",
        &["diagnose", "s.toml", "--recording", "semi.csv", "--quiet"],
        &["semi.csv:1", "separated by semicolons"],
    );
    // escape bytes in a recording's column name are not echoed raw
    std::fs::write(dir.join("esc.csv"), "time_s,\u{1b}[31mred_c\n0,1\n").unwrap();
    let out = run_in(
        &dir,
        &["diagnose", "s.toml", "--recording", "esc.csv", "--quiet"],
    );
    assert_error("escape", &out, &["esc.csv", "\\u{1b}[31mred_c"]);
    assert!(!stderr(&out).contains('\u{1b}'));
    // a dispersion group's name with escape bytes: check's table shows them escaped
    let margins = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenarios/reference-hinge-margins.toml"),
    )
    .unwrap()
    .replace("group = \"17-4PH lot\"", "group = \"bad\\u001b[31m\"");
    assert!(margins.contains("bad\\u001b"));
    std::fs::write(dir.join("group.toml"), margins).unwrap();
    let out = run_in(&dir, &["check", "group.toml"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        !stdout(&out).contains('\u{1b}') && stdout(&out).contains("bad\\u{1b}[31m"),
        "{}",
        stdout(&out)
    );
    // a log with a flipped byte: export-csv names the damaged chunk, recover leaves
    // the damaged messages out instead of calling the log complete
    let out = run_in(&dir, &["run", "s.toml", "--quiet", "--out", "l.mcap"]);
    assert!(out.status.success());
    let mut b = std::fs::read(dir.join("l.mcap")).unwrap();
    let at = b.len() / 2;
    b[at] ^= 0x01;
    std::fs::write(dir.join("flip.mcap"), &b).unwrap();
    let out = run_in(&dir, &["export-csv", "flip.mcap", "--out", "f.csv"]);
    assert_error(
        "export flipped",
        &out,
        &["flip.mcap", "does not match its CRC"],
    );
    assert!(!dir.join("f.csv").exists());
    let out = run_in(&dir, &["recover", "flip.mcap", "--out", "fixed.mcap"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stderr(&out).contains("damaged"), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("damaged messages left out: the copy lacks messages at "),
        "{}",
        stdout(&out)
    );
    let out = run_in(&dir, &["export-csv", "fixed.mcap", "--out", "f.csv"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // two damaged chunks far apart: the copy lacks two stretches of time, not all
    // that lies between them (it was told as one, from the first to the last)
    let mut b = std::fs::read(dir.join("l.mcap")).unwrap();
    let n = b.len();
    b[n / 4] ^= 0x01;
    b[3 * n / 4] ^= 0x01;
    std::fs::write(dir.join("flip2.mcap"), &b).unwrap();
    let out = run_in(&dir, &["recover", "flip2.mcap", "--out", "fixed2.mcap"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("the copy lacks messages in 2 stretches, t = "),
        "{}",
        stdout(&out)
    );
    // the copy is not called complete: its end record says recovered (the verdict, the
    // run's own, kept), and a figure of it says what it lacks
    let out = run_in(
        &dir,
        &["recover", "fixed.mcap", "--out", "again-fixed.mcap"],
    );
    assert!(
        stdout(&out).contains("run_end: recovered"),
        "{}",
        stdout(&out)
    );
    let out = run_in(&dir, &["plot", "fixed.mcap", "--out", "fixed.svg"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("damaged messages left out at t = "),
        "{}",
        stderr(&out)
    );
    // a flipped byte in the first chunk (schemas and channels, no message): the
    // readers refuse the file, so recover writes a readable copy all the same
    let mut b = std::fs::read(dir.join("l.mcap")).unwrap();
    b[1000] ^= 0x55;
    std::fs::write(dir.join("flip1.mcap"), &b).unwrap();
    let out = run_in(&dir, &["export-csv", "flip1.mcap", "--out", "f1.csv"]);
    assert_error(
        "export flipped first chunk",
        &out,
        &["does not match its CRC"],
    );
    let out = run_in(&dir, &["recover", "flip1.mcap", "--out", "fixed1.mcap"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        !stdout(&out).contains("nothing to recover"),
        "{}",
        stdout(&out)
    );
    let out = run_in(&dir, &["export-csv", "fixed1.mcap", "--out", "f1.csv"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // the undamaged log is still complete
    let out = run_in(&dir, &["recover", "l.mcap", "--out", "again.mcap"]);
    assert!(stdout(&out).contains("nothing to recover"));
    // huge numbers are refused or shown in exponent form, never with 300 digits
    let out = run_in(
        &dir,
        &[
            "run",
            "s.toml",
            "--no-log",
            "--set",
            "node.housing.capacitance_j_per_k=1e300",
        ],
    );
    assert_error("1e300", &out, &["capacitance_j_per_k", "1e12"]);
    assert!(first_error_line(&out).len() < 300);
    // a backlash limit of 1e308 µm printed a 300-digit margin: refused with its range
    let out = run_in(
        &dir,
        &[
            "backlash",
            "s.toml",
            "--uniform-c",
            "20",
            "--set",
            "gear_pair.mesh.min_backlash_um=1e308",
        ],
    );
    assert_error("limit 1e308", &out, &["min_backlash_um", "0 … 10000"]);
    assert!(first_error_line(&out).len() < 300);
    // a normal dispersion's reach is said in exponent form
    let text = std::fs::read_to_string(dir.join("s.toml")).unwrap()
        + "\n[[dispersion]]\npath = \"node.motor.capacitance_j_per_k\"\ndistribution = \"normal\"\nmean = 75.0\nsd = 1e300\n";
    std::fs::write(dir.join("wide.toml"), text).unwrap();
    let out = run_in(&dir, &["check", "wide.toml"]);
    assert_error("sd 1e300", &out, &["normal reaches -5.199e300"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Damage after a log's data section: a changed byte in the summary (which viewers seek
/// through) and bytes after the closing magic. The messages are whole (each chunk has
/// its own CRC), so the readers read them, but say so and point to `recover`, which
/// writes a clean copy instead of calling the file complete.
#[test]
fn cli_damage_after_the_data_is_named() {
    let dir = tmpdir("rel-tail");
    std::fs::write(dir.join("s.toml"), reference_text()).unwrap();
    let out = run_in(&dir, &["run", "s.toml", "--quiet", "--out", "l.mcap"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let good = std::fs::read(dir.join("l.mcap")).unwrap();
    // the footer: opcode, length, summary_start, summary_offset_start, summary_crc (29
    // bytes), then the closing magic (8)
    let footer_at = good.len() - 8 - 29;
    assert_eq!(good[footer_at], 0x02, "the footer's opcode");
    let summary_start = u64::from_le_bytes(good[footer_at + 9..footer_at + 17].try_into().unwrap());
    assert!(summary_start > 0 && (summary_start as usize) < footer_at);
    // the last byte of the summary (the high byte of the last summary offset's length)
    let mut summary = good.clone();
    summary[footer_at - 1] ^= 0x01;
    // cut within the summary: the data section is whole, the footer is missing
    let cut = good[..footer_at - 10].to_vec();
    // a changed letter in the summary's copy of a channel's topic: the data section's
    // copy, which the messages were written with, is the one read
    let topic = b"/thermal/temperature";
    let at = good
        .windows(topic.len())
        .rposition(|w| w == topic)
        .expect("the topic in the summary");
    assert!(at > summary_start as usize);
    let mut channel = good.clone();
    channel[at + 3] ^= 0x20;
    // the length of the summary's first record made too long for the file: the
    // summary cannot be read, the messages can
    let mut length = good.clone();
    length[summary_start as usize + 1..summary_start as usize + 9]
        .copy_from_slice(&u64::MAX.to_le_bytes());
    let mut trailing = good.clone();
    trailing.extend_from_slice(b"junk after the end\n");
    for (name, bytes, needle) in [
        ("summary.mcap", &summary, "does not match the footer's CRC"),
        (
            "trailing.mcap",
            &trailing,
            "19 byte(s) follow its closing MCAP magic",
        ),
        ("cut.mcap", &cut, "has no whole footer"),
        ("channel.mcap", &channel, "does not match the footer's CRC"),
        ("length.mcap", &length, "has no whole footer"),
    ] {
        std::fs::write(dir.join(name), bytes).unwrap();
        let csv = format!("{name}.csv");
        let out = run_in(&dir, &["export-csv", name, "--out", &csv]);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        let err = stderr(&out);
        assert!(err.contains(name) && err.contains(needle), "{name}: {err}");
        assert!(err.contains("orbitlash recover"), "{name}: {err}");
        assert_eq!(
            std::fs::read(dir.join(&csv)).unwrap(),
            {
                let o = run_in(&dir, &["export-csv", "l.mcap"]);
                o.stdout
            },
            "{name}: the messages read are the good log's"
        );
        let json = format!("{name}.json");
        let out = run_in(&dir, &["layout", name, "--out", &json]);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        assert!(stderr(&out).contains(needle), "{name}: {}", stderr(&out));
        let fixed = format!("fixed-{name}");
        let out = run_in(&dir, &["recover", name, "--out", &fixed]);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        assert!(
            stdout(&out).contains(needle) && !stdout(&out).contains("nothing to recover"),
            "{name}: {}",
            stdout(&out)
        );
        let out = run_in(&dir, &["export-csv", &fixed, "--out", "fixed.csv"]);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        assert!(!stderr(&out).contains("note:"), "{name}: {}", stderr(&out));
        let out = run_in(&dir, &["recover", &fixed, "--out", "again.mcap"]);
        assert!(
            stdout(&out).contains("nothing to recover"),
            "{name}: {}",
            stdout(&out)
        );
    }
    // cut just before the data section's end record (DataEnd, 13 bytes): every byte is
    // a whole record, and recover says so instead of "N of N bytes were whole; the rest
    // was cut off"
    assert_eq!(good[summary_start as usize - 13], 0x0F, "DataEnd");
    std::fs::write(dir.join("whole.mcap"), &good[..summary_start as usize - 13]).unwrap();
    let out = run_in(
        &dir,
        &["recover", "whole.mcap", "--out", "whole-fixed.mcap"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("bytes were whole records, but the log stops there"),
        "{}",
        stdout(&out)
    );
    // the good log: no note
    let out = run_in(&dir, &["export-csv", "l.mcap", "--out", "good.csv"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(!stderr(&out).contains("note:"), "{}", stderr(&out));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_margins_count_invalid_samples_and_say_one_orbit() {
    let dir = tmpdir("rel-invalid");
    // heater set points dispersed so that some samples have on_k ≥ off_k
    let text = reference_text()
        + "\n[[heater]]\nname = \"h\"\nnode = \"housing\"\npower_w = 2.0\non_k = 262.0\noff_k = 266.0\n\n[[dispersion]]\npath = \"heater.h.on_k\"\ndistribution = \"uniform\"\nmin = 255.0\nmax = 265.0\n\n[[dispersion]]\npath = \"heater.h.off_k\"\ndistribution = \"uniform\"\nmin = 260.0\nmax = 270.0\n";
    std::fs::write(dir.join("h.toml"), text).unwrap();
    let out = run_in(
        &dir,
        &[
            "margins",
            "h.toml",
            "--samples",
            "80",
            "--seed",
            "3",
            "--orbits",
            "1",
            "--quiet",
            "--json",
            "r.json",
            "--csv",
            "r.csv",
        ],
    );
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let so = stdout(&out);
    assert!(
        so.starts_with("FAIL mesh:") && so.contains("could not be run"),
        "{so}"
    );
    assert!(so.contains("1 orbit each"), "{so}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    let invalid = r["invalid"].as_array().unwrap();
    assert!(!invalid.is_empty());
    assert_eq!(
        r["valid_samples"].as_u64().unwrap() + invalid.len() as u64,
        80
    );
    // every invalid sample really has on ≥ off (values in the CSV), every valid one not
    let csv = std::fs::read_to_string(dir.join("r.csv")).unwrap();
    for line in csv.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        let (on, off): (f64, f64) = (c[1].parse().unwrap(), c[2].parse().unwrap());
        let marked = !c.last().unwrap().is_empty();
        assert_eq!(marked, on >= off, "{line}");
    }
    // the values are applied in any order: a sample whose off_k is below the nominal
    // on_k (262 K) but above its own is valid (and the plan accepted off_k's range,
    // 260 K being possible with a lower on_k)
    assert!(
        csv.lines().skip(1).any(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let (on, off): (f64, f64) = (c[1].parse().unwrap(), c[2].parse().unwrap());
            off < 262.0 && on < off && c.last().unwrap().is_empty()
        }),
        "no sample tested the order"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_constant_sensitivities_are_not_drawn_as_zero() {
    let dir = tmpdir("rel-nan");
    // a dispersion that cannot move the backlash within one orbit's first minute … and
    // a case list of one value: constant input, no rank correlation
    let text = reference_text()
        + "\n[[dispersion]]\npath = \"gear_pair.mesh.pinion.tooth_thinning_um\"\ndistribution = \"uniform\"\nmin = 16.0\nmax = 23.0\n\n[[dispersion]]\npath = \"environment.albedo\"\ndistribution = \"cases\"\nvalues = [0.3]\n";
    std::fs::write(dir.join("c.toml"), text).unwrap();
    std::fs::create_dir(dir.join("p")).unwrap();
    let out = run_in(
        &dir,
        &[
            "margins",
            "c.toml",
            "--samples",
            "60",
            "--seed",
            "1",
            "--orbits",
            "0.5",
            "--quiet",
            "--plots",
            "p",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stdout(&out).contains("environment.albedo")
            && stdout(&out).contains("no variation to rank"),
        "{}",
        stdout(&out)
    );
    let svg = std::fs::read_to_string(dir.join("p/mesh-sensitivity.svg")).unwrap();
    assert!(svg.contains("environment.albedo (no variation)"), "{svg}");
    assert!(!svg.contains("environment.albedo (+0.00)"));
    let _ = std::fs::remove_dir_all(&dir);
}

// 12: the shipped margins scenario checks and passes.
#[test]
fn cli_reference_hinge_margins_is_shipped_and_passes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let s = root.join("scenarios/reference-hinge-margins.toml");
    let text = std::fs::read_to_string(&s).unwrap();
    // every dispersion says where its numbers come from
    for block in text.split("[[dispersion]]").skip(1) {
        assert!(block.contains('#'), "an uncommented dispersion: {block}");
    }
    let out = bin().args(["check"]).arg(&s).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let out = bin()
        .args(["margins"])
        .arg(&s)
        .args([
            "--samples",
            "100",
            "--seed",
            "1",
            "--steady-state",
            "--quiet",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(
        stdout(&out).starts_with("PASS mesh: 95/95 lower bound"),
        "{}",
        stdout(&out)
    );
}

#[test]
fn cli_bench_margins_compares_thread_counts() {
    let dir = tmpdir("rel-bench");
    std::fs::write(dir.join("m.toml"), margins_text()).unwrap();
    let out = run_in(
        &dir,
        &[
            "bench",
            "--margins",
            "m.toml",
            "--samples",
            "24",
            "--margins-horizon",
            "0.3",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let so = stdout(&out);
    assert!(
        so.contains("1 thread:") && so.contains("parallel efficiency"),
        "{so}"
    );
    assert!(so.contains("yes, bit for bit"), "{so}");
    let _ = std::fs::remove_dir_all(&dir);
}

// Review fixes: merge and gear pairs, outputs where folders go, --set in corrected.toml
// and check, replay indices.
#[test]
fn cli_merge_outputs_and_sets_review_cases() {
    let dir = tmpdir("rel-review");
    shards(&dir);
    // a shard whose run has another gear pair: another run, not a panic or a lost pair
    edit_shard(&dir, "two-pairs.json", |v| {
        let allowed = v["run"]["pairs"][0][1].clone();
        v["run"]["pairs"]
            .as_array_mut()
            .unwrap()
            .push(serde_json::json!(["mesh2", allowed]));
        for o in v["outcomes"].as_array_mut().unwrap() {
            let p = o["pairs"][0].clone();
            o["pairs"].as_array_mut().unwrap().push(p);
        }
    });
    std::fs::create_dir(dir.join("plots")).unwrap();
    for order in [["two-pairs.json", "s1.json"], ["s1.json", "two-pairs.json"]] {
        refused_in(
            &dir,
            "pairs differ",
            &["merge", order[0], order[1], "--plots", "plots"],
            &["from another run", "they differ in the gear pairs"],
        );
    }
    // --csv with --shard is refused; merge writes the CSV the unsharded run writes
    refused_in(
        &dir,
        "shard csv",
        &[
            "margins",
            "m.toml",
            "--samples",
            "60",
            "--seed",
            "4",
            "--orbits",
            "0.5",
            "--quiet",
            "--shard",
            "0/2",
            "--json",
            "x.json",
            "--csv",
            "x.csv",
        ],
        &["--csv with --shard", "orbitlash merge"],
    );
    let out = run_in(
        &dir,
        &["merge", "s0.json", "s1.json", "--csv", "merged.csv"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let out = run_in(
        &dir,
        &[
            "margins",
            "m.toml",
            "--samples",
            "60",
            "--seed",
            "4",
            "--orbits",
            "0.5",
            "--quiet",
            "--csv",
            "whole.csv",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(
        std::fs::read(dir.join("merged.csv")).unwrap(),
        std::fs::read(dir.join("whole.csv")).unwrap()
    );
    // a replay index beyond any run is refused, naming --sample
    refused_in(
        &dir,
        "huge sample",
        &[
            "run",
            "m.toml",
            "--no-log",
            "--sample",
            "18446744073709551615",
            "--seed",
            "1",
        ],
        &["--sample 18446744073709551615", "at most 10000000 samples"],
    );
    // `check` samples nothing: a --set on a dispersed number is the value checked
    let out = run_in(
        &dir,
        &["check", "m.toml", "--set", "environment.beta_deg=60"],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // a named output where --out is to make its folder; the default log folder
    let rec = example("heater-housing.csv");
    let rec = rec.to_str().unwrap();
    refused_in(
        &dir,
        "json = out folder",
        &[
            "diagnose",
            "m.toml",
            "--recording",
            rec,
            "--quiet",
            "--json",
            "newE",
            "--out",
            "newE",
        ],
        &["newE", "--json"],
    );
    assert!(!dir.join("newE").exists());
    let fresh = tmpdir("rel-review-logs");
    std::fs::write(fresh.join("m.toml"), margins_text()).unwrap();
    refused_in(
        &fresh,
        "csv = logs",
        &["run", "m.toml", "--csv", "logs"],
        &["logs", "--csv", "folder"],
    );
    assert!(!fresh.join("logs").exists());
    // corrected.toml is the diagnosed model: its --set values are written in
    let out = run_in(
        &dir,
        &[
            "diagnose",
            "m.toml",
            "--recording",
            rec,
            "--quiet",
            "--set",
            "conductor.housing-bus.conductance_w_per_k=0.031",
            "--out",
            "D",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = std::fs::read_to_string(dir.join("D/corrected.toml")).unwrap();
    assert!(
        text.contains("# --set conductor.housing-bus.conductance_w_per_k=0.031"),
        "{text}"
    );
    assert!(
        text.contains("conductance_w_per_k = 0.031"),
        "the --set value is not in the file"
    );
    // a scenario that writes its heaters inline keeps them inline, the finding added
    let text = format!(
        "heater = [{{ name = \"idle\", node = \"motor\", power_w = 0.5, on_k = 150.0, off_k = 151.0 }}]\n{}",
        reference_text()
    );
    std::fs::write(dir.join("inline.toml"), text).unwrap();
    let out = run_in(
        &dir,
        &[
            "diagnose",
            "inline.toml",
            "--recording",
            rec,
            "--quiet",
            "--out",
            "I",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = std::fs::read_to_string(dir.join("I/corrected.toml")).unwrap();
    let first = text
        .lines()
        .find(|l| l.starts_with("heater = ["))
        .expect("still inline");
    assert!(
        first.contains("idle") && first.contains("diagnose.heater.housing"),
        "{first}"
    );
    let out = run_in(&dir, &["run", "I/corrected.toml", "--no-log", "--quiet"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let _ = std::fs::remove_dir_all(&fresh);
    let _ = std::fs::remove_dir_all(&dir);
}

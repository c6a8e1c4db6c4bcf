//! The scoring harness: `orbitlash diagnose` (the binary the tests are built with, not
//! the library) on every written case and on the untouched flight day, its JSON
//! findings against each case's `expected.json`, as a Markdown table.
//!
//! A case is a **hit** when a finding names the expected effect on the expected target
//! (node, channel or face); its parameters are then checked against the tolerances of
//! `expected.json` (power ±25 %, set points ±1.5 K, τ ±30 %, offset ±0.5 K, α scale
//! ±20 %). A finding of the expected effect on another target is a miss, reported as
//! such (`right effect, wrong target`); for a miss, the expected candidate's fate is
//! shown (fitted and rejected, or ranked too low to be fitted). A case whose effect is
//! `none` (the null case and the control) **passes**
//! when diagnose names nothing the untouched day does not already name.

use std::path::Path;
use std::time::Instant;

use serde_json::Value;

use super::cases;

/// The target keys a finding may carry, in the report's order.
const TARGET_KEYS: [&str; 9] = [
    "node",
    "channel",
    "conductor",
    "load",
    "face",
    "path",
    "gear_pair",
    "gear",
    "schedule",
];

/// A finding as the report gives it: effect id, target (`key=value`, joined), and the
/// fitted parameters.
#[derive(Clone, Debug)]
struct Named {
    effect: String,
    target: String,
    parameters: Vec<(String, f64)>,
    finding: Value,
}

impl Named {
    fn of(finding: &Value) -> Named {
        let target = TARGET_KEYS
            .iter()
            .filter_map(|k| {
                finding
                    .get(*k)
                    .and_then(Value::as_str)
                    .map(|v| format!("{k}={v}"))
            })
            .collect::<Vec<_>>()
            .join(" ");
        let parameters = finding["parameters"]
            .as_object()
            .map(|m| {
                m.iter()
                    .filter_map(|(k, v)| v.as_f64().map(|x| (k.clone(), x)))
                    .collect()
            })
            .unwrap_or_default();
        Named {
            effect: finding["effect"].as_str().unwrap_or("?").to_string(),
            target,
            parameters,
            finding: finding.clone(),
        }
    }

    /// `effect target (p=v, …)`.
    fn label(&self) -> String {
        let p: Vec<String> = self
            .parameters
            .iter()
            .map(|(k, v)| format!("{k}={}", short(*v)))
            .collect();
        format!("{} {} ({})", self.effect, self.target, p.join(", "))
    }
}

/// A number with 3 significant digits.
fn short(x: f64) -> String {
    if x == 0.0 || (1e-3..1e4).contains(&x.abs()) {
        let d = (2 - x.abs().max(1e-12).log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.d$}")
    } else {
        format!("{x:.2e}")
    }
}

/// Runs `orbitlash diagnose` on `recording`, writing its JSON to `json`; the report and
/// the wall time (s). Extra arguments from `INJECT_DIAGNOSE_ARGS`.
pub fn run_diagnose(
    scenario: &Path,
    recording: &Path,
    json: &Path,
    out_dir: Option<&Path>,
) -> (Value, f64) {
    match out_dir {
        Some(d) => run_diagnose_with(scenario, recording, json, &["--out", d.to_str().unwrap()]),
        None => run_diagnose_with(scenario, recording, json, &[]),
    }
}

/// [`run_diagnose`] with `args` added.
pub fn run_diagnose_with(
    scenario: &Path,
    recording: &Path,
    json: &Path,
    args: &[&str],
) -> (Value, f64) {
    let extra = std::env::var("INJECT_DIAGNOSE_ARGS").unwrap_or_default();
    let start = Instant::now();
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_orbitlash"));
    cmd.arg("diagnose")
        .arg(scenario)
        .arg("--recording")
        .arg(recording)
        .arg("--json")
        .arg(json)
        .arg("--quiet")
        .args(extra.split_whitespace());
    cmd.args(args);
    let out = cmd.output().expect("the orbitlash binary runs");
    let wall = start.elapsed().as_secs_f64();
    assert!(
        out.status.success(),
        "diagnose on {}: {}",
        recording.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(json).expect("diagnose wrote its JSON");
    (serde_json::from_str(&text).expect("diagnose's JSON"), wall)
}

fn findings(report: &Value) -> Vec<Named> {
    report["findings"]
        .as_array()
        .map(|a| a.iter().map(Named::of).collect())
        .unwrap_or_default()
}

/// Whether `fitted` is within the tolerance `tol` (`{"relative": r}` or
/// `{"absolute": a}`) of `truth`, and the error as text.
fn within(truth: f64, fitted: f64, tol: &Value) -> (bool, String) {
    if let Some(r) = tol["relative"].as_f64() {
        let e = fitted / truth - 1.0;
        (
            e.abs() <= r,
            format!("{:+.0} % (±{:.0} %)", 100.0 * e, 100.0 * r),
        )
    } else {
        let a = tol["absolute"].as_f64().expect("a tolerance");
        let e = fitted - truth;
        (e.abs() <= a, format!("{e:+.2} (±{a})"))
    }
}

/// The expected finding as text: `effect target (p=v, …)`.
fn expected_label(expected: &Value) -> String {
    let effect = expected["effect"].as_str().unwrap_or("?");
    if effect == "none" {
        let outside = &expected["truth"]["outside_vocabulary"];
        return if outside.is_null() {
            "none".into()
        } else {
            format!("none (outside: {outside})")
        };
    }
    let e = Named::of(expected);
    format!("{} {} ({})", effect, e.target, {
        let p: Vec<String> = e
            .parameters
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        p.join(", ")
    })
}

/// Scores one report against its expected finding: the result and the parameter
/// errors (text).
fn judge(expected: &Value, report: &Value, untouched: &[Named]) -> (String, String) {
    let found = findings(report);
    let effect = expected["effect"].as_str().unwrap_or("?");
    if effect == "none" {
        let new: Vec<String> = found
            .iter()
            .filter(|f| {
                !untouched
                    .iter()
                    .any(|u| u.effect == f.effect && u.target == f.target)
            })
            .map(|f| format!("{} {}", f.effect, f.target))
            .collect();
        return if new.is_empty() {
            ("PASS (nothing new named)".into(), String::new())
        } else {
            (format!("FAIL (new: {})", new.join("; ")), String::new())
        };
    }
    let want = Named::of(expected);
    let hit = found.iter().find(|f| {
        f.effect == effect
            && want
                .target
                .split(' ')
                .all(|kv| f.target.split(' ').any(|x| x == kv))
    });
    let Some(hit) = hit else {
        let elsewhere: Vec<String> = found
            .iter()
            .filter(|f| f.effect == effect)
            .map(|f| f.target.clone())
            .collect();
        let mut result = if elsewhere.is_empty() {
            "MISS".to_string()
        } else {
            format!(
                "MISS (right effect, wrong target: {})",
                elsewhere.join("; ")
            )
        };
        if let Some(d) = listed_as_alternative(expected, report) {
            result.push_str(&format!(
                "; the truth is among a finding's alternatives (ΔBIC {d:.2})"
            ));
        }
        return (result, candidate_status(expected, report));
    };
    let mut all_ok = true;
    let mut errs = Vec::new();
    for (name, truth) in &want.parameters {
        let Some((_, fitted)) = hit.parameters.iter().find(|(k, _)| k == name) else {
            all_ok = false;
            errs.push(format!("{name}: not reported"));
            continue;
        };
        let (ok, e) = within(*truth, *fitted, &expected["tolerances"][name]);
        all_ok &= ok;
        errs.push(format!("{name} {} {e}", if ok { "ok" } else { "OFF" }));
    }
    let result = if all_ok {
        "HIT (parameters within tolerance)"
    } else {
        "HIT (parameters off)"
    };
    (result.into(), errs.join("; "))
}

/// The ΔBIC at which a finding lists the expected effect on the expected target among
/// its alternatives (those that explain about as well), if one does.
fn listed_as_alternative(expected: &Value, report: &Value) -> Option<f64> {
    let effect = expected["effect"].as_str()?;
    let name = TARGET_KEYS
        .iter()
        .find_map(|k| expected.get(*k).and_then(Value::as_str))?;
    let label = format!("{effect} on {name}");
    report["findings"]
        .as_array()?
        .iter()
        .flat_map(|f| f["alternatives"].as_array().into_iter().flatten())
        .find(|a| {
            a["candidate"]
                .as_str()
                .is_some_and(|c| c == label || c.starts_with(&format!("{label} (")))
        })
        .and_then(|a| a["delta_bic"].as_f64())
}

/// What became of the expected effect on the expected target among the candidates
/// (its status, reason and parameters), for a miss.
fn candidate_status(expected: &Value, report: &Value) -> String {
    let effect = expected["effect"].as_str().unwrap_or("?");
    let name = TARGET_KEYS
        .iter()
        .find_map(|k| expected.get(*k).and_then(Value::as_str))
        .unwrap_or("");
    let Some(c) = report["candidates"].as_array().and_then(|a| {
        a.iter().find(|c| {
            c["effect"].as_str() == Some(effect)
                && c["target"].as_str().is_some_and(|t| t.contains(name))
        })
    }) else {
        return format!("no candidate {effect} on {name}");
    };
    let params = c["parameters"]
        .as_object()
        .map(|m| {
            m.iter()
                .map(|(k, v)| format!("{k}={}", v.as_f64().map_or("?".into(), short)))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .unwrap_or_default();
    format!(
        "candidate {}: {} ({}){}",
        c["target"].as_str().unwrap_or(""),
        c["status"].as_str().unwrap_or("?"),
        c["reason"].as_str().unwrap_or(""),
        if params.is_empty() {
            String::new()
        } else {
            format!(", fitted {params}")
        }
    )
}

/// A Markdown table cell (pipes escaped).
fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// Runs diagnose on the untouched day (`flight`) and on every case written in `dir`,
/// twice: single shot (the shipped scenario) and after calibration (the workflow:
/// the scenario `diagnose --out` corrected on the untouched day, then each case
/// against it with `--no-calibration`, the model being calibrated already, so that
/// what it names is what changed). The two scoring tables as
/// Markdown, with a count of each.
pub fn score_all(dir: &Path, flight: &Path) -> String {
    let shipped = super::repo_root().join(super::scenario::SCENARIO);
    let day_dir = dir.join("untouched");
    let _ = std::fs::remove_dir_all(&day_dir);
    let (day, day_s) = run_diagnose(
        &shipped,
        flight,
        &dir.join("untouched.json"),
        Some(&day_dir),
    );
    let mut out = String::from("### Single shot (scenarios/funcube-1.toml)\n\n");
    out += &score_pass(dir, &shipped, (&day, day_s), "", &[]);
    let corrected = day_dir.join("corrected.toml");
    let (again, again_s) = run_diagnose_with(
        &corrected,
        flight,
        &dir.join("untouched-again.json"),
        &["--no-calibration"],
    );
    out += "\n### After calibration (against the untouched day's corrected.toml)\n\n";
    out += &score_pass(
        dir,
        &corrected,
        (&again, again_s),
        "-calibrated",
        &["--no-calibration"],
    );
    out
}

/// One pass of [`score_all`]: every case against `scenario`, judged against what the
/// untouched day (`day`, its wall time) already names; reports `diagnose<suffix>.json`.
fn score_pass(
    dir: &Path,
    scenario: &Path,
    day: (&Value, f64),
    suffix: &str,
    extra: &[&str],
) -> String {
    let (day, day_s) = day;
    let untouched = findings(day);
    let mut out = String::from(
        "| case | expected | verdict | diagnose named | result | parameters / candidate | time |\n|---|---|---|---|---|---|---:|\n",
    );
    let named = |r: &Value| {
        let f: Vec<String> = findings(r).iter().map(Named::label).collect();
        if f.is_empty() {
            "nothing".into()
        } else {
            f.join("; ")
        }
    };
    out += &format!(
        "| untouched day | (reference) | {} | {} | | | {day_s:.0} s |\n",
        day["verdict"].as_str().unwrap_or("?"),
        cell(&named(day))
    );
    let (mut hits, mut effects, mut clean, mut controls) = (0, 0, 0, 0);
    for case in cases() {
        let folder = dir.join(case.name);
        let text = std::fs::read_to_string(folder.join("expected.json")).expect("expected.json");
        let expected: Value = serde_json::from_str(&text).expect("expected.json parses");
        let (report, wall) = run_diagnose_with(
            scenario,
            &folder.join("recording.csv"),
            &folder.join(format!("diagnose{suffix}.json")),
            extra,
        );
        let (result, detail) = judge(&expected, &report, &untouched);
        if expected["effect"] == "none" {
            controls += 1;
            clean += usize::from(result.starts_with("PASS"));
        } else {
            effects += 1;
            hits += usize::from(result == "HIT (parameters within tolerance)");
        }
        out += &format!(
            "| {} | {} | {} | {} | {} | {} | {wall:.0} s |\n",
            case.name,
            cell(&expected_label(&expected)),
            report["verdict"].as_str().unwrap_or("?"),
            cell(&named(&report)),
            result,
            cell(&detail)
        );
    }
    out += &format!(
        "\n{hits} of {effects} effects named with every parameter within tolerance; {clean} of {controls} cases without an effect in the vocabulary name nothing new.\n"
    );
    out
}

//! `orbitlash backlash`: the static calculator (like the paper's Table 1): backlash of
//! every gear pair at uniform temperatures or at given gear and housing temperatures,
//! for each model variant.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use orbitlash::constants::ZERO_CELSIUS_K;

use orbitlash::gear::backlash::MeshError;
use orbitlash::gear::{CenterDistance, DeformedGear, GearPair, MeshState};
use orbitlash::run::summary::PairVerdict;
use orbitlash::units::{c_to_k, k_to_c};

use super::table::{self, Align};
use super::{Outcome, print_out};

#[derive(Args, Debug)]
pub struct BacklashArgs {
    /// Scenario file (TOML). Default: the embedded reference-hinge scenario.
    scenario: Option<PathBuf>,
    /// Uniform temperatures, °C (repeatable). Default: 100 and −75, after the pair's
    /// assembly temperature (25 in the reference).
    #[arg(long = "uniform-c", allow_negative_numbers = true, value_parser = finite)]
    uniform_c: Vec<f64>,
    /// Pinion temperature, °C (all its nodes); with --wheel-c.
    #[arg(long, allow_negative_numbers = true, value_parser = finite, requires = "wheel_c")]
    pinion_c: Option<f64>,
    /// Wheel temperature, °C (all its nodes); with --pinion-c.
    #[arg(long, allow_negative_numbers = true, value_parser = finite, requires = "pinion_c")]
    wheel_c: Option<f64>,
    /// Housing temperature, °C, for a centre distance that follows the housing (every
    /// case). Default: each uniform case's own temperature, and the pair's assembly
    /// temperature for --pinion-c/--wheel-c.
    #[arg(long, allow_negative_numbers = true, value_parser = finite)]
    housing_c: Option<f64>,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
    /// Change a number of the scenario by its key path (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
}

fn finite(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v)
            if v.is_finite()
                && v > -ZERO_CELSIUS_K
                && v <= orbitlash::run::sim::MAX_TEMPERATURE_K - ZERO_CELSIUS_K =>
        {
            Ok(v)
        }
        _ => Err(format!(
            "`{s}` is not a temperature in °C above −273.15 and at most 9726.85 (0 … 10 000 K)"
        )),
    }
}

/// A case and the mesh it gives: the state, and why the gears do not mesh if they do
/// not (the state's mesh quantities are then NaN).
struct Evaluated {
    case: Case,
    mesh: MeshState,
    no_mesh: Option<MeshError>,
}

struct Case {
    label: String,
    pinion_c: f64,
    wheel_c: f64,
    housing_c: f64,
}

/// A pair's cases judged: the case with the smallest margin among those whose gears
/// mesh (none when no case meshes), the first case with no valid mesh, and the
/// verdict over every case ([`pair_verdict`]).
struct Judged<'a> {
    smallest: Option<&'a Evaluated>,
    no_mesh: Option<&'a Evaluated>,
    verdict: PairVerdict,
}

fn judge(states: &[Evaluated]) -> Judged<'_> {
    Judged {
        smallest: states
            .iter()
            .filter(|e| e.mesh.margin_m.is_finite())
            .min_by(|x, y| x.mesh.margin_m.total_cmp(&y.mesh.margin_m)),
        no_mesh: states.iter().find(|e| e.no_mesh.is_some()),
        verdict: pair_verdict(states),
    }
}

/// A pair's verdict over its cases, in `run`'s words and order of precedence: a case
/// with no valid mesh, then interference (no backlash left), then a margin violated.
fn pair_verdict(states: &[Evaluated]) -> PairVerdict {
    if states.iter().any(|e| e.no_mesh.is_some()) {
        PairVerdict::NoValidMesh
    } else if states
        .iter()
        .any(|e| e.mesh.backlash_exact_m.is_nan() || e.mesh.backlash_exact_m <= 0.0)
    {
        PairVerdict::Interference
    } else if states
        .iter()
        .any(|e| e.mesh.margin_m.is_nan() || e.mesh.margin_m < 0.0)
    {
        PairVerdict::MarginViolated
    } else {
        PairVerdict::Pass
    }
}

/// The verdict line of a pair: PASS or FAIL, the smallest margin (said as
/// interference when the backlash reached zero) and a case with no valid mesh, each
/// with its case.
fn verdict_line(pair: &GearPair, states: &[Evaluated]) -> String {
    let j = judge(states);
    let case = |c: &Case| {
        format!(
            "in case {} (pinion {:.2} °C, wheel {:.2} °C)",
            c.label, c.pinion_c, c.wheel_c
        )
    };
    let mut parts = Vec::new();
    if let Some(e) = j.no_mesh {
        let why = e
            .no_mesh
            .as_ref()
            .map_or(String::new(), |m| format!(": {m}"));
        parts.push(format!("no valid mesh {}{why}", case(&e.case)));
    }
    if let Some(e) = j.smallest {
        let m = &e.mesh;
        let (b_um, least_um) = (m.backlash_exact_m * 1e6, pair.min_backlash_m * 1e6);
        let d = orbitlash::units::decimals_apart(b_um, least_um, 3);
        let fixed = orbitlash::units::fixed;
        parts.push(format!(
            "{} {} µm (backlash {} µm, minimum {} µm) {}",
            if m.backlash_exact_m <= 0.0 {
                "the teeth interfere: margin"
            } else {
                "smallest margin"
            },
            fixed(m.margin_m * 1e6, d),
            fixed(b_um, d),
            fixed(least_um, d),
            case(&e.case)
        ));
    }
    format!(
        "{} {}: {}",
        if j.verdict.passes() { "PASS" } else { "FAIL" },
        pair.name,
        parts.join("; ")
    )
}

pub fn backlash(a: BacklashArgs) -> Result<Outcome> {
    let loaded = super::load_with(a.scenario.as_deref(), &a.sets)?;
    let sc = loaded.scenario();
    if sc.gears.is_empty() {
        bail!("{} has no [[gear_pair]]", loaded.file);
    }
    let n = sc.thermal.network.nodes.len();
    let mut cases = Vec::new();
    for pair in &sc.gears {
        let t_ref_c = k_to_c(pair.reference_temperature_k);
        let housing = a.housing_c.unwrap_or(t_ref_c);
        let mut list = vec![Case {
            label: "assembly".into(),
            pinion_c: t_ref_c,
            wheel_c: t_ref_c,
            housing_c: t_ref_c,
        }];
        let uniform = if a.uniform_c.is_empty() && a.pinion_c.is_none() {
            vec![100.0, -75.0]
        } else {
            a.uniform_c.clone()
        };
        for t in uniform {
            // "uniform" only when the housing shares the gears' temperature
            let housing_c = a.housing_c.unwrap_or(t);
            list.push(Case {
                label: if housing_c == t { "uniform" } else { "gears" }.into(),
                pinion_c: t,
                wheel_c: t,
                housing_c,
            });
        }
        if let (Some(p), Some(w)) = (a.pinion_c, a.wheel_c) {
            list.push(Case {
                label: "given".into(),
                pinion_c: p,
                wheel_c: w,
                housing_c: housing,
            });
        }
        // A state with no valid mesh is a failed verdict (NaN backlash), as in `run`.
        let states: Vec<Evaluated> = list
            .into_iter()
            .map(|case| {
                let temps = temperatures(pair, n, &case);
                let (mesh, no_mesh) = pair.evaluate_or_invalid(&temps);
                Evaluated {
                    case,
                    mesh,
                    no_mesh,
                }
            })
            .collect();
        cases.push((pair, states));
    }
    let pass = cases
        .iter()
        .all(|(_, states)| judge(states).verdict.passes());
    if a.json {
        print_out(&(serde_json::to_string_pretty(&to_json(&sc.name, &cases))? + "\n"))?;
        return Ok(Outcome::from_pass(pass));
    }
    let mut o = String::new();
    for (pair, states) in &cases {
        outln!(o, "{}", verdict_line(pair, states));
    }
    for (pair, states) in &cases {
        let centre = match pair.center {
            CenterDistance::Fixed => "fixed centre distance".to_string(),
            CenterDistance::Housing { .. } => "centre distance follows the housing".to_string(),
        };
        outln!(
            o,
            "{} / {}: {} × {} teeth, m = {} mm, {centre}, minimum allowed {:.3} µm",
            sc.name,
            pair.name,
            pair.gears[0].teeth,
            pair.gears[1].teeth,
            pair.module_m * 1e3,
            pair.min_backlash_m * 1e6
        );
        let mut align = vec![Align::Right; 10];
        align[0] = Align::Left;
        let mut table = table::new(
            &[
                "case",
                "pinion\n°C",
                "wheel\n°C",
                "housing\n°C",
                "exact\nµm",
                "closed form\nµm",
                "paper\nµm",
                "α_w\ndeg",
                "a\nmm",
                "margin\nµm",
            ],
            &align,
        );
        for Evaluated {
            case: c, mesh: m, ..
        } in states
        {
            table.add_row(vec![
                c.label.clone(),
                format!("{:.2}", c.pinion_c),
                format!("{:.2}", c.wheel_c),
                format!("{:.2}", c.housing_c),
                table::number(m.backlash_exact_m * 1e6, 3),
                table::number(m.backlash_closed_form_m * 1e6, 3),
                table::number(m.backlash_paper_m * 1e6, 3),
                table::number(m.pressure_angle_rad.to_degrees(), 4),
                table::number(m.center_distance_m * 1e3, 5),
                table::number(m.margin_m * 1e6, 3),
            ]);
        }
        o += &table::render(&table, "  ");
        outln!(
            o,
            "  exact: smallest normal backlash over a mesh cycle (involute, unequal base pitches);"
        );
        outln!(
            o,
            "  closed form: pitch-averaged; paper: equations (16)–(22) with the corrections documented in src/gear/paper.rs"
        );
    }
    print_out(&o)?;
    Ok(Outcome::from_pass(pass))
}

/// Node temperatures for a case: each gear's nodes at its temperature, the housing node
/// (if the centre distance follows one) at the housing's, everything else at assembly.
fn temperatures(pair: &GearPair, n: usize, c: &Case) -> Vec<f64> {
    let mut temps = vec![pair.reference_temperature_k; n];
    for (g, t) in pair.gears.iter().zip([c.pinion_c, c.wheel_c]) {
        for &i in g.nodes.iter().chain(g.shaft_node.iter()) {
            temps[i] = c_to_k(t);
        }
    }
    if let CenterDistance::Housing { node, .. } = pair.center {
        temps[node] = c_to_k(c.housing_c);
    }
    temps
}

/// `backlash --json`: keys in the order they are declared; documented in the README.
#[derive(serde::Serialize)]
struct BacklashReport<'a> {
    scenario: &'a str,
    pass: bool,
    pairs: Vec<PairReport<'a>>,
}

#[derive(serde::Serialize)]
struct PairReport<'a> {
    name: &'a str,
    /// "pass", "margin_violated", "interference" or "no_valid_mesh": the words of
    /// `run --json` (the worst case's).
    verdict: PairVerdict,
    min_margin_um: f64,
    /// The minimum allowed, µm: the name `run --json` gives it.
    min_backlash_allowed_um: f64,
    /// The same minimum allowed under its first name (in `run --json` this name is the
    /// smallest backlash reached): kept for scripts written against it.
    min_backlash_um: f64,
    cases: Vec<CaseReport<'a>>,
}

#[derive(serde::Serialize)]
struct CaseReport<'a> {
    case: &'a str,
    pinion_c: f64,
    wheel_c: f64,
    housing_c: f64,
    /// Why the gears do not mesh in this case (the mesh quantities are then null);
    /// null when they mesh.
    no_mesh: Option<String>,
    backlash_um: Variants,
    margin_um: f64,
    pressure_angle_deg: f64,
    center_distance_mm: f64,
    contact_ratio: f64,
    /// Pinion, wheel.
    base_radius_mm: [f64; 2],
    base_circle_displacement_um: [f64; 2],
    base_pitch_mm: [f64; 2],
    base_tooth_thickness_mm: [f64; 2],
    coating_um: [f64; 2],
}

#[derive(serde::Serialize)]
struct Variants {
    exact: f64,
    closed_form: f64,
    paper: f64,
}

fn to_json<'a>(name: &'a str, cases: &'a [(&GearPair, Vec<Evaluated>)]) -> BacklashReport<'a> {
    BacklashReport {
        scenario: name,
        pass: cases
            .iter()
            .all(|(_, states)| judge(states).verdict.passes()),
        pairs: cases
            .iter()
            .map(|(pair, states)| {
                let j = judge(states);
                PairReport {
                    name: &pair.name,
                    verdict: j.verdict,
                    // of the cases that mesh: null when none does
                    min_margin_um: j.smallest.map_or(f64::NAN, |e| e.mesh.margin_m * 1e6),
                    min_backlash_allowed_um: pair.min_backlash_m * 1e6,
                    min_backlash_um: pair.min_backlash_m * 1e6,
                    cases: states
                        .iter()
                        .map(|e| {
                            let (c, m) = (&e.case, &e.mesh);
                            let per_gear =
                                |f: fn(&DeformedGear) -> f64| [f(&m.gears[0]), f(&m.gears[1])];
                            CaseReport {
                                case: &c.label,
                                pinion_c: c.pinion_c,
                                wheel_c: c.wheel_c,
                                housing_c: c.housing_c,
                                no_mesh: e.no_mesh.as_ref().map(ToString::to_string),
                                backlash_um: Variants {
                                    exact: m.backlash_exact_m * 1e6,
                                    closed_form: m.backlash_closed_form_m * 1e6,
                                    paper: m.backlash_paper_m * 1e6,
                                },
                                margin_um: m.margin_m * 1e6,
                                pressure_angle_deg: m.pressure_angle_rad.to_degrees(),
                                center_distance_mm: m.center_distance_m * 1e3,
                                contact_ratio: m.contact_ratio,
                                base_radius_mm: per_gear(|g| g.base_radius_m * 1e3),
                                base_circle_displacement_um: per_gear(|g| {
                                    g.base_displacement_m * 1e6
                                }),
                                base_pitch_mm: per_gear(|g| g.base_pitch_m * 1e3),
                                base_tooth_thickness_mm: per_gear(|g| g.base_thickness_m * 1e3),
                                coating_um: per_gear(|g| g.coating_m * 1e6),
                            }
                        })
                        .collect(),
                }
            })
            .collect(),
    }
}

//! `orbitlash check`: validate a scenario and print what can be derived without a run.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use orbitlash::margins::dispersion::{Plan, Sampling};
use orbitlash::orbit::EnvironmentModel;
use orbitlash::spec::scenario::Scenario;
use orbitlash::thermal::analysis::time_constants;

use super::table::{self, Align};
use super::{Loaded, load_with, print_out};

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Change a number of the scenario by its key path (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
}

pub fn check(a: CheckArgs) -> Result<()> {
    let mut o = String::new();
    let loaded = load_with(Some(&a.scenario), &a.sets)?;
    // Dispersions are checked here too, before any margin run would start.
    let plan = super::plan(
        &loaded,
        Sampling::Random,
        1,
        0,
        super::SetsOnDispersed::Allowed,
    )?;
    let sc = loaded.scenario();
    let env = &sc.thermal.environment;
    let warnings = sc.warnings();
    outln!(
        o,
        "{}: valid ({}){}",
        loaded.file,
        sc.name,
        match warnings.len() {
            0 => String::new(),
            n => format!(", {n} warning(s)"),
        }
    );
    for w in &warnings {
        outln!(o, "warning: {w}");
    }
    if !sc.description.is_empty() {
        outln!(o, "  {}", sc.description);
    }
    let period = env.mean_period_s();
    outln!(o, "\norbit");
    for line in env.report() {
        outln!(o, "{line}");
    }

    network_section(&mut o, sc);
    gear_section(&mut o, sc)?;
    dispersions_section(&mut o, &loaded, &plan);
    run_section(&mut o, sc, period);
    print_out(&o)
}

/// "1 conductor", "2 conductors".
fn count(n: usize, what: &str) -> String {
    orbitlash::units::count(n as f64, what)
}

/// "1 load (1 Sun absorber)", "14 loads (6 faces, 8 dissipations)": what a load is differs (a Sun
/// absorber, a face, a dissipation), so the count says which.
fn loads_by_kind(loads: &[orbitlash::thermal::Load]) -> String {
    use orbitlash::thermal::LoadKind as K;
    let mut kinds: Vec<(&str, usize)> = Vec::new();
    for l in loads {
        let k = match l.kind {
            K::Sun { .. } => "Sun absorber",
            K::Albedo { .. } => "albedo absorber",
            K::EarthIr { .. } => "Earth-IR absorber",
            K::Dissipation { .. } => "dissipation",
            K::Face(_) => "face",
        };
        match kinds.iter_mut().find(|(n, _)| *n == k) {
            Some((_, c)) => *c += 1,
            None => kinds.push((k, 1)),
        }
    }
    let parts: Vec<String> = kinds.iter().map(|(k, c)| count(*c, k)).collect();
    if parts.is_empty() {
        count(0, "load")
    } else {
        format!("{} ({})", count(loads.len(), "load"), parts.join(", "))
    }
}

/// The network: element counts, time constants, linear solver, stiffness.
fn network_section(o: &mut String, sc: &Scenario) {
    let net = &sc.thermal.network;
    outln!(o, "\nnetwork");
    outln!(
        o,
        "  {}, {}, {}, {}, {}, {}, {}",
        count(net.nodes.len(), "diffusion node"),
        count(net.boundaries.len(), "boundary node"),
        count(net.conductors.len(), "conductor"),
        count(net.radiators.len(), "radiative conductor"),
        loads_by_kind(&net.loads),
        count(net.heaters.len(), "heater"),
        count(sc.thermal.modes.len(), "mode")
    );
    let temps = net.initial_temperatures_k();
    let boundary: Vec<f64> = net
        .boundaries
        .iter()
        .map(|b| b.temperature_k.at(0.0))
        .collect();
    let tc = time_constants(net, &temps, &boundary);
    // Every node of a small network; the fastest of a large one.
    const LISTED: usize = 12;
    let mut order: Vec<usize> = (0..net.nodes.len()).collect();
    if order.len() > 2 * LISTED {
        order.sort_by(|&a, &b| tc.node_s[a].total_cmp(&tc.node_s[b]));
        order.truncate(LISTED);
        outln!(
            o,
            "  time constants at the initial temperatures (C_i / sum of conductances), the {LISTED} fastest of {} nodes:",
            net.nodes.len()
        );
    } else {
        outln!(
            o,
            "  time constants at the initial temperatures (C_i / sum of conductances):"
        );
    }
    let mut table = table::new(
        &["", "", "", "", ""],
        &[
            Align::Left,
            Align::Left,
            Align::Right,
            Align::Left,
            Align::Right,
        ],
    );
    for (n, t) in order.iter().map(|&i| (&net.nodes[i], tc.node_s[i])) {
        table.add_row(vec![
            n.name.clone(),
            "C =".to_string(),
            format!("{} J/K", orbitlash::units::fixed(n.capacitance_j_per_k, 3)),
            "tau =".to_string(),
            format!("{t:.2} s"),
        ]);
    }
    *o += &table::render(&table, "    ");
    outln!(
        o,
        "  linear systems: {} ({} nodes; solver.linear = \"{}\")",
        sc.solver.linear.resolve(net.nodes.len()).name(),
        net.nodes.len(),
        sc.solver.linear.name()
    );
    outln!(
        o,
        "  eigen time constants: slowest {:.1} s, fastest {:.4} s, stiffness ratio {:.3e}",
        tc.slowest_s,
        tc.fastest_s,
        tc.stiffness_ratio()
    );
}

/// Each gear pair at assembly: centre distance, pressure angle, contact ratio, base
/// dimensions and backlash against its minimum.
fn gear_section(o: &mut String, sc: &Scenario) -> Result<()> {
    let net = &sc.thermal.network;
    for pair in &sc.gears {
        let m = pair
            .evaluate(&vec![pair.reference_temperature_k; net.nodes.len()])
            .map_err(|e| anyhow::anyhow!("gear pair {}: {e}", pair.name))?;
        outln!(
            o,
            "\ngear pair {} at assembly ({:.2} °C)",
            pair.name,
            pair.reference_temperature_k - orbitlash::constants::ZERO_CELSIUS_K
        );
        outln!(
            o,
            "  centre distance {:.4} mm, operating pressure angle {:.4}°, contact ratio {:.3}",
            m.center_distance_m * 1e3,
            m.pressure_angle_rad.to_degrees(),
            m.contact_ratio
        );
        let mut table = table::new(
            &[
                "gear",
                "teeth",
                "r_b mm",
                "p_b mm",
                "s_b mm (coated)",
                "nodes",
            ],
            &[
                Align::Left,
                Align::Right,
                Align::Right,
                Align::Right,
                Align::Right,
                Align::Left,
            ],
        );
        for (g, d) in pair.gears.iter().zip(&m.gears) {
            table.add_row(vec![
                g.name.clone(),
                g.teeth.to_string(),
                format!("{:.6}", d.base_radius_m * 1e3),
                format!("{:.6}", d.base_pitch_m * 1e3),
                format!("{:.6}", d.base_thickness_m * 1e3),
                g.nodes
                    .iter()
                    .map(|&i| net.nodes[i].name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            ]);
        }
        *o += &table::render(&table, "  ");
        outln!(
            o,
            "  normal backlash {:.3} µm, minimum allowed {:.3} µm, margin {:.3} µm",
            m.backlash_exact_m * 1e6,
            pair.min_backlash_m * 1e6,
            m.margin_m * 1e6
        );
    }
    Ok(())
}

/// The dispersions a margins run would draw from.
fn dispersions_section(o: &mut String, loaded: &Loaded, plan: &Plan) {
    if !plan.dispersions.is_empty() {
        outln!(o, "\ndispersions (for `orbitlash margins`)");
        let mut table = table::new(
            &["key path", "nominal", "distribution", "group"],
            &[Align::Left, Align::Right, Align::Left, Align::Left],
        );
        for d in &plan.dispersions {
            table.add_row(vec![
                d.path.clone(),
                orbitlash::units::exact(loaded.model.get(&d.path).unwrap_or(f64::NAN)),
                d.distribution.to_string(),
                d.group.clone().unwrap_or_default(),
            ]);
        }
        *o += &table::render(&table, "  ");
    }
}

/// Run length, solver settings and sensors.
fn run_section(o: &mut String, sc: &Scenario, period: f64) {
    outln!(o, "\nrun");
    outln!(
        o,
        "  duration {:.1} s ({}), CSV every {} s",
        sc.run.duration_s,
        orbitlash::units::orbits(sc.run.duration_s / period, 3),
        sc.run.output_interval_s
    );
    outln!(
        o,
        "  solver tr-bdf2, tolerance {} K, max step {} s, {}",
        sc.solver.tolerance_k,
        sc.solver.max_step_s,
        if sc.solver.adaptive {
            "adaptive"
        } else {
            "fixed step"
        }
    );
    outln!(
        o,
        "  sensors: {}",
        if sc.sensors.is_empty() {
            "none".to_string()
        } else {
            sc.sensors
                .iter()
                .map(|s| {
                    let mut t = s.column.clone();
                    if s.tau_s > 0.0 {
                        t += &format!(" (lag τ {} s)", s.tau_s);
                    }
                    if s.offset_k != 0.0 {
                        t += &format!(" (offset {:+} K)", s.offset_k);
                    }
                    t
                })
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
}

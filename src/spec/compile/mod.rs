//! Spec → validated numeric model. Every check of a scenario lives here (and in the
//! constructors it calls), so that a scenario built from TOML, from `--set` or from a
//! program meets the same invariants with the same error text. One file per domain
//! (`orbit`, `run`, `network`, `loads`, `faces`, `sensors`, `gear`, `names`); `cx` holds
//! the checks of single values; this file puts a scenario together from them.

mod cx;
mod faces;
mod gear;
mod loads;
mod names;
mod network;
mod orbit;
mod run;
mod sensors;

pub use cx::SpecError;
pub use names::MAX_DESCRIPTION_LEN;
pub use orbit::{MAX_PERIOD_S, MIN_PERIOD_S};

use cx::*;
use faces::*;
use gear::*;
use loads::*;
use names::*;
use network::*;
use orbit::*;
use run::*;
use sensors::*;

use std::collections::HashMap;

use super::keys::{ElementKeys, KeyPath, element_keys};
use super::*;
use crate::gear::disc::{BoreFit, DiscMaterial};
use crate::gear::involute::shifted_tooth_thickness;
use crate::gear::strain::StrainLaw;
use crate::gear::{CenterDistance, Coating, Gear, GearPair, MAX_GEAR_NODES};
use crate::orbit::dated::{DatedEnvironment, Shadow};
use crate::orbit::tle::{TleError, TleOrbit};
use crate::orbit::{CircularEnvironment, Environment, EnvironmentModel, Incidence, Orbit, Profile};
use crate::spec::quantity::{Quantity, Rule};
use crate::spec::scenario::SolverSettings;
use crate::spec::scenario::{
    Bindings, MAX_DURATION_S, MIN_DURATION_S, RunControl, Scenario, Sensor, SensorTarget,
};
use crate::thermal::iteration::{
    DENSE_MAX_NODES, LinearSolver, SPARSE_MAX_FLOPS, direct_fill_estimate,
};
use crate::thermal::{
    BoundaryNode, Conductor, DiffusionNode, Heater, Load, LoadKind, Mode, Network, NodeRef,
    Radiator, ThermalModel, When,
};
use crate::units::{SECONDS_PER_DAY, exact, num};

// ---------------------------------------------------------------- validation

/// The built-in boundary node.
const SPACE: &str = "space";

/// Validates `raw` into the numeric model.
pub fn compile(raw: ScenarioSpec) -> Result<Scenario, SpecError> {
    let cx = &Cx;
    let keys = element_keys(&raw);
    check_names(cx, &raw)?;

    let (mut environment, space_sink_k) = environment(cx, &raw.orbit, raw.environment)?;
    let period_s = environment.mean_period_s();
    let view_factor_default = match &environment {
        Environment::Circular(c) => c.orbit.earth_view_factor(),
        Environment::Dated(d) => d.mean_view_factor(),
    };
    let run = run_control(cx, &raw.run, period_s)?;
    if let Environment::Dated(d) = &mut environment {
        d.set_horizon_s(run.duration_s)
            .map_err(|m| cx.err(&KeyPath::new("orbit").key("tle"), m))?;
    }
    let solver = solver_settings(cx, &raw.solver)?;

    let (table, nodes, boundaries) =
        nodes_and_boundaries(cx, &keys, raw.node, raw.boundary, space_sink_k)?;
    let diffusion = |p: &KeyPath, name: &str| table.diffusion(cx, p, name);
    let (conductors, radiators) = links(cx, &keys, &table, &raw.conductor, &raw.radiation)?;
    // Modes before loads, which may refer to them.
    let modes = modes(cx, &keys, raw.mode)?;
    let sections = LoadSections {
        sun: raw.sun,
        albedo: raw.albedo,
        earth_ir: raw.earth_ir,
        dissipation: raw.dissipation,
    };
    let (loads, mut bindings) = loads(cx, &keys, &table, sections, &modes, view_factor_default)?;
    let heaters = heaters(cx, &keys, &table, raw.heater)?;
    let (mut loads, mut radiators) = (loads, radiators);
    // Each face's key and node, for the sensors that read a face.
    let face_nodes: Vec<(String, String)> = keys
        .face
        .iter()
        .zip(&raw.face)
        .map(|(k, f)| (k.clone(), f.node.clone()))
        .collect();
    bindings.face = faces(
        cx,
        &keys,
        &table,
        raw.attitude,
        raw.face,
        &mut loads,
        &mut radiators,
    )?;

    // Gear pairs.
    let mut gears = Vec::new();
    for (i, g) in raw.gear_pair.into_iter().enumerate() {
        let p = KeyPath::new("gear_pair").elem(i, &keys.gear_pair[i]);
        let pair = gear_pair(cx, &p, g, i, &nodes, &diffusion)?;
        if gears.iter().any(|x: &GearPair| x.name == pair.name) {
            return Err(cx.err(
                &KeyPath::new("gear_pair").at(i).key("name"),
                format!("gear pair `{}` is defined twice", pair.name),
            ));
        }
        gears.push(pair);
    }

    // Sensors (after the gear pairs they may name).
    let sensors = sensors(
        cx,
        raw.sensor,
        &keys.sensor,
        &gears,
        &face_nodes,
        &diffusion,
    )?;
    let recording = recording_format(cx, raw.recording, &environment)?;
    columns_read_once(cx, &sensors, &keys.sensor, &recording)?;

    let network = Network {
        nodes,
        boundaries,
        conductors,
        radiators,
        loads,
        heaters,
    };
    // An explicit direct solver must fit the network.
    let sp = KeyPath::new("solver");
    let n = network.nodes.len();
    match solver.linear {
        LinearSolver::Dense if n > DENSE_MAX_NODES => {
            return Err(cx.err(
                &sp.key("linear"),
                format!(
                    "\"dense\" takes 16 n² bytes ({:.1} GB) and O(n³) per factorisation for {n} nodes; it is limited to {DENSE_MAX_NODES} nodes: use \"iterative\" or \"auto\"",
                    16.0 * (n * n) as f64 / 1e9
                ),
            ));
        }
        LinearSolver::Sparse => {
            let (fill, flops) = direct_fill_estimate(&crate::thermal::Compiled::new(&network));
            if flops > SPARSE_MAX_FLOPS {
                return Err(cx.err(
                    &sp.key("linear"),
                    format!(
                        "the sparse LU of this network would fill in to about {} entries and take about {} operations per factorisation (the limit is {}): use \"iterative\" or \"auto\"",
                        num(fill as f64),
                        num(flops),
                        num(SPARSE_MAX_FLOPS)
                    ),
                ));
            }
        }
        _ => {}
    }

    Ok(Scenario {
        gears,
        bindings,
        name: raw.scenario.name,
        description: raw.scenario.description,
        thermal: ThermalModel {
            environment,
            network,
            modes,
        },
        run,
        solver,
        sensors,
        recording,
    })
}

/// The checks of single values, shared with the fast parameter writes of
/// `model::Model` so that a value written by path meets the compiler's checks with its
/// error text.
pub(crate) mod check {
    use super::*;

    /// `v` checked as a value of quantity `q`, with the compiler's error text.
    pub fn value(q: &Quantity, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        Cx.quantity(q, path, v)
    }

    /// A heater's band: `on_k < off_k` (the error is at `off_k`).
    pub fn heater_band(off_path: &KeyPath, on_k: f64, off_k: f64) -> Result<(), SpecError> {
        if on_k >= off_k {
            return Err(Cx.err(
                off_path,
                format!("must be above on_k ({on_k} K): the heater switches on when the sensor falls to on_k and off when it rises to off_k"),
            ));
        }
        Ok(())
    }

    /// Gear pair `index` of `spec` compiled again against the nodes of `network` (its
    /// other parts unchanged).
    pub fn gear_pair_again(
        spec: &ScenarioSpec,
        index: usize,
        key: &str,
        network: &Network,
    ) -> Result<GearPair, SpecError> {
        let diffusion = |p: &KeyPath, name: &str| -> Result<usize, SpecError> {
            network
                .nodes
                .iter()
                .position(|n| n.name == name)
                .ok_or_else(|| Cx.err(p, format!("unknown node `{name}`")))
        };
        let p = KeyPath::new("gear_pair").elem(index, key);
        gear_pair(
            &Cx,
            &p,
            spec.gear_pair[index].clone(),
            index,
            &network.nodes,
            &diffusion,
        )
    }
}

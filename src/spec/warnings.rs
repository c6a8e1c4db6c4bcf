//! The warnings of a valid scenario: likely mistakes (`check` and `run` print them).

use crate::spec::keys::key_segment;
use crate::spec::registry;
use crate::spec::scenario::{CELSIUS_AS_KELVIN_BELOW_K, Scenario, Warning, fixed_step_advice};

impl Scenario {
    /// Likely mistakes: a node with no path to a boundary (its temperature can run
    /// away), a fixed step longer than the fastest node's time constant, temperatures
    /// that look like °C typed as kelvin. O(nodes + links).
    pub fn warnings(&self) -> Vec<Warning> {
        use crate::thermal::analysis::{node_time_constants_s, unanchored_nodes};
        let net = &self.thermal.network;
        let mut w = Vec::new();
        let node_key =
            |i: usize, key: &str| format!("node.{}.{key}", key_segment(&net.nodes[i].name));
        let loose: Vec<usize> = unanchored_nodes(net)
            .iter()
            .enumerate()
            .filter_map(|(i, &u)| u.then_some(i))
            .collect();
        if let Some(&first) = loose.first() {
            let names: Vec<&str> = loose
                .iter()
                .take(8)
                .map(|&i| net.nodes[i].name.as_str())
                .collect();
            w.push(Warning {
                key: node_key(first, "name"),
                message: format!(
                    "{} node(s) have no conductive or radiative path to a boundary (space or a [[boundary]]): {}{}; their temperature can run away under any load",
                    loose.len(),
                    names.join(", "),
                    if loose.len() > names.len() { ", …" } else { "" }
                ),
            });
        }
        if let crate::orbit::Environment::Dated(d) = &self.thermal.environment {
            let year = sgp4::chrono::Datelike::year(&d.orbit.start_utc);
            let (lo, hi) = crate::orbit::sun::STATED_YEARS;
            if !(lo..=hi).contains(&year) {
                w.push(Warning {
                    key: "orbit.start_utc".into(),
                    message: format!(
                        "is in {year}: the Sun's position (the Astronomical Almanac's low-precision formulas) is stated to 0.01° for {lo} … {hi} only; beyond, its error grows slowly"
                    ),
                });
            }
            let days = d.orbit.epoch_age_days();
            if days.abs() > crate::orbit::tle::EPOCH_WARN_DAYS {
                w.push(Warning {
                    key: "orbit.start_utc".into(),
                    message: format!(
                        "starts {:.1} days from the TLE's epoch; a LEO TLE's along-track error grows to tens of km within a few days (β and eclipse lengths stay close, the minute of each eclipse drifts): a TLE nearer the start is better",
                        days.abs()
                    ),
                });
            }
        }
        // A resolved spin needs steps shorter than its turn.
        let spin = net.loads.iter().find_map(|l| match l.kind {
            crate::thermal::LoadKind::Face(crate::orbit::faces::Face {
                attitude:
                    crate::orbit::faces::Attitude::Spin {
                        rate_rad_per_s,
                        averaged: false,
                        ..
                    },
                ..
            }) if rate_rad_per_s != 0.0 => Some(2.0 * std::f64::consts::PI / rate_rad_per_s.abs()),
            _ => None,
        });
        if let Some(turn_s) = spin.filter(|t| self.solver.max_step_s > t / 8.0) {
            w.push(Warning {
                key: format!("attitude.{}", registry::SPIN_RATE_DEG_PER_S.name),
                message: format!(
                    "one turn takes {turn_s:.1} s but steps may be {} s long: the faces' loads are sampled, not followed; set solver.max_step_s ≤ {:.2} s or spin_averaged = true",
                    self.solver.max_step_s,
                    turn_s / 8.0
                ),
            });
        }
        if !self.solver.adaptive {
            let temps = net.initial_temperatures_k();
            let tau = node_time_constants_s(&self.thermal, &temps, 0.0);
            if let Some((i, &t)) = tau
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(b.1))
                .filter(|(_, t)| self.solver.max_step_s > **t)
            {
                w.push(Warning {
                    key: format!("solver.{}", registry::MAX_STEP_S.name),
                    message: format!(
                        "the fixed step of {} s (adaptive = false) exceeds the time constant of node {} ({t:.3e} s): its transients are not resolved; {}",
                        self.solver.max_step_s,
                        net.nodes[i].name,
                        fixed_step_advice(t)
                    ),
                });
            }
        }
        let celsius = |key: String, v: f64, w: &mut Vec<Warning>| {
            if v < CELSIUS_AS_KELVIN_BELOW_K {
                w.push(Warning {
                    key,
                    message: format!(
                        "{v} K ({:.2} °C) looks like a Celsius value typed as kelvin; {v} °C is {:.2} K",
                        v - crate::constants::ZERO_CELSIUS_K,
                        v + crate::constants::ZERO_CELSIUS_K
                    ),
                });
            }
        };
        for (i, n) in net.nodes.iter().enumerate() {
            celsius(
                node_key(i, registry::INITIAL_TEMPERATURE_K.name),
                n.initial_temperature_k,
                &mut w,
            );
        }
        for b in net.boundaries.iter().skip(1) {
            let (lo, _) = b.temperature_k.range();
            if (5.0..60.0).contains(&lo) {
                w.push(Warning {
                    key: format!(
                        "boundary.{}.{}",
                        key_segment(&b.name),
                        registry::BOUNDARY_TEMPERATURE_K.name
                    ),
                    message: format!(
                        "{lo} K ({:.2} °C) looks like a Celsius value typed as kelvin (cryogenic shrouds aside); {lo} °C is {:.2} K",
                        lo - crate::constants::ZERO_CELSIUS_K,
                        lo + crate::constants::ZERO_CELSIUS_K
                    ),
                });
            }
        }
        for h in &net.heaters {
            let k = format!("heater.{}", key_segment(&h.name));
            celsius(format!("{k}.{}", registry::ON_K.name), h.on_k, &mut w);
            celsius(format!("{k}.{}", registry::OFF_K.name), h.off_k, &mut w);
        }
        for g in &self.gears {
            celsius(
                format!(
                    "gear_pair.{}.{}",
                    key_segment(&g.name),
                    registry::REFERENCE_TEMPERATURE_K.name
                ),
                g.reference_temperature_k,
                &mut w,
            );
        }
        w
    }
}

//! A validated scenario: the thermal model, how long to run it, solver settings and
//! the sensors that name recording columns. Built by `io::scenario_toml`; everything
//! downstream may rely on it being physically valid.

use crate::gear::GearPair;
use crate::sim::SolverSettings;
use crate::thermal::ThermalModel;

#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    pub name: String,
    pub description: String,
    pub thermal: ThermalModel,
    pub run: RunControl,
    pub solver: SolverSettings,
    pub sensors: Vec<Sensor>,
    /// Gear pairs whose backlash is evaluated at every step.
    pub gears: Vec<GearPair>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct RunControl {
    /// How long to simulate, s.
    pub duration_s: f64,
    /// Interval between rows of the CSV export, s.
    pub output_interval_s: f64,
}

/// A recording column and what it measures.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensor {
    pub column: String,
    pub target: SensorTarget,
}

#[derive(Debug, Clone, PartialEq)]
pub enum SensorTarget {
    /// A diffusion node's temperature.
    Node(usize),
    /// A derived quantity, by name (see [`DERIVED_QUANTITIES`]).
    Derived(String),
}

/// Derived quantities a sensor may name.
pub const DERIVED_QUANTITIES: [&str; 1] = ["backlash_um"];

impl Scenario {
    /// Orbital period, s.
    pub fn period_s(&self) -> f64 {
        self.thermal.environment.orbit.period_s()
    }

    /// The same scenario run for `orbits` orbits.
    pub fn with_orbits(mut self, orbits: f64) -> Scenario {
        self.run.duration_s = orbits * self.period_s();
        self
    }
}

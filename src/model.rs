//! A scenario as a built model: the spec as the user wrote it and the validated numeric
//! model compiled from it, kept in step. Every number is read and written by its key
//! path ([`crate::spec::keys`]); a write, or an added element, goes through the same
//! compiler as a TOML file, so it meets the same checks with the same error text, and
//! everything that depends on the changed value (a view factor on the altitude, a run
//! length in orbits on the period, a tooth thickness on its thinning) follows.

use crate::scenario::Scenario;
use crate::spec::keys::{ElementKeys, element_keys};
use crate::spec::params::{self, Param, ParamError};
use crate::spec::{
    AlbedoSpec, DissipationSpec, EarthIrSpec, HeaterSpec, ScenarioSpec, SensorSpec, SpecError,
    SunSpec, compile,
};

/// Why a change to a model was refused; the model is left as it was.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// The key path leads to no number, or the value is not one.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The changed scenario is not valid.
    #[error(transparent)]
    Invalid(#[from] SpecError),
}

/// A load to add to a model.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadSpec {
    Sun(SunSpec),
    Albedo(AlbedoSpec),
    EarthIr(EarthIrSpec),
    Dissipation(DissipationSpec),
}

#[derive(Debug, Clone)]
pub struct Model {
    spec: ScenarioSpec,
    keys: ElementKeys,
    scenario: Scenario,
}

impl Model {
    /// Compiles `spec` (see [`crate::spec::compile`]).
    pub fn new(spec: ScenarioSpec) -> Result<Model, SpecError> {
        let scenario = compile(spec.clone())?;
        Ok(Model {
            keys: element_keys(&spec),
            spec,
            scenario,
        })
    }

    pub fn spec(&self) -> &ScenarioSpec {
        &self.spec
    }

    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Every number by key path, with unit and range.
    pub fn params(&self) -> Vec<Param> {
        params::params(&self.spec)
    }

    /// The number at `path`.
    pub fn get(&self, path: &str) -> Result<f64, ParamError> {
        params::get(&self.spec, path)
    }

    /// Writes one number; on any error the model is unchanged.
    pub fn set(&mut self, path: &str, value: f64) -> Result<(), ModelError> {
        self.set_many(&[(path, value)])
    }

    /// Writes several numbers and compiles once; on any error the model is unchanged
    /// and the error is that of the first offending key.
    pub fn set_many<K: AsRef<str>>(&mut self, changes: &[(K, f64)]) -> Result<(), ModelError> {
        let mut spec = self.spec.clone();
        for (path, value) in changes {
            params::set_with_keys(&mut spec, &self.keys, path.as_ref(), *value)?;
        }
        self.replace(spec)
    }

    /// Changes the spec with `edit` (any change: values, added or removed elements) and
    /// compiles it; on an error the model is unchanged.
    pub fn modify(&mut self, edit: impl FnOnce(&mut ScenarioSpec)) -> Result<(), ModelError> {
        let mut spec = self.spec.clone();
        edit(&mut spec);
        self.replace(spec)
    }

    /// Adds a thermostat heater.
    pub fn add_heater(&mut self, heater: HeaterSpec) -> Result<(), ModelError> {
        self.modify(|s| s.heater.push(heater))
    }

    /// Adds a load.
    pub fn add_load(&mut self, load: LoadSpec) -> Result<(), ModelError> {
        self.modify(|s| match load {
            LoadSpec::Sun(l) => s.sun.push(l),
            LoadSpec::Albedo(l) => s.albedo.push(l),
            LoadSpec::EarthIr(l) => s.earth_ir.push(l),
            LoadSpec::Dissipation(l) => s.dissipation.push(l),
        })
    }

    /// Adds a sensor (a recording column and what it measures).
    pub fn add_sensor(&mut self, sensor: SensorSpec) -> Result<(), ModelError> {
        self.modify(|s| s.sensor.push(sensor))
    }

    fn replace(&mut self, spec: ScenarioSpec) -> Result<(), ModelError> {
        let scenario = compile(spec.clone())?;
        self.keys = element_keys(&spec);
        self.spec = spec;
        self.scenario = scenario;
        Ok(())
    }
}

//! A scenario as a built model: the spec as the user wrote it and the validated numeric
//! model compiled from it, kept in step. Every number is read and written by its key
//! path ([`crate::spec::keys`]); a write, or an added element, goes through the same
//! compiler as a TOML file, so it meets the same checks with the same error text, and
//! everything that depends on the changed value (a view factor on the altitude, a run
//! length in orbits on the period, a tooth thickness on its thinning) follows.

use crate::spec::keys::{ElementKeys, element_keys};
use crate::spec::registry::{self, Fast, Param, ParamError, ParamRef, Sub};
use crate::spec::scenario::Scenario;
use crate::spec::{
    AlbedoSpec, DissipationSpec, EarthIrSpec, HeaterSpec, ProfileSpec, ScenarioSpec, SensorSpec,
    SpecError, SunSpec, compile,
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

/// Why an `[[input]]` could not follow its channel: the recording lacks it, or the model
/// refused what its readings make.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InputError {
    /// The recording has no such column.
    #[error("{file}: no column `{column}`, which [[input]] drives `{drives}` from")]
    NoColumn {
        file: String,
        column: String,
        drives: String,
    },
    /// The column has no reading.
    #[error("{file}: column `{column}` has no readings")]
    NoReadings { file: String, column: String },
    /// The model refused the profile (or eclipses) the readings make.
    #[error("[[input]] {drives} from `{column}`: {source}")]
    Refused {
        /// `sunlit`, or the driven key path in backquotes.
        drives: String,
        column: String,
        #[source]
        source: ModelError,
    },
    /// What the model refused comes from one reading: where it is in the recording.
    #[error("{file}:{line}: the reading {reading} of `{column}`: {refused}")]
    AtReading {
        file: String,
        /// The reading's line (CSV) or message number (MCAP), 1-based.
        line: u64,
        column: String,
        reading: f64,
        refused: Box<InputError>,
    },
}

impl InputError {
    /// The reading (its index among the readings given to [`Model::follow_input`])
    /// whose value the model refused, when the refusal names one (`….value[k]`).
    pub fn reading_index(&self) -> Option<usize> {
        use crate::spec::keys::Seg;
        let InputError::Refused {
            source: ModelError::Invalid(e),
            ..
        } = self
        else {
            return None;
        };
        match e.key.0.as_slice() {
            [.., Seg::K("value"), Seg::I(k)] => Some(*k),
            _ => None,
        }
    }
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
    /// Which elements the model has, and how they are written: changed by
    /// [`Model::modify`] (and what calls it), not by writing values. A [`ParamId`] of
    /// another shape is resolved again.
    shape: u64,
}

static SHAPES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

fn new_shape() -> u64 {
    SHAPES.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl Model {
    /// Compiles `spec` (see [`crate::spec::compile`]).
    pub fn new(spec: ScenarioSpec) -> Result<Model, SpecError> {
        let scenario = compile(spec.clone())?;
        let model = Model {
            keys: element_keys(&spec),
            spec,
            scenario,
            shape: new_shape(),
        };
        model.check_uncertain()?;
        model.check_inputs()?;
        Ok(model)
    }

    /// Each `[[input]]` drives a boundary's temperature or a dissipation's power that
    /// the scenario has, with finite scale and offset.
    fn check_inputs(&self) -> Result<(), SpecError> {
        use crate::spec::keys::KeyPath;
        for (i, inp) in self.spec.input.iter().enumerate() {
            let at = KeyPath::new("input").at(i);
            if inp.column.trim().is_empty() {
                return Err(SpecError {
                    key: at.key("column"),
                    message: "must not be empty".into(),
                    also: None,
                });
            }
            if inp.drives == "sunlit" {
                if self.spec.orbit.tle.is_none() {
                    return Err(SpecError {
                        key: at.key("drives"),
                        message: "\"sunlit\" needs a dated scenario ([orbit] tle and start_utc)"
                            .into(),
                        also: None,
                    });
                }
                if !inp.below.is_some_and(f64::is_finite) {
                    return Err(SpecError {
                        key: at.key("below"),
                        message: "\"sunlit\" needs `below`: the reading under which the spacecraft is in eclipse".into(),
                        also: None,
                    });
                }
            } else if inp.below.is_some() {
                return Err(SpecError {
                    key: at.key("below"),
                    message: "applies to drives = \"sunlit\" only".into(),
                    also: None,
                });
            } else if !input_target(&self.spec, &inp.drives) {
                return Err(SpecError {
                    key: at.key("drives"),
                    message: format!(
                        "`{}` is not a boundary's temperature or a dissipation's power of this scenario (`boundary.<name>.temperature_k`, `dissipation.<name>.power_w`)",
                        inp.drives
                    ),
                    also: None,
                });
            }
            // A column is one thing: the time, an ignored column or one input's.
            let fmt = &self.scenario.recording;
            if inp.column == fmt.time_column || fmt.ignore_columns.contains(&inp.column) {
                return Err(SpecError {
                    key: at.key("column"),
                    message: format!(
                        "`{}` is the recording's {}; an input reads a column of readings",
                        inp.column,
                        if inp.column == fmt.time_column {
                            "time column"
                        } else {
                            "ignored column ([recording] ignore_columns)"
                        }
                    ),
                    also: None,
                });
            }
            if let Some(j) = (0..i).find(|&j| self.spec.input[j].drives == inp.drives) {
                return Err(SpecError {
                    key: at.key("drives"),
                    message: format!(
                        "`{}` is driven by two inputs; one input drives a target",
                        inp.drives
                    ),
                    also: Some(KeyPath::new("input").at(j).key("drives")),
                });
            }
            for (key, v) in [("scale", inp.scale), ("offset", inp.offset)] {
                if v.is_some_and(|v| !v.is_finite()) {
                    return Err(SpecError {
                        key: at.key(key),
                        message: "must be a finite number".into(),
                        also: None,
                    });
                }
            }
        }
        Ok(())
    }

    /// Makes `[[input]]` number `i` follow `readings` (time s, value) of its channel:
    /// the driven profile becomes the table of `scale` × reading + `offset` (linear
    /// between readings), or, for `sunlit`, the eclipse windows of the readings below
    /// `below`. Returns what it did, in a line.
    pub fn follow_input(
        &mut self,
        i: usize,
        readings: &[(f64, f64)],
    ) -> Result<String, InputError> {
        let inp = self.spec.input[i].clone();
        let (scale, offset) = (inp.scale.unwrap_or(1.0), inp.offset.unwrap_or(0.0));
        let time_s: Vec<f64> = readings.iter().map(|r| r.0).collect();
        let value: Vec<f64> = readings.iter().map(|r| scale * r.1 + offset).collect();
        let n = value.len();
        if inp.drives == "sunlit" {
            let below = inp.below.unwrap_or(f64::NAN);
            let period =
                crate::orbit::EnvironmentModel::mean_period_s(&self.scenario.thermal.environment);
            let windows = eclipse_windows(&time_s, &value, below, period);
            let count = windows.len();
            self.modify(|s| s.orbit.eclipses_s = Some(windows))
                .map_err(|source| InputError::Refused {
                    drives: "sunlit".into(),
                    column: inp.column.clone(),
                    source,
                })?;
            return Ok(format!(
                "eclipses follow `{}` below {below} ({n} readings, {count} eclipses)",
                inp.column
            ));
        }
        let table = ProfileSpec::Table(crate::spec::TableSpec {
            time_s: Some(time_s),
            time_days: None,
            value,
        });
        self.modify(|s| {
            if let Some(p) = input_target_mut(s, &inp.drives) {
                *p = table;
            }
        })
        .map_err(|source| InputError::Refused {
            drives: format!("`{}`", inp.drives),
            column: inp.column.clone(),
            source,
        })?;
        Ok(format!(
            "`{}` follows `{}` ({n} readings × {scale} + {offset})",
            inp.drives, inp.column
        ))
    }

    /// Each `[[uncertain]]` names a number of the model, with finite bounds min < max
    /// that the model accepts at both ends; no `[[uncertain]]` or `[[dispersion]]`
    /// names how a recording is read.
    fn check_uncertain(&self) -> Result<(), SpecError> {
        use crate::spec::keys::KeyPath;
        // a dispersed number is a calibration candidate of `diagnose` too: neither may
        // be how a recording is read (the rest of a dispersion is `Plan::new`'s check)
        for (i, d) in self.spec.dispersion.iter().enumerate() {
            if let Some(why) = self
                .param(&d.path)
                .ok()
                .and_then(|id| id.not_of_the_model())
            {
                return Err(SpecError {
                    also: None,
                    key: KeyPath::new("dispersion").at(i).key("path"),
                    message: why,
                });
            }
        }
        for (i, u) in self.spec.uncertain.iter().enumerate() {
            let at = KeyPath::new("uncertain").at(i);
            let err = |key: &'static str, message: String| SpecError {
                also: None,
                key: at.key(key),
                message,
            };
            self.get(&u.path).map_err(|e| err("path", e.to_string()))?;
            let id = self
                .param(&u.path)
                .map_err(|e| err("path", e.to_string()))?;
            if let Some(why) = id.not_of_the_model() {
                return Err(err("path", why));
            }
            for (key, v) in [("min", u.min), ("max", u.max)] {
                if !v.is_finite() {
                    return Err(err(
                        key,
                        format!("the bound must be a finite number (got {v})"),
                    ));
                }
            }
            if u.min >= u.max {
                return Err(err(
                    "max",
                    format!("the bounds must have min < max (got {} … {})", u.min, u.max),
                ));
            }
            for (key, v) in [("min", u.min), ("max", u.max)] {
                let mut m = self.clone();
                m.set(&u.path, v)
                    .map_err(|e| err(key, format!("`{}` cannot be {v}: {e}", u.path)))?;
            }
        }
        Ok(())
    }

    pub fn spec(&self) -> &ScenarioSpec {
        &self.spec
    }

    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Every number by key path, with unit and range.
    pub fn params(&self) -> Vec<Param> {
        registry::params(&self.spec)
    }

    /// The number at `path`.
    pub fn get(&self, path: &str) -> Result<f64, ParamError> {
        registry::get(&self.spec, path)
    }

    /// Writes one number; on any error the model is unchanged.
    pub fn set(&mut self, path: &str, value: f64) -> Result<(), ModelError> {
        self.set_many(&[(path, value)])
    }

    /// Writes several numbers and compiles once; on any error the model is unchanged
    /// and the error is that of the first offending key.
    pub fn set_many<K: AsRef<str>>(&mut self, changes: &[(K, f64)]) -> Result<(), ModelError> {
        let spec = written(&self.spec, &self.keys, changes)?;
        self.replace(spec)
    }

    /// Changes the spec with `edit` (any change: values, added or removed elements) and
    /// compiles it; on an error the model is unchanged.
    pub fn modify(&mut self, edit: impl FnOnce(&mut ScenarioSpec)) -> Result<(), ModelError> {
        let mut spec = self.spec.clone();
        edit(&mut spec);
        self.replace(spec)?;
        self.shape = new_shape();
        Ok(())
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

    /// Compiles `spec` with `changes` (key path, value) written into it first: the
    /// model a file holding those values gives, also where the file's own values do
    /// not compile (a run longer than its orbit lasts, shortened by the change).
    pub fn with_changes<K: AsRef<str>>(
        spec: ScenarioSpec,
        changes: &[(K, f64)],
    ) -> Result<Model, ModelError> {
        Ok(Model::new(written(&spec, &element_keys(&spec), changes)?)?)
    }

    fn replace(&mut self, spec: ScenarioSpec) -> Result<(), ModelError> {
        let scenario = compile(spec.clone())?;
        self.keys = element_keys(&spec);
        self.spec = spec;
        self.scenario = scenario;
        Ok(())
    }
}

/// A parameter resolved once ([`Model::param`]) and written many times
/// ([`Model::set_param`]): the values Monte Carlo samples disperse and `diagnose`
/// fits. A number whose row has a fast write (capacitances, initial temperatures,
/// conductances, radiative and load areas and optical properties, faces, heater
/// settings, sensor lags and offsets, albedo, Earth IR, sink, β, solar flux and
/// dissipations when constant) is written straight into the spec and the compiled model
/// after the compiler's own check of the value; a gear-pair value recompiles that pair;
/// any other recompiles the scenario (see `spec::registry`).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamId {
    path: String,
    canonical: String,
    at: ParamRef,
    row: &'static registry::Row,
    /// The model shape it was resolved for.
    shape: u64,
}

impl ParamId {
    /// The path as it was given.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The path in one spelling (`node."housing" . capacitance_j_per_k` and
    /// `node.housing.capacitance_j_per_k` give the same), for messages and comparisons.
    pub fn canonical_path(&self) -> String {
        self.canonical.clone()
    }

    /// True when both name the same number of the scenario, however spelled.
    pub fn same_number(&self, other: &ParamId) -> bool {
        self.canonical == other.canonical
    }

    /// The row, element and place it names.
    pub fn at(&self) -> ParamRef {
        self.at
    }

    /// Why it cannot be varied in a simulation, if it cannot: a number of how a
    /// recording is read (`[recording] time_offset_s`) acts when the file is read, not
    /// on the model, so calibrating or dispersing it would change nothing; a gear
    /// pair's smallest allowed backlash is the verdict's limit, not a property of the
    /// hardware: `margins` judges every sample against one limit.
    pub fn not_of_the_model(&self) -> Option<String> {
        if std::ptr::eq(self.row.field, &registry::MIN_BACKLASH_UM) {
            return Some(format!(
                "`{}` is the acceptance limit every sample is judged against, not a number of the hardware: it cannot be calibrated or dispersed (set it in the file or with --set)",
                self.canonical
            ));
        }
        (self.row.section == registry::Section::Recording).then(|| {
            format!(
                "`{}` is how a recording is read, not a number of the model: it cannot be calibrated or dispersed (set it in the file or with --set)",
                self.canonical
            )
        })
    }
}

impl Model {
    /// Resolves `path` for [`Model::set_param`]: a number the scenario has.
    pub fn param(&self, path: &str) -> Result<ParamId, ParamError> {
        let at = registry::resolve(&self.spec, &self.keys, path)?;
        self.get(path)?; // it has a value
        Ok(self.id(at, path.to_string()))
    }

    /// The parameter at `at` (a row, element and place of this model's spec), for
    /// programs that name numbers by row rather than by path.
    pub fn param_at(&self, at: ParamRef) -> Result<ParamId, ParamError> {
        let path = at.key_path(&self.keys).to_string();
        registry::value(&self.spec, at).ok_or_else(|| ParamError {
            key: path.clone(),
            message: "no such number in this scenario".into(),
        })?;
        Ok(self.id(at, path))
    }

    /// The number of `row` (a registry row) in the element with key `element` (ignored
    /// for a table), at `sub`.
    pub fn param_of(&self, row: usize, element: &str, sub: Sub) -> Result<ParamId, ParamError> {
        let section = registry::rows()[row].section;
        let e = match section.keys(&self.keys) {
            Some(list) => list
                .iter()
                .position(|k| k == element)
                .ok_or_else(|| ParamError {
                    key: registry::key_path(row, Some((0, element)), sub).to_string(),
                    message: "no such number in this scenario".into(),
                })?,
            None => 0,
        };
        self.param_at(ParamRef {
            row,
            element: e,
            sub,
        })
    }

    /// The key of the element `at` is in ("" for a table).
    pub fn element_key(&self, at: ParamRef) -> &str {
        at.row()
            .section
            .keys(&self.keys)
            .map_or("", |k| k[at.element].as_str())
    }

    fn id(&self, at: ParamRef, path: String) -> ParamId {
        ParamId {
            canonical: at.key_path(&self.keys).to_string(),
            path,
            at,
            row: at.row(),
            shape: self.shape,
        }
    }

    /// The value of a resolved parameter.
    pub fn value(&self, id: &ParamId) -> Option<f64> {
        registry::value(&self.spec, id.at)
    }

    /// Writes the value of a resolved parameter (see [`ParamId`]); on an error the
    /// model is unchanged.
    pub fn set_param(&mut self, id: &ParamId, value: f64) -> Result<(), ModelError> {
        match id.row.fast {
            // the common case, without allocating
            Fast::Direct(f) if id.shape == self.shape && id.at.sub == Sub::One => {
                self.write_one(id, value, f)
            }
            _ => self.set_params(&[(id, value)]),
        }
    }

    /// Writes several resolved parameters at once, as [`Model::set_many`] does (each
    /// value is judged beside the others' new values: a heater's `on_k` and `off_k`
    /// moved together), through the fast writes when every one has one; on an error
    /// the model is unchanged.
    pub fn set_params(&mut self, values: &[(&ParamId, f64)]) -> Result<(), ModelError> {
        let mut at = Vec::with_capacity(values.len());
        for (id, v) in values {
            let r = if id.shape == self.shape {
                id.at
            } else {
                // resolved on a model with other elements: its indices may not hold here
                registry::resolve(&self.spec, &self.keys, &id.path)?
            };
            at.push((r, *v, id.path.as_str()));
        }
        let direct = |r: &ParamRef| matches!(r.row().fast, Fast::Direct(_)) && r.sub == Sub::One;
        if at.iter().all(|(r, ..)| direct(r)) {
            self.write_direct(&at)
        } else if at
            .iter()
            .all(|(r, ..)| matches!(r.row().fast, Fast::GearPair))
        {
            self.write_gear_pairs(&at)
        } else {
            let mut spec = self.spec.clone();
            for (r, v, path) in &at {
                write(&mut spec, *r, *v, path)?;
            }
            self.replace(spec)
        }
    }

    /// The fast writes: each value checked by its quantity with the compiler's text,
    /// all written into the spec, then each row's compiled value made again from it.
    fn write_direct(&mut self, at: &[(ParamRef, f64, &str)]) -> Result<(), ModelError> {
        for (r, v, _) in at {
            // the compiler's check; the key path is made only for its error
            if !r.quantity().accepts(*v) {
                crate::spec::check::value(r.quantity(), &r.key_path(&self.keys), *v)?;
            }
        }
        let mut saved = Vec::with_capacity(at.len());
        for (r, v, path) in at {
            match registry::swap(&mut self.spec, r.row(), *r, *v) {
                Ok(s) => saved.push(s),
                Err(message) => {
                    self.put_back(&at[..saved.len()], &saved, 0);
                    return Err(ModelError::Param(ParamError {
                        key: path.to_string(),
                        message: message.to_string(),
                    }));
                }
            }
        }
        for (k, (r, ..)) in at.iter().enumerate() {
            let Fast::Direct(f) = r.row().fast else {
                unreachable!("checked")
            };
            if let Err(e) = f(&self.spec, &self.keys, &mut self.scenario, r.element) {
                self.put_back(at, &saved, k);
                return Err(e.into());
            }
        }
        Ok(())
    }

    /// [`Model::write_direct`] of one value.
    fn write_one(&mut self, id: &ParamId, v: f64, f: registry::FastFn) -> Result<(), ModelError> {
        let (r, quantity) = (id.at, id.row.field.quantity);
        if !quantity.accepts(v) {
            crate::spec::check::value(quantity, &r.key_path(&self.keys), v)?;
        }
        let saved = registry::swap(&mut self.spec, id.row, r, v).map_err(|message| ParamError {
            key: id.path.clone(),
            message: message.to_string(),
        })?;
        if let Err(e) = f(&self.spec, &self.keys, &mut self.scenario, r.element) {
            registry::restore(&mut self.spec, r, saved);
            return Err(e.into());
        }
        Ok(())
    }

    /// Puts `saved` back into the spec and makes the compiled values of the first
    /// `made` writes again from it.
    fn put_back(&mut self, at: &[(ParamRef, f64, &str)], saved: &[registry::Saved], made: usize) {
        for ((r, ..), s) in at.iter().zip(saved).rev() {
            registry::restore(&mut self.spec, *r, *s);
        }
        for (r, ..) in &at[..made] {
            if let Fast::Direct(f) = r.row().fast {
                f(&self.spec, &self.keys, &mut self.scenario, r.element)
                    .expect("the model's own values are valid");
            }
        }
    }

    /// Writes numbers of gear pairs and recompiles those pairs only (their checks tie
    /// many numbers together); on an error the pairs are as before.
    fn write_gear_pairs(&mut self, at: &[(ParamRef, f64, &str)]) -> Result<(), ModelError> {
        let mut pairs: Vec<usize> = at.iter().map(|(r, ..)| r.element).collect();
        pairs.sort_unstable();
        pairs.dedup();
        let old: Vec<_> = pairs
            .iter()
            .map(|&g| self.spec.gear_pair[g].clone())
            .collect();
        let restore = |m: &mut Model| {
            for (&g, o) in pairs.iter().zip(&old) {
                m.spec.gear_pair[g] = o.clone();
            }
        };
        for (r, v, path) in at {
            if let Err(e) = write(&mut self.spec, *r, *v, path) {
                restore(self);
                return Err(e);
            }
        }
        let mut made = Vec::with_capacity(pairs.len());
        for &g in &pairs {
            match crate::spec::check::gear_pair_again(
                &self.spec,
                g,
                &self.keys.gear_pair[g],
                &self.scenario.thermal.network,
            ) {
                Ok(pair) => made.push(pair),
                Err(e) => {
                    restore(self);
                    return Err(e.into());
                }
            }
        }
        for (g, pair) in pairs.into_iter().zip(made) {
            self.scenario.gears[g] = pair;
        }
        Ok(())
    }
}

/// `spec` (whose elements have `keys`) with `changes` (key path, value) written into
/// it, each path resolved in `spec` as it was.
fn written<K: AsRef<str>>(
    spec: &ScenarioSpec,
    keys: &ElementKeys,
    changes: &[(K, f64)],
) -> Result<ScenarioSpec, ModelError> {
    let mut changed = spec.clone();
    for (path, value) in changes {
        let at = registry::resolve(spec, keys, path.as_ref())?;
        write(&mut changed, at, *value, path.as_ref())?;
    }
    Ok(changed)
}

/// Writes `value` at `at` of `spec`, the error naming `path` as given.
fn write(spec: &mut ScenarioSpec, at: ParamRef, value: f64, path: &str) -> Result<(), ModelError> {
    registry::write(spec, at, value).map_err(|e| {
        ModelError::Param(ParamError {
            key: path.to_string(),
            message: e.to_string(),
        })
    })
}

/// The profile an `[[input]]`'s `drives` names (a boundary's temperature or a
/// dissipation's power), if the scenario has it.
fn input_target_mut<'s>(spec: &'s mut ScenarioSpec, drives: &str) -> Option<&'s mut ProfileSpec> {
    let keys = element_keys(spec);
    let (row, e) = registry::locate(&keys, drives)?;
    if std::ptr::eq(row.field, &registry::BOUNDARY_TEMPERATURE_K) {
        spec.boundary.get_mut(e).map(|b| &mut b.temperature_k)
    } else if std::ptr::eq(row.field, &registry::DISSIPATION_POWER_W) {
        spec.dissipation.get_mut(e).map(|d| &mut d.power_w)
    } else {
        None
    }
}

fn input_target(spec: &ScenarioSpec, drives: &str) -> bool {
    input_target_mut(&mut spec.clone(), drives).is_some()
}

/// Longest step between two readings that an eclipse edge is placed inside, s; a
/// longer gap (a ground segment's fill, no pass) is bridged from the orbit's period.
pub const INPUT_MAX_GAP_S: f64 = 600.0;

/// Eclipse windows from readings `value` at `time_s` (dark below `below`): each change
/// of state halfway between the two readings around it. Across a gap longer than
/// [`INPUT_MAX_GAP_S`] the readings say nothing, and the last whole eclipse before it
/// is repeated every `period_s`. A recording that starts (ends) dark starts (ends) an
/// eclipse at its first (last) reading.
fn eclipse_windows(time_s: &[f64], value: &[f64], below: f64, period_s: f64) -> Vec<Vec<f64>> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut entry: Option<f64> = None;
    let mut template: Option<(f64, f64)> = None;
    let mut last: Option<(f64, bool)> = None;
    for (&t, &v) in time_s.iter().zip(value) {
        let dark = v < below;
        match last {
            None if dark => {
                entry = Some(if t <= INPUT_MAX_GAP_S { 0.0 } else { t });
            }
            None => {}
            Some((t0, _)) if t - t0 > INPUT_MAX_GAP_S => {
                // close what is open at the gap's start, bridge the gap, reopen after
                if let Some(a) = entry.take() {
                    out.push((a, t0));
                }
                if let Some((a, b)) = template {
                    let mut k = 1.0;
                    while a + k * period_s < t {
                        out.push((a + k * period_s, b + k * period_s));
                        k += 1.0;
                    }
                }
                if dark {
                    entry = Some(t);
                }
            }
            Some((t0, d0)) if d0 != dark => {
                let mid = 0.5 * (t0 + t);
                if dark {
                    entry = Some(mid);
                } else if let Some(a) = entry.take() {
                    out.push((a, mid));
                    template = Some((a, mid));
                }
            }
            _ => {}
        }
        last = Some((t, dark));
    }
    if let (Some(a), Some((t, _))) = (entry, last) {
        out.push((a, t));
    }
    // in order, overlaps (a bridged eclipse meeting a measured one) merged
    out.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for (a, b) in out {
        match merged.last_mut() {
            Some(l) if a <= l.1 => l.1 = l.1.max(b),
            _ => merged.push((a, b)),
        }
    }
    merged.into_iter().map(|(a, b)| vec![a, b]).collect()
}

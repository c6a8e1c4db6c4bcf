//! The vocabulary of `shared/spec/physics.md` §6 as model extensions: every effect, on
//! every node, conductor, load, gear or channel the scenario has, is a [`Candidate`]:
//! the scenario with the effect added (a real element of the scenario: a heater with a
//! thermostat, a dissipation with a schedule, albedo and Earth-IR loads, a centre
//! distance that follows a node, α(T), an elastic bore fit, a sensor's lag or offset, a
//! scaled number) and its physical parameters, written through key paths.

use serde::Serialize;

use crate::spec::keys::ElementKeys;
use crate::spec::model::Model;
use crate::spec::model::ParamId;
use crate::spec::registry::{self, Field, Param, ParamError, Section, Sub};
use crate::spec::{
    AlbedoSpec, BoreFitName, CenterDistanceSpec, DissipationSpec, EarthIrSpec, Follows, HeaterSpec,
    ProfileSpec, ScenarioSpec, Schedule,
};

/// The vocabulary, one row an effect: its variant, its id, its kind and where its
/// candidates are made (the generator function it is tried with). Adding an effect is
/// a row here, its generator and its row in `docs/vocabulary.md` (a test checks the
/// document against the rows).
macro_rules! vocabulary {
    ($($(#[$doc:meta])* $variant:ident = $id:literal, $kind:ident, $scope:expr;)*) => {
        /// The effect ids of `physics.md` §6 and our own.
        #[derive(Debug, Clone, Copy, PartialEq, Eq)]
        pub enum Effect {
            $($(#[$doc])* $variant,)*
        }

        impl Effect {
            /// Every effect, in the order its candidates are made on an element.
            pub const ALL: &'static [Effect] = &[$(Effect::$variant,)*];

            pub fn id(self) -> &'static str {
                match self {
                    $(Effect::$variant => $id,)*
                }
            }

            pub fn kind(self) -> EffectKind {
                match self {
                    $(Effect::$variant => EffectKind::$kind,)*
                }
            }

            /// Where its candidates are made.
            fn scope(self) -> Scope {
                match self {
                    $(Effect::$variant => $scope,)*
                }
            }
        }
    };
}

vocabulary! {
    EarthAlbedoIr = "earth_albedo_ir", Physics, Scope::Node(|g, n| g.earth_albedo_ir(n).into_iter().collect());
    HeaterThermostat = "heater_thermostat", Physics, Scope::Node(|g, n| g.heater_thermostat(n).into_iter().collect());
    InternalDissipation = "internal_dissipation", Physics, Scope::Node(|g, n| g.internal_dissipation(n));
    HousingExpansion = "housing_expansion", Physics, Scope::Node(|g, n| g.housing_expansion(n));
    /// A dissipation switched on at a time (a payload, a mode change): node, power and
    /// time fitted.
    SwitchedDissipation = "switched_dissipation", Physics, Scope::Node(|g, n| g.switched_dissipation(n).into_iter().collect());
    CteTemperature = "cte_temperature", Physics, Scope::Pair(|g, p| g.cte_temperature(p).into_iter().collect());
    CteScale = "cte_scale", Calibration, Scope::Pair(|g, p| g.cte_scale(p).into_iter().collect());
    BoreFit = "bore_fit", Physics, Scope::Pair(|g, p| g.bore_fits(p));
    SensorLag = "sensor_lag", Sensor, Scope::TemperatureChannel(|g, c| g.sensor_lag(c).into_iter().collect());
    SensorOffset = "sensor_offset", Sensor, Scope::TemperatureChannel(|g, c| g.sensor_offset(c).into_iter().collect());
    /// Made with the other scale calibrations and the declared numbers, in the order of
    /// the model's parameters.
    CapacitanceScale = "capacitance_scale", Calibration, Scope::Model(|g| g.calibrations());
    EmissivityScale = "emissivity_scale", Calibration, Scope::Shared;
    AbsorptivityScale = "absorptivity_scale", Calibration, Scope::Shared;
    ConductanceScale = "conductance_scale", Calibration, Scope::Shared;
    UncertainParameter = "uncertain_parameter", Calibration, Scope::Shared;
    /// Every face's and Sun load's absorptivity scaled by one factor: the level of
    /// absorbed sunlight an unknown attitude sets.
    SunlightScale = "sunlight_scale", Calibration, Scope::Model(|g| g.sunlight_scale().into_iter().collect());
    /// Every face's emissivity and every radiative coupling to space scaled by one
    /// factor.
    InfraredScale = "infrared_scale", Calibration, Scope::Model(|g| g.infrared_scale().into_iter().collect());
}

/// Where an effect's candidates are made: its generator, tried on each element of a
/// kind.
#[derive(Clone, Copy)]
enum Scope {
    /// On every diffusion node (its index).
    Node(fn(&Generator<'_>, usize) -> Vec<Candidate>),
    /// On every gear pair (its index).
    Pair(fn(&Generator<'_>, usize) -> Vec<Candidate>),
    /// On every temperature channel (its name).
    TemperatureChannel(fn(&Generator<'_>, &str) -> Vec<Candidate>),
    /// Once, on the whole model.
    Model(fn(&Generator<'_>) -> Vec<Candidate>),
    /// Made by another effect's generator.
    Shared,
}

/// Serialised as its id (`heater_thermostat`).
impl Serialize for Effect {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.id())
    }
}

impl std::fmt::Display for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.id())
    }
}

/// An effect equals its id (`Effect::BoreFit == "bore_fit"`).
impl PartialEq<&str> for Effect {
    fn eq(&self, other: &&str) -> bool {
        self.id() == *other
    }
}

/// What an effect is: physics the model left out, a sensor's own behaviour, or a
/// calibration of a number the model has. Serialised as "physics", "sensor",
/// "calibration".
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    Physics,
    Sensor,
    Calibration,
}

impl EffectKind {
    pub fn as_str(self) -> &'static str {
        match self {
            EffectKind::Physics => "physics",
            EffectKind::Sensor => "sensor",
            EffectKind::Calibration => "calibration",
        }
    }
}

impl std::fmt::Display for EffectKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

impl Effect {
    /// What its fitted parameters are, where they are not the physical numbers of the
    /// same name (shown beside them in reports and in `corrected.toml`).
    pub fn parameters_note(self) -> Option<&'static str> {
        match self {
            Effect::EarthAlbedoIr => Some(
                "albedo and earth_ir_w_per_m2 are effective values, as if on the node's \
                 whole Sun-facing and space-facing areas; corrected.toml holds the areas that \
                 give them at the scenario's own albedo and Earth infrared",
            ),
            _ => None,
        }
    }

    pub fn from_id(id: &str) -> Option<Effect> {
        Effect::ALL.iter().copied().find(|e| e.id() == id)
    }
}

/// One fitted parameter of a candidate, in report units.
#[derive(Debug, Clone)]
pub struct ParamDef {
    /// Report name (`power_w`, `on_c`, `scale`, …).
    pub name: &'static str,
    pub lower: f64,
    pub upper: f64,
    /// Finite-difference step.
    pub step: f64,
    /// A prior toward a value, (centre, standard deviation): a calibration number stays
    /// near nominal unless the data move it.
    pub prior: Option<(f64, f64)>,
    /// What a fit that ends on the lower bound means ([`Floor`]).
    pub floor: Floor,
}

/// What the lower bound of a parameter's range is to a fit that ends on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Floor {
    /// The end of the range: a fit pushed onto it wants to go further, a stand-in.
    Bound,
    /// A value the effect really takes: a bore fit of no interference still closes by
    /// differential expansion; a switched load of no power is the effect absent.
    Value,
    /// A value the effect takes alone, a stand-in in a fit with other findings (as it
    /// enters beside them, and in the final joint fit): a thermostat's band of 0.1 K
    /// is a near-proportional heater, which a lone controller may be, but when other
    /// findings are fitted with it and it still wants no band it is heat that follows
    /// the node's temperature, taking what the model's own error leaves (on
    /// FUNcube-1, 4.1 W that pulled an absorptivity found at × 0.80 to × 0.45;
    /// `docs/validation.md`).
    ValueAlone,
}

/// A number of the model written as a linear function of the parameters:
/// value = constant + Σ coefficient · θ\[index\].
#[derive(Debug, Clone)]
pub struct Setter {
    pub number: Number,
    pub constant: f64,
    pub terms: Vec<(usize, f64)>,
}

/// A number a setter writes: a registry row, the element by its key (the element may
/// be one an effect adds, at another position in a model with several effects) and the
/// place in its slot. Resolved once per model ([`Number::resolve`]), written through
/// the registry's fast writes.
#[derive(Debug, Clone, PartialEq)]
pub struct Number {
    pub row: usize,
    pub element: String,
    pub sub: Sub,
}

impl Number {
    /// Number `field` (in `table`) of the element with key `element` of `section`, when
    /// `m` has it.
    fn of(
        m: &Model,
        section: Section,
        table: &[&str],
        field: &'static Field,
        element: &str,
    ) -> Option<Number> {
        let n = Number {
            row: registry::row_of(section, table, field),
            element: element.to_string(),
            sub: Sub::One,
        };
        n.resolve(m).ok().map(|_| n)
    }

    /// The number a resolved parameter of `m` names.
    fn of_param(m: &Model, id: &ParamId) -> Number {
        let at = id.at();
        Number {
            row: at.row,
            element: m.element_key(at).to_string(),
            sub: at.sub,
        }
    }

    /// This number in model `m`.
    pub fn resolve(&self, m: &Model) -> Result<ParamId, ParamError> {
        m.param_of(self.row, &self.element, self.sub)
    }

    /// Its key path.
    pub fn path(&self) -> String {
        let keyed = registry::rows()[self.row]
            .section
            .keys(&Default::default())
            .is_some();
        registry::key_path(
            self.row,
            keyed.then_some((0, self.element.as_str())),
            self.sub,
        )
        .to_string()
    }
}

impl ParamDef {
    pub fn new(name: &'static str, lower: f64, upper: f64, step: f64) -> ParamDef {
        ParamDef {
            name,
            lower,
            upper,
            step,
            prior: None,
            floor: Floor::Bound,
        }
    }

    /// The same, its lower bound a value the effect takes ([`Floor::Value`]).
    pub fn floored(self) -> ParamDef {
        ParamDef {
            floor: Floor::Value,
            ..self
        }
    }

    /// The same, its lower bound a value the effect takes alone only
    /// ([`Floor::ValueAlone`]).
    pub fn floored_alone(self) -> ParamDef {
        ParamDef {
            floor: Floor::ValueAlone,
            ..self
        }
    }
}

impl Setter {
    /// The number set to `scale` × parameter `index`.
    pub fn scaled(number: Number, index: usize, scale: f64) -> Setter {
        Setter {
            number,
            constant: 0.0,
            terms: vec![(index, scale)],
        }
    }

    /// Its value for parameters `theta`.
    pub fn value(&self, theta: &[f64]) -> f64 {
        self.constant + self.terms.iter().map(|&(i, c)| c * theta[i]).sum::<f64>()
    }
}

/// What a candidate acts on. The report names it by the keys [`Target::node`] and its
/// siblings give (`node`, `channel`, …), as a [`super::Finding`]'s JSON does.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// A diffusion node (Earth albedo and IR, a heater).
    Node(String),
    /// A dissipation on a node, on a schedule: `always`, `sunlit`, `eclipse` or a mode.
    Scheduled { node: String, schedule: String },
    /// A gear pair whose centre distance follows a node.
    NodeAndPair { node: String, gear_pair: String },
    /// A gear pair's material.
    Pair(String),
    /// A gear's bore (`<pair>.pinion`), fitted to its shaft node.
    Bore {
        gear_pair: String,
        gear: String,
        shaft: String,
    },
    /// A recording channel's sensor.
    Channel(String),
    /// A sun load.
    Load(String),
    /// A conductor or radiative coupling.
    Conductor(String),
    /// A face (its absorptivity or emissivity).
    Face(String),
    /// A number the user declared uncertain (`[[uncertain]]`, `[[dispersion]]`), by its
    /// key path.
    Path(String),
    /// Every face (and Sun load, or coupling to space) at once: a global scale.
    Spacecraft,
}

impl Serialize for Target {
    /// The keys it has, in [`Target::fields`]' order (flattened into a finding).
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let fields = self.fields();
        let mut m = s.serialize_map(Some(fields.iter().filter(|f| f.1.is_some()).count()))?;
        for (k, v) in fields {
            if let Some(v) = v {
                m.serialize_entry(k, &v)?;
            }
        }
        m.end()
    }
}

impl Target {
    pub fn node(&self) -> Option<String> {
        match self {
            Target::Node(n)
            | Target::Scheduled { node: n, .. }
            | Target::NodeAndPair { node: n, .. }
            | Target::Bore { shaft: n, .. } => Some(n.clone()),
            _ => None,
        }
    }
    pub fn channel(&self) -> Option<String> {
        match self {
            Target::Channel(c) => Some(c.clone()),
            _ => None,
        }
    }
    pub fn conductor(&self) -> Option<String> {
        match self {
            Target::Conductor(c) => Some(c.clone()),
            _ => None,
        }
    }
    pub fn load(&self) -> Option<String> {
        match self {
            Target::Load(l) => Some(l.clone()),
            _ => None,
        }
    }
    pub fn face(&self) -> Option<String> {
        match self {
            Target::Face(f) => Some(f.clone()),
            _ => None,
        }
    }
    pub fn path(&self) -> Option<String> {
        match self {
            Target::Path(p) => Some(p.clone()),
            _ => None,
        }
    }
    pub fn gear_pair(&self) -> Option<String> {
        match self {
            Target::NodeAndPair { gear_pair: p, .. }
            | Target::Pair(p)
            | Target::Bore { gear_pair: p, .. } => Some(p.clone()),
            _ => None,
        }
    }
    pub fn gear(&self) -> Option<String> {
        match self {
            Target::Bore { gear, .. } => Some(gear.clone()),
            _ => None,
        }
    }
    pub fn schedule(&self) -> Option<String> {
        match self {
            Target::Scheduled { schedule, .. } => Some(schedule.clone()),
            _ => None,
        }
    }

    /// The keys it is reported by, in order, with the element each names.
    pub fn fields(&self) -> [(&'static str, Option<String>); 9] {
        [
            ("node", self.node()),
            ("channel", self.channel()),
            ("conductor", self.conductor()),
            ("load", self.load()),
            ("face", self.face()),
            ("path", self.path()),
            ("gear_pair", self.gear_pair()),
            ("gear", self.gear()),
            ("schedule", self.schedule()),
        ]
    }

    /// The element a label names: the node, channel, conductor, load, gear or gear
    /// pair, the first of these it has.
    fn named(&self) -> String {
        [
            self.node(),
            self.channel(),
            self.conductor(),
            self.load(),
            self.face(),
            self.path(),
            self.gear(),
            self.gear_pair(),
        ]
        .into_iter()
        .flatten()
        .next()
        .unwrap_or_else(|| {
            if *self == Target::Spacecraft {
                "the spacecraft".into()
            } else {
                String::new()
            }
        })
    }
}

/// An effect on one target, ready to be fitted.
#[derive(Clone)]
pub struct Candidate {
    pub effect: Effect,
    pub target: Target,
    pub params: Vec<ParamDef>,
    pub setters: Vec<Setter>,
    /// Start points for the cheap ranking (the best one starts the fit).
    pub starts: Vec<Vec<f64>>,
    /// Parameters at which the effect vanishes (the baseline), when there are such:
    /// the ranking then also projects the residual onto the line from there through
    /// each start point (a one-step linearised fit).
    pub null: Option<Vec<f64>>,
    /// The elements the effect adds to the scenario (none for a change of existing
    /// numbers); applied in order to build a model with several effects.
    pub edits: Vec<Edit>,
    /// How many of its best ranked points it is fitted from (1: the best only). More
    /// than one where the cost is not smooth in the parameters (a thermostat's set
    /// points move its switchings in steps) and a local minimum is likely.
    pub multi_start: usize,
    /// Points of a coarse global stage evaluated when the candidate is fitted (not when
    /// it is ranked): its best `multi_start − 1` start the fit besides the best ranked
    /// point.
    pub grid: Vec<Vec<f64>>,
}

/// A change of the scenario's elements.
pub type Edit = std::sync::Arc<dyn Fn(&mut ScenarioSpec) + Send + Sync>;

impl Candidate {
    /// `effect` on `target`, adding `edit` to the scenario; no parameters yet.
    fn new(effect: Effect, target: Target, edit: Option<Edit>) -> Candidate {
        Candidate {
            effect,
            target,
            params: Vec::new(),
            setters: Vec::new(),
            starts: Vec::new(),
            null: None,
            edits: edit.into_iter().collect(),
            multi_start: 1,
            grid: Vec::new(),
        }
    }

    /// A short label: `heater_thermostat on housing`.
    pub fn label(&self) -> String {
        let on = self.target.named();
        match self.target.schedule() {
            Some(s) => format!("{} on {on} ({s})", self.effect.id()),
            None => format!("{} on {on}", self.effect.id()),
        }
    }

    /// The key-path values for parameters `theta`.
    pub fn values(&self, theta: &[f64]) -> Vec<(String, f64)> {
        self.setters
            .iter()
            .map(|s| (s.number.path(), s.value(theta)))
            .collect()
    }

    /// The parameters as the report gives them, each a linear combination of the
    /// fitted ones (a row of J): the fitted ones as they are, but a heater's
    /// `hysteresis_k`, which is reported as `off_c` = `on_c` + `hysteresis_k`.
    pub(crate) fn report_rows(&self) -> Vec<(String, Vec<f64>)> {
        let k = self.params.len();
        let unit = |i: usize| (0..k).map(|j| f64::from(u8::from(i == j))).collect();
        let mut rows: Vec<(String, Vec<f64>)> = Vec::with_capacity(k);
        for (i, p) in self.params.iter().enumerate() {
            if self.effect == Effect::HeaterThermostat && p.name == "hysteresis_k" {
                let on = self.params.iter().position(|q| q.name == "on_c");
                let mut row: Vec<f64> = unit(i);
                if let Some(on) = on {
                    row[on] = 1.0;
                }
                rows.push(("off_c".into(), row));
            } else {
                rows.push((p.name.to_string(), unit(i)));
            }
        }
        rows
    }

    /// Parameters as the report gives them ([`Candidate::report_rows`]): name, value
    /// and standard error (from the fitted parameters' covariance `cov`, NaN without).
    pub fn report_params(
        &self,
        theta: &[f64],
        cov: Option<&[Vec<f64>]>,
    ) -> Vec<(String, f64, f64)> {
        let cov_of =
            |a: &[f64], b: &[f64]| cov.map_or(f64::NAN, |c| bilinear(a, |i, j| c[i][j], b));
        self.report_rows()
            .into_iter()
            .map(|(name, row)| {
                let v = row.iter().zip(theta).map(|(a, t)| a * t).sum();
                // NaN without a covariance (NaN.max(0.0) would be 0: "± 0")
                let var = cov_of(&row, &row);
                let se = if var.is_nan() {
                    var
                } else {
                    var.max(0.0).sqrt()
                };
                (name, v, se)
            })
            .collect()
    }

    /// The reported parameters' names and their correlations (from the fitted
    /// parameters' covariance `cov`; `None` where a standard error is zero or not
    /// finite), in the order of [`Candidate::report_params`].
    pub fn report_correlation(
        &self,
        cov: Option<&[Vec<f64>]>,
    ) -> (Vec<String>, Vec<Vec<Option<f64>>>) {
        let rows = self.report_rows();
        let cv = |a: &[f64], b: &[f64]| cov.map_or(f64::NAN, |c| bilinear(a, |i, j| c[i][j], b));
        let se: Vec<f64> = rows.iter().map(|(_, r)| cv(r, r).max(0.0).sqrt()).collect();
        let corr = rows
            .iter()
            .enumerate()
            .map(|(i, (_, a))| {
                rows.iter()
                    .enumerate()
                    .map(|(j, (_, b))| {
                        let r = if i == j {
                            1.0
                        } else {
                            cv(a, b) / (se[i] * se[j])
                        };
                        (se[i] > 0.0 && se[j] > 0.0 && r.is_finite()).then_some(r)
                    })
                    .collect()
            })
            .collect();
        (rows.into_iter().map(|(n, _)| n).collect(), corr)
    }
}

/// aᵀ C b (C's entry (i, j) by `c`) over the nonzero coefficients only (a
/// covariance's other entries may be NaN where a parameter is not determined).
pub(crate) fn bilinear(a: &[f64], c: impl Fn(usize, usize) -> f64, b: &[f64]) -> f64 {
    let mut s = 0.0;
    for (i, &ai) in a.iter().enumerate().filter(|(_, x)| **x != 0.0) {
        for (j, &bj) in b.iter().enumerate().filter(|(_, x)| **x != 0.0) {
            s += ai * c(i, j) * bj;
        }
    }
    s
}

/// What the data say before any fit, used to start candidates that a cost surface
/// alone would not find: per diffusion node, the baseline temperature (K) at which a
/// warming residual starts in the cold phase (a thermostat's set point).
#[derive(Debug, Clone, Default)]
pub struct Hints {
    pub heater_on_k: Vec<Option<f64>>,
}

/// The calibration set of `model`, taken out of `cands` (the vocabulary's candidates),
/// each parameter with its prior toward nominal: the numbers the user declared
/// uncertain (`[[uncertain]]`, `[[dispersion]]`; prior sd a quarter of the range), and
/// for a model with faces (a flight model, whose attitude and coatings set its level
/// of absorbed sunlight) the global sunlight scale (sd 25 %) and infrared scale (sd
/// 15 %) and the thermal masses of its two largest nodes (sd 30 %). Returns the set and
/// its nominal parameters.
///
/// A number the user declared is fitted on its own and nothing else writes it: the
/// global scales leave it out (they scale every other face, [`Generator::global_scale`]),
/// and a candidate of that one number (a mass scale beside a declared capacitance, a
/// face's α scale beside its declared α) is neither in the set nor searched later: it
/// would overwrite the declared number, which then stayed at nominal whatever the data
/// said (its interval came from its prior alone).
pub fn calibration_set(model: &Model, cands: &mut Vec<Candidate>) -> (Vec<Candidate>, Vec<f64>) {
    let spec = model.spec();
    let mut largest: Vec<(f64, &str)> = spec
        .node
        .iter()
        .map(|n| (n.capacitance_j_per_k, n.name.as_str()))
        .collect();
    largest.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(b.1)));
    let masses: Vec<String> = largest.iter().take(2).map(|(_, n)| n.to_string()).collect();
    let faces = !spec.face.is_empty();
    let sd_of = |c: &Candidate| -> Option<f64> {
        match (c.effect, &c.target) {
            (Effect::UncertainParameter, _) => Some(0.25 * (c.params[0].upper - c.params[0].lower)),
            (Effect::SunlightScale, _) if faces => Some(0.25),
            (Effect::InfraredScale, _) if faces => Some(0.15),
            (Effect::CapacitanceScale, Target::Node(n)) if faces && masses.contains(n) => Some(0.3),
            _ => None,
        }
    };
    let mut set = Vec::new();
    let mut nominal = Vec::new();
    let mut rest = Vec::new();
    for mut c in cands.drain(..) {
        match (sd_of(&c), c.null.clone()) {
            (Some(sd), Some(null)) if c.params.len() == 1 => {
                c.params[0].prior = Some((null[0], sd));
                nominal.push(null[0]);
                set.push(c);
            }
            _ => rest.push(c),
        }
    }
    let declared: Vec<Number> = set
        .iter()
        .filter(|c| c.effect == Effect::UncertainParameter)
        .flat_map(|c| c.setters.iter().map(|s| s.number.clone()))
        .collect();
    // a candidate of one number the calibration fits already (a mass scale beside a
    // declared capacitance, a face's α scale beside its declared α) would overwrite it
    let owns_declared = |c: &Candidate| {
        c.effect != Effect::UncertainParameter
            && c.setters.len() == 1
            && declared.contains(&c.setters[0].number)
    };
    rest.retain(|c| !owns_declared(c));
    *cands = rest;
    let (set, nominal): (Vec<Candidate>, Vec<f64>) = set
        .into_iter()
        .zip(nominal)
        .filter(|(c, _)| !owns_declared(c))
        .unzip();
    (set, nominal)
}

/// A switched dissipation's window lasts until this time, s (beyond any recording).
const SWITCHED_UNTIL_S: f64 = 1e9;

/// A switched dissipation is fitted from its best ranked points, this many: each start
/// time is a basin of its own.
const SWITCH_STARTS: usize = 3;

/// A thermostat is fitted from its best ranked points, this many: one long on-period
/// and several short cycles are separate basins of its cost (measured in
/// `docs/performance.md`).
pub const HEATER_STARTS: usize = 3;

/// The thermostat candidates of `cands` started again from `hints` (what the
/// calibrated model's residual says, where the first came from the baseline's): each
/// replaced by its node's candidate from `hints`, and one added for a node that had none
/// (none found in the baseline's residual); a node `hints` gives no start keeps its own.
pub fn rehint_thermostats(model: &Model, cands: &mut Vec<Candidate>, hints: &Hints) {
    let g = Generator::new(model, hints);
    for (ni, node) in model.spec().node.iter().enumerate() {
        let Some(fresh) = g.heater_thermostat(ni) else {
            continue;
        };
        let own = |c: &Candidate| {
            c.effect == Effect::HeaterThermostat
                && matches!(&c.target, Target::Node(n) if *n == node.name)
        };
        match cands.iter_mut().find(|c| own(c)) {
            Some(c) => *c = fresh,
            None => cands.push(fresh),
        }
    }
}

/// Every candidate of the vocabulary on every element of `model` that the recording's
/// `channels` (sensor columns) can see, in a fixed order: per node, per gear pair, per
/// temperature channel, then on the whole model; on each element, the effects of that
/// scope in the vocabulary's order.
pub fn candidates(model: &Model, channels: &[(String, bool)], hints: &Hints) -> Vec<Candidate> {
    let g = Generator::new(model, hints);
    let spec = model.spec();
    let scopes: Vec<Scope> = Effect::ALL.iter().map(|e| e.scope()).collect();
    let mut out = Vec::new();
    for ni in 0..spec.node.len() {
        for s in &scopes {
            if let Scope::Node(make) = s {
                out.extend(make(&g, ni));
            }
        }
    }
    for gi in 0..spec.gear_pair.len() {
        for s in &scopes {
            if let Scope::Pair(make) = s {
                out.extend(make(&g, gi));
            }
        }
    }
    for (col, _) in channels.iter().filter(|(_, is_temp)| *is_temp) {
        for s in &scopes {
            if let Scope::TemperatureChannel(make) = s {
                out.extend(make(&g, col));
            }
        }
    }
    for s in &scopes {
        if let Scope::Model(make) = s {
            out.extend(make(&g));
        }
    }
    out
}

/// Builds the candidates of one model: one method per effect (or per pair of effects
/// built from the same facts).
struct Generator<'a> {
    model: &'a Model,
    spec: &'a ScenarioSpec,
    /// What the data say before any fit (thermostat set points).
    hints: &'a Hints,
    /// The nodes of every gear body.
    gear_nodes: Vec<&'a str>,
}

impl<'a> Generator<'a> {
    fn new(model: &'a Model, hints: &'a Hints) -> Generator<'a> {
        let spec = model.spec();
        let gear_nodes = spec
            .gear_pair
            .iter()
            .flat_map(|g| g.pinion.nodes.iter().chain(&g.wheel.nodes))
            .map(|s| s.as_str())
            .collect();
        Generator {
            model,
            spec,
            hints,
            gear_nodes,
        }
    }

    /// The model with `edit` applied (None: the model refuses it).
    fn with(&self, edit: &Edit) -> Option<Model> {
        let mut m = self.model.clone();
        m.modify(|s| edit(s)).ok().map(|_| m)
    }

    /// Earth albedo and IR on node `n`, referred to the areas the node already shows
    /// the Sun and space (or 0.01 m² where it shows neither).
    fn earth_albedo_ir(&self, ni: usize) -> Option<Candidate> {
        let spec = self.spec;
        let n = spec.node[ni].name.as_str();
        // A node with a face has its Earth loads from the face's geometry: more Earth
        // on it is its attitude or its optics (the calibration's scales, the face's
        // absorptivity), not a load left out; fitted, it stands in for more heat.
        if spec.face.iter().any(|f| f.node == n) {
            return None;
        }
        let sun_aa: f64 = spec
            .sun
            .iter()
            .filter(|s| s.node == n)
            .map(|s| {
                s.absorptivity_area_m2
                    .unwrap_or(s.absorptivity.unwrap_or(0.0) * s.area_m2.unwrap_or(0.0))
            })
            .sum();
        let space_ea: f64 = spec
            .radiation
            .iter()
            .filter(|r| r.between.iter().any(|b| b == n) && r.between.iter().any(|b| b == "space"))
            .map(|r| {
                r.emissivity_area_m2
                    .unwrap_or(r.emissivity.unwrap_or(0.0) * r.area_m2.unwrap_or(0.0))
            })
            .sum();
        // In a model with faces, the outside is its faces and whatever else has a Sun
        // load or a link to space: a node with none of them is inside, sees no Earth,
        // and Earth loads on it would be more heat by another name.
        if !spec.face.is_empty() && sun_aa <= 0.0 && space_ea <= 0.0 {
            return None;
        }
        let a_ref = if sun_aa > 0.0 { sun_aa } else { 0.01 };
        let e_ref = if space_ea > 0.0 { space_ea } else { 0.01 };
        let env_albedo = spec
            .environment
            .albedo
            .unwrap_or(crate::constants::EARTH_ALBEDO);
        let env_ir = spec
            .environment
            .earth_ir_w_per_m2
            .unwrap_or(crate::constants::EARTH_IR_W_PER_M2);
        if !(env_albedo > 0.0 && env_ir > 0.0) {
            return None;
        }
        let (an, en) = (
            format!("diagnose.albedo.{n}"),
            format!("diagnose.earth_ir.{n}"),
        );
        let edit: Edit = {
            let (n, an, en) = (n.to_string(), an.clone(), en.clone());
            std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                s.albedo.push(AlbedoSpec {
                    name: Some(an.clone()),
                    node: n.clone(),
                    absorptivity_area_m2: Some(a_ref),
                    absorptivity: None,
                    area_m2: None,
                    view_factor: None,
                });
                s.earth_ir.push(EarthIrSpec {
                    name: Some(en.clone()),
                    node: n.clone(),
                    emissivity_area_m2: Some(e_ref),
                    emissivity: None,
                    area_m2: None,
                    view_factor: None,
                });
            })
        };
        let base = self.with(&edit)?;
        let pa = Number::of(
            &base,
            Section::Albedo,
            &[],
            &registry::ABSORPTIVITY_AREA_M2,
            &an,
        )?;
        let pe = Number::of(
            &base,
            Section::EarthIr,
            &[],
            &registry::EMISSIVITY_AREA_M2,
            &en,
        )?;
        Some(Candidate {
            params: vec![
                ParamDef::new(registry::ALBEDO.name, 1e-4, 1.0, 0.005),
                ParamDef::new(registry::EARTH_IR_W_PER_M2.name, 0.01, 500.0, 2.0),
            ],
            setters: vec![
                Setter::scaled(pa, 0, a_ref / env_albedo),
                Setter::scaled(pe, 1, e_ref / env_ir),
            ],
            starts: vec![
                vec![0.15, 0.01],
                vec![1e-4, 100.0],
                vec![0.15, 100.0],
                vec![0.3, 237.0],
            ],
            null: Some(vec![0.0, 0.0]),
            ..Candidate::new(Effect::EarthAlbedoIr, Target::Node(n.into()), Some(edit))
        })
    }

    /// A heater with a thermostat on node `ni` (reading the node), started at the set
    /// point the data suggest (none: no candidate).
    fn heater_thermostat(&self, ni: usize) -> Option<Candidate> {
        let on_k = self.hints.heater_on_k.get(ni).copied().flatten()?;
        let n = self.spec.node[ni].name.as_str();
        let hn = format!("diagnose.heater.{n}");
        let edit: Edit = {
            let (n, hn) = (n.to_string(), hn.clone());
            std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                s.heater.push(HeaterSpec {
                    name: Some(hn.clone()),
                    node: n.clone(),
                    sensor_node: None,
                    power_w: 1.0,
                    on_k,
                    off_k: on_k + 5.0,
                })
            })
        };
        let base = self.with(&edit)?;
        let heater = |f| Number::of(&base, Section::Heater, &[], f, &hn);
        let pp = heater(&registry::HEATER_POWER_W)?;
        let pon = heater(&registry::ON_K)?;
        let poff = heater(&registry::OFF_K)?;
        let on_c = on_k - crate::constants::ZERO_CELSIUS_K;
        let mut starts = Vec::new();
        for p in [1.0, 3.0, 8.0] {
            for h in [2.0, 5.0] {
                for d in [-1.0, 0.0] {
                    starts.push(vec![p, on_c + d, h]);
                }
            }
        }
        Some(Candidate {
            params: vec![
                ParamDef::new(registry::HEATER_POWER_W.name, 0.01, 1000.0, 0.02),
                ParamDef::new("on_c", on_c - 30.0, on_c + 30.0, 0.05),
                ParamDef::new("hysteresis_k", 0.1, 50.0, 0.05).floored_alone(),
            ],
            setters: vec![
                Setter::scaled(pp, 0, 1.0),
                Setter {
                    number: pon,
                    constant: crate::constants::ZERO_CELSIUS_K,
                    terms: vec![(1, 1.0)],
                },
                Setter {
                    number: poff,
                    constant: crate::constants::ZERO_CELSIUS_K,
                    terms: vec![(1, 1.0), (2, 1.0)],
                },
            ],
            starts,
            null: Some(vec![0.0, on_c, 5.0]),
            multi_start: HEATER_STARTS,
            grid: {
                let mut g = Vec::new();
                for d in [-3.0, -2.0, -1.0, 0.0, 1.0] {
                    for h in [2.0, 3.5, 5.0, 7.0] {
                        for p in [2.0, 4.0, 6.5, 9.5, 14.0] {
                            g.push(vec![p, on_c + d, h]);
                        }
                    }
                }
                g
            },
            ..Candidate::new(Effect::HeaterThermostat, Target::Node(n.into()), Some(edit))
        })
    }

    /// Internal dissipation on node `n`: always, sunlit, in eclipse, or in each mode.
    fn internal_dissipation(&self, ni: usize) -> Vec<Candidate> {
        let n = self.spec.node[ni].name.as_str();
        let mut whens = vec![Schedule::Always, Schedule::Sunlit, Schedule::Eclipse];
        whens.extend(
            self.spec
                .mode
                .iter()
                .map(|m| Schedule::Mode(m.name.clone())),
        );
        let mut out = Vec::new();
        for when in whens {
            let dn = format!("diagnose.dissipation.{n}.{}", when.name());
            let edit: Edit = {
                let (n, dn, when) = (n.to_string(), dn.clone(), when.clone());
                std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                    s.dissipation.push(DissipationSpec {
                        name: Some(dn.clone()),
                        node: n.clone(),
                        power_w: ProfileSpec::Constant(0.5),
                        when: Some(when.clone()),
                    })
                })
            };
            let Some(base) = self.with(&edit) else {
                continue;
            };
            let field = &registry::DISSIPATION_POWER_W;
            let Some(pp) = Number::of(&base, Section::Dissipation, &[], field, &dn) else {
                continue;
            };
            let target = Target::Scheduled {
                node: n.into(),
                schedule: when.name().to_string(),
            };
            out.push(Candidate {
                params: vec![ParamDef::new(
                    registry::DISSIPATION_POWER_W.name,
                    0.0,
                    1000.0,
                    0.02,
                )],
                setters: vec![Setter::scaled(pp, 0, 1.0)],
                starts: vec![vec![0.25], vec![1.0], vec![4.0]],
                null: Some(vec![0.0]),
                ..Candidate::new(Effect::InternalDissipation, target, Some(edit))
            });
        }
        out
    }

    /// The centre distance of each gear pair with a fixed one following node `n`
    /// (a node outside the gears: the housing or a structure).
    fn housing_expansion(&self, ni: usize) -> Vec<Candidate> {
        let n = self.spec.node[ni].name.as_str();
        let mut out = Vec::new();
        if self.gear_nodes.contains(&n) {
            return out;
        }
        for (gi, gp) in self.spec.gear_pair.iter().enumerate() {
            if gp
                .center_distance
                .as_ref()
                .is_some_and(|c| c.follows != Follows::Fixed)
            {
                continue;
            }
            let pair = pair_name(self.spec, gi);
            let edit: Edit = {
                let n = n.to_string();
                std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                    s.gear_pair[gi].center_distance = Some(CenterDistanceSpec {
                        follows: Follows::Housing,
                        node: Some(n.clone()),
                        alpha_per_k: Some(5e-6),
                        dalpha_dt_per_k2: None,
                        strain_polynomial: None,
                        alpha_polynomial: None,
                        strain_table: None,
                    })
                })
            };
            let Some(base) = self.with(&edit) else {
                continue;
            };
            let center = [registry::CENTER_DISTANCE];
            let field = &registry::ALPHA_PER_K;
            let Some(p) = Number::of(&base, Section::GearPair, &center, field, &pair) else {
                continue;
            };
            let target = Target::NodeAndPair {
                node: n.into(),
                gear_pair: pair,
            };
            out.push(Candidate {
                params: vec![ParamDef::new(registry::ALPHA_PER_K.name, -2e-5, 1e-4, 1e-7)],
                setters: vec![Setter::scaled(p, 0, 1.0)],
                starts: vec![vec![2e-6], vec![8e-6], vec![2e-5]],
                null: Some(vec![0.0]),
                ..Candidate::new(Effect::HousingExpansion, target, Some(edit))
            });
        }
        out
    }

    /// Gear pair `gi`'s gear materials, when both are linear (α only): their α.
    fn linear_alphas(&self, gi: usize) -> Option<(f64, f64)> {
        let gp = &self.spec.gear_pair[gi];
        let linear = |m: &crate::spec::MaterialSpec| {
            (m.strain_polynomial.is_none()
                && m.alpha_polynomial.is_none()
                && m.strain_table.is_none())
            .then_some(m.alpha_per_k)
            .flatten()
        };
        Some((linear(&gp.pinion.material)?, linear(&gp.wheel.material)?))
    }

    /// Number `field` of both gears' materials of pair `gi` in `m`.
    fn materials(&self, m: &Model, gi: usize, field: &'static Field) -> Option<(Number, Number)> {
        let pair = pair_name(self.spec, gi);
        let of = |gear| {
            let table = [gear, registry::MATERIAL];
            Number::of(m, Section::GearPair, &table, field, &pair)
        };
        Some((of(registry::PINION)?, of(registry::WHEEL)?))
    }

    /// For gear pair `gi` with linear materials and neither with an α(T) yet: α(T).
    fn cte_temperature(&self, gi: usize) -> Option<Candidate> {
        let gp = &self.spec.gear_pair[gi];
        self.linear_alphas(gi)?;
        if gp.pinion.material.dalpha_dt_per_k2.is_some()
            || gp.wheel.material.dalpha_dt_per_k2.is_some()
        {
            return None;
        }
        let edit: Edit = std::sync::Arc::new(move |s: &mut ScenarioSpec| {
            s.gear_pair[gi].pinion.material.dalpha_dt_per_k2 = Some(0.0);
            s.gear_pair[gi].wheel.material.dalpha_dt_per_k2 = Some(0.0);
        });
        let base = self.with(&edit)?;
        let dalpha = &registry::DALPHA_DT_PER_K2;
        let (p1, p2) = self.materials(&base, gi, dalpha)?;
        Some(Candidate {
            params: vec![ParamDef::new(dalpha.name, -1e-6, 1e-6, 1e-9)],
            setters: vec![Setter::scaled(p1, 0, 1.0), Setter::scaled(p2, 0, 1.0)],
            starts: vec![vec![-5e-8], vec![-1.5e-8], vec![1.5e-8], vec![5e-8]],
            null: Some(vec![0.0]),
            ..Candidate::new(
                Effect::CteTemperature,
                Target::Pair(pair_name(self.spec, gi)),
                Some(edit),
            )
        })
    }

    /// For gear pair `gi` with linear materials: both gears' α scaled.
    fn cte_scale(&self, gi: usize) -> Option<Candidate> {
        let (a1, a2) = self.linear_alphas(gi)?;
        let (p1, p2) = self.materials(self.model, gi, &registry::ALPHA_PER_K)?;
        Some(Candidate {
            params: vec![ParamDef::new("scale", 0.1, 5.0, 0.005)],
            setters: vec![Setter::scaled(p1, 0, a1), Setter::scaled(p2, 0, a2)],
            starts: vec![vec![0.8], vec![0.9], vec![1.1], vec![1.25]],
            null: Some(vec![1.0]),
            ..Candidate::new(
                Effect::CteScale,
                Target::Pair(pair_name(self.spec, gi)),
                None,
            )
        })
    }

    /// An elastic bore fit on each free gear of pair `gi` that sits on a shaft node
    /// (the node outside the gear its bore node conducts to).
    fn bore_fits(&self, gi: usize) -> Vec<Candidate> {
        let spec = self.spec;
        let gp = &spec.gear_pair[gi];
        let pair = pair_name(spec, gi);
        let mut out = Vec::new();
        for (which, g) in [(registry::PINION, &gp.pinion), (registry::WHEEL, &gp.wheel)] {
            if !matches!(g.bore_fit, None | Some(BoreFitName::Free)) {
                continue;
            }
            let bore = &g.nodes[0];
            let shaft = spec.conductor.iter().find_map(|c| {
                let other = match (c.between.first(), c.between.get(1)) {
                    (Some(a), Some(b)) if a == bore => b,
                    (Some(a), Some(b)) if b == bore => a,
                    _ => return None,
                };
                (!self.gear_nodes.contains(&other.as_str())
                    && spec.node.iter().any(|n| n.name == *other))
                .then(|| other.clone())
            });
            let Some(shaft) = shaft else { continue };
            let edit: Edit = {
                let shaft = shaft.clone();
                std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                    let gs = if which == registry::PINION {
                        &mut s.gear_pair[gi].pinion
                    } else {
                        &mut s.gear_pair[gi].wheel
                    };
                    gs.bore_fit = Some(BoreFitName::Elastic);
                    gs.shaft_node = Some(shaft.clone());
                    gs.shaft_material = Some(gs.material.clone());
                    gs.interference_um = Some(5.0);
                })
            };
            let Some(base) = self.with(&edit) else {
                continue;
            };
            let field = &registry::INTERFERENCE_UM;
            let Some(p) = Number::of(&base, Section::GearPair, &[which], field, &pair) else {
                continue;
            };
            let target = Target::Bore {
                gear_pair: pair.clone(),
                gear: format!("{pair}.{which}"),
                shaft,
            };
            out.push(Candidate {
                params: vec![
                    ParamDef::new(registry::INTERFERENCE_UM.name, 0.0, 500.0, 0.2).floored(),
                ],
                setters: vec![Setter::scaled(p, 0, 1.0)],
                starts: vec![vec![2.0], vec![10.0], vec![40.0]],
                ..Candidate::new(Effect::BoreFit, target, Some(edit))
            });
        }
        out
    }

    /// Temperature channel `col`'s lag and offset, with their values, when its sensor
    /// has them.
    fn sensor_numbers(&self, col: &str) -> Option<((Number, f64), (Number, f64))> {
        let sensor = |f| Number::of(self.model, Section::Sensor, &[], f, col);
        let value = |n: &Number| {
            n.resolve(self.model)
                .ok()
                .and_then(|id| self.model.value(&id))
        };
        let (pt, po) = (sensor(&registry::TAU_S)?, sensor(&registry::OFFSET_K)?);
        let (tau0, off0) = (value(&pt)?, value(&po)?);
        Some(((pt, tau0), (po, off0)))
    }

    /// A first-order lag on temperature channel `col`.
    fn sensor_lag(&self, col: &str) -> Option<Candidate> {
        let ((pt, tau0), _) = self.sensor_numbers(col)?;
        Some(Candidate {
            params: vec![ParamDef::new(registry::TAU_S.name, 0.0, 7200.0, 1.0)],
            setters: vec![Setter {
                number: pt,
                constant: tau0,
                terms: vec![(0, 1.0)],
            }],
            starts: vec![vec![20.0], vec![60.0], vec![200.0], vec![600.0]],
            null: Some(vec![0.0]),
            ..Candidate::new(Effect::SensorLag, Target::Channel(col.into()), None)
        })
    }

    /// A constant offset on temperature channel `col`.
    fn sensor_offset(&self, col: &str) -> Option<Candidate> {
        let (_, (po, off0)) = self.sensor_numbers(col)?;
        Some(Candidate {
            params: vec![ParamDef::new(registry::OFFSET_K.name, -50.0, 50.0, 0.05)],
            setters: vec![Setter {
                number: po,
                constant: off0,
                terms: vec![(0, 1.0)],
            }],
            starts: vec![vec![-0.5], vec![0.5]],
            null: Some(vec![0.0]),
            ..Candidate::new(Effect::SensorOffset, Target::Channel(col.into()), None)
        })
    }

    /// One scale on every number of `params` that `pick` chooses (with whether it is an
    /// optical property, which stays ≤ 1), as `effect` on the whole spacecraft.
    fn global_scale(
        &self,
        effect: Effect,
        starts: &[f64],
        pick: &dyn Fn(&Param) -> Option<bool>,
    ) -> Option<Candidate> {
        let keys = crate::spec::keys::element_keys(self.spec);
        let declared = self.declared_numbers();
        let mut upper = 20.0f64;
        let mut setters = Vec::new();
        for p in self.model.params() {
            let Some(optical) = pick(&p) else { continue };
            if p.value.is_nan() || p.value <= 0.0 {
                continue;
            }
            let row = p.id.row();
            let element = row
                .section
                .keys(&keys)
                .map_or(String::new(), |k| k[p.id.element].clone());
            let number = Number {
                row: p.id.row,
                element,
                sub: p.id.sub,
            };
            // a number the user declared is fitted on its own
            if declared.contains(&number) {
                continue;
            }
            if optical {
                upper = upper.min(1.0 / p.value);
            }
            setters.push(Setter::scaled(number, 0, p.value));
        }
        // one number is a per-element scale the vocabulary has already
        if setters.len() < 2 || upper <= 1.0 {
            return None;
        }
        Some(Candidate {
            params: vec![ParamDef::new("scale", 0.05, upper, 0.003)],
            setters,
            starts: starts.iter().map(|s| vec![s.min(upper)]).collect(),
            null: Some(vec![1.0]),
            ..Candidate::new(effect, Target::Spacecraft, None)
        })
    }

    /// Every face's and Sun load's absorptivity (or αA) scaled by one factor.
    fn sunlight_scale(&self) -> Option<Candidate> {
        self.global_scale(Effect::SunlightScale, &[0.6, 0.8, 1.15, 1.3], &|p| {
            let row = p.id.row();
            let (alpha, product) = (
                std::ptr::eq(row.field, &registry::ABSORPTIVITY),
                std::ptr::eq(row.field, &registry::ABSORPTIVITY_AREA_M2),
            );
            match row.section {
                Section::Face if alpha => Some(true),
                Section::Sun if alpha || product => Some(alpha),
                _ => None,
            }
        })
    }

    /// Every face's emissivity and every radiative coupling to `space` (its ε or εA)
    /// scaled by one factor.
    fn infrared_scale(&self) -> Option<Candidate> {
        let to_space = |e: usize| self.spec.radiation[e].between.iter().any(|n| n == "space");
        self.global_scale(Effect::InfraredScale, &[0.7, 0.85, 1.1, 1.2], &|p| {
            let row = p.id.row();
            let (eps, product) = (
                std::ptr::eq(row.field, &registry::EMISSIVITY),
                std::ptr::eq(row.field, &registry::EMISSIVITY_AREA_M2),
            );
            match row.section {
                Section::Face if eps => Some(true),
                Section::Radiation if (eps || product) && to_space(p.id.element) => Some(eps),
                _ => None,
            }
        })
    }

    /// A dissipation on node `ni` switched on at a time and left on: a mode whose one
    /// window starts at the fitted time (s from t = 0) and outlasts the recording.
    fn switched_dissipation(&self, ni: usize) -> Option<Candidate> {
        let n = self.spec.node[ni].name.clone();
        let (mode, dn) = (
            format!("diagnose.switch.{n}"),
            format!("diagnose.switched.{n}"),
        );
        let end_s = self.model.scenario().run.duration_s;
        let edit: Edit = {
            let (n, mode, dn) = (n.clone(), mode.clone(), dn.clone());
            std::sync::Arc::new(move |s: &mut ScenarioSpec| {
                s.mode.push(crate::spec::ModeSpec {
                    name: mode.clone(),
                    windows_s: Some(vec![vec![0.5 * end_s, SWITCHED_UNTIL_S]]),
                    windows_days: None,
                });
                s.dissipation.push(DissipationSpec {
                    name: Some(dn.clone()),
                    node: n.clone(),
                    power_w: ProfileSpec::Constant(0.5),
                    when: Some(Schedule::Mode(mode.clone())),
                })
            })
        };
        let base = self.with(&edit)?;
        let field = &registry::DISSIPATION_POWER_W;
        let power = Number::of(&base, Section::Dissipation, &[], field, &dn)?;
        let on = Number {
            row: registry::row_of(Section::Mode, &[], &registry::WINDOWS_S),
            element: mode,
            sub: Sub::Window(0, 0),
        };
        on.resolve(&base).ok()?;
        let mut starts = Vec::new();
        for f in [0.15, 0.35, 0.55, 0.75] {
            for p in [0.3, 1.0] {
                starts.push(vec![p, f * end_s]);
            }
        }
        Some(Candidate {
            params: vec![
                ParamDef::new(field.name, 0.0, 1000.0, 0.02).floored(),
                ParamDef::new("on_s", 0.0, end_s, 30.0),
            ],
            setters: vec![Setter::scaled(power, 0, 1.0), Setter::scaled(on, 1, 1.0)],
            starts,
            null: None,
            multi_start: SWITCH_STARTS,
            ..Candidate::new(Effect::SwitchedDissipation, Target::Node(n), Some(edit))
        })
    }

    /// Calibrations, in the order of the model's parameters: a sun load's
    /// absorptivity scaled, a conductor's or radiative coupling's conductance scaled.
    fn calibrations(&self) -> Vec<Candidate> {
        // Thermal masses and faces, the declared numbers, then loads and links (the
        // order breaks ties in the ranking).
        let params = self.model.params();
        let keys = crate::spec::keys::element_keys(self.spec);
        let scales = |first| {
            params
                .iter()
                .filter_map(|p| calibration_of(p, &keys, first))
                .collect::<Vec<_>>()
        };
        let mut out: Vec<Candidate> = scales(true);
        out.extend(self.uncertain());
        out.extend(scales(false));
        out
    }
}

/// The scale calibration of number `p`, when its row says `diagnose` may calibrate it
/// (`spec::registry`'s `Calibration`): a node's thermal mass or a face's ε or α
/// (`first`), a Sun load's α or a link's conductance (not `first`). Optical properties
/// stay within 0 … 1.
fn calibration_of(p: &Param, keys: &ElementKeys, first: bool) -> Option<Candidate> {
    use crate::spec::registry::{ScaleFamily, Section};
    let row = p.id.row();
    let c = row.calibration?;
    if c.first != first || p.value.is_nan() || p.value <= 0.0 {
        return None;
    }
    let name = row.section.keys(keys)?[p.id.element].clone();
    let number = Number {
        row: p.id.row,
        element: name.clone(),
        sub: p.id.sub,
    };
    let upper = c.upper.unwrap_or(1.0 / p.value);
    let (effect, target) = match c.family {
        ScaleFamily::ThermalMass => (Effect::CapacitanceScale, Target::Node(name)),
        ScaleFamily::Emissivity => (Effect::EmissivityScale, Target::Face(name)),
        ScaleFamily::Absorptivity if row.section == Section::Face => {
            (Effect::AbsorptivityScale, Target::Face(name))
        }
        ScaleFamily::Absorptivity => (Effect::AbsorptivityScale, Target::Load(name)),
        ScaleFamily::Conductance => (Effect::ConductanceScale, Target::Conductor(name)),
    };
    Some(Candidate {
        params: vec![ParamDef::new("scale", c.lower, upper, c.step)],
        setters: vec![Setter::scaled(number, 0, p.value)],
        starts: c.starts.iter().map(|s| vec![s.min(upper)]).collect(),
        null: Some(vec![1.0]),
        ..Candidate::new(effect, target, None)
    })
}

impl Generator<'_> {
    /// The numbers the user declared uncertain: each `[[uncertain]]` path with its range,
    /// then each `[[dispersion]]` path not declared already (uniform and triangular:
    /// its range; normal: mean ± 3 sd; log-normal: median ×/÷ e^(3σ)).
    fn declared(&self) -> Vec<(String, f64, f64)> {
        let mut declared: Vec<(String, f64, f64)> = self
            .spec
            .uncertain
            .iter()
            .map(|u| (u.path.clone(), u.min, u.max))
            .collect();
        for d in &self.spec.dispersion {
            let range = match (d.min, d.max, d.mean, d.sd, d.median, d.sigma) {
                (Some(lo), Some(hi), ..) => Some((lo, hi)),
                (_, _, Some(m), Some(sd), ..) => Some((m - 3.0 * sd, m + 3.0 * sd)),
                (.., Some(med), Some(sg)) => {
                    Some((med * (-3.0 * sg).exp(), med * (3.0 * sg).exp()))
                }
                _ => None,
            };
            if let Some((lo, hi)) = range
                && !declared.iter().any(|(p, ..)| *p == d.path)
            {
                declared.push((d.path.clone(), lo, hi));
            }
        }
        declared
    }

    /// The model numbers [`Generator::uncertain`] calibrates, each once.
    fn declared_numbers(&self) -> Vec<Number> {
        self.uncertain()
            .into_iter()
            .map(|c| c.setters[0].number.clone())
            .collect()
    }

    /// One calibration candidate of each number the user declared uncertain
    /// ([`Generator::declared`]), within its range; two paths to one number give one
    /// (the first). A path the model does not have is skipped (the scenario's compile
    /// has refused it already).
    fn uncertain(&self) -> Vec<Candidate> {
        let mut out: Vec<Candidate> = Vec::new();
        for (path, lo, hi) in self.declared() {
            let Ok(id) = self.model.param(&path) else {
                continue;
            };
            let number = Number::of_param(self.model, &id);
            if out.iter().any(|c| c.setters[0].number == number) {
                continue;
            }
            let Some(now) = self.model.value(&id) else {
                continue;
            };
            if lo >= hi || lo.is_nan() || hi.is_nan() || !now.is_finite() {
                continue;
            }
            let span = hi - lo;
            let null = now.clamp(lo, hi);
            out.push(Candidate {
                params: vec![ParamDef::new("value", lo, hi, 1e-3 * span)],
                setters: vec![Setter::scaled(number, 0, 1.0)],
                starts: [0.1, 0.35, 0.65, 0.9]
                    .iter()
                    .map(|f| vec![lo + f * span])
                    .collect(),
                null: Some(vec![null]),
                ..Candidate::new(Effect::UncertainParameter, Target::Path(path), None)
            });
        }
        out
    }
}

fn pair_name(spec: &ScenarioSpec, i: usize) -> String {
    spec.gear_pair[i].name.clone().unwrap_or_else(|| {
        if i == 0 {
            "mesh".to_string()
        } else {
            format!("mesh{i}")
        }
    })
}

/// FUNcube-1 for the unit tests of the search and its calibration.
#[cfg(test)]
pub(super) mod fixtures {
    use crate::spec::model::Model;

    /// FUNcube-1's shipped scenario text with `extra` TOML appended.
    pub fn funcube_text(extra: &str) -> String {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        std::fs::read_to_string(root.join("scenarios/funcube-1.toml")).unwrap() + extra
    }

    /// The model of scenario `text`, and its sensors as channels, every one recorded.
    pub fn model_and_channels(text: &str) -> (Model, Vec<(String, bool)>) {
        let spec = crate::io::scenario_toml::parse_spec(text, "funcube-1.toml").unwrap();
        let model = Model::new(spec).unwrap();
        let channels = model
            .spec()
            .sensor
            .iter()
            .map(|s| (s.name.clone().unwrap(), true))
            .collect();
        (model, channels)
    }
}

#[cfg(test)]
mod calibration {
    use super::fixtures::{funcube_text, model_and_channels};
    use super::*;

    /// FUNcube-1 with a face's absorptivity and the chassis' capacitance declared
    /// uncertain: the calibration fits each declared number, and nothing else in the
    /// set writes it (the sunlight scale keeps the other five faces, the chassis has no
    /// mass scale beside its declared capacitance, the stack keeps its own).
    #[test]
    fn core_a_declared_number_is_written_by_its_own_calibration_only() {
        let text = funcube_text(
            "\n[[uncertain]]\npath = \"face.px.absorptivity\"\nmin = 0.3\nmax = 0.9\n\
               \n[[uncertain]]\npath = \"node.chassis.capacitance_j_per_k\"\nmin = 100.0\nmax = 600.0\n",
        );
        let (model, channels) = model_and_channels(&text);
        let mut cands = candidates(&model, &channels, &Hints::default());
        let (set, nominal) = calibration_set(&model, &mut cands);
        assert_eq!(set.len(), nominal.len());
        for (c, n) in set.iter().zip(&nominal) {
            assert_eq!(c.null.as_ref().unwrap()[0], *n, "{}", c.label());
            assert_eq!(c.params[0].prior.unwrap().0, *n, "{}", c.label());
        }
        let number = |path: &str| Number::of_param(&model, &model.param(path).unwrap());
        let alpha_px = number("face.px.absorptivity");
        let chassis = number("node.chassis.capacitance_j_per_k");
        let writers = |n: &Number| -> Vec<Effect> {
            set.iter()
                .filter(|c| c.setters.iter().any(|s| s.number == *n))
                .map(|c| c.effect)
                .collect()
        };
        assert_eq!(writers(&alpha_px), vec![Effect::UncertainParameter]);
        assert_eq!(writers(&chassis), vec![Effect::UncertainParameter]);
        let sunlight = set
            .iter()
            .find(|c| c.effect == Effect::SunlightScale)
            .unwrap();
        assert_eq!(
            sunlight.setters.len(),
            5,
            "the other five faces' absorptivity"
        );
        assert_eq!(
            writers(&number("face.mx.absorptivity")),
            vec![Effect::SunlightScale]
        );
        assert_eq!(
            writers(&number("node.stack.capacitance_j_per_k")),
            vec![Effect::CapacitanceScale]
        );
        // the declared face's other number stays with the global scale
        assert_eq!(
            writers(&number("face.px.emissivity")),
            vec![Effect::InfraredScale]
        );
        // and nothing searched later writes a declared number
        for c in &cands {
            for s in &c.setters {
                assert!(
                    s.number != alpha_px && s.number != chassis,
                    "{} writes a declared number",
                    c.label()
                );
            }
        }
        // a declared face of α 1 does not take the global scale from the others (its
        // declared range widened to hold it: a range must hold the scenario's value)
        let mut spec = crate::io::scenario_toml::parse_spec(&text, "funcube-1.toml").unwrap();
        spec.face[0].absorptivity = 1.0;
        spec.uncertain[0].max = 1.0;
        let model = Model::new(spec).unwrap();
        let mut cands = candidates(&model, &channels, &Hints::default());
        let (set, _) = calibration_set(&model, &mut cands);
        let sunlight = set.iter().find(|c| c.effect == Effect::SunlightScale);
        assert_eq!(sunlight.map(|c| c.setters.len()), Some(5));
        assert!(sunlight.unwrap().params[0].upper > 1.0);
    }
}

#[cfg(test)]
mod vocabulary_doc {
    use super::{Effect, EffectKind};

    /// `docs/vocabulary.md` has a row for every effect, with its id and kind, and no
    /// row for an effect that does not exist.
    #[test]
    fn core_every_effect_has_its_row_in_the_vocabulary() {
        let doc = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/vocabulary.md"),
        )
        .unwrap();
        let rows: Vec<(String, String)> = doc
            .lines()
            .filter(|l| l.starts_with("| `") || l.starts_with("| **`"))
            .filter_map(|l| {
                let cells: Vec<&str> = l.split('|').map(str::trim).collect();
                let id = cells
                    .get(1)?
                    .trim_matches('*')
                    .trim_matches('`')
                    .to_string();
                Some((id, cells.get(2)?.to_string()))
            })
            .collect();
        for &e in Effect::ALL {
            let kind: EffectKind = e.kind();
            assert!(
                rows.iter()
                    .any(|(id, k)| id == e.id() && k == kind.as_str()),
                "docs/vocabulary.md has no row `{}` | {}",
                e.id(),
                kind
            );
        }
        for (id, _) in &rows {
            assert!(
                Effect::from_id(id).is_some(),
                "docs/vocabulary.md documents `{id}`, no effect"
            );
        }
        assert_eq!(rows.len(), Effect::ALL.len());
    }
}

#[cfg(test)]
mod reported {
    use super::*;

    fn heater() -> Candidate {
        Candidate {
            effect: Effect::HeaterThermostat,
            target: Target::Node("housing".into()),
            params: vec![
                ParamDef::new("power_w", 0.0, 1000.0, 0.02),
                ParamDef::new("on_c", -30.0, 30.0, 0.05),
                ParamDef::new("hysteresis_k", 0.1, 50.0, 0.05),
            ],
            setters: Vec::new(),
            starts: Vec::new(),
            null: None,
            edits: Vec::new(),
            multi_start: 1,
            grid: Vec::new(),
        }
    }

    /// A heater reports off_c = on_c + hysteresis_k, its variance var(on) + var(h) +
    /// 2 cov(on, h), and its correlations from the transformed covariance: by hand for
    /// σ = (0.1, 0.2, 0.3) and ρ(p, on) = −0.5, ρ(p, h) = 0.25, ρ(on, h) = −0.4.
    /// Without a covariance the errors are NaN (not 0: "± 0") and the correlations
    /// none.
    #[test]
    fn core_a_heater_reports_off_c_with_its_error_and_correlations() {
        let s = [0.1, 0.2, 0.3];
        let r = [[1.0, -0.5, 0.25], [-0.5, 1.0, -0.4], [0.25, -0.4, 1.0]];
        let cov: Vec<Vec<f64>> = (0..3)
            .map(|i| (0..3).map(|j| r[i][j] * s[i] * s[j]).collect())
            .collect();
        let h = heater();
        let p = h.report_params(&[2.0, -6.0, 3.0], Some(&cov));
        let names: Vec<&str> = p.iter().map(|x| x.0.as_str()).collect();
        assert_eq!(names, ["power_w", "on_c", "off_c"]);
        assert_eq!((p[0].1, p[1].1, p[2].1), (2.0, -6.0, -3.0));
        let var_off: f64 = 0.04 + 0.09 + 2.0 * (-0.4 * 0.2 * 0.3);
        assert!((p[2].2 - var_off.sqrt()).abs() < 1e-15, "{p:?}");
        assert!((p[0].2 - 0.1).abs() < 1e-15 && (p[1].2 - 0.2).abs() < 1e-15);
        let (order, c) = h.report_correlation(Some(&cov));
        assert_eq!(order, ["power_w", "on_c", "off_c"]);
        // cov(p, off) = cov(p, on) + cov(p, h); cov(on, off) = var(on) + cov(on, h)
        let p_off = (-0.5 * 0.1 * 0.2 + 0.25 * 0.1 * 0.3) / (0.1 * var_off.sqrt());
        let on_off = (0.04 - 0.4 * 0.2 * 0.3) / (0.2 * var_off.sqrt());
        assert!((c[0][2].unwrap() - p_off).abs() < 1e-12, "{c:?}");
        assert!((c[2][1].unwrap() - on_off).abs() < 1e-12, "{c:?}");
        assert!((c[0][1].unwrap() + 0.5).abs() < 1e-12);
        for (i, row) in c.iter().enumerate() {
            assert_eq!(row[i], Some(1.0));
        }
        let none = h.report_params(&[2.0, -6.0, 3.0], None);
        assert!(none.iter().all(|x| x.2.is_nan()), "{none:?}");
        let (_, c) = h.report_correlation(None);
        assert!(c.iter().flatten().all(Option::is_none));
    }
}

//! The registry of parameters: every number a scenario file holds, one [`Row`] each
//! (in `rows.rs`), in the order `orbitlash params` lists them. A row holds the section
//! and field of its number ([`Field`]: the key as written and its [`Quantity`], with the
//! unit, range and default), how to reach its slot in a spec, an optional fast write
//! into a compiled model, whether `diagnose` may calibrate it, and its doc line.
//!
//! A parameter is a row, an element of the row's section (the node, the heater, …) and,
//! for numbers inside a value, an index ([`Sub`]: a profile table's entries, a list's
//! items, a mode's windows): a [`ParamRef`]. Key paths (`node.housing.capacitance_j_per_k`,
//! see [`super::keys`]) are parsed once, at the edges (`--set`, `[[dispersion]]`,
//! `[[uncertain]]`), into a `ParamRef` ([`resolve`]); listing ([`params`]), reading
//! ([`get`]) and writing ([`set`]) go through the rows, and so do the compiler's checks
//! of single values (`Field::quantity`), `Scenario::validate` and the fast writes of
//! `Model::set_param` that margins and diagnose share.
//!
//! Adding a number: its field in the spec (`spec/mod.rs`), its row in `rows.rs`, the
//! compiler reading it through its [`Field`], and the physics struct it lands in.

/// Defines the fields a rows file holds (`NAME = "key", QUANTITY;`): each key of a
/// scenario file once, with its quantity from `spec::quantity`.
macro_rules! fields {
    ($($(#[$doc:meta])* $id:ident = $name:literal, $q:ident;)*) => {
        $($(#[$doc])* pub static $id: Field = Field {
            name: $name,
            quantity: &crate::spec::quantity::$q,
        };)*
    };
}

mod gear_rows;
mod rows;

use std::sync::LazyLock;

use super::keys::{ElementKeys, KeyPath, Part, element_keys, parse_path, quote_key};
use super::quantity::Quantity;
use super::scenario::Scenario;
use super::{ProfileSpec, ScenarioSpec, SpecError};

pub use gear_rows::*;
pub use rows::*;

/// A section of a scenario file: a table (`[orbit]`) or an array of tables whose
/// elements are named by key (`[[node]]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Section {
    Orbit,
    Environment,
    Run,
    Solver,
    Node,
    Boundary,
    Conductor,
    Radiation,
    Sun,
    Albedo,
    EarthIr,
    Dissipation,
    Heater,
    Attitude,
    Face,
    Mode,
    Recording,
    Sensor,
    GearPair,
}

impl Section {
    /// Every section, in the order `orbitlash params` lists them.
    pub const ALL: [Section; 19] = [
        Section::Orbit,
        Section::Environment,
        Section::Run,
        Section::Solver,
        Section::Node,
        Section::Boundary,
        Section::Conductor,
        Section::Radiation,
        Section::Sun,
        Section::Albedo,
        Section::EarthIr,
        Section::Dissipation,
        Section::Heater,
        Section::Attitude,
        Section::Face,
        Section::Mode,
        Section::Recording,
        Section::Sensor,
        Section::GearPair,
    ];

    /// The section's name in the file and in key paths.
    pub const fn name(self) -> &'static str {
        match self {
            Section::Orbit => "orbit",
            Section::Environment => "environment",
            Section::Run => "run",
            Section::Solver => "solver",
            Section::Node => "node",
            Section::Boundary => "boundary",
            Section::Conductor => "conductor",
            Section::Radiation => "radiation",
            Section::Sun => "sun",
            Section::Albedo => "albedo",
            Section::EarthIr => "earth_ir",
            Section::Dissipation => "dissipation",
            Section::Heater => "heater",
            Section::Attitude => "attitude",
            Section::Face => "face",
            Section::Mode => "mode",
            Section::Recording => "recording",
            Section::Sensor => "sensor",
            Section::GearPair => "gear_pair",
        }
    }

    pub fn from_name(name: &str) -> Option<Section> {
        Section::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The element keys of an array of tables (None for a table).
    pub fn keys(self, keys: &ElementKeys) -> Option<&[String]> {
        keys.section(self.name())
    }

    /// The key path of element `i` (with key `key`) of this section, or of the table.
    pub fn path(self, element: Option<(usize, &str)>) -> KeyPath {
        let p = KeyPath::new(self.name());
        match element {
            Some((i, key)) => p.elem(i, key),
            None => p,
        }
    }
}

/// A key as it is written in a file, with the kind of number it holds. One field may sit
/// in several rows (`area_m2` of a Sun load and of a face; a material's `alpha_per_k`
/// under each gear): the compiler checks a value through its field.
#[derive(Debug, PartialEq)]
pub struct Field {
    pub name: &'static str,
    pub quantity: &'static Quantity,
}

impl Field {
    /// The key path of this field in the table at `under`.
    pub fn key(&self, under: &KeyPath) -> KeyPath {
        under.key(self.name)
    }
}

/// What an absent optional value stands for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Default {
    /// The quantity's default; nothing (the key is not in the scenario, listed only when
    /// given) for a quantity without one.
    OfQuantity,
    /// The orbit's view factor of the Earth, (R / (R + h))².
    EarthViewFactor,
}

/// How a row's number is stored in a spec.
pub enum Slot<'a> {
    /// Always given.
    Value(&'a mut f64),
    /// Optional, standing for the row's [`Default`] when absent.
    Optional(&'a mut Option<f64>),
    /// An integer (a number of teeth).
    Integer(&'a mut i64),
    /// A number or a table over time ([`Sub::One`], or its times and values).
    Profile(&'a mut ProfileSpec),
    /// An optional profile; absent stands for the quantity's default, as a number.
    OptionalProfile(&'a mut Option<ProfileSpec>),
    /// A list of numbers ([`Sub::Item`]).
    List(&'a mut Vec<f64>),
    /// A list of [start, end] windows ([`Sub::Window`]).
    Windows(&'a mut Vec<Vec<f64>>),
}

/// The row's number inside its slot: the value itself, an entry of a profile table, an
/// item of a list, one end of a window.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sub {
    One,
    Item(usize),
    Time(usize),
    Days(usize),
    Value(usize),
    Window(usize, usize),
}

/// A write straight into a compiled model: the compiled value of element `e` made again
/// from the spec, which already holds the new value and its check by the field's
/// quantity (the compiler's check); it may check the value against others (a heater's
/// band). Gives exactly what compiling the spec gives.
pub type FastFn = fn(&ScenarioSpec, &ElementKeys, &mut Scenario, usize) -> Result<(), SpecError>;

/// How a written number reaches the compiled model.
#[derive(Clone, Copy)]
pub enum Fast {
    /// The whole scenario is compiled again (a number others depend on: an altitude).
    Recompile,
    /// [`FastFn`], for the number itself ([`Sub::One`]); table entries recompile.
    Direct(FastFn),
    /// The gear pair is compiled again (its checks tie many numbers together).
    GearPair,
}

/// Which scale `diagnose` may calibrate a number with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScaleFamily {
    /// A node's thermal mass.
    ThermalMass,
    /// A face's infrared emissivity.
    Emissivity,
    /// A face's or a Sun load's solar absorptivity.
    Absorptivity,
    /// A conductive or radiative link.
    Conductance,
}

/// How `diagnose` may calibrate a number: as a scale on its value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    pub family: ScaleFamily,
    /// Tried before the `[[uncertain]]` numbers (the others after them).
    pub first: bool,
    pub lower: f64,
    /// The largest scale; None for an optical property, which stays ≤ 1 (1 / value).
    pub upper: Option<f64>,
    /// The finite-difference step of the scale.
    pub step: f64,
    /// Start points of the fit (each at most the upper bound).
    pub starts: &'static [f64],
}

type SlotFn = dyn for<'a> Fn(&'a mut ScenarioSpec, usize) -> Option<Slot<'a>> + Send + Sync;

/// One number of a scenario: see the module docs.
pub struct Row {
    pub section: Section,
    /// The table inside the element the field sits in (`["pinion", "material"]`).
    pub table: &'static [&'static str],
    pub field: &'static Field,
    pub default: Default,
    /// The doc line of `scenarios/README.md`'s table.
    pub doc: &'static str,
    slot: Box<SlotFn>,
    pub fast: Fast,
    pub calibration: Option<Calibration>,
}

impl std::fmt::Debug for Row {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Row({})", self.pattern())
    }
}

/// A row is itself: two rows are equal when they are one.
impl PartialEq for Row {
    fn eq(&self, other: &Row) -> bool {
        std::ptr::eq(self, other)
    }
}

impl Row {
    /// The row's slot in element `e` of `spec`; None when the scenario does not have
    /// this number (a TLE orbit's altitude, a strain law given otherwise). May add an
    /// absent optional table (`[attitude]`) to hold the slot: read through a copy.
    pub fn slot<'a>(&self, spec: &'a mut ScenarioSpec, e: usize) -> Option<Slot<'a>> {
        (self.slot)(spec, e)
    }

    /// `section.<element>.table.field` with `<…>` for the element, as the README shows.
    pub fn pattern(&self) -> String {
        let mut s = self.section.name().to_string();
        if self.section.keys(&ElementKeys::default()).is_some() {
            s.push_str(".<name>");
        }
        for t in self.table {
            s.push('.');
            s.push_str(t);
        }
        s.push('.');
        s.push_str(self.field.name);
        s
    }
}

/// Every row, in listing order.
pub fn rows() -> &'static [Row] {
    static ROWS: LazyLock<Vec<Row>> = LazyLock::new(|| {
        let mut t = rows::table();
        gear_rows::gear_pairs(&mut t);
        t
    });
    &ROWS
}

/// A row with no fast write and no calibration (add them with [`Row::fast`] and
/// [`Row::calibrated`]).
fn row<F>(
    section: Section,
    table: &'static [&'static str],
    field: &'static Field,
    doc: &'static str,
    slot: F,
) -> Row
where
    F: for<'a> Fn(&'a mut ScenarioSpec, usize) -> Option<Slot<'a>> + Send + Sync + 'static,
{
    Row {
        section,
        table,
        field,
        default: Default::OfQuantity,
        doc,
        slot: Box::new(slot),
        fast: Fast::Recompile,
        calibration: None,
    }
}

impl Row {
    fn fast(mut self, f: FastFn) -> Row {
        self.fast = Fast::Direct(f);
        self
    }

    fn calibrated(mut self, c: Calibration) -> Row {
        self.calibration = Some(c);
        self
    }

    fn earth_view_factor(mut self) -> Row {
        self.default = Default::EarthViewFactor;
        self
    }

    fn gear_pair(mut self) -> Row {
        self.fast = Fast::GearPair;
        self
    }
}

/// The index of the row of `field` in `section` and `table`.
pub fn row_of(section: Section, table: &[&str], field: &'static Field) -> usize {
    rows()
        .iter()
        .position(|r| r.section == section && r.table == table && std::ptr::eq(r.field, field))
        .expect("a row of the registry")
}

/// One number of one scenario: a row, the element of its section (0 for a table) and
/// its place in the slot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ParamRef {
    pub row: usize,
    pub element: usize,
    pub sub: Sub,
}

impl ParamRef {
    pub fn row(&self) -> &'static Row {
        &rows()[self.row]
    }

    /// Its key path in a scenario with element keys `keys`.
    pub fn key_path(&self, keys: &ElementKeys) -> KeyPath {
        let element = self
            .row()
            .section
            .keys(keys)
            .map(|k| (self.element, k[self.element].as_str()));
        key_path(self.row, element, self.sub)
    }

    /// Its kind of number (a table's times have their own).
    pub fn quantity(&self) -> &'static Quantity {
        let row = self.row();
        match self.sub {
            Sub::Time(_) => &super::quantity::TABLE_TIME_S,
            Sub::Days(_) => &super::quantity::TABLE_TIME_DAYS,
            _ => row.field.quantity,
        }
    }
}

/// The key path of `sub` of `row` in the element at (position, key) of its section
/// (None: a table).
pub fn key_path(row: usize, element: Option<(usize, &str)>, sub: Sub) -> KeyPath {
    let row = &rows()[row];
    let mut p = row.section.path(element);
    for t in row.table {
        p = p.key(t);
    }
    p = row.field.key(&p);
    match sub {
        Sub::One => p,
        Sub::Item(i) => p.at(i),
        Sub::Time(i) => p.key(TIME_S).at(i),
        Sub::Days(i) => p.key(TIME_DAYS).at(i),
        Sub::Value(i) => p.key(VALUE).at(i),
        Sub::Window(i, j) => p.at(i).at(j),
    }
}

/// The profile table's keys (`environment.beta_deg.value[1]`).
pub const TIME_S: &str = "time_s";
pub const TIME_DAYS: &str = "time_days";
pub const VALUE: &str = "value";

/// A number's place, found from its slot and [`Sub`].
enum Place<'a> {
    Number(&'a mut f64),
    Optional(&'a mut Option<f64>),
    Integer(&'a mut i64),
    /// An absent optional profile: read as the default, written as a number.
    NewProfile(&'a mut Option<ProfileSpec>),
}

fn table_place(p: &mut ProfileSpec, sub: Sub) -> Option<Place<'_>> {
    match (p, sub) {
        (ProfileSpec::Constant(v), Sub::One) => Some(Place::Number(v)),
        (ProfileSpec::Table(t), Sub::Time(i)) => t.time_s.as_mut()?.get_mut(i).map(Place::Number),
        (ProfileSpec::Table(t), Sub::Days(i)) => {
            t.time_days.as_mut()?.get_mut(i).map(Place::Number)
        }
        (ProfileSpec::Table(t), Sub::Value(i)) => t.value.get_mut(i).map(Place::Number),
        _ => None,
    }
}

fn place(slot: Slot<'_>, sub: Sub) -> Option<Place<'_>> {
    match (slot, sub) {
        (Slot::Value(v), Sub::One) => Some(Place::Number(v)),
        (Slot::Optional(v), Sub::One) => Some(Place::Optional(v)),
        (Slot::Integer(v), Sub::One) => Some(Place::Integer(v)),
        (Slot::Profile(p), sub) => table_place(p, sub),
        (Slot::OptionalProfile(p), Sub::One) if p.is_none() => Some(Place::NewProfile(p)),
        (Slot::OptionalProfile(p), sub) => table_place(p.as_mut()?, sub),
        (Slot::List(l), Sub::Item(i)) => l.get_mut(i).map(Place::Number),
        (Slot::Windows(w), Sub::Window(i, j)) => w.get_mut(i)?.get_mut(j).map(Place::Number),
        _ => None,
    }
}

/// The places a slot holds, in listing order.
fn subs(slot: &Slot<'_>) -> Vec<Sub> {
    let table = |p: &ProfileSpec| match p {
        ProfileSpec::Constant(_) => vec![Sub::One],
        ProfileSpec::Table(t) => {
            let n = |v: &Option<Vec<f64>>| v.as_ref().map_or(0, Vec::len);
            (0..n(&t.time_s))
                .map(Sub::Time)
                .chain((0..n(&t.time_days)).map(Sub::Days))
                .chain((0..t.value.len()).map(Sub::Value))
                .collect()
        }
    };
    match slot {
        Slot::Value(_) | Slot::Optional(_) | Slot::Integer(_) => vec![Sub::One],
        Slot::Profile(p) => table(p),
        Slot::OptionalProfile(p) => p.as_ref().map_or(vec![Sub::One], table),
        Slot::List(l) => (0..l.len()).map(Sub::Item).collect(),
        Slot::Windows(w) => w
            .iter()
            .enumerate()
            .flat_map(|(i, x)| (0..x.len()).map(move |j| Sub::Window(i, j)))
            .collect(),
    }
}

/// What `row`'s absent value stands for in `spec` (None: nothing).
fn default_of(row: &Row, spec: &ScenarioSpec) -> Option<f64> {
    match row.default {
        Default::OfQuantity => row.field.quantity.default,
        Default::EarthViewFactor => Some(earth_view_factor(spec)),
    }
}

/// (R / (R + h))² of the spec's orbit.
fn earth_view_factor(spec: &ScenarioSpec) -> f64 {
    let r = spec
        .orbit
        .earth_radius_m
        .unwrap_or(super::quantity::EARTH_RADIUS_M.default_value());
    let radius = match (&spec.orbit.tle, spec.orbit.altitude_m) {
        (Some(lines), _) => lines
            .get(1)
            .and_then(|l| crate::orbit::tle::mean_radius_m(l))
            .unwrap_or(f64::NAN),
        (None, Some(h)) => r + h,
        (None, None) => f64::NAN,
    };
    (r / radius).powi(2)
}

/// A number's value read at its place, or what it stands for when absent.
fn value_at(place: &Place<'_>, row: &Row, spec: &ScenarioSpec) -> Option<f64> {
    match place {
        Place::Number(v) => Some(**v),
        Place::Integer(v) => Some(**v as f64),
        Place::Optional(Some(v)) => Some(*v),
        Place::Optional(None) | Place::NewProfile(_) => default_of(row, spec),
    }
}

/// One addressable value: its key path, its value (what an absent optional value
/// stands for, when it stands for one), unit and valid range.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    pub id: ParamRef,
    pub path: String,
    pub value: f64,
    pub unit: &'static str,
    pub range: String,
    /// Given in the scenario (false: a default).
    pub given: bool,
    pub quantity: &'static Quantity,
}

/// Every number of `spec` by key path, with unit and range; optional values that are
/// absent are listed with what they stand for, or left out when they stand for nothing
/// (the other form of a value given as a product, a duration given otherwise).
pub fn params(spec: &ScenarioSpec) -> Vec<Param> {
    let keys = element_keys(spec);
    let mut copy = spec.clone();
    let mut out = Vec::new();
    let all = rows();
    for section in Section::ALL {
        let count = section.keys(&keys).map_or(1, <[String]>::len);
        let rows: Vec<usize> = (0..all.len())
            .filter(|&r| all[r].section == section)
            .collect();
        for element in 0..count {
            for &r in &rows {
                let row = &all[r];
                let Some(slot) = row.slot(&mut copy, element) else {
                    continue;
                };
                for sub in subs(&slot) {
                    let id = ParamRef {
                        row: r,
                        element,
                        sub,
                    };
                    let Some(p) = row.slot(&mut copy, element).and_then(|s| place(s, sub)) else {
                        continue;
                    };
                    let given = matches!(p, Place::Number(_) | Place::Integer(_))
                        || matches!(p, Place::Optional(Some(_)));
                    let Some(value) = value_at(&p, row, spec) else {
                        continue;
                    };
                    let quantity = id.quantity();
                    out.push(Param {
                        id,
                        path: id.key_path(&keys).to_string(),
                        value,
                        unit: quantity.unit,
                        range: quantity.range(),
                        given,
                        quantity,
                    });
                }
            }
        }
    }
    out
}

/// A key path that does not lead to a number of the scenario, or a value that is not
/// one.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{key}`: {message}")]
pub struct ParamError {
    pub key: String,
    pub message: String,
}

fn unknown(text: &str, keys: &ElementKeys) -> ParamError {
    // name the elements of the section asked for, to help with typos (sensors are named
    // by their column, which the error already quotes)
    let hint = parse_path(text).ok().and_then(|parts| {
        let Some(Part::Key(first)) = parts.first() else {
            return None;
        };
        let section = Section::from_name(first).filter(|s| *s != Section::Sensor)?;
        if section == Section::Recording {
            // its one number exists only where the table does
            return Some(format!(
                " (recording: `{}`, in a [recording] table the scenario must have)",
                TIME_OFFSET_S.name
            ));
        }
        let known: Vec<String> = section.keys(keys)?.iter().map(|k| quote_key(k)).collect();
        Some(format!(" ({first}: {})", known.join(", ")))
    });
    ParamError {
        key: text.to_string(),
        message: format!(
            "no such number in this scenario{} (`orbitlash params` lists them)",
            hint.unwrap_or_default()
        ),
    }
}

/// The number `text` names in `spec` (with element keys `keys`), its path parsed once.
/// An optional value that is absent and stands for nothing is found too: reading it
/// fails, and writing it says which form the scenario uses.
pub fn resolve(
    spec: &ScenarioSpec,
    keys: &ElementKeys,
    text: &str,
) -> Result<ParamRef, ParamError> {
    let parts = parse_path(text).map_err(|message| ParamError {
        key: text.to_string(),
        message,
    })?;
    let key = |i: usize| match parts.get(i) {
        Some(Part::Key(k)) => Some(k.as_str()),
        _ => None,
    };
    let Some(section) = key(0).and_then(Section::from_name) else {
        return Err(unknown(text, keys));
    };
    let (element, rest) = match section.keys(keys) {
        Some(list) => {
            if let Some(Part::Index(i)) = parts.get(1) {
                return Err(ParamError {
                    key: text.to_string(),
                    message: format!("`[{i}]`: name the element by its key instead"),
                });
            }
            let Some(e) = key(1).and_then(|k| list.iter().position(|x| x == k)) else {
                return Err(unknown(text, keys));
            };
            (e, &parts[2..])
        }
        None => (0, &parts[1..]),
    };
    let mut copy = spec.clone();
    for (r, row) in rows().iter().enumerate() {
        if row.section != section {
            continue;
        }
        let Some(sub) = match_field(row, rest) else {
            continue;
        };
        if row
            .slot(&mut copy, element)
            .and_then(|s| place(s, sub))
            .is_some()
        {
            return Ok(ParamRef {
                row: r,
                element,
                sub,
            });
        }
    }
    Err(unknown(text, keys))
}

/// The row and element of a number that `text` names as itself ([`Sub::One`]),
/// whatever the scenario holds there (a profile table included).
pub fn locate(keys: &ElementKeys, text: &str) -> Option<(&'static Row, usize)> {
    let parts = parse_path(text).ok()?;
    let Some(Part::Key(first)) = parts.first() else {
        return None;
    };
    let section = Section::from_name(first)?;
    let (element, rest) = match section.keys(keys) {
        Some(list) => match parts.get(1) {
            Some(Part::Key(k)) => (list.iter().position(|x| x == k)?, &parts[2..]),
            _ => return None,
        },
        None => (0, &parts[1..]),
    };
    rows()
        .iter()
        .find(|r| r.section == section && match_field(r, rest) == Some(Sub::One))
        .map(|r| (r, element))
}

/// The [`Sub`] that `rest` (the parts after the element) names in `row`, if it names the
/// row's field.
fn match_field(row: &Row, rest: &[Part]) -> Option<Sub> {
    let n = row.table.len();
    let names = row.table.iter().copied().chain([row.field.name]);
    if rest.len() <= n {
        return None;
    }
    for (part, name) in rest.iter().zip(names) {
        if *part != Part::Key(name.to_string()) {
            return None;
        }
    }
    let key = |p: &Part, k: &str| matches!(p, Part::Key(x) if x == k);
    match &rest[n + 1..] {
        [] => Some(Sub::One),
        [Part::Index(i)] => Some(Sub::Item(*i)),
        [k, Part::Index(i)] if key(k, TIME_S) => Some(Sub::Time(*i)),
        [k, Part::Index(i)] if key(k, TIME_DAYS) => Some(Sub::Days(*i)),
        [k, Part::Index(i)] if key(k, VALUE) => Some(Sub::Value(*i)),
        [Part::Index(i), Part::Index(j)] => Some(Sub::Window(*i, *j)),
        _ => None,
    }
}

/// The value of `id` in `spec` (what an absent optional value stands for); None when it
/// is absent and stands for nothing.
pub fn value(spec: &ScenarioSpec, id: ParamRef) -> Option<f64> {
    let row = id.row();
    let mut copy = spec.clone();
    let p = place(row.slot(&mut copy, id.element)?, id.sub)?;
    value_at(&p, row, spec)
}

/// The value at `path` (what an absent optional value stands for).
pub fn get(spec: &ScenarioSpec, path: &str) -> Result<f64, ParamError> {
    let keys = element_keys(spec);
    let id = resolve(spec, &keys, path)?;
    value(spec, id).ok_or_else(|| unknown(path, &keys))
}

/// Writes `value` at `id`. Only that the value is a number of the slot's kind (an
/// integer for a number of teeth) and that the scenario gives this form of it are
/// checked here; whether the value is valid is the compiler's call (`spec::compile`),
/// so a value set by path and the same value in a TOML file give the same error.
pub fn write(spec: &mut ScenarioSpec, id: ParamRef, value: f64) -> Result<(), WriteError> {
    let row = id.row();
    let default = default_of(row, spec);
    let Some(p) = row.slot(spec, id.element).and_then(|s| place(s, id.sub)) else {
        return Err(WriteError::NoSuchNumber);
    };
    match p {
        Place::Number(v) => *v = value,
        Place::Integer(v) => {
            if value.fract() == 0.0 && value.abs() < 1e15 {
                *v = value as i64
            } else {
                return Err(WriteError::NotAnInteger(value));
            }
        }
        Place::Optional(v) => {
            if v.is_none() && default.is_none() {
                return Err(WriteError::OtherForm);
            }
            *v = Some(value);
        }
        Place::NewProfile(p) => *p = Some(ProfileSpec::Constant(value)),
    }
    Ok(())
}

/// Why a value could not be written at a number's place.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum WriteError {
    #[error("no such number in this scenario")]
    NoSuchNumber,
    /// A number of teeth.
    #[error("must be an integer (got {0})")]
    NotAnInteger(f64),
    /// An optional value standing for nothing: the scenario gives another form of it
    /// (α and A, not the product).
    #[error("is not given in this scenario (it uses another form of this value)")]
    OtherForm,
}

/// Writes `value` at `path` (see [`write`]).
pub fn set(spec: &mut ScenarioSpec, path: &str, value: f64) -> Result<(), ParamError> {
    let keys = element_keys(spec);
    let id = resolve(spec, &keys, path)?;
    write(spec, id, value).map_err(|e| ParamError {
        key: path.to_string(),
        message: e.to_string(),
    })
}

/// The number at `id` as it is before a write, to put back if the write is refused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Saved {
    Number(f64),
    Optional(Option<f64>),
}

/// Writes `value` at `id` (a [`Sub::One`] of a value or an optional value, as
/// [`write`] does) and returns what was there, to put back if the write is refused.
pub(crate) fn swap(
    spec: &mut ScenarioSpec,
    row: &Row,
    id: ParamRef,
    value: f64,
) -> Result<Saved, WriteError> {
    let stands_for_nothing =
        row.default == Default::OfQuantity && row.field.quantity.default.is_none();
    match row.slot(spec, id.element).and_then(|s| place(s, id.sub)) {
        Some(Place::Number(v)) => Ok(Saved::Number(std::mem::replace(v, value))),
        Some(Place::Optional(v)) if v.is_none() && stands_for_nothing => Err(WriteError::OtherForm),
        Some(Place::Optional(v)) => Ok(Saved::Optional(v.replace(value))),
        _ => unreachable!("a value or an optional value"),
    }
}

/// Puts a saved number back.
pub(crate) fn restore(spec: &mut ScenarioSpec, id: ParamRef, saved: Saved) {
    match (
        id.row()
            .slot(spec, id.element)
            .and_then(|s| place(s, id.sub)),
        saved,
    ) {
        (Some(Place::Number(v)), Saved::Number(x)) => *v = x,
        (Some(Place::Optional(v)), Saved::Optional(x)) => *v = x,
        _ => unreachable!("restored where it was saved"),
    }
}

/// Every row as a Markdown table (key path with `<name>` for the element, unit, range,
/// default, meaning): the key table of `scenarios/README.md`, which a test keeps equal
/// to this.
pub fn markdown_table() -> String {
    let mut s =
        String::from("| key path | unit | range | default | meaning |\n|---|---|---|---|---|\n");
    for row in rows() {
        let q = row.field.quantity;
        let default = match (row.default, q.default) {
            (Default::EarthViewFactor, _) => "(R/(R+h))²".to_string(),
            (Default::OfQuantity, Some(v)) => crate::units::exact(v),
            (Default::OfQuantity, None) => "–".to_string(),
        };
        let cell = |t: &str| {
            if t.is_empty() {
                "–".to_string()
            } else {
                t.replace('|', "\\|")
            }
        };
        s.push_str(&format!(
            "| `{}` | {} | {} | {} | {} |\n",
            row.pattern(),
            cell(q.unit),
            cell(&q.range()),
            default,
            cell(row.doc)
        ));
    }
    s
}

/// Parses `KEY=VALUE` (as `--set` takes it).
pub fn parse_assignment(text: &str) -> Result<(String, f64), ParamError> {
    let (key, value) = text.split_once('=').ok_or_else(|| ParamError {
        key: text.to_string(),
        message: format!(
            "give KEY=VALUE, e.g. {}=130",
            ParamRef {
                row: row_of(Section::Node, &[], &CAPACITANCE_J_PER_K),
                element: 0,
                sub: Sub::One,
            }
            .key_path(&ElementKeys {
                node: vec!["housing".into()],
                ..ElementKeys::default()
            })
        ),
    })?;
    let key = key.trim().to_string();
    let value = value.trim();
    let v = value
        .parse::<f64>()
        .ok()
        .or_else(|| toml_number(value))
        .ok_or_else(|| ParamError {
            key: key.clone(),
            message: format!("`{value}` is not a number"),
        })?;
    Ok((key, v))
}

/// A number as the scenario file may write it (TOML: `2_5`, `1_000.0`, `0x1F`), for
/// the values Rust's own parsing does not take.
fn toml_number(text: &str) -> Option<f64> {
    // one value, nothing after it
    if text.contains(['\n', '\r', '#', '=']) {
        return None;
    }
    match toml::from_str::<toml::Table>(&format!("v = {text}"))
        .ok()?
        .get("v")?
    {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_set_values_are_numbers_as_the_file_writes_them() {
        let v = |t: &str| parse_assignment(t).map(|(_, v)| v);
        assert_eq!(v("environment.beta_deg=2_5").unwrap(), 25.0);
        assert_eq!(v("environment.beta_deg=1_000.5").unwrap(), 1000.5);
        assert_eq!(v("environment.beta_deg=1e-3").unwrap(), 1e-3);
        for bad in ["2_5\nx = 3", "ten", "\"5\"", "5 # c", "[5]", "5 = 6"] {
            assert!(v(&format!("k={bad}")).is_err(), "{bad} taken");
        }
    }

    #[test]
    fn core_every_row_is_found_by_its_own_path() {
        for file in [
            "reference-hinge",
            "hinge-90-day-drift",
            "cubesat-1u",
            "hinge-tle-year",
            "funcube-1",
        ] {
            let text = std::fs::read_to_string(
                std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join(format!("scenarios/{file}.toml")),
            )
            .unwrap();
            let spec: ScenarioSpec = toml::from_str(&text).unwrap();
            let keys = element_keys(&spec);
            for p in params(&spec) {
                assert_eq!(
                    resolve(&spec, &keys, &p.path),
                    Ok(p.id),
                    "{file}: {}",
                    p.path
                );
                assert_eq!(get(&spec, &p.path), Ok(p.value), "{file}: {}", p.path);
            }
        }
    }

    #[test]
    fn core_no_two_rows_name_one_key() {
        let all = rows();
        for (i, a) in all.iter().enumerate() {
            for b in &all[..i] {
                assert!(
                    !(a.section == b.section && a.table == b.table && a.field == b.field),
                    "{} twice",
                    a.pattern()
                );
            }
        }
    }
}

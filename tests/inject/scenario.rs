//! `scenarios/funcube-1.toml` read as plain TOML data (the `toml` crate's `Table`): the
//! numbers of the network, the faces, the environment constants, the TLE and the
//! sensors. Nothing of orbitlash's scenario compiler is used; only the keys this file
//! uses are understood, and any other shape is a panic naming the key.

use toml::{Table, Value};

/// Path of the scenario the suite models.
pub const SCENARIO: &str = "scenarios/funcube-1.toml";

/// A linear conductor (W/K) or a radiative coupling (εA, m²) between two nodes.
#[derive(Clone, Debug)]
pub struct Link {
    pub a: usize,
    pub b: usize,
    pub value: f64,
}

/// An outer face: area, solar absorptivity, IR emissivity, and the node it belongs to.
#[derive(Clone, Debug)]
pub struct Face {
    pub name: String,
    pub node: usize,
    pub area_m2: f64,
    pub absorptivity: f64,
    pub emissivity: f64,
}

/// The lumped network: nodes (capacitance, initial temperature), conductors, radiative
/// couplings, faces and the constant dissipation per node.
#[derive(Clone, Debug)]
pub struct Network {
    pub names: Vec<String>,
    pub capacitance_j_per_k: Vec<f64>,
    pub initial_k: Vec<f64>,
    pub conductors: Vec<Link>,
    pub radiation: Vec<Link>,
    pub faces: Vec<Face>,
    pub dissipation_w: Vec<f64>,
}

/// A telemetry column and the node it reads (directly or through its face).
#[derive(Clone, Debug)]
pub struct Sensor {
    /// The column as the telemetry spells it (`Black Chassis deg. C`).
    pub column: String,
    /// The channel name in diagnose's reports (`chassis_black_c`).
    pub name: String,
    pub node: usize,
}

/// Everything the suite takes from the scenario file.
#[derive(Clone, Debug)]
pub struct Spacecraft {
    pub net: Network,
    pub sensors: Vec<Sensor>,
    /// Solar flux at 1 AU, W/m².
    pub solar_flux_1au_w_per_m2: f64,
    pub albedo: f64,
    pub earth_ir_w_per_m2: f64,
    pub sink_k: f64,
    /// The two TLE lines (used for the mean motion and, in a cross-check, the plane).
    pub tle: [String; 2],
    /// `YYYY-MM-DDTHH:MM:SSZ`: time zero of the recording.
    pub start_utc: String,
    pub time_column: String,
    /// Seconds added to each time stamp: when a row was measured (the recording's
    /// clock offset, `[recording] time_offset_s`, 0 when absent).
    pub time_offset_s: f64,
}

fn num(t: &Table, key: &str) -> f64 {
    match t.get(key) {
        Some(Value::Float(x)) => *x,
        Some(Value::Integer(i)) => *i as f64,
        other => panic!("{SCENARIO}: `{key}` is {other:?}, not a number"),
    }
}

fn text<'a>(t: &'a Table, key: &str) -> &'a str {
    t.get(key)
        .and_then(Value::as_str)
        .unwrap_or_else(|| panic!("{SCENARIO}: `{key}` is missing or not a string"))
}

fn table<'a>(t: &'a Table, key: &str) -> &'a Table {
    t.get(key)
        .and_then(Value::as_table)
        .unwrap_or_else(|| panic!("{SCENARIO}: [{key}] is missing"))
}

/// The `[[key]]` array of tables (empty when absent).
fn tables<'a>(t: &'a Table, key: &str) -> Vec<&'a Table> {
    match t.get(key) {
        None => Vec::new(),
        Some(Value::Array(a)) => a
            .iter()
            .map(|v| {
                v.as_table()
                    .unwrap_or_else(|| panic!("{SCENARIO}: [[{key}]] holds a non-table"))
            })
            .collect(),
        Some(v) => panic!("{SCENARIO}: `{key}` is {v:?}, not [[{key}]]"),
    }
}

impl Network {
    /// Index of a node by name.
    pub fn index(&self, name: &str) -> usize {
        self.names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no node {name:?}; nodes are {:?}", self.names))
    }

    /// Index of a face by its name (`px`).
    pub fn face(&self, name: &str) -> usize {
        self.faces
            .iter()
            .position(|f| f.name == name)
            .unwrap_or_else(|| panic!("no face {name:?}"))
    }

    fn links(&self, doc: &Table, key: &str, value_key: &str) -> Vec<Link> {
        tables(doc, key)
            .into_iter()
            .map(|l| {
                let between = l
                    .get("between")
                    .and_then(Value::as_array)
                    .unwrap_or_else(|| panic!("{SCENARIO}: [[{key}]] without `between`"));
                let end = |k: usize| self.index(between[k].as_str().expect("a node name"));
                Link {
                    a: end(0),
                    b: end(1),
                    value: num(l, value_key),
                }
            })
            .collect()
    }

    /// The network of a scenario document.
    fn read(doc: &Table) -> Network {
        let nodes = tables(doc, "node");
        let mut net = Network {
            names: nodes.iter().map(|n| text(n, "name").to_string()).collect(),
            capacitance_j_per_k: nodes
                .iter()
                .map(|n| num(n, "capacitance_j_per_k"))
                .collect(),
            initial_k: nodes
                .iter()
                .map(|n| num(n, "initial_temperature_k"))
                .collect(),
            conductors: Vec::new(),
            radiation: Vec::new(),
            faces: Vec::new(),
            dissipation_w: vec![0.0; nodes.len()],
        };
        net.conductors = net.links(doc, "conductor", "conductance_w_per_k");
        net.radiation = net.links(doc, "radiation", "emissivity_area_m2");
        net.faces = tables(doc, "face")
            .into_iter()
            .map(|f| Face {
                name: text(f, "name").to_string(),
                node: net.index(text(f, "node")),
                area_m2: num(f, "area_m2"),
                absorptivity: num(f, "absorptivity"),
                emissivity: num(f, "emissivity"),
            })
            .collect();
        for d in tables(doc, "dissipation") {
            let i = net.index(text(d, "node"));
            net.dissipation_w[i] += num(d, "power_w");
        }
        net
    }
}

impl Spacecraft {
    /// Reads the scenario file at `path`. Panics on a missing key or a shape this reader
    /// does not know (e.g. `[attitude] mode` other than `tumble`).
    pub fn read(path: &std::path::Path) -> Spacecraft {
        let src =
            std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let doc: Table = toml::from_str(&src).unwrap_or_else(|e| panic!("{SCENARIO}: {e}"));
        let attitude = text(table(&doc, "attitude"), "mode");
        assert_eq!(
            attitude, "tumble",
            "this model knows the tumble attitude only"
        );
        let net = Network::read(&doc);
        let sensors = tables(&doc, "sensor")
            .into_iter()
            .map(|s| {
                let node = match (s.get("node"), s.get("face")) {
                    (Some(n), None) => net.index(n.as_str().expect("a node name")),
                    (None, Some(f)) => net.faces[net.face(f.as_str().expect("a face"))].node,
                    _ => panic!("{SCENARIO}: a [[sensor]] needs `node` or `face`"),
                };
                let column = text(s, "column").to_string();
                let name = s
                    .get("name")
                    .and_then(Value::as_str)
                    .map_or_else(|| column.clone(), str::to_string);
                Sensor { column, name, node }
            })
            .collect();
        let env = table(&doc, "environment");
        let orbit = table(&doc, "orbit");
        let tle: Vec<String> = orbit
            .get("tle")
            .and_then(Value::as_array)
            .expect("[orbit] tle")
            .iter()
            .map(|l| l.as_str().expect("a TLE line").to_string())
            .collect();
        Spacecraft {
            net,
            sensors,
            solar_flux_1au_w_per_m2: num(env, "solar_flux_w_per_m2"),
            albedo: num(env, "albedo"),
            earth_ir_w_per_m2: num(env, "earth_ir_w_per_m2"),
            sink_k: num(env, "space_sink_k"),
            tle: [tle[0].clone(), tle[1].clone()],
            start_utc: text(orbit, "start_utc").to_string(),
            time_column: text(table(&doc, "recording"), "time_column").to_string(),
            time_offset_s: table(&doc, "recording")
                .get("time_offset_s")
                .map_or(0.0, |_| num(table(&doc, "recording"), "time_offset_s")),
        }
    }

    /// Index of a sensor by its channel name (`panel_mx_c`) or its column.
    pub fn sensor(&self, channel: &str) -> usize {
        self.sensors
            .iter()
            .position(|s| s.name == channel || s.column == channel)
            .unwrap_or_else(|| panic!("no sensor {channel:?}"))
    }
}

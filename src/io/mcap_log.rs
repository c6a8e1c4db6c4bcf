//! MCAP run log (first version: JSON messages with a JSON schema per channel).
//!
//! Log time is simulated time since t = 0 in integer nanoseconds, never wall clock,
//! so two runs of the same scenario produce identical files. Field names are node
//! names with `.` replaced by `_` and a unit suffix (`gear1_r2_k`).

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::{Map, Value, json};

use super::atomic::{AtomicFile, OutputError};
use super::csv_export::{gear_column_names, gear_values};
use crate::sim::{Event, EventKind, Observer, ObserverResult, RunStart, RunStats, StepView};

/// Provenance stored in the log's metadata record and attachment.
#[derive(Debug, Clone)]
pub struct Provenance {
    pub scenario_name: String,
    pub scenario_file: String,
    pub scenario_toml: String,
    pub solver: String,
}

pub struct McapLog {
    writer: Option<mcap::Writer<AtomicFile>>,
    provenance: Provenance,
    channels: Channels,
    names: Names,
    seq: u32,
}

#[derive(Default)]
struct Channels {
    temperature: u16,
    orbit: u16,
    heat: u16,
    log: u16,
    gears: u16,
}

#[derive(Default)]
struct Names {
    nodes: Vec<String>,
    loads: Vec<String>,
    heaters: Vec<String>,
    modes: Vec<String>,
    heater_power_w: Vec<f64>,
    period_s: f64,
    gear_fields: Vec<String>,
    pairs: Vec<String>,
}

/// A field name from a node or load name and a unit: `.` and `-` become `_`.
pub fn field_name(name: &str, unit: &str) -> String {
    format!("{}_{unit}", sanitize(name))
}

/// Every character but ASCII letters and digits becomes `_`.
pub fn sanitize(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

fn ns(t_s: f64) -> u64 {
    (t_s * 1e9).round().max(0.0) as u64
}

fn number_schema(title: &str, fields: &[String]) -> Vec<u8> {
    let props: Map<String, Value> = fields
        .iter()
        .map(|f| (f.clone(), json!({"type": "number"})))
        .collect();
    serde_json::to_vec(&json!({"title": title, "type": "object", "properties": props}))
        .expect("json")
}

impl McapLog {
    pub fn create(path: &Path, provenance: Provenance) -> Result<McapLog, OutputError> {
        let file = AtomicFile::create(path)?;
        let writer = mcap::WriteOptions::new()
            .library(format!("orbitlash {}", env!("CARGO_PKG_VERSION")))
            .create(file)
            .map_err(|e| OutputError {
                path: path.display().to_string(),
                source: std::io::Error::other(e),
            })?;
        Ok(McapLog {
            writer: Some(writer),
            provenance,
            channels: Channels::default(),
            names: Names::default(),
            seq: 0,
        })
    }

    fn w(&mut self) -> &mut mcap::Writer<AtomicFile> {
        self.writer.as_mut().expect("log open")
    }

    fn write(&mut self, channel: u16, t_s: f64, msg: &Value) -> ObserverResult {
        let data = serde_json::to_vec(msg)?;
        self.seq += 1;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.seq,
            log_time: ns(t_s),
            publish_time: ns(t_s),
        };
        self.w().write_to_known_channel(&header, &data)?;
        Ok(())
    }

    fn log(&mut self, t_s: f64, level: u8, message: String) -> ObserverResult {
        let secs = t_s.floor();
        let msg = json!({
            "timestamp": {"sec": secs as u64, "nsec": ((t_s - secs) * 1e9).round() as u64},
            "level": level,
            "message": message,
            "name": "orbitlash",
            "file": "",
            "line": 0
        });
        self.write(self.channels.log, t_s, &msg)
    }
}

const FOXGLOVE_LOG_SCHEMA: &str = r#"{"title":"foxglove.Log","type":"object","properties":{"timestamp":{"type":"object","properties":{"sec":{"type":"integer","minimum":0},"nsec":{"type":"integer","minimum":0,"maximum":999999999}}},"level":{"type":"integer"},"message":{"type":"string"},"name":{"type":"string"},"file":{"type":"string"},"line":{"type":"integer","minimum":0}}}"#;

impl Observer for McapLog {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        let model = r.model;
        let temps_k = r.temps_k;
        let net = &model.network;
        self.names = Names {
            nodes: net.nodes.iter().map(|n| field_name(&n.name, "k")).collect(),
            loads: net.loads.iter().map(|l| field_name(&l.name, "w")).collect(),
            heaters: net
                .heaters
                .iter()
                .map(|h| field_name(&h.name, "w"))
                .collect(),
            modes: model.modes.iter().map(|m| m.name.clone()).collect(),
            heater_power_w: net.heaters.iter().map(|h| h.power_w).collect(),
            period_s: model.environment.orbit.period_s(),
            gear_fields: gear_column_names(r.gears)
                .iter()
                .map(|c| sanitize(c))
                .collect(),
            pairs: r.gears.iter().map(|g| g.name.clone()).collect(),
        };
        let gear_fields = self.names.gear_fields.clone();
        let mut temp_fields = vec!["time_s".to_string()];
        temp_fields.extend(self.names.nodes.iter().cloned());
        let mut heat_fields = self.names.loads.clone();
        heat_fields.extend(self.names.heaters.iter().cloned());
        let orbit_fields: Vec<String> = [
            "orbit_angle_deg",
            "beta_deg",
            "solar_flux_w_per_m2",
            "sunlit",
            "orbit_number",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let empty = BTreeMap::new();
        let p = self.provenance.clone();
        let w = self.w();
        let s = w.add_schema(
            "orbitlash.NodeTemperatures",
            "jsonschema",
            &number_schema("orbitlash.NodeTemperatures", &temp_fields),
        )?;
        let temperature = w.add_channel(s, "/thermal/temperature", "json", &empty)?;
        let s = w.add_schema(
            "orbitlash.HeatFlows",
            "jsonschema",
            &number_schema("orbitlash.HeatFlows", &heat_fields),
        )?;
        let heat = w.add_channel(s, "/thermal/heat", "json", &empty)?;
        let s = w.add_schema(
            "orbitlash.OrbitState",
            "jsonschema",
            &number_schema("orbitlash.OrbitState", &orbit_fields),
        )?;
        let orbit = w.add_channel(s, "/orbit/state", "json", &empty)?;
        let s = w.add_schema("foxglove.Log", "jsonschema", FOXGLOVE_LOG_SCHEMA.as_bytes())?;
        let log = w.add_channel(s, "/events", "json", &empty)?;
        let s = w.add_schema(
            "orbitlash.GearMesh",
            "jsonschema",
            &number_schema("orbitlash.GearMesh", &gear_fields),
        )?;
        let gears = w.add_channel(s, "/gears/mesh", "json", &empty)?;
        let metadata: BTreeMap<String, String> = [
            ("tool", "orbitlash".to_string()),
            ("tool_version", env!("CARGO_PKG_VERSION").to_string()),
            ("scenario_name", p.scenario_name.clone()),
            ("scenario_file", p.scenario_file.clone()),
            ("solver", p.solver.clone()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        w.write_metadata(&mcap::records::Metadata {
            name: "orbitlash.provenance".into(),
            metadata,
        })?;
        w.attach(&mcap::Attachment {
            log_time: 0,
            create_time: 0,
            name: format!("{}.toml", p.scenario_name),
            media_type: "application/toml".into(),
            data: std::borrow::Cow::Owned(p.scenario_toml.into_bytes()),
        })?;
        self.channels = Channels {
            temperature,
            orbit,
            heat,
            log,
            gears,
        };
        let mut m = Map::new();
        m.insert("time_s".into(), json!(0.0));
        for (f, &v) in self.names.nodes.iter().zip(temps_k) {
            m.insert(f.clone(), json!(v));
        }
        self.write(temperature, 0.0, &Value::Object(m))
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let t = step.t1_s();
        let mut m = Map::new();
        m.insert("time_s".into(), json!(t));
        for (f, &v) in self.names.nodes.iter().zip(step.temps1_k()) {
            m.insert(f.clone(), json!(v));
        }
        self.write(self.channels.temperature, t, &Value::Object(m))?;
        let mut h = Map::new();
        for (f, &v) in self.names.loads.iter().zip(step.load_w) {
            h.insert(f.clone(), json!(v));
        }
        for ((f, &on), &p) in self
            .names
            .heaters
            .iter()
            .zip(step.heaters_on)
            .zip(&self.names.heater_power_w)
        {
            h.insert(f.clone(), json!(if on { p } else { 0.0 }));
        }
        self.write(self.channels.heat, t, &Value::Object(h))?;
        let e = &step.env1;
        let orbit = json!({
            "orbit_angle_deg": e.orbit_angle_rad.to_degrees().rem_euclid(360.0),
            "beta_deg": e.beta_rad.to_degrees(),
            "solar_flux_w_per_m2": e.solar_flux_w_per_m2,
            "sunlit": if e.sunlit { 1.0 } else { 0.0 },
            "orbit_number": (t / self.names.period_s).floor() + 1.0,
        });
        self.write(self.channels.orbit, t, &orbit)?;
        if !step.mesh.is_empty() {
            let mut g = Map::new();
            let values = step.mesh.iter().flat_map(gear_values);
            for (f, v) in self.names.gear_fields.iter().zip(values) {
                g.insert(f.clone(), json!(v));
            }
            self.write(self.channels.gears, t, &Value::Object(g))?;
        }
        Ok(())
    }

    fn on_event(&mut self, event: &Event) -> ObserverResult {
        let text = match event.kind {
            EventKind::EclipseEntry => "eclipse entry".to_string(),
            EventKind::EclipseExit => "eclipse exit".to_string(),
            EventKind::HeaterOn(k) => {
                format!("heater {} on", self.names.heaters[k].trim_end_matches("_w"))
            }
            EventKind::HeaterOff(k) => format!(
                "heater {} off",
                self.names.heaters[k].trim_end_matches("_w")
            ),
            EventKind::ModeStart(k) => format!("mode {} start", self.names.modes[k]),
            EventKind::ModeEnd(k) => format!("mode {} end", self.names.modes[k]),
            EventKind::MarginLow(k) => format!(
                "gear pair {}: backlash below the minimum allowed",
                self.names.pairs[k]
            ),
            EventKind::MarginRestored(k) => format!(
                "gear pair {}: backlash margin restored",
                self.names.pairs[k]
            ),
            EventKind::InterferenceStart(k) => format!(
                "gear pair {}: interference (backlash ≤ 0)",
                self.names.pairs[k]
            ),
            EventKind::InterferenceEnd(k) => {
                format!("gear pair {}: interference ended", self.names.pairs[k])
            }
            EventKind::MeshInvalid(k) => {
                format!("gear pair {}: no valid mesh", self.names.pairs[k])
            }
        };
        self.log(event.t_s, 2, text)
    }

    fn on_finish(&mut self, stats: &RunStats) -> ObserverResult {
        if stats.interrupted {
            self.log(
                stats.t_end_s,
                3,
                format!("run interrupted at t = {:.1} s", stats.t_end_s),
            )?;
        }
        let mut w = self.writer.take().expect("log open");
        w.finish()?;
        let file = w.into_inner();
        file.commit()?;
        Ok(())
    }
}

//! MCAP run log with protobuf messages whose schemas are stored in the file, so that
//! Foxglove and Rerun (whose MCAP importer decodes protobuf by reflection) plot every
//! series by name.
//!
//! Topics (field names carry units):
//! - `/thermal/temperature`: `time_s`, then `<node>_k` for every diffusion node
//!   (node names lower-cased with `.` → `_`; the channel metadata maps each field back
//!   to its node name as `node:<field>`);
//! - `/thermal/temperature_c`: the same temperatures in °C, `<node>_c` (no `time_s`),
//!   for viewers that plot a field as it is (Foxglove's message paths cannot add an
//!   offset); the channel metadata maps each field to its node as `node:<field>`;
//! - `/thermal/heat`: `absorbed_w`, `dissipated_w`, `to_<boundary>_w`, then
//!   `<load>_w` for every load and `<heater>_w` for every heater;
//! - `/orbit/state`: `orbit_angle_deg` (from orbit noon), `beta_deg`,
//!   `solar_flux_w_per_m2` (the flux that reaches the spacecraft: S at its distance
//!   from the Sun in sunlight, dimmed in a conical shadow's penumbra, 0 in the umbra),
//!   `sunlit` (1 when some of the Sun reaches it, that is the flux > 0; else 0),
//!   `orbit_number`;
//! - `/orbit/faces` (scenarios with `[[face]]`s): per face the incident flux before
//!   absorptivity, `<node>_<face>_solar_w_per_m2`, `…_albedo_w_per_m2`,
//!   `…_earth_ir_w_per_m2` (as `orbitlash environment --csv` writes them; the channel
//!   metadata maps each field to `<node>.<face>.…` as `face:<field>`);
//! - `/gears/<pair>`: exact / closed-form / paper backlash and margin (µm),
//!   operating pressure angle, centre distance, contact ratio, and per gear (`pinion`,
//!   `wheel`) the base-circle displacement, base radius, base pitch, base tooth
//!   thickness, tip radius, coating, and the radial profile (`radius_mm[]`,
//!   `temperature_k[]`);
//! - `/events`: `foxglove.Log` (eclipse entry/exit, heater on/off, mode changes, margin
//!   and interference, run end).
//!
//! Log time is simulated time since t = 0 in integer nanoseconds, never wall clock, so
//! two runs of the same scenario give identical bytes. The scenario file is attached
//! and a metadata record `orbitlash.provenance` names the tool version, scenario and
//! its SHA-256, solver and settings; `orbitlash.run_end` says how the run ended.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use super::atomic::{AtomicFile, OutputError, OutputPolicy};
use super::log_schema::{Kind, MessageType, descriptor_set, identifier, ns};
use super::protobuf::Encoder;
use super::scene;
use crate::gear::{GearPair, MeshState};
use crate::run::sample::{Cadence, Sample, Sampler, Want};
use crate::run::sim::{Event, EventKind, Observer, ObserverResult, RunStart, RunStats, StepView};
use crate::run::summary::{EclipseWindows, MeshStats, RunEnd, SmallestSamples};
use crate::thermal::ThermalModel;

/// How often the log records the state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LogCadence {
    /// Every n-th accepted step (1 = every step).
    Steps(u64),
    /// Every `dt` seconds of simulated time, from the solver's interpolant, at most
    /// once per accepted step (the last multiple of `dt` the step reaches): where the
    /// steps are longer than `dt` the log follows them, so it is never bigger than
    /// logging every step.
    Interval(f64),
}

/// Shortest log interval, s (`--log-every 0.001s`).
pub const MIN_LOG_INTERVAL_S: f64 = 1e-3;

impl std::str::FromStr for LogCadence {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || {
            format!("`{s}` is neither a step count (e.g. 10) nor an interval in seconds (e.g. 60s)")
        };
        if let Some(secs) = s.strip_suffix('s') {
            let v: f64 = secs.trim().parse().map_err(|_| bad())?;
            if !v.is_finite() {
                return Err(bad());
            }
            if v < MIN_LOG_INTERVAL_S {
                return Err(format!(
                    "`{s}`: the log interval must be at least {MIN_LOG_INTERVAL_S} s"
                ));
            }
            return Ok(LogCadence::Interval(v));
        }
        match s.trim().parse::<u64>() {
            Ok(n) if n > 0 => Ok(LogCadence::Steps(n)),
            _ => Err(bad()),
        }
    }
}

impl LogCadence {
    /// The sampling cadence of the log.
    pub fn cadence(&self) -> Cadence {
        match *self {
            LogCadence::Steps(n) => Cadence::Steps(n),
            LogCadence::Interval(dt) => Cadence::IntervalAtMostPerStep(dt),
        }
    }

    /// Samples a run of `steps` accepted steps over `t_end_s` logs.
    pub fn samples(&self, steps: f64, t_end_s: f64) -> f64 {
        1.0 + match *self {
            LogCadence::Steps(n) => steps / n as f64,
            LogCadence::Interval(dt) => (t_end_s / dt).min(steps),
        }
    }
}

/// Bytes one logged sample takes in the file (every topic, MCAP record and message
/// index entries), from the encoding rules, without the 3-D view. Within a few per
/// cent of the real size (tested in `tests/cli_bounds.rs`).
pub fn estimated_bytes_per_sample(model: &ThermalModel, gears: &[GearPair]) -> f64 {
    fn varint_len(v: u64) -> u64 {
        (64 - (v | 1).leading_zeros() as u64).div_ceil(7)
    }
    let key = |f: u64| varint_len(f << 3);
    let doubles = |count: u64| (1..=count).map(|f| key(f) + 8).sum::<u64>();
    // opcode, length, channel, sequence, two times; then a message-index entry.
    let record = 1 + 8 + 2 + 4 + 8 + 8 + 16;
    let net = &model.network;
    let temperature = doubles(net.nodes.len() as u64 + 1);
    let heat = doubles((2 + net.boundaries.len() + net.loads.len() + net.heaters.len()) as u64);
    let orbit = doubles(5);
    let faces = net.face_loads().count() as u64;
    let celsius = doubles(net.nodes.len() as u64);
    let mut total = 4 * record + temperature + celsius + heat + orbit;
    if faces > 0 {
        total += record + doubles(3 * faces);
    }
    for pair in gears {
        let mut body = doubles(7);
        for (k, g) in pair.gears.iter().enumerate() {
            let nodes = g.nodes.len() as u64;
            let packed = 2 * (1 + varint_len(8 * nodes) + 8 * nodes);
            let inner = doubles(6) + packed;
            body += key(8 + k as u64) + varint_len(inner) + inner;
        }
        total += record + body;
    }
    total as f64
}

/// Provenance stored in the log's metadata record and attachment.
#[derive(Debug, Clone)]
pub struct Provenance {
    pub scenario_name: String,
    pub scenario_file: String,
    pub scenario_toml: String,
    pub solver: String,
    pub seed: Option<u64>,
    /// `--set` changes applied to the attached scenario, in order.
    pub sets: Vec<(String, f64)>,
}

#[derive(Default)]
struct Channels {
    temperature: u16,
    /// `/thermal/temperature_c`.
    celsius: u16,
    heat: u16,
    orbit: u16,
    /// `/orbit/faces`, when the model has faces.
    faces: Option<u16>,
    gears: Vec<u16>,
    scenes: Vec<u16>,
    log: u16,
}

/// The optional 3-D view (`--scene`).
struct SceneState {
    interval_s: f64,
    next_s: f64,
    outlines: Vec<[scene::PlacedOutline; 2]>,
    /// Scene entity identifiers, per pair.
    names: Vec<String>,
}

/// Owns the MCAP writer and turns samples (values the run evaluated: temperatures,
/// switch states, heat flows, environment, mesh states) into messages. It runs on its
/// own thread once the run has started, so the simulation only copies numbers per
/// sample; records arrive in order, so the file is the same as if written inline.
struct LogWriter {
    /// Log time of t = 0, ns (see `LogDescription::time_origin_ns`).
    origin_ns: u64,
    path: PathBuf,
    writer: mcap::Writer<AtomicFile>,
    ch: Channels,
    enc: Encoder,
    seq: u32,
    pairs: Vec<PairLayout>,
    scene: Option<SceneState>,
}

/// What the writer needs to know of a gear pair: fixed geometry, not a model.
#[derive(Debug, Clone)]
struct PairLayout {
    /// Per gear (pinion, wheel): its nodes, inner to rim, and their radii, mm.
    nodes: [Vec<usize>; 2],
    radii_mm: [Vec<f64>; 2],
}

/// Names and fixed geometry the log's schemas and messages are made from, taken from the
/// model when the run starts.
struct LogDescription {
    nodes: Vec<String>,
    boundaries: Vec<String>,
    loads: Vec<String>,
    heaters: Vec<String>,
    /// Each face as `<node>.<face>`, in load order.
    faces: Vec<String>,
    pair_names: Vec<String>,
    pairs: Vec<PairLayout>,
    outlines: Vec<[scene::PlacedOutline; 2]>,
    /// Log time of t = 0, ns since the Unix epoch: the start's UTC for a dated
    /// scenario (viewers then show real dates), 0 otherwise.
    time_origin_ns: u64,
}

/// Layout of one sample in a batch: t, sunlit, temperatures, heater states, mode
/// states, heat flows (absorbed, dissipated, to each boundary, each load, each
/// heater), orbit (angle, β, solar flux, orbit number), then per face its solar,
/// albedo and Earth-IR flux.
#[derive(Debug, Clone, Copy, Default)]
struct Layout {
    nodes: usize,
    heaters: usize,
    modes: usize,
    boundaries: usize,
    loads: usize,
    faces: usize,
}

impl Layout {
    fn flows(&self) -> usize {
        2 + self.boundaries + self.loads + self.heaters
    }
    fn stride(&self) -> usize {
        2 + self.nodes + self.heaters + self.modes + self.flows() + 4 + 3 * self.faces
    }
}

enum Item {
    /// A sample at this offset of `Batch::values`, its gear states from this index of
    /// `Batch::meshes`.
    Sample(usize, usize),
    Event {
        t_s: f64,
        level: i64,
        text: String,
    },
}

#[derive(Default)]
struct Batch {
    values: Vec<f64>,
    meshes: Vec<MeshState>,
    items: Vec<Item>,
}

enum ToWriter {
    Batch(Batch),
    Finish(BTreeMap<String, String>),
}

struct WriterThread {
    tx: std::sync::mpsc::SyncSender<ToWriter>,
    handle: std::thread::JoinHandle<Result<PathBuf, OutputError>>,
    failed: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

/// Samples handed to the writer thread at a time.
const BATCH_SAMPLES: usize = 256;
/// A batch waits for a held sample (a smallest backlash still falling) up to this many
/// items; past it the held sample goes out as it is.
const MAX_HELD_BATCH: usize = 4096;

enum State {
    /// Created, before the run starts.
    Open(Box<mcap::Writer<AtomicFile>>),
    Running(WriterThread),
    /// Finished: the file is under its name (true) or was not written (false).
    Closed(bool),
}

pub struct McapLog {
    path: PathBuf,
    state: State,
    cadence: LogCadence,
    provenance: Provenance,
    layout: Layout,
    batch: Batch,
    sampler: Sampler,
    names: Names,
    scene_interval_s: Option<f64>,
    /// End of the last step the log saw: a failure with no time of its own is dated here.
    last_t_s: f64,
    /// The run's own statistics of each pair (every step probed inside, not only at
    /// samples): the end record's verdict and smallest backlash come from them. Per
    /// pair, the sample at a new smallest backlash is held until a step no longer
    /// lowers it, then goes into the log in time order.
    smallest: SmallestSamples,
    eclipses: EclipseWindows,
    /// Each pair's smallest allowed backlash, m.
    min_allowed_m: Vec<f64>,
    /// Time of the last sample pushed, s.
    last_logged_s: f64,
    /// The last step's end values, and the model and gears they are completed with
    /// when the run ends (completed, interrupted or failed) and the log has no sample
    /// there yet.
    last_end: Sample,
    end_model: Option<Box<(ThermalModel, Vec<GearPair>)>>,
}

/// Key of the provenance record holding the log time of t = 0 (ns since the Unix
/// epoch) in a dated scenario's log; absent, log times count from t = 0.
pub const TIME_ORIGIN_KEY: &str = "time_origin_unix_ns";

fn out_err(path: &Path, e: mcap::McapError) -> OutputError {
    OutputError::mcap(path, e)
}

impl LogWriter {
    fn write_encoded(&mut self, channel: u16, t_s: f64) -> Result<(), OutputError> {
        self.seq += 1;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.seq,
            log_time: self.origin_ns + ns(t_s),
            publish_time: self.origin_ns + ns(t_s),
        };
        let r = self.writer.write_to_known_channel(&header, &self.enc.buf);
        self.enc.clear();
        r.map_err(|e| out_err(&self.path, e))
    }

    /// Writes a foxglove message (the official crate's encoding).
    fn write_foxglove(
        &mut self,
        channel: u16,
        t_s: f64,
        m: &impl foxglove::Encode,
    ) -> Result<(), OutputError> {
        self.enc.clear();
        m.encode(&mut self.enc.buf)
            .map_err(|e| OutputError::other(&self.path, e))?;
        self.write_encoded(channel, t_s)
    }

    fn event(&mut self, t_s: f64, level: i64, message: &str) -> Result<(), OutputError> {
        let log = foxglove::messages::Log {
            timestamp: Some(scene::timestamp_at(self.origin_ns, t_s)),
            level: level as i32,
            message: message.into(),
            name: "orbitlash".into(),
            file: String::new(),
            line: 0,
        };
        self.write_foxglove(self.ch.log, t_s, &log)
    }

    /// Writes every topic for one sample laid out as `Layout` says.
    fn sample(
        &mut self,
        layout: Layout,
        v: &[f64],
        meshes: &[MeshState],
    ) -> Result<(), OutputError> {
        let t_s = v[0];
        let temps = &v[2..2 + layout.nodes];
        let flows_at = 2 + layout.nodes + layout.heaters + layout.modes;
        let flows = &v[flows_at..flows_at + layout.flows()];
        let orbit = &v[flows_at + layout.flows()..flows_at + layout.flows() + 4];
        let faces = &v[flows_at + layout.flows() + 4..];
        // Temperatures.
        self.enc.clear();
        self.enc.double(1, t_s);
        for (i, &t) in temps.iter().enumerate() {
            self.enc.double(i as u32 + 2, t);
        }
        self.write_encoded(self.ch.temperature, t_s)?;
        self.enc.clear();
        for (i, &t) in temps.iter().enumerate() {
            self.enc
                .double(i as u32 + 1, t - crate::constants::ZERO_CELSIUS_K);
        }
        self.write_encoded(self.ch.celsius, t_s)?;
        // Heat flows: absorbed, dissipated, each boundary, load and heater, in order.
        self.enc.clear();
        for (f, &q) in flows.iter().enumerate() {
            self.enc.double(f as u32 + 1, q);
        }
        self.write_encoded(self.ch.heat, t_s)?;
        // Orbit: angle, β, solar flux, sunlit, orbit number.
        self.enc.clear();
        self.enc.double(1, orbit[0]);
        self.enc.double(2, orbit[1]);
        self.enc.double(3, orbit[2]);
        self.enc.double(4, v[1]);
        self.enc.double(5, orbit[3]);
        self.write_encoded(self.ch.orbit, t_s)?;
        if let Some(ch) = self.ch.faces {
            self.enc.clear();
            for (f, &q) in faces.iter().enumerate() {
                self.enc.double(f as u32 + 1, q);
            }
            self.write_encoded(ch, t_s)?;
        }

        // Gear pairs.
        for (k, m) in meshes.iter().enumerate() {
            self.enc.clear();
            encode_mesh(&mut self.enc, &self.pairs[k], m, temps);
            self.write_encoded(self.ch.gears[k], t_s)?;
        }
        // The 3-D view, at its own interval.
        let due = match &mut self.scene {
            Some(sc) if t_s >= sc.next_s - 1e-9 => {
                while sc.next_s <= t_s + 1e-9 {
                    sc.next_s += sc.interval_s;
                }
                true
            }
            _ => false,
        };
        for k in 0..if due { self.pairs.len() } else { 0 } {
            let pair = &self.pairs[k];
            let rim = |g: usize| temps[*pair.nodes[g].last().expect("nodes")];
            let sc = self.scene.as_ref().expect("due");
            let update = scene::scene_update(
                &sc.names[k],
                &sc.outlines[k],
                [rim(0), rim(1)],
                t_s,
                ["pinion", "wheel"],
            );
            self.write_foxglove(self.ch.scenes[k], t_s, &update)?;
        }
        Ok(())
    }

    fn batch(&mut self, layout: Layout, b: &Batch) -> Result<(), OutputError> {
        for item in &b.items {
            match item {
                Item::Sample(at, mesh) => {
                    let meshes = &b.meshes[*mesh..*mesh + self.pairs.len()];
                    self.sample(layout, &b.values[*at..*at + layout.stride()], meshes)?
                }
                Item::Event { t_s, level, text } => self.event(*t_s, *level, text)?,
            }
        }
        Ok(())
    }

    fn finish(mut self, end: BTreeMap<String, String>) -> Result<PathBuf, OutputError> {
        let path = self.path.clone();
        self.writer
            .write_metadata(&mcap::records::Metadata {
                name: "orbitlash.run_end".into(),
                metadata: end,
            })
            .map_err(|e| out_err(&path, e))?;
        self.writer.finish().map_err(|e| out_err(&path, e))?;
        self.writer.into_inner().commit()
    }
}

impl McapLog {
    /// Opens the log (a temporary file until the run ends); fails now if `path`
    /// cannot be written.
    pub fn create(
        path: &Path,
        provenance: Provenance,
        cadence: LogCadence,
        policy: &OutputPolicy,
    ) -> Result<McapLog, OutputError> {
        let file = AtomicFile::create(path, policy)?;
        let writer = mcap::WriteOptions::new()
            .library(format!("orbitlash {}", env!("CARGO_PKG_VERSION")))
            .profile("")
            .compression(None)
            .chunk_size(Some(1 << 16))
            // a CRC per chunk lets readers (and `recover`) tell a flipped byte
            .calculate_chunk_crcs(true)
            .create(file)
            .map_err(|e| out_err(path, e))?;
        Ok(McapLog {
            path: path.to_path_buf(),
            state: State::Open(Box::new(writer)),
            cadence,
            provenance,
            layout: Layout::default(),
            batch: Batch::default(),
            sampler: Sampler::new(cadence.cadence(), Want::ALL),
            names: Names::default(),
            scene_interval_s: None,
            last_t_s: 0.0,
            smallest: SmallestSamples::new(MeshStats::last(f64::INFINITY)),
            eclipses: EclipseWindows::default(),
            min_allowed_m: Vec::new(),
            last_logged_s: f64::NEG_INFINITY,
            last_end: Sample::default(),
            end_model: None,
        })
    }

    /// Adds the 3-D view of the gear pairs (`foxglove.SceneUpdate` on
    /// `/gears/<pair>/scene`), one update every `interval_s` of simulated time.
    pub fn with_scene(mut self, interval_s: f64) -> McapLog {
        self.scene_interval_s = Some(interval_s);
        self
    }

    /// The pair statistics the log keeps (`mesh`: the window its `last` orbit covers,
    /// and the whole run); `run` reports from these instead of keeping a second copy.
    pub fn with_mesh_stats(mut self, mesh: MeshStats) -> McapLog {
        self.smallest.mesh = mesh;
        self
    }

    /// The run's pair statistics, as the log saw them.
    pub fn mesh_stats(&self) -> &MeshStats {
        &self.smallest.mesh
    }

    /// The end of the run as the `run_end` record says it (so far, before the end).
    pub fn run_end(&self, t_end_s: f64, complete: bool) -> RunEnd {
        RunEnd::new(
            &self.smallest.mesh.run_pairs,
            &self.min_allowed_m,
            self.eclipses.closed_at(t_end_s),
            complete,
        )
    }

    /// The held samples, then the last step's end (completed now) unless a sample is
    /// there: whatever ends the run, the log reaches its last step.
    fn release_end(&mut self) {
        self.release_held();
        let end = &mut self.last_end;
        if end.t_s > self.last_logged_s
            && let Some(m) = &self.end_model
        {
            let work = std::cell::RefCell::new(crate::run::sim::ProbeWork::default());
            let probe = crate::run::sim::Probe {
                model: &m.0,
                gears: &m.1,
                work: &work,
            };
            let mesh = std::mem::take(&mut end.mesh);
            probe.complete(Want::ALL, Some(&mesh), end);
            insert_sample(&mut self.batch, end);
            self.last_logged_s = end.t_s;
        }
    }

    fn send_batch(&mut self) -> ObserverResult {
        send_batch(&mut self.state, &mut self.batch, &self.path)
    }

    /// Puts the held samples into the batch at their times.
    fn release_held(&mut self) {
        let (batch, last) = (&mut self.batch, &mut self.last_logged_s);
        self.smallest.release_all(|s| {
            *last = last.max(s.t_s);
            insert_sample(batch, s);
        });
    }

    /// Closes the log after a failed run: the data so far, an error event and a
    /// `run_end` record saying so. The file is then valid and complete as a record of
    /// a failed run.
    /// `t_s` is the failure's time (the end of the last step the log saw when it is
    /// not finite); the error event and `run_end.t_end_s` carry it.
    pub fn close_failed(&mut self, t_s: f64, reason: &str) -> Result<PathBuf, OutputError> {
        let t_s = if t_s.is_finite() { t_s } else { self.last_t_s };
        self.release_end();
        self.batch.items.push(Item::Event {
            t_s,
            level: 4,
            text: format!("run failed: {reason}"),
        });
        self.finish("failed", t_s, reason)
    }

    fn finish(&mut self, status: &str, t_s: f64, detail: &str) -> Result<PathBuf, OutputError> {
        let path = self.path.clone();
        let mut end: BTreeMap<String, String> = [
            ("status", status.to_string()),
            ("t_end_s", format!("{t_s}")),
            ("detail", detail.to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        end.extend(self.run_end(t_s, status == "complete").to_metadata());
        if let Err(e) = self.send_batch()
            && matches!(self.state, State::Closed(false))
        {
            // the writer thread stopped on this error
            return Err(match e.downcast::<OutputError>() {
                Ok(e) => *e,
                Err(e) => OutputError::other(&path, e),
            });
        }
        let result = match std::mem::replace(&mut self.state, State::Closed(false)) {
            State::Open(mut w) => (|| {
                w.write_metadata(&mcap::records::Metadata {
                    name: "orbitlash.run_end".into(),
                    metadata: end,
                })
                .map_err(|e| out_err(&path, e))?;
                w.finish().map_err(|e| out_err(&path, e))?;
                w.into_inner().commit()
            })(),
            State::Running(t) => {
                let _ = t.tx.send(ToWriter::Finish(end));
                drop(t.tx);
                t.handle
                    .join()
                    .map_err(|_| OutputError::other(&path, "the writer thread panicked"))
                    .and_then(|r| r)
            }
            State::Closed(true) => Ok(path.clone()),
            State::Closed(false) => Err(OutputError::NotWritten {
                path: path.display().to_string(),
            }),
        };
        self.state = State::Closed(result.is_ok());
        result
    }
}

/// Hands the batch to the writer thread (when it runs), or reports why it stopped.
fn send_batch(state: &mut State, batch: &mut Batch, path: &Path) -> ObserverResult {
    if batch.items.is_empty() {
        return Ok(());
    }
    if let State::Running(t) = state {
        if t.failed.load(std::sync::atomic::Ordering::Relaxed) {
            // The writer stopped on an error: collect it, so the run reports the cause.
            let State::Running(t) = std::mem::replace(state, State::Closed(false)) else {
                unreachable!()
            };
            drop(t.tx);
            return Err(match t.handle.join() {
                Ok(Err(e)) => Box::new(e),
                _ => format!("writing {} failed", path.display()).into(),
            });
        }
        let next = Batch {
            values: Vec::with_capacity(batch.values.capacity()),
            meshes: Vec::with_capacity(batch.meshes.capacity()),
            items: Vec::with_capacity(BATCH_SAMPLES + 8),
        };
        let batch = std::mem::replace(batch, next);
        t.tx.send(ToWriter::Batch(batch))
            .map_err(|_| format!("the writer of {} stopped", path.display()))?;
    }
    Ok(())
}

/// Appends a sample to a batch, laid out as [`Layout`] says.
fn push_sample(batch: &mut Batch, s: &Sample) {
    let b = |on: &bool| if *on { 1.0 } else { 0.0 };
    let env = s.env.expect("the log samples the environment");
    // One definition for both fields (see the module doc): the flux that reaches the
    // spacecraft, and sunlit when any does.
    let flux = if s.sunlit {
        env.solar_flux_w_per_m2
    } else {
        0.0
    };
    let v = &mut batch.values;
    let at = v.len();
    v.push(s.t_s);
    v.push(b(&(flux > 0.0)));
    v.extend_from_slice(&s.temperatures_k);
    v.extend(s.heaters_on.iter().map(b));
    v.extend(s.modes_active.iter().map(b));
    let f = &s.flows;
    v.push(f.absorbed_w);
    v.push(f.dissipated_w);
    v.extend_from_slice(&f.to_boundary_w);
    v.extend_from_slice(&f.load_w);
    v.extend_from_slice(&f.heater_w);
    v.push(s.orbit_phase_deg);
    v.push(env.beta_rad.to_degrees());
    v.push(flux);
    v.push(s.orbit_number as f64);
    for i in &s.faces {
        v.extend([i.solar_w_per_m2, i.albedo_w_per_m2, i.earth_ir_w_per_m2]);
    }
    let mesh = batch.meshes.len();
    batch.meshes.extend_from_slice(&s.mesh);
    batch.items.push(Item::Sample(at, mesh));
}

/// The time of a batch item, s.
fn item_time(batch: &Batch, item: &Item) -> f64 {
    match item {
        Item::Sample(at, _) => batch.values[*at],
        Item::Event { t_s, .. } => *t_s,
    }
}

/// Adds a sample to a batch at its time among the items there (after events of the same
/// time); none if a sample of that time is there already.
fn insert_sample(batch: &mut Batch, s: &Sample) {
    let mut at = batch.items.len();
    while at > 0 && item_time(batch, &batch.items[at - 1]) > s.t_s {
        at -= 1;
    }
    // the items of this time are just before `at` (items are in time order)
    let taken = batch.items[..at]
        .iter()
        .rev()
        .take_while(|i| item_time(batch, i) == s.t_s)
        .any(|i| matches!(i, Item::Sample(..)));
    if taken {
        return;
    }
    push_sample(batch, s);
    let item = batch.items.pop().expect("just pushed");
    batch.items.insert(at, item);
}

/// Runs `w` on a thread fed by batches until `Finish`.
fn spawn_writer(
    setup: impl FnOnce() -> Result<LogWriter, OutputError> + Send + 'static,
    layout: Layout,
) -> WriterThread {
    let (tx, rx) = std::sync::mpsc::sync_channel::<ToWriter>(8);
    let failed = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = failed.clone();
    let handle = std::thread::Builder::new()
        .name("mcap-writer".into())
        .spawn(move || {
            let mut w = match setup() {
                Ok(w) => w,
                Err(e) => {
                    flag.store(true, std::sync::atomic::Ordering::Relaxed);
                    // drain until told to finish, then report
                    for _ in rx {}
                    return Err(e);
                }
            };
            // An older log under the same name stays until this one is committed
            // (`AtomicFile::commit` renames over it).
            let mut error: Option<OutputError> = None;
            for msg in rx {
                match msg {
                    ToWriter::Batch(b) => {
                        if error.is_none()
                            && let Err(e) = w.batch(layout, &b)
                        {
                            error = Some(e);
                            flag.store(true, std::sync::atomic::Ordering::Relaxed);
                        }
                    }
                    ToWriter::Finish(end) => {
                        return match error {
                            Some(e) => Err(e),
                            None => w.finish(end),
                        };
                    }
                }
            }
            // Dropped without finishing (the run failed elsewhere): the temporary file
            // is removed with the writer.
            Err(error.unwrap_or_else(|| {
                OutputError::other(&w.path, "the run ended before the log was closed")
            }))
        })
        .expect("spawn the MCAP writer thread");
    WriterThread { tx, handle, failed }
}

/// Writes one `orbitlash.GearMesh` message.
fn encode_mesh(e: &mut Encoder, pair: &PairLayout, m: &MeshState, temps: &[f64]) {
    e.double(1, m.backlash_exact_m * 1e6);
    e.double(2, m.backlash_closed_form_m * 1e6);
    e.double(3, m.backlash_paper_m * 1e6);
    e.double(4, m.margin_m * 1e6);
    e.double(5, m.pressure_angle_rad.to_degrees());
    e.double(6, m.center_distance_m * 1e3);
    e.double(7, m.contact_ratio);
    for k in 0..2 {
        let d = m.gears[k];
        e.message(8 + k as u32, |e| {
            e.double(1, d.base_displacement_m * 1e6);
            e.double(2, d.base_radius_m * 1e3);
            e.double(3, d.base_pitch_m * 1e3);
            e.double(4, d.base_thickness_m * 1e3);
            e.double(5, d.tip_radius_m * 1e3);
            e.double(6, d.coating_m * 1e6);
            e.packed_doubles(7, pair.radii_mm[k].iter().copied());
            e.packed_doubles(8, pair.nodes[k].iter().map(|&i| temps[i]));
        });
    }
}

fn gear_types() -> Vec<MessageType> {
    let mesh = MessageType::new("GearMesh")
        .with("backlash_exact_um", Kind::Double)
        .with("backlash_closed_form_um", Kind::Double)
        .with("backlash_paper_um", Kind::Double)
        .with("margin_um", Kind::Double)
        .with("pressure_angle_deg", Kind::Double)
        .with("center_distance_mm", Kind::Double)
        .with("contact_ratio", Kind::Double)
        .with("pinion", Kind::Message("GearDeformation".into()))
        .with("wheel", Kind::Message("GearDeformation".into()));
    let gear = MessageType::new("GearDeformation")
        .with("base_circle_displacement_um", Kind::Double)
        .with("base_radius_mm", Kind::Double)
        .with("base_pitch_mm", Kind::Double)
        .with("base_tooth_thickness_mm", Kind::Double)
        .with("tip_radius_mm", Kind::Double)
        .with("coating_um", Kind::Double)
        .with("radius_mm", Kind::RepeatedDouble)
        .with("temperature_k", Kind::RepeatedDouble);
    vec![mesh, gear]
}

/// Unique identifiers for `names` with `suffix`, disambiguated by a counter.
fn field_names(
    names: impl Iterator<Item = String>,
    suffix: &str,
    taken: &mut Vec<String>,
) -> Vec<String> {
    names
        .map(|n| {
            let base = format!("{}_{suffix}", identifier(&n));
            let mut name = base.clone();
            let mut k = 2;
            while taken.contains(&name) {
                name = format!("{base}{k}");
                k += 1;
            }
            taken.push(name.clone());
            name
        })
        .collect()
}

/// The `/thermal/temperature_c` channel: `<node>_c` per node, each mapped to its node
/// as `node:<field>`.
fn celsius_channel(
    w: &mut mcap::Writer<AtomicFile>,
    path: &Path,
    nodes: &[String],
) -> Result<u16, OutputError> {
    let fields = field_names(nodes.iter().cloned(), "c", &mut Vec::new());
    let mut message = MessageType::new("NodeTemperaturesCelsius");
    for f in &fields {
        message = message.with(f, Kind::Double);
    }
    let meta: BTreeMap<String, String> = fields
        .iter()
        .zip(nodes)
        .map(|(f, n)| (format!("node:{f}"), n.clone()))
        .collect();
    let s = w
        .add_schema(
            "orbitlash.NodeTemperaturesCelsius",
            "protobuf",
            &descriptor_set("NodeTemperaturesCelsius", &[message]),
        )
        .map_err(|e| out_err(path, e))?;
    w.add_channel(s, "/thermal/temperature_c", "protobuf", &meta)
        .map_err(|e| out_err(path, e))
}

/// Adds the schema of a Foxglove well-known message type as the official crate gives it.
fn foxglove_schema<M: foxglove::Encode>(
    w: &mut mcap::Writer<AtomicFile>,
    path: &Path,
) -> Result<u16, OutputError> {
    let s = M::get_schema().expect("foxglove message types have schemas");
    w.add_schema(&s.name, &s.encoding, &s.data)
        .map_err(|e| out_err(path, e))
}

/// The log's provenance (tool, scenario name, file and SHA-256, solver, seed, `--set`s,
/// end time, cadence) as MCAP metadata, and the scenario file as an attachment.
fn write_provenance(
    w: &mut mcap::Writer<AtomicFile>,
    path: &Path,
    p: Provenance,
    cadence: LogCadence,
    t_end_s: f64,
    time_origin_ns: u64,
) -> Result<(), OutputError> {
    let cadence = match cadence {
        LogCadence::Steps(n) => format!("every {n} step(s)"),
        LogCadence::Interval(dt) => format!("every {dt} s"),
    };
    let sha = Sha256::digest(p.scenario_toml.as_bytes());
    let sha: String = sha.iter().map(|b| format!("{b:02x}")).collect();
    let metadata: BTreeMap<String, String> = [
        ("tool", "orbitlash".to_string()),
        ("tool_version", env!("CARGO_PKG_VERSION").to_string()),
        ("scenario_name", p.scenario_name.clone()),
        ("scenario_file", p.scenario_file.clone()),
        ("scenario_sha256", sha),
        ("solver", p.solver.clone()),
        ("seed", p.seed.map_or("none".into(), |s| s.to_string())),
        (
            "set",
            p.sets
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect::<Vec<_>>()
                .join(" "),
        ),
        ("t_end_s", format!("{}", t_end_s)),
        ("log_cadence", cadence),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    let mut metadata = metadata;
    if time_origin_ns != 0 {
        // log times are UTC: t = 0 is this many ns after the Unix epoch
        metadata.insert(TIME_ORIGIN_KEY.to_string(), time_origin_ns.to_string());
    }
    w.write_metadata(&mcap::records::Metadata {
        name: "orbitlash.provenance".into(),
        metadata,
    })
    .map_err(|e| out_err(path, e))?;
    let file_name = match Path::new(&p.scenario_file).file_name() {
        Some(f) if !p.scenario_file.starts_with('<') => f.to_string_lossy().into_owned(),
        _ => format!("{}.toml", p.scenario_name),
    };
    w.attach(&mcap::Attachment {
        log_time: 0,
        create_time: 0,
        name: file_name,
        media_type: "application/toml".into(),
        data: std::borrow::Cow::Owned(p.scenario_toml.into_bytes()),
    })
    .map_err(|e| out_err(path, e))?;
    Ok(())
}

/// `/orbit/faces`' message type (per face its solar, albedo and Earth-IR flux) and the
/// channel metadata mapping each field to `<node>.<face>.<flux>_w_per_m2`.
fn face_fluxes_type(faces: &[String]) -> (MessageType, BTreeMap<String, String>) {
    let mut taken = Vec::new();
    let mut message = MessageType::new("FaceFluxes");
    let mut meta = BTreeMap::new();
    for face in faces {
        for q in ["solar", "albedo", "earth_ir"] {
            let name = format!("{face}.{q}");
            let field =
                field_names(std::iter::once(name.clone()), "w_per_m2", &mut taken).remove(0);
            message = message.with(&field, Kind::Double);
            meta.insert(format!("face:{field}"), format!("{name}_w_per_m2"));
        }
    }
    (message, meta)
}

/// Writes the schemas, channels, provenance and attachment of a new log and returns
/// the writer ready for samples (runs on the writer thread).
#[allow(clippy::too_many_arguments)]
fn open_log_writer(
    path: &Path,
    mut writer: Box<mcap::Writer<AtomicFile>>,
    provenance: Provenance,
    cadence: LogCadence,
    d: LogDescription,
    t_end_s: f64,
    scene_interval_s: Option<f64>,
) -> Result<LogWriter, OutputError> {
    let w = &mut writer;
    let mut taken = vec!["time_s".to_string()];
    let node_fields = field_names(d.nodes.iter().cloned(), "k", &mut taken);
    let mut temperature = MessageType::new("NodeTemperatures").with("time_s", Kind::Double);
    for f in &node_fields {
        temperature = temperature.with(f, Kind::Double);
    }
    let mut taken = vec!["absorbed_w".to_string(), "dissipated_w".to_string()];
    let mut heat = MessageType::new("HeatFlows")
        .with("absorbed_w", Kind::Double)
        .with("dissipated_w", Kind::Double);
    for f in field_names(
        d.boundaries.iter().map(|b| format!("to_{b}")),
        "w",
        &mut taken,
    ) {
        heat = heat.with(&f, Kind::Double);
    }
    for f in field_names(d.loads.iter().cloned(), "w", &mut taken) {
        heat = heat.with(&f, Kind::Double);
    }
    for f in field_names(d.heaters.iter().cloned(), "w", &mut taken) {
        heat = heat.with(&f, Kind::Double);
    }
    let orbit = MessageType::new("OrbitState")
        .with("orbit_angle_deg", Kind::Double)
        .with("beta_deg", Kind::Double)
        .with("solar_flux_w_per_m2", Kind::Double)
        .with("sunlit", Kind::Double)
        .with("orbit_number", Kind::Double);

    let mut node_map = BTreeMap::new();
    for (f, n) in node_fields.iter().zip(&d.nodes) {
        node_map.insert(format!("node:{f}"), n.clone());
    }
    let empty = BTreeMap::new();
    let schema = |w: &mut mcap::Writer<AtomicFile>, name: &str, data: &[u8]| {
        w.add_schema(name, "protobuf", data)
            .map_err(|e| out_err(path, e))
    };
    let channel =
        |w: &mut mcap::Writer<AtomicFile>, s: u16, topic: &str, meta: &BTreeMap<String, String>| {
            w.add_channel(s, topic, "protobuf", meta)
                .map_err(|e| out_err(path, e))
        };
    let s = schema(
        w,
        "orbitlash.NodeTemperatures",
        &descriptor_set("NodeTemperatures", &[temperature]),
    )?;
    let temperature = channel(w, s, "/thermal/temperature", &node_map)?;
    let celsius = celsius_channel(w, path, &d.nodes)?;
    let s = schema(
        w,
        "orbitlash.HeatFlows",
        &descriptor_set("HeatFlows", &[heat]),
    )?;
    let heat = channel(w, s, "/thermal/heat", &empty)?;
    let s = schema(
        w,
        "orbitlash.OrbitState",
        &descriptor_set("OrbitState", &[orbit]),
    )?;
    let orbit = channel(w, s, "/orbit/state", &empty)?;
    let faces = if d.faces.is_empty() {
        None
    } else {
        let (message, meta) = face_fluxes_type(&d.faces);
        let s = schema(
            w,
            "orbitlash.FaceFluxes",
            &descriptor_set("FaceFluxes", &[message]),
        )?;
        Some(channel(w, s, "/orbit/faces", &meta)?)
    };
    let mut gears = Vec::new();
    if !d.pairs.is_empty() {
        let s = schema(
            w,
            "orbitlash.GearMesh",
            &descriptor_set("GearMesh", &gear_types()),
        )?;
        for name in &d.pair_names {
            let meta: BTreeMap<String, String> =
                [("pair".to_string(), name.clone())].into_iter().collect();
            gears.push(channel(
                w,
                s,
                &format!("/gears/{}", identifier(name)),
                &meta,
            )?);
        }
    }
    let mut scenes = Vec::new();
    if scene_interval_s.is_some() && !d.pairs.is_empty() {
        let s = foxglove_schema::<foxglove::messages::SceneUpdate>(w, path)?;
        for name in &d.pair_names {
            scenes.push(channel(
                w,
                s,
                &format!("/gears/{}/scene", identifier(name)),
                &empty,
            )?);
        }
    }
    let s = foxglove_schema::<foxglove::messages::Log>(w, path)?;
    let log = channel(w, s, "/events", &empty)?;

    write_provenance(w, path, provenance, cadence, t_end_s, d.time_origin_ns)?;
    let ch = Channels {
        temperature,
        celsius,
        heat,
        orbit,
        faces,
        gears,
        scenes,
        log,
    };
    Ok(LogWriter {
        origin_ns: d.time_origin_ns,
        path: path.to_path_buf(),
        writer: *writer,
        ch,
        enc: Encoder::default(),
        seq: 0,
        scene: scene_interval_s
            .filter(|_| !d.pairs.is_empty())
            .map(|interval_s| SceneState {
                interval_s,
                next_s: 0.0,
                outlines: d.outlines,
                names: d.pair_names.iter().map(|n| identifier(n)).collect(),
            }),
        pairs: d.pairs,
    })
}

impl Observer for McapLog {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        let State::Open(writer) = std::mem::replace(&mut self.state, State::Closed(false)) else {
            return Err("the log was already started".into());
        };
        let net = &r.model.network;
        let names = |v: &mut dyn Iterator<Item = &String>| v.cloned().collect::<Vec<_>>();
        let description = LogDescription {
            nodes: names(&mut net.nodes.iter().map(|n| &n.name)),
            boundaries: names(&mut net.boundaries.iter().map(|b| &b.name)),
            loads: names(&mut net.loads.iter().map(|l| &l.name)),
            heaters: names(&mut net.heaters.iter().map(|h| &h.name)),
            faces: net
                .face_loads()
                .map(|(l, _)| format!("{}.{}", net.nodes[l.node].name, l.name))
                .collect(),
            pair_names: names(&mut r.gears.iter().map(|g| &g.name)),
            pairs: r
                .gears
                .iter()
                .map(|p| PairLayout {
                    nodes: [p.gears[0].nodes.clone(), p.gears[1].nodes.clone()],
                    radii_mm: [0, 1]
                        .map(|k| p.gears[k].node_radii_m.iter().map(|r| r * 1e3).collect()),
                })
                .collect(),
            outlines: if self.scene_interval_s.is_some() {
                r.gears.iter().map(scene::pair_outlines_m).collect()
            } else {
                vec![]
            },
            time_origin_ns: r.model.environment.start_unix_ns(),
        };
        let (path, provenance, cadence, t_end_s, scene_interval_s) = (
            self.path.clone(),
            self.provenance.clone(),
            self.cadence,
            r.t_end_s,
            self.scene_interval_s,
        );
        self.names = Names {
            pairs: description.pair_names.clone(),
            heaters: description.heaters.clone(),
            modes: r.model.modes.iter().map(|m| m.name.clone()).collect(),
        };
        self.layout = Layout {
            nodes: net.nodes.len(),
            heaters: net.heaters.len(),
            modes: r.model.modes.len(),
            boundaries: net.boundaries.len(),
            loads: net.loads.len(),
            faces: net.face_loads().count(),
        };
        // The initial state goes out with the first batch; the writer thread writes the
        // schemas, provenance and attachment while the run starts.
        self.last_t_s = r.t_start_s;
        self.smallest.on_start(r)?;
        self.eclipses.on_start(r)?;
        self.min_allowed_m = r.gears.iter().map(|g| g.min_backlash_m).collect();
        self.end_model = Some(Box::new((r.model.clone(), r.gears.to_vec())));
        self.last_end = Sample::default();
        self.sampler = Sampler::new(self.cadence.cadence(), Want::ALL);
        if let Some(s) = self.sampler.start(r) {
            push_sample(&mut self.batch, s);
            self.last_logged_s = s.t_s;
        }
        let setup = move || {
            open_log_writer(
                &path,
                writer,
                provenance,
                cadence,
                description,
                t_end_s,
                scene_interval_s,
            )
        };
        self.state = State::Running(spawn_writer(setup, self.layout));
        Ok(())
    }

    /// Besides the samples at the log's cadence, the log always holds each pair's
    /// sample at the run's smallest backlash (held while steps keep lowering it) and
    /// the last step's end, so a figure or viewer of the log shows the run's own
    /// minimum and end whatever the cadence.
    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let t1 = step.t1_s();
        self.last_t_s = t1;
        let batch = &mut self.batch;
        self.smallest.on_step(step, |s| insert_sample(batch, s))?;
        let (batch, last) = (&mut self.batch, &mut self.last_logged_s);
        self.sampler.each(step, |s| -> ObserverResult {
            push_sample(batch, s);
            *last = s.t_s;
            Ok(())
        })?;
        step.end_state_into(&mut self.last_end);
        let n = self.batch.items.len();
        if n >= BATCH_SAMPLES
            && (self.smallest.earliest_held_s().is_infinite() || n >= MAX_HELD_BATCH)
        {
            self.release_held();
            self.send_batch()?;
        }
        Ok(())
    }

    fn on_event(&mut self, event: &Event) -> ObserverResult {
        self.eclipses.on_event(event)?;
        // the pair statistics count margin and interference events (the summary's and
        // the end record's counts are theirs)
        self.smallest.mesh.on_event(event)?;
        let (level, text) = event_text(event.kind, &self.names);
        self.batch.items.push(Item::Event {
            t_s: event.t_s,
            level,
            text,
        });
        Ok(())
    }

    fn on_finish(&mut self, stats: &RunStats) -> ObserverResult {
        self.smallest.mesh.on_finish(stats)?;
        self.release_end();
        let (status, detail) = if stats.interrupted {
            self.batch.items.push(Item::Event {
                t_s: stats.t_end_s,
                level: 3,
                text: format!("run interrupted at t = {:.3} s", stats.t_end_s),
            });
            (
                "interrupted",
                "stopped on request; the data up to t_end_s are complete",
            )
        } else {
            let end = self.run_end(stats.t_end_s, true);
            let (level, text) = run_complete_event(stats.t_end_s, &end);
            self.batch.items.push(Item::Event {
                t_s: stats.t_end_s,
                level,
                text,
            });
            ("complete", "")
        };
        self.finish(status, stats.t_end_s, detail)?;
        Ok(())
    }
}

/// The `/events` entry that closes a complete run: its end time and verdict, and each
/// pair's smallest backlash with its time (as the `run_end` record carries them);
/// a warning (level 3) when the verdict fails, else info (2).
fn run_complete_event(t_end_s: f64, end: &RunEnd) -> (i64, String) {
    let mut text = format!(
        "run complete at t = {t_end_s:.3} s: verdict {}",
        end.verdict
    );
    for p in &end.pairs {
        match (p.min_backlash_um, p.t_min_s) {
            (Some(b), Some(t)) => text.push_str(&format!(
                "; {} smallest backlash {b:.3} µm at t = {t:.1} s ({})",
                p.name, p.verdict
            )),
            // no valid mesh at any step: no smallest, but the pair and its verdict
            _ => text.push_str(&format!(
                "; {}: no smallest backlash ({})",
                p.name, p.verdict
            )),
        }
    }
    let level = if end.verdict == "fail" { 3 } else { 2 };
    (level, text)
}

/// Names used in event texts.
#[derive(Debug, Clone, Default)]
struct Names {
    pairs: Vec<String>,
    heaters: Vec<String>,
    modes: Vec<String>,
}

fn event_text(kind: EventKind, n: &Names) -> (i64, String) {
    match kind {
        EventKind::EclipseEntry => (2, "eclipse entry".to_string()),
        EventKind::EclipseExit => (2, "eclipse exit".to_string()),
        EventKind::HeaterOn(k) => (2, format!("heater {} on", n.heaters[k])),
        EventKind::HeaterOff(k) => (2, format!("heater {} off", n.heaters[k])),
        EventKind::ModeStart(k) => (2, format!("mode {} starts", n.modes[k])),
        EventKind::ModeEnd(k) => (2, format!("mode {} ends", n.modes[k])),
        EventKind::MarginLow(k) => (
            3,
            format!(
                "gear pair {}: backlash below the minimum allowed",
                n.pairs[k]
            ),
        ),
        EventKind::MarginRestored(k) => (
            2,
            format!(
                "gear pair {}: backlash back above the minimum allowed",
                n.pairs[k]
            ),
        ),
        EventKind::InterferenceStart(k) => (
            4,
            format!("gear pair {}: interference (backlash ≤ 0)", n.pairs[k]),
        ),
        EventKind::InterferenceEnd(k) => {
            (3, format!("gear pair {}: interference ended", n.pairs[k]))
        }
        EventKind::MeshInvalid(k) => (4, format!("gear pair {}: no valid mesh", n.pairs[k])),
    }
}

//! # orbitlash
//!
//! Predicts how the gears of a spacecraft mechanism open and close their backlash as
//! the mechanism cycles through sunlight and eclipse.
//!
//! Data flows one way:
//!
//! ```text
//! scenario file ──io::scenario_toml──▶ ScenarioSpec ──spec::compile──▶ Scenario
//!     (model::Model keeps both in step: parameters by key path)
//!     ──sim::Setup (once) ──Setup::run(State → State)──▶ observers
//!     ──▶ summary, sensor::Readings, io::csv_export, io::mcap_log ──▶ reports (cli)
//! ```
//!
//! Many runs of one model, as margins and fits make them:
//!
//! ```
//! use orbitlash::io::scenario_toml::{REFERENCE_HINGE_TOML, parse_spec};
//! use orbitlash::spec::model::Model;
//! use orbitlash::run::sim::{Setup, Stop};
//! use orbitlash::run::summary::MeshStats;
//!
//! let mut model = Model::new(parse_spec(REFERENCE_HINGE_TOML, "reference").unwrap()).unwrap();
//! let beta = model.param("environment.beta_deg").unwrap(); // resolve a key path once
//! model.set_param(&beta, 35.0).unwrap(); // microseconds, the TOML's checks and errors
//! assert!(model.set_param(&beta, 120.0).is_err());
//!
//! let sc = model.scenario();
//! let mut setup = Setup::new(&sc.thermal, &sc.gears, &sc.solver); // once per model
//! let mut state = setup.initial_state(); // or setup.state_at(t_s, temperatures_k)
//! let mut mesh = MeshStats::last(sc.period_s());
//! // Pause after the step that passes half an orbit, then go on from the state it left:
//! // the steps are those of one run to the end, bit for bit.
//! let pause = Stop { pause_after_s: Some(0.5 * sc.period_s()), ..Stop::default() };
//! setup.run(&mut state, 2.0 * sc.period_s(), &mut mesh, pause).unwrap();
//! setup.run(&mut state, 2.0 * sc.period_s(), &mut mesh, Stop::default()).unwrap();
//! assert!(mesh.pairs[0].min_exact_m > sc.gears[0].min_backlash_m);
//! // A run *to* a time lands a step on it; going on from there agrees with one
//! // longer run to the solver's tolerance, not to the bit.
//! setup.run(&mut state, 3.0 * sc.period_s(), &mut (), Stop::default()).unwrap();
//! ```
//!
//! The physics (`orbit`, `thermal`, `gear`), the runs over it (`run`: `sim`, `sample`,
//! `sensor`, `summary`, `steady`), the scenario and its checks (`spec`: `compile`,
//! `model`, `validate`), the analyses (`margins`, `diagnose`) and the figures (`plot`)
//! know nothing of files or the CLI; `io` holds everything that reads or writes files;
//! the binary's `cli` maps commands to the pipeline; `constants`, `units` and `numeric`
//! are the leaves. See
//! `docs/ARCHITECTURE.md` for the module map and invariants.

/// An error and its causes on one line, each once (a cause its message already quotes
/// is left out): how library errors that end up as text (a margins sample's reason, a
/// failed diagnose candidate) are written.
pub(crate) fn error_chain(e: &dyn std::error::Error) -> String {
    let mut out = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !out.ends_with(&text) {
            out = format!("{out}: {text}");
        }
        cause = c.source();
    }
    out
}

pub mod constants;
pub mod diagnose;
pub mod gear;
pub mod io;
pub mod margins;
pub mod numeric;
pub mod orbit;
pub mod plot;
pub mod recording;
pub mod run;
pub mod spec;
pub mod thermal;
pub mod units;

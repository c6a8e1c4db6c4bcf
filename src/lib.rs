//! # orbitlash
//!
//! Predicts how the gears of a spacecraft mechanism open and close their backlash as
//! the mechanism cycles through sunlight and eclipse.
//!
//! Data flows one way:
//!
//! ```text
//! scenario file ──io::scenario_toml──▶ Scenario (validated model)
//!     ──sim::simulate (thermal::solver, orbit, gear at every step)──▶ Observer callbacks
//!     ──▶ summary, io::csv_export, io::mcap_log ──▶ reports (cli)
//! ```
//!
//! Physics (`orbit`, `thermal`, `gear`, `sim`, `summary`) knows nothing of files or the CLI;
//! `io` holds everything that reads or writes files; `cli` maps commands to the
//! pipeline. See `docs/ARCHITECTURE.md` for the module map and invariants.

pub mod constants;
pub mod gear;
pub mod io;
pub mod model;
pub mod orbit;
pub mod sample;
pub mod scenario;
pub mod sensor;
pub mod sim;
pub mod spec;
pub mod summary;
pub mod thermal;
pub mod units;
pub mod validate;

//! The run layer: a validated [`crate::spec::scenario::Scenario`] stepped through time,
//! and what observers make of the steps.
//!
//! - [`sim`]: `Setup` (built once per model) and `Setup::run` from an explicit `State`
//!   to an end time; the `Observer` trait every consumer of steps implements.
//! - [`sample`]: what one instant holds (`Sample`) and when to take one (`Sampler`).
//! - [`sensor`]: recording columns as lagged, offset readings of nodes or backlash.
//! - [`summary`]: last-orbit statistics, backlash extremes and the run's verdict.
//! - [`steady`]: the orbit-periodic solution (Newton shooting, marching as fallback).
//!
//! Nothing here reads or writes files: `io` turns observers' results into logs.

pub mod sample;
pub mod sensor;
pub mod sim;
pub mod steady;
pub mod summary;

//! Everything that touches files: scenario TOML, CSV export, MCAP logs.

pub mod atomic;
pub mod csv_export;
pub mod diagnose_out;
pub mod foxglove_layout;
pub mod log_schema;
pub mod mcap_lengths;
pub mod mcap_log;
pub mod mcap_read;
pub mod mcap_scan;
pub mod output;
pub mod protobuf;
pub mod recording;
pub mod scenario_toml;
pub mod scene;

//! Everything that touches files: scenario TOML, CSV export, MCAP logs.

pub mod atomic;
pub mod csv_export;
pub mod mcap_log;
pub mod scenario_toml;

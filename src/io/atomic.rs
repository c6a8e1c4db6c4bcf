//! Output files written to a temporary sibling and renamed into place on success, so
//! a failed or interrupted run never leaves a half-written file under the final name
//! (the type lives in `io::output`, beside the checks it runs first).

pub use super::output::{AtomicFile, OutputError, OutputPolicy};

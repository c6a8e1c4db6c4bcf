//! CSV export of a run: `time_s`, `<node>_k` for every diffusion node, then for each
//! gear pair `backlash_um` (exact worst case over the mesh cycle),
//! `backlash_closed_form_um`, `backlash_paper_um`, `pressure_angle_deg` and
//! `center_distance_mm` (prefixed `<pair>.` when there are several pairs). One row
//! per output interval, values from the solver's cubic interpolant; written atomically.

use std::io::Write;
use std::path::Path;

use super::atomic::{AtomicFile, OutputError, OutputPolicy};
use crate::gear::GearPair;
use crate::run::sample::{Cadence, Sample, Sampler, Want};
use crate::run::sim::{Observer, ObserverResult, RunStart, RunStats, StepView};

pub struct CsvExport {
    file: Option<AtomicFile>,
    sampler: Sampler,
}

/// Gear columns, per pair.
pub const GEAR_COLUMNS: [&str; 5] = [
    "backlash_um",
    "backlash_closed_form_um",
    "backlash_paper_um",
    "pressure_angle_deg",
    "center_distance_mm",
];

/// Header names of the gear columns for `pairs`.
pub fn gear_column_names(pairs: &[GearPair]) -> Vec<String> {
    let mut v = Vec::new();
    for p in pairs {
        for c in GEAR_COLUMNS {
            v.push(if pairs.len() == 1 {
                c.to_string()
            } else {
                format!("{}.{c}", p.name)
            });
        }
    }
    v
}

/// The gear column values of a pair state, in `GEAR_COLUMNS` order and units.
pub fn gear_values(m: &crate::gear::MeshState) -> [f64; 5] {
    [
        m.backlash_exact_m * 1e6,
        m.backlash_closed_form_m * 1e6,
        m.backlash_paper_m * 1e6,
        m.pressure_angle_rad.to_degrees(),
        m.center_distance_m * 1e3,
    ]
}

impl CsvExport {
    pub fn create(
        path: &Path,
        interval_s: f64,
        policy: &OutputPolicy,
    ) -> Result<CsvExport, OutputError> {
        Ok(CsvExport {
            file: Some(AtomicFile::create(path, policy)?),
            sampler: Sampler::new(Cadence::Interval(interval_s), Want::MESH),
        })
    }
}

/// Writes one row.
fn write_row(file: &mut Option<AtomicFile>, s: &Sample) -> Result<(), OutputError> {
    let f = file.as_mut().expect("open");
    let path = f.path().to_path_buf();
    let w = f.writer();
    (|| {
        write!(w, "{:.3}", s.t_s)?;
        for v in &s.temperatures_k {
            write!(w, ",{v:.6}")?;
        }
        for m in &s.mesh {
            for v in gear_values(m) {
                write!(w, ",{v:.6}")?;
            }
        }
        writeln!(w)
    })()
    .map_err(|e| OutputError::io(&path, e))
}

impl Observer for CsvExport {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        let f = self.file.as_mut().expect("open");
        let path = f.path().to_path_buf();
        let w = f.writer();
        (|| {
            write!(w, "time_s")?;
            for n in &r.model.network.nodes {
                write!(w, ",{}_k", n.name)?;
            }
            for c in gear_column_names(r.gears) {
                write!(w, ",{c}")?;
            }
            writeln!(w)
        })()
        .map_err(|e| OutputError::io(&path, e))?;
        if let Some(s) = self.sampler.start(r) {
            write_row(&mut self.file, s)?;
        }
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let file = &mut self.file;
        self.sampler.each(step, |s| write_row(file, s))?;
        Ok(())
    }

    fn on_finish(&mut self, _stats: &RunStats) -> ObserverResult {
        if let Some(f) = self.file.take() {
            f.commit()?;
        }
        Ok(())
    }
}

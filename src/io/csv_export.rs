//! CSV export of a run: `time_s`, `<node>_k` for every diffusion node, then for each
//! gear pair `backlash_um` (exact worst case over the mesh cycle),
//! `backlash_closed_form_um`, `backlash_paper_um`, `pressure_angle_deg` and
//! `center_distance_mm` (prefixed `<pair>.` when there are several pairs). One row
//! per output interval, values from the solver's cubic interpolant, and, in time
//! order among them, a row at each pair's smallest backlash so far (one per descent,
//! as the log holds it: the table's smallest is the run's own, at its time); written
//! atomically.

use std::io::Write;
use std::path::Path;

use super::atomic::{AtomicFile, OutputError, OutputPolicy};
use crate::gear::GearPair;
use crate::run::sample::{Cadence, Sample, Sampler, Want};
use crate::run::sim::{Observer, ObserverResult, RunStart, RunStats, StepView};
use crate::run::summary::{MeshStats, SmallestSamples};

pub struct CsvExport {
    file: Option<AtomicFile>,
    sampler: Sampler,
    smallest: SmallestSamples,
    /// Rows not yet written, in time order: those after the earliest held smallest
    /// wait for it.
    queue: Vec<Sample>,
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
            smallest: SmallestSamples::new(MeshStats::last(f64::INFINITY)),
            queue: Vec::new(),
        })
    }
}

/// Puts `s` among the rows in time order (a row already at its time, as the table
/// writes it to the millisecond, stands for it).
fn queue_row(queue: &mut Vec<Sample>, s: &Sample) {
    let at = queue.partition_point(|q| q.t_s <= s.t_s);
    let ms = |t: f64| (t * 1e3).round();
    let same = |q: &Sample| ms(q.t_s) == ms(s.t_s);
    if at > 0 && same(&queue[at - 1]) || queue.get(at).is_some_and(same) {
        return;
    }
    queue.insert(at, s.clone());
}

impl CsvExport {
    /// Writes the queued rows before `t_s`.
    fn flush_before(&mut self, t_s: f64) -> ObserverResult {
        let n = self.queue.partition_point(|q| q.t_s < t_s);
        for s in self.queue.drain(..n) {
            write_row(&mut self.file, &s)?;
        }
        Ok(())
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
        self.smallest.on_start(r)?;
        self.queue.clear();
        if let Some(s) = self.sampler.start(r) {
            write_row(&mut self.file, s)?;
        }
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let queue = &mut self.queue;
        self.smallest.on_step(step, |s| queue_row(queue, s))?;
        self.sampler.each(step, |s| -> ObserverResult {
            queue_row(queue, s);
            Ok(())
        })?;
        self.flush_before(self.smallest.earliest_held_s())
    }

    fn on_finish(&mut self, _stats: &RunStats) -> ObserverResult {
        let queue = &mut self.queue;
        self.smallest.release_all(|s| queue_row(queue, s));
        self.flush_before(f64::INFINITY)?;
        if let Some(f) = self.file.take() {
            f.commit()?;
        }
        Ok(())
    }
}

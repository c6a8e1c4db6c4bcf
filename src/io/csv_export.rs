//! CSV export of a run: `time_s`, `<node>_k` for every diffusion node, then for each
//! gear pair `backlash_um` (exact worst case over the mesh cycle),
//! `backlash_closed_form_um`, `backlash_paper_um`, `pressure_angle_deg` and
//! `center_distance_mm` (prefixed `<pair>.` when there are several pairs). One row
//! per output interval, values from the solver's cubic interpolant; written atomically.

use std::io::Write;
use std::path::Path;

use super::atomic::{AtomicFile, OutputError, OutputPolicy};
use crate::gear::GearPair;
use crate::sim::{Grid, Observer, ObserverResult, RunStart, RunStats, StepView, mesh_or_nan};

pub struct CsvExport {
    file: Option<AtomicFile>,
    grid: Grid,
    row: Vec<f64>,
    gear_values: Vec<f64>,
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
            grid: Grid::new(interval_s),
            row: vec![],
            gear_values: vec![],
        })
    }

    fn write_row(&mut self, t_s: f64) -> Result<(), OutputError> {
        let f = self.file.as_mut().expect("open");
        let path = f.path().to_path_buf();
        let w = f.writer();
        (|| {
            write!(w, "{t_s:.3}")?;
            for v in &self.row {
                write!(w, ",{v:.6}")?;
            }
            for v in &self.gear_values {
                write!(w, ",{v:.6}")?;
            }
            writeln!(w)
        })()
        .map_err(|e| OutputError::io(&path, e))
    }
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
        self.row = r.temps_k.to_vec();
        self.gear_values = r.mesh.iter().flat_map(gear_values).collect();
        self.write_row(r.t_start_s)?;
        self.grid.start(r.t_start_s);
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        while let Some(t) = self.grid.next_due(step.t1_s()) {
            let mut row = std::mem::take(&mut self.row);
            step.temperatures_at(t, &mut row);
            self.gear_values.clear();
            for g in step.gears {
                self.gear_values.extend(gear_values(&mesh_or_nan(g, &row)));
            }
            self.row = row;
            self.write_row(t)?;
        }
        Ok(())
    }

    fn on_finish(&mut self, _stats: &RunStats) -> ObserverResult {
        if let Some(f) = self.file.take() {
            f.commit()?;
        }
        Ok(())
    }
}

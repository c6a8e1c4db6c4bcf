//! CSV export of a run: `time_s` then `<node>_k` for every diffusion node, one row per
//! output interval (values from the solver's cubic interpolant), written atomically.

use std::io::Write;
use std::path::Path;

use super::atomic::{AtomicFile, OutputError};
use crate::sim::{Observer, ObserverResult, RunStats, StepView};
use crate::thermal::ThermalModel;

pub struct CsvExport {
    file: Option<AtomicFile>,
    interval_s: f64,
    next_row: u64,
    row: Vec<f64>,
}

impl CsvExport {
    pub fn create(path: &Path, interval_s: f64) -> Result<CsvExport, OutputError> {
        Ok(CsvExport {
            file: Some(AtomicFile::create(path)?),
            interval_s,
            next_row: 0,
            row: vec![],
        })
    }

    fn write_row(&mut self, t_s: f64) -> std::io::Result<()> {
        let w = self.file.as_mut().expect("open").writer();
        write!(w, "{t_s:.3}")?;
        for v in &self.row {
            write!(w, ",{v:.6}")?;
        }
        writeln!(w)
    }
}

impl Observer for CsvExport {
    fn on_start(&mut self, model: &ThermalModel, _t_end_s: f64, temps_k: &[f64]) -> ObserverResult {
        let w = self.file.as_mut().expect("open").writer();
        write!(w, "time_s")?;
        for n in &model.network.nodes {
            write!(w, ",{}_k", n.name)?;
        }
        writeln!(w)?;
        self.row = temps_k.to_vec();
        self.write_row(0.0)?;
        self.next_row = 1;
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        loop {
            let t = self.next_row as f64 * self.interval_s;
            if t > step.t1_s() * (1.0 + 1e-12) {
                break;
            }
            let mut row = std::mem::take(&mut self.row);
            step.temperatures_at(t, &mut row);
            self.row = row;
            self.write_row(t)?;
            self.next_row += 1;
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

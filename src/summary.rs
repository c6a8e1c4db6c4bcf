//! Run summaries computed as an observer: per-node min/max/mean over the last orbit
//! (or the whole run when it is shorter), using the solver's cubic interpolant so that
//! extremes between steps are not missed.

use crate::sim::{Observer, ObserverResult, RunStart, StepView};
use crate::thermal::solver::{hermite, hermite_interior_extrema};

#[derive(Debug, Clone, PartialEq)]
pub struct NodeStats {
    pub name: String,
    pub min_k: f64,
    pub max_k: f64,
    pub mean_k: f64,
}

/// Collects [`NodeStats`] over the window [t_end − window_s, t_end].
#[derive(Debug, Clone, Default)]
pub struct WindowStats {
    window_s: f64,
    start_s: f64,
    names: Vec<String>,
    min_k: Vec<f64>,
    max_k: Vec<f64>,
    integral_ks: Vec<f64>,
    covered_s: f64,
}

impl WindowStats {
    /// Statistics over the last `window_s` seconds of the run.
    pub fn last(window_s: f64) -> WindowStats {
        WindowStats {
            window_s,
            ..Default::default()
        }
    }

    pub fn window_start_s(&self) -> f64 {
        self.start_s
    }

    pub fn nodes(&self) -> Vec<NodeStats> {
        (0..self.names.len())
            .map(|i| NodeStats {
                name: self.names[i].clone(),
                min_k: self.min_k[i],
                max_k: self.max_k[i],
                mean_k: self.integral_ks[i] / self.covered_s.max(1e-300),
            })
            .collect()
    }

    fn see(&mut self, i: usize, v: f64) {
        self.min_k[i] = self.min_k[i].min(v);
        self.max_k[i] = self.max_k[i].max(v);
    }
}

impl Observer for WindowStats {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        let temps_k = r.temps_k;
        let n = temps_k.len();
        self.names = r
            .model
            .network
            .nodes
            .iter()
            .map(|n| n.name.clone())
            .collect();
        self.start_s = (r.t_end_s - self.window_s).max(0.0);
        self.min_k = vec![f64::INFINITY; n];
        self.max_k = vec![f64::NEG_INFINITY; n];
        self.integral_ks = vec![0.0; n];
        self.covered_s = 0.0;
        if self.start_s == 0.0 {
            for (i, &t) in temps_k.iter().enumerate() {
                self.see(i, t);
            }
        }
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let (t0, t1) = (step.t0_s(), step.t1_s());
        if t1 <= self.start_s {
            return Ok(());
        }
        let a = t0.max(self.start_s);
        let d = step.data;
        self.covered_s += t1 - a;
        for i in 0..self.names.len() {
            let (y0, y1, f0, f1, h) = (
                d.temps0_k[i],
                d.temps1_k[i],
                d.rates0_k_per_s[i],
                d.rates1_k_per_s[i],
                d.h_s,
            );
            let sa = (a - t0) / h;
            let p = |s: f64| hermite(y0, y1, f0, f1, h, s);
            self.see(i, p(sa));
            self.see(i, y1);
            if sa == 0.0 {
                for v in hermite_interior_extrema(y0, y1, f0, f1, h)
                    .into_iter()
                    .flatten()
                {
                    self.see(i, v);
                }
            } else {
                for k in 1..32 {
                    self.see(i, p(sa + (1.0 - sa) * k as f64 / 32.0));
                }
            }
            // Simpson's rule is exact for the cubic interpolant.
            let mid = p(0.5 * (sa + 1.0));
            self.integral_ks[i] += (t1 - a) / 6.0 * (p(sa) + 4.0 * mid + y1);
        }
        Ok(())
    }
}

/// Records every node's temperature at fixed times k·`interval_s` (k = 0, 1, …),
/// from the solver's cubic interpolant. For comparisons between runs.
#[derive(Debug, Clone, Default)]
pub struct Samples {
    pub interval_s: f64,
    pub times_s: Vec<f64>,
    /// One row per time, one column per node, K.
    pub temps_k: Vec<Vec<f64>>,
}

impl Samples {
    pub fn every(interval_s: f64) -> Samples {
        Samples {
            interval_s,
            ..Default::default()
        }
    }

    /// Largest |difference| between two sample sets over common rows, K.
    pub fn max_abs_diff_k(&self, other: &Samples) -> f64 {
        self.temps_k
            .iter()
            .zip(&other.temps_k)
            .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
            .fold(0.0, f64::max)
    }
}

impl Observer for Samples {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        self.times_s = vec![0.0];
        self.temps_k = vec![r.temps_k.to_vec()];
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        loop {
            let t = self.times_s.len() as f64 * self.interval_s;
            if t > step.t1_s() * (1.0 + 1e-12) {
                break;
            }
            let mut row = vec![0.0; step.temps1_k().len()];
            step.temperatures_at(t, &mut row);
            self.times_s.push(t);
            self.temps_k.push(row);
        }
        Ok(())
    }
}

//! Sensors: what a recording channel measures, and how.
//!
//! A [`Sensor`] maps a recording column (`housing_c`, `backlash_um`) onto the model: a
//! diffusion node's temperature or a derived quantity (a gear pair's backlash), in the
//! column's unit, through the instrument's own physics: a constant offset and a
//! first-order lag (a thermistor that follows its node with time constant τ,
//! τ dS/dt = T − S). [`Readings`] is the observer that reads every sensor of a
//! scenario at the times a [`Cadence`] says (every 30 s, or a recording's own times),
//! integrating each lag exactly over every step of the run.

use crate::run::sample::{Cadence, Sample, Sampler, Want};
use crate::run::sim::{Observer, ObserverResult, RunStart, StepView};
// The sensor types are part of the validated scenario (`spec::scenario`); kept
// reachable here, where they are read.
pub use crate::spec::quantity::{MAX_SENSOR_OFFSET_K, MAX_SENSOR_TAU_S};
pub use crate::spec::scenario::{ColumnUnit, Sensor, SensorTarget};

/// What `sensor` reads for a (lagged) temperature `sensed_k` or for the sample's
/// backlash, in the column's unit.
fn reading(sensor: &Sensor, sensed_k: f64, s: &Sample) -> f64 {
    match sensor.target {
        SensorTarget::Node(_) => {
            let t = sensed_k + sensor.offset_k;
            match sensor.unit() {
                ColumnUnit::Kelvin => t,
                _ => crate::units::k_to_c(t),
            }
        }
        SensorTarget::Backlash(k) => s.mesh[k].backlash_exact_m * 1e6,
    }
}

/// The sensor's state S after a stretch of length `h_s` over which its node follows
/// the cubic `T(v) = c[0] + c[1] v + c[2] v² + c[3] v³` (v = fraction of the stretch),
/// from `s0`: the exact solution of τ dS/dt = T − S. Stretches shorter than 2 τ use an
/// 8-point Gauss–Legendre rule on the convolution integral (its error is below 1e-15
/// of the integrand there); longer ones the polynomial particular solution, whose terms
/// shrink as (τ/h)^k.
pub fn lag_over(s0: f64, tau_s: f64, h_s: f64, c: [f64; 4]) -> f64 {
    if tau_s <= 0.0 {
        return c[0] + c[1] + c[2] + c[3];
    }
    if h_s <= 0.0 {
        return s0;
    }
    let lambda = h_s / tau_s;
    let decay = (-lambda).exp();
    let p = |v: f64| c[0] + v * (c[1] + v * (c[2] + v * c[3]));
    if lambda <= 2.0 {
        // S(1) = e^{−λ} S0 + λ ∫₀¹ e^{−λ(1−v)} T(v) dv
        let integral: f64 = crate::gear::disc::GAUSS8
            .iter()
            .map(|&(x, w)| {
                let v = 0.5 * (x + 1.0);
                0.5 * w * (-lambda * (1.0 - v)).exp() * p(v)
            })
            .sum();
        decay * s0 + lambda * integral
    } else {
        // S_p(v) = T − r T' + r² T'' − r³ T''' with r = τ/h (derivatives in v)
        let r = 1.0 / lambda;
        let particular = |v: f64| {
            let d1 = c[1] + v * (2.0 * c[2] + 3.0 * v * c[3]);
            let d2 = 2.0 * c[2] + 6.0 * v * c[3];
            let d3 = 6.0 * c[3];
            p(v) - r * (d1 - r * (d2 - r * d3))
        };
        particular(1.0) + (s0 - particular(0.0)) * decay
    }
}

/// The cubic of node `i` over the part [t0, t_s] of `step`, in the fraction of that part.
fn cubic_until(step: &StepView<'_>, i: usize, t_s: f64) -> [f64; 4] {
    let c = step.data.polynomial(i);
    let u = ((t_s - step.t0_s()) / step.data.h_s).clamp(0.0, 1.0);
    [c[0], c[1] * u, c[2] * u * u, c[3] * u * u * u]
}

/// Reads every sensor at the times of a cadence: `times_s[j]` and `values[k][j]` for
/// sensor k, in its column's unit. A run that starts where the previous one it
/// observed ended continues the readings (lag states carried, as one run would);
/// any other start begins afresh, each lagged sensor in equilibrium with its node.
#[derive(Debug, Clone)]
pub struct Readings {
    pub sensors: Vec<Sensor>,
    pub times_s: Vec<f64>,
    /// Per sensor, one value per time.
    pub values: Vec<Vec<f64>>,
    sampler: Sampler,
    /// Per sensor: its state S at the start of the current step, K.
    sensed_k: Vec<f64>,
}

impl Readings {
    pub fn new(sensors: Vec<Sensor>, cadence: Cadence) -> Readings {
        let want = Want {
            mesh: sensors
                .iter()
                .any(|s| matches!(s.target, SensorTarget::Backlash(_))),
            flows: false,
        };
        Readings {
            values: vec![Vec::new(); sensors.len()],
            sensed_k: vec![0.0; sensors.len()],
            sensors,
            times_s: Vec::new(),
            sampler: Sampler::new(cadence, want),
        }
    }

    /// The values of the sensor reading `column`.
    pub fn column(&self, column: &str) -> Option<&[f64]> {
        let k = self.sensors.iter().position(|s| s.column == column)?;
        Some(&self.values[k])
    }
}

impl Observer for Readings {
    fn on_start(&mut self, r: &RunStart<'_>) -> ObserverResult {
        if self.sampler.continues(r.t_start_s) {
            // A split run resumed from its end state: the readings and the lags go on.
            return Ok(());
        }
        self.times_s.clear();
        self.values.iter_mut().for_each(Vec::clear);
        // Every sensor starts in equilibrium with its node.
        for (x, sensor) in self.sensed_k.iter_mut().zip(&self.sensors) {
            if let SensorTarget::Node(i) = sensor.target {
                *x = r.temps_k[i];
            }
        }
        if let Some(s) = self.sampler.start(r) {
            self.times_s.push(s.t_s);
            for (k, sensor) in self.sensors.iter().enumerate() {
                self.values[k].push(reading(sensor, self.sensed_k[k], s));
            }
        }
        Ok(())
    }

    fn on_step(&mut self, step: &StepView<'_>) -> ObserverResult {
        let Readings {
            sensors,
            times_s,
            values,
            sampler,
            sensed_k,
        } = self;
        sampler.each(step, |s| {
            times_s.push(s.t_s);
            for (k, sensor) in sensors.iter().enumerate() {
                let sensed = match sensor.target {
                    SensorTarget::Node(i) if sensor.tau_s > 0.0 => lag_over(
                        sensed_k[k],
                        sensor.tau_s,
                        s.t_s - step.t0_s(),
                        cubic_until(step, i, s.t_s),
                    ),
                    SensorTarget::Node(i) => s.temperatures_k[i],
                    SensorTarget::Backlash(_) => f64::NAN,
                };
                values[k].push(reading(sensor, sensed, s));
            }
            Ok::<_, std::convert::Infallible>(())
        })?;
        // Each lag to the end of the step.
        for (k, sensor) in sensors.iter().enumerate() {
            if let SensorTarget::Node(i) = sensor.target {
                sensed_k[k] = if sensor.tau_s > 0.0 {
                    lag_over(
                        sensed_k[k],
                        sensor.tau_s,
                        step.data.h_s,
                        step.data.polynomial(i),
                    )
                } else {
                    step.temps1_k()[i]
                };
            }
        }
        Ok(())
    }
}

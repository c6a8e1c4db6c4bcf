//! Bounded Levenberg–Marquardt least squares with the parameter covariance.
//!
//! Minimises ½‖r(x)‖² with `lower ≤ x ≤ upper`. The Jacobian is taken by forward
//! differences (columns in parallel, each written to its own place, so the result does
//! not depend on the thread count). Steps solve (JᵀJ + λ diag(JᵀJ)) δ = −Jᵀr (Marquardt's
//! scaling) and are projected onto the bounds; λ follows Nielsen's update. At the end
//! the covariance is s² (JᵀJ)⁻¹ with s² = ‖r‖²/(n − k), the parameters' standard errors
//! are its diagonal's roots, and their correlations are the normalised covariance.
//!
//! Checked against NIST StRD nonlinear regression problems with certified values
//! (`tests/val_nist_lm.rs`).

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Stopping rules.
#[derive(Debug, Clone, Copy)]
pub struct LmOptions {
    /// Most accepted or rejected steps.
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub ftol: f64,
    /// Stop when a step moves every parameter by less than this fraction of its
    /// finite-difference step (or of its value).
    pub xtol: f64,
    /// Stop when the cost falls below this (an exact fit).
    pub cost_floor: f64,
}

impl Default for LmOptions {
    fn default() -> LmOptions {
        LmOptions {
            max_iterations: 200,
            ftol: 1e-12,
            xtol: 1e-12,
            cost_floor: 0.0,
        }
    }
}

/// The result of a fit.
#[derive(Debug, Clone)]
pub struct LmFit {
    pub x: Vec<f64>,
    /// Σ rᵢ² at `x`.
    pub sum_squares: f64,
    pub residuals: Vec<f64>,
    /// Calls of the residual function (Jacobian columns included).
    pub evaluations: usize,
    pub iterations: usize,
    /// Whether each parameter ended on a bound.
    pub at_bound: Vec<bool>,
    /// s² (JᵀJ)⁻¹; None when JᵀJ is singular (a parameter the data do not see).
    pub covariance: Option<DMatrix<f64>>,
}

impl LmFit {
    /// Standard errors (NaN when the covariance is undefined).
    pub fn std_errors(&self) -> Vec<f64> {
        match &self.covariance {
            Some(c) => (0..self.x.len())
                .map(|i| c[(i, i)].max(0.0).sqrt())
                .collect(),
            None => vec![f64::NAN; self.x.len()],
        }
    }

    /// Correlation matrix (row-major, k×k), NaN where undefined.
    pub fn correlation(&self) -> Vec<Vec<f64>> {
        let k = self.x.len();
        let se = self.std_errors();
        (0..k)
            .map(|i| {
                (0..k)
                    .map(|j| match &self.covariance {
                        Some(c) if se[i] > 0.0 && se[j] > 0.0 => c[(i, j)] / (se[i] * se[j]),
                        _ => f64::NAN,
                    })
                    .collect()
            })
            .collect()
    }
}

/// Minimises Σ r(x)² from `x0` within the bounds. `steps[i]` is the finite-difference
/// step of parameter i (taken away from the nearer bound when the step would cross
/// it). Errors of `f` end the fit and are returned.
pub fn minimize<E, F>(
    f: F,
    x0: &[f64],
    lower: &[f64],
    upper: &[f64],
    steps: &[f64],
    opts: LmOptions,
) -> Result<LmFit, E>
where
    F: Fn(&[f64]) -> Result<Vec<f64>, E> + Sync,
    E: Send,
{
    let k = x0.len();
    assert!(lower.len() == k && upper.len() == k && steps.len() == k);
    let clamp = |x: &mut [f64]| {
        for i in 0..k {
            x[i] = x[i].clamp(lower[i], upper[i]);
        }
    };
    let mut x = x0.to_vec();
    clamp(&mut x);
    let mut r = f(&x)?;
    let mut evaluations = 1;
    let n = r.len();
    let mut cost = sum_squares(&r);
    let mut jac = jacobian(&f, &x, &r, lower, upper, steps)?;
    evaluations += k;
    let mut lambda: f64 = 1e-3;
    let mut nu = 2.0;
    let mut iterations = 0;
    while iterations < opts.max_iterations && cost > opts.cost_floor && k > 0 {
        iterations += 1;
        let jtj = jac.transpose() * &jac;
        let g = jac.transpose() * DVector::from_column_slice(&r);
        // Parameters on a bound that descent would push out of it stay there this
        // step (an active set); the others take the damped Gauss–Newton step.
        let free: Vec<usize> = (0..k)
            .filter(|&i| !((x[i] <= lower[i] && g[i] > 0.0) || (x[i] >= upper[i] && g[i] < 0.0)))
            .collect();
        if free.is_empty() {
            break;
        }
        let m = free.len();
        let mut a = DMatrix::zeros(m, m);
        let mut rhs = DVector::zeros(m);
        for (p, &i) in free.iter().enumerate() {
            rhs[p] = -g[i];
            for (q, &j) in free.iter().enumerate() {
                a[(p, q)] = jtj[(i, j)];
            }
            a[(p, p)] += lambda * jtj[(i, i)].max(1e-300);
        }
        let Some(sol) = a.cholesky().map(|c| c.solve(&rhs)) else {
            lambda *= nu;
            nu *= 2.0;
            continue;
        };
        let mut delta = DVector::zeros(k);
        for (p, &i) in free.iter().enumerate() {
            delta[i] = sol[p];
        }
        let mut trial = x.clone();
        for i in 0..k {
            trial[i] += delta[i];
        }
        clamp(&mut trial);
        let step: Vec<f64> = (0..k).map(|i| trial[i] - x[i]).collect();
        let small = (0..k).all(|i| step[i].abs() <= opts.xtol * steps[i].abs().max(x[i].abs()));
        if small {
            break;
        }
        let r_trial = f(&trial)?;
        evaluations += 1;
        let cost_trial = sum_squares(&r_trial);
        // Gain ratio: actual against predicted reduction of the linear model.
        let s = DVector::from_column_slice(&step);
        let predicted = -(2.0 * g.dot(&s) + (&jac * &s).norm_squared());
        let rho = if predicted > 0.0 {
            (cost - cost_trial) / predicted
        } else {
            -1.0
        };
        if cost_trial < cost && rho > 0.0 {
            let reduction = (cost - cost_trial) / cost.max(1e-300);
            x = trial;
            r = r_trial;
            cost = cost_trial;
            lambda *= (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3));
            nu = 2.0;
            if reduction < opts.ftol {
                break;
            }
            jac = jacobian(&f, &x, &r, lower, upper, steps)?;
            evaluations += k;
        } else {
            lambda *= nu;
            nu *= 2.0;
            if lambda > 1e16 {
                break;
            }
        }
    }
    let at_bound = (0..k)
        .map(|i| x[i] <= lower[i] || x[i] >= upper[i])
        .collect();
    let dof = n.saturating_sub(k).max(1) as f64;
    let s2 = cost / dof;
    let jtj = jac.transpose() * &jac;
    let covariance = jtj.cholesky().map(|c| c.inverse() * s2);
    Ok(LmFit {
        x,
        sum_squares: cost,
        residuals: r,
        evaluations,
        iterations,
        at_bound,
        covariance,
    })
}

fn sum_squares(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// Forward-difference Jacobian, columns in parallel.
fn jacobian<E, F>(
    f: &F,
    x: &[f64],
    r: &[f64],
    lower: &[f64],
    upper: &[f64],
    steps: &[f64],
) -> Result<DMatrix<f64>, E>
where
    F: Fn(&[f64]) -> Result<Vec<f64>, E> + Sync,
    E: Send,
{
    let k = x.len();
    let columns: Vec<Result<Vec<f64>, E>> = (0..k)
        .into_par_iter()
        .map(|i| {
            let mut h = steps[i];
            if x[i] + h > upper[i] {
                h = -h;
            }
            if x[i] + h < lower[i] {
                h = upper[i] - x[i];
            }
            let mut xp = x.to_vec();
            xp[i] += h;
            let rp = f(&xp)?;
            Ok(rp.iter().zip(r).map(|(a, b)| (a - b) / h).collect())
        })
        .collect();
    let mut jac = DMatrix::zeros(r.len(), k);
    for (i, c) in columns.into_iter().enumerate() {
        let c = c?;
        jac.set_column(i, &DVector::from_vec(c));
    }
    Ok(jac)
}

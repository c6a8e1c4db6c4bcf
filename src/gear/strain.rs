//! Thermal strain laws ε(T) = ΔL/L relative to the assembly (zero-strain) temperature.
//! Non-linear laws are integrated as strains, never as α × ΔT with a mean α.

use crate::numeric::interpolate;

#[derive(Debug, Clone, PartialEq)]
pub enum StrainLaw {
    /// ε = α (T − T_ref).
    Linear { alpha_per_k: f64 },
    /// α(T) = α + dα/dT (T − T_ref): ε = α ΔT + ½ dα/dT ΔT².
    Quadratic {
        alpha_per_k: f64,
        dalpha_dt_per_k2: f64,
    },
    /// ΔL/L = scale · Σ cᵢ Tⁱ (a published fit, e.g. NIST cryogenic data), shifted so
    /// that ε(T_ref) = 0.
    Polynomial { coefficients: Vec<f64>, scale: f64 },
    /// α(T) = Σ aᵢ Tⁱ (1/K), integrated exactly: ε = ∫ α dT from T_ref.
    AlphaPolynomial { coefficients: Vec<f64> },
    /// ΔL/L tabulated against T (linear interpolation, held at the ends), shifted so
    /// that ε(T_ref) = 0.
    Table {
        temperature_k: Vec<f64>,
        strain: Vec<f64>,
    },
}

impl StrainLaw {
    /// Strain at `t_k` relative to `t_ref_k`.
    pub fn strain(&self, t_k: f64, t_ref_k: f64) -> f64 {
        let d = t_k - t_ref_k;
        match self {
            StrainLaw::Linear { alpha_per_k } => alpha_per_k * d,
            StrainLaw::Quadratic {
                alpha_per_k,
                dalpha_dt_per_k2,
            } => alpha_per_k * d + 0.5 * dalpha_dt_per_k2 * d * d,
            StrainLaw::Polynomial {
                coefficients,
                scale,
            } => {
                let p = |t: f64| coefficients.iter().rev().fold(0.0, |acc, c| acc * t + c);
                scale * (p(t_k) - p(t_ref_k))
            }
            StrainLaw::AlphaPolynomial { coefficients } => {
                // antiderivative Σ aᵢ Tⁱ⁺¹/(i+1)
                let p = |t: f64| {
                    coefficients
                        .iter()
                        .enumerate()
                        .rev()
                        .fold(0.0, |acc, (i, c)| acc * t + c / (i + 1) as f64)
                        * t
                };
                p(t_k) - p(t_ref_k)
            }
            StrainLaw::Table {
                temperature_k,
                strain,
            } => {
                interpolate(temperature_k, strain, t_k)
                    - interpolate(temperature_k, strain, t_ref_k)
            }
        }
    }

    /// Instantaneous expansion coefficient dε/dT at `t_k`, 1/K.
    pub fn alpha_at(&self, t_k: f64, t_ref_k: f64) -> f64 {
        match self {
            StrainLaw::Linear { alpha_per_k } => *alpha_per_k,
            StrainLaw::Quadratic {
                alpha_per_k,
                dalpha_dt_per_k2,
            } => alpha_per_k + dalpha_dt_per_k2 * (t_k - t_ref_k),
            StrainLaw::AlphaPolynomial { coefficients } => {
                coefficients.iter().rev().fold(0.0, |acc, c| acc * t_k + c)
            }
            _ => {
                let h = 0.01;
                (self.strain(t_k + h, t_ref_k) - self.strain(t_k - h, t_ref_k)) / (2.0 * h)
            }
        }
    }

    /// α when the law is linear.
    pub fn linear_alpha(&self) -> Option<f64> {
        match self {
            StrainLaw::Linear { alpha_per_k } => Some(*alpha_per_k),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_strain_laws_vanish_at_reference_and_agree_when_linear() {
        let t_ref = 298.15;
        let lin = StrainLaw::Linear { alpha_per_k: 11e-6 };
        let quad = StrainLaw::Quadratic {
            alpha_per_k: 11e-6,
            dalpha_dt_per_k2: 0.0,
        };
        let poly = StrainLaw::Polynomial {
            coefficients: vec![1.0, 11.0],
            scale: 1e-6,
        };
        let table = StrainLaw::Table {
            temperature_k: vec![0.0, 1000.0],
            strain: vec![0.0, 11e-3],
        };
        for law in [&lin, &quad, &poly, &table] {
            assert!(law.strain(t_ref, t_ref).abs() < 1e-18);
            assert!((law.strain(t_ref + 40.0, t_ref) - 440e-6).abs() < 1e-12);
            assert!((law.alpha_at(250.0, t_ref) - 11e-6).abs() < 1e-10);
        }
        let q = StrainLaw::Quadratic {
            alpha_per_k: 11e-6,
            dalpha_dt_per_k2: 2e-8,
        };
        // The same α(T) as a polynomial in T: α = (11e-6 − 2e-8 T_ref) + 2e-8 T.
        let ap = StrainLaw::AlphaPolynomial {
            coefficients: vec![11e-6 - 2e-8 * t_ref, 2e-8],
        };
        for t in [150.0, 250.0, 298.15, 400.0] {
            assert!(
                (ap.strain(t, t_ref) - q.strain(t, t_ref)).abs() < 1e-15,
                "{t}"
            );
            assert!((ap.alpha_at(t, t_ref) - q.alpha_at(t, t_ref)).abs() < 1e-11);
        }
        // ε = ∫ α(T) dT: 11e-6·(−100) + ½·2e-8·100²
        assert!((q.strain(t_ref - 100.0, t_ref) - (-1.1e-3 + 1e-4)).abs() < 1e-15);
    }
}

//! Thermal displacement of a gear's base circle from its radial temperature profile,
//! for a plane-stress disc (paper eqs. (11)–(16); `shared/spec/physics.md` §2).
//!
//! Between neighbouring gear nodes the temperature follows the steady-conduction
//! logarithmic profile of eq. (10). With I = ∫ ε(T(r)) r dr from bore r_a to base
//! circle r_b:
//! - free bore:  u(r_b) = 2 r_b I / (r_b² − r_a²)  (ν drops out; eq. (16) for two nodes);
//! - bore bonded to a rigid shaft (u(r_a) = 0): u(r_b) = 2(1+ν) r_b I / ((1+ν) r_b² + (1−ν) r_a²);
//! - bore on an elastic solid shaft with radial interference δ: Lamé contact pressure
//!   p ≥ 0 from u_disc(r_a) = δ + u_shaft(r_a); the rim then moves by
//!   u_free(r_b) + 2 p r_a² r_b / (E (r_b² − r_a²)).

use super::strain::StrainLaw;

/// How the bore is held.
#[derive(Debug, Clone, PartialEq)]
pub enum BoreFit {
    Free,
    /// Bonded to a rigid shaft that does not expand: u(r_a) = 0.
    Rigid,
    /// A solid elastic shaft with radial interference at assembly; contact carries
    /// compression only (the fit opens when the bore outgrows the shaft).
    Elastic {
        interference_m: f64,
        shaft_youngs_modulus_pa: f64,
        shaft_poisson: f64,
        shaft_strain: StrainLaw,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct DiscMaterial {
    pub strain: StrainLaw,
    pub youngs_modulus_pa: f64,
    pub poisson: f64,
}

/// Base-circle displacement and bore contact pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiscDisplacement {
    pub base_circle_m: f64,
    pub bore_pressure_pa: f64,
}

/// I = ∫ ε(T(r)) r dr over the gear nodes' radii (bore first, base circle last),
/// log-piecewise temperature between nodes. Exact for a linear strain law; 8-point
/// Gauss–Legendre per piece otherwise.
pub fn strain_moment_m2(radii_m: &[f64], temps_k: &[f64], law: &StrainLaw, t_ref_k: f64) -> f64 {
    let segments: Vec<Segment> = radii_m
        .windows(2)
        .map(|w| Segment::between(w[0], w[1]))
        .collect();
    strain_moment_with(radii_m, &segments, temps_k, law, t_ref_k)
}

/// What [`strain_moment_m2`] computes from the radii alone, per segment (r_k, r_k+1):
/// cached per gear, the same expressions, so the moment is the same to the last bit.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Segment {
    /// ln(r2/r1)
    pub l: f64,
    /// r2² − r1²
    pub area2: f64,
    /// r2²/2 − (r2² − r1²)/(4 ln(r2/r1)): the weight of the temperature change across
    /// the segment for a linear strain law.
    pub linear: f64,
}

impl Segment {
    /// The segments of `radii_m` (at most `MAX_GEAR_NODES` radii), in a fixed array.
    pub fn of(radii_m: &[f64]) -> [Segment; crate::gear::MAX_GEAR_NODES] {
        let mut out = [Segment::default(); crate::gear::MAX_GEAR_NODES];
        for (k, w) in radii_m.windows(2).enumerate().take(out.len()) {
            out[k] = Segment::between(w[0], w[1]);
        }
        out
    }

    /// The segment from radius `r1` to `r2`.
    pub fn between(r1: f64, r2: f64) -> Segment {
        let l = (r2 / r1).ln();
        let area2 = r2 * r2 - r1 * r1;
        Segment {
            l,
            area2,
            linear: 0.5 * r2 * r2 - area2 / (4.0 * l),
        }
    }
}

/// [`strain_moment_m2`] with the segments' constants given (`segments[k]` for radii k,
/// k + 1).
pub fn strain_moment_with(
    radii_m: &[f64],
    segments: &[Segment],
    temps_k: &[f64],
    law: &StrainLaw,
    t_ref_k: f64,
) -> f64 {
    debug_assert_eq!(radii_m.len(), temps_k.len());
    let mut total = 0.0;
    for k in 0..radii_m.len() - 1 {
        let (r1, r2) = (radii_m[k], radii_m[k + 1]);
        let (t1, t2) = (temps_k[k], temps_k[k + 1]);
        let Segment { l, area2, linear } = segments[k];
        total += match law.linear_alpha() {
            Some(alpha) => {
                let (d1, d2) = (t1 - t_ref_k, t2 - t_ref_k);
                alpha * (d1 * 0.5 * area2 + (d2 - d1) * linear)
            }
            None => {
                let half = 0.5 * (r2 - r1);
                let mid = 0.5 * (r2 + r1);
                GAUSS8
                    .iter()
                    .map(|&(x, w)| {
                        let r = mid + half * x;
                        let t = t1 + (t2 - t1) * (r / r1).ln() / l;
                        w * law.strain(t, t_ref_k) * r
                    })
                    .sum::<f64>()
                    * half
            }
        };
    }
    total
}

/// Base-circle displacement of a disc with bore `radii_m[0]` and base circle
/// `radii_m[last]`. `shaft_temp_k` is used by the elastic fit only.
pub fn base_circle_displacement(
    radii_m: &[f64],
    temps_k: &[f64],
    material: &DiscMaterial,
    fit: &BoreFit,
    t_ref_k: f64,
    shaft_temp_k: f64,
) -> DiscDisplacement {
    let i = strain_moment_m2(radii_m, temps_k, &material.strain, t_ref_k);
    displacement_of_moment(radii_m, i, material, fit, t_ref_k, shaft_temp_k)
}

/// [`base_circle_displacement`] from the strain moment `i` = ∫ ε r dr over the disc.
pub fn displacement_of_moment(
    radii_m: &[f64],
    i: f64,
    material: &DiscMaterial,
    fit: &BoreFit,
    t_ref_k: f64,
    shaft_temp_k: f64,
) -> DiscDisplacement {
    let ra = radii_m[0];
    let rb = *radii_m.last().expect("nodes");
    let nu = material.poisson;
    let free_b = 2.0 * rb * i / (rb * rb - ra * ra);
    match fit {
        BoreFit::Free => DiscDisplacement {
            base_circle_m: free_b,
            bore_pressure_pa: 0.0,
        },
        BoreFit::Rigid => DiscDisplacement {
            base_circle_m: 2.0 * (1.0 + nu) * rb * i
                / ((1.0 + nu) * rb * rb + (1.0 - nu) * ra * ra),
            bore_pressure_pa: f64::NAN,
        },
        BoreFit::Elastic {
            interference_m,
            shaft_youngs_modulus_pa: es,
            shaft_poisson: nus,
            shaft_strain,
        } => {
            let e = material.youngs_modulus_pa;
            let d2 = rb * rb - ra * ra;
            let free_a = 2.0 * ra * i / d2;
            // Bore displacement per unit internal pressure (Lamé, plane stress).
            let g_a = ra / e * ((1.0 - nu) * ra * ra + (1.0 + nu) * rb * rb) / d2;
            // Solid shaft: u = r ε − p r (1 − ν_s)/E_s.
            let g_s = ra * (1.0 - nus) / es;
            let shaft_free = ra * shaft_strain.strain(shaft_temp_k, t_ref_k);
            let p = ((interference_m + shaft_free - free_a) / (g_a + g_s)).max(0.0);
            DiscDisplacement {
                base_circle_m: free_b + p * 2.0 * ra * ra * rb / (e * d2),
                bore_pressure_pa: p,
            }
        }
    }
}

/// 8-point Gauss–Legendre nodes and weights on [−1, 1] (also the sensor lag's rule).
pub(crate) const GAUSS8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (-0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_47),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_26),
];

#[cfg(test)]
mod tests {
    use super::*;

    fn steel() -> DiscMaterial {
        DiscMaterial {
            strain: StrainLaw::Linear {
                alpha_per_k: 10.2e-6,
            },
            youngs_modulus_pa: 200e9,
            poisson: 0.3,
        }
    }

    #[test]
    fn val_physics_md_check_value_of_eq16() {
        // r_a = 5, r_b = 28.19078 mm, t_a = −20 K, t_b = −60 K, α = 10.2e-6 → −0.0143012 mm
        let t_ref = 300.0;
        let d = base_circle_displacement(
            &[5e-3, 28.19078e-3],
            &[t_ref - 20.0, t_ref - 60.0],
            &steel(),
            &BoreFit::Free,
            t_ref,
            t_ref,
        );
        assert!(
            (d.base_circle_m * 1e3 - (-0.014_301_2)).abs() < 5e-8,
            "{}",
            d.base_circle_m * 1e3
        );
    }

    #[test]
    fn core_gauss_path_matches_closed_form_for_a_linear_law() {
        let radii = [3e-3, 5.309499e-3, 9.396926e-3];
        let temps = [310.0, 290.0, 250.0];
        let lin = StrainLaw::Linear { alpha_per_k: 11e-6 };
        let quad = StrainLaw::Quadratic {
            alpha_per_k: 11e-6,
            dalpha_dt_per_k2: 0.0,
        };
        let a = strain_moment_m2(&radii, &temps, &lin, 298.15);
        let b = strain_moment_m2(&radii, &temps, &quad, 298.15);
        assert!((a - b).abs() < 1e-12 * a.abs());
    }

    #[test]
    fn core_elastic_fit_limits() {
        let radii = [5e-3, 18.8e-3];
        let temps = [330.0, 340.0];
        let t_ref = 298.15;
        let m = steel();
        let shaft = |e: f64, delta: f64| BoreFit::Elastic {
            interference_m: delta,
            shaft_youngs_modulus_pa: e,
            shaft_poisson: 0.3,
            shaft_strain: StrainLaw::Linear { alpha_per_k: 0.0 },
        };
        let free = base_circle_displacement(&radii, &temps, &m, &BoreFit::Free, t_ref, t_ref);
        // No interference and a warmer disc: the fit opens, the disc is free.
        let open = base_circle_displacement(&radii, &temps, &m, &shaft(200e9, 0.0), t_ref, t_ref);
        assert_eq!(open.bore_pressure_pa, 0.0);
        assert_eq!(open.base_circle_m, free.base_circle_m);
        // A colder disc shrinks onto a stiff, non-expanding shaft without interference:
        // the bore is held at u(r_a) = 0, as for the bonded rigid bore.
        let cold = [270.0, 250.0];
        let rigid = base_circle_displacement(&radii, &cold, &m, &BoreFit::Rigid, t_ref, t_ref);
        let stiff = base_circle_displacement(&radii, &cold, &m, &shaft(1e30, 0.0), t_ref, t_ref);
        assert!(stiff.bore_pressure_pa > 0.0);
        let rel = (stiff.base_circle_m - rigid.base_circle_m).abs() / rigid.base_circle_m.abs();
        assert!(
            rel < 1e-12,
            "{} vs {}",
            stiff.base_circle_m,
            rigid.base_circle_m
        );
        assert!(rigid.base_circle_m < 0.0 && free.base_circle_m > 0.0);
    }
}

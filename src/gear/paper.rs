//! The paper's backlash model, equations (16)–(22) of the seed paper, as printed,
//! with only the corrections needed to return the nominal backlash at ΔT = 0.
//!
//! Each correction is marked CORRECTION below. The equations, with t = change from the
//! assembly temperature and α_m the (constant) expansion coefficient:
//!
//! - (16) β_b = r_b α t_a + α r_b³ (t_b − t_a)/(r_b² − r_a²) − α r_b (t_b − t_a)/(2 ln(r_b/r_a)),
//!   with t_a the bore node and t_b the base-circle node (the paper has two nodes; the
//!   printed "a_m" is α_m).
//! - (17) R′_b = R_b + β_b + K′.
//! - (18) (R′_b1 + 2K′ + R′_b2)/cos α′ = (R_b1 + R_b2 + 2K)/cos α, which fixes α at
//!   assembly from the centre distance: cos α = (R_b1 + R_b2 + 2K)/a.
//! - (19) α′ = arccos((R_b1 + β_b1 + 2K′ + R_b2 + β_b2)/(R_b1 + R_b2 + 2K)).
//! - (20) Y_b1 = 2π R′_b1 / Z.
//! - (21) N_b = (R′_b + K′)[S/R − (inv α′ − inv α)].
//! - (22) F = Y_b1 − N_b1 − N_b1 + 2(R′_b1 + R′_b2 + K′) inv α′.

use super::GearPair;
use super::involute::inv;

/// What the paper's model needs that does not change with temperature, computed once
/// per pair (`GearPair::constants`): each expression as `raw` would evaluate it, so the
/// results are the same to the last bit.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Constants {
    /// Per gear: r_b, α_m, α_m r_b³ … as (16) uses them.
    rb: [f64; 2],
    alpha: [f64; 2],
    rb3: [f64; 2],
    /// r_b² − r_a²
    d2: [f64; 2],
    /// 2 ln(r_b/r_a)
    two_ln: [f64; 2],
    /// cos α (18) and α at assembly.
    cos_alpha: f64,
    inv_asm: f64,
    /// s/r + 2 inv α₀ per gear (21).
    s_over_r: [f64; 2],
    /// raw(ΔT = 0) at the assembly centre distance, and the nominal backlash.
    zero_m: f64,
    nominal_m: f64,
}

impl Constants {
    pub fn of(pair: &GearPair) -> Constants {
        let m = pair.module_m;
        let a0 = pair.pressure_angle_rad;
        let t_ref = pair.reference_temperature_k;
        let k0 = pair.coating.thickness_m;
        let g = &pair.gears;
        let each = |f: &dyn Fn(usize) -> f64| [f(0), f(1)];
        let rb = each(&|k| g[k].base_radius_m(m, a0));
        let ra = each(&|k| g[k].bore_radius_m);
        let cos_alpha = (rb[0] + rb[1] + 2.0 * k0) / pair.center_distance_m;
        let inv_a0 = inv(a0);
        let mut c = Constants {
            rb,
            alpha: each(&|k| g[k].material.strain.alpha_at(t_ref, t_ref)),
            rb3: each(&|k| rb[k].powi(3)),
            d2: each(&|k| rb[k] * rb[k] - ra[k] * ra[k]),
            two_ln: each(&|k| 2.0 * (rb[k] / ra[k]).ln()),
            cos_alpha,
            inv_asm: inv(cos_alpha.acos()),
            s_over_r: each(&|k| g[k].tooth_thickness_m / g[k].reference_radius_m(m) + 2.0 * inv_a0),
            zero_m: 0.0,
            nominal_m: pair.nominal_backlash_m(),
        };
        c.zero_m = raw(pair, &c, [(0.0, 0.0), (0.0, 0.0)], pair.center_distance_m);
        c
    }
}

/// Normal backlash by the paper's equations at node temperatures `temps_k` and centre
/// distance `a_m`, m.
pub fn backlash_m(pair: &GearPair, temps_k: &[f64], a_m: f64) -> f64 {
    let t_ref = pair.reference_temperature_k;
    let delta = |i: usize| temps_k[i] - t_ref;
    let state = |k: usize| {
        let g = &pair.gears[k];
        let ta = delta(g.nodes[0]);
        let tb = delta(*g.nodes.last().expect("nodes"));
        (ta, tb)
    };
    let c = &pair.constants().paper;
    raw(pair, c, [state(0), state(1)], a_m) - c.zero_m + c.nominal_m
}

/// Equations (16)–(22) with corrections 1–3; `dt[k]` = (t_a, t_b) of gear k.
fn raw(pair: &GearPair, c: &Constants, dt: [(f64, f64); 2], a_m: f64) -> f64 {
    let k0 = pair.coating.thickness_m;
    let g = &pair.gears;
    // α_m: the expansion coefficient at the assembly temperature.
    let alpha = |k: usize| c.alpha[k];
    // (16)
    let beta_b = |k: usize| {
        let (ta, tb) = dt[k];
        let rb = c.rb[k];
        let al = alpha(k);
        rb * al * ta + al * c.rb3[k] * (tb - ta) / c.d2[k] - al * rb * (tb - ta) / c.two_ln[k]
    };
    // K′ from the bonded-film formula at the rim temperature change (pinion's rim; the
    // paper has one K′ for both gears).
    let tb1 = dt[0].1;
    let k1 = pair.coating.thickness_at_m(tb1, alpha(0) * tb1);
    let rb = c.rb;
    let bb = [beta_b(0), beta_b(1)];
    // (17)
    let rbp = [rb[0] + bb[0] + k1, rb[1] + bb[1] + k1];
    // (18): α at assembly (cos α in the constants).
    let cos_alpha = c.cos_alpha;
    // (19). CORRECTION 1: the printed ratio drops the factor cos α of (18), which gives
    // α′ = 0 at ΔT = 0; restored. A centre distance that moves (a′ ≠ a) enters as a/a′.
    let cos_ap = (rb[0] + bb[0] + 2.0 * k1 + rb[1] + bb[1]) / (rb[0] + rb[1] + 2.0 * k0)
        * cos_alpha
        * (pair.center_distance_m / a_m);
    let ap = cos_ap.min(1.0).acos();
    // (20)
    let yb1 = std::f64::consts::TAU * rbp[0] / g[0].teeth as f64;
    // (21). CORRECTION 2: the printed bracket lacks the base-circle term 2 inv α₀ of the
    // standard base tooth thickness s_b = r_b (s/r + 2 inv α₀); added.
    let (inv_ap, inv_asm) = (inv(ap), c.inv_asm);
    let nb = |k: usize| (rbp[k] + k1) * (c.s_over_r[k] - (inv_ap - inv_asm));
    // (22). CORRECTION 3: the second N_b1 is N_b2.
    yb1 - nb(0) - nb(1) + 2.0 * (rbp[0] + rbp[1] + k1) * inv_ap
    // CORRECTION 4 (in `backlash_m`): the coating terms of (17)–(22) do not return the
    // nominal backlash at ΔT = 0 (K′ enters the radii, the pitch and the thicknesses),
    // so the model is used for the change from ΔT = 0, added to the nominal backlash.
}

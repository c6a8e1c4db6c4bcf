//! Gear pair of `reference-mechanism.md` §3 and `physics.md` §2–§4, written from the spec:
//! disc displacement of the base circle from a radial temperature profile (free, or
//! with the bore on an elastic shaft), coating, and the exact smallest normal backlash
//! over a mesh cycle by a tooth-pair scan on the two lines of action.
//!
//! Lengths in metres, temperatures as changes from the assembly temperature (K).

use std::f64::consts::PI;

/// Assembly (zero-strain) reference temperature (K).
pub const T_REF_K: f64 = 298.15;
/// Nominal centre distance at 25 °C (m).
pub const CENTRE_DISTANCE_M: f64 = 30.000e-3;
/// Coating: MoS2 thickness K on every flank (m), α_c, ν_c.
pub const COATING_M: f64 = 1.0e-6;
pub const COATING_ALPHA_PER_K: f64 = 8.0e-6;
pub const COATING_NU: f64 = 0.25;

/// Thermo-elastic material: strain law ε(ΔT) = α ΔT + ½ (dα/dT) ΔT², the integral of
/// α(T) = α + dα/dT (T − T_ref) from T_ref.
#[derive(Clone, Copy, Debug)]
pub struct Material {
    pub alpha_per_k: f64,
    pub dalpha_dt_per_k2: f64,
    pub e_pa: f64,
    pub nu: f64,
}

impl Material {
    /// 17-4PH: α = 11.0e-6 /K, E = 197 GPa, ν = 0.27.
    pub fn steel_17_4ph() -> Self {
        Material {
            alpha_per_k: 11.0e-6,
            dalpha_dt_per_k2: 0.0,
            e_pa: 197.0e9,
            nu: 0.27,
        }
    }

    /// Free thermal strain at ΔT from the assembly temperature.
    pub fn strain(&self, dt_k: f64) -> f64 {
        self.alpha_per_k * dt_k + 0.5 * self.dalpha_dt_per_k2 * dt_k * dt_k
    }
}

/// One gear's cold, uncoated geometry at 25 °C.
#[derive(Clone, Copy, Debug)]
pub struct GearSpec {
    pub teeth: f64,
    pub module_m: f64,
    pub pressure_angle_rad: f64,
    /// Tooth thinning from πm/2 (m).
    pub thinning_m: f64,
    pub tip_radius_m: f64,
    pub bore_radius_m: f64,
}

fn inv(a: f64) -> f64 {
    a.tan() - a
}

impl GearSpec {
    pub fn pinion() -> Self {
        GearSpec {
            teeth: 20.0,
            module_m: 1.0e-3,
            pressure_angle_rad: 20f64.to_radians(),
            thinning_m: 0.0194745e-3,
            tip_radius_m: 11.0e-3,
            bore_radius_m: 3.0e-3,
        }
    }

    pub fn wheel() -> Self {
        GearSpec {
            teeth: 40.0,
            tip_radius_m: 21.0e-3,
            bore_radius_m: 5.0e-3,
            ..Self::pinion()
        }
    }

    pub fn pitch_radius_m(&self) -> f64 {
        self.module_m * self.teeth / 2.0
    }

    /// r_b = r cos α₀.
    pub fn base_radius_m(&self) -> f64 {
        self.pitch_radius_m() * self.pressure_angle_rad.cos()
    }

    /// Reference tooth thickness s = πm/2 − thinning.
    pub fn tooth_thickness_m(&self) -> f64 {
        PI * self.module_m / 2.0 - self.thinning_m
    }

    /// Base tooth thickness s_b = r_b (s/r + 2 inv α₀) (uncoated).
    pub fn base_tooth_thickness_m(&self) -> f64 {
        self.base_radius_m()
            * (self.tooth_thickness_m() / self.pitch_radius_m()
                + 2.0 * inv(self.pressure_angle_rad))
    }

    /// The hot, coated tooth ring for a rim hoop strain `e` and coating thickness `k_m`:
    /// every tooth dimension scales with 1 + e, the coating adds 2K to the base tooth
    /// thickness and keeps the base circle.
    pub fn teeth_at(&self, e: f64, k_m: f64) -> Teeth {
        let s = 1.0 + e;
        let rb = self.base_radius_m() * s;
        Teeth {
            base_radius_m: rb,
            base_thickness_m: self.base_tooth_thickness_m() * s + 2.0 * k_m,
            tip_radius_m: self.tip_radius_m * s,
            base_pitch_m: 2.0 * PI * rb / self.teeth,
        }
    }
}

/// The tooth ring of one gear in its current state.
#[derive(Clone, Copy, Debug)]
pub struct Teeth {
    pub base_radius_m: f64,
    pub base_thickness_m: f64,
    pub tip_radius_m: f64,
    pub base_pitch_m: f64,
}

/// Gauss–Legendre nodes and weights on [−1, 1], by Newton's method on P_n.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let kf = k as f64;
                let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

/// I = ∫ ε(T(r)) r dr from the first to the last radius, with the logarithmic
/// steady-conduction profile between neighbouring nodes (T linear in ln r). Each
/// segment is integrated in u = ln r by Gauss–Legendre (12 points: exact to rounding
/// for the segments of these gears).
pub fn strain_area_integral(radii_m: &[f64], dt_k: &[f64], mat: &Material) -> f64 {
    assert_eq!(radii_m.len(), dt_k.len());
    let gl = gauss_legendre(12);
    let mut total = 0.0;
    for w in 0..radii_m.len() - 1 {
        let (u0, u1) = (radii_m[w].ln(), radii_m[w + 1].ln());
        let (t0, t1) = (dt_k[w], dt_k[w + 1]);
        let (mid, half) = ((u0 + u1) / 2.0, (u1 - u0) / 2.0);
        for &(x, wt) in &gl {
            let u = mid + half * x;
            let t = t0 + (t1 - t0) * (u - u0) / (u1 - u0);
            total += wt * half * mat.strain(t) * (2.0 * u).exp();
        }
    }
    total
}

/// A bore pressed on a solid shaft of the same material (`mat`) with radial
/// interference δ (shaft radius minus bore radius at 25 °C), shaft at `shaft_dt_k`.
#[derive(Clone, Copy, Debug)]
pub struct BoreFit {
    pub interference_m: f64,
    pub shaft_dt_k: f64,
}

/// Radial displacement of the rim (base circle) of a plane-stress disc from bore
/// `radii[0]` to rim `radii[last]` with nodal temperature changes `dt_k`.
///
/// Free bore: u(r_b) = 2 r_b I / (r_b² − r_a²).
/// Bore on an elastic solid shaft (plane stress for both), contact pressure p ≥ 0 from
/// u_disc(r_a) = u_shaft(r_a):
///   u_disc(r_a) = 2 r_a I/(r_b² − r_a²) + p r_a [(1−ν) r_a² + (1+ν) r_b²] / (E (r_b² − r_a²)),
///   u_shaft(r_a) = δ + r_a ε(T_shaft) − p r_a (1−ν)/E,
/// and then u(r_b) gains the Lamé term 2 p r_a² r_b / (E (r_b² − r_a²)).
pub fn rim_displacement_m(
    radii_m: &[f64],
    dt_k: &[f64],
    mat: &Material,
    fit: Option<BoreFit>,
) -> f64 {
    let ra = radii_m[0];
    let rb = *radii_m.last().unwrap();
    let d2 = rb * rb - ra * ra;
    let i = strain_area_integral(radii_m, dt_k, mat);
    let free_rim = 2.0 * rb * i / d2;
    let Some(fit) = fit else {
        return free_rim;
    };
    let (e, nu) = (mat.e_pa, mat.nu);
    let free_bore = 2.0 * ra * i / d2;
    let shaft = fit.interference_m + ra * mat.strain(fit.shaft_dt_k);
    let compliance =
        ra * ((1.0 - nu) * ra * ra + (1.0 + nu) * rb * rb) / (e * d2) + ra * (1.0 - nu) / e;
    let p = ((shaft - free_bore) / compliance).max(0.0);
    free_rim + 2.0 * p * ra * ra * rb / (e * d2)
}

/// Rim displacement of a bore bonded to a rigid shaft, physics.md §2:
/// u(r_b) = 2(1+ν) α r_b I / ((1+ν) r_b² + (1−ν) r_a²) (linear strain law).
pub fn rim_displacement_rigid_bore_m(radii_m: &[f64], dt_k: &[f64], mat: &Material) -> f64 {
    let ra = radii_m[0];
    let rb = *radii_m.last().unwrap();
    let i = strain_area_integral(radii_m, dt_k, mat);
    2.0 * (1.0 + mat.nu) * rb * i / ((1.0 + mat.nu) * rb * rb + (1.0 - mat.nu) * ra * ra)
}

/// Coating thickness at a rim temperature change: K (1 + ε_z),
/// ε_z = [(1+ν_c) α_c ΔT − 2 ν_c ε_s] / (1 − ν_c) with ε_s the substrate's free strain.
pub fn coating_thickness_m(dt_rim_k: f64, substrate: &Material) -> f64 {
    let ez = ((1.0 + COATING_NU) * COATING_ALPHA_PER_K * dt_rim_k
        - 2.0 * COATING_NU * substrate.strain(dt_rim_k))
        / (1.0 - COATING_NU);
    COATING_M * (1.0 + ez)
}

/// Mesh geometry shared by the backlash routines.
struct Mesh {
    alpha_w: f64,
    /// Path of contact on each line, measured from T1: [start, end].
    start: f64,
    end: f64,
    /// Gear-1 flanks on line B sit at a1 − σ + k p1 when its flanks on line A sit at σ + k p1.
    a1: f64,
    /// Gear-2 flanks on line B sit at a2 − τ + j p2 when its flanks on line A sit at τ + j p2.
    a2: f64,
    p1: f64,
    p2: f64,
}

fn mesh(g1: &Teeth, g2: &Teeth, centre_m: f64) -> Mesh {
    let rbs = g1.base_radius_m + g2.base_radius_m;
    assert!(rbs < centre_m, "base circles overlap the centre distance");
    let alpha_w = (rbs / centre_m).acos();
    let l = (centre_m * centre_m - rbs * rbs).sqrt();
    let tip1 = (g1.tip_radius_m.powi(2) - g1.base_radius_m.powi(2)).sqrt();
    let tip2 = (g2.tip_radius_m.powi(2) - g2.base_radius_m.powi(2)).sqrt();
    Mesh {
        alpha_w,
        start: (l - tip2).max(0.0),
        end: tip1.min(l),
        a1: 2.0 * g1.base_radius_m * alpha_w + g1.base_thickness_m,
        a2: 2.0 * l - 2.0 * g2.base_radius_m * alpha_w - g2.base_thickness_m,
        p1: g1.base_pitch_m,
        p2: g2.base_pitch_m,
    }
}

/// Normal backlash at one mesh position: gear-1 flanks of one side cross line of action
/// A at σ + k p₁ (distance from gear 1's tangency point T1), gear 2 is turned until its
/// nearest flank touches on line A; the backlash is then the smallest gap on line B.
/// Only flanks inside the path of contact (between the tip circles) count.
fn backlash_at(m: &Mesh, sigma: f64) -> f64 {
    let tau = sigma; // any gear-2 phase: turning gear 2 moves A gaps and B gaps oppositely
    let side = |x0: f64, y0: f64| -> f64 {
        let k0 = ((m.start - x0) / m.p1).ceil() as i64;
        let k1 = ((m.end - x0) / m.p1).floor() as i64;
        assert!(k0 <= k1, "no tooth pair in the path of contact");
        (k0..=k1)
            .map(|k| {
                let x = x0 + k as f64 * m.p1;
                let j = ((x - y0) / m.p2).round();
                y0 + j * m.p2 - x
            })
            .fold(f64::INFINITY, f64::min)
    };
    let gap_a = side(sigma, tau);
    let gap_b = side(m.a1 - sigma, m.a2 - tau);
    gap_a + gap_b
}

/// Exact smallest normal backlash over a mesh cycle (m). The set of tooth pairs inside
/// the path of contact on each line changes only where a gear-1 flank crosses an end of
/// the path; between those phases the backlash is constant, so one evaluation per
/// interval of σ ∈ [0, p₁) finds the exact minimum.
pub fn worst_backlash_m(g1: &Teeth, g2: &Teeth, centre_m: f64) -> f64 {
    let m = mesh(g1, g2, centre_m);
    let mut cuts: Vec<f64> = [m.start, m.end, m.a1 - m.start, m.a1 - m.end]
        .iter()
        .map(|c| c.rem_euclid(m.p1))
        .collect();
    cuts.push(0.0);
    cuts.push(m.p1);
    cuts.sort_by(f64::total_cmp);
    cuts.windows(2)
        .filter(|w| w[1] - w[0] > 1e-15)
        .map(|w| backlash_at(&m, 0.5 * (w[0] + w[1])))
        .fold(f64::INFINITY, f64::min)
}

/// The same by a plain scan of `n` mesh phases over one base pitch (a check).
pub fn worst_backlash_scan_m(g1: &Teeth, g2: &Teeth, centre_m: f64, n: usize) -> f64 {
    let m = mesh(g1, g2, centre_m);
    (0..n)
        .map(|i| backlash_at(&m, (i as f64 + 0.5) / n as f64 * m.p1))
        .fold(f64::INFINITY, f64::min)
}

/// Pitch-averaged closed form j_n = p̄_b − s_b1 − s_b2 + 2(r_b1 + r_b2) inv α_w.
pub fn pitch_averaged_backlash_m(g1: &Teeth, g2: &Teeth, centre_m: f64) -> f64 {
    let m = mesh(g1, g2, centre_m);
    0.5 * (m.p1 + m.p2) - g1.base_thickness_m - g2.base_thickness_m
        + 2.0 * (g1.base_radius_m + g2.base_radius_m) * inv(m.alpha_w)
}

/// The gear pair and the physics switches that act on it.
#[derive(Clone, Debug)]
pub struct Pair {
    pub pinion: GearSpec,
    pub wheel: GearSpec,
    pub material: Material,
    /// Radial interference of each bore on its shaft (m), `None` = free bore.
    pub fit: [Option<f64>; 2],
    /// Centre distance a' = a (1 + α_h ΔT_node) when `Some(α_h)`, else fixed.
    pub housing_alpha_per_k: Option<f64>,
}

impl Default for Pair {
    fn default() -> Self {
        Pair {
            pinion: GearSpec::pinion(),
            wheel: GearSpec::wheel(),
            material: Material::steel_17_4ph(),
            fit: [None, None],
            housing_alpha_per_k: None,
        }
    }
}

/// Temperatures (changes from T_ref, K) the pair's backlash depends on.
pub struct PairTemps<'a> {
    /// Node radii (m) and ΔT of each gear body, bore first, rim (base circle) last.
    pub radii_m: [&'a [f64]; 2],
    pub dt_k: [&'a [f64]; 2],
    /// ΔT of the shaft each bore sits on.
    pub shaft_dt_k: [f64; 2],
    /// ΔT of the node that sets the centre distance (housing).
    pub housing_dt_k: f64,
}

impl Pair {
    /// Tooth rings of both gears.
    pub fn teeth(&self, t: &PairTemps) -> [Teeth; 2] {
        let specs = [self.pinion, self.wheel];
        std::array::from_fn(|g| {
            let fit = self.fit[g].map(|d| BoreFit {
                interference_m: d,
                shaft_dt_k: t.shaft_dt_k[g],
            });
            let u = rim_displacement_m(t.radii_m[g], t.dt_k[g], &self.material, fit);
            let rb = *t.radii_m[g].last().unwrap();
            let rim_dt = *t.dt_k[g].last().unwrap();
            specs[g].teeth_at(u / rb, coating_thickness_m(rim_dt, &self.material))
        })
    }

    pub fn centre_distance_m(&self, t: &PairTemps) -> f64 {
        match self.housing_alpha_per_k {
            Some(a) => CENTRE_DISTANCE_M * (1.0 + a * t.housing_dt_k),
            None => CENTRE_DISTANCE_M,
        }
    }

    /// Worst-case normal backlash over a mesh cycle (m).
    pub fn backlash_m(&self, t: &PairTemps) -> f64 {
        let [g1, g2] = self.teeth(t);
        worst_backlash_m(&g1, &g2, self.centre_distance_m(t))
    }
}

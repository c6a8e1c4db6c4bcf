//! The orbit environment, built from the telemetry and a few lines of geometry (no
//! SGP4, no ephemeris in the model itself):
//!
//! - Eclipses: the photo-current's transitions fitted by a strictly periodic pair of
//!   windows (entry = a + kP, exit = b + kP, least squares over every observed entry
//!   and exit). Sunlit/eclipse is a step; no penumbra.
//! - Orbit: circular, its radius from the TLE's mean motion (Kepler's third law); the
//!   orbit angle from noon runs uniformly and is π (midnight) at the middle of each
//!   fitted eclipse.
//! - β: from the fitted eclipse length under a cylindrical shadow,
//!   cos β = √(1 − (R/r)²) / cos(π D / P). [`beta_from_tle_rad`] cross-checks it.
//! - Solar flux: the scenario's 1 AU value over d², d = 1 − 0.01671 cos(2π (doy − 4) /
//!   365.256) at the middle of the recording's day.
//! - Tumble-averaged face fluxes (a plate's orientation averaged over the sphere):
//!   S/4 direct Sun while sunlit; a quarter of the albedo radiance integrated over the
//!   visible Earth cap (Lambertian Earth, radiance a S cos ζ/π where the ground is lit),
//!   tabulated against the sub-satellite solar zenith ζ (cos ζ = cos β cos θ) by a
//!   midpoint rule over the cap; the Earth's infrared times the cap's solid angle over
//!   4π, (1 − √(1 − (R/r)²))/2.

use super::scenario::Spacecraft;
use super::telemetry::{Telemetry, day_of_year, unix_s};
use std::f64::consts::PI;

pub const SIGMA_W_PER_M2_K4: f64 = 5.670_374_419e-8;
pub const EARTH_RADIUS_M: f64 = 6_378_137.0;
pub const MU_EARTH_M3_PER_S2: f64 = 3.986_004_418e14;

/// Periodic eclipse windows `[entry0 + kP, exit0 + kP]`.
#[derive(Clone, Debug)]
pub struct Eclipses {
    pub period_s: f64,
    pub entry0_s: f64,
    /// The exit of the eclipse that starts at `entry0_s`.
    pub exit0_s: f64,
    /// Observed transition time minus the fitted one, per transition (s).
    pub residuals_s: Vec<f64>,
}

/// Solves the 3 × 3 system `a x = b` by Gaussian elimination with partial pivoting.
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> [f64; 3] {
    for c in 0..3 {
        let p = (c..3)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        let pivot = a[c];
        for r in c + 1..3 {
            let f = a[r][c] / pivot[c];
            for (x, p) in a[r].iter_mut().zip(&pivot).skip(c) {
                *x -= f * p;
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; 3];
    for r in (0..3).rev() {
        let s: f64 = (r + 1..3).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

impl Eclipses {
    /// Least-squares fit of entry = a + kP, exit = b + kP to `transitions` (time, is
    /// an entry), orbits numbered from the first entry with `period_guess_s`.
    pub fn fit(transitions: &[(f64, bool)], period_guess_s: f64) -> Eclipses {
        let first = transitions
            .iter()
            .find(|t| t.1)
            .expect("no eclipse entry in the telemetry")
            .0;
        let rows: Vec<(f64, bool, f64)> = transitions
            .iter()
            .map(|&(t, entry)| {
                let x = (t - first) / period_guess_s;
                let k = if entry { x.round() } else { x.floor() };
                (t, entry, k)
            })
            .collect();
        // normal equations of the unknowns (a, b, P)
        let (mut m, mut v) = ([[0.0; 3]; 3], [0.0; 3]);
        for &(t, entry, k) in &rows {
            let r = [f64::from(u8::from(entry)), f64::from(u8::from(!entry)), k];
            for i in 0..3 {
                for j in 0..3 {
                    m[i][j] += r[i] * r[j];
                }
                v[i] += r[i] * t;
            }
        }
        let [a, b, p] = solve3(m, v);
        let residuals_s = rows
            .iter()
            .map(|&(t, entry, k)| t - if entry { a } else { b } - k * p)
            .collect();
        Eclipses {
            period_s: p,
            entry0_s: a,
            exit0_s: b,
            residuals_s,
        }
    }

    pub fn duration_s(&self) -> f64 {
        self.exit0_s - self.entry0_s
    }

    pub fn sunlit(&self, t: f64) -> bool {
        (t - self.entry0_s).rem_euclid(self.period_s) >= self.duration_s()
    }

    /// Every entry and exit in `[t0, t1]`, in order.
    pub fn boundaries(&self, t0: f64, t1: f64) -> Vec<f64> {
        let k0 = ((t0 - self.exit0_s) / self.period_s).floor() as i64 - 1;
        let k1 = ((t1 - self.entry0_s) / self.period_s).ceil() as i64 + 1;
        (k0..=k1)
            .flat_map(|k| {
                let s = k as f64 * self.period_s;
                [self.entry0_s + s, self.exit0_s + s]
            })
            .filter(|t| (t0..=t1).contains(t))
            .collect()
    }

    /// Orbit angle from noon (rad): π at the middle of every eclipse.
    pub fn angle_from_noon_rad(&self, t: f64) -> f64 {
        let midnight = 0.5 * (self.entry0_s + self.exit0_s);
        PI + 2.0 * PI * (t - midnight) / self.period_s
    }
}

/// The TLE's mean motion (rev/day), line 2 columns 53–63.
pub fn mean_motion_rev_per_day(tle: &[String; 2]) -> f64 {
    tle[1][52..63]
        .trim()
        .parse()
        .expect("the TLE's mean motion")
}

/// The circular orbit radius of a mean motion (Kepler's third law), m.
pub fn orbit_radius_m(rev_per_day: f64) -> f64 {
    let n = rev_per_day * 2.0 * PI / 86_400.0;
    (MU_EARTH_M3_PER_S2 / (n * n)).cbrt()
}

/// Tumble-averaged albedo irradiance of a plate per unit a·S, at sub-satellite solar
/// zenith `zeta` and orbit radius `radius_m`: (1/4π) ∫ max(0, cos ζ_ground) dΩ over
/// the visible cap (midpoint rule, 120 rings × 240 sectors).
pub fn albedo_factor(zeta: f64, radius_m: f64) -> f64 {
    let (r, re) = (radius_m, EARTH_RADIUS_M);
    let gamma_max = (re / r).acos();
    let (ng, nf) = (120, 240);
    let (dg, df) = (gamma_max / ng as f64, 2.0 * PI / nf as f64);
    let sun = [zeta.sin(), 0.0, zeta.cos()];
    let mut sum = 0.0;
    for i in 0..ng {
        let g = (i as f64 + 0.5) * dg;
        let d2 = re * re + r * r - 2.0 * re * r * g.cos();
        let cos_e = (r * g.cos() - re) / d2.sqrt();
        let ring = re * re * g.sin() * dg * df * cos_e / d2;
        for j in 0..nf {
            let f = (j as f64 + 0.5) * df;
            let cos_sun = g.sin() * f.cos() * sun[0] + g.cos() * sun[2];
            if cos_sun > 0.0 {
                sum += cos_sun * ring;
            }
        }
    }
    sum / (4.0 * PI)
}

/// β from a TLE on a date (own cross-check, not used by the model): the orbit normal
/// with the RAAN precessed by J2 from the epoch, against the Sun's direction from the
/// low-precision solar longitude (mean longitude and the equation of centre).
pub fn beta_from_tle_rad(tle: &[String; 2], at_unix_s: f64) -> f64 {
    let f = |line: usize, a: usize, b: usize| -> f64 {
        tle[line][a..b].trim().parse().expect("a TLE field")
    };
    let (epoch_yy, epoch_day) = (f(0, 18, 20), f(0, 20, 32));
    let year = 2000 + epoch_yy as i64;
    let epoch_unix = unix_s(&format!("{year}-01-01T00:00:00Z")) + (epoch_day - 1.0) * 86_400.0;
    let (incl, raan0, n) = (
        f(1, 8, 16).to_radians(),
        f(1, 17, 25).to_radians(),
        mean_motion_rev_per_day(tle),
    );
    let a = orbit_radius_m(n);
    let n_rad_s = n * 2.0 * PI / 86_400.0;
    let j2 = 1.082_63e-3;
    let raan_rate = -1.5 * n_rad_s * j2 * (EARTH_RADIUS_M / a).powi(2) * incl.cos();
    let raan = raan0 + raan_rate * (at_unix_s - epoch_unix);
    let normal = [
        incl.sin() * raan.sin(),
        -incl.sin() * raan.cos(),
        incl.cos(),
    ];
    let d = at_unix_s / 86_400.0 + 2_440_587.5 - 2_451_545.0;
    let l = (280.460 + 0.985_647_4 * d).to_radians();
    let g = (357.528 + 0.985_600_3 * d).to_radians();
    let lambda = l + (1.915 * g.sin() + 0.020 * (2.0 * g).sin()).to_radians();
    let eps = (23.439 - 4.0e-7 * d).to_radians();
    let sun = [
        lambda.cos(),
        eps.cos() * lambda.sin(),
        eps.sin() * lambda.sin(),
    ];
    (normal[0] * sun[0] + normal[1] * sun[1] + normal[2] * sun[2]).asin()
}

/// The environment every face of the tumbling spacecraft sees.
#[derive(Clone, Debug)]
pub struct Environment {
    pub eclipses: Eclipses,
    /// Solar flux at the day's Sun distance, W/m².
    pub solar_w_per_m2: f64,
    pub albedo: f64,
    pub earth_ir_w_per_m2: f64,
    pub sink_k: f64,
    pub radius_m: f64,
    pub beta_rad: f64,
    /// The Earth cap's solid angle over 4π.
    pub ir_view: f64,
    /// [`albedo_factor`] at ζ = 0°, 1°, … 180°.
    albedo_table: Vec<f64>,
}

impl Environment {
    /// From the scenario's constants and TLE mean motion, and the telemetry's eclipses.
    pub fn new(craft: &Spacecraft, telemetry: &Telemetry) -> Environment {
        let n = mean_motion_rev_per_day(&craft.tle);
        let radius_m = orbit_radius_m(n);
        let eclipses = Eclipses::fit(&telemetry.sun_transitions(), 86_400.0 / n);
        let rho = EARTH_RADIUS_M / radius_m;
        let half = PI * eclipses.duration_s() / eclipses.period_s;
        let beta_rad = ((1.0 - rho * rho).sqrt() / half.cos())
            .clamp(-1.0, 1.0)
            .acos();
        let doy = day_of_year(&craft.start_utc) + 0.5;
        let d_au = 1.0 - 0.01671 * (2.0 * PI * (doy - 4.0) / 365.256).cos();
        Environment {
            eclipses,
            solar_w_per_m2: craft.solar_flux_1au_w_per_m2 / (d_au * d_au),
            albedo: craft.albedo,
            earth_ir_w_per_m2: craft.earth_ir_w_per_m2,
            sink_k: craft.sink_k,
            radius_m,
            beta_rad,
            ir_view: 0.5 * (1.0 - (1.0 - rho * rho).sqrt()),
            albedo_table: (0..=180)
                .map(|deg| albedo_factor(f64::from(deg).to_radians(), radius_m))
                .collect(),
        }
    }

    /// Direct Sun on a tumbling face, W/m² (orientation average S/4).
    pub fn direct_w_per_m2(&self, sunlit: bool) -> f64 {
        if sunlit {
            0.25 * self.solar_w_per_m2
        } else {
            0.0
        }
    }

    /// Albedo on a tumbling face at time `t`, W/m².
    pub fn albedo_w_per_m2(&self, t: f64) -> f64 {
        let theta = self.eclipses.angle_from_noon_rad(t);
        let zeta = (self.beta_rad.cos() * theta.cos()).acos().to_degrees();
        let i = (zeta.floor() as usize).min(179);
        let w = zeta - i as f64;
        let f = self.albedo_table[i] * (1.0 - w) + self.albedo_table[i + 1] * w;
        self.albedo * self.solar_w_per_m2 * f
    }

    /// Earth infrared on a tumbling face, W/m².
    pub fn earth_ir_face_w_per_m2(&self) -> f64 {
        self.earth_ir_w_per_m2 * self.ir_view
    }
}

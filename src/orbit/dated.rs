//! A real orbit on real dates: a TLE propagated by SGP4 ([`super::tle`]), the Sun where
//! it is on each date ([`super::sun`]), the solar flux scaled by the Sun's distance,
//! and the Earth's shadow from geometry: cylindrical, or conical with the penumbra in
//! which the flux ramps from full to none.
//!
//! β, the orbit angle, the eclipses and the period follow from the geometry; nothing is
//! given. The orbit angle θ is measured as in the circular model, from the in-plane
//! direction closest to the Sun (θ = 0 at orbit noon), so the incidence laws of
//! body-fixed faces of a nadir-pointing spacecraft ([`super::Incidence`]) hold as they
//! are. Eclipse edges: on each night half of the orbit (cos θ < 0, found by a scan of
//! an eighth of an orbit) the shadow function falls to one minimum near midnight and
//! rises; the minimum is found by golden section and each edge by bisection to
//! adjacent floating-point times, so grazing eclipses of any length are found.

use std::f64::consts::PI;

use super::faces::{cross, dot, norm, unit};
use super::sun::{AU_M, sun_at};
use super::tle::TleOrbit;
use super::{EnvState, EnvironmentModel, Incidence, LoadKink};

/// Mean radius of the Sun, m (IAU 2015 nominal).
pub const SUN_RADIUS_M: f64 = 6.957e8;

/// The shape of the Earth's shadow (`orbit.shadow`: "cylindrical" or "conical").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shadow {
    /// A cylinder of the Earth's radius behind it: sunlit or not.
    Cylindrical,
    /// The umbra and penumbra cones of the Sun's disc behind the Earth: in the penumbra
    /// the flux is the visible fraction of the disc (uniform brightness).
    Conical,
}

impl Shadow {
    pub fn name(self) -> &'static str {
        match self {
            Shadow::Cylindrical => "cylindrical",
            Shadow::Conical => "conical",
        }
    }
}

/// The environment of a TLE orbit on its dates.
#[derive(Debug, Clone, PartialEq)]
pub struct DatedEnvironment {
    pub orbit: TleOrbit,
    pub shadow: Shadow,
    /// Solar flux at 1 AU, W/m²; the flux at the spacecraft is this / d².
    pub solar_flux_1au_w_per_m2: f64,
    pub earth_radius_m: f64,
    pub albedo: f64,
    pub earth_ir_w_per_m2: f64,
    pub space_sink_k: f64,
    /// How long the run lasts, s.
    pub horizon_s: f64,
    /// Eclipses as given (`[orbit] eclipses_s`, or a telemetry channel through
    /// `[[input]] drives = "sunlit"`): [entry, exit) windows, increasing, in place of
    /// the shadow's geometry (sunlit outside them at the full flux, dark inside).
    pub eclipses_s: Option<GivenEclipses>,
}

/// Eclipse windows [entry, exit), s, increasing.
pub type GivenEclipses = std::sync::Arc<[(f64, f64)]>;

/// The geometry at one instant.
#[derive(Debug, Clone, Copy)]
pub struct Geometry {
    /// Spacecraft position, m (TEME).
    pub r: [f64; 3],
    /// Unit orbit normal (r × v).
    pub normal: [f64; 3],
    /// Unit vector toward the Sun (from the Earth's centre; the parallax of a LEO
    /// orbit, 4e-5 rad, is neglected except in the shadow cones).
    pub sun: [f64; 3],
    pub sun_distance_au: f64,
    pub beta_rad: f64,
    /// Orbit angle from orbit noon, rad in (−π, π].
    pub theta_rad: f64,
    /// Fraction of the Sun's disc visible, 0 … 1.
    pub sun_fraction: f64,
    /// Umbra function: < 0 inside the umbra (or the cylinder).
    pub umbra: f64,
    /// Penumbra function: < 0 inside the penumbra's outer cone (conical shadow only;
    /// equal to `umbra` for the cylinder).
    pub penumbra: f64,
}

/// Area of overlap of two discs of angular radii `a` and `b` whose centres are `c`
/// apart (small angles, flat sky).
fn disc_overlap(a: f64, b: f64, c: f64) -> f64 {
    if c >= a + b {
        return 0.0;
    }
    if c <= (a - b).abs() {
        return PI * a.min(b).powi(2);
    }
    let x = ((c * c + a * a - b * b) / (2.0 * c * a)).clamp(-1.0, 1.0);
    let y = ((c * c + b * b - a * a) / (2.0 * c * b)).clamp(-1.0, 1.0);
    a * a * x.acos() + b * b * y.acos()
        - 0.5
            * ((-c + a + b) * (c + a - b) * (c - a + b) * (c + a + b))
                .max(0.0)
                .sqrt()
}

/// How closely the terminator is found when it only brackets a night half, s.
const TERMINATOR_TOL_S: f64 = 1e-3;

/// Illinois regula falsi on a sign change of `f` in [`lo`, `hi`] until the bracket is
/// `tol_s` wide: the bracket, its `hi` end on the side `f` changes to.
fn narrow(f: &dyn Fn(f64) -> f64, lo: f64, hi: f64, falling: bool, tol_s: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (lo, hi);
    let (mut f_lo, mut f_hi) = (f(lo), f(hi));
    let mut side = 0i8;
    for _ in 0..60 {
        if hi - lo <= tol_s || !(f_lo.is_finite() && f_hi.is_finite()) {
            break;
        }
        let mut c = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        if !(c > lo && c < hi) {
            c = 0.5 * (lo + hi);
        }
        let fc = f(c);
        if (fc >= 0.0) == falling {
            lo = c;
            f_lo = fc;
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        } else {
            hi = c;
            f_hi = fc;
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        }
    }
    (lo, hi)
}

/// The first float in (`lo`, `hi`] on the far side of `f`'s sign change from `lo`
/// (`falling`: `f(lo)` ≥ 0 and `f(hi)` < 0): the Illinois form of regula falsi until
/// the bracket is a microsecond wide, then bisection to adjacent floats (the same
/// float as bisection alone: there is one sign change between adjacent floats).
fn bisect(f: &dyn Fn(f64) -> f64, lo: f64, hi: f64, falling: bool) -> f64 {
    let (mut lo, mut hi) = narrow(f, lo, hi, falling, 1e-6);
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return hi;
        }
        if (f(mid) >= 0.0) == falling {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

/// The minimum of a unimodal `f` on [`a`, `b`] by golden section, to 1e-3 of the
/// interval (a shadow function's minimum need not be exact: the roots on either side
/// are bisected to the float).
/// Returns the time and `f` there.
fn golden_minimum(f: &dyn Fn(f64) -> f64, a: f64, b: f64) -> (f64, f64) {
    let (a, b) = crate::numeric::golden_section(a, b, 1e-3 * (b - a).abs(), &mut |t| f(t));
    let m = 0.5 * (a + b);
    // the ends themselves when lower (a start past the minimum); the first of equals
    let mut best = (a, f(a));
    for x in [m, b] {
        let fx = f(x);
        if best.1.total_cmp(&fx) == std::cmp::Ordering::Greater {
            best = (x, fx);
        }
    }
    best
}

/// The Earth's shadow at position `r` (m, geocentric) with the Sun in direction
/// `sun` at `sun_distance_au`: the umbra function (< 0 inside the umbra, or the
/// cylinder), the penumbra function (< 0 inside the penumbra's outer cone; the umbra
/// function again for the cylinder) and the visible fraction of the Sun's disc.
///
/// Cylindrical: |r⊥| − R behind the Earth (r·s < 0), |r| − R in front, continuous
/// where they meet. Conical: with a and b the apparent radii of the Sun and the Earth
/// and c the angle between their centres seen from the spacecraft, the umbra is
/// c < b − a and the penumbra c < a + b; the visible fraction is one less the
/// overlap of the two discs over the Sun's disc.
pub fn shadow_at(
    r: [f64; 3],
    sun: [f64; 3],
    sun_distance_au: f64,
    shadow: Shadow,
    earth_radius_m: f64,
) -> (f64, f64, f64) {
    let rn = norm(r);
    let rs = dot(r, sun);
    match shadow {
        Shadow::Cylindrical => {
            let g = if rs >= 0.0 {
                rn - earth_radius_m
            } else {
                (rn * rn - rs * rs).max(0.0).sqrt() - earth_radius_m
            };
            (g, g, if g >= 0.0 { 1.0 } else { 0.0 })
        }
        // In front of the Earth (r·s ≥ 0) the Sun is fully visible; the searches use
        // only the sign there.
        Shadow::Conical if rs >= 0.0 => (rn - earth_radius_m, rn - earth_radius_m, 1.0),
        Shadow::Conical => {
            let (a, b, c) = cone_angles(cone_sines(r, rn, sun, sun_distance_au, earth_radius_m));
            (c - (b - a), c - (a + b), visible_fraction(a, b, c))
        }
    }
}

/// The visible fraction of the Sun's disc at `r` with a conical shadow: the third
/// number of [`shadow_at`], bit for bit, without its two arcsines and its arccosine
/// where the Sun is clearly whole. c ≥ a + b is first decided on the cosines (cos c
/// below cos(a + b) by more than 1e-9, an angle of at least 1e-9 rad, far above the
/// rounding of either side, where [`shadow_at`] also finds c ≥ a + b and returns 1);
/// near the penumbra's edge and inside it, from the angles as [`shadow_at`] does.
pub fn conical_sun_fraction(
    r: [f64; 3],
    sun: [f64; 3],
    sun_distance_au: f64,
    earth_radius_m: f64,
) -> f64 {
    let rn = norm(r);
    if dot(r, sun) >= 0.0 {
        return 1.0;
    }
    let sines = cone_sines(r, rn, sun, sun_distance_au, earth_radius_m);
    let (sin_a, sin_b, cos_c) = sines;
    let cos_ab = (1.0 - sin_a * sin_a).sqrt() * (1.0 - sin_b * sin_b).sqrt() - sin_a * sin_b;
    if cos_c < cos_ab - 1e-9 {
        return 1.0;
    }
    let (a, b, c) = cone_angles(sines);
    visible_fraction(a, b, c)
}

/// Behind the Earth, seen from `r` (`rn` its length): the sines of the apparent radii
/// of the Sun and the Earth and the cosine of the angle between their centres.
#[inline]
fn cone_sines(
    r: [f64; 3],
    rn: f64,
    sun: [f64; 3],
    sun_distance_au: f64,
    earth_radius_m: f64,
) -> (f64, f64, f64) {
    let d = sun_distance_au * AU_M;
    let to_sun = [d * sun[0] - r[0], d * sun[1] - r[1], d * sun[2] - r[2]];
    let ds = norm(to_sun);
    let to_earth = [-r[0] / rn, -r[1] / rn, -r[2] / rn];
    (
        SUN_RADIUS_M / ds,
        (earth_radius_m / rn).min(1.0),
        dot(to_sun, to_earth) / ds,
    )
}

/// The angles of [`cone_sines`]: the apparent radii a and b and the angle c, rad.
#[inline]
fn cone_angles((sin_a, sin_b, cos_c): (f64, f64, f64)) -> (f64, f64, f64) {
    (sin_a.asin(), sin_b.asin(), cos_c.clamp(-1.0, 1.0).acos())
}

/// The visible fraction of the Sun's disc, apparent radius `a`, behind the Earth's,
/// apparent radius `b`, their centres `c` apart.
fn visible_fraction(a: f64, b: f64, c: f64) -> f64 {
    let visible = if c >= a + b {
        1.0
    } else {
        1.0 - disc_overlap(a, b, c) / (PI * a * a)
    };
    visible.clamp(0.0, 1.0)
}

/// The umbra and penumbra functions of [`shadow_at`], the same numbers, without the
/// visible fraction (the edge searches need only these).
fn shadow_functions_at(
    r: [f64; 3],
    sun: [f64; 3],
    sun_distance_au: f64,
    shadow: Shadow,
    earth_radius_m: f64,
) -> (f64, f64) {
    let rn = norm(r);
    if shadow == Shadow::Conical && dot(r, sun) < 0.0 {
        let (a, b, c) = cone_angles(cone_sines(r, rn, sun, sun_distance_au, earth_radius_m));
        return (c - (b - a), c - (a + b));
    }
    let (umbra, penumbra, _) = shadow_at(r, sun, sun_distance_au, shadow, earth_radius_m);
    (umbra, penumbra)
}

impl DatedEnvironment {
    /// (R / a)², a the mean orbit radius: the Earth view factor a nadir face's loads
    /// take by default.
    pub fn mean_view_factor(&self) -> f64 {
        let a = (crate::constants::EARTH_MU_M3_PER_S2
            * (self.orbit.period_s() / (2.0 * PI)).powi(2))
        .cbrt();
        (self.earth_radius_m / a).powi(2)
    }

    /// Sets the run's length, checking one SGP4 point a day over it (a decayed or
    /// diverging orbit fails now, with its date). Nothing is tabulated here: each
    /// command tabulates what it uses, lazily (`check` the start, `environment` its
    /// orbits), and a run all of its length before its first step (`Setup::run`).
    pub fn set_horizon_s(&mut self, horizon_s: f64) -> Result<(), String> {
        // a decayed orbit is still found now, from one SGP4 point a day
        self.orbit.check_daily(horizon_s)?;
        self.horizon_s = horizon_s;
        Ok(())
    }

    /// The geometry at `t_s` after the start.
    pub fn geometry(&self, t_s: f64) -> Geometry {
        let mut g = self.orbit_geometry(t_s);
        (g.umbra, g.penumbra, g.sun_fraction) = shadow_at(
            g.r,
            g.sun,
            g.sun_distance_au,
            self.shadow,
            self.earth_radius_m,
        );
        g
    }

    /// [`Self::geometry`] without the shadow (its `umbra`, `penumbra` and
    /// `sun_fraction` NaN): the same numbers for the rest, for the callers that need
    /// only the orbit and the Sun.
    fn orbit_geometry(&self, t_s: f64) -> Geometry {
        let x = self.orbit.sample(t_s);
        let r = [x[0], x[1], x[2]];
        let v = [x[3], x[4], x[5]];
        let s = [x[6], x[7], x[8]];
        let sun_distance_au = x[9];
        let n = unit(cross(r, v));
        let sn = dot(s, n).clamp(-1.0, 1.0);
        let beta = sn.asin();
        // In-plane direction closest to the Sun (any when the Sun is on the normal).
        let sp = [s[0] - sn * n[0], s[1] - sn * n[1], s[2] - sn * n[2]];
        let e1 = if norm(sp) > 1e-12 {
            unit(sp)
        } else {
            unit(cross(n, [0.0, 0.0, 1.0]))
        };
        let e2 = cross(n, e1);
        let theta = dot(r, e2).atan2(dot(r, e1));
        Geometry {
            r,
            normal: n,
            sun: s,
            sun_distance_au,
            beta_rad: beta,
            theta_rad: theta,
            sun_fraction: f64::NAN,
            umbra: f64::NAN,
            penumbra: f64::NAN,
        }
    }

    /// r · ŝ at `t_s` (m): ≥ 0 on the day half of the orbit (cos θ ≥ 0), < 0 on the
    /// night half. Cheaper than [`Self::geometry`] (no orbit normal, β or θ) for the
    /// searches that only need the sign.
    fn sun_side(&self, t_s: f64) -> f64 {
        let x = self.orbit.sample(t_s);
        dot([x[0], x[1], x[2]], [x[6], x[7], x[8]])
    }

    /// The umbra and penumbra functions of [`shadow_at`] at `t_s`: the same numbers as
    /// [`Self::geometry`]'s, without the orbit normal, β and θ.
    fn shadow_functions(&self, t_s: f64) -> (f64, f64) {
        let x = self.orbit.sample(t_s);
        shadow_functions_at(
            [x[0], x[1], x[2]],
            [x[6], x[7], x[8]],
            x[9],
            self.shadow,
            self.earth_radius_m,
        )
    }

    /// The first root of `f` strictly after `t_s` and before `until_s`, with the sign
    /// it changes to (`true`: from ≥ 0 to < 0): a scan in steps of `step_s`, refined
    /// by bisection to adjacent floats, or only to within `tol_s` when given (the
    /// time returned is then on the far side of the root, at most `tol_s` past it).
    /// `f` must not change sign twice within a step.
    fn next_root(
        &self,
        t_s: f64,
        until_s: f64,
        step_s: f64,
        tol_s: Option<f64>,
        f: &dyn Fn(f64) -> f64,
    ) -> Option<(f64, bool)> {
        let mut a = t_s;
        let mut fa = f(a);
        while a < until_s {
            let b = (a + step_s).min(until_s);
            let fb = f(b);
            if (fa >= 0.0) != (fb >= 0.0) {
                let falling = fa >= 0.0;
                let hi = match tol_s {
                    None => bisect(f, a, b, falling),
                    Some(tol) => narrow(f, a, b, falling, tol).1,
                };
                // a root at `t_s` itself is not "after" it
                if hi > t_s {
                    return Some((hi, falling));
                }
            }
            a = b;
            fa = fb;
        }
        None
    }

    /// The next time after `t_s` (before `until_s`) at which cos θ changes sign with
    /// the given direction (`falling`: entering the night half, θ = 90°), within
    /// [`TERMINATOR_TOL_S`] past it; θ advances monotonically, so a scan of an eighth
    /// of an orbit cannot step over two roots. It only brackets a night half for the
    /// shadow searches (the spacecraft is lit on either side of the terminator; their
    /// roots are bisected to the float), so it need not be exact.
    fn next_terminator(&self, t_s: f64, until_s: f64, falling: bool) -> Option<f64> {
        let step = self.mean_period_s() / 8.0;
        let mut t = t_s;
        while let Some((tc, f)) = self.next_root(t, until_s, step, Some(TERMINATOR_TOL_S), &|t| {
            self.sun_side(t)
        }) {
            if f == falling {
                return Some(tc);
            }
            t = tc;
        }
        None
    }

    /// The first sign change of a shadow function `f` (the umbra's or the penumbra's)
    /// after `t_s`. On the day half (cos θ ≥ 0) the spacecraft is in front of the Earth
    /// and lit; on each night half `f` falls to one minimum near midnight and rises
    /// again, so the minimum is found by golden section and each side's root by
    /// bisection: a grazing eclipse of any length is found.
    fn next_shadow_edge(
        &self,
        t_s: f64,
        until_s: f64,
        f: &dyn Fn(f64) -> f64,
    ) -> Option<(f64, bool)> {
        let mut t = t_s;
        while t < until_s {
            if self.sun_side(t) >= 0.0 {
                t = self.next_terminator(t, until_s, true)?;
            }
            let night_end = self.next_terminator(t, until_s, false).unwrap_or(until_s);
            let f_t = f(t);
            let (t_min, f_min) = golden_minimum(f, t, night_end);
            if f_t >= 0.0 {
                if f_min < 0.0 {
                    let hi = bisect(f, t, t_min, true);
                    if hi > t_s {
                        return Some((hi, true));
                    }
                }
            } else if f(night_end) >= 0.0 {
                let lo = if t_min > t { t_min } else { t };
                let hi = bisect(f, lo, night_end, false);
                if hi > t_s {
                    return Some((hi, false));
                }
            }
            if night_end >= until_s {
                return None;
            }
            t = night_end;
        }
        None
    }

    /// The orbit and its environment as `orbitlash check` reports them.
    pub fn report(&self) -> Vec<String> {
        let o = &self.orbit;
        let g = self.geometry(0.0);
        let a_m =
            (crate::constants::EARTH_MU_M3_PER_S2 * (o.period_s() / (2.0 * PI)).powi(2)).cbrt();
        let perigee = a_m * (1.0 - o.eccentricity) - self.earth_radius_m;
        let apogee = a_m * (1.0 + o.eccentricity) - self.earth_radius_m;
        let age = o.epoch_age_days();
        vec![
            format!(
                "  TLE orbit (SGP4)        epoch {}, {:.2} days {} the start",
                o.epoch_utc.format("%Y-%m-%dT%H:%M:%SZ"),
                age.abs(),
                if age >= 0.0 { "before" } else { "after" }
            ),
            format!(
                "  start                   {}",
                o.start_utc.format("%Y-%m-%dT%H:%M:%SZ")
            ),
            format!(
                "  period                  {:.3} s ({:.2} min)",
                o.period_s(),
                o.period_s() / 60.0
            ),
            format!(
                "  inclination             {:.3}°, eccentricity {:.5}",
                o.inclination_deg, o.eccentricity
            ),
            format!(
                "  altitude                {:.1} … {:.1} km (perigee … apogee, mean elements)",
                perigee / 1e3,
                apogee / 1e3
            ),
            format!("  β at the start          {:.2}°", g.beta_rad.to_degrees()),
            format!(
                "  eclipse fraction        {:.4} (the first orbit; {})",
                self.eclipse_fraction_at(0.0),
                match self.eclipses_s {
                    // given eclipses (the file's, or an `[[input]]` eclipse flag's) replace the
                    // shadow's geometry
                    Some(_) => "the eclipses given, `orbit.eclipses_s`".to_string(),
                    None => format!("{} shadow", self.shadow.name()),
                }
            ),
            format!(
                "  Sun distance            {:.5} AU, solar flux {:.1} W/m² ({:.1} at 1 AU)",
                g.sun_distance_au,
                self.solar_flux_1au_w_per_m2 / g.sun_distance_au.powi(2),
                self.solar_flux_1au_w_per_m2
            ),
        ]
    }
}

impl DatedEnvironment {
    /// With given eclipses: whether `t_s` is inside one.
    fn in_given_eclipse(w: &[(f64, f64)], t_s: f64) -> bool {
        let k = w.partition_point(|&(a, _)| a <= t_s);
        k > 0 && t_s < w[k - 1].1
    }

    /// With given eclipses: the next entry or exit after `t_s`, before `until_s`.
    fn next_given_edge(w: &[(f64, f64)], t_s: f64, until_s: f64) -> Option<(f64, bool)> {
        w.iter()
            .flat_map(|&(a, b)| [(a, true), (b, false)])
            .find(|&(t, _)| t > t_s)
            .filter(|&(t, _)| t < until_s)
    }
}

impl EnvironmentModel for DatedEnvironment {
    fn state_with(&self, t_s: f64, sunlit: bool) -> EnvState {
        let g = self.orbit_geometry(t_s);
        let flux = self.solar_flux_1au_w_per_m2 / g.sun_distance_au.powi(2);
        // A step flagged sunlit sees the Sun from the lit side up to and at its end,
        // which lands on the edge: only the penumbra dims it (falling continuously to 0
        // at the umbra); the cylinder's first shadowed float would be a jump inside the
        // step, and given eclipses have no penumbra.
        let dimmed = sunlit && self.shadow == Shadow::Conical && self.eclipses_s.is_none();
        EnvState {
            t_s,
            orbit_angle_rad: g.theta_rad,
            beta_rad: g.beta_rad,
            solar_flux_w_per_m2: if dimmed {
                flux * conical_sun_fraction(g.r, g.sun, g.sun_distance_au, self.earth_radius_m)
            } else {
                flux
            },
            sunlit,
            radius_m: norm(g.r),
        }
    }

    fn sunlit(&self, t_s: f64) -> bool {
        if let Some(w) = &self.eclipses_s {
            return !Self::in_given_eclipse(w, t_s);
        }
        self.geometry(t_s).umbra >= 0.0
    }

    fn next_shadow_crossing(&self, t_s: f64, until_s: f64) -> Option<(f64, bool)> {
        if let Some(w) = &self.eclipses_s {
            return Self::next_given_edge(w, t_s, until_s);
        }
        self.next_shadow_edge(t_s, until_s, &|t| self.shadow_functions(t).0)
    }

    /// The terminator (θ = ±90°), noon and midnight (θ = 0°, 180°) and, with a
    /// conical shadow, the penumbra's outer edges (where the flux starts to ramp).
    fn next_load_kink(&self, t_s: f64, kinks: &[LoadKink]) -> f64 {
        let until = t_s + 1.01 * self.mean_period_s();
        // θ advances monotonically: an eighth of an orbit holds at most one root of
        // cos θ or sin θ
        let step = self.mean_period_s() / 8.0;
        let mut next = f64::INFINITY;
        for k in kinks {
            let f: Box<dyn Fn(f64) -> f64> = match k {
                LoadKink::Terminator => Box::new(|t| self.orbit_geometry(t).theta_rad.cos()),
                LoadKink::NoonMidnight => Box::new(|t| self.orbit_geometry(t).theta_rad.sin()),
            };
            if let Some((t, _)) = self.next_root(t_s, until, step, None, &*f) {
                next = next.min(t);
            }
        }
        if self.shadow == Shadow::Conical
            && self.eclipses_s.is_none()
            && let Some((t, _)) = self.next_shadow_edge(t_s, until, &|t| self.shadow_functions(t).1)
        {
            next = next.min(t);
        }
        next
    }
    /// Orbit k covers [(k − 1) T, k T) with T the mean period.
    fn orbit_number(&self, t_s: f64) -> u64 {
        (t_s / self.mean_period_s()).floor().max(0.0) as u64 + 1
    }

    fn orbit_phase_deg(&self, t_s: f64) -> f64 {
        self.orbit_geometry(t_s)
            .theta_rad
            .to_degrees()
            .rem_euclid(360.0)
    }

    fn mean_period_s(&self) -> f64 {
        self.orbit.period_s()
    }

    fn sun_w(&self, s: &EnvState, absorptivity_area_m2: f64, incidence: Incidence) -> f64 {
        super::direct_sun_w(s, absorptivity_area_m2, incidence)
    }

    /// As the circular model: α·A · S · a · F · max(0, cos θ cos β), with S the flux on
    /// the date (the same for the Earth as for the spacecraft).
    fn albedo_w(&self, s: &EnvState, absorptivity_area_m2: f64, view_factor: f64) -> f64 {
        let flux = if s.sunlit {
            // the penumbra dims the Sun seen by the spacecraft, not the Earth below it
            let g = self.orbit_geometry(s.t_s);
            self.solar_flux_1au_w_per_m2 / g.sun_distance_au.powi(2)
        } else {
            s.solar_flux_w_per_m2
        };
        absorptivity_area_m2
            * flux
            * self.albedo
            * view_factor
            * (s.orbit_angle_rad.cos() * s.beta_rad.cos()).max(0.0)
    }

    fn earth_ir_w(&self, emissivity_area_m2: f64, view_factor: f64) -> f64 {
        emissivity_area_m2 * self.earth_ir_w_per_m2 * view_factor
    }

    fn breakpoints_s(&self) -> Vec<f64> {
        Vec::new()
    }

    /// The fraction of the orbit starting at the orbit around `t_s` spent in the umbra
    /// (the cylinder), from its crossings.
    fn eclipse_fraction_at(&self, t_s: f64) -> f64 {
        let period = self.mean_period_s();
        let t0 = (t_s / period).floor() * period;
        let t1 = t0 + period;
        let mut t = t0;
        let mut lit = self.sunlit(t0);
        let mut dark = 0.0;
        while let Some((tc, entering)) = self.next_shadow_crossing(t, t1) {
            if !lit {
                dark += tc - t;
            }
            lit = !entering;
            t = tc;
        }
        if !lit {
            dark += t1 - t;
        }
        dark / period
    }

    /// β over the run, sampled every six hours (and at its end) from SGP4 directly.
    fn beta_range_rad(&self, t0_s: f64, t1_s: f64) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        let span = (t1_s - t0_s).max(0.0);
        let n = (span / 21_600.0).ceil().max(1.0) as usize;
        for k in 0..=n {
            let t = t0_s + (k as f64 * 21_600.0).min(span);
            let Ok(s6) = self.orbit.propagate(t) else {
                continue;
            };
            let normal = unit(cross([s6[0], s6[1], s6[2]], [s6[3], s6[4], s6[5]]));
            let sun = sun_at(self.orbit.start_jd + t / 86_400.0).direction;
            let b = dot(sun, normal).clamp(-1.0, 1.0).asin();
            lo = lo.min(b);
            hi = hi.max(b);
        }
        (lo, hi)
    }

    fn report(&self) -> Vec<String> {
        DatedEnvironment::report(self)
    }

    fn face_environment(&self, s: &EnvState) -> super::faces::FaceEnvironment {
        let g = self.orbit_geometry(s.t_s);
        let flux = self.solar_flux_1au_w_per_m2 / g.sun_distance_au.powi(2);
        super::faces::FaceEnvironment {
            sun_lvlh: super::faces::sun_lvlh(s.orbit_angle_rad, s.beta_rad),
            solar_w_per_m2: if s.sunlit { s.solar_flux_w_per_m2 } else { 0.0 },
            solar_on_earth_w_per_m2: flux,
            radius_m: s.radius_m,
            earth_radius_m: self.earth_radius_m,
            albedo: self.albedo,
            earth_ir_w_per_m2: self.earth_ir_w_per_m2,
            lvlh_axes: super::faces::lvlh_axes(g.r, g.normal),
            t_s: s.t_s,
        }
    }

    fn sun_fraction(&self, t_s: f64) -> f64 {
        if self.eclipses_s.is_some() {
            return if self.sunlit(t_s) { 1.0 } else { 0.0 };
        }
        let g = self.geometry(t_s);
        if g.umbra < 0.0 { 0.0 } else { g.sun_fraction }
    }
}

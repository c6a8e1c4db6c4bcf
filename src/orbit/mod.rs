//! Circular-orbit geometry, the cylindrical Earth shadow, and the environment a
//! spacecraft face sees (Sun, albedo, Earth infrared) along a mission profile.
//!
//! Frame: the orbit plane is spanned by `e1`, the in-plane direction closest to the
//! Sun, and `e2`, 90° ahead along the motion; `n` is the orbit normal. The Sun
//! direction is `cos β e1 + sin β n`. The orbit angle θ is measured from `e1`
//! (θ = 0 is orbit noon), so the radial unit vector is `cos θ e1 + sin θ e2`.

pub mod dated;
pub mod faces;
pub mod sun;
pub mod table;
pub mod tle;

use std::f64::consts::PI;

pub use table::Profile;

/// A circular orbit about a spherical Earth.
#[derive(Debug, Clone, PartialEq)]
pub struct Orbit {
    pub altitude_m: f64,
    pub earth_radius_m: f64,
    pub mu_m3_per_s2: f64,
    /// Orbit angle at t = 0, rad (0 = orbit noon).
    pub orbit_angle_at_start_rad: f64,
}

impl Orbit {
    /// Orbit radius R + h, m.
    pub fn radius_m(&self) -> f64 {
        self.earth_radius_m + self.altitude_m
    }

    /// Period T = 2π √((R+h)³/μ), s.
    pub fn period_s(&self) -> f64 {
        2.0 * PI * (self.radius_m().powi(3) / self.mu_m3_per_s2).sqrt()
    }

    /// Orbit angle θ(t), rad, unwrapped.
    pub fn orbit_angle_rad(&self, t_s: f64) -> f64 {
        self.orbit_angle_at_start_rad + 2.0 * PI * t_s / self.period_s()
    }

    /// Orbit number (1-based) at time `t_s`: orbit k covers [(k−1)T, kT).
    pub fn orbit_number(&self, t_s: f64) -> u64 {
        (t_s / self.period_s()).floor().max(0.0) as u64 + 1
    }

    /// Earth view factor of a nadir face, (R/(R+h))².
    pub fn earth_view_factor(&self) -> f64 {
        (self.earth_radius_m / self.radius_m()).powi(2)
    }

    /// √(1 − (R/(R+h))²): the spacecraft is eclipsed when cos θ cos β < −this.
    pub fn shadow_threshold(&self) -> f64 {
        (1.0 - self.earth_view_factor()).sqrt()
    }

    /// Largest |β| at which eclipses occur, rad: arcsin(R/(R+h)).
    pub fn critical_beta_rad(&self) -> f64 {
        (self.earth_radius_m / self.radius_m()).asin()
    }

    /// The first time strictly after `t_s` at which θ ≡ `angle_rad` (mod π).
    pub fn next_angle_mod_pi_s(&self, t_s: f64, angle_rad: f64) -> f64 {
        let omega = 2.0 * PI / self.period_s();
        let theta = self.orbit_angle_rad(t_s);
        let k = ((theta - angle_rad) / PI).floor() + 1.0;
        let mut t = t_s + (angle_rad + k * PI - theta) / omega;
        if t <= t_s + 1e-9 * (1.0 + t_s.abs()) {
            t += PI / omega;
        }
        t
    }

    /// Eclipse half-angle φ about orbit midnight, rad:
    /// cos φ = √((R+h)² − R²) / ((R+h) cos β); 0 when there is no eclipse.
    pub fn eclipse_half_angle_rad(&self, beta_rad: f64) -> f64 {
        let c = self.shadow_threshold() / beta_rad.cos();
        if c >= 1.0 { 0.0 } else { c.acos() }
    }

    /// Fraction of the orbit in eclipse, φ/π.
    pub fn eclipse_fraction(&self, beta_rad: f64) -> f64 {
        self.eclipse_half_angle_rad(beta_rad) / PI
    }

    /// Shadow function g = cos θ cos β + √(1 − (R/(R+h))²); eclipsed iff g < 0
    /// (cylindrical shadow, no penumbra).
    pub fn shadow_function(&self, theta_rad: f64, beta_rad: f64) -> f64 {
        theta_rad.cos() * beta_rad.cos() + self.shadow_threshold()
    }
}

/// A face orientation for the Sun load's incidence law (`sun.incidence`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Incidence {
    /// The face tracks the Sun: factor 1 whenever sunlit.
    Tracking,
    /// Body-fixed faces of a nadir-pointing spacecraft (LVLH frame).
    Zenith,
    Nadir,
    Ram,
    Wake,
    /// +orbit normal (towards the Sun's side for β > 0) and −orbit normal.
    NormalPlus,
    NormalMinus,
}

impl Incidence {
    /// cos of the Sun incidence angle on the face, clamped at 0 (face in its own shadow).
    /// Not inlined: the optimiser would otherwise compute the trigonometry of every
    /// face kind before the match, even for a Sun-tracking face.
    #[inline(never)]
    pub fn factor(self, theta_rad: f64, beta_rad: f64) -> f64 {
        let c = match self {
            Incidence::Tracking => 1.0,
            Incidence::Zenith => theta_rad.cos() * beta_rad.cos(),
            Incidence::Nadir => -theta_rad.cos() * beta_rad.cos(),
            Incidence::Ram => -theta_rad.sin() * beta_rad.cos(),
            Incidence::Wake => theta_rad.sin() * beta_rad.cos(),
            Incidence::NormalPlus => beta_rad.sin(),
            Incidence::NormalMinus => -beta_rad.sin(),
        };
        c.max(0.0)
    }
}

/// The circular-orbit environment over mission time: the orbit plus the mission
/// profile of β and solar flux, Earth albedo and infrared, and the deep-space sink.
#[derive(Debug, Clone, PartialEq)]
pub struct CircularEnvironment {
    pub orbit: Orbit,
    /// β(t), rad.
    pub beta_rad: Profile,
    /// S(t), W/m².
    pub solar_flux_w_per_m2: Profile,
    /// Albedo coefficient a.
    pub albedo: f64,
    /// Earth infrared flux at the top of the atmosphere, W/m².
    pub earth_ir_w_per_m2: f64,
    pub space_sink_k: f64,
}

/// The environment at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvState {
    pub t_s: f64,
    pub orbit_angle_rad: f64,
    pub beta_rad: f64,
    pub solar_flux_w_per_m2: f64,
    pub sunlit: bool,
    /// Distance from the Earth's centre, m.
    pub radius_m: f64,
}

/// Heat absorbed from direct Sun, W, by α·A `absorptivity_area_m2` facing as
/// `incidence` says, at the instant `s` (the same law for every kind of orbit: the
/// orbit angle from noon and β place the Sun).
#[inline]
pub(crate) fn direct_sun_w(s: &EnvState, absorptivity_area_m2: f64, incidence: Incidence) -> f64 {
    if !s.sunlit {
        return 0.0;
    }
    let factor = match incidence {
        Incidence::Tracking => 1.0,
        _ => incidence.factor(s.orbit_angle_rad, s.beta_rad),
    };
    absorptivity_area_m2 * s.solar_flux_w_per_m2 * factor
}

/// Where a load's slope jumps as the spacecraft goes round: the solver lands its steps
/// there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadKink {
    /// The terminator (orbit angle θ = 90° or 270°): where albedo, and Sun on zenith or
    /// nadir faces, start or stop.
    Terminator,
    /// Orbit noon and midnight (θ = 0° or 180°): where Sun on ram or wake faces starts
    /// or stops.
    NoonMidnight,
}

/// What the thermal model needs from where the spacecraft is, at any time: the sunlit
/// state, the Sun and Earth geometry of the loads, the next shadow crossing and load
/// kink, the orbit count and phase. The stepping loop, the summaries and the logs use
/// only this; the circular orbit ([`CircularEnvironment`]) is one implementation, real
/// orbits (TLE/SGP4) will be another variant of [`Environment`], so nothing outside `orbit/` may assume a uniform orbit
/// rate or a constant period.
pub trait EnvironmentModel {
    /// The environment at `t_s` with the sunlit flag decided by the caller (the solver
    /// decides it for a whole step, between shadow crossings it lands on).
    fn state_with(&self, t_s: f64, sunlit: bool) -> EnvState;
    /// Whether the spacecraft is in sunlight at `t_s`.
    fn sunlit(&self, t_s: f64) -> bool;
    /// The first eclipse entry or exit strictly after `t_s` and before `until_s`:
    /// `(time, entering_eclipse)`.
    fn next_shadow_crossing(&self, t_s: f64, until_s: f64) -> Option<(f64, bool)>;
    /// The first time strictly after `t_s` at which a load of one of `kinks` changes
    /// its slope (∞ when none).
    fn next_load_kink(&self, t_s: f64, kinks: &[LoadKink]) -> f64;
    /// Orbit number (1-based) at `t_s`.
    fn orbit_number(&self, t_s: f64) -> u64;
    /// Orbit angle from orbit noon at `t_s`, degrees in [0, 360).
    fn orbit_phase_deg(&self, t_s: f64) -> f64;
    /// Mean orbital period, s: the length of "an orbit" in reports and `--orbits`.
    fn mean_period_s(&self) -> f64;
    /// Heat absorbed from direct Sun, W, by an area `absorptivity_area_m2` (α·A).
    fn sun_w(&self, s: &EnvState, absorptivity_area_m2: f64, incidence: Incidence) -> f64;
    /// Earth albedo on a nadir face, W.
    fn albedo_w(&self, s: &EnvState, absorptivity_area_m2: f64, view_factor: f64) -> f64;
    /// Earth infrared on a nadir face, W.
    fn earth_ir_w(&self, emissivity_area_m2: f64, view_factor: f64) -> f64;
    /// Times at which the environment's own tables change their slope (the solver lands
    /// steps on them), sorted or not.
    fn breakpoints_s(&self) -> Vec<f64>;
    /// Fraction of the orbit in eclipse for the orbit around `t_s`.
    fn eclipse_fraction_at(&self, t_s: f64) -> f64;
    /// Smallest and largest β from `t0_s` to `t1_s` (a run's span), rad.
    fn beta_range_rad(&self, t0_s: f64, t1_s: f64) -> (f64, f64);
    /// The orbit and its eclipses as `orbitlash check` reports them, one line each.
    fn report(&self) -> Vec<String>;
    /// What body-fixed faces see at the instant `s` (see [`faces`]).
    fn face_environment(&self, s: &EnvState) -> faces::FaceEnvironment;
    /// The fraction of the Sun's disc the spacecraft sees at `t_s`: 1 sunlit, 0 in
    /// the umbra, between in a penumbra.
    fn sun_fraction(&self, t_s: f64) -> f64 {
        if self.sunlit(t_s) { 1.0 } else { 0.0 }
    }
}

/// The environment of a model: one of the implementations of [`EnvironmentModel`].
/// Code that needs what only one kind has (the circular orbit's altitude, its β
/// table) asks for it by name ([`Environment::circular`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Environment {
    /// A circular orbit about a spherical Earth with β and solar flux along a mission
    /// profile.
    Circular(CircularEnvironment),
    /// A TLE orbit on its dates: the Sun where it is, β and eclipses from geometry.
    Dated(dated::DatedEnvironment),
}

impl Environment {
    /// The circular-orbit environment, if the model has one.
    pub fn circular(&self) -> Option<&CircularEnvironment> {
        match self {
            Environment::Circular(c) => Some(c),
            Environment::Dated(_) => None,
        }
    }

    pub fn circular_mut(&mut self) -> Option<&mut CircularEnvironment> {
        match self {
            Environment::Circular(c) => Some(c),
            Environment::Dated(_) => None,
        }
    }

    /// When t = 0 is, for an environment on real dates.
    pub fn start_utc(&self) -> Option<sgp4::chrono::NaiveDateTime> {
        match self {
            Environment::Circular(_) => None,
            Environment::Dated(d) => Some(d.orbit.start_utc),
        }
    }

    /// t = 0 as ns since the Unix epoch for an environment on real dates (the log time
    /// of t = 0 in the MCAP files), 0 otherwise.
    pub fn start_unix_ns(&self) -> u64 {
        self.start_utc()
            .and_then(|u| u.and_utc().timestamp_nanos_opt())
            .map_or(0, |n| n.max(0) as u64)
    }

    /// The UTC date and time `t_s` seconds after t = 0, for an environment on real
    /// dates (None otherwise, or past the representable dates).
    pub fn utc_at(&self, t_s: f64) -> Option<sgp4::chrono::NaiveDateTime> {
        let ms = (t_s * 1e3).round();
        self.start_utc().and_then(|u| {
            (ms.abs() < 1e15).then(|| u + sgp4::chrono::Duration::milliseconds(ms as i64))
        })
    }

    /// The Earth's albedo coefficient, its infrared flux (W/m²) and the deep-space sink
    /// (K), whatever the orbit.
    pub fn earth_and_space_mut(&mut self) -> (&mut f64, &mut f64, &mut f64) {
        match self {
            Environment::Circular(c) => {
                (&mut c.albedo, &mut c.earth_ir_w_per_m2, &mut c.space_sink_k)
            }
            Environment::Dated(d) => (&mut d.albedo, &mut d.earth_ir_w_per_m2, &mut d.space_sink_k),
        }
    }
}

impl From<dated::DatedEnvironment> for Environment {
    fn from(d: dated::DatedEnvironment) -> Environment {
        Environment::Dated(d)
    }
}

impl From<CircularEnvironment> for Environment {
    fn from(c: CircularEnvironment) -> Environment {
        Environment::Circular(c)
    }
}

/// Each call goes to the kind of environment the model has.
macro_rules! each_kind {
    ($self:ident, $e:ident => $call:expr) => {
        match $self {
            Environment::Circular($e) => $call,
            Environment::Dated($e) => $call,
        }
    };
}

impl EnvironmentModel for Environment {
    fn state_with(&self, t_s: f64, sunlit: bool) -> EnvState {
        each_kind!(self, e => e.state_with(t_s, sunlit))
    }
    fn sunlit(&self, t_s: f64) -> bool {
        each_kind!(self, e => e.sunlit(t_s))
    }
    fn next_shadow_crossing(&self, t_s: f64, until_s: f64) -> Option<(f64, bool)> {
        each_kind!(self, e => e.next_shadow_crossing(t_s, until_s))
    }
    fn next_load_kink(&self, t_s: f64, kinks: &[LoadKink]) -> f64 {
        each_kind!(self, e => e.next_load_kink(t_s, kinks))
    }
    fn orbit_number(&self, t_s: f64) -> u64 {
        each_kind!(self, e => e.orbit_number(t_s))
    }
    fn orbit_phase_deg(&self, t_s: f64) -> f64 {
        each_kind!(self, e => e.orbit_phase_deg(t_s))
    }
    fn mean_period_s(&self) -> f64 {
        each_kind!(self, e => e.mean_period_s())
    }
    fn sun_w(&self, s: &EnvState, absorptivity_area_m2: f64, incidence: Incidence) -> f64 {
        each_kind!(self, e => e.sun_w(s, absorptivity_area_m2, incidence))
    }
    fn albedo_w(&self, s: &EnvState, absorptivity_area_m2: f64, view_factor: f64) -> f64 {
        each_kind!(self, e => e.albedo_w(s, absorptivity_area_m2, view_factor))
    }
    fn earth_ir_w(&self, emissivity_area_m2: f64, view_factor: f64) -> f64 {
        each_kind!(self, e => e.earth_ir_w(emissivity_area_m2, view_factor))
    }
    fn breakpoints_s(&self) -> Vec<f64> {
        each_kind!(self, e => EnvironmentModel::breakpoints_s(e))
    }
    fn eclipse_fraction_at(&self, t_s: f64) -> f64 {
        each_kind!(self, e => EnvironmentModel::eclipse_fraction_at(e, t_s))
    }
    fn beta_range_rad(&self, t0_s: f64, t1_s: f64) -> (f64, f64) {
        each_kind!(self, e => EnvironmentModel::beta_range_rad(e, t0_s, t1_s))
    }
    fn report(&self) -> Vec<String> {
        each_kind!(self, e => EnvironmentModel::report(e))
    }
    fn sun_fraction(&self, t_s: f64) -> f64 {
        each_kind!(self, e => EnvironmentModel::sun_fraction(e, t_s))
    }
    fn face_environment(&self, s: &EnvState) -> faces::FaceEnvironment {
        each_kind!(self, e => EnvironmentModel::face_environment(e, s))
    }
}

impl CircularEnvironment {
    fn shadow(&self, t_s: f64) -> f64 {
        self.orbit
            .shadow_function(self.orbit.orbit_angle_rad(t_s), self.beta_rad.at(t_s))
    }

    /// The orbit and its eclipses as `orbitlash check` reports them.
    pub fn report(&self) -> Vec<String> {
        let orbit = &self.orbit;
        let period = orbit.period_s();
        let mut o = vec![
            format!("  altitude                {:.1} km", orbit.altitude_m / 1e3),
            format!(
                "  period                  {period:.3} s ({:.2} min)",
                period / 60.0
            ),
            format!("  earth view factor       {:.6}", orbit.earth_view_factor()),
            format!(
                "  eclipses stop at |beta| {:.3}°",
                orbit.critical_beta_rad().to_degrees()
            ),
        ];
        let (b_lo, b_hi) = self.beta_rad.range();
        let mut betas = vec![b_lo];
        if b_hi != b_lo {
            betas.push(b_hi);
        }
        for b in betas {
            let f = orbit.eclipse_fraction(b);
            o.push(format!(
                "  beta {:7.3}°: eclipse half-angle {:.3}°, fraction {:.5}, duration {:.1} s",
                b.to_degrees(),
                orbit.eclipse_half_angle_rad(b).to_degrees(),
                f,
                f * period
            ));
        }
        let (s_lo, s_hi) = self.solar_flux_w_per_m2.range();
        o.push(format!("  solar flux              {s_lo} … {s_hi} W/m²"));
        o
    }

    /// The fraction of the orbit in eclipse at `t_s` (the β of that time), for reports.
    pub fn eclipse_fraction_at(&self, t_s: f64) -> f64 {
        self.orbit.eclipse_fraction(self.beta_rad.at(t_s))
    }

    /// The β range from `t0_s` to `t1_s`, rad.
    pub fn beta_range_rad(&self, t0_s: f64, t1_s: f64) -> (f64, f64) {
        self.beta_rad.range_over(t0_s, t1_s)
    }

    /// Closed form for constant β: entry at θ = π − φ, exit at θ = π + φ (mod 2π).
    fn next_shadow_crossing_constant_beta(
        &self,
        beta: f64,
        t_s: f64,
        until_s: f64,
    ) -> Option<(f64, bool)> {
        let phi = self.orbit.eclipse_half_angle_rad(beta);
        if phi == 0.0 {
            return None;
        }
        let period = self.orbit.period_s();
        let omega = 2.0 * PI / period;
        let theta = self.orbit.orbit_angle_rad(t_s);
        let turn = ((theta - (PI - phi)) / (2.0 * PI)).floor();
        let base = turn * 2.0 * PI;
        // Candidates in increasing θ; the first strictly after t (by more than round-off).
        let eps = 1e-9 * (1.0 + t_s.abs());
        for k in 0..3 {
            let b = base + 2.0 * PI * k as f64;
            for (angle, entering) in [(b + PI - phi, true), (b + PI + phi, false)] {
                let t = t_s + (angle - theta) / omega;
                if t > t_s + eps {
                    return (t < until_s).then_some((t, entering));
                }
            }
        }
        None
    }
}

impl CircularEnvironment {
    /// The shadow crossing the slow way (the reference of the predicted search): the
    /// shadow function scanned in 1° steps of orbit angle from just after `t_s`, the
    /// first step that changes sign refined to adjacent floats.
    pub fn next_shadow_crossing_by_scan(&self, t_s: f64, until_s: f64) -> Option<(f64, bool)> {
        let dt = self.orbit.period_s() / 360.0;
        let mut a = t_s + 1e-9 * dt;
        let mut ga = self.shadow(a);
        while a < until_s {
            let b = (a + dt).min(until_s);
            let gb = self.shadow(b);
            if (ga >= 0.0) != (gb >= 0.0) {
                let entering = ga >= 0.0;
                return Some((self.refine_crossing(a, ga, b, gb, entering), entering));
            }
            a = b;
            ga = gb;
        }
        None
    }

    /// The predicted search of [`EnvironmentModel::next_shadow_crossing`] for a
    /// drifting β: `Some(answer)` when its checks hold, `None` to scan instead.
    fn next_shadow_crossing_predicted(
        &self,
        t_s: f64,
        until_s: f64,
    ) -> Option<Option<(f64, bool)>> {
        let dt = self.orbit.period_s() / 360.0;
        let a = t_s + 1e-9 * dt;
        if a >= until_s {
            return Some(None);
        }
        let ga = self.shadow(a);
        let sunlit = ga >= 0.0;
        let (t_pred, entering) =
            self.next_shadow_crossing_constant_beta(self.beta_rad.at(a), a, f64::INFINITY)?;
        if entering != sunlit {
            return None;
        }
        // β moves the crossing by seconds over an orbit: the bracket grows until it
        // holds the crossing, and stays clear of the start by more than its width.
        let mut w = 0.05 * dt;
        for _ in 0..6 {
            let lo = t_pred - w;
            if lo <= a + 2.0 * w {
                return None;
            }
            if lo >= until_s {
                // No crossing before `until_s` when the sign there is still the start's.
                let gu = self.shadow(until_s);
                let mid = self.shadow(0.5 * (a + until_s));
                return ((gu >= 0.0) == sunlit && (mid >= 0.0) == sunlit).then_some(None);
            }
            let g_lo = self.shadow(lo);
            let g_mid = self.shadow(0.5 * (a + lo));
            if (g_lo >= 0.0) != sunlit || (g_mid >= 0.0) != sunlit {
                return None;
            }
            let hi = (t_pred + w).min(until_s);
            let g_hi = self.shadow(hi);
            if (g_hi >= 0.0) != sunlit {
                let t = self.refine_crossing(lo, g_lo, hi, g_hi, entering);
                return Some(Some((t, entering)));
            }
            if hi >= until_s {
                return None;
            }
            w *= 4.0;
        }
        None
    }

    /// The sign change of the shadow function between `lo` (on the side it leaves:
    /// sunlit when `entering`) and `hi`, narrowed to adjacent floats by the Illinois
    /// method (bisection when a secant point falls outside): the later of the two.
    /// With one sign change in the bracket the answer does not depend on the bracket.
    fn refine_crossing(
        &self,
        mut lo: f64,
        mut g_lo: f64,
        mut hi: f64,
        mut g_hi: f64,
        entering: bool,
    ) -> f64 {
        let mut last_side = 0i8;
        for _ in 0..400 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            let x = lo - g_lo * (hi - lo) / (g_hi - g_lo);
            let x = if x > lo && x < hi { x } else { mid };
            let gx = self.shadow(x);
            if (gx >= 0.0) == entering {
                lo = x;
                g_lo = gx;
                if last_side == -1 {
                    g_hi *= 0.5;
                }
                last_side = -1;
            } else {
                hi = x;
                g_hi = gx;
                if last_side == 1 {
                    g_lo *= 0.5;
                }
                last_side = 1;
            }
        }
        hi
    }
}

/// The circular orbit about a spherical Earth, with β and solar flux along a mission
/// profile.
impl EnvironmentModel for CircularEnvironment {
    fn state_with(&self, t_s: f64, sunlit: bool) -> EnvState {
        EnvState {
            t_s,
            orbit_angle_rad: self.orbit.orbit_angle_rad(t_s),
            beta_rad: self.beta_rad.at(t_s),
            solar_flux_w_per_m2: self.solar_flux_w_per_m2.at(t_s),
            sunlit,
            radius_m: self.orbit.radius_m(),
        }
    }

    fn sunlit(&self, t_s: f64) -> bool {
        self.shadow(t_s) >= 0.0
    }

    /// Found by the closed form when β is constant. With β drifting: the closed form
    /// at the current β predicts the crossing, a bracket around the prediction is
    /// checked (no sign change from `t_s` to the bracket, one across it), and the
    /// crossing is refined to adjacent floating-point times. When any check fails, the
    /// shadow function is scanned in 1° steps of orbit angle instead. Both give the
    /// same bits: the refinement ends at the one sign change between adjacent floats.
    fn next_shadow_crossing(&self, t_s: f64, until_s: f64) -> Option<(f64, bool)> {
        if let Profile::Constant(beta) = self.beta_rad {
            return self.next_shadow_crossing_constant_beta(beta, t_s, until_s);
        }
        match self.next_shadow_crossing_predicted(t_s, until_s) {
            Some(found) => found,
            None => self.next_shadow_crossing_by_scan(t_s, until_s),
        }
    }

    fn next_load_kink(&self, t_s: f64, kinks: &[LoadKink]) -> f64 {
        kinks
            .iter()
            .map(|k| {
                let angle = match k {
                    LoadKink::Terminator => std::f64::consts::FRAC_PI_2,
                    LoadKink::NoonMidnight => 0.0,
                };
                self.orbit.next_angle_mod_pi_s(t_s, angle)
            })
            .fold(f64::INFINITY, f64::min)
    }

    fn orbit_number(&self, t_s: f64) -> u64 {
        self.orbit.orbit_number(t_s)
    }

    fn orbit_phase_deg(&self, t_s: f64) -> f64 {
        self.orbit
            .orbit_angle_rad(t_s)
            .to_degrees()
            .rem_euclid(360.0)
    }

    fn mean_period_s(&self) -> f64 {
        self.orbit.period_s()
    }

    fn sun_w(&self, s: &EnvState, absorptivity_area_m2: f64, incidence: Incidence) -> f64 {
        direct_sun_w(s, absorptivity_area_m2, incidence)
    }

    /// α·A · S · a · F · max(0, cos θ cos β). Not inlined, so that its trigonometry is
    /// not hoisted into load loops that have no albedo load.
    #[inline(never)]
    fn albedo_w(&self, s: &EnvState, absorptivity_area_m2: f64, view_factor: f64) -> f64 {
        absorptivity_area_m2
            * s.solar_flux_w_per_m2
            * self.albedo
            * view_factor
            * (s.orbit_angle_rad.cos() * s.beta_rad.cos()).max(0.0)
    }

    /// ε·A · q_IR · F.
    fn earth_ir_w(&self, emissivity_area_m2: f64, view_factor: f64) -> f64 {
        emissivity_area_m2 * self.earth_ir_w_per_m2 * view_factor
    }

    /// The knots of the β and solar-flux tables.
    fn breakpoints_s(&self) -> Vec<f64> {
        self.beta_rad
            .knots_s()
            .iter()
            .chain(self.solar_flux_w_per_m2.knots_s())
            .copied()
            .collect()
    }

    fn eclipse_fraction_at(&self, t_s: f64) -> f64 {
        CircularEnvironment::eclipse_fraction_at(self, t_s)
    }

    fn beta_range_rad(&self, t0_s: f64, t1_s: f64) -> (f64, f64) {
        CircularEnvironment::beta_range_rad(self, t0_s, t1_s)
    }

    fn report(&self) -> Vec<String> {
        CircularEnvironment::report(self)
    }

    fn face_environment(&self, s: &EnvState) -> faces::FaceEnvironment {
        faces::FaceEnvironment {
            sun_lvlh: faces::sun_lvlh(s.orbit_angle_rad, s.beta_rad),
            solar_w_per_m2: if s.sunlit { s.solar_flux_w_per_m2 } else { 0.0 },
            solar_on_earth_w_per_m2: s.solar_flux_w_per_m2,
            radius_m: self.orbit.radius_m(),
            earth_radius_m: self.orbit.earth_radius_m,
            albedo: self.albedo,
            earth_ir_w_per_m2: self.earth_ir_w_per_m2,
            // the orbit frame as the inertial one: x toward orbit noon, z the normal
            lvlh_axes: faces::lvlh_axes(
                [s.orbit_angle_rad.cos(), s.orbit_angle_rad.sin(), 0.0],
                [0.0, 0.0, 1.0],
            ),
            t_s: s.t_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constants::*;
    use crate::orbit::EnvironmentModel;
    use std::f64::consts::FRAC_PI_2;

    fn reference() -> CircularEnvironment {
        CircularEnvironment {
            orbit: Orbit {
                altitude_m: 500e3,
                earth_radius_m: EARTH_RADIUS_M,
                mu_m3_per_s2: EARTH_MU_M3_PER_S2,
                orbit_angle_at_start_rad: 0.0,
            },
            beta_rad: Profile::Constant(20f64.to_radians()),
            solar_flux_w_per_m2: Profile::Constant(1361.0),
            albedo: 0.3,
            earth_ir_w_per_m2: 237.0,
            space_sink_k: 3.0,
        }
    }

    /// The slow reference of the shadow search as it was: 1° scan, then plain
    /// bisection to adjacent floats.
    fn crossing_by_bisection(
        env: &CircularEnvironment,
        t_s: f64,
        until_s: f64,
    ) -> Option<(f64, bool)> {
        let dt = env.orbit.period_s() / 360.0;
        let mut a = t_s + 1e-9 * dt;
        let mut ga = env.shadow(a);
        while a < until_s {
            let b = (a + dt).min(until_s);
            let gb = env.shadow(b);
            if (ga >= 0.0) != (gb >= 0.0) {
                let entering = ga >= 0.0;
                let (mut lo, mut hi) = (a, b);
                loop {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        return Some((hi, entering));
                    }
                    if (env.shadow(mid) >= 0.0) == entering {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
            }
            a = b;
            ga = gb;
        }
        None
    }

    #[test]
    fn val_second_method_drifting_beta_crossings_match_scan_and_bisection_bit_for_bit() {
        // β from 0 to 67.9° (eclipses stop at 68.0°) over 90 days, and back: the
        // predicted search must give the scan-and-bisect answer to the last bit, from
        // any start (including starts on a crossing and short horizons).
        let mut env = reference();
        let day = 86400.0;
        env.beta_rad = Profile::Table {
            time_s: vec![0.0, 90.0 * day, 120.0 * day],
            value: vec![0.0, 67.9f64.to_radians(), -30f64.to_radians()],
        };
        let period = env.orbit.period_s();
        let mut t = 0.0;
        let (mut checked, mut predicted) = (0, 0);
        let mut x = 0.123_f64;
        while t < 120.0 * day {
            for until in [t + period, t + 0.05 * period, t + 3.0 * period] {
                let want = crossing_by_bisection(&env, t, until);
                assert_eq!(
                    env.next_shadow_crossing(t, until),
                    want,
                    "t = {t}, until = {until}"
                );
                assert_eq!(env.next_shadow_crossing_by_scan(t, until), want);
                checked += 1;
                predicted += usize::from(env.next_shadow_crossing_predicted(t, until).is_some());
                if let Some((tc, _)) = want {
                    // starting exactly on the crossing finds the next one
                    let again = crossing_by_bisection(&env, tc, tc + period);
                    assert_eq!(env.next_shadow_crossing(tc, tc + period), again);
                }
            }
            x = (x * 7.13 + 0.37).fract();
            t += (0.3 + x) * 20.0 * period;
        }
        assert!(checked > 300, "{checked}");
        // the fast path answers nearly always (it falls back near β = 67.9°)
        assert!(predicted * 10 > checked * 9, "{predicted} of {checked}");
    }

    #[test]
    fn val_spec_shadow_crossings_at_the_half_angle() {
        let env = reference();
        // reference-mechanism.md §2, written out here rather than taken from the code:
        // T = 2π √((R+h)³/μ) (5676.978 s), cos φ = √((R+h)² − R²) / ((R+h) cos β)
        // (66.526° for the reference orbit).
        let (r, h) = (EARTH_RADIUS_M, 500e3);
        let t = 2.0 * PI * ((r + h).powi(3) / EARTH_MU_M3_PER_S2).sqrt();
        assert!((t - 5676.978).abs() < 5e-4);
        let phi = (((r + h).powi(2) - r * r).sqrt() / ((r + h) * 20f64.to_radians().cos())).acos();
        assert!((phi.to_degrees() - 66.526).abs() < 5e-4);
        let (t_in, entering) = env.next_shadow_crossing(0.0, 2.0 * t).unwrap();
        assert!(entering);
        assert!((t_in - t * (PI - phi) / (2.0 * PI)).abs() < 1e-6);
        let (t_out, entering) = env.next_shadow_crossing(t_in, 2.0 * t).unwrap();
        assert!(!entering);
        assert!((t_out - t * (PI + phi) / (2.0 * PI)).abs() < 1e-6);
        assert!(!env.sunlit(0.5 * (t_in + t_out)));
        assert!(env.sunlit(t_out + 1.0));
    }

    #[test]
    fn core_scanned_crossings_agree_with_the_closed_form() {
        // A β table holding a constant value takes the numerical scan-and-bisect path.
        let closed = reference();
        let mut scanned = reference();
        scanned.beta_rad = Profile::Table {
            time_s: vec![0.0, 1e9],
            value: vec![20f64.to_radians(); 2],
        };
        let (mut a, mut b) = (0.0, 0.0);
        for _ in 0..8 {
            let ca = closed.next_shadow_crossing(a, 1e6).unwrap();
            let cb = scanned.next_shadow_crossing(b, 1e6).unwrap();
            assert_eq!(ca.1, cb.1);
            assert!((ca.0 - cb.0).abs() < 1e-6, "{} vs {}", ca.0, cb.0);
            a = ca.0;
            b = cb.0;
        }
    }

    #[test]
    fn core_angle_crossings_every_half_orbit() {
        let env = reference();
        let o = &env.orbit;
        let half = o.period_s() / 2.0;
        let mut t = 0.0;
        for k in 0..6 {
            let next = o.next_angle_mod_pi_s(t, FRAC_PI_2);
            assert!(next > t);
            assert!(
                (next - (half / 2.0 + k as f64 * half)).abs() < 1e-6,
                "{k}: {next}"
            );
            assert!(o.orbit_angle_rad(next).cos().abs() < 1e-9);
            t = next;
        }
    }

    #[test]
    fn core_no_eclipse_above_critical_beta() {
        let mut env = reference();
        let crit = env.orbit.critical_beta_rad();
        env.beta_rad = Profile::Constant(crit + 0.01);
        assert_eq!(env.orbit.eclipse_fraction(crit + 0.01), 0.0);
        assert!(
            env.next_shadow_crossing(0.0, 10.0 * env.orbit.period_s())
                .is_none()
        );
    }
}

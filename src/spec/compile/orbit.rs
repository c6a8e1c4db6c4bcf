//! `[orbit]` and `[environment]`: a circular orbit or a TLE on its dates, the mission
//! profile, the Earth and the space sink.

use super::*;
use crate::spec::registry as r;

/// Orbital periods the model accepts, s: 10 minutes … 30 days.
pub const MIN_PERIOD_S: f64 = 600.0;
pub const MAX_PERIOD_S: f64 = 30.0 * SECONDS_PER_DAY;

/// `[orbit] eclipses_s`: [entry, exit] windows, finite, ≥ 0, each entry before its exit
/// and before the next entry.
pub(super) fn given_eclipses(
    cx: &Cx,
    op: &KeyPath,
    w: Option<&[Vec<f64>]>,
) -> Result<Option<crate::orbit::dated::GivenEclipses>, SpecError> {
    let Some(w) = w else { return Ok(None) };
    let p = op.key("eclipses_s");
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (i, pair) in w.iter().enumerate() {
        let [a, b] = pair[..] else {
            return Err(cx.err(&p.at(i), "an eclipse is [entry, exit] in s"));
        };
        let after = out.last().map_or(0.0, |l| l.1);
        if !(a.is_finite() && b.is_finite() && a >= after && b > a) {
            return Err(cx.err(
                &p.at(i),
                format!("[{a}, {b}]: windows must be finite, from 0 on, each entry before its exit and after the last exit"),
            ));
        }
        out.push((a, b));
    }
    Ok(Some(out.into()))
}

/// The orbit, its eclipses' geometry and the mission profile (β, solar flux, albedo,
/// Earth infrared, the space sink): the environment and the sink temperature. A TLE
/// makes a dated environment ([`dated_environment`]); otherwise the orbit is circular.
pub(super) fn environment(
    cx: &Cx,
    orbit_spec: &OrbitSpec,
    environment_spec: EnvironmentSpec,
) -> Result<(Environment, f64), SpecError> {
    if orbit_spec.tle.is_some() {
        return dated_environment(cx, orbit_spec, environment_spec);
    }
    let op = KeyPath::new("orbit");
    for (given, key) in [
        (orbit_spec.start_utc.is_some(), "start_utc"),
        (orbit_spec.start_offset_s.is_some(), r::START_OFFSET_S.name),
        (orbit_spec.eclipses_s.is_some(), "eclipses_s"),
        (orbit_spec.shadow.is_some(), "shadow"),
    ] {
        if given {
            return Err(cx.err(
                &op.key(key),
                "belongs to a real orbit: give `tle` too (or remove it for a circular orbit)",
            ));
        }
    }
    // Orbit.
    let earth_radius_m = cx.read_or_default(&r::EARTH_RADIUS_M, &op, orbit_spec.earth_radius_m)?;
    let Some(altitude_m) = orbit_spec.altitude_m else {
        return Err(cx.err(
            &op,
            format!(
                "give `{}` (a circular orbit) or `tle` and `start_utc` (a real orbit)",
                r::ALTITUDE_M.name
            ),
        ));
    };
    let altitude_m = cx.read(&r::ALTITUDE_M, &op, altitude_m)?;
    let orbit = Orbit {
        altitude_m,
        earth_radius_m,
        mu_m3_per_s2: cx.read_or_default(&r::MU_M3_PER_S2, &op, orbit_spec.mu_m3_per_s2)?,
        // Reduced modulo 360° exactly (fmod is exact) before the conversion, so that a
        // large angle keeps its fraction of a turn.
        orbit_angle_at_start_rad: cx
            .read_or_default(
                &r::ORBIT_ANGLE_AT_START_DEG,
                &op,
                orbit_spec.orbit_angle_at_start_deg,
            )?
            .rem_euclid(360.0)
            .to_radians(),
    };
    let period_s = orbit.period_s();
    if !(MIN_PERIOD_S..=MAX_PERIOD_S).contains(&period_s) {
        let which = if orbit_spec.mu_m3_per_s2.is_some() {
            &r::MU_M3_PER_S2
        } else {
            &r::ALTITUDE_M
        };
        return Err(cx.err(
            &which.key(&op),
            format!(
                "gives an orbital period of {period_s:.3e} s; it must be within {MIN_PERIOD_S} … {MAX_PERIOD_S:.0} s (10 min … 30 days)"
            ),
        ));
    }

    // Environment and mission profile.
    let ep = KeyPath::new("environment");
    let e = environment_spec;
    let (beta, flux) = (&r::BETA_DEG, &r::SOLAR_FLUX_W_PER_M2);
    let Some(beta_spec) = e.beta_deg else {
        return Err(cx.err(
            &ep,
            format!(
                "a circular orbit needs `{}` (a number or a table over mission time)",
                beta.name
            ),
        ));
    };
    let beta_deg = cx.profile(&beta.key(&ep), beta_spec, &|p, v| {
        cx.quantity(beta.quantity, p, v)
    })?;
    let solar_flux = cx.profile(
        &flux.key(&ep),
        e.solar_flux_w_per_m2
            .unwrap_or(ProfileSpec::Constant(flux.quantity.default_value())),
        &|p, v| cx.quantity(flux.quantity, p, v),
    )?;
    let (space_sink_k, albedo, earth_ir_w_per_m2) =
        earth_and_space(cx, e.space_sink_k, e.albedo, e.earth_ir_w_per_m2)?;
    let environment = CircularEnvironment {
        orbit,
        beta_rad: beta_deg.map(f64::to_radians),
        solar_flux_w_per_m2: solar_flux,
        albedo,
        earth_ir_w_per_m2,
        space_sink_k,
    };
    Ok((environment.into(), space_sink_k))
}

/// The environment's numbers every orbit has, in the order they are checked: the
/// space sink (K), the Earth's albedo and its infrared flux (W/m²).
pub(super) fn earth_and_space(
    cx: &Cx,
    space_sink_k: Option<f64>,
    albedo: Option<f64>,
    earth_ir_w_per_m2: Option<f64>,
) -> Result<(f64, f64, f64), SpecError> {
    let ep = KeyPath::new("environment");
    Ok((
        cx.read_or_default(&r::SPACE_SINK_K, &ep, space_sink_k)?,
        cx.read_or_default(&r::ALBEDO, &ep, albedo)?,
        cx.read_or_default(&r::EARTH_IR_W_PER_M2, &ep, earth_ir_w_per_m2)?,
    ))
}

/// A real orbit: the TLE (`orbit.tle`, two lines) from `orbit.start_utc` (shifted by
/// `start_offset_s`), with its shadow model; β, eclipses and period follow from the
/// geometry, and `environment.solar_flux_w_per_m2` is the flux at 1 AU.
pub(super) fn dated_environment(
    cx: &Cx,
    orbit_spec: &OrbitSpec,
    e: EnvironmentSpec,
) -> Result<(Environment, f64), SpecError> {
    let op = KeyPath::new("orbit");
    for (given, key) in [
        (orbit_spec.altitude_m.is_some(), r::ALTITUDE_M.name),
        (orbit_spec.mu_m3_per_s2.is_some(), r::MU_M3_PER_S2.name),
        (
            orbit_spec.orbit_angle_at_start_deg.is_some(),
            r::ORBIT_ANGLE_AT_START_DEG.name,
        ),
    ] {
        if given {
            return Err(cx.err(
                &op.key(key),
                "follows from the TLE; remove it (or remove `tle` for a circular orbit)",
            ));
        }
    }
    let ep = KeyPath::new("environment");
    if e.beta_deg.is_some() {
        return Err(cx.err(
            &r::BETA_DEG.key(&ep),
            "follows from the TLE and the dates; remove it (or remove `tle` for a circular orbit)",
        ));
    }
    let tp = op.key("tle");
    let lines = orbit_spec.tle.as_deref().unwrap_or_default();
    let [l1, l2] = lines else {
        return Err(cx.err(
            &tp,
            format!(
                "lists {} line(s); a TLE is two: tle = [\"1 …\", \"2 …\"]",
                lines.len()
            ),
        ));
    };
    let Some(start_text) = &orbit_spec.start_utc else {
        return Err(cx.err(
            &op,
            "a TLE needs `start_utc`: when the run starts (e.g. \"2016-02-04T00:00:00Z\")",
        ));
    };
    let start =
        crate::orbit::tle::parse_utc(start_text).map_err(|m| cx.err(&op.key("start_utc"), m))?;
    let offset_s = cx.read_or_default(&r::START_OFFSET_S, &op, orbit_spec.start_offset_s)?;
    let start = start + sgp4::chrono::Duration::nanoseconds((offset_s * 1e9).round() as i64);
    let orbit = TleOrbit::new([l1, l2], start).map_err(|err| match err {
        TleError::Line { line, message } => cx.err(&tp.at(line - 1), message),
        TleError::Elements(m) => cx.err(&tp, m),
        TleError::Start(m) => cx.err(&op.key("start_utc"), m),
        TleError::Propagation(m) => cx.err(&tp, m),
    })?;
    let shadow = orbit_spec.shadow.unwrap_or(Shadow::Cylindrical);
    let flux = &r::SOLAR_FLUX_W_PER_M2;
    let solar_flux = match e.solar_flux_w_per_m2 {
        None => flux.quantity.default_value(),
        Some(ProfileSpec::Constant(v)) => cx.read(flux, &ep, v)?,
        Some(ProfileSpec::Table(_)) => {
            return Err(cx.err(
                &flux.key(&ep),
                "with a TLE is one number, the flux at 1 AU (the Sun's distance on each date scales it)",
            ));
        }
    };
    let (space_sink_k, albedo, earth_ir_w_per_m2) =
        earth_and_space(cx, e.space_sink_k, e.albedo, e.earth_ir_w_per_m2)?;
    let environment = DatedEnvironment {
        orbit,
        shadow,
        solar_flux_1au_w_per_m2: solar_flux,
        earth_radius_m: cx.read_or_default(&r::EARTH_RADIUS_M, &op, orbit_spec.earth_radius_m)?,
        albedo,
        earth_ir_w_per_m2,
        space_sink_k,
        horizon_s: 0.0,
        eclipses_s: given_eclipses(cx, &op, orbit_spec.eclipses_s.as_deref())?,
    };
    let period_s = environment.mean_period_s();
    if !(MIN_PERIOD_S..=MAX_PERIOD_S).contains(&period_s) {
        return Err(cx.err(
            &tp.at(1),
            format!(
                "gives an orbital period of {period_s:.3e} s; it must be within {MIN_PERIOD_S} … {MAX_PERIOD_S:.0} s (10 min … 30 days)"
            ),
        ));
    }
    // The Earth must be inside the orbit (a radius of the orbit's own size or larger
    // would put the spacecraft in the umbra all day).
    let perigee_m = environment
        .orbit
        .perigee_radius_m(0.0)
        .map_err(|m| cx.err(&tp, m))?;
    if perigee_m <= environment.earth_radius_m {
        return Err(cx.err(
            &if orbit_spec.earth_radius_m.is_some() {
                op.key(r::EARTH_RADIUS_M.name)
            } else {
                tp.clone()
            },
            format!(
                "the Earth's radius ({:.0} km) reaches the orbit's perigee ({:.0} km from the Earth's centre): the spacecraft would be inside the Earth",
                environment.earth_radius_m / 1e3,
                perigee_m / 1e3
            ),
        ));
    }
    Ok((environment.into(), space_sink_k))
}

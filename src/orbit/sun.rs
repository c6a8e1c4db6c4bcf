//! The Sun's direction and distance on a date: the low-precision solar coordinates of
//! the Astronomical Almanac (section C, "Low precision formulas for the Sun"; the same
//! as Vallado, *Fundamentals of Astrodynamics and Applications*, Algorithm 29).
//!
//! Stated accuracy: 0.01° in direction and 0.0003 AU (about 45 000 km) in distance
//! between 1950 and 2050; outside those years the error grows slowly (the mean
//! elements are linear in time), so dates are accepted from 1900 to 2100
//! ([`EPHEMERIS_YEARS`]). The position is referred to the mean equator and equinox of
//! date, which for a thermal model is the frame of SGP4's TEME output: the two differ by
//! the nutation in right ascension, below 0.005°.
//!
//! Time: the formulas take UT1 ≈ UTC (the difference is below a second: 4e-6° of the
//! Sun's motion).

/// Julian date of J2000.0 (2000-01-01 12:00 TT; used here on the UTC scale).
pub const J2000_JD: f64 = 2_451_545.0;

/// One astronomical unit, m (IAU 2012).
pub const AU_M: f64 = 149_597_870_700.0;

/// The calendar years within which a date is accepted: the almanac's formulas are
/// stated for 1950–2050 and degrade slowly beyond.
pub const EPHEMERIS_YEARS: (i32, i32) = (1900, 2100);

/// The years for which the almanac states its accuracy: a start outside them is
/// accepted (within [`EPHEMERIS_YEARS`]) with a warning.
pub const STATED_YEARS: (i32, i32) = (1950, 2050);

/// Where the Sun is, seen from the Earth's centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SunPosition {
    /// Unit vector toward the Sun, mean equator and equinox of date.
    pub direction: [f64; 3],
    /// Earth–Sun distance, AU.
    pub distance_au: f64,
}

/// The Sun at Julian date `jd` (UTC taken as UT1).
pub fn sun_at(jd: f64) -> SunPosition {
    let n = jd - J2000_JD;
    let deg = std::f64::consts::PI / 180.0;
    // Mean longitude and mean anomaly, degrees.
    let mean_longitude = 280.460 + 0.985_647_4 * n;
    let g = (357.528 + 0.985_600_3 * n) * deg;
    // Ecliptic longitude (latitude < 0.00033°, taken as 0) and obliquity.
    let lambda = (mean_longitude + 1.915 * g.sin() + 0.020 * (2.0 * g).sin()) * deg;
    let epsilon = (23.439 - 0.000_000_4 * n) * deg;
    let distance_au = 1.000_14 - 0.016_71 * g.cos() - 0.000_14 * (2.0 * g).cos();
    let (sl, cl) = lambda.sin_cos();
    let (se, ce) = epsilon.sin_cos();
    SunPosition {
        direction: [cl, ce * sl, se * sl],
        distance_au,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_direction_and_distance_within_the_orbit() {
        for k in 0..400 {
            let s = sun_at(J2000_JD + 9.13 * k as f64);
            let n: f64 = s.direction.iter().map(|x| x * x).sum();
            assert!((n - 1.0).abs() < 1e-12);
            // perihelion 0.9833 AU, aphelion 1.0167 AU
            assert!(
                (0.983..=1.0168).contains(&s.distance_au),
                "{}",
                s.distance_au
            );
        }
    }
}

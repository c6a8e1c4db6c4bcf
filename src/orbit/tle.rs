//! An orbit from a two-line element set, propagated with SGP4.
//!
//! Propagator: the `sgp4` crate (a Rust transcription of the reference implementation
//! of Vallado et al. 2006, "Revisiting Spacetrack Report #3", AIAA 2006-6753, verified
//! by its authors against that paper's test set), run in its AFSPC-compatible mode:
//! WGS-72 constants and the AFSPC sidereal time, the model TLEs are fitted with. Output:
//! the True Equator, Mean Equinox (TEME) frame, which for the Sun's direction and the
//! Earth's shadow is the mean-of-date frame of [`super::sun`] to within the nutation in
//! right ascension (< 0.005°).
//!
//! Accuracy far from the epoch: SGP4 mean elements drift mostly along the track (a few
//! km a day for a LEO TLE, growing as the drag model ages); the orbit plane, and so β
//! and the eclipse fraction, stay close for weeks. A thermal prediction over months
//! from one TLE keeps the right seasons and eclipse lengths while the exact minute of
//! each eclipse drifts: compare telemetry with a TLE near its dates.
//!
//! The propagation is sampled every [`NODE_SPACING_S`] and interpolated between samples
//! by cubic Hermite polynomials in position and velocity (error below 1 m in LEO,
//! where 60 s of motion is 450 km), so that a step of the thermal solver costs a few
//! multiplications rather than an SGP4 evaluation. The samples are computed a day at a
//! time, once, and shared by every copy of the model and every thread.

use std::sync::{Arc, OnceLock};

use sgp4::chrono::{DateTime, NaiveDateTime};

/// Spacing of the propagated samples, s.
pub const NODE_SPACING_S: f64 = 60.0;
/// Samples per cached chunk (one day).
const CHUNK_NODES: usize = 1440;
const CHUNK_S: f64 = NODE_SPACING_S * CHUNK_NODES as f64;
/// Memory the propagation's table takes per simulated day, bytes (a run keeps every
/// day it has propagated).
pub const TABLE_BYTES_PER_DAY: f64 = ((CHUNK_NODES + 1) * 10 * 8) as f64;

/// Days between a TLE's epoch and the start of a run beyond which `check` warns: a
/// LEO TLE's along-track error grows to tens of km within a few days.
pub const EPOCH_WARN_DAYS: f64 = 3.0;
/// Days beyond which a TLE is refused for the start of a run: beyond about a month the
/// drag model has aged enough that even the orbit's decay rate (and with it the
/// altitude) is no longer known; a new TLE is the answer.
pub const EPOCH_LIMIT_DAYS: f64 = 30.0;

/// Why a TLE or a start date cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TleError {
    #[error("line {line} {message}")]
    Line { line: usize, message: String },
    #[error("{0}")]
    Elements(String),
    #[error("{0}")]
    Start(String),
    #[error("{0}")]
    Propagation(String),
}

/// A TLE orbit from a start date on: position and velocity at seconds after the start.
#[derive(Clone)]
pub struct TleOrbit {
    /// The two lines as given.
    pub lines: [String; 2],
    /// The start of the run (t = 0), UTC.
    pub start_utc: NaiveDateTime,
    /// The TLE's epoch, UTC.
    pub epoch_utc: NaiveDateTime,
    /// Julian date of the start (UTC).
    pub start_jd: f64,
    /// Minutes from the TLE's epoch to the start.
    start_minutes: f64,
    /// Revolutions per day (the TLE's mean motion).
    pub mean_motion_rev_per_day: f64,
    pub inclination_deg: f64,
    pub eccentricity: f64,
    constants: Arc<sgp4::Constants>,
    cache: Arc<Cache>,
}

impl std::fmt::Debug for TleOrbit {
    /// The lines and the start: what defines the orbit (the propagator's constants and
    /// the cached samples follow from them).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TleOrbit")
            .field("lines", &self.lines)
            .field("start_utc", &self.start_utc)
            .finish()
    }
}

impl PartialEq for TleOrbit {
    /// The same lines and start: the same orbit.
    fn eq(&self, other: &Self) -> bool {
        self.lines == other.lines && self.start_utc == other.start_utc
    }
}

/// The propagated samples, a chunk (day) at a time: `[x, y, z, vx, vy, vz]` in m and
/// m/s, or why the propagation failed. Blocks of [`BLOCK_DAYS`] chunks, each made on
/// first use: a chunk once filled is read with a few atomic loads and no lock or
/// shared counter written, so threads that read the same orbit (margins samples, diagnose
/// candidates) do not contend.
#[derive(Debug)]
struct Cache {
    blocks: Box<[OnceLock<Box<[Chunk]>>]>,
}

impl Default for Cache {
    fn default() -> Cache {
        Cache {
            blocks: (0..BLOCKS).map(|_| OnceLock::new()).collect(),
        }
    }
}

/// Chunks (days) per block of the cache, and blocks: 65 536 days (179 years) in all.
const BLOCK_DAYS: usize = 64;
const BLOCKS: usize = 1024;

/// One day of samples, or why they could not be propagated; filled on first use.
type Chunk = OnceLock<Result<Vec<Sample>, String>>;

/// One sample: TEME position (m) and velocity (m/s), the Sun's unit direction and its
/// distance (AU).
type Sample = [f64; 10];

/// The caches alive in this process, by orbit (lines and start).
type Registry = std::sync::Mutex<Vec<((String, String, NaiveDateTime), std::sync::Weak<Cache>)>>;

/// The cache of the orbit of `lines` from `start`: one per process while any model
/// holds it, so that recompiling a scenario (`--set`, a TOML edit, a diagnose
/// candidate) does not propagate the orbit again.
fn shared_cache(lines: [&str; 2], start: NaiveDateTime) -> Arc<Cache> {
    static CACHES: OnceLock<Registry> = OnceLock::new();
    let key = (
        lines[0].trim_end().to_string(),
        lines[1].trim_end().to_string(),
        start,
    );
    let mut all = CACHES
        .get_or_init(Default::default)
        .lock()
        .expect("cache registry lock");
    all.retain(|(_, w)| w.strong_count() > 0);
    if let Some(c) = all
        .iter()
        .find(|(k, _)| *k == key)
        .and_then(|(_, w)| w.upgrade())
    {
        return c;
    }
    let c = Arc::new(Cache::default());
    all.push((key, Arc::downgrade(&c)));
    c
}

/// Julian date of a UTC time.
pub fn julian_date(t: &NaiveDateTime) -> f64 {
    let utc = t.and_utc();
    2_440_587.5 + (utc.timestamp() as f64 + utc.timestamp_subsec_nanos() as f64 * 1e-9) / 86_400.0
}

/// The mean orbit radius, m, of a TLE's line 2 (its mean motion, columns 53–63, by
/// Kepler's third law): the radius the Earth's view factor of a nadir face is taken at.
pub fn mean_radius_m(line2: &str) -> Option<f64> {
    let n: f64 = line2.get(52..63)?.trim().parse().ok()?;
    if n.is_nan() || n <= 0.0 {
        return None;
    }
    let period_s = 86_400.0 / n;
    Some(
        (crate::constants::EARTH_MU_M3_PER_S2 * (period_s / (2.0 * std::f64::consts::PI)).powi(2))
            .cbrt(),
    )
}

/// Parses an RFC 3339 / ISO 8601 UTC time (`2016-02-04T00:00:00Z`).
pub fn parse_utc(text: &str) -> Result<NaiveDateTime, String> {
    DateTime::parse_from_rfc3339(text.trim())
        .map(|d| d.naive_utc())
        .map_err(|e| {
            format!("`{text}` is not a UTC time like 2016-02-04T00:00:00Z (RFC 3339): {e}")
        })
}

impl TleOrbit {
    /// The orbit of the TLE `lines` from `start_utc`. Checks the lines (length,
    /// checksums, fields), the epoch's distance from the start
    /// ([`EPOCH_LIMIT_DAYS`]), and that the orbit is elliptical and above the
    /// atmosphere at the start.
    pub fn new(lines: [&str; 2], start_utc: NaiveDateTime) -> Result<TleOrbit, TleError> {
        for (i, l) in lines.iter().enumerate() {
            check_line(i + 1, l)?;
        }
        let elements = sgp4::Elements::from_tle(
            None,
            lines[0].trim_end().as_bytes(),
            lines[1].trim_end().as_bytes(),
        )
        .map_err(|e| TleError::Elements(tle_error_text(&e.to_string())))?;
        let constants = sgp4::Constants::from_elements_afspc_compatibility_mode(&elements)
            .map_err(|e| TleError::Elements(format!("SGP4 refuses the elements: {e}")))?;
        let start_minutes = elements
            .datetime_to_minutes_since_epoch(&start_utc)
            .map_err(|e| TleError::Start(e.to_string()))?
            .0;
        let days = start_minutes / 1440.0;
        if days.abs() > EPOCH_LIMIT_DAYS {
            return Err(TleError::Start(format!(
                "starts {:.1} days {} the TLE's epoch ({}); a TLE predicts an orbit for about \
                 {EPOCH_LIMIT_DAYS} days around its epoch: use a TLE from near the start",
                days.abs(),
                if days > 0.0 { "after" } else { "before" },
                elements.datetime.format("%Y-%m-%dT%H:%M:%SZ")
            )));
        }
        let (y_lo, y_hi) = super::sun::EPHEMERIS_YEARS;
        let year = sgp4::chrono::Datelike::year(&start_utc);
        if !(y_lo..=y_hi).contains(&year) {
            return Err(TleError::Start(format!(
                "is in {year}; the solar ephemeris covers {y_lo} … {y_hi}"
            )));
        }
        let orbit = TleOrbit {
            lines: [
                lines[0].trim_end().to_string(),
                lines[1].trim_end().to_string(),
            ],
            start_utc,
            epoch_utc: elements.datetime,
            start_jd: julian_date(&start_utc),
            start_minutes,
            mean_motion_rev_per_day: elements.mean_motion,
            inclination_deg: elements.inclination,
            eccentricity: elements.eccentricity,
            constants: Arc::new(constants),
            cache: shared_cache(lines, start_utc),
        };
        orbit.propagate(0.0).map_err(TleError::Propagation)?;
        Ok(orbit)
    }

    /// Days from the TLE's epoch to the start (negative: the start is before it).
    pub fn epoch_age_days(&self) -> f64 {
        self.start_minutes / 1440.0
    }

    /// Mean period, s.
    pub fn period_s(&self) -> f64 {
        86_400.0 / self.mean_motion_rev_per_day
    }

    /// SGP4 at `t_s` after the start: TEME position (m) and velocity (m/s).
    pub fn propagate(&self, t_s: f64) -> Result<[f64; 6], String> {
        let p = self
            .constants
            .propagate_afspc_compatibility_mode(sgp4::MinutesSinceEpoch(
                self.start_minutes + t_s / 60.0,
            ))
            .map_err(|e| format!("SGP4 fails {:.1} days after the start: {e}", t_s / 86_400.0))?;
        let r = p.position.map(|x| x * 1e3);
        let v = p.velocity.map(|x| x * 1e3);
        if !(r.iter().chain(&v).all(|x| x.is_finite())) {
            return Err(format!(
                "SGP4 gives no finite position {:.1} days after the start",
                t_s / 86_400.0
            ));
        }
        let radius = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        if radius < crate::constants::EARTH_RADIUS_M + DECAY_ALTITUDE_M {
            return Err(format!(
                "the orbit has decayed {:.1} days after the start (altitude {:.0} km)",
                t_s / 86_400.0,
                (radius - crate::constants::EARTH_RADIUS_M) / 1e3
            ));
        }
        Ok([r[0], r[1], r[2], v[0], v[1], v[2]])
    }

    /// Position (m) and velocity (m/s) at `t_s` ≥ 0 after the start, interpolated
    /// between the cached samples (cubic Hermite in position, its derivative for the
    /// velocity). NaN when the propagation failed there (see [`TleOrbit::check_until`]).
    pub fn state(&self, t_s: f64) -> [f64; 6] {
        let s = self.sample(t_s);
        [s[0], s[1], s[2], s[3], s[4], s[5]]
    }

    /// Position (m), velocity (m/s), the Sun's direction and distance (AU) at `t_s` ≥ 0
    /// after the start: the orbit interpolated between the cached samples (cubic
    /// Hermite), the Sun linearly (it moves 0.04° a minute: the error is below
    /// 1e-10 rad). NaN when the propagation failed there.
    pub fn sample(&self, t_s: f64) -> Sample {
        let t = t_s.max(0.0);
        let chunk = (t / CHUNK_S).floor() as usize;
        let Some(Ok(samples)) = self.chunk(chunk) else {
            return [f64::NAN; 10];
        };
        let local = t - chunk as f64 * CHUNK_S;
        let j = ((local / NODE_SPACING_S).floor() as usize).min(CHUNK_NODES - 1);
        let (a, b) = (&samples[j], &samples[j + 1]);
        let h = NODE_SPACING_S;
        let s = (local - j as f64 * h) / h;
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        let d00 = (6.0 * s2 - 6.0 * s) / h;
        let d10 = 3.0 * s2 - 4.0 * s + 1.0;
        let d01 = (-6.0 * s2 + 6.0 * s) / h;
        let d11 = 3.0 * s2 - 2.0 * s;
        let mut out = [0.0; 10];
        for k in 0..3 {
            out[k] = h00 * a[k] + h10 * h * a[k + 3] + h01 * b[k] + h11 * h * b[k + 3];
            out[k + 3] = d00 * a[k] + d10 * a[k + 3] + d01 * b[k] + d11 * b[k + 3];
        }
        for k in 6..10 {
            out[k] = a[k] + s * (b[k] - a[k]);
        }
        let n = (out[6] * out[6] + out[7] * out[7] + out[8] * out[8]).sqrt();
        for x in &mut out[6..9] {
            *x /= n;
        }
        out
    }

    /// The perigee's distance from the Earth's centre, m, of the osculating orbit at
    /// `t_s` (two-body, from SGP4's position and velocity there); infinite for an
    /// orbit that is not bound.
    pub fn perigee_radius_m(&self, t_s: f64) -> Result<f64, String> {
        let x = self.propagate(t_s)?;
        Ok(perigee_radius_m([x[0], x[1], x[2]], [x[3], x[4], x[5]]))
    }

    /// One SGP4 point a day from the start to `t_end_s` (and at it): a decayed or
    /// diverging orbit found cheaply (a few ms for a 30-year run), before anything is
    /// tabulated; the first failure with its time. A point whose osculating perigee is
    /// below the decay altitude fails too: the orbit dips below it within a turn, even
    /// where the point itself is higher (a day's points fall anywhere on the orbit).
    pub fn check_daily(&self, t_end_s: f64) -> Result<(), String> {
        let days = (t_end_s.max(0.0) / 86_400.0).ceil() as u64;
        for d in 0..=days {
            let t = (d as f64 * 86_400.0).min(t_end_s.max(0.0));
            let perigee = self.perigee_radius_m(t)?;
            if perigee < crate::constants::EARTH_RADIUS_M + DECAY_ALTITUDE_M {
                return Err(format!(
                    "the orbit has decayed by {:.1} days after the start (its perigee is at {:.0} km altitude, below 80 km: it enters the atmosphere within a turn)",
                    t / 86_400.0,
                    (perigee - crate::constants::EARTH_RADIUS_M) / 1e3
                ));
            }
        }
        Ok(())
    }

    /// Propagates every cached day up to `t_end_s`: the first failure (a decayed or
    /// diverging orbit), with its time. The days are propagated in parallel
    /// ([`Self::fill_days`]): each is a pure function of the elements and its own
    /// times, so the table is the same for any thread count.
    pub fn check_until(&self, t_end_s: f64) -> Result<(), String> {
        let last = (t_end_s.max(0.0) / CHUNK_S).floor() as usize;
        if last >= BLOCK_DAYS * BLOCKS {
            return Err(format!(
                "the run is longer than the orbit's table holds ({} days)",
                BLOCK_DAYS * BLOCKS
            ));
        }
        self.fill_days(last);
        for c in 0..=last {
            if let Some(Err(e)) = self.chunk(c) {
                return Err(e.clone());
            }
        }
        Ok(())
    }

    /// Computes days 0 … `last` of the table in parallel: on the worker pool when called
    /// from one of its threads (margins, diagnose), else on scoped threads, one per
    /// core, taking the days in turn. It never starts rayon's global pool itself (the
    /// commands that want one build it with their checks), and a thread that cannot be
    /// started (a memory or process limit) leaves its days to the others.
    fn fill_days(&self, last: usize) {
        use rayon::prelude::*;
        if rayon::current_thread_index().is_some() {
            (0..=last).into_par_iter().for_each(|c| {
                self.chunk(c);
            });
            return;
        }
        let threads = std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(last + 1);
        let next = std::sync::atomic::AtomicUsize::new(0);
        let work = || {
            loop {
                let c = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if c > last {
                    break;
                }
                self.chunk(c);
            }
        };
        std::thread::scope(|s| {
            for _ in 1..threads {
                let _ = std::thread::Builder::new().spawn_scoped(s, work);
            }
            work();
        });
    }

    /// Chunk `c`'s samples (days `c` … `c + 1` after the start, both ends included),
    /// computed on first use (None beyond the table's [`BLOCK_DAYS`] × [`BLOCKS`] days).
    fn chunk(&self, c: usize) -> Option<&Result<Vec<Sample>, String>> {
        let block = self
            .cache
            .blocks
            .get(c / BLOCK_DAYS)?
            .get_or_init(|| (0..BLOCK_DAYS).map(|_| OnceLock::new()).collect());
        Some(block[c % BLOCK_DAYS].get_or_init(|| {
            (0..=CHUNK_NODES)
                .map(|j| {
                    let t = c as f64 * CHUNK_S + j as f64 * NODE_SPACING_S;
                    let p = self.propagate(t)?;
                    let sun = super::sun::sun_at(self.start_jd + t / 86_400.0);
                    let d = sun.direction;
                    Ok([
                        p[0],
                        p[1],
                        p[2],
                        p[3],
                        p[4],
                        p[5],
                        d[0],
                        d[1],
                        d[2],
                        sun.distance_au,
                    ])
                })
                .collect()
        }))
    }
}

/// Below this altitude, m, an orbit has decayed (the spacecraft re-enters).
const DECAY_ALTITUDE_M: f64 = 80e3;

/// The perigee's distance from the Earth's centre, m, of the two-body orbit through
/// position `r` (m) with velocity `v` (m/s); infinite when it is not bound.
fn perigee_radius_m(r: [f64; 3], v: [f64; 3]) -> f64 {
    use super::faces::{cross, dot, norm};
    let mu = crate::constants::EARTH_MU_M3_PER_S2;
    let rn = norm(r);
    let energy = 0.5 * dot(v, v) - mu / rn;
    if energy.is_nan() || energy >= 0.0 {
        return f64::INFINITY;
    }
    let a = -mu / (2.0 * energy);
    let h = cross(r, v);
    // e = (v × h) / μ − r / |r|
    let vh = cross(v, h);
    let e = norm([0, 1, 2].map(|k| vh[k] / mu - r[k] / rn));
    a * (1.0 - e)
}

/// Checks one TLE line before SGP4's parser sees it: its number, length and checksum,
/// with messages that name the line and what to fix.
fn check_line(n: usize, line: &str) -> Result<(), TleError> {
    let l = line.trim_end();
    let err = |message: String| TleError::Line { line: n, message };
    if !l.is_ascii() {
        return Err(err("holds characters that are not ASCII".into()));
    }
    if l.len() != 69 {
        return Err(err(format!(
            "has {} characters; a TLE line has 69 (columns 1 … 69)",
            l.len()
        )));
    }
    if !l.starts_with(&format!("{n} ")) {
        return Err(err(format!("must begin with \"{n} \"")));
    }
    let sum: u32 = l[..68]
        .bytes()
        .map(|b| match b {
            b'0'..=b'9' => (b - b'0') as u32,
            b'-' => 1,
            _ => 0,
        })
        .sum();
    let given = l.as_bytes()[68];
    if !given.is_ascii_digit() || (given - b'0') as u32 != sum % 10 {
        return Err(err(format!(
            "has checksum {} but its digits sum to {} (mod 10: {}): the line was altered or \
             mistyped",
            given as char,
            sum,
            sum % 10
        )));
    }
    fields(n, l).map_err(err)
}

/// A field of a TLE line, columns `from` … `to` (1-based, inclusive), as a number.
fn field(l: &str, from: usize, to: usize, what: &str) -> Result<f64, String> {
    let text = l[from - 1..to].trim();
    text.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{what}, columns {from} … {to}, `{text}` is not a number"))
}

/// The epoch (line 1) and the angles and mean motion (line 2) within their ranges,
/// each error naming the field and its columns.
fn fields(n: usize, l: &str) -> Result<(), String> {
    let within = |v: f64, lo: f64, hi: f64, hi_open: bool, what: &str, cols: (usize, usize)| {
        let ok = v >= lo && if hi_open { v < hi } else { v <= hi };
        if ok {
            Ok(())
        } else {
            Err(format!(
                "{what}, columns {} … {}, is {v}; it must be within {lo} … {hi}{}",
                cols.0,
                cols.1,
                if hi_open { " (excluded)" } else { "" }
            ))
        }
    };
    if n == 1 {
        let yy = field(l, 19, 20, "the epoch year")?;
        let year = if yy < 57.0 {
            2000 + yy as i32
        } else {
            1900 + yy as i32
        };
        let leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
        let day = field(l, 21, 32, "the epoch day of the year")?;
        let last = if leap { 367.0 } else { 366.0 };
        if !(1.0..last).contains(&day) {
            return Err(format!(
                "the epoch day of the year, columns 21 … 32, is {day}; {year} has days 1 … {} \
                 (day 1.0 is 1 January 0 h)",
                last - 1.0
            ));
        }
        return Ok(());
    }
    for (what, from, to, hi, open) in [
        ("the inclination in degrees", 9, 16, 180.0, false),
        (
            "the right ascension of the ascending node in degrees",
            18,
            25,
            360.0,
            true,
        ),
        ("the argument of perigee in degrees", 35, 42, 360.0, true),
        ("the mean anomaly in degrees", 44, 51, 360.0, true),
    ] {
        within(field(l, from, to, what)?, 0.0, hi, open, what, (from, to))?;
    }
    let n_rev = field(l, 53, 63, "the mean motion")?;
    if n_rev <= 0.0 {
        return Err(format!(
            "the mean motion (columns 53 … 63) is {n_rev} revolutions per day; it must be > 0"
        ));
    }
    Ok(())
}

/// SGP4's parse error, without its prefix.
fn tle_error_text(e: &str) -> String {
    e.trim_start_matches("TLE parse error: ").to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    const L1: &str = "1 39444U 13066AE  16035.38257241  .00000865  00000-0  11531-3 0  9990";
    const L2: &str = "2 39444  97.7004  94.3150 0060634  98.1157 262.6940 14.80829622117779";

    #[test]
    fn interpolation_agrees_with_sgp4_between_samples() {
        let o = TleOrbit::new([L1, L2], parse_utc("2016-02-04T00:00:00Z").unwrap()).unwrap();
        let mut worst: f64 = 0.0;
        for k in 0..500 {
            let t = 17.3 * k as f64 + 0.37;
            let a = o.state(t);
            let b = o.propagate(t).unwrap();
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            worst = worst.max(d);
        }
        assert!(worst < 1.0, "interpolation error {worst} m");
    }

    /// The table is filled once, from four threads at once, across a block boundary
    /// (day 64): every thread reads the same samples, each within a metre of SGP4;
    /// a run beyond the table's end is refused (before propagating 179 years).
    #[test]
    fn core_the_table_is_shared_by_threads_without_a_lock() {
        let start = parse_utc("2016-02-04T00:00:00Z").unwrap();
        let times: Vec<f64> = (0..64)
            .map(|k| (62.0 + 0.06 * k as f64) * 86_400.0 + 7.0)
            .collect();
        let shared = TleOrbit::new([L1, L2], start).unwrap();
        let seen: Vec<Vec<Sample>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..4)
                .map(|_| s.spawn(|| times.iter().map(|&t| shared.sample(t)).collect::<Vec<_>>()))
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        for got in &seen {
            assert_eq!(got, &seen[0]);
        }
        for (k, &t) in times.iter().enumerate() {
            let p = shared.propagate(t).unwrap();
            let d = (0..3)
                .map(|i| (seen[0][k][i] - p[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d < 1.0, "day {:.2}: {d} m from SGP4", t / 86_400.0);
        }
        let err = shared.check_until(1.0e10).unwrap_err();
        assert!(err.contains("longer than the orbit's table"), "{err}");
    }

    #[test]
    fn checksums_and_lengths_are_checked() {
        let start = parse_utc("2016-02-04T00:00:00Z").unwrap();
        let bad = L1.replace("9990", "9991");
        let e = TleOrbit::new([&bad, L2], start).unwrap_err().to_string();
        assert!(e.starts_with("line 1 has checksum 1"), "{e}");
        let e = TleOrbit::new([L1, &L2[..60]], start)
            .unwrap_err()
            .to_string();
        assert!(e.contains("has 60 characters"), "{e}");
        let far = parse_utc("2016-06-04T00:00:00Z").unwrap();
        let e = TleOrbit::new([L1, L2], far).unwrap_err().to_string();
        assert!(e.contains("days after the TLE's epoch"), "{e}");
    }
}

//! The FUNcube-1 Whole Orbit Data file as text: its rows kept cell by cell as written
//! (so that an untouched cell is written back byte for byte), the time stamps as
//! seconds from the scenario's `start_utc`, the warehouse's fill rows (a row repeating
//! every cell of the row before), and the eclipse transitions the photo-current shows.
//! The rewrite with a signature added lives here too ([`Telemetry::with_signature`]).

/// The total photo-current column, mA: about 0 in eclipse, 100 … 412 mA in sunlight.
pub const PHOTO_COLUMN: &str = "Tot. Photo Curr. mA";
/// Photo-current below which a row is in eclipse, mA.
pub const DARK_MA: f64 = 20.0;

/// The telemetry file as written.
#[derive(Clone, Debug)]
pub struct Telemetry {
    /// The header line, as written.
    pub header_line: String,
    pub header: Vec<String>,
    /// Every data row's cells, as written (column 0 is the time stamp).
    pub rows: Vec<Vec<String>>,
    /// Each row's time, s from `start_utc`.
    pub times_s: Vec<f64>,
    /// Whether a row is fill: every cell after the time stamp equal to the row before.
    pub fill: Vec<bool>,
}

/// Days from 1970-01-01 to a proleptic Gregorian date (H. Hinnant's algorithm).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// Seconds since 1970-01-01 of `YYYY-MM-DD[ T]HH:MM:SS[.f][Z]`.
pub fn unix_s(stamp: &str) -> f64 {
    let s = stamp.trim().trim_end_matches('Z');
    let bad = || -> ! { panic!("{stamp:?} is not a UTC time stamp") };
    if s.len() < 19 {
        bad();
    }
    let field = |a: usize, b: usize| s[a..b].parse::<i64>().unwrap_or_else(|_| bad());
    let days = days_from_civil(field(0, 4), field(5, 7), field(8, 10));
    let secs = s[17..].parse::<f64>().unwrap_or_else(|_| bad());
    (days * 86_400 + field(11, 13) * 3600 + field(14, 16) * 60) as f64 + secs
}

/// Day of the year (1 = 1 January) of a time stamp, with its fraction.
pub fn day_of_year(stamp: &str) -> f64 {
    let year: i64 = stamp[0..4].parse().expect("a year");
    let jan1 = days_from_civil(year, 1, 1) as f64 * 86_400.0;
    1.0 + (unix_s(stamp) - jan1) / 86_400.0
}

/// `value` written with as many decimals as `like` has (never as `-0.00`).
pub fn format_like(like: &str, value: f64) -> String {
    let decimals = like.split_once('.').map_or(0, |(_, f)| f.len());
    let out = format!("{value:.decimals$}");
    match out.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => out,
    }
}

impl Telemetry {
    /// Reads the file; `time_column` must be its first column. Panics on quoted cells
    /// or ragged rows (the file has neither).
    /// `offset_s` is added to every stamp (the time a row was measured).
    pub fn read(
        path: &std::path::Path,
        time_column: &str,
        start_utc: &str,
        offset_s: f64,
    ) -> Telemetry {
        let text =
            std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(!text.contains('"'), "{}: quoted cells", path.display());
        let mut lines = text.lines();
        let header_line = lines.next().expect("an empty telemetry file").to_string();
        let header: Vec<String> = header_line.split(',').map(str::to_string).collect();
        assert_eq!(header[0], time_column, "the time column must come first");
        let t0 = unix_s(start_utc);
        let rows: Vec<Vec<String>> = lines
            .filter(|l| !l.trim().is_empty())
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect();
        for (k, r) in rows.iter().enumerate() {
            assert_eq!(r.len(), header.len(), "line {}: {} cells", k + 2, r.len());
        }
        let times_s = rows.iter().map(|r| unix_s(&r[0]) - t0 + offset_s).collect();
        let fill = (0..rows.len())
            .map(|k| k > 0 && rows[k][1..] == rows[k - 1][1..])
            .collect();
        Telemetry {
            header_line,
            header,
            rows,
            times_s,
            fill,
        }
    }

    /// Index of a column by name.
    pub fn column(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name:?}"))
    }

    /// A column's values on the measured rows, `None` on fill rows.
    pub fn values(&self, column: usize) -> Vec<Option<f64>> {
        self.rows
            .iter()
            .zip(&self.fill)
            .map(|(r, &fill)| {
                (!fill).then(|| {
                    r[column]
                        .trim()
                        .parse()
                        .unwrap_or_else(|_| panic!("{:?} is not a number", r[column]))
                })
            })
            .collect()
    }

    /// Eclipse transitions: where two measured rows at most 61 s apart change state
    /// (photo-current below [`DARK_MA`]), the middle of the two rows' times, and
    /// whether it is an entry (true) or an exit.
    pub fn sun_transitions(&self) -> Vec<(f64, bool)> {
        let photo = self.values(self.column(PHOTO_COLUMN));
        let mut out = Vec::new();
        let mut last: Option<(f64, bool)> = None;
        for (t, pc) in self.times_s.iter().zip(&photo) {
            let Some(pc) = pc else { continue };
            let dark = *pc < DARK_MA;
            if let Some((t0, d0)) = last
                && d0 != dark
                && t - t0 <= 61.0
            {
                out.push((0.5 * (t0 + t), dark));
            }
            last = Some((*t, dark));
        }
        out
    }

    /// The file with `signature` added: `signature[c]` is (column index, the value to
    /// add at every row). Measured rows get each signed cell's value plus its
    /// signature, written with the cell's own decimals; cells without a signature (or
    /// with a signature of exactly 0 at that row) are kept as written; fill rows are rebuilt as repeats of the (modified) row before;
    /// the header and the time stamps are untouched.
    pub fn with_signature(&self, signature: &[(usize, Vec<f64>)]) -> String {
        let mut out = String::with_capacity(self.rows.len() * 120);
        out.push_str(&self.header_line);
        out.push('\n');
        let mut previous: Vec<String> = Vec::new();
        for (k, row) in self.rows.iter().enumerate() {
            let mut cells = row.clone();
            if self.fill[k] {
                cells[1..].clone_from_slice(&previous[1..]);
            } else {
                for (c, values) in signature.iter().filter(|(_, v)| v[k] != 0.0) {
                    let v: f64 = row[*c].trim().parse().expect("a number");
                    cells[*c] = format_like(&row[*c], v + values[k]);
                }
            }
            out.push_str(&cells.join(","));
            out.push('\n');
            previous = cells;
        }
        out
    }
}

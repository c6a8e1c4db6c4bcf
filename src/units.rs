//! Unit conversions used at the edges (SI inside; °C, µm, mm, days outside).

use crate::constants::ZERO_CELSIUS_K;

/// Kelvin to degrees Celsius.
pub fn k_to_c(t_k: f64) -> f64 {
    t_k - ZERO_CELSIUS_K
}

/// Degrees Celsius to kelvin.
pub fn c_to_k(t_c: f64) -> f64 {
    t_c + ZERO_CELSIUS_K
}

/// Seconds in one day.
pub const SECONDS_PER_DAY: f64 = 86_400.0;

/// A number for an error message: plain when it reads well, in exponent form when it
/// would take many digits (1e300, 1e-6).
pub fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-3..1e6).contains(&a) {
        format!("{v}")
    } else {
        // four significant digits, trailing zeros dropped: 1.856e10, 1e300
        let s = format!("{v:.3e}");
        let (mantissa, exponent) = s.split_once('e').expect("exponent form");
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        format!("{mantissa}e{exponent}")
    }
}

/// A number to four significant digits, in exponent form outside 1e-3 … 1e5 (a
/// fitted value and its error in a report).
pub fn sig(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let e = v.abs().log10().floor() as i32;
    if (-3..5).contains(&e) {
        format!("{:.*}", (3 - e).max(0) as usize, v)
    } else {
        format!("{v:.3e}")
    }
}

/// A number to `n` significant digits (n ≥ 1), trailing zeros dropped: plain when its
/// rounded value is within 1e-3 … 1e5 and `n` digits reach its units, else in exponent
/// form (29.9937, 1.11123e-5, 1.23e4 for 12345 to 3 digits, 1e5 for 99999.96 to 6): a
/// sampled value in a line of text, where [`exact`]'s 17 digits are noise and [`sig`]'s
/// four hide a dispersion of microns.
pub fn digits(v: f64, n: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let n = n.max(1) as i32;
    let trim = |s: &str| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s.to_string()
        }
    };
    // rounded first: its exponent after rounding (99999.96 to 6 digits is 1e5)
    let sci = format!("{v:.*e}", (n - 1) as usize);
    let (mantissa, exponent) = sci.split_once('e').expect("exponent form");
    let e: i32 = exponent.parse().expect("an exponent");
    if (-3..5).contains(&e) && n - 1 - e >= 0 {
        trim(&format!("{:.*}", (n - 1 - e) as usize, v))
    } else {
        format!("{}e{exponent}", trim(mantissa))
    }
}

/// A number with every digit it has (round-trips), compact: plain between 1e-4 and
/// 1e7, in exponent form otherwise (6378137, 3.986004418e14).
pub fn exact(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-4..1e7).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `v` with `decimals` digits after the point, or in exponent form (4 significant
/// digits) when it has more than nine digits before it: no 300-digit numbers.
pub fn fixed(v: f64, decimals: usize) -> String {
    if v.is_finite() && v.abs() >= 1e9 {
        num(v)
    } else {
        format!("{v:.decimals$}")
    }
}

/// Two numbers compared in one line ("12.345 µm < 12.346 µm"), each with the same
/// number of decimals, [`decimals_apart`].
pub fn apart(a: f64, b: f64, decimals: usize) -> (String, String) {
    let d = decimals_apart(a, b, decimals);
    (fixed(a, d), fixed(b, d))
}

/// The decimals that two numbers compared in one line need: at least `decimals`, more
/// (up to 12) while the two would print alike although they differ, so that a verdict
/// never reads "x < x".
pub fn decimals_apart(a: f64, b: f64, decimals: usize) -> usize {
    let mut d = decimals;
    // and their difference shows a digit that is not zero ("-0.0000")
    let zero = |d: usize| {
        fixed(a - b, d)
            .trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
    };
    while d < 12 && a != b && (fixed(a, d) == fixed(b, d) || zero(d)) {
        d += 1;
    }
    d
}

/// `v` followed by `unit`, plural unless v is 1: "1 orbit", "6 orbits", "1e300 orbits".
pub fn count(v: f64, unit: &str) -> String {
    if v == 1.0 {
        format!("1 {unit}")
    } else {
        format!("{} {unit}s", num(v))
    }
}

/// A number of orbits as a person writes it: "1 orbit", "6 orbits" when whole (to a
/// billionth), else with `decimals` digits ("0.50 orbits").
pub fn orbits(v: f64, decimals: usize) -> String {
    let r = snap_whole(v);
    if r.fract() == 0.0 {
        count(r, "orbit")
    } else {
        format!("{v:.decimals$} orbits")
    }
}

/// `v` as the whole number it is within a billionth of (a count of orbits computed as
/// a run's length over its period: 6 P / P can be 5.999999999999999), else as it is.
pub fn snap_whole(v: f64) -> f64 {
    let r = v.round();
    if v.is_finite() && (v - r).abs() <= 1e-9 * v.abs().max(1.0) {
        r
    } else {
        v
    }
}

/// Text from a file or the user as it may be shown on a terminal: control characters
/// (escape sequences, bells, carriage returns) written as `\u{1b}`, never sent raw.
pub fn shown(text: &str) -> std::borrow::Cow<'_, str> {
    shown_keeping(text, &[])
}

/// [`shown`], but the characters of `keep` (line ends, tabs) pass as they are: for a
/// whole report of many lines.
pub fn shown_keeping<'a>(text: &'a str, keep: &[char]) -> std::borrow::Cow<'a, str> {
    let escaped = |c: char| c.is_control() && !keep.contains(&c);
    if text.chars().any(escaped) {
        text.chars()
            .map(|c| {
                if escaped(c) {
                    c.escape_unicode().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect::<String>()
            .into()
    } else {
        text.into()
    }
}

/// A field name made of ASCII letters, digits and `_`, not starting with a digit.
pub fn identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect();
    if s.chars().next().is_none_or(|c| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

#[cfg(test)]
mod tests {
    use super::{apart, exact, num};

    #[test]
    fn core_exact_numbers() {
        assert_eq!(exact(6378137.0), "6378137");
        assert_eq!(exact(3.986004418e14), "3.986004418e14");
        assert_eq!(exact(0.002), "0.002");
        assert_eq!(exact(1.5e-5), "1.5e-5");
    }

    #[test]
    fn core_numbers_to_n_digits() {
        use super::digits;
        assert_eq!(digits(29.993712345, 6), "29.9937");
        assert_eq!(digits(1.111234567e-5, 6), "1.11123e-5");
        assert_eq!(digits(1393.0, 6), "1393");
        assert_eq!(digits(0.0347012, 6), "0.0347012");
        assert_eq!(digits(123456.7, 6), "1.23457e5");
        assert_eq!(digits(-0.5, 3), "-0.5");
        assert_eq!(digits(0.0, 6), "0");
        // fewer digits than the integer part has, and values that round up a decade
        assert_eq!(digits(12345.0, 3), "1.23e4");
        assert_eq!(digits(1393.0, 1), "1e3");
        assert_eq!(digits(99999.96, 6), "1e5");
        assert_eq!(digits(-99999.99, 6), "-1e5");
        assert_eq!(digits(99999.95, 6), "99999.9");
        assert_eq!(digits(9.9996, 4), "10");
        assert_eq!(digits(0.00099999, 6), "9.9999e-4");
    }

    #[test]
    fn core_numbers_for_messages() {
        assert_eq!(num(1e300), "1e300");
        assert_eq!(num(1.8564579906e10), "1.856e10");
        assert_eq!(num(1e-6), "1e-6");
        assert_eq!(num(0.001), "0.001");
        assert_eq!(num(300.0), "300");
        assert_eq!(num(-2.5e-7), "-2.5e-7");
    }

    #[test]
    fn core_two_numbers_compared_never_print_alike() {
        assert_eq!(apart(24.398, 24.4, 3), ("24.398".into(), "24.400".into()));
        assert_eq!(
            apart(10.0001, 10.0004, 3),
            ("10.0001".into(), "10.0004".into())
        );
        assert_eq!(apart(5.0, 5.0, 3), ("5.000".into(), "5.000".into()));
        // their difference shows a digit too (it read "-0.0000" for 5e-5)
        for (a, b) in [
            (24.39775, 24.3977505),
            (24.3977, 24.39775),
            (1.0, 1.0 + 1e-9),
        ] {
            let d = super::decimals_apart(a, b, 3);
            let diff = super::fixed(a - b, d);
            assert!(
                diff.chars().any(|c| ('1'..='9').contains(&c)),
                "{a} {b}: {diff}"
            );
            assert_ne!(super::fixed(a, d), super::fixed(b, d));
        }
    }
}

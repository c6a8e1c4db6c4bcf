//! Numerical helpers every domain may use (no physics, no files).

/// Linear interpolation in a strictly increasing abscissa, clamped at both ends.
pub fn interpolate(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    debug_assert_eq!(xs.len(), ys.len());
    let n = xs.len();
    if x.is_nan() {
        return f64::NAN;
    }
    if n == 1 || x <= xs[0] {
        return ys[0];
    }
    if x >= xs[n - 1] {
        return ys[n - 1];
    }
    let i = xs.partition_point(|&k| k <= x); // xs[i-1] <= x < xs[i]
    let (x0, x1, y0, y1) = (xs[i - 1], xs[i], ys[i - 1], ys[i]);
    y0 + (y1 - y0) * (x - x0) / (x1 - x0)
}

/// Golden-section search for the minimum of a unimodal `f` on [`lo`, `hi`], one
/// evaluation per iteration, until the bracket is at most `tol` wide (or after 60
/// iterations); returns the last bracket.
pub fn golden_section(
    mut lo: f64,
    mut hi: f64,
    tol: f64,
    f: &mut impl FnMut(f64) -> f64,
) -> (f64, f64) {
    const G: f64 = 0.618_033_988_749_895;
    let (mut x1, mut x2) = (hi - G * (hi - lo), lo + G * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..60 {
        if hi - lo <= tol {
            break;
        }
        if f1 < f2 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - G * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + G * (hi - lo);
            f2 = f(x2);
        }
    }
    (lo, hi)
}

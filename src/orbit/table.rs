//! Piecewise-linear tables of a quantity over mission time.

/// A quantity that is either constant or piecewise linear in time (held constant
/// outside the table). Knots are strictly increasing; the solver lands steps on them.
#[derive(Debug, Clone, PartialEq)]
pub enum Profile {
    Constant(f64),
    Table { time_s: Vec<f64>, value: Vec<f64> },
}

impl Profile {
    /// Value at time `t_s`.
    pub fn at(&self, t_s: f64) -> f64 {
        match self {
            Profile::Constant(v) => *v,
            Profile::Table { time_s, value } => interpolate(time_s, value, t_s),
        }
    }

    /// The knots where the slope may change (empty for a constant).
    pub fn knots_s(&self) -> &[f64] {
        match self {
            Profile::Constant(_) => &[],
            Profile::Table { time_s, .. } => time_s,
        }
    }

    /// Smallest and largest value the profile takes.
    pub fn range(&self) -> (f64, f64) {
        match self {
            Profile::Constant(v) => (*v, *v),
            Profile::Table { value, .. } => value
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                }),
        }
    }

    /// Applies `f` to every value (for unit conversion at the edge).
    pub fn map(self, f: impl Fn(f64) -> f64) -> Profile {
        match self {
            Profile::Constant(v) => Profile::Constant(f(v)),
            Profile::Table { time_s, value } => Profile::Table {
                time_s,
                value: value.into_iter().map(f).collect(),
            },
        }
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_table_interpolates_and_clamps() {
        let p = Profile::Table {
            time_s: vec![0.0, 10.0, 20.0],
            value: vec![1.0, 3.0, -1.0],
        };
        assert_eq!(p.at(-5.0), 1.0);
        assert_eq!(p.at(5.0), 2.0);
        assert_eq!(p.at(10.0), 3.0);
        assert_eq!(p.at(15.0), 1.0);
        assert_eq!(p.at(25.0), -1.0);
        assert_eq!(p.range(), (-1.0, 3.0));
    }
}

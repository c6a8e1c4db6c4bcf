//! Piecewise-linear tables of a quantity over mission time.

use crate::numeric::interpolate;

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

    /// Smallest and largest value the profile takes from `t0_s` to `t1_s`: at both
    /// ends and at the knots between (linear between knots, held outside them).
    pub fn range_over(&self, t0_s: f64, t1_s: f64) -> (f64, f64) {
        let inside = self
            .knots_s()
            .iter()
            .filter(|&&t| t > t0_s && t < t1_s)
            .map(|&t| self.at(t));
        [self.at(t0_s), self.at(t1_s)]
            .into_iter()
            .chain(inside)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
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
        assert_eq!(p.range_over(-10.0, 0.0), (p.at(-10.0), p.at(0.0)));
    }
}

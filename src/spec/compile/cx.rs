//! The compiler's checks of single values, each naming the key path it checks, and
//! the error they give.

use super::*;
use crate::spec::registry::Field;

/// A spec that does not make a valid model: the key path and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("`{key}`: {message}")]
pub struct SpecError {
    pub key: KeyPath,
    pub message: String,
    /// Another key the error concerns (the first of two that clash): its line is named
    /// too where the error is placed in the file.
    pub also: Option<KeyPath>,
}

/// The checks, each naming the key path it checks.
pub(crate) struct Cx;

impl Cx {
    /// An error at `path`.
    pub(super) fn err(&self, path: &KeyPath, message: impl Into<String>) -> SpecError {
        SpecError {
            key: path.clone(),
            message: message.into(),
            also: None,
        }
    }

    /// An error at `path` that clashes with `other` (two of one name).
    pub(super) fn clash(
        &self,
        path: &KeyPath,
        other: &KeyPath,
        message: impl Into<String>,
    ) -> SpecError {
        SpecError {
            key: path.clone(),
            message: message.into(),
            also: Some(other.clone()),
        }
    }

    pub(super) fn finite(&self, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(path, format!("must be a finite number (got {})", exact(v))))
        }
    }

    pub(super) fn positive(&self, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.err(path, format!("must be > 0 (got {})", exact(v))))
        }
    }

    /// A value > 0 and ≤ `hi` (a physically sensible upper bound, named in the error).
    pub(super) fn positive_up_to(
        &self,
        path: &KeyPath,
        v: f64,
        hi: f64,
        unit: &str,
    ) -> Result<f64, SpecError> {
        self.positive(path, v)?;
        if v <= hi {
            Ok(v)
        } else {
            Err(self.err(
                path,
                format!("must be at most {} {unit} (got {})", num(hi), exact(v)),
            ))
        }
    }

    /// A finite value ≥ `lo` (a physically sensible lower bound, named in the error).
    pub(super) fn at_least(
        &self,
        path: &KeyPath,
        v: f64,
        lo: f64,
        unit: &str,
    ) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        if v >= lo {
            Ok(v)
        } else {
            Err(self.err(
                path,
                format!("must be at least {} {unit} (got {})", num(lo), exact(v)),
            ))
        }
    }

    pub(super) fn non_negative(&self, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(self.err(path, format!("must be ≥ 0 (got {})", exact(v))))
        }
    }

    /// `v` checked by the rule of quantity `q` (see [`crate::spec::quantity`]), with its
    /// error text.
    pub(super) fn quantity(&self, q: &Quantity, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        match q.rule {
            Rule::Within { lo, hi, what } => self.within(path, v, lo, hi, what),
            Rule::Span {
                lo,
                hi,
                open,
                shown,
                got_unit,
            } => {
                self.finite(path, v)?;
                let inside = if open {
                    v > lo && v < hi
                } else {
                    (lo..=hi).contains(&v)
                };
                if inside {
                    Ok(v)
                } else {
                    // an open span's text shows its excluded ends ("−1 < … < 0.5")
                    let within = if open { "" } else { "within " };
                    Err(self.err(path, format!("must be {within}{shown} (got {v}{got_unit})")))
                }
            }
            Rule::Positive => self.positive(path, v),
            Rule::NonNegative => self.non_negative(path, v),
            Rule::PositiveUpTo { hi } => self.positive_up_to(path, v, hi, q.unit),
            Rule::PositiveAtLeast { lo, hi } => {
                let v = self.positive_up_to(path, v, hi, q.unit)?;
                self.at_least(path, v, lo, q.unit)
            }
            Rule::AtLeast { lo } => self.at_least(path, v, lo, q.unit),
            Rule::Temperature => self.temperature(path, v),
            Rule::InContext => self.finite(path, v),
        }
    }

    /// The value `v` of `field` in the table at `under`, checked by the field's quantity.
    pub(super) fn read(&self, field: &Field, under: &KeyPath, v: f64) -> Result<f64, SpecError> {
        self.quantity(field.quantity, &field.key(under), v)
    }

    /// An optional value of `field`, absent standing for its quantity's default.
    pub(super) fn read_or_default(
        &self,
        field: &Field,
        under: &KeyPath,
        v: Option<f64>,
    ) -> Result<f64, SpecError> {
        self.quantity_or_default(field.quantity, &field.key(under), v)
    }

    /// An optional value of quantity `q`, absent standing for the quantity's default,
    /// checked by its rule.
    pub(super) fn quantity_or_default(
        &self,
        q: &Quantity,
        path: &KeyPath,
        v: Option<f64>,
    ) -> Result<f64, SpecError> {
        self.quantity(q, path, v.unwrap_or(q.default_value()))
    }

    pub(super) fn within(
        &self,
        path: &KeyPath,
        v: f64,
        lo: f64,
        hi: f64,
        what: &str,
    ) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        if (lo..=hi).contains(&v) {
            Ok(v)
        } else {
            Err(self.err(
                path,
                format!(
                    "{what} must be within {} … {} (got {})",
                    num(lo),
                    num(hi),
                    exact(v)
                ),
            ))
        }
    }

    pub(super) fn temperature(&self, path: &KeyPath, v: f64) -> Result<f64, SpecError> {
        self.finite(path, v)?;
        use crate::constants::ZERO_CELSIUS_K;
        use crate::spec::quantity::MAX_TEMPERATURE_K;
        if v > 0.0 && v < MAX_TEMPERATURE_K {
            Ok(v)
        } else {
            Err(self.err(
                path,
                format!(
                    "is a temperature in kelvin and must be above 0 and below {MAX_TEMPERATURE_K} K (got {v}; °C values need + {ZERO_CELSIUS_K})"
                ),
            ))
        }
    }

    pub(super) fn profile(
        &self,
        path: &KeyPath,
        raw: ProfileSpec,
        check: &dyn Fn(&KeyPath, f64) -> Result<f64, SpecError>,
    ) -> Result<Profile, SpecError> {
        match raw {
            ProfileSpec::Constant(v) => Ok(Profile::Constant(check(path, v)?)),
            ProfileSpec::Table(t) => {
                use crate::spec::registry::{TIME_DAYS, TIME_S, VALUE};
                let (time_s, tkey) = match (t.time_s, t.time_days) {
                    (Some(s), None) => (s, TIME_S),
                    (None, Some(d)) => (
                        d.into_iter().map(|x| x * SECONDS_PER_DAY).collect(),
                        TIME_DAYS,
                    ),
                    _ => {
                        return Err(self.err(
                            path,
                            format!("a table needs exactly one of `{TIME_S}` or `{TIME_DAYS}`"),
                        ));
                    }
                };
                let tpath = path.key(tkey);
                if time_s.is_empty() {
                    return Err(self.err(&tpath, "must not be empty"));
                }
                if time_s.len() != t.value.len() {
                    return Err(self.err(
                        &path.key(VALUE),
                        format!(
                            "has {} entries but `{tkey}` has {}",
                            t.value.len(),
                            time_s.len()
                        ),
                    ));
                }
                for (i, w) in time_s.windows(2).enumerate() {
                    self.finite(&tpath.at(i + 1), w[1])?;
                    if w[1] <= w[0] {
                        return Err(self.err(
                            &tpath.at(i + 1),
                            format!(
                                "times must increase strictly (entry {} is not after entry {i})",
                                i + 1
                            ),
                        ));
                    }
                }
                self.finite(&tpath.at(0), time_s[0])?;
                let mut value = Vec::with_capacity(t.value.len());
                for (i, v) in t.value.into_iter().enumerate() {
                    value.push(check(&path.key(VALUE).at(i), v)?);
                }
                Ok(Profile::Table { time_s, value })
            }
        }
    }

    /// An area product in the element at `path`: `product` or both a `fraction` and the
    /// area (their product), never both forms; each value read through its field.
    pub(super) fn product(
        &self,
        path: &KeyPath,
        product: (Option<f64>, &Field),
        fraction: (Option<f64>, &Field),
        area: Option<f64>,
    ) -> Result<f64, SpecError> {
        let area_field = &crate::spec::registry::AREA_M2;
        match (product.0, fraction.0, area) {
            (Some(p), None, None) => self.read(product.1, path, p),
            (None, Some(x), Some(y)) => {
                let x = self.read(fraction.1, path, x)?;
                let y = self.read(area_field, path, y)?;
                Ok(x * y)
            }
            _ => Err(self.err(
                path,
                format!(
                    "give either `{}` or both `{}` and `{}`",
                    product.1.name, fraction.1.name, area_field.name
                ),
            )),
        }
    }
}

//! Dispersions: which numbers of a scenario scatter in a Monte Carlo margin check, how,
//! and the values of sample k.
//!
//! Each `[[dispersion]]` names a number by its key path and gives it a distribution
//! (normal, truncated normal, uniform, triangular, log-normal, or a list of equally
//! likely cases). Dispersions with the same `group` draw one quantile per sample
//! between them (one material lot: rank correlation 1). A sample's quantiles depend only
//! on (seed, sample index): each sample has its own ChaCha12 stream, and Latin
//! hypercube strata come from per-dimension permutations seeded by the seed alone, so
//! any thread count and any sharding give the same numbers.
//!
//! Before any sample runs, [`Plan::new`] checks every path, every distribution's
//! parameters, and that the distribution stays within the parameter's valid range (the
//! bounds of bounded ones, the 1e-7 and 1 − 1e-7 quantiles of normal and log-normal
//! ones, every case), by writing those values into a copy of the model: the error
//! names the `dispersion` entry and says which value the model refused and why.

use rand_chacha::ChaCha12Rng;
use rand_chacha::rand_core::{Rng, SeedableRng};
use statrs::distribution::{ContinuousCDF, Normal};

use crate::spec::DispersionSpec;
use crate::spec::compile::SpecError;
use crate::spec::keys::KeyPath;
use crate::spec::model::{Model, ModelError, ParamId};

/// The most samples a plan holds (its Latin hypercube keeps a stratum per sample and
/// dimension; a margins run reports every sample).
pub const MAX_SAMPLES: u64 = 10_000_000;

/// Why a plan cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// A `[[dispersion]]` entry is wrong (the key path names the entry).
    #[error(transparent)]
    Spec(#[from] SpecError),
    #[error("{samples} samples: a plan holds 1 … {MAX_SAMPLES}")]
    Samples { samples: u64 },
}

/// The tails a normal or log-normal distribution must keep inside the parameter's
/// range: 1 in 10⁷ on each side (±5.2 σ).
pub const TAIL: f64 = 1e-7;

/// A distribution, by its quantile function.
#[derive(Debug, Clone, PartialEq)]
pub enum Distribution {
    Normal {
        mean: f64,
        sd: f64,
    },
    TruncatedNormal {
        mean: f64,
        sd: f64,
        min: f64,
        max: f64,
    },
    Uniform {
        min: f64,
        max: f64,
    },
    Triangular {
        min: f64,
        mode: f64,
        max: f64,
    },
    /// ln x ~ N(ln median, σ²).
    LogNormal {
        median: f64,
        sigma: f64,
    },
    /// Equally likely values.
    Cases(Vec<f64>),
}

fn std_normal() -> Normal {
    Normal::new(0.0, 1.0).expect("the standard normal")
}

impl Distribution {
    /// The value at quantile `u` in (0, 1).
    pub fn quantile(&self, u: f64) -> f64 {
        match self {
            Distribution::Normal { mean, sd } => mean + sd * std_normal().inverse_cdf(u),
            Distribution::TruncatedNormal { mean, sd, min, max } => {
                let z = truncated_std_normal((min - mean) / sd, (max - mean) / sd, u);
                (mean + sd * z).clamp(*min, *max)
            }
            Distribution::Uniform { min, max } => min + u * (max - min),
            Distribution::Triangular { min, mode, max } => {
                let f = (mode - min) / (max - min);
                if u < f {
                    min + (u * (max - min) * (mode - min)).sqrt()
                } else {
                    max - ((1.0 - u) * (max - min) * (max - mode)).sqrt()
                }
            }
            Distribution::LogNormal { median, sigma } => {
                median * (sigma * std_normal().inverse_cdf(u)).exp()
            }
            Distribution::Cases(v) => v[((u * v.len() as f64) as usize).min(v.len() - 1)],
        }
    }

    /// The values a draw can take: a bounded distribution's bounds, an unbounded one's
    /// quantiles at 1e-12 and 1 − 1e-12 (no sampling plan draws further out).
    pub fn support(&self) -> (f64, f64) {
        // the farthest any draw reaches: u = 2^-54 (half an ulp of 1) and its mirror
        let z = -std_normal().inverse_cdf(f64::EPSILON / 4.0);
        match self {
            Distribution::Normal { mean, sd } => (mean - z * sd, mean + z * sd),
            Distribution::LogNormal { median, sigma } => {
                (median * (-z * sigma).exp(), median * (z * sigma).exp())
            }
            Distribution::TruncatedNormal { min, max, .. }
            | Distribution::Uniform { min, max }
            | Distribution::Triangular { min, max, .. } => (*min, *max),
            Distribution::Cases(v) => v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(*x), b.max(*x))
                }),
        }
    }

    /// The values that must lie within the parameter's range.
    fn extremes(&self) -> Vec<f64> {
        match self {
            Distribution::Normal { .. } | Distribution::LogNormal { .. } => {
                vec![self.quantile(TAIL), self.quantile(1.0 - TAIL)]
            }
            Distribution::TruncatedNormal { min, max, .. }
            | Distribution::Uniform { min, max }
            | Distribution::Triangular { min, max, .. } => vec![*min, *max],
            Distribution::Cases(v) => v.clone(),
        }
    }
}

impl std::fmt::Display for Distribution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use crate::units::exact;
        match self {
            Distribution::Normal { mean, sd } => {
                write!(f, "normal, mean {}, sd {}", exact(*mean), exact(*sd))
            }
            Distribution::TruncatedNormal { mean, sd, min, max } => write!(
                f,
                "truncated normal, mean {}, sd {}, {} … {}",
                exact(*mean),
                exact(*sd),
                exact(*min),
                exact(*max)
            ),
            Distribution::Uniform { min, max } => {
                write!(f, "uniform, {} … {}", exact(*min), exact(*max))
            }
            Distribution::Triangular { min, mode, max } => write!(
                f,
                "triangular, {} … {} … {}",
                exact(*min),
                exact(*mode),
                exact(*max)
            ),
            Distribution::LogNormal { median, sigma } => {
                write!(
                    f,
                    "log-normal, median {}, σ(ln) {}",
                    exact(*median),
                    exact(*sigma)
                )
            }
            Distribution::Cases(v) => write!(
                f,
                "cases {}",
                v.iter().map(|x| exact(*x)).collect::<Vec<_>>().join(", ")
            ),
        }
    }
}

/// ln Φ̄(z) = ln P(Z > z) for the standard normal, accurate for every z: from erfc
/// up to z = 5, beyond that from the Mills ratio R(z) = Φ̄(z)/φ(z) by its continued
/// fraction R = 1/(z + 1/(z + 2/(z + 3/(z + …)))) (no underflow: Φ̄(40) ≈ 4e-350).
pub fn ln_upper_tail(z: f64) -> f64 {
    if z < 5.0 {
        (0.5 * statrs::function::erf::erfc(z / std::f64::consts::SQRT_2)).ln()
    } else {
        let mut t = z;
        for k in (1..=80).rev() {
            t = z + k as f64 / t;
        }
        -0.5 * z * z - 0.5 * (2.0 * std::f64::consts::PI).ln() - t.ln()
    }
}

/// The u-quantile of the standard normal restricted to [a, b] (a < b). Where the
/// interval lies in one tail, the inverse is taken on ln Φ̄ (upper tail; the lower by
/// symmetry), so bounds tens of σ from the mean still spread the samples over the
/// interval instead of piling them on a bound.
pub fn truncated_std_normal(a: f64, b: f64, u: f64) -> f64 {
    if b <= 0.0 {
        return -truncated_std_normal(-b, -a, 1.0 - u);
    }
    if a < 0.0 {
        // the interval holds the mode: the plain CDF has no cancellation to fear
        let n = std_normal();
        let (pa, pb) = (n.cdf(a), n.cdf(b));
        return n.inverse_cdf(pa + u * (pb - pa)).clamp(a, b);
    }
    // 0 ≤ a < b: solve ln Φ̄(x) = ln(Φ̄(a) − u (Φ̄(a) − Φ̄(b))), in logs
    let (la, lb) = (ln_upper_tail(a), ln_upper_tail(b));
    let target = la + (-u * -(lb - la).exp_m1()).ln_1p();
    // ln Φ̄ falls strictly: Newton steps kept inside a shrinking bracket [lo, hi]
    let (mut lo, mut hi) = (a, b);
    let mut x = a;
    for _ in 0..200 {
        let f = ln_upper_tail(x) - target;
        if f > 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        // d/dx ln Φ̄(x) = −φ(x)/Φ̄(x)
        let ln_phi = -0.5 * x * x - 0.5 * (2.0 * std::f64::consts::PI).ln();
        let slope = -(ln_phi - ln_upper_tail(x)).exp();
        let mut next = x - f / slope;
        if !(next > lo && next < hi && next.is_finite()) {
            next = 0.5 * (lo + hi);
        }
        if (next - x).abs() <= 1e-15 * x.abs().max(1.0) || hi - lo <= 1e-15 * hi.abs() {
            return next.clamp(a, b);
        }
        x = next;
    }
    x.clamp(a, b)
}

/// How the samples cover the quantiles. Serialised (margins reports, shards) as
/// "random" or "latin_hypercube".
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    /// Independent draws.
    Random,
    /// Latin hypercube: each dimension's N quantiles fall one in each of N strata.
    LatinHypercube,
}

impl Sampling {
    pub fn as_str(self) -> &'static str {
        match self {
            Sampling::Random => "random",
            Sampling::LatinHypercube => "latin_hypercube",
        }
    }
}

impl std::fmt::Display for Sampling {
    /// As serialised; honours width and alignment.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.as_str())
    }
}

/// A dispersed number, checked.
#[derive(Debug, Clone)]
pub struct Dispersion {
    pub path: String,
    pub id: ParamId,
    pub distribution: Distribution,
    pub group: Option<String>,
    /// The quantile dimension it draws from (shared within a group).
    pub dimension: usize,
}

/// The dispersions of a scenario and the draws of every sample.
#[derive(Debug, Clone)]
pub struct Plan {
    pub dispersions: Vec<Dispersion>,
    pub sampling: Sampling,
    pub samples: u64,
    pub seed: u64,
    dimensions: usize,
    /// Latin hypercube: per dimension, the stratum of each sample.
    strata: Vec<Vec<u32>>,
}

fn err(key: KeyPath, message: impl Into<String>) -> SpecError {
    SpecError {
        key,
        message: message.into(),
        also: None,
    }
}

impl Plan {
    /// Checks `specs` against `model` (see the module docs) and prepares `samples`
    /// samples from `seed`.
    pub fn new(
        model: &Model,
        specs: &[DispersionSpec],
        sampling: Sampling,
        samples: u64,
        seed: u64,
    ) -> Result<Plan, PlanError> {
        if !(1..=MAX_SAMPLES).contains(&samples) {
            return Err(PlanError::Samples { samples });
        }
        let mut dispersions = Vec::new();
        let mut groups: Vec<String> = Vec::new();
        let mut dimensions = 0;
        for (i, d) in specs.iter().enumerate() {
            let at = KeyPath::new("dispersion").at(i);
            let id = model
                .param(&d.path)
                .map_err(|e| err(at.key("path"), e.to_string()))?;
            if let Some(why) = id.not_of_the_model() {
                return Err(err(at.key("path"), why).into());
            }
            let nominal = model
                .get(&d.path)
                .map_err(|e| err(at.key("path"), e.to_string()))?;
            let distribution = distribution(d, nominal, &at)?;
            let dimension = match &d.group {
                Some(g) => match groups.iter().position(|x| x == g) {
                    Some(k) => dispersions
                        .iter()
                        .find(|x: &&Dispersion| x.group.as_deref() == Some(groups[k].as_str()))
                        .map(|x| x.dimension)
                        .expect("a group's first member"),
                    None => {
                        groups.push(g.clone());
                        dimensions += 1;
                        dimensions - 1
                    }
                },
                None => {
                    dimensions += 1;
                    dimensions - 1
                }
            };
            // the same number however it is spelled (`node."housing"`, `node . housing`)
            if let Some((j, x)) = dispersions
                .iter()
                .enumerate()
                .find(|(_, x): &(usize, &Dispersion)| x.id.same_number(&id))
            {
                return Err(PlanError::Spec(err(
                    at.key("path"),
                    format!(
                        "`{}` names the same number ({}) as dispersion[{j}] (`{}`): one number has one distribution",
                        d.path,
                        id.canonical_path(),
                        x.path
                    ),
                )));
            }
            dispersions.push(Dispersion {
                path: d.path.clone(),
                id,
                distribution,
                group: d.group.clone(),
                dimension,
            });
        }
        // Within each parameter's range: the model itself says. A value refused beside
        // the other numbers' nominal values (a heater's on_k above the nominal off_k)
        // may be possible beside their dispersed ones: it is tried again with the other
        // dispersed numbers at their lower, then at their upper extremes. Combinations
        // the model refuses at run time are reported as invalid samples.
        for (i, (d, x)) in specs.iter().zip(&dispersions).enumerate() {
            let at = KeyPath::new("dispersion").at(i);
            for v in x.distribution.extremes() {
                let mut probe = model.clone();
                let Err(e) = probe.set_param(&x.id, v) else {
                    continue;
                };
                let possible = [false, true].iter().any(|&upper| {
                    let mut probe = model.clone();
                    let mut values: Vec<(&ParamId, f64)> = dispersions
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != i)
                        .filter_map(|(_, o)| {
                            let ex = o.distribution.extremes();
                            let pick = if upper { ex.last() } else { ex.first() };
                            pick.map(|&w| (&o.id, w))
                        })
                        .collect();
                    values.push((&x.id, v));
                    set_in_any_order(&mut probe, &values).is_ok()
                });
                if possible {
                    continue;
                }
                let why = match e {
                    ModelError::Param(e) => e.to_string(),
                    ModelError::Invalid(e) => format!("`{}`: {}", e.key, e.message),
                };
                let tail = match x.distribution {
                    Distribution::Normal { .. } | Distribution::LogNormal { .. } => {
                        format!(" (at its {TAIL:e} tail; truncated_normal bounds it)")
                    }
                    _ => String::new(),
                };
                return Err(PlanError::Spec(err(
                    at,
                    format!(
                        "{} reaches {}{tail}, which `{}` cannot take: {why}",
                        d.distribution,
                        crate::units::num(v),
                        d.path
                    ),
                )));
            }
        }
        let strata = match sampling {
            Sampling::Random => Vec::new(),
            Sampling::LatinHypercube => (0..dimensions)
                .map(|d| permutation(seed, d as u64, samples))
                .collect(),
        };
        Ok(Plan {
            dispersions,
            sampling,
            samples,
            seed,
            dimensions,
            strata,
        })
    }

    /// The quantile of every dimension for sample `k` (0-based), each in (0, 1); `None`
    /// when the plan has no sample `k` (k ≥ samples).
    pub fn quantiles(&self, k: u64) -> Option<Vec<f64>> {
        if k >= self.samples {
            return None;
        }
        let mut rng = ChaCha12Rng::seed_from_u64(self.seed);
        rng.set_stream(k);
        let unit = |x: u64| ((x >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
        Some(
            (0..self.dimensions)
                .map(|d| {
                    let u = unit(rng.next_u64());
                    match self.sampling {
                        Sampling::Random => u,
                        Sampling::LatinHypercube => {
                            (self.strata[d][k as usize] as f64 + u) / self.samples as f64
                        }
                    }
                })
                .collect(),
        )
    }

    /// The value of every dispersion for sample `k`, in the order of `dispersions`;
    /// `None` when the plan has no sample `k`.
    pub fn values(&self, k: u64) -> Option<Vec<f64>> {
        let u = self.quantiles(k)?;
        Some(
            self.dispersions
                .iter()
                .map(|d| d.distribution.quantile(u[d.dimension]))
                .collect(),
        )
    }

    /// The dispersion of the number `id` names, however spelled.
    pub fn dispersion_of(&self, id: &ParamId) -> Option<(usize, &Dispersion)> {
        self.dispersions
            .iter()
            .enumerate()
            .find(|(_, d)| d.id.same_number(id))
    }

    /// Writes sample `k`'s values into `model` (a copy of the nominal one).
    pub fn apply(&self, model: &mut Model, k: u64) -> Result<Vec<f64>, SampleError> {
        let values = self.values(k).ok_or(SampleError::NoSuchSample {
            index: k,
            samples: self.samples,
        })?;
        let pairs: Vec<(&ParamId, f64)> = self
            .dispersions
            .iter()
            .zip(&values)
            .map(|(d, v)| (&d.id, *v))
            .collect();
        set_in_any_order(model, &pairs).map_err(|(i, source)| SampleError::Model {
            index: k,
            path: self.dispersions[i].path.clone(),
            value: values[i],
            source,
        })?;
        Ok(values)
    }
}

/// Writes `values` into `model`. A value may be refused beside the current value of
/// another number and accepted beside its new one (a heater's on_k above the old
/// off_k, off_k raised too): values refused are tried again after the others, until
/// none goes in; then the first refusal (its index in `values`) is the error.
fn set_in_any_order(
    model: &mut Model,
    values: &[(&ParamId, f64)],
) -> Result<(), (usize, ModelError)> {
    let mut pending: Vec<usize> = (0..values.len()).collect();
    loop {
        let mut refused = Vec::new();
        let mut first_error = None;
        for &i in &pending {
            if let Err(e) = model.set_param(values[i].0, values[i].1) {
                refused.push(i);
                first_error.get_or_insert((i, e));
            }
        }
        match first_error {
            None => return Ok(()),
            Some(e) if refused.len() == pending.len() => return Err(e),
            Some(_) => pending = refused,
        }
    }
}

/// Why sample k cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum SampleError {
    #[error("there is no sample {index}: the plan has {samples} (0 … {})", samples - 1)]
    NoSuchSample { index: u64, samples: u64 },
    #[error("sample {index}: {path} = {}: {source}", crate::units::exact(*value))]
    Model {
        index: u64,
        path: String,
        value: f64,
        #[source]
        source: ModelError,
    },
}

/// A random permutation of 0 … n−1 for dimension `d` (Fisher–Yates on its own stream).
fn permutation(seed: u64, d: u64, n: u64) -> Vec<u32> {
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    rng.set_stream(u64::MAX - d);
    // n ≤ MAX_SAMPLES < 2³², checked by `Plan::new`
    let n = u32::try_from(n).expect("n ≤ MAX_SAMPLES");
    let mut p: Vec<u32> = (0..n).collect();
    for i in (1..p.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        p.swap(i, j);
    }
    p
}

fn distribution(d: &DispersionSpec, nominal: f64, at: &KeyPath) -> Result<Distribution, SpecError> {
    let need = |v: Option<f64>, key: &'static str| {
        v.ok_or_else(|| err(at.key(key), format!("`{}` needs `{key}`", d.distribution)))
            .and_then(|x| {
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(err(at.key(key), "must be a finite number"))
                }
            })
    };
    let positive = |v: f64, key: &'static str| {
        if v > 0.0 {
            Ok(v)
        } else {
            Err(err(at.key(key), format!("must be > 0 (got {v})")))
        }
    };
    let ordered = |min: f64, max: f64| {
        if min < max {
            Ok(())
        } else {
            Err(err(
                at.key("max"),
                format!("must be above min ({min}), got {max}"),
            ))
        }
    };
    // Each distribution's keys; any other key given is an error naming it.
    use crate::spec::DistributionName as D;
    let allowed: &[&str] = match d.distribution {
        D::Normal => &["mean", "sd"],
        D::TruncatedNormal => &["mean", "sd", "min", "max"],
        D::Uniform => &["min", "max"],
        D::Triangular => &["min", "max", "mode"],
        D::Lognormal => &["median", "sigma"],
        D::Cases => &["values"],
    };
    let given = [
        ("mean", d.mean.is_some()),
        ("sd", d.sd.is_some()),
        ("min", d.min.is_some()),
        ("max", d.max.is_some()),
        ("mode", d.mode.is_some()),
        ("median", d.median.is_some()),
        ("sigma", d.sigma.is_some()),
        ("values", d.values.is_some()),
    ];
    if let Some((k, _)) = given.iter().find(|(k, g)| *g && !allowed.contains(k)) {
        return Err(err(
            at.key(k),
            format!("is not a parameter of `{}`", d.distribution),
        ));
    }
    Ok(match d.distribution {
        D::Normal => Distribution::Normal {
            mean: need(d.mean.or(Some(nominal)), "mean")?,
            sd: positive(need(d.sd, "sd")?, "sd")?,
        },
        D::TruncatedNormal => {
            let (min, max) = (need(d.min, "min")?, need(d.max, "max")?);
            ordered(min, max)?;
            Distribution::TruncatedNormal {
                mean: need(d.mean.or(Some(nominal)), "mean")?,
                sd: positive(need(d.sd, "sd")?, "sd")?,
                min,
                max,
            }
        }
        D::Uniform => {
            let (min, max) = (need(d.min, "min")?, need(d.max, "max")?);
            ordered(min, max)?;
            Distribution::Uniform { min, max }
        }
        D::Triangular => {
            let (min, max) = (need(d.min, "min")?, need(d.max, "max")?);
            ordered(min, max)?;
            let mode = need(d.mode.or(Some(nominal)), "mode")?;
            if !(min..=max).contains(&mode) {
                return Err(err(
                    at.key("mode"),
                    format!("must lie within min … max ({min} … {max}), got {mode}"),
                ));
            }
            Distribution::Triangular { min, mode, max }
        }
        D::Lognormal => Distribution::LogNormal {
            median: positive(need(d.median.or(Some(nominal)), "median")?, "median")?,
            sigma: positive(need(d.sigma, "sigma")?, "sigma")?,
        },
        D::Cases => {
            let v = d.values.clone().unwrap_or_default();
            if v.is_empty() || v.iter().any(|x| !x.is_finite()) {
                return Err(err(
                    at.key("values"),
                    "`cases` needs a non-empty list of finite values",
                ));
            }
            Distribution::Cases(v)
        }
    })
}

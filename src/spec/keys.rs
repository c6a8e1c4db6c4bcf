//! Key paths: how a value of a scenario is named, in errors, in `orbitlash params` and
//! in `--set`.
//!
//! A path follows the TOML keys, with the elements of arrays of tables named by their
//! key rather than their position: `node.housing.capacitance_j_per_k`,
//! `environment.beta_deg`, `gear_pair.mesh.pinion.tooth_thinning_um`,
//! `conductor.housing-bus.conductance_w_per_k`. A key holding anything but letters,
//! digits, `_` and `-` is quoted as in TOML: `node."gear1.r2".capacitance_j_per_k`.
//! Arrays of numbers take an index: `environment.beta_deg.value[1]`.
//!
//! Element keys ([`element_keys`]): nodes, boundaries, modes by their name; gear pairs by
//! their name (default `mesh`, `mesh1`, …); conductors and radiative links by their
//! `name`, else `<a>-<b>` from the nodes they join; loads (`sun`, `albedo`, `earth_ir`,
//! `dissipation`) and heaters by their `name`, else their node; a key that repeats
//! within its array gets `-2`, `-3`, … in order.

use std::fmt;

use super::ScenarioSpec;

/// One step of a key path.
#[derive(Debug, Clone, PartialEq)]
pub enum Seg {
    /// A key of a table.
    K(&'static str),
    /// An index into an array of numbers (or of tables whose element has no key).
    I(usize),
    /// An element of an array of tables: its position and its key.
    E(usize, std::sync::Arc<str>),
}

/// A key path into a scenario, e.g. `node.motor.capacitance_j_per_k`.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyPath(pub Vec<Seg>);

impl KeyPath {
    pub fn new(k: &'static str) -> KeyPath {
        KeyPath(vec![Seg::K(k)])
    }
    /// This path and one more step, in one allocation.
    fn with(&self, seg: Seg) -> KeyPath {
        let mut v = Vec::with_capacity(self.0.len() + 1);
        v.extend_from_slice(&self.0);
        v.push(seg);
        KeyPath(v)
    }
    pub fn at(&self, i: usize) -> KeyPath {
        self.with(Seg::I(i))
    }
    /// The element at position `i` with key `key`.
    pub fn elem(&self, i: usize, key: &str) -> KeyPath {
        self.with(Seg::E(i, key.into()))
    }
    pub fn key(&self, k: &'static str) -> KeyPath {
        self.with(Seg::K(k))
    }
}

/// A key as it is written in a path: bare when it is letters, digits, `_` and `-`,
/// quoted otherwise.
pub fn quote_key(key: &str) -> String {
    let bare = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        key.to_string()
    } else {
        format!("\"{}\"", key.replace('\\', "\\\\").replace('"', "\\\""))
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (n, s) in self.0.iter().enumerate() {
            match s {
                Seg::K(k) if n == 0 => write!(f, "{k}")?,
                Seg::K(k) => write!(f, ".{k}")?,
                Seg::I(i) => write!(f, "[{i}]")?,
                Seg::E(_, key) => write!(f, ".{}", quote_key(key))?,
            }
        }
        Ok(())
    }
}

/// A key path as a user typed it: keys (bare or quoted) and indices.
#[derive(Debug, Clone, PartialEq)]
pub enum Part {
    Key(String),
    Index(usize),
}

/// Splits `node."gear1.r2".capacitance_j_per_k` or `environment.beta_deg.value[1]` into
/// its parts.
pub fn parse_path(text: &str) -> Result<Vec<Part>, String> {
    let mut parts = Vec::new();
    let mut chars = text.chars().peekable();
    let mut expect_key = true;
    while let Some(&c) = chars.peek() {
        match c {
            '.' if !expect_key => {
                chars.next();
                expect_key = true;
            }
            '[' => {
                chars.next();
                let mut digits = String::new();
                for d in chars.by_ref() {
                    if d == ']' {
                        break;
                    }
                    digits.push(d);
                }
                let i = digits
                    .trim()
                    .parse()
                    .map_err(|_| format!("`[{digits}]` is not an index"))?;
                parts.push(Part::Index(i));
                expect_key = false;
            }
            '"' if expect_key => {
                chars.next();
                let mut key = String::new();
                let mut closed = false;
                while let Some(d) = chars.next() {
                    match d {
                        '\\' => {
                            if let Some(e) = chars.next() {
                                key.push(e);
                            }
                        }
                        '"' => {
                            closed = true;
                            break;
                        }
                        _ => key.push(d),
                    }
                }
                if !closed {
                    return Err("a quoted key is not closed".into());
                }
                parts.push(Part::Key(key));
                expect_key = false;
            }
            _ if expect_key => {
                let mut key = String::new();
                while let Some(&d) = chars.peek() {
                    if d == '.' || d == '[' {
                        break;
                    }
                    key.push(d);
                    chars.next();
                }
                if key.is_empty() {
                    return Err("an empty key".into());
                }
                parts.push(Part::Key(key.trim().to_string()));
                expect_key = false;
            }
            _ => return Err(format!("unexpected `{c}`")),
        }
    }
    if parts.is_empty() || expect_key {
        return Err("the path is empty or ends with `.`".into());
    }
    Ok(parts)
}

/// The keys of every element of every array of tables, in the order of the spec.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ElementKeys {
    pub node: Vec<String>,
    pub boundary: Vec<String>,
    pub conductor: Vec<String>,
    pub radiation: Vec<String>,
    pub sun: Vec<String>,
    pub albedo: Vec<String>,
    pub earth_ir: Vec<String>,
    pub dissipation: Vec<String>,
    pub heater: Vec<String>,
    pub mode: Vec<String>,
    pub sensor: Vec<String>,
    pub gear_pair: Vec<String>,
    pub face: Vec<String>,
}

impl ElementKeys {
    /// The keys of the array of tables `section` (`heater`, `sun`, …), if it is one.
    pub fn section(&self, section: &str) -> Option<&[String]> {
        Some(match section {
            "node" => &self.node,
            "boundary" => &self.boundary,
            "conductor" => &self.conductor,
            "radiation" => &self.radiation,
            "sun" => &self.sun,
            "albedo" => &self.albedo,
            "earth_ir" => &self.earth_ir,
            "dissipation" => &self.dissipation,
            "heater" => &self.heater,
            "mode" => &self.mode,
            "sensor" => &self.sensor,
            "gear_pair" => &self.gear_pair,
            "face" => &self.face,
            _ => return None,
        })
    }
}

/// Makes keys unique within their array: the second `a` becomes `a-2`, and so on.
fn unique(keys: impl Iterator<Item = String>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for k in keys {
        let mut key = k.clone();
        let mut n = 2;
        while out.contains(&key) {
            key = format!("{k}-{n}");
            n += 1;
        }
        out.push(key);
    }
    out
}

/// The name of face `i` on `node` when none is given: `<node>.face<i>`.
pub fn face_name(node: &str, i: usize) -> String {
    format!("{node}.face{i}")
}

/// The key of element `i` of the array of tables `section` (None for another array),
/// from its fields: `field(k)` is its string field `k` (`name`, `node`, `column`),
/// `between` a link's two nodes. Its `name`, else the default of its kind (see the
/// module docs), before [`element_keys`] makes repeated keys unique. The TOML reader
/// names elements by it too, so that every error names an element one way.
pub fn element_key(
    section: &str,
    i: usize,
    field: &dyn Fn(&str) -> Option<String>,
    between: Option<Vec<String>>,
) -> Option<String> {
    let named = field("name");
    match section {
        "node" | "boundary" | "mode" => named,
        "conductor" | "radiation" => named.or_else(|| between.map(|b| b.join("-"))),
        "sun" | "albedo" | "earth_ir" | "dissipation" | "heater" => named.or_else(|| field("node")),
        "sensor" => named.or_else(|| field("column").map(|c| sensor_name_of(&c))),
        "face" => named.or_else(|| field("node").map(|n| face_name(&n, i))),
        "gear_pair" => Some(named.unwrap_or_else(|| {
            if i == 0 {
                "mesh".to_string()
            } else {
                format!("mesh{i}")
            }
        })),
        _ => None,
    }
}

/// The element keys of `spec` (see the module docs).
pub fn element_keys(spec: &ScenarioSpec) -> ElementKeys {
    fn keys<T>(
        section: &str,
        items: &[T],
        field: impl Fn(&T, &str) -> Option<String>,
        between: impl Fn(&T) -> Option<Vec<String>>,
    ) -> Vec<String> {
        unique(items.iter().enumerate().map(|(i, x)| {
            element_key(section, i, &|k| field(x, k), between(x)).expect("an array of tables")
        }))
    }
    fn none<T>(_: &T) -> Option<Vec<String>> {
        None
    }
    let link = |name: &Option<String>, k: &str| (k == "name").then(|| name.clone()).flatten();
    let loaded = |name: &Option<String>, node: &str, k: &str| match k {
        "name" => name.clone(),
        "node" => Some(node.to_string()),
        _ => None,
    };
    let named = |name: &str, k: &str| (k == "name").then(|| name.to_string());
    ElementKeys {
        node: keys("node", &spec.node, |n, k| named(&n.name, k), none),
        boundary: keys("boundary", &spec.boundary, |b, k| named(&b.name, k), none),
        conductor: keys(
            "conductor",
            &spec.conductor,
            |c, k| link(&c.name, k),
            |c| Some(c.between.clone()),
        ),
        radiation: keys(
            "radiation",
            &spec.radiation,
            |c, k| link(&c.name, k),
            |c| Some(c.between.clone()),
        ),
        sun: keys("sun", &spec.sun, |l, k| loaded(&l.name, &l.node, k), none),
        albedo: keys(
            "albedo",
            &spec.albedo,
            |l, k| loaded(&l.name, &l.node, k),
            none,
        ),
        earth_ir: keys(
            "earth_ir",
            &spec.earth_ir,
            |l, k| loaded(&l.name, &l.node, k),
            none,
        ),
        dissipation: keys(
            "dissipation",
            &spec.dissipation,
            |l, k| loaded(&l.name, &l.node, k),
            none,
        ),
        heater: keys(
            "heater",
            &spec.heater,
            |l, k| loaded(&l.name, &l.node, k),
            none,
        ),
        mode: keys("mode", &spec.mode, |m, k| named(&m.name, k), none),
        face: keys("face", &spec.face, |f, k| loaded(&f.name, &f.node, k), none),
        sensor: keys(
            "sensor",
            &spec.sensor,
            |x, k| match k {
                "name" => x.name.clone(),
                "column" => Some(x.column.clone()),
                _ => None,
            },
            none,
        ),
        gear_pair: keys(
            "gear_pair",
            &spec.gear_pair,
            |g, k| (k == "name").then(|| g.name.clone()).flatten(),
            none,
        ),
    }
}

// ---------------------------------------------------------------- names

/// Longest name of a scenario, node, boundary, load, heater, mode or gear pair.
pub const MAX_NAME_LEN: usize = 100;

/// Checks a name given in a scenario: 1 … 100 characters from `A–Z a–z 0–9 _ - .`,
/// beginning with a letter, a digit or `_`. Names become file names (the default log
/// `logs/<scenario>.mcap`), log field names and key paths, so nothing that could leave
/// a folder (`/`, `..`) or break a CSV header (`,`, spaces) gets in.
pub fn check_name(name: &str) -> Result<(), String> {
    let first_ok = name
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
    let rest_ok = name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    if name.is_empty() {
        Err("must not be empty".into())
    } else if name.len() > MAX_NAME_LEN {
        Err(format!("is longer than {MAX_NAME_LEN} characters"))
    } else if !(first_ok && rest_ok) {
        Err(format!(
            "{name:?} is not a valid name: use letters, digits, `_`, `-` and `.`, beginning with a letter, digit or `_`"
        ))
    } else {
        Ok(())
    }
}

/// A name as a key-path segment: quoted as in TOML when it holds a dot.
pub fn key_segment(name: &str) -> String {
    if name.contains('.') {
        format!("\"{name}\"")
    } else {
        name.to_string()
    }
}

/// The channel name of a recording column: the column itself when it is a valid name
/// ([`check_name`]), else lower-cased with each run of other characters made one `_`,
/// a sign before a letter or digit kept as `p` or `m` (`Solar Panel -X deg. C` →
/// `solar_panel_mx_deg_c`).
pub fn sensor_name_of(column: &str) -> String {
    if check_name(column).is_ok() {
        return column.to_string();
    }
    let chars: Vec<char> = column.chars().collect();
    let mut out = String::new();
    for (i, &c) in chars.iter().enumerate() {
        let next_alnum = chars.get(i + 1).is_some_and(|n| n.is_ascii_alphanumeric());
        let prev_alnum = i > 0 && chars[i - 1].is_ascii_alphanumeric();
        if c.is_ascii_alphanumeric() || c == '_' {
            out.push(c.to_ascii_lowercase());
        } else if matches!(c, '+' | '-') && next_alnum && !prev_alnum {
            out.push(if c == '+' { 'p' } else { 'm' });
        } else if !out.ends_with('_') {
            out.push('_');
        }
    }
    let out = out.trim_matches('_');
    let mut out: String = out.chars().take(MAX_NAME_LEN).collect();
    if out.is_empty() {
        out.push_str("channel");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn core_key_paths_parse_and_print() {
        let p = parse_path("node.\"gear1.r2\".c_j_per_k").unwrap();
        assert_eq!(
            p,
            vec![
                Part::Key("node".into()),
                Part::Key("gear1.r2".into()),
                Part::Key("c_j_per_k".into())
            ]
        );
        let p = parse_path("environment.beta_deg.value[1]").unwrap();
        assert_eq!(p[2], Part::Key("value".into()));
        assert_eq!(p[3], Part::Index(1));
        assert!(parse_path("node.").is_err());
        assert!(parse_path("node.\"x").is_err());
        let k = KeyPath::new("node").elem(3, "gear1.r2").key("c_j_per_k");
        assert_eq!(k.to_string(), "node.\"gear1.r2\".c_j_per_k");
        let k = KeyPath::new("conductor")
            .elem(0, "housing-bus")
            .key("g_w_per_k");
        assert_eq!(k.to_string(), "conductor.housing-bus.g_w_per_k");
    }
}

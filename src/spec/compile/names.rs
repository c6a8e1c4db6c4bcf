//! The names a scenario gives, checked by one rule.

use super::*;

/// Every name a scenario gives (scenario, nodes, boundaries, conductors, radiative
/// couplings, loads, heaters, modes, gear pairs, sensor columns), checked by the one
/// rule [`crate::spec::scenario::check_name`]: names become file names (the default log,
/// `diagnose`'s `residuals-<column>.svg`), log fields, CSV headers, key paths and
/// terminal text. The description, free text, may hold no control characters (no
/// escape sequences reach a terminal).
pub(super) fn check_names(cx: &Cx, raw: &ScenarioSpec) -> Result<(), SpecError> {
    let named = |section: &'static str, i: usize| KeyPath::new(section).at(i).key("name");
    let mut all: Vec<(KeyPath, &str)> =
        vec![(KeyPath::new("scenario").key("name"), &raw.scenario.name)];
    all.extend(
        raw.node
            .iter()
            .enumerate()
            .map(|(i, x)| (named("node", i), x.name.as_str())),
    );
    all.extend(
        raw.boundary
            .iter()
            .enumerate()
            .map(|(i, x)| (named("boundary", i), x.name.as_str())),
    );
    all.extend(
        raw.mode
            .iter()
            .enumerate()
            .map(|(i, x)| (named("mode", i), x.name.as_str())),
    );
    let optional = [
        (
            "conductor",
            raw.conductor
                .iter()
                .map(|x| x.name.as_deref())
                .collect::<Vec<_>>(),
        ),
        (
            "radiation",
            raw.radiation.iter().map(|x| x.name.as_deref()).collect(),
        ),
        ("sun", raw.sun.iter().map(|x| x.name.as_deref()).collect()),
        (
            "albedo",
            raw.albedo.iter().map(|x| x.name.as_deref()).collect(),
        ),
        (
            "earth_ir",
            raw.earth_ir.iter().map(|x| x.name.as_deref()).collect(),
        ),
        (
            "dissipation",
            raw.dissipation.iter().map(|x| x.name.as_deref()).collect(),
        ),
        (
            "heater",
            raw.heater.iter().map(|x| x.name.as_deref()).collect(),
        ),
        (
            "gear_pair",
            raw.gear_pair.iter().map(|x| x.name.as_deref()).collect(),
        ),
        ("face", raw.face.iter().map(|x| x.name.as_deref()).collect()),
    ];
    for (section, names) in optional {
        for (i, n) in names.into_iter().enumerate() {
            if let Some(n) = n {
                all.push((named(section, i), n));
            }
        }
    }
    all.extend(raw.sensor.iter().enumerate().filter_map(|(i, x)| {
        x.name
            .as_deref()
            .map(|n| (KeyPath::new("sensor").at(i).key("name"), n))
    }));
    // A recording's own column names may hold spaces and signs (telemetry), not
    // control characters.
    for (i, x) in raw.sensor.iter().enumerate() {
        let c = &x.column;
        let problem = if c.trim().is_empty() {
            Some("must not be empty".to_string())
        } else if c.len() > 200 {
            Some("is longer than 200 characters".to_string())
        } else if c.chars().any(char::is_control) {
            Some(format!("{c:?} holds a control character"))
        } else {
            None
        };
        if let Some(m) = problem {
            return Err(cx.err(&KeyPath::new("sensor").at(i).key("column"), m));
        }
    }
    for (p, name) in all {
        crate::spec::scenario::check_name(name).map_err(|m| cx.err(&p, m))?;
    }
    let d = &raw.scenario.description;
    if let Some(c) = d
        .chars()
        .find(|c| c.is_control() && *c != '\n' && *c != '\t')
    {
        return Err(cx.err(
            &KeyPath::new("scenario").key("description"),
            format!(
                "holds the control character {}: a description is plain text",
                c.escape_unicode()
            ),
        ));
    }
    if d.chars().count() > MAX_DESCRIPTION_LEN {
        return Err(cx.err(
            &KeyPath::new("scenario").key("description"),
            format!("is longer than {MAX_DESCRIPTION_LEN} characters"),
        ));
    }
    Ok(())
}

/// Longest scenario description.
pub const MAX_DESCRIPTION_LEN: usize = 2000;

/// A node name not yet taken (its form is checked by [`check_names`]).
pub(super) fn check_name(
    cx: &Cx,
    p: &KeyPath,
    name: &str,
    names: &HashMap<String, NodeRef>,
) -> Result<(), SpecError> {
    if names.contains_key(name) {
        return Err(cx.err(p, format!("node `{name}` is defined twice")));
    }
    Ok(())
}

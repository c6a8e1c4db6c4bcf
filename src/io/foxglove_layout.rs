//! A Foxglove layout generated from a run log's own channels (`orbitlash layout LOG`):
//! every panel plots only paths the log has, whatever the scenario, with temperatures
//! in °C from `/thermal/temperature_c`.
//!
//! First tab: the nodes other than gears' (°C) and each gear's radial nodes from bore
//! to rim (°C) on the left; each gear pair's backlash (exact, closed form, the paper's)
//! with the run's smallest allowed as a reference line, the heat flows (heaters
//! included) and, for a model with faces, the sunlight on each face on the right; the
//! events below. Second tab: the orbit state, and the 3-D gear view of a `run --scene`
//! log.

use std::collections::BTreeMap;

use serde_json::{Value, json};

use super::mcap_scan::Scan;

/// One channel of the log: its schema name, its message's field names in order and
/// its metadata.
#[derive(Debug, Clone, Default)]
pub struct TopicOutline {
    pub schema: String,
    pub fields: Vec<String>,
    pub metadata: BTreeMap<String, String>,
}

/// What a layout is made from: the scenario's name, each topic, each gear topic's
/// smallest allowed backlash (µm, from the run's end record) and whether the log is
/// dated (log time is UTC).
#[derive(Debug, Clone, Default)]
pub struct Outline {
    pub name: String,
    pub topics: BTreeMap<String, TopicOutline>,
    pub min_allowed_um: BTreeMap<String, f64>,
    pub dated: bool,
}

/// The outline of a scanned log: channels with their schemas' fields, the provenance's
/// scenario name, run_end's `pairs_json`.
pub fn outline(scan: &Scan<'_>) -> Result<Outline, String> {
    let mut topics = BTreeMap::new();
    for ch in scan.channels.values() {
        let schema = scan
            .schemas
            .get(&ch.schema_id)
            .ok_or_else(|| format!("channel {} has no schema", ch.topic))?;
        let fields = if schema.name.starts_with("foxglove.") {
            Vec::new()
        } else {
            super::mcap_read::message_type(&schema.data, &schema.name)?
                .fields()
                .map(|f| f.name().to_string())
                .collect()
        };
        topics.insert(
            ch.topic.clone(),
            TopicOutline {
                schema: schema.name.clone(),
                fields,
                metadata: ch.metadata.clone(),
            },
        );
    }
    let mut min_allowed_um = BTreeMap::new();
    if let Some(raw) = scan.metadata_value("orbitlash.run_end", "pairs_json") {
        let pairs: Value =
            serde_json::from_str(raw).map_err(|e| format!("run_end's pairs_json: {e}"))?;
        for p in pairs.as_array().into_iter().flatten() {
            let topic = p["topic"].as_str().map(str::to_string).or_else(|| {
                let name = p["name"].as_str()?;
                topics
                    .iter()
                    .find(|(_, t)| t.metadata.get("pair").map(String::as_str) == Some(name))
                    .map(|(k, _)| k.clone())
            });
            if let (Some(t), Some(v)) = (topic, p["min_allowed_um"].as_f64()) {
                min_allowed_um.insert(t, v);
            }
        }
    }
    Ok(Outline {
        name: scan
            .metadata_value("orbitlash.provenance", "scenario_name")
            .unwrap_or("orbitlash")
            .to_string(),
        topics,
        min_allowed_um,
        dated: scan.time_origin_ns() != 0,
    })
}

/// Line colours (Tableau 10), in order within a panel.
const COLOURS: [&str; 10] = [
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
    "#bcbd22", "#17becf",
];
/// The smallest allowed backlash's line.
const ALLOWED: &str = "#e34b4b";

/// A Plot panel's configuration: `series` as (message path, label), `lines` as
/// (value, label) reference lines.
fn plot(
    title: &str,
    y_label: &str,
    dated: bool,
    series: &[(String, String)],
    lines: &[(f64, String)],
) -> Value {
    let mut paths: Vec<Value> = series
        .iter()
        .enumerate()
        .map(|(i, (path, label))| {
            json!({"value": path, "enabled": true, "timestampMethod": "receiveTime",
                   "label": label, "color": COLOURS[i % COLOURS.len()]})
        })
        .collect();
    paths.extend(lines.iter().map(|(v, label)| {
        json!({"value": format!("{v}"), "enabled": true, "timestampMethod": "receiveTime",
               "label": label, "color": ALLOWED})
    }));
    json!({
        "paths": paths, "showXAxisLabels": true, "showYAxisLabels": true, "showLegend": true,
        "legendDisplay": "top", "showPlotValuesInLegend": false, "isSynced": true,
        "xAxisVal": "timestamp", "sidebarDimension": 240,
        "xAxisLabel": if dated { "time since the log's start (s); log time is UTC" } else { "simulated time since t = 0 (s)" },
        "yAxisLabel": y_label, "foxglovePanelTitle": title,
    })
}

/// Panels stacked in `direction` ("row" or "column"), each an equal share.
fn stack(ids: &[String], direction: &str) -> Value {
    match ids {
        [] => Value::Null,
        [one] => json!(one),
        [first, rest @ ..] => json!({
            "first": first, "second": stack(rest, direction), "direction": direction,
            "splitPercentage": 100.0 / ids.len() as f64,
        }),
    }
}

/// Splits a node name `gear1.r2` into its gear and radial index.
fn gear_node(node: &str) -> Option<(&str, usize)> {
    let (gear, r) = node.rsplit_once('.')?;
    Some((gear, r.strip_prefix('r')?.parse().ok()?))
}

/// The temperature plots: the nodes other than gears', then each gear's radial nodes
/// (°C from `/thermal/temperature_c`; K from `/thermal/temperature` in a log without it).
fn temperature_panels(o: &Outline, panels: &mut BTreeMap<String, Value>) -> Vec<String> {
    let (topic, unit) = if o.topics.contains_key("/thermal/temperature_c") {
        ("/thermal/temperature_c", "°C")
    } else {
        ("/thermal/temperature", "K")
    };
    let Some(t) = o.topics.get(topic) else {
        return Vec::new();
    };
    let mut body = Vec::new();
    let mut gears: BTreeMap<String, Vec<(usize, String, String)>> = BTreeMap::new();
    for f in t.fields.iter().filter(|f| *f != "time_s") {
        let node = t
            .metadata
            .get(&format!("node:{f}"))
            .cloned()
            .unwrap_or_else(|| f.clone());
        let path = format!("{topic}.{f}");
        match gear_node(&node) {
            Some((g, r)) => {
                gears
                    .entry(g.to_string())
                    .or_default()
                    .push((r, path, format!("{node} ({unit})")))
            }
            None => body.push((path, format!("{node} ({unit})"))),
        }
    }
    let mut ids = Vec::new();
    let y = format!("temperature ({unit})");
    if !body.is_empty() {
        let title = if gears.is_empty() {
            "Node temperatures"
        } else {
            "Nodes other than gears"
        };
        let id = "Plot!temperatures".to_string();
        panels.insert(
            id.clone(),
            plot(&format!("{title} ({unit})"), &y, o.dated, &body, &[]),
        );
        ids.push(id);
    }
    for (g, mut nodes) in gears {
        nodes.sort_by_key(|n| n.0);
        let series: Vec<(String, String)> = nodes.into_iter().map(|(_, p, l)| (p, l)).collect();
        let id = format!("Plot!temperatures-{g}");
        let title = format!("{g}: radial nodes, bore r0 … rim ({unit})");
        panels.insert(id.clone(), plot(&title, &y, o.dated, &series, &[]));
        ids.push(id);
    }
    ids
}

/// The right-hand plots: each pair's backlash with its smallest allowed, the heat
/// flows, the sunlight on each face.
fn flow_panels(o: &Outline, panels: &mut BTreeMap<String, Value>) -> Vec<String> {
    let mut ids = Vec::new();
    for (topic, t) in o.topics.iter().filter(|(k, t)| {
        k.starts_with("/gears/") && t.fields.iter().any(|f| f == "backlash_exact_um")
    }) {
        let pair = t
            .metadata
            .get("pair")
            .cloned()
            .unwrap_or_else(|| topic["/gears/".len()..].to_string());
        let series: Vec<(String, String)> = [
            ("backlash_exact_um", "exact (µm)"),
            ("backlash_closed_form_um", "closed form (µm)"),
            ("backlash_paper_um", "paper's formula (µm)"),
        ]
        .iter()
        .filter(|(f, _)| t.fields.iter().any(|x| x == f))
        .map(|(f, l)| (format!("{topic}.{f}"), l.to_string()))
        .collect();
        let lines: Vec<(f64, String)> = o
            .min_allowed_um
            .get(topic)
            .map(|&v| (v, format!("smallest allowed, {v} µm")))
            .into_iter()
            .collect();
        let id = format!("Plot!backlash-{}", &topic["/gears/".len()..]);
        panels.insert(
            id.clone(),
            plot(
                &format!("Backlash, gear pair {pair} (µm)"),
                "backlash (µm)",
                o.dated,
                &series,
                &lines,
            ),
        );
        ids.push(id);
    }
    if let Some(t) = o.topics.get("/thermal/heat") {
        let series: Vec<(String, String)> = t
            .fields
            .iter()
            .map(|f| {
                (
                    format!("/thermal/heat.{f}"),
                    format!("{} (W)", f.strip_suffix("_w").unwrap_or(f)),
                )
            })
            .collect();
        panels.insert(
            "Plot!heat-flows".into(),
            plot(
                "Heat flows (W): absorbed, dissipated, to each boundary, each load and heater",
                "heat flow (W)",
                o.dated,
                &series,
                &[],
            ),
        );
        ids.push("Plot!heat-flows".into());
    }
    if let Some(t) = o.topics.get("/orbit/faces") {
        let series: Vec<(String, String)> = t
            .fields
            .iter()
            .filter(|f| f.ends_with("_solar_w_per_m2"))
            .map(|f| {
                let name = t
                    .metadata
                    .get(&format!("face:{f}"))
                    .cloned()
                    .unwrap_or_else(|| f.clone());
                (format!("/orbit/faces.{f}"), format!("{name} (W/m²)"))
            })
            .collect();
        if !series.is_empty() {
            panels.insert(
                "Plot!face-sunlight".into(),
                plot(
                    "Sunlight on each face before absorptivity (W/m²)",
                    "flux (W/m²)",
                    o.dated,
                    &series,
                    &[],
                ),
            );
            ids.push("Plot!face-sunlight".into());
        }
    }
    ids
}

/// The layout for the log outlined by `o` (Foxglove's layout JSON: `configById`,
/// `layout`, …).
pub fn layout(o: &Outline) -> Value {
    let mut panels = BTreeMap::new();
    let left = temperature_panels(o, &mut panels);
    let right = flow_panels(o, &mut panels);
    let mut top: Vec<Value> = Vec::new();
    for column in [&left, &right] {
        if !column.is_empty() {
            top.push(stack(column, "column"));
        }
    }
    let top = match top.len() {
        0 => Value::Null,
        1 => top.remove(0),
        _ => json!({"first": top[0], "second": top[1], "direction": "row", "splitPercentage": 50}),
    };
    let mut first = top;
    if o.topics
        .get("/events")
        .is_some_and(|t| t.schema == "foxglove.Log")
    {
        panels.insert(
            "RosOut!events".into(),
            json!({
            "searchTerms": [], "minLogLevel": 1, "topicToRender": "/events",
            "foxglovePanelTitle": "Events (/events): eclipses, heaters, modes, margin, run end"}),
        );
        first = if first.is_null() {
            json!("RosOut!events")
        } else {
            json!({"first": first, "second": "RosOut!events", "direction": "column", "splitPercentage": 80})
        };
    }
    let mut second = Vec::new();
    if o.topics.contains_key("/orbit/state") {
        panels.insert("RawMessages!orbit-state".into(), json!({
            "diffEnabled": false, "diffMethod": "custom", "diffTopicPath": "",
            "showFullMessageForDiff": false, "topicPath": "/orbit/state",
            "foxglovePanelTitle": "Orbit state (/orbit/state): angle, beta, solar flux, sunlit, orbit"}));
        second.push("RawMessages!orbit-state".to_string());
    }
    let scenes: Vec<&String> = o
        .topics
        .iter()
        .filter(|(k, t)| k.ends_with("/scene") && t.schema == "foxglove.SceneUpdate")
        .map(|(k, _)| k)
        .collect();
    if !scenes.is_empty() {
        let topics: serde_json::Map<String, Value> = scenes
            .iter()
            .map(|s| ((*s).clone(), json!({"visible": true})))
            .collect();
        panels.insert(
            "3D!gear-mesh".into(),
            json!({
            "cameraState": {"distance": 0.12, "perspective": true, "phi": 20, "target": [0, 0, 0],
                            "targetOffset": [0.015, 0, 0], "targetOrientation": [0, 0, 0, 1],
                            "thetaOffset": 0, "fovy": 45, "near": 0.001, "far": 100},
            "followMode": "follow-pose", "followTf": "gears",
            "scene": {"transforms": {"visible": false, "showLabel": false}, "enableStats": false},
            "transforms": {}, "topics": topics, "layers": {},
            "foxglovePanelTitle": "Gear pairs: tooth outlines coloured by rim temperature"}),
        );
        second.insert(0, "3D!gear-mesh".to_string());
    }
    let mut tabs = vec![
        // named by what it plots: a model without gear pairs has no backlash panel
        json!({"title": format!("{}: temperatures, {}heat", o.name,
            if o.topics.keys().any(|k| k.starts_with("/gears/")) { "backlash, " } else { "" }),
            "layout": first}),
    ];
    if !second.is_empty() {
        tabs.push(json!({"title": format!("{}: orbit{}", o.name, if scenes.is_empty() { "" } else { ", gear mesh 3-D" }), "layout": stack(&second, "row")}));
    }
    panels.insert(
        "Tab!orbitlash".into(),
        json!({"activeTabIdx": 0, "tabs": tabs}),
    );
    json!({
        "configById": panels, "globalVariables": {}, "userNodes": {},
        "playbackConfig": {"speed": 1}, "layout": "Tab!orbitlash",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn topic(fields: &[&str], meta: &[(&str, &str)]) -> TopicOutline {
        TopicOutline {
            schema: "orbitlash.X".into(),
            fields: fields.iter().map(|s| s.to_string()).collect(),
            metadata: meta
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
        }
    }

    /// A log's nodes split into the body's and each gear's (in radial order), the
    /// pair's line at its smallest allowed, and no panel for what the log lacks.
    #[test]
    fn core_layout_follows_the_log() {
        let mut o = Outline {
            name: "x".into(),
            ..Outline::default()
        };
        o.topics.insert(
            "/thermal/temperature_c".into(),
            topic(
                &["box_c", "g_r1_c", "g_r0_c"],
                &[
                    ("node:box_c", "box"),
                    ("node:g_r1_c", "g.r1"),
                    ("node:g_r0_c", "g.r0"),
                ],
            ),
        );
        o.topics.insert(
            "/gears/p".into(),
            topic(&["backlash_exact_um", "margin_um"], &[("pair", "p")]),
        );
        o.min_allowed_um.insert("/gears/p".into(), 7.5);
        let l = layout(&o);
        let panels = l["configById"].as_object().unwrap();
        let paths = |id: &str| -> Vec<String> {
            panels[id]["paths"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| p["value"].as_str().unwrap().to_string())
                .collect()
        };
        assert_eq!(paths("Plot!temperatures"), ["/thermal/temperature_c.box_c"]);
        assert_eq!(
            paths("Plot!temperatures-g"),
            [
                "/thermal/temperature_c.g_r0_c",
                "/thermal/temperature_c.g_r1_c"
            ]
        );
        assert_eq!(
            paths("Plot!backlash-p"),
            ["/gears/p.backlash_exact_um", "7.5"]
        );
        assert!(!panels.contains_key("Plot!heat-flows") && !panels.contains_key("RosOut!events"));
    }
}

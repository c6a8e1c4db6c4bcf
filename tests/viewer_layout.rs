//! Foxglove layouts against the logs they are for. `orbitlash layout LOG` makes one from
//! a log's own channels; `viewer/foxglove-layout.json` is that layout for the reference
//! scenario's log with the 3-D view. For it and for the layout of every shipped
//! scenario's log: every panel is placed, every message path is a channel of the log
//! and resolves in its protobuf schema, every plotted path gives a finite number in
//! every message, and each backlash plot's reference line is that pair's smallest
//! allowed backlash (`backlash_exact_um - margin_um`).

mod common;

use std::collections::{BTreeMap, BTreeSet};

use prost_reflect::{DescriptorPool, DynamicMessage, Kind, MessageDescriptor, Value};
use serde_json::{Map, Value as Json};

/// A Foxglove message path `/topic.field.sub[k]`: the topic, then each field with an
/// optional index into a repeated field (the only syntax the layout uses).
struct MessagePath {
    text: String,
    topic: String,
    fields: Vec<(String, Option<usize>)>,
}

fn parse_path(text: &str) -> MessagePath {
    let (topic, rest) = text.split_once('.').unwrap_or((text, ""));
    let plain = |s: &str| !s.is_empty() && s.chars().all(|c| c == '_' || c.is_ascii_alphanumeric());
    let topic_ok = topic.starts_with('/') && topic[1..].split('/').all(plain);
    assert!(topic_ok, "`{text}`: not a plain `/topic`");
    let field = |seg: &str| {
        let (name, index) = match seg.split_once('[') {
            None => (seg, None),
            Some((name, i)) => match i.strip_suffix(']').map(str::parse::<usize>) {
                Some(Ok(i)) => (name, Some(i)),
                _ => panic!("`{text}`: `[{i}` is not an index like `[2]`"),
            },
        };
        // filters, slices and math modifiers would need checks of their own
        assert!(
            plain(name),
            "`{text}`: `{seg}` is not a field name this test reads"
        );
        (name.to_string(), index)
    };
    let fields = (!rest.is_empty()).then(|| rest.split('.').map(field).collect());
    let (text, topic) = (text.to_string(), topic.to_string());
    MessagePath {
        text,
        topic,
        fields: fields.unwrap_or_default(),
    }
}

/// What the panels refer to: plotted series, topics of other panels (with the schema
/// they need), and plot reference lines (a series whose value is a number).
#[derive(Default)]
struct Refs {
    plotted: Vec<(String, MessagePath)>,
    topics: Vec<(String, MessagePath, Option<&'static str>)>,
    lines: Vec<(String, f64)>,
}

fn layout_refs(panels: &Map<String, Json>) -> Refs {
    let mut refs = Refs::default();
    for (id, config) in panels {
        let get = |key: &str| {
            config
                .get(key)
                .unwrap_or_else(|| panic!("{id}: no `{key}`"))
        };
        let at = |key: &str| {
            get(key)
                .as_str()
                .unwrap_or_else(|| panic!("{id}: `{key}`?"))
        };
        let mut topic =
            |path: &str, schema| refs.topics.push((id.clone(), parse_path(path), schema));
        match id.split_once('!').map(|(kind, _)| kind) {
            Some("RosOut") => topic(at("topicToRender"), Some("foxglove.Log")),
            Some("RawMessages") => topic(at("topicPath"), None),
            Some("3D") => {
                for t in get("topics").as_object().into_iter().flat_map(|t| t.keys()) {
                    topic(t.as_str(), Some("foxglove.SceneUpdate"));
                }
            }
            Some("Plot") => {
                for s in get("paths").as_array().into_iter().flatten() {
                    let value = s["value"].as_str().unwrap_or_else(|| panic!("{id}: {s}"));
                    match value.trim().parse::<f64>() {
                        Ok(line) => refs.lines.push((id.clone(), line)),
                        Err(_) => refs.plotted.push((id.clone(), parse_path(value))),
                    }
                }
            }
            Some("Tab") => {}
            _ => panic!("panel {id}: a kind this test does not read; teach it where its paths are"),
        }
    }
    refs
}

/// The panel ids a layout node places: an id (a Tab's tabs included) or a split.
fn placed<'a>(node: &'a Json, panels: &'a Map<String, Json>, out: &mut BTreeSet<&'a str>) {
    match node {
        Json::String(id) => {
            out.insert(id);
            let tabs = panels.get(id).and_then(|config| config["tabs"].as_array());
            for tab in tabs.into_iter().flatten() {
                placed(&tab["layout"], panels, out);
            }
        }
        Json::Object(_) => {
            placed(&node["first"], panels, out);
            placed(&node["second"], panels, out);
        }
        other => panic!("layout node {other} is neither a panel id nor a split"),
    }
}

/// Resolves the path's fields in `desc`: the last field's kind and whether it is a whole
/// list (`None` for a bare topic).
fn field_kind(desc: &MessageDescriptor, path: &MessagePath) -> Option<(Kind, bool)> {
    let (mut desc, mut last, text) = (desc.clone(), None, &path.text);
    for (name, index) in &path.fields {
        match &last {
            Some((Kind::Message(inner), false)) => desc = inner.clone(),
            Some(_) => panic!("`{text}`: `{name}` follows a field that is not a message"),
            None => {}
        }
        let Some(field) = desc.get_field_by_name(name) else {
            let names: Vec<String> = desc.fields().map(|f| f.name().to_string()).collect();
            panic!(
                "`{text}`: {} has no `{name}`, only {names:?}",
                desc.full_name()
            );
        };
        assert!(
            index.is_none() || field.is_list(),
            "`{text}`: `{name}` is not repeated"
        );
        last = Some((field.kind(), field.is_list() && index.is_none()));
    }
    last
}

/// A single number (not a list, message, bool, string or enum).
fn is_number(kind: &Option<(Kind, bool)>) -> bool {
    use Kind::*;
    let numbers = [Double, Float, Int32, Int64, Uint32, Uint64, Sint32, Sint64];
    let fixed = [Fixed32, Fixed64, Sfixed32, Sfixed64];
    matches!(kind, Some((k, false)) if numbers.contains(k) || fixed.contains(k))
}

/// The number `path` gives in a decoded message.
fn number_at(msg: &DynamicMessage, path: &MessagePath) -> f64 {
    let (mut value, text) = (Value::Message(msg.clone()), &path.text);
    for (name, index) in &path.fields {
        let Value::Message(m) = &value else {
            panic!("`{text}`: `{name}` in a non-message")
        };
        let v = m
            .get_field_by_name(name)
            .unwrap_or_else(|| panic!("`{text}`: no `{name}`"));
        let v = v.into_owned();
        value = match index {
            Some(i) => v
                .as_list()
                .and_then(|list| list.get(*i))
                .cloned()
                .unwrap_or_else(|| panic!("`{text}`: `{name}` has no item {i}")),
            None => v,
        };
    }
    match value {
        Value::F64(x) => x,
        Value::F32(x) => x.into(),
        Value::I32(x) => x.into(),
        Value::U32(x) => x.into(),
        Value::I64(x) => x as f64,
        Value::U64(x) => x as f64,
        other => panic!("`{text}` gives {other:?}, not a number"),
    }
}

/// Every panel of `layout` is placed; every message path of it is a channel of the log
/// at `log` and resolves in its protobuf schema; every plotted path gives a finite
/// number in every message; each reference line is beside a pair's exact backlash and
/// equals that pair's smallest allowed (`backlash_exact_um - margin_um`).
fn check_layout_against_log(layout: &Json, log: &std::path::Path) {
    let panels = layout["configById"]
        .as_object()
        .expect("a `configById` object");
    let mut shown = BTreeSet::new();
    placed(&layout["layout"], panels, &mut shown);
    let configured: BTreeSet<&str> = panels.keys().map(String::as_str).collect();
    assert_eq!(
        shown, configured,
        "the panels the layout places and those it configures"
    );
    let refs = layout_refs(panels);
    let bytes = std::fs::read(log).unwrap();
    let summary = mcap::Summary::read(&bytes)
        .expect("a readable log")
        .expect("a summary");
    let mut types = BTreeMap::new();
    for channel in summary.channels.values() {
        let schema = channel.schema.as_ref().expect("a schema");
        let pool = DescriptorPool::decode(&schema.data[..]);
        let pool = pool.unwrap_or_else(|e| panic!("{}: {e}", channel.topic));
        let desc = pool
            .get_message_by_name(&schema.name)
            .expect("the schema's own type");
        types.insert(channel.topic.clone(), desc);
    }
    let type_of = |id: &str, path: &MessagePath| {
        let (topics, text) = (types.keys().collect::<Vec<_>>(), &path.text);
        let missing = format!("{id}: `{text}`: the log has no such topic, only {topics:?}");
        types
            .get(&path.topic)
            .unwrap_or_else(|| panic!("{missing}"))
    };
    for (id, path, schema) in &refs.topics {
        let (desc, topic) = (type_of(id, path), &path.topic);
        let name = desc.full_name();
        assert!(
            schema.is_none_or(|s| s == name),
            "{id}: {topic} is {name}, not {schema:?}"
        );
        field_kind(desc, path);
    }
    for (id, path) in &refs.plotted {
        let kind = field_kind(type_of(id, path), path);
        assert!(
            is_number(&kind),
            "{id}: `{}` is not a number: {kind:?}",
            path.text
        );
    }

    // Every message of a plotted topic decodes and gives a finite number for each path;
    // the mesh messages give the smallest allowed backlash.
    let (mut seen, mut allowed) = (BTreeSet::new(), BTreeMap::<String, Vec<f64>>::new());
    for message in mcap::MessageStream::new(&bytes).expect("the log's messages") {
        let message = message.unwrap_or_else(|e| panic!("{}: {e}", log.display()));
        let topic = message.channel.topic.as_str();
        let on_topic: Vec<_> = refs
            .plotted
            .iter()
            .filter(|(_, p)| p.topic == topic)
            .collect();
        if on_topic.is_empty() {
            continue;
        }
        let msg = DynamicMessage::decode(types[topic].clone(), &message.data[..]);
        let msg = msg.unwrap_or_else(|e| panic!("message {} on {topic}: {e}", message.sequence));
        seen.insert(topic.to_string());
        for (id, path) in on_topic {
            let v = number_at(&msg, path);
            assert!(
                v.is_finite(),
                "{id}: `{}` is {v} at {} ns",
                path.text,
                message.log_time
            );
        }
        if topic.starts_with("/gears/") && !topic.ends_with("/scene") {
            let exact = parse_path(&format!("{topic}.backlash_exact_um"));
            let margin = parse_path(&format!("{topic}.margin_um"));
            let a = number_at(&msg, &exact) - number_at(&msg, &margin);
            allowed.entry(topic.to_string()).or_default().push(a);
        }
    }
    for (id, path) in &refs.plotted {
        assert!(
            seen.contains(&path.topic),
            "{id}: no message on {}",
            path.topic
        );
    }
    let pairs = allowed.len();
    assert!(
        pairs == 0 || refs.lines.len() == pairs,
        "{} reference lines for {pairs} gear pairs",
        refs.lines.len()
    );
    for (id, line) in &refs.lines {
        let pair = refs
            .plotted
            .iter()
            .find(|(pid, p)| {
                pid == id && p.topic.starts_with("/gears/") && p.fields[0].0 == "backlash_exact_um"
            })
            .map(|(_, p)| p.topic.clone());
        let pair = pair
            .unwrap_or_else(|| panic!("{id}: a reference line ({line}) outside a backlash plot"));
        let a = &allowed[&pair];
        assert!(
            a.iter().all(|a| (a - line).abs() < 1e-9),
            "{id}: line at {line} µm, {pair}'s smallest allowed backlash {:?} µm",
            a.first()
        );
    }
}

/// The layout `orbitlash layout` writes for the log at `log` (into `dir`).
fn generated_layout(log: &std::path::Path, dir: &std::path::Path) -> Json {
    let out = dir.join("layout.json");
    let o = common::bin()
        .arg("layout")
        .arg(log)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "orbitlash layout: {stderr}");
    let text = std::fs::read_to_string(&out).unwrap();
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", out.display()))
}

/// A log of `args` (a short run) in `dir`.
fn run_log(dir: &std::path::Path, name: &str, args: &[&str]) -> std::path::PathBuf {
    let log = dir.join(format!("{name}.mcap"));
    let out = common::bin()
        .arg("run")
        .args(args)
        .args(["--quiet", "--out"])
        .arg(&log)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.code().is_some_and(|c| c < 2),
        "orbitlash run {args:?}: {stderr}"
    );
    log
}

/// The shipped layout (viewer/foxglove-layout.json, the reference scenario) is the one
/// `orbitlash layout` makes for the reference run's log with the 3-D view, and it
/// holds against that log: the four plot groups in panels of their own, every node in
/// °C.
#[test]
fn cli_foxglove_layout_paths_exist_in_a_reference_log() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/viewer/foxglove-layout.json");
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{file}: {e}"));
    let layout: Json = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{file}: {e}"));
    let panels = layout["configById"]
        .as_object()
        .expect("a `configById` object");
    let refs = layout_refs(panels);
    let mut group_of = BTreeMap::new();
    for p in [
        "/thermal/temperature_c.housing_c",
        "/thermal/temperature_c.gear1_r0_c",
        "/gears/mesh.backlash_exact_um",
        "/thermal/heat.to_space_w",
    ] {
        let panel = refs.plotted.iter().find(|(_, path)| path.text == p);
        let (id, _) = panel.unwrap_or_else(|| panic!("the layout plots no `{p}`"));
        assert!(
            group_of.insert(id, p).is_none(),
            "{id} holds {p} and {group_of:?}"
        );
    }
    let nodes = [
        "housing", "motor", "shaft1", "shaft2", "gear1_r0", "gear1_r1", "gear1_r2", "gear2_r0",
        "gear2_r1", "gear2_r2",
    ];
    for node in nodes {
        let p = format!("/thermal/temperature_c.{node}_c");
        assert!(
            refs.plotted.iter().any(|(_, path)| path.text == p),
            "no plot of `{p}`"
        );
    }
    let dir = common::tmpdir("foxglove-layout");
    let log = run_log(&dir, "ref", &["--orbits", "1", "--scene"]);
    check_layout_against_log(&layout, &log);
    assert_eq!(
        generated_layout(&log, &dir),
        layout,
        "viewer/foxglove-layout.json is not what `orbitlash layout` makes for the reference log: regenerate it"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every shipped scenario's log (two orbits of each) gets a layout from `orbitlash
/// layout` whose every path resolves to a finite number in every message, with every
/// node's temperature plotted.
#[test]
fn cli_foxglove_layout_generated_for_every_shipped_scenario() {
    let dir = common::tmpdir("foxglove-layout-every");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut names: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 5, "shipped scenarios: {names:?}");
    for scenario in names {
        let stem = scenario.file_stem().unwrap().to_string_lossy().into_owned();
        let s = scenario.to_string_lossy().into_owned();
        let log = run_log(&dir, &stem, &[&s, "--orbits", "2"]);
        let layout = generated_layout(&log, &dir);
        check_layout_against_log(&layout, &log);
        let refs = layout_refs(layout["configById"].as_object().unwrap());
        let bytes = std::fs::read(&log).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let celsius = summary
            .channels
            .values()
            .find(|c| c.topic == "/thermal/temperature_c")
            .unwrap_or_else(|| panic!("{stem}: no /thermal/temperature_c"));
        let nodes = celsius
            .metadata
            .keys()
            .filter(|k| k.starts_with("node:"))
            .count();
        let plotted = refs
            .plotted
            .iter()
            .filter(|(_, p)| p.topic == "/thermal/temperature_c")
            .count();
        assert_eq!(
            plotted, nodes,
            "{stem}: {plotted} of {nodes} node temperatures plotted"
        );
        // the first tab is named by what it plots: backlash only with gear pairs
        // (helper-29: FUNcube-1's said "temperatures, backlash, heat")
        let gears = summary
            .channels
            .values()
            .any(|c| c.topic.starts_with("/gears/"));
        let tabs = layout["configById"]
            .as_object()
            .unwrap()
            .values()
            .find_map(|c| c["tabs"].as_array())
            .unwrap_or_else(|| panic!("{stem}: no tabs"));
        let title = tabs[0]["title"].as_str().unwrap();
        assert_eq!(title.contains("backlash"), gears, "{stem}: {title}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

//! Rules of `docs/ARCHITECTURE.md` that can be read off the source: a number's key is
//! written once, in its registry field; no two files of `src/` import each other
//! (directly or round a loop). (No function over 150 lines and no cycle between the
//! top-level modules: `python3 ../shared/tools/code_shape.py src 150`, run by `.ci/run`.)

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every `.rs` file under `dir`, with its text.
fn files(dir: &Path, out: &mut Vec<(PathBuf, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            let text = std::fs::read_to_string(&p).unwrap();
            out.push((p, text));
        }
    }
}

/// The code of a file: comments and its test module left out.
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Keys that name another thing besides the number (each with where and why).
const ALSO_ELSEWHERE: &[(&str, &str)] = &[
    // the log's and the CSV's field names follow the keys (units in names, one name in
    // TOML, code and logs); they are the log schema's identity
    ("beta_deg", "the environment's log field"),
    ("solar_flux_w_per_m2", "the environment's log field"),
    ("center_distance_mm", "the gear pair's log and CSV field"),
    ("pressure_angle_deg", "the gear pair's log and CSV field"),
    ("radius_mm", "a gear node's log field"),
    ("tip_radius_mm", "a gear's log field"),
    ("temperature_k", "a node's log field"),
    ("min_backlash_um", "margins' report column"),
];

/// A number's key is written as a string once: in its registry field
/// (beside its rows, in `src/spec/registry/rows.rs` or `gear_rows.rs`). Keys with a unit in their name are checked (the
/// plain words, `albedo`, `scale`, `teeth`, are other things' names too); the
/// acceptance's three by name.
#[test]
fn core_a_keys_string_is_written_in_its_registry_field_only() {
    let mut all = Vec::new();
    files(&src(), &mut all);
    let homes = ["spec/registry/rows.rs", "spec/registry/gear_rows.rs"];
    let names: BTreeSet<&str> = orbitlash::spec::registry::rows()
        .iter()
        .map(|r| r.field.name)
        .filter(|n| n.contains('_') && !ALSO_ELSEWHERE.iter().any(|(k, _)| k == n))
        .collect();
    for must in ["conductance_w_per_k", "capacitance_j_per_k", "altitude_m"] {
        assert!(names.contains(must), "{must} is not checked");
    }
    let mut found: BTreeMap<&str, Vec<String>> = BTreeMap::new();
    for (path, text) in &all {
        let code = code(text);
        for n in &names {
            let quoted = format!("\"{n}\"");
            if code.contains(&quoted) {
                found
                    .entry(n)
                    .or_default()
                    .push(path.strip_prefix(src()).unwrap().display().to_string());
            }
        }
    }
    for n in &names {
        let places = found.get(n).cloned().unwrap_or_default();
        assert!(
            places.len() == 1 && homes.contains(&places[0].as_str()),
            "the key `{n}` is written as a string outside its registry field: {places:?}"
        );
    }
}

/// The module path of a file (`src/spec/compile/gear.rs` → [spec, compile, gear]).
fn module_of(path: &Path) -> Vec<String> {
    let rel = path.strip_prefix(src()).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().to_string())
        .collect();
    if parts
        .last()
        .is_some_and(|l| l == "mod" || l == "lib" || l == "main")
    {
        parts.pop();
    }
    parts
}

/// The file of the deepest module of `path` that is a file of `modules`.
fn file_of(path: &[String], modules: &BTreeMap<Vec<String>, usize>) -> Option<usize> {
    (1..=path.len())
        .rev()
        .find_map(|n| modules.get(&path[..n]).copied())
}

/// No two files import each other, directly or round a loop: the files of `src/` and
/// the `crate::…` and `super::…` paths they use (a file's own submodules and the
/// modules above it aside: a parent declares its children, a child may use what its
/// parent holds) make an acyclic graph.
#[test]
fn core_no_file_level_import_cycles() {
    let mut all = Vec::new();
    files(&src(), &mut all);
    let modules: BTreeMap<Vec<String>, usize> = all
        .iter()
        .enumerate()
        .filter(|(_, (p, _))| !p.ends_with("main.rs"))
        .map(|(i, (p, _))| (module_of(p), i))
        .collect();
    let path_re = |text: &str, prefix: &str| -> Vec<Vec<String>> {
        let mut out = Vec::new();
        for (i, _) in text.match_indices(prefix) {
            let rest = &text[i + prefix.len()..];
            let end = rest
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(rest.len());
            let parts: Vec<String> = rest[..end]
                .split("::")
                .filter(|s| !s.is_empty())
                .map(str::to_string)
                .collect();
            out.push(parts);
        }
        out
    };
    let mut edges: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); all.len()];
    for (i, (p, text)) in all.iter().enumerate() {
        if p.ends_with("main.rs") {
            continue;
        }
        let me = module_of(p);
        let code = code(text);
        let mut targets = path_re(&code, "crate::");
        let parent: Vec<String> = me[..me.len().saturating_sub(1)].to_vec();
        for rel in path_re(&code, "super::") {
            targets.push(parent.iter().cloned().chain(rel).collect());
        }
        for t in targets {
            let Some(j) = file_of(&t, &modules) else {
                continue;
            };
            let them = module_of(&all[j].0);
            // a module above or below this one: not an import between two files
            if j == i || me.starts_with(&them) || them.starts_with(&me) {
                continue;
            }
            edges[i].insert(j);
        }
    }
    // depth-first search for a back edge
    fn visit(
        v: usize,
        edges: &[BTreeSet<usize>],
        state: &mut [u8],
        stack: &mut Vec<usize>,
    ) -> Option<Vec<usize>> {
        state[v] = 1;
        stack.push(v);
        for &w in &edges[v] {
            if state[w] == 1 {
                let k = stack.iter().position(|&x| x == w).unwrap();
                return Some(stack[k..].to_vec());
            }
            if state[w] == 0
                && let Some(c) = visit(w, edges, state, stack)
            {
                return Some(c);
            }
        }
        stack.pop();
        state[v] = 2;
        None
    }
    let mut state = vec![0u8; all.len()];
    for v in 0..all.len() {
        if state[v] == 0 {
            let cycle = visit(v, &edges, &mut state, &mut Vec::new());
            let names: Vec<String> = cycle
                .unwrap_or_default()
                .iter()
                .map(|&k| all[k].0.strip_prefix(src()).unwrap().display().to_string())
                .collect();
            assert!(
                names.is_empty(),
                "files that import each other: {}",
                names.join(" → ")
            );
        }
    }
}

/// No file of the spec layer grows past 1000 lines: the compiler is split by domain and
/// the registry by kind of row.
#[test]
fn core_no_spec_file_over_1000_lines() {
    let mut all = Vec::new();
    files(&src().join("spec"), &mut all);
    for (path, text) in &all {
        let n = text.lines().count();
        assert!(n <= 1000, "{} has {n} lines", path.display());
    }
}

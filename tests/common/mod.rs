//! Helpers shared by the integration tests.
#![allow(dead_code)]

use orbitlash::io::scenario_toml;
use orbitlash::spec::scenario::Scenario;

/// A scenario from its parts: `[environment]` keys, `[run]`/`[solver]` keys and the
/// network body. The orbit is 500 km unless `orbit` is given.
pub fn scenario(orbit: &str, environment: &str, run: &str, body: &str) -> Scenario {
    let orbit = if orbit.is_empty() {
        "altitude_m = 500e3"
    } else {
        orbit
    };
    let text = format!(
        "[scenario]\nname = \"test\"\n\n[orbit]\n{orbit}\n\n[environment]\n{environment}\n\n[run]\n{run}\n\n{body}\n"
    );
    scenario_toml::parse(&text, "<test>").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Path of a file under ../shared (beside the clone), or `None` when `../shared` is not
/// there: the test then prints one line saying it skipped, and returns. A clone on its
/// own passes `cargo test` that way; `.ci/run` sets `ORBITLASH_REQUIRE_SHARED=1`, under
/// which a missing `../shared` fails the test instead (CI has it beside the clone).
pub fn shared(rel: &str) -> Option<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared");
    if root.is_dir() {
        return Some(root.join(rel));
    }
    if std::env::var_os("ORBITLASH_REQUIRE_SHARED").is_some() {
        panic!(
            "{} is missing and ORBITLASH_REQUIRE_SHARED is set: this test needs the spec's recordings",
            root.display()
        );
    }
    eprintln!(
        "SKIPPED: {} is not beside the clone (needed for {rel})",
        root.display()
    );
    None
}

/// `let path = shared_or_return!("cases/null/recording.csv");`: the path, or the test
/// returns after its skip line (see [`shared`]).
#[macro_export]
macro_rules! shared_or_return {
    ($rel:expr) => {
        match common::shared($rel) {
            Some(p) => p,
            None => return,
        }
    };
}

/// The orbitlash binary built for these tests, as an `assert_cmd` command (`.output()`
/// for the raw result, `.assert()` for exit status and output predicates).
pub fn bin() -> assert_cmd::Command {
    assert_cmd::cargo::cargo_bin_cmd!("orbitlash")
}

/// A fresh, empty temporary folder for one test, removed when the test ends well and
/// kept (its path in the failure's output) when the test panics, to be looked at.
pub fn tmpdir(name: &str) -> TestDir {
    let d = std::env::temp_dir().join(format!("orbitlash-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    TestDir(d)
}

/// A test's temporary folder (see [`tmpdir`]): a path that removes its folder when
/// dropped, unless the thread is panicking.
pub struct TestDir(std::path::PathBuf);

impl std::ops::Deref for TestDir {
    type Target = std::path::PathBuf;
    fn deref(&self) -> &std::path::PathBuf {
        &self.0
    }
}

impl AsRef<std::path::Path> for TestDir {
    fn as_ref(&self) -> &std::path::Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for TestDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept for inspection: {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// The reference scenario's text (scenarios/reference-hinge.toml).
pub fn reference_text() -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/reference-hinge.toml"),
    )
    .unwrap()
}

/// The reference scenario with each `(old, new)` replaced once (`old` must occur).
pub fn reference_with(edits: &[(&str, &str)]) -> String {
    let mut text = reference_text();
    for (old, new) in edits {
        assert!(text.contains(old), "`{old}` not in the reference scenario");
        text = text.replacen(old, new, 1);
    }
    text
}

/// The first line of a command's standard error.
pub fn first_error_line(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_default()
        .to_string()
}

/// Asserts a command failed with exit status 2, no panic, and an error whose first
/// line holds every needle.
/// `check` refuses `text` written to `dir/<case>.toml`: its first error line names the
/// file and holds every one of `needles`.
pub fn assert_check_refuses(dir: &std::path::Path, case: &str, text: &str, needles: &[&str]) {
    let file = dir.join(format!("{case}.toml"));
    std::fs::write(&file, text).unwrap();
    let out = bin().arg("check").arg(&file).output().unwrap();
    let name = format!("{case}.toml:");
    let mut all = needles.to_vec();
    all.push(&name);
    assert_error(case, &out, &all);
}

pub fn assert_error(case: &str, out: &std::process::Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{case}: exit status {:?}\n{stderr}",
        out.status
    );
    assert!(!stderr.contains("panicked"), "{case}: panic\n{stderr}");
    let line = first_error_line(out);
    for n in needles {
        assert!(
            line.contains(n),
            "{case}: `{n}` missing from the first error line\n{stderr}"
        );
    }
}

/// Every file under `dir` (recursively) with its bytes, to show nothing changed.
pub fn snapshot(dir: &std::path::Path) -> std::collections::BTreeMap<std::path::PathBuf, Vec<u8>> {
    let mut out = std::collections::BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let meta = std::fs::symlink_metadata(&p).unwrap();
            if meta.is_dir() {
                stack.push(p);
            } else if meta.is_file() {
                out.insert(p.clone(), std::fs::read(&p).unwrap());
            } else {
                out.insert(p.clone(), Vec::new());
            }
        }
    }
    out
}

/// `args` run in `dir`: the binary's raw result.
pub fn run_in(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    bin().args(args).current_dir(dir).output().unwrap()
}

pub fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A shipped scenario's text (`scenarios/<name>`).
pub fn shipped(name: &str) -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenarios")
            .join(name),
    )
    .unwrap()
}

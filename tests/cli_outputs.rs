//! Outputs never replace an input or a non-file, never escape `logs/` by default, and
//! fail before anything is written (issue 8, items 1 and 2).

use std::path::Path;
use std::process::Output;

mod common;
use common::{assert_error, bin, reference_text, reference_with, snapshot, tmpdir};

fn run_in(dir: &Path, args: &[&str]) -> Output {
    bin().args(args).current_dir(dir).output().unwrap()
}

/// A folder with the reference scenario as `s.toml` and a finished log `l.mcap`.
fn setup(name: &str) -> common::TestDir {
    let dir = tmpdir(name);
    std::fs::write(dir.join("s.toml"), reference_text()).unwrap();
    let out = run_in(
        &dir,
        &[
            "run", "s.toml", "--orbits", "1", "--quiet", "--out", "l.mcap",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir
}

/// Runs `args` in a fresh copy of the setup and asserts: exit 2, the first error line
/// names `needles`, and no file in the folder was created, changed or removed.
fn refused(case: &str, args: &[&str], prepare: &dyn Fn(&Path), needles: &[&str]) {
    let dir = setup(case);
    prepare(&dir);
    let before = snapshot(&dir);
    let out = run_in(&dir, args);
    assert_error(case, &out, needles);
    assert_eq!(
        snapshot(&dir),
        before,
        "{case}: files changed although the command was refused"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

fn nothing(_: &Path) {}

#[test]
fn cli_the_log_never_replaces_the_scenario() {
    refused(
        "out-is-input",
        &["run", "s.toml", "--out", "s.toml"],
        &nothing,
        &["s.toml", "input"],
    );
    // by another spelling of the same path, and through a hard link
    refused(
        "out-is-input-dot",
        &["run", "s.toml", "--out", "./s.toml"],
        &nothing,
        &["./s.toml", "input"],
    );
    refused(
        "out-is-hard-link",
        &["run", "s.toml", "--out", "hard.mcap"],
        &|d| std::fs::hard_link(d.join("s.toml"), d.join("hard.mcap")).unwrap(),
        &["hard.mcap", "same file as s.toml"],
    );
}

#[test]
fn cli_the_csv_never_replaces_the_scenario_or_the_log() {
    refused(
        "csv-is-input",
        &["run", "s.toml", "--no-log", "--csv", "s.toml"],
        &nothing,
        &["s.toml", "input"],
    );
    refused(
        "csv-is-log",
        &["run", "s.toml", "--out", "x.mcap", "--csv", "./x.mcap"],
        &nothing,
        &["same file"],
    );
}

/// `environment --csv` and `--plot` on one file: refused like the other commands'
/// outputs (the plot replaced the CSV the command said it wrote; black-box helper-21).
#[test]
fn cli_environment_outputs_never_replace_each_other() {
    refused(
        "environment-csv-is-plot",
        &[
            "environment",
            "s.toml",
            "--plot",
            "./e.svg",
            "--csv",
            "e.svg",
        ],
        &nothing,
        &["--csv", "--plot", "same file"],
    );
}

#[test]
fn cli_outputs_cannot_take_a_temporary_name() {
    // `a.mcap`'s temporary file would be `a.mcap.<pid>.partial`; names ending in
    // `.partial` are reserved
    refused(
        "csv-partial",
        &[
            "run",
            "s.toml",
            "--out",
            "a.mcap",
            "--csv",
            "a.mcap.partial",
        ],
        &nothing,
        &["a.mcap.partial", "reserved"],
    );
    refused(
        "log-partial",
        &[
            "run",
            "s.toml",
            "--out",
            "b.mcap.partial",
            "--csv",
            "b.mcap",
        ],
        &nothing,
        &["b.mcap.partial", "reserved"],
    );
}

#[test]
fn cli_inputs_must_be_regular_files() {
    // a FIFO would block the read forever, a device never end
    let dir = setup("input-fifo");
    let status = std::process::Command::new("mkfifo")
        .arg(dir.join("f.toml"))
        .status()
        .unwrap();
    assert!(status.success());
    for args in [
        vec!["run", "f.toml", "--dry-run"],
        vec!["check", "f.toml"],
        vec!["recover", "f.toml"],
        vec!["export-csv", "/dev/zero"],
    ] {
        let out = run_in(&dir, &args);
        assert_error("input-fifo", &out, &["not a regular file"]);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_a_dry_run_writes_nothing() {
    let dir = setup("dry-run");
    let before = snapshot(&dir);
    let out = run_in(&dir, &["run", "s.toml", "--dry-run", "--csv", "c.csv"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("estimate: about"));
    assert_eq!(snapshot(&dir), before);
    assert!(!dir.join("logs").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_export_never_replaces_its_log() {
    refused(
        "export-over-log",
        &["export-csv", "l.mcap", "--out", "l.mcap"],
        &nothing,
        &["l.mcap", "input"],
    );
}

#[test]
fn cli_devices_fifos_folders_and_links_are_refused() {
    refused(
        "dev-full",
        &["run", "s.toml", "--out", "/dev/full"],
        &nothing,
        &["/dev/full", "device"],
    );
    refused(
        "dev-null-csv",
        &["run", "s.toml", "--no-log", "--csv", "/dev/null"],
        &nothing,
        &["/dev/null", "device"],
    );
    refused(
        "fifo",
        &["run", "s.toml", "--out", "pipe"],
        &|d| {
            let status = std::process::Command::new("mkfifo")
                .arg(d.join("pipe"))
                .status()
                .unwrap();
            assert!(status.success());
        },
        &["pipe", "FIFO"],
    );
    refused(
        "folder",
        &["run", "s.toml", "--out", "sub"],
        &|d| std::fs::create_dir(d.join("sub")).unwrap(),
        &["sub", "directory"],
    );
    // a link to a regular file that is not an input is refused too (documented: no
    // writing through links), and the file it points to is untouched
    refused(
        "link-to-file",
        &["run", "s.toml", "--out", "link.mcap"],
        &|d| std::os::unix::fs::symlink(d.join("l.mcap"), d.join("link.mcap")).unwrap(),
        &["link.mcap", "symbolic link"],
    );
    refused(
        "link-to-input",
        &["export-csv", "l.mcap", "--out", "link.csv"],
        &|d| std::os::unix::fs::symlink(d.join("l.mcap"), d.join("link.csv")).unwrap(),
        &["link.csv", "symbolic link"],
    );
}

#[test]
fn cli_missing_folders_are_created_only_under_logs() {
    refused(
        "no-such-dir",
        &["run", "s.toml", "--out", "missing/x.mcap"],
        &nothing,
        &["missing/x.mcap", "no such directory"],
    );
    refused(
        "no-such-dir-csv",
        &["run", "s.toml", "--no-log", "--csv", "missing/x.csv"],
        &nothing,
        &["no such directory"],
    );
    refused(
        "parent-is-a-file",
        &["run", "s.toml", "--out", "s.toml/x.mcap"],
        &nothing,
        &["s.toml/x.mcap"],
    );
    // A folder that takes no file (here /sys, which refuses files to root as well) is
    // found before the run: nothing is written, the log and the CSV included, where
    // the JSON used to fail only after the whole run, leaving the others written.
    refused(
        "unwritable-json",
        &[
            "run",
            "s.toml",
            "--orbits",
            "1",
            "--out",
            "n.mcap",
            "--csv",
            "n.csv",
            "--json",
            "/sys/n.json",
        ],
        &nothing,
        &["/sys/n.json", "cannot be written in"],
    );
    // plot's default figure folder is created as well
    let dir = setup("default-logs-plot");
    let out = run_in(&dir, &["plot", "l.mcap"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("logs/l.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);
    // the default log's folder is created
    let dir = setup("default-logs");
    let out = run_in(&dir, &["run", "s.toml", "--orbits", "1", "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("logs/reference-hinge.mcap").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_scenario_names_cannot_leave_logs() {
    for (case, name) in [
        ("name-dotdot", "../../etc/evil"),
        ("name-abs", "/abs/path"),
        ("name-slash", "a/b"),
        ("name-space", "a b"),
        ("name-dot", ".hidden"),
        ("name-empty", ""),
    ] {
        let dir = tmpdir(case);
        let text = reference_with(&[("name = \"reference-hinge\"", &format!("name = \"{name}\""))]);
        std::fs::write(dir.join("s.toml"), text).unwrap();
        let before = snapshot(&dir);
        let out = run_in(&dir, &["run", "s.toml", "--orbits", "1", "--quiet"]);
        assert_error(case, &out, &["s.toml", "scenario.name"]);
        assert_eq!(snapshot(&dir), before, "{case}: something was written");
        let _ = std::fs::remove_dir_all(&dir);
    }
    // node names are held to the same rule
    let dir = tmpdir("node-name");
    let text = reference_with(&[("name = \"motor\"", "name = \"mo/tor\"")]);
    std::fs::write(dir.join("s.toml"), text).unwrap();
    let out = run_in(&dir, &["check", "s.toml"]);
    assert_error("node-name", &out, &["node[1].name", "mo/tor"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_recover_never_replaces_its_input() {
    // recovering `x.mcap.partial` into `x.mcap` must not use `x.mcap.partial` as its
    // temporary file
    let dir = setup("recover-tmp");
    let bytes = std::fs::read(dir.join("l.mcap")).unwrap();
    std::fs::write(dir.join("x.mcap.partial"), &bytes[..bytes.len() / 2]).unwrap();
    let out = run_in(&dir, &["recover", "x.mcap.partial", "--out", "x.mcap"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read(dir.join("x.mcap.partial")).unwrap(),
        &bytes[..bytes.len() / 2],
        "the input changed"
    );
    assert!(dir.join("x.mcap").is_file());
    refused(
        "recover-over-input",
        &["recover", "y.mcap", "--out", "y.mcap"],
        &|d| {
            let b = std::fs::read(d.join("l.mcap")).unwrap();
            std::fs::write(d.join("y.mcap"), &b[..b.len() / 2]).unwrap();
        },
        &["y.mcap", "input"],
    );
    // a `logs` that is a file: refused as `run` refuses it, naming the folder (it read
    // "Not a directory (os error 20)"; black-box helper-25)
    refused(
        "recover-logs-file",
        &["recover", "z.mcap"],
        &|d| {
            let b = std::fs::read(d.join("l.mcap")).unwrap();
            std::fs::write(d.join("z.mcap"), &b[..b.len() / 2]).unwrap();
            std::fs::write(d.join("logs"), "").unwrap();
        },
        &["logs", "the default log folder", "regular file"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// An output path with an escape sequence or a line end in it is printed escaped on
/// the success lines too, as errors print it (black-box helper-27: `csv:`, `figure:`
/// and `wrote` printed it raw, so a name could recolour the terminal or split a line),
/// and the file is written under the name given.
#[test]
fn cli_success_lines_escape_control_characters_in_paths() {
    let dir = setup("escaped-paths");
    let name = "we\nird\u{1b}[31m";
    let csv = format!("{name}.csv");
    let svg = format!("{name}.svg");
    for (args, label) in [
        (
            vec![
                "run",
                "s.toml",
                "--orbits",
                "1",
                "--no-log",
                "--csv",
                csv.as_str(),
            ],
            "csv: ",
        ),
        (vec!["plot", "l.mcap", "--out", svg.as_str()], "figure: "),
    ] {
        let out = run_in(&dir, &args);
        let text = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{text}{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(!text.contains('\u{1b}'), "a raw escape: {text:?}");
        assert!(
            text.contains(&format!("{label}we\\u{{a}}ird\\u{{1b}}[31m.")),
            "{text:?}"
        );
    }
    assert!(dir.join(&csv).is_file() && dir.join(&svg).is_file());
    // errors too (review helper-28: main printed the chain as it was), and a scenario
    // read from such a name is named escaped in its report
    let out = run_in(&dir, &["plot", &format!("{name}.missing.csv")]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    // (a line end stays one in an error: a message may have lines of its own)
    assert!(
        !err.contains('\u{1b}') && err.contains("ird\\u{1b}[31m.missing.csv"),
        "{err:?}"
    );
    let toml = format!("{name}.toml");
    std::fs::copy(dir.join("s.toml"), dir.join(&toml)).unwrap();
    let out = run_in(&dir, &["check", &toml]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{text}");
    assert!(
        text.lines()
            .next()
            .unwrap()
            .contains("we\\u{a}ird\\u{1b}[31m.toml"),
        "{text:?}"
    );
}

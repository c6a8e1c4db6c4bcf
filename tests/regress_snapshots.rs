//! Snapshots (insta) of the human reports for the shipped reference scenario: a change of
//! wording, layout or of a printed number shows as a diff against `tests/snapshots/`.
//! Each snapshot's description is the command that produced it (run from the clone's
//! root). Review a change with `cargo insta review`, or accept it with
//! `INSTA_UPDATE=always cargo test --release --test regress_snapshots`, and say why in the
//! commit.

mod common;
use common::bin;

/// Standard output of `orbitlash ARGS` run in the clone's root; it must exit with `code`.
fn report(args: &[&str], code: i32) -> String {
    let out = bin()
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(code),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn snapshot(name: &str, args: &[&str]) {
    let text = report(args, 0);
    insta::with_settings!({
        description => format!("orbitlash {}", args.join(" ")),
        omit_expression => true,
    }, {
        insta::assert_snapshot!(name, text);
    });
}

#[test]
fn regress_snapshot_run_summary() {
    snapshot("run_summary", &["run", "--no-log"]);
}

#[test]
fn regress_snapshot_check() {
    snapshot("check", &["check", "scenarios/reference-hinge.toml"]);
}

#[test]
fn regress_snapshot_backlash() {
    snapshot("backlash", &["backlash"]);
}

#[test]
fn regress_snapshot_params() {
    snapshot("params", &["params"]);
}

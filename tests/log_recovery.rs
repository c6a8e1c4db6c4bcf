//! A killed run's log is readable: cut at many offsets, a log gives back every message
//! it holds whole, `export-csv` reads it saying how much, and `recover` writes a valid
//! MCAP file of it (issue 8, item 7).

use std::path::Path;

mod common;
use common::{bin, tmpdir};
use orbitlash::io::mcap_read::read_log;
use orbitlash::io::mcap_scan::scan;

/// A reference run's log (2 orbits, every step).
fn full_log(dir: &Path) -> Vec<u8> {
    let out = bin()
        .args(["run", "--orbits", "2", "--quiet", "--out"])
        .arg(dir.join("full.mcap"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::read(dir.join("full.mcap")).unwrap()
}

/// Where each message record of an MCAP file ends, and where its data section ends
/// (after the DataEnd record), found by walking the file with the spec's layout
/// directly (not with the scanner under test): top-level records, and inside each chunk
/// its records.
fn message_ends(b: &[u8]) -> (Vec<usize>, usize) {
    let u64_at = |i: usize| u64::from_le_bytes(b[i..i + 8].try_into().unwrap()) as usize;
    let u32_at = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap()) as usize;
    let mut ends = Vec::new();
    let mut at = 8;
    while at + 9 <= b.len() {
        let (op, len) = (b[at], u64_at(at + 1));
        let body = at + 9;
        match op {
            0x05 => ends.push(body + len),
            0x06 => {
                // start, end, uncompressed size, crc, compression, records length
                let name_len = u32_at(body + 28);
                let records = body + 32 + name_len + 8;
                let mut r = records;
                while r < body + len {
                    let (rop, rlen) = (b[r], u64_at(r + 1));
                    if rop == 0x05 {
                        ends.push(r + 9 + rlen);
                    }
                    r += 9 + rlen;
                }
            }
            0x0F => return (ends, body + len), // data end
            _ => {}
        }
        at = body + len;
    }
    panic!("no DataEnd record")
}

#[test]
fn cli_a_log_cut_anywhere_gives_back_every_whole_message() {
    let dir = tmpdir("recovery-cuts");
    let bytes = full_log(&dir);
    let (ends, data_end) = message_ends(&bytes);
    let full = scan(&bytes).unwrap();
    assert!(full.complete);
    assert_eq!(full.messages.len(), ends.len());
    // 50 offsets spread over the file, plus a few on and next to record boundaries
    let mut cuts: Vec<usize> = (1..=50).map(|k| k * bytes.len() / 51).collect();
    cuts.extend([ends[10], ends[10] - 1, ends[10] + 1, 9, 100]);
    cuts.sort();
    let mut last = 0;
    for &cut in &cuts {
        let part = &bytes[..cut];
        let s = scan(part).unwrap_or_else(|e| panic!("cut at {cut}: {e}"));
        // a cut in the summary section leaves the data section whole, but the file
        // is not complete (readers that need the summary fail on it)
        assert_eq!(s.data_complete, cut >= data_end, "cut at {cut}");
        assert!(!s.complete, "cut at {cut}");
        // every message whose record lies whole before the cut, and no other. (The first
        // chunk's header must be whole too; a chunk header is 49 bytes here.)
        let want = ends.iter().filter(|&&e| e <= cut).count();
        let got = s.messages.len();
        assert!(
            got == want || (got < want && ends[got] + 49 > cut),
            "cut at {cut}: {got} messages recovered, {want} lie whole before the cut"
        );
        for (a, b) in s.messages.iter().zip(&full.messages) {
            assert_eq!(a.data, b.data, "cut at {cut}: a message differs");
            assert_eq!(a.header.log_time, b.header.log_time);
        }
        assert!(got >= last, "fewer messages from a longer file");
        last = got;
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_export_reads_a_cut_log_and_recover_makes_it_valid() {
    let dir = tmpdir("recovery-cli");
    let bytes = full_log(&dir);
    let cut = bytes.len() * 3 / 5;
    let partial = dir.join("run.mcap.partial");
    std::fs::write(&partial, &bytes[..cut]).unwrap();

    let out = bin().arg("export-csv").arg(&partial).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let note = String::from_utf8_lossy(&out.stderr);
    assert!(
        note.contains("was cut off: read") && note.contains("messages up to t ="),
        "{note}"
    );
    let csv = String::from_utf8_lossy(&out.stdout).to_string();
    let full_csv = bin()
        .arg("export-csv")
        .arg(dir.join("full.mcap"))
        .output()
        .unwrap()
        .stdout;
    let full_csv = String::from_utf8_lossy(&full_csv);
    // the rows read are the full log's rows (the last may lack topics cut off)
    let rows: Vec<&str> = csv.lines().collect();
    assert!(rows.len() > 100);
    for (a, b) in rows.iter().zip(full_csv.lines()).take(rows.len() - 1) {
        assert_eq!(a, &b);
    }

    let out = bin()
        .arg("recover")
        .arg(&partial)
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("recovered") && text.contains("wrote logs/run.recovered.mcap"),
        "{text}"
    );
    let recovered = dir.join("logs/run.recovered.mcap");
    let r = std::fs::read(&recovered).unwrap();
    // a valid, complete MCAP file with a summary, readable by the mcap crate's reader
    assert!(mcap::Summary::read(&r).unwrap().is_some());
    let s = scan(&r).unwrap();
    assert!(s.complete);
    assert_eq!(
        s.metadata_value("orbitlash.run_end", "status"),
        Some("recovered")
    );
    assert!(
        s.metadata_value("orbitlash.provenance", "scenario_sha256")
            .is_some()
    );
    let table = read_log(&recovered).unwrap();
    assert!(table.truncated.is_none());
    assert_eq!(table.rows.len() + 1, rows.len());

    // asked to stop while writing (Ctrl-C: `recover` passes its interrupt flag), the
    // copy is not written, and neither is its temporary file left behind
    let s = scan(&bytes[..cut]).unwrap();
    assert!(s.messages.len() > 256, "{} messages", s.messages.len());
    let out = dir.join("stopped/run.recovered.mcap");
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    let policy = orbitlash::io::output::OutputPolicy::reading(&[&partial]);
    let err = orbitlash::io::mcap_scan::recover(&s, &out, &policy, None, &|| true).unwrap_err();
    let chain = format!(
        "{err}: {}",
        std::error::Error::source(&err).map_or(String::new(), |c| c.to_string())
    );
    assert!(
        chain.contains("interrupted: nothing was written"),
        "{chain}"
    );
    let left: Vec<_> = std::fs::read_dir(out.parent().unwrap()).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_a_complete_log_needs_no_recovery_and_garbage_is_refused() {
    let dir = tmpdir("recovery-complete");
    full_log(&dir);
    let out = bin()
        .arg("recover")
        .arg(dir.join("full.mcap"))
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("nothing to recover"));
    assert!(!dir.join("logs").exists());
    std::fs::write(dir.join("junk.mcap"), b"not an mcap file at all").unwrap();
    let out = bin()
        .arg("recover")
        .arg(dir.join("junk.mcap"))
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not an MCAP file"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `orbitlash` with `args` in `dir`.
fn cli(dir: &Path, args: &[&str]) -> std::process::Output {
    bin().args(args).current_dir(dir).output().unwrap()
}

#[test]
fn cli_a_log_cut_in_its_summary_is_rewritten_whole() {
    let dir = tmpdir("recovery-summary");
    let bytes = full_log(&dir);
    let (ends, data_end) = message_ends(&bytes);
    std::fs::write(dir.join("s.mcap"), &bytes[..(data_end + bytes.len()) / 2]).unwrap();
    let out = cli(&dir, &["recover", "s.mcap", "--out", "r.mcap"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = std::fs::read(dir.join("r.mcap")).unwrap();
    assert!(mcap::Summary::read(&r).unwrap().is_some());
    let s = scan(&r).unwrap();
    assert!(s.complete);
    assert_eq!(s.messages.len(), ends.len(), "every message kept");
    // the original run_end (complete) is kept
    assert_eq!(
        s.metadata_value("orbitlash.run_end", "status"),
        Some("complete")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_a_zero_filled_tail_ends_the_data() {
    // A power loss can leave the end of a file as zeros: the messages before them are
    // recovered, the zeros (and a message cut by them) are not taken for data.
    let dir = tmpdir("recovery-zeros");
    let bytes = full_log(&dir);
    let (ends, _) = message_ends(&bytes);
    let cut = (ends[40] + ends[41]) / 2; // inside message 41
    let mut z = bytes[..cut].to_vec();
    z.extend(std::iter::repeat_n(0u8, 8192));
    std::fs::write(dir.join("z.mcap"), &z).unwrap();
    let out = cli(&dir, &["export-csv", "z.mcap"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(!csv.contains("NaN"), "a half row was exported:\n{csv}");
    let out = cli(&dir, &["recover", "z.mcap", "--out", "r.mcap"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = std::fs::read(dir.join("r.mcap")).unwrap();
    let s = scan(&r).unwrap();
    assert_eq!(s.messages.len(), 41);
    let again = cli(&dir, &["export-csv", "r.mcap"]);
    assert!(again.status.success());
    assert!(String::from_utf8_lossy(&again.stdout).starts_with("time_s,"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_a_log_cut_before_its_first_message_is_a_clear_error() {
    let dir = tmpdir("recovery-early");
    let bytes = full_log(&dir);
    let (ends, _) = message_ends(&bytes);
    std::fs::write(dir.join("e.mcap"), &bytes[..ends[0] - 1]).unwrap();
    std::fs::write(dir.join("empty.mcap"), &bytes[..5]).unwrap();
    for (file, needle) in [
        ("e.mcap", "before its first whole message"),
        ("empty.mcap", "nothing was written"),
    ] {
        for cmd in ["recover", "export-csv"] {
            let out = cli(&dir, &[cmd, file]);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{cmd} {file}: {stderr}");
            assert!(stderr.contains(needle), "{cmd} {file}: {stderr}");
        }
    }
    assert!(!dir.join("logs").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_a_killed_runs_partial_log_survives_the_next_run() {
    let dir = tmpdir("recovery-keep");
    std::fs::create_dir(dir.join("logs")).unwrap();
    let left = dir.join("logs/reference-hinge.mcap.4242.partial");
    std::fs::write(&left, b"\x89MCAP0\r\n half a log").unwrap();
    let out = cli(&dir, &["run", "--orbits", "1", "--quiet"]);
    assert!(out.status.success());
    assert_eq!(std::fs::read(&left).unwrap(), b"\x89MCAP0\r\n half a log");
    assert!(dir.join("logs/reference-hinge.mcap").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

//! Damaged length fields (issue 27 item 12): a length made huge at every offset of a
//! small log is an error from every reader, never an allocation of what the length
//! says. The test runs under an address-space limit of 2 GiB, so a reader that trusted
//! a length would fail to allocate and abort the process (the test fails).

mod common;
use common::{bin, tmpdir};

use orbitlash::io::mcap_read::read_log;
use orbitlash::io::mcap_scan::scan;
use orbitlash::io::recording::Recording;

#[test]
fn core_every_damaged_length_is_an_error_not_an_abort() {
    let dir = tmpdir("len-fuzz");
    let log = dir.join("small.mcap");
    let out = bin()
        .args([
            "run",
            "--quiet",
            "--orbits",
            "0.2",
            "--log-every",
            "600s",
            "--out",
        ])
        .arg(&log)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let good = std::fs::read(&log).unwrap();
    assert!(read_log(&log).is_ok());
    // 2 GiB of address space: a 4 GB allocation fails (and aborts) under it
    // (the hard limit kept: lowering the soft one needs no privilege)
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    assert_eq!(unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut limit) }, 0);
    limit.rlim_cur = limit.rlim_max.min(2 << 30);
    assert_eq!(unsafe { libc::setrlimit(libc::RLIMIT_AS, &limit) }, 0);
    let damaged = dir.join("damaged.mcap");
    let (mut refused, mut read) = (0, 0);
    for pattern in [&[0xff, 0xff, 0xff, 0x7f][..], &[0xff; 8][..]] {
        for at in 0..=good.len() - pattern.len() {
            let mut bytes = good.clone();
            bytes[at..at + pattern.len()].copy_from_slice(pattern);
            let _ = scan(&bytes);
            std::fs::write(&damaged, &bytes).unwrap();
            match read_log(&damaged) {
                Ok(_) => read += 1,
                Err(e) => {
                    refused += 1;
                    assert!(!e.to_string().is_empty());
                }
            }
            let _ = Recording::read(&damaged);
        }
    }
    // both sides reached: damage the reader refuses, and damage in values it reads
    assert!(refused > 100 && read > 0, "{refused} refused, {read} read");
    let _ = std::fs::remove_dir_all(&dir);
}

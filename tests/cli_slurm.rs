//! `deploy/slurm/submit.sh` as shipped, on a real single-node Slurm
//! (`../shared/tools/slurm-local.sh`): the job array and the dependent merge give the
//! unsharded `margins` report byte for byte. Installing Slurm needs root and the Debian
//! archive, so this test is run by `.ci/run` (`cargo test --release --test cli_slurm --
//! --ignored`); it says so and passes where Slurm cannot be installed (status 3),
//! except under `ORBITLASH_REQUIRE_SLURM=1` (set by `.ci/run`), where that fails.

mod common;
use common::{bin, reference_text, tmpdir};

#[test]
#[ignore = "needs a local Slurm (run by .ci/run)"]
fn cli_slurm_submit_merges_to_the_unsharded_report() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let slurm = shared_or_return!("tools/slurm-local.sh");
    let dir = tmpdir("slurm");
    let text = reference_text()
        + "\n[[dispersion]]\npath = \"gear_pair.mesh.pinion.tooth_thinning_um\"\ndistribution = \"uniform\"\nmin = 16.0\nmax = 23.0\n";
    std::fs::write(dir.join("m.toml"), text).unwrap();
    let margins = ["--samples", "61", "--seed", "12"];
    let out = bin()
        .args(["margins", "m.toml"])
        .args(margins)
        .args(["--orbits", "1", "--quiet", "--json", "unsharded.json"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let out_dir = dir.join("cluster");
    let script = format!(
        "{submit} {scenario} --samples 61 --seed 12 --shards 4 --out {out} -- --orbits 1 && \
         for i in $(seq 1 600); do [ -f {out}/margins.json ] && exit 0; sleep 0.5; done; \
         squeue -h -r -t all -o '%i %T'; exit 1",
        submit = root.join("deploy/slurm/submit.sh").display(),
        scenario = dir.join("m.toml").display(),
        out = out_dir.display(),
    );
    let run = std::process::Command::new(&slurm)
        .args(["run", "--", "bash", "-c", &script])
        .env("ORBITLASH_BIN", env!("CARGO_BIN_EXE_orbitlash"))
        .output()
        .unwrap();
    if run.status.code() == Some(3) {
        // On a laptop a skip is fine; `.ci/run` sets ORBITLASH_REQUIRE_SLURM=1, and
        // there a skip is a failure.
        assert!(
            std::env::var_os("ORBITLASH_REQUIRE_SLURM").is_none(),
            "Slurm could not be installed or started, and ORBITLASH_REQUIRE_SLURM is set:\n{}",
            String::from_utf8_lossy(&run.stderr)
        );
        eprintln!(
            "SKIPPED: Slurm could not be installed or started here:\n{}",
            String::from_utf8_lossy(&run.stderr)
        );
        return;
    }
    assert!(
        run.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        stdout.contains("array job") && stdout.contains("merge job"),
        "{stdout}"
    );
    for i in 0..4 {
        assert!(out_dir.join(format!("shard-{i}.json")).is_file());
    }
    assert_eq!(
        std::fs::read(out_dir.join("margins.json")).unwrap(),
        std::fs::read(dir.join("unsharded.json")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

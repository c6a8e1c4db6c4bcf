#!/usr/bin/env python3
"""Byte-for-byte comparison of two orbitlash binaries' outputs (for changes that must
not move a number, e.g. a refactor): `run` (text, JSON, CSV, MCAP log), `margins --json`
and `diagnose --json` on the shipped scenarios and example recordings (and on
`../shared/cases` when it is there); `params` listings and the `check --set` errors of
every key at four values. Both binaries must have the same file name (usage texts
quote it), e.g. `/tmp/before/orbitlash` and `target/release/orbitlash`.

    python3 tools/compare_outputs.py BEFORE_BINARY AFTER_BINARY [WORK_DIR]

Wall-clock timings (`wall_time_s`, `time_s`, "... s of computing") are the only
differences allowed; every other byte must agree. Exit status 0 when all agree.
"""
import json
import pathlib
import re
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
TIMING_KEYS = {"wall_time_s", "time_s", "wall_s", "time_per_candidate_s"}


def strip_timings(v):
    if isinstance(v, dict):
        return {k: strip_timings(x) for k, x in v.items() if k not in TIMING_KEYS}
    if isinstance(v, list):
        return [strip_timings(x) for x in v]
    return v


def text_without_timings(b: bytes) -> str:
    t = b.decode("utf-8", "replace")
    t = re.sub(r"[0-9.]+ (s|ms|min) of computing", "<time>", t)
    t = re.sub(r"wall[^\n]*", "<wall>", t)
    t = re.sub(r"in [0-9.]+ s\b", "in <time>", t)
    t = re.sub(r"time: [0-9.]+ s \([0-9.]+ s per candidate\)", "time: <time>", t)
    return t


def cases(out: pathlib.Path):
    sc = ROOT / "scenarios"
    rec = ROOT / "examples" / "recordings"
    for name in ["reference-hinge", "hinge-90-day-drift"]:
        p = out / name
        yield name + " run", ["run", str(sc / f"{name}.toml"), "--json", f"{p}.json",
                              "--csv", f"{p}.csv", "--out", f"{p}.mcap"], [f"{p}.json", f"{p}.csv", f"{p}.mcap"]
    # the dated scenarios (faces, TLE orbits, attitudes) over a few orbits
    for name in ["cubesat-1u", "hinge-tle-year", "funcube-1"]:
        p = out / name
        yield name + " run", ["run", str(sc / f"{name}.toml"), "--orbits", "3", "--json", f"{p}.json",
                              "--csv", f"{p}.csv", "--out", f"{p}.mcap"], [f"{p}.json", f"{p}.csv", f"{p}.mcap"]
    p = out / "margins-steady"
    yield "margins steady", ["margins", str(sc / "reference-hinge-margins.toml"), "--samples", "200",
                             "--seed", "7", "--json", f"{p}.json"], [f"{p}.json"]
    p = out / "margins-mission"
    yield "margins mission", ["margins", str(sc / "hinge-90-day-margins.toml"), "--samples", "4",
                              "--seed", "7", "--mission", "--json", f"{p}.json"], [f"{p}.json"]
    for r in ["heater-housing", "null"]:
        p = out / f"diagnose-{r}"
        yield f"diagnose {r}", ["diagnose", str(sc / "reference-hinge.toml"), "--recording", str(rec / f"{r}.csv"),
                                "--json", f"{p}.json"], [f"{p}.json"]
    # FUNcube-1's day of flight telemetry
    flight = ROOT.parent / "shared" / "data" / "funcube-1" / "funcube1_wod_2016-02-04.csv"
    if flight.is_file():
        p = out / "diagnose-funcube-1"
        yield "diagnose funcube-1 flight", ["diagnose", str(sc / "funcube-1.toml"), "--recording", str(flight),
                                            "--json", f"{p}.json"], [f"{p}.json"]
    shared = ROOT.parent / "shared" / "cases"
    for case in sorted(d.name for d in shared.iterdir()) if shared.is_dir() else []:
        p = out / f"diagnose-shared-{case}"
        yield f"diagnose shared {case}", ["diagnose", str(sc / "reference-hinge.toml"), "--recording",
                                          str(shared / case / "recording.csv"), "--json", f"{p}.json"], [f"{p}.json"]


def check_cases(binary: str):
    """`params` of every shipped scenario, and `check --set KEY=V` on the reference for
    every key `params` lists at four values (huge, tiny, zero, negative): the check
    errors of the spec layer, byte for byte."""
    sc = ROOT / "scenarios"
    for f in sorted(sc.glob("*.toml")):
        yield f"params {f.stem}", ["params", str(f)]
    listing = subprocess.run([binary, "params"], capture_output=True, text=True).stdout
    keys = sorted({line.split()[0] for line in listing.splitlines()
                   if len(line.split()) > 1 and line.split()[1] == "="})
    for k in keys:
        for v in ["-1e30", "1e30", "0", "-0.5"]:
            yield f"check {k}={v}", ["check", str(sc / "reference-hinge.toml"), "--set", f"{k}={v}"]


def run_checks(binary: str):
    """Exit status and output of each of `check_cases`, as one dictionary."""
    out = {}
    for label, args in check_cases(binary):
        r = subprocess.run([binary, *args], capture_output=True)
        out[label] = (r.returncode, r.stdout, r.stderr)
    return out


def run_all(binary: str, out: pathlib.Path):
    out.mkdir(parents=True, exist_ok=True)
    results = {}
    for label, args, files in cases(out):
        r = subprocess.run([binary, *args], capture_output=True, cwd=out)
        got = {"exit": r.returncode,
               "stdout": text_without_timings(r.stdout.replace(str(out).encode(), b"<dir>")),
               "stderr": text_without_timings(r.stderr.replace(str(out).encode(), b"<dir>"))}
        for f in files:
            data = pathlib.Path(f).read_bytes()
            if f.endswith(".json"):
                got[pathlib.Path(f).name] = strip_timings(json.loads(data))
            else:
                got[pathlib.Path(f).name] = data
        results[label] = got
    return results


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    work = pathlib.Path(sys.argv[3]) if len(sys.argv) > 3 else pathlib.Path(tempfile.mkdtemp())
    before = run_all(str(pathlib.Path(sys.argv[1]).resolve()), work / "before")
    after = run_all(str(pathlib.Path(sys.argv[2]).resolve()), work / "after")
    bad = 0
    for label in before:
        for k in before[label]:
            same = before[label][k] == after[label].get(k)
            if not same:
                bad += 1
                print(f"DIFFERENT  {label}: {k}")
        print(f"{'same' if all(before[label][k] == after[label].get(k) for k in before[label]) else 'DIFF'}  {label}")
    # The binaries must be called by the same name: usage texts quote it.
    cb = run_checks(str(pathlib.Path(sys.argv[1]).resolve()))
    ca = run_checks(str(pathlib.Path(sys.argv[2]).resolve()))
    differing = [k for k in cb if cb[k] != ca.get(k)]
    for k in differing:
        print(f"DIFFERENT  {k}")
    bad += len(differing)
    print(f"{'same' if not differing else 'DIFF'}  params listings and {len(cb)} check --set errors")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

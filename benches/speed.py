#!/usr/bin/env python3
"""The speed figures of issue 31, measured in one go and written into
docs/performance.md (between the `<!-- bench:speed -->` markers), machine named.

    python3 benches/speed.py [--binary target/release/orbitlash] [--python .venv/bin/python]
                             [--quick] [--no-write]

Build first (`cargo build --release`). What it measures, each as the median of
repeated whole processes:

1. per orbit of the reference run: the solver alone (`orbitlash bench`), `run` without
   and with its MCAP log over 600 orbits, and scipy's Radau on the same network
   (`benches/scipy_radau_reference.py`, when the Python given has scipy);
2. per orbit of `hinge-tle-year` (300 orbits, no log) with its conical shadow, with a
   cylindrical one, and of the same scenario on a circular orbit of its mean altitude
   and starting β (written to a temporary file);
3. `margins` of the 90-day mission on 1 thread and on every core (`orbitlash bench
   --margins --margins-horizon mission`), with the parallel efficiency; and of
   `hinge-tle-year` (200 orbits, its tooth thinnings dispersed as the mission's), whose
   threads all read one shared table of the orbit.

`--quick` uses fewer repetitions and samples (for a check that the script runs).
"""
import argparse
import json
import os
import pathlib
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
START, END = "<!-- bench:speed -->", "<!-- /bench:speed -->"


def wall(cmd, repeat):
    """Median wall time of `cmd` run `repeat` times, s (stdout and stderr dropped)."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def machine():
    model = platform.processor() or "?"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{os.cpu_count()} × {model}, {platform.system()} {platform.release()}"


def circular_twin(tle_toml: pathlib.Path, binary: str) -> pathlib.Path:
    """The TLE scenario on a circular orbit of its mean altitude and starting β."""
    check = subprocess.run([binary, "check", str(tle_toml)], capture_output=True, text=True).stdout
    lo, hi = map(float, re.search(r"altitude\s+([\d.]+) … ([\d.]+) km", check).groups())
    beta = float(re.search(r"β at the start\s+([-\d.]+)°", check).group(1))
    text = tle_toml.read_text()
    text = re.sub(r"\[orbit\]\n.*?\n\n", f"[orbit]\naltitude_m = {0.5 * (lo + hi) * 1e3:.1f}\n\n",
                  text, flags=re.S)
    text = text.replace("[environment]\n", f"[environment]\nbeta_deg = {beta}\n", 1)
    out = pathlib.Path(tempfile.mkdtemp()) / "tle-circular.toml"
    out.write_text(text)
    return out


def with_dispersions(toml: pathlib.Path, source: pathlib.Path) -> pathlib.Path:
    """`toml` with the tooth-thinning [[dispersion]] entries of `source` appended."""
    entries = [e for e in source.read_text().split("[[dispersion]]")[1:]
               if "tooth_thinning_um" in e.split("\n", 2)[1]]
    text = toml.read_text() + "".join("\n[[dispersion]]" + e.split("\n\n")[0] + "\n"
                                      for e in entries)
    out = pathlib.Path(tempfile.mkdtemp()) / "tle-dispersed.toml"
    out.write_text(text)
    return out


def with_shadow(tle_toml: pathlib.Path, shadow: str) -> pathlib.Path:
    text = re.sub(r'^shadow = ".*"$', f'shadow = "{shadow}"', tle_toml.read_text(), flags=re.M)
    out = pathlib.Path(tempfile.mkdtemp()) / f"tle-{shadow}.toml"
    out.write_text(text)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", default=str(ROOT / "target/release/orbitlash"))
    ap.add_argument("--python", default=str(ROOT / ".venv/bin/python"))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--no-write", action="store_true")
    a = ap.parse_args()
    b = a.binary
    rep = 3 if a.quick else 9
    tmp = pathlib.Path(tempfile.mkdtemp())
    rows = []

    # 1. the reference run
    out = subprocess.run([b, "bench", "--repeat", "9" if a.quick else "31", "--no-accuracy"],
                         capture_output=True, text=True, check=True).stdout
    solver_us = float(re.search(r"([\d.]+) µs per orbit", out).group(1))
    orbits = 100 if a.quick else 600
    no_log = wall([b, "run", "--quiet", "--no-log", "--orbits", str(orbits)], rep) / orbits
    log = wall([b, "run", "--quiet", "--out", str(tmp / "r.mcap"), "--orbits", str(orbits)],
               rep) / orbits
    scipy_ms = None
    if pathlib.Path(a.python).exists():
        r = subprocess.run([a.python, str(ROOT / "benches/scipy_radau_reference.py"),
                            "--repeat", "3" if a.quick else "5", "--json", str(tmp / "s.json")],
                           capture_output=True, text=True)
        if r.returncode == 0:
            scipy_ms = json.loads((tmp / "s.json").read_text())["ms_per_orbit"]
    times = lambda s: f"{scipy_ms / (s * 1e3):.0f}×" if scipy_ms else "–"
    rows.append("| what (reference hinge) | per orbit | × scipy Radau |")
    rows.append("|---|---|---|")
    rows.append(f"| scipy Radau, rtol 1e-6, piecewise, analytic Jacobian | "
                f"{scipy_ms:.2f} ms | 1× |" if scipy_ms else "| scipy Radau | not run (no scipy) | – |")
    rows.append(f"| solver alone (`orbitlash bench`) | {solver_us:.1f} µs | {times(solver_us * 1e-6)} |")
    rows.append(f"| `run --no-log`, {orbits} orbits | {no_log * 1e6:.0f} µs | {times(no_log)} |")
    rows.append(f"| `run` with its log, {orbits} orbits | {log * 1e6:.0f} µs | {times(log)} |")
    rows.append("")

    # 2. real orbits
    tle = ROOT / "scenarios/hinge-tle-year.toml"
    n = 100 if a.quick else 300
    cases = [("circular twin", circular_twin(tle, b)), ("TLE, cylindrical", with_shadow(tle, "cylindrical")),
             ("TLE, conical (shipped)", tle)]
    per = {}
    for name, f in cases:
        per[name] = wall([b, "run", str(f), "--quiet", "--no-log", "--orbits", str(n)], rep) / n
    rows.append(f"| orbit (`hinge-tle-year`, {n} orbits, no log) | per orbit | × circular |")
    rows.append("|---|---|---|")
    for name, _ in cases:
        rows.append(f"| {name} | {per[name] * 1e3:.3f} ms | {per[name] / per['circular twin']:.2f} |")
    rows.append("")

    # 3. margins on cores
    samples = "4" if a.quick else "24"
    out = subprocess.run([b, "bench", "scenarios/hinge-90-day-margins.toml", "--margins",
                          "--samples", samples, "--margins-horizon", "mission", "--repeat", "1"],
                         capture_output=True, text=True, check=True, cwd=ROOT).stdout
    rows.append(f"`margins` of the 90-day mission, {samples} samples:")
    rows.append("")
    rows += ["    " + l for l in out.strip().splitlines()]
    rows.append("")

    # 3b. margins on a TLE orbit: every thread reads one shared table of the orbit
    tle_disp = with_dispersions(tle, ROOT / "scenarios/hinge-90-day-margins.toml")
    out = subprocess.run([b, "bench", str(tle_disp), "--margins", "--samples", samples,
                          "--margins-horizon", "200", "--repeat", "1"],
                         capture_output=True, text=True, check=True, cwd=ROOT).stdout
    out = out.replace(str(tle_disp), "hinge-tle-year.toml + the thinnings")
    rows.append(f"`margins` of `hinge-tle-year` (200 orbits each, the two tooth thinnings of "
                f"the 90-day mission dispersed), {samples} samples:")
    rows.append("")
    rows += ["    " + l for l in out.strip().splitlines()]

    block = "\n".join([START, "", f"Machine: {machine()}; {time.strftime('%Y-%m-%d')}, "
                       f"`python3 benches/speed.py`.", ""] + rows + ["", END])
    print(block)
    if not a.no_write:
        doc = ROOT / "docs/performance.md"
        text = doc.read_text()
        if START in text and END in text:
            text = text[:text.index(START)] + block + text[text.index(END) + len(END):]
        else:
            text = text.rstrip("\n") + "\n\n### Measured by `benches/speed.py`\n\n" + block + "\n"
        tmp_doc = doc.with_suffix(".md.partial")
        tmp_doc.write_text(text)
        os.replace(tmp_doc, doc)


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Tests of the Python helpers viewer/rerun_export.py, tests/viewer/check_log.py and
tests/viewer/rerun_screenshot.py, on logs made here with the orbitlash binary.

    python tests/viewer/test_helpers.py [path/to/orbitlash]

(default binary: target/release/orbitlash). Needs the pinned clients of
tests/viewer/requirements.txt. Works in a temporary folder, prints one line per check
(PASS or FAIL, its name, why it failed) and ends with `N passed, M failed`; exit 0 when
none failed, 1 when some did, 2 when the checks could not start.

What they check:
- requirements: viewer/requirements.txt and tests/viewer/requirements.txt pin the same;
- a missing package: both scripts name it in one line and exit 2;
- `-o`: the export refuses (exit 2, one line naming the path) to write over the log
  (through a symlink or a hard link), a symlink, a directory, a FIFO, a file that is not
  an .rrd (a scenario .toml: only with --force) or through a `.partial` that links to
  the log; it writes over a previous .rrd and beside the log by default; a failure
  removes the .partial and leaves the previous .rrd as it was; the screenshot script
  refuses a screenshot path that is the log;
- chunk CRCs: a byte flipped inside a chunk makes the export exit 2 (the previous .rrd
  untouched) and check_log.py fail;
- the run's smallest backlash: from run_end's pairs_json (value, time, verdict, the
  smallest allowed line) when the log has it, from the samples when it does not; on
  logs written here in Python (the binary's log, with a smallest below every sample),
  and on the binary's own log when it writes pairs_json (a SKIP line when not).
"""
import contextlib
import importlib.util
import io
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
EXPORT = os.path.join(ROOT, "viewer", "rerun_export.py")
CHECK_LOG = os.path.join(HERE, "check_log.py")
SCREENSHOT = os.path.join(HERE, "rerun_screenshot.py")
PY = sys.executable
RRD_MAGIC = b"RRF2"  # the first bytes of an .rrd written by rerun-sdk 0.41

results = {"passed": 0, "failed": 0}


class Failed(Exception):
    pass


def expect(condition, why):
    if not condition:
        raise Failed(why)


def check(name, test, *args):
    """Runs one check; one line: PASS name, or FAIL name: why."""
    try:
        test(*args)
    except Exception as e:  # a failed expectation, or the check itself broke
        results["failed"] += 1
        why = str(e) if isinstance(e, Failed) else f"{type(e).__name__}: {e}"
        print(f"FAIL {name}: {' '.join(why.split())[:400]}")
        return
    results["passed"] += 1
    print(f"PASS {name}")


def run(cmd, env=None, timeout=300):
    """The finished process (stdout, stderr, returncode); returncode None on a timeout."""
    try:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return subprocess.CompletedProcess(cmd, None, "", f"timed out after {timeout} s")


def export(*args, env=None):
    return run([PY, EXPORT, *args], env=env)


def read(path):
    with open(path, "rb") as f:
        return f.read()


def shown(p):
    return f"exit {p.returncode}, stderr {p.stderr.strip()[-300:]!r}"


def expect_refused(p, path):
    """Exit 2 and one line on stderr that names the path."""
    lines = p.stderr.strip().splitlines()
    expect(p.returncode == 2 and len(lines) == 1 and path in lines[0],
           f"wanted exit 2 and one line naming {path}; got {shown(p)}")


# ---- logs ------------------------------------------------------------------------------

def make_logs(binary, tmp):
    """The reference run logged at every step, and logged every 3600 s."""
    ref = os.path.join(tmp, "ref.mcap")
    sparse = os.path.join(tmp, "sparse.mcap")
    for cmd in ([binary, "run", "--quiet", "--out", ref],
                [binary, "run", "--quiet", "--log-every", "3600s", "--out", sparse]):
        p = run(cmd)
        if p.returncode != 0:
            raise SystemExit(f"cannot make a log: {' '.join(cmd)}: {shown(p)}")
    return ref, sparse


def case_dir(tmp, name, log):
    """A folder of its own for one check, with a copy of the log to put at risk."""
    d = os.path.join(tmp, name)
    os.mkdir(d)
    copy = os.path.join(d, "log.mcap")
    shutil.copyfile(log, copy)
    return d, copy


def u(data, at, n):
    return int.from_bytes(data[at:at + n], "little")


def varint(b, i):
    v = shift = 0
    while True:
        c = b[i]
        i += 1
        v |= (c & 0x7F) << shift
        shift += 7
        if c < 0x80:
            return v, i


def doubles_of(b, i, end):
    """Offsets of the 8-byte fields (protobuf wire type 1: double) of one message."""
    found = []
    while i < end:
        key, i = varint(b, i)
        wire = key & 7
        if wire == 1:
            found.append(i)
            i += 8
        elif wire == 0:
            _, i = varint(b, i)
        elif wire == 2:
            n, i = varint(b, i)
            i += n
        elif wire == 5:
            i += 4
        else:
            break
    return found


def flip_in_chunk(src, dst):
    """Copies the log with one bit flipped inside a chunk: the exponent of a value logged
    in the second chunk (the second double of its first such message, after time_s), so
    the file still decodes, with a number 65536 times too large. Returns the value
    before and after."""
    data = bytearray(read(src))
    pos, chunks = 8, 0  # after the magic: records of opcode u8, length u64
    while pos + 9 <= len(data):
        op, body = data[pos], pos + 9
        if op == 0x06:  # Chunk: start, end u64, size u64, crc u32, compression, records
            chunks += 1
            compression = u(data, body + 28, 4)
            at = body + 32 + compression
            end = at + 8 + u(data, at, 8)
            at += 8
            while at < end and chunks >= 2:
                if data[at] == 0x05:  # Message: channel u16, sequence u32, 2 × time u64, data
                    doubles = doubles_of(data, at + 9 + 22, at + 9 + u(data, at + 1, 8))
                    if len(doubles) >= 2:
                        x = doubles[1]
                        before = struct.unpack("<d", data[x:x + 8])[0]
                        data[x + 7] ^= 0x01
                        with open(dst, "wb") as f:
                            f.write(data)
                        return before, struct.unpack("<d", data[x:x + 8])[0]
                at += 9 + u(data, at + 1, 8)
        pos = body + u(data, pos + 1, 8)
    raise Failed(f"{src}: found no chunk with a message to damage")


def imitation(src, dst, run_end, origin_ns=0):
    """Writes `src` again with the mcap writer, as orbitlash would: every record copied,
    the log dated (time origin origin_ns, when not 0), and orbitlash.run_end's keys
    pairs_json, eclipses_json and verdict replaced by those of `run_end` (none: a log
    from before them)."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer

    with open(src, "rb") as f, open(dst, "wb") as out:
        r = make_reader(f)
        header, summary = r.get_header(), r.get_summary()
        w = Writer(out, compression=CompressionType.NONE)
        w.start(header.profile, header.library)
        schemas = {k: w.register_schema(s.name, s.encoding, s.data) for k, s in summary.schemas.items()}
        channels = {k: w.register_channel(c.topic, c.message_encoding, schemas[c.schema_id], dict(c.metadata))
                    for k, c in summary.channels.items()}
        for _, channel, m in r.iter_messages(log_time_order=True):
            w.add_message(channels[channel.id], m.log_time + origin_ns, m.data,
                          m.publish_time + origin_ns, m.sequence)
        for a in r.iter_attachments():
            w.add_attachment(a.create_time, a.log_time, a.name, a.media_type, a.data)
        for m in r.iter_metadata():
            values = dict(m.metadata)
            if m.name == "orbitlash.provenance" and origin_ns:
                values["time_origin_unix_ns"] = str(origin_ns)
            if m.name == "orbitlash.run_end":
                for key in ("pairs_json", "eclipses_json", "verdict"):
                    values.pop(key, None)
                values.update(run_end)
            w.add_metadata(m.name, values)
        w.finish()


def logged_backlash(log):
    """(t_ns, µm) of every logged backlash_exact_um of /gears/mesh."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    with open(log, "rb") as f:
        r = make_reader(f, decoder_factories=[DecoderFactory()])
        return [(m.log_time, p.backlash_exact_um)
                for _, _, m, p in r.iter_decoded_messages(topics=["/gears/mesh"])]


def rrd_entity(rrd, entity):
    """The static components of an entity of an .rrd and its rows over time (times as
    integer ns: sim_time since t = 0, utc since 1970)."""
    import pyarrow as pa
    from rerun.chunk import RrdReader

    static, rows = {}, []
    for chunk in RrdReader(rrd).stream():
        if str(chunk.entity_path) != entity:
            continue
        rb = chunk.to_record_batch()
        columns = [c.cast(pa.int64()) if pa.types.is_duration(c.type) or pa.types.is_timestamp(c.type) else c
                   for c in rb.columns]
        for row in pa.RecordBatch.from_arrays(columns, names=rb.schema.names).to_pylist():
            row.pop("rerun.controls.RowId", None)
            if chunk.is_static:
                static.update(row)
            else:
                rows.append(row)
    return static, rows


def load_export_module():
    sys.dont_write_bytecode = True  # no viewer/__pycache__ in the tree
    spec = importlib.util.spec_from_file_location("rerun_export", EXPORT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ---- requirements and imports ----------------------------------------------------------

def pins(path):
    with open(path) as f:
        return sorted(line.split("#")[0].strip() for line in f if line.split("#")[0].strip())


def test_requirements_agree():
    viewer = os.path.join(ROOT, "viewer", "requirements.txt")
    tests = os.path.join(HERE, "requirements.txt")
    expect(os.path.exists(viewer), "viewer/requirements.txt does not exist")
    expect(pins(viewer) == pins(tests), f"viewer/ pins {pins(viewer)}, tests/viewer/ pins {pins(tests)}")
    expect(all("==" in p for p in pins(viewer)), f"not every requirement is pinned: {pins(viewer)}")


def without_module(tmp, module):
    """An environment in which `import module` fails, as when it is not installed."""
    shadow = os.path.join(tmp, f"no-{module}")
    os.makedirs(os.path.join(shadow, module), exist_ok=True)
    with open(os.path.join(shadow, module, "__init__.py"), "w") as f:
        f.write(f"raise ModuleNotFoundError(\"No module named '{module}'\", name='{module}')\n")
    return dict(os.environ, PYTHONPATH=shadow)


def test_missing_package(tmp, log, script, module, package):
    p = run([PY, script, log], env=without_module(tmp, module))
    lines = (p.stdout + p.stderr).strip().splitlines()
    name = os.path.basename(script)
    expect(p.returncode == 2 and len(lines) == 1
           and f"{name} needs the Python package `{package}`" in lines[0] and "pip install -r" in lines[0],
           f"wanted exit 2 and one line '{name} needs the Python package `{package}`: pip install -r …'; "
           f"got exit {p.returncode}, output {lines[-3:]}")


# ---- A: what -o writes over ------------------------------------------------------------

def test_refuses_link_to_log(tmp, log, kind):
    d, victim = case_dir(tmp, f"{kind}-to-log", log)
    out = os.path.join(d, f"{kind}.rrd")
    (os.symlink if kind == "symlink" else os.link)(victim, out)
    before = read(victim)
    p = export(victim, "-o", out)
    expect(read(victim) == before, f"the log changed ({shown(p)})")
    expect_refused(p, out)


def test_refuses_log_given_through_link(tmp, log):
    d, victim = case_dir(tmp, "log-through-link", log)
    link = os.path.join(d, "link.mcap")
    os.symlink(victim, link)
    before = read(victim)
    p = export(link, "-o", victim)
    expect(read(victim) == before, f"the log changed ({shown(p)})")
    expect_refused(p, victim)


def test_refuses_partial_link_to_log(tmp, log):
    d, victim = case_dir(tmp, "partial-to-log", log)
    out = os.path.join(d, "x.rrd")
    os.symlink(victim, out + ".partial")
    before = read(victim)
    p = export(victim, "-o", out)
    expect(read(victim) == before, f"the log was written over through {out}.partial ({shown(p)})")
    expect(p.returncode == 2 and not os.path.exists(out), f"wanted exit 2 and no {out}; got {shown(p)}")


def test_refuses_symlink(tmp, log):
    d, victim = case_dir(tmp, "symlink-to-rrd", log)
    target = os.path.join(d, "target.rrd")
    with open(target, "wb") as f:
        f.write(RRD_MAGIC + b"\0" * 60)
    out = os.path.join(d, "link.rrd")
    os.symlink(target, out)
    p = export(victim, "-o", out)
    expect(os.path.islink(out) and read(target) == RRD_MAGIC + b"\0" * 60, f"the link or its file changed ({shown(p)})")
    expect_refused(p, out)


def test_refuses_special(tmp, log, kind):
    d, victim = case_dir(tmp, f"special-{kind}", log)
    out = os.path.join(d, f"{kind}.rrd")
    os.mkdir(out) if kind == "directory" else os.mkfifo(out)
    p = export(victim, "-o", out)
    expect(os.path.isdir(out) if kind == "directory" else not os.path.isfile(out),
           f"the {kind} was replaced ({shown(p)})")
    expect_refused(p, out)


def test_not_rrd(tmp, log, name, content):
    d, victim = case_dir(tmp, f"not-rrd-{name}", log)
    out = os.path.join(d, name)
    with open(out, "wb") as f:
        f.write(content)
    p = export(victim, "-o", out)
    expect(read(out) == content, f"{out} was written over ({shown(p)})")
    expect_refused(p, out)
    p = export(victim, "-o", out, "--force")
    expect(p.returncode == 0 and read(out).startswith(RRD_MAGIC), f"--force did not write it: {shown(p)}")


def test_writes_over_rrd(tmp, log):
    d, victim = case_dir(tmp, "over-rrd", log)
    out = os.path.join(d, "previous.rrd")
    for _ in range(2):
        p = export(victim, "-o", out)
        expect(p.returncode == 0, f"export: {shown(p)}")
    expect(read(out).startswith(RRD_MAGIC) and not os.path.exists(out + ".partial"),
           "no .rrd, or a .partial left")


def test_default_beside_log(tmp, log):
    d, victim = case_dir(tmp, "default-out", log)
    p = export(victim)
    expect(p.returncode == 0 and read(os.path.join(d, "log.rrd")).startswith(RRD_MAGIC),
           f"no log.rrd beside the log: {shown(p)}")


def test_failure_keeps_previous(tmp, log):
    """A failure while writing (the blueprint step fails, in this process) leaves no
    .partial and the previous .rrd as it was."""
    d, victim = case_dir(tmp, "failure", log)
    out = os.path.join(d, "previous.rrd")
    p = export(victim, "-o", out)
    expect(p.returncode == 0, f"first export: {shown(p)}")
    before = read(out)
    module = load_export_module()

    def broken(*args, **kwargs):
        raise RuntimeError("failure injected by test_helpers.py")

    module.make_blueprint = broken
    said = io.StringIO()
    with contextlib.redirect_stderr(said):
        code = module.main([victim, "-o", out])
    expect(code == 2 and "failure injected" in said.getvalue(), f"main returned {code}: {said.getvalue()!r}")
    expect(not os.path.lexists(out + ".partial"), f"{out}.partial was left")
    expect(read(out) == before, "the previous .rrd changed")


def test_screenshot_refuses_log(tmp, log, kind):
    d, victim = case_dir(tmp, f"shot-{kind}", log)
    shot = os.path.join(d, "shot.png")
    (os.symlink if kind == "symlink" else os.link)(victim, shot)
    before = read(victim)
    env = {k: v for k, v in os.environ.items() if k != "ORBITLASH_REQUIRE_VIEWER"}
    p = run([PY, SCREENSHOT, victim, shot], env=env)
    expect(read(victim) == before and os.path.lexists(shot), "the log or the link changed")
    expect(p.returncode == 2 and "log" in p.stdout, f"wanted exit 2 naming the log; got exit {p.returncode}, "
           f"{p.stdout.strip()[-200:]!r}")


# ---- B: chunk CRCs ---------------------------------------------------------------------

def damaged_copy(tmp, log, name):
    d, good = case_dir(tmp, name, log)
    bad = os.path.join(d, "damaged.mcap")
    before, after = flip_in_chunk(good, bad)
    expect(before != after, "the flipped bit changed nothing")
    return d, bad


def test_export_refuses_damaged(tmp, log):
    d, bad = damaged_copy(tmp, log, "damaged-export")
    out = os.path.join(d, "previous.rrd")
    p = export(log, "-o", out)  # the undamaged log: a previous export
    expect(p.returncode == 0, f"export of the undamaged log: {shown(p)}")
    previous = read(out)
    p = export(bad, "-o", out)
    lines = p.stderr.strip().splitlines()
    expect(p.returncode == 2 and len(lines) == 1 and bad in lines[0] and "CRC" in lines[0],
           f"wanted exit 2 and one line naming {bad} and its chunk CRC; got {shown(p)}")
    expect(read(out) == previous and not os.path.lexists(out + ".partial"),
           "the previous .rrd changed or a .partial was left")


def test_check_log_fails_damaged(tmp, log):
    good = run([PY, CHECK_LOG, log])
    expect(good.returncode == 0 and "RESULT: OK" in good.stdout, f"the undamaged log fails: {good.stdout[-300:]}")
    _, bad = damaged_copy(tmp, log, "damaged-check")
    p = run([PY, CHECK_LOG, bad])
    expect(p.returncode not in (0, None) and "RESULT: OK" not in p.stdout and "CRC" in p.stdout,
           f"check_log.py passed a damaged log (exit {p.returncode}): {p.stdout.strip()[-200:]!r}")


# ---- C: the run's smallest backlash ----------------------------------------------------

ORIGIN_NS = 1_454_544_000_000_000_000  # 2016-02-04T00:00Z, the cubesat-1u epoch
T_MIN_S = 12345.678901234  # between two logged samples


def below_samples(sparse, **change):
    """A pairs_json entry whose smallest backlash is below every logged sample."""
    lowest = min(v for _, v in logged_backlash(sparse))
    entry = {"name": "mesh", "topic": "/gears/mesh", "min_backlash_um": lowest - 0.5,
             "t_min_s": T_MIN_S, "min_allowed_um": 5.0, "verdict": "pass"}
    entry.update(change)
    return entry


def export_imitation(tmp, sparse, name, run_end):
    log = os.path.join(tmp, f"{name}.mcap")
    rrd = os.path.join(tmp, f"{name}.rrd")
    imitation(sparse, log, run_end, ORIGIN_NS)
    p = export(log, "-o", rrd)
    expect(p.returncode == 0, f"export: {shown(p)}")
    return rrd


def smallest_of(rrd, pair="mesh"):
    """(label, value µm, sim_time ns, utc ns or None) of the export's smallest point, and
    the values of its smallest allowed line."""
    static, rows = rrd_entity(rrd, f"/backlash/{pair}/smallest")
    expect(len(rows) == 1, f"{len(rows)} smallest points")
    _, allowed = rrd_entity(rrd, f"/backlash/{pair}/minimum_allowed")
    label = static.get("SeriesPoints:names", [""])[0]
    row = rows[0]
    return (label, row["Scalars:scalars"][0], row["sim_time"], row.get("utc")), {r["Scalars:scalars"][0] for r in allowed}


def test_smallest_from_run(tmp, sparse):
    pair = below_samples(sparse)
    run_end = {"verdict": "pass", "pairs_json": json.dumps([pair]), "eclipses_json": json.dumps([[2100.0, 4200.0]])}
    (label, value, t_ns, utc_ns), allowed = smallest_of(export_imitation(tmp, sparse, "run-min", run_end))
    expect(value == pair["min_backlash_um"], f"smallest {value} µm, the run's {pair['min_backlash_um']}")
    expect(abs(t_ns - T_MIN_S * 1e9) < 1e3, f"smallest at sim_time {t_ns * 1e-9} s, the run's at {T_MIN_S} s")
    expect(utc_ns is not None and abs(utc_ns - (ORIGIN_NS + T_MIN_S * 1e9)) < 1e3,
           f"smallest at utc {utc_ns} ns, the run's at {ORIGIN_NS + T_MIN_S * 1e9:.0f}")
    expect(label == f"smallest: {value:.3f} µm (PASS)", f"label {label!r}")
    expect(allowed == {5.0}, f"smallest allowed line {sorted(allowed)}")


def test_smallest_verdict_fail(tmp, sparse):
    """A failed pair, its entry named but without "topic" (as the binary writes it now)."""
    pair = below_samples(sparse, min_allowed_um=25.0, verdict="margin_violated")
    del pair["topic"]
    run_end = {"verdict": "fail", "pairs_json": json.dumps([pair])}
    (label, value, _, _), allowed = smallest_of(export_imitation(tmp, sparse, "run-fail", run_end))
    expect(value == pair["min_backlash_um"], f"smallest {value} µm, the run's {pair['min_backlash_um']}")
    expect(label.startswith(f"smallest: {value:.3f} µm (FAIL"), f"label {label!r}")
    expect(allowed == {25.0}, f"smallest allowed line {sorted(allowed)}, not the run's 25.0")


def test_smallest_older_log(tmp, sparse):
    """A log without pairs_json: the smallest of the samples, as before."""
    t_ns, value = min(logged_backlash(sparse), key=lambda x: x[1])
    (label, got, got_t, _), _ = smallest_of(export_imitation(tmp, sparse, "older", {}))
    expect(got == value and got_t == t_ns and label == f"smallest: {value:.3f} µm",
           f"smallest {label!r} {got} at {got_t} ns, the samples' {value} at {t_ns} ns")


def binary_pairs(log):
    from mcap.reader import make_reader

    with open(log, "rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    raw = meta.get("orbitlash.run_end", {}).get("pairs_json")
    return json.loads(raw) if raw else None


def test_smallest_binary_log(tmp, sparse, pairs):
    """The binary's own log, with its own pairs_json."""
    rrd = os.path.join(tmp, "binary.rrd")
    p = export(sparse, "-o", rrd)
    expect(p.returncode == 0, f"export: {shown(p)}")
    pair = pairs[0]
    (label, value, t_ns, _), allowed = smallest_of(rrd, pair["name"])
    expect(value == pair["min_backlash_um"] and abs(t_ns - pair["t_min_s"] * 1e9) < 1e3,
           f"smallest {value} µm at {t_ns * 1e-9} s, the run's {pair['min_backlash_um']} at {pair['t_min_s']} s")
    expect(label == f"smallest: {value:.3f} µm ({pair['verdict'].upper()})", f"label {label!r}")
    expect(allowed == {pair["min_allowed_um"]}, f"smallest allowed line {sorted(allowed)}")


def test_smallest_not_finite():
    """A pair without a valid mesh (null in pairs_json): no point, the verdict kept."""
    module = load_export_module()
    meta = {"orbitlash.run_end": {"pairs_json": json.dumps([{
        "name": "mesh", "topic": "/gears/mesh", "min_backlash_um": None, "t_min_s": None,
        "min_allowed_um": 5.0, "verdict": "no_valid_mesh"}])}}
    series = {("/gears/mesh", "backlash_exact_um"): ([0, 10], [30.0, 31.0]),
              ("/gears/mesh", "margin_um"): ([0, 10], [25.0, 26.0])}
    low = module.smallest_point("/gears/mesh", series, module.run_pairs(meta), 0)
    expect(low.t_ns is None and low.allowed_um == 5.0 and low.verdict == "no_valid_mesh", f"got {low}")


# ---- D: the per-orbit tab of a long run ----------------------------------------------

def test_per_orbit_closed_form():
    """A sine of period P sampled unevenly over 40 orbits of P, with orbit_number
    changing at the first sample of each orbit (late by up to a step): each whole
    orbit's range is the sine's (±1 within the sampling), its time-weighted mean 0,
    and the orbit starts are put back on k·P by the straight-line fit."""
    import numpy as np

    module = load_export_module()
    period_ns = 5_000 * 10**9
    rng = np.random.default_rng(7)
    t = np.cumsum(rng.uniform(20, 120, 20_000) * 1e9).astype(np.int64)
    t = t[t < 40 * period_ns]
    n = 1 + t // period_ns
    series = {("/orbit/state", "orbit_number"): (list(t), list(n.astype(float)))}
    starts = module.orbit_starts(series)
    expect(starts is not None and len(starts) == 40, f"{None if starts is None else len(starts)} orbits, not 40")
    off = np.abs(starts[1:] - np.arange(1, 40) * period_ns) / 1e9
    expect(np.max(off) < 25.0, f"orbit starts off k·P by up to {np.max(off):.0f} s (steps of 20 … 120 s)")
    v = np.sin(2 * np.pi * t / period_ns)
    mid, lo, hi, mean = module.per_orbit(t, v, starts)
    inner = slice(1, -1)  # whole orbits
    expect(np.all(lo[inner] < -0.99) and np.all(hi[inner] > 0.99), f"ranges {lo[inner].max()} … {hi[inner].min()}")
    expect(np.max(np.abs(mean[inner])) < 0.02, f"orbit means up to {np.max(np.abs(mean[inner]))}, not 0")
    # a run of 40 whole orbits logs the 41st orbit's first sample at its end: that
    # one-sample "orbit" (min = max) is not drawn; half an orbit more is not either
    for extra_ns, name in ((0, "its first sample"), (period_ns // 2, "half of it")):
        t2 = np.r_[t, np.arange(40 * period_ns, 40 * period_ns + extra_ns + 1, 60 * 10**9)]
        n2 = 1 + t2 // period_ns
        starts2 = module.orbit_starts({("/orbit/state", "orbit_number"): (list(t2), list(n2.astype(float)))})
        mid2, lo2, hi2, _ = module.per_orbit(t2, np.sin(2 * np.pi * t2 / period_ns), starts2)
        expect(len(starts2) == 41 and len(mid2) == 40,
               f"the 41st orbit ({name}) drawn: {len(mid2)} of {len(starts2)} orbits")
        expect(lo2[-1] < -0.99 and hi2[-1] > 0.99, f"the last drawn orbit's range {lo2[-1]} … {hi2[-1]}")
    # samples a fifth of an orbit apart (4 or 5 per orbit): every whole orbit is drawn,
    # the last one too (review helper-28: 39 of 40 with a rule of 90 % of the period)
    t3 = np.arange(0, 40 * period_ns, period_ns * 2 // 9)
    n3 = 1 + t3 // period_ns
    starts3 = module.orbit_starts({("/orbit/state", "orbit_number"): (list(t3), list(n3.astype(float)))})
    mid3, _, _, _ = module.per_orbit(t3, np.sin(2 * np.pi * t3 / period_ns), starts3)
    expect(len(mid3) == 40, f"{len(mid3)} of 40 whole orbits sampled at 2/9 of an orbit drawn")
    few = {("/orbit/state", "orbit_number"): (list(t[t < 10 * period_ns]), list(n[t < 10 * period_ns]))}
    expect(module.orbit_starts(few) is None, "10 orbits got the per-orbit tab (it is for more than 30)")


def test_sunlit_share_from_eclipses():
    """Eclipses of 0.3 P in each orbit of P (and a last orbit cut at 0.5 P): every
    whole orbit's sunlit share is 0.7 exactly, from the windows; from the samples of
    the flag it is within a sample's share; the cut orbit is left out."""
    import numpy as np

    module = load_export_module()
    p = 6000.0
    eclipses = [[k * p + 0.5 * p, k * p + 0.8 * p] for k in range(50)]
    t = np.arange(0, 49.5 * p, 10.0)
    sunlit = np.array([0.0 if (x % p) > 0.5 * p and (x % p) <= 0.8 * p else 1.0 for x in t])
    t_ns = (t * 1e9).astype(np.int64)
    starts = (np.arange(50) * p * 1e9).astype(np.int64)
    mid, share = module.sunlit_share(t_ns, sunlit, starts, eclipses, 0)
    expect(len(share) == 49, f"{len(share)} orbits, not 49 whole ones")
    expect(np.max(np.abs(share - 0.7)) < 1e-12, f"shares {share.min()} … {share.max()}, not 0.7")
    mid, share = module.sunlit_share(t_ns, sunlit, starts, None, 0)
    expect(np.max(np.abs(share - 0.7)) < 10.0 / p + 1e-9, f"from samples {share.min()} … {share.max()}")


def test_legend_corner_avoids_the_data():
    """A view whose line runs along the top goes to a bottom corner; lines through
    every corner but the left bottom one (one along the top, one along the bottom of
    the second half) put the legend there; no data keeps the default."""
    import numpy as np

    module = load_export_module()
    t = np.arange(0, 1001, dtype=float) * 1e9
    top = {"a": (t, np.r_[np.zeros(1), np.full(1000, 10.0)])}
    expect(module.legend_corner(["a"], top, 0, 1000.0).endswith("Bottom"),
           module.legend_corner(["a"], top, 0, 1000.0))
    shape = {"b": (t, np.full(len(t), 10.0)), "c": (t[500:], np.zeros(len(t) - 500))}
    expect(module.legend_corner(["b", "c"], shape, 0, 1000.0) == "LeftBottom",
           module.legend_corner(["b", "c"], shape, 0, 1000.0))
    expect(module.legend_corner(["none"], {}, 0, 1.0) == "RightTop", "no data: the default corner")


# ---- main ------------------------------------------------------------------------------

def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "release", "orbitlash")
    if not os.access(binary, os.X_OK):
        print(f"error: no orbitlash binary at {binary} (give its path)", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="orbitlash-helpers-") as tmp:
        ref, sparse = make_logs(os.path.abspath(binary), tmp)
        check("requirements: viewer/ and tests/viewer/ pin the same packages", test_requirements_agree)
        for script, module, package in [(EXPORT, "mcap_protobuf", "mcap-protobuf-support"),
                                        (EXPORT, "rerun", "rerun-sdk"),
                                        (CHECK_LOG, "mcap_protobuf", "mcap-protobuf-support")]:
            check(f"imports: {os.path.basename(script)} names a missing {package} in one line",
                  test_missing_package, tmp, sparse, script, module, package)
        check("A: -o a symlink to the log is refused", test_refuses_link_to_log, tmp, sparse, "symlink")
        check("A: -o a hard link to the log is refused", test_refuses_link_to_log, tmp, sparse, "hardlink")
        check("A: -o the log, given through a symlink, is refused", test_refuses_log_given_through_link, tmp, sparse)
        check("A: a .partial that links to the log is refused", test_refuses_partial_link_to_log, tmp, sparse)
        check("A: -o a symlink (to an .rrd) is refused", test_refuses_symlink, tmp, sparse)
        check("A: -o a directory is refused", test_refuses_special, tmp, sparse, "directory")
        check("A: -o a FIFO is refused", test_refuses_special, tmp, sparse, "fifo")
        with open(os.path.join(ROOT, "scenarios", "reference-hinge.toml"), "rb") as f:
            toml = f.read()
        check("A: -o a scenario .toml is refused, written with --force", test_not_rrd, tmp, sparse, "scenario.toml", toml)
        check("A: -o a .rrd that is not one is refused, written with --force", test_not_rrd, tmp, sparse,
              "notes.rrd", b"not an rrd\n")
        check("A: -o a previous .rrd is written over, no .partial left", test_writes_over_rrd, tmp, sparse)
        check("A: the default output is beside the log", test_default_beside_log, tmp, sparse)
        check("A: a failure mid-export keeps the previous .rrd and removes the .partial",
              test_failure_keeps_previous, tmp, sparse)
        check("A: rerun_screenshot.py refuses a screenshot that is a symlink to the log",
              test_screenshot_refuses_log, tmp, sparse, "symlink")
        check("A: rerun_screenshot.py refuses a screenshot that is a hard link to the log",
              test_screenshot_refuses_log, tmp, sparse, "hardlink")
        check("B: the export refuses a damaged chunk, keeps the previous .rrd", test_export_refuses_damaged, tmp, ref)
        check("B: check_log.py fails a damaged chunk", test_check_log_fails_damaged, tmp, ref)
        check("C: the smallest point is the run's (pairs_json): value, time, utc, label, allowed line",
              test_smallest_from_run, tmp, sparse)
        check("C: a failed pair (entry without topic): label and smallest allowed line",
              test_smallest_verdict_fail, tmp, sparse)
        check("C: a log without pairs_json: the smallest of the samples", test_smallest_older_log, tmp, sparse)
        pairs = binary_pairs(sparse)
        if pairs:
            check("C: the binary's own log: the smallest point and label from its pairs_json",
                  test_smallest_binary_log, tmp, sparse, pairs)
        else:
            print("SKIP C: the binary's own log: it writes no pairs_json yet")
        check("C: a pair with no finite smallest: no point, verdict kept", test_smallest_not_finite)
        check("D: per-orbit range and mean of a sine, orbit starts on k·P, no cut last orbit", test_per_orbit_closed_form)
        check("D: the sunlit share of each whole orbit from the eclipse windows", test_sunlit_share_from_eclipses)
        check("D: a view's legend goes to the corner its lines leave free", test_legend_corner_avoids_the_data)
    print(f"{results['passed']} passed, {results['failed']} failed")
    return 1 if results["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Would Foxglove and Rerun show an orbitlash log as plots?

    python tests/viewer/check_log.py LOG.mcap [--allow-interrupted] [--allow-recovered]

Reads the file with the MCAP reader Foxglove publishes (protobuf decoded through the
schemas stored in the file) and imports it with Rerun's own MCAP importer, then checks:
- every chunk matches its CRC (a file changed after it was written fails);
- every channel has a schema and is protobuf (Rerun decodes protobuf by reflection;
  JSON would reach it as raw bytes);
- every message decodes, the message count matches the summary, log time never goes
  backwards within a channel;
- every node of /thermal/temperature (names from the channel metadata `node:<field>`),
  every face flux of /orbit/faces (`face:<field>`) and the backlash fields of every
  /gears/<pair> channel (required when the attached scenario has gear pairs) are finite numbers in every
  message for Foxglove, and full, null-free, finite numeric columns in Rerun;
- foxglove.Log channels arrive in Rerun as text logs, one row per message;
- provenance: the metadata record and the attached scenario file are present, and the
  run_end record says the run completed (or was interrupted, with --allow-interrupted,
  or was recovered from a cut-off log by `orbitlash recover`, with --allow-recovered).
Exit 0 = OK, 1 = a viewer would not get the data, 2 = the check could not run (one line
naming a missing Python package: pip install -r tests/viewer/requirements.txt).
"""
import argparse, importlib, math, sys
from collections import defaultdict

# The modules imported here and the Python packages (pip names) that provide them,
# dependencies first, so that a missing one is named rather than its dependent.
PACKAGES = [("mcap", "mcap"), ("google.protobuf", "protobuf"), ("mcap_protobuf", "mcap-protobuf-support"),
            ("pyarrow", "pyarrow"), ("rerun", "rerun-sdk")]

GEAR_FIELDS = ["backlash_exact_um", "backlash_closed_form_um", "backlash_paper_um", "margin_um",
               "pressure_angle_deg", "center_distance_mm"]

problems = []

def fail(msg):
    problems.append(msg)
    print("FAIL:", msg)

def missing_package():
    """(pip name, error) of the first package that does not import, or None."""
    for module, package in PACKAGES:
        try:
            importlib.import_module(module)
        except ImportError as e:
            return package, e
    return None

def foxglove_side(path, allowed_ends):
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory
    expected = {}            # topic -> [field]
    counts = defaultdict(int)
    logs = set()
    scenes = set()
    with open(path, "rb") as f:
        # every chunk read is checked against its CRC (CRCValidationError)
        r = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
        s = r.get_summary()
        if s is None or s.statistics is None:
            fail("no summary section: the file was not closed")
            return expected, counts, logs
        meta = {m.name: dict(m.metadata) for m in r.iter_metadata()}
        prov = meta.get("orbitlash.provenance", {})
        for key in ["tool_version", "scenario_name", "scenario_sha256", "solver", "seed"]:
            if key not in prov:
                fail(f"provenance metadata lacks {key}")
        end = meta.get("orbitlash.run_end", {}).get("status")
        if end != "complete" and end not in allowed_ends:
            fail(f"run_end status is {end!r}")
        if not any(a.media_type == "application/toml" for a in s.attachment_indexes):
            fail("the scenario file is not attached")
        for cid, ch in s.channels.items():
            sc = s.schemas.get(ch.schema_id)
            if sc is None or sc.encoding != "protobuf" or ch.message_encoding != "protobuf":
                fail(f"{ch.topic}: not protobuf with a schema ({sc and sc.encoding}, {ch.message_encoding})")
                continue
            if sc.name == "foxglove.Log":
                logs.add(ch.topic)
            elif ch.topic == "/thermal/temperature":
                nodes = {k[5:]: v for k, v in ch.metadata.items() if k.startswith("node:")}
                if not nodes:
                    fail("/thermal/temperature has no node:<field> metadata")
                expected[ch.topic] = sorted(nodes)
            elif ch.topic == "/orbit/faces":
                faces = {k[5:]: v for k, v in ch.metadata.items() if k.startswith("face:")}
                if not faces:
                    fail("/orbit/faces has no face:<field> metadata")
                expected[ch.topic] = sorted(faces)
            elif sc.name == "orbitlash.GearMesh":
                expected[ch.topic] = GEAR_FIELDS
            elif sc.name == "foxglove.SceneUpdate":
                scenes.add(ch.topic)
        print(f"[foxglove] {len(s.channels)} channels, {s.statistics.message_count} messages; "
              f"scenario {prov.get('scenario_name')!r} sha256 {prov.get('scenario_sha256', '')[:12]}…, run_end {end!r}")
        values = defaultdict(lambda: defaultdict(list))
        last = {}
        for sc, ch, msg, dec in r.iter_decoded_messages():
            counts[ch.topic] += 1
            if msg.log_time < last.get(ch.topic, 0):
                fail(f"{ch.topic}: log time goes backwards at {msg.log_time}")
            last[ch.topic] = msg.log_time
            for field in expected.get(ch.topic, []):
                values[ch.topic][field].append(getattr(dec, field))
        for topic in scenes:
            print(f"[foxglove] {topic}: {counts[topic]} foxglove.SceneUpdate messages (3-D view)")
        if sum(counts.values()) != s.statistics.message_count:
            fail("decoded message count differs from the summary statistics")
        for topic, fields in expected.items():
            for field in fields:
                v = values[topic][field]
                if len(v) != counts[topic] or not all(isinstance(x, float) and math.isfinite(x) for x in v):
                    fail(f"{topic}.{field}: not a finite number in every message")
            print(f"[foxglove] {topic}: {counts[topic]} messages, {len(fields)} checked fields, e.g. "
                  + ", ".join(f"{f} {min(values[topic][f]):.6g}…{max(values[topic][f]):.6g}" for f in fields[:2]))
    return expected, counts, logs

def has_gear_pairs(path):
    """Whether the scenario attached to the log has gear pairs (then it must log them)."""
    from mcap.reader import make_reader
    with open(path, "rb") as f:
        for a in make_reader(f, validate_crcs=True).iter_attachments():
            if a.media_type == "application/toml":
                return any(line.strip().startswith("[[gear_pair]]")
                           for line in a.data.decode("utf-8", "replace").splitlines())
    return True

def rerun_side(path, expected, counts, logs):
    import rerun as rr
    import pyarrow.compute as pc
    from rerun.chunk import McapReader, Selector
    print(f"[rerun] rerun-sdk {rr.__version__}")
    cols = defaultdict(list)
    rows = defaultdict(int)
    for chunk in McapReader(path, timeline_type="duration_ns").stream():
        if chunk.is_static:
            continue
        rb = chunk.to_record_batch()
        for f in rb.schema:
            cols[chunk.entity_path].append((f.name, rb.column(f.name)))
            rows[(chunk.entity_path, f.name)] += chunk.num_rows
    for topic, fields in expected.items():
        ent = "/" + topic.lstrip("/")
        msg_cols = [(n, c) for n, c in cols.get(ent, []) if n.endswith(":message")]
        if not msg_cols:
            fail(f"{ent}: Rerun decoded no message column (got {[n for n, _ in cols.get(ent, [])]})")
            continue
        for field in fields:
            # Rerun splits an entity's rows into chunks: gather the field from all.
            values, nulls, found = [], 0, False
            for name, col in msg_cols:
                try:
                    got = Selector("[]." + field).execute(col)
                except Exception:
                    got = None
                if got is None:
                    continue
                found = True
                nulls += got.null_count
                values.extend(got.to_pylist())
            if not found:
                fail(f"{ent}.{field}: not a column in Rerun")
                continue
            finite = all(isinstance(x, float) and math.isfinite(x) for x in values)
            if len(values) != counts[topic] or nulls or not finite:
                fail(f"{ent}.{field}: Rerun gives {len(values)} rows for {counts[topic]} messages, "
                     f"{nulls} nulls, finite={finite}")
        print(f"[rerun] {ent}: {len(fields)} numeric series by name, {counts[topic]} rows each")
    for topic in logs:
        ent = "/" + topic.lstrip("/")
        text = [k for (e, n), k in rows.items() if e == ent and n.startswith("TextLog:text")]
        if not text or max(text) != counts[topic]:
            fail(f"{ent}: Rerun imported {text} text-log rows for {counts[topic]} foxglove.Log messages")
        else:
            print(f"[rerun] {ent}: {counts[topic]} events as TextLog")

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("log")
    ap.add_argument("--allow-interrupted", action="store_true")
    ap.add_argument("--allow-recovered", action="store_true")
    a = ap.parse_args()
    allowed_ends = {e for e, ok in [("interrupted", a.allow_interrupted),
                                    ("recovered", a.allow_recovered)] if ok}
    missing = missing_package()
    if missing:
        package, e = missing
        print(f"check_log.py needs the Python package `{package}`: "
              f"pip install -r tests/viewer/requirements.txt ({e})")
        return 2
    from mcap.stream_reader import CRCValidationError
    try:
        expected, counts, logs = foxglove_side(a.log, allowed_ends)
        if "/thermal/temperature" not in expected:
            fail("no /thermal/temperature channel")
        if has_gear_pairs(a.log) and not any(t.startswith("/gears/") for t in expected):
            fail("no /gears/<pair> channel")
        if counts:
            rerun_side(a.log, expected, counts, logs)
    except CRCValidationError:
        fail(f"{a.log}: a chunk's CRC does not match its bytes: the file is damaged (it changed after "
             "it was written; `orbitlash recover` writes a copy without the damaged chunks)")
    except Exception as e:  # unreadable, truncated, undecodable
        fail(f"{type(e).__name__}: {e}")
    print("RESULT:", "OK" if not problems else f"{len(problems)} problem(s)")
    return 1 if problems else 0

if __name__ == "__main__":
    sys.exit(main())

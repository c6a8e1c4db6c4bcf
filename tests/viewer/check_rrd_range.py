#!/usr/bin/env python3
"""Does the Rerun export of a long run plot its temperatures' whole range?

    python tests/viewer/check_rrd_range.py LOG.mcap LOG.rrd

Reads the .rrd back with Rerun's own reader (rerun.chunk.RrdReader) and checks, against
the log's temperatures read with Foxglove's MCAP reader:

- every line the viewer draws is aggregated MinMax (or not at all), so that a pixel
  covering many samples keeps their extremes (Rerun's default, the average of min and
  max, drew a 90-day run's −10 … 83 °C as 30 … 50 °C): what the viewer then draws
  spans the data the .rrd holds;
- the data behind the first tab (a log of more than 30 orbits: the per-orbit range)
  and behind the samples tab each span at least 90 % of the run's true range (lowest
  to highest temperature of any node over the log): nothing was lost or decimated on
  the way. (The data check alone cannot fail for want of MinMax; the policy check is
  what guards the drawing.)
- a long log has the per-orbit tab, with one min and one max line per node.

Exit 0 = all hold, 1 = one does not (each failure printed), 2 = the check could not run.
"""
import argparse
import math
import sys
from collections import defaultdict

COVER = 0.90


def log_range(path):
    """The lowest and highest temperature (°C) of any node over the log, and the
    number of nodes."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    lo, hi, nodes = math.inf, -math.inf, set()
    with open(path, "rb") as f:
        r = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, _, proto in r.iter_decoded_messages(topics=["/thermal/temperature"]):
            for fd in proto.DESCRIPTOR.fields:
                v = getattr(proto, fd.name)
                if fd.name.endswith("_k") and isinstance(v, float) and math.isfinite(v):
                    nodes.add(fd.name)
                    lo, hi = min(lo, v - 273.15), max(hi, v - 273.15)
    return lo, hi, len(nodes)


def rrd_entities(path):
    """Per entity: its scalar values' (min, max) and its static components."""
    import numpy as np
    import pyarrow.compute as pc
    import rerun.chunk as rc

    ranges, static = {}, defaultdict(dict)
    for chunk in rc.RrdReader(path).stream():
        entity = str(chunk.entity_path)
        batch = chunk.to_record_batch()
        if chunk.is_static:
            for name in batch.schema.names:
                if name.startswith("SeriesLines:") or name.startswith("SeriesPoints:"):
                    static[entity][name] = batch.column(name).to_pylist()[0]
            continue
        if "Scalars:scalars" not in batch.schema.names:
            continue
        v = np.asarray(pc.list_flatten(batch.column("Scalars:scalars")).to_numpy(zero_copy_only=False), float)
        v = v[np.isfinite(v)]
        if len(v):
            lo, hi = ranges.get(entity, (math.inf, -math.inf))
            ranges[entity] = (min(lo, v.min()), max(hi, v.max()))
    return ranges, static


def main():
    p = argparse.ArgumentParser()
    p.add_argument("log")
    p.add_argument("rrd")
    a = p.parse_args()
    try:
        import rerun as rr

        minmax = rr.components.AggregationPolicy.MinMax.value
        off = rr.components.AggregationPolicy.Off.value
        lo, hi, n_nodes = log_range(a.log)
        ranges, static = rrd_entities(a.rrd)
    except Exception as e:  # the reader's own words
        print(f"FAIL: could not read {a.log} or {a.rrd}: {type(e).__name__}: {e}")
        return 2
    fails = []
    lines = [e for e, c in static.items() if "SeriesLines:names" in c]
    for e in lines:
        policy = (static[e].get("SeriesLines:aggregation_policy") or [None])[0]
        if policy not in (minmax, off):
            fails.append(f"{e}: aggregation policy {policy}, not MinMax: a pixel of many samples loses its extremes")
    print(f"[range] {len(lines)} lines, each aggregated MinMax or not at all")
    true = hi - lo
    print(f"[range] the log's temperatures: {lo:.2f} … {hi:.2f} °C over {n_nodes} nodes")
    for tab, prefix in (("per orbit", "/per_orbit/temperature/"), ("samples", "/temperature/")):
        got = [r for e, r in ranges.items() if e.startswith(prefix)]
        if not got:
            fails.append(f"tab '{tab}': no temperature series")
            continue
        shown = max(h for _, h in got) - min(l for l, _ in got)
        share = shown / true if true > 0 else 1.0
        print(f"[range] tab '{tab}': {min(l for l, _ in got):.2f} … {max(h for _, h in got):.2f} °C, "
              f"{100 * share:.1f} % of the true range")
        if share < COVER:
            fails.append(f"tab '{tab}' spans {100 * share:.1f} % of the run's temperature range (< {100 * COVER:.0f} %)")
    per_orbit = [e for e in ranges if e.startswith("/per_orbit/temperature/")]
    if len(per_orbit) != 2 * n_nodes:
        fails.append(f"the per-orbit tab has {len(per_orbit)} temperature lines, not a min and a max for each of {n_nodes} nodes")
    for f in fails:
        print(f"FAIL: {f}")
    if not fails:
        print("RESULT: OK, the export plots the run's whole temperature range")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""An orbitlash MCAP log as a Rerun recording that opens with its plots.

    python3 viewer/rerun_export.py LOG.mcap [-o LOG.rrd]
    rerun LOG.rrd

Rerun's own MCAP importer leaves each protobuf message one opaque struct (no plot until
a blueprint picks its fields by hand) and names the recording after the file's path, so
no blueprint shipped with the project could match it. This script instead reads the log
with the MCAP reader Foxglove publishes and writes native Rerun scalars, one entity per
number, on a timeline of simulated time (`sim_time`, a duration: never 1970), plus `utc`
when the scenario is dated; with them, in the same file, a blueprint of time-series
views grouped as an engineer reads them:

- temperatures, °C: housing, motor, shafts (every node that is not a gear's) and each
  gear's radial nodes r0 (bore) … rN (rim);
- backlash, µm: exact, closed form and the paper's, the smallest allowed (a line) and
  the run's smallest backlash (a point);
- heat flows, W; the orbit (sunlit, β, solar flux); face fluxes of a dated scenario;
- events (eclipse entries and exits, heater switches) as a text log.

It reads `run` logs, `margins --replay` logs and `diagnose --out`'s diagnose.mcap (the
recorded, baseline and corrected series side by side per channel). The application id
is "orbitlash"; the recording id is the log's scenario hash and seed, so re-exporting
the same log gives the same recording.

Needs the pinned clients of tests/viewer/requirements.txt (rerun-sdk, mcap,
mcap-protobuf-support). Exit 0 on success, 2 when the log cannot be read or written.
"""
import argparse
import math
import os
import re
import sys
from collections import defaultdict

APP_ID = "orbitlash"
# diagnose.mcap: the recording pale, the model before orange, after blue
DIAGNOSE_COLORS = {
    "recorded": [200, 200, 200],
    "baseline": [230, 140, 40],
    "corrected": [60, 140, 230],
    "residual_before": [230, 140, 40],
    "residual_after": [60, 140, 230],
}
GEAR_NODE = re.compile(r"^(gear\w*?)_r(\d+)_k$")


def read_log(path):
    """Every numeric field of every protobuf channel as series over log time, the
    text logs, the channel metadata and the provenance."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    series = defaultdict(lambda: ([], []))  # (topic, field) -> (t_ns, values)
    texts = []  # (t_ns, level, message)
    with open(path, "rb") as f:
        r = make_reader(f, decoder_factories=[DecoderFactory()])
        s = r.get_summary()
        if s is None:
            raise ValueError(f"{path}: no summary section (run `orbitlash recover` on it first)")
        meta = {m.name: dict(m.metadata) for m in r.iter_metadata()}
        channels = {c.topic: (s.schemas[c.schema_id].name, dict(c.metadata)) for c in s.channels.values()}
        for schema, channel, message, proto in r.iter_decoded_messages(log_time_order=True):
            t = message.log_time
            if schema.name == "foxglove.Log":
                texts.append((t, int(proto.level), proto.message))
                continue
            if schema.name.startswith("foxglove."):
                continue  # the 3-D scene: Rerun's importer shows it as it is
            # Every scalar field of the schema, not ListFields(): proto3 leaves a field at
            # zero out of the message (the eclipse flag, a heater off).
            for fd in proto.DESCRIPTOR.fields:
                if fd.name == "time_s" or fd.is_repeated or fd.message_type:
                    continue
                v = getattr(proto, fd.name)
                if isinstance(v, (int, float)) and not isinstance(v, bool):
                    xs, ys = series[(channel.topic, fd.name)]
                    xs.append(t)
                    ys.append(float(v))
    return series, texts, channels, meta


def c_of(field):
    return field[:-2] + "_c" if field.endswith("_k") else field


def export(log, out):
    import numpy as np
    import rerun as rr
    import rerun.blueprint as rrb

    series, texts, channels, meta = read_log(log)
    prov = meta.get("orbitlash.provenance", {})
    origin_ns = int(prov.get("time_origin_unix_ns", "0") or 0)
    name = prov.get("scenario_name", os.path.basename(log))
    rec_id = f"{prov.get('scenario_sha256', 'unknown')[:16]}-seed{prov.get('seed', '0')}-{os.path.basename(log)}"
    rec = rr.RecordingStream(APP_ID, recording_id=rec_id)
    # written beside, renamed when whole: a failed export leaves no half .rrd
    partial = out + ".partial"
    rec.save(partial)

    def times(t_ns):
        t = np.asarray(t_ns, dtype=np.int64)
        cols = [rr.TimeColumn("sim_time", duration=(t - origin_ns) * 1e-9)]
        if origin_ns:
            cols.append(rr.TimeColumn("utc", timestamp=t * 1e-9))
        return cols

    def send(entity, t_ns, values, label, color=None, points=False, width=None):
        style = (
            rr.SeriesPoints(names=label, colors=color, marker_sizes=1.5)
            if points
            else rr.SeriesLines(names=label, colors=color, widths=width)
        )
        rec.log(entity, style, static=True)
        rec.send_columns(entity, indexes=times(t_ns), columns=rr.Scalars.columns(scalars=np.asarray(values)))

    groups = defaultdict(list)  # view title -> entity origins
    body, gears = [], defaultdict(list)
    for (topic, field), (t, v) in sorted(series.items()):
        if topic == "/thermal/temperature":
            node = channels[topic][1].get(f"node:{field}", field[:-2] if field.endswith("_k") else field)
            m = GEAR_NODE.match(field)
            entity = f"temperature/{m.group(1)}/r{m.group(2)}" if m else f"temperature/body/{node}"
            send(entity, t, [x - 273.15 for x in v], f"{node} (°C)")
            (gears[m.group(1)] if m else body).append(entity)
        elif topic.startswith("/gears/"):
            pair = topic[len("/gears/"):].replace("/", "_")
            if field in ("backlash_exact_um", "backlash_closed_form_um", "backlash_paper_um"):
                entity = f"backlash/{pair}/{field[:-3]}"
                send(entity, t, v, f"{pair} {field[:-3].replace('_', ' ')} (µm)")
                groups[f"backlash, gear pair {pair} (µm)"].append(entity)
            elif field == "margin_um" and (topic, "backlash_exact_um") in series:
                bt, bv = series[(topic, "backlash_exact_um")]
                allowed = [b - m for b, m in zip(bv, v)]
                entity = f"backlash/{pair}/minimum_allowed"
                send(entity, bt, allowed, f"{pair} smallest allowed (µm)")
                finite = [k for k in range(len(bv)) if math.isfinite(bv[k])]
                if not finite:
                    groups[f"backlash, gear pair {pair} (µm)"].append(entity)
                    continue
                i = min(finite, key=lambda k: bv[k])
                low = f"backlash/{pair}/smallest"
                rec.log(low, rr.SeriesPoints(names=f"{pair} smallest: {bv[i]:.3f} µm", marker_sizes=8.0), static=True)
                rec.send_columns(low, indexes=times([bt[i]]), columns=rr.Scalars.columns(scalars=[bv[i]]))
                groups[f"backlash, gear pair {pair} (µm)"] += [entity, low]
            else:
                entity = f"gears/{pair}/{field}"
                send(entity, t, v, field)
                groups[f"mesh geometry, gear pair {pair}"].append(entity)
        elif topic == "/thermal/heat":
            entity = f"heat/{field}"
            send(entity, t, v, f"{field[:-2] if field.endswith('_w') else field} (W)")
            groups["heat flows (W)"].append(entity)
        elif topic.startswith("/diagnose/"):
            # diagnose.mcap: one topic per channel, fields recorded/baseline/corrected/residuals
            ch = topic.rsplit("/", 1)[-1]
            if field == "train":
                continue  # the fitted/held-out flag, not a series
            entity = f"diagnose/{ch}/{field}"
            # the recording as points, the corrected model as the boldest line
            send(entity, t, v, f"{ch} {field.replace('_', ' ')}", DIAGNOSE_COLORS.get(field),
                 points=field == "recorded", width=2.5 if field.endswith(("corrected", "after")) else None)
            key = "residuals" if field.startswith("residual") else "series"
            groups[f"{ch}: {key}"].append(entity)
        else:
            entity = f"{topic.strip('/')}/{field}"
            send(entity, t, v, field)
            groups[topic.strip("/")].append(entity)
    if texts:
        levels = {1: "DEBUG", 2: "INFO", 3: "WARN", 4: "ERROR", 5: "CRITICAL"}
        for t, level, text in texts:
            rec.set_time("sim_time", duration=(t - origin_ns) * 1e-9)
            if origin_ns:
                rec.set_time("utc", timestamp=t * 1e-9)
            rec.log("events", rr.TextLog(text, level=levels.get(level, "INFO")))

    # Every plot shows the whole run (not a window around the time cursor).
    t_all = [x for xs, _ in series.values() for x in (xs[0], xs[-1])]
    span = (0.0, (max(t_all) - origin_ns) * 1e-9) if t_all else (0.0, 1.0)
    whole = rr.TimeRange(
        start=rr.TimeRangeBoundary.absolute(seconds=span[0]),
        end=rr.TimeRangeBoundary.absolute(seconds=span[1]),
    )

    def view(title, entities):
        return rrb.TimeSeriesView(
            name=title,
            origin="/",
            contents=[f"/{e}" for e in entities],
            axis_x=rrb.archetypes.TimeAxis(view_range=whole, link="Independent"),
        )

    temps = []
    if body:
        temps.append(view("nodes other than gears (°C)" if gears else "node temperatures (°C)", body))
    for g, ents in sorted(gears.items()):
        temps.append(view(f"{g}: radial nodes, bore r0 … rim (°C)", ents))
    # The first tab: temperatures beside backlash, heat flows and the eclipse flag;
    # everything else (mesh geometry, orbit, faces, events) on the second.
    diag = (": series", ": residuals")
    main = [view(k, v) for k, v in groups.items() if k.startswith(("backlash", "heat")) and not k.endswith(diag)]
    sunlit = [e for e in groups.get("orbit/state", []) if e.endswith("/sunlit")]
    if sunlit:
        main.append(view("sunlit (1) or eclipse (0)", sunlit))
    fitted = [view(k, v) for k, v in groups.items() if k.endswith(": series")]
    residuals = [view(k, v) for k, v in groups.items() if k.endswith(": residuals")]
    rest = [
        view(k, v)
        for k, v in groups.items()
        if not k.startswith(("backlash", "heat")) and not k.endswith(diag)
    ]
    if texts:
        rest.append(rrb.TextLogView(name="events", origin="/events"))
    panes = [rrb.Vertical(*x) for x in (temps, main) if x]
    tabs = [rrb.Horizontal(*panes, name=name)] if panes else []
    # diagnose.mcap: recorded, baseline and corrected per channel; then the residuals
    if fitted:
        tabs.append(rrb.Grid(*fitted, name="recorded, baseline, corrected"))
    if residuals:
        tabs.append(rrb.Grid(*residuals, name="residuals before and after"))
    if rest:
        tabs.append(rrb.Grid(*rest, name="mesh, orbit, events" if body else "more"))
    blueprint = rrb.Blueprint(
        rrb.Tabs(*tabs),
        rrb.TimePanel(timeline="sim_time", state="collapsed"),
        collapse_panels=True,
    )
    rec.send_blueprint(blueprint)
    rec.flush()
    rec.disconnect()
    os.replace(partial, out)
    n = sum(len(x[0]) for x in series.values())
    print(f"{out}: {len(series)} series, {n} points, {len(texts)} events; app id {APP_ID!r}, "
          f"timeline sim_time{' and utc' if origin_ns else ''}")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("log", help="an orbitlash MCAP log")
    p.add_argument("-o", "--out", help="the .rrd to write (default: beside the log, .rrd)")
    a = p.parse_args()
    out = a.out or os.path.splitext(a.log)[0] + ".rrd"
    if os.path.abspath(out) == os.path.abspath(a.log):
        print(f"error: --out {out} is the log itself", file=sys.stderr)
        return 2
    if not os.path.isdir(os.path.dirname(os.path.abspath(out))):
        print(f"error: --out {out}: its folder does not exist", file=sys.stderr)
        return 2
    try:
        export(a.log, out)
    except Exception as e:  # a damaged or foreign file: the reader's own words, exit 2
        print(f"error: {a.log}: {type(e).__name__}: {e}", file=sys.stderr)
        if os.path.exists(out + ".partial"):
            os.remove(out + ".partial")
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

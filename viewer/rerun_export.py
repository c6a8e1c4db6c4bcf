#!/usr/bin/env python3
"""An orbitlash MCAP log as a Rerun recording that opens with its plots.

    python3 viewer/rerun_export.py LOG.mcap [-o LOG.rrd] [--force]
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
  the run's smallest backlash (a point, labelled with the pair's verdict). Both come
  from the run itself (`pairs_json` of the log's `orbitlash.run_end` record), not from
  the logged samples, which can miss the minimum between them; a log written before
  that record had them gets both from its samples;
- heat flows, W; the orbit (sunlit, β, solar flux); face fluxes of a dated scenario;
- events (eclipse entries and exits, heater switches, the run's end) as a text log.

Every line keeps its extremes when a pixel covers many samples (aggregation MinMax:
Rerun's default averages them, and a 90-day run's temperatures would show a third of
their range). A log of more than 30 orbits also gets a first tab, "per orbit: min and
max": each temperature, backlash and heat flow as its range over each orbit (two
points per orbit, sent before the samples), and the sunlit share of each orbit, so
the whole mission is on screen at once while the samples load behind it.

It reads `run` logs, `margins --replay` logs and `diagnose --out`'s diagnose.mcap (the
recorded, baseline and corrected series side by side per channel). The application id
is "orbitlash"; the recording id is the log's scenario hash and seed, so re-exporting
the same log gives the same recording.

Every chunk's CRC is checked: a log changed after it was written is refused (exit 2).
The .rrd is written as `<out>.partial` and renamed into place when whole; a failure
removes the .partial and leaves a previous .rrd as it was. `-o` never writes over the
log itself (also through a symbolic or hard link), a symbolic link, a directory or a
device, nor over an existing file that is not an .rrd unless `--force` is given.

Needs the pinned clients of viewer/requirements.txt (mcap, mcap-protobuf-support,
protobuf, rerun-sdk). Exit 0 on success, 2 when the log cannot be read or the .rrd
cannot be written.
"""
import argparse
import importlib
import json
import math
import os
import re
import stat
import sys
from collections import defaultdict, namedtuple

APP_ID = "orbitlash"
# diagnose.mcap: the recording pale, the model before orange, after blue
DIAGNOSE_COLORS = {
    "recorded": [200, 200, 200],
    "baseline": [230, 140, 40],
    "corrected": [60, 140, 230],
    "residual_before": [230, 140, 40],
    "residual_after": [60, 140, 230],
}
# Distinct colours for the lines of one view (Tableau 10), so that no two of a view's
# nodes look alike; a node keeps its colour in every tab.
PALETTE = [
    [31, 119, 180], [255, 127, 14], [44, 160, 44], [214, 39, 40], [148, 103, 189],
    [140, 86, 75], [227, 119, 194], [127, 127, 127], [188, 189, 34], [23, 190, 207],
]
# The smallest allowed backlash: red in every view.
ALLOWED_RED = [220, 40, 40]
# A log of more than this many orbits gets the per-orbit tab.
ENVELOPE_ORBITS = 30
GEAR_NODE = re.compile(r"^(gear\w*?)_r(\d+)_k$")
# A gear's radial node by its name (`gear1.r2`, `pinion.r0`), as `orbitlash layout`
# groups them.
RADIAL_NODE = re.compile(r"^(.+)\.r(\d+)$")


def radial(node, field):
    """(gear, radial index) of a temperature field's node, or None for a node that is
    not a gear's: by the node's name (channel metadata), else, in a log without it, by
    the field's (`gear1_r2_k`)."""
    m = RADIAL_NODE.match(node) or GEAR_NODE.match(field)
    return (re.sub(r"\W", "_", m.group(1)), int(m.group(2))) if m else None
BACKLASH_FIELDS = ("backlash_exact_um", "backlash_closed_form_um", "backlash_paper_um")
LEVELS = {1: "DEBUG", 2: "INFO", 3: "WARN", 4: "ERROR", 5: "CRITICAL"}
# The modules this script imports and the Python packages (pip names) that provide
# them, dependencies first, so that a missing one is named rather than its dependent.
PACKAGES = [
    ("mcap", "mcap"),
    ("google.protobuf", "protobuf"),
    ("mcap_protobuf", "mcap-protobuf-support"),
    ("numpy", "numpy"),
    ("pyarrow", "pyarrow"),
    ("rerun", "rerun-sdk"),
]
# An .rrd starts with Rerun's FourCC: RRF2 (rerun-sdk 0.41), RRF0 and RRF1 before.
RRD_MAGICS = (b"RRF2", b"RRF1", b"RRF0")
# A gear pair's verdict in run_end's pairs_json, as the smallest point's label says it.
VERDICTS = {
    "pass": "PASS",
    "margin_violated": "FAIL: margin violated",
    "interference": "FAIL: teeth interfere",
    "no_valid_mesh": "no valid mesh",
}
# The run's smallest backlash on a gear topic: log time (None when no value is finite),
# µm, the smallest allowed (None: from the samples), verdict and pair name (None: the
# log predates pairs_json).
Smallest = namedtuple("Smallest", "t_ns value_um allowed_um verdict name")


def missing_package():
    """(pip name, error) of the first package that does not import, or None."""
    for module, package in PACKAGES:
        try:
            importlib.import_module(module)
        except ImportError as e:
            return package, e
    return None


def read_log(path):
    """Every numeric field of every protobuf channel as series over log time, the
    text logs, the channel metadata and the provenance. Checks every chunk's CRC."""
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    series = defaultdict(lambda: ([], []))  # (topic, field) -> (t_ns, values)
    texts = []  # (t_ns, level, message)
    with open(path, "rb") as f:
        r = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
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
                continue  # the 3-D scene (`run --scene`): for Foxglove's 3D panel, not exported
            if channel.topic == "/thermal/temperature_c":
                continue  # the °C copy of /thermal/temperature, converted here anyway
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


def finite(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def run_pairs(meta, channels=None):
    """The run's own smallest backlash per gear topic: run_end's pairs_json entries by
    topic (an entry without "topic" goes to the channel whose `pair` metadata is its
    name, else to /gears/<name>); None for a log written before pairs_json."""
    raw = meta.get("orbitlash.run_end", {}).get("pairs_json")
    if raw is None:
        return None
    try:
        entries = json.loads(raw)
    except ValueError as e:
        raise ValueError(f"run_end's pairs_json is not JSON ({e})") from None
    by_name = {md.get("pair"): topic for topic, (_, md) in (channels or {}).items() if md.get("pair")}
    pairs = {}
    for entry in entries:
        name = entry.get("name")
        pairs[entry.get("topic") or by_name.get(name) or f"/gears/{name}"] = entry
    return pairs


def smallest_point(topic, series, pairs, origin_ns):
    """The run's smallest backlash on a gear topic (a Smallest): from the run itself
    (run_pairs) when the log has it, else the smallest logged sample."""
    entry = (pairs or {}).get(topic)
    if entry is not None:
        value, t_s, allowed = entry.get("min_backlash_um"), entry.get("t_min_s"), entry.get("min_allowed_um")
        known = finite(value) and finite(t_s)
        return Smallest(
            origin_ns + round(t_s * 1e9) if known else None,
            value if known else None,
            allowed if finite(allowed) else None,
            entry.get("verdict"),
            entry.get("name"),
        )
    bt, bv = series[(topic, "backlash_exact_um")]
    kept = [k for k in range(len(bv)) if math.isfinite(bv[k])]
    if not kept:
        return Smallest(None, None, None, None, None)
    i = min(kept, key=lambda k: bv[k])
    return Smallest(bt[i], bv[i], None, None, None)


def smallest_label(low):
    """E.g. "smallest: 24.398 µm (FAIL: margin violated)" (the view's title names the
    pair)."""
    text = f"smallest: {low.value_um:.3f} µm"
    verdict = VERDICTS.get(low.verdict, str(low.verdict).upper()) if low.verdict else None
    return f"{text} ({verdict})" if verdict else text


class Recording:
    """The .rrd being written: series on the log's timelines (sim_time since t = 0, and
    utc when the log is dated, i.e. its time origin is not 0)."""

    def __init__(self, rec, origin_ns):
        self.rec = rec
        self.origin_ns = origin_ns
        self.t_end_ns = None  # the latest time sent
        self.shape = {}  # entity -> (times ns, values), at most 2000 of each: where it runs

    def times(self, t_ns):
        import numpy as np
        import rerun as rr

        t = np.asarray(t_ns, dtype=np.int64)
        last = int(t.max())
        self.t_end_ns = last if self.t_end_ns is None else max(self.t_end_ns, last)
        cols = [rr.TimeColumn("sim_time", duration=(t - self.origin_ns) * 1e-9)]
        if self.origin_ns:
            cols.append(rr.TimeColumn("utc", timestamp=t * 1e-9))
        return cols

    def series(self, entity, t_ns, values, label, color=None, points=False, width=None):
        import numpy as np
        import rerun as rr

        style = (
            rr.SeriesPoints(names=label, colors=color, marker_sizes=1.5)
            if points
            else rr.SeriesLines(names=label, colors=color, widths=width, aggregation_policy="MinMax")
        )
        self.rec.log(entity, style, static=True)
        self.rec.send_columns(entity, indexes=self.times(t_ns), columns=rr.Scalars.columns(scalars=np.asarray(values)))
        every = max(1, len(values) // 2000)
        self.shape[entity] = (np.asarray(t_ns, dtype=float)[::every], np.asarray(values, dtype=float)[::every])

    def point(self, entity, t_ns, value, label):
        import rerun as rr

        self.rec.log(entity, rr.SeriesPoints(names=label, marker_sizes=8.0), static=True)
        self.rec.send_columns(entity, indexes=self.times([t_ns]), columns=rr.Scalars.columns(scalars=[value]))

    def events(self, texts):
        import rerun as rr

        for t, level, text in texts:
            self.rec.set_time("sim_time", duration=(t - self.origin_ns) * 1e-9)
            if self.origin_ns:
                self.rec.set_time("utc", timestamp=t * 1e-9)
            self.rec.log("events", rr.TextLog(text, level=LEVELS.get(level, "INFO")))


def send_gear(out, topic, field, t, v, series, pairs, groups):
    """One field of a /gears/<pair> topic: the backlash series; with margin_um, the
    smallest allowed line and the run's smallest point; the mesh geometry."""
    pair = topic[len("/gears/"):].replace("/", "_")
    backlash = f"backlash, gear pair {pair} (µm)"
    if field in BACKLASH_FIELDS:
        entity = f"backlash/{pair}/{field[:-3]}"
        colour = PALETTE[BACKLASH_FIELDS.index(field)]
        out.series(entity, t, v, field[len("backlash_"):-3].replace("_", " "), colour)
        groups[backlash].append(entity)
    elif field == "margin_um" and (topic, "backlash_exact_um") in series:
        bt, bv = series[(topic, "backlash_exact_um")]
        low = smallest_point(topic, series, pairs, out.origin_ns)
        if low.allowed_um is not None:  # the run's own minimum
            allowed = [low.allowed_um] * len(bt)
        else:  # a log before pairs_json: backlash less margin
            allowed = [b - m for b, m in zip(bv, v)]
        label = "smallest allowed"
        if low.t_ns is None and low.verdict:  # no point to carry the verdict
            label += f" ({VERDICTS.get(low.verdict, str(low.verdict).upper())})"
        entity = f"backlash/{pair}/minimum_allowed"
        out.series(entity, bt, allowed, label, ALLOWED_RED)
        groups[backlash].append(entity)
        if low.t_ns is not None:
            out.point(f"backlash/{pair}/smallest", low.t_ns, low.value_um, smallest_label(low))
            groups[backlash].append(f"backlash/{pair}/smallest")
    else:
        entity = f"gears/{pair}/{field}"
        out.series(entity, t, v, field)
        groups[f"mesh geometry, gear pair {pair}: {unit_group(field)}"].append(entity)


def orbit_starts(series):
    """Log time (ns) at which each orbit starts (the log's orbit_number changes), when
    the log spans more than ENVELOPE_ORBITS orbits; else None."""
    import numpy as np

    key = ("/orbit/state", "orbit_number")
    if key not in series:
        return None
    t, n = (np.asarray(x) for x in series[key])
    first = np.flatnonzero(np.r_[True, np.diff(n) != 0])
    if len(first) <= ENVELOPE_ORBITS:
        return None
    # The first sample of an orbit is up to a step (300 s) after its true start, half a
    # step on average: a straight line through them against the orbit number (constant
    # period; an orbit without a sample leaves no gap in the count), less half the
    # median step, puts every boundary where it is, unless the orbits are not of one
    # period.
    number = n[first[1:]].astype(float)
    observed = t[first[1:]].astype(float)
    period, t0 = np.polyfit(number, observed, 1)
    fitted = t0 + number * period - 0.5 * float(np.median(np.diff(t)))
    if np.max(np.abs(fitted - observed)) < 0.1 * period:
        return np.r_[t[0], np.maximum(fitted, t[0] + 1).astype(np.int64)]
    return t[first]


def per_orbit(t_ns, values, starts_ns, keep_cut=False):
    """A series' range and time-weighted mean over each orbit: (mid time ns, min, max,
    mean) arrays, one entry per orbit that has samples; NaN samples are skipped. A last
    orbit the run's end cuts short (its samples span less than the others' by more
    than a step and a half) is left out, unless `keep_cut`: its range is not an
    orbit's (a run of whole orbits ends on the next orbit's first sample, whose min
    and max are that value)."""
    import numpy as np

    t = np.asarray(t_ns, dtype=np.int64)
    v = np.asarray(values, dtype=float)
    orbit = np.searchsorted(starts_ns, t, side="right") - 1
    seg = np.flatnonzero(np.r_[True, np.diff(orbit) != 0])
    last = np.r_[seg[1:], len(t)] - 1
    # a logged sample stands for the step that ends at it
    dt = np.r_[0, np.diff(t)].astype(float)
    ok = np.isfinite(v)
    w = np.where(ok, dt, 0.0)
    weight = np.add.reduceat(w, seg)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.add.reduceat(np.where(ok, v, 0.0) * w, seg) / weight
    mean = np.where(weight > 0, mean, np.fmin.reduceat(v, seg))
    mid = (t[seg] + t[last]) // 2
    keep = slice(None)
    if len(seg) > 2 and not keep_cut:
        # the span of each orbit's samples, against the others' less a step and a
        # half (samples a fifth of an orbit apart span three or four fifths of a
        # whole orbit, whichever the phase gives)
        span = (t[last] - t[seg]).astype(float)
        if span[-1] < float(np.median(span[:-1])) - 1.5 * float(np.median(np.diff(t))):
            keep = slice(0, len(seg) - 1)
    return mid[keep], np.fmin.reduceat(v, seg)[keep], np.fmax.reduceat(v, seg)[keep], mean[keep]


def send_envelopes(out, series, channels, pairs, starts, eclipses=None):
    """The per-orbit tab's series (each temperature's and backlash's range over each
    orbit as two lines of one colour, with the smallest allowed backlash and the run's
    smallest; the orbit-average heat flows; the sunlit share of each orbit); returns
    its views (title -> entities)."""
    views = defaultdict(list)
    colour = defaultdict(int)  # view title -> lines coloured so far

    def both(title, entity, label, t, v, scale=1.0, offset=0.0, k=None):
        mid, lo, hi, _ = per_orbit(t, v, starts)
        c = PALETTE[(colour[title] if k is None else k) % len(PALETTE)]
        colour[title] += 1
        for part, y in (("min", lo), ("max", hi)):
            out.series(f"per_orbit/{entity}/{part}", mid, y * scale + offset, f"{label} {part}", c)
            views[title].append(f"per_orbit/{entity}/{part}")

    for (topic, field), (t, v) in sorted(series.items()):
        if topic == "/thermal/temperature":
            node = channels[topic][1].get(f"node:{field}", field[:-2] if field.endswith("_k") else field)
            g = radial(node, field)
            title = (f"{g[0]} per orbit: min and max (°C)" if g
                     else "node temperatures per orbit: min and max (°C)")
            # a gear's node keeps the colour of its radial index, as in the samples tab
            both(title, f"temperature/{node}", node, t, v, offset=-273.15, k=g[1] if g else None)
        elif topic.startswith("/gears/") and field == "backlash_exact_um":
            pair = topic[len("/gears/"):].replace("/", "_")
            title = f"backlash per orbit, gear pair {pair} (µm)"
            both(title, f"backlash/{pair}", "exact", t, v)
            low = smallest_point(topic, series, pairs, out.origin_ns)
            if low.allowed_um is not None:  # the smallest allowed: a line from start to end
                out.series(f"per_orbit/backlash/{pair}/minimum_allowed", [t[0], t[-1]], [low.allowed_um] * 2,
                           "smallest allowed", ALLOWED_RED)
                views[title].append(f"per_orbit/backlash/{pair}/minimum_allowed")
            if low.t_ns is not None:  # the run's smallest, sent with the samples
                views[title].append(f"backlash/{pair}/smallest")
        elif topic == "/thermal/heat":
            mid, _, _, mean = per_orbit(t, v, starts)
            title = "heat flows, orbit average (W)"
            entity = f"per_orbit/heat/{field}"
            name = field[:-2] if field.endswith("_w") else field
            out.series(entity, mid, mean, name, PALETTE[colour[title] % len(PALETTE)])
            colour[title] += 1
            views[title].append(entity)
        elif (topic, field) == ("/orbit/state", "sunlit"):
            mid, share = sunlit_share(t, v, starts, eclipses, out.origin_ns)
            out.series("per_orbit/sunlit_share", mid, 100.0 * share, "sunlit share of the orbit (%)", PALETTE[1])
            views["sunlit share of each orbit (%)"].append("per_orbit/sunlit_share")
    return views


def sunlit_share(t_ns, sunlit, starts_ns, eclipses, origin_ns):
    """Each whole orbit's sunlit share (mid time ns, share): from the run's eclipse
    windows (run_end's eclipses_json, s since t = 0) when the log has them, exact;
    else from the sunlit flag's samples. A last orbit cut short by the run's end is
    left out."""
    import numpy as np

    end = int(t_ns[-1])
    bounds = np.r_[np.asarray(starts_ns, dtype=np.int64), end]
    length = np.diff(bounds).astype(float)
    # an orbit cut by the run's end, or two orbits between starts (one had no sample)
    whole = np.abs(length - np.median(length)) <= 0.02 * np.median(length)
    mid = (bounds[:-1] + bounds[1:]) // 2
    if eclipses:
        w = np.asarray(eclipses, dtype=float) * 1e9 + origin_ns  # (entry, exit), ns
        edges = w.ravel()
        dark = np.r_[0.0, np.cumsum(w[:, 1] - w[:, 0])]  # eclipse time before each window
        cum = np.ravel(np.column_stack([dark[:-1], dark[1:]]))  # at each entry, exit
        before = np.interp(bounds.astype(float), edges, cum, left=0.0, right=dark[-1])
        share = 1.0 - np.diff(before) / length
    else:
        _, _, _, share = per_orbit(t_ns, sunlit, starts_ns, keep_cut=True)
        share = share[: len(length)]
    return mid[whole], share[whole]


def send_series(out, series, channels, pairs):
    """Every series of the log, as entities; returns the views' groups (title ->
    entities), the body temperatures and each gear's radial nodes."""
    groups = defaultdict(list)  # view title -> entity origins
    body, gears = [], defaultdict(list)
    for (topic, field), (t, v) in sorted(series.items()):
        if topic == "/thermal/temperature":
            node = channels[topic][1].get(f"node:{field}", field[:-2] if field.endswith("_k") else field)
            g = radial(node, field)
            entity = f"temperature/{g[0]}/r{g[1]}" if g else f"temperature/body/{node}"
            k = g[1] if g else len(body)
            out.series(entity, t, [x - 273.15 for x in v], node, PALETTE[k % len(PALETTE)])
            (gears[g[0]] if g else body).append(entity)
        elif topic.startswith("/gears/"):
            send_gear(out, topic, field, t, v, series, pairs, groups)
        elif topic == "/thermal/heat":
            entity = f"heat/{field}"
            k = len(groups["heat flows (W)"])
            out.series(entity, t, v, field[:-2] if field.endswith("_w") else field, PALETTE[k % len(PALETTE)])
            groups["heat flows (W)"].append(entity)
        elif topic.startswith("/diagnose/"):
            # diagnose.mcap: one topic per channel, fields recorded/baseline/corrected/residuals
            ch = topic.rsplit("/", 1)[-1]
            if field == "train":
                continue  # the fitted/held-out flag, not a series
            entity = f"diagnose/{ch}/{field}"
            # the recording and the residuals (each at a reading) as points, so that
            # nothing is drawn across the recording's gaps; the corrected model as
            # the boldest line (the view's title names the channel)
            out.series(entity, t, v, field.replace("_", " "), DIAGNOSE_COLORS.get(field),
                       points=field == "recorded" or field.startswith("residual"),
                       width=2.5 if field.endswith(("corrected", "after")) else None)
            key = "residuals" if field.startswith("residual") else "series"
            groups[f"{ch}: {key}"].append(entity)
        elif topic == "/orbit/faces" and face_flux(field, channels):
            # one view per flux (six faces of three fluxes on one axis were 18 lines
            # whose legend covered the plot), each face by its name and colour
            face, kind = face_flux(field, channels)
            entity = f"orbit/faces/{field}"
            faces = sorted({face_flux(f, channels)[0] for (tp, f) in series if tp == topic and face_flux(f, channels)})
            out.series(entity, t, v, face, PALETTE[faces.index(face) % len(PALETTE)])
            groups[f"faces: {kind}, incident (W/m²)"].append(entity)
        else:
            entity = f"{topic.strip('/')}/{field}"
            out.series(entity, t, v, field)
            groups[f"{topic.strip('/')}: {unit_group(field)}"].append(entity)
    return groups, body, gears


FLUXES = (("solar", "direct Sun"), ("albedo", "albedo"), ("earth_ir", "Earth infrared"))


def face_flux(field, channels):
    """(face, flux) of a field of `/orbit/faces`: from the channel metadata's
    `face:<field>` = `<node>.<face>.<flux>_w_per_m2` (`panel_px.px`, "direct Sun"), else
    from the field's suffix; None for a field that is neither."""
    name = channels.get("/orbit/faces", (None, {}))[1].get(f"face:{field}", field)
    for key, said in FLUXES:
        for sep in (".", "_"):
            suffix = f"{sep}{key}_w_per_m2"
            if name.endswith(suffix):
                return name[: -len(suffix)], said
    return None


# A field's unit from its name's suffix, for one axis per unit.
UNITS = [("_w_per_m2", "W/m²"), ("_deg", "deg"), ("_mm", "mm"), ("_um", "µm"), ("_k", "K"), ("_w", "W")]


def unit_group(field):
    """The view a field of the second tab goes to: its unit (`solar_flux_w_per_m2` →
    `W/m²`), or the field itself when its name carries none (`sunlit`,
    `contact_ratio`), so that one axis never mixes units."""
    return next((u for sfx, u in UNITS if field.endswith(sfx)), field.replace("_", " "))


def backlash_range(series):
    """The backlash views' axis: from 0 (or 10 % below the smallest backlash logged,
    when it is negative: interference must stay in view) to 10 % above the largest;
    None without a positive backlash."""
    values = [x for (topic, field), (_, v) in series.items()
              if topic.startswith("/gears/") and field in BACKLASH_FIELDS for x in v if math.isfinite(x)]
    if not values or max(values) <= 0:
        return None
    return (min(0.0, 1.1 * min(values)), 1.1 * max(values))


def diagnose_title(key):
    """A diagnose view's title with its unit: `housing_c: series` → `housing_c:
    recorded, baseline, corrected (°C)`; `…: residuals` → `…: residual before, after
    (K)` (a temperature difference is in kelvin)."""
    ch, kind = key.rsplit(": ", 1)
    unit = {"_c": ("°C", "K"), "_um": ("µm", "µm"), "_k": ("K", "K")}
    level, diff = next((u for sfx, u in unit.items() if ch.endswith(sfx)), ("", ""))
    if kind == "series":
        return f"{ch}: recorded, baseline, corrected" + (f" ({level})" if level else "")
    return f"{ch}: residual before, after" + (f" ({diff})" if diff else "")


def late_smallest(series, pairs, origin_ns, span_s):
    """The titles of the backlash views whose pair has its smallest backlash in the
    second half of the run (their legend goes left)."""
    late = set()
    for topic in {topic for topic, _ in series if topic.startswith("/gears/")}:
        low = smallest_point(topic, series, pairs, origin_ns)
        if low.t_ns is not None and (low.t_ns - origin_ns) * 1e-9 > 0.5 * span_s:
            pair = topic[len("/gears/"):].replace("/", "_")
            late |= {f"backlash, gear pair {pair} (µm)", f"backlash per orbit, gear pair {pair} (µm)"}
    return late


CORNERS = ("RightTop", "LeftTop", "RightBottom", "LeftBottom")


def legend_corner(entities, shape, origin_ns, span_s):
    """The corner of a view where its legend hides the fewest of its points: each corner
    box about a third of the width and a tenth of the height per entry (at most
    two thirds), over the view's data range; ties go in the order of CORNERS."""
    import numpy as np

    pts = [shape[e] for e in entities if e in shape]
    if not pts:
        return "RightTop"
    # each line where it runs, on an even grid of its time (a long straight segment
    # counts as much as a wiggle); a single point (a marker) as itself
    grid = np.linspace(0.0, 1.0, 400)
    ts, vs = [], []
    for tp, vp in pts:
        x = (tp - origin_ns) * 1e-9 / max(span_s, 1e-9)
        keep = np.isfinite(x) & np.isfinite(vp)
        x, y = x[keep], vp[keep]
        if len(x) > 1:
            g = grid[(grid >= x[0]) & (grid <= x[-1])]
            ts.append(g)
            vs.append(np.interp(g, x, y))
        else:
            ts.append(x)
            vs.append(y)
    t = np.concatenate(ts) if ts else np.array([])
    v = np.concatenate(vs) if vs else np.array([])
    ok = np.isfinite(t) & np.isfinite(v)
    t, v = t[ok], v[ok]
    if len(v) == 0:
        return "RightTop"
    lo, hi = v.min(), v.max()
    y = (v - lo) / (hi - lo) if hi > lo else np.full_like(v, 0.5)
    w, h = 0.35, min(0.67, 0.05 + 0.1 * len(entities))
    inside = {
        "RightTop": (t > 1 - w) & (y > 1 - h),
        "LeftTop": (t < w) & (y > 1 - h),
        "RightBottom": (t > 1 - w) & (y < h),
        "LeftBottom": (t < w) & (y < h),
    }
    return min(CORNERS, key=lambda c: (int(inside[c].sum()), CORNERS.index(c)))


def make_blueprint(name, groups, body, gears, has_events, span_s, envelopes=None, backlash_axis=None,
                   late_smallest=(), corner=None):
    """The views: temperatures beside backlash, heat flows and the eclipse flag on the
    first tab; diagnose.mcap's fits; everything else (mesh geometry, orbit, faces,
    events) on the last. Every plot shows the whole run (0 … span_s), not a window
    around the time cursor; its legend in the corner `corner(entities)` says (where
    it hides the fewest points; backlash: at the top, away from the run's smallest)."""
    import rerun as rr
    import rerun.blueprint as rrb

    whole = rr.TimeRange(
        start=rr.TimeRangeBoundary.absolute(seconds=0.0),
        end=rr.TimeRangeBoundary.absolute(seconds=span_s),
    )

    def view(title, entities):
        # backlash: the legend at the top (the minima are at the bottom), on the side
        # away from the run's smallest, and the axis from 0 (or below, for
        # interference) so that the smallest allowed line is not the bottom edge
        backlash = title.startswith(("backlash,", "backlash per orbit"))
        return rrb.TimeSeriesView(
            name=title,
            origin="/",
            contents=[f"/{e}" for e in entities],
            axis_x=rrb.archetypes.TimeAxis(view_range=whole, link="Independent"),
            axis_y=(rrb.ScalarAxis(range=backlash_axis) if backlash and backlash_axis
                    else rrb.ScalarAxis(range=(0.0, 100.0)) if title.startswith("sunlit share") else None),
            plot_legend=rrb.PlotLegend(
                ("LeftTop" if title in late_smallest else "RightTop") if backlash
                else corner(entities) if corner else "RightTop"),
        )

    temps = []
    if body:
        temps.append(view("nodes other than gears (°C)" if gears else "node temperatures (°C)", body))
    for g, ents in sorted(gears.items()):
        temps.append(view(f"{g}: radial nodes, bore r0 … rim (°C)", ents))
    diag = (": series", ": residuals")
    main = [view(k, v) for k, v in groups.items() if k.startswith(("backlash", "heat")) and not k.endswith(diag)]
    sunlit = [e for e in groups.get("orbit/state: sunlit", []) if e.endswith("/sunlit")]
    if sunlit:
        main.append(view("sunlit (1) or eclipse (0)", sunlit))
    fitted = [view(diagnose_title(k), v) for k, v in groups.items() if k.endswith(": series")]
    residuals = [view(diagnose_title(k), v) for k, v in groups.items() if k.endswith(": residuals")]
    rest = [view(k, v) for k, v in groups.items() if not k.startswith(("backlash", "heat")) and not k.endswith(diag)]
    if has_events:
        rest.append(rrb.TextLogView(name="events", origin="/events"))
    panes = [rrb.Vertical(*x) for x in (temps, main) if x]
    tabs = []
    if envelopes:  # a long run: the whole mission per orbit first, quick to load
        # the body's nodes first, then each gear's
        hot = sorted((k for k in envelopes if "°C" in k), key=lambda k: (not k.startswith("node"), k))
        cold = [k for k in envelopes if "°C" not in k]
        # each view as tall as its legend needs: a body of four nodes has eight entries
        # (min and max), which a third of the column cut off above two gears of six;
        # at most three times a small view's share (a body of fifty nodes would leave
        # the gears' views a few pixels)
        columns = [([view(k, envelopes[k]) for k in keys], [min(max(4, len(envelopes[k])), 12) for k in keys])
                   for keys in (hot, cold) if keys]
        tabs.append(rrb.Horizontal(*(rrb.Vertical(*x, row_shares=shares) for x, shares in columns),
                                   name=f"{name}: per orbit, min and max"))
    tabs += [rrb.Horizontal(*panes, name=name)] if panes else []
    # diagnose.mcap: recorded, baseline and corrected per channel; then the residuals
    if fitted:
        tabs.append(rrb.Grid(*fitted, name="recorded, baseline, corrected"))
    if residuals:
        tabs.append(rrb.Grid(*residuals, name="residuals before and after"))
    if rest:
        # named by what it holds (a model without gears has no mesh geometry), three
        # views a row at most (four cut titles and time axes)
        held = [w for w, there in (("mesh", any(k.startswith("mesh") for k in groups)),
                                   ("orbit", any(k.startswith(("orbit", "faces")) for k in groups)),
                                   ("events", has_events)) if there]
        tabs.append(rrb.Grid(*rest, grid_columns=min(3, len(rest)), name=", ".join(held) or "more"))
    return rrb.Blueprint(
        rrb.Tabs(*tabs),
        rrb.TimePanel(timeline="sim_time", state="collapsed"),
        collapse_panels=True,
    )


def export(log, out, partial):
    """Writes the log as an .rrd to `partial`, then renames it to `out`."""
    import rerun as rr

    series, texts, channels, meta = read_log(log)
    prov = meta.get("orbitlash.provenance", {})
    origin_ns = int(prov.get("time_origin_unix_ns", "0") or 0)
    pairs = run_pairs(meta, channels)
    name = prov.get("scenario_name", os.path.basename(log))
    rec_id = f"{prov.get('scenario_sha256', 'unknown')[:16]}-seed{prov.get('seed', '0')}-{os.path.basename(log)}"
    rec = rr.RecordingStream(APP_ID, recording_id=rec_id)
    rec.save(partial)
    try:
        recording = Recording(rec, origin_ns)
        starts = orbit_starts(series)
        # the per-orbit series first: the viewer draws them while the samples load
        eclipses = json.loads(meta.get("orbitlash.run_end", {}).get("eclipses_json", "null") or "null")
        envelopes = (send_envelopes(recording, series, channels, pairs, starts, eclipses)
                     if starts is not None else None)
        groups, body, gears = send_series(recording, series, channels, pairs)
        recording.events(texts)
        end_ns = recording.t_end_ns
        span_s = (end_ns - origin_ns) * 1e-9 if end_ns is not None else 1.0
        top = backlash_range(series)
        late = late_smallest(series, pairs, origin_ns, span_s)
        corner = lambda ents: legend_corner(ents, recording.shape, origin_ns, span_s)  # noqa: E731
        rec.send_blueprint(make_blueprint(name, groups, body, gears, bool(texts), span_s, envelopes, top, late,
                                          corner))
        rec.flush()
    finally:
        rec.disconnect()
    os.replace(partial, out)
    n = sum(len(x[0]) for x in series.values())
    print(f"{out}: {len(series)} series, {n} points, {len(texts)} events; app id {APP_ID!r}, "
          f"timeline sim_time{' and utc' if origin_ns else ''}")


def same_file(a, b):
    """Whether two paths are one file: the same resolved path, or the same inode (a
    hard link)."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist
        return False


def refusal(path, log, force):
    """Why the export must not write `path` (a phrase), or None when it may."""
    if same_file(path, log):
        return "it is the log itself"
    if os.path.islink(path):
        return "it is a symbolic link (give the file itself, or another name)"
    if not os.path.lexists(path):
        return None
    mode = os.lstat(path).st_mode
    if stat.S_ISDIR(mode):
        return "it is a directory"
    if not stat.S_ISREG(mode):
        return "it is not a regular file (a device, FIFO or socket)"
    if force:
        return None
    with open(path, "rb") as f:
        head = f.read(4)
    if head not in RRD_MAGICS:
        return f"it exists and is not an .rrd (it does not start with {RRD_MAGICS[0].decode()}); --force writes over it"
    return None


def unreadable(e):
    """The one-line reason an export failed."""
    from mcap.stream_reader import CRCValidationError

    if isinstance(e, CRCValidationError):
        return ("a chunk's CRC does not match its bytes: the file is damaged (it changed after it was "
                "written); `orbitlash recover` writes a copy without the damaged chunks")
    return f"{type(e).__name__}: {' '.join(str(e).split())}"


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("log", help="an orbitlash MCAP log")
    p.add_argument("-o", "--out", help="the .rrd to write (default: beside the log, .rrd)")
    p.add_argument("--force", action="store_true",
                   help="write over an existing file that is not an .rrd (never over the log, a link, a directory or a device)")
    a = p.parse_args(argv)
    missing = missing_package()
    if missing:
        package, e = missing
        print(f"rerun_export.py needs the Python package `{package}`: pip install -r viewer/requirements.txt ({e})",
              file=sys.stderr)
        return 2
    out = a.out or os.path.splitext(a.log)[0] + ".rrd"
    partial = out + ".partial"
    for path in (out, partial):
        why = refusal(path, a.log, a.force)
        if why:
            print(f"error: will not write {path}: {why}", file=sys.stderr)
            return 2
    if not os.path.isdir(os.path.dirname(os.path.abspath(out))):
        print(f"error: --out {out}: its folder does not exist", file=sys.stderr)
        return 2
    try:
        export(a.log, out, partial)
    except Exception as e:  # a damaged or foreign file: the reader's own words, exit 2
        print(f"error: {a.log}: {unreadable(e)}", file=sys.stderr)
        return 2
    finally:  # after a failure (or Ctrl-C): no half .rrd
        if os.path.lexists(partial):
            os.remove(partial)
    return 0


if __name__ == "__main__":
    sys.exit(main())

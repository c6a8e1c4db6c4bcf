#!/usr/bin/env python3
"""Measured against simulated, per channel, before and after `diagnose`: an SVG figure
from `series.csv` of `orbitlash diagnose --out DIR` (no plotting library needed). One
panel per channel: the recording (dots), the baseline model (grey) and the corrected
model (blue), the held-out orbits shaded, and each model's held-out RMSE in the title.

    python3 tools/plot_diagnose.py DIR/series.csv OUT.svg [TITLE] [--hours A B]

--hours A B draws only hours A to B of the recording (the whole day is ~14 orbits).
"""
import csv
import math
import sys


def rmse(rows, ch, key):
    d = [float(r[f"{ch}.recorded"]) - float(r[f"{ch}.{key}"])
         for r in rows if r["part"] == "holdout" and r[f"{ch}.recorded"] != ""]
    return math.sqrt(sum(x * x for x in d) / len(d)) if d else float("nan")


def main():
    args = sys.argv[1:]
    window = None
    if "--hours" in args:
        i = args.index("--hours")
        window = (float(args[i + 1]), float(args[i + 2]))
        del args[i:i + 3]
    src, out = args[0], args[1]
    title = args[2] if len(args) > 2 else src
    rows = list(csv.DictReader(open(src)))
    channels = [c[: -len(".recorded")] for c in rows[0] if c.endswith(".recorded")]
    shown = [r for r in rows if window is None or window[0] <= float(r["time_s"]) / 3600 <= window[1]]
    t = [float(r["time_s"]) / 3600.0 for r in shown]
    cols, n = 2, len(channels)
    nrows = (n + cols - 1) // cols
    W, left, right, top, pw_gap, ph, gap = 1100, 60, 20, 70, 60, 170, 55
    pw = (W - left - right - (cols - 1) * pw_gap) / cols
    H = top + nrows * (ph + gap) + 20
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H:.0f}" font-family="sans-serif" font-size="11">',
           f'<rect width="{W}" height="{H:.0f}" fill="white"/>',
           f'<text x="{W/2}" y="24" text-anchor="middle" font-size="15">{title}</text>',
           f'<g font-size="12"><circle cx="{W/2-250}" cy="44" r="3" fill="#222"/>'
           f'<text x="{W/2-242}" y="48">recorded (measured rows)</text>'
           f'<line x1="{W/2-60}" y1="44" x2="{W/2-35}" y2="44" stroke="#999" stroke-width="2"/>'
           f'<text x="{W/2-30}" y="48">baseline model</text>'
           f'<line x1="{W/2+90}" y1="44" x2="{W/2+115}" y2="44" stroke="#1f5fbf" stroke-width="2"/>'
           f'<text x="{W/2+120}" y="48">corrected model</text>'
           f'<rect x="{W/2+235}" y="38" width="14" height="12" fill="#fdf0d0"/>'
           f'<text x="{W/2+254}" y="48">held out (never fitted)</text></g>']
    t0, t1 = t[0], t[-1]
    for k, ch in enumerate(channels):
        gx = left + (k % cols) * (pw + pw_gap)
        gy = top + (k // cols) * (ph + gap) + 10
        x = lambda v: gx + (v - t0) / (t1 - t0) * pw
        rec = [float(r[f"{ch}.recorded"]) if r[f"{ch}.recorded"] != "" else None for r in shown]
        base = [float(r[f"{ch}.baseline"]) for r in shown]
        corr = [float(r[f"{ch}.corrected"]) for r in shown]
        vals = [v for v in rec if v is not None] + base + corr
        lo, hi = math.floor(min(vals) / 10) * 10, math.ceil(max(vals) / 10) * 10
        y = lambda v: gy + ph - (v - lo) / (hi - lo) * ph
        # held-out span
        ho = [tt for tt, r in zip(t, shown) if r["part"] == "holdout"]
        if ho:
            svg.append(f'<rect x="{x(ho[0]):.1f}" y="{gy}" width="{x(ho[-1]) - x(ho[0]):.1f}" height="{ph}" fill="#fdf0d0"/>')
        svg.append(f'<rect x="{gx}" y="{gy}" width="{pw:.1f}" height="{ph}" fill="none" stroke="#333"/>')
        for v in range(int(lo), int(hi) + 1, 10):
            svg.append(f'<line x1="{gx}" y1="{y(v):.1f}" x2="{gx + pw:.1f}" y2="{y(v):.1f}" stroke="#eee"/>')
            svg.append(f'<text x="{gx - 5}" y="{y(v) + 4:.1f}" text-anchor="end">{v}</text>')
        step = 2 if (t1 - t0) > 8 else 1
        for h in range(math.ceil(t0), math.floor(t1) + 1, step):
            svg.append(f'<text x="{x(h):.1f}" y="{gy + ph + 14}" text-anchor="middle">{h}</text>')
        for series, color in [(base, "#999"), (corr, "#1f5fbf")]:
            pts = " ".join(f"{x(tt):.1f},{y(v):.1f}" for tt, v in zip(t, series))
            svg.append(f'<polyline points="{pts}" fill="none" stroke="{color}" stroke-width="1.4"/>')
        for tt, v in zip(t, rec):
            if v is not None:
                svg.append(f'<circle cx="{x(tt):.1f}" cy="{y(v):.1f}" r="1.3" fill="#222"/>')
        svg.append(f'<text x="{gx + pw / 2:.1f}" y="{gy - 6}" text-anchor="middle" font-size="12">'
                   f'{ch} (°C): held-out RMSE {rmse(rows, ch, "baseline"):.2f} → {rmse(rows, ch, "corrected"):.2f}</text>')
    svg.append(f'<text x="{W/2}" y="{H - 6:.0f}" text-anchor="middle">hours since the start (UTC 00:00)</text>')
    svg.append("</svg>")
    open(out, "w").write("\n".join(svg))


if __name__ == "__main__":
    main()

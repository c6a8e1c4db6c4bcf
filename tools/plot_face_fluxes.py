#!/usr/bin/env python3
"""Per-face incident fluxes of one orbit from `orbitlash environment --csv` as an SVG
figure (no plotting library needed): solar, albedo and Earth infrared, one panel each,
one line per face, eclipses shaded.

    python3 tools/plot_face_fluxes.py ENV.csv OUT.svg [TITLE]
"""
import csv
import math
import sys

COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f"]


def main():
    src, out = sys.argv[1], sys.argv[2]
    title = sys.argv[3] if len(sys.argv) > 3 else src
    rows = list(csv.DictReader(open(src)))
    t = [float(r["time_s"]) / 60.0 for r in rows]
    lit = [float(r["sunlit"]) for r in rows]
    faces = [c[: -len(".solar_w_per_m2")] for c in rows[0] if c.endswith(".solar_w_per_m2")]
    kinds = [("solar", "direct Sun"), ("albedo", "Earth albedo"), ("earth_ir", "Earth infrared")]
    W, H, left, right, top, ph, gap = 900, 760, 80, 150, 60, 190, 50
    pw = W - left - right
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<text x="{W/2}" y="28" text-anchor="middle" font-size="15">{title}</text>']
    t0, t1 = t[0], t[-1]
    x = lambda v: left + (v - t0) / (t1 - t0) * pw
    for k, (key, label) in enumerate(kinds):
        y0 = top + k * (ph + gap)
        series = {f: [float(r[f"{f}.{key}_w_per_m2"]) for r in rows] for f in faces}
        vmax = max(max(s) for s in series.values()) or 1.0
        step = 10 ** math.floor(math.log10(vmax)) / 2
        vmax = math.ceil(vmax / step) * step
        y = lambda v: y0 + ph - v / vmax * ph
        # eclipses shaded
        i = 0
        while i < len(t) - 1:
            if lit[i] < 0.5:
                j = i
                while j < len(t) - 1 and lit[j] < 0.5:
                    j += 1
                svg.append(f'<rect x="{x(t[i]):.1f}" y="{y0}" width="{x(t[j])-x(t[i]):.2f}" height="{ph}" fill="#e8e8e8"/>')
                i = j
            i += 1
        svg.append(f'<rect x="{left}" y="{y0}" width="{pw}" height="{ph}" fill="none" stroke="black"/>')
        for j in range(5):
            v = vmax * j / 4
            svg.append(f'<line x1="{left-4}" x2="{left}" y1="{y(v):.1f}" y2="{y(v):.1f}" stroke="black"/>')
            svg.append(f'<text x="{left-8}" y="{y(v)+4:.1f}" text-anchor="end">{v:g}</text>')
        svg.append(f'<text x="{left}" y="{y0-8}" font-size="13">{label}, W/m² (incident)</text>')
        for i, f in enumerate(faces):
            pts = " ".join(f"{x(a):.1f},{y(b):.1f}" for a, b in zip(t, series[f]))
            svg.append(f'<polyline points="{pts}" fill="none" stroke="{COLORS[i % len(COLORS)]}" stroke-width="1.6"/>')
    yb = top + 3 * ph + 2 * gap
    tick = 10.0 if t1 - t0 <= 200 else 10 ** math.floor(math.log10(t1 - t0))
    v = math.ceil(t0 / tick) * tick
    while v <= t1:
        svg.append(f'<text x="{x(v):.1f}" y="{yb+18}" text-anchor="middle">{v:.0f}</text>')
        svg.append(f'<line x1="{x(v):.1f}" x2="{x(v):.1f}" y1="{yb}" y2="{yb+5}" stroke="black"/>')
        v += tick
    svg.append(f'<text x="{left+pw/2}" y="{top+3*ph+2*gap+40}" text-anchor="middle">time from the start, min (grey: eclipse)</text>')
    for i, f in enumerate(faces):
        yy = top + 20 + i * 20
        svg.append(f'<line x1="{W-right+15}" x2="{W-right+40}" y1="{yy}" y2="{yy}" stroke="{COLORS[i % len(COLORS)]}" stroke-width="3"/>')
        svg.append(f'<text x="{W-right+46}" y="{yy+4}">{f.split(".")[-1]}</text>')
    svg.append("</svg>")
    open(out, "w").write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main()

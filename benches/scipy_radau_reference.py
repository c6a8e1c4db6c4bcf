"""SciPy Radau baseline for the orbitlash reference hinge (speed and agreement check).

What it models
--------------
The lumped thermal network of the reference mechanism ``reference-hinge``: 10 diffusion
nodes (housing, motor, shaft1, shaft2, gear1.r0..r2, gear2.r0..r2), two boundary nodes
(``bus`` at 293.15 K, ``space`` at 3 K), 12 linear conductors, 4 radiative conductors
(sigma * epsA * (Tj^4 - Ti^4)) and one load: the Sun on the housing,
Q_sun = alpha * A * S = 0.7 * 0.025 m^2 * 1361 W/m^2 while sunlit, 0 in eclipse (the face
tracks the Sun, so no incidence factor).  Albedo and Earth IR are switched off in the
reference model and are not included.  Circular orbit, altitude 500 km, beta = 20 deg,
theta(t) = 2 pi t / T with theta = 0 at orbit noon, cylindrical shadow (no penumbra):
eclipsed when cos(theta) cos(beta) < 0 and (R+h)^2 (1 - cos^2 theta cos^2 beta) < R^2,
i.e. for theta in (pi - phi, pi + phi), cos(phi) = sqrt((R+h)^2 - R^2) / ((R+h) cos beta).
Every diffusion node starts at 293.15 K.

Where the numbers come from
---------------------------
``/work/shared/spec/reference-mechanism.md`` (sections 1 and 2) and the same case as TOML,
``scenarios/reference-hinge.toml``, which this script reads with ``tomllib``.  The derived
quantities (period 5676.978 s, eclipse half-angle 66.526 deg, eclipse fraction 0.36959)
are recomputed here and checked against the digits the spec gives.  The conductances are
the tabulated values (e.g. 1.585 W/K for the pinion body, not the unrounded
2 pi k b / ln(r+/r-) = 1.58494...).  This is an independent implementation: nothing is
taken from the orbitlash Rust source or from its output.

Solver settings
---------------
``scipy.integrate.solve_ivp(method="Radau", rtol=1e-6, atol=1e-6)`` with the *analytic*
Jacobian (constant linear-conductor matrix plus the 4 sigma epsA T^3 radiation terms),
default first step and no max_step.  The Sun load is discontinuous at eclipse entry and
exit, so the run is integrated piecewise: one ``solve_ivp`` call per sunlit or eclipse
arc (eclipse entry/exit times computed in closed form), the state carried across each
edge, so the solver never steps over a discontinuity.  Output is taken at every 30 s
(``t_eval``, the same grid orbitlash writes) inside the timed runs.

Timing: median wall time of ``--repeat`` full runs (default 5), in ms per orbit; the
numbers of accepted steps, RHS evaluations and Jacobian evaluations (summed over the
arcs) are printed too.

Run (from /work/main)
---------------------
    /work/main/.venv/bin/python benches/scipy_radau_reference.py \
        [--orbits N] [--repeat K] [--compare orbitlash.csv] [--json out.json]

``--compare`` reads an orbitlash CSV (``time_s``, ``<node>_k`` columns, e.g. written by
``orbitlash run --csv OUT.csv``), evaluates this solution at its times (untimed run) and
prints the largest |T_scipy - T_orbitlash| per node.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import platform
import statistics
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import scipy
from scipy.integrate import solve_ivp

SIGMA = 5.670374419e-8  # W/m^2 K^4 (spec section 2)
RTOL = 1e-6
ATOL = 1e-6
OUTPUT_INTERVAL_S = 30.0
DEFAULT_SCENARIO = Path(__file__).resolve().parent.parent / "scenarios" / "reference-hinge.toml"


# --------------------------------------------------------------------------- model
class Hinge:
    """The reference hinge's thermal network as dT/dt = f(t, T)."""

    def __init__(self, scenario_path: Path):
        with open(scenario_path, "rb") as fh:
            sc = tomllib.load(fh)

        orb, env = sc["orbit"], sc["environment"]
        self.R = float(orb["earth_radius_m"])
        self.h = float(orb["altitude_m"])
        mu = float(orb["mu_m3_per_s2"])
        self.beta = math.radians(float(env["beta_deg"]))
        self.theta0 = math.radians(float(orb.get("orbit_angle_at_start_deg", 0.0)))
        self.S = float(env["solar_flux_w_per_m2"])
        t_space = float(env["space_sink_k"])

        a = self.R + self.h
        self.period = 2.0 * math.pi * math.sqrt(a**3 / mu)
        cos_phi = math.sqrt(a**2 - self.R**2) / (a * math.cos(self.beta))
        if cos_phi >= 1.0:
            self.phi = 0.0  # no eclipse at this beta
        else:
            self.phi = math.acos(cos_phi)
        # Check the derived numbers against the digits in the spec (section 1).
        if sc["scenario"]["name"] == "reference-hinge":
            assert abs(self.period - 5676.978) < 5e-4, self.period
            assert abs(math.degrees(self.phi) - 66.526) < 5e-4, math.degrees(self.phi)
            assert abs(self.phi / math.pi - 0.36959) < 5e-6, self.phi / math.pi

        # Nodes.
        self.names = [n["name"] for n in sc["node"]]
        idx = {n: i for i, n in enumerate(self.names)}
        self.n = len(self.names)
        self.C = np.array([float(n["capacitance_j_per_k"]) for n in sc["node"]])
        self.T0 = np.array([float(n["initial_temperature_k"]) for n in sc["node"]])
        bounds = {"space": t_space}
        for b in sc.get("boundary", []):
            bounds[b["name"]] = float(b["temperature_k"])

        # Linear conductors: K T + b (W), K constant.
        K = np.zeros((self.n, self.n))
        b = np.zeros(self.n)
        for c in sc.get("conductor", []):
            g = float(c["conductance_w_per_k"])
            i, j = c["between"]
            for p, q in ((i, j), (j, i)):
                if p in idx:
                    K[idx[p], idx[p]] -= g
                    if q in idx:
                        K[idx[p], idx[q]] += g
                    else:
                        b[idx[p]] += g * bounds[q]
        self.K, self.b_lin = K, b

        # Radiative conductors between two diffusion nodes (pairs) and to a boundary.
        pi_, pj_, pg_ = [], [], []
        self.rad_bound_sig = np.zeros(self.n)  # sum sigma epsA to boundaries, per node
        rad_bound_src = np.zeros(self.n)  # sum sigma epsA Tb^4
        for r in sc.get("radiation", []):
            sg = SIGMA * float(r["emissivity_area_m2"])
            i, j = r["between"]
            if i in idx and j in idx:
                pi_.append(idx[i]), pj_.append(idx[j]), pg_.append(sg)
            else:
                node, other = (i, j) if i in idx else (j, i)
                self.rad_bound_sig[idx[node]] += sg
                rad_bound_src[idx[node]] += sg * bounds[other] ** 4
        self.pi = np.array(pi_, dtype=int)
        self.pj = np.array(pj_, dtype=int)
        self.pg = np.array(pg_)
        # Constant part of the heat balance (boundary conductors and boundary radiation).
        self.b_const = self.b_lin + rad_bound_src

        # Sun load (tracking face: no incidence factor), sunlit only.
        self.q_sun = np.zeros(self.n)
        for s in sc.get("sun", []):
            assert s.get("incidence", "tracking") == "tracking"
            self.q_sun[idx[s["node"]]] += float(s["absorptivity"]) * float(s["area_m2"]) * self.S
        if sc["scenario"]["name"] == "reference-hinge":
            assert abs(self.q_sun[idx["housing"]] - 0.0175 * self.S) < 1e-9
        for key in ("albedo", "earth_ir", "dissipation", "heater", "face", "mode"):
            assert key not in sc, f"[[{key}]] is not part of the reference model"

        self.invC = 1.0 / self.C

    # -- orbit
    def sunlit(self, t: float) -> bool:
        """The spec's shadow test, used to label arcs (at an arc's midpoint)."""
        a = self.R + self.h
        th = self.theta0 + 2.0 * math.pi * t / self.period
        x = math.cos(th) * math.cos(self.beta)
        return not (x < 0.0 and a * a * (1.0 - x * x) < self.R**2)

    def arcs(self, t_end: float):
        """[(t0, t1, sunlit)] split at every eclipse entry/exit in [0, t_end]."""
        edges = {0.0, t_end}
        if self.phi > 0.0:
            w = 2.0 * math.pi / self.period
            k = 0
            while True:
                base = k * self.period - self.theta0 / w
                t_in = base + (math.pi - self.phi) / w
                t_out = base + (math.pi + self.phi) / w
                if t_in > t_end and t_out > t_end:
                    break
                for t in (t_in, t_out):
                    if 0.0 < t < t_end:
                        edges.add(t)
                k += 1
        ts = sorted(edges)
        return [(t0, t1, self.sunlit(0.5 * (t0 + t1))) for t0, t1 in zip(ts[:-1], ts[1:])]

    # -- right-hand side and Jacobian
    def make_rhs(self, sunlit: bool):
        K, invC, pi, pj, pg = self.K, self.invC, self.pi, self.pj, self.pg
        rbs = self.rad_bound_sig
        src = self.b_const + (self.q_sun if sunlit else 0.0)
        n = self.n

        def rhs(_t, T):
            T4 = T * T * T * T
            q = K @ T + src - rbs * T4
            f = pg * (T4[pj] - T4[pi])  # heat into pi, out of pj
            q += np.bincount(pi, f, n) - np.bincount(pj, f, n)
            return q * invC

        def jac(_t, T):
            T3 = 4.0 * T * T * T
            J = K.copy()
            J[np.arange(n), np.arange(n)] -= rbs * T3
            gi, gj = pg * T3[pi], pg * T3[pj]
            np.add.at(J, (pi, pi), -gi)
            np.add.at(J, (pi, pj), gj)
            np.add.at(J, (pj, pj), -gj)
            np.add.at(J, (pj, pi), gi)
            return J * invC[:, None]

        return rhs, jac


def solve_counting(model: Hinge, orbits: float, t_out=None, rtol=RTOL, atol=ATOL):
    """Piecewise Radau run; returns (times, temperatures, stats) with accepted steps."""
    t_end = orbits * model.period
    if t_out is None:
        t_out = np.arange(0.0, t_end + 1e-9, OUTPUT_INTERVAL_S)
    t_out = np.asarray(t_out, dtype=float)
    out = np.full((t_out.size, model.n), np.nan)
    rhs_fns = {True: model.make_rhs(True), False: model.make_rhs(False)}
    y = model.T0.copy()
    stats = {"steps": 0, "rhs_evals": 0, "jac_evals": 0, "lu_decompositions": 0, "arcs": 0}
    arcs = model.arcs(t_end)
    for k, (t0, t1, lit) in enumerate(arcs):
        last = k == len(arcs) - 1
        sel = (t_out >= t0) & ((t_out <= t1) if last else (t_out < t1))
        fun, jac = rhs_fns[lit]
        # dense_output=True costs one interpolant per step and lets us sample any time
        # while keeping the end-of-arc state; t_eval would drop it.
        sol = solve_ivp(fun, (t0, t1), y, method="Radau", rtol=rtol, atol=atol, jac=jac,
                        dense_output=True)
        if sol.status != 0:
            raise RuntimeError(f"solve_ivp failed on [{t0}, {t1}]: {sol.message}")
        if sel.any():
            out[sel] = sol.sol(t_out[sel]).T
        y = sol.y[:, -1]
        stats["steps"] += len(sol.t) - 1  # accepted steps
        stats["rhs_evals"] += sol.nfev
        stats["jac_evals"] += sol.njev
        stats["lu_decompositions"] += sol.nlu
        stats["arcs"] += 1
    return t_out, out, stats


# --------------------------------------------------------------------------- compare
def read_orbitlash_csv(path: Path, names):
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    t = np.array([float(r["time_s"]) for r in rows])
    T = np.array([[float(r[f"{n}_k"]) if r[f"{n}_k"] != "" else np.nan for n in names]
                  for r in rows])
    return t, T


# --------------------------------------------------------------------------- main
def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--orbits", type=float, default=6.0, help="run length in orbits (default 6)")
    ap.add_argument("--repeat", type=int, default=5, help="timed repetitions (default 5)")
    ap.add_argument("--compare", type=Path, help="orbitlash CSV (time_s, <node>_k columns)")
    ap.add_argument("--json", type=Path, help="write a JSON summary here")
    ap.add_argument("--scenario", type=Path, default=DEFAULT_SCENARIO,
                    help="scenario TOML (default scenarios/reference-hinge.toml)")
    args = ap.parse_args(argv)

    model = Hinge(args.scenario)
    arcs = model.arcs(args.orbits * model.period)
    print("scipy Radau baseline: reference-hinge thermal network")
    print(f"  nodes {model.n}, period {model.period:.3f} s, eclipse half-angle "
          f"{math.degrees(model.phi):.3f} deg (fraction {model.phi / math.pi:.5f})")
    print(f"  Radau rtol={RTOL:g} atol={ATOL:g}, analytic Jacobian, piecewise over "
          f"{len(arcs)} sunlit/eclipse arcs, output every {OUTPUT_INTERVAL_S:g} s")

    # Warm-up (imports, first-call overheads), then the timed runs.
    solve_counting(model, min(args.orbits, 1.0))
    walls = []
    stats = None
    for _ in range(max(1, args.repeat)):
        t0 = time.perf_counter()
        _, T, stats = solve_counting(model, args.orbits)
        walls.append(time.perf_counter() - t0)
    wall = statistics.median(walls)
    ms_per_orbit = 1e3 * wall / args.orbits
    print(f"\n  orbits {args.orbits:g}, repeats {len(walls)}: median wall {1e3 * wall:.1f} ms "
          f"(min {1e3 * min(walls):.1f}, max {1e3 * max(walls):.1f})")
    print(f"  ms per orbit (median): {ms_per_orbit:.2f}")
    print(f"  accepted steps {stats['steps']}, RHS evaluations {stats['rhs_evals']}, "
          f"Jacobian evaluations {stats['jac_evals']}, LU decompositions "
          f"{stats['lu_decompositions']}")

    # Last-orbit extremes, for orientation against the spec's section 5.
    t_grid = np.arange(0.0, args.orbits * model.period + 1e-9, OUTPUT_INTERVAL_S)
    last = t_grid >= (math.ceil(args.orbits) - 1) * model.period
    print(f"\n  last orbit extremes (30 s samples), deg C:")
    for name in ("housing", "gear1.r2", "gear2.r2"):
        j = model.names.index(name)
        print(f"    {name:9s} {T[last, j].min() - 273.15:7.2f} ... {T[last, j].max() - 273.15:6.2f}")

    max_abs = None
    per_node = None
    if args.compare:
        tc, Tc = read_orbitlash_csv(args.compare, model.names)
        keep = tc <= args.orbits * model.period + 1e-6
        tc, Tc = tc[keep], Tc[keep]
        _, Ts, _ = solve_counting(model, args.orbits, t_out=tc)
        d = np.abs(Ts - Tc)
        per_node = {n: float(np.nanmax(d[:, j])) for j, n in enumerate(model.names)}
        max_abs = float(np.nanmax(d))
        jmax = np.unravel_index(np.nanargmax(d), d.shape)
        print(f"\n  compare with {args.compare} ({tc.size} rows, t <= {tc[-1]:.1f} s):")
        for n, v in per_node.items():
            print(f"    {n:9s} max |dT| = {v:.4f} K")
        print(f"  overall max |T_scipy - T_orbitlash| = {max_abs:.4f} K "
              f"({model.names[jmax[1]]} at t = {tc[jmax[0]]:.1f} s)")
        if max_abs > 0.5:
            print("  WARNING: disagreement above 0.5 K")

    if args.json:
        doc = {
            "ms_per_orbit": ms_per_orbit,
            "orbits": args.orbits,
            "repeat": len(walls),
            "steps": stats["steps"],
            "rhs_evals": stats["rhs_evals"],
            "jac_evals": stats["jac_evals"],
            "max_abs_diff_k": max_abs,
            "max_abs_diff_k_per_node": per_node,
            "solver": {"method": "Radau", "rtol": RTOL, "atol": ATOL, "jacobian": "analytic",
                       "piecewise_arcs": len(arcs)},
            "python": platform.python_version(),
            "scipy": scipy.__version__,
            "numpy": np.__version__,
        }
        args.json.write_text(json.dumps(doc, indent=2) + "\n")
        print(f"\n  wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Benchmark: the height field's evaluation on floats (core/ground/terrain.py), against the
``core/ground/terrain.py`` of an earlier revision in the same run.  Prints a Markdown table.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_heightfield.py --baseline f34ecfa~1 [--repeat 5]

- ``derivatives_one`` (height and five derivatives) and ``slopes_one`` (the five derivatives:
  what the stepper asks at every RK4 stage) at 20,000 random points of the demo's mogul slope
  (``terrain_gen.ski_slope``, 2 m cells), warm (every cell's coefficients computed), us a point;
- the cold cost: the coefficients of one cell, the first time a figure enters it;
- a 60 s slalom down the mogul slope with the skier's friction and drag (``simulate``), the
  case of ``bench_core.py --terrain``.

The baseline module is the file ``git show REV:blender_turning/core/ground/terrain.py`` loaded as a
sibling of ``core/ground/terrain.py`` (its relative imports resolve in this checkout).
"""
from __future__ import annotations

import argparse
import datetime
import importlib.util
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start
from blender_turning.core.ground import terrain as current
from blender_turning.core.physics.model import RESISTANCE
from blender_turning.core.ground.terrain_gen import ski_slope
from bench_common import best  # noqa: E402  (scripts/)

ROOT = Path(__file__).resolve().parent.parent


def baseline_module(rev: str):
    """``core/ground/terrain.py`` at ``rev``, imported as ``blender_turning.core._terrain_baseline``."""
    text = subprocess.run(["git", "show", f"{rev}:blender_turning/core/ground/terrain.py"], cwd=ROOT,
                          capture_output=True, text=True, check=True).stdout
    folder = Path(tempfile.mkdtemp(prefix="bench-heightfield-"))
    path = folder / "terrain_baseline.py"
    path.write_text(text)
    name = "blender_turning.core._terrain_baseline"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def per_point(field, xs, ys, repeat):
    """us a point of ``derivatives_one`` and ``slopes_one``, warm."""
    for x, y in zip(xs, ys):                                  # every cell's coefficients
        field.derivatives_one(x, y)
    one, slopes = field.derivatives_one, field.slopes_one
    pts = list(zip(xs, ys))
    t_one = best(lambda: [one(x, y) for x, y in pts], repeat) / len(pts)
    t_slopes = best(lambda: [slopes(x, y) for x, y in pts], repeat) / len(pts)
    return t_one * 1e6, t_slopes * 1e6


def per_cell(module, heights, x0, y0, cell, repeat):
    """us for the coefficients of one cell (a fresh field, 2,000 cells)."""
    def go():
        f = module.HeightField(heights, x0, y0, cell)
        for k in range(2000):
            f._cell(k % (f.nx - 1), k // (f.nx - 1))
    return best(go, repeat) / 2000 * 1e6


def run_60s(field, repeat):
    fig = preset("skier")
    w, tm, fall = math.pi, math.radians(23), -math.pi / 2

    def go():
        s0 = slalom_start(fig.body, w, tm, fall, -40.0, 790.0)
        return simulate(fig, PhaseEllipse(fig.body, w, tm, heading=fall), 60.0, 0.02, s0,
                        ground=field, resistance=RESISTANCE["skier"])
    go()                                                      # the feasibility tables, cells
    return best(go, repeat)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--baseline", required=True, help="git revision of the baseline terrain.py")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    old = baseline_module(args.baseline)
    slope = ski_slope(length=1600.0, width=400.0, cell=2.0)
    heights = slope._h[2:-2, 2:-2]
    fields = {"baseline": old.HeightField(heights, slope.x0, slope.y0, slope.cell),
              "current": current.HeightField(heights, slope.x0, slope.y0, slope.cell)}
    rng = np.random.default_rng(0)
    xs = rng.uniform(-190.0, 190.0, 20000).tolist()
    ys = rng.uniform(-790.0, 790.0, 20000).tolist()
    rows = {}
    for name in ("baseline", "current", "baseline", "current"):   # interleaved: a noisy machine
        module = old if name == "baseline" else current
        f = fields[name]
        one, sl = per_point(f, xs, ys, args.repeat)
        c = per_cell(module, heights, slope.x0, slope.y0, slope.cell, args.repeat)
        r = run_60s(f, max(1, args.repeat // 2))
        prev = rows.get(name)
        rows[name] = (one, sl, c, r) if prev is None else tuple(map(min, prev, (one, sl, c, r)))
    print(f"date: {datetime.date.today()}, machine: {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}; baseline "
          f"{args.baseline}")
    print()
    print("| height field | derivatives_one | slopes_one | one cell's coefficients "
          "| 60 s slalom, mogul slope |")
    print("|---|---|---|---|---|")
    for name, label in (("baseline", f"bicubic ({args.baseline})"),
                        ("current", "biquintic (this checkout)")):
        one, sl, c, r = rows[name]
        print(f"| {label} | {one:.2f} us | {sl:.2f} us | {c:.1f} us | {r * 1e3:.0f} ms |")
    b, n = rows["baseline"], rows["current"]
    print(f"| ratio | {n[0] / b[0]:.2f}x | {n[1] / b[1]:.2f}x | {n[2] / b[2]:.2f}x "
          f"| {n[3] / b[3]:.2f}x |")


if __name__ == "__main__":
    t0 = time.perf_counter()
    main()
    print(f"\n({time.perf_counter() - t0:.0f} s)")

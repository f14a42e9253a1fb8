"""Benchmark of the feasibility tables (core/controllers/feasible.py): what building one costs,
this tree's ``FeasibleTurns`` against a baseline commit's, in one run.  Prints a Markdown table.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_feasible.py [--base 16452b2] [--repeat 3]

The tables are the demo's kind: each sport's preset body and limits at every 0.5 m/s from
0.5 to 17.5 m/s (a run down the demo's mountain builds one per body and 0.5 m/s of speed).
The baseline's ``feasible.py`` is read from git (``git show BASE:...``) and imported beside
this tree's as a module of the same package.  Also the largest difference of the leans
(baseline minus this tree's, rad) and how many binding bounds differ.  Times are process CPU
(the machine is shared: wall time measures the load), best of ``--repeat``.
"""
from __future__ import annotations

import argparse
import datetime
import importlib.util
import os
import platform
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from blender_turning.core import preset
from blender_turning.core.controllers import feasible

ROOT = Path(__file__).resolve().parent.parent
SOURCE = "blender_turning/core/controllers/feasible.py"
SPORTS = ("skier", "snowboarder", "telemark", "cyclist")


def baseline_module(commit: str):
    """``feasible.py`` as it was at ``commit``, imported as a sibling module of the package
    (its relative imports resolve to this tree's, which it only reads constants from)."""
    text = subprocess.run(["git", "show", f"{commit}:{SOURCE}"], cwd=ROOT, check=True,
                          capture_output=True, text=True).stdout
    name = "blender_turning.core.controllers._feasible_baseline"
    spec = importlib.util.spec_from_loader(name, loader=None)
    mod = importlib.util.module_from_spec(spec)
    mod.__package__ = "blender_turning.core.controllers"
    sys.modules[name] = mod                 # dataclasses look their module up there
    exec(compile(text, f"{commit}:{SOURCE}", "exec"), mod.__dict__)
    return mod


def cases():
    out = []
    for sport in SPORTS:
        p = preset(sport)
        out += [(replace(p.body, V_cm=0.5 * k), p.limits) for k in range(1, 36)]
    return out


def build_all(cls, keys, repeat):
    """Best of ``repeat``: process CPU seconds to build every table; the last tables built."""
    best, tables = float("inf"), None
    for _ in range(repeat):
        t0 = time.process_time()
        tables = [cls(body, limits) for body, limits in keys]
        best = min(best, time.process_time() - t0)
    return best, tables


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default="16452b2", help="the baseline commit")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    keys = cases()
    base = baseline_module(args.base)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                          capture_output=True, text=True).stdout.strip()
    t_base, old = build_all(base.FeasibleTurns, keys, args.repeat)
    t_new, new = build_all(feasible.FeasibleTurns, keys, args.repeat)
    diff = max(float(np.max(np.abs(a._lean - b._lean))) for a, b in zip(old, new))
    bounds = sum(int(np.sum(a._bound != b._bound)) for a, b in zip(old, new))
    print(f"{datetime.datetime.utcnow():%Y-%m-%d %H:%M} UTC, load {os.getloadavg()[0]:.1f}, "
          f"Python {platform.python_version()}, numpy {np.__version__}; "
          f"{len(keys)} tables ({', '.join(SPORTS)} at 0.5-17.5 m/s), best of {args.repeat}")
    print("\n| tree | CPU per table | all tables |\n|---|---|---|")
    print(f"| baseline {args.base} | {1e3 * t_base / len(keys):.1f} ms | {t_base:.2f} s |")
    print(f"| this tree ({head}, LEAN_TOL = {feasible.LEAN_TOL:g} rad) | "
          f"{1e3 * t_new / len(keys):.1f} ms | {t_new:.2f} s |")
    print(f"\nlargest lean difference {diff:.3g} rad; binding bounds that differ: {bounds} of "
          f"{sum(a._bound.size for a in old)}")


if __name__ == "__main__":
    main()

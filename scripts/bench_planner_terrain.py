"""Benchmark the planner on terrain beside the flat slalom, in one process.

Runs each scene file's whole course (``Scene.run``, its own planner settings) ``--repeat`` times
and prints the best planning wall time, the nodes expanded, the replannings and the course's
duration and speeds.  Usage: python scripts/bench_planner_terrain.py [--repeat 3]
"""
from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from blender_turning.core.planner import Problem  # noqa: E402
from blender_turning.core.course.scene import load_scene  # noqa: E402

SCENES = ("slalom", "slope_slalom")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"python {platform.python_version()}, numpy {np.__version__}, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    print("| scene | ground | N | q | replans | nodes expanded | planning wall (best / worst) "
          "| course | speed |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in SCENES:
        sc = load_scene(ROOT / "scenes" / f"{name}.json")
        walls = []
        for _ in range(args.repeat):
            r = sc.run()
            tot = r.totals()
            walls.append(tot["wall_time"])
        tr = r.trajectory
        ground = tr.meta.get("ground", "flat")
        print(f"| {name} | {ground} | {sc.settings.n_stages} | {sc.settings.q} | "
              f"{tot['replans']} | {tot['expanded']} | {min(walls):.2f} / {max(walls):.2f} s | "
              f"{tr.duration:.1f} s, {tr.x[-1] - tr.x[0]:.0f} m | "
              f"{tr.V_cm.min():.1f}-{tr.V_cm.max():.1f} m/s |")
    stage_costs(args.repeat)


def stage_costs(repeat: int, m: int = 640) -> None:
    """One stage for ``m`` nodes (a batch of 128 nodes' 5 children): flat, plane, height field."""
    from blender_turning.core.ground.terrain_gen import ski_slope
    flat = load_scene(ROOT / "scenes" / "slalom.json").problem()
    sc = load_scene(ROOT / "scenes" / "slope_slalom.json")
    plane = sc.problem()
    hf = Problem(sc.figure, plane.distance, plane.obstacles, sc.settings,
                 ground=ski_slope(length=400.0, width=400.0, cell=2.0), resistance=sc.resistance)
    rng = np.random.default_rng(1)
    x = np.zeros((6, m))
    x[0], x[1] = rng.uniform(0, 150, m), rng.uniform(-5, 5, m)
    x[2], x[3], x[5] = rng.uniform(-0.3, 0.3, m), rng.uniform(-0.2, 0.2, m), 12.0
    u = rng.choice(flat.u_values, m)
    z = np.zeros(m)
    print(f"\n| one stage of {m} nodes | best of {repeat} |\n|---|---|")
    for label, p, rows in (("flat (slalom.json)", flat, 5), ("18 deg plane", plane, 6),
                           ("ski_slope height field, 2 m cells", hf, 6)):
        best = np.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            p.simulate_stage(x[:rows], z, u, z, z)
            best = min(best, time.perf_counter() - t0)
        print(f"| {label} | {best * 1e3:.1f} ms |")


if __name__ == "__main__":
    main()

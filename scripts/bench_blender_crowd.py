"""Benchmark of Follow Path on several figures in Blender.  Prints a Markdown table.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_blender_crowd.py [--figures 4] [--gates 4]

``--figures`` telemark figures, each with its own slalom of ``--gates`` gates 12 m apart (3 m to
either side), are planned

- one after the other in Blender's process, as a single-figure Follow Path does (one figure at a
  time: ``follow_scene.prepare(...).run()``, the single-figure job's planner call) -- the baseline:
  *warm* (the planner's fall table, built once per body and settings and kept for the process,
  already built) and *cold* (that cache emptied first: the first plan of a session);
- all at once by the multi-figure job (``blender/jobs/crowd_job.py``): spawned worker processes, one
  per core, started for the job, each importing the core and building its fall table (cold).

Interleaved, best of ``--repeat``.  The plans are checked equal first.  The mapping and bake
after the plans are the same in both and not timed.
"""
from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
import bpy  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
from bench_common import best  # noqa: E402

from blender_turning import blender as addon  # noqa: E402
from blender_turning.blender.jobs import crowd_job  # noqa: E402
from blender_turning.blender.scene import follow_scene  # noqa: E402
from blender_turning.core.planner import fall_table  # noqa: E402


def figures(count, gates=2):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    figs = []
    for i in range(count):
        bpy.context.scene.cursor.location = (8.0 * i, 0.0, 0.0)
        bpy.ops.turning.add_figure(sport="TELEMARK")
        fig = bpy.context.view_layer.objects.active
        curve = bpy.data.curves.new(f"Path{i}", "CURVE")
        sp = curve.splines.new("BEZIER")
        pts = [(8.0 * i, 0)] + [(8.0 * i + 3 * (-1) ** g, -12 * (g + 1)) for g in range(gates)]
        pts.append((8.0 * i, -12 * (gates + 1)))
        sp.bezier_points.add(len(pts) - 1)
        for bp, (x, y) in zip(sp.bezier_points, pts):
            bp.co = (x, y, 0)
            bp.handle_left_type = bp.handle_right_type = "AUTO"
        path = bpy.data.objects.new(f"Path{i}", curve)
        bpy.context.scene.collection.objects.link(path)
        fig.turning.path = path
        fig.turning.plan_curvature_rate = 0.3
        figs.append(fig)
    return figs


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figures", type=int, default=4)
    ap.add_argument("--gates", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args()
    figs = figures(args.figures, args.gates)
    ctx = bpy.context
    out = {}

    def one_by_one():
        kind = "cpu warm" if fall_table._CACHE else "cpu cold"
        c0 = time.process_time()
        plans = [follow_scene.prepare(ctx, f).run() for f in figs]
        out.setdefault(kind, []).append(time.process_time() - c0)
        return plans

    def one_by_one_cold():
        fall_table._CACHE.clear()                  # the process-wide cache of fall tables
        return one_by_one()

    def in_workers():
        job = crowd_job.CrowdFollow(figs, avoid=False)    # each alone, as the baseline
        job.read(ctx)
        t0 = time.perf_counter()
        job.start()
        started = time.perf_counter() - t0
        job.wait()
        out.setdefault("start", []).append(started)
        out["workers"] = job.workers
        results = job.results()
        out.setdefault("cpu workers", []).append(sum(r.cpu_time for _, r in results))
        return results

    alone, together = one_by_one(), in_workers()     # the same plans, bit for bit
    for a, (_, r) in zip(alone, together):
        assert np.array_equal(a.trajectory.data, r.trajectory.data)
    seq, cold, par = [], [], []
    for _ in range(args.repeat):                      # interleaved
        seq.append(best(one_by_one, 1))
        cold.append(best(one_by_one_cold, 1))
        par.append(best(in_workers, 1))
    course = sum(a.trajectory.duration for a in alone)
    print(f"date: {datetime.date.today()}, machine: {platform.machine()}, "
          f"{os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}, "
          f"bpy {bpy.app.version_string}\n")
    print(f"| {args.figures} figures, {args.gates} gates ({course:.1f} s of course in all) "
          "| wall time | vs warm | vs cold |")
    print("|---|---|---|---|")
    w, c, p = min(seq), min(cold), min(par)
    print(f"| one after the other in Blender's process, warm (baseline) | {w:.2f} s | 1.0x | |")
    print(f"| one after the other in Blender's process, cold (baseline) | {c:.2f} s | | 1.0x |")
    print(f"| multi-figure Follow Path, {out['workers']} spawned workers (cold) | {p:.2f} s | "
          f"{w / p:.2f}x | {c / p:.2f}x |")
    print("| of which submitting the plans (starts the worker processes) | "
          f"{min(out['start']):.2f} s | | |")
    print(f"\nCPU s of the plans (least): in Blender's process warm "
          f"{min(out['cpu warm']):.2f}, cold {min(out['cpu cold']):.2f}; in the workers "
          f"{min(out['cpu workers']):.2f} in all (each task's process time; the workers' "
          "imports not counted)")
    print(f"\nall runs: warm {', '.join(f'{t:.2f}' for t in seq)} s; cold "
          f"{', '.join(f'{t:.2f}' for t in cold)} s; workers {', '.join(f'{t:.2f}' for t in par)} s")

if __name__ == "__main__":
    main()

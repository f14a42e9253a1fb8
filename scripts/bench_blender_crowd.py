"""Benchmark of Follow Path on several figures in Blender (issue 11).  Prints a Markdown table.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_blender_crowd.py [--figures 4] [--repeat 2]

``--figures`` telemark figures, each with its own 24 m S-curve (the operator tests' path), are
planned (a) one after the other in Blender's process, as Follow Path did before issue 11 (one
figure at a time: ``ops_path.prepare(...).run()``, the single-figure job's planner call) -- the
baseline -- and (b) all at once by the multi-figure job (``blender/crowd_job.py``: spawned worker
processes, one per core, each importing the core cold), interleaved, best of ``--repeat``.  The
mapping and bake after the plans are the same in both and not timed.  Also: the wall time until
the workers have started (the first result cannot come earlier).
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
from blender_turning.blender import crowd_job, ops_path  # noqa: E402


def figures(count):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    figs = []
    for i in range(count):
        bpy.context.scene.cursor.location = (8.0 * i, 0.0, 0.0)
        bpy.ops.turning.add_figure(sport="TELEMARK")
        fig = bpy.context.view_layer.objects.active
        curve = bpy.data.curves.new(f"Path{i}", "CURVE")
        sp = curve.splines.new("BEZIER")
        pts = [(8.0 * i, 0), (8.0 * i + 3, -12), (8.0 * i - 2, -22)]
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
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args()
    figs = figures(args.figures)
    ctx = bpy.context
    out = {}

    def one_by_one():
        return [ops_path.prepare(ctx, f).run() for f in figs]

    def in_workers():
        job = crowd_job.CrowdFollow(figs)
        job.read(ctx)
        t0 = time.perf_counter()
        job.start()
        started = time.perf_counter() - t0
        job.wait()
        out.setdefault("start", []).append(started)
        out["workers"] = job.workers
        return job.results()

    alone, together = one_by_one(), in_workers()     # the same plans, bit for bit
    for a, (_, r) in zip(alone, together):
        assert np.array_equal(a.trajectory.data, r.trajectory.data)
    seq, par = [], []
    for _ in range(args.repeat):                      # interleaved
        seq.append(best(one_by_one, 1))
        par.append(best(in_workers, 1))
    course = sum(a.trajectory.duration for a in alone)
    print(f"date: {datetime.date.today()}, machine: {platform.machine()}, "
          f"{os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}, "
          f"bpy {bpy.app.version_string}\n")
    print(f"| {args.figures} figures ({course:.1f} s of course in all) | wall time | speed-up |")
    print("|---|---|---|")
    print(f"| one after the other in Blender's process (baseline) | {min(seq):.2f} s | 1.0x |")
    print(f"| multi-figure Follow Path, {out['workers']} spawned workers | {min(par):.2f} s | "
          f"{min(seq) / min(par):.2f}x |")
    print("| of which submitting the plans (starts the worker processes) | "
          f"{min(out['start']):.2f} s | |")
    print(f"\nall runs: baseline {', '.join(f'{t:.2f}' for t in seq)} s; "
          f"workers {', '.join(f'{t:.2f}' for t in par)} s")


if __name__ == "__main__":
    main()

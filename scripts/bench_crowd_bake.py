"""Benchmark: a crowd of 100 parametric figures, 60 s at 24 fps: simulate (one batch), map
(``crowd.map_crowd``: ``mapping.map_trajectory`` per figure, on ``--workers`` processes) and
bake (``blender.bake.bake_pose_track``, whole F-curves with ``foreach_set``, as
``scripts/bench_bake.py``), each step timed; the rigs are built untimed.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_crowd_bake.py [--figures 100] [--workers 2]
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-bench-"))

import bpy  # noqa: E402

from blender_turning.blender import bake, rig_builder  # noqa: E402
from blender_turning.blender import props_rig  # noqa: E402
from blender_turning.blender import props as props_mod  # noqa: E402
from blender_turning.core import preset  # noqa: E402
from blender_turning.crowd import (Crowd, CrowdFigure, Turns, follow_leader,  # noqa: E402
                                   map_crowd, run_crowd)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--figures", type=int, default=100)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--fps", type=int, default=24)
    ap.add_argument("--workers", type=int, default=1, help="processes mapping the figures")
    args = ap.parse_args()
    registered = not hasattr(bpy.types.Object, "turning")
    if registered:                     # the figure settings and their nested groups
        props_rig.register()
        props_mod.register()
    try:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        fig = preset("skier")
        lead = CrowdFigure("lead", fig, Turns(2.0, math.radians(20), 0.0))
        crowd = Crowd("crowd", (lead,) + follow_leader(lead, args.figures - 1, 0.1,
                                                       lateral=[-2, 2], seed=1,
                                                       period_jitter=0.05), args.seconds)
        t = time.perf_counter()
        spec = rig_builder.load_spec("skier")
        objs = [rig_builder.build_figure(bpy.context, spec, f.name, (0.0, 3.0 * i, 0.0))
                for i, f in enumerate(crowd.figures)]
        t_build = time.perf_counter() - t
        t = time.perf_counter()
        res = run_crowd(crowd)
        t_sim = time.perf_counter() - t
        t = time.perf_counter()
        poses = map_crowd(res, args.fps, workers=args.workers)
        t_map = time.perf_counter() - t
        tracks = [poses[f.name] for f in crowd.figures]
        t = time.perf_counter()
        for obj, track in zip(objs, tracks):
            bake.bake_pose_track(obj, track)
        t_bake = time.perf_counter() - t
    finally:
        if registered:
            props_mod.unregister()
            props_rig.unregister()
    frames = sum(len(tr.frames) for tr in tracks)
    print(f"crowd bake: {len(objs)} skiers x {args.seconds:g} s x {args.fps} fps ({frames} "
          f"frames); Blender {bpy.app.version_string}, Python {platform.python_version()}, "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}")
    print(f"  rigs built (untimed) {t_build:.2f} s")
    print(f"  simulate {t_sim:.2f} s, map ({args.workers} worker(s)) {t_map:.2f} s, "
          f"bake {t_bake:.2f} s; "
          f"total {t_sim + t_map + t_bake:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

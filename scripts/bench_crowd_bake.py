"""Benchmark: a crowd of 100 parametric figures, 60 s at 24 fps: simulate (one batch), map
(``crowd.map_crowd``: ``mapping.map_trajectory`` per figure, on ``--workers`` processes) and
bake (``blender.anim.bake.bake_pose_track``, whole F-curves with ``foreach_set``, as
``scripts/bench_bake.py``), each step timed; the rigs are built untimed.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_crowd_bake.py [--figures 100] [--workers 2]

With ``--against DIR`` (a copy of another commit's tree, e.g. ``git archive 4da8091 | tar -x -C
/tmp/base``) it runs the same benchmark on that tree's package and on this one, each in a fresh
process, interleaved ``--repeat`` times (the machine may be shared: the load hits both alike),
and prints the best of each step for both.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if "--root" in sys.argv:                 # the package of another tree (a run for --against)
    ROOT = Path(sys.argv[sys.argv.index("--root") + 1]).resolve()
sys.path.insert(0, str(ROOT))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-bench-"))

import bpy  # noqa: E402

from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.scene import rig_builder  # noqa: E402
from blender_turning import blender as addon  # noqa: E402
from blender_turning.core import preset  # noqa: E402
from blender_turning.crowd import (Crowd, CrowdFigure, Turns, follow_leader,  # noqa: E402
                                   map_crowd, run_crowd)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--figures", type=int, default=100)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--fps", type=int, default=24)
    ap.add_argument("--workers", type=int, default=1, help="processes mapping the figures")
    ap.add_argument("--against", help="another tree to compare with, interleaved")
    ap.add_argument("--repeat", type=int, default=3, help="rounds with --against (best kept)")
    ap.add_argument("--root", help=argparse.SUPPRESS)
    ap.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.against:
        return compare(args)
    registered = not hasattr(bpy.types.Object, "turning")
    if registered:                     # the figure settings and their nested groups
        addon.register()               # the figure settings and their nested groups
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
            addon.unregister()
    frames = sum(len(tr.frames) for tr in tracks)
    if args.json:
        print("JSON" + json.dumps({"simulate": t_sim, "map": t_map, "bake": t_bake,
                                   "frames": frames}))
        return 0
    print(f"crowd bake: {len(objs)} skiers x {args.seconds:g} s x {args.fps} fps ({frames} "
          f"frames); Blender {bpy.app.version_string}, Python {platform.python_version()}, "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}")
    print(f"  rigs built (untimed) {t_build:.2f} s")
    print(f"  simulate {t_sim:.2f} s, map ({args.workers} worker(s)) {t_map:.2f} s, "
          f"bake {t_bake:.2f} s; "
          f"total {t_sim + t_map + t_bake:.2f} s")
    return 0


def compare(args) -> int:
    """The benchmark on ``--against``'s tree (the baseline) and on this one, each in a fresh
    process, interleaved; the best of ``--repeat`` rounds of each step."""
    trees = {"baseline": Path(args.against).resolve(), "this": ROOT}
    best = {k: {} for k in trees}
    loads = [os.getloadavg()[0]]
    for _ in range(args.repeat):
        for name, root in trees.items():
            out = subprocess.run(
                [sys.executable, __file__, "--root", str(root), "--json", "--figures",
                 str(args.figures), "--seconds", str(args.seconds), "--fps", str(args.fps),
                 "--workers", str(args.workers)], capture_output=True, text=True, check=True,
                env=dict(os.environ, PYTHONPATH=str(root)))
            r = json.loads(next(line[4:] for line in out.stdout.splitlines()
                                if line.startswith("JSON")))
            r["total"] = r["simulate"] + r["map"] + r["bake"]
            for k, v in r.items():
                best[name][k] = min(best[name].get(k, v), v)
            loads.append(os.getloadavg()[0])
    print(f"crowd bake: {args.figures} skiers x {args.seconds:g} s x {args.fps} fps "
          f"({best['this']['frames']} frames); Blender {bpy.app.version_string}, Python "
          f"{platform.python_version()}, {os.cpu_count()} CPUs, load average "
          f"{min(loads):.1f}-{max(loads):.1f}; best of {args.repeat}, interleaved, each run in "
          f"a fresh process\n")
    print("| tree | simulate s | map s | bake s | total s |\n|---|---|---|---|---|")
    for name, root in trees.items():
        b = best[name]
        print(f"| {name} ({root}) | {b['simulate']:.2f} | {b['map']:.2f} | {b['bake']:.2f} | "
              f"{b['total']:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())

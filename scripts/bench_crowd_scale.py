"""Benchmark: a crowd's cost per figure-frame against its size, in bpy: build the rigs, simulate
(``crowd.run_crowd``), then figure by figure resample at 24 fps and map
(``mapping.map_trajectory``) and bake (``blender.figure_bake.BakeWriter``, as Bake Turns writes
them: the F-curves and the foot track, with ``--fewer-keys`` then
``blender.fewer_keys.reduce_bake``; a figure whose motion is another's plays its bake, unless
``--no-share``), each step timed, and the process's peak memory.

    .venv/bin/python scripts/bench_crowd_scale.py --figures 10 100 1000 --seconds 1
    .venv/bin/python scripts/bench_crowd_scale.py --figures 100 --seconds 60 [--fewer-keys]
    .venv/bin/python scripts/bench_crowd_scale.py --figures 100 --seconds 1 --body-jitter 0.05

Each size runs in a fresh process (its peak resident size is its own), ``count`` skiers in a
synchronized line 3 m apart (in phase: one motion, moved; ``--body-jitter J``: each body's mass,
height and inertia drawn within ``1 +- J``, seed 0, so every skier differs): one built, the
others duplicated from it as Add Crowd does.  ``per figure-frame``: each step's time over
figures x frames;
memory: the peak resident size above the process's after the rigs were built (what the crowd's
run, mapping and bake add), over figures x frames.  ``--profile N`` prints the N costliest
functions of one size (cProfile, cumulative).
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-bench-"))


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def one(count: int, seconds: float, fewer: bool, share: bool = True,
        jitter: float = 0.0) -> dict:
    """Run one size in this process; the timings and memory as a dict."""
    import bpy

    from blender_turning import blender as addon
    from blender_turning.blender.scene import crowd_scene, rig_builder
    from blender_turning.blender.anim.figure_bake import BakeWriter
    from blender_turning.core import preset
    from blender_turning.mapping.keys import DEFAULT_TOLERANCE
    from blender_turning.crowd import Crowd, CrowdFigure, Turns, run_crowd, synchronized
    from blender_turning.mapping import map_trajectory

    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    lead = CrowdFigure("s", preset("skier"), Turns(2.0, math.radians(20), 0.0))
    members = synchronized(lead, count, spacing=3.0, antiphase=False)
    if jitter:
        import random
        from dataclasses import replace
        rng = random.Random(0)
        members = [replace(m, figure=replace(m.figure, body=replace(
            m.figure.body, **{k: getattr(m.figure.body, k) * (1 + jitter * (2 * rng.random() - 1))
                              for k in ("m", "l", "I_v")}))) for m in members]
    crowd = Crowd("crowd", members, seconds)
    out = {}
    t = time.perf_counter()
    first = rig_builder.build_figure(bpy.context, rig_builder.load_spec("skier"),
                                     crowd.figures[0].name)
    coll = crowd_scene.new_crowd_collection(bpy.context)     # the rest as Add Crowd makes them
    children = first.children_recursive
    objs = [first] + [crowd_scene.duplicate_figure(first, f.name, coll, children)
                      for f in crowd.figures[1:]]
    for obj, i in zip(objs, range(len(objs))):
        obj.location = (0.0, 3.0 * i, 0.0)
    out["build"] = time.perf_counter() - t
    base = peak_mb()
    t = time.perf_counter()
    res = run_crowd(crowd)
    out["simulate"] = time.perf_counter() - t
    out["map"] = out["bake"] = 0.0
    writer = BakeWriter(export_ready=False, fewer=DEFAULT_TOLERANCE if fewer else None,
                        share=share)
    for obj, r in zip(objs, res.figures):        # figure by figure: one pose track at a time
        t = time.perf_counter()
        traj = r.trajectory.resample(24)
        track = map_trajectory("skier", traj, fps=24)
        t2 = time.perf_counter()
        writer.write(obj, traj, track)
        out["map"] += t2 - t
        out["bake"] += time.perf_counter() - t2
    out["shared"] = len(writer.shared)
    out["frames"] = len(crowd.figures) * (round(seconds * 24) + 1)
    out["peak_mb"] = peak_mb() - base
    addon.unregister()
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figures", type=int, nargs="+", default=[10, 100, 1000])
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--fewer-keys", action="store_true", help="bake with Fewer Keys")
    ap.add_argument("--no-share", action="store_true",
                    help="every figure bakes its own action (no shared motion)")
    ap.add_argument("--body-jitter", type=float, default=0.0,
                    help="each body within 1 +- this (seed 0): every skier's motion differs")
    ap.add_argument("--profile", type=int, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        if args.profile:
            import cProfile
            import pstats
            prof = cProfile.Profile()
            r = prof.runcall(one, args.one, args.seconds, args.fewer_keys, not args.no_share,
                             args.body_jitter)
            pstats.Stats(prof).sort_stats("tottime").print_stats(args.profile)
        else:
            r = one(args.one, args.seconds, args.fewer_keys, not args.no_share, args.body_jitter)
        print("JSON" + json.dumps(r))
        return 0
    now = datetime.datetime.now(datetime.timezone.utc)
    print(f"{platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}, "
          f"load {os.getloadavg()[0]:.1f}; {now:%Y-%m-%d %H:%M} UTC; skiers x {args.seconds:g} s "
          f"at 24 fps{', Fewer Keys' if args.fewer_keys else ''}"
          f"{', no sharing' if args.no_share else ''}"
          f"{f', body jitter {args.body_jitter:g}' if args.body_jitter else ''}\n")
    print("| figures | figure-frames | build s | simulate s | map s | bake s | "
          "sim+map+bake us per figure-frame | bake us per figure-frame | peak MB above the rigs "
          "| kB per figure-frame | sharing |\n|---|---|---|---|---|---|---|---|---|---|---|")
    for n in args.figures:
        cmd = [sys.executable, __file__, "--one", str(n), "--seconds", str(args.seconds)]
        cmd += ["--fewer-keys"] if args.fewer_keys else []
        cmd += ["--no-share"] if args.no_share else []
        cmd += ["--body-jitter", str(args.body_jitter)]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
        r = json.loads(next(line[4:] for line in proc.stdout.splitlines()
                            if line.startswith("JSON")))
        ff = r["frames"]
        work = r["simulate"] + r["map"] + r["bake"]
        print(f"| {n:,} | {ff:,} | {r['build']:.2f} | {r['simulate']:.2f} | {r['map']:.2f} | "
              f"{r['bake']:.2f} | {1e6 * work / ff:.0f} | {1e6 * r['bake'] / ff:.0f} | "
              f"{r['peak_mb']:.0f} | {1024 * r['peak_mb'] / ff:.2f} | {r['shared']:,} |",
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Benchmark: bake 4 figures x 60 s x 24 fps with whole-F-curve ``foreach_set`` against a
per-frame ``keyframe_insert`` loop writing the same poses, in the same run.

    python scripts/bench_bake.py                      # on the bpy wheel (.venv)
    blender -b --python scripts/bench_bake.py -- --seconds 60

Only the writing of keys is timed (simulation and mapping happen once, before, and are reported
separately).  Both writers start from figures without animation; the results are compared key
by key so both wrote the same poses.
"""
from __future__ import annotations

import argparse
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
import numpy as np  # noqa: E402

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.scene import rig_builder  # noqa: E402
from blender_turning import blender as addon  # noqa: E402
from blender_turning.core.registry import SPORTS  # noqa: E402
from blender_turning.blender.jobs.pipeline import figure_pose_track  # noqa: E402
from blender_turning.blender.scene.scene_adapters import (FrameRange,  # noqa: E402
                                                          settings_from_preset)


def build(sport: str, name: str, x: float):
    obj = rig_builder.build_figure(bpy.context, rig_builder.load_spec(sport), name, (x, 0, 0))
    s = obj.turning
    s.is_figure = True
    settings_from_preset(s, sport.upper())
    s.start = (x, 0.0, 0.0)
    return obj


def keyframe_insert_loop(obj, track) -> None:
    """The slow baseline: set each frame's pose, then ``keyframe_insert`` every channel."""
    pbs = {name: obj.pose.bones[name] for name in track.bones}
    for prop, v in track.props.items():
        obj[prop] = float(v[0])
    for k, frame in enumerate(track.frames):
        f = float(frame)
        obj.location = track.location[k]
        obj.rotation_euler = track.rotation[k]
        obj.keyframe_insert("location", frame=f, group="Object Transforms")
        obj.keyframe_insert("rotation_euler", frame=f, group="Object Transforms")
        for name, ch in track.bones.items():
            pb = pbs[name]
            if ch.location is not None:
                pb.location = ch.location[k]
                pb.keyframe_insert("location", frame=f, group=name)
            if ch.rotation is not None:
                pb.rotation_quaternion = ch.rotation[k]
                pb.keyframe_insert("rotation_quaternion", frame=f, group=name)
        for prop, v in track.props.items():
            obj[prop] = float(v[k])
            obj.keyframe_insert(f'["{prop}"]', frame=f, group=bake.PROP_GROUP)


def curves(obj) -> dict:
    out = {}
    for fc in bake.baked_channels(obj).fcurves:
        co = np.empty(2 * len(fc.keyframe_points), np.float32)
        fc.keyframe_points.foreach_get("co", co)
        out[(fc.data_path, fc.array_index)] = co
    return out


def main(argv=None) -> int:
    argv = sys.argv if argv is None else argv
    argv = argv[argv.index("--") + 1:] if "--" in argv else argv[1:]
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sports", default=",".join(SPORTS))      # every registered sport
    p.add_argument("--seconds", type=float, default=60.0)
    p.add_argument("--fps", type=int, default=24)
    p.add_argument("--repeat", type=int, default=3, help="foreach_set bakes timed (best kept)")
    args = p.parse_args(argv)
    sports = args.sports.split(",")

    registered = not hasattr(bpy.types.Object, "turning")
    if registered:
        addon.register()               # the figure settings and their nested groups
    try:
        return _bench(args, sports)
    finally:
        if registered:                 # bpy 4.2 crashes at exit on a registered PointerProperty
            addon.unregister()


def _bench(args, sports) -> int:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start = args.fps, 1
    scene.frame_end = 1 + int(round(args.seconds * args.fps))
    frames = FrameRange.of_scene(scene)

    t = time.perf_counter()
    fast = [build(s, f"{s.title()} A", 4.0 * i) for i, s in enumerate(sports)]
    slow = [build(s, f"{s.title()} B", 4.0 * i) for i, s in enumerate(sports)]
    t_build = time.perf_counter() - t
    t = time.perf_counter()
    tracks = [figure_pose_track(o, frames)[1] for o in fast]
    t_compute = time.perf_counter() - t
    n_curves = sum(len(bake._channel_list(o, tr)) for o, tr in zip(fast, tracks))
    n_keys = n_curves * len(tracks[0])

    best = float("inf")
    for _ in range(args.repeat):                       # re-baking replaces the same curves
        t = time.perf_counter()
        for obj, track in zip(fast, tracks):
            bake.bake_pose_track(obj, track)
        best = min(best, time.perf_counter() - t)
    t = time.perf_counter()
    for obj, track in zip(slow, tracks):
        keyframe_insert_loop(obj, track)
    t_slow = time.perf_counter() - t

    worst = 0.0                                        # both wrote the same poses
    for a, b in zip(fast, slow):
        ca, cb = curves(a), curves(b)
        assert ca.keys() == cb.keys(), set(ca) ^ set(cb)
        worst = max(worst, max(float(np.max(np.abs(ca[k] - cb[k]))) for k in ca))

    print(f"bake benchmark: {len(sports)} figures ({', '.join(sports)}) x {args.seconds:g} s x "
          f"{args.fps} fps = {len(tracks[0])} frames each; {n_curves} F-curves, {n_keys} keys")
    print(f"  Blender {bpy.app.version_string}, Python {platform.python_version()}, "
          f"{platform.machine()}, {os.cpu_count()} CPUs, {platform.platform()}")
    print(f"  rig build {t_build:.2f} s (8 figures); simulate + map {t_compute:.2f} s (untimed "
          "below)")
    print(f"  foreach_set bake (best of {args.repeat}): {best:.3f} s")
    print(f"  keyframe_insert loop:          {t_slow:.3f} s")
    print(f"  speed-up: {t_slow / best:.1f}x; largest key difference {worst:.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

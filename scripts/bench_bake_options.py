"""Benchmark the animator's bake options, each against its plain baseline in the same run:

- the core's simulation of 60 s with a speed schedule against a constant speed (skier);
- simulate + map with a keyed speed (ramp) against a constant speed, per figure;
- Bake Turns on every 4th frame (Hermite in-betweens) against every frame, writing only;
- Bake Turns on four selected figures at once against four single-figure bakes.

    .venv/bin/python scripts/bench_bake_options.py [--seconds 60 --fps 24]
"""
from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-bench-"))

import bpy  # noqa: E402

from blender_turning import blender as addon  # noqa: E402
from blender_turning.core.registry import SPORTS as REGISTERED  # noqa: E402
from blender_turning.core import PhaseEllipse, Schedule, preset, simulate  # noqa: E402
from blender_turning.blender.anim.figure_bake import apply_bake  # noqa: E402
from blender_turning.blender.jobs.pipeline import figure_pose_track  # noqa: E402
from blender_turning.blender.scene.scene_adapters import FrameRange  # noqa: E402
from bench_common import best  # noqa: E402  (scripts/)

SPORTS = tuple(s.key for s in REGISTERED.values())        # every registered sport


def add(sport, x):
    bpy.context.scene.cursor.location = (x, 0, 0)
    bpy.ops.turning.add_figure(sport=sport)
    return bpy.context.view_layer.objects.active


def select(objs):
    for o in bpy.context.view_layer.objects:
        o.select_set(o in objs)
    bpy.context.view_layer.objects.active = objs[0]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=60.0)
    p.add_argument("--fps", type=int, default=24)
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else None)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    try:
        return _bench(args)
    finally:
        addon.unregister()


def _bench(args) -> int:
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start = args.fps, 1
    scene.frame_end = 1 + int(round(args.seconds * args.fps))
    frames = FrameRange.of_scene(scene)
    figs = [add(s, 4.0 * i) for i, s in enumerate(SPORTS)]
    ramped = [add(s, 4.0 * i + 40) for i, s in enumerate(SPORTS)]
    for fig in ramped:              # up 30 % and back (slower than the preset: a turn it cannot make)
        v = fig.turning.speed
        for frame, factor in ((1, 1.0), (scene.frame_end // 3, 1.3), (scene.frame_end, 1.0)):
            fig.turning.speed = v * factor
            fig.keyframe_insert("turning.speed", frame=frame)
    print(f"bake options: {len(SPORTS)} figures x {args.seconds:g} s x {args.fps} fps; "
          f"Blender {bpy.app.version_string}, Python {platform.python_version()}, "
          f"{platform.machine()}, {os.cpu_count()} CPUs")
    skier = preset("skier")
    ramp = Schedule.sampled([0, args.seconds / 3, args.seconds], [10, 13, 10])

    def core(speed):
        ctl = PhaseEllipse(skier.body, 3.14159, 0.4, heading=1.5708)
        simulate(skier, ctl, args.seconds, state0=(0, 0, 1.5708, 0, 3.14159 * 0.4), speed=speed)

    t_c, t_r = best(lambda: core(None), 5 * args.repeat), best(lambda: core(ramp), 5 * args.repeat)
    print(f"  core simulate (skier): constant speed {t_c:.3f} s, speed schedule {t_r:.3f} s "
          f"({t_r / t_c:.2f}x)")
    for fig, ram in zip(figs, ramped):
        t_c = best(lambda: figure_pose_track(fig, frames), args.repeat)
        t_r = best(lambda: figure_pose_track(ram, frames), args.repeat)
        print(f"  {fig.turning.sport.lower():12s} simulate + map: constant speed {t_c:.3f} s, "
              f"keyed speed {t_r:.3f} s ({t_r / t_c:.2f}x)")
    computed = [(fig,) + figure_pose_track(fig, frames) for fig in figs]
    for step in (1, 4):
        t = best(lambda: [apply_bake(f, tr, tk, step) for f, tr, tk in computed], args.repeat)
        print(f"  write 4 figures, step {step}: {t:.3f} s")

    def one_by_one():
        for fig in figs:
            select([fig])
            bpy.ops.turning.bake_turns()

    def all_at_once():
        select(figs)
        bpy.ops.turning.bake_turns()

    t1, t4 = best(one_by_one, args.repeat), best(all_at_once, args.repeat)
    print(f"  Bake Turns operator: 4 single-figure bakes {t1:.3f} s, one bake of 4 selected "
          f"{t4:.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

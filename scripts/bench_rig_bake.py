"""Benchmark: retarget + bake of a run on a Rigify rig against the built-in skier's
map + bake, in the same run.

    python scripts/bench_rig_bake.py                  # on the bpy wheel (.venv); 60 s at 24 fps
    blender -b --python scripts/bench_rig_bake.py -- --seconds 60

The simulation is done once and shared (both figures have the same settings); timed are the
Section 7 mapping, the retargeting and the F-curve bake, each the best of ``--repeat``; then, on
the Rigify rig and on a Mixamo-like one, keying the equipment for export
(``export_ready.bake_equipment``, Bake Turns' Export-Ready Equipment).
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
for p in (ROOT, ROOT / "tests"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-bench-"))

import bpy  # noqa: E402

from blender_turning import blender as addon  # noqa: E402
from blender_turning.blender.anim import bake, export_ready  # noqa: E402
from blender_turning.blender.scene import retarget_adapter  # noqa: E402
from blender_turning.blender.jobs.pipeline import map_track, simulate_figure  # noqa: E402
from blender_turning.blender.scene.scene_adapters import FrameRange  # noqa: E402
from blender_turning.mapping.retarget.retarget import retarget  # noqa: E402
from rig_fixtures import mixamo_skeleton, rigify_rig  # noqa: E402


def best_of(repeat, fn):
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def main(argv=None) -> int:
    argv = sys.argv if argv is None else argv
    argv = argv[argv.index("--") + 1:] if "--" in argv else argv[1:]
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seconds", type=float, default=60.0)
    p.add_argument("--fps", type=int, default=24)
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    try:
        return _bench(args)
    finally:
        addon.unregister()          # bpy 4.2 crashes at exit on a registered PointerProperty


def _bench(args) -> int:
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start = args.fps, 1
    scene.frame_end = 1 + int(round(args.seconds * args.fps))
    frames = FrameRange.of_scene(scene)
    t = time.perf_counter()
    rig = rigify_rig(location=(3.0, 0.0, 0.0))
    t_rigify = time.perf_counter() - t
    bpy.context.view_layer.objects.active = rig
    assert bpy.ops.turning.make_figure(sport="SKIER", bone_map="RIGIFY") == {"FINISHED"}
    scene.cursor.location = (0, 0, 0)
    assert bpy.ops.turning.add_figure(sport="SKIER") == {"FINISHED"}
    builtin = bpy.context.view_layer.objects.active
    for name in ("mass", "com_height", "speed", "period", "lean", "heading", "start_heading"):
        setattr(rig.turning, name, getattr(builtin.turning, name))

    t = time.perf_counter()
    traj = simulate_figure(builtin, frames)
    t_sim = time.perf_counter() - t
    t_map, track = best_of(args.repeat, lambda: map_track("skier", traj, frames))
    t_ret, rtrack = best_of(args.repeat, lambda: retarget(
        track, "skier", retarget_adapter.user_rig(rig), retarget_adapter.figure_bone_map(rig)))
    t_bake_b, res_b = best_of(args.repeat, lambda: bake.bake_pose_track(builtin, track))
    t_bake_r, res_r = best_of(args.repeat, lambda: bake.bake_pose_track(rig, rtrack))
    builtin_total = t_map + t_bake_b
    rig_total = t_map + t_ret + t_bake_r
    print(f"rig bake benchmark: skier, {args.seconds:g} s x {args.fps} fps = {len(track)} frames")
    print(f"  Blender {bpy.app.version_string}, Python {platform.python_version()}, "
          f"{platform.machine()}, {os.cpu_count()} CPUs, {platform.platform()}")
    print(f"  (untimed: Rigify generate {t_rigify:.1f} s, simulate {t_sim:.2f} s)")
    print(f"  built-in skier: map {t_map:.3f} s + bake {t_bake_b:.3f} s ({res_b.fcurves} F-curves)"
          f" = {builtin_total:.3f} s")
    print(f"  Rigify rig:     map {t_map:.3f} s + retarget {t_ret:.3f} s + bake {t_bake_r:.3f} s "
          f"({res_r.fcurves} F-curves) = {rig_total:.3f} s")
    print(f"  ratio Rigify / built-in: {rig_total / builtin_total:.2f}x (best of {args.repeat})")
    bake.clear_bake(rig)
    bpy.data.objects.remove(builtin)
    _bench_equipment(rig, track, frames, "Rigify rig")
    retarget_adapter.remove_equipment(rig)
    bpy.data.objects.remove(rig)
    bpy.context.view_layer.objects.active = mixamo_skeleton("Mixamo", location=(-3.0, 0.0, 0.0))
    assert bpy.ops.turning.make_figure(sport="SKIER", bone_map="AUTO") == {"FINISHED"}
    _bench_equipment(bpy.context.view_layer.objects.active, track, frames, "Mixamo-like rig")
    return 0


def _bench_equipment(fig, track, frames, label) -> None:
    """Key ``fig``'s equipment for export (alone in the scene): CPU and wall seconds."""
    rtrack = retarget(track, "skier", retarget_adapter.user_rig(fig),
                      retarget_adapter.figure_bone_map(fig))
    bake.bake_pose_track(fig, rtrack)
    c, t = time.process_time(), time.perf_counter()
    export_ready.bake_equipment(fig, rtrack.frames)
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    print(f"  {label}'s equipment keys ({len(export_ready.equipment(fig))} pieces): "
          f"{wall:.3f} s ({cpu:.3f} s CPU)")
    bake.clear_bake(fig)
    export_ready.clear_equipment(fig)


if __name__ == "__main__":
    sys.exit(main())

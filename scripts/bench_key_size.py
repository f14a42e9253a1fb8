"""Benchmark: the .blend of 10 skiers baked over 60 s at 24 fps, every frame against Fewer Keys.

    .venv/bin/python scripts/bench_key_size.py [--figures 10] [--seconds 60]

One process: the skiers are added 4 m apart, all baked by one Bake Turns on every frame, each its
own action (*Share Motion* off: the baseline), the file saved uncompressed; then baked again with
Fewer Keys (the default tolerances) and saved again; then both again with *Share Motion* on (the
skiers are one motion, moved: they play one action).  Prints the keys, the bake's wall time and
the file's size.
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

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-bench-"))

import bpy  # noqa: E402

from blender_turning import blender as addon  # noqa: E402
from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402


def keys_of(figs) -> int:
    """Keys of the bake actions the figures play (a shared one once)."""
    actions = {bake.figure_action(f) for f in figs}
    return sum(len(fc.keyframe_points) for a in actions for fc in compat.all_fcurves(a))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figures", type=int, default=10)
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    scene = bpy.context.scene
    scene.render.fps = 24
    scene.frame_start, scene.frame_end = 1, 1 + round(args.seconds * 24)
    figs = []
    for k in range(args.figures):
        scene.cursor.location = (4.0 * k, 0.0, 0.0)
        assert bpy.ops.turning.add_figure(sport="SKIER") == {"FINISHED"}
        figs.append(bpy.context.view_layer.objects.active)
    for f in figs:
        f.select_set(True)
    now = datetime.datetime.now(datetime.timezone.utc)
    print(f"bpy {bpy.app.version_string}, {platform.machine()}, {os.cpu_count()} CPUs, load "
          f"{os.getloadavg()[0]:.1f}; {now:%Y-%m-%d %H:%M} UTC; {args.figures} skiers x "
          f"{args.seconds:g} s at 24 fps ({scene.frame_end} frames)\n")
    print("| bake | keys | bake s | .blend MB |\n|---|---|---|---|")
    out = Path(tempfile.mkdtemp(prefix="turning-keys-"))
    for label, kw in (("every frame (baseline)", {"share": False}),
                      ("Fewer Keys (0.1 deg, 1 mm)", {"fewer_keys": True, "share": False}),
                      ("every frame, Share Motion", {}),
                      ("Fewer Keys, Share Motion", {"fewer_keys": True})):
        t0 = time.perf_counter()
        assert bpy.ops.turning.bake_turns(**kw) == {"FINISHED"}
        wall = time.perf_counter() - t0
        path = out / "crowd.blend"
        bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=False, copy=True)
        print(f"| {label} | {keys_of(figs):,} | {wall:.1f} | {path.stat().st_size / 1e6:.1f} |")
    addon.unregister()


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else None)

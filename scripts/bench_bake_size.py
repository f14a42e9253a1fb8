"""Benchmark: time and memory of Bake Turns (the operator: simulate, map, write) against the
length of the frame range, for the bound ``scene_adapters.MAX_FRAMES``.

    python scripts/bench_bake_size.py [--frames 2400 12000 24000]

Each length is baked once, in increasing order, in one process (each bake replaces the previous
one's keys); memory is the process's peak resident size (``ru_maxrss``) above what it was after a
two-frame bake, so the peak of the longest bake so far.
"""
from __future__ import annotations

import argparse
import os
import platform
import resource
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
from blender_turning.blender.scene.scene_adapters import MAX_FRAMES  # noqa: E402


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, nargs="+", default=[2400, 12000, 24000])
    args = ap.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    scene = bpy.context.scene
    scene.render.fps = 24
    bpy.ops.turning.add_figure(sport="SKIER")
    scene.frame_end = 2
    bpy.ops.turning.bake_turns()
    print(f"bpy {bpy.app.version_string}, {platform.machine()}, Python "
          f"{platform.python_version()}; MAX_FRAMES = {MAX_FRAMES}")
    print("frames   seconds   ms/frame   peak above start MB   kB/frame")
    base = peak_mb()
    for n in sorted(args.frames):
        scene.frame_end = scene.frame_start + n - 1
        t0 = time.perf_counter()
        assert bpy.ops.turning.bake_turns() == {"FINISHED"}
        dt = time.perf_counter() - t0
        grow = peak_mb() - base
        print(f"{n:6d}   {dt:7.2f}   {1e3 * dt / n:8.3f}   {grow:19.0f}   {1024 * grow / n:8.1f}")
    addon.unregister()


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else None)

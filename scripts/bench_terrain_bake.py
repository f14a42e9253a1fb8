"""Benchmark: Bake Turns of one cyclist over 60 s at 24 fps on a 200 m x 200 m Ground mesh (the
project's ``ski_slope`` with its rolls and mogul field but no overall slope, as a 1 m grid mesh:
a figure that stays on 200 m for a minute) against the same bake on flat ground, in the same run
(within 2x).  The cyclist rides at 3 m/s with its own rolling resistance and drag,
slalom lean 5 deg, period 3 s, heading +x from (-95, 10).

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_terrain_bake.py [--repeat 3] [--cell 1.0]
    PYTHONPATH=$PWD .venv/bin/python scripts/bench_terrain_bake.py --profile 30   # cProfile

Timed: the whole bake as the operator does it (``BakeJob``: read the mesh, simulate, resample,
the feet's heights on the mesh, map, write F-curves), best of ``--repeat``, the cases interleaved: the
terrain bake the first time over the mesh (reading it) and again (the read is kept while the
mesh is unchanged: a figure's settings changed); and the parts: reading the mesh, and the
simulation with its resampling (and, on terrain, the feet's heights on the mesh) alone.
"""
from __future__ import annotations

import argparse
import math
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
from blender_turning.blender.scene import ground as mesh_ground  # noqa: E402
from blender_turning.blender.scene.ground import mesh_from_height_field  # noqa: E402
from blender_turning.blender.jobs.pipeline import simulate_figure  # noqa: E402
from blender_turning.blender.jobs.bake_job import BakeJob  # noqa: E402
from blender_turning.blender.scene.scene_adapters import FrameRange  # noqa: E402
from blender_turning.core.ground.terrain_gen import ski_slope  # noqa: E402
from bench_common import best  # noqa: E402  (scripts/)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--cell", type=float, default=1.0, help="mesh grid spacing, m")
    ap.add_argument("--profile", type=int, default=0, metavar="N",
                    help="instead of timing: cProfile the first terrain bake, print N lines")
    args = ap.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start = 24, 1
    scene.frame_end = 1 + int(args.seconds * 24)
    frames = FrameRange.of_scene(scene)
    slope = ski_slope(length=200.0, width=200.0, slope_deg=0.0, cell=args.cell)
    mountain = bpy.data.objects.new("Mountain", mesh_from_height_field(bpy, slope, "Mountain"))
    scene.collection.objects.link(mountain)
    figs = {}
    for name, x, y, ground in (("flat", -95.0, 300.0, None), ("terrain", -95.0, 10.0, mountain)):
        scene.cursor.location = (x, y, 0.0)
        scene.cursor.rotation_euler = (0.0, 0.0, math.radians(-90.0))    # facing +x
        bpy.ops.turning.add_figure(sport="CYCLIST")
        fig = bpy.context.view_layer.objects.active
        fig.name = name
        fig.turning.ground = ground
        fig.turning.speed, fig.turning.period = 3.0, 3.0
        fig.turning.lean = math.radians(5.0)
        figs[name] = fig

    def bake(name):
        job = BakeJob([name], frames)
        job.compute_next()
        job.write()

    def cold(name):
        mesh_ground._READ.clear()                      # the first bake over this mesh
        bake(name)

    if args.profile:
        import cProfile
        import pstats
        bake("flat"), cold("terrain")                  # warm: imports, first calls
        prof = cProfile.Profile()
        prof.runcall(cold, "terrain")
        pstats.Stats(prof).sort_stats("tottime").print_stats(args.profile)
        pstats.Stats(prof).sort_stats("cumulative").print_stats(args.profile)
        addon.unregister()
        return
    depsgraph = bpy.context.evaluated_depsgraph_get
    read = mesh_ground.read_ground(mountain, depsgraph())
    parts = {
        "flat bake (baseline)": lambda: bake("flat"),
        "terrain bake, first (reads the mesh)": lambda: cold("terrain"),
        "terrain bake, again (mesh unchanged)": lambda: bake("terrain"),
        "  reading the mesh, first": lambda: (mesh_ground._READ.clear(),
                                              mesh_ground.read_ground(mountain, depsgraph())),
        "  reading the mesh, again": lambda: mesh_ground.read_ground(mountain, depsgraph()),
        "  simulate + resample, flat": lambda: simulate_figure(figs["flat"], frames, ground=None),
        "  simulate + resample + foot heights, terrain": lambda: simulate_figure(
            figs["terrain"], frames, ground=read),
    }
    times = {k: math.inf for k in parts}
    for _ in range(args.repeat):                   # interleaved: the machine's load is shared
        for k, fn in parts.items():
            times[k] = min(times[k], best(fn, 1))
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, bpy {bpy.app.version_string}")
    print(f"mesh: {len(mountain.data.vertices)} vertices ({args.cell:g} m grid, 200 x 200 m), "
          f"read at {read.field.cell:g} m ({read.field.nx * read.field.ny} samples); "
          f"{frames.end - frames.start + 1} frames; best of {args.repeat}")
    flat = times["flat bake (baseline)"]
    for k, v in times.items():
        ratio = "" if k.startswith("  ") else f"  ({v / flat:.2f}x flat)"
        print(f"{k:44s} {v:7.3f} s{ratio}")
    addon.unregister()


if __name__ == "__main__":
    main()

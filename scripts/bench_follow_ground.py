"""Benchmark: Follow Path of one skier on a 200 m x 200 m Ground mesh (the project's ``ski_slope``
at ``--slope`` deg with its rolls, as a ``--cell`` m grid mesh) against the same path on flat
ground, in the same run (the planner in Blender).  The path runs 120 m down the fall
line in a gentle S (2 m to each side every 30 m) at x = 50 m, away from the mogul field.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_follow_ground.py [--repeat 2] [--cell 1.0]

Timed, best of ``--repeat``, flat and terrain interleaved: reading the scene into a planning job
(``follow_scene.prepare``: on terrain reading the mesh, checking it is a height field and that the
path lies over it), the plan (``FollowJob.run``), and writing it (``follow_scene.finish``: resample,
ray-cast the feet, map, F-curves); on terrain also the mesh reading and the height-field check
alone.
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

from blender_turning import blender as addon  # noqa: E402
from blender_turning.blender.scene import follow_scene  # noqa: E402
from blender_turning.blender.scene.follow_ground import check_height_field  # noqa: E402
from blender_turning.blender.scene.ground import mesh_from_height_field, read_ground  # noqa: E402
from blender_turning.core.ground.terrain_gen import ski_slope  # noqa: E402


def make_path(x0: float, name: str):
    curve = bpy.data.curves.new(name, "CURVE")
    sp = curve.splines.new("BEZIER")
    pts = [(x0, 80.0), (x0, 65.0), (x0 + 2.0, 35.0), (x0 - 2.0, 5.0), (x0, -25.0), (x0, -40.0)]
    sp.bezier_points.add(len(pts) - 1)
    for bp, (x, y) in zip(sp.bezier_points, pts):
        bp.co = (x, y, 0.0)
        bp.handle_left_type = bp.handle_right_type = "AUTO"
    obj = bpy.data.objects.new(name, curve)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--cell", type=float, default=1.0, help="mesh grid spacing, m")
    ap.add_argument("--slope", type=float, default=10.0, help="the slope's fall line, deg")
    args = ap.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start = 24, 1
    field = ski_slope(length=200.0, width=200.0, slope_deg=args.slope, cell=args.cell)
    mountain = bpy.data.objects.new("Mountain", mesh_from_height_field(bpy, field, "Mountain"))
    scene.collection.objects.link(mountain)
    figs = {}
    for name, ground in (("flat", None), ("terrain", mountain)):
        scene.cursor.location = (0.0, 0.0, 0.0)
        bpy.ops.turning.add_figure(sport="SKIER")
        fig = bpy.context.view_layer.objects.active
        fig.name = name
        fig.turning.ground = ground
        fig.turning.speed = 8.0
        fig.turning.path = make_path(50.0, f"{name} path")
        figs[name] = fig

    times = {name: {"prepare": [], "plan": [], "write": []} for name in figs}
    runs = {}
    for _ in range(args.repeat):
        for name, fig in figs.items():                  # interleaved: the same load for both
            t0 = time.perf_counter()
            job = follow_scene.prepare(bpy.context, fig)
            t1 = time.perf_counter()
            result = job.run()
            t2 = time.perf_counter()
            follow_scene.finish(bpy.context, fig, job, result)
            t3 = time.perf_counter()
            for key, dt in zip(("prepare", "plan", "write"), (t1 - t0, t2 - t1, t3 - t2)):
                times[name][key].append(dt)
            runs[name] = result
    dg = bpy.context.evaluated_depsgraph_get()
    read, check = [], []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        ground = read_ground(mountain, dg)
        t1 = time.perf_counter()
        check_height_field(mountain, dg, ground)
        read.append(t1 - t0)
        check.append(time.perf_counter() - t1)

    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, bpy {bpy.app.version_string}, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    print(f"mesh: {len(mountain.data.vertices)} vertices, {len(mountain.data.polygons)} faces "
          f"({args.cell:g} m grid, 200 x 200 m, {args.slope:g} deg); path 120 m")
    print("| ground | prepare | plan | write | replans | nodes expanded | run | speed |")
    print("|---|---|---|---|---|---|---|---|")
    for name in figs:
        tot = runs[name].totals()
        tr = runs[name].trajectory
        print(f"| {name} | {min(times[name]['prepare']):.3f} s | {min(times[name]['plan']):.2f} s"
              f" | {min(times[name]['write']):.3f} s | {tot['replans']} | {tot['expanded']} | "
              f"{tr.duration:.1f} s | {tr.V_cm.min():.1f}-{tr.V_cm.max():.1f} m/s |")
    print(f"terrain prepare: reading the mesh {min(read):.3f} s, the height-field check "
          f"{min(check):.3f} s")
    addon.unregister()


if __name__ == "__main__":
    main()

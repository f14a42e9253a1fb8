"""docs/racing.png: the skier's preset and the slalom racer at the same gate of Reid et al.'s
10 m slalom course (core/course/reid.py), each at the frame its foot passes that gate: the racer
follows the course round its poles (the planner as scripts/reid_courses.py runs it, 12 m/s); the
skier's preset finds no plan round the poles (its skis carve no tighter than 6 m), so it
follows the course's line without them, its best attempt.  The built-in figures baked in
Blender from the plans and rendered (Workbench) from behind and from the front, side by side,
with the gate's poles and the angles the mapping posed printed under each.

    .venv/bin/python scripts/racing_figure.py [--out docs/racing.png] [--gate 3]
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for p in (ROOT, ROOT / "tests"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-render-"))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from blender_turning import blender as addon  # noqa: E402
from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.anim.figure_bake import apply_bake  # noqa: E402
from blender_turning.blender.jobs.pipeline import map_track  # noqa: E402
from blender_turning.blender.render.build import make_obstacles  # noqa: E402
from blender_turning.blender.scene.rig_builder import material  # noqa: E402
from blender_turning.blender.scene.scene_adapters import FrameRange  # noqa: E402
from blender_turning.core.course.reid import course, gate_positions  # noqa: E402
from blender_turning.core.course.scene import scene_from_dict  # noqa: E402
from blender_turning.mapping.kinematics import Skeleton  # noqa: E402
from blender_turning.mapping.rig_spec import load_rig  # noqa: E402

FIGURES = (("SKIER", "skier preset"), ("SLALOM_RACER", "slalom racer"))
GAP, SPEED, GATES, FPS = 10.0, 12.0, 6, 24
#: The planner as scripts/reid_courses.py runs Reid's courses (docs/racing.md).
PLANNER = {"stages": 10, "choices": 9, "stage_time": 0.2}


def plan(preset: str, poles: bool):
    """The trajectory of ``preset`` following the course (round its poles, or its line alone)."""
    doc = course(GAP, SPEED, "skier" if preset == "SKIER" else preset.lower(), gates=GATES,
                 planner=PLANNER)
    doc["figure"]["limits"] = {"dC_f_max": 1.0}
    if not poles:
        doc["obstacles"] = []
    return scene_from_dict(doc, f"reid {GAP:g} m").run().trajectory


def add(preset: str):
    bpy.context.scene.cursor.location = (0.0, 0.0, 0.0)
    assert bpy.ops.turning.add_figure(sport="SKIER") == {"FINISHED"}
    obj = bpy.context.view_layer.objects.active
    if preset != "SKIER":
        assert bpy.ops.turning.apply_figure_preset(sport=preset) == {"FINISHED"}
    return obj


def bake_plan(obj, result):
    """Key the plan ``result`` (a trajectory on the course's ground plane) on ``obj`` as Follow
    Path writes one; returns the trajectory at the scene's rate and its pose track."""
    scene = bpy.context.scene
    traj = result.resample(FPS, start=0.0)
    frames = FrameRange(scene.frame_start, scene.frame_start + len(traj) - 1, FPS)
    scene.frame_end = max(scene.frame_end, frames.end)
    track = map_track(obj.turning.sport, traj, frames, obj=obj)
    bake.check_track(obj, track)
    apply_bake(obj, traj, track)
    return traj, track


def poles(gates: int):
    """The turning poles' inner tips (Reid's courses: 1.5 m inside the line 2.5 m out), 1.8 m
    slalom poles, red and blue in turn."""
    xs = gate_positions(GAP, gates)
    make_obstacles(bpy, [{"group": "Gates", "kind": "pole", "size": 0.04, "height": 1.8,
                          "at": (float(x), (1.0 if k % 2 == 0 else -1.0) * 1.0)}
                         for k, x in enumerate(xs)])


def _incl(v):
    """Lean from vertical across the travel (the rig's x-z plane), deg, > 0 to the left."""
    return math.degrees(math.atan2(-v[0], v[2]))


def angles(traj, track, i: int) -> dict:
    """The mapping's angles at sample ``i`` (deg, on the pose track the bake keys): the lean,
    the left ski's edge, the outside shin's, the leg line's (ankles to hips), the trunk's (hips
    to shoulders) and the shoulders' turn from the skis seen from above (> 0: to the outside)."""
    skel = Skeleton.from_spec(load_rig("skier"))
    P = {b: m[i] for b, m in skel.fk(track.bones, len(track)).items()}
    h = lambda b: P[b][:3, 3]                                        # noqa: E731
    mid = lambda b: 0.5 * (h(f"{b}.L") + h(f"{b}.R"))                # noqa: E731
    lean = math.degrees(traj.theta_v[i])
    out = "R" if lean > 0 else "L"
    line = h("upper_arm.L") - h("upper_arm.R")
    return {"lean": lean, "edge": math.degrees(math.atan2(P["ski.L"][2, 0], P["ski.L"][0, 0])),
            "shin": _incl(h(f"shin.{out}") - h(f"foot.{out}")),
            "legs": _incl(mid("thigh") - mid("foot")),
            "trunk": _incl(mid("upper_arm") - mid("thigh")),
            "counter": math.degrees(math.atan2(line[1], -line[0])) * (1.0 if lean > 0 else -1.0)}


def camera(scene):
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    target = bpy.data.objects.new("Target", None)
    scene.collection.objects.link(target)
    c = cam.constraints.new("TRACK_TO")
    c.target, c.track_axis, c.up_axis = target, "TRACK_NEGATIVE_Z", "UP_Y"
    scene.camera = cam
    return cam, target


def shoot(scene, cam, target, obj, lean: float, view: str, path: Path) -> None:
    """Render ``obj`` alone from behind (orthographic, along the travel: the angles across it
    as they are) or from the front and to the outside of the turn (perspective), aimed 0.6 m up
    the line of the lean ``lean`` (deg) from the foot point."""
    centre = np.array(obj.matrix_world.translation)
    fwd = np.array(obj.matrix_world.col[1][:3])         # the rig's travel, +Y
    d = np.array([fwd[0], fwd[1], 0.0]) / math.hypot(fwd[0], fwd[1])
    left = np.array([-d[1], d[0], 0.0])
    th = math.radians(lean)
    aim = centre + 0.6 * (math.sin(th) * left + np.array([0.0, 0.0, math.cos(th)]))
    target.location = tuple(aim)
    if view == "behind":        # 8 deg above the horizontal: the snow shows, the angles barely
        cam.data.type, cam.data.ortho_scale = "ORTHO", 3.2        # change
        cam.location = tuple(aim - 8.0 * d + [0.0, 0.0, 8.0 * math.tan(math.radians(8))])
    else:
        cam.data.type, cam.data.lens = "PERSP", 50
        cam.location = tuple(aim + 3.6 * d - 1.8 * left + [0.0, 0.0, 0.6])
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)


def main(argv=None) -> int:
    argv = sys.argv if argv is None else argv
    argv = argv[argv.index("--") + 1:] if "--" in argv else argv[1:]
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=str(ROOT / "docs" / "racing.png"))
    p.add_argument("--gate", type=int, default=3,
                   help="the turning pole (1-6) each figure is shown passing")
    args = p.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    try:
        render(args)
    finally:
        addon.unregister()
    return 0


def render(args) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end, scene.render.fps = 1, 2, FPS
    plans = [plan(preset, preset != "SKIER") for preset, _ in FIGURES]
    figs = [add(preset) for preset, _ in FIGURES]
    baked = [bake_plan(obj, tr) for obj, tr in zip(figs, plans)]
    gate_x = float(gate_positions(GAP, GATES)[args.gate - 1])
    at = [int(np.argmax(traj.x >= gate_x)) for traj, _ in baked]   # the foot passes the gate
    poles(GATES)
    mesh = bpy.data.meshes.new("Ground")
    mesh.from_pydata([(-200, -200, 0), (200, -200, 0), (200, 200, 0), (-200, 200, 0)], [],
                     [(0, 1, 2, 3)])
    snow = bpy.data.materials.new("Snow")
    snow.diffuse_color = (0.92, 0.94, 0.98, 1.0)
    mesh.materials.append(snow)
    scene.collection.objects.link(bpy.data.objects.new("Ground", mesh))
    material("equipment")
    r = scene.render
    r.engine = "BLENDER_WORKBENCH"
    r.resolution_x, r.resolution_y, r.resolution_percentage = 520, 560, 100
    shading = scene.display.shading
    shading.light, shading.color_type, shading.show_shadows = "STUDIO", "MATERIAL", True
    compat.set_output_format(scene, "PNG")
    cam, target = camera(scene)
    tmp = Path(tempfile.mkdtemp(prefix="racing-figure-"))
    fig, axes = plt.subplots(2, 2, figsize=(8.0, 9.4))
    side = "right" if args.gate % 2 else "left"
    for col, (obj, (_, label)) in enumerate(zip(figs, FIGURES)):
        for other in figs:                              # this figure alone in the picture
            for o in [other] + list(other.children_recursive):
                o.hide_render = other is not obj
        traj, track = baked[col]
        scene.frame_set(scene.frame_start + at[col])
        a = angles(traj, track, at[col])
        for row, view in enumerate(("behind", "front")):
            path = tmp / f"{col}{view}.png"
            shoot(scene, cam, target, obj, a['lean'], view, path)
            ax = axes[row, col]
            ax.imshow(plt.imread(str(path)))
            ax.axis("off")
        axes[0, col].set_title(
            f"{label}: lean {abs(a['lean']):.1f}, skis on edge {abs(a['edge']):.1f} deg\n"
            f"outside shin {abs(a['shin']):.1f}, legs {abs(a['legs']):.1f}, "
            f"trunk {abs(a['trunk']):.1f} deg", fontsize=9)
        tip = 1.0 if args.gate % 2 else -1.0
        out = (traj.y[at[col]] - tip) * tip         # > 0: round the pole, < 0: through it
        where = (f"{out:.2f} m outside the pole" if out > 0 else
                 f"{-out:.2f} m inside the pole's tip")
        axes[1, col].set_title(f"t = {traj.t[at[col]]:.2f} s: the foot {where}\n"
                               f"shoulders turned {a['counter']:.1f} deg to the outside",
                               fontsize=9)
    fig.suptitle(f"Reid's 10 m slalom, 12 m/s, turning pole {args.gate} (a {side} turn)\n"
                 "racer: round the poles; skier's preset: no plan round them, the line alone\n"
                 "top: from behind (orthographic, 8 deg above the snow)", fontsize=10)
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print("racing_figure:", args.out, "samples", at, "foot y", [round(float(t.y[i]), 2)
                                                            for (t, _), i in zip(baked, at)])


if __name__ == "__main__":
    sys.exit(main())

"""docs/racing.png: the skier's preset and the slalom racer at the same phase of the same
commanded slalom (period 2 s, lean asked 59 deg, 12 m/s), the built-in figures baked in Blender
and rendered (Workbench) from behind and from the front, side by side, with the angles the
mapping posed printed under each (measured on the baked pose track).

    .venv/bin/python scripts/racing_figure.py [--out docs/racing.png] [--frame N]
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
from blender_turning.blender.jobs.pipeline import figure_pose_track  # noqa: E402
from blender_turning.blender.scene.rig_builder import material  # noqa: E402
from blender_turning.blender.scene.scene_adapters import FrameRange  # noqa: E402
from blender_turning.mapping.kinematics import Skeleton  # noqa: E402
from blender_turning.mapping.rig_spec import load_rig  # noqa: E402
from rig_fixtures import activate  # noqa: E402

FIGURES = (("SKIER", "skier preset"), ("SLALOM_RACER", "slalom racer"))
SPEED, PERIOD, LEAN = 12.0, 2.0, math.radians(59.0)   # the skier falls past 60
FRAMES = 96


def add(preset: str):
    bpy.context.scene.cursor.location = (0.0, 0.0, 0.0)
    assert bpy.ops.turning.add_figure(sport="SKIER") == {"FINISHED"}
    obj = bpy.context.view_layer.objects.active
    if preset != "SKIER":
        assert bpy.ops.turning.apply_figure_preset(sport=preset) == {"FINISHED"}
    obj.turning.speed, obj.turning.period, obj.turning.lean = SPEED, PERIOD, LEAN
    return obj


def _incl(v):
    """Lean from vertical across the travel (the rig's x-z plane), deg, > 0 to the left."""
    return math.degrees(math.atan2(-v[0], v[2]))


def angles(obj, frame: int) -> dict:
    """The mapping's angles at ``frame`` (deg, on the pose track the bake keys): the lean, the
    left ski's edge, the outside shin's, the leg line's (ankles to hips), the trunk's (hips to
    shoulders) and the shoulders' turn from the skis seen from above (> 0: to the outside)."""
    scene = bpy.context.scene
    traj, track = figure_pose_track(obj, FrameRange.of_scene(scene))
    i = frame - scene.frame_start
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
            "counter": math.copysign(math.degrees(math.atan2(line[1], -line[0])), lean)}


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
    heading = obj.rotation_euler[2] + math.pi / 2
    d = np.array([math.cos(heading), math.sin(heading), 0.0])
    left = np.array([-d[1], d[0], 0.0])
    th = math.radians(lean)
    aim = centre + 0.6 * (math.sin(th) * left + np.array([0.0, 0.0, math.cos(th)]))
    target.location = tuple(aim)
    if view == "behind":        # 8 deg above the horizontal: the snow shows, the angles barely
        cam.data.type, cam.data.ortho_scale = "ORTHO", 2.4        # change
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
    p.add_argument("--frame", type=int, default=0,
                   help="frame to show (default: the racer's deepest lean after the first turn)")
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
    scene.frame_start, scene.frame_end, scene.render.fps = 1, FRAMES, 24
    figs = [add(preset) for preset, _ in FIGURES]
    for obj in figs:
        activate(obj)
        assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    frame = args.frame
    if not frame:       # the racer's deepest lean in the second and third turns (a left one)
        traj, _ = figure_pose_track(figs[1], FrameRange.of_scene(scene))
        lo = int(PERIOD * 24)
        frame = lo + int(np.argmax(traj.theta_v[lo:])) + scene.frame_start
    scene.frame_set(frame)
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
    for col, (obj, (_, label)) in enumerate(zip(figs, FIGURES)):
        for other in figs:                              # this figure alone in the picture
            for o in [other] + list(other.children_recursive):
                o.hide_render = other is not obj
        a = angles(obj, frame)
        for row, view in enumerate(("behind", "front")):
            path = tmp / f"{col}{view}.png"
            shoot(scene, cam, target, obj, a['lean'], view, path)
            ax = axes[row, col]
            ax.imshow(plt.imread(str(path)))
            ax.axis("off")
        axes[0, col].set_title(
            f"{label}: lean {a['lean']:.1f}, skis on edge {a['edge']:.1f} deg\n"
            f"outside shin {a['shin']:.1f}, legs {a['legs']:.1f}, trunk {a['trunk']:.1f} deg",
            fontsize=9)
        axes[1, col].set_title(f"from the front: shoulders turned {a['counter']:.1f} deg "
                               f"to the outside", fontsize=9)
    fig.suptitle(f"Frame {frame}, the racer's apex of a left turn asked at 59 deg, 2 s, 12 m/s\n"
                 "top: from behind (orthographic, 8 deg above the snow)", fontsize=10)
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print("racing_figure:", args.out, "frame", frame)


if __name__ == "__main__":
    sys.exit(main())

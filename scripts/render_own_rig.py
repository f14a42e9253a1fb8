"""The picture of docs/own-rigs.md: a Rigify rig (generated from Blender's Human metarig) and a
Mixamo-named skeleton skiing beside the built-in skier, same settings, one frame, Workbench.

    python scripts/render_own_rig.py --out docs/own_rig.png [--frame 40]

The generated rigs have no body of their own: each gets simple capsules skinned to its deforming
limb and spine bones so that the render shows the motion (the bake never looks at meshes).
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
from blender_turning.blender.scene.rig_builder import material, primitive  # noqa: E402
from rig_fixtures import activate, mixamo_skeleton, rigify_rig  # noqa: E402

#: The Rigify rig's deforming limb and spine bones that get a capsule.
RIGIFY_SKIN = (["DEF-spine", "DEF-spine.001", "DEF-spine.002", "DEF-spine.003", "DEF-spine.004",
                "DEF-spine.006"]
               + [f"DEF-{b}.{s}" for s in "LR" for b in (
                   "thigh", "shin", "foot", "toe", "upper_arm", "forearm", "hand")]
               + [f"DEF-{b}.{s}.001" for s in "LR" for b in ("thigh", "shin", "upper_arm",
                                                             "forearm")])
RADIUS = {"spine": 0.12, "head": 0.1, "spine.006": 0.1, "thigh": 0.075, "shin": 0.055,
          "foot": 0.045, "toe": 0.035, "upper_arm": 0.05, "forearm": 0.042, "hand": 0.04,
          "UpLeg": 7.5, "Leg": 5.5, "Foot": 4.5, "ToeBase": 3.5, "Arm": 5.0, "ForeArm": 4.2,
          "Hand": 4.0, "Hips": 12.0, "Spine": 12.0, "Spine1": 12.0, "Spine2": 13.0, "Neck": 5.0,
          "Head": 10.0, "Shoulder": 5.0}


def _radius(bone_name):
    base = bone_name.split(":")[-1].replace("DEF-", "").split(".")[0]
    for side in ("Left", "Right"):
        base = base.replace(side, "") if base.startswith(side) else base
    if bone_name.endswith("spine.006"):
        return RADIUS["head"]
    return RADIUS.get(base, RADIUS["spine"] if base.startswith("spine") else 0.05)


def skin(obj, bones, color):
    """Capsules along ``bones``, each skinned rigidly to its bone (weight 1)."""
    verts, faces, groups, start = [], [], {}, 0
    for name in bones:
        b = obj.data.bones.get(name)
        if b is None:
            continue
        v, f = primitive("capsule", (_radius(name), b.length + _radius(name)))
        m = np.array(b.matrix_local)
        v = v + [0.0, b.length / 2, 0.0]
        verts.append(v @ m[:3, :3].T + m[:3, 3])
        faces += [tuple(i + start for i in face) for face in f]
        groups[name] = range(start, start + len(v))
        start += len(v)
    mesh = bpy.data.meshes.new(f"{obj.name} Body")
    mesh.from_pydata(np.vstack(verts).tolist(), [], faces)
    mat = bpy.data.materials.new(f"{obj.name} skin")
    mat.diffuse_color = color
    mesh.materials.append(mat)
    body = bpy.data.objects.new(f"{obj.name} Body", mesh)
    bpy.context.scene.collection.objects.link(body)
    body.parent = obj
    body.matrix_parent_inverse.identity()
    for name, idx in groups.items():
        body.vertex_groups.new(name=name).add(list(idx), 1.0, "REPLACE")
    body.modifiers.new("Armature", "ARMATURE").object = obj


def main(argv=None) -> int:
    argv = sys.argv if argv is None else argv
    argv = argv[argv.index("--") + 1:] if "--" in argv else argv[1:]
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=str(ROOT / "docs" / "own_rig.png"))
    p.add_argument("--frame", type=int, default=0,
                   help="frame to render (default: the deepest lean between frames 20 and 48)")
    args = p.parse_args(argv)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    try:
        render(args)
    finally:
        addon.unregister()
    return 0


def render(args):
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, max(args.frame, 48)
    scene.render.fps = 24
    rigify = rigify_rig(location=(2.2, 0.0, 0.0))
    mixamo = mixamo_skeleton(location=(-2.2, 0.0, 0.0))
    skin(rigify, RIGIFY_SKIN, (0.85, 0.45, 0.15, 1.0))
    skin(mixamo, [b.name for b in mixamo.data.bones], (0.2, 0.65, 0.35, 1.0))
    scene.cursor.location = (0, 0, 0)
    bpy.ops.turning.add_figure(sport="SKIER")
    builtin = bpy.context.view_layer.objects.active
    for obj in (rigify, mixamo):
        obj.rotation_euler = (0.0, 0.0, math.pi)
        activate(obj)
        bpy.ops.turning.make_figure(sport="SKIER")
        for n in ("mass", "com_height", "speed", "period", "lean", "heading", "start_heading"):
            setattr(obj.turning, n, getattr(builtin.turning, n))
    for obj in (builtin, rigify, mixamo):
        activate(obj)
        bpy.ops.turning.bake_turns()
    frame = args.frame
    if not frame:
        fc = next(c for c in bake.baked_channels(builtin).fcurves if c.data_path == '["turn_lean"]')
        frame = max(range(20, 49), key=lambda f: abs(fc.evaluate(f)))
    scene.frame_set(frame)
    centre = np.array(builtin.matrix_world.translation)
    heading = builtin.rotation_euler[2] + math.pi / 2
    d = np.array([math.cos(heading), math.sin(heading), 0.0])
    side = np.array([-d[1], d[0], 0.0])
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.lens = 35
    scene.collection.objects.link(cam)
    cam.location = tuple(centre + 8.0 * d - 0.8 * side + [0, 0, 1.3])
    target = bpy.data.objects.new("Target", None)
    target.location = tuple(centre + [0, 0, 0.8])
    scene.collection.objects.link(target)
    c = cam.constraints.new("TRACK_TO")
    c.target, c.track_axis, c.up_axis = target, "TRACK_NEGATIVE_Z", "UP_Y"
    scene.camera = cam
    mesh = bpy.data.meshes.new("Ground")
    lo, hi = centre[:2] - 60, centre[:2] + 60
    mesh.from_pydata([(lo[0], lo[1], 0), (hi[0], lo[1], 0), (hi[0], hi[1], 0), (lo[0], hi[1], 0)],
                     [], [(0, 1, 2, 3)])
    snow = bpy.data.materials.new("Snow")
    snow.diffuse_color = (0.92, 0.94, 0.98, 1.0)
    mesh.materials.append(snow)
    scene.collection.objects.link(bpy.data.objects.new("Ground", mesh))
    material("equipment")
    r = scene.render
    r.engine = "BLENDER_WORKBENCH"
    r.resolution_x, r.resolution_y, r.resolution_percentage = 960, 540, 100
    shading = scene.display.shading
    shading.light, shading.color_type, shading.show_shadows = "STUDIO", "MATERIAL", True
    compat.set_output_format(scene, "PNG")
    r.filepath = str(Path(args.out).resolve())
    bpy.ops.render.render(write_still=True)
    print("wrote", r.filepath, "frame", frame)


if __name__ == "__main__":
    sys.exit(main())

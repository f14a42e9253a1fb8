"""The user's own rig on a Ground mesh, on the bpy wheel: a Mixamo-named
skeleton made a skier rides a 15 deg plane beside the built-in skier with the same settings; it
stands in the local surface as the built-in does (its object tilts with the surface), so its
skis lie in the surface and its feet stay on them."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning import blender as addon  # noqa: E402
from rig_fixtures import activate, mixamo_skeleton, sample  # noqa: E402

pytestmark = pytest.mark.blender
FRAMES = (1, 48)
SIGMA = math.radians(15.0)
#: The plane rotated by SIGMA about +X: rises towards +Y, through the origin.
NORMAL = np.array([0.0, -math.sin(SIGMA), math.cos(SIGMA)])
SAME = ("mass", "com_height", "inertia", "speed", "period", "lean", "heading", "start_heading")


def _height(y):
    return y * math.tan(SIGMA)


@pytest.fixture(scope="module")
def run():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = FRAMES
    sc.render.fps = 24
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=10, y_subdivisions=10, size=200)
    plane = bpy.context.object
    plane.rotation_euler = (SIGMA, 0.0, 0.0)
    sc.cursor.location = (-3.0, 40.0, _height(40.0))
    sc.cursor.rotation_euler = (0.0, 0.0, math.radians(-180.0))       # heading downhill, -Y
    assert bpy.ops.turning.add_figure(sport="SKIER") == {"FINISHED"}
    builtin = bpy.context.view_layer.objects.active
    user = mixamo_skeleton(location=(3.0, 40.0, _height(40.0)))      # faces -Y: downhill
    activate(user)
    assert bpy.ops.turning.make_figure(sport="SKIER", bone_map="AUTO") == {"FINISHED"}
    for n in SAME:
        setattr(user.turning, n, getattr(builtin.turning, n))
    figures = {"builtin": builtin, "mixamo": user}
    for obj in figures.values():
        obj.turning.ground = plane
        activate(obj)
        assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    skis = {o["turning_equipment"]: o for o in user.turning.rig.equipment.objects
            if o.get("turning_equipment", "").startswith("ski")}
    rows = []
    for f in range(FRAMES[0], FRAMES[1] + 1):
        sc.frame_set(f)
        row = {}
        for name, ski in skis.items():
            mw = np.array(ski.matrix_world)
            v = np.array([tuple(x.co) for x in ski.data.vertices])
            b = np.array(builtin.matrix_world) @ np.array(builtin.pose.bones[name].matrix)
            row[name] = (mw[:3, :3] / np.linalg.norm(mw[:3, :3], axis=0),
                         (v @ mw[:3, :3].T + mw[:3, 3]) @ NORMAL,
                         b[:3, :3] / np.linalg.norm(b[:3, :3], axis=0))
        rows.append(row)
    _, _, gap, _ = sample(figures, FRAMES, {"ski.L": [("ankle", "L")],
                                            "ski.R": [("ankle", "R")]})
    yield builtin, user, rows, np.array(gap["mixamo"])
    addon.unregister()


def test_the_rig_tilts_with_the_surface(run):
    builtin, user, _, _ = run
    ub, bb = np.array(user.matrix_world), np.array(builtin.matrix_world)
    for mw in (ub, bb):
        z = mw[:3, 2] / np.linalg.norm(mw[:3, 2])
        assert math.degrees(math.acos(min(1.0, z @ NORMAL))) < 0.01


def test_skis_in_the_surface_feet_on_them(run):
    """The issue's measures: each ski's long axis lies in the surface and is turned as the
    built-in's ski beside it, within 1 deg (measured 2e-5 deg and 0); its sole is on the plane
    (no vertex below by more than 1 mm, measured 0.1 mm of float32 round-off ~10 m up the
    slope; the lowest within 2 cm, measured 0.13 mm) and the ankles on the bindings within
    1 cm (measured 8e-6 m).  Standing upright, the skis would be 15 deg out of the surface."""
    _, _, rows, gap = run
    for row in rows:
        for name, (R, dist, Rb) in row.items():
            assert abs(math.degrees(math.asin(R[:, 1] @ NORMAL))) < 1.0, name
            turn = np.clip((np.trace(R.T @ Rb) - 1.0) / 2.0, -1.0, 1.0)
            assert math.degrees(math.acos(turn)) < 1.0, name
            assert dist.min() > -1e-3, (name, dist.min())
        assert min(d.min() for _, d, _ in row.values()) < 0.02
    assert gap.max() < 0.01, gap.max()

"""Follow Path on a Ground mesh (the planner in Blender), on the bpy wheel: the path
curve projected onto the mesh, an obstacle standing on it avoided, the speed computed along the
way, and the result baked on the mesh; a cancelled plan, a curve off the mesh and a mesh that is
not a height field leave the scene as it was."""
import math
import os
import re
import tempfile
import time

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from scene_snapshot import diff, snapshot  # noqa: E402

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.scene import follow_scene, scene_adapters  # noqa: E402
from blender_turning.blender.scene.ground import (height_field_of,  # noqa: E402
                                                  mesh_from_height_field)
from blender_turning.core.course.follow_problem import DEFAULT_CLEARANCE  # noqa: E402
from blender_turning.core.course.obstacles import Obstacles  # noqa: E402
from blender_turning.core.course.path import HermitePath  # noqa: E402
from blender_turning.core.ground.terrain import HeightField, surface_frame  # noqa: E402
from modal_stand_ins import Context, WindowManager  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]

SLOPE = math.radians(12.0)
SHELF = -20.0          # flat for y > SHELF, then (after a 10 m rounded edge) 12 deg down -y
EDGE = 10.0
#: The curve: down the shelf and the slope in a gentle S (its z wanders above and below the
#: mesh: it is projected vertically).
CURVE = [(0.0, 8.0, 3.0), (0.0, -8.0, -1.0), (1.5, -30.0, 0.0), (-1.5, -52.0, -20.0),
         (0.0, -74.0, 5.0)]
POST = ((0.6, -14.0), (1.0, 1.0))     # centre, size: standing across the curve
START_SPEED = 8.0


def shelf_and_slope() -> HeightField:
    """A flat shelf, a rounded edge (a parabola: C1) and a plane of 12 deg falling toward -y."""
    xs, ys = np.arange(-25.0, 25.01, 1.0), np.arange(-130.0, 20.01, 1.0)
    u = np.clip(SHELF - ys, 0.0, None)                    # metres below the shelf's edge
    h = -math.tan(SLOPE) * np.where(u < EDGE, u * u / (2 * EDGE), u - EDGE / 2)
    return HeightField(np.tile(h[:, None], (1, len(xs))), xs[0], ys[0], 1.0)


def link(obj, collection=None):
    (collection or bpy.context.scene.collection).objects.link(obj)
    return obj


def make_curve(points, name="Path"):
    curve = bpy.data.curves.new(name, "CURVE")
    curve.dimensions = "3D"
    sp = curve.splines.new("BEZIER")
    sp.bezier_points.add(len(points) - 1)
    for bp, p in zip(sp.bezier_points, points):
        bp.co = p
        bp.handle_left_type = bp.handle_right_type = "AUTO"
    return link(bpy.data.objects.new(name, curve))


def make_box(name, center, size, z0=0.0, height=1.0):
    mesh = bpy.data.meshes.new(name)
    sx, sy = size[0] / 2, size[1] / 2
    mesh.from_pydata([(-sx, -sy, 0), (sx, -sy, 0), (sx, sy, 0), (-sx, sy, 0),
                      (-sx, -sy, height), (sx, -sy, height), (sx, sy, height), (-sx, sy, height)],
                     [], [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                          (3, 0, 4, 7)])
    obj = bpy.data.objects.new(name, mesh)
    obj.location = (*center, z0)
    return obj


def add_figure(sport="SKIER"):
    bpy.context.scene.cursor.location = (0.0, 0.0, 0.0)
    assert bpy.ops.turning.add_figure(sport=sport) == {"FINISHED"}
    return bpy.context.view_layer.objects.active


def curves_of(obj):
    out = {}
    for fc in bake.baked_channels(obj).fcurves:
        co = np.empty(2 * len(fc.keyframe_points))
        fc.keyframe_points.foreach_get("co", co)
        out[(fc.data_path, fc.array_index)] = co[1::2]
    return out


def ray(obj, x, y, normal=False):
    """The mesh's height under each ``(x, y)`` (or its face's normal there, (n, 3))."""
    from mathutils.bvhtree import BVHTree
    bvh = BVHTree.FromObject(obj, bpy.context.evaluated_depsgraph_get())
    hits = [bvh.ray_cast((a, b, 500.0), (0, 0, -1)) for a, b in zip(x, y)]
    return np.array([tuple(h[1]) for h in hits]) if normal else np.array([h[0][2] for h in hits])


def angle(u, v) -> np.ndarray:
    """Degrees between the rows of ``u`` and ``v`` (unit vectors)."""
    return np.degrees(np.arccos(np.clip(np.einsum("ni,ni->n", u, v), -1.0, 1.0)))


def object_up(curves) -> np.ndarray:
    """(n, 3) world +Z of the baked object (Euler XYZ: Rz Ry Rx applied to (0, 0, 1))."""
    a, b, c = (curves[("rotation_euler", i)] for i in range(3))
    return np.stack([np.cos(c) * np.sin(b) * np.cos(a) + np.sin(c) * np.sin(a),
                     np.sin(c) * np.sin(b) * np.cos(a) - np.cos(c) * np.sin(a),
                     np.cos(b) * np.cos(a)], -1)


def modal_operator(fig):
    """A stand-in ``self`` for ``TURNING_OT_follow_path.modal`` with the job started."""
    op_cls = bpy.types.TURNING_OT_follow_path
    reports = []
    fake = type("Op", (), {"report": lambda self, kind, msg: reports.append((kind, msg)),
                           "_cleanup": op_cls._cleanup, "_complete": op_cls._complete})()
    fake._job = follow_scene.prepare(bpy.context, fig)
    fake._fig_uid, fake._timer = fig.session_uid, object()
    fake._job.start()
    return op_cls, fake, reports


@pytest.fixture(scope="module")
def world(registered):
    """The shelf-and-slope Ground mesh, a post standing on it beside the curve, an Obstacles
    collection holding the post *and the ground* (the ground is never an obstacle), and a skier
    whose Follow Path has run once."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.render.fps, sc.frame_start, sc.frame_end = 24, 1, 48
    field = shelf_and_slope()
    ground = link(bpy.data.objects.new("Slope", mesh_from_height_field(bpy, field, "Slope")))
    obstacles = bpy.data.collections.new("Obstacles")
    sc.collection.children.link(obstacles)
    post = make_box("Post", *POST, z0=float(field.derivatives(*POST[0])[0]) - 0.1)
    obstacles.objects.link(post)
    obstacles.objects.link(ground)
    fig = add_figure("SKIER")
    s = fig.turning
    s.ground, s.path, s.obstacles = ground, make_curve(CURVE), obstacles
    s.speed = START_SPEED
    bpy.context.view_layer.objects.active = fig
    # As with a window: the plan in the background job, the modal operator polling it.
    op_cls, fake, reports = modal_operator(fig)
    wm = WindowManager()
    timer = type("E", (), {"type": "TIMER"})()
    while (result := op_cls.modal(fake, Context(wm), timer)) == {"RUNNING_MODAL"}:
        time.sleep(0.02)                    # Blender's timer ticks; leave the planner the GIL
    return {"scene": sc, "field": field, "ground": ground, "post": post, "fig": fig,
            "result": result, "reports": reports, "progress": wm.progress,
            "curves": curves_of(fig)}


def test_the_run_follows_the_projected_curve_around_the_post(world):
    assert world["result"] == {"FINISHED"}, world["reports"]
    assert any(re.fullmatch(r"Follow Path: baked Skier over frames 1-\d+", r[1])
               for r in world["reports"]), world["reports"]
    progress = [v for v in world["progress"] if isinstance(v, int)]
    assert progress == sorted(progress) and progress[-1] == 100 and "end" in world["progress"]
    cv = world["curves"]
    xy = np.column_stack([cv[("location", 0)], cv[("location", 1)]])
    path = HermitePath.from_bezier(scene_adapters.bezier_control_points(world["fig"].turning.path))
    samples = path.sample(64)
    assert np.abs(samples[0] - CURVE[0][:2]).max() < 1e-6        # projected: x, y kept
    # The post stands across the curve, so the figure must leave it to pass on either side ...
    feet = dict(scene_adapters.obstacle_footprints(world["post"].users_collection[0]))
    post = Obstacles(polygons=[feet["Post"]])
    assert post.min_distance(samples).min() < 0.0
    # ... and does, keeping the clearance (measured 0.53 m) up to what the planner cannot see: it
    # checks every 0.1 s, 0.7 m at 7 m/s, and such a chord between two points at the clearance
    # from a corner comes 0.5 - sqrt(0.5^2 - 0.35^2) = 0.14 m closer in between.
    gap = post.min_distance(xy)
    assert gap.min() > DEFAULT_CLEARANCE - 0.15, gap.min()
    # Elsewhere it follows the curve (and the straight run-out beyond its end, up to where the
    # end test stops it): within 3 m all the way.  Measured 2.63 m at most (2.05 m swinging out
    # around the post before the speed balanced energy, docs/TERRAIN.md Section 4: it reaches
    # 0.7 m to the right of the curve, the figure passes it there with the clearance and
    # overshoots; 1.7 m at the last bend of the S, at 12 m/s); the end 2.7 m from the curve's
    # last point (the run stops once its progress along the curve passes the end).
    ahead = path.extended(20.0).sample(64)
    dist = np.min(np.linalg.norm(xy[:, None] - ahead[None], axis=2), axis=1)
    assert dist.max() < 3.0, dist.max()
    assert np.linalg.norm(xy[-1] - CURVE[-1][:2]) < 3.0


def test_the_feet_ride_on_the_mesh_in_its_surface(world):
    cv = world["curves"]
    x, y, z = (cv[("location", i)] for i in range(3))
    assert z.max() - z.min() > 8.0                       # it went down the hill
    # On the mesh on every frame (the issue asks for 1 cm of a ray cast; measured 9e-5 m: float32
    # keys at heights up to 17 m).
    assert np.abs(z - ray(world["ground"], x, y)).max() < 1e-3
    # +Z of the figure is the normal of the smooth field read from the mesh under the foot (the
    # skis lie in the surface; measured 7e-6 deg: float32 keys) ...
    up = object_up(cv)
    field = height_field_of(world["ground"], bpy.context.evaluated_depsgraph_get())
    fr = surface_frame(field, x, y, np.zeros_like(x), 9.81)
    assert angle(up, np.asarray(fr.n).T).max() < 1e-3
    # ... within 1 deg of the mesh's own face there (measured 0.52 deg: on the rounded edge the
    # faces turn 1.2 deg from one to the next, the smooth normal lies between), tilted with it.
    assert angle(up, ray(world["ground"], x, y, normal=True)).max() < 1.0
    assert np.degrees(np.arccos(up[:, 2])).max() > 10.0


def test_the_speed_is_computed_along_the_way(world):
    """Keyed ``turn_speed``: it starts at the Speed setting, falls on the flat shelf (snow
    friction, drag) and grows down the slope, never faster than the drop allows."""
    cv = world["curves"]
    y, z, v = cv[("location", 1)], cv[("location", 2)], cv[('["turn_speed"]', 0)]
    cf, lean = cv[('["turn_curvature"]', 0)], cv[('["turn_lean"]', 0)]
    assert v[0] == pytest.approx(START_SPEED, abs=1e-3)
    flat = y > SHELF + 1.0
    slope = y < SHELF - EDGE - 1.0
    assert flat.sum() > 10 and slope.sum() > 10
    assert np.all(np.diff(v[flat]) < 0)                 # slowing on the flat
    assert v[slope][-1] > v[slope][0] + 3.0             # speeding up downhill
    assert v.max() > START_SPEED + 3.0
    # Energy: friction and drag only take away.  Gravity along the track acts on the body's
    # speed V_cm while the foot drops at V_f = V_cm / (1 - C_f l sin theta_v) (Eq. 21), so what
    # the drop gives is at most (1 + max(0, -C_f l sin theta_v)) times 2 g (z0 - z).
    out = max(0.0, float(np.max(-cf * world["fig"].turning.com_height * np.sin(lean))))
    gain = 2 * 9.81 * (z[0] - z) * (1 + out)
    assert np.all(v ** 2 <= START_SPEED ** 2 + gain + 1e-3)


def test_the_foot_track_lies_on_the_surface(world):
    track = world["fig"].turning.foot_track.data.splines[0].points
    co = np.empty(4 * len(track))
    track.foreach_get("co", co)
    co = co.reshape(-1, 4)
    above = co[:, 2] - ray(world["ground"], co[:, 0], co[:, 1])
    np.testing.assert_allclose(above, 0.01, atol=1e-3)


def test_cancelled_follow_on_the_ground_leaves_the_scene_unchanged(world):
    fig = add_figure("TELEMARK")
    fig.turning.ground, fig.turning.path = world["ground"], make_curve(CURVE, "Cancel Path")
    bpy.context.view_layer.objects.active = fig
    before = snapshot()
    op_cls, fake, reports = modal_operator(fig)
    assert fake._job.mesh_ground is not None
    wm = WindowManager()
    assert op_cls.modal(fake, Context(wm), type("E", (), {"type": "ESC"})()) == {"CANCELLED"}
    assert fake._job.done() and "end" in wm.progress
    assert reports and "cancelled" in reports[0][1]
    assert snapshot() == before, diff(before, snapshot())


def test_a_curve_off_the_mesh_is_reported(world):
    fig = add_figure("CYCLIST")
    fig.turning.ground = world["ground"]
    fig.turning.path = make_curve([(0.0, 8.0, 0.0), (10.0, -20.0, 0.0), (40.0, -40.0, 0.0)],
                                  "Off Path")
    bpy.context.view_layer.objects.active = fig
    before = snapshot()
    with pytest.raises(RuntimeError, match=r"path 'Off Path' leaves ground 'Slope' at "
                                           r"\(2[5-9]\.\d\d, -[\d.]+\) m, [\d.]+ m along it"):
        bpy.ops.turning.follow_path()
    assert snapshot() == before, diff(before, snapshot())


@pytest.mark.parametrize("shape", ["solid", "overhang"])
def test_a_mesh_that_is_not_a_height_field_is_reported(world, shape):
    """A closed box (its bottom lies under its top) and a sheet folded back over itself."""
    if shape == "solid":
        obj = link(make_box("Block", (0.0, -20.0), (60.0, 80.0), z0=-5.0, height=5.0))
    else:
        mesh = bpy.data.meshes.new("Fold")
        mesh.from_pydata([(-30, 20, 0), (30, 20, 0), (30, -60, 0), (-30, -60, 0),
                          (30, -20, 2), (-30, -20, 2)], [],
                         [(0, 1, 2, 3), (3, 2, 4, 5)])          # a flap back over the sheet
        obj = link(bpy.data.objects.new("Fold", mesh))
    fig = add_figure("SNOWBOARDER")
    fig.turning.ground = obj
    fig.turning.path = make_curve([(0.0, 8.0, 0.0), (0.0, -30.0, 0.0)], f"{shape} path")
    bpy.context.view_layer.objects.active = fig
    before = snapshot()
    with pytest.raises(RuntimeError, match=rf"ground '{obj.name}' is not a height field: at "
                                           r"\(-?[\d.]+, -?[\d.]+\) m a face lies [\d.]+ m under"):
        bpy.ops.turning.follow_path()
    assert snapshot() == before, diff(before, snapshot())



def test_a_plan_that_fails_near_the_ground_edge_says_where_it_ends(world):
    """The planner clips every branch that leaves the ground, so a plan failing within one
    horizon's reach of the mesh's edge gets a note saying where the ground ends (planning such a
    run to its failure searches the whole tree: the note is tested on the failure itself)."""
    from blender_turning.blender.scene.follow_ground import edge_note, read_follow_ground
    from blender_turning.core.errors import PlanInfeasible
    fig = world["fig"]
    ground = read_follow_ground(fig, bpy.context.evaluated_depsgraph_get())
    near = PlanInfeasible(3.0, (0.0, 16.5))                    # the mesh ends at y = 20
    assert re.fullmatch(r" \(ground 'Slope' ends 3\.5 m from there; the planner looks one "
                        r"horizon, up to 30 m, ahead, .*\)", edge_note(near, ground, 30.0))
    assert edge_note(near, ground, 3.0) == ""                   # out of its reach
    assert edge_note(PlanInfeasible(3.0, (0.0, -50.0)), ground, 20.0) == ""
    assert edge_note(ValueError("x"), ground, 30.0) == ""
    assert edge_note(near, None, 30.0) == ""                    # flat ground has no edge


def test_the_plan_starts_at_the_speed_keyed_at_the_first_frame(world):
    """A keyed Speed: the plan on the ground starts at its value at the scene's first frame (the
    speed is a state from there), whatever frame is current; friction and drag are the
    figure's."""
    from blender_turning.blender.scene.follow_ground import plan_inputs
    from blender_turning.blender.scene.scene_adapters import figure_from_settings
    sc = world["scene"]
    fig = add_figure("SKIER")
    fig.turning.ground = world["ground"]
    fig.turning.terrain.friction, fig.turning.terrain.drag_area = 0.08, 0.4
    fig.turning.speed = 6.0
    fig.keyframe_insert("turning.speed", frame=sc.frame_start)
    fig.turning.speed = 15.0
    fig.keyframe_insert("turning.speed", frame=sc.frame_start + 40)
    sc.frame_set(sc.frame_start + 40)
    dg = bpy.context.evaluated_depsgraph_get()
    figure, ground, terrain = plan_inputs(bpy.context, fig, figure_from_settings(fig.turning), dg)
    assert figure.body.V_cm == pytest.approx(6.0)
    assert ground.name == "Slope" and terrain["ground"] is ground.field
    assert (terrain["resistance"].mu, terrain["resistance"].CdA) == pytest.approx((0.08, 0.4))
    fig.turning.ground = None
    assert plan_inputs(bpy.context, fig, figure, dg)[1:] == (None, {})


def test_bake_turns_draws_its_foot_track_on_the_ground_too(world):
    """Both operators write the track through the same bake: on a Ground mesh it lies on it."""
    sc = world["scene"]
    sc.cursor.location = (0.0, -25.0, 0.0)                     # on the rounded edge, facing
    sc.cursor.rotation_euler = (0.0, 0.0, math.radians(-180.0))     # -y: down the hill
    assert bpy.ops.turning.add_figure(sport="SNOWBOARDER") == {"FINISHED"}
    fig = bpy.context.view_layer.objects.active
    sc.cursor.rotation_euler = (0.0, 0.0, 0.0)
    fig.turning.ground = world["ground"]
    assert bpy.ops.turning.bake_turns(frame_range="CUSTOM", frame_start=1,
                                      frame_end=97) == {"FINISHED"}
    track = fig.turning.foot_track.data.splines[0].points
    co = np.empty(4 * len(track))
    track.foreach_get("co", co)
    co = co.reshape(-1, 4)
    assert co[:, 2].max() - co[:, 2].min() > 2.0
    np.testing.assert_allclose(co[:, 2] - ray(world["ground"], co[:, 0], co[:, 1]), 0.01,
                               atol=1e-3)

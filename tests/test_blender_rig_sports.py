"""The user's own rig as a snowboarder and a telemark skier, on the bpy wheel: a
Rigify rig and a Mixamo-named skeleton beside the built-in figure of the sport, same settings;
each rig is made a figure of one sport, baked, measured and given back (Remove Figure) before
the next."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning import blender as addon  # noqa: E402
from blender_turning.blender.scene.retarget_adapter import facing  # noqa: E402
from rig_fixtures import (activate, knee, lean, mixamo_skeleton, rigify_rig, sample,  # noqa: E402
                          state)

pytestmark = pytest.mark.blender
FRAMES = (1, 48)
SAME = ("mass", "com_height", "inertia", "speed", "period", "lean", "heading", "start_heading")
#: Ground equipment -> the joints bound to it (the telemark's ball of the foot stays on its ski).
BINDINGS = {
    "SNOWBOARDER": {"board": [("ankle", "L"), ("ankle", "R")]},
    "GOOFY": {"board": [("ankle", "L"), ("ankle", "R")]},
    "TELEMARK": {"ski.L": [("toe", "L")], "ski.R": [("toe", "R")]},
    # Feet on the pedals, hands on the bar, hips on the saddle.
    "CYCLIST": {"pedal.L": [("ankle", "L")], "pedal.R": [("ankle", "R")],
                "fork": [("wrist", "L"), ("wrist", "R")], "frame": [("pelvis", None)]},
}
GROUND = {"CYCLIST": ("wheel.F", "wheel.R")}


@pytest.fixture(scope="module")
def rigs():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = FRAMES
    sc.render.fps = 24
    users = {"rigify": rigify_rig(location=(4.0, 0.0, 0.0)),
             "mixamo": mixamo_skeleton(location=(-4.0, 0.0, 0.0))}
    for obj in users.values():
        obj.rotation_euler = (0.0, 0.0, math.pi)
    yield users
    addon.unregister()


@pytest.fixture(scope="module", params=["SNOWBOARDER", "GOOFY", "TELEMARK", "CYCLIST"])
def run(request, rigs):
    """``GOOFY``: goofy snowboarders (the built-in rig too)."""
    case = request.param
    sport, stance = ("SNOWBOARDER", "GOOFY") if case == "GOOFY" else (case, "REGULAR")
    before = {k: state(o) for k, o in rigs.items()}
    sc = bpy.context.scene
    sc.cursor.location = (0, 0, 0)
    assert bpy.ops.turning.add_figure(sport=sport) == {"FINISHED"}
    builtin = bpy.context.view_layer.objects.active
    builtin.turning.rig.stance = stance                   # the built-in rides goofy too
    for obj in rigs.values():
        activate(obj)
        assert bpy.ops.turning.make_figure(sport=sport, bone_map="AUTO",
                                           stance=stance) == {"FINISHED"}
        for n in SAME:
            setattr(obj.turning, n, getattr(builtin.turning, n))
        # Turned to start along the built-in's heading (the snowboarder rides side-on).
        obj.rotation_euler[2] = builtin.turning.start_heading - facing(obj)
    figures = {"builtin": builtin, **rigs}
    for obj in figures.values():
        activate(obj)
        assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    yield case, sample(figures, FRAMES, BINDINGS[case], GROUND.get(case))
    for k, obj in rigs.items():
        activate(obj)
        assert bpy.ops.turning.remove_figure() == {"FINISHED"}
        assert state(obj) == before[k], k
    activate(builtin)
    bpy.ops.turning.clear_bake()


@pytest.mark.parametrize("key", ["rigify", "mixamo"])
def test_lean_and_knees_follow_the_builtin(run, key):
    sport, (out, _, _, _) = run
    lb = lean(out["builtin"])
    assert np.ptp(lb) > math.radians(15)
    assert np.max(np.abs(lean(out[key]) - lb)) < math.radians(0.02), sport
    for s in "LR":
        kb = knee(out["builtin"], s)
        assert np.ptp(kb) > math.radians(3)
        assert np.max(np.abs(knee(out[key], s) - kb)) < math.radians(0.5), (
            sport, s, np.degrees(np.max(np.abs(knee(out[key], s) - kb))))


@pytest.mark.parametrize("key", ["rigify", "mixamo"])
def test_boots_bound_and_equipment_on_the_snow(run, key):
    """Snowboard: both ankles on the board; telemark: the balls of the feet on the skis (the
    trailing heel lifts); cyclist: feet on the pedals, hands on the bar, hips on the saddle, both
    tyres on the ground; no point of the equipment below the ground, none 2 cm above it."""
    sport, (_, low, gap, _) = run
    low, gap = np.array(low[key]), np.array(gap[key])
    if sport == "CYCLIST":
        # The tyres touch: the front one slides along the fork as the built-in's (a driver on
        # the baked turn_fork_slide); measured within 3.1e-5 m (float32 world matrices).
        assert np.abs(low).max() < 1e-4, (low.min(axis=0), low.max(axis=0))
    low = low.min(axis=1)                    # the lowest piece
    assert np.all(low > -1e-3) and np.all(low < 0.02), (sport, low.min(), low.max())
    assert np.all(gap < 0.01), (sport, gap.max())


@pytest.mark.parametrize("key", ["rigify", "mixamo"])
def test_deforming_bones_move_none_sheared(run, key):
    sport, (_, _, _, deform) = run
    for n in deform[key][0]:
        arm = np.array([f[n][0] for f in deform[key]])
        world = np.array([f[n][1] for f in deform[key]])
        assert np.all(np.isfinite(world)), n
        cols = world[:, :3, :3] / np.linalg.norm(world[:, :3, :3], axis=1, keepdims=True)
        assert np.abs(np.einsum("fki,fkj->fij", cols, cols) - np.eye(3)).max() < 1e-3, n
        assert np.ptp(arm.reshape(len(arm), -1), axis=0).max() > 1e-3, (sport, n)


@pytest.mark.parametrize("key", ["builtin", "rigify", "mixamo"])
def test_the_stance_says_which_boot_leads(run, key):
    case, (out, _, _, _) = run
    if case in ("TELEMARK", "CYCLIST"):
        pytest.skip("no stance")
    lead = "R" if case == "GOOFY" else "L"
    back = "L" if lead == "R" else "R"
    for p, h in zip(out[key]["p"], out[key]["heading"]):
        ahead = (p["ankle", lead] - p["ankle", back])[:2] @ np.array([math.cos(h), math.sin(h)])
        assert ahead > 0.2, (case, ahead)


@pytest.mark.parametrize("key", ["rigify", "mixamo"])
def test_the_bicycle_wheels_roll_with_the_distance(run, rigs, key):
    """The wheels turn about their axles by the distance travelled over the tyre's radius (a
    driver on the baked ``turn_distance``): a few turns in two seconds at 6 m/s."""
    case, _ = run
    if case != "CYCLIST":
        pytest.skip("no wheels")
    obj = rigs[key]
    wheels = [o for o in obj.turning.rig.equipment.objects
              if o.get("turning_equipment") in ("wheel.F", "wheel.R")]
    assert len(wheels) == 2
    sc = bpy.context.scene
    for f in (FRAMES[0], 30, FRAMES[1]):
        sc.frame_set(f)
        d = obj["turn_distance"]
        for w in wheels:
            spin = w.animation_data.drivers[0].driver.expression.split(" * ")[0]
            assert w.rotation_euler[1] == pytest.approx(float(spin) * d, rel=1e-5, abs=1e-6)
    assert obj["turn_distance"] > 5.0
    assert abs(wheels[0].rotation_euler[1]) > 2 * math.pi

"""The bake an animator expects: every selected figure, frame ranges and steps, a keyed
speed, the Add menu, tooltips and soft limits, glTF extras, sub-panels, and a .blend saved by the
add-on at commit 8b11d74 opening and re-baking unchanged."""
import math
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.ops import figure as ops_figure  # noqa: E402
from blender_turning.blender.ui import panel  # noqa: E402
from blender_turning.blender.props.figure import TurningFigureSettings  # noqa: E402
from blender_turning.core.physics.params import PRESETS  # noqa: E402
from modal_stand_ins import Context, WindowManager  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]
DATA = Path(__file__).parent / "data"


@pytest.fixture
def scene(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, 48
    sc.render.fps = 24
    return sc


def add(sport="SKIER", at=(0, 0, 0)):
    bpy.context.scene.cursor.location = at
    assert bpy.ops.turning.add_figure(sport=sport) == {"FINISHED"}
    return bpy.context.view_layer.objects.active


def select(objs, active):
    for o in bpy.context.view_layer.objects:
        o.select_set(o in objs)
    bpy.context.view_layer.objects.active = active


def keys(obj, path, index=0):
    """``(frames, values)`` of the F-curve ``path[index]`` of ``obj``'s bake or tweak layer."""
    bags = [bake.baked_channels(obj), compat.channels(obj)]
    fc = next(f for bag in bags if bag is not None for f in bag.fcurves
              if f.data_path == path and f.array_index == index)
    co = np.empty(2 * len(fc.keyframe_points), np.float32)
    fc.keyframe_points.foreach_get("co", co)
    return co[0::2], co[1::2]


def all_keys(obj):
    """Every key of the figure: its bake layer's and its active action's (the tweak layer)."""
    out = {}
    bags = [bake.baked_channels(obj), compat.channels(obj)]
    for fc in [fc for bag in bags if bag is not None for fc in bag.fcurves]:
        co = np.empty(2 * len(fc.keyframe_points), np.float32)
        fc.keyframe_points.foreach_get("co", co)
        out[(fc.data_path, fc.array_index)] = co
    return out


def snapshot():
    out = {"objects": sorted(o.name for o in bpy.data.objects),
           "actions": sorted(a.name for a in bpy.data.actions)}
    for a in bpy.data.actions:
        for fc in compat.all_fcurves(a):
            co = np.empty(2 * len(fc.keyframe_points), np.float32)
            fc.keyframe_points.foreach_get("co", co)
            out[(a.name, fc.data_path, fc.array_index)] = co.tobytes()
    for o in bpy.data.objects:
        out[o.name] = (tuple(o.location), tuple(o.rotation_euler), tuple(o.turning.start))
    return out


# -- every selected figure --------------------------------------------------------------------

def test_bake_turns_bakes_every_selected_figure(scene):
    figs = [add("SKIER", (0, 0, 0)), add("SNOWBOARDER", (5, 0, 0)), add("CYCLIST", (10, 0, 0))]
    unselected = add("TELEMARK", (15, 0, 0))
    select(figs[1:] + [figs[0].children[0]], figs[1])          # a body mesh counts for its rig
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    for fig in figs:
        frames, _ = keys(fig, "location", 0)
        np.testing.assert_array_equal(frames, np.arange(1, 49))
        assert fig.turning.foot_track is not None
    assert unselected.animation_data is None
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert all(f.animation_data is None or f.animation_data.action is None for f in figs)


def test_one_bad_figure_bakes_nothing(scene):
    good, bad = add("SKIER"), add("SKIER", (5, 0, 0))
    bad.turning.lean = bad.turning.fall_angle
    select([good, bad], good)
    before = snapshot()
    with pytest.raises(RuntimeError, match=f"{bad.name}: Lean \\(turning.lean\\) = 60 deg at "
                       r"frame 1 is outside the allowed range \[1, 60\) deg"):
        bpy.ops.turning.bake_turns()
    assert snapshot() == before


@pytest.mark.installed
def test_a_keyed_lean_is_checked_at_the_first_frame_past_its_range(scene):
    fig = add("SKIER")
    s = fig.turning
    scene.frame_end = 48
    for frame, deg in ((1, 20.0), (40, 70.0)):
        s.lean = math.radians(deg)
        fig.keyframe_insert('turning.lean', frame=frame)
    first = None
    for frame in range(1, 49):
        scene.frame_set(frame)
        if first is None and s.lean >= s.fall_angle:
            first = frame
    assert first is not None and 1 < first < 40
    select([fig], fig)
    with pytest.raises(RuntimeError, match=f"Lean \\(turning.lean\\) = .* deg at frame {first} "
                       r"is outside the allowed range \[1, 60\) deg"):
        bpy.ops.turning.bake_turns()


def modal_bake(figs):
    """A stand-in ``self`` for the modal Bake Turns over ``figs`` (no window in the wheel)."""
    from blender_turning.blender.jobs.bake_job import BakeJob
    from blender_turning.blender.scene.scene_adapters import FrameRange
    op_cls = bpy.types.TURNING_OT_bake_turns
    reports = []
    fake = type("Op", (), {"report": lambda self, kind, msg: reports.append((kind, msg)),
                           "_cleanup": op_cls._cleanup, "_status": op_cls._status,
                           "_finish": op_cls._finish})()
    fake._job = BakeJob([f.name for f in figs], FrameRange.of_scene(bpy.context.scene))
    fake._timer = object()
    return op_cls, fake, reports


def test_modal_bake_reports_progress_and_esc_writes_nothing(scene):
    figs = [add("SKIER"), add("SNOWBOARDER", (5, 0, 0)), add("TELEMARK", (10, 0, 0))]
    before = snapshot()
    op_cls, fake, reports = modal_bake(figs)
    wm, timer = WindowManager(), type("E", (), {"type": "TIMER"})()
    assert op_cls.modal(fake, Context(wm), timer) == {"RUNNING_MODAL"}
    assert op_cls.modal(fake, Context(wm), type("E", (), {"type": "ESC"})()) == {"CANCELLED"}
    assert wm.progress == [1, "end"] and "cancelled" in reports[0][1]
    assert snapshot() == before
    op_cls, fake, reports = modal_bake(figs)
    wm = WindowManager()
    while (ret := op_cls.modal(fake, Context(wm), timer)) == {"RUNNING_MODAL"}:
        pass
    assert ret == {"FINISHED"} and wm.progress == [1, 2, 3, "end"]
    assert all(bake.figure_action(f).name == f.name for f in figs)


# -- frame range and step ---------------------------------------------------------------------

def test_preview_and_custom_ranges(scene):
    fig = add("SKIER")
    with pytest.raises(RuntimeError, match="no preview range"):
        bpy.ops.turning.bake_turns(frame_range="PREVIEW")
    scene.use_preview_range = True
    scene.frame_preview_start, scene.frame_preview_end = 11, 30
    assert bpy.ops.turning.bake_turns(frame_range="PREVIEW") == {"FINISHED"}
    np.testing.assert_array_equal(keys(fig, "location")[0], np.arange(11, 31))
    assert bpy.ops.turning.bake_turns(frame_range="CUSTOM", frame_start=-5,
                                      frame_end=60) == {"FINISHED"}
    np.testing.assert_array_equal(keys(fig, "location")[0], np.arange(-5, 61))
    with pytest.raises(RuntimeError, match="at least two frames"):
        bpy.ops.turning.bake_turns(frame_range="CUSTOM", frame_start=9, frame_end=9)


def test_a_step_keys_every_nth_frame_and_interpolates_smoothly(scene):
    fig = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    exact = all_keys(fig)
    lean = fig.pose.bones.keys()
    assert bpy.ops.turning.bake_turns(step=4) == {"FINISHED"}
    stepped = all_keys(fig)
    assert stepped.keys() == exact.keys()
    want = np.r_[np.arange(1, 49, 4), 48]
    bezier = 0
    for key, co in stepped.items():
        if key[0].startswith("turning."):
            continue
        np.testing.assert_array_equal(co[0::2], want)
        np.testing.assert_array_equal(co[1::2], exact[key][1::2][want - 1])    # the same keys
    for fc in bake.baked_channels(fig).fcurves:
        if not fc.data_path.startswith("turning."):
            assert {k.interpolation for k in fc.keyframe_points} == {"BEZIER"}
            bezier += 1
    assert bezier == len(exact) and lean
    # In between, the curves follow the every-frame bake closely (cubic Hermite through the
    # keys with the motion's own slopes): the lean, a 2 s turn keyed every 1/6 s, within
    # 0.05 deg (measured 0.043 in the start's transient, 0.006 after; linear in-betweens miss
    # by 0.8 deg, auto-clamped handles by 1.4 deg).
    fc = next(f for f in bake.baked_channels(fig).fcurves if f.data_path == '["turn_lean"]')
    between = np.array([fc.evaluate(f) for f in range(1, 49)])
    err = np.abs(between - exact[('["turn_lean"]', 0)][1::2])
    assert np.degrees(err.max()) < 0.05, np.degrees(err).round(4)


# -- speed -------------------------------------------------------------------------------------

def crank_rate(fig, frames):
    """Crank angle per frame (rad), from consecutive keys of its quaternion."""
    q = np.column_stack([keys(fig, 'pose.bones["crank"].rotation_quaternion', i)[1]
                         for i in range(4)]).astype(float)
    dots = np.abs(np.sum(q[1:] * q[:-1], axis=1)).clip(0, 1)
    return 2 * np.arccos(dots)[frames]


RTOL_SPEED = 5e-4      # measured 1.9e-4: frames fall between the 0.02 s steps (interpolated)
RTOL_PEDAL = 1.5e-3    # measured 6.4e-4 over half-second windows (frame-to-frame: 1e-2)


def test_keyed_speed_speeds_up_and_brakes_the_figure_and_its_pedals(scene):
    """Speed keyed 5 -> 10 -> 6 m/s: the body's speed, and the pedal rate, follow."""
    scene.frame_end = 145
    fig = add("CYCLIST")
    for frame, speed in ((1, 5.0), (73, 10.0), (145, 6.0)):
        fig.turning.speed = speed
        fig.keyframe_insert("turning.speed", frame=frame)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert ("turning.speed", 0) in all_keys(fig)                    # the user's keys stay
    _, v_f = keys(fig, '["turn_speed"]')
    _, c_f = keys(fig, '["turn_curvature"]')
    _, lean = keys(fig, '["turn_lean"]')
    v_cm = v_f * (1.0 - c_f * fig.turning.com_height * np.sin(lean))      # Eq. (21) backwards
    fc = next(f for f in compat.channels(fig).fcurves if f.data_path == "turning.speed")
    keyed = np.array([fc.evaluate(f) for f in range(1, 146)])       # eased in and out (Bezier)
    np.testing.assert_allclose(v_cm, keyed, rtol=RTOL_SPEED)
    # The pedals turn with the distance travelled: crank angle over the foot's distance (V_f by
    # the trapezoid rule), half a second at a time, is one constant, 1 / (r_wheel gear).
    per_metre = (crank_rate(fig, slice(None)) / (0.5 * (v_f[1:] + v_f[:-1]))).reshape(-1, 12)
    per_metre = per_metre.mean(axis=1)
    assert np.ptp(per_metre) / per_metre.mean() < RTOL_PEDAL, np.ptp(per_metre)
    start, top, end = (crank_rate(fig, slice(a, a + 12)).mean() for a in (0, 66, 132))
    assert top > 1.8 * start and end < 0.7 * top


def test_a_keyed_speed_out_of_range_is_reported(scene):
    fig = add("SKIER")
    fig.keyframe_insert("turning.speed", frame=1)
    fc = next(f for f in compat.channels(fig).fcurves if f.data_path == "turning.speed")
    fc.keyframe_points.insert(30, -1.0)
    before = snapshot()
    with pytest.raises(RuntimeError, match=r"speed = .* m/s at frame \d+ is outside the allowed "
                                           r"range \[0.5, 60\] m/s"):
        bpy.ops.turning.bake_turns()
    assert snapshot() == before


# -- Add menu, tooltips, sub-panels -------------------------------------------------------------

class LayoutStub:
    def __init__(self, calls):
        object.__setattr__(self, "calls", calls)

    def __getattr__(self, name):
        def call(*args, **kwargs):
            self.calls.append((name, args, kwargs))
            return LayoutStub(self.calls)
        return call

    def __setattr__(self, name, value):
        self.calls.append(("set", name, value))


def test_add_menu_lists_every_sport(scene):
    calls = []
    ops_figure.VIEW3D_MT_turning_figure_add.draw(type("M", (), {"layout": LayoutStub(calls)})(),
                                                 bpy.context)
    assert [c[2]["text"] for c in calls if c[0] == "operator"] == [
        "Skier", "Snowboarder", "Telemark", "Cyclist"]
    assert [c[2] for c in calls if c[0] == "set" and c[1] == "sport"] == [
        "SKIER", "SNOWBOARDER", "TELEMARK", "CYCLIST"]
    assert ("operator_menu_enum", ("turning.add_crowd", "formation")) in [c[:2] for c in calls]
    drawn = bpy.types.VIEW3D_MT_add._dyn_ui_initialize()
    assert ops_figure.draw_add_menu in drawn
    calls = []
    ops_figure.draw_add_menu(type("M", (), {"layout": LayoutStub(calls)})(), bpy.context)
    assert calls[0][1] == ("VIEW3D_MT_turning_figure_add",)


def test_tooltips_units_and_soft_limits():
    props = TurningFigureSettings.bl_rna.properties
    for p in props:
        if p.identifier in ("rna_type", "name"):
            continue
        assert p.description and p.description[0].isupper(), p.identifier
        if p.type == "FLOAT" and p.array_length == 0:
            assert p.hard_min <= p.soft_min < p.soft_max <= p.hard_max, p.identifier
    symbols = {"mass": "(m, kg)", "com_height": "(l, m)", "inertia": "(I_v, kg m^2",
               "speed": "(V_cm, m/s)", "curvature_max": "(C_f max, 1/m)",
               "curvature_rate_max": "(dC_f/dt max, 1/(m s))", "fall_angle": "(theta_fall)",
               "period": "(2 pi / omega0, s)", "lean": "(theta_max)", "heading": "(theta_h)"}
    for name, symbol in symbols.items():
        assert symbol in props[name].description, name
    assert props["lean"].description.startswith("How far the body leans at the apex of a turn")
    for name, unit in (("curvature_max", "(1/m)"), ("curvature_rate_max", "(1/(m s))"),
                       ("inertia", "(kg m^2)")):
        assert props[name].name.endswith(unit)
    for name in ("period", "lean", "heading", "speed"):
        assert props[name].is_animatable, name
    # The presets lie inside the soft ranges, so dragging reaches them.
    for fig in PRESETS.values():
        for name, value in (("mass", fig.body.m), ("com_height", fig.body.l),
                            ("inertia", fig.body.I_v), ("speed", fig.body.V_cm),
                            ("curvature_max", fig.limits.C_f_max),
                            ("curvature_rate_max", fig.limits.dC_f_max),
                            ("fall_angle", fig.limits.theta_fall)):
            v32 = float(np.float32(value))      # Blender keeps a FloatProperty in float32
            assert props[name].soft_min <= v32 <= props[name].soft_max, (fig.name, name)


def test_settings_take_their_ranges_from_the_core_table():
    """One table of ranges (core/ranges.py) for flags, files, job keys and these
    settings; Blender holds its floats in single precision."""
    from blender_turning.core.ranges import RANGES
    props = TurningFigureSettings.bl_rna.properties
    for name, key in (("mass", "m"), ("com_height", "l"), ("inertia", "I_v"), ("speed", "V_cm"),
                      ("curvature_max", "C_f_max"), ("curvature_rate_max", "dC_f_max"),
                      ("fall_angle", "theta_fall"), ("period", "period"), ("lean", "theta_max"),
                      ("heading", "heading"), ("plan_curvature_rate", "plan_curvature_rate")):
        assert props[name].hard_min == pytest.approx(RANGES[key].lo, rel=1e-6), name
        assert props[name].hard_max == pytest.approx(RANGES[key].hi, rel=1e-6), name


def test_sub_panels(scene):
    subs = [c for c in panel.classes if c is not panel.VIEW3D_PT_turning]
    assert {c.bl_label for c in subs} == {"Turns", "Bake", "Body", "Limits", "Ground",
                                          "Speed Control", "Follow Path", "Rig"}
    assert all(c.bl_parent_id == panel.ROOT_PANEL for c in subs)
    fig = add("SKIER")
    drawn = {}
    for cls in subs:
        assert cls.poll(bpy.context)
        calls = []
        mixins = tuple(b for b in cls.__mro__[1:] if b.__module__ == panel.__name__)
        cls.draw(type("P", mixins, {"layout": LayoutStub(calls)})(), bpy.context)
        if cls not in (panel.VIEW3D_PT_turning_bake, panel.VIEW3D_PT_turning_rig):
            assert ("set", "use_property_split", True) in calls, cls
        drawn[cls.bl_label] = [c[1][1] for c in calls if c[0] == "prop" and len(c[1]) > 1]
    assert drawn["Body"] == ["mass", "com_height", "inertia"]
    assert drawn["Limits"] == ["curvature_max", "curvature_rate_max", "fall_angle"]
    assert drawn["Ground"] == ["start", "start_heading", "ground", "friction", "drag_area",
                              "air_density"]
    assert drawn["Speed Control"] == ["target_speed", "style", "snow", "grip", "use_stop",
                                      "stop_frame"]
    assert drawn["Turns"] == ["period", "lean", "use_heading", "heading", "speed"]
    # Rig shows for an armature that is not a figure yet (Make Figure hangs under it).
    arm = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    scene.collection.objects.link(arm)
    select([arm], arm)
    assert panel.VIEW3D_PT_turning_rig.poll(bpy.context)
    assert not panel.VIEW3D_PT_turning_body.poll(bpy.context)
    assert fig.turning.is_figure


# -- glTF ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("extras", [True, False])
def test_state_properties_go_out_as_gltf_extras(scene, extras, tmp_path):
    import addon_utils
    addon_utils.enable("io_scene_gltf2", default_set=False)
    fig = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    scene.frame_set(20)
    state = {k: fig[k] for k in ("turn_phase", "turn_lean", "turn_curvature", "turn_leg_force",
                                 "turn_speed")}
    assert abs(state["turn_lean"]) > 0.05
    path = str(tmp_path / "figure.glb")
    bpy.ops.export_scene.gltf(filepath=path, export_format="GLB", export_extras=extras,
                              export_current_frame=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    if extras:
        for k, v in state.items():
            assert arm[k] == pytest.approx(v, rel=1e-6), k
    else:
        assert not [k for k in arm.keys() if k.startswith("turn_")]


# -- a file saved by today's code ----------------------------------------------------------------

def legacy_files():
    # Blender 4.2 cannot read a 5.0 file; both read the 4.2 one (5.0 converts its action).
    names = ["legacy_8b11d74_bpy42.blend"]
    if bpy.app.version >= (4, 5, 0):
        names.append("legacy_8b11d74.blend")
    return names


def motion(curves, fig) -> dict:
    """``curves`` without the export take a bake keys on its figure (docs/export.md): exactly
    one, the figure's own."""
    take = [k for k in curves if k[0].startswith('["turn_take ')]
    assert take == [(f'["turn_take {fig.name}"]', 0)], take
    return {k: v for k, v in curves.items() if k not in take}


@pytest.mark.parametrize("name", legacy_files())
def test_a_file_saved_at_8b11d74_opens_and_rebakes_the_same_motion(registered, name):
    bpy.ops.wm.open_mainfile(filepath=str(DATA / name), load_ui=False)
    fig = bpy.data.objects["Skier"]
    s = fig.turning
    assert s.is_figure and s.sport == "SKIER" and not s.use_heading
    assert (s.mass, s.speed, s.start[0], s.start[1]) == pytest.approx((72.0, 10.0, 1.0, 2.0))
    saved = all_keys(fig)
    period = saved[("turning.period", 0)]
    np.testing.assert_allclose(period, [1, 2.4, 48, 1.8], rtol=1e-6)
    assert ("turning.lean", 0) in saved and len(saved) == 104
    select([fig], fig)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    rebaked = motion(all_keys(fig), fig)
    # Today's bake keys the skid angle too (turn_skid, docs/skidding.md Section 8).
    assert set(rebaked) == set(saved) | {('["turn_skid"]', 0)}
    # The motion itself has changed since 8b11d74 (the smooth phase-ellipse law, frame
    # output that obeys the model), so "unchanged" means: the old file's settings and keys are
    # read exactly as today's.  A figure made now with the same settings, keys and start bakes
    # the same keys, bit for bit.
    fresh = add("SKIER", at=tuple(s.start))
    fresh.rotation_euler = (0.0, 0.0, s.start_heading - math.pi / 2)
    for prop in s.bl_rna.properties:
        if not prop.is_readonly and prop.type not in ("POINTER", "COLLECTION") \
                and prop.identifier not in ("rna_type", "name"):
            setattr(fresh.turning, prop.identifier, getattr(s, prop.identifier))
    for path in ("period", "lean"):
        frames, values = keys(fig, f"turning.{path}")
        for f, v in zip(frames, values):
            setattr(fresh.turning, path, float(v))
            fresh.keyframe_insert(f"turning.{path}", frame=float(f))
    select([fresh], fresh)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    again = motion(all_keys(fresh), fresh)
    assert again.keys() == rebaked.keys()
    for key, co in rebaked.items():
        np.testing.assert_array_equal(again[key], co, err_msg=str(key))
    select([fig], fig)
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert set(all_keys(fig)) == {("turning.period", 0), ("turning.lean", 0)}

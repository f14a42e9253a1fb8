"""What the model changed is said: Bake Turns and the Turns panel give the lean a figure's bounds
let it reach when that is not the asked one, and why (the core's report); Follow Path, on one
figure and on several, gives the largest distance of the foot from the drawn path and where, and
warns beyond *Warn Beyond*.  Reports are read as Blender prints them in background mode."""
import math
import os
import re
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from test_blender_operators import LayoutStub, add, make_path, scene  # noqa: E402,F401

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.ui import panel  # noqa: E402
from blender_turning.blender.scene import scene_adapters  # noqa: E402
from blender_turning.core.course.path import HermitePath  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]

LEAN = re.compile(r"Warning: Bake Turns: (\S+): lean ([\d.]+) deg at period [\d.]+ s "
                  r"\(asked ([\d.]+) deg; limited by (\S+)(| of the half-turn \w+ to [\d.]+ "
                  r"\(heading control's room\)) from")
FAR = re.compile(r"(Info|Warning): Follow Path: (\S+): the foot is at most ([\d.]+) m from the "
                 r"drawn path \(at frame (\d+), (\d+) m along it\)")


def keyed(obj, path):
    fc = next(f for f in bake.baked_channels(obj).fcurves if f.data_path == path)
    co = np.empty(2 * len(fc.keyframe_points))
    fc.keyframe_points.foreach_get("co", co)
    return co[0::2], co[1::2]


def turns_panel_labels(context) -> list:
    calls = []
    cls = panel.VIEW3D_PT_turning_controller
    mixins = tuple(b for b in cls.__mro__[1:] if b.__module__ == panel.__name__)
    cls.draw(type("P", mixins, {"layout": LayoutStub(calls)})(), context)
    return [kw.get("text", "") for name, _, kw in calls if name == "label"]


# -- the lean -------------------------------------------------------------------------------------

@pytest.mark.installed
def test_bake_and_panel_say_the_lean_the_bounds_allow_and_why(scene, capfd):
    """The telemark's 23 deg is more than its Max Curvature allows at a 2 s period."""
    tele = add("TELEMARK")
    assert math.degrees(tele.turning.lean) == pytest.approx(23.0)
    text = turns_panel_labels(bpy.context)
    at = text.index("Leans 19.6\u00b0, not 23.0\u00b0: limited by Max Curvature")
    assert text[at + 1] == "in the room Hold Heading keeps to steer"
    assert len([t for t in text if t.startswith("Leans")]) == 1, text
    capfd.readouterr()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    out = capfd.readouterr().out
    found = LEAN.findall(out)
    assert len(found) == 1, out
    name, lean, asked, bound, room = found[0]
    # Hold Heading: the half-turn flattened to 0.8 (faster, so it asks more curvature) is at
    # Max Curvature (the turn itself would lean 20.02 deg).
    assert (name, float(asked), bound) == ("Telemark", 23.0, "C_f_max")
    assert room == " of the half-turn flattened to 0.8 (heading control's room)"
    assert "Max Curvature" in out.split("Warning: Bake Turns")[1]
    # What was said is what was baked: the keyed lean peaks at the reported value (printed to
    # 0.01 deg) within the frames' sampling of the apex: a frame at most half a frame from it
    # at 24 fps and a 2 s period is below the peak by up to theta (1 - cos(pi / 48)) = 0.04 deg
    # (measured peak 19.610 deg for the report's 19.62).
    _, baked = keyed(tele, '["turn_lean"]')
    assert math.degrees(np.abs(baked).max()) == pytest.approx(float(lean), abs=0.05)
    assert float(lean) < 23.0 - 3.0                    # a real difference, worth the warning


@pytest.mark.parametrize("sport", ["SKIER", "CYCLIST"])
def test_a_lean_as_asked_is_not_remarked(scene, capfd, sport):
    obj = add(sport)
    assert not [t for t in turns_panel_labels(bpy.context) if t.startswith("Leans")]
    capfd.readouterr()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert "Warning" not in capfd.readouterr().out
    _, baked = keyed(obj, '["turn_lean"]')       # measured 22.9995 and 22.9898 deg
    assert math.degrees(np.abs(baked).max()) == pytest.approx(23.0, abs=0.02)


def test_a_crowds_bake_says_each_members_limited_lean(scene, capfd):
    """Bake Turns on a crowd (Add Crowd of a telemark whose 23 deg its bounds hold to about
    19.6 deg) warns for every member with its own lean reached and the bound; none is left
    out (each member is its own run, its period jittered)."""
    add("TELEMARK")
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=3, gap_time=1.0,
                                     period_jitter=0.05, seed=3) == {"FINISHED"}
    figs = {o.name for o in bpy.context.selected_objects if o.type == "ARMATURE"}
    assert len(figs) == 4
    capfd.readouterr()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    said = {m.group(1): m for m in re.finditer(
        r"Warning: Bake Turns: ([^:]+): lean ([\d.]+) deg at period [\d.]+ s \(asked ([\d.]+) "
        r"deg; limited by", capfd.readouterr().out)}
    assert set(said) == figs
    for m in said.values():
        assert float(m.group(3)) == pytest.approx(23.0) and 17.0 < float(m.group(2)) < 22.0


def test_bake_says_the_tyre_s_grip_held_the_lean(scene, capfd):
    """The cyclist's 50 deg is more than dry asphalt's grip (mu 0.9) holds: Bake Turns says so
    in the command line's words (the core's ``grip_limited``), and the baked lean is the
    grip's 42.0 deg."""
    obj = add("CYCLIST")
    obj.turning.period, obj.turning.lean = 4.0, math.radians(50.0)
    capfd.readouterr()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    out = capfd.readouterr().out
    assert ("Warning: Bake Turns: Cyclist: the lean asked (50.0 deg at t = 0 s) is more than "
            "the tyre's grip holds (mu 0.9): limited to 42.0 deg") in out, out
    _, baked = keyed(obj, '["turn_lean"]')
    assert math.degrees(np.abs(baked).max()) == pytest.approx(42.0, abs=0.2)


def test_the_note_says_the_leans_reached_over_the_run():
    """A run whose lean followed changes (the slalom racer gathering speed down 19 deg) is noted
    with the leans reached and from when, as the command line says it."""
    from blender_turning.blender.jobs import model_notes
    from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start
    from blender_turning.core.ground.terrain import Plane
    fig = preset("slalom_racer")
    ctl = PhaseEllipse(fig.body, math.pi, math.radians(70.0), -math.pi / 2, limits=fig.limits)
    w, tm = ctl.target(0.0)
    tr = simulate(fig, ctl, 6.0, state0=slalom_start(fig.body, w, tm, -math.pi / 2),
                  ground=Plane(math.radians(19), -math.pi / 2))
    note = model_notes.turn_note(model_notes.with_turn(tr, ctl))
    assert note == (f"{ctl.report.describe()}: a longer Turn Period or a higher Limits > Max "
                    "Curvature leans further")
    assert note.startswith("lean 61.77-70.00 deg over the run: ") and "(as asked) from" in note


def test_a_lean_past_the_fall_angle_is_refused_as_on_the_command_line(scene):
    """Lean 65 deg (the property goes to the racers' 85): the skier's range is the command
    line's (core/ranges.py ``lean_range``), named with the value, the frame and the reason, and
    nothing is baked; the slalom racer bakes it."""
    from scene_snapshot import snapshot
    obj = add("SKIER")
    obj.turning.lean = math.radians(65.0)
    before = snapshot()
    with pytest.raises(RuntimeError, match=r"Lean \(turning.lean\) = 65 deg at frame 1 is "
                       r"outside the allowed range \[1, 60\) deg: the skier's fall angle "
                       r"theta_fall \(Limits > Fall Angle\) is 60 deg"):
        bpy.ops.turning.bake_turns()
    assert snapshot() == before
    assert bpy.ops.turning.apply_figure_preset(sport="SLALOM_RACER") == {"FINISHED"}
    obj.turning.lean = math.radians(65.0)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}


# -- the path -------------------------------------------------------------------------------------

def farthest(obj):
    """``(distance, frame, along)`` of the baked foot track farthest from the figure's curve,
    measured here on 512 samples per segment (not the core's exact distance)."""
    frames, x = keyed(obj, "location")
    pts = obj.turning.foot_track.data.splines[0].points
    co = np.empty(4 * len(pts))
    pts.foreach_get("co", co)
    xy = co.reshape(-1, 4)[:, :2]
    curve = HermitePath.from_bezier(scene_adapters.bezier_control_points(obj.turning.path))
    s = curve.sample(512)
    d = np.linalg.norm(xy[:, None, :] - s[None, :, :], axis=2)
    k = int(np.argmax(d.min(axis=1)))
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(s, axis=0), axis=1))])
    return float(d[k].min()), int(frames[0]) + k, float(arc[int(np.argmin(d[k]))])


def reported(out, name):
    found = [m for m in FAR.findall(out) if m[1] == name]
    assert len(found) == 1, out
    level, _, dist, frame, along = found[0]
    return level, float(dist), int(frame), float(along)


def test_follow_path_says_how_far_it_cut_a_corner_and_warns(scene, capfd):
    scene.frame_start = 11                           # frames are counted from the scene's start
    obj = add("TELEMARK")
    obj.turning.path = make_path([(0, 0), (0, -25), (25, -25)])      # a right-angle corner
    capfd.readouterr()
    assert bpy.ops.turning.follow_path() == {"FINISHED"}
    out = capfd.readouterr().out
    level, dist, frame, along = reported(out, "Telemark")
    want, at, where = farthest(obj)
    assert level == "Warning" and "more than 3 m" in out
    # The report is from the planner's 50 Hz run, the track is at 24 fps: the two maxima are a
    # sample apart at most (measured 6.6 m reported, 0.03 m and one frame apart), and the
    # report prints 0.1 m and 1 m.
    assert dist == pytest.approx(want, abs=0.1) and want > 5.0
    assert abs(frame - at) <= 1 and along == pytest.approx(where, abs=1.0)
    # Above Warn Beyond only: the same run with a wider margin is said, not warned about.
    bpy.ops.turning.clear_bake()
    capfd.readouterr()
    assert bpy.ops.turning.follow_path(warn_distance=10.0) == {"FINISHED"}
    level, dist2, _, _ = reported(capfd.readouterr().out, "Telemark")
    assert level == "Info" and dist2 == dist


def test_follow_path_on_several_figures_says_each_ones_distance(scene, capfd):
    figs = []
    for i, pts in enumerate(([(0, 0), (3, -12), (-3, -24), (0, -36)],
                             [(10, 0), (10, -25), (35, -25)])):
        fig = add("TELEMARK", at=(pts[0][0], 0.0, 0.0))
        fig.turning.path = make_path(pts, f"Path{i}")
        figs.append(fig)
    for fig in figs:
        fig.select_set(True)
    capfd.readouterr()
    assert bpy.ops.turning.follow_path(avoid=False) == {"FINISHED"}
    out = capfd.readouterr().out
    levels = []
    for fig in figs:
        level, dist, frame, _ = reported(out, fig.name)
        want, at, _ = farthest(fig)
        assert dist == pytest.approx(want, abs=0.1) and abs(frame - at) <= 1
        levels.append(level)
    assert levels == ["Info", "Warning"]       # the slalom is followed, the corner is cut


@pytest.mark.installed
def test_a_fall_names_the_setting_that_holds_each_bound(scene):
    """A figure that falls with its curvature held at a bound: the report names the bound as the
    core does (the scene files' key) and the setting the panels show for it."""
    from types import SimpleNamespace
    from blender_turning.blender.props.figure import TurningFigureSettings
    from blender_turning.blender.scene.figure_context import BOUND_SETTING, report_error
    from blender_turning.core.controllers.feasible import fall_cause
    from blender_turning.core.errors import FellOver
    from blender_turning.core.physics.params import Limits
    lim = Limits(C_f_max=0.5, dC_f_max=0.8)
    t = np.linspace(0.0, 1.0, 51)
    C_f = np.minimum(0.8 * t, 0.5)                     # the rate bound, then the curvature bound
    reports = []
    op = SimpleNamespace(report=lambda kind, text: reports.append((kind, text)))
    exc = FellOver(1.0, math.radians(61), cause=fall_cause(lim, C_f, t))
    assert report_error(op, "Bake Turns", "Skier", exc) == {"CANCELLED"}
    (kind, text), = reports
    assert kind == {"ERROR"}
    assert "C_f_max (Limits > Max Curvature) = 0.5 1/m" in text, text
    assert "dC_f_max (Limits > Max Curvature Rate) = 0.8 1/(m s)" in text, text
    # The settings named are the panels' labels.
    rna = TurningFigureSettings.bl_rna.properties
    labels = {"C_f_max": rna["curvature_max"].name, "dC_f_max": rna["curvature_rate_max"].name,
              "theta_fall": rna["fall_angle"].name, "physical branch": rna["com_height"].name}
    for bound, setting in BOUND_SETTING.items():
        assert labels[bound].startswith(setting.rpartition(" > ")[2]), (bound, labels[bound])

"""Speed control in Blender (docs/skidding.md): the Speed Control panel's settings (Target Speed,
keyable; Style; Snow; Grip; Stop at a frame) reach the bake's simulation, Follow Path brakes to
the Target Speed, a style the sport has not is refused; on the bpy wheel."""
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender.jobs import pipeline  # noqa: E402
from blender_turning.blender.scene import follow_ground  # noqa: E402
from blender_turning.blender.scene.scene_adapters import (FrameRange, SceneInputError,  # noqa: E402
                                                    figure_from_settings,
                                                    skidding_from_settings)
from blender_turning.core.physics.grip import SNOW  # noqa: E402

from mountain_scene import mountain_scene  # noqa: E402

pytestmark = pytest.mark.blender
SECONDS, FPS = 8, 24


@pytest.fixture(scope="module")
def scene():
    yield from mountain_scene(SECONDS, FPS, length=200)


def _figure(scene, sport="SKIER"):
    sc, mountain = scene
    sc.cursor.location = (0.0, 80.0, 0.0)
    sc.cursor.rotation_euler = (0.0, 0.0, np.radians(-180.0))      # heading -90 deg: downhill
    bpy.ops.turning.add_figure(sport=sport)
    fig = bpy.context.view_layer.objects.active
    fig.turning.ground = mountain
    fig.turning.use_heading = True
    return fig


def _run(fig):
    return pipeline.simulate_figure(fig, FrameRange.of_scene(bpy.context.scene))


def test_the_speed_control_panel_is_there(scene):
    assert hasattr(bpy.types, "VIEW3D_PT_turning_speed")
    fig = _figure(scene)
    k = fig.turning.skid
    assert (k.style, k.snow, k.use_stop) == ("CARVE", "HARD", False)
    assert fig.turning.terrain.bl_rna.properties["target_speed"].is_animatable
    assert skidding_from_settings(fig, FrameRange.of_scene(bpy.context.scene)) is None


def test_skidding_brakes_where_carving_cannot(scene):
    fig = _figure(scene)
    fig.turning.terrain.target_speed = 8.0
    carved = _run(fig)
    fig.turning.skid.style = "SKID"
    skidded = _run(fig)
    assert np.all(carved.brake == 0.0)
    assert skidded.brake.max() > 1.0 and np.abs(skidded.skid).max() > 0.2
    late = skidded.t >= SECONDS / 2
    assert skidded.V_cm[late].mean() < carved.V_cm[late].mean() - 0.5


@pytest.mark.installed
@pytest.mark.parametrize("snow", ["HARD", "SOFT", "RACE"])
def test_the_snow_menu_is_the_cores_snow(scene, snow):
    """Each Snow item is the core's grip of that name (docs/skidding.md, Section 1)."""
    fig = _figure(scene)
    fig.turning.skid.style = "SKID"
    fig.turning.skid.snow = snow
    got = skidding_from_settings(fig, FrameRange.of_scene(bpy.context.scene))
    assert got.grip == SNOW[snow.lower()]


def test_a_keyed_target_speed_is_followed(scene):
    fig = _figure(scene)
    fig.turning.skid.style = "SKID"
    t = fig.turning.terrain
    t.target_speed = 12.0
    t.keyframe_insert("target_speed", frame=1)
    t.target_speed = 6.0
    t.keyframe_insert("target_speed", frame=1 + 5 * FPS)
    traj = _run(fig)
    assert traj.V_cm[-1] < 8.0 < traj.V_cm[(traj.t > 3.0) & (traj.t < 5.0)].max()


def test_a_stop_at_a_frame(scene):
    fig = _figure(scene)
    k = fig.turning.skid
    k.use_stop, k.stop_frame = True, 1 + 3 * FPS
    traj = _run(fig)
    assert traj.V_cm[-1] == 0.0 and traj.V_cm[traj.t < 3.0].min() > 5.0
    k.stop_frame = 10 ** 6
    with pytest.raises(SceneInputError, match="Stop Frame"):
        _run(fig)


def test_a_style_the_sport_has_not_is_refused(scene):
    fig = _figure(scene, "SNOWBOARDER")
    fig.turning.skid.style = "WEDGE"
    with pytest.raises(SceneInputError, match="Style Wedge.*snowboarder has: Carve, Skid, Slip"):
        _run(fig)
    with pytest.raises(RuntimeError, match="Style Wedge"):        # reported, cancelled
        bpy.ops.turning.bake_turns()
    assert not (fig.animation_data and fig.animation_data.action)


def test_follow_path_brakes_to_the_target_speed(scene):
    fig = _figure(scene)
    fig.turning.terrain.target_speed = 9.0
    depsgraph = bpy.context.evaluated_depsgraph_get()
    figure = figure_from_settings(fig.turning)
    _, ground, terrain = follow_ground.plan_inputs(bpy.context, fig, figure, depsgraph)
    assert ground is not None and terrain["speed_cap"].speed == 9.0
    assert terrain["speed_cap"].grip.name == "hard"
    assert "braking to at most 9 m/s" in follow_ground.target_speed_note(fig)
    fig.turning.terrain.target_speed = 0.0
    assert "speed_cap" not in follow_ground.plan_inputs(bpy.context, fig, figure, depsgraph)[2]


def test_the_beginner_preset_sets_its_wedge_and_speed(scene):
    """The beginner's and the recreational skier's presets set the Speed Control's Style and
    Target Speed (core/controllers/speed_habits.py); a sport's own preset leaves them."""
    fig = _figure(scene)
    assert bpy.ops.turning.apply_figure_preset(sport="BEGINNER") == {"FINISHED"}
    assert (fig.turning.skid.style, fig.turning.terrain.target_speed) == ("WEDGE", 4.5)
    assert fig.turning.equipment.preset == "beginner"
    assert bpy.ops.turning.apply_figure_preset(sport="RECREATIONAL") == {"FINISHED"}
    assert (fig.turning.skid.style, fig.turning.terrain.target_speed) == ("SKID", 10.5)
    assert bpy.ops.turning.apply_figure_preset(sport="SKIER") == {"FINISHED"}
    assert (fig.turning.skid.style, fig.turning.terrain.target_speed) == ("SKID", 10.5)


def test_a_skidded_track_is_a_brushed_band(scene):
    """The render job's snow track (blender/render/terrain.py) follows the baked turn_skid:
    a band ``ski length |sin skid|`` wide where the figure skids, two grooves where it carves."""
    from blender_turning.blender.anim import bake
    from blender_turning.blender.render import build, terrain
    sc, mountain = scene
    widths = {}
    for style in ("CARVE", "SKID"):
        fig = _figure(scene)
        fig.turning.terrain.target_speed = 8.0
        fig.turning.skid.style = style
        assert bpy.ops.turning.bake_turns() == {"FINISHED"}
        frames = range(sc.frame_start, sc.frame_end + 1)
        track = terrain.make_tracks(bpy, fig, mountain, build._material, frames)
        v = np.array([vert.co[:] for vert in track.data.vertices])
        n = len(frames)
        # The ribbons' outer edges: the first offset's left edge, the last one's right edge.
        widths[style] = np.linalg.norm(v[3 * n:4 * n, :2] - v[:n, :2], axis=1)
        fc = next(fc for fc in bake.baked_channels(fig).fcurves
                  if fc.data_path == '["turn_skid"]')
        widths[style + " skid"] = np.array([fc.evaluate(f) for f in frames])
    assert widths["CARVE"].max() < 0.35                          # 2 x 0.11 + 2 x 0.045
    big = np.abs(widths["SKID skid"]) > np.radians(20)
    assert big.sum() > 5
    # Both skis' bands: 0.22 m apart, each 1.65 |sin skid| wide (the draping adds round-off).
    want = 0.22 + 1.65 * np.abs(np.sin(widths["SKID skid"][big]))
    np.testing.assert_allclose(widths["SKID"][big], want, rtol=0.02)

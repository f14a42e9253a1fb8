"""An export-ready bake, checked by exporting with Blender's own glTF and FBX exporters (their
default settings) and importing the files back with its importers: a user rig's equipment moves
with it, and one figure's file holds that figure's animation only."""
import importlib
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")
import addon_utils  # noqa: E402

import installed_addon  # noqa: E402
from rig_fixtures import activate, mixamo_skeleton, rigify_rig  # noqa: E402
from test_blender_operators import add  # noqa: E402

from blender_turning.blender import compat  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]
FRAMES = (1, 9, 17, 24)
FORMATS = ("glb", "fbx")
#: FBX with the bake on its own NLA layer (docs/layers.md): the exporter's defaults write the
#: bake's strip, the bake's action and the tweak layer as three takes, and the takes it re-imports
#: first are not the baked one: a known gap (docs/export.md), recorded so it turns red when fixed.
FBX_TAKES = pytest.mark.xfail(strict=True, reason="FBX writes the bake's NLA strip, its action "
                              "and the tweak layer as separate takes")
FORMATS_LAYERED = ("glb", pytest.param("fbx", marks=FBX_TAKES))
GLTF_HOOK = "blender_turning.blender.anim.export_gltf"
TOLERANCE = {"glb": 1e-5, "fbx": 1e-3}         # m, see the measurements where they are used


@pytest.fixture
def scene(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, 24
    sc.render.fps = 24
    for mod in ("io_scene_gltf2", "io_scene_fbx"):
        addon_utils.enable(mod, default_set=True)
    yield sc
    addons = bpy.context.preferences.addons
    if GLTF_HOOK in addons:
        addons.remove(addons[GLTF_HOOK])


def listed_as_addon():
    """The glTF exporter asks each enabled add-on's module for its user extension; from the
    checkout the add-on is registered, not enabled: list the module that offers it (again after
    each factory reset, which forgets it)."""
    if not installed_addon.ACTIVE and GLTF_HOOK not in bpy.context.preferences.addons:
        importlib.import_module(GLTF_HOOK)          # the exporter looks in sys.modules
        bpy.context.preferences.addons.new().module = GLTF_HOOK


def world(objs) -> np.ndarray:
    """``(frames, objects, 3)`` world positions of ``objs`` as evaluated on ``FRAMES``."""
    sc = bpy.context.scene
    out = []
    for f in FRAMES:
        sc.frame_set(f)
        out.append([tuple(o.matrix_world.translation) for o in objs])
    sc.frame_set(1)
    return np.array(out)


def export(path, objs):
    listed_as_addon()
    bpy.ops.object.select_all(action="DESELECT")
    for o in objs:
        o.select_set(True)
    if path.endswith(".fbx"):
        assert bpy.ops.export_scene.fbx(filepath=path, use_selection=True) == {"FINISHED"}
    else:
        assert bpy.ops.export_scene.gltf(filepath=path, use_selection=True) == {"FINISHED"}


def reimport(path):
    """A new empty file with ``path`` imported (Blender's importers, default settings)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    for mod in ("io_scene_gltf2", "io_scene_fbx"):
        addon_utils.enable(mod, default_set=True)
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = 1, 24
    if path.endswith(".fbx"):
        assert bpy.ops.import_scene.fbx(filepath=path) == {"FINISHED"}
    else:
        assert bpy.ops.import_scene.gltf(filepath=path) == {"FINISHED"}


@pytest.mark.installed
@pytest.mark.parametrize("fmt", FORMATS_LAYERED)
def test_a_user_rigs_equipment_rides_along_in_the_file(scene, tmp_path, fmt):
    rig = mixamo_skeleton("Ann")
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    gear = list(rig.turning.rig.equipment.objects)
    names = [o.name for o in gear]
    assert len(gear) == 4
    assert bpy.ops.turning.bake_turns(export_ready=False) == {"FINISHED"}
    live = world(gear)                                 # the constraints place it
    assert not any(o.animation_data and o.animation_data.action for o in gear)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}            # on by default
    keyed = world(gear)
    assert all(not c.enabled for o in gear for c in o.constraints)
    # The keys are what the constraints made, frame by frame (float32 keys: measured 4e-7 m).
    np.testing.assert_allclose(keyed, live, atol=1e-5)
    assert np.linalg.norm(keyed[-1] - keyed[0], axis=1).min() > 5.0    # it rides 9.5 m
    path = str(tmp_path / f"ann.{fmt}")
    export(path, [rig, *gear])
    reimport(path)
    back = world([bpy.data.objects[n] for n in names])
    # glTF: the keys' float32 values (measured 0 m); FBX: curves its exporter simplifies by default
    # (simplify factor 1; measured 3.7e-4 m).
    np.testing.assert_allclose(back, keyed, atol=TOLERANCE[fmt])


@pytest.mark.installed
@pytest.mark.parametrize("fmt", FORMATS_LAYERED)
def test_one_figure_exports_its_own_animation_only(scene, tmp_path, fmt):
    first = add("SKIER", at=(0, 0, 0))
    first.turning.period = 2.5
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    other = add("SKIER", at=(5, 0, 0))                 # the same bones: its bake fits the first
    other.turning.period = 1.5
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    want = world([first])
    path = str(tmp_path / f"skier.{fmt}")
    export(path, [first, *first.children_recursive])
    reimport(path)
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    bone_actions = [a for a in bpy.data.actions
                    if any(fc.data_path.startswith("pose.bones") for fc in compat.all_fcurves(a))]
    assert len(bone_actions) == 1, [a.name for a in bpy.data.actions]
    assert arm.animation_data.action == bone_actions[0]
    # (measured 0 m in both formats)
    np.testing.assert_allclose(world([arm]), want, atol=TOLERANCE[fmt])


def test_clear_bake_gives_the_equipment_back_to_its_constraints(scene):
    rig = mixamo_skeleton("Ann")
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    gear = list(rig.turning.rig.equipment.objects)
    modes = [o.rotation_mode for o in gear]
    before = np.array([o.matrix_basis for o in gear])
    actions = len(bpy.data.actions)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}        # a re-bake keys them afresh
    assert len(bpy.data.actions) == actions + 2 + len(gear)     # the bake, its tweak layer
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert len(bpy.data.actions) == actions
    assert [o.rotation_mode for o in gear] == modes
    # Given back through its Euler angles and float32 properties: measured 1.2e-7.
    np.testing.assert_allclose(np.array([o.matrix_basis for o in gear]), before, atol=1e-6)
    assert all(c.enabled for o in gear for c in o.constraints)
    assert not [p for o in [rig, *gear] for p in o.keys() if p.startswith("turn_take")]
    from blender_turning.blender.anim.export_ready import KEYED
    assert not any(KEYED in o for o in gear)


def bone_world(fig) -> np.ndarray:
    """``(frames, bones, 4, 4)`` world matrices of every pose bone on ``FRAMES``."""
    sc = bpy.context.scene
    out = []
    for f in FRAMES:
        sc.frame_set(f)
        out.append([np.array(fig.matrix_world @ pb.matrix) for pb in fig.pose.bones])
    sc.frame_set(1)
    return np.array(out)


@pytest.mark.parametrize("fmt", FORMATS)
def test_root_motion_moves_the_root_bone_and_keeps_every_bone_in_place(scene, tmp_path, fmt):
    fig = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    want = bone_world(fig)
    assert bpy.ops.turning.bake_turns(root_motion=True) == {"FINISHED"}
    got = bone_world(fig)
    # float32 keys of a root 0-9.5 m away (measured 9.5e-7 m, 2.4e-7 in rotation)
    np.testing.assert_allclose(got, want, atol=1e-5)
    locs = np.array(world([fig]))[:, 0]
    assert np.ptp(locs, axis=0).max() == 0.0                 # the object stays
    root = fig.pose.bones.find("root")
    travel = np.linalg.norm(got[-1, root, :3, 3] - got[0, root, :3, 3])
    assert travel > 5.0
    path = str(tmp_path / f"root.{fmt}")
    export(path, [fig, *fig.children_recursive])
    reimport(path)
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    back = bone_world(arm)[:, arm.pose.bones.find("root"), :3, 3]
    assert np.ptp(np.array(world([arm]))[:, 0], axis=0).max() < 1e-6
    # measured 1.9e-6 m (glTF), 4.1e-7 m (FBX)
    np.testing.assert_allclose(back, got[:, root, :3, 3], atol=1e-5)


def test_root_motion_on_a_rig_without_a_root_is_refused(scene):
    from scene_snapshot import diff, snapshot
    rig = mixamo_skeleton("Ann")
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    before = snapshot()
    with pytest.raises(RuntimeError, match="no bone 'root' to carry the root motion"):
        bpy.ops.turning.bake_turns(root_motion=True)
    assert snapshot() == before, diff(before, snapshot())


def test_root_motion_on_rigifys_root_control(scene):
    """Rigify's ``root`` control carries the travel; the deforming bones (the ones a game
    engine skins with) stay where the object-level bake puts them, as do the equipment."""
    rig = rigify_rig("Rob")
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    deform = [i for i, pb in enumerate(rig.pose.bones) if pb.bone.use_deform]
    gear = list(rig.turning.rig.equipment.objects)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    want, want_gear = bone_world(rig)[:, deform], world(gear)
    assert bpy.ops.turning.bake_turns(root_motion=True) == {"FINISHED"}
    got = bone_world(rig)
    assert np.ptp(np.array(world([rig]))[:, 0], axis=0).max() == 0.0
    root = rig.pose.bones.find("root")
    assert np.linalg.norm(got[-1, root, :3, 3] - got[0, root, :3, 3]) > 5.0
    # float32 keys through Rigify's IK chains (measured 9.5e-6 m, the equipment 4.8e-6 m)
    np.testing.assert_allclose(got[:, deform][..., :3, 3], want[..., :3, 3], atol=1e-4)
    np.testing.assert_allclose(world(gear), want_gear, atol=1e-4)

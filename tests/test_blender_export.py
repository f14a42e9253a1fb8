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
from blender_turning.blender.anim import bake  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]
FRAMES = (1, 9, 17, 24)
FORMATS = ("glb", "fbx")
GLTF_HOOK = "blender_turning.blender.anim.export_gltf"
TOLERANCE = {"glb": 1e-5, "fbx": 1e-3}         # m, see the measurements where they are used
ANGLE = {"glb": 1e-5, "fbx": 1e-2}             # rad, likewise
RELATIVE = {"glb": 1e-6, "fbx": 4e-3}          # of a value's magnitude, likewise


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


def export(path, objs, with_tweaks=False):
    """Export ``objs`` with Blender's exporter at its defaults; ``with_tweaks``: FBX through
    Export FBX with Tweaks."""
    listed_as_addon()
    bpy.ops.object.select_all(action="DESELECT")
    for o in objs:
        o.select_set(True)
    if path.endswith(".fbx") and with_tweaks:
        assert bpy.ops.turning.export_fbx(filepath=path, use_selection=True) == {"FINISHED"}
    elif path.endswith(".fbx"):
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


def world_matrices(objs) -> np.ndarray:
    """``(frames, objects, 4, 4)`` world matrices of ``objs`` as evaluated on ``FRAMES``."""
    sc = bpy.context.scene
    out = []
    for f in FRAMES:
        sc.frame_set(f)
        out.append([np.array(o.matrix_world) for o in objs])
    sc.frame_set(1)
    return np.array(out)


def takes_of(obj) -> list:
    """The actions an FBX import made for ``obj`` (``<object>|<take>``), the one it plays first."""
    own = [a for a in bpy.data.actions if a.name.split("|")[0] == obj.name]
    return sorted(own, key=lambda a: a != obj.animation_data.action)


def play(obj, action) -> None:
    obj.animation_data.action = action
    if compat.SLOTTED_ACTIONS:
        obj.animation_data.action_slot = action.slots[0]


# In a process of its own: on bpy 4.2 the glTF and FBX exports and imports of the tests run after
# Rigify generated a rig in the same process crashed in 9 of 23 runs of this file.
@pytest.mark.own_process
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


@pytest.mark.installed
@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("sport, pieces", [("SKIER", 4), ("CYCLIST", 9)])
def test_a_user_rigs_equipment_rides_along_in_the_file(scene, tmp_path, fmt, sport, pieces):
    """The file carries the equipment as its constraints and drivers move it (the wheels roll,
    the crank faces its pedal), in the take an importer plays first: FBX's take of the bake's
    NLA strip holds the figure and every piece."""
    rig = mixamo_skeleton("Ann")
    activate(rig)
    assert bpy.ops.turning.make_figure(sport=sport) == {"FINISHED"}
    gear = list(rig.turning.rig.equipment.objects)
    names = [o.name for o in gear]
    assert len(gear) == pieces
    assert bpy.ops.turning.bake_turns(export_ready=False) == {"FINISHED"}
    live = world_matrices(gear)                        # the constraints and drivers place it
    assert not any(o.animation_data and o.animation_data.action for o in gear)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}            # on by default
    keyed = world_matrices(gear)
    assert all(o.animation_data.action for o in gear)
    assert all(c.enabled for o in gear for c in o.constraints)      # they still place it
    # The keys hold each piece's transform under its constraints: the same evaluation (0 m).
    np.testing.assert_allclose(keyed, live, atol=1e-6)
    travel = np.linalg.norm(keyed[-1, :, :3, 3] - keyed[0, :, :3, 3], axis=1)
    assert travel.min() > 5.0                                       # it rides 6-9.5 m
    path = str(tmp_path / f"ann.{fmt}")
    export(path, [rig, *gear])
    reimport(path)
    objs = [bpy.data.objects[n] for n in names]
    takes = [(world_matrices(objs), keyed)]
    if fmt == "fbx":                  # every take that moves a piece: the bake's, the piece's own
        for j, obj in enumerate(objs):
            for action in takes_of(obj)[1:]:
                play(obj, action)
                takes.append((world_matrices([obj]), keyed[:, [j]]))
    for back, want in takes:
        pos, turn = off_by(back, want)
        # float32 positions up to 10 m (measured 5.3e-7 m); the turn: float32 (3.9e-7 rad) in
        # glTF, FBX's default curve simplification (factor 1: 3.8e-3 rad, 5.3e-7 without it)
        assert pos < 1e-5 and turn < ANGLE[fmt], (pos, turn)


def off_by(got, want) -> tuple:
    """The largest distance (m) and angle (rad) between ``(..., 4, 4)`` world matrices."""
    got, want = np.asarray(got, float), np.asarray(want, float)
    pos = np.linalg.norm(got[..., :3, 3] - want[..., :3, 3], axis=-1).max()
    rot = [m[..., :3, :3] / np.linalg.norm(m[..., :3, :3], axis=-2, keepdims=True)
           for m in (got, want)]
    chord = np.linalg.norm(rot[0] - rot[1], axis=(-2, -1))     # 2 sqrt(2) sin(angle / 2)
    return float(pos), float(2.0 * np.arcsin(np.clip(chord / np.sqrt(8.0), 0.0, 1.0)).max())


@pytest.mark.installed
@pytest.mark.parametrize("fmt", FORMATS)
def test_one_figure_exports_its_own_animation_only(scene, tmp_path, fmt):
    """Every animation in the file plays the exported figure: glTF holds one; FBX the take of the
    bake's NLA strip (first, the one an importer plays) and the tweak layer's (the figure as it
    plays with its tweaks; 4.2 also plays it under each empty tweak layer of the file), never the
    bake's action over itself or another figure's bake."""
    first = add("SKIER", at=(0, 0, 0))
    first.turning.period = 2.5
    first["turn_take Skier"] = 0.0                # as a bake made it before it was key-only
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert "turn_take Skier" not in first
    other = add("SKIER", at=(5, 0, 0))                 # the same bones: its bake fits the first
    other.turning.period = 1.5
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    want, name, bones = bone_world(first), first.name, [pb.name for pb in first.pose.bones]
    path = str(tmp_path / f"skier.{fmt}")
    export(path, [first, *first.children_recursive])
    reimport(path)
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    bone_actions = [a for a in bpy.data.actions
                    if any(fc.data_path.startswith("pose.bones") for fc in compat.all_fcurves(a))]
    assert arm.animation_data.action in bone_actions
    if fmt == "glb":
        assert len(bone_actions) == 1, [a.name for a in bpy.data.actions]
    else:
        assert arm.animation_data.action.name == f"{arm.name}|{name}"     # the NLA strip's
        assert f"{arm.name}|{name}|{name} Tweaks" in bpy.data.actions
    same = [arm.pose.bones.find(b) for b in bones]     # FBX adds a leaf bone to each chain
    for action in sorted(bone_actions, key=lambda a: a != arm.animation_data.action):
        play(arm, action)
        got = bone_world(arm)[:, same][..., :3, 3]
        # float32 positions up to 10 m (measured 9.5e-7 m both formats; 0.75 m apart from the
        # other figure's motion on these frames, 9.4 m for a take of one frame)
        np.testing.assert_allclose(got, want[..., :3, 3], atol=1e-5, err_msg=action.name)


# The take an importer plays against the pose Blender shows: float32 bones, 1e-5 m and 1e-4 rad
# (measured 2.5e-6 m, 4.0e-6 rad in glTF, 1.4e-6 m, 2.2e-6 rad in FBX without its curve
# simplification, bpy 5.0 and 4.2); FBX's default simplification drops a sample within 0.1 % of
# its neighbours' summed magnitudes, of Euler angles up to pi here: 1e-2 rad, and 5e-3 m at the
# end of the 0.5 m from neck to head (measured 2.1e-3 rad, 8.1e-4 m).  A tweak lost: 0.44 rad.
@pytest.mark.installed
@pytest.mark.parametrize("fmt, simplify, pos_tol, turn_tol", [
    ("glb", None, 1e-5, 1e-4), ("fbx", 0.0, 1e-5, 1e-4), ("fbx", None, 5e-3, 1e-2)])
def test_the_animators_tweaks_play_in_the_file(scene, tmp_path, fmt, simplify, pos_tol,
                                               turn_tol):
    """The take an importer plays is the bake with the tweak layer above it: glTF at the
    exporter's defaults, FBX through Export FBX with Tweaks (the FBX exporter at its defaults,
    or with its curve simplification off)."""
    from scene_snapshot import diff, snapshot
    from test_blender_layers import key_head_tweak
    fig = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    untweaked = bone_world(fig)
    key_head_tweak(fig, frame=9)                      # 25 deg on the neck, held over the shot
    other = add("SKIER", at=(5, 0, 0))                # the same bones, tweaks of its own
    other.turning.period = 1.5
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    key_head_tweak(other, frame=17)
    key_head_tweak(other, frame=24)                   # 50 deg at the end: not the first's
    want, bones = bone_world(fig), [pb.name for pb in fig.pose.bones]
    assert off_by(want, untweaked)[1] > 0.4
    path = str(tmp_path / f"tweaked.{fmt}")
    before = snapshot()
    if simplify is None:
        export(path, [fig, *fig.children_recursive], with_tweaks=True)
    else:
        for o in [other, *other.children_recursive]:
            o.select_set(False)
        for o in [fig, *fig.children_recursive]:
            o.select_set(True)
        assert bpy.ops.turning.export_fbx(filepath=path, use_selection=True,
                                          bake_anim_simplify_factor=simplify) == {"FINISHED"}
    assert snapshot() == before, diff(before, snapshot())        # the layers given back
    name = fig.name
    reimport(path)
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    # one animation, one take (the bake's strip, the bake with the tweaks): never the other's
    assert len(bpy.data.actions) == 1, [a.name for a in bpy.data.actions]
    assert fmt != "fbx" or bpy.data.actions[0].name == f"{arm.name}|{name}"
    got = bone_world(arm)[:, [arm.pose.bones.find(b) for b in bones]]
    pos, turn = off_by(got, want)
    assert pos < pos_tol and turn < turn_tol, (pos, turn)


def test_a_tweak_layer_short_of_the_bake_leaves_the_bake_whole_in_gltf(scene, tmp_path):
    """glTF samples the tweak layer over its own frame range; one that the user cut short of the
    bake's frames is left out, and the file plays the bake, every frame of it."""
    from test_blender_layers import key_head_tweak
    fig = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    want, bones = bone_world(fig), [pb.name for pb in fig.pose.bones]
    key_head_tweak(fig, frame=9)
    fig.animation_data.action.frame_end = 12
    path = str(tmp_path / "short.glb")
    export(path, [fig, *fig.children_recursive])
    reimport(path)
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    pos, turn = off_by(bone_world(arm)[:, [arm.pose.bones.find(b) for b in bones]], want)
    assert pos < 1e-5 and turn < 1e-4, (pos, turn)        # float32 bones, as above


def test_a_failed_export_with_tweaks_changes_nothing(scene, tmp_path):
    """The FBX exporter fails (a folder that does not exist) inside the flattening: the strip
    plays the bake again, the tweak layer is active again, as it was."""
    from scene_snapshot import diff, snapshot
    from test_blender_layers import key_head_tweak
    fig = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    key_head_tweak(fig, frame=9)
    bpy.context.scene.frame_set(5)
    before = snapshot()
    with pytest.raises(RuntimeError, match="Export FBX with Tweaks: .*nothing was changed"):
        bpy.ops.turning.export_fbx(filepath=str(tmp_path / "no" / "such.fbx"))
    assert snapshot() == before, diff(before, snapshot())


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


def test_follow_path_keys_the_equipment_once_over_its_frames(scene):
    """Follow Path (run twice: the second replaces the first) keys each piece once, over the
    frames it bakes, where its constraints put it."""
    from test_blender_operators import make_path
    from blender_turning.blender.anim.export_ready import clear_equipment
    rig = mixamo_skeleton("Ann")
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    gear = list(rig.turning.rig.equipment.objects)
    rig.turning.path = make_path([(0, 0), (3, -12), (-3, -24), (0, -36)])
    actions = len(bpy.data.actions)
    for _ in range(2):
        assert bpy.ops.turning.follow_path() == {"FINISHED"}
    sc = bpy.context.scene
    assert len(bpy.data.actions) == actions + 2 + len(gear)     # the bake, its tweak layer
    for obj in gear:
        assert obj.animation_data.action.name == obj.name
        frames = {k.co[0] for fc in compat.all_fcurves(obj.animation_data.action)
                  for k in fc.keyframe_points}
        assert frames == {sc.frame_start, sc.frame_end}
    shown = world_matrices(gear)
    clear_equipment(rig)
    # the same evaluation, from float32 keys of the transform (measured 1.4e-9)
    np.testing.assert_allclose(world_matrices(gear), shown, atol=1e-6)


@pytest.mark.installed
@pytest.mark.parametrize("fmt", FORMATS)
def test_the_turn_state_comes_back_on_every_frame(scene, tmp_path, fmt):
    """With Export Turn State each ``turn_*`` property is the X location of an Empty of its own
    (a child of the figure) in the file, on every frame."""
    from blender_turning.mapping.base import STATE_PROPS
    fig = add("SKIER")
    assert bpy.ops.turning.bake_turns(export_turn_state=True) == {"FINISHED"}
    sc = bpy.context.scene
    frames = range(sc.frame_start, sc.frame_end + 1)
    want = {}
    for f in frames:
        sc.frame_set(f)
        for prop in STATE_PROPS:
            want.setdefault(prop, []).append(fig[prop])
    sc.frame_set(1)
    assert np.ptp(want["turn_lean"]) > 0.1 and np.ptp(want["turn_speed"]) > 0.0
    path = str(tmp_path / f"state.{fmt}")
    export(path, [fig, *fig.children_recursive])
    name = fig.name
    reimport(path)
    sc = bpy.context.scene
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    for prop, values in want.items():
        emp = bpy.data.objects[f"{name} {prop}"]
        assert emp.parent == arm
        got = []
        for f in frames:
            sc.frame_set(f)
            got.append(emp.matrix_local.translation.copy())
        got = np.array(got)
        # float32 positions of a figure 10 m away (1e-5 m, as elsewhere) and of the value itself
        # (glTF: measured 2.7e-7 of the largest, 2.4e-4 of a leg force of 920); FBX's default
        # curve simplification drops a sample within 0.1 % of the sum of its neighbours'
        # magnitudes (io_scene_fbx, AnimationCurveNodeWrapper.simplify, factor 1): up to 0.4 %
        # (measured 1.7e-3 of the speed: 0.018 m/s of 10.3)
        tol = 1e-5 + RELATIVE[fmt] * float(np.abs(values).max())
        np.testing.assert_allclose(got[:, 0], values, atol=tol, err_msg=prop)
        np.testing.assert_allclose(got[:, 1:], 0.0, atol=tol, err_msg=prop)


def test_the_state_empties_go_with_clear_bake_and_a_bake_without_them(scene):
    from test_blender_operators import make_path
    from blender_turning.blender.anim.export_state import CARRIES, carriers
    from blender_turning.blender.ops.rig import remove_user_figure
    from blender_turning.blender.scene import crowd_scene
    rig = mixamo_skeleton("Ann")
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    path = make_path([(0, 0), (0, -30)])
    objects, actions = len(bpy.data.objects), len(bpy.data.actions)
    for _ in range(2):                                     # a rebake makes them afresh
        assert bpy.ops.turning.bake_turns(export_turn_state=True) == {"FINISHED"}
        assert sorted(o.name for o in carriers(rig)) == sorted(f"Ann {p}" for p in (
            "turn_phase", "turn_lean", "turn_curvature", "turn_leg_force", "turn_speed",
            "turn_skid"))
    assert len(bpy.data.actions) == actions + 2 + 4 + 6   # the bake, tweaks, gear, Empties
    copy = crowd_scene.duplicate_figure(rig, "Bo", rig.users_collection[0])    # Add Crowd's
    assert not [o for o in copy.children if CARRIES in o]
    remove_user_figure(copy)
    bpy.data.objects.remove(copy)
    rig.turning.path = path
    assert bpy.ops.turning.follow_path() == {"FINISHED"}          # keeps them, on its frames
    sc = bpy.context.scene
    assert len(carriers(rig)) == 6 and all(
        {k.co[0] for fc in compat.all_fcurves(o.animation_data.action)
         for k in fc.keyframe_points} == {sc.frame_start, sc.frame_end} for o in carriers(rig))
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert not carriers(rig) and len(bpy.data.actions) == actions + 2 + 4
    assert bpy.ops.turning.bake_turns(export_turn_state=True) == {"FINISHED"}
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert not carriers(rig) and len(bpy.data.actions) == actions
    assert len(bpy.data.objects) == objects


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


TOL = {"glb": (1e-5, 1e-4), "fbx": (5e-3, 1e-2), "tweaks": (1e-5, 1e-4)}


# A crowd follower playing the leader's bake (docs/crowds.md, Shared motion), strung out along
# the track (moved) or waiting at the start (moved and 6 frames later), or baked on its own
# (OWN_WAIT: waiting, Share Motion off): FBX at its defaults simplifies its curves (the tolerances
# of the tweaks' test above); glTF and FBX without simplification: float32 bones, 1e-5 m and
# 1e-4 rad.  FBX writes each strip and each action as a take from its first frame as time 0, so
# a waiting figure's bake holds its first pose from the scene's first frame (``bake.held_from``;
# before, its take came back 6 frames early, 1.8 m off).
@pytest.mark.installed
@pytest.mark.parametrize("route, who, staging", [
    ("glb", 1, "ALONG_TRACK"), ("fbx", 1, "ALONG_TRACK"), ("tweaks", 1, "ALONG_TRACK"),
    ("glb", 1, "WAIT"), ("fbx", 1, "WAIT"), ("tweaks", 1, "WAIT"),
    ("glb", 0, "WAIT"), ("fbx", 0, "WAIT"), ("fbx", 1, "OWN_WAIT"), ("glb", 1, "OWN_WAIT"),
    ("tweaks", 1, "OWN_WAIT")])
def test_a_figure_sharing_a_bake_exports_its_own_motion_only(scene, tmp_path, route, who,
                                                              staging):
    """A follower that plays the leader's bake (later, moved) exported alone, or the leader
    alone: the file's every animation plays that figure as Blender shows it (its time shift and
    its Delta Transform's translation), never the other's motion; the scene is as it was."""
    from scene_snapshot import diff, snapshot
    from test_blender_layers import key_head_tweak
    lead = add("CYCLIST")                  # waiting at the start it shares, 6 frames later
    own = staging == "OWN_WAIT"
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=1, gap_time=0.25, lateral=1.5,
                                     staging="WAIT" if own else staging) == {"FINISHED"}
    follower = bpy.data.objects["Cyclist 1"]
    select_all = [lead, follower]
    for o in select_all:
        o.select_set(True)
    assert bpy.ops.turning.bake_turns(share=not own) == {"FINISHED"}
    shared, strip = bake.shared_source(follower)
    if own:
        action, strip = bake.find_bake(follower)
        assert shared is None and action != bake.find_bake(lead)[0]
        assert strip.frame_start == 1 and min(fc.range()[0] for fc in compat.all_fcurves(
            action) if fc.data_path.startswith("pose.bones")) == 7         # held from frame 1
    else:
        assert shared == bake.find_bake(lead)[0]                            # it shares,
        assert strip.frame_start - strip.action_frame_start == (6 if staging == "WAIT" else 0)
    pos_tol, turn_tol = TOL[route]
    fig, other = select_all[who], select_all[1 - who]
    if route != "fbx":                     # FBX's first take is the bake, without tweaks
        key_head_tweak(fig, frame=9)
    want, name = bone_world(fig), fig.name
    bones = [pb.name for pb in fig.pose.bones]
    assert off_by(bone_world(other), want)[0] > 1.0            # the other's motion is elsewhere
    path = str(tmp_path / f"shared.{'glb' if route == 'glb' else 'fbx'}")
    before = snapshot()
    if route == "tweaks":                  # Export FBX with Tweaks, no curve simplification
        bpy.ops.object.select_all(action="DESELECT")
        for o in [fig, *fig.children_recursive]:
            o.select_set(True)
        assert bpy.ops.turning.export_fbx(filepath=path, use_selection=True,
                                          bake_anim_simplify_factor=0.0) == {"FINISHED"}
    else:
        export(path, [fig, *fig.children_recursive])
    assert snapshot() == before, diff(before, snapshot())
    reimport(path)
    (arm,) = [o for o in bpy.data.objects if o.type == "ARMATURE"]
    bone_actions = [a for a in bpy.data.actions
                    if any(fc.data_path.startswith("pose.bones") for fc in compat.all_fcurves(a))]
    assert arm.animation_data.action in bone_actions
    if route == "glb":
        assert len(bone_actions) == 1, [a.name for a in bpy.data.actions]
    else:
        assert arm.animation_data.action.name.startswith(f"{arm.name}|"), name
    same = [arm.pose.bones.find(b) for b in bones]
    for action in sorted(bone_actions, key=lambda a: a != arm.animation_data.action):
        play(arm, action)
        pos, turn = off_by(bone_world(arm)[:, same], want)
        assert pos < pos_tol and turn < turn_tol, (action.name, pos, turn)



def failing_gltf_export(monkeypatch):
    """Blender's glTF exporter fails after its pre-export callbacks, before the post-export ones
    (as when gathering raises): its module's ``__export`` raises."""
    try:                                                   # 4.3+
        module = importlib.import_module("io_scene_gltf2.blender.exp.export")
    except ImportError:                                    # 4.2
        module = importlib.import_module("io_scene_gltf2.blender.exp.gltf2_blender_export")

    def fail(export_settings):
        raise ValueError("the exporter fails")
    monkeypatch.setattr(module, "__export", fail)


@pytest.mark.installed
@pytest.mark.parametrize("then", ["timer", "save", "export", "load"])
def test_a_failed_gltf_export_gives_the_follower_its_shared_bake_back(scene, tmp_path,
                                                                      monkeypatch, then):
    """The glTF exporter fails after giving a sharing follower its copy: the scene is as it was
    when Blender's window runs the timer after the failed export, before a save, before the next
    export; a file loaded in between exports as it should."""
    from scene_snapshot import diff, snapshot
    from blender_turning.blender.anim import export_gltf
    lead = add("CYCLIST")
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=1, gap_time=0.25,
                                     lateral=1.5, staging="WAIT") == {"FINISHED"}
    follower = bpy.data.objects["Cyclist 1"]
    for o in (lead, follower):
        o.select_set(True)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    name, saved = follower.name, str(tmp_path / "before.blend")
    path = str(tmp_path / "shared.glb")
    # once without a failure: the exporter's own traces (it leaves the turn_* properties as it
    # sampled them, in float32) are in the scene before it
    export(path, [follower, *follower.children_recursive])
    bpy.ops.wm.save_as_mainfile(filepath=saved, copy=True)
    before = snapshot()
    with monkeypatch.context() as patch:
        failing_gltf_export(patch)
        with pytest.raises(RuntimeError, match="the exporter fails"):
            export(path, [follower, *follower.children_recursive])
    assert bake.shared_source(follower)[0] is None           # the copy plays, left by the failure
    assert bpy.context.scene.frame_current == 0      # the exporter's: it goes back after success
    bpy.context.scene.frame_set(1)
    if then == "timer":                                      # as Blender's window runs it
        assert bpy.app.timers.is_registered(export_gltf.restore_after_export)
        assert export_gltf.restore_after_export() is None    # once
    elif then == "save":
        bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "after.blend"))
        assert snapshot() == before, diff(before, snapshot())
        bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "after.blend"), load_ui=False)
    elif then == "load":
        bpy.ops.wm.open_mainfile(filepath=saved, load_ui=False)
    if then in ("export", "load"):
        follower = bpy.data.objects[name]
        export(path, [follower, *follower.children_recursive])
        assert gltf_animations(path) == [name]
    assert snapshot() == before, diff(before, snapshot())


def gltf_animations(path) -> list:
    """The names of the animations in a ``.glb`` file (its JSON chunk)."""
    import json
    import struct
    with open(path, "rb") as fh:
        data = fh.read()
    (length,) = struct.unpack_from("<I", data, 12)
    return [a.get("name") for a in json.loads(data[20:20 + length]).get("animations", [])]


@pytest.mark.installed
def test_a_user_rig_sharing_a_bake_exports_one_animation_with_its_equipment(scene, tmp_path):
    """A follower made from the user's rig plays the leader's bake: its glTF holds one animation,
    the figure with its equipment as its constraints move it, on every frame."""
    rig = mixamo_skeleton("Ann")
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=1, gap_time=0.25,
                                     lateral=1.5) == {"FINISHED"}
    bpy.ops.object.select_all(action="SELECT")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    follower = bpy.data.objects["Ann 1"]
    assert bake.shared_source(follower)[0] == bake.find_bake(rig)[0]
    gear = list(follower.turning.rig.equipment.objects)
    names, want = [o.name for o in gear], world_matrices(gear)
    from scene_snapshot import diff, snapshot
    path = str(tmp_path / "ann1.glb")
    before = snapshot()
    export(path, [follower, *gear])
    assert snapshot() == before, diff(before, snapshot())
    assert gltf_animations(path) == [follower.name]
    reimport(path)
    pos, turn = off_by(world_matrices([bpy.data.objects[n] for n in names]), want)
    assert pos < 1e-5 and turn < 1e-5, (pos, turn)    # float32, as the equipment's test above

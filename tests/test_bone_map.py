"""Bone maps as data: the shipped maps load, AUTO picks by names and says which, and a
rig lacking a required joint is refused with the whole list of what is missing."""
import pytest

from blender_turning.mapping import bones as B
from blender_turning.mapping.retarget.bone_map import (BONE_MAPS, JOINT_PARENT, JOINTS,
                                                       REQUIRED_JOINTS,
                                              MissingBoneError, auto_bone_map, load_bone_map,
                                              parse_bone_map, require_joints)

MIXAMO = ["mixamorig:" + n for n in (
    "Hips", "Spine", "Spine1", "Spine2", "Neck", "Head",
    *(s + b for s in ("Left", "Right") for b in ("Shoulder", "Arm", "ForeArm", "Hand", "UpLeg",
                                                   "Leg", "Foot", "ToeBase")))]


@pytest.mark.parametrize("name", BONE_MAPS)
def test_shipped_maps_load_and_map_every_required_joint(name):
    bm = load_bone_map(name)
    assert bm.name == name
    assert set(REQUIRED_JOINTS) <= set(bm.joints)
    assert len(set(bm.joints.values())) == len(bm.joints)


def test_joint_tree_covers_every_joint_parent_first():
    order = list(JOINTS)
    for j in JOINTS:
        p = JOINT_PARENT[j]
        assert p is None or order.index(p) < order.index(j) or p in JOINT_PARENT


def test_auto_picks_by_names():
    assert auto_bone_map(MIXAMO).name == "mixamo"
    assert auto_bone_map(B.HUMAN + ("root",)).name == "builtin"
    rigify = list(load_bone_map("rigify").joints.values()) + [
        c.bone for c in load_bone_map("rigify").controls]
    assert auto_bone_map(rigify).name == "rigify"


def test_missing_joints_are_listed_all_at_once():
    names = [n for n in MIXAMO if n not in ("mixamorig:LeftFoot", "mixamorig:Head")]
    with pytest.raises(MissingBoneError) as exc:
        require_joints(load_bone_map("mixamo"), names, "armature 'Bob'")
    msg = str(exc.value)
    assert "armature 'Bob'" in msg and "2 bone(s)" in msg
    assert "foot.L -> 'mixamorig:LeftFoot'" in msg and "spine.006 -> 'mixamorig:Head'" in msg
    with pytest.raises(MissingBoneError, match="nearest, 'mixamo', lacks 2"):
        auto_bone_map(names)
    # An optional joint (the toe) may be absent.
    require_joints(load_bone_map("mixamo"), [n for n in MIXAMO if "ToeBase" not in n])


@pytest.mark.parametrize("doc, match", [
    ({"joints": {}}, "missing key 'name'"),
    ({"name": "x", "joints": {"elbow": "a"}}, "joint 'elbow' is not one of ours"),
    ({"name": "x", "joints": {"spine": ""}}, "not a bone name"),
    ({"name": "x", "joints": {"spine": "a", "thigh.L": "a"}}, "plays both"),
    ({"name": "x", "joints": {"spine": "a"}, "controls": [{"bone": "c", "joint": "thigh.L"}]},
     "joint = 'thigh.L' is not a mapped joint"),
    ({"name": "x", "joints": {"spine": "a"}, "rig_settings": [{"bone": "b"}]}, "rig setting #0"),
    ({"name": "x", "joints": {"spine": "a"},
      "controls": [{"bone": "c", "joint": "spine", "parent": "spine", "location": "yes"}]},
     r"control #0 \('c'\): location = 'yes' must be true or false"),
])
def test_bad_maps_are_refused_naming_the_problem(doc, match):
    with pytest.raises(ValueError, match=match):
        parse_bone_map(doc, "custom")


def test_unknown_shipped_map():
    with pytest.raises(ValueError, match="bone_map = 'blender' is not one of rigify"):
        load_bone_map("blender")

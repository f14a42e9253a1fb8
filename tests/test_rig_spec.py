"""rigs/*.json: the four figures as data, and their loader (mapping/rig_spec.py)."""
import copy
import json

import numpy as np
import pytest

from blender_turning.mapping import bones as B
from blender_turning.mapping.sports.common import mesh_points
from blender_turning.mapping.kinematics import Skeleton, quat_to_matrix
from blender_turning.mapping.rig_spec import RIG_NAMES, RIGS_DIR, load_rig, parse_rig


def raw(name):
    return json.loads((RIGS_DIR / f"{name}.json").read_text())


@pytest.mark.parametrize("name", RIG_NAMES)
def test_rigs_load_with_rigify_names_and_equipment(name):
    spec = load_rig(name)
    assert spec.sport == name
    names = spec.bone_names
    for b in B.REQUIRED[name]:
        assert b in names
    assert spec.bone("root").parent is None and spec.bone("lean").parent == "root"
    assert not spec.bone("root").deform and not spec.bone("lean").deform
    # every human bone but the toes and the neck/head helpers is dressed in a mesh
    dressed = {m.bone for m in spec.meshes}
    for b in B.HUMAN:
        if not b.startswith(("toe", "spine.005", "spine.006")):
            assert b in dressed, b


@pytest.mark.parametrize("name", RIG_NAMES)
def test_rest_pose_stands_on_the_ground(name):
    """Nothing below z = 0; the equipment touches the ground within 1 mm at rest."""
    spec = load_rig(name)
    sk = Skeleton.from_spec(spec)
    lowest = {}
    for m in spec.meshes:
        rest = sk.rest_of(m.bone)
        r = rest[:3, :3] @ quat_to_matrix(np.array(m.rotation))
        c = rest[:3, :3] @ np.array(m.offset) + rest[:3, 3]
        if m.shape == "box":
            low = c[2] - 0.5 * np.abs(r[2]) @ np.array(m.size)
        else:   # cylinder/capsule about the local Y axis: radius across, half length along
            radius, length = m.size
            ax = r[:, 1]
            low = c[2] - 0.5 * length * abs(ax[2]) - radius * np.sqrt(max(0.0, 1 - ax[2] ** 2))
        lowest[m.bone] = min(lowest.get(m.bone, np.inf), low)
    assert min(lowest.values()) > -1e-3
    ground = {"skier": B.SKI, "telemark": B.SKI, "snowboarder": (B.BOARD,),
              "cyclist": (B.WHEEL_F, B.WHEEL_R)}[name]
    for b in ground:
        assert abs(lowest[b]) < 1e-3, b


def test_box_corners_of_a_ski_span_its_length():
    pts = mesh_points(load_rig("skier"), "ski.L")
    assert pts[:, 1].max() - pts[:, 1].min() > 1.5


def test_connected_heads_meet_parent_tails():
    for name in RIG_NAMES:
        spec = load_rig(name)
        for b in spec.bones:
            if b.connected:
                assert np.allclose(b.head, spec.bone(b.parent).tail)


def test_missing_required_bone_is_named():
    doc = raw("skier")
    doc["bones"] = [b for b in doc["bones"] if b["name"] != "pole.R"]
    doc["meshes"] = [m for m in doc["meshes"] if m["bone"] != "pole.R"]
    with pytest.raises(B.MissingBoneError, match="'pole.R'"):
        parse_rig(doc)
    with pytest.raises(ValueError, match="'pole.R'"):      # what the operators catch
        parse_rig(doc)
    with pytest.raises(KeyError, match="'nope'"):
        load_rig("skier").bone("nope")


@pytest.mark.parametrize("edit, match", [
    (lambda d: d["bones"][3].update(parent="ghost"), "ghost"),
    (lambda d: d["bones"][3].update(tail=d["bones"][3]["head"]), "coincide"),
    (lambda d: d["bones"][3].update(head=[0, 0, 9], connected=True), "connected"),
    (lambda d: d["bones"].append(dict(d["bones"][0])), "twice"),
    (lambda d: d["meshes"][0].update(shape="blob"), "blob"),
    (lambda d: d["meshes"][0].update(size=[1, 2]), "size"),
    (lambda d: d["meshes"][0].update(material="gold"), "gold"),
    (lambda d: d["meshes"][0].update(rotation=[2, 0, 0, 0]), "unit quaternion"),
    (lambda d: d.update(sport="curling"), "curling"),
])
def test_invalid_documents_are_rejected_with_the_field_named(edit, match):
    doc = copy.deepcopy(raw("skier"))
    edit(doc)
    with pytest.raises(ValueError, match=match):
        parse_rig(doc)


def test_unknown_rig_name():
    with pytest.raises(ValueError, match="rig = 'horse'"):
        load_rig("horse")


def test_mirror_helpers():
    assert B.mirror("thigh.L") == "thigh.R" and B.mirror("pedal.R") == "pedal.L"
    assert B.mirror("spine") == "spine" and B.side("foot", "L") == "foot.L"
    with pytest.raises(ValueError):
        B.side("foot", "X")

"""Make Figure refuses, by name, a rig whose motion the bake could not write (docs/failures.md): an
object constraint that overrides the keys (a Copy Location to an empty: the figure would never
move), and a rig linked from a library (it cannot be keyed); nothing of the rig changes."""
import os
import tempfile

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning import blender as addon  # noqa: E402
from rig_fixtures import activate, mixamo_skeleton, state  # noqa: E402

pytestmark = pytest.mark.blender


@pytest.fixture
def scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    yield bpy.context.scene
    addon.unregister()


def test_a_copy_location_constraint_is_refused_by_name(scene):
    rig = mixamo_skeleton()
    anchor = bpy.data.objects.new("Anchor", None)
    scene.collection.objects.link(anchor)
    c = rig.constraints.new("COPY_LOCATION")
    c.name, c.target = "Stay Put", anchor
    activate(rig)
    before = state(rig)
    with pytest.raises(RuntimeError, match=r"'Mixamo' has the constraint 'Stay Put' "
                                           r"\(COPY_LOCATION\), which overrides"):
        bpy.ops.turning.make_figure(sport="SKIER", bone_map="MIXAMO")
    assert state(rig) == before and not rig.turning.is_figure
    c.mute = True                                 # muted: the keys are what moves it
    assert bpy.ops.turning.make_figure(sport="SKIER", bone_map="MIXAMO") == {"FINISHED"}


def test_a_rig_linked_from_a_library_is_refused(scene, tmp_path):
    mixamo_skeleton(name="Linked")
    lib = tmp_path / "rigs.blend"
    bpy.data.libraries.write(str(lib), {bpy.data.objects["Linked"]})
    bpy.data.objects.remove(bpy.data.objects["Linked"])
    with bpy.data.libraries.load(str(lib), link=True) as (src, dst):
        dst.objects = ["Linked"]
    rig = dst.objects[0]
    scene.collection.objects.link(rig)
    activate(rig)
    with pytest.raises(RuntimeError, match=r"armature 'Linked' is linked from the library "
                                           r".*rigs\.blend.*make it local"):
        bpy.ops.turning.make_figure(sport="SKIER", bone_map="MIXAMO")
    assert not rig.turning.is_figure

"""Undo restores the rig after Make Figure and after Remove Figure (issue 8), on the bpy wheel
(Blender's memfile undo runs headless).  Operators called from Python push no undo step of
their own here, so the test pushes one after each, as the window manager does after an operator
with the UNDO flag: what is checked is that everything they change is undoable data."""
import os
import tempfile

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning import blender as addon  # noqa: E402
from rig_fixtures import activate, mixamo_skeleton, state  # noqa: E402

pytestmark = pytest.mark.blender


@pytest.fixture(scope="module", autouse=True)
def registered():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    yield
    addon.unregister()


def test_undo_make_figure_and_remove_figure():
    obj = mixamo_skeleton("Bob")
    activate(obj)
    before = state(obj)
    objects = sorted(o.name for o in bpy.data.objects)
    bpy.ops.ed.undo_push(message="the rig")
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    bpy.ops.ed.undo_push(message="Make Figure")
    assert len(bpy.data.objects) == len(objects) + 4            # skis and poles
    bpy.ops.ed.undo()
    obj = bpy.data.objects["Bob"]
    assert sorted(o.name for o in bpy.data.objects) == objects
    assert state(obj) == before
    assert not obj.turning.is_figure
    bpy.ops.ed.redo()
    obj = bpy.data.objects["Bob"]
    assert obj.turning.is_figure and obj.turning.rig.equipment is not None
    activate(obj)
    assert bpy.ops.turning.remove_figure() == {"FINISHED"}
    bpy.ops.ed.undo_push(message="Remove Figure")
    assert sorted(o.name for o in bpy.data.objects) == objects
    bpy.ops.ed.undo()
    obj = bpy.data.objects["Bob"]
    assert obj.turning.is_figure and len(obj.turning.rig.equipment.objects) == 4

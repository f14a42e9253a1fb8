"""Follow Path on the bpy wheel: a path the figure cannot finish within the time
limit is reported, with how far along it got, and nothing is written."""
import os
import tempfile

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from test_blender_operators import add, make_path, scene, snapshot  # noqa: E402,F401

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]


def test_path_not_finished_in_time_is_reported_and_scene_unchanged(scene):  # noqa: F811
    """A 12 m switchback with 3 m between its legs: too tight for the skier to come back."""
    obj = add("SKIER")
    obj.turning.path = make_path([(0, 0), (0, -12), (3, -12), (3, 0)])
    bpy.context.view_layer.objects.active = obj
    before = snapshot()
    with pytest.raises(RuntimeError, match=r"the end of the path was not reached within the "
                                           r"time limit of [\d.]+ s: got [\d.]+ m of [\d.]+ m"):
        bpy.ops.turning.follow_path()
    assert snapshot() == before

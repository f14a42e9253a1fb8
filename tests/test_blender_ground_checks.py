"""A bad Ground is refused with a message naming the object and what is wrong (docs/failures.md):
a vertex that is not finite (with its index), one far from the rest, an animated Ground (read at
one frame only), one not in the scene, a figure's own body, one 1,000 km from the origin; and a
large fine mesh is sampled at a step its extent allows rather than refused."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender.scene import ground  # noqa: E402
from blender_turning.core.ground.terrain_gen import ski_slope  # noqa: E402

pytestmark = pytest.mark.blender


def _mountain(name="Mountain", cell=1.0, length=40, width=30):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    slope = ski_slope(length=length, width=width, cell=cell, seed=4)
    obj = bpy.data.objects.new(name, ground.mesh_from_height_field(bpy, slope, name))
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.update()
    return obj


def _read(obj):
    return ground.read_ground(obj, bpy.context.evaluated_depsgraph_get())


def _refused(obj, *words):
    with pytest.raises(ValueError) as info:
        _read(obj)
    msg = str(info.value)
    assert repr(obj.name) in msg, msg
    for w in words:
        assert w in msg, msg
    return msg


@pytest.mark.parametrize("value, shown", [(math.nan, "nan"), (math.inf, "3.40282e+38")])
def test_a_vertex_that_is_not_finite_is_named_with_its_index(value, shown):
    obj = _mountain()
    obj.data.vertices[17].co.z = value
    _refused(obj, "vertex 17", shown, "not a finite position")


def test_a_stray_vertex_far_from_the_rest_is_named():
    """A vertex at x = y = 1e30 would stretch the ground's box (10^60 samples)."""
    obj = _mountain()
    obj.data.vertices[5].co.x = obj.data.vertices[5].co.y = 1e30
    _refused(obj, "vertex 5", "stray vertex")


def test_a_ground_1000_km_from_the_origin_names_the_object_not_x0():
    obj = _mountain()
    obj.location = (1e6, 0.0, 0.0)
    bpy.context.view_layer.update()
    msg = _refused(obj, "reaches x = 9999", "allowed range")
    assert "x0" not in msg


def test_an_animated_ground_is_refused():
    obj = _mountain()
    obj.keyframe_insert("location", frame=1)
    _refused(obj, "animated", "one frame")


def test_a_ground_moved_by_an_animated_parent_is_refused():
    obj = _mountain()
    rig = bpy.data.objects.new("Carrier", None)
    bpy.context.scene.collection.objects.link(rig)
    obj.parent = rig
    rig.keyframe_insert("location", frame=1)
    _refused(obj, "animated", "'Carrier'")


def test_a_ground_not_in_the_scene_is_named():
    obj = _mountain()
    bpy.context.scene.collection.objects.unlink(obj)
    _refused(obj, "not in the scene")


def test_a_figures_own_body_is_not_ground():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    from blender_turning import blender as addon
    registered = hasattr(bpy.types.Object, "turning")
    if not registered:
        addon.register()
    try:
        bpy.ops.turning.add_figure(sport="SKIER")
        fig = bpy.context.view_layer.objects.active
        body = next(c for c in fig.children if c.type == "MESH")
        msg = _refused(body, "part of the figure", repr(fig.name))
        assert msg
    finally:
        if not registered:
            addon.unregister()


def test_a_large_fine_ground_is_sampled_within_the_limit():
    """800 m x 600 m at 0.5 m (1.9 million triangles): a quarter of its detail would be 7.7
    million samples; the step is coarsened to the limit's instead of refusing."""
    obj = _mountain(cell=0.5, length=800, width=600)
    read = _read(obj)
    f = read.field
    assert f.nx * f.ny <= ground.MAX_SAMPLES
    assert f.nx * f.ny > 0.95 * ground.MAX_SAMPLES     # as fine as the limit allows
    assert 0.125 < f.cell < 0.8

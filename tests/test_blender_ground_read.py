"""Reading a Ground mesh cheaply (issue 10, "the bake stays fast"): exact heights by
``Object.ray_cast`` on a moved, tilted, scaled mesh, and a read kept only while the mesh, its
placement and the cell stay the same."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender import ground  # noqa: E402
from blender_turning.core.terrain_gen import ski_slope  # noqa: E402

pytestmark = pytest.mark.blender


def _mountain(**placement):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    slope = ski_slope(length=40, width=30, cell=1.0, seed=4)
    obj = bpy.data.objects.new("Mountain", ground.mesh_from_height_field(bpy, slope, "Mountain"))
    bpy.context.scene.collection.objects.link(obj)
    for k, v in placement.items():
        setattr(obj, k, v)
    bpy.context.view_layer.update()
    return obj


def _world_rays(obj, x, y):
    """Ray casts from above onto the mesh's world-space triangles (a BVHTree of our own)."""
    from mathutils.bvhtree import BVHTree
    world, tris = ground._world_triangles(obj, bpy.context.evaluated_depsgraph_get())
    bvh = BVHTree.FromPolygons(world.tolist(), tris.tolist(), all_triangles=True)
    top = world[:, 2].max() + 1.0
    hits = [bvh.ray_cast((a, b, top), (0.0, 0.0, -1.0))[0] for a, b in zip(x, y)]
    return np.array([np.nan if h is None else h[2] for h in hits])


def test_heights_are_ray_casts_onto_a_moved_tilted_scaled_mesh():
    obj = _mountain(location=(7.0, -4.0, 3.0), rotation_euler=(math.radians(8), 0.0, 0.6),
                    scale=(1.3, 0.8, 1.2))
    read = ground.read_ground(obj, bpy.context.evaluated_depsgraph_get())
    x_lo, x_hi, y_lo, y_hi = read.field.extent
    rng = np.random.default_rng(6)
    x, y = rng.uniform(x_lo, x_hi, 600), rng.uniform(y_lo, y_hi, 600)
    want = _world_rays(obj, x, y)
    got = read.heights(x, y)
    on = np.isfinite(want)
    assert 200 < on.sum() < 600                   # the rotated mesh leaves corners of its box
    np.testing.assert_allclose(got[on], want[on], atol=2e-5)      # float32 vertices
    # Off the mesh: the smooth field's height (its border cells filled from the nearest).
    np.testing.assert_allclose(got[~on], read.field.derivatives(x[~on], y[~on])[0])


def test_a_read_is_kept_only_while_the_mesh_stays_the_same():
    obj = _mountain()
    depsgraph = bpy.context.evaluated_depsgraph_get
    first = ground.read_ground(obj, depsgraph())
    assert ground.read_ground(obj, depsgraph()) is first          # unchanged: not read again
    assert ground.read_ground(obj, depsgraph(), cell=0.5).field.cell == 0.5
    v = obj.data.vertices[200]
    v.co.z += 1.0                                  # an edit of the mesh
    obj.data.update()
    edited = ground.read_ground(obj, depsgraph())
    assert edited is not first
    x, y = (obj.matrix_world @ v.co).xy
    assert edited.field.derivatives(x, y)[0] == pytest.approx(
        first.field.derivatives(x, y)[0] + 1.0, abs=1e-5)
    obj.location.x += 2.0                          # moved
    bpy.context.view_layer.update()
    moved = ground.read_ground(obj, depsgraph())
    assert moved is not edited and moved.field.x0 == pytest.approx(edited.field.x0 + 2.0)
    mod = obj.modifiers.new("Up", 'DISPLACE')      # a modifier changes the evaluated mesh
    mod.direction, mod.mid_level, mod.strength = 'Z', 0.0, 0.5       # +0.5 m up
    bpy.context.view_layer.update()
    shifted = ground.read_ground(obj, depsgraph())
    assert shifted.field.derivatives(x + 2.0, y)[0] == pytest.approx(
        moved.field.derivatives(x + 2.0, y)[0] + 0.5, abs=1e-5)

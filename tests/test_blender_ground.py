"""Ground meshes read into the core's height field and the demo mountain written as a mesh
(docs/TERRAIN.md), on the bpy wheel."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender.scene.ground import (height_field_of,  # noqa: E402
                                                  mesh_from_height_field)
from blender_turning.core.ground.terrain import Plane  # noqa: E402
from blender_turning.core.ground.terrain_gen import ski_slope  # noqa: E402

pytestmark = pytest.mark.blender


def _object(mesh, name):
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def test_a_tilted_plane_mesh_reads_back_as_the_plane():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=20, y_subdivisions=20, size=40)
    obj = bpy.context.object
    obj.location = (5.0, -3.0, 2.0)
    obj.rotation_euler = (math.radians(15), 0.0, 0.0)       # tilted about x: falls toward -y
    field = height_field_of(obj, bpy.context.evaluated_depsgraph_get())
    sigma = math.radians(15)
    plane = Plane(sigma, -math.pi / 2, x0=5.0, y0=-3.0, z0=2.0)
    x_lo, x_hi, y_lo, y_hi = field.extent
    rng = np.random.default_rng(1)
    x, y = rng.uniform(x_lo + 1, x_hi - 1, 100), rng.uniform(y_lo + 1, y_hi - 1, 100)
    got = field.derivatives(x, y)
    want = plane.derivatives(x, y)
    # Mesh vertices are float32: heights of ~5 m carry ~1e-6 m of round-off.
    np.testing.assert_allclose(got[0], want[0], atol=2e-5)
    np.testing.assert_allclose(got[1:3], want[1:3], atol=1e-5)


def test_the_height_field_stays_within_a_centimetre_of_ray_casts():
    """The demo mountain as a 1 m mesh (moguls every 4 m: creases at every edge), read back at
    the default cell: the smooth field the physics uses is within 1.5 cm of a ray cast onto the
    mesh everywhere (where the bake places the feet it casts rays itself)."""
    from mathutils.bvhtree import BVHTree
    bpy.ops.wm.read_factory_settings(use_empty=True)
    slope = ski_slope(length=80, width=60, cell=1.0, seed=3)
    obj = _object(mesh_from_height_field(bpy, slope, "Mountain"), "Mountain")
    depsgraph = bpy.context.evaluated_depsgraph_get()
    field = height_field_of(obj, depsgraph)
    assert field.cell == pytest.approx(0.25)
    bvh = BVHTree.FromObject(obj, depsgraph)
    rng = np.random.default_rng(2)
    x_lo, x_hi, y_lo, y_hi = slope.extent
    x, y = rng.uniform(x_lo + 1, x_hi - 1, 1000), rng.uniform(y_lo + 1, y_hi - 1, 1000)
    ray = np.array([bvh.ray_cast((a, b, 100.0), (0, 0, -1))[0][2] for a, b in zip(x, y)])
    assert np.abs(ray - slope.derivatives(x, y)[0]).max() > 0.03   # the mesh has creases
    # Measured 1.15 cm at most over these 1000 points: the spline's rounding of the creases,
    # linear in the cell (2 cm at 0.5 m, 0.4 cm at 0.125 m).
    assert np.abs(field.derivatives(x, y)[0] - ray).max() < 0.015


def test_the_grid_is_what_ray_casts_from_above_return():
    """The vectorized rasterization against one ray cast per grid point, on a rotated, tilted,
    bumpy mesh with a hole and an overhang-free fold: equal to float32 round-off, NaN where no
    ray hits (before the holes are filled)."""
    from mathutils.bvhtree import BVHTree
    from blender_turning.blender.scene.ground import _rasterize, _world_triangles
    bpy.ops.wm.read_factory_settings(use_empty=True)
    slope = ski_slope(length=30, width=24, cell=1.5, seed=5)
    obj = _object(mesh_from_height_field(bpy, slope, "Bumps"), "Bumps")
    obj.rotation_euler = (0.2, -0.1, 0.7)
    obj.location = (3.0, -2.0, 1.0)
    bpy.context.view_layer.update()
    dg = bpy.context.evaluated_depsgraph_get()
    world, tris = _world_triangles(obj, dg)
    x0, y0 = world[:, 0].min(), world[:, 1].min()
    cell, nx, ny = 0.37, 90, 100
    got = _rasterize(world, tris, x0, y0, cell, nx, ny)
    bvh = BVHTree.FromPolygons(world.tolist(), tris.tolist(), all_triangles=True)
    want = np.full((ny, nx), np.nan)
    for j in range(ny):
        for i in range(nx):
            hit = bvh.ray_cast((x0 + i * cell, y0 + j * cell, 100.0), (0, 0, -1))[0]
            if hit is not None:
                want[j, i] = hit[2]
    both = np.isfinite(got) & np.isfinite(want)
    # A ray grazing a shared edge may count as a hit on one side only: a few points differ.
    assert (np.isfinite(got) != np.isfinite(want)).sum() <= 0.002 * got.size
    assert both.sum() > 0.5 * got.size and np.isnan(want).sum() > 100   # rotated: corners empty
    # The ray casts are float32 (hits ~100 m down): measured 2.1e-5 m at most.
    np.testing.assert_allclose(got[both], want[both], atol=5e-5)


def test_bad_grounds_are_refused():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.object.empty_add()
    with pytest.raises(ValueError, match="not a mesh"):
        height_field_of(bpy.context.object, bpy.context.evaluated_depsgraph_get())
    mesh = bpy.data.meshes.new("Empty")
    obj = _object(mesh, "NoFaces")
    with pytest.raises(ValueError, match="no faces"):
        height_field_of(obj, bpy.context.evaluated_depsgraph_get())


def test_the_render_tiles_are_the_mesh_and_shade_as_it():
    """The render job draws a terrain as tiles (render/terrain.py: Workbench leaves out the ones
    that cannot show): together they are the whole grid, each quad once, and every vertex has
    the whole mesh's normal, so a tile's border shades as the mesh does; the mesh itself, the
    figures' Ground, is not rendered."""
    from blender_turning.blender.render.terrain import render_tiles
    bpy.ops.wm.read_factory_settings(use_empty=True)
    field = ski_slope(40, 30, 18.0, 1.0, 7)
    obj = _object(mesh_from_height_field(bpy, field, "Mountain"), "Mountain")
    tiles = render_tiles(bpy, obj, (field.ny, field.nx), 12)
    assert obj.hide_render and not any(t.hide_render for t in tiles)
    assert len(tiles) == 3 * 4                         # 30 x 40 quads in tiles of 12: 3 x 4

    def quads(o):
        co = np.array([v.co for v in o.data.vertices])
        return {tuple(np.round(co[list(p.vertices)].mean(0), 4)) for p in o.data.polygons}

    parts = [quads(t) for t in tiles]
    assert sum(map(len, parts)) == len(obj.data.polygons)
    assert set().union(*parts) == quads(obj)
    whole = {tuple(np.round(v.co, 4)): np.array(n.vector)
             for v, n in zip(obj.data.vertices, obj.data.vertex_normals)}
    worst = 0.0
    for t in tiles:
        t.data.update()
        for loop, normal in zip(t.data.loops, t.data.corner_normals):
            want = whole[tuple(np.round(t.data.vertices[loop.vertex_index].co, 4))]
            worst = max(worst, float(np.abs(np.array(normal.vector) - want).max()))
    # Custom normals are stored compressed: measured 4.7e-4 off the float normal (0.025 at a
    # border without them).
    assert worst < 1e-3, worst

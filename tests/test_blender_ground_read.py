"""Reading a Ground mesh cheaply ("the bake stays fast"): exact heights by
``Object.ray_cast`` on a moved, tilted, scaled mesh, and a read kept only while the mesh, its
placement and the cell stay the same."""
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


def test_heights_on_a_grid_mesh_are_its_triangles_without_ray_casts():
    """A grid mesh (moved, turned by 90 deg, stretched) gives the feet's heights from its
    lattice: the world-space ray casts' heights to float32, off the mesh the smooth field's."""
    obj = _mountain(location=(7.0, -4.0, 3.0), rotation_euler=(0.0, 0.0, math.pi / 2),
                    scale=(1.3, 0.8, 1.2))
    read = ground.read_ground(obj, bpy.context.evaluated_depsgraph_get())
    assert read.grid is not None
    x_lo, x_hi, y_lo, y_hi = read.field.extent
    rng = np.random.default_rng(7)
    x, y = rng.uniform(x_lo, x_hi, 600), rng.uniform(y_lo, y_hi, 600)
    want = _world_rays(obj, x, y)
    got = read.heights(x, y)
    on = np.isfinite(want)
    assert on.sum() > 550
    np.testing.assert_allclose(got[on], want[on], atol=2e-5)
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


def _triangle_grid(diagonals, xs, ys, z):
    """A mesh of triangles on the lattice ``xs`` x ``ys`` with heights ``z[j, i]``, each cell
    split along (i, j)-(i+1, j+1) where ``diagonals[j, i]``, else along the other diagonal."""
    nx = len(xs)
    X, Y = np.meshgrid(xs, ys)
    co = np.stack([X, Y, z], -1).reshape(-1, 3)
    faces = []
    for j in range(len(ys) - 1):
        for i in range(nx - 1):
            a, b, c, d = j * nx + i, j * nx + i + 1, (j + 1) * nx + i, (j + 1) * nx + i + 1
            faces += [(a, b, d), (a, d, c)] if diagonals[j, i] else [(a, b, c), (b, d, c)]
    mesh = bpy.data.meshes.new("Triangles")
    mesh.from_pydata(co.tolist(), [], faces)
    mesh.update()
    obj = bpy.data.objects.new("Triangles", mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def _both(obj, cell=0.23):
    """The grid path's heights on the sample grid (None: not a grid mesh) and the general
    rasterization's."""
    world, tris = ground._world_triangles(obj, bpy.context.evaluated_depsgraph_get())
    lo, hi = world.min(0), world.max(0)
    nx, ny = (int(np.floor((hi[k] - lo[k]) / cell)) + 1 for k in (0, 1))
    grid = ground._grid_mesh(world, tris)
    xs, ys = lo[0] + cell * np.arange(nx), lo[1] + cell * np.arange(ny)
    return (None if grid is None else grid.heights(xs[None, :], ys[:, None]),
            ground._rasterize(world, tris, float(lo[0]), float(lo[1]), cell, nx, ny))


def test_a_grid_mesh_is_rasterized_by_its_lattice():
    """The grid path (each point's triangle from its place in its lattice cell) gives the
    general rasterization's heights: on cells split along either diagonal (mixed at random),
    on the demo mountain moved, turned by 90 deg and stretched; a turned, holed or irregular
    mesh is left to the general path."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    rng = np.random.default_rng(9)
    xs, ys = np.linspace(-7.0, 8.0, 16), np.linspace(2.0, 13.0, 12)
    z = rng.normal(0.0, 0.6, (12, 16))
    grid, general = _both(_triangle_grid(rng.random((11, 15)) < 0.5, xs, ys, z))
    assert np.isfinite(general).all()
    np.testing.assert_allclose(grid, general, rtol=0, atol=1e-12)
    obj = _mountain(location=(5.0, -3.0, 1.0), rotation_euler=(0.0, 0.0, math.pi / 2),
                    scale=(1.3, 0.7, 1.0))
    grid, general = _both(obj)
    inside = np.isfinite(general)              # float32 edges: border rows missed there
    assert inside.mean() > 0.97 and np.isfinite(grid).all()
    np.testing.assert_allclose(grid[inside], general[inside], rtol=0, atol=5e-6)
    obj.rotation_euler.z = 0.3                 # not axis-aligned
    bpy.context.view_layer.update()
    assert _both(obj)[0] is None
    holed = _mountain()
    holed.data.polygons[37].select = True      # a face deleted: a hole
    bpy.context.view_layer.objects.active = holed
    bpy.ops.object.mode_set(mode='EDIT')
    bpy.ops.mesh.select_all(action='DESELECT')
    bpy.ops.object.mode_set(mode='OBJECT')
    holed.data.polygons[37].select = True
    bpy.ops.object.mode_set(mode='EDIT')
    bpy.ops.mesh.delete(type='ONLY_FACE')
    bpy.ops.object.mode_set(mode='OBJECT')
    grid, general = _both(holed)
    assert grid is None and np.isnan(general).any()
    odd = _triangle_grid(np.ones((11, 15), bool), np.cumsum(rng.uniform(0.9, 1.1, 16)), ys, z)
    assert _both(odd)[0] is None               # uneven columns (+-10%)


def _loop_triangles(obj):
    """Blender's own loop triangles of the evaluated mesh, as vertex indices."""
    ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = ev.to_mesh()
    mesh.calc_loop_triangles()
    tris = np.empty(3 * len(mesh.loop_triangles), np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    ev.to_mesh_clear()
    return tris.reshape(-1, 3)


def test_quads_are_split_as_blender_splits_them(monkeypatch):
    """A mesh of quads is split by Blender's rule (corners (0, 1, 2) and (0, 2, 3), or (0, 1, 3)
    and (1, 2, 3) where the 0-2 diagonal leaves the quad) without reading its triangles: the
    same triangles as Blender's on quads bent and skewed at random, starting at any corner
    (both splits common), and on the demo mountain; a mesh of triangles is read from Blender."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    rng = np.random.default_rng(4)
    n = 24
    X, Y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    co = np.stack([X + rng.uniform(-0.45, 0.45, X.shape), Y + rng.uniform(-0.45, 0.45, X.shape),
                   rng.normal(0.0, 2.0, X.shape)], -1).reshape(-1, 3)
    ii, jj = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    a = (jj * n + ii).ravel()
    q = np.stack([a, a + 1, a + n + 1, a + n], -1)
    q = np.array([np.roll(r, k) for r, k in zip(q, rng.integers(0, 4, len(q)))])
    mesh = bpy.data.meshes.new("Bent")
    mesh.from_pydata(co.tolist(), [], q.tolist())
    mesh.update()
    obj = bpy.data.objects.new("Bent", mesh)
    bpy.context.scene.collection.objects.link(obj)
    want = _loop_triangles(obj)
    flipped = np.mean(want[0::2, 2] == q[:, 3])                 # split along 1-3
    assert 0.2 < flipped < 0.8
    rule, by_rule = ground._quad_triangles, []
    monkeypatch.setattr(ground, "_quad_triangles",
                        lambda *a: by_rule.append(rule(*a)) or by_rule[-1])
    depsgraph = bpy.context.evaluated_depsgraph_get
    np.testing.assert_array_equal(ground._world_triangles(obj, depsgraph())[1], want)
    assert by_rule[-1] is not None                              # not Blender's, read
    mountain = _mountain()
    np.testing.assert_array_equal(ground._world_triangles(mountain, depsgraph())[1],
                                  _loop_triangles(mountain))
    assert by_rule[-1] is not None
    rng = np.random.default_rng(9)
    tri = _triangle_grid(rng.random((5, 6)) < 0.5, np.arange(7.0), np.arange(6.0),
                         rng.normal(0.0, 0.5, (6, 7)))
    np.testing.assert_array_equal(ground._world_triangles(tri, depsgraph())[1],
                                  _loop_triangles(tri))
    assert by_rule[-1] is None                                  # triangles: Blender's, read


def test_a_grid_mesh_is_sampled_where_the_run_goes():
    """A grid mesh's height field is sampled as a run visits it (a few tiles of the grid for a
    point), and is the field of all its lattice heights, bit for bit."""
    from blender_turning.core.ground.terrain import HeightField, LazyHeightField
    obj = _mountain(location=(3.0, -2.0, 1.0))
    read = ground.read_ground(obj, bpy.context.evaluated_depsgraph_get())
    field = read.field
    assert isinstance(field, LazyHeightField) and not field._done.any()
    x_lo, _, y_lo, _ = field.extent
    field.derivatives_one(x_lo + 1.0, y_lo + 1.0)
    assert 0 < field._done.sum() < field._done.size
    xs, ys = x_lo + field.cell * np.arange(field.nx), y_lo + field.cell * np.arange(field.ny)
    full = HeightField(read.grid.heights(xs[None, :], ys[:, None]), x_lo, y_lo, field.cell)
    np.testing.assert_array_equal(field._h, full._h)

"""Ground mesh <-> the core's height field (docs/TERRAIN.md).  The core stays bpy-free: a mesh
object the user picks as ground is read once into a :class:`..core.ground.terrain.HeightField` (what
ray casts from above on a regular grid return, rasterized in numpy, or for a grid mesh sampled
from its lattice where a run goes; kept while the mesh does not change); the demo's mountain goes
the other way."""
from __future__ import annotations

import hashlib
import math

import numpy as np

from ...core.ranges import RANGES
from ...core.ground.terrain import HeightField, LazyHeightField

#: Most grid points a ground is sampled at (a 200 m x 200 m terrain at 0.25 m is 641,601).
MAX_SAMPLES = 1_000_000


def _world_triangles(obj, depsgraph):
    """The evaluated mesh's vertices in world space and its triangles (Blender's loop
    triangles, as vertex indices), as numpy arrays."""
    return _read_mesh(obj, depsgraph)[1:]


def _read_mesh(obj, depsgraph, cell=None, known: bytes | None = None):
    """``(key, world, tris)``: a digest of what a read depends on (the evaluated mesh, its
    placement, ``cell``), and :func:`_world_triangles`'s arrays, ``None`` when the key is
    ``known`` (the read kept is still good)."""
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    try:
        # Through the attributes: float32 positions and the corners' vertices are read as one
        # block each (``vertices.foreach_get("co")`` costs ~3 ms, into float64 the same values).
        co = _attribute(mesh, "position", "vector", 3 * len(mesh.vertices), np.float32)
        co = co.reshape(-1, 3)
        corners = _attribute(mesh, ".corner_vert", "value", len(mesh.loops), np.int32)
        mesh.calc_loop_triangles()
        faces = np.empty(len(mesh.loop_triangle_polygons), dtype=np.int32)
        mesh.loop_triangle_polygons.foreach_get("value", faces)
        m = np.array(obj.matrix_world)
        # The triangles follow from the positions and the faces' corners (faces: each
        # triangle's face, hence each face's size): they need not be hashed.
        h = hashlib.blake2b(co.tobytes(), digest_size=20)
        for part in (corners, faces, m):
            h.update(part.tobytes())
        h.update(repr(cell).encode())
        key = h.digest()
        if key == known:
            return key, None, None
        tris = _quad_triangles(co, corners, faces)
        if tris is None:            # not all quads, or a quad Blender's rule could split either way
            tris = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
            mesh.loop_triangles.foreach_get("vertices", tris)     # ~7-10 ms for 80,000
    finally:
        ev.to_mesh_clear()
    world = co.astype(float) @ m[:3, :3].T + m[:3, 3]
    return key, world, tris.reshape(-1, 3)


def _attribute(mesh, name, prop, size, dtype):
    """The mesh attribute ``name`` as a flat array of ``size`` (an empty mesh has none)."""
    out = np.empty(size, dtype=dtype)
    if size:
        mesh.attributes[name].data.foreach_get(prop, out)
    return out


def _column_min(a) -> np.ndarray:
    """``a.min(0)`` of an (n, k) array column by column (numpy's reduction over the first axis of
    a few columns costs ~30x more: ~1.8 ms for the min and max of 40,401 vertices)."""
    return np.array([a[:, k].min() for k in range(a.shape[1])])


def _quad_triangles(co, corners, faces):
    """The loop triangles of a mesh of quads only, as Blender makes them
    (``mesh_calc_tessellation_for_face``: corners (0, 1, 2) and (0, 2, 3), or (0, 1, 3) and
    (1, 2, 3) where ``is_quad_flip_v3_first_third_fast`` finds the 0-2 diagonal outside the
    quad), from the positions ``co`` (object space), the corners' vertices and each
    triangle's face; ``None`` when a face is not a quad or a quad's test is within round-off of
    its threshold (Blender tests in float32; then its own triangles are read)."""
    n = len(corners) // 4
    if len(corners) != 4 * n or len(faces) != 2 * n or \
            not np.array_equal(faces, np.repeat(np.arange(n, dtype=faces.dtype), 2)):
        return None
    q0, q1, q2, q3 = np.ascontiguousarray(corners.reshape(n, 4).T)
    # In float64 from the float32 positions, coordinate by coordinate (contiguous gathers).
    d12, d13, d14 = [], [], []
    for k in range(3):
        X = co[:, k].astype(float)
        x1 = X[q0]
        d12.append(X[q1] - x1)
        d13.append(X[q2] - x1)
        d14.append(X[q3] - x1)

    def cross(a, b):
        return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])

    (ax, ay, az), (bx, by, bz) = cross(d12, d13), cross(d14, d13)
    dot = ax * bx + ay * by + az * bz
    size = np.sqrt((ax * ax + ay * ay + az * az) * (bx * bx + by * by + bz * bz))
    if not np.all(np.abs(dot) > 1e-4 * size):
        return None
    flip = dot > 0.0
    tris = np.empty((n, 2, 3), dtype=corners.dtype)
    tris[:, 0, 0], tris[:, 0, 1], tris[:, 0, 2] = q0, q1, np.where(flip, q3, q2)
    tris[:, 1, 0], tris[:, 1, 1], tris[:, 1, 2] = np.where(flip, q1, q0), q2, q3
    return tris.reshape(-1, 3)


class MeshGround:
    """A ground mesh read once: its smooth :attr:`field` for the physics, and exact heights on
    the mesh (:meth:`heights`)."""

    def __init__(self, name: str, field: HeightField, grid: _GridMesh | None = None):
        self.name, self.field, self.grid = name, field, grid

    def heights(self, x, y) -> np.ndarray:
        """The mesh's height under each ``(x, y)``: what a ray cast from above returns (the
        smooth field's where none hits, off the mesh's edge)."""
        x, y = np.asarray(x, float), np.asarray(y, float)
        z = self.top(x, y)
        off = np.isnan(z)
        if off.any():
            z[off] = np.asarray(self.field.derivatives(x[off], y[off])[0], float)
        return z

    def top(self, x, y) -> np.ndarray:
        """The height of the mesh's topmost face over each ``(x, y)``, NaN where a ray cast
        straight down misses it.  A grid mesh is evaluated from its lattice (:class:`_GridMesh`);
        any other by ``Object.ray_cast`` in the object's own space (Blender keeps the evaluated
        mesh's BVH tree between calls and bakes, where a ``BVHTree`` of our own cost ~0.2 s to
        build for a 200 m x 200 m, 1 m mesh)."""
        x, y = np.asarray(x, float).ravel(), np.asarray(y, float).ravel()
        z = np.full(len(x), np.nan)
        if self.grid is not None:
            on = self.grid.contains(x, y)
            z[on] = self.grid.heights(x[on], y[on])
            return z
        import bpy
        obj = bpy.data.objects.get(self.name)
        if obj is None:
            raise ValueError(f"ground {self.name!r} was deleted while baking")
        ev = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        m = np.array(ev.matrix_world)
        inv = np.linalg.inv(m)
        # From 1 m above the mesh's box: the BVH works in float32, a ray from 1 km above
        # would carry ~0.3 mm of round-off into the hit.
        top = float(np.max(np.array(ev.bound_box) @ m[2, :3] + m[2, 3])) + 1.0
        origins = np.stack([x, y, np.full_like(x, top)], -1) @ inv[:3, :3].T + inv[:3, 3]
        down = tuple(-inv[:3, 2])
        cast = ev.ray_cast
        for k, o in enumerate(origins.tolist()):
            hit, loc = cast(o, down)[:2]
            if hit:
                z[k] = m[2, 0] * loc[0] + m[2, 1] * loc[1] + m[2, 2] * loc[2] + m[2, 3]
        return z


def height_field_of(obj, depsgraph, cell: float | None = None) -> HeightField:
    """:func:`read_ground`'s height field."""
    return read_ground(obj, depsgraph, cell).field


def read_ground(obj, depsgraph, cell: float | None = None) -> MeshGround:
    """Sample the mesh object ``obj`` (with its modifiers) into a height field over its
    horizontal bounding box.  ``cell`` (m) defaults to a quarter of the median of each
    triangle's shortest side seen from above: the spline through the samples then rounds the
    mesh's creases by about a centimetre on a 1 m mogul mesh (measured: 1.2 cm at a quarter,
    2 cm at half), coarser where the ground's extent would need more than :data:`MAX_SAMPLES`
    (:func:`_default_cell`).  A Ground not in the scene, part of a figure, animated, with a
    vertex that is not finite or strays far from the rest, or reaching past 100 km from the
    origin is refused, naming the object (and the vertex).  A grid mesh's samples are computed as a
    run visits them
    (:class:`..core.ground.terrain.LazyHeightField`); any other mesh is rasterized whole.  Grid
    points the mesh does not cover take the height of the nearest covered point in their row
    (then column); raises ``ValueError`` naming the object when it has no faces."""
    if obj is None or obj.type != 'MESH':
        raise ValueError(f"ground {getattr(obj, 'name', obj)!r} is not a mesh object")
    check_ground_object(obj, depsgraph)
    kept = _READ.get(obj.name)
    key, world, tris = _read_mesh(obj, depsgraph, cell, kept and kept[0])
    if world is None:
        return kept[1]
    if len(tris) == 0:
        raise ValueError(f"ground {obj.name!r} has no faces")
    used = np.unique(tris)                 # loose vertices are not ground
    check_vertices(obj.name, world, used)
    lo, hi = _column_min(world[used]), -_column_min(-world[used])
    if cell is None:
        cell = _default_cell(world, tris, hi - lo)
    nx = int(np.floor((hi[0] - lo[0]) / cell)) + 1
    ny = int(np.floor((hi[1] - lo[1]) / cell)) + 1
    if nx < 2 or ny < 2:
        raise ValueError(f"ground {obj.name!r} is less than one cell ({cell:g} m) across")
    if nx * ny > MAX_SAMPLES:
        raise ValueError(f"ground {obj.name!r} needs {nx * ny} samples at {cell:g} m; "
                         f"at most {MAX_SAMPLES}: use a coarser cell")
    x0, y0, cell = float(lo[0]), float(lo[1]), float(cell)
    limit = RANGES["coordinate"]
    for axis, v in (("x", x0), ("y", y0), ("x", float(hi[0])), ("y", float(hi[1]))):
        if not limit.lo <= v <= limit.hi:
            raise ValueError(f"ground {obj.name!r} reaches {axis} = {v:.6g} m, outside the "
                             f"allowed range [{limit.lo:g}, {limit.hi:g}] m: move it (and the "
                             "figures) nearer the origin")
    grid = _grid_mesh(world, tris)
    if grid is not None:
        # The lattice covers the grid: its samples are computed as the run visits them.
        field = LazyHeightField(lambda rows, cols: grid.heights(x0 + cell * cols[None, :],
                                                                y0 + cell * rows[:, None]),
                                nx, ny, x0, y0, cell)
    else:
        h = _rasterize(world, tris, x0, y0, cell, nx, ny)
        if np.isnan(h).all():
            raise ValueError(f"ground {obj.name!r}: no ray from above hit it")
        _fill_nearest(h)
        field = HeightField(h, x0, y0, cell)
    ground = MeshGround(obj.name, field, grid)
    _READ.pop(obj.name, None)
    while len(_READ) >= _KEEP:                              # the oldest read goes
        _READ.pop(next(iter(_READ)))
    _READ[obj.name] = (key, ground)
    return ground


def check_ground_object(obj, depsgraph) -> None:
    """Refuse, naming ``obj``, a Ground the figure cannot ride as read: not in the scene being
    baked, a figure's own body, or animated (it is read at one frame only)."""
    scene = depsgraph.scene
    if scene.objects.get(obj.name) is not obj:
        raise ValueError(f"ground {obj.name!r} is not in the scene {scene.name!r} (unlinked or "
                         "in another scene): link it, or pick another Ground")
    rig = obj
    while rig is not None:
        settings = getattr(rig, "turning", None)
        if settings is not None and getattr(settings, "is_figure", False):
            raise ValueError(f"ground {obj.name!r} is part of the figure {rig.name!r}, not "
                             "ground: pick the terrain mesh")
        rig = rig.parent
    holder = obj
    while holder is not None:
        if _animated(holder) or (holder is obj and _animated(getattr(obj.data, "shape_keys",
                                                                      None))):
            what = "its mesh's shape keys" if holder is obj and not _animated(obj) else (
                "it" if holder is obj else f"its parent {holder.name!r}")
            raise ValueError(f"ground {obj.name!r} is animated ({what} has keyframes or "
                             "drivers), but it is read at one frame only: apply or remove "
                             "the animation")
        holder = holder.parent


def _animated(idblock) -> bool:
    ad = getattr(idblock, "animation_data", None)
    return ad is not None and (ad.action is not None or len(ad.drivers) > 0)


#: A vertex this many times the spread of the others away from them is a stray one.
STRAY_FACTOR = 1000.0


def check_vertices(name: str, world, used) -> None:
    """Refuse, naming the ground and the vertex (its index in the evaluated mesh), a face's
    vertex that is not a finite position or lies far from all the others (the ground's box,
    and so its samples, would reach out to it)."""
    pts = world[used]
    # Blender stores an infinite coordinate as float32's largest, 3.4e38.
    bad = ~(np.abs(pts) < 1e37).all(axis=1)
    if bad.any():
        i = int(used[np.flatnonzero(bad)[0]])
        raise ValueError(f"ground {name!r}: vertex {i} is at "
                         f"({', '.join(f'{v:g}' for v in world[i])}), not a finite position "
                         "(inf is kept as 3.4e+38): fix or delete it")
    if len(pts) < 20:
        return
    q1, q99 = np.percentile(pts[:, :2], [1, 99], axis=0)
    spread = max(float((q99 - q1).max()), 1e-3)
    off = np.abs(pts[:, :2] - 0.5 * (q1 + q99)).max(axis=1)
    far = np.flatnonzero(off > STRAY_FACTOR * spread)
    if len(far):
        i = int(used[far[np.argmax(off[far])]])
        raise ValueError(f"ground {name!r}: vertex {i} at "
                         f"({', '.join(f'{v:.4g}' for v in world[i])}) is {off.max():.3g} m from "
                         f"the rest of the mesh (which spans {spread:.3g} m): a stray vertex? "
                         "Delete it")


def _default_cell(world, tris, size) -> float:
    """A quarter of the median shortest side (the mesh's detail), made coarser where that
    would take more than :data:`MAX_SAMPLES` samples over the ground's extent ``size``: a large,
    fine mesh (a scanned slope of a million faces) is sampled as finely as the limit allows."""
    cell = 0.25 * _median_shortest_side(world, tris)
    w, h = float(size[0]), float(size[1])

    def samples(c):
        return (np.floor(w / c) + 1) * (np.floor(h / c) + 1)

    if samples(cell) > MAX_SAMPLES:
        cell = max(cell, math.sqrt(w * h / MAX_SAMPLES), max(w, h) / (MAX_SAMPLES - 1))
        while samples(cell) > MAX_SAMPLES:
            cell *= 1.001
    return cell


def _median_shortest_side(world, tris) -> float:
    """The median of each triangle's shortest side seen from above (a quad's diagonal is never
    it), 1 m when all are degenerate: ``np.median`` of the sides' lengths, from their squares
    (the same order) and the square roots of the middle one or two only."""
    X, Y = (np.ascontiguousarray(world[:, k])[tris] for k in (0, 1))    # (k, 3) each

    def side(a, b):
        dx, dy = X[:, a] - X[:, b], Y[:, a] - Y[:, b]
        return dx * dx + dy * dy

    sq = np.minimum(np.minimum(side(0, 2), side(1, 0)), side(2, 1))
    sq = sq[sq > 0]
    if not len(sq):
        return 1.0
    mid = len(sq) // 2
    if len(sq) % 2:
        return float(np.sqrt(np.partition(sq, mid)[mid]))
    part = np.partition(sq, [mid - 1, mid])
    return float(np.median(np.sqrt(part[mid - 1:mid + 1])))


#: Grounds read, by object name: ``(digest of the world-space mesh and cell, MeshGround)``.
#: Baking again over an unchanged mesh (a figure's settings changed, not the mountain) skips the
#: rasterization (~0.2-0.3 s for 200 m x 200 m at 0.25 m); any change to the evaluated mesh, its
#: placement or the cell changes the digest.
_READ: dict[str, tuple[bytes, MeshGround]] = {}
_KEEP = 4


#: Most grid points a side of the triangles rasterized together (bigger ones go one by one).
_MAX_SPAN = 32


def _rasterize(world, tris, x0, y0, cell, nx, ny):
    """The highest triangle's height over every grid point ``(x0 + i cell, y0 + j cell)`` (NaN
    where none covers it): what a ray cast from above returns, computed for all points at once.
    Each triangle's grid points inside its horizontal bounding box get barycentric weights;
    points inside (to 1e-9, so shared edges are covered) take the interpolated height."""
    P = world[tris]                                         # (k, 3 vertices, 3)
    a, b, c = P[:, 0], P[:, 1], P[:, 2]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    ok = np.abs(det) > 1e-12                                # seen edge-on from above: no area
    a, b, c, det = a[ok], b[ok], c[ok], det[ok]
    xy = np.stack([a, b, c], 1)[:, :, :2]
    i0 = np.clip(np.ceil((xy[:, :, 0].min(1) - x0) / cell - 1e-9), 0, nx - 1).astype(int)
    i1 = np.clip(np.floor((xy[:, :, 0].max(1) - x0) / cell + 1e-9), -1, nx - 1).astype(int)
    j0 = np.clip(np.ceil((xy[:, :, 1].min(1) - y0) / cell - 1e-9), 0, ny - 1).astype(int)
    j1 = np.clip(np.floor((xy[:, :, 1].max(1) - y0) / cell + 1e-9), -1, ny - 1).astype(int)

    # Barycentric weights as affine functions of the point: u = ku0 + kux px + kuy py, same for v.
    ax, ay, bx, by, cx, cy = a[:, 0], a[:, 1], b[:, 0], b[:, 1], c[:, 0], c[:, 1]
    ku = np.stack([bx * cy - cx * by, by - cy, cx - bx], 1) / det[:, None]
    kv = np.stack([cx * ay - ax * cy, cy - ay, ax - cx], 1) / det[:, None]
    za, zb, zc = a[:, 2], b[:, 2], c[:, 2]
    found_i, found_z = [], []

    def cover(sel, di, dj):
        """Grid points ``(i0 + di, j0 + dj)`` of the triangles ``sel`` (di, dj broadcast)."""
        I0, I1, J0, J1, KU, KV, ZA, ZB, ZC = sel
        i, j = I0 + di, J0 + dj
        px, py = x0 + i * cell, y0 + j * cell
        u = KU[0] + KU[1] * px + KU[2] * py                 # weight of vertex a
        v = KV[0] + KV[1] * px + KV[2] * py                 # weight of vertex b
        w = 1.0 - u - v
        tol = -1e-9
        hit = (i <= I1) & (j <= J1) & (u >= tol) & (v >= tol) & (w >= tol)
        found_i.append((j * nx + i)[hit])
        found_z.append((u * ZA + v * ZB + w * ZC)[hit])

    def pick(k):
        return (i0[k], i1[k], j0[k], j1[k], ku[k].T, kv[k].T, za[k], zb[k], zc[k])

    extent = np.maximum(i1 - i0, j1 - j0) + 1
    span = int(min(np.percentile(extent, 99), _MAX_SPAN)) if len(extent) else 0
    small = pick(np.flatnonzero(extent <= span))
    for di in range(span):
        for dj in range(span):
            cover(small, di, dj)
    for k in np.flatnonzero(extent > span):                 # large triangles, one at a time
        di, dj = np.meshgrid(np.arange(max(i1[k] - i0[k] + 1, 0)),
                             np.arange(max(j1[k] - j0[k] + 1, 0)))
        cover(pick(k), di.ravel(), dj.ravel())
    h = np.full(ny * nx, -np.inf)
    if found_i:                                             # the highest hit of each point
        np.maximum.at(h, np.concatenate(found_i), np.concatenate(found_z))
    h[np.isinf(h)] = np.nan
    return h.reshape(ny, nx)


class _GridMesh:
    """A grid mesh's triangles as planes over its lattice cells (:func:`_grid_mesh`): the mesh's
    exact height anywhere over the lattice from where the point lies in its cell.  ``Z``: the
    lattice's heights ``(rows, columns)``; ``main``: per cell, split along (0,0)-(1,1)."""

    def __init__(self, lo, step, n, Z, main):
        self.lo, self.step, self.n, self.Z, self.main = lo, step, n, Z.ravel(), main

    def contains(self, x, y):
        hi = self.lo + self.step * (np.array(self.n) - 1)
        return (x >= self.lo[0]) & (x <= hi[0]) & (y >= self.lo[1]) & (y <= hi[1])

    def heights(self, x, y):
        """The mesh's height at ``(x, y)`` (arrays that broadcast; inside :meth:`contains`).

        Each cell's two triangles are planes over ``(u, v)`` in [0, 1]^2, ``h = c0 + a u + b
        v``: the first holds ``u >= v`` (split along the main diagonal) or ``u + v <= 1``
        (across), the second the rest; their coefficients from the cell's corners."""
        n0, n1 = self.n
        fx = np.clip((x - self.lo[0]) / self.step[0], 0.0, n0 - 1)
        fy = np.clip((y - self.lo[1]) / self.step[1], 0.0, n1 - 1)
        i = np.minimum(fx.astype(np.int64), n0 - 2)
        j = np.minimum(fy.astype(np.int64), n1 - 2)
        u, v = fx - i, fy - j
        main = self.main[j * (n0 - 1) + i]
        second = np.where(main, u < v, u + v > 1.0)
        k = j * n0 + i
        Z = self.Z
        z00, z10, z01, z11 = Z[k], Z[k + 1], Z[k + n0], Z[k + n0 + 1]
        c0 = np.where(second & ~main, z01 + z10 - z11, z00)
        a = np.where(second, z11 - z01, z10 - z00)
        b = np.where(second == main, z01 - z00, z11 - z10)
        return c0 + a * u + b * v


def _grid_mesh(world, tris) -> _GridMesh | None:
    """The mesh as a :class:`_GridMesh` when it is one, else ``None``: vertices on an
    axis-aligned lattice (every node present once), each lattice cell split into two triangles
    along one of its diagonals (Blender's triangulation of the quads, as read).  Then a point's
    triangle follows from its place in its lattice cell, and its height is that triangle's
    plane there: the general rasterization's heights (to round-off) for 200 m x 200 m at
    0.25 m in ~40 ms instead of ~0.14 s, and the feet's heights without ray casts."""
    xy = world[:, :2]
    lo = _column_min(xy)
    n, step = [], []
    for k in (0, 1):                                        # lattice columns, then rows
        gaps = np.diff(np.sort(xy[:, k]))
        if not len(gaps) or gaps.max() <= 0.0:
            return None
        n.append(1 + int((gaps > 0.5 * gaps.max()).sum()))  # a lattice's gaps: 0 or a step
        step.append((xy[:, k].max() - lo[k]) / (n[-1] - 1))
    step = np.array(step)
    idx = np.rint((xy - lo) / step).astype(np.int64)
    if n[0] * n[1] != len(world) or np.abs(lo + idx * step - xy).max() > 1e-4 * step.min():
        return None
    ix, iy = np.ascontiguousarray(idx.T)
    node = iy * n[0] + ix
    if len(np.unique(node)) != len(node):
        return None
    Z = np.empty(len(node))
    Z[node] = world[:, 2]
    Z = Z.reshape(n[1], n[0])
    # Each triangle within one lattice cell; the cell's diagonal from the corners it holds.
    # (Column by column: numpy's reductions along a short last axis cost ~10x more here.)
    ti, tj = ix[tris], iy[tris]                            # (k, 3)
    ti0, ti1, ti2, tj0, tj1, tj2 = ti[:, 0], ti[:, 1], ti[:, 2], tj[:, 0], tj[:, 1], tj[:, 2]
    ci = np.minimum(np.minimum(ti0, ti1), ti2)
    cj = np.minimum(np.minimum(tj0, tj1), tj2)
    if ((np.maximum(np.maximum(ti0, ti1), ti2) - ci != 1).any()
            or (np.maximum(np.maximum(tj0, tj1), tj2) - cj != 1).any()):
        return None
    # A triangle's corners as bits (0: (0,0) 1: (1,0) 2: (0,1) 3: (1,1)): 11, 13 / 7, 14.
    mask = ((1 << ((ti0 - ci) + 2 * (tj0 - cj))) + (1 << ((ti1 - ci) + 2 * (tj1 - cj)))
            + (1 << ((ti2 - ci) + 2 * (tj2 - cj))))
    cell_id = cj * (n[0] - 1) + ci
    cells = (n[0] - 1) * (n[1] - 1)
    both = np.bincount(cell_id, weights=mask, minlength=cells)
    # Two triangles a cell, split along (0,0)-(1,1) (11 + 13) or (1,0)-(0,1) (7 + 14): no
    # holes (0 or one triangle), overlaps or other shapes (no other sums give 24 or 21).
    if ((both != 24) & (both != 21)).any():
        return None
    return _GridMesh(lo, step, n, Z, both == 24)


def _fill_nearest(h):
    """Fill NaN holes along rows, then columns, from the nearest finite neighbour (in place)."""
    if not np.isnan(h).any():
        return
    for grid in (h, h.T):
        for row in grid:
            ok = np.isfinite(row)
            if ok.any() and not ok.all():
                idx = np.flatnonzero(ok)
                nearest = idx[np.clip(np.searchsorted(idx, np.arange(len(row))), 0, len(idx) - 1)]
                left = idx[np.clip(np.searchsorted(idx, np.arange(len(row))) - 1, 0, len(idx) - 1)]
                pick = np.where(np.abs(left - np.arange(len(row))) <
                                np.abs(nearest - np.arange(len(row))), left, nearest)
                row[~ok] = row[pick[~ok]]


def mesh_from_height_field(bpy, field: HeightField, name: str, step: int = 1):
    """A grid mesh through every ``step``-th sample of ``field`` (world coordinates)."""
    x_lo, _, y_lo, _ = field.extent
    xs = x_lo + field.cell * np.arange(0, field.nx, step)
    ys = y_lo + field.cell * np.arange(0, field.ny, step)
    X, Y = np.meshgrid(xs, ys)
    Z = field.derivatives(X, Y)[0]
    return grid_mesh(bpy, np.stack([X, Y, Z], -1), name)


def grid_mesh(bpy, co, name: str):
    """A mesh of quads through a grid of points ``co`` (ny, nx, 3), row by row."""
    ny, nx = co.shape[:2]
    ii, jj = np.meshgrid(np.arange(nx - 1), np.arange(ny - 1))
    a = (jj * nx + ii).ravel()
    quads = np.stack([a, a + 1, a + nx + 1, a + nx], -1).reshape(-1)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(nx * ny)
    mesh.vertices.foreach_set("co", np.asarray(co, np.float32).reshape(-1))
    mesh.loops.add(len(quads))
    mesh.loops.foreach_set("vertex_index", quads.astype(np.int32))
    n_faces = len(quads) // 4
    mesh.polygons.add(n_faces)
    mesh.polygons.foreach_set("loop_start", (4 * np.arange(n_faces)).astype(np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(n_faces, 4, dtype=np.int32))
    mesh.update()
    mesh.validate()
    return mesh

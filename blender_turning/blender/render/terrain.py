"""The render job's terrain: a snowy mountain from ``core.ground.terrain_gen.ski_slope``, a
hill with a road for the cyclist, the tracks the figures leave in the snow, one follow camera per
figure and a sheet of their shots.  Used by ``scripts/render_job.py`` (``[terrain.<name>]``
tables, a figure's ``ground``, ``camera.follow = "each"``)."""
from __future__ import annotations

import math

import numpy as np

from ...core.sports import sport
from ...core.ground.terrain import HeightField
from ...core.ground.terrain_gen import ski_slope
from ...mapping.rig_spec import load_rig
from ...mapping.sports.skid_pose import brushed_half_width, equipment_length

#: Stops of exposure (see :func:`light_the_snow`); the colours below are before it.
EXPOSURE = 1.6
SNOW = (0.96, 0.97, 1.0, 1.0)
GRASS = (0.10, 0.15, 0.07, 1.0)
ROAD = (0.05, 0.05, 0.055, 1.0)
TRACK = (0.16, 0.20, 0.30, 1.0)       # the groove's shaded, blue-grey snow
SKY = (0.07, 0.15, 0.34)              # a clear blue after the exposure


def hill(length, width, height, spread, cell, at):
    """A hill across a strip ``width`` (x) by ``length`` (y) centred on ``at``: a Gaussian ridge
    across y, ``height`` high, ``spread`` its standard deviation along y (m)."""
    xs = np.arange(-width / 2, width / 2 + 0.5 * cell, cell)
    ys = np.arange(-length / 2, length / 2 + 0.5 * cell, cell)
    X, Y = np.meshgrid(xs, ys)
    h = height * np.exp(-0.5 * (Y / spread) ** 2) * (1.0 - 0.1 * (X / width) ** 2)
    return HeightField(h, float(at[0] + xs[0]), float(at[1] + ys[0]), cell)


def height_field(spec) -> HeightField:
    """The height field of one ``[terrain.<name>]`` table (already validated)."""
    if spec["kind"] == "ski_slope":            # centred on the origin
        return ski_slope(spec["length"], spec["width"], spec["slope_deg"], spec["cell"],
                         int(spec["seed"]), spec["moguls"])
    return hill(spec["length"], spec["width"], spec["height"], spec["spread"], spec["cell"],
                spec["at"])


#: m: the terrain renders as tiles about this size.  Workbench leaves out of a frame every tile
#: neither seen nor shadowing what is seen, and its shadows cost by the triangle: a figure's shot
#: of the demo 0.53 -> 0.28 s CPU a frame, the school's 0.77 -> 0.49 s (BENCHMARKS.md).
TILE = 25.0


def make_terrain(bpy, name, spec, material):
    """The ground mesh of ``spec`` (smooth shaded), linked to the scene: the figures' Ground,
    which their tracks drape on, hidden from the render, which draws its :func:`render_tiles`."""
    from ..scene.ground import mesh_from_height_field
    field = height_field(spec)
    mesh = mesh_from_height_field(bpy, field, name)
    mesh.polygons.foreach_set("use_smooth", np.ones(len(mesh.polygons), bool))
    mesh.materials.append(material(bpy, f"{name} {spec['surface']}",
                                   SNOW if spec["surface"] == "snow" else GRASS))
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    render_tiles(bpy, obj, (field.ny, field.nx), max(1, round(TILE / field.cell)))
    if spec["kind"] == "hill" and spec["road"] > 0:
        make_road(bpy, obj, field, spec, material)
    return obj


def render_tiles(bpy, obj, shape, cells: int) -> list:
    """Copies of the grid mesh ``obj`` (``shape`` = (rows, columns) of vertices) in tiles of
    ``cells`` x ``cells`` quads, sharing their border vertices, each with the whole mesh's
    vertex normals (so the shading is the same across a border); ``obj`` is hidden from the
    render.  Returns the tiles."""
    from ..scene.ground import grid_mesh
    ny, nx = shape
    me = obj.data
    co = np.empty(3 * len(me.vertices), np.float32)
    me.vertices.foreach_get("co", co)
    nor = np.empty_like(co)
    me.vertex_normals.foreach_get("vector", nor)
    co, nor = co.reshape(ny, nx, 3), nor.reshape(ny, nx, 3)
    tiles = []
    for j in range(0, ny - 1, cells):
        for i in range(0, nx - 1, cells):
            rows, cols = slice(j, min(j + cells, ny - 1) + 1), slice(i, min(i + cells, nx - 1) + 1)
            mesh = grid_mesh(bpy, co[rows, cols], f"{obj.name} tile")
            mesh.polygons.foreach_set("use_smooth", np.ones(len(mesh.polygons), bool))
            mesh.normals_split_custom_set_from_vertices(nor[rows, cols].reshape(-1, 3).tolist())
            for mat in me.materials:
                mesh.materials.append(mat)
            tile = bpy.data.objects.new(mesh.name, mesh)
            tile.matrix_world = obj.matrix_world
            for coll in obj.users_collection:
                coll.objects.link(tile)
            tiles.append(tile)
    obj.hide_render = True
    return tiles


def _draped_strip(bpy, name, ground_obj, x, y, half_width, lift, material, rgba, offsets=(0.0,)):
    """Ribbons of quads along ``(x, y)`` (n,), each ``offsets`` metres to the left of it and
    ``half_width`` (a number or (n,)) either side of that, every vertex a ray cast onto
    ``ground_obj`` lifted by
    ``lift``: they lie on the surface, not on a plane.  One mesh; faces in order along the path
    (all ribbons' k-th quads together)."""
    from mathutils.bvhtree import BVHTree
    dg = bpy.context.evaluated_depsgraph_get()
    bvh = BVHTree.FromObject(ground_obj, dg)
    p = np.stack([x, y], 1)
    d = np.gradient(p, axis=0)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)
    side = np.stack([-d[:, 1], d[:, 0]], 1)
    half = np.broadcast_to(np.asarray(half_width, float), (len(p),))[:, None]
    verts = []
    for off in offsets:
        for sgn in (-1.0, 1.0):
            for q in p + (off + sgn * half) * side:
                hit = bvh.ray_cast((float(q[0]), float(q[1]), 1e3), (0.0, 0.0, -1.0))[0]
                verts.append((q[0], q[1], (hit[2] if hit is not None else 0.0) + lift))
    n = len(p)
    faces = [(2 * r * n + k, 2 * r * n + k + 1, (2 * r + 1) * n + k + 1, (2 * r + 1) * n + k)
             for k in range(n - 1) for r in range(len(offsets))]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.materials.append(material(bpy, name.split(".")[0], rgba))
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def make_road(bpy, hill_obj, field, spec, material):
    """A straight road up the hill's length through its middle, ``spec['road']`` wide."""
    x_lo, x_hi, y_lo, y_hi = field.extent
    y = np.arange(y_lo + 1.0, y_hi - 1.0, 0.5)
    x = np.full_like(y, 0.5 * (x_lo + x_hi))
    _draped_strip(bpy, "Road", hill_obj, x, y, spec["road"] / 2, 0.02, material, ROAD)


def make_tracks(bpy, fig_obj, ground_obj, material, frames):
    """The figure's tracks in the snow: a shaded groove ribbon along the baked foot point (a ski
    pair's width, a board's), growing behind the figure (a Build modifier reveals its faces in
    order, one a frame).  Where the figure skids (its baked ``turn_skid``) each ski or the
    board brushes a band ``length |sin skid|`` wide instead (docs/skidding.md Section 8)."""
    from ..anim import bake
    bag = bake.baked_channels(fig_obj)
    fcs = {fc.array_index: fc for fc in bag.fcurves if fc.data_path == "location"}
    xy = np.array([[fcs[i].evaluate(f) for i in range(2)] for f in frames])
    skid_fc = next((fc for fc in bag.fcurves if fc.data_path == '["turn_skid"]'), None)
    skid = np.array([skid_fc.evaluate(f) for f in frames]) if skid_fc else np.zeros(len(xy))
    record = sport(fig_obj.turning.sport)
    half, offsets = record.snow_tracks
    half = brushed_half_width(half, equipment_length(load_rig(record.name)), skid)
    obj = _draped_strip(bpy, f"Track {fig_obj.name}", ground_obj, xy[:, 0], xy[:, 1], half,
                        0.03, material, TRACK, offsets)
    build = obj.modifiers.new("Grow", "BUILD")
    build.frame_start, build.frame_duration = float(frames[0]), float(len(frames) - 1)
    return obj


def make_follow_cameras(bpy, figures, distance, height, lens):
    """One camera per figure, behind it (uphill of its mean direction) and to its side, aimed at
    its body; returns ``[(figure name, camera)]``."""
    from .. import compat
    scene = bpy.context.scene
    frames = np.arange(scene.frame_start, scene.frame_end + 1)
    out = []
    for fig in figures:
        locs = key_locations(compat, fig, frames)
        # The aim point: the body's middle.
        target = follow_target(bpy, f"Camera Target {fig.name}", locs, frames)
        d = locs[-1, :2] - locs[0, :2]
        d = d / np.linalg.norm(d) if np.linalg.norm(d) > 1e-6 else np.array([0.0, 1.0])
        side = np.array([-d[1], d[0]])
        offset = -0.75 * distance * d + 0.65 * distance * side
        out.append((fig.name, tracking_camera(bpy, f"Camera {fig.name}", lens,
                                              (offset[0], offset[1], height), target)))
    return out


def key_locations(compat, obj, frames) -> np.ndarray:
    """``obj``'s keyed location at every frame of ``frames``: shape ``(frames, 3)``."""
    from ..anim import bake
    fcs = {fc.array_index: fc for fc in bake.baked_channels(obj).fcurves
           if fc.data_path == "location"}
    return np.array([[fcs[i].evaluate(f) for i in range(3)] for f in frames])


def follow_target(bpy, name, aim, frames):
    """An empty keyed at ``aim`` (``(frames, 3)``) 0.9 m up, smoothed over half a second so a
    shot aimed at it does not swing with every turn."""
    from .. import compat
    from ..anim import bake
    scene = bpy.context.scene
    k = max(1, int(round(0.5 * scene.render.fps)))
    kernel = np.ones(k) / k
    smooth = np.stack([np.convolve(np.pad(aim[:, i], (k // 2, k - 1 - k // 2), mode="edge"),
                                   kernel, mode="valid") for i in range(3)], 1)
    target = bpy.data.objects.new(name, None)
    scene.collection.objects.link(target)
    compat.assign_new_action(target, target.name)
    bake.write_channels(compat.channels(target),
                        [("location", i, "Object Transforms", smooth[:, i] + (i == 2) * 0.9)
                         for i in range(3)], np.asarray(frames, float))
    return target


def tracking_camera(bpy, name, lens, offset, target):
    """A camera at ``offset`` from ``target`` (it moves with it) that looks at it."""
    cam_data = bpy.data.cameras.new(name)
    cam_data.lens = lens
    cam = bpy.data.objects.new(name, cam_data)
    bpy.context.scene.collection.objects.link(cam)
    cam.location = offset
    c = cam.constraints.new("COPY_LOCATION")
    c.target, c.use_offset = target, True
    c = cam.constraints.new("TRACK_TO")
    c.target, c.track_axis, c.up_axis = target, "TRACK_NEGATIVE_Z", "UP_Y"
    return cam


def light_the_snow(bpy):
    """White snow under a blue sky: the sky colour as the world, the Standard view transform
    (Filmic / AgX would map the near-white snow to a light grey) and a sun."""
    scene = bpy.context.scene
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.color = SKY
    scene.view_settings.view_transform = "Standard"
    # Workbench's studio light shades a white slope seen at a slant to ~0.3 (linear; 190 of 255
    # in the PNG): EXPOSURE stops up put the snow near white and keep the slopes facing away a
    # lighter grey, so the shape still shows.
    scene.view_settings.exposure = EXPOSURE
    sun_data = bpy.data.lights.new("Sun", "SUN")
    sun_data.energy = 3.0
    sun = bpy.data.objects.new("Sun", sun_data)
    sun.rotation_euler = (math.radians(40), 0.0, math.radians(30))
    scene.collection.objects.link(sun)


def contact_sheet(bpy, pngs, out_path, columns=2):
    """One PNG of the given frames (same size) in a grid, ``columns`` wide."""
    imgs = []
    for p in pngs:
        im = bpy.data.images.load(str(p))
        w, h = im.size
        px = np.empty(w * h * 4, np.float32)
        im.pixels.foreach_get(px)
        imgs.append(px.reshape(h, w, 4))
        bpy.data.images.remove(im)
    h, w = imgs[0].shape[:2]
    rows = math.ceil(len(imgs) / columns)
    sheet = np.ones((rows * h, columns * w, 4), np.float32)
    for k, px in enumerate(imgs):
        r, c = divmod(k, columns)
        sheet[(rows - 1 - r) * h:(rows - r) * h, c * w:(c + 1) * w] = px   # Blender: bottom up
    out = bpy.data.images.new("sheet", columns * w, rows * h, alpha=True)
    out.pixels.foreach_set(sheet.ravel())
    out.filepath_raw = str(out_path)
    out.file_format = "PNG"
    out.save()
    bpy.data.images.remove(out)

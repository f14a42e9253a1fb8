"""The render job's scene: path curves, obstacle objects, the figures (added and baked by the
add-on's own operators), the camera that follows them, the ground and the light, and the render
settings."""
from __future__ import annotations

import math
import time

from .config import GPU_BACKENDS, ConfigError
from .output import log


def _material(bpy, name, rgba):
    from .. import compat
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.diffuse_color = rgba
    compat.set_base_color(mat, rgba, 0.6, 0.0)
    return mat


def make_path(bpy, name, points):
    curve = bpy.data.curves.new(f"Path {name}", "CURVE")
    curve.dimensions = "3D"
    curve.bevel_depth = 0.04
    sp = curve.splines.new("BEZIER")
    sp.bezier_points.add(len(points) - 1)
    for bp, (x, y) in zip(sp.bezier_points, points):
        bp.co = (x, y, 0.02)
        bp.handle_left_type = bp.handle_right_type = "AUTO"
    obj = bpy.data.objects.new(f"Path {name}", curve)
    bpy.context.scene.collection.objects.link(obj)
    curve.materials.append(_material(bpy, "Path", (0.1, 0.6, 0.1, 1.0)))
    return obj


def make_obstacles(bpy, obstacles):
    groups = {}
    for i, o in enumerate(obstacles):
        coll = groups.get(o["group"])
        if coll is None:
            coll = groups[o["group"]] = bpy.data.collections.new(o["group"])
            bpy.context.scene.collection.children.link(coll)
        mesh = bpy.data.meshes.new(f"{o['group']}.{i}")
        s, h = o["size"] / 2, o["height"]
        if o["kind"] == "pole":
            n = 12
            ring = [(s * math.cos(2 * math.pi * k / n), s * math.sin(2 * math.pi * k / n))
                    for k in range(n)]
            verts = [(x, y, 0.0) for x, y in ring] + [(x, y, h) for x, y in ring]
            faces = [(k, (k + 1) % n, n + (k + 1) % n, n + k) for k in range(n)]
            faces += [tuple(range(n - 1, -1, -1)), tuple(range(n, 2 * n))]
        else:
            verts = [(x, y, z) for z in (0.0, h) for x, y in ((-s, -s), (s, -s), (s, s), (-s, s))]
            faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                     (3, 0, 4, 7)]
        mesh.from_pydata(verts, [], faces)
        mesh.materials.append(_material(bpy, "Gate", (0.85, 0.1, 0.1, 1.0) if i % 2 == 0
                                        else (0.1, 0.2, 0.85, 1.0)))
        obj = bpy.data.objects.new(mesh.name, mesh)
        obj.location = (*o["at"], 0.0)
        coll.objects.link(obj)
    return groups


def add_figure(bpy, fig, cfg, paths, groups, grounds):
    scene = bpy.context.scene
    scene.cursor.location = (*fig["start"], 0.0)
    scene.cursor.rotation_euler = (0.0, 0.0, math.radians(fig["direction_deg"]) - math.pi / 2)
    bpy.ops.turning.add_figure(sport=fig["sport"].upper())
    obj = bpy.context.view_layer.objects.active
    obj.name = fig["name"]
    for child in obj.children:
        child.name = f"{obj.name} Body"
    s = obj.turning
    s.period = fig["period"]
    s.lean = math.radians(fig["lean_deg"])
    s.use_heading = fig["heading_deg"] is not None
    if s.use_heading:
        s.heading = math.radians(fig["heading_deg"])
    if fig["speed"] is not None:
        s.speed = fig["speed"]
    if fig["body"] is not None:                      # a crowd's follower: its own body
        s.mass, s.com_height, s.inertia = (fig["body"][k] for k in ("mass", "com_height",
                                                                     "inertia"))
    s.crowd.time_offset = fig["time_offset"]         # a waiting follower's start
    if fig["ground"] is not None:                    # rides on that terrain's mesh
        s.ground = grounds[fig["ground"]]
        s.terrain.target_speed = fig["target_speed"]
        s.skid.style = fig["style"].upper()          # docs/skidding.md: how it brakes
        scene = bpy.context.scene
        stop = None if fig["stop_s"] is None else \
            scene.frame_start + round(fig["stop_s"] * scene.render.fps)
        if stop is not None and stop <= scene.frame_end:  # a stop after the job's end: none
            s.skid.use_stop, s.skid.stop_frame = True, stop
    if fig["control"] == "path":
        s.path = paths[fig["path"]]
        s.obstacles = groups.get(fig["obstacles"]) if fig["obstacles"] else None
        if fig["plan_curvature_rate"] is not None:    # else the sport preset's
            s.plan_curvature_rate = fig["plan_curvature_rate"]
    return obj


def bake_figure(bpy, obj, fig, frame_end):
    scene = bpy.context.scene
    scene.frame_end = frame_end
    t = time.perf_counter()
    op = bpy.ops.turning.follow_path if fig["control"] == "path" else bpy.ops.turning.bake_turns
    op()                                       # a failure raises RuntimeError with the report
    log(f"baked {obj.name} ({fig['sport']}, {fig['control']}) in "
        f"{time.perf_counter() - t:.2f} s")
    scene.frame_end = frame_end


def _sampled_locations(bpy, obj, frames):
    from ..anim import bake
    bag = bake.baked_channels(obj)
    fcs = {fc.array_index: fc for fc in bag.fcurves if fc.data_path == "location"}
    return [[fcs[i].evaluate(f) for i in range(3)] for f in frames]


def make_camera(bpy, cfg, figures):
    import numpy as np
    from ..anim import bake
    scene = bpy.context.scene
    frames = list(range(scene.frame_start, scene.frame_end + 1))
    follow = cfg["camera"]["follow"]
    chosen = figures if follow == "all" else [o for o in figures if o.name == follow]
    if not chosen:
        raise ConfigError(f"camera.follow = {follow!r} is not 'all' or a figure's name")
    locs = np.mean([_sampled_locations(bpy, o, frames) for o in chosen], axis=0)
    target = bpy.data.objects.new("Camera Target", None)
    scene.collection.objects.link(target)
    target.animation_data_create()
    from .. import compat
    compat.assign_new_action(target, "Camera Target")
    bake.write_channels(compat.channels(target),
                        [("location", i, "Object Transforms", locs[:, i] + (i == 2) * 1.0)
                         for i in range(3)], np.asarray(frames, float))
    d = locs[-1, :2] - locs[0, :2]
    d = d / np.linalg.norm(d) if np.linalg.norm(d) > 1e-6 else np.array([0.0, 1.0])
    side = np.array([-d[1], d[0]])
    dist, h = cfg["camera"]["distance"], cfg["camera"]["height"]
    # One figure: a three-quarter view from its side; all: from behind, so that figures side by
    # side spread across the picture.
    offset = (-0.9 * dist * d + 0.35 * dist * side) if len(chosen) > 1 else \
        (-0.55 * dist * d + 0.85 * dist * side)
    cam_data = bpy.data.cameras.new("Camera")
    cam_data.lens = cfg["camera"]["lens"]
    cam = bpy.data.objects.new("Camera", cam_data)
    scene.collection.objects.link(cam)
    cam.location = (offset[0], offset[1], h)
    c = cam.constraints.new("COPY_LOCATION")
    c.target, c.use_offset = target, True
    c = cam.constraints.new("TRACK_TO")
    c.target, c.track_axis, c.up_axis = target, "TRACK_NEGATIVE_Z", "UP_Y"
    scene.camera = cam
    return locs


def make_ground_and_light(bpy, cfg, locs, figures):
    import numpy as np
    scene = bpy.context.scene
    pts = [locs[:, :2]]
    for o in figures:
        tr = o.turning.foot_track
        if tr is not None:
            co = np.empty(4 * len(tr.data.splines[0].points))
            tr.data.splines[0].points.foreach_get("co", co)
            pts.append(co.reshape(-1, 4)[:, :2])
    pts = np.vstack(pts)
    lo, hi = pts.min(axis=0) - 40.0, pts.max(axis=0) + 40.0
    mesh = bpy.data.meshes.new("Ground")
    mesh.from_pydata([(lo[0], lo[1], 0), (hi[0], lo[1], 0), (hi[0], hi[1], 0), (lo[0], hi[1], 0)],
                     [], [(0, 1, 2, 3)])
    color = (0.92, 0.94, 0.98, 1.0) if cfg["ground"] == "snow" else (0.25, 0.25, 0.27, 1.0)
    mesh.materials.append(_material(bpy, "Ground", color))
    ground = bpy.data.objects.new("Ground", mesh)
    scene.collection.objects.link(ground)
    sun_data = bpy.data.lights.new("Sun", "SUN")
    sun_data.energy = 3.0
    sun = bpy.data.objects.new("Sun", sun_data)
    sun.rotation_euler = (math.radians(50), 0.0, math.radians(30))
    scene.collection.objects.link(sun)
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.color = (0.55, 0.7, 0.9)


def setup_render(bpy, cfg):
    from .. import compat
    scene = bpy.context.scene
    r, rc = scene.render, cfg["render"]
    r.engine = {"WORKBENCH": "BLENDER_WORKBENCH", "EEVEE": compat.EEVEE_ENGINE,
                "CYCLES": "CYCLES"}[rc["engine"]]
    r.resolution_x, r.resolution_y = rc["resolution"]
    r.resolution_percentage = 100
    scene.frame_step = cfg["frame_step"]
    if rc["engine"] == "WORKBENCH":
        shading = scene.display.shading
        shading.light, shading.color_type = "STUDIO", "MATERIAL"
        shading.show_shadows = True
        scene.display.render_aa = rc["antialiasing"]
    elif rc["engine"] == "CYCLES":
        scene.cycles.samples = rc["samples"]
        scene.cycles.device = rc["device"]
    else:
        eevee = scene.eevee
        if hasattr(eevee, "taa_render_samples"):
            eevee.taa_render_samples = rc["samples"]
    # Relative to the saved .blend ("//"), which is saved in the output folder: the .blend can
    # move to a farm's storage and its frames land next to it.
    if rc["format"] == "VIDEO":
        compat.set_output_format(scene, "VIDEO")
        r.filepath = f"//{cfg['name']}.mp4"
    else:
        compat.set_output_format(scene, "PNG")
        r.filepath = "//frames/frame_"


def use_gpu(bpy) -> str:
    """Point Cycles at the first GPU backend with a device (in this session's preferences: a
    farm worker opening the .blend uses its own, see docs/render-farms.md); the backend's
    name, or :class:`ConfigError` naming ``--device`` where there is none."""
    prefs = bpy.context.preferences.addons["cycles"].preferences
    for backend in GPU_BACKENDS:
        try:
            prefs.compute_device_type = backend
        except TypeError:                         # not built into this Blender
            continue
        prefs.refresh_devices()
        gpus = [d for d in prefs.devices if d.type == backend]
        if gpus:
            for d in prefs.devices:
                d.use = d.type == backend
            return backend
    prefs.compute_device_type = "NONE"
    raise ConfigError("--device = 'GPU': Cycles finds no GPU on this machine (tried "
                      f"{', '.join(GPU_BACKENDS)}); render with --device CPU")

"""Headless job: build a scene from a TOML config, bake the figures, save a .blend, render.

    blender -b --python scripts/render_job.py -- --config scripts/configs/demo.toml
    python scripts/render_job.py --config scripts/configs/demo.toml      # on the bpy wheel

The scene: a ground plane, the figures (each baked with the parametric controller, ``control =
"turns"``, or along a path around obstacles, ``control = "path"``), the path curves, the obstacle
objects, a camera that follows the figures and a sun.  Frames go to ``<output>/frames/`` (PNG) or
``<output>/<name>.mp4`` (``format = "VIDEO"``); the scene to ``<output>/<name>.blend``.  A bad
config exits with status 2 and one line naming the problem; a failed bake with status 1.
See ``scripts/configs/*.toml`` for the format.

On a render farm: bake once, then render chunks with plain ``blender -b job.blend -s A -e B -a``
on any farm::

    blender -b --python scripts/render_job.py -- --config job.toml --no-render --output shared/job
    blender -b shared/job/job.blend -s 1 -e 24 -a          # one farm task per chunk of frames

The saved .blend holds its output path relative to itself (``//frames/frame_``), so it can move
to the farm's storage and its frames land next to it.  ``--frames A-B`` renders one chunk of the
job's frames (after saving the whole range in the .blend); ``--device GPU`` renders Cycles on the
GPU and fails with one line (exit 2) where Cycles finds none -- no silent CPU fallback, which
would make a farm task tens of times slower unnoticed.  ``scripts/flamenco/
turning_bake_render.js`` is a Flamenco job type doing the bake once and then the chunks.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:                      # inside a Blender binary: find the package
    sys.path.insert(0, str(ROOT))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-job-"))

from blender_turning.core import signals  # noqa: E402
from blender_turning.core.files import (OutputLock, OutputLocked, WriteError,  # noqa: E402
                                        disk_reason, file_size_limit, temp_beside,
                                        verify_file)
from blender_turning.core.registry import SPORTS, import_extension  # noqa: E402
from blender_turning.core.ranges import RANGES, Range  # noqa: E402
from blender_turning.core.validate import Fields, check, nearest, read_text  # noqa: E402

sys.path.insert(0, str(ROOT / "scripts"))
import render_crowds  # noqa: E402
import render_terrain  # noqa: E402

ENGINES = ("WORKBENCH", "EEVEE", "CYCLES")
DEVICES = ("CPU", "GPU")
#: Workbench's render anti-aliasing (``scene.display.render_aa``): FXAA is one screen-space pass;
#: the numbers are samples per pixel (Blender's default is 8).
WORKBENCH_AA = ("OFF", "FXAA", "5", "8", "11", "16", "32")
GPU_BACKENDS = ("OPTIX", "CUDA", "HIP", "ONEAPI", "METAL")     # Cycles' compute_device_type


class ConfigError(ValueError):
    """A config that cannot be run (the message names the key)."""


# -- config --------------------------------------------------------------------------------------
# Every value is checked here, before anything is built, against the core's table of ranges
# (blender_turning/core/ranges.py) with the field validator every file format uses.

_KNOWN = {
    "": {"job", "render", "camera", "ground", "figures", "paths", "obstacles", "terrain",
         "crowds"},
    "job": {"name", "seconds", "fps", "frame_step", "output"},
    "render": {"engine", "resolution", "format", "samples", "antialiasing",
               "crowd_antialiasing"},
    "camera": {"follow", "distance", "height", "lens"},
    "ground": {"kind"},
    "path": {"points"},
    "obstacle": {"group", "kind", "at", "size", "height"},
    "figure": {"sport", "control", "name", "start", "direction_deg", "period", "lean_deg",
               "heading_deg", "path", "obstacles", "plan_curvature_rate", "ground", "speed",
               "target_speed", "tracks"},
    "terrain": {"kind", "surface", "length", "width", "slope_deg", "cell", "seed", "moguls",
                "at", "height", "spread", "road"},
}


def _terrains(top) -> dict:
    """``[terrain.<name>]`` tables: a ``ski_slope`` mountain (core.terrain_gen) or a ``hill``
    with an optional road; each becomes a Ground mesh figures can ride on."""
    out = {}
    tt = top.table("terrain")
    for name in tt.keys():
        t = tt.table(name, _KNOWN["terrain"])
        kind = t.string("kind", "ski_slope", choices=("ski_slope", "hill"))
        out[name] = {"kind": kind,
                     "surface": t.string("surface", "snow" if kind == "ski_slope" else "grass",
                                         choices=("snow", "grass")),
                     "length": t.number("length", "terrain_size", 200.0),
                     "width": t.number("width", "terrain_size", 200.0),
                     "slope_deg": t.number("slope_deg", "terrain_slope", 18.0),
                     "cell": t.number("cell", "terrain_cell", 1.0),
                     "seed": t.number("seed", "terrain_seed", 7),
                     "moguls": t.boolean("moguls", True),
                     "at": tuple(float(v) for v in t.xy("at", [0.0, 0.0])),
                     "height": t.number("height", "hill_height", 3.0),
                     "spread": t.number("spread", "terrain_size", 12.0),
                     "road": t.number("road", "road_width", 0.0)}
    return out


def _file_name(f, key, default):
    """A plain file name (the job's .blend and video are named after it): no folders, so the
    output stays inside the output folder."""
    name = f.string(key, default)
    if (not name.strip() or name in (".", "..") or any(c in name for c in "/\\\0")
            or name.startswith(".")):
        f.fail(key, f"= {name!r} is not a plain file name (no folders, not hidden)")
    return name


def _resolution(given, where):
    """``[width, height]`` from a list or a ``WIDTHxHEIGHT`` string, each in pixels."""
    size = given
    if isinstance(given, str):
        try:
            size = [int(v) for v in given.lower().split("x")]
        except ValueError:
            size = None
    if not isinstance(size, list) or len(size) != 2:
        raise ConfigError(f"{where} = {given!r} should be "
                          f"{'WIDTHxHEIGHT' if isinstance(given, str) else '[width, height]'} "
                          "in pixels")
    return [check(f"{where}[{i}]", v, "pixels") for i, v in enumerate(size)]


def check_output(out: Path, flag: str) -> None:
    """The output folder can be created and written (checked before anything is built): it is a
    folder or does not exist yet, and its nearest existing folder takes a new file."""
    if out.exists() and not out.is_dir():
        raise ConfigError(f"{flag} = {str(out)!r} is a file, not a folder")
    probe = out
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        raise ConfigError(f"{flag} = {str(out)!r}: {str(probe)!r} is a file, not a folder")
    try:
        tmp = temp_beside(probe / "probe")
    except OSError as exc:
        raise ConfigError(f"{flag} = {str(out)!r} cannot be written: "
                          f"{exc.strerror or exc}") from None
    tmp.unlink()


def _frames(given: str, last: int):
    """``(first, last)`` of ``--frames A-B`` (or ``A``): whole frames inside the job's
    ``1..last``, ``A <= B``."""
    parts = given.strip().split("-")
    try:
        pair = [int(v) for v in parts]
    except ValueError:
        pair = []
    if len(pair) not in (1, 2):
        raise ConfigError(f"--frames = {given!r} should be A-B (first and last frame) or A")
    job = Range(1, last, "", "the job's frames", integer=True)
    a = check("--frames first", pair[0], job)
    b = check("--frames last", pair[-1], Range(a, last, "", "the job's frames", integer=True))
    return a, b


def _cli_choice(given, flag, choices):
    value = given.upper()
    if value not in choices:
        raise ConfigError(f"{flag} = {given!r} is not one of {', '.join(choices)}")
    return value


def read_figure(f, earlier, paths, obstacles, terrains) -> dict:
    """One ``[[figures]]`` table (or a crowd's leader), checked against the config's paths,
    obstacle groups, terrains and the ``earlier`` figures' names."""
    lean, heading = RANGES["theta_max"].deg(), RANGES["heading"].deg()
    sport = f.string("sport").lower()
    if sport not in SPORTS:
        f.fail("sport", f"= {sport!r} is not one of {', '.join(SPORTS)}")
    fig = {"sport": sport, "control": f.string("control", "turns", choices=("turns", "path")),
           "name": f.string("name", SPORTS[sport].label),
           "start": tuple(float(v) for v in f.xy("start", [0.0, 0.0])),
           "direction_deg": f.number("direction_deg", heading, 90.0),
           "period": f.number("period", "period", 2.0),
           "lean_deg": f.number("lean_deg", lean, 20.0),
           "heading_deg": f.number("heading_deg", heading, None),
           "path": f.string("path", None),
           "obstacles": f.string("obstacles", None),
           "plan_curvature_rate": f.number("plan_curvature_rate", "plan_curvature_rate",
                                           None),
           "ground": f.string("ground", None),
           "speed": f.number("speed", "V_cm", None),
           "target_speed": f.number("target_speed", "target_speed", 0.0),
           "tracks": f.boolean("tracks", True),
           "body": None, "crowd": None, "time_offset": 0.0}
    if fig["ground"] is not None and fig["ground"] not in terrains:
        f.fail("ground", f"= {fig['ground']!r} is not a [terrain.<name>] of the config")
    fall = math.degrees(SPORTS[sport].figure.limits.theta_fall)
    if fig["lean_deg"] >= fall:
        f.fail("lean_deg", f"= {fig['lean_deg']:g} is not below the {sport}'s fall angle "
                           f"({fall:g} deg)")
    if not fig["name"].strip():
        f.fail("name", "= '' is empty")
    if any(fig["name"] == g["name"] for g in earlier):
        f.fail("name", f"= {fig['name']!r} is the name of an earlier figure")
    if fig["control"] == "path" and fig["path"] not in paths:
        f.fail("path", f"= {fig['path']!r} is not a [paths.<name>] of the config"
                       f"{nearest(fig['path'], paths) if paths and fig['path'] else ''}")
    if fig["obstacles"] and not any(o["group"] == fig["obstacles"] for o in obstacles):
        f.fail("obstacles", f"= {fig['obstacles']!r} names no obstacle group")
    return fig


def load_config(path: Path, overrides) -> dict:
    src = str(path)
    try:
        doc = tomllib.loads(read_text(path, "config"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config {src!r} is not valid TOML: {exc}") from None
    except RecursionError:
        raise ConfigError(f"config {src!r} is nested too deeply") from None
    top = Fields(doc, src).only(_KNOWN[""])
    job = top.table("job", _KNOWN["job"])
    name = _file_name(job, "name", path.stem)
    if getattr(overrides, "name", None) is not None:
        name = _file_name(Fields({"--name": overrides.name}, ""), "--name", None)
    cfg = {"name": name,
           "seconds": job.number("seconds", "job_seconds", 5.0),
           "fps": job.number("fps", "job_fps", 24),
           "frame_step": job.number("frame_step", "frame_step", 1)}
    if overrides.seconds is not None:
        cfg["seconds"] = check("--seconds", overrides.seconds, "job_seconds")
    if overrides.frame_step is not None:
        cfg["frame_step"] = check("--frame-step", overrides.frame_step, "frame_step")
    out = job.string("output", f"out/{cfg['name']}")
    if not out.strip():
        job.fail("output", f"= {out!r} is not a folder path")
    cfg["output"], flag = Path(out).resolve(), f"{src}: job.output"
    if overrides.output is not None:
        if not overrides.output.strip():
            raise ConfigError(f"--output = {overrides.output!r} is not a folder path")
        cfg["output"], flag = Path(overrides.output).resolve(), "--output"
    check_output(cfg["output"], flag)

    r = top.table("render", _KNOWN["render"])
    engine = r.string("engine", "WORKBENCH").upper()
    if engine not in ENGINES:
        r.fail("engine", f"= {engine!r} is not one of {', '.join(ENGINES)}")
    if overrides.engine is not None:
        engine = overrides.engine.upper()
        if engine not in ENGINES:
            raise ConfigError(f"--engine = {engine!r} is not one of {', '.join(ENGINES)}")
    res = _resolution(r.value("resolution", [640, 360]), f"{src}: render.resolution")
    if overrides.resolution is not None:
        res = _resolution(overrides.resolution, "--resolution")
    fmt = r.string("format", "PNG").upper()
    if fmt not in ("PNG", "VIDEO"):
        r.fail("format", f"= {fmt!r} is not PNG or VIDEO")
    cfg["render"] = {"engine": engine, "resolution": res, "format": fmt,
                     "samples": r.number("samples", "render_samples", 16), "device": "CPU",
                     "antialiasing": r.string("antialiasing", "8", choices=WORKBENCH_AA)}
    # A crowd's shot shows many thin tracks far off, which one FXAA pass breaks into dashes.
    cfg["render"]["crowd_antialiasing"] = r.string("crowd_antialiasing",
                                                   cfg["render"]["antialiasing"],
                                                   choices=WORKBENCH_AA)
    if getattr(overrides, "device", None) is not None:
        cfg["render"]["device"] = _cli_choice(overrides.device, "--device", DEVICES)
        if cfg["render"]["device"] == "GPU" and engine != "CYCLES":
            raise ConfigError(f"--device = {overrides.device!r} is for Cycles; the engine is "
                              f"{engine} (give --engine CYCLES)")
    last = 1 + int(round(cfg["seconds"] * cfg["fps"]))
    if getattr(overrides, "farm_frames", None) is not None:
        # A farm's job type cannot read the config: the bake checks the frames it will ask for.
        try:
            _frames(overrides.farm_frames, last)
        except ValueError as exc:
            raise ConfigError(f"{str(exc).replace('--frames', '--farm-frames', 1)} (the shot "
                              f"has frames 1-{last}: {cfg['seconds']:g} s at {cfg['fps']} "
                              "fps)") from None
    cfg["frames"] = None
    if getattr(overrides, "frames", None) is not None:
        if getattr(overrides, "no_render", False):
            raise ConfigError(f"--frames = {overrides.frames!r} picks frames to render; "
                              "--no-render renders none")
        cfg["frames"] = _frames(overrides.frames, 1 + int(round(cfg["seconds"] * cfg["fps"])))
    cam = top.table("camera", _KNOWN["camera"])
    cfg["camera"] = {"follow": cam.string("follow", "all"),
                     "distance": cam.number("distance", "camera_distance", 16.0),
                     "height": cam.number("height", "camera_height", 6.0),
                     "lens": cam.number("lens", "lens", 35.0)}
    cfg["ground"] = top.table("ground", _KNOWN["ground"]).string("kind", "snow",
                                                                choices=("snow", "road"))
    paths = {}
    pt = top.table("paths")
    for name in pt.keys():
        pts = pt.table(name, _KNOWN["path"], required=True).points("points", 2)
        for i in range(1, len(pts)):
            if (pts[i] == pts[i - 1]).all():
                raise ConfigError(f"{src}: paths.{name}.points[{i}] = {pts[i].tolist()} is the "
                                  f"same point as paths.{name}.points[{i - 1}]; a path needs "
                                  "distinct consecutive points")
        paths[name] = [(float(x), float(y)) for x, y in pts]
    obstacles = []
    for o in top.tables("obstacles", _KNOWN["obstacle"]):
        obstacles.append({"group": o.string("group", "obstacles"),
                          "kind": o.string("kind", "pole", choices=("pole", "box")),
                          "at": tuple(float(v) for v in o.xy("at")),
                          "size": o.number("size", "object_size", 0.6),
                          "height": o.number("height", "object_height", 1.8)})
    terrains = _terrains(top)
    figures = top.tables("figures", _KNOWN["figure"])
    if not figures and not top.has("crowds"):
        raise ConfigError(f"{src}: the config has no [[figures]]")
    cfg["figures"] = []
    for f in figures:
        cfg["figures"].append(read_figure(f, cfg["figures"], paths, obstacles, terrains))
    cfg["crowds"] = render_crowds.read_crowds(top, cfg["figures"], paths, obstacles, terrains,
                                              read_figure, cfg["seconds"])
    names = [fig["name"] for fig in cfg["figures"]]
    cfg["terrain"] = terrains
    if cfg["camera"]["follow"] not in ("all", "each", *names):
        cam.fail("follow", f"= {cfg['camera']['follow']!r} is not 'all', 'each' or a figure's name "
                           f"({', '.join(names)})")
    if cfg["camera"]["follow"] == "each" and not (
            any(f["crowd"] is None for f in cfg["figures"])
            or any(c["shot"] for c in cfg["crowds"])):
        cam.fail("follow", "= 'each' gives a shot to every [[figures]] entry and every crowd "
                           "with shot = true: there is none")
    cfg["paths"], cfg["obstacles"] = paths, obstacles
    _check_object_names(cfg, src)
    return cfg


def _check_object_names(cfg, src) -> None:
    """Every figure's objects (the figure, ``<name> Body``) get exactly their names in the scene:
    Blender renames an object whose name is taken (``.001``), and then the camera, the shots'
    folders and a farm's scripts would look for the wrong one."""
    taken = {n: "an object the job makes" for n in ("Camera", "Camera Target", "Sun", "Ground")}
    taken.update((n, f"the terrain [terrain.{n}]") for n in cfg["terrain"])
    taken.update((f"Path {n}", f"the curve of [paths.{n}]") for n in cfg["paths"])
    for fig in cfg["figures"]:
        who = (f"the crowd {fig['crowd']!r}'s member {fig['name']!r}" if fig["crowd"]
               else f"the figure {fig['name']!r}")
        for name in (fig["name"], f"{fig['name']} Body"):
            if name in taken:
                raise ConfigError(f"{src}: {who} would make an object named {name!r}, the name "
                                  f"of {taken[name]}: rename one of them")
            taken[name] = who + ("'s body" if name != fig["name"] else "")


# -- scene ---------------------------------------------------------------------------------------

def log(msg: str) -> None:
    print(f"render_job: {msg}", flush=True)


def _material(bpy, name, rgba):
    from blender_turning.blender import compat
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
    from blender_turning.blender import bake
    bag = bake.baked_channels(obj)
    fcs = {fc.array_index: fc for fc in bag.fcurves if fc.data_path == "location"}
    return [[fcs[i].evaluate(f) for i in range(3)] for f in frames]


def make_camera(bpy, cfg, figures):
    import numpy as np
    from blender_turning.blender import bake
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
    from blender_turning.blender import compat
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
    from blender_turning.blender import compat
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


def run(cfg, render: bool = True) -> dict:
    import bpy
    from blender_turning import blender as addon
    if hasattr(bpy.types.Object, "turning"):     # the installed extension is enabled: use it
        return _run(bpy, cfg, render)
    addon.register()
    try:
        return _run(bpy, cfg, render)
    finally:
        # Unregister what the job registered (bpy 4.2 crashes at exit on a registered
        # PointerProperty otherwise).
        addon.unregister()


def _run(bpy, cfg, render):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if cfg["render"]["device"] == "GPU":        # before the bake: fail fast, nothing written
        log(f"Cycles renders on the GPU ({use_gpu(bpy)})")
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = cfg["fps"], 1.0
    scene.frame_start = 1
    frame_end = 1 + int(round(cfg["seconds"] * cfg["fps"]))
    scene.frame_end = frame_end
    paths = {name: make_path(bpy, name, pts) for name, pts in cfg["paths"].items()}
    groups = make_obstacles(bpy, cfg["obstacles"])
    grounds = {name: render_terrain.make_terrain(bpy, name, spec, _material)
               for name, spec in cfg["terrain"].items()}
    figures = []
    for fig in cfg["figures"]:
        obj = add_figure(bpy, fig, cfg, paths, groups, grounds)
        bake_figure(bpy, obj, fig, frame_end)
        signals.checkpoint()                     # a signal during the bake stops here
        figures.append(obj)
        spec = cfg["terrain"].get(fig["ground"])
        if spec is not None and spec["surface"] == "snow" and fig["tracks"]:
            render_terrain.make_tracks(bpy, obj, grounds[fig["ground"]], _material,
                                       range(scene.frame_start, frame_end + 1))
    cameras = []
    if cfg["camera"]["follow"] == "each":      # a shot per figure, and one per crowd
        cam = cfg["camera"]
        alone = [o for o, fig in zip(figures, cfg["figures"]) if fig["crowd"] is None]
        cameras = render_terrain.make_follow_cameras(bpy, alone, cam["distance"],
                                                     cam["height"], cam["lens"])
        cameras += render_crowds.make_crowd_cameras(bpy, cfg["crowds"], figures,
                                                    cam["distance"], cam["height"], cam["lens"])
        scene.camera = cameras[0][1]
    else:
        locs = make_camera(bpy, cfg, figures)
    if grounds:
        render_terrain.light_the_snow(bpy)
    else:
        make_ground_and_light(bpy, cfg, locs, figures)
    setup_render(bpy, cfg)
    out = cfg["output"]
    out.mkdir(parents=True, exist_ok=True)
    blend = out / f"{cfg['name']}.blend"
    save_blend(bpy, blend)
    KEPT.append(blend)
    log(f"saved {blend}")
    signals.checkpoint()
    result = {"blend": blend, "frames": None}
    if not render:
        return result
    if cfg["frames"] is not None:               # one chunk; the .blend keeps the whole range
        scene.frame_start, scene.frame_end = cfg["frames"]
    frames = list(range(scene.frame_start, scene.frame_end + 1, scene.frame_step))
    shots = [(None, scene.camera)] if not cameras else cameras
    t = time.perf_counter()
    count = [0, len(frames) * len(shots)]
    for i, (name, cam) in enumerate(shots, 1):  # one shot per figure, each in its own folder
        scene.camera = cam
        if name is not None:                    # a crowd's shot: its own anti-aliasing
            crowd = any(c["name"] == name for c in cfg["crowds"])
            scene.display.render_aa = cfg["render"]["crowd_antialiasing" if crowd
                                                    else "antialiasing"]
        if cfg["render"]["format"] == "VIDEO":
            render_video(bpy, out / (f"{cfg['name']}.mp4" if name is None
                                     else f"{cfg['name']}_{name}.mp4"))
            count[0] += len(frames)
        else:
            render_frames(bpy, out / "frames" if name is None else out / "frames" / name,
                          frames, count)
        if len(shots) > 1:
            log(shot_progress(i, len(shots), name, count[0], count[1], time.perf_counter() - t))
    log(f"rendered {count[0]} frames with {cfg['render']['engine']} in "
        f"{time.perf_counter() - t:.1f} s")
    result["frames"] = (out / f"{cfg['name']}.mp4" if cfg["render"]["format"] == "VIDEO"
                        else out / "frames")
    if cameras and cfg["render"]["format"] == "PNG":
        shots = [sorted((out / "frames" / name).glob("frame_*.png")) for name, _ in cameras]
        middle = [s[len(s) // 2] for s in shots if s]
        if middle:
            sheet = out / "shots.png"
            staged = _staged(sheet)
            try:
                render_terrain.contact_sheet(bpy, middle, staged)
                _check_and_place(staged, sheet, "the contact sheet")
            finally:
                staged.unlink(missing_ok=True)
            KEPT.append(sheet)
            log(f"shots: {sheet}")
    return result


# -- writing: every file to a hidden name, checked, then renamed (docs/failures.md) -------------

KEPT: list = []                 # the files this job has put in place (said when it is stopped)


def _staged(final: Path) -> Path:
    """The hidden name ``final`` is written under first (same folder, same suffix)."""
    return final.with_name(f".tmp-{os.getpid()}-{final.name}")


def _check_and_place(staged: Path, final: Path, what: str) -> None:
    try:
        verify_file(staged, final.suffix.lstrip("."))
    except WriteError as exc:
        raise WriteError(f"{what} {str(final)!r} was not written: {exc}") from None
    try:
        os.replace(staged, final)
    except OSError as exc:
        raise WriteError(f"{what} {str(final)!r} was not written: {disk_reason(final, exc)}") \
            from None


def save_blend(bpy, blend: Path) -> None:
    """Save the scene as ``blend``: to a hidden name, checked (Blender's header), renamed.  A
    save that fails (a full disk, a file too large) leaves no .blend, old or partial, behind:
    :class:`WriteError`."""
    staged = _staged(blend)
    try:
        try:
            # Blender writes ``<path>@`` and renames it itself; a failure can leave either.
            bpy.ops.wm.save_as_mainfile(filepath=str(staged), check_existing=False)
        except RuntimeError as exc:
            why = str(exc).strip().splitlines()[-1] if str(exc).strip() else ""
            why = disk_reason(blend) or why or "Blender could not save it"
            limit = file_size_limit()          # Blender's own words may not say it hit it
            if limit is not None and "too large" not in why:
                why += f" (files are limited to {limit} bytes here: ulimit -f)"
            raise WriteError(f"the .blend {str(blend)!r} was not written: {why}") from None
        _check_and_place(staged, blend, "the .blend")
    finally:
        staged.unlink(missing_ok=True)
        Path(f"{staged}@").unlink(missing_ok=True)


def render_frames(bpy, folder: Path, frames, count) -> None:
    """Render ``frames`` one by one, each to a hidden name, checked (a whole PNG) and renamed
    to ``folder/frame_####.png``.  The first frame that does not come out whole stops the job
    with :class:`WriteError` naming the frames not written and why (the ones before it are
    kept)."""
    scene = bpy.context.scene
    folder.mkdir(parents=True, exist_ok=True)
    for k, f in enumerate(frames):
        final = folder / f"frame_{f:04d}.png"
        staged = _staged(final)
        scene.frame_set(f)
        scene.render.filepath = str(staged)
        try:
            bpy.ops.render.render(write_still=True)
            try:
                _check_and_place(staged, final, "frame")
            except WriteError as exc:
                rest = frames[k:]
                span = f"{rest[0]}" if len(rest) == 1 else f"{rest[0]}-{rest[-1]}"
                why = str(exc).split(": ", 1)[-1]
                raise WriteError(f"{len(rest)} of {len(frames)} frames not written to "
                                 f"{str(folder)!r} (frames {span}; frame {f}: {why})") from None
        finally:
            staged.unlink(missing_ok=True)
        KEPT.append(final)
        count[0] += 1
        log(f"rendered frame {f} ({count[0]}/{count[1]})")
        signals.checkpoint()                   # a signal during the frame stops here


def render_video(bpy, final: Path) -> None:
    """Render the animation as one video to a hidden name, checked (not empty), renamed."""
    scene = bpy.context.scene
    staged = _staged(final)
    scene.render.filepath = str(staged)
    try:
        bpy.ops.render.render(animation=True)
        _check_and_place(staged, final, "the video")
    finally:
        staged.unlink(missing_ok=True)
    KEPT.append(final)
    signals.checkpoint()


def shot_progress(shot: int, shots: int, name: str, done: int, total: int, elapsed: float) -> str:
    """The line after shot ``shot`` of ``shots``: frames so far, the time spent and the time left
    at the pace so far (every frame of a job costs about the same)."""
    left = elapsed / done * (total - done) if done else float("nan")
    return (f"shot {shot}/{shots} {name} done: {done}/{total} frames in {elapsed:.0f} s, "
            f"about {left:.0f} s left")


class _Parser(argparse.ArgumentParser):
    def error(self, message):          # one line, exit 2, like every other bad input
        self.exit(2, f"render_job: error: {message}\n")


def parse_args(argv):
    argv = argv[argv.index("--") + 1:] if "--" in argv else argv[1:]
    p = _Parser(prog="render_job.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--config", required=True, type=Path, help="the job's TOML file")
    p.add_argument("--output", help="output folder (overrides job.output)")
    p.add_argument("--engine", help="WORKBENCH, EEVEE or CYCLES (overrides render.engine)")
    p.add_argument("--resolution", help="WIDTHxHEIGHT in pixels (overrides render.resolution)")
    p.add_argument("--seconds", type=float, help="length of the animation (overrides job.seconds)")
    p.add_argument("--frame-step", type=int, help="render every n-th frame (overrides "
                   "job.frame_step)")
    p.add_argument("--no-render", action="store_true", help="build, bake and save only: "
                   "bake once, then render chunks with plain `blender -b job.blend -s A -e B -a` "
                   "on any farm")
    p.add_argument("--frames", help="render only frames A-B of the job (a farm task's chunk)")
    p.add_argument("--farm-frames", help="the frames A-B a farm will render from the baked "
                   ".blend: refused (exit 2, before the bake) unless inside the job's frames")
    p.add_argument("--device", help="CPU or GPU: Cycles' render device (default CPU); GPU fails "
                   "where Cycles finds none")
    p.add_argument("--name", help="the job's name: <output>/<name>.blend (overrides job.name)")
    p.add_argument("--register", action="append", default=[], metavar="MODULE",
                   help="import a module (a .py file or a module name) that registers your own "
                        "sports or formations (docs/registry.md) before the config is read; "
                        "repeatable")
    return p.parse_args(argv)


def main(argv=None) -> int:
    """Exit 0 when every file asked for was written and checked; 2 for a bad config or an
    output another job holds; 1 for a failed bake or write (naming what was not written);
    130 / 143 on SIGINT / SIGTERM (docs/failures.md)."""
    with signals.stop_on_signals():
        KEPT.clear()
        made = []
        try:
            return _main(argv, made)
        except signals.Interrupted as exc:
            print(signals.interrupted_line("render_job", exc, KEPT), file=sys.stderr,
                  flush=True)
            return exc.code
        finally:
            _remove_if_empty(made)


def _remove_if_empty(made) -> None:
    """Remove the output folders this job created if it wrote nothing into them."""
    for folder in reversed(made):
        try:
            folder.rmdir()
        except OSError:
            break


def _main(argv, made) -> int:
    args = parse_args(sys.argv if argv is None else argv)
    try:
        for spec in args.register:
            import_extension(spec)
        cfg = load_config(args.config, args)
    except ValueError as exc:                     # ConfigError, FieldError: names the key
        print(f"render_job: error: {exc}", file=sys.stderr, flush=True)
        return 2
    out = cfg["output"]
    missing = []
    probe = out
    while not probe.exists():
        missing.append(probe)
        probe = probe.parent
    try:
        out.mkdir(parents=True, exist_ok=True)     # to hold the lock; removed if left empty
    except OSError as exc:
        print(f"render_job: error: cannot create {str(out)!r}: {disk_reason(out, exc)}",
              file=sys.stderr, flush=True)
        return 1
    made.extend(reversed(missing))
    flag = "--output" if args.output is not None else f"{args.config}: job.output"
    log(f"job {cfg['name']!r}: {len(cfg['figures'])} figure(s), {cfg['seconds']:g} s at "
        f"{cfg['fps']} fps, {cfg['render']['engine']} {cfg['render']['resolution'][0]}x"
        f"{cfg['render']['resolution'][1]}")
    try:
        with signals.deferred(), OutputLock(out, flag, f"render_job {cfg['name']}"):
            # Held signals: Blender prints, rather than passes on, an exception raised in the
            # add-on's code it calls; the job stops at its checkpoints (after each figure's
            # bake, each frame) instead.  Held from before the lock is taken, so a signal
            # cannot leave a lock file (and the folder made for it) behind.
            res = run(cfg, render=not args.no_render)
    except OutputLocked as exc:
        print(f"render_job: error: {exc}", file=sys.stderr, flush=True)
        return 2
    except ConfigError as exc:
        print(f"render_job: error: {exc}", file=sys.stderr, flush=True)
        return 2
    except WriteError as exc:
        kept = f"; kept {len(KEPT)} file(s) written before it" if KEPT else ""
        print(f"render_job: error: {exc}{kept}", file=sys.stderr, flush=True)
        return 1
    except RuntimeError as exc:                   # an operator's report (fell over, no plan)
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else "bake failed"
        print(f"render_job: error: {reason}", file=sys.stderr, flush=True)
        return 1
    except OSError as exc:                        # the disk filled up, the folder went away
        print(f"render_job: error: cannot write to {str(out)!r}: "
              f"{disk_reason(out, exc)}", file=sys.stderr, flush=True)
        return 1
    log(f"blend: {res['blend']}")
    if res["frames"] is not None:
        log(f"frames: {res['frames']}")
    return 0


if __name__ == "__main__":
    code = main()
    if code:
        sys.exit(code)

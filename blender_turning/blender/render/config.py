"""The render job's config (a TOML file, ``scripts/configs/*.toml``): every value checked before
anything is built, against the core's table of ranges with the field validator every file format
uses; a bad value is a :class:`ConfigError` naming its key.  Crowds' tables are read by
:mod:`.crowds`."""
from __future__ import annotations

import tomllib
from pathlib import Path

from ...core.files import temp_beside
from ...core.ranges import RANGES, Range, lean_range
from ...core.registry import SPORTS
from ...core.validate import Fields, check, nearest, read_text
from . import crowds

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
               "target_speed", "tracks", "style", "stop_s"},
    "terrain": {"kind", "surface", "length", "width", "slope_deg", "cell", "seed", "moguls",
                "at", "height", "spread", "road"},
}


def _terrains(top) -> dict:
    """``[terrain.<name>]`` tables: a ``ski_slope`` mountain (core.ground.terrain_gen) or a ``hill``
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
    heading = RANGES["heading"].deg()
    sport = f.string("sport").lower()
    if sport not in SPORTS:
        f.fail("sport", f"= {sport!r} is not one of {', '.join(SPORTS)}")
    lean = lean_range(SPORTS[sport].figure.limits.theta_fall, f"the {sport}").deg()
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
           "style": f.string("style", "carve", choices=SPORTS[sport].styles),
           "stop_s": f.number("stop_s", "stop_at", None),
           "body": None, "crowd": None, "time_offset": 0.0}
    if fig["ground"] is not None and fig["ground"] not in terrains:
        f.fail("ground", f"= {fig['ground']!r} is not a [terrain.<name>] of the config")
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
    cfg["crowds"] = crowds.read_crowds(top, cfg["figures"], paths, obstacles, terrains,
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

"""Crowd scene files (JSON; the format is in docs/crowds.md): read, validate, build.

Every problem is one ``ValueError`` (:class:`~..core.validate.FieldError`) naming the file and
the field, read by the core's one validator with the core's ranges where the field is the
core's (``ski_school.json: figures[1].turns.period = -2 is outside the allowed range [0.3, 20]
s``).  A path figure's ``follow`` object is a path-following scene (docs/cli.md, "Scene files"),
read by the core's scene reader; its errors name the crowd file and ``figures[i].follow``.
"""
from __future__ import annotations

import math
from pathlib import Path

from ..core.ranges import CROWD_RANGES, RANGES, lean_range
from ..core.course.scene import read_figure, scene_from_dict
from ..core.validate import FieldError, Fields, read_json
from .formations import FORMATIONS
from .registry import FormationRefused
from .model import BODY_CLEARANCE, FIRST_TURNS, Crowd, CrowdFigure, FollowPath, Turns

__all__ = ["load_crowd", "crowd_from_dict"]

_TOP = {"name", "description", "seed", "duration", "dt", "figures", "formations", "priority",
        "clearance"}
_FIGURE = {"name", "preset", "body", "limits", "turns", "follow", "start", "time_offset"}


def load_crowd(path) -> Crowd:
    """Read and validate a crowd scene file (a path figure's ``follow.scene`` file names are
    relative to it)."""
    return crowd_from_dict(read_json(path, "crowd file"), Path(path).parent, Path(path).name)


def crowd_from_dict(doc, base_dir=".", source: str = "crowd") -> Crowd:
    """Validate a parsed crowd document; errors name ``source`` and the field."""
    if not isinstance(doc, dict):
        raise FieldError(f"{source}: the crowd must be a JSON object, not {type(doc).__name__}")
    top = Fields(doc, source).only(_TOP)
    seed = top.number("seed", CROWD_RANGES["seed"], 0)
    figures = [_figure(f, Path(base_dir)) for f in top.tables("figures", _FIGURE)]
    for i, f in enumerate(top.tables("formations")):
        figures.extend(_formation(f, figures, seed, Path(base_dir)))
    if not figures:
        top.fail("figures", "is empty (and no formation adds any)")
    duration = top.number("duration", "duration")
    dt = top.number("dt", "dt", 0.02)
    priority = _priority(top, figures)
    clearance = top.number("clearance", "body_clearance", BODY_CLEARANCE)
    try:
        return Crowd(top.string("name", "crowd"), tuple(figures), duration, dt, seed, priority,
                     clearance)
    except ValueError as exc:
        raise FieldError(f"{source}: {exc}") from None


def _priority(top: Fields, figures: list) -> tuple:
    """``priority``: a list of figure names, or ``"all"``: the parametric figures (they cannot
    steer), then the path figures, each in the crowd's order (formations after their leaders)."""
    v = top.value("priority", [])
    if v == "all":
        return tuple([f.name for f in figures if not f.is_path] +
                     [f.name for f in figures if f.is_path])
    if not isinstance(v, list) or not all(isinstance(n, str) for n in v):
        top.fail("priority", f"= {v!r} is neither \"all\" nor a list of figure names")
    return tuple(v)


def _figure(f: Fields, base: Path) -> CrowdFigure:
    name = f.string("name")
    kinds = [k for k in ("turns", "follow") if f.has(k)]
    if len(kinds) != 1:
        f.fail("turns", "or follow: exactly one is needed")
    offset = f.number("time_offset", CROWD_RANGES["time_offset"], 0.0)
    try:
        if kinds[0] == "follow":
            if f.has("start"):
                f.fail("start", "is for turns; a path figure starts where its follow.start says")
            scene = _scene(f, base)
            return CrowdFigure(name, scene.figure, FollowPath(scene), time_offset=offset)
        t = f.table("turns", {"period", "lean_deg", "heading_deg"}, required=True)
        heading = t.number("heading_deg", RANGES["heading"].deg(), 0.0) \
            if t.value("heading_deg", 0.0) is not None else None
        figure = read_figure(f)
        leans = lean_range(figure.limits.theta_fall, f"the {figure.name}")
        turns = Turns(t.number("period", "period"),
                      math.radians(t.number("lean_deg", leans.deg())),
                      None if heading is None else math.radians(heading))
        s = f.table("start", {"position", "first_turn"})
        return CrowdFigure(name, figure, turns, tuple(s.xy("position", [0.0, 0.0])),
                           s.string("first_turn", "left", FIRST_TURNS), offset)
    except FieldError:
        raise
    except ValueError as exc:                 # a combination the model refuses
        raise FieldError(f"{f.source}: {f.path}: {exc}") from None


def _scene(f: Fields, base: Path):
    """The path-following scene of ``follow``: its ``scene`` file (relative to the crowd file)
    with its objects overridden key by key, the figure's ``preset``/``body``/``limits`` as its
    figure."""
    follow = f.table("follow", required=True)
    doc = dict(follow.doc)
    if "scene" in doc:
        ref = follow.string("scene")
        try:
            loaded = read_json(base / ref, "scene file")
        except ValueError as exc:
            follow.fail("scene", f"= {ref!r} cannot be read ({exc})")
        if not isinstance(loaded, dict):
            follow.fail("scene", f"= {ref!r} is not a JSON object")
        doc = {**loaded, **{k: {**loaded[k], **v} if isinstance(v, dict) and isinstance(
            loaded.get(k), dict) else v for k, v in doc.items() if k != "scene"}}
    fig_doc = {k: f.doc[k] for k in ("preset", "body", "limits") if k in f.doc}
    if fig_doc:
        doc["figure"] = fig_doc
    doc.setdefault("name", f.doc["name"])
    return scene_from_dict(doc, f"{f.source}: {follow.path}")


def _formation(f: Fields, figures: list, seed: int, base: Path) -> tuple:
    """A ``formations`` entry: its record (:data:`.registry.FORMATIONS`, by ``type``) reads its
    keys and makes its members from the leader (a figure defined before it) or the template."""
    kind = f.string("type", choices=tuple(FORMATIONS))
    record = FORMATIONS[kind]
    f.only(record.file_keys)
    name = f.string("name", None)
    if record.template == "leader":
        lead = f.string("leader")
        member = next((m for m in figures if m.name == lead), None)
        if member is None:
            f.fail("leader", f"= {lead!r} names no figure defined before it")
    else:
        member = _figure(f.table("template", _FIGURE, required=True), base)
    try:
        return tuple(record.read(f, member, seed, name))
    except FormationRefused as exc:           # a combination the formation refuses
        raise FieldError(f"{f.source}: {f.path}: {exc}") from None

"""Crowd scene files (JSON; the format is in README.md, "Crowds"): read, validate, build.

Every problem is one ``ValueError`` naming the field: ``crowd field figures[1].turns.period =
-2 is outside the allowed range (0, 1000]``.  A path figure's ``follow`` object is a
path-following scene (README, "Path following"), read by the core's scene reader; its errors come
back prefixed with the crowd field.
"""
from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

from ..core.params import check_range, preset
from ..core.scene import scene_from_dict
from . import formations as formations_
from .model import FIRST_TURNS, Crowd, CrowdFigure, FollowPath, Turns

__all__ = ["load_crowd", "crowd_from_dict"]

_TOP = {"name", "description", "seed", "duration", "dt", "figures", "formations"}
_FIGURE = {"name", "preset", "body", "limits", "turns", "follow", "start", "time_offset"}
_FORMATIONS = {
    "follow_leader": {"type", "leader", "count", "gap_s", "gap_m", "lateral_m", "body_jitter",
                      "timing_jitter_s", "period_jitter", "name", "seed"},
    "synchronized": {"type", "template", "count", "spacing_m", "antiphase", "gap_s", "name"},
    "peloton": {"type", "template", "count", "gap_m", "abreast", "spacing_m", "body_jitter",
                "name", "seed"},
}


class _Doc:
    """A JSON object read field by field; every error names the field in full."""

    def __init__(self, doc, where: str, allowed=None):
        if not isinstance(doc, dict):
            raise ValueError(f"crowd field {where or 'file'} is not an object")
        self.doc, self.where = doc, where
        for k in doc if allowed is not None else ():
            if k not in allowed:
                raise ValueError(f"crowd field {self.name(k)} is not known (expected one of: "
                                 f"{', '.join(sorted(allowed))})")

    def name(self, key) -> str:
        return f"{self.where}.{key}" if self.where else str(key)

    def fail(self, key, msg):
        raise ValueError(f"crowd field {self.name(key)} {msg}")

    def has(self, key) -> bool:
        return key in self.doc

    def number(self, key, default=None, lo=-math.inf, hi=math.inf, lo_open=False):
        v = self.doc.get(key, default)
        if v is None:
            self.fail(key, "is missing")
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(key, f"= {v!r} is not a number")
        return check_range(f"crowd field {self.name(key)}", v, lo, hi, lo_open=lo_open)

    def integer(self, key, default, lo, hi) -> int:
        v = self.number(key, default, lo, hi)
        if v != int(v):
            self.fail(key, f"= {self.doc[key]!r} is not a whole number")
        return int(v)

    def string(self, key, default=None, choices=None) -> str:
        v = self.doc.get(key, default)
        if v is None:
            self.fail(key, "is missing")
        if not isinstance(v, str) or not v:
            self.fail(key, f"= {v!r} is not a non-empty string")
        if choices is not None and v not in choices:
            self.fail(key, f"= {v!r} is not one of {', '.join(choices)}")
        return v

    def boolean(self, key, default) -> bool:
        v = self.doc.get(key, default)
        if not isinstance(v, bool):
            self.fail(key, f"= {v!r} is not true or false")
        return v

    def obj(self, key, allowed=None, required=False) -> "_Doc":
        if key not in self.doc and not required:
            return _Doc({}, self.name(key))
        if key not in self.doc:
            self.fail(key, "is missing")
        return _Doc(self.doc[key], self.name(key), allowed)

    def items(self, key) -> list:
        v = self.doc.get(key, [])
        if not isinstance(v, list):
            self.fail(key, "is not a list")
        return v


def load_crowd(path) -> Crowd:
    """Read and validate a crowd scene file (a path figure's ``follow.scene`` file names are
    relative to it)."""
    try:
        with open(path) as fh:
            doc = json.load(fh)
    except OSError as exc:
        raise ValueError(f"crowd file {str(path)!r} cannot be read: {exc.strerror}") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"crowd file {str(path)!r} is not valid JSON ({exc})") from None
    return crowd_from_dict(doc, Path(path).parent)


def crowd_from_dict(doc, base_dir=".") -> Crowd:
    top = _Doc(doc, "", _TOP)
    seed = top.integer("seed", 0, 0, 2**63 - 1)
    figures = [_figure(_Doc(f, f"figures[{i}]", _FIGURE), Path(base_dir))
               for i, f in enumerate(top.items("figures"))]
    for i, f in enumerate(top.items("formations")):
        figures.extend(_formation(f, f"formations[{i}]", figures, seed, Path(base_dir)))
    if not figures:
        top.fail("figures", "is empty (and no formation adds any)")
    try:
        return Crowd(top.string("name", "crowd"), tuple(figures),
                     top.number("duration", lo=0.0, hi=1e5, lo_open=True),
                     top.number("dt", 0.02, 1e-4, 0.1), seed)
    except ValueError as exc:
        raise ValueError(f"crowd: {exc}") from None


def _figure(f: _Doc, base: Path) -> CrowdFigure:
    name = f.string("name")
    kinds = [k for k in ("turns", "follow") if f.has(k)]
    if len(kinds) != 1:
        f.fail("turns", "or follow: exactly one is needed")
    fig_doc = {k: f.doc[k] for k in ("preset", "body", "limits") if k in f.doc}
    offset = f.number("time_offset", 0.0, 0.0, 1e5)
    if kinds[0] == "follow":
        if f.has("start"):
            f.fail("start", "is for turns; a path figure starts where its follow.start says")
        return CrowdFigure(name, (scene := _scene(f, fig_doc, base)).figure, FollowPath(scene),
                           time_offset=offset)
    fig = _body(f, fig_doc)
    t = f.obj("turns", {"period", "lean_deg", "heading_deg"}, required=True)
    heading = t.doc.get("heading_deg", 0.0)
    turns = Turns(t.number("period", lo=0.0, hi=1e3, lo_open=True),
                  math.radians(t.number("lean_deg", lo=0.0, hi=89.0, lo_open=True)),
                  None if heading is None else math.radians(t.number("heading_deg", 0.0,
                                                                     -1e4, 1e4)))
    s = f.obj("start", {"position", "first_turn"})
    pos = s.doc.get("position", [0.0, 0.0])
    if not (isinstance(pos, list) and len(pos) == 2 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in pos)):
        s.fail("position", f"= {pos!r} is not an [x, y] pair of numbers")
    return CrowdFigure(name, fig, turns, tuple(pos), s.string("first_turn", "left", FIRST_TURNS),
                       offset)


def _body(f: _Doc, fig_doc: dict):
    """The preset with the figure's ``body`` and ``limits`` overrides."""
    try:
        fig = preset(f.string("preset"))
    except ValueError as exc:
        if "preset =" in str(exc):
            f.fail("preset", f"= {f.doc['preset']!r} is not one of skier, snowboarder, "
                             f"telemark, cyclist")
        raise
    body = f.obj("body", {"m", "l", "I_v", "V_cm", "g"})
    lim = f.obj("limits", {"C_f_max", "dC_f_max", "theta_fall_deg"})
    b = {k: body.number(k, lo=0.0, hi=1e5, lo_open=True) for k in body.doc}
    lm = {k: lim.number(k, lo=0.0, hi=1e3, lo_open=True) for k in ("C_f_max", "dC_f_max")
          if lim.has(k)}
    if lim.has("theta_fall_deg"):
        lm["theta_fall"] = math.radians(lim.number("theta_fall_deg", lo=0.0, hi=89.9,
                                                   lo_open=True))
    try:
        return replace(fig, body=replace(fig.body, **b), limits=replace(fig.limits, **lm))
    except ValueError as exc:
        raise ValueError(f"crowd field {f.where}.{exc}") from None


def _scene(f: _Doc, fig_doc: dict, base: Path):
    """The path-following scene of ``follow``: its ``scene`` file (relative to the crowd file)
    overlaid with the other keys, the figure's ``preset``/``body``/``limits`` as its figure."""
    follow = f.obj("follow", required=True)
    doc = dict(follow.doc)
    if "scene" in doc:
        ref = follow.string("scene")
        try:
            with open(base / ref) as fh:
                loaded = json.load(fh)
        except (OSError, json.JSONDecodeError) as exc:
            follow.fail("scene", f"= {ref!r} cannot be read ({exc})")
        # The file's objects (planner, start ...) take the overlay's keys one level deep.
        doc = {**loaded, **{k: {**loaded[k], **v} if isinstance(v, dict) and isinstance(
            loaded.get(k), dict) else v for k, v in doc.items() if k != "scene"}}
    if fig_doc:
        doc["figure"] = fig_doc
    doc.setdefault("name", f.doc["name"])
    try:
        return scene_from_dict(doc)
    except ValueError as exc:
        raise ValueError(f"crowd field {follow.where}: {exc}") from None


def _name(f: _Doc):
    """A formation's optional ``name`` (the prefix of its figures' names)."""
    return f.string("name") if f.has("name") else None


def _formation(doc, where: str, figures: list, seed: int, base: Path) -> tuple:
    kind = _Doc(doc, where).string("type", choices=tuple(_FORMATIONS))
    f = _Doc(doc, where, _FORMATIONS[kind])
    try:
        if kind == "follow_leader":
            lead = f.string("leader")
            leader = next((m for m in figures if m.name == lead), None)
            if leader is None:
                f.fail("leader", f"= {lead!r} names no figure defined before it")
            if f.has("gap_s") == f.has("gap_m"):
                f.fail("gap_s", "or gap_m: exactly one is needed")
            by = "time" if f.has("gap_s") else "distance"
            lateral = f.doc.get("lateral_m", 0.0)
            return formations_.follow_leader(
                leader, f.integer("count", None, 1, 10000),
                f.number("gap_s" if by == "time" else "gap_m", lo=0.0, lo_open=True), by,
                lateral, f.integer("seed", seed, 0, 2**63 - 1),
                f.number("body_jitter", 0.0, 0.0, 0.3),
                f.number("timing_jitter_s", 0.0, 0.0, 1e3),
                f.number("period_jitter", 0.0, 0.0, 0.3), _name(f))
        template = _figure(f.obj("template", _FIGURE, required=True), base)
        if kind == "synchronized":
            return formations_.synchronized(template, f.integer("count", 2, 1, 10000),
                                            f.number("spacing_m", 0.0, 0.0, 1e3),
                                            f.boolean("antiphase", True),
                                            _name(f),
                                            f.number("gap_s", 0.0, 0.0, 1e4))
        return formations_.peloton(template, f.integer("count", None, 1, 10000),
                                   f.number("gap_m", lo=0.0, hi=1e3, lo_open=True),
                                   f.integer("abreast", 2, 1, 100),
                                   f.number("spacing_m", 0.8, 0.0, 1e2),
                                   f.integer("seed", seed, 0, 2**63 - 1),
                                   f.number("body_jitter", 0.0, 0.0, 0.3), _name(f))
    except ValueError as exc:
        msg = str(exc)
        raise ValueError(msg if msg.startswith("crowd") else f"crowd field {where}: {msg}") \
            from None

"""Formations: crowds generated from a template figure and a seed; each one's record (how a crowd
file, a render job and Blender's Add Crowd read and make it, :mod:`.registry`) at the end.

- :func:`follow_leader`: ``count`` figures on the leader's track, each ``gap`` seconds (or metres)
  further behind, with a lateral offset and small random differences of body and timing.
- :func:`synchronized`: a pair or a line turning in phase or in antiphase (the figure-8s of the
  paper's Fig. 10, track 1: two figures on one line, out of phase), or riding a path side by
  side.
- :func:`peloton`: riders on a road path in rows of ``abreast``, rows ``gap`` metres apart.

Random choices come from ``random.Random`` seeded by the formation's seed and name, drawn in a
fixed order per figure, so a crowd is the same on every machine and in every process.
"""
from __future__ import annotations

import math
import random
from dataclasses import replace

import numpy as np

from ..core.physics.params import check_range
from ..core.ranges import CROWD_RANGES
from ..core.validate import check
from ..core.course.path import HermitePath
from .model import CrowdFigure, FollowPath, Turns
from .registry import FORMATIONS, Formation, FormationRefused, register_formation

__all__ = ["follow_leader", "synchronized", "peloton", "offset_path", "point_at_distance",
           "FORMATIONS"]


def _left(v) -> np.ndarray:
    """The unit vector 90 deg counter-clockwise of ``v`` (the figure's left)."""
    v = np.asarray(v, float) / np.linalg.norm(v)
    return np.array([-v[1], v[0]])


def offset_path(path: HermitePath, d: float) -> HermitePath:
    """``path`` moved ``d`` m to its left (negative: right): each knot moves along the mitred
    normal (``d / cos`` of half the corner's angle, so both straight legs of a corner stay ``d``
    away), the tangents are kept.  Exact for straight segments; on a curved one the offset
    differs from ``d`` by the order of ``d^2`` times its curvature."""
    if d == 0.0:
        return path
    n = path.n_segments
    knots = path.knots.copy()
    for i in range(n + 1):
        a = path.t_in[i - 1] if i > 0 else path.t_out[0]
        b = path.t_out[i] if i < n else path.t_in[n - 1]
        ua, ub = a / np.linalg.norm(a), b / np.linalg.norm(b)
        if np.linalg.norm(ua + ub) < 1e-6:           # a reversal: no mitre, use the way out
            knots[i] += d * _left(ub)
            continue
        m = _left(ua + ub)
        knots[i] += d * m / float(m @ _left(ub))
    return HermitePath(knots, path.t_out, path.t_in)


def point_at_distance(path: HermitePath, s: float):
    """The point ``(x, y)`` and the heading (rad) ``s`` m along ``path`` (64 chords per
    segment); ``ValueError`` beyond its length."""
    pts = path.sample(64)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    if not 0.0 <= s <= cum[-1]:
        raise ValueError(f"{s:g} m along the path is beyond its length ({cum[-1]:.1f} m)")
    i = min(int(np.searchsorted(cum, s, side="right")) - 1, len(seg) - 1)
    u = (s - cum[i]) / seg[i] if seg[i] > 0 else 0.0
    p = pts[i] + u * (pts[i + 1] - pts[i])
    d = pts[i + 1] - pts[i]
    return p, math.atan2(d[1], d[0])


def _jittered_body(fig, rng: random.Random, jitter: float):
    """The body with ``m``, ``l`` and ``I_v`` each scaled by ``1 + U(-jitter, jitter)`` (drawn
    in that order, always, so the stream does not depend on ``jitter``)."""
    scale = [1.0 + jitter * (2.0 * rng.random() - 1.0) for _ in range(3)]
    if jitter == 0.0:
        return fig
    b = fig.body
    return replace(fig, body=replace(b, m=b.m * scale[0], l=b.l * scale[1], I_v=b.I_v * scale[2]))


def _moved(member: CrowdFigure, name, fig, lateral, s_along=None, **changes) -> CrowdFigure:
    """``member`` renamed, with body ``fig``, moved ``lateral`` m to the left of its start
    heading (a path figure: its path offset too; ``s_along``: started that far along it)."""
    if not member.is_path:
        head = member.state0()[2] if member.controller.heading is None \
            else member.controller.heading
        pos = np.asarray(member.position) + lateral * _left([math.cos(head), math.sin(head)])
        return replace(member, name=name, figure=fig, position=tuple(pos), **changes)
    sc = member.controller.scene
    path = offset_path(sc.path, lateral)
    state0 = np.array(sc.state0, float)
    if s_along is not None:
        p, head = point_at_distance(path, s_along)
        state0[:3] = p[0], p[1], head
    else:
        state0[:2] += lateral * _left([math.cos(state0[2]), math.sin(state0[2])])
    scene = replace(sc, name=f"{sc.name}/{name}", figure=fig, path=path, state0=state0)
    return replace(member, name=name, figure=fig, controller=FollowPath(scene), **changes)


def _laterals(lateral, count) -> list:
    vals = list(lateral) if isinstance(lateral, (list, tuple, np.ndarray)) else [lateral]
    if not vals:
        raise ValueError("lateral is an empty list")
    for v in vals:
        check("lateral", v, CROWD_RANGES["lateral_m"])
    return [float(vals[i % len(vals)]) for i in range(count)]


def follow_leader(leader: CrowdFigure, count: int, gap: float, by: str = "time",
                  lateral=0.0, seed: int = 0, body_jitter: float = 0.0,
                  timing_jitter: float = 0.0, period_jitter: float = 0.0,
                  name: str | None = None) -> tuple:
    """``count`` followers on the leader's track: follower ``i`` (1-based) starts ``i gap`` s
    after the leader (``by="distance"``: ``gap`` m, i.e. ``gap / V_cm`` s at the leader's speed)
    from the leader's start moved ``lateral`` m to the left (a number, or a list cycled over
    the followers: ``[-1, 1]`` alternates sides).  A path leader's followers follow its path
    offset by the same amount.  Random differences, uniform in ``+-``: ``body_jitter`` (relative,
    on ``m``, ``l``, ``I_v``), ``timing_jitter`` (s, on the start time) and ``period_jitter``
    (relative, on the turn period; turns only).  Followers are named ``<name>1 ...``
    (default: the leader's name + ``"-"``)."""
    check("count", count, CROWD_RANGES["count"])
    if by not in ("time", "distance"):
        raise ValueError(f"by = {by!r} is not one of time, distance")
    check("gap", gap, CROWD_RANGES["gap_s" if by == "time" else "gap_m"])
    check("body_jitter", body_jitter, CROWD_RANGES["jitter"])
    check("period_jitter", period_jitter, CROWD_RANGES["jitter"])
    gap_t = gap if by == "time" else gap / leader.figure.body.V_cm
    check_range("timing_jitter", timing_jitter, 0.0, 0.5 * gap_t)
    prefix = f"{leader.name}-" if name is None else name
    rng = random.Random(f"follow_leader:{seed}:{prefix}")
    out = []
    for i, lat in enumerate(_laterals(lateral, int(count)), start=1):
        fig = _jittered_body(leader.figure, rng, body_jitter)
        late = timing_jitter * (2.0 * rng.random() - 1.0)
        stretch = 1.0 + period_jitter * (2.0 * rng.random() - 1.0)
        changes = {"time_offset": leader.time_offset + i * gap_t + late}
        if not leader.is_path:
            changes["controller"] = replace(leader.controller,
                                            period=leader.controller.period * stretch)
        out.append(_moved(leader, f"{prefix}{i}", fig, lat, **changes))
    return tuple(out)


def synchronized(template: CrowdFigure, count: int = 2, spacing: float = 0.0,
                 antiphase: bool = True, name: str | None = None, gap: float = 0.0) -> tuple:
    """``count`` figures turning together on a line across the heading, ``spacing`` m apart
    (centred on the template's start); with ``antiphase`` every other one starts with the
    opposite turn (``count = 2, spacing = 0``: the figure-8s of Fig. 10, track 1).  ``gap``
    (s): each one starts that much after the one before, in the same place (synchronised
    skiers drawing figure-8s ski one behind the other; ``gap = 0`` starts them together, on
    top of each other when ``spacing`` is 0).  A path template: each figure rides the
    template's path offset by its place in the line (its first turn is the path's).  Named
    ``<name>1 ...`` (default: the template's name)."""
    check("count", count, CROWD_RANGES["count"])
    check("spacing", spacing, CROWD_RANGES["spacing_m"])
    check("gap", gap, CROWD_RANGES["sync_gap_s"])
    prefix = template.name if name is None else name
    flip = {"left": "right", "right": "left"}
    out = []
    for k in range(int(count)):
        first = flip[template.first_turn] if antiphase and k % 2 else template.first_turn
        out.append(_moved(template, f"{prefix}{k + 1}", template.figure,
                          (k - 0.5 * (count - 1)) * spacing, first_turn=first,
                          time_offset=template.time_offset + k * gap))
    return tuple(out)


def peloton(template: CrowdFigure, count: int, gap: float, abreast: int = 2,
            spacing: float = 0.8, seed: int = 0, body_jitter: float = 0.0,
            name: str | None = None) -> tuple:
    """``count`` riders on the template's path, ``abreast`` to a row ``spacing`` m apart,
    rows ``gap`` m apart along the path; all start at once (the template's time offset), the
    back row at the path's start, each rider on the path offset by its place in the row.  Every
    rider rides as far: a row ends as far short of the path's end as it starts behind the front
    row, so the bunch arrives as it rode (a rider at the end stands there, and the planner
    does not see a figure after its end: docs/crowds.md).
    ``body_jitter`` as in :func:`follow_leader`.  Named ``<name>1 ...`` from the front."""
    if not template.is_path:
        raise ValueError("peloton needs a path template (the riders follow a road)")
    check("count", count, CROWD_RANGES["count"])
    check("gap", gap, CROWD_RANGES["gap_m"])
    check("abreast", abreast, CROWD_RANGES["abreast"])
    check("spacing", spacing, CROWD_RANGES["spacing_m"])
    check("body_jitter", body_jitter, CROWD_RANGES["jitter"])
    count, abreast = int(count), int(abreast)
    rows = -(-count // abreast)
    length = template.controller.scene.path.length()
    if (rows - 1) * gap >= length:
        raise ValueError(f"gap = {gap:g} m: {rows} rows need {(rows - 1) * gap:g} m of a "
                         f"{length:.1f} m path")
    prefix = template.name if name is None else name
    rng = random.Random(f"peloton:{seed}:{prefix}")
    out = []
    for k in range(count):
        row, col = divmod(k, abreast)
        in_row = min(abreast, count - row * abreast)
        fig = _jittered_body(template.figure, rng, body_jitter)
        rider = _moved(template, f"{prefix}{k + 1}", fig, (col - 0.5 * (in_row - 1)) * spacing,
                       s_along=(rows - 1 - row) * gap)
        out.append(cut_short(rider, row * gap))
    return tuple(out)


def cut_short(member: CrowdFigure, short: float) -> CrowdFigure:
    """The path figure ``member`` with its path ending ``short`` m (less than its length)
    before its end."""
    if short <= 0.0:
        return member
    sc = member.controller.scene
    path = sc.path.split(sc.path.length() - short)[0]
    return replace(member, controller=FollowPath(replace(sc, path=path)))


# -- the built-in formations' records (docs/registry.md) -------------------------------------------

def made(make, *args):
    """``make(*args)``, a refusal (any ``ValueError``: a combination the formation refuses, a
    value its own check refuses) raised as :class:`.registry.FormationRefused`, which the
    readers report against the formation's table.  A record's ``read`` reads its keys first
    (their errors name the key) and then calls ``made``."""
    try:
        return make(*args)
    except ValueError as exc:
        raise FormationRefused(str(exc)) from None


def _read_follow_leader(f, leader, seed, name):
    count = f.number("count", CROWD_RANGES["count"])
    if f.has("gap_s") == f.has("gap_m"):
        f.fail("gap_s", "or gap_m: exactly one is needed")
    by = "time" if f.has("gap_s") else "distance"
    lateral = f.numbers("lateral_m", CROWD_RANGES["lateral_m"]) \
        if isinstance(f.value("lateral_m", 0.0), list) \
        else f.number("lateral_m", CROWD_RANGES["lateral_m"], 0.0)
    return made(
        follow_leader, leader, count, f.number("gap_s" if by == "time" else "gap_m",
                                CROWD_RANGES["gap_s" if by == "time" else "gap_m"]),
        by, lateral, f.number("seed", CROWD_RANGES["seed"], seed),
        f.number("body_jitter", CROWD_RANGES["jitter"], 0.0),
        f.number("timing_jitter_s", CROWD_RANGES["timing_jitter_s"], 0.0),
        f.number("period_jitter", CROWD_RANGES["jitter"], 0.0), name)


def _build_follow_leader(lead, v, name):
    by_time = v.gap_by == "TIME"
    lateral = [-v.lateral, v.lateral] if v.alternate else v.lateral
    return follow_leader(lead, v.count, v.gap_time if by_time else v.gap_distance,
                         "time" if by_time else "distance", lateral, v.seed, v.body_jitter,
                         v.timing_jitter, v.period_jitter, name)


def _fields_follow_leader(v):
    return ("gap_by", "gap_time" if v.gap_by == "TIME" else "gap_distance", "lateral",
            "alternate", "seed", "body_jitter", "timing_jitter", "period_jitter")


def _read_synchronized(f, template, seed, name):
    return made(synchronized, template, f.number("count", CROWD_RANGES["count"], 2),
                        f.number("spacing_m", CROWD_RANGES["spacing_m"], 0.0),
                        f.boolean("antiphase", True), name,
                        f.number("gap_s", CROWD_RANGES["sync_gap_s"], 0.0))


def _read_peloton(f, template, seed, name):
    return made(peloton, template, f.number("count", CROWD_RANGES["count"]),
                   f.number("gap_m", CROWD_RANGES["gap_m"]),
                   f.number("abreast", CROWD_RANGES["abreast"], 2),
                   f.number("spacing_m", CROWD_RANGES["spacing_m"], 0.8),
                   f.number("seed", CROWD_RANGES["seed"], seed),
                   f.number("body_jitter", CROWD_RANGES["jitter"], 0.0), name)


def _peloton_start(k, v):
    """Rows from the back, as :func:`peloton` places them: member ``k``'s row's distance."""
    rows = -(-v.count // v.abreast)
    return (rows - 1 - (k - 1) // v.abreast) * v.row_gap


register_formation(Formation(
    name="follow_leader", label="Follow the Leader", number=0, template="leader",
    description="Figures on the template's track, each a time or distance further behind (a ski "
                "school behind its instructor); the template leads",
    keys={"count", "gap_s", "gap_m", "lateral_m", "body_jitter", "timing_jitter_s",
          "period_jitter", "seed"},
    read=_read_follow_leader, build=_build_follow_leader, fields=_fields_follow_leader))
register_formation(Formation(
    name="synchronized", label="Synchronized", number=1, template="any",
    description="A pair or a line turning together, in phase or in antiphase (the figure-8s of "
                "Fig. 10); the template's turns, or its path side by side",
    keys={"count", "spacing_m", "antiphase", "gap_s"},
    read=_read_synchronized,
    build=lambda lead, v, name: synchronized(lead, v.count, v.spacing, v.antiphase, name,
                                             v.sync_gap),
    fields=lambda v: ("spacing", "antiphase", "sync_gap")))
register_formation(Formation(
    name="peloton", label="Peloton", number=2, template="path",
    description="Riders in rows on the template's path curve, all starting at once (a cyclist "
                "following a road)",
    keys={"count", "gap_m", "abreast", "spacing_m", "body_jitter", "seed"},
    read=_read_peloton,
    build=lambda lead, v, name: peloton(lead, v.count, v.row_gap, v.abreast,
                                        v.row_spacing, v.seed, v.body_jitter, name),
    fields=lambda v: ("row_gap", "abreast", "row_spacing", "seed", "body_jitter"),
    start_along=_peloton_start))

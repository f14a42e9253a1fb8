"""How a crowd's followers stand at the first frame: strung out along the leader's track, or
waiting at the start.  One rule for Blender's Add Crowd and the headless render job.

A formation (:mod:`.formations`) says *when* each follower starts after the leader (its
``time_offset``: the gap in time, or the gap in metres at the leader's speed).  The shot shows it
one of two ways:

- ``"along_track"`` (the default): every figure moves from the first frame; a turning follower
  due ``dt`` s after the leader instead starts ``dt V_cm`` m behind the leader's start, back
  along the leader's mean direction of travel (its heading, Section 5.2), at the leader's phase,
  so the line of figures is the leader's track with the gaps in it.  A path follower stays on
  the crowd's clock (it waits at the start of its path: the planner spaces the figures on the
  path by time, and a start before the path's would be off it).
- ``"wait"``: every follower stands at the leader's start (its lateral offset applied) until its
  time comes, as the core's crowd clock has it (:func:`.runner.run_crowd`).  The shot then needs
  :func:`shot_length` seconds for the last follower to run as long as the leader.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

__all__ = ["STAGINGS", "stage", "waiting_span", "shot_length"]

STAGINGS = ("along_track", "wait")


def stage(leader, members, heading: float, staging: str = "along_track") -> tuple:
    """``members`` (the formation's followers of ``leader``, :class:`.CrowdFigure`) as the shot
    stages them (module doc).  ``heading``: the leader's mean direction of travel, rad CCW from
    +x (its heading, or its start heading when it has no directional control)."""
    if staging not in STAGINGS:
        raise ValueError(f"staging = {staging!r} is not one of {', '.join(STAGINGS)}")
    if not math.isfinite(heading):
        raise ValueError(f"heading = {heading!r} is not a finite number (rad)")
    if staging == "wait":
        return tuple(members)
    d = np.array([math.cos(heading), math.sin(heading)])
    out = []
    for m in members:
        late = m.time_offset - leader.time_offset
        if m.is_path or late <= 0.0:
            out.append(m)
            continue
        # The leader covers V_cm late metres in `late` seconds (V_cm is its speed; a follower's
        # body differences keep it): the follower starts that far back on the leader's line.
        pos = np.asarray(m.position, float) - late * leader.figure.body.V_cm * d
        out.append(replace(m, position=(float(pos[0]), float(pos[1])),
                           time_offset=leader.time_offset))
    return tuple(out)


def waiting_span(members) -> float:
    """The latest start of ``members`` on the crowd's clock, s (0 for an empty crowd)."""
    return max((float(m.time_offset) for m in members), default=0.0)


def shot_length(leader, members, duration: float) -> float:
    """Seconds a shot needs so that every one of ``members`` runs ``duration`` s, as the leader
    does in a shot of ``duration`` s from its own start."""
    if not duration > 0:
        raise ValueError(f"duration = {duration!r} is outside the allowed range (0, inf) s")
    return max(duration, waiting_span(members) - leader.time_offset + duration)

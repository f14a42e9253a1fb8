"""How a crowd's followers stand at the first frame: strung out along the leader's track, or
waiting at the start.  One rule for Blender's Add Crowd and the headless render job.

A formation (:mod:`.formations`) says *when* each follower starts after the leader (its
``time_offset``: the gap in time, or the gap in metres at the leader's speed).  The shot shows it
one of two ways:

- ``"along_track"`` (the default): every figure moves from the first frame; a turning follower
  due ``dt`` s after the leader instead starts ``dt V_cm`` m behind the leader's start, back
  along the leader's mean direction of travel (its heading, Section 5.2), at the leader's phase,
  so the line of figures is the leader's track with the gaps in it.  A path follower likewise
  starts ``dt V_cm`` m behind the start of its path: its path gets a straight lead-in of that
  length along the path's start tangent (the leader's track run backwards), and the planner
  (Section 6) follows it from there, upright as the leader starts, so it reaches the path's
  start about ``dt`` s after the leader.  Its run is as long as the leader's: it ends that far
  short of the path's end, as a turning follower ends its gap behind the leader, so the line
  keeps its gaps to the last frame.
- ``"wait"``: every follower stands at the leader's start (its lateral offset applied) until its
  time comes, as the core's crowd clock has it (:func:`.runner.run_crowd`).  The shot then needs
  :func:`shot_length` seconds for the last follower to run as long as the leader.  A path
  follower's run ends ``dt V_cm`` m short of its path's end, as along the track.

A figure that has reached its path's end stands there in the shot; the planner leaves it out
(:mod:`..core.course.moving`: its lookahead past a follower's own end would meet it), so a
line's followers end apart: each its gap behind the one before.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .formations import cut_short
from .model import FollowPath

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
    d = np.array([math.cos(heading), math.sin(heading)])
    along = staging == "along_track"
    out = []
    for i, m in enumerate(members, start=1):
        late = m.time_offset - leader.time_offset
        if late <= 0.0 or not (along or m.is_path):
            out.append(m)
            continue
        # The leader covers V_cm late metres in `late` seconds (V_cm is its speed; a follower's
        # body differences keep it): the follower is that far back on the leader's line.
        back = late * leader.figure.body.V_cm
        if m.is_path and not along:
            total = m.controller.scene.path.length()
            if back >= total:
                raise ValueError(f"follower {i}, {back:.1f} m behind the leader and waiting at "
                                 f"the start, would end before the start of its {total:.1f} m "
                                 "path: give a smaller gap or fewer followers, or stage them "
                                 "along the track")
            out.append(cut_short(m, back))
            continue
        if m.is_path:
            out.append(replace(m, controller=_led_in(m.controller, back),
                               time_offset=leader.time_offset))
            continue
        pos = np.asarray(m.position, float) - back * d
        out.append(replace(m, position=(float(pos[0]), float(pos[1])),
                           time_offset=leader.time_offset))
    return tuple(out)


def _led_in(controller: FollowPath, back: float) -> FollowPath:
    """``controller``'s scene after a straight lead-in of ``back`` m before its path and with
    as much cut off its end, started at the lead-in's first point (the start state's lean and
    lean rate kept)."""
    sc = controller.scene
    path = sc.path.led_in(back).split(sc.path.length())[0]
    state0 = np.array(sc.state0, float)
    state0[:2] = path.knots[0]
    return FollowPath(replace(sc, path=path, state0=state0))


def waiting_span(members) -> float:
    """The latest start of ``members`` on the crowd's clock, s (0 for an empty crowd)."""
    return max((float(m.time_offset) for m in members), default=0.0)


def shot_length(leader, members, duration: float) -> float:
    """Seconds a shot needs so that every one of ``members`` runs ``duration`` s, as the leader
    does in a shot of ``duration`` s from its own start."""
    if not duration > 0:
        raise ValueError(f"duration = {duration!r} is outside the allowed range (0, inf) s")
    return max(duration, waiting_span(members) - leader.time_offset + duration)

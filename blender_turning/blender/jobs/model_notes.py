"""What the model changed, said to the user: the lean a bake reached when the figure's bounds
or its tyre's grip kept it below the asked one (the core's
:class:`~..core.controllers.feasible.TurnsFollowed` report), and how far a Follow Path run
strayed from its drawn path (the core's :func:`~..core.course.path.path_deviation`).  Bake
Turns, Follow Path (one figure and several) and the Turns panel all take their words from here;
nothing is recomputed in an operator.
"""
from __future__ import annotations

import math
from ...core.controllers.feasible import TURN_KEY, FeasibleTurn, TurnsFollowed, turn_meta
from ...core.course.path import path_deviation
from ..scene.figure_context import BOUND_SETTING
from ..scene.scene_adapters import FrameRange, controller_from_settings, figure_from_settings

#: Follow Path warns when the foot strays farther than this from the drawn path, m.  The four
#: shipped sports follow a slalom of 3 m offsets 12 m apart, the crowd tests' path and a bend of
#: 25 m radius to 0.9-2.4 m (measured, largest near the path's end); a right-angle corner is cut
#: by 6.6 m (the telemark) to 14.7 m (the skier).
WARN_DISTANCE = 3.0


def with_turn(traj, controller):
    """``traj`` with the core's report of the turns a run followed in its meta when one was
    limited (unchanged when each turn was the one asked for, or the controller reports none)."""
    meta = turn_meta(getattr(controller, "report", None))
    return type(traj)(traj.data, {**traj.meta, **meta}) if meta else traj


def _why(report: TurnsFollowed) -> str:
    bound = report.worst.bound
    setting = BOUND_SETTING.get(bound)
    more = f" or a higher {setting}" if setting and bound != "physical branch" else ""
    return f"{report.describe()}: a longer Turn Period{more} leans further"


def turn_note(traj) -> str:
    """``"lean 17.01 deg at period ... (asked 23.00 deg; limited by C_f_max ...)"`` and what to
    change, for a bake whose lean its bounds limited, and the tyre's grip's report
    (``meta["grip_limited"]``, :func:`...core.physics.simulate.simulate`); ``""`` when it
    leaned as asked."""
    turn = traj.meta.get(TURN_KEY)
    notes = [traj.meta.get("grip_limited", "")] + \
        ([] if turn is None else [_why(TurnsFollowed.from_dict(turn))])
    return "; ".join(n for n in notes if n)


def panel_turn(obj, scene) -> FeasibleTurn | None:
    """The turn a bake follows for the figure's Turns settings at the current frame (before
    baking); ``None`` when the settings cannot be read (the bake says why)."""
    fps = scene.render.fps / scene.render.fps_base
    try:
        figure = figure_from_settings(obj.turning)
        ctl = controller_from_settings(obj, figure, FrameRange(scene.frame_current,
                                                               scene.frame_current + 1, fps))
    except ValueError:
        return None
    return ctl.commanded_turn(0.0)


def panel_text(turn: FeasibleTurn) -> list[str]:
    """The Turns panel's lines, naming the bound by the setting's label the panel shows; a
    second line when the bound is that of a half-turn Hold Heading keeps room to steer with."""
    setting = BOUND_SETTING.get(turn.bound, turn.bound).rpartition(" > ")[2]
    if turn.bound == "physical branch":
        setting = "the physical branch"
    lines = [f"Leans {math.degrees(turn.lean):.1f}\u00b0, "
             f"not {math.degrees(turn.commanded_lean):.1f}\u00b0: limited by {setting}"]
    if turn.beta != 1.0:
        lines.append("in the room Hold Heading keeps to steer")
    return lines


def warn_distance(op) -> float:
    """Follow Path's *Warn Beyond* (stand-ins of the operator in tests may lack it)."""
    return float(getattr(op, "warn_distance", WARN_DISTANCE))


def follow_note(path, traj, frame_start: int, fps: float, warn: float) -> tuple[str, str]:
    """``(level, text)`` of a Follow Path run's largest distance from its drawn ``path`` (the
    core's ``HermitePath``) and its largest lean; ``level`` is ``"WARNING"`` above ``warn`` m.
    ``traj``'s ``t = 0`` is ``frame_start`` (a crowd's follower: its own offset included)."""
    dev = path_deviation(path, traj.t, traj.x, traj.y)
    frame = frame_start + round(dev.t * fps)
    text = (f"the foot is at most {dev.distance:.1f} m from the drawn path (at frame {frame}, "
            f"{dev.along:.0f} m along it); lean up to "
            f"{math.degrees(float(abs(traj.theta_v).max())):.1f} deg, planned for the path")
    if dev.distance > warn:
        return "WARNING", (text + f": more than {warn:g} m, the drawn line is not followed there "
                           "(a gentler bend, a higher Planner Curvature Rate or Max Curvature, "
                           "or less Speed)")
    return "INFO", text

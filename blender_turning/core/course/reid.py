"""Reid et al. 2020's slalom courses as scene documents, and the per-turn measures they report
(docs/racing.md, "The racer's line").

Reid, Haugen, Gilgien, Kipp & Smith, "Alpine Ski Motion Characteristics in Slalom", Front.
Sports Act. Living 2:25 (2020), abstract: on a 19 deg slope with gates 10 m and 13 m apart, the
skis' edge angles reached maximum values of 65.7 +- 1.7 and 71.0 +- 1.9 deg and the turn radii
minimum values of 3.96 +- 0.23 and 4.94 +- 0.59 m, "in good agreement with theoretical
predictions by Howe (2001) of turn radius based on edging angle": radii of the measured ski
trajectories ("how measured ski trajectories compare to predictions based on theoretical models
of ski-snow interaction mechanics"), each a turn's minimum (and each edge a turn's maximum),
given as mean +- SD.  Howe's prediction, ``R = R_sc cos(edge)``, is the ski's own arc.

So a run is measured turn by turn (:func:`per_turn`): each turn's tightest radius and largest
edge angle, then their mean and SD (:func:`summary`), leaving out the turns into and out of the
course.  Both radii are measured: the skis' (the foot's, ``1 / max |C_f|``; Section 3's ``C_f`` is
the curvature of the foot's path), which is what Reid et al. measured, and the centre of mass's
(the curvature of its track), which they did not; :func:`against_reid` sets a run's turns
against Reid's means on the skis' radius and edge.
"""
from __future__ import annotations

import math

import numpy as np

from ..equipment import carving_of
from ..validate import check_range

__all__ = ["REID", "course", "gate_positions", "com_radius", "turns", "per_turn", "summary",
           "against_reid"]

#: Reid et al. 2020 by gate spacing (m): minimum turn radius mean, SD (m); maximum edge angle
#: mean, SD (deg).
REID = {10.0: (3.96, 0.23, 65.7, 1.7), 13.0: (4.94, 0.59, 71.0, 1.9)}

#: Where the first turning pole's course begins along the fall line, m (a straight lead-in).
LEAD_IN = 10.0


def course(gap: float, speed: float, preset: str = "slalom_racer", gates: int = 8,
           planner: dict | None = None, amplitude: float = 2.5, inside: float = 1.5,
           edge: float = 12.0) -> dict:
    """The scene document of a course of ``gates`` turning poles ``gap`` m apart along the fall
    line (+x) after a straight lead-in: the line through them ``amplitude`` m left and right of
    it, each turning pole a line from ``inside`` m inside the line to the course's edge
    (``edge`` m out), where two long poles close the course."""
    pts, tans, obs = [[0.0, 0.0], [LEAD_IN, 0.0]], [[gap, 0.0], [gap, 0.0]], []
    for k, x in enumerate(gate_positions(gap, gates)):
        side = 1.0 if k % 2 == 0 else -1.0
        pts.append([float(x), side * amplitude])
        tans.append([1.5 * gap, 0.0])
        obs.append({"type": "segment", "from": [float(x), side * (amplitude - inside)],
                    "to": [float(x), -side * edge]})
    end = LEAD_IN + gap * (gates + 1)
    pts += [[end, 0.0], [end + gap, 0.0]]
    tans += [[gap, 0.0], [gap, 0.0]]
    obs += [{"type": "segment", "from": [-5.0, s * edge], "to": [end + 2 * gap, s * edge]}
            for s in (1.0, -1.0)]
    return {"name": f"reid {gap:g} m", "figure": {"preset": preset, "body": {"V_cm": speed}},
            "path": {"points": pts, "tangents": tans}, "clearance": 0.3, "obstacles": obs,
            "start": {"position": [0, 0], "heading_deg": 0},
            "planner": {"stages": 10, "choices": 5, "stage_time": 0.3,
                        "lean_bound_deg": 75, **(planner or {})}}


def gate_positions(gap: float, gates: int = 8) -> np.ndarray:
    """The turning poles' positions along the fall line, m (:func:`course`)."""
    return LEAD_IN + gap * np.arange(1, gates + 1)


def com_radius(traj, l: float) -> np.ndarray:
    """The radius of the centre of mass's track at every sample, m: the COM stands ``l
    sin(theta_v)`` to the left of the foot (Fig. 2, ``theta_v > 0`` leans left), and the
    curvature of its track is ``|x' y'' - y' x''| / |v|^3`` (central differences in time)."""
    off = l * np.sin(traj.theta_v)
    x = traj.x - off * np.sin(traj.theta_dir)
    y = traj.y + off * np.cos(traj.theta_dir)
    t = traj.t
    dx, dy = np.gradient(x, t), np.gradient(y, t)
    ddx, ddy = np.gradient(dx, t), np.gradient(dy, t)
    k = np.abs(dx * ddy - dy * ddx) / np.maximum(np.hypot(dx, dy), 1e-9) ** 3
    return 1.0 / np.maximum(k, 1e-12)


def turns(traj, gate_x) -> list[tuple[int, slice]]:
    """The turns around the gates at ``gate_x`` (m along +x): ``(gate index, samples)``.  A turn
    runs from one change of the lean's side to the next (the body crosses over the skis) and
    belongs to the one gate within its stretch of the fall line; a stretch with no gate or two
    is no turn."""
    side = np.sign(traj.theta_v)
    cross = np.nonzero(side[1:] * side[:-1] < 0)[0] + 1
    out = []
    for a, b in zip(cross[:-1], cross[1:]):
        inside = np.nonzero((gate_x >= traj.x[a]) & (gate_x < traj.x[b]))[0]
        if len(inside) == 1:
            out.append((int(inside[0]), slice(a, b)))
    return out


def per_turn(traj, figure, gate_x, skip: int = 1) -> dict:
    """Each turn's extremes (:func:`turns`) for the gates but the first and the last ``skip``
    (the turn in from the straight lead-in and the one out into the run-out): ``R_com``, the
    centre of mass's tightest radius (m); ``R_foot``, the foot's, ``1 / max |C_f|`` (the skis'
    arc, m); ``edge``, the skis' largest edge angle (the sidecut relation for ``C_f``,
    :meth:`..equipment.Carving.edge_angle`, deg); ``lean``, the largest ``|theta_v|`` (deg);
    ``F_bw``, the peak leg force (Appendix A, body weights); ``V_lo``, ``V_hi``: the centre of
    mass's slowest and fastest speed (m/s).  Arrays with one entry a turn; ``gates``: the turns'
    gate indices."""
    carving = carving_of(figure.name)
    if carving is None:
        raise ValueError(f"figure = {figure.name!r} has no carving equipment: the edge angle is "
                         f"the sidecut relation's, on the racer and carver presets only")
    R = com_radius(traj, figure.body.l)
    weight = figure.body.m * figure.body.g
    rows = [(k, R[sl].min(), 1.0 / np.abs(traj.C_f[sl]).max(),
             math.degrees(np.abs(carving.edge_angle(traj.C_f[sl])).max()),
             math.degrees(np.abs(traj.theta_v[sl]).max()), traj.F_leg[sl].max() / weight,
             traj.V_cm[sl].min(), traj.V_cm[sl].max())
            for k, sl in turns(traj, gate_x) if skip <= k < len(gate_x) - skip]
    cols = np.array(rows, float).reshape(-1, 8).T
    return dict(zip(("gates", "R_com", "R_foot", "edge", "lean", "F_bw", "V_lo", "V_hi"), cols))


def summary(turn: dict) -> dict:
    """Mean and sample SD of each column of :func:`per_turn`: ``{name: (mean, sd)}``."""
    return {k: (float(v.mean()), float(v.std(ddof=1)) if len(v) > 1 else 0.0)
            for k, v in turn.items() if k != "gates"}


def against_reid(turn: dict, gap: float, tol: float = 0.1) -> dict:
    """A run's turns (:func:`per_turn`) against Reid's means for the course of gates ``gap`` m
    apart: ``{"radius": (mean, Reid's, within), "edge": (...)}``, each mean over the turns and
    within when at most ``tol`` (relative) from Reid's.  The radius is the skis' (``R_foot``):
    Reid et al. measured the skis' trajectories, and the centre of mass's track (``R_com``) is
    wider or tighter than the skis' as the lean swings over them (docs/racing.md)."""
    if gap not in REID:
        raise ValueError(f"gap = {gap!r} m: Reid et al. measured the courses of gates "
                         f"{sorted(REID)} m apart")
    check_range("tol", tol, 0.0, 1.0)
    R, _, edge, _ = REID[gap]
    out = {}
    for name, key, ref in (("radius", "R_foot", R), ("edge", "edge", edge)):
        mean = float(np.mean(turn[key]))
        out[name] = (mean, ref, abs(mean - ref) <= tol * ref)
    return out

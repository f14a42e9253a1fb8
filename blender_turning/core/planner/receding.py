"""Receding-horizon path following (Section 6.1): plan N stages, apply the first, plan again.

:func:`follow` returns a :class:`FollowResult`: the trajectory (docs/ARCHITECTURE.md Sec. 3, ``phi``
from the Section 6.2 post-pass) and one :class:`Replan` per planning step.  When no plan survives
(every branch hits an obstacle or falls) it raises :class:`..errors.PlanInfeasible` with the time,
the position and the trajectory up to there; when the time limit comes before the end of the
path, :class:`..errors.PathNotFinished` with how far along it got: never a silent fall-through.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..errors import PathNotFinished, PlanInfeasible
from ..course.path import PathProgress
from ..course.phase_estimate import estimate_phase
from ..physics.trajectory import Trajectory, body_meta
from .problem import Problem
from .search import SearchStats, branch_and_bound
from .viable import dead_end

__all__ = ["Replan", "FollowResult", "follow"]


@dataclass(frozen=True)
class Replan:
    """One planning step: when, from where, what it chose and what the search did."""

    t: float
    x: float
    y: float
    f_opt: float
    u: float
    stats: SearchStats
    dead_end: bool = False
    """The plan's last node has no continuation: each of its q children falls or collides."""
    viable: bool = True
    """False when no plan with a viable last node existed (``search.py``)."""

    def as_dict(self) -> dict:
        return {"t": self.t, "x": self.x, "y": self.y, "f_opt": self.f_opt, "dC_f_dt": self.u,
                "dead_end": self.dead_end, "viable": self.viable, **self.stats.as_dict()}


@dataclass(frozen=True)
class FollowResult:
    trajectory: Trajectory
    replans: tuple
    reached_end: bool
    progress: float = 0.0
    """How far along the path the foot got (arc length, m; 0 when not followed to an end)."""

    def totals(self) -> dict:
        keys = ("expanded", "generated", "clipped_collision", "clipped_fall", "clipped_bound",
                "clipped_doomed", "leaves", "wall_time")
        out = {k: sum(getattr(r.stats, k) for r in self.replans) for k in keys}
        out["replans"] = len(self.replans)
        out["dead_ends"] = sum(r.dead_end for r in self.replans)
        out["not_viable"] = sum(not r.viable for r in self.replans)
        out["proven"] = all(r.stats.proven for r in self.replans)
        out["duration"] = self.trajectory.duration
        return out


def follow(problem: Problem, state0, C_f0: float = 0.0, duration: float | None = None,
           progress: PathProgress | None = None, meta: dict | None = None,
           on_replan=None) -> FollowResult:
    """Follow the path from ``state0`` (shape ``(5,)``; ``(6,)`` with ``V_cm`` on terrain) for
    ``duration`` seconds or, given a
    :class:`..path.PathProgress`, until the foot reaches the end of the path (progress along it
    by arc length, :meth:`PathProgress.at_end`), ``duration`` then being the time limit.

    Raises :class:`..errors.PathNotFinished` when the time limit comes first, and
    :class:`..errors.PlanInfeasible` when no plan survives.  ``on_replan(t, xy, fraction)`` is
    called before every replanning (``fraction``: of the path done, 0 without ``progress``); an
    exception it raises ends the run (cancelling).
    """
    if duration is None:
        raise ValueError("follow needs a duration (with a path progress: the time limit)")
    st = problem.settings
    x = np.asarray(state0, float).reshape(-1, 1).copy()
    cf, t, s = float(C_f0), 0.0, 0.0
    rows = {k: [] for k in ("state", "C_f", "alpha_v", "V_f", "t")}
    replans = []
    previous = proof = None
    q_last = st.q
    reached = False
    p = 0.0
    while t < duration - 1e-9:
        if on_replan is not None:
            on_replan(t, x[:2, 0].copy(), p / progress.length if progress else 0.0)
        clock = time.perf_counter()
        local = problem.local(x[:2, 0], x[:, 0], t)
        if previous is not None and local.settings.q != q_last:   # q_near: other choices
            previous = proof = None
        q_last = local.settings.q
        plan = branch_and_bound(local, x[:, 0], cf, t, s, previous, proof)
        if not plan.feasible:
            traj = _trajectory(problem, rows, x, cf, t, s, meta)
            raise PlanInfeasible(t, (float(x[0, 0]), float(x[1, 0])), traj, plan.stats)
        stats = plan.stats
        stats = SearchStats(**{**stats.as_dict(), "wall_time": time.perf_counter() - clock})
        replans.append(Replan(t, float(x[0, 0]), float(x[1, 0]), plan.f_opt, plan.u[0], stats,
                              dead_end(local, plan.leaf), plan.viable))
        r = local.simulate_stage(x, np.array([cf]), np.array([plan.u[0]]), np.array([t]),
                                 np.array([s]), record=True)
        for k in rows:
            rows[k].extend(r.record[k])
        x, cf, s, t = r.state, float(r.C_f[0]), float(r.s[0]), t + st.t_stage
        previous = plan.choices
        proof = plan.proof.after(plan.choices[0])
        if getattr(local, "runaways", 0):     # terrain: the next search's rules may be looser
            proof = None
        if local.race is not None and local.free:   # its costs refer to the root (RaceCost)
            proof = None
        if progress is not None:
            steps = [xs[:2, 0] for xs in r.record["state"]] + [x[:2, 0]]
            for a, b in zip(steps[:-1], steps[1:]):
                p = progress.advance(p, b, float(np.hypot(*(b - a))))
            if progress.at_end(p, x[:2, 0]):
                reached = True
                break
    traj = _trajectory(problem, rows, x, cf, t, s, meta)
    if progress is not None and not reached:
        raise PathNotFinished(t, p, progress.length, traj)
    return FollowResult(traj, tuple(replans), reached, p)


def _trajectory(problem: Problem, rows, x, cf, t, s, meta) -> Trajectory:
    """The recorded steps plus the final state, with F_leg, s and the post-pass phase (the
    problem gives the force, the speed and, on terrain, the height: ``Problem.columns``)."""
    body = problem.body
    states = [np.asarray(v).reshape(-1) for v in rows["state"]] + [x.reshape(-1)]
    S = np.array(states).T
    C = np.array([float(np.ravel(v)[0]) for v in rows["C_f"]] + [cf])
    T = np.array([float(np.ravel(v)[0]) for v in rows["t"]] + [t])
    V = np.array([float(np.ravel(v)[0]) for v in rows["V_f"]] + [np.nan])
    A = np.array([float(np.ravel(v)[0]) for v in rows["alpha_v"]] + [np.nan])
    # The final sample's alpha_v and V_f: from its own state and curvature.
    a_end, v_end = problem.end_rates(x, cf, t, s)
    A[-1], V[-1] = float(np.ravel(a_end)[0]), float(np.ravel(v_end)[0])
    cols = {"t": T, "x": S[0], "y": S[1], "theta_dir": S[2], "theta_v": S[3], "omega_v": S[4],
            "alpha_v": A, "C_f": C, "V_f": V, **problem.columns(S, A, C, V)}
    ds = 0.5 * (V[1:] + V[:-1]) * np.diff(T)
    cols["s"] = np.concatenate([[0.0], np.cumsum(ds)])
    cols["phi"] = estimate_phase(T, S[3], S[4]).phi if len(T) > 1 else np.zeros(len(T))
    meta = {"preset": problem.figure.name, "dt": problem.settings.dt, **body_meta(body),
            "planner": "branch-and-bound (Section 6)", **problem.meta(), **(meta or {})}
    return Trajectory.from_columns(cols, meta)

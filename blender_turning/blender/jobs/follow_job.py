"""Follow Path as a job the modal operator can watch and cancel: the planner (Section 6) runs in a
worker thread on plain arrays; the scene is written only after it finishes, on the main thread.

Cancelling is cooperative: the planner calls the job before every replanning, and the job raises
:class:`Cancelled` there once :meth:`FollowJob.cancel` was called.
"""
from __future__ import annotations

import threading

import numpy as np

from ...core.course.follow_problem import DEFAULT_CLEARANCE, FollowSetup
from ...core.course.obstacles import Obstacles
from ...core.course.path import HermitePath
from ...core.planner import PlannerSettings


class Cancelled(Exception):
    """The user pressed ESC."""


class FollowJob:
    """Plan a figure's run along a path around obstacles; :meth:`run` or :meth:`start`/:meth:`poll`.

    ``control`` are the path's Bezier control points (3 k + 1, 2) in world metres, ``footprints``
    a list of ``(name, polygon (k, 2))``, ``clearance`` the distance kept from them (m).  The
    problem, its run-out, time limit, start state and end test come from the core's one builder
    (:class:`~..core.course.follow_problem.FollowSetup`), as for a scene file; on terrain
    (``ground``, a
    core surface, and ``resistance``; ``follow_ground.py``) it is the terrain problem, braking to
    ``speed_cap`` (:class:`~..core.planner.speed_cap.SpeedCap`) when given.
    """

    def __init__(self, figure, control, footprints, clearance: float = DEFAULT_CLEARANCE,
                 settings: PlannerSettings | None = None, ground=None, resistance=None,
                 speed_cap=None):
        self.figure = figure
        self.path = HermitePath.from_bezier(np.asarray(control, float))
        self.obstacles = Obstacles(polygons=[p for _, p in footprints], clearance=clearance)
        self.setup = FollowSetup(figure, self.path, self.obstacles,
                                 settings or PlannerSettings(), ground=ground,
                                 resistance=resistance, speed_cap=speed_cap)
        self.problem = self.setup.problem()
        self.length = self.path.length()
        self.duration = self.setup.time_limit()
        self.progress = 0.0
        self.result = None
        self.error = None
        self.cancel_requested = threading.Event()
        self._thread = None

    def _on_replan(self, t, xy, fraction):
        """Called before every replanning: honour a cancel request, report the progress."""
        if self.cancel_requested.is_set():
            raise Cancelled()
        self.progress = fraction

    def run(self):
        """Plan now (blocking); the :class:`~..core.planner.FollowResult`.  Raises
        ``PlanInfeasible``, ``PathNotFinished`` (the time limit came before the end of the path)
        or :class:`Cancelled`."""
        return self.setup.run(problem=self.problem, on_replan=self._on_replan)

    def _work(self):
        try:
            self.result = self.run()
        except BaseException as exc:           # handed to the main thread, reported there
            self.error = exc
        self.progress = 1.0

    def start(self) -> None:
        self._thread = threading.Thread(target=self._work, name="turning-follow", daemon=True)
        self._thread.start()

    def done(self) -> bool:
        return self._thread is not None and not self._thread.is_alive()

    def cancel(self, wait: bool = True) -> None:
        self.cancel_requested.set()
        if wait and self._thread is not None:
            self._thread.join()

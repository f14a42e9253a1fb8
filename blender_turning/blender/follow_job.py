"""Follow Path as a job the modal operator can watch and cancel: the planner (Section 6) runs in a
worker thread on plain arrays; the scene is written only after it finishes, on the main thread.

Cancelling is cooperative: the planner asks its problem for a local copy before every replan, and
the job's problem raises :class:`Cancelled` there once :meth:`FollowJob.cancel` was called.
"""
from __future__ import annotations

import math
import threading

import numpy as np

from ..core.obstacles import Obstacles
from ..core.path import HermitePath, PathDistance
from ..core.planner import PlannerSettings, Problem, follow


class Cancelled(Exception):
    """The user pressed ESC."""


class _WatchedProblem(Problem):
    """A planning problem that reports progress and honours a cancel request at every replan."""

    def watch(self, job):
        self._job = job
        return self

    def local(self, center):
        job = self._job
        if job.cancel_requested.is_set():
            raise Cancelled()
        job.progress = job.fraction_done(center)
        return super().local(center)


class FollowJob:
    """Plan a figure's run along a path around obstacles; :meth:`run` or :meth:`start`/:meth:`poll`.

    ``control`` are the path's Bezier control points (3 k + 1, 2) in world metres, ``footprints``
    a list of ``(name, polygon (k, 2))``, ``clearance`` the distance kept from them (m).
    """

    def __init__(self, figure, control, footprints, clearance: float = 0.5,
                 settings: PlannerSettings | None = None):
        self.figure = figure
        self.path = HermitePath.from_bezier(np.asarray(control, float))
        self.length = self.path.length()
        runout = figure.body.V_cm * 3.0
        self.samples = self.path.sample(16)
        self.obstacles = Obstacles(polygons=[p for _, p in footprints], clearance=clearance)
        settings = settings or PlannerSettings(batch=64)
        self.problem = _WatchedProblem(figure, PathDistance(self.path.extended(runout)),
                                       self.obstacles, settings).watch(self)
        start = self.path.knots[0]
        d = self.path.evaluate(0, 0.0, 1)
        self.state0 = (float(start[0]), float(start[1]), math.atan2(d[1], d[0]), 0.0, 0.0)
        # Time cap: the path at the speed of the centre of mass, and a generous margin.
        self.duration = 1.5 * self.length / figure.body.V_cm + 5.0
        self.progress = 0.0
        self.result = None
        self.error = None
        self.cancel_requested = threading.Event()
        self._thread = None
        self._arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(self.samples, axis=0),
                                                                    axis=1))])

    def fraction_done(self, xy) -> float:
        i = int(np.argmin(np.linalg.norm(self.samples - np.asarray(xy)[None, :2], axis=1)))
        return float(min(1.0, self._arc[i] / max(self._arc[-1], 1e-9)))

    def run(self):
        """Plan now (blocking); the :class:`~..core.planner.FollowResult`.  Raises
        ``PlanInfeasible`` or :class:`Cancelled`."""
        return follow(self.problem, self.state0, duration=self.duration, end=self.path.knots[-1],
                      end_dir=self.path.end_direction(), meta={"path_length": self.length})

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

"""Domain errors of the core. The CLI turns them into one line and exit code 2 (a lost worker,
:class:`WorkerLost`, which is not the input's fault: exit 1)."""
from __future__ import annotations


class TurningError(Exception):
    """Base class of the core's domain errors."""


class RunEnded(TurningError):
    """A run that ended early as a physical event: the figure fell over, stopped or left the
    terrain.  Carries the time ``t`` (s), the foot's ``position`` ``(x, y)`` (m, ``None`` when
    no trajectory came with it), the ``reason`` (the message) and the ``trajectory`` up to
    there."""

    def __init__(self, t: float, what: str, detail: str = "", trajectory=None, position=None):
        if position is None and trajectory is not None and len(trajectory.t):
            position = (trajectory.x[-1], trajectory.y[-1])
        self.position = None if position is None else (float(position[0]), float(position[1]))
        where = "" if self.position is None else \
            f" at ({self.position[0]:.1f}, {self.position[1]:.1f}) m"
        self.reason = f"the figure {what} at t = {t:.2f} s{where}{detail}"
        super().__init__(self.reason)
        self.t = t
        self.trajectory = trajectory


class FellOver(RunEnded):
    """The lean exceeded the fall bound."""

    def __init__(self, t: float, theta_v: float, trajectory=None, cause: str | None = None):
        super().__init__(t, "fell over", f" (lean {theta_v * 57.29578:.1f} deg)"
                         + (f"; {cause}" if cause else ""), trajectory)
        self.cause = cause
        self.theta_v = theta_v


class PlanInfeasible(TurningError):
    """Path following (Section 6): every branch of the search hits an obstacle or falls over.
    Carries the time, the foot position, the trajectory up to there and the search statistics."""

    def __init__(self, t: float, position, trajectory=None, stats=None):
        x, y = float(position[0]), float(position[1])
        super().__init__(f"no feasible plan at t = {t:.2f} s, position ({x:.2f}, {y:.2f}) m: "
                         f"every branch hits an obstacle or falls over")
        self.t = t
        self.position = (x, y)
        self.trajectory = trajectory
        self.stats = stats


class Stopped(RunEnded):
    """With the speed a state: the figure slowed below the speed the turning model needs
    (friction and drag beat the slope)."""

    def __init__(self, t: float, V_cm: float, trajectory=None):
        super().__init__(t, "stopped", f" (speed {V_cm:.2f} m/s): the slope is too gentle for "
                         "the friction and drag", trajectory)
        self.V_cm = V_cm


class LeftTerrain(RunEnded):
    """The figure ran off the edge of the terrain (a height field covers a finite area);
    ``position`` is the last position on it."""

    def __init__(self, t: float, position, trajectory=None):
        super().__init__(t, "left the terrain", "", trajectory, position)


class PathNotFinished(TurningError):
    """Path following (Section 6) stopped at its time limit before reaching the end of the path.
    Carries how far along the path it got (arc length, m), the path's length and the trajectory."""

    def __init__(self, t: float, progress: float, length: float, trajectory=None):
        super().__init__(f"the end of the path was not reached within the time limit of "
                         f"{t:.1f} s: got {progress:.1f} m of {length:.1f} m along the path "
                         f"({100.0 * progress / max(length, 1e-12):.0f}%)")
        self.t = t
        self.progress = progress
        self.length = length
        self.trajectory = trajectory


class WorkerLost(Exception):
    """A worker process or cluster worker died while it ran figures (killed, out of memory):
    ``figures`` names them.  Not a domain error: the same input may well run again."""

    def __init__(self, message: str, figures=()):
        super().__init__(message)
        self.figures = tuple(figures)

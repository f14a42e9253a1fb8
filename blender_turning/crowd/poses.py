"""A crowd's poses: every figure's trajectory mapped onto its sport's rig (Section 7,
:func:`blender_turning.mapping.map_trajectory`), fanned out like the planning.

Frames are on the crowd's clock: frame ``frame_start + k`` is ``t = k / fps``; a figure's first
frame is the first at or after its start (its time offset), its last the last before its end.
Mapping is deterministic, so the poses do not depend on the engine either.
"""
from __future__ import annotations

import math

from ..mapping import map_trajectory
from .runner import CrowdResult, execute

__all__ = ["map_crowd", "map_task"]


def map_task(task) -> list:
    """Map one chunk ``(fps, frame_start, [(sport, trajectory), ...])``: a list of
    :class:`~..mapping.PoseTrack` (``None`` for a figure without samples)."""
    fps, frame_start, items = task
    out = []
    for sport, traj in items:
        if traj is None or len(traj) < 2:
            out.append(None)
            continue
        k0 = math.ceil(traj.t[0] * fps - 1e-9)
        out.append(map_trajectory(sport, traj.resample(fps, start=k0 / fps),
                                  frame_start=frame_start + k0))
    return out


def map_crowd(result: CrowdResult, fps: float, frame_start: int = 1, workers: int = 1,
              scheduler: str | None = None, executor=None, chunks: int | None = None) -> dict:
    """``{figure name: PoseTrack}`` for every figure of ``result`` with samples (a figure that
    fell or found no plan: up to there), in crowd order.  The figures are mapped in ``chunks``
    tasks (default: 4 per worker, 1 in this process) on the engine of :func:`run_crowd`'s
    ``workers``/``scheduler``/``executor``."""
    if not fps > 0:
        raise ValueError(f"fps = {fps!r} is outside the allowed range (0, inf)")
    figs = list(zip(result.crowd.figures, result.figures))
    n = chunks or (1 if workers == 1 and scheduler is None and executor is None
                   else 4 * max(int(workers), 2))
    n = max(1, min(n, len(figs)))
    bounds = [len(figs) * i // n for i in range(n + 1)]
    tasks = [(float(fps), int(frame_start), [(f.figure.name, r.trajectory)
                                             for f, r in figs[a:b]])
             for a, b in zip(bounds, bounds[1:])]
    tracks = {}
    execute(map_task, tasks, lambda i, out: tracks.update({i: out}), workers, scheduler,
            executor)
    flat = [t for i in range(len(tasks)) for t in tracks[i]]
    return {f.name: t for (f, _), t in zip(figs, flat) if t is not None}

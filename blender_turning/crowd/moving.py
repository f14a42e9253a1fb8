"""Figures as moving obstacles for one another (issue 11).

A planned figure occupies, at each moment, the segment from its foot to its centre of mass's
ground point: the CM sits ``l sin theta_v`` to the left of the foot across the heading (Fig. 2,
``theta_v > 0`` leans left).  :class:`MovingBodies` holds those segments for figures already
planned, on a common clock, and answers the planner's question "does this track step, taken at
time ``t``, come within the clearance of anybody?" (:meth:`MovingBodies.collides`, the moving
counterpart of :meth:`blender_turning.core.obstacles.Obstacles.collides`).  Priority planning
(each figure planning around the bodies of those before it) needs the planner to pass each
step's time to its obstacles; until it does, :func:`closest_approach` reports how close the
figures of a finished crowd came to each other (the crowd summary lists it).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.obstacles import segment_distance

__all__ = ["MovingBodies", "closest_approach"]


@dataclass(frozen=True, eq=False)
class MovingBodies:
    """``foot[j, k]`` and ``cm[j, k]`` (shape ``(m, n, 2)``, m): body ``j``'s foot and CM ground
    point at ``t0 + k dt``; NaN where body ``j`` is not moving (before its start, after its end
    or fall).  ``clearance``: the distance to keep from every body, m."""

    names: tuple
    t0: float
    dt: float
    foot: np.ndarray
    cm: np.ndarray
    clearance: float = 0.0

    @classmethod
    def from_tracks(cls, tracks, dt: float = 0.1, clearance: float = 0.0) -> "MovingBodies":
        """``tracks``: ``(name, trajectory, l)`` triples (``l``: the body's CM height, m); the
        trajectories are sampled every ``dt`` s (linear interpolation, on their own times)."""
        if not dt > 0:
            raise ValueError(f"dt = {dt!r} is outside the allowed range (0, inf)")
        tracks = [(n, tr, l) for n, tr, l in tracks if tr is not None and len(tr)]
        if not tracks:
            raise ValueError("no trajectories to sample")
        t0 = min(float(tr.t[0]) for _, tr, _ in tracks)
        t1 = max(float(tr.t[-1]) for _, tr, _ in tracks)
        grid = t0 + dt * np.arange(int(math.floor((t1 - t0) / dt + 1e-9)) + 1)
        foot = np.full((len(tracks), len(grid), 2), np.nan)
        cm = np.full_like(foot, np.nan)
        for j, (_, tr, l) in enumerate(tracks):
            ok = ~np.isnan(tr.x)
            t = tr.t[ok]
            x, y, head, lean = (np.interp(grid, t, v[ok], left=np.nan, right=np.nan)
                                for v in (tr.x, tr.y, tr.theta_dir, tr.theta_v))
            foot[j, :, 0], foot[j, :, 1] = x, y
            side = l * np.sin(lean)                          # to the left of the heading
            cm[j, :, 0], cm[j, :, 1] = x - side * np.sin(head), y + side * np.cos(head)
        return cls(tuple(n for n, _, _ in tracks), t0, float(dt), foot, cm, float(clearance))

    def at(self, t) -> tuple:
        """Foot and CM points of every body at times ``t`` (nearest sample): two arrays of shape
        ``(m,) + shape(t) + (2,)``, NaN for bodies not moving then."""
        k = np.rint((np.asarray(t, float) - self.t0) / self.dt).astype(int)
        inside = (k >= 0) & (k < self.foot.shape[1])
        kk = np.clip(k, 0, self.foot.shape[1] - 1)
        mask = np.where(inside, 1.0, np.nan)[None, ..., None]
        return self.foot[:, kk] * mask, self.cm[:, kk] * mask

    def collides(self, t, a, b) -> np.ndarray:
        """Which track steps ``a -> b`` (shape ``(k, 2)`` each) taken at times ``t`` (shape
        ``(k,)``) pass within ``clearance`` of a body's foot-CM segment then."""
        a = np.asarray(a, float).reshape(-1, 2)
        b = np.asarray(b, float).reshape(-1, 2)
        foot, cm = self.at(np.broadcast_to(np.asarray(t, float), (len(a),)))
        d = segment_distance(a[None], b[None], foot, cm)
        return np.any(d <= self.clearance, axis=0)           # NaN (absent) never collides


def closest_approach(bodies: MovingBodies) -> dict:
    """For each body: ``(distance m, the other body's name, t s)`` of its closest approach to
    any other body's foot-CM segment at the same sample; ``(inf, None, None)`` when it never
    shares the shot."""
    m = len(bodies.names)
    out = {}
    for j in range(m):
        others = [i for i in range(m) if i != j]
        if not others:
            out[bodies.names[j]] = (math.inf, None, None)
            continue
        d = segment_distance(bodies.foot[j][None], bodies.cm[j][None], bodies.foot[others],
                             bodies.cm[others])
        d = np.where(np.isnan(d), np.inf, d)
        i, k = np.unravel_index(int(np.argmin(d)), d.shape)
        out[bodies.names[j]] = ((float(d[i, k]), bodies.names[others[i]],
                                 bodies.t0 + k * bodies.dt) if np.isfinite(d[i, k])
                                else (math.inf, None, None))
    return out

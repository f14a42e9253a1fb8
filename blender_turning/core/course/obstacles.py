"""Obstacles for path following (Section 6): line segments (slalom poles "drawn as lines", road
edges), circles (trees, potholes) and polygons, with a minimum clearance.

A track segment (the foot's straight move over one integration step) collides when it comes
within ``clearance`` of an obstacle: its distance to a segment, to a circle's rim, or to a
polygon's boundary is ``<= clearance`` (so with clearance 0 touching counts), or it lies inside a
circle or polygon.  Everything is vectorised over track segments and obstacles.
"""
from __future__ import annotations

import numpy as np

__all__ = ["Obstacles", "segment_distance", "point_segment_distance"]


def point_segment_distance(p, a, b):
    """Distance from points ``p`` to segments ``a b`` (broadcast over leading axes, last axis 2)."""
    ab = b - a
    den = np.einsum("...k,...k->...", ab, ab)
    t = np.einsum("...k,...k->...", p - a, ab) / np.where(den > 0, den, 1.0)
    t = np.clip(np.where(den > 0, t, 0.0), 0.0, 1.0)
    r = p - (a + t[..., None] * ab)
    return np.sqrt(np.einsum("...k,...k->...", r, r))


def _cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def segment_distance(a, b, c, d):
    """Distance between segments ``a b`` and ``c d`` (broadcast), 0 where they intersect."""
    r, s = b - a, d - c
    d1 = _cross(r, c - a)
    d2 = _cross(r, d - a)
    d3 = _cross(s, a - c)
    d4 = _cross(s, b - c)
    # Proper crossing: each segment's ends on opposite sides of the other (touching: product 0).
    crossing = (d1 * d2 <= 0) & (d3 * d4 <= 0) & ((d1 != 0) | (d2 != 0) | (d3 != 0) | (d4 != 0))
    dist = np.minimum(np.minimum(point_segment_distance(a, c, d), point_segment_distance(b, c, d)),
                      np.minimum(point_segment_distance(c, a, b), point_segment_distance(d, a, b)))
    return np.where(crossing, 0.0, dist)


class Obstacles:
    """Plain arrays, as the Blender side hands them over.

    ``segments``: shape ``(n, 2, 2)`` (two end points each), m.  ``circles``: shape ``(n, 3)``
    (centre x, y and radius), m.  ``polygons``: a sequence of ``(k, 2)`` vertex arrays (k >= 3, any
    orientation, closed implicitly).  ``clearance``: the minimum distance kept from all of them, m.
    """

    def __init__(self, segments=(), circles=(), polygons=(), clearance: float = 0.0):
        self.segments = np.asarray(segments, float).reshape(-1, 2, 2)
        self.circles = np.asarray(circles, float).reshape(-1, 3)
        self.polygons = tuple(np.asarray(p, float).reshape(-1, 2) for p in polygons)
        self.clearance = float(clearance)
        if not (self.clearance >= 0 and np.isfinite(self.clearance)):
            raise ValueError(f"clearance = {clearance!r} is outside the allowed range [0, inf)")
        if np.any(self.circles[:, 2] <= 0):
            raise ValueError("a circle obstacle has a radius outside (0, inf)")
        for p in self.polygons:
            if len(p) < 3:
                raise ValueError(f"a polygon obstacle needs at least 3 vertices, not {len(p)}")
        edges = [self.segments] + [np.stack([p, np.roll(p, -1, axis=0)], axis=1)
                                   for p in self.polygons]
        #: Every straight edge: the segments, then each polygon's sides, shape (m, 2, 2).
        self.edges = np.concatenate(edges, axis=0) if edges else np.zeros((0, 2, 2))
        if not (np.all(np.isfinite(self.edges)) and np.all(np.isfinite(self.circles))):
            raise ValueError("an obstacle coordinate is not a finite number")
        self._lo, self._hi = self._boxes()

    def __len__(self) -> int:
        return len(self.segments) + len(self.circles) + len(self.polygons)

    def _boxes(self):
        lo = [self.segments.min(axis=1), self.circles[:, :2] - self.circles[:, 2:]]
        hi = [self.segments.max(axis=1), self.circles[:, :2] + self.circles[:, 2:]]
        lo += [p.min(axis=0)[None] for p in self.polygons]
        hi += [p.max(axis=0)[None] for p in self.polygons]
        return np.concatenate(lo).reshape(-1, 2), np.concatenate(hi).reshape(-1, 2)

    def near(self, center, radius: float) -> "Obstacles":
        """The obstacles that a track within ``radius`` of ``center`` could collide with (box test
        inflated by the clearance: exact, only obstacles that cannot matter are dropped)."""
        c = np.asarray(center, float)
        r = radius + self.clearance
        ok = np.all((self._lo <= c + r) & (self._hi >= c - r), axis=1)
        ns, nc = len(self.segments), len(self.circles)
        return Obstacles(self.segments[ok[:ns]], self.circles[ok[ns:ns + nc]],
                         [p for p, k in zip(self.polygons, ok[ns + nc:]) if k], self.clearance)

    def collides(self, a, b) -> np.ndarray:
        """Which track segments ``a -> b`` (shape ``(m, 2)`` each) collide with any obstacle."""
        a = np.asarray(a, float).reshape(-1, 2)
        b = np.asarray(b, float).reshape(-1, 2)
        hit = np.zeros(len(a), bool)
        cl = self.clearance
        if len(self.edges):
            e0, e1 = self.edges[:, 0], self.edges[:, 1]
            lo = np.minimum(a, b)[:, None] - cl
            hi = np.maximum(a, b)[:, None] + cl
            box = np.all((np.minimum(e0, e1) <= hi) & (np.maximum(e0, e1) >= lo), axis=2)
            if box.any():
                i, j = np.nonzero(box)
                d = segment_distance(a[i], b[i], e0[j], e1[j])
                hit[i[d <= cl]] = True
        if len(self.circles):
            # Only pairs whose boxes meet: a segment within r of a centre has the centre in its
            # box grown by r (exact), and the box test is cheaper than the distance.
            c = self.circles
            r = c[:, 2] + cl
            lo, hi = np.minimum(a, b), np.maximum(a, b)
            box = ((c[None, :, 0] - r <= hi[:, 0:1]) & (c[None, :, 0] + r >= lo[:, 0:1]) &
                   (c[None, :, 1] - r <= hi[:, 1:2]) & (c[None, :, 1] + r >= lo[:, 1:2]))
            i, j = np.nonzero(box)
            if len(i):
                d = point_segment_distance(c[j, :2], a[i], b[i])
                hit[i[d <= r[j]]] = True
        for p in self.polygons:      # a segment inside a polygon without touching its sides
            hit |= _inside(a, p)
        return hit

    def min_distance(self, points) -> np.ndarray:
        """Clearance left at each point (distance to the nearest obstacle; < 0 inside one), m."""
        p = np.asarray(points, float).reshape(-1, 2)
        d = np.full(len(p), np.inf)
        if len(self.edges):
            d = np.minimum(d, point_segment_distance(p[:, None], self.edges[None, :, 0],
                                                     self.edges[None, :, 1]).min(axis=1))
        if len(self.circles):
            dc = np.linalg.norm(p[:, None] - self.circles[None, :, :2], axis=2) - self.circles[:, 2]
            d = np.minimum(d, dc.min(axis=1))
        for poly in self.polygons:
            d = np.where(_inside(p, poly), -np.abs(d), d)
        return d


def _inside(p, poly):
    """Even-odd rule: which points ``p`` (shape ``(m, 2)``) lie inside polygon ``poly``."""
    x, y = p[:, 0:1], p[:, 1:2]
    x0, y0 = poly[:, 0], poly[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    straddle = (y0 > y) != (y1 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
    return np.count_nonzero(straddle & (x < xc), axis=1) % 2 == 1

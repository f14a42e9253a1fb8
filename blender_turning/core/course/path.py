"""The path to follow (Section 6, Fig. 11): a piecewise cubic Hermite spline, and the distance d_i
from a foot position to it (Fig. 12).

A :class:`HermitePath` of ``n`` segments holds the ``n + 1`` knots and, per segment, the tangent
leaving its start knot and the tangent arriving at its end knot.  Built from points and tangents it
is C1 (both tangents at a knot are the same); built from a Bezier curve it is exactly that curve
(a cubic Bezier ``P0..P3`` is the Hermite segment with tangents ``3 (P1 - P0)`` and
``3 (P3 - P2)``), corners included; built from a polyline each segment is the straight chord.

:class:`PathDistance` is the paper's ``d_i = min_j |P_i - S_j|`` over samples ``S_j`` taken at
``per_segment`` (default 12) equal parameter steps per segment, or, with ``exact=True``, the
distance to the nearest point of the spline itself.  Both are distances to a set, so both are
1-Lipschitz in the foot position, which the planner's lower bound relies on.

:class:`PathProgress` is how far along the path (arc length) the foot has got, tracked so that it
can only move forward through the parts of the path the foot has actually passed near: the test
of "the end of the path was reached" (not a half-plane through the end, which a switchback, a loop
or a start far from the path satisfy at once).

:func:`path_deviation` is where a finished run strayed farthest from the path it followed (the
planner minimises the sum of ``d_i``, not its largest value: a cut bend is part of a good plan).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["HermitePath", "PathDeviation", "PathDistance", "PathProgress", "path_deviation"]

# Hermite basis in monomial form: S(u) = [1 u u^2 u^3] @ _H @ [P0, T0, P1, T1].
_H = np.array([[1.0, 0.0, 0.0, 0.0],
               [0.0, 1.0, 0.0, 0.0],
               [-3.0, -2.0, 3.0, -1.0],
               [2.0, 1.0, -2.0, 1.0]])


def _points(name, value, min_rows):
    a = np.asarray(value, float)
    if a.ndim != 2 or a.shape[1] != 2 or a.shape[0] < min_rows:
        raise ValueError(f"{name} must be an array of at least {min_rows} (x, y) rows, "
                         f"not shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} has a value that is not a finite number")
    return a


class HermitePath:
    """A piecewise cubic Hermite spline in the ground plane (m).

    ``knots`` has shape ``(n + 1, 2)``; ``t_out[i]`` and ``t_in[i]`` (shape ``(n, 2)``, m per unit
    parameter) are segment ``i``'s tangents at its start and its end.
    """

    def __init__(self, knots, t_out, t_in):
        self.knots = _points("path points", knots, 2)
        n = len(self.knots) - 1
        self.t_out = _points("path tangents", t_out, n)
        self.t_in = _points("path tangents", t_in, n)
        if len(self.t_out) != n or len(self.t_in) != n:
            raise ValueError(f"a path of {n + 1} points needs {n} segment tangents")
        geom = np.stack([self.knots[:-1], self.t_out, self.knots[1:], self.t_in], axis=1)
        #: Monomial coefficients, shape (n, 4, 2): S_i(u) = sum_k coef[i, k] u^k.
        self.coef = np.einsum("kj,njd->nkd", _H, geom)

    # -- constructors ------------------------------------------------------------------------
    @classmethod
    def from_points(cls, points, tangents) -> "HermitePath":
        """Section 6: knots and one tangent per knot (C1 at every knot)."""
        p = _points("path points", points, 2)
        t = _points("path tangents", tangents, 1)
        if len(t) != len(p):
            raise ValueError(f"path has {len(p)} points but {len(t)} tangents")
        return cls(p, t[:-1], t[1:])

    @classmethod
    def from_polyline(cls, points) -> "HermitePath":
        """Connected straight segments (Section 6: "could be used equally well")."""
        p = _points("path points", points, 2)
        chord = np.diff(p, axis=0)
        return cls(p, chord, chord)

    @classmethod
    def from_bezier(cls, control) -> "HermitePath":
        """Cubic Bezier control points ``P0, P1, P2, P3, P4, ...`` (shape ``(3 n + 1, 2)``), as
        Blender stores them (knot, right handle, next left handle, next knot).  Exact."""
        c = _points("path bezier", control, 4)
        if (len(c) - 1) % 3:
            raise ValueError(f"path bezier needs 3 n + 1 control points, not {len(c)}")
        return cls(c[0::3], 3.0 * (c[1::3] - c[0:-1:3]), 3.0 * (c[3::3] - c[2::3]))

    # -- evaluation --------------------------------------------------------------------------
    @property
    def n_segments(self) -> int:
        return len(self.coef)

    def evaluate(self, seg, u, derivative: int = 0):
        """Point (or derivative 1, 2) of segment(s) ``seg`` at parameter(s) ``u`` in [0, 1]."""
        c = self.coef[np.asarray(seg)]
        u = np.asarray(u, float)[..., None]
        if derivative == 0:
            return c[..., 0, :] + u * (c[..., 1, :] + u * (c[..., 2, :] + u * c[..., 3, :]))
        if derivative == 1:
            return c[..., 1, :] + u * (2.0 * c[..., 2, :] + 3.0 * u * c[..., 3, :])
        if derivative == 2:
            return 2.0 * c[..., 2, :] + 6.0 * u * c[..., 3, :]
        raise ValueError(f"derivative = {derivative!r} is not one of 0, 1, 2")

    def sample(self, per_segment: int = 12) -> np.ndarray:
        """``per_segment`` points per segment at equal parameter steps, plus the last knot:
        shape ``(n * per_segment + 1, 2)``."""
        if int(per_segment) != per_segment or per_segment < 1:
            raise ValueError(f"samples per segment = {per_segment!r} is outside [1, inf)")
        per = int(per_segment)
        u = np.arange(per) / per
        seg = np.repeat(np.arange(self.n_segments), per)
        pts = self.evaluate(seg, np.tile(u, self.n_segments))
        return np.vstack([pts, self.knots[-1:]])

    def start_direction(self) -> np.ndarray:
        """Unit tangent leaving the start of the path: the first non-degenerate one (coincident
        first points, or a zero first tangent, are skipped)."""
        return self._direction(1)

    def end_direction(self) -> np.ndarray:
        """Unit tangent arriving at the end of the path (the last non-degenerate one)."""
        return self._direction(-1)

    def _direction(self, sign) -> np.ndarray:
        """The tangent direction where the path leaves its start (``sign`` 1) or arrives at its
        end (-1), skipping segments of no length: on the first (last) segment that has length,
        its tangent at that end; where that is zero (a handle on its knot), the second
        derivative's direction (``S(u) - S(0) ~ S''(0) u^2 / 2``); failing both, the chord."""
        per = 64
        pts = self.sample(per)[::sign]
        step = np.diff(pts, axis=0) * sign
        length = np.hypot(step[:, 0], step[:, 1])
        tiny = 1e-12 * max(float(np.abs(self.knots).max()), 1.0)
        ok = np.flatnonzero(length > tiny)
        if not len(ok):
            raise ValueError("path has no length: all its points coincide")
        i = int(ok[0]) // per
        seg, u = (i, 0.0) if sign > 0 else (self.n_segments - 1 - i, 1.0)
        for d in (self.evaluate(seg, u, 1), sign * self.evaluate(seg, u, 2), step[ok[0]]):
            if np.hypot(*d) > tiny:
                return d / np.hypot(*d)
        raise AssertionError("unreachable: the chord has length")

    def extended(self, length: float) -> "HermitePath":
        """This path with a straight run-out of ``length`` m along its end tangent (the planner
        looks beyond the end of the path; without a run-out it would turn back to the end)."""
        if not length > 0:
            return self
        d = self.end_direction() * length
        return HermitePath(np.vstack([self.knots, self.knots[-1] + d]),
                           np.vstack([self.t_out, d]), np.vstack([self.t_in, d]))

    def led_in(self, length: float) -> "HermitePath":
        """This path with a straight lead-in of ``length`` m before its start, along its start
        tangent (a follower strung out behind its leader starts there: docs/crowds.md)."""
        if not length > 0:
            return self
        d = self.start_direction() * length
        return HermitePath(np.vstack([self.knots[0] - d, self.knots]),
                           np.vstack([d, self.t_out]), np.vstack([d, self.t_in]))

    def split(self, s: float) -> tuple:
        """``(before, after)``: the path up to and from ``s`` m along it, ``0 < s <`` its
        length (on 64 chords a segment).  The segment there is split (de Casteljau) so that both
        parts are the rest of the curve unchanged; they meet at the chords' point at ``s`` (off
        the curve by at most a chord's sagitta, under a millimetre on a road)."""
        per = 64
        pts = self.sample(per)
        cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        if not 0.0 < s < cum[-1]:
            raise ValueError(f"{s:g} m along the path is not inside it (0, {cum[-1]:.1f}) m")
        i = int(np.searchsorted(cum, s, side="right")) - 1
        seg, frac = divmod(i, per)
        w = (s - cum[i]) / (cum[i + 1] - cum[i])
        u = (frac + w) / per
        k0, k1 = self.knots[seg], self.knots[seg + 1]
        p = [k0, k0 + self.t_out[seg] / 3.0, k1 - self.t_in[seg] / 3.0, k1]
        a = [p[j] + u * (p[j + 1] - p[j]) for j in range(3)]           # de Casteljau at u
        b = [a[j] + u * (a[j + 1] - a[j]) for j in range(2)]
        c = b[0] + u * (b[1] - b[0])                                     # on the curve at u
        at = pts[i] + w * (pts[i + 1] - pts[i])
        before = HermitePath(np.vstack([self.knots[:seg + 1], at]),
                             np.vstack([self.t_out[:seg], 3.0 * (a[0] - k0)]),
                             np.vstack([self.t_in[:seg], 3.0 * (c - b[0])]))
        after = HermitePath(np.vstack([at, self.knots[seg + 1:]]),
                            np.vstack([3.0 * (b[1] - c), self.t_out[seg + 1:]]),
                            np.vstack([3.0 * (k1 - a[2]), self.t_in[seg + 1:]]))
        return before, after

    def length(self, per_segment: int = 64) -> float:
        """Arc length (polyline through ``per_segment`` samples per segment), m."""
        return float(np.sum(np.linalg.norm(np.diff(self.sample(per_segment), axis=0), axis=1)))


class PathDistance:
    """``d(P)``: distance from foot positions ``P`` (shape ``(..., 2)``) to the path.

    Default: the paper's nearest-sample distance (Section 6, ``per_segment`` samples per spline
    segment).  ``exact=True``: distance to the spline's nearest point (a Newton refinement on every
    sample interval, started from the best of nine points on it).
    """

    def __init__(self, path: HermitePath, per_segment: int = 12, exact: bool = False,
                 _subset=None):
        self.path = path
        self.per_segment = int(per_segment)
        self.exact = bool(exact)
        pts = path.sample(self.per_segment)
        seg = np.minimum(np.arange(len(pts)) // self.per_segment, path.n_segments - 1)
        u = np.arange(len(pts)) / self.per_segment - seg
        self._all = (pts, seg, u)
        idx = np.arange(len(pts)) if _subset is None else np.asarray(_subset)
        self.samples = pts[idx]
        self._idx = idx
        self._key_p = -2.0 * self.samples.T                       # (2, n)
        self._key_s = np.einsum("nk,nk->n", self.samples, self.samples)

    def near(self, center, radius: float) -> "PathDistance":
        """The same distance function for points within ``radius`` of ``center``, on fewer samples.

        Exact: with ``d0`` the distance from ``center`` to the nearest sample, a point ``P`` in the
        disc has ``d(P) <= radius + d0``; a sample farther than ``2 radius + d0`` from ``center``
        is farther than that from ``P`` and can never be the nearest.
        """
        pts = self._all[0]
        r = np.linalg.norm(pts - np.asarray(center, float), axis=1)
        keep = np.flatnonzero(r <= 2.0 * radius + r.min() + 1e-9)
        if self.exact:            # keep the neighbouring samples: intervals need both ends
            keep = np.unique(np.clip(np.concatenate([keep - 1, keep, keep + 1]), 0, len(pts) - 1))
        return PathDistance(self.path, self.per_segment, self.exact, keep)

    def __call__(self, P) -> np.ndarray:
        P = np.asarray(P, float)
        flat = P.reshape(-1, 2)
        j = self._nearest(flat)
        r = flat - self.samples[j]
        d = np.sqrt(r[:, 0] * r[:, 0] + r[:, 1] * r[:, 1]).reshape(P.shape[:-1])
        if self.exact:
            d = np.minimum(d, self._refined(P))
        return d

    def _nearest(self, flat):
        """Index of the nearest sample to each row of ``flat`` (shape ``(m, 2)``).

        ``|P - S|^2 = |P|^2 - 2 P.S + |S|^2``: one matrix product finds the nearest sample; the
        distance itself is then computed directly (so it has full precision near the path).
        """
        if len(flat) < 8 or len(self.samples) < 16:
            key = flat @ self._key_p + self._key_s     # (m, n): |S|^2 - 2 P.S
            return np.argmin(key, axis=1)
        # Only samples that can be nearest to some point of the points' bounding box: a sample
        # nearer to the box than another is to its farthest corner (exact, with a margin for
        # rounding; the planner's batches are close together and keep a tenth of the samples).
        S = self.samples
        lo, hi = flat.min(axis=0), flat.max(axis=0)
        gap = np.maximum(np.maximum(lo - S, S - hi), 0.0)
        far = np.maximum(np.abs(S - lo), np.abs(S - hi))
        reach = np.einsum("nk,nk->n", far, far).min()
        keep = np.flatnonzero(np.einsum("nk,nk->n", gap, gap) <= reach * (1 + 1e-9) + 1e-12)
        key = flat @ self._key_p[:, keep] + self._key_s[keep]
        return keep[np.argmin(key, axis=1)]

    def nearest_index(self, P) -> np.ndarray:
        """Index (into the full sample list) of the nearest sample to each point."""
        P = np.asarray(P, float)
        return self._idx[self._nearest(P.reshape(-1, 2))].reshape(P.shape[:-1])

    def _refined(self, P):
        pts, seg, u = self._all
        idx = self._idx
        # Sample intervals [j, j+1] with both ends present (u from u[j] to u[j] + du on the
        # segment of sample j; the last interval of a segment ends on the next knot).
        j = idx[:-1][(np.diff(idx) == 1)]
        if len(j) == 0:
            return np.full(P.shape[:-1], np.inf)
        s = seg[j]
        u0 = u[j]
        du = 1.0 / self.per_segment
        flat = P.reshape(-1, 2)[:, None, :]
        # Start from the best of 9 points on each interval, then Newton within its eighth:
        # a short arc's squared distance has one minimum per eighth of the interval.
        k = np.linspace(0.0, 1.0, 9)
        best_w = np.zeros((len(flat), len(j)))
        best_d = np.full((len(flat), len(j)), np.inf)
        for w in k:
            r = self.path.evaluate(s, u0 + w * du) - flat
            d2 = np.einsum("mjk,mjk->mj", r, r)
            better = d2 < best_d
            best_d = np.where(better, d2, best_d)
            best_w = np.where(better, w, best_w)
        lo = u0 + np.maximum(best_w - 0.125, 0.0) * du
        hi = u0 + np.minimum(best_w + 0.125, 1.0) * du
        uu = u0 + best_w * du
        for _ in range(4):      # Newton on g(u) = (S(u) - P) . S'(u)
            S = self.path.evaluate(s, uu)
            S1 = self.path.evaluate(s, uu, 1)
            S2 = self.path.evaluate(s, uu, 2)
            r = S - flat
            g = np.einsum("mjk,mjk->mj", r, S1)
            h = np.einsum("mjk,mjk->mj", S1, S1) + np.einsum("mjk,mjk->mj", r, S2)
            step = np.where(h > 0, g / np.where(h > 0, h, 1.0), 0.0)
            uu = np.clip(uu - step, lo, hi)
        r = self.path.evaluate(s, uu) - flat
        d = np.sqrt(np.einsum("mjk,mjk->mj", r, r).min(axis=1))
        return d.reshape(P.shape[:-1])


class PathProgress:
    """Arc length along the path reached so far, m.

    The path is sampled at ``per_segment`` equal parameter steps per segment (arc lengths: the
    polyline through the samples).  :meth:`advance` is called for each small move of the foot
    (``travel`` m): the progress ``p`` moves to the arc length of the sample nearest the foot
    among those from ``p - near`` to ``p + 2 travel + spacing`` along the path (``spacing``: the
    largest between samples; ties go to the sample nearest ``p`` along the path), if the foot is
    within ``near`` of it, and never backwards.  So the progress goes through the path in order,
    no faster than twice the foot (the nearest point runs ahead of the foot only inside a curve,
    by ``R / (R - e)`` at ``e`` m inside a radius ``R``): it cannot jump to the other leg of a
    switchback or the end of a loop, and a foot farther than ``near`` from the path makes none.
    The end is reached when the progress is the path's length (the foot is nearest the last
    sample) and the foot has crossed the line through the end, normal to the end direction.
    """

    def __init__(self, path: HermitePath, near: float, per_segment: int = 64):
        if not near > 0:
            raise ValueError(f"progress distance = {near!r} is outside the allowed range (0, inf)")
        self.near = float(near)
        self.samples = path.sample(per_segment)
        step = np.hypot(*np.diff(self.samples, axis=0).T)
        self.arc = np.concatenate([[0.0], np.cumsum(step)])
        self.spacing = float(step.max())
        self.length = float(self.arc[-1])
        self.end = path.knots[-1]
        self.end_dir = path.end_direction()

    def advance(self, p: float, xy, travel: float) -> float:
        """The progress after the foot moved ``travel`` m to ``xy``, from progress ``p``."""
        lo = np.searchsorted(self.arc, p - self.near, side="left")
        hi = np.searchsorted(self.arc, p + 2.0 * travel + self.spacing, side="right")
        cand = self.samples[lo:hi] - np.asarray(xy, float)[None, :2]
        d = np.hypot(cand[:, 0], cand[:, 1])
        best = np.flatnonzero(d <= d.min() * (1 + 1e-12) + 1e-12)
        j = lo + best[np.argmin(np.abs(self.arc[lo + best] - p))]
        if d[j - lo] > self.near:
            return float(p)
        return float(max(p, self.arc[j]))

    def at_end(self, p: float, xy) -> bool:
        """Has the foot at ``xy`` with progress ``p`` reached the end of the path?"""
        crossed = float(np.dot(np.asarray(xy, float)[:2] - self.end, self.end_dir)) >= 0.0
        return bool(p >= self.length and crossed)


@dataclass(frozen=True)
class PathDeviation:
    """Where a foot track is farthest from the path it followed (SI units)."""

    distance: float
    """The largest distance from the foot to the path (the spline itself), m."""
    t: float
    """When, s (the track's own time)."""
    xy: tuple
    """Where the foot was then, m."""
    along: float
    """Where along the path: the arc length to the path's point nearest the foot then, m."""


#: Samples per segment of :func:`path_deviation`'s arc length (the exact distance needs no more).
_DEVIATION_SAMPLES = 64


def path_deviation(path: HermitePath, t, x, y) -> PathDeviation:
    """The largest exact distance from the foot track ``(x, y)`` (at times ``t``) to ``path``,
    when, where, and how far along the path (:class:`PathDeviation`)."""
    P = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
    if len(P) == 0:
        raise ValueError("path_deviation: the track has no samples")
    dist = PathDistance(path, _DEVIATION_SAMPLES, exact=True)
    d = dist(P)
    k = int(np.argmax(d))
    pts = dist.samples
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
    j = int(dist.nearest_index(P[k:k + 1])[0])
    return PathDeviation(float(d[k]), float(np.asarray(t, float)[k]),
                         (float(P[k, 0]), float(P[k, 1])), float(arc[j]))

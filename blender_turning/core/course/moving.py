"""Figures as moving obstacles for one another: the bodies of figures already
planned, and the planner's time-aware check of a figure's track against them.

**The body.**  At time ``t`` a figure occupies the segment from its foot to the ground point
under its centre of mass: the CM sits ``l sin theta_v`` to the left of the foot across the
heading (Fig. 2; ``theta_v > 0`` leans left, docs/ARCHITECTURE.md Section 4), the same point as
:meth:`.planner.Problem.body_point`.  :class:`MovingBodies` holds those segments for figures
already planned, sampled every ``dt`` at the times ``m dt`` (whole ``m``) of one clock, each end
moving in a straight line from one sample to the next: the planner treats its own foot and
body point the same way within one integration step (Section 6 checks the track's straight
step segments).  A body exists from the first to the last sample of its trajectory (before its
start and after its end or fall it is not in the shot); it is linearly interpolated onto the
grid from its own samples (exact where its samples are on the grid: same ``dt``, time offsets
whole multiples of it).

**The rule the planner applies** (:meth:`MovingBodies.collides`, from
``Problem.simulate_stage``): a step of the planning figure from ``t`` to ``t + dt`` collides
with a body when, at some moment of the step, the two segments come within ``clearance`` of
each other.  Both segments' ends move linearly over the step, so with ``tau`` in ``[0, 1]`` the
distance ``d(tau) = min_{s,u} |(1-s) P + s Q - (1-u) R - u S|`` (``P Q`` the planner's foot and
body point, ``R S`` the body's) is a minimum of norms of vectors affine in ``tau`` whose rates
``(1-s) dP + s dQ - (1-u) dR - u dS`` are at most ``L = max |dP - dR|, |dP - dS|, |dQ - dR|,
|dQ - dS|`` long (a convex function of ``(s, u)`` peaks at a corner of the square): ``d`` is
``L``-Lipschitz, and over a part ``[a, b]`` of the step ``d >= (d(a) + d(b) - L (b - a)) / 2``.
A step collides when ``d`` at a tested moment is ``<= clearance``, or when, after halving the
step up to :data:`BISECTIONS` times where that bound is ``<= clearance``, some part's bound
still is: a guarantee in continuous time (no plan passes within the clearance between the
samples), at most ``L / 2**(BISECTIONS + 1)`` stricter than the exact rule (relative motion
``L`` is about 1 m per 0.05 s step for two figures meeting head on at 10 m/s, so 3 cm).

Everything is vectorised over steps and bodies, with a bounding-box test first.  Each body's
answer depends on its own samples only, so adding a body that never comes near changes
nothing, bit for bit (the crowd runner's independent groups rest on this: ``crowd/runner.py``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .obstacles import segment_distance

__all__ = ["MovingBodies", "around", "closest_approach", "BISECTIONS"]

#: Halvings of a step whose Lipschitz bound is inconclusive (module doc).
BISECTIONS = 4

#: How far (in steps) a query time may be from the grid (rounding of ``t0 + k dt``).
_ON_GRID = 1e-6


@dataclass(frozen=True, eq=False)
class MovingBodies:
    """``foot[j, k]`` and ``cm[j, k]`` (shape ``(n_bodies, n, 2)``, m): body ``j``'s foot and CM
    ground point at ``t = (m0 + k) dt``; NaN where body ``j`` is not in the shot.
    ``clearance``: the distance kept from every body, m: one number, or one per body (shape
    ``(n_bodies,)``: a pair that starts closer than a crowd's clearance keeps less,
    ``crowd/priority.py``).  ``log``: when a list, every
    :meth:`near` appends ``(x, y, radius, t_lo, t_hi)`` of its query to it (the region a
    figure's searches looked at: ``crowd/runner.py``)."""

    names: tuple
    dt: float
    m0: int
    foot: np.ndarray
    cm: np.ndarray
    clearance: float | np.ndarray = 0.0
    log: list | None = None

    @classmethod
    def from_tracks(cls, tracks, dt: float = 0.1, clearance: float = 0.0,
                    shift: float = 0.0, log: list | None = None) -> "MovingBodies":
        """``tracks``: ``(name, trajectory, l)`` triples (``l``: the body's CM height, m;
        trajectories without samples are left out).  Sampled at ``m dt`` on a clock reading
        ``t - shift`` (``shift``: a planning figure's time offset, to put the bodies on its own
        clock).  ``clearance``: one number, or one per track."""
        if not (dt > 0 and math.isfinite(dt)):
            raise ValueError(f"dt = {dt!r} is outside the allowed range (0, inf)")
        tracks = list(tracks)
        cl = np.asarray(clearance, float)
        if cl.ndim and cl.shape != (len(tracks),):
            raise ValueError(f"clearance: {cl.shape[0]} values for {len(tracks)} tracks")
        if not (np.all(cl >= 0) and np.all(np.isfinite(cl))):
            raise ValueError(f"clearance = {clearance!r} is outside the allowed range [0, inf)")
        keep = [tr is not None and len(tr) for _, tr, _ in tracks]
        tracks = [t for t, k in zip(tracks, keep) if k]
        cl = cl[np.array(keep, bool)] if cl.ndim else float(cl)
        if not tracks:
            return cls((), float(dt), 0, np.zeros((0, 1, 2)), np.zeros((0, 1, 2)), cl, log)
        times = [np.asarray(tr.t, float) - shift for _, tr, _ in tracks]
        m0 = int(math.floor(min(float(t[0]) for t in times) / dt + 1e-9))
        m1 = int(math.ceil(max(float(t[-1]) for t in times) / dt - 1e-9))
        grid = dt * np.arange(m0, m1 + 1)                 # m dt: the same whatever the set
        foot = np.full((len(tracks), len(grid), 2), np.nan)
        cm = np.full_like(foot, np.nan)
        for j, ((_, tr, l), t) in enumerate(zip(tracks, times)):
            ok = ~np.isnan(tr.x)
            x, y, head, lean = (np.interp(grid, t[ok], v[ok], left=np.nan, right=np.nan)
                                for v in (tr.x, tr.y, tr.theta_dir, tr.theta_v))
            foot[j, :, 0], foot[j, :, 1] = x, y
            side = l * np.sin(lean)                          # to the left of the heading
            cm[j, :, 0], cm[j, :, 1] = x - side * np.sin(head), y + side * np.cos(head)
        return cls(tuple(n for n, _, _ in tracks), float(dt), m0, foot, cm, cl, log)

    def clearances(self) -> np.ndarray:
        """The clearance kept from each body, m, shape ``(n_bodies,)``."""
        return np.broadcast_to(np.asarray(self.clearance, float), (len(self.names),))

    @property
    def t0(self) -> float:
        """The time of the first sample, s."""
        return self.m0 * self.dt

    def __len__(self) -> int:
        return len(self.names)

    def at(self, t) -> tuple:
        """Foot and CM points of every body at times ``t`` (nearest sample): two arrays of shape
        ``(n_bodies,) + shape(t) + (2,)``, NaN for bodies not in the shot then."""
        k = np.rint(np.asarray(t, float) / self.dt).astype(int) - self.m0
        inside = (k >= 0) & (k < self.foot.shape[1])
        kk = np.clip(k, 0, self.foot.shape[1] - 1)
        mask = np.where(inside, 1.0, np.nan)[None, ..., None]
        return self.foot[:, kk] * mask, self.cm[:, kk] * mask

    # -- the planner's side ---------------------------------------------------------------------

    def _seen(self, center, radius, t_lo, t_hi) -> np.ndarray:
        """Which bodies come within ``radius + clearance`` of ``center`` (box test per grid
        interval, exact: only bodies that cannot come near are left out) between ``t_lo`` and
        ``t_hi`` (``None``: any time)."""
        n = self.foot.shape[1]
        k0 = 0 if t_lo is None else max(int(math.floor(t_lo / self.dt)) - self.m0 - 1, 0)
        k1 = n if t_hi is None else min(int(math.ceil(t_hi / self.dt)) - self.m0 + 2, n)
        if k1 - k0 < 1 or not len(self.names):
            return np.zeros(len(self.names), bool)
        pts = np.concatenate([self.foot[:, k0:k1], self.cm[:, k0:k1]], axis=2)
        pts = pts.reshape(len(self.names), k1 - k0, 2, 2)
        lo, hi = pts.min(axis=2), pts.max(axis=2)         # NaN: absent, never near
        if k1 - k0 > 1:                                   # an interval's moves, both ends
            lo = np.minimum(lo[:, 1:], lo[:, :-1])
            hi = np.maximum(hi[:, 1:], hi[:, :-1])
        c = np.asarray(center, float)
        r = (radius + self.clearances())[:, None, None]
        return np.any(np.all((lo <= c + r) & (hi >= c - r), axis=2), axis=1)

    def near(self, center, radius: float, t_lo: float | None = None,
             t_hi: float | None = None) -> "MovingBodies":
        """The bodies that a track within ``radius`` of ``center`` between ``t_lo`` and
        ``t_hi`` could come within the clearance of (:meth:`Problem.local`)."""
        if self.log is not None:
            self.log.append((float(center[0]), float(center[1]), float(radius),
                             -math.inf if t_lo is None else float(t_lo),
                             math.inf if t_hi is None else float(t_hi)))
        keep = self._seen(center, radius, t_lo, t_hi)
        cl = self.clearance if np.ndim(self.clearance) == 0 else self.clearance[keep]
        return replace(self, names=tuple(n for n, k in zip(self.names, keep) if k),
                       foot=self.foot[keep], cm=self.cm[keep], clearance=cl)

    def seen_by(self, queries) -> np.ndarray:
        """Which bodies any of ``queries`` (rows ``(x, y, radius, t_lo, t_hi)`` of a
        :attr:`log`) would have kept: :meth:`near`'s own test."""
        seen = np.zeros(len(self.names), bool)
        for x, y, r, lo, hi in np.reshape(queries, (-1, 5)):
            seen |= self._seen((x, y), r, None if lo == -math.inf else lo,
                               None if hi == math.inf else hi)
        return seen

    def collides(self, foot, body, t0, dt: float) -> np.ndarray:
        """Which columns of a stage collide (module doc).  ``foot``, ``body``: the planning
        figure's foot and body point at the ends of its integration steps, shape ``(2, S + 1,
        m)``; ``t0``: each column's start time (shape ``(m,)``), on the bodies' clock and grid;
        ``dt``: the step, which must be the bodies' ``dt``."""
        foot = np.asarray(foot, float)
        steps, m = foot.shape[1] - 1, foot.shape[2]
        hit = np.zeros(steps * m, bool)
        if not len(self.names) or not steps:
            return np.zeros(m, bool)
        if abs(dt - self.dt) > 1e-12 * self.dt:
            raise ValueError(f"the planner's step dt = {dt!r} s is not the moving bodies' "
                             f"sampling step {self.dt!r} s")
        g = np.broadcast_to(np.asarray(t0, float), (m,)) / self.dt
        k = np.rint(g)
        if np.any(np.abs(g - k) > _ON_GRID):
            raise ValueError(f"step times {np.asarray(t0).ravel()[:3]} s are not on the moving "
                             f"bodies' grid (multiples of {self.dt!r} s)")
        k = (k.astype(np.int64) - self.m0)[None, :] + np.arange(steps)[:, None]   # (S, m)
        n = self.foot.shape[1]
        # The whole stage first: the bodies whose box over its time span meets the track's.
        a, b = min(max(int(k.min()), 0), n), min(max(int(k.max()) + 2, 0), n)
        if a >= b or n < 2:                # one sample (a plan failed at its start): no step
            return np.zeros(m, bool)
        theirs = np.concatenate([self.foot[:, a:b], self.cm[:, a:b]], axis=1)
        body = np.asarray(body, float)
        mine = np.concatenate([foot.reshape(2, -1), body.reshape(2, -1)], axis=1)
        cl = self.clearances()[:, None]
        near = np.all((np.fmin.reduce(theirs, axis=1) <= mine.max(axis=1) + cl) &
                      (np.fmax.reduce(theirs, axis=1) >= mine.min(axis=1) - cl),
                      axis=1)                            # all NaN (absent): False
        if not near.any():
            return np.zeros(m, bool)
        inside = (k >= 0) & (k + 1 < n)
        kk = np.clip(k, 0, max(n - 2, 0))
        # Step instances (i: flat (S, m)) against bodies (j), box test first.
        P0, P1 = (np.moveaxis(foot[:, s], 0, -1).reshape(-1, 2) for s in
                  (slice(0, -1), slice(1, None)))
        Q0, Q1 = (np.moveaxis(body[:, s], 0, -1).reshape(-1, 2) for s in
                  (slice(0, -1), slice(1, None)))
        F, C = self.foot[near], self.cm[near]
        R0, R1 = F[:, kk.ravel()], F[:, kk.ravel() + 1]                     # (B, S m, 2)
        S0, S1 = C[:, kk.ravel()], C[:, kk.ravel() + 1]
        cl = cl[near]                                     # (B, 1): each body's clearance
        mine = np.stack([P0, P1, Q0, Q1])
        lo, hi = mine.min(axis=0), mine.max(axis=0)
        theirs = np.stack([R0, R1, S0, S1])
        box = np.all((theirs.min(axis=0) <= hi + cl[..., None]) &
                     (theirs.max(axis=0) >= lo - cl[..., None]), axis=2)
        j, i = np.nonzero(box & inside.ravel()[None, :])
        if len(i):
            hit[i[_pair_collides(P0[i], P1[i], Q0[i], Q1[i], R0[j, i], R1[j, i], S0[j, i],
                                 S1[j, i], cl[j, 0])]] = True
        return hit.reshape(steps, m).any(axis=0)


def _pair_collides(P0, P1, Q0, Q1, R0, R1, S0, S1, cl) -> np.ndarray:
    """The rule of the module doc for pairs of moving segments ``P Q`` and ``R S`` (rows),
    each pair keeping its clearance ``cl`` (one number or one per row)."""
    dP, dQ, dR, dS = P1 - P0, Q1 - Q0, R1 - R0, S1 - S0
    L = np.max([np.hypot(*(a - b).T) for a in (dP, dQ) for b in (dR, dS)], axis=0)
    d0 = segment_distance(P0, Q0, R0, S0)
    d1 = segment_distance(P1, Q1, R1, S1)
    cl = np.broadcast_to(cl, d0.shape)
    hit = (d0 <= cl) | (d1 <= cl)
    # Parts of steps still in doubt: (pair, a, b, d(a), d(b)).
    idx = np.flatnonzero(~hit & (0.5 * (d0 + d1 - L) <= cl))
    a, b = np.zeros(len(idx)), np.ones(len(idx))
    da, db = d0[idx], d1[idx]
    for _ in range(BISECTIONS):
        if not len(idx):
            break
        mid = 0.5 * (a + b)
        w = mid[:, None]
        dm = segment_distance(P0[idx] + w * dP[idx], Q0[idx] + w * dQ[idx],
                              R0[idx] + w * dR[idx], S0[idx] + w * dS[idx])
        c = cl[idx]
        hit[idx[dm <= c]] = True
        half = 0.5 * (b - a) * L[idx]
        left = ~hit[idx] & (0.5 * (da + dm - half) <= c)
        right = ~hit[idx] & (0.5 * (dm + db - half) <= c)
        idx = np.concatenate([idx[left], idx[right]])
        a, b = np.concatenate([a[left], mid[right]]), np.concatenate([mid[left], b[right]])
        da, db = np.concatenate([da[left], dm[right]]), np.concatenate([dm[left], db[right]])
        keep = ~hit[idx]                       # a part of a pair already hit needs no more
        idx, a, b, da, db = idx[keep], a[keep], b[keep], da[keep], db[keep]
    hit[idx] = True                            # still in doubt: counted as a collision
    return hit


def around(problem, bodies: MovingBodies | None):
    """A copy of the planning ``problem`` (:class:`.planner.Problem`) that avoids ``bodies``
    (on the planning figure's own clock, sampled at its integration step ``dt``) besides its
    obstacles; ``None``: none."""
    if bodies is not None and abs(bodies.dt - problem.settings.dt) > 1e-12 * bodies.dt:
        raise ValueError(f"the moving bodies are sampled every {bodies.dt!r} s; the planner "
                         f"steps {problem.settings.dt!r} s")
    p = type(problem).__new__(type(problem))
    p.__dict__.update(problem.__dict__)
    p.movers = bodies
    return p


def closest_approach(bodies: MovingBodies) -> dict:
    """For each body: ``(distance m, the other body's name, t s)`` of its closest approach to
    any other body's foot-CM segment at the same sample; ``(inf, None, None)`` when it never
    shares the shot.  Of equal distances the other body first in ``names``, then the earliest
    sample, wins.

    Near-linear in the samples: the segments of every sample are put in a grid of cells ``h``
    wide by their midpoints, and a body's segments are compared with those of the same sample
    in the 3 x 3 cells around.  A segment outside them has its midpoint ``h`` or more away, so
    it is at least ``h - 2 r`` away (``r``: the longest half segment); a body whose closest
    candidate is no farther than that has its answer.  The others are asked again with cells
    four times as wide, until the cells span the whole shot (:func:`_closest_brute`, the
    all-pairs rule, gives the same answers: a test holds them equal)."""
    n = len(bodies.names)
    out = {name: (math.inf, None, None) for name in bodies.names}
    ok = ~(np.isnan(bodies.foot).any(axis=2) | np.isnan(bodies.cm).any(axis=2))
    jj, kk = np.nonzero(ok)                          # the items: (body, sample) in the shot
    if n < 2 or not len(jj):
        return out
    F, C = bodies.foot[jj, kk], bodies.cm[jj, kk]
    mid = 0.5 * (F + C)
    r = 0.5 * float(np.sqrt(((C - F) ** 2).sum(axis=1)).max())
    lo, span = mid.min(axis=0), float((mid.max(axis=0) - mid.min(axis=0)).max())
    # Cells about as wide as the bodies' spacing at one moment (a crowd on the move covers
    # much more ground over the shot than at any sample), and wide enough to resolve anything.
    h = max(4.0 * r, 1e-3, _spacing(kk, mid))
    found = []                                       # (body, other, sample, distance) winners
    todo = np.ones(n, bool)
    while todo.any():
        whole = h > 2.0 * span                       # one cell holds everything: exact
        win = _closest_in_cells(jj, kk, F, C, mid, lo, h, todo)
        bound = math.inf if whole else h - 2.0 * r
        done = np.zeros(n, bool)
        if len(win):
            good = win[:, 3] <= bound
            found.append(win[good])
            done[win[good, 0].astype(int)] = True
        todo &= ~done
        if whole:
            break
        h *= 4.0
    if not found:
        return out
    win = np.concatenate(found)
    for j, i, k, d in win:
        out[bodies.names[int(j)]] = (float(d), bodies.names[int(i)],
                                     bodies.t0 + int(k) * bodies.dt)
    return out


def _spacing(kk, mid) -> float:
    """The median over the samples of ``sqrt(area / bodies)``: ``area`` the box around the
    bodies' midpoints at that sample."""
    m = int(kk.max()) + 1
    box = np.full((4, m), np.inf)
    box[2:] = -np.inf
    np.minimum.at(box[0], kk, mid[:, 0])
    np.minimum.at(box[1], kk, mid[:, 1])
    np.maximum.at(box[2], kk, mid[:, 0])
    np.maximum.at(box[3], kk, mid[:, 1])
    count = np.bincount(kk, minlength=m)
    on = count > 1
    if not on.any():
        return 0.0
    wide = np.maximum(box[2:, on] - box[:2, on], 1e-3)
    return float(np.median(np.sqrt(wide[0] * wide[1] / count[on])))


def _closest_in_cells(jj, kk, F, C, mid, lo, h, todo, chunk=500_000):
    """For the bodies ``todo``: the closest segment of another body at the same sample among
    those in the 3 x 3 cells (``h`` wide) around each of its segments; rows ``(body, other,
    sample, distance)``, one per body that has a candidate (ties: the other body first in
    order, then the earliest sample)."""
    cx = np.floor((mid[:, 0] - lo[0]) / h).astype(np.int64) + 1
    cy = np.floor((mid[:, 1] - lo[1]) / h).astype(np.int64) + 1
    nx, ny = int(cx.max()) + 2, int(cy.max()) + 2
    key = (kk.astype(np.int64) * nx + cx) * ny + cy
    order = np.argsort(key, kind="stable")
    skey = key[order]
    queries = np.nonzero(todo[jj])[0]
    rows = []
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            want = key[queries] + dx * ny + dy
            a = np.searchsorted(skey, want, "left")
            b = np.searchsorted(skey, want, "right")
            count = b - a
            q_all = np.repeat(queries, count)
            starts = np.repeat(a - np.cumsum(count) + count, count)
            t_all = order[starts + np.arange(len(q_all))] if len(q_all) else q_all
            for s in range(0, len(q_all), chunk):
                q, t = q_all[s:s + chunk], t_all[s:s + chunk]
                keep = jj[q] != jj[t]
                q, t = q[keep], t[keep]
                d = segment_distance(F[q], C[q], F[t], C[t])
                rows.append(_winners(np.stack([jj[q], jj[t], kk[q], d], axis=1)))
    return _winners(np.concatenate(rows)) if rows else np.zeros((0, 4))


def _winners(rows):
    """Of rows ``(body, other, sample, distance)``, each body's closest (ties: the other body
    first in order, then the earliest sample)."""
    if not len(rows):
        return rows
    rows = rows[np.lexsort((rows[:, 2], rows[:, 1], rows[:, 3], rows[:, 0]))]
    return rows[np.unique(rows[:, 0], return_index=True)[1]]


def _closest_brute(bodies: MovingBodies) -> dict:
    """:func:`closest_approach` by comparing every pair of bodies (quadratic: the reference its
    test holds the grid to)."""
    n = len(bodies.names)
    out = {}
    for j in range(n):
        others = [i for i in range(n) if i != j]
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

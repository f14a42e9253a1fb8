"""Priority planning: the path figures a crowd's ``priority`` names plan in that
order, each around the bodies of those before it (moving obstacles: :mod:`..core.course.moving`),
and groups of figures that cannot see each other plan in parallel.

The result is defined as planning one figure after another, each with every body before it;
the groups only make it faster, and they give the same result bit for bit:

- Each figure's searches look only at the bodies that :meth:`Problem.local` keeps, i.e. those
  that come near the search's root within its horizon (``MovingBodies.near``, exact: a body it
  drops cannot touch any branch), and a body's answers depend on its own samples only.  Each
  figure records the regions its searches looked at (the ``near`` queries, on its own clock:
  :attr:`.runner.FigureResult.region`).
- Groups are first guessed from space-time boxes of the figures' paths and time windows
  (:func:`initial_groups`) and planned in parallel, in priority order within each.  Then every
  figure's regions are checked against the bodies of the figures before it in other groups
  (:func:`conflicts`, with ``near``'s own test).  Where one would have been kept, the two groups
  merge and the merged group is planned again; the rest stand.  When no figure sees a body of
  another group, each figure's searches were exactly those of one-after-another planning (by
  induction over the priority order), so its trajectory is too.

The guess only decides how much is planned twice.  Nothing depends on which worker finishes
first, so the result is the same whatever the engine and the number of workers.
"""
from __future__ import annotations

import numpy as np

from ..core.course.moving import MovingBodies
from ..core.course.obstacles import segment_distance

__all__ = ["START_SHARE", "pair_clearances", "bodies_for", "initial_groups", "conflicts", "merge"]


#: The share of their distance at the start that two figures starting closer than the
#: clearance keep (docs/crowds.md, "Figures that start close").
START_SHARE = 0.5


def start_segment(f) -> np.ndarray:
    """The path figure ``f``'s body at its start: foot and CM ground point, shape ``(2, 2)``
    (:meth:`..core.planner.Problem.body_point` of its start state)."""
    x, y, head, lean = np.asarray(f.controller.scene.state0, float)[:4]
    side = f.figure.body.l * np.sin(lean)
    return np.array([[x, y], [x - side * np.sin(head), y + side * np.cos(head)]])


def pair_clearances(f, tracks, clearance: float) -> np.ndarray:
    """The clearance ``f`` keeps from each of ``tracks`` (``(name, trajectory, l)``, on the
    crowd's clock): ``clearance``, but where a body is in the shot when ``f`` starts and its
    segment is then within ``clearance`` of ``f``'s (riders of a peloton side by side, a
    synchronised pair), :data:`START_SHARE` of that distance: they keep most of the room they
    start with instead of an infeasible start."""
    mine = start_segment(f)
    out = np.full(len(tracks), float(clearance))
    for k, (_, tr, l) in enumerate(tracks):
        if tr is None or not len(tr) or not tr.t[0] <= f.time_offset <= tr.t[-1]:
            continue
        x, y, head, lean = (float(np.interp(f.time_offset, tr.t, v))
                            for v in (tr.x, tr.y, tr.theta_dir, tr.theta_v))
        side = l * np.sin(lean)
        d = float(segment_distance(mine[0], mine[1], np.array([x, y]),
                                   np.array([x - side * np.sin(head), y + side * np.cos(head)])))
        if d <= clearance:
            out[k] = START_SHARE * d
    return out


def bodies_for(f, tracks, clearance: float, log: list | None = None) -> MovingBodies:
    """``tracks`` (``(name, trajectory, l)``, on the crowd's clock) as the path figure ``f``
    plans around them: sampled at its planner's step, on its own clock, each kept at its
    :func:`pair_clearances`."""
    sc = f.controller.scene
    tracks = list(tracks)
    return MovingBodies.from_tracks(tracks, sc.settings.dt,
                                    pair_clearances(f, tracks, clearance),
                                    shift=f.time_offset, log=log)


def _box(f, clearance: float) -> np.ndarray:
    """A guess of where and when ``f`` moves: its path's box grown by one search's reach, its
    body and half the clearance; from its start to its time limit.  ``(x0, y0, x1, y1, t0,
    t1)``."""
    sc = f.controller.scene
    setup = sc.setup()
    grow = setup.problem().reach() + sc.figure.body.l + 0.5 * clearance
    pts = sc.path.sample(16)
    span = sc.duration if sc.duration is not None else setup.time_limit()
    return np.concatenate([pts.min(axis=0) - grow, pts.max(axis=0) + grow,
                           [f.time_offset, f.time_offset + span]])


def _components(n: int, pairs) -> list:
    root = list(range(n))

    def find(i):
        while root[i] != i:
            root[i] = root[root[i]]
            i = root[i]
        return i
    for a, b in pairs:
        ra, rb = find(a), find(b)
        if ra != rb:
            root[max(ra, rb)] = min(ra, rb)
    groups = {}
    for i in range(n):
        groups.setdefault(find(i), []).append(i)
    return [tuple(g) for g in groups.values()]


def initial_groups(figures, clearance: float) -> list:
    """Indices of ``figures`` (in priority order) grouped where their boxes (:func:`_box`)
    overlap, transitively; each group in priority order, groups by their first figure."""
    boxes = np.array([_box(f, clearance) for f in figures])
    pairs = [(i, j) for i in range(len(figures)) for j in range(i)
             if np.all(boxes[i, :2] <= boxes[j, 2:4]) and np.all(boxes[j, :2] <= boxes[i, 2:4])
             and boxes[i, 4] <= boxes[j, 5] and boxes[j, 4] <= boxes[i, 5]]
    return sorted(_components(len(figures), pairs))


def conflicts(figures, groups, results, clearance: float) -> list:
    """Pairs of group indices ``(a, b)``: a figure of group ``b`` would have kept, in one of its
    searches (its ``region``), the body of a figure of group ``a`` before it."""
    where = {i: g for g, members in enumerate(groups) for i in members}
    out = set()
    boxes = [_track_box(f, results[i].trajectory, clearance) for i, f in enumerate(figures)]
    for k, fk in enumerate(figures):
        region = results[k].region
        if region is None or not len(region):
            continue
        x, y, r = region[:, 0], region[:, 1], region[:, 2]
        pad = 4.0 * fk.controller.scene.settings.dt          # near's window: a few steps more
        reach = np.array([(x - r).min(), (y - r).min(), (x + r).max(), (y + r).max(),
                          region[:, 3].min() + fk.time_offset - pad,
                          region[:, 4].max() + fk.time_offset + pad])
        for j in range(k):
            tr = results[j].trajectory
            if where[j] == where[k] or (where[j], where[k]) in out or boxes[j] is None or \
                    not _overlap(boxes[j], reach):      # a quick test first (conservative)
                continue
            body = bodies_for(fk, [(figures[j].name, tr, figures[j].figure.body.l)], clearance)
            if body.seen_by(region).any():
                out.add((where[j], where[k]))
    return sorted(out)


def _track_box(f, tr, clearance: float):
    """Where and when a trajectory's body is, grown by its CM height and the clearance:
    ``(x0, y0, x1, y1, t0, t1)`` on the crowd's clock, or ``None``."""
    if tr is None or not len(tr):
        return None
    grow = f.figure.body.l + clearance
    lo, hi = np.fmin.reduce, np.fmax.reduce                 # NaN samples left out
    return np.array([lo(tr.x) - grow, lo(tr.y) - grow, hi(tr.x) + grow, hi(tr.y) + grow,
                     tr.t[0], tr.t[-1]])


def _overlap(a, b) -> bool:
    return bool(a[0] <= b[2] and b[0] <= a[2] and a[1] <= b[3] and b[1] <= a[3]
                and a[4] <= b[5] and b[4] <= a[5])


def merge(groups, pairs) -> list:
    """``groups`` with those joined by ``pairs`` merged (members in priority order)."""
    joined = _components(len(groups), pairs)
    return sorted(tuple(sorted(i for g in c for i in groups[g])) for c in joined)

"""The branch-and-bound search of Fig. 14, made exact-and-fast, and the exhaustive reference.

Nodes are the states at stage boundaries (Fig. 13).  A node's ``f`` is ``sum d_i`` over the track
samples so far (Section 6); ``f`` never decreases along a branch, so a node whose ``f`` (plus an
admissible lower bound on the cost still to come) exceeds the best complete plan found so far
cannot lead to a better one and is clipped.  Clipping uses a strict ``>`` (with a 1e-9 relative
tolerance for rounding), so the search returns the same optimal ``f_opt`` as the exhaustive search
of all ``q^N`` plans, whatever the order in which it expands nodes; of plans with exactly the
same ``f_opt`` it returns the one with the lexicographically smallest choices, so the plan does
not depend on the order either (mirror-image plans tie on a straight path).

Beyond the paper (each switchable, for the benchmarks and the exactness tests):

- warm start: the previous plan shifted by one stage (all q choices for the new last stage) is
  simulated first and gives the first upper bound; without a previous plan, a greedy dive does;
- lower bound: ``Problem.sample_bounds`` per sample still to come (Lipschitz, the arc of the
  current curvature, where the foot can be: ``reach.py``) combined by ``Problem.total_bound``
  (consecutive samples cannot both be near the path's samples: ``spacing.py``), added to ``f``
  both for ordering (A*) and for clipping;
- fall table (``fall_table.py``): a child that will fall within the horizon whatever it does is
  clipped at once instead of through its subtree;
- proof reuse (``proof.py``): in the receding horizon, a node's cost still to come is also
  bounded by what the previous search proved about the same subtree (``f + h`` of the nodes it
  clipped, backed up through the nodes it expanded);
- batches: ``batch`` queue nodes are expanded together, their ``batch * q`` children simulated as
  one array operation.

The problem solved (``viable_stages = M > 0``, the tests in ``viable.py``; with M = 0 it is the
paper's): the receding horizon applies only the first stage of a plan, so a plan whose last node
cannot go on is a poor choice however close it keeps to the path (in the paper's problem about
four in five executed plans ended so on the shipped scenes: BENCHMARKS.md).  A plan is *allowed*
when none of its nodes collides or falls (the paper's condition) and

- no node of it, at depth ``d``, is *doomed*: proved by the fall table (``fall_table.py``; its
  conservative grid lookup, exactly as ``FallTable.doomed`` computes it) to pass the lean bound
  within ``N - d + M`` stages whatever it does, i.e. before M stages after the horizon;
- its last node is not a *dead end*: one of its q children neither collides nor falls within one
  more stage (simulated as any stage).

Where the table does not apply (a varying speed, a figure whose lean is not monotone) only the
second condition is tested.  The search returns the least ``f`` over the allowed plans, the
lexicographically smallest of ties; when no plan is allowed, the paper's optimum (the same over
all plans that neither collide nor fall), flagged ``Plan.viable = False``.  ``exhaustive``
computes the same (tested).  With M > 0 the ``fall_table`` switch changes nothing (the doomed
test is part of the problem); with M = 0 it is the exact speed-up described above.  Every bound
stays admissible: the allowed plans are a subset of the paper's, so a lower bound on the cost of
any completion bounds theirs; a warm start only offers allowed plans as upper bounds; a proof
(``proof.py``) marks a node without allowed completions infinite only where it has none in the
next search either (a doomed node stays doomed one stage later, with one stage more to go; a dead
last node keeps its ``f``, as it is an inner node then), and a fallback search starts without one.
"""
from __future__ import annotations

import heapq
import math
import time
from dataclasses import dataclass, replace

import numpy as np

from .problem import Problem
from .proof import ProvenBounds, back_up
from .viable import dead_leaves, doomed_nodes, paper_problem

__all__ = ["SearchStats", "Plan", "branch_and_bound", "exhaustive"]

_REL_TOL = 1e-9


@dataclass(frozen=True)
class SearchStats:
    """What one search did.  ``expanded``: nodes whose children were simulated, those of the
    warm start's plans included.  Clipped counts are children (or queued nodes) dropped, by reason:
    collision, fall (the lean passed its bound), bound (cannot beat the best plan) and doomed
    (will fall within the horizon, or with ``viable_stages`` before that many stages after it,
    whatever it does, ``fall_table.py``; and last nodes that are dead ends).  After a fallback
    to the paper's problem, the counts of both searches."""

    expanded: int
    generated: int
    clipped_collision: int
    clipped_fall: int
    clipped_bound: int
    clipped_doomed: int
    leaves: int
    wall_time: float
    proven: bool
    warm_cost: float

    def as_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass(frozen=True)
class Plan:
    """The best plan: indices into ``Problem.u_values`` per stage, its u values and ``f_opt``."""

    choices: tuple
    u: tuple
    f_opt: float
    stats: SearchStats
    proof: ProvenBounds | None = None
    """What the search proved about its subtrees, for the next replanning (``proof.py``)."""
    leaf: tuple | None = None
    """The plan's last node: ``(state (5,), C_f, t, s)``."""
    viable: bool = True
    """False when no plan with a viable last node exists and this is the paper's optimum."""

    @property
    def feasible(self) -> bool:
        """False when every branch was clipped by a collision or a fall (no choices, f_opt inf)."""
        return bool(self.choices)


class _Nodes:
    """Growable column store of search nodes.  Besides each node's state and ``f``: whether it
    was expanded and, per child, the bound recorded when the child was generated (``proof.py``)."""

    def __init__(self, q, rows=5, cap=1024):
        self.n = 0
        self.state = np.empty((rows, cap))
        self.cols = {k: np.empty(cap) for k in ("cf", "f", "d", "t", "s")}
        self.ints = {k: np.empty(cap, np.int64) for k in ("depth", "parent", "choice", "old")}
        self.expanded = np.zeros(cap, bool)
        self.child_total = np.empty((cap, q))
        self.child_f = np.empty((cap, q))

    def __getattr__(self, name):
        try:
            return self.__dict__["ints"][name]
        except KeyError:
            raise AttributeError(name) from None

    def add(self, state, depth, parent, choice, old, **cols):
        m = state.shape[1]
        need = self.n + m
        if need > self.state.shape[1]:
            cap = max(need, 2 * self.state.shape[1])

            def grow(a, fill=None):
                extra = np.empty((cap - a.shape[-1],) if a.ndim == 1 else (cap - len(a),) +
                                 a.shape[1:], a.dtype)
                if fill is not None:
                    extra[...] = fill
                return np.concatenate([a, extra])
            self.state = np.concatenate([self.state, np.empty((len(self.state),
                                                              cap - self.state.shape[1]))], 1)
            self.cols = {k: grow(v) for k, v in self.cols.items()}
            self.ints = {k: grow(v) for k, v in self.ints.items()}
            self.expanded = grow(self.expanded, False)
            self.child_total, self.child_f = grow(self.child_total), grow(self.child_f)
        sl = slice(self.n, need)
        self.state[:, sl] = state
        for k, v in (("depth", depth), ("parent", parent), ("choice", choice), ("old", old)):
            self.ints[k][sl] = v
        for k, v in cols.items():
            self.cols[k][sl] = v
        self.n = need
        return np.arange(sl.start, sl.stop)

    def choices(self, i):
        out = []
        while i >= 0 and self.parent[i] >= -1 and self.depth[i] > 0:
            out.append(int(self.choice[i]))
            i = int(self.parent[i])
        return out[::-1]

    def proof(self) -> ProvenBounds:
        n = self.n
        return back_up(self.parent[:n], self.choice[:n], self.depth[:n], self.expanded[:n],
                       self.child_total[:n], self.child_f[:n])


def _expand(problem: Problem, nodes: _Nodes, ids):
    """Simulate the q children of nodes ``ids``; returns the stage result, parent/choice and the
    ``(parents, choices)`` left out: a child whose ``dC_f/dt`` equals an earlier sibling's
    (``spread = "range"`` on the bound, where the curvature left is 0) is the same branch, and
    of tied plans the search returns the one with the smaller choices anyway."""
    q = problem.settings.q
    ids = np.asarray(ids)
    par = np.repeat(ids, q)
    ch = np.tile(np.arange(q), len(ids))
    u = problem.rates(nodes.cols["cf"][par], ch).reshape(len(ids), q)
    same = np.zeros(u.shape, bool)
    for j in range(1, q if problem.settings.spread == "range" else 0):   # "rate": all distinct
        same[:, j] = (u[:, :j] == u[:, j:j + 1]).any(axis=1)
    same = same.reshape(-1)
    dropped = (par[same], ch[same])
    par, ch, u = par[~same], ch[~same], u.reshape(-1)[~same]
    args = (nodes.state[:, par], nodes.cols["cf"][par], u, nodes.cols["t"][par],
            nodes.cols["s"][par])
    if problem.settings.vectorize_children:
        r = problem.simulate_stage(*args)
    else:                         # the paper's one child at a time (the benchmark baseline)
        parts = [problem.simulate_stage(args[0][:, j:j + 1], *(a[j:j + 1] for a in args[1:]))
                 for j in range(len(par))]
        r = type(parts[0])(*(np.concatenate([getattr(p, f) for p in parts], axis=-1)
                             for f in ("state", "C_f", "s", "cost", "d_last", "collided", "fell")))
    return r, par, ch, dropped


def _bound(problem, r, depth, togo, reach, cols, pairs=None, direct=None):
    """Lower bound on the cost still to come after children ``cols`` of a stage result: the
    per-sample bounds (``Problem.sample_bounds``) combined by ``Problem.total_bound`` and, given
    the previous search's ``togo`` (proof.py, which covers all stages but the last), ``togo`` plus
    the bounds on the last stage's samples.  ``pairs``: the pair floors, ``direct``: the direct
    bounds (``Problem.direct_bounds``), when already known.  Returns the bound and the direct
    bounds."""
    st = problem.settings
    if not st.lower_bound:
        return (np.zeros(len(cols)) if togo is None else togo), None
    if problem.race is not None:      # the racer's line (reach.RaceCost); its last stage costs >= 0
        h = problem.race.bound(r.state[:, cols], r.C_f[cols], depth[cols])
        return (h if togo is None else np.maximum(h, togo)), None
    depth = depth[cols]
    state = r.state[:, cols]
    n = int(np.max(st.n_stages - depth, initial=0)) * st.samples_per_stage
    if direct is None and n:
        direct = problem.direct_bounds(r.d_last[cols], state, r.C_f[cols], n)
    terms = problem.sample_bounds(r.d_last[cols], depth, state, r.C_f[cols], reach, direct)
    h = problem.total_bound(terms, r.d_last[cols], depth, state, pairs)
    if togo is None or not terms.shape[1]:
        return (h if togo is None else np.maximum(h, togo)), direct
    per = st.samples_per_stage
    K = (st.n_stages - depth) * per
    last = np.take_along_axis(terms, np.maximum(K[:, None] - per + np.arange(per), 0), 1)
    return np.maximum(h, togo + np.where(K[:, None] >= per, last, 0.0).sum(axis=1)), direct


def _root(q, state, C_f, t0, s0, old):
    state = np.asarray(state, float).reshape(-1, 1)    # 5 rows, 6 on terrain (V_cm)
    nodes = _Nodes(q, len(state))
    nodes.add(state, 0, -1, -1, old, cf=C_f, f=0.0, d=0.0, t=t0,
              s=s0)
    return nodes


def _follow_choices(problem, state, C_f, t0, s0, choices):
    """Simulate one fixed plan (all q choices at its last stage when ``choices`` is one short).
    Returns ``(cost, full choices, nodes whose children were simulated, leaf)`` of its best
    feasible completion (a viable last node: :func:`.viable.dead_leaves`), or ``(inf, None, nodes,
    None)``."""
    st = problem.settings
    x, cf, t, s = np.asarray(state, float).reshape(-1, 1), np.array([C_f]), t0, np.array([s0])
    f = np.zeros(1)
    for k, c in enumerate(choices):
        r = problem.simulate_stage(x, cf, problem.rates(cf, [c]), np.array([t]), s)
        if r.collided[0] or r.fell[0] or doomed_nodes(problem, r.state, r.C_f, k + 1)[0]:
            return np.inf, None, k + 1, None
        x, cf, s, f, t = r.state, r.C_f, r.s, f + r.cost, t + st.t_stage
    if len(choices) < st.n_stages:
        q = st.q
        r = problem.simulate_stage(np.repeat(x, q, 1), np.repeat(cf, q),
                                   problem.rates(cf, np.arange(q)), np.full(q, t),
                                   np.repeat(s, q))
        bad = r.collided | r.fell | doomed_nodes(problem, r.state, r.C_f, st.n_stages)
        bad[~bad] = dead_leaves(problem, r.state[:, ~bad], r.C_f[~bad], t + st.t_stage,
                                 r.s[~bad])
        fc = np.where(bad, np.inf, f[0] + r.cost)
        j = int(np.argmin(fc))
        n = len(choices) + 1
        if not np.isfinite(fc[j]):
            return np.inf, None, n, None
        return float(fc[j]), list(choices) + [j], n, (r.state[:, j].copy(), float(r.C_f[j]),
                                                      t + st.t_stage, float(r.s[j]))
    if dead_leaves(problem, x, cf, t, s)[0]:
        return np.inf, None, len(choices), None
    return float(f[0]), list(choices), len(choices), (x[:, 0].copy(), float(cf[0]), t,
                                                      float(s[0]))


def _greedy_dive(problem, state, C_f, t0, s0):
    """A first complete plan: at each stage take the child with the least ``f + lower bound``
    (at the last, only viable ones: :func:`.viable.dead_leaves`).  Returns ``(cost, choices, nodes
    expanded, leaf)``, or ``(inf, None, nodes expanded, None)``."""
    st = problem.settings
    q = st.q
    x, cf, t, s = np.asarray(state, float).reshape(-1, 1), np.array([C_f]), t0, np.array([s0])
    f = 0.0
    choices = []
    for depth in range(1, st.n_stages + 1):
        r = problem.simulate_stage(np.repeat(x, q, 1), np.repeat(cf, q),
                                   problem.rates(cf, np.arange(q)), np.full(q, t),
                                   np.repeat(s, q))
        key = f + r.cost + problem.lower_bound(r.d_last, depth, r.state, r.C_f)
        bad = r.collided | r.fell | doomed_nodes(problem, r.state, r.C_f, depth)
        if depth == st.n_stages:
            bad[~bad] = dead_leaves(problem, r.state[:, ~bad], r.C_f[~bad], t + st.t_stage,
                                     r.s[~bad])
        key = np.where(bad, np.inf, key)
        j = int(np.argmin(key))
        if not np.isfinite(key[j]):
            return np.inf, None, depth, None
        choices.append(j)
        x, cf, s, f, t = r.state[:, [j]], r.C_f[[j]], r.s[[j]], f + r.cost[j], t + st.t_stage
    return float(f), choices, st.n_stages, (x[:, 0].copy(), float(cf[0]), t, float(s[0]))


def branch_and_bound(problem: Problem, state, C_f: float, t0: float = 0.0, s0: float = 0.0,
                     previous: tuple | None = None,
                     proof: ProvenBounds | None = None) -> Plan:
    """Fig. 14 from ``state`` (shape ``(5,)``) with curvature ``C_f`` at time ``t0``.

    ``previous``: the last plan's choices (warm start).  ``proof``: what the last search proved
    below the node it applied (``last_plan.proof.after(last_plan.choices[0])``, ``proof.py``);
    only valid when ``state`` is that node's state.  Returns the optimal :class:`Plan`, with
    its statistics; when every branch is clipped by a collision or a fall the plan is not
    ``feasible`` (the caller raises ``PlanInfeasible``).
    """
    st = problem.settings
    clock = time.perf_counter()
    N = st.n_stages
    ub, best, best_leaf = np.inf, None, None
    warm_cost = np.inf
    expanded = 0              # every node whose children are simulated, the warm start's too
    hot = False               # the first bound is the previous plan (usually the optimum)
    if st.warm_start:
        if previous is not None and len(previous) == N:
            ub, best, n, best_leaf = _follow_choices(problem, state, C_f, t0, s0,
                                                     list(previous[1:]))
            expanded += n
            hot = best is not None
        if best is None:
            ub, best, n, best_leaf = _greedy_dive(problem, state, C_f, t0, s0)
            expanded += n
        warm_cost = ub
    if not st.reuse_proof:
        proof = None
    nodes = _root(st.q, state, C_f, t0, s0, -1 if proof is None else proof.root)
    heap = [(0.0, 0, 0)]
    generated = leaves = 0
    clip_col = clip_fall = clip_bound = clip_doom = 0
    proven = True
    tol = lambda: _REL_TOL * max(1.0, abs(ub))     # noqa: E731
    while heap:
        ids = []
        # Batches expand nodes past the optimum when the bound is not yet tight: take whole
        # batches only from the previous plan's bound; else a quarter, and until a first complete
        # plan, batches growing with the search.  A long search takes batches of up to a quarter
        # of the nodes it has expanded (at most 4 whole ones): the overshoot is then small
        # against the search, and numpy's cost per call is spread over more nodes.
        limit = max(st.batch if hot else max(1, st.batch // 4),
                    min(4 * st.batch, expanded // 4))
        if ub == np.inf:
            limit = min(limit, max(8, expanded // 4))
        while heap and len(ids) < limit:
            prio, _, i = heapq.heappop(heap)
            if prio > ub + tol():          # everything left in the queue is worse
                clip_bound += 1 + len(heap)
                heap.clear()
                break
            ids.append(i)
        if not ids:
            break
        if st.max_expansions and expanded >= st.max_expansions:
            proven = False
            break
        expanded += len(ids)
        nodes.expanded[ids] = True
        r, par, ch, dropped = _expand(problem, nodes, ids)
        nodes.child_total[dropped], nodes.child_f[dropped] = np.inf, 0.0   # a sibling's (proof.py)
        generated += len(par)
        depth = nodes.depth[par] + 1
        f = nodes.cols["f"][par] + r.cost
        clip_col += int(np.count_nonzero(r.collided))
        clip_fall += int(np.count_nonzero(r.fell & ~r.collided))
        alive = ~(r.collided | r.fell)
        doomed = np.zeros(len(par), bool)
        doomed[alive] = doomed_nodes(problem, r.state[:, alive], r.C_f[alive], depth[alive])
        clip_doom += int(np.count_nonzero(doomed))
        alive &= ~doomed
        leaf = alive & (depth == N)
        dead = np.zeros(len(par), bool)
        if leaf.any() and st.viable_stages:       # dead-end last nodes are not plans here
            # Only those that could be the best plan need the (costly) check.
            j = np.flatnonzero(leaf & ~(f > ub + tol()))
            dead[j] = dead_leaves(problem, r.state[:, j], r.C_f[j],
                                   nodes.cols["t"][par[j]] + st.t_stage, r.s[j])
            clip_doom += int(np.count_nonzero(dead))
            leaf &= ~dead
        leaves += int(np.count_nonzero(leaf))
        if leaf.any():
            f_min = f[leaf].min()
            if f_min <= ub:
                tied = np.flatnonzero(leaf & (f == f_min))
                plan, j = min((nodes.choices(int(par[j])) + [int(ch[j])], int(j)) for j in tied)
                if f_min < ub or best is None or plan < list(best):
                    ub, best = float(f_min), plan
                    best_leaf = (r.state[:, j].copy(), float(r.C_f[j]),
                                 float(nodes.cols["t"][par[j]]) + st.t_stage, float(r.s[j]))
        inner = alive & (depth < N)
        old = np.full(len(par), -1)
        togo = None
        if proof is not None:
            old, togo = proof.children(nodes.old[par], ch)
        # Bounds for the children still in play; the costlier reach bound only where the cheap
        # ones pass.
        prio = np.full(len(par), np.inf)
        i = np.flatnonzero(inner)
        pairs = problem.pair_floors(r.state[:, i], (N - depth[i]) * st.samples_per_stage) \
            if st.lower_bound and len(i) and problem.race is None else None
        h, direct = _bound(problem, r, depth, None if togo is None else togo[i], False, i, pairs)
        prio[i] = f[i] + h
        # What this search proves about each child (proof.py): f + h, f for a leaf, inf if none.
        nodes.child_f[par, ch] = f
        keep = inner & ~(prio > ub + tol())
        if (st.lower_bound and keep.any() and problem.race is None
                and problem.reach_bound() is not None):
            sub = np.flatnonzero(keep[i])
            k = i[sub]
            prio[k] = np.maximum(prio[k], f[k] + _bound(
                problem, r, depth, None if togo is None else togo[k], True, k,
                None if pairs is None else pairs[sub], None if direct is None else direct[sub])[0])
            keep[k] = ~(prio[k] > ub + tol())
        # A dead last node keeps its f: one stage on (the next search) it may have a live one.
        # (A doomed one does not: it falls within the horizon and M stages, as does every node
        # below it, and the next search's horizon ends one stage later.)
        nodes.child_total[par, ch] = np.where(leaf | dead, f, np.where(inner, prio, np.inf))
        clip_bound += int(np.count_nonzero(inner & ~keep))
        if keep.any():
            k = np.flatnonzero(keep)
            new = nodes.add(r.state[:, k], depth[k], par[k], ch[k], old[k], cf=r.C_f[k], f=f[k],
                            d=r.d_last[k], t=nodes.cols["t"][par[k]] + st.t_stage, s=r.s[k])
            seq = new.tolist()
            for p, dd, i in zip(prio[k].tolist(), depth[k].tolist(), seq):
                heapq.heappush(heap, (p, -dd, i))
    stats = SearchStats(expanded, generated, clip_col, clip_fall, clip_bound, clip_doom, leaves,
                        time.perf_counter() - clock, proven, float(warm_cost))
    if best is None:
        if st.viable_stages:
            # No plan ends viably: the paper's problem (its own proof; the one handed in was
            # proved for the restricted problem and may mark its plans infeasible).
            plan = branch_and_bound(paper_problem(problem), state, C_f, t0, s0, previous)
            stats = SearchStats(**{**plan.stats.as_dict(), **{
                k: getattr(stats, k) + getattr(plan.stats, k) for k in _COUNTS},
                "wall_time": time.perf_counter() - clock})
            return replace(plan, stats=stats, viable=False)
        return Plan((), (), math.inf, stats)
    return Plan(tuple(best), _rates_of(problem, state, C_f, t0, s0, best), float(ub), stats,
                nodes.proof(), best_leaf)


def _rates_of(problem, state, C_f, t0, s0, choices) -> tuple:
    """The plan's ``dC_f/dt`` per stage (:meth:`.Problem.rates`: with ``spread = "range"`` each
    stage's from the curvature the plan reaches, simulated)."""
    if problem.settings.spread == "rate":
        return tuple(float(problem.u_values[c]) for c in choices)
    x, cf, s = np.asarray(state, float).reshape(-1, 1), np.array([C_f], float), np.array([s0])
    out = []
    for k, c in enumerate(choices):
        u = problem.rates(cf, [c])
        out.append(float(u[0]))
        if k + 1 < len(choices):
            r = problem.simulate_stage(x, cf, u, np.array([t0 + k * problem.settings.t_stage]), s)
            x, cf, s = r.state, r.C_f, r.s
    return tuple(out)


_COUNTS = ("expanded", "generated", "clipped_collision", "clipped_fall", "clipped_bound",
           "clipped_doomed", "leaves")


def exhaustive(problem: Problem, state, C_f: float, t0: float = 0.0, s0: float = 0.0,
               fallback: bool = True):
    """Reference: simulate all ``q^N`` plans level by level (clipping only collisions and falls)
    and return ``(f_opt, choices)`` of the problem stated in the module docstring (the least
    cost of the allowed plans, or if there are none, of all: not with ``fallback=False``), or
    ``(inf, None)`` when none survives."""
    st = problem.settings
    q = st.q
    x = np.asarray(state, float).reshape(-1, 1)
    cf, t, s, f = np.array([C_f], float), np.array([t0], float), np.array([s0], float), np.zeros(1)
    paths = np.zeros((1, 0), np.int64)
    ok = np.ones(1, bool)           # no node so far is doomed within the horizon and M stages
    for depth in range(1, st.n_stages + 1):
        m = x.shape[1]
        par = np.repeat(np.arange(m), q)
        ch = np.tile(np.arange(q), m)
        r = problem.simulate_stage(x[:, par], cf[par], problem.rates(cf[par], ch), t[par],
                                   s[par])
        alive = ~(r.collided | r.fell)
        if not alive.any():
            return np.inf, None
        ok = (ok[par] & ~doomed_nodes(problem, r.state, r.C_f, depth))[alive]
        x, cf, s = r.state[:, alive], r.C_f[alive], r.s[alive]
        f = (f[par] + r.cost)[alive]
        t = t[par][alive] + st.t_stage
        paths = np.concatenate([paths[par], ch[:, None]], axis=1)[alive]
    viable = ok & ~dead_leaves(problem, x, cf, t, s)
    if st.viable_stages and (viable.any() or not fallback):
        f, paths = f[viable], paths[viable]
        if not len(f):
            return np.inf, None
    j = int(np.argmin(f))
    return float(f[j]), tuple(int(c) for c in paths[j])

"""Which plans the search may return (``search.py``, "The problem solved"): nodes the fall table
proves doomed before ``viable_stages`` stages after the horizon, and last nodes that are dead
ends (each of their q children collides or falls within one more stage); and the paper's problem,
for when no plan avoids both."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .problem import Problem

__all__ = ["doomed_nodes", "dead_leaves", "no_way_on", "dead_end", "paper_problem"]


def doomed_nodes(problem: Problem, state, C_f, depth) -> np.ndarray:
    """Nodes at ``depth`` that the fall table proves will fall within the horizon or the
    ``viable_stages`` after it whatever they do; with ``viable_stages`` 0, within the horizon
    (only where ``fall_table`` is set: then it is a pure speed-up)."""
    st = problem.settings
    C_f = np.atleast_1d(np.asarray(C_f, float))
    table = problem.fall_table() if (st.fall_table or st.viable_stages) else None
    if table is None or not len(C_f):
        return np.zeros(len(C_f), bool)
    steps = (st.n_stages - np.asarray(depth) + st.viable_stages) * st.steps_per_stage
    return table.doomed(state, C_f, steps)


def dead_leaves(problem: Problem, state, C_f, t, s) -> np.ndarray:
    """Which last nodes are dead ends, when ``viable_stages`` is set (else none)."""
    C_f = np.atleast_1d(np.asarray(C_f, float))
    if not problem.settings.viable_stages:
        return np.zeros(len(C_f), bool)
    return no_way_on(problem, state, C_f, t, s)


def no_way_on(problem: Problem, state, C_f, t, s) -> np.ndarray:
    """Nodes (``state`` shape ``(5, m)``, curvature, time, distance travelled) each of whose q
    children collides or falls within one more stage."""
    C_f = np.atleast_1d(np.asarray(C_f, float))
    if not len(C_f):
        return np.zeros(0, bool)
    q, m = problem.settings.q, len(C_f)
    t = np.broadcast_to(np.asarray(t, float), C_f.shape)
    s = np.broadcast_to(np.asarray(s, float), C_f.shape)
    r = problem.simulate_stage(np.repeat(state, q, 1), np.repeat(C_f, q),
                               problem.rates(np.repeat(C_f, q), np.tile(np.arange(q), m)),
                               np.repeat(t, q), np.repeat(s, q))
    return (r.collided | r.fell).reshape(m, q).all(axis=1)


def dead_end(problem: Problem, leaf) -> bool:
    """Does a plan's last node ``leaf`` (``Plan.leaf``) end in a dead end?  (The measurement of
    ``receding.py``: one stage of q children.)"""
    x, cf, t, s = leaf
    return bool(no_way_on(problem, np.reshape(x, (-1, 1)), cf, t, s)[0])


def paper_problem(problem: Problem) -> Problem:
    """The same problem with ``viable_stages = 0`` (sharing its tables: none depends on it)."""
    p = type(problem).__new__(type(problem))
    p.__dict__.update(problem.__dict__)
    p.settings = replace(problem.settings, viable_stages=0)
    return p

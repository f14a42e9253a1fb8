"""What a finished search proved about the cost still to come, reused by the next replanning
(Section 6.1's receding horizon: the next search starts where the first stage of this plan ends).

Every node the search generated gets a lower bound ``T`` on the total cost (from the search's
root) of any complete plan through it, over this search's horizon:

- a leaf (depth N): its ``f``, exactly, also when it is a dead end (``search.py``): one stage
  later, in the next search, it is an inner node and may have a live last node below it;
- a child that collided, fell, or is doomed to fall (``fall_table.py``): infinity, it has no
  feasible completion;
- a node clipped by the bound or left in the queue: its ``f + h`` (``h`` admissible);
- an expanded node: the least ``T`` of its q children (every completion goes through one).

By induction on the height of the subtree each ``T`` is a lower bound.  So ``T - f`` bounds the
cost still to come after the node within this horizon.  The next search's tree is the subtree
below the root's child that was applied, with one stage more at the end: a node there at depth
``d`` is the node at depth ``d + 1`` here, and its cost still to come over ``N - d`` stages is at
least its cost over the first ``N - d - 1`` of them (every ``d_i >= 0``), which is bounded by
``T - f`` here.  The same states are simulated again (same dynamics, same path distance and
obstacles within the horizon, ``Problem.local`` being exact), so the bound holds up to rounding,
for which :data:`REL_TOL` is taken off; a branch that falls or collides exactly at its bound
could flip with rounding there, as it could between any two searches of the same tree.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ProvenBounds", "REL_TOL"]

#: Relative slack taken off a reused bound (sums of the same costs in a different order).
REL_TOL = 1e-9


@dataclass(frozen=True)
class ProvenBounds:
    """``child[i, c]``: store index of node ``i``'s child ``c`` (-1: not stored); ``togo[i, c]``:
    lower bound on the cost still to come after that child within the search's horizon (inf: no
    feasible completion; NaN: node ``i`` was not expanded).  ``root``: the store index of the
    node these bounds are for (the search's root, or after :meth:`after`, one of its children)."""

    child: np.ndarray
    togo: np.ndarray
    root: int = 0

    def after(self, choice: int) -> "ProvenBounds | None":
        """The bounds below the root's child ``choice`` (the first stage applied), if stored."""
        j = int(self.child[self.root, choice])
        return None if j < 0 else ProvenBounds(self.child, self.togo, j)

    def children(self, old, choice):
        """For nodes at store indices ``old`` (-1: unknown) and their children ``choice``: the
        children's store indices and their reusable cost-to-go bounds (0 where unknown)."""
        old = np.asarray(old)
        known = old >= 0
        o = np.where(known, old, 0)
        child = np.where(known, self.child[o, choice], -1)
        togo = np.where(known, self.togo[o, choice], 0.0)
        togo = np.where(np.isnan(togo), 0.0, togo)
        slack = REL_TOL * np.maximum(1.0, np.where(np.isinf(togo), 0.0, togo))
        return child, togo - slack


def back_up(parent, choice, depth, expanded, child_total, child_f) -> ProvenBounds:
    """The bounds of a finished search from its node store (see the module docstring).

    ``child_total[i, c]`` holds ``T`` of node ``i``'s child ``c`` as recorded when it was
    generated (its ``f + h``, or ``f`` for a leaf, or inf); the ``T`` of children that were
    expanded is replaced here by the least of their own children's, deepest first.
    """
    n = len(parent)
    total = child_total.copy()
    for d in range(int(depth.max(initial=0)), 0, -1):
        ids = np.flatnonzero(expanded & (depth == d))
        if len(ids):
            total[parent[ids], choice[ids]] = total[ids].min(axis=1)
    togo = np.full(total.shape, np.nan)
    togo[expanded] = total[expanded] - child_f[expanded]
    return ProvenBounds(_child_table(parent, choice, n, total.shape[1]), togo)


def _child_table(parent, choice, n, q):
    child = np.full((n, q), -1, np.int64)
    ids = np.flatnonzero(parent >= 0)
    child[parent[ids], choice[ids]] = ids
    return child

"""Planner settings (Section 6.1) and the speed profile along the path (Section 6: "the speed can
be made to vary as a function of the terrain")."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..physics.params import check_range
from .reach import LINES

__all__ = ["PlannerSettings", "SpeedProfile", "SPREADS"]

#: How the choices of dC_f/dt spread (``PlannerSettings.spread``).
SPREADS = ("rate", "range")


@dataclass(frozen=True)
class PlannerSettings:
    """The branch-and-bound search of Fig. 14.  Defaults are the paper's typical values (6.1)."""

    t_stage: float = 0.3
    """Duration of one stage, during which dC_f/dt is held constant, s."""
    n_stages: int = 10
    """N, the number of stages planned ahead (the horizon is N t_stage)."""
    q: int = 5
    """Number of dC_f/dt values tried per stage, spread evenly over [-dC_f_max, dC_f_max]."""
    spread: str = "rate"
    """How the ``q`` values of dC_f/dt spread: ``"rate"``, evenly over ``[-dC_f_max, dC_f_max]``
    (Section 6.1); ``"range"``, the same fractions ``linspace(-1, 1, q)`` of the rate each side
    can use this stage, ``min(dC_f_max, (C_f_max -+ C_f) / t_stage)``: the largest brings
    ``C_f`` exactly to its bound at the stage's end, 0 still holds it, and the others split the
    curvature left into equal steps, so near the bound the curvatures between the paper's
    lattice points are reachable (docs/racing.md, "The planner's curvature lattice").  Either
    keeps every choice within Section 6.1's bounds, which the lower bounds and the fall table
    assume (exact)."""
    q_near: int = 0
    """Number of dC_f/dt values tried per stage by a search with an obstacle or another figure
    within the horizon's reach (``Problem.local``), evenly spread as ``q``'s; 0: ``q``.  With
    ``q_near = 2 q - 1`` the values include ``q``'s, and the line passes an obstacle as close as
    the finer rates allow (docs/racing.md, "An obstacle on the line")."""
    theta_bound: float = math.radians(30.0)
    """|theta_v| beyond which a branch counts as fallen over and is clipped, rad."""
    sample_dt: float = 0.1
    """Interval at which the track is sampled for f_opt = sum d_i, s."""
    dt: float = 0.05
    """Integration step (RK4), s; t_stage and sample_dt must be whole multiples of it."""
    warm_start: bool = True
    """Use the previous plan, shifted by one stage, as the first upper bound."""
    lower_bound: bool = True
    """Add an admissible bound on the cost still to come (the foot closes on the path no faster
    than its largest speed, and the refinements below) when clipping and ordering."""
    lookahead: int = 6
    """With ``lower_bound``: how many of the next samples get the tighter arc bound (the foot
    stays near the arc of its current curvature for a short while); 0 turns it off."""
    reach_directions: int = 8
    """With ``lower_bound``: directions in which the reachable set's support is tabulated for the
    bound on later samples (``reach.py``); 0 turns it off."""
    pair_floor: bool = True
    """With ``lower_bound``: two consecutive samples cannot both be close to the path's samples
    (``spacing.py``)."""
    fall_table: bool = True
    """Also clip nodes that provably fall within their remaining stages whatever they do
    (``fall_table.py``; exact).  Off: only the paper's clip of a branch that has fallen."""
    viable_stages: int = 3
    """Prefer plans that do not end in a dead end: a plan whose last node has no child that
    survives one more stage, or one of whose nodes the fall table (``fall_table.py``) proves
    will fall before this many stages after the horizon whatever it does, is only taken when no
    other plan is feasible (``search.py`` states the problem solved); 0: the paper's problem."""
    reuse_proof: bool = True
    """Receding horizon: bound the cost still to come by what the previous search proved about
    the same subtree (``proof.py``; exact)."""
    edge_limit: bool = False
    """On a preset's carving skis, clip branches whose curvature needs a larger edge angle than
    the lean and the body's angulation give (``problem.py``, core/equipment.py's
    ``EdgeLimit``); off (the default: it tightens the racers' lines on Reid's courses,
    docs/racing.md): Section 3's curvature bounds alone."""
    leg_force_max: float = 0.0
    """The largest leg force a branch may need, in body weights (Appendix A's ``F_leg`` over
    ``m g`` at every integration step's end, at the state's speed); a branch that needs more
    is clipped as one the figure cannot ski, as a fall is (exact: clipping only removes
    branches).  0: no limit, the paper's problem.  A racer's legs hold about 5 (Supej &
    Holmberg 2019's peaks; docs/racing.md, "The least-time line")."""
    line: str = "path"
    """The cost: ``"path"``, Section 6's ``sum d_i`` (the foot's distance to the drawn path);
    ``"race"``, the racer's line, the least time through the course: the distance not made good
    along the course's direction, around the obstacles (:class:`.reach.RaceCost`;
    docs/racing.md)."""
    batch: int = 128
    """Nodes taken from the queue and expanded together as one array operation (1 = the paper's
    one node at a time; a long search grows its batches up to 4 times this, ``search.py``).  Any
    value returns the same optimum."""
    vectorize_children: bool = True
    """Simulate the q children of a node as one (5, q) array (False: one child at a time)."""
    max_expansions: int = 0
    """Stop a search after this many node expansions (0: no limit).  A stopped search is not
    proven optimal and says so in its statistics."""

    def __post_init__(self):
        if self.spread not in SPREADS:
            raise ValueError(f"spread = {self.spread!r} is not one of {', '.join(SPREADS)}")
        if self.line not in LINES:
            raise ValueError(f"line = {self.line!r} is not one of {', '.join(LINES)}")
        check_range("t_stage", self.t_stage, 0.0, 60.0, lo_open=True)
        if self.leg_force_max:
            check_range("leg_force_max", self.leg_force_max, 1.0, 20.0)
        check_range("n_stages", self.n_stages, 1, 64)
        check_range("q", self.q, 2, 64)
        if self.q_near:
            check_range("q_near", self.q_near, 2, 64)
        check_range("theta_bound", self.theta_bound, 0.0, math.pi / 2, lo_open=True, hi_open=True)
        check_range("sample_dt", self.sample_dt, 0.0, 60.0, lo_open=True)
        check_range("dt", self.dt, 1e-4, 1.0)
        check_range("batch", self.batch, 1, 4096)
        check_range("lookahead", self.lookahead, 0, 1000)
        check_range("reach_directions", self.reach_directions, 0, 1000)
        check_range("max_expansions", self.max_expansions, 0, 1e12)
        check_range("viable_stages", self.viable_stages, 0, 64)
        for name in ("n_stages", "q", "q_near", "batch", "lookahead", "reach_directions",
                     "max_expansions", "viable_stages"):
            if int(getattr(self, name)) != getattr(self, name):
                raise ValueError(f"{name} = {getattr(self, name)!r} is not a whole number")
        for name in ("t_stage", "sample_dt"):
            k = getattr(self, name) / self.dt
            if abs(k - round(k)) > 1e-9 or round(k) < 1:
                raise ValueError(f"{name} = {getattr(self, name)!r} is not a whole multiple of "
                                 f"dt = {self.dt!r}")
        k = self.t_stage / self.sample_dt
        if abs(k - round(k)) > 1e-9:
            raise ValueError(f"t_stage = {self.t_stage!r} is not a whole multiple of "
                             f"sample_dt = {self.sample_dt!r}")

    @property
    def steps_per_stage(self) -> int:
        return int(round(self.t_stage / self.dt))

    @property
    def steps_per_sample(self) -> int:
        return int(round(self.sample_dt / self.dt))

    @property
    def samples_per_stage(self) -> int:
        return int(round(self.t_stage / self.sample_dt))

    @property
    def horizon(self) -> float:
        return self.n_stages * self.t_stage


class SpeedProfile:
    """``V_cm`` as a function of time (``by="time"``) or of the foot's distance travelled
    (``by="distance"``): piecewise linear through ``(at[i], V_cm[i])``, constant beyond the ends.
    ``SpeedProfile.constant(v)`` is the default.  Within one integration step the speed is held at
    its value at the step's start."""

    def __init__(self, by: str, at, V_cm):
        if by not in ("constant", "time", "distance"):
            raise ValueError(f"speed.by = {by!r} is not one of constant, time, distance")
        self.by = by
        self.at = np.asarray(at, float).reshape(-1)
        self.V = np.asarray(V_cm, float).reshape(-1)
        if len(self.at) != len(self.V) or len(self.V) == 0:
            raise ValueError("speed.at and speed.V_cm must have the same, non-zero length")
        if np.any(np.diff(self.at) <= 0):
            raise ValueError("speed.at must increase strictly")
        for i, v in enumerate(self.V):
            check_range(f"speed.V_cm[{i}]", v, 0.0, 100.0, lo_open=True)

    @classmethod
    def constant(cls, V_cm: float) -> "SpeedProfile":
        return cls("constant", [0.0], [V_cm])

    @property
    def is_constant(self) -> bool:
        return self.by == "constant" or bool(np.all(self.V == self.V[0]))

    @property
    def max(self) -> float:
        return float(self.V.max())

    def __call__(self, t, s):
        """``V_cm`` at times ``t`` and distances ``s`` (broadcast), m/s."""
        if self.by == "constant":
            return np.full(np.broadcast(np.asarray(t), np.asarray(s)).shape, self.V[0])
        x = t if self.by == "time" else s
        return np.interp(x, self.at, self.V)

"""The planning :class:`.problem.Problem` where the speed is a state (any ground but flat with
nothing slowing the figure; :func:`..model.speed_held`): Section 6's search with the figure on a
surface ``z = h(x, y)`` (:mod:`..terrain`).  :class:`.problem.Problem` calls the functions here
when its ``free`` is set.

The node state grows a sixth row, ``V_cm`` (:data:`..model.STATE`); a stage
is simulated for all nodes at once with :func:`..model.rhs`'s rates under
the stage's law ``C_f = C0 + u tau``, bounded exactly as on flat ground (the RK4 of
:meth:`.problem.Problem.simulate_stage`, whose arithmetic this shares).  The path's distance
``d_i`` and the distance travelled ``s`` stay horizontal (x, y), as on flat ground.

Exactness.  Every lower bound of the flat search assumes a known speed profile; here:

- The Lipschitz bound (``Problem.sample_bounds``: a sample ``x`` from the path makes the next at
  least ``x - b``) needs the most the foot moves in one sample, ``b = v_max sample_dt``.  The
  speed changes by ``dV/dt = g_t - mu N V_f / (m V) - k V^2 + l omega V_f C_f cos th``
  (docs/TERRAIN.md Sections 3-4), with ``g_t = -g t_z <= g sin sigma_max`` (``|t_z| = |p| /
  sqrt(1 + p^2)`` with the slope along the heading ``|p| <= tan sigma_max``); friction (for
  ``N >= 0``) and drag only slow, and the lean's share only trades the lean's energy back and
  forth; so within the ``T`` seconds a search simulates (the horizon and one stage for the
  dead-end test) the speed stays near ``V_root + g sin sigma_max T``, and ``|V_f| <= V_cm /
  (1 - slip)`` (Eq. 21, as on flat ground).  Rather than rest exactness on ``N >= 0`` and on the
  lean's share (the model does not hold off the ground; a figure can pump), that speed is made a
  rule of the problem, like the lean bound: a branch whose foot speed passes it at any RK4 stage
  is a *run-away* and is clipped (it does not happen on the shipped scenes).  Then ``b`` bounds
  every surviving branch by construction, and the bound is admissible.
- The receding horizon reuses a search's proof in the next one (``proof.py``), whose root is
  faster or slower, so its speed limit higher or lower.  A lower limit only clips more (the old
  bounds stay lower bounds, an infeasible subtree stays infeasible); a higher one could free a
  branch the old proof counted out, so a search that clipped any run-away hands no proof on
  (``runaways``; ``receding.py``).
- Also clipped (rules of the problem, counted as falls): a branch whose speed drops below
  :data:`..terrain_sim.MIN_SPEED` (the model is a body carried by its speed) and one whose foot
  leaves a height field's grid.  Adding a clip only removes branches: every bound stays admissible.
- Switched off, as each assumes a constant speed or flat lean dynamics: the arc bound
  (``lookahead``), the reach bound (``reach.py``), the pair floor (``spacing.py``: its least foot
  travel needs a least speed) and the fall table (``fall_table.py``: the lean dynamics at one
  speed on flat ground).  The doomed test of ``viable.py`` therefore tests only dead ends, as it
  already does for a varying speed profile.

The exhaustive search (``search.exhaustive``) applies the same clips, so both return the same
optimum (tests/test_planner_terrain.py).
"""
from __future__ import annotations

import math

import numpy as np

from ..physics import model
from ..physics.grip import foot_lateral, skid_angle
from ..physics.params import Limits
from ..physics.dynamics import PHYSICAL_MARGIN, THETA_V, X, Y
from ..physics.model import V_CM
from ..ground.terrain import HeightField, Plane, surface_frame
from ..physics.terrain_sim import MIN_SPEED, describe_ground
from ..physics.trajectory import resistance_meta

__all__ = ["steepest_sine"]


def steepest_sine(ground) -> float:
    """``sin sigma_max``: the sine of the ground's steepest slope, which bounds ``|t_z|``.

    A plane: its slope (exact).  A height field: 1.5 times the largest slope between grid
    neighbours (an estimate with a margin for the bicubic's overshoot between grid points).  The
    search's exactness does not rest on it: it sets the run-away speed limit (module doc), and
    too low a value would only clip more branches, in the search and the exhaustive reference
    alike."""
    if isinstance(ground, Plane):
        return math.sin(ground.slope)
    if isinstance(ground, HeightField):
        h = ground._h
        gx = np.abs(np.diff(h, axis=1)).max() / ground.cell
        gy = np.abs(np.diff(h, axis=0)).max() / ground.cell
        m = 1.5 * math.hypot(gx, gy)
        return m / math.sqrt(1.0 + m * m)
    return 1.0                      # |t_z| <= 1 always


def setup(p, lean: float) -> None:
    """The free-speed parts of :class:`.problem.Problem`'s state (``p.V0`` set): the bounds that
    assume a constant speed off (module doc), the run-away speed limit, the grid's extent."""
    p._sin_max = steepest_sine(p.ground)
    p._slip = min(PHYSICAL_MARGIN, p.limits.C_f_max * p.body.l * math.sin(lean))
    p._lookahead = None                    # the arc bound assumes a constant speed
    p._fall_table = None                   # flat lean dynamics at one speed
    p._reach = None                        # a constant speed
    p._pairs = None                        # a least speed
    p.v_max = speed_limit(p, p.V0)
    # Branches clipped as run-aways, shared by the copies of one search (paper_problem's).
    p._runaways = np.zeros(1, np.int64)
    p._grid = p.ground.extent if isinstance(p.ground, HeightField) else None


def speed_limit(p, V_root: float) -> float:
    """The largest foot speed of a search from a root at speed ``V_root``: ``(V_root + g
    sin sigma_max T) / (1 - slip)``, ``T`` the horizon and one stage more (module doc)."""
    st = p.settings
    T = st.horizon + st.t_stage + st.dt
    return (V_root + p.body.g * p._sin_max * T) / (1.0 - p._slip) * (1 + 1e-9)


def rhs(p, x, tau, C0, u, anchor, rate_step, out, bad=None):
    """:func:`..model.rhs` under ``C_f = C0 + u tau`` into ``out`` (shape (6, m)); marks in
    ``bad`` the columns off the grid, stopped or run away."""
    px, py = x[X], x[Y]
    off = None
    if p._grid is not None:
        x_lo, x_hi, y_lo, y_hi = p._grid
        off = ~((px >= x_lo) & (px <= x_hi) & (py >= y_lo) & (py <= y_hi))
        if off.any():
            px, py = np.clip(px, x_lo, x_hi), np.clip(py, y_lo, y_hi)
    state = (px, py, x[2], x[THETA_V], x[4], x[V_CM])
    d, cf, alpha, V_f, N, fr = model.rhs(p.body, p.limits, p.ground, C0 + u * tau, state,
                                         anchor, rate_step, p.resistance)
    if p.speed_cap is not None:
        b = p.speed_cap.brake(p.body, d, cf, x[V_CM], V_f, N, fr, x[THETA_V])
        d = d[:5] + (d[5] - b * V_f / x[V_CM],)
    for row, v in enumerate(d):
        out[row] = v
    if bad is not None:
        runaway = ~(np.abs(V_f) <= p.v_max)
        if runaway.any():
            p._runaways[0] += int(np.count_nonzero(runaway & ~bad))
        bad |= runaway | ~(x[V_CM] >= MIN_SPEED)
        if off is not None:
            bad |= off
    return cf, alpha, V_f


def end_rates(p, x, cf):
    """``(alpha_v, V_f)`` of the state ``x`` (shape ``(6, 1)``) at curvature ``cf``."""
    _, _, a, v, _, _ = model.rhs(p.body, p.limits, p.ground, np.array([cf]), tuple(x[:, 0:1]),
                                 None, 0.0, p.resistance)
    return a, v


def leg_force_bw(p, S, C) -> np.ndarray:
    """Appendix A's leg force on the ground (:func:`..model.leg_force`) in body weights at states
    ``S`` (shape ``(6, m)``) with curvatures ``C`` already within their bounds."""
    state = tuple(S[k] for k in range(6))
    _, cf, alpha, V_f, _, fr = model.rhs(p.body, Limits(), p.ground, C, state,
                                         resistance=p.resistance)
    F = model.leg_force(p.body, S[THETA_V], S[4], alpha, cf, S[V_CM], V_f, fr)[0]
    return F / (p.body.m * p.body.g)


def columns(p, S, A, C, V) -> dict:
    """``z`` (the ground under the foot), ``V_cm`` (the state) and ``F_leg`` on the ground;
    with a speed cap the braking force and the skid angle it makes (docs/skidding.md)."""
    fr = surface_frame(p.ground, S[X], S[Y], S[2], p.body.g)
    F = model.leg_force(p.body, S[THETA_V], S[4], A, C, S[V_CM], V, fr)[0]
    out = {"z": np.asarray(fr.z, float), "V_cm": S[V_CM], "F_leg": F}
    if p.speed_cap is not None:
        state = tuple(S[k] for k in range(6))
        d, _, _, V_f, N, fr = model.rhs(p.body, Limits(), p.ground, C, state,
                                        resistance=p.resistance)
        b = p.speed_cap.brake(p.body, d, C, S[V_CM], V_f, N, fr, S[THETA_V])
        out["brake"] = b
        out["skid"] = skid_angle(b, foot_lateral(p.body.l, fr, S[V_CM], V_f, C, S[THETA_V],
                                                 S[4], d[4]))
        out["ski_heading"] = S[2] + out["skid"]
    return out


def meta(p) -> dict:
    return {"ground": describe_ground(p.ground), **resistance_meta(p.resistance)}

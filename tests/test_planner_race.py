"""The racer's line as the planner's cost (core/planner/reach.py; docs/racing.md, "The racer's
line"): each stage's cost is non-negative, the bound never exceeds the cost still to come, the
branch-and-bound returns the exhaustive search's optimum, and a straight corridor is skied
straight."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.course.scene import scene_from_dict
from blender_turning.core.planner import (PlannerSettings, Problem, SpeedProfile, branch_and_bound,
                                          exhaustive)
from blender_turning.core.validate import FieldError


def racer(N=3, q=5, obstacles=Obstacles(), direction=(1.0, 0.0), rate=1.0, **kw):
    """The slalom racer at 12 m/s on a straight course along ``direction``."""
    fig = preset("slalom_racer")
    fig = replace(fig, limits=replace(fig.limits, dC_f_max=rate),
                  body=replace(fig.body, V_cm=12.0))
    d = 60.0 * np.asarray(direction, float)
    path = HermitePath.from_points(np.array([[0.0, 0.0], d]), np.array([d, d]))
    st = PlannerSettings(n_stages=N, q=q, t_stage=0.2, theta_bound=math.radians(75.0),
                         line="race", **kw)
    return Problem(fig, PathDistance(path), obstacles, st)


def random_nodes(problem, m, seed):
    """Nodes anywhere on the course: heading, lean, lean rate and curvature at random."""
    rng = np.random.default_rng(seed)
    c = problem.limits.C_f_max
    state = np.stack([rng.uniform(0, 20, m), rng.uniform(-3, 3, m), rng.uniform(-np.pi, np.pi, m),
                      rng.uniform(-1.0, 1.0, m), rng.uniform(-1.0, 1.0, m)])
    return state, rng.uniform(-c, c, m)


def test_each_stage_costs_the_distance_its_centre_of_mass_does_not_make_good():
    p = racer()
    state, C0 = random_nodes(p, 400, 1)
    u = np.random.default_rng(2).choice(p.u_values, 400)
    r = p.simulate_stage(state, C0, u, np.zeros(400), np.zeros(400))
    assert r.cost.min() >= 0.0 and r.cost.max() <= 2 * 12.0 * 0.2
    # Upright on a straight heading alpha off the course: V_cm t_stage (1 - cos alpha).
    alpha = np.array([0.0, 0.3, -1.0, 2.5])
    still = np.zeros((5, 4))
    still[2] = alpha
    r = p.simulate_stage(still, np.zeros(4), np.zeros(4), np.zeros(4), np.zeros(4))
    np.testing.assert_allclose(r.cost, 12.0 * 0.2 * (1 - np.cos(alpha)), atol=1e-12)
    # The course's direction is the path's, start to end: along it a stage costs nothing.
    p = racer(direction=(0.6, -0.8))
    still[2] = [math.atan2(-0.8, 0.6), 0.0, math.pi, -math.pi / 2]
    r = p.simulate_stage(still, np.zeros(4), np.zeros(4), np.zeros(4), np.zeros(4))
    np.testing.assert_allclose(r.cost, 12.0 * 0.2 * np.array([0.0, 0.4, 1.6, 0.2]), atol=1e-12)


@pytest.mark.parametrize("direction", [(1.0, 0.0), (0.6, -0.8)])
def test_the_bound_never_exceeds_the_least_cost_still_to_come(direction):
    """Random nodes two stages from the horizon: the bound against every completion's cost
    (q^2 plans; no obstacles, so all are allowed, and the least is the true cost to come)."""
    p = racer(N=3, q=5, direction=direction, viable_stages=0)
    state, C0 = random_nodes(p, 300, 3)
    bound = p.race.bound(state, C0, np.ones(300, int))
    q = len(p.u_values)
    x, c = np.repeat(state, q * q, 1), np.repeat(C0, q * q)
    u1 = np.tile(np.repeat(p.u_values, q), 300)
    u2 = np.tile(p.u_values, 300 * q)
    r1 = p.simulate_stage(x, c, u1, np.zeros(len(c)), np.zeros(len(c)))
    r2 = p.simulate_stage(r1.state, r1.C_f, u2, np.zeros(len(c)), np.zeros(len(c)))
    least = (r1.cost + r2.cost).reshape(300, q * q).min(axis=1)
    assert np.all(bound <= least + 1e-9)
    # ... and it bounds something: above 0 for nodes heading across or up the course.
    across = np.abs(((state[2] - math.atan2(direction[1], direction[0]) + np.pi) % (2 * np.pi))
                    - np.pi) > 1.5
    assert bound[across].min() > 0.5


@pytest.mark.parametrize("N,q", [(3, 4), (3, 5), (4, 3)])
def test_the_search_returns_the_exhaustive_optimum_around_a_pole(N, q):
    """A turning pole 3 m ahead from 0.6 m left of the line across to the course's edge: every
    plan must swing left of it; the branch and bound finds the exhaustive search's optimum."""
    poles = Obstacles(segments=[((8.0, 0.6), (8.0, -12.0))], clearance=0.3)
    p = racer(N, q, poles)
    state = np.array([0.0, 0.0, 0.3, 0.0, 0.0])
    f, choices = exhaustive(p, state, 0.0)
    plan = branch_and_bound(p, state, 0.0)
    assert plan.f_opt == pytest.approx(f, rel=1e-9) and plan.choices == choices
    off = replace(p.settings, lower_bound=False, warm_start=False)
    assert branch_and_bound(Problem(p.figure, p.distance, poles, off), state, 0.0).choices == \
        choices


def test_a_straight_corridor_is_skied_straight():
    walls = Obstacles(segments=[((-5.0, 1.5), (80.0, 1.5)), ((-5.0, -1.5), (80.0, -1.5))],
                      clearance=0.3)
    p = racer(N=6, q=5, obstacles=walls)
    plan = branch_and_bound(p, np.zeros(5), 0.0)
    assert plan.u == (0.0,) * 6
    assert plan.f_opt == 0.0


def test_the_paper_cost_is_the_default_and_other_lines_are_refused():
    assert PlannerSettings().line == "path"
    assert racer().race is not None
    with pytest.raises(ValueError, match="line = 'fastest' is not one of path, race"):
        PlannerSettings(line="fastest")
    doc = {"figure": {"preset": "slalom_racer"}, "path": {"polyline": [[0, 0], [40, 0]]},
           "planner": {"line": "fast"}}
    with pytest.raises(FieldError, match="planner.line = 'fast' is not one of path, race"):
        scene_from_dict(doc, "s.json")
    doc["planner"]["line"] = "race"
    assert scene_from_dict(doc, "s.json").settings.line == "race"
    # The choices' spread (PlannerSettings.spread, tests/test_planner_spread.py) the same way.
    assert PlannerSettings().spread == "rate"
    doc["planner"]["spread"] = "wide"
    with pytest.raises(FieldError, match="planner.spread = 'wide' is not one of rate, range"):
        scene_from_dict(doc, "s.json")
    doc["planner"]["spread"] = "range"
    assert scene_from_dict(doc, "s.json").settings.spread == "range"


def test_the_leg_force_limit_clips_what_the_trajectory_would_show_past_it():
    """``leg_force_max``: a branch falls when Appendix A's leg force passes the limit at a step's
    start or the stage's end; the force the planner checks is the trajectory's ``F_leg`` at the
    same states (to rounding), and the search with the clip stays exact."""
    p = racer(N=3, q=5, leg_force_max=4.0)
    state, C0 = random_nodes(p, 60, 5)
    assert_leg_force_clipped(p, racer(N=3, q=5), state, C0, 4.0)


def assert_leg_force_clipped(p, free, state, C0, limit):
    """One stage from random nodes with the problem ``p`` (its ``leg_force_max`` = ``limit``):
    the leg force it checks is the trajectory's ``F_leg`` at the same states (to rounding), some
    branches and not all pass ``limit``, and ``p`` fells exactly the branches the problem without
    the limit (``free``) fells and those."""
    u = np.random.default_rng(6).choice(p.u_values, len(C0))
    zeros = np.zeros(len(C0))
    r = p.simulate_stage(state, C0, u, zeros, zeros, record=True)
    S, C = np.stack(r.record["state"]), np.stack(r.record["C_f"])
    F = p.columns(S.transpose(1, 0, 2), np.stack(r.record["alpha_v"]), C,
                  np.stack(r.record["V_f"]))["F_leg"] / (p.body.m * p.body.g)
    both = p.leg_force_bw(np.concatenate([S, r.state[None]]), np.concatenate([C, r.C_f[None]]))
    np.testing.assert_allclose(both[:-1], F, rtol=1e-12, atol=1e-12)
    over = (both > limit).any(axis=0)
    assert over.any() and not over.all()
    plain = free.simulate_stage(state, C0, u, zeros, zeros)
    np.testing.assert_array_equal(r.fell, plain.fell | over)
    # Exact: the search returns the exhaustive optimum around a pole within 2 body weights (at
    # the preset's own rate, 2.06 1/(m s)), which is not the optimum without the limit.
    poles = Obstacles(segments=[((8.0, 0.6), (8.0, -12.0))], clearance=0.3)
    p = racer(N=3, q=5, obstacles=poles, leg_force_max=2.0, rate=2.06)
    start = np.array([0.0, 0.0, 0.3, 0.0, 0.0])
    f, choices = exhaustive(p, start, 0.0)
    assert branch_and_bound(p, start, 0.0).choices == choices
    assert exhaustive(racer(N=3, q=5, obstacles=poles, rate=2.06), start, 0.0)[1] != choices
    with pytest.raises(ValueError, match="leg_force_max = 0.5 is outside"):
        PlannerSettings(leg_force_max=0.5)
    varying = SpeedProfile("time", [0.0, 5.0], [12.0, 14.0])
    with pytest.raises(ValueError, match="leg_force_max needs a constant speed held"):
        Problem(p.figure, p.distance, poles, p.settings, varying)


@pytest.mark.parametrize("kw", [{}, {"rate": 2.06, "spread": "range"}])
def test_the_receding_horizon_plans_the_same_line_with_and_without_its_speed_ups(kw):
    """Past a turning pole, the receding horizon for 1.8 s: the warm start, the reused proof and
    the bound (each exact for the racer's cost) leave every plan as the plain search's; also
    with the choices spread over the curvature left (``PlannerSettings.spread``), where a child
    with a sibling's rate is left out (and proved so, ``proof.py``)."""
    from blender_turning.core.planner import follow
    poles = Obstacles(segments=[((18.0, 0.6), (18.0, -12.0)), ((28.0, -0.6), (28.0, 12.0))],
                      clearance=0.3)
    fast = racer(N=6, q=5, obstacles=poles, **kw)
    plain = Problem(fast.figure, fast.distance, poles, replace(
        fast.settings, warm_start=False, reuse_proof=False, lower_bound=False))
    a, b = (follow(p, np.zeros(5), 0.0, 1.8) for p in (fast, plain))
    assert [r.u for r in a.replans] == [r.u for r in b.replans]
    np.testing.assert_allclose([r.f_opt for r in a.replans], [r.f_opt for r in b.replans],
                               rtol=1e-9)
    tr = a.trajectory
    assert np.interp(18.0, tr.x, tr.y) > 0.9                 # round the pole's tip, outside it
    assert sum(r.stats.expanded for r in a.replans) < sum(r.stats.expanded for r in b.replans)

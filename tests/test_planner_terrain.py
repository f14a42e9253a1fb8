"""The path planner on terrain: the stage simulation against the terrain model's own
RK4, the exact search against exhaustive search on small terrain problems, flat scenes planned
exactly as before, and the shipped scenes/slope_slalom.json."""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from blender_turning.core.course.follow_problem import FollowSetup, start_state
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.physics.params import preset
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.planner import (PlannerSettings, Problem, SpeedProfile,
                                          branch_and_bound, exhaustive)
from blender_turning.core.planner.terrain_problem import steepest_sine
from blender_turning.core.course.scene import load_scene
from blender_turning.core.ground.terrain import HeightField, Plane, surface_frame
from blender_turning.core.physics import model
from blender_turning.core.physics.model import RESISTANCE, Resistance, plumb_lean

ROOT = Path(__file__).resolve().parents[1]
SKIER = RESISTANCE["skier"]


def _bumps(n=41, cell=2.0):
    """An 18 deg slope falling along +x with rolls and a side tilt, on a grid from (-10, -40)."""
    xs = -10.0 + cell * np.arange(n)
    ys = -40.0 + cell * np.arange(n)
    X, Y = np.meshgrid(xs, ys)
    h = -math.tan(math.radians(18)) * X + 1.5 * np.sin(X / 7.0) + 0.05 * X * np.sin(Y / 9.0)
    return HeightField(h, -10.0, -40.0, cell)


def _problem(ground, resistance=SKIER, N=4, q=4, obstacles=True, **kw):
    fig = preset("skier", V_cm=8.0)
    fig = replace(fig, limits=replace(fig.limits, dC_f_max=0.3))
    path = HermitePath.from_points([[0, 0], [12, 2], [24, -2], [36, 0]],
                                   [[12, 0], [12, 0], [12, 0], [12, 0]])
    obs = Obstacles(np.array([[[12.0, 0.5], [12.0, -10.0]]]), np.array([[20.0, 1.5, 0.4]]),
                    [], 0.3) if obstacles else Obstacles()
    st = PlannerSettings(n_stages=N, q=q, theta_bound=math.radians(40), **kw)
    return Problem(fig, PathDistance(path, 12), obs, st, ground=ground, resistance=resistance)


def _root(V=8.0, heading=0.0, ground=None, y=0.0):
    """At ``(0, y)``; on ``ground``, leaning along the plumb line (a traverse's balance)."""
    lean = 0.0 if ground is None else plumb_lean(surface_frame(ground, 0.0, y, heading, 9.81))
    return np.array([0.0, y, heading, lean, 0.0, V])


def test_stage_matches_terrain_rk4():
    """One stage of the batched simulation is terrain_rk4_step under C_f = C0 + u tau, the
    curvature bounded relative to the step's start exactly as the core does (to round-off)."""
    p = _problem(_bumps(), obstacles=False)
    x0 = np.array([[0.0, 1.0], [0.5, -3.0], [0.2, -0.4], [0.1, -0.05], [0.3, 0.2], [8.0, 11.0]])
    C0, u = np.array([0.02, -0.05]), np.array([0.3, -0.15])
    r = p.simulate_stage(x0, C0, u, np.zeros(2), np.zeros(2), record=True)
    st = p.settings
    for j in range(2):
        x, prev = x0[:, j].copy(), C0[j]
        for k in range(st.steps_per_stage):
            tau = k * st.dt
            # The step's curvature: the demand, within dC_f_max dt of the last step's.
            cf = float(r.record["C_f"][k][j])
            assert cf == pytest.approx(np.clip(C0[j] + u[j] * tau, prev - 0.3 * st.dt,
                                               prev + 0.3 * st.dt), abs=1e-15)
            x = model.rk4_step(p.body, p.limits, p.ground, x, tau, st.dt,
                                 lambda t, s, j=j: C0[j] + u[j] * t, cf, resistance=p.resistance)
            prev = cf
        np.testing.assert_allclose(r.state[:, j], x, rtol=0, atol=1e-12)
    assert not r.fell.any() and np.all(r.state[5] != 8.0)          # the speed is a state


def test_flat_terrain_is_the_flat_problem():
    """A level plane without friction or drag is the paper's ground: the one Problem holds the
    speed there (5 rows, the fused flat stage), every stage is the flat problem's bit for bit
    and the search returns the flat search's plan; with friction the speed is a state."""
    T = _problem(Plane(0.0, 0.0), Resistance(mu=0.0, CdA=0.0))
    F = Problem(T.figure, T.distance, T.obstacles, T.settings, SpeedProfile.constant(8.0))
    assert not T.free and T._fused and T.meta() == {}
    x = np.array([[0.0], [0.0], [0.1], [0.05], [-0.2]])
    for u in (-0.3, 0.1):
        a = T.simulate_stage(x, np.array([0.01]), np.array([u]), np.zeros(1), np.zeros(1))
        b = F.simulate_stage(x, np.array([0.01]), np.array([u]), np.zeros(1), np.zeros(1))
        np.testing.assert_array_equal(a.state, b.state)
        assert a.cost[0] == b.cost[0]
    pt = branch_and_bound(T, _root()[:5], 0.0)
    pf = branch_and_bound(F, _root()[:5], 0.0)
    assert pt.choices == pf.choices and pt.f_opt == pf.f_opt
    slowed = _problem(Plane(0.0, 0.0), RESISTANCE["skier"])
    assert slowed.free and slowed.meta()["ground"] == "flat"


GROUNDS = {"plane": Plane(math.radians(18), 0.0), "traverse": Plane(math.radians(25), -1.2),
           "bumps": _bumps()}


@pytest.mark.parametrize("name", sorted(GROUNDS))
@pytest.mark.parametrize("variant", [{}, {"viable_stages": 0}, {"batch": 1, "warm_start": False},
                                     {"lower_bound": False}])
def test_search_equals_exhaustive_on_terrain(name, variant):
    """Branch and bound on terrain returns exhaustive search's optimum and plan."""
    p = _problem(GROUNDS[name], N=6, q=3, **variant)
    # On the path, and 6 m off it (the foot closing on the path as fast as it can: an
    # over-estimated lower bound clips the optimum there).
    solved = 0
    for heading, V, y in ((0.0, 8.0, 0.0), (0.3, 5.0, 0.0), (-0.9, 9.0, 6.0)):
        x0 = _root(V, heading, p.ground, y)
        plan = branch_and_bound(p.local(x0[:2], x0), x0, 0.0)
        f, choices = exhaustive(p.local(x0[:2], x0), x0, 0.0)
        if not math.isfinite(f):
            assert not plan.feasible and choices is None
            continue
        solved += 1
        assert plan.f_opt == pytest.approx(f, rel=1e-9, abs=1e-12)
        assert plan.choices == choices
    assert solved >= 1


@pytest.mark.parametrize("name", sorted(GROUNDS))
def test_lower_bound_is_admissible_on_terrain(name):
    """At every node of the full tree, the lower bound (what the search adds to f) is at most the
    cost still to come of each completion that neither collides nor falls."""
    p = _problem(GROUNDS[name], N=5, q=4, obstacles=False)
    p.limits = replace(p.limits, dC_f_max=0.15)
    p.u_values = p.limits.dC_f_max * np.linspace(-1.0, 1.0, 4)
    checked = 0
    for heading, y in ((0.0, 0.0), (-0.9, 6.0), (0.6, -5.0)):
        x0 = _root(9.0, heading, p.ground, y)
        loc = p.local(x0[:2], x0)
        st, q = loc.settings, 4
        x, cf, f = x0.reshape(-1, 1), np.zeros(1), np.zeros(1)
        levels = []                               # per depth: (parent index, f, h, alive)
        for depth in range(1, st.n_stages + 1):
            m = x.shape[1]
            par = np.repeat(np.arange(m), q)
            r = loc.simulate_stage(x[:, par], cf[par], np.tile(loc.u_values, m),
                                   np.zeros(m * q), np.zeros(m * q))
            f = f[par] + r.cost
            h = loc.lower_bound(r.d_last, depth, r.state, r.C_f)
            levels.append((par, f, h, ~(r.collided | r.fell)))
            x, cf = r.state, r.C_f
        # The least surviving leaf cost below each node, backed up level by level.
        par, f, h, alive = levels[-1]
        best = np.where(alive, f, np.inf)
        for depth in range(len(levels) - 1, 0, -1):
            up = np.full(len(levels[depth - 1][1]), np.inf)
            np.minimum.at(up, par, best)
            par, f, h, alive = levels[depth - 1]
            best = np.where(alive, up, np.inf)
            ok = np.isfinite(best)
            assert np.all(f[ok] + h[ok] <= best[ok] * (1 + 1e-9) + 1e-12)
            checked += int(ok.sum())
    assert checked > 50


def test_search_prunes_on_terrain():
    """The Lipschitz bound with the speed limit clips nodes (not a blind enumeration)."""
    p = _problem(GROUNDS["plane"], N=6, q=4, obstacles=False)
    x0 = _root()
    plan = branch_and_bound(p.local(x0[:2], x0), x0, 0.0)
    assert plan.viable and plan.stats.clipped_bound > 0
    assert plan.stats.expanded < (4 ** 6 - 1) / 3 / 4
    assert plan.f_opt == pytest.approx(exhaustive(p.local(x0[:2], x0), x0, 0.0)[0], rel=1e-9)


def test_speed_limit_bounds_every_step():
    """Every surviving branch's foot moves at most v_max per unit time (what the Lipschitz bound
    assumes), and the limit is a rule: a branch past it is clipped."""
    p = _problem(GROUNDS["bumps"], obstacles=False)
    x0 = _root(12.0)
    loc = p.local(x0[:2], x0)
    q = 4
    x = np.repeat(x0.reshape(-1, 1), q, 1)
    cf = np.zeros(q)
    for _ in range(loc.settings.n_stages):
        r = loc.simulate_stage(x, cf, loc.u_values, np.zeros(q), np.zeros(q), record=True)
        P = np.array([s[:2] for s in r.record["state"]] + [r.state[:2]])
        step = np.hypot(*np.diff(P, axis=0).transpose(1, 0, 2))
        assert np.all(step[:, ~r.fell] <= loc.v_max * loc.settings.dt)
        x, cf = r.state, r.C_f
    tight = loc.local(x0[:2])
    tight.v_max = 8.0
    r = tight.simulate_stage(x0.reshape(-1, 1), np.zeros(1), np.zeros(1), np.zeros(1),
                             np.zeros(1))
    assert r.fell[0]                               # 12 m/s is past a limit of 8: a run-away


def test_steepest_sine():
    assert steepest_sine(Plane(math.radians(18), 0.3)) == pytest.approx(math.sin(math.radians(18)))
    hf = _bumps()
    xs = np.linspace(-10, 69.99, 400)
    X, Y = np.meshgrid(xs, np.linspace(-40, 39.99, 400))
    _, hx, hy, *_ = hf.derivatives(X, Y)
    grad = np.hypot(hx, hy).max()
    assert grad / math.sqrt(1 + grad * grad) <= steepest_sine(hf) < 1.0


def test_flat_scene_plans_exactly_as_before():
    """scenes/slalom.json (no terrain): the first search and five replans as on main before the
    terrain planner (nodes expanded and f_opt recorded from that code)."""
    sc = load_scene(ROOT / "scenes" / "slalom.json")
    assert sc.ground is None and len(sc.state0) == 5
    plan = branch_and_bound(sc.problem().local(sc.state0[:2]), sc.state0, 0.0)
    assert plan.f_opt == 16.313956610244407
    assert plan.choices == (2, 2, 1, 4, 4, 0, 1, 1, 3, 4)
    assert (plan.stats.expanded, plan.stats.generated) == (101, 460)
    r = sc.setup().run(sc.state0, 0.0, 1.5)
    assert [(x.f_opt, x.stats.expanded) for x in r.replans] == [
        (16.313956610244407, 101), (23.770837624345187, 102), (29.100206775185846, 65),
        (34.713646166764796, 88), (36.11536915352838, 27)]
    assert float(r.trajectory.x[-1]) == 12.061152801670126
    assert np.all(r.trajectory.z == 0.0)
    np.testing.assert_allclose(r.trajectory.V_cm, 8.0, rtol=1e-14)


def test_slope_slalom_scene():
    """The shipped slalom down an 18 deg plane: followed to the end through every gate, the
    speed computed along the way (gained from the drop, less friction and drag), z on the plane."""
    sc = load_scene(ROOT / "scenes" / "slope_slalom.json")
    assert isinstance(sc.ground, Plane) and sc.resistance == SKIER
    r = sc.run()
    tr = r.trajectory
    assert r.reached_end and tr.meta["ground"].startswith("plane (slope 18")
    np.testing.assert_allclose(tr.z, -math.tan(math.radians(18)) * tr.x, atol=1e-9)
    assert tr.V_cm[0] == 8.0 and tr.V_cm[-1] > 20.0
    # The speed obeys dV/dt = g_t - (mu N / m) V_f / V - k V^2 + l omega V_f C_f cos th along
    # the run (docs/TERRAIN.md Section 4): the rows' rates, integrated by the trapezoid rule,
    # give the rows' speeds (to the rule's O(dt^2); leaving out the drag or the friction moves
    # the end speed by 13 or 6 m/s).
    b, res = sc.figure.body, sc.resistance
    fr = surface_frame(sc.ground, tr.x, tr.y, tr.theta_dir, b.g)
    s, c = np.sin(tr.theta_v), np.cos(tr.theta_v)
    N_m = fr.g_normal - b.l * (tr.alpha_v * s + tr.omega_v ** 2 * c)
    rate = (fr.g_along - res.mu * N_m * tr.V_f / tr.V_cm - res.drag_k(b.m) * tr.V_cm ** 2
            + b.l * tr.omega_v * c * tr.V_f * tr.C_f)
    V = tr.V_cm[0] + np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1])
                                                       * np.diff(tr.t))])
    np.testing.assert_allclose(V, tr.V_cm, rtol=0, atol=5e-3)      # measured: 2.6e-3
    # Energy: the kinetic energy gained is less than the drop (friction and drag take some).
    assert 0.0 < 0.5 * (tr.V_cm[-1] ** 2 - 64.0) < -tr.z[-1] * b.g
    assert np.all(np.abs(tr.theta_v) <= sc.settings.theta_bound)


def test_follow_setup_terrain_start_state():
    """FollowSetup on terrain appends the start speed to a 5-entry start state."""
    p = _problem(GROUNDS["plane"])
    path = HermitePath.from_points([[0, 0], [30, 0]], [[10, 0], [10, 0]])
    setup = FollowSetup(p.figure, path, Obstacles(), p.settings, ground=GROUNDS["plane"],
                        resistance=SKIER)
    res = setup.run(start_state(path), duration=0.6)
    assert res.trajectory.V_cm[0] == 8.0 and res.trajectory.V_cm[-1] > 8.0
    assert setup.problem().free


def test_runaways_counted_and_proof_dropped(monkeypatch):
    """A search that clips a run-away counts it (its copies too), and the receding horizon
    then hands no proof to the next search (its speed limit may be higher)."""
    from blender_turning.core.planner import receding
    p = _problem(GROUNDS["plane"], N=3, q=3, obstacles=False)
    x0 = _root()
    loc = p.local(x0[:2], x0)
    assert loc.runaways == 0
    branch_and_bound(loc, x0, 0.0)
    assert loc.runaways == 0                          # no branch comes near the limit
    loc.v_max = 9.0                                   # the foot reaches 9 m/s within the horizon
    plan = branch_and_bound(loc, x0, 0.0)
    assert loc.runaways > 0 and plan.stats.clipped_fall > 0
    seen, clipped = [], []
    real = receding.branch_and_bound

    def spy(problem, state, C_f, t0=0.0, s0=0.0, previous=None, proof=None):
        seen.append(proof is not None)
        if limit is not None:                         # a limit some branches pass
            problem.v_max = state[5] + limit
        plan = real(problem, state, C_f, t0, s0, previous, proof)
        clipped.append(problem.runaways)
        return plan
    monkeypatch.setattr(receding, "branch_and_bound", spy)
    for limit in (2.5, None):
        seen.clear(), clipped.clear()
        receding.follow(p, x0, 0.0, 0.9)
        assert seen[1:] == [c == 0 for c in clipped[:-1]]
        assert (min(clipped) > 0) == (limit is not None)
        assert seen[1:] == [limit is None] * 2

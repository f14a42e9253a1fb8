"""The racer's line with the speed free (core/planner/reach.py ``RaceCost``, a free speed;
docs/racing.md, "On Reid's 19 deg slope"): on a 19 deg plane each stage costs the envelope's
distance less what the centre of mass makes good, never below 0; the bound never exceeds the
least cost still to come; the search returns the exhaustive optimum around a pole; the leg force
is checked at the state's own speed on the ground; braking for the racer is not capped by the
drawn path's bends."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.ground.terrain import Plane
from blender_turning.core.physics.grip import SNOW
from blender_turning.core.physics.model import RESISTANCE, V_CM
from blender_turning.core.planner import PlannerSettings, Problem, branch_and_bound, exhaustive
from blender_turning.core.planner.speed_cap import SpeedCap

SLOPE = math.radians(19.0)


def racer(N=3, q=5, obstacles=Obstacles(), rate=2.06, slope=SLOPE, **kw):
    """The slalom racer from 12 m/s on a plane falling along +x, the course straight down it."""
    fig = preset("slalom_racer")
    fig = replace(fig, limits=replace(fig.limits, dC_f_max=rate),
                  body=replace(fig.body, V_cm=12.0))
    path = HermitePath.from_points(np.array([[0.0, 0.0], [60.0, 0.0]]),
                                   np.array([[60.0, 0.0], [60.0, 0.0]]))
    st = PlannerSettings(n_stages=N, q=q, t_stage=0.2, theta_bound=math.radians(75.0),
                         line="race", **kw)
    return Problem(fig, PathDistance(path), obstacles, st, ground=Plane(slope, 0.0),
                   resistance=RESISTANCE["skier"])


def at_root(p, root):
    """The problem as the receding horizon searches it from ``root`` at t = 0."""
    return p.local(root[:2], root, 0.0)


def random_nodes(m, seed, V=(10.0, 14.0)):
    rng = np.random.default_rng(seed)
    c = 0.25
    state = np.stack([rng.uniform(0, 20, m), rng.uniform(-3, 3, m), rng.uniform(-np.pi, np.pi, m),
                      rng.uniform(-1.0, 1.0, m), rng.uniform(-1.0, 1.0, m),
                      rng.uniform(*V, m)])
    return state, rng.uniform(-c, c, m)


def test_a_stage_costs_the_envelope_less_what_the_centre_of_mass_makes_good():
    root = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 12.0])
    p = at_root(racer(), root)
    a = 9.81 * math.sin(SLOPE)
    # The envelope of a root upright and still: V_r + g sin(sigma) t, and the speed the lean
    # could give falling to its bound, g l (1 - cos 75 deg).
    lean = 2 * 9.81 * p.body.l * (1 - math.cos(math.radians(75.0)))
    np.testing.assert_allclose(p.race.envelope(p.race.root, [0.0, 1.0]),
                               np.sqrt(np.array([12.0, 12.0 + a]) ** 2 + lean))
    # Upright runs at headings alpha: the trapezoid of E - V_cm cos(alpha) over the steps.
    alpha = np.array([0.0, 0.3, -1.0, 2.5])
    still = np.zeros((6, 4))
    still[2], still[V_CM] = alpha, 12.0
    r = p.simulate_stage(still, np.zeros(4), np.zeros(4), np.zeros(4), np.zeros(4), record=True)
    V = np.stack([s[V_CM] for s in r.record["state"]] + [r.state[V_CM]])     # (steps + 1, 4)
    t = 0.05 * np.arange(len(V))[:, None]
    short = np.sqrt((12.0 + a * t) ** 2 + lean) - V * np.cos(alpha)
    np.testing.assert_allclose(r.cost, 0.05 * 0.5 * (short[:-1] + short[1:]).sum(axis=0),
                               rtol=1e-12, atol=1e-12)
    assert r.cost[0] < r.cost[1] < r.cost[2] < r.cost[3]
    # Random nodes within the envelope: never below 0.
    state, C0 = random_nodes(400, 1, V=(8.0, 12.0))
    u = np.random.default_rng(2).choice(p.u_values, 400)
    r = p.simulate_stage(state, C0, u, np.zeros(400), np.zeros(400))
    assert r.cost[~r.fell].min() >= 0.0


def test_a_lean_stores_speed_the_envelope_allows():
    """A root leaning 60 deg: the envelope grows by the lean's energy above its bound's."""
    root = np.array([0.0, 0.0, 0.0, math.radians(60.0), 0.5, 12.0])
    p = at_root(racer(slope=0.0), root)
    b = p.body
    lean = b.g * b.l * (0.5 - math.cos(math.radians(75.0))) + 0.5 * (b.l ** 2 + b.I_v / b.m) * 0.25
    assert p.race.envelope(p.race.root, 5.0) == pytest.approx(math.sqrt(144.0 + 2 * lean))


def test_the_bound_never_exceeds_the_least_cost_still_to_come():
    """Random nodes two stages from the horizon of a search from a 12 m/s root: the bound
    against every completion's cost (q^2 plans, none clipped but by the rules)."""
    root = np.array([0.0, 0.0, 0.0, 0.3, 0.0, 12.0])
    p = at_root(racer(N=3, q=5, viable_stages=0), root)
    state, C0 = random_nodes(300, 3, V=(11.0, 12.5))
    t1 = np.full(300, 0.2)
    bound = p.race.bound(state, C0, np.ones(300, int))
    q = len(p.u_values)
    x, c = np.repeat(state, q * q, 1), np.repeat(C0, q * q)
    u1 = np.tile(np.repeat(p.u_values, q), 300)
    u2 = np.tile(p.u_values, 300 * q)
    t = np.repeat(t1, q * q)
    r1 = p.simulate_stage(x, c, u1, t, np.zeros(len(c)))
    r2 = p.simulate_stage(r1.state, r1.C_f, u2, t + 0.2, np.zeros(len(c)))
    cost = np.where(r1.fell | r2.fell, np.inf, r1.cost + r2.cost).reshape(300, q * q)
    least = cost.min(axis=1)
    ok = np.isfinite(least)
    assert ok.sum() > 200
    assert np.all(bound[ok] <= least[ok] + 1e-9)
    across = np.abs(((state[2] + np.pi) % (2 * np.pi)) - np.pi) > 1.5
    assert bound[across & ok].min() > 0.5


@pytest.mark.parametrize("N,q", [(3, 4), (3, 5)])
def test_the_search_returns_the_exhaustive_optimum_around_a_pole(N, q):
    poles = Obstacles(segments=[((8.0, 0.6), (8.0, -12.0))], clearance=0.3)
    root = np.array([0.0, 0.0, 0.3, 0.0, 0.0, 12.0])
    p = at_root(racer(N, q, poles), root)
    f, choices = exhaustive(p, root, 0.0)
    plan = branch_and_bound(p, root, 0.0)
    assert plan.f_opt == pytest.approx(f, rel=1e-9) and plan.choices == choices


def test_the_leg_force_is_checked_on_the_ground_at_the_state_s_speed():
    from test_planner_race import assert_leg_force_clipped
    root = np.array([0, 0, 0, 0, 0, 12.0])
    state, C0 = random_nodes(60, 5)
    assert_leg_force_clipped(at_root(racer(N=3, q=5, leg_force_max=3.0), root),
                             at_root(racer(N=3, q=5), root), state, C0, 3.0)


def test_the_racer_s_braking_is_not_capped_by_the_drawn_line():
    from blender_turning.core.course.reid import course
    from blender_turning.core.course.scene import scene_from_dict
    doc = course(10.0, 12.0, gates=2, planner={"line": "race"})
    doc["terrain"] = {"type": "plane", "slope_deg": 19, "downhill_deg": 0}
    scene = replace(scene_from_dict(doc, "reid"), speed_cap=SpeedCap(12.0, SNOW["hard"]))
    assert scene.problem().speed_cap.cap(9.81) == 12.0
    path = scene.with_settings(line="path").problem().speed_cap.cap(9.81)
    assert path == pytest.approx(math.sqrt(9.81 / 0.192), rel=0.05)


@pytest.mark.parametrize("V,gain,lean", [(0.5, math.cos(SLOPE), 1.0), (0.5, math.cos(SLOPE), -1.0),
                                         (1.0, 1.0 / math.cos(SLOPE), 1.0),
                                         (1.0, 1.0 / math.cos(SLOPE), -1.0)])
def test_the_heading_tables_hold_the_slowest_and_the_fastest_turn(V, gain, lean):
    """The heading after n steps of the curvature at its fastest rate up (down) from each cell's
    end, at the slowest speed (the clip's 0.5 m/s) and the plane's least heading gain cos sigma,
    or at the envelope's top and 1 / cos sigma (a track down the fall line), the lean at its
    bound either way: within the tables' interval (``V`` 1.0: the envelope's top)."""
    root = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 12.0])
    p = at_root(racer(N=3, q=5), root)
    t = p.race.tables
    speed = V if V < 1.0 else float(p.race.envelope(p.race.root, 4 * 0.2))
    lim, l, sl = p.limits, p.body.l, lean * p._sin_lean
    h, sub = p.settings.dt, 200
    tau = (np.arange(t.lo.shape[1] * sub) + 0.5) * h / sub            # midpoints, fine steps
    for cell in range(0, len(t.grid) - 1, 7):
        for end, sign in ((t.grid[cell], -1.0), (t.grid[cell + 1], 1.0)):
            C = np.clip(end + sign * lim.dC_f_max * tau, -lim.C_f_max, lim.C_f_max)
            rate = speed * gain * C / (1.0 - C * l * sl)
            psi = np.cumsum(rate * h / sub)[sub - 1::sub]                  # each step's end
            assert np.all(psi >= t.lo[cell] - 1e-9) and np.all(psi <= t.hi[cell] + 1e-9)

"""The edge a lean can hold (core/equipment.py's ``EdgeLimit``; docs/racing.md, "The racer's
line"): the skis' edge angle for a curvature (the sidecut relation) at most the lean plus the
body's angulation, and the planner's clip of branches that break it (``PlannerSettings.
edge_limit``), which keeps the search exact."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.equipment import ANGULATION, EdgeLimit, carving_of, edge_limit_of
from blender_turning.core.planner import PlannerSettings, Problem, branch_and_bound, exhaustive

SL = carving_of("slalom_racer")


def test_the_curvature_a_lean_holds_is_the_sidecut_relations_at_lean_plus_angulation():
    limit = EdgeLimit(SL, math.radians(15.0))
    for lean_deg, edge_deg in ((30.0, 45.0), (50.0, 65.0), (-10.0, 5.0)):
        c = 1.0 / SL.radius(math.radians(edge_deg))      # the curvature carved at that edge
        lean = math.radians(lean_deg)
        assert limit.holds(lean, c) and limit.holds(-lean, -c)
        assert not limit.holds(lean, c * 1.001) and not limit.holds(-lean, -c * 1.001)
    # A flat ski (a lean out of the turn past the angulation) carves the sidecut's own arc;
    # the skis' largest edge bounds the curvature whatever the lean.
    assert limit.holds(math.radians(-40.0), 1.0 / SL.sidecut_radius)
    assert not limit.holds(math.radians(-40.0), 1.001 / SL.sidecut_radius)
    assert limit.holds(math.radians(80.0), SL.C_f_max)
    assert not limit.holds(math.radians(80.0), SL.C_f_max * 1.001)


def test_only_the_presets_with_carving_equipment_have_it():
    assert edge_limit_of("slalom_racer") == EdgeLimit(SL, ANGULATION)
    assert edge_limit_of("skier") is None and edge_limit_of(None) is None
    settings = PlannerSettings(edge_limit=True)
    fig = preset("skier")
    path = PathDistance(HermitePath.from_points(np.array([[0.0, 0.0], [50.0, 0.0]]),
                                                np.array([[50.0, 0.0], [50.0, 0.0]])))
    assert Problem(fig, path, Obstacles(), settings).edge_limit is None


def racer_problem(edge_limit, N=3, q=4):
    """The slalom racer, 12 m/s, about to swing round a gate 3 m to its left (the planner's
    rate 0.5 1/(m s): with the preset's own 2.06 every coarse branch breaks the limit)."""
    fig = preset("slalom_racer")
    fig = replace(fig, limits=replace(fig.limits, dC_f_max=0.5))
    pts = np.array([[0.0, 0.0], [8.0, 3.0], [16.0, 0.0], [30.0, -3.0]])
    tang = np.array([[12.0, 0.0], [12.0, 0.0], [12.0, -6.0], [12.0, 0.0]])
    st = PlannerSettings(n_stages=N, q=q, t_stage=0.3, theta_bound=math.radians(80.0),
                         edge_limit=edge_limit)
    return Problem(fig, PathDistance(HermitePath.from_points(pts, tang)), Obstacles(), st)


@pytest.mark.parametrize("N,q", [(3, 4), (3, 5)])
def test_the_clip_keeps_the_search_exact_and_every_plan_holds_its_edges(N, q):
    state = np.array([0.0, 0.0, 0.0, math.radians(36.0), 0.0])
    on, off = racer_problem(True, N, q), racer_problem(False, N, q)
    plan = branch_and_bound(on, state, 0.0)
    f, choices = exhaustive(on, state, 0.0)
    assert plan.viable and plan.f_opt == pytest.approx(f, rel=1e-9) and plan.choices == choices
    # The clip binds: without it the optimum is cheaper and breaks the edge limit.
    free = branch_and_bound(off, state, 0.0)
    assert free.viable and free.f_opt < plan.f_opt
    for p, ok in ((plan, True), (free, False)):
        x, cf, t, s = state.reshape(-1, 1), np.zeros(1), np.zeros(1), np.zeros(1)
        held = True
        for u in p.u:
            r = on.simulate_stage(x, cf, np.array([u]), t, s, record=True)
            lean = np.array([np.ravel(v) for v in r.record["state"]])[:, 3]
            cfs = np.array([np.ravel(c)[0] for c in r.record["C_f"]])
            held &= bool(on.edge_limit.holds(lean, cfs).all())
            x, cf, t, s = r.state, r.C_f, t + 0.3, r.s
        assert held == ok

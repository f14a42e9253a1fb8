"""The branch-and-bound search returns the exhaustive search's optimum (part 4)."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.planner import PlannerSettings, Problem, branch_and_bound, exhaustive
from blender_turning.core.planner.viable import dead_end, doomed_nodes
from blender_turning.core.planner.spacing import PairFloor


def random_problem(rng, N, q, **settings):
    """A small random scene near the start: a wiggly path, a few trees, poles and a polygon."""
    fig = preset(str(rng.choice(["skier", "cyclist", "snowboarder"])))
    fig = replace(fig, limits=replace(fig.limits, dC_f_max=float(rng.uniform(0.05, 0.4))))
    if fig.name != "cyclist" and rng.random() < 0.6:   # slower: the fall table applies (mostly)
        fig = replace(fig, body=replace(fig.body, V_cm=float(rng.uniform(5.0, 8.0))))
    v = fig.body.V_cm
    span = v * N * 0.3
    xs = np.linspace(0.0, span * 1.5, 4)
    pts = np.column_stack([xs, rng.normal(0.0, 0.15 * span, 4)])
    tang = np.column_stack([np.full(4, xs[1]), rng.normal(0, 0.2 * span, 4)])
    path = HermitePath.from_points(pts, tang)
    n_c = int(rng.integers(0, 4))
    circles = np.column_stack([rng.uniform(0.5, 1.0, n_c) * span,
                               rng.choice([-1, 1], n_c) * rng.uniform(0.05, 0.3, n_c) * span,
                               rng.uniform(0.2, 0.05 * span + 0.3, n_c)])
    n_s = int(rng.integers(0, 3))
    a = np.column_stack([rng.uniform(0.5, 1.0, n_s) * span,
                         rng.choice([-1, 1], n_s) * rng.uniform(0.05, 0.3, n_s) * span])
    segs = np.stack([a, a + rng.normal(0, 0.1 * span, (n_s, 2))], axis=1)
    polys = []
    if rng.random() < 0.3:
        c = np.array([rng.uniform(0.6, 1.0) * span, rng.choice([-1, 1]) * 0.3 * span])
        polys.append(c + rng.uniform(0.5, 2) * np.array([[1, 0], [0, 1], [-1, 0.2], [0, -1]]))
    obs = Obstacles(segs, circles, polys, clearance=float(rng.uniform(0.0, 0.5)))
    st = PlannerSettings(n_stages=N, q=q, **settings)
    problem = Problem(fig, PathDistance(path, exact=bool(rng.random() < 0.2)), obs, st)
    state = np.array([0.0, 0.0, rng.normal(0, 0.1), rng.normal(0, 0.05), rng.normal(0, 0.1)])
    cf = float(rng.uniform(-0.5, 0.5) * fig.limits.C_f_max * 0.2)
    return problem, state, cf


VARIANTS = [dict(warm_start=w, lower_bound=lb, batch=b)
            for w in (False, True) for lb in (False, True) for b in (1, 8)]
VARIANTS += [dict(lookahead=0), dict(lookahead=1, batch=3), dict(lookahead=30, warm_start=False),
             dict(fall_table=False), dict(fall_table=False, lower_bound=False, warm_start=False),
             dict(reach_directions=0), dict(reach_directions=3, warm_start=False)]


@pytest.mark.parametrize("seed", range(48))
def test_same_optimum_as_exhaustive(seed):
    rng = np.random.default_rng(seed)
    N = int(rng.integers(1, 6))
    q = int(rng.integers(2, 6)) if seed % 8 == 0 else int(rng.integers(3, 6))
    problem, state, cf = random_problem(rng, N, q)
    f_ref, plan_ref = exhaustive(problem, state, cf)
    previous = tuple(int(c) for c in rng.integers(0, q, N))
    for v in VARIANTS:
        p = replace(problem.settings, **v)
        pb = Problem(problem.figure, problem.distance, problem.obstacles, p)
        plan = branch_and_bound(pb, state, cf, previous=previous)
        if plan_ref is None:
            assert not plan.feasible and plan.f_opt == math.inf, v
            continue
        assert plan.feasible, v
        assert plan.f_opt == pytest.approx(f_ref, rel=1e-9, abs=1e-9), v
        assert plan.stats.proven
        # The plan's value is what its choices really cost.
        assert len(plan.choices) == N


def feasible_problem(seed, N, q):
    while True:
        problem, state, cf = random_problem(np.random.default_rng(seed), N, q)
        if exhaustive(problem, state, cf)[1] is not None:
            return problem, state, cf
        seed += 1000


def test_vectorised_children_change_nothing():
    problem, state, cf = feasible_problem(123, 4, 4)
    a = branch_and_bound(problem, state, cf)
    pb = Problem(problem.figure, problem.distance, problem.obstacles,
                 replace(problem.settings, vectorize_children=False, batch=1, warm_start=False,
                         lower_bound=False))
    b = branch_and_bound(pb, state, cf)
    f_ref, _ = exhaustive(problem, state, cf)
    assert a.f_opt == pytest.approx(f_ref, rel=1e-9) and b.f_opt == pytest.approx(f_ref, rel=1e-9)


@pytest.mark.parametrize("seed", [7, 11, 12, 13, 14, 15])
def test_warm_start_and_proof_from_the_previous_search_are_exact(seed):
    """Receding horizon: plan, apply a stage, plan again with the shifted plan as first bound
    and the previous search's proven bounds (proof.py)."""
    rng = np.random.default_rng(seed)
    problem, state, cf = random_problem(rng, 4, 5)
    previous = proof = None
    t = 0.0
    for _ in range(3):
        plan = branch_and_bound(problem, state, cf, t, previous=previous, proof=proof)
        f_ref, _ = exhaustive(problem, state, cf, t)
        if not plan.feasible:
            assert f_ref == math.inf
            return
        assert plan.f_opt == pytest.approx(f_ref, rel=1e-9, abs=1e-9)
        r = problem.simulate_stage(state[:, None], np.array([cf]), np.array([plan.u[0]]),
                                   np.array([t]), np.zeros(1))
        state, cf, t, previous = r.state[:, 0], float(r.C_f[0]), t + 0.3, plan.choices
        proof = plan.proof.after(plan.choices[0])


@pytest.mark.parametrize("seed", range(4))
def test_proven_bounds_are_admissible(seed):
    """Below the applied child, each child's proven cost still to come is at most the true
    optimum of the rest of the old horizon (inf only where no completion exists)."""
    problem, state, cf = feasible_problem(seed, 4, 4)
    st = problem.settings
    plan = branch_and_bound(problem, state, cf)
    proof = plan.proof.after(plan.choices[0])
    r = problem.simulate_stage(state[:, None], np.array([cf]), np.array([plan.u[0]]),
                               np.zeros(1), np.zeros(1))
    q = st.q
    kids = problem.simulate_stage(np.repeat(r.state, q, 1), np.repeat(r.C_f, q),
                                  problem.u_values, np.full(q, 0.3), np.repeat(r.s, q))
    rest = Problem(problem.figure, problem.distance, problem.obstacles,
                   replace(st, n_stages=st.n_stages - 2))
    checked = 0
    for c in range(q):
        togo = proof.togo[proof.root, c]
        if kids.collided[c] or kids.fell[c]:
            continue
        if doomed_nodes(problem, kids.state[:, [c]], kids.C_f[[c]], 2)[0]:
            assert togo == math.inf     # not a node of any allowed plan (module docstring)
            continue
        f_ref, _ = exhaustive(rest, kids.state[:, c], float(kids.C_f[c]), 0.6, float(kids.s[c]),
                              fallback=False)         # the problem the search proved it for
        assert togo <= f_ref * (1 + 1e-9) + 1e-9
        checked += np.isfinite(togo) and togo > 0
    assert checked


@pytest.mark.parametrize("seed", range(6))
def test_lower_bound_is_admissible(seed):
    """Along every surviving branch the cost still to come is at least the lower bound (the
    Lipschitz bound, the arc bound and the reachable-set bound over the next samples)."""
    problem, state, cf = feasible_problem(seed, 4, 4)
    st = problem.settings
    q = st.q
    x, c, f = state[:, None], np.array([cf]), np.zeros(1)
    t, s, alive = np.zeros(1), np.zeros(1), np.ones(1, bool)
    hist = []
    for depth in range(1, st.n_stages + 1):
        m = x.shape[1]
        par = np.repeat(np.arange(m), q)
        ch = np.tile(np.arange(q), m)
        r = problem.simulate_stage(x[:, par], c[par], problem.u_values[ch], t[par], s[par])
        f = f[par] + r.cost
        alive = alive[par] & ~(r.collided | r.fell)
        hist.append((par, f.copy(), problem.lower_bound(r.d_last, depth, r.state, r.C_f,
                                                        reach=True),
                     problem.lower_bound(r.d_last, depth)))
        x, c, t, s = r.state, r.C_f, t[par] + 0.3, r.s
    final = hist[-1][1]
    idx = np.flatnonzero(alive)
    assert len(idx)
    for par, f_d, lb_arc, lb_lip in reversed(hist):
        togo = final[alive] - f_d[idx]
        assert np.all(togo >= lb_arc[idx] - 1e-9)
        assert np.all(lb_arc[idx] >= lb_lip[idx] - 1e-12)
        idx = par[idx]


def test_settings_are_validated():
    with pytest.raises(ValueError, match="n_stages"):
        PlannerSettings(n_stages=0)
    with pytest.raises(ValueError, match="t_stage"):
        PlannerSettings(t_stage=0.33)
    with pytest.raises(ValueError, match="q = 1"):
        PlannerSettings(q=1)


def branch_tracks(problem, state, cf):
    """The foot's samples (branches, samples, 2) on all q^N branches from ``state``, and which
    branches never fall."""
    st = problem.settings
    q, per = st.q, st.steps_per_sample
    x, c, s = state[:, None], np.array([cf]), np.zeros(1)
    alive = np.ones(1, bool)
    track = np.zeros((1, 0, 2))
    for _ in range(st.n_stages):
        m = x.shape[1]
        par = np.repeat(np.arange(m), q)
        r = problem.simulate_stage(x[:, par], c[par], np.tile(problem.u_values, m),
                                   np.zeros(len(par)), s[par], record=True)
        steps = np.array(r.record["state"][1:] + [r.state])[:, :2, :].transpose(2, 0, 1)
        track = np.concatenate([track[par], steps[:, per - 1::per]], axis=1)
        alive = alive[par] & ~r.fell
        x, c, s = r.state, r.C_f, r.s
    return track, alive


@pytest.mark.parametrize("seed", range(6))
def test_reach_bound_holds_at_every_sample(seed):
    """reach.py: on every branch that does not fall, the distance at each of the next samples is
    at least the reachable-set bound from the root (all q^N plans, per sample)."""
    problem, state, cf = feasible_problem(seed + 50, 3, 4)
    problem = Problem(problem.figure, PathDistance(problem.distance.path), problem.obstacles,
                      problem.settings)
    rb = problem.reach_bound()
    assert rb is not None and rb.samples > 0
    track, alive = branch_tracks(problem, state, cf)
    n = min(rb.samples, track.shape[1])
    k = np.arange(1, n + 1)
    bound = rb.sample_bounds(problem.distance.samples, state[:, None], np.array([cf]), k)[0]
    d = problem.distance(track[alive][:, :n])
    assert np.all(d >= bound[None, :] - 1e-9)
    assert bound.max() > 0 and np.any(d.min(axis=0) < bound + 0.5)    # it bites, and is tight


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("spacing", [1.5, 3.0])
def test_pair_floor_holds_on_every_branch(seed, spacing):
    """spacing.py: on every branch that does not fall, each two consecutive samples (the first
    with the root's own) are together at least their pair's floor, and the floor bites.  Path
    samples about ``spacing`` times the foot's travel per sample apart."""
    problem, state, cf = feasible_problem(seed + 80, 3, 4)
    st = problem.settings
    path = problem.distance.path
    per_segment = max(1, round(path.length() / path.n_segments / (spacing * problem.v_max *
                                                                   st.sample_dt)))
    coarse = PathDistance(path, per_segment=per_segment)
    problem = Problem(problem.figure, coarse, problem.obstacles, st)
    pf = PairFloor(problem)
    track, alive = branch_tracks(problem, state, cf)
    d0 = float(coarse(state[:2]))
    d = np.concatenate([np.full((int(alive.sum()), 1), d0), coarse(track[alive])], axis=1)
    floor = pf.floor(state[:, None], track.shape[1])[0]
    assert np.all(d[:, :-1] + d[:, 1:] >= floor[None, :] - 1e-9)
    assert floor.max() > 0


def paper_problem(problem):
    """The same problem with ``viable_stages = 0``: the paper's (no dead-end test)."""
    return Problem(problem.figure, problem.distance, problem.obstacles,
                   replace(problem.settings, viable_stages=0), problem.speed)


def simulate_plan(problem, state, cf, choices):
    x, c, s = np.asarray(state, float).reshape(5, 1), np.array([cf]), np.zeros(1)
    for k, ch in enumerate(choices):
        r = problem.simulate_stage(x, c, problem.u_values[[ch]], np.array([0.3 * k]), s)
        x, c, s = r.state, r.C_f, r.s
    return x[:, 0], float(c[0])


def test_dead_end_preference_changes_the_optimum_on_many_random_problems():
    """The equivalence test above covers the restricted problem, not only the paper's: on these
    random problems the least-cost plan of the paper's problem often ends in a dead end."""
    differ = 0
    for seed in range(48):
        rng = np.random.default_rng(seed)
        N = int(rng.integers(1, 6))
        q = int(rng.integers(2, 6)) if seed % 8 == 0 else int(rng.integers(3, 6))
        problem, state, cf = random_problem(rng, N, q)
        differ += exhaustive(problem, state, cf) != exhaustive(paper_problem(problem), state, cf)
    assert differ >= 10


@pytest.mark.parametrize("seed", range(0, 48, 3))
def test_the_plan_does_not_end_in_a_dead_end(seed):
    """The returned plan's last node is where its choices lead, and unless no plan ends alive,
    one of its q children neither collides nor falls over the next stage."""
    rng = np.random.default_rng(seed)
    N = int(rng.integers(1, 6))
    q = int(rng.integers(3, 6))
    problem, state, cf = random_problem(rng, N, q)
    plan = branch_and_bound(problem, state, cf)
    if not plan.feasible:
        return
    x, c = simulate_plan(problem, state, cf, plan.choices)
    np.testing.assert_allclose(plan.leaf[0], x, rtol=1e-12, atol=1e-12)
    assert plan.leaf[1] == pytest.approx(c, abs=1e-15) and plan.leaf[2] == pytest.approx(0.3 * N)
    paper = branch_and_bound(paper_problem(problem), state, cf)
    if plan.viable:
        assert not dead_end(problem, plan.leaf)
        assert paper.f_opt <= plan.f_opt * (1 + 1e-9)
    else:                     # no plan ends alive (the fall table may say so): the paper's plan
        assert (plan.f_opt, plan.choices) == (paper.f_opt, paper.choices)


def walled_problem(viable_stages=3):
    """A wall across the path one stage beyond what the horizon can reach: every plan is
    feasible up to its last node, and every last node is a dead end."""
    fig = preset("skier")
    st = PlannerSettings(n_stages=3, q=3, viable_stages=viable_stages)
    wall_x = fig.body.V_cm * (st.horizon + 0.5 * st.t_stage)
    obs = Obstacles(segments=[[[wall_x, -40.0], [wall_x, 40.0]]])
    path = HermitePath.from_polyline([[0, 0], [60, 0]])
    return Problem(fig, PathDistance(path), obs, st)


def test_when_every_plan_ends_in_a_dead_end_the_papers_optimum_is_returned():
    problem = walled_problem()
    state = np.zeros(5)
    plan = branch_and_bound(problem, state, 0.0)
    paper = branch_and_bound(paper_problem(problem), state, 0.0)
    assert plan.feasible and not plan.viable and dead_end(problem, plan.leaf)
    assert (plan.f_opt, plan.choices) == (paper.f_opt, paper.choices)
    assert exhaustive(problem, state, 0.0) == (paper.f_opt, paper.choices)
    # Through a receding horizon: the next search (after a fallback) reuses nothing unproven.
    r = problem.simulate_stage(state[:, None], np.zeros(1), np.array([plan.u[0]]), np.zeros(1),
                               np.zeros(1))
    nxt = branch_and_bound(problem, r.state[:, 0], float(r.C_f[0]), 0.3, 0.0, plan.choices,
                           plan.proof.after(plan.choices[0]))
    ref = exhaustive(problem, r.state[:, 0], float(r.C_f[0]), 0.3)
    assert nxt.f_opt == pytest.approx(ref[0], rel=1e-9)

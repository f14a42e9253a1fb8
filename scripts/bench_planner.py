"""Benchmark the path-following planner against the paper's plain best-first search.

For each scene: one receding-horizon run with the planner as shipped (warm start, the previous
search's proof, lower bounds, fall table, children and queue nodes simulated in batches); per
replanning its wall time and nodes expanded.
Then, on a few of the same replanning states, the paper's plain best-first search (Fig. 14: no
warm start, no lower bound, no fall table, one node at a time):

- node count: the identical search with each node's q children simulated as one array (same
  expansion sequence, same counts), stopped at ``--plain-cap`` (50) times our count + 1 (so
  "capped" proves at least that ratio);
- wall time per expansion: measured literally one child at a time over its first expansions;
  the baseline's wall time is count x that (a lower bound when the count is capped).

Each run also counts the executed plans that end in a dead end (every one of the last node's q
children collides or falls within one more stage) and those for which no other plan existed.

Usage: python scripts/bench_planner.py [--quick] [--no-baseline] [--viable-stages M]
[--json out.json]
"""
from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from blender_turning.core.planner import Problem, branch_and_bound  # noqa: E402
from blender_turning.core.course.scene import load_scene  # noqa: E402

CASES = [  # scene, N, q, baseline samples
    ("slalom", 12, 7, 7),
    ("tree_skiing", 10, 5, 3),
    ("tree_skiing", 12, 5, 3),
    ("cyclist_corner", 10, 5, 3),
    ("potholes", 10, 5, 3),
]


def baseline(scene, problem, state, cf, t, ours_expanded, literal_cap, plain_cap):
    """Plain best-first from one replanning state: (expanded, capped, per-expansion s, f_opt)."""
    local = problem.local(state[:2])
    plain = replace(problem.settings, warm_start=False, lower_bound=False, fall_table=False,
                    reuse_proof=False, reach_directions=0, pair_floor=False, batch=1,
                    max_expansions=plain_cap * ours_expanded + 1)
    pb = Problem(problem.figure, local.distance, local.obstacles, plain, problem.speed)
    plan = branch_and_bound(pb, state, cf, t)
    stats = plan.stats
    literal = replace(plain, vectorize_children=False, max_expansions=literal_cap)
    pl = Problem(problem.figure, local.distance, local.obstacles, literal, problem.speed)
    clock = time.perf_counter()
    lit = branch_and_bound(pl, state, cf, t).stats
    per = (time.perf_counter() - clock) / max(lit.expanded, 1)
    return stats.expanded, not stats.proven, per, plan.f_opt


def run_case(name, N, q, n_base, literal_cap, plain_cap, viable_stages=None):
    scene = load_scene(ROOT / "scenes" / f"{name}.json").with_settings(n_stages=N, q=q)
    if viable_stages is not None:
        scene = scene.with_settings(viable_stages=viable_stages)
    clock = time.perf_counter()
    result = scene.run()
    wall = time.perf_counter() - clock
    tr = result.trajectory
    reps = result.replans
    ex = np.array([r.stats.expanded for r in reps])
    wt = np.array([r.stats.wall_time for r in reps])
    out = {"scene": name, "N": N, "q": q, "q^N": q ** N, "replans": len(reps),
           "course_s": float(tr.duration), "wall_total_s": wall,
           "expanded_median": float(np.median(ex)), "expanded_max": int(ex.max()),
           "expanded_total": int(ex.sum()), "wall_median_s": float(np.median(wt)),
           "wall_max_s": float(wt.max()), "real_time_factor": wall / float(tr.duration),
           "per_replan_wall_s": wt.tolist(), "per_replan_expanded": ex.tolist(),
           "track_mean_d": float(np.mean(scene.problem().distance(
               np.column_stack([tr.x, tr.y])))),
           "dead_ends": sum(r.dead_end for r in reps),
           "not_viable": sum(not r.viable for r in reps)}
    if n_base < 0:                                        # --no-baseline
        return out
    problem = scene.problem()
    steps = scene.settings.steps_per_stage
    picks = (np.arange(len(reps)) if n_base == 0 else     # 0: every replanning
             np.unique(np.linspace(0, len(reps) - 1, n_base).round().astype(int)))
    base = []
    for j in picks:
        k = j * steps
        state, cf = tr.data[1:6, k].copy(), float(tr.C_f[k])
        n, capped, per, f = baseline(scene, problem, state, cf, float(tr.t[k]),
                                     int(ex[j]), literal_cap, plain_cap)
        same = (not capped) and abs(f - reps[j].f_opt) <= 1e-9 * max(1.0, abs(f))
        base.append({"replan": int(j), "t": float(tr.t[k]), "ours_expanded": int(ex[j]),
                     "ours_wall_s": float(wt[j]), "plain_expanded": n, "plain_capped": capped,
                     "plain_s_per_expansion": per, "plain_wall_s_estimate": n * per,
                     "same_f_opt": same if not capped else None})
        print(f"  {name} N={N} q={q} replan {j}: ours {ex[j]} nodes {wt[j]:.3f} s; plain "
              f"{'>=' if capped else ''}{n} nodes (x{n / max(ex[j], 1):.1f}), "
              f"{per * 1e3:.1f} ms/expansion", flush=True)
    out["baseline"] = base
    out["ratio_min"] = min(b["plain_expanded"] / max(b["ours_expanded"], 1) for b in base)
    out["ratio_all"] = sum(b["plain_expanded"] for b in base) / max(
        sum(b["ours_expanded"] for b in base), 1)
    print(f"  {name} N={N} q={q}: plain / ours nodes: least x{out['ratio_min']:.1f}, all sampled "
          f"states together x{out['ratio_all']:.1f}", flush=True)
    return out


def doomed_share(name="slalom", N=12, q=7, fall_table=False):
    """Of the nodes our search expands at the first replanning, how many can never reach depth N
    without falling (whatever the obstacles and the path): a depth-first probe of the lean
    alone (theta_v, omega_v, C_f evolve independently of position at constant speed)."""
    from blender_turning.core.course.obstacles import Obstacles
    from blender_turning.core.course.path import HermitePath, PathDistance
    from blender_turning.core.planner import search

    scene = load_scene(ROOT / "scenes" / f"{name}.json").with_settings(n_stages=N, q=q,
                                                                          fall_table=fall_table)
    problem = scene.problem().local(scene.state0[:2])
    seen = []
    expand = search._expand

    def recording(pb, nodes, ids):
        for i in np.asarray(ids):
            seen.append((nodes.state[:, i].copy(), float(nodes.cols["cf"][i]), int(nodes.depth[i])))
        return expand(pb, nodes, ids)
    search._expand = recording
    try:
        branch_and_bound(problem, scene.state0, scene.C_f0)
    finally:
        search._expand = expand
    lean = Problem(problem.figure, PathDistance(HermitePath.from_polyline([[0, 0], [1, 0]]), 1),
                   Obstacles(), problem.settings)

    def viable(x, cf, r):
        if r == 0:
            return True
        res = lean.simulate_stage(np.repeat(x[:, None], q, 1), np.full(q, cf), lean.u_values,
                                  np.zeros(q), np.zeros(q))
        return any(not res.fell[j] and viable(res.state[:, j], res.C_f[j], r - 1)
                   for j in np.argsort(np.abs(res.state[3])))
    doomed = sum(not viable(x, cf, N - d) for x, cf, d in seen)
    return {"scene": name, "N": N, "q": q, "fall_table": fall_table, "expanded": len(seen),
            "lean_doomed": doomed}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one baseline sample per scene")
    ap.add_argument("--json", help="write the results here")
    ap.add_argument("--doomed", action="store_true",
                    help="only: how many expanded nodes are doomed to fall (slalom, first plan)")
    ap.add_argument("--literal-cap", type=int, default=200,
                    help="expansions timed for the one-child-at-a-time baseline")
    ap.add_argument("--plain-cap", type=int, default=50,
                    help="stop the plain search at this many times our node count (+1)")
    ap.add_argument("--viable-stages", type=int,
                    help="PlannerSettings.viable_stages (0: the paper's problem; default: as "
                         "shipped)")
    ap.add_argument("--no-baseline", action="store_true",
                    help="only our planner's runs (time, nodes, dead ends)")
    ap.add_argument("--course", action="store_true",
                    help="only: the slalom (N = 12, q = 7) against plain best-first on every "
                         "replanning of the course (node counts; ~10 s per replanning)")
    args = ap.parse_args(argv)
    info = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "python": platform.python_version(), "numpy": np.__version__,
            "machine": platform.machine(), "cpus": __import__("os").cpu_count()}
    print(json.dumps(info), flush=True)
    if args.doomed:
        print(json.dumps(doomed_share(fall_table=False)))
        print(json.dumps(doomed_share(fall_table=True)))
        return 0
    cases = [("slalom", 12, 7, 0)] if args.course else CASES
    results = []
    for name, N, q, nb in cases:
        nb = -1 if args.no_baseline else 1 if args.quick else nb
        r = run_case(name, N, q, nb, args.literal_cap, args.plain_cap, args.viable_stages)
        results.append(r)
        print(f"{name} N={N} q={q}: course {r['course_s']:.1f} s, planning "
              f"{r['wall_total_s']:.1f} s"
              f" (x{r['real_time_factor']:.2f} real time); per replan median "
              f"{r['wall_median_s'] * 1e3:.0f} ms, worst {r['wall_max_s'] * 1e3:.0f} ms; nodes "
              f"median {r['expanded_median']:.0f}, worst {r['expanded_max']}; mean distance "
              f"from the path {r['track_mean_d']:.3f} m; plans ending in a "
              f"dead end {r['dead_ends']} of {r['replans']} ({r['not_viable']} with no other)",
              flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps({"info": info, "results": results}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

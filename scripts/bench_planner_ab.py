"""The planner before and after a change, in one process, interleaved: each shipped scene's whole
course planned with the code of a git revision (``--before``) and with this tree's, alternately,
so both see the same load on a shared machine.  Node counts are exact; walls and CPU times
(``time.process_time``: the honest figure on a shared machine) are the minimum of ``--repeat``
runs.  Every run starts cold (the fall table and reach bound caches emptied), as a ``follow``
command does; CPU per course second is the planning's CPU time over the course's duration.
``--cases every_scene``: every shipped scene at N = 12, q = 7.

Usage: python scripts/bench_planner_ab.py --before 8b11d74 [--repeat 2] [--cases every_scene]
       [--json out.json]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

CASES = {"slalom_trees": [("slalom", 12, 7), ("tree_skiing", 10, 5), ("tree_skiing", 12, 5),
                    ("cyclist_corner", 10, 5), ("potholes", 10, 5)],
         "every_scene": [(p.stem, 12, 7) for p in sorted((ROOT / "scenes").glob("*.json"))]}


def import_revision(rev: str, where: Path):
    """The ``core.course.scene`` module of ``blender_turning`` at ``rev``, as package ``bt_before``
    (the core imports itself relatively, so a renamed copy is a separate module tree)."""
    tar = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "blender_turning"],
                         check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=tar, check=True)
    (where / "blender_turning").rename(where / "bt_before")
    sys.path.insert(0, str(where))
    import bt_before.core.course.scene as before
    return before


def cold(module):
    """Empty the planner's per-process table caches of ``module``'s package tree."""
    for name in ("fall_table", "reach"):
        part = sys.modules.get(module.__name__.rsplit(".", 1)[0] + ".planner." + name)
        if part is not None:
            part._CACHE.clear()


def run(module, name, N, q):
    try:
        scene = module.load_scene(ROOT / "scenes" / f"{name}.json").with_settings(n_stages=N,
                                                                                  q=q)
    except (ValueError, KeyError, TypeError) as e:    # a scene this revision cannot read
        return {"error": str(e).splitlines()[0]}
    cold(module)
    clock, cpu = time.perf_counter(), time.process_time()
    result = scene.run()
    cpu = time.process_time() - cpu
    wall = time.perf_counter() - clock
    tr = result.trajectory
    d = scene.problem().distance(np.column_stack([tr.x, tr.y]))
    return {"wall_s": wall, "cpu_s": cpu, "course_s": float(tr.duration),
            "nodes": sum(r.stats.expanded for r in result.replans),
            "replans": len(result.replans), "mean_d": float(np.mean(d)),
            "x_end": float(tr.x[-1]),
            "dead_ends": sum(getattr(r, "dead_end", False) for r in result.replans)}


def describe(r) -> str:
    if "error" in r:
        return f"(cannot run: {r['error']})"
    return (f"nodes {r['nodes']}, CPU {r['cpu_s']:.2f} s (max {r['cpu_max_s']:.2f}) for "
            f"{r['course_s']:.1f} s = {r['cpu_per_course_s']:.3f} CPU-s per course s, wall "
            f"{r['wall_s']:.2f} s, mean distance {r['mean_d']:.3f} m, x_end {r['x_end']!r}, "
            f"dead ends {r['dead_ends']}/{r['replans']}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", required=True, help="git revision to compare with")
    ap.add_argument("--repeat", type=int, default=2, help="runs of each (walls: the minimum)")
    ap.add_argument("--cases", choices=sorted(CASES), default="slalom_trees",
                    help="which scenes and settings (default: the slalom and tree scenes)")
    ap.add_argument("--json", help="write the results here")
    args = ap.parse_args(argv)
    import blender_turning.core.course.scene as after
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        before = import_revision(args.before, Path(tmp))
        for name, N, q in CASES[args.cases]:
            runs = {"before": [], "after": []}
            for _ in range(args.repeat):
                runs["before"].append(run(before, name, N, q))
                runs["after"].append(run(after, name, N, q))
            row = {"scene": name, "N": N, "q": q}
            for k, rs in runs.items():
                row[k] = rs[0] if "error" in rs[0] else {
                    **rs[0], "wall_s": min(r["wall_s"] for r in rs),
                    "wall_max_s": max(r["wall_s"] for r in rs),
                    "cpu_s": min(r["cpu_s"] for r in rs), "cpu_max_s": max(r["cpu_s"] for r in rs),
                    "cpu_per_course_s": min(r["cpu_s"] for r in rs) / rs[0]["course_s"]}
            print(f"{name} N={N} q={q}: {describe(row['before'])} -> {describe(row['after'])}",
                  flush=True)
            out.append(row)
    if args.json:
        Path(args.json).write_text(json.dumps({"before": args.before, "results": out}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The planner before and after a change, in one process, interleaved: each shipped scene's whole
course planned with the code of a git revision (``--before``) and with this tree's, alternately,
so both see the same load on a shared machine.  Node counts are exact; walls are the minimum of
``--repeat`` runs.

Usage: python scripts/bench_planner_ab.py --before 8b11d74 [--repeat 2] [--json out.json]
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

CASES = [("slalom", 12, 7), ("tree_skiing", 10, 5), ("tree_skiing", 12, 5),
         ("cyclist_corner", 10, 5), ("potholes", 10, 5)]


def import_revision(rev: str, where: Path):
    """The ``core.scene`` module of ``blender_turning`` at ``rev``, as package ``bt_before``
    (the core imports itself relatively, so a renamed copy is a separate module tree)."""
    tar = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "blender_turning"],
                         check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=tar, check=True)
    (where / "blender_turning").rename(where / "bt_before")
    sys.path.insert(0, str(where))
    import bt_before.core.scene as before
    return before


def run(module, name, N, q):
    scene = module.load_scene(ROOT / "scenes" / f"{name}.json").with_settings(n_stages=N, q=q)
    clock = time.perf_counter()
    result = scene.run()
    wall = time.perf_counter() - clock
    tr = result.trajectory
    d = scene.problem().distance(np.column_stack([tr.x, tr.y]))
    return {"wall_s": wall, "nodes": sum(r.stats.expanded for r in result.replans),
            "replans": len(result.replans), "mean_d": float(np.mean(d)),
            "dead_ends": sum(getattr(r, "dead_end", False) for r in result.replans)}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", required=True, help="git revision to compare with")
    ap.add_argument("--repeat", type=int, default=2, help="runs of each (walls: the minimum)")
    ap.add_argument("--json", help="write the results here")
    args = ap.parse_args(argv)
    import blender_turning.core.scene as after
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        before = import_revision(args.before, Path(tmp))
        for name, N, q in CASES:
            runs = {"before": [], "after": []}
            for _ in range(args.repeat):
                runs["before"].append(run(before, name, N, q))
                runs["after"].append(run(after, name, N, q))
            row = {"scene": name, "N": N, "q": q}
            for k, rs in runs.items():
                row[k] = {**rs[0], "wall_s": min(r["wall_s"] for r in rs),
                          "wall_max_s": max(r["wall_s"] for r in rs)}
            b, a = row["before"], row["after"]
            print(f"{name} N={N} q={q}: nodes {b['nodes']} -> {a['nodes']}; wall (min of "
                  f"{args.repeat}) {b['wall_s']:.2f} -> {a['wall_s']:.2f} s; mean distance "
                  f"{b['mean_d']:.3f} -> {a['mean_d']:.3f} m; dead ends {a['dead_ends']} of "
                  f"{a['replans']} after", flush=True)
            out.append(row)
    if args.json:
        Path(args.json).write_text(json.dumps({"before": args.before, "results": out}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

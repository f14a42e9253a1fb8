"""Benchmark of priority planning: what planning around the figures planned before
costs against planning every figure alone.  Prints a Markdown table.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_crowd_priority.py [--repeat 3]

- ``crossing``: scenes/crowds/crossing.json, two lines of four skiers crossing (one group: every
  figure sees the one it meets), with its ``priority`` and without it (the baseline: the same
  figures planned alone, as before priority planning existed), in this process.  CPU seconds
  (``time.process_time``, of the planning tasks and of this process: the machine is shared,
  CPU time says what the work cost) and the closest approach (foot-CM segments sampled every
  0.01 s).
- ``two crossings``: the same crossing twice, 200 m apart (two independent groups): priority
  planning on 1 and on 2 local worker processes (wall time; the groups fan out).
Interleaved, best of ``--repeat`` (by wall time).
"""
from __future__ import annotations

import argparse
import copy
import datetime
import json
import os
import platform
import time
from pathlib import Path

from blender_turning.core.course.moving import MovingBodies, closest_approach
from blender_turning.crowd import crowd_from_dict, run_crowd

ROOT = Path(__file__).resolve().parent.parent


def crossing(priority: bool, twice: bool = False) -> dict:
    doc = json.loads((ROOT / "scenes" / "crowds" / "crossing.json").read_text())
    if twice:                              # the same crossing again, 200 m to the east
        more = copy.deepcopy(doc["figures"])
        for f in more:
            f["name"] = "far-" + f["name"]
            pts = f["follow"]["path"]["polyline"]
            f["follow"]["path"]["polyline"] = [[x + 200.0, y] for x, y in pts]
        forms = copy.deepcopy(doc["formations"])
        for f in forms:
            f["leader"] = "far-" + f["leader"]
            f["name"] = f["leader"] + "-"
        doc["figures"] += more
        doc["formations"] += forms
        doc["priority"] = "all"
    if not priority:
        doc.pop("priority")
    return doc


def measure(doc, workers=1):
    crowd = crowd_from_dict(doc, ROOT / "scenes" / "crowds")
    cpu, wall = time.process_time(), time.perf_counter()
    res = run_crowd(crowd, workers=workers)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    assert all(r.status == "ok" for r in res.figures), [r.message for r in res.failed]
    tracks = [(f.name, r.trajectory, f.figure.body.l) for f, r in zip(crowd.figures,
                                                                    res.figures)]
    near = min(d for d, _, _ in closest_approach(MovingBodies.from_tracks(tracks, 0.01))
               .values())
    groups = {r.plan["priority"]["group"]: r.cpu_time for r in res.figures
              if "priority" in r.plan}          # a group's figures share its task's CPU time
    tasks = sum(groups.values()) + sum(r.cpu_time for r in res.figures
                                       if "priority" not in r.plan)
    return cpu, wall, near, len(groups), len(crowd.figures), tasks


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    runs = {"crossing, alone (baseline)": (crossing(False), 1),
            "crossing, priority": (crossing(True), 1),
            "two crossings, priority, 1 worker": (crossing(True, True), 1),
            "two crossings, priority, 2 workers": (crossing(True, True), 2)}
    best = {k: None for k in runs}
    for _ in range(args.repeat):                       # interleaved
        for k, (doc, workers) in runs.items():
            m = measure(doc, workers)
            if best[k] is None or m[1] < best[k][1]:
                best[k] = m
    print(f"{datetime.date.today()}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}, "
          f"best of {args.repeat}\n")
    print("| run | figures | groups | CPU s (tasks) | CPU s (this process) | wall s | "
          "closest approach m |")
    print("|---|---|---|---|---|---|---|")
    for k, (cpu, wall, near, groups, n, tasks) in best.items():
        print(f"| {k} | {n} | {groups or '-'} | {tasks:.2f} | {cpu:.2f} | {wall:.2f} | "
              f"{near:.3f} |")


if __name__ == "__main__":
    main()

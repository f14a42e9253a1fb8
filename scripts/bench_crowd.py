"""Benchmark of crowds (issue 11).  Prints a Markdown table.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_crowd.py [--skip-dask] [--course 8]

- 8 path-following figures (the four shipped scenes at their own planner settings, each a
  leader and a follower 1 s behind, the first ``--course`` seconds of each):
  wall time on 1 local worker (this process) and on 2 worker processes, and on a Dask
  LocalCluster of 2 worker processes; also the CPU seconds the tasks used (the machine may be
  shared: CPU time says what the work cost, wall time what it took).
- A crowd of 100 figures on the parametric controller (one batch: a leader and 99 followers,
  period within 5 %), 60 s at 24 fps: simulate, then resample at 24 fps and map every figure
  onto the skier rig (``blender_turning.mapping.map_trajectory``).
Baseline in the same run: the 8 figures on one worker; the 100 figures one by one (10 of them,
scaled) for the batch.
"""
from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import time
from pathlib import Path

from blender_turning.crowd import Crowd, CrowdFigure, Turns, crowd_from_dict, follow_leader
from blender_turning.crowd import run_crowd
from blender_turning.core import preset
from blender_turning.mapping import map_trajectory

ROOT = Path(__file__).resolve().parent.parent


def path_crowd(course: float):
    """The four shipped scenes, each a leader and one follower 1 s behind on its track."""
    scenes = ("slalom", "tree_skiing", "cyclist_corner", "potholes")
    return crowd_from_dict({"name": "eight", "duration": course, "figures": [
        {"name": name, "follow": {"scene": f"{name}.json", "duration": course}}
        for name in scenes],
        "formations": [{"type": "follow_leader", "leader": name, "count": 1, "gap_s": 1.0}
                       for name in scenes]}, ROOT / "scenes")


def timed(fn):
    wall, cpu = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - wall, time.process_time() - cpu


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-dask", action="store_true")
    ap.add_argument("--course", type=float, default=8.0, help="s of the slalom planned")
    args = ap.parse_args()
    now = datetime.datetime.now(datetime.timezone.utc)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f} before; {now:%Y-%m-%d %H:%M} UTC")
    crowd = path_crowd(args.course)
    rows = []
    one, w1, _ = timed(lambda: run_crowd(crowd))
    task_cpu = sum(r.cpu_time for r in one.figures)
    assert not one.failed, [r.message for r in one.failed]
    rows.append(("8 path figures, 1 worker (baseline)", w1, task_cpu, 1.0))
    two, w2, _ = timed(lambda: run_crowd(crowd, workers=2))
    rows.append(("8 path figures, 2 local workers", w2, sum(r.cpu_time for r in two.figures),
                 w1 / w2))
    if not args.skip_dask:
        from dask.distributed import LocalCluster
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster:
            run_crowd(crowd, scheduler=cluster.scheduler_address)      # workers warm
            dk, wd, _ = timed(lambda: run_crowd(crowd, scheduler=cluster.scheduler_address))
        rows.append(("8 path figures, Dask LocalCluster 2 workers", wd,
                     sum(r.cpu_time for r in dk.figures), w1 / wd))
    print(f"load average {os.getloadavg()[0]:.1f} after the path figures")
    print(f"\ncourse {args.course:g} s per figure ({8 * args.course:g} figure-seconds)\n")
    print("| run | wall s | task CPU s | task CPU / wall | speed-up vs 1 worker |\n"
          "|---|---|---|---|---|")
    for name, wall, cpu, sp in rows:
        print(f"| {name} | {wall:.2f} | {cpu:.2f} | {cpu / wall:.2f} | {sp:.2f}x |")

    fig = preset("skier")
    lead = CrowdFigure("lead", fig, Turns(2.0, math.radians(20), 0.0))
    big = Crowd("100", (lead,) + follow_leader(lead, 99, 0.1, lateral=[-2, 2], seed=1,
                                              period_jitter=0.05), duration=60.0)
    res, ws, cs = timed(lambda: run_crowd(big))
    assert not res.failed
    solo = Crowd("10", big.figures[:10], 60.0)
    _, w10, c10 = timed(lambda: [run_crowd(Crowd("1", (f,), 60.0)) for f in solo.figures])
    poses, wm, cm = timed(lambda: [map_trajectory("skier", r.trajectory, fps=24)
                                   for r in res.figures])
    frames = sum(len(p.frames) for p in poses)
    print(f"\n100 parametric figures, 60 s ({int(60 / big.dt)} steps each), "
          f"{frames} frames mapped\n")
    print("| step | wall s | CPU s |\n|---|---|---|")
    print(f"| simulate, one batch of 100 | {ws:.2f} | {cs:.2f} |")
    print(f"| simulate one by one (baseline: 10 figures, x 10) | {10 * w10:.2f} | {10 * c10:.2f} |")
    print(f"| resample at 24 fps + map onto the skier rig, 100 figures | {wm:.2f} | {cm:.2f} |")
    print(f"| simulate + map | {ws + wm:.2f} | {cs + cm:.2f} |")


if __name__ == "__main__":
    main()

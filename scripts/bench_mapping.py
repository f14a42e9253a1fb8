"""Benchmark of the Section 7 mapping alone (no bpy).  Prints a Markdown table.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_mapping.py [--against DIR] [--repeat 3]

For each built-in sport (skier, snowboarder, telemark, cyclist): a 60 s run on the parametric
controller (its preset, a 2 s turn, 20 deg lean) resampled at 24 fps (1,441 frames), mapped
whole (``map_trajectory``) and as Live Preview's drag step maps it: a window of 73 frames in
the middle of the run (the run's edge-tilt fit passed in, as ``blender/jobs/live.py`` does).
The carver's and the slalom racer's 20 s slaloms (``PRESETS``), mapped whole.
Times are the least over the calls of one process, wall and CPU (the process's CPU: OpenBLAS
threads woken by LAPACK calls show as CPU above wall).  And the crowd's mapping
(``scripts/bench_crowd.py``'s 100 skiers, a leader and followers 0.1 s apart, 60 s): the first
``--crowd`` of them resampled at 24 fps and mapped once per round, with the CPU ticks of the
process's other threads (OpenBLAS's, woken by a large BLAS call: they spin, and on an idle
machine burn a second core).

``--against DIR`` times another tree's package (e.g. ``git archive f2c78aa | tar -x -C DIR``;
trees from 2026-11-28 on)
on the same trajectories (simulated once with this tree, handed over as columns): each tree in
a fresh process, the trees interleaved, ``--repeat`` rounds, the least CPU kept.
"""
from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SPORTS = ("skier", "snowboarder", "telemark", "cyclist")
#: Presets whose mapping keeps the centre of mass on the lean (docs/racing.md): a 20 s slalom
#: from ``slalom_start``, (turn period s, lean asked deg), 481 frames at 24 fps.
PRESETS = {"carver": (2.5, 70.0), "slalom_racer": (2.0, 60.0)}
WINDOW = 73                 # Live Preview's drag step: 12 frames either side + 24 of context
CALLS = {"window": 40, "run": 5}
CROWD = "crowd: resample at 24 fps + map {} skiers"


def make_runs(path: Path, crowd: int) -> None:
    """Simulate each sport's 60 s run with this tree and write its 24 fps samples as JSON, and
    the first ``crowd`` figures of bench_crowd's 100 as simulated (the mapping resamples)."""
    from blender_turning.core import PhaseEllipse, preset, simulate
    from blender_turning.crowd import Crowd, CrowdFigure, Turns, follow_leader, run_crowd
    fig = preset("skier")
    lead = CrowdFigure("lead", fig, Turns(2.0, math.radians(20), 0.0))
    big = Crowd("100", (lead,) + follow_leader(lead, 99, 0.1, lateral=[-2, 2], seed=1,
                                              period_jitter=0.05), duration=60.0)
    res = run_crowd(Crowd("part", big.figures[:crowd], 60.0))
    runs = {"crowd": [{"meta": r.trajectory.meta, "data": {c: v.tolist() for c, v in
                                                            r.trajectory.columns().items()}}
                      for r in res.figures]}
    for sport in SPORTS:
        fig = preset(sport)
        traj = simulate(fig, PhaseEllipse(fig.body, omega0=math.pi, theta_max=math.radians(20),
                                          heading=0.0), duration=60.0).resample(24)
        runs[sport] = {"meta": traj.meta, "data": {c: v.tolist() for c, v in
                                                   traj.columns().items()}}
    from blender_turning.core import slalom_start
    for name, (period, lean) in PRESETS.items():
        fig = preset(name)
        ctl = PhaseEllipse(fig.body, 2 * math.pi / period, math.radians(lean), 0.0,
                           limits=fig.limits)
        w, tm = ctl.target(0.0)
        traj = simulate(fig, ctl, 20.0, state0=slalom_start(fig.body, w, tm)).resample(24)
        runs[name] = {"meta": traj.meta, "data": {c: v.tolist() for c, v in
                                                  traj.columns().items()}}
    path.write_text(json.dumps(runs))


def timed(fn, calls):
    fn()                                            # warm: the rig's file, caches
    wall, cpu = [], []
    for _ in range(calls):
        w, c = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - w)
        cpu.append(time.process_time() - c)
    return 1e3 * min(wall), 1e3 * min(cpu)


def one_tree(runs_path: str, poses_path: str) -> None:
    """In a fresh process with the tree's package first on sys.path: time every case, print
    JSON ``{case: [wall ms, cpu ms]}``; write every case's poses to ``poses_path`` (npz)."""
    from dataclasses import replace

    import numpy as np

    from blender_turning.core import Trajectory
    from blender_turning.mapping import MAPPINGS, map_trajectory
    try:
        from blender_turning.core.physics.trajectory import COLUMNS
        from blender_turning.mapping.sports.snow import tilt_gain
    except ImportError:                         # a tree from before core/ and mapping/ had folders
        from blender_turning.core.trajectory import COLUMNS
        from blender_turning.mapping.snow import tilt_gain

    out, poses = {}, {}

    def keep(case, track):
        poses[f"{case}/location"], poses[f"{case}/rotation"] = track.location, track.rotation
        for bone, ch in track.bones.items():
            for name in ("location", "rotation"):
                if getattr(ch, name) is not None:
                    poses[f"{case}/{bone}/{name}"] = getattr(ch, name)
        return track

    runs = json.loads(Path(runs_path).read_text())
    crowd = [Trajectory.from_columns({c: doc["data"][c] for c in COLUMNS}, doc["meta"])
             for doc in runs.pop("crowd")]
    for name, doc in runs.items():
        traj = Trajectory.from_columns({c: doc["data"][c] for c in COLUMNS}, doc["meta"])
        if name in PRESETS:                     # the whole slalom only
            from blender_turning.core.equipment import sport_of
            sport = sport_of(name)
            case = f"{name} slalom, {PRESETS[name][1]:.0f} deg ({len(traj)} frames)"
            keep(case, map_trajectory(sport, traj))
            out[case] = timed(lambda: map_trajectory(sport, traj), CALLS["run"])
            continue
        sport = name
        n = len(traj)
        lo = n // 2 - WINDOW // 2
        part = Trajectory(traj.data[:, lo:lo + WINDOW], {**traj.meta, "s_start": float(traj.s[0])})
        options = MAPPINGS[sport].Options()
        if getattr(options, "tilt_gain", 0.0) is None:
            options = replace(options, tilt_gain=tilt_gain(traj, None))
        for case, call, calls in (
                (f"{sport}, {WINDOW} frames",
                 lambda: map_trajectory(sport, part, options, frame_start=lo + 1), "window"),
                (f"{sport}, 60 s ({n} frames)", lambda: map_trajectory(sport, traj), "run")):
            keep(case, call())
            out[case] = timed(call, CALLS[calls])
    ticks = other_threads_ticks()
    out[CROWD.format(len(crowd))] = timed(
        lambda: [map_trajectory("skier", t, fps=24) for t in crowd], 1)
    out["crowd: other threads' CPU ticks"] = (other_threads_ticks() - ticks, 0.0)
    np.savez(poses_path, **poses)
    print(json.dumps(out))


def other_threads_ticks() -> int:
    """CPU clock ticks (user + system) of this process's threads but the main one (Linux)."""
    me, ticks = str(os.getpid()), 0
    for t in os.listdir("/proc/self/task"):
        if t != me:
            with open(f"/proc/self/task/{t}/stat") as fh:
                fields = fh.read().rsplit(")", 1)[1].split()
            ticks += int(fields[11]) + int(fields[12])
    return ticks


def run_tree(tree: Path, runs_path: Path, poses_path: Path) -> dict:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    res = subprocess.run([sys.executable, __file__, "--one", str(runs_path), str(poses_path)],
                         cwd=tree, env=env, capture_output=True, text=True, check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def poses_differ(tmp: Path) -> dict:
    """Per case, the largest difference between the two trees' channels (quaternion components
    and locations, m); a channel one tree has and the other not is infinite."""
    import numpy as np
    a, b = np.load(tmp / "baseline.npz"), np.load(tmp / "this.npz")
    out = {}
    for key in set(a.files) | set(b.files):
        case = key.split("/")[0]
        d = (float(np.max(np.abs(a[key] - b[key]))) if key in a.files and key in b.files
             else math.inf)
        out[case] = max(out.get(case, 0.0), d)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--against", type=Path, help="another tree's root (the baseline)")
    ap.add_argument("--repeat", type=int, default=3, help="rounds, interleaved (best kept)")
    ap.add_argument("--crowd", type=int, default=10, help="crowd figures mapped per round")
    ap.add_argument("--one", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        return one_tree(*args.one)
    now = datetime.datetime.now(datetime.timezone.utc)
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f} before; {now:%Y-%m-%d %H:%M} UTC")
    trees = ([("baseline", args.against.resolve())] if args.against else []) + [("this", ROOT)]
    with tempfile.TemporaryDirectory() as tmp:
        runs = Path(tmp) / "runs.json"
        make_runs(runs, args.crowd)
        best = {name: {} for name, _ in trees}
        for r in range(args.repeat):
            for name, tree in (trees if r % 2 == 0 else trees[::-1]):
                for case, (wall, cpu) in run_tree(tree, runs, Path(tmp) / name).items():
                    old = best[name].get(case)
                    if case.endswith("ticks"):                  # summed over the rounds
                        best[name][case] = (wall + (old or (0, 0))[0], 0.0)
                    elif old is None or cpu < old[1]:
                        best[name][case] = (wall, cpu)
        diff = poses_differ(Path(tmp)) if len(trees) == 2 else {}
    print(f"load average {os.getloadavg()[0]:.1f} after; least ms per call, wall (CPU), "
          f"best of {args.repeat} rounds\n")
    names = [name for name, _ in trees]
    two = len(trees) == 2
    print("| case | " + " | ".join(names) + (" | CPU ratio | largest pose difference |"
                                              if two else " |"))
    print("|---" * (len(names) + 1 + 2 * two) + "|")
    for case in best["this"]:
        if case.endswith("ticks"):
            print(f"| {case}, all rounds | " + " | ".join(str(best[n][case][0]) for n in names)
                  + (" | | |" if two else " |"))
            continue
        cells = [f"{best[n][case][0]:.1f} ({best[n][case][1]:.1f})" for n in names]
        ratio = ""
        if two:
            ratio = (f" {best['baseline'][case][1] / best['this'][case][1]:.2f}x | "
                     + (f"{diff[case]:.1e} |" if case in diff else "- |"))
        print(f"| {case} | " + " | ".join(cells) + " |" + ratio)


if __name__ == "__main__":
    main()

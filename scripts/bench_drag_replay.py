"""Benchmark: the core's work in Live Preview's drag steps on a Ground mesh, replayed without bpy.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_live.py --capture calls.pkl --frame end
    PYTHONPATH=$PWD .venv/bin/python scripts/bench_drag_replay.py calls.pkl count      # stages
    PYTHONPATH=$PWD .venv/bin/python scripts/bench_drag_replay.py calls.pkl callgrind
    PYTHONPATH=$PWD .venv/bin/python scripts/bench_drag_replay.py calls.pkl time
    PYTHONPATH=$PWD .venv/bin/python scripts/bench_drag_replay.py calls.pkl hash > now.txt

``bench_live.py --capture`` records the ``simulate(...)`` calls of a case's drag steps (the
cyclist on the Ground mesh over 60 s by default, one drag step at each of ``--leans``): the
figure, the controller's constant inputs, the mesh's height field (all of its samples) and the
run's arguments.  Here each call is run again as the drag step runs it (a fresh
:class:`PhaseEllipse`, inside :func:`nearby_tables` at the drag step's tolerance), after one
pass that makes the cells' polynomials and the feasibility tables (a drag finds most of them
made):

- ``count``: RK4 stages and ground reads (``slopes_one``) per run;
- ``callgrind``: the instructions of one pass per run, by ``valgrind --tool=callgrind`` (this
  script under it twice, the warm pass alone and the warm pass and one more: the difference),
  deterministic where milliseconds on a shared machine are not;
- ``time``: CPU ms per run, the least of ``--repeat`` passes;
- ``hash``: a digest of every column of every row of each call's preview (its ``stride``) and
  release (``stride = 1``) run, and of runs on the test suite's grounds (``CASES``: the rolls,
  a mogul slope with and without a course, a plane, a 12 deg slope, flat ground with friction,
  a straight run, a target speed with skidding), each at both strides where a preview may
  run: two trees whose digests agree step bit for bit alike;
- ``error``: how far a preview is from its release, at 24 fps over the run: the foot's largest
  distance (cm) and the heading's and the lean's largest differences (deg), for each captured
  call (at its stride) and the slope, mogul and rolls cases at strides 3 and 5 and at Live
  Preview's for their turns (:func:`...terrain_sim.preview_stride`), with the release at a
  thousandth of a degree more lean, for scale (a run that sensitive parts from itself).
"""
from __future__ import annotations

import argparse
import hashlib
import math
import os
import pickle
import re
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start  # noqa: E402
from blender_turning.core.controllers import Straight  # noqa: E402
from blender_turning.core.controllers.feasible import nearby_tables  # noqa: E402
from blender_turning.core.errors import RunEnded  # noqa: E402
from blender_turning.core.ground.terrain import FLAT, Plane  # noqa: E402
from blender_turning.core.ground.terrain_gen import ski_slope  # noqa: E402
from blender_turning.core.physics import terrain_one_figure  # noqa: E402
from blender_turning.core.physics.model import RESISTANCE  # noqa: E402
from blender_turning.core.physics.skidding import Skidding  # noqa: E402
from blender_turning.core.physics.terrain_sim import preview_stride  # noqa: E402


def run(call, stride=None, whole=False):
    """One captured call, as the drag step runs it (``stride``: another longest step;
    ``whole``: every sample, not the window's only)."""
    fig, dt = call["figure"], call["dt"]
    ctl = PhaseEllipse(fig.body, call["omega0"], call["theta_max"], call["heading"],
                       limits=fig.limits)
    kwargs = dict(call["kwargs"], stride=call["kwargs"]["stride"] if stride is None else stride)
    if whole:
        kwargs["keep"] = 0.0
    with nearby_tables(call["nearby"]):
        return _traj(lambda: simulate(fig, ctl, call["duration"], dt, **kwargs))


def _traj(fn):
    """``fn()``'s trajectory, or the trajectory so far of a run that ended early."""
    try:
        return fn()
    except RunEnded as e:
        return e.trajectory


def _digest(traj) -> str:
    return f"{len(traj.t)} rows {hashlib.sha256(traj.data.tobytes()).hexdigest()[:16]}"


def cases():
    """``name -> fn(stride) -> Trajectory``: runs on the grounds the tests use."""
    fall = -math.pi / 2
    rolls = ski_slope(length=200.0, width=200.0, slope_deg=0.0, cell=1.0)
    moguls = ski_slope(length=400.0, width=200.0, cell=2.0)
    slope12 = ski_slope(length=800.0, width=300.0, slope_deg=12.0, cell=1.0, moguls=False)

    def make(sport, V, period, lean_deg, heading, ground, start, duration, **kw):
        fig = replace(preset(sport), body=replace(preset(sport).body, V_cm=V))
        w = 2 * math.pi / period

        def go(stride, more_deg=0.0):
            tm = math.radians(lean_deg + more_deg)
            ctl = PhaseEllipse(fig.body, w, tm, heading, limits=fig.limits)
            s0 = start if len(start) == 6 else (*slalom_start(fig.body, w, tm, *start), V)
            return _traj(lambda: simulate(fig, ctl, duration, 0.02, s0, ground=ground,
                                          resistance=RESISTANCE[sport], stride=stride, **kw))
        go.period, go.ground = period, ground
        return go

    cyclist = 2 * math.pi / 3.0 * math.radians(4.0)
    return {
        "rolls cyclist 3 m/s": make("cyclist", 3.0, 3.0, 4.0, 0.0, rolls,
                                    (-95.0, 10.0, 0.0, 0.0, cyclist, 3.0), 30.0),
        "mogul slope skier": make("skier", 10.0, 2.0, 25.0, fall, moguls, (fall, -40.0, 150.0),
                                  12.0),
        "mogul slope, no course": make("skier", 10.0, 2.0, 25.0, None, moguls,
                                       (fall, -40.0, 150.0), 12.0),
        "plane traverse": make("skier", 10.0, 2.0, 25.0, fall + 1.0,
                               Plane(math.radians(20), fall), (fall + 1.0, 0.0, 0.0), 12.0),
        "12 deg skier 8 m/s": make("skier", 8.0, 3.0, 15.0, fall, slope12, (fall, 20.0, 390.0),
                                   30.0),
        "12 deg snowboarder": make("snowboarder", 12.0, 2.0, 30.0, fall, slope12,
                                   (fall, 20.0, 390.0), 30.0),
        "flat, friction": make("skier", 10.0, 2.0, 25.0, None, FLAT, (0.0, 0.0, 0.0), 20.0),
        "straight traverse": lambda stride: _traj(lambda: simulate(
            preset("skier"), Straight(preset("skier").body), 2.0, 0.02,
            (0.0, 0.0, fall + 1.0, 0.0, 0.0, 8.0), ground=Plane(math.radians(20), fall),
            resistance=RESISTANCE["skier"], stride=stride)),
        "target speed, skidding": make("skier", 12.0, 2.0, 30.0, fall, slope12,
                                       (fall, 20.0, 390.0), 20.0, target_speed=10.0,
                                       skidding=Skidding("skid", corridor=5.0)),
    }


def off(a, b, ground):
    """``(foot cm, heading deg, lean deg)``: the largest differences of ``a`` from ``b`` at
    24 fps over the frames both cover."""
    fa, fb = (t.resample(24, start=0.0, ground=ground) for t in (a, b))
    n = min(len(fa), len(fb))
    return (100 * np.hypot(fa.x[:n] - fb.x[:n], fa.y[:n] - fb.y[:n]).max(),
            math.degrees(np.abs(fa.theta_dir[:n] - fb.theta_dir[:n]).max()),
            math.degrees(np.abs(fa.theta_v[:n] - fb.theta_v[:n]).max()))


def errors(calls):
    """The ``error`` table's lines."""
    def cell(v):
        return "{:.1f} cm / {:.2f} / {:.2f} deg".format(*v)
    for call in calls:
        ground, release = call["kwargs"]["ground"], run(call, 1, True)
        yield (f"captured, lean {math.degrees(call['theta_max']):.2f} deg, stride "
               f"{call['kwargs']['stride']}: {cell(off(run(call, whole=True), release, ground))}")
    for name, go in cases().items():
        if not hasattr(go, "period") or go.ground is FLAT or "target" in name:
            continue
        live = preview_stride(go.period, 0.02)
        release = go(1)
        parts = [f"stride {k}{' (live)' if k == live else ''} "
                 f"{cell(off(go(k), release, go.ground))}" for k in sorted({3, 5, live})]
        parts.append(f"release at +0.001 deg {off(go(1, 0.001), release, go.ground)[0]:.1f} cm")
        yield f"{name} ({go.period:g} s turns): " + "; ".join(parts)


def count(calls):
    """Mean RK4 stages and ground reads per call."""
    tally = {"stages": 0, "reads": 0}
    init = terrain_one_figure.TerrainStage.__init__

    def counted(self, *a, **k):
        init(self, *a, **k)
        stage = self.stage

        def counted_stage(*a):
            tally["stages"] += 1
            return stage(*a)
        self.stage = counted_stage

    terrain_one_figure.TerrainStage.__init__ = counted
    try:
        for call in calls:
            field = call["kwargs"]["ground"]
            slopes = field.slopes_one

            def counted_read(x, y):
                tally["reads"] += 1
                return slopes(x, y)
            field.slopes_one = counted_read             # before the stage binds it
            try:
                run(call)
            finally:
                field.slopes_one = slopes
    finally:
        terrain_one_figure.TerrainStage.__init__ = init
    return {k: v / len(calls) for k, v in tally.items()}


def callgrind(path, python=sys.executable):
    """Instructions (valgrind's ``Collected``) of one pass over the calls, per call."""
    got = {}
    for passes in (0, 1):
        out = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                              python, __file__, path, "passes", "--repeat", str(passes)],
                             capture_output=True, text=True, check=True, env=os.environ).stderr
        got[passes] = int(re.search(r"Collected : (\d+)", out).group(1))
    return got[1] - got[0]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("calls", help="the pickle of bench_live.py --capture")
    ap.add_argument("what", choices=("count", "callgrind", "time", "hash", "error", "passes"))
    ap.add_argument("--repeat", type=int, default=5, help="passes timed (passes: run)")
    args = ap.parse_args(argv)
    with open(args.calls, "rb") as f:
        calls = pickle.load(f)
    if args.what == "callgrind":
        print(f"callgrind: {callgrind(args.calls) / len(calls) / 1e6:.1f} M instructions per "
              f"run ({len(calls)} runs, the warm pass subtracted)")
        return
    for call in calls:                  # warm: the cells' polynomials, the tables
        run(call)
    if args.what == "passes":
        for _ in range(args.repeat):
            for call in calls:
                run(call)
    elif args.what == "error":
        print("\n".join(errors(calls)))
    elif args.what == "count":
        print(" ".join(f"{k} {v:,.0f}" for k, v in count(calls).items()), "per run")
    elif args.what == "time":
        spent = []
        for _ in range(args.repeat):
            c = time.process_time()
            for call in calls:
                run(call)
            spent.append((time.process_time() - c) / len(calls))
        print(f"CPU ms per run, least of {args.repeat}: {1000 * min(spent):.1f} "
              f"(all: {' '.join(f'{1000 * s:.1f}' for s in spent)})")
    else:
        for call in calls:
            print(f"captured, lean {math.degrees(call['theta_max']):.2f} deg: preview "
                  f"{_digest(run(call, whole=True))}, release {_digest(run(call, 1, True))}")
        for name, go in cases().items():
            strides = (1,) if "target" in name else (1, 3, 5)
            print(f"{name}: " + ", ".join(f"stride {s} {_digest(go(s))}" for s in strides))


if __name__ == "__main__":
    main()

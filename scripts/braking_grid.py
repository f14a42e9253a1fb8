"""Speed control by turning (docs/TERRAIN.md Section 6) over a grid of runs: sports, slopes,
downhill directions, target speeds, on a plane and on the demo's ski slope; each with the sport's
friction and drag, 60 s of the 2 s / 23 deg slalom along the fall line.  Prints one line a run:
how it ended (ok, fell, left, stopped, at what time), the mean speed over the last 30 s and the
largest speed.

    PYTHONPATH=$PWD .venv/bin/python scripts/braking_grid.py [--quick] [--jobs 2]
"""
import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start
from blender_turning.core.errors import TurningError
from blender_turning.core.registry import SPORTS
from blender_turning.core.ground.terrain import Plane
from blender_turning.core.physics.model import RESISTANCE
from blender_turning.core.ground.terrain_gen import ski_slope

W, TM = math.pi, math.radians(23)
_SLOPE = {}


def ground_of(kind, slope_deg, downhill_deg):
    if kind == "plane":
        return Plane(math.radians(slope_deg), math.radians(downhill_deg))
    key = slope_deg
    if key not in _SLOPE:
        _SLOPE[key] = ski_slope(length=1600.0, width=200.0, slope_deg=slope_deg, cell=2.0)
    return _SLOPE[key]


def one(args):
    sport, kind, slope_deg, downhill_deg, target, duration = args
    fig = preset(sport)
    body = fig.body
    ground = ground_of(kind, slope_deg, downhill_deg)
    fall = math.radians(downhill_deg if kind == "plane" else -90.0)
    x0, y0 = (0.0, 0.0) if kind == "plane" else (-40.0, 790.0)
    ctl = PhaseEllipse(body, W, TM, heading=fall)
    s0 = slalom_start(body, W, TM, fall, x0, y0)
    end, t_end = "ok", duration
    try:
        traj = simulate(fig, ctl, duration, 0.02, s0, ground=ground,
                        resistance=RESISTANCE[sport], target_speed=target)
    except TurningError as e:
        traj = e.trajectory
        end, t_end = type(e).__name__, float(traj.t[-1])
    late = traj.t >= traj.t[-1] - 30.0
    return (sport, kind, slope_deg, downhill_deg, target, end, t_end,
            float(traj.V_cm[late].mean()), float(traj.V_cm.max()),
            float(np.abs(traj.x - x0).max()) if kind != "plane" else float("nan"))


def grid(quick):
    sports = tuple(SPORTS)                    # every registered sport
    slopes = (6, 12, 18, 25) if not quick else (12, 18)
    targets = (8.0, 12.0) if not quick else (10.0,)
    for sport in sports:
        for slope in slopes:
            for target in targets:
                for down in ((-90.0, 30.0) if not quick else (-90.0,)):
                    yield sport, "plane", slope, down, target, 60.0
                yield sport, "ski_slope", slope, -90.0, target, 60.0


def main(argv=None):
    p = argparse.ArgumentParser()
    p.add_argument("--quick", action="store_true")
    p.add_argument("--jobs", type=int, default=1)
    p.add_argument("--sport")
    a = p.parse_args(argv)
    cases = [c for c in grid(a.quick) if a.sport is None or c[0] == a.sport]
    print("sport        ground     slope down  target  end          t    mean30  max  |dx|")
    with ProcessPoolExecutor(a.jobs) as ex:
        for r in ex.map(one, cases):
            print("%-12s %-9s %5g %5g %6g  %-10s %5.1f  %6.2f %5.2f %5.1f" % r, flush=True)


if __name__ == "__main__":
    sys.exit(main())

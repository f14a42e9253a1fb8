"""Cost of speed control by turning (core/controllers/braking.py): a 60 s braking run (skier, 18 deg plane,
target 12 m/s) against the same slalom without a target, best of N wall time.  Run it with
PYTHONPATH set to the tree to measure (for a baseline, a copy of main's tree).

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_braking.py [repeat]
"""
import math
import sys

from bench_common import best

from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start
from blender_turning.core.errors import TurningError
from blender_turning.core.ground.terrain import Plane
from blender_turning.core.physics.model import RESISTANCE


def run(target):
    fig = preset("skier")
    w, tm, fall = math.pi, math.radians(23), -math.pi / 2
    try:
        simulate(fig, PhaseEllipse(fig.body, w, tm, heading=fall), 60.0, 0.02,
                 slalom_start(fig.body, w, tm, fall), ground=Plane(math.radians(18), fall),
                 resistance=RESISTANCE["skier"], target_speed=target)
    except TurningError:
        pass


if __name__ == "__main__":
    repeat = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    free, held = best(lambda: run(None), repeat), best(lambda: run(12.0), repeat)
    print(f"free {free * 1e3:.0f} ms, target 12 m/s {held * 1e3:.0f} ms, ratio {held / free:.2f}")

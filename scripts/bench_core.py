"""Benchmark of the physics core (issue 2). Prints a Markdown table; timings are best of N.

    .venv/bin/python scripts/bench_core.py [--repeat 5]

- One figure: 60 s of a 2 s / 23 deg slalom under the phase-ellipse controller with heading
  control, at the default step (the accuracy the tests demand): simulated seconds per wall second;
  also the open-loop slalom of Section 4 (no feedback), for scale.
  Baseline in the same run: the same figure stepped by the numpy backend (a batch of one).
- A batch of 1,000 figures stepped together: figure-steps per second.  Baseline in the same run:
  the 1,000 figures one after another on the scalar backend.
"""
from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import time

import numpy as np

from blender_turning.core import OpenLoop, PhaseEllipse, preset, run
from blender_turning.core.heading_table import heading_table
from blender_turning.core.simulate import DEFAULT_DT


def best(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--batch", type=int, default=1000)
    args = ap.parse_args()
    fig = preset("skier")
    w, tm = 2 * math.pi / 2.0, math.radians(23)
    heading_table(fig.body)                               # built once per body, not timed
    s0 = np.array([0.0, 0.0, 0.0, 0.0, w * tm])

    def one(state):
        return lambda: run(fig.body, fig.limits, PhaseEllipse(fig.body, w, tm, heading=0.0),
                           state, 60.0, DEFAULT_DT)

    t_scalar = best(one(s0), args.repeat)
    t_open = best(lambda: run(fig.body, fig.limits, OpenLoop(fig.body, w, tm), s0, 60.0,
                              DEFAULT_DT), args.repeat)
    t_numpy1 = best(one(s0[:, None]), max(1, args.repeat // 2))
    n = args.batch
    rng = np.random.default_rng(0)
    starts = np.tile(s0[:, None], (1, n))
    starts[3] = rng.uniform(-0.1, 0.1, n)
    dur = 4.0
    steps = int(round(dur / DEFAULT_DT)) + 1
    t_batch = best(lambda: run(fig.body, fig.limits, PhaseEllipse(fig.body, w, tm, heading=0.0),
                               starts, dur, DEFAULT_DT), args.repeat)
    k = 50                                                # sequential baseline on 50 figures
    t_seq = best(lambda: [run(fig.body, fig.limits, PhaseEllipse(fig.body, w, tm, heading=0.0),
                              starts[:, j], dur, DEFAULT_DT) for j in range(k)], 1)
    print(f"date: {datetime.date.today()}, machine: {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}, dt = {DEFAULT_DT} s")
    print()
    print("| case | wall time | rate | goal |")
    print("|---|---|---|---|")
    print(f"| one figure, 60 s phase-ellipse slalom with heading control, scalar backend | {t_scalar * 1e3:.0f} ms | "
          f"{60 / t_scalar:.0f}x real time | 1000x |")
    print(f"| one figure, 60 s open-loop slalom (Section 4), scalar | {t_open * 1e3:.0f} ms | "
          f"{60 / t_open:.0f}x real time | 1000x |")
    print(f"| baseline: the phase-ellipse run on the numpy backend (batch of one) | {t_numpy1 * 1e3:.0f} ms | "
          f"{60 / t_numpy1:.0f}x real time | |")
    print(f"| batch of {n}, {dur:g} s ({steps} steps) | {t_batch * 1e3:.0f} ms | "
          f"{n * steps / t_batch / 1e6:.2f} M figure-steps/s | 10 M |")
    print(f"| baseline: {k} figures one at a time (scalar) | {t_seq * 1e3:.0f} ms | "
          f"{k * steps / t_seq / 1e6:.3f} M figure-steps/s | |")


if __name__ == "__main__":
    main()

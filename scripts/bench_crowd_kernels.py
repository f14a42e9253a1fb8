"""Benchmark: the two kernels of a crowd's parametric figures (crowd/kernels.py) against the
number of figures: one numpy batch against each figure on floats, CPU seconds, best of
``--repeat``; and a crowd of 10 (``run_crowd``, which picks the kernel) against the same 10
figures run as 10 crowds of one.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_crowd_kernels.py [--figures 1 10 40 80 100 140]

The figures: a skier leading and followers 0.1 s apart (period within 5 %), 60 s at dt 0.02 s.
"""
from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import time

from blender_turning.core import preset
from blender_turning.crowd import Crowd, CrowdFigure, Turns, follow_leader, kernels, run_crowd


def cpu(fn) -> float:
    t = time.process_time()
    fn()
    return time.process_time() - t


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figures", type=int, nargs="+", default=[1, 10, 40, 80, 100, 140])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    lead = CrowdFigure("lead", preset("skier"), Turns(2.0, math.radians(20), 0.0))
    figs = (lead,) + follow_leader(lead, max(args.figures) - 1, 0.1, lateral=[-2, 2], seed=1,
                                   period_jitter=0.05)
    now = datetime.datetime.now(datetime.timezone.utc)
    print(f"{platform.machine()}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}; "
          f"{now:%Y-%m-%d %H:%M} UTC; {args.seconds:g} s at dt 0.02 s, CPU s, best of "
          f"{args.repeat}; BATCH_FROM = {kernels.BATCH_FROM}\n")
    print("| figures | floats | batch | batch / floats | chosen |\n|---|---|---|---|---|")
    for n in args.figures:
        sub = figs[:n]
        t = {k: min(cpu(lambda k=k: kernels.run_turns(0.02, args.seconds, sub, k))
                    for _ in range(args.repeat)) for k in kernels.KERNELS}
        print(f"| {n} | {t['floats']:.3f} | {t['batch']:.3f} | {t['batch'] / t['floats']:.2f} | "
              f"{kernels.kernel_for(n)} |", flush=True)
    ten = figs[:10]
    crowd = min(cpu(lambda: run_crowd(Crowd("10", ten, args.seconds)))
                for _ in range(args.repeat))
    alone = min(cpu(lambda: [run_crowd(Crowd("1", (f,), args.seconds)) for f in ten])
                for _ in range(args.repeat))
    print(f"\ncrowd of 10: {crowd:.3f} CPU s; the same 10 as crowds of one (baseline): "
          f"{alone:.3f} CPU s")


if __name__ == "__main__":
    main()

"""The telemark skier's body: centre-of-mass height ``l`` and roll inertia ``I_v`` of
the built-in telemark figure in its own lunge, from Winter's segment data
(:mod:`blender_turning.mapping.anthropometry`), iterated to a fixed point (the body sets the
run, the run sets the lunge).  Prints what the telemark's record (``mapping/sports/telemark.py``) holds.

    PYTHONPATH=$PWD .venv/bin/python scripts/telemark_body.py [--sport telemark]
"""
from __future__ import annotations

import argparse
import math
from dataclasses import replace

from blender_turning.core import preset, simulate
from blender_turning.core.controllers import PhaseEllipse
from blender_turning.mapping.posed import posed_body

#: The run the body is averaged over: a 2 s slalom of 23 deg leans (the telemark tests' run).
OMEGA0, THETA_MAX, SECONDS = math.pi, math.radians(23.0), 6.0


def run(sport: str, body):
    """The run the body is averaged over, with ``body``, one sample per frame at 24 fps."""
    fig = replace(preset(sport), body=body)
    return simulate(fig, PhaseEllipse(body, omega0=OMEGA0, theta_max=THETA_MAX, heading=0.0),
                    duration=SECONDS).resample(24)


def fixed_point(sport: str, passes: int = 5):
    body = preset(sport).body
    for _ in range(passes):
        l, inertia = posed_body(sport, run(sport, body), body.m)
        body = replace(body, l=float(l.mean()), I_v=float(inertia.mean()))
    return body


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sport", default="telemark")
    args = ap.parse_args(argv)
    body = fixed_point(args.sport)
    l, inertia = posed_body(args.sport, run(args.sport, body), body.m)
    print(f"{args.sport}: m = {body.m:g} kg, l = {body.l:.3f} m (range {l.min():.3f}-"
          f"{l.max():.3f}), I_v = {body.I_v:.2f} kg m^2 (range {inertia.min():.2f}-"
          f"{inertia.max():.2f})")


if __name__ == "__main__":
    main()

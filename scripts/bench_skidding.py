"""Grip and skidding: the measured goals of docs/skidding.md, each beside its baseline (today's
carving) measured in the same run.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_skidding.py            # about 30 s
    PYTHONPATH=$PWD .venv/bin/python scripts/bench_skidding.py --planner  # + the slalom, ~1 min

Prints, per sport and slope, the mean speed over the last 30 s of 60 s at a 10 m/s target, the
largest distance from the fall line through the start and the share of braking done by turning
(``skidding.turning_share``), skidding and carving; then stops, the wedge, the 10 m slalom, the
giant slalom's drag share and the cyclist's lean and braking distances.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start
from blender_turning.core.controllers.braking import TargetSpeed, round_turns
from blender_turning.core.controllers.straight import Straight
from blender_turning.core.errors import RunEnded
from blender_turning.core.physics.grip import tyre
from blender_turning.core.physics import model
from blender_turning.core.physics.model import RESISTANCE
from blender_turning.core.physics.params import Limits
from blender_turning.core.physics.skidding import Skidding, turning_share
from blender_turning.core.ground.terrain import Plane

ROOT = Path(__file__).resolve().parent.parent
FALL = -math.pi / 2


def run(sport, slope, target, skid, V0=None, period=2.0, lean=23.0, duration=60.0, res=None,
        rounds=False):
    """One run down the fall line; ``rounds``: speed control's round turns (``round_turns``)
    instead of the ``period`` / ``lean`` slalom."""
    fig = preset(sport)
    if V0 is not None:
        fig = replace(fig, body=replace(fig.body, V_cm=V0))
    res = res or RESISTANCE[sport]
    ground = Plane(math.radians(slope), FALL)
    if rounds:
        rt = round_turns(fig, math.radians(slope), res, target, skid.corridor)
        ctl = PhaseEllipse(fig.body, rt.omega0, rt.theta_max, heading=FALL)
        ctl.begin_run(fig.limits)
        s0 = rt.start(FALL, fig.body.V_cm)
    else:
        ctl = PhaseEllipse(fig.body, 2 * math.pi / period, math.radians(lean), heading=FALL)
        ctl.begin_run(fig.limits)
        s0 = slalom_start(fig.body, *ctl.target(0.0), FALL)
    t0 = time.perf_counter()
    traj = simulate(fig, ctl, duration, 0.02, s0, ground=ground, resistance=res,
                    target_speed=target, skidding=skid)
    return traj, ground, time.perf_counter() - t0


def pistes():
    print("sport        slope  turns          mean m/s  |x| max m  turning share  wall s")
    for sport in ("skier", "snowboarder"):
        for slope in (12, 18, 25):
            for name, skid, rounds in (("skid, round", Skidding("skid"), True),
                                       ("skid, 2 s", Skidding("skid"), False),
                                       ("carve, 2 s", None, False)):
                try:
                    traj, ground, wall = run(sport, slope, 10.0, skid, rounds=rounds)
                except RunEnded as exc:
                    print(f"{sport:12s} {slope:4d}   {name:13s}  {exc}")
                    continue
                mean = traj.V_cm[traj.t >= 30.0].mean()
                share = turning_share(traj, ground, 9.81)
                print(f"{sport:12s} {slope:4d}   {name:13s}  {mean:8.2f}  "
                      f"{np.abs(traj.x).max():9.1f}  {share:13.2f}  {wall:6.2f}")


def stops():
    print("\nstop from 10 m/s on 15 deg: distance to < 0.3 m/s, m (time, s)")
    for sport, side in (("skier", None), ("snowboarder", "heel"), ("snowboarder", "toe")):
        for snow in ("hard", "soft"):
            from blender_turning.core.physics.grip import SNOW
            traj, _, _ = run(sport, 15, None, Skidding("carve", SNOW[snow], 0.0, side), V0=10.0,
                             duration=6.0)
            i = int(np.argmax(traj.V_cm < 0.3))
            print(f"  {sport:12s} {side or '':5s} {snow:5s} {traj.s[i]:5.1f} m ({traj.t[i]:.2f} s)")
    traj, _, _ = run("skier", 8, 4.0, Skidding("wedge"), V0=4.0)
    print(f"wedge on 8 deg, 4 m/s target: mean {traj.V_cm[traj.t >= 30].mean():.2f} m/s, "
          f"half-angle max {math.degrees(traj.skid.max()):.1f} deg")
    traj, _, _ = run("snowboarder", 20, 4.0, Skidding("slip"), V0=4.0)
    print(f"side-slip on 20 deg, 4 m/s target: mean {traj.V_cm[traj.t >= 30].mean():.2f} m/s")


def dissipation(traj, ground, fig, res):
    st = tuple(getattr(traj, k) for k in model.STATE)
    _, _, _, V_f, N, _ = model.rhs(fig.body, Limits(), ground, traj.C_f, st, resistance=res)
    dt = np.diff(traj.t)
    drag = np.sum((res.drag_k(fig.body.m) * traj.V_cm ** 3)[:-1] * dt)
    fric = np.sum((res.mu * N / fig.body.m * V_f)[:-1] * dt)
    skid = np.sum((traj.brake * V_f)[:-1] * dt)
    return drag / (drag + fric + skid)


def races():
    print("\nraces on 19 deg (40 s; speeds over the last 20 s)")
    for label, sport, V, period, lean, corridor in (
            ("slalom, 10 m gates", "skier", 12.0, 1.67, 45, 3.0),
            ("giant slalom", "gs_racer", 18.0, 2.8, 50, 5.0),
            ("giant slalom at 16 m/s", "gs_racer", 16.0, 2.8, 50, 5.0),
            ("giant slalom, skier's 0.5 m^2", "skier", 18.0, 2.8, 50, 5.0)):
        res = RESISTANCE[sport]
        for name, skid in (("skid", Skidding("skid", corridor=corridor)), ("carve", None)):
            target = TargetSpeed(V, corridor=corridor)
            traj, ground, _ = run(sport, 19, target, skid, V0=18.0 if V >= 16 else V,
                                  period=period, lean=lean, duration=40.0)
            late = traj.V_cm[traj.t >= 20.0]
            fig = replace(preset(sport), body=replace(preset(sport).body, V_cm=V))
            print(f"  {label:30s} {name:5s} mean {late.mean():5.2f} ({late.min():.1f}-"
                  f"{late.max():.1f}) m/s, drag {dissipation(traj, ground, fig, res):.1%} of the "
                  f"dissipated energy (CdA {res.CdA:g} m^2, {fig.body.m:g} kg)")


def cyclist():
    print("\ncyclist")
    fig = preset("cyclist")
    lim = Limits(C_f_max=fig.limits.C_f_max, dC_f_max=fig.limits.dC_f_max,
                 theta_fall=math.radians(70))
    for mu in (2.0, 0.9, 0.5):
        ctl = PhaseEllipse(fig.body, 2 * math.pi / 3, math.radians(48), heading=0.0, limits=lim)
        ctl.begin_run(fig.limits)
        traj = simulate(fig, ctl, 12.0, 0.02, slalom_start(fig.body, *ctl.target(0.0), 0.0),
                        skidding=Skidding("carve", tyre(mu)))
        print(f"  48 deg asked, mu {mu:g}: lean max {math.degrees(np.abs(traj.theta_v).max()):.1f}"
              f" deg ({traj.meta.get('grip_limited', 'not limited')})")
    for mu in (0.9, 0.5, 0.35):
        traj = simulate(fig, Straight(fig.body), 5.0, 0.02, (0.0, 0.0, 0.0, 0.0, 0.0, 10.0),
                        skidding=Skidding("carve", tyre(mu), stop_at=0.0))
        print(f"  braking from 10 m/s, mu {mu:g}: {traj.s[-1]:.2f} m (v^2/(2 mu g) = "
              f"{100.0 / (2 * mu * fig.body.g):.2f} m)")


def planner():
    from blender_turning.cli import main
    doc = json.loads((ROOT / "scenes" / "slalom.json").read_text())
    doc["terrain"] = {"type": "plane", "slope_deg": 19, "downhill_deg": 0}
    with tempfile.TemporaryDirectory() as tmp:
        scene = Path(tmp) / "slalom19.json"
        scene.write_text(json.dumps(doc))
        print("\nfollow scenes/slalom.json on a 19 deg plane; without braking, then "
              "--target-speed 12:")
        main(["follow", str(scene)])
        t0 = time.perf_counter()
        main(["follow", str(scene), "--target-speed", "12"])
        print(f"  wall {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--planner", action="store_true", help="also plan the slalom on 19 deg")
    args = ap.parse_args()
    pistes()
    stops()
    races()
    cyclist()
    if args.planner:
        planner()
    sys.exit(0)

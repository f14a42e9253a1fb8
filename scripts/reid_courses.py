"""Reid et al. 2020's slalom courses (Front. Sports Act. Living 2:25) as scene files, followed
by the path planner (Section 6) with a racer preset; prints the minimum centre-of-mass radius,
the peak edge angle of the skis (the sidecut relation, core/equipment.py) and the peak leg force.

    python scripts/reid_courses.py [--gates 10 13] [--speed 12] [--stages 10 --choices 5]

The courses (docs/racing.md): gates ``gap`` m apart along the fall line (+x), the line through
them 2.5 m left and right of it, each turning pole a line from 1.5 m inside the line to the
course's edge (12 m out); flat ground at constant speed (the racers ride 11-13 m/s on Reid's
19 deg slope).  Reid: minimum radii 3.96 +- 0.23 m (10 m gates) and 4.94 +- 0.59 m (13 m),
peak edge angles 65.7 +- 1.7 and 71.0 +- 1.9 deg."""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from blender_turning.core.equipment import (SPORT_PRESETS, carving_of,  # noqa: E402
                                            register_preset)
from blender_turning.core.course.scene import scene_from_dict  # noqa: E402
from blender_turning.core.errors import PlanInfeasible  # noqa: E402

REID = {10.0: (3.96, 0.23, 65.7, 1.7), 13.0: (4.94, 0.59, 71.0, 1.9)}


def course(gap: float, speed: float, preset: str = "slalom_racer", gates: int = 8,
           planner: dict | None = None, amplitude: float = 2.5, inside: float = 1.5,
           edge: float = 12.0) -> dict:
    """The scene document of a course of ``gates`` turning poles ``gap`` m apart."""
    x0 = 10.0
    pts, tans, obs = [[0.0, 0.0], [x0, 0.0]], [[gap, 0.0], [gap, 0.0]], []
    for k in range(gates):
        side = 1.0 if k % 2 == 0 else -1.0
        x = x0 + gap * (k + 1)
        pts.append([x, side * amplitude])
        tans.append([1.5 * gap, 0.0])
        obs.append({"type": "segment", "from": [x, side * (amplitude - inside)],
                    "to": [x, -side * edge]})
    end = x0 + gap * (gates + 1)
    pts += [[end, 0.0], [end + gap, 0.0]]
    tans += [[gap, 0.0], [gap, 0.0]]
    obs += [{"type": "segment", "from": [-5.0, s * edge], "to": [end + 2 * gap, s * edge]}
            for s in (1.0, -1.0)]
    return {"name": f"reid {gap:g} m", "figure": {"preset": preset, "body": {"V_cm": speed}},
            "path": {"points": pts, "tangents": tans}, "clearance": 0.3, "obstacles": obs,
            "start": {"position": [0, 0], "heading_deg": 0},
            "planner": {"stages": 10, "choices": 5, "stage_time": 0.3,
                        "lean_bound_deg": 75, **(planner or {})}}


def com_radius(traj, l: float) -> np.ndarray:
    """The radius of the centre of mass's track at every sample, m: the COM stands ``l
    sin(theta_v)`` to the left of the foot (Fig. 2, ``theta_v > 0`` leans left), and the
    curvature of its track is ``|x' y'' - y' x''| / |v|^3`` (central differences in time)."""
    off = l * np.sin(traj.theta_v)
    x = traj.x - off * np.sin(traj.theta_dir)
    y = traj.y + off * np.cos(traj.theta_dir)
    t = traj.t
    dx, dy = np.gradient(x, t), np.gradient(y, t)
    ddx, ddy = np.gradient(dx, t), np.gradient(dy, t)
    k = np.abs(dx * ddy - dy * ddx) / np.maximum(np.hypot(dx, dy), 1e-9) ** 3
    return 1.0 / np.maximum(k, 1e-12)


def measure(traj, fig, x_lo: float, x_hi: float) -> dict:
    """Minimum centre-of-mass radius (its track's curvature) and the foot's (``1 / max |C_f|``),
    peak edge angle (the sidecut relation for C_f), peak lean and the leg force in body weights
    over the gates."""
    m = (traj.x >= x_lo) & (traj.x <= x_hi)
    R = com_radius(traj, fig.body.l)[m]
    edge = np.abs(carving_of(fig.name).edge_angle(traj.C_f[m]))
    bw = traj.F_leg[m] / (fig.body.m * fig.body.g)
    return {"R_min": float(R.min()), "edge_max": math.degrees(float(edge.max())),
            "R_foot_min": 1.0 / float(np.abs(traj.C_f[m]).max()),
            "lean_max": math.degrees(float(np.abs(traj.theta_v[m]).max())),
            "F_max_bw": float(bw.max()), "F_mean_bw": float(bw.mean())}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--gates", type=float, nargs="+", default=[10.0, 13.0])
    p.add_argument("--speed", type=float, default=12.0)
    p.add_argument("--preset", default="slalom_racer")
    p.add_argument("--stages", type=int, default=10)
    p.add_argument("--choices", type=int, default=7)
    p.add_argument("--stage-time", type=float, default=0.2)
    p.add_argument("--rate", type=float, default=1.0,
                   help="the planner's dC_f_max, 1/(m s): its q choices span +-rate (with the "
                        "preset's own 2.06 no plan exists at t = 0)")
    p.add_argument("--angulation", type=float, default=None,
                   help="with --edge-limit: the racer's largest angulation, deg (default: the "
                        "preset's)")
    p.add_argument("--edge-limit", action="store_true",
                   help="clip lines whose edge the lean and the angulation cannot hold "
                        "(PlannerSettings.edge_limit)")
    a = p.parse_args(argv)
    if a.angulation is not None:
        record = SPORT_PRESETS[a.preset]
        register_preset(replace(record, angulation=math.radians(a.angulation)), replace=True)
    for gap in a.gates:
        doc = course(gap, a.speed, a.preset, planner={"stages": a.stages, "choices": a.choices,
                                                      "stage_time": a.stage_time})
        doc["figure"]["limits"] = {"dC_f_max": a.rate}
        scene = scene_from_dict(doc, f"reid {gap:g}").with_settings(
            edge_limit=a.edge_limit)
        t0 = time.perf_counter()
        try:
            result = scene.run()
        except PlanInfeasible as exc:
            print(f"gates {gap:g} m at {a.speed:g} m/s: {exc}")
            continue
        traj = getattr(result, "trajectory", result)
        got = measure(traj, scene.figure, 10.0 + gap, 10.0 + gap * 8)
        ref = REID.get(gap)
        print(f"gates {gap:g} m at {a.speed:g} m/s ({a.preset}, N = {a.stages}, q = {a.choices}, "
              f"t_stage {a.stage_time:g} s, rate {scene.figure.limits.dC_f_max:.3g}, "
              f"edge limit {'on' if a.edge_limit else 'off'}, "
              f"{time.perf_counter() - t0:.0f} s): R_min {got['R_min']:.2f} m (the foot's "
              f"{got['R_foot_min']:.2f} m), edge max "
              f"{got['edge_max']:.1f} deg, lean max {got['lean_max']:.1f} deg, leg force max "
              f"{got['F_max_bw']:.2f} BW, mean {got['F_mean_bw']:.2f} BW"
              + (f"; Reid: R_min {ref[0]} +- {ref[1]} m, edge {ref[2]} +- {ref[3]} deg"
                 if ref else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())

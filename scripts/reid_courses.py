"""Reid et al. 2020's slalom courses (Front. Sports Act. Living 2:25) as scene files, followed
by the path planner (Section 6) with a racer preset; prints each turn's tightest radius of the
skis (the foot's) and of the centre of mass, the skis' largest edge angle (the sidecut relation,
core/equipment.py), the largest lean and the peak leg force, their mean +- SD over the turns,
the skis' radius and edge against Reid's (their measures: core/course/reid.py, against_reid),
and the whole run's extremes.

    python scripts/reid_courses.py [--gates 10 13] [--speed 12] [--stages 10 --choices 9]
        [--line race] [--leg-force 5] [--rate 2.06] [--slope 19 --target-speed 12 [--snow race] [--grip 2]]

The courses (docs/racing.md, "The racer's line"): gates ``gap`` m apart along the fall line
(+x), the line through them 2.5 m left and right of it, each turning pole a line from 1.5 m
inside the line to the course's edge (12 m out); flat ground at constant speed (the racers ride
11-13 m/s on Reid's 19 deg slope), or with ``--slope`` that slope, the speed free."""
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
from blender_turning.core.course.reid import (REID, against_reid, com_radius,  # noqa: E402
                                              course, gate_positions, per_turn, summary)
from blender_turning.core.course.scene import scene_from_dict  # noqa: E402
from blender_turning.core.errors import PlanInfeasible  # noqa: E402
from blender_turning.core.physics.grip import SNOW  # noqa: E402
from blender_turning.core.planner.speed_cap import SpeedCap  # noqa: E402
from blender_turning.cli.terrain_flags import grip_of  # noqa: E402


def extremes(traj, fig, x_lo: float, x_hi: float) -> dict:
    """The single extremes over the gates ``x_lo``-``x_hi`` (the tightest radius of the whole
    run, the largest edge): the statistic :func:`per_turn` replaces, kept for comparison."""
    m = (traj.x >= x_lo) & (traj.x <= x_hi)
    edge = np.abs(carving_of(fig.name).edge_angle(traj.C_f[m]))
    bw = traj.F_leg[m] / (fig.body.m * fig.body.g)
    return {"R_com": float(com_radius(traj, fig.body.l)[m].min()),
            "R_foot": 1.0 / float(np.abs(traj.C_f[m]).max()),
            "edge": math.degrees(float(edge.max())), "F_bw": float(bw.max()),
            "F_mean_bw": float(bw.mean())}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--gates", type=float, nargs="+", default=[10.0, 13.0])
    p.add_argument("--count", type=int, default=8, help="turning poles a course")
    p.add_argument("--speed", type=float, default=12.0)
    p.add_argument("--preset", default="slalom_racer")
    p.add_argument("--stages", type=int, default=10)
    p.add_argument("--choices", type=int, default=9)
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
    p.add_argument("--line", choices=("path", "race"), default="path",
                   help="the planner's cost: the distance to the drawn line (Section 6) or the "
                        "racer's least time through the gates (PlannerSettings.line)")
    p.add_argument("--spread", choices=("rate", "range"), default="range",
                   help="the planner's choices of dC_f/dt (PlannerSettings.spread)")
    p.add_argument("--leg-force", type=float, default=0.0, metavar="BW",
                   help="clip lines whose leg force passes this many body weights "
                        "(PlannerSettings.leg_force_max; 0: no limit)")
    p.add_argument("--edge-max", type=float, default=None, metavar="DEG",
                   help="the skis' largest edge angle, deg: C_f_max = 1 / (R_sc cos(edge)) by "
                        "the sidecut relation (default: the preset's)")
    p.add_argument("--amplitude", type=float, default=2.5, metavar="M",
                   help="the line through the gates, m left and right of the fall line (the "
                        "turning poles from 1.5 m inside it)")
    p.add_argument("--slope", type=float, default=0.0, metavar="DEG",
                   help="the courses on a plane of this slope falling along them, the speed "
                        "free from --speed on (Reid's: 19); 0: flat, the speed held")
    p.add_argument("--target-speed", type=float, default=None, metavar="V",
                   help="with --slope: brake to this speed within the snow's grip "
                        "(docs/skidding.md, the planner brakes)")
    p.add_argument("--snow", default="race", choices=tuple(SNOW),
                   help="with --target-speed: the snow's grip (default race: a race piste, "
                        "docs/skidding.md)")
    p.add_argument("--grip", type=float, default=None, metavar="MU",
                   help="with --target-speed: the snow's largest force ratio, overriding "
                        "--snow's")
    a = p.parse_args(argv)
    if a.angulation is not None:
        record = SPORT_PRESETS[a.preset]
        register_preset(replace(record, angulation=math.radians(a.angulation)), replace=True)
    for gap in a.gates:
        doc = course(gap, a.speed, a.preset, gates=a.count, amplitude=a.amplitude,
                     planner={"stages": a.stages, "choices": a.choices,
                              "stage_time": a.stage_time, "line": a.line, "spread": a.spread,
                              "leg_force_max_bw": a.leg_force})
        doc["figure"]["limits"] = {"dC_f_max": a.rate}
        if a.slope:
            doc["terrain"] = {"type": "plane", "slope_deg": a.slope, "downhill_deg": 0.0}
        if a.edge_max is not None:
            sidecut = carving_of(a.preset).sidecut_radius
            doc["figure"]["limits"]["C_f_max"] = 1.0 / (sidecut * math.cos(math.radians(
                a.edge_max)))
        scene = scene_from_dict(doc, f"reid {gap:g}").with_settings(
            edge_limit=a.edge_limit)
        if a.target_speed is not None:
            scene = replace(scene, speed_cap=SpeedCap(a.target_speed, grip_of(a, a.preset)))
        t0 = time.perf_counter()
        try:
            result = scene.run()
        except PlanInfeasible as exc:
            print(f"gates {gap:g} m at {a.speed:g} m/s: {exc}")
            continue
        traj = getattr(result, "trajectory", result)
        gate_x = gate_positions(gap, a.count)
        turn = per_turn(traj, scene.figure, gate_x)
        ext = extremes(traj, scene.figure, gate_x[0], gate_x[-1])
        print(f"gates {gap:g} m at {a.speed:g} m/s{f' on {a.slope:g} deg' if a.slope else ''}"
              f"{'' if a.target_speed is None else f', braking to {a.target_speed:g} m/s'}"
              f"{'' if a.target_speed is None else f' on {grip_of(a, a.preset).name} snow'} "
              f"({a.preset}, N = {a.stages}, q = {a.choices}, "
              f"t_stage {a.stage_time:g} s, line {a.line}, spread {a.spread}, "
              f"leg force <= {a.leg_force:g} BW, "
              f"rate {scene.figure.limits.dC_f_max:.3g}, "
              f"C_f_max {scene.figure.limits.C_f_max:.3g}, "
              f"edge limit {'on' if a.edge_limit else 'off'}, "
              f"{time.perf_counter() - t0:.0f} s)")
        for i, k in enumerate(turn["gates"]):
            print(f"  gate {int(k) + 1}: COM {turn['R_com'][i]:.2f} m, foot "
                  f"{turn['R_foot'][i]:.2f} m, edge {turn['edge'][i]:.1f} deg, lean "
                  f"{turn['lean'][i]:.1f} deg, leg force {turn['F_bw'][i]:.2f} BW, speed "
                  f"{turn['V_lo'][i]:.1f}-{turn['V_hi'][i]:.1f} m/s")
        ref = REID.get(gap)
        verdicts = against_reid(turn, gap) if ref else {}
        for name, unit, ref_i, measure in (
                ("R_com", "m", None, None), ("R_foot", "m", 0, "radius"),
                ("edge", "deg", 2, "edge"), ("lean", "deg", None, None),
                ("F_bw", "BW", None, None), ("V_lo", "m/s", None, None),
                ("V_hi", "m/s", None, None)):
            mean, sd = summary(turn)[name]
            verdict = ""
            if measure in verdicts:
                verdict = (f"  Reid {ref[ref_i]:g} +- {ref[ref_i + 1]:g}: "
                           f"{'within' if verdicts[measure][2] else 'NOT within'} 10 %")
            print(f"  per turn ({len(turn['gates'])} turns) {name}: {mean:.2f} +- {sd:.2f} "
                  f"{unit}{verdict}")
        print(f"  whole run's extremes: COM {ext['R_com']:.2f} m, foot {ext['R_foot']:.2f} m, "
              f"edge {ext['edge']:.1f} deg, leg force {ext['F_bw']:.2f} BW (mean "
              f"{ext['F_mean_bw']:.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

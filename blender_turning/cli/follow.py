"""``follow``: path following around obstacles (Section 6) from a scene file.

Writes the trajectory CSV (docs/ARCHITECTURE.md Sec. 3, ``phi`` from the 6.2 post-pass), the search
statistics (JSON: one entry per replanning and totals) and a plot of path, obstacles and track.
When no plan survives, the error names the time and the position; when the time limit (three times
the time to ride the path) comes before the end of the path, how far along it got (arc length);
either is one line on stderr, exit 2, and no trajectory or statistics are written (``--plot``
still draws the track up to there, to show where it went wrong).  While it plans, a progress bar
(share of the path, course time planned, time left) goes to stderr when it is a terminal.
"""
from __future__ import annotations

import json
import math
from dataclasses import replace

from ..core.errors import PathNotFinished, PlanInfeasible
from ..core.physics.params import check_range
from ..core.planner.speed_cap import SpeedCap
from ..core.course.scene import check_horizon, load_scene
from ..core.validate import check
from .common import Outputs, require_matplotlib
from .progress import Progress
from .terrain_flags import SNOW_HELP, grip_of


def register(sub):
    p = sub.add_parser("follow", help="follow a drawn path around obstacles (branch and bound)",
                       description="Plan a figure's run along the path of a scene file, around its "
                                   "obstacles, with the receding-horizon branch-and-bound search "
                                   "of Section 6.")
    p.add_argument("scene", help="scene JSON file (see docs/cli.md, 'Scene files')")
    p.add_argument("--stages", type=int, help="N, stages planned ahead (scene default)")
    p.add_argument("--choices", type=int, help="q, values of dC_f/dt tried per stage")
    p.add_argument("--choices-near", type=int,
                   help="values of dC_f/dt tried per stage with an obstacle within reach "
                        "(0: --choices; 2 q - 1 passes obstacles closer)")
    p.add_argument("--stage-time", type=float, help="t_stage, s")
    p.add_argument("--line", choices=("path", "race"),
                   help="the planner's cost: path, the distance to the drawn path (Section 6); "
                        "race, the least time down the course around the obstacles (scene "
                        "default; docs/racing.md)")
    p.add_argument("--spread", choices=("rate", "range"),
                   help="how the choices of dC_f/dt spread: rate, evenly over the largest rate "
                        "(Section 6.1); range, over the rate that brings C_f to its bound by "
                        "the stage's end (scene default; docs/racing.md)")
    p.add_argument("--target-speed", type=float, metavar="V",
                   help="m/s: brake at the foot, within the grip, to hold at most this speed "
                        "(and what the grip allows on the path's tightest bend; "
                        "docs/skidding.md)")
    p.add_argument("--snow", help=SNOW_HELP + " (with --target-speed)")
    p.add_argument("--grip", type=float, metavar="MU",
                   help="the friction circle's mu at the foot, overriding the sport's (with "
                        "--target-speed)")
    p.add_argument("--out", help="trajectory CSV to write")
    p.add_argument("--stats", help="search statistics JSON to write")
    p.add_argument("--plot", help="PNG of the path, the obstacles and the track")
    p.set_defaults(func=run)


def run(args) -> int:
    if args.plot:
        require_matplotlib("--plot")
    changes = {}
    if args.stages is not None:
        changes["n_stages"] = check("--stages", args.stages, "n_stages")
    if args.choices is not None:
        changes["q"] = check("--choices", args.choices, "q")
    if args.choices_near is not None:
        changes["q_near"] = check("--choices-near", args.choices_near, "q_near")
    if args.stage_time is not None:
        changes["t_stage"] = check("--stage-time", args.stage_time, "t_stage")
    if args.line is not None:
        changes["line"] = args.line
    if args.spread is not None:
        changes["spread"] = args.spread
    scene = load_scene(args.scene)
    for flag, value in (("--grip", args.grip), ("--snow", args.snow)):
        if value is not None and args.target_speed is None:
            raise ValueError(f"{flag} needs --target-speed (the grip bounds the braking)")
    if args.target_speed is not None:
        scene = replace(scene, speed_cap=_speed_cap(args, scene.figure.name))
    if changes:
        try:
            scene = scene.with_settings(**changes)
        except ValueError as exc:
            raise ValueError(f"planner settings: {exc}") from None
        check_horizon(scene.settings, "with --stages, --choices, --choices-near, --stage-time: ")
    outputs = Outputs()                       # every output path checked before the work
    for flag in ("out", "stats", "plot"):
        outputs.reserve(f"--{flag}", getattr(args, flag))
    try:
        with Progress(100, "%", "follow") as bar:
            result = scene.run(on_replan=_progress(bar, scene.duration))
            bar.update(100, note=f"{result.trajectory.duration:.1f} s of course planned")
    except (PlanInfeasible, PathNotFinished) as exc:
        # The plot of the failed run (where it got stuck) is the one output written.
        if args.plot and exc.trajectory is not None:
            where = getattr(exc, "position", None) or (float(exc.trajectory.x[-1]),
                                                       float(exc.trajectory.y[-1]))
            _plot(outputs, scene, exc.trajectory, failed_at=where)
            outputs.commit(only=("--plot",))
        raise
    traj = result.trajectory
    if args.out:
        outputs.write("--out", traj.to_csv)
    if args.stats:
        doc = {"scene": scene.name, "settings": _settings(scene.settings),
               "replans": [r.as_dict() for r in result.replans], "totals": result.totals()}
        text = json.dumps(doc, indent=1)
        outputs.write("--stats", lambda path: path.write_text(text))
    if args.plot:
        _plot(outputs, scene, traj)
    outputs.commit()
    tot = result.totals()
    st = scene.settings
    free = scene.ground is not None or scene.speed_cap is not None
    print(f"follow: {scene.name}, {scene.figure.name}, N = {st.n_stages}, q = {st.q}, "
          f"{traj.duration:.2f} s, {tot['replans']} replans, {tot['expanded']} nodes expanded, "
          f"{tot['wall_time']:.2f} s planning; lean max "
          f"{math.degrees(abs(traj.theta_v).max()):.1f} deg"
          f"{f', speed {traj.V_cm.min():.1f}-{traj.V_cm.max():.1f} m/s' if free else ''}"
          f"{f', brake max {traj.brake.max():.1f} m/s^2' if scene.speed_cap else ''}"
          f"{'' if result.reached_end else ' (stopped at the given duration)'}"
          f"{f' -> {args.out}' if args.out else ''}")
    return 0


def _speed_cap(args, sport: str) -> SpeedCap:
    """The :class:`..core.planner.speed_cap.SpeedCap` of ``--target-speed``, ``--snow`` and
    ``--grip``."""
    V = check_range("--target-speed", args.target_speed, 0.0, 100.0, lo_open=True)
    return SpeedCap(V, grip_of(args, sport))


def _progress(bar, duration):
    """The planner's ``on_replan`` drawing ``bar``: the share of the path done (of ``duration``
    when the scene gives one) and the course time planned so far."""
    def on_replan(t, xy, fraction):
        done = t / duration if duration else fraction
        bar.update(min(int(100 * done), 99), note=f"{t:.1f} s of course planned")
    return on_replan


def _settings(st) -> dict:
    return {"t_stage": st.t_stage, "n_stages": st.n_stages, "q": st.q, "q_near": st.q_near,
            "theta_bound": st.theta_bound, "sample_dt": st.sample_dt, "dt": st.dt,
            "warm_start": st.warm_start, "lower_bound": st.lower_bound,
            "lookahead": st.lookahead, "fall_table": st.fall_table, "batch": st.batch,
            "line": st.line, "spread": st.spread, "leg_force_max": st.leg_force_max}


def _plot(outputs, scene, traj, failed_at=None):
    from ..figures.planner import plot_scene
    outputs.write("--plot", lambda path: plot_scene(scene, [(traj, "track", "-")], path,
                                                    failed_at=failed_at))

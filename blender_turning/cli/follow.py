"""``follow``: path following around obstacles (Section 6) from a scene file.

Writes the trajectory CSV (DESIGN.md columns, ``phi`` from the Section 6.2 post-pass), the search
statistics (JSON: one entry per replanning and totals) and a plot of path, obstacles and track.
When no plan survives, the error names the time and the position; when the time limit (three times
the time to ride the path) comes before the end of the path, how far along it got (arc length);
either is one line on stderr, exit 2, and no trajectory or statistics are written (``--plot``
still draws the track up to there, to show where it went wrong).
"""
from __future__ import annotations

import json
import math

from ..core.errors import PathNotFinished, PlanInfeasible
from ..core.params import check_range
from ..core.scene import load_scene
from ..core.trajectory import _atomic_write
from .common import atomic_plot, check_out_path, require_matplotlib


def register(sub):
    p = sub.add_parser("follow", help="follow a drawn path around obstacles (branch and bound)",
                       description="Plan a figure's run along the path of a scene file, around its "
                                   "obstacles, with the receding-horizon branch-and-bound search "
                                   "of Section 6.")
    p.add_argument("scene", help="scene JSON file (see README, 'Path following')")
    p.add_argument("--stages", type=int, help="N, stages planned ahead (scene default)")
    p.add_argument("--choices", type=int, help="q, values of dC_f/dt tried per stage")
    p.add_argument("--stage-time", type=float, help="t_stage, s")
    p.add_argument("--out", help="trajectory CSV to write")
    p.add_argument("--stats", help="search statistics JSON to write")
    p.add_argument("--plot", help="PNG of the path, the obstacles and the track")
    p.set_defaults(func=run)


def run(args) -> int:
    for flag in ("out", "stats", "plot"):
        check_out_path(f"--{flag}", getattr(args, flag))
    if args.plot:
        require_matplotlib("--plot")
    scene = load_scene(args.scene)
    changes = {}
    if args.stages is not None:
        check_range("--stages", args.stages, 1, 64)
        changes["n_stages"] = args.stages
    if args.choices is not None:
        check_range("--choices", args.choices, 2, 64)
        changes["q"] = args.choices
    if args.stage_time is not None:
        changes["t_stage"] = check_range("--stage-time", args.stage_time, 0.0, 60.0,
                                         lo_open=True)
    if changes:
        try:
            scene = scene.with_settings(**changes)
        except ValueError as exc:
            raise ValueError(f"planner settings: {exc}") from None
    try:
        result = scene.run()
    except (PlanInfeasible, PathNotFinished) as exc:
        if args.plot and exc.trajectory is not None:
            where = getattr(exc, "position", None) or (float(exc.trajectory.x[-1]),
                                                       float(exc.trajectory.y[-1]))
            _plot(args.plot, scene, exc.trajectory, failed_at=where)
        raise
    traj = result.trajectory
    if args.out:
        traj.to_csv(args.out)
    if args.stats:
        doc = {"scene": scene.name, "settings": _settings(scene.settings),
               "replans": [r.as_dict() for r in result.replans], "totals": result.totals()}
        _atomic_write(args.stats, json.dumps(doc, indent=1))
    if args.plot:
        _plot(args.plot, scene, traj)
    tot = result.totals()
    st = scene.settings
    print(f"follow: {scene.name}, {scene.figure.name}, N = {st.n_stages}, q = {st.q}, "
          f"{traj.duration:.2f} s, {tot['replans']} replans, {tot['expanded']} nodes expanded, "
          f"{tot['wall_time']:.2f} s planning; lean max "
          f"{math.degrees(abs(traj.theta_v).max()):.1f} deg"
          f"{'' if result.reached_end else ' (stopped at the given duration)'}"
          f"{f' -> {args.out}' if args.out else ''}")
    return 0


def _settings(st) -> dict:
    return {"t_stage": st.t_stage, "n_stages": st.n_stages, "q": st.q,
            "theta_bound": st.theta_bound, "sample_dt": st.sample_dt, "dt": st.dt,
            "warm_start": st.warm_start, "lower_bound": st.lower_bound,
            "lookahead": st.lookahead, "fall_table": st.fall_table, "batch": st.batch}


def _plot(path, scene, traj, failed_at=None):
    from ..figures.planner import plot_scene
    atomic_plot(path, lambda tmp: plot_scene(scene, [(traj, "track", "-")], tmp,
                                             failed_at=failed_at))

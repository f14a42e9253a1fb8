"""``simulate``: one figure under the open-loop or phase-ellipse controller -> trajectory CSV."""
from __future__ import annotations

import math
import sys

from ..core import CONTROLLERS, PRESETS, preset, read_schedule_csv, simulate, slalom_start
from ..core.controllers.braking import round_turns
from ..core.ranges import RANGES, Range, lean_range
from ..core.controllers.schedule import Schedule
from ..core.ground.terrain import Plane
from ..core.physics.simulate import DEFAULT_DT
from ..core.validate import check
from .common import Outputs, check_steps, require_matplotlib
from .terrain_flags import add_terrain_flags, start_point, terrain_options

# flag -> BodyParams field; the ranges are the core's table (core/ranges.py), named by the flag.
BODY_FLAGS = {"mass": "m", "com_height": "l", "inertia": "I_v", "speed": "V_cm", "gravity": "g"}


def register(sub):
    p = sub.add_parser("simulate", help="simulate a slalom and write its trajectory",
                       description="Simulate one figure (Sections 3-5) and write the trajectory "
                                   "CSV (columns of docs/ARCHITECTURE.md Section 3, SI units, "
                                   "radians).")
    p.add_argument("--preset", default="skier", choices=sorted(PRESETS))
    p.add_argument("--mass", type=float, help="kg")
    p.add_argument("--com-height", type=float, help="height of the centre of mass, m")
    p.add_argument("--inertia", type=float, help="roll inertia about the centre of mass, kg m^2")
    p.add_argument("--speed", type=float, help="forward speed V_cm, m/s")
    p.add_argument("--gravity", type=float, help="m/s^2")
    p.add_argument("--controller", default="ellipse", choices=sorted(CONTROLLERS),
                   help="; ".join(f"{n}: {c.description}" for n, c in sorted(CONTROLLERS.items())))
    p.add_argument("--law", default="smooth", choices=("smooth", "paper"),
                   help="phase-ellipse law: smooth (default) or Section 5.1 as written")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--period", type=float, help="turn period 2 pi / omega0, s (default 2)")
    g.add_argument("--omega0", type=float, help="turn frequency, rad/s")
    p.add_argument("--lean-deg", type=float, default=None, help="theta_max, deg (default 23)")
    p.add_argument("--heading-deg", type=float, default=None,
                   help="heading theta_h, deg CCW from +x (default 0)")
    p.add_argument("--schedule", help="CSV with columns t, period, lean_deg, heading_deg")
    p.add_argument("--theta0-deg", type=float, help="initial lean, deg (default 0)")
    p.add_argument("--omega-v0-deg", type=float,
                   help="initial lean rate, deg/s (default: on the ellipse, omega0 theta_max)")
    p.add_argument("--duration", type=float, default=20.0, help="s")
    p.add_argument("--dt", type=float, default=DEFAULT_DT,
                   help=f"integration step, s ({RANGES['dt'].lo:g}-{RANGES['dt'].hi:g}; "
                        "BENCHMARKS.md: accuracy per step)")
    p.add_argument("--fps", type=float, help="resample to this frame rate (24, 25, 30, 60 ...)")
    p.add_argument("--out", help="trajectory CSV to write")
    p.add_argument("--plot", help="PNG of the track, lean, curvature and phase diagram")
    add_terrain_flags(p)
    p.set_defaults(func=run)


def _flag(name: str, value, key: str | Range, deg: bool = False) -> float:
    """The flag ``--name``'s value checked against ``RANGES[key]`` or the range ``key`` (in
    degrees if ``deg``)."""
    rng = RANGES[key] if isinstance(key, str) else key
    rng = rng.deg() if deg else rng
    return check(f"--{name.replace('_', '-')}", value, rng)


def _default_heading(terrain) -> float:
    """The heading without ``--heading-deg``, deg: down the fall line of a plane when a target
    speed controls the speed (the turns brake about the fall line, docs/skidding.md), else 0."""
    ground = terrain.get("ground")
    if "target_speed" in terrain and isinstance(ground, Plane):
        return math.degrees(ground.downhill)
    return 0.0


def run(args) -> int:
    overrides = {field: _flag(flag, getattr(args, flag), field)
                 for flag, field in BODY_FLAGS.items() if getattr(args, flag) is not None}
    fig = preset(args.preset, **overrides)
    duration = _flag("duration", args.duration, "duration")
    dt = _flag("dt", args.dt, "dt")
    if args.fps is not None:
        _flag("fps", args.fps, "fps")
    check_steps(duration, dt, args.fps)
    if args.plot:
        require_matplotlib("--plot")
    terrain = terrain_options(args, fig.name)
    leans = lean_range(fig.limits.theta_fall, f"the {fig.name}")   # the preset's fall angle

    if args.schedule:
        given = [f for f in ("period", "omega0", "lean_deg", "heading_deg")
                 if getattr(args, f) is not None]
        if given:
            raise ValueError(f"--schedule replaces --{given[0].replace('_', '-')}; give one or "
                             "the other")
        sched = read_schedule_csv(args.schedule, leans)
        omega0, theta_max = sched.omega0, sched.theta_max
        # No heading_deg column: the heading is held at 0 deg, as without --heading-deg.
        heading = sched.heading or Schedule.constant(0.0)
    x0, y0 = start_point(args, terrain.get("ground"))
    rounds = None
    if not args.schedule:
        if args.omega0 is not None:
            w = _flag("omega0", args.omega0, "omega0")
        else:
            w = 2 * math.pi / _flag("period", 2.0 if args.period is None else args.period,
                                    "period")
        lean = math.radians(_flag("lean_deg", 23.0 if args.lean_deg is None else args.lean_deg,
                                  leans, deg=True))
        head = _flag("heading_deg", _default_heading(terrain) if args.heading_deg is None
                     else args.heading_deg, "heading", deg=True)
        rounds = _round_turns(args, fig, terrain, x0, y0)
        if rounds is not None:                # speed control's own turns (docs/skidding.md)
            w, lean = rounds.omega0, rounds.theta_max
        omega0, theta_max = Schedule.constant(w), Schedule.constant(lean)
        heading = Schedule.constant(math.radians(head))

    record = CONTROLLERS.lookup(args.controller)
    ctl = record.make(fig, omega0, theta_max, heading, args.law)
    w0, tm0 = ctl.target(0.0)           # the ellipse followed (made feasible for the figure)
    theta0 = math.radians(_flag("theta0_deg", args.theta0_deg or 0.0, "theta_v0", deg=True))
    straight = record.start == "straight"
    omega_v0 = (w0 * tm0 * (not straight) if args.omega_v0_deg is None else
                math.radians(_flag("omega_v0_deg", args.omega_v0_deg, "omega_v0", deg=True)))
    outputs = Outputs()                       # every output path checked before the work
    outputs.reserve("--out", args.out)
    outputs.reserve("--plot", args.plot)
    # Start so that the slalom is centred on the heading (with the lean and rate asked for;
    # round turns at the bottom of their swing on the slope); a straight run starts on the
    # heading.
    state0 = ((x0, y0, heading(0.0)) if straight else
              rounds.start(heading(0.0), fig.body.V_cm, x0, y0)[:3] if rounds is not None else
              slalom_start(fig.body, w0, tm0, heading(0.0), x0, y0)[:3]) + (theta0, omega_v0)
    traj = simulate(fig, ctl, duration, dt, state0, meta={"controller": args.controller},
                    **terrain)
    if "grip_limited" in traj.meta:
        print(f"simulate: warning: {traj.meta['grip_limited']}", file=sys.stderr)
    if args.fps:
        traj = traj.resample(args.fps, ground=terrain.get("ground"))
    if args.plot:
        from ..figures.plots import plot_trajectory
        outputs.write("--plot", lambda path: plot_trajectory(traj, path, title=(
            f"{fig.name}, {args.controller} controller")))
    if args.out:
        outputs.write("--out", traj.to_csv)
    outputs.commit()
    print(f"simulate: {fig.name}, {args.controller}, {traj.duration:.2f} s, {len(traj)} samples"
          f"{f' at {args.fps:g} fps' if args.fps else ''}; lean max "
          f"{math.degrees(abs(traj.theta_v).max()):.1f} deg, |C_f| max "
          f"{abs(traj.C_f).max():.3f} 1/m, distance {traj.s[-1]:.1f} m"
          f"{f', speed {traj.V_cm.min():.1f}-{traj.V_cm.max():.1f} m/s' if terrain else ''}"
          f"{'; turn ' + ctl.report.describe() if getattr(ctl, 'report', None) else ''}"
          f"{_round_summary(rounds)}"
          f"{_skid_summary(traj)}"
          f"{f' -> {args.out}' if args.out else ''}")
    return 0


def _round_turns(args, fig, terrain: dict, x: float, y: float):
    """Speed control's round turns (:func:`..core.controllers.braking.round_turns`) when a
    target speed is held by skidded turns on a slope and no turn was asked for (``--period``,
    ``--omega0``, ``--lean-deg``, ``--schedule``), else ``None``."""
    skid, ground = terrain.get("skidding"), terrain.get("ground")
    if (skid is None or skid.style != "skid" or skid.stop_at is not None or ground is None
            or "target_speed" not in terrain or args.controller != "ellipse"
            or any(getattr(args, f) is not None for f in ("period", "omega0", "lean_deg"))):
        return None
    d = ground.derivatives(x, y)
    slope = math.atan(math.hypot(float(d[1]), float(d[2])))
    if slope <= 0.0:
        return None
    return round_turns(fig, slope, terrain["resistance"], float(terrain["target_speed"]),
                       skid.corridor)


def _round_summary(rounds) -> str:
    """``; round turns 9.9 s / 45 deg`` (speed control chose the turn), else ``""``."""
    if rounds is None:
        return ""
    return (f"; round turns {2 * math.pi / rounds.omega0:.1f} s / "
            f"{math.degrees(rounds.theta_max):.0f} deg")


def _skid_summary(traj) -> str:
    """``; style skid (hard snow), skid max 60 deg, brake max 5.2 m/s^2, stopped at 3.1 s`` for
    a run that brakes at the foot (docs/skidding.md); ``""`` for a carved one."""
    if "style" not in traj.meta:
        return ""
    m = traj.meta
    text = (f"; style {m['style']} ({m['grip.name']} {m['grip']}), skid max "
            f"{math.degrees(abs(traj.skid).max()):.0f} deg, brake max {traj.brake.max():.1f} "
            "m/s^2")
    if "stop_at" in m:
        rest = traj.t[traj.V_cm == 0.0]
        text += f", at rest from {rest[0]:.2f} s" if len(rest) else ", not at rest yet"
    return text

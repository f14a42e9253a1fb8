"""``simulate``: one figure under the open-loop or phase-ellipse controller -> trajectory CSV."""
from __future__ import annotations

import math

from ..core import CONTROLLERS, PRESETS, preset, read_schedule_csv, simulate, slalom_start
from ..core.controllers import PhaseEllipse
from ..core.params import check_range
from ..core.schedule import Schedule
from ..core.simulate import DEFAULT_DT
from .common import atomic_plot, check_out_path, require_matplotlib
from .terrain_flags import add_terrain_flags, terrain_options

# flag -> (BodyParams field, allowed range); the ranges are the core's, named by the flag.
BODY_FLAGS = {"mass": ("m", 0.0, 1e4), "com_height": ("l", 0.0, 10.0),
              "inertia": ("I_v", 0.0, 1e5), "speed": ("V_cm", 0.0, 100.0),
              "gravity": ("g", 0.0, 100.0)}


#: Steps where the rows obey the model to 1e-3 of scale under the trapezoid rule for a 2 s turn
#: ((2 pi dt / period)^2 / 12 <= 1e-3 up to 0.034 s; BENCHMARKS.md "Turn control accuracy").
DT_RANGE = (0.001, 0.03)


def register(sub):
    p = sub.add_parser("simulate", help="simulate a slalom and write its trajectory",
                       description="Simulate one figure (Sections 3-5) and write the trajectory "
                                   "CSV (columns of DESIGN.md, SI units, radians).")
    p.add_argument("--preset", default="skier", choices=sorted(PRESETS))
    p.add_argument("--mass", type=float, help="kg")
    p.add_argument("--com-height", type=float, help="height of the centre of mass, m")
    p.add_argument("--inertia", type=float, help="roll inertia about the centre of mass, kg m^2")
    p.add_argument("--speed", type=float, help="forward speed V_cm, m/s")
    p.add_argument("--gravity", type=float, help="m/s^2")
    p.add_argument("--controller", default="ellipse", choices=sorted(CONTROLLERS))
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
                   help=f"integration step, s ({DT_RANGE[0]:g}-{DT_RANGE[1]:g}; BENCHMARKS.md: "
                        "accuracy per step)")
    p.add_argument("--fps", type=float, help="resample to this frame rate (24, 25, 30, 60 ...)")
    p.add_argument("--out", help="trajectory CSV to write")
    p.add_argument("--plot", help="PNG of the track, lean, curvature and phase diagram")
    add_terrain_flags(p)
    p.set_defaults(func=run)


def _flag(name: str, value, lo, hi, **kw) -> float:
    return check_range(f"--{name.replace('_', '-')}", value, lo, hi, **kw)


def run(args) -> int:
    overrides = {}
    for flag, (field, lo, hi) in BODY_FLAGS.items():
        v = getattr(args, flag)
        if v is not None:
            overrides[field] = _flag(flag, v, lo, hi, lo_open=(flag != "inertia"))
    fig = preset(args.preset, **overrides)
    duration = _flag("duration", args.duration, 0.0, 1e5, lo_open=True)
    dt = _flag("dt", args.dt, *DT_RANGE)
    if args.fps is not None:
        _flag("fps", args.fps, 0.0, 1000.0, lo_open=True)
    check_out_path("--out", args.out)
    check_out_path("--plot", args.plot)
    if args.plot:
        require_matplotlib("--plot")
    terrain = terrain_options(args, fig.name)

    if args.schedule:
        given = [f for f in ("period", "omega0", "lean_deg", "heading_deg")
                 if getattr(args, f) is not None]
        if given:
            raise ValueError(f"--schedule replaces --{given[0].replace('_', '-')}; give one or "
                             "the other")
        sched = read_schedule_csv(args.schedule)
        omega0, theta_max, heading = sched.omega0, sched.theta_max, sched.heading
    else:
        if args.omega0 is not None:
            w = _flag("omega0", args.omega0, 0.0, 1e3, lo_open=True)
        else:
            w = 2 * math.pi / _flag("period", 2.0 if args.period is None else args.period,
                                    0.0, 1e3, lo_open=True)
        lean = _flag("lean_deg", 23.0 if args.lean_deg is None else args.lean_deg, 0.0, 90.0,
                     lo_open=True, hi_open=True)
        head = _flag("heading_deg", 0.0 if args.heading_deg is None else args.heading_deg,
                     -3600.0, 3600.0)
        omega0, theta_max = Schedule.constant(w), Schedule.constant(math.radians(lean))
        heading = Schedule.constant(math.radians(head))

    if args.controller == "ellipse":
        ctl = PhaseEllipse(fig.body, omega0, theta_max, heading, law=args.law, limits=fig.limits)
    else:
        ctl = CONTROLLERS[args.controller](fig.body, omega0, theta_max)
    w0, tm0 = ctl.target(0.0)           # the ellipse followed (made feasible for the figure)
    theta0 = math.radians(_flag("theta0_deg", args.theta0_deg or 0.0, -90.0, 90.0,
                                lo_open=True, hi_open=True))
    straight = args.controller == "straight"
    omega_v0 = (w0 * tm0 * (not straight) if args.omega_v0_deg is None else
                math.radians(_flag("omega_v0_deg", args.omega_v0_deg, -1e4, 1e4)))
    # Start so that the slalom is centred on the heading (with the lean and rate asked for);
    # a straight run starts on the heading.
    state0 = ((0.0, 0.0, heading(0.0)) if straight else
              slalom_start(fig.body, w0, tm0, heading(0.0))[:3]) + (theta0, omega_v0)
    traj = simulate(fig, ctl, duration, dt, state0, meta={"controller": args.controller},
                    **terrain)
    if args.fps:
        traj = traj.resample(args.fps, ground=terrain.get("ground"))
    if args.plot:
        from ..figures.plots import plot_trajectory
        atomic_plot(args.plot, lambda path: plot_trajectory(traj, path, title=(
            f"{fig.name}, {args.controller} controller")))
    if args.out:
        traj.to_csv(args.out)
    print(f"simulate: {fig.name}, {args.controller}, {traj.duration:.2f} s, {len(traj)} samples"
          f"{f' at {args.fps:g} fps' if args.fps else ''}; lean max "
          f"{math.degrees(abs(traj.theta_v).max()):.1f} deg, |C_f| max "
          f"{abs(traj.C_f).max():.3f} 1/m, distance {traj.s[-1]:.1f} m"
          f"{f', speed {traj.V_cm.min():.1f}-{traj.V_cm.max():.1f} m/s' if terrain else ''}"
          f"{'; turn ' + ctl.achieved.describe() if getattr(ctl, 'achieved', None) else ''}"
          f"{f' -> {args.out}' if args.out else ''}")
    return 0

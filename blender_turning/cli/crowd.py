"""``crowd``: many figures in one shot from a crowd scene file (docs/crowds.md).

Writes ``DIR/<figure>.csv`` per figure (the trajectory columns of docs/ARCHITECTURE.md Section 3,
``t`` on the crowd's clock) and ``DIR/summary.json``.  Parametric figures run as batches here; path
figures are planned one task
each (those in the crowd's ``priority``: one task per independent group) on ``--workers K``
local processes or a Dask scheduler (``--scheduler ADDRESS``).  A figure
that falls or finds no feasible plan is written up to there, listed in the summary, and makes
the command end with one line and exit 2.  A worker that dies ends the command with one line
naming the figures it ran, nothing written, exit 1; with ``--keep-going`` the other figures are
written and the lost ones listed in the summary (still exit 1).  ``--out`` is locked for the run
(``DIR/.turning.lock``): a second crowd on the same folder is refused, naming the first.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

from ..core.controllers.feasible import TURN_KEY, TurnsFollowed
from ..core.errors import WorkerLost
from ..core.files import OutputLock
from ..core.physics.params import check_range
from ..core.ranges import MAX_SAMPLES
from ..crowd import load_crowd, run_crowd
from ..crowd.runner import check_scheduler_address
from ..core.course.moving import MovingBodies, closest_approach
from .common import Outputs
from .progress import Progress


def register(sub):
    p = sub.add_parser("crowd", help="many figures: formations, batches, parallel planning",
                       description="Simulate and plan every figure of a crowd scene file; one "
                                   "trajectory CSV per figure plus summary.json.")
    p.add_argument("scene", help="crowd scene JSON file (see docs/crowds.md)")
    p.add_argument("--out", required=True, help="folder for the CSVs and summary.json")
    engine = p.add_mutually_exclusive_group()
    engine.add_argument("--workers", type=int, default=1,
                        help="local worker processes for path planning (default 1: this one)")
    engine.add_argument("--scheduler", help="address of a running Dask distributed scheduler "
                                            "(tcp://host:8786), needs the cluster extra")
    p.add_argument("--fps", type=float, help="write frames at this rate (default: the samples)")
    p.add_argument("--keep-going", action="store_true",
                   help="when a worker dies, write the other figures (and list the lost ones "
                        "in summary.json) rather than nothing; the exit status is 1 either way")
    p.set_defaults(func=run)


def run(args) -> int:
    check_range("--workers", args.workers, 1, 1024)
    if args.scheduler is not None:
        check_scheduler_address(args.scheduler)
    if args.fps is not None:
        check_range("--fps", args.fps, 0.0, 1000.0, lo_open=True)
    crowd = load_crowd(args.scene)
    if args.fps is not None and crowd.duration * args.fps > MAX_SAMPLES:
        raise ValueError(f"--fps {args.fps:g} x duration {crowd.duration:g} s is more than "
                         f"{MAX_SAMPLES:,} frames a figure")
    if not args.out.strip():
        raise ValueError(f"--out = {args.out!r} is not a folder path")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out = {args.out!r} is a file, not a folder")
    made = not out.exists()
    if made and not out.parent.resolve().is_dir():
        raise ValueError(f"--out = {args.out!r}: the folder {str(out.parent.resolve())!r} "
                         f"does not exist")
    try:
        out.mkdir(exist_ok=True)
    except OSError as exc:
        raise ValueError(f"--out = {args.out!r} cannot be created: "
                         f"{exc.strerror or exc}") from None
    try:
        with OutputLock(out, "--out", "crowd"):
            return _run(args, crowd, out)
    finally:
        if made:
            try:
                out.rmdir()                   # only if nothing was written into it
            except OSError:
                pass


def _run(args, crowd, out: Path) -> int:
    outputs = Outputs()
    try:
        return _write(args, crowd, out, outputs)
    except BaseException:         # the hidden files go before the folder made for them does
        outputs.discard()
        raise


def _write(args, crowd, out: Path, outputs: Outputs) -> int:
    try:                                      # every file checked before the work
        for f in crowd.figures:
            outputs.reserve(f"--out {f.name}.csv", out / f"{f.name}.csv")
        outputs.reserve("--out summary.json", out / "summary.json")
        with Progress(len(crowd.figures), "figure", "crowd") as bar:
            result = run_crowd(crowd, workers=args.workers, scheduler=args.scheduler,
                               progress=bar, keep_going=args.keep_going)
    except WorkerLost as exc:
        raise WorkerLost(f"{exc}; nothing written (--keep-going writes the other figures)",
                         exc.figures) from None
    tracks = [(f.name, r.trajectory, f.figure.body.l) for f, r in zip(crowd.figures,
                                                                    result.figures)]
    near = closest_approach(MovingBodies.from_tracks(tracks, dt=0.1)) \
        if any(tr is not None and len(tr) for _, tr, _ in tracks) else {}
    rows = []
    for f, r in zip(crowd.figures, result.figures):
        traj = r.trajectory
        if traj is not None and args.fps is not None and len(traj) > 1:
            traj = traj.resample(args.fps, start=math.ceil(traj.t[0] * args.fps) / args.fps)
        csv = None
        if traj is not None and len(traj):
            csv = f"{f.name}.csv"
            outputs.write(f"--out {csv}", traj.to_csv)
        rows.append(_row(f, r, traj, csv))
        if f.name in near:           # foot-CM segments sampled every 0.1 s (core/course/moving.py)
            d, other, t = near[f.name]
            rows[-1]["closest"] = {"distance_m": d if math.isfinite(d) else None,
                                   "to": other, "t": t}
    doc = {"crowd": crowd.name, "seed": crowd.seed, "duration": crowd.duration, "dt": crowd.dt,
           "priority": list(crowd.priority), "clearance": crowd.clearance,
           "fps": args.fps, "figures": rows, "failed": [r.name for r in result.failed],
           "wall_time": result.wall_time,
           "engine": {"workers": args.workers, "scheduler": args.scheduler}}
    text = json.dumps(doc, indent=1)
    outputs.write("--out summary.json", lambda path: path.write_text(text))
    outputs.commit(only=[f"--out {f.name}.csv" for f, row in zip(crowd.figures, rows)
                         if row["csv"]] + ["--out summary.json"])
    n_path = sum(f.is_path for f in crowd.figures)
    print(f"crowd: {crowd.name}, {len(crowd.figures)} figures ({n_path} following paths), "
          f"{result.wall_time:.2f} s -> {out}")
    limited = [(row["name"], row["lean_report"]) for row in rows if "lean_report" in row]
    for name, note in limited[:LEAN_LINES]:
        print(f"crowd: {name}: {note}")
    if len(limited) > LEAN_LINES:
        print(f"crowd: {len(limited) - LEAN_LINES} more figures lean less than asked "
              f"({out / 'summary.json'}, lean_report)")
    lost = [r.name for r in result.figures if r.status == "lost"]
    if lost:
        raise WorkerLost(f"a worker process died while it ran {len(lost)} figure"
                         f"{'s' if len(lost) > 1 else ''} ({', '.join(lost[:5])}"
                         f"{' ...' if len(lost) > 5 else ''}); the other "
                         f"{len(crowd.figures) - len(lost)} written to {out} (see "
                         f"{out / 'summary.json'})", lost)
    if result.failed:
        first = result.failed[0]
        raise ValueError(f"{len(result.failed)} of {len(crowd.figures)} figures failed (see "
                         f"{out / 'summary.json'}); {first.name}: {first.message}")
    return 0


#: Figures whose limited lean the command prints (all are in summary.json's ``lean_report``).
LEAN_LINES = 10


def _row(f, r, traj, csv) -> dict:
    row = {"name": f.name, "preset": f.figure.name, "controller": "path" if f.is_path else
           "turns", "time_offset": f.time_offset, "status": r.status, "message": r.message,
           "csv": csv, "cpu_time": r.cpu_time,
           "body": {"m": f.figure.body.m, "l": f.figure.body.l, "I_v": f.figure.body.I_v,
                    "V_cm": f.figure.body.V_cm}}
    if not f.is_path:
        c = f.controller
        row["turns"] = {"period": c.period, "lean_deg": math.degrees(c.lean),
                        "heading_deg": None if c.heading is None else math.degrees(c.heading),
                        "first_turn": f.first_turn}
    if traj is not None and len(traj):
        row.update(t_start=float(traj.t[0]), t_end=float(traj.t[-1]), samples=len(traj),
                   distance=float(traj.s[-1]),
                   lean_max_deg=math.degrees(float(abs(traj.theta_v).max())))
    turn = None if r.trajectory is None else r.trajectory.meta.get(TURN_KEY)
    if turn is not None:              # the lean reached where the bounds kept it below the asked
        row["lean_report"] = TurnsFollowed.from_dict(turn).describe()
    if r.plan:
        row["plan"] = r.plan
    return row

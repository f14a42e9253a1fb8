"""Benchmark: Live Preview's latency per drag step, against today's way (Bake Turns), in one run.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_live.py [--steps 15] [--only skier-10]
        [--ways drag]      # some of the three ways only (a user rig's Bake Turns takes seconds)
    PYTHONPATH=$PWD .venv/bin/python scripts/bench_live.py --profile rigify-60   # cProfile
    PYTHONPATH=$PWD .venv/bin/python scripts/bench_live.py --parts    # where a drag step goes
    PYTHONPATH=$PWD .venv/bin/python scripts/bench_live.py --capture calls.pkl --frame end
        # the core's simulate calls of drag steps, for scripts/bench_drag_replay.py (no bpy)

Each case is one figure with Live Preview on, the current frame in the middle of the range
(``--frame end``: the last frame, the dearest: a drag step simulates from the first frame to
just past the frames around the current one, which it re-bakes first); a drag step sets its
slider (``turning.lean``, or for the Body cases ``turning.mass``) a little further and
re-bakes.  Timed, median of ``--steps``
steps (in ms) and the largest (a step that builds feasibility tables stands out), the three
ways interleaved step by step (the machine is shared), and the feasibility tables built over
the steps (a deterministic count):

- ``bake op``: today's figure, ``bpy.ops.turning.bake_turns()`` after the set (curves made anew,
  the foot track, an undo step);
- ``refresh op``: ``bpy.ops.turning.refresh_preview()`` after the set (what a script does);
- ``drag step``: :func:`blender_turning.blender.jobs.live.schedule`, what the message bus calls at
  every step of a slider drag in the interface (the keys; the foot track waits for the release).

Cases: the built-in skier, a Rigify rig as a skier, a cyclist on a 200 m x 200 m Ground mesh
(1 m grid, the rolls of ``ski_slope`` without its slope), each over 10 s and 60 s at 24 fps, and
a Body slider (mass) on the built-in skier (10 s) and on the cyclist on the Ground mesh (10 s and
60 s), and the COM Height on the latter (60 s).
"""
from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
for p in (ROOT, ROOT / "tests"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-bench-"))

import bpy  # noqa: E402

from blender_turning import blender as addon  # noqa: E402
from blender_turning.blender.jobs import live  # noqa: E402

CASES = ("skier-10", "skier-60", "rigify-10", "rigify-60", "cyclist-ground-10",
         "cyclist-ground-60", "body-skier-10", "body-ground-10", "body-ground-60",
         "height-ground-60")


def select(fig):
    for o in bpy.context.view_layer.objects:
        o.select_set(o == fig)
    bpy.context.view_layer.objects.active = fig


def build():
    """The three figures (live off), by kind."""
    from blender_turning.blender.scene.ground import mesh_from_height_field
    from blender_turning.core.ground.terrain_gen import ski_slope
    from rig_fixtures import rigify_rig
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start = 24, 1
    figs = {}
    scene.cursor.location = (0.0, 0.0, 0.0)
    bpy.ops.turning.add_figure(sport="SKIER")
    figs["skier"] = bpy.context.view_layer.objects.active
    rig = rigify_rig(location=(0.0, 400.0, 0.0))
    select(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER", bone_map="RIGIFY") == {"FINISHED"}
    figs["rigify"] = rig
    slope = ski_slope(length=200.0, width=200.0, slope_deg=0.0, cell=1.0)
    mountain = bpy.data.objects.new("Mountain", mesh_from_height_field(bpy, slope, "Mountain"))
    scene.collection.objects.link(mountain)
    scene.cursor.location = (-95.0, 10.0, 0.0)
    scene.cursor.rotation_euler = (0.0, 0.0, math.radians(-90.0))    # facing +x
    bpy.ops.turning.add_figure(sport="CYCLIST")
    cyc = bpy.context.view_layer.objects.active
    cyc.turning.ground = mountain
    # 4 deg: it rolls the 60 s to the mesh's far side at every lean the drag reaches (4 down
    # to 3.4 deg, measured); at 5 deg it falls at 35 s, and a step that fails is no re-bake.
    cyc.turning.speed, cyc.turning.period, cyc.turning.lean = 3.0, 3.0, math.radians(4.0)
    figs["cyclist-ground"] = cyc
    return figs


#: Where the current frame stands (``--frame``): a drag step simulates from the first frame to
#: just past it, so the last frame is the dearest.
AT = {"middle": 0.5, "end": 1.0}
_at = ["middle"]


def case_setup(name, figs):
    """``(figure, setting, values)`` of a case, the scene's range set."""
    parts = name.split("-")
    seconds = int(parts[-1])
    scene = bpy.context.scene
    scene.frame_end = 1 + 24 * seconds
    scene.frame_set(1 + round(AT[_at[0]] * 24 * seconds))   # the current frame (--frame)
    if parts[0] == "body":
        fig = figs["skier" if parts[1] == "skier" else "cyclist-ground"]
        return fig, "mass", [75.0 + 0.25 * k for k in range(400)]
    if parts[0] == "height":                   # 0.5 % a step: past 2 % every fourth or fifth
        return figs["cyclist-ground"], "com_height", [1.0 + 0.005 * k for k in range(400)]
    fig = figs["-".join(parts[:-1])]
    base = math.degrees(fig.turning.lean)
    # The cyclist on the Ground mesh's rolls falls at some leans a little above 4 deg: dragged
    # down from there.
    sign = -1.0 if parts[0] == "cyclist" else 1.0
    return fig, "lean", [math.radians(base + sign * 0.01 * k) for k in range(400)]


def bake_op():
    try:
        bpy.ops.turning.bake_turns()
    except RuntimeError:                   # a fall: reported, nothing written
        pass


WAYS = ("bake", "refresh", "drag")


def run_case(name, figs, steps, ways=WAYS):
    fig, setting, values = case_setup(name, figs)
    for f in figs.values():
        f.turning.live = f == fig
    select(fig)
    bake_op()
    bpy.ops.turning.refresh_preview()            # the first live bake: in place from here on
    ways = {k: fn for k, fn in (("bake op", bake_op),
                                ("refresh op", lambda: bpy.ops.turning.refresh_preview()),
                                ("drag step", live.schedule)) if k.split()[0] in ways}
    times = {k: [] for k in ways}
    cpu = {k: [] for k in ways}
    built = dict.fromkeys(ways, 0j)
    nodes = dict.fromkeys(ways, 0)
    k, failed = 0, []
    for _ in range(steps):
        for way, fn in ways.items():
            k += 1
            setattr(fig.turning, setting, values[k])
            n, m = tables_built(), preview_nodes()
            t, c = time.perf_counter(), time.process_time()
            fn()
            times[way].append(time.perf_counter() - t)
            cpu[way].append(time.process_time() - c)
            built[way] += tables_built() - n
            nodes[way] += preview_nodes() - m
            if fig.name in live.FAILURES:
                failed.append(live.FAILURES[fig.name].message)
    if failed:                             # a step that fails re-bakes nothing: not a measure
        print(f"{name}: {len(failed)} of {k} steps failed: {failed[-1]}")
    if bpy.app.timers.is_registered(live._tick):
        bpy.app.timers.unregister(live._tick)
    live.settle()
    setattr(fig.turning, setting, values[0])
    fig.turning.live = False
    return ({way: 1000 * statistics.median(v) for way, v in times.items()},
            {way: 1000 * statistics.median(v) for way, v in cpu.items()},
            {way: 1000 * max(v) for way, v in times.items()},
            {way: 1000 * max(v) for way, v in cpu.items()}, built, nodes)


def tables_built():
    """Feasibility tables built so far (:func:`...core.controllers.feasible.feasible_turns`):
    whole ones and a drag step's own (``PreviewTurns``, solved where asked), as a complex
    number to be summed (real: whole, imaginary: preview)."""
    from blender_turning.core.controllers import feasible
    return complex(feasible._feasible_turns.cache_info().misses,
                   len(getattr(feasible, "_PREVIEWS", ())))


def preview_nodes():
    """The frequencies the drag steps' own tables solved so far (of 256 a table)."""
    from blender_turning.core.controllers import feasible
    return sum(sum(t._solved) for t in getattr(feasible, "_PREVIEWS", {}).values())


def run_parts(name, figs, steps):
    """CPU ms of a drag step's parts, median of ``steps``: the simulation, the mapping (and a
    user rig's retarget), writing the keys, and the whole step."""
    from blender_turning.blender.anim import bake
    from blender_turning.blender.jobs import pipeline
    fig, setting, values = case_setup(name, figs)
    for f in figs.values():
        f.turning.live = f == fig
    select(fig)
    bpy.ops.turning.refresh_preview()
    spent = {}
    wrapped = [(pipeline, "simulate_figure", "sim"), (pipeline, "map_track", "map"),
               (bake, "rewrite_pose_track", "keys")]
    real = [getattr(mod, attr) for mod, attr, _ in wrapped]

    def timed(fn, part):
        def call(*a, **k):
            c = time.process_time()
            try:
                return fn(*a, **k)
            finally:
                spent[part] = spent.get(part, 0.0) + time.process_time() - c
        return call

    rows = []
    try:
        for (mod, attr, part), fn in zip(wrapped, real):
            setattr(mod, attr, timed(fn, part))
        for k in range(1, steps + 1):
            setattr(fig.turning, setting, values[k])
            spent.clear()
            c = time.process_time()
            live.schedule()
            rows.append({**spent, "step": time.process_time() - c})
    finally:
        for (mod, attr, _), fn in zip(wrapped, real):
            setattr(mod, attr, fn)
    if bpy.app.timers.is_registered(live._tick):
        bpy.app.timers.unregister(live._tick)
    live.settle()
    setattr(fig.turning, setting, values[0])
    fig.turning.live = False
    return {part: 1000 * statistics.median(r.get(part, 0.0) for r in rows)
            for part in ("sim", "map", "keys", "step")}


def capture(name, figs, leans, path):
    """Pickle the core's ``simulate(...)`` calls of one drag step at each of ``leans`` (deg) of
    case ``name`` (the figure, the controller's constant inputs, the ground's height field, the
    arguments) for ``scripts/bench_drag_replay.py``; returns how many."""
    import pickle
    from blender_turning.blender.jobs import pipeline
    fig, setting, _ = case_setup(name, figs)
    if setting != "lean":
        raise SystemExit(f"--capture drags the Lean: {name} drags the {setting}")
    for f in figs.values():
        f.turning.live = f == fig
    select(fig)
    bpy.ops.turning.refresh_preview()
    calls, real = [], pipeline.simulate

    def record(figure, controller, duration, dt, **kwargs):
        inputs = {k: None if s is None else s.constant_value for k, s in (
            ("omega0", controller.omega0), ("theta_max", controller.theta_max),
            ("heading", controller.heading))}
        if inputs["omega0"] is None or inputs["theta_max"] is None or (
                controller.heading is not None and inputs["heading"] is None):
            raise SystemExit("--capture replays constant turn settings only (none keyed)")
        calls.append({"figure": figure, **inputs, "duration": duration, "dt": dt,
                      "nearby": live.NEARBY_BODY,
                      "kwargs": {k: v for k, v in kwargs.items() if k != "meta"}})
        return real(figure, controller, duration, dt, **kwargs)

    pipeline.simulate = record
    try:
        for lean in leans:
            fig.turning.lean = math.radians(lean)
            live.schedule()
    finally:
        pipeline.simulate = real
        if bpy.app.timers.is_registered(live._tick):
            bpy.app.timers.unregister(live._tick)
        live.settle()
        fig.turning.live = False
    with open(path, "wb") as f:
        pickle.dump(calls, f)
    return len(calls)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=15)
    ap.add_argument("--only", nargs="*", choices=CASES, default=None)
    ap.add_argument("--ways", nargs="*", choices=WAYS, default=WAYS)
    ap.add_argument("--profile", choices=CASES, help="cProfile 20 drag steps of one case")
    ap.add_argument("--frame", choices=tuple(AT), default="middle",
                    help="the current frame: the middle of the range or its last frame")
    ap.add_argument("--parts", action="store_true",
                    help="CPU ms of each drag step's simulation, mapping and keys")
    ap.add_argument("--capture", metavar="PKL",
                    help="pickle the simulate calls of the drag steps to --leans of one case "
                         "(--only, default cyclist-ground-60) for scripts/bench_drag_replay.py")
    ap.add_argument("--leans", nargs="*", type=float,
                    default=[3.4, 3.6, 3.8, 3.9, 3.95, 3.99], help="deg, with --capture")
    args = ap.parse_args(argv)
    _at[0] = args.frame
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    try:
        figs = build()
        if args.profile:
            import cProfile
            import pstats
            fig, setting, values = case_setup(args.profile, figs)
            fig.turning.live = True
            select(fig)
            bpy.ops.turning.refresh_preview()
            prof = cProfile.Profile()
            for k in range(1, 21):
                setattr(fig.turning, setting, values[k])
                prof.runcall(live.schedule)
            pstats.Stats(prof).sort_stats("cumulative").print_stats(30)
            return
        if args.capture:
            name = (args.only or ["cyclist-ground-60"])[0]
            n = capture(name, figs, args.leans, args.capture)
            print(f"{name}, current frame {args.frame}: {n} simulate calls in {args.capture}")
            return
        print(f"current frame: {args.frame} of the range")
        print(f"machine: {platform.machine()}, {os.cpu_count()} cores, load average "
              f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}, Python "
              f"{platform.python_version()}, bpy {bpy.app.version_string}")
        if args.parts:
            print(f"CPU ms per drag step, median of {args.steps}: simulation, mapping (and "
                  "retarget), keys, the whole step")
            for name in args.only or CASES:
                parts = run_parts(name, figs, args.steps)
                print(f"{name:20s} " + " ".join(f"{k} {v:6.1f}" for k, v in parts.items()),
                      flush=True)
            return
        print(f"ms per drag step of {args.steps} (24 fps; goal <= 40 ms), median and largest: "
              "wall (CPU); the feasibility tables built over the steps: whole + preview "
              "(the previews' frequencies solved)")
        heads = {"bake": "bake op", "refresh": "refresh op", "drag": "drag step"}
        print(f"{'case':20s} " + " ".join(f"{heads[w] + ' median':>15s} {'max':>15s} tables"
                                          for w in WAYS if w in args.ways))
        for name in args.only or CASES:
            wall, cpu, top, top_cpu, built, nodes = run_case(name, figs, args.steps, args.ways)
            print(f"{name:20s} " + " ".join(
                f"{wall[w]:7.1f} ({cpu[w]:5.1f}) {top[w]:7.1f} ({top_cpu[w]:5.1f}) "
                f"{built[w].real:3.0f}+{built[w].imag:.0f} ({nodes[w]})" for w in wall),
                flush=True)
        print(f"load average after: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    finally:
        addon.unregister()


if __name__ == "__main__":
    main()

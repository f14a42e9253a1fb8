"""Headless job: build a scene from a TOML config, bake the figures, save a .blend, render.

    blender -b --python scripts/render_job.py -- --config scripts/configs/demo.toml
    python scripts/render_job.py --config scripts/configs/demo.toml      # on the bpy wheel

The scene: a ground plane, the figures (each baked with the parametric controller, ``control =
"turns"``, or along a path around obstacles, ``control = "path"``), the path curves, the obstacle
objects, a camera that follows the figures and a sun.  Frames go to ``<output>/frames/`` (PNG) or
``<output>/<name>.mp4`` (``format = "VIDEO"``); the scene to ``<output>/<name>.blend``.  A bad
config exits with status 2 and one line naming the problem; a failed bake with status 1.
See ``scripts/configs/*.toml`` for the format.

On a render farm: bake once, then render chunks with plain ``blender -b job.blend -s A -e B -a``
on any farm::

    blender -b --python scripts/render_job.py -- --config job.toml --no-render --output shared/job
    blender -b shared/job/job.blend -s 1 -e 24 -a          # one farm task per chunk of frames

The saved .blend holds its output path relative to itself (``//frames/frame_``), so it can move
to the farm's storage and its frames land next to it.  ``--frames A-B`` renders one chunk of the
job's frames (after saving the whole range in the .blend); ``--device GPU`` renders Cycles on the
GPU and fails with one line (exit 2) where Cycles finds none -- no silent CPU fallback, which
would make a farm task tens of times slower unnoticed.  ``scripts/flamenco/
turning_bake_render.js`` is a Flamenco job type doing the bake once and then the chunks.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ...core import signals
from ...core.files import OutputLock, OutputLocked, WriteError, disk_reason
from ...core.registry import import_extension
from . import crowds, terrain
from .build import (_material, add_figure, bake_figure, make_camera, make_ground_and_light,
                    make_obstacles, make_path, setup_render, use_gpu)
from .config import ConfigError, load_config
from .output import (KEPT, _check_and_place, _staged, log, render_frames, render_video,
                     save_blend)


def run(cfg, render: bool = True) -> dict:
    import bpy
    from ... import blender as addon
    if hasattr(bpy.types.Object, "turning"):     # the installed extension is enabled: use it
        return _run(bpy, cfg, render)
    addon.register()
    try:
        return _run(bpy, cfg, render)
    finally:
        # Unregister what the job registered (bpy 4.2 crashes at exit on a registered
        # PointerProperty otherwise).
        addon.unregister()


def _run(bpy, cfg, render):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if cfg["render"]["device"] == "GPU":        # before the bake: fail fast, nothing written
        log(f"Cycles renders on the GPU ({use_gpu(bpy)})")
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = cfg["fps"], 1.0
    scene.frame_start = 1
    frame_end = 1 + int(round(cfg["seconds"] * cfg["fps"]))
    scene.frame_end = frame_end
    paths = {name: make_path(bpy, name, pts) for name, pts in cfg["paths"].items()}
    groups = make_obstacles(bpy, cfg["obstacles"])
    grounds = {name: terrain.make_terrain(bpy, name, spec, _material)
               for name, spec in cfg["terrain"].items()}
    figures = []
    for fig in cfg["figures"]:
        obj = add_figure(bpy, fig, cfg, paths, groups, grounds)
        bake_figure(bpy, obj, fig, frame_end)
        signals.checkpoint()                     # a signal during the bake stops here
        figures.append(obj)
        spec = cfg["terrain"].get(fig["ground"])
        if spec is not None and spec["surface"] == "snow" and fig["tracks"]:
            terrain.make_tracks(bpy, obj, grounds[fig["ground"]], _material,
                                range(scene.frame_start, frame_end + 1))
    cameras = []
    if cfg["camera"]["follow"] == "each":      # a shot per figure, and one per crowd
        cam = cfg["camera"]
        alone = [o for o, fig in zip(figures, cfg["figures"]) if fig["crowd"] is None]
        cameras = terrain.make_follow_cameras(bpy, alone, cam["distance"], cam["height"],
                                              cam["lens"])
        cameras += crowds.make_crowd_cameras(bpy, cfg["crowds"], figures, cam["distance"],
                                             cam["height"], cam["lens"])
        scene.camera = cameras[0][1]
    else:
        locs = make_camera(bpy, cfg, figures)
    if grounds:
        terrain.light_the_snow(bpy)
    else:
        make_ground_and_light(bpy, cfg, locs, figures)
    setup_render(bpy, cfg)
    out = cfg["output"]
    out.mkdir(parents=True, exist_ok=True)
    blend = out / f"{cfg['name']}.blend"
    save_blend(bpy, blend)
    KEPT.append(blend)
    log(f"saved {blend}")
    signals.checkpoint()
    result = {"blend": blend, "frames": None}
    if not render:
        return result
    if cfg["frames"] is not None:               # one chunk; the .blend keeps the whole range
        scene.frame_start, scene.frame_end = cfg["frames"]
    frames = list(range(scene.frame_start, scene.frame_end + 1, scene.frame_step))
    shots = [(None, scene.camera)] if not cameras else cameras
    t = time.perf_counter()
    count = [0, len(frames) * len(shots)]
    for i, (name, cam) in enumerate(shots, 1):  # one shot per figure, each in its own folder
        scene.camera = cam
        if name is not None:                    # a crowd's shot: its own anti-aliasing
            crowd = any(c["name"] == name for c in cfg["crowds"])
            scene.display.render_aa = cfg["render"]["crowd_antialiasing" if crowd
                                                    else "antialiasing"]
        if cfg["render"]["format"] == "VIDEO":
            render_video(bpy, out / (f"{cfg['name']}.mp4" if name is None
                                     else f"{cfg['name']}_{name}.mp4"))
            count[0] += len(frames)
        else:
            render_frames(bpy, out / "frames" if name is None else out / "frames" / name,
                          frames, count)
        if len(shots) > 1:
            log(shot_progress(i, len(shots), name, count[0], count[1], time.perf_counter() - t))
    log(f"rendered {count[0]} frames with {cfg['render']['engine']} in "
        f"{time.perf_counter() - t:.1f} s")
    result["frames"] = (out / f"{cfg['name']}.mp4" if cfg["render"]["format"] == "VIDEO"
                        else out / "frames")
    if cameras and cfg["render"]["format"] == "PNG":
        shots = [sorted((out / "frames" / name).glob("frame_*.png")) for name, _ in cameras]
        middle = [s[len(s) // 2] for s in shots if s]
        if middle:
            sheet = out / "shots.png"
            staged = _staged(sheet)
            try:
                terrain.contact_sheet(bpy, middle, staged)
                _check_and_place(staged, sheet, "the contact sheet")
            finally:
                staged.unlink(missing_ok=True)
            KEPT.append(sheet)
            log(f"shots: {sheet}")
    return result


def shot_progress(shot: int, shots: int, name: str, done: int, total: int, elapsed: float) -> str:
    """The line after shot ``shot`` of ``shots``: frames so far, the time spent and the time left
    at the pace so far (every frame of a job costs about the same)."""
    left = elapsed / done * (total - done) if done else float("nan")
    return (f"shot {shot}/{shots} {name} done: {done}/{total} frames in {elapsed:.0f} s, "
            f"about {left:.0f} s left")


class _Parser(argparse.ArgumentParser):
    def error(self, message):          # one line, exit 2, like every other bad input
        self.exit(2, f"render_job: error: {message}\n")


def parse_args(argv):
    argv = argv[argv.index("--") + 1:] if "--" in argv else argv[1:]
    p = _Parser(prog="render_job.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--config", required=True, type=Path, help="the job's TOML file")
    p.add_argument("--output", help="output folder (overrides job.output)")
    p.add_argument("--engine", help="WORKBENCH, EEVEE or CYCLES (overrides render.engine)")
    p.add_argument("--resolution", help="WIDTHxHEIGHT in pixels (overrides render.resolution)")
    p.add_argument("--seconds", type=float, help="length of the animation (overrides job.seconds)")
    p.add_argument("--frame-step", type=int, help="render every n-th frame (overrides "
                   "job.frame_step)")
    p.add_argument("--no-render", action="store_true", help="build, bake and save only: "
                   "bake once, then render chunks with plain `blender -b job.blend -s A -e B -a` "
                   "on any farm")
    p.add_argument("--frames", help="render only frames A-B of the job (a farm task's chunk)")
    p.add_argument("--farm-frames", help="the frames A-B a farm will render from the baked "
                   ".blend: refused (exit 2, before the bake) unless inside the job's frames")
    p.add_argument("--device", help="CPU or GPU: Cycles' render device (default CPU); GPU fails "
                   "where Cycles finds none")
    p.add_argument("--name", help="the job's name: <output>/<name>.blend (overrides job.name)")
    p.add_argument("--register", action="append", default=[], metavar="MODULE",
                   help="import a module (a .py file or a module name) that registers your own "
                        "sports or formations (docs/registry.md) before the config is read; "
                        "repeatable")
    return p.parse_args(argv)


def main(argv=None) -> int:
    """Exit 0 when every file asked for was written and checked; 2 for a bad config or an
    output another job holds; 1 for a failed bake or write (naming what was not written);
    130 / 143 on SIGINT / SIGTERM (docs/failures.md)."""
    with signals.stop_on_signals():
        KEPT.clear()
        made = []
        try:
            return _main(argv, made)
        except signals.Interrupted as exc:
            print(signals.interrupted_line("render_job", exc, KEPT), file=sys.stderr,
                  flush=True)
            return exc.code
        finally:
            _remove_if_empty(made)


def _remove_if_empty(made) -> None:
    """Remove the output folders this job created if it wrote nothing into them."""
    for folder in reversed(made):
        try:
            folder.rmdir()
        except OSError:
            break


def _main(argv, made) -> int:
    args = parse_args(sys.argv if argv is None else argv)
    try:
        for spec in args.register:
            import_extension(spec)
        cfg = load_config(args.config, args)
    except ValueError as exc:                     # ConfigError, FieldError: names the key
        print(f"render_job: error: {exc}", file=sys.stderr, flush=True)
        return 2
    out = cfg["output"]
    missing = []
    probe = out
    while not probe.exists():
        missing.append(probe)
        probe = probe.parent
    try:
        out.mkdir(parents=True, exist_ok=True)     # to hold the lock; removed if left empty
    except OSError as exc:
        print(f"render_job: error: cannot create {str(out)!r}: {disk_reason(out, exc)}",
              file=sys.stderr, flush=True)
        return 1
    made.extend(reversed(missing))
    flag = "--output" if args.output is not None else f"{args.config}: job.output"
    log(f"job {cfg['name']!r}: {len(cfg['figures'])} figure(s), {cfg['seconds']:g} s at "
        f"{cfg['fps']} fps, {cfg['render']['engine']} {cfg['render']['resolution'][0]}x"
        f"{cfg['render']['resolution'][1]}")
    try:
        with signals.deferred(), OutputLock(out, flag, f"render_job {cfg['name']}"):
            # Held signals: Blender prints, rather than passes on, an exception raised in the
            # add-on's code it calls; the job stops at its checkpoints (after each figure's
            # bake, each frame) instead.  Held from before the lock is taken, so a signal
            # cannot leave a lock file (and the folder made for it) behind.
            res = run(cfg, render=not args.no_render)
    except OutputLocked as exc:
        print(f"render_job: error: {exc}", file=sys.stderr, flush=True)
        return 2
    except ConfigError as exc:
        print(f"render_job: error: {exc}", file=sys.stderr, flush=True)
        return 2
    except WriteError as exc:
        kept = f"; kept {len(KEPT)} file(s) written before it" if KEPT else ""
        print(f"render_job: error: {exc}{kept}", file=sys.stderr, flush=True)
        return 1
    except RuntimeError as exc:                   # an operator's report (fell over, no plan)
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else "bake failed"
        print(f"render_job: error: {reason}", file=sys.stderr, flush=True)
        return 1
    except OSError as exc:                        # the disk filled up, the folder went away
        print(f"render_job: error: cannot write to {str(out)!r}: "
              f"{disk_reason(out, exc)}", file=sys.stderr, flush=True)
        return 1
    log(f"blend: {res['blend']}")
    if res["frames"] is not None:
        log(f"frames: {res['frames']}")
    return 0

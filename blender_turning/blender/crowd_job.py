"""Follow Path for several figures at once (issue 11): one plan per figure, in worker processes.

Each figure is read as the single-figure Follow Path reads it (:func:`.ops_path.prepare`: its
path, obstacles, settings), made a core path-following :class:`~..core.scene.Scene` with the
same start, planner settings and problem, and the whole selection a :class:`~..crowd.Crowd`.
The crowd runner splits it into one task per figure (:func:`~..crowd.runner.crowd_tasks`) and
:func:`~..crowd.runner.run_task` plans each in a worker process of a
:class:`concurrent.futures.ProcessPoolExecutor`.  Every figure's plan depends on its own data
only, so each is bit for bit the plan Follow Path makes for that figure alone.

The workers are started with ``spawn``, never ``fork``: a forked copy of Blender would carry its
threads and its state into the child.  They get plain data (the core's frozen dataclasses and
numpy arrays) and import only the bpy-free core; nothing of bpy crosses.  The tasks are
submitted on the main thread, which is also where the pool starts its processes, while
``__main__`` is hidden (:func:`_plain_main`): ``spawn`` would otherwise run the script Blender
was started with (``blender -b --python job.py``) again in every worker.  As an extension this
package is ``bl_ext.<repository>.blender_turning...``, whose first two names Blender makes at run
time; the workers make the same names first (:func:`_worker_stubs`), so the pickled tasks load.

Nothing is written until every figure has its plan; Esc (:meth:`CrowdFollow.cancel`) drops the
tasks not started and ends the worker processes, and writes nothing.
"""
from __future__ import annotations

import math
import multiprocessing
import os
import sys
import types
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager

import bpy

from ..core.follow_problem import start_state
from ..core.scene import Scene
from ..crowd import Crowd, CrowdFigure, FollowPath
from ..crowd.runner import crowd_tasks, run_task
from . import bake
from .ops_bake import apply_bake
from .ops_common import check_figure
from .pipeline import map_track, on_ground, started, surface_normals
from .scene_adapters import FrameRange

#: Where this package's modules live: the root of the names the pickled tasks carry.
PACKAGE = __name__.rsplit(".", 2)[0]

_STUB_CODE = """
import sys, types
for name, path in stubs:
    if name not in sys.modules:
        module = types.ModuleType(name)
        module.__path__ = list(path)
        sys.modules[name] = module
"""


def _worker_stubs() -> list:
    """``[(name, __path__)]`` of the packages above this one that have no file of their own
    (Blender's ``bl_ext`` and ``bl_ext.<repository>``), for the workers to make before they
    load a task; empty when the package is imported under its own name."""
    parts = PACKAGE.split(".")
    out = []
    for i in range(1, len(parts)):
        module = sys.modules.get(".".join(parts[:i]))
        if module is not None and getattr(module, "__file__", None) is None \
                and hasattr(module, "__path__"):
            out.append((".".join(parts[:i]), list(module.__path__)))
    return out


@contextmanager
def _plain_main():
    """``__main__`` as an empty module while worker processes start (see the module's text)."""
    saved = sys.modules.get("__main__")
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        yield
    finally:
        if saved is not None:
            sys.modules["__main__"] = saved


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` spawned processes that can load this package's tasks."""
    # ``exec`` is a builtin, so the initializer itself needs no import of ours in the worker.
    return ProcessPoolExecutor(max_workers=workers,
                               mp_context=multiprocessing.get_context("spawn"),
                               initializer=exec, initargs=(_STUB_CODE, {"stubs": _worker_stubs()}))


def figure_scene(name: str, job) -> Scene:
    """The core scene of a prepared Follow Path job (:func:`.ops_path.prepare`): the same
    figure, path, obstacles, planner settings, start (:func:`~..core.follow_problem.start_state`
    of the path) and problem, so its plan is the one :meth:`.follow_job.FollowJob.run` makes."""
    setup = job.setup
    return Scene(name, setup.figure, setup.path, setup.obstacles, start_state(setup.path), 0.0,
                 setup.speed, setup.settings, setup.samples_per_segment, setup.exact_distance,
                 run_out=setup.run_out, ground=setup.ground, resistance=setup.resistance)


class CrowdFollow:
    """Plan the figures ``figs`` (armature objects) along their paths, in worker processes.

    :meth:`read` reads the figures, :meth:`start` submits the plans, :meth:`done` and
    :attr:`progress` are polled by the modal operator, :meth:`results` collects them (raising
    what a worker raised), :meth:`write` bakes them; :meth:`cancel` stops.  :attr:`current` is
    the figure being read or written (for a report).
    """

    def __init__(self, figs, workers: int | None = None):
        self.uids = [f.session_uid for f in figs]
        self.names = [f.name for f in figs]
        self.current = self.names[0]
        self.max_workers = workers
        self.tasks = []
        self._pool = None
        self._futures = []

    def read(self, context) -> None:
        """Read every figure as Follow Path reads one (raises ``ValueError`` naming the bad
        input; :attr:`current` names the figure)."""
        from .ops_path import prepare             # ops_path dispatches here: import when used
        figs = [self.figure(i) for i in range(len(self.uids))]
        members = []
        self.grounds = []                       # each figure's Ground mesh as read (or None)
        for i, fig in enumerate(figs):
            self.current = fig.name
            job = prepare(context, fig)
            self.grounds.append(getattr(job, "mesh_ground", None))
            # Names of the crowd's own (a CSV file name each): the object names may hold '/'.
            members.append(CrowdFigure(f"f{i}", job.figure, FollowPath(figure_scene(f"f{i}", job)),
                                       time_offset=float(fig.turning.crowd.time_offset)))
        self.crowd = Crowd("follow_path", members, duration=1.0)
        self.tasks = crowd_tasks(self.crowd)      # one ("path", figure) task per figure

    @property
    def workers(self) -> int:
        """Worker processes: one per figure, at most one per core (or the number asked)."""
        return max(1, min(len(self.uids), self.max_workers or os.cpu_count() or 1))

    def start(self) -> None:
        """Start the workers and hand them every plan (on the main thread: see the module)."""
        self._pool = worker_pool(self.workers)
        with _plain_main():
            self._futures = [self._pool.submit(run_task, task) for task in self.tasks]

    @property
    def progress(self) -> float:
        """The fraction of figures planned."""
        return sum(f.done() for f in self._futures) / max(len(self._futures), 1)

    def done(self) -> bool:
        return bool(self._futures) and all(f.done() for f in self._futures)

    def wait(self) -> None:
        for fut in self._futures:
            fut.exception()                        # blocks until the plan is done

    def results(self) -> list:
        """``[(name, FigureResult)]`` in the figures' order; shuts the pool down."""
        try:
            out = [r for fut in self._futures for r in fut.result()]
        finally:
            self._shutdown()
        return list(zip(self.names, out))

    def cancel(self) -> None:
        """Drop the plans not started and end the worker processes; nothing is written."""
        if self._pool is None:
            return
        processes = list((getattr(self._pool, "_processes", None) or {}).values())
        self._pool.shutdown(wait=False, cancel_futures=True)
        # concurrent.futures cannot stop a running task before Python 3.14's
        # terminate_workers(); a plan takes seconds to minutes: end its process.
        for proc in processes:
            if proc.is_alive():
                proc.terminate()
        for proc in processes:
            proc.join(5)
        self._pool = None

    def _shutdown(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    def figure(self, i: int):
        """The i-th figure's object now (by session id: it may have been renamed), or None."""
        return next((o for o in bpy.data.objects if o.session_uid == self.uids[i]), None)

    def write(self, context, results) -> FrameRange:
        """Map every plan and check it against its figure, then bake them all (nothing is
        written if one fails).  The scene's range is made to fit the longest run on the scene's
        clock; each figure is keyed from the first frame at or after its start.  Returns it."""
        scene = context.scene
        fps = scene.render.fps / scene.render.fps_base
        end = max(float(r.trajectory.t[-1]) for _, r in results)
        n = int(math.floor(end * fps + 1e-9))
        frames = FrameRange(scene.frame_start, scene.frame_start + max(n, 1), fps)
        computed = []
        for i, (name, r) in enumerate(results):
            self.current = name
            fig = self.figure(i)
            if fig is None:
                raise ValueError("the figure was deleted while planning")
            check_figure(fig)                   # the rig may have changed while it planned
            offset = float(r.trajectory.t[0])
            shown = started(frames, offset)
            k0 = shown.start - frames.start
            ground = self.grounds[i]
            traj = r.trajectory.resample(fps, start=k0 / fps,     # on the scene's clock
                                         ground=getattr(ground, "field", None))
            traj = type(traj)(traj.data[:, :shown.end - shown.start + 1], traj.meta)
            shown = FrameRange(shown.start, shown.start + len(traj) - 1, fps)
            if ground is not None:              # the foot on the mesh, as ops_path.finish does
                traj = on_ground(traj, ground)
            track = map_track(fig.turning.sport, traj, shown, obj=fig,
                              normal=surface_normals(traj, ground))
            bake.check_track(fig, track)
            computed.append((fig, traj, track))
        scene.frame_end = frames.end
        for fig, traj, track in computed:
            apply_bake(fig, traj, track)
        return frames


# -- the operator's steps for several figures (``turning.follow_path`` dispatches here) --------

TITLE = "Follow Path"


def follow_figures(context) -> list:
    """The figures Follow Path plans: every selected one (or the active Crowd collection's)
    with a path curve."""
    from .ops_common import selected_figures
    return [f for f in selected_figures(context) if f.turning.path is not None]


def needs_crowd(figs) -> bool:
    """Several figures, or one that starts late, plan here; one figure from the first frame
    plans on the single-figure job (a thread, with progress along its path)."""
    return len(figs) > 1 or any(f.turning.crowd.time_offset > 0 for f in figs)


def prepare_crowd(op, context, figs):
    """The job for ``figs``, or ``None`` (reported)."""
    from .ops_common import report_error
    job = CrowdFollow(figs)
    try:
        job.read(context)
    except Exception as exc:
        report_error(op, TITLE, job.current, exc)
        return None
    return job


def complete_crowd(op, context, job) -> set:
    """Collect the plans, refuse them all if one figure found none, else bake them all."""
    from .ops_common import report_error
    try:
        results = job.results()
    except Exception as exc:                       # a worker raised: a bug, or it was killed
        return report_error(op, TITLE, job.current, exc)
    failed = [(name, r) for name, r in results if r.status != "ok"]
    if failed:
        more = f" (and {len(failed) - 1} more figures)" if len(failed) > 1 else ""
        op.report({"ERROR"}, f"{TITLE}: {failed[0][0]}: {failed[0][1].message}{more}; "
                             "nothing was written")
        return {"CANCELLED"}
    try:
        frames = job.write(context, results)
    except Exception as exc:
        return report_error(op, TITLE, job.current, exc)
    op.report({"INFO"}, f"{TITLE}: baked {len(results)} figures over frames "
                        f"{frames.start}-{frames.end} (planned on {job.workers} worker "
                        f"processes)")
    return {"FINISHED"}


def run_crowd_inline(op, context, figs) -> set:
    """Background or scripted: plan in the workers and wait."""
    job = prepare_crowd(op, context, figs)
    if job is None:
        return {"CANCELLED"}
    job.start()
    job.wait()
    return complete_crowd(op, context, job)


def status(context, job) -> None:
    if context.workspace is not None:
        done = round(job.progress * len(job.names))
        context.workspace.status_text_set(
            f"{TITLE}: {done} of {len(job.names)} figures planned on {job.workers} worker "
            "processes (Esc to cancel)")


def crowd_modal(op, context, event) -> set:
    """One event of the modal operator planning several figures."""
    from .ops_common import end_modal
    job = op._crowd
    if event.type == "ESC":
        job.cancel()
        end_modal(op, context)
        op.report({"WARNING"}, f"{TITLE} cancelled; the scene is unchanged")
        return {"CANCELLED"}
    if event.type != "TIMER":
        return {"PASS_THROUGH"}
    finished = job.done()
    context.window_manager.progress_update(100 if finished else int(100 * job.progress))
    if not finished:
        status(context, job)
        return {"RUNNING_MODAL"}
    end_modal(op, context)
    return complete_crowd(op, context, job)

"""Follow Path for several figures at once: the crowd runner's plans, in worker
processes.

Each figure is read as the single-figure Follow Path reads it (:func:`.follow_scene.prepare`: its
path, obstacles, settings), made a core path-following :class:`~..core.course.scene.Scene` with the
same start, planner settings and problem, and the whole selection a :class:`~..crowd.Crowd`,
planned by :func:`~..crowd.runner.run_crowd`, the CLI's ``crowd`` planner:

- *Avoid Each Other* (:class:`CrowdOptions`, on by default): the crowd's ``priority`` names every
  figure in planning order, by its *Planning Order* (``turning.crowd.priority``, lower first; the
  selection's order is not stable in Blender) and then by name; each figure plans around the
  bodies (foot to CM ground point) of those before it, keeping ``clearance``
  (:mod:`..crowd.priority`: groups that cannot see each other plan in parallel, merged and
  planned again where one would have seen another).  The result is the CLI's priority planning
  of the same crowd, bit for bit.
- Off: one task per figure; each plan is bit for bit the plan Follow Path makes for that
  figure alone.

The runner runs on a planning thread; the tasks it submits go to worker processes (spawned, on
the main thread: :mod:`.workers`) through a :class:`~.workers.PumpedExecutor` that the modal
operator's timer pumps (:meth:`CrowdFollow.pump`), so Blender's UI stays responsive.

Nothing is written until every figure has its plan; Esc (:meth:`CrowdFollow.cancel`) fails the
runner's calls (its thread ends), drops the tasks not started and ends the worker processes,
and writes nothing.
"""
from __future__ import annotations

import math
import os
import re
import threading

import bpy
from bpy.props import BoolProperty, FloatProperty

from ...core import signals
from ...core.errors import WorkerLost
from ...core.course.follow_problem import start_state
from ...core.ranges import RANGES
from ...core.course.scene import Scene
from ...core.validate import check
from ...crowd import Crowd, CrowdFigure, FollowPath
from ...crowd.model import BODY_CLEARANCE
from ...crowd.runner import run_crowd
from ..anim import bake
from ..anim.figure_bake import BakeWriter, write_bakes
from ..scene.figure_context import check_figure, end_modal, report_error, selected_figures
from ..scene.follow_scene import prepare
from .model_notes import follow_note, warn_distance
from .pipeline import map_track, on_ground, started, surface_heights, surface_normals
from ..scene.scene_adapters import FrameRange
from .workers import PumpedExecutor, worker_pool


def figure_scene(name: str, job) -> Scene:
    """The core scene of a prepared Follow Path job (:func:`.follow_scene.prepare`): the same
    figure, path, obstacles, planner settings, start
    (:func:`~..core.course.follow_problem.start_state`
    of the path) and problem, so its plan is the one :meth:`.follow_job.FollowJob.run` makes."""
    setup = job.setup
    return Scene(name, setup.figure, setup.path, setup.obstacles, start_state(setup.path), 0.0,
                 setup.speed, setup.settings, setup.samples_per_segment, setup.exact_distance,
                 run_out=setup.run_out, ground=setup.ground, resistance=setup.resistance)


_BAD_NAME = re.compile(r"[/\\\0]")


def member_names(names) -> list:
    """The crowd's names of the objects ``names`` (a crowd figure's name is a CSV file's): the
    object's own where it can be, so the runner's reports name the objects; a name with a path
    separator or a leading dot gets ``_`` for them, made unique."""
    taken, out = set(names), []
    for name in names:
        if name and not name.startswith(".") and not _BAD_NAME.search(name):
            out.append(name)
            continue
        base = _BAD_NAME.sub("_", name)
        base = "_" + base[1:] if base.startswith(".") else base
        new, k = base, 1
        while new in taken:
            new, k = f"{base}_{k}", k + 1
        taken.add(new)
        out.append(new)
    return out


class CrowdFollow:
    """Plan the figures ``figs`` (armature objects) along their paths, in worker processes.

    ``avoid``: with several figures, plan them in priority order (:func:`planning_order`), each
    around the bodies of the figures before it, keeping ``clearance`` m from them (the crowd
    runner's priority planning, :mod:`..crowd.priority`); without it each plans alone.

    :meth:`read` reads the figures, :meth:`start` starts :func:`~..crowd.runner.run_crowd` on a
    planning thread whose plans go to the worker processes through a :class:`PumpedExecutor`;
    the modal operator calls :meth:`pump` and polls :meth:`done` and :attr:`progress`;
    :meth:`results` collects them (raising what the planning raised), :meth:`write` bakes them;
    :meth:`cancel` stops.  :attr:`current` is the figure being read or written (for a report).
    """

    def __init__(self, figs, workers: int | None = None, avoid: bool = True,
                 clearance: float = BODY_CLEARANCE):
        self.uids = [f.session_uid for f in figs]
        self.names = [f.name for f in figs]
        self.current = self.names[0]
        self.max_workers = workers
        self.avoid = bool(avoid) and len(figs) > 1
        self.clearance = clearance
        self._pool = self._executor = self._thread = None
        self._result = self._error = None
        self._done = 0
        self.stash_notes = {}               # name -> a user's action the bake stashed

    def read(self, context) -> None:
        """Read every figure as Follow Path reads one (raises ``ValueError`` naming the bad
        input; :attr:`current` names the figure)."""
        check("clearance", self.clearance, "body_clearance")
        figs = [self.figure(i) for i in range(len(self.uids))]
        self.members = member_names(self.names)
        members = []
        self.grounds = []                       # each figure's Ground mesh as read (or None)
        self.paths = []
        for i, fig in enumerate(figs):
            self.current = fig.name
            job = prepare(context, fig)
            self.grounds.append(getattr(job, "mesh_ground", None))
            self.paths.append(job.path)         # the drawn path, for the report
            name = self.members[i]
            members.append(CrowdFigure(name, job.figure, FollowPath(figure_scene(name, job)),
                                       time_offset=float(fig.turning.crowd.time_offset)))
        where = {fig.name: i for i, fig in enumerate(figs)}
        order = [self.members[where[n]] for n in planning_order(figs)] if self.avoid else []
        self.crowd = Crowd("follow_path", members, duration=1.0, priority=order,
                           clearance=self.clearance)

    @property
    def workers(self) -> int:
        """Worker processes: one per figure, at most one per core (or the number asked)."""
        return max(1, min(len(self.uids), self.max_workers or os.cpu_count() or 1))

    def start(self) -> None:
        """Start the planning thread (its plans reach the workers through :meth:`pump`)."""
        self._pool = worker_pool(self.workers)
        self._executor = PumpedExecutor(self._pool)
        self._thread = threading.Thread(target=self._plan, name="turning-crowd", daemon=True)
        self._thread.start()

    def _plan(self) -> None:
        try:
            self._result = run_crowd(self.crowd, executor=self._executor,
                                     progress=self._progress)
        except BaseException as exc:              # handed to results(), on the main thread
            self._error = exc

    def _progress(self, done: int, total: int) -> None:
        self._done = done

    def pump(self) -> None:
        """Hand the plans the runner asked for to the worker processes (main thread)."""
        if self._executor is not None:
            self._executor.pump()

    @property
    def progress(self) -> float:
        """The fraction of figures planned (a figure planned again after a merge of groups
        counts once: :mod:`..crowd.priority`)."""
        return self._done / len(self.names)

    def done(self) -> bool:
        return self._thread is not None and not self._thread.is_alive()

    def wait(self) -> None:
        """Pump until the planning thread ends (background or scripted runs)."""
        while not self.done():
            self.pump()
            self._thread.join(0.02)

    def results(self) -> list:
        """``[(name, FigureResult)]`` in the figures' order; shuts the pool down."""
        if self._error is not None:
            self.cancel()
            raise self._error
        self._shutdown()
        return list(zip(self.names, self._result.figures))

    def object_names(self, members) -> list:
        """The objects' names of the crowd figures ``members`` (:func:`member_names`)."""
        return [self.names[self.members.index(m)] for m in members if m in self.members]

    def rank(self, member: str) -> int:
        """Where the crowd figure ``member`` plans (its place in the priority; alone: its place
        in the selection)."""
        order = self.crowd.priority or self.members
        return order.index(member) if member in order else len(order)

    def cancel(self) -> None:
        """Drop the plans not started and end the worker processes; nothing is written."""
        if self._pool is None:
            return
        self._executor.close()                    # the planning thread ends
        # concurrent.futures cannot stop a running task before Python 3.14's
        # terminate_workers(); a plan takes seconds to minutes: end its process (and wait
        # until the pool has reaped every worker).
        signals.stop_pool(self._pool)
        self._thread.join(5)
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
            if ground is not None:              # the foot on the mesh, as follow_scene.finish does
                traj = on_ground(traj, ground)
            track = map_track(fig.turning.sport, traj, shown, obj=fig,
                              normal=surface_normals(traj, ground),
                              surface=surface_heights(ground))
            bake.check_track(fig, track)
            computed.append((fig, traj, track))
        scene.frame_end = frames.end
        writer = BakeWriter()
        write_bakes(*zip(*computed), writer)          # a figure with another's motion plays it
        self.stash_notes = writer.stash_notes
        return frames


# -- the operator's steps for several figures (``turning.follow_path`` dispatches here) --------

TITLE = "Follow Path"


def follow_figures(context) -> list:
    """The figures Follow Path plans: every selected one (or the active Crowd collection's)
    with a path curve."""
    return [f for f in selected_figures(context) if f.turning.path is not None]


def planning_order(figs) -> list:
    """The names of ``figs`` in the order Follow Path plans them when they avoid each other: by
    their *Planning Order* (``turning.crowd.priority``, lower first), then by name."""
    return [f.name for f in sorted(figs, key=lambda f: (f.turning.crowd.priority, f.name))]


def needs_crowd(figs) -> bool:
    """Several figures, or one that starts late, plan here; one figure from the first frame
    plans on the single-figure job (a thread, with progress along its path)."""
    return len(figs) > 1 or any(f.turning.crowd.time_offset > 0 for f in figs)


class CrowdOptions:
    """Follow Path's options for several figures (a mixin of the operator: its redo panel)."""

    avoid: BoolProperty(
        name="Avoid Each Other", default=True,
        description="Several figures: plan them one after another in their Planning Order "
                    "(Crowd panel; then by name), each around the bodies of the figures "
                    "planned before it, keeping Clearance from them. Off: each plans alone")
    clearance: FloatProperty(
        name="Clearance", default=BODY_CLEARANCE, min=RANGES["body_clearance"].lo,
        max=RANGES["body_clearance"].hi, soft_max=5.0, unit="LENGTH",
        description="With Avoid Each Other: the distance each figure keeps from the bodies "
                    "(foot to centre of mass) of the figures planned before it")


def prepare_crowd(op, context, figs):
    """The job for ``figs`` with the operator's :class:`CrowdOptions`, or ``None`` (reported)."""
    job = CrowdFollow(figs, avoid=op.avoid, clearance=op.clearance)
    try:
        job.read(context)
    except Exception as exc:
        report_error(op, TITLE, job.current, exc)
        return None
    return job


def complete_crowd(op, context, job) -> set:
    """Collect the plans, refuse them all if one figure found none (the first in planning
    order is named, and the figures in its way), else bake them all and say how far each
    strayed from its path (:func:`.model_notes.follow_note`)."""
    try:
        results = job.results()
    except WorkerLost as exc:                      # killed (by hand, out of memory): not a bug
        op.report({"ERROR"}, f"{TITLE}: a worker process died while planning "
                             f"{', '.join(job.object_names(exc.figures))}; nothing was changed")
        return {"CANCELLED"}
    except Exception as exc:                       # a worker raised: a bug
        return report_error(op, TITLE, job.current, exc)
    failed = sorted(((name, r) for name, r in results if r.status != "ok"),
                    key=lambda nr: job.rank(nr[1].name))
    if failed:
        more = f" (and {len(failed) - 1} more figures)" if len(failed) > 1 else ""
        op.report({"ERROR"}, f"{TITLE}: {failed[0][0]}: {failed[0][1].message}{more}; "
                             "nothing was written")
        return {"CANCELLED"}
    try:
        frames = job.write(context, results)
    except Exception as exc:
        return report_error(op, TITLE, job.current, exc)
    how = (f"each around the figures before it in the order {', '.join(job.crowd.priority)}"
           if job.crowd.priority else f"on {job.workers} worker processes")
    notes = [(name, *follow_note(path, r.trajectory, frames.start, frames.fps,
                                 warn_distance(op)))
             for (name, r), path in zip(results, job.paths)]
    for name, level, note in notes:
        if level == "INFO":
            op.report({level}, f"{TITLE}: {name}: {note}")
    for name, note in job.stash_notes.items():
        op.report({"WARNING"}, f"{TITLE}: {name}: {note}")
    op.report({"INFO"}, f"{TITLE}: baked {len(results)} figures over frames "
                        f"{frames.start}-{frames.end} (planned {how})")
    for name, level, note in notes:             # last: the status bar shows the last report
        if level != "INFO":
            op.report({level}, f"{TITLE}: {name}: {note}")
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
    job = op._crowd
    if event.type == "ESC":
        job.cancel()
        end_modal(op, context)
        op.report({"WARNING"}, f"{TITLE} cancelled; the scene is unchanged")
        return {"CANCELLED"}
    if event.type != "TIMER":
        return {"PASS_THROUGH"}
    job.pump()
    finished = job.done()
    context.window_manager.progress_update(100 if finished else int(100 * job.progress))
    if not finished:
        status(context, job)
        return {"RUNNING_MODAL"}
    end_modal(op, context)
    return complete_crowd(op, context, job)

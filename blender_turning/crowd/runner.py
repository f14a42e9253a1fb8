"""Running a crowd: parametric figures in batches, path figures one task each, on any executor.

The work is split into tasks the same way whatever runs them: one task per group of
:class:`~.model.Turns` figures that share a body and limits (:func:`blender_turning.core.run` on the
cheaper kernel for their number, :mod:`.kernels`:
per-figure ellipses, a figure that falls stops alone), and one
task per :class:`~.model.FollowPath` figure (the planner of Section 6).  Tasks run in this
process (``workers=1``), on a :class:`concurrent.futures.ProcessPoolExecutor` (``workers=K``),
on a Dask distributed scheduler (``scheduler="tcp://..."``, through ``Client.get_executor()``)
or on any ``concurrent.futures``-style executor the caller passes.  Nothing random is drawn
here and every figure's result depends only on its own data, so the trajectories are the same
bit for bit whatever the engine and the number of workers (tests hold them to ``==``).

With a ``priority`` the path figures it names are planned after the rest, one task
per group of figures that can see each other, each figure around the bodies of those before it
(:mod:`.priority`: the groups give the same result as planning them one after another).
"""
from __future__ import annotations

import re
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

import numpy as np

from ..core import signals
from ..core.controllers.feasible import turn_meta
from ..core.errors import PlanInfeasible, TurningError, WorkerLost
from ..core.physics.trajectory import Trajectory, body_meta
from . import priority as priority_
from .kernels import run_turns
from .model import Crowd, CrowdFigure

__all__ = ["FigureResult", "CrowdResult", "run_crowd", "crowd_tasks", "run_task", "execute",
           "SCHEDULER_TIMEOUT", "check_scheduler_address"]

#: Seconds to reach a Dask scheduler and hear it answer (docs/failures.md), then the address is
#: given up with one error naming ``--scheduler``.
SCHEDULER_TIMEOUT = 10.0


@dataclass(frozen=True, eq=False)
class FigureResult:
    """One figure's outcome.  ``trajectory`` is on the crowd's clock (``t`` starts at the
    figure's ``time_offset``) and ends at the fall or where planning failed; ``status`` is
    ``"ok"``, ``"fell"``, ``"infeasible"`` (no feasible plan), ``"failed"`` (another domain
    error of the planner, e.g. the path not finished in time; ``message`` says when and
    where) or ``"lost"`` (the worker running it died; ``keep_going`` of :func:`run_crowd`).
    ``cpu_time``:
    CPU seconds of the task that computed it (shared by a batch), ``plan`` the planner's totals
    (path figures).  ``region``: for a figure planned by priority, the regions its searches
    looked at for other figures' bodies, rows ``(x, y, radius, t_lo, t_hi)`` on its own clock
    (``MovingBodies.near``)."""

    name: str
    trajectory: Trajectory | None
    status: str = "ok"
    message: str = ""
    cpu_time: float = 0.0
    plan: dict = field(default_factory=dict)
    region: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class CrowdResult:
    crowd: Crowd
    figures: tuple
    wall_time: float = 0.0

    @property
    def failed(self) -> tuple:
        return tuple(r for r in self.figures if r.status != "ok")

    def __getitem__(self, name: str) -> FigureResult:
        for r in self.figures:
            if r.name == name:
                return r
        raise KeyError(name)


def crowd_tasks(crowd: Crowd) -> list:
    """The crowd's tasks, in a fixed order: each a ``("turns", dt, duration, figures)`` batch
    (figures sharing a body, limits and the presence of heading control, in crowd order) or a
    ``("path", figure)``.  Path figures named in the crowd's ``priority`` are not among them
    (they are planned after these: :func:`run_crowd`)."""
    groups, tasks = {}, []
    for f in crowd.figures:
        if f.is_path:
            if f.name not in crowd.priority:
                tasks.append(("path", f))
            continue
        key = (f.figure.body, f.figure.limits, f.controller.heading is None)
        if key not in groups:
            groups[key] = []
            tasks.append(("turns", crowd.dt, crowd.duration, groups[key]))
        groups[key].append(f)
    return [(t[0], t[1], t[2], tuple(t[3])) if t[0] == "turns" else t for t in tasks]


def run_task(task) -> list:
    """Run one task of :func:`crowd_tasks` or a ``("group", clearance, bodies, figures)`` of
    priority planning (in any process): a list of :class:`FigureResult`."""
    cpu = time.process_time()
    if task[0] == "path":
        out = [_plan(task[1])]
    elif task[0] == "group":
        out = _group(*task[1:])
    else:
        out = _batch(*task[1:])
    cpu = time.process_time() - cpu
    return [replace(r, cpu_time=cpu) for r in out]


def _on_crowd_clock(traj: Trajectory, f: CrowdFigure) -> Trajectory:
    cols = traj.columns()
    cols["t"] = cols["t"] + f.time_offset
    return Trajectory.from_columns(cols, {**traj.meta, "figure": f.name,
                                          "time_offset": f.time_offset})


def _plan(f: CrowdFigure, bodies=None) -> FigureResult:
    """Plan ``f`` (around ``bodies``, a ``MovingBodies`` on its clock, if given)."""
    try:
        sc = f.controller.scene
        res = sc.run() if bodies is None else sc.run(bodies)
    except TurningError as exc:      # no feasible plan, the path not finished in time, ...
        tr = getattr(exc, "trajectory", None)
        tr = None if tr is None else _on_crowd_clock(tr, f)
        msg = str(exc)
        if isinstance(exc, PlanInfeasible) and bodies is not None and bodies.log:
            near = [n for n, k in zip(bodies.names, bodies.seen_by(bodies.log[-1:])) if k]
            msg += (f", with {', '.join(near)} (planned before it) within reach" if near else
                    "; no figure planned before it was within reach")
        return FigureResult(f.name, tr, "infeasible" if isinstance(exc, PlanInfeasible)
                            else "failed", msg)
    return FigureResult(f.name, _on_crowd_clock(res.trajectory, f),
                        plan={**res.totals(), "reached_end": res.reached_end})


def _group(clearance: float, bodies: tuple, figures: tuple) -> list:
    """Priority planning of ``figures`` in order, each around ``bodies`` (``(name, trajectory,
    l)`` on the crowd's clock) and the figures before it (a failed one: up to where it got)."""
    done, out = list(bodies), []
    for f in figures:
        log = []
        r = _plan(f, priority_.bodies_for(f, done, clearance, log))
        out.append(replace(r, region=np.array(log, float).reshape(-1, 5)))
        if r.trajectory is not None and len(r.trajectory):
            done.append((f.name, r.trajectory, f.figure.body.l))
    return out


def _batch(dt: float, duration: float, figures: tuple) -> list:
    """One task of parametric figures (Section 5) sharing body and limits, each run for the
    crowd's duration less its time offset, on its own clock, on the cheaper kernel
    (:mod:`.kernels`)."""
    fig = figures[0].figure
    meta = {"preset": fig.name, "dt": dt, **body_meta(fig.body)}
    out = []
    for f, (cols, fell_at, report) in zip(figures, run_turns(dt, duration, figures)):
        status, msg = ("ok", "") if fell_at is None else \
            ("fell", f"fell over at t = {fell_at + f.time_offset:.2f} s")
        traj = Trajectory.from_columns(cols, {**meta, **turn_meta(report)})
        out.append(FigureResult(f.name, _on_crowd_clock(traj, f), status, msg))
    return out


def run_crowd(crowd: Crowd, workers: int = 1, scheduler: str | None = None, executor=None,
              progress=None, keep_going: bool = False) -> CrowdResult:
    """Simulate and plan every figure of ``crowd``.

    ``workers``: local worker processes (1: this process); ``scheduler``: the address of a
    running Dask distributed scheduler (needs ``dask[distributed]``, the ``cluster`` extra);
    ``executor``: any object with ``submit(fn, arg)`` returning ``concurrent.futures.Future``
    (e.g. ``Client.get_executor()``), used as given and not shut down.  At most one of
    ``workers > 1``, ``scheduler`` and ``executor``.  ``progress(done, total)`` is called with
    the number of figures done after each task.  Failures (a fall, no feasible plan) are
    reported per figure in :attr:`CrowdResult.figures`, not raised.  A worker that dies
    raises :class:`~..core.errors.WorkerLost` naming the figures it took with it, or with
    ``keep_going`` marks them ``"lost"`` and goes on with the rest."""
    clock = time.perf_counter()
    tasks = crowd_tasks(crowd)
    total = len(crowd.figures)
    by_name = {}

    def collect(i, rs):
        new = any(r.name not in by_name for r in rs)
        by_name.update((r.name, r) for r in rs)
        if progress is not None and new:
            progress(len(by_name), total)

    with engine(workers, scheduler, executor) as ex:
        _fan_out(ex, run_task, tasks, collect, keep_going)
        named = [crowd[n] for n in crowd.priority if crowd[n].is_path]
        if named:
            bodies = tuple((n, by_name[n].trajectory, crowd[n].figure.body.l)
                           for n in crowd.priority if not crowd[n].is_path)
            _by_priority(named, bodies, crowd.clearance, ex, collect, keep_going)
    return CrowdResult(crowd, tuple(by_name[f.name] for f in crowd.figures),
                       time.perf_counter() - clock)


def _by_priority(named, bodies, clearance, ex, collect, keep_going=False) -> None:
    """Plan the path figures ``named`` (in priority order) around ``bodies`` and each other:
    groups in parallel, merged and planned again until none sees another (:mod:`.priority`)."""
    groups = priority_.initial_groups(named, clearance)
    pending, final = groups, {}
    while pending:
        tasks = [("group", clearance, bodies, tuple(named[i] for i in g)) for g in pending]
        def done(i, rs):
            final.update(zip(pending[i], rs))
            collect(i, rs)                          # progress: figures with a first result
        _fan_out(ex, run_task, tasks, done, keep_going)
        merged = priority_.merge(groups, priority_.conflicts(named, groups, final, clearance))
        pending = [g for g in merged if g not in groups]
        groups = merged
    for gi, g in enumerate(groups):
        for rank, i in enumerate(g):
            r = final[i]
            plan = {**r.plan, "priority": {"group": gi, "rank": rank,
                                           "after": [named[j].name for j in g[:rank]]}}
            collect(i, [replace(r, plan=plan)])


def execute(fn, tasks, collect, workers: int = 1, scheduler: str | None = None,
            executor=None) -> None:
    """``collect(i, fn(tasks[i]))`` for every task, as they finish, on the engine chosen as in
    :func:`run_crowd` (``fn`` must be a module-level function, so other processes can import
    it)."""
    with engine(workers, scheduler, executor) as ex:
        _fan_out(ex, fn, tasks, collect)


@contextmanager
def engine(workers: int = 1, scheduler: str | None = None, executor=None):
    """The executor chosen as in :func:`run_crowd`, open for the ``with`` block (``None``:
    this process)."""
    if isinstance(workers, bool) or int(workers) != workers or not 1 <= workers <= 1024:
        raise ValueError(f"workers = {workers!r} is outside the allowed range [1, 1024]")
    if sum((workers > 1, scheduler is not None, executor is not None)) > 1:
        raise ValueError("give at most one of workers > 1, scheduler and executor")
    if scheduler is not None:
        client = _dask_client(scheduler)
        try:
            yield client.get_executor()
        finally:
            client.close()
    elif executor is not None:
        yield executor
    elif workers > 1:
        # Workers leave Ctrl-C to this process, which ends them itself when it stops (an
        # interrupt, an error) rather than waiting for their running tasks.
        pool = ProcessPoolExecutor(max_workers=int(workers),
                                   initializer=signals.ignore_in_worker)
        try:
            yield pool
        except BaseException:
            signals.stop_pool(pool)
            raise
        pool.shutdown()
    else:
        yield None


def _task_figures(task) -> tuple:
    """The names of the figures a task of :func:`crowd_tasks` (or a priority group) runs."""
    figs = (task[1],) if task[0] == "path" else task[3]
    return tuple(f.name for f in figs)


def _worker_died(exc: BaseException) -> bool:
    """A process pool broken by a dead worker, or Dask's ``KilledWorker`` (a task whose workers
    died three times); matched by name so that dask need not be imported."""
    return any(c.__name__ in ("BrokenProcessPool", "BrokenExecutor", "KilledWorker")
               for c in type(exc).__mro__)


def _fan_out(executor, fn, tasks, collect, keep_going: bool = False) -> None:
    if executor is None:
        for i, task in enumerate(tasks):
            collect(i, fn(task))
        return
    futures, lost = {}, {}
    # A process pool forks its workers in submit(), where Python runs its at-fork hooks and
    # drops what they raise: a signal there would be lost, so it is held until the tasks are out.
    with signals.deferred():
        for i, task in enumerate(tasks):
            try:
                futures[executor.submit(fn, task)] = i
            except Exception as exc:          # the pool broke before this task went out
                if not _worker_died(exc):
                    raise
                lost[i] = exc
    for fut in as_completed(futures):
        i = futures[fut]
        try:
            rs = fut.result()
        except Exception as exc:
            if not _worker_died(exc):
                raise
            lost[i] = exc
            if not keep_going:
                break
            continue
        collect(i, rs)
    if not lost:
        return
    names = [n for i in sorted(lost) for n in _task_figures(tasks[i])]
    why = next(iter(lost.values()))
    msg = f"its worker process died ({type(why).__name__}: {str(why).splitlines()[0]})" \
        if str(why).strip() else f"its worker process died ({type(why).__name__})"
    if not keep_going:
        raise WorkerLost(f"a worker process died while it ran {_listed(names)} "
                         f"({type(why).__name__})", names)
    for i in sorted(lost):
        task = tasks[i]
        figs = (task[1],) if task[0] == "path" else task[3]
        collect(i, [FigureResult(f.name, None, "lost", msg) for f in figs])


def _listed(names) -> str:
    shown = ", ".join(names[:5])
    return f"{shown} and {len(names) - 5} more" if len(names) > 5 else shown


_ADDRESS = re.compile(r"^(?:(tcp|tls|ws|wss|ucx)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):"
                      r"([0-9]{1,5})/?$")


def check_scheduler_address(address) -> str:
    """``address`` if it reads as a scheduler's (``[tcp://]HOST:PORT``, also ``tls``, ``ws``,
    ``wss``, ``ucx``), else a ``ValueError`` naming ``--scheduler``."""
    if not isinstance(address, str) or not address.strip():
        raise ValueError(f"--scheduler = {address!r} is empty: give the scheduler's address, "
                         "tcp://HOST:PORT")
    m = _ADDRESS.match(address.strip())
    if m is None or not 1 <= int(m.group(3)) <= 65535:
        raise ValueError(f"--scheduler = {address!r} is not a scheduler address "
                         "(tcp://HOST:PORT, port 1-65535)")
    return address.strip() if m.group(1) else f"tcp://{address.strip()}"


def _probe(address: str, target: str) -> None:
    """A plain TCP connection first, so that a closed port or an unknown host is said at once
    (Dask retries such an address until its timeout)."""
    import socket
    scheme, _, rest = target.partition("://")
    if scheme not in ("tcp", "tls", "ws", "wss"):
        return
    host, _, port = rest.rstrip("/").rpartition(":")
    try:
        socket.create_connection((host.strip("[]"), int(port)),
                                 timeout=SCHEDULER_TIMEOUT).close()
    except OSError as exc:
        why = exc.strerror or str(exc) or type(exc).__name__
        if isinstance(exc, TimeoutError) or isinstance(exc, socket.timeout):
            why = f"no answer within {SCHEDULER_TIMEOUT:g} s"
        raise ValueError(f"--scheduler = {address!r}: tried {target}: cannot connect ({why})") \
            from None


def _dask_client(address: str):
    """A Dask client of the scheduler at ``address``, or one ``ValueError`` naming
    ``--scheduler`` within about :data:`SCHEDULER_TIMEOUT` s: a plain TCP connection first (a
    closed port or an unknown host is said at once), then Dask's ``identity`` call under a
    deadline (a peer that accepts and never answers, or answers in another protocol -- an HTTP
    proxy's reply read as a Dask frame length asks for exabytes -- is given up on before any
    client exists), then the client."""
    target = check_scheduler_address(address)
    try:
        import asyncio

        from dask.distributed import Client
        from distributed.core import rpc
    except ImportError:
        raise ValueError("--scheduler needs dask.distributed "
                         "(pip install 'blender-turning[cluster]')") from None
    _probe(address, target)

    async def identity():
        peer = rpc(target, timeout=SCHEDULER_TIMEOUT)
        try:
            return await peer.identity()
        finally:
            await peer.close_rpc()

    tried = f"--scheduler = {address!r}: tried {target} for {SCHEDULER_TIMEOUT:g} s"
    try:
        ident = asyncio.run(asyncio.wait_for(identity(), SCHEDULER_TIMEOUT))
    except (TimeoutError, asyncio.TimeoutError):
        raise ValueError(f"{tried}: it accepted the connection but no Dask scheduler "
                         "answered") from None
    except OSError as exc:
        raise ValueError(f"{tried}: cannot connect ({str(exc).splitlines()[0]})") from None
    except Exception as exc:               # a reply that is not Dask's (MemoryError, ...)
        raise ValueError(f"{tried}: the address answers, but not as a Dask scheduler "
                         f"({type(exc).__name__})") from None
    kind = ident.get("type") if isinstance(ident, dict) else None
    if kind != "Scheduler":
        raise ValueError(f"{tried}: the address answers as a Dask {kind or 'peer'}, not a "
                         "scheduler")
    try:
        return Client(target, timeout=SCHEDULER_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise ValueError(f"{tried}: cannot connect ({str(exc).splitlines()[0]})") from None

"""Worker processes started from inside Blender, for Follow Path on several figures
(:mod:`.crowd_job`).

The workers are started with ``spawn``, never ``fork``: a forked copy of Blender would carry its
threads and its state into the child.  They get plain data (the core's frozen dataclasses and
numpy arrays) and import only the bpy-free core; nothing of bpy crosses.  Tasks are submitted on
the main thread, which is also where the pool starts its processes, while ``__main__`` is hidden
(:func:`_plain_main`; swapping it from another thread would race with Blender's): ``spawn`` would
otherwise run the script Blender was started with (``blender -b --python job.py``) again in
every worker.  As an extension this package is ``bl_ext.<repository>.blender_turning...``, whose
first two names Blender makes at run time; the workers make the same names first
(:func:`_worker_stubs`), so the pickled tasks load.

The crowd runner (:func:`~..crowd.runner.run_crowd`) runs on a planning thread and submits its
tasks to a :class:`PumpedExecutor`, which hands them to the pool when the main thread calls
:meth:`PumpedExecutor.pump` (the modal operator's timer).
"""
from __future__ import annotations

import multiprocessing
import os
import sys
import threading
import types
from concurrent.futures import CancelledError, Future, InvalidStateError, ProcessPoolExecutor
from contextlib import contextmanager
from functools import partial

__all__ = ["PumpedExecutor", "worker_pool"]

#: Where this package's modules live: the root of the names the pickled tasks carry.
PACKAGE = __name__.rsplit(".", 3)[0]

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
    load a task; empty when the package is imported under its own name.  Blender's junction
    modules carry a placeholder ``__file__`` (``"[bl_ext]"``), not ``None``, and ``bl_ext`` has
    no ``__path__``: what counts is whether a file is there for a worker's import to load."""
    parts = PACKAGE.split(".")
    out = []
    for i in range(1, len(parts)):
        module = sys.modules.get(".".join(parts[:i]))
        if module is not None and not os.path.isfile(getattr(module, "__file__", None) or ""):
            # (Blender's ``bl_ext`` has no ``__path__``: its repositories are set on it.)
            out.append((".".join(parts[:i]), list(getattr(module, "__path__", ()))))
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


class PumpedExecutor:
    """The executor :func:`~..crowd.runner.run_crowd` is given on the planning thread: its
    :meth:`submit` queues a call, and :meth:`pump`, on Blender's main thread, hands the queued
    calls to the worker pool (so the processes start on the main thread with ``__main__``
    hidden: see the module's text).  :meth:`close` fails every call not done, so the thread
    waiting on them ends."""

    def __init__(self, pool):
        self._pool = pool
        self._lock = threading.Lock()
        self._queued = []
        self._futures = []
        self._closed = False

    def submit(self, fn, arg) -> Future:
        fut = Future()
        with self._lock:
            self._futures.append(fut)
            if not self._closed:
                self._queued.append((fut, fn, arg))
                return fut
        _drop(fut)
        return fut

    def pump(self) -> None:
        """Submit the queued calls to the pool (on the main thread)."""
        with self._lock:
            queued, self._queued = self._queued, []
        if not queued:
            return
        with _plain_main():
            for fut, fn, arg in queued:
                if fut.set_running_or_notify_cancel():
                    self._pool.submit(fn, arg).add_done_callback(partial(_relay, fut))

    def close(self) -> None:
        with self._lock:
            self._closed, queued, self._queued = True, self._queued, []
            futures = list(self._futures)
        for fut, _, _ in queued:
            _drop(fut)
        for fut in futures:                    # in the pool: fail it (unless it has just ended)
            _settle(fut, exc=CancelledError())


def _drop(fut: Future) -> None:
    """Cancel a pending ``fut`` and tell its waiters (``as_completed`` hears of a cancel only
    through ``set_running_or_notify_cancel``)."""
    fut.cancel()
    fut.set_running_or_notify_cancel()


def _settle(fut: Future, result=None, exc=None) -> None:
    try:
        if exc is None:
            fut.set_result(result)
        else:
            fut.set_exception(exc)
    except InvalidStateError:                  # settled already (closed meanwhile)
        pass


def _relay(outer: Future, inner: Future) -> None:
    """The pool's future ``inner`` settles the planning thread's ``outer``."""
    if inner.cancelled():
        _settle(outer, exc=CancelledError())
    elif inner.exception() is not None:
        _settle(outer, exc=inner.exception())
    else:
        _settle(outer, inner.result())

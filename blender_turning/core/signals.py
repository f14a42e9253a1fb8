"""How every command line and headless job stops on SIGINT (Ctrl-C) and SIGTERM (a farm manager
stopping a task): one policy, used by ``python -m blender_turning ...`` and the scripts' jobs
(docs/failures.md).

While :func:`stop_on_signals` is active, either signal raises :class:`Interrupted` in the main
thread; the command unwinds (every ``finally`` and ``except BaseException`` runs: hidden files
are removed, locks released, worker processes ended), prints one line and exits
``128 + signal`` (130 for SIGINT, 143 for SIGTERM).  A second signal while it unwinds is
ignored, so the clean-up is not cut short.  Code that must not be cut in the middle (renaming
finished outputs into place, a call into Blender that would print the exception rather than
pass it on) runs inside :func:`deferred`: a signal then is held until the block ends.  Python
drops what some code raises (``__del__``, weakref callbacks, its own at-fork hooks) and hands it
to ``sys.unraisablehook``: an :class:`Interrupted` dropped there is kept, silently, and raised
again at the next :func:`check` or :func:`checkpoint` (the end of any :func:`deferred` block),
so a signal is never lost.
"""
from __future__ import annotations

import os
import signal
import sys
import threading
from contextlib import contextmanager

__all__ = ["Interrupted", "stop_on_signals", "deferred", "check", "interrupted_line",
           "ignore_in_worker", "stop_pool", "checkpoint"]

SIGNALS = (signal.SIGINT, signal.SIGTERM)


class Interrupted(BaseException):
    """SIGINT or SIGTERM arrived (a ``BaseException``, like ``KeyboardInterrupt``, so that no
    ``except Exception`` swallows it).  ``code``: the exit status, ``128 + signum``."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)
        self.code = 128 + self.signum
        self.name = signal.Signals(signum).name


_state = {"active": False, "held": None, "depth": 0, "dropped": None}


def _handler(signum, frame):
    if _state["depth"]:                    # inside deferred(): hold it until the block ends
        if _state["held"] is None:
            _state["held"] = signum
        return
    for s in SIGNALS:                      # unwinding: a second signal must not cut it short
        signal.signal(s, signal.SIG_IGN)
    raise Interrupted(signum)


@contextmanager
def stop_on_signals():
    """Turn SIGINT and SIGTERM into :class:`Interrupted` for the ``with`` block (main thread
    only; elsewhere, and nested, it does nothing).  The handlers before it are put back."""
    if _state["active"] or threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {s: signal.signal(s, _handler) for s in SIGNALS}
    old_hook = sys.unraisablehook

    def unraisable(args):
        if isinstance(args.exc_value, Interrupted):      # dropped by Python: keep it
            if _state["dropped"] is None:
                _state["dropped"] = args.exc_value.signum
            return
        old_hook(args)

    sys.unraisablehook = unraisable
    _state.update(active=True, held=None, depth=0, dropped=None)
    try:
        yield
    finally:
        _state.update(active=False, held=None, depth=0, dropped=None)
        sys.unraisablehook = old_hook
        for s, h in old.items():
            signal.signal(s, h)


@contextmanager
def deferred():
    """Hold SIGINT and SIGTERM for the ``with`` block; one that came meanwhile raises
    :class:`Interrupted` when the block ends (not if the block raised).  Outside the main
    thread (where no signal handler runs) it does nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
    if _state["depth"] == 0:
        check()


def _pending():
    """The signal held by :func:`deferred` or dropped by Python (taken: it is acted on once)."""
    signum = _state["held"] if _state["held"] is not None else _state["dropped"]
    _state["held"] = _state["dropped"] = None
    return signum


def check() -> None:
    """Raise :class:`Interrupted` for a signal held by :func:`deferred` or dropped by Python (at
    a point where stopping is safe)."""
    if _state["depth"]:
        return
    signum = _pending()
    if signum is not None:
        for s in SIGNALS:
            signal.signal(s, signal.SIG_IGN)
        raise Interrupted(signum)


def checkpoint() -> None:
    """Inside :func:`deferred`: raise :class:`Interrupted` now for a signal held so far (the
    caller is at a point where stopping is safe, e.g. between two frames of a render)."""
    signum = _pending()
    if signum is not None:
        for s in SIGNALS:
            signal.signal(s, signal.SIG_IGN)
        raise Interrupted(signum)


def interrupted_line(prog: str, exc: Interrupted, kept=()) -> str:
    """The one line a stopped command prints: what was kept and where, or that nothing was."""
    kept = [str(k) for k in kept]
    if not kept:
        return f"{prog}: interrupted ({exc.name}); nothing written"
    where = os.path.commonpath(kept) if len(kept) > 1 else kept[0]
    return (f"{prog}: interrupted ({exc.name}); kept {len(kept)} file"
            f"{'s' if len(kept) > 1 else ''} written before it in {where}")


def ignore_in_worker() -> None:
    """A worker process's initializer: Ctrl-C in a terminal reaches the whole process group,
    and only the parent decides what stops (it ends its workers itself); SIGTERM keeps its
    default (the parent's :func:`stop_pool` sends it)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def stop_pool(pool) -> None:
    """End a ``ProcessPoolExecutor`` now: cancel what has not started, terminate its worker
    processes, reap them and wait for the pool's management thread to finish
    (``shutdown(wait=True)`` would wait for the running tasks).

    The wait for that thread matters at exit: ``concurrent.futures`` wakes every management
    thread still running (``_python_exit``) by writing to a pipe the thread closes as it ends;
    one still ending then can close it under that write, and the exit prints a traceback."""
    # Private ProcessPoolExecutor internals (CPython 3.9-3.13): it keeps no public list of its
    # processes or handle on its management thread; both are gone once shutdown() returns.
    procs = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=5)
    if manager is not None:
        manager.join(timeout=5)

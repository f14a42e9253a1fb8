"""Dask workers set up for crowd tasks: Dask's settings that keep its own threads quiet, and a
local cluster started with them.

A crowd task is pure Python and numpy on one thread for seconds (a path figure's planner, a
batch).  A Dask worker runs it on a thread of a process whose event loop also wakes every
20 ms (the tick monitor), samples the task thread's stack every 10 ms (the profiler), measures
the process's memory every 100 ms and the machine every 500 ms; each wakeup takes the GIL from
the task.  Measured on the 8 path figures of ``scripts/bench_crowd.py`` (2-core machine, cold
workers, load 13-20): Dask's defaults cost 3.5-5 CPU s of the workers' other threads on 14-16
CPU s of tasks, :data:`WORKER_CONFIG` 0.6 s (BENCHMARKS.md); the timers run per second of wall
time, so on idle cores they cost less.  It also imports the runner when a worker starts
(``preload``), once per cluster, where a fresh worker otherwise imports it inside the first
crowd it runs (about 0.7 CPU s).  None of it changes a result: the tasks are the same.

For a cluster started by hand (docs/crowds.md) the same settings are the environment variables
of :data:`WORKER_ENVIRON` and ``dask worker --preload blender_turning.crowd.runner``.
"""
from __future__ import annotations

from contextlib import contextmanager

__all__ = ["WORKER_CONFIG", "WORKER_ENVIRON", "local_cluster"]

#: Dask configuration for workers that run crowd tasks (``dask.config.set``).
WORKER_CONFIG = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.memory.monitor-interval": "1s",
    "distributed.admin.system-monitor.interval": "5s",
    "distributed.worker.preload": ["blender_turning.crowd.runner"],
}

#: :data:`WORKER_CONFIG` as the environment of ``dask worker`` (Dask reads ``DASK_`` variables,
#: ``__`` for a level); the preload is ``--preload blender_turning.crowd.runner`` there.
WORKER_ENVIRON = {"DASK_" + key.upper().replace(".", "__").replace("-", "_"): str(value)
                  for key, value in WORKER_CONFIG.items() if not key.endswith(".preload")}


@contextmanager
def local_cluster(workers: int = 2, config: dict | None = None):
    """A Dask ``LocalCluster`` of ``workers`` worker processes of one thread each, started
    with ``config`` (default :data:`WORKER_CONFIG`; ``{}``: Dask's defaults) and closed at the
    end of the ``with`` block; yields its scheduler's address (for ``run_crowd(...,
    scheduler=...)``).  Needs ``dask[distributed]``."""
    if isinstance(workers, bool) or int(workers) != workers or not 1 <= workers <= 1024:
        raise ValueError(f"workers = {workers!r} is outside the allowed range [1, 1024]")
    import dask
    from dask.distributed import LocalCluster

    with dask.config.set(WORKER_CONFIG if config is None else config):
        with LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster:
            yield cluster.scheduler_address

"""``python tests/pool_races.py RACE crowd ...``: the crowd command with one of two races of
its process pool made certain rather than left to the machine's scheduling (docs/failures.md,
tests/test_failure_pool_exit.py):

- ``slow-close``: at exit, ``concurrent.futures`` wakes every pool management thread still
  running (``_python_exit``): it checks that the thread's pipe is open, then writes to it.  Here
  the management thread takes a second to end its pool (and close that pipe), and the write
  comes only once the pipe is closed, as a busy machine may interleave them.
- ``signal-at-fork``: SIGTERM arrives while the pool forks its first worker, when Python runs
  its own at-fork hooks (whose exceptions it prints and drops).
"""
import os
import runpy
import signal
import sys
import time
from concurrent.futures import process

RACE = sys.argv[1]

if RACE == "slow-close":
    real_join, real_wakeup = (process._ExecutorManagerThread.join_executor_internals,
                              process._ThreadWakeup.wakeup)

    def join_executor_internals(self):
        time.sleep(1.0)
        real_join(self)

    def wakeup(self):
        if process._global_shutdown and not self._closed:      # at exit, the thread still on
            end = time.monotonic() + 5.0
            while not self._closed and time.monotonic() < end:
                time.sleep(0.01)
            self._writer.send_bytes(b"")
            return
        real_wakeup(self)

    process._ExecutorManagerThread.join_executor_internals = join_executor_internals
    process._ThreadWakeup.wakeup = wakeup
elif RACE == "signal-at-fork":
    sent = []

    def before_fork():
        if not sent:
            sent.append(True)
            os.kill(os.getpid(), signal.SIGTERM)

    os.register_at_fork(before=before_fork)
else:
    raise SystemExit(f"unknown race {RACE!r}")

sys.argv = ["blender_turning", *sys.argv[2:]]
runpy.run_module("blender_turning", run_name="__main__", alter_sys=True)

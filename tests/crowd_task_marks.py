"""``python tests/crowd_task_marks.py MARKS crowd ...``: the crowd command, with each task
leaving a mark in the folder MARKS, so that a test knows where the work stands without guessing
from the clock.  A task of several figures (a batch) writes ``hold-<pid>`` and then waits until
its worker is killed; a task of one figure runs and writes ``done-<name>`` as it returns.
Workers are forked (the default on Linux), so the patched task reaches them."""
import os
import runpy
import sys
import time
from pathlib import Path

from blender_turning.crowd import runner

MARKS = Path(sys.argv[1])
_real_task = runner.run_task


def run_task(task):
    names = runner._task_figures(task)
    if len(names) > 1:
        (MARKS / f"hold-{os.getpid()}").write_text(",".join(names))
        while True:
            time.sleep(1.0)
    out = _real_task(task)
    (MARKS / f"done-{names[0]}").write_text("")
    return out


run_task.__module__, run_task.__qualname__ = runner.__name__, "run_task"   # pickled by name
runner.run_task = run_task
sys.argv = ["blender_turning", *sys.argv[2:]]
runpy.run_module("blender_turning", run_name="__main__", alter_sys=True)

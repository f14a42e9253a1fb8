"""``python tests/signal_in_del.py crowd ...``: the crowd command with SIGTERM landing where
Python drops what is raised: in an object's ``__del__`` (as in a weakref callback or Python's
at-fork hooks), right after the first task has run in this process (``--workers 1``)."""
import os
import runpy
import signal
import sys

from blender_turning.crowd import runner

_real_task = runner.run_task
sent = []


class Dropped:
    def __del__(self):
        os.kill(os.getpid(), signal.SIGTERM)      # the handler runs here, and raises here


def run_task(task):
    out = _real_task(task)
    if not sent:
        sent.append(True)
        Dropped()                                 # made and collected at once
    return out


runner.run_task = run_task
sys.argv = ["blender_turning", *sys.argv[1:]]
runpy.run_module("blender_turning", run_name="__main__", alter_sys=True)

"""The signal policy (blender_turning/core/signals.py) with threads: a block another thread
holds signals for (the planning thread of Follow Path in Blender runs the crowd runner, which
holds them while it submits tasks) must not hold the main thread's, where the handler runs."""
import os
import signal
import threading

import pytest

from blender_turning.core import signals


def test_a_deferred_block_in_another_thread_does_not_hold_the_main_threads_signals():
    inside, leave, raised = threading.Event(), threading.Event(), []

    def worker():
        try:
            with signals.deferred():
                inside.set()
                leave.wait(30)
        except BaseException as exc:              # what the thread would raise and lose
            raised.append(exc)

    with signals.stop_on_signals():
        t = threading.Thread(target=worker)
        t.start()
        assert inside.wait(30)
        try:
            with pytest.raises(signals.Interrupted):
                os.kill(os.getpid(), signal.SIGTERM)    # the handler runs as it returns
        finally:
            leave.set()
            t.join(30)
    assert raised == []

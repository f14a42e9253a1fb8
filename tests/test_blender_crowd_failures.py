"""Follow Path on several figures when a worker process dies mid-plan (killed by the user, the
out-of-memory killer, a farm manager): a plain report naming the figures whose plans were lost,
no "internal error", and the scene unchanged (docs/failures.md)."""
import os
import signal
import tempfile
import time

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from modal_stand_ins import Context, WindowManager  # noqa: E402
from scene_snapshot import diff, snapshot  # noqa: E402
from test_blender_crowd import (TIMER, modal_crowd, path_figures, scene,  # noqa: E402,F401
                                started_workers)  # (scene: the same 96-frame scene)

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]


@pytest.mark.parametrize("avoid", [False, True])
def test_a_worker_killed_mid_plan_is_reported_by_figure_and_nothing_changes(scene, avoid):
    """Three figures on the workers; one worker is killed as soon as it holds a plan (a plan
    takes seconds here: the kill lands before the first one is back)."""
    figs = path_figures()
    names = {f.name for f in figs}
    before = snapshot()
    op_cls, fake, reports = modal_crowd(figs, avoid=avoid)
    procs = started_workers(fake._crowd)
    assert procs and not fake._crowd.done()
    os.kill(procs[0].pid, signal.SIGKILL)
    wm = WindowManager()
    end = time.monotonic() + 120
    while (ret := op_cls.modal(fake, Context(wm), TIMER)) == {"RUNNING_MODAL"} and \
            time.monotonic() < end:
        time.sleep(0.05)
    assert ret == {"CANCELLED"}, reports
    kind, line = reports[-1]
    assert kind == {"ERROR"}
    assert "a worker process died while planning " in line and "nothing was changed" in line
    assert "internal error" not in line and "Broken" not in line, line
    lost = line.split("while planning ", 1)[1].split(";", 1)[0].split(", ")
    assert lost and set(lost) <= names, line
    assert "end" in wm.progress
    assert all(p.exitcode is not None for p in procs), "a worker outlived the job"
    assert snapshot() == before, diff(before, snapshot())

"""``python tests/render_job_hold_bake.py MARKS render_job-args...``: scripts/render_job.py with
each figure's bake held until a signal has come, so a test knows the signal lands during the
bake without guessing from the clock (as tests/crowd_task_marks.py does for the crowd).  The bake
writes ``MARKS/baking-<figure>`` and waits until the job's signal handler holds a signal (the
job holds SIGINT and SIGTERM while Blender runs the add-on's code: docs/failures.md), then bakes
as usual."""
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-job-"))
from blender_turning.blender.render import job  # noqa: E402  (what scripts/render_job.py runs)

MARKS = Path(sys.argv[1])
_real_bake = job.bake_figure


def bake_figure(bpy, obj, fig, frame_end):
    (MARKS / f"baking-{obj.name}").write_text("")
    end = time.monotonic() + 120
    while job.signals._state["held"] is None and time.monotonic() < end:  # (private: a test's)
        time.sleep(0.01)
    _real_bake(bpy, obj, fig, frame_end)


job.bake_figure = bake_figure
code = job.main(["render_job.py", *sys.argv[2:]])
if code:
    sys.exit(code)

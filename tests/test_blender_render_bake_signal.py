"""SIGINT or SIGTERM while the render job (scripts/render_job.py) bakes a figure: the bake is
held (tests/render_job_hold_bake.py) until the signal has come, so it surely lands mid-bake.
One line, exit 130 / 143, no traceback, and nothing written: the output folder made for the
job's lock is gone again (docs/failures.md)."""
import os
import signal
import subprocess
import sys
import tempfile
import time

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
pytest.importorskip("bpy")

from test_blender_render_failures import ROOT, SLALOM, TINY, one_line  # noqa: E402

pytestmark = pytest.mark.blender
HOLD = ROOT / "tests" / "render_job_hold_bake.py"


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_mid_bake_writes_nothing(tmp_path, sig, code):
    marks, out = tmp_path / "marks", tmp_path / "job"
    marks.mkdir()
    p = subprocess.Popen([sys.executable, str(HOLD), marks, "--config", SLALOM, *TINY,
                          "--seconds", "0.5", "--output", out], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, cwd=ROOT)
    end = time.monotonic() + 300
    while not any(marks.iterdir()) and p.poll() is None and time.monotonic() < end:
        time.sleep(0.02)
    assert p.poll() is None, p.communicate()
    assert [m.name for m in marks.iterdir()] == ["baking-Skier"], list(marks.iterdir())
    assert out.exists()                        # made for the job's lock
    p.send_signal(sig)
    stdout, err = p.communicate(timeout=300)
    assert p.returncode == code, stdout[-2000:] + err
    assert one_line(err) == f"render_job: interrupted ({sig.name}); nothing written"
    assert "saved" not in stdout                # stopped after the bake, before the .blend
    assert not out.exists()

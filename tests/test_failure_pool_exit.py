"""``crowd --workers 2`` stopped by a signal where its process pool is in a race with it
(tests/pool_races.py makes each race certain): one line, exit 130 / 143, no traceback at exit,
nothing written (docs/failures.md)."""
import json
import os
import signal
import subprocess
import sys
import time

from cli_helpers import ROOT, snapshot
from test_failure_signals import SLOW_CROWD, children, one_line

RACES = ROOT / "tests" / "pool_races.py"


def start(race, scene, out):
    return subprocess.Popen([sys.executable, str(RACES), race, "crowd", scene, "--out", out,
                             "--workers", "2"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)),
                            start_new_session=True)


def crowd_and_out(tmp_path):
    scene = tmp_path / "slow.json"
    scene.write_text(json.dumps(SLOW_CROWD))
    out = tmp_path / "out"
    out.mkdir()
    return scene, out


def test_the_pool_has_ended_before_the_exit(tmp_path):
    """Ctrl-C while the workers run; the pool's management thread is slow to end it.  The exit
    must not find that thread still running (it would write to the pipe the thread closes)."""
    scene, out = crowd_and_out(tmp_path)
    proc = start("slow-close", scene, out)
    end = time.monotonic() + 60
    while len(children(proc.pid)) < 2 and proc.poll() is None and time.monotonic() < end:
        time.sleep(0.02)
    time.sleep(0.2)
    assert proc.poll() is None, proc.communicate()
    os.killpg(proc.pid, signal.SIGINT)             # as a terminal sends it
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert one_line(err).endswith("interrupted (SIGINT); nothing written")
    assert snapshot(out) == {}


def test_a_signal_while_the_pool_forks_is_not_lost(tmp_path):
    """SIGTERM while the pool forks its first worker, inside Python's at-fork hooks (which drop
    what they raise): the crowd still stops, rather than going on to exit 0."""
    scene, out = crowd_and_out(tmp_path)
    proc = start("signal-at-fork", scene, out)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert one_line(err).endswith("interrupted (SIGTERM); nothing written")
    assert snapshot(out) == {}

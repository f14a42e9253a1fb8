"""A signal whose exception Python drops (raised in ``__del__``, a weakref callback, an at-fork
hook: Python prints "Exception ignored" and goes on) is not lost: the command still stops at
its next safe point, with one line and exit 143, nothing written (docs/failures.md)."""
import json
import os
import subprocess
import sys

from cli_helpers import ROOT, snapshot
from test_failure_signals import one_line

CROWD = {"duration": 2, "figures": [{"name": f"f{i}", "preset": "skier",
                                     "turns": {"period": 2, "lean_deg": 20},
                                     "start": {"position": [3 * i, 0]}} for i in range(3)]}


def test_a_signal_dropped_in_a_del_still_stops_the_crowd(tmp_path):
    scene = tmp_path / "crowd.json"
    scene.write_text(json.dumps(CROWD))
    out = tmp_path / "out"
    out.mkdir()
    r = subprocess.run([sys.executable, str(ROOT / "tests" / "signal_in_del.py"), "crowd",
                        scene, "--out", out], capture_output=True, text=True, timeout=300,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert r.returncode == 143, r.stderr
    assert "Exception ignored" not in r.stderr
    assert one_line(r.stderr).endswith("interrupted (SIGTERM); nothing written")
    assert snapshot(out) == {}

"""SIGINT and SIGTERM sent to real command-line processes in the middle of their work
(docs/failures.md): one line, exit 130 / 143, no traceback, no hidden temporary file anywhere
in the output folder, an earlier result there untouched, and no worker process left running."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cli_helpers import ROOT, snapshot

# A crowd that runs for several seconds on this machine (100 parametric figures for 12 s of
# motion: about 5 s in one process, measured), so a signal surely lands in the middle.
SLOW_CROWD = {"name": "slow", "duration": 12, "dt": 0.02,
              "figures": [{"name": "lead", "preset": "skier",
                           "turns": {"period": 2, "lean_deg": 20}}],
              "formations": [{"type": "follow_leader", "leader": "lead", "count": 100,
                              "gap_s": 0.01, "lateral_m": [-4, -2, 0, 2, 4]}]}


def start(*args, cwd=None):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.Popen([sys.executable, "-m", "blender_turning", *map(str, args)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            cwd=cwd, start_new_session=True)


def wait_for_hidden(folder: Path, proc, timeout=60.0):
    """Until the command has reserved its outputs (hidden files in ``folder``): it is then
    past its checks and in the middle of its work."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if any(p.name.startswith(".tmp-") for p in folder.iterdir()):
            return
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.02)
    pytest.fail("the command never reserved its outputs")


def children(pid: int) -> list:
    out = []
    for p in Path("/proc").iterdir():
        if p.name.isdigit():
            try:
                stat = (p / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(p.name))
    return out


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err and ".tmp-" not in err
    return lines[0]


def earlier_result(out: Path) -> dict:
    out.mkdir()
    (out / "summary.json").write_text('{"crowd": "earlier"}')
    (out / "lead.csv").write_text("t,x,y\n0,0,0\n")
    return snapshot(out)


@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
@pytest.mark.parametrize("workers", [1, 2])
def test_crowd_stopped_by_a_signal_leaves_the_earlier_result(tmp_path, sig, code, workers):
    scene = tmp_path / "slow.json"
    scene.write_text(json.dumps(SLOW_CROWD))
    out = tmp_path / "out"
    before = earlier_result(out)
    proc = start("crowd", scene, "--out", out, "--workers", workers)
    wait_for_hidden(out, proc)
    end = time.monotonic() + 30
    while workers > 1 and len(children(proc.pid)) < workers and time.monotonic() < end:
        time.sleep(0.02)
    time.sleep(0.2)
    pool = children(proc.pid)
    assert proc.poll() is None, "the crowd ended before the signal"
    if workers > 1:
        assert pool, "no worker process started"
    # SIGINT as a terminal sends it: to the whole process group (the workers too).
    (os.killpg if sig == signal.SIGINT else os.kill)(proc.pid, sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code, err
    assert one_line(err).endswith(f"interrupted ({sig.name}); nothing written")
    assert snapshot(out) == before            # no .tmp-*.csv, .tmp-*.json or lock left
    assert not [p for p in pool if alive(p)], "a worker outlived the command"


def test_crowd_into_a_new_folder_stopped_leaves_no_folder(tmp_path):
    scene = tmp_path / "slow.json"
    scene.write_text(json.dumps(SLOW_CROWD))
    out = tmp_path / "new"
    proc = start("crowd", scene, "--out", out)
    end = time.monotonic() + 60
    while not (out.exists() and any(out.iterdir())) and time.monotonic() < end:
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    one_line(err)
    assert not out.exists()


def test_simulate_stopped_keeps_the_old_csv(tmp_path):
    old = tmp_path / "o.csv"
    old.write_text("old run\n")
    before = snapshot(tmp_path)
    # 3000 s at dt 0.02: 150,000 steps, a few seconds (BENCHMARKS.md: 200,000 steps in 4.7 s).
    proc = start("simulate", "--duration", "3000", "--out", old)
    wait_for_hidden(tmp_path, proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert "interrupted (SIGTERM); nothing written" in one_line(err)
    assert snapshot(tmp_path) == before and old.read_text() == "old run\n"


def test_a_second_crowd_on_the_same_folder_is_refused_naming_the_first(tmp_path):
    scene = tmp_path / "slow.json"
    scene.write_text(json.dumps(SLOW_CROWD))
    out = tmp_path / "out"
    before = earlier_result(out)
    first = start("crowd", scene, "--out", out)
    wait_for_hidden(out, first)
    second = start("crowd", scene, "--out", out)
    _, err = second.communicate(timeout=60)
    first.send_signal(signal.SIGTERM)
    first.communicate(timeout=60)
    assert second.returncode == 2, err
    line = one_line(err)
    assert "--out" in line and f"pid {first.pid} on " in line
    assert snapshot(out) == before


def test_a_stale_lock_of_a_killed_job_is_taken_over(tmp_path):
    """A job killed with SIGKILL cannot remove its lock; the next job sees its pid gone and
    goes ahead."""
    scene = tmp_path / "slow.json"
    scene.write_text(json.dumps(SLOW_CROWD))
    out = tmp_path / "out"
    out.mkdir()
    first = start("crowd", scene, "--out", out)
    wait_for_hidden(out, first)
    first.send_signal(signal.SIGKILL)
    first.communicate(timeout=60)
    assert (out / ".turning.lock").exists()
    small = dict(SLOW_CROWD, duration=1, formations=[])
    scene.write_text(json.dumps(small))
    for p in out.glob(".tmp-*"):              # what SIGKILL left (nothing can catch it)
        p.unlink()
    r = subprocess.run([sys.executable, "-m", "blender_turning", "crowd", str(scene), "--out",
                        str(out)], capture_output=True, text=True, timeout=120,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out.iterdir()) == ["lead.csv", "summary.json"]


def _crowd_with_quick_figures(tmp_path) -> Path:
    doc = json.loads(json.dumps(SLOW_CROWD))
    doc["duration"] = 30                 # the batch: several seconds even on an idle machine
    doc["figures"] += [{"name": "board", "preset": "snowboarder",
                        "turns": {"period": 2, "lean_deg": 20}, "start": {"position": [0, 30]},
                        "time_offset": 29.5},
                       {"name": "bike", "preset": "cyclist",
                        "turns": {"period": 3, "lean_deg": 15}, "start": {"position": [0, 60]},
                        "time_offset": 29.5}]
    scene = tmp_path / "mixed.json"
    scene.write_text(json.dumps(doc))
    return scene


@pytest.mark.parametrize("keep_going", [False, True])
def test_a_worker_killed_mid_crowd_is_reported_by_figure(tmp_path, keep_going):
    """Three tasks on two workers: the 101-skier batch and two single figures.  The tasks leave
    marks (tests/crowd_task_marks.py): the batch holds its worker until it is killed, so the kill
    lands in the middle of it on any machine.  The batch's figures are named; --keep-going writes
    the other two and lists the lost ones in the summary."""
    scene = _crowd_with_quick_figures(tmp_path)
    out, marks = tmp_path / "out", tmp_path / "marks"
    out.mkdir()
    marks.mkdir()
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, str(ROOT / "tests" / "crowd_task_marks.py"), marks,
                             "crowd", scene, "--out", out, "--workers", "2",
                             *(["--keep-going"] if keep_going else [])],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)
    want = {"done-board", "done-bike"}
    end = time.monotonic() + 120
    while time.monotonic() < end and proc.poll() is None:
        names = {p.name for p in marks.iterdir()}
        holds = [n for n in names if n.startswith("hold-")]
        if holds and want <= names:
            break
        time.sleep(0.02)
    assert proc.poll() is None, proc.communicate()
    assert holds and want <= names, names
    time.sleep(0.2)                    # the parent collects the two quick results
    os.kill(int(holds[0].split("-")[1]), signal.SIGKILL)
    _, err = proc.communicate(timeout=120)
    line = one_line(err)
    assert proc.returncode == 1, err
    assert "worker process died" in line and "lead" in line
    if not keep_going:
        assert "nothing written" in line and "--keep-going" in line
        assert sorted(p.name for p in out.iterdir()) == []
        return
    names = sorted(p.name for p in out.iterdir())
    assert names == ["bike.csv", "board.csv", "summary.json"], names
    doc = json.loads((out / "summary.json").read_text())
    lost = [r["name"] for r in doc["figures"] if r["status"] == "lost"]
    assert len(lost) == 101 and "lead" in lost and set(doc["failed"]) == set(lost)

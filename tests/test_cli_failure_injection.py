"""Failures injected where a user cannot provoke them on purpose: the disk filling up mid-write, a
rename that fails after another output is already in place, a permission error on the folder, an
interrupt in the middle of the work.  Each leaves the output folder exactly as it was (old files
kept whole, no hidden temporary file) and, where the command goes on to report, one line naming
the flag."""
import errno
import os
import stat

import pytest

import blender_turning.cli.common as common
import blender_turning.cli.simulate as sim
from blender_turning.cli import main
from blender_turning.core import files
from blender_turning.core.physics.trajectory import Trajectory
from cli_helpers import snapshot


def err_line(capsys):
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    assert ".tmp-" not in lines[0]
    return lines[0]


def test_disk_full_while_writing_the_csv(tmp_path, monkeypatch, capsys):
    pytest.importorskip("matplotlib")
    (tmp_path / "o.csv").write_text("old run")
    before = snapshot(tmp_path)

    def half_then_full(self, path):
        with open(path, "w") as fh:
            fh.write("t,x,y\n0,0,")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(Trajectory, "to_csv", half_then_full)
    assert main(["simulate", "--duration", "1", "--plot", str(tmp_path / "p.png"),
                 "--out", str(tmp_path / "o.csv")]) == 1          # a failed write: exit 1
    line = err_line(capsys)
    assert "--out" in line and "No space left on device" in line
    assert snapshot(tmp_path) == before and (tmp_path / "o.csv").read_text() == "old run"


def test_disk_full_inside_the_atomic_writer(tmp_path, monkeypatch, capsys):
    """The core's own writer (Trajectory.to_csv, to_json) cleans up after itself too."""
    real_open = open

    class Full:
        def __init__(self, fh):
            self.fh = fh

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.fh.close()

        def write(self, text):
            self.fh.write(text[:10])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def full_open(path, mode="r", *a, **k):
        fh = real_open(path, mode, *a, **k)
        return Full(fh) if "w" in mode else fh

    monkeypatch.setattr(files, "open", full_open, raising=False)
    assert main(["simulate", "--duration", "1", "--out", str(tmp_path / "o.csv")]) == 1
    assert "--out" in err_line(capsys)
    assert snapshot(tmp_path) == {}


def test_a_failed_rename_puts_back_what_was_replaced(tmp_path, monkeypatch, capsys):
    (tmp_path / "t.csv").write_text("old track")
    before = snapshot(tmp_path)
    real = os.replace
    calls = []

    def replace(src, dst):
        calls.append((src, dst))
        if str(dst).endswith("s.json"):
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        return real(src, dst)

    monkeypatch.setattr(common.os, "replace", replace)
    scene = tmp_path.parent / f"{tmp_path.name}-scene.json"
    scene.write_text('{"figure": {"preset": "cyclist", "limits": {"dC_f_max": 0.4}}, '
                     '"path": {"polyline": [[0, 0], [8, 0]]}, '
                     '"planner": {"stages": 3, "choices": 3}}')
    assert main(["follow", str(scene), "--out", str(tmp_path / "t.csv"), "--stats",
                 str(tmp_path / "s.json")]) == 1
    line = err_line(capsys)
    assert "--stats" in line and "Input/output error" in line
    assert any(str(d).endswith("t.csv") for _, d in calls)     # t.csv had been put in place
    assert snapshot(tmp_path) == before and (tmp_path / "t.csv").read_text() == "old track"


def test_permission_error_on_the_folder_is_named_before_the_work(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sim, "simulate", lambda *a, **k: pytest.fail("simulated first"))

    def denied(path):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path) + ".tmp-x")

    monkeypatch.setattr(common, "temp_beside", denied)
    assert main(["simulate", "--out", str(tmp_path / "o.csv")]) == 2
    assert "--out" in err_line(capsys)
    assert snapshot(tmp_path) == {}


def test_an_interrupt_mid_run_leaves_nothing(tmp_path, monkeypatch, capsys):
    """Ctrl-C in the middle of the simulation: cli.main removes the reserved hidden files and
    says so in one line, exit 130."""
    def interrupted(*a, **k):
        assert len(list(tmp_path.iterdir())) == 2         # the two reserved hidden files
        raise KeyboardInterrupt

    monkeypatch.setattr(sim, "simulate", interrupted)
    assert main(["simulate", "--out", str(tmp_path / "o.csv"), "--plot",
                 str(tmp_path / "p.png")]) == 130
    assert "interrupted (SIGINT); nothing written" in err_line(capsys)
    assert snapshot(tmp_path) == {}


def test_a_read_only_existing_output_is_refused(tmp_path, capsys):
    if os.geteuid() == 0:
        pytest.skip("root writes read-only files")
    out = tmp_path / "o.csv"
    out.write_text("keep")
    out.chmod(0o444)
    assert main(["simulate", "--duration", "1", "--out", str(out)]) == 2
    assert "--out" in err_line(capsys) and out.read_text() == "keep"


def test_the_core_writer_writes_a_pipe_in_place(tmp_path):
    """Trajectory.to_csv on a pipe (or a device such as /dev/null) writes into it; a rename
    would put a regular file in its place."""
    import threading

    from blender_turning.core import PhaseEllipse, preset, simulate
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_text()), daemon=True)
    reader.start()
    fig = preset("skier")
    simulate(fig, PhaseEllipse(fig.body, 3.0, 0.3, 0.0), 0.2).to_csv(fifo)
    reader.join(timeout=30)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode) and got[0].startswith("t,x,y")

"""The command line: success path and every bad-input case (one line, exit 2, no file)."""
import subprocess
import sys

import pytest

from blender_turning.cli import main
from blender_turning.core import COLUMNS


def cli(*args):
    return subprocess.run([sys.executable, "-m", "blender_turning", *args], capture_output=True,
                          text=True, timeout=120)


def test_simulate_writes_the_trajectory(tmp_path, capsys):
    out = tmp_path / "s.csv"
    assert main(["simulate", "--duration", "4", "--fps", "24", "--out", str(out)]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == ",".join(COLUMNS)
    assert len(lines) == 1 + 4 * 24 + 1
    assert "simulate: skier, ellipse" in capsys.readouterr().out


def test_schedule_file(tmp_path):
    sched = tmp_path / "s.csv"
    sched.write_text("t,period,lean_deg,heading_deg\n0,2,15,0\n6,3,25,10\n")
    out = tmp_path / "o.csv"
    assert main(["simulate", "--schedule", str(sched), "--duration", "8", "--out",
                 str(out)]) == 0
    assert out.exists()


BAD = [
    (["--mass", "nan"], "--mass"),
    (["--mass", "0"], "--mass"),
    (["--mass", "-70"], "--mass"),
    (["--com-height", "0"], "--com-height"),
    (["--com-height", "-1"], "--com-height"),
    (["--speed", "0"], "--speed"),
    (["--speed", "-3"], "--speed"),
    (["--lean-deg", "90"], "--lean-deg"),
    (["--lean-deg", "120"], "--lean-deg"),
    (["--period", "0"], "--period"),
    (["--period", "-2"], "--period"),
    (["--duration", "nan"], "--duration"),
    (["--schedule", "/nonexistent/schedule.csv"], "schedule file"),
    (["--preset", "surfer"], "--preset"),
]


@pytest.mark.parametrize("args,name", BAD)
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, name):
    out = tmp_path / "o.csv"
    short = [] if "--duration" in args else ["--duration", "2"]     # keep good runs quick
    r = cli("simulate", *args, *short, "--out", str(out))
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and name in lines[0], r.stderr
    assert "Traceback" not in r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_bad_schedule_contents(tmp_path):
    sched = tmp_path / "s.csv"
    sched.write_text("t,period,lean_deg\n0,2,95\n")
    r = cli("simulate", "--schedule", str(sched), "--duration", "2")
    assert r.returncode == 2 and "lean_deg = 95" in r.stderr and len(r.stderr.splitlines()) == 1
    sched.write_text("time,foo\n1,2\n")
    r = cli("simulate", "--schedule", str(sched), "--duration", "2")
    assert r.returncode == 2 and "column 'time' in the header is not known" in r.stderr


def test_missing_output_folder_is_reported_before_work(tmp_path):
    r = cli("simulate", "--duration", "2", "--out", str(tmp_path / "no" / "o.csv"))
    assert r.returncode == 2 and "--out" in r.stderr


def test_figures_command_writes_pngs(tmp_path):
    pytest.importorskip("matplotlib")
    assert main(["figures", "--out", str(tmp_path), "--only", "fig05_typical_turn",
                 "fig06_tracks"]) == 0
    for stem in ("fig05_typical_turn", "fig06_tracks"):
        data = (tmp_path / f"{stem}.png").read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000

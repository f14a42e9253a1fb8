"""The render job (scripts/render_job.py) under failures a farm sees (docs/failures.md): its output
disk full (a small tmpfs) before the .blend or in the middle of the frames, SIGTERM / SIGINT in
the middle of the render, a second job on the same output.  Never exit 0 on a file not
written, one line naming what was not written, no hidden file, no partial .blend or frame."""
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
pytest.importorskip("bpy")

pytestmark = pytest.mark.blender
ROOT = Path(__file__).resolve().parents[1]
JOB = ROOT / "scripts" / "render_job.py"
SLALOM = ROOT / "scripts" / "configs" / "skier_slalom.toml"
TINY = ("--resolution", "32x24")


def job(*args, **kw):
    return subprocess.Popen([sys.executable, str(JOB), *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=ROOT, **kw)


def run_job(*args, timeout=600):
    p = job(*args)
    out, err = p.communicate(timeout=timeout)
    return p.returncode, out, err


def files(folder: Path) -> list:
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())


def no_hidden(folder: Path):
    hidden = [f for f in files(folder) if "/." in f"/{f}"]
    assert not hidden, hidden


def one_line(err: str) -> str:
    # Blender's own EGL notices (no display on a farm node) are not the job's words.
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("EGL Error")]
    assert len(lines) == 1, err
    assert "Traceback" not in err and ".tmp-" not in err
    return lines[0]


@pytest.fixture
def small_disk(tmp_path):
    """A tmpfs of a chosen size (root only; skipped where mounting is not allowed)."""
    mounted = []

    def make(kib: int) -> Path:
        where = tmp_path / f"disk{len(mounted)}"
        where.mkdir()
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={kib}k", "tmpfs", str(where)],
                           capture_output=True, text=True)
        if r.returncode:
            pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip()}")
        mounted.append(where)
        return where

    yield make
    for where in mounted:
        subprocess.run(["umount", "-l", str(where)], capture_output=True)


def test_a_full_disk_before_the_blend_leaves_no_blend(small_disk):
    disk = small_disk(64)                 # the slalom's .blend is about 160 KB (measured)
    code, out, err = run_job("--config", SLALOM, *TINY, "--seconds", "0.25", "--output",
                             disk / "job")
    assert code == 1, out[-2000:] + err
    line = one_line(err)
    assert ".blend" in line and "No space left on device" in line
    assert files(disk) == [] and not (disk / "job").exists()


def test_a_disk_that_fills_while_rendering_names_the_frames_not_written(tmp_path, small_disk):
    code, out, err = run_job("--config", SLALOM, *TINY, "--seconds", "0.25", "--no-render",
                             "--output", tmp_path / "probe")
    assert code == 0, err
    blend_kib = -(-(tmp_path / "probe" / "skier_slalom.blend").stat().st_size // 4096) * 4
    # Room for the .blend, the two folders and a few tiny frames (tmpfs counts 4 KiB pages; a
    # 32x24 frame is about 1.4 KB, one page), not for all 7.
    disk = small_disk(blend_kib + 20)
    code, out, err = run_job("--config", SLALOM, *TINY, "--seconds", "0.25", "--output",
                             disk / "job")
    assert code == 1, out[-2000:] + err
    line = one_line(err)
    got = files(disk / "job")
    frames = [f for f in got if f.startswith("frames/")]
    assert got == ["skier_slalom.blend", *frames] or got == [*frames, "skier_slalom.blend"]
    k = len(frames)
    assert 1 <= k < 7 and frames == [f"frames/frame_{i:04d}.png" for i in range(1, k + 1)]
    span = "7" if k == 6 else f"{k + 1}-7"          # the last frame alone: no range
    assert f"{7 - k} of 7 frames not written" in line and f"(frames {span};" in line, line
    assert "No space left on device" in line
    no_hidden(disk / "job")


@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_mid_render_stops_with_its_own_status(tmp_path, sig, code):
    """A render job stopped in the middle of its frames (not exit 0): the frames done are
    kept whole, and said so; no hidden frame is left."""
    p = job("--config", SLALOM, *TINY, "--seconds", "2", "--output", tmp_path / "job")
    end = time.monotonic() + 300
    frames = tmp_path / "job" / "frames"
    while time.monotonic() < end and p.poll() is None:
        if frames.exists() and len(list(frames.glob("frame_*.png"))) >= 2:
            break
        time.sleep(0.05)
    assert p.poll() is None, p.communicate()
    p.send_signal(sig)
    out, err = p.communicate(timeout=120)
    assert p.returncode == code, out[-2000:] + err
    line = one_line(err)
    assert f"interrupted ({sig.name}); kept" in line
    got = files(tmp_path / "job")
    assert "skier_slalom.blend" in got and 2 <= len(got) - 1 < 49   # 49 frames in 2 s
    no_hidden(tmp_path / "job")


def test_a_second_job_on_the_same_output_is_refused_naming_the_first(tmp_path):
    first = job("--config", SLALOM, *TINY, "--seconds", "2", "--output", tmp_path / "job")
    lock = tmp_path / "job" / ".turning.lock"
    end = time.monotonic() + 120
    while not lock.exists() and time.monotonic() < end and first.poll() is None:
        time.sleep(0.05)
    code, out, err = run_job("--config", SLALOM, *TINY, "--seconds", "2", "--output",
                             tmp_path / "job")
    first.send_signal(signal.SIGTERM)
    first.communicate(timeout=120)
    assert code == 2, err
    line = one_line(err)
    assert "--output" in line and f"pid {first.pid} on " in line
    assert not lock.exists()


def test_a_signal_during_the_bake_writes_nothing(tmp_path):
    """SIGTERM as soon as the job starts building (before its .blend): exit 143, one line, and
    the output folder it made for its lock is gone again."""
    p = job("--config", SLALOM, *TINY, "--seconds", "4", "--output", tmp_path / "job")
    line = p.stdout.readline()
    assert line.startswith("render_job: job "), line
    p.send_signal(signal.SIGTERM)
    out, err = p.communicate(timeout=300)
    assert p.returncode == 143, out[-2000:] + err
    assert "interrupted (SIGTERM); nothing written" in one_line(err)
    assert not (tmp_path / "job").exists()

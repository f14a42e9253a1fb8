"""The headless job (scripts/render_job.py) on the bpy wheel: builds, bakes, saves a .blend and
renders tiny PNG frames; a bad config exits non-zero with a one-line reason."""
import os
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
pytest.importorskip("bpy")

pytestmark = pytest.mark.blender
ROOT = Path(__file__).resolve().parents[1]
JOB = ROOT / "scripts" / "render_job.py"
CONFIGS = ROOT / "scripts" / "configs"


def run_job(*args, timeout=600):
    return subprocess.run([sys.executable, str(JOB), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, cwd=ROOT)


def png_size(path):
    with open(path, "rb") as fh:
        head = fh.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", head[16:24])


def test_demo_job_renders_tiny_frames(tmp_path):
    """The demo: the figures on terrain, one follow shot per figure, a shot of the
    ski school, and a sheet."""
    r = run_job("--config", CONFIGS / "demo.toml", "--resolution", "32x24", "--seconds", "0.25",
                "--output", tmp_path)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    names = ("Skier", "Snowboarder", "Telemark", "Cyclist")
    for name in names:
        frames = sorted((tmp_path / "frames" / name).glob("frame_*.png"))
        assert len(frames) == 4                # 0.25 s at 24 fps, frame_step 2: frames 1, 3, 5, 7
        assert all(png_size(f) == (32, 24) for f in frames)
        assert f"baked {name}" in r.stdout
    school = sorted((tmp_path / "frames" / "School").glob("frame_*.png"))
    assert len(school) == 4 and "baked School 8" in r.stdout and "baked Instructor" in r.stdout
    assert not (tmp_path / "frames" / "Instructor").exists()     # the crowd's one shot only
    assert png_size(tmp_path / "shots.png") == (64, 72)          # 5 shots, 2 columns
    # White snow under a blue sky: the skier's shot looks down the slope, its lower half is
    # snow (measured median 228 of 255 at 320 x 180; 190 before the exposure, Filmic ~150).
    import bpy
    img = bpy.data.images.load(str(tmp_path / "frames" / "Skier" / "frame_0007.png"))
    px = np.empty(32 * 24 * 4, np.float32)
    img.pixels.foreach_get(px)
    rgb = px.reshape(24, 32, 4)[:, :, :3]                          # bottom row first
    lower = rgb[:8].reshape(-1, 3)
    assert np.median(lower.mean(1)) > 0.82
    assert np.median(lower.max(1) - lower.min(1)) < 0.1              # white, not tinted
    top = rgb[-3:].reshape(-1, 3)
    assert np.median(top[:, 2] - top[:, 0]) > 0.3                    # the sky is blue
    assert (tmp_path / "demo.blend").stat().st_size > 0
    assert "rendered frame 7 (20/20)" in r.stdout and f"blend: {tmp_path / 'demo.blend'}" in r.stdout


@pytest.mark.parametrize("config", sorted(p.name for p in CONFIGS.glob("*.toml")))
def test_shipped_configs_build_and_bake(tmp_path, config):
    r = run_job("--config", CONFIGS / config, "--seconds", "1", "--no-render", "--output", tmp_path)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert list(tmp_path.glob("*.blend"))


@pytest.mark.parametrize("text, reason", [
    ("[job]\nseconds = 2\n", "no [[figures]]"),
    ('[[figures]]\nsport = "unicyclist"\n', "figures[0].sport = 'unicyclist'"),
    ('[render]\nengine = "POVRAY"\n[[figures]]\nsport = "skier"\n', "render.engine"),
    ('[[figures]]\nsport = "skier"\ncontrol = "path"\npath = "nowhere"\n', "figures[0].path"),
    ("[job\n", "not valid TOML"),
])
def test_bad_config_exits_with_one_line(tmp_path, text, reason):
    cfg = tmp_path / "bad.toml"
    cfg.write_text(text)
    r = run_job("--config", cfg, "--output", tmp_path / "out")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("render_job: error:") and reason in lines[0], \
        r.stderr
    assert not (tmp_path / "out").exists()


def test_cycles_renders_too(tmp_path):
    r = run_job("--config", CONFIGS / "skier_slalom.toml", "--engine", "CYCLES",
                "--resolution", "32x24", "--seconds", "0.05", "--output", tmp_path)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    frames = sorted((tmp_path / "frames").glob("frame_*.png"))
    assert len(frames) == 2 and all(png_size(f) == (32, 24) for f in frames)
    assert "with CYCLES" in r.stdout


def test_a_failed_bake_is_one_line_exit_1_and_creates_no_output(tmp_path):
    """A config that is valid but whose figure cannot do what it asks (a path straight into a
    wall as wide as the world: no feasible plan): the operator's report, exit 1, and the output
    folder never created (it is made only after the bakes).  (A slalom too sharp for the body no
    longer fails: the controller follows the nearest feasible turn.)"""
    cfg = tmp_path / "walled.toml"
    cfg.write_text('[paths.straight]\npoints = [[0.0, 0.0], [0.0, 30.0]]\n'
                   '[[obstacles]]\ngroup = "wall"\nkind = "box"\nat = [0.0, 60.0]\n'
                   'size = 100.0\nheight = 1.0\n'
                   '[[figures]]\nsport = "skier"\ncontrol = "path"\npath = "straight"\n'
                   'obstacles = "wall"\n')
    r = run_job("--config", cfg, "--seconds", "2", "--no-render", "--output", tmp_path / "out")
    assert r.returncode == 1, r.stdout[-2000:] + r.stderr[-2000:]
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "no feasible plan" in lines[0] and "Traceback" not in r.stderr
    assert not (tmp_path / "out").exists()

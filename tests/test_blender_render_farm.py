"""Rendering on a farm, on the bpy wheel: the job bakes once and saves a .blend whose
output path is relative to itself, so it can move to a farm's storage and be rendered in chunks
exactly as ``blender -b job.blend -s A -e B -a`` does (open, set the frame range, render the
animation) with the frames landing next to it; ``--frames`` renders one chunk and keeps the whole
range in the .blend; ``--device GPU`` fails in one line where Cycles finds no GPU; the Flamenco job
type's tasks, run in order, render every frame once."""
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
pytest.importorskip("bpy")

from cli_helpers import one_line_error  # noqa: E402
from flamenco_helpers import compile_job  # noqa: E402

pytestmark = pytest.mark.blender
ROOT = Path(__file__).resolve().parents[1]
JOB = ROOT / "scripts" / "render_job.py"
TINY = """[job]
name = "shot"
seconds = 0.25
fps = 24
[render]
resolution = [32, 24]
[[figures]]
sport = "skier"
"""                                              # frames 1..7

# What `blender -b BLEND -s A -e B -a` does, on the wheel: open, set the range, render the
# animation; prints the saved scene's settings first.
RENDER = """
import json, sys, bpy
blend, a, b = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
bpy.ops.wm.open_mainfile(filepath=blend)
s = bpy.context.scene
print("SAVED " + json.dumps([s.render.filepath, s.frame_start, s.frame_end, s.frame_step,
                             s.cycles.device]))
s.frame_start, s.frame_end = a, b
bpy.ops.render.render(animation=True)
"""


def run_job(*args):
    return subprocess.run([sys.executable, str(JOB), *map(str, args)], capture_output=True,
                          text=True, timeout=600, cwd=ROOT)


def render_chunk(blend, a, b):
    r = subprocess.run([sys.executable, "-c", RENDER, str(blend), str(a), str(b)],
                       capture_output=True, text=True, timeout=600, cwd=blend.parent.parent)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    line = next(x for x in r.stdout.splitlines() if x.startswith("SAVED "))
    return json.loads(line[len("SAVED "):])


def pngs(folder):
    return sorted(p.name for p in (folder / "frames").glob("*.png"))


def test_bake_once_move_the_blend_render_chunks_next_to_it(tmp_path):
    cfg = tmp_path / "shot.toml"
    cfg.write_text(TINY)
    r = run_job("--config", cfg, "--no-render", "--engine", "CYCLES", "--output",
                tmp_path / "bake")
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    farm = tmp_path / "farm" / "shots"
    farm.mkdir(parents=True)
    blend = farm / "shot.blend"
    (tmp_path / "bake" / "shot.blend").rename(blend)
    saved = render_chunk(blend, 3, 4)
    assert saved == ["//frames/frame_", 1, 7, 1, "CPU"]     # relative, the whole range, Cycles CPU
    render_chunk(blend, 5, 5)
    assert pngs(farm) == ["frame_0003.png", "frame_0004.png", "frame_0005.png"]
    # the figures moved: their animation is in the .blend (keyframes; no add-on is registered)
    assert (farm / "frames" / "frame_0003.png").read_bytes() != \
        (farm / "frames" / "frame_0005.png").read_bytes()
    assert not (tmp_path / "bake" / "frames").exists()


def test_frames_renders_one_chunk_and_saves_the_whole_range(tmp_path):
    cfg = tmp_path / "shot.toml"
    cfg.write_text(TINY)
    r = run_job("--config", cfg, "--frames", "2-3", "--output", tmp_path / "out")
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert pngs(tmp_path / "out") == ["frame_0002.png", "frame_0003.png"]
    assert "rendered frame 3 (2/2)" in r.stdout
    blend = tmp_path / "out" / "shot.blend"
    moved = tmp_path / "elsewhere" / "shot.blend"
    moved.parent.mkdir()
    blend.rename(moved)
    assert render_chunk(moved, 7, 7)[:3] == ["//frames/frame_", 1, 7]
    assert pngs(tmp_path / "elsewhere") == ["frame_0007.png"]


def test_gpu_where_cycles_finds_none_is_one_line_before_the_bake(tmp_path):
    cfg = tmp_path / "shot.toml"
    cfg.write_text(TINY)
    r = run_job("--config", cfg, "--engine", "CYCLES", "--device", "GPU", "--frames", "1",
                "--output", tmp_path / "out")
    if r.returncode == 0:                      # a machine with a GPU: it rendered on it
        assert "Cycles renders on the GPU (" in r.stdout
        assert render_chunk(tmp_path / "out" / "shot.blend", 1, 1)[4] == "GPU"
        return
    one_line_error(r, "--device = 'GPU': Cycles finds no GPU on this machine",
                   "render with --device CPU")
    assert "baked" not in r.stdout and not (tmp_path / "out").exists()


def test_the_flamenco_tasks_run_in_order_render_every_frame_once(tmp_path):
    cfg = tmp_path / "shot.toml"
    cfg.write_text(TINY)
    out = tmp_path / "renders"
    tasks = compile_job({"render_job_script": str(JOB), "config": str(cfg),
                         "output_dir": str(out), "job_name": "farmed", "frames": "1-7",
                         "chunk_size": 3, "device": "CPU", "cycles_device": ""})["tasks"]
    bake = tasks[0]["commands"][0]["parameters"]["args"]
    # blender -b --python render_job.py -- ARGS is render_job.py ARGS on the wheel.
    assert bake[:2] == ["--python", str(JOB)]
    r = run_job(*bake[bake.index("--") + 1:])
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    for t in tasks[1:]:
        p = t["commands"][0]["parameters"]
        s, e = p["args"][p["args"].index("-s") + 1], p["args"][p["args"].index("-e") + 1]
        render_chunk(Path(p["blendfile"]), s, e)
    assert pngs(out) == [f"frame_{f:04d}.png" for f in range(1, 8)]

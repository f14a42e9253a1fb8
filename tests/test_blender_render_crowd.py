"""A render job with a crowd (scripts/render_job.py ``[[crowds]]``) builds and bakes
the leader and its N followers, each its own rig, and a shot of the crowd (no render)."""
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
pytest.importorskip("bpy")

pytestmark = pytest.mark.blender
ROOT = Path(__file__).resolve().parents[1]
JOB = ROOT / "scripts" / "render_job.py"

CONFIG = """
[job]
seconds = 0.5
fps = 24
[camera]
follow = "each"
[terrain.mountain]
kind = "ski_slope"
length = 120.0
width = 60.0
[[figures]]
sport = "snowboarder"
ground = "mountain"
start = [15.0, 30.0]
direction_deg = -90.0
heading_deg = -90.0
[[crowds]]
name = "School"
count = 3
gap_m = 3.0
lateral_m = [-1.0, 1.0]
seed = 3
body_jitter = 0.05
period_jitter = 0.05
[crowds.leader]
sport = "skier"
name = "Instructor"
ground = "mountain"
start = [-4.0, 30.0]
direction_deg = -90.0
speed = 9.0
period = 2.2
lean_deg = 18.0
heading_deg = -90.0
"""

# Read back in a fresh interpreter: every armature, its first baked location, its keys and
# settings, and the cameras with what their shots aim at.
READ = """
import json, sys, bpy
sys.path.insert(0, sys.argv[2])
from blender_turning import blender as addon
from blender_turning.blender import compat
from blender_turning.blender.anim import bake
addon.register()
bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
out = {"figures": {}, "cameras": sorted(o.name for o in bpy.data.objects if o.type == "CAMERA")}
for o in bpy.data.objects:
    if o.type != "ARMATURE":
        continue
    fcs = list(bake.baked_channels(o).fcurves)
    loc = {fc.array_index: fc for fc in fcs if fc.data_path == "location"}
    out["figures"][o.name] = {"data": o.data.name, "action": bake.figure_action(o).name,
                              "start": [loc[i].evaluate(1.0) for i in range(2)],
                              "keys": len(loc[0].keyframe_points), "curves": len(fcs),
                              "mass": o.turning.mass, "period": o.turning.period}
# Each figure's tracks in the snow: the grooves (two edges of n vertices each, one a frame) and
# the first groove's width (its edges' first vertices).
n = bpy.context.scene.frame_end - bpy.context.scene.frame_start + 1
out["tracks"] = {o.name[len("Track "):]: [len(o.data.vertices) / (2 * n),
                                          (o.data.vertices[0].co - o.data.vertices[n].co).xy.length]
                 for o in bpy.data.objects if o.name.startswith("Track ")}
addon.unregister()
print("JSON" + json.dumps(out))
"""


def test_a_crowd_job_builds_and_bakes_its_leader_and_followers(tmp_path):
    cfg = tmp_path / "crowd.toml"
    cfg.write_text(CONFIG)
    r = subprocess.run([sys.executable, str(JOB), "--config", str(cfg), "--no-render",
                        "--output", str(tmp_path / "out")], capture_output=True, text=True,
                       timeout=600, cwd=ROOT)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert "5 figure(s)" in r.stdout                  # the snowboarder, the leader, 3 followers
    blend = tmp_path / "out" / "crowd.blend"
    r = subprocess.run([sys.executable, "-c", READ, str(blend), str(ROOT)], capture_output=True,
                       text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    got = json.loads(next(line[4:] for line in r.stdout.splitlines() if line.startswith("JSON")))
    figs = got["figures"]
    crowd = ["Instructor", "School 1", "School 2", "School 3"]
    assert sorted(figs) == sorted(crowd + ["Snowboarder"])
    # N + 1 figures, each baked on its own rig and action over the job's 13 frames.
    assert len({figs[n]["data"] for n in crowd}) == 4 == len({figs[n]["action"] for n in crowd})
    assert all(figs[n]["keys"] == 13 and figs[n]["curves"] > 50 for n in crowd)
    # In a line behind the leader (3 m apart uphill, alternating 1 m left and right), each with
    # its own drawn body and period.
    x0, y0 = figs["Instructor"]["start"]
    for i, n in enumerate(crowd[1:], start=1):
        x, y = figs[n]["start"]
        assert abs(y - (y0 + 3.0 * i)) < 0.3 and abs(x - (x0 + (-1.0 if i % 2 else 1.0))) < 0.3
    masses = {round(figs[n]["mass"], 6) for n in crowd}
    periods = {round(figs[n]["period"], 6) for n in crowd}
    assert len(masses) == 4 and len(periods) == 4
    # Tracks from each figure's sport record: a board cuts one groove its width (0.28 m), skis two
    # narrow ones (0.09 m; float32 vertices).
    assert sorted(got["tracks"]) == sorted(crowd + ["Snowboarder"])
    for name, (grooves, width) in got["tracks"].items():
        want = (1, 0.28) if name == "Snowboarder" else (2, 0.09)
        assert grooves == want[0] and abs(width - want[1]) < 1e-5, (name, grooves, width)
    # One shot per lone figure and one for the crowd (not one per member).
    assert got["cameras"] == ["Camera School", "Camera Snowboarder"]


LIMITED = """
[job]
seconds = 0.5
fps = 24
[[crowds]]
name = "Steep"
count = 2
gap_m = 3.0
seed = 3
period_jitter = 0.05
[crowds.leader]
sport = "skier"
name = "Lead"
start = [0.0, 0.0]
direction_deg = -90.0
period = 1.6
lean_deg = 50.0
heading_deg = -90.0
"""


def test_a_crowd_job_says_each_members_limited_lean(tmp_path):
    """Each member of a crowd whose asked 50 deg its bounds hold lower is baked with Bake
    Turns' warning in the job's output: the lean it reached and the bound, every member."""
    cfg = tmp_path / "limited.toml"
    cfg.write_text(LIMITED)
    r = subprocess.run([sys.executable, str(JOB), "--config", str(cfg), "--no-render",
                        "--output", str(tmp_path / "out")], capture_output=True, text=True,
                       timeout=600, cwd=ROOT)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    said = [line for line in (r.stdout + r.stderr).splitlines()
            if "Bake Turns:" in line and "(asked 50.00 deg; limited by" in line]
    for name in ("Lead", "Steep 1", "Steep 2"):
        assert sum(f"Bake Turns: {name}: lean " in line for line in said) == 1, (name, said)

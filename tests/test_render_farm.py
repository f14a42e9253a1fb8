"""Rendering on a farm (no Blender needed): the render job's farm flags (--frames,
--device, --name) are validated like every other value, one line naming the flag, exit 2, before
anything is built; the Flamenco job type is valid JavaScript and authors one bake task and frame
chunks that depend on it, with arguments the render job accepts."""
import subprocess

import pytest

from cli_helpers import ROOT, one_line_error
from flamenco_helpers import JOB_TYPE, compile_job, node
from test_render_job_config import FIG, job

from blender_turning.blender.render.config import load_config
from blender_turning.blender.render.job import parse_args


@pytest.mark.parametrize("flags, names", [
    # 1 s at 24 fps: the job's frames are 1..25
    (["--frames", "0-3"], ["--frames first = 0", "[1, 25] (whole numbers)"]),
    (["--frames", "3-26"], ["--frames last = 26", "[3, 25]"]),
    (["--frames", "5-2"], ["--frames last = 2", "[5, 25]"]),
    (["--frames", "26"], ["--frames first = 26", "[1, 25]"]),
    (["--frames", "x"], ["--frames = 'x' should be A-B"]),
    (["--frames", "1-2-3"], ["--frames = '1-2-3' should be A-B"]),
    (["--frames", "1.5-3"], ["--frames = '1.5-3' should be A-B"]),
    (["--frames", "1-3", "--no-render"], ["--frames = '1-3'", "--no-render renders none"]),
    (["--device", "TPU"], ["--device = 'TPU' is not one of CPU, GPU"]),
    (["--device", "GPU"], ["--device = 'GPU' is for Cycles", "WORKBENCH"]),
    (["--device", "GPU", "--engine", "EEVEE"], ["--device = 'GPU' is for Cycles", "EEVEE"]),
    (["--name", "../up"], ["--name = '../up' is not a plain file name"]),
    (["--name", ""], ["--name = '' is not a plain file name"]),
])
def test_bad_farm_flags_name_the_flag(tmp_path, flags, names):
    r = job(tmp_path, "[job]\nseconds = 1\nfps = 24\n" + FIG, *flags)
    line = one_line_error(r, *names)
    assert line.startswith("render_job: error: ") and r.stdout == ""
    assert not (tmp_path / "out").exists()


def test_frames_are_checked_against_the_seconds_flag(tmp_path):
    """The job's last frame is 1 + seconds * fps after --seconds overrides job.seconds."""
    r = job(tmp_path, "[job]\nseconds = 1\nfps = 24\n" + FIG, "--seconds", "0.5", "--frames",
            "10-25")
    one_line_error(r, "--frames last = 25", "[10, 13]")


def test_good_farm_flags_are_read():
    args = parse_args(["render_job.py", "--config", str(ROOT / "scripts" / "configs" /
                       "skier_slalom.toml"), "--frames", " 3 - 9", "--device", "cpu",
                       "--name", "shot", "--engine", "CYCLES"])
    cfg = load_config(args.config, args)
    assert cfg["frames"] == (3, 9) and cfg["render"]["device"] == "CPU" and cfg["name"] == "shot"
    args.frames, args.device = "7", "gpu"
    cfg = load_config(args.config, args)
    assert cfg["frames"] == (7, 7) and cfg["render"]["device"] == "GPU"


def test_the_job_type_is_valid_javascript():
    r = subprocess.run([node(), "--check", str(JOB_TYPE)], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr


SETTINGS = {"render_job_script": "/farm/blender_turning/scripts/render_job.py",
            "config": "/farm/shots/slalom.toml", "output_dir": "/farm/renders/slalom",
            "job_name": "slalom", "frames": "1-50", "chunk_size": 24, "device": "GPU",
            "cycles_device": ""}


def test_one_bake_then_chunks_that_depend_on_it():
    out = compile_job(SETTINGS)
    tasks = out["tasks"]
    bake, renders = tasks[0], tasks[1:]
    assert bake["name"] == "bake" and bake["deps"] == [] and len(bake["commands"]) == 1
    cmd = bake["commands"][0]["parameters"]
    assert bake["commands"][0]["name"] == "blender-render" and cmd["blendfile"] == ""
    assert cmd["exe"] == "{blender}" and cmd["exeArgs"] == "{blenderArgs}"
    assert cmd["args"][:3] == ["--python", SETTINGS["render_job_script"], "--"]
    # What follows "--" is a command line the render job accepts, baking without rendering.
    args = parse_args(["blender", *cmd["args"]])
    assert args.no_render and args.config.as_posix() == SETTINGS["config"]
    assert (args.output, args.name, args.device) == ("/farm/renders/slalom", "slalom", "GPU")
    # 50 frames in chunks of 24: 1-24, 25-48, 49-50, each a plain -s A -e B -a of the baked .blend.
    assert [t["name"] for t in renders] == ["render-1-24", "render-25-48", "render-49-50"]
    for t, (a, b) in zip(renders, [(1, 24), (25, 48), (49, 50)]):
        assert t["deps"] == ["bake"] and t["type"] == "blender"
        p = t["commands"][0]["parameters"]
        assert p["blendfile"] == "/farm/renders/slalom/slalom.blend"
        assert p["args"] == ["-s", str(a), "-e", str(b), "-a"]


def test_a_single_frame_chunk_and_a_gpu_backend():
    out = compile_job(dict(SETTINGS, frames="5..7", chunk_size=2, cycles_device="OPTIX"))
    args = [t["commands"][0]["parameters"]["args"] for t in out["tasks"][1:]]
    assert args == [["-s", "5", "-e", "6", "-a", "--", "--cycles-device", "OPTIX"],
                    ["-s", "7", "-e", "7", "-a", "--", "--cycles-device", "OPTIX"]]


@pytest.mark.parametrize("change, words", [
    ({"job_name": "a/b"}, 'job_name = "a/b"'),
    ({"job_name": ".hidden"}, 'job_name = ".hidden"'),
    ({"frames": "1-3,7"}, 'frames = "1-3,7"'),
    ({"frames": "9-2"}, 'frames = "9-2"'),
    ({"frames": "0-5"}, 'frames = "0-5"'),
    ({"chunk_size": 0}, "chunk_size = 0"),
    ({"device": "TPU"}, 'device = "TPU"'),
    ({"cycles_device": "VULKAN"}, 'cycles_device = "VULKAN"'),
])
def test_bad_settings_are_refused_by_name(change, words):
    out = compile_job(dict(SETTINGS, **change))
    assert "tasks" not in out and words in out["error"], out


def test_the_job_type_declares_its_settings():
    keys = {s["key"] for s in compile_job(SETTINGS)["job_type"]["settings"]}
    assert set(SETTINGS) == keys


def test_the_bake_refuses_farm_frames_outside_the_shot(tmp_path):
    """The job type cannot read the config, so its bake task passes the farm's frames: a job of
    frames 1-1,000,000 for a 241-frame shot (10 s at 24 fps) stops at the bake, one line naming
    --farm-frames and the shot's frames, nothing built; inside the shot it bakes as before."""
    r = job(tmp_path, "[job]\nseconds = 10\nfps = 24\n" + FIG, "--no-render", "--farm-frames",
            "1-1000000")
    one_line_error(r, "--farm-frames last = 1000000", "[1, 241]", "the shot has frames 1-241")
    assert not (tmp_path / "out").exists()
    args = parse_args(["render_job.py", "--config", str(ROOT / "scripts" / "configs" /
                       "skier_slalom.toml"), "--no-render", "--farm-frames", "1-193"])
    assert load_config(args.config, args)["frames"] is None        # 8 s at 24 fps: 193


def test_the_job_type_passes_its_frames_to_the_bake_and_caps_the_tasks():
    bake = compile_job(dict(SETTINGS, frames="5..7"))["tasks"][0]["commands"][0]["parameters"]
    assert bake["args"][-2:] == ["--farm-frames", "5-7"]
    out = compile_job(dict(SETTINGS, frames="1-1000000", chunk_size=24))
    assert "tasks" not in out and "41667 render tasks; at most 10000" in out["error"], out

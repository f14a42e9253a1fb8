"""The headless render job (scripts/render_job.py): the whole config is validated before
anything is built (no bpy is imported for a bad one), with the core's ranges and field validator;
every bad config or flag is one line naming the key, exit 2, no traceback, and the output folder
is not created."""
import os
import subprocess
import sys

import pytest

from cli_helpers import ROOT, one_line_error, read_only_folder

JOB = ROOT / "scripts" / "render_job.py"
FIG = '[[figures]]\nsport = "skier"\n'


def job(tmp_path, text=None, *flags, raw=None, output=None):
    cfg = tmp_path / "job.toml"
    if raw is not None:
        cfg.write_bytes(raw)
    else:
        cfg.write_text(text)
    out = tmp_path / "out" if output is None else output
    return subprocess.run([sys.executable, str(JOB), "--config", str(cfg), "--output", str(out),
                           *map(str, flags)], capture_output=True, text=True, timeout=120,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)))


def refused(r, tmp_path, *names):
    line = one_line_error(r, *names)
    assert line.startswith("render_job: error: ")
    assert r.stdout == ""                          # nothing was built or baked
    assert not (tmp_path / "out").exists()
    return line


@pytest.mark.parametrize("text, names", [
    ("job = 5\n" + FIG, ["job.toml: job = 5 is not a table"]),
    ("figures = [1]\n", ["job.toml: figures[0] = 1 is not a table"]),
    ("paths = 3\n" + FIG, ["job.toml: paths = 3 is not a table"]),
    ("obstacles = [5]\n" + FIG, ["job.toml: obstacles[0] = 5 is not a table"]),
    ("[job]\nsecnds = 3\n" + FIG, ["job.secnds is not a known field", "did you mean 'seconds'"]),
    (FIG + "leanDeg = 20\n", ["figures[0].leanDeg is not a known field",
                              "did you mean 'lean_deg'"]),
    ("[rendr]\n" + FIG, ["job.toml: rendr is not a known field", "did you mean 'render'"]),
    ('[render]\nantialiasing = "4"\n' + FIG,
     ["render.antialiasing = '4' is not one of OFF, FXAA, 5, 8, 11, 16, 32"]),
    ('[render]\ncrowd_antialiasing = "fxaa"\n' + FIG, ["render.crowd_antialiasing = 'fxaa'"]),
    (FIG + "period = -1\n", ["figures[0].period = -1", "[0.3, 20] s"]),
    (FIG + "lean_deg = 89\n", ["figures[0].lean_deg = 89", "[1, 60) deg",
                                "the skier's fall angle theta_fall is 60 deg"]),
    ('[[figures]]\nsport = "cyclist"\nlean_deg = 55\n',
     ["figures[0].lean_deg = 55 is outside the allowed range [1, 55) deg: the cyclist's fall "
      "angle theta_fall is 55 deg"]),
    (FIG + "lean_deg = nan\n", ["figures[0].lean_deg = nan", "[1, 60) deg"]),
    (FIG + 'lean_deg = "20"\n', ["figures[0].lean_deg = '20' is not a number"]),
    (FIG + "start = [nan, 0]\n", ["figures[0].start[0] = nan"]),
    (FIG + "start = [1e300, 0]\n", ["figures[0].start[0] = 1e+300"]),
    ('[job]\nname = "../escaped"\n' + FIG, ["job.name = '../escaped' is not a plain file name"]),
    ('[job]\nname = "a/b"\n' + FIG, ["job.name = 'a/b'"]),
    ("[job]\noutput = 5\n" + FIG, ["job.output = 5 is not a string"]),
    ("[job]\nseconds = 0\n" + FIG, ["job.seconds = 0", "(0, 600] s"]),
    ("[job]\nfps = 2.5\n" + FIG, ["job.fps = 2.5", "(whole numbers)"]),
    ('[camera]\nfollow = "Skeir"\n' + FIG, ["camera.follow = 'Skeir'"]),
    (FIG + FIG, ["figures[1].name = 'Skier' is the name of an earlier figure"]),
    ('[paths.p]\npoints = [[0, 0], [5, 5], [5, 5]]\n' + FIG + 'control = "path"\npath = "p"\n',
     ["paths.p.points[2] = [5.0, 5.0] is the same point as paths.p.points[1]"]),
    ('[paths.p]\npoints = [[0, 0]]\n' + FIG + 'control = "path"\npath = "p"\n',
     ["paths.p.points has 1 points"]),
    ('[paths.slalom]\npoints = [[0, 0], [5, 5]]\n' + FIG + 'control = "path"\npath = "slalon"\n',
     ["figures[0].path = 'slalon'", "did you mean 'slalom'"]),
    ("[[obstacles]]\nat = [0, 0]\nsize = -1\n" + FIG, ["obstacles[0].size = -1"]),
    ("[job\n", ["not valid TOML"]),
    ("", ["no [[figures]]"]),
])
def test_bad_configs_name_the_key(tmp_path, text, names):
    refused(job(tmp_path, text), tmp_path, *names)


def test_a_binary_config_names_the_file(tmp_path):
    png = (ROOT / "docs" / "demo.png").read_bytes()[:200]
    refused(job(tmp_path, raw=png), tmp_path, "config", "job.toml", "not a UTF-8 text file")


@pytest.mark.parametrize("flags, names", [
    (["--seconds", "nan"], ["--seconds = nan"]),
    (["--seconds", "0"], ["--seconds = 0.0", "(0, 600] s"]),
    (["--seconds", "1e9"], ["--seconds = 1000000000.0"]),
    (["--frame-step", "0"], ["--frame-step = 0"]),
    (["--resolution", "10"], ["--resolution = '10' should be WIDTHxHEIGHT"]),
    (["--resolution", "2x2"], ["--resolution[0] = 2", "[4, 8192] px"]),
    (["--engine", "POVRAY"], ["--engine = 'POVRAY'"]),
    (["--seconds", "x"], ["--seconds", "invalid float value"]),
])
def test_bad_flags_name_the_flag(tmp_path, flags, names):
    refused(job(tmp_path, FIG, *flags), tmp_path, *names)


@pytest.mark.parametrize("text, flags, names", [
    ('[render]\nengine = "POVRAY"\n' + FIG, ["--engine", "CYCLES"], ["render.engine = 'POVRAY'"]),
    ("[render]\nresolution = [1, 1]\n" + FIG, ["--resolution", "8x8"],
     ["render.resolution[0] = 1"]),
    ("[job]\nseconds = -1\n" + FIG, ["--seconds", "1"], ["job.seconds = -1"]),
])
def test_the_config_is_checked_even_where_a_flag_overrides_it(tmp_path, text, flags, names):
    refused(job(tmp_path, text, *flags), tmp_path, *names)


def test_output_in_a_read_only_folder_is_refused_before_the_bake(tmp_path):
    ro = read_only_folder(tmp_path)
    refused(job(tmp_path, FIG, output=ro / "out"), tmp_path, "--output", "cannot be written")


def test_output_pointing_at_a_file_is_refused_before_the_bake(tmp_path):
    f = tmp_path / "taken"
    f.write_text("mine")
    refused(job(tmp_path, FIG, output=f), tmp_path, "--output", "is a file, not a folder")
    assert f.read_text() == "mine"


def test_output_below_a_file_is_refused(tmp_path):
    f = tmp_path / "taken"
    f.write_text("mine")
    refused(job(tmp_path, FIG, output=f / "out"), tmp_path, "--output", "is a file")


def test_an_empty_output_is_refused(tmp_path):
    refused(job(tmp_path, FIG, output=""), tmp_path, "--output = ''")

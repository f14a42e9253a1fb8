"""The command line: every hostile or careless input ends in one line naming the flag (or the
file, field, row and column) and exit 2, with no traceback, no numpy warning and the output folder
as it was; outputs are checked before the work and written all together or not at all."""
import json
import math
import os
import stat

import pytest

from blender_turning.cli import main
from blender_turning.core.ranges import RANGES, lean_range
from cli_helpers import ROOT, one_line_error, read_only_folder, run, snapshot

SCENES = ROOT / "scenes"


def small_scene(folder, **change):
    doc = {"name": "road", "figure": {"preset": "cyclist", "limits": {"dC_f_max": 0.4}},
           "path": {"polyline": [[0, 0], [12, 0]]},
           "obstacles": [{"type": "segment", "from": [-5, -3], "to": [40, -3]},
                         {"type": "segment", "from": [-5, 3], "to": [40, 3]}],
           "planner": {"stages": 4, "choices": 3}}
    doc.update(change)
    p = folder / "scene.json"
    p.write_text(json.dumps(doc))
    return p


# -- inputs that would run away --------------------------------------------------------------------

def test_a_run_of_a_billion_steps_is_refused_with_the_bound(tmp_path):
    before = snapshot(tmp_path)
    r = run("simulate", "--duration", "100000", "--dt", "0.001", "--out", tmp_path / "o.csv")
    line = one_line_error(r, "--duration", "--dt", "200,000 steps")
    assert "1e+08 steps" in line
    assert snapshot(tmp_path) == before


def test_a_run_shorter_than_one_step_is_refused():
    one_line_error(run("simulate", "--duration", "1e-300", "--fps", "24"), "--duration = 1e-300",
                   "shorter than one step")


def test_frames_are_bounded_too(tmp_path):
    one_line_error(run("simulate", "--duration", "1000", "--fps", "1000"), "--fps", "1e+06 frames",
                   "200,000 frames")


@pytest.mark.parametrize("flag, value, bound", [("--stages", 64, "[1, 16]"),
                                                ("--choices", 64, "[2, 9]"),
                                                ("--choices", 2.5, "[2, 9]")])
def test_a_search_that_would_explode_is_refused(tmp_path, flag, value, bound):
    r = run("follow", SCENES / "slalom.json", flag, value, "--out", tmp_path / "t.csv")
    if isinstance(value, float):         # argparse: an int flag
        assert r.returncode == 2 and flag in r.stderr and "Traceback" not in r.stderr
        return
    one_line_error(r, f"{flag} = {value}", bound)
    assert list(tmp_path.iterdir()) == []


# -- values that break the numerics get the range the model handles --------------------------------

@pytest.mark.parametrize("flag, value, key", [
    ("--period", "1e-300", "period"), ("--mass", "1e-300", "m"), ("--speed", "1e-300", "V_cm"),
    ("--inertia", "100000", "I_v"), ("--com-height", "1e-300", "l"), ("--gravity", "1e300", "g"),
    ("--omega0", "1e300", "omega0"), ("--lean-deg", "nan", "lean"),
    ("--heading-deg", "inf", "heading"), ("--theta0-deg", "-90", "theta_v0"),
    ("--dt", "0", "dt"), ("--fps", "0", "fps"), ("--duration", "-1", "duration"),
])
def test_values_outside_the_models_range_name_the_flag_and_range(tmp_path, flag, value, key):
    """(``lean``: the default preset's lean range, below the skier's fall angle.)"""
    rng = lean_range(math.radians(60), "the skier") if key == "lean" else RANGES[key]
    rng = rng.deg() if flag.endswith("-deg") else rng
    r = run("simulate", flag, value, "--duration" if flag != "--duration" else "--dt", "2"
            if flag != "--duration" else "0.02", "--out", tmp_path / "o.csv")
    one_line_error(r, flag, str(rng))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args", [["--mass", "1000"], ["--inertia", "0"], ["--speed", "60"],
                                  ["--gravity", "30"], ["--gravity", "1"], ["--period", "20"],
                                  ["--period", "0.3", "--lean-deg", "1"], ["--com-height", "3"],
                                  ["--com-height", "0.2"], ["--lean-deg", "1"]])
def test_the_ends_of_the_ranges_run_without_a_warning(args):
    r = run("simulate", *args, "--duration", "4")
    assert r.returncode == 0 and r.stderr == "", r.stderr


# -- output paths ----------------------------------------------------------------------------------

def test_an_unwritable_out_is_named_before_the_work(tmp_path, monkeypatch, capsys):
    import blender_turning.cli.simulate as sim
    monkeypatch.setattr(sim, "simulate", lambda *a, **k: pytest.fail("simulated first"))
    ro = read_only_folder(tmp_path)
    before = snapshot(tmp_path)
    assert main(["simulate", "--plot", str(tmp_path / "p.png"), "--out",
                 str(ro / "o.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert f"--out = '{ro / 'o.csv'}' cannot be written" in err and ".tmp-" not in err
    assert snapshot(tmp_path) == before          # no p.png, no hidden file


def test_plot_is_not_left_behind_when_out_fails(tmp_path):
    ro = read_only_folder(tmp_path)
    one_line_error(run("simulate", "--duration", "2", "--plot", tmp_path / "p.png", "--out",
                       ro / "o.csv"), "--out")
    assert not any(p.name != "RO" for p in tmp_path.iterdir())


def test_follow_leaves_no_track_when_stats_cannot_be_written(tmp_path):
    scene = small_scene(tmp_path)
    ro = read_only_folder(tmp_path)
    before = snapshot(tmp_path)
    one_line_error(run("follow", scene, "--out", tmp_path / "t.csv", "--stats",
                       ro / "s.json"), "--stats")
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("args, flag, says", [
    (["--out", ""], "--out", "is not a file path"),
    (["--out", " "], "--out", "is not a file path"),
    (["--out", "."], "--out", "is a folder"),
    (["--out", "pipe"], "--out", "is not a regular file"),
    (["--out", "nowhere/o.csv"], "--out", "does not exist"),
    (["--out", "a.csv", "--plot", "a.csv"], "--plot", "same file as --out"),
])
def test_bad_output_paths(tmp_path, args, flag, says):
    os.mkfifo(tmp_path / "pipe")             # a device or pipe (/dev/null) is never replaced
    before = snapshot(tmp_path)
    one_line_error(run("simulate", "--duration", "1", *args, cwd=tmp_path), flag, says)
    assert snapshot(tmp_path) == before


@pytest.mark.parametrize("umask", [0o022, 0o002, 0o077])
def test_outputs_get_the_users_umask(tmp_path, umask):
    pytest.importorskip("matplotlib")
    r = run("simulate", "--duration", "1", "--out", tmp_path / "o.csv", "--plot",
            tmp_path / "p.png", umask=umask)
    assert r.returncode == 0, r.stderr
    for name in ("o.csv", "p.png"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o666 & ~umask
    scene = small_scene(tmp_path)
    r = run("follow", scene, "--out", tmp_path / "t.csv", "--stats", tmp_path / "s.json",
            umask=umask)
    assert r.returncode == 0, r.stderr
    for name in ("t.csv", "s.json"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == 0o666 & ~umask


def test_an_existing_output_is_replaced_whole(tmp_path):
    out = tmp_path / "o.csv"
    out.write_text("old")
    assert run("simulate", "--duration", "1", "--out", out).returncode == 0
    assert out.read_text().startswith("t,x,y")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o.csv"]


# -- files -----------------------------------------------------------------------------------------

def schedule(tmp_path, text, raw=None):
    p = tmp_path / "s.csv"
    p.write_bytes(raw if raw is not None else text.encode())
    return p


@pytest.mark.parametrize("text, names", [
    ("t,period,lean_deg,heading_deg\n0,2,20,0\n5,2\n", ["s.csv", "row 2 (line 3)", "2 values"]),
    ("t,period,lean_deg\n0,2,20\n5,fast,20\n", ["s.csv", "row 2 (line 3), column period",
                                               "'fast' is not a number"]),
    ("t,period,lean_deg\n0,2,95\n", ["s.csv", "column lean_deg = 95.0", "[1, 60) deg"]),
    ("t,period,lean_deg\n0,2,20\n0,2,25\n", ["s.csv", "column t = 0.0", "does not come after"]),
    ("t,perod,lean_deg\n0,2,20\n", ["s.csv", "'perod'", "did you mean 'period'"]),
    ("t,period,lean_deg,heading_deg\n0,2,20,0\n5,2,20,\n", ["s.csv", "heading_deg is blank"]),
    ("t,period,lean_deg\n", ["s.csv", "at least one row"]),
    ("", ["s.csv", "empty"]),
    ('t,period,lean_deg\n0,2,"' + "x" * 200000 + '"\n', ["s.csv", "is not a CSV file"]),
])
def test_bad_schedules_name_file_row_column_and_value(tmp_path, text, names):
    one_line_error(run("simulate", "--schedule", schedule(tmp_path, text), "--duration", "2"),
                   *names)


def test_a_binary_schedule_names_the_file(tmp_path):
    png = (ROOT / "docs" / "demo.png").read_bytes()[:200]
    one_line_error(run("simulate", "--schedule", schedule(tmp_path, "", png), "--duration", "2"),
                   "schedule file", "s.csv", "not a UTF-8 text file")


@pytest.mark.parametrize("raw", [
    b"t, period, lean_deg, heading_deg\n0, 2, 15, 0\n6, 3, 25, 10\n",
    b"\xef\xbb\xbft,period,lean_deg,heading_deg\r\n0,2,15,0\r\n6,3,25,10\r\n",
    b"t,period,lean_deg\n0,2,15\n6,3,25\n",                  # heading_deg is optional
    b"t,period,lean_deg,heading_deg\n0,2,15,\n6,3,25,\n",   # ... or blank on every row
])
def test_schedules_as_the_readme_writes_them(tmp_path, raw):
    out = tmp_path / "o.csv"
    r = run("simulate", "--schedule", schedule(tmp_path, "", raw), "--duration", "8", "--out", out)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert out.read_text().startswith("t,x,y")


def test_the_header_spelling_does_not_change_the_run(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir(), b.mkdir()
    (a / "s.csv").write_text("t,period,lean_deg,heading_deg\n0,2,15,0\n6,3,25,10\n")
    (b / "s.csv").write_bytes(b"\xef\xbb\xbf t , period , lean_deg , heading_deg \n"
                              b"0, 2, 15, 0\n6, 3, 25, 10\n")
    for d in (a, b):
        assert run("simulate", "--schedule", d / "s.csv", "--duration", "8", "--out",
                   d / "o.csv").returncode == 0
    assert (a / "o.csv").read_text() == (b / "o.csv").read_text()


def test_a_schedule_without_heading_holds_heading_zero(tmp_path):
    """Without heading_deg the heading is held at 0 deg, as without --heading-deg."""
    with_h = schedule(tmp_path, "t,period,lean_deg,heading_deg\n0,2,20,0\n")
    assert run("simulate", "--schedule", with_h, "--duration", "6", "--out",
               tmp_path / "a.csv").returncode == 0
    no_h = schedule(tmp_path, "t,period,lean_deg\n0,2,20\n")
    assert run("simulate", "--schedule", no_h, "--duration", "6", "--out",
               tmp_path / "b.csv").returncode == 0
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()


@pytest.mark.parametrize("text, names", [
    ("[" * 100000, ["scene file", "nested too deeply"]),
    ("{not json", ["scene file", "not valid JSON"]),
    ("[1, 2]", ["scene.json", "must be a JSON object"]),
])
def test_unreadable_scenes(tmp_path, text, names):
    p = tmp_path / "scene.json"
    p.write_text(text)
    one_line_error(run("follow", p, "--out", tmp_path / "t.csv"), *names)
    assert sorted(q.name for q in tmp_path.iterdir()) == ["scene.json"]


def test_a_binary_scene_names_the_file(tmp_path):
    p = tmp_path / "scene.json"
    p.write_bytes((ROOT / "docs" / "demo.png").read_bytes()[:200])
    one_line_error(run("follow", p), "scene file", "scene.json", "not a UTF-8 text file")


@pytest.mark.parametrize("change, names", [
    ({"path": {"polyline": [[0, 0], ["25", 0]]}},
     ["path.polyline[1][0] = '25' is not a number"]),
    ({"path": {"polyline": [[0, 0], [1e300, 0]]}},
     ["path.polyline[1][0] = 1e+300 is outside the allowed range [-100000, 100000] m"]),
    ({"path": {"polyline": [[0, 0], [12, 0], [12, 0]]}},
     ["path.polyline[2] = [12.0, 0.0] is the same point as path.polyline[1]"]),
    ({"path": {"bezier": [[0, 0], [4, 0], [8, 0], [12, 0], [12, 0], [12, 0], [12, 0]]}},
     ["path.bezier[6]", "same point as path.bezier[3]"]),
    ({"start": {"position": [0, "0"]}}, ["start.position[1] = '0' is not a number"]),
    ({"obstacles": [{"type": "circle", "center": [5, 1e300], "radius": 1}]},
     ["obstacles[0].center[1] = 1e+300"]),
    ({"obstacles": [5]}, ["obstacles[0] = 5 is not a table"]),
    ({"figure": {"preset": "skier", "body": {"m": 1e-300}}},
     ["figure.body.m = 1e-300", "[1, 1000] kg"]),
    ({"figure": {"preset": "skier", "body": {"mass": 70}}},
     ["figure.body.mass is not a known field", "(known: I_v, V_cm, g, l, m)"]),
    ({"planner": {"stages": 64}}, ["planner.stages = 64", "[1, 16] (whole numbers)"]),
    ({"planner": {"stagse": 4}}, ["planner.stagse", "did you mean 'stages'"]),
    ({"duration": 1e9}, ["duration = 1000000000.0", "(0, 3600] s"]),
])
def test_bad_scene_fields_name_file_field_and_value(tmp_path, change, names):
    one_line_error(run("follow", small_scene(tmp_path, **change), "--out", tmp_path / "t.csv"),
                   "scene.json: ", *names)
    assert not (tmp_path / "t.csv").exists()


def test_a_message_reads_the_same_from_a_flag_and_a_file(tmp_path):
    """The same bad mass from the command line and from a scene file: the same words."""
    flag = one_line_error(run("simulate", "--mass", "0.5"), "--mass")
    field = one_line_error(run("follow", small_scene(
        tmp_path, figure={"preset": "cyclist", "body": {"m": 0.5}})), "figure.body.m")
    assert flag.split("--mass", 1)[1] == field.split("figure.body.m", 1)[1]


def test_a_body_whose_inertia_term_overflows_is_refused():
    """Each body value in range, together out of what the model handles (Eq. 2's J)."""
    one_line_error(run("simulate", "--mass", "1", "--inertia", "300"), "I_v = 300",
                   "m = 1 kg", "J = (I_v + l^2 m) / (m l) = 301 m", "(0, 100] m")


def test_a_path_too_long_for_a_bounded_run_asks_for_a_duration(tmp_path):
    scene = small_scene(tmp_path, path={"polyline": [[0, 0], [90000, 0]]})
    one_line_error(run("follow", scene), "scene.json: duration is missing", "(0, 3600] s")


@pytest.mark.parametrize("out, says", [("", "is not a folder path"),
                                       ("s.csv", "is a file, not a folder")])
def test_figures_out_must_be_a_folder(tmp_path, out, says):
    (tmp_path / "s.csv").write_text("mine")
    before = snapshot(tmp_path)
    one_line_error(run("figures", "--out", out, cwd=tmp_path), "--out", says)
    assert snapshot(tmp_path) == before


def test_a_horizon_of_too_many_steps_is_refused(tmp_path):
    scene = small_scene(tmp_path, planner={"stages": 4, "stage_time": 60, "dt": 0.001,
                                           "sample_dt": 0.1})
    one_line_error(run("follow", scene), "scene.json: planner: the horizon N t_stage / dt",
                   "240000", "[1, 2000]")
    one_line_error(run("follow", small_scene(tmp_path), "--stages", "16", "--stage-time", "60"),
                   "--stages, --choices, --choices-near, --stage-time", "[1, 2000]")


def test_the_search_size_is_bounded():
    """N = 16 and q = 9 are each allowed; together (9^16 leaves) they run for minutes."""
    one_line_error(run("follow", SCENES / "slalom.json", "--stages", "16", "--choices", "9"),
                   "--choices", "q^N = 9^16", "7^16")


def test_an_infeasible_plan_writes_only_its_plot(tmp_path):
    """README: with --plot, the plot of the run up to the failure is the one file written."""
    pytest.importorskip("matplotlib")
    wall = {"type": "segment", "from": [8, -3], "to": [8, 3]}
    scene = small_scene(tmp_path, obstacles=[
        {"type": "segment", "from": [-5, -3], "to": [40, -3]},
        {"type": "segment", "from": [-5, 3], "to": [40, 3]}, wall])
    r = run("follow", scene, "--out", tmp_path / "t.csv", "--stats", tmp_path / "s.json",
            "--plot", tmp_path / "p.png")
    one_line_error(r, "no feasible plan at t = ")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.png", "scene.json"]
    assert (tmp_path / "p.png").read_bytes()[:4] == b"\x89PNG"

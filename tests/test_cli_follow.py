"""``python -m blender_turning follow``: outputs, one-line errors, exit codes."""
import csv
import json
import subprocess
import sys

import pytest

from blender_turning.cli import main
from blender_turning.core.physics.trajectory import COLUMNS


def small_scene(tmp_path, wall=False, **extra):
    doc = {
        "name": "short road",
        "figure": {"preset": "cyclist", "limits": {"dC_f_max": 0.4}},
        "path": {"polyline": [[0, 0], [25, 0]]},
        "clearance": 0.3,
        "obstacles": [{"type": "segment", "from": [-5, -3], "to": [60, -3]},
                      {"type": "segment", "from": [-5, 3], "to": [60, 3]},
                      {"type": "circle", "center": [14, 1.6], "radius": 0.4}],
        "planner": {"stages": 5, "choices": 3},
        **extra,
    }
    if wall:
        doc["obstacles"].append({"type": "segment", "from": [20, -3], "to": [20, 3]})
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(doc))
    return p


def test_follow_writes_track_stats_and_plot(tmp_path, capsys):
    scene = small_scene(tmp_path)
    out, stats, plot = tmp_path / "t.csv", tmp_path / "s.json", tmp_path / "p.png"
    rc = main(["follow", str(scene), "--stages", "6", "--choices", "5", "--stage-time", "0.3",
               "--choices-near", "7", "--out", str(out), "--stats", str(stats), "--plot",
               str(plot)])
    assert rc == 0
    with open(out) as fh:
        rows = list(csv.reader(fh))
    assert tuple(rows[0]) == COLUMNS and len(rows) > 20
    doc = json.loads(stats.read_text())
    assert doc["settings"]["n_stages"] == 6 and doc["settings"]["q"] == 5
    assert doc["settings"]["q_near"] == 7
    r0 = doc["replans"][0]
    for key in ("expanded", "clipped_collision", "clipped_fall", "clipped_bound", "wall_time"):
        assert key in r0
    assert doc["totals"]["replans"] == len(doc["replans"])
    assert doc["totals"]["expanded"] == sum(r["expanded"] for r in doc["replans"])
    assert plot.stat().st_size > 1000
    assert "follow: short road" in capsys.readouterr().out


def test_follow_plans_the_racers_line_when_asked(tmp_path, capsys):
    """``--line race``: the least time down the road (core/planner/reach.py); the road is
    straight and the tree beside it, so the line is straight and costs nothing."""
    stats = tmp_path / "s.json"
    assert main(["follow", str(small_scene(tmp_path)), "--line", "race", "--stats",
                 str(stats)]) == 0
    doc = json.loads(stats.read_text())
    assert doc["settings"]["line"] == "race"
    assert all(r["f_opt"] == 0.0 for r in doc["replans"])
    with pytest.raises(SystemExit):
        main(["follow", str(small_scene(tmp_path)), "--line", "fastest"])
    assert "invalid choice: 'fastest'" in capsys.readouterr().err


def test_closed_corridor_is_one_line_with_the_position(tmp_path):
    scene = small_scene(tmp_path, wall=True)
    r = subprocess.run([sys.executable, "-m", "blender_turning", "follow", str(scene),
                        "--out", str(tmp_path / "t.csv")], capture_output=True, text=True)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1
    assert "no feasible plan at t = " in lines[0] and "position (" in lines[0]
    assert not (tmp_path / "t.csv").exists()


@pytest.mark.parametrize("doc_change, field", [
    ({"clearance": -1}, "scene.json: clearance = -1"),
    ({"planner": {"choices": 1}}, "scene.json: planner.choices = 1"),
    ({"start": {"lean_deg": 100}}, "scene.json: start.lean_deg = 100"),
])
def test_bad_scene_is_one_line_naming_the_field(tmp_path, capsys, doc_change, field):
    scene = small_scene(tmp_path, **doc_change)
    assert main(["follow", str(scene)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]


@pytest.mark.parametrize("value, text", [("12", "--choices-near = 12 is outside"),
                                         ("1", "q_near = 1 is outside")])
def test_bad_choices_near_is_one_line(tmp_path, capsys, value, text):
    assert main(["follow", str(small_scene(tmp_path)), "--choices-near", value]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and text in err[0]


def test_missing_file_and_bad_json(tmp_path, capsys):
    assert main(["follow", str(tmp_path / "nope.json")]) == 2
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["follow", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "not valid JSON" in err[1]
    assert "nope.json" in err[0] and "cannot be read" in err[0]


def test_bad_flags(tmp_path, capsys):
    scene = small_scene(tmp_path)
    assert main(["follow", str(scene), "--stages", "0"]) == 2
    assert main(["follow", str(scene), "--stage-time", "0.33"]) == 2
    err = capsys.readouterr().err
    assert "--stages = 0" in err and "t_stage = 0.33" in err


def run_cli(tmp_path, doc):
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(doc))
    out = tmp_path / "t.csv"
    r = subprocess.run([sys.executable, "-m", "blender_turning", "follow", str(p), "--out",
                        str(out)], capture_output=True, text=True)
    return r, out


def test_switchback_is_not_reached_after_one_stage(tmp_path):
    """Out 12 m and back 3 m to the side: the end lies behind the start.  The end test is the
    progress along the path, so the run does not stop after a stage; at the time limit it has
    not come back (the skier cannot turn that tightly), which is a failure, exit 2, one line
    saying how far along it got, nothing written."""
    doc = {"name": "switchback", "figure": {"preset": "skier", "body": {"V_cm": 6.0},
                                            "limits": {"dC_f_max": 0.3}},
           "path": {"polyline": [[0, 0], [12, 0], [12, 3], [0, 3]]},
           "planner": {"stages": 4, "choices": 3}}
    r, out = run_cli(tmp_path, doc)
    assert r.returncode == 2, r.stdout
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1
    assert "the end of the path was not reached within the time limit" in lines[0]
    assert "m of 27.0 m along the path" in lines[0]
    assert not out.exists()


def test_start_far_from_the_path_is_not_at_its_end(tmp_path):
    """A start 500 m beside the path, beyond its end: not done after one stage."""
    doc = {"name": "far", "figure": {"preset": "cyclist", "limits": {"dC_f_max": 0.4}},
           "path": {"polyline": [[0, 0], [20, 0]]},
           "start": {"position": [40, 500], "heading_deg": 0},
           "planner": {"stages": 3, "choices": 3}}
    r, out = run_cli(tmp_path, doc)
    assert r.returncode == 2
    assert "got 0.0 m of 20.0 m along the path (0%)" in r.stderr.strip().splitlines()[0]
    assert not out.exists()

"""Crowds in the headless render job (scripts/render_job.py ``[[crowds]]``, built by
blender/render/crowds.py): the config is validated like the other job keys (one line naming the
key, nothing built), and a crowd expands into its leader and followers as figures of the job."""
import math
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from cli_helpers import ROOT, one_line_error

JOB = ROOT / "scripts" / "render_job.py"
from blender_turning.blender.render.config import load_config
from blender_turning.core.physics.params import PRESETS

CROWD = """
[terrain.mountain]
kind = "ski_slope"
[[crowds]]
name = "School"
count = 8
gap_m = 3.0
lateral_m = [-1.0, 1.0]
seed = 3
body_jitter = 0.05
period_jitter = 0.05
{extra}
[crowds.leader]
sport = "skier"
name = "Instructor"
ground = "mountain"
start = [-4.0, 50.0]
direction_deg = -90.0
speed = 9.0
period = 2.2
lean_deg = 18.0
heading_deg = -90.0
{leader}
"""


def load(tmp_path, text):
    cfg = tmp_path / "job.toml"
    cfg.write_text(text)
    flags = SimpleNamespace(name=None, seconds=None, frame_step=None, output=str(tmp_path / "o"),
                            engine=None, resolution=None, device=None, frames=None,
                            no_render=False)
    return load_config(cfg, flags)


def test_a_crowd_is_its_leader_and_followers_in_a_line_behind(tmp_path):
    cfg = load(tmp_path, CROWD.format(extra="", leader=""))
    figs = cfg["figures"]
    assert [f["name"] for f in figs] == ["Instructor"] + [f"School {i}" for i in range(1, 9)]
    assert cfg["crowds"] == [{"name": "School", "members": [f["name"] for f in figs],
                              "shot": True}]
    assert all(f["crowd"] == "School" and f["sport"] == "skier" and f["ground"] == "mountain"
               for f in figs)
    lead, followers = figs[0], figs[1:]
    assert lead["body"] is None and lead["start"] == (-4.0, 50.0)
    # Heading -90 deg (down -y): follower i is 3 i m behind, uphill (+y), and lateral_m to the
    # left of the heading (+x): -1, +1, -1, ... m.
    for i, f in enumerate(followers, start=1):
        assert f["start"][1] == pytest.approx(50.0 + 3.0 * i, abs=1e-9)
        assert f["start"][0] == pytest.approx(-4.0 + (-1.0 if i % 2 else 1.0), abs=1e-9)
        body = PRESETS["skier"].body
        for key, base in (("mass", body.m), ("com_height", body.l), ("inertia", body.I_v)):
            assert abs(f["body"][key] / base - 1.0) <= 0.05
        assert abs(f["period"] / 2.2 - 1.0) <= 0.05
        assert {k: v for k, v in f.items() if k not in ("name", "start", "period", "body")} == \
            {k: v for k, v in lead.items() if k not in ("name", "start", "period", "body")}
    # The draws differ between followers (seeded: the same every run).
    assert len({f["period"] for f in followers}) == 8
    assert load(tmp_path, CROWD.format(extra="", leader=""))["figures"] == figs


def test_a_time_gap_is_that_long_at_the_leaders_speed(tmp_path):
    cfg = load(tmp_path, CROWD.format(extra="", leader="").replace("gap_m = 3.0", "gap_s = 0.5"))
    ys = [f["start"][1] for f in cfg["figures"]]
    assert np.allclose(np.diff(ys), 0.5 * 9.0)


def test_a_waiting_crowd_stands_at_the_leaders_start_until_its_time(tmp_path):
    cfg = load(tmp_path, CROWD.format(extra='staging = "wait"', leader=""))
    lead, followers = cfg["figures"][0], cfg["figures"][1:]
    assert lead["time_offset"] == 0.0
    for i, f in enumerate(followers, start=1):
        assert f["start"][1] == pytest.approx(50.0, abs=1e-9)      # all at the leader's start
        assert f["start"][0] == pytest.approx(-4.0 + (-1.0 if i % 2 else 1.0), abs=1e-9)
        assert f["time_offset"] == pytest.approx(3.0 * i / 9.0, rel=1e-12)   # 3 m at 9 m/s
    strung = load(tmp_path, CROWD.format(extra="", leader=""))["figures"]
    assert all(f["time_offset"] == 0.0 for f in strung)


def test_the_demo_has_a_ski_school_of_eight_with_a_shot(tmp_path):
    cfg = load(tmp_path, (ROOT / "scripts" / "configs" / "demo.toml").read_text())
    assert cfg["camera"]["follow"] == "each"
    (school,) = cfg["crowds"]
    assert school["shot"] and len(school["members"]) >= 9
    alone = [f["name"] for f in cfg["figures"] if f["crowd"] is None]
    assert alone == ["Skier", "Snowboarder", "Telemark", "Cyclist"]
    # Beginners in a wedge behind their instructor, who skis skidded turns, at a ski school's
    # speed, a stop at the end, on the mountain's 18 deg (docs/skidding.md).
    lead, *pupils = [f for f in cfg["figures"] if f["crowd"] is not None]
    assert (lead["style"], lead["target_speed"], lead["stop_s"]) == ("skid", 5.0, 3.0)
    assert {(f["style"], f["target_speed"], f["stop_s"]) for f in pupils} == {("wedge", 5.0, 3.0)}
    assert cfg["terrain"][lead["ground"]]["slope_deg"] > 15.0


def test_followers_may_brake_in_their_own_style(tmp_path):
    """``[crowds.followers]`` sets the followers' style, target speed and stop; the rest is
    the leader's, and the leader keeps its own."""
    text = CROWD.format(extra="", leader='target_speed = 6.0\nstyle = "skid"') + \
        '[crowds.followers]\nstyle = "wedge"\ntarget_speed = 4.5\nstop_s = 2.0\n'
    lead, *followers = load(tmp_path, text)["figures"]
    assert (lead["style"], lead["target_speed"], lead["stop_s"]) == ("skid", 6.0, None)
    assert {(f["style"], f["target_speed"], f["stop_s"]) for f in followers} == \
        {("wedge", 4.5, 2.0)}
    plain = load(tmp_path, CROWD.format(extra="", leader='target_speed = 6.0\nstyle = "skid"'))
    assert {f["style"] for f in plain["figures"]} == {"skid"}


@pytest.mark.parametrize("table, words", [
    ('style = "slip"', ["crowds[0].followers.style = 'slip'", "wedge"]),
    ("target_speed = -2", ["crowds[0].followers.target_speed = -2"]),
    ("speed = 3.0", ["crowds[0].followers", "speed"]),
])
def test_bad_follower_settings_are_named(tmp_path, table, words):
    text = CROWD.format(extra="", leader="") + f"[crowds.followers]\n{table}\n"
    with pytest.raises(ValueError) as err:
        load(tmp_path, text)
    for w in words:
        assert w in str(err.value)


@pytest.mark.parametrize("old, new, words", [
    ('style = "wedge"', 'style = "slip"', ["style = 'slip'", "wedge"]),
    ("stop_s = 3.0", "stop_s = -1", ["stop_s = -1"])])
def test_a_bad_style_or_stop_is_named(tmp_path, old, new, words):
    text = (ROOT / "scripts" / "configs" / "demo.toml").read_text().replace(old, new)
    with pytest.raises(Exception) as err:
        load(tmp_path, text)
    for w in words:
        assert w in str(err.value)


@pytest.mark.parametrize("extra, leader, names", [
    ("count = 0", "", ["crowds[0].count = 0", "[1, 200]"]),
    ("", 'control = "path"\npath = "p"',
     ["crowds[0].leader.path = 'p' is not a [paths.<name>]"]),
    ("gap_s = 1.0", "", ["crowds[0].gap_s or gap_m", "exactly one"]),
    ("lateral_x = 2", "", ["crowds[0]", "lateral_x"]),
    ("body_jitter = 0.5", "", ["crowds[0].body_jitter = 0.5", "[0, 0.3]"]),
    ('formation = "peloton"', "", ["crowds[0].formation = 'peloton'"]),
    ("timing_jitter_s = 2.0", "", ["crowds[0].formation", "timing_jitter"]),
    ("", 'sport = "unicyclist"', ["crowds[0].leader.sport = 'unicyclist'"]),
    ("", 'ground = "moon"', ["crowds[0].leader.ground = 'moon'"]),
    ('staging = "queue"', "", ["crowds[0].staging = 'queue'", "along_track, wait"]),
    ('staging = "wait"\ncount = 20', "", ["crowds[0].staging = 'wait'", "starts at 6.67 s",
                                          "job.seconds = 5"]),
])
def test_bad_crowds_name_the_key(tmp_path, extra, leader, names):
    text = CROWD
    for line in (extra, leader):                      # the given value replaces the default
        for given in filter(None, line.splitlines()):
            key = given.split("=")[0].strip()
            text = "\n".join(t for t in text.splitlines() if not t.startswith(f"{key} = "))
    text = text.format(extra=extra, leader=leader)
    cfg = tmp_path / "job.toml"
    cfg.write_text(text)
    r = subprocess.run([sys.executable, str(JOB), "--config", str(cfg), "--output",
                        str(tmp_path / "out")], capture_output=True, text=True, timeout=120)
    line = one_line_error(r, *names)
    assert line.startswith("render_job: error: ") and r.stdout == ""
    assert not (tmp_path / "out").exists()


def test_a_path_leader_is_refused(tmp_path):
    text = ('[paths.p]\npoints = [[0, 0], [0, -20]]\n'
            + CROWD.format(extra="", leader='control = "path"\npath = "p"'))
    with pytest.raises(ValueError, match=r"crowds\[0\].leader.control = 'path'"):
        load(tmp_path, text)


def test_follower_names_may_not_clash_and_each_needs_a_shot(tmp_path):
    with pytest.raises(ValueError, match=r"follower 'School 1' has the name of another figure"):
        load(tmp_path, '[[figures]]\nsport = "skier"\nname = "School 1"\n'
             + CROWD.format(extra="", leader=""))
    with pytest.raises(ValueError, match=r"camera.follow = 'each'.*there is none"):
        load(tmp_path, '[camera]\nfollow = "each"\n' + CROWD.format(extra="shot = false",
                                                                     leader=""))
    assert math.isfinite(load(tmp_path, CROWD.format(extra="shot = false", leader=""))
                         ["figures"][1]["period"])


@pytest.mark.parametrize("before, names", [
    ('[[figures]]\nsport = "skier"\nname = "School 2 Body"\n', ["'School 2'", "'School 2 Body'"]),
    ('[[figures]]\nsport = "skier"\nname = "Sun"\n', ["'Sun'", "an object the job makes"]),
    ('[[figures]]\nsport = "skier"\nname = "mountain"\n', ["'mountain'", "[terrain.mountain]"]),
])
def test_a_member_or_figure_named_like_another_object_is_refused(tmp_path, before, names):
    """Blender renames an object whose name is taken ('School 2 Body.001'): the job refuses the
    config (exit 2) before anything is built, so no .blend is left."""
    cfg = tmp_path / "job.toml"
    cfg.write_text(before + CROWD.format(extra="", leader=""))
    r = subprocess.run([sys.executable, str(JOB), "--config", str(cfg), "--no-render",
                        "--output", str(tmp_path / "o")], capture_output=True, text=True,
                       timeout=300, cwd=ROOT)
    one_line_error(r, "would make an object named", *names, code=2)
    assert not (tmp_path / "o").exists()

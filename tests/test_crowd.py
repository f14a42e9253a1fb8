"""Crowds: formations from a seed, the crowd file reader, batch == one by one."""
import json
import math
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.course.path import HermitePath
from blender_turning.crowd import (Crowd, CrowdFigure, Turns, crowd_from_dict, follow_leader,
                                   offset_path, peloton, run_crowd, synchronized)
from blender_turning.crowd.formations import point_at_distance

SKIER = preset("skier")
LEADER = CrowdFigure("lead", SKIER, Turns(2.0, math.radians(20), 0.0))
PATH = {"path": {"points": [[0, 0], [15, 1.5], [30, 0]], "tangents": [[10, 0], [10, 0], [10, 0]]},
        "planner": {"stages": 4, "choices": 3, "stage_time": 0.3, "lean_bound_deg": 35}}
ROAD = {"path": {"polyline": [[0, 0], [60, 0]]},
        "planner": {"stages": 4, "choices": 3, "stage_time": 0.3}}


def test_follow_leader_is_the_same_for_the_same_seed_and_differs_for_another():
    kw = dict(count=5, gap=1.5, lateral=[-1, 1], body_jitter=0.05, timing_jitter=0.2,
              period_jitter=0.05)
    a, b = follow_leader(LEADER, seed=3, **kw), follow_leader(LEADER, seed=3, **kw)
    c = follow_leader(LEADER, seed=4, **kw)
    assert a == b
    assert [f.figure.body for f in a] != [f.figure.body for f in c]
    for i, f in enumerate(a, start=1):
        assert abs(f.time_offset - 1.5 * i) <= 0.2
        assert f.position == (0.0, -1.0 if i % 2 else 1.0)      # to the left of heading 0 is +y
        for name in ("m", "l", "I_v"):
            r = getattr(f.figure.body, name) / getattr(SKIER.body, name)
            assert 0.95 <= r <= 1.05 and r != 1.0
        assert 0.95 * 2.0 <= f.controller.period <= 1.05 * 2.0
    assert len({f.time_offset for f in a}) == 5


def test_follow_leader_without_jitter_is_the_leaders_track_shifted_in_time_and_sideways():
    fol = follow_leader(LEADER, count=2, gap=10.0, by="distance", lateral=2.0)
    assert [f.time_offset for f in fol] == [1.0, 2.0]            # 10 m at the leader's 10 m/s
    res = run_crowd(Crowd("c", (LEADER,) + fol, duration=8.0))
    lead = res["lead"].trajectory
    for i, f in enumerate(fol, start=1):
        tr = res[f.name].trajectory
        n = len(tr)
        assert n == 8.0 / 0.02 - 50 * i + 1
        np.testing.assert_allclose(tr.t - i * 1.0, lead.t[:n], rtol=0, atol=1e-12)
        np.testing.assert_allclose(tr.y, lead.y[:n] + 2.0, rtol=0, atol=1e-9)
        np.testing.assert_allclose(tr.x, lead.x[:n], rtol=0, atol=1e-9)
        np.testing.assert_array_equal(tr.theta_v, lead.theta_v[:n])


@pytest.mark.parametrize("antiphase", [True, False])
def test_synchronized_pair_turns_in_antiphase_as_mirror_images_or_together(antiphase):
    """Fig. 10, track 1: two figures on one line, out of phase: mirror images about the line
    (Section 1 symmetry), so their tracks cross at every half-turn: figure-8s."""
    pair = synchronized(LEADER, 2, spacing=0.0, antiphase=antiphase)
    assert [f.first_turn for f in pair] == (["left", "right"] if antiphase else ["left"] * 2)
    res = run_crowd(Crowd("pair", pair, duration=10.0))
    a, b = (res[f.name].trajectory for f in pair)
    sign = -1.0 if antiphase else 1.0
    np.testing.assert_allclose(b.y, sign * a.y, rtol=0, atol=1e-9)
    np.testing.assert_allclose(b.theta_v, sign * a.theta_v, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b.x, a.x, rtol=0, atol=1e-9)
    if antiphase:
        assert np.count_nonzero(np.diff(np.sign(a.y - b.y)) != 0) >= 9    # crossings: 8s


def test_synchronized_gap_starts_each_one_later_in_the_same_place():
    pair = synchronized(replace(LEADER, time_offset=0.5), 3, gap=1.25)
    assert [f.time_offset for f in pair] == [0.5, 1.75, 3.0]
    assert {f.position for f in pair} == {(0.0, 0.0)}


def test_synchronized_line_is_centred_across_the_heading():
    line = synchronized(replace(LEADER, controller=Turns(2.0, 0.3, math.pi / 2)), 3,
                        spacing=2.0)
    np.testing.assert_allclose([f.position for f in line], [[2, 0], [0, 0], [-2, 0]],
                               atol=1e-12)


def _path_figure(doc, name="rider", sport="cyclist"):
    c = crowd_from_dict({"duration": 5, "figures": [{"name": name, "preset": sport,
                                                     "follow": doc}]})
    return c.figures[0]


def test_peloton_rows_are_gap_apart_along_the_road_and_abreast_across_it():
    rider = _path_figure(ROAD)
    riders = peloton(rider, 5, gap=3.0, abreast=2, spacing=1.0)
    starts = np.array([f.state0()[:3] for f in riders])
    # 3 rows: front row 6 m along, then 3 m, then the back row (alone) at the start.
    np.testing.assert_allclose(starts, [[6, -0.5, 0], [6, 0.5, 0], [3, -0.5, 0], [3, 0.5, 0],
                                        [0, 0, 0]], atol=1e-9)
    np.testing.assert_allclose(riders[1].controller.scene.path.knots, [[0, 0.5], [60, 0.5]])
    # every rider rides 60 m less its row's start: a row ends as far behind the front row
    ends = [f.controller.scene.path.knots[-1] for f in riders]
    np.testing.assert_allclose(ends, [[60, -0.5], [60, 0.5], [57, -0.5], [57, 0.5], [54, 0]],
                               atol=1e-9)
    assert {f.time_offset for f in riders} == {0.0}
    with pytest.raises(ValueError, match="gap = 40 m"):
        peloton(rider, 6, gap=40.0)


def test_offset_path_keeps_both_legs_of_a_corner_at_the_offset():
    path = HermitePath.from_polyline([[0, 0], [10, 0], [10, 10]])
    off = offset_path(path, 1.0)                                  # to the left: inside
    np.testing.assert_allclose(off.knots, [[0, 1], [9, 1], [9, 10]], atol=1e-12)
    p, head = point_at_distance(path, 15.0)
    np.testing.assert_allclose(p, [10, 5], atol=1e-9)
    assert head == pytest.approx(math.pi / 2)


def test_a_batch_gives_each_figure_exactly_its_run_alone():
    """Figures of one body batch together (per-figure ellipses, heading control, time offsets,
    a fall); each equals the same figure run as a crowd of one, bit for bit."""
    rng = np.random.default_rng(1)
    figs = [CrowdFigure(f"f{k}", SKIER, Turns(float(rng.uniform(1.8, 2.2)),
                                              float(np.radians(rng.uniform(18, 25))),
                                              math.radians(5 * (k % 3))),
                        (0.0, 4.0 * k), "left" if k % 2 else "right", 0.5 * (k % 4))
            for k in range(8)]
    figs.append(CrowdFigure("falls", SKIER, Turns(1.0, math.radians(55), 0.0)))
    crowd = Crowd("batch", figs, duration=16.0)
    res = run_crowd(crowd)
    assert [r.status for r in res.figures] == ["ok"] * 8 + ["fell"]
    for f, r in zip(figs, res.figures):
        alone = run_crowd(Crowd("one", (f,), duration=16.0)).figures[0]
        assert alone.status == r.status
        np.testing.assert_array_equal(r.trajectory.data, alone.trajectory.data)
    assert len(res["falls"].trajectory) < len(res["f0"].trajectory)


def test_crowd_file_builds_formations_after_their_leaders(tmp_path):
    doc = {"name": "school", "seed": 2, "duration": 10,
           "figures": [{"name": "boss", "preset": "skier",
                        "turns": {"period": 2, "lean_deg": 20, "heading_deg": 10}}],
           "formations": [{"type": "follow_leader", "leader": "boss", "count": 3, "gap_s": 1,
                           "body_jitter": 0.05},
                          {"type": "synchronized", "name": "p", "antiphase": True,
                           "template": {"name": "x", "preset": "snowboarder",
                                        "turns": {"period": 3, "lean_deg": 25}}}]}
    c = crowd_from_dict(doc)
    assert [f.name for f in c.figures] == ["boss", "boss-1", "boss-2", "boss-3", "p1", "p2"]
    assert c["boss-2"].time_offset == 2.0
    assert c["boss"].controller.heading == pytest.approx(math.radians(10))
    assert c["p2"].figure.name == "snowboarder" and c["p2"].first_turn == "right"
    assert crowd_from_dict(doc) == c
    (tmp_path / "scene.json").write_text(json.dumps({**PATH, "figure": {"preset": "skier"}}))
    f = crowd_from_dict({"duration": 5, "figures": [
        {"name": "g", "preset": "telemark", "follow": {"scene": "scene.json",
                                                       "planner": {"stages": 3}}}]},
        tmp_path).figures[0]
    assert f.figure.name == "telemark" and f.controller.scene.settings.n_stages == 3
    assert f.controller.scene.settings.q == 3 and f.is_path


TURNS = {"name": "a", "preset": "skier", "turns": {"period": 2, "lean_deg": 20}}


@pytest.mark.parametrize("doc, field", [
    ({"figures": [TURNS]}, "duration"),
    ({"duration": 5, "figures": [{**TURNS, "turns": {"period": -2, "lean_deg": 20}}]},
     "figures[0].turns.period"),
    ({"duration": 5, "figures": [{**TURNS, "preset": "skater"}]}, "figures[0].preset"),
    ({"duration": 5, "figures": [{**TURNS, "body": {"m": 0}}]}, "figures[0].body.m"),
    ({"duration": 5, "figures": [{**TURNS, "start": {"first_turn": "up"}}]},
     "figures[0].start.first_turn"),
    ({"duration": 5, "figures": [{**TURNS, "colour": "red"}]}, "figures[0].colour"),
    ({"duration": 5, "figures": [{"name": "a", "preset": "skier"}]}, "figures[0].turns"),
    ({"duration": 5, "figures": [{"name": "a", "preset": "skier", "follow": {
        "path": {"polyline": [[0, 0]]}}}]}, "crowd: figures[0].follow: path.polyline has 1 points"),
    ({"duration": 5, "figures": [TURNS], "formations": [{"type": "follow_leader",
                                                         "leader": "b", "count": 2,
                                                         "gap_s": 1}]}, "formations[0].leader"),
    ({"duration": 5, "figures": [TURNS], "formations": [{"type": "follow_leader",
                                                         "leader": "a", "count": 2}]},
     "formations[0].gap_s"),
    ({"duration": 5, "figures": [TURNS], "formations": [{"type": "follow_leader",
                                                         "leader": "a", "count": 0,
                                                         "gap_s": 1}]}, "formations[0].count"),
    ({"duration": 5, "figures": [TURNS], "formations": [{"type": "conga"}]},
     "formations[0].type"),
    ({"duration": 5, "formations": [{"type": "peloton", "count": 2, "gap_m": 2,
                                     "template": TURNS}]}, "formations[0]: peloton needs a path"),
    ({"duration": 5, "figures": [TURNS, TURNS]}, "'a' is used twice"),
    ({"duration": 5, "figures": [{**TURNS, "time_offset": 6}]}, "time_offset = 6"),
])
def test_a_bad_crowd_file_is_one_line_naming_the_field(doc, field):
    with pytest.raises(ValueError) as err:
        crowd_from_dict(doc)
    for part in (field,) if isinstance(field, str) else field:
        assert part in str(err.value)
    assert "\n" not in str(err.value)


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "blender_turning", "crowd", *args],
                          capture_output=True, text=True, cwd=cwd)


def test_crowd_command_writes_a_csv_per_figure_and_a_summary(tmp_path):
    scene = tmp_path / "crowd.json"
    scene.write_text(json.dumps({"name": "two", "duration": 3, "formations": [
        {"type": "synchronized", "template": TURNS}]}))
    r = _cli(str(scene), "--out", str(tmp_path / "out"), "--fps", "24", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""                                 # no progress bar into a pipe
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert [f["name"] for f in summary["figures"]] == ["a1", "a2"]
    # The antiphase pair on one line cross each other's tracks: they touch (distance 0).
    assert summary["figures"][0]["closest"]["to"] == "a2"
    assert summary["figures"][0]["closest"]["distance_m"] == 0.0
    assert summary["failed"] == []
    lines = (tmp_path / "out" / "a2.csv").read_text().splitlines()
    assert lines[0].startswith("t,x,y") and len(lines) == 1 + 3 * 24 + 1


def test_crowd_command_bad_file_and_failed_figure_exit_2_with_one_line(tmp_path):
    scene = tmp_path / "crowd.json"
    scene.write_text(json.dumps({"duration": 3, "figures": [{**TURNS, "body": {"l": -1}}]}))
    r = _cli(str(scene), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "figures[0].body.l" in r.stderr
    assert not (tmp_path / "out").exists()
    scene.write_text(json.dumps({"duration": 6, "figures": [
        TURNS, {"name": "b", "preset": "skier", "turns": {"period": 1, "lean_deg": 55}}]}))
    r = _cli(str(scene), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.count("\n") == 1
    assert "1 of 2 figures failed" in r.stderr and "b: fell over at t =" in r.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["failed"] == ["b"] and (tmp_path / "out" / "a.csv").exists()


def test_crowds_need_neither_bpy_nor_dask_nor_tqdm(tmp_path):
    """The core stays importable and usable without the optional extras: with dask and tqdm
    made unimportable a crowd runs, and --scheduler names what is missing."""
    scene = tmp_path / "crowd.json"
    scene.write_text(json.dumps({"duration": 2, "figures": [TURNS]}))
    code = f"""
import sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] in ('dask', 'distributed', 'tqdm'):
            raise ImportError(name)
sys.meta_path.insert(0, Block())
from blender_turning.cli import main
assert main(['crowd', {str(scene)!r}, '--out', {str(tmp_path / 'o')!r}]) == 0
assert main(['crowd', {str(scene)!r}, '--out', {str(tmp_path / 'o')!r},
             '--scheduler', 'tcp://127.0.0.1:1']) == 2
bad = [m for m in sys.modules if m.split('.')[0] in ('bpy', 'mathutils', 'dask', 'tqdm')]
print(bad)
sys.exit(1 if bad else 0)
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "--scheduler needs dask.distributed" in r.stderr


def test_the_documented_crowd_example_is_a_valid_crowd_file():
    from pathlib import Path
    root = Path(__file__).resolve().parent.parent
    text = (root / "docs" / "crowds.md").read_text()
    block = text[text.index("## Crowds on the command line"):].split("```json\n", 1)[1].split("```")[0]
    crowd = crowd_from_dict(json.loads(block), root / "scenes" / "crowds")
    assert len(crowd.figures) == 2 + 8 + 2 + 6 and crowd["guide"].figure.name == "telemark"


def test_a_path_figure_that_fails_is_reported_not_raised(monkeypatch):
    from blender_turning.core.errors import PathNotFinished
    from blender_turning.core.course.scene import Scene

    def unfinished(self):
        raise PathNotFinished(9.0, 12.0, 30.0)

    crowd = Crowd("c", (_path_figure(PATH, "g", "skier"), LEADER), duration=3.0)
    monkeypatch.setattr(Scene, "run", unfinished)
    res = run_crowd(crowd)
    assert [r.status for r in res.figures] == ["failed", "ok"]
    assert res["g"].trajectory is None and str(PathNotFinished(9.0, 12.0, 30.0)) == \
        res["g"].message and res.failed == (res["g"],)


def test_formations_hold_their_arguments_to_the_crowd_files_ranges():
    """A formation called from Python refuses exactly what a crowd file's reader refuses: both
    read core.ranges.CROWD_RANGES (the peloton once had its own, tighter gap and spacing)."""
    from blender_turning.core.ranges import CROWD_RANGES
    rider = _path_figure(ROAD)
    for call, field, rng in (
            (lambda v: peloton(rider, 1, gap=v), "gap", CROWD_RANGES["gap_m"]),
            (lambda v: peloton(rider, 1, gap=1.0, spacing=v), "spacing",
             CROWD_RANGES["spacing_m"]),
            (lambda v: synchronized(LEADER, 2, spacing=v), "spacing", CROWD_RANGES["spacing_m"]),
            (lambda v: follow_leader(LEADER, 1, v, by="distance"), "gap", CROWD_RANGES["gap_m"]),
            (lambda v: follow_leader(LEADER, 1, 1.0, body_jitter=v), "body_jitter",
             CROWD_RANGES["jitter"])):
        call(rng.hi)                                      # the largest allowed is allowed
        with pytest.raises(ValueError, match=f"{field} = .* outside the allowed range "
                                             rf"\[?\(?{rng.lo:g}, {rng.hi:g}\]"):
            call(rng.hi * 1.5)


def test_crowd_command_reports_each_limited_members_lean(tmp_path, monkeypatch):
    """A member whose bounds keep its lean below the one asked is named with the lean it
    reached and the bound (printed and in summary.json's ``lean_report``), on the batch kernel
    too; a member leaning as asked has no report."""
    from blender_turning.cli import crowd as cli_crowd
    from blender_turning.cli import main
    from blender_turning.crowd import kernels
    monkeypatch.setattr(kernels, "BATCH_FROM", 2)              # the numpy batch for 3 figures
    monkeypatch.chdir(tmp_path)
    scene = tmp_path / "crowd.json"
    scene.write_text(json.dumps({"duration": 6, "figures": [
        TURNS, {"name": "b", "preset": "skier", "turns": {"period": 1.6, "lean_deg": 50}},
        {"name": "c", "preset": "skier", "turns": {"period": 2, "lean_deg": 21}},
        {"name": "d", "preset": "skier", "turns": {"period": 1.6, "lean_deg": 45}}]}))
    monkeypatch.setattr(cli_crowd, "LEAN_LINES", 1)
    import io
    from contextlib import redirect_stdout
    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["crowd", str(scene), "--out", str(tmp_path / "out")]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    rows = {f["name"]: f for f in summary["figures"]}
    assert "lean_report" not in rows["a"] and "lean_report" not in rows["c"]
    assert rows["b"]["lean_report"].startswith("lean ") and "asked 50.00 deg" in \
        rows["b"]["lean_report"] and "limited by" in rows["b"]["lean_report"]
    assert "asked 45.00 deg" in rows["d"]["lean_report"]
    lines = out.getvalue().splitlines()
    assert f"crowd: b: {rows['b']['lean_report']}" in lines          # the first LEAN_LINES
    assert not any(line.startswith("crowd: d:") for line in lines)
    assert any(line.startswith("crowd: 1 more figures lean less than asked") for line in lines)

"""Crowd staging (docs/crowds.md): followers strung out along the leader's track and moving from
the first frame, or waiting at its start; the one rule Add Crowd and the render job share."""
import math

import numpy as np
import pytest

from blender_turning.core.course.obstacles import segment_distance
from blender_turning.core.physics.params import preset
from blender_turning.crowd import (Crowd, CrowdFigure, Turns, crowd_from_dict, follow_leader,
                                   run_crowd, shot_length, stage)
from blender_turning.crowd.staging import waiting_span

HEADING = math.radians(-60.0)
#: A leader on a 30 m path (a cheap planner: 4 stages of 0.3 s, 3 choices).
PATH = {"path": {"points": [[0, 0], [15, 1.5], [30, 0]], "tangents": [[10, 0], [10, 0], [10, 0]]},
        "planner": {"stages": 4, "choices": 3, "stage_time": 0.3, "lean_bound_deg": 35}}


def leader(offset=0.0):
    return CrowdFigure("Lead", preset("skier"), Turns(2.0, math.radians(20), HEADING),
                       position=(3.0, -2.0), time_offset=offset)


@pytest.mark.parametrize("by, gap", [("time", 1.48), ("distance", 6.0)])
def test_followers_stand_a_gap_apart_on_the_leaders_line_and_start_with_it(by, gap):
    lead = leader(offset=0.5)
    followers = follow_leader(lead, 10, gap, by, [-1.5, 1.5])
    staged = stage(lead, followers, HEADING)
    d = np.array([math.cos(HEADING), math.sin(HEADING)])
    left = np.array([-d[1], d[0]])
    step = gap * lead.figure.body.V_cm if by == "time" else gap
    for i, (f, s) in enumerate(zip(followers, staged), start=1):
        rel = np.asarray(s.position) - lead.position
        # i gaps behind on the line, the lateral offset kept (round-off of a few 1e-15 m).
        assert rel @ d == pytest.approx(-i * step, abs=1e-9)
        assert rel @ left == pytest.approx((-1.5, 1.5)[(i - 1) % 2], abs=1e-9)
        assert s.time_offset == lead.time_offset          # moving from the leader's start
        assert (s.controller, s.figure, s.first_turn) == (f.controller, f.figure, f.first_turn)
    pos = np.array([s.position for s in staged])
    gaps = np.linalg.norm(pos[:, None] - pos[None], axis=2)[np.triu_indices(len(pos), 1)]
    assert gaps.min() > 0.9 * step                         # nobody inside anybody


def test_waiting_keeps_the_formation_and_the_shot_fits_the_last_start():
    lead = leader()
    followers = follow_leader(lead, 10, 1.48, "time", [-1.5, 1.5])
    assert stage(lead, followers, HEADING, "wait") == followers
    assert waiting_span(followers) == pytest.approx(14.8)
    assert shot_length(lead, followers, 10.0) == pytest.approx(24.8)
    assert shot_length(lead, (), 10.0) == 10.0
    # timing jitter: a follower due early or late starts that far nearer or further back
    jittered = follow_leader(lead, 3, 1.0, "time", 0.0, seed=2, timing_jitter=0.4)
    for f, s in zip(jittered, stage(lead, jittered, HEADING)):
        back = -(np.asarray(s.position) - lead.position) @ [math.cos(HEADING), math.sin(HEADING)]
        assert back == pytest.approx(f.time_offset * lead.figure.body.V_cm, abs=1e-9)


def test_bad_staging_names_the_parameter():
    lead = leader()
    with pytest.raises(ValueError, match="staging = 'queue' is not one of along_track, wait"):
        stage(lead, (), HEADING, "queue")
    with pytest.raises(ValueError, match="heading = nan"):
        stage(lead, (), float("nan"))
    with pytest.raises(ValueError, match=r"duration = 0 is outside the allowed range"):
        shot_length(lead, (), 0)


def path_leader():
    return crowd_from_dict({"duration": 5, "figures": [{"name": "Lead", "preset": "skier",
                                                         "follow": PATH}]}).figures[0]


def test_path_followers_start_their_gap_behind_on_the_leaders_track_and_end_as_far_short():
    lead = path_leader()
    followers = follow_leader(lead, 3, 1.0, "time", [0.0, 1.0])
    total = lead.controller.scene.path.length()
    for i, (f, s) in enumerate(zip(followers, stage(lead, followers, 0.0)), start=1):
        back = i * 1.0 * lead.figure.body.V_cm                 # 10 m a second of gap
        own = f.controller.scene.path
        path = s.controller.scene.path
        # On the leader's line run backwards from its (offset) path's start, heading along it
        np.testing.assert_allclose(s.state0(), [-back, own.knots[0][1], 0, 0, 0], atol=1e-12)
        np.testing.assert_allclose(path.knots[0], s.state0()[:2], atol=0)
        np.testing.assert_allclose(path.knots[1:-1], own.knots[:len(path.knots) - 2])
        # as long a run as the leader's: it ends `back` m short of the end (64-chord lengths)
        assert path.length() == pytest.approx(total, abs=1e-3)
        assert s.time_offset == lead.time_offset == 0.0
        assert (s.figure, s.first_turn, s.name) == (f.figure, f.first_turn, f.name)
    waiting = stage(lead, followers, 0.0, "wait")
    for i, (f, s) in enumerate(zip(followers, waiting), start=1):
        np.testing.assert_array_equal(s.state0(), f.state0())       # at the start, waiting
        assert s.time_offset == f.time_offset
        assert s.controller.scene.path.length() == pytest.approx(total - 10.0 * i, abs=1e-3)
    with pytest.raises(ValueError, match=r"follower 3, 31\.5 m behind the leader and waiting "
                                         rf"at the start, would end before the start of its "
                                         rf"{total:.1f} m path"):
        stage(lead, follow_leader(lead, 3, 10.5, "distance"), 0.0, "wait")


def bodies_at(res, crowd, t):
    """Every figure's body (foot, CM ground point) at times ``t`` as the shot shows it: standing
    where it starts before its start and where it ends after its end."""
    out = []
    for f in crowd.figures:
        tr = res[f.name].trajectory
        x, y, head, lean = (np.interp(t, tr.t, v) for v in (tr.x, tr.y, tr.theta_dir,
                                                           tr.theta_v))
        side = f.figure.body.l * np.sin(lean)
        out.append((np.stack([x, y], 1),
                    np.stack([x - side * np.sin(head), y + side * np.cos(head)], 1)))
    return out


def test_a_path_leaders_line_moves_from_the_start_and_keeps_the_clearance_to_the_end():
    """Planned by priority (the leader first), every follower runs from t = 0 and no two bodies
    come within the clearance at any moment, after their ends too (each stands at its end)."""
    lead = path_leader()
    line = (lead,) + stage(lead, follow_leader(lead, 3, 1.0, "time"), 0.0)
    crowd = Crowd("line", line, duration=10.0, priority=tuple(f.name for f in line))
    res = run_crowd(crowd)
    assert [r.status for r in res.figures] == ["ok"] * 4
    ends = [res[f.name].trajectory.t[-1] for f in line]
    t = np.arange(0.0, max(ends) + 1.0, 0.01)
    for f in line:
        tr = res[f.name].trajectory
        assert tr.t[0] == 0.0 and np.hypot(tr.x[5] - tr.x[0], tr.y[5] - tr.y[0]) > 0.5
    body = bodies_at(res, crowd, t)
    closest = min(float(segment_distance(*body[a], *body[b]).min())
                  for a in range(len(line)) for b in range(a))
    # Measured 7.0 m (the last follower, stopping 10 m behind the one before, overshoots its
    # end by about 3 m)
    assert closest >= crowd.clearance, closest

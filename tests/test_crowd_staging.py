"""Crowd staging (docs/crowds.md): followers strung out along the leader's track and moving from
the first frame, or waiting at its start; the one rule Add Crowd and the render job share."""
import math

import numpy as np
import pytest

from blender_turning.core.physics.params import preset
from blender_turning.crowd import CrowdFigure, Turns, follow_leader, shot_length, stage
from blender_turning.crowd.staging import waiting_span

HEADING = math.radians(-60.0)


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

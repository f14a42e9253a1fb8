"""Which figures' pose tracks are another's (mapping.shared_motion): the same keys, later by whole
frames and translated; anything else bakes its own."""
import math

import numpy as np
import pytest

from blender_turning.crowd import Crowd, CrowdFigure, Turns, run_crowd, synchronized
from blender_turning.core import preset
from blender_turning.mapping import map_trajectory
from blender_turning.mapping.base import BoneChannels, PoseTrack
from blender_turning.mapping.shared_motion import Share, plan, shares


def track(n=40, first=1, seed=0, move=(0.0, 0.0, 0.0)) -> PoseTrack:
    """A made-up pose track: ``n`` frames from ``first``, its motion drawn from ``seed`` (the
    same seed: the same motion), moved by ``move``."""
    rng = np.random.default_rng(seed)
    loc = np.cumsum(rng.normal(size=(n, 3)), axis=0) + np.asarray(move)
    quat = rng.normal(size=(n, 4))
    quat /= np.linalg.norm(quat, axis=1)[:, None]
    return PoseTrack(np.arange(first, first + n, dtype=float), loc, rng.normal(size=(n, 3)),
                     {"thigh.L": BoneChannels(rotation=quat),
                      "spine": BoneChannels(location=rng.normal(size=(n, 3)))},
                     {"turn_lean": rng.normal(size=n)})


def later(t: PoseTrack, k: int) -> PoseTrack:
    """``t``'s first ``len(t) - k`` rows, ``k`` frames later (a follower starting later)."""
    n = len(t) - k
    return PoseTrack(t.frames[:n] + k, t.location[:n], t.rotation[:n],
                     {b: BoneChannels(*(None if a is None else a[:n]
                                        for a in (c.location, c.rotation)))
                      for b, c in t.bones.items()},
                     {p: v[:n] for p, v in t.props.items()})


def test_a_translated_track_shares_with_its_translation():
    a, b = track(), track(move=(3.0, -10.0, 0.5))
    got = shares(a, b)
    assert got.shift == 0
    np.testing.assert_allclose(got.translation, (3.0, -10.0, 0.5), atol=1e-6)
    assert plan([a, b]) == [None, Share(0, 0, got.translation)]


def test_a_later_start_shares_shifted_and_the_earliest_is_the_source():
    a = track(n=60)
    b = later(a, 12)
    assert plan([b, a]) == [Share(1, 12, (0.0, 0.0, 0.0)), None]


@pytest.mark.parametrize("change", ["rotation", "bone", "prop", "location", "frames"])
def test_one_value_off_by_more_than_a_key_resolves_bakes_its_own(change):
    a, b = track(), track(move=(2.0, 0.0, 0.0))
    if change == "rotation":
        b.rotation[17, 2] += 1e-6
    elif change == "bone":
        b.bones["thigh.L"].rotation[30, 1] += 1e-6
    elif change == "prop":
        b.props["turn_lean"][5] += 1e-6
    elif change == "location":
        b.location[25, 0] += 1e-5          # 2 units in the last place of ~20 m are 3.8e-6
    else:
        b = PoseTrack(b.frames + 0.5, b.location, b.rotation, b.bones, b.props)
    assert shares(a, b) is None
    assert plan([a, b]) == [None, None]


def test_differences_below_the_float32_keys_still_share():
    """float64 runs of one motion from another start differ by ~1e-15: the same float32 keys."""
    a, b = track(), track(move=(40.0, 0.0, 0.0))
    b.rotation[:] += 1e-15
    b.bones["thigh.L"].rotation[:] *= 1.0 + 1e-15
    assert shares(a, b) is not None


def test_other_channels_or_a_longer_run_do_not_share():
    a = track()
    other = PoseTrack(a.frames, a.location, a.rotation, a.bones, {})
    assert shares(a, other) is None
    assert shares(later(a, 5), a) is None           # the source must cover the whole run


def test_distinct_tracks_each_bake_and_groups_find_their_own_source():
    a, b, c = track(seed=1), track(seed=2), track(seed=3)
    got = plan([a, b, track(seed=1, move=(1, 2, 3)), c, track(seed=3, move=(0, 5, 0))])
    assert [g if g is None else g.source for g in got] == [None, None, 0, None, 3]


def skier_tracks(count, spacing, antiphase=False, jitter=None):
    lead = CrowdFigure("s", preset("skier"), Turns(2.0, math.radians(20), 0.0))
    members = synchronized(lead, count, spacing=spacing, antiphase=antiphase)
    if jitter is not None:
        from dataclasses import replace
        body = members[1].figure.body
        members = (members[0], replace(members[1], figure=replace(
            members[1].figure, body=replace(body, m=body.m * (1 + jitter)))), *members[2:])
    res = run_crowd(Crowd("c", members, 3.0))
    return [map_trajectory("skier", r.trajectory.resample(24)) for r in res.figures]


def test_a_synchronized_line_of_skiers_in_phase_shares_one_motion():
    got = plan(skier_tracks(4, 3.0))
    assert got[0] is None and all(g.source == 0 and g.shift == 0 for g in got[1:])
    # 3 m apart across the heading
    np.testing.assert_allclose([math.hypot(*g.translation[:2]) for g in got[1:]], [3.0, 6.0, 9.0],
                               atol=1e-5)


def test_antiphase_and_a_heavier_body_are_different_motions():
    assert plan(skier_tracks(2, 3.0, antiphase=True)) == [None, None]
    assert plan(skier_tracks(2, 3.0, jitter=0.01)) == [None, None]

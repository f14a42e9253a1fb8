"""Fewer keys (mapping/keys.py): the reduced curve is within the bound of the every-frame motion
at every frame, keeps the ends and the extrema, and needs far fewer keys."""
import math

import numpy as np
import pytest

from blender_turning.core import PhaseEllipse, preset, simulate
from blender_turning.mapping import keys, map_trajectory


@pytest.fixture(scope="module")
def skier_track():
    fig = preset("skier")
    traj = simulate(fig, PhaseEllipse(fig.body, math.pi, math.radians(20), heading=0.0), 20.0)
    return map_trajectory("skier", traj, fps=24)


def channels(track):
    """``(kind, values)`` of every motion channel of a pose track."""
    out = [("location", track.location[:, i]) for i in range(3)]
    out += [("euler", track.rotation[:, i]) for i in range(3)]
    for ch in track.bones.values():
        if ch.location is not None:
            out += [("location", ch.location[:, i]) for i in range(3)]
        if ch.rotation is not None:
            out += [("quaternion", ch.rotation[:, i]) for i in range(4)]
    return out


def reduced(frames, values, bound):
    idx = keys.reduce_keys(frames, values, bound)
    d = keys.key_slopes(frames, values, bound)
    return idx, keys.hermite(frames[idx], values[idx], d[idx], frames)


def test_every_channel_of_a_skier_is_within_its_bound_at_every_frame(skier_track):
    f = np.asarray(skier_track.frames, float)
    tol = keys.DEFAULT_TOLERANCE
    kept = total = 0
    for kind, v in channels(skier_track):
        bound = keys.channel_tolerance(kind, tol)
        idx, curve = reduced(f, v, bound)
        assert np.max(np.abs(curve - v)) <= bound, kind
        assert idx[0] == 0 and idx[-1] == len(f) - 1
        kept += len(idx)
        total += len(f)
    assert kept < 0.3 * total              # measured 0.22 at the default (0.1 deg, 1 mm)


def test_the_bounds_per_component_add_up_to_the_tolerance():
    tol = keys.KeyTolerance(angle=math.radians(0.5), length=0.003)
    # A rotation's angle from a quaternion change dq (unit q, small dq): 2 |dq| <= 4 max |dq_i|.
    q = np.array([0.6, 0.0, 0.8, 0.0])
    dq = np.full(4, keys.channel_tolerance("quaternion", tol)) * [1, -1, 1, -1]
    p = (q + dq) / np.linalg.norm(q + dq)
    assert 2 * math.acos(min(1.0, abs(float(q @ p)))) <= tol.angle
    assert math.sqrt(3) * keys.channel_tolerance("location", tol) == pytest.approx(0.003)
    assert 3 * keys.channel_tolerance("euler", tol) == pytest.approx(tol.angle)


def test_ends_and_extrema_are_keys_and_a_cubic_needs_only_its_ends():
    f = np.arange(1.0, 201.0)
    v = np.sin(f / 10.0)
    idx, _ = reduced(f, v, 1e-4)
    peaks = np.flatnonzero((v[1:-1] > v[:-2]) & (v[1:-1] > v[2:])) + 1
    troughs = np.flatnonzero((v[1:-1] < v[:-2]) & (v[1:-1] < v[2:])) + 1
    assert set(peaks) | set(troughs) <= set(idx) and {0, 199} <= set(idx)
    # Monotonic, no extrema; the slopes at the ends are second-order differences, 2e-6 off a
    # cubic's, so its Hermite is 4e-5 off at most (measured): a bound of 1e-4 needs its ends only.
    cubic = 1e-6 * (f - 50.0) ** 3 + 0.01 * f
    idx, curve = reduced(f, cubic, 1e-4)
    assert list(idx) == [0, 199]


def test_a_corner_is_one_key_with_two_slopes():
    """A joint reaching its limit: the slope jumps at frame 100.  The key there arrives and
    leaves with each side's own slope, so the corner costs one key, not a cluster of them."""
    f = np.arange(1.0, 201.0)
    v = np.where(f < 100, 0.3, 0.6) * np.sin((f - 100.0) / 20.0)
    bound = 1e-4
    idx, curve = reduced(f, v, bound)
    assert np.max(np.abs(curve - v)) <= bound
    d = keys.key_slopes(f, v, bound)
    assert 99 in idx and d[99, 0] == pytest.approx(0.3 / 20, rel=1e-3)
    assert d[99, 1] == pytest.approx(0.6 / 20, rel=1e-3)
    rounded = keys.reduce_keys(f, v, bound, keys.slopes(f, v))      # one slope everywhere
    assert {98, 100} <= set(rounded) and not {98, 100} & set(idx)


def test_read_outs_are_held_to_their_range_and_the_lean_to_the_angle():
    tol = keys.KeyTolerance(readout=2e-3)
    assert keys.channel_tolerance("readout", tol, [700.0, 650.0, 760.0]) == pytest.approx(0.22)
    assert keys.channel_tolerance("readout", tol, [10.0, 10.0]) == pytest.approx(0.02)
    assert keys.channel_tolerance("angle", tol) == tol.angle
    assert set(keys.READOUTS) == {"turn_lean", "turn_curvature", "turn_leg_force", "turn_speed",
                                  "turn_skid"}


def test_a_constant_channel_with_round_off_keeps_two_keys():
    f = np.arange(1.0, 1441.0)
    v = 1.0 + np.random.default_rng(0).normal(scale=1e-16, size=f.size)
    assert list(keys.reduce_keys(f, v, 1e-5)) == [0, 1439]


def test_float32_storage_stays_within_the_bound():
    """600 m of travel: a float32 unit in the last place is 61 um there; the keys as Blender
    stores them (float32), evaluated, stay within 1 mm / sqrt(3) of the stored every-frame
    values; a bound float32 cannot hold keeps every frame."""
    f = np.arange(1.0, 1441.0)
    v = (10.0 * f / 24.0 + 3.0 * np.sin(f / 8.0)).astype(np.float32).astype(float)
    bound = keys.channel_tolerance("location", keys.DEFAULT_TOLERANCE)
    idx = keys.reduce_keys(f, v, bound)
    d = keys.key_slopes(f, v, bound)
    kv = v[idx].astype(np.float32).astype(float)
    kd = d[idx].astype(np.float32).astype(float)
    stored = keys.hermite(f[idx], kv, kd, f).astype(np.float32).astype(float)
    assert np.max(np.abs(stored - v)) <= bound
    assert len(keys.reduce_keys(f, v, 1e-4)) == len(f)     # 0.1 mm: 2 ulp take it all


@pytest.mark.parametrize("call, match", [
    (lambda: keys.KeyTolerance(angle=0.0), r"angle tolerance = 0.0 is outside"),
    (lambda: keys.KeyTolerance(length=-1e-3), r"length tolerance = -0.001 is outside"),
    (lambda: keys.channel_tolerance("scale", keys.DEFAULT_TOLERANCE), r"kind = 'scale'"),
    (lambda: keys.reduce_keys(np.arange(3.0), np.arange(4.0), 1e-3), r"two \(n,\) arrays"),
    (lambda: keys.reduce_keys(np.arange(3.0), np.arange(3.0), 0.0), r"bound = 0.0"),
])
def test_bad_input_is_refused_by_name(call, match):
    with pytest.raises(ValueError, match=match):
        call()

"""A crowd of 10,000 followers (the most the crowd file's ranges allow) without quadratic work:
the summary's closest approaches (:func:`~blender_turning.core.course.moving.closest_approach`) and the
reservation of every output (``Outputs.reserve``) counted in operations, not timed.  A
quadratic step would compare every body with every other (10,000 x 9,999 pairs per sample) or
resolve every earlier path again for each new one."""
import math
from pathlib import Path

import numpy as np
import pytest

from blender_turning.cli.common import Outputs
from blender_turning.core.course import moving
from blender_turning.core.course.moving import MovingBodies, closest_approach
from blender_turning.core.ranges import CROWD_RANGES

LANES, SAMPLES = 50, 10
SIZES = (1250, 10_000)


def followers(n: int) -> MovingBodies:
    """``n`` skiers in 50 lanes 2 m apart, 1.5 m one behind the other in a lane, all at 10 m/s
    and leaning 20 degrees (a foot-CM segment 0.6 m long): the crowd grows longer, not
    denser, with ``n``, as a follow-the-leader formation does (docs/crowds.md)."""
    j = np.arange(n)
    t = 0.1 * np.arange(SAMPLES)
    x = 10.0 * t[None, :] - 1.5 * (j // LANES)[:, None]
    y = np.broadcast_to(2.0 * (j % LANES)[:, None], x.shape)
    foot = np.stack([x, y], axis=2)
    cm = foot + np.array([0.0, 1.75 * math.sin(math.radians(20))])
    return MovingBodies(tuple(f"f{i}" for i in j), 0.1, 0, foot, cm)


@pytest.fixture
def pairs(monkeypatch):
    """Counts the segment pairs :func:`closest_approach` measures."""
    count = [0]
    real = moving.segment_distance

    def counted(f1, c1, f2, c2):
        count[0] += int(np.broadcast(np.asarray(f1)[..., 0], np.asarray(f2)[..., 0]).size)
        return real(f1, c1, f2, c2)

    monkeypatch.setattr(moving, "segment_distance", counted)
    return count


def test_the_largest_crowd_is_what_the_ranges_allow():
    assert CROWD_RANGES["count"].hi == SIZES[-1]


def test_closest_approach_measures_a_bounded_number_of_pairs_per_body(pairs):
    per_body = []
    for n in SIZES:
        pairs[0] = 0
        near = closest_approach(followers(n))
        per_body.append(pairs[0] / (n * SAMPLES))
        # the answer is a neighbour: the one ahead or behind (1.5 m) or beside (2 m)
        d = np.array([near[f"f{i}"][0] for i in range(0, n, 97)])
        assert np.all(d <= 1.5 + 1e-9), d.max()
    # All pairs would be n - 1 per body and sample: 1,249 for the smaller crowd, 9,999 for the
    # larger.  The grid compares a body with those in the cells around it, twice here (the
    # nearest neighbour, 1.5 m away, is beyond what the first cells prove), the same number
    # whatever the crowd's length but for its ends (measured: 118 and 137 per body and sample).
    assert max(per_body) < 200, per_body
    assert per_body[-1] < 1.5 * per_body[0], per_body


def test_reserving_ten_thousand_outputs_resolves_the_folder_once(tmp_path, monkeypatch):
    resolved = []
    real = Path.resolve

    def counted(self, *a, **k):
        resolved.append(self)
        return real(self, *a, **k)

    monkeypatch.setattr(Path, "resolve", counted)
    out = Outputs()
    try:
        for i in range(SIZES[-1]):
            out.reserve(f"--out f{i}.csv", tmp_path / f"f{i}.csv")
        out.reserve("--out summary.json", tmp_path / "summary.json")
        assert len(list(tmp_path.iterdir())) == SIZES[-1] + 1      # one hidden file each
        assert len(resolved) <= 1, resolved[:5]
    finally:
        out.discard()
    assert list(tmp_path.iterdir()) == []

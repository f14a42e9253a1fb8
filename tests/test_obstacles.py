"""Obstacles of Section 6: segments, circles, polygons, clearance; vectorised collision tests."""
import numpy as np
import pytest

from blender_turning.core.course.obstacles import Obstacles, segment_distance


def dense_distance(a, b, c, d, n=801):
    u = np.linspace(0, 1, n)[:, None]
    p = a + u * (b - a)
    q = c + u * (d - c)
    return np.sqrt(((p[:, None] - q[None]) ** 2).sum(-1)).min()


def test_segment_distance_against_brute_force():
    rng = np.random.default_rng(0)
    for _ in range(60):
        a, b, c, d = rng.uniform(-5, 5, (4, 2))
        # The dense minimum never underestimates, and overestimates by at most half a sample
        # spacing on each segment (the nearest samples to the true closest points).
        exact, dense = segment_distance(a, b, c, d), dense_distance(a, b, c, d)
        slack = 0.5 * (np.linalg.norm(b - a) + np.linalg.norm(d - c)) / 800
        assert exact <= dense + 1e-12 and dense - exact <= slack + 1e-12


def test_crossing_segments_have_distance_zero():
    assert segment_distance(np.array([0., -1]), np.array([0., 1]), np.array([-1., 0]),
                            np.array([1., 0])) == 0.0


def test_a_pole_drawn_as_a_line_blocks_one_side_only():
    pole = Obstacles(segments=[[[10, 1], [10, 20]]], clearance=0.3)
    a = np.array([[9.5, 5.0], [9.5, 0.0], [9.5, 0.8]])
    b = np.array([[10.5, 5.0], [10.5, 0.0], [10.5, 0.8]])
    np.testing.assert_array_equal(pole.collides(a, b), [True, False, True])


def test_circle_with_clearance():
    tree = Obstacles(circles=[[0, 0, 1.0]], clearance=0.5)
    a = np.array([[-5, 1.4], [-5, 1.6], [0.0, 0.2], [3, 3]])
    b = np.array([[5, 1.4], [5, 1.6], [0.1, 0.2], [4, 4]])
    np.testing.assert_array_equal(tree.collides(a, b), [True, False, True, False])


def test_polygon_inside_and_near():
    box = Obstacles(polygons=[[[0, 0], [4, 0], [4, 4], [0, 4]]], clearance=0.2)
    a = np.array([[1, 1], [-1, 2], [-1, -0.3], [5, 5]])
    b = np.array([[2, 2], [-0.1, 2], [5, -0.3], [6, 6]])
    np.testing.assert_array_equal(box.collides(a, b), [True, True, False, False])


def test_near_drops_only_what_cannot_matter():
    rng = np.random.default_rng(1)
    obs = Obstacles(segments=rng.uniform(-50, 50, (30, 2, 2)),
                    circles=np.column_stack([rng.uniform(-50, 50, (30, 2)),
                                             rng.uniform(0.2, 3, 30)]),
                    polygons=[rng.uniform(-3, 3, (5, 2)) + rng.uniform(-40, 40, 2)
                              for _ in range(5)], clearance=0.4)
    c = np.array([3.0, -2.0])
    local = obs.near(c, 12.0)
    assert len(local) < len(obs)
    a = c + rng.uniform(-8, 8, (2000, 2))
    b = a + rng.normal(0, 2, (2000, 2))
    np.testing.assert_array_equal(local.collides(a, b), obs.collides(a, b))


def test_min_distance():
    obs = Obstacles(circles=[[0, 0, 1]], polygons=[[[10, 0], [12, 0], [12, 2]]])
    d = obs.min_distance([[3, 0], [11.5, 0.5]])
    assert d[0] == pytest.approx(2.0)
    assert d[1] < 0


def test_validation():
    with pytest.raises(ValueError, match="clearance"):
        Obstacles(clearance=-1)
    with pytest.raises(ValueError, match="radius"):
        Obstacles(circles=[[0, 0, 0]])
    with pytest.raises(ValueError, match="3 vertices"):
        Obstacles(polygons=[[[0, 0], [1, 1]]])


def test_circle_box_prefilter_is_exact():
    """Segments against many circles: the same as every segment's distance to every centre,
    touching included (rims at exactly representable distances, reached from either side)."""
    from blender_turning.core.course.obstacles import point_segment_distance
    rng = np.random.default_rng(3)
    circles = np.column_stack([rng.integers(-20, 20, (40, 2)), 0.25 * rng.integers(1, 8, 40)])
    obs = Obstacles(circles=circles, clearance=0.25)
    a = rng.uniform(-22, 22, (5000, 2))
    b = a + rng.normal(0, 1.5, (5000, 2))
    rim = np.column_stack([circles[:, 2] + 0.25, np.zeros(40)])
    a[:20] = circles[:20, :2] + rim[:20]                 # leaving the grown rim to the right
    b[:20] = a[:20] + [1.0, 0.0]
    b[20:40] = circles[20:, :2] - rim[20:]               # arriving at it from the left
    a[20:40] = b[20:40] - [1.0, 0.0]
    direct = (point_segment_distance(circles[None, :, :2], a[:, None], b[:, None])
              <= circles[None, :, 2] + 0.25).any(axis=1)
    got = obs.collides(a, b)
    np.testing.assert_array_equal(got, direct)
    assert got[:40].all() and 100 < got.sum() < 4900

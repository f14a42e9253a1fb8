"""The path of Section 6: Hermite spline (C1), polyline, exact Bezier conversion, distances."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from blender_turning.core.course.path import HermitePath, PathDistance

coord = st.floats(-50, 50, allow_nan=False)
pts4 = st.lists(st.tuples(coord, coord), min_size=4, max_size=4)


def bezier(P, u):
    u = np.asarray(u)[:, None]
    return ((1 - u) ** 3 * P[0] + 3 * (1 - u) ** 2 * u * P[1] + 3 * (1 - u) * u ** 2 * P[2]
            + u ** 3 * P[3])


@settings(max_examples=50, deadline=None)
@given(pts4, pts4)
def test_bezier_conversion_is_exact(a, b):
    P = np.array(a + b[1:], float)                 # two segments sharing a knot
    path = HermitePath.from_bezier(P)
    u = np.linspace(0, 1, 17)
    np.testing.assert_allclose(path.evaluate(np.zeros(17, int), u), bezier(P[:4], u), atol=1e-9)
    np.testing.assert_allclose(path.evaluate(np.ones(17, int), u), bezier(P[3:], u), atol=1e-9)


def test_hermite_interpolates_points_and_tangents_and_is_c1():
    pts = np.array([[0, 0], [10, 3], [20, -2], [35, 0]], float)
    tan = np.array([[10, 0], [8, 2], [12, -1], [10, 0]], float)
    path = HermitePath.from_points(pts, tan)
    for i in range(3):
        np.testing.assert_allclose(path.evaluate(i, 0.0), pts[i])
        np.testing.assert_allclose(path.evaluate(i, 1.0), pts[i + 1])
        np.testing.assert_allclose(path.evaluate(i, 0.0, 1), tan[i])
        np.testing.assert_allclose(path.evaluate(i, 1.0, 1), tan[i + 1])
    # C1 at the inner knots: value and first derivative agree from both sides.
    for i in range(2):
        np.testing.assert_allclose(path.evaluate(i, 1.0, 1), path.evaluate(i + 1, 0.0, 1))


def test_polyline_is_straight_chords():
    path = HermitePath.from_polyline([[0, 0], [10, 0], [10, 10]])
    p = path.evaluate(np.zeros(5, int), np.linspace(0, 1, 5))
    np.testing.assert_allclose(p, np.column_stack([np.linspace(0, 10, 5), np.zeros(5)]))
    assert path.length() == pytest.approx(20.0)


def test_sampling_twelve_per_segment():
    path = HermitePath.from_polyline([[0, 0], [12, 0], [24, 0]])
    s = path.sample()
    assert s.shape == (25, 2)
    np.testing.assert_allclose(s[:, 0], np.arange(25))


def test_sample_distance_is_the_papers_nearest_sample():
    path = HermitePath.from_polyline([[0, 0], [12, 0]])
    d = PathDistance(path)
    np.testing.assert_allclose(d(np.array([[0.5, 2.0], [3.0, -1.0]])),
                               [np.hypot(0.5, 2.0), 1.0])


def test_exact_distance_matches_dense_sampling():
    rng = np.random.default_rng(3)
    path = HermitePath.from_points([[0, 0], [10, 5], [20, -5], [30, 0]],
                                   [[15, 0], [10, 0], [10, 0], [15, 5]])
    dense = path.sample(4000)
    exact = PathDistance(path, exact=True)
    coarse = PathDistance(path)
    P = rng.uniform([-5, -10], [35, 10], (300, 2))
    ref = np.sqrt(((P[:, None] - dense[None]) ** 2).sum(-1)).min(1)
    # Never above the densely sampled distance, and below it only by the sampling's own error.
    assert np.all(exact(P) <= ref + 1e-9)
    assert np.all(exact(P) >= ref - 3e-4)
    assert np.all(coarse(P) >= exact(P) - 1e-12)


def test_near_keeps_the_distance_exact():
    rng = np.random.default_rng(4)
    path = HermitePath.from_points([[0, 0], [40, 10], [80, -10], [120, 0]],
                                   [[40, 0], [40, 0], [40, 0], [40, 0]])
    for exact in (False, True):
        full = PathDistance(path, exact=exact)
        c = np.array([50.0, 3.0])
        local = full.near(c, 15.0)
        assert len(local.samples) < len(full.samples)
        ang = rng.uniform(0, 2 * np.pi, 500)
        P = c + rng.uniform(0, 15, 500)[:, None] * np.column_stack([np.cos(ang), np.sin(ang)])
        np.testing.assert_allclose(local(P), full(P), atol=1e-12)


def test_distance_is_1_lipschitz():
    rng = np.random.default_rng(5)
    path = HermitePath.from_bezier([[0, 0], [5, 8], [15, -8], [20, 0]])
    for exact in (False, True):
        d = PathDistance(path, exact=exact)
        P = rng.uniform(-10, 30, (400, 2))
        Q = P + rng.normal(0, 1, (400, 2))
        assert np.all(np.abs(d(P) - d(Q)) <= np.linalg.norm(P - Q, axis=1) + 1e-9)


def test_extension_runs_straight_out_of_the_end():
    path = HermitePath.from_points([[0, 0], [10, 0]], [[0, 10], [10, 0]])
    ext = path.extended(5.0)
    np.testing.assert_allclose(ext.knots[-1], [15, 0])
    np.testing.assert_allclose(ext.evaluate(1, 0.5), [12.5, 0])


def test_lead_in_runs_straight_into_the_start():
    path = HermitePath.from_points([[0, 0], [10, 0]], [[0, 10], [10, 0]])
    led = path.led_in(5.0)
    np.testing.assert_allclose(led.knots[0], [0, -5])
    np.testing.assert_allclose(led.evaluate(0, 0.5), [0, -2.5])
    np.testing.assert_allclose(led.knots[1:], path.knots)
    assert led.length() == pytest.approx(path.length() + 5.0, abs=1e-9)
    assert path.led_in(0.0) is path


@pytest.mark.parametrize("s", [0.3, 7.7, 22.0, 40.1])
def test_split_gives_the_curve_before_and_after_a_distance(s):
    """Both parts lie on the curve (within the 64-chord arc length's sagitta: 0.4 mm measured
    on this 4-segment path, 1 mm allowed), meet at the point ``s`` m along it and add up to
    its length (to the same 1 mm)."""
    path = HermitePath.from_points([[0, 0], [15, 1.5], [30, 0], [40, 20]],
                                   [[10, 0], [10, 0], [10, 0], [0, 10]])
    before, after = path.split(s)
    on = PathDistance(path, 64, exact=True)
    assert on(before.sample(64)).max() < 1e-3 and on(after.sample(64)).max() < 1e-3
    np.testing.assert_array_equal(before.knots[-1], after.knots[0])
    assert before.length() == pytest.approx(s, abs=1e-3)
    assert before.length() + after.length() == pytest.approx(path.length(), abs=1e-3)
    np.testing.assert_allclose(before.knots[:-1], path.knots[:len(before.knots) - 1])
    with pytest.raises(ValueError, match="70 m along the path is not inside it"):
        path.split(70.0)


def test_bad_inputs_name_the_problem():
    with pytest.raises(ValueError, match="3 n \\+ 1"):
        HermitePath.from_bezier(np.zeros((5, 2)))
    with pytest.raises(ValueError, match="tangents"):
        HermitePath.from_points([[0, 0], [1, 0]], [[1, 0]])
    with pytest.raises(ValueError, match="finite"):
        HermitePath.from_polyline([[0, 0], [np.nan, 1]])


def test_start_direction_skips_coincident_first_points():
    """A repeated first point (zero first segment) or a zero first handle: the heading comes
    from the first non-degenerate tangent, not +x."""
    down = HermitePath.from_polyline([[0, 0], [0, 0], [0, -10], [5, -20]])
    np.testing.assert_allclose(down.start_direction(), [0.0, -1.0], atol=1e-12)
    back = HermitePath.from_polyline([[0, 0], [-3, -4], [-3, -4]])
    np.testing.assert_allclose(back.end_direction(), [-0.6, -0.8], atol=1e-12)
    # A Bezier whose first handle sits on its knot leaves toward the second handle.
    bez = HermitePath.from_bezier([[0, 0], [0, 0], [-5, 5], [-10, 5]])
    np.testing.assert_allclose(bez.start_direction(), np.array([-1.0, 1.0]) / np.sqrt(2),
                               atol=1e-12)
    with pytest.raises(ValueError, match="no length"):
        HermitePath.from_polyline([[1, 1], [1, 1]]).start_direction()


def test_scene_start_heading_follows_the_path_not_plus_x():
    """A scene path (Bezier) whose first handle sits on its first point starts along the path,
    not along +x.  (Scene files refuse repeated consecutive points; the core handles them.)"""
    from blender_turning.core.course.scene import scene_from_dict
    sc = scene_from_dict({"figure": {"preset": "skier"},
                          "path": {"bezier": [[0, 0], [0, 0], [0, 20], [0, 30]]}})
    assert sc.state0[2] == pytest.approx(np.pi / 2, abs=1e-12)


def progress_along(path, track, window):
    from blender_turning.core.course.path import PathProgress
    pr = PathProgress(path, window)
    p, out, prev = 0.0, [], None
    for xy in np.asarray(track, float):
        p = pr.advance(p, xy, 0.0 if prev is None else float(np.hypot(*(xy - prev))))
        out.append((p, pr.at_end(p, xy)))
        prev = xy
    return pr, out


def test_progress_on_a_switchback_does_not_jump_to_the_end():
    """Out 40 m, back 40 m, 4 m to the side: the end is level with the start and behind it.
    Standing near the start (or past it) is no progress, and walking out is half the path."""
    path = HermitePath.from_polyline([[0, 0], [40, 0], [40, 4], [0, 4]])
    pr, out = progress_along(path, [[0.5, 0.3], [-2.0, 2.0], [-5.0, 4.0]], window=10.0)
    assert all(p < 1.0 and not end for p, end in out)
    walk = [[x, 0.2] for x in np.arange(0.0, 40.0, 1.0)] + [[40.5, 2.0]] + \
        [[x, 3.8] for x in np.arange(39.0, -1.5, -1.0)]
    pr, out = progress_along(path, walk, window=10.0)
    assert out[39][0] == pytest.approx(39.0, abs=0.8) and not out[39][1]
    assert out[-1][1] and out[-1][0] == pytest.approx(pr.length)
    assert [end for _, end in out].index(True) == len(walk) - 2      # at x = 0, on the end line

    # A loop (shorter than the distance counted as near) whose end is its start: not at the end
    # from the start nor from just behind it; at the end once round.
    ang = np.linspace(0, 2 * np.pi, 25)
    ring = np.column_stack([5 * np.sin(ang), 5 - 5 * np.cos(ang)])
    loop = HermitePath.from_polyline(ring)
    pr, out = progress_along(loop, [[-0.05, 0.0], [0.0, 0.02], [0.3, 0.0]], window=50.0)
    assert all(p < 1.0 and not end for p, end in out)
    a = np.linspace(0.0, 2 * np.pi + 0.3, 200)
    pr, out = progress_along(loop, np.column_stack([5.2 * np.sin(a), 5 - 5.2 * np.cos(a)]),
                             window=50.0)
    first = [end for _, end in out].index(True)
    assert a[first] == pytest.approx(2 * np.pi, abs=0.04) and out[first][0] == pr.length


def test_progress_needs_the_foot_near_the_path():
    """500 m beside the path, beyond its end: no progress at all."""
    path = HermitePath.from_polyline([[0, 0], [50, 0]])
    _, out = progress_along(path, [[60.0, 500.0], [80.0, 500.0]], window=20.0)
    assert out[-1] == (0.0, False)


def test_path_deviation_is_the_largest_distance_when_and_how_far_along():
    """Round a quarter circle of radius 20 m (a Bezier's quarter-circle, within 0.03% of it) on a
    track whose distance from it is 0.5 + 3 sin(pi s^2) over s in [0, 1]: at most 3.5 m, at
    s = 1/sqrt(2), 22.2 m along the 31.4 m arc."""
    from blender_turning.core.course.path import path_deviation
    R, k = 20.0, 0.5522847498                          # the cubic Bezier's quarter circle
    path = HermitePath.from_bezier(np.array([[R, 0], [R, k * R], [k * R, R], [0, R]]))
    s = np.linspace(0.0, 1.0, 2001)
    a = 0.5 * np.pi * s
    r = R + 0.5 + 3.0 * np.sin(np.pi * s * s)          # outside the arc
    dev = path_deviation(path, 10.0 * s, r * np.cos(a), r * np.sin(a))
    # The Bezier strays 0.027% from the circle (5.4 mm at R = 20 m): the distance and its place
    # carry that; the arc length to the nearest of 64 samples per segment is 0.25 m coarse.
    assert dev.distance == pytest.approx(3.5, abs=6e-3)
    peak = 2 ** -0.5
    assert dev.t == pytest.approx(10.0 * peak, abs=0.01)
    a = 0.5 * np.pi * peak
    assert dev.xy == pytest.approx((23.5 * np.cos(a), 23.5 * np.sin(a)), abs=0.05)
    assert dev.along == pytest.approx(a * R, abs=0.3)
    with pytest.raises(ValueError, match="no samples"):
        path_deviation(path, [], [], [])

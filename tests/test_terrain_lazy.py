"""A height field sampled as it is visited (core/ground/terrain.py ``LazyHeightField``, so "the
bake stays fast"): the same field, bit for bit, as the one of all samples, on floats and arrays,
at the grid's edges (its linear extension) and after pickling; only the tiles a query touches
are sampled."""
import pickle

import numpy as np
import pytest

from blender_turning.core.ground.terrain import HeightField, LazyHeightField

NY, NX = 150, 171                        # not multiples of the tile: partial tiles at the edges
HEIGHTS = np.random.default_rng(11).normal(0.0, 0.5, (NY, NX))
X0, Y0, CELL = -12.5, 3.0, 0.4


class _Sampler:
    """``HEIGHTS`` by rows and columns, counting the samples asked for."""

    def __init__(self):
        self.asked = 0

    def __call__(self, rows, cols):
        self.asked += len(rows) * len(cols)
        return HEIGHTS[rows[:, None], cols[None, :]]


def _pair():
    sampler = _Sampler()
    return (HeightField(HEIGHTS, X0, Y0, CELL),
            LazyHeightField(sampler, NX, NY, X0, Y0, CELL), sampler)


def _points(field, rng, n):
    x_lo, x_hi, y_lo, y_hi = field.extent
    xs, ys = rng.uniform(x_lo, x_hi, n), rng.uniform(y_lo, y_hi, n)
    # The corners and edges (the stencil reaches into the extension there).
    return (np.concatenate([xs, [x_lo, x_hi, x_lo, x_hi, x_lo, 0.5 * (x_lo + x_hi)]]),
            np.concatenate([ys, [y_lo, y_hi, y_hi, y_lo, 0.5 * (y_lo + y_hi), y_hi]]))


def test_floats_are_the_full_fields_bit_for_bit():
    eager, lazy, sampler = _pair()
    xs, ys = _points(eager, np.random.default_rng(2), 300)
    for x, y in zip(xs.tolist(), ys.tolist()):
        assert lazy.derivatives_one(x, y) == eager.derivatives_one(x, y)
        assert lazy.slopes_one(x, y) == eager.slopes_one(x, y) == eager.derivatives_one(x, y)[1:]
    np.testing.assert_array_equal(lazy._h, eager._h)        # the rest, and the padding


def test_arrays_are_the_full_fields_bit_for_bit():
    eager, lazy, sampler = _pair()
    xs, ys = _points(eager, np.random.default_rng(3), 40)
    for a, b in zip(lazy.derivatives(xs, ys), eager.derivatives(xs, ys)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(lazy._h, eager._h)


def test_only_the_tiles_visited_are_sampled():
    """A query near the grid's lower left corner samples one tile (and the rows and columns
    its padding's extension and its edge need), a query on floats in the middle at most four."""
    T = LazyHeightField.TILE
    for query in ("derivatives", "derivatives_one"):
        sampler = _Sampler()
        lazy = LazyHeightField(sampler, NX, NY, X0, Y0, CELL)
        x, y = X0 + 3.3 * CELL, Y0 + 5.6 * CELL
        getattr(lazy, query)(np.array([x]) if query == "derivatives" else x,
                             np.array([y]) if query == "derivatives" else y)
        assert 0 < sampler.asked <= (T + 2) ** 2 and lazy._done.sum() == 1
        sampler.asked = 0
        x, y = X0 + (T - 3.5) * CELL, Y0 + (T - 2.5) * CELL           # a stencil on 4 tiles
        got = getattr(lazy, query)(np.array([x]) if query == "derivatives" else x,
                                   np.array([y]) if query == "derivatives" else y)
        assert lazy._done.sum() == 4 and sampler.asked <= 3 * (T + 2) ** 2
        eager = HeightField(HEIGHTS, X0, Y0, CELL)
        np.testing.assert_array_equal(np.ravel(got), np.ravel(
            eager.derivatives(np.array([x]), np.array([y])) if query == "derivatives" else
            eager.derivatives_one(x, y)))
    assert lazy._done.size >= 9
    # Two diagonal tiles filled first: the stencil across four still fills the other two.
    lazy = LazyHeightField(_Sampler(), NX, NY, X0, Y0, CELL)
    for k in (10.5, T + 10.5):
        lazy.derivatives_one(X0 + k * CELL, Y0 + k * CELL)
    x, y = X0 + (T - 3.5) * CELL, Y0 + (T - 2.5) * CELL
    assert lazy.derivatives_one(x, y) == HeightField(HEIGHTS, X0, Y0, CELL).derivatives_one(x, y)


def test_a_pickled_lazy_field_is_the_full_field():
    eager, lazy, _ = _pair()
    lazy.derivatives_one(0.0, 10.0)
    back = pickle.loads(pickle.dumps(lazy))
    assert type(back) is HeightField
    np.testing.assert_array_equal(back._h, eager._h)
    assert back.derivatives_one(1.0, 20.0) == eager.derivatives_one(1.0, 20.0)


def test_bad_samples_and_grids_are_refused():
    lazy = LazyHeightField(lambda r, c: np.full((len(r), len(c)), np.nan), NX, NY, X0, Y0, CELL)
    with pytest.raises(ValueError, match="not a finite number"):
        lazy.derivatives_one(0.0, 10.0)
    with pytest.raises(ValueError, match="at least 2 x 2"):
        LazyHeightField(_Sampler(), 1, NY, X0, Y0, CELL)
    eager, lazy, _ = _pair()
    with pytest.raises(ValueError, match="off the terrain"):
        lazy.slopes_one(X0 - 0.01, 10.0)


def _one_cell(field, i, j):
    """Cell ``(i, j)``'s coefficients made alone: ``M^T P M`` of its own 4 x 4 stencil about its
    corner (``HeightField._cell``'s formula, one matrix at a time)."""
    from blender_turning.core.ground.terrain import _HERMITE_POWERS as M, _POW
    P = field._h[j + 1:j + 5, i + 1:i + 5]
    A = M.T @ (P - P[1, 1]) @ M
    A[0, 0] += P[1, 1]
    Au = A[:, 1:] * _POW[1:]
    Auu = Au[:, 1:] * _POW[1:-1]
    return tuple(np.concatenate([A.ravel(), Au.ravel(), Auu.ravel()]).tolist())


def test_cells_made_with_their_block_are_made_alone_bit_for_bit():
    """A cell's polynomial is made with the cells of its 4 x 4 block (``BLOCK``) in one numpy
    pass (a drag's next run finds its neighbours made): each is the cell's own, bit for bit,
    on both fields, at the grid's last cells (a partial block) too."""
    eager, lazy, _ = _pair()
    rng = np.random.default_rng(5)
    cells = [(int(i), int(j)) for i, j in zip(rng.integers(0, NX - 1, 60),
                                              rng.integers(0, NY - 1, 60))]
    cells += [(0, 0), (NX - 2, NY - 2), (NX - 2, 0), (0, NY - 2)]
    for field in (lazy, eager):
        for i, j in cells:
            assert field._cell(i, j) == _one_cell(eager, i, j)
        assert len(field._coef) > 10 * len(cells)          # 4 x 4 cells a block
        for key, coef in field._coef.items():
            assert coef == _one_cell(eager, key % NX, key // NX)

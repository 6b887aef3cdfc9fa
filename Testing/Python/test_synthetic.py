"""The synthetic label volume generators: shapes, dtypes, determinism and defining properties."""
import numpy as np
import pytest

from vtksvdag import synthetic


def brute_force_voronoi(shape, n_cells, seed):
    """Nearest seed for every voxel by comparing against all seeds (the definition)."""
    nz, ny, nx = shape
    seeds = np.random.default_rng(seed).random((n_cells, 3)) * (np.array([nx, ny, nz]) - 1.0)
    z, y, x = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    points = np.stack([x, y, z], axis=-1).reshape(-1, 1, 3)
    dist2 = np.sum((points - seeds[None]) ** 2, axis=2)
    return (np.argmin(dist2, axis=1) + 1).reshape(shape)


@pytest.mark.parametrize(
    "make",
    [
        lambda s: synthetic.voronoi(s, 20, seed=3),
        lambda s: synthetic.tubes(s, 4, 2.0, seed=3),
        lambda s: synthetic.checkerboard(s, 3, 2),
        lambda s: synthetic.random_labels(s, 5, seed=3),
    ],
    ids=["voronoi", "tubes", "checkerboard", "random_labels"],
)
def test_shape_dtype_and_determinism(make):
    shape = (9, 14, 23)  # (nz, ny, nx), not multiples of any tile size
    a = make(shape)
    assert a.shape == shape
    assert a.dtype == np.uint32
    assert a.flags.c_contiguous
    np.testing.assert_array_equal(a, make(shape))


def test_seed_changes_the_volume():
    assert not np.array_equal(synthetic.voronoi((8, 8, 8), 10, seed=1), synthetic.voronoi((8, 8, 8), 10, seed=2))
    assert not np.array_equal(synthetic.tubes((16, 16, 16), 2, 2.0, seed=1), synthetic.tubes((16, 16, 16), 2, 2.0, seed=2))
    assert not np.array_equal(synthetic.random_labels((8, 8, 8), 4, seed=1), synthetic.random_labels((8, 8, 8), 4, seed=2))


@pytest.mark.parametrize("shape, n_cells", [((13, 17, 21), 30), ((40, 33, 9), 200), ((1, 1, 1), 3), ((3, 30, 2), 7)])
def test_voronoi_matches_brute_force(shape, n_cells):
    a = synthetic.voronoi(shape, n_cells, seed=11)
    np.testing.assert_array_equal(a, brute_force_voronoi(shape, n_cells, 11))


def test_voronoi_is_dense_and_uses_the_label_range():
    a = synthetic.voronoi((32, 32, 32), 50, seed=0)
    assert a.min() >= 1  # no background
    assert a.max() <= 50
    assert len(np.unique(a)) > 40  # seeds this sparse almost all own voxels


def test_tubes_are_sparse_thin_and_labelled():
    a = synthetic.tubes((48, 48, 48), 5, 2.0, seed=4)
    labels = np.unique(a)
    assert labels[0] == 0
    assert set(labels[1:]) <= set(range(1, 6))
    assert len(labels) >= 4  # later tubes may overwrite earlier ones only partly
    fraction = np.count_nonzero(a) / a.size
    assert 0.002 < fraction < 0.3
    # A tube of radius 2 cannot fill a 6^3 box: no foreground voxel has a solid 6^3 around it.
    from numpy.lib.stride_tricks import sliding_window_view

    windows = sliding_window_view(a != 0, (6, 6, 6))
    assert not windows.all(axis=(3, 4, 5)).any()


def test_checkerboard_alternates():
    a = synthetic.checkerboard((6, 7, 8))
    assert set(np.unique(a)) == {1, 2}
    for axis in range(3):
        assert np.all(np.diff(a.astype(np.int64), axis=axis) != 0)
    assert a[0, 0, 0] == 1 and a[0, 0, 1] == 2 and a[1, 1, 0] == 1


def test_checkerboard_period_and_label_count():
    a = synthetic.checkerboard((8, 8, 8), n_labels=3, period=2)
    assert set(np.unique(a)) == {1, 2, 3}
    # constant on aligned 2^3 cubes, different across their faces
    cubes = a.reshape(4, 2, 4, 2, 4, 2)
    assert np.all(cubes == cubes[:, :1, :, :1, :, :1])
    coarse = cubes[:, 0, :, 0, :, 0].astype(np.int64)
    for axis in range(3):
        assert np.all(np.diff(coarse, axis=axis) != 0)


def test_random_labels_cover_the_range_uniformly():
    a = synthetic.random_labels((20, 20, 20), 4, seed=0)
    values, counts = np.unique(a, return_counts=True)
    np.testing.assert_array_equal(values, [1, 2, 3, 4])
    assert counts.min() > 0.8 * a.size / 4


def test_other_dtypes_and_bad_arguments():
    assert synthetic.checkerboard((2, 2, 2), dtype=np.uint8).dtype == np.uint8
    assert synthetic.voronoi((4, 4, 4), 3, dtype=np.int64).dtype == np.int64
    with pytest.raises(ValueError):
        synthetic.random_labels((4, 4, 4), 300, dtype=np.uint8)  # labels do not fit
    with pytest.raises(ValueError):
        synthetic.voronoi((4, 4), 3)
    with pytest.raises(ValueError):
        synthetic.voronoi((4, 0, 4), 3)
    with pytest.raises(ValueError):
        synthetic.tubes((4, 4, 4), 1, 0.0)
    with pytest.raises(ValueError):
        synthetic.checkerboard((4, 4, 4), period=0)
    with pytest.raises(ValueError):
        synthetic.random_labels((4, 4, 4), 3, dtype=np.float32)

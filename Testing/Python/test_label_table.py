"""SegmentationVolume.label_table: per-label statistics from the compressed form, checked against
brute-force numpy (np.unique counts, bincount-weighted centroids, a neighbour-shift surface count)."""
import warnings

import numpy as np
import pandas as pd
import pytest

import vtksvdag
from vtksvdag.synthetic import tubes, voronoi

DTYPES = [np.uint8, np.uint16, np.uint32, np.uint64, np.int8, np.int16, np.int32, np.int64]
COLUMNS = ["voxel_count", "volume", "xmin", "xmax", "ymin", "ymax", "zmin", "zmax", "centroid_i",
           "centroid_j", "centroid_k", "centroid_x", "centroid_y", "centroid_z", "surface_voxels"]


def reference_table(array, background, spacing=(1, 1, 1), origin=(0, 0, 0), direction=None):
    """The table computed from the dense array with numpy alone."""
    direction = np.eye(3) if direction is None else np.asarray(direction, float)
    values, inverse, counts = np.unique(array, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(array.shape)
    keep = values != background
    i, j, k = np.meshgrid(*(np.arange(n) for n in array.shape), indexing="ij")
    n = len(values)
    sums = [np.bincount(inverse.ravel(), weights=c.ravel(), minlength=n) for c in (i, j, k)]
    centroid = np.stack(sums, axis=1) / counts[:, None]
    # Surface: any of the 6 face neighbours differs, outside the volume counting as different
    # (pad with a value no label index has).
    padded = np.pad(inverse, 1, constant_values=-1)
    core = padded[1:-1, 1:-1, 1:-1]
    open_ = np.zeros(array.shape, dtype=bool)
    for axis in range(3):
        for shift in (-1, 1):
            open_ |= np.roll(padded, shift, axis=axis)[1:-1, 1:-1, 1:-1] != core
    surface = np.bincount(inverse[open_], minlength=n)
    bounds = np.zeros((n, 6), dtype=np.int64)
    for index in np.nonzero(keep)[0]:
        where = np.nonzero(inverse == index)
        bounds[index] = [f(w) for w in where for f in (np.min, np.max)]
    world = np.asarray(origin, float) + (centroid * np.asarray(spacing, float)) @ direction.T
    return {
        "labels": values[keep], "voxel_count": counts[keep], "bounds": bounds[keep],
        "centroid": centroid[keep], "world": world[keep], "surface": surface[keep],
        "volume": counts[keep] * np.prod(spacing),
    }


def check_table(table, array, volume, **geometry):
    ref = reference_table(array, volume.background, **geometry)
    assert list(table.columns) == COLUMNS + ["color"]
    assert table.index.name == "label" and table.index.dtype == array.dtype
    np.testing.assert_array_equal(table.index.to_numpy(), ref["labels"])
    np.testing.assert_array_equal(table["voxel_count"].to_numpy(), ref["voxel_count"])
    np.testing.assert_allclose(table["volume"].to_numpy(), ref["volume"], rtol=1e-12)
    np.testing.assert_array_equal(table[["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]].to_numpy(), ref["bounds"])
    np.testing.assert_allclose(table[["centroid_i", "centroid_j", "centroid_k"]].to_numpy(), ref["centroid"],
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(table[["centroid_x", "centroid_y", "centroid_z"]].to_numpy(), ref["world"],
                               rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(table["surface_voxels"].to_numpy(), ref["surface"])
    for column in ("voxel_count", "xmin", "surface_voxels"):
        assert table[column].dtype == np.int64


@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_table_matches_numpy_for_every_dtype(dtype, rng):
    info = np.iinfo(dtype)
    palette = np.array(sorted({int(info.min), int(info.max), 0, 1, 9} | ({-3} if info.min < 0 else set())),
                       dtype=dtype)
    # Coherent blobs across cell borders (odd sizes: partial cells on every side) plus speckle.
    cells = voronoi((35, 19, 41), 9, seed=int(rng.integers(1000)), dtype=np.uint32).transpose(2, 1, 0)
    array = palette[cells % len(palette)]
    speckle = rng.random(array.shape) < 0.03
    array[speckle] = rng.choice(palette, speckle.sum())
    volume = vtksvdag.from_numpy(array)
    check_table(volume.label_table(), array, volume)


def test_table_world_geometry_and_non_zero_background(rng):
    array = rng.integers(0, 4, size=(23, 34, 18)).astype(np.int16) - 1  # -1 .. 2
    theta = 0.4
    direction = np.array([[1, 0, 0], [0, np.cos(theta), -np.sin(theta)], [0, np.sin(theta), np.cos(theta)]])
    geometry = dict(spacing=(0.5, 1.5, 2.25), origin=(-10, 4, 7), direction=direction)
    volume = vtksvdag.from_numpy(array, background=-1, **geometry)
    table = volume.label_table()
    assert -1 not in table.index and list(table.index) == [0, 1, 2]
    check_table(table, array, volume, **geometry)


def test_sparse_thin_objects_and_deep_volumes():
    # Tubes: thin labels crossing many 16-voxel cell layers (the layer-by-layer surface count).
    array = tubes((70, 33, 29), 6, radius=2.5, seed=4, dtype=np.uint32).transpose(2, 1, 0)
    volume = vtksvdag.from_numpy(array)
    check_table(volume.label_table(), array, volume)
    # Single voxels and a label filling a whole face layer.
    array = np.zeros((16, 16, 33), dtype=np.uint8)
    array[0, 0, 0] = 1
    array[15, 15, 32] = 2
    array[:, :, 16] = 3
    volume = vtksvdag.from_numpy(array)
    table = volume.label_table()
    check_table(table, array, volume)
    assert table.loc[3, "surface_voxels"] == 256 and table.loc[1, "surface_voxels"] == 1


def test_solid_and_empty_volumes():
    full = vtksvdag.from_numpy(np.full((20, 17, 18), 5, dtype=np.uint64))
    table = full.label_table()
    interior = 18 * 15 * 16
    assert table.loc[5, "surface_voxels"] == 20 * 17 * 18 - interior
    np.testing.assert_allclose(table.loc[5, ["centroid_i", "centroid_j", "centroid_k"]].to_numpy(float),
                               [9.5, 8, 8.5])
    empty = vtksvdag.from_numpy(np.zeros((5, 6, 7), dtype=np.int32)).label_table()
    assert len(empty) == 0 and list(empty.columns) == COLUMNS + ["color"] and empty.index.name == "label"


def test_attributes_left_join(tmp_path):
    array = np.zeros((8, 9, 10), dtype=np.uint64)
    array[1:3] = 4
    array[5:7] = 2**64 - 1
    array[7] = 11
    volume = vtksvdag.from_numpy(array)
    attributes = pd.DataFrame({"label": np.array([4, 2**64 - 1], dtype=np.uint64), "name": ["a", "max"],
                               "weight": [1.5, 2.5]})
    table = volume.label_table(attributes)
    assert list(table.columns) == COLUMNS + ["name", "weight", "color"]
    assert table.loc[4, "name"] == "a" and table.loc[2**64 - 1, "weight"] == 2.5
    assert pd.isna(table.loc[11, "name"]) and len(table) == 3
    # Indexed by label, and from a CSV file; unknown labels warn and are left out.
    csv = tmp_path / "attributes.csv"
    pd.DataFrame({"label": [11, 12, 4], "kind": ["x", "unknown", "y"]}).to_csv(csv, index=False)
    with pytest.warns(UserWarning, match="1 labels of the attributes are not in the volume.*12"):
        table = volume.label_table(csv)
    assert table.loc[[4, 11], "kind"].tolist() == ["y", "x"] and pd.isna(table.loc[2**64 - 1, "kind"])
    assert 12 not in table.index
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = volume.label_table(pd.DataFrame({"kind": ["z"]}, index=pd.Index([11], name="label")))
    assert table.loc[11, "kind"] == "z"


def test_attribute_errors(tmp_path):
    volume = vtksvdag.from_numpy(np.ones((4, 4, 4), dtype=np.int8))
    with pytest.raises(ValueError, match="'label' column"):
        volume.label_table(pd.DataFrame({"id": [1]}))
    with pytest.raises(ValueError, match="clash"):
        volume.label_table(pd.DataFrame({"label": [1], "voxel_count": [3]}))
    with pytest.raises(ValueError, match="more than one row"):
        volume.label_table(pd.DataFrame({"label": [1, 1], "a": [1, 2]}))
    with pytest.raises(ValueError, match="integers|whole"):
        volume.label_table(pd.DataFrame({"label": [1.5], "a": [1]}))
    with pytest.raises(TypeError):
        volume.label_table({"label": [1]})
    with pytest.raises(FileNotFoundError):
        volume.label_table(tmp_path / "missing.csv")
    # A label outside the dtype's range is unknown, not an error.
    with pytest.warns(UserWarning, match="1000"):
        table = volume.label_table(pd.DataFrame({"label": [1, 1000], "a": [7, 8]}))
    assert table.loc[1, "a"] == 7


def test_real_volume_table(shared_data):
    import nrrd

    path = sorted(shared_data.glob("*.nrrd"))[0]
    array, _ = nrrd.read(str(path))
    volume = vtksvdag.read(path)
    check_table(volume.label_table(), array.astype(volume.dtype), volume,
                spacing=volume.spacing, origin=volume.origin, direction=volume.direction)

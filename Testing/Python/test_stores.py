"""Chunked stores (Zarr v2/v3, OME-Zarr, N5, neuroglancer precomputed) through tensorstore:
vtksvdag.read, `vtksvdag compress STORE` and `vtksvdag decompress X.svdag -o OUT.zarr`.

Every fixture store is written by tensorstore itself from a numpy array; the reads are checked
against that array, and the geometry against the numbers written into the metadata.
"""
import json

import numpy as np
import pytest

import vtksvdag
from vtksvdag import stores
from vtksvdag.streaming import Builder

from test_cli import run_cli

ts = pytest.importorskip("tensorstore")

# Odd shapes (no multiple of 16) and chunk shapes that do not divide them.
SHAPE_ZYX = (37, 29, 23)
CHUNKS = [10, 7, 6]


def labels_zyx(dtype, shape=SHAPE_ZYX, seed=0):
    """A (z, y, x) label array of ``dtype``: boxes of a few labels and noise, using the extremes
    of the dtype (negatives for signed ones, values above 2**63 for uint64)."""
    rng = np.random.default_rng(seed)
    info = np.iinfo(dtype)
    values = [info.min, info.max, info.max - 1, 1, 0, info.min // 2 + 1]
    if dtype == np.uint64:
        values += [2**63 + 12345, 2**64 - 17, 9007199254740993]  # 2**53 + 1: not a double
    table = np.array(values, dtype=object).astype(dtype)
    array = table[rng.integers(0, len(table), size=shape)]
    array[: shape[0] // 3] = table[1]  # a solid region: whole-cell blocks
    array[:, :4, :5] = 0
    return array


def write_store(spec, array, **kwargs):
    """Create the tensorstore ``spec`` and write ``array`` into it (its whole domain)."""
    store = ts.open(spec, create=True, delete_existing=True, **kwargs).result()
    store[...].write(array).result()
    return store


def zarr2_spec(path, array, chunks=CHUNKS):
    return {
        "driver": "zarr",
        "kvstore": {"driver": "file", "path": str(path)},
        "metadata": {"shape": list(array.shape), "chunks": list(chunks), "dtype": array.dtype.str},
    }


def zarr3_spec(path, array, chunks=CHUNKS):
    return {
        "driver": "zarr3",
        "kvstore": {"driver": "file", "path": str(path)},
        "metadata": {
            "shape": list(array.shape),
            "data_type": array.dtype.name,
            "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": list(chunks)}},
        },
    }


def n5_spec(path, xyz, chunks=(6, 7, 10)):
    return {
        "driver": "n5",
        "kvstore": {"driver": "file", "path": str(path)},
        "metadata": {
            "dimensions": list(xyz.shape), "blockSize": list(chunks), "dataType": xyz.dtype.name,
            "compression": {"type": "gzip"},
        },
    }


def precomputed_spec(path, xyz, encoding, resolution, voxel_offset, channels=1, chunk=(6, 7, 10)):
    scale = {
        "size": list(xyz.shape[:3]), "resolution": list(resolution),
        "voxel_offset": list(voxel_offset), "encoding": encoding, "chunk_size": list(chunk),
    }
    if encoding == "compressed_segmentation":
        scale["compressed_segmentation_block_size"] = [8, 8, 8]
    return {
        "driver": "neuroglancer_precomputed",
        "kvstore": {"driver": "file", "path": str(path)},
        "multiscale_metadata": {"type": "segmentation", "data_type": xyz.dtype.name,
                                "num_channels": channels},
        "scale_metadata": scale,
    }


def open_zarr(path):
    """An existing Zarr v2 array, opened by tensorstore alone."""
    return ts.open({"driver": "zarr", "kvstore": {"driver": "file", "path": str(path)}}).result()


def as_xyz(zyx):
    return np.ascontiguousarray(zyx.transpose(2, 1, 0))


def assert_volume(volume, zyx, spacing=(1, 1, 1), origin=(0, 0, 0)):
    decoded = volume.to_numpy("zyx")
    assert decoded.dtype == zyx.dtype
    assert decoded.shape == zyx.shape
    np.testing.assert_array_equal(decoded, zyx)
    assert volume.dims == zyx.shape[::-1]
    np.testing.assert_allclose(volume.spacing, spacing)
    np.testing.assert_allclose(volume.origin, origin)


DTYPES = [np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32, np.uint64, np.int64]


# -- Zarr v2 / v3 -----------------------------------------------------------------------------
@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_zarr_v2_round_trip(tmp_path, dtype):
    zyx = labels_zyx(dtype)
    write_store(zarr2_spec(tmp_path / "a.zarr", zyx), zyx)
    volume = vtksvdag.read(tmp_path / "a.zarr")
    assert_volume(volume, zyx)
    # The streamed build is the one from_numpy makes of the whole array.
    reference = vtksvdag.from_numpy(zyx, axis_order="zyx")
    volume.save(tmp_path / "a.svdag")
    reference.save(tmp_path / "b.svdag")
    assert (tmp_path / "a.svdag").read_bytes() == (tmp_path / "b.svdag").read_bytes()


@pytest.mark.parametrize("dtype", [np.int8, np.uint64, np.int32], ids=lambda d: np.dtype(d).name)
def test_zarr_v3_round_trip(tmp_path, dtype):
    zyx = labels_zyx(dtype, seed=3)
    write_store(zarr3_spec(tmp_path / "a.zarr", zyx), zyx)
    assert (tmp_path / "a.zarr" / "zarr.json").is_file()
    assert_volume(vtksvdag.read(str(tmp_path / "a.zarr")), zyx)


def test_file_url(tmp_path):
    zyx = labels_zyx(np.uint16)
    write_store(zarr2_spec(tmp_path / "a.zarr", zyx), zyx)
    assert_volume(vtksvdag.read((tmp_path / "a.zarr").as_uri()), zyx)


def test_zarr_axis_order_override(tmp_path):
    zyx = labels_zyx(np.uint32)
    xyz = as_xyz(zyx)
    write_store(zarr2_spec(tmp_path / "xyz.zarr", xyz, chunks=(6, 7, 10)), xyz)
    # By convention the store is (z, y, x): its first dimension is taken as z.
    assert vtksvdag.read(tmp_path / "xyz.zarr").dims == zyx.shape
    assert_volume(vtksvdag.read(tmp_path / "xyz.zarr", axis_order="xyz"), zyx)


def test_dataset_inside_a_group(tmp_path):
    zyx = labels_zyx(np.int16)
    write_store(zarr2_spec(tmp_path / "group" / "labels" / "seg", zyx), zyx)
    assert_volume(vtksvdag.read(tmp_path / "group", dataset="labels/seg"), zyx)


def cache_limit(array):
    """The chunk cache bound a StoreArray was opened with (0 when there is none)."""
    pool = array.store.spec(retain_context=True).to_json()["context"]["cache_pool"]
    return pool.get("total_bytes_limit", 0)


def test_slabs_of_16_slices_and_bounded_cache(tmp_path, monkeypatch):
    """The reader hands the Builder z-slabs of 16·k slices that keep to the chunks along z, and
    opens the store without a chunk cache when they do (each chunk is read once), with a
    bounded one when they do not."""
    zyx = labels_zyx(np.uint32, shape=(53, 17, 19))
    write_store(zarr2_spec(tmp_path / "a.zarr", zyx, chunks=(16, 8, 8)), zyx)
    write_store(zarr2_spec(tmp_path / "b.zarr", zyx, chunks=(5, 8, 8)), zyx)
    shapes = []
    add_slab = Builder.add_slab
    monkeypatch.setattr(Builder, "add_slab", lambda self, a: (shapes.append(a.shape), add_slab(self, a))[1])
    monkeypatch.setattr(stores, "SLAB_BYTES", 1)  # the thinnest slabs the chunks allow
    opened = []
    open_store = stores.open_store
    monkeypatch.setattr(stores, "open_store", lambda *a, **k: opened.append(open_store(*a, **k)) or opened[-1])
    volume = vtksvdag.read(tmp_path / "a.zarr")
    assert_volume(volume, zyx)
    assert [s[0] for s in shapes] == [16, 16, 16, 5]
    assert all(s[1:] == (17, 19) for s in shapes)
    assert cache_limit(opened[-1]) == 0
    # Chunks of 5 slices: slabs of lcm(16, 5) = 80 slices keep to them (where 80 slices stay
    # near the slab size).
    monkeypatch.setattr(stores, "SLAB_BYTES", 2**20)
    shapes.clear()
    assert_volume(vtksvdag.read(tmp_path / "b.zarr"), zyx)
    assert [s[0] for s in shapes] == [53] and cache_limit(opened[-1]) == 0
    assert stores.context_spec(12345) == {"cache_pool": {"total_bytes_limit": 12345}}

    # Slabs that cut through chunks read with the bounded cache; an explicit bound is kept.
    location, kind = stores.find_store(str(tmp_path / "b.zarr"))
    shapes.clear()
    other = stores.read_store(location, kind, slab_slices=32)
    assert [s[0] for s in shapes] == [32, 21]
    assert cache_limit(opened[-1]) == stores.DEFAULT_CACHE_BYTES
    assert_volume(other, zyx)
    array = stores.open_store(location, kind, cache_bytes=1 << 20)
    assert cache_limit(array) == 1 << 20
    assert_volume(stores.read_store(location, kind, slab_slices=32, cache_bytes=1 << 20), zyx)
    assert cache_limit(opened[-1]) == 1 << 20
    with pytest.raises(ValueError, match="multiple of 16"):
        stores.read_store(location, kind, slab_slices=20)

    # read() takes the bound too; it is for chunked stores only.
    assert_volume(vtksvdag.read(tmp_path / "a.zarr", cache_bytes=1 << 21), zyx)
    assert cache_limit(opened[-1]) == 1 << 21
    with pytest.raises(ValueError, match="cache_bytes"):
        vtksvdag.read(tmp_path / "a.zarr", cache_bytes=-1)
    np.save(tmp_path / "a.npy", zyx)
    with pytest.raises(ValueError, match="only for chunked stores"):
        vtksvdag.read(tmp_path / "a.npy", cache_bytes=1 << 21)


def test_slabs_cover_whole_chunks_along_z(tmp_path):
    zyx = labels_zyx(np.uint8, shape=(90, 5, 6))
    write_store(zarr2_spec(tmp_path / "a.zarr", zyx, chunks=(40, 5, 6)), zyx)
    array = stores.open_store(*stores.find_store(str(tmp_path / "a.zarr")))
    assert array.chunk_z() == 40
    assert stores.slab_slices_for(array) % 16 == 0 and stores.slab_slices_for(array) >= 40


def test_cli_info_on_a_store(tmp_path):
    zyx = labels_zyx(np.int32)
    write_store(zarr3_spec(tmp_path / "a.zarr", zyx), zyx)
    result = run_cli("info", tmp_path / "a.zarr", "--json")
    assert result.returncode == 0, result.stderr
    stats = json.loads(result.stdout)
    assert stats["dims"] == list(zyx.shape[::-1]) and stats["dtype"] == "int32"
    assert stats["labels"] == len(np.unique(zyx[zyx != 0]))
    assert stats["file_bytes"] == sum(p.stat().st_size for p in (tmp_path / "a.zarr").rglob("*") if p.is_file())


# -- N5 ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("dtype", [np.uint64, np.int8, np.uint16], ids=lambda d: np.dtype(d).name)
def test_n5_is_xyz_with_resolution(tmp_path, dtype):
    zyx = labels_zyx(dtype, seed=5)
    xyz = as_xyz(zyx)
    write_store(n5_spec(tmp_path / "a.n5", xyz), xyz)
    attributes_file = tmp_path / "a.n5" / "attributes.json"
    attributes = json.loads(attributes_file.read_text())
    assert attributes["dimensions"] == list(xyz.shape)  # N5 lists x first
    assert_volume(vtksvdag.read(tmp_path / "a.n5"), zyx)
    attributes["resolution"] = [4, 5, 40]
    attributes_file.write_text(json.dumps(attributes))
    assert_volume(vtksvdag.read(tmp_path / "a.n5"), zyx, spacing=(4, 5, 40))
    del attributes["resolution"]
    attributes["pixelResolution"] = {"unit": "nm", "dimensions": [1.5, 2, 3]}
    attributes_file.write_text(json.dumps(attributes))
    assert_volume(vtksvdag.read(tmp_path / "a.n5"), zyx, spacing=(1.5, 2, 3))
    # Overridden: the N5 dimensions taken as z, y, x.
    assert vtksvdag.read(tmp_path / "a.n5", axis_order="zyx").dims == xyz.shape[::-1]


# -- neuroglancer precomputed -----------------------------------------------------------------
@pytest.mark.parametrize(
    "encoding,dtype",
    [("raw", np.uint16), ("raw", np.uint64), ("compressed_segmentation", np.uint64),
     ("compressed_segmentation", np.uint32)],
)
def test_precomputed(tmp_path, encoding, dtype):
    zyx = labels_zyx(dtype, seed=7)
    xyzc = as_xyz(zyx)[..., None]
    spec = precomputed_spec(tmp_path / "pc", xyzc, encoding, (4, 6, 40), (10, -3, 7))
    store = write_store(spec, xyzc)
    assert store.domain.inclusive_min == (10, -3, 7, 0)
    info = json.loads((tmp_path / "pc" / "info").read_text())
    assert info["scales"][0]["encoding"] == encoding
    assert_volume(vtksvdag.read(tmp_path / "pc"), zyx, spacing=(4, 6, 40),
                  origin=(40, -18, 280))


def test_precomputed_scale_selection(tmp_path):
    full = labels_zyx(np.uint64, seed=8)
    half = labels_zyx(np.uint64, shape=(19, 15, 12), seed=9)
    write_store(precomputed_spec(tmp_path / "pc", as_xyz(full)[..., None], "raw", (4, 4, 40), (0, 0, 0)),
                as_xyz(full)[..., None])
    # A second scale added to the same info file (open=True: the info exists).
    spec = precomputed_spec(tmp_path / "pc", as_xyz(half)[..., None], "compressed_segmentation",
                            (8, 8, 80), (2, 3, 4))
    ts.open(spec, create=True, open=True).result()[...].write(as_xyz(half)[..., None]).result()
    assert len(json.loads((tmp_path / "pc" / "info").read_text())["scales"]) == 2
    assert_volume(vtksvdag.read(tmp_path / "pc"), full, spacing=(4, 4, 40))
    assert_volume(vtksvdag.read(tmp_path / "pc", scale=1), half, spacing=(8, 8, 80),
                  origin=(16, 24, 320))
    with pytest.raises(ValueError, match="scale 2 is out of range"):
        vtksvdag.read(tmp_path / "pc", scale=2)


def test_precomputed_with_two_channels_is_refused(tmp_path):
    zyx = labels_zyx(np.uint32)
    xyzc = np.stack([as_xyz(zyx), as_xyz(zyx)], axis=-1)
    write_store(precomputed_spec(tmp_path / "pc", xyzc, "raw", (1, 1, 1), (0, 0, 0), channels=2), xyzc)
    with pytest.raises(ValueError, match="channel"):
        vtksvdag.read(tmp_path / "pc")


# -- OME-Zarr ---------------------------------------------------------------------------------
def write_ome(root, levels, axes=("z", "y", "x"), version="0.4", global_scale=None):
    """An OME-Zarr multiscale group at ``root`` with one Zarr array per (array, scale,
    translation) of ``levels``, in the order of ``axes``."""
    multiscale = {
        "version": version,
        "axes": [{"name": a, "type": "space" if a in "xyz" else "channel"} for a in axes],
        "datasets": [
            {"path": f"s{i}", "coordinateTransformations": [
                {"type": "scale", "scale": list(scale)},
                {"type": "translation", "translation": list(translation)}]}
            for i, (_, scale, translation) in enumerate(levels)
        ],
    }
    if global_scale is not None:
        multiscale["coordinateTransformations"] = [{"type": "scale", "scale": list(global_scale)}]
    root.mkdir()
    if version == "0.5":
        (root / "zarr.json").write_text(json.dumps({
            "zarr_format": 3, "node_type": "group",
            "attributes": {"ome": {"version": "0.5", "multiscales": [multiscale]}}}))
        make_spec = zarr3_spec
    else:
        (root / ".zgroup").write_text('{"zarr_format": 2}')
        (root / ".zattrs").write_text(json.dumps({"multiscales": [multiscale]}))
        make_spec = zarr2_spec
    for i, (array, _, _) in enumerate(levels):
        write_store(make_spec(root / f"s{i}", array, chunks=[min(9, n) for n in array.shape]), array)


@pytest.mark.parametrize("version", ["0.4", "0.5"])
def test_ome_zarr_multiscale(tmp_path, version):
    full = labels_zyx(np.uint32, seed=11)
    half = np.ascontiguousarray(full[::2, ::2, ::2])
    write_ome(tmp_path / "ome.zarr", [
        (full, (2.0, 0.5, 0.25), (10.0, 20.0, 30.0)),
        (half, (4.0, 1.0, 0.5), (11.0, 20.25, 30.125)),
    ], version=version)
    # Spacing and origin are given in x, y, z order: the OME (z, y, x) values reversed.
    assert_volume(vtksvdag.read(tmp_path / "ome.zarr"), full, spacing=(0.25, 0.5, 2), origin=(30, 20, 10))
    assert_volume(vtksvdag.read(tmp_path / "ome.zarr", scale=1), half, spacing=(0.5, 1, 4),
                  origin=(30.125, 20.25, 11))
    with pytest.raises(ValueError, match="scale 2 is out of range"):
        vtksvdag.read(tmp_path / "ome.zarr", scale=2)


def test_ome_zarr_axes_decide_the_order(tmp_path):
    zyx = labels_zyx(np.int8, seed=12)
    cxyz = as_xyz(zyx)[None]  # (c, x, y, z) with one channel
    write_ome(tmp_path / "ome.zarr", [(cxyz, (1, 3, 2, 5), (0, 1, 2, 3))], axes=("c", "x", "y", "z"),
              global_scale=(1, 2, 2, 2))
    # The level's transforms, then the multiscale's scale (applied to the translation too).
    assert_volume(vtksvdag.read(tmp_path / "ome.zarr"), zyx, spacing=(6, 4, 10), origin=(2, 4, 6))


def test_ome_zarr_channel_of_two_is_refused(tmp_path):
    zyx = labels_zyx(np.uint8)
    czyx = np.stack([zyx, zyx])
    write_ome(tmp_path / "ome.zarr", [(czyx, (1, 1, 1, 1), (0, 0, 0, 0))], axes=("c", "z", "y", "x"))
    with pytest.raises(ValueError, match="size 2"):
        vtksvdag.read(tmp_path / "ome.zarr")


# -- errors -----------------------------------------------------------------------------------
def test_directory_without_a_store(tmp_path):
    (tmp_path / "plain").mkdir()
    (tmp_path / "plain" / "notes.txt").write_text("nothing here")
    with pytest.raises(IsADirectoryError):
        vtksvdag.read(tmp_path / "plain")
    with pytest.raises(IsADirectoryError):
        vtksvdag.read(tmp_path / "plain", dataset="x")


def test_float_store_is_refused(tmp_path):
    values = np.zeros(SHAPE_ZYX, np.float32)
    write_store(zarr2_spec(tmp_path / "f.zarr", values), values)
    with pytest.raises(ValueError, match="float32"):
        vtksvdag.read(tmp_path / "f.zarr")


def test_plain_arrays_have_one_scale_and_four_dims_need_one_channel(tmp_path):
    zyx = labels_zyx(np.uint8)
    write_store(zarr2_spec(tmp_path / "a.zarr", zyx), zyx)
    assert_volume(vtksvdag.read(tmp_path / "a.zarr", scale=0), zyx)
    with pytest.raises(ValueError, match="scale 1 is out of range"):
        vtksvdag.read(tmp_path / "a.zarr", scale=1)
    czyx = np.stack([zyx, zyx])
    write_store(zarr2_spec(tmp_path / "c.zarr", czyx, chunks=[1] + CHUNKS), czyx)
    with pytest.raises(ValueError, match="size 2"):
        vtksvdag.read(tmp_path / "c.zarr")
    one = czyx[:1]
    write_store(zarr2_spec(tmp_path / "one.zarr", one, chunks=[1] + CHUNKS), one)
    assert_volume(vtksvdag.read(tmp_path / "one.zarr"), zyx)


def test_store_options_on_plain_files(tmp_path):
    np.save(tmp_path / "a.npy", np.ones((3, 4, 5), np.uint8))
    with pytest.raises(ValueError, match="only for chunked stores"):
        vtksvdag.read(tmp_path / "a.npy", scale=0)
    with pytest.raises(ValueError, match="axis_order"):
        vtksvdag.read(tmp_path / "a.npy", axis_order="yxz")


# -- command line -----------------------------------------------------------------------------
def test_cli_compress_store(tmp_path):
    full = labels_zyx(np.uint64, seed=13)
    half = np.ascontiguousarray(full[::2, ::2, ::2])
    write_ome(tmp_path / "ome.zarr", [(full, (2, 1, 1), (0, 0, 0)), (half, (4, 2, 2), (1, 0.5, 0.5))])
    for extra in ([], ["--scale", "1"]):
        out = tmp_path / f"cli{len(extra)}.svdag"
        result = run_cli("compress", tmp_path / "ome.zarr", "-o", out, *extra)
        assert result.returncode == 0, result.stderr
        reference = vtksvdag.read(tmp_path / "ome.zarr", scale=int(extra[1]) if extra else None)
        reference.save(tmp_path / "ref.svdag")
        assert out.read_bytes() == (tmp_path / "ref.svdag").read_bytes()
    assert_volume(vtksvdag.read(tmp_path / "cli2.svdag"), half, spacing=(2, 2, 4), origin=(0.5, 0.5, 1))

    xyz = as_xyz(full)
    write_store(zarr2_spec(tmp_path / "xyz.zarr", xyz, chunks=(6, 7, 10)), xyz)
    out = tmp_path / "xyz.svdag"
    result = run_cli("compress", tmp_path / "xyz.zarr", "-o", out, "--axis-order", "xyz")
    assert result.returncode == 0, result.stderr
    assert_volume(vtksvdag.read(out), full)

    result = run_cli("compress", tmp_path / "ome.zarr", "-o", out, "--scale", "5")
    assert result.returncode == 1 and "scale 5 is out of range" in result.stderr, result.stderr
    (tmp_path / "empty").mkdir()
    result = run_cli("compress", tmp_path / "empty", "-o", out)
    assert result.returncode != 0 and "Is a directory" in result.stderr, result.stderr


@pytest.mark.parametrize("dtype", [np.uint64, np.int8, np.uint16], ids=lambda d: np.dtype(d).name)
def test_cli_decompress_to_zarr(tmp_path, dtype):
    zyx = labels_zyx(dtype, shape=(70, 33, 21), seed=14)
    spacing, origin = (0.5, 0.75, 2.0), (-4.0, 1.0, 10.0)
    vtksvdag.from_numpy(zyx, axis_order="zyx", spacing=spacing, origin=origin).save(tmp_path / "a.svdag")
    result = run_cli("decompress", tmp_path / "a.svdag", "-o", tmp_path / "out.zarr", "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["file_bytes"] > 0
    # Read back with tensorstore alone: the array "0", (z, y, x), the original dtype.
    store = open_zarr(tmp_path / "out.zarr" / "0")
    assert store.dtype.numpy_dtype == zyx.dtype
    np.testing.assert_array_equal(store.read().result(), zyx)
    attributes = json.loads((tmp_path / "out.zarr" / ".zattrs").read_text())
    [level] = attributes["multiscales"][0]["datasets"]
    assert level["coordinateTransformations"] == [
        {"type": "scale", "scale": list(spacing[::-1])},
        {"type": "translation", "translation": list(origin[::-1])}]
    assert [a["name"] for a in attributes["multiscales"][0]["axes"]] == ["z", "y", "x"]
    # And through vtksvdag.read: the geometry comes back.
    assert_volume(vtksvdag.read(tmp_path / "out.zarr"), zyx, spacing=spacing, origin=origin)
    # An existing store is not overwritten.
    result = run_cli("decompress", tmp_path / "a.svdag", "-o", tmp_path / "out.zarr")
    assert result.returncode != 0 and "exists" in result.stderr, result.stderr


def test_write_zarr_keeps_direction_and_background(tmp_path):
    zyx = labels_zyx(np.int16, shape=(20, 18, 17), seed=15)
    direction = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], float)
    volume = vtksvdag.from_numpy(zyx, axis_order="zyx", direction=direction, background=int(zyx[0, 0, 0]))
    stores.write_zarr(volume, tmp_path / "out.zarr", chunk=16)
    store = open_zarr(tmp_path / "out.zarr" / "0")
    np.testing.assert_array_equal(store.read().result(), zyx)
    assert store.chunk_layout.read_chunk.shape == (16, 16, 16)
    back = vtksvdag.read(tmp_path / "out.zarr")
    np.testing.assert_allclose(back.direction, direction)
    np.testing.assert_array_equal(back.to_numpy("zyx"), zyx)

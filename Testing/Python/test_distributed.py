"""Merging partial volumes and the Dask-distributed build (issue 11, deliverable 3).

The reference is always the single-machine build of the same labels (from_numpy, the file
reader, vtksvdag.read of the store), compared on the saved bytes: a merge must give the same
bytes for every partition, not merely the same voxels.
"""
import os
import pickle

import numpy as np
import pytest

import vtksvdag
from vtksvdag.distributed import z_ranges
from vtksvdag.streaming import Builder

from conftest import SHARED_DATA, shared_volumes
from test_stores import labels_zyx, n5_spec, write_store, zarr2_spec

ts = pytest.importorskip("tensorstore")
distributed = pytest.importorskip("dask.distributed")

DTYPES = [np.int8, np.uint8, np.int16, np.uint16, np.int32, np.uint32, np.int64, np.uint64]


def merged(xyz, ranges, **options):
    """The volume of ``xyz`` built as one volume per z-range, appended in order."""
    builder = Builder(xyz.shape, xyz.dtype, **options)
    for z0, z1 in ranges:
        builder.add_volume(vtksvdag.from_numpy(np.ascontiguousarray(xyz[:, :, z0:z1]), **{
            k: v for k, v in options.items() if k in ("background", "exclude")}))
    return builder.finish()


# -- merging (no Dask) -----------------------------------------------------------------------
@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("parts", [1, 2, 3, 7])
def test_merged_parts_have_the_bytes_of_the_whole_build(dtype, parts):
    xyz = labels_zyx(dtype, shape=(119, 29, 23), seed=parts).transpose(2, 1, 0)
    whole = vtksvdag.from_numpy(xyz).to_bytes()
    assert merged(xyz, z_ranges(xyz.shape[2], parts)).to_bytes() == whole


def test_merge_with_background_exclusions_and_geometry():
    xyz = labels_zyx(np.int16, shape=(70, 17, 31), seed=3).transpose(2, 1, 0)
    info = np.iinfo(np.int16)
    options = dict(background=1, exclude=[info.max - 1], spacing=(0.5, 2, 3), origin=(1, -2, 5))
    whole = vtksvdag.from_numpy(xyz, **options).to_bytes()
    assert merged(xyz, [(0, 32), (32, 48), (48, 70)], **options).to_bytes() == whole


def test_add_volume_then_slabs():
    xyz = labels_zyx(np.uint32, shape=(50, 9, 11), seed=5).transpose(2, 1, 0)
    builder = Builder(xyz.shape, xyz.dtype)
    builder.add_volume(vtksvdag.from_numpy(np.ascontiguousarray(xyz[:, :, :32])))
    builder.add_slab(xyz[:, :, 32:40])
    builder.add_slab(xyz[:, :, 40:])
    assert builder.finish().to_bytes() == vtksvdag.from_numpy(xyz).to_bytes()


def test_add_volume_errors_leave_the_builder_usable():
    xyz = labels_zyx(np.uint8, shape=(40, 8, 8), seed=1).transpose(2, 1, 0)
    part = vtksvdag.from_numpy(np.ascontiguousarray(xyz[:, :, :16]))
    builder = Builder(xyz.shape, np.uint8)
    with pytest.raises(TypeError, match="SegmentationVolume"):
        builder.add_volume(xyz[:, :, :16])
    with pytest.raises(ValueError, match="dtype int8"):
        builder.add_volume(vtksvdag.from_numpy(np.zeros((8, 8, 16), np.int8) + 1))
    with pytest.raises(ValueError, match="x and y"):
        builder.add_volume(vtksvdag.from_numpy(np.ones((8, 9, 16), np.uint8)))
    with pytest.raises(ValueError, match="background"):
        builder.add_volume(vtksvdag.from_numpy(np.ascontiguousarray(xyz[:, :, :16]), background=3))
    excluding = Builder(xyz.shape, np.uint8, exclude=[int(part.labels[-1])])
    with pytest.raises(ValueError, match="excludes"):
        excluding.add_volume(part)
    builder.add_slab(xyz[:, :, :3])
    with pytest.raises(ValueError, match="16-slice slab"):
        builder.add_volume(part)
    builder.add_slab(xyz[:, :, 3:16])
    with pytest.raises(ValueError, match="does not fit"):
        builder.add_volume(vtksvdag.from_numpy(np.ascontiguousarray(xyz[:, :, :8])))  # not last
    builder.add_volume(vtksvdag.from_numpy(np.ascontiguousarray(xyz[:, :, 16:32])))
    builder.add_volume(vtksvdag.from_numpy(np.ascontiguousarray(xyz[:, :, 32:])))
    assert builder.finish().to_bytes() == vtksvdag.from_numpy(xyz).to_bytes()


def test_z_ranges():
    assert z_ranges(112, 7) == [(16 * i, 16 * i + 16) for i in range(7)]
    assert z_ranges(120, 3) == [(0, 48), (48, 96), (96, 120)]
    assert z_ranges(20, 7) == [(0, 16), (16, 20)]  # at most one range per step
    assert z_ranges(200, 3, unit=64) == [(0, 128), (128, 192), (192, 200)]


# -- bytes and pickling ----------------------------------------------------------------------
def test_bytes_and_pickle_round_trip():
    xyz = labels_zyx(np.uint64, shape=(21, 19, 17)).transpose(2, 1, 0)
    volume = vtksvdag.from_numpy(xyz, spacing=(1, 2, 3), origin=(4, 5, 6))
    data = volume.to_bytes()
    again = vtksvdag.from_bytes(data)
    assert again.to_bytes() == data
    assert np.array_equal(again.to_numpy(), xyz)
    assert (again.spacing, again.origin) == (volume.spacing, volume.origin)
    for payload in (bytearray(data), memoryview(data), np.frombuffer(data, np.uint8)):
        assert vtksvdag.from_bytes(payload).to_bytes() == data
    copy = pickle.loads(pickle.dumps(volume))
    assert copy.to_bytes() == data and copy.build_seconds == volume.build_seconds
    # Format 2, stored uncompressed: other bytes, the same volume (pickling travels this way).
    stored = volume.to_bytes(0, format_version=2)
    assert stored != data and stored[8] == 2 and data[8] == 4
    assert vtksvdag.from_bytes(stored).to_bytes() == data
    # A background other than 0 (and a negative one) is kept, not re-encoded.
    for dtype, background in ((np.uint8, 7), (np.int32, -5)):
        labels = (np.arange(6 * 5 * 4).reshape(6, 5, 4) % 9 - 6).astype(dtype)
        volume = vtksvdag.from_numpy(labels, background=background)
        again = pickle.loads(pickle.dumps(volume))
        assert again.background == background and again.to_bytes() == volume.to_bytes()
        assert np.array_equal(again.to_numpy(), labels)


def test_from_bytes_rejects_bad_bytes():
    data = vtksvdag.from_numpy(np.eye(9, dtype=np.uint8)[:, :, None]).to_bytes()
    with pytest.raises(OSError, match="truncated"):
        vtksvdag.from_bytes(data[:-3])
    corrupt = bytearray(data)
    corrupt[len(corrupt) // 2] ^= 0x40
    with pytest.raises(OSError, match="input array"):
        vtksvdag.from_bytes(bytes(corrupt))
    with pytest.raises(OSError, match="no bytes"):
        vtksvdag.from_bytes(b"")
    with pytest.raises(TypeError, match="bytes-like"):
        vtksvdag.from_bytes("not bytes")
    with pytest.raises(ValueError, match="compression_level"):
        vtksvdag.from_numpy(np.ones((2, 2, 2), np.uint8)).to_bytes(23)


# -- Dask ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=":0")
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def zarr_store(path, zyx, chunks=(10, 7, 6)):
    write_store(zarr2_spec(path, zyx, chunks=chunks), zyx)
    return str(path)


@pytest.mark.parametrize("dtype", [np.uint8, np.int32, np.uint64])
def test_dask_build_is_the_single_machine_build(tmp_path, client, dtype):
    zyx = labels_zyx(dtype, shape=(117, 29, 23), seed=7)
    path = zarr_store(tmp_path / "seg.zarr", zyx)
    reference = vtksvdag.read(path).to_bytes()
    assert reference == vtksvdag.from_numpy(zyx.transpose(2, 1, 0)).to_bytes()
    for parts in (1, 2, 7):
        volume = vtksvdag.build_distributed(path, client, partitions=parts)
        assert volume.build_report["partitions"] == parts
        assert len(volume.build_report["merge_seconds"]) == parts - 1
        assert volume.to_bytes() == reference, f"{parts} partitions"
    # By default one task per worker thread (2 here); slab sets the slices read at a time.
    seen = []
    volume = vtksvdag.build_distributed(path, client, slab=32, progress=seen.append)
    assert volume.build_report["partitions"] == 2 and volume.to_bytes() == reference
    assert seen[-1] == 1.0 and seen == sorted(seen)


def test_dask_build_through_a_scheduler_address(tmp_path, client):
    # A "tcp://host:port" string connects a client of its own (closed after the build).
    zyx = labels_zyx(np.int8, shape=(40, 11, 9), seed=9)
    path = zarr_store(tmp_path / "seg.zarr", zyx)
    address = client.scheduler.address
    assert address.startswith("tcp://")
    volume = vtksvdag.build_distributed(path, address, partitions=2)
    assert volume.to_bytes() == vtksvdag.read(path).to_bytes()
    assert volume.build_report["partitions"] == 2


def test_dask_build_of_n5_with_options(tmp_path, client):
    zyx = labels_zyx(np.int16, shape=(50, 21, 19), seed=2)
    xyz = np.ascontiguousarray(zyx.transpose(2, 1, 0))
    write_store(n5_spec(tmp_path / "seg.n5", xyz), xyz)
    info = np.iinfo(np.int16)
    options = dict(background=1, exclude=[info.max - 1])
    reference = vtksvdag.read(str(tmp_path / "seg.n5"), **options).to_bytes()
    volume = vtksvdag.build_distributed(str(tmp_path / "seg.n5"), client, partitions=3, **options)
    assert volume.to_bytes() == reference


@pytest.mark.parametrize("name", shared_volumes())
def test_dask_build_of_shared_volumes(tmp_path, client, shared_data, name):
    # One-shot filter (from_numpy), the file reader, the streaming builder and Dask with 1, 2
    # and 7 partitions give the same bytes.
    read = vtksvdag.read(str(SHARED_DATA / f"{name}.nrrd"))
    xyz = read.to_numpy()
    reference = read.to_bytes()
    assert vtksvdag.from_numpy(xyz, spacing=read.spacing, origin=read.origin,
                               direction=read.direction).to_bytes() == reference
    path = tmp_path / f"{name}.zarr"
    write_store(zarr2_spec(path, np.ascontiguousarray(xyz.transpose(2, 1, 0)), chunks=(64, 64, 64)),
                np.ascontiguousarray(xyz.transpose(2, 1, 0)))
    # The store has no geometry: compare with the same labels at unit spacing.
    plain = vtksvdag.from_numpy(xyz).to_bytes()
    builder = Builder(xyz.shape, xyz.dtype)
    for z0 in range(0, xyz.shape[2], 40):
        builder.add_slab(xyz[:, :, z0:z0 + 40])
    assert builder.finish().to_bytes() == plain
    for parts in (1, 2, 7):
        volume = vtksvdag.build_distributed(str(path), client, partitions=parts)
        assert volume.build_report["partitions"] == min(parts, -(-xyz.shape[2] // 16))
        assert volume.to_bytes() == plain, f"{parts} partitions"


def test_a_corrupt_chunk_is_named(tmp_path, client):
    zyx = labels_zyx(np.uint16, shape=(40, 14, 12), seed=4)
    path = zarr_store(tmp_path / "seg.zarr", zyx, chunks=(10, 14, 12))
    with open(os.path.join(path, "2.0.0"), "wb") as f:  # chunk z 20..29: garbage, not blosc
        f.write(b"\x00not a chunk" * 7)
    with pytest.raises(OSError, match=r"z-slices 16\.\.31 \(chunks 1\.\.3 along z\)"):
        vtksvdag.build_distributed(path, client, slab=16, partitions=2)


class _KillOnce(distributed.WorkerPlugin):
    """Kills its worker process when the first partial build starts (a worker lost mid-task)."""

    def __init__(self, marker):
        self.marker = marker

    def setup(self, worker):
        pass

    def transition(self, key, start, finish, **kwargs):
        name = key[0] if isinstance(key, tuple) else str(key)
        if finish == "executing" and "_build_part" in name and not os.path.exists(self.marker):
            open(self.marker, "w").close()
            os._exit(1)


def test_a_lost_worker_is_replaced(tmp_path):
    zyx = labels_zyx(np.uint32, shape=(64, 20, 18), seed=6)
    path = zarr_store(tmp_path / "seg.zarr", zyx)
    marker = str(tmp_path / "killed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=":0")
    with cluster, distributed.Client(cluster) as c:
        c.register_plugin(_KillOnce(marker))
        volume = vtksvdag.build_distributed(path, c, partitions=4)
    assert os.path.exists(marker), "no worker was killed: the test did not test anything"
    assert volume.to_bytes() == vtksvdag.read(path).to_bytes()


def test_bad_arguments(tmp_path):
    zyx = labels_zyx(np.uint8, shape=(20, 5, 5))
    path = zarr_store(tmp_path / "seg.zarr", zyx)
    with pytest.raises(ValueError, match="multiple of 16"):
        vtksvdag.build_distributed(path, "local:1", slab=20)
    with pytest.raises(TypeError, match="multiple of 16"):
        vtksvdag.build_distributed(path, "local:1", slab=16.0)
    with pytest.raises(ValueError, match="partitions"):
        vtksvdag.build_distributed(path, "local:1", partitions=0)
    with pytest.raises(TypeError, match="partitions"):
        vtksvdag.build_distributed(path, "local:1", partitions=2.5)
    with pytest.raises(ValueError, match="local:N"):
        vtksvdag.build_distributed(path, "local:zero")
    with pytest.raises(TypeError, match="client"):
        vtksvdag.build_distributed(path, 3)
    with pytest.raises(ValueError, match="chunked stores"):
        vtksvdag.build_distributed(str(SHARED_DATA / "fib25_64.nrrd") if SHARED_DATA.is_dir()
                                   else __file__, "local:1")
    with pytest.raises(ValueError, match="out of range"):
        vtksvdag.build_distributed(path, "local:1", background=300)


def test_cli_compress_on_dask(tmp_path):
    from test_cli import run_cli

    zyx = labels_zyx(np.uint16, shape=(50, 12, 10), seed=8)
    path = zarr_store(tmp_path / "seg.zarr", zyx)
    one, two = tmp_path / "one.svdag", tmp_path / "two.svdag"
    assert run_cli("compress", path, "-o", one).returncode == 0
    result = run_cli("compress", path, "-o", two, "--dask", "local:2", "--slab", "16",
                     "--partitions", "3")
    assert result.returncode == 0, result.stderr
    assert one.read_bytes() == two.read_bytes()
    for args, message in ((["--slab", "16"], "only with --dask"),
                          (["--partitions", "2"], "only with --dask"),
                          (["--dask", "local:2", "--slab", "24"], "multiple of 16")):
        result = run_cli("compress", path, "-o", tmp_path / "x.svdag", *args)
        assert result.returncode != 0 and message in result.stderr

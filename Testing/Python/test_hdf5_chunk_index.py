"""HDF5 chunked datasets: a damaged chunk index is an error, never a volume of fill values.

A gzip-chunked int32 dataset is written with h5py; its version-1 B-tree (the chunk index of
files written with the default, earliest format) is found by its "TREE" signature and damaged.
Every read must then raise, or return exactly the original voxels. Chunks that were never
written are legitimate: they read as the dataset's fill value (as h5py reads them), with a
warning that says so.
"""
import pathlib
import sys
import warnings

import h5py
import numpy as np
import pytest

import vtksvdag

# The B-tree layout is the fuzzing harness's (its h5_chunk_index target damages the same bytes).
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "fuzz"))
from fuzz_readers import H5_CHUNK_ENTRY_BYTES as ENTRY_BYTES  # noqa: E402
from fuzz_readers import chunk_btree as find_chunk_btree  # noqa: E402

SHAPE_ZYX = (16, 16, 16)
CHUNKS = (4, 8, 8)


def labels_zyx():
    rng = np.random.default_rng(11)
    return rng.integers(1, 500, size=SHAPE_ZYX).astype(np.int32)


def xyz(a_zyx):
    return np.ascontiguousarray(a_zyx.transpose(2, 1, 0))


def write_chunked(path, data, fill=None, write=True):
    with h5py.File(path, "w") as f:
        d = f.create_dataset("labels", shape=SHAPE_ZYX, dtype=np.int32, chunks=CHUNKS,
                             compression="gzip", fillvalue=fill)
        if write is True:
            d[...] = data
        else:
            for z0, z1 in write:  # only these z-ranges (whole chunk layers)
                d[z0:z1] = data[z0:z1]


def chunk_btree(raw):
    """Offset of the raw-data-chunk B-tree leaf and its number of entries."""
    found = find_chunk_btree(raw)
    assert found is not None, "no chunk B-tree leaf in the file"
    return found


def test_intact_file_reads_exactly(tmp_path):
    path = tmp_path / "ok.h5"
    data = labels_zyx()
    write_chunked(path, data)
    np.testing.assert_array_equal(vtksvdag.read(path).to_numpy(), xyz(data))


def test_corrupt_chunk_offset_is_an_error(tmp_path):
    # Two bytes of one key's first chunk offset: HDF5 loses track of chunks and, unchecked,
    # returned the fill value for their voxels.
    path = tmp_path / "bad.h5"
    data = labels_zyx()
    write_chunked(path, data)
    raw = bytearray(path.read_bytes())
    node, entries = chunk_btree(raw)
    assert entries == np.prod([s // c for s, c in zip(SHAPE_ZYX, CHUNKS)])
    key = node + 24 + 5 * ENTRY_BYTES
    raw[key + 8] ^= 0x5A
    raw[key + 9] ^= 0x01
    path.write_bytes(bytes(raw))
    with pytest.raises((OSError, ValueError), match="chunk"):
        vtksvdag.read(path)


def test_random_chunk_index_damage_never_gives_a_wrong_volume(tmp_path):
    path = tmp_path / "flip.h5"
    data = labels_zyx()
    write_chunked(path, data)
    clean = path.read_bytes()
    node, entries = chunk_btree(clean)
    rng = np.random.default_rng(3)
    refused = 0
    for trial in range(24):
        raw = bytearray(clean)
        for _ in range(int(rng.integers(1, 3))):
            offset = node + 24 + int(rng.integers(0, entries * ENTRY_BYTES))
            raw[offset] ^= int(rng.integers(1, 256))
        path.write_bytes(bytes(raw))
        try:
            got = vtksvdag.read(path).to_numpy()
        except (OSError, ValueError):
            refused += 1
            continue
        np.testing.assert_array_equal(got, xyz(data), err_msg=f"trial {trial}: wrong volume")
    assert refused > 0  # the damage is real: most flips are refused


def test_chunks_never_written_read_as_the_fill_value_with_a_warning(tmp_path):
    path = tmp_path / "partial.h5"
    data = labels_zyx()
    write_chunked(path, data, fill=7, write=[(0, 4), (12, 16)])
    with h5py.File(path, "r") as f:
        expected = f["labels"][...]
    assert (expected[4:12] == 7).all()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = vtksvdag.read(path).to_numpy()
    np.testing.assert_array_equal(got, xyz(expected))
    text = " ".join(str(w.message) for w in caught)
    assert "never written" in text and "fill value 7" in text, text

"""Format 1.0 .svdag files (before leaf references carried a symmetry) still read, bit-exactly.

The fixtures in Testing/Data/format1 were written by the last 1.0 build from arrays whose SHA-256
(computed from the arrays themselves) is in expected.json; make_format1.py says how.
"""
import hashlib
import json
import pathlib
import struct

import numpy as np
import pytest

import vtksvdag

DATA = pathlib.Path(__file__).resolve().parents[1] / "Data" / "format1"
EXPECTED = json.loads((DATA / "expected.json").read_text())


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_format1_file_decodes_to_its_source_array(name, tmp_path):
    path = DATA / f"{name}.svdag"
    assert struct.unpack_from("<HH", path.read_bytes(), 8) == (1, 0)
    expected = EXPECTED[name]
    volume = vtksvdag.read(path)
    labels = volume.to_numpy()
    assert list(labels.shape) == expected["shape_xyz"]
    assert str(labels.dtype) == expected["dtype"]
    assert hashlib.sha256(np.ascontiguousarray(labels).tobytes()).hexdigest() == expected["sha256_xyz_c_order"]
    assert [int(v) for v in volume.labels] == expected["labels"]
    # A fresh build of the same voxels agrees on everything but the (now smaller) encoding.
    fresh = vtksvdag.from_numpy(labels)
    assert fresh.stats()["bytes_total"] <= volume.stats()["bytes_total"]
    assert fresh.stats()["blocks"] == volume.stats()["blocks"]
    np.testing.assert_array_equal(fresh.label_voxel_counts, volume.label_voxel_counts)
    # Saved again, it is a 3.0 (or 2.0) file with the same voxels; 3.0 holds the fresh build.
    for version in (3, 2):
        again = tmp_path / f"again{version}.svdag"
        volume.save(again, format_version=version)
        assert struct.unpack_from("<HH", again.read_bytes(), 8) == (version, 0)
        np.testing.assert_array_equal(vtksvdag.read(again).to_numpy(), labels)
    assert vtksvdag.read(tmp_path / "again3.svdag").to_bytes() == fresh.to_bytes()

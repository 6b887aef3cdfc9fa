"""The pyvista examples in examples/ run off-screen and save a non-blank picture or movie.

Each example runs as a user would start it, in its own process from the repository root:
``python examples/<name>.py --off-screen --output <file>``.
"""
import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image, ImageSequence

REPO = pathlib.Path(__file__).resolve().parents[2]

EXAMPLES = [
    ("quick_start", "png"),
    ("explorer", "png"),
    ("label_colors", "png"),
    ("turntable", "gif"),
    ("lod_comparison", "png"),
    ("labels_over_intensity", "png"),
    ("clipping", "png"),
    ("atlas", "png"),
    ("connectome", "png"),
]


def run_example(name, output, *extra):
    script = REPO / "examples" / f"{name}.py"
    result = subprocess.run(
        [sys.executable, str(script), "--off-screen", "--output", str(output), *extra],
        cwd=REPO, capture_output=True, text=True, timeout=120,
    )
    assert result.returncode == 0, (
        f"{script.name} exited {result.returncode}\nstdout:\n{result.stdout}\nstderr:\n{result.stderr}"
    )
    assert output.is_file(), f"{script.name} wrote no {output.name}\nstdout:\n{result.stdout}"
    return result


def distinct_colors(frame):
    pixels = np.asarray(frame.convert("RGB")).reshape(-1, 3)
    return len(np.unique(pixels, axis=0))


@pytest.mark.parametrize("name, ext", EXAMPLES, ids=[name for name, _ in EXAMPLES])
def test_example_runs_off_screen(name, ext, tmp_path):
    output = tmp_path / f"{name}.{ext}"
    result = run_example(name, output)
    if name == "explorer":  # the simulated pick at the image center hits a cell, highlighted
        assert "label " in result.stdout and " at (" in result.stdout, result.stdout
        assert "highlighted label " in result.stdout, result.stdout
    if name == "clipping":  # the pick at the image center is on the cut face: the plane's normal
        assert "normal (-0.28, -0.94, -0.19)" in result.stdout, result.stdout
    with Image.open(output) as image:
        if ext == "gif":
            frames = [frame.copy() for frame in ImageSequence.Iterator(image)]
            assert len(frames) == 12
            assert all(distinct_colors(frame) > 1 for frame in frames)
            # the camera orbits: consecutive frames differ
            arrays = [np.asarray(frame.convert("RGB")) for frame in frames]
            assert all(not np.array_equal(a, b) for a, b in zip(arrays, arrays[1:]))
        else:
            assert distinct_colors(image) > 1, f"{output.name} is blank"



def read_freesurfer_lut(path):
    """``{index: (name, (r, g, b) in 0-1)}`` of a FreeSurfer color table, parsed here by hand (not
    with vtksvdag.read_label_table, whose result the example shows)."""
    table = {}
    for line in path.read_text().splitlines():
        if line.strip() and not line.lstrip().startswith("#"):
            index, name, r, g, b, _ = line.split()
            table[int(index)] = (name, tuple(int(c) / 255 for c in (r, g, b)))
    return table


def test_atlas_legend_names_and_colors_are_the_tables(tmp_path):
    """The legend lists labels on the cut face with the names and colors of the LUT written next
    to the volume."""
    result = run_example("atlas", tmp_path / "atlas.png", "--workdir", str(tmp_path))
    lut = read_freesurfer_lut(tmp_path / "FreeSurferColorLUT.txt")
    lines = result.stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("legend: "))
    entries = [re.fullmatch(r"  (\d+) (\S+) \(([\d.]+), ([\d.]+), ([\d.]+)\)", line)
               for line in lines[start + 1:] if line.startswith("  ")]
    assert len(entries) >= 8 and all(entries), result.stdout
    import vtksvdag

    volume = vtksvdag.read(tmp_path / "aparc+aseg.nii.gz")
    # The cut face: the voxel slice through the plane (the middle of y, CUT_FRACTION = 0.5).
    face = set(np.unique(volume.to_numpy()[:, volume.dims[1] // 2, :]).tolist())
    for match in entries:
        value, name = int(match[1]), match[2]
        assert name == lut[value][0], (value, name)
        np.testing.assert_allclose([float(match[i]) for i in (3, 4, 5)], lut[value][1], atol=1e-3)
        assert value in face, f"legend label {value} is not on the cut face"
        assert not name.startswith(("Right-", "ctx-rh-")), name
    # The deep structures the cut passes through are named.
    names = {match[2] for match in entries}
    assert {"Left-Cerebral-White-Matter", "Left-Thalamus", "Left-Putamen"} <= names, names


def brute_force_neighbours(labels, label):
    """The labels sharing a voxel face with ``label`` (6-neighbourhood), background 0 excluded."""
    found = set()
    for axis in range(3):
        a = np.moveaxis(labels, axis, 0)
        lo, hi = a[:-1], a[1:]
        found |= set(hi[(lo == label) & (hi != label)].tolist())
        found |= set(lo[(hi == label) & (lo != label)].tolist())
    return sorted(found - {0})


def test_connectome_neighbours_are_the_touching_labels(tmp_path):
    """The printed neighbours of the picked neuron equal a numpy brute-force adjacency of it on
    the same volume."""
    result = run_example("connectome", tmp_path / "connectome.png")
    source = re.search(r"^volume: (.+)$", result.stdout, re.M)[1]
    label = int(re.search(r"^picked label (\d+) at", result.stdout, re.M)[1])
    printed = re.search(r"^neighbours \((\d+)\): ([\d ]*)$", result.stdout, re.M)
    neighbours = [int(v) for v in printed[2].split()]
    assert int(printed[1]) == len(neighbours)
    if source.startswith("synthetic"):
        from vtksvdag.synthetic import voronoi

        labels = voronoi((64, 64, 64), 60, seed=7)  # the example's stand-in, (z, y, x)
    else:
        import nrrd

        labels, _ = nrrd.read(source, index_order="C")
    assert label in np.unique(labels)
    expected = brute_force_neighbours(labels, label)
    assert expected, "the picked neuron touches no other: a poor example"
    assert neighbours == expected

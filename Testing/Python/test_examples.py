"""The pyvista examples in examples/ run off-screen and save a non-blank picture or movie.

Each example runs as a user would start it, in its own process from the repository root:
``python examples/<name>.py --off-screen --output <file>``.
"""
import pathlib
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
]


def run_example(name, output):
    script = REPO / "examples" / f"{name}.py"
    result = subprocess.run(
        [sys.executable, str(script), "--off-screen", "--output", str(output)],
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


"""bench/_volcanite.py and render.py's same-run comparison with Volcanite, which is no dependency:
the input file against pynrrd (an independent reader), the comparison's plumbing through a
stand-in executable that answers as Volcanite does (its CSGV compression, its evaluation log).
Never timings."""
import pathlib
import stat
import sys

import nrrd
import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "bench"))
import _volcanite  # noqa: E402
import render as bench_render  # noqa: E402

# Volcanite's command-line answers: `-c OUT IN` writes its CSGV file; a headless render appends
# the median frame time to the evaluation log after the format line, writes the image given by
# -i and prints its fps line. This stand-in checks the arguments the templates pass.
STAND_IN = r'''#!{python}
import os, sys
args = sys.argv[1:]
assert os.environ.get("VOLCANITE_DEVICE") == "0" and "--headless" in args
if "-c" in args:
    out, volume = args[args.index("-c") + 1], args[-1]
    assert open(volume, "rb").read(9) == b"NRRD0004\n"
    open(out, "w").write("csgv of " + volume)
    sys.exit(0)
assert args[-1].endswith(".csgv") and args[args.index("-r") + 1] == "16x16"
config = args[args.index("--config") + 1]
assert "Accumulation Frames: 3" in config and "Post-Processing: 0" in config  # no denoiser
if "--eval-logfiles" in args:
    log = args[args.index("--eval-logfiles") + 1]
    assert open(log).readline().startswith("#fmt:")
    open(log, "a").write("median_ms=12.5\n")
open(args[args.index("-i") + 1], "wb").write(b"png")
print("rendering of 3 frames finished with 75 fps (13.3333ms/frame)")
'''


@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.uint32, np.int64, np.uint64])
def test_input_is_the_nrrd_volcanite_reads(tmp_path, dtype):
    rng = np.random.default_rng(3)
    info = np.iinfo(dtype)
    labels = rng.integers(0, 5, size=(5, 7, 9)).astype(dtype)  # z, y, x: odd sizes
    labels[0, 0, 0], labels[1, 2, 3] = info.max, info.min
    path = _volcanite.write_input(labels, tmp_path / "v.nrrd")
    assert path.read_bytes().startswith(b"NRRD0004\n")
    data, header = nrrd.read(str(path), index_order="C")
    assert header["encoding"] == "raw" and header["endian"] == "little"
    assert list(header["sizes"]) == [9, 7, 5]
    unsigned = np.dtype(f"u{np.dtype(dtype).itemsize}")
    assert data.dtype == unsigned.newbyteorder("<") or data.dtype == unsigned
    np.testing.assert_array_equal(data, labels.view(unsigned))  # the same bit patterns


def test_comparison_runs_through_a_stand_in(tmp_path):
    import vtksvdag

    stand_in = tmp_path / "volcanite"
    stand_in.write_text(STAND_IN.replace("{python}", sys.executable))
    stand_in.chmod(stand_in.stat().st_mode | stat.S_IXUSR)
    labels = np.zeros((20, 18, 16), np.uint16)
    labels[2:15, 3:14, 4:12] = 7
    labels[8:18, 5:16, 2:9] = 300
    volume = vtksvdag.from_numpy(labels, axis_order="zyx")
    rows = bench_render.volcanite_comparison(str(stand_in), _volcanite.DEFAULT_COMMAND,
                                             [("boxes", volume)], [16], 3, 2, tmp_path / "out")
    theirs = [r for r in rows if r["kind"] == "volcanite"]
    ours = [r for r in rows if r["kind"] == "matched"]
    assert [(r["volume"], r["width"], r["ms_median"]) for r in theirs] == [("boxes", 16, 12.5)]
    assert sorted(r["backend"] for r in ours) == ["compute", "rt"]
    assert all(r["ms_median"] > 0 and r["ms_min"] <= r["ms_median"] for r in ours)
    # The input was written and compressed once; only the compressed form is kept.
    assert not (tmp_path / "out" / "volcanite" / "boxes.nrrd").exists()
    assert (tmp_path / "out" / "volcanite" / "boxes.csgv").read_text().startswith("csgv of ")
    # A template without {log}: the last "<n> ms" it prints (its mean over the frames).
    template = _volcanite.DEFAULT_COMMAND.replace(" --eval-logfiles {log}", "")
    assert _volcanite.frame_ms(str(stand_in), template,
                               tmp_path / "out" / "volcanite" / "boxes.csgv", 16, 16, 3,
                               tmp_path / "w") == pytest.approx(13.3333)

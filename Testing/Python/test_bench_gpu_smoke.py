"""Smoke test of the prepared GPU benchmark: `bench/gpu.sh` runs the C++ tool for both backends,
both LODs and both bounce counts, accumulating and restarting, and prints one table row per
file, LOD and bounce count (here on lavapipe, at a tiny size). Asserts structure, not timings."""
import json
import pathlib
import subprocess

import numpy as np

import vtksvdag

REPO = pathlib.Path(__file__).resolve().parents[2]


def tool_folder():
    import vtksvdag.vtkSVDAGRendering as module

    # <build>/python/vtksvdag/vtkSVDAGRendering*.so -> <build>/bin
    folder = pathlib.Path(module.__file__).resolve().parents[2] / "bin"
    assert (folder / "vtksvdag-render").is_file(), f"vtksvdag-render was not built in {folder}"
    return folder


def test_gpu_script_prints_one_table(tmp_path):
    rng = np.random.default_rng(2)
    labels = np.where(rng.random((24, 20, 18)) < 0.4, rng.integers(1, 6, (24, 20, 18)), 0).astype(np.uint16)
    for name in ("a", "b"):
        vtksvdag.from_numpy(labels if name == "a" else labels[:, :, ::-1].copy()).save(tmp_path / f"{name}.svdag")
    run = subprocess.run(["bash", str(REPO / "bench" / "gpu.sh"), "--bin", str(tool_folder()),
                          "--width", "32", "--height", "24", "--frames", "2", str(tmp_path)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    lines = run.stdout.strip().splitlines()
    assert "32x24, 1 spp" in lines[0]
    end = lines.index("") if "" in lines else len(lines)
    rows = [line.split() for line in lines[2:end]]
    assert sorted((r[0], r[1], r[2]) for r in rows) == sorted(
        (f, lod, b) for f in "ab" for lod in ("voxel", "block") for b in ("1", "4"))
    for r in rows:
        # Per backend: accumulating, restarting, restarting denoised, the same traced at half
        # resolution and upsampled; the ratio; the denoiser's cost per backend (percent of the
        # restarting frame, from the two columns before); the bytes.
        numbers = [float(v) for v in r[3:] if v != "|"]
        assert len(numbers) == 13, r
        times, costs = numbers[:9] + numbers[11:], numbers[9:11]
        assert all(n > 0 for n in times), r
        for cost, restart, denoised in zip(costs, (numbers[1], numbers[5]), (numbers[2], numbers[6])):
            # The times are printed to 0.005 ms and the cost to 0.5%.
            low = 100.0 * ((denoised - 0.005) / (restart + 0.005) - 1.0) - 0.5
            high = 100.0 * ((denoised + 0.005) / (restart - 0.005) - 1.0) + 0.5
            assert low <= cost <= high, r
    # The start-up of each backend: every cache empty (with the full pipeline, with the
    # preview's first frame, with the smooth-shading and the clipping variants), and with our
    # pipeline cache warm; each with its compile seconds.
    startup = [line.replace(",", "").split() for line in lines[end + 2:]]
    assert sorted((s[0], s[1]) for s in startup) == sorted(
        (b, state) for b in ("rt", "compute")
        for state in ("cold", "cold-preview", "cold-smooth", "cold-clipped", "ours-warm"))
    for s in startup:
        assert float(s[2]) > 0 and s[4] == "compile" and float(s[5]) > 0, s
        assert s[8] == ("True" if s[1] == "cold-preview" else "False"), s
    # A missing input or an empty folder is an error, not an empty table.
    bad = subprocess.run(["bash", str(REPO / "bench" / "gpu.sh"), str(tmp_path / "none")],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode != 0 and "neither a .svdag file nor a folder" in bad.stderr
    (tmp_path / "empty").mkdir()
    bad = subprocess.run(["bash", str(REPO / "bench" / "gpu.sh"), str(tmp_path / "empty")],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode != 0 and "no .svdag files" in bad.stderr


def test_render_tool_traces_reduced_and_upsamples(tmp_path):
    """--trace-reduction R: the image keeps its size, differs from the full-resolution trace (the
    paths were traced on fewer pixels) but stays close to it, and R is range-checked."""
    from PIL import Image

    labels = np.zeros((40, 40, 40), dtype=np.uint8)
    labels[5:35, 5:35, 5:20] = 1
    labels[10:30, 10:30, 20:35] = 2
    path = tmp_path / "boxes.svdag"
    vtksvdag.from_numpy(labels).save(path)
    tool = tool_folder() / "vtksvdag-render"
    images = {}
    for r in (1, 4):
        run = subprocess.run([str(tool), str(path), str(tmp_path / f"r{r}.png"), "--width", "64",
                              "--height", "48", "--frames", "8", "--no-denoise",
                              "--trace-reduction", str(r)], capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr
        assert json.loads(run.stdout.strip().splitlines()[-1])["trace_reduction"] == r
        images[r] = np.asarray(Image.open(tmp_path / f"r{r}.png").convert("RGB"), dtype=float)
    assert images[4].shape == images[1].shape == (48, 64, 3)
    difference = np.abs(images[4] - images[1]).mean()
    assert 0 < difference < 12, difference
    bad = subprocess.run([str(tool), str(path), str(tmp_path / "x.png"), "--trace-reduction", "9"],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode == 1 and "--trace-reduction needs an integer in [1, 8]" in bad.stderr

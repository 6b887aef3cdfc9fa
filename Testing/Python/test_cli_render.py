"""``vtksvdag render``, run as a separate process on small images (lavapipe here)."""
import json
import os
import subprocess
import sys

import nrrd
import numpy as np
import pytest
from PIL import Image

WIDTH, HEIGHT = 40, 24
JSON_KEYS = {"device", "width", "height", "spp", "lod", "backend", "setup_seconds", "render_seconds",
             "ms_per_frame", "bytes_blas", "bytes_tlas", "bytes_device"}


def run_cli(*args, env=None):
    return subprocess.run([sys.executable, "-m", "vtksvdag"] + [str(a) for a in args],
                          capture_output=True, text=True, timeout=120, check=False,
                          env=env)


def assert_one_line_error(result, match, code=1):
    assert result.returncode == code, (result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("vtksvdag: error: ") and match in lines[0], lines[0]
    assert "Traceback" not in result.stderr


@pytest.fixture(scope="module")
def volume_file(tmp_path_factory):
    rng = np.random.default_rng(3)
    labels = np.zeros((20, 20, 20), np.uint16)
    labels[3:17, 3:17, 3:17] = rng.choice([4, 8, 15], size=(14, 14, 14))
    labels[rng.random(labels.shape) < 0.3] = 0
    path = tmp_path_factory.mktemp("cli_render") / "small.nrrd"
    nrrd.write(str(path), labels, index_order="C")
    return path


def render(volume_file, output, *options):
    result = run_cli("render", volume_file, "-o", output, "--width", WIDTH, "--height", HEIGHT,
                     "--json", *options)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def test_render_png_and_json(volume_file, tmp_path):
    out = tmp_path / "a.png"
    info = render(volume_file, out, "--spp", 3, "--lod", "leaf", "--bounces", 2)
    assert JSON_KEYS <= set(info)
    assert (info["width"], info["height"], info["spp"], info["lod"]) == (WIDTH, HEIGHT, 3, "leaf")
    assert info["device"] and info["backend"] in ("rt", "compute")
    assert (info["bytes_blas"] > 0 and info["bytes_tlas"] > 0) == (info["backend"] == "rt")
    parts = info["bytes_device"]
    assert parts["encoding"] > 0 and parts["acceleration"] > 0
    # 20 words a pixel, and the denoiser's working images (on by default, 16 words) and edge
    # coverage records (24 words).
    assert info["denoise"] is True and parts["images"] == WIDTH * HEIGHT * (80 + 64 + 96)
    assert parts["total"] >= parts["encoding"] + parts["acceleration"] + parts["materials"] + parts["images"]
    assert info["ms_per_frame"] > 0 and info["render_seconds"] > 0
    image = np.asarray(Image.open(out))
    assert image.shape == (HEIGHT, WIDTH, 4)
    assert len(np.unique(image.reshape(-1, 4), axis=0)) > 10  # not a blank image


def test_backends_render_the_same_image(volume_file, tmp_path):
    """--backend rt and --backend compute: the same scene, the chosen backend reported, no BVH
    on compute; the images agree (the same integrator and random numbers; a grazing ray may
    differ)."""
    images = {}
    for backend in ("rt", "compute"):
        out = tmp_path / f"{backend}.png"
        info = render(volume_file, out, "--spp", 2, "--backend", backend)
        assert info["backend"] == backend
        assert (info["bytes_blas"] > 0) == (backend == "rt")
        images[backend] = np.asarray(Image.open(out)).astype(int)
    close = np.all(np.abs(images["rt"] - images["compute"]) <= 2, axis=2)
    assert close.mean() >= 0.97, close.mean()


def test_backend_rt_without_ray_tracing_is_a_clear_error(volume_file, tmp_path):
    import os
    import subprocess

    env = dict(os.environ, SVDAG_VK_NO_RAY_TRACING="1")
    result = subprocess.run([sys.executable, "-m", "vtksvdag", "render", str(volume_file), "-o",
                             str(tmp_path / "a.png"), "--width", "8", "--height", "8", "--spp", "1",
                             "--backend", "rt"], capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 1
    assert "needs a Vulkan device with ray tracing" in result.stderr, result.stderr
    assert not (tmp_path / "a.png").exists()
    result = subprocess.run([sys.executable, "-m", "vtksvdag", "render", str(volume_file), "-o",
                             str(tmp_path / "b.png"), "--width", "8", "--height", "8", "--spp", "1",
                             "--json"], capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["backend"] == "compute"


def test_seed_and_options(volume_file, tmp_path):
    a = tmp_path / "a.png"
    b = tmp_path / "b.png"
    c = tmp_path / "c.png"
    render(volume_file, a, "--spp", 2, "--seed", 9)
    render(volume_file, b, "--spp", 2, "--seed", 9)
    render(volume_file, c, "--spp", 2, "--seed", 10)
    assert a.read_bytes() == b.read_bytes()
    assert a.read_bytes() != c.read_bytes()
    # Sun, plain estimator, another view: a different image.
    d = tmp_path / "d.png"
    info = render(volume_file, d, "--spp", 2, "--seed", 9, "--sun", 45, 60, "--no-nee",
                  "--azimuth", 100, "--elevation", -10, "--zoom", 1.5)
    assert info["nee"] is False
    assert a.read_bytes() != d.read_bytes()


def test_hide_and_exr_and_svdag_input(volume_file, tmp_path):
    svdag = tmp_path / "small.svdag"
    assert run_cli("compress", volume_file, "-o", svdag).returncode == 0
    exr = tmp_path / "all.exr"
    render(svdag, exr, "--spp", 1)
    assert exr.stat().st_size > 0
    # Hiding two of the three label values leaves fewer lit pixels in the PNG's alpha-1 area.
    full = tmp_path / "full.png"
    part = tmp_path / "part.png"
    render(svdag, full, "--spp", 1)
    info = render(svdag, part, "--spp", 1, "--hide", 4, 8)
    assert info["hidden_labels"] == [4, 8]
    assert Image.open(full).tobytes() != Image.open(part).tobytes()
    # The EXR of the first run is an equirectangular map like any other.
    lit = tmp_path / "lit.png"
    render(svdag, lit, "--spp", 1, "--environment", exr)
    assert Image.open(lit).tobytes() != Image.open(full).tobytes()


def test_errors(volume_file, tmp_path):
    assert_one_line_error(run_cli("render", volume_file, "-o", tmp_path / "x.jpg"),
                          "render writes .png or .exr files", code=2)
    assert_one_line_error(run_cli("render", volume_file, "-o", tmp_path / "x.png", "--hide", 99),
                          "label 99")
    assert_one_line_error(run_cli("render", volume_file, "-o", tmp_path / "x.png", "--bounces", 99),
                          "argument --bounces: must be in 0..64, got 99", code=2)
    assert_one_line_error(run_cli("render", volume_file, "-o", tmp_path / "x.png",
                                  "--environment", tmp_path / "missing.exr", "--width", 8,
                                  "--height", 8), "missing.exr")
    env = dict(os.environ, SVDAG_VK_DEVICE="nonexistent")
    result = run_cli("render", volume_file, "-o", tmp_path / "x.png", "--width", 8, "--height", 8,
                     env=env)
    assert_one_line_error(result, "no usable Vulkan device")
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize(
    "args, match",
    [
        (["--width", "20000"], "argument --width: must be in 1..16384, got 20000"),
        (["--width", str(2**31)], "argument --width: must be in 1..16384"),
        (["--width", "0"], "argument --width: must be in 1..16384"),
        (["--width", "1.5"], "argument --width: must be an integer in 1..16384"),
        (["--height", "16385"], "argument --height: must be in 1..16384"),
        (["--height", "-3"], "argument --height: must be in 1..16384"),
        (["--spp", "65537"], "argument --spp: must be in 1..65536"),
        (["--spp", "0"], "argument --spp: must be in 1..65536"),
        (["--bounces", "-1"], "argument --bounces: must be in 0..64"),
        (["--bounces", "65"], "argument --bounces: must be in 0..64"),
        (["--seed", "-1"], "argument --seed: must be in 0..4294967295"),
        (["--seed", str(2**32)], "argument --seed: must be in 0..4294967295"),
        (["--zoom", "0"], "argument --zoom: must be a finite number > 0"),
        (["--zoom", "inf"], "argument --zoom: must be a finite number > 0"),
        (["--zoom", "nan"], "argument --zoom: must be a finite number > 0"),
        (["--azimuth", "inf"], "argument --azimuth: must be a finite number"),
        (["--elevation", "nan"], "argument --elevation: must be a finite number"),
        (["--sun", "inf", "0"], "argument --sun: must be a finite number"),
        (["--sun", "0", "nan"], "argument --sun: must be a finite number"),
        (["--sky", "1", "-1", "1"], "argument --sky: must be a finite number >= 0"),
        (["--sky", "1", "nan", "1"], "argument --sky: must be a finite number >= 0"),
        (["--hide", str(2**64)], "argument --hide: must be in"),
        (["--background", str(2**64)], "argument --background: must be in"),
        (["--background", "70000"], "argument --background: 70000 is out of range for the labels"),
        (["--exclude", "-1"], "argument --exclude: -1 is out of range for the labels"),
    ],
)
def test_numeric_options_are_range_checked(volume_file, tmp_path, args, match):
    out = tmp_path / "x.png"
    result = run_cli("render", volume_file, "-o", out, "--width", 8, "--height", 8, *args)
    assert_one_line_error(result, match, code=2)
    assert not out.exists()


def test_the_largest_width_is_rendered_as_reported(volume_file, tmp_path):
    out = tmp_path / "wide.png"
    info = render(volume_file, out, "--spp", 1, "--width", 16384, "--height", 1, "--seed",
                  2**32 - 1, "--bounces", 0)
    assert (info["width"], info["height"], info["seed"]) == (16384, 1, 2**32 - 1)
    assert np.asarray(Image.open(out)).shape == (1, 16384, 4)

"""The vtksvdag command line, run as a separate process (`python -m vtksvdag`)."""
import json
import os
import subprocess
import sys

import nrrd
import numpy as np
import pytest

from conftest import REPO

STATS_KEYS = {
    "dims", "voxels", "labels", "blocks", "dag_nodes", "root_nodes", "mid_nodes", "leaves",
    "bytes_blocks", "bytes_dag", "bytes_labels", "bytes_total", "raw_bytes_32", "bits_per_voxel",
    "build_seconds", "load_seconds", "dtype", "spacing", "origin",
}


def run_cli(*args, executable=None):
    """Run the command line; returns the CompletedProcess (text output)."""
    command = [executable] if executable else [sys.executable, "-m", "vtksvdag"]
    return subprocess.run(
        command + [str(a) for a in args], capture_output=True, text=True, timeout=120, check=False
    )


def run_json(*args):
    result = run_cli(*args, "--json")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""  # no progress bar: stderr is not a terminal, and --json
    return json.loads(result.stdout)


def assert_one_line_error(result, code, match):
    assert result.returncode == code, (result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("vtksvdag: error: "), lines[0]
    assert match in lines[0], lines[0]
    assert "Traceback" not in result.stderr


@pytest.fixture(scope="module")
def small_nrrd(tmp_path_factory):
    """A gzip NRRD [x, y, z] int16 volume with negative labels, spacing and origin."""
    rng = np.random.default_rng(7)
    labels = np.zeros((23, 17, 35), np.int16)
    labels[2:20, 3:15, 4:30] = rng.integers(-3, 4, size=(18, 12, 26))
    labels[:, :, 31:] = 9
    path = tmp_path_factory.mktemp("cli") / "small.nrrd"
    header = {
        "encoding": "gzip",
        "space dimension": 3,
        "space directions": np.diag([0.5, 0.75, 2.0]),
        "space origin": np.array([-4.0, 1.0, 10.0]),
    }
    nrrd.write(str(path), labels, header=header, index_order="F")
    return path, labels


def test_version_and_console_script():
    result = run_cli("--version")
    assert result.returncode == 0 and result.stdout.strip() == "vtksvdag 0.1.0"
    script = REPO / ".venv" / "bin" / "vtksvdag"
    assert script.exists(), "scripts/setup.sh installs the console script"
    result = run_cli("--help", executable=str(script))
    assert result.returncode == 0
    for command in ("compress", "decompress", "info"):
        assert command in result.stdout


def test_info_on_a_label_volume(small_nrrd):
    path, labels = small_nrrd
    stats = run_json("info", path)
    assert STATS_KEYS | {"input", "file_bytes"} <= set(stats)
    assert stats["dims"] == list(labels.shape)
    assert stats["voxels"] == labels.size
    assert stats["labels"] == len(np.unique(labels[labels != 0]))
    assert stats["dtype"] == "int16"
    assert stats["spacing"] == [0.5, 0.75, 2.0] and stats["origin"] == [-4.0, 1.0, 10.0]
    assert stats["bytes_total"] == stats["bytes_blocks"] + stats["bytes_dag"] + stats["bytes_labels"]
    assert stats["file_bytes"] == os.path.getsize(path)
    assert stats["build_seconds"] > 0 and stats["load_seconds"] is None
    assert stats["file_format"] is None  # not a .svdag file
    human = run_cli("info", path)
    assert human.returncode == 0 and human.stderr == ""
    assert "bytes: total" in human.stdout and f"{stats['bytes_total']:,}" in human.stdout


def test_compress_info_decompress_round_trip(small_nrrd, tmp_path):
    path, labels = small_nrrd
    svdag = tmp_path / "small.svdag"
    compressed = run_json("compress", path, "-o", svdag, "--level", "5")
    assert STATS_KEYS | {"input", "output", "file_bytes"} <= set(compressed)
    assert compressed["output"] == str(svdag)
    assert compressed["file_bytes"] == os.path.getsize(svdag) > 0

    info = run_json("info", svdag)
    assert info["load_seconds"] > 0 and info["build_seconds"] is None
    assert info["file_format"] == "4.0"  # the default
    assert ".svdag 4.0: the DAG streams" in run_cli("info", svdag).stdout
    archive = tmp_path / "archive.svdag"
    run_json("compress", path, "-o", archive, "--format-version", "3")
    assert run_json("info", archive)["file_format"] == "3.0"
    for key in ("dims", "labels", "blocks", "dag_nodes", "bytes_total", "dtype", "spacing", "origin"):
        assert info[key] == compressed[key], key

    out_nrrd = tmp_path / "out.nrrd"
    result = run_json("decompress", svdag, "-o", out_nrrd)
    assert result["dims"] == list(labels.shape) and result["file_bytes"] == os.path.getsize(out_nrrd)
    data, header = nrrd.read(str(out_nrrd))
    assert data.dtype == np.int16
    np.testing.assert_array_equal(data, labels)
    assert header["encoding"] == "gzip"
    np.testing.assert_allclose(header["space directions"], np.diag([0.5, 0.75, 2.0]))
    np.testing.assert_allclose(header["space origin"], [-4.0, 1.0, 10.0])

    out_npy = tmp_path / "out.npy"
    run_json("decompress", svdag, "-o", out_npy)
    np.testing.assert_array_equal(np.load(out_npy), labels)  # documented order [x, y, z]

    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOXML import vtkXMLImageDataReader

    out_vti = tmp_path / "out.vti"
    run_json("decompress", svdag, "-o", out_vti)
    reader = vtkXMLImageDataReader()
    reader.SetFileName(str(out_vti))
    reader.Update()
    image = reader.GetOutput()
    assert image.GetDimensions() == labels.shape and image.GetSpacing() == (0.5, 0.75, 2.0)
    decoded = vtk_to_numpy(image.GetPointData().GetArray("Labels")).reshape(labels.shape, order="F")
    np.testing.assert_array_equal(decoded, labels)

    human = run_cli("decompress", svdag, "-o", tmp_path / "again.nrrd")
    assert human.returncode == 0 and "out.nrrd" not in human.stdout and "again.nrrd" in human.stdout


def test_compress_with_background_and_exclusions(small_nrrd, tmp_path):
    path, labels = small_nrrd
    svdag = tmp_path / "excl.svdag"
    stats = run_json("compress", path, "-o", svdag, "--background", "-3", "--exclude", "9", "2")
    kept = labels[~np.isin(labels, [-3, 9, 2])]
    assert stats["labels"] == len(np.unique(kept)) and stats["background"] == -3
    out = tmp_path / "excl.npy"
    run_json("decompress", svdag, "-o", out)
    np.testing.assert_array_equal(np.load(out), np.where(np.isin(labels, [9, 2]), -3, labels))


def test_shared_volume_round_trip(shared_data, tmp_path):
    source = shared_data / "fib25_64.nrrd"
    expected, _ = nrrd.read(str(source))
    svdag = tmp_path / "fib25.svdag"
    stats = run_json("compress", source, "-o", svdag)
    assert stats["dims"] == [64, 64, 64] and stats["dtype"] == "uint64"
    assert stats["labels"] == len(np.unique(expected[expected != 0]))
    assert stats["bits_per_voxel"] == pytest.approx(8 * stats["bytes_total"] / 64**3)
    out = tmp_path / "fib25.nhdr"
    run_json("decompress", svdag, "-o", out)
    data, _ = nrrd.read(str(out))
    assert data.dtype == np.uint64
    np.testing.assert_array_equal(data, expected)


def test_usage_errors_exit_2(tmp_path):
    assert_one_line_error(run_cli(), 2, "required: COMMAND")
    assert_one_line_error(run_cli("frobnicate"), 2, "invalid choice")
    assert_one_line_error(run_cli("compress", "in.nrrd"), 2, "-o/--output")
    assert_one_line_error(run_cli("compress", "in.nrrd", "-o", "x.svdag", "--level", "abc"), 2, "--level")
    assert_one_line_error(run_cli("decompress", "in.svdag", "-o", tmp_path / "x.png"), 2, "unsupported format")
    assert_one_line_error(run_cli("info", "in.nrrd", "--background", "1.5"), 2, "--background")


def test_bad_files_exit_1(tmp_path, small_nrrd):
    assert_one_line_error(run_cli("info", tmp_path / "missing.nrrd"), 1, "No such file")
    assert_one_line_error(run_cli("info", tmp_path), 1, "directory")
    text = tmp_path / "notes.nrrd"
    text.write_text("this is not a volume\n")
    assert_one_line_error(run_cli("info", text), 1, "notes.nrrd")
    floats = tmp_path / "floats.nrrd"
    nrrd.write(str(floats), np.zeros((4, 4, 4), np.float32), header={"encoding": "raw"})
    assert_one_line_error(run_cli("info", floats), 1, "float")
    # a truncated gzip NRRD
    path, _ = small_nrrd
    truncated = tmp_path / "truncated.nrrd"
    truncated.write_bytes(path.read_bytes()[: os.path.getsize(path) // 2])
    assert_one_line_error(run_cli("info", truncated), 1, "truncated.nrrd")
    # an unwritable output
    assert_one_line_error(run_cli("compress", path, "-o", tmp_path / "no" / "such" / "dir.svdag"), 1, "dir.svdag")


def test_bad_svdag_files_exit_1(tmp_path, small_nrrd):
    path, _ = small_nrrd
    svdag = tmp_path / "good.svdag"
    run_json("compress", path, "-o", svdag)
    data = svdag.read_bytes()
    truncated = tmp_path / "truncated.svdag"
    truncated.write_bytes(data[: len(data) // 2])
    assert_one_line_error(run_cli("decompress", truncated, "-o", tmp_path / "t.npy"), 1, "truncated.svdag")
    assert not (tmp_path / "t.npy").exists()
    corrupt = bytearray(data)
    corrupt[len(corrupt) // 2] ^= 0xFF
    bad = tmp_path / "corrupt.svdag"
    bad.write_bytes(bytes(corrupt))
    assert_one_line_error(run_cli("info", bad), 1, "corrupt.svdag")


def test_progress_bar_only_on_a_terminal(small_nrrd):
    """With stderr a terminal the bar is drawn; --no-progress and --json turn it off."""
    import pty

    path, _ = small_nrrd

    def stderr_on_a_tty(*args):
        leader, follower = pty.openpty()
        try:
            process = subprocess.run(
                [sys.executable, "-m", "vtksvdag", *map(str, args)],
                stdout=subprocess.PIPE, stderr=follower, timeout=120, check=False,
            )
        finally:
            os.close(follower)
        chunks = []
        try:
            while True:
                try:
                    chunk = os.read(leader, 4096)
                except OSError:  # EIO: the other end is closed and everything was read
                    break
                if not chunk:
                    break
                chunks.append(chunk)
        finally:
            os.close(leader)
        assert process.returncode == 0
        return b"".join(chunks).decode()

    drawn = stderr_on_a_tty("info", path)
    assert "read [" in drawn and "100%" in drawn
    assert stderr_on_a_tty("info", path, "--no-progress") == ""
    assert stderr_on_a_tty("info", path, "--json") == ""


@pytest.fixture(scope="module")
def uint8_nrrd(tmp_path_factory):
    labels = (np.arange(6 * 5 * 4) % 7).astype(np.uint8).reshape(6, 5, 4)
    path = tmp_path_factory.mktemp("cli_u8") / "u8.nrrd"
    nrrd.write(str(path), labels, index_order="F")
    return path, labels


@pytest.mark.parametrize(
    "args, match",
    [
        (["--level", "23"], "argument --level: must be in 0..22, got 23"),
        (["--level", "-1"], "argument --level: must be in 0..22, got -1"),
        (["--level", "100"], "argument --level: must be in 0..22"),
        (["--background", str(2**64)], "argument --background: must be in"),
        (["--background", str(-(2**63) - 1)], "argument --background: must be in"),
        (["--exclude", "1", str(2**64)], "argument --exclude: must be in"),
        (["--background", "nan"], "argument --background: must be an integer"),
    ],
)
def test_compress_numeric_options_are_range_checked(uint8_nrrd, tmp_path, args, match):
    path, _ = uint8_nrrd
    out = tmp_path / "x.svdag"
    assert_one_line_error(run_cli("compress", path, "-o", out, *args), 2, match)
    assert not out.exists()


@pytest.mark.parametrize("command", ["compress", "info"])
@pytest.mark.parametrize(
    "args, match",
    [
        (["--background", "300"], "argument --background: 300 is out of range for the labels of"),
        (["--background", "-1"], "argument --background: -1 is out of range"),
        (["--exclude", "2", "256"], "argument --exclude: 256 is out of range"),
    ],
)
def test_labels_outside_the_files_dtype_exit_2(uint8_nrrd, tmp_path, command, args, match):
    path, _ = uint8_nrrd
    out = tmp_path / "x.svdag"
    extra = ["-o", out] if command == "compress" else []
    result = run_cli(command, path, *extra, *args)
    assert_one_line_error(result, 2, match)
    assert "uint8: 0..255" in result.stderr and "u8.nrrd" in result.stderr
    assert not out.exists()
    # the extremes of the dtype are accepted
    ok = run_cli(command, path, *extra, "--background", "255", "--exclude", "0", "--json")
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["background"] == 255


@pytest.mark.parametrize("name", ["x.nrrd", "x.npy", "x.vti", "x.svdag.gz", "x"])
def test_compress_refuses_an_output_that_is_not_svdag(uint8_nrrd, tmp_path, name):
    path, _ = uint8_nrrd
    result = run_cli("compress", path, "-o", tmp_path / name)
    suffix = os.path.splitext(name)[1]
    assert_one_line_error(result, 2, "argument -o/--output")
    assert (f"suffix '{suffix}'" if suffix else "no suffix") in result.stderr
    assert "compress writes .svdag files" in result.stderr
    assert not (tmp_path / name).exists()
    # any case of .svdag is fine
    assert run_cli("compress", path, "-o", tmp_path / "X.SVDAG").returncode == 0


def test_dataset_for_a_file_that_is_not_hdf5(uint8_nrrd):
    path, _ = uint8_nrrd
    assert_one_line_error(run_cli("info", path, "--dataset", "labels"), 1, "only for HDF5")

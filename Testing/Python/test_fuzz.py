"""Fuzzing of every volume reader and the .svdag loader (Testing/fuzz/fuzz_readers.py).

- every input in Testing/fuzz/crashes/ (each a crash, hang or silently wrong volume the fuzzer
  once found) is replayed in a child process: it must now be rejected cleanly or read right;
- the seeds of every target are read right (the harness's own checks hold on valid files);
- a bounded atheris campaign over all targets (VTKSVDAG_FUZZ_SECONDS, default 60 s in all)
  finds nothing. scripts/fuzz.sh runs longer campaigns.
"""
import json
import os
import pathlib
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
FUZZ = REPO / "Testing" / "fuzz"
HARNESS = FUZZ / "fuzz_readers.py"
CRASHES = sorted(p for p in (FUZZ / "crashes").glob("*") if p.is_file() and p.name != "README.md")
sys.path.insert(0, str(FUZZ))

from fuzz_readers import TARGETS  # noqa: E402


def replay(target, paths, workdir, timeout=120):
    return subprocess.run(
        [sys.executable, str(HARNESS), "--target", target, "--workdir", str(workdir),
         "--replay", *map(str, paths)],
        capture_output=True, text=True, timeout=timeout)


def test_sanitized_build_is_the_one_loaded():
    """Under scripts/sanitize.sh the wrapped modules must come from the sanitized build."""
    expected = os.environ.get("VTKSVDAG_EXPECT_BUILD")
    if not expected:
        pytest.skip("not a sanitizer run")
    import vtksvdag.vtkSVDAGIO

    assert vtksvdag.vtkSVDAGIO.__file__.startswith(os.path.join(expected, "python", ""))


@pytest.mark.parametrize("path", CRASHES, ids=[p.name for p in CRASHES])
def test_crash_regressions(path, tmp_path):
    """A regression input, named <target>--<what>: a clean error or the right volume."""
    target = path.name.split("--")[0]
    assert target in TARGETS, f"{path.name}: name it <target>--<what>, target one of {list(TARGETS)}"
    result = replay(target, [path], tmp_path)
    assert result.returncode == 0, (
        f"{path.name}: exit status {result.returncode}\n{result.stdout}\n{result.stderr[-6000:]}")


@pytest.mark.parametrize("target", list(TARGETS))
def test_seeds_read_right(target, tmp_path):
    seeds = tmp_path / "seeds"
    subprocess.run([sys.executable, str(HARNESS), "--target", target, "--write-seeds", str(seeds)],
                   check=True, timeout=120)
    result = replay(target, sorted(seeds.iterdir()), tmp_path)
    assert result.returncode == 0, result.stderr[-6000:]
    stats = json.loads(result.stdout.strip().splitlines()[-1])
    assert stats["accepted"] == stats["inputs"] > 0
    assert stats["accepted_exact_checked"] == stats["inputs"]
    assert stats["soft"] == 0


def test_harness_catches_a_silently_wrong_volume(tmp_path):
    """The check itself: a NRRD whose raw body says other voxels than the reader gives must be
    flagged. Simulated by replaying a raw NRRD against the gzip target's expectations."""
    from fuzz_readers import _nrrd_header, seed_volumes

    volume = seed_volumes()["b"]
    header = _nrrd_header(volume, "gzip")
    import gzip

    body = bytearray(volume.tobytes())
    body[100] ^= 1
    bad = tmp_path / "flipped.nrrd"
    bad.write_bytes(header + gzip.compress(bytes(body), mtime=0))  # valid gzip, other voxels
    result = replay("nrrd_gzip", [bad], tmp_path)
    assert result.returncode != 0 and "SilentWrongVolume" in result.stderr


def test_bounded_campaign(tmp_path):
    """About 60 s of atheris over every target (VTKSVDAG_FUZZ_SECONDS): no finding."""
    import atheris  # noqa: F401 (Python/requirements.txt; setup.sh installs it)
    seconds = float(os.environ.get("VTKSVDAG_FUZZ_SECONDS", "60"))
    out = tmp_path / "campaign"
    result = subprocess.run(
        [sys.executable, str(FUZZ / "campaign.py"), "--seconds", str(seconds), "--out", str(out)],
        capture_output=True, text=True, timeout=seconds + 600)
    print(result.stdout)
    summary = json.loads((out / "summary.json").read_text())
    assert {s["target"] for s in summary} == set(TARGETS)
    assert all(s["inputs"] > 0 for s in summary), result.stdout
    findings = [f for s in summary for f in s["findings"]]
    details = ""
    for f in findings[:3]:
        log = pathlib.Path(str(f) + ".log")
        if log.exists():
            details += f"\n--- {f}\n" + log.read_text(errors="replace")[-3000:]
    assert not findings, f"the fuzzer found {len(findings)} inputs:\n{result.stdout}{details}"

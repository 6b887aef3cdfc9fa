"""One Vulkan device per process: eight volumes in two render windows (four viewports each)
share one device, the process's threads grow by one device's worth, and every volume renders
what it renders alone.

The references are independent processes: each volume rendered alone in a process of its own
(device_sharing.py), compared exactly for labels (picked at every pixel) and window depth, and
within 1/255 for color; the thread counts come from /proc/self/task. The eight-volume scene also
runs in a fresh process, so that no other test's renderers share (or keep) its device.
"""
import os
import subprocess
import sys

import numpy as np
import pytest

import device_sharing

HERE = os.path.dirname(os.path.abspath(__file__))


def run_scene(out, *args):
    return subprocess.Popen([sys.executable, os.path.join(HERE, "device_sharing.py"), str(out)]
                            + [str(a) for a in args], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


def finish(process, out):
    output, _ = process.communicate(timeout=600)
    assert process.returncode == 0, output
    return np.load(out)


@pytest.fixture(scope="module")
def renders(tmp_path_factory):
    """(together, [alone 0 .. 7]): the .npz contents of each process."""
    tmp = tmp_path_factory.mktemp("device_sharing")
    together = run_scene(tmp / "together.npz", "together")
    together_result = finish(together, tmp / "together.npz")
    alone = []
    # Two at a time: the machine's cores, and each process's own lavapipe device.
    for first in range(0, device_sharing.COUNT, 2):
        pair = [(run_scene(tmp / ("alone%d.npz" % i), "alone", i), tmp / ("alone%d.npz" % i))
                for i in (first, first + 1)]
        alone += [finish(p, out) for p, out in pair]
    return together_result, alone


def test_eight_volumes_use_one_device(renders):
    together, _ = renders
    assert together["users_before"] == 0
    assert together["users_all"] == device_sharing.COUNT
    ids = {int(together["device%d" % i]) for i in range(device_sharing.COUNT)}
    assert ids == {1}


def test_threads_grow_by_one_devices_worth(renders):
    together, _ = renders
    one = int(together["threads_one"]) - int(together["threads_base"])
    eight = int(together["threads_all"]) - int(together["threads_base"])
    assert one >= 1, "the first volume's device started no thread: nothing to compare"
    # The target: at most 1.2 times one volume's threads (eight devices would be 8x).
    assert eight <= 1.2 * one, (one, eight)


@pytest.mark.parametrize("i", range(device_sharing.COUNT))
def test_each_volume_renders_what_it_renders_alone(renders, i):
    together, alone = renders
    label, depth, color = (together["%s%d" % (k, i)] for k in ("label", "depth", "color"))
    reference = alone[i]
    # The volume's own labels (each volume has others), seen over a good part of its viewport.
    assert set(np.unique(label)) == {0, 10 * i + 1, 10 * i + 2}
    assert (label > 0).mean() > 0.1
    np.testing.assert_array_equal(label, reference["label"])
    np.testing.assert_array_equal(depth, reference["depth"])
    assert np.abs(color.astype(int) - reference["color"].astype(int)).max() <= 1
    # Each mapper's device bytes are its own: what it holds alone.
    assert int(together["bytes%d" % i]) == int(reference["bytes"])


def test_the_device_goes_with_its_last_user(renders):
    together, alone = renders
    assert together["users_released"] == 0
    assert together["users_again"] == 1
    assert together["device_again"] == together["device_first"] + 1
    np.testing.assert_array_equal(together["label_again"], alone[0]["label"])

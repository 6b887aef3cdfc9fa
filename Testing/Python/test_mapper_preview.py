"""The mapper's preview while the path tracer's pipeline compiles (PreviewWhileCompiling): in a
window whose interactor is initialized, the first frame of a new process (nothing compiled) is
the preview, whose labels are the block boxes' (the CPU ray caster at block LOD through the
same pixel centres is the reference); the interactor's timer then renders the path tracer's
frame by itself; a render that must be final (RefineStillRenders' still render) never previews;
with the path tracer's binary kept on disk by an earlier process, the first frame is the path
tracer's. Each case runs in a new process with its own cache directory (XDG_CACHE_HOME), so that
its Vulkan device has compiled nothing."""
import os
import subprocess
import sys
import textwrap

import pytest

from conftest import REPO

SCRIPT = textwrap.dedent("""
    import sys, time
    import numpy as np
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401
    from vtkmodules.vtkRenderingCore import (vtkRenderer, vtkRenderWindow,
                                             vtkRenderWindowInteractor, vtkVolume)
    import vtksvdag
    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper
    final = sys.argv[1] == "final"
    labels = np.zeros((40, 36, 30), np.uint16)
    x, y, z = np.meshgrid(np.arange(40), np.arange(36), np.arange(30), indexing="ij")
    labels[3:37, 3:33, 3:27] = (1 + (x // 9 + y // 12 + z // 7) % 4)[3:37, 3:33, 3:27]
    seg = vtksvdag.from_numpy(labels)
    mapper = vtkSegmentationSVDAGVolumeMapper()
    mapper.SetInputData(seg.dataobject)
    mapper.SetRefineStillRenders(final)
    mapper.GetSettings().SetDenoise(False)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    renderer = vtkRenderer()
    renderer.AddVolume(volume)
    window = vtkRenderWindow()
    # On screen (Xvfb): the X interactor's timers fire in its event processing.
    window.SetSize(120, 100)
    window.AddRenderer(renderer)
    interactor = vtkRenderWindowInteractor()
    interactor.SetRenderWindow(window)
    interactor.Initialize()
    renderer.ResetCamera()
    renderer.GetActiveCamera().Azimuth(30)
    renderer.GetActiveCamera().Elevation(20)
    renderer.ResetCameraClippingRange()
    window.SetDesiredUpdateRate(interactor.GetStillUpdateRate() if final else 5.0)
    window.Render()
    first = mapper.GetLastFramePreviewed()
    picks = []
    for y in range(5, 100, 9):
        for x in range(5, 120, 9):
            picks.append((x, y, mapper.Pick(renderer, x + 0.5, y + 0.5), mapper.GetPickedLabel()))
    print("FIRST", int(first), int(mapper.IsConverged()))
    # The interactor's timer renders again until the full pipeline is ready: its event loop runs
    # until then (or for 120 s of previews; a loop whose timer never fires ends with the
    # caller's timeout).
    renders = [0]
    start = time.time()
    def ended(*args):
        renders[0] += 1
        if not mapper.GetLastFramePreviewed() or time.time() - start > 120:
            interactor.TerminateApp()
    if first:
        window.AddObserver("EndEvent", ended)
        interactor.Start()
    print("LATER", int(mapper.GetLastFramePreviewed()), renders[0])
    # The preview's picks against the block LOD's (the path tracer at block LOD, same pixels).
    mapper.GetSettings().SetLODToBlock()
    window.SetDesiredUpdateRate(interactor.GetStillUpdateRate())
    mapper.RefineStillRendersOn()
    window.Render()
    same = total = 0
    for x, y, hit, label in picks:
        hit2 = mapper.Pick(renderer, x + 0.5, y + 0.5)
        total += 1
        same += hit == hit2 and (not hit or label == mapper.GetPickedLabel())
    print("PICKS", same, total, sum(1 for p in picks if p[2]))
    """)


def run(mode, cache_home):
    env = dict(os.environ, XDG_CACHE_HOME=str(cache_home))
    env.pop("VTKSVDAG_PIPELINE_CACHE", None)
    result = subprocess.run([sys.executable, "-c", SCRIPT, mode], capture_output=True, text=True,
                            timeout=300, cwd=str(REPO), env=env)
    assert result.returncode == 0, result.stderr[-3000:]
    return {line.split()[0]: [int(v) for v in line.split()[1:]]
            for line in result.stdout.splitlines() if line.split() and line.split()[0].isupper()}


def test_preview_then_the_path_tracer_by_the_interactors_timer(tmp_path):
    out = run("interactive", tmp_path)
    previewed, converged = out["FIRST"]
    assert previewed == 1 and converged == 0
    still_previewed, renders = out["LATER"]
    assert still_previewed == 0 and renders >= 1  # rendered by the timer, not by this script
    same, total, hits = out["PICKS"]
    assert hits > total // 4
    assert same == total


def test_a_final_render_never_previews(tmp_path):
    out = run("final", tmp_path)
    assert out["FIRST"][0] == 0


@pytest.mark.skipif(bool(os.environ.get("SVDAG_VK_NO_SHADER_OBJECTS")),
                    reason="compute shaders are pipelines here (SVDAG_VK_NO_SHADER_OBJECTS): no "
                    "binaries are kept, so every new process previews")
def test_a_warm_start_shows_the_path_tracer_at_once(tmp_path):
    """The path tracer's binary, kept by the first process (shader objects, as lavapipe has),
    is created at once by the next: its first interactive frame is no preview."""
    cold = run("interactive", tmp_path)
    assert cold["FIRST"][0] == 1
    assert list((tmp_path / "vtksvdag").glob("shader-*.bin"))
    warm = run("interactive", tmp_path)
    assert warm["FIRST"] == [0, 0] and warm["LATER"] == [0, 0]
    assert warm["PICKS"][2] > warm["PICKS"][1] // 4  # it hit the volume

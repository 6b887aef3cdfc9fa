"""How the volume mapper's traced color and the depth move between OpenGL and Vulkan: through
memory shared with Vulkan (VK_KHR_external_memory_fd imported with GL_EXT_memory_object_fd) or
through the host.

The host path is the reference (the regression images and the depth tests of test_mapper.py
check it): the shared path must draw exactly the same pixels and depth, at full and at reduced
resolution, after a resize (a new allocation, imported again) and when switched at run time.
Whether it can run is decided from the window's OpenGL extensions and the devices' UUIDs; on
Mesa (lavapipe with llvmpipe, as in CI) both exist and match, so the shared path must run there.
The depth has a shared path of its own (the scene depth read into Vulkan memory, ray limits and
written depth computed by a compute pass in double precision): it must give the host path's bits
too, and a change of the scene depth between frames must still restart the refinement.
"""
import numpy as np
import pytest
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL factory overrides)
from conftest import compress_zyx, mapper_scene, tilted_slab, two_boxes
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

W, H = 160, 120



@pytest.fixture(scope="module")
def svdag():
    return compress_zyx(two_boxes())


def scene(svdag, shared, size=(W, H), shared_depth=True):
    window, renderer, volume, mapper = mapper_scene(svdag, size=size)
    window.SetMultiSamples(0)
    mapper.SetSharedMemory(shared)
    mapper.SetSharedDepth(shared_depth)
    mapper.SetTargetSamplesPerPixel(3)
    # A tilted slab through the volume: scene depth in, composited depth out.
    renderer.AddActor(tilted_slab())
    return window, renderer, volume, mapper


def capture(window):
    width, height = window.GetSize()
    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGBA()
    grab.ReadFrontBufferOff()
    grab.ShouldRerenderOff()
    grab.Update()
    color = vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars()).reshape(height, width, 4)
    depth = vtkFloatArray()
    window.GetZbufferData(0, 0, width - 1, height - 1, depth)
    return color.copy(), vtk_to_numpy(depth).reshape(height, width).copy()


def mesa_interop(window):
    """Whether this window's OpenGL lists GL_EXT_memory_object_fd and is Mesa's llvmpipe, whose
    Vulkan twin (lavapipe) is the device the renderer picks on a machine without a GPU."""
    capabilities = window.ReportCapabilities()
    return "GL_EXT_memory_object_fd" in capabilities and "llvmpipe" in capabilities


def require_interop(window):
    """Skips unless the window (rendered once: its capabilities need a context) can import."""
    if not mesa_interop(window):
        pytest.skip("this OpenGL cannot import the Vulkan device's memory (no GL_EXT_memory_object_fd "
                    "on Mesa's llvmpipe): the shared depth path cannot run here")


def slab_of(renderer):
    return renderer.GetActors().GetLastActor()


def assert_same(shared_capture, host_capture):
    (color_s, depth_s), (color_h, depth_h) = shared_capture, host_capture
    assert np.array_equal(color_s, color_h), np.argwhere(np.any(color_s != color_h, axis=-1))[:5]
    assert np.array_equal(depth_s, depth_h)


def test_shared_and_host_paths_draw_the_same_pixels(svdag):
    shared = scene(svdag, True)
    host = scene(svdag, False)
    captures = {}
    for name, (window, _, _, mapper) in (("shared", shared), ("host", host)):
        assert mapper.GetSharedMemory() == (name == "shared")
        assert mapper.GetCompositePath() == ""  # before a frame
        assert mapper.RenderUntilConverged(window, 60.0) > 0
        assert mapper.GetAccumulatedSamples() == 3
        captures[name] = capture(window)
    expected = "shared memory" if mesa_interop(shared[0]) else "host"
    assert shared[3].GetCompositePath() == expected
    assert host[3].GetCompositePath() == "host"
    # Something of each was drawn: both labels' boxes, the mesh in front of part of them.
    color, depth = captures["host"]
    assert (depth < 1).sum() > 0.2 * W * H
    green = (color[..., 1] > 200) & (color[..., 0] < 60) & (color[..., 2] < 60)
    assert 100 < green.sum() < 0.8 * W * H
    assert_same(captures["shared"], captures["host"])
    # The copy time is part of the frame's.
    for _, _, _, mapper in (shared, host):
        assert 0 < mapper.GetLastCopyMilliseconds() < mapper.GetLastFrameMilliseconds()


def test_reduced_frames_and_resizes_draw_the_same_pixels(svdag):
    """Interactive frames (a reduced image scaled up by the shader's bilinear filter) and a new
    window size (the renderer allocates new outputs: imported again) agree too."""
    shared = scene(svdag, True)
    host = scene(svdag, False)
    for window, renderer, volume, mapper in (shared, host):
        mapper.GetSettings().SetLODToVoxel()
        window.Render()
    for step in range(2):
        captures = []
        for window, renderer, volume, mapper in (shared, host):
            if step == 1:
                window.SetSize(W + 37, H + 23)
            # A short budget: the frame after the first one is traced reduced.
            window.SetDesiredUpdateRate(1000.0)
            renderer.GetActiveCamera().Azimuth(3.0)
            window.Render()
            renderer.GetActiveCamera().Azimuth(3.0)
            window.Render()
            captures.append((mapper.GetLastReductionFactor(), capture(window)))
        (reduction_s, shared_capture), (reduction_h, host_capture) = captures
        assert reduction_s == reduction_h
        if step == 0:
            assert reduction_s > 1
        assert shared[3].GetDepthPath() == ("shared memory" if mesa_interop(shared[0]) else "host")
        assert_same(shared_capture, host_capture)


def test_switching_paths_at_run_time(svdag):
    window, renderer, volume, mapper = scene(svdag, True)
    mapper.RenderUntilConverged(window, 60.0)
    first = capture(window)
    path = mapper.GetCompositePath()
    mapper.SharedMemoryOff()
    window.Render()  # the color moves to host memory: traced again, refinement restarted
    assert mapper.GetCompositePath() == "host"
    assert mapper.GetAccumulatedSamples() == 1
    mapper.RenderUntilConverged(window, 60.0)
    assert_same(capture(window), first)
    mapper.SharedMemoryOn()
    mapper.RenderUntilConverged(window, 60.0)
    assert mapper.GetCompositePath() == path
    assert_same(capture(window), first)
    # Released and drawn again (a new OpenGL import; the window's mesh is drawn anew too, which
    # restarts the refinement on either path).
    volume.ReleaseGraphicsResources(window)
    renderer.ReleaseGraphicsResources(window)
    mapper.RenderUntilConverged(window, 60.0)
    assert mapper.GetCompositePath() == path
    assert_same(capture(window), first)


def test_two_mappers_in_one_window_share_one_path(svdag):
    """Two volumes, one window: each imports its own renderer's output."""
    from vtkmodules.vtkRenderingCore import vtkVolume

    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper

    window, renderer, volume, mapper = scene(svdag, True)
    other = vtkSegmentationSVDAGVolumeMapper()
    other.SetInputData(svdag)
    other.SetTargetSamplesPerPixel(3)
    moved = vtkVolume()
    moved.SetMapper(other)
    moved.SetPosition(45, 0, 0)
    renderer.AddVolume(moved)
    renderer.ResetCamera()
    for m in (mapper, other):
        m.SetSharedMemory(True)
    mapper.RenderUntilConverged(window, 60.0)
    shared_capture = capture(window)
    assert mapper.GetCompositePath() == other.GetCompositePath() != ""
    for m in (mapper, other):
        m.SetSharedMemory(False)
    mapper.RenderUntilConverged(window, 60.0)
    other.RenderUntilConverged(window, 60.0)
    assert mapper.GetCompositePath() == other.GetCompositePath() == "host"
    assert_same(shared_capture, capture(window))


def test_shared_depth_path_gives_the_host_paths_bits(svdag):
    """With the mesh cutting through the volume (in front of it here, behind it there), the depth
    through shared memory (ray limits and written depth computed on the device) draws the same
    pixels and writes the same z-buffer as the host's arithmetic, with the color shared or not."""
    scenes = {"shared": scene(svdag, True), "shared color": scene(svdag, True, shared_depth=False),
              "host": scene(svdag, False)}
    captures = {}
    for name, (window, _, _, mapper) in scenes.items():
        assert mapper.GetDepthPath() == ""  # before a frame
        assert mapper.RenderUntilConverged(window, 60.0) > 0
        assert mapper.GetAccumulatedSamples() == 3
        captures[name] = capture(window)
    require_interop(scenes["shared"][0])
    paths = {name: (m.GetCompositePath(), m.GetDepthPath()) for name, (_, _, _, m) in scenes.items()}
    assert paths == {"shared": ("shared memory", "shared memory"),
                     "shared color": ("shared memory", "host"), "host": ("host", "host")}
    # The mesh alone covers `slab`; of that, the mesh is seen in front of the volume somewhere
    # (green) and behind it elsewhere (the volume's hits, written over the mesh's depth).
    window, renderer, volume, mapper = scenes["host"]
    volume.VisibilityOff()
    window.Render()
    slab = capture(window)[1] < 1
    volume.VisibilityOn()
    color, depth = captures["host"]
    green = (color[..., 1] > 200) & (color[..., 0] < 60) & (color[..., 2] < 60)
    assert (slab & green).sum() > 100
    assert (slab & ~green & (depth < 1)).sum() > 100
    assert_same(captures["shared"], captures["host"])
    assert_same(captures["shared color"], captures["host"])


def test_a_moved_mesh_restarts_the_shared_depth_path(svdag):
    """The frame's identity compares the scene depth through the mappings of the two scene depth
    buffers: the same depth keeps the refined image (no trace), a moved mesh traces anew, and
    what it draws is the host path's."""
    shared, host = scene(svdag, True), scene(svdag, False)
    for window, _, _, mapper in (shared, host):
        mapper.RenderUntilConverged(window, 60.0)
        require_interop(shared[0])
        window.Render()  # the same depth read again, into the other buffer on the shared path
        assert mapper.GetAccumulatedSamples() == 3 and mapper.GetLastTraceMilliseconds() == 0
    # Twice: each of the two buffers holds the accumulating frame's depth once.
    for step in range(2):
        captures = []
        for window, renderer, _, mapper in (shared, host):
            slab_of(renderer).AddPosition(0, 0, 3)
            window.Render()
            assert mapper.GetAccumulatedSamples() == 1 and mapper.GetLastTraceMilliseconds() > 0
            assert mapper.RenderUntilConverged(window, 60.0) > 0
            assert mapper.GetAccumulatedSamples() == 3
            captures.append(capture(window))
        assert shared[3].GetDepthPath() == "shared memory"
        assert_same(*captures)

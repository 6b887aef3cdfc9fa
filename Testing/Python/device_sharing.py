"""Scenes for test_device_sharing.py and bench/devices.py: eight small volumes, each alone in a
window, or four per window (one per quarter viewport) in two windows of one process.

Run as a script it writes what it rendered to an .npz file (``python device_sharing.py OUT
alone I`` or ``python device_sharing.py OUT together``): per volume, the label image (picked at
every pixel center), the window depth and the RGBA color of its viewport, the mapper's device
bytes and device id; and the process's thread counts before and after the volumes' first frames.
"""
import gc
import os
import sys
import time

import numpy as np

COUNT = 8
W, H = 64, 48  # one viewport
CAMERA = ((80, -60, 90), (20, 20, 20), (0, 0, 1))


def threads():
    """Threads of this process now (the entries of /proc/self/task)."""
    return len(os.listdir("/proc/self/task"))


def labels(i, n=40):
    """Volume i: two boxes whose place and size depend on i, labels 10 i + 1 and 10 i + 2, so that
    each volume's label image is its own."""
    volume = np.zeros((n, n, n), np.uint16)
    a = 3 + i
    volume[a:a + 15, 8:30 - i, 10:25] = 10 * i + 1
    volume[15:35 - i, 12 + i:25, 20:38] = 10 * i + 2
    return volume


def compress(i):
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData

    zyx = labels(i)
    image = vtkImageData()
    image.SetDimensions(zyx.shape[2], zyx.shape[1], zyx.shape[0])
    image.GetPointData().SetScalars(numpy_to_vtk(np.ascontiguousarray(zyx).ravel(), deep=True))
    from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG

    builder = vtkImageDataToSegmentationSVDAG()
    builder.SetInputData(image)
    builder.Update()
    return builder.GetOutput()


def add_volume(window, svdag, viewport):
    """A renderer over `viewport` of `window` with one volume drawn by the SVDAG mapper and the
    fixed camera: (renderer, volume, mapper)."""
    from vtkmodules.vtkRenderingCore import vtkRenderer, vtkVolume
    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper

    mapper = vtkSegmentationSVDAGVolumeMapper()
    mapper.SetInputData(svdag)
    mapper.GetSettings().SetSamplesPerPixel(1)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    renderer = vtkRenderer()
    renderer.SetViewport(*viewport)
    renderer.AddVolume(volume)
    window.AddRenderer(renderer)
    camera = renderer.GetActiveCamera()
    camera.SetPosition(*CAMERA[0])
    camera.SetFocalPoint(*CAMERA[1])
    camera.SetViewUp(*CAMERA[2])
    camera.SetClippingRange(20.0, 300.0)
    return renderer, volume, mapper


def make_window(width, height):
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL factory overrides)
    from vtkmodules.vtkRenderingCore import vtkRenderWindow

    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(width, height)
    return window


def grab(window, renderer, mapper):
    """(label, depth, rgba) of the renderer's viewport, rows from the bottom: the picked label
    value at every pixel center (0: none), the window depth and the RGBA8 color."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkFloatArray, vtkUnsignedCharArray

    x0, y0 = renderer.GetOrigin()
    w, h = renderer.GetSize()
    label = np.zeros((h, w), np.int64)
    for y in range(h):
        for x in range(w):
            if mapper.Pick(renderer, x0 + x + 0.5, y0 + y + 0.5):
                label[y, x] = mapper.GetPickedLabel()
    depth = vtkFloatArray()
    window.GetZbufferData(x0, y0, x0 + w - 1, y0 + h - 1, depth)
    color = vtkUnsignedCharArray()
    window.GetRGBACharPixelData(x0, y0, x0 + w - 1, y0 + h - 1, 0, color)
    return (label, vtk_to_numpy(depth).reshape(h, w).copy(),
            vtk_to_numpy(color).reshape(h, w, 4).copy())


QUARTERS = [(0, 0, 0.5, 0.5), (0.5, 0, 1, 0.5), (0, 0.5, 0.5, 1), (0.5, 0.5, 1, 1)]


def together(volumes=None):
    """Eight volumes, four per window in two windows, in this process. Returns the per-volume
    images and figures, the thread counts (windows drawn without any volume: `base`; after
    the first volume's first frame: `one`; after all eight: `all`) and the setup seconds of the
    first volume and of all eight."""
    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper

    volumes = volumes if volumes is not None else [compress(i) for i in range(COUNT)]
    windows = [make_window(2 * W, 2 * H) for _ in range(2)]
    scenes = []
    for i, svdag in enumerate(volumes):
        window = windows[i // 4]
        renderer, volume, mapper = add_volume(window, svdag, QUARTERS[i % 4])
        volume.VisibilityOff()  # no device until the volumes are drawn
        scenes.append((window, renderer, volume, mapper))
    for window in windows:
        window.Render()  # the OpenGL contexts and their threads exist before any device
    result = {"users_before": vtkSegmentationSVDAGVolumeMapper.GetDeviceUsers(),
              "threads_base": threads()}
    # The first volume's first frame, from another camera position: the frame below, from the
    # fixed one, starts a new accumulation, so that every volume is compared after one frame.
    first_camera = scenes[0][1].GetActiveCamera()
    first_camera.SetPosition(70, -60, 90)
    start = time.perf_counter()
    scenes[0][2].VisibilityOn()
    windows[0].Render()
    result["seconds_one"] = time.perf_counter() - start
    result["threads_one"] = threads()
    first_camera.SetPosition(*CAMERA[0])
    start = time.perf_counter()
    for scene in scenes:
        scene[2].VisibilityOn()
    for window in windows:
        window.Render()
    result["seconds_all"] = result["seconds_one"] + time.perf_counter() - start
    result["threads_all"] = threads()
    result["users_all"] = vtkSegmentationSVDAGVolumeMapper.GetDeviceUsers()
    for i, (window, renderer, volume, mapper) in enumerate(scenes):
        result["label%d" % i], result["depth%d" % i], result["color%d" % i] = grab(
            window, renderer, mapper)
        result["bytes%d" % i] = mapper.GetDeviceBytes()
        result["device%d" % i] = mapper.GetDeviceId()
    # The device goes with its last user, and a later user creates a new one.
    first_id = scenes[0][3].GetDeviceId()
    del scenes, scene, windows, window, renderer, volume, mapper, first_camera
    gc.collect()
    result["users_released"] = vtkSegmentationSVDAGVolumeMapper.GetDeviceUsers()
    result["threads_released"] = threads()
    window = make_window(W, H)
    renderer, volume, mapper = add_volume(window, volumes[0], (0, 0, 1, 1))
    window.Render()
    result["users_again"] = vtkSegmentationSVDAGVolumeMapper.GetDeviceUsers()
    result["device_again"] = mapper.GetDeviceId()
    result["device_first"] = first_id
    result["label_again"] = grab(window, renderer, mapper)[0]
    return result


def alone(i):
    """Volume i alone in a window of one viewport's size, in this process."""
    window = make_window(W, H)
    renderer, volume, mapper = add_volume(window, compress(i), (0, 0, 1, 1))
    base = threads()
    start = time.perf_counter()
    window.Render()
    result = {"seconds": time.perf_counter() - start, "threads_base": base, "threads": threads()}
    result["label"], result["depth"], result["color"] = grab(window, renderer, mapper)
    result["bytes"] = mapper.GetDeviceBytes()
    return result


if __name__ == "__main__":
    out, mode = sys.argv[1], sys.argv[2]
    found = together() if mode == "together" else alone(int(sys.argv[3]))
    np.savez(out, **found)

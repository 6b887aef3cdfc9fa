"""Shared fixtures and helpers for the Python test suites (and Testing/Python/extreme_cases.py)."""
import math
import os
import pathlib

import numpy as np
import pytest
from vtkmodules.util.misc import calldata_type
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.util.vtkConstants import VTK_STRING
from vtkmodules.vtkCommonDataModel import vtkImageData

from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG

REPO = pathlib.Path(__file__).resolve().parents[2]
# The real segmentation volumes: ../shared/data next to the repository, or wherever the
# environment variable VTKSVDAG_SHARED_DATA points (a fresh clone has no ../shared).
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")


def under_ci():
    """True where CI runs the tests (it sets CI=true): there missing shared data is a failure."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


def shared_data_missing_message(path=None):
    path = SHARED_DATA if path is None else path
    return (f"the shared test data {path} is missing (a clone without ../shared/data; "
            f"set VTKSVDAG_SHARED_DATA to its location)")


def require_shared_data(path=None):
    """The shared data folder (or a file in it); skips the calling test when it is missing,
    except under CI (CI=true), where that is a failure."""
    path = SHARED_DATA if path is None else pathlib.Path(path)
    if not path.exists():
        if under_ci():
            pytest.fail(shared_data_missing_message(path) + " under CI")
        pytest.skip(shared_data_missing_message(path))
    return path


def shared_volumes():
    """Names of the real segmentation volumes in the shared data folder (see its README); with
    the folder missing one placeholder name, so that each test parametrized over them still runs
    and skips (or fails under CI) through the shared_data fixture instead of vanishing."""
    if not SHARED_DATA.is_dir():
        return ["shared-data-missing"]
    return sorted(p.name[: -len(".nrrd")] for p in SHARED_DATA.glob("*.nrrd"))


@pytest.fixture(scope="session")
def shared_data():
    return require_shared_data()


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def compress_zyx(labels, spacing=(1, 1, 1), origin=(0, 0, 0), direction=None, excluded=()):
    """A vtkSegmentationSVDAG from a (z, y, x) label array, through the VTK filter."""
    image = vtkImageData()
    image.SetDimensions(labels.shape[2], labels.shape[1], labels.shape[0])
    image.SetSpacing(*spacing)
    image.SetOrigin(*origin)
    if direction is not None:
        image.SetDirectionMatrix(*np.asarray(direction, float).ravel())
    image.GetPointData().SetScalars(numpy_to_vtk(np.ascontiguousarray(labels).ravel(), deep=True))
    builder = vtkImageDataToSegmentationSVDAG()
    builder.SetInputData(image)
    for value in excluded:
        builder.AddExcludedLabel(int(value))
    builder.Update()
    return builder.GetOutput()


def capture_errors(vtk_object):
    """A list that collects the messages of vtk_object's ErrorEvents from now on."""
    messages = []

    @calldata_type(VTK_STRING)
    def on_error(_obj, _event, message):
        messages.append(message)

    vtk_object.AddObserver("ErrorEvent", on_error)
    return messages


# --- Rays and pixels: the renderer's documented pixel-center convention and VTK's display rays.

def primary_rays(renderer):
    """World-space origin and unit directions (pixels in output order) of the rays of a
    vtkSegmentationSVDAGRenderer (GpuLayout.h: pixel (x, y), y = 0 the bottom row, at index
    x + width * y), generated here in double precision from the camera, independently."""
    position = np.array(renderer.GetCameraPosition(), float)
    forward = np.array(renderer.GetCameraFocalPoint(), float) - position
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, renderer.GetCameraViewUp())
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    h = math.tan(math.radians(renderer.GetCameraViewAngle()) / 2)
    width, height = renderer.GetWidth(), renderer.GetHeight()
    x, y = np.meshgrid(np.arange(width), np.arange(height))  # y = 0 first: the bottom row
    u = 2 * (x.ravel() + 0.5) / width - 1
    v = 2 * (y.ravel() + 0.5) / height - 1
    dirs = forward + (u * h * width / height)[:, None] * right + (v * h)[:, None] * up
    return position, dirs / np.linalg.norm(dirs, axis=1, keepdims=True)


def display_to_world(renderer, x, y, z):
    """World point of display point (x, y, z) of a vtkRenderer (z = 0 near plane, 1 far plane)."""
    renderer.SetDisplayPoint(x, y, z)
    renderer.DisplayToWorld()
    p = np.array(renderer.GetWorldPoint(), float)
    return p[:3] / p[3]


def pixel_ray(renderer, x, y):
    """World origin (on the near plane) and direction (to the far plane, not normalized) of the
    ray through display pixel (x, y)'s center, as VTK's own DisplayToWorld computes it."""
    near = display_to_world(renderer, x + 0.5, y + 0.5, 0.0)
    far = display_to_world(renderer, x + 0.5, y + 0.5, 1.0)
    return near, far - near


def mapper_pick(mapper, renderer, x, y):
    """vtkSegmentationSVDAGVolumeMapper.Pick as (label, world position, world normal) or None."""
    if not mapper.Pick(renderer, x, y):
        return None
    position = [0.0] * 3
    normal = [0.0] * 3
    mapper.GetPickedPosition(position)
    mapper.GetPickedNormal(normal)
    return mapper.GetPickedLabel(), np.array(position), np.array(normal)


def caster_pick(caster, origin, direction, to_world=None):
    """The caster's hit as (label, world position, world normal); `to_world` maps model to world."""
    if to_world is None:
        model_origin, model_direction = origin, direction
    else:
        inverse = np.linalg.inv(to_world)
        model_origin = (inverse @ np.append(origin, 1.0))[:3]
        model_direction = inverse[:3, :3] @ direction
    if not caster.CastRay(model_origin, model_direction):
        return None
    label = int(vtk_to_numpy(caster.GetHitLabelValue())[0])
    position = np.array(caster.GetHitPosition())
    normal = np.array(caster.GetHitNormal())
    if to_world is not None:
        position = (to_world @ np.append(position, 1.0))[:3]
        normal = np.linalg.inv(to_world[:3, :3]).T @ normal
        if np.linalg.norm(normal) > 0:
            normal /= np.linalg.norm(normal)
    return label, position, normal


def interior(mask):
    """The pixels of an image mask whose 8 neighbours are all in it too, without the image's
    border: where two layers are composited, the silhouette pixels mix them at sub-pixel level."""
    inner = mask.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner &= np.roll(np.roll(mask, dy, 0), dx, 1)
    inner[[0, -1], :] = False
    inner[:, [0, -1]] = False
    return inner


@pytest.fixture
def plotter():
    """A small off-screen pyvista plotter, closed after the test (skipped without pyvista)."""
    pv = pytest.importorskip("pyvista")
    p = pv.Plotter(off_screen=True, window_size=(64, 48))
    yield p
    p.close()


def two_boxes(n=40):
    """(z, y, x) uint16 labels: two overlapping boxes, labels 3 and 7 (the mapper tests' volume)."""
    labels = np.zeros((n, n, n), np.uint16)
    labels[5:20, 8:30, 10:25] = 3
    labels[15:35, 12:25, 20:38] = 7
    return labels


def mesh_actor(source):
    """A vtkActor drawing a poly data source's output with a vtkPolyDataMapper."""
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

    mesh_mapper = vtkPolyDataMapper()
    mesh_mapper.SetInputConnection(source.GetOutputPort())
    actor = vtkActor()
    actor.SetMapper(mesh_mapper)
    return actor


def tilted_slab():
    """A flat green slab (ambient only) through two_boxes' volume, tilted against its voxel faces:
    the mesh of the depth compositing tests."""
    from vtkmodules.vtkFiltersSources import vtkCubeSource

    cube = vtkCubeSource()
    cube.SetCenter(0, 0, 0)
    cube.SetXLength(60)
    cube.SetYLength(4)
    cube.SetZLength(60)
    actor = mesh_actor(cube)
    actor.SetPosition(22, 18, 20)
    actor.RotateZ(30)
    prop = actor.GetProperty()
    prop.SetColor(0.0, 1.0, 0.0)
    prop.SetAmbient(1.0)
    prop.SetDiffuse(0.0)
    prop.SetSpecular(0.0)
    return actor


def mapper_scene(svdag, camera_position=(80, -60, 90), focal=(20, 20, 20), up=(0, 0, 1),
                 parallel=False, clipping=(20.0, 300.0), size=(200, 150)):
    """An off-screen VTK window with one volume drawn by vtkSegmentationSVDAGVolumeMapper and a
    fixed camera: (window, renderer, volume, mapper)."""
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL factory overrides)
    from vtkmodules.vtkRenderingCore import vtkRenderer, vtkRenderWindow, vtkVolume

    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper

    mapper = vtkSegmentationSVDAGVolumeMapper()
    mapper.SetInputData(svdag)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    renderer = vtkRenderer()
    renderer.AddVolume(volume)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetSize(*size)
    window.AddRenderer(renderer)
    camera = renderer.GetActiveCamera()
    camera.SetPosition(*camera_position)
    camera.SetFocalPoint(*focal)
    camera.SetViewUp(*up)
    if parallel:
        camera.ParallelProjectionOn()
        camera.SetParallelScale(30.0)
    camera.SetClippingRange(*clipping)
    return window, renderer, volume, mapper

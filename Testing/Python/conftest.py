"""Shared fixtures for the Python test suites."""
import pathlib

import numpy as np
import pytest
from vtkmodules.util.misc import calldata_type
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.util.vtkConstants import VTK_STRING
from vtkmodules.vtkCommonDataModel import vtkImageData

from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG

REPO = pathlib.Path(__file__).resolve().parents[2]
SHARED_DATA = REPO.parent / "shared" / "data"


def shared_volumes():
    """Names of the real segmentation volumes in ../shared/data (see its README)."""
    return sorted(p.name[: -len(".nrrd")] for p in SHARED_DATA.glob("*.nrrd"))


@pytest.fixture(scope="session")
def shared_data():
    if not SHARED_DATA.is_dir():
        pytest.fail(f"the shared test data folder {SHARED_DATA} is missing")
    return SHARED_DATA


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

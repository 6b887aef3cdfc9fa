"""The wrapped VTK classes import and interoperate with vtkmodules."""
import numpy as np
from conftest import compress_zyx
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkImageData

from vtksvdag.vtkSVDAGCore import (
    vtkImageDataToSegmentationSVDAG,
    vtkSegmentationSVDAG,
    vtkSegmentationSVDAGToImageData,
)


def test_pipeline_round_trip(rng):
    labels = rng.integers(0, 7, size=(19, 21, 37)).astype(np.int64)  # (z, y, x)
    image = vtkImageData()
    image.SetDimensions(37, 21, 19)
    image.SetSpacing(0.5, 1.0, 2.0)
    image.SetOrigin(-3.0, 4.0, 5.0)
    image.GetPointData().SetScalars(numpy_to_vtk(labels.ravel(), deep=True))
    build = vtkImageDataToSegmentationSVDAG()
    build.SetInputData(image)
    decode = vtkSegmentationSVDAGToImageData()
    decode.SetInputConnection(build.GetOutputPort())
    decode.Update()
    out = decode.GetOutput()
    assert out.GetDimensions() == (37, 21, 19)
    assert out.GetSpacing() == (0.5, 1.0, 2.0)
    assert out.GetOrigin() == (-3.0, 4.0, 5.0)
    decoded = vtk_to_numpy(out.GetPointData().GetScalars()).reshape(labels.shape)
    assert decoded.dtype == np.int64
    np.testing.assert_array_equal(decoded, labels)
    svdag = build.GetOutput()
    assert isinstance(svdag, vtkSegmentationSVDAG)
    np.testing.assert_array_equal(vtk_to_numpy(svdag.NewLabelValues()), np.arange(1, 7))


def test_shallow_and_deep_copy(rng):
    labels = rng.integers(0, 3, size=(5, 6, 7)).astype(np.uint8)
    src = compress_zyx(labels)
    for copy in ("ShallowCopy", "DeepCopy"):
        dst = vtkSegmentationSVDAG()
        getattr(dst, copy)(src)
        assert dst.GetNumberOfBlocks() == src.GetNumberOfBlocks()
        assert dst.GetCompressedSize() == src.GetCompressedSize()
        assert dst.GetLabelIndexAt(3, 2, 1) == src.GetLabelIndexAt(3, 2, 1)
    assert src.GetActualMemorySize() > 0

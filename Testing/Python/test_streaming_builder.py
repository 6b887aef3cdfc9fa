"""vtksvdag.Builder and vtkSegmentationSVDAGStreamBuilder: compressing a volume given in z-slabs.

The reference is vtksvdag.from_numpy (the one-shot vtkImageDataToSegmentationSVDAG filter) on
the whole array: the streamed volume must be the same bytes (the .svdag files written by both)
and decode to the original array.
"""
import doctest
import gc
import tracemalloc
import weakref

import numpy as np
import pytest
from vtkmodules.util.numpy_support import get_vtk_array_type, numpy_to_vtk
from vtkmodules.vtkCommonCore import vtkCommand, vtkFloatArray

import vtksvdag
import vtksvdag.streaming
from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAG, vtkSegmentationSVDAGStreamBuilder

from conftest import capture_errors

INTEGER_DTYPES = [np.int8, np.uint8, np.int16, np.uint16, np.int32, np.uint32, np.int64, np.uint64]


def saved_bytes(volume, path):
    volume.save(path)
    return path.read_bytes()


def labels_with_extremes(shape, dtype, rng):
    """Random labels [x, y, z] with the dtype's min and max, -1 (signed) and background 0, in
    blobs so that cells hold several blocks and a shared DAG, not only noise."""
    info = np.iinfo(dtype)
    values = np.array([info.min, info.max, 0, 1, 2, -1 if info.min < 0 else info.max - 1], dtype)
    coarse = rng.integers(0, len(values), size=tuple(s // 5 + 1 for s in shape))
    blobs = coarse.repeat(5, 0).repeat(5, 1).repeat(5, 2)[: shape[0], : shape[1], : shape[2]]
    noise = rng.random(shape) < 0.1
    idx = np.where(noise, rng.integers(0, len(values), size=shape), blobs)
    return values[idx]


def slab_sizes(total, step):
    """Slab depths covering `total` slices, `step` at a time (None: all at once)."""
    if step is None:
        return [total]
    sizes = [step] * (total // step)
    return sizes + ([total % step] if total % step else [])


def stream(labels_xyz, step, axis_order="xyz", **kwargs):
    """Compress labels [x, y, z] through Builder, `step` slices per add_slab."""
    builder = vtksvdag.Builder(labels_xyz.shape, labels_xyz.dtype, axis_order=axis_order, **kwargs)
    z = 0
    for n in slab_sizes(labels_xyz.shape[2], step):
        slab = labels_xyz[:, :, z: z + n]
        builder.add_slab(slab if axis_order == "xyz" else slab.transpose(2, 1, 0))
        z += n
        assert builder.next_z == z
    return builder.finish()


def assert_same_volume(streamed, labels_xyz, tmp_path, **kwargs):
    reference = vtksvdag.from_numpy(labels_xyz, **kwargs)
    assert saved_bytes(streamed, tmp_path / "streamed.svdag") == saved_bytes(
        reference, tmp_path / "reference.svdag"
    )
    decoded = streamed.to_numpy()
    assert decoded.dtype == labels_xyz.dtype
    assert np.array_equal(decoded, labels_xyz)
    np.testing.assert_array_equal(streamed.labels, reference.labels)
    assert streamed.dims == reference.dims


@pytest.mark.parametrize("step", [1, 7, 16, 33, None], ids=lambda s: f"slab{s}")
@pytest.mark.parametrize("dtype", INTEGER_DTYPES, ids=lambda d: np.dtype(d).name)
def test_every_dtype_matches_from_numpy(dtype, step, rng, tmp_path):
    labels = labels_with_extremes((19, 23, 37), dtype, rng)
    assert_same_volume(stream(labels, step), labels, tmp_path)


@pytest.mark.parametrize("axis_order", ["xyz", "zyx"])
@pytest.mark.parametrize("step", [1, 7, 16, 33, None], ids=lambda s: f"slab{s}")
@pytest.mark.parametrize(
    "shape", [(1, 1, 1), (1, 1, 17), (17, 1, 40), (5, 33, 16), (16, 16, 32), (40, 3, 50)],
    ids=lambda s: "x".join(map(str, s)),
)
def test_shapes_slab_sizes_and_axis_orders(shape, step, axis_order, rng, tmp_path):
    labels = labels_with_extremes(shape, np.int16, rng)
    assert_same_volume(stream(labels, step, axis_order), labels, tmp_path)


def test_irregular_slab_sizes(rng, tmp_path):
    labels = labels_with_extremes((21, 18, 70), np.uint32, rng)
    builder = vtksvdag.Builder(labels.shape, np.uint32)
    z = 0
    for n in [3, 13, 16, 1, 20, 2, 15]:
        builder.add_slab(labels[:, :, z: z + n])
        z += n
    assert z == 70 and builder.next_z == 70
    assert_same_volume(builder.finish(), labels, tmp_path)


@pytest.mark.parametrize(
    "dtype,background,exclude",
    [
        (np.int8, -128, (127, 2)),
        (np.uint8, 255, [0]),
        (np.int32, -1, range(1, 3)),
        (np.uint64, 2**64 - 1, (2,)),
        (np.int64, 2**63 - 1, (-(2**63),)),
        (np.uint16, 1, ()),
    ],
)
def test_background_and_exclude(dtype, background, exclude, rng, tmp_path):
    labels = labels_with_extremes((20, 17, 41), dtype, rng)
    options = dict(background=background, exclude=exclude)
    streamed = stream(labels, 7, **options)
    reference = vtksvdag.from_numpy(labels, **options)
    assert saved_bytes(streamed, tmp_path / "a.svdag") == saved_bytes(
        reference, tmp_path / "b.svdag"
    )
    # Independent of from_numpy: background and excluded labels decode as background.
    expected = labels.copy()
    expected[np.isin(labels, np.array(list(exclude), dtype=dtype))] = background
    assert np.array_equal(streamed.to_numpy(), expected)
    assert int(streamed.background) == background


def test_geometry(rng, tmp_path):
    labels = labels_with_extremes((12, 9, 30), np.uint16, rng)
    angle = np.radians(30)
    direction = np.array(
        [[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, -1]]
    )
    geometry = dict(spacing=(0.5, 1.25, 3.0), origin=(-10.0, 2.5, 7.0), direction=direction)
    for axis_order in ("xyz", "zyx"):
        streamed = stream(labels, 11, axis_order, **geometry)
        np.testing.assert_array_equal(streamed.spacing, geometry["spacing"])
        np.testing.assert_array_equal(streamed.origin, geometry["origin"])
        np.testing.assert_array_equal(np.reshape(streamed.direction, (3, 3)), direction)
        assert_same_volume(streamed, labels, tmp_path, **geometry)


def test_memory_layouts_byte_orders_and_bool(rng, tmp_path):
    labels = labels_with_extremes((13, 11, 20), np.int32, rng)
    builder = vtksvdag.Builder(labels.shape, ">i4")  # a dtype given big-endian means int32
    assert builder.dtype == np.int32
    builder.add_slab(labels[:, :, :5].astype(">i4"))           # big-endian
    builder.add_slab(np.asfortranarray(labels[:, :, 5:9]))       # a view with x fastest
    reversed_copy = labels[::-1, ::-1, ::-1].copy()
    builder.add_slab(reversed_copy[::-1, ::-1, ::-1][:, :, 9:14])  # negative strides
    builder.add_slab(labels[:, :, 14:].astype("<i4", order="C"))  # little-endian, C order
    assert_same_volume(builder.finish(), labels, tmp_path)

    mask = rng.random((9, 8, 19)) < 0.3
    builder = vtksvdag.Builder(mask.shape, bool)
    builder.add_slab(mask[:, :, :10])
    builder.add_slab(mask[:, :, 10:].astype(np.uint8))  # bool is stored as uint8: the same dtype
    streamed = builder.finish()
    assert streamed.dtype == np.uint8
    assert np.array_equal(streamed.to_numpy(), mask.astype(np.uint8))


def test_build_seconds_and_context_manager():
    with vtksvdag.Builder((4, 4, 4), np.uint8) as builder:
        builder.add_slab(np.ones((4, 4, 4), np.uint8))
        volume = builder.finish()
    assert volume.build_seconds >= 0
    assert builder.next_z == 4  # a finished builder is complete
    with vtksvdag.Builder((4, 4, 4), np.uint8) as builder:
        builder.add_slab(np.ones((4, 4, 2), np.uint8))
    with pytest.raises(RuntimeError, match="closed"):
        builder.add_slab(np.ones((4, 4, 2), np.uint8))
    with pytest.raises(RuntimeError, match="closed"):
        builder.next_z
    assert "closed" in repr(builder)


# --- errors --------------------------------------------------------------------------------

def test_wrong_dtype_names_both():
    builder = vtksvdag.Builder((4, 5, 6), np.uint16)
    with pytest.raises(TypeError, match=r"int16.*uint16"):
        builder.add_slab(np.zeros((4, 5, 6), np.int16))
    with pytest.raises(TypeError, match=r"float32.*uint16"):
        builder.add_slab(np.zeros((4, 5, 6), np.float32))
    with pytest.raises(TypeError, match="masked"):
        builder.add_slab(np.ma.zeros((4, 5, 6), np.uint16))
    assert builder.next_z == 0  # nothing was consumed
    builder.add_slab(np.zeros((4, 5, 6), np.uint16))
    builder.finish()


def test_wrong_shape():
    builder = vtksvdag.Builder((4, 5, 6), np.uint8)
    with pytest.raises(ValueError, match=r"\(4, 5, n\)"):
        builder.add_slab(np.zeros((5, 4, 2), np.uint8))  # nx and ny swapped
    with pytest.raises(ValueError, match="3D"):
        builder.add_slab(np.zeros((4, 5), np.uint8))
    with pytest.raises(ValueError, match="n >= 1"):
        builder.add_slab(np.zeros((4, 5, 0), np.uint8))
    zyx = vtksvdag.Builder((4, 5, 6), np.uint8, axis_order="zyx")
    with pytest.raises(ValueError, match=r"\(n, 5, 4\)"):
        zyx.add_slab(np.zeros((2, 4, 5), np.uint8))  # an [x, y, z] slab given as zyx
    zyx.add_slab(np.zeros((6, 5, 4), np.uint8))
    assert zyx.next_z == 6


def test_too_many_slices_and_finish_early():
    builder = vtksvdag.Builder((3, 3, 20), np.int8)
    builder.add_slab(np.zeros((3, 3, 18), np.int8))
    with pytest.raises(ValueError, match="too many slices"):
        builder.add_slab(np.zeros((3, 3, 3), np.int8))
    with pytest.raises(ValueError, match="2 of 20 slices are missing"):
        builder.finish()
    builder.add_slab(np.full((3, 3, 2), 4, np.int8))  # still usable after both errors
    volume = builder.finish()
    expected = np.zeros((3, 3, 20), np.int8)
    expected[:, :, 18:] = 4
    assert np.array_equal(volume.to_numpy(), expected)


def test_use_after_finish():
    builder = vtksvdag.Builder((2, 2, 2), np.uint8)
    builder.add_slab(np.ones((2, 2, 2), np.uint8))
    builder.finish()
    with pytest.raises(RuntimeError, match="finished"):
        builder.add_slab(np.ones((2, 2, 1), np.uint8))
    with pytest.raises(RuntimeError, match="finished"):
        builder.finish()


@pytest.mark.parametrize(
    "kwargs,error",
    [
        (dict(dims=(4, 4)), ValueError),
        (dict(dims=(4, 0, 4)), ValueError),
        (dict(dims=(4, 4.0, 4)), TypeError),
        (dict(dims=(4, 4, 4), dtype=np.float64), TypeError),
        (dict(dims=(4, 4, 4), background=256), ValueError),
        (dict(dims=(4, 4, 4), exclude=(-1,)), ValueError),
        (dict(dims=(4, 4, 4), spacing=(1, 0, 1)), ValueError),
        (dict(dims=(4, 4, 4), direction=np.zeros((3, 3))), ValueError),
        (dict(dims=(4, 4, 4), axis_order="xzy"), ValueError),
        (dict(dims=(2**31 - 1, 2**31 - 1, 2**31 - 1)), ValueError),  # more than 2^32 cells
    ],
)
def test_invalid_arguments(kwargs, error):
    kwargs.setdefault("dtype", np.uint8)
    dims = kwargs.pop("dims")
    with pytest.raises(error):
        vtksvdag.Builder(dims, **kwargs)


# --- memory --------------------------------------------------------------------------------

def test_caller_arrays_are_not_kept():
    builder = vtksvdag.Builder((16, 16, 40), np.uint32)
    refs = []
    for n in (5, 20, 15):  # a partial slab, one spanning a slab boundary, the end
        slab = np.ones((16, 16, n), np.uint32)
        refs.append(weakref.ref(slab))
        builder.add_slab(slab)
        del slab
    gc.collect()
    assert all(ref() is None for ref in refs)
    assert builder.finish().labels.tolist() == [1]


def test_python_memory_stays_near_one_slab():
    """Streaming an 8 MiB volume in 8-slice slabs allocates (on the Python side) about one slab
    and its x-fastest copy at a time, never the whole volume."""
    nx, ny, nz, step = 64, 64, 512, 8
    x = np.arange(nx, dtype=np.uint32)[:, None, None] // 9
    y = np.arange(ny, dtype=np.uint32)[None, :, None] // 7

    def slab(z0):  # 128 KiB, built without int64 temporaries
        z = np.arange(z0, z0 + step, dtype=np.uint32)[None, None, :] // 5
        return (x + y + z) % np.uint32(11)

    tracemalloc.start()
    try:
        builder = vtksvdag.Builder((nx, ny, nz), np.uint32)
        for z0 in range(0, nz, step):
            builder.add_slab(slab(z0))
        streamed = builder.finish()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    whole = np.concatenate([slab(z0) for z0 in range(0, nz, step)], axis=2)
    assert peak < whole.nbytes / 8, (peak, whole.nbytes)
    assert np.array_equal(streamed.to_numpy(), whole)


# --- the VTK class directly ----------------------------------------------------------------

def vtk_values(array):
    return numpy_to_vtk(np.ravel(array, order="F"), deep=True)


def test_vtk_class_matches_filter_and_reports_progress(rng, tmp_path):
    labels = labels_with_extremes((10, 12, 35), np.int64, rng)
    builder = vtkSegmentationSVDAGStreamBuilder()
    builder.SetBackgroundLabel(2)
    builder.AddExcludedLabel(-1)
    progress = []
    builder.AddObserver(
        vtkCommand.ProgressEvent, lambda obj, _event: progress.append(obj.GetProgress())
    )
    scalar_type = get_vtk_array_type(labels.dtype)
    assert builder.Initialize(list(labels.shape), scalar_type, [1.0, 2.0, 3.0], [4.0, 5.0, 6.0])
    assert builder.AddSlab(vtk_values(labels[:, :, :20]))
    assert builder.GetNextSlice() == 20
    assert builder.AddSlab(vtk_values(labels[:, :, 20:30]), 20)
    assert builder.AddSlab(vtk_values(labels[:, :, 30:]), 30, 5)
    output = vtkSegmentationSVDAG()
    assert builder.Finish(output)
    assert progress == pytest.approx([16 / 35, 32 / 35, 1.0])
    assert not builder.IsInitialized()
    reference = vtksvdag.from_numpy(labels, spacing=(1, 2, 3), origin=(4, 5, 6), background=2,
                                    exclude=[-1])
    streamed = vtksvdag.SegmentationVolume(output)
    assert saved_bytes(streamed, tmp_path / "a.svdag") == saved_bytes(
        reference, tmp_path / "b.svdag"
    )


def test_vtk_class_errors_leave_it_unchanged():
    builder = vtkSegmentationSVDAGStreamBuilder()
    errors = capture_errors(builder)
    output = vtkSegmentationSVDAG()
    good = vtk_values(np.ones((4, 3, 2), np.uint8))

    assert not builder.AddSlab(good)                   # before Initialize
    assert not builder.Finish(output)
    assert not builder.Initialize([4, 3, 5], vtkFloatArray().GetDataType())  # not an integer type
    assert not builder.Initialize([4, 0, 5], good.GetDataType())              # empty
    assert not builder.Initialize([2**31 - 1] * 3, good.GetDataType())        # absurd
    assert len(errors) == 5 and not builder.IsInitialized()

    assert builder.Initialize([4, 3, 5], good.GetDataType())
    floats = vtkFloatArray()
    floats.SetNumberOfTuples(24)
    floats.Fill(1)
    assert not builder.AddSlab(floats)                  # wrong scalar type
    assert "uint8" in errors[-1] and "float" in errors[-1]
    assert not builder.AddSlab(vtk_values(np.ones(13, np.uint8)))   # not whole slices
    assert not builder.AddSlab(good, 0, 3)              # says 3 slices, holds 2
    assert not builder.AddSlab(good, 1)                 # out of order
    assert not builder.AddSlab(vtk_values(np.ones((4, 3, 6), np.uint8)))  # too many
    assert not builder.AddSlab(good, -1)
    assert not builder.AddSlab(None)
    assert not builder.Finish(output)                   # slices missing
    assert len(errors) == 13 and builder.GetNextSlice() == 0 and not output.HasVolume()

    assert builder.AddSlab(good, 0, 2)
    assert builder.AddSlab(vtk_values(np.ones((4, 3, 3), np.uint8)), 2)
    assert not builder.Finish(None)
    assert builder.Finish(output) and output.GetNumberOfLabels() == 1
    assert not builder.Finish(output)                   # a second Finish
    assert len(errors) == 15


def test_docstring_examples():
    result = doctest.testmod(vtksvdag.streaming, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0

"""Random access from the compressed form: slices, sub-boxes, label masks, oblique planes, the
vtkSegmentationSVDAGSlice filter and add_segmentation_slice, each checked against numpy indexing
(or a brute-force numpy resampling) of the array the volume was built from."""
import doctest

import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy

import vtksvdag
from vtksvdag._vtkrun import run_algorithm
from vtksvdag.synthetic import voronoi
from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGSlice

from conftest import capture_errors

DTYPES = [np.uint8, np.uint16, np.uint32, np.uint64, np.int8, np.int16, np.int32, np.int64]
# Odd sizes, none a multiple of 16, several cells along each axis (and one single-cell volume).
SHAPES = [(37, 21, 50), (5, 40, 17)]


def labelled(shape, dtype, rng):
    """Blobs of a few labels (with the dtype's extremes and, when signed, negative values) on a
    background of 0, coherent enough to give mixed and solid DAG nodes, plus random speckle."""
    info = np.iinfo(dtype)
    values = np.array(sorted({int(info.min), int(info.max), 1, 7, int(info.max) // 3}
                             | ({-1, -5} if info.min < 0 else set())), dtype=dtype)
    values = values[values != 0]
    nx, ny, nz = shape
    x, y, z = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    index = ((x // 7 + 2 * (y // 9) + 3 * (z // 11)) % (len(values) + 1)).astype(np.int64)
    speckle = rng.random(shape) < 0.05
    index[speckle] = rng.integers(0, len(values) + 1, speckle.sum())
    table = np.concatenate([np.zeros(1, dtype=dtype), values])
    return table[index]


@pytest.fixture(scope="module")
def volumes():
    rng = np.random.default_rng(7)
    out = {}
    for dtype in DTYPES:
        for shape in SHAPES:
            array = labelled(shape, dtype, rng)
            out[np.dtype(dtype).name, shape] = (array, vtksvdag.from_numpy(array))
    return out


@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: "x".join(map(str, s)))
@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_axis_slices_match_numpy(volumes, dtype, shape):
    array, volume = volumes[np.dtype(dtype).name, shape]
    for axis in range(3):
        n = shape[axis]
        for index in sorted({0, 1, n // 2, 15, 16, n - 1} & set(range(n))):
            got = volume.slice("xyz"[axis], index)
            assert got.dtype == array.dtype
            np.testing.assert_array_equal(got, np.take(array, index, axis=axis))
            zyx = volume.slice(axis, index, axis_order="zyx")
            np.testing.assert_array_equal(zyx, np.take(array.transpose(2, 1, 0), index, axis=2 - axis))


def test_default_index_is_the_middle(volumes):
    array, volume = volumes["int32", SHAPES[0]]
    np.testing.assert_array_equal(volume.slice(), array[:, :, array.shape[2] // 2])
    np.testing.assert_array_equal(volume.slice("x"), array[array.shape[0] // 2])


@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_sub_boxes_match_numpy(volumes, dtype, rng):
    for shape in SHAPES:
        array, volume = volumes[np.dtype(dtype).name, shape]
        boxes = [(0, shape[0] - 1, 0, shape[1] - 1, 0, shape[2] - 1), (0, 0, 0, 0, 0, 0),
                 (shape[0] - 1, shape[0] - 1, shape[1] - 1, shape[1] - 1, shape[2] - 1, shape[2] - 1)]
        for _ in range(12):
            lo = [int(rng.integers(0, s)) for s in shape]
            hi = [int(rng.integers(a, s)) for a, s in zip(lo, shape)]
            boxes.append((lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]))
        for b in boxes:
            expected = array[b[0]:b[1] + 1, b[2]:b[3] + 1, b[4]:b[5] + 1]
            got = volume.to_numpy(bounds=b)
            assert got.dtype == array.dtype
            np.testing.assert_array_equal(got, expected)
            np.testing.assert_array_equal(volume.to_numpy("zyx", bounds=b), expected.transpose(2, 1, 0))


@pytest.mark.parametrize("dtype", DTYPES, ids=lambda d: np.dtype(d).name)
def test_masks_match_numpy(volumes, dtype):
    for shape in SHAPES:
        array, volume = volumes[np.dtype(dtype).name, shape]
        for value in list(volume.labels) + [volume.background]:
            got = volume.mask(value)
            assert got.dtype == np.bool_
            np.testing.assert_array_equal(got, array == value)
            b = (2, shape[0] - 2, 1, shape[1] - 1, 3, shape[2] - 1)
            np.testing.assert_array_equal(volume.mask(int(value), bounds=b),
                                          (array == value)[2:shape[0] - 1, 1:, 3:])
        # The label's own bounds: the tight box around its voxels.
        value = volume.labels[-1]
        where = np.nonzero(array == value)
        tight = tuple(s for w in where for s in (int(w.min()), int(w.max())))
        expected = (array == value)[tight[0]:tight[1] + 1, tight[2]:tight[3] + 1, tight[4]:tight[5] + 1]
        np.testing.assert_array_equal(volume.mask(value, bounds="label"), expected)
        np.testing.assert_array_equal(volume.mask(value, axis_order="zyx"), (array == value).transpose(2, 1, 0))


def test_mask_of_a_value_not_stored_is_empty(volumes):
    array, volume = volumes["uint16", SHAPES[0]]
    absent = next(v for v in range(2, 1000) if v not in set(volume.labels.tolist()))
    assert not volume.mask(absent).any()
    assert volume.mask(absent).shape == array.shape
    with pytest.raises(ValueError, match="not a label"):
        volume.mask(absent, bounds="label")
    with pytest.raises(ValueError):
        volume.mask(70000)  # does not fit uint16
    with pytest.raises(TypeError):
        volume.mask(1.5)
    with pytest.raises(ValueError):
        volume.mask(1, bounds="everything")


def nearest_reference(array, volume, image):
    """Brute-force nearest resampling of `array` at the world points of the samples of `image`
    (a pyvista.ImageData from resample_plane): sample (a, b) lies at image origin + D_image @
    (a * su, b * sv, 0); its continuous index in the volume is D^-1 (p - origin) / spacing;
    the nearest voxel is floor(index + 0.5). Also returns where a coordinate is within 1e-6 of
    a tie between two voxels (either answer is right there)."""
    nu, nv, _ = image.dimensions
    a, b = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    d_img = np.array(image.direction_matrix, float).reshape(3, 3)
    s = image.spacing
    p = np.array(image.origin, float)[:, None, None] + np.einsum(
        "ij,jab->iab", d_img, np.stack([a * s[0], b * s[1], np.zeros_like(a, float)]))
    rel = p - np.array(volume.origin, float)[:, None, None]
    idx = np.einsum("ij,jab->iab", np.linalg.inv(volume.direction), rel) / np.array(volume.spacing)[:, None, None]
    near = np.floor(idx + 0.5)
    frac = idx + 0.5 - near
    tie = np.any((frac < 1e-6) | (frac > 1 - 1e-6), axis=0)
    dims = np.array(volume.dims)[:, None, None]
    inside = np.all((near >= 0) & (near < dims), axis=0)
    out = np.full((nu, nv), volume.background, dtype=array.dtype)
    n = near.astype(np.int64)
    out[inside] = array[n[0][inside], n[1][inside], n[2][inside]]
    return out, tie


@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.uint64, np.int64], ids=lambda d: np.dtype(d).name)
def test_oblique_planes_match_brute_force_nearest(dtype, rng):
    array = labelled((37, 21, 50), dtype, rng)
    theta = 0.3
    rotation = np.array([[np.cos(theta), -np.sin(theta), 0], [np.sin(theta), np.cos(theta), 0], [0, 0, 1]])
    for direction, spacing in ((None, (1, 1, 1)), (rotation, (0.7, 1.3, 2.0))):
        volume = vtksvdag.from_numpy(array, spacing=spacing, origin=(3, -2, 5), direction=direction)
        center = np.array(volume.origin) + volume.direction @ ((np.array(volume.dims) - 1) / 2 * np.array(spacing))
        cases = [dict(normal=(0.3, -0.5, 0.8)), dict(normal=(1, 1, 1), origin=center + 3.3),
                 dict(normal=(0, 0.2, 1), shape=(70, 40), spacing=0.45),
                 dict(normal="y", shape=(9, 200), spacing=(0.5, 0.35), x_axis=(1, 0, 1)),
                 dict(normal=rng.normal(size=3), origin=center + rng.normal(size=3) * 4)]
        for case in cases:
            image = volume.resample_plane(as_image=True, **case)
            got = volume.resample_plane(**case)
            assert got.dtype == array.dtype and got.shape == image.dimensions[:2]
            np.testing.assert_array_equal(got, np.asarray(image.point_data["Labels"]).reshape(got.shape, order="F"))
            expected, tie = nearest_reference(array, volume, image)
            assert (got == expected)[~tie].all(), case
            assert (got != volume.background).any() and (~tie).mean() > 0.9
            # The grid: the normal is the image's third axis, u and v are orthonormal in the plane.
            d = np.array(image.direction_matrix, float).reshape(3, 3)
            normal = case["normal"]
            if isinstance(normal, str):
                normal = volume.direction[:, "xyz".index(normal)]
            n = np.asarray(normal, float) / np.linalg.norm(normal)
            np.testing.assert_allclose(d[:, 2], n, atol=1e-12)
            np.testing.assert_allclose(d.T @ d, np.eye(3), atol=1e-12)
            if "shape" in case:
                origin = case.get("origin", center)
                mid = np.array(image.origin) + d @ (np.array([(image.dimensions[0] - 1) * image.spacing[0],
                                                              (image.dimensions[1] - 1) * image.spacing[1], 0]) / 2)
                np.testing.assert_allclose(mid, origin, atol=1e-9)


def test_oblique_axis_plane_equals_the_axis_slice(volumes):
    array, volume = volumes["int64", SHAPES[0]]
    for k in (0, 20, array.shape[2] - 1):
        np.testing.assert_array_equal(volume.resample_plane("z", origin=(0, 0, k)), array[:, :, k])
    # x normal: u = y, v = x cross y = z.
    np.testing.assert_array_equal(volume.resample_plane("x", origin=(4, 0, 0)), array[4])
    # Beyond the volume: background only.
    assert (volume.resample_plane("z", origin=(0, 0, -3)) == volume.background).all()


def test_slice_images_are_in_world_geometry(volumes):
    array = volumes["uint32", SHAPES[0]][0]
    volume = vtksvdag.from_numpy(array, spacing=(0.5, 2, 3), origin=(10, 20, 30))
    image = volume.slice("y", 4, as_image=True)
    assert image.extent == (0, 36, 4, 4, 0, 49)
    assert image.spacing == (0.5, 2, 3) and image.origin == (10, 20, 30)
    np.testing.assert_array_equal(np.asarray(image.point_data["Labels"]).reshape((37, 50), order="F"), array[:, 4, :])
    # The points are where the voxels are: voxel (i, 4, k) at origin + spacing * index.
    np.testing.assert_allclose(image.points[0], (10, 20 + 4 * 2, 30))
    np.testing.assert_allclose(image.points[-1], (10 + 36 * 0.5, 28, 30 + 49 * 3))


def test_slice_filter_output_values_and_geometry(volumes):
    array = volumes["int16", SHAPES[0]][0]
    direction = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], float)
    volume = vtksvdag.from_numpy(array, spacing=(1, 2, 3), origin=(-1, -2, -3), direction=direction)
    f = vtkSegmentationSVDAGSlice()
    f.SetInputDataObject(0, volume.dataobject)
    assert f.GetMode() == f.AXIS_ALIGNED and f.GetAxis() == 2 and f.GetIndex() == 0
    for axis in range(3):
        for index in (0, array.shape[axis] - 1):
            f.SetAxis(axis)
            f.SetIndex(index)
            run_algorithm(f)
            out = f.GetOutput()
            extent = [0, array.shape[0] - 1, 0, array.shape[1] - 1, 0, array.shape[2] - 1]
            extent[2 * axis] = extent[2 * axis + 1] = index
            assert list(out.GetExtent()) == extent
            assert out.GetSpacing() == (1, 2, 3) and out.GetOrigin() == (-1, -2, -3)
            m = [out.GetDirectionMatrix().GetElement(r, c) for r in range(3) for c in range(3)]
            np.testing.assert_array_equal(m, direction.ravel())
            scalars = out.GetPointData().GetScalars()
            assert scalars.GetName() == "Labels" and scalars.GetDataTypeAsString() == "short"
            dims = out.GetDimensions()
            np.testing.assert_array_equal(vtk_to_numpy(scalars).reshape(dims, order="F").squeeze(axis),
                                          np.take(array, index, axis=axis))
    # Oblique mode through the same filter: a z normal gives u = the volume's x axis (world +y
    # here), v = n x u = its y axis (world -x); spacing (1, 2) samples every voxel center, and the
    # grid starts at the smallest projection, voxel (0, 0, 7).
    f.SetModeToOblique()
    f.SetPlaneNormal(0, 0, 1)
    f.SetOutputSpacing(1, 2)
    f.SetPlaneOrigin(*(np.array(volume.origin) + direction @ np.array([5, 4, 3 * 7])))
    run_algorithm(f)
    out = f.GetOutput()
    assert out.GetDimensions() == (37, 21, 1) and out.GetSpacing() == (1, 2, 1)
    np.testing.assert_allclose(out.GetOrigin(), np.array(volume.origin) + direction @ np.array([0, 0, 21]))
    got = vtk_to_numpy(out.GetPointData().GetScalars()).reshape((37, 21), order="F")
    np.testing.assert_array_equal(got, array[:, :, 7])
    text = str(f)
    assert "Mode: Oblique" in text and "PlaneNormal: 0 0 1" in text


def test_slice_filter_errors(volumes):
    volume = volumes["uint8", SHAPES[0]][1]
    f = vtkSegmentationSVDAGSlice()
    f.SetInputDataObject(0, volume.dataobject)
    for axis, index, message in ((3, 0, "axis"), (-1, 0, "axis"), (0, 37, "outside"), (2, -1, "outside")):
        f.SetAxis(axis)
        f.SetIndex(index)
        with pytest.raises(ValueError, match=message):
            run_algorithm(f)
    f.SetAxis(0)
    f.SetIndex(3)
    run_algorithm(f)  # recovers
    f.SetModeToOblique()
    f.SetPlaneNormal(0, 0, 0)
    with pytest.raises(ValueError, match="normal"):
        run_algorithm(f)
    f.SetPlaneNormal(0, 0, 1)
    f.SetPlaneXAxis(0, 0, 2)
    with pytest.raises(ValueError, match="x axis"):
        run_algorithm(f)
    f.SetPlaneXAxis(0, 0, 0)
    f.SetOutputDimensions(2**30, 2**30)
    with pytest.raises(ValueError, match="needs .* bytes"):
        run_algorithm(f)
    empty = vtkSegmentationSVDAGSlice()
    errors = capture_errors(empty)
    empty.SetInputDataObject(0, vtksvdag.vtkSVDAGCore.vtkSegmentationSVDAG())
    empty.Update()
    assert errors and "no compressed volume" in errors[0]


def test_bad_arguments_raise(volumes):
    array, volume = volumes["uint8", SHAPES[0]]
    with pytest.raises(ValueError, match="axis"):
        volume.slice("w", 0)
    with pytest.raises(ValueError, match="axis"):
        volume.slice(3, 0)
    with pytest.raises(ValueError, match="axis"):
        volume.slice(True, 0)
    with pytest.raises(IndexError):
        volume.slice("x", 37)
    with pytest.raises(IndexError):
        volume.slice("z", -1)
    with pytest.raises(TypeError):
        volume.slice("z", 1.5)
    with pytest.raises(ValueError, match="axis_order"):
        volume.slice("z", 1, axis_order="xzy")
    for bounds, error in (((0, 1, 0, 1, 0), ValueError), ((0, 1, 0, 1, 0, 1, 2), ValueError), ("abcdef", ValueError),
                          ((2, 1, 0, 1, 0, 1), ValueError), ((0, 37, 0, 1, 0, 1), IndexError),
                          ((-1, 3, 0, 1, 0, 1), IndexError), ((0, 1.0, 0, 1, 0, 1), TypeError)):
        with pytest.raises(error):
            volume.to_numpy(bounds=bounds)
        with pytest.raises(error):
            volume.mask(1, bounds=bounds)
    for kwargs in (dict(normal=(0, 0, 0)), dict(normal=(0, np.nan, 1)), dict(normal="q"),
                   dict(normal=(1, 2)), dict(normal="z", origin=(1, 2)), dict(normal="z", shape=(0, 3)),
                   dict(normal="z", shape=(3,)), dict(normal="z", shape=(2.5, 3)), dict(normal="z", spacing=0),
                   dict(normal="z", spacing=(1, -1)), dict(normal="z", x_axis=(0, 0, 1)),
                   dict(normal="z", x_axis=(0, 0, 0)), dict(normal="z", shape=(2**30, 2**30))):
        with pytest.raises(ValueError):
            volume.resample_plane(**kwargs)


def test_single_label_and_empty_volumes():
    empty = vtksvdag.from_numpy(np.zeros((20, 3, 33), dtype=np.int8))
    assert (empty.slice("z", 32) == 0).all() and empty.slice("x", 19).shape == (3, 33)
    assert (empty.resample_plane((1, 2, 3)) == 0).all()
    full = vtksvdag.from_numpy(np.full((17, 18, 19), -128, dtype=np.int8))
    assert (full.slice("y", 17) == -128).all() and full.mask(-128, bounds="label").all()


def test_real_volumes_slices(shared_data):
    import nrrd

    path = sorted(shared_data.glob("*.nrrd"))[0]
    array, _ = nrrd.read(str(path))
    volume = vtksvdag.read(path)
    for axis in range(3):
        k = array.shape[axis] // 2
        np.testing.assert_array_equal(volume.slice(axis, k), np.take(array, k, axis=axis).astype(volume.dtype))


def test_docstring_examples(tmp_path, monkeypatch):
    import vtksvdag.slicing
    import vtksvdag.volume

    monkeypatch.chdir(tmp_path)
    for module in (vtksvdag.volume, vtksvdag.slicing):
        result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
        assert result.failed == 0, module.__name__


# --- add_segmentation_slice -----------------------------------------------------------------

def test_add_segmentation_slice_colors_and_geometry():
    pv = pytest.importorskip("pyvista")
    import matplotlib

    labels = voronoi((20, 24, 28), 12, seed=3, dtype=np.uint16)  # (z, y, x)
    labels[labels == 5] = 0
    volume = vtksvdag.from_numpy(labels, axis_order="zyx", spacing=(0.5, 1, 2), origin=(1, 2, 3))
    array = volume.to_numpy()
    plotter = pv.Plotter(off_screen=True)
    colors = {1: "gold", 2: (0.1, 0.2, 0.3)}
    actor = vtksvdag.add_segmentation_slice(plotter, volume, normal="z", index=9, colors=colors, cmap="tab20")
    mesh = actor.mapper.dataset
    values = array[:, :, 9].ravel(order="F")
    assert mesh.n_cells == int((values != 0).sum())
    np.testing.assert_array_equal(np.asarray(mesh.cell_data["Labels"]), values[values != 0])
    rgb = np.asarray(mesh.cell_data["RGB"])
    tab20 = matplotlib.colormaps["tab20"]
    for value, color in zip(mesh.cell_data["Labels"][:200], rgb[:200]):
        if value == 1:
            expected = pv.Color("gold").int_rgb
        elif value == 2:
            expected = (26, 51, 77)
        else:
            index = int(np.searchsorted(volume.labels, value))
            expected = tuple(int(c * 255 + 0.5) for c in tab20(index % 20)[:3])
        # The colors come from the renderer's float32 linear materials: within one 8-bit level.
        np.testing.assert_allclose(color, expected, atol=1)
    # Flat quads centered on the voxels of layer 9 (world z = 3 + 9 * 2).
    full = vtksvdag.add_segmentation_slice(plotter, volume, normal="z", index=9, show_background=True)
    b = full.mapper.dataset.bounds
    np.testing.assert_allclose(b, (0.75, 14.75, 1.5, 25.5, 21, 21), atol=1e-9)
    assert full.mapper.dataset.n_cells == 28 * 24
    # By origin: the nearest layer; an oblique plane.
    by_origin = vtksvdag.add_segmentation_slice(plotter, volume, normal="x", origin=(1 + 0.5 * 6.2, 0, 0))
    np.testing.assert_array_equal(np.asarray(by_origin.mapper.dataset.cell_data["Labels"]),
                                  array[6].ravel(order="F")[array[6].ravel(order="F") != 0])
    oblique = vtksvdag.add_segmentation_slice(plotter, volume, normal=(1, 1, 1), show_background=True)
    assert oblique.mapper.dataset.n_cells > 100
    with pytest.raises(ValueError):
        vtksvdag.add_segmentation_slice(plotter, volume, normal=(0, 0, 1), index=3)
    with pytest.raises(IndexError):
        vtksvdag.add_segmentation_slice(plotter, volume, normal="z", index=99)
    with pytest.raises(ValueError):
        vtksvdag.add_segmentation_slice(plotter, volume, colors={999: "red"})
    plotter.close()


def test_hashed_default_colors_are_the_renderers():
    """The slice's hash colors (cmap="hash") are the renderer's (its materials), and that is the
    documented svdagLabelColor finalizer, recomputed here with Python integers."""
    from vtksvdag.slicing import _srgb_from_linear, label_colors

    def reference(i):
        x = i
        x ^= x >> 16
        x = (x * 0x7FEB352D) & 0xFFFFFFFF
        x ^= x >> 15
        x = (x * 0x846CA68B) & 0xFFFFFFFF
        x ^= x >> 16
        return [0.15 + 0.8 * ((x >> s) & 255) / 255 for s in (0, 8, 16)]

    volume = vtksvdag.from_numpy(np.arange(1, 301, dtype=np.uint16).reshape(10, 6, 5))
    got = label_colors(volume, cmap="hash")
    expected = _srgb_from_linear(np.array([reference(i) for i in range(300)]))
    np.testing.assert_allclose(got, expected, rtol=1e-6)
    # Without colors or cmap, the slice has the 3D view's default: the distinct colors.
    np.testing.assert_allclose(label_colors(volume), volume.distinct_colors(), atol=1e-6)


def test_slice_filter_in_a_pipeline(rng):
    """Connected to the compressing filter (the input exists only once upstream has run), and
    feeding vtkImageSliceMapper."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtkmodules.vtkRenderingCore import vtkImageSliceMapper

    from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG

    zyx = rng.integers(0, 4, (30, 20, 10)).astype(np.uint8)
    image = vtkImageData()
    image.SetDimensions(10, 20, 30)
    image.GetPointData().SetScalars(numpy_to_vtk(zyx.ravel(), deep=True))
    builder = vtkImageDataToSegmentationSVDAG()
    builder.SetInputData(image)
    slicer = vtkSegmentationSVDAGSlice()
    slicer.SetInputConnection(builder.GetOutputPort())
    for index in (29, 3):
        slicer.SetIndex(index)
        run_algorithm(slicer)
        out = slicer.GetOutput()
        assert out.GetExtent() == (0, 9, 0, 19, index, index)
        np.testing.assert_array_equal(vtk_to_numpy(out.GetPointData().GetScalars()).reshape(20, 10), zyx[index])
    mapper = vtkImageSliceMapper()
    mapper.SetInputConnection(slicer.GetOutputPort())
    mapper.Update()
    assert mapper.GetInput().GetExtent() == (0, 9, 0, 19, 3, 3)

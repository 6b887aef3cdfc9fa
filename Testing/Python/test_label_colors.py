"""The default look: label adjacency from the compressed form, the categorical palette, the graph
coloring over the adjacency, the colors add_segmentation puts on the mapper and the camera framing
of the visible labels.

References are independent of the C++ core: adjacency against a numpy brute force on the decoded
array, CIELAB with this file's own conversion (checked on published values), camera framing
against bounds computed here from the label array.
"""
import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkSMPTools

import vtksvdag
from vtksvdag import synthetic
from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAG

DTYPES = [np.int8, np.uint8, np.int16, np.uint16, np.int32, np.uint32, np.int64, np.uint64]


def srgb_to_lab(rgb):
    """CIELAB (D65) of display sRGB in [0, 1] (IEC 61966-2-1 and CIE 15 formulas)."""
    rgb = np.asarray(rgb, float)
    linear = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    m = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    t = linear @ m.T / np.array([0.95047, 1.0, 1.08883])
    f = np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]),
                     200 * (f[..., 1] - f[..., 2])], axis=-1)


def test_lab_reference_values():
    # Published CIELAB of the sRGB primaries and white (D65).
    lab = srgb_to_lab([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]])
    assert np.allclose(lab, [[53.24, 80.09, 67.20], [87.73, -86.18, 83.18],
                             [32.30, 79.19, -107.86], [100, 0, 0]], atol=0.05)


def brute_force_adjacency(labels, background):
    """Touching pairs (values a < b) of an (x, y, z) array, by comparing each voxel with its
    +1 neighbour along every axis."""
    pairs = set()
    for axis in range(3):
        lo = np.moveaxis(labels, axis, 0)[:-1].ravel()
        hi = np.moveaxis(labels, axis, 0)[1:].ravel()
        keep = (lo != hi) & (lo != background) & (hi != background)
        for a, b in zip(lo[keep].tolist(), hi[keep].tolist()):
            pairs.add((min(a, b), max(a, b)))
    return sorted(pairs)


def random_volume(rng, shape, dtype, n_values):
    info = np.iinfo(dtype)
    # Values near both ends of the type (negative ones for signed types) and the background 0.
    ends = np.array([0, info.min, info.max], dtype=dtype)
    values = np.unique(np.concatenate([ends, rng.integers(info.min, info.max, n_values, dtype=dtype,
                                                          endpoint=True)]))
    # Blobs of constant value rather than white noise, so that blocks are not all singletons.
    coarse = rng.integers(0, len(values), size=tuple(max(1, s // 3) for s in shape))
    index = coarse[tuple(np.minimum(np.arange(s) // 3, c - 1)[(slice(None),) + (None,) * (2 - a)]
                         for a, (s, c) in enumerate(zip(shape, coarse.shape)))]
    return values[index]


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("shape", [(17, 33, 5), (40, 1, 1), (1, 1, 40), (1, 37, 1), (31, 18, 47)])
def test_adjacency_matches_brute_force_random(dtype, shape):
    rng = np.random.default_rng(hash((np.dtype(dtype).name, shape)) % 2**32)
    labels = random_volume(rng, shape, dtype, 6)
    volume = vtksvdag.from_numpy(labels)
    got = volume.label_adjacency()
    assert got.dtype == np.dtype(dtype) and got.shape[1] == 2
    assert [tuple(p) for p in got.tolist()] == brute_force_adjacency(labels, 0)


@pytest.mark.parametrize("name, labels", [
    ("voronoi", synthetic.voronoi((45, 38, 50), 60, seed=3)),
    ("tubes", synthetic.tubes((48, 48, 48), 12, 2.5, seed=2)),
    ("checkerboard", synthetic.checkerboard((19, 20, 21), n_labels=3, period=1)),
    ("random noise", synthetic.random_labels((18, 17, 35), 9, seed=4)),
])
def test_adjacency_matches_brute_force_structured(name, labels):
    volume = vtksvdag.from_numpy(labels)
    expected = brute_force_adjacency(labels, 0)
    assert expected, "the scene must have touching labels"
    assert [tuple(p) for p in volume.label_adjacency().tolist()] == expected


def test_adjacency_of_trivial_volumes():
    empty = np.zeros((20, 20, 20), np.uint16)
    assert vtksvdag.from_numpy(empty).label_adjacency().shape == (0, 2)
    one = np.full((20, 20, 20), 4, np.uint16)
    assert vtksvdag.from_numpy(one).label_adjacency().shape == (0, 2)
    # Two labels separated by one background voxel do not touch; diagonal neighbours neither.
    gap = np.zeros((5, 5, 5), np.uint8)
    gap[0, :2, :2], gap[2, :2, :2] = 1, 2
    gap[4, 4, 4], gap[3, 3, 3] = 3, 4
    assert vtksvdag.from_numpy(gap).label_adjacency().shape == (0, 2)


def test_adjacency_across_cell_layers_and_threads():
    """Boundaries on the 16-voxel cell planes (x, y and z = 16, 32) are found, with any number of
    threads."""
    labels = np.zeros((40, 40, 40), np.uint32)
    labels[:16], labels[16:32], labels[32:] = 1, 2, 3
    labels[:, :, 16:32] += 10
    labels[:, 16:, :] += 100
    expected = brute_force_adjacency(labels, 0)
    volume = vtksvdag.from_numpy(labels)
    before = vtkSMPTools.GetEstimatedNumberOfThreads()
    try:
        results = []
        for threads in (1, 2, 4):
            vtkSMPTools.Initialize(threads)
            results.append([tuple(p) for p in volume.label_adjacency().tolist()])
    finally:
        vtkSMPTools.Initialize(before)
    assert all(r == expected for r in results)


def palette(n):
    colors = vtkDoubleArray()
    vtkSegmentationSVDAG.GetCategoricalPalette(n, colors)
    return vtk_to_numpy(colors).reshape(-1, 3)


def test_palette_distinct_saturated_in_gamut():
    colors = palette(256)
    assert colors.shape == (256, 3) and np.all((colors >= 0) & (colors <= 1))
    assert len(np.unique(colors, axis=0)) == 256
    lab = srgb_to_lab(colors)
    # The palette's lightness and chroma limits (svdag/Palette.h): no grays, no near-black.
    assert lab[:, 0].min() >= 40 - 1e-6 and lab[:, 0].max() <= 82 + 1e-6
    assert np.hypot(lab[:, 1], lab[:, 2]).min() >= 35 - 1e-6
    distance = np.linalg.norm(lab[:, None] - lab[None], axis=2)
    np.fill_diagonal(distance, np.inf)
    # The first colors are the most distinct: far beyond tab20's closest pair (about 11).
    for k, minimum in ((8, 55), (20, 35), (32, 27), (128, 14)):
        assert distance[:k, :k].min() >= minimum, k
    # Greedy farthest point: each color's distance to the colors before it never increases.
    nearest = [distance[k, :k].min() for k in range(1, 256)]
    assert np.all(np.diff(nearest) <= 1e-9)
    # Past its size the palette repeats.
    assert np.array_equal(palette(300)[256:], colors[:44])


def pair_distances(volume, colors):
    index = np.searchsorted(volume.labels, volume.label_adjacency())
    lab = srgb_to_lab(colors)
    return np.linalg.norm(lab[index[:, 0]] - lab[index[:, 1]], axis=1)


def test_coloring_separates_touching_labels():
    # A chain of 30 slabs (each touches the next only) and a Voronoi volume (degree about 12).
    chain = np.repeat(np.arange(1, 31, dtype=np.uint16), 2)[:, None, None] * np.ones((1, 4, 4), np.uint16)
    for labels in (chain, synthetic.voronoi((48, 48, 48), 150, seed=5)):
        volume = vtksvdag.from_numpy(labels)
        colors = volume.distinct_colors()
        assert colors.shape == (len(volume.labels), 3)
        # Every color is a palette color.
        pal = palette(256)
        assert all(np.any(np.all(np.isclose(pal, c), axis=1)) for c in colors)
        d = pair_distances(volume, colors)
        assert len(d) and d.min() >= 25, d.min()
        # Deterministic, and varied: labels far apart are not all given the same few colors.
        assert np.array_equal(colors, vtksvdag.from_numpy(labels).distinct_colors())
        assert len(np.unique(colors, axis=0)) >= min(20, len(colors))


def test_coloring_of_labels_without_neighbours():
    labels = np.zeros((30, 5, 5), np.uint8)
    labels[0:2], labels[5:7], labels[10:12] = 1, 2, 3
    colors = vtksvdag.from_numpy(labels).distinct_colors()
    assert len(np.unique(colors, axis=0)) == 3  # the least used color goes to each


def test_tab20_fails_where_the_palette_does_not():
    """What bench/palette.py measures, on a volume where it is known to matter: tab20 cycled in
    label order gives labels 0 and 20 (in table order) the same color, and here they touch."""
    import matplotlib

    labels = np.zeros((40, 4, 4), np.uint8)
    labels[:, :2] = np.repeat(np.arange(1, 21, dtype=np.uint8), 2)[:, None, None]
    labels[:, 2:] = 21  # touches every slab
    volume = vtksvdag.from_numpy(labels)
    tab20 = np.array([matplotlib.colormaps["tab20"](i % 20)[:3] for i in range(21)])
    assert pair_distances(volume, tab20).min() == 0
    assert pair_distances(volume, volume.distinct_colors()).min() >= 25


# -- add_segmentation ---------------------------------------------------------------------------
def test_default_colors_on_the_mapper_are_the_palette_assignment(plotter):
    labels = synthetic.voronoi((30, 30, 30), 25, seed=7).astype(np.int16) - 12  # negative values
    volume = vtksvdag.from_numpy(labels)
    actor = vtksvdag.add_segmentation(plotter, volume, colors={3: (0.0, 0.0, 1.0)}, spp=1)
    props = actor.GetMapper().GetLabelProperties()
    expected = volume.distinct_colors()
    rgb = [0.0] * 3
    for value, color in zip(volume.labels.tolist(), expected):
        assert props.GetColor(value, rgb)
        assert np.allclose(rgb, (0, 0, 1) if value == 3 else color), value
    # The material the renderer gets is the same color, linearised.
    material = [0.0] * 16
    value, color = volume.labels.tolist()[0], expected[0]
    assert props.GetMaterial(volume.dataobject, value, material)
    linear = np.where(color <= 0.04045, color / 12.92, ((color + 0.055) / 1.055) ** 2.4)
    assert np.allclose(material[:3], linear, atol=1e-5)


@pytest.mark.parametrize("dtype", DTYPES)
def test_default_colors_reach_every_label_of_every_dtype(plotter, dtype):
    """The colors are keyed by each label's 64-bit pattern (sign-extended, uint64 above 2^63 as
    negative int64) without a call per label: every label, the extremes of its type included,
    reads its palette color back by its value."""
    info = np.iinfo(dtype)
    labels = np.zeros((6, 7, 8), dtype)
    values = sorted({info.min, info.min + 1, 1, 2, info.max - 1, info.max} - {0})
    for i, value in enumerate(values):
        labels[i, i % 7, :] = value
    volume = vtksvdag.from_numpy(labels)
    assert volume.labels.tolist() == values
    props = vtksvdag.add_segmentation(plotter, volume, spp=1).GetMapper().GetLabelProperties()
    rgb = [0.0] * 3
    for value, color in zip(values, volume.distinct_colors()):
        key = value - 2**64 if value >= 2**63 else value  # the mapper's int64 key
        assert props.GetColor(key, rgb), value
        assert np.allclose(rgb, color), value


def test_hash_colors_stay_available(plotter):
    labels = synthetic.voronoi((20, 20, 20), 10, seed=1)
    actor = vtksvdag.add_segmentation(plotter, labels, cmap="hash", spp=1)
    props = actor.GetMapper().GetLabelProperties()
    # No color set: the renderer's hash applies (svdagLabelColor, test_slices checks its values).
    assert not any(props.GetColor(int(v), [0.0] * 3) for v in np.unique(labels))


def test_default_look_settings(plotter):
    from vtksvdag.plotting import DEFAULT_SKY, DEFAULT_SUN_ANGULAR_RADIUS

    actor = vtksvdag.add_segmentation(plotter, np.ones((4, 4, 4), np.uint8), spp=1)
    settings = actor.GetMapper().GetSettings()
    sky = [0.0] * 3
    settings.GetEnvironmentColor(sky)
    assert settings.GetSun() and settings.GetSunAngularRadius() == pytest.approx(DEFAULT_SUN_ANGULAR_RADIUS)
    assert np.allclose(sky, DEFAULT_SKY)
    off = vtksvdag.add_segmentation(plotter, np.ones((4, 4, 4), np.uint8), sun=False, spp=1)
    assert not off.GetMapper().GetSettings().GetSun()


def world_box(lo, hi, spacing, origin):
    """World bounds of the voxels [lo, hi] (inclusive indices), voxels centered on their points."""
    lo, hi, spacing, origin = (np.asarray(v, float) for v in (lo, hi, spacing, origin))
    return np.ravel([origin + (lo - 0.5) * spacing, origin + (hi + 0.5) * spacing], order="F")


def test_camera_frames_the_visible_labels(plotter):
    labels = np.zeros((40, 30, 20), np.uint8)
    labels[2:8, 3:9, 1:5] = 1      # a small box near the origin corner
    labels[30:40, 20:30, 10:20] = 2  # a big one in the far corner, hidden below
    labels[20:22, 0:2, 0:2] = 3      # opacity 0: does not count either
    spacing, origin = (0.5, 1.0, 2.0), (10.0, -5.0, 3.0)
    volume = vtksvdag.from_numpy(labels, spacing=spacing, origin=origin)
    vtksvdag.add_segmentation(plotter, volume, hidden_labels=[2], opacity={3: 0.0}, spp=1)
    box = world_box((2, 3, 1), (7, 8, 4), spacing, origin)
    center = box.reshape(3, 2).mean(axis=1)
    assert np.allclose(plotter.camera.focal_point, center)
    # The whole box is in view and fills a good part of it (not the whole volume's framing).
    assert plotter.camera.distance < 4 * np.linalg.norm(box[1::2] - box[0::2])
    # pyvista's first render does not reset it back to the whole volume.
    plotter.render()
    assert np.allclose(plotter.camera.focal_point, center)
    # A second volume added to the framed camera is framed with the first.
    more = np.zeros((4, 4, 4), np.uint8)
    more[1:3, 1:3, 1:3] = 9
    vtksvdag.add_segmentation(plotter, more, spp=1)
    union = np.ravel([np.minimum(box[0::2], world_box((1,) * 3, (2,) * 3, (1,) * 3, (0,) * 3)[0::2]),
                      np.maximum(box[1::2], world_box((1,) * 3, (2,) * 3, (1,) * 3, (0,) * 3)[1::2])],
                     order="F")
    assert np.allclose(plotter.camera.focal_point, union.reshape(3, 2).mean(axis=1))
    # A camera the user set is left alone.
    plotter.camera_position = [(100, 100, 100), (1, 2, 3), (0, 0, 1)]
    vtksvdag.add_segmentation(plotter, more, spp=1)
    assert np.allclose(plotter.camera.focal_point, (1, 2, 3))

"""Per-label attribute tables in the 3D view: color_by, query, the selection highlight.

add_segmentation(attributes=, color_by=, query=, highlight=, dim=) and the returned
SegmentationActor's set_* methods, vtkSegmentationSVDAGLabelProperties' highlight API, and
``vtksvdag render --attributes/--color-by/--query/--highlight``. References: the colormap
itself (matplotlib), the label properties' GetMaterial (what the renderer is given), the CPU ray
caster on a volume with the hidden labels removed, and the rendered pixels under each label.
"""
import json
import subprocess
import sys
import time

import matplotlib
import numpy as np
import pandas as pd
import pytest
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL factory overrides)
from conftest import SHARED_DATA, caster_pick, compress_zyx, mapper_pick, pixel_ray, require_shared_data
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

import vtksvdag
from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGRayCaster
from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGLabelProperties

pv = pytest.importorskip("pyvista")

W, H = 160, 120
NAN_GREY = (0.5, 0.5, 0.5)


def srgb_to_linear(c):
    c = np.asarray(c, float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def slabs():
    """[x, y, z] uint16 labels: five slabs side by side along x (labels 1..5), each seen from
    the default camera; label 9 is a small cube behind them (not in the attribute table)."""
    labels = np.zeros((44, 24, 24), np.uint16)
    for i in range(5):
        labels[2 + 8 * i: 8 + 8 * i, 2:22, 2:22] = i + 1
    labels[40:43, 10:13, 10:13] = 9
    return labels


ATTRIBUTES = pd.DataFrame({
    "label": [1, 2, 3, 4, 5],
    "score": [0.0, 2.5, 5.0, 7.5, 10.0],
    "type": ["pyramidal", "glia", "pyramidal", None, "glia"],
})


def key_material(actor, label):
    material = [0.0] * 16
    assert actor.label_properties.GetMaterial(actor.GetMapper().GetInput(), label, material)
    return np.array(material)


@pytest.fixture
def plotter():
    p = pv.Plotter(off_screen=True, window_size=(W, H))
    p.camera_position = [(22, -70, 60), (22, 12, 12), (0, 0, 1)]
    yield p
    p.close()


def rgb(plotter):
    """The window's colors, (H, W, 3) ints, row 0 the bottom (display y)."""
    grab = vtkWindowToImageFilter()
    grab.SetInput(plotter.render_window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    image = grab.GetOutput()
    return vtk_to_numpy(image.GetPointData().GetScalars()).reshape(H, W, -1)[:, :, :3].astype(float)


def label_image(actor, plotter, step=2):
    """The picked (primary) label per grid pixel of the last frame: {(x, y): label or 0}."""
    mapper = actor.GetMapper()
    out = {}
    for y in range(1, H - 1, step):
        for x in range(1, W - 1, step):
            hit = mapper_pick(mapper, plotter.renderer, x + 0.5, y + 0.5)
            out[(x, y)] = 0 if hit is None else hit[0]
    return out


def mean_color(color, labels, label):
    """Mean RGB over the pixels whose 8 neighbours on the grid carry the same label (interior:
    the silhouette mixes in the background)."""
    pixels = []
    for (x, y), value in labels.items():
        if value != label:
            continue
        if all(labels.get((x + dx, y + dy)) == label for dx in (-2, 0, 2) for dy in (-2, 0, 2)):
            pixels.append(color[y, x])
    assert len(pixels) > 20, (label, len(pixels))
    return np.mean(pixels, axis=0)


# color_by ---------------------------------------------------------------------------------------
def test_color_by_numeric_is_the_colormap_value(plotter):
    actor = vtksvdag.add_segmentation(plotter, slabs(), attributes=ATTRIBUTES, color_by="score",
                                      cmap="viridis", spp=8, bounces=1)
    assert isinstance(actor, pv.Volume) and actor.color_by == "score"
    viridis = matplotlib.colormaps["viridis"]
    props = actor.label_properties
    for label, score in zip(ATTRIBUTES.label, ATTRIBUTES.score):
        expected = np.array(viridis(score / 10.0)[:3])
        got = [0.0] * 3
        assert props.GetColor(label, got)
        np.testing.assert_allclose(got, expected, atol=1e-12)
        # What the renderer gets: the same color, linear, visible.
        material = key_material(actor, label)
        np.testing.assert_allclose(material[:3], srgb_to_linear(expected), atol=1e-6)
        assert material[3] == 1.0
    # Label 9 has no row: the neutral grey.
    got = [0.0] * 3
    assert props.GetColor(9, got)
    np.testing.assert_allclose(got, NAN_GREY)

    # Rendered: the low end of viridis is purple (blue > green), the high end yellow (red >
    # blue), under the default white environment.
    vtksvdag.refine(plotter)
    color, labels = rgb(plotter), label_image(actor, plotter)
    low, high = mean_color(color, labels, 1), mean_color(color, labels, 5)
    assert low[2] > low[1] + 30, low
    assert high[0] > high[2] + 80 and high[1] > high[2] + 80, high

    # clim clips: with clim (0, 5) labels 3..5 share the top color.
    actor.set_color_by("score", cmap="viridis", clim=(0, 5))
    tops = [actor.label_properties.GetColor(v, got) and tuple(got) for v in (3, 4, 5)]
    np.testing.assert_allclose(tops, [viridis(1.0)[:3]] * 3, atol=1e-12)
    # Back to the colors of add_segmentation (none given: the distinct default colors).
    actor.set_color_by(None)
    volume = vtksvdag.from_numpy(slabs())
    for value, color in zip(volume.labels.tolist(), volume.distinct_colors()):
        assert actor.label_properties.GetColor(value, got)
        np.testing.assert_allclose(got, color)


def test_color_by_categorical_and_explicit_colors(plotter):
    actor = vtksvdag.add_segmentation(plotter, slabs(), attributes=ATTRIBUTES, color_by="type",
                                      colors={5: "red"}, nan_color=(0.1, 0.2, 0.3), spp=1)
    tab10 = matplotlib.colormaps["tab10"]
    got = [0.0] * 3
    # Categories in sorted order: glia 0, pyramidal 1.
    for label, index in ((1, 1), (2, 0), (3, 1)):
        assert actor.label_properties.GetColor(label, got)
        np.testing.assert_allclose(got, tab10(index)[:3], atol=1e-12)
    # A missing value (label 4) and a missing row (label 9) take nan_color; colors wins (5).
    for label, expected in ((4, (0.1, 0.2, 0.3)), (9, (0.1, 0.2, 0.3)), (5, (1.0, 0.0, 0.0))):
        assert actor.label_properties.GetColor(label, got)
        np.testing.assert_allclose(got, expected, atol=1e-12)
    # A computed column colors too (voxel_count: label 9 is the smallest).
    actor.set_color_by("voxel_count", cmap="magma")
    assert actor.label_properties.GetColor(9, got)
    np.testing.assert_allclose(got, matplotlib.colormaps["magma"](0.0)[:3], atol=1e-12)


# query ------------------------------------------------------------------------------------------
def caster_agreement(actor, plotter, reference_xyz, step=4):
    """Fraction of grid pixels where the mapper's pick equals the CPU ray caster's on the
    reference volume; and the labels the mapper showed."""
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(compress_zyx(np.ascontiguousarray(reference_xyz.transpose(2, 1, 0))))
    mapper = actor.GetMapper()
    agree = total = 0
    seen = set()
    for y in range(step // 2, H, step):
        for x in range(step // 2, W, step):
            expected = caster_pick(caster, *pixel_ray(plotter.renderer, x, y))
            got = mapper_pick(mapper, plotter.renderer, x + 0.5, y + 0.5)
            if got is not None:
                seen.add(got[0])
            total += 1
            agree += (expected is None and got is None) or (
                expected is not None and got is not None and expected[0] == got[0])
    return agree / total, seen


def test_query_hides_exactly_the_non_matching_labels(plotter):
    labels = slabs()
    actor = vtksvdag.add_segmentation(plotter, labels, attributes=ATTRIBUTES, color_by="score",
                                      query="score >= 5 and type == 'glia' or score < 1",
                                      hidden_labels=[1], spp=1)
    # Matching: 1 (score 0) and 5; 1 is hidden by hidden_labels, so only 5 is drawn.
    assert actor.query.startswith("score >= 5")
    assert actor.visible_labels == [5]
    vtksvdag.refine(plotter)
    reference = np.where(labels == 5, labels, 0)
    fraction, seen = caster_agreement(actor, plotter, reference)
    assert seen == {5}
    assert fraction >= 0.99

    mapper = actor.GetMapper()
    builds = mapper.GetNumberOfBVHBuilds()
    matched = actor.set_query("score > 1")
    assert matched == [2, 3, 4, 5]
    vtksvdag.refine(plotter)
    # Visibility only: one BVH rebuild on the rt backend, none on compute (bits).
    assert mapper.GetNumberOfBVHBuilds() == builds + (mapper.GetBackendInUse() == "rt")
    reference = np.where(np.isin(labels, [2, 3, 4, 5]), labels, 0)
    fraction, seen = caster_agreement(actor, plotter, reference)
    assert seen == {2, 3, 4, 5} and fraction >= 0.99
    assert actor.visible_labels == [2, 3, 4, 5]

    # pandas' rules for missing values: a comparison is false, except != (label 4 has no type,
    # label 9 no row).
    assert actor.set_query("type == 'glia' or type == 'pyramidal'") == [1, 2, 3, 5]
    assert actor.set_query("type != 'pyramidal'") == [2, 4, 5, 9]
    assert actor.visible_labels == [2, 4, 5, 9]
    actor.set_query(None)
    assert actor.visible_labels == [2, 3, 4, 5, 9]

    # A color change is a material upload: no rebuild.
    vtksvdag.refine(plotter)
    builds = mapper.GetNumberOfBVHBuilds()
    actor.set_color_by("type")
    vtksvdag.refine(plotter)
    assert mapper.GetNumberOfBVHBuilds() == builds


def test_query_without_attributes_uses_computed_columns(plotter):
    actor = vtksvdag.add_segmentation(plotter, slabs(), query="voxel_count > 100", spp=1)
    assert actor.visible_labels == [1, 2, 3, 4, 5]
    assert list(actor.label_table.index) == [1, 2, 3, 4, 5, 9]
    assert actor.label_table.index.name == "label"
    assert actor.label_table.loc[9, "voxel_count"] == 27


def test_attributes_from_csv(plotter, tmp_path):
    path = tmp_path / "cells.csv"
    ATTRIBUTES.to_csv(path, index=False)
    actor = vtksvdag.add_segmentation(plotter, slabs(), attributes=path, query="type == 'glia'",
                                      spp=1)
    assert actor.visible_labels == [2, 5]
    # Indexed by label, whole floats as labels, and a row of a label the volume lacks (warned).
    indexed = ATTRIBUTES.assign(label=ATTRIBUTES.label.astype(float)).set_index("label")
    indexed.loc[77.0] = [1.0, "glia"]
    with pytest.warns(UserWarning, match="77"):
        actor2 = vtksvdag.add_segmentation(plotter, slabs(), attributes=indexed,
                                           query="score == 10", spp=1, name="second")
    assert actor2.visible_labels == [5]
    assert 77 not in actor2.label_table.index
    assert actor2.label_table.loc[5, "surface_voxels"] > 0  # the computed columns are there


# highlight --------------------------------------------------------------------------------------
def test_highlight_emission_and_dimming(plotter):
    actor = vtksvdag.add_segmentation(plotter, slabs(), attributes=ATTRIBUTES,
                                      colors={v: (0.6, 0.6, 0.6) for v in (1, 2, 3, 4, 5, 9)},
                                      spp=8, bounces=1)
    mapper = actor.GetMapper()
    mapper.SetRefineStillRenders(False)  # one pass per render: the restart below shows
    before = {v: key_material(actor, v) for v in (1, 2, 3, 4, 5, 9)}
    assert all(np.all(m[4:7] == 0) for m in before.values())
    vtksvdag.refine(plotter)
    builds = mapper.GetNumberOfBVHBuilds()
    color0, labels0 = rgb(plotter), label_image(actor, plotter)

    assert actor.set_highlight([3], dim=0.3) == [3]
    assert actor.highlighted_labels == [3]
    after = {v: key_material(actor, v) for v in before}
    amber = srgb_to_linear((1.0, 0.8, 0.2))
    np.testing.assert_allclose(after[3][4:7], amber, atol=1e-6)  # the tint, intensity 1
    np.testing.assert_allclose(after[3][:4], before[3][:4])      # its own color is kept
    for v in (1, 2, 4, 5, 9):
        np.testing.assert_array_equal(after[v][4:7], 0)
        np.testing.assert_allclose(after[v][:3], 0.3 * before[v][:3], rtol=1e-6)
        assert after[v][3] == 1.0  # still visible: no BVH rebuild
    # The next frame restarts the accumulation and shows it, without rebuilding geometry.
    plotter.render()
    assert mapper.GetAccumulatedSamples() == 1
    vtksvdag.refine(plotter)
    assert mapper.GetNumberOfBVHBuilds() == builds
    color1, labels1 = rgb(plotter), label_image(actor, plotter)
    assert labels1 == labels0  # the same geometry
    lit0, lit1 = mean_color(color0, labels0, 3), mean_color(color1, labels1, 3)
    # Brighter: amber adds mostly red and green (its linear blue is 0.03).
    assert np.all(lit1 >= lit0 - 1) and lit1[0] > lit0[0] + 40 and lit1.mean() > lit0.mean() + 20, (
        lit0, lit1)
    assert lit1[0] > lit1[2] + 40  # grey + amber: red over blue
    for v in (2, 4):
        other0, other1 = mean_color(color0, labels0, v), mean_color(color1, labels1, v)
        assert np.all(other1 < 0.75 * other0), (v, other0, other1)

    # Two labels, a color and intensity; then no highlight: the materials come back exactly.
    actor.set_highlight([2, 5], color="cyan", intensity=2.0)
    np.testing.assert_allclose(key_material(actor, 5)[4:7], 2 * srgb_to_linear((0, 1, 1)), atol=1e-6)
    np.testing.assert_array_equal(key_material(actor, 3)[4:7], 0)
    actor.set_highlight(None, dim=1.0)
    for v in before:
        np.testing.assert_allclose(key_material(actor, v), before[v], atol=0)
    vtksvdag.refine(plotter)
    assert mapper.GetNumberOfBVHBuilds() == builds


def test_highlight_at_add_and_others_opacity(plotter):
    actor = vtksvdag.add_segmentation(plotter, slabs(), highlight=4, dim=0.5, others_opacity=0.25,
                                      highlight_color="white", spp=1)
    assert actor.highlighted_labels == [4]
    props = actor.label_properties
    assert props.IsHighlighted(4) and not props.IsHighlighted(3)
    assert props.GetDimOthers() == 0.5 and props.GetOthersOpacity() == 0.25
    # Opacity 0.25 is transmission 0.75 through the surface (index of refraction 1).
    other = key_material(actor, 1)
    assert other[10] == pytest.approx(0.75) and other[11] == 1.0
    assert key_material(actor, 4)[10] == 0.0


def test_label_properties_highlight_api():
    """VTK users have the highlight too (set-like, Modified only on change, clamped)."""
    props = vtkSegmentationSVDAGLabelProperties()
    t = props.GetMTime()
    props.AddHighlightedLabel(7)
    props.AddHighlightedLabel(-3)
    assert props.GetMTime() > t
    t = props.GetMTime()
    props.AddHighlightedLabel(7)
    assert props.GetMTime() == t
    assert [props.GetHighlightedLabel(i) for i in range(props.GetNumberOfHighlightedLabels())] == [-3, 7]
    props.RemoveHighlightedLabel(-3)
    assert props.GetNumberOfHighlightedLabels() == 1 and props.IsHighlighted(7)
    props.RemoveAllHighlightedLabels()
    assert props.GetNumberOfHighlightedLabels() == 0
    props.SetHighlightColor(2.0, -1.0, 0.5)
    assert props.GetHighlightColor() == (1.0, 0.0, 0.5)
    props.SetDimOthers(-1)
    props.SetOthersOpacity(3)
    assert props.GetDimOthers() == 0.0 and props.GetOthersOpacity() == 1.0
    props.SetEmission(5, 1, 2, 3)
    emission = [0.0] * 3
    assert props.GetEmission(5, emission) and emission == [1, 2, 3]
    assert not props.GetEmission(6, emission)
    # GetMaterial: the label's emission plus the tint; a label the volume lacks is False.
    labels = np.zeros((8, 8, 8), np.uint8)
    labels[2:6, 2:6, 2:6] = 5
    svdag = compress_zyx(labels)
    props.SetHighlightColor(1, 1, 1)
    props.SetHighlightIntensity(0.5)
    props.AddHighlightedLabel(5)
    material = [0.0] * 16
    assert props.GetMaterial(svdag, 5, material)
    np.testing.assert_allclose(material[4:7], [1.5, 2.5, 3.5], atol=1e-6)
    assert not props.GetMaterial(svdag, 6, material)
    props.SetColor(5, 1, 0, 0)
    props.RemoveColor(5)
    assert not props.GetColor(5, emission)


# bad input --------------------------------------------------------------------------------------
@pytest.mark.parametrize("options, match", [
    ({"attributes": ATTRIBUTES, "color_by": "nope"}, r"color_by column 'nope'.*columns are .*score"),
    ({"color_by": "score"}, r"'score' is not in the label table.*voxel_count"),
    ({"attributes": ATTRIBUTES, "query": "score >"}, r"query 'score >' failed.*SyntaxError"),
    ({"attributes": ATTRIBUTES, "query": "weight > 3"}, r"query 'weight > 3' failed.*score"),
    ({"attributes": ATTRIBUTES, "query": "score + 1"}, r"query 'score \+ 1'"),
    ({"attributes": ATTRIBUTES.rename(columns={"label": "id"})}, r"needs a 'label' column.*'id'"),
    ({"attributes": pd.DataFrame({"label": [1, 1], "x": [1, 2]})}, r"more than one row for labels \[1\]"),
    ({"attributes": pd.DataFrame({"label": [1.5], "x": [1]})}, r"labels must be integers"),
    ({"attributes": pd.DataFrame({"label": ["a"], "x": [1]})}, r"labels must be integers"),
    ({"attributes": ATTRIBUTES.assign(volume=1.0)}, r"\['volume'\] clash"),
    ({"attributes": ATTRIBUTES, "color_by": "score", "cmap": "no-such-map"}, r"unknown colormap"),
    ({"highlight": [77]}, r"highlight label 77 is not a label"),
    ({"highlight": [1], "dim": 1.5}, r"dim must be a number in \[0, 1\]"),
])
def test_bad_input_raises_value_error(plotter, options, match):
    with pytest.raises(ValueError, match=match):
        vtksvdag.add_segmentation(plotter, slabs(), spp=1, **options)
    assert plotter.renderer.GetVolumes().GetNumberOfItems() == 0


def test_bad_input_types(plotter, tmp_path):
    with pytest.raises(TypeError, match="DataFrame or the path"):
        vtksvdag.add_segmentation(plotter, slabs(), attributes={"label": [1]})
    with pytest.raises(FileNotFoundError):
        vtksvdag.add_segmentation(plotter, slabs(), attributes=tmp_path / "missing.csv")
    actor = vtksvdag.add_segmentation(plotter, slabs(), attributes=ATTRIBUTES, spp=1)
    with pytest.raises(ValueError, match="query"):
        actor.set_query("")
    with pytest.raises(ValueError, match="not in the label table"):
        actor.set_color_by("Score")
    # A failed change leaves the state as it was.
    assert actor.query is None and actor.visible_labels == [1, 2, 3, 4, 5, 9]


# command line -----------------------------------------------------------------------------------
def test_cli_render_attributes(tmp_path):
    import nrrd

    volume = tmp_path / "slabs.nrrd"
    nrrd.write(str(volume), slabs())  # [x, y, z]
    table = tmp_path / "cells.csv"
    ATTRIBUTES.to_csv(table, index=False)
    common = [sys.executable, "-m", "vtksvdag", "render", str(volume), "--width", "48",
              "--height", "32", "--spp", "2"]
    result = subprocess.run(common + ["-o", str(tmp_path / "a.png"), "--json", "--attributes",
                                      str(table), "--color-by", "score", "--query", "score > 1",
                                      "--highlight", "3,5", "--dim", "0.3"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)
    assert info["visible_labels"] == [2, 3, 4, 5] and info["highlighted_labels"] == [3, 5]
    for options, match in ((["--attributes", str(table), "--color-by", "nope"], "--color-by: color_by column 'nope'"),
                           (["--attributes", str(table), "--query", "score >"], "--query: query 'score >' failed"),
                           (["--highlight", "3,x"], "--highlight"),
                           (["--highlight", "77"], "--highlight: highlight label 77"),
                           (["--attributes", str(table)], "need --color-by or --query")):
        result = subprocess.run(common + ["-o", str(tmp_path / "b.png")] + options,
                                capture_output=True, text=True, timeout=120)
        assert result.returncode != 0
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("vtksvdag: error: ") and match in lines[0], lines


# cost on a real volume --------------------------------------------------------------------------
def test_change_costs_on_shared_volume(capsys):
    """Query, color and highlight changes on voronoi256_sphere (588 labels): the next frame shows
    them with one BVH rebuild for a query and none for colors or the highlight; the times to the
    next frame are printed (lavapipe)."""
    path = require_shared_data(SHARED_DATA / "voronoi256_sphere.nrrd")
    volume = vtksvdag.read(path)
    p = pv.Plotter(off_screen=True, window_size=(320, 240))
    try:
        actor = vtksvdag.add_segmentation(p, volume, color_by="voxel_count", spp=1, lod="voxel",
                                          auto_adjust=False)
        mapper = actor.GetMapper()
        vtksvdag.refine(p)
        median = float(actor.label_table.voxel_count.median())

        def next_frame(change):
            start = time.perf_counter()
            change()
            p.render()
            return time.perf_counter() - start

        next_frame(lambda: None)  # warm
        builds = mapper.GetNumberOfBVHBuilds()
        times = {"unchanged": next_frame(lambda: None)}
        times["query"] = next_frame(lambda: actor.set_query(f"voxel_count > {median}"))
        rebuilt = mapper.GetBackendInUse() == "rt"  # compute: hidden labels are bits
        assert mapper.GetNumberOfBVHBuilds() == builds + rebuilt
        assert len(actor.visible_labels) < len(volume.labels)
        times["color"] = next_frame(lambda: actor.set_color_by("volume", cmap="plasma"))
        times["highlight (first: emission pipeline)"] = next_frame(
            lambda: actor.set_highlight([actor.visible_labels[0]], dim=0.3))
        times["highlight"] = next_frame(lambda: actor.set_highlight([actor.visible_labels[1]]))
        assert mapper.GetNumberOfBVHBuilds() == builds + rebuilt
        assert mapper.GetAccumulatedSamples() == 1
        with capsys.disabled():
            print("\n" + ", ".join(f"{k} {1e3 * v:.1f} ms" for k, v in times.items()))
    finally:
        p.close()

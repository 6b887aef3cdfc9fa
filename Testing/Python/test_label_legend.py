"""The label legend and colors in hand (issue 20, item 4): add_label_legend / show_scalar_bar,
plotter.add_scalar_bar() on a segmentation, label_table's color column, get_color / set_color /
hide / show, and vtkSegmentationSVDAGLabelProperties.GetColor(label) from Python.

Small volumes and 200x150 windows: these run on lavapipe."""
import numpy as np
import pandas as pd
import pytest

import vtksvdag
from vtksvdag.legend import MAX_ENTRIES
from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGLabelProperties

W, H = 200, 150


def labels_xyz():
    """Labels 3, 5, 7, 9 with voxel counts 5832 (7), 1152 (3), 64 (5), 8 (9)."""
    labels = np.zeros((24, 24, 24), np.uint8)
    labels[2:20, 2:20, 2:20] = 7
    labels[0:2, :, :] = 3
    labels[20:24, 0:4, 0:4] = 5
    labels[22:24, 20:22, 20:22] = 9
    return labels


@pytest.fixture
def plotter():
    import pyvista as pv

    p = pv.Plotter(off_screen=True, window_size=(W, H))
    yield p
    p.close()


def legend_entries(legend):
    return [(legend.GetEntryString(i), tuple(legend.GetEntryColor(i)))
            for i in range(legend.GetNumberOfEntries())]


def display_color(actor, label):
    rgb = [0.0] * 3
    assert actor.label_properties.GetDisplayColor(actor.segmentation.dataobject, label, rgb)
    return tuple(rgb)


def test_get_color_returns_the_color():
    props = vtkSegmentationSVDAGLabelProperties()
    assert props.GetColor(17) is None  # none set
    props.SetColor(17, 0.25, 0.5, 1.0)
    assert props.GetColor(17) == (0.25, 0.5, 1.0)
    rgb = [0.0] * 3
    assert props.GetColor(17, rgb) and rgb == [0.25, 0.5, 1.0]  # the out-parameter form stays
    props.RemoveColor(17)
    assert props.GetColor(17) is None


def test_display_color_precedence():
    """SetColor, else the lookup table, else the default palette (the materials' base color)."""
    from vtkmodules.vtkCommonCore import vtkLookupTable

    volume = vtksvdag.from_numpy(labels_xyz())
    props = vtkSegmentationSVDAGLabelProperties()
    rgb = [0.0] * 3
    assert not props.GetDisplayColor(volume.dataobject, 4, rgb)  # not a label of the volume
    # Default: the sRGB of the material's linear base color.
    material = [0.0] * 16
    assert props.GetMaterial(volume.dataobject, 7, material)
    assert props.GetDisplayColor(volume.dataobject, 7, rgb)
    linear = np.where(np.array(rgb) <= 0.04045, np.array(rgb) / 12.92,
                      ((np.array(rgb) + 0.055) / 1.055) ** 2.4)
    np.testing.assert_allclose(linear, material[:3], atol=1e-6)
    table = vtkLookupTable()
    table.SetNumberOfTableValues(10)
    table.SetTableRange(0, 9)
    table.Build()
    for i in range(10):
        table.SetTableValue(i, i / 10, 0.5, 1 - i / 10, 1)
    props.SetLookupTable(table)
    assert props.GetDisplayColor(volume.dataobject, 7, rgb)
    np.testing.assert_allclose(rgb, (0.7, 0.5, 0.3), atol=0.5 / 255)  # the table keeps 8 bits
    props.SetColor(7, 1, 0, 0)
    props.AddHighlightedLabel(3)
    props.SetDimOthers(0.2)  # the highlight dims the drawn material, not the label's color
    assert props.GetDisplayColor(volume.dataobject, 7, rgb) and rgb == [1, 0, 0]


def test_volume_label_table_has_the_default_colors():
    volume = vtksvdag.from_numpy(labels_xyz())
    table = volume.label_table()
    props = vtkSegmentationSVDAGLabelProperties()
    for label, color in table["color"].items():
        rgb = [0.0] * 3
        assert props.GetDisplayColor(volume.dataobject, label, rgb)
        assert color == tuple(rgb) and all(0 <= c <= 1 for c in color)
    assert len(set(table["color"])) == 4  # one color per label
    named = volume.label_table(pd.DataFrame({"label": [7], "name": ["box"]}))
    assert named.loc[7, "name"] == "box" and pd.isna(named.loc[3, "name"])
    assert named["color"].tolist() == table["color"].tolist()


def test_actor_colors_in_hand(plotter):
    actor = vtksvdag.add_segmentation(plotter, labels_xyz(), colors={3: "red"}, spp=1)
    assert actor.get_color(3) == (1.0, 0.0, 0.0)
    assert actor.get_color(7) == display_color(actor, 7)  # the default palette
    actor.set_color(7, (0.2, 0.4, 0.6))
    assert actor.get_color(7) == (0.2, 0.4, 0.6)
    assert actor.label_properties.GetColor(7) == (0.2, 0.4, 0.6)
    actor.set_color(5, "#0000ff")
    assert actor.label_table.loc[5, "color"] == (0.0, 0.0, 1.0)
    assert actor.label_table.loc[7, "color"] == (0.2, 0.4, 0.6)
    # set_color wins over a color column, as colors= does.
    table = pd.DataFrame({"label": [3, 5, 7, 9], "score": [1.0, 2.0, 3.0, 4.0]})
    actor2 = vtksvdag.add_segmentation(plotter, labels_xyz(), attributes=table, color_by="score", spp=1)
    actor2.set_color(9, "white")
    actor2.set_color_by("score", cmap="viridis")
    assert actor2.get_color(9) == (1.0, 1.0, 1.0)
    assert actor2.get_color(3) != actor2.get_color(5)
    with pytest.raises(ValueError, match="label 4 is not a label of the volume"):
        actor.get_color(4)
    with pytest.raises(TypeError, match="integer label value"):
        actor.set_color("7", "red")


def test_hide_and_show(plotter):
    actor = vtksvdag.add_segmentation(plotter, labels_xyz(), spp=1)
    vtksvdag.refine(plotter)
    assert vtksvdag.pick(plotter, W / 2, H / 2)["label"] == 7
    actor.hide(7)
    assert actor.visible_labels == [3, 5, 9]
    vtksvdag.refine(plotter)
    hit = vtksvdag.pick(plotter, W / 2, H / 2)
    assert hit is None or hit["label"] != 7
    # Hidden through a query, as hidden_labels.
    actor.set_query("voxel_count > 10")
    assert actor.visible_labels == [3, 5]
    actor.show([7, 9])
    assert actor.visible_labels == [3, 5, 7, 9]
    vtksvdag.refine(plotter)
    assert vtksvdag.pick(plotter, W / 2, H / 2)["label"] == 7
    actor.set_query("voxel_count > 10")  # a query decides again for the labels it does not match
    assert actor.visible_labels == [3, 5, 7]
    with pytest.raises(ValueError, match="label to hide 4 is not a label"):
        actor.hide([4])


def test_legend_entries_and_colors(plotter):
    names = pd.DataFrame({"label": [7, 5], "name": ["box", "corner"]})
    actor = vtksvdag.add_segmentation(plotter, labels_xyz(), attributes=names, colors={3: "red"},
                                      hidden_labels=[5], spp=1)
    legend = vtksvdag.add_label_legend(actor)
    assert plotter.renderer.legend is legend
    entries = legend_entries(legend)
    # Visible first, each group by voxel count: 7 (5832), 3 (1152), 9 (8), then hidden 5.
    assert [text for text, _ in entries] == ["box", "3", "9", "corner"]
    for (text, color), label in zip(entries, (7, 3, 9, 5)):
        # pyvista.Color keeps 8 bits.
        np.testing.assert_allclose(color, display_color(actor, label), atol=0.5 / 255)
    assert entries[1][1] == (1.0, 0.0, 0.0)
    # Chosen labels in their order, and max_entries with a "+N more" entry.
    assert [t for t, _ in legend_entries(vtksvdag.add_label_legend(actor, labels=[9, 7]))] == ["9", "box"]
    short = legend_entries(vtksvdag.add_label_legend(actor, max_entries=2))
    assert [t for t, _ in short] == ["box", "3", "+2 more"]
    assert MAX_ENTRIES >= 4  # the default lists all 4
    with pytest.raises(ValueError, match="max_entries must be an integer >= 1"):
        vtksvdag.add_label_legend(actor, max_entries=0)
    with pytest.raises(ValueError, match="legend label 4 is not a label"):
        vtksvdag.add_label_legend(actor, labels=[4])
    with pytest.raises(TypeError, match="SegmentationActor"):
        vtksvdag.add_label_legend(plotter)


def test_show_scalar_bar_and_rendered_legend(plotter):
    actor = vtksvdag.add_segmentation(plotter, labels_xyz(), colors={7: (0.0, 0.0, 1.0)},
                                      show_scalar_bar=True, spp=1)
    legend = plotter.renderer.legend
    assert legend is not None and legend_entries(legend)[0] == ("7", (0.0, 0.0, 1.0))
    vtksvdag.refine(plotter)
    image = plotter.screenshot()
    # The legend box is drawn in the upper right: pure blue pixels of the swatch of label 7
    # (the volume's blue is shaded, not (0, 0, 255) everywhere).
    corner = image[: H // 3, W // 2:]
    assert np.any(np.all(corner == (0, 0, 255), axis=-1))
    assert actor.GetVisibility()


def test_add_scalar_bar_on_a_segmentation(plotter):
    names = pd.DataFrame({"label": [7], "name": ["box"]})
    actor = vtksvdag.add_segmentation(plotter, labels_xyz(), attributes=names, spp=1)
    actor.set_color(3, "red")  # after adding: the bar shows the colors when it is added
    bar = plotter.add_scalar_bar()  # raised AttributeError: Mapper does not exist
    table = bar.GetLookupTable()
    assert table.GetIndexedLookup()
    annotations = [table.GetAnnotation(i) for i in range(table.GetNumberOfAnnotatedValues())]
    assert annotations == ["box", "3", "5", "9"]
    values = [table.GetAnnotatedValue(i).ToDouble() for i in range(table.GetNumberOfAnnotatedValues())]
    assert values == [7, 3, 5, 9]
    for i, label in enumerate((7, 3, 5, 9)):
        # vtkLookupTable keeps 8 bits.
        np.testing.assert_allclose(table.GetTableValue(i)[:3], display_color(actor, label),
                                   atol=0.5 / 255)
    assert table.GetTableValue(1)[:3] == (1.0, 0.0, 0.0)
    # A mesh added with scalars takes plotter.mapper, as in pyvista.
    import pyvista as pv

    mesh = pv.Sphere()
    mesh["z"] = mesh.points[:, 2]
    plotter.add_mesh(mesh, show_scalar_bar=False)
    assert not plotter.add_scalar_bar("z").GetLookupTable().GetIndexedLookup()

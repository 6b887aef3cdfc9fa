"""SegmentationVolume.encoding_statistics against a brute force from the label array.

The reference never looks at the compressed form: it cuts every (16^3 cell, label) pair into
its occupancy, the 8^3 and 4^3 sub-blocks below it, and builds each DAG level as the set of
distinct canonical shapes (complemented so that voxel [0, 0, 0] is empty, the encoding's rule;
leaves up to the 48 symmetries of the cube too, as the encoding stores them), the symmetry
classes with numpy's flips and transposes, and the reference counts by counting children of
distinct parents.
"""
import itertools
import math

import numpy as np
import pytest

import vtksvdag
from vtksvdag import synthetic

PERMUTATIONS = list(itertools.permutations(range(3)))
MIRRORS = [m for m in itertools.product((False, True), repeat=3)]


def canonical(block):
    """The shape as stored: complemented when its voxel [0, 0, 0] is set."""
    return ~block if block[0, 0, 0] else block


def key(block):
    return canonical(block).tobytes()


def transforms(block, permutations):
    for p in permutations:
        t = block.transpose(p)
        for m in MIRRORS:
            axes = tuple(a for a in range(3) if m[a])
            yield np.flip(t, axes) if axes else t


def class_key(block, permutations):
    return min(key(np.ascontiguousarray(t)) for t in transforms(block, permutations))


def children(block):
    """The 8 octants, each with whether it is mixed (neither empty nor full)."""
    h = block.shape[0] // 2
    for oz, oy, ox in itertools.product((0, 1), repeat=3):
        child = block[ox * h:(ox + 1) * h, oy * h:(oy + 1) * h, oz * h:(oz + 1) * h]
        yield child, bool(child.any() and not child.all())


def brute_force(labels, background=0):
    """Per level: distinct nodes, their mixed children, incoming counts and symmetry classes."""
    padded_shape = [-(-s // 16) * 16 for s in labels.shape]
    padded = np.full(padded_shape, background, dtype=labels.dtype)
    padded[: labels.shape[0], : labels.shape[1], : labels.shape[2]] = labels
    # Voxels outside the volume are empty for every label: pad with a value no label has.
    outside = np.ones(padded_shape, dtype=bool)
    outside[: labels.shape[0], : labels.shape[1], : labels.shape[2]] = False
    blocks = []
    for cx, cy, cz in itertools.product(*(range(s // 16) for s in padded_shape)):
        cell = np.s_[cx * 16:(cx + 1) * 16, cy * 16:(cy + 1) * 16, cz * 16:(cz + 1) * 16]
        values = padded[cell]
        inside = ~outside[cell]
        for label in np.unique(values[inside]):
            if label != background:
                blocks.append((values == label) & inside)
    levels = {}
    parents = [(None, b) for b in blocks]  # (parent key, node); blocks are the roots' parents
    for name in ("roots", "mids", "leaves"):
        nodes, incoming = {}, {}
        for _, node in parents:
            k = class_key(node, PERMUTATIONS) if name == "leaves" else key(node)
            nodes.setdefault(k, node)
            incoming[k] = incoming.get(k, 0) + 1
        levels[name] = {"nodes": nodes, "incoming": incoming}
        # Children of the distinct nodes (a shared node holds its references once).
        parents = [
            (k, child)
            for k, node in nodes.items()
            for child, mixed in children(canonical(node))
            if mixed and node.shape[0] > 4
        ]
    levels["blocks"] = len(blocks)
    return levels


def volumes():
    rng = np.random.default_rng(7)
    noise = rng.integers(0, 3, size=(21, 18, 17)).astype(np.uint8)
    mirrored = synthetic.voronoi((32, 16, 16), 6, seed=3, dtype=np.uint16)
    mirrored = np.concatenate([mirrored, np.flip(mirrored, 0)], axis=0)  # 64 x 16 x 16
    return {
        "voronoi_odd": synthetic.voronoi((37, 29, 35), 14, seed=11),
        "tubes": synthetic.tubes((40, 40, 24), 5, 2.5, seed=5, dtype=np.int16),
        "noise3": noise,
        "mirrored": mirrored,
    }


@pytest.fixture(scope="module", params=sorted(volumes()))
def case(request):
    labels = volumes()[request.param]
    volume = vtksvdag.from_numpy(labels)
    return labels, volume, volume.encoding_statistics(), brute_force(labels)


def test_levels_and_counts_match_the_brute_force(case):
    labels, volume, table, reference = case
    assert list(table.index) == ["blocks", "roots", "mids", "leaves"]
    stats = volume.stats()
    assert table.loc["blocks", "nodes"] == reference["blocks"] == stats["blocks"]
    for level in ("roots", "mids", "leaves"):
        assert table.loc[level, "nodes"] == len(reference[level]["nodes"]), level
    # The next level's incoming references are this level's references.
    assert table.loc["blocks", "references"] == table.loc["roots", "incoming_references"]
    assert table.loc["roots", "references"] == table.loc["mids", "incoming_references"]
    assert table.loc["mids", "references"] == table.loc["leaves", "incoming_references"]
    assert table.loc["leaves", "references"] == 0
    # Bytes held in memory (the compact form) are what the data object counts; the pooled
    # form's bits (every node once, a reference per child) are checked field by field below.
    compact = table["compact_bytes"]
    assert compact["roots"] + compact["mids"] + compact["leaves"] == stats["bytes_dag"]
    assert compact["blocks"] == stats["bytes_blocks"]
    # The compact form stores the pooled form's leaves used more than once, and no more.
    assert compact["leaves"] == 8 * stats["leaves"] <= table.loc["leaves", "bytes"]
    for level in table.index:
        row = table.loc[level]
        assert row["bits"] == row["header_bits"] + row["reference_bits"], level
        assert row["reference_bits"] == row["references"] * row["reference_width"], level


def test_reference_skew_matches_the_brute_force(case):
    _, _, table, reference = case
    for level in ("roots", "mids", "leaves"):
        counts = np.array(sorted(reference[level]["incoming"].values(), reverse=True))
        row = table.loc[level]
        total = counts.sum()
        assert row["incoming_references"] == total, level
        assert row["referenced_once"] == np.count_nonzero(counts == 1), level
        assert row["max_incoming"] == counts[0], level
        for share, fraction in (("top1_percent_share", 0.01), ("top10_percent_share", 0.10)):
            k = max(1, math.ceil(fraction * len(counts)))
            assert row[share] == pytest.approx(counts[:k].sum() / total), (level, share)
        p = counts / total
        assert row["reference_entropy_bits"] == pytest.approx(-(p * np.log2(p)).sum()), level


def test_symmetry_classes_match_the_brute_force(case):
    _, _, table, reference = case
    for level in ("roots", "mids", "leaves"):
        nodes = reference[level]["nodes"].values()
        mirror = {class_key(n, PERMUTATIONS[:1]) for n in nodes}
        symmetry = {class_key(n, PERMUTATIONS) for n in nodes}
        assert table.loc[level, "mirror_classes"] == len(mirror), level
        assert table.loc[level, "symmetry_classes"] == len(symmetry), level
        assert len(symmetry) <= len(mirror) <= len(nodes)


def test_shared_bits_follow_the_layout(case):
    """The symmetry-aware estimate: classes of leaves at 64 bits, nodes at 16 bits plus a
    reference per mixed child, references widened by the transform's bits."""
    _, _, table, reference = case

    def width(units, transform_bits):
        return max(int(units) - 1, 0).bit_length() + 1 + transform_bits

    for group, permutations, transform_bits in (
        ("mirror", PERMUTATIONS[:1], 3), ("symmetry", PERMUTATIONS, 6)
    ):
        leaf_classes = table.loc["leaves", f"{group}_classes"]
        assert table.loc["leaves", f"{group}_bits"] == 64 * leaf_classes
        child_units = leaf_classes
        for level in ("mids", "roots"):
            representatives = {}
            for n in reference[level]["nodes"].values():
                representatives.setdefault(class_key(n, permutations), n)
            w = width(child_units, transform_bits)
            expected = sum(
                16 + w * sum(mixed for _, mixed in children(canonical(n)))
                for n in representatives.values()
            )
            assert table.loc[level, f"{group}_bits"] == expected, (group, level)
            child_units = expected
        blocks = table.loc["blocks"]
        assert blocks[f"{group}_bits"] == blocks["header_bits"] + blocks["nodes"] * width(
            child_units, transform_bits
        )


def test_a_mirror_image_is_one_class():
    labels = np.zeros((16, 16, 16), dtype=np.uint8)
    rng = np.random.default_rng(1)
    half = rng.random((8, 16, 16)) < 0.4
    labels[:8][half] = 1
    labels[8:][np.flip(half, 0)] = 2  # label 2 is label 1 mirrored across x = 8
    table = vtksvdag.from_numpy(labels).encoding_statistics()
    assert table.loc["roots", "nodes"] == 2
    assert table.loc["roots", "mirror_classes"] == 1
    assert table.loc["roots", "symmetry_classes"] == 1


def test_empty_volume_has_empty_levels():
    table = vtksvdag.from_numpy(np.zeros((5, 6, 7), dtype=np.uint8)).encoding_statistics()
    assert (table[["nodes", "bits", "references", "mirror_classes"]] == 0).all().all()
    assert (table["reference_entropy_bits"] == 0).all()

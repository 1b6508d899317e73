"""Mesh numbering, coordinates and element maps against theory 2.2 and 2.3."""

import numpy as np
import pytest

from simulator.model.mesh import BarType, SpringKind, make_mesh
from simulator.geometry.example_patterns import (crane_pattern, double_fold_pattern, gripper_pattern,
                                miura_sheet_pattern, single_fold_pattern, strip_pattern)

REF = 1  # the reference is 1-based (theory 1.2); ours is 0-based


@pytest.fixture(scope="module")
def single():
    return make_mesh(single_fold_pattern())


def test_single_fold_node_coordinates(single):
    mm = 1e-3
    expected = {1: (0, 0, 0), 2: (0.5, 0, 0), 3: (0.5, 0.5, 0), 4: (0, 0.5, 0), 5: (0.7, 0, 0),
                6: (1.2, 0, 0), 7: (1.2, 0.5, 0), 8: (0.7, 0.5, 0), 13: (0.6, 0, 0),
                14: (0.6, 0.5, 0), 15: (0.6, 0.25, 0), 16: (0.25, 0.25, 0), 17: (0.95, 0.25, 0),
                18: (0.625, 0.2625, -0.15)}
    assert single.n_nodes == 18
    for ref_id, xyz in expected.items():
        np.testing.assert_allclose(single.nodes[ref_id - REF], np.array(xyz) * mm, rtol=1e-12,
                                   atol=1e-12 * mm)


def test_single_fold_bars(single):
    expected = [[1, 4], [1, 2], [2, 3], [3, 4], [5, 8], [5, 6], [6, 7], [7, 8], [9, 12], [9, 10],
                [10, 11], [11, 12], [2, 13], [2, 15], [3, 15], [3, 14], [13, 15], [14, 15],
                [5, 13], [5, 15], [8, 15], [8, 14]]
    np.testing.assert_array_equal(single.bars[:22] + REF, expected)
    spokes = single.bars[22:] + REF
    np.testing.assert_array_equal(spokes[:, 0], np.arange(1, 13))
    np.testing.assert_array_equal(spokes[:, 1], np.repeat([16, 17, 18], 4))
    assert single.bar_type.tolist() == [1] * 12 + [2, 3, 3, 2, 4, 4, 2, 3, 3, 2] + [5] * 12
    assert np.all(single.bars[:, 0] < single.bars[:, 1])


def test_single_fold_springs_after_polarity(single):
    expected = {3: (15, 2, 3, 16), 5: (15, 8, 5, 17), 14: (3, 15, 2, 13), 15: (14, 15, 3, 2),
                17: (2, 15, 13, 5), 18: (3, 14, 15, 8), 20: (13, 15, 5, 8), 21: (14, 8, 15, 5),
                23: (2, 1, 16, 4), 24: (3, 2, 16, 1), 25: (4, 3, 16, 2), 26: (1, 4, 16, 3),
                27: (6, 5, 17, 8), 28: (7, 6, 17, 5), 29: (8, 7, 17, 6), 30: (5, 8, 17, 7),
                31: (10, 9, 18, 12), 32: (11, 10, 18, 9), 33: (12, 11, 18, 10),
                34: (9, 12, 18, 11)}
    assert len(single.springs) == 20
    np.testing.assert_array_equal(single.spring_bar + REF, list(expected))
    np.testing.assert_array_equal(single.springs + REF, list(expected.values()))


def test_single_fold_triangles_and_crease_maps(single):
    crease_tris = [(15, 13, 2), (5, 13, 15), (5, 15, 8), (8, 14, 15), (3, 15, 14), (3, 15, 2)]
    fans = [(16, 1, 2), (16, 2, 3), (16, 3, 4), (16, 1, 4), (17, 5, 6), (17, 6, 7), (17, 7, 8),
            (17, 5, 8), (18, 9, 10), (18, 10, 11), (18, 11, 12), (18, 9, 12)]
    np.testing.assert_array_equal(single.triangles + REF, crease_tris + fans)
    # creaseRef(3, :) = [3 5 14 15 17 18 20 21]
    np.testing.assert_array_equal(single.spring_bar[single.crease_springs[0]] + REF,
                                  [3, 5, 14, 15, 17, 18, 20, 21])
    np.testing.assert_array_equal(single.crease_nodes[0] + REF, [2, 3, 5, 8, 13, 14, 15])
    np.testing.assert_array_equal(single.crease_bars[0] + REF, np.arange(13, 23))
    np.testing.assert_array_equal(single.crease_panels[0], [0, 1])
    assert single.crease_ids.tolist() == [2]
    assert single.panel_center.tolist() == [15, 16, 17]
    assert single.bar_crease[single.crease_bars[0]].tolist() == [-1, 2, 2, -1, 2, 2, -1, 2, 2, -1]
    kinds = single.spring_kind[single.crease_springs[0]]
    assert kinds.tolist() == [SpringKind.CREASE_EDGE] * 2 + [SpringKind.CREASE_DIAGONAL] * 2 \
        + [SpringKind.CREASE_CENTRE] * 2 + [SpringKind.CREASE_DIAGONAL] * 2


def test_polarity_convention(single):
    """Every crease spring of a flat pattern has z((X_j - X_i) x (X_k - X_j)) <= 0."""
    s = single.springs[single.spring_kind != SpringKind.PANEL]
    x = single.nodes
    z = np.cross(x[s[:, 1]] - x[s[:, 0]], x[s[:, 2]] - x[s[:, 1]])[:, 2]
    assert np.all(z <= 0)


@pytest.mark.parametrize("factory, counts, ctr, centres", [
    (double_fold_pattern, (26, 52, 28, 32), [19, 22], [23, 24, 25, 26]),
    (miura_sheet_pattern, (32, 72, 40, 48), [19, 22, 25, 28], [29, 30, 31, 32]),
    (gripper_pattern, (42, 88, 48, 56), [27, 30, 33, 36], [37, 38, 39, 40, 41, 42]),
    (strip_pattern, (13, 26, 14, 16), [11], [12, 13]),
])
def test_mesh_counts(factory, counts, ctr, centres):
    mesh = make_mesh(factory())
    assert (mesh.n_nodes, len(mesh.bars), len(mesh.triangles), len(mesh.springs)) == counts
    np.testing.assert_array_equal(mesh.crease_nodes[:, 6] + REF, ctr)
    np.testing.assert_array_equal(mesh.panel_center + REF, centres)


def test_double_fold_edge_bars():
    mesh = make_mesh(double_fold_pattern())
    np.testing.assert_array_equal(mesh.bars[mesh.crease_edge_bars[0]] + REF, [[2, 3], [5, 8]])
    np.testing.assert_array_equal(mesh.bars[mesh.crease_edge_bars[1]] + REF, [[6, 7], [9, 12]])


def test_crane_creases():
    mesh = make_mesh(crane_pattern())
    assert (mesh.crease_ids + REF).tolist() == [1, 3, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 17,
                                                18, 19, 21]


def test_counts_formula_large_miura():
    """nodes = S + 3C + P, bars = 2S + 10C, triangles = 6C + S, springs = 8C + S."""
    mesh = make_mesh(miura_sheet_pattern(m=7, n=5))
    S, P, C = 4 * 35, 35, mesh.n_creases
    assert C == 7 * 4 + 6 * 5
    assert (mesh.n_nodes, len(mesh.bars), len(mesh.triangles), len(mesh.springs)) == \
        (S + 3 * C + P, 2 * S + 10 * C, 6 * C + S, 8 * C + S)
    # every crease owns exactly its maps
    assert np.all(mesh.bar_crease[mesh.crease_bars[:, 1]] == mesh.crease_ids)
    assert np.all(mesh.spring_crease[mesh.crease_springs] == np.arange(C)[:, None])
    assert np.all(mesh.triangle_crease[mesh.crease_triangles] == np.arange(C)[:, None])
    assert set(np.unique(mesh.bar_type)) == {BarType.PANEL_EDGE, BarType.CREASE_SIDE,
                                             BarType.CREASE_DIAGONAL, BarType.CREASE_CENTRE,
                                             BarType.SPOKE}


def test_with_nodes_keeps_bar_lengths(single):
    moved = single.with_nodes(single.nodes * 1.1)
    np.testing.assert_array_equal(moved.bar_length, single.bar_length)


def test_mesh_and_pattern_arrays_are_read_only(single):
    arrays = {k: v for k, v in vars(single).items() if isinstance(v, np.ndarray)}
    arrays.update(crease_row=single.crease_row, spring_crease=single.spring_crease,
                  fan_triangles=single.fan_triangles)
    pat = single.pattern
    arrays.update(vertices=pat.vertices, edges=pat.edges, edge_panels=pat.edge_panels,
                  crease_width=pat.crease_width, panel_thickness=pat.panel_thickness,
                  creases=pat.creases, corner_edges=pat.corner_edges)
    assert len(arrays) > 30
    for name, a in arrays.items():
        assert not a.flags.writeable, name
    with pytest.raises(ValueError, match="read-only"):
        single.nodes[0, 0] = 1.0


def test_with_nodes_copies_the_callers_array(single):
    x = np.array(single.nodes)
    moved = single.with_nodes(x)
    x[0, 0] = 1.0                      # the caller's array stays writable and does not leak in
    assert moved.nodes[0, 0] == single.nodes[0, 0] and not moved.nodes.flags.writeable

"""Contact candidate search: static list (small meshes) and k-d tree (large) agree."""

import numpy as np

import simulator.mechanics.contact_search as cs
from simulator.mechanics.contact_search import ContactSearch
from simulator.model.mesh import make_mesh
from simulator.model.model import ContactParameters
from simulator.geometry.example_patterns import miura_sheet_pattern, single_fold_pattern


def _pairs(search, x):
    conn, d0, _ = search.candidates(x)
    return {tuple(r) for r in conn.tolist()}, conn, d0


def test_static_and_tree_modes_find_the_same_pairs(monkeypatch):
    mesh = make_mesh(miura_sheet_pattern(m=4, n=3))
    params = ContactParameters(d0_corner=300e-6, d0_centre=250e-6)
    rng = np.random.default_rng(0)
    x = mesh.nodes + rng.normal(size=mesh.nodes.shape) * 1e-4
    static = ContactSearch(mesh, params)
    assert static.static is not None
    monkeypatch.setattr(cs, "STATIC_PAIR_LIMIT", 0)
    tree = ContactSearch(mesh, params)
    assert tree.static is None
    a, _, _ = _pairs(static, x)
    b, _, _ = _pairs(tree, x)
    assert a == b and len(a) > 0


def test_exclusion_rules():
    mesh = make_mesh(single_fold_pattern())
    search = ContactSearch(mesh, ContactParameters(d0_corner=1.0, d0_centre=1.0))  # all near
    pairs, conn, d0 = _pairs(search, mesh.nodes)
    point_panel = mesh.node_panel[conn[:, 0]]
    tri_panel = mesh.node_panel[conn[:, 1]]         # fan triangles start with a corner node
    assert np.all(point_panel != tri_panel)          # never against its own panel
    v = mesh.node_vertex
    shared = (v[conn[:, [0]]] == v[conn[:, 1:]]) & (v[conn[:, [0]]] >= 0)
    assert not shared.any()                          # no copies of the same pattern vertex
    assert np.all(mesh.node_kind[conn[:, 0]] != 1)   # crease nodes are never contact points
    assert set(np.unique(d0)) == {1.0}

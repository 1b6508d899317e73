"""StiffnessPattern: the node-pair construction equals the DOF-pair reference, entry for
entry, on meshes with partial and elastic supports, contact families and scalar DOFs."""

import numpy as np
import pytest
import scipy.sparse as sp

from simulator.mechanics import assembly
from simulator.mechanics.assembly import StiffnessPattern, _block_positions, _reference_positions
from simulator.cases import single_fold_model
from simulator.geometry.example_patterns import miura_sheet_pattern
from simulator.model.model import Supports, make_model
from simulator.mechanics import equilibrium_system


def _families(system):
    fams = [system.bar_dofs, system.spr_dofs]
    if system.contact_in_pattern:
        fams.append(assembly.element_dofs(system.contact.static_conn))
    return fams


def _miura(supports):
    mesh = make_model(miura_sheet_pattern(m=4, n=3)).mesh
    return equilibrium_system(make_model(mesh, supports(mesh)))


CASES = {
    "clamped panel": lambda: _miura(lambda mesh: Supports.nodes(mesh.panel_nodes(0))),
    "partial and elastic supports": lambda: _miura(lambda mesh: Supports(
        fixed={0: "xz", 1: "y", 5: "xyz", 9: "z"},
        elastic=((2, "x", 3.0), (2, "z", 4.0), (7, "y", 1.0), (5, "x", 2.0)))),
    "contact in the pattern": lambda: equilibrium_system(single_fold_model(contact=True)),
}


@pytest.mark.parametrize("case", CASES)
def test_node_pair_pattern_equals_the_dof_pair_reference(case):
    system = CASES[case]()
    fams, diag = _families(system), system.elastic_dofs
    ref = _reference_positions(fams, system.free_index, diag, system.n_free)
    new = _block_positions(fams, system.free_index, diag, system.n_free, chunk=7)
    assert new is not None
    for a, b in zip(ref, new):
        assert a.dtype == b.dtype and np.array_equal(a, b)


def test_pattern_matrix_sums_hessians_in_entry_order():
    system = CASES["partial and elastic supports"]()
    fams, diag = _families(system), system.elastic_dofs
    rng = np.random.default_rng(3)
    values = [rng.normal(size=(len(d), d.shape[1], d.shape[1])) for d in fams]
    values.append(rng.normal(size=len(diag)))
    K = system.pattern.matrix(values)
    # the plain COO sum on free DOFs
    rows, cols, data = [], [], []
    for d, v in zip(fams, values):
        m = d.shape[1]
        rows.append(np.repeat(d, m, axis=1).ravel())
        cols.append(np.tile(d, (1, m)).ravel())
        data.append(v.ravel())
    rows += [diag]
    cols += [diag]
    data += [values[-1]]
    r, c = system.free_index[np.concatenate(rows)], system.free_index[np.concatenate(cols)]
    keep = (r >= 0) & (c >= 0)
    ref = sp.csr_matrix((np.concatenate(data)[keep], (r[keep], c[keep])), shape=K.shape)
    assert K.has_canonical_format
    assert abs(K - ref).max() <= 1e-12 * abs(ref).max()
    # subsets: only some elements of a family carry values
    sub = np.array([1, 4])
    K2 = system.pattern.matrix([values[0][sub], np.zeros((0,) + values[1].shape[1:]), values[2]],
                               {0: sub, 1: np.zeros(0, dtype=int)})
    only = [np.zeros_like(values[0]), np.zeros_like(values[1]), values[2]]
    only[0][sub] = values[0][sub]
    assert abs(K2 - system.pattern.matrix(only)).max() == 0


def test_other_dof_layouts_take_the_reference_path():
    tri = np.array([[0, 1, 2], [1, 2, 3]])           # scalar DOFs (a thermal pattern)
    free_index = np.array([0, -1, 1, 2])
    assert _block_positions([tri], free_index, None, 3) is None
    pattern = StiffnessPattern([tri], free_index, diagonal=np.array([0, 2]))
    K = pattern.matrix([np.ones((2, 3, 3)), np.array([10.0, 20.0])]).toarray()
    assert np.array_equal(K, [[11, 1, 0], [1, 22, 1], [0, 1, 1]])
    # free DOFs numbered out of order
    dofs = assembly.element_dofs(np.array([[0, 1]]))
    shuffled = np.array([1, 0, 2, 3, 4, 5])
    assert _block_positions([dofs], shuffled, None, 6) is None
    assert StiffnessPattern([dofs], shuffled).nnz == 36


def test_compiled_scatter_equals_the_numpy_reference_bit_for_bit(monkeypatch):
    system = CASES["partial and elastic supports"]()
    fams = _families(system)
    rng = np.random.default_rng(5)
    values = [rng.normal(size=(len(d), d.shape[1], d.shape[1])) for d in fams]
    values.append(rng.normal(size=len(system.elastic_dofs)))
    pattern = system.pattern
    monkeypatch.setattr(assembly, "JIT_ENTRIES", 0)
    scatter = assembly._scatter_compiled()
    if scatter is None:
        pytest.skip("numba not available")
    ref = assembly.scatter_numpy(pattern.positions, values, pattern.nnz)
    assert np.array_equal(scatter(pattern.positions, values, pattern.nnz), ref)
    assert np.array_equal(pattern.matrix(values).data, ref)


def test_scatter_loop_follows_the_kernel_backend():
    """With the numpy backend in force the scatter loop is not used (nor numba compiled)."""
    from simulator.kernels import spring_kernel_backend
    from simulator.mechanics import assembly
    with spring_kernel_backend("numpy"):
        assert assembly._scatter_compiled() is None
    with spring_kernel_backend("numba"):
        assert assembly._scatter_compiled() is not None

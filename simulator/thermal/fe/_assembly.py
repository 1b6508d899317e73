"""scikit-fem assembly and solution of the medium's conduction (P2 Lagrange elements).

The medium carries ``k grad(u) . grad(v)`` on tetrahedra (triangles in 2-D); the outer sphere
(circle) carries the far-field Robin term ``(k c / R) u v`` with ``c`` the decay order of the far
field (1: a monopole in free space, 2: a dipole over an isothermal plane; 2-D: ``1 / ln(R/r0)``
is not used, the 2-D outer circle is held at room temperature). scikit-fem is
imported here only.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp


def medium_system(points, cells, k, box_radius, robin_order, plane_z=None, center=None):
    """Stiffness of the medium [W/K] on P2 dofs and what the boundary conditions need.

    Parameters
    ----------
    points : (N, d) mesh vertices [m] (d = 3 or 2), cells : (M, d + 1) vertex ids.
    k : float, medium conductivity [W/(m K)].
    box_radius : float, outer radius R [m] (about ``center``).
    robin_order : float or None, far-field decay order c (None: the outer boundary is held at
        room temperature).
    plane_z : float or None, the isothermal plane (last coordinate) [m].

    Returns
    -------
    A : (n_dof, n_dof) csr matrix [W/K]; doflocs : (n_dof, d) dof positions [m];
    fixed : (n_dof,) bool, dofs at room temperature (plane; outer boundary without Robin);
    basis : the scikit-fem basis (for facet dofs of embedded surfaces).
    """
    import skfem
    from skfem.helpers import dot, grad

    dim = points.shape[1]
    center = np.zeros(dim) if center is None else np.asarray(center, float)
    if dim == 3:
        mesh, elem = skfem.MeshTet(points.T.copy(), cells.T.copy()), skfem.ElementTetP2()
    else:
        mesh, elem = skfem.MeshTri(points.T.copy(), cells.T.copy()), skfem.ElementTriP2()
    basis = skfem.Basis(mesh, elem)
    A = skfem.asm(skfem.BilinearForm(lambda u, v, w: k * dot(grad(u), grad(v))), basis)
    tol = 1e-6 * box_radius
    mid = mesh.p[:, mesh.facets].mean(axis=1)
    bnd = np.zeros(mesh.facets.shape[1], bool)
    bnd[mesh.boundary_facets()] = True
    on_plane = bnd & (np.abs(mid[-1] - plane_z) < tol) if plane_z is not None else bnd & False
    far = np.linalg.norm(mid - center[:, None], axis=0) > 0.9 * box_radius
    outer = np.flatnonzero(bnd & ~on_plane & far)
    fixed = np.zeros(basis.N, bool)
    if plane_z is not None:
        fixed[basis.get_dofs(facets=np.flatnonzero(on_plane)).all()] = True
    if robin_order is None:
        fixed[basis.get_dofs(facets=outer).all()] = True
    elif len(outer):
        fb = skfem.FacetBasis(mesh, elem, facets=outer)
        h = k * robin_order / box_radius
        A = A + skfem.asm(skfem.BilinearForm(lambda u, v, w: h * u * v), fb)
    return A.tocsr(), basis.doflocs.T.copy(), fixed, basis


def facet_ids(basis, cells):
    """Indices of the mesh facets with the vertices ``cells`` (k, d) (surface triangles in 3-D,
    segments in 2-D); raises if one is not a facet of the mesh."""
    facets = np.sort(basis.mesh.facets, axis=0)
    n = basis.mesh.p.shape[1]
    key = facets[0].astype(np.int64)
    want_s = np.sort(cells, axis=1).astype(np.int64)
    want = want_s[:, 0]
    for row in range(1, facets.shape[0]):
        key = key * n + facets[row]
        want = want * n + want_s[:, row]
    order = np.argsort(key)
    pos = np.minimum(np.searchsorted(key, want, sorter=order), len(key) - 1)
    if not np.array_equal(key[order[pos]], want):
        raise RuntimeError("an embedded surface triangle is not a facet of the volume mesh")
    return order[pos]


def facet_dofs(basis, facets):
    """P2 dofs (vertices and edge midpoints) of the given facets."""
    return basis.get_dofs(facets=np.asarray(facets)).all()


def solve_spd(A, b):
    """Solve the SPD system ``A x = b`` by the toolkit's factorisation ladder
    (:func:`~simulator.linalg.ladder.factorize`: PARDISO if installed, else SuperLU).
    Returns (x, relative residual norm)."""
    from ...linalg.ladder import factorize

    A = sp.csr_matrix(A)
    x = factorize(A, kind="spd").solve(b)
    nb = float(np.linalg.norm(b)) or 1.0
    return x, float(np.linalg.norm(A @ x - b)) / nb
